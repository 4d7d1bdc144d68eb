//! White-furnace tests: non-absorbing (albedo 1) Lambertian objects under a uniform sky
//! of radiance 1 are invisible — every pixel equals the sky — however many bounces the
//! light takes between them. A BSDF or integrator that loses or gains energy shows.

use crate::common;

use common::channel_mean_and_se;
use glam::Vec3;
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::material::Material;
use tracer::mesh::{quad, uv_sphere};
use tracer::{CpuBackend, Environment, RenderSettings, Scene};
use tracer::{CpuScene, SceneOptions};

fn furnace(albedo: f32) -> CpuScene {
    let white = || Material::diffuse("white", Colour::constant(albedo)).unwrap();
    let mut scene = Scene::default();
    scene.add(&uv_sphere(Vec3::new(0.0, 0.5, 0.0), 0.5, 16, 32, false), white());
    // An open box around it (no front wall): concave, so light bounces many times.
    for (c, n) in [
        (Vec3::new(0.0, -0.01, 0.0), Vec3::Y),
        (Vec3::new(0.0, 2.0, 0.0), -Vec3::Y),
        (Vec3::new(0.0, 1.0, -1.0), Vec3::Z),
        (Vec3::new(-1.0, 1.0, 0.0), Vec3::X),
        (Vec3::new(1.0, 1.0, 0.0), -Vec3::X),
    ] {
        scene.add(&quad(c, n, 1.0), white());
    }
    scene.environment = Some(Environment::uniform(Colour::constant(1.0)));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 1.0, 3.5), center: Vec3::new(0.0, 1.0, 0.0), up: Vec3::Y, fov_y_deg: 40.0 });
    CpuBackend::new(2).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap()
}

fn mean_image(albedo: f32, mode: SpectralMode) -> [(f64, f64); 3] {
    let settings = RenderSettings { width: 32, height: 32, spp: 64, seed: 3, mode, ..Default::default() };
    let (film, stats) = tracer::render(&furnace(albedo), &settings, &|_| {}).unwrap();
    assert_eq!(stats.non_finite, 0);
    std::array::from_fn(|c| channel_mean_and_se(&film, c))
}

#[test]
fn non_absorbing_objects_vanish_in_the_furnace() {
    for mode in [SpectralMode::Rgb, SpectralMode::Hero] {
        let sky = if mode == SpectralMode::Rgb {
            [1.0; 3]
        } else {
            spectral::colour::spectrum_to_linear_srgb(|_| 1.0).map(|v| v as f64)
        };
        for (c, (mean, se)) in mean_image(1.0, mode).into_iter().enumerate() {
            assert!(((mean - sky[c]) / se).abs() < 4.5, "{mode:?} channel {c}: {mean} vs {} (se {se})", sky[c]);
            assert!((mean / sky[c] - 1.0).abs() < 0.005, "{mode:?} channel {c}: {mean}");
        }
    }
}

#[test]
fn an_absorbing_object_is_visible_so_the_test_can_fail() {
    // Albedo 0.95: the box interior darkens measurably below the sky.
    let (mean, se) = mean_image(0.95, SpectralMode::Rgb)[1];
    assert!((1.0 - mean) / se > 10.0, "mean {mean} (se {se}) should be clearly below 1");
}
