//! The ray kernels: a ray prepared for testing a wide node's `W` boxes at once and a
//! leaf's triangles ([`RayKernel`]), and the portable [`ScalarKernel`]. The SSE kernel
//! (4 lanes, x86_64 baseline) is in `sse`, the AVX2 one (8 lanes, chosen at run time) in
//! `avx`.

use super::WideNode;
use crate::{Hit, Ray, Triangle, WatertightRay, intersect_triangle, intersect_triangle_watertight};
use glam::Vec3;

/// A ray prepared for testing the `W` boxes of a [`WideNode`] at once, and a leaf's
/// triangles.
///
/// Box conventions as in `SlabRay::enter` and [`Aabb::hit`](crate::Aabb::hit): closed boxes, entry in
/// (t_min, ∞) ∩ (−∞, t_max], and an origin on a slab plane with a zero direction component
/// (0·∞ = NaN) counts as inside that slab. The near and far planes are picked per axis by
/// the sign of the reciprocal direction (so −0 picks the max plane first), and every
/// slab distance is folded into an accumulator that starts at t_min or t_max with an
/// operation that keeps the accumulator when the distance is NaN, which ignores
/// exactly the on-plane slabs. Picking planes by sign also makes an unused slot's
/// inverted box (+∞, −∞) give an entry of +∞ and an exit of −∞ on every axis.
pub(super) trait RayKernel<const W: usize> {
    fn new(ray: &Ray) -> Self;

    /// The ray's set-up for the watertight test: [`WatertightRay::new`], which a kernel
    /// may compute faster with its instructions, to the same bits.
    #[inline(always)]
    fn watertight_ray(ray: &Ray) -> WatertightRay {
        WatertightRay::new(ray)
    }

    /// Bit `i` set if the ray enters child `i`'s box within (t_min, t_max]; lane `i` of
    /// the array is then its entry distance.
    fn enter(&self, node: &WideNode<W>, t_max: f32) -> (u32, [f32; W]);

    /// Tests a leaf's triangles in order as [`intersect_triangle`] would, lowering
    /// `t_max` and setting `best` at each closer hit; with `ANY_HIT`, returns true at the
    /// first hit.
    fn triangles<const ANY_HIT: bool>(&self, ray: &Ray, leaf: Leaf, t_max: &mut f32, best: &mut Option<Hit>) -> bool {
        let n = leaf.ids.len();
        for (i, &prim) in leaf.ids.iter().enumerate() {
            let row =
                |k: usize| [leaf.soa[3 * k * n + i], leaf.soa[(3 * k + 1) * n + i], leaf.soa[(3 * k + 2) * n + i]];
            let tri = Triangle::new(&[0, 1, 2].map(|k| Vec3::from_array(row(k))));
            if let Some((t, u, v)) = intersect_triangle(&tri, ray, *t_max)
                && record_hit::<ANY_HIT>(Hit { prim, t, u, v }, t_max, best)
            {
                return true;
            }
        }
        false
    }

    /// As [`RayKernel::triangles`] with the watertight test.
    #[inline(always)]
    fn watertight<const ANY_HIT: bool>(
        &self,
        ray: &WatertightRay,
        leaf: Leaf,
        t_max: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        for (i, &prim) in leaf.ids.iter().enumerate() {
            if let Some((t, u, v)) =
                intersect_triangle_watertight(&leaf.vertices(i), ray, tie_bound(*t_max, best.is_some()))
                && closer(t, prim, *t_max, best)
                && record_hit::<ANY_HIT>(Hit { prim, t, u, v }, t_max, best)
            {
                return true;
            }
        }
        false
    }
}

/// Whether a hit at `t` on triangle `prim` replaces the closest so far: nearer than
/// `t_max`, or — with a closest hit `best` at `t_max` — as near and of a lower triangle
/// index. The tie rule makes the closest hit independent of the order in which a
/// traversal meets the triangles (a packet's walk and a single ray's differ), so that
/// both return the same triangle where two share a t (a shared edge, coplanar copies).
#[inline(always)]
pub(super) fn closer(t: f32, prim: u32, t_max: f32, best: &Option<Hit>) -> bool {
    closer_than(t, prim, t_max, best.is_some(), best.map_or(u32::MAX, |b| b.prim))
}

/// [`closer`] with the closest hit so far given as whether there is one (`found`) and its
/// triangle (`best_prim`): the form a packet's lanes keep.
#[inline(always)]
pub(super) fn closer_than(t: f32, prim: u32, t_max: f32, found: bool, best_prim: u32) -> bool {
    t < t_max || (found && t == t_max && prim < best_prim)
}

/// The strict upper bound to hand a triangle test so that it also reports a tie with the
/// closest hit so far (one ulp above `t_max` where there is one, `found`; [`closer`]
/// decides).
#[inline(always)]
pub(super) fn tie_bound(t_max: f32, found: bool) -> f32 {
    if found { t_max.next_up() } else { t_max }
}

/// Makes `hit` the closest so far (its t the new `t_max`); true if that ends the query
/// (`ANY_HIT`).
#[inline(always)]
pub(super) fn record_hit<const ANY_HIT: bool>(hit: Hit, t_max: &mut f32, best: &mut Option<Hit>) -> bool {
    *t_max = hit.t;
    *best = Some(hit);
    ANY_HIT
}

impl Leaf<'_> {
    /// The vertices of the leaf's `i`-th triangle.
    #[inline(always)]
    pub(super) fn vertices(&self, i: usize) -> [Vec3; 3] {
        let n = self.ids.len();
        let c = |row: usize| self.soa[row * n + i];
        [Vec3::new(c(0), c(1), c(2)), Vec3::new(c(3), c(4), c(5)), Vec3::new(c(6), c(7), c(8))]
    }
}

/// A leaf's triangles as [`RayKernel::triangles`] sees them: `soa` from the leaf's first
/// float to the end of the array, `ids` the triangles' input indices.
#[derive(Clone, Copy)]
pub(super) struct Leaf<'a> {
    pub(super) soa: &'a [f32],
    pub(super) ids: &'a [u32],
}

/// Plane rows of [`Bvh4Node::planes`] to use for the near and far planes on each axis.
#[inline(always)]
pub(super) fn plane_rows(inv_dir: Vec3) -> ([usize; 3], [usize; 3]) {
    let neg = inv_dir.is_negative_bitmask() as usize;
    let near = std::array::from_fn(|a| a + 3 * ((neg >> a) & 1));
    let far = std::array::from_fn(|a| a + 3 * (1 - ((neg >> a) & 1)));
    (near, far)
}

/// The portable [`RayKernel`]: `W` lanes in scalar code.
pub(super) struct ScalarKernel {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    near: [usize; 3],
    far: [usize; 3],
    t_min: f32,
}

impl<const W: usize> RayKernel<W> for ScalarKernel {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let (near, far) = plane_rows(ray.inv_dir);
        Self { origin: ray.origin.to_array(), inv_dir: ray.inv_dir.to_array(), near, far, t_min: ray.t_min }
    }

    #[inline(always)]
    fn enter(&self, node: &WideNode<W>, t_max: f32) -> (u32, [f32; W]) {
        // SSE's maxps/minps: the second operand unless the first is strictly greater
        // (smaller), so a NaN first operand yields the second.
        let max = |a: f32, acc: f32| if a > acc { a } else { acc };
        let min = |a: f32, acc: f32| if a < acc { a } else { acc };
        let planes = node.planes();
        let mut mask = 0;
        let mut t = [0.0; W];
        for lane in 0..W {
            let (mut enter, mut exit) = (self.t_min, t_max);
            for axis in (0..3).rev() {
                let near = (planes[self.near[axis]][lane] - self.origin[axis]) * self.inv_dir[axis];
                let far = (planes[self.far[axis]][lane] - self.origin[axis]) * self.inv_dir[axis];
                enter = max(near, enter);
                exit = min(far, exit);
            }
            t[lane] = enter;
            mask |= ((enter <= exit) as u32) << lane;
        }
        (mask, t)
    }
}
