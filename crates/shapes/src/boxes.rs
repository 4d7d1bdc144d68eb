//! Boxes (cuboids), axis-aligned or oriented, intersected by the slab method (lecture
//! slides "Schnitt Strahl — Box"; Kay & Kajiya, "Ray Tracing Complex Scenes", SIGGRAPH
//! 1986; Williams, Barrus, Morley & Shirley, "An Efficient and Robust Ray–Box
//! Intersection Algorithm", JGT 10(1), 2005).
//!
//! The slides note that the slab method works unchanged for oriented boxes (OBBs): the
//! ray is expressed in the box's frame, where the box is [−h, h]³. An axis-aligned box
//! skips that transform entirely and runs the slab test on its world-space corners, so
//! its plane parameters are as exact as f32 allows.

use crate::{Aabb, Ray, Shape, ShapeError, SurfaceHit};
use glam::{Quat, Vec2, Vec3};

/// (entry t, exit t, entry axis, exit axis), as returned by [`slab`].
type SlabHit = (f32, f32, usize, usize);

/// A solid box: centre, half extents along its three orthonormal axes. Both the inside
/// and the outside of the surface are hit; the normal points outward.
///
/// Fields are private to keep the invariants (orthonormal axes, positive extents, the
/// axis-aligned flag matching the axes, exact corners for the axis-aligned case); build
/// it with [`Cuboid::axis_aligned`] or [`Cuboid::oriented`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    centre: Vec3,
    half_extent: Vec3,
    axes: [Vec3; 3],
    /// Axes are exactly the world axes: then `min`/`max` are the exact world corners and
    /// no frame transform is applied to rays.
    axis_aligned: bool,
    min: Vec3,
    max: Vec3,
}

impl Cuboid {
    /// The axis-aligned box [min, max] (an AABB, the slides' case). `min < max` in every
    /// component, all finite. The corners are kept exactly as given: rays are tested
    /// against them directly, without a local frame, so a ray with power-of-two direction
    /// components gets exact plane distances.
    pub fn axis_aligned(min: Vec3, max: Vec3) -> Result<Self, ShapeError> {
        if !min.is_finite() || !max.is_finite() {
            return Err(ShapeError::Invalid(format!("box corners {min}, {max} are not finite")));
        }
        if !min.cmplt(max).all() {
            return Err(ShapeError::Invalid(format!("box min {min} must be < max {max} in every axis")));
        }
        let half_extent = 0.5 * (max - min);
        if !half_extent.is_finite() || !half_extent.cmpgt(Vec3::ZERO).all() {
            return Err(ShapeError::Invalid(format!("box extent {} is out of range", max - min)));
        }
        let centre = 0.5 * min + 0.5 * max;
        Ok(Self { centre, half_extent, axes: [Vec3::X, Vec3::Y, Vec3::Z], axis_aligned: true, min, max })
    }

    /// An oriented box (OBB): its local frame is `rotation` applied to the world axes,
    /// and it spans ±`half_extent` along them around `centre`. The quaternion must be
    /// finite and normalised (glam's `is_normalized`, |‖q‖² − 1| ≤ 2·10⁻⁴… within its
    /// tolerance) so that the axes are orthonormal and the frame change is a rotation. A
    /// rotation that leaves the axes exactly unchanged (the identity, −identity) makes
    /// an axis-aligned box.
    pub fn oriented(centre: Vec3, half_extent: Vec3, rotation: Quat) -> Result<Self, ShapeError> {
        if !centre.is_finite() {
            return Err(ShapeError::Invalid(format!("box centre {centre} is not finite")));
        }
        if !half_extent.is_finite() || !half_extent.cmpgt(Vec3::ZERO).all() {
            return Err(ShapeError::Invalid(format!("box half extent {half_extent} must be finite and > 0")));
        }
        if !rotation.is_finite() || !rotation.is_normalized() {
            return Err(ShapeError::Invalid(format!("box rotation {rotation} is not a unit quaternion")));
        }
        let axes = [rotation * Vec3::X, rotation * Vec3::Y, rotation * Vec3::Z];
        let axis_aligned = axes == [Vec3::X, Vec3::Y, Vec3::Z];
        let (min, max) = (centre - half_extent, centre + half_extent);
        if !min.is_finite() || !max.is_finite() {
            return Err(ShapeError::Invalid("box corners overflow".into()));
        }
        Ok(Self { centre, half_extent, axes, axis_aligned, min, max })
    }

    /// Centre.
    pub fn centre(&self) -> Vec3 {
        self.centre
    }

    /// Half extents along [`Cuboid::axes`].
    pub fn half_extent(&self) -> Vec3 {
        self.half_extent
    }

    /// The box's orthonormal local axes in world space.
    pub fn axes(&self) -> [Vec3; 3] {
        self.axes
    }

    /// True if the axes are exactly the world axes (no frame transform for rays).
    pub fn is_axis_aligned(&self) -> bool {
        self.axis_aligned
    }

    /// World → local: the components of `v` along the three axes (Rᵀv).
    #[inline]
    fn local_of(&self, v: Vec3) -> Vec3 {
        Vec3::new(self.axes[0].dot(v), self.axes[1].dot(v), self.axes[2].dot(v))
    }

    /// Local → world: Rv.
    #[inline]
    fn world_of(&self, v: Vec3) -> Vec3 {
        self.axes[0] * v.x + self.axes[1] * v.y + self.axes[2] * v.z
    }

    /// Slab test in the frame where the box is [lo, hi]: (entry, exit, entry axis, exit
    /// axis), unclamped.
    #[inline]
    fn slab_frame(&self, ray: &Ray) -> Option<(Vec3, Vec3, SlabHit)> {
        if self.axis_aligned {
            let s = slab_bounds(ray.origin, ray.inv_dir, self.min, self.max, ray.t_min, ray.t_max)?;
            Some((ray.origin, ray.dir, s))
        } else {
            let o = self.local_of(ray.origin - self.centre);
            let d = self.local_of(ray.dir);
            let s = slab(o, d, self.half_extent, ray.t_min, ray.t_max)?;
            Some((o, d, s))
        }
    }
}

/// Slab test for the box [−half, half]³ in its own frame (Kay & Kajiya 1986; Williams
/// et al. 2005). Returns `(t_entry, t_exit, entry_axis, exit_axis)`: the parameters where
/// the ray's line enters and leaves the closed box, *not* clamped to (t_min, t_max) (so
/// t_entry ≤ t_min means the origin is inside or the box is behind), and the axes whose
/// planes give them. `None` if the line misses the box or the box interval [t_entry,
/// t_exit] does not meet the open interval (t_min, t_max).
///
/// Cases, as the slides warn ("Achtung: teste auf Parallelität!"):
/// * Reciprocal directions `1/d` are used (Williams et al.): a zero component gives +∞,
///   a negative zero −∞ (IEEE 754), so a ray parallel to a slab gets slab parameters
///   (−∞, +∞) if its origin is strictly inside the slab and (±∞, ±∞) — an empty
///   interval — if outside, with no special branch. Subnormal components also give ±∞
///   (1/d overflows) and are treated as parallel.
/// * Origin exactly on a slab plane with a zero direction component: (±h − o)·(1/d) =
///   0·∞ = NaN. The ray runs inside the plane of a face, which belongs to the closed
///   box, so the slab does not restrict it; the axis is skipped explicitly. (Left in,
///   the NaN would either poison min/max — `f32::min` returns the other operand, so
///   min(NaN, +∞) = +∞ would reject the ray — or be silently lost.)
/// * Entry/exit are swapped per axis (t0 > t1 for negative directions), the entry is
///   the largest near value and the exit the smallest far value; ties keep the first
///   axis. An edge or corner grazed exactly gives t_entry = t_exit: a hit (closed box).
/// * Huge and tiny coordinates: only one subtraction and one multiplication per plane,
///   each correctly rounded, so relative accuracy does not depend on scale as long as
///   nothing overflows; with power-of-two directions the parameters are exact.
pub fn slab(
    origin_local: Vec3,
    dir_local: Vec3,
    half: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<(f32, f32, usize, usize)> {
    slab_bounds(origin_local, dir_local.recip(), -half, half, t_min, t_max)
}

/// The slab test against [lo, hi] with a precomputed reciprocal direction (see [`slab`]).
#[inline]
fn slab_bounds(o: Vec3, inv: Vec3, lo: Vec3, hi: Vec3, t_min: f32, t_max: f32) -> Option<SlabHit> {
    let mut entry = f32::NEG_INFINITY;
    let mut exit = f32::INFINITY;
    let (mut entry_axis, mut exit_axis) = (0, 0);
    for i in 0..3 {
        let t0 = (lo[i] - o[i]) * inv[i];
        let t1 = (hi[i] - o[i]) * inv[i];
        if t0.is_nan() || t1.is_nan() {
            // On a face plane, moving within it: inside the closed slab.
            continue;
        }
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        if near > entry {
            entry = near;
            entry_axis = i;
        }
        if far < exit {
            exit = far;
            exit_axis = i;
        }
    }
    (entry <= exit && exit > t_min && entry < t_max).then_some((entry, exit, entry_axis, exit_axis))
}

impl Shape for Cuboid {
    /// The entry if it lies in (t_min, t_max), else the exit (origin inside the box, or
    /// t_min past the entry). The normal is the face's outward axis: −sign(d)·axis at the
    /// entry, +sign(d)·axis at the exit. The point is o + t·d with its coordinate along
    /// the face axis snapped onto the face plane (so it lies exactly on the box in the
    /// axis-aligned case).
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        let (o, d, (entry, exit, ea, xa)) = self.slab_frame(ray)?;
        let (t, axis, outward_sign) = if entry > ray.t_min && entry < ray.t_max {
            (entry, ea, if d[ea] > 0.0 { -1.0 } else { 1.0 })
        } else if exit > ray.t_min && exit < ray.t_max {
            (exit, xa, if d[xa] > 0.0 { 1.0 } else { -1.0 })
        } else {
            return None;
        };
        let mut p = o + t * d;
        let n;
        if self.axis_aligned {
            p[axis] = if outward_sign > 0.0 { self.max[axis] } else { self.min[axis] };
            n = outward_sign * Vec3::AXES[axis];
        } else {
            p[axis] = outward_sign * self.half_extent[axis];
            p = self.centre + self.world_of(p);
            n = outward_sign * self.axes[axis];
        }
        Some(SurfaceHit { t, p, n })
    }

    /// Exact corners for the axis-aligned box; for an oriented one the box of its eight
    /// transformed corners, padded by a few ulp of the coordinates' magnitude so that
    /// rounding in the corner transform cannot make the bounds cut off a grazing hit.
    fn bounds(&self) -> Aabb {
        if self.axis_aligned {
            return Aabb { min: self.min, max: self.max };
        }
        let h = self.half_extent;
        let mut b = Aabb::EMPTY;
        for i in 0..8 {
            let s = Vec3::new(
                if i & 1 == 0 { -h.x } else { h.x },
                if i & 2 == 0 { -h.y } else { h.y },
                if i & 4 == 0 { -h.z } else { h.z },
            );
            b = b.grow(self.centre + self.world_of(s));
        }
        let pad = 4.0 * f32::EPSILON * (self.centre.abs() + Vec3::splat(h.element_sum()));
        Aabb { min: b.min - pad, max: b.max + pad }
    }

    fn area(&self) -> f32 {
        let h = self.half_extent;
        8.0 * (h.x * h.y + h.y * h.z + h.z * h.x)
    }

    /// Uniform by area: `u.x` picks one of the six faces with probability ∝ its area
    /// (4·h_j·h_k for the two faces normal to axis i) and is then rescaled to [0, 1) to
    /// serve as the first in-face coordinate, `u.y` the second (the usual reuse of a
    /// sample dimension, pbrt-v4 §2.3.2).
    fn sample_area(&self, u: Vec2) -> Option<(Vec3, Vec3)> {
        let h = self.half_extent;
        let face_area = [h.y * h.z, h.z * h.x, h.x * h.y];
        let total = 2.0 * (face_area[0] + face_area[1] + face_area[2]);
        let mut x = u.x.clamp(0.0, 1.0) * total;
        let mut face = 5;
        for f in 0..6 {
            let a = face_area[f / 2];
            if x < a || f == 5 {
                face = f;
                break;
            }
            x -= a;
        }
        let axis = face / 2;
        let sign = if face % 2 == 0 { -1.0 } else { 1.0 };
        let u0 = (x / face_area[axis]).clamp(0.0, 1.0);
        let (j, k) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut local = Vec3::ZERO;
        local[axis] = sign * h[axis];
        local[j] = (2.0 * u0 - 1.0) * h[j];
        local[k] = (2.0 * u.y - 1.0) * h[k];
        if self.axis_aligned {
            let mut p = self.centre + local;
            p[axis] = if sign > 0.0 { self.max[axis] } else { self.min[axis] };
            Some((p, sign * Vec3::AXES[axis]))
        } else {
            Some((self.centre + self.world_of(local), sign * self.axes[axis]))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_4;

    use rng::Pcg32;

    fn unit_box() -> Cuboid {
        Cuboid::axis_aligned(Vec3::ZERO, Vec3::ONE).unwrap()
    }

    #[test]
    fn rejects_invalid_boxes() {
        assert!(Cuboid::axis_aligned(Vec3::ONE, Vec3::ZERO).is_err());
        assert!(Cuboid::axis_aligned(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0)).is_err());
        assert!(Cuboid::axis_aligned(Vec3::ZERO, Vec3::new(1.0, f32::NAN, 1.0)).is_err());
        assert!(Cuboid::oriented(Vec3::ZERO, Vec3::new(1.0, -1.0, 1.0), Quat::IDENTITY).is_err());
        assert!(Cuboid::oriented(Vec3::ZERO, Vec3::ONE, Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)).is_err());
        assert!(Cuboid::oriented(Vec3::INFINITY, Vec3::ONE, Quat::IDENTITY).is_err());
        let b = Cuboid::oriented(Vec3::ONE, Vec3::ONE, Quat::IDENTITY).unwrap();
        assert!(b.is_axis_aligned());
        assert!(!Cuboid::oriented(Vec3::ONE, Vec3::ONE, Quat::from_rotation_z(0.1)).unwrap().is_axis_aligned());
    }

    #[test]
    fn axis_rays_with_zero_and_negative_zero_components() {
        let b = unit_box();
        for z in [0.0f32, -0.0] {
            let inside = Ray::new(Vec3::new(0.5, -1.0, 0.5), Vec3::new(z, 1.0, z));
            let h = b.intersect(&inside).unwrap();
            assert_eq!((h.t, h.p, h.n), (1.0, Vec3::new(0.5, 0.0, 0.5), -Vec3::Y));
            let outside = Ray::new(Vec3::new(0.5, -1.0, 1.5), Vec3::new(z, 1.0, z));
            assert!(b.intersect(&outside).is_none());
            let down = Ray::new(Vec3::new(0.25, 3.0, 0.75), Vec3::new(z, -2.0, z));
            let h = b.intersect(&down).unwrap();
            assert_eq!((h.t, h.n), (1.0, Vec3::Y));
            // Through the slab function directly.
            let s = slab(Vec3::new(0.0, -3.0, 0.0), Vec3::new(z, 1.0, -z), Vec3::ONE, 0.0, f32::INFINITY);
            assert_eq!(s, Some((2.0, 4.0, 1, 1)));
        }
    }

    #[test]
    fn origin_on_a_face_plane_moving_parallel_is_inside_the_closed_slab() {
        let b = unit_box();
        for z in [0.0f32, -0.0] {
            // On x = 0 (a face plane), moving along y: the x slab yields 0·∞ = NaN.
            let r = Ray::new(Vec3::new(0.0, -1.0, 0.5), Vec3::new(z, 1.0, z));
            let h = b.intersect(&r).expect("a ray within a face plane hits the closed box");
            assert_eq!((h.t, h.n), (1.0, -Vec3::Y));
            // On x = 1, moving along −z.
            let r = Ray::new(Vec3::new(1.0, 0.5, 2.0), Vec3::new(z, z, -1.0));
            let h = b.intersect(&r).unwrap();
            assert_eq!((h.t, h.n), (1.0, Vec3::Z));
            // Along an edge line (x = 0 and y = 1), two NaN slabs.
            let r = Ray::new(Vec3::new(0.0, 1.0, -4.0), Vec3::new(z, z, 2.0));
            assert_eq!(b.intersect(&r).map(|h| h.t), Some(2.0));
            // Just off the plane: a miss.
            let r = Ray::new(Vec3::new(-1e-7, -1.0, 0.5), Vec3::new(z, 1.0, z));
            assert!(b.intersect(&r).is_none());
        }
        assert_eq!(
            slab(Vec3::new(1.0, -3.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::ONE, 0.0, f32::INFINITY),
            Some((2.0, 4.0, 1, 1))
        );
    }

    #[test]
    fn origin_inside_hits_the_exit() {
        let b = unit_box();
        let r = Ray::new(Vec3::new(0.5, 0.25, 0.5), Vec3::new(0.0, 0.5, 0.0));
        let h = b.intersect(&r).unwrap();
        assert_eq!((h.t, h.p, h.n), (1.5, Vec3::new(0.5, 1.0, 0.5), Vec3::Y));
        let r = Ray::new(Vec3::new(0.5, 0.25, 0.5), Vec3::new(-1.0, 0.0, 0.0));
        let h = b.intersect(&r).unwrap();
        assert_eq!((h.t, h.n), (0.5, -Vec3::X));
        // The slab reports the (negative) entry behind the origin.
        let s = slab(Vec3::ZERO, Vec3::X, Vec3::ONE, 0.0, f32::INFINITY).unwrap();
        assert_eq!(s, (-1.0, 1.0, 0, 0));
        // Segment ends before the exit: no hit.
        assert!(b.intersect(&Ray::segment(Vec3::splat(0.5), Vec3::X, 0.0, 0.25)).is_none());
        // t_min past the entry: the exit.
        let r = Ray::segment(Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 1.5, 10.0);
        assert_eq!(b.intersect(&r).map(|h| (h.t, h.n)), Some((2.0, Vec3::X)));
        // Box behind.
        assert!(b.intersect(&Ray::new(Vec3::new(2.0, 0.5, 0.5), Vec3::X)).is_none());
    }

    #[test]
    fn huge_and_tiny_boxes_give_exact_t() {
        let huge = Cuboid::axis_aligned(Vec3::splat(-1e6), Vec3::splat(1e6)).unwrap();
        let r = Ray::new(Vec3::new(-3e6, 0.5, -0.25), Vec3::X);
        let h = huge.intersect(&r).unwrap();
        assert_eq!((h.t, h.p, h.n), (2e6, Vec3::new(-1e6, 0.5, -0.25), -Vec3::X));
        let r = Ray::new(Vec3::new(1e5, 2e5, 3e6), Vec3::new(0.0, 0.0, -0.5));
        assert_eq!(huge.intersect(&r).map(|h| (h.t, h.n)), Some((4e6, Vec3::Z)));

        let (lo, hi) = (Vec3::new(1e-6, 2e-6, 3e-6), Vec3::new(2e-6, 4e-6, 6e-6));
        let tiny = Cuboid::axis_aligned(lo, hi).unwrap();
        let o = Vec3::new(1.5e-6, 3e-6, -1e-6);
        let h = tiny.intersect(&Ray::new(o, Vec3::Z)).unwrap();
        assert_eq!(h.t, 3e-6 - (-1e-6f32)); // One correctly rounded subtraction.
        assert_eq!(h.p, Vec3::new(1.5e-6, 3e-6, 3e-6));
        assert_eq!(h.n, -Vec3::Z);
        let h = tiny.intersect(&Ray::new(Vec3::new(1.5e-6, 3e-6, 4e-6), Vec3::Z)).unwrap();
        assert_eq!((h.t, h.p.z, h.n), (6e-6 - 4e-6f32, 6e-6, Vec3::Z));
    }

    #[test]
    fn oriented_box_rotated_45_degrees() {
        // Unit half extents rotated 45° about z: a diamond in xy with corners at ±√2 on
        // the axes, faces at distance 1 from the centre with normals (±1, ±1, 0)/√2.
        let c = Vec3::new(2.0, -1.0, 0.5);
        let b = Cuboid::oriented(c, Vec3::ONE, Quat::from_rotation_z(FRAC_PI_4)).unwrap();
        assert!(!b.is_axis_aligned());
        // Along +x through the centre, from x = c.x − 5: the ray meets the diamond's
        // vertical edge (where two faces meet) at x = c.x − √2.
        let r = Ray::new(c - Vec3::new(5.0, 0.0, 0.0), Vec3::X);
        let h = b.intersect(&r).unwrap();
        assert!((h.t - (5.0 - 2f32.sqrt())).abs() < 1e-5, "{}", h.t);
        // Off-centre at y = c.y + 0.5: the face with normal (−1, 1, 0)/√2. The face plane
        // is (p − c)·n = 1, i.e. −x + y = √2 in centred coordinates: x = 0.5 − √2.
        let r = Ray::new(c + Vec3::new(-5.0, 0.5, 0.0), Vec3::X);
        let h = b.intersect(&r).unwrap();
        let expect_t = 5.0 + 0.5 - 2f32.sqrt();
        assert!((h.t - expect_t).abs() < 1e-5, "{} vs {expect_t}", h.t);
        let n = Vec3::new(-1.0, 1.0, 0.0).normalize();
        assert!((h.n - n).length() < 1e-6, "{}", h.n);
        assert!(((h.p - c).dot(n) - 1.0).abs() < 1e-5);
        // From inside, downward: exits through the face with normal (±1, −1, 0)/√2.
        let r = Ray::new(c + Vec3::new(0.25, 0.0, 0.0), -Vec3::Y);
        let h = b.intersect(&r).unwrap();
        assert!((h.t - (2f32.sqrt() - 0.25)).abs() < 1e-5);
        assert!((h.n - Vec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-6);
        // The top face (z) is still axis-aligned.
        let r = Ray::new(c + Vec3::new(0.1, 0.2, 3.0), -Vec3::Z);
        let h = b.intersect(&r).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6 && (h.n - Vec3::Z).length() < 1e-6);
        // Bounds hold the diamond: ±√2 in x and y.
        let bb = b.bounds();
        assert!((bb.max.x - c.x - 2f32.sqrt()).abs() < 1e-5 && (bb.min.z - (c.z - 1.0)).abs() < 1e-5);
    }

    #[test]
    fn area_and_sampling() {
        let h = Vec3::new(0.5, 1.0, 2.0);
        for b in [
            Cuboid::axis_aligned(Vec3::new(1.0, 2.0, 3.0) - h, Vec3::new(1.0, 2.0, 3.0) + h).unwrap(),
            Cuboid::oriented(Vec3::new(1.0, 2.0, 3.0), h, Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1))
                .unwrap(),
        ] {
            let area = b.area();
            assert!((area - 8.0 * (0.5 + 2.0 + 1.0)).abs() < 1e-5);
            let bb = b.bounds();
            let mut rng = Pcg32::seed_from_u64(7);
            let n = 60_000;
            let mut counts = [0usize; 6];
            for _ in 0..n {
                let (p, nrm) = b.sample_area(Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
                assert!(p.cmpge(bb.min).all() && p.cmple(bb.max).all());
                let local = b.local_of(p - b.centre());
                let axis = (0..3).find(|&i| (nrm.dot(b.axes()[i]).abs() - 1.0).abs() < 1e-5).unwrap();
                let sign = nrm.dot(b.axes()[axis]).signum();
                // On the face plane, inside the face rectangle.
                assert!((local[axis] - sign * h[axis]).abs() < 1e-5, "{local} {nrm}");
                assert!((local.abs() - h).max_element() < 1e-5);
                counts[2 * axis + usize::from(sign > 0.0)] += 1;
            }
            for (f, &count) in counts.iter().enumerate() {
                let a = 4.0 * h[(f / 2 + 1) % 3] * h[(f / 2 + 2) % 3];
                let p = (a / area) as f64;
                let mean = n as f64 * p;
                let sigma = (n as f64 * p * (1.0 - p)).sqrt();
                assert!((count as f64 - mean).abs() < 3.0 * sigma, "face {f}: {count} vs {mean} ± {sigma}");
            }
        }
    }

    #[test]
    fn bounds_and_the_axis_aligned_box_agree_with_aabb_hit() {
        let b = Cuboid::axis_aligned(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 0.5, 3.0)).unwrap();
        let aabb = b.bounds();
        let mut rng = Pcg32::seed_from_u64(99);
        for _ in 0..1000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 8.0 - 4.0;
            let d = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let r = Ray::new(o, d);
            let mine = b.intersect(&r).map(|h| h.t);
            let theirs = aabb.hit(&r, r.t_max);
            // Aabb::hit returns the clamped entry (t_min when inside); compare hit/miss.
            assert_eq!(mine.is_some(), theirs.is_some(), "{o} {d}");
        }
    }
}
