//! Ray accelerators over triangle soups.
//!
//! * [`Accelerator`]: the trait the integrator calls — closest hit and any-hit occlusion;
//! * [`Bvh`]: a bounding volume hierarchy built by full-sweep SAH, binned SAH, midpoint
//!   or the thesis's hybrid ([`SplitMethod`]), flattened depth-first into small POD
//!   nodes ([`BvhNode`]) that a GPU can traverse unchanged;
//! * [`Bvh4`], [`Bvh8`]: 4- and 8-wide BVHs collapsed from a [`Bvh`], a node's child
//!   boxes tested at once with SIMD (SSE; AVX2 detected at run time) — [`WideBvh`] picks
//!   the width for the CPU it runs on;
//! * [`isa`]: the vector instruction set the kernels use (detected, or capped for
//!   measurements);
//! * [`TwoLevel`]: the thesis's two-level structure — a top-level BVH over instances
//!   (with transforms) of per-object accelerators;
//! * [`BoxBvh`]: a BVH over the boxes of primitives the crate does not know (analytic
//!   shapes), intersected through a callback;
//! * [`BruteForce`]: tests every triangle; the oracle the tests compare against;
//! * `ObvhsBvh2`, `ObvhsCwBvh`: the obvhs crate's BVH2 and compressed wide BVH8 behind
//!   the same trait, so that benchmarks compare them with ours in the same run (cargo
//!   feature `obvhs`, on by default);
//! * [`make_ray_sets`]: primary, diffuse-bounce and shadow ray sets for benchmarks.
//!
//! This crate knows boxes, rays and triangles, nothing of materials.
//!
//! Citations: "the thesis", "the lecture" and the papers named in comments are listed in `docs/references.md`.

mod aabb;
mod boxes;
mod brute;
mod build;
mod builders;
mod instance;
pub mod isa;
#[cfg(feature = "obvhs")]
mod obvhs_adapter;
mod ray;
mod raysets;
#[cfg(test)]
mod test_util;
mod triangle;
mod wide;

pub use aabb::Aabb;
pub use boxes::BoxBvh;
pub use brute::BruteForce;
pub use build::{BuildConfig, Bvh, BvhNode, BvhStats, SplitMethod};
pub use instance::{Instance, TwoLevel};
#[cfg(feature = "obvhs")]
pub use obvhs_adapter::{ObvhsBvh2, ObvhsCwBvh, ObvhsQuality};
pub use ray::{Hit, Ray};
pub use raysets::{RaySets, make_ray_sets, make_ray_sets_from};
pub use triangle::{Triangle, TriangleTest, WatertightRay, intersect_triangle, intersect_triangle_watertight};
pub use wide::{
    Bvh4, Bvh4Node, Bvh8, Bvh8Node, BvhWide, BvhWidth, PACKET, WideBvh, WideNode, WideStats, wide8_accelerated,
};

use glam::Vec3;

/// Why an accelerator could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// A triangle has a NaN or infinite coordinate.
    #[error("triangle {index} has a non-finite vertex coordinate {vertex:?}")]
    NonFinite {
        /// Index of the triangle in the input.
        index: usize,
        /// The offending vertex.
        vertex: [f32; 3],
    },
    /// An instance of a two-level structure is unusable.
    #[error("instance {index}: {reason}")]
    BadInstance {
        /// Index of the instance.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// The structure would be deeper than its traversal supports.
    #[error("the tree would be {} deep, more than the {limit} its traversal supports", depth.map_or("too".to_string(), |d| d.to_string()))]
    TooDeep {
        /// The depth, where known.
        depth: Option<usize>,
        /// The supported depth.
        limit: usize,
    },
    /// More triangles than a 32-bit index can address.
    #[error("{0} triangles exceed the 2^32 − 1 an accelerator can index")]
    TooManyTriangles(usize),
}

/// Finds ray–scene intersections; implemented by every acceleration structure.
pub trait Accelerator: Send + Sync {
    /// The closest hit with t in (`ray.t_min`, `ray.t_max`), if any.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;
    /// True if anything is hit with t in (`ray.t_min`, `ray.t_max`): shadow rays stop at
    /// the first hit found.
    fn occluded(&self, ray: &Ray) -> bool;
    /// The bounds of everything in the structure.
    fn bounds(&self) -> Aabb;
    /// Closest hit, counting nodes visited and triangles tested into `stats`; structures
    /// that do not count just call [`Accelerator::intersect`].
    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        let _ = stats;
        self.intersect(ray)
    }
    /// [`Accelerator::occluded`], counting as [`Accelerator::intersect_counted`] does: a
    /// shadow ray's walk stops at the first hit and may visit the children in another
    /// order, so its counts differ from the closest hit's. Structures that do not count
    /// just call [`Accelerator::occluded`].
    fn occluded_counted(&self, ray: &Ray, stats: &mut RayStats) -> bool {
        let _ = stats;
        self.occluded(ray)
    }
}

/// Per-ray traversal work, summed over rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayStats {
    /// Rays traced.
    pub rays: u64,
    /// Nodes visited (interior and leaf).
    pub nodes_visited: u64,
    /// Ray–triangle tests.
    pub triangles_tested: u64,
}

/// Checks every vertex for NaN/∞ and the count for u32 indexing.
pub(crate) fn validate(triangles: &[[Vec3; 3]]) -> Result<(), BuildError> {
    if triangles.len() >= u32::MAX as usize {
        return Err(BuildError::TooManyTriangles(triangles.len()));
    }
    // 0·x is 0 for finite x and NaN for an infinity or a NaN, so one sum per chunk tells
    // whether every coordinate in it is finite (a branch per vertex cost more than
    // building the primitives' boxes).
    let finite = |ts: &[[Vec3; 3]]| {
        ts.iter().fold(Vec3::ZERO, |acc, t| acc + (t[0] * 0.0 + t[1] * 0.0 + t[2] * 0.0)) == Vec3::ZERO
    };
    let all_finite = if triangles.len() > 64 * 1024 {
        use rayon::prelude::*;
        triangles.par_chunks(16 * 1024).all(finite)
    } else {
        finite(triangles)
    };
    if all_finite {
        return Ok(());
    }
    for (index, tri) in triangles.iter().enumerate() {
        if let Some(v) = tri.iter().find(|v| !v.is_finite()) {
            return Err(BuildError::NonFinite { index, vertex: v.to_array() });
        }
    }
    unreachable!("a chunk with a non-finite coordinate has a triangle with one")
}
