//! Full-sweep SAH: the thesis's Algorithm 8.2 evaluates the SAH at every primitive
//! boundary along each axis after sorting by centroid. Sorting at every node costs
//! O(n log² n); here the primitives are sorted once per axis and the three sorted lists
//! are partitioned stably at each split (Wald & Havran 2006), so the whole build is
//! O(n log n).

use super::{Output, Prim, area_weighted, forced_leaf, sah_prefers_leaf, split_cost};
use crate::Aabb;
use crate::build::BuildConfig;

/// Builds the subtree over `ids` by full-sweep SAH; returns its node index.
pub(crate) fn build(prims: &[Prim], ids: &[u32], config: &BuildConfig, out: &mut Output, depth: usize) -> usize {
    // Work on local indices 0..n so that scratch arrays are sized by the subtree.
    let local: Vec<&Prim> = ids.iter().map(|&i| &prims[i as usize]).collect();
    let n = local.len();
    let mut sorted: [Vec<u32>; 3] = std::array::from_fn(|axis| {
        let mut v: Vec<u32> = (0..n as u32).collect();
        v.sort_by(|&a, &b| {
            local[a as usize].centre()[axis].total_cmp(&local[b as usize].centre()[axis]).then(a.cmp(&b))
        });
        v
    });
    let mut scratch = Scratch { left: vec![false; n], tmp: vec![0; n], right_area: vec![0.0; n] };
    let [x, y, z] = &mut sorted;
    recurse(&local, ids, [x, y, z], &mut scratch, config, out, depth)
}

struct Scratch {
    left: Vec<bool>,
    tmp: Vec<u32>,
    right_area: Vec<f32>,
}

fn recurse(
    local: &[&Prim],
    global: &[u32],
    sorted: [&mut [u32]; 3],
    s: &mut Scratch,
    config: &BuildConfig,
    out: &mut Output,
    depth: usize,
) -> usize {
    let n = sorted[0].len();
    let bounds = sorted[0].iter().fold(Aabb::EMPTY, |b, &i| b.union(local[i as usize].bounds()));
    let leaf = |out: &mut Output, ids: &[u32]| out.leaf(&bounds, ids.iter().map(|&i| global[i as usize]));
    if forced_leaf(config, n, depth) {
        return leaf(out, sorted[0]);
    }
    let parent_area = bounds.surface_area();
    let mut best: Option<(usize, usize, f32)> = None;
    for axis in 0..3 {
        let list = &sorted[axis];
        // Right-to-left sweep: area of the last k primitives' bounds.
        let mut acc = Aabb::EMPTY;
        for k in (1..n).rev() {
            acc = acc.union(local[list[k] as usize].bounds());
            s.right_area[k] = acc.surface_area();
        }
        // Left-to-right sweep evaluates every split between positions k−1 and k.
        let mut acc = Aabb::EMPTY;
        for k in 1..n {
            acc = acc.union(local[list[k - 1] as usize].bounds());
            let cost = split_cost(
                config,
                parent_area,
                area_weighted(config, (acc.surface_area(), k), (s.right_area[k], n - k)),
            );
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, k, cost));
            }
        }
    }
    let Some((axis, mid, cost)) = best else { return leaf(out, sorted[0]) };
    if sah_prefers_leaf(config, n, cost) {
        return leaf(out, sorted[0]);
    }
    // Mark the left side by the chosen axis, then partition the other two lists stably.
    for (k, &i) in sorted[axis].iter().enumerate() {
        s.left[i as usize] = k < mid;
    }
    let [mut sx, mut sy, mut sz] = sorted;
    for (a, list) in [&mut sx, &mut sy, &mut sz].into_iter().enumerate() {
        if a == axis {
            continue;
        }
        let (mut l, mut r) = (0, mid);
        for &i in list.iter() {
            if s.left[i as usize] {
                s.tmp[l] = i;
                l += 1;
            } else {
                s.tmp[r] = i;
                r += 1;
            }
        }
        list.copy_from_slice(&s.tmp[..n]);
    }
    let index = out.interior(&bounds);
    let (xl, xr) = sx.split_at_mut(mid);
    let (yl, yr) = sy.split_at_mut(mid);
    let (zl, zr) = sz.split_at_mut(mid);
    recurse(local, global, [xl, yl, zl], s, config, out, depth + 1);
    let right = recurse(local, global, [xr, yr, zr], s, config, out, depth + 1);
    out.nodes[index].index = right as u32;
    index
}
