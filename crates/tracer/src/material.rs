//! Surface materials: which BSDF model a triangle has, with its resolved parameters, and
//! what it emits.
//!
//! Built-in models are named by [`BuiltinModel`] and parameterised by the model's own
//! declaration ([`brdf::params::ModelDef`]); models written outside our crates plug in
//! through [`brdf::DynBsdfBuilder`] without any change to the tracer.

use brdf::models::{
    self, AshikhminShirley, Dielectric, Lambert, Mirror, OrenNayar, RoughConductor, RoughDielectric, Schlick,
    SmoothConductor,
};
use brdf::params::{ModelDef, ParamError, ParamValue, ResolvedParams};
use brdf::{Bsdf, BsdfSample, DynBsdfBuilder, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::spectrum::Colour;
use spectral::{SampledSpectrum, SampledWavelengths};
use std::sync::Arc;

/// The built-in BSDF models, dispatched by `match` on the hot path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BuiltinModel {
    /// [`brdf::models::Lambert`].
    Lambert,
    /// [`brdf::models::Mirror`].
    Mirror,
    /// [`brdf::models::Dielectric`].
    Dielectric,
    /// [`brdf::models::SmoothConductor`].
    Conductor,
    /// [`brdf::models::RoughConductor`] (GGX).
    RoughConductor,
    /// [`brdf::models::RoughDielectric`] (GGX).
    RoughDielectric,
    /// [`brdf::models::OrenNayar`].
    OrenNayar,
    /// [`brdf::models::Schlick`] (Schlick 1994).
    Schlick,
    /// [`brdf::models::AshikhminShirley`] (Shirley & Ashikhmin 2000).
    ShirleyAshikhmin,
}

impl BuiltinModel {
    /// Every built-in model.
    pub const ALL: [BuiltinModel; 9] = [
        Self::Lambert,
        Self::Mirror,
        Self::Dielectric,
        Self::Conductor,
        Self::RoughConductor,
        Self::RoughDielectric,
        Self::OrenNayar,
        Self::Schlick,
        Self::ShirleyAshikhmin,
    ];

    /// The model's parameter declaration.
    pub fn def(self) -> &'static ModelDef {
        match self {
            Self::Lambert => &models::lambert::DEF,
            Self::Mirror => &models::mirror::DEF,
            Self::Dielectric => &models::dielectric::DEF,
            Self::Conductor => &models::conductor::DEF,
            Self::RoughConductor => &models::microfacet::ROUGH_CONDUCTOR_DEF,
            Self::RoughDielectric => &models::microfacet::ROUGH_DIELECTRIC_DEF,
            Self::OrenNayar => &models::oren_nayar::DEF,
            Self::Schlick => &models::schlick::DEF,
            Self::ShirleyAshikhmin => &models::ashikhmin::DEF,
        }
    }

    /// The model called `name` (case-insensitive).
    pub fn by_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.def().name.eq_ignore_ascii_case(name))
    }

    /// True if light can pass through the surface: the BSDF then sees both sides as
    /// they are (no two-sided flipping), and the geometric normal marks the outside.
    pub fn is_transmissive(self) -> bool {
        matches!(self, Self::Dielectric | Self::RoughDielectric)
    }
}

/// How a surface scatters light.
#[derive(Clone)]
pub enum Surface {
    /// A built-in model with parameters resolved against its declaration.
    Builtin {
        /// Which model.
        model: BuiltinModel,
        /// Its parameters, in declaration order.
        params: ResolvedParams,
    },
    /// A model from outside the workspace.
    Custom {
        /// Builds the BSDF at a hit.
        builder: Arc<dyn DynBsdfBuilder>,
        /// Whether it transmits (see [`BuiltinModel::is_transmissive`]).
        transmissive: bool,
    },
}

impl std::fmt::Debug for Surface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Builtin { model, params } => {
                f.debug_struct("Builtin").field("model", model).field("params", params).finish()
            }
            Self::Custom { transmissive, .. } => f.debug_struct("Custom").field("transmissive", transmissive).finish(),
        }
    }
}

/// A named material: a surface and, for area lights, an emitted radiance.
#[derive(Clone, Debug)]
pub struct Material {
    /// The name from the scene file (used in messages).
    pub name: String,
    /// Scattering.
    pub surface: Surface,
    /// Emitted radiance, on the front face only (counter-clockwise winding), or `None`.
    pub emission: Option<Colour>,
}

impl Material {
    /// A built-in model with parameters given by name; values are range-checked against
    /// the model's declaration and errors name the material and the parameter.
    pub fn builtin(name: &str, model: BuiltinModel, params: &[(&str, ParamValue)]) -> Result<Self, ParamError> {
        Ok(Self {
            name: name.into(),
            surface: Surface::Builtin { model, params: model.def().resolve(name, params)? },
            emission: None,
        })
    }

    /// A Lambertian material; the albedo must lie in [0, 1].
    pub fn diffuse(name: &str, albedo: Colour) -> Result<Self, ParamError> {
        Self::builtin(name, BuiltinModel::Lambert, &[("reflectance", ParamValue::Colour(albedo))])
    }

    /// A clear smooth dielectric of index `ior`.
    pub fn dielectric(name: &str, ior: f32) -> Result<Self, ParamError> {
        Self::builtin(name, BuiltinModel::Dielectric, &[("ior", ParamValue::Scalar(ior))])
    }

    /// A material whose BSDF comes from outside the workspace.
    pub fn custom(name: &str, builder: Arc<dyn DynBsdfBuilder>, transmissive: bool) -> Self {
        Self { name: name.into(), surface: Surface::Custom { builder, transmissive }, emission: None }
    }

    /// This material, emitting `radiance` from its front faces.
    pub fn with_emission(mut self, radiance: Colour) -> Self {
        self.emission = Some(radiance);
        self
    }

    /// True if the BSDF acts on both faces the same way (everything that does not
    /// transmit).
    pub fn is_two_sided(&self) -> bool {
        match &self.surface {
            Surface::Builtin { model, .. } => !model.is_transmissive(),
            Surface::Custom { transmissive, .. } => !transmissive,
        }
    }

    /// True if the index of refraction varies with wavelength: paths through it must
    /// follow a single wavelength.
    pub fn is_dispersive(&self) -> bool {
        match &self.surface {
            Surface::Builtin { model: BuiltinModel::Dielectric, params } => Dielectric::<1>::is_dispersive(params),
            _ => false,
        }
    }

    /// The Beer–Lambert absorption coefficient inside a transmissive material, if any.
    pub fn absorption(&self) -> Option<&Colour> {
        match &self.surface {
            Surface::Builtin { model: BuiltinModel::Dielectric, params } => Dielectric::<1>::absorption(params),
            _ => None,
        }
    }

    /// The BSDF at the path's wavelengths.
    #[inline]
    pub fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> MaterialBsdf<'_, N> {
        match &self.surface {
            Surface::Builtin { model, params } => match model {
                BuiltinModel::Lambert => MaterialBsdf::Lambert(Lambert::from_params(params, wl)),
                BuiltinModel::Mirror => MaterialBsdf::Mirror(Mirror::from_params(params, wl)),
                BuiltinModel::Dielectric => MaterialBsdf::Dielectric(Dielectric::from_params(params, wl)),
                BuiltinModel::Conductor => MaterialBsdf::Conductor(SmoothConductor::from_params(params, wl)),
                BuiltinModel::RoughConductor => MaterialBsdf::RoughConductor(RoughConductor::from_params(params, wl)),
                BuiltinModel::RoughDielectric => {
                    MaterialBsdf::RoughDielectric(RoughDielectric::from_params(params, wl))
                }
                BuiltinModel::OrenNayar => MaterialBsdf::OrenNayar(OrenNayar::from_params(params, wl)),
                BuiltinModel::Schlick => MaterialBsdf::Schlick(Schlick::from_params(params, wl)),
                BuiltinModel::ShirleyAshikhmin => {
                    MaterialBsdf::ShirleyAshikhmin(AshikhminShirley::from_params(params, wl))
                }
            },
            Surface::Custom { builder, .. } => MaterialBsdf::Custom(brdf::instantiate(builder.as_ref(), wl)),
        }
    }
}

/// The BSDF of one hit: a built-in model by value, or a boxed custom one.
pub enum MaterialBsdf<'a, const N: usize> {
    /// Lambert.
    Lambert(Lambert<N>),
    /// Perfect mirror.
    Mirror(Mirror<N>),
    /// Smooth dielectric.
    Dielectric(Dielectric<N>),
    /// Smooth conductor.
    Conductor(SmoothConductor<N>),
    /// GGX conductor.
    RoughConductor(RoughConductor<N>),
    /// GGX dielectric.
    RoughDielectric(RoughDielectric<N>),
    /// Oren–Nayar.
    OrenNayar(OrenNayar<N>),
    /// Schlick 1994.
    Schlick(Schlick<N>),
    /// Shirley–Ashikhmin 2000.
    ShirleyAshikhmin(AshikhminShirley<N>),
    /// A model from outside the workspace.
    Custom(Box<dyn Bsdf<N> + 'a>),
}

macro_rules! dispatch {
    ($self:ident, $b:ident => $e:expr) => {
        match $self {
            Self::Lambert($b) => $e,
            Self::Mirror($b) => $e,
            Self::Dielectric($b) => $e,
            Self::Conductor($b) => $e,
            Self::RoughConductor($b) => $e,
            Self::RoughDielectric($b) => $e,
            Self::OrenNayar($b) => $e,
            Self::Schlick($b) => $e,
            Self::ShirleyAshikhmin($b) => $e,
            Self::Custom($b) => $e,
        }
    };
}

impl<const N: usize> Bsdf<N> for MaterialBsdf<'_, N> {
    #[inline]
    fn flags(&self) -> ScatterFlags {
        dispatch!(self, b => b.flags())
    }
    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        dispatch!(self, b => b.eval(wo, wi))
    }
    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        dispatch!(self, b => b.pdf(wo, wi))
    }
    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        dispatch!(self, b => b.sample(wo, uc, u))
    }
}
