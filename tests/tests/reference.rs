//! Our Cornell box against Mitsuba 3's converged references in `../shared/refs/`:
//! image means per channel within 1 %, and ≥ 99 % of pixel-channels passing a z-test
//! (z = Δ / √(se_ours² + se_ref²), α = 0.01 Šidák-corrected), in RGB mode against the
//! RGB reference and in hero-spectral mode against the spectral one.

use crate::common;

use common::z_test;
use glam::Vec3;
use spectral::SpectralMode;
use std::path::{Path, PathBuf};
use tracer::SceneOptions;
use tracer::camera::Camera;
use tracer::integrator::PathSettings;
use tracer::output::read_rgb32f;
use tracer::sampler::SamplerKind;
use tracer::{CpuBackend, RenderSettings};

fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared")
}

struct Reference {
    camera: Camera,
    width: u32,
    height: u32,
    mean: Vec<f32>,
    se: Vec<f32>,
}

fn load_reference(variant: &str) -> Option<Reference> {
    let dir = shared().join("refs/cornell-box-original");
    let stem = format!("cornell-box-original_{variant}_256_4096spp");
    let json = dir.join(format!("{stem}.json"));
    let Ok(text) = std::fs::read_to_string(&json) else {
        eprintln!("SKIPPED: {} is absent (the shared references are not checked out)", json.display());
        return None;
    };
    let meta: serde_json::Value = serde_json::from_str(&text).expect("reference JSON parses");
    let v = |k: &str| {
        let a = meta["camera"][k].as_array().expect("camera vector");
        Vec3::new(a[0].as_f64().unwrap() as f32, a[1].as_f64().unwrap() as f32, a[2].as_f64().unwrap() as f32)
    };
    let camera = Camera {
        eye: v("eye"),
        center: v("center"),
        up: v("up"),
        fov_y_deg: meta["camera"]["vertical_fov_deg"].as_f64().unwrap() as f32,
    };
    let (width, height, mean) = read_rgb32f(&dir.join(format!("{stem}.exr"))).expect("reference EXR");
    let (_, _, se) = read_rgb32f(&dir.join(format!("{stem}_stderr.exr"))).expect("reference stderr EXR");
    assert_eq!(width as u64, meta["film"]["width"].as_u64().unwrap());
    Some(Reference { camera, width, height, mean, se })
}

/// `rr_scale`: Russian roulette's scale (`None`: the default's).
fn compare(variant: &str, mode: SpectralMode, sampler: SamplerKind, spp: u32, rr_scale: Option<f32>) {
    let Some(reference) = load_reference(variant) else { return };
    let scene_path = shared().join("scenes/cornell-box/CornellBox-Original-fixed.obj");
    let scene = tracer::obj::load_obj(&scene_path).expect("Cornell box loads");
    let prepared = CpuBackend::new(2).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap();
    let settings = RenderSettings {
        width: reference.width,
        height: reference.height,
        spp,
        seed: 2024,
        mode,
        sampler,
        // Unbounded depth, as the reference (Russian roulette is unbiased).
        path: PathSettings {
            max_depth: 0,
            rr_depth: 5,
            rr_scale: rr_scale.unwrap_or(PathSettings::default().rr_scale),
            ..Default::default()
        },
        camera: Some(reference.camera),
        crop: None,
    };
    let (film, stats) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
    assert_eq!(stats.non_finite, 0, "NaN/Inf samples");
    let ours = film.mean_rgb();
    let ours_se = film.std_error_rgb();
    let means = |img: &[f32]| -> [f64; 3] {
        let n = (img.len() / 3) as f64;
        std::array::from_fn(|c| img.iter().skip(c).step_by(3).map(|&v| v as f64).sum::<f64>() / n)
    };
    let (m_ours, m_ref) = (means(&ours), means(&reference.mean));
    let cmp = z_test(&ours, &ours_se, &reference.mean, &reference.se);
    eprintln!(
        "{variant} vs {mode:?} ({}) @ {spp} spp: means ours {m_ours:.5?} ref {m_ref:.5?}; z-test pass {:.4} (|z| ≤ {:.2}, worst {:.1})",
        sampler.name(),
        cmp.pass_fraction,
        cmp.z_max,
        cmp.worst
    );
    for c in 0..3 {
        let rel = m_ours[c] / m_ref[c] - 1.0;
        assert!(rel.abs() < 0.01, "{variant}: channel {c} mean differs by {:.2} %", rel * 100.0);
    }
    assert!(cmp.pass_fraction >= 0.99, "{variant}: only {:.3} % of pixel-channels pass", cmp.pass_fraction * 100.0);
}

#[test]
fn rgb_mode_matches_mitsuba_rgb() {
    compare("rgb", SpectralMode::Rgb, SamplerKind::Independent, 64, None);
}

#[test]
fn hero_spectral_mode_matches_mitsuba_spectral() {
    compare("spectral", SpectralMode::Hero, SamplerKind::Independent, 64, None);
}

/// The Sobol sampler is unbiased too. (Its per-pixel standard errors come from the sample
/// variance, which overestimates the error of stratified samples: the z-test is the more
/// lenient for it, the channel means are as sharp.)
#[test]
fn zsobol_sampler_matches_mitsuba_spectral() {
    compare("spectral", SpectralMode::Hero, SamplerKind::ZSobol, 64, None);
}

/// Russian roulette at other scales (`PathSettings::rr_scale`; the renders above use the
/// default, 2) is unbiased too: Mitsuba's own rule, 1, and 3, whose survivors' weight must
/// divide by the raised survival probability.
#[test]
fn other_roulette_scales_match_mitsuba_spectral() {
    compare("spectral", SpectralMode::Hero, SamplerKind::ZSobol, 64, Some(1.0));
    compare("spectral", SpectralMode::Hero, SamplerKind::ZSobol, 64, Some(3.0));
}
