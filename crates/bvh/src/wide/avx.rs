//! The AVX [`RayKernel`] of the 8-wide tree: eight boxes per `enter` in one 256-bit
//! register per plane row (the box test of `lanes`); the watertight leaf test runs eight
//! triangles at a time (the same generic group as the SSE kernel's four), the
//! Möller–Trumbore one four at a time by the SSE kernel.
//!
//! Only called from functions compiled with `#[target_feature(enable = "avx2")]` after a
//! run-time check ([`crate::isa::active`]), into which these `#[inline(always)]` methods are
//! inlined, so that the intrinsics compile to single instructions.

use super::Bvh8Node;
use super::kernel::{Leaf, RayKernel};
use super::lanes::{BoxRay, watertight_group, watertight_groups};
use super::sse::SseKernel;
use crate::{Hit, Ray, WatertightRay};
use std::arch::x86_64::*;

/// The AVX [`RayKernel`] for 8-wide nodes.
pub(super) struct AvxKernel {
    boxes: BoxRay<__m256>,
    leaves: SseKernel,
}

impl RayKernel<8> for AvxKernel {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        // SAFETY: the kernel is only used where AVX2 was detected (see the module
        // documentation).
        Self { boxes: unsafe { BoxRay::new(ray) }, leaves: <SseKernel as RayKernel<4>>::new(ray) }
    }

    /// The SSE kernel's box test on eight lanes (the same operations, so the same
    /// conventions for NaN and on-plane origins).
    #[inline(always)]
    fn enter(&self, node: &Bvh8Node, t_max: f32) -> (u32, [f32; 8]) {
        // SAFETY: AVX is available (see `new`), and the node is 8 wide.
        unsafe { self.boxes.enter(node, t_max) }
    }

    #[inline(always)]
    fn watertight_ray(ray: &Ray) -> WatertightRay {
        // SAFETY: as in `new`.
        unsafe { watertight_ray(ray) }
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
        // Leaves of up to eight triangles (all that the default build makes) run one
        // group without a loop; larger ones go to the looped function, out of line as
        // the SSE kernel's.
        if leaf.ids.len() <= 8 {
            // SAFETY: AVX is available (see `new`); the tree pads its arrays for 8-wide
            // loads.
            return unsafe { watertight_group::<__m256, ANY_HIT>(ray, leaf, 0, t_max, best) };
        }
        // SAFETY: as above.
        unsafe { watertight_groups_avx::<ANY_HIT>(ray, leaf, t_max, best) }
    }
}

/// The looped leaf test for leaves of more than eight triangles.
///
/// # Safety
///
/// The CPU must have AVX2.
#[inline(never)]
#[target_feature(enable = "avx2")]
unsafe fn watertight_groups_avx<const ANY_HIT: bool>(
    ray: &WatertightRay,
    leaf: Leaf,
    t_max: &mut f32,
    best: &mut Option<Hit>,
) -> bool {
    // SAFETY: the caller's guarantee; the tree pads its arrays for 8-wide loads.
    unsafe { watertight_groups::<__m256, ANY_HIT>(ray, leaf, t_max, best) }
}

/// The permutation `[kx, ky, kz, 3]` of [`WatertightRay::new`] for the dominant axis kz
/// (entries 2·kz and 2·kz + 1) and whether the direction points along −kz, which swaps kx
/// and ky (the odd entries): the index vector of `vpermilps`, lane 3 left in place.
const PERMUTATIONS: [[i32; 4]; 6] =
    [[1, 2, 0, 3], [2, 1, 0, 3], [2, 0, 1, 3], [0, 2, 1, 3], [0, 1, 2, 3], [1, 0, 2, 3]];

/// [`WatertightRay::new`] with the permutation applied to the direction and the origin
/// by one `vpermilps` each, its index vector read from a table, instead of by selects
/// among the three cyclic shifts (about a hundred instructions of blends per ray with
/// AVX2). The shear's quotients have the same operands as there, so the same bits
/// (`tests::the_avx_watertight_ray_is_the_portable_one`). They are divided after the
/// permutation: dividing every candidate axis's quotients first, as there, and picking
/// lane z′ of each cost 0.7–2.6 % more traversal instructions
/// (`bench/patches/early-shear-division.patch`, docs/figures.md).
///
/// # Safety
///
/// The CPU must have AVX (and SSE4.1, which it implies).
#[inline(always)]
pub(super) unsafe fn watertight_ray(ray: &Ray) -> WatertightRay {
    let (d, o) = (ray.dir, ray.origin);
    let (x_dominant, y_dominant) = crate::triangle::dominant_axis(d);
    let kz = 2 - 2 * x_dominant as usize - y_dominant as usize;
    // SAFETY: the caller's guarantee; the table's entries are in 0..4.
    unsafe {
        let dv = _mm_setr_ps(d.x, d.y, d.z, 0.0);
        // `d[kz] < 0.0` as there (−0 does not flip).
        let negative = _mm_movemask_ps(_mm_cmplt_ps(dv, _mm_setzero_ps())) as usize;
        let k = &PERMUTATIONS[2 * kz + ((negative >> kz) & 1)];
        let index = _mm_loadu_si128(k.as_ptr().cast());
        let dp = _mm_permutevar_ps(dv, index);
        let op = _mm_permutevar_ps(_mm_setr_ps(o.x, o.y, o.z, 0.0), index);
        // (d[kx], d[ky], 1) / d[kz].
        let shear = _mm_div_ps(_mm_blend_ps::<0b0100>(dp, _mm_set1_ps(1.0)), _mm_shuffle_ps::<0b1010_1010>(dp, dp));
        let (mut s, mut origin) = ([0.0f32; 4], [0.0f32; 4]);
        _mm_storeu_ps(s.as_mut_ptr(), shear);
        _mm_storeu_ps(origin.as_mut_ptr(), op);
        WatertightRay {
            origin: [origin[0], origin[1], origin[2]],
            k: [k[0] as usize, k[1] as usize, k[2] as usize],
            shear: [s[0], s[1], s[2]],
            t_min: ray.t_min,
        }
    }
}
