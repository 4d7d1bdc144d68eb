//! Real and complex roots of univariate polynomials.
//!
//! Coefficients are always in **ascending** order: `c[0] + c[1]·t + c[2]·t² + …`.
//!
//! * quadratics: the textbook formula ([`quadratic_naive`]) next to the cancellation-free
//!   one ([`quadratic_stable`], [`quadratic_f64`]; Press et al., *Numerical Recipes*, 3rd
//!   ed., §5.6; the discriminant as in Kahan, "On the cost of floating-point computation
//!   without extra-precise arithmetic", 2004);
//! * [`cubic`](fn@cubic) and [`quartic`](fn@quartic) in closed form (Numerical Recipes §5.6; Blinn, "How to
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
//!
//! One file per method: `quadratic`, `cubic`, `quartic` (closed forms), `laguerre` (with
//! the `complex` arithmetic it needs) and `interval` (the real roots in an interval by
//! either solver); `eval` holds Horner evaluation and the coefficient trimming they share.

mod complex;
mod cubic;
mod eval;
mod interval;
mod laguerre;
mod quadratic;
mod quartic;
#[cfg(test)]
mod tests;

pub use complex::Complex;
pub use cubic::cubic;
pub use eval::{eval_poly, eval_poly_deriv};
pub use interval::{RootSolver, SolveReport, real_roots_in};
pub use laguerre::{LaguerreOutcome, LaguerreSettings, laguerre_roots, laguerre_roots_from};
pub use quadratic::{quadratic_f64, quadratic_naive, quadratic_stable};
pub use quartic::quartic;

use eval::newton_polish;

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
pub const LEAD_TOL: f64 = 1e-13;

/// Whether a complex root `(re, im)` counts as real (see [`REAL_IM_TOL`]).
#[inline]
fn nearly_real(re: f64, im: f64) -> bool {
    im.abs() <= REAL_IM_TOL * re.abs().max(1.0)
}

/// Up to four real roots, ascending, as returned by [`cubic`](fn@cubic) and
/// [`quartic`](fn@quartic) (the closed forms' shared result: no allocation, a double root stored twice).
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
