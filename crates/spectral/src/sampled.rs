//! Spectra at a handful of sampled wavelengths: the per-path currency of the integrator.
//!
//! A path carries a [`SampledSpectrum<N>`] of throughput and radiance, one value per
//! entry of its [`SampledWavelengths<N>`]. Three strategies ([`SpectralMode`]) choose
//! those entries:
//!
//! * **hero** (default, N = 4): four wavelengths per path, stratified over [0, 1) and
//!   importance-sampled by a pdf that follows the visual response (Radziszewski et al.
//!   2009; Wilkie et al. 2014 "hero wavelength"; pdf from pbrt-v4 §4.6.5);
//! * **bins40** (N = 40): the seed thesis's fixed 40 wavelengths 380, 390, …, 770 nm,
//!   a 10 nm Riemann sum — deterministic in λ (no colour noise) but biased by the
//!   quadrature and blind outside 380–770 nm;
//! * **rgb** (N = 3): the three linear-sRGB channels, not spectral at all; for comparison
//!   with RGB renderers.

use crate::colour::{cie_xyz, xyz_to_linear_srgb};
use crate::tables::CIE_Y_INTEGRAL;
use std::ops::{Add, AddAssign, Div, DivAssign, Index, IndexMut, Mul, MulAssign, Sub};

/// Shortest wavelength the renderer samples, nm (the CIE tables' range).
pub const LAMBDA_MIN: f32 = 360.0;
/// Longest wavelength the renderer samples, nm.
pub const LAMBDA_MAX: f32 = 830.0;

/// Values of a spectrum (or, in RGB mode, of three colour channels) at N sampled points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledSpectrum<const N: usize>(pub [f32; N]);

impl<const N: usize> SampledSpectrum<N> {
    /// Every entry equal to `v`.
    #[inline]
    pub const fn splat(v: f32) -> Self {
        Self([v; N])
    }
    /// All zeros.
    #[inline]
    pub const fn zero() -> Self {
        Self([0.0; N])
    }
    /// All ones.
    #[inline]
    pub const fn one() -> Self {
        Self([1.0; N])
    }
    /// True if every entry is zero.
    #[inline]
    pub fn is_black(&self) -> bool {
        self.0.iter().all(|&v| v == 0.0)
    }
    /// True if no entry is NaN or infinite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
    /// The largest entry.
    #[inline]
    pub fn max_component(&self) -> f32 {
        self.0.iter().copied().fold(f32::NEG_INFINITY, f32::max)
    }
    /// The mean of the entries.
    #[inline]
    pub fn average(&self) -> f32 {
        self.0.iter().sum::<f32>() / N as f32
    }
    /// Applies `f` to every entry.
    #[inline]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Self(self.0.map(f))
    }
    /// Division that yields 0 where the divisor is 0 (for MIS weights and throughputs).
    #[inline]
    pub fn safe_div(self, rhs: Self) -> Self {
        let mut out = self.0;
        for (o, d) in out.iter_mut().zip(rhs.0) {
            *o = if d != 0.0 { *o / d } else { 0.0 };
        }
        Self(out)
    }
}

macro_rules! elementwise {
    ($tr:ident, $f:ident, $tra:ident, $fa:ident, $op:tt, $opa:tt) => {
        impl<const N: usize> $tr for SampledSpectrum<N> {
            type Output = Self;
            #[inline]
            fn $f(mut self, rhs: Self) -> Self {
                for (a, b) in self.0.iter_mut().zip(rhs.0) {
                    *a $opa b;
                }
                self
            }
        }
        impl<const N: usize> $tr<f32> for SampledSpectrum<N> {
            type Output = Self;
            #[inline]
            fn $f(mut self, rhs: f32) -> Self {
                for a in self.0.iter_mut() {
                    *a $opa rhs;
                }
                self
            }
        }
        impl<const N: usize> $tra for SampledSpectrum<N> {
            #[inline]
            fn $fa(&mut self, rhs: Self) {
                *self = *self $op rhs;
            }
        }
        impl<const N: usize> $tra<f32> for SampledSpectrum<N> {
            #[inline]
            fn $fa(&mut self, rhs: f32) {
                *self = *self $op rhs;
            }
        }
    };
}
elementwise!(Add, add, AddAssign, add_assign, +, +=);
elementwise!(Mul, mul, MulAssign, mul_assign, *, *=);
elementwise!(Div, div, DivAssign, div_assign, /, /=);

impl<const N: usize> Sub for SampledSpectrum<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, rhs: Self) -> Self {
        for (a, b) in self.0.iter_mut().zip(rhs.0) {
            *a -= b;
        }
        self
    }
}

impl<const N: usize> Mul<SampledSpectrum<N>> for f32 {
    type Output = SampledSpectrum<N>;
    #[inline]
    fn mul(self, rhs: SampledSpectrum<N>) -> SampledSpectrum<N> {
        rhs * self
    }
}

impl<const N: usize> Index<usize> for SampledSpectrum<N> {
    type Output = f32;
    #[inline]
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}

impl<const N: usize> IndexMut<usize> for SampledSpectrum<N> {
    #[inline]
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        &mut self.0[i]
    }
}

/// How a render samples the spectrum; chosen once per render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpectralMode {
    /// Four stratified, importance-sampled wavelengths per path (N = 4).
    #[default]
    Hero,
    /// The thesis's fixed 40 wavelengths, 380–770 nm in 10 nm steps (N = 40).
    Bins40,
    /// Three linear-sRGB channels (N = 3): an RGB renderer, for comparison.
    Rgb,
}

impl SpectralMode {
    /// Every mode, for sweeps and help texts.
    pub const ALL: [SpectralMode; 3] = [Self::Hero, Self::Bins40, Self::Rgb];

    /// The mode's name as the CLI spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Hero => "hero",
            Self::Bins40 => "bins40",
            Self::Rgb => "rgb",
        }
    }

    /// How many values a path carries in this mode.
    pub fn lanes(self) -> usize {
        match self {
            Self::Hero => 4,
            Self::Bins40 => 40,
            Self::Rgb => 3,
        }
    }
}

impl std::str::FromStr for SpectralMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| format!("unknown spectral mode '{s}' (expected hero, bins40 or rgb)"))
    }
}

/// The points at which a path's spectra are sampled, with the weight each gets when the
/// path's radiance is turned into colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths<const N: usize> {
    /// Wavelengths in nm (unused in RGB mode).
    pub lambda: [f32; N],
    /// Per-entry estimator weight: 1 / (N · pdf(λ)) for the spectral modes, so that
    /// XYZ = Σ wᵢ · L(λᵢ) · cmf(λᵢ) / ∫ȳ; 1 for RGB.
    pub weight: [f32; N],
    rgb: bool,
}

/// The visible-wavelength pdf p(λ) ∝ sech²(k(λ − 538 nm)) on [360, 830] nm (pbrt-v4
/// §4.6.5): its k, nm⁻¹.
pub const VIS_K: f32 = 0.0072;
/// The centre of the visible-wavelength pdf, nm.
pub const VIS_CENTRE: f32 = 538.0;

/// tanh(k·(360 − 538)): the visible-wavelength CDF's lower end, precomputed (checked
/// against the formula by a test) because `tanh` is not `const`.
pub const VIS_TANH_LO: f32 = -0.856_910_6;
/// tanh(k·(830 − 538)): the CDF's upper end.
pub const VIS_TANH_HI: f32 = 0.970_591_35;

/// The pdf (per nm) of [`sample_visible_wavelength`]:
/// p(λ) = k / ((tanh_hi − tanh_lo) · cosh²(k(λ − 538))).
#[inline]
pub fn visible_wavelength_pdf(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let t = (VIS_K * (lambda - VIS_CENTRE)).tanh();
    visible_pdf_from_tanh(t)
}

/// The same pdf from t = tanh(k(λ − 538)), using 1/cosh² = 1 − tanh².
#[inline]
fn visible_pdf_from_tanh(t: f32) -> f32 {
    VIS_K * (1.0 - t * t) / (VIS_TANH_HI - VIS_TANH_LO)
}

/// Maps u ∈ [0, 1) to a wavelength distributed by [`visible_wavelength_pdf`]
/// (inverse of its CDF, F(λ) = (tanh k(λ−538) − tanh k(360−538)) / (tanh k(830−538) − tanh k(360−538))).
#[inline]
pub fn sample_visible_wavelength(u: f32) -> f32 {
    sample_visible(u).0
}

/// (λ, pdf(λ)) for u ∈ [0, 1).
#[inline]
fn sample_visible(u: f32) -> (f32, f32) {
    let t = (VIS_TANH_LO + u * (VIS_TANH_HI - VIS_TANH_LO)).clamp(-0.999_999, 0.999_999);
    let lambda = (VIS_CENTRE + atanh(t) / VIS_K).clamp(LAMBDA_MIN, LAMBDA_MAX);
    (lambda, visible_pdf_from_tanh(t))
}

/// atanh(t) = ½ ln((1 + t)/(1 − t)) for |t| < 1, without a call into libm: `f32::atanh`
/// goes through `log1pf`, which cost 4–5 % of a Cornell-box render for four wavelengths
/// per sample. Within 2·10⁻⁷ of the exact value (absolute, for |t| ≤ 0.999 999; 10⁻⁷
/// relative away from 0) — a wavelength error below 10⁻⁴ nm, and the sample's pdf is
/// computed from `t` itself, so it stays exact. Branch-free, so that the hero loop over
/// the lanes vectorises.
#[inline]
fn atanh(t: f32) -> f32 {
    0.5 * ln_positive((1.0 + t) / (1.0 - t))
}

/// ln x for a positive, finite, normal x: x = 2ᵉ·m with m ∈ [√½, √2), ln m = 2 atanh(s)
/// with s = (m − 1)/(m + 1), |s| ≤ 0.1716, summed to s⁹ (the next term is below 10⁻⁹).
#[inline]
fn ln_positive(x: f32) -> f32 {
    let bits = x.to_bits();
    // m in [1, 2), then halved (and e raised) above √2.
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let high = m > std::f32::consts::SQRT_2;
    let m = if high { 0.5 * m } else { m };
    let e = ((bits >> 23) & 0xff) as i32 - 127 + high as i32;
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let series = 2.0 + s2 * (2.0 / 3.0 + s2 * (2.0 / 5.0 + s2 * (2.0 / 7.0 + s2 * (2.0 / 9.0))));
    e as f32 * std::f32::consts::LN_2 + s * series
}

/// Entry `i` of N hero wavelengths from the sample value `u`: (λ, weight 1 / (N·pdf(λ))).
#[inline(always)]
fn hero_entry<const N: usize>(u: f32, i: usize) -> (f32, f32) {
    // (u + i/N) mod 1 by one subtraction: `fract` calls libm's `truncf` where
    // the baseline x86-64 target has no rounding instruction (0.7 % of a render).
    let ui = u + i as f32 / N as f32;
    let ui = if ui >= 1.0 { ui - 1.0 } else { ui };
    let (l, pdf) = sample_visible(ui);
    (l, 1.0 / (N as f32 * pdf))
}

impl<const N: usize> SampledWavelengths<N> {
    /// Hero sampling: N wavelengths from u, u + 1/N, … (mod 1) through the visible pdf.
    pub fn sample_hero(u: f32) -> Self {
        let mut lambda = [0.0; N];
        let mut weight = [0.0; N];
        for i in 0..N {
            (lambda[i], weight[i]) = hero_entry::<N>(u, i);
        }
        Self { lambda, weight, rgb: false }
    }

    /// [`Self::sample_hero`] of each of `L` sample values, by the same operations (so to
    /// the bit the same wavelengths and weights), one wavelength at a time across the
    /// samples: the loops vectorise across them where the caller is compiled for wide
    /// vectors. One sample's four wavelengths are a chain of dependent divisions, which
    /// one at a time cost 4.4 % of a Cornell-box render (docs/figures.md).
    #[inline(always)]
    pub fn sample_hero_each<const L: usize>(u: &[f32; L]) -> [Self; L] {
        let mut lambda = [[0.0; L]; N];
        let mut weight = [[0.0; L]; N];
        for i in 0..N {
            for k in 0..L {
                (lambda[i][k], weight[i][k]) = hero_entry::<N>(u[k], i);
            }
        }
        std::array::from_fn(|k| Self {
            lambda: std::array::from_fn(|i| lambda[i][k]),
            weight: std::array::from_fn(|i| weight[i][k]),
            rgb: false,
        })
    }

    /// Equally spaced wavelengths `first`, `first + step`, … with Riemann weights `step`.
    pub fn fixed_bins(first: f32, step: f32) -> Self {
        Self { lambda: std::array::from_fn(|i| first + step * i as f32), weight: [step; N], rgb: false }
    }

    /// The three linear-sRGB channels (only meaningful for N = 3).
    pub fn rgb() -> Self {
        Self { lambda: [0.0; N], weight: [1.0; N], rgb: true }
    }

    /// Keeps only lane `k` (moved to lane 0) for the rest of the path, as a
    /// single-wavelength estimate: needed once a path's direction depends on wavelength
    /// (dispersion). Its weight grows N-fold and the others drop to zero, which keeps the
    /// estimate unbiased (pbrt-v4's `TerminateSecondary`, generalised to any kept lane).
    /// The caller must swap lanes 0 and `k` of its own per-lane values too.
    pub fn collapse_to(&mut self, k: usize) {
        self.lambda.swap(0, k);
        self.weight.swap(0, k);
        self.weight[0] *= N as f32;
        for w in &mut self.weight[1..] {
            *w = 0.0;
        }
    }

    /// True once [`SampledWavelengths::collapse_to`] has left a single lane.
    pub fn is_collapsed(&self) -> bool {
        N > 1 && self.weight[1..].iter().all(|&w| w == 0.0)
    }

    /// True in RGB mode: entries are colour channels, not wavelengths.
    #[inline]
    pub fn is_rgb(&self) -> bool {
        self.rgb
    }

    /// Evaluates a spectrum at every sampled wavelength.
    ///
    /// A plain loop, inlined with the spectrum: `array::map` went through an iterator
    /// adapter that kept the spectrum behind a call per lane (3–4 % of a render).
    #[inline(always)]
    pub fn eval(&self, spectrum: impl Fn(f32) -> f32) -> SampledSpectrum<N> {
        let mut out = [0.0; N];
        for i in 0..N {
            out[i] = spectrum(self.lambda[i]);
        }
        SampledSpectrum(out)
    }

    /// The linear-sRGB colour of a radiance estimate at these wavelengths.
    #[inline]
    pub fn to_linear_srgb(&self, radiance: &SampledSpectrum<N>) -> [f32; 3] {
        if self.rgb {
            return std::array::from_fn(|i| if i < N { radiance.0[i] } else { 0.0 });
        }
        let mut xyz = [0.0f32; 3];
        for i in 0..N {
            let term = xyz_term(radiance.0[i] * self.weight[i], self.lambda[i]);
            for c in 0..3 {
                xyz[c] += term[c];
            }
        }
        xyz_to_linear_srgb(xyz.map(|v| v / CIE_Y_INTEGRAL))
    }

    /// [`Self::to_linear_srgb`] of `L` samples (wavelengths `wl[k]`, radiance
    /// `radiance[k]`), by the same operations (the same bits), one wavelength at a time
    /// across the samples, so that the loops vectorise across them where the caller is
    /// compiled for wide vectors.
    #[inline(always)]
    pub fn to_linear_srgb_each<const L: usize>(wl: &[Self; L], radiance: &[SampledSpectrum<N>; L]) -> [[f32; 3]; L] {
        if wl.iter().any(|w| w.rgb) {
            return std::array::from_fn(|k| wl[k].to_linear_srgb(&radiance[k]));
        }
        let mut xyz = [[0.0f32; L]; 3];
        for i in 0..N {
            for k in 0..L {
                let term = xyz_term(radiance[k].0[i] * wl[k].weight[i], wl[k].lambda[i]);
                for c in 0..3 {
                    xyz[c][k] += term[c];
                }
            }
        }
        std::array::from_fn(|k| xyz_to_linear_srgb([0, 1, 2].map(|c| xyz[c][k] / CIE_Y_INTEGRAL)))
    }
}

/// One wavelength's term of a radiance's XYZ: `l` (radiance times the wavelength's
/// weight) times the colour-matching functions at `lambda`. A zero `l` adds ±0, which
/// leaves the sums as they were (they start at +0 and can never become −0), so no term
/// needs skipping.
#[inline(always)]
fn xyz_term(l: f32, lambda: f32) -> [f32; 3] {
    cie_xyz(lambda).map(|c| l * c)
}

#[cfg(test)]
mod tests;
