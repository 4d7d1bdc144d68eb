//! Oren–Nayar rough diffuse reflection.

use crate::models::lambert::same_hemisphere;
use crate::sampling::{cosine_hemisphere_two_sided, cosine_hemisphere_two_sided_pdf};
use crate::wgsl::{ModelWgsl, WgslPiece, WgslTextureSlots};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2};

crate::model_params! {
    /// Oren–Nayar's parameters.
    pub struct OrenNayarParams for "orennayar" {
        doc: "Oren–Nayar rough diffuse reflection, the qualitative model (Oren & Nayar 1994, \"Generalization of \
              Lambert's Reflectance Model\", SIGGRAPH); σ = 0 is Lambert; two-sided.",
        reflectance: spectrum { doc: "diffuse albedo R (of the facets)", default: 0.5, mtl: "Kd" },
        sigma: scalar {
            doc: "roughness σ: standard deviation of the facet slope angle, radians",
            default: 0.3,
            min: 0.0,
            max: FRAC_PI_2,
        },
    }
}

impl Model for OrenNayarParams {
    type Bsdf<const N: usize> = OrenNayar<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots::base("reflectance"),
        source: include_str!("oren_nayar.wgsl"),
        needs: &[WgslPiece::Sampling],
        constants: &[],
    };

    const TEXTURE_SLOTS: TextureSlots = TextureSlots::BASE_COLOUR;

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> OrenNayar<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> OrenNayar<N> {
        OrenNayar::new(texels.base(self.reflectance.sample(wl)), self.sigma)
    }
}

/// The qualitative Oren–Nayar model (Oren & Nayar 1994, "Generalization of Lambert's
/// Reflectance Model", SIGGRAPH, its simplified "qualitative model"):
/// f = R/π (A + B max(0, cos(φi − φo)) sin α tan β), α = max(θi, θo), β = min(θi, θo),
/// A = 1 − 0.5 σ²/(σ² + 0.33), B = 0.45 σ²/(σ² + 0.09).
///
/// Since sin θi sin θo cos(φi − φo) = ωi,x ωo,x + ωi,y ωo,y and sin α tan β /
/// (sin θi sin θo) = 1/max(cos θi, cos θo), the angular term is evaluated as
/// max(0, ωi,x ωo,x + ωi,y ωo,y) / max(|cos θi|, |cos θo|): no trigonometry, and
/// visibly symmetric in ωi, ωo. Cosine-weighted sampling; two-sided like
/// [`crate::Lambert`]. The qualitative model leaves out interreflection: for R = 1 its
/// albedo is 0.56–0.89 at normal incidence for σ = π/2 … 0.3; yet at grazing incidence it
/// tends to A + B/2, which exceeds 1 for 0 < σ < 0.326 rad (by up to 1.5 % at σ ≈ 0.2), a
/// property of the fit (pinned by the tests).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrenNayar<const N: usize> {
    /// Facet albedo R per wavelength, in [0, 1].
    pub reflectance: SampledSpectrum<N>,
    /// A = 1 − 0.5 σ²/(σ² + 0.33).
    pub a: f32,
    /// B = 0.45 σ²/(σ² + 0.09).
    pub b: f32,
}

impl<const N: usize> OrenNayar<N> {
    /// The model for facet albedo R and roughness σ (radians).
    pub fn new(reflectance: SampledSpectrum<N>, sigma: f32) -> Self {
        let s2 = sigma * sigma;
        Self { reflectance, a: 1.0 - 0.5 * s2 / (s2 + 0.33), b: 0.45 * s2 / (s2 + 0.09) }
    }

    /// f / (R/π) = A + B max(0, cos Δφ) sin α tan β, for ωo, ωi on the same side.
    #[inline]
    fn factor(&self, wo: Vec3, wi: Vec3) -> f32 {
        let m = wo.z.abs().max(wi.z.abs());
        let c = (wo.x * wi.x + wo.y * wi.y).max(0.0);
        if m > 0.0 && c > 0.0 { self.a + self.b * (c / m) } else { self.a }
    }
}

impl<const N: usize> Bsdf<N> for OrenNayar<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE
    }

    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        if same_hemisphere(wo, wi) {
            self.reflectance * FRAC_1_PI * self.factor(wo, wi)
        } else {
            SampledSpectrum::zero()
        }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        cosine_hemisphere_two_sided_pdf(wo, wi)
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        let (wi, pdf) = cosine_hemisphere_two_sided(wo, u)?;
        Some(BsdfSample { wi, f: self.reflectance * FRAC_1_PI * self.factor(wo, wi), pdf, flags: self.flags() })
    }
}

#[cfg(test)]
mod tests;
