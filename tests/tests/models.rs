//! Every built-in BSDF model, through the whole renderer: a sphere of it (default
//! parameters) in a white furnace — a uniform sky of radiance 1 — must never come out
//! brighter than the sky (no model creates energy), and never yield NaN or Inf.

use crate::common;

use common::channel_mean_and_se;
use glam::Vec3;
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::SceneOptions;
use tracer::camera::Camera;
use tracer::material::{Material, ModelId};
use tracer::mesh::uv_sphere;
use tracer::{CpuBackend, Environment, RenderSettings, Scene};

#[test]
fn no_model_is_brighter_than_the_furnace_or_produces_nan() {
    for &model in ModelId::ALL {
        let mut scene = Scene::default();
        let material = Material::builtin(model.def().name, model, &[]).unwrap();
        scene.add(&uv_sphere(Vec3::ZERO, 1.0, 24, 48, false), material);
        scene.environment = Some(Environment::uniform(Colour::constant(1.0)));
        // Close enough that the sphere fills the frame.
        scene.camera = Some(Camera { eye: Vec3::new(0.0, 0.0, 2.0), center: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 30.0 });
        let prepared = CpuBackend::new(2).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap();
        for mode in [SpectralMode::Rgb, SpectralMode::Hero] {
            let settings = RenderSettings { width: 16, height: 16, spp: 64, seed: 8, mode, ..Default::default() };
            let (film, stats) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
            assert_eq!(stats.non_finite, 0, "{model:?} {mode:?}");
            let sky = if mode == SpectralMode::Rgb {
                [1.0; 3]
            } else {
                spectral::colour::spectrum_to_linear_srgb(|_| 1.0).map(|v| v as f64)
            };
            for (c, &sky_c) in sky.iter().enumerate() {
                let (mean, se) = channel_mean_and_se(&film, c);
                assert!(mean <= sky_c + 4.5 * se + 1e-3, "{model:?} {mode:?} channel {c}: {mean} > sky {sky_c}");
                assert!(mean > 0.05, "{model:?} {mode:?} channel {c}: black ({mean})");
            }
        }
    }
}
