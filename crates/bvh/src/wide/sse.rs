//! The SSE [`RayKernel`]: four boxes per `enter`, four triangles per step of a leaf, each
//! lane computing exactly what the scalar tests compute.

use super::Bvh4Node;
use super::kernel::{Leaf, RayKernel, record_hit};
use super::lanes::BoxRay;
use crate::{Hit, Ray, WatertightRay, intersect_triangle_watertight};
use std::arch::x86_64::*;

/// The SSE [`RayKernel`] (SSE2 is part of the x86_64 baseline).
pub(super) struct SseKernel {
    boxes: BoxRay<__m128>,
    dir: [__m128; 3],
}

impl RayKernel<4> for SseKernel {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        // SAFETY (all `unsafe` blocks here): SSE and SSE2 are part of the x86_64
        // baseline, so the intrinsics are always available.
        unsafe {
            Self {
                boxes: BoxRay::new(ray),
                dir: [_mm_set1_ps(ray.dir.x), _mm_set1_ps(ray.dir.y), _mm_set1_ps(ray.dir.z)],
            }
        }
    }

    #[inline(always)]
    fn enter(&self, node: &Bvh4Node, t_max: f32) -> (u32, [f32; 4]) {
        // SAFETY: baseline instructions (see `new`), and the node is 4 wide.
        unsafe { self.boxes.enter(node, t_max) }
    }

    #[inline(always)]
    fn triangles<const ANY_HIT: bool>(&self, _ray: &Ray, leaf: Leaf, t_max: &mut f32, best: &mut Option<Hit>) -> bool {
        let n = leaf.ids.len();
        // Four triangles at a time, lane by lane the operations of `intersect_triangle`
        // (bit-identical: no fused multiply-adds), then the lanes' hits in order.
        for j in (0..n).step_by(4) {
            let mut t = [0.0f32; 4];
            let mut u = [0.0f32; 4];
            let mut v = [0.0f32; 4];
            // SAFETY: intrinsics as in `new`; row k of this group starts at float
            // k·n + j ≤ 9n − 1 of `leaf.soa`, and the array has three floats of padding
            // after the last leaf, so every 4-wide load stays inside it.
            let mask = unsafe {
                debug_assert!(leaf.soa.len() >= 9 * n + 3);
                let ld = |k: usize| _mm_loadu_ps(leaf.soa.as_ptr().add(k * n + j));
                let [dx, dy, dz] = self.dir;
                let [ox, oy, oz] = self.boxes.origin;
                let (add, sub, mul) = (_mm_add_ps, _mm_sub_ps, _mm_mul_ps);
                // The edges as `Triangle::new` computes them.
                let (v0x, v0y, v0z) = (ld(0), ld(1), ld(2));
                let (e1x, e1y, e1z) = (sub(ld(3), v0x), sub(ld(4), v0y), sub(ld(5), v0z));
                let (e2x, e2y, e2z) = (sub(ld(6), v0x), sub(ld(7), v0y), sub(ld(8), v0z));
                let dot = |ax, ay, az, bx, by, bz| add(add(mul(ax, bx), mul(ay, by)), mul(az, bz));
                // p = dir × e2, det = e1 · p.
                let px = sub(mul(dy, e2z), mul(e2y, dz));
                let py = sub(mul(dz, e2x), mul(e2z, dx));
                let pz = sub(mul(dx, e2y), mul(e2x, dy));
                let det = dot(e1x, e1y, e1z, px, py, pz);
                let inv_det = _mm_div_ps(_mm_set1_ps(1.0), det);
                let (sx, sy, sz) = (sub(ox, v0x), sub(oy, v0y), sub(oz, v0z));
                let uu = mul(dot(sx, sy, sz, px, py, pz), inv_det);
                // q = s × e1.
                let qx = sub(mul(sy, e1z), mul(e1y, sz));
                let qy = sub(mul(sz, e1x), mul(e1z, sx));
                let qz = sub(mul(sx, e1y), mul(e1x, sy));
                let vv = mul(dot(dx, dy, dz, qx, qy, qz), inv_det);
                let tt = mul(dot(e2x, e2y, e2z, qx, qy, qz), inv_det);
                let abs_det = _mm_andnot_ps(_mm_set1_ps(-0.0), det);
                let zero = _mm_setzero_ps();
                let one = _mm_set1_ps(1.0);
                let and = _mm_and_ps;
                let ok = and(
                    and(_mm_cmpneq_ps(det, zero), _mm_cmplt_ps(abs_det, _mm_set1_ps(f32::INFINITY))),
                    and(_mm_cmpge_ps(uu, zero), _mm_cmple_ps(uu, one)),
                );
                let ok = and(ok, and(_mm_cmpnlt_ps(vv, zero), _mm_cmpngt_ps(add(uu, vv), one)));
                let ok = and(ok, and(_mm_cmpgt_ps(tt, self.boxes.t_min), _mm_cmplt_ps(tt, _mm_set1_ps(*t_max))));
                _mm_storeu_ps(t.as_mut_ptr(), tt);
                _mm_storeu_ps(u.as_mut_ptr(), uu);
                _mm_storeu_ps(v.as_mut_ptr(), vv);
                _mm_movemask_ps(ok) as u32 & (0b1111 >> 4usize.saturating_sub(n - j))
            };
            let mut m = mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                if t[i] < *t_max
                    && record_hit::<ANY_HIT>(Hit { prim: leaf.ids[j + i], t: t[i], u: u[i], v: v[i] }, t_max, best)
                {
                    return true;
                }
            }
        }
        false
    }

    #[inline(always)]
    fn watertight<const ANY_HIT: bool>(
        &self,
        ray: &WatertightRay,
        leaf: Leaf,
        t_max: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        // Leaves of up to four triangles, nearly all of them, run one group without a loop
        // (looped, the compiler kept each leaf's row addresses on the stack); larger ones
        // go to the looped function, kept out of line.
        if leaf.ids.len() <= 4 {
            return watertight_group::<ANY_HIT>(ray, leaf, 0, t_max, best);
        }
        watertight_groups::<ANY_HIT>(ray, leaf, t_max, best)
    }
}

/// [`watertight_group`] over a leaf of more than four triangles. Not inlined: inlined,
/// its loop changed how the whole traversal's registers were allocated, for 0.8 % and
/// 2.1 % more traversal instructions on the bunny's and Sponza's ray sets (1.6 % fewer on
/// the Cornell box's; callgrind), where such leaves are rare.
#[inline(never)]
fn watertight_groups<const ANY_HIT: bool>(
    ray: &WatertightRay,
    leaf: Leaf,
    t_max: &mut f32,
    best: &mut Option<Hit>,
) -> bool {
    for j in (0..leaf.ids.len()).step_by(4) {
        if watertight_group::<ANY_HIT>(ray, leaf, j, t_max, best) {
            return true;
        }
    }
    false
}

/// Tests triangles `j..j + 4` (those of them in the leaf) of `leaf` four at a time, lane
/// by lane the operations of `intersect_triangle_watertight` (bit-identical: no fused
/// multiply-adds); a lane with an edge function of exactly zero is redone by the scalar
/// test, which falls back to double precision. A function, not a closure, so that it is
/// inlined into the AVX2 traversal (a closure was compiled apart, without AVX).
#[inline(always)]
fn watertight_group<const ANY_HIT: bool>(
    ray: &WatertightRay,
    leaf: Leaf,
    j: usize,
    t_max: &mut f32,
    best: &mut Option<Hit>,
) -> bool {
    let n = leaf.ids.len();
    let [kx, ky, kz] = ray.k;
    let lanes = 0b1111u32 >> 4usize.saturating_sub(n - j);
    // SAFETY: intrinsics as in `new`; loads as in `triangles`.
    let (mask, zero_lanes, tt, uu, vv) = unsafe {
        debug_assert!(leaf.soa.len() >= 9 * n + 3);
        // Row 3v + k starts at float (3v + k)·n: three offsets for the axes and one
        // base per vertex, rather than nine products.
        let (x_row, y_row, z_row) = (kx * n, ky * n, kz * n);
        let vertex = |v: usize| leaf.soa.as_ptr().add(3 * v * n + j);
        let (add, sub, mul) = (_mm_add_ps, _mm_sub_ps, _mm_mul_ps);
        let (sx, sy, sz) = (_mm_set1_ps(ray.shear[0]), _mm_set1_ps(ray.shear[1]), _mm_set1_ps(ray.shear[2]));
        let [ox, oy, oz] = ray.origin.map(|o| _mm_set1_ps(o));
        // Vertex `v` relative to the origin, permuted and sheared.
        let rel = |v: usize| {
            let base = vertex(v);
            let px = sub(_mm_loadu_ps(base.add(x_row)), ox);
            let py = sub(_mm_loadu_ps(base.add(y_row)), oy);
            let pz = sub(_mm_loadu_ps(base.add(z_row)), oz);
            (sub(px, mul(sx, pz)), sub(py, mul(sy, pz)), mul(sz, pz))
        };
        let (ax, ay, az) = rel(0);
        let (bx, by, bz) = rel(1);
        let (cx, cy, cz) = rel(2);
        let e0 = sub(mul(cx, by), mul(cy, bx));
        let e1 = sub(mul(ax, cy), mul(ay, cx));
        let e2 = sub(mul(bx, ay), mul(by, ax));
        let zero = _mm_setzero_ps();
        let any_zero = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(e0, zero), _mm_cmpeq_ps(e1, zero)), _mm_cmpeq_ps(e2, zero));
        let neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(e0, zero), _mm_cmplt_ps(e1, zero)), _mm_cmplt_ps(e2, zero));
        let pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(e0, zero), _mm_cmpgt_ps(e1, zero)), _mm_cmpgt_ps(e2, zero));
        let det = add(add(e0, e1), e2);
        let inv_det = _mm_div_ps(_mm_set1_ps(1.0), det);
        let tt = mul(add(add(mul(e0, az), mul(e1, bz)), mul(e2, cz)), inv_det);
        let uu = mul(e1, inv_det);
        let vv = mul(e2, inv_det);
        let abs_t = _mm_andnot_ps(_mm_set1_ps(-0.0), tt);
        let ok = _mm_andnot_ps(_mm_and_ps(neg, pos), _mm_cmpneq_ps(det, zero));
        let ok = _mm_and_ps(ok, _mm_cmplt_ps(abs_t, _mm_set1_ps(f32::INFINITY)));
        let ok =
            _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(tt, _mm_set1_ps(ray.t_min)), _mm_cmplt_ps(tt, _mm_set1_ps(*t_max))));
        (_mm_movemask_ps(ok) as u32 & lanes, _mm_movemask_ps(any_zero) as u32 & lanes, tt, uu, vv)
    };
    let mut m = mask | zero_lanes;
    if m == 0 {
        // Most groups: nothing hit, nothing to store.
        return false;
    }
    let (mut t, mut u, mut v) = ([0.0f32; 4], [0.0f32; 4], [0.0f32; 4]);
    // SAFETY: SSE is baseline; each array holds four floats.
    unsafe {
        _mm_storeu_ps(t.as_mut_ptr(), tt);
        _mm_storeu_ps(u.as_mut_ptr(), uu);
        _mm_storeu_ps(v.as_mut_ptr(), vv);
    }
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let hit = if zero_lanes & (1 << i) != 0 {
            intersect_triangle_watertight(&leaf.vertices(j + i), ray, *t_max)
        } else {
            (t[i] < *t_max).then_some((t[i], u[i], v[i]))
        };
        if let Some((t, u, v)) = hit
            && record_hit::<ANY_HIT>(Hit { prim: leaf.ids[j + i], t, u, v }, t_max, best)
        {
            return true;
        }
    }
    false
}
