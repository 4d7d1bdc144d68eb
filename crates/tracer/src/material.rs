//! Surface materials: which BSDF a triangle has, with its colours, and what it emits.

use brdf::models::FresnelModel;
use brdf::{Bsdf, BsdfSample, Dielectric, Lambert, Mirror, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::spectrum::Colour;
use spectral::{SampledSpectrum, SampledWavelengths};

/// How a surface scatters light.
#[derive(Clone, Debug, PartialEq)]
pub enum Surface {
    /// Lambertian, two-sided.
    Diffuse {
        /// Albedo.
        albedo: Colour,
    },
    /// Perfect mirror, two-sided.
    Mirror {
        /// Reflectance.
        reflectance: Colour,
    },
    /// Smooth dielectric; the geometric normal points outside.
    Dielectric {
        /// Index of refraction inside (outside is vacuum/air = 1).
        ior: f32,
        /// Colour filter (1 for clear).
        tint: Colour,
        /// Fresnel formula.
        fresnel: FresnelModel,
    },
}

/// A named material: a surface and, for area lights, an emitted radiance.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The name from the scene file (used in messages).
    pub name: String,
    /// Scattering.
    pub surface: Surface,
    /// Emitted radiance, on the front face only (counter-clockwise winding), or `None`.
    pub emission: Option<Colour>,
}

impl Material {
    /// A grey Lambertian material that emits nothing.
    pub fn diffuse(name: &str, albedo: Colour) -> Self {
        Self { name: name.into(), surface: Surface::Diffuse { albedo }, emission: None }
    }

    /// True if the surface is a pure Dirac delta (light sampling cannot reach it).
    pub fn is_specular(&self) -> bool {
        !matches!(self.surface, Surface::Diffuse { .. })
    }

    /// True if the BSDF acts on both faces the same way (everything but dielectrics).
    pub fn is_two_sided(&self) -> bool {
        !matches!(self.surface, Surface::Dielectric { .. })
    }

    /// The BSDF at the path's wavelengths.
    #[inline]
    pub fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> MaterialBsdf<N> {
        match &self.surface {
            Surface::Diffuse { albedo } => MaterialBsdf::Lambert(Lambert { reflectance: albedo.sample(wl) }),
            Surface::Mirror { reflectance } => MaterialBsdf::Mirror(Mirror { reflectance: reflectance.sample(wl) }),
            Surface::Dielectric { ior, tint, fresnel } => {
                MaterialBsdf::Dielectric(Dielectric { eta: *ior, fresnel: *fresnel, tint: tint.sample(wl) })
            }
        }
    }
}

/// The closed set of built-in BSDFs, dispatched by `match` (no dynamic dispatch on the
/// hot path).
#[derive(Clone, Copy, Debug)]
pub enum MaterialBsdf<const N: usize> {
    /// Lambert.
    Lambert(Lambert<N>),
    /// Perfect mirror.
    Mirror(Mirror<N>),
    /// Smooth dielectric.
    Dielectric(Dielectric<N>),
}

impl<const N: usize> Bsdf<N> for MaterialBsdf<N> {
    #[inline]
    fn flags(&self) -> ScatterFlags {
        match self {
            Self::Lambert(b) => b.flags(),
            Self::Mirror(b) => b.flags(),
            Self::Dielectric(b) => b.flags(),
        }
    }
    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        match self {
            Self::Lambert(b) => b.eval(wo, wi),
            Self::Mirror(b) => b.eval(wo, wi),
            Self::Dielectric(b) => b.eval(wo, wi),
        }
    }
    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Self::Lambert(b) => b.pdf(wo, wi),
            Self::Mirror(b) => b.pdf(wo, wi),
            Self::Dielectric(b) => b.pdf(wo, wi),
        }
    }
    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        match self {
            Self::Lambert(b) => b.sample(wo, uc, u),
            Self::Mirror(b) => b.sample(wo, uc, u),
            Self::Dielectric(b) => b.sample(wo, uc, u),
        }
    }
}
