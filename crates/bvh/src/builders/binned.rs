//! Binned SAH split search (Wald 2007, "On fast Construction of SAH-based Bounding
//! Volume Hierarchies"): centroids are binned along each axis and the SAH is evaluated
//! only at the bin boundaries. All three axes are binned in one pass over the
//! primitives, split across threads for large nodes.

use super::{Prim, centroid_bounds, partition, split_cost};
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

/// Bins `ids` along all three axes: `bins[axis * nb + b]`.
fn bin(prims: &[Prim], ids: &[u32], min: Vec3, scale: Vec3, nb: usize) -> Vec<Bin> {
    let mut bins = vec![EMPTY_BIN; 3 * nb];
    for &i in ids {
        let p = &prims[i as usize];
        let b = ((p.centre - min) * scale).as_uvec3().min(glam::UVec3::splat(nb as u32 - 1));
        for axis in 0..3 {
            let bin = &mut bins[axis * nb + b[axis] as usize];
            bin.bounds = bin.bounds.union(p.bounds);
            bin.count += 1;
        }
    }
    bins
}

/// Partitions `ids` at the best binned-SAH plane; returns (left count, cost), or `None`
/// when the centroids span no extent.
pub(crate) fn split(prims: &[Prim], ids: &mut [u32], bounds: &Aabb, config: &BuildConfig) -> Option<(usize, f32)> {
    let cb = centroid_bounds(prims, ids);
    let extent = cb.extent();
    let parent_area = bounds.surface_area();
    let nb = config.bins;
    // Axes without extent get scale 0: everything lands in bin 0 and no plane is valid.
    let scale = Vec3::select(extent.cmpgt(Vec3::ZERO), Vec3::splat(nb as f32) / extent, Vec3::ZERO);
    let bins = if ids.len() > 2 * PARALLEL_CHUNK {
        ids.par_chunks(PARALLEL_CHUNK).map(|c| bin(prims, c, cb.min, scale, nb)).reduce_with(|mut a, b| {
            for (x, y) in a.iter_mut().zip(b) {
                x.bounds = x.bounds.union(y.bounds);
                x.count += y.count;
            }
            a
        })?
    } else {
        bin(prims, ids, cb.min, scale, nb)
    };
    let mut best: Option<(usize, usize, f32)> = None;
    let mut right = vec![(0.0f32, 0usize); nb];
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
    Some((mid, cost))
}
