//! The device-resident accumulation (a viewer's frames): the film it gives is, bit for
//! bit, the film a render of the same samples gives — across frames of any size, across
//! the fold at 1024 samples, after a restart and after a resize — and its display pixels
//! are that film's `display_pixels` within one 8-bit step (the GPU's `pow` and f32
//! combination of the folded and pending means). Skipped (with a message) where no
//! adapter exists, unless `SPT_REQUIRE_GPU` is set.

use gpu::GpuBackend;
use gpu::accumulation::DeviceAccumulation;
use std::path::Path;
use std::sync::Arc;
use tracer::render::{RenderSettings, SceneOptions};
use tracer::{Accumulation, Film, PreparedScene, SpectralMode};

const CORNELL: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes/cornell-box/CornellBox-Original.obj");

fn settings(width: u32, height: u32, spp: u32) -> RenderSettings {
    RenderSettings { width, height, spp, seed: 11, mode: SpectralMode::Hero, ..RenderSettings::default() }
}

fn prepared() -> Option<Arc<gpu::GpuScene>> {
    let ctx = gpu::require_gpu()?;
    if !Path::new(CORNELL).exists() {
        eprintln!("skipping: {CORNELL} is absent");
        return None;
    }
    let scene = tracer::obj::load_obj(Path::new(CORNELL)).unwrap();
    Some(Arc::new(GpuBackend::with_context(ctx).prepare_gpu(scene, &SceneOptions::default()).unwrap()))
}

/// The largest difference of any 8-bit channel between two displays.
fn worst_channel_step(a: &[u32], b: &[u32]) -> u32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(&x, &y)| [16, 8, 0].map(|s| ((x >> s) & 0xff).abs_diff((y >> s) & 0xff)))
        .max()
        .unwrap_or(0)
}

/// What the accumulation shows, and what its film's `display_pixels` shows.
fn displays(acc: &mut DeviceAccumulation) -> (Vec<u32>, Vec<u32>) {
    let s = acc.settings().clone();
    let mut shown = vec![0xdead_beef; (s.width * s.height) as usize];
    acc.display(&mut shown).unwrap();
    let mut expected = vec![0; shown.len()];
    acc.film().unwrap().display_pixels(&mut expected);
    (shown, expected)
}

#[test]
fn frames_on_the_device_give_the_films_of_renders() {
    let Some(scene) = prepared() else { return };
    let s = settings(16, 12, 1100);
    let mut acc = DeviceAccumulation::new(Arc::clone(&scene), &s).unwrap();

    // Frames of 1, 3 and 1096 samples: the last crosses the fold at 1024.
    acc.add(1).unwrap();
    acc.add(3).unwrap();
    let (shown, expected) = displays(&mut acc);
    let (four, four_stats) = tracer::render(scene.as_ref(), &RenderSettings { spp: 4, ..s.clone() }, &|_| {}).unwrap();
    assert_eq!(acc.film().unwrap(), four, "4 spp in frames of 1 and 3");
    assert_eq!(acc.counters().unwrap().rays, four_stats.rays);
    assert!(expected.iter().any(|&p| p != 0), "the Cornell box is not black");
    assert!(worst_channel_step(&shown, &expected) <= 1, "display vs film at 4 spp");

    acc.add(1096).unwrap();
    assert_eq!(acc.samples(), 1100);
    let (whole, stats) = tracer::render(scene.as_ref(), &s, &|_| {}).unwrap();
    assert_eq!(acc.film().unwrap(), whole, "1100 spp in frames, folded at 1024");
    assert_eq!(acc.counters().unwrap().rays, stats.rays);
    let (shown, expected) = displays(&mut acc);
    assert!(worst_channel_step(&shown, &expected) <= 1, "display vs film at 1100 spp");

    // A restart forgets everything (the folded means too); a new view renders afresh.
    let moved = RenderSettings { seed: 12, ..s.clone() };
    acc.restart(&moved).unwrap();
    assert_eq!(acc.samples(), 0);
    assert_eq!(acc.film().unwrap(), Film::new(16, 12));
    assert_eq!(acc.counters().unwrap().rays, 0);
    let (shown, _) = displays(&mut acc);
    assert!(shown.iter().all(|&p| p == 0), "a restarted display is black");
    acc.add(2).unwrap();
    let (two, _) = tracer::render(scene.as_ref(), &RenderSettings { spp: 2, ..moved.clone() }, &|_| {}).unwrap();
    assert_eq!(acc.film().unwrap(), two, "after a restart");

    // A resize reallocates.
    let resized = settings(9, 7, 1100);
    acc.restart(&resized).unwrap();
    acc.add(5).unwrap();
    let (five, _) = tracer::render(scene.as_ref(), &RenderSettings { spp: 5, ..resized.clone() }, &|_| {}).unwrap();
    assert_eq!(acc.film().unwrap(), five, "after a resize");
    let (shown, expected) = displays(&mut acc);
    assert!(worst_channel_step(&shown, &expected) <= 1, "display after a resize");
}

#[test]
fn the_gpu_scene_accumulates_on_the_device_and_refuses_what_it_cannot() {
    let Some(scene) = prepared() else { return };
    // Through the trait, as the viewer and `spt bench --frames` use it.
    let s = settings(8, 8, 64);
    let mut acc = (Arc::clone(&scene) as Arc<dyn PreparedScene>).accumulate(&s).unwrap();
    acc.add(3).unwrap();
    let (three, _) = tracer::render(scene.as_ref(), &RenderSettings { spp: 3, ..s.clone() }, &|_| {}).unwrap();
    assert_eq!(acc.film().unwrap(), three);
    let mut wrong = vec![0; 10];
    assert!(acc.display(&mut wrong).is_err(), "a display of the wrong size");

    let crop = tracer::render::PixelRect { x: 0, y: 0, width: 2, height: 2 };
    let err = DeviceAccumulation::new(Arc::clone(&scene), &RenderSettings { crop: Some(crop), ..s.clone() })
        .err()
        .expect("a crop window is refused")
        .to_string();
    assert!(err.contains("crop"), "{err}");
    let deep = RenderSettings { path: tracer::integrator::PathSettings { max_depth: 1000, ..s.path }, ..s.clone() };
    assert!(acc.restart(&deep).is_err(), "1000 bounces are beyond the GPU backend");
    // RGB mode restarts the accumulation with its own kernel: the film of a render in it.
    let rgb = RenderSettings { mode: SpectralMode::Rgb, ..s.clone() };
    acc.restart(&rgb).unwrap();
    acc.add(2).unwrap();
    let (two, _) = tracer::render(scene.as_ref(), &RenderSettings { spp: 2, ..rgb.clone() }, &|_| {}).unwrap();
    assert_eq!(acc.film().unwrap(), two);

    let limits = &scene.context().limits;
    assert!(DeviceAccumulation::fits(limits, 8, 8));
    assert!(!DeviceAccumulation::fits(limits, u32::MAX, u32::MAX));
}
