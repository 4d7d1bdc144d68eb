//! Estimates from independent batches (renders with different seeds), for integrators
//! whose light tracing splats onto arbitrary pixels: a film's per-pixel standard errors
//! do not cover those, so errors come from the spread between batches, for every
//! integrator compared alike. And the small diffuse box such comparisons run in.

use super::z_test;
use glam::Vec3;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::material::Material;
use tracer::mesh::{quad, uv_sphere};
use tracer::{CpuBackend, Integrator, RenderSettings, Scene, SceneOptions};

/// Per pixel-channel means and standard errors, and per channel the image mean and its
/// standard error, from `batches` independent renders.
pub struct Batched {
    pub mean: Vec<f32>,
    pub se: Vec<f32>,
    pub channels: [(f64, f64); 3],
    /// Rays traced over all the batches.
    pub rays: u64,
}

pub fn batched<I: Integrator>(integrator: I, scene: &Scene, settings: &RenderSettings, batches: u32) -> Batched {
    batched_with(integrator, scene, &SceneOptions::default(), settings, batches)
}

/// [`batched`] with the scene prepared with `options`.
pub fn batched_with<I: Integrator>(
    integrator: I,
    scene: &Scene,
    options: &SceneOptions,
    settings: &RenderSettings,
    batches: u32,
) -> Batched {
    let prepared = CpuBackend::with_integrator(2, integrator).unwrap().prepare_cpu(scene.clone(), options).unwrap();
    let mut rays = 0;
    let images: Vec<Vec<f32>> = (0..batches)
        .map(|k| {
            let settings = RenderSettings { seed: settings.seed.wrapping_add(1000 * k as u64), ..settings.clone() };
            let (film, stats) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
            assert_eq!(stats.non_finite, 0, "NaN/Inf samples");
            rays += stats.rays;
            film.mean_rgb()
        })
        .collect();
    let n = batches as f64;
    let len = images[0].len();
    let mut mean = vec![0.0f32; len];
    let mut se = vec![0.0f32; len];
    for i in 0..len {
        let m = images.iter().map(|img| img[i] as f64).sum::<f64>() / n;
        let var = images.iter().map(|img| (img[i] as f64 - m).powi(2)).sum::<f64>() / (n - 1.0);
        mean[i] = m as f32;
        se[i] = (var / n).sqrt() as f32;
    }
    let channels = std::array::from_fn(|c| {
        let per_batch: Vec<f64> = images
            .iter()
            .map(|img| img.iter().skip(c).step_by(3).map(|&v| v as f64).sum::<f64>() / (len / 3) as f64)
            .collect();
        let m = per_batch.iter().sum::<f64>() / n;
        let var = per_batch.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
        (m, (var / n).sqrt())
    });
    Batched { mean, se, channels, rays }
}

/// Both estimates agree: at least `min_pass` of the pixel-channels within the
/// Šidák-corrected bound, and the channel means within 4.5σ.
pub fn assert_agree(a: &Batched, b: &Batched, min_pass: f64) {
    let c = z_test(&a.mean, &a.se, &b.mean, &b.se);
    assert!(c.pass_fraction >= min_pass, "{c:?}");
    for ch in 0..3 {
        let ((x, sx), (y, sy)) = (a.channels[ch], b.channels[ch]);
        assert!((x - y).abs() <= 4.5 * (sx * sx + sy * sy).sqrt(), "channel {ch}: {x} ± {sx} vs {y} ± {sy}");
    }
}

pub fn camera(eye: Vec3, center: Vec3) -> Option<Camera> {
    Some(Camera { eye, center, up: Vec3::Y, fov_y_deg: 50.0 })
}

/// A box open towards the camera: a floor, a back and two side walls (red and green),
/// a ceiling with a small lamp facing down.
pub fn diffuse_box(lamp_half: f32, lamp_radiance: f32) -> Scene {
    let mut scene = Scene::default();
    let white = Material::diffuse("white", Colour::constant(0.75)).unwrap();
    let red = Material::diffuse("red", Colour::reflectance_rgb([0.7, 0.15, 0.1]).unwrap()).unwrap();
    let green = Material::diffuse("green", Colour::reflectance_rgb([0.15, 0.6, 0.15]).unwrap()).unwrap();
    let lamp = lamp("lamp", [lamp_radiance, 0.85 * lamp_radiance, 0.6 * lamp_radiance]);
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), white.clone());
    scene.add(&quad(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, 1.0), white.clone());
    scene.add(&quad(Vec3::new(0.0, 1.0, -1.0), Vec3::Z, 1.0), white);
    scene.add(&quad(Vec3::new(-1.0, 1.0, 0.0), Vec3::X, 1.0), red);
    scene.add(&quad(Vec3::new(1.0, 1.0, 0.0), -Vec3::X, 1.0), green);
    scene.add(&quad(Vec3::new(0.0, 1.99, 0.0), -Vec3::Y, lamp_half), lamp);
    scene.camera = camera(Vec3::new(0.0, 1.0, 3.4), Vec3::new(0.0, 1.0, 0.0));
    scene
}

/// A black diffuse emitter of linear-sRGB radiance `rgb`.
pub fn lamp(name: &str, rgb: [f32; 3]) -> Material {
    Material::diffuse(name, Colour::constant(0.0)).unwrap().with_emission(Colour::illuminant_rgb(rgb).unwrap())
}

/// A smooth glass ball (interpolated normals), a rough glass pane and a mirror under a
/// large lamp, and a coarse diffuse ball with smooth normals: caustics through
/// refraction and off a mirror, at a size the path tracer's estimate of them converges at
/// a few dozen samples per pixel.
pub fn glass_and_mirror_box() -> Scene {
    // A large lamp, so that the path tracer's estimate of the caustics (camera paths
    // that hit the lamp through glass) converges at this sample count; under a small
    // one its rare large samples leave it low with an underestimated error.
    let mut scene = diffuse_box(0.6, 2.0);
    let glass = Material::dielectric("glass", 1.5).unwrap();
    let frosted = Material::builtin(
        "frosted",
        brdf::ModelId::RoughDielectric,
        &[("alpha", brdf::params::ParamValue::Scalar(0.3)), ("ior", brdf::params::ParamValue::Scalar(1.6))],
    )
    .unwrap();
    let mirror = Material::builtin("mirror", brdf::ModelId::Mirror, &[]).unwrap();
    scene.add(&uv_sphere(Vec3::new(-0.35, 0.4, 0.1), 0.35, 16, 32, false), glass);
    scene.add(&quad(Vec3::new(0.35, 1.3, 0.1), Vec3::new(0.2, 1.0, 0.3), 0.4), frosted);
    scene.add(&quad(Vec3::new(0.5, 0.5, -0.9), Vec3::new(-0.4, 0.0, 1.0), 0.35), mirror);
    let white = Material::diffuse("white", Colour::constant(0.8)).unwrap();
    scene.add(&uv_sphere(Vec3::new(0.4, 0.3, 0.3), 0.3, 4, 6, false), white);
    scene
}
