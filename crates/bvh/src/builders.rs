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

    /// Appends another output's nodes and order, fixing up its indices.
    fn append(&mut self, other: Output) {
        let (node_offset, order_offset) = (self.nodes.len() as u32, self.order.len() as u32);
        self.nodes.extend(other.nodes.into_iter().map(|mut n| {
            n.index += if n.count > 0 { order_offset } else { node_offset };
            n
        }));
        self.order.extend(other.order);
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

/// Builds the subtree over `ids`, whose bounds are `bounds` (and whose centroids' bounds
/// are `centroids`, where known), with the configured method.
pub(crate) fn build(
    prims: &[Prim],
    ids: &mut [u32],
    bounds: Aabb,
    centroids: Option<Aabb>,
    config: &BuildConfig,
    out: &mut Output,
    depth: usize,
) -> usize {
    let n = ids.len();
    match config.method {
        SplitMethod::SweepSah => return sweep::build(prims, ids, config, out, depth),
        SplitMethod::Hybrid { threshold } if n <= threshold => return sweep::build(prims, ids, config, out, depth),
        _ => {}
    }
    if forced_leaf(config, n, depth) {
        return out.leaf(&bounds, ids.iter().copied());
    }
    let split = match config.method {
        SplitMethod::BinnedSah => binned::split(prims, ids, &bounds, centroids, config),
        _ => midpoint::split(prims, ids, &bounds, config),
    };
    // Halving by position, for the cases below.
    let halve = |ids: &[u32]| {
        let mid = n / 2;
        (mid, bounds_of(prims, &ids[..mid]), bounds_of(prims, &ids[mid..]), (None, None))
    };
    let (mid, left_bounds, right_bounds, (left_centroids, right_centroids)) = match split {
        // A plane that leaves one side empty (centroids closer together than the float
        // spacing at the midpoint) would recurse on the same set: halve by position.
        Some(s) if !sah_prefers_leaf(config, n, s.cost) => {
            if s.mid == 0 || s.mid == n {
                halve(ids)
            } else {
                (s.mid, s.left, s.right, s.centroids.unzip())
            }
        }
        Some(_) => return out.leaf(&bounds, ids.iter().copied()),
        // No split separates the centroids: halve by position to bound leaf sizes.
        None if n > config.max_leaf_size => halve(ids),
        None => return out.leaf(&bounds, ids.iter().copied()),
    };
    let index = out.interior(&bounds);
    let (left, right) = ids.split_at_mut(mid);
    if n > PARALLEL_THRESHOLD {
        let (l, r) = rayon::join(
            || {
                let mut o = Output::default();
                build(prims, left, left_bounds, left_centroids, config, &mut o, depth + 1);
                o
            },
            || {
                let mut o = Output::default();
                build(prims, right, right_bounds, right_centroids, config, &mut o, depth + 1);
                o
            },
        );
        out.append(l);
        let right_index = out.nodes.len();
        out.append(r);
        out.nodes[index].index = right_index as u32;
    } else {
        build(prims, left, left_bounds, left_centroids, config, out, depth + 1);
        let right_index = build(prims, right, right_bounds, right_centroids, config, out, depth + 1);
        out.nodes[index].index = right_index as u32;
    }
    index
}

/// Builds a tree over arbitrary boxes (e.g. object instances for a top-level BVH) with
/// the configured method; the result's `order` maps leaf slots to box indices.
pub(crate) fn build_over_boxes(boxes: &[Aabb], config: &BuildConfig) -> Output {
    let prims: Vec<Prim> = boxes.iter().map(|b| Prim::new(*b)).collect();
    let mut ids: Vec<u32> = (0..prims.len() as u32).collect();
    let mut out = Output::default();
    if !ids.is_empty() {
        let bounds = bounds_of(&prims, &ids);
        build(&prims, &mut ids, bounds, None, config, &mut out, 1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SplitMethod;
    use glam::Vec3;

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
