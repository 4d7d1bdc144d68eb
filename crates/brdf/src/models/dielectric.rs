//! The smooth dielectric interface.

use crate::fresnel::{fresnel_dielectric, fresnel_schlick, reflect_local, refract_local};
use crate::params::{ModelDef, ParamDef, ParamKind, ResolvedParams};
use crate::{Bsdf, BsdfSample, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};

/// The smooth dielectric's declaration.
pub const DEF: ModelDef = ModelDef {
    name: "dielectric",
    doc: "Smooth dielectric: specular reflection with Fresnel probability, Snell refraction, total internal reflection.",
    params: &[
        ParamDef {
            name: "ior",
            kind: ParamKind::Scalar,
            min: 1.0e-3,
            max: 10.0,
            default: 1.5,
            mtl_key: Some("Ni"),
            doc: "index of refraction inside (the normal points outside, index 1)",
        },
        ParamDef {
            name: "tint",
            kind: ParamKind::Spectrum,
            min: 0.0,
            max: 1.0,
            default: 1.0,
            mtl_key: Some("Tf"),
            doc: "colour filter on reflection and transmission",
        },
        ParamDef {
            name: "schlick",
            kind: ParamKind::Scalar,
            min: 0.0,
            max: 1.0,
            default: 0.0,
            mtl_key: None,
            doc: "1 for Schlick's Fresnel approximation, 0 for the exact formula",
        },
    ],
};

/// How a dielectric computes its Fresnel reflectance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FresnelModel {
    /// The exact unpolarised formula (both polarisations).
    #[default]
    Exact,
    /// Schlick's approximation.
    Schlick,
}

/// A smooth dielectric interface (glass, water): specular reflection with probability F
/// and refraction by Snell's law with probability 1 − F, including total internal
/// reflection. +z is the outside; η = n_inside / n_outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric<const N: usize> {
    /// Relative index of refraction n_inside / n_outside.
    pub eta: f32,
    /// Fresnel formula.
    pub fresnel: FresnelModel,
    /// Colour filter on both reflection and transmission (1 for clear glass).
    pub tint: SampledSpectrum<N>,
}

impl<const N: usize> Dielectric<N> {
    #[inline]
    fn reflectance(&self, cos_o: f32) -> f32 {
        match self.fresnel {
            FresnelModel::Exact => fresnel_dielectric(cos_o, self.eta),
            FresnelModel::Schlick => fresnel_schlick(cos_o, self.eta),
        }
    }
}

impl<const N: usize> Bsdf<N> for Dielectric<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::TRANSMISSION | ScatterFlags::SPECULAR
    }
    fn eval(&self, _wo: Vec3, _wi: Vec3) -> SampledSpectrum<N> {
        SampledSpectrum::zero()
    }
    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, _u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        if uc < r {
            let wi = reflect_local(wo);
            return Some(BsdfSample {
                wi,
                f: self.tint * (r / wi.z.abs()),
                pdf: r,
                flags: ScatterFlags::REFLECTION | ScatterFlags::SPECULAR,
            });
        }
        let wi = refract_local(wo, self.eta)?;
        let t = 1.0 - r;
        // Radiance is compressed by (n_i/n_t)² on entering a denser medium (Veach 1997
        // §5.2); η' is n on ωi's side over n on ωo's side... here n_t/n_i for ωo → ωi.
        let etap = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        Some(BsdfSample {
            wi,
            f: self.tint * (t / (wi.z.abs() * etap * etap)),
            pdf: t,
            flags: ScatterFlags::TRANSMISSION | ScatterFlags::SPECULAR,
        })
    }
}

impl<const N: usize> Dielectric<N> {
    /// From parameters resolved against [`DEF`], at the path's wavelengths.
    pub fn from_params(p: &ResolvedParams, wl: &SampledWavelengths<N>) -> Self {
        let fresnel = if p.scalar(2) >= 0.5 { FresnelModel::Schlick } else { FresnelModel::Exact };
        Self { eta: p.scalar(0), fresnel, tint: p.colour(1).sample(wl) }
    }
}
