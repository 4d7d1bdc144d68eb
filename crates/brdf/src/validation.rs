//! Tools that prove a BSDF correct, public so that authors of new models can run them on
//! theirs: the chi-square goodness-of-fit test of `sample` against `pdf` (as pbrt-v4's
//! and Mitsuba 3's BSDF tests do it), the pdf's integral, the directional albedo and
//! reciprocity.
//!
//! All of them work on a single-wavelength BSDF ([`Bsdf<1>`]) and are deterministic for
//! a seed.

use crate::{Bsdf, BsdfSample, ScatterFlags};
use glam::{DVec3, Vec2, Vec3};
use rng::Pcg32;
use spectral::SampledSpectrum;
use std::f64::consts::{PI, TAU};

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
    let mut rng = Pcg32::seed_from_u64(seed);
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
    let mut rng = Pcg32::seed_from_u64(seed);
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
    let mut rng = Pcg32::seed_from_u64(seed);
    mean_and_standard_error((0..samples).map(|_| {
        let uc = rng.next_f32();
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        match bsdf.sample(wo, uc, u) {
            Some(s) if s.pdf > 0.0 => (s.f[0] * s.wi.z.abs() / s.pdf) as f64,
            _ => 0.0,
        }
    }))
}

/// Worst relative asymmetry |f(a, b) − f(b, a)| / max(f) over `pairs` random direction
/// pairs in the upper hemisphere.
pub fn reciprocity_error(bsdf: &impl Bsdf<1>, pairs: usize, seed: u64) -> f32 {
    let mut rng = Pcg32::seed_from_u64(seed);
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

/// A direction at cosine `z` to the normal and azimuth `phi_deg` degrees from the tangent.
pub fn direction(z: f32, phi_deg: f32) -> Vec3 {
    let s = (1.0 - z * z).max(0.0).sqrt();
    let phi = phi_deg.to_radians();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// Zooms into a narrow lobe for the chi-square test: directions on the lobe's side of a
/// frame (s, t, c) around its centre c get their gnomonic coordinates (x/z, y/z) scaled by
/// (a_s, a_t); the other side is left alone. The map is a bijection of the sphere with
/// dω/dω' = z³ / (z'³ a_s a_t), so the zoomed BSDF's pdf is known exactly, and a θ×φ
/// histogram of the zoomed directions resolves a lobe far narrower than its cells.
pub struct Zoom<B> {
    inner: B,
    frame: [DVec3; 3],
    scale: (f64, f64),
}

impl<B: Bsdf<1>> Zoom<B> {
    /// Zooms around the mirror direction of `wo` (the frame's t axis is perpendicular to
    /// the plane of incidence, s lies in it).
    pub fn mirror(inner: B, wo: Vec3, a_s: f64, a_t: f64) -> Self {
        let c = DVec3::new(-wo.x as f64, -wo.y as f64, wo.z as f64).normalize();
        let t = if c.z.abs() < 0.999_999 { DVec3::Z.cross(c).normalize() } else { DVec3::Y };
        let s = t.cross(c);
        Self { inner, frame: [s, t, c], scale: (a_s, a_t) }
    }
    /// World direction → zoomed direction, and dω/dω' there.
    fn forward(&self, w: Vec3) -> (Vec3, f64) {
        let w = w.as_dvec3();
        let l = DVec3::new(w.dot(self.frame[0]), w.dot(self.frame[1]), w.dot(self.frame[2])).normalize();
        if l.z <= 0.0 {
            return (l.as_vec3(), 1.0);
        }
        let (x, y) = (self.scale.0 * l.x / l.z, self.scale.1 * l.y / l.z);
        let z2 = 1.0 / (1.0 + x * x + y * y).sqrt();
        (DVec3::new(x * z2, y * z2, z2).as_vec3(), l.z.powi(3) / (z2.powi(3) * self.scale.0 * self.scale.1))
    }
    /// Zoomed direction → world direction, and dω/dω' there.
    fn inverse(&self, w2: Vec3) -> (Vec3, f64) {
        let l2 = w2.as_dvec3().normalize();
        let l = if l2.z <= 0.0 {
            l2
        } else {
            let (x, y) = (l2.x / (l2.z * self.scale.0), l2.y / (l2.z * self.scale.1));
            let z = 1.0 / (1.0 + x * x + y * y).sqrt();
            DVec3::new(x * z, y * z, z)
        };
        let jac = if l2.z <= 0.0 { 1.0 } else { l.z.powi(3) / (l2.z.powi(3) * self.scale.0 * self.scale.1) };
        ((self.frame[0] * l.x + self.frame[1] * l.y + self.frame[2] * l.z).as_vec3(), jac)
    }
}

impl<B: Bsdf<1>> Bsdf<1> for Zoom<B> {
    fn flags(&self) -> ScatterFlags {
        self.inner.flags()
    }
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<1> {
        self.inner.eval(wo, self.inverse(wi).0)
    }
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (w, jac) = self.inverse(wi);
        (self.inner.pdf(wo, w) as f64 * jac) as f32
    }
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<1>> {
        let s = self.inner.sample(wo, uc, u)?;
        if s.flags.is_specular() {
            return Some(s);
        }
        let (wi, _) = self.forward(s.wi);
        // f and pdf are re-evaluated at the zoomed direction: for the narrowest lobes
        // (and f ∝ 1/cos θi near the horizon) they are ill-conditioned against the f32
        // round trip of the direction. `sample_agrees_with_eval_and_pdf` checks `sample`
        // against `eval` and `pdf` on the unzoomed BSDFs instead.
        Some(BsdfSample { wi, f: self.eval(wo, wi), pdf: self.pdf(wo, wi), ..s })
    }
}

impl Chi2Config {
    /// A 1°×1° grid with `quadrature`² points per cell, for lobes a few degrees wide.
    pub const fn fine(quadrature: usize) -> Self {
        Self { theta_bins: 180, phi_bins: 360, samples: 1_000_000, min_expected: 5.0, quadrature }
    }

    /// 0.5° in θ × 0.25° in φ, for a lobe a fraction of a degree wide that also meets the
    /// horizon (which stays a cell boundary).
    pub const FINER: Self =
        Self { theta_bins: 360, phi_bins: 1440, samples: 1_000_000, min_expected: 5.0, quadrature: 4 };
}

/// How a [`Chi2Case`] bins the sampled directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Chi2Grid {
    /// [`Chi2Config::default`].
    Default,
    /// [`Chi2Config::fine`] with this quadrature.
    Fine(usize),
    /// [`Chi2Config::FINER`].
    Finer,
    /// The default grid over a [`Zoom`] around the mirror direction by (a_s, a_t), with
    /// this quadrature.
    Zoom(f64, f64, usize),
}

/// One chi-square case: a BSDF, an incidence and a grid that resolves its lobes.
#[derive(Clone, Debug)]
pub struct Chi2Case<B> {
    /// What it is (printed, and named on failure).
    pub name: String,
    /// The BSDF.
    pub bsdf: B,
    /// ωo.
    pub wo: Vec3,
    /// The grid.
    pub grid: Chi2Grid,
}

impl<B: Bsdf<1> + Clone> Chi2Case<B> {
    /// [`chi2_test`] of the case on its grid.
    pub fn run(&self, seed: u64) -> Chi2Result {
        match self.grid {
            Chi2Grid::Default => chi2_test(&self.bsdf, self.wo, &Chi2Config::default(), seed),
            Chi2Grid::Fine(q) => chi2_test(&self.bsdf, self.wo, &Chi2Config::fine(q), seed),
            Chi2Grid::Finer => chi2_test(&self.bsdf, self.wo, &Chi2Config::FINER, seed),
            Chi2Grid::Zoom(a, b, q) => {
                let config = Chi2Config { quadrature: q, ..Chi2Config::default() };
                chi2_test(&Zoom::mirror(self.bsdf.clone(), self.wo, a, b), self.wo, &config, seed)
            }
        }
    }
}

/// Runs every `parts`-th case of `cases` starting at `part` (so that a long list can be
/// split over several tests) at α = 0.01 Šidák-corrected over all of `cases`, seeding case
/// `k` with `seed + k`; panics naming every failure. `label` prefixes the printed lines.
pub fn check_chi2_cases<B: Bsdf<1> + Clone>(label: &str, cases: &[Chi2Case<B>], part: usize, parts: usize, seed: u64) {
    let alpha = sidak(0.01, cases.len());
    let mut failed = Vec::new();
    for (k, case) in cases.iter().enumerate().filter(|(k, _)| k % parts == part) {
        let res = case.run(seed + k as u64);
        eprintln!("chi2 {label} | {:<45} | p = {:.4} (dof {})", case.name, res.p_value, res.dof);
        if !(res.p_value > alpha && res.inconsistent == 0) {
            failed.push(format!("{}: {res:?}", case.name));
        }
    }
    assert!(failed.is_empty(), "α = {alpha:.2e}: {failed:#?}");
}

/// [`sample_consistency`] of every case's BSDF and ωo (a zoomed case's sample is checked
/// unzoomed: [`Zoom`] re-evaluates f and pdf at its direction); panics on the first failure.
pub fn check_sample_consistency<B: Bsdf<1>>(cases: &[Chi2Case<B>]) {
    for (k, case) in cases.iter().enumerate() {
        if let Some(e) = sample_consistency(&case.bsdf, case.wo, 20_000, k as u64, 1e-5) {
            panic!("{}: {e}", case.name);
        }
    }
}

/// Directions where BSDF formulas divide by cosines or meet their poles: the normal from
/// both sides, the horizon, a hair above and below it, a denormal elevation, and two
/// ordinary directions.
pub fn special_directions() -> Vec<Vec3> {
    vec![
        Vec3::Z,
        -Vec3::Z,
        Vec3::X,
        Vec3::Y,
        Vec3::new(0.6, 0.8, 0.0),
        Vec3::new(1.0, 0.0, 1e-7).normalize(),
        Vec3::new(-1.0, 0.0, 1e-7).normalize(),
        Vec3::new(0.0, -1.0, -1e-7).normalize(),
        Vec3::new(1.0, 0.0, 1e-30),
        Vec3::new(0.3, 0.4, 0.866).normalize(),
        Vec3::new(-0.3, -0.4, 0.866).normalize(),
    ]
}

/// Panics unless `bsdf` gives finite, non-negative `eval` and `pdf` for (ωo, ωi), and a
/// sample at (`uc`, `u`), if any, has a unit direction and finite positive f and pdf.
pub fn assert_finite(bsdf: &impl Bsdf<1>, wo: Vec3, wi: Vec3, uc: f32, u: Vec2, what: &str) {
    let (f, p) = (bsdf.eval(wo, wi)[0], bsdf.pdf(wo, wi));
    assert!(f.is_finite() && f >= 0.0 && p.is_finite() && p >= 0.0, "{what}: wo={wo} wi={wi}: f={f} pdf={p}");
    if let Some(s) = bsdf.sample(wo, uc, u) {
        assert!(s.wi.is_finite() && (s.wi.length() - 1.0).abs() < 1e-3, "{what}: wo={wo} uc={uc} u={u}: {s:?}");
        assert!(
            s.f[0].is_finite() && s.f[0] >= 0.0 && s.pdf.is_finite() && s.pdf > 0.0,
            "{what}: wo={wo} uc={uc} u={u}: {s:?}"
        );
    }
}

/// [`assert_finite`] for every pair of [`special_directions`] with corner sample inputs,
/// then for `random` random direction pairs and inputs.
pub fn assert_finite_everywhere(bsdf: &impl Bsdf<1>, random: usize, rng: &mut Pcg32, what: &str) {
    let special = special_directions();
    let corners = [Vec2::ZERO, Vec2::splat(0.999_999_9), Vec2::new(0.0, 0.999_999_9), Vec2::new(0.5, 0.25)];
    for &wo in &special {
        for &wi in &special {
            for uc in [0.0, 0.5, 0.999_999_9] {
                for u in corners {
                    assert_finite(bsdf, wo, wi, uc, u, what);
                }
            }
        }
    }
    for _ in 0..random {
        let wo = crate::sampling::uniform_sphere(rng.next_2d());
        let wi = crate::sampling::uniform_sphere(rng.next_2d());
        assert_finite(bsdf, wo, wi, rng.next_f32(), rng.next_2d(), what);
    }
}

/// The mean of `weights` and its standard error.
pub fn mean_and_standard_error(weights: impl IntoIterator<Item = f64>) -> (f64, f64) {
    let (mut sum, mut sum2, mut n) = (0.0f64, 0.0f64, 0usize);
    for w in weights {
        sum += w;
        sum2 += w * w;
        n += 1;
    }
    let n = n as f64;
    let mean = sum / n;
    (mean, ((sum2 / n - mean * mean).max(0.0) / (n - 1.0).max(1.0)).sqrt())
}

/// `inner` with its pdf replaced by `pdf` — in `pdf` and in its samples — for the
/// deliberately broken variants that prove a chi-square test can fail (a forgotten
/// Jacobian, a wrong cosine, …).
pub struct WithPdf<B, F> {
    /// The BSDF whose sampling is kept.
    pub inner: B,
    /// The pdf claimed instead of `inner.pdf`.
    pub pdf: F,
}

impl<B: Bsdf<1>, F: Fn(&B, Vec3, Vec3) -> f32> Bsdf<1> for WithPdf<B, F> {
    fn flags(&self) -> ScatterFlags {
        self.inner.flags()
    }
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<1> {
        self.inner.eval(wo, wi)
    }
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        (self.pdf)(&self.inner, wo, wi)
    }
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<1>> {
        self.inner.sample(wo, uc, u).map(|s| BsdfSample { pdf: self.pdf(wo, s.wi), ..s })
    }
}

/// Test functions for a list of [`Chi2Case`]s: `sample_agrees_with_eval_and_pdf`
/// ([`check_sample_consistency`]) and one test per named part running every
/// `parts`-th case ([`check_chi2_cases`]), so that a long list runs in parallel:
///
/// ```ignore
/// brdf::chi2_tests!("schlick", cases(), seed 1000, parts [part_1, part_2, part_3]);
/// ```
#[macro_export]
macro_rules! chi2_tests {
    ($label:literal, $cases:expr, seed $seed:expr, parts [$($part:ident),+ $(,)?]) => {
        /// `sample` returns what `eval` and `pdf` give for its direction, for every
        /// chi-square case's BSDF and ωo.
        #[test]
        fn sample_agrees_with_eval_and_pdf() {
            $crate::validation::check_sample_consistency(&$cases);
        }

        $crate::chi2_tests!(@parts $label, $cases, $seed, [$($part),+], 0usize, [$($part),+]);
    };
    (@parts $label:literal, $cases:expr, $seed:expr, [$first:ident $(, $rest:ident)*], $index:expr, [$($all:ident),+]) => {
        /// Chi-square goodness of fit of `sample` against `pdf` for this part of the cases.
        #[test]
        fn $first() {
            let parts = [$(stringify!($all)),+].len();
            $crate::validation::check_chi2_cases($label, &$cases, $index, parts, $seed);
        }
        $crate::chi2_tests!(@parts $label, $cases, $seed, [$($rest),*], $index + 1usize, [$($all),+]);
    };
    (@parts $label:literal, $cases:expr, $seed:expr, [], $index:expr, [$($all:ident),+]) => {};
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
