//! Occlusion and closest hits of up to [`PACKET`] rays at once: one walk down the tree
//! for the whole packet (Wald, Slusallek, Benthin & Wagner 2001, "Interactive rendering
//! with coherent ray tracing"; Embree's `rtcOccluded16`/`rtcIntersect16`, which Mitsuba 3's
//! LLVM variants call with their sixteen lanes). Each box and each triangle is tested for
//! all of the packet's rays that reached it, in lanes; for occlusion a ray drops out of
//! the packet at its first occluder, for closest hits each lane keeps its own t_max.
//!
//! Lane by lane the result is the single-ray traversal's: a lane tests the boxes and
//! triangles its own traversal would (a child is entered by the lanes whose slab test
//! passes, with the same operations as the kernels' box test), and each triangle test is
//! `intersect_triangle_watertight`'s operations in the same order (no fused multiply-adds;
//! an edge function of exactly zero goes to the scalar test, which falls back to f64).
//! A closest hit does not depend on the order the walk meets the triangles in: ties in t
//! go to the lower triangle index, in the single-ray traversal too (`kernel::closer`).
//! Trees built for the Möller–Trumbore test trace their rays one at a time.
//!
//! Shadow rays: where at most `ALONE` of the packet's rays enter a child, each goes on
//! alone from there by the single-ray traversal (Embree's hybrid traversal does the
//! same). Measured against single rays (`spt rays trace --packet`, docs/figures.md):
//! faster on the Cornell box's shadow rays and camera rays, slower on the bunny's and
//! Sponza's, and on every scene's diffuse rays, where a packet's rays part ways early and
//! the walk has no near-to-far order; the renderer's lanes trace theirs one at a time,
//! since there packets only broke even on the box (shadow rays and camera rays alike).

use super::kernel::{RayKernel, ScalarKernel, closer_than, tie_bound};
use super::traverse::traceable;
use super::{BvhWide, MAX_WIDTH};
use crate::{Accelerator, Hit, Ray, TriangleTest, WatertightRay, intersect_triangle_watertight};
use glam::Vec3;
use std::mem::MaybeUninit;

/// Rays per packet: sixteen, AVX-512's lanes (two AVX2 registers).
pub const PACKET: usize = 16;

type Lanes = [f32; PACKET];

/// The packet's rays in structure of arrays for the box test, and each ray prepared for
/// the watertight test, whose per-lane fields the triangle test reads across the lanes.
struct Packet {
    origin: [Lanes; 3],
    inv_dir: [Lanes; 3],
    /// Whether `inv_dir` is negative (sign bit) on each axis: the near plane is the box's
    /// upper one.
    negative: [[bool; PACKET]; 3],
    t_min: Lanes,
    t_max: Lanes,
    /// Each lane's [`WatertightRay`] (for a lane an edge function leaves to the scalar
    /// test), and its permutation, shear and permuted origin in structure of arrays.
    watertight: [WatertightRay; PACKET],
    k: [[u8; PACKET]; 3],
    shear: [Lanes; 3],
    w_origin: [Lanes; 3],
}

/// The maxps/minps of the kernels' box test: the second operand unless the first is
/// strictly greater (smaller), so a NaN first operand yields the second.
#[inline(always)]
fn max_ps(a: f32, acc: f32) -> f32 {
    if a > acc { a } else { acc }
}
#[inline(always)]
fn min_ps(a: f32, acc: f32) -> f32 {
    if a < acc { a } else { acc }
}

/// One coordinate of each lane's permuted axis `k`: x, y or z by lane.
#[inline(always)]
fn pick(k: u8, v: Vec3) -> f32 {
    let xy = if k == 0 { v.x } else { v.y };
    if k == 2 { v.z } else { xy }
}

impl Packet {
    /// The packet of `rays`; lanes past their count hold a ray along z from the origin
    /// (never tested: every test is masked by the lanes in use).
    #[inline(always)]
    fn new(rays: &[Ray]) -> Self {
        let unused = Ray::new(Vec3::ZERO, Vec3::Z);
        let mut p = Packet {
            origin: [[0.0; PACKET]; 3],
            inv_dir: [[0.0; PACKET]; 3],
            negative: [[false; PACKET]; 3],
            t_min: [0.0; PACKET],
            t_max: [0.0; PACKET],
            watertight: [WatertightRay::new(&unused); PACKET],
            k: [[0; PACKET]; 3],
            shear: [[0.0; PACKET]; 3],
            w_origin: [[0.0; PACKET]; 3],
        };
        for (i, ray) in rays.iter().chain(std::iter::repeat(&unused)).take(PACKET).enumerate() {
            let w = WatertightRay::new(ray);
            let (o, inv) = (ray.origin.to_array(), ray.inv_dir.to_array());
            for a in 0..3 {
                p.origin[a][i] = o[a];
                p.inv_dir[a][i] = inv[a];
                p.negative[a][i] = inv[a].is_sign_negative();
                p.k[a][i] = w.k[a] as u8;
                p.shear[a][i] = w.shear[a];
                p.w_origin[a][i] = w.origin[a];
            }
            p.t_min[i] = ray.t_min;
            p.t_max[i] = ray.t_max;
            p.watertight[i] = w;
        }
        p
    }

    /// The lanes of `lanes` that enter child `c` of `node` within (t_min, t_max].
    #[inline(always)]
    fn enter<const W: usize>(&self, node: &super::WideNode<W>, c: usize, lanes: u32) -> u32 {
        let lo = [node.min_x[c], node.min_y[c], node.min_z[c]];
        let hi = [node.max_x[c], node.max_y[c], node.max_z[c]];
        let mut mask = 0u32;
        for i in 0..PACKET {
            let (mut enter, mut exit) = (self.t_min[i], self.t_max[i]);
            for a in (0..3).rev() {
                let neg = self.negative[a][i];
                let (near, far) = if neg { (hi[a], lo[a]) } else { (lo[a], hi[a]) };
                enter = max_ps((near - self.origin[a][i]) * self.inv_dir[a][i], enter);
                exit = min_ps((far - self.origin[a][i]) * self.inv_dir[a][i], exit);
            }
            mask |= ((enter <= exit) as u32) << i;
        }
        mask & lanes
    }

    /// Lane `i`'s watertight test of triangle `v` up to its t (`intersect_triangle_watertight`'s
    /// operations in its order): whether an edge function is exactly zero, whether the
    /// edge functions' signs and the determinant admit a hit with a finite t above t_min,
    /// and t, u and v.
    #[inline(always)]
    fn lane_test(&self, i: usize, v: &[Vec3; 3]) -> (bool, bool, f32, f32, f32) {
        let [kx, ky, kz] = [self.k[0][i], self.k[1][i], self.k[2][i]];
        let [sx, sy, sz] = [self.shear[0][i], self.shear[1][i], self.shear[2][i]];
        let [ox, oy, oz] = [self.w_origin[0][i], self.w_origin[1][i], self.w_origin[2][i]];
        let rel = |p: Vec3| {
            let px = pick(kx, p) - ox;
            let py = pick(ky, p) - oy;
            let pz = pick(kz, p) - oz;
            (px - sx * pz, py - sy * pz, sz * pz)
        };
        let (ax, ay, az) = rel(v[0]);
        let (bx, by, bz) = rel(v[1]);
        let (cx, cy, cz) = rel(v[2]);
        let e0 = cx * by - cy * bx;
        let e1 = ax * cy - ay * cx;
        let e2 = bx * ay - by * ax;
        let any_zero = e0 == 0.0 || e1 == 0.0 || e2 == 0.0;
        let neg = e0 < 0.0 || e1 < 0.0 || e2 < 0.0;
        let pos = e0 > 0.0 || e1 > 0.0 || e2 > 0.0;
        let det = e0 + e1 + e2;
        let inv_det = 1.0 / det;
        let t = (e0 * az + e1 * bz + e2 * cz) * inv_det;
        let ok = !(neg && pos) && det != 0.0 && t.abs() < f32::INFINITY && t > self.t_min[i];
        (any_zero, ok, t, e1 * inv_det, e2 * inv_det)
    }

    /// The lanes of `lanes` whose ray hits triangle `v` within (t_min, t_max).
    #[inline(always)]
    fn hits(&self, v: &[Vec3; 3], lanes: u32) -> u32 {
        let mut hit = 0u32;
        let mut zero = 0u32;
        for i in 0..PACKET {
            let (any_zero, ok, t, _, _) = self.lane_test(i, v);
            hit |= ((ok && t < self.t_max[i]) as u32) << i;
            zero |= (any_zero as u32) << i;
        }
        let mut redo = zero & lanes;
        let mut hit = hit & !zero & lanes;
        while redo != 0 {
            let i = redo.trailing_zeros() as usize;
            redo &= redo - 1;
            if intersect_triangle_watertight(v, &self.watertight[i], self.t_max[i]).is_some() {
                hit |= 1 << i;
            }
        }
        hit
    }

    /// Tests triangle `v` (index `prim`, in `leaf`) for the lanes of `lanes` and takes it
    /// as a lane's closest hit where it is nearer than the lane's closest so far (its
    /// `t_max`), or as near and of a lower index (`kernel::closer`'s tie rule). Returns the lanes
    /// with an edge function of exactly zero, which the caller redoes by the scalar test.
    #[inline(always)]
    fn take_closest(&mut self, best: &mut Closest, v: &[Vec3; 3], prim: u32, leaf: (u32, u32), lanes: u32) -> u32 {
        let mut zero = [false; PACKET];
        for i in 0..PACKET {
            let (any_zero, ok, t, u, w) = self.lane_test(i, v);
            let live = lanes & (1 << i) != 0;
            let t_max = self.t_max[i];
            let closer = closer_than(t, prim, t_max, best.found[i], best.prim[i]);
            let take = live && !any_zero && ok && closer;
            self.t_max[i] = if take { t } else { t_max };
            best.u[i] = if take { u } else { best.u[i] };
            best.v[i] = if take { w } else { best.v[i] };
            best.prim[i] = if take { prim } else { best.prim[i] };
            best.leaf[i] = if take { leaf } else { best.leaf[i] };
            best.found[i] |= take;
            zero[i] = live && any_zero;
        }
        let mut mask = 0;
        for (i, &z) in zero.iter().enumerate() {
            mask |= (z as u32) << i;
        }
        mask
    }

    /// [`Packet::take_closest`] for lane `i` alone by the scalar test (which falls back to
    /// f64 where an edge function is zero).
    #[inline(never)]
    fn take_closest_scalar(&mut self, best: &mut Closest, v: &[Vec3; 3], prim: u32, leaf: (u32, u32), i: usize) {
        let t_max = self.t_max[i];
        if let Some((t, u, w)) = intersect_triangle_watertight(v, &self.watertight[i], tie_bound(t_max, best.found[i]))
            && closer_than(t, prim, t_max, best.found[i], best.prim[i])
        {
            self.t_max[i] = t;
            (best.u[i], best.v[i], best.prim[i], best.leaf[i], best.found[i]) = (u, w, prim, leaf, true);
        }
    }
}

/// `occluded_packet` for a tree type, with the kernels its rays continue with alone.
macro_rules! packets_for {
    ($tree:ty, $avx:ty, $baseline:ty) => {
        impl $tree {
            /// For each of `rays` (at most [`PACKET`]), whether something blocks it: the
            /// same answers as [`Accelerator::occluded`] ray by ray, from one walk down the
            /// tree for the packet (see the module documentation). Rays that share their
            /// way through the tree share its cost; where few of the packet's rays enter a
            /// child, they go on one at a time.
            pub fn occluded_packet(&self, rays: &[Ray], occluded: &mut [bool]) {
                assert!(rays.len() <= PACKET && occluded.len() == rays.len(), "at most {PACKET} rays, one answer each");
                if self.test != TriangleTest::Watertight {
                    for (o, r) in occluded.iter_mut().zip(rays) {
                        *o = self.occluded(r);
                    }
                    return;
                }
                let blocked = self.blocked_lanes(rays);
                for (i, o) in occluded.iter_mut().enumerate() {
                    *o = blocked & (1 << i) != 0;
                }
            }

            /// The closest hit of each of `rays` (at most [`PACKET`]) into `hits`: the
            /// same as [`Accelerator::intersect`] ray by ray, from one walk down the tree
            /// for the packet.
            pub fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
                assert!(rays.len() <= PACKET && hits.len() == rays.len(), "at most {PACKET} rays, one answer each");
                if self.test != TriangleTest::Watertight {
                    for (h, r) in hits.iter_mut().zip(rays) {
                        *h = self.intersect(r);
                    }
                    return;
                }
                #[cfg(target_arch = "x86_64")]
                match crate::isa::active() {
                    // SAFETY: `active` is at most what the CPU has (detected).
                    crate::isa::Isa::Avx512 => return unsafe { self.closest_lanes_avx512(rays, hits) },
                    // SAFETY: as above.
                    crate::isa::Isa::Avx2 => return unsafe { self.closest_lanes_avx2(rays, hits) },
                    crate::isa::Isa::Baseline => {}
                }
                self.closest_lanes(rays, hits)
            }

            /// Compiled for AVX-512.
            ///
            /// # Safety
            ///
            /// The CPU must have AVX-512 F, VL, BW and DQ.
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
            unsafe fn closest_lanes_avx512(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
                self.closest_lanes(rays, hits)
            }

            /// Compiled for AVX2.
            ///
            /// # Safety
            ///
            /// The CPU must have AVX2.
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            unsafe fn closest_lanes_avx2(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
                self.closest_lanes(rays, hits)
            }

            #[inline]
            fn blocked_lanes(&self, rays: &[Ray]) -> u32 {
                #[cfg(target_arch = "x86_64")]
                match crate::isa::active() {
                    // SAFETY: `active` is at most what the CPU has (detected).
                    crate::isa::Isa::Avx512 => return unsafe { self.blocked_lanes_avx512(rays) },
                    // SAFETY: as above.
                    crate::isa::Isa::Avx2 => return unsafe { self.blocked_lanes_avx2(rays) },
                    crate::isa::Isa::Baseline => {}
                }
                self.occluded_lanes::<$baseline>(rays)
            }

            /// Compiled for AVX-512: sixteen lanes to a register.
            ///
            /// # Safety
            ///
            /// The CPU must have AVX-512 F, VL, BW and DQ.
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
            unsafe fn blocked_lanes_avx512(&self, rays: &[Ray]) -> u32 {
                self.occluded_lanes::<$avx>(rays)
            }

            /// Compiled for AVX2.
            ///
            /// # Safety
            ///
            /// The CPU must have AVX2.
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            unsafe fn blocked_lanes_avx2(&self, rays: &[Ray]) -> u32 {
                self.occluded_lanes::<$avx>(rays)
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
packets_for!(super::Bvh8, super::avx::AvxKernel, ScalarKernel);
#[cfg(target_arch = "x86_64")]
packets_for!(super::Bvh4, super::sse::SseKernel, super::sse::SseKernel);
#[cfg(not(target_arch = "x86_64"))]
packets_for!(super::Bvh8, ScalarKernel, ScalarKernel);
#[cfg(not(target_arch = "x86_64"))]
packets_for!(super::Bvh4, ScalarKernel, ScalarKernel);

/// Lanes that go on alone: at most this many of a packet's rays entering a child (3, 6
/// and 10 measured on the shadow ray sets: 3 is best on the Cornell box, 24.4 against 23.7
/// Mrays/s at 10, and worst on the bunny, 3.7 against 4.3).
const ALONE: u32 = 3;

impl<const W: usize> BvhWide<W> {
    /// Pushes each child of node `node` that lanes of `lanes` enter, with those lanes.
    #[inline(always)]
    fn push_entered(
        &self,
        p: &Packet,
        node: u32,
        lanes: u32,
        stack: &mut [MaybeUninit<(u32, u32, u32)>],
        sp: &mut usize,
    ) {
        let node = &self.nodes[node as usize];
        for c in 0..W {
            let m = p.enter(node, c, lanes);
            if m != 0 {
                stack[*sp] = MaybeUninit::new((node.child[c], node.count[c], m));
                *sp += 1;
            }
        }
    }

    /// Bit i set if ray i is blocked.
    #[inline(always)]
    fn occluded_lanes<K: RayKernel<W>>(&self, rays: &[Ray]) -> u32 {
        let mut live = 0u32;
        for (i, r) in rays.iter().enumerate() {
            live |= (traceable(r) as u32) << i;
        }
        if self.nodes.is_empty() || live == 0 {
            return 0;
        }
        let p = Packet::new(rays);
        let mut blocked = 0u32;
        // (child, count, lanes that entered it): the root first. A node's children are
        // all pushed (W, not the single ray's W − 1), so the bound is W per level.
        // Uninitialised, as the single-ray stack: zeroing it would cost more than a short
        // walk.
        let mut stack = [MaybeUninit::<(u32, u32, u32)>::uninit(); MAX_WIDTH * 64 + 1];
        stack[0] = MaybeUninit::new((0, 0, live));
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            // SAFETY: entries below `sp` were all written by the pushes.
            let (child, count, entered) = unsafe { stack[sp].assume_init() };
            let lanes = entered & !blocked;
            if lanes == 0 {
                continue;
            }
            if lanes.count_ones() <= ALONE {
                // Too few to share the work: each goes on by the single-ray traversal,
                // from this child (the tests it makes there are its own traversal's).
                let mut m = lanes;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let stats = &mut crate::RayStats::default();
                    if self.traverse_from::<K, false, true>(&rays[i], stats, (child, count)).is_some() {
                        blocked |= 1 << i;
                    }
                }
            } else if count == 0 {
                self.push_entered(&p, child, lanes, &mut stack, &mut sp);
            } else {
                let (first, n) = (child as usize, count as usize);
                let leaf = self.leaf(first, n);
                let mut left = lanes;
                for i in 0..n {
                    let h = p.hits(&leaf.vertices(i), left);
                    blocked |= h;
                    left &= !h;
                    if left == 0 {
                        break;
                    }
                }
            }
            if blocked == live {
                break;
            }
        }
        blocked
    }
}

/// Each lane's closest hit so far in a packet walk (its t is the packet's `t_max`), and
/// the leaf it lies in (for `refine`).
struct Closest {
    found: [bool; PACKET],
    prim: [u32; PACKET],
    u: Lanes,
    v: Lanes,
    leaf: [(u32, u32); PACKET],
}

impl<const W: usize> BvhWide<W> {
    /// Closest hits of `rays` (at most [`PACKET`]) into `hits`: one walk for the packet,
    /// children in index order, each leaf's triangles tested across the lanes that
    /// entered it.
    #[inline(always)]
    fn closest_lanes(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        hits.fill(None);
        let mut live = 0u32;
        for (i, r) in rays.iter().enumerate() {
            live |= (traceable(r) as u32) << i;
        }
        if self.nodes.is_empty() || live == 0 {
            return;
        }
        let mut p = Packet::new(rays);
        let mut best = Closest {
            found: [false; PACKET],
            prim: [u32::MAX; PACKET],
            u: [0.0; PACKET],
            v: [0.0; PACKET],
            leaf: [(0, 0); PACKET],
        };
        // (child, count, lanes that entered it), the root first, in index order.
        let mut stack = [MaybeUninit::<(u32, u32, u32)>::uninit(); MAX_WIDTH * 64 + 1];
        stack[0] = MaybeUninit::new((0, 0, live));
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            // SAFETY: entries below `sp` were all written by the pushes.
            let (child, count, lanes) = unsafe { stack[sp].assume_init() };
            if count == 0 {
                self.push_entered(&p, child, lanes, &mut stack, &mut sp);
            } else {
                let (first, n) = (child as usize, count as usize);
                let leaf = self.leaf(first, n);
                for i in 0..n {
                    let v = leaf.vertices(i);
                    let mut zero = p.take_closest(&mut best, &v, leaf.ids[i], (child, count), lanes);
                    while zero != 0 {
                        let l = zero.trailing_zeros() as usize;
                        zero &= zero - 1;
                        p.take_closest_scalar(&mut best, &v, leaf.ids[i], (child, count), l);
                    }
                }
            }
        }
        for i in (0..rays.len()).filter(|&i| best.found[i]) {
            let (first, n) = (best.leaf[i].0 as usize, best.leaf[i].1 as usize);
            let leaf = self.leaf(first, n);
            let hit = Hit { prim: best.prim[i], t: p.t_max[i], u: best.u[i], v: best.v[i] };
            hits[i] = self.refine(&rays[i], Some(hit), leaf);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{rays, soup};
    use crate::{BuildConfig, Bvh4, Bvh8};

    /// Every packet size from 1 to 16 over `rays`, against the single-ray answers, through
    /// the dispatched build and the portable one; returns how many rays are blocked.
    fn check<const W: usize>(bvh: &BvhWide<W>, rays: &[Ray], packet: impl Fn(&[Ray], &mut [bool])) -> usize
    where
        BvhWide<W>: Accelerator,
    {
        let single: Vec<bool> = rays.iter().map(|r| bvh.occluded(r)).collect();
        let mut start = 0;
        let mut size = 1;
        while start < rays.len() {
            let end = (start + size).min(rays.len());
            let mut got = [false; PACKET];
            packet(&rays[start..end], &mut got[..end - start]);
            let portable = bvh.occluded_lanes::<ScalarKernel>(&rays[start..end]);
            for i in start..end {
                assert_eq!(got[i - start], single[i], "{W}-wide, ray {i} ({:?}), packet {start}..{end}", rays[i]);
                assert_eq!(portable & (1 << (i - start)) != 0, single[i], "{W}-wide portable, ray {i}");
            }
            start = end;
            size = size % PACKET + 1;
        }
        single.iter().filter(|&&b| b).count()
    }

    /// Closest hits in packets of every size from 1 to 16 over `rays`, against the single
    /// ray's (prim, t, u and v to the bit), through the dispatched build and the portable
    /// one; returns how many rays hit.
    fn check_closest<const W: usize>(
        bvh: &BvhWide<W>,
        rays: &[Ray],
        packet: impl Fn(&[Ray], &mut [Option<Hit>]),
    ) -> usize
    where
        BvhWide<W>: Accelerator,
    {
        let single: Vec<Option<Hit>> = rays.iter().map(|r| bvh.intersect(r)).collect();
        let bits = |h: &Option<Hit>| h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
        let (mut start, mut size) = (0, 1);
        while start < rays.len() {
            let end = (start + size).min(rays.len());
            let mut got = [None; PACKET];
            packet(&rays[start..end], &mut got[..end - start]);
            let mut portable = [None; PACKET];
            bvh.closest_lanes(&rays[start..end], &mut portable[..end - start]);
            for i in start..end {
                assert_eq!(
                    bits(&got[i - start]),
                    bits(&single[i]),
                    "{W}-wide, ray {i} ({:?}), packet {start}..{end}",
                    rays[i]
                );
                assert_eq!(bits(&portable[i - start]), bits(&single[i]), "{W}-wide portable, ray {i}");
            }
            start = end;
            size = size % PACKET + 1;
        }
        single.iter().filter(|h| h.is_some()).count()
    }

    #[test]
    fn closest_hits_in_packets_are_the_single_rays_on_a_soup_and_a_grid() {
        let tris = soup(7, 3000, 10.0, 1.0);
        let rs = rays(8, 5000, 10.0);
        let four = Bvh4::build(&tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
        let eight = Bvh8::build(&tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
        let hit = check_closest(&four, &rs, |r, h| four.intersect_packet(r, h));
        assert_eq!(check_closest(&eight, &rs, |r, h| eight.intersect_packet(r, h)), hit);
        assert!(hit > 500 && hit < 4500, "a mix of hits and misses: {hit}");

        // Rays straight down onto a grid's vertices, edges and centres (edge functions of
        // zero, ties between the triangles that share them), some stopping short, and a
        // NaN ray.
        let (tris, mut rs) = grid_and_rays();
        rs.push(Ray::new(Vec3::new(1.0, 1.0, 1.0), Vec3::new(f32::NAN, 0.0, -1.0)));
        let grid = Bvh8::build(&tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
        let hit = check_closest(&grid, &rs, |r, h| grid.intersect_packet(r, h));
        assert!(hit > 300 && hit < rs.len() - 300, "{hit} of {}", rs.len());

        let empty = Bvh8::build(&[], BuildConfig::default()).unwrap();
        let mut got = [Some(Hit { prim: 0, t: 1.0, u: 0.0, v: 0.0 }); 3];
        empty.intersect_packet(&rs[..3], &mut got);
        assert_eq!(got, [None; 3]);
    }

    /// Two copies of every triangle of the grid (coplanar: the same t for every ray), rays
    /// onto shared edges and vertices: whatever order a traversal meets the triangles in —
    /// single rays through 4- and 8-wide trees of the list and of its reverse, and
    /// packets — the closest hit is the triangle of lowest index among those hit at the
    /// least t, as the brute-force oracle finds it.
    #[test]
    fn a_tie_goes_to_the_lower_index_in_every_traversal() {
        let (grid, rs) = grid_and_rays();
        let twice: Vec<[Vec3; 3]> = grid.iter().chain(grid.iter()).copied().collect();
        let reversed: Vec<[Vec3; 3]> = twice.iter().rev().copied().collect();
        let mut ties = 0;
        for tris in [&twice, &reversed] {
            let b8 = Bvh8::build(tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
            let b4 = Bvh4::build(tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
            for r in &rs {
                let w = WatertightRay::new(r);
                let oracle = (0..tris.len() as u32)
                    .filter_map(|p| intersect_triangle_watertight(&tris[p as usize], &w, r.t_max).map(|h| (h.0, p)))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let Some((t, prim)) = oracle else { continue };
                ties += 1;
                for got in [b8.intersect(r), b4.intersect(r)] {
                    let got = got.expect("the oracle's hit");
                    assert_eq!((got.prim, got.t), (prim, t), "{r:?}");
                }
            }
            check_closest(&b8, &rs, |r, h| b8.intersect_packet(r, h));
            check_closest(&b4, &rs, |r, h| b4.intersect_packet(r, h));
        }
        assert!(ties > 600, "{ties}");
    }

    /// A grid of unit squares (two triangles each) in z = 0, and rays straight down onto
    /// its vertices, edges and centres, every third stopping short.
    fn grid_and_rays() -> (Vec<[Vec3; 3]>, Vec<Ray>) {
        let mut tris = Vec::new();
        for x in 0..8 {
            for y in 0..8 {
                let p = |dx: i32, dy: i32| Vec3::new((x + dx) as f32, (y + dy) as f32, 0.0);
                tris.push([p(0, 0), p(1, 0), p(1, 1)]);
                tris.push([p(0, 0), p(1, 1), p(0, 1)]);
            }
        }
        let mut rs = Vec::new();
        for i in 0..33 {
            for j in 0..33 {
                let o = Vec3::new(i as f32 * 0.25, j as f32 * 0.25, 2.0);
                let t_max = if (i + j) % 3 == 0 { 1.5 } else { f32::INFINITY };
                rs.push(Ray::segment(o, Vec3::new(0.0, 0.0, -1.0), 0.0, t_max));
            }
        }
        (tris, rs)
    }

    #[test]
    fn packets_answer_as_single_rays_on_a_soup() {
        let tris = soup(7, 3000, 10.0, 1.0);
        let rs = rays(8, 5000, 10.0);
        let four = Bvh4::build(&tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
        let eight = Bvh8::build(&tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
        let blocked = check(&four, &rs, |r, o| four.occluded_packet(r, o));
        assert_eq!(check(&eight, &rs, |r, o| eight.occluded_packet(r, o)), blocked);
        assert!(blocked > 500 && blocked < 4500, "a mix of blocked and free rays: {blocked}");
    }

    /// A grid of unit squares (two triangles each) in z = 0, and rays straight down onto
    /// its vertices, edges and centres: edge functions of exactly zero, decided by the
    /// scalar test's f64 fallback; plus rays that stop short, rays inside a closed room
    /// (every ray blocked), rays with NaN and an empty tree.
    #[test]
    fn packets_answer_as_single_rays_on_shared_edges_in_rooms_and_for_bad_rays() {
        let (tris, mut rs) = grid_and_rays();
        rs.push(Ray::new(Vec3::new(1.0, 1.0, 1.0), Vec3::new(f32::NAN, 0.0, -1.0)));
        let grid = Bvh8::build(&tris, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
        let blocked = check(&grid, &rs, |r, o| grid.occluded_packet(r, o));
        assert!(blocked > 300 && blocked < rs.len() - 300, "{blocked} of {}", rs.len());

        // A closed cube of twelve triangles, rays from its centre: all blocked but those
        // that stop short.
        let c = |i: usize| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        let faces = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];
        let room: Vec<[Vec3; 3]> =
            faces.iter().flat_map(|f| [[c(f[0]), c(f[1]), c(f[2])], [c(f[0]), c(f[2]), c(f[3])]]).collect();
        let inside: Vec<Ray> = rays(3, 400, 1.0)
            .iter()
            .enumerate()
            .map(|(i, r)| Ray::segment(Vec3::splat(0.5), r.dir, 0.0, if i % 4 == 0 { 0.3 } else { 10.0 }))
            .collect();
        let room4 = Bvh4::build(&room, BuildConfig::default()).unwrap().with_triangle_test(TriangleTest::Watertight);
        assert_eq!(
            check(&room4, &inside, |r, o| room4.occluded_packet(r, o)),
            300,
            "every ray that reaches a wall is blocked"
        );

        let empty = Bvh8::build(&[], BuildConfig::default()).unwrap();
        let mut got = [true; 3];
        empty.occluded_packet(&inside[..3], &mut got);
        assert_eq!(got, [false; 3]);
    }
}
