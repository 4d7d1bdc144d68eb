//! BVH builders. Each produces the same depth-first node layout through [`Output`]:
//! an interior node's left child follows it, its right child is at `index`; a leaf's
//! primitives are appended to `order` as the leaf is made.
//!
//! * [`binned`]: binned SAH (Wald 2007), subtrees built in parallel with rayon;
//! * [`sweep`]: full-sweep SAH (the thesis's Algorithm 8.2) made O(n log n) by sorting
//!   once per axis and partitioning the sorted lists stably (Wald & Havran 2006);
//! * [`midpoint`]: the midpoint of the longest centroid axis (the thesis's fast fallback);
//!
//! the hybrid (midpoint above a face count, sweep SAH below) combines the last two.

pub(crate) mod binned;
pub(crate) mod midpoint;
pub(crate) mod presplit;
pub(crate) mod sweep;

use crate::Aabb;
use crate::build::{BuildConfig, BvhNode, SplitMethod};
use glam::Vec3A;

/// Deepest tree the builders make: traversal uses a fixed 64-entry stack.
pub(crate) const MAX_DEPTH: usize = 62;

/// Subtrees above this many primitives are built in parallel.
const PARALLEL_THRESHOLD: usize = 4096;

/// A primitive as the builders see it: its box in SIMD registers (32 bytes, aligned), so
/// that binning unions boxes and finds centroids with one instruction per corner.
#[derive(Clone, Copy)]
pub(crate) struct Prim {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Prim {
    pub fn new(bounds: Aabb) -> Self {
        Self { min: bounds.min.into(), max: bounds.max.into() }
    }

    #[inline(always)]
    pub fn bounds(&self) -> Aabb {
        Aabb { min: self.min.into(), max: self.max.into() }
    }

    /// The box's centre, bit for bit [`Aabb::centre`].
    #[inline(always)]
    pub fn centre(&self) -> Vec3A {
        0.5 * (self.min + self.max)
    }
}

/// How many items ahead the builders' loops over ids prefetch: their reads of
/// `items[ids[j]]` are random once the ids no longer follow the input order.
const PREFETCH_AHEAD: usize = 16;

/// Starts loading `items[ids[j + PREFETCH_AHEAD]]`, if there is one (both ends: a 32- or
/// 36-byte item may straddle two cache lines).
#[inline(always)]
pub(crate) fn prefetch<T>(items: &[T], ids: &[u32], j: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(&i) = ids.get(j + PREFETCH_AHEAD) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let p = items.as_ptr().wrapping_add(i as usize).cast::<i8>();
        // SAFETY: SSE is baseline on x86_64, and a prefetch never faults (`wrapping_add`
        // forms the address without dereferencing it).
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
            _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(size_of::<T>() - 1));
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (items, ids, j);
}

/// Nodes and the leaf order of primitives, appended depth-first.
#[derive(Default)]
pub(crate) struct Output {
    pub nodes: Vec<BvhNode>,
    pub order: Vec<u32>,
}

impl Output {
    /// Appends a leaf over `ids`; returns its node index.
    pub fn leaf(&mut self, bounds: &Aabb, ids: impl ExactSizeIterator<Item = u32>) -> usize {
        let index = self.nodes.len();
        self.nodes.push(BvhNode {
            min: bounds.min.to_array(),
            index: self.order.len() as u32,
            max: bounds.max.to_array(),
            count: ids.len() as u32,
        });
        self.order.extend(ids);
        index
    }

    /// Appends an interior node whose right child is still unknown.
    pub fn interior(&mut self, bounds: &Aabb) -> usize {
        let index = self.nodes.len();
        self.nodes.push(BvhNode { min: bounds.min.to_array(), index: 0, max: bounds.max.to_array(), count: 0 });
        index
    }
}

/// Folds `f` over `ids`, in parallel chunks for large sets.
fn fold_boxes(ids: &[u32], f: impl Fn(Aabb, u32) -> Aabb + Sync) -> Aabb {
    const CHUNK: usize = 16 * 1024;
    if ids.len() > 2 * CHUNK {
        use rayon::prelude::*;
        ids.par_chunks(CHUNK).map(|c| c.iter().fold(Aabb::EMPTY, |b, &i| f(b, i))).reduce(|| Aabb::EMPTY, Aabb::union)
    } else {
        ids.iter().fold(Aabb::EMPTY, |b, &i| f(b, i))
    }
}

/// The bounds of a set of primitives.
pub(crate) fn bounds_of(prims: &[Prim], ids: &[u32]) -> Aabb {
    fold_boxes(ids, |b, i| b.union(prims[i as usize].bounds()))
}

/// The bounds of a set of primitive centroids.
pub(crate) fn centroid_bounds(prims: &[Prim], ids: &[u32]) -> Aabb {
    fold_boxes(ids, |b, i| b.grow(prims[i as usize].centre().into()))
}

/// A node's split: `ids[..mid]` go left; the SAH cost, both children's bounds and, where
/// the split found them on the way, their centroid bounds.
pub(crate) struct Split {
    pub mid: usize,
    pub cost: f32,
    pub left: Aabb,
    pub right: Aabb,
    pub centroids: Option<(Aabb, Aabb)>,
}

/// The number of primitive tests a set of `n` costs in the SAH: `n` rounded up to whole
/// blocks of [`BuildConfig::sah_block`].
#[inline]
fn tests(config: &BuildConfig, n: usize) -> f32 {
    // A power of two (see `Bvh::build_topology`): round up with a mask, not a division.
    let mask = config.sah_block - 1;
    ((n + mask) & !mask) as f32
}

/// A split's area-weighted test count A_l·n_l + A_r·n_r for children of (area, count)
/// `left` and `right`, the counts in whole blocks ([`BuildConfig::sah_block`]).
#[inline]
pub(crate) fn area_weighted(config: &BuildConfig, left: (f32, usize), right: (f32, usize)) -> f32 {
    left.0 * tests(config, left.1) + right.0 * tests(config, right.1)
}

/// SAH cost of splitting a node of area `parent_area` into children whose
/// [`area_weighted`] test count is `weighted` (MacDonald & Booth 1990):
/// C_t + C_i·(A_l·n_l + A_r·n_r)/A.
#[inline]
pub(crate) fn split_cost(config: &BuildConfig, parent_area: f32, weighted: f32) -> f32 {
    config.traversal_cost + config.intersection_cost * weighted / parent_area.max(f32::MIN_POSITIVE)
}

/// Whether a node of `n` primitives must, may or must not become a leaf before any split
/// is considered.
pub(crate) fn forced_leaf(config: &BuildConfig, n: usize, depth: usize) -> bool {
    n <= 1 || depth >= MAX_DEPTH || (!config.leaf_by_sah && n <= config.max_leaf_size)
}

/// After the best split was found: leaf if it does not pay (only when allowed).
pub(crate) fn sah_prefers_leaf(config: &BuildConfig, n: usize, split_cost: f32) -> bool {
    config.leaf_by_sah && n <= config.max_leaf_size && split_cost >= config.intersection_cost * tests(config, n)
}

/// In-place partition; returns the number of ids for which `pred` holds.
pub(crate) fn partition(ids: &mut [u32], pred: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    for j in 0..ids.len() {
        if pred(ids[j]) {
            ids.swap(i, j);
            i += 1;
        }
    }
    i
}

/// How a node is built: a leaf, or split at `ids[..mid]` with each side's bounds and,
/// where the split found them, its centroids' bounds.
enum Choice {
    Leaf,
    Split { mid: usize, bounds: (Aabb, Aabb), centroids: (Option<Aabb>, Option<Aabb>) },
}

/// Chooses how to build the node over `ids` (bounds `bounds`, centroid bounds
/// `centroids` where known) with the configured split method, partitioning `ids` for a
/// split. Not for the sweep SAH, which builds whole subtrees at once.
fn choose(
    prims: &[Prim],
    ids: &mut [u32],
    bounds: &Aabb,
    centroids: Option<Aabb>,
    config: &BuildConfig,
    depth: usize,
) -> Choice {
    let n = ids.len();
    if forced_leaf(config, n, depth) {
        return Choice::Leaf;
    }
    let split = match config.method {
        SplitMethod::BinnedSah => binned::split(prims, ids, bounds, centroids, config),
        _ => midpoint::split(prims, ids, bounds, config),
    };
    // Halving by position, for the cases below.
    let halve = |ids: &[u32]| {
        let mid = n / 2;
        Choice::Split {
            mid,
            bounds: (bounds_of(prims, &ids[..mid]), bounds_of(prims, &ids[mid..])),
            centroids: (None, None),
        }
    };
    match split {
        // A plane that leaves one side empty (centroids closer together than the float
        // spacing at the midpoint) would recurse on the same set: halve by position.
        Some(s) if !sah_prefers_leaf(config, n, s.cost) => {
            if s.mid == 0 || s.mid == n {
                halve(ids)
            } else {
                Choice::Split { mid: s.mid, bounds: (s.left, s.right), centroids: s.centroids.unzip() }
            }
        }
        Some(_) => Choice::Leaf,
        // No split separates the centroids: halve by position to bound leaf sizes.
        None if n > config.max_leaf_size => halve(ids),
        None => Choice::Leaf,
    }
}

/// True if the subtree over `n` primitives is built by the sweep SAH.
fn by_sweep(config: &BuildConfig, n: usize) -> bool {
    match config.method {
        SplitMethod::SweepSah => true,
        SplitMethod::Hybrid { threshold } => n <= threshold,
        _ => false,
    }
}

/// Builds the subtree over `ids`, whose bounds are `bounds` (and whose centroids' bounds
/// are `centroids`, where known), with the configured method, on this thread, appending
/// it to `out`; returns its root's index.
fn build(
    prims: &[Prim],
    ids: &mut [u32],
    bounds: Aabb,
    centroids: Option<Aabb>,
    config: &BuildConfig,
    out: &mut Output,
    depth: usize,
) -> usize {
    if by_sweep(config, ids.len()) {
        return sweep::build(prims, ids, config, out, depth);
    }
    match choose(prims, ids, &bounds, centroids, config, depth) {
        Choice::Leaf => out.leaf(&bounds, ids.iter().copied()),
        Choice::Split { mid, bounds: (lb, rb), centroids: (lc, rc) } => {
            let index = out.interior(&bounds);
            let (left, right) = ids.split_at_mut(mid);
            build(prims, left, lb, lc, config, out, depth + 1);
            let right_index = build(prims, right, rb, rc, config, out, depth + 1);
            out.nodes[index].index = right_index as u32;
            index
        }
    }
}

/// A tree built in pieces, depth-first: subtrees built in parallel each append to their
/// own [`Output`], and the pieces are copied together once at the end. (Appending each
/// subtree to its parent's output copied a node once per parallel level above it: 15 %
/// of a one-thread build of 1.1M triangles, docs/figures.md.)
struct Pieces {
    outputs: Vec<Output>,
    /// (piece, piece): the first piece holds an interior node alone, whose right child is
    /// the second piece's first node.
    links: Vec<(usize, usize)>,
}

impl Pieces {
    fn one(out: Output) -> Self {
        Self { outputs: vec![out], links: Vec::new() }
    }

    /// An interior node of bounds `bounds` over the subtrees `left` and `right`.
    fn interior(bounds: &Aabb, left: Pieces, right: Pieces) -> Self {
        let mut node = Output::default();
        node.interior(bounds);
        let right_first = 1 + left.outputs.len();
        let mut links = Vec::with_capacity(1 + left.links.len() + right.links.len());
        links.push((0, right_first));
        links.extend(left.links.iter().map(|&(a, b)| (a + 1, b + 1)));
        links.extend(right.links.iter().map(|&(a, b)| (a + right_first, b + right_first)));
        let mut outputs = Vec::with_capacity(right_first + right.outputs.len());
        outputs.push(node);
        outputs.extend(left.outputs);
        outputs.extend(right.outputs);
        Self { outputs, links }
    }

    /// The pieces as one output: each copied once to its place (in parallel), its indices
    /// moved by its offsets, and the links set.
    fn concat(self) -> Output {
        use rayon::prelude::*;
        if self.outputs.len() == 1 {
            return self.outputs.into_iter().next().expect("one piece");
        }
        let mut node_at = Vec::with_capacity(self.outputs.len());
        let (mut nodes_total, mut order_total) = (0, 0);
        for o in &self.outputs {
            node_at.push((nodes_total, order_total));
            nodes_total += o.nodes.len();
            order_total += o.order.len();
        }
        let mut nodes: Vec<BvhNode> = bytemuck::zeroed_vec(nodes_total);
        let mut order: Vec<u32> = vec![0; order_total];
        // One pair of destination slices per piece.
        let mut slices = Vec::with_capacity(self.outputs.len());
        let (mut node_rest, mut order_rest) = (&mut nodes[..], &mut order[..]);
        for o in &self.outputs {
            let (n, rest) = node_rest.split_at_mut(o.nodes.len());
            let (r, order_tail) = order_rest.split_at_mut(o.order.len());
            slices.push((n, r));
            (node_rest, order_rest) = (rest, order_tail);
        }
        self.outputs.par_iter().zip(slices).zip(&node_at).for_each(|((o, (n, r)), &(node_offset, order_offset))| {
            for (dst, src) in n.iter_mut().zip(&o.nodes) {
                *dst = *src;
                dst.index += if src.count > 0 { order_offset as u32 } else { node_offset as u32 };
            }
            r.copy_from_slice(&o.order);
        });
        for &(node, right) in &self.links {
            nodes[node_at[node].0].index = node_at[right].0 as u32;
        }
        Output { nodes, order }
    }
}

/// [`build`], with the two subtrees of nodes above [`PARALLEL_THRESHOLD`] primitives built
/// in parallel.
fn build_parallel(
    prims: &[Prim],
    ids: &mut [u32],
    bounds: Aabb,
    centroids: Option<Aabb>,
    config: &BuildConfig,
    depth: usize,
) -> Pieces {
    if ids.len() <= PARALLEL_THRESHOLD || by_sweep(config, ids.len()) {
        // A binary tree over n primitives has at most 2n − 1 nodes: reserved, so that the
        // piece never grows by copying (untouched pages cost nothing).
        let mut out = Output { nodes: Vec::with_capacity(2 * ids.len()), order: Vec::with_capacity(ids.len()) };
        build(prims, ids, bounds, centroids, config, &mut out, depth);
        return Pieces::one(out);
    }
    match choose(prims, ids, &bounds, centroids, config, depth) {
        Choice::Leaf => {
            let mut out = Output::default();
            out.leaf(&bounds, ids.iter().copied());
            Pieces::one(out)
        }
        Choice::Split { mid, bounds: (lb, rb), centroids: (lc, rc) } => {
            let (left, right) = ids.split_at_mut(mid);
            let (l, r) = rayon::join(
                || build_parallel(prims, left, lb, lc, config, depth + 1),
                || build_parallel(prims, right, rb, rc, config, depth + 1),
            );
            Pieces::interior(&bounds, l, r)
        }
    }
}

/// Builds the tree over `ids` (all of `prims`' primitives, or some) with the configured
/// method, subtrees in parallel (the output's `order` is the leaf order).
pub(crate) fn build_tree(prims: &[Prim], ids: &mut [u32], config: &BuildConfig) -> Output {
    if ids.is_empty() {
        return Output::default();
    }
    let bounds = bounds_of(prims, ids);
    build_parallel(prims, ids, bounds, None, config, 1).concat()
}

/// Builds a tree over arbitrary boxes (e.g. object instances for a top-level BVH) with
/// the configured method; the result's `order` maps leaf slots to box indices.
pub(crate) fn build_over_boxes(boxes: &[Aabb], config: &BuildConfig) -> Output {
    let prims: Vec<Prim> = boxes.iter().map(|b| Prim::new(*b)).collect();
    let mut ids: Vec<u32> = (0..prims.len() as u32).collect();
    build_tree(&prims, &mut ids, config)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SplitMethod;
    use glam::Vec3;

    #[test]
    fn a_tree_built_in_pieces_equals_one_built_on_one_thread() {
        // 30K random boxes: the parallel build's pieces (subtrees above 4096 primitives
        // split, each below built alone) copied together must give the sequential build's
        // nodes and leaf order exactly, every right-child link and leaf offset moved.
        let prims = crate::test_util::prims(11, 30_000, 100.0);
        for method in [SplitMethod::BinnedSah, SplitMethod::Midpoint] {
            let config = BuildConfig { method, ..Default::default() };
            let all: Vec<u32> = (0..prims.len() as u32).collect();
            let bounds = bounds_of(&prims, &all);
            let mut whole = Output::default();
            build(&prims, &mut all.clone(), bounds, None, &config, &mut whole, 1);
            let pieces = build_parallel(&prims, &mut all.clone(), bounds, None, &config, 1);
            assert!(pieces.outputs.len() > 8, "{method:?}: {} pieces", pieces.outputs.len());
            let joined = pieces.concat();
            assert_eq!(joined.order, whole.order, "{method:?}");
            assert!(joined.nodes == whole.nodes, "{method:?}: the nodes differ");
        }
    }

    #[test]
    fn nearly_coincident_centroids_still_split_into_small_leaves() {
        // Centroids 1 ulp apart at 1e4: the midpoint plane equals the minimum, so a
        // naive partition puts everything on one side at every level.
        let base = 1.0e4f32;
        let prims: Vec<Prim> = (0..4000)
            .map(|i| {
                let c = Vec3::new(if i % 2 == 0 { base } else { f32::from_bits(base.to_bits() + 1) }, 0.0, 0.0);
                Prim::new(Aabb { min: c - 1.0, max: c + 1.0 })
            })
            .collect();
        let config =
            BuildConfig { method: SplitMethod::Midpoint, max_leaf_size: 1, leaf_by_sah: false, ..Default::default() };
        let mut ids: Vec<u32> = (0..prims.len() as u32).collect();
        let mut out = Output::default();
        let bounds = bounds_of(&prims, &ids);
        build(&prims, &mut ids, bounds, None, &config, &mut out, 1);
        let largest = out.nodes.iter().map(|n| n.count).max().unwrap();
        assert!(largest <= 1, "a leaf of {largest} primitives");
        assert!(out.nodes.iter().all(|n| n.count > 0 || n.index as usize > 0), "no empty subtrees");
    }
}
