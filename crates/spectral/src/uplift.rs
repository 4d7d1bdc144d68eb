//! RGB → spectrum uplifting after Jakob & Hanika 2019, "A Low-Dimensional Function
//! Space for Efficient Spectral Upsampling" (Computer Graphics Forum 38(2)).
//!
//! A reflectance is the paper's sigmoid of a quadratic polynomial in wavelength,
//!
//! ```text
//! s(λ) = S(c₀λ² + c₁λ + c₂),   S(x) = ½ + x / (2·√(1 + x²)),
//! ```
//!
//! smooth, bounded to [0, 1] by construction and only three numbers.
//! [`fit_reflectance`] finds the coefficients of a linear-sRGB colour as the paper's
//! optimiser (and its `rgb2spec` table generator, whose tables Mitsuba 3 and pbrt-v4
//! use) does: the spectrum is lit by CIE D65, seen by the CIE 1931 2° observer, and
//! compared with the target in CIELAB. Here the fit runs per colour at scene load
//! (tens of µs) instead of through a precomputed 3D table.
//!
//! Emitters ([`RgbIlluminantSpectrum`]) are a scaled sigmoid polynomial times D65, as in
//! pbrt-v4's `RGBIlluminantSpectrum` and Mitsuba 3's emitter uplifting, so that an RGB
//! (1, 1, 1) light is D65, sRGB's own white.
//!
//! Fit details (all in `f64`):
//!
//! * integration: plain 1 nm Riemann sums over the CIE tables' 360–830 nm (the same
//!   weights as [`crate::colour::spectrum_to_xyz`]), with D65 linearly interpolated
//!   from its 5 nm table and the sums divided by N_w = Σ D65·ȳ (s ≡ 1 has Y = 1);
//! * target: linear sRGB → XYZ by [`SRGB_TO_XYZ`], after scaling each channel by the
//!   linear sRGB of the tabulated D65 itself ((1.00016, 0.99998, 0.99976), i.e. the
//!   offset of the 5 nm D65 table and 1 nm CMFs from sRGB's exact white point). Thus
//!   rgb (1, 1, 1) targets exactly s ≡ 1, greys are exactly constant spectra, and the
//!   reachable set (symmetric about s ≡ ½, since S(−x) = 1 − S(x)) contains the whole
//!   cube. Without it, colours like (0.999, 1, 1) lie just outside the reachable set
//!   and the fit cannot converge. The price: the round trip through
//!   [`XYZ_TO_SRGB`] reproduces rgb only up to that per-channel factor (≤ 2.5e-4);
//! * residual: CIELAB of the target minus CIELAB of the spectrum, white point = XYZ of
//!   s ≡ 1 (so white is L = 100, a = b = 0);
//! * solver: Newton (Gauss–Newton on a square system) with an analytic 3×3 Jacobian,
//!   Cramer's rule and a backtracking line search, on the polynomial in the normalised
//!   wavelength t = (λ − 360)/(830 − 360), expanded to nanometres at the end;
//! * continuation: start from the constant spectrum with the target's luminance (exact
//!   closed form) and walk the target linearly in XYZ towards the requested colour:
//!   the full step first, halving on failure and doubling on success, each step
//!   warm-started by the previous solution. Most colours converge in one step of
//!   4–6 iterations; colours with channels at 0 or 1 take a few more steps.

use std::sync::LazyLock;

use crate::SpectralError;
use crate::colour::{SRGB_TO_XYZ, XYZ_TO_SRGB};
use crate::tables::{CIE_SAMPLES, CIE_X, CIE_Y, CIE_Z, D65, D65_LAMBDA_MIN, D65_LAMBDA_STEP};

/// First wavelength (nm) of the fit's integration range and of the normalised variable t.
const FIT_LAMBDA_MIN: f64 = 360.0;
/// Last wavelength (nm) of the fit's integration range.
const FIT_LAMBDA_MAX: f64 = 830.0;

/// Targets are clamped into [ε, 1 − ε] before the fit: a channel of exactly 0 or 1
/// (other than for greys) needs infinite coefficients. This costs ≤ ε in the round trip.
const TARGET_EPS: f64 = 1e-6;
/// Newton stops once the CIELAB residual norm (ΔE*ab) is below this.
const TOL_FINAL: f64 = 1e-9;
/// A final residual up to this ΔE*ab is accepted as converged.
const TOL_ACCEPT: f64 = 1e-3;
/// Intermediate continuation steps only need to land in Newton's basin.
const TOL_STEP: f64 = 1e-3;
/// Newton iterations per continuation step.
const MAX_ITER: usize = 30;
/// Halvings of the Newton step in the line search.
const MAX_BACKTRACK: usize = 12;
/// The smallest continuation step (fraction of the whole path) before giving up.
const MIN_STEP: f64 = 1.0 / 4096.0;
/// |c₂| standing for ±∞ in the black and white greys: finite, so that the coefficients
/// serialise, and beyond the 1e18 where [`sigmoid`] returns exactly 0 or 1.
const GREY_LIMIT: f32 = 1e30;

/// The sigmoid S(x) = ½ + x / (2√(1 + x²)) of Jakob & Hanika 2019, in `f32`.
///
/// Exactly 0 / 1 for x = ∓∞ (and for |x| > 1e18, where x² would overflow); NaN stays NaN.
#[inline]
fn sigmoid(x: f32) -> f32 {
    // Both computed and one selected (no branch), so that loops over wavelengths
    // vectorise.
    let y = 0.5 + x / (2.0 * (1.0 + x * x).sqrt());
    // Beyond ±1e18 (and at ±∞, where x / √(1 + x²) would be ∞/∞ = NaN): exactly 1 or 0.
    let limit = if x > 0.0 { 1.0 } else { 0.0 };
    if x.abs() > 1e18 { limit } else { y }
}

/// The sigmoid in `f64`, exact 0 / 1 where x² would overflow.
#[inline]
fn sigmoid64(x: f64) -> f64 {
    if x.abs() > 1e150 {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

/// Inverse of the sigmoid for v in (0, 1): x = (v − ½)/√(v(1 − v)).
#[inline]
fn inverse_sigmoid64(v: f64) -> f64 {
    (v - 0.5) / (v * (1.0 - v)).sqrt()
}

/// Coefficients of a sigmoid polynomial s(λ) = S(c₀λ² + c₁λ + c₂), λ in nm
/// (Jakob & Hanika 2019).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SigmoidPolynomial {
    /// Coefficient of λ² (nm⁻²).
    pub c0: f32,
    /// Coefficient of λ (nm⁻¹).
    pub c1: f32,
    /// Constant term.
    pub c2: f32,
}

impl SigmoidPolynomial {
    /// s(λ) = S(c₀λ² + c₁λ + c₂) at `lambda_nm` (Jakob & Hanika 2019), in [0, 1].
    #[inline]
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        sigmoid((self.c0 * lambda_nm + self.c1) * lambda_nm + self.c2)
    }

    /// The maximum of s(λ) over 360–830 nm (Jakob & Hanika 2019's sigmoid is
    /// increasing, so it is at an end of the range or at the polynomial's vertex
    /// −c₁/(2c₀)). Evaluated in `f64` (not a hot path), so it can differ from
    /// [`eval`](Self::eval)'s `f32` rounding by ~1e-5 for large coefficients.
    pub fn max_value(&self) -> f32 {
        let (c0, c1, c2) = (self.c0 as f64, self.c1 as f64, self.c2 as f64);
        let x = |l: f64| (c0 * l + c1) * l + c2;
        let mut m = x(FIT_LAMBDA_MIN).max(x(FIT_LAMBDA_MAX));
        if c0 != 0.0 {
            let vertex = -c1 / (2.0 * c0);
            if (FIT_LAMBDA_MIN..=FIT_LAMBDA_MAX).contains(&vertex) {
                m = m.max(c2 - c1 * c1 / (4.0 * c0));
            }
        }
        sigmoid64(m) as f32
    }

    /// The constant spectrum v ∈ [0, 1] in closed form: c₀ = c₁ = 0, c₂ = S⁻¹(v) (as
    /// pbrt-v4 does for greys); v = 0 and v = 1 use ∓[`GREY_LIMIT`], giving exactly 0
    /// and 1.
    fn grey(v: f32) -> Self {
        let c2 = if v <= 0.0 {
            -GREY_LIMIT
        } else if v >= 1.0 {
            GREY_LIMIT
        } else {
            inverse_sigmoid64(v as f64) as f32
        };
        Self { c0: 0.0, c1: 0.0, c2 }
    }
}

/// Linear interpolation of the D65 table in `f64`; zero outside 300–830 nm.
fn d65_table(lambda: f64) -> f64 {
    let x = (lambda - D65_LAMBDA_MIN as f64) / D65_LAMBDA_STEP as f64;
    if !(0.0..=(D65.len() - 1) as f64).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(D65.len() - 2);
    let f = x - i as f64;
    D65[i] as f64 + f * (D65[i + 1] as f64 - D65[i] as f64)
}

/// 1 / N with N = Σ D65(λ)ȳ(λ) / Σ ȳ(λ) over 360–830 nm at 1 nm.
static D65_INV_NORM: LazyLock<f32> = LazyLock::new(|| {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (i, &y) in CIE_Y.iter().enumerate() {
        num += d65_table(FIT_LAMBDA_MIN + i as f64) * y as f64;
        den += y as f64;
    }
    (den / num) as f32
});

/// The factor 1 / N [`d65_normalised`] scales the D65 table by (for backends that
/// evaluate it elsewhere: the GPU).
pub fn d65_inv_norm() -> f32 {
    *D65_INV_NORM
}

/// CIE D65 linearly interpolated from [`crate::tables::D65`] and divided by
/// N = Σ D65·ȳ / Σ ȳ (1 nm sums over 360–830 nm), so that as a radiance it has
/// luminance Y = 1: the illuminant of Jakob & Hanika 2019's sRGB fit. Zero outside
/// 300–830 nm (and for NaN). O(1): N is computed once.
#[inline]
pub fn d65_normalised(lambda_nm: f32) -> f32 {
    let x = (lambda_nm - D65_LAMBDA_MIN) / D65_LAMBDA_STEP;
    if !(0.0..=(D65.len() - 1) as f32).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(D65.len() - 2);
    let f = x - i as f32;
    (D65[i] + f * (D65[i + 1] - D65[i])) * *D65_INV_NORM
}

/// Precomputed integration weights and colour transforms for the fit.
struct FitTables {
    /// Normalised wavelength t = (λ − 360)/470 of each 1 nm sample.
    t: [f64; CIE_SAMPLES],
    /// D65(λ)·[x̄, ȳ, z̄](λ) / N_w at each sample: XYZ = Σ s(λ)·w(λ).
    w: [[f64; 3]; CIE_SAMPLES],
    /// XYZ of s ≡ 1 (Y = 1): the CIELAB white point.
    white: [f64; 3],
    /// Linear sRGB → target XYZ: [`SRGB_TO_XYZ`] after scaling each channel by the
    /// linear sRGB of `white`, so that rgb (1, 1, 1) targets exactly `white`.
    rgb_to_target: [[f64; 3]; 3],
}

static FIT: LazyLock<FitTables> = LazyLock::new(|| {
    let mut t = [0.0; CIE_SAMPLES];
    let mut w = [[0.0; 3]; CIE_SAMPLES];
    let mut norm = 0.0;
    for i in 0..CIE_SAMPLES {
        let lambda = FIT_LAMBDA_MIN + i as f64;
        t[i] = (lambda - FIT_LAMBDA_MIN) / (FIT_LAMBDA_MAX - FIT_LAMBDA_MIN);
        let d = d65_table(lambda);
        w[i] = [d * CIE_X[i] as f64, d * CIE_Y[i] as f64, d * CIE_Z[i] as f64];
        norm += w[i][1];
    }
    let mut white = [0.0; 3];
    for wi in &mut w {
        for k in 0..3 {
            wi[k] /= norm;
            white[k] += wi[k];
        }
    }
    let to_xyz = SRGB_TO_XYZ.map(|row| row.map(f64::from));
    let to_rgb = XYZ_TO_SRGB.map(|row| row.map(f64::from));
    let white_rgb = to_rgb.map(|row| dot3(row, white));
    let rgb_to_target = to_xyz.map(|row| [0, 1, 2].map(|j| row[j] * white_rgb[j]));
    FitTables { t, w, white, rgb_to_target }
});

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// CIELAB's f(t) and its derivative f'(t).
#[inline]
fn lab_f(t: f64) -> (f64, f64) {
    const DELTA: f64 = 6.0 / 29.0;
    if t > DELTA * DELTA * DELTA {
        let c = t.cbrt();
        (c, 1.0 / (3.0 * c * c))
    } else {
        let k = 1.0 / (3.0 * DELTA * DELTA);
        (t * k + 4.0 / 29.0, k)
    }
}

/// CIE 1976 L*a*b* relative to `white`.
fn lab(xyz: [f64; 3], white: [f64; 3]) -> [f64; 3] {
    let f = |k: usize| lab_f(xyz[k] / white[k]).0;
    let (fx, fy, fz) = (f(0), f(1), f(2));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// CIELAB of the sigmoid polynomial with coefficients `c` (in t) and its Jacobian
/// ∂Lab/∂c, both analytic: ∂s/∂x = S'(x) = ½(1 + x²)^(−3/2).
fn lab_and_jacobian(c: [f64; 3], tables: &FitTables) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut xyz = [0.0f64; 3];
    let mut dxyz = [[0.0f64; 3]; 3]; // dxyz[k][j] = ∂XYZ_k/∂c_j
    for (&t, w) in tables.t.iter().zip(&tables.w) {
        let x = (c[0] * t + c[1]) * t + c[2];
        let q = 1.0 / (1.0 + x * x).sqrt();
        let s = if x.abs() < 1e150 { 0.5 + 0.5 * x * q } else { sigmoid64(x) };
        let ds = 0.5 * q * q * q;
        let g = [ds * t * t, ds * t, ds];
        for k in 0..3 {
            xyz[k] += s * w[k];
            for j in 0..3 {
                dxyz[k][j] += g[j] * w[k];
            }
        }
    }
    let white = tables.white;
    let (fx, dfx) = lab_f(xyz[0] / white[0]);
    let (fy, dfy) = lab_f(xyz[1] / white[1]);
    let (fz, dfz) = lab_f(xyz[2] / white[2]);
    let (dfx, dfy, dfz) = (dfx / white[0], dfy / white[1], dfz / white[2]);
    let lab = [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)];
    let mut jac = [[0.0; 3]; 3];
    for j in 0..3 {
        jac[0][j] = 116.0 * dfy * dxyz[1][j];
        jac[1][j] = 500.0 * (dfx * dxyz[0][j] - dfy * dxyz[1][j]);
        jac[2][j] = 200.0 * (dfy * dxyz[1][j] - dfz * dxyz[2][j]);
    }
    (lab, jac)
}

/// Solves the 3×3 system `a x = b` by Cramer's rule; `None` if singular.
fn solve3(a: &[[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let det = det3(a);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let mut x = [0.0; 3];
    for (col, xc) in x.iter_mut().enumerate() {
        let mut m = *a;
        for row in 0..3 {
            m[row][col] = b[row];
        }
        *xc = det3(&m) / det;
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Newton iterations on Lab(c) = `target` from `c`, with a backtracking line search on
/// the residual norm. Returns the final ΔE*ab; `c` holds the best coefficients found.
fn newton(c: &mut [f64; 3], target: [f64; 3], tol: f64, tables: &FitTables) -> f64 {
    let (lab0, mut jac) = lab_and_jacobian(*c, tables);
    let mut r = sub3(lab0, target);
    let mut err = dot3(r, r).sqrt();
    for _ in 0..MAX_ITER {
        if err < tol {
            break;
        }
        let Some(step) = solve3(&jac, [-r[0], -r[1], -r[2]]) else {
            break;
        };
        let mut alpha = 1.0;
        let mut improved = false;
        for _ in 0..MAX_BACKTRACK {
            let trial = [c[0] + alpha * step[0], c[1] + alpha * step[1], c[2] + alpha * step[2]];
            let (lab_t, jac_t) = lab_and_jacobian(trial, tables);
            let r_t = sub3(lab_t, target);
            let err_t = dot3(r_t, r_t).sqrt();
            if err_t < err {
                (*c, jac, r, err, improved) = (trial, jac_t, r_t, err_t, true);
                break;
            }
            alpha *= 0.5;
        }
        if !improved {
            break; // Stagnated (at rounding level, or stuck): the caller judges `err`.
        }
    }
    err
}

/// Fits the coefficients in the normalised variable t for a linear-sRGB target already
/// clamped into [ε, 1 − ε]³, by continuation from grey. `Err` carries the best ΔE*ab.
fn fit_normalised(rgb: [f64; 3]) -> Result<[f64; 3], f64> {
    let tables = &*FIT;
    let xyz_target = tables.rgb_to_target.map(|row| dot3(row, rgb));

    // Start: the constant spectrum with the target's luminance (exact, residual 0).
    let v = xyz_target[1].clamp(TARGET_EPS, 1.0 - TARGET_EPS);
    let mut c = [0.0, 0.0, inverse_sigmoid64(v)];
    let xyz_start = tables.white.map(|w| w * v);

    let (mut tau, mut h) = (0.0f64, 1.0f64);
    let mut best = f64::INFINITY;
    loop {
        let next = (tau + h).min(1.0);
        let last = next >= 1.0;
        let xyz = [0, 1, 2].map(|k| xyz_start[k] + next * (xyz_target[k] - xyz_start[k]));
        let goal = lab(xyz, tables.white);
        let mut trial = c;
        let err = newton(&mut trial, goal, if last { TOL_FINAL } else { TOL_STEP }, tables);
        if last {
            best = best.min(err);
        }
        if err < if last { TOL_ACCEPT } else { TOL_STEP } {
            if last {
                return Ok(trial);
            }
            (c, tau) = (trial, next);
            h *= 2.0;
        } else {
            h *= 0.5;
            if h < MIN_STEP {
                return Err(best);
            }
        }
    }
}

/// Expands a polynomial in t = (λ − 360)/470 into one in λ (nm), in `f64`.
fn to_nanometres(c: [f64; 3]) -> SigmoidPolynomial {
    let a = 1.0 / (FIT_LAMBDA_MAX - FIT_LAMBDA_MIN);
    let b = -FIT_LAMBDA_MIN * a;
    // x = c0 (aλ + b)² + c1 (aλ + b) + c2
    SigmoidPolynomial {
        c0: (c[0] * a * a) as f32,
        c1: (2.0 * c[0] * a * b + c[1] * a) as f32,
        c2: (c[0] * b * b + c[1] * b + c[2]) as f32,
    }
}

/// Fits coefficients so that the reflectance, lit by CIE D65 and seen by the CIE 1931
/// observer, reproduces `rgb` (linear sRGB, each in \[0, 1\]), minimising the CIELAB
/// difference as Jakob & Hanika 2019's optimiser does (details in the module docs).
///
/// Exact greys (r = g = b = v) are the constant v in closed form. Other colours have
/// their channels clamped into [1e-6, 1 − 1e-6] first (0 and 1 need infinite
/// coefficients). Components outside [0, 1] or NaN give
/// [`SpectralError::ReflectanceOutOfRange`]; a fit that does not reach ΔE*ab < 1e-3
/// gives [`SpectralError::UpliftDidNotConverge`] (not seen for any colour in the cube).
pub fn fit_reflectance(rgb: [f32; 3]) -> Result<SigmoidPolynomial, SpectralError> {
    if !rgb.iter().all(|v| (0.0..=1.0).contains(v)) {
        return Err(SpectralError::ReflectanceOutOfRange { rgb });
    }
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return Ok(SigmoidPolynomial::grey(rgb[0]));
    }
    let target = rgb.map(|v| (v as f64).clamp(TARGET_EPS, 1.0 - TARGET_EPS));
    match fit_normalised(target) {
        Ok(c) => Ok(to_nanometres(c)),
        Err(residual) => Err(SpectralError::UpliftDidNotConverge { rgb, residual: residual as f32 }),
    }
}

/// A reflectance spectrum uplifted from linear sRGB in \[0, 1\]³ (Jakob & Hanika 2019;
/// pbrt-v4's `RGBAlbedoSpectrum`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbAlbedoSpectrum {
    /// The fitted sigmoid polynomial.
    pub poly: SigmoidPolynomial,
}

impl RgbAlbedoSpectrum {
    /// Uplifts `rgb` with [`fit_reflectance`] (same errors).
    pub fn new(rgb: [f32; 3]) -> Result<Self, SpectralError> {
        Ok(Self { poly: fit_reflectance(rgb)? })
    }

    /// The reflectance at `lambda_nm`, in [0, 1].
    #[inline]
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        self.poly.eval(lambda_nm)
    }
}

/// An emission spectrum uplifted from an unbounded linear-sRGB radiance:
/// scale = 2·max(rgb), poly = fit(rgb/scale) (all zero → zero spectrum),
/// eval(λ) = scale · poly(λ) · d65_normalised(λ). This matches pbrt-v4's
/// RGBIlluminantSpectrum and Mitsuba 3's emitter uplifting (Jakob & Hanika 2019 sigmoid
/// polynomials), so that a white (1,1,1) emitter renders as exactly white in sRGB (up
/// to the D65 table's own 2.4e-4 offset from sRGB's white point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbIlluminantSpectrum {
    /// 2·max(rgb): brings the colour into [0, ½]³, where fits are easy.
    pub scale: f32,
    /// The sigmoid polynomial fitted to rgb / scale.
    pub poly: SigmoidPolynomial,
}

impl RgbIlluminantSpectrum {
    /// Uplifts a linear-sRGB radiance (Jakob & Hanika 2019 sigmoid times D65).
    /// Components must be finite and non-negative (and 2·max finite), otherwise
    /// [`SpectralError::BadValue`]; a failed fit gives
    /// [`SpectralError::UpliftDidNotConverge`].
    pub fn new(rgb: [f32; 3]) -> Result<Self, SpectralError> {
        if let Some(&value) = rgb.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(SpectralError::BadValue { what: "RGB illuminant component", value });
        }
        let m = rgb[0].max(rgb[1]).max(rgb[2]);
        if m == 0.0 {
            return Ok(Self { scale: 0.0, poly: SigmoidPolynomial::grey(0.0) });
        }
        let scale = 2.0 * m;
        if !scale.is_finite() {
            return Err(SpectralError::BadValue { what: "RGB illuminant component", value: m });
        }
        let poly = fit_reflectance(rgb.map(|v| v / scale))?;
        Ok(Self { scale, poly })
    }

    /// The emitted radiance at `lambda_nm`: scale · s(λ) · D65(λ)/N.
    #[inline]
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        self.scale * self.poly.eval(lambda_nm) * d65_normalised(lambda_nm)
    }
}

pub mod table;
pub use table::{TABLE_RES, UpliftTable, uplift_table};

#[cfg(test)]
mod tests;
