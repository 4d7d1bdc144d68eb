use crate::{Aabb, Ray};
use glam::Vec3;

/// A triangle stored for Möller–Trumbore: vertex 0 and the two edges from it.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Triangle {
    /// Vertex 0.
    pub v0: [f32; 3],
    /// v1 − v0.
    pub e1: [f32; 3],
    /// v2 − v0.
    pub e2: [f32; 3],
}

impl Triangle {
    /// From three vertices.
    #[inline]
    pub fn new(v: &[Vec3; 3]) -> Self {
        Self { v0: v[0].to_array(), e1: (v[1] - v[0]).to_array(), e2: (v[2] - v[0]).to_array() }
    }

    /// The triangle's bounding box.
    pub fn bounds(v: &[Vec3; 3]) -> Aabb {
        Aabb::from_points(v)
    }
}

/// Möller–Trumbore ray–triangle intersection (JGT 1997), as in the thesis: returns
/// (t, u, v) for a hit with t in (t_min, t_max). Both faces are hit; degenerate
/// (zero-area) triangles never are.
#[inline]
pub fn intersect_triangle(tri: &Triangle, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
    let e1 = Vec3::from_array(tri.e1);
    let e2 = Vec3::from_array(tri.e2);
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - Vec3::from_array(tri.v0);
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t > ray.t_min && t < t_max).then_some((t, u, v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_and_misses_outside() {
        let tri = Triangle::new(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
        let (t, u, v) = intersect_triangle(&tri, &r, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-6 && (u - 0.25).abs() < 1e-6 && (v - 0.25).abs() < 1e-6);
        let back = Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z);
        assert!(intersect_triangle(&tri, &back, f32::INFINITY).is_some(), "both faces");
        let miss = Ray::new(Vec3::new(0.75, 0.75, 1.0), -Vec3::Z);
        assert!(intersect_triangle(&tri, &miss, f32::INFINITY).is_none());
        assert!(intersect_triangle(&tri, &r, 0.5).is_none(), "beyond t_max");
        let parallel = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::X);
        assert!(intersect_triangle(&tri, &parallel, f32::INFINITY).is_none());
    }

    #[test]
    fn degenerate_triangles_are_never_hit() {
        let tri = Triangle::new(&[Vec3::ZERO, Vec3::X, 2.0 * Vec3::X]);
        let r = Ray::new(Vec3::new(0.5, 0.0, 1.0), -Vec3::Z);
        assert!(intersect_triangle(&tri, &r, f32::INFINITY).is_none());
    }
}
