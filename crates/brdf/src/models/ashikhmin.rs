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

use crate::frame::flip_z;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::wgsl::{ModelWgsl, WgslConstant, WgslPiece, WgslValue};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags};
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
        source: include_str!("ashikhmin.wgsl"),
        needs: &[WgslPiece::Sampling],
        constants: &[
            WgslConstant { name: "MAT_ASHIKHMIN_MAX_EXPONENT", value: WgslValue::F32(MAX_EXPONENT) },
            WgslConstant { name: "MAT_ASHIKHMIN_MIN_COS", value: WgslValue::F32(MIN_COS) },
            WgslConstant { name: "MAT_ASHIKHMIN_MIN_LOBE_PROBABILITY", value: WgslValue::F32(MIN_LOBE_PROBABILITY) },
        ],
    };

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Ashikhmin<N> {
        Ashikhmin::new(self.nu, self.nv, self.rs.sample(wl), self.rd.sample(wl))
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
        if wo.z * wi.z <= 0.0 {
            return SampledSpectrum::zero();
        }
        if wo.z < 0.0 { self.eval_up(flip_z(wo), flip_z(wi)) } else { self.eval_up(wo, wi) }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z * wi.z <= 0.0 {
            return 0.0;
        }
        if wo.z < 0.0 { self.pdf_up(flip_z(wo), flip_z(wi)) } else { self.pdf_up(wo, wi) }
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
mod tests {
    use super::*;
    use crate::models::schlick::tests::Zoom;
    use crate::validation::{
        Chi2Config, Chi2Result, TestRng, chi2_test, directional_albedo, pdf_integral, reciprocity_error, sidak,
    };

    fn sa(nu: f32, nv: f32, rs: f32, rd: f32) -> Ashikhmin<1> {
        Ashikhmin::new(nu, nv, SampledSpectrum([rs]), SampledSpectrum([rd]))
    }

    fn dir(z: f32, phi_deg: f32) -> Vec3 {
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = phi_deg.to_radians();
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }

    const D45: f32 = std::f32::consts::FRAC_1_SQRT_2;
    const GRAZING: f32 = 0.05;

    /// A 1°×1° grid with 6×6 quadrature points per cell, for lobes a few degrees wide.
    const FINE: Chi2Config =
        Chi2Config { theta_bins: 180, phi_bins: 360, samples: 1_000_000, min_expected: 5.0, quadrature: 6 };

    /// 0.5° in θ × 0.25° in φ, for a lobe a third of a degree wide across the plane of
    /// incidence that also meets the horizon (which stays a cell boundary here).
    const FINER: Chi2Config =
        Chi2Config { theta_bins: 360, phi_bins: 1440, samples: 1_000_000, min_expected: 5.0, quadrature: 4 };

    #[derive(Clone, Copy, Debug)]
    enum Grid {
        Finer,
        Default,
        Fine,
        /// Zoomed around the mirror direction, scaling the in-plane (s) and perpendicular
        /// (t) gnomonic coordinates, with this many quadrature points per cell side.
        Zoom(f64, f64, usize),
    }

    struct Case {
        name: String,
        bsdf: Ashikhmin<1>,
        wo: Vec3,
        grid: Grid,
    }

    fn run(case: &Case, seed: u64) -> Chi2Result {
        match case.grid {
            Grid::Default => chi2_test(&case.bsdf, case.wo, &Chi2Config::default(), seed),
            Grid::Fine => chi2_test(&case.bsdf, case.wo, &FINE, seed),
            Grid::Finer => chi2_test(&case.bsdf, case.wo, &FINER, seed),
            Grid::Zoom(a, b, q) => {
                let config = Chi2Config { quadrature: q, ..Chi2Config::default() };
                chi2_test(&Zoom::mirror(case.bsdf, case.wo, a, b), case.wo, &config, seed)
            }
        }
    }

    /// A zoom for the specular lobe at ωo in the xz plane (cos θo = `z`): ωi spreads about
    /// 2/√(n_u + 1) in the plane of incidence and 2 cos θo/√(n_v + 1) across it, scaled to
    /// about 0.3 in gnomonic units.
    fn zoom_xz(nu: f32, nv: f32, z: f32, q: usize) -> Grid {
        let (su, sv) = (2.0 / ((nu + 1.0) as f64).sqrt(), 2.0 * z.abs() as f64 / ((nv + 1.0) as f64).sqrt());
        Grid::Zoom(0.3 / su, 0.3 / sv, q)
    }

    /// Every chi-square case of this file (the Šidák correction counts them all).
    fn cases() -> Vec<Case> {
        let mut v = Vec::new();
        let wos = [
            ("n", dir(1.0, 0.0)),
            ("45°", dir(D45, 0.0)),
            ("grazing", dir(GRAZING, 0.0)),
            ("below 45°", -dir(D45, 0.0)),
        ];
        // Broad lobes, with the default diffuse + specular mix.
        for n in [1.0f32, 10.0] {
            for (wn, wo) in wos {
                v.push(Case {
                    name: format!("n={n} Rs=0.05 Rd=0.5 wo={wn}"),
                    bsdf: sa(n, n, 0.05, 0.5),
                    wo,
                    grid: Grid::Default,
                });
            }
        }
        for (wn, wo) in [("45°", dir(D45, 20.0)), ("grazing", dir(GRAZING, 0.0))] {
            v.push(Case {
                name: format!("n=100 Rs=0.05 Rd=0.5 wo={wn}"),
                bsdf: sa(100.0, 100.0, 0.05, 0.5),
                wo,
                grid: Grid::Default,
            });
        }
        // The specular lobe alone (R_d = 0): n = 1000 on a 1° grid (a finer one at grazing
        // incidence, where it is 0.4° across the plane of incidence and meets the horizon),
        // n = 10⁵ zoomed.
        for (wn, wo) in wos {
            let grid = if wo.z.abs() < 0.1 { Grid::Finer } else { Grid::Fine };
            v.push(Case { name: format!("n=1000 specular wo={wn}"), bsdf: sa(1000.0, 1000.0, 0.05, 0.0), wo, grid });
        }
        for (wn, wo) in wos {
            v.push(Case {
                name: format!("n=1e5 specular wo={wn} (zoom)"),
                bsdf: sa(1e5, 1e5, 0.05, 0.0),
                wo,
                grid: zoom_xz(1e5, 1e5, wo.z, 6),
            });
        }
        // Anisotropic: 10 × 1000 on the 1° grid; 10⁴ × 10 zoomed across u at normal incidence
        // and on the 1° grid at 45°, where its wide arc meets the horizon (a zoom would
        // squeeze that edge into a few cells).
        for (wn, wo) in [("n", dir(1.0, 0.0)), ("45° in xz", dir(D45, 0.0)), ("45° in yz", dir(D45, 90.0))] {
            v.push(Case {
                name: format!("nu=10 nv=1000 wo={wn}"),
                bsdf: sa(10.0, 1000.0, 0.05, 0.5),
                wo,
                grid: Grid::Fine,
            });
        }
        for (wn, wo) in [("n (zoom)", dir(1.0, 0.0)), ("45° in xz", dir(D45, 0.0)), ("below n (zoom)", -Vec3::Z)] {
            let grid =
                if wn.ends_with("(zoom)") { Grid::Zoom(0.3 * 101.0 / 2.0, 0.3 * 3.3 / 2.0, 6) } else { Grid::Fine };
            v.push(Case { name: format!("nu=1e4 nv=10 specular wo={wn}"), bsdf: sa(1e4, 10.0, 0.05, 0.0), wo, grid });
        }
        // Extremes of the parameters: n = 0 (a uniform half-vector density), R_s = 1.
        v.push(Case {
            name: "n=0 Rs=0.05 Rd=0.5 wo=45°".into(),
            bsdf: sa(0.0, 0.0, 0.05, 0.5),
            wo: dir(D45, 0.0),
            grid: Grid::Default,
        });
        v.push(Case {
            name: "nu=1e6 nv=0 Rs=1 wo=n (zoom)".into(),
            bsdf: sa(1e6, 0.0, 1.0, 1.0),
            wo: Vec3::Z,
            grid: Grid::Zoom(150.0, 0.15, 6),
        });
        v
    }

    /// `sample` returns what `eval` and `pdf` give for its direction, for every chi-square
    /// case's BSDF and ωo (the zoomed cases re-evaluate them, see [`Zoom`]).
    #[test]
    fn sample_agrees_with_eval_and_pdf() {
        for (k, case) in cases().iter().enumerate() {
            if let Some(e) = crate::validation::sample_consistency(&case.bsdf, case.wo, 20_000, k as u64, 1e-5) {
                panic!("{}: {e}", case.name);
            }
        }
    }

    fn check_cases(part: usize, parts: usize) {
        let all = cases();
        let alpha = sidak(0.01, all.len());
        let mut failed = Vec::new();
        for (k, case) in all.iter().enumerate().filter(|(k, _)| k % parts == part) {
            let res = run(case, 2000 + k as u64);
            eprintln!("chi2 ashikhmin | {:<40} | p = {:.4} (dof {})", case.name, res.p_value, res.dof);
            if !(res.p_value > alpha && res.inconsistent == 0) {
                failed.push(format!("{}: {res:?}", case.name));
            }
        }
        assert!(failed.is_empty(), "α = {alpha:.2e}: {failed:#?}");
    }

    #[test]
    fn sampling_matches_pdf_part_1() {
        check_cases(0, 3);
    }
    #[test]
    fn sampling_matches_pdf_part_2() {
        check_cases(1, 3);
    }
    #[test]
    fn sampling_matches_pdf_part_3() {
        check_cases(2, 3);
    }

    /// Prints the directional albedo over exponents, reflectances and cos θo, for reports:
    /// `cargo test -p brdf --lib ashikhmin_albedo_table -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn ashikhmin_albedo_table() {
        for (rs, rd) in [(1.0f32, 1.0f32), (0.0, 1.0), (0.05, 1.0), (0.05, 0.5), (1.0, 0.0), (0.5, 1.0)] {
            for (nu, nv) in [
                (0.0f32, 0.0f32),
                (1.0, 1.0),
                (10.0, 10.0),
                (100.0, 100.0),
                (1e4, 1e4),
                (1e5, 1e5),
                (10.0, 1000.0),
                (1e4, 10.0),
            ] {
                let b = sa(nu, nv, rs, rd);
                let row: Vec<String> = [1.0f32, 0.7, 0.4, 0.2, 0.1, 0.05, 0.01]
                    .iter()
                    .map(|&z| {
                        let (a, se) = directional_albedo(&b, dir(z, 30.0), 200_000, 5);
                        format!("{a:6.4}±{se:.4}")
                    })
                    .collect();
                eprintln!("Rs={rs:<4} Rd={rd:<4} nu={nu:<6} nv={nv:<6} | {}", row.join(" "));
            }
        }
    }

    /// The specular lobe's pdf without the reflection's Jacobian 1/(4 ωo·h): must fail.
    struct NoJacobian(Ashikhmin<1>);

    impl Bsdf<1> for NoJacobian {
        fn flags(&self) -> ScatterFlags {
            self.0.flags()
        }
        fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<1> {
            self.0.eval(wo, wi)
        }
        fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
            if wo.z <= 0.0 || wi.z <= 0.0 {
                return 0.0;
            }
            let b = &self.0;
            let ps = b.specular_probability(wo.z);
            let h = (wo + wi).normalize();
            ps * b.norm * (0.5 * FRAC_1_PI) * phong_lobe(b.nu, b.nv, h) + (1.0 - ps) * cosine_hemisphere_pdf(wi.z)
        }
        fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<1>> {
            let s = self.0.sample(wo, uc, u)?;
            Some(BsdfSample { pdf: self.pdf(wo, s.wi), ..s })
        }
    }

    #[test]
    fn a_pdf_without_the_half_vector_jacobian_fails() {
        for (k, (b, wo)) in [(sa(100.0, 100.0, 0.05, 0.5), dir(0.8, 20.0)), (sa(10.0, 1000.0, 0.05, 0.0), Vec3::Z)]
            .into_iter()
            .enumerate()
        {
            let r = chi2_test(&NoJacobian(b), wo, &Chi2Config::default(), 31 + k as u64);
            eprintln!("chi2 ashikhmin broken (no Jacobian) {k} | p = {:.3e}", r.p_value);
            assert!(r.p_value < 1e-6, "the broken pdf passed: {r:?}");
        }
    }

    /// The fraction of `sample` calls that return a direction.
    fn accepted(b: &Ashikhmin<1>, wo: Vec3, n: usize, seed: u64) -> f64 {
        let mut rng = TestRng::new(seed);
        let k = (0..n)
            .filter(|_| b.sample(wo, rng.next_f32(), Vec2::new(rng.next_f32(), rng.next_f32())).is_some())
            .count();
        k as f64 / n as f64
    }

    #[test]
    fn pdf_integrates_to_the_probability_of_a_sample() {
        let wos = [dir(1.0, 0.0), dir(D45, 30.0), dir(GRAZING, 0.0), -dir(D45, 0.0)];
        let bsdfs = [
            sa(0.0, 0.0, 0.05, 0.5),
            sa(1.0, 1.0, 0.05, 0.5),
            sa(10.0, 10.0, 0.5, 0.5),
            sa(100.0, 100.0, 0.05, 0.0),
            sa(10.0, 1000.0, 0.05, 0.5),
            sa(1000.0, 1000.0, 0.05, 0.0),
        ];
        for (i, b) in bsdfs.iter().enumerate() {
            for (j, &wo) in wos.iter().enumerate() {
                // The n = 1000 lobes are too narrow for a 1000² grid: zoomed (the same
                // integral) away from the horizon, a 4000² grid at grazing incidence, where
                // they meet the horizon and are 0.2° across the plane of incidence.
                let integral = match (i >= 4, wo.z.abs() < 0.1) {
                    (false, _) => pdf_integral(b, wo, 1000),
                    (true, true) => pdf_integral(b, wo, 4000),
                    (true, false) => {
                        let Grid::Zoom(a_s, a_t, _) = zoom_xz(b.nu, b.nv, wo.z, 6) else { unreachable!() };
                        pdf_integral(&Zoom::mirror(*b, wo, a_s, a_t), wo, 1000)
                    }
                };
                let expect = accepted(b, wo, 500_000, (10 * i + j) as u64);
                assert!(integral <= 1.0 + 2e-3, "{i} {wo}: {integral}");
                assert!((integral - expect).abs() < 3e-3, "{i} {wo}: ∫pdf = {integral}, accepted {expect}");
            }
        }
        // Far too narrow for the grid: integrate the zoomed pdf (the same integral).
        for (j, &wo) in wos.iter().enumerate() {
            let b = sa(1e5, 1e5, 0.05, 0.0);
            let Grid::Zoom(a_s, a_t, _) = zoom_xz(1e5, 1e5, wo.z, 6) else { unreachable!() };
            let integral = pdf_integral(&Zoom::mirror(b, wo, a_s, a_t), wo, 1000);
            let expect = accepted(&b, wo, 500_000, 90 + j as u64);
            assert!((integral - expect).abs() < 3e-3, "n=1e5 {wo}: ∫pdf = {integral}, accepted {expect}");
        }
        // Nothing is lost at normal incidence with a narrow lobe.
        let zoomed = Zoom::mirror(bsdfs[5], Vec3::Z, 5.0, 5.0);
        assert!((pdf_integral(&zoomed, Vec3::Z, 1000) - 1.0).abs() < 2e-3);
    }

    #[test]
    fn energy_is_conserved() {
        let mut seed = 0;
        let exponents = [
            (0.0f32, 0.0f32),
            (1.0, 1.0),
            (10.0, 10.0),
            (100.0, 100.0),
            (1e4, 1e4),
            (1e5, 1e5),
            (10.0, 1000.0),
            (1e4, 10.0),
        ];
        for (rs, rd) in [(1.0f32, 1.0f32), (0.0, 1.0), (0.05, 1.0), (0.5, 1.0)] {
            for (nu, nv) in exponents {
                for z in [1.0f32, 0.7, 0.4, 0.1, 0.01] {
                    seed += 1;
                    let (albedo, se) = directional_albedo(&sa(nu, nv, rs, rd), dir(z, 30.0), 20_000, seed);
                    assert!(albedo <= 1.0 + 4.0 * se + 1e-5, "Rs={rs} Rd={rd} n=({nu}, {nv}) z={z}: {albedo} ± {se}");
                }
            }
        }
        // The bound is reached: with F ≡ 1 and a narrow lobe at normal incidence nothing is
        // lost, and the diffuse term alone gives 1 − (1 − v₂/2)⁵ ≈ 0.969 at v₂ = 1.
        let (albedo, se) = directional_albedo(&sa(1e5, 1e5, 1.0, 0.0), Vec3::Z, 100_000, 1);
        assert!(albedo > 0.999 && albedo <= 1.0 + 4.0 * se, "{albedo} ± {se}");
        // But broad lobes lose most of it: ρ_s n·k₁ = p(ωi) F n·k₁/max(n·k₁, n·k₂), and the
        // half-vector density sends much of p below the horizon (n = 0: 86 % lost).
        let (albedo, se) = directional_albedo(&sa(0.0, 0.0, 1.0, 0.0), Vec3::Z, 100_000, 2);
        assert!((albedo - 0.1385).abs() < 4.0 * se + 2e-3, "{albedo} ± {se}");
    }

    #[test]
    fn reciprocal() {
        for (k, b) in [
            sa(100.0, 100.0, 0.05, 0.5),
            sa(10.0, 1000.0, 0.5, 0.2),
            sa(1e4, 10.0, 0.0, 1.0),
            sa(0.0, 0.0, 1.0, 0.0),
            sa(3.0, 30.0, 0.9, 0.9),
        ]
        .iter()
        .enumerate()
        {
            let e = reciprocity_error(b, 20_000, k as u64);
            assert!(e < 1e-4, "case {k}: {e}");
        }
    }

    #[test]
    fn no_nan_or_inf_anywhere() {
        let mut bsdfs = Vec::new();
        for nu in [0.0f32, 1.0, 1e3, MAX_EXPONENT] {
            for nv in [0.0f32, 10.0, MAX_EXPONENT] {
                for (rs, rd) in [(0.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.05, 0.5)] {
                    bsdfs.push(sa(nu, nv, rs, rd));
                }
            }
        }
        let special = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::Y,
            Vec3::new(0.6, 0.8, 0.0),
            Vec3::new(1.0, 0.0, 1e-7).normalize(),
            Vec3::new(-1.0, 0.0, 1e-7).normalize(),
            Vec3::new(0.0, -1.0, -1e-7).normalize(),
            Vec3::new(1.0, 0.0, 1e-30),
            Vec3::new(0.3, 0.4, 0.866).normalize(),
            Vec3::new(-0.3, -0.4, 0.866).normalize(),
        ];
        let check = |b: &Ashikhmin<1>, wo: Vec3, wi: Vec3, uc: f32, u: Vec2| {
            let (f, p) = (b.eval(wo, wi)[0], b.pdf(wo, wi));
            assert!(f.is_finite() && f >= 0.0 && p.is_finite() && p >= 0.0, "{b:?} {wo} {wi}: f={f} pdf={p}");
            if let Some(s) = b.sample(wo, uc, u) {
                assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-3, "{b:?} {wo}: {s:?}");
                assert!(s.f[0].is_finite() && s.f[0] >= 0.0 && s.pdf.is_finite() && s.pdf > 0.0, "{b:?} {wo}: {s:?}");
            }
        };
        let mut rng = TestRng::new(99);
        let per = 1_000_000 / bsdfs.len() + 1;
        for b in &bsdfs {
            for &wo in &special {
                for &wi in &special {
                    for uc in [0.0, 0.5, 0.999_999_9] {
                        for u in
                            [Vec2::ZERO, Vec2::splat(0.999_999_9), Vec2::new(0.0, 0.999_999_9), Vec2::new(0.5, 0.25)]
                        {
                            check(b, wo, wi, uc, u);
                        }
                    }
                }
            }
            for _ in 0..per {
                let mut d = || crate::sampling::uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
                let (wo, wi) = (d(), d());
                check(b, wo, wi, rng.next_f32(), Vec2::new(rng.next_f32(), rng.next_f32()));
            }
        }
    }

    #[test]
    fn half_vector_sampling_follows_the_paper() {
        // With n_u = n_v the azimuth is uniform and cos θ_h = (1 − ξ₂)^{1/(n + 1)}.
        let h = sample_half(10.0, 10.0, 1.0, Vec2::new(0.1, 0.5));
        assert!((h.z - 0.5f32.powf(1.0 / 11.0)).abs() < 1e-6);
        assert!((h.y.atan2(h.x) - 0.4 * FRAC_PI_2).abs() < 1e-5);
        // p_h integrates to 1 over the hemisphere of half vectors (the paper's normalisation).
        for (nu, nv) in [(0.0f32, 0.0f32), (10.0, 1000.0), (100.0, 100.0)] {
            let norm = ((nu + 1.0) * (nv + 1.0)).sqrt() as f64 * 0.5 / std::f64::consts::PI;
            let n = 2000;
            let mut sum = 0.0;
            for i in 0..n {
                let z = (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                for j in 0..n {
                    let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n as f64;
                    let h = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                    sum += norm * phong_lobe(nu, nv, h) as f64;
                }
            }
            let integral = sum * std::f64::consts::TAU / (n * n) as f64;
            assert!((integral - 1.0).abs() < 2e-3, "({nu}, {nv}): {integral}");
        }
        // Huge exponents near h = n: no 0/0, and the value matches t^e in f64.
        let h = Vec3::new(1e-3, 2e-3, 1.0).normalize();
        let (hx2, hy2) = ((h.x as f64).powi(2), (h.y as f64).powi(2));
        let (t, e) = ((1.0 - hx2 - hy2).sqrt(), (1e5 * hx2 + 1e6 * hy2) / (hx2 + hy2));
        assert!((phong_lobe(1e5, 1e6, h) as f64 - t.powf(e)).abs() < 1e-4 * t.powf(e));
        assert_eq!(phong_lobe(1e6, 1e6, Vec3::Z), 1.0);
    }

    #[test]
    fn parameters_resolve() {
        use crate::params::{ParamSet, ParamValue};
        let wl = SampledWavelengths::<1>::fixed_bins(550.0, 10.0);
        let b = AshikhminParams::default().bsdf(&wl);
        assert_eq!((b.nu, b.nv), (100.0, 100.0));
        assert!((b.rs[0] - 0.05).abs() < 0.01 && (b.rd[0] - 0.5).abs() < 0.05, "{b:?}");
        let given =
            AshikhminParams::resolve("m", &[("nu", ParamValue::Scalar(1e6)), ("nv", ParamValue::Scalar(0.0))]).unwrap();
        let b = given.bsdf(&wl);
        assert_eq!((b.nu, b.nv), (1e6, 0.0));
        assert!(AshikhminParams::resolve("m", &[("nu", ParamValue::Scalar(2e6))]).is_err());
        for key in ["nu", "nv", "Rs", "Rd"] {
            assert!(AshikhminParams::DEF.param_by_mtl_key(key).is_some(), "{key}");
        }
    }
}
