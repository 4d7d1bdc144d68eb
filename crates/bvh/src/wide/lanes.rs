//! The SIMD box test and watertight leaf test, written once for both register widths:
//! [`Lanes`] is the handful of operations they need, implemented for SSE's `__m128` (4
//! lanes, the [`Bvh4`](super::Bvh4) kernel) and AVX's `__m256` (8 lanes, the
//! [`Bvh8`](super::Bvh8) kernel); [`BoxRay`] is a ray prepared for testing a node's boxes
//! with them, [`watertight_group`] the test of a leaf's triangles `L::WIDTH` at a time.

use super::WideNode;
use super::kernel::{Leaf, closer, plane_rows, record_hit, tie_bound};
use crate::{Hit, Ray, WatertightRay, intersect_triangle_watertight};
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
    /// An unaligned load of `WIDTH` floats.
    unsafe fn load_unaligned(p: *const f32) -> Self;
    unsafe fn add(self, o: Self) -> Self;
    unsafe fn div(self, o: Self) -> Self;
    unsafe fn or(self, o: Self) -> Self;
    unsafe fn and(self, o: Self) -> Self;
    /// `!self & o`, bit by bit.
    unsafe fn and_not(self, o: Self) -> Self;
    /// All bits set where `self == o` (ordered), else clear.
    unsafe fn eq(self, o: Self) -> Self;
    /// All bits set where `self != o` or either is NaN (unordered), else clear.
    unsafe fn ne(self, o: Self) -> Self;
    /// All bits set where `self < o` (ordered), else clear.
    unsafe fn lt(self, o: Self) -> Self;
    /// All bits set where `self <= o` (ordered), else clear.
    unsafe fn le(self, o: Self) -> Self;
    /// All bits set where `self > o` (ordered), else clear.
    unsafe fn gt(self, o: Self) -> Self;
    /// The lanes' sign bits, lane `i` in bit `i`.
    unsafe fn sign_mask(self) -> u32;
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
    #[inline(always)]
    unsafe fn load_unaligned(p: *const f32) -> Self {
        unsafe { _mm_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn add(self, o: Self) -> Self {
        unsafe { _mm_add_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn div(self, o: Self) -> Self {
        unsafe { _mm_div_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn or(self, o: Self) -> Self {
        unsafe { _mm_or_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn and(self, o: Self) -> Self {
        unsafe { _mm_and_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn and_not(self, o: Self) -> Self {
        unsafe { _mm_andnot_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn eq(self, o: Self) -> Self {
        unsafe { _mm_cmpeq_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn ne(self, o: Self) -> Self {
        unsafe { _mm_cmpneq_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn lt(self, o: Self) -> Self {
        unsafe { _mm_cmplt_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn le(self, o: Self) -> Self {
        unsafe { _mm_cmple_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn gt(self, o: Self) -> Self {
        unsafe { _mm_cmpgt_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn sign_mask(self) -> u32 {
        unsafe { _mm_movemask_ps(self) as u32 }
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
    #[inline(always)]
    unsafe fn load_unaligned(p: *const f32) -> Self {
        unsafe { _mm256_loadu_ps(p) }
    }
    #[inline(always)]
    unsafe fn add(self, o: Self) -> Self {
        unsafe { _mm256_add_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn div(self, o: Self) -> Self {
        unsafe { _mm256_div_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn or(self, o: Self) -> Self {
        unsafe { _mm256_or_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn and(self, o: Self) -> Self {
        unsafe { _mm256_and_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn and_not(self, o: Self) -> Self {
        unsafe { _mm256_andnot_ps(self, o) }
    }
    #[inline(always)]
    unsafe fn eq(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn ne(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_NEQ_UQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn lt(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn le(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn gt(self, o: Self) -> Self {
        unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self, o) }
    }
    #[inline(always)]
    unsafe fn sign_mask(self) -> u32 {
        unsafe { _mm256_movemask_ps(self) as u32 }
    }
}

/// A ray prepared for testing the boxes of a node whose width is `L::WIDTH`, with the
/// conventions of [`RayKernel::enter`](super::kernel::RayKernel::enter).
#[derive(Clone, Copy)]
pub(super) struct BoxRay<L> {
    pub(super) origin: [L; 3],
    /// −1/d: the slab distance is computed as (origin − plane)·(−1/d), which lets the
    /// plane's load be the subtraction's memory operand and is (plane − origin)·(1/d) to
    /// the bit (both roundings are sign-symmetric) but for the sign of a zero distance
    /// (x − x is +0 either way round), which no comparison tells apart and which is never
    /// returned: the masks and the visit order are the same.
    neg_inv_dir: [L; 3],
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
            neg_inv_dir: splat(-ray.inv_dir),
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
            let slab =
                |row: usize, axis: usize| self.origin[axis].sub(L::load(base.add(row))).mul(self.neg_inv_dir[axis]);
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

/// Tests triangles `j..j + L::WIDTH` (those of them in the leaf) of `leaf` at once, lane
/// by lane the operations of `intersect_triangle_watertight` (bit-identical: no fused
/// multiply-adds), lowering `t_max` and setting `best` at each closer hit in lane order;
/// with `ANY_HIT`, returns true at the first hit. A lane with an edge function of exactly
/// zero is redone by the scalar test, which falls back to double precision. A function,
/// not a closure, so that it is inlined into the AVX2 traversal (a closure was compiled
/// apart, without AVX).
///
/// # Safety
///
/// The CPU must run `L`'s instructions, and `leaf.soa` must hold `L::WIDTH − 1` floats
/// past the leaf's last row (the tree's padding).
#[inline(always)]
pub(super) unsafe fn watertight_group<L: Lanes, const ANY_HIT: bool>(
    ray: &WatertightRay,
    leaf: Leaf,
    j: usize,
    t_max: &mut f32,
    best: &mut Option<Hit>,
) -> bool {
    let n = leaf.ids.len();
    let [kx, ky, kz] = ray.k;
    let lanes = (u32::MAX >> (32 - L::WIDTH)) >> L::WIDTH.saturating_sub(n - j);
    // SAFETY: the caller's guarantees; row k of this group starts at float k·n + j ≤
    // 9n − 1 of `leaf.soa`, so every load ends inside the padding.
    let (mask, zero_lanes, tt, uu, vv) = unsafe {
        debug_assert!(leaf.soa.len() >= 9 * n + L::WIDTH - 1);
        // Row 3v + k starts at float (3v + k)·n: three offsets for the axes and one
        // base per vertex, rather than nine products. (No closures: those would be
        // compiled apart from the AVX2 traversal, without AVX.)
        let rows = [kx * n, ky * n, kz * n];
        let shear = [L::splat(ray.shear[0]), L::splat(ray.shear[1]), L::splat(ray.shear[2])];
        let origin = [L::splat(ray.origin[0]), L::splat(ray.origin[1]), L::splat(ray.origin[2])];
        let first = leaf.soa.as_ptr().add(j);
        let (ax, ay, az) = sheared_vertex(first, rows, origin, shear);
        let (bx, by, bz) = sheared_vertex(first.add(3 * n), rows, origin, shear);
        let (cx, cy, cz) = sheared_vertex(first.add(6 * n), rows, origin, shear);
        let e0 = cx.mul(by).sub(cy.mul(bx));
        let e1 = ax.mul(cy).sub(ay.mul(cx));
        let e2 = bx.mul(ay).sub(by.mul(ax));
        let zero = L::splat(0.0);
        let any_zero = e0.eq(zero).or(e1.eq(zero)).or(e2.eq(zero));
        let neg = e0.lt(zero).or(e1.lt(zero)).or(e2.lt(zero));
        let pos = e0.gt(zero).or(e1.gt(zero)).or(e2.gt(zero));
        let det = e0.add(e1).add(e2);
        let inv_det = L::splat(1.0).div(det);
        let tt = e0.mul(az).add(e1.mul(bz)).add(e2.mul(cz)).mul(inv_det);
        let uu = e1.mul(inv_det);
        let vv = e2.mul(inv_det);
        let abs_t = L::splat(-0.0).and_not(tt);
        let ok = neg.and(pos).and_not(det.ne(zero));
        let ok = ok.and(abs_t.lt(L::splat(f32::INFINITY)));
        // t ≤ t_max (not <): a tie with the closest hit so far goes to `closer`.
        let ok = ok.and(tt.gt(L::splat(ray.t_min)).and(tt.le(L::splat(*t_max))));
        (ok.sign_mask() & lanes, any_zero.sign_mask() & lanes, tt, uu, vv)
    };
    let mut m = mask | zero_lanes;
    if m == 0 {
        // Most groups: nothing hit, nothing to store.
        return false;
    }
    const { assert!(L::WIDTH <= 8, "the stores below hold eight lanes") };
    let (mut t, mut u, mut v) = ([0.0f32; 8], [0.0f32; 8], [0.0f32; 8]);
    // SAFETY: the caller's guarantee; each array holds at least `L::WIDTH` floats.
    unsafe {
        tt.store(t.as_mut_ptr());
        uu.store(u.as_mut_ptr());
        vv.store(v.as_mut_ptr());
    }
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        let hit = if zero_lanes & (1 << i) != 0 {
            intersect_triangle_watertight(&leaf.vertices(j + i), ray, tie_bound(*t_max, best.is_some()))
        } else {
            Some((t[i], u[i], v[i]))
        };
        let prim = leaf.ids[j + i];
        if let Some((t, u, v)) = hit
            && closer(t, prim, *t_max, best)
            && record_hit::<ANY_HIT>(Hit { prim, t, u, v }, t_max, best)
        {
            return true;
        }
    }
    false
}

/// A group's vertex (its rows starting at `base`, the permuted axes' rows `rows` floats
/// further) relative to the ray origin, permuted and sheared as in
/// `intersect_triangle_watertight` — with x and y negated. Their differences are taken as
/// origin minus vertex, so that each load is the subtraction's memory operand, and that is
/// the negated difference to the bit but for the sign of a zero; so x and y are the scalar
/// test's negated, up to the sign of a zero, and the edge functions, products of two of
/// them, are the scalar test's to the bit where they are not zero (a lane with a zero edge
/// function is redone by the scalar test). z, which t is computed from, keeps the scalar
/// test's order (vertex minus origin): its zero's sign would reach a t of zero.
///
/// # Safety
///
/// The CPU must run `L`'s instructions, and `L::WIDTH` floats must be readable at each
/// row.
#[inline(always)]
unsafe fn sheared_vertex<L: Lanes>(base: *const f32, rows: [usize; 3], origin: [L; 3], shear: [L; 3]) -> (L, L, L) {
    // SAFETY: the caller's guarantees.
    unsafe {
        let qx = origin[0].sub(L::load_unaligned(base.add(rows[0])));
        let qy = origin[1].sub(L::load_unaligned(base.add(rows[1])));
        let pz = L::load_unaligned(base.add(rows[2])).sub(origin[2]);
        // −(p_x − o_x − S_x p_z) = (o_x − p_x) + S_x p_z, as rounding is sign-symmetric.
        (qx.add(shear[0].mul(pz)), qy.add(shear[1].mul(pz)), shear[2].mul(pz))
    }
}

/// [`watertight_group`] over every group of a leaf, in order.
///
/// # Safety
///
/// As [`watertight_group`].
#[inline(always)]
pub(super) unsafe fn watertight_groups<L: Lanes, const ANY_HIT: bool>(
    ray: &WatertightRay,
    leaf: Leaf,
    t_max: &mut f32,
    best: &mut Option<Hit>,
) -> bool {
    for j in (0..leaf.ids.len()).step_by(L::WIDTH) {
        // SAFETY: the caller's guarantees.
        if unsafe { watertight_group::<L, ANY_HIT>(ray, leaf, j, t_max, best) } {
            return true;
        }
    }
    false
}
