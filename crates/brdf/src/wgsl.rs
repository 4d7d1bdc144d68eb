//! The WGSL twins of the BSDF models, for the GPU crate's code generator.
//!
//! Each model ships, beside its Rust file, a hand-written WGSL file that transcribes its
//! `eval`, `pdf` and `sample` line by line ([`ModelWgsl`]); shared WGSL that several
//! models call lives beside the Rust file it mirrors ([`WgslPiece`]). The GPU crate
//! generates everything else from the parameter declarations: the parameter structs and
//! their loaders, the per-model dispatch, the buffers. The GPU crate's tests run every
//! twin against its Rust model.
//!
//! # The contract a model's WGSL is written against
//!
//! For a model declared as `"name"` with parameter struct `NameParams` (generated: one
//! field per declared parameter, in order — a scalar is an `f32`, a spectrum or
//! coefficient a `u32` offset for `spectrum_at`, a switch a `bool`, a choice a `u32`
//! index), the WGSL defines
//!
//! ```wgsl
//! fn name_eval(p: NameParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f;
//! fn name_pdf(p: NameParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32;
//! fn name_sample(p: NameParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample;
//! ```
//!
//! and may call what [`COMMON`] declares (`BsdfSample`, `spectrum_at`, the `SCATTER_*`
//! flags, `mat_*` helpers mirroring Rust's f32 library and [`crate::frame`]), the pieces
//! it lists in [`ModelWgsl::needs`], and its own [`ModelWgsl::constants`]. Its own
//! identifiers start with its name (`name_…`) so that models never collide.

use crate::models::dispersion::{BK7, DispersionPreset, FUSED_SILICA, LAMBDA_D};
use crate::models::microfacet::Ggx;
use crate::params::{ModelDef, ResolvedParams};

/// Helpers every model's WGSL may use (see the module documentation).
pub const COMMON: &str = include_str!("common.wgsl");

/// The WGSL twin of a BSDF written outside the registry ([`crate::BsdfBuilder::wgsl_twin`]):
/// what a registered model has in its [`ModelDef`] and [`ModelWgsl`], plus the material's
/// own values. The GPU generator treats it as one more model — a `<Name>Params` struct
/// generated from `def` (so `def.name` must be a lower-case identifier, distinct from the
/// registered models'), the values packed by their declarations, `wgsl.source` defining
/// `<name>_eval`, `<name>_pdf` and `<name>_sample` — so the same equivalence harness checks
/// it against its Rust. Texture slots are ignored: a custom BSDF is never textured on the
/// CPU either.
#[derive(Clone, Debug, PartialEq)]
pub struct WgslTwin {
    /// The parameter declaration (e.g. `<P as ParamSet>::DEF` of a [`crate::model_params!`]
    /// struct).
    pub def: ModelDef,
    /// The WGSL source and the shared pieces it calls.
    pub wgsl: ModelWgsl,
    /// This material's values, in `def`'s order (e.g. `ParamSet::to_resolved`).
    pub params: ResolvedParams,
}

/// A model's WGSL twin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelWgsl {
    /// The WGSL source: `<name>_eval`, `<name>_pdf`, `<name>_sample`.
    pub source: &'static str,
    /// The shared pieces it calls.
    pub needs: &'static [WgslPiece],
    /// Constants it shares with its Rust code, declared before its source.
    pub constants: &'static [WgslConstant],
    /// What its texture slots ([`crate::Model::TEXTURE_SLOTS`]) drive in the WGSL.
    pub texture: WgslTextureSlots,
}

/// Where a model's texture slots act in its WGSL twin, so that the GPU applies textures as
/// the model's `bsdf_textured` does: the base-colour and specular texels multiply the
/// spectra of the parameters named here (the generator gives those parameters their own
/// tables, which `spectrum_at` multiplies), and a model with the metallic–roughness slot
/// defines `fn name_textured(p: NameParams, roughness: f32, metallic: f32) -> NameParams`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WgslTextureSlots {
    /// The spectrum parameter the base-colour texel multiplies.
    pub base_colour: Option<&'static str>,
    /// The spectrum parameter the specular texel multiplies.
    pub specular: Option<&'static str>,
    /// Whether the twin defines `name_textured` for the metallic–roughness texel.
    pub metallic_roughness: bool,
}

impl WgslTextureSlots {
    /// No texture slots.
    pub const NONE: Self = Self { base_colour: None, specular: None, metallic_roughness: false };

    /// The base colour multiplies `param`.
    pub const fn base(param: &'static str) -> Self {
        Self { base_colour: Some(param), ..Self::NONE }
    }
}

/// A constant the WGSL shares with Rust, so that it is written once (in Rust).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WgslConstant {
    /// The WGSL name.
    pub name: &'static str,
    /// The value.
    pub value: WgslValue,
}

/// The value of a [`WgslConstant`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WgslValue {
    /// An `f32`.
    F32(f32),
    /// A `u32`.
    U32(u32),
    /// A `vec3f`.
    Vec3([f32; 3]),
}

impl WgslConstant {
    /// The WGSL declaration, with literals that parse back to the same values.
    pub fn declaration(&self) -> String {
        fn f(v: f32) -> String {
            assert!(v.is_finite(), "WGSL has no literal for {v}");
            format!("{v:?}f")
        }
        match self.value {
            WgslValue::F32(v) => format!("const {}: f32 = {};", self.name, f(v)),
            WgslValue::U32(v) => format!("const {}: u32 = {v}u;", self.name),
            WgslValue::Vec3(v) => format!("const {}: vec3f = vec3f({}, {}, {});", self.name, f(v[0]), f(v[1]), f(v[2])),
        }
    }
}

/// Shared WGSL that models may need; each mirrors one Rust file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum WgslPiece {
    /// Dielectric and conductor Fresnel terms (`fresnel.rs`, `models/metal.rs`).
    Fresnel,
    /// Cosine-weighted hemisphere sampling (`sampling.rs`).
    Sampling,
    /// The anisotropic GGX distribution (`models/microfacet.rs`).
    Ggx,
    /// Measured metals' (n, k) lookup (`models/metal.rs`); the GPU crate generates
    /// `mat_metal_table(id) -> vec2u` (offset, rows) for the presets a scene uses before it.
    Metal,
    /// Wavelength-dependent index of refraction (`models/dispersion.rs`); where no
    /// material disperses the GPU crate replaces it by a constant-index stub of the same
    /// signature.
    Dispersion,
}

impl WgslPiece {
    /// Every piece, in the order they are emitted.
    pub const ALL: [WgslPiece; 5] = [Self::Fresnel, Self::Sampling, Self::Ggx, Self::Metal, Self::Dispersion];

    /// The WGSL source.
    pub fn source(self) -> &'static str {
        match self {
            Self::Fresnel => include_str!("fresnel.wgsl"),
            Self::Sampling => include_str!("sampling.wgsl"),
            Self::Ggx => include_str!("models/ggx.wgsl"),
            Self::Metal => include_str!("models/metal.wgsl"),
            Self::Dispersion => include_str!("models/dispersion.wgsl"),
        }
    }

    /// The constants it shares with Rust.
    pub fn constants(self) -> &'static [WgslConstant] {
        const GGX: &[WgslConstant] =
            &[WgslConstant { name: "MAT_GGX_ALPHA_MIN", value: WgslValue::F32(Ggx::ALPHA_MIN) }];
        const DISPERSION: &[WgslConstant] = &[
            WgslConstant { name: "MAT_LAMBDA_D", value: WgslValue::F32(LAMBDA_D) },
            WgslConstant { name: "MAT_BK7_B", value: WgslValue::Vec3(BK7.b) },
            WgslConstant { name: "MAT_BK7_C", value: WgslValue::Vec3(BK7.c) },
            WgslConstant { name: "MAT_FUSED_SILICA_B", value: WgslValue::Vec3(FUSED_SILICA.b) },
            WgslConstant { name: "MAT_FUSED_SILICA_C", value: WgslValue::Vec3(FUSED_SILICA.c) },
            WgslConstant { name: "MAT_DISPERSION_CAUCHY", value: WgslValue::U32(DispersionPreset::Cauchy.index()) },
            WgslConstant { name: "MAT_DISPERSION_BK7", value: WgslValue::U32(DispersionPreset::Bk7.index()) },
            WgslConstant {
                name: "MAT_DISPERSION_FUSED_SILICA",
                value: WgslValue::U32(DispersionPreset::FusedSilica.index()),
            },
        ];
        match self {
            Self::Ggx => GGX,
            Self::Dispersion => DISPERSION,
            Self::Fresnel | Self::Sampling | Self::Metal => &[],
        }
    }
}
