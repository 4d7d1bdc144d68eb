//! The AVX [`RayKernel`] of the 8-wide tree: eight boxes per `enter` in one 256-bit
//! register per plane row; leaves are tested four triangles at a time by the SSE kernel.
//!
//! Only called from functions compiled with `#[target_feature(enable = "avx2")]` after a
//! run-time check ([`avx2_available`]), into which these `#[inline(always)]` methods are
//! inlined, so that the intrinsics compile to single instructions.

use super::Bvh8Node;
use super::kernel::{Leaf, RayKernel, plane_rows};
use super::sse::SseKernel;
use crate::{Hit, Ray, WatertightRay};
use std::arch::x86_64::*;

/// True if this CPU runs AVX2 (checked once by the standard library, then cached).
#[inline]
pub(super) fn avx2_available() -> bool {
    is_x86_feature_detected!("avx2")
}

/// The AVX [`RayKernel`] for 8-wide nodes.
pub(super) struct AvxKernel {
    origin: [__m256; 3],
    inv_dir: [__m256; 3],
    near: [usize; 3],
    far: [usize; 3],
    t_min: __m256,
    leaves: SseKernel,
}

impl RayKernel<8> for AvxKernel {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let (near, far) = plane_rows(ray.inv_dir);
        // SAFETY (all `unsafe` blocks here): the kernel is only used where AVX2 was
        // detected (see the module documentation).
        let splat = |v: glam::Vec3| unsafe { [_mm256_set1_ps(v.x), _mm256_set1_ps(v.y), _mm256_set1_ps(v.z)] };
        Self {
            origin: splat(ray.origin),
            inv_dir: splat(ray.inv_dir),
            near: near.map(|r| r * 8),
            far: far.map(|r| r * 8),
            t_min: unsafe { _mm256_set1_ps(ray.t_min) },
            leaves: <SseKernel as RayKernel<4>>::new(ray),
        }
    }

    /// As the SSE kernel's `enter`, on eight lanes (the same operations, so the same
    /// conventions for NaN and on-plane origins).
    #[inline(always)]
    fn enter(&self, node: &Bvh8Node, t_max: f32) -> (u32, [f32; 8]) {
        let base = node.planes().as_ptr().cast::<f32>();
        let mut t = [0.0f32; 8];
        // SAFETY: AVX is available (see `new`); a plane row is a multiple of 8 below 48,
        // i.e. a 32-byte-aligned row of the 64-byte-aligned node's six plane rows; `t`
        // has room for eight floats.
        let mask = unsafe {
            let slab = |row: usize, axis: usize| {
                let plane = _mm256_load_ps(base.add(row));
                _mm256_mul_ps(_mm256_sub_ps(plane, self.origin[axis]), self.inv_dir[axis])
            };
            // vmaxps/vminps return their second operand when either is NaN: the
            // accumulator, which is never NaN for a non-NaN t_min / t_max.
            let mut enter = self.t_min;
            let mut exit = _mm256_set1_ps(t_max);
            for axis in (0..3).rev() {
                enter = _mm256_max_ps(slab(self.near[axis], axis), enter);
                exit = _mm256_min_ps(slab(self.far[axis], axis), exit);
            }
            _mm256_storeu_ps(t.as_mut_ptr(), enter);
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32
        };
        (mask, t)
    }

    #[inline(always)]
    fn triangles<const ANY_HIT: bool>(&self, ray: &Ray, leaf: Leaf, t_max: &mut f32, best: &mut Option<Hit>) -> bool {
        <SseKernel as RayKernel<4>>::triangles::<ANY_HIT>(&self.leaves, ray, leaf, t_max, best)
    }

    #[inline(always)]
    fn watertight<const ANY_HIT: bool>(
        &self,
        ray: &WatertightRay,
        leaf: Leaf,
        t_max: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        <SseKernel as RayKernel<4>>::watertight::<ANY_HIT>(&self.leaves, ray, leaf, t_max, best)
    }
}
