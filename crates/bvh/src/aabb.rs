use crate::Ray;
use glam::Vec3;

/// An axis-aligned bounding box; empty when min > max.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The box holding this box's eight corners under `t` (empty stays empty): where an
    /// object-space box lies in the world.
    pub fn transformed(&self, t: &glam::Affine3A) -> Aabb {
        if self.is_empty() {
            return Aabb::EMPTY;
        }
        (0..8).fold(Aabb::EMPTY, |acc, k| {
            let corner = Vec3::new(
                if k & 1 == 0 { self.min.x } else { self.max.x },
                if k & 2 == 0 { self.min.y } else { self.max.y },
                if k & 4 == 0 { self.min.z } else { self.max.z },
            );
            acc.grow(t.transform_point3(corner))
        })
    }

    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Self = Self { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    /// The smallest box holding the points.
    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    /// This box grown to hold `p`.
    #[inline]
    pub fn grow(self, p: Vec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }

    /// The smallest box holding both.
    #[inline]
    pub fn union(self, o: Self) -> Self {
        Self { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// True if the box holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Edge lengths (zero for an empty box).
    #[inline]
    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    /// The centre.
    #[inline]
    pub fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Surface area (zero for an empty box), the SAH's measure of hit probability.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Slab test (Kay & Kajiya 1986): the entry distance if the ray meets the box within
    /// (t_min, ∞) ∩ (−∞, t_max]. A zero direction component (0 or −0) gives a ±∞
    /// reciprocal, so the slab is all or nothing; an origin lying exactly on that slab's
    /// plane gives 0·∞ = NaN, and the ray is then counted inside the slab (the box is
    /// closed). SIMD min/max do not ignore NaN, hence the explicit mask.
    #[inline]
    pub fn hit(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let t0 = (self.min - ray.origin) * ray.inv_dir;
        let t1 = (self.max - ray.origin) * ray.inv_dir;
        let on_plane = t0.is_nan_mask() | t1.is_nan_mask();
        let near = Vec3::select(on_plane, Vec3::NEG_INFINITY, t0.min(t1));
        let far = Vec3::select(on_plane, Vec3::INFINITY, t0.max(t1));
        let t_enter = ray.t_min.max(near.x).max(near.y).max(near.z);
        let t_exit = t_max.min(far.x).min(far.y).min(far.z);
        (t_enter <= t_exit).then_some(t_enter)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb { min: Vec3::ZERO, max: Vec3::ONE }
    }

    #[test]
    fn axis_parallel_rays_with_zero_and_negative_zero() {
        for dz in [0.0f32, -0.0] {
            let inside = Ray::new(Vec3::new(0.5, -1.0, 0.5), Vec3::new(0.0, 1.0, dz));
            assert_eq!(unit().hit(&inside, f32::INFINITY), Some(1.0));
            let outside = Ray::new(Vec3::new(0.5, -1.0, 1.5), Vec3::new(0.0, 1.0, dz));
            assert_eq!(unit().hit(&outside, f32::INFINITY), None);
            let flipped = Ray::new(Vec3::new(-0.0, 2.0, 0.5), Vec3::new(dz, -1.0, 0.0));
            assert_eq!(unit().hit(&flipped, f32::INFINITY), Some(1.0));
        }
    }

    #[test]
    fn origin_on_a_slab_plane_counts_as_inside() {
        // Origin exactly on x = 0, moving parallel to it.
        let r = Ray::new(Vec3::new(0.0, -1.0, 0.5), Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(unit().hit(&r, f32::INFINITY), Some(1.0));
        let r = Ray::new(Vec3::new(1.0, 0.5, -2.0), Vec3::new(-0.0, 0.0, 1.0));
        assert_eq!(unit().hit(&r, f32::INFINITY), Some(2.0));
    }

    #[test]
    fn respects_the_segment() {
        let r = Ray::segment(Vec3::new(0.5, 0.5, -2.0), Vec3::Z, 0.0, 1.5);
        assert_eq!(unit().hit(&r, r.t_max), None);
        let r = Ray::segment(Vec3::new(0.5, 0.5, 0.5), Vec3::Z, 0.0, 10.0);
        assert_eq!(unit().hit(&r, r.t_max), Some(0.0));
        let behind = Ray::new(Vec3::new(0.5, 0.5, 2.0), Vec3::Z);
        assert_eq!(unit().hit(&behind, f32::INFINITY), None);
    }

    #[test]
    fn surface_area_and_union() {
        assert_eq!(unit().surface_area(), 6.0);
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        let b = unit().union(Aabb { min: Vec3::splat(2.0), max: Vec3::splat(3.0) });
        assert_eq!(b.extent(), Vec3::splat(3.0));
    }
}
