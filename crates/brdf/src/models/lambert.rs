//! Lambertian (perfectly diffuse) reflection.

use crate::sampling::{cosine_hemisphere_two_sided, cosine_hemisphere_two_sided_pdf};
use crate::wgsl::{ModelWgsl, WgslPiece, WgslTextureSlots};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::FRAC_1_PI;

crate::model_params! {
    /// Lambert's parameters.
    pub struct LambertParams for "lambert" {
        doc: "Lambertian reflection f = R/π (Lambert 1760), two-sided.",
        reflectance: spectrum { doc: "diffuse albedo R", default: 0.5, mtl: "Kd" },
    }
}

impl Model for LambertParams {
    type Bsdf<const N: usize> = Lambert<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots::base("reflectance"),
        source: include_str!("lambert.wgsl"),
        needs: &[WgslPiece::Sampling],
        constants: &[],
    };

    const TEXTURE_SLOTS: TextureSlots = TextureSlots::BASE_COLOUR;

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Lambert<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> Lambert<N> {
        Lambert { reflectance: texels.base(self.reflectance.sample(wl)) }
    }
}

#[inline]
pub(crate) fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// Lambertian reflection f = R/π, sampled by cosine-weighted hemisphere sampling. It
/// reflects on the side ωo is on, so it is two-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert<const N: usize> {
    /// Albedo R per wavelength, in [0, 1].
    pub reflectance: SampledSpectrum<N>,
}

impl<const N: usize> Bsdf<N> for Lambert<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE
    }

    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        if same_hemisphere(wo, wi) { self.reflectance * FRAC_1_PI } else { SampledSpectrum::zero() }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        cosine_hemisphere_two_sided_pdf(wo, wi)
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        let (wi, pdf) = cosine_hemisphere_two_sided(wo, u)?;
        Some(BsdfSample { wi, f: self.reflectance * FRAC_1_PI, pdf, flags: self.flags() })
    }
}
