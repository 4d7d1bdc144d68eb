//! Procedural meshes for tests, examples and built-in scenes.

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// A triangle mesh: positions, per-vertex normals and counter-clockwise triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit per-vertex normals (pointing to the front side), or empty for flat shading.
    pub normals: Vec<Vec3>,
    /// Unit per-vertex tangents (orienting anisotropic BSDFs), or empty.
    pub tangents: Vec<Vec3>,
    /// Per-vertex texture coordinates ((0, 0): the image's top-left corner), or empty.
    pub uvs: Vec<glam::Vec2>,
    /// Triangles, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
}

/// A latitude–longitude sphere with `rings` × `segments` quads (poles as fans). With
/// `inward` the front faces (and normals) point to the centre: a closed room.
pub fn uv_sphere(centre: Vec3, radius: f32, rings: u32, segments: u32, inward: bool) -> Mesh {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut m = Mesh::default();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = TAU * s as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            m.positions.push(centre + radius * n);
            m.normals.push(if inward { -n } else { n });
            // ∂p/∂φ: along the parallels, like the grooves of a turned object.
            m.tangents.push(Vec3::new(-phi.sin(), 0.0, phi.cos()));
        }
    }
    let idx = |r: u32, s: u32| r * segments + s % segments;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (idx(r, s), idx(r, s + 1), idx(r + 1, s), idx(r + 1, s + 1));
            // Outward-facing counter-clockwise order; reversed for inward.
            let mut quad = Vec::new();
            if r != 0 {
                quad.push([a, b, d]);
            }
            if r != rings - 1 {
                quad.push([a, d, c]);
            }
            for t in quad {
                m.triangles.push(if inward { [t[0], t[2], t[1]] } else { t });
            }
        }
    }
    m
}

/// An axis-aligned quad with its front facing `normal` (one of ±x, ±y, ±z), centred at
/// `centre` with half-sizes `half` along the two other axes.
pub fn quad(centre: Vec3, normal: Vec3, half: f32) -> Mesh {
    let n = normal.normalize();
    let a = if n.x.abs() > 0.5 { Vec3::Y } else { Vec3::X };
    let u = n.cross(a).normalize() * half;
    let v = n.cross(u).normalize() * half;
    // Counter-clockwise seen from the front: (−u−v) → (+u−v) → (+u+v) with u × v ∥ n.
    let (u, v) = if u.cross(v).dot(n) > 0.0 { (u, v) } else { (v, u) };
    Mesh {
        positions: vec![centre - u - v, centre + u - v, centre + u + v, centre - u + v],
        normals: vec![n; 4],
        tangents: vec![u.normalize(); 4],
        // The image upright on the front face: (0, 0) at the −u+v corner.
        uvs: vec![glam::Vec2::new(0.0, 1.0), glam::Vec2::new(1.0, 1.0), glam::Vec2::new(1.0, 0.0), glam::Vec2::ZERO],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// Area-weighted vertex normals (each triangle adds its unnormalised cross product to its
/// vertices), for meshes that come without normals: smooth shading of scanned models.
/// Vertices of only degenerate triangles get a zero normal (= use the geometric one).
pub fn smooth_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            normals[i as usize] += n;
        }
    }
    normals.iter().map(|n| n.try_normalize().unwrap_or(Vec3::ZERO)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face_normal(m: &Mesh, t: [u32; 3]) -> Vec3 {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        (b - a).cross(c - a)
    }

    #[test]
    fn sphere_winding_matches_its_normals() {
        for inward in [false, true] {
            let m = uv_sphere(Vec3::new(1.0, 2.0, 3.0), 2.0, 8, 12, inward);
            for &t in &m.triangles {
                let n = face_normal(&m, t);
                let centroid = t.iter().map(|&i| m.positions[i as usize]).sum::<Vec3>() / 3.0;
                let out = centroid - Vec3::new(1.0, 2.0, 3.0);
                assert!(n.length() > 0.0);
                assert_eq!(n.dot(out) > 0.0, !inward);
            }
        }
    }

    #[test]
    fn quad_faces_its_normal() {
        for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            let m = quad(Vec3::ZERO, n, 1.0);
            for &t in &m.triangles {
                assert!(face_normal(&m, t).normalize().dot(n) > 0.999, "{n}");
            }
        }
    }

    #[test]
    fn smooth_normals_of_a_sphere_point_outwards() {
        let sphere = uv_sphere(Vec3::new(1.0, 2.0, 3.0), 2.0, 16, 32, false);
        let normals = smooth_normals(&sphere.positions, &sphere.triangles);
        for (p, n) in sphere.positions.iter().zip(&normals) {
            let radial = (*p - Vec3::new(1.0, 2.0, 3.0)).normalize();
            assert!(n.dot(radial) > 0.99, "{p:?}: {n:?}");
        }
        let degenerate = smooth_normals(&[Vec3::ZERO, Vec3::X, Vec3::X * 2.0], &[[0, 1, 2]]);
        assert!(degenerate.iter().all(|n| *n == Vec3::ZERO));
    }
}
