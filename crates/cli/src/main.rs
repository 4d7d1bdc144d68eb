//! `spt`: the spectral path tracer's command-line tool.
// The arguments' doc comments are clap's help text, where `[:LEVEL]` means an optional
// part, not a link.
#![allow(rustdoc::broken_intra_doc_links)]

mod atlas_table;
mod bvh_table;
mod compare;
mod light_arg;
mod rays;
mod shards;
mod sheet;
mod stability;

use anyhow::{Context, Result, bail};
use bvh::isa::Isa;
use bvh::{BvhWidth, TriangleTest};
use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use spectral::SpectralMode;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;
use tracer::camera::Camera;
use tracer::integrator::{PathSettings, ShadingNormals};
use tracer::render::{Capabilities, PreparedScene, RenderStats, SceneOptions};
use tracer::sampler::SamplerKind;
use tracer::{Backend, CpuBackend, PathTracer, RenderSettings, Scene};

#[derive(Parser)]
#[command(name = "spt", version, about = "A spectral, physically based path tracer")]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Vector instructions the kernels may use: `auto`, the widest this CPU has, or at
    /// most `avx512`, `avx2` or `baseline` (SSE2: 4-wide trees), to measure the widths
    /// against each other on one machine. A level the CPU lacks is an error.
    #[arg(long, global = true, default_value = "auto", value_name = "ISA", value_parser = simd_parser())]
    simd: Isa,
}

/// `--simd`'s values: `auto` (the detected level) or a level's name.
fn simd_parser() -> impl clap::builder::TypedValueParser<Value = Isa> {
    use clap::builder::TypedValueParser;
    let names = std::iter::once("auto").chain(Isa::ALL.iter().rev().map(|i| i.name()));
    clap::builder::PossibleValuesParser::new(names)
        .map(|name| Isa::ALL.into_iter().find(|i| i.name() == name).unwrap_or_else(bvh::isa::detected))
}

/// Applies `--simd` (before any accelerator is built: the tree's width depends on it).
fn apply_simd(wanted: Isa) -> Result<()> {
    let detected = bvh::isa::detected();
    if wanted > detected {
        bail!("--simd {wanted}: this CPU runs at most {detected}");
    }
    bvh::isa::limit_to(wanted);
    Ok(())
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (PNG: 8-bit sRGB; EXR: linear float).
    Render(RenderArgs),
    /// Time whole renders of a scene in each spectral mode and print samples/s.
    Bench(BenchArgs),
    /// Render a labelled contact sheet of a BSDF parameter sweep on the material sphere.
    Sheet(SheetArgs),
    /// Compare BVH builders (the thesis's table 9.6 and more): build time, tree
    /// statistics, traversal work and rays/s, against obvhs in the same run.
    Bvh(BvhArgs),
    /// Measure every intersection routine on adversarial cases: failure rate against f64
    /// references and ns per test, as a table, a CSV and one PNG chart per family.
    Stability(stability::StabilityArgs),
    /// Open a window showing the scene refined frame by frame (running mean); drag to
    /// orbit (left) or pan (right), wheel to dolly, WASD/QE to fly, arrows to turn, R to
    /// reset, P/X to save PNG/EXR, Escape to quit. Any camera change restarts the mean.
    View(ViewArgs),
    /// Ray sets on disk, to compare our traversal ray for ray with another ray tracer:
    /// `export` a scene's triangles and rays, `trace` them (build ms, Mrays/s, hits).
    #[command(subcommand)]
    Rays(rays::RaysCommand),
    /// Merge partial renders (`render --shard K/N`, checkpoints) into one image, after
    /// checking they are one render's pieces covering every sample exactly once; the
    /// image equals the unsharded render byte for byte.
    Merge(shards::MergeArgs),
    /// Render a scene under several configurations (integrators, spectral modes,
    /// samplers, triangle tests, BVH widths, backends) at 1, 2, 4, … spp, measure relMSE
    /// and SSIM against a reference, and chart error against time (CSV, PNG, SVG).
    Compare(compare::CompareArgs),
    /// Print what a scene holds: geometry counts, materials by model, lights, the
    /// environment, the memory its arrays take and its bounds.
    Info(InfoArgs),
    /// Build the atlas integrator's texture atlas of a scene and time its gather for
    /// sample counts × atlas resolutions (the atlas thesis's table 1); write its images.
    Atlas(atlas_table::AtlasArgs),
}

#[derive(Args)]
struct InfoArgs {
    /// The scene: an .obj file (with its .mtl), a .gltf or .glb file, a .toml scene file,
    /// or a built-in scene `builtin:NAME`.
    scene: PathBuf,
}

/// `names` each once, in the order first met, with how often it occurs where more than
/// once ("lamp ×4, floor").
fn counted<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let mut seen: Vec<(&str, usize)> = Vec::new();
    for n in names {
        match seen.iter_mut().find(|(m, _)| *m == n) {
            Some((_, k)) => *k += 1,
            None => seen.push((n, 1)),
        }
    }
    seen.iter().map(|(n, k)| if *k > 1 { format!("{n} ×{k}") } else { n.to_string() }).collect::<Vec<_>>().join(", ")
}

/// `spt info`: a scene's contents, as loaded (before any default sky is added).
fn run_info(args: InfoArgs) -> Result<()> {
    let (scene, cameras) = if is_gltf(&args.scene) {
        let loaded = load_gltf(&args.scene, None)?;
        (loaded.scene, loaded.cameras)
    } else {
        (load_scene(&args.scene)?, Vec::new())
    };
    println!("{}", args.scene.display());
    println!(
        "  geometry: {} triangles, {} vertices ({} with shading normals, {} with tangents, {} with texture \
         coordinates), {} analytic shapes",
        scene.triangles.len(),
        scene.positions.len(),
        scene.normals.len(),
        scene.tangents.len(),
        scene.uvs.len(),
        scene.shapes.len()
    );
    if !scene.instances.is_empty() {
        let object_triangles: usize = scene.objects.iter().map(|o| o.triangles.len()).sum();
        println!(
            "    {} instances of {} objects ({} triangles kept once, {} placed; a two-level BVH)",
            scene.instances.len(),
            scene.objects.len(),
            object_triangles,
            scene.instanced_triangle_count()
        );
    }
    let mut shape_kinds: std::collections::BTreeMap<&str, usize> = Default::default();
    for s in &scene.shapes {
        *shape_kinds.entry(s.shape.name()).or_default() += 1;
    }
    for (kind, n) in &shape_kinds {
        println!("    {n} × {kind}");
    }
    // Per model, each name once (OBJ files and copied meshes repeat materials), with how
    // often it occurs.
    let mut by_model: std::collections::BTreeMap<String, Vec<&str>> = Default::default();
    for m in &scene.materials {
        let model = m.model().map_or("custom".to_string(), |id| id.name().to_string());
        by_model.entry(model).or_default().push(&m.name);
    }
    println!("  materials: {}", scene.materials.len());
    for (model, names) in by_model {
        println!("    {model}: {}", counted(names));
    }
    let textured: Vec<&tracer::texture::MaterialTextures> =
        scene.materials.iter().filter_map(|m| m.textures.as_deref()).collect();
    if !textured.is_empty() {
        let (images, bytes) = scene.texture_images();
        let count = |has: fn(&tracer::texture::MaterialTextures) -> bool| textured.iter().filter(|t| has(t)).count();
        println!(
            "  textures: {images} images, {:.1} MB of texels; {} textured materials ({} base colour, {} specular, \
             {} metallic-roughness, {} normal, {} bump, {} emissive, {} alpha)",
            bytes as f64 / 1e6,
            textured.len(),
            count(|t| t.base_colour.is_some()),
            count(|t| t.specular.is_some()),
            count(|t| t.metallic_roughness.is_some()),
            count(|t| t.normal.is_some()),
            count(|t| t.bump.is_some()),
            count(|t| t.emissive.is_some()),
            count(|t| t.alpha.is_some()),
        );
    }
    let emissive: Vec<String> = scene
        .materials
        .iter()
        .filter(|m| m.emission.is_some())
        .map(|m| {
            if m.has_textured_emission() { format!("{} (textured: seen, not sampled)", m.name) } else { m.name.clone() }
        })
        .collect();
    let emits = |id: u32| scene.materials.get(id as usize).is_some_and(|m| m.emission.is_some());
    let emitting_triangles = scene.material_ids.iter().filter(|&&id| emits(id)).count();
    let emitting_shapes = scene.shapes.iter().filter(|s| emits(s.material)).count();
    println!(
        "  lights: {emitting_triangles} emissive triangles, {emitting_shapes} emissive shapes ({} emissive \
         materials{}), environment: {}",
        emissive.len(),
        if emissive.is_empty() { String::new() } else { format!(": {}", counted(emissive.iter().map(String::as_str))) },
        if scene.environment.is_some() { "yes" } else { "none" }
    );
    if !scene.punctual_lights.is_empty() {
        let mut kinds: Vec<&str> = scene.punctual_lights.iter().map(|l| l.kind()).collect();
        kinds.sort_unstable();
        kinds.dedup();
        println!("    {} point, spot or directional lights ({})", scene.punctual_lights.len(), kinds.join(", "));
    }
    if !scene.has_lights() {
        println!("    no light: renders get the default white sky (--sky)");
    }
    for c in &cameras {
        let name = c.name.as_deref().map(|n| format!(" ({n})")).unwrap_or_default();
        match &c.camera {
            Some(v) => println!(
                "  camera {}{name}: eye {:.3}, looking at {:.3}, vertical field of view {:.1}°",
                c.index, v.eye, v.center, v.fov_y_deg
            ),
            None => println!("  camera {}{name}: orthographic (not supported)", c.index),
        }
    }
    let bytes = std::mem::size_of_val(scene.positions.as_slice())
        + std::mem::size_of_val(scene.normals.as_slice())
        + std::mem::size_of_val(scene.tangents.as_slice())
        + std::mem::size_of_val(scene.uvs.as_slice())
        + std::mem::size_of_val(scene.triangles.as_slice())
        + std::mem::size_of_val(scene.material_ids.as_slice())
        + std::mem::size_of_val(scene.shapes.as_slice())
        + scene
            .objects
            .iter()
            .map(|o| {
                std::mem::size_of_val(o.positions.as_slice())
                    + std::mem::size_of_val(o.normals.as_slice())
                    + std::mem::size_of_val(o.tangents.as_slice())
                    + std::mem::size_of_val(o.uvs.as_slice())
                    + std::mem::size_of_val(o.triangles.as_slice())
                    + std::mem::size_of_val(o.material_ids.as_slice())
            })
            .sum::<usize>()
        + std::mem::size_of_val(scene.instances.as_slice());
    println!(
        "  memory: {:.1} kB of vertex, triangle, shape and instance arrays (before any BVH; textures above)",
        bytes as f64 / 1e3
    );
    let b = scene.bounds();
    if b.is_empty() {
        println!("  bounds: empty");
    } else {
        println!("  bounds: {:?} – {:?} (extent {:?})", b.min.to_array(), b.max.to_array(), b.extent().to_array());
    }
    if let Some(c) = &scene.camera {
        println!("  camera: eye {:?}, centre {:?}, fov {}°", c.eye.to_array(), c.center.to_array(), c.fov_y_deg);
    }
    Ok(())
}

#[derive(Args)]
// A scene file's [render] settings come first on the command line; the user's win.
#[command(args_override_self = true)]
struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Samples per pixel added each frame.
    #[arg(long, default_value_t = 1)]
    spp_per_frame: u32,
    /// Stop refining at this many samples per pixel (until the camera moves).
    #[arg(long)]
    max_spp: Option<u32>,
    /// Quit after this many frames (for scripted runs).
    #[arg(long)]
    frames: Option<u32>,
    /// Save the image here when the viewer quits (.png or .exr).
    #[arg(long)]
    save: Option<PathBuf>,
    /// Spectral sampling mode.
    #[arg(long, default_value = "hero")]
    spectral: SpectralMode,
    /// With --backend gpu: read every frame back and show it through a CPU framebuffer,
    /// instead of drawing it from the device through a wgpu surface.
    #[arg(long)]
    no_gpu_surface: bool,
}

fn run_view(args: ViewArgs) -> Result<()> {
    if let Some(p) = &args.save {
        tracer::output::ImageFormat::from_path(p)?;
    }
    // The viewer refines without end: samplers that need the sample count only on request.
    let (prepared, settings) =
        prepare(&args.scene, args.spp_per_frame.max(1), args.spectral, |_| SamplerKind::Independent)?;
    let options = viewer::ViewerOptions {
        width: args.scene.width,
        height: args.scene.height,
        spp_per_frame: args.spp_per_frame,
        max_spp: args.max_spp,
        exit_after_frames: args.frames,
        save_on_exit: args.save.clone(),
        title: args.scene.scene.display().to_string(),
        device_display: !args.no_gpu_surface,
    };
    options.validate()?;
    let stats = viewer::run(prepared, settings, options)?;
    eprintln!(
        "{} frames ({} drawn from the GPU's device), {} spp, {:.3} M samples/s",
        stats.frames,
        stats.frames_on_device,
        stats.spp,
        stats.samples_per_second / 1e6
    );
    if stats.interrupted {
        // As a shell reports a command ended by Ctrl-C (128 + SIGINT; SIGTERM too), after
        // saving.
        std::process::exit(130);
    }
    Ok(())
}

#[derive(Args)]
struct BvhArgs {
    /// The scene file (.obj with its .mtl).
    scene: PathBuf,
    /// Image width for the primary rays.
    #[arg(long, default_value_t = 256)]
    width: u32,
    /// Image height for the primary rays.
    #[arg(long, default_value_t = 256)]
    height: u32,
    /// Builders, comma-separated (default: all): sweep_sah, binned_sah, midpoint, hybrid.
    #[arg(long, value_delimiter = ',')]
    builders: Vec<String>,
    /// Maximum leaf sizes, comma-separated (default: 1,2,3,4,8).
    #[arg(long, value_delimiter = ',')]
    leaf_sizes: Vec<usize>,
    /// Camera position x,y,z for the primary rays (default: frame the bounding box from +z).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, requires = "center")]
    eye: Option<Vec3>,
    /// Point the camera looks at, x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, requires = "eye")]
    center: Option<Vec3>,
}

fn run_bvh(args: BvhArgs) -> Result<()> {
    let mut scene = load_scene(&args.scene)?;
    // The builders compared here take one triangle soup: instances are copied into it.
    scene.flatten_instances();
    if scene.triangles.is_empty() {
        bail!("{}: the scene has no triangles", args.scene.display());
    }
    let name = args.scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let builders: Vec<&str> = args.builders.iter().map(String::as_str).collect();
    let camera = args.eye.zip(args.center);
    bvh_table::run(&scene.triangle_soup(), &name, args.width, args.height, &builders, &args.leaf_sizes, camera)
}

#[derive(Args)]
struct SheetArgs {
    /// A sweep from the thesis's figures: schlick-r, schlick-p, sa-n, sa-aniso.
    #[arg(long, conflicts_with_all = ["model", "param", "values"])]
    preset: Option<String>,
    /// BSDF model to sweep (when not using --preset).
    #[arg(long, requires_all = ["param", "values"])]
    model: Option<String>,
    /// Parameter to sweep.
    #[arg(long)]
    param: Option<String>,
    /// Values of the swept parameter, comma-separated.
    #[arg(long, value_delimiter = ',')]
    values: Vec<f32>,
    /// Fixed parameters, name=value (repeatable).
    #[arg(long = "set", value_parser = parse_assignment)]
    fixed: Vec<(String, f32)>,
    /// Cell size in pixels.
    #[arg(long, default_value_t = 160)]
    cell: u32,
    /// Samples per pixel per cell.
    #[arg(long, default_value_t = 64)]
    spp: u32,
    /// Spectral sampling mode.
    #[arg(long, default_value = "hero")]
    spectral: SpectralMode,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Output PNG.
    #[arg(short, long, default_value = "sheet.png")]
    output: PathBuf,
}

fn parse_assignment(s: &str) -> Result<(String, f32), String> {
    let (k, v) = s.split_once('=').ok_or_else(|| format!("expected name=value, got '{s}'"))?;
    let v: f32 = v.trim().parse().map_err(|_| format!("'{v}' is not a number"))?;
    Ok((k.trim().to_string(), v))
}

fn run_sheet(args: SheetArgs) -> Result<()> {
    let mut sweep = match (&args.preset, &args.model, &args.param) {
        (Some(p), _, _) => sheet::preset(p)?,
        (None, Some(m), Some(param)) => sheet::Sweep {
            model: tracer::material::ModelId::by_name(m).ok_or_else(|| {
                anyhow::anyhow!("unknown model '{m}' (known: {})", tracer::material::ModelId::names())
            })?,
            fixed: vec![],
            cells: args.values.iter().map(|&v| vec![(param.clone(), v)]).collect(),
        },
        _ => bail!("give --preset, or --model with --param and --values"),
    };
    sweep.fixed.extend(args.fixed.iter().cloned());
    sheet::render_sheet(&sweep, args.cell, args.spp, args.spectral, args.threads, &args.output)?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

#[derive(Args, Clone)]
struct SceneArgs {
    /// The scene: an .obj file (with its .mtl), a .gltf or .glb file, a .toml scene file,
    /// or a built-in scene `builtin:NAME` (sphereflake[:LEVEL], glass-torus,
    /// glass-torus-laguerre, glass-bunny[:OBJ]).
    scene: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Random seed: the same seed gives the same image, whatever the thread count.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Maximum number of bounces; 0 = unbounded (Russian roulette only).
    #[arg(long, default_value_t = 0)]
    max_depth: u32,
    /// Maximum number of diffuse or glossy bounces (mirrors and glass do not count); 0 =
    /// no limit. 2 is direct light plus one diffuse bounce, what --integrator atlas
    /// approximates (the path tracer, CPU or GPU).
    #[arg(long, default_value_t = 0)]
    max_diffuse_depth: u32,
    /// Run the CPU path tracer's general loop even where the scene needs no more than
    /// diffuse triangles, instead of its lanes kernel (eight paths per vector
    /// instruction; the same image to the bit): to measure what the specialisation saves.
    #[arg(long)]
    no_lanes: bool,
    /// Bounces before Russian roulette starts.
    #[arg(long, default_value_t = 3)]
    rr_depth: u32,
    /// Russian roulette keeps a path with probability min(0.95, S × its throughput). 1 is
    /// Mitsuba's rule; the default 2 reached a given error as soon or sooner on every scene
    /// measured, by up to 30 % (docs/figures.md). Unbiased for any S in (0, 100].
    #[arg(long, value_name = "S", default_value_t = 2.0, allow_negative_numbers = true)]
    rr_scale: f32,
    /// Extra bounces allowed beyond --max-depth through purely specular surfaces
    /// (mirrors, glass): the thesis's path extension.
    #[arg(long, default_value_t = 0)]
    extension: u32,
    /// A glTF scene's camera, by index or name (default: the first camera the scene
    /// places; --eye, --center and --fov start from it).
    #[arg(long, value_name = "N|NAME")]
    camera: Option<String>,
    /// Camera position x,y,z (default: the scene's camera, else frame its bounding box).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<Vec3>,
    /// Point the camera looks at, x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    center: Option<Vec3>,
    /// Camera up direction x,y,z.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    up: Vec3,
    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = tracer::camera::DEFAULT_FOV_Y_DEG)]
    fov: f32,
    /// Ray–triangle test: watertight (Woop et al. 2013) or moller-trumbore (the thesis's).
    #[arg(long, default_value = "watertight", value_parser = parse_triangle_test)]
    triangle_test: TriangleTest,
    /// Children per node of the triangle BVH: auto (the backend's choice: on the CPU 8
    /// where it has AVX2, else 4; on the GPU 2), 2 (binary, GPU only), 4 (SSE on the CPU,
    /// 4-wide nodes on the GPU) or 8 (AVX2 on the CPU, 8-wide nodes on the GPU).
    #[arg(long, default_value = "auto", value_parser = parse_bvh_width)]
    bvh_width: BvhWidth,
    /// How the triangle BVH's nodes are split: binned_sah (the default), sweep_sah (full
    /// sweep, the thesis's Algorithm 8.2), midpoint, or hybrid (midpoint above 1000
    /// triangles, sweep below); on the GPU it builds the binary tree the kernel traverses.
    #[arg(long, value_parser = parse_bvh_builder)]
    bvh_builder: Option<bvh::SplitMethod>,
    /// GPU path tracer only: trace paths as a wavefront (one kernel per stage — camera
    /// rays, closest hits, shading, shadow rays — the paths' state in device memory)
    /// instead of the megakernel's one loop per camera ray; the same image statistics, to
    /// measure the two designs against each other (docs/gpu.md).
    #[arg(long)]
    wavefront: bool,
    /// How next-event estimation chooses a light: power (in proportion to power, the
    /// same everywhere), tree (a light tree, Conty Estevez & Kulla 2018: by what each
    /// emitter, point or spot light can give the shading point — for scenes of many
    /// lights; the path, direct and atlas integrators, and path-caustics on the CPU) or
    /// auto (the tree from 8 such lights where the integrator takes one, else power).
    #[arg(long, default_value = "auto", value_parser = parse_light_sampler)]
    light_sampler: tracer::LightSampler,
    /// Where to trace: cpu (rayon, every feature) or gpu (wgpu compute; hero mode, triangle
    /// meshes, registered BSDFs). A request outside a backend's capabilities is refused
    /// before any work, with the way out.
    #[arg(long, default_value = "cpu", value_parser = BACKENDS)]
    backend: String,
    /// Sample values: zsobol (Owen-scrambled Sobol in Morton order: stratified per pixel,
    /// blue-noise error; lays its samples out for --spp, best a power of two), sobol
    /// (Owen-scrambled Sobol per pixel) or independent (PCG32 per pixel sample). Default:
    /// the backend's best (zsobol on both); the viewer: independent.
    #[arg(long, value_parser = parse_sampler)]
    sampler: Option<SamplerKind>,
    /// Light transport: path (path tracing with next-event estimation and MIS),
    /// path-caustics (CPU only: path tracing with the caustics seen on diffuse surfaces,
    /// through glass or off mirrors, found by light paths instead — far less noise there,
    /// the same image in expectation; without a specular surface, with a depth limit or
    /// dispersion it is path), direct
    /// (emission plus light sampled at the first surface: path tracing's --max-depth 1
    /// without BSDF-sampled light), ao (ambient occlusion within --ao-distance; not
    /// light), whitted (recursive ray tracing: mirrors and glass split into their Fresnel-
    /// weighted reflections and refractions, direct light only elsewhere; depth
    /// --max-depth, 8 when unbounded), bdpt (bidirectional path tracing: camera and light
    /// subpaths connected in every way, weighted by MIS, light tracing splatted onto the
    /// image; for small lights and caustics), atlas (one bounce of diffuse light gathered
    /// on a texture atlas of the scene, built once per scene; direct light per pixel).
    /// direct, ao, whitted and atlas are biased by design.
    #[arg(long, default_value = "path", value_parser = INTEGRATORS)]
    integrator: String,
    /// The ao integrator's reach: occluders farther than this from the surface do not
    /// count (scene units; default: any distance).
    #[arg(long, default_value_t = f32::INFINITY, value_parser = parse_distance)]
    ao_distance: f32,
    /// The atlas integrator's atlas side in texels (its density is the largest whose
    /// charts fit; grown if they cannot).
    #[arg(long, default_value_t = 512)]
    atlas_resolution: u32,
    /// The atlas's texels per scene unit instead of --atlas-resolution (0: from it).
    #[arg(long, default_value_t = 0.0)]
    atlas_density: f32,
    /// Points gathered per atlas texel for its bounce of indirect light.
    #[arg(long, default_value_t = 256)]
    atlas_samples: u32,
    /// Whether the gather tests visibility (off: light leaks through walls, as in the
    /// atlas thesis).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    atlas_visibility: String,
    /// What the atlas lookup does at chart borders: dilate (the gathered light fills the
    /// gutter) or none (the thesis's dark seams).
    #[arg(long, default_value = "dilate", value_parser = ["dilate", "none"])]
    atlas_seams: String,
    /// Light samples per atlas texel for its direct light.
    #[arg(long, default_value_t = 16)]
    atlas_direct_samples: u32,
    /// Shading normals: adapted (bent where they disagree with the geometry),
    /// face-forward (the thesis's workaround) or geometric (flat shading).
    #[arg(long, default_value = "adapted", value_parser = parse_shading_normals)]
    shading_normals: ShadingNormals,
    /// Light from everywhere that hits nothing: auto (the scene's own; a uniform white sky
    /// — CIE D65, luminance 1 — if the scene has no light at all), none (no sky, even the
    /// scene's), white or white:LUMINANCE (a uniform white sky replacing the scene's),
    /// FILE.spec (the `sky` SPD of a SPEC file in the thesis's format), or an environment
    /// map FILE.exr|.hdr|.png|.jpg[:SCALE] (latitude-longitude, y up, its centre towards
    /// −z; importance-sampled by luminance; CPU backend).
    #[arg(long, default_value = "auto", value_parser = parse_sky)]
    sky: Sky,
    /// A SPEC file (the thesis's JSON of SPDs) giving the scene's materials diffuse and
    /// specular spectra and its sky; default for an OBJ: the SPEC file of the same name
    /// beside it, if any.
    #[arg(long, value_name = "FILE.spec")]
    spec: Option<PathBuf>,
    /// Changes a value of a .toml scene file before it is read (repeatable): a dotted key
    /// and a TOML value, e.g. materials.gold.alpha=0.3, shape.0.radius=0.4, camera.fov=30.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Adds a light (repeatable): point:X,Y,Z:I, spot:X,Y,Z:DX,DY,DZ:INNER,OUTER:I or
    /// sun:DX,DY,DZ:E[:DIAMETER], with I (radiant intensity) or E (irradiance) one value for
    /// white or R,G,B in linear sRGB, cone half-angles and the sun's angular diameter in
    /// degrees (0, the default: a delta direction), D the direction it shines in.
    /// CPU backend only. A scene so lit gets no default sky.
    #[arg(long = "light", value_name = "LIGHT", value_parser = light_arg::parse_light, allow_hyphen_values = true)]
    lights: Vec<tracer::PunctualLight>,
    /// Renders the materials without their textures (colour, normal, bump, alpha and
    /// emission maps): their factors alone, as a backend without textures would need.
    /// The files are still read.
    #[arg(long)]
    no_textures: bool,
}

/// `--sky`: what lights a scene from infinitely far away.
#[derive(Clone, Debug, PartialEq)]
enum Sky {
    /// The scene's own environment, or the default white sky if nothing emits.
    Auto,
    /// No environment.
    None,
    /// A uniform D65 sky of this luminance.
    White(f32),
    /// The `sky` SPD of a SPEC file.
    Spec(PathBuf),
    /// A latitude–longitude environment map times a scale.
    Map(PathBuf, f32),
}

fn parse_sky(s: &str) -> Result<Sky, String> {
    let bad = || {
        format!(
            "unknown sky '{s}' (known: auto, none, white, white:LUMINANCE with LUMINANCE > 0, FILE.spec, or an environment map FILE.exr|.hdr|.png|.jpg[:SCALE])"
        )
    };
    let lower = s.to_ascii_lowercase();
    if lower.ends_with(".spec") {
        return Ok(Sky::Spec(PathBuf::from(s)));
    }
    // FILE.exr (and .hdr, .png, .jpg), optionally :SCALE.
    let (file, scale) = match s.rsplit_once(':') {
        Some((file, scale)) if scale.trim().parse::<f32>().is_ok() => (file, scale.trim().parse::<f32>().unwrap()),
        _ => (s, 1.0),
    };
    if [".exr", ".hdr", ".png", ".jpg", ".jpeg"].iter().any(|e| file.to_ascii_lowercase().ends_with(e)) {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(format!("environment map scale {scale} must be positive and finite"));
        }
        return Ok(Sky::Map(PathBuf::from(file), scale));
    }
    match s {
        "auto" => Ok(Sky::Auto),
        "none" => Ok(Sky::None),
        "white" => Ok(Sky::White(tracer::scene::DEFAULT_SKY_LUMINANCE)),
        _ => {
            let l: f32 = s.strip_prefix("white:").ok_or_else(bad)?.trim().parse().map_err(|_| bad())?;
            if l.is_finite() && l > 0.0 { Ok(Sky::White(l)) } else { Err(bad()) }
        }
    }
}

/// Applies `--sky` to a loaded scene (warning when the default sky stands in for missing
/// lights, as `spt render` and `spt view` would otherwise show black).
fn apply_sky(scene: &mut Scene, sky: &Sky) -> Result<()> {
    match sky {
        Sky::Auto if !scene.has_lights() => {
            let l = tracer::scene::DEFAULT_SKY_LUMINANCE;
            scene.environment = Some(tracer::Environment::white_sky(l));
            eprintln!(
                "warning: the scene has no light (no Ke > 0 and no environment): lit by a uniform white sky \
                 (D65, luminance {l}); --sky none renders it unlit, --sky white:L sets the luminance"
            );
        }
        Sky::Auto => {}
        Sky::None => scene.environment = None,
        Sky::White(l) => scene.environment = Some(tracer::Environment::white_sky(*l)),
        Sky::Spec(path) => {
            let Some(radiance) = tracer::spec::load_spec(path)?.sky_radiance() else {
                bail!("--sky {}: the SPEC file names no sky", path.display())
            };
            scene.environment = Some(tracer::Environment::uniform(radiance));
        }
        Sky::Map(path, scale) => {
            let map = tracer::envmap::EnvironmentMap::load(path, 0.0)?;
            scene.environment = Some(tracer::Environment::from_map(map, *scale));
        }
    }
    Ok(())
}

pub(crate) fn parse_triangle_test(s: &str) -> Result<TriangleTest, String> {
    [TriangleTest::Watertight, TriangleTest::MollerTrumbore]
        .into_iter()
        .find(|t| t.name() == s)
        .ok_or_else(|| format!("unknown triangle test '{s}' (known: watertight, moller-trumbore)"))
}

fn parse_bvh_width(s: &str) -> Result<BvhWidth, String> {
    BvhWidth::ALL
        .into_iter()
        .find(|w| w.name() == s)
        .ok_or_else(|| format!("unknown BVH width '{s}' (known: auto, 2, 4, 8)"))
}

/// `--light-sampler`'s values (and `spt compare`'s "light_sampler").
pub(crate) fn parse_light_sampler(s: &str) -> Result<tracer::LightSampler, String> {
    match s {
        "auto" => Ok(tracer::LightSampler::Auto),
        "power" => Ok(tracer::LightSampler::Power),
        "tree" => Ok(tracer::LightSampler::Tree),
        _ => Err(format!("unknown light sampler {s:?}: auto, power or tree")),
    }
}

fn parse_bvh_builder(s: &str) -> Result<bvh::SplitMethod, String> {
    bvh::SplitMethod::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
        let known: Vec<&str> = bvh::SplitMethod::ALL.iter().map(|m| m.name()).collect();
        format!("unknown BVH builder '{s}' (known: {})", known.join(", "))
    })
}

fn parse_sampler(s: &str) -> Result<SamplerKind, String> {
    SamplerKind::ALL.into_iter().find(|k| k.name() == s).ok_or_else(|| {
        let known: Vec<&str> = SamplerKind::ALL.iter().map(|k| k.name()).collect();
        format!("unknown sampler '{s}' (known: {})", known.join(", "))
    })
}

fn parse_shading_normals(s: &str) -> Result<ShadingNormals, String> {
    [ShadingNormals::Adapted, ShadingNormals::FaceForward, ShadingNormals::Geometric]
        .into_iter()
        .find(|t| t.name() == s)
        .ok_or_else(|| format!("unknown shading-normal mode '{s}' (known: adapted, face-forward, geometric)"))
}

#[derive(Args)]
// A scene file's [render] settings come first on the command line; the user's win.
#[command(args_override_self = true)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64)]
    spp: u32,
    /// Spectral sampling: hero (4 importance-sampled wavelengths), bins40 (the thesis's
    /// fixed 380–770 nm bins) or rgb.
    #[arg(long, default_value = "hero")]
    spectral: SpectralMode,
    /// Output image (.png or .exr).
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,
    /// Also write the per-pixel standard error of the mean (linear EXR).
    #[arg(long)]
    stderr: Option<PathBuf>,
    /// Measure the render against this image (linear EXR of the same size) as it goes:
    /// passes end at powers of two of the sample count and each prints its relMSE (as
    /// `spt compare` defines it; pbrt's --mse-reference-image). The image written is the
    /// one a render without it writes.
    #[arg(long, value_name = "REF.exr")]
    reference: Option<PathBuf>,
    #[command(flatten)]
    pieces: shards::PieceArgs,
}

#[derive(Args)]
// A scene file's [render] settings come first on the command line; the user's win.
#[command(args_override_self = true)]
struct BenchArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Samples per pixel per timed render.
    #[arg(long, default_value_t = 16)]
    spp: u32,
    /// Timed renders per mode (the median is reported).
    #[arg(long, default_value_t = 3)]
    repeats: u32,
    /// Spectral modes to time, comma-separated [default: those of hero,bins40,rgb the
    /// backend runs — all three, but for the GPU's --wavefront, which has no bins40].
    #[arg(long, value_delimiter = ',')]
    modes: Vec<SpectralMode>,
    /// Time N viewer frames per mode instead of whole renders: each frame adds --spp
    /// samples per pixel to a running accumulation and converts it for display (what
    /// `spt view` does per frame, without the window); frames/s and the median frame
    /// time are reported, after one untimed frame.
    #[arg(long, value_name = "N")]
    frames: Option<u32>,
    /// With --frames and --backend gpu: leave each frame's display pixels on the device
    /// instead of reading them back (what `spt view --backend gpu` does with its wgpu
    /// surface, less the drawing onto the window).
    #[arg(long, requires = "frames")]
    frames_on_device: bool,
}

pub(crate) fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected x,y,z, got '{s}'"));
    }
    let mut v = [0.0f32; 3];
    for (o, p) in v.iter_mut().zip(&parts) {
        *o = p.trim().parse().map_err(|_| format!("'{p}' is not a number"))?;
        if !o.is_finite() {
            return Err(format!("'{p}' is not finite"));
        }
    }
    Ok(Vec3::from_array(v))
}

pub(crate) fn load_scene(path: &Path) -> Result<Scene> {
    load_scene_with(path, None, None, &[])
}

/// A scene path's format, by its extension (lower case), or `builtin` for `builtin:NAME`.
fn scene_format(path: &Path) -> Option<String> {
    if path.to_str().is_some_and(|p| p.starts_with("builtin:")) {
        return Some("builtin".into());
    }
    path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase)
}

/// Whether `path` names a glTF file.
fn is_gltf(path: &Path) -> bool {
    matches!(scene_format(path).as_deref(), Some("gltf" | "glb"))
}

/// A glTF file converted, its notes (what the conversion ignored) printed as warnings.
fn load_gltf(path: &Path, camera: Option<&str>) -> Result<tracer::gltf_scene::GltfScene> {
    let options = tracer::gltf_scene::GltfOptions { camera: camera.map(str::to_string) };
    let loaded = tracer::gltf_scene::load_gltf(path, &options)?;
    for note in &loaded.notes {
        eprintln!("warning: {}: {note}", path.display());
    }
    Ok(loaded)
}

/// Loads a scene by its format: `camera` picks a glTF file's camera (index or name), `sets`
/// changes a scene file's values, and a SPEC file is applied — `spec`, else for an OBJ the
/// one beside it.
pub(crate) fn load_scene_with(
    path: &Path,
    camera: Option<&str>,
    spec: Option<&Path>,
    sets: &[String],
) -> Result<Scene> {
    let format = scene_format(path);
    let format = format.as_deref();
    if let Some(camera) = camera
        && !matches!(format, Some("gltf" | "glb"))
    {
        match format {
            Some("toml") => bail!(
                "--camera {camera}: {} is a scene file (its [camera] or a glTF mesh's camera applies)",
                path.display()
            ),
            _ => bail!("--camera {camera}: {} has no cameras (only glTF scenes do)", path.display()),
        }
    }
    if !sets.is_empty() && format != Some("toml") {
        bail!("--set applies to .toml scene files; {} is not one", path.display());
    }
    let mut scene = match format {
        Some("builtin") => tracer::scenes::builtin(&path.to_string_lossy()["builtin:".len()..])?,
        Some("gltf" | "glb") => load_gltf(path, camera)?.scene,
        Some("toml") => tracer::scene_file::load_scene_file_with(path, sets)?,
        Some("obj") => tracer::obj::load_obj(path)?,
        _ => bail!(
            "{}: unsupported scene format (supported: .obj, .gltf, .glb, .toml, or builtin:NAME with NAME one of {})",
            path.display(),
            tracer::scenes::BUILTIN_SCENES.join(", ")
        ),
    };
    let spec = match spec {
        Some(spec) => Some(spec.to_path_buf()),
        None if format == Some("obj") => tracer::spec::spec_beside(path)
            .inspect(|s| eprintln!("note: applying {} (the SPEC file beside the OBJ)", s.display())),
        None => None,
    };
    if let Some(spec) = spec {
        for note in tracer::spec::load_spec(&spec)?.apply(&mut scene)? {
            eprintln!("warning: {}: {note}", spec.display());
        }
    }
    Ok(scene)
}

fn settings(
    args: &SceneArgs,
    spp: u32,
    mode: SpectralMode,
    sampler: SamplerKind,
    scene: &Scene,
) -> Result<RenderSettings> {
    let camera = match (args.eye, args.center) {
        (None, None) if args.fov == tracer::camera::DEFAULT_FOV_Y_DEG && args.up == Vec3::Y => None,
        (eye, center) => {
            let base = scene
                .camera
                .unwrap_or_else(|| Camera::framing(&scene.bounds(), args.width as f32 / args.height.max(1) as f32));
            Some(Camera {
                eye: eye.unwrap_or(base.eye),
                center: center.unwrap_or(base.center),
                up: args.up,
                fov_y_deg: args.fov,
            })
        }
    };
    let s = RenderSettings {
        width: args.width,
        height: args.height,
        spp,
        seed: args.seed,
        mode,
        sampler,
        path: PathSettings {
            max_depth: args.max_depth,
            rr_depth: args.rr_depth,
            rr_scale: args.rr_scale,
            specular_extension: args.extension,
            shading_normals: args.shading_normals,
            max_diffuse_depth: args.max_diffuse_depth,
            lanes: !args.no_lanes,
            ..Default::default()
        },
        camera,
        crop: None,
    };
    s.validate()?;
    Ok(s)
}

/// The backend's preferred sampler (its capabilities list samplers best first).
fn best_sampler(caps: &Capabilities) -> SamplerKind {
    caps.samplers.first().copied().unwrap_or_default()
}

/// The backends `--backend` accepts.
const BACKENDS: [&str; 2] = ["cpu", "gpu"];

/// The integrators `--integrator` accepts.
const INTEGRATORS: [&str; 7] = ["path", "path-caustics", "direct", "ao", "whitted", "bdpt", "atlas"];

fn parse_distance(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(d) if d > 0.0 && !d.is_nan() => Ok(d),
        _ => Err(format!("'{s}' is not a positive distance (inf for any)")),
    }
}

/// A share of extra BVH references (`--presplit`): 0 to 4.
pub(crate) fn parse_fraction(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(f) if (0.0..=4.0).contains(&f) => Ok(f),
        _ => Err(format!("'{s}' is not a fraction between 0 and 4 (extra references per triangle)")),
    }
}

/// Loads the scene, makes the backend `args` asks for, checks the render settings
/// against its capabilities (before building anything), and prepares the scene. Without
/// `--sampler`, `default_sampler` picks one from the backend's capabilities.
fn prepare(
    args: &SceneArgs,
    spp: u32,
    mode: SpectralMode,
    default_sampler: fn(&Capabilities) -> SamplerKind,
) -> Result<(Box<dyn PreparedScene>, RenderSettings)> {
    prepare_checked(args, spp, mode, default_sampler, |_| Ok(()))
}

/// [`prepare`], with `check` of the command's own options against the backend's
/// capabilities also run before anything is built.
fn prepare_checked(
    args: &SceneArgs,
    spp: u32,
    mode: SpectralMode,
    default_sampler: fn(&Capabilities) -> SamplerKind,
    check: impl FnOnce(&Capabilities) -> Result<()>,
) -> Result<(Box<dyn PreparedScene>, RenderSettings)> {
    let scene = loaded_scene(args)?;
    let backend = make_backend(args)?;
    let caps = backend.capabilities();
    check(&caps)?;
    let sampler = args.sampler.unwrap_or_else(|| default_sampler(&caps));
    let settings = settings(args, spp, mode, sampler, &scene)?;
    caps.check_settings(&settings)?;
    let options = SceneOptions { first_render: Some((settings.sampler, settings.mode)), ..scene_options(args) };
    let prepared = backend.prepare(scene, &options)?;
    // Whatever else the render needs before its first sample (the GPU compiled the
    // settings' kernel while preparing) belongs to preparation, not to the timed render.
    prepared.warm_up(&settings)?;
    Ok((prepared, settings))
}

/// The scene `args` names, with its extra lights, textures stripped if asked and the
/// sky applied.
fn loaded_scene(args: &SceneArgs) -> Result<Scene> {
    let mut scene = load_scene_with(&args.scene, args.camera.as_deref(), args.spec.as_deref(), &args.sets)?;
    if scene.triangles.is_empty() && scene.shapes.is_empty() && scene.instances.is_empty() {
        bail!("{}: the scene has no geometry", args.scene.display());
    }
    scene.punctual_lights.extend(args.lights.iter().cloned());
    if args.no_textures {
        scene.strip_textures();
    }
    apply_sky(&mut scene, &args.sky)?;
    Ok(scene)
}

/// The scene-level choices `args` makes.
fn scene_options(args: &SceneArgs) -> SceneOptions {
    SceneOptions {
        triangle_test: args.triangle_test,
        bvh_width: args.bvh_width,
        bvh_builder: args.bvh_builder,
        first_render: None,
        wavefront: args.wavefront,
        light_sampler: args.light_sampler,
    }
}

/// The atlas integrator's settings from the command line.
fn atlas_settings(args: &SceneArgs) -> Result<tracer::AtlasSettings> {
    let s = tracer::AtlasSettings {
        density: args.atlas_density,
        resolution: args.atlas_resolution,
        samples: args.atlas_samples,
        visibility: args.atlas_visibility == "on",
        seams: if args.atlas_seams == "none" { tracer::SeamFix::None } else { tracer::SeamFix::Dilate },
        direct_samples: args.atlas_direct_samples,
        seed: args.seed,
    };
    s.validate()?;
    Ok(s)
}

/// The backend `args` asks for, running the integrator it names; a GPU that cannot be
/// opened is an error that says so.
fn make_backend(args: &SceneArgs) -> Result<Box<dyn Backend>> {
    let backend: Box<dyn Backend> = match args.backend.as_str() {
        "gpu" => {
            let integrator = match args.integrator.as_str() {
                "path" => gpu::kernel::GpuIntegrator::Path,
                "direct" => gpu::kernel::GpuIntegrator::Direct,
                "ao" => gpu::kernel::GpuIntegrator::AmbientOcclusion { max_distance: args.ao_distance },
                "whitted" => gpu::kernel::GpuIntegrator::Whitted,
                "atlas" => gpu::kernel::GpuIntegrator::Atlas(atlas_settings(args)?),
                "bdpt" => gpu::kernel::GpuIntegrator::Bdpt,
                "path-caustics" => bail!("the GPU backend has no path-caustics integrator: use --backend cpu"),
                other => bail!("unknown integrator '{other}' (known: {})", INTEGRATORS.join(", ")),
            };
            let gpu = gpu::GpuBackend::new()?.with_integrator(integrator);
            let info = &gpu.context().info;
            eprintln!("GPU: {} ({:?}, driver {})", info.name, info.backend, info.driver);
            Box::new(gpu)
        }
        _ => match args.integrator.as_str() {
            "path" => Box::new(CpuBackend::with_integrator(args.threads, PathTracer)?),
            "path-caustics" => Box::new(CpuBackend::with_integrator(args.threads, tracer::CausticPathTracer)?),
            "direct" => Box::new(CpuBackend::with_integrator(args.threads, tracer::DirectLighting)?),
            "whitted" => Box::new(CpuBackend::with_integrator(args.threads, tracer::Whitted)?),
            "bdpt" => Box::new(CpuBackend::with_integrator(args.threads, tracer::Bdpt)?),
            "atlas" => {
                Box::new(CpuBackend::with_integrator(args.threads, tracer::AtlasGi::new(atlas_settings(args)?))?)
            }
            "ao" => {
                Box::new(CpuBackend::with_integrator(args.threads, tracer::AmbientOcclusion::new(args.ao_distance))?)
            }
            other => bail!("unknown integrator '{other}' (known: {})", INTEGRATORS.join(", ")),
        },
    };
    let caps = backend.capabilities();
    if caps.integrator != args.integrator {
        bail!(
            "the {} backend runs the '{}' integrator, not '{}': use --integrator {}, or --backend cpu",
            caps.backend,
            caps.integrator,
            args.integrator,
            caps.integrator
        );
    }
    Ok(backend)
}

/// The end-of-render line: wall time, speed, dropped and truncated samples.
fn report(output: &Path, stats: &RenderStats, caps: &Capabilities) {
    let secs = stats.wall.as_secs_f64();
    eprintln!(
        "wrote {}: {:.2} s, {:.3} M samples/s, {:.2} M rays/s, {} NaN/Inf samples dropped",
        output.display(),
        secs,
        stats.samples_per_second() / 1e6,
        stats.rays as f64 / secs.max(1e-9) / 1e6,
        stats.non_finite
    );
    if stats.truncated > 0 {
        match caps.max_bounces {
            Some(cap) => eprintln!(
                "warning: {} paths reached the {} backend's cap of {cap} bounces and were cut short (a bias; \
                 --backend cpu has no cap)",
                stats.truncated, caps.backend,
            ),
            // The backend has none: the integrator's own (bdpt's subpaths).
            None => eprintln!(
                "warning: {} paths reached the {} integrator's cap of {} bounces and were cut short (a bias)",
                stats.truncated,
                caps.integrator,
                tracer::integrator::BDPT_MAX_VERTICES - 2
            ),
        }
    }
}

fn run_render(args: RenderArgs) -> Result<()> {
    let outputs = args.pieces.outputs(&args.output)?;
    if let Some(p) = &args.stderr
        && outputs.image.is_none()
    {
        bail!("{}: a shard writes no images (`spt merge --stderr` does)", p.display());
    }
    if let Some(p) = &args.stderr
        && tracer::output::ImageFormat::from_path(p)? != tracer::output::ImageFormat::Exr
    {
        bail!("{}: the standard-error image must be an .exr (it is linear)", p.display());
    }
    let tiles = outputs.shard.is_some() && args.pieces.shard_by == shard::Split::Tiles;
    // A band of rows is refused again where it is rendered (`shard::run_work`); checked
    // here too so that the refusal comes before the scene is built.
    let (prepared, settings) = prepare_checked(&args.scene, args.spp, args.spectral, best_sampler, |caps| {
        if tiles {
            shard::check_band(caps)?;
        }
        Ok(())
    })?;
    let s = prepared.scene();
    let stats = prepared.stats();
    let instanced = if s.instances.is_empty() {
        String::new()
    } else {
        format!(
            " (+ {} placed by {} instances of {} objects)",
            s.instanced_triangle_count(),
            s.instances.len(),
            s.objects.len()
        )
    };
    eprintln!(
        "{}: {} triangles{instanced}, {} shapes, {} emissive{}{}, {} built in {:.1} ms{}; {}×{} at {} spp, {} mode, {} backend{}",
        args.scene.scene.display(),
        s.triangles.len(),
        s.shapes.len(),
        stats.emitters,
        match s.punctual_lights.len() {
            0 => String::new(),
            n => format!(" + {n} punctual"),
        },
        if stats.light_tree { " (chosen by a light tree)" } else { "" },
        stats.accelerator,
        stats.build.as_secs_f64() * 1e3,
        match stats.hull_triangles {
            0 => String::new(),
            n => format!(" ({n} on the hull left out of shadow rays)"),
        } + &stats.compile.map_or(String::new(), |c| format!(", kernel compiled in {:.1} ms", c.as_secs_f64() * 1e3))
            + &stats
                .integrator
                .map_or(String::new(), |c| format!(", integrator prepared in {:.1} ms", c.as_secs_f64() * 1e3)),
        settings.width,
        settings.height,
        settings.spp,
        settings.mode.name(),
        prepared.capabilities().backend,
        prepared.kernel(&settings).map_or(String::new(), |k| format!(" ({k})"))
    );
    if !s.has_lights() {
        eprintln!("warning: the scene has no light (no Ke > 0, and --sky none): the image will be black");
    }
    if args.scene.integrator == "atlas" && !s.shapes.is_empty() {
        eprintln!(
            "warning: the atlas holds triangles only: the {} analytic shapes get no indirect light and give none",
            s.shapes.len()
        );
    }
    if let Some(reference) = &args.reference {
        let p = &args.pieces;
        if p.shard.is_some() || p.time.is_some() || p.write_partial.is_some() || p.partial.is_some() {
            bail!(
                "--reference measures one whole render pass by pass: it does not combine with --shard, --time, \
                 --write-partial or --partial"
            );
        }
        let (film, stats) = render_against_reference(prepared.as_ref(), &settings, reference)?;
        shards::write_image_atomically(&args.output, &film, &film.mean_rgb())?;
        if let Some(p) = &args.stderr {
            shards::write_image_atomically(p, &film, &film.std_error_rgb())?;
        }
        report(&args.output, &stats, &prepared.capabilities());
        return Ok(());
    }
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template("{bar:40} {percent:>3}% {human_pos}/{human_len} samples, ETA {eta}")
            .expect("static template"),
    );
    let piece = shards::render_piece(
        &args.pieces,
        &outputs,
        &args.scene.scene.display().to_string(),
        prepared.as_ref(),
        &settings,
        &scene_options(&args.scene),
        &bar,
    )?;
    bar.finish_and_clear();
    let (film, m) = (&piece.film, &piece.manifest);
    let written = outputs.image.as_ref().or(outputs.partial.as_ref()).expect("a render writes something");
    if let Some(image) = &outputs.image {
        shards::write_image_atomically(image, film, &film.mean_rgb())?;
        if let Some(p) = &args.stderr {
            shards::write_image_atomically(p, film, &film.std_error_rgb())?;
        }
    }
    let stats = RenderStats {
        wall: piece.stats.wall,
        samples: piece.stats.samples,
        rays: piece.stats.rays,
        non_finite: film.non_finite,
        truncated: piece.stats.truncated,
    };
    report(written, &stats, &prepared.capabilities());
    if let Some(p) = &outputs.partial {
        eprintln!("partial {}: {}", p.display(), m.describe());
    }
    if !m.complete() {
        eprintln!(
            "stopped at the time budget with {}: rerun the same command to continue{}",
            m.progress(),
            outputs.partial.as_ref().map_or(String::new(), |p| format!(" from {}", p.display()))
        );
    }
    Ok(())
}

/// `spt render --reference`: the render in passes that end at every power of two of the
/// sample count that is a multiple of the backend's sample block (so the film's bytes are
/// those of one pass), with the relMSE against the reference printed after each.
fn render_against_reference(
    prepared: &dyn PreparedScene,
    settings: &RenderSettings,
    path: &Path,
) -> Result<(tracer::Film, RenderStats)> {
    let (rw, rh, reference) = tracer::output::read_rgb32f(path)?;
    if (rw, rh) != (settings.width, settings.height) {
        bail!("{}: the reference is {rw}×{rh}, the render {}×{}", path.display(), settings.width, settings.height);
    }
    let block = prepared.capabilities().sample_block.max(1);
    let mut ends: Vec<u32> = std::iter::successors(Some(1u32), |n| n.checked_mul(2))
        .take_while(|&n| n < settings.spp)
        .filter(|n| n % block == 0)
        .collect();
    ends.push(settings.spp);
    let mut film = tracer::Film::new(settings.width, settings.height);
    let (mut done, mut wall) = (0, std::time::Duration::ZERO);
    let mut counters = tracer::integrator::PathCounters::default();
    eprintln!("{:>8}  {:>11}  {:>9}", "spp", "relMSE", "seconds");
    for end in ends {
        let start = Instant::now();
        counters += prepared.render_pass(settings, &mut film, done, end - done, &|_| {})?;
        wall += start.elapsed();
        done = end;
        eprintln!("{done:>8}  {:>11.4e}  {:>9.3}", compare::rel_mse(&film.mean_rgb(), &reference), wall.as_secs_f64());
    }
    let samples = settings.width as u64 * settings.height as u64 * settings.spp as u64;
    let stats =
        RenderStats { wall, samples, rays: counters.rays, non_finite: film.non_finite, truncated: counters.truncated };
    Ok((film, stats))
}

fn run_bench(args: BenchArgs) -> Result<()> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    let first_mode = args.modes.first().copied().unwrap_or_default();
    let (prepared, base) = prepare(&args.scene, args.spp, first_mode, best_sampler)?;
    let modes = if args.modes.is_empty() {
        let runs = prepared.capabilities().spectral_modes;
        [SpectralMode::Hero, SpectralMode::Bins40, SpectralMode::Rgb].into_iter().filter(|m| runs.contains(m)).collect()
    } else {
        args.modes.clone()
    };
    // Every mode is checked against the backend before anything is timed.
    let all: Vec<RenderSettings> = modes.iter().map(|&mode| RenderSettings { mode, ..base.clone() }).collect();
    for s in &all {
        prepared.capabilities().check_settings(s)?;
    }
    // Each other mode's kernel compiles now, not in its first timed run.
    for s in &all {
        prepared.warm_up(s)?;
    }
    println!(
        "# {} {}x{} {} spp, {} backend, {}",
        args.scene.scene.display(),
        args.scene.width,
        args.scene.height,
        args.spp,
        prepared.capabilities().backend,
        args.frames.map_or(format!("median of {}", args.repeats), |n| format!("{n} frames of {} spp", args.spp))
    );
    let stats = prepared.stats();
    println!(
        "# {} triangles; {} built in {:.1} ms{}; prepared in {:.1} ms",
        prepared.scene().triangles.len(),
        stats.accelerator,
        stats.build.as_secs_f64() * 1e3,
        stats.compile.map_or(String::new(), |c| format!(", kernel compiled in {:.1} ms", c.as_secs_f64() * 1e3))
            + &stats
                .integrator
                .map_or(String::new(), |c| format!(", integrator prepared in {:.1} ms", c.as_secs_f64() * 1e3)),
        stats.total.as_secs_f64() * 1e3
    );
    if let Some(frames) = args.frames {
        return bench_frames(Arc::from(prepared), &all, args.spp, frames, args.frames_on_device);
    }
    println!("{:<8} {:>12} {:>12} {:>10} {:>10}", "mode", "Msamples/s", "Mrays/s", "wall_s", "nan");
    for settings in &all {
        let mut runs = Vec::new();
        for _ in 0..args.repeats {
            let (_, stats) = tracer::render(prepared.as_ref(), settings, &|_| {})?;
            runs.push(stats);
        }
        runs.sort_by_key(|r| r.wall);
        let m = runs[runs.len() / 2];
        let secs = m.wall.as_secs_f64();
        println!(
            "{:<8} {:>12.3} {:>12.3} {:>10.3} {:>10}",
            settings.mode.name(),
            m.samples_per_second() / 1e6,
            m.rays as f64 / secs / 1e6,
            secs,
            m.non_finite
        );
    }
    Ok(())
}

/// `spt bench --frames`: viewer frames through [`tracer::Accumulation`], timed one by
/// one after an untimed first frame; `on_device`: displayed on the GPU's device without a
/// read-back.
fn bench_frames(
    prepared: Arc<dyn PreparedScene>,
    all: &[RenderSettings],
    spp: u32,
    frames: u32,
    on_device: bool,
) -> Result<()> {
    if frames == 0 {
        bail!("--frames must be at least 1");
    }
    let budget = spp.checked_mul(frames + 1).filter(|&n| n <= tracer::film::MAX_PIXEL_SAMPLES).with_context(|| {
        format!("--frames {frames} × --spp {spp} is beyond {} samples per pixel", tracer::film::MAX_PIXEL_SAMPLES)
    })?;
    println!(
        "{:<8} {:>10} {:>10} {:>12} {:>12} {:>8}",
        "mode", "frames/s", "median_ms", "Msamples/s", "Mrays/s", "frames"
    );
    for settings in all {
        let settings = RenderSettings { spp: budget, ..settings.clone() };
        let mut acc = Arc::clone(&prepared).accumulate(&settings)?;
        if on_device && gpu::accumulation::DeviceAccumulation::of(acc.as_mut()).is_none() {
            bail!("--frames-on-device needs --backend gpu and an integrator whose film stays on the device");
        }
        let mut out = vec![0u32; settings.width as usize * settings.height as usize];
        let mut frame = |acc: &mut Box<dyn tracer::Accumulation>| -> Result<()> {
            acc.add(spp)?;
            match gpu::accumulation::DeviceAccumulation::of(acc.as_mut()).filter(|_| on_device) {
                Some(device) => drop(device.display_frame()?),
                None => acc.display(&mut out)?,
            }
            Ok(())
        };
        frame(&mut acc)?;
        acc.restart(&settings)?;
        let mut times = Vec::with_capacity(frames as usize);
        let start = Instant::now();
        for _ in 0..frames {
            let t = Instant::now();
            frame(&mut acc)?;
            times.push(t.elapsed());
        }
        let wall = start.elapsed().as_secs_f64();
        let counters = acc.counters()?;
        times.sort();
        let samples = settings.width as f64 * settings.height as f64 * (spp as f64 * frames as f64);
        println!(
            "{:<8} {:>10.2} {:>10.2} {:>12.3} {:>12.3} {:>8}",
            settings.mode.name(),
            frames as f64 / wall,
            times[times.len() / 2].as_secs_f64() * 1e3,
            samples / wall / 1e6,
            counters.rays as f64 / wall / 1e6,
            frames
        );
    }
    Ok(())
}

/// The options a scene file's `[render]` table stands for, for `command` (render, bench
/// or view: each takes those it has), with the subcommand's name they follow, or an error
/// in the file.
fn scene_file_options(command: &Command) -> Result<(&'static str, Vec<String>)> {
    let (name, scene, spp, spectral) = match command {
        Command::Render(a) => ("render", &a.scene.scene, true, true),
        Command::Bench(a) => ("bench", &a.scene.scene, true, false),
        Command::View(a) => ("view", &a.scene.scene, false, true),
        _ => return Ok(("", Vec::new())),
    };
    if scene_format(scene).as_deref() != Some("toml") {
        return Ok((name, Vec::new()));
    }
    let d = tracer::scene_file::render_defaults(scene)?;
    let mut out = Vec::new();
    let mut push = |flag: &str, value: Option<String>| {
        if let Some(v) = value {
            out.extend([flag.to_string(), v]);
        }
    };
    push("--width", d.width.map(|v| v.to_string()));
    push("--height", d.height.map(|v| v.to_string()));
    push("--seed", d.seed.map(|v| v.to_string()));
    push("--max-depth", d.max_depth.map(|v| v.to_string()));
    push("--rr-depth", d.rr_depth.map(|v| v.to_string()));
    push("--rr-scale", d.rr_scale.map(|v| v.to_string()));
    push("--sampler", d.sampler);
    push("--integrator", d.integrator);
    if spp {
        push("--spp", d.spp.map(|v| v.to_string()));
    }
    if spectral {
        push("--spectral", d.spectral);
    }
    Ok((name, out))
}

/// The command line, with a scene file's `[render]` settings put in front of the user's
/// own options (right after the subcommand), so that those given win: clap keeps the last
/// value of an option given twice.
fn parse_command_line() -> Result<Cli> {
    let argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let cli = Cli::parse_from(&argv);
    let (name, extra) = scene_file_options(&cli.command)?;
    if extra.is_empty() {
        return Ok(cli);
    }
    // The scene file's options go right after the subcommand's name (global options such
    // as `--simd avx2` may come before it; the name is never one of their values).
    let at = argv.iter().skip(1).position(|a| a == name).map_or(2, |i| i + 2);
    let mut with_defaults = argv[..at].to_vec();
    with_defaults.extend(extra.into_iter().map(Into::into));
    with_defaults.extend(argv[at..].iter().cloned());
    Cli::try_parse_from(&with_defaults).map_err(|e| {
        let message = e.to_string();
        let first = message.lines().next().unwrap_or_default().trim_start_matches("error: ").to_string();
        anyhow::anyhow!("the scene file's [render] table: {first}")
    })
}

fn main() -> ExitCode {
    // Rust starts programs with SIGPIPE ignored, so `spt info SCENE | head` panicked in
    // `println!` once `head` closed the pipe; restore the default action (end quietly), as
    // command-line tools behave.
    #[cfg(unix)]
    // SAFETY: called before any other thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = match parse_command_line() {
        Ok(cli) => cli,
        Err(e) => {
            eprintln!("error: {e:#}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = apply_simd(cli.simd) {
        eprintln!("error: {e:#}");
        return ExitCode::FAILURE;
    }
    let result = match cli.command {
        Command::Render(a) => run_render(a).context("render failed"),
        Command::Bench(a) => run_bench(a).context("bench failed"),
        Command::Sheet(a) => run_sheet(a).context("sheet failed"),
        Command::Bvh(a) => run_bvh(a).context("bvh failed"),
        Command::Stability(a) => stability::run(a).context("stability failed"),
        Command::View(a) => run_view(a).context("view failed"),
        Command::Rays(c) => rays::run(c).context("rays failed"),
        Command::Merge(a) => shards::run_merge(a).context("merge failed"),
        Command::Atlas(a) => atlas_table::run(a).context("atlas failed"),
        Command::Compare(a) => compare::run(a).context("compare failed"),
        Command::Info(a) => run_info(a).context("info failed"),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
