//! Tools that prove a BSDF correct, public so that authors of new models can run them on
//! theirs: the chi-square goodness-of-fit test of `sample` against `pdf` (as pbrt-v4's
//! and Mitsuba 3's BSDF tests do it), the pdf's integral, the directional albedo and
//! reciprocity.
//!
//! All of them work on a single-wavelength BSDF ([`Bsdf<1>`]) and are deterministic for
//! a seed.

use crate::{Bsdf, ScatterFlags};
use glam::{Vec2, Vec3};
use std::f64::consts::{PI, TAU};

/// A small deterministic generator (PCG32) for the tests' random numbers.
#[derive(Clone, Debug)]
pub struct TestRng(u64);

impl TestRng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        let mut r = Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03);
        r.next_u32();
        r
    }

    /// 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        x.rotate_right((old >> 59) as u32)
    }

    /// A float in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// Settings of [`chi2_test`].
#[derive(Clone, Copy, Debug)]
pub struct Chi2Config {
    /// Cells in θ over [0, π].
    pub theta_bins: usize,
    /// Cells in φ over [0, 2π).
    pub phi_bins: usize,
    /// Samples drawn.
    pub samples: usize,
    /// Cells expecting fewer samples are pooled into one.
    pub min_expected: f64,
    /// Quadrature points per cell side when integrating the pdf.
    pub quadrature: usize,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Self { theta_bins: 40, phi_bins: 80, samples: 1_000_000, min_expected: 5.0, quadrature: 6 }
    }
}

/// Outcome of [`chi2_test`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chi2Result {
    /// Pearson's statistic.
    pub statistic: f64,
    /// Degrees of freedom (cells after pooling, minus one).
    pub dof: usize,
    /// P(χ² ≥ statistic) under the hypothesis that samples follow the pdf.
    pub p_value: f64,
    /// Samples whose returned pdf or value disagreed with `pdf()` / `eval()`.
    pub inconsistent: usize,
}

/// Chi-square test of `sample` against `pdf` for outgoing direction `wo`: a θ×φ histogram
/// of the non-delta samples against expected counts from the pdf integrated over each
/// cell (midpoint rule in cos θ and φ, exact in solid angle). Delta (specular) samples
/// are left out; `pdf()` must then include the probability of choosing a non-delta lobe.
pub fn chi2_test(bsdf: &impl Bsdf<1>, wo: Vec3, config: &Chi2Config, seed: u64) -> Chi2Result {
    let (nt, np) = (config.theta_bins, config.phi_bins);
    let cell = |w: Vec3| {
        let theta = (w.z.clamp(-1.0, 1.0) as f64).acos();
        let phi = (w.y as f64).atan2(w.x as f64).rem_euclid(TAU);
        let i = ((theta / PI) * nt as f64) as usize;
        let j = ((phi / TAU) * np as f64) as usize;
        i.min(nt - 1) * np + j.min(np - 1)
    };
    let mut observed = vec![0.0f64; nt * np];
    let mut rng = TestRng::new(seed);
    let mut inconsistent = 0;
    for _ in 0..config.samples {
        let uc = rng.next_f32();
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let Some(s) = bsdf.sample(wo, uc, u) else { continue };
        if s.flags.contains(ScatterFlags::SPECULAR) || s.pdf <= 0.0 {
            continue;
        }
        let (p, f) = (bsdf.pdf(wo, s.wi), bsdf.eval(wo, s.wi)[0]);
        if (s.pdf - p).abs() > 1e-3 * p.max(1e-3) || (s.f[0] - f).abs() > 1e-3 * f.abs().max(1e-3) {
            inconsistent += 1;
        }
        observed[cell(s.wi)] += 1.0;
    }
    let mut expected = vec![0.0f64; nt * np];
    let q = config.quadrature;
    for i in 0..nt {
        let (c0, c1) = ((i as f64 * PI / nt as f64).cos(), ((i + 1) as f64 * PI / nt as f64).cos());
        for j in 0..np {
            let (p0, p1) = (j as f64 * TAU / np as f64, (j + 1) as f64 * TAU / np as f64);
            let mut sum = 0.0;
            for a in 0..q {
                let z = c0 + (c1 - c0) * (a as f64 + 0.5) / q as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                for b in 0..q {
                    let phi = p0 + (p1 - p0) * (b as f64 + 0.5) / q as f64;
                    let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                    sum += bsdf.pdf(wo, w) as f64;
                }
            }
            expected[i * np + j] = sum / (q * q) as f64 * (c0 - c1) * (p1 - p0) * config.samples as f64;
        }
    }
    let (mut stat, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < config.min_expected {
            pool_o += o;
            pool_e += e;
        } else {
            stat += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pool_e >= config.min_expected {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1;
    } else if pool_o > 10.0 * config.min_expected {
        // Many samples where the pdf says almost none: a failure by itself.
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(1e-3);
        dof += 1;
    }
    let dof = dof.saturating_sub(1).max(1);
    Chi2Result { statistic: stat, dof, p_value: chi2_survival(stat, dof as f64), inconsistent }
}

/// Checks that `sample` returns exactly what `eval` and `pdf` give for its direction
/// (relative tolerance `tol`), over `samples` non-delta samples; the first mismatch, if any.
pub fn sample_consistency(bsdf: &impl Bsdf<1>, wo: Vec3, samples: usize, seed: u64, tol: f32) -> Option<String> {
    let mut rng = TestRng::new(seed);
    for _ in 0..samples {
        let (uc, u) = (rng.next_f32(), Vec2::new(rng.next_f32(), rng.next_f32()));
        let Some(s) = bsdf.sample(wo, uc, u) else { continue };
        if s.flags.is_specular() {
            continue;
        }
        let (f, p) = (bsdf.eval(wo, s.wi)[0], bsdf.pdf(wo, s.wi));
        if (s.f[0] - f).abs() > tol * f || (s.pdf - p).abs() > tol * p {
            return Some(format!("sample {s:?} but eval {f}, pdf {p}"));
        }
    }
    None
}

/// P(χ²_k ≥ x): the regularised upper incomplete gamma function Q(k/2, x/2), by its
/// series or continued fraction (Numerical Recipes §6.2).
pub fn chi2_survival(x: f64, k: f64) -> f64 {
    let (a, x) = (0.5 * k, 0.5 * x);
    if x <= 0.0 {
        return 1.0;
    }
    let ln_gamma_a = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut del, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - ln_gamma_a).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - ln_gamma_a).exp() * h
    }
}

/// ln Γ(x) for x > 0 (Lanczos approximation, g = 7, n = 9).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (TAU).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The per-test significance that keeps the family-wise level at `alpha` over `tests`
/// independent tests (Šidák correction).
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests.max(1) as f64)
}

/// Complementary error function: erf's Maclaurin series below 2, Lentz's continued
/// fraction above (relative error < 1e-10 over the range the z-tests use).
pub fn erfc(x: f64) -> f64 {
    if x < 0.0 {
        return 2.0 - erfc(-x);
    }
    let sqrt_pi = std::f64::consts::PI.sqrt();
    if x < 2.0 {
        let (mut sum, mut term, x2) = (x, x, x * x);
        for n in 1..200 {
            term *= -x2 / n as f64;
            let add = term / (2 * n + 1) as f64;
            sum += add;
            if add.abs() < 1e-17 {
                break;
            }
        }
        1.0 - 2.0 / sqrt_pi * sum
    } else {
        let (mut f, mut c, mut d) = (x, x, 0.0);
        for n in 1..300 {
            let a = n as f64 / 2.0;
            d = 1.0 / (x + a * d);
            c = x + a / c;
            let delta = c * d;
            f *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (-x * x).exp() / (f * sqrt_pi)
    }
}

/// Two-sided normal quantile: the |z| exceeded with probability `p`, by bisection on
/// [`erfc`] (accurate to ~1e-6, plenty for thresholds).
pub fn z_threshold(p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if erfc(mid / std::f64::consts::SQRT_2) > p { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// The |z| threshold for `tests` two-sided z-tests at family-wise level `alpha` (Šidák).
pub fn sidak_z(alpha: f64, tests: usize) -> f64 {
    z_threshold(sidak(alpha, tests))
}

/// ∫ pdf(ωo, ω) dω over the sphere, by a stratified (cos θ, φ) grid of `n`² points.
pub fn pdf_integral(bsdf: &impl Bsdf<1>, wo: Vec3, n: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        for j in 0..n {
            let phi = TAU * (j as f64 + 0.5) / n as f64;
            sum += bsdf.pdf(wo, Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)) as f64;
        }
    }
    sum * 4.0 * PI / (n * n) as f64
}

/// Directional albedo ∫ f·|cos θi| dωi by importance sampling (delta lobes included):
/// (mean, standard error) over `samples` samples.
pub fn directional_albedo(bsdf: &impl Bsdf<1>, wo: Vec3, samples: usize, seed: u64) -> (f64, f64) {
    let mut rng = TestRng::new(seed);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..samples {
        let uc = rng.next_f32();
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let w = match bsdf.sample(wo, uc, u) {
            Some(s) if s.pdf > 0.0 => (s.f[0] * s.wi.z.abs() / s.pdf) as f64,
            _ => 0.0,
        };
        sum += w;
        sum2 += w * w;
    }
    let n = samples as f64;
    let mean = sum / n;
    (mean, ((sum2 / n - mean * mean).max(0.0) / (n - 1.0)).sqrt())
}

/// Worst relative asymmetry |f(a, b) − f(b, a)| / max(f) over `pairs` random direction
/// pairs in the upper hemisphere.
pub fn reciprocity_error(bsdf: &impl Bsdf<1>, pairs: usize, seed: u64) -> f32 {
    let mut rng = TestRng::new(seed);
    let mut hemi = || {
        let z = rng.next_f32().max(1e-3);
        let r = (1.0 - z * z).sqrt();
        let phi = std::f32::consts::TAU * rng.next_f32();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    let mut worst = 0.0f32;
    for _ in 0..pairs {
        let (a, b) = (hemi(), hemi());
        let (fab, fba) = (bsdf.eval(a, b)[0], bsdf.eval(b, a)[0]);
        let m = fab.abs().max(fba.abs());
        if m > 0.0 {
            worst = worst.max((fab - fba).abs() / m);
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_survival_matches_tables() {
        // Standard table values: P(χ²_10 ≥ 23.209) = 0.01, P(χ²_1 ≥ 3.841) = 0.05,
        // P(χ²_100 ≥ 135.807) = 0.01.
        assert!((chi2_survival(23.209, 10.0) - 0.01).abs() < 1e-4);
        assert!((chi2_survival(3.841, 1.0) - 0.05).abs() < 1e-4);
        assert!((chi2_survival(135.807, 100.0) - 0.01).abs() < 1e-4);
        assert!((chi2_survival(0.0, 5.0) - 1.0).abs() < 1e-12);
    }
}
