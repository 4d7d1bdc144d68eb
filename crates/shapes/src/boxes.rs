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
mod tests;
