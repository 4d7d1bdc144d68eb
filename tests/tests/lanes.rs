//! The path tracer's lanes kernel (eight paths per vector instruction on the diffuse
//! surfaces of triangle scenes, the others one lane at a time) against its general loop on
//! the shared Cornell box, the bunny, and glass and mirror spheres in the box: the same
//! image, to the bit, in every spectral mode and with every sampler, with Russian
//! roulette's default scale and Mitsuba's, and leaving caustics to light tracing (alone,
//! and with `path-caustics`' light paths added).

use glam::Vec3;
use spectral::SpectralMode;
use std::path::{Path, PathBuf};
use tracer::camera::Camera;
use tracer::integrator::PathSettings;
use tracer::render::SceneOptions;
use tracer::sampler::SamplerKind;
use tracer::{CausticPathTracer, CpuBackend, Integrator, PathTracer, RenderSettings};

fn shared() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared")
}

/// The shared OBJ at `relative`, or `None` (with a note) where the shared scenes are absent.
fn load(relative: &str) -> Option<tracer::Scene> {
    let path = shared().join(relative);
    if !path.exists() {
        eprintln!("SKIPPED: {} is absent (the shared scenes are not checked out)", path.display());
        return None;
    }
    Some(tracer::obj::load_obj(&path).expect("the shared scene loads"))
}

fn lanes_and_general_loop_agree(scene: tracer::Scene, camera: Camera, spp: u32) {
    lanes_and_general_loop_agree_with(PathTracer, scene, camera, spp);
}

/// As `lanes_and_general_loop_agree` with `integrator`; where it splats (light paths), the
/// lanes' render must hold splats too.
fn lanes_and_general_loop_agree_with<I: Integrator>(integrator: I, scene: tracer::Scene, camera: Camera, spp: u32) {
    let splatting = integrator.splats();
    let prepared =
        CpuBackend::with_integrator(2, integrator).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap();
    let default = PathSettings::default().rr_scale;
    for (mode, sampler, rr_scale, leave_caustics) in [
        (SpectralMode::Hero, SamplerKind::ZSobol, default, false),
        (SpectralMode::Hero, SamplerKind::Independent, default, false),
        (SpectralMode::Rgb, SamplerKind::Sobol, default, false),
        (SpectralMode::Bins40, SamplerKind::ZSobol, default, false),
        (SpectralMode::Hero, SamplerKind::ZSobol, 1.0, false),
        (SpectralMode::Hero, SamplerKind::ZSobol, default, true),
    ] {
        let settings = RenderSettings {
            width: 40,
            height: 40,
            spp,
            seed: 11,
            mode,
            sampler,
            path: PathSettings { rr_depth: 5, rr_scale, leave_caustics, ..Default::default() },
            camera: Some(camera),
            crop: None,
        };
        let what = format!("{mode:?} {sampler:?} {rr_scale} {leave_caustics}");
        assert!(PathTracer::runs_in_lanes(&prepared.view(), &settings.path), "the scene is one for the lanes");
        let general = RenderSettings { path: PathSettings { lanes: false, ..settings.path }, ..settings.clone() };
        assert!(!PathTracer::runs_in_lanes(&prepared.view(), &general.path));
        let (a, sa) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
        let (b, sb) = tracer::render(&prepared, &general, &|_| {}).unwrap();
        assert_eq!((sa.rays, sa.non_finite), (sb.rays, sb.non_finite), "{what}: rays traced");
        assert!(a.mean_rgb().iter().sum::<f32>() > 0.0, "a lit image");
        assert!(a.pixels() == b.pixels(), "{what}: the lanes' image differs from the general loop's");
        assert!(a.splat_sums() == b.splat_sums(), "{what}: the light paths' splats differ");
        let splatted = a.splat_sums().is_some_and(|s| s.iter().any(|p| *p != [0; 3]));
        assert_eq!(splatted, splatting, "{what}: splats");
    }
}

#[test]
fn lanes_render_the_general_loops_image_of_the_cornell_box() {
    let Some(scene) = load("scenes/cornell-box/CornellBox-Original-fixed.obj") else { return };
    let camera =
        Camera { eye: Vec3::new(0.0, 1.0, 3.9), center: Vec3::new(0.0, 1.0, 0.0), up: Vec3::Y, fov_y_deg: 39.3077 };
    lanes_and_general_loop_agree(scene, camera, 16);
}

#[test]
fn lanes_render_the_general_loops_image_of_the_bunny() {
    let Some(mut scene) = load("scenes/bunny/bunny.obj") else { return };
    // Lit by a lamp above it.
    let lamp = tracer::material::Material::diffuse("lamp", spectral::spectrum::Colour::constant(0.0))
        .unwrap()
        .with_emission(spectral::spectrum::Colour::illuminant_rgb([8.0, 7.0, 6.0]).unwrap());
    let b = scene.bounds();
    let (centre, extent) = (0.5 * (b.min + b.max), (b.max - b.min).max_element());
    let light = tracer::mesh::quad(centre + Vec3::Y * extent, -Vec3::Y, 0.5 * extent);
    scene.add(&light, lamp);
    let camera =
        Camera { eye: centre + Vec3::new(0.3, 0.4, 2.5) * extent, center: centre, up: Vec3::Y, fov_y_deg: 35.0 };
    lanes_and_general_loop_agree(scene, camera, 4);
}

#[test]
fn lanes_render_the_general_loops_image_of_glass_and_mirror_spheres_in_the_box() {
    let Some((scene, camera)) = spheres_in_the_box() else { return };
    lanes_and_general_loop_agree(scene, camera, 8);
}

/// `path-caustics`: the camera paths in lanes leave out what its light paths add, as the
/// general loop does, and the light paths (drawn from the same samplers) splat the same.
#[test]
fn lanes_render_the_general_loops_image_with_light_traced_caustics() {
    let Some((scene, camera)) = spheres_in_the_box() else { return };
    lanes_and_general_loop_agree_with(CausticPathTracer, scene, camera, 8);
}

/// The shared Cornell box with a glass and a mirror sphere, and its camera.
fn spheres_in_the_box() -> Option<(tracer::Scene, Camera)> {
    let mut scene = load("scenes/cornell-box/CornellBox-Original-fixed.obj")?;
    // Smooth-shaded UV spheres (normals and tangents per vertex) of glass and of a mirror,
    // which the lanes shade one lane at a time.
    let glass = tracer::material::Material::dielectric("glass", 1.5).unwrap();
    scene.add(&tracer::mesh::uv_sphere(Vec3::new(-0.45, 0.3, 0.55), 0.3, 24, 48, false), glass);
    let mirror = tracer::material::Material::builtin("mirror", brdf::ModelId::Mirror, &[]).unwrap();
    scene.add(&tracer::mesh::uv_sphere(Vec3::new(0.33, 0.85, 0.37), 0.25, 24, 48, false), mirror);
    let camera =
        Camera { eye: Vec3::new(0.0, 1.0, 3.9), center: Vec3::new(0.0, 1.0, 0.0), up: Vec3::Y, fov_y_deg: 39.3077 };
    Some((scene, camera))
}
