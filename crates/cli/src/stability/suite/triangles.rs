//! The triangles family: Möller–Trumbore against the watertight test on rays through
//! the shared vertices and edges of closed icospheres (leaks).

use super::{Row, Scale, row, timed};
use glam::{DVec3, Vec3};
use rng::Pcg32;
use shapes::Ray;
use shapes::triangle::{Triangle, WatertightRay, icosphere, intersect_triangle, intersect_triangle_watertight};

/// Möller–Trumbore ([`intersect_triangle`]) against the watertight test
/// ([`intersect_triangle_watertight`]) on closed meshes.
///
/// Meshes: [`icosphere`] with 3 and 5 subdivisions (1280 and 20480 triangles), scaled by
/// 1, 10³ and 10⁻³, and at scale 1 translated to (10⁴, −2·10³, 5·10³); vertices
/// transformed in f64 and rounded once, so shared vertices stay bit-identical. Rays from
/// outside towards a target seen from the front (1 to 3 radii away, direction within
/// 60° of the normal): a mesh vertex (half of the rays axis-parallel, which pass through
/// the f32 vertex exactly), a point on a shared edge (the f32 lerp of its two vertices;
/// half axis-parallel), or a random interior point of a face.
///
/// Every ray is tested against **all** triangles (brute force) and the closest hit kept.
/// **Failure (leak)**: no hit within a quarter radius behind the target's parameter —
/// the ray went through the surface to the far side or out. Hitting both triangles of
/// an edge is fine (a closed mesh is entered once either way) and not counted. One
/// test = one ray; the time is per ray–triangle test (the brute-force loop's time over
/// rays × triangles).
pub fn triangles(scale: Scale) -> Vec<Row> {
    let mut rng = Pcg32::seed_from_u64(0x5EED_0003);
    let mut rows = Vec::new();
    let transforms: [(&str, f64, DVec3); 4] = [
        ("x1", 1.0, DVec3::ZERO),
        ("x1e3", 1e3, DVec3::ZERO),
        ("x1e-3", 1e-3, DVec3::ZERO),
        ("+1e4", 1.0, DVec3::new(1e4, -2e3, 5e3)),
    ];
    for (subdiv, base_rays) in [(3u32, 64usize), (5, 16)] {
        let (unit_verts, faces) = icosphere(subdiv);
        for (tname, s, offset) in transforms {
            let verts: Vec<Vec3> = unit_verts.iter().map(|v| (v.as_dvec3() * s + offset).as_vec3()).collect();
            let tris: Vec<[Vec3; 3]> = faces.iter().map(|f| f.map(|i| verts[i as usize])).collect();
            let mt: Vec<Triangle> = tris.iter().map(Triangle::new).collect();
            let normal = |p: Vec3| (p.as_dvec3() - offset).normalize();
            let n = scale.n(base_rays);
            for kind in ["vertex", "edge", "interior"] {
                // (ray, t of the target, margin in t)
                let mut cases: Vec<(Ray, f64, f64)> = Vec::with_capacity(n);
                for i in 0..n {
                    let face = faces[rng.below(faces.len() as u64) as usize];
                    let target = match kind {
                        "vertex" => verts[face[rng.below(3) as usize] as usize],
                        "edge" => {
                            let e = rng.below(3) as usize;
                            let (a, b) = (verts[face[e] as usize], verts[face[(e + 1) % 3] as usize]);
                            a.lerp(b, rng.range(0.05, 0.95) as f32)
                        }
                        _ => {
                            let (mut u, mut v) = (rng.next_f64(), rng.next_f64());
                            if u + v > 1.0 {
                                (u, v) = (1.0 - u, 1.0 - v);
                            }
                            let (u, v) = (
                                (1.0 / 3.0 + 0.8 * (u - 1.0 / 3.0)) as f32,
                                (1.0 / 3.0 + 0.8 * (v - 1.0 / 3.0)) as f32,
                            );
                            let [a, b, c] = face.map(|k| verts[k as usize]);
                            a * (1.0 - u - v) + b * u + c * v
                        }
                    };
                    let nrm = normal(target);
                    let axis_parallel = kind != "interior" && i % 2 == 0;
                    let (o, d) = if axis_parallel {
                        let a = nrm.abs().max_position();
                        let sign = nrm[a].signum();
                        let mut o = target;
                        o[a] = (target[a] as f64 + sign * 2.0 * s) as f32;
                        let mut d = Vec3::ZERO;
                        d[a] = -sign as f32;
                        (o, d)
                    } else {
                        let w = loop {
                            let w = (nrm + 0.9 * rng.unit_vector()).normalize();
                            if w.dot(nrm) >= 0.5 {
                                break w;
                            }
                        };
                        let o = (target.as_dvec3() + w * s * rng.range(1.0, 3.0)).as_vec3();
                        (o, target - o)
                    };
                    let (od, dd) = (o.as_dvec3(), d.as_dvec3());
                    let t_target = (target.as_dvec3() - od).dot(dd) / dd.dot(dd);
                    cases.push((Ray::new(o, d), t_target, 0.25 * s / dd.length()));
                }
                let (mt_hits, mt_ns) = timed(scale, &cases, |(ray, _, _)| {
                    let mut best = f32::INFINITY;
                    for tri in &mt {
                        if let Some((t, _, _)) = intersect_triangle(tri, ray, best) {
                            best = t;
                        }
                    }
                    best
                });
                let (wt_hits, wt_ns) = timed(scale, &cases, |(ray, _, _)| {
                    let wr = WatertightRay::new(ray);
                    let mut best = f32::INFINITY;
                    for tri in &tris {
                        if let Some((t, _, _)) = intersect_triangle_watertight(tri, &wr, best) {
                            best = t;
                        }
                    }
                    best
                });
                let case = format!("ico{subdiv} {tname} {kind}");
                let per_test = tris.len() as f64;
                for (name, hits, ns) in [("moller-trumbore", mt_hits, mt_ns), ("watertight", wt_hits, wt_ns)] {
                    let leaks = hits
                        .iter()
                        .zip(&cases)
                        .filter(|&(&t, &(_, tt, margin))| t.is_nan() || t as f64 > tt + margin)
                        .count();
                    rows.push(row("triangles", name, &case, n as u64, leaks as u64, 0, ns / per_test));
                }
            }
        }
    }
    rows
}
