//! Wide BVHs collapsed from a binary [`Bvh`] and traversed with SIMD: [`Bvh4`] (4 children
//! per node, SSE — part of every x86_64 CPU) and [`Bvh8`] (8 children, AVX2 where the CPU
//! has it, detected at run time, so that a plain `cargo build --release` uses the machine
//! it runs on); [`BvhWide`] is the structure both are made of.
//!
//! * Nodes: each [`WideNode`] holds the boxes of up to `W` children in
//!   structure-of-arrays form, so that one ray is tested against all of them at once (a
//!   scalar loop with the same semantics where the SIMD kernel is unavailable).
//! * Collapse: the children of a wide node are found greedily — starting from a binary
//!   node's two children, the interior child with the largest surface area is replaced by
//!   its own two children until there are `W` or only leaves are left.
//! * Leaves: sibling leaves of at most `W` triangles together become one leaf where an
//!   SAH that counts one `W`-wide triangle test per leaf says so. A leaf's triangles are stored in
//!   structure-of-arrays form and tested `W` at a time (the watertight test; four at a
//!   time for Möller–Trumbore) with the operations of
//!   [`intersect_triangle`](crate::intersect_triangle), lane by lane, so hits are
//!   bit-identical to it.
//! * Traversal is ordered: the children a ray enters are visited nearest first, the
//!   others are pushed with their entry distance and culled on pop against the closest
//!   hit so far.
//!
//! The module is split by concern: [`WideNode`] and its layout in `node`, the collapse
//! from a binary tree in `collapse`, the ray kernels (the portable one and the leaf
//! kernels' contract) in `kernel` with the SSE kernel in `sse` and the AVX one in `avx`,
//! and the ordered traversal in `traverse`.

#[cfg(target_arch = "x86_64")]
mod avx;
mod choice;
mod collapse;
mod kernel;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod node;
mod packet;
#[cfg(target_arch = "x86_64")]
mod sse;
#[cfg(test)]
mod tests;
mod traverse;

pub use choice::{BvhWidth, WideBvh};
pub use node::{Bvh4Node, Bvh8Node, WideNode};
pub use packet::PACKET;

use crate::{BuildConfig, BuildError, Bvh, TriangleTest};
use glam::Vec3;

/// The widest node of any [`BvhWide`].
const MAX_WIDTH: usize = 8;

/// Entries of the traversal stack: a wide node pushes at most `W − 1` children and the
/// binary trees our builders make are at most 62 levels deep, so a path holds at most 62
/// wide nodes; [`BvhWide::from_bvh`] checks the bound.
const STACK_DEPTH: usize = (MAX_WIDTH - 1) * 64;

/// Figures describing a built [`BvhWide`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WideStats {
    /// Wide nodes.
    pub nodes: usize,
    /// Leaf child slots: the source tree's leaves, some merged (see [`Bvh4::from_bvh`]).
    pub leaves: usize,
    /// Levels including the leaf level (a root whose children are all leaves gives 2).
    pub depth: usize,
    /// Σ_nodes C_t·A/A_root + Σ_leaves C_i·n·A/A_root with the source tree's cost
    /// constants: one traversal step per wide node, as for obvhs's CWBVH, and one test per
    /// triangle (although a leaf's triangles are tested several at a time).
    pub sah_cost: f32,
}

/// A BVH over triangles with up to `W` children per node, collapsed from a binary [`Bvh`].
#[derive(Clone, Debug)]
pub struct BvhWide<const W: usize> {
    nodes: Vec<WideNode<W>>,
    /// The triangles leaf by leaf in structure of arrays: a leaf of n triangles starting
    /// at triangle `first` holds v0.x × n, v0.y × n, …, v2.z × n from float 9·first; seven
    /// floats of padding at the end let 8-wide loads run past the last leaf. Vertices,
    /// not edges, so that the watertight test sees each shared vertex bit for bit.
    soa: Vec<f32>,
    prim_ids: Vec<u32>,
    /// Each triangle's plane in f64 by primitive id (`collapse::plane`), from which
    /// `traverse::refine` recomputes closest hits' t; empty in trees of
    /// `collapse::PLANE_TABLE_MAX` primitives or more, which recompute it from the hit
    /// leaf's vertices.
    planes: Vec<[f64; 4]>,
    costs: (f32, f32),
    test: TriangleTest,
    /// Recompute every closest hit's t in f64 ([`BvhWide::with_exact_t`], the default).
    exact_t: bool,
}

/// A 4-wide BVH: SSE box and triangle tests (x86_64 baseline).
pub type Bvh4 = BvhWide<4>;

/// An 8-wide BVH: AVX box and watertight triangle tests where the CPU has AVX2 (detected
/// at run time); elsewhere the portable kernel, slower than [`Bvh4`]'s.
pub type Bvh8 = BvhWide<8>;

/// True if [`Bvh8`]'s AVX kernel runs here (the CPU has AVX2 and [`crate::isa::limit_to`]
/// did not rule it out): where it does not, [`Bvh4`] is faster.
pub fn wide8_accelerated() -> bool {
    cfg!(target_arch = "x86_64") && crate::isa::active() >= crate::isa::Isa::Avx2
}

impl<const W: usize> BvhWide<W> {
    /// Builds a binary [`Bvh`] with `config` and collapses it; rejects non-finite
    /// coordinates. An empty input gives a tree that nothing hits.
    pub fn build(triangles: &[[Vec3; 3]], config: BuildConfig) -> Result<Self, BuildError> {
        let bvh = Bvh::build_topology(triangles, config)?;
        let ids = bvh.prim_ids();
        Ok(Self::collapse(&bvh, |i| {
            // The leaves are filled in leaf order, a gather from the input order: start
            // loading a triangle a few ahead.
            crate::builders::prefetch(triangles, ids, i);
            triangles[ids[i] as usize]
        }))
    }

    /// The triangle test this tree runs ([`TriangleTest::Watertight`] by default).
    pub fn triangle_test(&self) -> TriangleTest {
        self.test
    }

    /// Selects the triangle test.
    pub fn with_triangle_test(mut self, test: TriangleTest) -> Self {
        self.test = test;
        self
    }

    /// With `true` (the default), every closest hit's t is recomputed in f64 from the hit
    /// triangle's plane: correctly rounded (within 6·10⁻⁸ relative) except where the ray is
    /// parallel to the plane. The f32 tests' own t (`false`) is off by about ε·R/D
    /// relative, R the coordinates' magnitude around the origin and D the origin's distance
    /// to the plane: beyond 10⁻⁶ for about one hit in 10⁴–10⁵ of the ray sets (grazing
    /// hits, hits near the origin beside large triangles, slivers), up to 2.6·10⁻⁴ on
    /// Sponza's slivers. The refinement adds 4.9 % to the traversal instructions of the
    /// Cornell box's ray sets, 1.6 % to the bunny's and 0.6 % to Sponza's, and 1.8 % to a
    /// Cornell box render's (docs/figures.md, thirty-fifth session). `false` also frees the
    /// table of planes ([`BuildConfig::exact_t`] `false` does not build it); turned on
    /// again, the tree refines from the hit leaf's vertices.
    pub fn with_exact_t(mut self, exact: bool) -> Self {
        self.exact_t = exact;
        if !exact {
            self.planes = Vec::new();
        }
        self
    }

    /// The tree without its table of planes, refining t from the hit leaf's vertices as a
    /// tree of `collapse::PLANE_TABLE_MAX` primitives or more does: for the tests of both.
    #[cfg(test)]
    pub(super) fn without_plane_table(mut self) -> Self {
        self.planes = Vec::new();
        self
    }

    /// Whether the tree keeps a table of its triangles' planes (`collapse::PLANE_TABLE_MAX`).
    #[cfg(test)]
    pub(super) fn has_plane_table(&self) -> bool {
        !self.planes.is_empty()
    }

    /// The wide nodes (root first).
    pub fn nodes(&self) -> &[WideNode<W>] {
        &self.nodes
    }

    /// For each triangle in leaf order, its index in the input.
    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    /// Node count, leaf count, depth and SAH cost.
    pub fn stats(&self) -> WideStats {
        let mut s = WideStats { nodes: self.nodes.len(), ..Default::default() };
        let Some(root) = self.nodes.first() else {
            return s;
        };
        let root_area = root.bounds().surface_area().max(f32::MIN_POSITIVE) as f64;
        let (c_t, c_i) = (self.costs.0 as f64, self.costs.1 as f64);
        let mut cost = 0.0f64;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            s.depth = s.depth.max(depth);
            cost += c_t * n.bounds().surface_area() as f64 / root_area;
            for slot in 0..W {
                let b = n.child_bounds(slot);
                if b.is_empty() {
                    continue;
                }
                if n.count[slot] > 0 {
                    s.leaves += 1;
                    s.depth = s.depth.max(depth + 1);
                    cost += c_i * n.count[slot] as f64 * b.surface_area() as f64 / root_area;
                } else {
                    stack.push((n.child[slot] as usize, depth + 1));
                }
            }
        }
        s.sah_cost = cost as f32;
        s
    }
}
