//! The backend-agnostic renderer API: a [`Backend`] turns a [`Scene`] into a
//! [`PreparedScene`] — the structures it traverses, built its own way (the CPU's 4-wide
//! BVH, the GPU's buffers and compiled kernel) — and a prepared scene renders passes of
//! samples into a [`Film`]. Each backend declares its [`Capabilities`]; a request outside
//! them fails before any work, naming the feature and the way out.

use crate::accumulation::{Accumulation, FilmAccumulation};
use crate::camera::Camera;
use crate::film::{Film, MAX_PIXEL_SAMPLES};
use crate::integrator::{PathCounters, PathSettings};
pub use crate::lights::LightSampler;
use crate::sampler::SamplerKind;
use crate::scene::Scene;
use crate::{Error, Result};
use bvh::{Aabb, BvhWidth, TriangleTest};
use spectral::SpectralMode;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What to render and how.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of every random stream; same seed, same image.
    pub seed: u64,
    /// How the spectrum is sampled.
    pub mode: SpectralMode,
    /// How sample values are drawn.
    pub sampler: SamplerKind,
    /// Path depth, Russian roulette and shading normals, which every integrator reads.
    pub path: PathSettings,
    /// Camera to use instead of the scene's (or the default framing).
    pub camera: Option<Camera>,
    /// Render only these pixels of the image (a crop window); the others stay empty.
    /// Pixels keep their place, camera ray and random streams, so the crop of a render
    /// equals the same pixels of the full render bit for bit.
    pub crop: Option<PixelRect>,
}

/// A rectangle of pixels: columns `x .. x + width`, rows `y .. y + height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct PixelRect {
    /// First column.
    pub x: u32,
    /// First row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl PixelRect {
    /// The whole of a `width` × `height` image.
    pub fn full(width: u32, height: u32) -> Self {
        Self { x: 0, y: 0, width, height }
    }

    /// Pixels inside.
    pub fn pixel_count(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Whether it lies inside a `width` × `height` image and is not empty.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.width > 0
            && self.height > 0
            && self.x as u64 + self.width as u64 <= width as u64
            && self.y as u64 + self.height as u64 <= height as u64
    }

    /// Whether pixel (x, y) is inside.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        x >= self.x && y >= self.y && x - self.x < self.width && y - self.y < self.height
    }

    /// Whether the two share a pixel.
    pub fn overlaps(&self, other: &PixelRect) -> bool {
        let span =
            |a: u32, la: u32, b: u32, lb: u32| (a as u64) < b as u64 + lb as u64 && (b as u64) < a as u64 + la as u64;
        span(self.x, self.width, other.x, other.width) && span(self.y, self.height, other.y, other.height)
    }
}

impl std::fmt::Display for PixelRect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}×{} at ({}, {})", self.width, self.height, self.x, self.y)
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            spp: 64,
            seed: 0,
            mode: SpectralMode::Hero,
            sampler: SamplerKind::default(),
            path: PathSettings::default(),
            camera: None,
            crop: None,
        }
    }
}

/// Largest image side accepted (a 16K image; beyond that the film alone is > 6 GiB).
pub const MAX_IMAGE_SIDE: u32 = 16_384;

impl RenderSettings {
    /// The pixels rendered: the crop window, else the whole image.
    pub fn region(&self) -> PixelRect {
        self.crop.unwrap_or(PixelRect::full(self.width, self.height))
    }

    /// Rejects absurd values with a message naming the setting.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 || self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return Err(Error::Setting(format!(
                "image size {}×{} must be between 1 and {MAX_IMAGE_SIDE} on each side",
                self.width, self.height
            )));
        }
        if self.spp == 0 || self.spp > MAX_PIXEL_SAMPLES {
            return Err(Error::Setting(format!(
                "samples per pixel must be between 1 and {MAX_PIXEL_SAMPLES} (the film's exact sums hold at most that many)"
            )));
        }
        if let Some(crop) = &self.crop
            && !crop.fits(self.width, self.height)
        {
            return Err(Error::Setting(format!(
                "crop window {crop} is empty or reaches outside the {}×{} image",
                self.width, self.height
            )));
        }
        let rr_scale = self.path.rr_scale;
        let max = crate::integrator::MAX_RR_SCALE;
        if !(rr_scale > 0.0 && rr_scale <= max) {
            return Err(Error::Setting(format!(
                "Russian roulette scale {rr_scale} must be above 0 and at most {max} (1: keep a path \
                 with probability min(0.95, its throughput))"
            )));
        }
        if let Some(c) = &self.camera {
            c.validate().map_err(Error::Setting)?;
        }
        Ok(())
    }
}

/// Scene-level choices a backend builds its structures for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneOptions {
    /// The ray–triangle test compiled into the traversal.
    pub triangle_test: TriangleTest,
    /// Children per node of the triangle BVH ([`BvhWidth::Auto`]: the backend's choice —
    /// on the CPU 8 where it has AVX2, else 4; on the GPU the binary tree).
    pub bvh_width: BvhWidth,
    /// How the triangle BVH's nodes are split (`None`: binned SAH, the default).
    pub bvh_builder: Option<bvh::SplitMethod>,
    /// The sampler and spectral mode the renders will use, where known. A backend that
    /// compiles a kernel per sampler and mode (the GPU's) compiles this one while
    /// preparing; `None` means those of [`RenderSettings::default`]. Another sampler or
    /// mode still renders, after compiling its own kernel (on lavapipe tens of seconds).
    pub first_render: Option<(SamplerKind, SpectralMode)>,
    /// Trace paths as a wavefront (one kernel per stage — camera rays, closest hits,
    /// shading, shadow rays — with the paths' state in device memory) instead of one loop
    /// per camera ray; only a backend whose [`Capabilities::wavefront`] says so runs it
    /// (the GPU's path tracer), the others refuse it.
    pub wavefront: bool,
    /// How next-event estimation chooses among the emitters, point and spot lights (by
    /// power, or by a light tree for the shading point; [`LightSampler::Auto`]: the tree
    /// from [`LightSampler::TREE_FROM`] of them where the backend has one).
    pub light_sampler: LightSampler,
}

/// What a backend can render. [`Capabilities::check_scene`] and
/// [`Capabilities::check_settings`] turn a request outside them into
/// [`Error::Unsupported`] before any work is done.
#[derive(Clone, Debug, PartialEq)]
pub struct Capabilities {
    /// The backend's name (`cpu`, `gpu`), for messages.
    pub backend: &'static str,
    /// Spectral modes it traces.
    pub spectral_modes: Vec<SpectralMode>,
    /// Samplers it draws from, the best (the CLI's default) first.
    pub samplers: Vec<SamplerKind>,
    /// The kinds of analytic shape it intersects ([`crate::ShapeKind::name`]), and why not
    /// the others.
    pub analytic_shapes: ShapeSupport,
    /// Which BSDFs written outside the workspace ([`brdf::DynBsdfBuilder`]) it runs.
    pub custom_bsdfs: CustomBsdfs,
    /// Whether it samples point, spot and directional lights ([`crate::PunctualLight`]).
    pub punctual_lights: bool,
    /// Whether it reads material textures (colour, normal, bump, alpha, emission maps).
    pub textures: bool,
    /// Whether it lights scenes by environment maps (`--sky MAP`).
    pub environment_maps: bool,
    /// Ray–triangle tests it implements.
    pub triangle_tests: Vec<TriangleTest>,
    /// Triangle-BVH node widths it can be asked for ([`BvhWidth::Auto`] = its own choice).
    pub bvh_widths: Vec<BvhWidth>,
    /// The integrator it runs (`--integrator` name).
    pub integrator: &'static str,
    /// The most scattering events a path may have, if the backend has a hard cap (paths
    /// that reach it with an unbounded `max_depth` are counted as truncated); `None` if
    /// paths end only by the depth limit and Russian roulette.
    pub max_bounces: Option<u32>,
    /// Whether its integrator lengthens paths by `PathSettings::specular_extension`, so
    /// that it counts against `max_bounces` (only the path tracer does: Whitted, bdpt,
    /// direct lighting, ambient occlusion and the atlas ignore it).
    pub extension: bool,
    /// Whether its integrator limits non-specular bounces
    /// (`PathSettings::max_diffuse_depth`; the CPU's path tracer does).
    pub diffuse_depth: bool,
    /// Whether it builds its BVH with the split method asked for
    /// ([`SceneOptions::bvh_builder`]).
    pub bvh_builders: bool,
    /// Passes that split a render at multiples of this sample index give the same film,
    /// bit for bit, as one pass (1 on the CPU; the GPU sums up to this many samples in f32
    /// before they reach the film's exact sums).
    pub sample_block: u32,
    /// Whether it can trace paths as a wavefront ([`SceneOptions::wavefront`]).
    pub wavefront: bool,
    /// Whether its integrator adds light to pixels other than its samples' own (it traces
    /// paths from the lights and splats them where they meet the camera:
    /// [`crate::Integrator::splats`]), so that a band of the image's rows is no piece of
    /// the whole image that can be rendered alone.
    pub splats: bool,
    /// Whether it chooses emitters by a light tree ([`LightSampler::Tree`]; the CPU's
    /// integrators that declare [`crate::Integrator::chooses_lights_per_point`], the GPU's
    /// path tracer, direct light and atlas), or by power only (the others, where
    /// [`LightSampler::Auto`] means power).
    pub light_tree: bool,
}

/// Which custom BSDFs ([`crate::material::Surface::Custom`]) a backend runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CustomBsdfs {
    /// None.
    None,
    /// Those that ship a WGSL twin ([`brdf::BsdfBuilder::wgsl_twin`]).
    WithWgslTwin,
    /// Any (the CPU calls their Rust).
    Any,
}

impl CustomBsdfs {
    /// Whether a backend with this support runs `material`'s BSDF (registered models
    /// always).
    pub fn runs(self, material: &crate::material::Material) -> bool {
        material.params().is_some()
            || match self {
                Self::Any => true,
                Self::WithWgslTwin => material.wgsl_twin().is_some(),
                Self::None => false,
            }
    }
}

/// Which analytic shapes a backend intersects.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeSupport {
    /// The kinds it intersects, by [`crate::ShapeKind::name`].
    pub kinds: Vec<&'static str>,
    /// Why the others are not (for the error message).
    pub why_not: &'static str,
}

impl ShapeSupport {
    /// Every kind of shape.
    pub fn all() -> Self {
        Self { kinds: crate::ShapeKind::NAMES.to_vec(), why_not: "" }
    }
}

impl Capabilities {
    /// Everything the scene and its options need, against what the backend can do.
    pub fn check_scene(&self, scene: &Scene, options: &SceneOptions) -> Result<()> {
        let unsupported = |feature: String, way_out: &str| Error::Unsupported {
            backend: self.backend.to_string(),
            feature,
            way_out: way_out.to_string(),
        };
        if options.wavefront && !self.wavefront {
            return Err(unsupported(
                format!("the wavefront schedule for the {} integrator", self.integrator),
                "it is the GPU path tracer's (--backend gpu --integrator path); drop --wavefront",
            ));
        }
        if options.light_sampler == LightSampler::Tree && !self.light_tree {
            return Err(unsupported(
                format!("a light tree for the {} integrator", self.integrator),
                "it chooses emitters by power: leave --light-sampler at auto or power (the path, direct \
                 and atlas integrators take the tree on either backend, path-caustics on the CPU)",
            ));
        }
        if !self.bvh_builders
            && let Some(m) = options.bvh_builder
        {
            return Err(unsupported(
                format!("a choice of BVH builder ({})", m.name()),
                "leave --bvh-builder at its default, or use --backend cpu",
            ));
        }
        if let Some(s) = scene.shapes.iter().find(|s| !self.analytic_shapes.kinds.contains(&s.shape.name())) {
            let kind = s.shape.name();
            let count = scene.shapes.iter().filter(|t| t.shape.name() == kind).count();
            return Err(unsupported(
                format!("analytic shapes of kind {kind} ({count} in this scene)"),
                &format!("{}; tessellate them into triangles, or use --backend cpu", self.analytic_shapes.why_not),
            ));
        }
        if !self.punctual_lights
            && let Some(light) = scene.punctual_lights.first()
        {
            return Err(unsupported(
                format!(
                    "point, spot and directional lights ({} in this scene, the first a {} light)",
                    scene.punctual_lights.len(),
                    light.kind()
                ),
                "use --backend cpu",
            ));
        }
        if let Some(m) = scene.materials.iter().find(|m| !self.custom_bsdfs.runs(m)) {
            return Err(match self.custom_bsdfs {
                CustomBsdfs::WithWgslTwin => unsupported(
                    format!("custom BSDFs without a WGSL twin (material '{}')", m.name),
                    "give its BsdfBuilder a wgsl_twin (see the tracer's examples/custom_brdf.rs), register the model \
                     in brdf's registry with its twin, or use --backend cpu",
                ),
                _ => unsupported(
                    format!("custom BSDFs (material '{}')", m.name),
                    "register the model in brdf's registry, or use --backend cpu",
                ),
            });
        }
        if !self.textures
            && let Some(m) = scene.materials.iter().find(|m| m.textures.is_some())
        {
            let count = scene.materials.iter().filter(|m| m.textures.is_some()).count();
            return Err(unsupported(
                format!("textures ({count} textured materials in this scene, the first '{}')", m.name),
                "use --backend cpu (or --no-textures to render the materials' factors alone)",
            ));
        }
        if !self.environment_maps && scene.environment.as_ref().is_some_and(|e| e.map.is_some()) {
            return Err(unsupported(
                "environment maps".into(),
                "use --backend cpu, or a uniform sky (--sky white[:LUMINANCE])",
            ));
        }
        if !self.triangle_tests.contains(&options.triangle_test) {
            let known: Vec<&str> = self.triangle_tests.iter().map(|t| t.name()).collect();
            return Err(unsupported(
                format!("the '{}' triangle test", options.triangle_test.name()),
                &format!("use --triangle-test {}, or --backend cpu", known.join(" or ")),
            ));
        }
        if !self.bvh_widths.contains(&options.bvh_width) {
            let known: Vec<&str> = self.bvh_widths.iter().map(|w| w.name()).collect();
            return Err(unsupported(
                format!("a {}-wide triangle BVH", options.bvh_width.name()),
                &if self.backend == "cpu" {
                    format!("use --bvh-width {}, or --backend gpu", known.join(" or "))
                } else {
                    format!("use --bvh-width {}, or --backend cpu", known.join(" or "))
                },
            ));
        }
        Ok(())
    }

    /// Everything a render's settings need.
    pub fn check_settings(&self, settings: &RenderSettings) -> Result<()> {
        let unsupported = |feature: String, way_out: String| Error::Unsupported {
            backend: self.backend.to_string(),
            feature,
            way_out,
        };
        if !self.spectral_modes.contains(&settings.mode) {
            let known: Vec<&str> = self.spectral_modes.iter().map(|m| m.name()).collect();
            return Err(unsupported(
                format!("the '{}' spectral mode", settings.mode.name()),
                format!("use --spectral {}, or --backend cpu", known.join(" or ")),
            ));
        }
        if !self.samplers.contains(&settings.sampler) {
            let known: Vec<&str> = self.samplers.iter().map(|s| s.name()).collect();
            return Err(unsupported(
                format!("the '{}' sampler", settings.sampler.name()),
                format!("use --sampler {}, or --backend cpu", known.join(" or ")),
            ));
        }
        if settings.path.max_diffuse_depth > 0 && !self.diffuse_depth {
            return Err(unsupported(
                format!("a limit on diffuse bounces (--max-diffuse-depth) with the '{}' integrator", self.integrator),
                "use --max-depth, or the CPU's path integrator (--backend cpu --integrator path)".into(),
            ));
        }
        if let Some(cap) = self.max_bounces {
            let extension = if self.extension { settings.path.specular_extension } else { 0 };
            let depth = settings.path.max_depth.saturating_add(extension);
            if settings.path.max_depth > 0 && depth > cap {
                let (what, hint) = if self.extension {
                    (
                        format!("paths of {depth} bounces (--max-depth plus --extension; it traces at most {cap})"),
                        format!("use --max-depth and --extension summing to at most {cap}, or --backend cpu"),
                    )
                } else {
                    (
                        format!("a recursion {depth} deep (--max-depth; it traces at most {cap})"),
                        format!("use --max-depth {cap} or less, or --backend cpu"),
                    )
                };
                return Err(unsupported(what, hint));
            }
        }
        Ok(())
    }
}

/// Figures from preparing a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PrepareStats {
    /// Building the acceleration structure.
    pub build: Duration,
    /// Compiling kernels, where the backend compiles any (near zero where the device had
    /// compiled the same kernel before: the GPU's are kept per device).
    pub compile: Option<Duration>,
    /// Preparing the integrator's per-scene data (the atlas), where it has any.
    pub integrator: Option<Duration>,
    /// All of the preparation.
    pub total: Duration,
    /// Primitives that emit light.
    pub emitters: usize,
    /// Whether next-event estimation chooses among them (and the point and spot lights)
    /// by a light tree.
    pub light_tree: bool,
    /// The triangles' acceleration structure, for messages (e.g. "8-wide BVH (AVX2)").
    pub accelerator: &'static str,
    /// Triangles on faces of the scene's convex hull that shadow rays towards its lights
    /// leave out (the CPU's [`crate::geometry::Occluders`]; 0 where they test them all).
    pub hull_triangles: usize,
}

/// A way of executing an integrator (CPU with rayon, GPU with wgpu): it prepares scenes,
/// and the prepared scenes render.
pub trait Backend: Send + Sync {
    /// What it can render (and its name, for messages).
    fn capabilities(&self) -> Capabilities;

    /// Builds what this backend traverses from `scene`. Fails with
    /// [`Error::Unsupported`] for a scene outside its capabilities, before building
    /// anything.
    fn prepare(&self, scene: Scene, options: &SceneOptions) -> Result<Box<dyn PreparedScene>>;
}

/// A scene made ready by a [`Backend`]: it renders passes of samples. Sample `k` of pixel
/// `p` always uses the same random stream, so passes may split the samples any way.
pub trait PreparedScene: Send + Sync + 'static {
    /// The backend's capabilities (for checking settings before a render) and name.
    fn capabilities(&self) -> Capabilities;

    /// The scene.
    fn scene(&self) -> &Scene;

    /// The scene's bounds, computed once when it was prepared (the default camera frames
    /// them, and computing them visits every vertex).
    fn bounds(&self) -> Aabb;

    /// What preparing it took.
    fn stats(&self) -> PrepareStats;

    /// The specialised kernel a render with `settings` runs in, if any (the CPU path
    /// tracer's "lanes"), for reports; the default: none.
    fn kernel(&self, settings: &RenderSettings) -> Option<&'static str> {
        let _ = settings;
        None
    }

    /// Adds samples `first_sample .. first_sample + spp` of every pixel to `film` (which
    /// must have the settings' size); `progress` is told how many samples each finished
    /// piece of work took.
    fn render_pass(
        &self,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<PathCounters>;

    /// Does ahead of a render what its first pass with `settings` would otherwise do
    /// inside the timed render (the GPU compiles the kernel for the settings' sampler);
    /// the default does nothing.
    fn warm_up(&self, settings: &RenderSettings) -> Result<()> {
        let _ = settings;
        Ok(())
    }

    /// An empty [`Accumulation`] of this scene seen with `settings`, for frame-by-frame
    /// refinement (a viewer). The default renders passes into a film
    /// ([`FilmAccumulation`]); a backend whose film would have to travel (the GPU's)
    /// keeps its statistics where it renders.
    fn accumulate(self: Arc<Self>, settings: &RenderSettings) -> Result<Box<dyn Accumulation>> {
        Ok(Box::new(FilmAccumulation::new(self, settings)?))
    }

    /// The camera a render uses: the settings', else the scene's, else the default
    /// framing of the scene's bounds.
    fn camera(&self, settings: &RenderSettings) -> Camera {
        settings
            .camera
            .or(self.scene().camera)
            .unwrap_or_else(|| Camera::framing(&self.bounds(), settings.width as f32 / settings.height as f32))
    }
}

/// Checks `settings` and the film against a prepared scene's backend; every backend's
/// `render_pass` starts with it.
pub fn check_pass(prepared: &dyn PreparedScene, settings: &RenderSettings, film: &Film) -> Result<()> {
    settings.validate()?;
    prepared.capabilities().check_settings(settings)?;
    if film.width() != settings.width || film.height() != settings.height {
        return Err(Error::Setting("film size differs from the settings' image size".into()));
    }
    Ok(())
}

/// The Sobol samplers lay their samples out for `settings.spp` samples per pixel (rounded
/// up to a power of two): a pass must stay within them.
pub fn check_sample_range(settings: &RenderSettings, first_sample: u32, spp: u32) -> Result<()> {
    let budget = (settings.spp as u64).next_power_of_two();
    if settings.sampler.needs_sample_budget() && first_sample as u64 + spp as u64 > budget {
        return Err(Error::Setting(format!(
            "the {} sampler lays out {budget} samples per pixel (--spp {} rounded up to a power of two); \
             samples {first_sample}..{} are beyond them: raise --spp, or use --sampler independent",
            settings.sampler.name(),
            settings.spp,
            first_sample as u64 + spp as u64
        )));
    }
    Ok(())
}

/// Figures from a finished render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Wall-clock time of the sampling (not the scene preparation).
    pub wall: Duration,
    /// Samples taken (pixels × spp).
    pub samples: u64,
    /// Rays traced.
    pub rays: u64,
    /// Samples dropped because they were NaN or infinite.
    pub non_finite: u64,
    /// Paths cut short by the backend's bounce cap ([`Capabilities::max_bounces`]).
    pub truncated: u64,
}

impl RenderStats {
    /// Samples per second.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.wall.as_secs_f64().max(1e-9)
    }
}

/// Renders `settings.spp` samples per pixel in one pass.
pub fn render(
    scene: &dyn PreparedScene,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Film, RenderStats)> {
    settings.validate()?;
    scene.capabilities().check_settings(settings)?;
    let mut film = Film::new(settings.width, settings.height);
    let start = Instant::now();
    let counters = scene.render_pass(settings, &mut film, 0, settings.spp, progress)?;
    let stats = RenderStats {
        wall: start.elapsed(),
        samples: settings.region().pixel_count() * settings.spp as u64,
        rays: counters.rays,
        non_finite: film.non_finite,
        truncated: counters.truncated,
    };
    Ok((film, stats))
}
