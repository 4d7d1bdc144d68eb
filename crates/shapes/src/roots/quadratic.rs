//! Quadratics: the textbook formula beside the cancellation-free one, and the monic
//! quadratic with the near-real tolerance that the cubic and quartic deflate to.

use super::{RealRoots, nearly_real};

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
pub(super) fn monic_quadratic_tol(b: f64, c: f64, out: &mut RealRoots) {
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

/// Real roots of degree ≤ 2 (after trimming), for the fall-backs.
pub(super) fn low_degree(c: &[f64], out: &mut RealRoots) {
    match c.len() {
        2 => out.push(-c[0] / c[1]),
        3 => {
            let a = c[2];
            monic_quadratic_tol(c[1] / a, c[0] / a, out);
        }
        _ => {}
    }
}
