//! The real roots of a polynomial in an interval, by the closed forms or by Laguerre's
//! method: what ray–implicit-surface intersection calls.

use super::eval::trim_zeros;
use super::quadratic::low_degree;
use super::{LaguerreSettings, RealRoots, cubic, laguerre_roots_from, nearly_real, quartic};

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
/// [`RootSolver::ClosedForm`] uses [`quadratic_f64`](super::quadratic_f64), [`cubic`](fn@cubic) or
/// [`quartic`](fn@quartic) for degree
/// ≤ 4 and falls back to Laguerre (with polishing, reported in `used_laguerre`) above.
/// [`RootSolver::Laguerre`] runs [`laguerre_roots_from`] starting from `lo` (or `hi`, or
/// 0, whichever is the first finite one) and keeps the roots with
/// |im| ≤ [`REAL_IM_TOL`](super::REAL_IM_TOL)·max(1, |re|) — the tolerance that keeps tangent rays, whose
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
