//! Microfacet models on the GGX / Trowbridge–Reitz distribution: a rough conductor and
//! a rough dielectric.
//!
//! * Distribution: GGX (Walter, Marschner, Li & Torrance 2007, "Microfacet Models for
//!   Refraction through Rough Surfaces", EGSR, eq. 33), in the anisotropic form with
//!   α_x, α_y of Heitz 2014 ("Understanding the Masking-Shadowing Function in
//!   Microfacet-Based BRDFs", JCGT 3(2)).
//! * Masking: Smith's G1 = 1/(1 + Λ) with the GGX Λ (Heitz 2014; Walter eq. 34 is the
//!   same G1). The rough conductor uses the height-correlated G2 = 1/(1 + Λ(ωo) + Λ(ωi))
//!   (Heitz 2014); the rough dielectric uses Walter's separable G2 = G1(ωo)·G1(ωi)
//!   (Walter eq. 23) for both lobes, because the height-correlated form for
//!   transmission is not that formula (Heitz 2014 derives it as a Beta function of the
//!   Λs, which is costly on a GPU).
//! * Sampling: visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible
//!   Normals", JCGT 7(4), the code in its appendix), pdf
//!   D_ωo(h) = G1(ωo) max(0, ωo·h) D(h) / cos θo.
//!
//! All of these are single-scattering models: light that would scatter more than once
//! between microfacets is lost, so they darken at high roughness (the tests measure by
//! how much).
//!
//! Formulas are written in forms that stay finite at grazing angles: with
//! s(ω) = √(α_x² ω_x² + α_y² ω_y² + ω_z²), G1(ω) = 2|ω_z| / (|ω_z| + s(ω)), so the
//! cosines in the denominators of the BSDFs cancel analytically.

use crate::frame::{flip_z, reflect};
use crate::fresnel::fresnel_dielectric;
use crate::models::metal::{MetalPreset, fresnel_spectrum};
use crate::wgsl::{ModelWgsl, WgslPiece, WgslTextureSlots};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{PI, TAU};

crate::model_params! {
    /// The rough conductor's parameters.
    pub struct RoughConductorParams for "roughconductor" {
        doc: "Rough conductor: GGX microfacets (Walter et al. 2007) with height-correlated Smith masking \
              (Heitz 2014), the exact conductor Fresnel term and visible-normal sampling (Heitz 2018); two-sided.",
        alpha: scalar {
            doc: "GGX roughness α (the slope-space width, not perceptual roughness; α = r² for a perceptual r); \
                  α_x when alpha_y is set",
            default: 0.1,
            min: Ggx::ALPHA_MIN,
            max: 1.0,
        },
        alpha_y: scalar {
            doc: "GGX roughness along the bitangent for anisotropic surfaces; 0 means alpha (isotropic)",
            default: 0.0,
            min: 0.0,
            max: 1.0,
        },
        metal: choice(MetalPreset) {
            doc: "measured metal: custom (eta, k), gold, silver, copper (default), aluminium",
            default: MetalPreset::Copper,
        },
        eta: scalar { doc: "real part n of the complex index (metal = custom)", default: 1.5, min: 0.0, max: 10.0 },
        k: scalar { doc: "extinction coefficient κ (metal = custom)", default: 3.0, min: 0.0, max: 20.0 },
        tint: spectrum { doc: "colour filter multiplying the Fresnel reflectance", default: 1.0 },
    }
}

impl Model for RoughConductorParams {
    type Bsdf<const N: usize> = RoughConductor<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots::NONE,
        source: include_str!("rough_conductor.wgsl"),
        needs: &[WgslPiece::Fresnel, WgslPiece::Metal, WgslPiece::Ggx],
        constants: &[],
    };

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> RoughConductor<N> {
        let (eta, k) = self.metal.eta_k(self.eta, self.k, wl);
        RoughConductor { distribution: Ggx::from_alphas(self.alpha, self.alpha_y), eta, k, tint: self.tint.sample(wl) }
    }
}

crate::model_params! {
    /// The rough dielectric's parameters.
    pub struct RoughDielectricParams for "roughdielectric" {
        doc: "Rough dielectric: GGX microfacet reflection and refraction (Walter et al. 2007, eq. 20–21) with \
              separable Smith masking, exact dielectric Fresnel and visible-normal sampling (Heitz 2018).",
        alpha: scalar {
            doc: "GGX roughness α (slope-space width); α_x when alpha_y is set",
            default: 0.1,
            min: Ggx::ALPHA_MIN,
            max: 1.0,
        },
        alpha_y: scalar { doc: "GGX roughness along the bitangent; 0 means alpha", default: 0.0, min: 0.0, max: 1.0 },
        ior: scalar {
            doc: "index of refraction inside (the normal points outside, index 1)",
            default: 1.5,
            min: 1.0e-3,
            max: 10.0,
            mtl: "Ni",
        },
        tint: spectrum { doc: "colour filter on reflection and transmission", default: 1.0, mtl: "Tf" },
    }
}

impl Model for RoughDielectricParams {
    type Bsdf<const N: usize> = RoughDielectric<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots { metallic_roughness: true, ..WgslTextureSlots::base("tint") },
        source: include_str!("rough_dielectric.wgsl"),
        needs: &[WgslPiece::Fresnel, WgslPiece::Ggx],
        constants: &[],
    };

    /// glTF's base colour tints transmission; its roughness texture multiplies the
    /// perceptual roughness r = √α (so α by its square), kept above 10⁻³.
    const TEXTURE_SLOTS: TextureSlots = TextureSlots { base_colour: true, specular: false, metallic_roughness: true };

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> RoughDielectric<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> RoughDielectric<N> {
        let (ax, ay) = if texels.roughness == 1.0 {
            (self.alpha, self.alpha_y)
        } else {
            let k = texels.roughness * texels.roughness;
            ((self.alpha * k).max(1e-3), if self.alpha_y > 0.0 { (self.alpha_y * k).max(1e-3) } else { 0.0 })
        };
        RoughDielectric {
            distribution: Ggx::from_alphas(ax, ay),
            eta: self.ior,
            tint: texels.base(self.tint.sample(wl)),
        }
    }

    fn is_transmissive(&self) -> bool {
        true
    }
}

/// The anisotropic GGX (Trowbridge–Reitz) microfacet distribution in the local frame
/// (α_x along the tangent x, α_y along the bitangent y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Roughness along x.
    pub alpha_x: f32,
    /// Roughness along y.
    pub alpha_y: f32,
}

impl Ggx {
    /// The smallest α used: below it D overflows f32 precision in practice and the
    /// surface is better modelled as smooth.
    pub const ALPHA_MIN: f32 = 1.0e-3;

    /// A distribution with roughnesses α_x, α_y, each raised to at least [`Self::ALPHA_MIN`].
    pub fn new(alpha_x: f32, alpha_y: f32) -> Self {
        Self { alpha_x: alpha_x.max(Self::ALPHA_MIN), alpha_y: alpha_y.max(Self::ALPHA_MIN) }
    }

    /// From the `alpha` and `alpha_y` parameters: α_y = 0 means α_y = α_x.
    pub fn from_alphas(alpha: f32, alpha_y: f32) -> Self {
        Self::new(alpha, if alpha_y > 0.0 { alpha_y } else { alpha })
    }

    /// An isotropic distribution.
    pub fn isotropic(alpha: f32) -> Self {
        Self::new(alpha, alpha)
    }

    /// D(h) = 1 / (π α_x α_y (h_x²/α_x² + h_y²/α_y² + h_z²)²) for h_z > 0, else 0: Walter
    /// eq. 33 (1/(π α² cos⁴θ (α² + tan²θ)²) · α⁴) written without tan θ; normalised so
    /// that ∫ D(h) cos θh dh = 1.
    #[inline]
    pub fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (h.x / self.alpha_x, h.y / self.alpha_y);
        let e = x * x + y * y + h.z * h.z;
        1.0 / (PI * self.alpha_x * self.alpha_y * e * e)
    }

    /// s(ω) = √(α_x² ω_x² + α_y² ω_y² + ω_z²): |ω_z| (1 + 2Λ(ω)).
    #[inline]
    pub(crate) fn s(&self, w: Vec3) -> f32 {
        let (x, y) = (self.alpha_x * w.x, self.alpha_y * w.y);
        (x * x + y * y + w.z * w.z).sqrt()
    }

    /// Smith's Λ(ω) = (√(1 + α(φ)² tan²θ) − 1)/2 for GGX (Heitz 2014), α(φ)² =
    /// cos²φ α_x² + sin²φ α_y²; infinite at the horizon.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        0.5 * (self.s(w) / w.z.abs() - 1.0)
    }

    /// Smith's masking G1(ω) = 1/(1 + Λ(ω)) = 2|ω_z| / (|ω_z| + s(ω)).
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        let z = w.z.abs();
        let d = z + self.s(w);
        if d > 0.0 { 2.0 * z / d } else { 0.0 }
    }

    /// Height-correlated masking-shadowing for reflection, 1/(1 + Λ(ωo) + Λ(ωi)) (Heitz
    /// 2014) = 2|z_o||z_i| / (s(ωo)|z_i| + s(ωi)|z_o|).
    #[inline]
    pub fn g2_correlated(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (zo, zi) = (wo.z.abs(), wi.z.abs());
        let d = self.s(wo) * zi + self.s(wi) * zo;
        if d > 0.0 { 2.0 * zo * zi / d } else { 0.0 }
    }

    /// Separable (uncorrelated) masking-shadowing G1(ωo)·G1(ωi) (Walter eq. 23).
    #[inline]
    pub fn g2_separable(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.g1(wo) * self.g1(wi)
    }

    /// The distribution of visible normals D_ω(h) = G1(ω) max(0, ω·h) D(h) / |ω_z| (Heitz
    /// 2014, 2018) = 2 max(0, ω·h) D(h) / (|ω_z| + s(ω)); ∫ D_ω(h) dh = 1.
    #[inline]
    pub fn d_visible(&self, w: Vec3, h: Vec3) -> f32 {
        let d = w.z.abs() + self.s(w);
        let c = w.dot(h);
        if d > 0.0 && c > 0.0 { 2.0 * c * self.d(h) / d } else { 0.0 }
    }

    /// Samples a normal h from D_ω (Heitz 2018, the code in its appendix) for ω with
    /// ω_z ≥ 0; h_z > 0.
    #[inline]
    pub fn sample_visible(&self, w: Vec3, u: Vec2) -> Vec3 {
        // Stretch to the hemisphere configuration (α = 1).
        let vh = Vec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z).normalize_or(Vec3::Z);
        // Orthonormal basis around vh (T1 = x when vh is the normal).
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { Vec3::X };
        let t2 = vh.cross(t1);
        // A point on the projected disk, warped to the visible half (Heitz 2018 §4.2).
        let r = u.x.sqrt();
        let phi = TAU * u.y;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
        // Reproject onto the hemisphere and unstretch.
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(1.0e-6)).normalize()
    }

    /// pdf of the reflected direction when h is drawn from D_ωo and ωi = reflect(ωo, h):
    /// D_ωo(h) / (4 ωo·h) = D(h) / (2 (|z_o| + s(ωo))) (ωo, ωi in the upper hemisphere).
    #[inline]
    pub(crate) fn reflection_pdf(&self, wo: Vec3, h: Vec3) -> f32 {
        let d = wo.z.abs() + self.s(wo);
        if d > 0.0 { self.d(h) / (2.0 * d) } else { 0.0 }
    }
}

#[inline]
fn finite_dir(w: Vec3) -> bool {
    w.is_finite() && w.length_squared() > 0.0
}

/// A rough metal: f = D(h) G2(ωo, ωi) F(ωo·h) / (4 |cos θo| |cos θi|) (Walter eq. 20) with
/// height-correlated G2 and the exact conductor Fresnel term per wavelength; visible-
/// normal sampling, pdf D_ωo(h)/(4 ωo·h) (Walter eq. 14 for the Jacobian). Two-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor<const N: usize> {
    /// The microfacet distribution.
    pub distribution: Ggx,
    /// Real part n of the complex index, per wavelength.
    pub eta: SampledSpectrum<N>,
    /// Extinction coefficient κ, per wavelength.
    pub k: SampledSpectrum<N>,
    /// Colour filter on the reflectance (1 for a physical metal).
    pub tint: SampledSpectrum<N>,
}

impl<const N: usize> RoughConductor<N> {
    /// A rough conductor of index η + iκ (per wavelength), untinted.
    pub fn new(distribution: Ggx, eta: SampledSpectrum<N>, k: SampledSpectrum<N>) -> Self {
        Self { distribution, eta, k, tint: SampledSpectrum::one() }
    }

    /// (ωo, ωi, h) moved to the upper hemisphere, or None if not a reflection.
    #[inline]
    fn configuration(wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
        if wo.z * wi.z <= 0.0 || !wo.is_finite() || !wi.is_finite() {
            return None;
        }
        let (wo, wi) = if wo.z < 0.0 { (flip_z(wo), flip_z(wi)) } else { (wo, wi) };
        let h = (wo + wi).normalize_or_zero();
        if h.z <= 0.0 { None } else { Some((wo, wi, h)) }
    }
}

impl<const N: usize> Bsdf<N> for RoughConductor<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::GLOSSY
    }

    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        let Some((wo, wi, h)) = Self::configuration(wo, wi) else { return SampledSpectrum::zero() };
        let ggx = &self.distribution;
        // D G2 / (4 z_o z_i) with G2 = 2 z_o z_i / (s_o z_i + s_i z_o).
        let den = 2.0 * (ggx.s(wo) * wi.z + ggx.s(wi) * wo.z);
        if den <= 0.0 || den.is_nan() {
            return SampledSpectrum::zero();
        }
        fresnel_spectrum(wo.dot(h), &self.eta, &self.k, &self.tint) * (ggx.d(h) / den)
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match Self::configuration(wo, wi) {
            Some((wo, _, h)) => self.distribution.reflection_pdf(wo, h),
            None => 0.0,
        }
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 || !finite_dir(wo) {
            return None;
        }
        let up = if wo.z < 0.0 { flip_z(wo) } else { wo };
        let h = self.distribution.sample_visible(up, u);
        let wi = reflect(up, h);
        if wi.z <= 0.0 {
            return None;
        }
        let wi = if wo.z < 0.0 { flip_z(wi) } else { wi };
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 || pdf.is_nan() {
            return None;
        }
        Some(BsdfSample { wi, f: self.eval(wo, wi), pdf, flags: self.flags() })
    }
}

/// A rough dielectric interface (frosted glass): Walter et al. 2007 eq. 20 (reflection)
/// and eq. 21 (transmission through the generalised half vector h ∝ −(ωo + η' ωi),
/// eq. 16), separable Smith G2, exact Fresnel. Sampling draws h from the visible normals
/// and reflects with probability F(ωo·h), refracts otherwise; the pdfs carry the
/// Jacobians 1/(4|ωo·h|) (eq. 14) and |ωi·h| / (ωi·h + ωo·h/η')² (eq. 17). Like the
/// smooth [`crate::Dielectric`], transmitted radiance is scaled by 1/η'² (η' = n on ωi's
/// side over n on ωo's side). +z is the outside; η = n_inside / n_outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric<const N: usize> {
    /// The microfacet distribution.
    pub distribution: Ggx,
    /// Relative index of refraction n_inside / n_outside.
    pub eta: f32,
    /// Colour filter on both reflection and transmission (1 for clear glass).
    pub tint: SampledSpectrum<N>,
}

/// The scalar parts of a rough dielectric evaluation: (f without tint, pdf).
#[derive(Clone, Copy, Debug)]
struct DielectricEval {
    f: f32,
    pdf: f32,
}

impl<const N: usize> RoughDielectric<N> {
    /// A rough dielectric of relative index η, untinted.
    pub fn new(distribution: Ggx, eta: f32) -> Self {
        Self { distribution, eta, tint: SampledSpectrum::one() }
    }

    /// f (if `with_f`) and pdf together: they share h, F, D and the Jacobian. ωo below
    /// the surface is handled by mirroring both directions and inverting η.
    #[inline]
    fn evaluate(&self, wo: Vec3, wi: Vec3, with_f: bool) -> DielectricEval {
        const ZERO: DielectricEval = DielectricEval { f: 0.0, pdf: 0.0 };
        if wo.z == 0.0 || wi.z == 0.0 || self.eta <= 0.0 || self.eta.is_nan() {
            return ZERO;
        }
        let (wo, wi, eta) = if wo.z < 0.0 { (flip_z(wo), flip_z(wi), 1.0 / self.eta) } else { (wo, wi, self.eta) };
        let ggx = &self.distribution;
        let (zo, zi) = (wo.z, wi.z.abs());
        // 1/(z_o + s_o) = G1(ωo)/(2 z_o): D_ωo(h) = 2 (ωo·h) D(h) / (z_o + s_o).
        let inv_o = 1.0 / (zo + ggx.s(wo));
        // Separable G2 with both cosines cancelled: G2/(z_o z_i) = 4/((z_o + s_o)(z_i + s_i)).
        let g_over_cos = |ggx: &Ggx| 4.0 * inv_o / (zi + ggx.s(wi));
        if wi.z > 0.0 {
            // Reflection (Walter eq. 13, 20): pdf = F D_ωo(h) / (4 ωo·h).
            let h = (wo + wi).normalize_or_zero();
            if h.z <= 0.0 {
                return ZERO;
            }
            let r = fresnel_dielectric(wo.dot(h), eta);
            let d = ggx.d(h);
            let f = if with_f { 0.25 * d * g_over_cos(ggx) * r } else { 0.0 };
            DielectricEval { f, pdf: 0.5 * r * d * inv_o }
        } else {
            // Transmission (Walter eq. 16, 17, 21): h ∝ −(ωo + η ωi), on the outside.
            let h = (wo + eta * wi).normalize_or_zero();
            let h = if h.z < 0.0 { -h } else { h };
            let (oh, ih) = (wo.dot(h), wi.dot(h));
            // Only microfacets facing ωo and, from behind, ωi refract.
            if h.z <= 0.0 || oh <= 0.0 || ih >= 0.0 {
                return ZERO;
            }
            let t = 1.0 - fresnel_dielectric(oh, eta);
            let den = ih + oh / eta;
            let den2 = den * den;
            if den2 <= 0.0 || den2.is_nan() {
                return ZERO;
            }
            let d = ggx.d(h);
            // Walter eq. 21 in pbrt-v4's normalisation (η_o = 1), times 1/η² for radiance.
            let f = if with_f { d * g_over_cos(ggx) * t * (-ih * oh) / (den2 * eta * eta) } else { 0.0 };
            // pdf = (1 − F) D_ωo(h) |ωi·h| / (ωi·h + ωo·h/η)².
            let pdf = t * 2.0 * oh * d * inv_o * -ih / den2;
            DielectricEval { f, pdf }
        }
    }
}

impl<const N: usize> Bsdf<N> for RoughDielectric<N> {
    fn eta(&self) -> f32 {
        self.eta
    }
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::TRANSMISSION | ScatterFlags::GLOSSY
    }

    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        let e = self.evaluate(wo, wi, true);
        if e.f.is_finite() { self.tint * e.f } else { SampledSpectrum::zero() }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = self.evaluate(wo, wi, false).pdf;
        if p.is_finite() { p } else { 0.0 }
    }

    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 || !finite_dir(wo) || self.eta <= 0.0 || self.eta.is_nan() {
            return None;
        }
        let below = wo.z < 0.0;
        let (up, eta) = if below { (flip_z(wo), 1.0 / self.eta) } else { (wo, self.eta) };
        let h = self.distribution.sample_visible(up, u);
        let c = up.dot(h);
        if c <= 0.0 {
            return None;
        }
        let r = fresnel_dielectric(c, eta);
        let (wi, flags) = if uc < r {
            let wi = reflect(up, h);
            if wi.z <= 0.0 {
                return None;
            }
            (wi, ScatterFlags::REFLECTION | ScatterFlags::GLOSSY)
        } else {
            // Snell's law about h (η = n_t / n_i here).
            let sin2_t = (1.0 - c * c).max(0.0) / (eta * eta);
            if sin2_t >= 1.0 {
                return None;
            }
            let cos_t = (1.0 - sin2_t).sqrt();
            let wi = (-up / eta + (c / eta - cos_t) * h).normalize_or_zero();
            if wi.z >= 0.0 {
                return None;
            }
            (wi, ScatterFlags::TRANSMISSION | ScatterFlags::GLOSSY)
        };
        let wi = if below { flip_z(wi) } else { wi };
        let e = self.evaluate(wo, wi, true);
        if e.pdf <= 0.0 || !e.pdf.is_finite() || !e.f.is_finite() {
            return None;
        }
        Some(BsdfSample { wi, f: self.tint * e.f, pdf: e.pdf, flags })
    }
}

#[cfg(test)]
mod tests;
