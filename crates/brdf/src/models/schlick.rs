//! Schlick's inexpensive BRDF (C. Schlick 1994, "An Inexpensive BRDF Model for
//! Physically-based Rendering", Computer Graphics Forum 13(3); seed thesis eq. 6.2–6.12).
//!
//! R_λ = S_λ(u) · D with S_λ(u) = C_λ + (1 − C_λ)(1 − u)⁵ (paper eq. 24), u = ωi·h, and
//! D = a/π + b·B(t, v₁, v₂, w) + c·(mirror delta); t = n·h, v₁ = n·ωi, v₂ = n·ωo,
//! w = cos of h's azimuth from the tangent. B is the microfacet term
//!
//! * B₁ = Z(t) Â(w) / (4π v₁ v₂), or
//! * B₂ = G(v₁)G(v₂) Z(t) Â(w) / (4π v₁ v₂) + (1 − G(v₁)G(v₂)) / (4π v₁ v₂),
//!
//! with Z(t) = r / (1 + r t² − t²)², A(w) = √(p / (p² − p² w² + w²)), G(v) = v / (r − r v + v).
//!
//! **Normalisation (derived).** ∫ Z(t) t dω_h = 2π ∫₀¹ r t / (1 − (1 − r) t²)² dt = π, so
//! Z/π is a normalised distribution of normals (it is Trowbridge–Reitz/GGX with α² = r).
//! The azimuth factor is not normalised: (1/2π) ∫₀^{2π} A(cos φ) dφ = (2/π) √p K(1 − p²) =
//! √p / AGM(1, p) (K the complete elliptic integral, AGM the arithmetic–geometric mean),
//! which is 1 only at p = 1 (0.971 at p = ½, 0.62 at p = 0.05): the paper's D loses that
//! fraction of the glossy energy. We use Â = A · AGM(1, p)/√p, so that
//! ∫ Z(t) Â(w) t dω_h / π = 1 exactly and B₁ is the standard D/(4 v₁ v₂) microfacet form.
//!
//! **Sampling (derived).** The zenith is sampled exactly: F(t²) = ∫₀^{t²} Z d(t²) =
//! r t² / (1 − t² + r t²), so t = √(ξ₁ / (r − r ξ₁ + ξ₁)) — the thesis's printed
//! θ = arccos √(ξ/(r − ξ)) leaves [0, 1] for ξ > r/2 (a test pins it failing). The azimuth
//! follows Schlick's formula, read as the fraction of a quadrant (as LuxRender reads it):
//! ψ = (π/2) √(p² ξ² / (1 − ξ² + ξ² p²)), measured from the bitangent (where A peaks), one
//! quadrant per quarter of ξ₂ (thesis eq. 6.11–6.12). Its exact density over the circle is
//! q(φ) = p² / (p² + (1 − p²) s²)^{3/2} / 2π with s = 2ψ/π (uniform at p = 1; A is not
//! sampled exactly: Â/(2π q) runs from AGM(1, p) at ψ = 0 to AGM(1, p)/p² at ψ = π/2). So
//! p_h(h) = 2 t Z(t) q(φ) and pdf(ωi) = p_h / (4 ωo·h). Reading the formula as w = cos φ
//! instead gives density ∝ |sin φ| even at p = 1 (zero along the tangent where f is not):
//! infinite variance.
//!
//! The lobes are picked with probabilities ∝ a (cosine-weighted), b (half vector),
//! b·M(v₂) for B₂'s multiple-reflection term (uniform over the hemisphere, which keeps its
//! weight (1 − G G)/(2 v₂) bounded where cosine sampling's 1/(4 v₁ v₂) is not) and c (the
//! mirror, a delta with pdf = its probability); `pdf` is the mixture of the non-delta lobes.
//!
//! Energy: both B₁ and B₂ have 1/v₂ terms whose directional albedo grows without bound at
//! grazing ωo (B₂'s multiple-scattering term alone integrates to b(1 − G(v₂)Ḡ)/(2 v₂),
//! Ḡ = ∫₀¹ G); see the tests for measured values.

use crate::frame::{flip_z, upper_pair};
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::wgsl::{ModelWgsl, WgslConstant, WgslPiece, WgslTextureSlots, WgslValue};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, TAU};

crate::model_params! {
    /// Schlick's parameters.
    pub struct SchlickParams for "schlick" {
        doc: "Schlick 1994 (CGF 13(3)): R = S(u)·(a/π + b·B + c·mirror), Schlick Fresnel S, rational \
              zenith Z(r) and azimuth A(p) factors, B1 or B2 (self-shadowing); reflection only, two-sided.",
        reflectance: spectrum {
            doc: "reflection factor C (reflectance at normal incidence, S(1) = C)",
            default: 0.5,
            mtl: "Kd",
        },
        roughness: scalar { doc: "roughness r: 0 a mirror, 1 Lambertian-like", default: 0.3, min: 0.0, max: 1.0, mtl: "rough" },
        isotropy: scalar {
            doc: "isotropy p: 1 isotropic, towards 0 grooves along the tangent (highlight stretched along the bitangent)",
            default: 1.0,
            min: 0.0,
            max: 1.0,
            mtl: "p",
        },
        a: scalar {
            doc: "Lambertian weight a; if a, b or c is negative, all three come from r (thesis eq. 6.5)",
            default: -1.0,
            min: -1.0,
            max: 1.0,
        },
        b: scalar { doc: "glossy (microfacet) weight b; negative: derived from r", default: -1.0, min: -1.0, max: 1.0 },
        c: scalar {
            doc: "mirror weight c; negative: derived from r. Given weights summing over 1 are scaled to sum 1",
            default: -1.0,
            min: -1.0,
            max: 1.0,
        },
        geometric: choice(SchlickGeometry) {
            doc: "b1: no self-shadowing; b2: self-shadowing G(v) = v/(r − rv + v) and its multiple-reflection term",
            default: SchlickGeometry::B2,
        },
    }
}

impl Model for SchlickParams {
    type Bsdf<const N: usize> = Schlick<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots::base("reflectance"),
        source: include_str!("schlick.wgsl"),
        needs: &[WgslPiece::Sampling],
        constants: &[
            WgslConstant { name: "MAT_SCHLICK_MIN_ROUGHNESS", value: WgslValue::F32(MIN_ROUGHNESS) },
            WgslConstant { name: "MAT_SCHLICK_MIN_ISOTROPY", value: WgslValue::F32(MIN_ISOTROPY) },
            WgslConstant { name: "MAT_SCHLICK_MIN_COS", value: WgslValue::F32(MIN_COS) },
            WgslConstant { name: "MAT_SCHLICK_B2", value: WgslValue::U32(SchlickGeometry::B2.index()) },
        ],
    };

    const TEXTURE_SLOTS: TextureSlots = TextureSlots::BASE_COLOUR;

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Schlick<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> Schlick<N> {
        let w = [self.a, self.b, self.c];
        let weights = if w.iter().any(|&x| x < 0.0) { None } else { Some(w) };
        Schlick::new(texels.base(self.reflectance.sample(wl)), self.roughness, self.isotropy, weights, self.geometric)
    }
}

/// Roughness used by the glossy terms when r is smaller (r = 0 makes Z a Dirac delta; the
/// derived weights then give everything to the mirror lobe instead).
pub const MIN_ROUGHNESS: f32 = 1e-4;
/// Isotropy used when p is smaller (p = 0 makes A a Dirac delta in azimuth).
pub const MIN_ISOTROPY: f32 = 1e-3;
/// Smallest cosine in the 1/(4π v₁ v₂) factors, so that f stays finite on the horizon.
const MIN_COS: f32 = 1e-6;

crate::choice_param! {
    /// Which microfacet term B Schlick's model uses.
    pub enum SchlickGeometry {
        /// B₁ = Z Â / (4π v₁ v₂): no self-shadowing.
        B1 = "b1",
        /// B₂: self-shadowing by G(v) = v/(r − r v + v), the shadowed fraction re-emitted by
        /// the multiple-reflection term (1 − G G)/(4π v₁ v₂) (paper §5, thesis eq. 6.2–6.8).
        B2 = "b2",
    }
}

/// Schlick's BRDF bound to a path's wavelengths. Build it with [`Schlick::new`] or
/// [`SchlickParams`]: the constructor derives the weights and normalisations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schlick<const N: usize> {
    reflectance: SampledSpectrum<N>,
    r: f32,
    p: f32,
    a: f32,
    b: f32,
    c: f32,
    geometry: SchlickGeometry,
    /// AGM(1, p): Â = A · AGM(1, p)/√p = AGM(1, p) s / √(h_x² + p² h_y²).
    agm: f32,
    /// Ḡ = ∫₀¹ G(v) dv, for the multiple-reflection lobe's albedo.
    g_mean: f32,
}

/// The lobe weights of thesis eq. 6.5: b = 4r(1 − r); a = 0, c = 1 − b below r = ½,
/// a = 1 − b, c = 0 above.
#[inline]
pub fn derived_weights(r: f32) -> [f32; 3] {
    let b = 4.0 * r * (1.0 - r);
    if r < 0.5 { [0.0, b, 1.0 - b] } else { [1.0 - b, b, 0.0] }
}

/// Schlick's zenith factor Z(t) = r / (1 + r t² − t²)², written with s² = 1 − t² = h_x² + h_y²
/// (exact near t = 1): Z = r / (s² + r t²)².
#[inline]
pub fn zenith(r: f32, t2: f32, s2: f32) -> f32 {
    let d = s2 + r * t2;
    (r / d) / d
}

/// Schlick's self-shadowing factor G(v) = v / (r − r v + v) (paper §5, thesis eq. 6.2–6.8).
#[inline]
pub fn shadowing(r: f32, v: f32) -> f32 {
    v / (r - r * v + v)
}

/// The arithmetic–geometric mean AGM(1, x) for x in (0, 1] (quadratic convergence:
/// 6 steps reach f32 precision down to x = 10⁻³).
#[inline]
pub fn agm1(x: f32) -> f32 {
    let (mut a, mut g) = (1.0f32, x);
    for _ in 0..6 {
        let m = 0.5 * (a + g);
        g = (a * g).sqrt();
        a = m;
    }
    0.5 * (a + g)
}

/// The normalised azimuth factor Â(w) = A(w) · AGM(1, p)/√p, with w² = h_x²/s²:
/// A = √(p s² / (h_x² + p² h_y²)), and (1/2π) ∫ Â dφ = 1.
#[inline]
fn azimuth(p: f32, agm: f32, hx2: f32, hy2: f32) -> f32 {
    let s2 = hx2 + hy2;
    if s2 <= 0.0 {
        return 1.0; // h = n: the azimuth is undefined, a set of measure zero
    }
    agm * (s2 / (hx2 + p * p * hy2)).sqrt()
}

/// The exact density over φ ∈ [0, 2π) of the azimuth sampling in [`sample_half`]:
/// q = p² / (p² + (1 − p²) s²)^{3/2} / 2π with s = 2ψ/π, ψ the angle from the bitangent.
#[inline]
fn azimuth_pdf(p: f32, hx: f32, hy: f32) -> f32 {
    let s = hx.abs().atan2(hy.abs()) * (2.0 * FRAC_1_PI);
    let p2 = p * p;
    let d = p2 + (1.0 - p2) * s * s;
    p2 / (d * d.sqrt()) * (0.5 * FRAC_1_PI)
}

/// Samples a half vector: t = √(ξ₁/(r − r ξ₁ + ξ₁)) inverts the zenith CDF
/// r t²/(1 − t² + r t²) exactly; ψ = (π/2) √(p² ξ² / (1 − ξ² + ξ² p²)) per quadrant of ξ₂
/// (Schlick's azimuth formula, quadrants mirrored so that strata stay contiguous).
#[inline]
pub fn sample_half(r: f32, p: f32, u: Vec2) -> Vec3 {
    let den = r * (1.0 - u.x) + u.x;
    let t2 = u.x / den;
    let s2 = r * (1.0 - u.x) / den;
    let v4 = 4.0 * u.y;
    let quadrant = (v4 as u32).min(3);
    let frac = v4 - quadrant as f32;
    let xi = if quadrant & 1 == 0 { frac } else { 1.0 - frac };
    let psi = FRAC_PI_2 * p * xi / ((1.0 - xi) * (1.0 + xi) + xi * xi * p * p).sqrt();
    let (sx, sy) = match quadrant {
        0 => (1.0, 1.0),
        1 => (1.0, -1.0),
        2 => (-1.0, -1.0),
        _ => (-1.0, 1.0),
    };
    let s = s2.sqrt();
    Vec3::new(sx * s * psi.sin(), sy * s * psi.cos(), t2.sqrt())
}

/// The solid-angle density of [`sample_half`]: p_h(h) = 2 t Z(t) q(φ).
#[inline]
pub fn half_pdf(r: f32, p: f32, h: Vec3) -> f32 {
    let s2 = (h.x * h.x + h.y * h.y).min(1.0);
    2.0 * h.z.max(0.0) * zenith(r, h.z * h.z, s2) * azimuth_pdf(p, h.x, h.y)
}

/// A uniform direction on the +z hemisphere (pdf 1/2π).
#[inline]
fn uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = 1.0 - u.x;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let phi = TAU * u.y;
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

impl<const N: usize> Schlick<N> {
    /// Schlick's BRDF with reflection factor C, roughness r, isotropy p, the lobe weights
    /// (a, b, c) or `None` to derive them from r (thesis eq. 6.5), and the microfacet term.
    /// Given weights summing over 1 are scaled to sum 1 (Schlick's a + b + c = 1).
    pub fn new(
        reflectance: SampledSpectrum<N>,
        roughness: f32,
        isotropy: f32,
        weights: Option<[f32; 3]>,
        geometry: SchlickGeometry,
    ) -> Self {
        let [a, b, c] = match weights {
            Some(w) => {
                let w = w.map(|x| x.max(0.0));
                let sum = w[0] + w[1] + w[2];
                if sum > 1.0 { w.map(|x| x / sum) } else { w }
            }
            None => derived_weights(roughness.clamp(0.0, 1.0)),
        };
        let r = roughness.clamp(MIN_ROUGHNESS, 1.0);
        let p = isotropy.clamp(MIN_ISOTROPY, 1.0);
        Self { reflectance, r, p, a, b, c, geometry, agm: agm1(p), g_mean: shadowing_mean(r) }
    }

    /// The lobe weights (a, b, c) in use.
    pub fn weights(&self) -> [f32; 3] {
        [self.a, self.b, self.c]
    }

    /// S_λ(u) = C + (1 − C)(1 − u)⁵, given m = 1 − u.
    #[inline]
    fn fresnel(&self, m: f32) -> SampledSpectrum<N> {
        let m = m.clamp(0.0, 1.0);
        let m5 = (m * m) * (m * m) * m;
        self.reflectance + (SampledSpectrum::one() - self.reflectance) * m5
    }

    /// The probabilities of sampling the (Lambertian, glossy, multiple-reflection, mirror)
    /// lobes for ωo at cosine `v2`: proportional to a, b, b·M(v₂) and c, where
    /// M(v₂) = (1 − G(v₂) Ḡ)/(2 v₂) is the exact albedo of B₂'s multiple-reflection term.
    #[inline]
    fn lobe_probabilities(&self, v2: f32) -> [f32; 4] {
        let wm = match self.geometry {
            SchlickGeometry::B1 => 0.0,
            SchlickGeometry::B2 => {
                let v = v2.max(1e-3);
                self.b * (1.0 - shadowing(self.r, v) * self.g_mean).max(0.0) / (2.0 * v)
            }
        };
        let w = [self.a, self.b, wm, self.c];
        let sum = w[0] + w[1] + w[2] + w[3];
        if sum > 0.0 { w.map(|x| x / sum) } else { [0.0; 4] }
    }

    /// f for ωo, ωi both on the +z side (non-delta part).
    #[inline]
    fn eval_up(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        let hv = wo + wi;
        let len2 = hv.length_squared();
        if len2 <= 0.0 {
            return SampledSpectrum::zero();
        }
        let h = hv / len2.sqrt();
        let (v1, v2) = (wi.z.max(MIN_COS), wo.z.max(MIN_COS));
        let (hx2, hy2) = (h.x * h.x, h.y * h.y);
        let za = zenith(self.r, h.z * h.z, (hx2 + hy2).min(1.0)) * azimuth(self.p, self.agm, hx2, hy2);
        let (x, y) = match self.geometry {
            SchlickGeometry::B1 => (1.0, 0.0),
            SchlickGeometry::B2 => {
                let gg = shadowing(self.r, v1) * shadowing(self.r, v2);
                (gg, 1.0 - gg)
            }
        };
        let d = self.a * FRAC_1_PI + self.b * (x * za + y) / (4.0 * std::f32::consts::PI * v1 * v2);
        // u = ωi·h = |ωo + ωi|/2, and 1 − u = |ωo − ωi|²/(4(1 + u)): symmetric in ωo, ωi
        // (exactly reciprocal) and without cancellation where (1 − u)⁵ is tiny.
        let u = 0.5 * len2.sqrt();
        self.fresnel((wo - wi).length_squared() / (4.0 * (1.0 + u))) * d
    }

    /// The non-delta mixture pdf for ωo, ωi both on the +z side.
    #[inline]
    fn pdf_up(&self, wo: Vec3, wi: Vec3) -> f32 {
        let [pd, pg, pm, _] = self.lobe_probabilities(wo.z);
        let mut pdf = pd * cosine_hemisphere_pdf(wi.z) + pm * (0.5 * FRAC_1_PI);
        let hv = wo + wi;
        let len2 = hv.length_squared();
        if pg > 0.0 && len2 > 0.0 {
            let h = hv / len2.sqrt();
            let oh = wo.dot(h);
            if oh > 0.0 {
                pdf += pg * half_pdf(self.r, self.p, h) / (4.0 * oh);
            }
        }
        pdf
    }
}

/// Ḡ = ∫₀¹ v/(r + (1 − r) v) dv = (1 + (r/k) ln r)/k with k = 1 − r, or its series
/// Σ kⁿ/((n + 1)(n + 2)) for small k (where the closed form cancels).
#[inline]
fn shadowing_mean(r: f32) -> f32 {
    let k = 1.0 - r;
    if k > 0.25 {
        (1.0 + r / k * r.ln()) / k
    } else {
        let (mut sum, mut kn) = (0.0, 1.0);
        for n in 0..14 {
            sum += kn / ((n + 1) * (n + 2)) as f32;
            kn *= k;
        }
        sum
    }
}

impl<const N: usize> Bsdf<N> for Schlick<N> {
    fn flags(&self) -> ScatterFlags {
        let mut f = ScatterFlags::REFLECTION;
        if self.a > 0.0 || (self.b > 0.0 && self.geometry == SchlickGeometry::B2) {
            f = f | ScatterFlags::DIFFUSE;
        }
        if self.b > 0.0 {
            f = f | ScatterFlags::GLOSSY;
        }
        if self.c > 0.0 {
            f = f | ScatterFlags::SPECULAR;
        }
        f
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
        let [pd, pg, pm, ps] = self.lobe_probabilities(wo_up.z);
        let back = |w: Vec3| if down { flip_z(w) } else { w };
        if uc < ps {
            // The mirror lobe c·δ: h = n, so u = v₂; weight c·S(v₂).
            let wi = Vec3::new(-wo_up.x, -wo_up.y, wo_up.z);
            let f = self.fresnel(1.0 - wo_up.z) * (self.c / wi.z);
            return Some(BsdfSample {
                wi: back(wi),
                f,
                pdf: ps,
                flags: ScatterFlags::REFLECTION | ScatterFlags::SPECULAR,
            });
        }
        // The last lobe with a non-zero probability also takes what rounding leaves over.
        let x = uc - ps;
        let (wi, flags) = if pd > 0.0 && (x < pd || pg + pm <= 0.0) {
            (cosine_hemisphere(u), ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE)
        } else if pg > 0.0 && (x < pd + pg || pm <= 0.0) {
            let h = sample_half(self.r, self.p, u);
            let oh = wo_up.dot(h);
            if oh <= 0.0 {
                return None;
            }
            ((2.0 * oh * h - wo_up).normalize(), ScatterFlags::REFLECTION | ScatterFlags::GLOSSY)
        } else if pm > 0.0 {
            (uniform_hemisphere(u), ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE)
        } else {
            return None;
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf_up(wo_up, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample { wi: back(wi), f: self.eval_up(wo_up, wi), pdf, flags })
    }
}

#[cfg(test)]
mod tests;
