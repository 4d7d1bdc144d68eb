//! Ray–triangle tests: Möller–Trumbore (the thesis's) and the watertight test of Woop,
//! Benthin & Wald (2013), both from the `bvh` crate, which runs them inside its leaves;
//! plus a double-precision reference and a closed test mesh for measuring leaks.

pub use bvh::{Triangle, TriangleTest, WatertightRay, intersect_triangle, intersect_triangle_watertight};
use glam::{DVec3, Vec3};

/// The hit of a ray with a triangle in double precision, (t, u, v) with u, v the weights
/// of vertices 1 and 2, computed from the f32 inputs widened exactly — the reference
/// the stability measurements compare the f32 tests against. Edges count as inside.
pub fn reference_f64(v: &[Vec3; 3], origin: Vec3, dir: Vec3) -> Option<(f64, f64, f64)> {
    let [a, b, c] = v.map(|p| p.as_dvec3());
    let (o, d) = (origin.as_dvec3(), dir.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let w = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && w >= 0.0 && u + w <= 1.0 && t > 0.0).then_some((t, u, w))
}

/// A closed, consistently wound triangle mesh of the unit sphere: an icosahedron whose
/// faces are split `subdivisions` times into four, vertices shared (indexed), so that
/// every edge belongs to exactly two triangles. A ray from outside towards the centre
/// must hit it; one that does not has leaked through a crack.
pub fn icosphere(subdivisions: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<DVec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, vertices: &mut Vec<DVec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                vertices.push(((vertices[a as usize] + vertices[b as usize]) / 2.0).normalize());
                vertices.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let (ab, bc, ca) = (mid(a, b, &mut vertices), mid(b, c, &mut vertices), mid(c, a, &mut vertices));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    (vertices.iter().map(|v| v.as_vec3()).collect(), faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bvh::Ray;

    #[test]
    fn icosphere_is_closed_and_outward_wound() {
        for s in 0..3 {
            let (v, f) = icosphere(s);
            assert_eq!(f.len(), 20 * 4usize.pow(s));
            // Euler: V − E + F = 2 with E = 3F/2 for a closed triangle mesh.
            assert_eq!(v.len() as i64 - 3 * f.len() as i64 / 2 + f.len() as i64, 2);
            let mut edges = std::collections::HashMap::new();
            for t in &f {
                for k in 0..3 {
                    *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
                }
                let [a, b, c] = t.map(|i| v[i as usize]);
                assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "outward winding");
            }
            // Each directed edge once, and its reverse once: closed and consistently wound.
            assert!(edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1)));
        }
    }

    #[test]
    fn reference_agrees_with_both_tests() {
        let v = [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)];
        let o = Vec3::new(0.2, 0.3, 0.0);
        let (t, u, w) = reference_f64(&v, o, Vec3::Z).unwrap();
        assert!((t - 1.0).abs() < 1e-12 && (u - 0.2).abs() < 1e-7 && (w - 0.3).abs() < 1e-7);
        let r = Ray::new(o, Vec3::Z);
        let mt = intersect_triangle(&Triangle::new(&v), &r, f32::INFINITY).unwrap();
        let wt = intersect_triangle_watertight(&v, &WatertightRay::new(&r), f32::INFINITY).unwrap();
        assert!((mt.0 - 1.0).abs() < 1e-6 && (wt.0 - 1.0).abs() < 1e-6);
        assert!(reference_f64(&v, Vec3::new(0.8, 0.8, 0.0), Vec3::Z).is_none());
    }
}
