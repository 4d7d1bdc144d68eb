//! Adapter and device selection.

use crate::GpuError;

/// An open device and its queue.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter is (name, backend, driver), for messages and reports.
    pub info: wgpu::AdapterInfo,
    /// The device's limits.
    pub limits: wgpu::Limits,
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
        Ok(Self { device, queue, info: adapter.get_info(), limits })
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
