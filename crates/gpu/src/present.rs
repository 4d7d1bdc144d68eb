//! Showing frames on the device: display pixels drawn from a GPU buffer onto a window's
//! surface, never copied to the CPU.
//!
//! Why: the viewer's other path reads each frame's display pixels back (8 MB per 1080p
//! frame, and a wait for the copy) only to upload them again through a CPU framebuffer.
//! Here the display kernel of [`DeviceAccumulation`](crate::accumulation::DeviceAccumulation)
//! writes a [`DeviceFrame`], and a [`Presenter`] draws it (`wgsl/present.wgsl`: one
//! full-target triangle, nearest-neighbour scaling as the CPU path scales previews) into
//! the surface's texture of a [`WindowSurface`].

use crate::{GpuContext, GpuError};
use std::sync::Arc;

/// A frame of display pixels on the device: `width × height` words 0x00RRGGBB
/// (sRGB-encoded, row-major), the layout of [`tracer::film::Film::display_pixels`].
///
/// Cloning shares the buffer. The accumulation that made it does not write into it again
/// while a clone is alive, so a window may keep its frame to redraw it.
#[derive(Clone)]
pub struct DeviceFrame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    pub(crate) pixels: Arc<wgpu::Buffer>,
}

impl DeviceFrame {
    /// A frame holding `pixels` (one word per pixel of `width × height`), uploaded: for
    /// frames that were made on the CPU.
    pub fn upload(ctx: &GpuContext, width: u32, height: u32, pixels: &[u32]) -> Result<Self, GpuError> {
        if pixels.len() as u64 != width as u64 * height as u64 {
            return Err(GpuError::Shader(format!("{} display pixels for a {width}×{height} frame", pixels.len())));
        }
        let buffer = frame_buffer(ctx, pixels.len() as u64)?;
        ctx.queue.write_buffer(&buffer, 0, bytemuck::cast_slice(pixels));
        Ok(Self { width, height, pixels: Arc::new(buffer) })
    }

    /// Whether no clone of this frame is held elsewhere (the accumulation may write it).
    pub(crate) fn is_free(&self) -> bool {
        Arc::strong_count(&self.pixels) == 1
    }
}

/// A buffer for `pixels` display words (at least one word: wgpu binds no empty buffer).
pub(crate) fn frame_buffer(ctx: &GpuContext, pixels: u64) -> Result<wgpu::Buffer, GpuError> {
    let bytes = pixels.max(1) * 4;
    crate::backend::check_size("a frame's display pixels", bytes, &ctx.limits)?;
    Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("display frame"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

/// The draw of a [`DeviceFrame`] onto targets of one texture format.
pub struct Presenter {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    decode_srgb: bool,
}

impl Presenter {
    /// Compiles the draw for targets of `format` (a colour format a render pass can write).
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            visibility: wgpu::ShaderStages::FRAGMENT,
            ..crate::backend::buffer_entry(binding, ty)
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("spt present"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("spt present"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("spt present"),
            source: wgpu::ShaderSource::Wgsl(include_str!("wgsl/present.wgsl").into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("spt present"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("pt_present_vertex"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("pt_present_fragment"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("spt present params"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(format!("the present pipeline for {format:?} does not compile: {e}")));
        }
        Ok(Self { pipeline, layout, params, decode_srgb: format.is_srgb() })
    }

    /// Draws `frame` over the whole of `target` (`width × height`), scaled by nearest
    /// neighbour, and submits it.
    pub fn draw(&self, ctx: &GpuContext, frame: &DeviceFrame, target: &wgpu::TextureView, width: u32, height: u32) {
        let params = [frame.width, frame.height, width.max(1), height.max(1), u32::from(self.decode_srgb), 0, 0, 0];
        ctx.queue.write_buffer(&self.params, 0, bytemuck::cast_slice(&params));
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("spt present"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: frame.pixels.as_entire_binding() },
            ],
        });
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("spt present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if frame.width > 0 && frame.height > 0 {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.draw(0..3, 0..1);
            }
        }
        ctx.queue.submit([encoder.finish()]);
    }
}

/// Makes the window's surface again (after the surface was lost).
type MakeSurface = Box<dyn Fn() -> Result<wgpu::Surface<'static>, GpuError> + Send + Sync>;

/// A window's surface configured for a device, and the draw of frames onto it.
///
/// Configure it (make, resize, present) from one thread only, the one that submits the
/// device's work: wgpu configures a surface only while no other thread submits.
pub struct WindowSurface {
    ctx: GpuContext,
    surface: wgpu::Surface<'static>,
    make_surface: MakeSurface,
    config: wgpu::SurfaceConfiguration,
    presenter: Presenter,
}

/// What [`WindowSurface::present`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presented {
    /// The frame is on screen.
    Shown,
    /// The window cannot show it now (minimised, a timeout, a surface still outdated
    /// after configuring it again): present it again later.
    Skipped,
}

impl WindowSurface {
    /// A surface on `window` (e.g. an `Arc` of a winit window) for `ctx`'s device, sized
    /// `width × height`. Fails where the context cannot present (opened with
    /// [`GpuContext::from_parts`], or an adapter that cannot present to this window, as a
    /// headless one).
    pub fn new<W: wgpu::WindowHandle + wgpu::rwh::HasDisplayHandle + Clone + 'static>(
        ctx: &GpuContext,
        window: W,
        width: u32,
        height: u32,
    ) -> Result<Self, GpuError> {
        let (instance, adapter) = ctx.adapter.clone().ok_or_else(|| {
            GpuError::Unsupported("presenting from a device opened elsewhere (GpuContext::from_parts)".into())
        })?;
        let make_surface: MakeSurface = Box::new(move || {
            instance
                .create_surface(window.clone())
                .map_err(|e| GpuError::Device(format!("cannot make a window surface: {e}")))
        });
        let surface = make_surface()?;
        if !adapter.is_surface_supported(&surface) {
            return Err(GpuError::Unsupported(format!("presenting to this window from {}", ctx.info.name)));
        }
        let caps = surface.get_capabilities(&adapter);
        // A format that stores the display words' bytes as they are (no sRGB encoding by
        // the target) where there is one: the shader then does no conversion.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| matches!(f, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm))
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| GpuError::Unsupported(format!("presenting to this window from {}", ctx.info.name)))?;
        // Mailbox shows the newest frame without waiting for the display's refresh, so
        // the render thread that presents goes on refining; then Immediate (it may tear);
        // FIFO, which every surface has, waits for the refresh.
        let present_mode = [wgpu::PresentMode::Mailbox, wgpu::PresentMode::Immediate]
            .into_iter()
            .find(|m| caps.present_modes.contains(m))
            .unwrap_or(wgpu::PresentMode::Fifo);
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: width.max(1),
            height: height.max(1),
            present_mode,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: Vec::new(),
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        configure(ctx, &surface, &config)?;
        let presenter = Presenter::new(ctx, format)?;
        Ok(Self { ctx: ctx.clone(), surface, make_surface, config, presenter })
    }

    /// The surface's texture format and present mode, for messages.
    pub fn describe(&self) -> String {
        format!("{:?}, {:?}", self.config.format, self.config.present_mode)
    }

    /// Follows the window to `width × height`.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), GpuError> {
        let (width, height) = (width.max(1), height.max(1));
        if (width, height) != (self.config.width, self.config.height) {
            self.config.width = width;
            self.config.height = height;
            configure(&self.ctx, &self.surface, &self.config)?;
        }
        Ok(())
    }

    /// Draws `frame` over the whole window and presents it. An outdated surface is
    /// configured again and a lost one made again, then tried once more; a window that
    /// cannot show a frame now (minimised, a timeout, a surface that cannot be configured
    /// or made again yet) is [`Presented::Skipped`].
    pub fn present(&mut self, frame: &DeviceFrame) -> Result<Presented, GpuError> {
        let mut retried = false;
        let texture = loop {
            match self.surface.get_current_texture() {
                wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => break t,
                wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                    return Ok(Presented::Skipped);
                }
                // Failing to configure or make it now (a window in the middle of a change,
                // minimised to nothing) is a frame skipped, not an error: later presents try again.
                wgpu::CurrentSurfaceTexture::Outdated if !retried => {
                    if configure(&self.ctx, &self.surface, &self.config).is_err() {
                        return Ok(Presented::Skipped);
                    }
                }
                wgpu::CurrentSurfaceTexture::Lost if !retried => {
                    match (self.make_surface)() {
                        Ok(surface) => self.surface = surface,
                        Err(_) => return Ok(Presented::Skipped),
                    }
                    if configure(&self.ctx, &self.surface, &self.config).is_err() {
                        return Ok(Presented::Skipped);
                    }
                }
                wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                    return Ok(Presented::Skipped);
                }
                wgpu::CurrentSurfaceTexture::Validation => {
                    return Err(GpuError::Device("the window surface reported a validation error".into()));
                }
            }
            retried = true;
        };
        let view = texture.texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.presenter.draw(&self.ctx, frame, &view, self.config.width, self.config.height);
        self.ctx.queue.present(texture);
        Ok(Presented::Shown)
    }
}

/// Configures `surface` with `config`, its validation errors returned (not panicked on).
fn configure(ctx: &GpuContext, surface: &wgpu::Surface, config: &wgpu::SurfaceConfiguration) -> Result<(), GpuError> {
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    surface.configure(&ctx.device, config);
    match pollster::block_on(scope.pop()) {
        Some(e) => Err(GpuError::Device(format!("cannot configure the window surface: {e}"))),
        None => Ok(()),
    }
}
