//! Instancing: objects placed by transforms and traced through the two-level BVH render
//! the same image as the same triangles copied into one mesh (`Scene::flatten_instances`),
//! within statistics — including a mirrored placement, a per-instance material and an
//! instanced area light, which next-event estimation must find in world space.

use glam::{Mat4, Quat, Vec3};
use spectral::spectrum::Colour;
use tracer::material::Material;
use tracer::mesh::{quad, uv_sphere};
use tracer::{Camera, CpuBackend, PreparedScene, RenderSettings, Scene, SceneOptions, SpectralMode};

/// A floor, an object (a smooth half-sphere-ish lump with a flat lid) placed three
/// times, and a lamp object placed twice.
fn instanced_scene() -> Scene {
    let mut scene = Scene::default();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 4.0), Material::diffuse("floor", Colour::constant(0.6)).unwrap());
    let red = scene.materials.len() as u32;
    scene.materials.push(Material::diffuse("red", Colour::reflectance_rgb([0.8, 0.2, 0.1]).unwrap()).unwrap());
    // The object: a sphere with its own material.
    let mut ball = Scene::default();
    ball.add(
        &uv_sphere(Vec3::new(0.3, 0.5, 0.0), 0.5, 12, 24, false),
        Material::diffuse("ball", Colour::constant(0.7)).unwrap(),
    );
    ball.add(&quad(Vec3::new(0.3, 1.0, 0.0), Vec3::Y, 0.3), Material::diffuse("lid", Colour::constant(0.3)).unwrap());
    let ball = scene.add_object(ball, None).unwrap();
    scene.place(ball, Mat4::from_translation(Vec3::new(-1.5, 0.0, 0.0))).unwrap();
    // Mirrored in x and turned: fronts must stay fronts.
    let mirrored = Mat4::from_translation(Vec3::new(0.2, 0.0, -0.5))
        * Mat4::from_quat(Quat::from_rotation_y(0.7))
        * Mat4::from_scale(Vec3::new(-1.0, 1.2, 1.0));
    scene.place(ball, mirrored).unwrap();
    scene.place_with(ball, Mat4::from_translation(Vec3::new(1.6, 0.0, 0.3)), Some(red)).unwrap();
    // The light: a downward quad placed twice.
    let mut lamp = Scene::default();
    lamp.add(
        &quad(Vec3::ZERO, -Vec3::Y, 0.4),
        Material::diffuse("lamp", Colour::constant(0.0)).unwrap().with_emission(Colour::constant(12.0)),
    );
    let lamp = scene.add_object(lamp, None).unwrap();
    scene.place(lamp, Mat4::from_translation(Vec3::new(-0.8, 3.0, 0.5))).unwrap();
    // Mirrored: it must still shine downwards.
    let mirrored_lamp = Mat4::from_translation(Vec3::new(1.2, 2.5, -0.5))
        * Mat4::from_rotation_x(0.3)
        * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    scene.place(lamp, mirrored_lamp).unwrap();
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 2.5, 6.0), center: Vec3::new(0.0, 0.6, 0.0), up: Vec3::Y, fov_y_deg: 40.0 });
    scene
}

fn render(scene: Scene, seed: u64) -> tracer::Film {
    let prepared = CpuBackend::new(2).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap();
    let settings =
        RenderSettings { width: 40, height: 30, spp: 64, seed, mode: SpectralMode::Rgb, ..Default::default() };
    tracer::render(&prepared, &settings, &|_| {}).unwrap().0
}

#[test]
fn the_scene_knows_its_instances() {
    let scene = instanced_scene();
    scene.validate().unwrap();
    assert!(scene.has_lights());
    assert_eq!((scene.objects.len(), scene.instances.len()), (2, 5));
    let per_ball = scene.objects[0].triangles.len() as u64;
    assert_eq!(scene.instanced_triangle_count(), 3 * per_ball + 2 * 2);
    // The bounds hold every placement (the mirrored ball reaches to x < 0.2 − 0.8).
    let b = scene.bounds();
    assert!(b.min.x < -1.5 && b.max.x > 1.6 + 0.7 && b.max.y >= 3.0, "{b:?}");
    let mut flat = scene.clone();
    flat.flatten_instances();
    assert!(flat.instances.is_empty() && flat.objects.is_empty());
    assert_eq!(flat.triangles.len() as u64, 2 + scene.instanced_triangle_count());
    // Two lamps, two triangles each, found as emitters in both forms.
    let emitters =
        |s: Scene| CpuBackend::new(1).unwrap().prepare_cpu(s, &SceneOptions::default()).unwrap().stats().emitters;
    assert_eq!(emitters(scene), 4);
    assert_eq!(emitters(flat), 4);
}

/// χ²/n of the per-pixel differences between two renders, and how many values differ
/// by more than 4σ.
fn compare(a: &tracer::Film, b: &tracer::Film) -> (f64, usize, usize) {
    let (ma, mb) = (a.mean_rgb(), b.mean_rgb());
    let (ea, eb) = (a.std_error_rgb(), b.std_error_rgb());
    let (mut chi2, mut n, mut far) = (0.0f64, 0, 0);
    for i in 0..ma.len() {
        let var = (ea[i] as f64).powi(2) + (eb[i] as f64).powi(2);
        if var <= 0.0 {
            if ma[i] != mb[i] {
                far += 1;
            }
            continue;
        }
        let z2 = (ma[i] as f64 - mb[i] as f64).powi(2) / var;
        chi2 += z2;
        n += 1;
        if z2 > 16.0 {
            far += 1;
        }
    }
    (chi2 / n as f64, far, n)
}

#[test]
fn instances_render_as_their_flattened_copies() {
    let scene = instanced_scene();
    let mut flat = scene.clone();
    flat.flatten_instances();
    // Independent seeds: the two images differ only by noise. χ²/n ≈ 1 for equal means.
    let (chi2, far, n) = compare(&render(scene, 1), &render(flat, 2));
    assert!(chi2 < 1.3, "χ²/n = {chi2} over {n} values");
    assert!(far <= n / 200, "{far} of {n} values differ by more than 4σ");
}

#[test]
fn the_comparison_sees_a_misplaced_instance() {
    // The check above has teeth: one lamp moved by 0.3, or the mirrored ball unmirrored,
    // and the images differ far beyond their noise.
    let scene = instanced_scene();
    let mut moved = scene.clone();
    moved.instances[3].transform = Mat4::from_translation(Vec3::new(0.3, 0.0, 0.0)) * moved.instances[3].transform;
    let mut unmirrored = scene.clone();
    unmirrored.instances[1].transform *= Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let reference = render(scene, 1);
    for (what, broken) in [("moved lamp", moved), ("unmirrored ball", unmirrored)] {
        broken.validate().unwrap();
        let (chi2, _, n) = compare(&reference, &render(broken, 2));
        assert!(chi2 > 1.5, "{what}: χ²/n = {chi2} over {n} values");
    }
}
