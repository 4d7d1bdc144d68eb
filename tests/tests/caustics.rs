//! `path-caustics` ([`CausticPathTracer`]) is unbiased: the path tracer leaves out the
//! caustics it sees on diffuse surfaces (E D S⁺ L) and light paths add exactly those
//! back, so the sum must estimate what the path tracer does, pixel by pixel — under a
//! large lamp, where the path tracer's own estimate of the caustics converges: a room lit
//! only off a mirror (in RGB), through a glass ball onto the mirror and glass, a mirror
//! and a rough pane (in hero mode), and a floor seen from inside a glass cube (RGB); and
//! the part left to the light paths must be a real share of the image (else the
//! comparison proves nothing).

use crate::common;

use common::batched::{assert_agree, batched, diffuse_box, glass_and_mirror_box, lamp};
use glam::Vec3;
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::integrator::PathSettings;
use tracer::material::Material;
use tracer::mesh::{quad, uv_sphere};
use tracer::{CausticPathTracer, CpuBackend, Integrator, PathTracer, RenderSettings, Scene, SceneOptions};

/// `path-caustics` at 32 spp and `path` at 96, 16 batches each, agree pixel by pixel.
fn agree_with_path_tracing(scene: &Scene, mode: SpectralMode) {
    let caustics = batched(CausticPathTracer, scene, &settings(mode, 32), 16);
    let path = batched(PathTracer, scene, &settings(mode, 96), 16);
    assert_agree(&caustics, &path, 0.99);
}

fn settings(mode: SpectralMode, spp: u32) -> RenderSettings {
    RenderSettings { width: 20, height: 20, spp, seed: 5, mode, ..Default::default() }
}

#[test]
fn light_traced_caustics_equal_path_tracing_off_a_mirror_in_rgb() {
    agree_with_path_tracing(&mirror_lit_box(false), SpectralMode::Rgb);
}

/// The lamp's light passes through a smooth glass ball (refractions whose radiance
/// scaling and shading normals the light paths' adjoint must undo) before the mirror.
#[test]
fn light_traced_caustics_equal_path_tracing_through_glass_in_hero_mode() {
    agree_with_path_tracing(&mirror_lit_box(true), SpectralMode::Hero);
}

/// The camera and a diffuse floor inside a closed glass block, the lamp outside above
/// it: all of the floor's light has entered the glass, where radiance is η² = 2.25 times
/// the transmitted radiance outside. The camera paths carry that by the BSDF's radiance
/// scaling, the light paths by the adjoint's factor (`importance_factor`), which a closed
/// glass ball cancels on the way out; here nothing cancels it, so light paths that left
/// it out would be 2.25 times off in their share of the image.
#[test]
fn light_traced_caustics_equal_path_tracing_seen_inside_glass() {
    let scene = inside_glass();
    agree_with_path_tracing(&scene, SpectralMode::Rgb);
    // Most of the image is the caustic on the floor (measured: 77–84 % per channel), so
    // the agreement is the light paths'.
    assert_left_to_light_tracing(&scene, 32, 4, 0.6);
}

/// Glass, a mirror and a rough pane under a large lamp: caustics a small share of the
/// image, among every other kind of path.
#[test]
fn light_traced_caustics_equal_path_tracing_among_other_paths() {
    agree_with_path_tracing(&glass_and_mirror_box(), SpectralMode::Hero);
}

/// The path tracer with `leave_caustics` (what `path-caustics` runs for its camera
/// paths) lacks the light of the caustics: in the room lit off the mirror, a quarter of
/// the image (26 %; the rest is its dim ceiling lamp and longer paths, E D D S L) — so
/// that the comparisons there test the light paths' part.
#[test]
fn the_caustics_left_to_light_tracing_are_a_real_share_of_the_image() {
    assert_left_to_light_tracing(&mirror_lit_box(false), 96, 8, 0.2);
}

/// The path tracer with and without `leave_caustics` (RGB, `spp` × `batches`): in every
/// channel the light left to light tracing is more than `share` of the image and ten
/// standard errors.
fn assert_left_to_light_tracing(scene: &Scene, spp: u32, batches: u32, share: f64) {
    let full = batched(PathTracer, scene, &settings(SpectralMode::Rgb, spp), batches);
    let leaving = RenderSettings {
        path: PathSettings { leave_caustics: true, ..Default::default() },
        ..settings(SpectralMode::Rgb, spp)
    };
    let left = batched(PathTracer, scene, &leaving, batches);
    for c in 0..3 {
        let ((a, sa), (b, sb)) = (full.channels[c], left.channels[c]);
        let gap = a - b;
        assert!(
            gap > share * a && gap > 10.0 * (sa * sa + sb * sb).sqrt(),
            "channel {c}: {a} ± {sa} against {b} ± {sb} without the caustics"
        );
    }
}

/// Where the split does not apply — a depth limit, no film (a caller of `radiance`) — the
/// integrator is the path tracer: the same image to the bit.
#[test]
fn with_a_depth_limit_light_traced_caustics_are_the_path_tracer() {
    let scene = glass_and_mirror_box();
    let limited =
        RenderSettings { path: PathSettings { max_depth: 4, ..Default::default() }, ..settings(SpectralMode::Rgb, 8) };
    let a = render(CausticPathTracer, &scene, &limited);
    let b = render(PathTracer, &scene, &limited);
    assert!(a.pixels() == b.pixels(), "the camera samples differ");
    assert!(a.splat_sums().is_none(), "light paths splatted");
}

fn render<I: Integrator>(integrator: I, scene: &Scene, settings: &RenderSettings) -> tracer::film::Film {
    let prepared = CpuBackend::with_integrator(2, integrator)
        .unwrap()
        .prepare_cpu(scene.clone(), &SceneOptions::default())
        .unwrap();
    tracer::render(&prepared, settings, &|_| {}).unwrap().0
}

/// The diffuse box with a dim lamp on its ceiling, lit by a large lamp at mid-height that
/// faces up, onto a mirror under the ceiling: the floor and walls get their light off
/// the mirror, paths of the form E D S L (and longer); with `glass`, through a glass ball
/// above the lamp first.
fn mirror_lit_box(glass: bool) -> Scene {
    let mut scene = diffuse_box(0.05, 1.0);
    let mirror = Material::builtin("mirror", brdf::ModelId::Mirror, &[]).unwrap();
    scene.add(&quad(Vec3::new(0.0, 1.95, 0.0), -Vec3::Y, 0.9), mirror);
    let lamp = lamp("up-lamp", [3.0, 2.7, 2.2]);
    scene.add(&quad(Vec3::new(0.0, 1.2, -0.2), Vec3::Y, 0.3), lamp);
    if glass {
        let glass = Material::dielectric("glass", 1.5).unwrap();
        scene.add(&uv_sphere(Vec3::new(0.0, 1.5, -0.2), 0.25, 16, 32, false), glass);
    }
    scene
}

/// A closed glass cube (edge 2, outward faces) holding the camera and a diffuse floor and
/// ball, under a large lamp outside it facing down: every path from the lamp to the floor
/// refracts into the glass (E D S L and longer: the floor's light is all caustic).
fn inside_glass() -> Scene {
    let mut scene = Scene::default();
    let glass = Material::dielectric("glass", 1.5).unwrap();
    for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        scene.add(&quad(Vec3::new(0.0, 1.0, 0.0) + n, n, 1.0), glass.clone());
    }
    let floor = Material::diffuse("floor", Colour::reflectance_rgb([0.7, 0.6, 0.4]).unwrap()).unwrap();
    scene.add(&quad(Vec3::new(0.0, 0.05, 0.0), Vec3::Y, 0.9), floor);
    let ball = Material::diffuse("ball", Colour::constant(0.6)).unwrap();
    scene.add(&uv_sphere(Vec3::new(0.3, 0.35, -0.3), 0.3, 8, 16, false), ball);
    let lamp = lamp("lamp", [2.0, 1.8, 1.5]);
    scene.add(&quad(Vec3::new(0.0, 2.6, 0.0), -Vec3::Y, 1.2), lamp);
    scene.camera = common::batched::camera(Vec3::new(0.0, 1.2, 0.9), Vec3::new(0.0, 0.3, -0.2));
    scene
}
