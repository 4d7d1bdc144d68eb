//! The cubic in closed form: one root by the trigonometric or Cardano formula, polished
//! and divided out, the other two from the stable quadratic.

use super::RealRoots;
use super::eval::{newton_polish, trim_negligible};
use super::quadratic::{low_degree, monic_quadratic_tol};

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
/// |im| ≤ [`REAL_IM_TOL`](super::REAL_IM_TOL)·max(1, |re|) counts as a real double root, which is reported
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
