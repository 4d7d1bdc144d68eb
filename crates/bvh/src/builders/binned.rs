//! Binned SAH split search (Wald 2007, "On fast Construction of SAH-based Bounding
//! Volume Hierarchies"): centroids are binned along each axis and the SAH is evaluated
//! only at the bin boundaries. All three axes are binned in one pass over the
//! primitives, split across threads for large nodes.

use super::{Prim, Split, centroid_bounds, partition, split_cost};
use crate::Aabb;
use crate::build::BuildConfig;
use glam::Vec3;
use rayon::prelude::*;

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: usize,
}

const EMPTY_BIN: Bin = Bin { bounds: Aabb::EMPTY, count: 0 };

/// Nodes above this many primitives bin in parallel chunks of this size.
const PARALLEL_CHUNK: usize = 16 * 1024;

/// Bin counts up to which a node's bins live on the stack: most nodes are small, and a
/// heap allocation per node cost more than their binning.
const STACK_BINS: usize = 16;

/// Bins `ids` along all three axes into `bins[axis * nb + b]` (3·nb empty bins).
fn bin(prims: &[Prim], ids: &[u32], min: Vec3, scale: Vec3, nb: usize, bins: &mut [Bin]) {
    for &i in ids {
        let p = &prims[i as usize];
        let b = ((p.centre - min) * scale).as_uvec3().min(glam::UVec3::splat(nb as u32 - 1));
        for axis in 0..3 {
            let bin = &mut bins[axis * nb + b[axis] as usize];
            bin.bounds = bin.bounds.union(p.bounds);
            bin.count += 1;
        }
    }
}

/// Partitions `ids` at the best binned-SAH plane, or returns `None` when the centroids
/// span no extent.
pub(crate) fn split(prims: &[Prim], ids: &mut [u32], bounds: &Aabb, config: &BuildConfig) -> Option<Split> {
    let cb = centroid_bounds(prims, ids);
    let extent = cb.extent();
    let parent_area = bounds.surface_area();
    // Small nodes get fewer bins (at least four, at most one per primitive): a node's
    // fixed cost is its 3·(nb − 1) candidate planes, and most nodes are small.
    let nb = config.bins.min(ids.len().max(4));
    // Axes without extent get scale 0: everything lands in bin 0 and no plane is valid.
    let scale = Vec3::select(extent.cmpgt(Vec3::ZERO), Vec3::splat(nb as f32) / extent, Vec3::ZERO);
    let mut stack_bins = [EMPTY_BIN; 3 * STACK_BINS];
    let heap_bins: Vec<Bin>;
    let bins: &[Bin] = if ids.len() > 2 * PARALLEL_CHUNK {
        heap_bins = ids
            .par_chunks(PARALLEL_CHUNK)
            .map(|c| {
                let mut bins = vec![EMPTY_BIN; 3 * nb];
                bin(prims, c, cb.min, scale, nb, &mut bins);
                bins
            })
            .reduce_with(|mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    x.bounds = x.bounds.union(y.bounds);
                    x.count += y.count;
                }
                a
            })?;
        &heap_bins
    } else if nb <= STACK_BINS {
        bin(prims, ids, cb.min, scale, nb, &mut stack_bins[..3 * nb]);
        &stack_bins[..3 * nb]
    } else {
        let mut bins = vec![EMPTY_BIN; 3 * nb];
        bin(prims, ids, cb.min, scale, nb, &mut bins);
        heap_bins = bins;
        &heap_bins
    };
    let mut best: Option<(usize, usize, f32)> = None;
    let mut stack_right = [(0.0f32, 0usize); STACK_BINS];
    let mut heap_right: Vec<(f32, usize)>;
    let right: &mut [(f32, usize)] = if nb <= STACK_BINS {
        &mut stack_right[..nb]
    } else {
        heap_right = vec![(0.0f32, 0usize); nb];
        &mut heap_right
    };
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let bins = &bins[axis * nb..(axis + 1) * nb];
        // Sweep from the right, then from the left, evaluating the nb − 1 planes.
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for i in (1..nb).rev() {
            acc = acc.union(bins[i].bounds);
            cnt += bins[i].count;
            right[i] = (acc.surface_area(), cnt);
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for i in 0..nb - 1 {
            acc = acc.union(bins[i].bounds);
            cnt += bins[i].count;
            if cnt == 0 || right[i + 1].1 == 0 {
                continue;
            }
            let cost = split_cost(config, parent_area, (acc.surface_area(), cnt), right[i + 1]);
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, i + 1, cost));
            }
        }
    }
    let (axis, boundary, cost) = best?;
    let (min, s) = (cb.min[axis], scale[axis]);
    // Partition with the same bin arithmetic as the binning, so the split is exact.
    let mid = partition(ids, |i| {
        ((((prims[i as usize].centre[axis] - min) * s) as u32).min(nb as u32 - 1) as usize) < boundary
    });
    // The children's bounds are their bins' (no pass over the primitives).
    let side =
        |range: std::ops::Range<usize>| bins[axis * nb..][range].iter().fold(Aabb::EMPTY, |b, x| b.union(x.bounds));
    Some(Split { mid, cost, left: side(0..boundary), right: side(boundary..nb) })
}
