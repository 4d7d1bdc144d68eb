//! Adapter and device selection.

use crate::GpuError;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

/// A compiled kernel: what [`KernelCache`] keeps.
pub(crate) type CompiledKernel = (wgpu::ComputePipeline, wgpu::ShaderModule);

/// The kernels compiled on one device, by WGSL source and bind group layout entries.
///
/// Why: the driver compiles a path kernel in tens of milliseconds on a GPU but in tens of
/// seconds on lavapipe, and preparing a second scene with the same materials and
/// features (another camera, another image size, the same scene again, a copy of the
/// context with other limits) needs the same kernel. Pipelines made from a layout with
/// the same entries are compatible with the new scene's bind groups: wgpu deduplicates
/// identical bind group layouts on a device.
#[derive(Clone, Default)]
pub(crate) struct KernelCache(Arc<Mutex<HashMap<KernelKey, CompiledKernel>>>);

/// The source and the layout entries a kernel was compiled with.
type KernelKey = (String, Vec<wgpu::BindGroupLayoutEntry>);

impl KernelCache {
    /// The kernel compiled from `source` with `entries`, if it was.
    pub(crate) fn get(&self, source: &str, entries: &[wgpu::BindGroupLayoutEntry]) -> Option<CompiledKernel> {
        let kernels = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        // (Keys are compared in full: the source is a few hundred kilobytes at most.)
        kernels.get(&(source.to_string(), entries.to_vec())).cloned()
    }

    /// Keeps a kernel compiled without error.
    pub(crate) fn insert(&self, source: &str, entries: &[wgpu::BindGroupLayoutEntry], kernel: CompiledKernel) {
        let mut kernels = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        kernels.insert((source.to_string(), entries.to_vec()), kernel);
    }

    /// How many kernels are kept.
    pub(crate) fn len(&self) -> usize {
        self.0.lock().unwrap_or_else(PoisonError::into_inner).len()
    }
}

/// An open device and its queue. Cloning shares the device, the queue and the kernels
/// compiled on it (lower [`GpuContext::limits`] on a clone to test what a smaller device
/// would do without compiling again).
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
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(Self { device, queue, info: adapter.get_info(), limits, kernels: KernelCache::default() })
    }

    /// How many kernels have been compiled on the device and kept for reuse (each distinct
    /// WGSL source and layout once).
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
