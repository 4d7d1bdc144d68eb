//! The perfect mirror.

use crate::fresnel::reflect_local;
use crate::params::{ModelDef, ParamDef, ParamKind, ResolvedParams};
use crate::{Bsdf, BsdfSample, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};

/// The mirror's declaration.
pub const DEF: ModelDef = ModelDef {
    name: "mirror",
    doc: "Perfect specular reflection (a Dirac delta at the mirror direction), two-sided.",
    params: &[ParamDef {
        name: "reflectance",
        kind: ParamKind::Spectrum,
        min: 0.0,
        max: 1.0,
        default: 1.0,
        mtl_key: Some("Ks"),
        doc: "reflectance at every angle",
    }],
};

/// A perfect mirror with reflectance R (1 for an ideal mirror): a Dirac delta at the
/// mirror direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror<const N: usize> {
    /// Reflectance per wavelength.
    pub reflectance: SampledSpectrum<N>,
}

impl<const N: usize> Bsdf<N> for Mirror<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::SPECULAR
    }
    fn eval(&self, _wo: Vec3, _wi: Vec3) -> SampledSpectrum<N> {
        SampledSpectrum::zero()
    }
    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }
    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, _u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 {
            return None;
        }
        let wi = reflect_local(wo);
        Some(BsdfSample { wi, f: self.reflectance / wi.z.abs(), pdf: 1.0, flags: self.flags() })
    }
}

impl<const N: usize> Mirror<N> {
    /// From parameters resolved against [`DEF`], at the path's wavelengths.
    pub fn from_params(p: &ResolvedParams, wl: &SampledWavelengths<N>) -> Self {
        Self { reflectance: p.colour(0).sample(wl) }
    }
}
