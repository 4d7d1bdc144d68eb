//! The GPU backend: the tracer's integrator as a wgpu compute kernel.
//!
//! # Design
//!
//! * [`SceneData`] turns a [`PreparedScene`] into the flat arrays the kernel reads — a
//!   binary BVH (binned SAH, leaves of at most 4 triangles) in `bvh`'s 32-byte node
//!   layout, the triangles' vertices in leaf order, per-vertex normals and tangents with
//!   the triangle → vertex map, the CIE 1931 tables, the environment's spectrum, the
//!   light distribution, and the material kernel from [`crate::materials`] — and checks
//!   every buffer against the device's limits ([`SceneData::check_limits`]).
//! * [`GpuScene`] is that data on the device with the compiled pipeline: preparing it
//!   (upload, shader compilation) is the expensive part, so it is made once per scene —
//!   explicitly with [`GpuBackend::prepare`], or implicitly by the [`Backend`] impl,
//!   which caches the last scene it saw (keyed by the `PreparedScene`'s address, its BVH
//!   build time and the addresses and lengths of its arrays; a scene changed in place
//!   must be announced with [`GpuBackend::invalidate`]). An interactive viewer calling
//!   `render_pass` once per frame therefore pays only for the frame's samples.
//! * A pass renders the image in bands of rows (so that the per-pixel accumulators fit
//!   the device's buffer limits whatever the image size), each band in dispatches of at
//!   most [`DISPATCH_BUDGET`] pixel-samples (1–64 samples per pixel; short dispatches
//!   stay clear of GPU watchdogs and feed the progress callback). Each invocation adds
//!   its pixel's samples to an f32 count / mean / M2 (Welford); after the band (or
//!   every [`SAMPLES_PER_READBACK`] samples) the accumulators are read back and merged
//!   into the film's f64 [`PixelStats`] with Chan et al.'s parallel update, so a film
//!   may mix CPU and GPU passes.
//! * Rays (camera, extension and shadow, counted as the CPU counts them) are summed
//!   per invocation and added to a 64-bit atomic counter.
//!
//! # Differences from the CPU integrator
//!
//! The kernel (`wgsl/path.wgsl`) is a line-by-line port of `integrator::radiance`, and it
//! draws the CPU's own random stream (`Pcg32::for_sample(seed, pixel, sample)`, with the
//! 64-bit arithmetic emulated on word pairs) in the CPU's order, so a GPU path starts as
//! the CPU path of the same pixel sample and usually stays on it. What differs:
//!
//! * Hero mode only (four wavelengths); `bins40` and `rgb` are
//!   [`GpuError::Unsupported`], as are analytic shapes and custom (out-of-workspace)
//!   BSDFs (the latter by [`crate::materials::generate`]).
//! * A path has at most [`MAX_BOUNCES`] scattering events, also when `max_depth` is 0
//!   (unbounded on the CPU): with Russian roulette (q ≥ 0.05) the probability of
//!   reaching the cap is below 0.95²⁵⁶ ≈ 2·10⁻⁶ per path, a negligible bias.
//! * Rounding: the driver may contract multiply–adds into FMAs, and `atanh`, `sqrt`,
//!   `exp`, `sin`/`cos` are the GPU's, so values differ in the last bits and a path
//!   occasionally takes another branch (a Russian-roulette or Fresnel decision on the
//!   threshold, a ray grazing an edge) and decorrelates from the CPU's from there on;
//!   images are close to the CPU's, not bit-identical.
//! * Triangles are traced in a binary BVH (binned SAH, leaves ≤ 4) instead of the CPU's
//!   4-wide BVH; with hits at exactly equal distances the two may report different
//!   triangles.
//! * The watertight triangle test has no double-precision fallback (WGSL has no f64):
//!   an edge function that rounds to exactly zero counts as "on the edge", which can
//!   add a hit but never lose one; with FMA contraction the two triangles of a shared
//!   edge might disagree in the last bit for rays within an ulp of the edge.
//! * The environment's radiance spectrum is tabulated at 1 nm (360–830 nm) and
//!   interpolated linearly (exact for constant spectra; for uplifted RGB the error is
//!   far below the noise).
//! * WGSL has no infinities: ray extents are finite (3·10³⁸), and zero direction
//!   components become ±10⁻³⁰ in the slab test (the CPU's "on a slab plane counts as
//!   inside" rule, reached another way). Non-finite samples are found from their bits,
//!   immune to fast-math folding, and dropped and counted as on the CPU.
//! * Each pixel's mean and M2 are accumulated in f32 over at most
//!   [`SAMPLES_PER_READBACK`] samples (relative rounding ≲ 1024 · 2⁻²⁴ ≈ 6·10⁻⁵ in the
//!   worst case), then merged into the film's f64 statistics.

use crate::{GpuContext, GpuError};
use bvh::{Aabb, BuildConfig, Bvh, BvhNode, SplitMethod};
use bytemuck::{Pod, Zeroable};
use spectral::SpectralMode;
use spectral::tables::{CIE_SAMPLES, CIE_X, CIE_Y, CIE_Z};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};
use tracer::Camera;
use tracer::film::{Film, PixelStats};
use tracer::integrator::{PathCounters, ShadingNormals};
use tracer::render::{Backend, PreparedScene, RenderSettings};
use wgpu::util::DeviceExt;

/// The most scattering events a GPU path may have, whatever `max_depth` says.
pub const MAX_BOUNCES: u32 = 256;

/// The most pixel-samples one dispatch traces (fewer samples per pixel for larger
/// images, never less than one).
pub const DISPATCH_BUDGET: u64 = 1 << 18;

/// The most samples per pixel in one dispatch.
const MAX_SAMPLES_PER_DISPATCH: u32 = 64;

/// The most samples per pixel accumulated in f32 on the device before they are read
/// back and merged into the film's f64 statistics.
pub const SAMPLES_PER_READBACK: u32 = 1024;

/// The kernel's workgroup side (8 × 8 invocations, one per pixel).
const WORKGROUP: u32 = 8;

/// Bytes of one pixel's accumulator: mean (3 × f32), count (u32), M2 (3 × f32), dropped
/// non-finite samples (u32).
const PIXEL_BYTES: u64 = 32;

/// Bytes before the accumulators: the 64-bit ray counter and padding.
const FILM_HEADER_BYTES: u64 = 16;

/// The largest accumulator buffer a band uses (the device's limits may make it smaller).
const FILM_BAND_CAP: u64 = 64 << 20;

/// Storage buffers the kernel binds (six of ours, two of the material kernel's).
const STORAGE_BUFFERS: u32 = 8;

/// The integrator, appended to the generated material kernel.
const PATH_WGSL: &str = include_str!("wgsl/path.wgsl");

/// The kernel's uniform block (`PtParams` in `path.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Params {
    width: u32,
    height: u32,
    band_y0: u32,
    band_rows: u32,
    first_sample: u32,
    samples: u32,
    seed_lo: u32,
    seed_hi: u32,
    max_depth: u32,
    rr_depth: u32,
    specular_extension: u32,
    shading: u32,
    scene_flags: u32,
    node_count: u32,
    light_count: u32,
    env_pmf: f32,
    eye: [f32; 4],
    forward: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    inv_size: [f32; 2],
    lights_offset: u32,
    env_offset: u32,
}

const HAS_NORMALS: u32 = 1;
const HAS_TANGENTS: u32 = 2;
const HAS_ENVIRONMENT: u32 = 4;

/// Floats per light in the tables: three vertices, cdf, pmf, material id (bits).
const LIGHT_FLOATS: usize = 12;

/// What the kernel's uniforms and the camera need of a scene besides its buffers, kept
/// from [`SceneData`] into [`GpuScene`].
#[derive(Clone, Copy, Debug)]
struct SceneConstants {
    node_count: u32,
    light_count: u32,
    lights_offset: u32,
    env_offset: u32,
    env_pmf: f32,
    scene_flags: u32,
    camera: Option<Camera>,
    bounds: Aabb,
}

/// A scene as the flat arrays the kernel reads, built on the CPU; see the module docs.
pub struct SceneData {
    nodes: Vec<BvhNode>,
    tri_verts: Vec<[f32; 4]>,
    tri_vidx: Vec<[u32; 4]>,
    attrs: Vec<[f32; 4]>,
    tables: Vec<f32>,
    material_wgsl: String,
    material_data: Vec<u32>,
    spectra: Vec<f32>,
    constants: SceneConstants,
}

impl SceneData {
    /// Flattens `scene` for the kernel. Fails with [`GpuError::Unsupported`] for what
    /// the kernel cannot trace (analytic shapes, custom BSDFs) and passes on the
    /// material code generator's errors.
    pub fn new(prepared: &PreparedScene) -> Result<Self, GpuError> {
        let scene = &prepared.scene;
        if !scene.shapes.is_empty() {
            return Err(GpuError::Unsupported("analytic shapes (spheres, boxes, …)".into()));
        }
        let kernel = crate::materials::generate(&scene.materials, true)?;
        let config = BuildConfig {
            method: SplitMethod::BinnedSah,
            max_leaf_size: 4,
            leaf_by_sah: true,
            ..BuildConfig::default()
        };
        let bvh = Bvh::build(&scene.triangle_soup(), config)
            .map_err(|e| GpuError::Unsupported(format!("this geometry ({e})")))?;
        let lights = &prepared.lights;
        let pmfs = lights.prim_pmfs();

        let mut tri_verts = Vec::with_capacity(3 * bvh.prim_ids().len());
        for &prim in bvh.prim_ids() {
            let v = scene.triangle_vertices(prim as usize);
            let material = scene.material_ids[prim as usize];
            let pmf = pmfs.get(prim as usize).copied().unwrap_or(0.0);
            tri_verts.push([v[0].x, v[0].y, v[0].z, f32::from_bits(material)]);
            tri_verts.push([v[1].x, v[1].y, v[1].z, pmf]);
            tri_verts.push([v[2].x, v[2].y, v[2].z, f32::from_bits(prim)]);
        }
        let mut scene_flags = 0;
        if !scene.normals.is_empty() {
            scene_flags |= HAS_NORMALS;
        }
        if !scene.tangents.is_empty() {
            scene_flags |= HAS_TANGENTS;
        }
        let (tri_vidx, attrs) = if scene_flags & (HAS_NORMALS | HAS_TANGENTS) != 0 {
            let vidx = bvh.prim_ids().iter().map(|&p| {
                let t = scene.triangles[p as usize];
                [t[0], t[1], t[2], 0]
            });
            let attrs = (0..scene.positions.len()).flat_map(|i| {
                let n = scene.normals.get(i).copied().unwrap_or([0.0; 3]);
                let t = scene.tangents.get(i).copied().unwrap_or([0.0; 3]);
                [[n[0], n[1], n[2], 0.0], [t[0], t[1], t[2], 0.0]]
            });
            (vidx.collect(), attrs.collect())
        } else {
            (Vec::new(), Vec::new())
        };

        // Tables: CIE x̄ȳz̄ interleaved, the environment's spectrum, the lights.
        let mut tables = Vec::with_capacity(4 * CIE_SAMPLES + LIGHT_FLOATS * lights.prims().len());
        for i in 0..CIE_SAMPLES {
            tables.extend([CIE_X[i], CIE_Y[i], CIE_Z[i]]);
        }
        let env_offset = tables.len() as u32;
        for i in 0..CIE_SAMPLES {
            let lambda = spectral::tables::CIE_LAMBDA_MIN + i as f32;
            tables.push(scene.environment.as_ref().map_or(0.0, |e| e.radiance.spectrum.eval(lambda)));
        }
        if scene.environment.is_some() {
            scene_flags |= HAS_ENVIRONMENT;
        }
        let lights_offset = tables.len() as u32;
        for (&prim, &cdf) in lights.prims().iter().zip(lights.cdf()) {
            // Shapes are rejected above, so every sampled emitter is a triangle.
            let v = scene.triangle_vertices(prim as usize);
            tables.extend(v.iter().flat_map(|p| p.to_array()));
            tables.extend([cdf, pmfs[prim as usize], f32::from_bits(scene.material_ids[prim as usize])]);
        }

        let constants = SceneConstants {
            node_count: bvh.nodes().len() as u32,
            light_count: lights.prims().len() as u32,
            lights_offset,
            env_offset,
            env_pmf: lights.environment_pmf(),
            scene_flags,
            camera: scene.camera,
            bounds: scene.bounds(),
        };
        Ok(Self {
            constants,
            nodes: bvh.nodes().to_vec(),
            tri_verts,
            tri_vidx,
            attrs,
            tables,
            material_wgsl: kernel.wgsl,
            material_data: kernel.data,
            spectra: kernel.spectra,
        })
    }

    /// What each storage buffer holds and how many bytes it needs, in binding order
    /// (the per-pixel accumulators are not included: their size follows the image and
    /// is split into bands to fit).
    pub fn buffer_sizes(&self) -> [(&'static str, u64); 7] {
        let bytes = |n: usize, each: usize| (n * each) as u64;
        [
            ("BVH nodes", bytes(self.nodes.len(), 32)),
            ("triangle vertices", bytes(self.tri_verts.len(), 16)),
            ("triangle vertex indices", bytes(self.tri_vidx.len(), 16)),
            ("vertex normals and tangents", bytes(self.attrs.len(), 16)),
            ("spectral tables and lights", bytes(self.tables.len(), 4)),
            ("material parameters", bytes(self.material_data.len(), 4)),
            ("material spectra", bytes(self.spectra.len(), 4)),
        ]
    }

    /// Checks every buffer against `limits` (`max_storage_buffer_binding_size`,
    /// `max_buffer_size`) and the number of storage buffers the kernel binds against
    /// `max_storage_buffers_per_shader_stage`; the error names the buffer, the limit and
    /// both sizes.
    pub fn check_limits(&self, limits: &wgpu::Limits) -> Result<(), GpuError> {
        if limits.max_storage_buffers_per_shader_stage < STORAGE_BUFFERS {
            return Err(GpuError::Unsupported(format!(
                "a device with {} storage buffers per shader stage (max_storage_buffers_per_shader_stage; the kernel \
                 binds {STORAGE_BUFFERS})",
                limits.max_storage_buffers_per_shader_stage
            )));
        }
        for (what, needed) in self.buffer_sizes() {
            check_size(what, needed, limits)?;
        }
        Ok(())
    }

    /// The WGSL of the whole kernel: the generated materials, then the integrator
    /// (`wgsl/path.wgsl`) with its bounce cap.
    pub fn shader_source(&self) -> String {
        format!("{}\nconst PT_MAX_BOUNCES: u32 = {MAX_BOUNCES}u;\n{PATH_WGSL}", self.material_wgsl)
    }
}

/// One buffer of `needed` bytes against the binding and allocation limits.
fn check_size(what: &'static str, needed: u64, limits: &wgpu::Limits) -> Result<(), GpuError> {
    let checks = [
        ("max_storage_buffer_binding_size", limits.max_storage_buffer_binding_size),
        ("max_buffer_size", limits.max_buffer_size),
    ];
    for (limit_name, limit) in checks {
        if needed > limit {
            return Err(GpuError::Limit { what, needed, limit_name, limit });
        }
    }
    Ok(())
}

/// The per-band accumulators, their read-back copy and the bind group that uses them.
struct FilmBuffers {
    pixels: u64,
    accum: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// A scene on the device: its buffers and the compiled pipeline. Made by
/// [`GpuBackend::prepare`]; rendered by [`GpuBackend::render_prepared`].
pub struct GpuScene {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// Scene buffers in binding order 1–5, then the material buffers (10, 11).
    buffers: Vec<wgpu::Buffer>,
    film: Mutex<Option<FilmBuffers>>,
    constants: SceneConstants,
    compile_time: Duration,
    prepare_time: Duration,
}

impl GpuScene {
    /// Time spent compiling the shader and creating the pipeline.
    pub fn compile_time(&self) -> Duration {
        self.compile_time
    }

    /// Time spent preparing the scene in all: flattening (BVH build, material code
    /// generation), upload and compilation.
    pub fn prepare_time(&self) -> Duration {
        self.prepare_time
    }

    /// The camera a render uses, as [`PreparedScene::camera`] chooses it.
    fn camera(&self, settings: &RenderSettings) -> Camera {
        settings
            .camera
            .or(self.constants.camera)
            .unwrap_or_else(|| Camera::framing(&self.constants.bounds, settings.width as f32 / settings.height as f32))
    }
}

/// Identifies the scene the [`Backend`] impl has cached (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SceneKey {
    address: usize,
    build_time: Duration,
    arrays: [(usize, usize); 4],
}

impl SceneKey {
    fn of(p: &PreparedScene) -> Self {
        let s = &p.scene;
        let arr = |ptr: *const u8, len: usize| (ptr as usize, len);
        Self {
            address: p as *const PreparedScene as usize,
            build_time: p.build_time,
            arrays: [
                arr(s.positions.as_ptr().cast(), s.positions.len()),
                arr(s.triangles.as_ptr().cast(), s.triangles.len()),
                arr(s.materials.as_ptr().cast(), s.materials.len()),
                arr(s.normals.as_ptr().cast(), s.normals.len()),
            ],
        }
    }
}

/// The tracer's [`Backend`] on a wgpu device.
pub struct GpuBackend {
    ctx: GpuContext,
    cache: Mutex<Option<(SceneKey, Arc<GpuScene>)>>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Waits for an error scope and turns what it caught into a [`GpuError::Shader`].
fn pop_scope(scope: wgpu::ErrorScopeGuard, what: &str) -> Result<(), GpuError> {
    match pollster::block_on(scope.pop()) {
        None => Ok(()),
        Some(e) => Err(GpuError::Shader(format!("{what}: {e}"))),
    }
}

impl GpuBackend {
    /// Opens the default adapter ([`GpuContext::new`]).
    pub fn new() -> Result<Self, GpuError> {
        Ok(Self::with_context(GpuContext::new()?))
    }

    /// A backend on an already open device.
    pub fn with_context(ctx: GpuContext) -> Self {
        Self { ctx, cache: Mutex::new(None) }
    }

    /// The device the backend renders on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Shader compilation and pipeline creation time of the scene the [`Backend`] impl
    /// has cached (the last one rendered), if any.
    pub fn compile_time(&self) -> Option<Duration> {
        lock(&self.cache).as_ref().map(|(_, s)| s.compile_time)
    }

    /// Total preparation time (flattening, upload, compilation) of the cached scene.
    pub fn prepare_time(&self) -> Option<Duration> {
        lock(&self.cache).as_ref().map(|(_, s)| s.prepare_time)
    }

    /// Forgets the cached scene, so that the next `render_pass` prepares it again: call
    /// it after changing a [`PreparedScene`] in place (its materials, say).
    pub fn invalidate(&self) {
        *lock(&self.cache) = None;
    }

    /// Uploads `scene` and compiles its kernel.
    pub fn prepare(&self, scene: &PreparedScene) -> Result<GpuScene, GpuError> {
        let start = Instant::now();
        let data = SceneData::new(scene)?;
        data.check_limits(&self.ctx.limits)?;
        let device = &self.ctx.device;
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);

        // Bindings may not be empty: pad every array to at least one element (16 bytes;
        // 32 for the nodes), which the kernel never reads (its counts say so).
        let storage = |label: &str, bytes: &[u8], min: usize| {
            let mut contents = bytes.to_vec();
            if contents.len() < min {
                contents.resize(min, 0);
            }
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let buffers = vec![
            storage("bvh nodes", bytemuck::cast_slice(&data.nodes), 32),
            storage("triangle vertices", bytemuck::cast_slice(&data.tri_verts), 48),
            storage("triangle vertex indices", bytemuck::cast_slice(&data.tri_vidx), 16),
            storage("vertex attributes", bytemuck::cast_slice(&data.attrs), 32),
            storage("tables", bytemuck::cast_slice(&data.tables), 16),
            storage("material data", bytemuck::cast_slice(&data.material_data), 16),
            storage("material spectra", bytemuck::cast_slice(&data.spectra), 16),
        ];
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let entries: Vec<_> = [(0, wgpu::BufferBindingType::Uniform)]
            .into_iter()
            .chain([1, 2, 3, 4, 5, 10, 11].map(|b| (b, read)))
            .chain([(6, wgpu::BufferBindingType::Storage { read_only: false })])
            .map(|(b, ty)| entry(b, ty))
            .collect();
        let layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("spt"), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("spt"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });

        let source = data.shader_source();
        let compile_start = Instant::now();
        let shader_scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("spt path tracer"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("spt path tracer"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("pt_main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let shader_result = pop_scope(shader_scope, "the path-tracing kernel does not compile");
        let compile_time = compile_start.elapsed();
        let memory_result = pop_scope(memory, "out of GPU memory uploading the scene");
        let validation_result = pop_scope(validation, "uploading the scene");
        shader_result?;
        memory_result?;
        validation_result?;

        Ok(GpuScene {
            pipeline,
            layout,
            params,
            buffers,
            film: Mutex::new(None),
            constants: data.constants,
            compile_time,
            prepare_time: start.elapsed(),
        })
    }

    /// The cached GPU scene for `scene`, prepared now if it is not the cached one.
    fn cached(&self, scene: &PreparedScene) -> Result<Arc<GpuScene>, GpuError> {
        let key = SceneKey::of(scene);
        let mut cache = lock(&self.cache);
        if let Some((k, s)) = cache.as_ref()
            && *k == key
        {
            return Ok(Arc::clone(s));
        }
        *cache = None;
        let prepared = Arc::new(self.prepare(scene)?);
        *cache = Some((key, Arc::clone(&prepared)));
        Ok(prepared)
    }

    /// Adds samples `first_sample .. first_sample + spp` of every pixel to `film`, as
    /// [`Backend::render_pass`] does, on a scene prepared by [`GpuBackend::prepare`]
    /// (with this backend's device). `settings` should have passed
    /// [`RenderSettings::validate`]; the film must have the settings' size.
    pub fn render_prepared(
        &self,
        gpu: &GpuScene,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<PathCounters, GpuError> {
        if settings.mode != SpectralMode::Hero {
            return Err(unsupported_mode(settings.mode));
        }
        let (width, height) = (settings.width, settings.height);
        if film.width() != width || film.height() != height {
            return Err(GpuError::Unsupported("a film whose size differs from the settings' image size".into()));
        }
        if spp == 0 || width == 0 || height == 0 {
            return Ok(PathCounters::default());
        }
        let device = &self.ctx.device;
        let queue = &self.ctx.queue;
        let limits = &self.ctx.limits;

        // Bands of whole rows whose accumulators fit one buffer.
        let row_bytes = PIXEL_BYTES * width as u64;
        let cap = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size).min(FILM_BAND_CAP);
        check_size("one image row of per-pixel accumulators", FILM_HEADER_BYTES + row_bytes, limits)?;
        let band_rows_max = ((cap.saturating_sub(FILM_HEADER_BYTES) / row_bytes).max(1) as u32).min(height);
        let band_pixels_max = band_rows_max as u64 * width as u64;

        let mut film_slot = lock(&gpu.film);
        if film_slot.as_ref().is_none_or(|f| f.pixels < band_pixels_max) {
            *film_slot = Some(self.film_buffers(gpu, band_pixels_max));
        }
        let fb = film_slot.as_ref().expect("just made");

        let (eye, forward, right, up) = gpu.camera(settings).rays(width, height).basis();
        let v4 = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        let shading = match settings.path.shading_normals {
            ShadingNormals::Adapted => 0,
            ShadingNormals::FaceForward => 1,
            ShadingNormals::Geometric => 2,
        };
        let mut params = Params {
            width,
            height,
            seed_lo: settings.seed as u32,
            seed_hi: (settings.seed >> 32) as u32,
            max_depth: settings.path.max_depth,
            rr_depth: settings.path.rr_depth,
            specular_extension: settings.path.specular_extension,
            shading,
            scene_flags: gpu.constants.scene_flags,
            node_count: gpu.constants.node_count,
            light_count: gpu.constants.light_count,
            env_pmf: gpu.constants.env_pmf,
            eye: v4(eye),
            forward: v4(forward),
            right: v4(right),
            up: v4(up),
            inv_size: [1.0 / width as f32, 1.0 / height as f32],
            lights_offset: gpu.constants.lights_offset,
            env_offset: gpu.constants.env_offset,
            ..Params::default()
        };

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut rays = 0u64;
        let mut y0 = 0;
        while y0 < height {
            let rows = band_rows_max.min(height - y0);
            let band_pixels = rows as u64 * width as u64;
            let band_bytes = FILM_HEADER_BYTES + band_pixels * PIXEL_BYTES;
            let per_dispatch = (DISPATCH_BUDGET / band_pixels).clamp(1, MAX_SAMPLES_PER_DISPATCH as u64) as u32;
            params.band_y0 = y0;
            params.band_rows = rows;
            let mut done = 0;
            while done < spp {
                let n = per_dispatch.min(spp - done).min(SAMPLES_PER_READBACK - done % SAMPLES_PER_READBACK);
                params.first_sample = first_sample.wrapping_add(done);
                params.samples = n;
                queue.write_buffer(&gpu.params, 0, bytemuck::bytes_of(&params));
                let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                if done % SAMPLES_PER_READBACK == 0 {
                    encoder.clear_buffer(&fb.accum, 0, Some(band_bytes));
                }
                {
                    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("spt"),
                        timestamp_writes: None,
                    });
                    pass.set_pipeline(&gpu.pipeline);
                    pass.set_bind_group(0, &fb.bind_group, &[]);
                    pass.dispatch_workgroups(width.div_ceil(WORKGROUP), rows.div_ceil(WORKGROUP), 1);
                }
                let index = queue.submit([encoder.finish()]);
                device
                    .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
                    .map_err(|e| GpuError::Shader(format!("waiting for the GPU: {e}")))?;
                progress(band_pixels * n as u64);
                done += n;
                if done % SAMPLES_PER_READBACK == 0 || done == spp {
                    rays += self.read_band(fb, band_bytes, film, y0, rows)?;
                }
            }
            y0 += rows;
        }
        pop_scope(scope, "rendering")?;
        Ok(PathCounters { rays })
    }

    /// Accumulator and read-back buffers for `pixels` pixels, with their bind group.
    fn film_buffers(&self, gpu: &GpuScene, pixels: u64) -> FilmBuffers {
        let device = &self.ctx.device;
        let size = FILM_HEADER_BYTES + pixels * PIXEL_BYTES;
        let accum = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("accumulators"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("accumulator read-back"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let b = &gpu.buffers;
        let bindings = [
            (0, &gpu.params),
            (1, &b[0]),
            (2, &b[1]),
            (3, &b[2]),
            (4, &b[3]),
            (5, &b[4]),
            (6, &accum),
            (10, &b[5]),
            (11, &b[6]),
        ];
        let entries: Vec<_> = bindings
            .iter()
            .map(|&(binding, buffer)| wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() })
            .collect();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("spt"),
            layout: &gpu.layout,
            entries: &entries,
        });
        FilmBuffers { pixels, accum, readback, bind_group }
    }

    /// Copies a band's accumulators back, merges them into `film` (rows `y0 ..
    /// y0 + rows`) and returns the band's ray count.
    fn read_band(&self, fb: &FilmBuffers, bytes: u64, film: &mut Film, y0: u32, rows: u32) -> Result<u64, GpuError> {
        let device = &self.ctx.device;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.copy_buffer_to_buffer(&fb.accum, 0, &fb.readback, 0, Some(bytes));
        self.ctx.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        fb.readback.map_async(wgpu::MapMode::Read, 0..bytes, move |r| {
            let _ = tx.send(r);
        });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Shader(format!("waiting for the GPU: {e}")))?;
        rx.recv()
            .map_err(|e| GpuError::Shader(format!("reading the accumulators back: {e}")))?
            .map_err(|e| GpuError::Shader(format!("reading the accumulators back: {e}")))?;
        let rays;
        {
            let view = fb
                .readback
                .get_mapped_range(0..bytes)
                .map_err(|e| GpuError::Shader(format!("reading the accumulators back: {e}")))?;
            let words: &[u32] = bytemuck::cast_slice(&view);
            rays = words[0] as u64 | (words[1] as u64) << 32;
            let width = film.width() as usize;
            let first = y0 as usize * width;
            let pixels = &words[(FILM_HEADER_BYTES / 4) as usize..];
            let mut non_finite = 0u64;
            for (i, px) in pixels.chunks_exact(8).take(rows as usize * width).enumerate() {
                let f = |k: usize| f32::from_bits(px[k]) as f64;
                let pass = PixelStats { count: px[3], mean: [f(0), f(1), f(2)], m2: [f(4), f(5), f(6)] };
                film.pixels_mut()[first + i].merge(&pass);
                non_finite += px[7] as u64;
            }
            film.non_finite += non_finite;
        }
        fb.readback.unmap();
        Ok(rays)
    }
}

fn unsupported_mode(mode: SpectralMode) -> GpuError {
    GpuError::Unsupported(format!(
        "the '{}' spectral mode (it traces hero wavelengths only: use --spectral hero, or --backend cpu)",
        mode.name()
    ))
}

impl From<GpuError> for tracer::Error {
    fn from(e: GpuError) -> Self {
        tracer::Error::Backend(e.to_string())
    }
}

impl Backend for GpuBackend {
    fn name(&self) -> &str {
        "gpu"
    }

    fn render_pass(
        &self,
        scene: &PreparedScene,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> tracer::Result<PathCounters> {
        settings.validate()?;
        if film.width() != settings.width || film.height() != settings.height {
            return Err(tracer::Error::Setting("film size differs from the settings' image size".into()));
        }
        if settings.mode != SpectralMode::Hero {
            return Err(unsupported_mode(settings.mode).into());
        }
        let gpu = self.cached(scene)?;
        Ok(self.render_prepared(&gpu, settings, film, first_sample, spp, progress)?)
    }
}
