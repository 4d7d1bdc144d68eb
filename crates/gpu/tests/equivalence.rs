//! CPU/GPU equivalence: the same scene and settings rendered by both backends agree
//! statistically — per pixel-channel z = Δ/√(se_cpu² + se_gpu²) within the Šidák-corrected
//! threshold at α = 0.01 for ≥ 99 % of pixel-channels, and image channel means within
//! 1 % — on the Cornell box and on small scenes of glass and of every built-in BSDF
//! model. Plus the GPU backend's errors. Skipped (with a message) where no adapter
//! exists, unless `SPT_REQUIRE_GPU` is set.
//!
//! Each scene is rendered once on the CPU and twice on the GPU:
//!
//! * with the **same seed**: the GPU draws the CPU's own random stream (`Pcg32` per
//!   pixel sample, in the same order), so its paths start as the CPU's and the two
//!   images are strongly correlated — the channel means must agree within 1 % and ≥ 99 %
//!   of pixel-channels pass the z-test (conservative for correlated images);
//! * with **another seed**: independent estimates of the same image — ≥ 99 % of
//!   pixel-channels pass the z-test, and the channel means agree within 4.5 standard
//!   errors (at these sample counts a standard error is ~0.5 %, so "within 1 %" would be
//!   a coin toss for independent images; the same-seed render makes it sharp).
//!
//! Russian roulette makes per-pixel sample distributions heavy-tailed (a few paths carry
//! 1/(1−q) weights), which skews per-pixel z-tests at low sample counts; the renders
//! here use `rr_depth` beyond `max_depth`, so no path is ever rouletted.

use brdf::params::ParamValue;
use glam::Vec3;
use gpu::backend::SceneData;
use gpu::kernel::{GpuIntegrator, KernelOptions, NodeLayout};
use gpu::{GpuBackend, GpuError};
use spectral::spectrum::Colour;
use std::path::Path;
use std::time::Instant;
use tracer::film::{Film, PixelStats};
use tracer::integrator::{PathSettings, ShadingNormals};
use tracer::material::{Material, ModelId};
use tracer::mesh::{quad, uv_sphere};
use tracer::render::{PreparedScene, RenderSettings, SceneOptions};
use tracer::scene::{Environment, Scene};
use tracer::{Camera, SpectralMode};
use tracer::{CpuBackend, CpuScene};

#[path = "../../../tests/tests/common/room.rs"]
mod room;

#[path = "../../tracer/examples/support/phong.rs"]
mod phong;

const CORNELL: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes/cornell-box/CornellBox-Original.obj");

/// How two films compare.
#[derive(Debug)]
struct Comparison {
    /// Fraction of pixel-channels with |z| within the threshold.
    pass_fraction: f64,
    /// The Šidák-corrected threshold.
    z_max: f64,
    /// The worst |z|.
    worst: f64,
    /// Image channel means, CPU and GPU.
    means: [[f64; 3]; 2],
    /// Relative differences of the channel means, GPU vs CPU.
    mean_rel_diff: [f64; 3],
    /// Standard error of each channel mean difference (independent images), relative to
    /// the CPU mean.
    mean_rel_se: [f64; 3],
}

impl Comparison {
    fn summary(&self) -> String {
        format!(
            "{:.2} % of pixel-channels pass |z| ≤ {:.2} (worst {:.2}); channel means cpu {:.4?} gpu {:.4?}, difference \
             {:+.3?} % (s.e. {:.3?} %)",
            100.0 * self.pass_fraction,
            self.z_max,
            self.worst,
            self.means[0],
            self.means[1],
            self.mean_rel_diff.map(|d| 100.0 * d),
            self.mean_rel_se.map(|d| 100.0 * d),
        )
    }

    /// What fails the same-seed criteria (≥ 99 % pass, means within 1 %), if anything.
    fn same_seed_failures(&self) -> Option<String> {
        let bad_mean = self.mean_rel_diff.iter().any(|d| d.abs() > 0.01);
        (self.pass_fraction < 0.99 || bad_mean).then(|| format!("same seed: {}", self.summary()))
    }

    /// What fails the independent-seed criteria (≥ 99 % pass, means within 4.5 s.e.).
    fn independent_failures(&self) -> Option<String> {
        let bad_mean = (0..3).any(|c| self.mean_rel_diff[c].abs() > 4.5 * self.mean_rel_se[c]);
        (self.pass_fraction < 0.99 || bad_mean).then(|| format!("other seed: {}", self.summary()))
    }
}

fn compare(cpu: &Film, gpu: &Film) -> Comparison {
    let n = cpu.pixels().len();
    let tests = 3 * n;
    let z_max = brdf::validation::sidak_z(0.01, tests);
    let (mut pass, mut worst) = (0usize, 0.0f64);
    let mut var_sum = [0.0f64; 3];
    for (a, b) in cpu.pixels().iter().zip(gpu.pixels()) {
        let (sa, sb) = (a.std_error(), b.std_error());
        for c in 0..3 {
            let se = (sa[c] * sa[c] + sb[c] * sb[c]).sqrt();
            var_sum[c] += se * se;
            let d = (a.mean()[c] - b.mean()[c]).abs();
            let z = if se > 0.0 {
                d / se
            } else if d < 1e-6 {
                0.0
            } else {
                f64::INFINITY
            };
            worst = worst.max(z);
            pass += (z <= z_max) as usize;
        }
    }
    let means = [cpu.channel_means(), gpu.channel_means()];
    let mean_rel_diff = std::array::from_fn(|c| (means[1][c] - means[0][c]) / means[0][c]);
    let mean_rel_se = std::array::from_fn(|c| var_sum[c].sqrt() / n as f64 / means[0][c]);
    Comparison { pass_fraction: pass as f64 / tests as f64, z_max, worst, means, mean_rel_diff, mean_rel_se }
}

/// The films and rates of one scene: CPU, GPU with the same seed, GPU with another.
struct Renders {
    cpu: Film,
    same: Film,
    other: Film,
    cpu_rate: f64,
    gpu_rate: f64,
    /// The GPU's kernel compilation and whole preparation.
    compile: std::time::Duration,
    prepare: std::time::Duration,
}

/// `scene` prepared on the CPU (2 threads) and on `gpu` (its kernel for the sampler and
/// spectral mode of `first_render`; `None`: those of the default settings, as [`settings`]'s).
fn prepare_both(
    gpu: &GpuBackend,
    scene: &Scene,
    first_render: Option<&RenderSettings>,
) -> Result<(CpuScene, gpu::GpuScene), tracer::Error> {
    // Both choose emitters by power (as Mitsuba does; both backends' `auto` would take a
    // light tree from 8 emitters, which `the_light_tree_chooses_as_on_the_cpu` tests).
    let options = SceneOptions {
        first_render: first_render.map(|s| (s.sampler, s.mode)),
        light_sampler: tracer::LightSampler::Power,
        ..SceneOptions::default()
    };
    Ok((CpuBackend::new(2)?.prepare_cpu(scene.clone(), &options)?, gpu.prepare_gpu(scene.clone(), &options)?))
}

fn render_three(gpu: &GpuBackend, scene: &Scene, s: &RenderSettings) -> Result<Renders, tracer::Error> {
    let (cpu_scene, gpu_scene) = prepare_both(gpu, scene, Some(s))?;
    render_three_with(&cpu_scene, &gpu_scene, s)
}

/// [`render_three`] of scenes already prepared (on backends running another integrator).
fn render_three_with(
    cpu_scene: &dyn PreparedScene,
    gpu_scene: &gpu::GpuScene,
    s: &RenderSettings,
) -> Result<Renders, tracer::Error> {
    let samples = (s.width * s.height * s.spp) as f64;
    let timed = |p: &dyn PreparedScene, s: &RenderSettings| -> Result<(Film, f64), tracer::Error> {
        let start = Instant::now();
        let (film, _) = tracer::render(p, s, &|_| {})?;
        Ok((film, samples / start.elapsed().as_secs_f64()))
    };
    // One sample first, so that the GPU timing excludes the driver's first-dispatch work.
    gpu_scene.render_pass(s, &mut Film::new(s.width, s.height), 0, 1, &|_| {})?;
    let (cpu, cpu_rate) = timed(cpu_scene, s)?;
    let (same, gpu_rate) = timed(gpu_scene, s)?;
    let (other, _) = timed(gpu_scene, &RenderSettings { seed: s.seed + 1000, ..s.clone() })?;
    let (compile, prepare) = (gpu_scene.compile_time(), gpu_scene.prepare_time());
    Ok(Renders { cpu, same, other, cpu_rate, gpu_rate, compile, prepare })
}

/// Compares the renders of one scene; prints both comparisons and returns the failures.
fn compare_all(name: &str, r: &Renders) -> Vec<String> {
    let same = compare(&r.cpu, &r.same);
    let other = compare(&r.cpu, &r.other);
    println!("{name}, same seed: {}", same.summary());
    println!("{name}, other seed: {}", other.summary());
    println!(
        "{name}: non-finite samples cpu {}, gpu {} and {}",
        r.cpu.non_finite, r.same.non_finite, r.other.non_finite
    );
    [same.same_seed_failures(), other.independent_failures()]
        .into_iter()
        .flatten()
        .map(|f| format!("{name}: {f}"))
        .collect()
}

/// Depth 8 without Russian roulette (see the module docs).
fn settings(width: u32, height: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp,
        seed: 7,
        mode: SpectralMode::Hero,
        path: PathSettings { max_depth: 8, rr_depth: 100, ..PathSettings::default() },
        ..RenderSettings::default()
    }
}

fn cornell() -> Option<Scene> {
    if !Path::new(CORNELL).exists() {
        eprintln!("skipping: {CORNELL} is absent");
        return None;
    }
    Some(tracer::obj::load_obj(Path::new(CORNELL)).unwrap())
}

#[test]
fn cornell_box_matches_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    println!("adapter: {} ({:?})", ctx.info.name, ctx.info.backend);
    let gpu = GpuBackend::with_context(ctx);
    let s = settings(48, 48, 256);
    let r = render_three(&gpu, &scene, &s).unwrap();
    println!(
        "Cornell box {}×{} at {} spp: cpu (2 threads) {:.0} samples/s, gpu {:.0} samples/s; shader compile and \
         pipeline {:?}, scene preparation {:?}",
        s.width, s.height, s.spp, r.cpu_rate, r.gpu_rate, r.compile, r.prepare,
    );
    let failures = compare_all("Cornell box", &r);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A small preview scene: a low-polygon sphere of `material` (smooth normals, tangents
/// along the parallels) on a coloured floor, under a warm area light and a dim sky.
fn model_scene(material: Material) -> Scene {
    let mut scene = Scene::default();
    scene.add(&uv_sphere(Vec3::new(0.0, 1.0, 0.0), 1.0, 10, 20, false), material);
    let floor = Material::diffuse("floor", Colour::reflectance_rgb([0.6, 0.45, 0.3]).unwrap()).unwrap();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 3.0), floor);
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([5.0, 4.5, 3.5]).unwrap());
    let mut light = quad(Vec3::new(-1.5, 4.0, 1.5), -Vec3::Y, 1.0);
    light.normals.clear();
    scene.add(&light, lamp);
    scene.environment = Some(Environment::uniform(Colour::constant(0.3)));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 2.0, 3.6), center: Vec3::new(0.0, 0.9, 0.0), up: Vec3::Y, fov_y_deg: 40.0 });
    scene
}

/// Every built-in model at its defaults, plus a dispersive (N-BK7), absorbing glass.
fn model_cases() -> Vec<(String, Material)> {
    let mut v: Vec<_> = ModelId::ALL
        .iter()
        .copied()
        .map(|m| (m.def().name.to_string(), Material::builtin(m.def().name, m, &[]).unwrap()))
        .collect();
    let glass = Material::builtin(
        "dispersive glass",
        ModelId::Dielectric,
        &[("dispersion", ParamValue::Scalar(2.0)), ("absorption", ParamValue::Rgb([0.4, 0.15, 0.05]))],
    )
    .unwrap();
    v.push(("dispersive absorbing glass".into(), glass));
    v
}

/// Every case of [`model_cases`] in [`model_scene`], each scene holding the other cases'
/// materials too (unused): their kernels are then one source, compiled once and kept by
/// the test's device (lavapipe takes tens of seconds a kernel; each model's specialised
/// kernel alone is validated by naga in `materials.rs`).
fn model_case_scenes() -> Vec<(String, Scene)> {
    let cases = model_cases();
    let materials: Vec<Material> = cases.iter().map(|(_, m)| m.clone()).collect();
    cases
        .into_iter()
        .map(|(name, m)| {
            let mut scene = model_scene(m);
            scene.materials.extend(materials.iter().cloned());
            (name, scene)
        })
        .collect()
}

#[test]
fn every_model_and_glass_match_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let s = settings(32, 32, 128);
    let mut failures = Vec::new();
    for (name, scene) in model_case_scenes() {
        match render_three(&gpu, &scene, &s) {
            Ok(r) => {
                println!(
                    "{name}: cpu {:.0} samples/s, gpu {:.0} samples/s, compile {:?}",
                    r.cpu_rate, r.gpu_rate, r.compile
                );
                failures.extend(compare_all(&name, &r));
            }
            Err(e) => {
                println!("{name}: {e}");
                failures.push(format!("{name}: {e}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The integrator's other settings, on glass with smooth normals (where the shading-normal
/// modes differ most): same seed only, which replicates the CPU's paths closely enough
/// that few samples suffice.
#[test]
fn path_settings_match_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let (cpu, gpu) = prepare_both(&gpu, &model_scene(Material::dielectric("glass", 1.5).unwrap()), None).unwrap();
    let base = settings(32, 32, 64);
    let variants = [
        ("face-forward normals", PathSettings { shading_normals: ShadingNormals::FaceForward, ..base.path }),
        ("geometric normals", PathSettings { shading_normals: ShadingNormals::Geometric, ..base.path }),
        ("unbounded depth, roulette from 3", PathSettings::default()),
        ("depth 2, specular extension 3", PathSettings { max_depth: 2, specular_extension: 3, ..base.path }),
    ];
    let mut failures = Vec::new();
    for (name, path) in variants {
        let s = RenderSettings { path, ..base.clone() };
        let (a, _) = tracer::render(&cpu, &s, &|_| {}).unwrap();
        let (b, _) = tracer::render(&gpu, &s, &|_| {}).unwrap();
        let c = compare(&a, &b);
        println!("{name}: {}", c.summary());
        failures.extend(c.same_seed_failures().map(|f| format!("{name}: {f}")));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn max_diffuse_depth_ends_paths_as_on_the_cpu() {
    // One diffuse bounce: direct light only (the second hit's emission, then the end).
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let (cpu, gpu) = prepare_both(&GpuBackend::with_context(ctx), &scene, None).unwrap();
    let base = settings(32, 32, 64);
    let limited = RenderSettings { path: PathSettings { max_diffuse_depth: 1, ..base.path }, ..base.clone() };
    let (a, _) = tracer::render(&cpu, &limited, &|_| {}).unwrap();
    let (b, _) = tracer::render(&gpu, &limited, &|_| {}).unwrap();
    let c = compare(&a, &b);
    println!("diffuse depth 1: {}", c.summary());
    assert!(c.same_seed_failures().is_none(), "{:?}", c.same_seed_failures());
    // The limit took the indirect light away on the GPU too.
    let (full, _) = tracer::render(&gpu, &base, &|_| {}).unwrap();
    let total = |f: &Film| f.pixels().iter().map(|p| p.mean().iter().sum::<f64>()).sum::<f64>();
    let ratio = total(&b) / total(&full);
    assert!(ratio < 0.85, "with one diffuse bounce the image keeps {ratio:.3} of its light");
}

#[test]
fn every_bvh_builder_renders_the_cpus_image() {
    // `--bvh-builder`: the GPU's binary tree built by each split method; the same paths as
    // the CPU's (its wide tree collapsed from a tree built the same way).
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let s = settings(32, 32, 16);
    let mut failures = Vec::new();
    // The trees differ (the option reaches the build through the options `prepare_gpu`
    // uploads with): the midpoint split's nodes are not the SAH's.
    let nodes = |method| {
        let options = SceneOptions { bvh_builder: Some(method), ..SceneOptions::default() };
        SceneData::new(&scene, gpu.kernel_options(&options)).unwrap().node_bytes().to_vec()
    };
    assert_ne!(nodes(bvh::SplitMethod::Midpoint), nodes(bvh::SplitMethod::BinnedSah));
    // (Binned SAH, the default, is in every other test; the hybrid mixes these two.)
    for method in [bvh::SplitMethod::SweepSah, bvh::SplitMethod::Midpoint] {
        let options = SceneOptions { bvh_builder: Some(method), ..SceneOptions::default() };
        let cpu = CpuBackend::new(2).unwrap().prepare_cpu(scene.clone(), &options).unwrap();
        let prepared = gpu.prepare_gpu(scene.clone(), &options).unwrap();
        let (a, _) = tracer::render(&cpu, &s, &|_| {}).unwrap();
        let (b, _) = tracer::render(&prepared, &s, &|_| {}).unwrap();
        let c = compare(&a, &b);
        println!("{}: {}", method.name(), c.summary());
        failures.extend(c.same_seed_failures().map(|f| format!("{}: {f}", method.name())));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn passes_bands_and_reruns_add_up() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let device = ctx.clone();
    let Some(scene) = cornell() else { return };
    // Accumulators limited to the largest scene buffer (at least 8 KiB): an image of
    // twice that many rows and a bit is rendered in three bands.
    let largest =
        SceneData::new(&scene, KernelOptions::default()).unwrap().buffer_sizes().iter().map(|b| b.1).max().unwrap();
    let limit = largest.max(8 << 10);
    let rows_per_band = ((limit - 16) / (32 * 32)) as u32;
    let s = settings(32, 2 * rows_per_band + 3, 16);
    let limits = wgpu::Limits { max_storage_buffer_binding_size: limit, ..ctx.limits.clone() };
    let prepared = GpuBackend::with_context(ctx).prepare_gpu(scene.clone(), &SceneOptions::default()).unwrap();
    let (whole, _) = tracer::render(&prepared, &s, &|_| {}).unwrap();
    let (again, _) = tracer::render(&prepared, &s, &|_| {}).unwrap();
    assert_eq!(device.compiled_kernels(), 1, "the default settings' kernel, compiled while preparing");
    assert_eq!(whole, again, "a seed must give the same image");
    // Two passes of 8 samples: the same samples, grouped differently.
    let mut split = Film::new(s.width, s.height);
    let counted = std::sync::atomic::AtomicU64::new(0);
    let progress = |n: u64| {
        counted.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    };
    prepared.render_pass(&s, &mut split, 0, 8, &progress).unwrap();
    prepared.render_pass(&s, &mut split, 8, 8, &progress).unwrap();
    assert_eq!(counted.into_inner(), whole.samples());
    assert_eq!(split.samples(), whole.samples());
    for (a, b) in split.pixels().iter().zip(whole.pixels()) {
        for c in 0..3 {
            assert!((a.mean()[c] - b.mean()[c]).abs() <= 1e-5 * b.mean()[c].abs().max(1e-3), "{a:?} vs {b:?}");
            assert!((a.m2()[c] - b.m2()[c]).abs() <= 1e-4 * b.m2()[c].abs().max(1e-3), "{a:?} vs {b:?}");
        }
    }
    // Banded: the same pixels, bit for bit.
    // A clone of the device with lower limits: the kernel compiled above is reused.
    let mut ctx = device.clone();
    ctx.limits = limits;
    let banded = GpuBackend::with_context(ctx);
    let banded = banded.prepare_gpu(scene, &SceneOptions::default()).unwrap();
    let (bands, stats) = tracer::render(&banded, &s, &|_| {}).unwrap();
    assert_eq!(device.compiled_kernels(), 1, "the same scene compiled its kernel again");
    assert_eq!(bands, whole, "bands of rows must not change the image");
    assert!(stats.rays >= stats.samples, "{} rays for {} samples", stats.rays, stats.samples);
}

/// Long passes are read back and merged at every multiple of `SAMPLES_PER_READBACK` in the
/// sample index: one pass of 1100 samples is, bit for bit, a pass of 1024 and one of 76
/// (whichever runs first); a crop window is, bit for bit, the same pixels of the image.
#[test]
fn long_passes_are_merged_in_groups() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let gpu = GpuBackend::with_context(ctx).prepare_gpu(scene, &SceneOptions::default()).unwrap();
    let s = settings(8, 8, 1100);
    assert_eq!(gpu::backend::SAMPLES_PER_READBACK, 1024);
    let (one, _) = tracer::render(&gpu, &s, &|_| {}).unwrap();
    let mut two = Film::new(8, 8);
    gpu.render_pass(&s, &mut two, 1024, 76, &|_| {}).unwrap();
    gpu.render_pass(&s, &mut two, 0, 1024, &|_| {}).unwrap();
    assert_eq!(one, two);
    let crop = tracer::render::PixelRect { x: 2, y: 3, width: 5, height: 4 };
    let (cropped, stats) = tracer::render(&gpu, &RenderSettings { crop: Some(crop), ..s.clone() }, &|_| {}).unwrap();
    assert_eq!(stats.samples, 20 * 1100);
    for y in 0..8 {
        for x in 0..8 {
            let expected = if crop.contains(x, y) { *one.pixel(x, y) } else { PixelStats::default() };
            assert_eq!(*cropped.pixel(x, y), expected, "pixel ({x}, {y})");
        }
    }
}

#[test]
fn unsupported_scenes_and_modes_are_clear_errors() {
    // Implicit surfaces need f64 in the kernel: accepted on a device with SHADER_F64 (what
    // `capabilities` describes), refused on one without; spheres, boxes and polygons always.
    let torus = tracer::scenes::glass_torus(shapes::roots::RootSolver::ClosedForm).unwrap();
    let data = SceneData::new(&torus, KernelOptions::default()).unwrap();
    assert_eq!(data.options().implicit_coeffs, 5, "a quartic's arrays");
    let caps = gpu::backend::capabilities();
    caps.check_scene(&torus, &SceneOptions::default()).unwrap();
    let mut without_f64 = caps.clone();
    without_f64.analytic_shapes.kinds.retain(|k| *k != "implicit surface");
    let err = without_f64.check_scene(&torus, &SceneOptions::default()).unwrap_err().to_string();
    assert!(err.contains("implicit surface (1 in this scene)") && err.contains("--backend cpu"), "{err}");
    assert!(err.contains("SHADER_F64"), "{err}");
    let flake = tracer::scenes::sphere_flake(1).unwrap();
    caps.check_scene(&flake, &SceneOptions::default()).unwrap();
    SceneData::new(&flake, KernelOptions::default()).unwrap();
    // A scene of shapes alone has an empty triangle tree at every width.
    for nodes in [NodeLayout::Wide4 { stack: 0 }, NodeLayout::Wide8 { stack: 0 }] {
        let data = SceneData::new(&flake, KernelOptions { nodes, ..KernelOptions::default() }).unwrap();
        assert!(data.node_bytes().is_empty(), "{nodes:?}");
    }
    // The kernel traverses a binary, 4-wide or 8-wide BVH: every width is accepted.
    let room = tracer::scenes::material_sphere(Material::diffuse("grey", Colour::constant(0.5)).unwrap());
    for width in [bvh::BvhWidth::Auto, bvh::BvhWidth::Two, bvh::BvhWidth::Four, bvh::BvhWidth::Eight] {
        caps.check_scene(&room, &SceneOptions { bvh_width: width, ..SceneOptions::default() }).unwrap();
    }
    // The path tracer, direct light and the atlas choose emitters by a light tree where
    // asked (as on the CPU); Whitted, bdpt and ambient occlusion by power only: a tree is
    // refused there with the way out, power and auto (which means power there) accepted.
    let light = |light_sampler| SceneOptions { light_sampler, ..SceneOptions::default() };
    for sampler in [tracer::LightSampler::Tree, tracer::LightSampler::Power, tracer::LightSampler::Auto] {
        caps.check_scene(&room, &light(sampler)).unwrap();
    }
    for integrator in [GpuIntegrator::Direct, GpuIntegrator::Atlas(Default::default())] {
        gpu::backend::capabilities_for(integrator).check_scene(&room, &light(tracer::LightSampler::Tree)).unwrap();
    }
    for integrator in
        [GpuIntegrator::Whitted, GpuIntegrator::Bdpt, GpuIntegrator::AmbientOcclusion { max_distance: 1.0 }]
    {
        let by_power = gpu::backend::capabilities_for(integrator);
        let err = by_power.check_scene(&room, &light(tracer::LightSampler::Tree)).unwrap_err().to_string();
        assert!(err.contains("light tree") && err.contains("--light-sampler"), "{err}");
        by_power.check_scene(&room, &light(tracer::LightSampler::Power)).unwrap();
        by_power.check_scene(&room, &light(tracer::LightSampler::Auto)).unwrap();
    }
    // Textures and environment maps are read.
    let mut textured = room.clone();
    let image = std::sync::Arc::new(tracer::texture::TextureImage::from_rgba8(1, 1, vec![[9, 9, 9, 255]]).unwrap());
    let map = tracer::texture::TextureMap::new(image, tracer::texture::Encoding::Srgb);
    let textures = tracer::texture::MaterialTextures { base_colour: Some(map), ..Default::default() };
    textured.materials[0] = textured.materials[0].clone().with_textures(textures);
    caps.check_scene(&textured, &SceneOptions::default()).unwrap();
    let sky = tracer::envmap::EnvironmentMap::new(2, 1, vec![[1.0, 0.5, 0.25], [0.2, 0.3, 0.4]], 0.0).unwrap();
    textured.environment = Some(Environment::from_map(sky, 1.0));
    caps.check_scene(&textured, &SceneOptions::default()).unwrap();
    let s = settings(8, 8, 1);
    caps.check_settings(&RenderSettings { mode: SpectralMode::Rgb, ..s.clone() }).unwrap();
    caps.check_settings(&RenderSettings { mode: SpectralMode::Bins40, ..s.clone() }).unwrap();
    println!("{err}");
    let deep = RenderSettings { path: PathSettings { max_depth: 1000, ..s.path }, ..s.clone() };
    let err = caps.check_settings(&deep).unwrap_err().to_string();
    assert!(err.contains("1000 bounces") && err.contains("256"), "{err}");
    for sampler in tracer::sampler::SamplerKind::ALL {
        caps.check_settings(&RenderSettings { sampler, ..s.clone() }).unwrap();
    }
    let unbounded = RenderSettings { path: PathSettings { max_depth: 0, ..s.path }, ..s.clone() };
    assert!(caps.check_settings(&unbounded).is_ok(), "an unbounded depth is traced, truncations counted");
    // The path tracer's cap counts --extension; Whitted's stack counts only its depth,
    // as its recursion ignores the extension.
    let with_extension = |max_depth, specular_extension| RenderSettings {
        path: PathSettings { max_depth, specular_extension, ..s.path },
        ..s.clone()
    };
    let err = caps.check_settings(&with_extension(250, 10)).unwrap_err().to_string();
    assert!(err.contains("260 bounces") && err.contains("--extension"), "{err}");
    let whitted = gpu::backend::capabilities_for(GpuIntegrator::Whitted);
    let max = gpu::kernel::WHITTED_MAX_DEPTH;
    whitted.check_settings(&with_extension(max, 10)).unwrap();
    let err = whitted.check_settings(&with_extension(max + 1, 0)).unwrap_err().to_string();
    assert!(err.contains(&format!("--max-depth {max} or less")) && !err.contains("--extension"), "{err}");
    // Direct lighting reads neither: its cap is the path tracer's, without the extension.
    let direct = gpu::backend::capabilities_for(GpuIntegrator::Direct);
    direct.check_settings(&with_extension(250, 10)).unwrap();
    // Only bdpt's light paths splat onto other pixels (which a band of rows cannot hold).
    for integrator in [GpuIntegrator::Path, GpuIntegrator::Direct, GpuIntegrator::Whitted, GpuIntegrator::Bdpt] {
        let splats = gpu::backend::capabilities_for(integrator).splats;
        assert_eq!(splats, integrator == GpuIntegrator::Bdpt, "{}", integrator.name());
    }
    // The same refusals through a device: before any upload or compilation.
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let on_device = tracer::Backend::capabilities(&gpu);
    let implicit = on_device.analytic_shapes.kinds.contains(&"implicit surface");
    assert_eq!(implicit, gpu.context().shader_f64(), "{:?}", on_device.analytic_shapes.kinds);
    let scene = model_scene(Material::diffuse("grey", Colour::constant(0.5)).unwrap());
    let prepared = gpu.prepare_gpu(scene, &SceneOptions::default()).unwrap();
    let deep = RenderSettings { path: PathSettings { max_depth: 1000, ..s.path }, ..s.clone() };
    let err = tracer::render(&prepared, &deep, &|_| {}).unwrap_err().to_string();
    assert!(err.contains("1000 bounces") && err.contains("--backend cpu"), "{err}");
}

#[test]
fn buffers_beyond_the_limits_are_named() {
    let scene = model_scene(Material::diffuse("grey", Colour::constant(0.5)).unwrap());
    let data = SceneData::new(&scene, KernelOptions::default()).unwrap();
    assert!(data.check_limits(&wgpu::Limits::default()).is_ok());
    let tiny = wgpu::Limits { max_storage_buffer_binding_size: 4096, ..wgpu::Limits::default() };
    let err = data.check_limits(&tiny).unwrap_err();
    let needed = data.buffer_sizes().iter().find(|(_, n)| *n > 4096).unwrap().1;
    assert!(matches!(err, GpuError::Limit { limit_name: "max_storage_buffer_binding_size", limit: 4096, .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.contains("max_storage_buffer_binding_size") && msg.contains(&needed.to_string()), "{msg}");
    println!("{msg}");
    let small = wgpu::Limits { max_buffer_size: 2048, ..wgpu::Limits::default() };
    assert!(data.check_limits(&small).unwrap_err().to_string().contains("max_buffer_size"));
    let few = wgpu::Limits { max_storage_buffers_per_shader_stage: 4, ..wgpu::Limits::default() };
    assert!(data.check_limits(&few).unwrap_err().to_string().contains("max_storage_buffers_per_shader_stage"));
}

/// The GPU's per-pass statistics (count, mean, M2) become the film's sums through
/// `PixelStats::from_moments`: merged passes agree with adding every sample.
#[test]
fn merging_pass_statistics_equals_adding_every_sample() {
    let xs: Vec<[f32; 3]> = (0..37).map(|i| [(i as f32 * 0.37).sin(), (i * i % 11) as f32, 2.0]).collect();
    let mut all = PixelStats::default();
    xs.iter().for_each(|&x| assert!(all.add(x)));
    let mut merged = PixelStats::default();
    for chunk in xs.chunks(10) {
        let mut pass = PixelStats::default();
        chunk.iter().for_each(|&x| assert!(pass.add(x)));
        merged.merge(&PixelStats::from_moments(pass.count, pass.mean(), pass.m2()));
    }
    merged.merge(&PixelStats::default());
    assert_eq!(merged.count, all.count);
    for c in 0..3 {
        assert!((merged.mean()[c] - all.mean()[c]).abs() < 1e-12);
        assert!((merged.m2()[c] - all.m2()[c]).abs() < 1e-9 * all.m2()[c].max(1.0));
    }
}

/// `--triangle-test moller-trumbore` is honoured on the GPU: the kernel compiled with it
/// matches the CPU's Möller–Trumbore render of the same seed.
#[test]
fn moller_trumbore_matches_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let options = SceneOptions { triangle_test: bvh::TriangleTest::MollerTrumbore, ..SceneOptions::default() };
    let cpu = CpuBackend::new(2).unwrap().prepare_cpu(scene.clone(), &options).unwrap();
    let gpu = GpuBackend::with_context(ctx).prepare_gpu(scene, &options).unwrap();
    let s = settings(32, 32, 64);
    let (a, _) = tracer::render(&cpu, &s, &|_| {}).unwrap();
    let (b, _) = tracer::render(&gpu, &s, &|_| {}).unwrap();
    let c = compare(&a, &b);
    println!("Möller–Trumbore, same seed: {}", c.summary());
    assert!(c.same_seed_failures().is_none(), "{}", c.summary());
}

/// An "unbounded" depth is never silently cut: in a closed white room without Russian
/// roulette every GPU path reaches the bounce cap, and every one is counted; with
/// roulette (the default) none does.
#[test]
fn paths_cut_by_the_bounce_cap_are_counted() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let mut room = Scene::default();
    let walls = Material::diffuse("walls", Colour::constant(0.9))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([0.1; 3]).unwrap());
    // A closed cube, faces inward (its quads' fronts face the centre).
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        for sign in [-1.0, 1.0] {
            room.add(&quad(axis * sign, -axis * sign, 1.0), walls.clone());
        }
    }
    room.camera = Some(Camera { eye: Vec3::ZERO, center: -Vec3::Z, up: Vec3::Y, fov_y_deg: 60.0 });
    let gpu = GpuBackend::with_context(ctx).prepare_gpu(room, &SceneOptions::default()).unwrap();
    let no_roulette = PathSettings { max_depth: 0, rr_depth: u32::MAX, ..PathSettings::default() };
    let s = RenderSettings { path: no_roulette, ..settings(4, 4, 2) };
    let (_, stats) = tracer::render(&gpu, &s, &|_| {}).unwrap();
    assert_eq!(stats.truncated, stats.samples, "every path reaches the cap");
    let s = RenderSettings { path: PathSettings::default(), ..settings(4, 4, 2) };
    let (_, stats) = tracer::render(&gpu, &s, &|_| {}).unwrap();
    assert_eq!(stats.truncated, 0);
}

/// 4000 small grey triangles scattered through a box, seen from inside it under a white
/// sky: rays cross many overlapping boxes, so wide nodes have many children entered at once
/// and the traversal's ordering and stack are exercised (a Cornell box's 8-wide tree is a
/// root with leaf children).
fn triangle_cloud() -> Scene {
    let mut state = 12_345u32;
    let mut next = || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut mesh = tracer::mesh::Mesh::default();
    for i in 0..4000u32 {
        let c = Vec3::new(next(), next(), next()) * 10.0 - Vec3::splat(5.0);
        let a = Vec3::new(next(), next(), next()) - Vec3::splat(0.5);
        let b = Vec3::new(next(), next(), next()) - Vec3::splat(0.5);
        mesh.positions.extend([c, c + a * 0.8, c + b * 0.8]);
        mesh.triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let mut scene = Scene::default();
    scene.add(&mesh, Material::diffuse("grey", Colour::constant(0.6)).unwrap());
    scene.environment = Some(Environment::uniform(Colour::constant(1.0)));
    scene.camera = Some(Camera { eye: Vec3::new(-4.0, 0.5, -4.5), center: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 60.0 });
    scene
}

/// The 4- and 8-wide BVHs (`--bvh-width 4`, `8`) and the binary one they are collapsed
/// from (the default) find the same hits: the same image, bit for bit, on the Cornell box
/// and on a smooth glass sphere (refraction, shading normals).
#[test]
fn wide_and_binary_bvhs_give_the_same_image() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(cornell) = cornell() else { return };
    let backend = GpuBackend::with_context(ctx.clone());
    let glass = tracer::scenes::material_sphere(Material::dielectric("glass", 1.5).unwrap());
    for (name, scene) in [("Cornell box", cornell), ("glass sphere", glass), ("triangle cloud", triangle_cloud())] {
        let compiled_before = ctx.kernels_compiled();
        // (Kept while the loop runs: auto's kernel is the binary tree's, which the device
        // finds again while a scene holds it, however many kernels were compiled since.)
        let mut scenes = Vec::new();
        // Depth 5 without roulette: the depth at which a traversal with slot loops lost
        // rays on lavapipe (see crates/gpu/src/wide.rs).
        let s =
            RenderSettings { path: PathSettings { max_depth: 5, ..settings(24, 24, 16).path }, ..settings(24, 24, 16) };
        let mut films = Vec::new();
        let widths = [
            (bvh::BvhWidth::Two, "binary BVH"),
            (bvh::BvhWidth::Four, "4-wide BVH"),
            (bvh::BvhWidth::Eight, "8-wide BVH"),
            (bvh::BvhWidth::Auto, "binary BVH"),
        ];
        for (width, expected) in widths {
            let options = SceneOptions { bvh_width: width, ..SceneOptions::default() };
            let prepared = backend.prepare_gpu(scene.clone(), &options).unwrap();
            assert_eq!(prepared.stats().accelerator, expected);
            films.push(tracer::render(&prepared, &s, &|_| {}).unwrap());
            scenes.push(prepared);
        }
        assert_eq!(ctx.kernels_compiled() - compiled_before, 3, "{name}: one kernel per width, auto's reused");
        assert!(films[0].0.samples() > 0);
        assert!(films[0].0 == films[1].0, "{name}: the 4-wide BVH's image differs from the binary's");
        assert!(films[0].0 == films[2].0, "{name}: the 8-wide BVH's image differs from the binary's");
        assert!(films[0].0 == films[3].0, "{name}: auto is the binary BVH");
        assert_eq!(films[0].1.rays, films[1].1.rays, "{name}: ray counts");
        assert_eq!(films[0].1.rays, films[2].1.rays, "{name}: ray counts");
    }
}

/// The biased integrators compiled into the kernel (`--integrator direct|ao --backend
/// gpu`) match the CPU's `DirectLighting` and `AmbientOcclusion` on the Cornell box: the
/// same z-tests and channel-mean checks as the path tracer's.
#[test]
fn direct_lighting_and_ambient_occlusion_match_the_cpu() {
    use tracer::{AmbientOcclusion, Backend, DirectLighting};
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let s = settings(32, 32, 128);
    let reach = 150.0; // the box is 550 wide: some corners occluded, the open middle not
    let cases: [(&str, GpuIntegrator, Box<dyn Backend>); 2] = [
        ("direct", GpuIntegrator::Direct, Box::new(CpuBackend::with_integrator(2, DirectLighting).unwrap())),
        (
            "ao",
            GpuIntegrator::AmbientOcclusion { max_distance: reach },
            Box::new(CpuBackend::with_integrator(2, AmbientOcclusion::new(reach)).unwrap()),
        ),
    ];
    let mut failures = Vec::new();
    for (name, integrator, cpu) in cases {
        let options = SceneOptions::default();
        let cpu_scene = cpu.prepare(scene.clone(), &options).unwrap();
        let backend = GpuBackend::with_context(ctx.clone()).with_integrator(integrator);
        assert_eq!(backend.capabilities().integrator, name);
        let gpu_scene = backend.prepare_gpu(scene.clone(), &options).unwrap();
        let r = render_three_with(cpu_scene.as_ref(), &gpu_scene, &s).unwrap();
        assert!(r.cpu.channel_means()[1] > 0.01, "{name}: a black image proves nothing");
        failures.extend(compare_all(&format!("Cornell box, {name}"), &r));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A black emitter of linear-sRGB radiance `rgb`.
fn lamp(name: &str, rgb: [f32; 3]) -> Material {
    Material::diffuse(name, Colour::constant(0.0)).unwrap().with_emission(Colour::illuminant_rgb(rgb).unwrap())
}

/// A hall for the light tree: a floor and a back wall under a 4 × 4 grid of small lamps
/// facing down (powers varying fourfold, large and low enough that BSDF samples find them,
/// so that a wrong MIS weight for those hits shows), a glowing ball (an analytic shape in
/// the tree), a point light and a spot (in the tree too), a sun and a dim sky (which keep
/// their shares of the choice beside the tree's). The sun comes first in the scene's
/// lights, the light table puts it after the spot and the point light.
fn lamp_hall() -> Scene {
    let mut scene = Scene::default();
    let grey = Material::diffuse("grey", Colour::constant(0.6)).unwrap();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 5.0), grey.clone());
    scene.add(&quad(Vec3::new(0.0, 2.0, -5.0), Vec3::Z, 5.0), grey);
    for i in 0..4 {
        for j in 0..4 {
            let s = 2.0 * (1 + (i * 3 + j) % 4) as f32;
            let centre = Vec3::new(-3.6 + 2.4 * i as f32, 0.8, -3.6 + 2.4 * j as f32);
            let rgb = [[1.0, 0.75, 0.45], [0.55, 0.7, 1.0]][(i + j) % 2].map(|c| c * s);
            scene.add(&quad(centre, -Vec3::Y, 0.4), lamp(&format!("lamp{i}{j}"), rgb));
        }
    }
    let ball = shapes::sphere::Sphere::new(Vec3::new(1.2, 0.3, 1.0), 0.3, Default::default()).unwrap();
    scene.add_shape(tracer::ShapeKind::Sphere(ball), lamp("ball", [2.0, 1.5, 1.0]));
    let sun = Colour::illuminant_rgb([0.05, 0.045, 0.04]).unwrap();
    scene.punctual_lights.push(tracer::PunctualLight::directional(Vec3::new(0.3, -1.0, -0.4), sun));
    let spot = Colour::illuminant_rgb([4.0, 3.0, 2.0]).unwrap();
    let aim = Vec3::new(0.5, -1.0, 0.2);
    scene.punctual_lights.push(tracer::PunctualLight::spot(Vec3::new(0.6, 1.5, -1.0), aim, spot, 0.4, 0.7));
    scene
        .punctual_lights
        .push(tracer::PunctualLight::point(Vec3::new(-2.0, 3.0, 2.0), Colour::illuminant_rgb([3.0; 3]).unwrap()));
    scene.environment = Some(Environment::uniform(Colour::illuminant_rgb([0.01, 0.014, 0.02]).unwrap()));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 2.5, 6.5), center: Vec3::new(0.0, 0.3, 0.0), up: Vec3::Y, fov_y_deg: 60.0 });
    scene
}

/// `--light-sampler tree` on the GPU: the path tracer (megakernel and wavefront) and
/// direct light choose emitters, point and spot lights by the CPU's light tree (its nodes, walk and trails in
/// `wgsl/lights.wgsl`), so that same-seed renders follow the CPU's paths — which the GPU's
/// power sampling, unbiased too, does not (checked: the test can tell them apart) — and
/// other seeds pass the z-tests. The path tracer's MIS weights of lamps hit by BSDF samples
/// read the tree's probability from the previous vertex.
#[test]
fn the_light_tree_chooses_as_on_the_cpu() {
    use tracer::{Backend, DirectLighting, LightSampler};
    let Some(ctx) = gpu::require_gpu() else { return };
    let scene = lamp_hall();
    let s = settings(24, 18, 64);
    let by = |light_sampler| SceneOptions { light_sampler, ..SceneOptions::default() };
    let path = GpuBackend::with_context(ctx.clone());
    let cpu_path = CpuBackend::new(2).unwrap().prepare_cpu(scene.clone(), &by(LightSampler::Tree)).unwrap();
    let cpu_direct = CpuBackend::with_integrator(2, DirectLighting)
        .unwrap()
        .prepare(scene.clone(), &by(LightSampler::Tree))
        .unwrap();
    let direct = GpuBackend::with_context(ctx).with_integrator(GpuIntegrator::Direct);
    let wavefront = SceneOptions { wavefront: true, ..by(LightSampler::Tree) };
    let cases: [(&str, &dyn PreparedScene, &GpuBackend, SceneOptions); 3] = [
        ("path", &cpu_path, &path, by(LightSampler::Tree)),
        ("path, wavefront", &cpu_path, &path, wavefront),
        ("direct", cpu_direct.as_ref(), &direct, by(LightSampler::Tree)),
    ];
    let mut failures = Vec::new();
    for (name, cpu, backend, options) in cases {
        let gpu_scene = backend.prepare_gpu(scene.clone(), &options).unwrap();
        assert!(gpu_scene.stats().light_tree && gpu_scene.stats().emitters == 33, "{name}: {:?}", gpu_scene.stats());
        let r = render_three_with(cpu, &gpu_scene, &s).unwrap();
        assert!(r.cpu.channel_means()[1] > 0.01, "{name}: a black image proves nothing");
        failures.extend(compare_all(&format!("lamp hall, {name}"), &r));
        failures.extend(paths_follow_the_cpu(&format!("lamp hall, {name}"), &r, 0.05));
        if name == "path" {
            // A kernel compiled later, for another sampler, walks the tree too.
            let independent = RenderSettings { sampler: tracer::sampler::SamplerKind::Independent, ..s.clone() };
            let r = render_three_with(cpu, &gpu_scene, &independent).unwrap();
            failures.extend(paths_follow_the_cpu("lamp hall, path, a second kernel", &r, 0.05));
        }
    }
    // By power, the GPU's same-seed paths leave the CPU tree's.
    let power = path.prepare_gpu(scene.clone(), &by(LightSampler::Power)).unwrap();
    assert!(!power.stats().light_tree);
    let r = render_three_with(&cpu_path, &power, &s).unwrap();
    assert!(paths_follow_the_cpu("lamp hall, power against the tree", &r, 0.05).is_some());
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The mean squared difference of two films' pixel means. Same-seed renders that drew
/// the same sample values differ only where rounding sent a path elsewhere; renders with
/// other sample values (another seed, or a sampler that is unbiased but not the CPU's)
/// differ by their full noise.
fn mean_squared_difference(a: &Film, b: &Film) -> f64 {
    let (x, y) = (a.mean_rgb(), b.mean_rgb());
    x.iter().zip(&y).map(|(p, q)| ((p - q) as f64).powi(2)).sum::<f64>() / x.len() as f64
}

/// Sharper than the z-tests: the same-seed GPU paths follow the CPU's, so the two images
/// differ far less than independent renders do — at most `limit` of their squared
/// difference (else, or for a ratio that is not a number, the failure).
fn paths_follow_the_cpu(label: &str, r: &Renders, limit: f64) -> Option<String> {
    let ratio = mean_squared_difference(&r.cpu, &r.same) / mean_squared_difference(&r.cpu, &r.other);
    println!("{label}: same-seed squared difference {ratio:.4} of the independent one");
    (ratio.is_nan() || ratio > limit)
        .then(|| format!("{label}: same-seed paths diverge ({ratio:.4} of the independent squared difference)"))
}

/// The Sobol samplers on the GPU draw the CPU's values bit for bit (64-bit scrambles on
/// word pairs, the CPU's tables): same-seed Cornell-box renders agree pixel for pixel
/// where the paths do, and pass the z-tests with another seed.
#[test]
fn sobol_samplers_match_the_cpu() {
    use tracer::sampler::SamplerKind;
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let gpu = GpuBackend::with_context(ctx);
    // Preparing compiles the kernel of the first render's sampler (without a hint the
    // default settings'); warming up compiles another's.
    let (cpu_scene, gpu_scene) = prepare_both(&gpu, &scene, None).unwrap();
    assert_eq!(gpu_scene.compiled_samplers(), [SamplerKind::Independent]);
    gpu_scene.warm_up(&RenderSettings { sampler: SamplerKind::ZSobol, ..settings(8, 8, 1) }).unwrap();
    assert_eq!(gpu_scene.compiled_samplers(), [SamplerKind::Independent, SamplerKind::ZSobol]);
    let hint = SceneOptions { first_render: Some((SamplerKind::Sobol, SpectralMode::Hero)), ..SceneOptions::default() };
    assert_eq!(gpu.prepare_gpu(scene, &hint).unwrap().compiled_samplers(), [SamplerKind::Sobol]);
    let mut failures = Vec::new();
    for sampler in [SamplerKind::Independent, SamplerKind::ZSobol, SamplerKind::Sobol] {
        let s = RenderSettings { sampler, ..settings(32, 32, 64) };
        let r = render_three_with(&cpu_scene, &gpu_scene, &s).unwrap();
        failures.extend(paths_follow_the_cpu(sampler.name(), &r, 0.25));
        failures.extend(compare_all(&format!("Cornell box, {}", sampler.name()), &r));
    }
    // Beyond the layout: a pass past the power-of-two budget is refused, as on the CPU.
    let s = RenderSettings { sampler: SamplerKind::ZSobol, ..settings(8, 8, 4) };
    let err = gpu_scene.render_pass(&s, &mut Film::new(8, 8), 4, 1, &|_| {}).unwrap_err().to_string();
    assert!(err.contains("raise --spp"), "{err}");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A room of analytic shapes only: an axis-aligned box as the floor, an oriented box,
/// spheres by each intersection method (glass, rough metal, diffuse), a self-intersecting
/// pentagram by the crossing-number rule and a concave L by the winding rule on the back
/// wall, lit by a glowing sphere, a glowing concave polygon and a glowing tilted box (all
/// sampled by area) and a dim sky.
fn shape_scene() -> Scene {
    use shapes::boxes::Cuboid;
    use shapes::polygon::{InsideTest, Polygon};
    use shapes::sphere::{Sphere, SphereMethod};
    use tracer::ShapeKind;
    let diffuse = |name: &str, rgb: [f32; 3]| Material::diffuse(name, Colour::reflectance_rgb(rgb).unwrap()).unwrap();
    let mut scene = Scene::default();
    let floor = Cuboid::axis_aligned(Vec3::new(-3.0, -0.2, -3.0), Vec3::new(3.0, 0.0, 3.0)).unwrap();
    scene.add_shape(ShapeKind::Cuboid(floor), diffuse("floor", [0.6, 0.55, 0.5]));
    let tilted =
        Cuboid::oriented(Vec3::new(1.3, 0.5, -0.2), Vec3::new(0.35, 0.5, 0.3), glam::Quat::from_rotation_y(0.6));
    scene.add_shape(ShapeKind::Cuboid(tilted.unwrap()), diffuse("red", [0.7, 0.15, 0.1]));
    let sphere = |c: Vec3, r: f32, method| ShapeKind::Sphere(Sphere::new(c, r, method).unwrap());
    scene.add_shape(
        sphere(Vec3::new(-1.2, 0.5, 0.3), 0.5, SphereMethod::Geometric),
        Material::dielectric("glass", 1.5).unwrap(),
    );
    let metal = Material::builtin(
        "metal",
        ModelId::RoughConductor,
        &[("metal", ParamValue::Scalar(1.0)), ("alpha", ParamValue::Scalar(0.2))],
    )
    .unwrap();
    scene.add_shape(sphere(Vec3::new(0.0, 0.45, -0.6), 0.45, SphereMethod::AlgebraicStable), metal);
    scene.add_shape(
        sphere(Vec3::new(0.2, 0.25, 0.8), 0.25, SphereMethod::AlgebraicNaive),
        diffuse("blue", [0.1, 0.3, 0.7]),
    );
    let star: Vec<Vec3> = (0..5)
        .map(|k| {
            let a = std::f32::consts::FRAC_PI_2 + k as f32 * 4.0 * std::f32::consts::PI / 5.0;
            Vec3::new(-1.0 + 0.8 * a.cos(), 1.6 + 0.8 * a.sin(), -1.5)
        })
        .collect();
    let star = Polygon::new(star, InsideTest::CrossingNumber).unwrap();
    scene.add_shape(ShapeKind::Polygon(star), diffuse("yellow", [0.8, 0.7, 0.1]));
    let ell = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.4], [0.4, 0.4], [0.4, 1.2], [0.0, 1.2]]
        .map(|[x, y]| Vec3::new(0.6 + x, 0.4 + y, -1.5));
    scene.add_shape(
        ShapeKind::Polygon(Polygon::new(ell.to_vec(), InsideTest::WindingNumber).unwrap()),
        diffuse("green", [0.1, 0.6, 0.2]),
    );
    // A concave lamp facing down (clockwise seen from above).
    let lamp_l = [[0.0, 0.0], [0.0, 0.8], [0.3, 0.8], [0.3, 0.3], [0.9, 0.3], [0.9, 0.0]]
        .map(|[x, z]| Vec3::new(-0.6 + x, 2.6, -0.4 + z));
    scene.add_shape(
        ShapeKind::Polygon(Polygon::new(lamp_l.to_vec(), InsideTest::WindingNumber).unwrap()),
        lamp("lamp", [6.0, 5.5, 4.5]),
    );
    scene.add_shape(sphere(Vec3::new(1.6, 1.6, 0.6), 0.15, SphereMethod::Geometric), lamp("bulb", [30.0, 20.0, 10.0]));
    let glow =
        Cuboid::oriented(Vec3::new(-1.8, 1.2, -0.8), Vec3::new(0.12, 0.2, 0.1), glam::Quat::from_rotation_z(0.5));
    scene.add_shape(ShapeKind::Cuboid(glow.unwrap()), lamp("glowing box", [8.0, 14.0, 20.0]));
    scene.environment = Some(Environment::uniform(Colour::constant(0.15)));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 1.6, 4.0), center: Vec3::new(0.0, 0.7, 0.0), up: Vec3::Y, fov_y_deg: 45.0 });
    scene
}

#[test]
fn analytic_shapes_match_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let scene = shape_scene();
    let s = settings(32, 32, 128);
    let r = render_three(&gpu, &scene, &s).unwrap();
    assert!(r.cpu.channel_means()[1] > 0.02, "a dark image proves little");
    let failures = compare_all("analytic shapes", &r);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// [`model_scene`] lit also by a point light, a spot light, a sun with a 40° disk (which
/// glossy reflections find by BSDF sampling: MIS) and a delta directional light, over a
/// rough-metal sphere and an analytic ball.
fn punctual_scene() -> Scene {
    use tracer::punctual::PunctualLight;
    let metal = Material::builtin(
        "metal",
        ModelId::RoughConductor,
        &[("metal", ParamValue::Scalar(2.0)), ("alpha", ParamValue::Scalar(0.15))],
    )
    .unwrap();
    let mut scene = model_scene(metal);
    let ball = shapes::sphere::Sphere::new(Vec3::new(1.4, 0.4, 0.6), 0.4, Default::default()).unwrap();
    let white = Material::diffuse("white", Colour::reflectance_rgb([0.8, 0.8, 0.8]).unwrap()).unwrap();
    scene.add_shape(tracer::ShapeKind::Sphere(ball), white);
    let rgb = |c: [f32; 3]| Colour::illuminant_rgb(c).unwrap();
    scene.punctual_lights = vec![
        PunctualLight::point(Vec3::new(1.5, 2.0, 1.5), rgb([6.0, 5.0, 4.0])),
        PunctualLight::spot(Vec3::new(-1.5, 2.5, 1.0), Vec3::new(0.5, -1.0, -0.4), rgb([20.0, 20.0, 30.0]), 0.2, 0.45),
        PunctualLight::sun(Vec3::new(-0.3, -1.0, -0.5), rgb([1.5, 1.3, 1.0]), 40f32.to_radians()),
        PunctualLight::directional(Vec3::new(0.6, -1.0, 0.2), rgb([0.4, 0.4, 0.5])),
    ];
    scene
}

#[test]
fn punctual_lights_match_the_cpu() {
    use gpu::kernel::GpuIntegrator;
    use tracer::{Backend, DirectLighting};
    let Some(ctx) = gpu::require_gpu() else { return };
    let scene = punctual_scene();
    let s = settings(32, 32, 128);
    let mut failures = Vec::new();
    let r = render_three(&GpuBackend::with_context(ctx), &scene, &s).unwrap();
    failures.extend(compare_all("punctual lights, path", &r));
    // Sharper than the z-tests for the directions a sun's disk is sampled in (its
    // penumbrae).
    failures.extend(paths_follow_the_cpu("punctual lights", &r, 0.05));
    // Direct lighting sees the sun's disk unweighted.
    let options = SceneOptions::default();
    let cpu = CpuBackend::with_integrator(2, DirectLighting).unwrap().prepare(scene.clone(), &options).unwrap();
    let backend = GpuBackend::with_context(gpu::require_gpu().unwrap()).with_integrator(GpuIntegrator::Direct);
    let r = render_three_with(cpu.as_ref(), &backend.prepare_gpu(scene, &options).unwrap(), &s).unwrap();
    failures.extend(compare_all("punctual lights, direct", &r));
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Implicit surfaces in f64 (`wgsl/implicit.wgsl`) in one room: a glass torus solved in
/// closed form (a quartic), a rough-metal heart by Laguerre's method without polishing (degree
/// 6), a red ball by Laguerre with polishing, on a box floor under a glowing ball and a sky.
fn implicit_scene() -> Scene {
    use shapes::boxes::Cuboid;
    use shapes::implicit::{Implicit, parse};
    use shapes::roots::RootSolver;
    use tracer::ShapeKind;
    let mut scene = Scene::default();
    let implicit = |expression: &str, min: [f32; 3], max: [f32; 3], solver| {
        let bounds = bvh::Aabb { min: Vec3::from(min), max: Vec3::from(max) };
        ShapeKind::Implicit(Implicit::new(parse(expression).unwrap(), bounds, solver).unwrap())
    };
    let torus = Implicit::torus(0.6, 0.2, RootSolver::ClosedForm).unwrap();
    scene.add_shape(ShapeKind::Implicit(torus), Material::dielectric("glass", 1.5).unwrap());
    let metal = Material::builtin(
        "metal",
        ModelId::RoughConductor,
        &[("metal", ParamValue::Scalar(1.0)), ("alpha", ParamValue::Scalar(0.25))],
    )
    .unwrap();
    let heart = "((x - 1.5)^2 + 2.25 y^2 + z^2 - 1)^3 - (x - 1.5)^2 z^3 - 0.1125 y^2 z^3";
    let unpolished = RootSolver::Laguerre { polish: false };
    scene.add_shape(implicit(heart, [0.3, -0.8, -1.05], [2.7, 0.8, 1.3], unpolished), metal);
    let ball = "(x + 1.4)^2 + y^2 + (z + 0.6)^2 - 0.25";
    let polished = RootSolver::Laguerre { polish: true };
    let red = Material::diffuse("red", Colour::reflectance_rgb([0.7, 0.15, 0.1]).unwrap()).unwrap();
    scene.add_shape(implicit(ball, [-1.9, -0.5, -1.1], [-0.9, 0.5, -0.1], polished), red);
    let floor = Cuboid::axis_aligned(Vec3::new(-4.0, -4.0, -1.3), Vec3::new(4.0, 4.0, -1.1)).unwrap();
    let grey = Material::diffuse("floor", Colour::reflectance_rgb([0.6, 0.55, 0.5]).unwrap()).unwrap();
    scene.add_shape(ShapeKind::Cuboid(floor), grey);
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([20.0, 18.0, 15.0]).unwrap());
    let bulb = shapes::sphere::Sphere::new(Vec3::new(-1.0, -1.5, 2.2), 0.3, Default::default()).unwrap();
    scene.add_shape(ShapeKind::Sphere(bulb), lamp);
    scene.environment = Some(Environment::uniform(Colour::constant(0.2)));
    scene.camera = Some(Camera {
        eye: Vec3::new(0.0, -4.2, 1.6),
        center: Vec3::new(0.0, 0.0, -0.3),
        up: Vec3::Z,
        fov_y_deg: 48.0,
    });
    scene
}

/// Implicit surfaces (`implicit.wgsl`, on devices with `SHADER_F64`): the room of
/// [`implicit_scene`] (every root solver, degrees 2, 4 and 6) and `scenes/cornell-spheres.toml`
/// (the scene file's glass ball, an expression solved in closed form, beside a gold sphere).
#[test]
fn implicit_surfaces_match_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    if !ctx.shader_f64() {
        assert!(std::env::var_os("SPT_REQUIRE_GPU").is_none(), "{} lacks SHADER_F64", ctx.info.name);
        eprintln!("skipping: {} lacks SHADER_F64", ctx.info.name);
        return;
    }
    let gpu = GpuBackend::with_context(ctx);
    let mut failures = Vec::new();
    let room = render_three(&gpu, &implicit_scene(), &settings(24, 24, 96)).unwrap();
    println!("implicit surfaces: kernel compiled in {:?}", room.compile);
    assert!(room.cpu.channel_means()[1] > 0.02, "a dark image proves little");
    failures.extend(compare_all("implicit surfaces", &room));
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-spheres.toml");
    match tracer::scene_file::load_scene_file(&file) {
        Ok(scene) => {
            let r = render_three(&gpu, &scene, &settings(24, 24, 96)).unwrap();
            println!("cornell-spheres.toml: kernel compiled in {:?}", r.compile);
            failures.extend(compare_all("cornell-spheres.toml", &r));
        }
        // (Its box is the shared Cornell box.)
        Err(e) => eprintln!("skipping cornell-spheres.toml: {e}"),
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A diffuse ball inside an absorbing glass box, lit from above: the light from the ball
/// reaches the camera only through the glass, so every segment inside it (also those that
/// start at the ball) must be attenuated, as on the CPU
/// (`light_from_inside_absorbing_glass_is_attenuated` in the top-level tests). (The shadow
/// rays' own rule needs next-event estimation on an absorbing surface, which the built-in
/// models do not have: only smooth, purely specular glass absorbs.)
#[test]
fn light_inside_absorbing_glass_matches_the_cpu() {
    use shapes::boxes::Cuboid;
    use tracer::ShapeKind;
    let Some(ctx) = gpu::require_gpu() else { return };
    let mut scene = model_scene(Material::diffuse("grey", Colour::constant(0.5)).unwrap());
    let glass = Material::builtin(
        "tinted glass",
        ModelId::Dielectric,
        &[("ior", ParamValue::Scalar(1.2)), ("absorption", ParamValue::Rgb([1.2, 0.4, 0.1]))],
    )
    .unwrap();
    let case = Cuboid::axis_aligned(Vec3::new(-1.3, 0.05, -1.3), Vec3::new(1.3, 2.1, 1.3)).unwrap();
    scene.add_shape(ShapeKind::Cuboid(case), glass);
    let r = render_three(&GpuBackend::with_context(ctx), &scene, &settings(32, 32, 128)).unwrap();
    let failures = compare_all("ball in absorbing glass", &r);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Russian roulette on the GPU, as on the CPU (`tests/tests/glass.rs`), judges a path by
/// its throughput times η'²: in a white furnace of a clear ball of index 1.5, with roulette
/// from the first bounce, the samples' relative spread is 0.343 (as on the CPU) and 1.148 if
/// the compressed throughput decides (checked once on lavapipe).
#[test]
fn russian_roulette_inside_glass_sees_through_radiance_compression() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let mut scene = Scene::default();
    scene.add(&uv_sphere(Vec3::ZERO, 0.5, 32, 64, false), Material::dielectric("glass", 1.5).unwrap());
    scene.environment = Some(Environment::uniform(Colour::constant(1.0)));
    scene.camera = Some(Camera { eye: Vec3::new(0.0, 0.0, 3.0), center: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 0.05 });
    let prepared = GpuBackend::with_context(ctx).prepare_gpu(scene, &SceneOptions::default()).unwrap();
    let spp = 4096;
    let path = PathSettings { rr_depth: 1, ..Default::default() };
    let s = RenderSettings { width: 1, height: 1, spp, mode: SpectralMode::Rgb, path, ..Default::default() };
    let (film, _) = tracer::render(&prepared, &s, &|_| {}).unwrap();
    let (mean, se) = (film.pixel(0, 0).mean()[1], film.pixel(0, 0).std_error()[1]);
    let spread = se * (spp as f64).sqrt() / mean;
    println!("furnace {mean} ± {se}, relative spread {spread:.3}");
    assert!((mean - 1.0).abs() < 4.0 * se, "furnace: {mean} ± {se}");
    assert!(spread < 0.6, "relative spread of the samples {spread:.3}");
}

/// Russian roulette's scale (`PathSettings::rr_scale`) on the GPU, in a closed glowing
/// room (Lambertian walls of albedo 0.8 emitting 0.5: radiance 0.5 / (1 − 0.8) = 2.5
/// everywhere): both scales converge to it, and scale 4 keeps paths longer for a lower
/// error per sample (the CPU's test in `tests/tests/analytic.rs`). Scale 4 also runs as a
/// wavefront, which must trace longer paths too and give the megakernel's film (bit for
/// bit on lavapipe), and BDPT's subpaths grow longer with it as well.
#[test]
fn russian_roulette_scale_converges_in_a_glowing_room() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let exact = ctx.info.device_type == wgpu::DeviceType::Cpu;
    let scene = room::glowing_room(0.8, 0.5);
    let gpu = GpuBackend::with_context(ctx);
    let megakernel = gpu.prepare_gpu(scene.clone(), &SceneOptions::default()).unwrap();
    let wavefront =
        gpu.prepare_gpu(scene.clone(), &SceneOptions { wavefront: true, ..SceneOptions::default() }).unwrap();
    let bdpt = gpu.with_integrator(gpu::kernel::GpuIntegrator::Bdpt).prepare_gpu(scene, &SceneOptions::default());
    let render = |prepared: &gpu::GpuScene, rr_scale: f32| {
        let path = PathSettings { max_depth: 0, rr_depth: 3, rr_scale, ..PathSettings::default() };
        let s = RenderSettings { mode: SpectralMode::Rgb, path, ..settings(12, 12, 512) };
        let (film, stats) = tracer::render(prepared, &s, &|_| {}).unwrap();
        assert_eq!(stats.non_finite, 0);
        let n = film.pixels().len() as f64;
        let mean = film.pixels().iter().map(|p| p.mean()[1]).sum::<f64>() / n;
        let se_of_mean = film.pixels().iter().map(|p| p.std_error()[1].powi(2)).sum::<f64>().sqrt() / n;
        let se = film.pixels().iter().map(|p| p.std_error()[1]).sum::<f64>() / n;
        println!("scale {rr_scale}: mean {mean:.4} ± {se_of_mean:.4}, per-pixel se {se:.4}, {} rays", stats.rays);
        assert!((mean - 2.5).abs() < 4.5 * se_of_mean && (mean / 2.5 - 1.0).abs() < 0.01, "scale {rr_scale}: {mean}");
        (film, se, stats.rays)
    };
    let (_, se_1, rays_1) = render(&megakernel, 1.0);
    let (film_4, se_4, rays_4) = render(&megakernel, 4.0);
    assert!(rays_4 as f64 > 1.2 * rays_1 as f64, "longer paths: {rays_4} against {rays_1} rays");
    assert!(se_4 < 0.8 * se_1, "a lower error per sample: {se_4} against {se_1}");
    let (wave_4, _, wave_rays) = render(&wavefront, 4.0);
    assert!(wave_rays as f64 > 1.2 * rays_1 as f64, "the wavefront's paths: {wave_rays} against {rays_1} rays");
    if exact {
        assert!(wave_4 == film_4 && wave_rays == rays_4, "the wavefront's film differs from the megakernel's");
    }
    // BDPT: rays only (its statistics are `bdpt_matches_the_cpu`'s, in batches: light
    // tracing's splats are not in the pixels' standard errors), at a few samples.
    let bdpt = bdpt.unwrap();
    let rays = |rr_scale: f32| {
        let path = PathSettings { max_depth: 0, rr_depth: 3, rr_scale, ..PathSettings::default() };
        let s = RenderSettings { mode: SpectralMode::Rgb, path, ..settings(12, 12, 16) };
        tracer::render(&bdpt, &s, &|_| {}).unwrap().1.rays
    };
    let (bdpt_1, bdpt_4) = (rays(1.0), rays(4.0));
    assert!(bdpt_4 as f64 > 1.2 * bdpt_1 as f64, "BDPT's subpaths: {bdpt_4} against {bdpt_1} rays");
}

/// RGB mode (`--spectral rgb`): colours as their linear-sRGB values, metals' (n, k) at the
/// CPU's three channel wavelengths, no dispersion, no wavelength drawn by the camera — on
/// every model (and the dispersive, absorbing glass), the analytic shapes and the punctual
/// lights' scenes, and the Cornell box.
#[test]
fn rgb_mode_matches_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let s = RenderSettings { mode: SpectralMode::Rgb, ..settings(24, 24, 96) };
    let mut scenes = model_case_scenes();
    scenes.push(("analytic shapes".into(), shape_scene()));
    scenes.push(("punctual lights".into(), punctual_scene()));
    scenes.extend(cornell().map(|c| ("Cornell box".to_string(), c)));
    let mut failures = Vec::new();
    for (name, scene) in scenes {
        let r = render_three(&gpu, &scene, &s).unwrap();
        failures.extend(compare_all(&format!("{name} (rgb)"), &r));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// An RGBA8 image from a function of the texel (x, y).
fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) -> std::sync::Arc<tracer::texture::TextureImage> {
    let texels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| f(x, y)).collect();
    std::sync::Arc::new(tracer::texture::TextureImage::from_rgba8(w, h, texels).unwrap())
}

/// A small hash of integers to a byte, for texture contents.
fn byte(a: u32, b: u32, salt: u32) -> u8 {
    let mut h = a.wrapping_mul(0x9e37_79b9) ^ b.wrapping_mul(0x85eb_ca6b) ^ salt.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    (h >> 24) as u8
}

/// Every kind of texture a material reads: a checkered, bump-mapped floor tiled by a uv
/// transform; a metallic–roughness ball with base-colour (mirrored and clamped wraps),
/// metallic–roughness and normal maps; a cut-out card (alpha mask at 0.5) and a
/// half-transparent one (blend) in front of it, casting shadows; a wall of Ashikhmin–
/// Shirley with diffuse and specular maps; a rough glass ball whose roughness is textured;
/// a panel glowing through an emissive texture; lit by an untextured lamp and a dim sky.
fn textured_scene() -> Scene {
    use tracer::texture::{Alpha, AlphaMode, BumpMap, Encoding, MaterialTextures, NormalMap, TextureMap, Wrap};
    let map = |img, encoding| TextureMap::new(img, encoding);
    let mut scene = Scene::default();
    let checker = image(8, 8, |x, y| if (x + y) % 2 == 0 { [230, 200, 40, 255] } else { [30, 60, 200, 255] });
    let heights = image(16, 16, |x, y| [byte(x, y, 1), 0, 0, 255]);
    let mut floor_map = map(checker.clone(), Encoding::Srgb);
    floor_map.transform = tracer::texture::khr_texture_transform([0.1, 0.2], 0.3, [3.0, 2.0]);
    let floor = Material::diffuse("floor", Colour::constant(0.8)).unwrap().with_textures(MaterialTextures {
        base_colour: Some(floor_map),
        bump: Some(BumpMap { map: map(heights, Encoding::Linear), scale: 0.3 }),
        ..Default::default()
    });
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 3.0), floor);

    let mut ball = uv_sphere(Vec3::new(-0.6, 0.8, 0.0), 0.8, 12, 24, false);
    ball.uvs =
        (0..=12u32).flat_map(|r| (0..24u32).map(move |s| glam::Vec2::new(s as f32 / 8.0, r as f32 / 10.0))).collect();
    let mut colours = map(image(4, 4, |x, y| [byte(x, y, 2), byte(x, y, 3), byte(x, y, 4), 255]), Encoding::Srgb);
    colours.wrap = [Wrap::Mirror, Wrap::Clamp];
    let mr = image(8, 8, |x, y| [0, 40 + byte(x, y, 5) / 2, byte(x, y, 6), 255]);
    let normals = image(8, 8, |x, y| [100 + byte(x, y, 7) / 4, 100 + byte(x, y, 8) / 4, 230, 255]);
    let metal = Material::builtin("metal", ModelId::MetallicRoughness, &[("roughness", ParamValue::Scalar(0.8))])
        .unwrap()
        .with_textures(MaterialTextures {
            base_colour: Some(colours),
            metallic_roughness: Some(map(mr.clone(), Encoding::Linear)),
            normal: Some(NormalMap { map: map(normals, Encoding::Linear), scale: 1.0 }),
            ..Default::default()
        });
    scene.add(&ball, metal);

    let card = |name: &str, alpha: Alpha| {
        Material::diffuse(name, Colour::constant(0.7)).unwrap().with_textures(MaterialTextures {
            base_colour: Some(map(checker.clone(), Encoding::Srgb)),
            alpha: Some(alpha),
            ..Default::default()
        })
    };
    let holes = image(4, 4, |x, y| [255, 255, 255, if (x * 3 + y) % 4 == 0 { 0 } else { 255 }]);
    let mask = Alpha { mode: AlphaMode::Mask { cutoff: 0.5 }, factor: 1.0, map: Some(map(holes, Encoding::Linear)) };
    scene.add(&quad(Vec3::new(0.7, 0.7, 0.9), Vec3::Z, 0.6), card("cut-out card", mask));
    let blend = Alpha { mode: AlphaMode::Blend, factor: 0.6, map: None };
    scene.add(&quad(Vec3::new(-1.2, 0.5, 1.3), Vec3::Z, 0.4), card("blended card", blend));

    let wall = Material::builtin(
        "wall",
        ModelId::Ashikhmin,
        &[("nu", ParamValue::Scalar(50.0)), ("nv", ParamValue::Scalar(50.0))],
    )
    .unwrap()
    .with_textures(MaterialTextures {
        base_colour: Some(map(checker.clone(), Encoding::Srgb)),
        specular: Some(map(image(2, 2, |x, y| [byte(x, y, 9), 128, byte(x, y, 10), 255]), Encoding::Srgb)),
        ..Default::default()
    });
    scene.add(&quad(Vec3::new(0.0, 1.5, -1.5), Vec3::Z, 1.5), wall);
    let glass = Material::builtin("rough glass", ModelId::RoughDielectric, &[("alpha", ParamValue::Scalar(0.3))])
        .unwrap()
        .with_textures(MaterialTextures { metallic_roughness: Some(map(mr, Encoding::Linear)), ..Default::default() });
    let mut glass_ball = uv_sphere(Vec3::new(1.3, 0.45, -0.2), 0.45, 8, 16, false);
    glass_ball.uvs =
        (0..=8u32).flat_map(|r| (0..16u32).map(move |s| glam::Vec2::new(s as f32 / 16.0, r as f32 / 8.0))).collect();
    scene.add(&glass_ball, glass);
    let panel = Material::diffuse("panel", Colour::constant(0.1))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([2.0, 2.0, 2.0]).unwrap())
        .with_textures(MaterialTextures { emissive: Some(map(checker, Encoding::Srgb)), ..Default::default() });
    scene.add(&quad(Vec3::new(-2.2, 1.0, -0.5), Vec3::X, 0.5), panel);
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .unwrap()
        .with_emission(Colour::illuminant_rgb([6.0, 5.5, 4.5]).unwrap());
    let mut light = quad(Vec3::new(0.5, 3.5, 1.0), -Vec3::Y, 0.8);
    light.normals.clear();
    scene.add(&light, lamp);
    scene.environment = Some(Environment::uniform(Colour::constant(0.2)));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.3, 1.8, 4.2), center: Vec3::new(0.0, 0.7, 0.0), up: Vec3::Y, fov_y_deg: 50.0 });
    scene
}

#[test]
fn textures_match_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let scene = textured_scene();
    let mut failures = Vec::new();
    for mode in [SpectralMode::Hero, SpectralMode::Rgb] {
        let s = RenderSettings { mode, ..settings(32, 32, 128) };
        let r = render_three(&gpu, &scene, &s).unwrap();
        assert!(r.cpu.channel_means()[1] > 0.02, "a dark image proves little");
        failures.extend(compare_all(&format!("textures ({})", mode.name()), &r));
        // Sharper than the z-tests for what bends normals (a normal map's handedness, a bump
        // map): a normal bent otherwise sends every path that meets it elsewhere.
        failures.extend(paths_follow_the_cpu(&format!("textures ({})", mode.name()), &r, 0.05));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Real textures: Sponza's OBJ with its MTL's 36 textured materials (diffuse and bump
/// maps), seen from inside under a white sky. Its deep tree and long paths also guard the
/// dispatch size on software rasterisers: at 64 samples per dispatch lavapipe's loop
/// limiter cut the traversal short and the image came out 6.5 % too bright (untextured,
/// 1024 spp: ±0.4 %; `SOFTWARE_SAMPLES_PER_DISPATCH`). Sponza's same-seed paths partly
/// decorrelate (the BVHs break its many ties otherwise), so both GPU renders are held to
/// the independent criteria.
#[test]
fn textured_sponza_matches_the_cpu() {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes/sponza/sponza.obj"));
    if !path.exists() {
        eprintln!("skipping: {} is absent", path.display());
        return;
    }
    let Some(ctx) = gpu::require_gpu() else { return };
    let mut scene = tracer::obj::load_obj(path).unwrap();
    assert!(scene.materials.iter().filter(|m| m.textures.is_some()).count() > 20, "Sponza's textures were not read");
    scene.environment = Some(Environment::white_sky(1.0));
    scene.camera = Some(Camera {
        eye: Vec3::new(-12.0, 3.0, 0.0),
        center: Vec3::new(10.0, 5.0, 0.0),
        up: Vec3::Y,
        fov_y_deg: 60.0,
    });
    let gpu = GpuBackend::with_context(ctx);
    println!(
        "adapter: {} ({:?}, {:?})",
        gpu.context().info.name,
        gpu.context().info.backend,
        gpu.context().info.device_type
    );
    let r = render_three(&gpu, &scene, &settings(40, 24, 256)).unwrap();
    let mut failures = Vec::new();
    for (seed, film) in [("same seed", &r.same), ("other seed", &r.other)] {
        let c = compare(&r.cpu, film);
        println!("textured Sponza, {seed}: {}", c.summary());
        failures.extend(c.independent_failures().map(|f| format!("textured Sponza, {seed}: {f}")));
    }
    assert!(r.same.non_finite == 0 && r.other.non_finite == 0, "non-finite samples on the GPU");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A procedural sky map: a blue gradient with a small, bright, warm sun (the case
/// importance sampling by the 3×3 neighbourhood's maximum is for), turned by 30°.
fn sky_map() -> tracer::envmap::EnvironmentMap {
    let (w, h) = (64u32, 32u32);
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let t = y as f32 / h as f32;
            let sun = if (x as i32 - 40).abs() <= 1 && (y as i32 - 9).abs() <= 1 { 60.0 } else { 0.0 };
            [0.2 + 0.3 * t + sun, 0.3 + 0.3 * t + 0.8 * sun, 0.6 + 0.1 * t + 0.5 * sun]
        })
        .collect();
    tracer::envmap::EnvironmentMap::new(w, h, texels, 30.0).unwrap()
}

/// An environment map lights a scene (with and without a small area light, so that the
/// map shares next-event estimation), through the path tracer and direct lighting, in
/// hero and RGB mode: its lookup, its importance sampling and the MIS pdf of escaping rays.
#[test]
fn environment_maps_match_the_cpu() {
    use gpu::kernel::GpuIntegrator;
    use tracer::{Backend, DirectLighting};
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let metal = Material::builtin(
        "metal",
        ModelId::RoughConductor,
        &[("metal", ParamValue::Scalar(2.0)), ("alpha", ParamValue::Scalar(0.1))],
    )
    .unwrap();
    let mut lit = model_scene(metal);
    lit.environment = Some(Environment::from_map(sky_map(), 1.5));
    let mut only_sky = lit.clone();
    let lamp = only_sky.materials.iter().position(|m| m.name == "lamp").unwrap() as u32;
    let keep: Vec<usize> = (0..only_sky.triangles.len()).filter(|&t| only_sky.material_ids[t] != lamp).collect();
    only_sky.triangles = keep.iter().map(|&t| only_sky.triangles[t]).collect();
    only_sky.material_ids = keep.iter().map(|&t| only_sky.material_ids[t]).collect();
    let mut failures = Vec::new();
    for (name, scene) in [("sky map and lamp", &lit), ("sky map alone", &only_sky)] {
        for mode in [SpectralMode::Hero, SpectralMode::Rgb] {
            let s = RenderSettings { mode, ..settings(32, 32, 128) };
            let r = render_three(&gpu, scene, &s).unwrap();
            failures.extend(compare_all(&format!("{name}, path ({})", mode.name()), &r));
        }
    }
    let options = SceneOptions::default();
    let cpu = CpuBackend::with_integrator(2, DirectLighting).unwrap().prepare(only_sky.clone(), &options).unwrap();
    let direct = GpuBackend::with_context(gpu::require_gpu().unwrap()).with_integrator(GpuIntegrator::Direct);
    let r = render_three_with(cpu.as_ref(), &direct.prepare_gpu(only_sky, &options).unwrap(), &settings(32, 32, 128))
        .unwrap();
    failures.extend(compare_all("sky map alone, direct", &r));
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The light table holds each sun's sampling frame intact: two unit tangents perpendicular
/// to its axis and to each other (they once overlapped the cdf's float).
#[test]
fn sun_disks_keep_their_sampling_frame() {
    use gpu::kernel::{LIGHT_KIND, LightKind};
    let data = SceneData::new(&punctual_scene(), KernelOptions::default()).unwrap();
    let v = |e: &[f32], at: usize| Vec3::new(e[at], e[at + 1], e[at + 2]);
    let mut suns = 0;
    for e in data.light_entries() {
        if e[LIGHT_KIND].to_bits() != LightKind::Directional as u32 {
            continue;
        }
        suns += 1;
        let (axis, t, b) = (v(e, 0), v(e, 13), v(e, 16));
        for (what, x) in [("|t|", t.length() - 1.0), ("|b|", b.length() - 1.0), ("t·axis", t.dot(axis))] {
            assert!(x.abs() < 1e-5, "{what} = {x}");
        }
        for (what, x) in [("b·axis", b.dot(axis)), ("t·b", t.dot(b))] {
            assert!(x.abs() < 1e-5, "{what} = {x}");
        }
    }
    assert_eq!(suns, 2, "the sun and the delta directional light");
}

/// `--spectral bins40` on the GPU: the 40 fixed 10-nm bins as ten paths of four wavelengths
/// per sample from the same sample values (the CPU carries all 40 in one path, whose lobe
/// choices see all 40, so the images agree in expectation, not path for path: both GPU
/// renders are held to the independent criteria). On the dispersive absorbing glass, a
/// measured metal, the textured scene, the sky map and the Cornell box.
#[test]
fn bins40_matches_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let s = RenderSettings { mode: SpectralMode::Bins40, ..settings(24, 24, 64) };
    let cases = model_cases();
    let case = |name: &str| cases.iter().find(|(n, _)| n == name).unwrap().1.clone();
    let mut sky = model_scene(case("lambert"));
    sky.environment = Some(Environment::from_map(sky_map(), 1.5));
    let mut scenes = vec![
        ("dispersive absorbing glass".to_string(), model_scene(case("dispersive absorbing glass"))),
        ("conductor".to_string(), model_scene(case("conductor"))),
        ("textures".to_string(), textured_scene()),
        ("sky map".to_string(), sky),
    ];
    scenes.extend(cornell().map(|c| ("Cornell box".to_string(), c)));
    let mut failures = Vec::new();
    for (name, scene) in scenes {
        let r = render_three(&gpu, &scene, &s).unwrap();
        for (seed, film) in [("same seed", &r.same), ("other seed", &r.other)] {
            let c = compare(&r.cpu, film);
            println!("{name} (bins40), {seed}: {}", c.summary());
            failures.extend(c.independent_failures().map(|f| format!("{name} (bins40), {seed}: {f}")));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// [`model_scene`] of the dispersive, absorbing glass beside a smooth mirror ball (an
/// analytic sphere): the specular chains Whitted and the atlas follow.
fn glass_and_mirror_scene() -> Scene {
    let cases = model_cases();
    let glass = cases.into_iter().find(|(n, _)| n == "dispersive absorbing glass").unwrap().1;
    let mut scene = model_scene(glass);
    let ball = shapes::sphere::Sphere::new(Vec3::new(1.4, 0.5, 0.4), 0.5, Default::default()).unwrap();
    scene.add_shape(tracer::ShapeKind::Sphere(ball), Material::builtin("mirror", ModelId::Conductor, &[]).unwrap());
    scene
}

/// Whitted ray tracing (`--integrator whitted --backend gpu`): the CPU's recursion walked
/// depth first with a stack, every punctual light by its own shadow ray. On dispersive,
/// absorbing glass beside a mirror ball under a point light, a sun with a disk and a delta
/// directional light (hero and RGB, the default depth and a short one), and on the room of
/// analytic shapes (a glass ball, glowing shapes, the sky).
#[test]
fn whitted_matches_the_cpu() {
    use gpu::kernel::GpuIntegrator;
    use tracer::punctual::PunctualLight;
    use tracer::{Backend, Whitted};
    let Some(ctx) = gpu::require_gpu() else { return };
    let mut glass_scene = glass_and_mirror_scene();
    let rgb = |c: [f32; 3]| Colour::illuminant_rgb(c).unwrap();
    glass_scene.punctual_lights = vec![
        PunctualLight::point(Vec3::new(1.5, 2.5, 1.5), rgb([6.0, 5.0, 4.0])),
        PunctualLight::sun(Vec3::new(-0.3, -1.0, -0.5), rgb([1.5, 1.3, 1.0]), 10f32.to_radians()),
        PunctualLight::directional(Vec3::new(0.6, -1.0, 0.2), rgb([0.4, 0.4, 0.5])),
    ];
    let backend = GpuBackend::with_context(ctx).with_integrator(GpuIntegrator::Whitted);
    assert_eq!(backend.capabilities().integrator, "whitted");
    let cpu = CpuBackend::with_integrator(2, Whitted).unwrap();
    let options = SceneOptions::default();
    let deep = RenderSettings { path: PathSettings::default(), ..settings(24, 24, 64) };
    let short = RenderSettings { path: PathSettings { max_depth: 3, ..PathSettings::default() }, ..deep.clone() };
    let rgb_mode = RenderSettings { mode: SpectralMode::Rgb, ..deep.clone() };
    let mut failures = Vec::new();
    for (name, scene, runs) in [
        ("glass and mirror", glass_scene, vec![("default depth", &deep), ("depth 3", &short), ("rgb", &rgb_mode)]),
        ("analytic shapes", shape_scene(), vec![("default depth", &deep)]),
    ] {
        let cpu_scene = cpu.prepare(scene.clone(), &options).unwrap();
        let gpu_scene = backend.prepare_gpu(scene, &options).unwrap();
        for (run, s) in runs {
            let r = render_three_with(cpu_scene.as_ref(), &gpu_scene, s).unwrap();
            assert!(r.cpu.channel_means()[1] > 0.02, "{name}: a dark image proves little");
            let label = format!("whitted, {name}, {run}");
            failures.extend(paths_follow_the_cpu(&label, &r, 0.05));
            failures.extend(compare_all(&label, &r));
        }
    }
    // Deeper than the stack: refused up front, naming the limit.
    let too_deep = RenderSettings { path: PathSettings { max_depth: 17, ..PathSettings::default() }, ..deep };
    let err = backend.capabilities().check_settings(&too_deep).unwrap_err().to_string();
    assert!(err.contains("16"), "{err}");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A custom BSDF (the modified Phong model of the tracer's `examples/custom_brdf.rs`,
/// outside the registry) renders on the GPU through the WGSL twin its builder ships: the
/// Cornell box's two blocks in glossy Phong, and the model scene's ball in a sharper one,
/// hero and RGB.
#[test]
fn custom_bsdf_twins_match_the_cpu() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let phong = |kd, ks, exponent| {
        let params = phong::PhongParams {
            kd: Colour::reflectance_rgb(kd).unwrap(),
            ks: Colour::reflectance_rgb(ks).unwrap(),
            exponent,
        };
        std::sync::Arc::new(params)
    };
    let mut scenes = vec![(
        "ball".to_string(),
        model_scene(Material::custom("phong ball", phong([0.2, 0.3, 0.5], [0.6, 0.5, 0.3], 300.0), false)),
    )];
    if let Some(mut box_) = cornell() {
        let blocks = phong([0.35, 0.3, 0.25], [0.5, 0.5, 0.5], 60.0);
        for m in &mut box_.materials {
            if m.name == "shortBox" || m.name == "tallBox" {
                *m = Material::custom(&m.name, blocks.clone(), false);
            }
        }
        scenes.push(("Cornell box".to_string(), box_));
    }
    let mut failures = Vec::new();
    for (name, scene) in scenes {
        for mode in [SpectralMode::Hero, SpectralMode::Rgb] {
            let r = render_three(&gpu, &scene, &RenderSettings { mode, ..settings(24, 24, 64) }).unwrap();
            let label = format!("phong {name} ({})", mode.name());
            // The twin's sampling must be the Rust's.
            failures.extend(paths_follow_the_cpu(&label, &r, 0.05));
            failures.extend(compare_all(&label, &r));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The atlas's gather runs on the device (`wgsl/atlas_gather.wgsl`) and gives the CPU's
/// irradiance texel for texel: the same points, the same form factors, the same shadow
/// rays; only the last bits of square roots and divisions differ, and a shadow ray grazing
/// an edge may decide otherwise.
#[test]
fn the_atlas_gather_on_the_device_gives_the_cpus_irradiance() {
    use gpu::kernel::GpuIntegrator;
    use tracer::integrator::{Atlas, AtlasSettings, SceneView};
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let backend = GpuBackend::with_context(ctx);
    let geometry = tracer::geometry::Geometry::build(&scene, &SceneOptions::default()).unwrap();
    let lights = tracer::lights::Lights::new(&scene);
    for visibility in [true, false] {
        let base = AtlasSettings { resolution: 64, samples: 24, direct_samples: 4, ..AtlasSettings::default() };
        let settings = AtlasSettings { visibility, ..base };
        let gpu_scene = backend
            .clone()
            .with_integrator(GpuIntegrator::Atlas(settings))
            .prepare_gpu(scene.clone(), &SceneOptions::default())
            .unwrap();
        assert!(gpu_scene.stats().integrator.is_some());
        assert_eq!(gpu_scene.atlas_gathered_on_device(), Some(true));
        // What the kernel's lookups read: the tables on the device.
        let gpu = gpu_scene.atlas_irradiance().unwrap().expect("the atlas integrator's scene has an atlas");
        let cpu_atlas = Atlas::build(&SceneView::new(&scene, &geometry, &lights), &settings).unwrap();
        let cpu = cpu_atlas.irradiance();
        assert_eq!(cpu.len(), gpu.len());
        let total = |v: &[[f32; 3]]| v.iter().flatten().map(|&x| x as f64).sum::<f64>();
        let (cpu_total, gpu_total) = (total(cpu), total(&gpu));
        assert!(cpu_total > 0.0, "no indirect light gathered");
        let lit = cpu.iter().filter(|t| t.iter().any(|&x| x > 0.0)).count();
        let close = cpu
            .iter()
            .zip(&gpu)
            .filter(|(c, _)| c.iter().any(|&x| x > 0.0))
            .filter(|(c, g)| c.iter().zip(g.iter()).all(|(&a, &b)| (a - b).abs() <= 1e-4 * a.abs().max(1e-6)))
            .count();
        println!(
            "atlas gather, visibility {visibility}: {lit} lit texels, {close} within 1e-4 of the CPU's; totals \
             {cpu_total:.6} (CPU) {gpu_total:.6} (GPU)"
        );
        assert!((gpu_total - cpu_total).abs() <= 1e-4 * cpu_total, "totals {cpu_total} and {gpu_total}");
        assert!(close as f64 >= 0.99 * lit as f64, "{close} of {lit} lit texels within 1e-4");
    }
}

/// A device whose buffers cannot hold the gather's texels (80 bytes each) but can hold
/// the scene gets its atlas gathered on the CPU: the CPU's irradiance, exactly.
#[test]
fn an_atlas_too_large_for_the_device_is_gathered_on_the_cpu() {
    use gpu::kernel::GpuIntegrator;
    use tracer::integrator::{Atlas, AtlasSettings, SceneView};
    let Some(mut ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let settings = AtlasSettings { resolution: 256, samples: 4, direct_samples: 2, ..AtlasSettings::default() };
    let options = KernelOptions { integrator: GpuIntegrator::Atlas(settings), ..KernelOptions::default() };
    let largest = SceneData::new(&scene, options).unwrap().buffer_sizes().iter().map(|&(_, b)| b).max().unwrap();
    let geometry = tracer::geometry::Geometry::build(&scene, &SceneOptions::default()).unwrap();
    let lights = tracer::lights::Lights::new(&scene);
    let cpu_atlas = Atlas::build(&SceneView::new(&scene, &geometry, &lights), &settings).unwrap();
    let used = cpu_atlas.stats.texels_used as u64;
    assert!(80 * used > largest, "the gather's texels ({used}) must outgrow the scene's largest buffer ({largest} B)");
    // Room for the scene's buffers, not for the gather's texels.
    ctx.limits.max_storage_buffer_binding_size = largest.max(80 * used - 1);
    let backend = GpuBackend::with_context(ctx).with_integrator(GpuIntegrator::Atlas(settings));
    let gpu_scene = backend.prepare_gpu(scene, &SceneOptions::default()).unwrap();
    assert_eq!(gpu_scene.atlas_gathered_on_device(), Some(false));
    let gpu = gpu_scene.atlas_irradiance().unwrap().unwrap();
    assert!(gpu == cpu_atlas.irradiance(), "the CPU's gather, bit for bit");
}

/// Atlas GI (`--integrator atlas --backend gpu`): the atlas built by the CPU's code and
/// gathered on the device when the scene is prepared, each pixel's specular chain, direct light and atlas
/// lookup in the kernel. On the Cornell box (hero and RGB) and on dispersive, absorbing
/// glass beside a mirror ball (the chain, one wavelength per sample).
#[test]
fn atlas_matches_the_cpu() {
    use gpu::kernel::GpuIntegrator;
    use tracer::integrator::AtlasSettings;
    use tracer::{AtlasGi, Backend};
    let Some(ctx) = gpu::require_gpu() else { return };
    let atlas = AtlasSettings { resolution: 96, samples: 16, direct_samples: 4, ..AtlasSettings::default() };
    let backend = GpuBackend::with_context(ctx).with_integrator(GpuIntegrator::Atlas(atlas));
    assert_eq!(backend.capabilities().integrator, "atlas");
    let cpu = CpuBackend::with_integrator(2, AtlasGi::new(atlas)).unwrap();
    let mut scenes = vec![("glass and mirror", glass_and_mirror_scene(), vec![SpectralMode::Hero])];
    scenes.extend(cornell().map(|c| ("Cornell box", c, vec![SpectralMode::Hero, SpectralMode::Rgb])));
    let options = SceneOptions::default();
    let mut failures = Vec::new();
    for (name, scene, modes) in scenes {
        let cpu_scene = cpu.prepare(scene.clone(), &options).unwrap();
        let gpu_scene = backend.prepare_gpu(scene, &options).unwrap();
        for mode in modes {
            let s = RenderSettings { mode, ..settings(24, 24, 64) };
            let r = render_three_with(cpu_scene.as_ref(), &gpu_scene, &s).unwrap();
            assert!(r.cpu.channel_means()[1] > 0.02, "{name}: a dark image proves little");
            let label = format!("atlas, {name} ({})", mode.name());
            failures.extend(paths_follow_the_cpu(&label, &r, 0.05));
            failures.extend(compare_all(&label, &r));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// How a bdpt render on the GPU compares with the CPU's, splats included: light tracing
/// lands anywhere, so the per-pixel standard errors of the camera samples do not cover a
/// pixel's estimate, and the two backends draw their sample dimensions in another order
/// (no same-seed correlation). Instead two independent GPU renders measure the spread:
/// `ratio` = Σ (cpu − gpu)² / Σ (gpu − gpu')² over pixel-channels is ≈ 1 for images
/// of the same expectation and variance (a bias adds to the numerator), and `mean_z` is
/// each channel mean's difference over its standard error estimated from that spread.
struct SplatComparison {
    ratio: f64,
    mean_z: [f64; 3],
    means: [[f64; 3]; 2],
}

fn compare_with_splats(cpu: &Film, gpu: &Film, gpu_other: &Film) -> SplatComparison {
    let (c, g, o) = (cpu.mean_rgb(), gpu.mean_rgb(), gpu_other.mean_rgb());
    let n = cpu.pixels().len() as f64;
    let (mut num, mut den) = (0.0f64, 0.0f64);
    let mut spread = [0.0f64; 3];
    for i in 0..c.len() {
        let d = (c[i] - g[i]) as f64;
        let e = (g[i] - o[i]) as f64;
        num += d * d;
        den += e * e;
        spread[i % 3] += e * e;
    }
    let means = [cpu.channel_means(), gpu.channel_means()];
    let mean_z = std::array::from_fn(|k| (means[0][k] - means[1][k]) / (spread[k].sqrt() / n));
    SplatComparison { ratio: num / den, mean_z, means }
}

/// Bidirectional path tracing (`--integrator bdpt --backend gpu`): every strategy,
/// light tracing's splats included, against the CPU's estimate — on the Cornell box
/// (bounded, depth 3, unbounded with Russian roulette, a crop window, RGB), on the room
/// of point, spot, sun and directional lights, and on dispersive absorbing glass beside
/// a mirror ball (caustics). `ratio` < 1.3 and |z| < 4.5 per channel mean; checked once
/// that it fails with light tracing's splats dropped (the film has none) and with the
/// weights' light-side sum left out (the Cornell box 27 % too bright, channel-mean z
/// −11, −10, −5).
#[test]
fn bdpt_matches_the_cpu() {
    use gpu::kernel::GpuIntegrator;
    use tracer::{Backend, Bdpt};
    let Some(ctx) = gpu::require_gpu() else { return };
    let backend = GpuBackend::with_context(ctx).with_integrator(GpuIntegrator::Bdpt);
    assert_eq!(backend.capabilities().integrator, "bdpt");
    assert_eq!(backend.capabilities().max_bounces, None, "bdpt's own cap, as on the CPU");
    let cpu = CpuBackend::with_integrator(2, Bdpt).unwrap();
    let options = SceneOptions::default();
    let base = settings(32, 32, 64);
    let depth3 = RenderSettings { path: PathSettings { max_depth: 3, ..PathSettings::default() }, ..base.clone() };
    let unbounded = RenderSettings { path: PathSettings::default(), ..base.clone() };
    let crop = RenderSettings {
        crop: Some(tracer::render::PixelRect { x: 5, y: 9, width: 19, height: 14 }),
        spp: 128,
        ..base.clone()
    };
    let rgb = RenderSettings { mode: SpectralMode::Rgb, ..base.clone() };
    let mut cases = vec![
        ("punctual lights", punctual_scene(), vec![("depth 8", base.clone())]),
        ("glass and mirror", glass_and_mirror_scene(), vec![("depth 8", base.clone())]),
        // Light subpaths through instanced (mirrored) glass: two-level traversal and
        // shading on both subpaths.
        ("instances", instanced_scene(), vec![("depth 8", base.clone())]),
    ];
    if let Some(scene) = cornell() {
        cases.insert(
            0,
            (
                "Cornell box",
                scene,
                vec![
                    ("depth 8", base.clone()),
                    ("depth 3", depth3),
                    ("unbounded", unbounded),
                    ("crop", crop),
                    ("rgb", rgb),
                ],
            ),
        );
    }
    let mut failures = Vec::new();
    for (name, scene, runs) in cases {
        let cpu_scene = cpu.prepare(scene.clone(), &options).unwrap();
        let gpu_scene = backend.prepare_gpu(scene, &options).unwrap();
        println!("bdpt, {name}: kernel compile {:?}", gpu_scene.stats().compile.unwrap_or_default());
        for (run, s) in runs {
            let (cpu_film, _) = tracer::render(cpu_scene.as_ref(), &s, &|_| {}).unwrap();
            let started = Instant::now();
            let (gpu_film, _) = tracer::render(&gpu_scene, &s, &|_| {}).unwrap();
            println!("bdpt, {name}, {run}: gpu render {:?}", started.elapsed());
            let other = RenderSettings { seed: s.seed + 1000, ..s.clone() };
            let (gpu_other, _) = tracer::render(&gpu_scene, &other, &|_| {}).unwrap();
            assert!(gpu_film.has_splats() && gpu_film.light_paths() == s.spp as u64, "{name}, {run}: no light tracing");
            assert!(cpu_film.channel_means()[1] > 0.01, "{name}, {run}: a dark image proves little");
            // (The CPU against the other seed: same-seed renders are correlated through
            // the camera samples.)
            let c = compare_with_splats(&cpu_film, &gpu_other, &gpu_film);
            println!(
                "bdpt, {name}, {run}: ratio {:.3}, channel-mean z {:+.2?}, means cpu {:.4?} gpu {:.4?}; non-finite cpu \
                 {} gpu {}",
                c.ratio, c.mean_z, c.means[0], c.means[1], cpu_film.non_finite, gpu_film.non_finite
            );
            if !(c.ratio < 1.3 && c.mean_z.iter().all(|z| z.abs() < 4.5)) {
                failures.push(format!("bdpt, {name}, {run}: ratio {:.3}, z {:+.2?}", c.ratio, c.mean_z));
            }
            if let Some(crop) = s.crop {
                // Nothing outside the crop window: no sample, no splat.
                let outside = (0..s.width * s.height)
                    .filter(|&i| !crop.contains(i % s.width, i / s.width))
                    .any(|i| gpu_film.pixel_mean(i as usize) != [0.0; 3]);
                assert!(!outside, "{name}, {run}: light reached a pixel outside the crop window");
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// bdpt in bands of rows (as many as its scratch holds under a lowered binding limit: 3
/// rows of 32 pixels here) gives the one-band film bit for bit, splats included: a pixel's
/// samples do not depend on the band, and the splat sums are exact integers.
#[test]
fn bdpt_bands_give_the_same_film() {
    use gpu::kernel::{BDPT_SLOT_BYTES, GpuIntegrator};
    let Some(ctx) = gpu::require_gpu() else { return };
    let Some(scene) = cornell() else { return };
    let options = KernelOptions { integrator: GpuIntegrator::Bdpt, ..KernelOptions::default() };
    let largest = SceneData::new(&scene, options).unwrap().buffer_sizes().iter().map(|b| b.1).max().unwrap();
    let s = settings(32, 20, 16);
    // (The scene's buffers are smaller: three rows per band, seven bands.)
    assert!(largest < 4 * 32 * BDPT_SLOT_BYTES, "the largest buffer ({largest} B) would allow wider bands");
    let limit = largest.max(3 * 32 * BDPT_SLOT_BYTES);
    let limits = wgpu::Limits { max_storage_buffer_binding_size: limit, ..ctx.limits.clone() };
    let mut banded_ctx = ctx.clone();
    let whole_backend = GpuBackend::with_context(ctx).with_integrator(GpuIntegrator::Bdpt);
    let (whole, _) =
        tracer::render(&whole_backend.prepare_gpu(scene.clone(), &SceneOptions::default()).unwrap(), &s, &|_| {})
            .unwrap();
    // (A clone of the device with lower limits: the kernel compiled above is reused.)
    banded_ctx.limits = limits;
    let banded = GpuBackend::with_context(banded_ctx).with_integrator(GpuIntegrator::Bdpt);
    let (bands, _) =
        tracer::render(&banded.prepare_gpu(scene, &SceneOptions::default()).unwrap(), &s, &|_| {}).unwrap();
    assert!(whole.has_splats());
    assert!(bands == whole, "bands of rows must not change bdpt's film");
}

/// A floor, a smooth copper ball with a lid placed three times (once turned, mirrored
/// and in glass, once in red: materials of the scene's instead of its own), a lamp
/// placed twice (once mirrored: it must still shine down) and an object without
/// triangles.
fn instanced_scene() -> Scene {
    use glam::{Mat4, Quat};
    let mut scene = Scene::default();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 4.0), Material::diffuse("floor", Colour::constant(0.6)).unwrap());
    let red = scene.materials.len() as u32;
    scene.materials.push(Material::diffuse("red", Colour::reflectance_rgb([0.8, 0.2, 0.1]).unwrap()).unwrap());
    let glass = scene.materials.len() as u32;
    scene.materials.push(Material::dielectric("glass", 1.5).unwrap());
    // An object of vertices without triangles, placed in view first: nothing to see (its
    // tree is empty; a root taken from the next object's would show the ball here).
    let nothing = Scene { positions: vec![[0.0; 3], [0.5, 0.5, 0.5]], ..Scene::default() };
    let nothing = scene.add_object(nothing, None).unwrap();
    scene.place(nothing, Mat4::from_translation(Vec3::new(0.0, 0.0, 1.5))).unwrap();
    let mut ball = Scene::default();
    ball.add(
        &uv_sphere(Vec3::new(0.3, 0.5, 0.0), 0.5, 12, 24, false),
        Material::builtin(
            "copper",
            ModelId::RoughConductor,
            &[("metal", ParamValue::Scalar(1.0)), ("alpha", ParamValue::Scalar(0.3))],
        )
        .unwrap(),
    );
    ball.add(&quad(Vec3::new(0.3, 1.0, 0.0), Vec3::Y, 0.3), Material::diffuse("lid", Colour::constant(0.3)).unwrap());
    let ball = scene.add_object(ball, None).unwrap();
    scene.place(ball, Mat4::from_translation(Vec3::new(-1.5, 0.0, 0.0))).unwrap();
    let mirrored = Mat4::from_translation(Vec3::new(0.2, 0.0, -0.5))
        * Mat4::from_quat(Quat::from_rotation_y(0.7))
        * Mat4::from_scale(Vec3::new(-1.0, 1.2, 1.0));
    // Glass, whose inside and outside the orientation tells apart (every other material
    // here is two-sided).
    scene.place_with(ball, mirrored, Some(glass)).unwrap();
    scene.place_with(ball, Mat4::from_translation(Vec3::new(1.6, 0.0, 0.3)), Some(red)).unwrap();
    let mut lamp = Scene::default();
    lamp.add(
        &quad(Vec3::ZERO, -Vec3::Y, 0.4),
        Material::diffuse("lamp", Colour::constant(0.0)).unwrap().with_emission(Colour::constant(12.0)),
    );
    let lamp = scene.add_object(lamp, None).unwrap();
    scene.place(lamp, Mat4::from_translation(Vec3::new(-0.8, 3.0, 0.5))).unwrap();
    let mirrored_lamp = Mat4::from_translation(Vec3::new(1.2, 2.5, -0.5))
        * Mat4::from_rotation_x(0.3)
        * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    scene.place(lamp, mirrored_lamp).unwrap();
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 2.5, 6.0), center: Vec3::new(0.0, 0.6, 0.0), up: Vec3::Y, fov_y_deg: 40.0 });
    scene
}

/// Instances are traced two-level on the device (each object's triangles uploaded once,
/// the lamps' placements copied into the world's triangles for light sampling) and match
/// the CPU's two-level render; binary and 8-wide trees (each object's rebased into the
/// shared arrays) give the same image bit for bit.
#[test]
fn instances_match_the_cpu() {
    let scene = instanced_scene();
    // Uploaded once per object: the floor's 2, the lamps' 2 × 2, the ball's triangles once
    // (not three times).
    let ball_triangles = scene.objects[1].triangles.len();
    let data = SceneData::new(
        &{
            let mut s = scene.clone();
            s.flatten_light_instances();
            s
        },
        KernelOptions::default(),
    )
    .unwrap();
    let vertex_bytes = data.buffer_sizes().iter().find(|(name, _)| *name == "triangle vertices").unwrap().1;
    assert_eq!(vertex_bytes as usize, 48 * (2 + 4 + ball_triangles));
    // A placement on an area light left for the kernel is refused (light sampling needs it
    // in world space).
    assert!(matches!(SceneData::new(&scene, KernelOptions::default()), Err(GpuError::Unsupported(_))));

    let Some(ctx) = gpu::require_gpu() else { return };
    let gpu = GpuBackend::with_context(ctx);
    let s = settings(32, 24, 128);
    let (cpu_scene, binary) = prepare_both(&gpu, &scene, None).unwrap();
    let r = render_three_with(&cpu_scene, &binary, &s).unwrap();
    assert!(r.cpu.channel_means()[1] > 0.02, "a dark image proves little");
    println!(
        "instances: cpu {:.3} M samples/s, gpu {:.3}; kernel compile {:?}, preparation {:?}",
        r.cpu_rate / 1e6,
        r.gpu_rate / 1e6,
        r.compile,
        r.prepare
    );
    let failures = compare_all("instances", &r);
    assert!(failures.is_empty(), "{failures:#?}");

    // (4-wide trees are rebased by the same code as 8-wide ones: one kernel fewer to
    // compile on lavapipe.)
    let quick = settings(24, 18, 8);
    let wide = gpu.prepare_gpu(scene, &SceneOptions { bvh_width: bvh::BvhWidth::Eight, ..SceneOptions::default() });
    let binary_film = tracer::render(&binary, &quick, &|_| {}).unwrap().0;
    assert!(binary_film.samples() > 0);
    assert!(
        binary_film == tracer::render(&wide.unwrap(), &quick, &|_| {}).unwrap().0,
        "the 8-wide trees' image differs from the binary trees'"
    );
}

/// The wavefront (`SceneOptions::wavefront`: one kernel per stage, the paths' state in
/// device memory) restates the megakernel's loop body with the same random numbers and
/// adds each pixel's samples in the same order, so on lavapipe (whose compiler fuses no
/// multiply–add) it gives the megakernel's film bit for bit, and the same ray and
/// truncation counts. The cases reach every branch of the loop body: dispersive,
/// absorbing glass beside a mirror ball at a depth limit in RGB mode (every bounce
/// dispatched up front) and in hero mode with a short limit and a long specular extension,
/// a diffuse-bounce limit and Russian roulette (the wavelengths collapse; bounces followed in
/// chunks, the host reading the live count between them); punctual lights and a sky at
/// unbounded depth; the Cornell box at unbounded depth. A GPU's compiler may fuse
/// differently in the two (an H200's does), so there the films must agree as same-seed
/// renders do. The viewer's device-side accumulation runs the wavefront too. The 40-bin
/// mode and the CPU refuse it by name.
#[test]
fn the_wavefront_gives_the_megakernels_image() {
    let Some(ctx) = gpu::require_gpu() else { return };
    let exact = ctx.info.device_type == wgpu::DeviceType::Cpu;
    let gpu = GpuBackend::with_context(ctx);
    // The same film, bit for bit where the compiler fuses no multiply–add; else the same
    // image as a same-seed render.
    let agree = |name: &str, got: &Film, want: &Film| {
        if exact {
            assert!(got == want, "{name}: the wavefront's film differs from the megakernel's");
        } else {
            let c = compare(want, got);
            assert!(c.same_seed_failures().is_none(), "{name}: {}", c.summary());
        }
    };
    let unbounded = PathSettings { max_depth: 0, rr_depth: 3, ..PathSettings::default() };
    // Through glass and mirrors past the depth limit: by one more bounce at most (which a
    // path through the glass ball needs), and by up to 15 (more than 16 bounces in all, so
    // the bounces go in chunks).
    let short = PathSettings { max_depth: 2, specular_extension: 1, max_diffuse_depth: 1, rr_depth: 1, ..unbounded };
    let deep = PathSettings { specular_extension: 15, ..short };
    let mut cases = vec![
        (
            "glass and mirror (RGB)",
            glass_and_mirror_scene(),
            RenderSettings { mode: SpectralMode::Rgb, ..settings(32, 32, 8) },
        ),
        ("glass and mirror (hero)", glass_and_mirror_scene(), RenderSettings { path: short, ..settings(32, 32, 8) }),
        (
            "glass and mirror (hero, deep)",
            glass_and_mirror_scene(),
            RenderSettings { path: deep, ..settings(32, 32, 8) },
        ),
        ("punctual lights", punctual_scene(), RenderSettings { path: unbounded, ..settings(32, 32, 8) }),
    ];
    if let Some(scene) = cornell() {
        cases.push(("Cornell box", scene, RenderSettings { path: unbounded, ..settings(40, 40, 8) }));
    }
    for (name, scene, s) in cases {
        let first_render = Some((s.sampler, s.mode));
        let mega = SceneOptions { first_render, ..SceneOptions::default() };
        let megakernel = gpu.prepare_gpu(scene.clone(), &mega).unwrap();
        let wavefront = gpu.prepare_gpu(scene, &SceneOptions { wavefront: true, ..mega }).unwrap();
        let (want, want_stats) = tracer::render(&megakernel, &s, &|_| {}).unwrap();
        let (got, got_stats) = tracer::render(&wavefront, &s, &|_| {}).unwrap();
        println!(
            "{name}: megakernel compiled in {:?}, wavefront in {:?}; {} rays, {} truncated",
            megakernel.compile_time(),
            wavefront.compile_time(),
            want_stats.rays,
            want_stats.truncated
        );
        assert!(want_stats.rays > (s.width * s.height * s.spp) as u64, "{name}: {want_stats:?}");
        if exact {
            assert_eq!((got_stats.rays, got_stats.truncated), (want_stats.rays, want_stats.truncated), "{name}");
        } else {
            let ratio = got_stats.rays as f64 / want_stats.rays as f64;
            assert!((ratio - 1.0).abs() < 0.01, "{name}: {} rays against {}", got_stats.rays, want_stats.rays);
        }
        agree(name, &got, &want);
        // Frames as the viewer adds them (statistics on the device), same samples.
        let mut frames = std::sync::Arc::new(wavefront).accumulate(&s).unwrap();
        frames.add(s.spp / 2).unwrap();
        frames.add(s.spp - s.spp / 2).unwrap();
        agree(name, &frames.film().unwrap(), &want);
    }

    let bins = SceneOptions {
        wavefront: true,
        first_render: Some((Default::default(), SpectralMode::Bins40)),
        ..SceneOptions::default()
    };
    let err = gpu.prepare_gpu(glass_and_mirror_scene(), &bins).err().expect("bins40 refused").to_string();
    assert!(err.contains("40-bin") && err.contains("--wavefront"), "{err}");
    let cpu = CpuBackend::new(1).unwrap();
    let wavefront = SceneOptions { wavefront: true, ..SceneOptions::default() };
    let err = cpu.prepare_cpu(glass_and_mirror_scene(), &wavefront).err().expect("the CPU refuses").to_string();
    assert!(err.contains("wavefront"), "{err}");
}
