//! Polynomial evaluation by Horner's rule, Newton polishing, and the trimming of
//! (negligible) leading coefficients that every solver starts with.

use super::LEAD_TOL;

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
pub(super) fn newton_polish(c: &[f64], mut t: f64, steps: u32) -> f64 {
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
pub(super) fn trim_zeros(c: &[f64]) -> &[f64] {
    let n = c.iter().rposition(|&x| x != 0.0).map_or(0, |i| i + 1);
    &c[..n]
}

/// The coefficient slice with leading coefficients that are negligible (see [`LEAD_TOL`])
/// dropped, for the closed forms.
pub(super) fn trim_negligible(c: &[f64]) -> &[f64] {
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
