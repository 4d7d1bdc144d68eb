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
use std::arch::x86_64::__m256;

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
