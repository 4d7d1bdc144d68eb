//! The biased integrators against what they should equal: ambient occlusion against its
//! closed form, direct lighting against path tracing limited to one bounce, Whitted ray
//! tracing against path tracing on a scene of mirrors and glass and on diffuse surfaces
//! under point lights.

use crate::common;

use common::{channel_mean_and_se, z_test};
use glam::Vec3;
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::integrator::PathSettings;
use tracer::material::Material;
use tracer::mesh::quad;
use tracer::{
    AmbientOcclusion, CpuBackend, DirectLighting, Integrator, PathTracer, PunctualLight, RenderSettings, Scene, Whitted,
};

fn render<I: Integrator>(integrator: I, scene: &Scene, settings: &RenderSettings) -> tracer::Film {
    let backend = CpuBackend::with_integrator(2, integrator).unwrap();
    let prepared = backend.prepare_cpu(scene.clone(), &Default::default()).unwrap();
    let (film, stats) = tracer::render(&prepared, settings, &|_| {}).unwrap();
    assert_eq!(stats.non_finite, 0);
    film
}

/// Two estimates of the same image: per-pixel z-tests (at least `min_pass` of the
/// pixel-channels within the Šidák-corrected bound) and channel means within 4.5σ.
fn assert_images_agree(a: &tracer::Film, b: &tracer::Film, min_pass: f64) {
    let c = z_test(&a.mean_rgb(), &a.std_error_rgb(), &b.mean_rgb(), &b.std_error_rgb());
    assert!(c.pass_fraction >= min_pass, "{c:?}");
    for ch in 0..3 {
        let ((x, sx), (y, sy)) = (channel_mean_and_se(a, ch), channel_mean_and_se(b, ch));
        assert!((x - y).abs() <= 4.5 * (sx * sx + sy * sy).sqrt(), "channel {ch}: {x} ± {sx} vs {y} ± {sy}");
    }
}

/// A floor under a ceiling at height h, both 100 wide (infinite for these purposes), the
/// camera between them looking down. A cosine-distributed direction from the floor
/// reaches the ceiling within distance d iff cos θ ≥ h/d, which has probability
/// 1 − (h/d)²: the unoccluded fraction is (h/d)² for d ≥ h, 1 for d < h.
#[test]
fn ambient_occlusion_matches_its_closed_form() {
    let h = 0.5f32;
    let grey = Material::diffuse("grey", Colour::constant(0.5)).unwrap();
    let mut scene = Scene::default();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 50.0), grey.clone());
    scene.add(&quad(Vec3::new(0.0, h, 0.0), -Vec3::Y, 50.0), grey);
    scene.camera = Some(Camera { eye: Vec3::new(0.0, 0.3, 0.0), center: Vec3::ZERO, up: Vec3::Z, fov_y_deg: 60.0 });
    for (d, expected) in [(0.4f32, 1.0f64), (1.0, 0.25), (2.0, 0.0625), (f32::INFINITY, 0.0)] {
        for mode in [SpectralMode::Rgb, SpectralMode::Hero] {
            let settings = RenderSettings { width: 16, height: 16, spp: 64, seed: 5, mode, ..Default::default() };
            let film = render(AmbientOcclusion::new(d), &scene, &settings);
            for c in 0..3 {
                let (mean, se) = channel_mean_and_se(&film, c);
                // Within 4.5σ, plus the hero mode's D65 → sRGB white (1 ± 10⁻³) and the
                // finite ceiling (rays escaping at cos θ < 0.01: ≤ 10⁻⁴).
                let tolerance = 4.5 * se + 2e-3 * expected + 1e-4;
                assert!((mean - expected).abs() <= tolerance, "d = {d}, {mode:?}: {mean} ± {se}, expected {expected}");
            }
        }
    }
}

/// Direct lighting (light sampling only) and path tracing at depth 1 (light and BSDF
/// sampling with MIS) estimate the same image on a scene without specular surfaces.
#[test]
fn direct_lighting_equals_path_tracing_at_depth_one() {
    let mut scene = Scene::default();
    let red = Material::diffuse("red", Colour::reflectance_rgb([0.7, 0.2, 0.1]).unwrap()).unwrap();
    let white = Material::diffuse("white", Colour::constant(0.8)).unwrap();
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([6.0, 5.0, 4.0]).unwrap());
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), red);
    scene.add(&quad(Vec3::new(-1.0, 1.0, 0.0), Vec3::X, 1.0), white.clone());
    scene.add(&quad(Vec3::new(0.0, 1.0, -1.0), Vec3::Z, 1.0), white);
    scene.add(&quad(Vec3::new(0.2, 1.6, 0.1), -Vec3::Y, 0.3), lamp);
    scene.camera =
        Some(Camera { eye: Vec3::new(0.3, 1.2, 3.0), center: Vec3::new(0.0, 0.6, 0.0), up: Vec3::Y, fov_y_deg: 50.0 });
    let base = RenderSettings { width: 24, height: 24, spp: 256, seed: 3, ..Default::default() };
    let depth_one = RenderSettings { path: PathSettings { max_depth: 1, ..Default::default() }, ..base.clone() };
    let direct = render(DirectLighting, &scene, &base);
    let path = render(PathTracer, &scene, &depth_one);
    assert_images_agree(&direct, &path, 0.995);
    // Indirect light exists in this scene: full path tracing is brighter, so the test can
    // tell the two apart.
    let (full, full_se) = channel_mean_and_se(&render(PathTracer, &scene, &base), 1);
    let (one, one_se) = channel_mean_and_se(&path, 1);
    assert!(full - one > 6.0 * (full_se * full_se + one_se * one_se).sqrt(), "{full} vs {one}");
}

/// A mirror, a smooth glass ball and a tinted glass slab in front of an area light and a
/// sky: only purely specular surfaces, so Whitted's deterministic split into reflection and
/// refraction estimates what path tracing's random choice between them does, at the same
/// depth limit. A Whitted that ignored the Fresnel split (both lobes at full weight) or
/// reflection altogether would be told apart (checked below).
#[test]
fn whitted_equals_path_tracing_on_mirrors_and_glass() {
    let mut scene = Scene::default();
    let mirror = Material::builtin("mirror", brdf::ModelId::Mirror, &[]).unwrap();
    let glass = Material::dielectric("glass", 1.5).unwrap();
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([5.0, 4.0, 3.0]).unwrap());
    scene.add(&quad(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 1.5), mirror);
    scene.add(&tracer::mesh::uv_sphere(Vec3::new(0.3, 0.1, 0.0), 0.5, 24, 48, false), glass.clone());
    scene.add(&quad(Vec3::new(-0.6, 0.0, 0.3), Vec3::new(1.0, 0.0, 1.0), 0.3), glass);
    scene.add(&quad(Vec3::new(0.0, 1.2, 0.0), -Vec3::Y, 0.4), lamp);
    scene.environment = Some(tracer::Environment::uniform(Colour::reflectance_rgb([0.2, 0.3, 0.5]).unwrap()));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.2, 0.4, 3.0), center: Vec3::new(0.0, 0.1, 0.0), up: Vec3::Y, fov_y_deg: 45.0 });
    let path_settings = PathSettings { max_depth: 6, rr_depth: 100, ..Default::default() };
    let settings = RenderSettings {
        width: 20,
        height: 20,
        spp: 128,
        seed: 9,
        mode: SpectralMode::Rgb,
        path: path_settings,
        ..Default::default()
    };
    let whitted = render(Whitted, &scene, &settings);
    let path = render(PathTracer, &scene, &RenderSettings { spp: 512, ..settings.clone() });
    assert_images_agree(&whitted, &path, 0.99);
    // The same depth limit matters: at depth 1 the light behind two glass surfaces is gone.
    let shallow = RenderSettings { path: PathSettings { max_depth: 1, ..path_settings }, ..settings.clone() };
    let (deep, deep_se) = channel_mean_and_se(&whitted, 1);
    let (one, one_se) = channel_mean_and_se(&render(Whitted, &scene, &shallow), 1);
    assert!(deep - one > 6.0 * (deep_se * deep_se + one_se * one_se).sqrt(), "{deep} vs {one}");
}

/// On diffuse surfaces Whitted gathers direct light only: every point light by its own
/// shadow ray, the area light by one sample. That is path tracing at depth 1.
#[test]
fn whitted_on_diffuse_surfaces_is_path_tracing_at_depth_one() {
    let mut scene = Scene::default();
    let white = Material::diffuse("white", Colour::constant(0.8)).unwrap();
    let lamp = Material::diffuse("lamp", Colour::constant(0.0)).unwrap().with_emission(Colour::constant(3.0));
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), white.clone());
    scene.add(&quad(Vec3::new(0.0, 1.0, -1.0), Vec3::Z, 1.0), white);
    scene.add(&quad(Vec3::new(0.5, 1.5, 0.0), -Vec3::Y, 0.2), lamp);
    scene.punctual_lights = vec![
        PunctualLight::point(Vec3::new(-0.5, 0.8, 0.5), Colour::illuminant_rgb([1.0, 0.6, 0.3]).unwrap()),
        PunctualLight::spot(Vec3::new(0.0, 1.5, 1.0), Vec3::new(0.0, -1.0, -0.5), Colour::constant(2.0), 0.3, 0.6),
    ];
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 1.0, 3.0), center: Vec3::new(0.0, 0.5, 0.0), up: Vec3::Y, fov_y_deg: 50.0 });
    let base = RenderSettings { width: 20, height: 20, spp: 128, seed: 4, ..Default::default() };
    let depth_one = RenderSettings { path: PathSettings { max_depth: 1, ..Default::default() }, ..base.clone() };
    let whitted = render(Whitted, &scene, &base);
    let path = render(PathTracer, &scene, &depth_one);
    assert_images_agree(&whitted, &path, 0.99);
}
