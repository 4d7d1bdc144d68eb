//! The atlas integrator (one diffuse bounce gathered on a texture atlas) against what it
//! should equal: the path tracer limited to one diffuse bounce (`max_diffuse_depth` 2),
//! within the atlas's discretisation error, which is measured here; its documented
//! artefacts — light leaking through walls without visibility, dark seams without the
//! gutter's dilation — shown to exist and to be fixed.

use glam::Vec3;
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::integrator::PathSettings;
use tracer::material::Material;
use tracer::mesh::quad;
use tracer::{
    AtlasGi, AtlasSettings, CpuBackend, Integrator, PathTracer, RenderSettings, Scene, SceneOptions, SeamFix,
};

fn render<I: Integrator>(integrator: I, scene: &Scene, settings: &RenderSettings) -> Vec<f32> {
    let prepared = CpuBackend::with_integrator(2, integrator)
        .unwrap()
        .prepare_cpu(scene.clone(), &SceneOptions::default())
        .unwrap();
    let (film, stats) = tracer::render(&prepared, settings, &|_| {}).unwrap();
    assert_eq!(stats.non_finite, 0);
    film.mean_rgb()
}

/// A closed box room (inward walls, red left and green right) with a lamp under the
/// ceiling and a block on the floor, seen from inside.
fn room() -> Scene {
    let mut scene = Scene::default();
    let white = Material::diffuse("white", Colour::constant(0.75)).unwrap();
    let red = Material::diffuse("red", Colour::reflectance_rgb([0.7, 0.15, 0.1]).unwrap()).unwrap();
    let green = Material::diffuse("green", Colour::reflectance_rgb([0.15, 0.6, 0.15]).unwrap()).unwrap();
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([12.0, 10.0, 8.0]).unwrap());
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), white.clone());
    scene.add(&quad(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, 1.0), white.clone());
    scene.add(&quad(Vec3::new(0.0, 1.0, -1.0), Vec3::Z, 1.0), white.clone());
    scene.add(&quad(Vec3::new(0.0, 1.0, 1.0), -Vec3::Z, 1.0), white.clone());
    scene.add(&quad(Vec3::new(-1.0, 1.0, 0.0), Vec3::X, 1.0), red);
    scene.add(&quad(Vec3::new(1.0, 1.0, 0.0), -Vec3::X, 1.0), green);
    scene.add(&quad(Vec3::new(0.0, 1.99, 0.0), -Vec3::Y, 0.25), lamp);
    // A block: four sides and a top.
    let (c, h) = (Vec3::new(0.3, 0.3, -0.2), 0.3);
    for n in [Vec3::X, -Vec3::X, Vec3::Z, -Vec3::Z, Vec3::Y] {
        scene.add(&quad(c + n * h, n, h), white.clone());
    }
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 1.0, 0.95), center: Vec3::new(0.0, 0.8, 0.0), up: Vec3::Y, fov_y_deg: 80.0 });
    scene
}

fn settings(spp: u32, path: PathSettings) -> RenderSettings {
    RenderSettings { width: 32, height: 32, spp, seed: 17, mode: SpectralMode::Rgb, path, ..Default::default() }
}

fn mean(img: &[f32]) -> f64 {
    img.iter().map(|&v| v as f64).sum::<f64>() / img.len() as f64
}

/// The indirect part of an image (minus direct light), averaged over 8 × 8-pixel blocks.
fn indirect_blocks(img: &[f32], direct: &[f32]) -> Vec<f64> {
    let mut blocks = vec![0.0f64; 16];
    for y in 0..32 {
        for x in 0..32 {
            for c in 0..3 {
                let i = (y * 32 + x) * 3 + c;
                blocks[(y / 8) * 4 + x / 8] += (img[i] - direct[i]) as f64 / (64.0 * 3.0);
            }
        }
    }
    blocks
}

/// With visibility and enough points, the atlas's bounce is the path tracer's second
/// diffuse bounce up to the atlas's discretisation; a finer atlas gets closer (the
/// discretisation error is measured at two resolutions).
#[test]
fn atlas_converges_to_path_tracing_with_one_diffuse_bounce() {
    let scene = room();
    let direct = render(PathTracer, &scene, &settings(256, PathSettings { max_depth: 1, ..Default::default() }));
    let reference =
        render(PathTracer, &scene, &settings(1024, PathSettings { max_diffuse_depth: 2, ..Default::default() }));
    let want = indirect_blocks(&reference, &direct);
    let mut errors = Vec::new();
    for resolution in [64, 256] {
        let atlas = AtlasGi::new(AtlasSettings { resolution, samples: 2048, ..Default::default() });
        let img = render(atlas, &scene, &settings(256, PathSettings::default()));
        let got = indirect_blocks(&img, &direct);
        let total = (mean(&img) - mean(&direct)) / (mean(&reference) - mean(&direct));
        let worst = got.iter().zip(&want).map(|(g, w)| (g - w).abs() / w.abs().max(1e-3)).fold(0.0f64, f64::max);
        eprintln!(
            "atlas {resolution}²: indirect light {total:.4} of the path tracer's, worst 8×8 block off by {worst:.3}"
        );
        errors.push(((total - 1.0).abs(), worst));
    }
    let [(coarse_total, coarse_worst), (fine_total, fine_worst)] = errors[..] else { unreachable!() };
    assert!(fine_total < 0.03 && fine_worst < 0.1, "the finer atlas: {errors:?}");
    assert!(coarse_total < 0.08 && fine_total < coarse_total && fine_worst < coarse_worst, "{errors:?}");
    // Indirect light is a good part of the image here, so the test can tell a missing
    // bounce: without the atlas's lookup the image is the direct light alone.
    assert!(mean(&reference) > 1.2 * mean(&direct));
}

/// The depth mode: on a scene without mirrors or glass, two diffuse bounces are two
/// bounces, sample for sample.
#[test]
fn max_diffuse_depth_equals_max_depth_on_diffuse_scenes() {
    let scene = room();
    let a = render(PathTracer, &scene, &settings(16, PathSettings { max_diffuse_depth: 2, ..Default::default() }));
    let b = render(PathTracer, &scene, &settings(16, PathSettings { max_depth: 2, ..Default::default() }));
    assert_eq!(a, b);
    let full = render(PathTracer, &scene, &settings(16, PathSettings::default()));
    assert!(mean(&full) > 1.02 * mean(&a), "more bounces, more light");
}

/// Two closed rooms side by side, the lamp in one and the camera in the other: with
/// visibility the dark room stays black; without (the thesis's gather), the lit room's
/// light leaks through the wall between them.
#[test]
fn without_visibility_light_leaks_through_walls() {
    let mut scene = room();
    let white = Material::diffuse("white", Colour::constant(0.75)).unwrap();
    // A second room at x ∈ [1.02, 3.02], facing inward, no lamp.
    let c = Vec3::new(2.02, 1.0, 0.0);
    for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        scene.add(&quad(c - n, n, 1.0), white.clone());
    }
    scene.camera =
        Some(Camera { eye: Vec3::new(2.3, 1.0, 0.9), center: Vec3::new(1.5, 0.7, 0.0), up: Vec3::Y, fov_y_deg: 80.0 });
    let base = AtlasSettings { resolution: 128, samples: 256, ..Default::default() };
    let sealed = render(AtlasGi::new(base), &scene, &settings(16, PathSettings::default()));
    assert_eq!(mean(&sealed), 0.0, "no light reaches the closed room");
    let leaky = render(
        AtlasGi::new(AtlasSettings { visibility: false, ..base }),
        &scene,
        &settings(16, PathSettings::default()),
    );
    assert!(mean(&leaky) > 1e-3, "the thesis's gather leaks: {}", mean(&leaky));
}

/// A floor placed as a mirrored instance (its world winding reversed; its front, as the
/// renderer keeps it, still up) is lit in the atlas as the plain floor is.
#[test]
fn mirrored_instances_keep_their_front_in_the_atlas() {
    let plain = room();
    let mut mirrored = room();
    // Swap the floor (its first two triangles) for a placement of it mirrored in x.
    let white = Material::diffuse("white", Colour::constant(0.75)).unwrap();
    let mut floor = Scene::default();
    floor.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), white);
    mirrored.triangles.drain(..2);
    mirrored.material_ids.drain(..2);
    let object = mirrored.add_object(floor, None).unwrap();
    mirrored.place(object, glam::Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))).unwrap();
    let atlas = || AtlasGi::new(AtlasSettings { resolution: 96, samples: 256, ..Default::default() });
    let a = mean(&render(atlas(), &plain, &settings(16, PathSettings::default())));
    let b = mean(&render(atlas(), &mirrored, &settings(16, PathSettings::default())));
    assert!((b / a - 1.0).abs() < 0.03, "mirrored {b} vs plain {a}");
}

/// Without dilation, lookups at chart borders blend with the empty gutter: the room's
/// edges darken (the seams); with it they match the interior.
#[test]
fn dilation_removes_the_dark_seams() {
    let scene = room();
    let base = AtlasSettings { resolution: 64, samples: 512, ..Default::default() };
    let direct = render(PathTracer, &scene, &settings(64, PathSettings { max_depth: 1, ..Default::default() }));
    let fixed = render(AtlasGi::new(base), &scene, &settings(64, PathSettings::default()));
    let seams = render(
        AtlasGi::new(AtlasSettings { seams: SeamFix::None, ..base }),
        &scene,
        &settings(64, PathSettings::default()),
    );
    let (fixed, seams) = (mean(&fixed) - mean(&direct), mean(&seams) - mean(&direct));
    eprintln!("indirect light: dilated {fixed:.5}, raw gutter {seams:.5}");
    assert!(seams < 0.97 * fixed, "raw {seams} vs dilated {fixed}");
}
