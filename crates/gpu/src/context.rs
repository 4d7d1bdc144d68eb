//! Adapter and device selection.

use crate::GpuError;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

/// A compiled kernel: what [`KernelCache`] keeps.
pub(crate) type CompiledKernel = (wgpu::ComputePipeline, wgpu::ShaderModule);

/// The kernels compiled on one device, by WGSL source and bind group layout entries.
///
/// Why: a GPU's driver compiles a path kernel in about a second (H100: 0.9–1.2 s, 8–12 ms
/// from its own disk cache; `docs/gpu/figures-h100.txt`), lavapipe in 20–50 s, and
/// preparing a second scene with the same materials and features (another camera or
/// image size, the same scene again, a clone of the context with other limits) needs the
/// same kernel. Pipelines made from a layout with the same entries are compatible with
/// the new scene's bind groups: wgpu deduplicates identical bind group layouts on a
/// device. Only the [`KEPT_KERNELS`] most recently compiled are kept: lavapipe's compiled
/// code is large (a device keeping every kernel of the equivalence tests grew to 24 GB and
/// was killed), and a scene keeps its own kernels anyway.
#[derive(Clone, Default)]
pub(crate) struct KernelCache(Arc<Mutex<Kept>>);

/// How many compiled kernels a device keeps beyond those its scenes hold.
pub const KEPT_KERNELS: usize = 2;

/// The kept kernels' slots, and their keys oldest first.
#[derive(Default)]
struct Kept {
    slots: HashMap<KernelKey, KernelSlot>,
    order: std::collections::VecDeque<KernelKey>,
}

/// The source and the layout entries a kernel was compiled with.
type KernelKey = (String, Vec<wgpu::BindGroupLayoutEntry>);

/// One kernel's entry: empty until it compiled without error. Locked while it compiles, so
/// that a second thread asking for the same kernel waits for it instead of compiling too.
type KernelSlot = Arc<Mutex<Option<CompiledKernel>>>;

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl KernelCache {
    /// The kernel compiled from `source` with `entries`: the kept one, or `compile`'s
    /// (kept if it succeeds; an error is returned and nothing kept).
    pub(crate) fn get_or_compile(
        &self,
        source: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
        compile: impl FnOnce() -> Result<CompiledKernel, GpuError>,
    ) -> Result<CompiledKernel, GpuError> {
        let slot = {
            let mut kept = lock(&self.0);
            let key = (source.to_string(), entries.to_vec());
            match kept.slots.get(&key) {
                Some(slot) => Arc::clone(slot),
                None => {
                    if kept.order.len() >= KEPT_KERNELS
                        && let Some(oldest) = kept.order.pop_front()
                    {
                        kept.slots.remove(&oldest);
                    }
                    let slot = KernelSlot::default();
                    kept.slots.insert(key.clone(), Arc::clone(&slot));
                    kept.order.push_back(key);
                    slot
                }
            }
        };
        let mut kernel = lock(&slot);
        if let Some(kept) = &*kernel {
            return Ok(kept.clone());
        }
        let compiled = compile()?;
        *kernel = Some(compiled.clone());
        Ok(compiled)
    }

    /// How many kernels are kept.
    pub(crate) fn len(&self) -> usize {
        let slots: Vec<KernelSlot> = lock(&self.0).slots.values().cloned().collect();
        slots.iter().filter(|slot| lock(slot).is_some()).count()
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

    /// How many compiled kernels the device keeps for reuse (each distinct WGSL source and
    /// layout once, the [`KEPT_KERNELS`] most recent).
    pub fn compiled_kernels(&self) -> usize {
        self.kernels.len()
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
