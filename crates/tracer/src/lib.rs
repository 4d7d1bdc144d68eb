//! The path tracer: scenes, loaders, the integrator, the film and image output, behind a
//! backend-agnostic renderer API.
//!
//! Data flows one way: a [`Scene`] (flat, `bytemuck`-friendly arrays of vertices,
//! triangles and per-triangle material ids, plus materials, lights and a camera) →
//! an accelerator from the `bvh` crate → the [`integrator`] → a [`Film`] → images.
//! A [`Backend`] prepares a scene its own way ([`PreparedScene`]), which then renders
//! passes of samples into a film; [`CpuBackend`] runs an [`Integrator`] with rayon,
//! tile-parallel and bit-identical for a given seed whatever the thread count.
//!
//! Citations: "the thesis", "the lecture" and the papers named in comments are listed in `docs/references.md`.

pub mod accumulation;
pub mod camera;
pub mod cpu;
pub mod envmap;
pub mod film;
pub mod geometry;
pub mod gltf_scene;
pub mod integrator;
pub mod lights;
pub mod material;
pub mod mesh;
pub mod mtl;
pub mod obj;
pub mod output;
pub mod punctual;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod scene_file;
pub mod scenes;
pub mod shading;
pub mod spec;
pub mod texture;

pub use accumulation::{Accumulation, FilmAccumulation};
pub use camera::Camera;
pub use cpu::{CpuBackend, CpuScene};
pub use film::Film;
pub use geometry::{Geometry, SceneShape, ShapeKind};
pub use integrator::{
    AmbientOcclusion, AtlasGi, AtlasSettings, Bdpt, CausticPathTracer, DirectLighting, Integrator, PathTracer, SeamFix,
    Whitted,
};
pub use material::Material;
pub use punctual::PunctualLight;
pub use render::{Backend, LightSampler, PreparedScene, RenderSettings, RenderStats, SceneOptions, render};
pub use scene::{Environment, Scene};
pub use spectral::SpectralMode;

use std::path::PathBuf;

/// Everything that can go wrong between a scene file and an image.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A scene file is malformed.
    #[error("{path}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The 1-based line, where known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A scene file is malformed at a known line and column.
    #[error("{path}:{line}:{column}: {message}")]
    ParseAt {
        /// The file.
        path: PathBuf,
        /// The 1-based line.
        line: usize,
        /// The 1-based column (in characters).
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A texture cannot be read or used.
    #[error("material '{material}': texture '{texture}': {message}")]
    Texture {
        /// The material naming it.
        material: String,
        /// The file (or, inside a glTF file, `images[i]`).
        texture: String,
        /// What is wrong.
        message: String,
    },
    /// A material or light colour is invalid.
    #[error("material '{material}': {source}")]
    Material {
        /// The material's name.
        material: String,
        /// Why.
        source: spectral::SpectralError,
    },
    /// A material parameter is unknown or out of range.
    #[error(transparent)]
    Param(#[from] brdf::params::ParamError),
    /// The geometry cannot be put in an accelerator.
    #[error("geometry: {0}")]
    Geometry(#[from] bvh::BuildError),
    /// A render setting is out of range.
    #[error("invalid setting: {0}")]
    Setting(String),
    /// A request outside what the chosen backend can do, found before any work.
    #[error("the {backend} backend does not support {feature}: {way_out}")]
    Unsupported {
        /// The backend's name.
        backend: String,
        /// What it cannot do.
        feature: String,
        /// What the user can do instead.
        way_out: String,
    },
    /// A render backend (the GPU, say) failed or cannot render this scene; the message
    /// says why and what to do.
    #[error("{0}")]
    Backend(String),
    /// An image could not be encoded.
    #[error("{path}: {message}")]
    Image {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// A malformed file, where no line can be named (a binary or re-serialised file, or a
    /// problem of the whole file).
    pub(crate) fn parse(path: &std::path::Path, message: String) -> Self {
        Self::Parse { path: path.to_path_buf(), line: None, message }
    }
}

/// A caught panic's message (its `&str` or `String` payload; empty otherwise), for the
/// loaders that turn a dependency's panic into an error naming the file.
pub(crate) fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_default()
}
