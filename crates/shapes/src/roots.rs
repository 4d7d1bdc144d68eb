//! Real and complex roots of univariate polynomials.
//!
//! Coefficients are always in **ascending** order: `c[0] + c[1]·t + c[2]·t² + …`.
//!
//! * quadratics: the textbook formula ([`quadratic_naive`]) next to the cancellation-free
//!   one ([`quadratic_stable`], [`quadratic_f64`]; Press et al., *Numerical Recipes*, 3rd
//!   ed., §5.6; the discriminant as in Kahan, "On the cost of floating-point computation
//!   without extra-precise arithmetic", 2004);
//! * [`cubic`] and [`quartic`] in closed form (Numerical Recipes §5.6; Blinn, "How to
//!   solve a cubic equation", IEEE CG&A 2006–07; Ferrari/Descartes through the resolvent
//!   cubic), every root polished by Newton's method on the original polynomial;
//! * [`laguerre_roots`]: all complex roots of any degree by Laguerre's method with
//!   deflation and polishing (Numerical Recipes §9.5, `laguer`/`zroots`) — the lecture's
//!   "sure-fire" method for implicit surfaces of degree ≥ 5;
//! * [`real_roots_in`]: the real roots in an interval by either solver ([`RootSolver`]),
//!   which is what ray–implicit-surface intersection needs.
//!
//! # Double roots
//!
//! A ray tangent to a surface gives a double root. In floating point it splits either
//! into two nearly equal real roots or into a complex-conjugate pair with a tiny
//! imaginary part (of the order of √ε relative: a perturbation δ of the coefficients
//! moves a double root by ~√δ). Every solver here therefore counts a complex root as real
//! when |im| ≤ [`REAL_IM_TOL`]·max(1, |re|), and reports a double root **twice**
//! (multiplicity kept, so a quartic reports at most four roots counted with multiplicity).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// Relative tolerance on the imaginary part below which a complex root is taken as real:
/// |im| ≤ `REAL_IM_TOL`·max(1, |re|).
///
/// A simple real root computed in f64 has an imaginary part near 1e-16 relative, a
/// double root (tangent ray) one of order √ε ≈ 1.5e-8 times the polynomial's scale; 1e-6
/// leaves a margin of ~60× for the latter. The price: a ray that misses a surface by
/// less than ~1e-12 relative (im² ~ distance) counts as grazing it, which no image
/// shows. Callers should scale the variable so that the roots of interest are O(1)
/// (the implicit surfaces measure t in units of their bounding box's diagonal).
pub const REAL_IM_TOL: f64 = 1e-6;

/// Leading coefficients with |c_n| ≤ `LEAD_TOL`·max|c_i| count as zero in the closed
/// forms. The dropped root has magnitude ≳ |c_{n−1}/c_n| ≥ 1e13 times the scale of the
/// other coefficients, and dividing by such a c_n would wreck the closed formulas.
const LEAD_TOL: f64 = 1e-13;

/// Whether a complex root `(re, im)` counts as real (see [`REAL_IM_TOL`]).
#[inline]
fn nearly_real(re: f64, im: f64) -> bool {
    im.abs() <= REAL_IM_TOL * re.abs().max(1.0)
}

// ---------------------------------------------------------------------------------------
// Evaluation
// ---------------------------------------------------------------------------------------

/// P(t) by Horner's rule (ascending coefficients); 0 for an empty slice.
#[inline]
pub fn eval_poly(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ci| acc * t + ci)
}

/// (P(t), P′(t)) by Horner's rule, the derivative accumulated alongside (Numerical
/// Recipes §5.1), without forming the derivative's coefficients.
#[inline]
pub fn eval_poly_deriv(c: &[f64], t: f64) -> (f64, f64) {
    let mut p = 0.0;
    let mut dp = 0.0;
    for &ci in c.iter().rev() {
        dp = dp * t + p;
        p = p * t + ci;
    }
    (p, dp)
}

/// Up to `steps` Newton steps on P from `t`; a step is kept only if it lowers |P| (so a
/// double root, where P′ → 0, or a bad start cannot make things worse).
fn newton_polish(c: &[f64], mut t: f64, steps: u32) -> f64 {
    let (mut p, mut dp) = eval_poly_deriv(c, t);
    for _ in 0..steps {
        if p == 0.0 || dp == 0.0 {
            break;
        }
        let t1 = t - p / dp;
        if !t1.is_finite() {
            break;
        }
        let (p1, dp1) = eval_poly_deriv(c, t1);
        if p1.abs() >= p.abs() {
            break;
        }
        (t, p, dp) = (t1, p1, dp1);
    }
    t
}

/// The coefficient slice without trailing (leading-power) exact zeros.
fn trim_zeros(c: &[f64]) -> &[f64] {
    let n = c.iter().rposition(|&x| x != 0.0).map_or(0, |i| i + 1);
    &c[..n]
}

/// The coefficient slice with leading coefficients that are negligible (see [`LEAD_TOL`])
/// dropped, for the closed forms.
fn trim_negligible(c: &[f64]) -> &[f64] {
    let mut c = trim_zeros(c);
    while c.len() > 1 {
        let n = c.len() - 1;
        let scale = c[..n].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if c[n].abs() > LEAD_TOL * scale {
            break;
        }
        c = trim_zeros(&c[..n]);
    }
    c
}

// ---------------------------------------------------------------------------------------
// Quadratics
// ---------------------------------------------------------------------------------------

/// Roots of a·t² + b·t + c by the textbook formula (−b ± √(b² − 4ac)) / 2a in f32,
/// ascending. Kept to show what goes wrong: when b² ≫ |4ac| the smaller root is the
/// difference of two nearly equal numbers and loses all its digits (Numerical Recipes
/// §5.6). `a == 0` solves b·t + c = 0 and returns (r, r); `None` for a negative
/// discriminant or when no root exists (a = b = 0).
pub fn quadratic_naive(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    if a == 0.0 {
        if b == 0.0 {
            return None;
        }
        let r = -c / b;
        return Some((r, r));
    }
    let disc = b * b - 4.0 * a * c;
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    let r1 = (-b - sq) / (2.0 * a);
    let r2 = (-b + sq) / (2.0 * a);
    Some((r1.min(r2), r1.max(r2)))
}

/// b² − 4ac with the error of the product 4ac recovered by a fused multiply-add (Kahan
/// 2004), so that nearly tangent cases keep their discriminant's sign and digits.
#[inline]
fn discriminant(a: f64, b: f64, c: f64) -> f64 {
    let w = 4.0 * a * c;
    let e = (-4.0 * a).mul_add(c, w); // exact: −(4ac − w)
    let f = b.mul_add(b, -w);
    f + e
}

/// Roots of a·t² + b·t + c in f64, ascending, without cancellation: with
/// q = −½(b + sign(b)·√(b² − 4ac)) the roots are q/a and c/q, neither a difference of
/// nearly equal numbers (Numerical Recipes §5.6; pbrt-v4 `Quadratic`). The discriminant
/// uses Kahan's FMA trick. `a == 0` solves the linear equation and returns (r, r);
/// `None` for a negative discriminant, a = b = 0, or non-finite input.
pub fn quadratic_f64(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return None;
    }
    if a == 0.0 {
        if b == 0.0 {
            return None;
        }
        let r = -c / b;
        return Some((r, r));
    }
    if b == 0.0 && c == 0.0 {
        return Some((0.0, 0.0));
    }
    let disc = discriminant(a, b, c);
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    let q = -0.5 * (b + sq.copysign(b));
    // q = 0 needs b = 0 and disc = 0, i.e. c = 0: handled above.
    let r1 = q / a;
    let r2 = c / q;
    Some((r1.min(r2), r1.max(r2)))
}

/// Roots of a·t² + b·t + c for f32 input, ascending, computed by [`quadratic_f64`]: the
/// discriminant needs the extra precision (in f32, b² − 4ac with b = 1e4, a = c = 1
/// rounds to b² and the naive small root becomes 0), and q/a, c/q avoid the cancellation
/// of the textbook formula (Numerical Recipes §5.6). Handles a = 0 (linear: (r, r)),
/// b = 0 and c = 0 without NaN.
pub fn quadratic_stable(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    quadratic_f64(a as f64, b as f64, c as f64).map(|(r1, r2)| (r1 as f32, r2 as f32))
}

/// Real roots of the monic t² + b·t + c; a complex pair that [`nearly_real`] accepts is a
/// double root at −b/2.
fn monic_quadratic_tol(b: f64, c: f64, out: &mut RealRoots) {
    match quadratic_f64(1.0, b, c) {
        Some((r1, r2)) => {
            out.push(r1);
            out.push(r2);
        }
        None => {
            let re = -0.5 * b;
            let im2 = c - re * re;
            if im2.is_finite() && nearly_real(re, im2.max(0.0).sqrt()) {
                out.push(re);
                out.push(re);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Cubic and quartic
// ---------------------------------------------------------------------------------------

/// Up to four real roots, ascending, as returned by [`cubic`] and [`quartic`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RealRoots {
    roots: [f64; 4],
    len: usize,
}

impl RealRoots {
    /// The roots, ascending.
    #[inline]
    pub fn as_slice(&self) -> &[f64] {
        &self.roots[..self.len]
    }

    /// How many roots (a double root counts twice).
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if there is no real root.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn push(&mut self, r: f64) {
        if self.len < 4 && r.is_finite() {
            self.roots[self.len] = r;
            self.len += 1;
        }
    }

    fn sort(&mut self) {
        self.roots[..self.len].sort_by(f64::total_cmp);
    }

    fn polish(&mut self, c: &[f64]) {
        for r in &mut self.roots[..self.len] {
            *r = newton_polish(c, *r, 2);
        }
        self.sort();
    }
}

/// Real roots of degree ≤ 2 (after trimming), for the fall-backs.
fn low_degree(c: &[f64], out: &mut RealRoots) {
    match c.len() {
        2 => out.push(-c[0] / c[1]),
        3 => {
            let a = c[2];
            monic_quadratic_tol(c[1] / a, c[0] / a, out);
        }
        _ => {}
    }
}

/// Real roots of the cubic `c[0] + c[1]·t + c[2]·t² + c[3]·t³`, ascending, each polished
/// by two Newton steps on the original polynomial.
///
/// Closed form after Numerical Recipes §5.6 (see also Blinn 2006–07): with the monic
/// t³ + A t² + B t + C, Q = (A² − 3B)/9 and R = (2A³ − 9AB + 27C)/54, one real root r₁
/// comes from the trigonometric formula when R² < Q³ (the largest in magnitude of its
/// three) and otherwise from Cardano's formula with the stable sign choice
/// A' = −sign(R)·∛(|R| + √(R² − Q³)), B' = Q/A' (a quotient, not a difference). The
/// closed forms lose digits near multiple roots and for roots much smaller than the
/// others (a root at 1e-6 beside one at 1e3), so only r₁ is taken from them: it is
/// polished by Newton's method and divided out, and the remaining quadratic
/// t² + (A + r₁)t − C/r₁ is solved stably. A complex pair with
/// |im| ≤ [`REAL_IM_TOL`]·max(1, |re|) counts as a real double root, which is reported
/// twice. A negligible leading coefficient (≤ 1e-13 of the others) falls back
/// to the quadratic; the zero polynomial has no (reported) roots.
pub fn cubic(c: [f64; 4]) -> RealRoots {
    let mut out = RealRoots::default();
    let t = trim_negligible(&c);
    if t.len() < 4 {
        low_degree(t, &mut out);
        out.polish(&c);
        return out;
    }
    let inv = 1.0 / c[3];
    let (a, b, cc) = (c[2] * inv, c[1] * inv, c[0] * inv);
    let q = (a * a - 3.0 * b) / 9.0;
    let r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * cc) / 54.0;
    let a3 = a / 3.0;
    let q3 = q * q * q;
    let r2 = r * r;
    // One real root by the closed form: the largest in magnitude of the three when all
    // are real (it is the best conditioned of the trigonometric formula's outputs).
    let r1 = if r2 < q3 {
        let sq = q.sqrt();
        let theta = (r / (sq * sq * sq)).clamp(-1.0, 1.0).acos();
        let m = -2.0 * sq;
        let tau = std::f64::consts::TAU;
        [theta, theta + tau, theta - tau]
            .map(|th| m * (th / 3.0).cos() - a3)
            .into_iter()
            .max_by(|x, y| x.abs().total_cmp(&y.abs()))
            .unwrap_or(0.0)
    } else {
        let big_a = -r.signum() * (r.abs() + (r2 - q3).sqrt()).cbrt();
        let big_b = if big_a != 0.0 { q / big_a } else { 0.0 };
        big_a + big_b - a3
    };
    let monic = [cc, b, a, 1.0];
    let r1 = newton_polish(&monic, r1, 4);
    out.push(r1);
    // Deflate: t³ + a t² + b t + c = (t − r₁)(t² + e t + f) with e = a + r₁ and
    // f = −c/r₁ (the product of the other two roots, accurate as r₁ is; b + e·r₁ would
    // cancel when r₁ is large), f = b when r₁ = 0.
    let e = a + r1;
    let f = if r1 != 0.0 { -cc / r1 } else { b };
    monic_quadratic_tol(e, f, &mut out);
    out.polish(&c);
    out
}

/// Real roots of the quartic `c[0] + … + c[4]·t⁴`, ascending, each polished by two Newton
/// steps on the original polynomial.
///
/// Ferrari/Descartes: the monic quartic is depressed by t = y − a/4 to
/// y⁴ + p y² + q y + r; with m ≥ 0 the largest root of the resolvent cubic
/// m³ + p m² + (p²/4 − r) m − q²/8 ([`cubic`]) and s = √(2m) it factors into
/// (y² − s y + e₁)(y² + s y + e₂) with e₁,₂ = p/2 + m ± q/(2s). Of e₁, e₂ the one
/// where the terms add is computed so, the other as r divided by it (e₁e₂ = r), which
/// avoids cancellation. That is 0/0 when m → 0 (q → 0, the biquadratic case); there e₁
/// and e₂ are instead the roots of z² − (p + 2m) z + r (their sum and product), e₁ the
/// larger when q ≥ 0 (because e₁ − e₂ = q/s) — which in turn would be ill-conditioned
/// for e₁ ≈ e₂, the tangent-to-a-torus case (y² − h²)², where m is large. Each quadratic
/// is solved stably; a complex pair that is real within [`REAL_IM_TOL`] counts as a
/// double root, reported twice. A negligible leading coefficient falls back to
/// [`cubic`].
pub fn quartic(c: [f64; 5]) -> RealRoots {
    let t = trim_negligible(&c);
    if t.len() < 5 {
        let mut c3 = [0.0; 4];
        c3[..t.len()].copy_from_slice(t);
        return cubic(c3);
    }
    let inv = 1.0 / c[4];
    let (a, b, cc, d) = (c[3] * inv, c[2] * inv, c[1] * inv, c[0] * inv);
    let a2 = a * a;
    let p = b - 0.375 * a2;
    let q = cc - 0.5 * a * b + 0.125 * a2 * a;
    let r = d - 0.25 * a * cc + a2 * b / 16.0 - 3.0 * a2 * a2 / 256.0;

    let resolvent = cubic([-0.125 * q * q, 0.25 * p * p - r, p, 1.0]);
    let m = resolvent.as_slice().last().copied().unwrap_or(0.0).max(0.0);
    let s = (2.0 * m).sqrt();
    // The scale of y² in the depressed quartic: m is computed to ~ε times it.
    let rho2 = p.abs().max(q.abs().powf(2.0 / 3.0)).max(r.abs().sqrt());
    let (e1, e2) = if m > 1e-4 * rho2 {
        // e₁,₂ = p/2 + m ± q/(2s): the sum without cancellation, the other as r/it.
        let base = 0.5 * p + m;
        let d = q / (2.0 * s);
        if (base >= 0.0) == (d >= 0.0) {
            let e1 = base + d;
            (e1, if e1 != 0.0 { r / e1 } else { base - d })
        } else {
            let e2 = base - d;
            (if e2 != 0.0 { r / e2 } else { base + d }, e2)
        }
    } else {
        // m ≈ 0 (q ≈ 0): e₁, e₂ as the roots of z² − (p + 2m) z + r.
        let (e_lo, e_hi) = quadratic_f64(1.0, -(p + 2.0 * m), r).unwrap_or_else(|| {
            let mid = 0.5 * (p + 2.0 * m);
            (mid, mid)
        });
        if q >= 0.0 { (e_hi, e_lo) } else { (e_lo, e_hi) }
    };

    let mut ys = RealRoots::default();
    monic_quadratic_tol(-s, e1, &mut ys);
    monic_quadratic_tol(s, e2, &mut ys);
    let mut out = RealRoots::default();
    for &y in ys.as_slice() {
        out.push(y - 0.25 * a);
    }
    out.polish(&c);
    out
}

// ---------------------------------------------------------------------------------------
// Complex numbers
// ---------------------------------------------------------------------------------------

/// A complex number in f64, just enough arithmetic for Laguerre's method.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex {
    /// 0.
    pub const ZERO: Self = Self { re: 0.0, im: 0.0 };
    /// 1.
    pub const ONE: Self = Self { re: 1.0, im: 0.0 };

    /// re + i·im.
    #[inline]
    pub const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }

    /// The real number x.
    #[inline]
    pub const fn real(x: f64) -> Self {
        Self { re: x, im: 0.0 }
    }

    /// |z|, without overflow for large parts (`hypot`).
    #[inline]
    pub fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }

    /// The complex conjugate.
    #[inline]
    pub fn conj(self) -> Self {
        Self { re: self.re, im: -self.im }
    }

    /// z·s for a real s.
    #[inline]
    pub fn scale(self, s: f64) -> Self {
        Self { re: self.re * s, im: self.im * s }
    }

    /// The principal square root (re ≥ 0), computed without cancellation or overflow as
    /// in Numerical Recipes §5.5 (`csqrt`).
    pub fn sqrt(self) -> Self {
        if self.re == 0.0 && self.im == 0.0 {
            return Self::ZERO;
        }
        let x = self.re.abs();
        let y = self.im.abs();
        let w = if x >= y {
            let r = y / x;
            x.sqrt() * (0.5 * (1.0 + (1.0 + r * r).sqrt())).sqrt()
        } else {
            let r = x / y;
            y.sqrt() * (0.5 * (r + (1.0 + r * r).sqrt())).sqrt()
        };
        if self.re >= 0.0 {
            Self { re: w, im: self.im / (2.0 * w) }
        } else {
            Self { re: y / (2.0 * w), im: if self.im >= 0.0 { w } else { -w } }
        }
    }

    /// True if both parts are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

impl Add for Complex {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self { re: self.re + o.re, im: self.im + o.im }
    }
}

impl Sub for Complex {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self { re: self.re - o.re, im: self.im - o.im }
    }
}

impl Mul for Complex {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self { re: self.re * o.re - self.im * o.im, im: self.re * o.im + self.im * o.re }
    }
}

impl Div for Complex {
    type Output = Self;
    /// Smith's algorithm (1962; Numerical Recipes §5.5): scales by the larger part of the
    /// divisor to avoid overflow.
    #[inline]
    fn div(self, o: Self) -> Self {
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let den = o.re + r * o.im;
            Self { re: (self.re + r * self.im) / den, im: (self.im - r * self.re) / den }
        } else {
            let r = o.re / o.im;
            let den = o.im + r * o.re;
            Self { re: (self.re * r + self.im) / den, im: (self.im * r - self.re) / den }
        }
    }
}

impl Neg for Complex {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self { re: -self.re, im: -self.im }
    }
}

// ---------------------------------------------------------------------------------------
// Laguerre
// ---------------------------------------------------------------------------------------

/// Settings of [`laguerre_roots`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LaguerreSettings {
    /// Iterations per root search before giving up (Numerical Recipes uses 80: 8 limit
    /// cycle breaks every 10 steps).
    pub max_iterations: u32,
    /// Polish every root found on the deflated polynomial by Laguerre on the original
    /// one, undoing the rounding errors deflation accumulates (Numerical Recipes §9.5).
    pub polish: bool,
}

impl Default for LaguerreSettings {
    fn default() -> Self {
        Self { max_iterations: 80, polish: true }
    }
}

/// The result of [`laguerre_roots`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LaguerreOutcome {
    /// All roots, with multiplicity (as many as the trimmed degree), sorted by real part
    /// then imaginary part.
    pub roots: Vec<Complex>,
    /// How many of them come from a search that hit the iteration limit (their value is
    /// the last iterate: usable, but not to full precision).
    pub not_converged: u32,
}

/// One root of the polynomial with complex coefficients `a` (ascending, degree ≥ 1) by
/// Laguerre's method from `x`: Numerical Recipes §9.5 `laguer`. Returns the root and
/// whether it converged, i.e. |P(x)| fell to the rounding-error bound of Horner's rule
/// (Adams's estimate, the "elegant stopping criterion" the lecture praises) or the step
/// no longer changed x beyond a few ulps. Every 10th step is a fractional one to break limit cycles.
fn laguer(a: &[Complex], mut x: Complex, max_iterations: u32) -> (Complex, bool) {
    const MT: u32 = 10;
    const FRAC: [f64; 8] = [0.5, 0.25, 0.75, 0.13, 0.38, 0.62, 0.88, 1.0];
    let m = a.len() - 1;
    let mf = m as f64;
    for iter in 1..=max_iterations {
        // P (b), P′ (d) and P″/2 (f) by Horner, with the rounding bound err.
        let mut b = a[m];
        let mut err = b.abs();
        let mut d = Complex::ZERO;
        let mut f = Complex::ZERO;
        let abx = x.abs();
        for j in (0..m).rev() {
            f = x * f + d;
            d = x * d + b;
            b = x * b + a[j];
            err = b.abs() + abx * err;
        }
        err *= f64::EPSILON;
        if b.abs() <= err {
            return (x, true);
        }
        // Laguerre's step a = n / (G ± √((n−1)(nH − G²))), sign maximising |denominator|.
        let g = d / b;
        let g2 = g * g;
        let h = g2 - (f / b).scale(2.0);
        let sq = ((h.scale(mf) - g2).scale(mf - 1.0)).sqrt();
        let gp = g + sq;
        let gm = g - sq;
        let (abp, abm) = (gp.abs(), gm.abs());
        let den = if abp < abm { gm } else { gp };
        let dx = if abp.max(abm) > 0.0 {
            Complex::real(mf) / den
        } else {
            // P′ = P″ = 0 here: step in a "random" direction (NR).
            let it = iter as f64;
            Complex::new(it.cos(), it.sin()).scale(1.0 + abx)
        };
        let x1 = x - dx;
        if !x1.is_finite() {
            return (x, false);
        }
        // Converged when the step no longer changes x beyond its last bits: NR tests
        // x₁ == x only, which a period-2 cycle between neighbouring floats defeats.
        if x1 == x || dx.abs() <= 4.0 * f64::EPSILON * x1.abs() {
            return (x1, true);
        }
        x = if iter % MT != 0 { x1 } else { x - dx.scale(FRAC[((iter / MT - 1) % 8) as usize]) };
    }
    (x, false)
}

/// All complex roots of the real polynomial `c` (ascending) by Laguerre's method with
/// deflation, every search starting at 0. See [`laguerre_roots_from`].
pub fn laguerre_roots(c: &[f64], settings: &LaguerreSettings) -> LaguerreOutcome {
    laguerre_roots_from(c, 0.0, settings)
}

/// All complex roots of the real polynomial `c` (ascending), every search starting from
/// the real value `start` — for ray tracing, the ray's entry into the surface's bounding
/// box (the lecture's "Startwert: Schnitt zwischen Strahl und BBox der Fläche").
///
/// Numerical Recipes §9.5 `zroots`: find a root of the deflated polynomial by
/// Laguerre's iteration (`laguer`) from `start`, snap it to the real axis if |im| ≤ 2ε|re|, divide it out
/// by synthetic division (the quotient keeps complex coefficients), repeat until the
/// degree is exhausted; then, if `settings.polish`, re-run Laguerre on the **original**
/// polynomial from each root, which removes the errors deflation accumulated (a polish
/// that does not converge keeps the deflated root). Since Laguerre tends to converge to
/// the root nearest its start, roots are found roughly in order of distance from
/// `start`, which is also the stable deflation order.
///
/// Trailing zero leading coefficients are trimmed; a constant or all-zero polynomial
/// has no roots. `not_converged` counts roots whose (final) search hit
/// `settings.max_iterations`.
pub fn laguerre_roots_from(c: &[f64], start: f64, settings: &LaguerreSettings) -> LaguerreOutcome {
    let c = trim_zeros(c);
    let mut out = LaguerreOutcome::default();
    if c.len() < 2 || c.iter().any(|x| !x.is_finite()) {
        return out;
    }
    let degree = c.len() - 1;
    let orig: Vec<Complex> = c.iter().map(|&x| Complex::real(x)).collect();
    let mut ad = orig.clone();
    let mut found: Vec<(Complex, bool)> = Vec::with_capacity(degree);
    let x0 = Complex::real(if start.is_finite() { start } else { 0.0 });
    for j in (1..=degree).rev() {
        let (mut x, ok) = laguer(&ad[..=j], x0, settings.max_iterations);
        if x.im.abs() <= 2.0 * f64::EPSILON * x.re.abs() {
            x.im = 0.0;
        }
        found.push((x, ok));
        // Synthetic division by (t − x): the quotient overwrites ad[0..j].
        let mut b = ad[j];
        for jj in (0..j).rev() {
            let cj = ad[jj];
            ad[jj] = b;
            b = x * b + cj;
        }
    }
    if settings.polish {
        for (x, ok) in &mut found {
            let (xp, okp) = laguer(&orig, *x, settings.max_iterations);
            if okp {
                *x = xp;
                *ok = true;
            }
        }
    }
    out.not_converged = found.iter().filter(|(_, ok)| !ok).count() as u32;
    out.roots = found.into_iter().map(|(x, _)| x).collect();
    out.roots.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
    out
}

// ---------------------------------------------------------------------------------------
// Real roots in an interval
// ---------------------------------------------------------------------------------------

/// Which root finder [`real_roots_in`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RootSolver {
    /// Closed forms for degree ≤ 4 (lecture: "Falls Grad < 5: nach t auflösen"); higher
    /// degrees fall back to Laguerre with polishing.
    ClosedForm,
    /// Laguerre's method with deflation for every degree.
    Laguerre {
        /// Polish the deflated roots on the original polynomial.
        polish: bool,
    },
}

/// What [`real_roots_in`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SolveReport {
    /// Roots (of all, not just those in the interval) whose Laguerre search hit the
    /// iteration limit.
    pub not_converged: u32,
    /// True if Laguerre's method ran: requested, or the closed-form solver's fall-back
    /// for degree > 4.
    pub used_laguerre: bool,
}

/// The real roots of `c` (ascending coefficients) in the closed interval [lo, hi],
/// ascending, written to `out` (cleared first). A double root appears twice.
///
/// [`RootSolver::ClosedForm`] uses [`quadratic_f64`], [`cubic`] or [`quartic`] for degree
/// ≤ 4 and falls back to Laguerre (with polishing, reported in `used_laguerre`) above.
/// [`RootSolver::Laguerre`] runs [`laguerre_roots_from`] starting from `lo` (or `hi`, or
/// 0, whichever is the first finite one) and keeps the roots with
/// |im| ≤ [`REAL_IM_TOL`]·max(1, |re|) — the tolerance that keeps tangent rays, whose
/// double root splits into a complex pair with an imaginary part of order √ε.
pub fn real_roots_in(c: &[f64], lo: f64, hi: f64, solver: RootSolver, out: &mut Vec<f64>) -> SolveReport {
    out.clear();
    let mut report = SolveReport::default();
    let c = trim_zeros(c);
    if c.len() < 2 || lo.is_nan() || hi.is_nan() || lo > hi {
        return report;
    }
    let polish = match solver {
        RootSolver::ClosedForm if c.len() <= 5 => {
            let mut rr = RealRoots::default();
            match c.len() {
                2 | 3 => low_degree(c, &mut rr),
                4 => rr = cubic([c[0], c[1], c[2], c[3]]),
                _ => rr = quartic([c[0], c[1], c[2], c[3], c[4]]),
            }
            if c.len() <= 3 {
                rr.polish(c);
            }
            out.extend(rr.as_slice().iter().copied().filter(|r| (lo..=hi).contains(r)));
            return report;
        }
        RootSolver::ClosedForm => true,
        RootSolver::Laguerre { polish } => polish,
    };
    report.used_laguerre = true;
    let start = [lo, hi, 0.0].into_iter().find(|x| x.is_finite()).unwrap_or(0.0);
    let settings = LaguerreSettings { polish, ..LaguerreSettings::default() };
    let lag = laguerre_roots_from(c, start, &settings);
    report.not_converged = lag.not_converged;
    out.extend(lag.roots.iter().filter(|z| nearly_real(z.re, z.im)).map(|z| z.re).filter(|r| (lo..=hi).contains(r)));
    out.sort_by(f64::total_cmp);
    report
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;
    use rng::Pcg32;

    /// Ascending coefficients of lead·Π(t − rᵢ).
    pub(crate) fn poly_from_roots(roots: &[f64], lead: f64) -> Vec<f64> {
        let mut c = vec![lead];
        for &r in roots {
            c = mul(&c, &[-r, 1.0]);
        }
        c
    }

    fn mul(a: &[f64], b: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; a.len() + b.len() - 1];
        for (i, x) in a.iter().enumerate() {
            for (j, y) in b.iter().enumerate() {
                out[i + j] += x * y;
            }
        }
        out
    }

    /// Multiplies by (t − z)(t − z̄) = t² − 2 Re z·t + |z|².
    fn times_pair(c: &[f64], z: Complex) -> Vec<f64> {
        mul(c, &[z.re * z.re + z.im * z.im, -2.0 * z.re, 1.0])
    }

    fn rel_err(x: f64, truth: f64) -> f64 {
        (x - truth).abs() / truth.abs().max(1e-300)
    }

    /// Greedy matching: for each expected root the nearest unused computed root; the
    /// largest distance relative to max(1, |expected|).
    fn match_roots(expected: &[Complex], got: &[Complex]) -> f64 {
        assert_eq!(expected.len(), got.len(), "root count: expected {expected:?}, got {got:?}");
        let mut used = vec![false; got.len()];
        let mut worst = 0.0f64;
        for e in expected {
            let (k, d) = got
                .iter()
                .enumerate()
                .filter(|(k, _)| !used[*k])
                .map(|(k, g)| (k, (*g - *e).abs()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            used[k] = true;
            worst = worst.max(d / e.abs().max(1.0));
        }
        worst
    }

    fn min_separation(roots: &[f64]) -> f64 {
        let mut s = roots.to_vec();
        s.sort_by(f64::total_cmp);
        s.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn quadratic_known_roots() {
        // (t − 2)(t + 3) = t² + t − 6, and scaled by −2.
        assert_eq!(quadratic_naive(1.0, 1.0, -6.0), Some((-3.0, 2.0)));
        assert_eq!(quadratic_stable(1.0, 1.0, -6.0), Some((-3.0, 2.0)));
        assert_eq!(quadratic_f64(-2.0, -2.0, 12.0), Some((-3.0, 2.0)));
        assert_eq!(quadratic_stable(-2.0, -2.0, 12.0), Some((-3.0, 2.0)));
        assert_eq!(quadratic_naive(1.0, 0.0, 1.0), None);
        assert_eq!(quadratic_stable(1.0, 0.0, 1.0), None);
        assert_eq!(quadratic_f64(1.0, 2.0, 5.0), None);
    }

    #[test]
    fn quadratic_degenerate_coefficients() {
        // a = 0: linear 2t − 4 = 0.
        assert_eq!(quadratic_naive(0.0, 2.0, -4.0), Some((2.0, 2.0)));
        assert_eq!(quadratic_stable(0.0, 2.0, -4.0), Some((2.0, 2.0)));
        assert_eq!(quadratic_f64(0.0, 2.0, -4.0), Some((2.0, 2.0)));
        // a = b = 0: no root (or every t); None.
        assert_eq!(quadratic_naive(0.0, 0.0, 1.0), None);
        assert_eq!(quadratic_stable(0.0, 0.0, 1.0), None);
        assert_eq!(quadratic_stable(0.0, 0.0, 0.0), None);
        // b = 0: ±√(−c/a).
        assert_eq!(quadratic_stable(1.0, 0.0, -4.0), Some((-2.0, 2.0)));
        assert_eq!(quadratic_f64(2.0, 0.0, -8.0), Some((-2.0, 2.0)));
        // c = 0: 0 and −b/a, sorted, no NaN.
        assert_eq!(quadratic_stable(1.0, 3.0, 0.0), Some((-3.0, 0.0)));
        assert_eq!(quadratic_stable(1.0, -3.0, 0.0), Some((0.0, 3.0)));
        // b = c = 0: the double root 0.
        assert_eq!(quadratic_stable(5.0, 0.0, 0.0), Some((0.0, 0.0)));
        assert_eq!(quadratic_f64(f64::NAN, 1.0, 1.0), None);
    }

    #[test]
    fn quadratic_discriminant_zero() {
        // (t − 3)² = t² − 6t + 9: a double root, reported twice.
        assert_eq!(quadratic_naive(1.0, -6.0, 9.0), Some((3.0, 3.0)));
        assert_eq!(quadratic_stable(1.0, -6.0, 9.0), Some((3.0, 3.0)));
        assert_eq!(quadratic_f64(4.0, 4.0, 1.0), Some((-0.5, -0.5)));
    }

    #[test]
    fn quadratic_catastrophic_cancellation() {
        // t² + 1e4·t + 1 = 0: roots −1.00000001e-4 and −9999.9999.
        let (a, b, c) = (1.0f32, 1e4f32, 1.0f32);
        let small_true = -2.0 / (1e4 + (1e8f64 - 4.0).sqrt()); // = 2c / (−b − √disc), exact enough
        let large_true = -(1e4 + (1e8f64 - 4.0).sqrt()) / 2.0;
        let (n_small, n_large) = (quadratic_naive(a, b, c).unwrap().1, quadratic_naive(a, b, c).unwrap().0);
        let (s_small, s_large) = (quadratic_stable(a, b, c).unwrap().1, quadratic_stable(a, b, c).unwrap().0);
        let naive_err = rel_err(n_small as f64, small_true);
        let stable_err = rel_err(s_small as f64, small_true);
        println!(
            "small root {small_true:e}: naive {n_small:e} (rel err {naive_err:e}), \
             stable {s_small:e} (rel err {stable_err:e})"
        );
        assert!(stable_err < 1e-6, "stable small root error {stable_err}");
        assert!(naive_err > 0.1, "naive small root should lose its digits, error {naive_err}");
        assert!(rel_err(s_large as f64, large_true) < 1e-6);
        assert!(rel_err(n_large as f64, large_true) < 1e-6, "the large root is fine either way");
        // In f64 the same happens at b = 1e9.
        let (s, _) = quadratic_f64(1.0, 1e9, 1.0).map(|(l, s)| (s, l)).unwrap();
        assert!(rel_err(s, -1e-9) < 1e-15, "{s:e}");
    }

    #[test]
    fn eval_poly_and_derivative() {
        // 1 − 2t + 3t²: P(2) = 9, P′(2) = −2 + 12 = 10.
        let c = [1.0, -2.0, 3.0];
        assert_eq!(eval_poly(&c, 2.0), 9.0);
        assert_eq!(eval_poly_deriv(&c, 2.0), (9.0, 10.0));
        assert_eq!(eval_poly(&[], 2.0), 0.0);
        assert_eq!(eval_poly_deriv(&[7.0], 2.0), (7.0, 0.0));
    }

    #[test]
    fn complex_arithmetic() {
        let z = Complex::new(3.0, 4.0);
        assert_eq!(z.abs(), 5.0);
        assert_eq!(Complex::real(-4.0).sqrt(), Complex::new(0.0, 2.0));
        let s = Complex::new(-3.0, -4.0).sqrt(); // ±(1 − 2i), principal has re ≥ 0
        assert!((s - Complex::new(1.0, -2.0)).abs() < 1e-15, "{s:?}");
        assert!((s * s - Complex::new(-3.0, -4.0)).abs() < 1e-14);
        let w = Complex::new(-1.5, 0.25);
        assert!(((z * w) / w - z).abs() < 1e-14);
        assert!(((z / w) * w - z).abs() < 1e-14);
        assert_eq!(z + w - w, z);
        assert_eq!(-z, Complex::new(-3.0, -4.0));
        assert_eq!(z.conj(), Complex::new(3.0, -4.0));
        // No overflow in |z| or √z for huge parts.
        let big = Complex::new(1e300, 1e300);
        assert!(big.abs().is_finite() && big.sqrt().is_finite());
    }

    #[test]
    fn cubic_random_polynomials_with_known_roots() {
        let mut rng = Pcg32::seed_from_u64(1);
        let mut worst = 0.0f64;
        let mut tested = 0;
        while tested < 500 {
            let roots: Vec<f64> = (0..3).map(|_| rng.range(-10.0, 10.0)).collect();
            if min_separation(&roots) < 0.1 {
                continue;
            }
            let lead = rng.range(0.1, 10.0) * if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
            let c = poly_from_roots(&roots, lead);
            let got = cubic([c[0], c[1], c[2], c[3]]);
            let mut want = roots.clone();
            want.sort_by(f64::total_cmp);
            assert_eq!(got.len(), 3, "roots {want:?} got {got:?}");
            for (g, w) in got.as_slice().iter().zip(&want) {
                worst = worst.max((g - w).abs() / w.abs().max(1.0));
            }
            tested += 1;
        }
        println!("cubic: worst relative root error over 500 polynomials {worst:e}");
        assert!(worst < 1e-9, "{worst}");
    }

    #[test]
    fn cubic_special_cases() {
        // One real root and a complex pair: (t − 1)(t² + 1).
        let r = cubic([-1.0, 1.0, -1.0, 1.0]);
        assert_eq!(r.len(), 1);
        assert!((r.as_slice()[0] - 1.0).abs() < 1e-14);
        // Double root (t − 1)²(t + 2) = t³ − 3t + 2: reported twice.
        let r = cubic([2.0, -3.0, 0.0, 1.0]);
        assert_eq!(r.len(), 3, "{r:?}");
        let s = r.as_slice();
        assert!((s[0] + 2.0).abs() < 1e-12 && (s[1] - 1.0).abs() < 1e-7 && (s[2] - 1.0).abs() < 1e-7, "{s:?}");
        // A double root from rounded coefficients: (t − 0.3)²(t − 2).
        let c = poly_from_roots(&[0.3, 0.3, 2.0], 1.0);
        let r = cubic([c[0], c[1], c[2], c[3]]);
        assert_eq!(r.len(), 3, "{r:?}");
        assert!((r.as_slice()[0] - 0.3).abs() < 1e-7 && (r.as_slice()[1] - 0.3).abs() < 1e-7, "{r:?}");
        // Triple root (t − 1)³.
        let r = cubic([-1.0, 3.0, -3.0, 1.0]);
        assert_eq!(r.len(), 3);
        assert!(r.as_slice().iter().all(|x| (x - 1.0).abs() < 1e-5), "{r:?}");
        // Degenerate leading coefficient: the quadratic t² + t − 6.
        let r = cubic([-6.0, 1.0, 1.0, 0.0]);
        assert_eq!(r.as_slice(), &[-3.0, 2.0]);
        let r = cubic([-6.0, 1.0, 1.0, 1e-20]);
        assert_eq!(r.len(), 2);
        assert!((r.as_slice()[0] + 3.0).abs() < 1e-12 && (r.as_slice()[1] - 2.0).abs() < 1e-12);
        // Linear and constant.
        assert_eq!(cubic([-6.0, 3.0, 0.0, 0.0]).as_slice(), &[2.0]);
        assert!(cubic([1.0, 0.0, 0.0, 0.0]).is_empty());
        assert!(cubic([0.0; 4]).is_empty());
        // A root at zero and a tiny root next to big ones.
        let c = poly_from_roots(&[0.0, 1e-6, 1e3], 1.0);
        let r = cubic([c[0], c[1], c[2], c[3]]);
        assert_eq!(r.len(), 3);
        assert!(r.as_slice()[0].abs() < 1e-18 && rel_err(r.as_slice()[1], 1e-6) < 1e-9, "{r:?}");
    }

    #[test]
    fn quartic_random_polynomials_with_known_roots() {
        let mut rng = Pcg32::seed_from_u64(2);
        let mut worst = 0.0f64;
        let mut tested = 0;
        while tested < 500 {
            let roots: Vec<f64> = (0..4).map(|_| rng.range(-10.0, 10.0)).collect();
            if min_separation(&roots) < 0.1 {
                continue;
            }
            let lead = rng.range(0.1, 10.0) * if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
            let c = poly_from_roots(&roots, lead);
            let got = quartic([c[0], c[1], c[2], c[3], c[4]]);
            let mut want = roots.clone();
            want.sort_by(f64::total_cmp);
            assert_eq!(got.len(), 4, "roots {want:?} got {got:?}");
            for (g, w) in got.as_slice().iter().zip(&want) {
                worst = worst.max((g - w).abs() / w.abs().max(1.0));
            }
            tested += 1;
        }
        println!("quartic: worst relative root error over 500 polynomials {worst:e}");
        assert!(worst < 1e-9, "{worst}");
    }

    #[test]
    fn quartic_special_cases() {
        // Two complex pairs: (t² + 1)(t² + 2t + 5) → no real root.
        let c = times_pair(&times_pair(&[1.0], Complex::new(0.0, 1.0)), Complex::new(-1.0, 2.0));
        assert!(quartic([c[0], c[1], c[2], c[3], c[4]]).is_empty());
        // One real pair, one complex pair: (t − 1)(t − 3)(t² + 1).
        let c = times_pair(&poly_from_roots(&[1.0, 3.0], 1.0), Complex::new(0.0, 1.0));
        let r = quartic([c[0], c[1], c[2], c[3], c[4]]);
        assert_eq!(r.len(), 2);
        assert!((r.as_slice()[0] - 1.0).abs() < 1e-13 && (r.as_slice()[1] - 3.0).abs() < 1e-13);
        // Biquadratic (q = 0): (t² − 1)(t² − 4).
        let r = quartic([4.0, 0.0, -5.0, 0.0, 1.0]);
        assert_eq!(r.len(), 4);
        for (g, w) in r.as_slice().iter().zip([-2.0, -1.0, 1.0, 2.0]) {
            assert!((g - w).abs() < 1e-14, "{r:?}");
        }
        // Two double roots (a ray tangent to a torus twice): (t − 1)²(t + 2)².
        let c = poly_from_roots(&[1.0, 1.0, -2.0, -2.0], 1.0);
        let r = quartic([c[0], c[1], c[2], c[3], c[4]]);
        assert_eq!(r.len(), 4, "{r:?}");
        for (g, w) in r.as_slice().iter().zip([-2.0, -2.0, 1.0, 1.0]) {
            assert!((g - w).abs() < 1e-7, "{r:?}");
        }
        // A double root with a complex pair: (t − 0.7)²(t² + 1), coefficients rounded.
        let c = times_pair(&poly_from_roots(&[0.7, 0.7], 1.0), Complex::new(0.0, 1.0));
        let r = quartic([c[0], c[1], c[2], c[3], c[4]]);
        assert_eq!(r.len(), 2, "{r:?}");
        assert!(r.as_slice().iter().all(|x| (x - 0.7).abs() < 1e-7), "{r:?}");
        // Degenerate leading coefficient falls back to the cubic.
        let r = quartic([2.0, -3.0, 0.0, 1.0, 0.0]);
        assert_eq!(r.len(), 3);
        assert!(quartic([0.0; 5]).is_empty());
    }

    #[test]
    fn laguerre_random_polynomials_with_known_roots() {
        let mut rng = Pcg32::seed_from_u64(3);
        let mut worst = 0.0f64;
        for degree in 2..=10usize {
            let mut done = 0;
            while done < 40 {
                // Some roots real, some complex pairs.
                let mut expected = Vec::new();
                let mut c = vec![rng.range(0.5, 2.0)];
                while expected.len() < degree {
                    if expected.len() + 2 <= degree && rng.next_f64() < 0.3 {
                        let z = Complex::new(rng.range(-5.0, 5.0), rng.range(0.2, 3.0));
                        c = times_pair(&c, z);
                        expected.extend([z, z.conj()]);
                    } else {
                        let r = rng.range(-5.0, 5.0);
                        c = mul(&c, &[-r, 1.0]);
                        expected.push(Complex::real(r));
                    }
                }
                let sep = expected
                    .iter()
                    .enumerate()
                    .flat_map(|(i, a)| expected[i + 1..].iter().map(move |b| (*a - *b).abs()))
                    .fold(f64::INFINITY, f64::min);
                if sep < 0.3 {
                    continue;
                }
                let out = laguerre_roots(&c, &LaguerreSettings::default());
                assert_eq!(out.not_converged, 0, "degree {degree}: {expected:?}");
                let err = match_roots(&expected, &out.roots);
                assert!(err < 1e-8, "degree {degree}: error {err:e}, expected {expected:?}, got {:?}", out.roots);
                worst = worst.max(err);
                done += 1;
            }
        }
        println!("laguerre degree 2..10: worst relative root error {worst:e}");
    }

    #[test]
    fn laguerre_complex_roots_and_deflation_count() {
        // (t² + 1)(t − 2) = t³ − 2t² + t − 2.
        let out = laguerre_roots(&[-2.0, 1.0, -2.0, 1.0], &LaguerreSettings::default());
        assert_eq!(out.roots.len(), 3);
        assert_eq!(out.not_converged, 0);
        let want = [Complex::new(0.0, -1.0), Complex::new(0.0, 1.0), Complex::real(2.0)];
        assert!(match_roots(&want, &out.roots) < 1e-14, "{:?}", out.roots);
        // Multiple roots keep the count: (t − 1)³(t + 1)² has 5 roots.
        let c = poly_from_roots(&[1.0, 1.0, 1.0, -1.0, -1.0], 1.0);
        let out = laguerre_roots(&c, &LaguerreSettings::default());
        assert_eq!(out.roots.len(), 5);
        assert_eq!(out.not_converged, 0);
        assert!(out.roots[..2].iter().all(|z| (*z - Complex::real(-1.0)).abs() < 1e-6), "{:?}", out.roots);
        assert!(out.roots[2..].iter().all(|z| (*z - Complex::real(1.0)).abs() < 1e-4), "{:?}", out.roots);
        // Zero roots: t³(t − 1).
        let out = laguerre_roots(&[0.0, 0.0, 0.0, -1.0, 1.0], &LaguerreSettings::default());
        assert_eq!(out.roots.len(), 4);
        assert_eq!(out.roots[..3], [Complex::ZERO; 3]);
        assert!((out.roots[3] - Complex::ONE).abs() < 1e-15);
    }

    #[test]
    fn laguerre_trims_leading_zeros_and_degenerate_input() {
        let out = laguerre_roots(&[1.0, 2.0, 0.0, 0.0], &LaguerreSettings::default());
        assert_eq!(out.roots, vec![Complex::real(-0.5)]);
        assert!(laguerre_roots(&[0.0, 0.0, 0.0], &LaguerreSettings::default()).roots.is_empty());
        assert!(laguerre_roots(&[5.0], &LaguerreSettings::default()).roots.is_empty());
        assert!(laguerre_roots(&[], &LaguerreSettings::default()).roots.is_empty());
        assert!(laguerre_roots(&[1.0, f64::NAN, 1.0], &LaguerreSettings::default()).roots.is_empty());
        // A start far from every root still converges.
        let c = poly_from_roots(&[1.0, 2.0, 3.0], 1.0);
        let out = laguerre_roots_from(&c, 1e6, &LaguerreSettings::default());
        assert_eq!(out.not_converged, 0);
        let want: Vec<_> = [1.0, 2.0, 3.0].map(Complex::real).to_vec();
        assert!(match_roots(&want, &out.roots) < 1e-13);
        // Too few iterations: counted.
        let c = poly_from_roots(&[1.0, 2.0, 3.0, 4.0, 5.0], 1.0);
        let out = laguerre_roots_from(&c, 1e9, &LaguerreSettings { max_iterations: 2, polish: false });
        assert!(out.not_converged > 0);
        assert_eq!(out.roots.len(), 5);
    }

    #[test]
    fn laguerre_wilkinson_degree_10() {
        let roots: Vec<f64> = (1..=10).map(f64::from).collect();
        let c = poly_from_roots(&roots, 1.0);
        for polish in [false, true] {
            let out = laguerre_roots(&c, &LaguerreSettings { polish, ..Default::default() });
            assert_eq!(out.not_converged, 0);
            let want: Vec<_> = roots.iter().map(|&r| Complex::real(r)).collect();
            let err = match_roots(&want, &out.roots);
            println!("Wilkinson 10, polish {polish}: worst relative error {err:e}");
            assert!(err < 1e-8, "{err:e} {:?}", out.roots);
            assert!(out.roots.iter().all(|z| z.im.abs() < 1e-8));
        }
    }

    #[test]
    fn laguerre_polishing_improves_clustered_roots() {
        // A cluster of four roots 0.01 apart beside larger ones. Started at 10, beyond all
        // roots, Laguerre finds the large roots first, and deflating by them (forward
        // deflation in decreasing magnitude, the unstable order, NR §9.5) spoils the
        // quotients from which the cluster is then found; polishing on the original
        // polynomial repairs that. (Started at 0 the order is stable and polishing has
        // nothing left to improve: the roots already meet its stopping criterion.)
        let roots = [0.5, 0.51, 0.52, 0.53, 3.0, -4.0, 5.0, 6.0];
        let c = poly_from_roots(&roots, 1.0);
        let want: Vec<_> = roots.iter().map(|&r| Complex::real(r)).collect();
        let err = |start, polish| {
            let out = laguerre_roots_from(&c, start, &LaguerreSettings { polish, ..Default::default() });
            assert_eq!(out.not_converged, 0);
            match_roots(&want, &out.roots)
        };
        let (raw, polished) = (err(10.0, false), err(10.0, true));
        println!(
            "clustered roots from 10: unpolished error {raw:e}, polished {polished:e}; from 0: {:e}, {:e}",
            err(0.0, false),
            err(0.0, true)
        );
        assert!(polished < raw, "polished {polished:e} unpolished {raw:e}");
        assert!(polished < 1e-9 && raw > 1e-8, "polished {polished:e} unpolished {raw:e}");
        assert!(err(0.0, true) < 1e-9);
    }

    #[test]
    fn real_roots_in_filters_and_solvers_agree() {
        // (t + 2)(t − 0.5)(t − 1)(t − 3) in [0, 2].
        let c = poly_from_roots(&[-2.0, 0.5, 1.0, 3.0], 1.0);
        let mut out = Vec::new();
        for solver in
            [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }, RootSolver::Laguerre { polish: false }]
        {
            let rep = real_roots_in(&c, 0.0, 2.0, solver, &mut out);
            assert_eq!(out.len(), 2, "{solver:?} {out:?}");
            assert!((out[0] - 0.5).abs() < 1e-12 && (out[1] - 1.0).abs() < 1e-12, "{out:?}");
            assert_eq!(rep.used_laguerre, solver != RootSolver::ClosedForm);
            assert_eq!(rep.not_converged, 0);
        }
        // Closed intervals: the end points count.
        real_roots_in(&c, 0.5, 1.0, RootSolver::ClosedForm, &mut out);
        assert_eq!(out, vec![0.5, 1.0]);
        // Empty and inverted intervals, constant polynomials.
        real_roots_in(&c, 1.5, 2.5, RootSolver::ClosedForm, &mut out);
        assert!(out.is_empty());
        real_roots_in(&c, 2.0, 0.0, RootSolver::ClosedForm, &mut out);
        assert!(out.is_empty());
        real_roots_in(&[3.0, 0.0], -1.0, 1.0, RootSolver::Laguerre { polish: true }, &mut out);
        assert!(out.is_empty());
        // Degree 5 with ClosedForm falls back to Laguerre.
        let c = poly_from_roots(&[-2.0, -1.0, 0.25, 1.0, 3.0], 2.0);
        let rep = real_roots_in(&c, -1.5, 10.0, RootSolver::ClosedForm, &mut out);
        assert!(rep.used_laguerre);
        assert_eq!(out.len(), 4);
        // Random degree ≤ 4 polynomials (real roots and complex pairs): both solvers agree.
        let mut rng = Pcg32::seed_from_u64(4);
        let (mut lag, mut cf) = (Vec::new(), Vec::new());
        for _ in 0..2000 {
            let degree = 1 + (rng.next_u64() % 4) as usize;
            let mut c = vec![rng.range(-3.0, 3.0)];
            let mut k = 0;
            while k < degree {
                if k + 2 <= degree && rng.next_f64() < 0.3 {
                    c = times_pair(&c, Complex::new(rng.range(-3.0, 3.0), rng.range(0.01, 2.0)));
                    k += 2;
                } else {
                    c = mul(&c, &[-rng.range(-3.0, 3.0), 1.0]);
                    k += 1;
                }
            }
            let rep = real_roots_in(&c, -1.0, 2.0, RootSolver::ClosedForm, &mut cf);
            assert!(!rep.used_laguerre);
            real_roots_in(&c, -1.0, 2.0, RootSolver::Laguerre { polish: true }, &mut lag);
            // Roots within 1e-9 of an end may fall either side; compare the rest.
            let inner =
                |v: &Vec<f64>| v.iter().copied().filter(|r| *r > -1.0 + 1e-9 && *r < 2.0 - 1e-9).collect::<Vec<_>>();
            let (a, b) = (inner(&cf), inner(&lag));
            assert_eq!(a.len(), b.len(), "{c:?}: closed form {cf:?}, laguerre {lag:?}");
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() < 1e-6 * x.abs().max(1.0), "{c:?}: {cf:?} vs {lag:?}");
            }
        }
    }

    #[test]
    fn tangent_double_root_is_reported_by_every_solver() {
        // (t − 0.3)²(t − 2)(t + 1): the coefficients are rounded, so the double root may
        // come out as a complex pair with a tiny imaginary part.
        let c = poly_from_roots(&[0.3, 0.3, 2.0, -1.0], 1.0);
        let mut out = Vec::new();
        for solver in
            [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }, RootSolver::Laguerre { polish: false }]
        {
            real_roots_in(&c, 0.0, 1.0, solver, &mut out);
            assert!(!out.is_empty(), "{solver:?}");
            assert!(out.iter().all(|r| (r - 0.3).abs() < 1e-7), "{solver:?} {out:?}");
        }
        // A genuinely complex pair well off the axis is not reported.
        let c = times_pair(&[1.0], Complex::new(0.3, 1e-3));
        for solver in [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }] {
            real_roots_in(&c, 0.0, 1.0, solver, &mut out);
            assert!(out.is_empty(), "{solver:?} {out:?}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn laguerre_recovers_random_real_roots(
            roots in proptest::collection::vec(-10.0f64..10.0, 2..=6),
            lead in 0.1f64..10.0,
        ) {
            let sep = min_separation(&roots);
            prop_assume!(sep > 1e-3);
            let c = poly_from_roots(&roots, lead);
            let out = laguerre_roots(&c, &LaguerreSettings::default());
            prop_assert_eq!(out.not_converged, 0);
            prop_assert_eq!(out.roots.len(), roots.len());
            let mut want = roots.clone();
            want.sort_by(f64::total_cmp);
            for &r in &want {
                // First-order error bound of a simple root: ε·Σ|cᵢ||r|ⁱ / |P′(r)|, with
                // |P′(r)| = lead·Π|r − rⱼ| (small when roots crowd), times a safety factor.
                let abs_eval: f64 = c.iter().enumerate().map(|(i, ci)| ci.abs() * r.abs().powi(i as i32)).sum();
                let dp: f64 = lead * want.iter().filter(|&&x| x != r).map(|x| (r - x).abs()).product::<f64>();
                let tol = 1e-12 * r.abs().max(1.0) + 1e3 * f64::EPSILON * abs_eval / dp;
                let best = out.roots.iter().map(|z| (*z - Complex::real(r)).abs()).fold(f64::INFINITY, f64::min);
                prop_assert!(best <= tol, "root {} off by {:e} > {:e}; got {:?}", r, best, tol, out.roots);
            }
        }
    }
}
