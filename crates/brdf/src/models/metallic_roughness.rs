//! glTF 2.0's metallic–roughness material (the glTF 2.0 specification, Appendix B, "BRDF
//! Implementation"), the material every glTF file describes.
//!
//! With h the half vector of ωo and ωi, VdotH = ωo·h and m₅ = (1 − VdotH)⁵:
//!
//! * specular_brdf = D(h) G2(ωo, ωi) / (4 |cos θo| |cos θi|), GGX with α = roughness²
//!   and height-correlated Smith masking (the appendix's V_GGX · D_GGX);
//! * metal_brdf = (base + (1 − base) m₅) · specular_brdf (`conductor_fresnel`);
//! * dielectric_brdf = (1 − F) base/π + F specular_brdf, F = f₀ + (1 − f₀) m₅ with
//!   f₀ = ((η − 1)/(η + 1))² (`fresnel_mix`; f₀ = 0.04 at the default η = 1.5,
//!   `KHR_materials_ior` changes η);
//! * f = (1 − metallic) dielectric_brdf + metallic · metal_brdf.
//!
//! Like the appendix's, this is a single-scattering model (a rough white metal reflects
//! 31 % at normal incidence), and `fresnel_mix` weights the diffuse base by 1 − F at the
//! microfacet rather than by what the coating lets through, so the dielectric part is not
//! energy-conserving: a smooth white dielectric reflects 1.03× what it receives at
//! cos θo = 0.5 and 1.72× at cos θo = 0.05 (measured and pinned by the tests; the metal
//! never exceeds 1; `cargo test -p brdf --lib metallic_roughness_albedo_table -- --ignored
//! --nocapture` prints all of these albedos). That is the specification's model, kept as written so that glTF
//! files render as their authors' viewers show them.
//!
//! Sampling is a one-sample mixture of visible-normal GGX sampling (Heitz 2018) and
//! cosine sampling, the specular lobe chosen with its estimated share of the reflected
//! energy at ωo (at least 10 % for each lobe present); pdf = p_s · D_ωo(h)/(4 ωo·h) +
//! (1 − p_s) cos θi/π. Reflection only, two-sided.

use crate::frame::{flip_z, reflect, upper_pair};
use crate::models::microfacet::Ggx;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::wgsl::{ModelWgsl, WgslConstant, WgslPiece, WgslTextureSlots, WgslValue};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::FRAC_1_PI;

crate::model_params! {
    /// glTF's metallic–roughness parameters (`pbrMetallicRoughness` and `KHR_materials_ior`).
    pub struct MetallicRoughnessParams for "metallicroughness" {
        doc: "glTF 2.0 metallic-roughness (the specification's Appendix B): a GGX specular lobe (α = roughness², \
              height-correlated Smith) over a Lambertian base mixed by Schlick Fresnel, blended with a Schlick \
              metal of F0 = base colour by `metallic`; reflection only, two-sided.",
        base_color: spectrum {
            doc: "base colour: the diffuse albedo of the dielectric part and the normal-incidence reflectance of \
                  the metal part (glTF baseColorFactor)",
            default: 1.0,
            mtl: "Kd",
        },
        metallic: scalar {
            doc: "metalness: 0 dielectric, 1 metal, blended in between (glTF metallicFactor)",
            default: 1.0,
            min: 0.0,
            max: 1.0,
            mtl: "Pm",
        },
        roughness: scalar {
            doc: "perceptual roughness r (glTF roughnessFactor); the GGX α is r²",
            default: 1.0,
            min: 0.0,
            max: 1.0,
            mtl: "Pr",
        },
        ior: scalar {
            doc: "index of refraction of the dielectric part, giving F0 = ((η − 1)/(η + 1))² (KHR_materials_ior)",
            default: 1.5,
            min: 1.0,
            max: 10.0,
            mtl: "Ni",
        },
    }
}

impl Model for MetallicRoughnessParams {
    type Bsdf<const N: usize> = MetallicRoughness<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots { metallic_roughness: true, ..WgslTextureSlots::base("base_color") },
        source: include_str!("metallic_roughness.wgsl"),
        needs: &[WgslPiece::Sampling, WgslPiece::Ggx],
        constants: &[WgslConstant {
            name: "MAT_METALLICROUGHNESS_MIN_LOBE_PROBABILITY",
            value: WgslValue::F32(MIN_LOBE_PROBABILITY),
        }],
    };

    const TEXTURE_SLOTS: TextureSlots = TextureSlots { base_colour: true, specular: false, metallic_roughness: true };

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> MetallicRoughness<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, t: &Texels<N>) -> MetallicRoughness<N> {
        let base = t.base(self.base_color.sample(wl));
        MetallicRoughness::new(base, self.metallic * t.metallic, self.roughness * t.roughness, self.ior)
    }
}

/// Each lobe present is sampled with at least this probability.
const MIN_LOBE_PROBABILITY: f32 = 0.1;

/// The metallic–roughness BRDF bound to a path's wavelengths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness<const N: usize> {
    base: SampledSpectrum<N>,
    metallic: f32,
    distribution: Ggx,
    /// The dielectric part's normal-incidence reflectance ((η − 1)/(η + 1))².
    f0: f32,
    /// The base colour's mean over the wavelengths, for the lobe probabilities.
    mean_base: f32,
}

/// (1 − c)⁵ for c clamped to [0, 1]: Schlick's Fresnel weight.
#[inline]
fn schlick_weight(c: f32) -> f32 {
    let m = 1.0 - c.clamp(0.0, 1.0);
    (m * m) * (m * m) * m
}

impl<const N: usize> MetallicRoughness<N> {
    /// The BRDF of base colour `base`, metalness and perceptual roughness in [0, 1] (clamped)
    /// and dielectric index `ior` ≥ 1.
    pub fn new(base: SampledSpectrum<N>, metallic: f32, roughness: f32, ior: f32) -> Self {
        let r = roughness.clamp(0.0, 1.0);
        let ior = ior.max(1.0);
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        Self {
            base,
            metallic: metallic.clamp(0.0, 1.0),
            distribution: Ggx::isotropic(r * r),
            f0,
            mean_base: base.average(),
        }
    }

    /// The probability of sampling the specular lobe at cos θo = `zo`: the lobes' Fresnel
    /// weights at normal-to-ωo microfacets (mean over wavelengths) — metallic ·
    /// F_metal + (1 − metallic) F against (1 − metallic)(1 − F) base — each kept at ≥ 10 %;
    /// 1 when there is no diffuse part.
    #[inline]
    fn specular_probability(&self, zo: f32) -> f32 {
        let w = schlick_weight(zo);
        let dielectric = self.f0 + (1.0 - self.f0) * w;
        let wd = (1.0 - self.metallic) * (1.0 - dielectric) * self.mean_base;
        if wd <= 0.0 {
            return 1.0;
        }
        let metal = self.mean_base + (1.0 - self.mean_base) * w;
        let ws = self.metallic * metal + (1.0 - self.metallic) * dielectric;
        (ws / (ws + wd)).clamp(MIN_LOBE_PROBABILITY, 1.0 - MIN_LOBE_PROBABILITY)
    }

    /// f for ωo, ωi both on the +z side.
    #[inline]
    fn eval_up(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        let hv = wo + wi;
        let len2 = hv.length_squared();
        if len2.is_nan() || len2 <= 0.0 {
            return SampledSpectrum::zero();
        }
        let h = hv / len2.sqrt();
        let ggx = &self.distribution;
        let w = schlick_weight(wo.dot(h));
        let dielectric = self.f0 + (1.0 - self.f0) * w;
        // D G2 / (4 z_o z_i) with the height-correlated G2 = 2 z_o z_i / (s_o z_i + s_i z_o).
        let den = 2.0 * (ggx.s(wo) * wi.z + ggx.s(wi) * wo.z);
        let specular = if den > 0.0 { ggx.d(h) / den } else { 0.0 };
        let one = SampledSpectrum::one();
        let metal = self.base + (one - self.base) * w;
        let diffuse = (1.0 - self.metallic) * (1.0 - dielectric) * FRAC_1_PI;
        self.base * diffuse + (metal * self.metallic + one * ((1.0 - self.metallic) * dielectric)) * specular
    }

    /// The mixture pdf for ωo, ωi both on the +z side.
    #[inline]
    fn pdf_up(&self, wo: Vec3, wi: Vec3) -> f32 {
        let ps = self.specular_probability(wo.z);
        let mut pdf = (1.0 - ps) * cosine_hemisphere_pdf(wi.z);
        let hv = wo + wi;
        let len2 = hv.length_squared();
        if len2 > 0.0 {
            pdf += ps * self.distribution.reflection_pdf(wo, hv / len2.sqrt());
        }
        pdf
    }
}

impl<const N: usize> Bsdf<N> for MetallicRoughness<N> {
    fn flags(&self) -> ScatterFlags {
        let f = ScatterFlags::REFLECTION | ScatterFlags::GLOSSY;
        // By metalness alone (not the base colour at these wavelengths): the flags then
        // do not depend on the wavelengths a path carries.
        if self.metallic < 1.0 { f | ScatterFlags::DIFFUSE } else { f }
    }

    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        upper_pair(wo, wi).map_or(SampledSpectrum::zero(), |(wo, wi)| self.eval_up(wo, wi))
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        upper_pair(wo, wi).map_or(0.0, |(wo, wi)| self.pdf_up(wo, wi))
    }

    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 || !wo.is_finite() {
            return None;
        }
        let down = wo.z < 0.0;
        let wo_up = if down { flip_z(wo) } else { wo };
        let (wi, flags) = if uc < self.specular_probability(wo_up.z) {
            let h = self.distribution.sample_visible(wo_up, u);
            (reflect(wo_up, h), ScatterFlags::REFLECTION | ScatterFlags::GLOSSY)
        } else {
            (cosine_hemisphere(u), ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE)
        };
        if wi.z <= 0.0 || !wi.is_finite() {
            return None;
        }
        let pdf = self.pdf_up(wo_up, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let f = self.eval_up(wo_up, wi);
        Some(BsdfSample { wi: if down { flip_z(wi) } else { wi }, f, pdf, flags })
    }
}

#[cfg(test)]
mod tests;
