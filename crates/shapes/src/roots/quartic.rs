//! The quartic in closed form (Ferrari/Descartes through the resolvent cubic), factored
//! into two quadratics without cancellation.

use super::eval::trim_negligible;
use super::quadratic::{monic_quadratic_tol, quadratic_f64};
use super::{RealRoots, cubic};

/// Real roots of the quartic `c[0] + … + c[4]·t⁴`, ascending, each polished by two Newton
/// steps on the original polynomial.
///
/// Ferrari/Descartes: the monic quartic is depressed by t = y − a/4 to
/// y⁴ + p y² + q y + r; with m ≥ 0 the largest root of the resolvent cubic
/// m³ + p m² + (p²/4 − r) m − q²/8 ([`cubic`](fn@cubic)) and s = √(2m) it factors into
/// (y² − s y + e₁)(y² + s y + e₂) with e₁,₂ = p/2 + m ± q/(2s). Of e₁, e₂ the one
/// where the terms add is computed so, the other as r divided by it (e₁e₂ = r), which
/// avoids cancellation. That is 0/0 when m → 0 (q → 0, the biquadratic case); there e₁
/// and e₂ are instead the roots of z² − (p + 2m) z + r (their sum and product), e₁ the
/// larger when q ≥ 0 (because e₁ − e₂ = q/s) — which in turn would be ill-conditioned
/// for e₁ ≈ e₂, the tangent-to-a-torus case (y² − h²)², where m is large. Each quadratic
/// is solved stably; a complex pair that is real within [`REAL_IM_TOL`](super::REAL_IM_TOL) counts as a
/// double root, reported twice. A negligible leading coefficient falls back to
/// [`cubic`](fn@cubic).
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
