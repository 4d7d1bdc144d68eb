//! The GPU backend: the tracer's integrator as a wgpu compute kernel.
//!
//! * [`context`]: adapter and device selection (honours `WGPU_BACKEND`, runs on Mesa's
//!   lavapipe where no GPU exists), with errors that say what to do;
//! * [`materials`]: WGSL for the material parameter structs, their packing and the
//!   per-model `eval`/`pdf`/`sample` dispatch, generated from the `brdf` crate's
//!   parameter definitions (`ModelDef`) for exactly the models a scene uses;
//! * [`kernel`]: the path-tracing kernel's WGSL — structs and constants generated from
//!   the Rust definitions, the rest one hand-written file per Rust file it mirrors;
//! * [`backend`]: [`GpuBackend`], the tracer's [`tracer::Backend`] on the GPU, and
//!   [`GpuScene`], a scene prepared on the device;
//! * [`accumulation`]: a viewer's frame-by-frame refinement with the statistics kept on
//!   the device and only display pixels read back — or none: [`present`] draws its
//!   frames onto a window's surface from the device.
//!
//! Citations: "the thesis", "the lecture" and the papers named in comments are listed in `docs/references.md`.

pub mod accumulation;
pub mod backend;
pub mod context;
pub mod kernel;
pub mod materials;
pub mod present;
pub mod wavefront;
pub mod wide;

pub use backend::{GpuBackend, GpuScene};
pub use context::{GpuContext, require_gpu};

/// What can go wrong on the GPU path.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter (GPU or software Vulkan) could be found.
    #[error(
        "no GPU adapter found ({0}); install a GPU driver or Mesa's software Vulkan (mesa-vulkan-drivers), or use --backend cpu"
    )]
    NoAdapter(String),
    /// The device could not be created.
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    /// A buffer the scene needs exceeds a device limit.
    #[error("the scene needs {needed} bytes for {what}, but the device's {limit_name} is {limit} bytes")]
    Limit {
        /// What the buffer holds.
        what: &'static str,
        /// Bytes needed.
        needed: u64,
        /// The limit's wgpu name.
        limit_name: &'static str,
        /// The limit's value.
        limit: u64,
    },
    /// The scene uses something the GPU kernel does not support.
    #[error("the GPU backend does not support {0}")]
    Unsupported(String),
    /// WGSL failed to compile or the device reported an error.
    #[error("GPU error: {0}")]
    Shader(String),
}
