//! Laguerre's method with deflation and polishing (Numerical Recipes §9.5, `laguer` and
//! `zroots`): all complex roots of a real polynomial of any degree.

use super::Complex;
use super::eval::trim_zeros;

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
