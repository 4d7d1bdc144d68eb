//! The backend-agnostic renderer API and the CPU backend.

use crate::camera::Camera;
use crate::film::{Film, PixelStats};
use crate::geometry::Geometry;
use crate::integrator::{PathCounters, PathSettings, SceneView, radiance};
use crate::lights::Lights;
use crate::sampler::Pcg32;
use crate::scene::Scene;
use crate::{Error, Result};
use bvh::TriangleTest;
use glam::Vec2;
use rayon::prelude::*;
use spectral::{SampledWavelengths, SpectralMode};
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
    /// Path depth and Russian roulette.
    pub path: PathSettings,
    /// Camera to use instead of the scene's (or the default framing).
    pub camera: Option<Camera>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            spp: 64,
            seed: 0,
            mode: SpectralMode::Hero,
            path: PathSettings::default(),
            camera: None,
        }
    }
}

/// Largest image side accepted (a 16K image; beyond that the film alone is > 6 GiB).
pub const MAX_IMAGE_SIDE: u32 = 16_384;

impl RenderSettings {
    /// Rejects absurd values with a message naming the setting.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 || self.width > MAX_IMAGE_SIDE || self.height > MAX_IMAGE_SIDE {
            return Err(Error::Setting(format!(
                "image size {}×{} must be between 1 and {MAX_IMAGE_SIDE} on each side",
                self.width, self.height
            )));
        }
        if self.spp == 0 {
            return Err(Error::Setting("samples per pixel must be at least 1".into()));
        }
        if let Some(c) = &self.camera {
            c.validate().map_err(Error::Setting)?;
        }
        Ok(())
    }
}

/// A scene made ready to render: validated, with its accelerator, lights and camera.
pub struct PreparedScene {
    /// The scene.
    pub scene: Scene,
    /// Its accelerators.
    pub geometry: Geometry,
    /// Its emitters.
    pub lights: Lights,
    /// Time spent building the BVH.
    pub build_time: Duration,
}

impl PreparedScene {
    /// Validates the scene and builds its accelerators (watertight triangle test) and
    /// light distribution.
    pub fn new(scene: Scene) -> Result<Self> {
        Self::with_triangle_test(scene, TriangleTest::default())
    }

    /// As [`PreparedScene::new`], with the given ray–triangle test.
    pub fn with_triangle_test(scene: Scene, test: TriangleTest) -> Result<Self> {
        scene.validate()?;
        let start = Instant::now();
        let geometry = Geometry::build(&scene, test)?;
        let build_time = start.elapsed();
        let lights = Lights::new(&scene);
        Ok(Self { scene, geometry, lights, build_time })
    }

    /// The camera a render uses: the settings', else the scene's, else the default framing.
    pub fn camera(&self, settings: &RenderSettings) -> Camera {
        settings
            .camera
            .or(self.scene.camera)
            .unwrap_or_else(|| Camera::framing(&self.scene.bounds(), settings.width as f32 / settings.height as f32))
    }
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
}

impl RenderStats {
    /// Samples per second.
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.wall.as_secs_f64().max(1e-9)
    }
}

/// A way of executing the integrator (CPU now, GPU later). Backends add samples to a
/// film; sample `k` of pixel `p` always uses the same random stream, so a backend may
/// split the work any way it likes.
pub trait Backend {
    /// A short name for messages.
    fn name(&self) -> &str;

    /// Adds samples `first_sample .. first_sample + spp` of every pixel to `film`;
    /// `progress` is told how many samples each finished piece of work took.
    fn render_pass(
        &self,
        scene: &PreparedScene,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<PathCounters>;
}

/// Renders `settings.spp` samples per pixel in one pass.
pub fn render(
    backend: &dyn Backend,
    scene: &PreparedScene,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(Film, RenderStats)> {
    settings.validate()?;
    let mut film = Film::new(settings.width, settings.height);
    let start = Instant::now();
    let counters = backend.render_pass(scene, settings, &mut film, 0, settings.spp, progress)?;
    let stats = RenderStats {
        wall: start.elapsed(),
        samples: settings.width as u64 * settings.height as u64 * settings.spp as u64,
        rays: counters.rays,
        non_finite: film.non_finite,
    };
    Ok((film, stats))
}

/// The CPU backend: 16×16 tiles rendered in parallel by rayon.
pub struct CpuBackend {
    pool: rayon::ThreadPool,
}

/// Tile side in pixels.
pub const TILE: u32 = 16;

impl CpuBackend {
    /// A backend with `threads` worker threads (0 = one per core).
    pub fn new(threads: usize) -> Result<Self> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::Setting(format!("cannot start {threads} threads: {e}")))?;
        Ok(Self { pool })
    }

    /// Worker threads in use.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }
}

struct TileResult {
    x0: u32,
    y0: u32,
    w: u32,
    pixels: Vec<PixelStats>,
    non_finite: u64,
    counters: PathCounters,
}

fn render_tiles<const N: usize>(
    scene: &PreparedScene,
    settings: &RenderSettings,
    film: &mut Film,
    first_sample: u32,
    spp: u32,
    wavelengths: impl Fn(&mut Pcg32) -> SampledWavelengths<N> + Sync,
    progress: &(dyn Fn(u64) + Sync),
) -> PathCounters {
    let (width, height) = (film.width(), film.height());
    let camera = scene.camera(settings).rays(width, height);
    let view = SceneView { scene: &scene.scene, geometry: &scene.geometry, lights: &scene.lights };
    let tiles_x = width.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> =
        (0..height.div_ceil(TILE)).flat_map(|ty| (0..tiles_x).map(move |tx| (tx * TILE, ty * TILE))).collect();
    let existing: &Film = film;
    let results: Vec<TileResult> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let (w, h) = (TILE.min(width - x0), TILE.min(height - y0));
            let mut pixels = Vec::with_capacity((w * h) as usize);
            let mut non_finite = 0;
            let mut counters = PathCounters::default();
            for y in y0..y0 + h {
                for x in x0..x0 + w {
                    let mut stats = *existing.pixel(x, y);
                    let pixel_index = y * width + x;
                    for s in first_sample..first_sample + spp {
                        let mut rng = Pcg32::for_sample(settings.seed, pixel_index, s);
                        let mut wl = wavelengths(&mut rng);
                        let jitter = rng.next_2d();
                        let ray = camera.ray(Vec2::new(x as f32, y as f32) + jitter);
                        let l = radiance(&view, ray, &mut wl, &settings.path, &mut rng, &mut counters);
                        let rgb = wl.to_linear_srgb(&l);
                        if rgb.iter().all(|v| v.is_finite()) {
                            stats.add(rgb);
                        } else {
                            non_finite += 1;
                        }
                    }
                    pixels.push(stats);
                }
            }
            progress((w * h) as u64 * spp as u64);
            TileResult { x0, y0, w, pixels, non_finite, counters }
        })
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
    total
}

impl Backend for CpuBackend {
    fn name(&self) -> &str {
        "cpu"
    }

    fn render_pass(
        &self,
        scene: &PreparedScene,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<PathCounters> {
        settings.validate()?;
        if film.width() != settings.width || film.height() != settings.height {
            return Err(Error::Setting("film size differs from the settings' image size".into()));
        }
        Ok(self.pool.install(|| match settings.mode {
            SpectralMode::Hero => render_tiles::<4>(
                scene,
                settings,
                film,
                first_sample,
                spp,
                |rng| SampledWavelengths::sample_hero(rng.next_f32()),
                progress,
            ),
            SpectralMode::Bins40 => render_tiles::<40>(
                scene,
                settings,
                film,
                first_sample,
                spp,
                |_| SampledWavelengths::fixed_bins(380.0, 10.0),
                progress,
            ),
            SpectralMode::Rgb => {
                render_tiles::<3>(scene, settings, film, first_sample, spp, |_| SampledWavelengths::rgb(), progress)
            }
        }))
    }
}
