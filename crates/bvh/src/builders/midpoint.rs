//! The midpoint split: halve the longest axis of the centroid bounds — the thesis's
//! fast fallback for large objects (its chapter 8.3). Cheap (O(n) per level, no area
//! evaluations) but blind to where the primitives are.

use super::{Prim, Split, area_weighted, bounds_of, centroid_bounds, partition, split_cost};
use crate::Aabb;
use crate::build::BuildConfig;

/// Partitions `ids` at the centroid-bounds midpoint of the longest axis, or returns `None`
/// when the centroids span no extent.
pub(crate) fn split(prims: &[Prim], ids: &mut [u32], bounds: &Aabb, config: &BuildConfig) -> Option<Split> {
    let cb = centroid_bounds(prims, ids);
    let e = cb.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    if e[axis] <= 0.0 {
        return None;
    }
    let pos = cb.min[axis] + 0.5 * e[axis];
    let mid = partition(ids, |i| prims[i as usize].centre()[axis] < pos);
    let (l, r) = ids.split_at(mid);
    let (left, right) = (bounds_of(prims, l), bounds_of(prims, r));
    let cost = split_cost(
        config,
        bounds.surface_area(),
        area_weighted(config, (left.surface_area(), l.len()), (right.surface_area(), r.len())),
    );
    Some(Split { mid, cost, left, right, centroids: None })
}
