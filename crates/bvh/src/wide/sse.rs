//! The SSE [`RayKernel`]: four boxes per `enter`, four triangles per step of a leaf, each
//! lane computing exactly what the scalar tests compute.

use super::Bvh4Node;
use super::kernel::{Leaf, RayKernel, record_hit};
use super::lanes::{BoxRay, watertight_group, watertight_groups};
use crate::{Hit, Ray, WatertightRay};
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
            // k·n + j ≤ 9n − 1 of `leaf.soa`, and the array has seven floats of padding
            // after the last leaf, so every 4-wide load stays inside it.
            let mask = unsafe {
                debug_assert!(leaf.soa.len() >= 9 * n + 7);
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
            // SAFETY: SSE is baseline; the tree pads its arrays for 8-wide loads.
            return unsafe { watertight_group::<__m128, ANY_HIT>(ray, leaf, 0, t_max, best) };
        }
        watertight_groups_sse::<ANY_HIT>(ray, leaf, t_max, best)
    }
}

/// The looped leaf test over a leaf of more than four triangles. Not inlined: inlined,
/// its loop changed how the whole traversal's registers were allocated, for 0.8 % and
/// 2.1 % more traversal instructions on the bunny's and Sponza's ray sets (1.6 % fewer on
/// the Cornell box's; callgrind), where such leaves are rare.
#[inline(never)]
fn watertight_groups_sse<const ANY_HIT: bool>(
    ray: &WatertightRay,
    leaf: Leaf,
    t_max: &mut f32,
    best: &mut Option<Hit>,
) -> bool {
    // SAFETY: SSE is baseline; the tree pads its arrays for 8-wide loads.
    unsafe { watertight_groups::<__m128, ANY_HIT>(ray, leaf, t_max, best) }
}
