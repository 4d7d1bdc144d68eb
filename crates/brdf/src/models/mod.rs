//! The BSDF models, one file each: its typed parameters (declared once with
//! [`model_params!`](crate::model_params)), its [`Model`](crate::Model) impl, the BSDF
//! itself and, beside it, its WGSL twin. The registry below lists them.

pub mod ashikhmin;
pub mod conductor;
pub mod dielectric;
pub mod dispersion;
pub mod lambert;
pub mod metal;
pub mod metallic_roughness;
pub mod microfacet;
pub mod mirror;
pub mod oren_nayar;
pub mod schlick;

pub use ashikhmin::{Ashikhmin, AshikhminParams};
pub use conductor::{Conductor, ConductorParams};
pub use dielectric::{Dielectric, DielectricParams, FresnelModel};
pub use dispersion::{Dispersion, DispersionPreset};
pub use lambert::{Lambert, LambertParams};
pub use metal::{Metal, MetalPreset, fresnel_conductor};
pub use metallic_roughness::{MetallicRoughness, MetallicRoughnessParams};
pub use microfacet::{Ggx, RoughConductor, RoughConductorParams, RoughDielectric, RoughDielectricParams};
pub use mirror::{Mirror, MirrorParams};
pub use oren_nayar::{OrenNayar, OrenNayarParams};
pub use schlick::{Schlick, SchlickGeometry, SchlickParams};

/// Calls `callback!` with the built-in models, `Variant(ParamsType)` each, followed by
/// `extra` entries: the one list of models. Adding a model to the renderer is one line
/// here (and its file). A program may register its own models beside the built-ins:
/// `brdf::with_builtin_models!(brdf::registry, Toy(ToyParams));`
#[macro_export]
macro_rules! with_builtin_models {
    ($callback:path $(, $($extra:tt)*)?) => {
        $callback! {
            Lambert($crate::models::LambertParams),
            Mirror($crate::models::MirrorParams),
            Dielectric($crate::models::DielectricParams),
            Conductor($crate::models::ConductorParams),
            RoughConductor($crate::models::RoughConductorParams),
            RoughDielectric($crate::models::RoughDielectricParams),
            OrenNayar($crate::models::OrenNayarParams),
            Schlick($crate::models::SchlickParams),
            Ashikhmin($crate::models::AshikhminParams),
            MetallicRoughness($crate::models::MetallicRoughnessParams),
            $($($extra)*)?
        }
    };
}

crate::with_builtin_models!(crate::registry);

#[cfg(test)]
mod tests;
