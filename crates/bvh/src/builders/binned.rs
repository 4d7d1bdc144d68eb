//! Binned SAH split search (Wald 2007, "On fast Construction of SAH-based Bounding
//! Volume Hierarchies"): centroids are binned along each axis and the SAH is evaluated
//! only at the bin boundaries.

use super::{Prim, centroid_bounds, partition, split_cost};
use crate::Aabb;
use crate::build::BuildConfig;

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: usize,
}

/// Partitions `ids` at the best binned-SAH plane; returns (left count, cost), or `None`
/// when the centroids span no extent.
pub(crate) fn split(prims: &[Prim], ids: &mut [u32], bounds: &Aabb, config: &BuildConfig) -> Option<(usize, f32)> {
    let cb = centroid_bounds(prims, ids);
    let extent = cb.extent();
    let parent_area = bounds.surface_area();
    let nb = config.bins;
    let mut best: Option<(usize, f32, f32)> = None;
    let mut bins = vec![Bin { bounds: Aabb::EMPTY, count: 0 }; nb];
    let mut right = vec![(0.0f32, 0usize); nb];
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        bins.fill(Bin { bounds: Aabb::EMPTY, count: 0 });
        let scale = nb as f32 / extent[axis];
        let bin_of = |c: f32| (((c - cb.min[axis]) * scale) as usize).min(nb - 1);
        for &i in ids.iter() {
            let p = &prims[i as usize];
            let b = &mut bins[bin_of(p.centre[axis])];
            b.bounds = b.bounds.union(p.bounds);
            b.count += 1;
        }
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
                best = Some((axis, (i + 1) as f32, cost));
            }
        }
    }
    let (axis, boundary, cost) = best?;
    let scale = nb as f32 / extent[axis];
    let min = cb.min[axis];
    // Partition with the same bin arithmetic as the binning, so the split is exact.
    let mid =
        partition(ids, |i| ((((prims[i as usize].centre[axis] - min) * scale) as usize).min(nb - 1) as f32) < boundary);
    Some((mid, cost))
}
