//! Analytic whole-renderer tests: a closed room whose walls are Lambertian with albedo ρ
//! and emit Le everywhere has radiance Le / (1 − ρ) at every point and in every
//! direction (the Neumann series Le·Σρᵏ). The render must match within its own
//! confidence interval, in every spectral mode.

use crate::common;

use common::{channel_mean_and_se, sidak_z};
use spectral::{SampledSpectrum, SampledWavelengths, SpectralMode};
use tracer::integrator::PathSettings;
use tracer::sampler::SamplerKind;
use tracer::{CpuBackend, CpuScene, RenderSettings, SceneOptions};

fn glowing_room(albedo: f32, le: f32) -> CpuScene {
    let scene = common::room::glowing_room(albedo, le);
    CpuBackend::new(2).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap()
}

/// The colour a constant spectrum of 1 has in each mode (E is not sRGB white; the
/// 40 fixed bins have their own Riemann-sum weights).
fn unit_colour(mode: SpectralMode) -> [f64; 3] {
    match mode {
        SpectralMode::Rgb => [1.0; 3],
        SpectralMode::Hero => spectral::colour::spectrum_to_linear_srgb(|_| 1.0).map(|v| v as f64),
        SpectralMode::Bins40 => {
            SampledWavelengths::<40>::fixed_bins(380.0, 10.0).to_linear_srgb(&SampledSpectrum::one()).map(|v| v as f64)
        }
    }
}

fn check_room(albedo: f32, mode: SpectralMode, sampler: SamplerKind, spp: u32) {
    check_room_with(albedo, mode, sampler, spp, PathSettings::default().rr_scale);
}

/// [`check_room`] with Russian roulette's scale `rr_scale`; returns the image's mean
/// per-pixel standard error (green) and the rays traced.
fn check_room_with(albedo: f32, mode: SpectralMode, sampler: SamplerKind, spp: u32, rr_scale: f32) -> (f64, u64) {
    let le = 0.5f32;
    let prepared = glowing_room(albedo, le);
    let settings = RenderSettings {
        width: 12,
        height: 12,
        spp,
        seed: 11,
        mode,
        sampler,
        path: PathSettings { max_depth: 0, rr_depth: 3, rr_scale, ..Default::default() },
        camera: None,
        crop: None,
    };
    let (film, stats) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
    assert_eq!(stats.non_finite, 0);
    let expected = unit_colour(mode).map(|c| c * (le / (1.0 - albedo)) as f64);
    // Image means against the analytic value, at a 4.5σ bound on the mean's own error.
    for c in 0..3 {
        let (mean, se) = channel_mean_and_se(&film, c);
        let z = (mean - expected[c]) / se;
        assert!(z.abs() < 4.5, "ρ={albedo} {mode:?} channel {c}: mean {mean} vs {} (se {se}, z {z})", expected[c]);
        // And not merely within noise: within 1 % as well.
        assert!((mean / expected[c] - 1.0).abs() < 0.01, "ρ={albedo} {mode:?} channel {c}: {mean} vs {}", expected[c]);
    }
    // Every pixel-channel, Šidák-corrected at α = 0.01. Russian roulette makes the
    // per-sample distribution right-skewed (p50 ≈ 0.91, p99 ≈ 2.4 for a mean of 1 at
    // ρ = 0.5), so per-pixel means need a few hundred samples before the normal
    // approximation behind the z-test holds; at 64 spp ~3 % of pixels fail low.
    let z_max = sidak_z(0.01, film.pixels().len() * 3);
    let mut fails = 0;
    for p in film.pixels() {
        for c in 0..3 {
            let z = (p.mean()[c] - expected[c]) / p.std_error()[c].max(1e-12);
            if z.abs() > z_max {
                fails += 1;
            }
        }
    }
    assert!(fails as f64 <= 0.01 * (film.pixels().len() * 3) as f64, "{mode:?}: {fails} pixel-channels fail");
    let se = film.pixels().iter().map(|p| p.std_error()[1]).sum::<f64>() / film.pixels().len() as f64;
    (se, stats.rays)
}

#[test]
fn closed_room_albedo_half() {
    for mode in SpectralMode::ALL {
        check_room(0.5, mode, SamplerKind::Independent, 512);
    }
}

/// The analytic answer with Owen-scrambled Sobol samples (unbiased like independent ones).
#[test]
fn closed_room_with_the_zsobol_sampler() {
    for mode in [SpectralMode::Rgb, SpectralMode::Hero] {
        check_room(0.5, mode, SamplerKind::ZSobol, 512);
    }
}

/// Russian roulette that keeps more paths (`PathSettings::rr_scale`) still converges to
/// the closed form, and in this closed room, where a path's light does not fade with its
/// throughput, it buys a lower error per sample with longer paths: at ρ = 0.8 the rule
/// of scale 1 cuts a path from bounce 3 with probability 1 − 0.8ᵏ, scale 4 only 5 % of
/// the time until 4·0.8ᵏ < 0.95.
#[test]
fn closed_room_with_a_raised_roulette_scale() {
    let (se_1, rays_1) = check_room_with(0.8, SpectralMode::Rgb, SamplerKind::Independent, 512, 1.0);
    let (se_4, rays_4) = check_room_with(0.8, SpectralMode::Rgb, SamplerKind::Independent, 512, 4.0);
    eprintln!("scale 1: se {se_1:.5}, {rays_1} rays; scale 4: se {se_4:.5}, {rays_4} rays");
    assert!(rays_4 as f64 > 1.2 * rays_1 as f64, "longer paths: {rays_4} against {rays_1} rays");
    assert!(se_4 < 0.8 * se_1, "a lower error per sample: {se_4} against {se_1}");
}

#[test]
fn closed_room_albedo_0_9_needs_long_paths_and_russian_roulette() {
    for mode in [SpectralMode::Rgb, SpectralMode::Hero] {
        check_room(0.9, mode, SamplerKind::Independent, 512);
    }
}

#[test]
fn a_depth_limit_cuts_the_series() {
    // With at most k bounces the radiance is Le·Σ_{j≤k} ρʲ: the test can tell a bounded
    // from an unbounded path.
    let (albedo, le) = (0.5f32, 0.5f32);
    let prepared = glowing_room(albedo, le);
    for k in [1u32, 2] {
        let settings = RenderSettings {
            width: 16,
            height: 16,
            spp: 64,
            seed: 5,
            mode: SpectralMode::Rgb,
            sampler: SamplerKind::Independent,
            path: PathSettings { max_depth: k, rr_depth: 100, ..Default::default() },
            camera: None,
            crop: None,
        };
        let (film, _) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
        let expected: f64 = (0..=k).map(|j| (le * albedo.powi(j as i32)) as f64).sum();
        let (mean, se) = channel_mean_and_se(&film, 1);
        assert!(((mean - expected) / se).abs() < 4.5, "k={k}: {mean} vs {expected} (se {se})");
    }
}
