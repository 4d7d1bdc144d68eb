//! Binned SAH split search (Wald 2007, "On fast Construction of SAH-based Bounding
//! Volume Hierarchies"): centroids are binned along each axis and the SAH is evaluated
//! only at the bin boundaries. All three axes are binned in one pass over the
//! primitives, split across threads for large nodes; bins hold their boxes in SIMD
//! registers, and the partition that applies a split also finds both children's centroid
//! bounds, so that no node makes a pass over its primitives for them.

use super::{Prim, Split, area_weighted, centroid_bounds, prefetch, split_cost};
use crate::Aabb;
use crate::build::BuildConfig;
use glam::Vec3A;
use rayon::prelude::*;
use std::mem::MaybeUninit;

/// A bin: the box of the primitives whose centroids fall in it, and their number.
#[derive(Clone, Copy)]
struct Bin {
    min: Vec3A,
    max: Vec3A,
    count: u32,
}

const EMPTY_BIN: Bin = Bin { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY, count: 0 };

impl Bin {
    #[inline(always)]
    fn add(&mut self, o: &Bin) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
        self.count += o.count;
    }

    fn bounds(&self) -> Aabb {
        Aabb { min: self.min.into(), max: self.max.into() }
    }

    /// Surface area, zero for an empty bin (as [`Aabb::surface_area`]).
    #[inline(always)]
    fn area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}

/// Nodes above this many primitives bin in parallel chunks of this size.
const PARALLEL_CHUNK: usize = 16 * 1024;

/// Bin counts up to which a node's bins live on the stack: most nodes are small, and a
/// heap allocation per node cost more than their binning.
const STACK_BINS: usize = 16;

/// Maps centroids to bin indices on each axis.
#[derive(Clone, Copy)]
struct Binner {
    min: Vec3A,
    scale: Vec3A,
    /// The last bin's index, as a float on every axis.
    last: Vec3A,
}

impl Binner {
    /// The bin of `centre` on each axis: ⌊(c − min)·scale⌋ clamped to the last bin.
    #[inline(always)]
    fn index(&self, centre: Vec3A) -> [u32; 4] {
        let x = ((centre - self.min) * self.scale).min(self.last);
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{__m128i, _mm_cvttps_epi32};
            // SAFETY: SSE2 is part of the x86_64 baseline. Lanes x, y, z lie in [0, last]
            // (centroids within their bounds; `minps` gives `last` for a NaN from an
            // overflowing scale), where truncation is the floor; the binning and the
            // partition both call this function, so any lane value is used consistently.
            unsafe { std::mem::transmute::<__m128i, [u32; 4]>(_mm_cvttps_epi32(x.into())) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let i = x.as_uvec3();
            [i.x, i.y, i.z, 0]
        }
    }
}

/// The first `n` bins of `storage`, emptied: only the bins a node uses are initialised, as
/// most nodes are small.
#[inline(always)]
fn empty_bins(storage: &mut [MaybeUninit<Bin>; 3 * STACK_BINS], n: usize) -> &mut [Bin] {
    let bins = &mut storage[..n];
    for b in bins.iter_mut() {
        b.write(EMPTY_BIN);
    }
    // SAFETY: every element of the slice was just initialised.
    unsafe { &mut *(bins as *mut [MaybeUninit<Bin>] as *mut [Bin]) }
}

/// Adds primitive `p`, whose bin on each axis is `b`, to `bins` (3·nb bins, axis-major).
#[inline(always)]
fn add_to_bins(bins: &mut [Bin], nb: usize, b: [u32; 4], p: &Prim) {
    let one = Bin { min: p.min, max: p.max, count: 1 };
    for axis in 0..3 {
        bins[axis * nb + b[axis] as usize].add(&one);
    }
}

/// Bins `ids` along all three axes into `bins[axis * nb + b]` (3·nb empty bins), one
/// primitive after the other.
fn bin_serial(prims: &[Prim], ids: &[u32], binner: &Binner, nb: usize, bins: &mut [Bin]) {
    for (j, &i) in ids.iter().enumerate() {
        prefetch(prims, ids, j);
        let p = &prims[i as usize];
        add_to_bins(bins, nb, binner.index(p.centre()), p);
    }
}

/// [`bin_serial`]'s result, computed with the even and the odd primitives in two sets of
/// bins merged at the end: neighbouring primitives mostly fall in the same bins, and
/// with one set each update waits for the previous one's store (docs/figures.md, "Builds,
/// sixth session").
fn bin(prims: &[Prim], ids: &[u32], binner: &Binner, nb: usize, bins: &mut [Bin]) {
    if ids.len() < 64 || nb > STACK_BINS {
        return bin_serial(prims, ids, binner, nb, bins);
    }
    let mut odd_bins = [MaybeUninit::<Bin>::uninit(); 3 * STACK_BINS];
    let odd = empty_bins(&mut odd_bins, 3 * nb);
    let pairs = ids.chunks_exact(2);
    let rest = pairs.remainder();
    for (k, pair) in pairs.enumerate() {
        prefetch(prims, ids, 2 * k);
        prefetch(prims, ids, 2 * k + 1);
        let (p, q) = (&prims[pair[0] as usize], &prims[pair[1] as usize]);
        add_to_bins(bins, nb, binner.index(p.centre()), p);
        add_to_bins(odd, nb, binner.index(q.centre()), q);
    }
    bin_serial(prims, rest, binner, nb, bins);
    for (a, b) in bins.iter_mut().zip(odd.iter()) {
        a.add(b);
    }
}

/// Partitions `ids` at the best binned-SAH plane, or returns `None` when the centroids
/// span no extent. `centroids`: the bounds of the primitives' centroids, if known.
pub(crate) fn split(
    prims: &[Prim],
    ids: &mut [u32],
    bounds: &Aabb,
    centroids: Option<Aabb>,
    config: &BuildConfig,
) -> Option<Split> {
    let cb = centroids.unwrap_or_else(|| centroid_bounds(prims, ids));
    let extent = Vec3A::from(cb.extent());
    let parent_area = bounds.surface_area();
    // Small nodes get fewer bins (at least four, at most one per primitive): a node's
    // fixed cost is its 3·(nb − 1) candidate planes, and most nodes are small.
    let nb = config.bins.min(ids.len().max(4));
    // Axes without extent get scale 0: everything lands in bin 0 and no plane is valid.
    let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), Vec3A::splat(nb as f32) / extent, Vec3A::ZERO);
    let binner = Binner { min: cb.min.into(), scale, last: Vec3A::splat((nb - 1) as f32) };
    let mut stack_bins = [MaybeUninit::<Bin>::uninit(); 3 * STACK_BINS];
    let heap_bins: Vec<Bin>;
    let bins: &[Bin] = if ids.len() > 2 * PARALLEL_CHUNK {
        heap_bins = ids
            .par_chunks(PARALLEL_CHUNK)
            .map(|c| {
                let mut bins = vec![EMPTY_BIN; 3 * nb];
                bin(prims, c, &binner, nb, &mut bins);
                bins
            })
            .reduce_with(|mut a, b| {
                for (x, y) in a.iter_mut().zip(&b) {
                    x.add(y);
                }
                a
            })?;
        &heap_bins
    } else if nb <= STACK_BINS {
        let bins = empty_bins(&mut stack_bins, 3 * nb);
        bin(prims, ids, &binner, nb, bins);
        bins
    } else {
        let mut bins = vec![EMPTY_BIN; 3 * nb];
        bin(prims, ids, &binner, nb, &mut bins);
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
        let mut acc = EMPTY_BIN;
        for i in (1..nb).rev() {
            acc.add(&bins[i]);
            right[i] = (acc.area(), acc.count as usize);
        }
        let mut acc = EMPTY_BIN;
        for i in 0..nb - 1 {
            acc.add(&bins[i]);
            if acc.count == 0 || right[i + 1].1 == 0 {
                continue;
            }
            // The SAH's area-weighted test count; the cost is monotonic in it.
            let weighted = area_weighted(config, (acc.area(), acc.count as usize), right[i + 1]);
            if best.is_none_or(|(_, _, c)| weighted < c) {
                best = Some((axis, i + 1, weighted));
            }
        }
    }
    let (axis, boundary, weighted) = best?;
    let cost = split_cost(config, parent_area, weighted);
    // Partition with the same bin arithmetic as the binning, so the split is exact, and
    // collect each side's centroid bounds on the way.
    let (mut lmin, mut lmax) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
    let (mut rmin, mut rmax) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
    let mut mid = 0;
    for j in 0..ids.len() {
        prefetch(prims, ids, j);
        let c = prims[ids[j] as usize].centre();
        if (binner.index(c)[axis] as usize) < boundary {
            ids.swap(mid, j);
            mid += 1;
            lmin = lmin.min(c);
            lmax = lmax.max(c);
        } else {
            rmin = rmin.min(c);
            rmax = rmax.max(c);
        }
    }
    // A side without primitives keeps (+∞, −∞): the empty box.
    let left_c = Aabb { min: lmin.into(), max: lmax.into() };
    let right_c = Aabb { min: rmin.into(), max: rmax.into() };
    // The children's bounds are their bins' (no pass over the primitives).
    let side = |range: std::ops::Range<usize>| {
        bins[axis * nb..][range].iter().fold(EMPTY_BIN, |mut b, x| {
            b.add(x);
            b
        })
    };
    Some(Split {
        mid,
        cost,
        left: side(0..boundary).bounds(),
        right: side(boundary..nb).bounds(),
        centroids: Some((left_c, right_c)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_sets_of_bins_bin_as_one() {
        // Random boxes, the ids shuffled, an odd count: both passes give the same bins,
        // bit for bit (min, max and counts are exact whatever the order).
        let prims = crate::test_util::prims(7, 999, 10.0);
        let mut ids: Vec<u32> = (0..prims.len() as u32).collect();
        ids.sort_by_key(|&i| (i * 7919) % 999);
        let cb = centroid_bounds(&prims, &ids);
        let extent = Vec3A::from(cb.extent());
        for nb in [5, 8, STACK_BINS] {
            let last = Vec3A::splat((nb - 1) as f32);
            let binner = Binner { min: cb.min.into(), scale: Vec3A::splat(nb as f32) / extent, last };
            let (mut one, mut two) = (vec![EMPTY_BIN; 3 * nb], vec![EMPTY_BIN; 3 * nb]);
            bin_serial(&prims, &ids, &binner, nb, &mut one);
            bin(&prims, &ids, &binner, nb, &mut two);
            assert_eq!(one.iter().map(|b| b.count).sum::<u32>(), 3 * 999);
            for (a, b) in one.iter().zip(&two) {
                assert_eq!((a.min, a.max, a.count), (b.min, b.max, b.count), "{nb} bins");
            }
        }
    }
}
