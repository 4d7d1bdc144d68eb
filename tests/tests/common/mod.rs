//! Statistics shared by the whole-system tests.
#![allow(dead_code)]

use tracer::film::Film;

/// Two-sided normal quantile for a tail probability `p` (|z| exceeded with prob. p),
/// by bisection on erfc — accurate to ~1e-6, plenty for thresholds.
pub fn z_threshold(p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if erfc(mid / std::f64::consts::SQRT_2) > p { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// Complementary error function (W. J. Cody's rational approximations via libm-free
/// continued fraction for large x, series for small x); |rel. error| < 1e-10 here.
pub fn erfc(x: f64) -> f64 {
    if x < 0.0 {
        return 2.0 - erfc(-x);
    }
    if x < 2.0 {
        // erf by its Maclaurin series.
        let mut sum = x;
        let mut term = x;
        let x2 = x * x;
        for n in 1..200 {
            term *= -x2 / n as f64;
            let add = term / (2 * n + 1) as f64;
            sum += add;
            if add.abs() < 1e-17 {
                break;
            }
        }
        1.0 - 2.0 / std::f64::consts::PI.sqrt() * sum
    } else {
        // Lentz's continued fraction.
        let mut f = x;
        let mut c = x;
        let mut d = 0.0;
        for n in 1..300 {
            let a = n as f64 / 2.0;
            d = x + a * d;
            d = 1.0 / d;
            c = x + a / c;
            let delta = c * d;
            f *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (-x * x).exp() / (f * std::f64::consts::PI.sqrt())
    }
}

/// The threshold for per-pixel-channel z-tests at family-wise level `alpha` over `tests`
/// comparisons (Šidák correction).
pub fn sidak_z(alpha: f64, tests: usize) -> f64 {
    let per_test = 1.0 - (1.0 - alpha).powf(1.0 / tests as f64);
    z_threshold(per_test)
}

/// Result of comparing an image against expected values.
#[derive(Debug)]
pub struct Comparison {
    /// Fraction of pixel-channels with |z| below the threshold.
    pub pass_fraction: f64,
    /// The threshold used.
    pub z_max: f64,
    /// Worst |z|.
    pub worst: f64,
}

/// Per pixel-channel z = (a − b)/√(se_a² + se_b²), Šidák-corrected at α = 0.01.
pub fn z_test(a: &[f32], se_a: &[f32], b: &[f32], se_b: &[f32]) -> Comparison {
    assert_eq!(a.len(), b.len());
    let z_max = sidak_z(0.01, a.len());
    let mut pass = 0usize;
    let mut worst = 0.0f64;
    for i in 0..a.len() {
        let se = ((se_a[i] as f64).powi(2) + (se_b[i] as f64).powi(2)).sqrt();
        let d = (a[i] - b[i]) as f64;
        let z = if se > 0.0 {
            d.abs() / se
        } else if d.abs() < 1e-6 {
            0.0
        } else {
            f64::INFINITY
        };
        worst = worst.max(z);
        if z <= z_max {
            pass += 1;
        }
    }
    Comparison { pass_fraction: pass as f64 / a.len() as f64, z_max, worst }
}

/// Image-wide mean of a film channel and its standard error (pixels are independent).
pub fn channel_mean_and_se(film: &Film, c: usize) -> (f64, f64) {
    let n = film.pixels().len() as f64;
    let mean = film.pixels().iter().map(|p| p.mean[c]).sum::<f64>() / n;
    let var = film.pixels().iter().map(|p| p.std_error()[c].powi(2)).sum::<f64>();
    (mean, var.sqrt() / n)
}

#[test]
fn quantiles_are_right() {
    assert!((z_threshold(0.05) - 1.959964).abs() < 1e-4);
    assert!((z_threshold(0.01) - 2.575829).abs() < 1e-4);
    assert!((erfc(3.0) - 2.209049699858544e-5).abs() < 1e-12);
}
