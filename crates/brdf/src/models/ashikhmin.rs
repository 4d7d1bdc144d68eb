//! Ashikhmin and Shirley's anisotropic Phong BRDF (M. Ashikhmin, P. Shirley 2000, "An
//! Anisotropic Phong BRDF Model", Journal of Graphics Tools 5(2)).
//!
//! f = ρ_s + ρ_d with (k₁ = ωi, k₂ = ωo, k either of them, h their half vector, u, v the
//! tangent and bitangent)
//!
//! * ρ_s = √((n_u + 1)(n_v + 1)) / 8π · (n·h)^{(n_u (h·u)² + n_v (h·v)²)/(1 − (n·h)²)}
//!   / ((h·k) max(n·k₁, n·k₂)) · F(k·h), with F = R_s + (1 − R_s)(1 − k·h)⁵;
//! * ρ_d = 28 R_d / 23π · (1 − R_s)(1 − (1 − n·k₁/2)⁵)(1 − (1 − n·k₂/2)⁵).
//!
//! The specular lobe is sampled by the paper's half-vector recipe:
//! φ = atan(√((n_u + 1)/(n_v + 1)) tan(π ξ₁/2)) per quadrant of ξ₁,
//! cos θ_h = (1 − ξ₂)^{1/(n_u cos²φ + n_v sin²φ + 1)}, whose density is exactly
//! p_h = √((n_u + 1)(n_v + 1))/2π · (n·h)^{n_u cos²φ + n_v sin²φ}, and p(ωi) = p_h / (4 ωo·h)
//! (the reflection's Jacobian). Since ρ_s · n·k₁ = p(ωi) F n·k₁ / max(n·k₁, n·k₂) ≤ p(ωi) F,
//! the lobe reflects at most F of the energy: that is the paper's energy argument.
//!
//! (n·h)^e is computed as exp(½ (n_u h_x² + n_v h_y²) ln(1 − s²)/s²) with s² = h_x² + h_y²,
//! which has no 0/0 at h = n, no overflow for exponents up to 10⁶, and full precision when
//! 1 − n·h is below f32's resolution (WGSL has no `log1p`/`expm1`: mirror them with the
//! usual `log(1 + x)·x/((1 + x) − 1)` and `(exp(x) − 1)` series guards).

use crate::frame::{flip_z, upper_pair};
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::wgsl::{ModelWgsl, WgslConstant, WgslPiece, WgslTextureSlots, WgslValue};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2};

crate::model_params! {
    /// The Ashikhmin–Shirley parameters.
    pub struct AshikhminParams for "ashikhmin" {
        doc: "Ashikhmin & Shirley 2000 (JGT 5(2)) anisotropic Phong: a Schlick-Fresnel specular lobe with \
              exponents n_u, n_v over a coupled, energy-conserving diffuse term; reflection only, two-sided.",
        nu: scalar {
            doc: "Phong exponent n_u along the tangent u (larger: a narrower highlight across u)",
            default: 100.0,
            min: 0.0,
            max: MAX_EXPONENT,
            mtl: "nu",
        },
        nv: scalar { doc: "Phong exponent n_v along the bitangent v", default: 100.0, min: 0.0, max: MAX_EXPONENT, mtl: "nv" },
        rs: spectrum {
            doc: "specular reflectance R_s at normal incidence (Schlick Fresnel towards 1 at grazing)",
            default: 0.05,
            mtl: "Rs",
        },
        rd: spectrum { doc: "diffuse reflectance R_d of the substrate under the specular coat", default: 0.5, mtl: "Rd" },
    }
}

impl Model for AshikhminParams {
    type Bsdf<const N: usize> = Ashikhmin<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots { base_colour: Some("rd"), specular: Some("rs"), metallic_roughness: false },
        source: include_str!("ashikhmin.wgsl"),
        needs: &[WgslPiece::Sampling],
        constants: &[
            WgslConstant { name: "MAT_ASHIKHMIN_MAX_EXPONENT", value: WgslValue::F32(MAX_EXPONENT) },
            WgslConstant { name: "MAT_ASHIKHMIN_MIN_COS", value: WgslValue::F32(MIN_COS) },
            WgslConstant { name: "MAT_ASHIKHMIN_MIN_LOBE_PROBABILITY", value: WgslValue::F32(MIN_LOBE_PROBABILITY) },
        ],
    };

    const TEXTURE_SLOTS: TextureSlots = TextureSlots { base_colour: true, specular: true, metallic_roughness: false };

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Ashikhmin<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> Ashikhmin<N> {
        Ashikhmin::new(self.nu, self.nv, texels.spec(self.rs.sample(wl)), texels.base(self.rd.sample(wl)))
    }
}

/// The largest Phong exponent (the declared range).
pub const MAX_EXPONENT: f32 = 1.0e6;
/// Smallest cosine in the specular denominator, so that f stays finite on the horizon.
const MIN_COS: f32 = 1e-6;
/// Each lobe is sampled with at least this probability when its reflectance is not zero.
const MIN_LOBE_PROBABILITY: f32 = 0.1;

/// The Ashikhmin–Shirley BRDF bound to a path's wavelengths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ashikhmin<const N: usize> {
    nu: f32,
    nv: f32,
    rs: SampledSpectrum<N>,
    rd: SampledSpectrum<N>,
    /// √((n_u + 1)(n_v + 1)).
    norm: f32,
    /// √((n_u + 1)/(n_v + 1)), the azimuth warp of the sampling.
    aspect: f32,
    /// Mean R_s and mean R_d (1 − R_s) over the wavelengths, for the lobe probabilities.
    mean_rs: f32,
    mean_rd: f32,
}

/// (n·h)^{(n_u h_x² + n_v h_y²)/(1 − h_z²)} for a unit h with h_z ≥ 0.
#[inline]
pub fn phong_lobe(nu: f32, nv: f32, h: Vec3) -> f32 {
    let (hx2, hy2) = (h.x * h.x, h.y * h.y);
    let q = nu * hx2 + nv * hy2;
    if q <= 0.0 {
        return 1.0; // exponent 0 (or h = n, where every exponent gives 1)
    }
    let s2 = hx2 + hy2;
    if s2 >= 1.0 {
        return 0.0; // n·h = 0 with a positive exponent
    }
    (0.5 * q * ((-s2).ln_1p() / s2)).exp()
}

/// Samples a half vector by the paper's recipe (quadrants mirrored so that strata stay
/// contiguous): tan φ = √((n_u + 1)/(n_v + 1)) tan(π ξ₁/2),
/// cos θ = (1 − ξ₂)^{1/(n_u cos²φ + n_v sin²φ + 1)}.
#[inline]
pub fn sample_half(nu: f32, nv: f32, aspect: f32, u: Vec2) -> Vec3 {
    let v4 = 4.0 * u.x;
    let quadrant = (v4 as u32).min(3);
    let frac = v4 - quadrant as f32;
    let xi = if quadrant & 1 == 0 { frac } else { 1.0 - frac };
    // (cos φ, sin φ) ∝ (cos(πξ/2), aspect · sin(πξ/2)): tan φ as in the paper, without tan's pole.
    let a = FRAC_PI_2 * xi;
    let (c, s) = (a.cos().max(0.0), aspect * a.sin());
    let len = (c * c + s * s).sqrt();
    let (cos_phi, sin_phi) = (c / len, s / len);
    let (sx, sy) = match quadrant {
        0 => (1.0, 1.0),
        1 => (-1.0, 1.0),
        2 => (-1.0, -1.0),
        _ => (1.0, -1.0),
    };
    let e = nu * cos_phi * cos_phi + nv * sin_phi * sin_phi + 1.0;
    let l = (-u.y).ln_1p() / e; // ln cos θ
    let cos_theta = l.exp();
    let sin_theta = (-(2.0 * l).exp_m1()).clamp(0.0, 1.0).sqrt();
    Vec3::new(sx * sin_theta * cos_phi, sy * sin_theta * sin_phi, cos_theta)
}

/// 1 − (1 − x/2)⁵, the diffuse term's angular factor.
#[inline]
fn diffuse_factor(x: f32) -> f32 {
    let m = 1.0 - 0.5 * x;
    1.0 - (m * m) * (m * m) * m
}

impl<const N: usize> Ashikhmin<N> {
    /// The BRDF with exponents n_u, n_v (clamped to [0, 10⁶]) and reflectances R_s, R_d.
    pub fn new(nu: f32, nv: f32, rs: SampledSpectrum<N>, rd: SampledSpectrum<N>) -> Self {
        let (nu, nv) = (nu.clamp(0.0, MAX_EXPONENT), nv.clamp(0.0, MAX_EXPONENT));
        let mean_rd = (rd * (SampledSpectrum::one() - rs)).average();
        Self {
            nu,
            nv,
            rs,
            rd,
            norm: ((nu + 1.0) * (nv + 1.0)).sqrt(),
            aspect: ((nu + 1.0) / (nv + 1.0)).sqrt(),
            mean_rs: rs.average(),
            mean_rd,
        }
    }

    /// The probability of sampling the specular lobe for ωo at cosine `v2`: its estimated
    /// albedo F(v₂) (mean over wavelengths) against the diffuse term's exact albedo
    /// R_d (1 − R_s)(1 − (1 − v₂/2)⁵), each lobe kept at ≥ 10 % (the specular lobe is never
    /// zero: F ≥ (1 − k·h)⁵). 1 when the diffuse term vanishes.
    #[inline]
    fn specular_probability(&self, v2: f32) -> f32 {
        if self.mean_rd <= 0.0 {
            return 1.0;
        }
        let m = 1.0 - v2.clamp(0.0, 1.0);
        let ws = self.mean_rs + (1.0 - self.mean_rs) * (m * m) * (m * m) * m;
        let wd = self.mean_rd * diffuse_factor(v2);
        (ws / (ws + wd)).clamp(MIN_LOBE_PROBABILITY, 1.0 - MIN_LOBE_PROBABILITY)
    }

    /// f for ωo, ωi both on the +z side.
    #[inline]
    fn eval_up(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        let one = SampledSpectrum::one();
        let diffuse =
            self.rd * (one - self.rs) * (28.0 / 23.0 * FRAC_1_PI * diffuse_factor(wi.z) * diffuse_factor(wo.z));
        let hv = wo + wi;
        let len2 = hv.length_squared();
        if len2 <= 0.0 {
            return diffuse;
        }
        let h = hv / len2.sqrt();
        // k·h = |ωo + ωi|/2 and 1 − k·h = |ωo − ωi|²/(4(1 + k·h)): symmetric in ωo, ωi
        // (exactly reciprocal) and free of cancellation near the mirror direction.
        let kh = 0.5 * len2.sqrt();
        let m = ((wo - wi).length_squared() / (4.0 * (1.0 + kh))).clamp(0.0, 1.0);
        let fresnel = self.rs + (one - self.rs) * ((m * m) * (m * m) * m);
        let denom = kh.max(MIN_COS) * wi.z.max(wo.z).max(MIN_COS);
        let spec = self.norm * (0.125 * FRAC_1_PI) * phong_lobe(self.nu, self.nv, h) / denom;
        fresnel * spec + diffuse
    }

    /// The mixture pdf for ωo, ωi both on the +z side.
    #[inline]
    fn pdf_up(&self, wo: Vec3, wi: Vec3) -> f32 {
        let ps = self.specular_probability(wo.z);
        let mut pdf = (1.0 - ps) * cosine_hemisphere_pdf(wi.z);
        let hv = wo + wi;
        let len2 = hv.length_squared();
        if len2 > 0.0 {
            let h = hv / len2.sqrt();
            let kh = 0.5 * len2.sqrt();
            let ph = self.norm * (0.5 * FRAC_1_PI) * phong_lobe(self.nu, self.nv, h);
            pdf += ps * ph / (4.0 * kh.max(MIN_COS));
        }
        pdf
    }
}

impl<const N: usize> Bsdf<N> for Ashikhmin<N> {
    fn flags(&self) -> ScatterFlags {
        let f = ScatterFlags::REFLECTION | ScatterFlags::GLOSSY;
        if self.mean_rd > 0.0 { f | ScatterFlags::DIFFUSE } else { f }
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
            let h = sample_half(self.nu, self.nv, self.aspect, u);
            let oh = wo_up.dot(h);
            if oh <= 0.0 {
                return None;
            }
            ((2.0 * oh * h - wo_up).normalize(), ScatterFlags::REFLECTION | ScatterFlags::GLOSSY)
        } else {
            (cosine_hemisphere(u), ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE)
        };
        if wi.z <= 0.0 {
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
