//! The CPU backend: an [`Integrator`] run by rayon over 16×16 tiles, bit-identical for
//! a given seed whatever the thread count.

use crate::camera::RayGenerator;
use crate::film::{Film, PixelStats, SplatImage};
use crate::geometry::Geometry;
use crate::integrator::{CameraSample, Integrator, PathCounters, PathTracer, SceneView};
use crate::lights::{LightSampler, Lights};
use crate::render::{
    Backend, Capabilities, CustomBsdfs, PixelRect, PrepareStats, PreparedScene, RenderSettings, SceneOptions,
    check_pass, check_sample_range,
};
use crate::sampler::{PaddedSobol, Pcg32, Sampler, SamplerKind, ZSobolLayout};
use crate::scene::Scene;
use crate::{Error, Result};
use bvh::{Aabb, BvhWidth, TriangleTest};
use glam::Vec2;
use rayon::prelude::*;
use spectral::{SampledSpectrum, SampledWavelengths, SpectralMode};
use std::sync::Arc;
use std::time::Instant;

mod per_sample;

/// Splats a tile holds before it adds them to the pass's shared splat image.
const SPLAT_FLUSH: usize = 1 << 14;

/// Tile side in pixels.
pub const TILE: u32 = 16;

/// The most camera samples handed to the integrator at once (a tile's pixels × samples
/// are split into blocks of at most this many, in pixel-major order).
///
/// Large, for the lanes integrator (`integrator::lanes`): its 64 lanes take a block's
/// samples as paths end and idle once the block is used up, so each block ends with
/// turns at a few live lanes that cost the vector work of all 64. Cornell box, 256² at
/// 16 spp, one thread: 47.8 of 64 lanes busy per turn on average with blocks of 256, 59.0
/// with 1024, 62.7 with 4096; 2 threads at 64 spp, 2.43 → 2.54 M samples/s (+4.6 %), the
/// same image (docs/figures.md). A full block holds 480 KiB per thread (120-byte
/// samples with the Z-Sobol sampler, four wavelengths).
pub const BLOCK: usize = 4096;

/// The CPU backend, generic over the integrator it runs.
pub struct CpuBackend<I: Integrator = PathTracer> {
    pool: Arc<rayon::ThreadPool>,
    integrator: Arc<I>,
}

impl CpuBackend<PathTracer> {
    /// A path-tracing backend with `threads` worker threads (0 = one per core).
    pub fn new(threads: usize) -> Result<Self> {
        Self::with_integrator(threads, PathTracer)
    }
}

impl<I: Integrator> CpuBackend<I> {
    /// A backend running `integrator` on `threads` worker threads (0 = one per core).
    pub fn with_integrator(threads: usize, integrator: I) -> Result<Self> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::Setting(format!("cannot start {threads} threads: {e}")))?;
        Ok(Self { pool: Arc::new(pool), integrator: Arc::new(integrator) })
    }

    /// Worker threads in use.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Prepares `scene` (validates it, builds the triangles' wide BVH with the given
    /// test and width, the shapes' BVH and the light distribution), with the concrete type.
    pub fn prepare_cpu(&self, scene: Scene, options: &SceneOptions) -> Result<CpuScene<I>> {
        self.capabilities().check_scene(&scene, options)?;
        scene.validate()?;
        let start = Instant::now();
        let geometry = Geometry::build(&scene, options)?;
        let build = start.elapsed();
        // An integrator that chooses by power gets no tree (`check_scene` refused `Tree`).
        let sampler =
            if self.integrator.chooses_lights_per_point() { options.light_sampler } else { LightSampler::Power };
        let lights = Lights::with_sampler(&scene, sampler);
        // Colour textures uplift through a table decoded on first use (about 2 ms since it
        // ships fitted): decode it here, in preparation, not in the first samples.
        let colour_textures = scene
            .materials
            .iter()
            .filter_map(|m| m.textures.as_deref())
            .any(|t| t.base_colour.is_some() || t.specular.is_some() || t.emissive.is_some());
        if colour_textures {
            spectral::uplift::uplift_table();
        }
        // The integrator's own per-scene data (the atlas), on this backend's threads.
        let integrator_start = Instant::now();
        let prepared = self.pool.install(|| self.integrator.for_scene(&SceneView::new(&scene, &geometry, &lights)))?;
        let integrator = prepared.map_or_else(|| Arc::clone(&self.integrator), Arc::new);
        let integrator_time = integrator_start.elapsed();
        let stats = PrepareStats {
            build,
            compile: None,
            integrator: (integrator_time > std::time::Duration::ZERO && !Arc::ptr_eq(&integrator, &self.integrator))
                .then_some(integrator_time),
            total: start.elapsed(),
            emitters: lights.emitter_count(),
            light_tree: lights.has_tree(),
            accelerator: geometry.triangles.description(),
            hull_triangles: geometry.hull_triangles(),
        };
        Ok(CpuScene {
            bounds: scene.bounds(),
            scene,
            geometry,
            lights,
            stats,
            pool: Arc::clone(&self.pool),
            integrator,
        })
    }
}

/// The CPU backend's capabilities when it runs `integrator`.
fn cpu_capabilities(integrator: &impl Integrator) -> Capabilities {
    Capabilities {
        backend: "cpu",
        spectral_modes: vec![SpectralMode::Hero, SpectralMode::Bins40, SpectralMode::Rgb],
        samplers: vec![SamplerKind::ZSobol, SamplerKind::Sobol, SamplerKind::Independent],
        analytic_shapes: crate::render::ShapeSupport::all(),
        custom_bsdfs: CustomBsdfs::Any,
        punctual_lights: true,
        textures: true,
        environment_maps: true,
        triangle_tests: vec![TriangleTest::Watertight, TriangleTest::MollerTrumbore],
        bvh_widths: BvhWidth::CPU.to_vec(),
        integrator: integrator.name(),
        max_bounces: None,
        extension: integrator.extends_specular(),
        diffuse_depth: integrator.limits_diffuse_depth(),
        bvh_builders: true,
        sample_block: 1,
        wavefront: false,
        splats: integrator.splats(),
        light_tree: integrator.chooses_lights_per_point(),
    }
}

impl<I: Integrator> Backend for CpuBackend<I> {
    fn capabilities(&self) -> Capabilities {
        cpu_capabilities(self.integrator.as_ref())
    }

    fn prepare(&self, scene: Scene, options: &SceneOptions) -> Result<Box<dyn PreparedScene>> {
        Ok(Box::new(self.prepare_cpu(scene, options)?))
    }
}

/// A scene prepared for the CPU: the scene, its accelerators and lights, and the
/// backend's threads and integrator.
pub struct CpuScene<I: Integrator = PathTracer> {
    scene: Scene,
    bounds: Aabb,
    geometry: Geometry,
    lights: Lights,
    stats: PrepareStats,
    pool: Arc<rayon::ThreadPool>,
    integrator: Arc<I>,
}

impl<I: Integrator> CpuScene<I> {
    /// Everything the integrator reads.
    pub fn view(&self) -> SceneView<'_> {
        SceneView::new(&self.scene, &self.geometry, &self.lights)
    }

    /// The scene's accelerators.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The scene's emitters.
    pub fn lights(&self) -> &Lights {
        &self.lights
    }
}

impl<I: Integrator> PreparedScene for CpuScene<I> {
    fn capabilities(&self) -> Capabilities {
        cpu_capabilities(self.integrator.as_ref())
    }

    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn stats(&self) -> PrepareStats {
        self.stats
    }

    fn kernel(&self, settings: &RenderSettings) -> Option<&'static str> {
        self.integrator.kernel(&self.view(), &settings.path)
    }

    fn render_pass(
        &self,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<PathCounters> {
        check_pass(self, settings, film)?;
        check_sample_range(settings, first_sample, spp)?;
        let camera = self.camera(settings).rays(film.width(), film.height());
        let pass = Pass { scene: self, settings, camera, first_sample, spp, progress };
        let seed = settings.seed;
        let width = film.width();
        Ok(self.pool.install(|| match settings.sampler {
            SamplerKind::Independent => {
                pass.modes(film, &|x: u32, y: u32, s: u32| Pcg32::for_sample(seed, y * width + x, s))
            }
            SamplerKind::Sobol => {
                let total = settings.spp;
                pass.modes(film, &|x: u32, y: u32, s: u32| PaddedSobol::new(x, y, s, total, seed))
            }
            SamplerKind::ZSobol => {
                let layout = ZSobolLayout::new(film.width(), film.height(), settings.spp, seed);
                pass.modes(film, &|x: u32, y: u32, s: u32| layout.sampler(x, y, s))
            }
        }))
    }
}

/// The image grid's [`TILE`] × [`TILE`] cells clipped to `region`, row by row (the grid
/// stays anchored at the image's corner, so a crop window's tiles are pieces of the full
/// render's; no pixel's result depends on its tile).
fn tiles_of(region: PixelRect) -> Vec<PixelRect> {
    let (x_end, y_end) = (region.x + region.width, region.y + region.height);
    let cells = |start: u32, end: u32| {
        let first = start / TILE * TILE;
        (first..end).step_by(TILE as usize).map(move |c| (c.max(start), (c + TILE).min(end)))
    };
    cells(region.y, y_end)
        .flat_map(|(y0, y1)| {
            cells(region.x, x_end).map(move |(x0, x1)| PixelRect { x: x0, y: y0, width: x1 - x0, height: y1 - y0 })
        })
        .collect()
}

/// One render pass over a CPU scene.
struct Pass<'a, I: Integrator> {
    scene: &'a CpuScene<I>,
    settings: &'a RenderSettings,
    /// The camera's rays, set up once per pass.
    camera: RayGenerator,
    first_sample: u32,
    spp: u32,
    progress: &'a (dyn Fn(u64) + Sync),
}

/// A pass's wavelengths: hero wavelengths drawn per sample from one sample value
/// ([`SampledWavelengths::sample_hero`], a block at a time), or the same for all.
#[derive(Clone, Copy)]
enum Wavelengths<const N: usize> {
    Hero,
    Fixed(SampledWavelengths<N>),
}

struct TileResult {
    x0: u32,
    y0: u32,
    w: u32,
    pixels: Vec<PixelStats>,
    non_finite: u64,
    counters: PathCounters,
}

impl<I: Integrator> Pass<'_, I> {
    /// Renders in the settings' spectral mode with samplers made by `sampler(x, y, s)`.
    fn modes<S: Sampler>(&self, film: &mut Film, sampler: &(dyn Fn(u32, u32, u32) -> S + Sync)) -> PathCounters {
        match self.settings.mode {
            SpectralMode::Hero => self.tiles::<4, S>(film, sampler, Wavelengths::Hero),
            SpectralMode::Bins40 => {
                self.tiles::<40, S>(film, sampler, Wavelengths::Fixed(SampledWavelengths::fixed_bins(380.0, 10.0)))
            }
            SpectralMode::Rgb => self.tiles::<3, S>(film, sampler, Wavelengths::Fixed(SampledWavelengths::rgb())),
        }
    }

    /// Renders every tile in parallel and writes the results into `film`.
    fn tiles<const N: usize, S: Sampler>(
        &self,
        film: &mut Film,
        sampler: &(dyn Fn(u32, u32, u32) -> S + Sync),
        wavelengths: Wavelengths<N>,
    ) -> PathCounters {
        let width = film.width();
        let tiles = tiles_of(self.settings.region());
        let existing: &Film = film;
        // Splats go straight into one shared image (in flushes of a few thousand), not
        // into the tiles' results: a pass holds a few blocks of them, not all.
        let splat_image =
            self.scene.integrator.splats().then(|| std::sync::Mutex::new(SplatImage::new(film.width(), film.height())));
        let results: Vec<TileResult> = tiles
            .par_iter()
            .map(|tile| self.tile(existing, tile, sampler, &wavelengths, splat_image.as_ref()))
            .collect();
        let mut total = PathCounters::default();
        for t in results {
            for (i, p) in t.pixels.iter().enumerate() {
                let (x, y) = (t.x0 + i as u32 % t.w, t.y0 + i as u32 / t.w);
                film.pixels_mut()[(y * width + x) as usize] = *p;
            }
            film.non_finite += t.non_finite;
            total += t.counters;
        }
        if let Some(image) = splat_image {
            film.add_splat_image(&image.into_inner().expect("no thread panicked holding it"));
            film.count_light_paths(self.spp as u64);
        }
        total
    }

    /// One tile: its pixel samples in pixel-major order, in blocks of at most [`BLOCK`]
    /// handed to the integrator, accumulated in the same order.
    fn tile<const N: usize, S: Sampler>(
        &self,
        film: &Film,
        tile: &PixelRect,
        sampler: &(dyn Fn(u32, u32, u32) -> S + Sync),
        wavelengths: &Wavelengths<N>,
        splat_image: Option<&std::sync::Mutex<SplatImage>>,
    ) -> TileResult {
        let (x0, y0, w, h) = (tile.x, tile.y, tile.width, tile.height);
        let view = self.scene.view().with_film(self.camera, self.settings.region());
        let mut splats = Vec::new();
        let mut pixels: Vec<PixelStats> =
            (y0..y0 + h).flat_map(|y| (x0..x0 + w).map(move |x| (x, y))).map(|(x, y)| *film.pixel(x, y)).collect();
        let mut non_finite = 0;
        let mut counters = PathCounters::default();
        let samples = (0..w * h).flat_map(|i| (0..self.spp).map(move |s| (i, self.first_sample + s)));
        // The block's samples and, for each, its pixel's index in the tile.
        let mut block: Vec<CameraSample<N, S>> = Vec::with_capacity(BLOCK);
        let mut owners: Vec<u32> = Vec::with_capacity(BLOCK);
        // The hero wavelengths' sample values, and the samples' colours.
        let mut u_wavelengths: Vec<f32> = Vec::with_capacity(BLOCK);
        let mut colours: Vec<[f32; 3]> = Vec::with_capacity(BLOCK);
        let hero = matches!(wavelengths, Wavelengths::Hero);
        let mut samples = samples.peekable();
        while samples.peek().is_some() {
            block.clear();
            owners.clear();
            u_wavelengths.clear();
            for (i, s) in samples.by_ref().take(BLOCK) {
                let (x, y) = (x0 + i % w, y0 + i / w);
                let mut sampler = sampler(x, y, s);
                let (u_wavelength, jitter) = sampler.camera(hero);
                let wl = match wavelengths {
                    // A stand-in, overwritten for the whole block below.
                    Wavelengths::Hero => {
                        u_wavelengths.push(u_wavelength);
                        SampledWavelengths::fixed_bins(0.0, 0.0)
                    }
                    Wavelengths::Fixed(wl) => *wl,
                };
                let ray = self.camera.ray(Vec2::new(x as f32, y as f32) + jitter);
                block.push(CameraSample { ray, wl, sampler, radiance: SampledSpectrum::zero() });
                owners.push(i);
            }
            if hero {
                per_sample::hero_wavelengths(&u_wavelengths, &mut block);
            }
            self.scene.integrator.radiance_block_splatting(
                &view,
                &self.settings.path,
                &mut block,
                &mut counters,
                &mut splats,
            );
            per_sample::linear_srgb(&block, &mut colours);
            non_finite += per_sample::add_to_pixels(&mut pixels, &owners, &colours);
            if splats.len() >= SPLAT_FLUSH || (samples.peek().is_none() && !splats.is_empty()) {
                if let Some(image) = splat_image {
                    image.lock().expect("no thread panicked holding it").add(&splats);
                }
                splats.clear();
            }
        }
        (self.progress)((w * h) as u64 * self.spp as u64);
        TileResult { x0, y0, w, pixels, non_finite, counters }
    }
}

#[cfg(test)]
mod tests {
    use crate::integrator::{AmbientOcclusion, Bdpt, CausticPathTracer, DirectLighting, PathTracer, Whitted};
    use crate::{Backend, CpuBackend};

    /// The capabilities that depend on the integrator follow its own declarations: bdpt
    /// and path-caustics splat light paths onto other pixels; the path tracer and
    /// path-caustics (whose camera paths are the path tracer's) lengthen paths by the
    /// specular extension and limit diffuse bounces; those two and direct light take a
    /// light tree's choice; the others do none of these.
    #[test]
    fn integrator_capabilities_follow_the_integrator() {
        let backends: [(Box<dyn Backend>, [bool; 4]); 6] = [
            (Box::new(CpuBackend::with_integrator(1, PathTracer).unwrap()), [false, true, true, true]),
            (Box::new(CpuBackend::with_integrator(1, CausticPathTracer).unwrap()), [true, true, true, true]),
            (Box::new(CpuBackend::with_integrator(1, Bdpt).unwrap()), [true, false, false, false]),
            (Box::new(CpuBackend::with_integrator(1, DirectLighting).unwrap()), [false, false, false, true]),
            (Box::new(CpuBackend::with_integrator(1, Whitted).unwrap()), [false, false, false, false]),
            (
                Box::new(CpuBackend::with_integrator(1, AmbientOcclusion::new(1.0)).unwrap()),
                [false, false, false, false],
            ),
        ];
        for (backend, expected) in backends {
            let c = backend.capabilities();
            assert_eq!([c.splats, c.extension, c.diffuse_depth, c.light_tree], expected, "{}", c.integrator);
        }
    }
}
