//! The SIMD box test, written once for both register widths: [`Lanes`] is the handful of
//! operations it needs, implemented for SSE's `__m128` (4 lanes, the [`Bvh4`](super::Bvh4)
//! kernel) and AVX's `__m256` (8 lanes, the [`Bvh8`](super::Bvh8) kernel), and [`BoxRay`]
//! a ray prepared for testing a node's boxes with them.

use super::WideNode;
use super::kernel::plane_rows;
use crate::Ray;
use std::arch::x86_64::*;

/// A register of f32 lanes.
///
/// # Safety
///
/// Every method runs the register's instructions: callers must make sure the CPU has them
/// (SSE is x86_64 baseline; AVX is checked at run time, see `avx`).
pub(super) trait Lanes: Copy {
    /// Lanes per register.
    const WIDTH: usize;
    unsafe fn splat(x: f32) -> Self;
    /// An aligned load of `WIDTH` floats.
    unsafe fn load(p: *const f32) -> Self;
    unsafe fn store(self, p: *mut f32);
    unsafe fn sub(self, o: Self) -> Self;
    unsafe fn mul(self, o: Self) -> Self;
    /// `maxps`: `self` if it is greater than `o`, else `o` (also when either is NaN).
    unsafe fn max(self, o: Self) -> Self;
    /// `minps`: `self` if it is less than `o`, else `o` (also when either is NaN).
    unsafe fn min(self, o: Self) -> Self;
    /// Bit `i` set where lane `i` of `self` ≤ `o` (ordered: false for NaN).
    unsafe fn le_mask(self, o: Self) -> u32;
}

impl Lanes for __m128 {
    const WIDTH: usize = 4;
    #[inline(always)]
    unsafe fn splat(x: f32) -> Self {
        unsafe { _mm_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> Self {
        unsafe { _mm_load_ps(p) }
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut f32) {
        unsafe { _mm_storeu_ps(p, self) }
    }
    #[inline(always)]
    unsafe fn sub(self, o: Self) -> Self {
        unsafe { _mm_sub_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn mul(self, o: Self) -> Self {
        unsafe { _mm_mul_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn max(self, o: Self) -> Self {
        unsafe { _mm_max_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn min(self, o: Self) -> Self {
        unsafe { _mm_min_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn le_mask(self, o: Self) -> u32 {
        unsafe { _mm_movemask_ps(_mm_cmple_ps(self, o)) as u32 }
    }
}

impl Lanes for __m256 {
    const WIDTH: usize = 8;
    #[inline(always)]
    unsafe fn splat(x: f32) -> Self {
        unsafe { _mm256_set1_ps(x) }
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> Self {
        unsafe { _mm256_load_ps(p) }
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut f32) {
        unsafe { _mm256_storeu_ps(p, self) }
    }
    #[inline(always)]
    unsafe fn sub(self, o: Self) -> Self {
        unsafe { _mm256_sub_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn mul(self, o: Self) -> Self {
        unsafe { _mm256_mul_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn max(self, o: Self) -> Self {
        unsafe { _mm256_max_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn min(self, o: Self) -> Self {
        unsafe { _mm256_min_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn le_mask(self, o: Self) -> u32 {
        unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(self, o)) as u32 }
    }
}

/// A ray prepared for testing the boxes of a node whose width is `L::WIDTH`, with the
/// conventions of [`RayKernel::enter`](super::kernel::RayKernel::enter).
#[derive(Clone, Copy)]
pub(super) struct BoxRay<L> {
    pub(super) origin: [L; 3],
    inv_dir: [L; 3],
    /// First float of the near and far plane row on each axis.
    near: [usize; 3],
    far: [usize; 3],
    pub(super) t_min: L,
}

impl<L: Lanes> BoxRay<L> {
    /// # Safety
    ///
    /// The CPU must run `L`'s instructions.
    #[inline(always)]
    pub(super) unsafe fn new(ray: &Ray) -> Self {
        let (near, far) = plane_rows(ray.inv_dir);
        // SAFETY (here and in `enter`): the caller's guarantee.
        let splat = |v: glam::Vec3| unsafe { [L::splat(v.x), L::splat(v.y), L::splat(v.z)] };
        Self {
            origin: splat(ray.origin),
            inv_dir: splat(ray.inv_dir),
            near: near.map(|r| r * L::WIDTH),
            far: far.map(|r| r * L::WIDTH),
            t_min: unsafe { L::splat(ray.t_min) },
        }
    }

    /// Bit `i` set if the ray enters child `i`'s box within (t_min, t_max]; lane `i` of
    /// the array is then its entry distance.
    ///
    /// # Safety
    ///
    /// The CPU must run `L`'s instructions, and `W` must be `L::WIDTH`.
    #[inline(always)]
    pub(super) unsafe fn enter<const W: usize>(&self, node: &WideNode<W>, t_max: f32) -> (u32, [f32; W]) {
        debug_assert_eq!(W, L::WIDTH);
        let base = node.planes().as_ptr().cast::<f32>();
        let mut t = [0.0f32; W];
        // SAFETY: a plane row starts at a multiple of W below 6W, i.e. a (4W)-byte-aligned
        // row of the 64-byte-aligned node's six plane rows; `t` has room for W floats.
        unsafe {
            let slab = |row: usize, axis: usize| L::load(base.add(row)).sub(self.origin[axis]).mul(self.inv_dir[axis]);
            // max/min return their second operand when either is NaN: the accumulator,
            // which is never NaN for a non-NaN t_min / t_max.
            let mut enter = self.t_min;
            let mut exit = L::splat(t_max);
            for axis in (0..3).rev() {
                enter = slab(self.near[axis], axis).max(enter);
                exit = slab(self.far[axis], axis).min(exit);
            }
            enter.store(t.as_mut_ptr());
            (enter.le_mask(exit), t)
        }
    }
}
