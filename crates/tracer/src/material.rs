//! Surface materials: which BSDF model a triangle has, with its resolved parameters, and
//! what it emits.
//!
//! Registered models are named by [`ModelId`] and carry their typed parameters
//! ([`ModelParams`], from the `brdf` registry); models written outside our crates plug in
//! through [`brdf::DynBsdfBuilder`] without any change to the tracer.

use brdf::params::{ParamError, ParamValue};
use brdf::{Bsdf, BsdfSample, DynBsdfBuilder, ModelBsdf, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::spectrum::Colour;
use spectral::{SampledSpectrum, SampledWavelengths};
use std::sync::Arc;

use crate::texture::{Alpha, AlphaMode, MaterialTextures};

pub use brdf::{ModelId, ModelParams};

/// How a surface scatters light.
#[derive(Clone)]
pub enum Surface {
    /// A registered model ([`brdf::ModelId`]) with its typed parameters.
    Builtin(ModelParams),
    /// A model from outside the workspace.
    Custom {
        /// Builds the BSDF at a hit.
        builder: Arc<dyn DynBsdfBuilder>,
        /// Whether it transmits (see [`brdf::Model::is_transmissive`]).
        transmissive: bool,
    },
}

impl std::fmt::Debug for Surface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Builtin(params) => f.debug_tuple("Builtin").field(params).finish(),
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
    /// Textures that modulate its parameters, normal, emission and alpha, or `None`.
    pub textures: Option<Arc<MaterialTextures>>,
}

impl Material {
    /// A built-in model with parameters given by name; values are range-checked against
    /// the model's declaration and errors name the material and the parameter.
    pub fn builtin(name: &str, model: ModelId, params: &[(&str, ParamValue)]) -> Result<Self, ParamError> {
        Ok(Self::from_params(name, model.resolve(name, params)?))
    }

    /// A registered model with parameters already typed (e.g. `LambertParams { .. }.into()`).
    pub fn from_params(name: &str, params: ModelParams) -> Self {
        Self { name: name.into(), surface: Surface::Builtin(params), emission: None, textures: None }
    }

    /// A Lambertian material; the albedo must lie in [0, 1].
    pub fn diffuse(name: &str, albedo: Colour) -> Result<Self, ParamError> {
        Self::builtin(name, ModelId::Lambert, &[("reflectance", ParamValue::Colour(albedo))])
    }

    /// A clear smooth dielectric of index `ior`.
    pub fn dielectric(name: &str, ior: f32) -> Result<Self, ParamError> {
        Self::builtin(name, ModelId::Dielectric, &[("ior", ParamValue::Scalar(ior))])
    }

    /// The registered model and its parameters, or `None` for a custom BSDF.
    pub fn params(&self) -> Option<&ModelParams> {
        match &self.surface {
            Surface::Builtin(p) => Some(p),
            Surface::Custom { .. } => None,
        }
    }

    /// The registered model, or `None` for a custom BSDF.
    pub fn model(&self) -> Option<ModelId> {
        self.params().map(ModelParams::model)
    }

    /// The WGSL twin of a custom BSDF, if its builder ships one (`None` for registered
    /// models, whose twins the registry holds).
    pub fn wgsl_twin(&self) -> Option<brdf::wgsl::WgslTwin> {
        match &self.surface {
            Surface::Builtin(_) => None,
            Surface::Custom { builder, .. } => builder.wgsl_twin(),
        }
    }

    /// A material whose BSDF comes from outside the workspace.
    pub fn custom(name: &str, builder: Arc<dyn DynBsdfBuilder>, transmissive: bool) -> Self {
        Self { name: name.into(), surface: Surface::Custom { builder, transmissive }, emission: None, textures: None }
    }

    /// This material, emitting `radiance` from its front faces.
    pub fn with_emission(mut self, radiance: Colour) -> Self {
        self.emission = Some(radiance);
        self
    }

    /// This material with `textures` (none if they are empty).
    pub fn with_textures(mut self, textures: MaterialTextures) -> Self {
        self.textures = (!textures.is_empty()).then(|| Arc::new(textures));
        self
    }

    /// Whether an emissive texture modulates the emission: such an emitter is found only
    /// by paths that hit it, never sampled as a light (its power varies over the surface).
    #[inline]
    pub fn has_textured_emission(&self) -> bool {
        self.textures.as_ref().is_some_and(|t| t.emissive.is_some())
    }

    /// The material's alpha, if it can be (partly) transparent.
    #[inline]
    pub fn alpha(&self) -> Option<&Alpha> {
        self.textures.as_ref()?.alpha.as_ref().filter(|a| a.mode != AlphaMode::Opaque)
    }

    /// The BSDF at a hit with texture coordinates `uv` (textures applied, if any).
    /// Always inlined, the textured path kept out of line: built in place, the untextured
    /// BSDF costs what [`Material::bsdf`] does (out of line, this cost 3 % of a Cornell-box
    /// render).
    #[inline(always)]
    pub fn bsdf_at<const N: usize>(&self, uv: Vec2, wl: &SampledWavelengths<N>) -> MaterialBsdf<'_, N> {
        match &self.textures {
            None => self.bsdf(wl),
            Some(t) => self.textured_bsdf(t, uv, wl),
        }
    }

    #[inline(never)]
    fn textured_bsdf<const N: usize>(
        &self,
        textures: &MaterialTextures,
        uv: Vec2,
        wl: &SampledWavelengths<N>,
    ) -> MaterialBsdf<'_, N> {
        match &self.surface {
            Surface::Builtin(p) => MaterialBsdf::Builtin(p.bsdf_textured(wl, &textures.texels(uv, wl))),
            Surface::Custom { .. } => self.bsdf(wl),
        }
    }

    /// The emitted radiance at a hit with texture coordinates `uv`, if any.
    #[inline(always)]
    pub fn emission_at<const N: usize>(&self, uv: Vec2, wl: &SampledWavelengths<N>) -> Option<SampledSpectrum<N>> {
        let e = self.emission.as_ref()?.sample(wl);
        Some(match &self.textures {
            Some(t) => e * t.emission_scale(uv, wl),
            None => e,
        })
    }

    /// True if the BSDF acts on both faces the same way (everything that does not
    /// transmit).
    #[inline]
    pub fn is_two_sided(&self) -> bool {
        match &self.surface {
            Surface::Builtin(p) => !p.is_transmissive(),
            Surface::Custom { transmissive, .. } => !transmissive,
        }
    }

    /// True if the index of refraction varies with wavelength: paths through it must
    /// follow a single wavelength.
    #[inline]
    pub fn is_dispersive(&self) -> bool {
        matches!(&self.surface, Surface::Builtin(p) if p.is_dispersive())
    }

    /// The Beer–Lambert absorption coefficient inside a transmissive material, if any.
    #[inline]
    pub fn absorption(&self) -> Option<&Colour> {
        match &self.surface {
            Surface::Builtin(p) => p.absorption(),
            Surface::Custom { .. } => None,
        }
    }

    /// The BSDF at the path's wavelengths.
    #[inline(always)]
    pub fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> MaterialBsdf<'_, N> {
        match &self.surface {
            Surface::Builtin(p) => MaterialBsdf::Builtin(p.bsdf(wl)),
            Surface::Custom { builder, .. } => MaterialBsdf::Custom(brdf::instantiate(builder.as_ref(), wl)),
        }
    }
}

/// The BSDF of one hit: a registered model by value, or a boxed custom one.
pub enum MaterialBsdf<'a, const N: usize> {
    /// A registered model.
    Builtin(ModelBsdf<N>),
    /// A model from outside the workspace.
    Custom(Box<dyn Bsdf<N> + 'a>),
}

impl<const N: usize> Bsdf<N> for MaterialBsdf<'_, N> {
    #[inline]
    fn flags(&self) -> ScatterFlags {
        match self {
            Self::Builtin(b) => b.flags(),
            Self::Custom(b) => b.flags(),
        }
    }
    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        match self {
            Self::Builtin(b) => b.eval(wo, wi),
            Self::Custom(b) => b.eval(wo, wi),
        }
    }
    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Self::Builtin(b) => b.pdf(wo, wi),
            Self::Custom(b) => b.pdf(wo, wi),
        }
    }
    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        match self {
            Self::Builtin(b) => b.sample(wo, uc, u),
            Self::Custom(b) => b.sample(wo, uc, u),
        }
    }
    #[inline]
    fn eta(&self) -> f32 {
        match self {
            Self::Builtin(b) => b.eta(),
            Self::Custom(b) => b.eta(),
        }
    }
}
