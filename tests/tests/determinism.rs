//! Same seed, same bytes — whatever the thread count.

use glam::Vec3;
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::material::Material;
use tracer::mesh::{quad, uv_sphere};
use tracer::{CpuBackend, CpuScene, PreparedScene, RenderSettings, Scene, SceneOptions};

/// The test scene, prepared on a CPU backend with `threads` threads.
fn scene(threads: usize) -> CpuScene {
    let mut s = Scene::default();
    let red = Material::diffuse("red", Colour::reflectance_rgb([0.7, 0.1, 0.1]).unwrap()).unwrap();
    let glass = Material::dielectric("glass", 1.5).unwrap();
    let light = Material::diffuse("light", Colour::constant(0.5))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([8.0, 7.0, 5.0]).unwrap());
    s.add(&quad(Vec3::ZERO, Vec3::Y, 2.0), red);
    s.add(&uv_sphere(Vec3::new(0.0, 0.6, 0.0), 0.5, 12, 24, false), glass);
    s.add(&quad(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, 0.5), light);
    s.camera =
        Some(Camera { eye: Vec3::new(0.0, 1.0, 3.0), center: Vec3::new(0.0, 0.5, 0.0), up: Vec3::Y, fov_y_deg: 45.0 });
    CpuBackend::new(threads).unwrap().prepare_cpu(s, &SceneOptions::default()).unwrap()
}

#[test]
fn one_and_two_threads_give_identical_images() {
    let (one, two) = (scene(1), scene(2));
    for mode in SpectralMode::ALL {
        // 37×29 is not a multiple of the tile size: edge tiles are exercised too.
        let settings = RenderSettings { width: 37, height: 29, spp: 8, seed: 1234, mode, ..Default::default() };
        let (a, _) = tracer::render(&one, &settings, &|_| {}).unwrap();
        let (b, _) = tracer::render(&two, &settings, &|_| {}).unwrap();
        let bits =
            |f: &tracer::Film| f.mean_rgb().iter().chain(&f.std_error_rgb()).map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b), "{mode:?}");
        // A different seed must change the image (the test can fail).
        let other = RenderSettings { seed: 1235, ..settings };
        let (c, _) = tracer::render(&two, &other, &|_| {}).unwrap();
        assert_ne!(bits(&a), bits(&c));
    }
}

/// The film's sums are exact: passes in any sizes and any order give the film of one
/// pass, bit for bit (sums, squares and counts), for every sampler; a crop window gives
/// the same pixels as the full image.
#[test]
fn passes_in_any_order_and_crops_equal_one_pass() {
    let prepared = scene(2);
    for sampler in tracer::sampler::SamplerKind::ALL {
        let settings = RenderSettings { width: 21, height: 18, spp: 13, seed: 9, sampler, ..Default::default() };
        let (one, _) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
        let mut film = tracer::Film::new(21, 18);
        for (first, n) in [(9, 4), (0, 1), (3, 6), (1, 2)] {
            prepared.render_pass(&settings, &mut film, first, n, &|_| {}).unwrap();
        }
        assert!(film == one, "{sampler:?}: passes 9..13, 0..1, 3..9, 1..3 differ from one pass");
        let crop = tracer::render::PixelRect { x: 5, y: 17, width: 16, height: 1 };
        let (cropped, stats) =
            tracer::render(&prepared, &RenderSettings { crop: Some(crop), ..settings }, &|_| {}).unwrap();
        assert_eq!(stats.samples, 16 * 13);
        for y in 0..18 {
            for x in 0..21 {
                let expected = if crop.contains(x, y) { *one.pixel(x, y) } else { Default::default() };
                assert_eq!(*cropped.pixel(x, y), expected, "{sampler:?}: pixel ({x}, {y})");
            }
        }
    }
}

/// A viewer's accumulation on the CPU (the trait's default, a film): frames of any size
/// give the film of one render, a restart forgets it, a resize changes the film's size,
/// and its display is the film's `display_pixels`.
#[test]
fn frames_accumulate_to_the_film_of_one_render() {
    let prepared: std::sync::Arc<dyn PreparedScene> = std::sync::Arc::new(scene(2));
    let settings = RenderSettings { width: 21, height: 18, spp: 13, seed: 9, ..Default::default() };
    let mut acc = std::sync::Arc::clone(&prepared).accumulate(&settings).unwrap();
    for n in [1, 4, 8] {
        acc.add(n).unwrap();
    }
    assert_eq!(acc.samples(), 13);
    let (one, stats) = tracer::render(prepared.as_ref(), &settings, &|_| {}).unwrap();
    let film = acc.film().unwrap();
    assert!(film == one, "frames of 1, 4 and 8 samples differ from one 13-spp render");
    assert_eq!(acc.counters().unwrap().rays, stats.rays);
    let (mut shown, mut expected) = (vec![0; 21 * 18], vec![1; 21 * 18]);
    acc.display(&mut shown).unwrap();
    one.display_pixels(&mut expected);
    assert_eq!(shown, expected);
    assert!(shown.iter().any(|&p| p != 0));

    let resized = RenderSettings { width: 5, height: 4, seed: 10, ..settings };
    acc.restart(&resized).unwrap();
    assert_eq!(acc.samples(), 0);
    assert_eq!(acc.film().unwrap(), tracer::Film::new(5, 4));
    acc.add(2).unwrap();
    let (two, _) = tracer::render(prepared.as_ref(), &RenderSettings { spp: 2, ..resized.clone() }, &|_| {}).unwrap();
    assert!(acc.film().unwrap() == two, "after a restart at another size");
    let crop = tracer::render::PixelRect { x: 0, y: 0, width: 1, height: 1 };
    assert!(acc.restart(&RenderSettings { crop: Some(crop), ..resized }).is_err(), "a crop window is refused");
}
