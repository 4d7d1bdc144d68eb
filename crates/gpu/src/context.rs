//! Adapter and device selection.

use crate::GpuError;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

/// A compiled kernel: what [`KernelCache`] keeps.
pub(crate) struct CompiledKernel {
    /// The pipeline of the entry point it was compiled for.
    pub(crate) pipeline: wgpu::ComputePipeline,
    /// Its module (the kernel's other entry points, e.g. the wavefront's stages).
    pub(crate) module: wgpu::ShaderModule,
}

/// The kernels compiled on one device, by WGSL source and bind group layout entries.
///
/// Why: a GPU's driver compiles a path kernel in about a second (H100: 0.9–1.2 s, 8–12 ms
/// from its own disk cache; `docs/gpu/figures-h100.txt`), lavapipe in 20–90 s, and
/// preparing a second scene with the same materials and features (another camera or
/// image size, the same scene again, a clone of the context with other limits) needs the
/// same kernel. Pipelines made from a layout with the same entries are compatible with
/// the new scene's bind groups: wgpu deduplicates identical bind group layouts on a
/// device.
///
/// Two ways a kernel is found again: the cache itself holds the [`KEPT_KERNELS`] most
/// recently used (lavapipe's compiled code is large: a device holding every kernel of the
/// equivalence tests grew to 24 GB and was killed), and any kernel a prepared scene still
/// holds is found too, however long ago it was compiled — it costs no memory that the
/// scene does not already hold (the cache keeps only a weak reference to it).
#[derive(Clone, Default)]
pub(crate) struct KernelCache(Arc<Mutex<Kept>>);

/// How many compiled kernels a device keeps beyond those its scenes hold.
pub const KEPT_KERNELS: usize = 2;

/// The kernels' slots, and strong references to the most recently used.
#[derive(Default)]
struct Kept {
    slots: HashMap<KernelKey, KernelSlot>,
    recent: std::collections::VecDeque<Arc<CompiledKernel>>,
    /// How many kernels were compiled (what the cache did not spare).
    compiled: usize,
}

impl Kept {
    /// Keeps `kernel` as the most recently used (once), dropping the oldest beyond
    /// [`KEPT_KERNELS`].
    fn touch(&mut self, kernel: &Arc<CompiledKernel>) {
        self.recent.retain(|k| !Arc::ptr_eq(k, kernel));
        self.recent.push_back(Arc::clone(kernel));
        while self.recent.len() > KEPT_KERNELS {
            self.recent.pop_front();
        }
    }
}

/// The source and the layout entries a kernel was compiled with.
type KernelKey = (String, Vec<wgpu::BindGroupLayoutEntry>);

/// One kernel's entry: a weak reference to it once it compiled without error (alive while
/// the cache's recent list or a scene holds it). Locked while it compiles, so that a
/// second thread asking for the same kernel waits for it instead of compiling too.
type KernelSlot = Arc<Mutex<std::sync::Weak<CompiledKernel>>>;

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl KernelCache {
    /// The kernel compiled from `source` with `entries`: a kept or still held one, or
    /// `compile`'s (kept if it succeeds; an error is returned and nothing kept). Holding
    /// the returned kernel keeps it findable.
    pub(crate) fn get_or_compile(
        &self,
        source: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
        compile: impl FnOnce() -> Result<CompiledKernel, GpuError>,
    ) -> Result<Arc<CompiledKernel>, GpuError> {
        let slot = {
            let mut kept = lock(&self.0);
            let key = (source.to_string(), entries.to_vec());
            // Forget kernels nobody holds (a slot locked or shared is being compiled or
            // waited for: kept).
            kept.slots.retain(|k, slot| {
                *k == key || Arc::strong_count(slot) > 1 || slot.try_lock().map_or(true, |w| w.strong_count() > 0)
            });
            Arc::clone(kept.slots.entry(key).or_default())
        };
        let mut weak = lock(&slot);
        if let Some(kernel) = weak.upgrade() {
            lock(&self.0).touch(&kernel);
            return Ok(kernel);
        }
        let kernel = Arc::new(compile()?);
        *weak = Arc::downgrade(&kernel);
        let mut kept = lock(&self.0);
        kept.touch(&kernel);
        kept.compiled += 1;
        Ok(kernel)
    }

    /// How many kernels were compiled.
    pub(crate) fn compiled(&self) -> usize {
        lock(&self.0).compiled
    }

    /// How many compiled kernels can be found again (kept or held).
    pub(crate) fn len(&self) -> usize {
        let slots: Vec<KernelSlot> = lock(&self.0).slots.values().cloned().collect();
        slots.iter().filter(|slot| lock(slot).strong_count() > 0).count()
    }
}

/// An open device and its queue. Cloning shares the device, the queue and the kernels
/// compiled on it (lower [`GpuContext::limits`] on a clone to test what a smaller device
/// would do without compiling again; a clone given another `device` would share kernels
/// that are not its own — open it with [`GpuContext::from_parts`] instead).
#[derive(Clone)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter is (name, backend, driver), for messages and reports.
    pub info: wgpu::AdapterInfo,
    /// The device's limits.
    pub limits: wgpu::Limits,
    /// The kernels compiled on the device (shared by clones).
    pub(crate) kernels: KernelCache,
    /// The instance and adapter the device was opened from, for window surfaces
    /// ([`crate::present::WindowSurface`]); `None` for [`GpuContext::from_parts`].
    pub(crate) adapter: Option<(wgpu::Instance, wgpu::Adapter)>,
}

impl GpuContext {
    /// Opens the default adapter without a window. `WGPU_BACKEND` (e.g. `vulkan`) and
    /// `WGPU_ADAPTER_NAME` select among several; on a machine without a GPU, Mesa's
    /// lavapipe (software Vulkan) is found like any other adapter.
    pub fn new() -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::from_env().unwrap_or(wgpu::PowerPreference::HighPerformance),
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("spt"),
            // f64 in shaders where the adapter has it: implicit surfaces' root finder needs it.
            required_features: adapter.features() & wgpu::Features::SHADER_F64,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let info = adapter.get_info();
        Ok(Self { adapter: Some((instance, adapter)), ..Self::from_parts(device, queue, info, limits) })
    }

    /// A context around a device opened elsewhere, with no kernels compiled yet. It cannot
    /// make window surfaces ([`crate::present::WindowSurface`] needs the adapter; contexts
    /// from [`GpuContext::new`] can).
    pub fn from_parts(device: wgpu::Device, queue: wgpu::Queue, info: wgpu::AdapterInfo, limits: wgpu::Limits) -> Self {
        Self { device, queue, info, limits, kernels: KernelCache::default(), adapter: None }
    }

    /// Whether kernels may use f64 (wgpu's `SHADER_F64`, requested by [`GpuContext::new`]
    /// where the adapter offers it): implicit surfaces need it.
    pub fn shader_f64(&self) -> bool {
        self.device.features().contains(wgpu::Features::SHADER_F64)
    }

    /// How many compiled kernels the device can reuse (each distinct WGSL source and layout
    /// once: the [`KEPT_KERNELS`] most recently used and those prepared scenes hold).
    pub fn compiled_kernels(&self) -> usize {
        self.kernels.len()
    }

    /// How many kernels were compiled on the device and its clones (each compile the cache
    /// did not spare; a failed one not counted): what a session's first renders cost.
    pub fn kernels_compiled(&self) -> usize {
        self.kernels.compiled()
    }
}

/// For tests: the context, or `None` with a printed message where no adapter exists —
/// unless the environment variable `SPT_REQUIRE_GPU` is set (CI sets it), in which case
/// a missing adapter is a panic, so that GPU tests can never silently not run.
pub fn require_gpu() -> Option<GpuContext> {
    match GpuContext::new() {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var_os("SPT_REQUIRE_GPU").is_some() => {
            panic!("SPT_REQUIRE_GPU is set but no GPU is usable: {e}")
        }
        Err(e) => {
            eprintln!("skipping a GPU test: {e}");
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trivial kernel, different per `n` (lavapipe compiles it in milliseconds).
    fn tiny(ctx: &GpuContext, n: u32) -> Result<Arc<CompiledKernel>, GpuError> {
        let source = format!("@compute @workgroup_size(1) fn main() {{ _ = {n}u; }}");
        let layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor::default());
        ctx.kernels.get_or_compile(&source, &[], || crate::backend::compile_kernel(ctx, &layout, &source, "main"))
    }

    /// The cache finds the most recently used kernels and any kernel still held, and
    /// forgets the others.
    #[test]
    fn held_and_recent_kernels_are_found_again() {
        let Some(ctx) = require_gpu() else { return };
        let held = tiny(&ctx, 1).unwrap();
        for n in 2..=4 {
            tiny(&ctx, n).unwrap();
        }
        assert_eq!(ctx.kernels_compiled(), 4);
        // Held (though the oldest): found, not compiled again.
        assert!(Arc::ptr_eq(&tiny(&ctx, 1).unwrap(), &held));
        assert_eq!(ctx.kernels_compiled(), 4);
        // The most recent before it: kept.
        tiny(&ctx, 4).unwrap();
        assert_eq!(ctx.kernels_compiled(), 4);
        // Neither held nor among the two most recent: compiled again.
        tiny(&ctx, 2).unwrap();
        assert_eq!(ctx.kernels_compiled(), 5);
        // Findable now: 1 (held; it is not among the recent, 4 and 2), 4 and 2.
        assert_eq!(ctx.compiled_kernels(), 3);
        drop(held);
        assert_eq!(ctx.compiled_kernels(), 2);
        // A clone shares the kernels and the count.
        let clone = ctx.clone();
        tiny(&clone, 2).unwrap();
        assert_eq!(ctx.kernels_compiled(), 5);
    }
}
