//! Renders that outgrow one machine or one sitting.
//!
//! A render is a set of pixel samples: pixel `(x, y)`, sample index `k`, each with its
//! own random stream keyed by the seed, the pixel and `k`. This crate cuts that set into
//! pieces, runs them anywhere and puts them back together **bit for bit**:
//!
//! * [`ShardSpec`] (`--shard K/N`) picks piece `K` of `N`: a range of sample indices for
//!   every pixel ([`Split::Samples`], the default: equal work per shard), or a band of
//!   image rows with every sample ([`Split::Tiles`]). [`ShardSpec::work`] turns it into
//!   [`Work`]: a pixel region and a sample range.
//! * [`Partial`] is a piece on disk: the film's exact per-pixel sums (count, Σx, Σx² in
//!   fixed point, see [`tracer::film`]) over the region, with a JSON [`Manifest`] (what
//!   was rendered — a hash of the scene's content, every setting that changes a pixel,
//!   the tool's version — and which samples are done). The format is documented in
//!   [`partial`]; files are written to a temporary name and renamed, so a reader never
//!   sees half a file, and carry a SHA-256 of their bytes, so a truncated or corrupted
//!   file is refused with its name.
//! * [`merge()`] checks that the partials belong to one render and cover every pixel's
//!   samples exactly once (naming duplicates, overlaps and what is missing) and adds
//!   them. The film's sums are integers, so the merged film — and the image written
//!   from it — equals the single-machine render's byte for byte.
//! * [`run_work`] renders a piece in passes, stopping before a time budget runs out and
//!   writing checkpoints; a render resumed from its checkpoint equals an uninterrupted
//!   one, again because the sums are exact.

pub mod manifest;
pub mod merge;
pub mod partial;
pub mod plan;
pub mod progressive;

pub use manifest::{Job, Manifest, scene_hash};
pub use merge::{merge, plan_coverage, read_manifests};
pub use partial::Partial;
pub use plan::{ShardSpec, Split, Work};
pub use progressive::{Budget, WorkStats, check_band, run_work};

use std::path::PathBuf;

/// What can go wrong with shards, partials and merges.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// A file is not a partial render, or is damaged (truncated, altered, malformed).
    #[error("{}: not a valid partial render: {reason}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// Partials that belong to different renders, or a partial that does not belong to
    /// the render asked for.
    #[error("{0}")]
    Mismatch(String),
    /// Partials that do not cover the image's samples exactly once.
    #[error("{0}")]
    Coverage(String),
    /// A shard request that cannot be satisfied (`--shard 5/4`, more shards than rows).
    #[error("{0}")]
    Plan(String),
    /// An output that exists and would be overwritten.
    #[error("{}: exists; pass --force to overwrite it", .0.display())]
    Exists(PathBuf),
    /// The renderer failed.
    #[error(transparent)]
    Render(#[from] tracer::Error),
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
