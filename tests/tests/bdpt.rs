//! Bidirectional path tracing is unbiased: it must estimate what the path tracer does,
//! pixel by pixel, on scenes that exercise each of its strategies — a small area light
//! in a diffuse box, glass and a mirror (caustics: light tracing through refraction),
//! point, spot and sky light together — and match the analytic glowing room and Mitsuba
//! 3's reference of the Cornell box.
//!
//! Light tracing splats onto arbitrary pixels, so a film's per-pixel standard errors do
//! not cover a bidirectional render: its errors come from independent batches (renders
//! with different seeds) instead, for both integrators alike.

use crate::common;

use common::batched::{Batched, assert_agree, batched, diffuse_box, glass_and_mirror_box};
use common::{sidak_z, z_test};
use glam::Vec3;
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::integrator::PathSettings;
use tracer::material::Material;
use tracer::mesh::{quad, uv_sphere};
use tracer::{Bdpt, PathTracer, PunctualLight, RenderSettings};

/// A small lamp in a diffuse box with a glossy block: every strategy carries weight.
#[test]
fn bdpt_equals_path_tracing_in_a_box_with_a_small_lamp() {
    let mut scene = diffuse_box(0.12, 40.0);
    let glossy = Material::builtin(
        "glossy",
        brdf::ModelId::RoughConductor,
        &[("alpha", brdf::params::ParamValue::Scalar(0.25))],
    )
    .unwrap();
    scene.add(&quad(Vec3::new(0.3, 0.6, -0.2), Vec3::new(-1.0, 0.3, 1.0), 0.3), glossy);
    let settings = RenderSettings { width: 20, height: 20, spp: 16, seed: 7, ..Default::default() };
    let bdpt = batched(Bdpt, &scene, &settings, 16);
    let path = batched(PathTracer, &scene, &RenderSettings { spp: 48, ..settings.clone() }, 16);
    assert_agree(&bdpt, &path, 0.99);
}

/// A smooth glass ball (interpolated normals), a rough glass pane and a mirror under a
/// lamp, and a coarse diffuse ball with smooth normals: the caustics under the
/// glass come mostly from light tracing, through refractions whose 1/η² radiance scaling
/// a light subpath must undo, and light paths reflected off the coarse ball need the
/// adjoint's shading-normal correction.
#[test]
fn bdpt_equals_path_tracing_with_glass_and_a_mirror() {
    let scene = glass_and_mirror_box();
    let settings =
        RenderSettings { width: 20, height: 20, spp: 16, seed: 3, mode: SpectralMode::Rgb, ..Default::default() };
    let bdpt = batched(Bdpt, &scene, &settings, 16);
    let path = batched(PathTracer, &scene, &RenderSettings { spp: 96, ..settings.clone() }, 16);
    assert_agree(&bdpt, &path, 0.99);
}

/// Point and spot lights start light subpaths too (never hit by camera paths), and a sky
/// with a sun disk is sampled as the path tracer samples it.
#[test]
fn bdpt_equals_path_tracing_under_point_spot_and_sky_light() {
    let mut scene = diffuse_box(0.1, 10.0);
    scene.punctual_lights = vec![
        PunctualLight::point(Vec3::new(-0.5, 1.4, 0.3), Colour::illuminant_rgb([1.0, 0.6, 0.3]).unwrap()),
        PunctualLight::spot(Vec3::new(0.3, 1.8, 0.8), Vec3::new(0.0, -1.0, -0.6), Colour::constant(3.0), 0.2, 0.5),
        PunctualLight::sun(Vec3::new(-0.3, -1.0, -0.4), Colour::constant(2.0), 0.05),
    ];
    scene.environment = Some(tracer::Environment::uniform(Colour::reflectance_rgb([0.3, 0.4, 0.6]).unwrap()));
    let settings = RenderSettings { width: 20, height: 20, spp: 16, seed: 5, ..Default::default() };
    let bdpt = batched(Bdpt, &scene, &settings, 16);
    let path = batched(PathTracer, &scene, &RenderSettings { spp: 48, ..settings.clone() }, 16);
    assert_agree(&bdpt, &path, 0.99);
}

/// The glowing room of `analytic.rs` (every wall emits Le and reflects ρ = 0.5:
/// radiance Le/(1 − ρ) everywhere): light subpaths start anywhere, long paths end by
/// Russian roulette on both sides; at roulette scales 1 and 4, the latter with longer
/// subpaths.
#[test]
fn bdpt_matches_the_glowing_room() {
    let (scale_1, scale_4) = (glowing_room_with_roulette_scale(1.0), glowing_room_with_roulette_scale(4.0));
    // Russian roulette's scale reaches both subpaths' roulettes: longer subpaths.
    assert!(scale_4.rays as f64 > 1.2 * scale_1.rays as f64, "rays: {} against {}", scale_4.rays, scale_1.rays);
}

/// [`bdpt_matches_the_glowing_room`] with `PathSettings::rr_scale` = `rr_scale`.
fn glowing_room_with_roulette_scale(rr_scale: f32) -> Batched {
    let (albedo, le) = (0.5f32, 0.5f32);
    let scene = common::room::glowing_room(albedo, le);
    let settings = RenderSettings {
        width: 12,
        height: 12,
        spp: 32,
        seed: 11,
        mode: SpectralMode::Rgb,
        path: PathSettings { max_depth: 0, rr_depth: 3, rr_scale, ..Default::default() },
        ..Default::default()
    };
    let b = batched(Bdpt, &scene, &settings, 16);
    let expected = (le / (1.0 - albedo)) as f64;
    for (c, &(m, se)) in b.channels.iter().enumerate() {
        assert!(
            (m - expected).abs() < 4.5 * se && (m / expected - 1.0).abs() < 0.01,
            "scale {rr_scale}, channel {c}: {m} ± {se}"
        );
    }
    let z_max = sidak_z(0.01, b.mean.len());
    let fails =
        b.mean.iter().zip(&b.se).filter(|&(&m, &s)| ((m as f64 - expected) / s.max(1e-9) as f64).abs() > z_max).count();
    assert!(fails as f64 <= 0.01 * b.mean.len() as f64, "scale {rr_scale}: {fails} pixel-channels fail");
    b
}

/// The Cornell box against Mitsuba 3's converged spectral reference (as
/// `reference.rs` tests the path tracer): means within 1 %, pixels by z-test.
#[test]
fn bdpt_matches_mitsuba_on_the_cornell_box() {
    let shared = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared");
    let dir = shared.join("refs/cornell-box-original");
    let stem = "cornell-box-original_spectral_256_4096spp";
    let Ok(text) = std::fs::read_to_string(dir.join(format!("{stem}.json"))) else {
        eprintln!("SKIPPED: {} is absent (the shared references are not checked out)", dir.display());
        return;
    };
    let meta: serde_json::Value = serde_json::from_str(&text).unwrap();
    let v = |k: &str| {
        let a = meta["camera"][k].as_array().unwrap();
        Vec3::new(a[0].as_f64().unwrap() as f32, a[1].as_f64().unwrap() as f32, a[2].as_f64().unwrap() as f32)
    };
    let cam = Camera {
        eye: v("eye"),
        center: v("center"),
        up: v("up"),
        fov_y_deg: meta["camera"]["vertical_fov_deg"].as_f64().unwrap() as f32,
    };
    let (width, height, reference) = tracer::output::read_rgb32f(&dir.join(format!("{stem}.exr"))).unwrap();
    let (_, _, reference_se) = tracer::output::read_rgb32f(&dir.join(format!("{stem}_stderr.exr"))).unwrap();
    let scene = tracer::obj::load_obj(&shared.join("scenes/cornell-box/CornellBox-Original-fixed.obj")).unwrap();
    let settings = RenderSettings {
        width,
        height,
        spp: 8,
        seed: 2025,
        path: PathSettings { max_depth: 0, rr_depth: 5, ..Default::default() },
        camera: Some(cam),
        ..Default::default()
    };
    let b = batched(Bdpt, &scene, &settings, 12);
    let n = (reference.len() / 3) as f64;
    for c in 0..3 {
        let r = reference.iter().skip(c).step_by(3).map(|&x| x as f64).sum::<f64>() / n;
        let rel = b.channels[c].0 / r - 1.0;
        assert!(rel.abs() < 0.01, "channel {c}: {} vs {r}", b.channels[c].0);
    }
    let cmp = z_test(&b.mean, &b.se, &reference, &reference_se);
    eprintln!(
        "bdpt vs Mitsuba spectral: z-test pass {:.4} (|z| ≤ {:.2}, worst {:.1})",
        cmp.pass_fraction, cmp.z_max, cmp.worst
    );
    assert!(cmp.pass_fraction >= 0.99, "{cmp:?}");
}

/// Interpolated normals on a coarse ball make the light subpath's BSDF the adjoint only
/// with Veach's shading-normal correction (1997, eq. 5.17): without it, light reflected
/// off the ball into the camera by light tracing is wrong.
#[test]
fn bdpt_corrects_shading_normals_on_light_paths() {
    let mut scene = diffuse_box(0.3, 6.0);
    let white = Material::diffuse("white", Colour::constant(0.9)).unwrap();
    scene.add(&uv_sphere(Vec3::new(0.0, 0.6, 0.0), 0.55, 3, 5, false), white);
    let settings =
        RenderSettings { width: 20, height: 20, spp: 16, seed: 13, mode: SpectralMode::Rgb, ..Default::default() };
    let bdpt = batched(Bdpt, &scene, &settings, 16);
    let path = batched(PathTracer, &scene, &RenderSettings { spp: 48, ..settings.clone() }, 16);
    assert_agree(&bdpt, &path, 0.99);
}
