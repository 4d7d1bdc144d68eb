//! Frame-by-frame refinement with the statistics on the device (a viewer's loop).
//!
//! [`DeviceAccumulation`] keeps one accumulator per pixel of the whole image on the GPU
//! across frames: a frame is its dispatches plus a small display kernel
//! (`wgsl/display.wgsl`) whose 4-byte pixels are all that is read back — 8 MB at 1080p
//! instead of the 66 MB of accumulators and a 2M-pixel merge on the CPU that
//! [`PreparedScene::render_pass`] costs — or nothing at all, where a window draws them
//! from the device ([`DeviceAccumulation::display_frame`], [`crate::present`]). Exactness is kept: at every multiple of
//! [`SAMPLES_PER_READBACK`] in the sample index (where `render_pass` reads back too) the
//! accumulators are folded into an exact [`Film`] on the CPU and their means uploaded for
//! the display kernel, so [`Accumulation::film`] gives the bytes a render of the same
//! samples gives.

use crate::backend::{DISPATCH_BUDGET, GpuScene, SAMPLES_PER_READBACK, map_read};
use crate::kernel::{FILM_HEADER_BYTES, PixelAccum, display_source};
use crate::present::DeviceFrame;
use crate::{GpuContext, GpuError};
use std::sync::Arc;
use tracer::accumulation::{Accumulation, check_accumulation_settings};
use tracer::film::{Film, MAX_PIXEL_SAMPLES};
use tracer::integrator::PathCounters;
use tracer::render::{PixelRect, PreparedScene, RenderSettings};

/// Bytes of one pixel's accumulator.
const PIXEL_BYTES: u64 = std::mem::size_of::<PixelAccum>() as u64;

/// Bytes the device holds per pixel: accumulators, their read-back copy, the folded
/// means (16) and the display word with its read-back copy (4 + 4). A window's frames
/// ([`DeviceAccumulation::display_frame`]) add 4 each, at most two at a time in the viewer.
pub const DEVICE_BYTES_PER_PIXEL: u64 = 2 * PIXEL_BYTES + 16 + 8;

/// The display kernel: compiled once per accumulation.
struct Display {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl Display {
    fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let entry = crate::backend::buffer_entry;
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("spt display"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, read),
                entry(2, read),
                entry(3, wgpu::BufferBindingType::Storage { read_only: false }),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("spt display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("spt display"),
            source: wgpu::ShaderSource::Wgsl(display_source().into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("spt display"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("pt_display_main"),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(format!("the display kernel does not compile: {e}")));
        }
        Ok(Self { pipeline, layout })
    }

    /// The kernel's bind group: its parameters, the accumulators, the folded means and the
    /// display words it writes.
    fn bind_group(&self, ctx: &GpuContext, buffers: [&wgpu::Buffer; 4]) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = (0..)
            .zip(buffers)
            .map(|(binding, b)| wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() })
            .collect();
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("spt display"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Runs the kernel of `bind` over a `width × height` image.
    fn encode(&self, encoder: &mut wgpu::CommandEncoder, bind: &wgpu::BindGroup, width: u32, height: u32) {
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("spt display"), timestamp_writes: None });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
    }
}

/// The buffers of one image size.
struct Buffers {
    width: u32,
    height: u32,
    /// The kernel's uniforms (its own: a render of the same scene may run beside it).
    params: wgpu::Buffer,
    accum: wgpu::Buffer,
    accum_readback: wgpu::Buffer,
    /// A wavefront kernel's paths and queues, one path per pixel (in `path_bind`).
    wavefront: Option<crate::wavefront::Buffers>,
    path_bind: wgpu::BindGroup,
    /// Per pixel: the folded samples' mean (xyz) and count (w), for the display.
    folded: wgpu::Buffer,
    display_params: wgpu::Buffer,
    display_out: wgpu::Buffer,
    display_readback: wgpu::Buffer,
    display_bind: wgpu::BindGroup,
    /// Frames made for a window ([`DeviceAccumulation::display_frame`]), each with the
    /// display kernel's bind group writing it; one whose clones were all dropped is
    /// written again.
    frames: Vec<(DeviceFrame, wgpu::BindGroup)>,
}

impl Buffers {
    fn accum_bytes(&self) -> u64 {
        FILM_HEADER_BYTES + self.width as u64 * self.height as u64 * PIXEL_BYTES
    }
}

/// An [`Accumulation`] whose per-pixel statistics stay on the GPU; see the module docs.
pub struct DeviceAccumulation {
    scene: Arc<GpuScene>,
    display: Display,
    buffers: Buffers,
    settings: RenderSettings,
    /// The exact statistics of the folded samples (those before `folded_samples`).
    film: Film,
    folded_counters: PathCounters,
    folded_samples: u32,
    samples: u32,
}

impl DeviceAccumulation {
    /// An empty accumulation of `scene` seen with `settings`; fails where the whole
    /// image's accumulators do not fit one buffer of the device (see
    /// [`DeviceAccumulation::fits`]).
    pub fn new(scene: Arc<GpuScene>, settings: &RenderSettings) -> Result<Self, tracer::Error> {
        check_accumulation_settings(&scene.capabilities(), settings)?;
        let ctx = scene.context();
        let display = Display::new(ctx)?;
        let buffers = Self::buffers(&scene, &display, settings.width, settings.height)?;
        Ok(Self {
            film: Film::new(settings.width, settings.height),
            scene,
            display,
            buffers,
            settings: settings.clone(),
            folded_counters: PathCounters::default(),
            folded_samples: 0,
            samples: 0,
        })
    }

    /// Whether a `width` × `height` image's accumulators fit one buffer of the device.
    pub fn fits(limits: &wgpu::Limits, width: u32, height: u32) -> bool {
        let bytes =
            (width as u64 * height as u64).checked_mul(PIXEL_BYTES).and_then(|b| b.checked_add(FILM_HEADER_BYTES));
        bytes.is_some_and(|b| b <= limits.max_storage_buffer_binding_size.min(limits.max_buffer_size))
    }

    fn buffers(scene: &GpuScene, display: &Display, width: u32, height: u32) -> Result<Buffers, GpuError> {
        let ctx = scene.context();
        let limits = &ctx.limits;
        let pixels = width as u64 * height as u64;
        let accum_bytes = FILM_HEADER_BYTES + pixels * PIXEL_BYTES;
        if !Self::fits(limits, width, height) {
            return Err(GpuError::Limit {
                what: "the whole image's accumulators",
                needed: accum_bytes,
                limit_name: "max_storage_buffer_binding_size",
                limit: limits.max_storage_buffer_binding_size.min(limits.max_buffer_size),
            });
        }
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        use wgpu::BufferUsages as U;
        let params = buffer("accumulation params", crate::kernel::UNIFORM_BYTES, U::UNIFORM | U::COPY_DST);
        let accum = buffer("accumulation", accum_bytes, U::STORAGE | U::COPY_SRC | U::COPY_DST);
        let accum_readback = buffer("accumulation read-back", accum_bytes, U::MAP_READ | U::COPY_DST);
        let folded = buffer("folded means", pixels.max(1) * 16, U::STORAGE | U::COPY_DST);
        let display_out = buffer("display", pixels.max(1) * 4, U::STORAGE | U::COPY_SRC);
        let display_readback = buffer("display read-back", pixels.max(1) * 4, U::MAP_READ | U::COPY_DST);
        let display_params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display params"),
            size: 16,
            usage: U::UNIFORM | U::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue.write_buffer(&display_params, 0, bytemuck::cast_slice(&[width, height, 0, 0]));
        let wavefront = scene.wavefront_buffers(pixels)?;
        let path_bind = scene.bind_group(&params, &accum, None, wavefront.as_ref());
        let display_bind = display.bind_group(ctx, [&display_params, &accum, &folded, &display_out]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(format!("out of GPU memory for a {width}×{height} accumulation: {e}")));
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.clear_buffer(&accum, 0, None);
        encoder.clear_buffer(&folded, 0, None);
        ctx.queue.submit([encoder.finish()]);
        Ok(Buffers {
            width,
            height,
            params,
            accum,
            accum_readback,
            wavefront,
            path_bind,
            folded,
            display_params,
            display_out,
            display_readback,
            display_bind,
            frames: Vec::new(),
        })
    }

    /// Reads the accumulators back and merges them into `film`, returning their
    /// counters.
    fn read_into(&self, film: &mut Film) -> Result<PathCounters, GpuError> {
        let b = &self.buffers;
        let whole = PixelRect::full(b.width, b.height);
        self.scene.read_back(&b.accum, &b.accum_readback, b.accum_bytes(), film, 0, b.height, whole)
    }

    /// Moves the device's samples into the exact film and starts the next block: the
    /// accumulators cleared, the folded means uploaded for the display.
    fn fold(&mut self) -> Result<(), GpuError> {
        let mut film = std::mem::replace(&mut self.film, Film::new(0, 0));
        let read = self.read_into(&mut film);
        self.film = film;
        self.folded_counters += read?;
        self.folded_samples = self.samples;
        let folded: Vec<[f32; 4]> = self
            .film
            .pixels()
            .iter()
            .map(|p| {
                let m = p.mean();
                [m[0] as f32, m[1] as f32, m[2] as f32, p.count as f32]
            })
            .collect();
        let ctx = self.scene.context();
        ctx.queue.write_buffer(&self.buffers.folded, 0, bytemuck::cast_slice(&folded));
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.clear_buffer(&self.buffers.accum, 0, None);
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    }

    fn add_gpu(&mut self, spp: u32) -> Result<(), GpuError> {
        let scene = Arc::clone(&self.scene);
        let ctx = scene.context();
        let (width, height) = (self.buffers.width, self.buffers.height);
        let pixels = width as u64 * height as u64;
        let per_dispatch = (DISPATCH_BUDGET / pixels.max(1)).clamp(1, scene.max_samples_per_dispatch() as u64) as u32;
        let mut params = scene.kernel_params(&self.settings);
        let kernel = scene.kernel_for(&self.settings)?;
        scene.write_seeds(&self.buffers.params, &self.settings);
        params.band_y0 = 0;
        params.band_rows = height;
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut left = spp.min(MAX_PIXEL_SAMPLES - self.samples);
        while left > 0 {
            let n = per_dispatch.min(left).min(SAMPLES_PER_READBACK - self.samples % SAMPLES_PER_READBACK);
            params.first_sample = self.samples;
            params.samples = n;
            ctx.queue.write_buffer(&self.buffers.params, 0, bytemuck::bytes_of(&params));
            let encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            let b = &self.buffers;
            scene.submit_samples(encoder, &kernel, &b.path_bind, b.wavefront.as_ref(), width, height, &params)?;
            self.samples += n;
            left -= n;
            if self.samples.is_multiple_of(SAMPLES_PER_READBACK) {
                self.fold()?;
            }
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(format!("rendering: {e}")));
        }
        Ok(())
    }

    fn display_gpu(&self, out: &mut [u32]) -> Result<(), GpuError> {
        let ctx = self.scene.context();
        let b = &self.buffers;
        let bytes = b.width as u64 * b.height as u64 * 4;
        if out.len() as u64 * 4 != bytes {
            return Err(GpuError::Shader(format!(
                "a display of {} pixels for a {}×{} image",
                out.len(),
                b.width,
                b.height
            )));
        }
        if bytes == 0 {
            return Ok(());
        }
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        self.display.encode(&mut encoder, &b.display_bind, b.width, b.height);
        encoder.copy_buffer_to_buffer(&b.display_out, 0, &b.display_readback, 0, Some(bytes));
        ctx.queue.submit([encoder.finish()]);
        {
            let view = map_read(ctx, &b.display_readback, bytes, "reading the display back")?;
            out.copy_from_slice(bytemuck::cast_slice(&view));
        }
        b.display_readback.unmap();
        Ok(())
    }

    /// The running mean as display words on the device (what [`Accumulation::display`]
    /// reads back), for a window that draws them from there
    /// ([`crate::present::WindowSurface`]). Returns once the GPU has made them, so a
    /// viewer's frame time is its render's; nothing is copied to the CPU.
    pub fn display_frame(&mut self) -> Result<DeviceFrame, GpuError> {
        let scene = Arc::clone(&self.scene);
        let ctx = scene.context();
        let b = &mut self.buffers;
        let slot = match b.frames.iter().position(|(frame, _)| frame.is_free()) {
            Some(i) => i,
            None => {
                let pixels = crate::present::frame_buffer(ctx, b.width as u64 * b.height as u64)?;
                let bind = self.display.bind_group(ctx, [&b.display_params, &b.accum, &b.folded, &pixels]);
                let frame = DeviceFrame { width: b.width, height: b.height, pixels: Arc::new(pixels) };
                b.frames.push((frame, bind));
                b.frames.len() - 1
            }
        };
        let (frame, bind) = &b.frames[slot];
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        self.display.encode(&mut encoder, bind, b.width, b.height);
        let done = ctx.queue.submit([encoder.finish()]);
        ctx.device
            .poll(wgpu::PollType::Wait { submission_index: Some(done), timeout: None })
            .map_err(|e| GpuError::Shader(format!("waiting for the GPU: {e}")))?;
        Ok(frame.clone())
    }

    /// The GPU's accumulation behind `accumulation`, if it is one (a viewer or benchmark
    /// that can use [`DeviceAccumulation::display_frame`]).
    pub fn of(accumulation: &mut dyn Accumulation) -> Option<&mut Self> {
        accumulation.as_any_mut().and_then(|a| a.downcast_mut())
    }

    /// The context the accumulation renders with (a window surface showing its frames
    /// must be made from it).
    pub fn context(&self) -> &GpuContext {
        self.scene.context()
    }
}

impl Accumulation for DeviceAccumulation {
    fn samples(&self) -> u32 {
        self.samples
    }

    fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    fn restart(&mut self, settings: &RenderSettings) -> tracer::Result<()> {
        check_accumulation_settings(&self.scene.capabilities(), settings)?;
        if (settings.width, settings.height) != (self.buffers.width, self.buffers.height) {
            self.buffers = Self::buffers(&self.scene, &self.display, settings.width, settings.height)?;
            self.film = Film::new(settings.width, settings.height);
        } else {
            let ctx = self.scene.context();
            let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            encoder.clear_buffer(&self.buffers.accum, 0, None);
            encoder.clear_buffer(&self.buffers.folded, 0, None);
            ctx.queue.submit([encoder.finish()]);
            self.film.clear();
        }
        self.settings = settings.clone();
        self.samples = 0;
        self.folded_samples = 0;
        self.folded_counters = PathCounters::default();
        Ok(())
    }

    fn add(&mut self, spp: u32) -> tracer::Result<()> {
        tracer::render::check_sample_range(&self.settings, self.samples, spp)?;
        Ok(self.add_gpu(spp)?)
    }

    fn display(&mut self, out: &mut [u32]) -> tracer::Result<()> {
        Ok(self.display_gpu(out)?)
    }

    fn film(&mut self) -> tracer::Result<Film> {
        let mut film = self.film.clone();
        if self.samples > self.folded_samples {
            self.read_into(&mut film)?;
        }
        Ok(film)
    }

    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(self)
    }

    fn counters(&mut self) -> tracer::Result<PathCounters> {
        let mut counters = self.folded_counters;
        if self.samples > self.folded_samples {
            // The header alone: a film of no rows takes no pixels.
            let b = &self.buffers;
            let mut none = Film::new(b.width, 0);
            let rect = PixelRect::full(b.width, 0);
            counters += self.scene.read_back(&b.accum, &b.accum_readback, FILM_HEADER_BYTES, &mut none, 0, 0, rect)?;
        }
        Ok(counters)
    }
}
