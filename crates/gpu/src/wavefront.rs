//! The path tracer as a wavefront (`wgsl/wavefront.wgsl`; Laine, Karras & Aila 2013,
//! "Megakernels considered harmful"): its stages' pipelines, the paths' state between
//! them, and the order in which a pass dispatches them.
//!
//! One wave is one sample of every pixel of a band: the camera stage starts a path per
//! pixel, then each bounce dispatches extension (closest hits), shading (`pt_path_step`,
//! the megakernel's loop body restated with its shadow ray deferred), shadow rays and a
//! one-invocation kernel that swaps the two queues of live paths and writes the next
//! dispatch's size, read by indirect dispatches (so no bounce waits for the host). Where a
//! depth limit keeps a path within [`CHUNK`] bounces, every bounce is recorded up front;
//! otherwise (a deeper limit, or Russian roulette alone) the bounces go in chunks of
//! [`CHUNK`], the host reading the live count after each. The film stage then adds each
//! pixel's sample to its statistics in the megakernel's order.

use std::sync::Arc;

use crate::GpuError;
use crate::backend::{MAX_BOUNCES, buffer_entry, map_read};
use crate::context::GpuContext;
use crate::kernel::Params;

/// Bytes of one path's state (`PtWfPath` in `wgsl/wavefront.wgsl`, as naga lays it out;
/// `crates/gpu/tests/kernel.rs` checks it).
pub const PATH_BYTES: u64 = 272;

/// Invocations per workgroup of the per-path stages (`PT_WF_GROUP`, which
/// `crates/gpu/tests/kernel.rs` checks).
pub const GROUP: u64 = 64;

/// Bounces dispatched between two reads of the live count when paths are unbounded.
pub const CHUNK: u32 = 16;

/// The most paths one wave holds: its per-slot dispatches stay within the 65 535
/// workgroups a dimension may have, and its state within 1 GiB.
pub fn max_slots(limits: &wgpu::Limits) -> u64 {
    let bytes = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size).min(1 << 30);
    (bytes / PATH_BYTES).min(limits.max_compute_workgroups_per_dimension as u64 * GROUP)
}

/// The bind group layout of the control kernels' group 1 (the indirect dispatch sizes).
pub(crate) fn group_one_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let write = wgpu::BufferBindingType::Storage { read_only: false };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("wavefront dispatch sizes"),
        entries: &[buffer_entry(0, write)],
    })
}

/// Group 0's wavefront bindings: the paths (15) and the queues (16).
pub(crate) fn group_zero_entries() -> [wgpu::BindGroupLayoutEntry; 2] {
    let write = wgpu::BufferBindingType::Storage { read_only: false };
    [buffer_entry(15, write), buffer_entry(16, write)]
}

/// The stages' pipelines (the shading stage is the kernel's main pipeline, compiled first).
pub(crate) struct Stages {
    begin: wgpu::ComputePipeline,
    camera: wgpu::ComputePipeline,
    extend: wgpu::ComputePipeline,
    shadow: wgpu::ComputePipeline,
    next: wgpu::ComputePipeline,
    film: wgpu::ComputePipeline,
    end: wgpu::ComputePipeline,
}

impl Stages {
    /// The stages of `module` (a kernel with `wgsl/wavefront.wgsl`): the per-path ones with
    /// `layout` (group 0), the control ones with `control` (groups 0 and 1).
    pub(crate) fn new(
        ctx: &GpuContext,
        module: &wgpu::ShaderModule,
        layout: &wgpu::PipelineLayout,
        control: &wgpu::PipelineLayout,
    ) -> Result<Arc<Self>, GpuError> {
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = |entry: &str, layout: &wgpu::PipelineLayout| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(layout),
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let stages = Self {
            begin: pipeline("pt_wf_begin", control),
            camera: pipeline("pt_wf_camera", layout),
            extend: pipeline("pt_wf_extend", layout),
            shadow: pipeline("pt_wf_shadow", layout),
            next: pipeline("pt_wf_next", control),
            film: pipeline("pt_wf_film", layout),
            end: pipeline("pt_wf_end", control),
        };
        match pollster::block_on(scope.pop()) {
            None => Ok(Arc::new(stages)),
            Some(e) => Err(GpuError::Shader(format!("the wavefront's stages do not compile: {e}"))),
        }
    }
}

/// The state of one wave of `slots` paths: the paths, the queues with their counts, the
/// indirect dispatch sizes (with their bind group) and a read-back for the live count.
pub(crate) struct Buffers {
    slots: u64,
    pub(crate) paths: wgpu::Buffer,
    pub(crate) control: wgpu::Buffer,
    groups: wgpu::Buffer,
    groups_bind: wgpu::BindGroup,
    readback: wgpu::Buffer,
}

/// Bytes before the queues in the control buffer (`PtWfControl`: sample, cur, two counts).
const CONTROL_HEADER: u64 = 16;

impl Buffers {
    /// Buffers for waves of up to `slots` paths.
    pub(crate) fn new(ctx: &GpuContext, slots: u64, group_one: &wgpu::BindGroupLayout) -> Result<Self, GpuError> {
        let limits = &ctx.limits;
        let slots = slots.max(1);
        if slots > max_slots(limits) {
            return Err(GpuError::Limit {
                what: "one wave of the wavefront's paths (one per pixel of a band, 272 bytes each)",
                needed: slots * PATH_BYTES,
                limit_name: "wave size (max_compute_workgroups_per_dimension × 64 paths, at most 1 GiB)",
                limit: max_slots(limits) * PATH_BYTES,
            });
        }
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        use wgpu::BufferUsages as U;
        let paths = buffer("wavefront paths", slots * PATH_BYTES, U::STORAGE);
        let control = buffer("wavefront queues", CONTROL_HEADER + 8 * slots, U::STORAGE | U::COPY_SRC | U::COPY_DST);
        let groups = buffer("wavefront dispatch sizes", 12, U::STORAGE | U::INDIRECT);
        let readback = buffer("wavefront live count", CONTROL_HEADER, U::MAP_READ | U::COPY_DST);
        let groups_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("wavefront dispatch sizes"),
            layout: group_one,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: groups.as_entire_binding() }],
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(format!("out of GPU memory for a wavefront of {slots} paths: {e}")));
        }
        Ok(Self { slots, paths, control, groups, groups_bind, readback })
    }

    /// The queue being traced and its live count (after a submitted chunk).
    fn live(&self, ctx: &GpuContext) -> Result<u32, GpuError> {
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.copy_buffer_to_buffer(&self.control, 0, &self.readback, 0, Some(CONTROL_HEADER));
        ctx.queue.submit([encoder.finish()]);
        let words: [u32; 4] = {
            let view = map_read(ctx, &self.readback, CONTROL_HEADER, "reading the wavefront's live count")?;
            bytemuck::pod_read_unaligned(&view)
        };
        self.readback.unmap();
        Ok(words[2 + (words[1] & 1) as usize])
    }
}

/// The most bounces a path of `params` can take: its depth limit and specular extension
/// (the shading stage ends it at the next hit), else the backend's cap.
pub fn bounces(params: &Params) -> u32 {
    if params.max_depth > 0 {
        params.max_depth.saturating_add(1).saturating_add(params.specular_extension).min(MAX_BOUNCES)
    } else {
        MAX_BOUNCES
    }
}

/// Records `params.samples` waves of the band of `params` (a path per pixel) into
/// `encoder` and submits them, `shade` being the shading stage and `bind` the kernel's group 0 with
/// `buffers`' paths and queues in it. Where a path may take more than [`CHUNK`] bounces,
/// each wave is submitted in chunks until no path is live (the host waits for each).
pub(crate) fn submit(
    ctx: &GpuContext,
    stages: &Stages,
    shade: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    buffers: &Buffers,
    mut encoder: wgpu::CommandEncoder,
    params: &Params,
) -> Result<wgpu::SubmissionIndex, GpuError> {
    let slots = params.band_rows as u64 * params.width as u64;
    if slots > buffers.slots {
        let held = buffers.slots;
        return Err(GpuError::Shader(format!(
            "a band of {slots} paths for a wave of {held} (an internal sizing error)"
        )));
    }
    let per_slot = slots.div_ceil(GROUP) as u32;
    let bounces = bounces(params);
    encoder.clear_buffer(&buffers.control, 0, Some(CONTROL_HEADER));
    let single = |encoder: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, groups: u32| {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.set_bind_group(1, &buffers.groups_bind, &[]);
        pass.dispatch_workgroups(groups, 1, 1);
    };
    let bounce_chunk = |encoder: &mut wgpu::CommandEncoder, n: u32| {
        for _ in 0..n {
            {
                let mut pass =
                    encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
                pass.set_bind_group(0, bind, &[]);
                for stage in [&stages.extend, shade, &stages.shadow] {
                    pass.set_pipeline(stage);
                    pass.dispatch_workgroups_indirect(&buffers.groups, 0);
                }
            }
            single(encoder, &stages.next, 1);
        }
    };
    for _ in 0..params.samples {
        single(&mut encoder, &stages.begin, 1);
        {
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
            pass.set_pipeline(&stages.camera);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(per_slot, 1, 1);
        }
        if bounces <= CHUNK {
            bounce_chunk(&mut encoder, bounces);
        } else {
            let mut done = 0;
            while done < bounces {
                let n = CHUNK.min(bounces - done);
                bounce_chunk(&mut encoder, n);
                done += n;
                ctx.queue.submit([encoder.finish()]);
                encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                if buffers.live(ctx)? == 0 {
                    break;
                }
            }
        }
        {
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
            pass.set_pipeline(&stages.film);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(per_slot, 1, 1);
        }
        single(&mut encoder, &stages.end, 1);
    }
    Ok(ctx.queue.submit([encoder.finish()]))
}
