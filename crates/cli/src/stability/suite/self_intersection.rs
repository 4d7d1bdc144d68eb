//! The self_intersection family: secondary rays spawned with a fixed ε against Wächter &
//! Binder's robust offset, on spheres, triangles and quads across scene scales.

use super::{Row, Scale, row, timed};
use glam::{DVec3, Vec3};
use rng::Pcg32;
use shapes::offset::{offset_fixed_epsilon, offset_ray_origin};
use shapes::polygon::{InsideTest, Polygon};
use shapes::sphere::{Sphere, SphereMethod};
use shapes::triangle::{WatertightRay, intersect_triangle_watertight};
use shapes::{Ray, Shape};

/// The fixed ε of the baseline in [`self_intersection`].
pub const FIXED_EPSILON: f32 = 1e-4;

/// A surface for [`self_intersection`].
enum Surface {
    Sphere(Sphere),
    Triangle([Vec3; 3]),
    Quad(Polygon),
}

impl Surface {
    /// The closest hit's point and unit normal (as the shape computes them).
    fn hit(&self, ray: &Ray) -> Option<(Vec3, Vec3)> {
        match self {
            Self::Sphere(s) => s.intersect(ray).map(|h| (h.p, h.n)),
            Self::Quad(q) => q.intersect(ray).map(|h| (h.p, h.n)),
            Self::Triangle(v) => {
                let (_, u, w) = intersect_triangle_watertight(v, &WatertightRay::new(ray), ray.t_max)?;
                let p = v[0] * (1.0 - u - w) + v[1] * u + v[2] * w;
                Some((p, (v[1] - v[0]).cross(v[2] - v[0]).normalize()))
            }
        }
    }

    /// Signed side of `p` in f64: > 0 on the normal's side (outside the sphere; the
    /// front of the triangle or of the quad's plane), 0 on the surface.
    fn side(&self, p: Vec3) -> f64 {
        let p = p.as_dvec3();
        match self {
            Self::Sphere(s) => (p - s.centre.as_dvec3()).length_squared() - (s.radius as f64).powi(2),
            Self::Triangle(v) => {
                let [a, b, c] = v.map(|x| x.as_dvec3());
                (p - a).dot((b - a).cross(c - a))
            }
            Self::Quad(q) => {
                // The polygon's own plane: its f32 normal through its f32 anchor (the
                // vertex centroid rounded to f32), as its intersection uses it.
                let vs = q.vertices();
                let anchor = (vs.iter().map(|v| v.as_dvec3()).sum::<DVec3>() / vs.len() as f64).as_vec3();
                (p - anchor.as_dvec3()).dot(q.normal().as_dvec3())
            }
        }
    }
}

/// Secondary rays leaving a surface: the fixed offset p + ε·n ([`offset_fixed_epsilon`],
/// ε = [`FIXED_EPSILON`]) against Wächter & Binder's ([`offset_ray_origin`]).
///
/// Surfaces: a sphere ([`Sphere`], robust geometric method), a triangle (watertight test,
/// point interpolated from the barycentrics) and a tilted quad ([`Polygon`]), each of size
/// s and at a distance of a few s from the world origin, for s = 10⁻³, 1, 10³, 10⁵. Each
/// hit point comes from the shape's own intersection of a random ray from outside (from
/// either side for the planar ones), so it carries the real f32 error; its normal is
/// turned to face that ray.
///
/// Cases: "reflect" rays leave on the normal's side in a cosine-distributed direction
/// from origin offset(p, n); **failure** = the ray hits the same surface again at t > 0
/// (on a convex sphere or a plane every such hit is a self-intersection). "refract" rays
/// enter the surface (direction on the −n side) from origin offset(p, −n); **failure** =
/// that origin is not strictly on the −n side according to an exact-enough f64 test
/// (the sphere's |o − c|² − r², the triangle's plane through its f32 vertices, the
/// quad's own f32 plane). One test = one spawned ray; the time is per offset computation.
///
/// Not measured: a fixed ε that is too *large* for a small scene (10⁻⁴ is a tenth of
/// the 10⁻³ sphere) jumps over thin features rather than re-hitting its own surface, so
/// it shows no failure here at small scales.
pub fn self_intersection(scale: Scale) -> Vec<Row> {
    let mut rng = Pcg32::seed_from_u64(0x5EED_0005);
    let n = scale.n(400);
    let mut rows = Vec::new();
    type OffsetFn = fn(Vec3, Vec3) -> Vec3;
    let methods: [(&str, OffsetFn); 2] = [
        ("fixed-epsilon 1e-4", |p, n| offset_fixed_epsilon(p, n, FIXED_EPSILON)),
        ("robust-offset", offset_ray_origin),
    ];
    for (label, s) in [("1e-3", 1e-3), ("1", 1.0), ("1e3", 1e3), ("1e5", 1e5)] {
        let c = DVec3::new(1.5, -2.5, 3.5) * s;
        let at = |v: DVec3| (c + v * s).as_vec3();
        let quad_a = DVec3::new(1.0, 0.3, -0.2);
        let quad_b = DVec3::new(-0.25, 0.9, 0.4);
        let surfaces = [
            ("sphere", Surface::Sphere(Sphere::new(c.as_vec3(), s as f32, SphereMethod::Geometric).expect("sphere"))),
            (
                "triangle",
                Surface::Triangle([
                    at(DVec3::new(-1.0, -0.8, 0.3)),
                    at(DVec3::new(1.1, -0.5, -0.4)),
                    at(DVec3::new(0.1, 1.2, 0.5)),
                ]),
            ),
            (
                "quad",
                Surface::Quad(
                    Polygon::new(
                        vec![at(-quad_a - quad_b), at(quad_a - quad_b), at(quad_a + quad_b), at(-quad_a + quad_b)],
                        InsideTest::default(),
                    )
                    .expect("planar quad"),
                ),
            ),
        ];
        for (sname, surface) in &surfaces {
            // Hit points with the normal facing the incoming ray.
            let mut points: Vec<(Vec3, Vec3)> = Vec::with_capacity(n);
            while points.len() < n {
                let target = match surface {
                    Surface::Sphere(_) => c + rng.unit_vector() * s,
                    Surface::Triangle(v) => {
                        let (mut u, mut w) = (rng.next_f64(), rng.next_f64());
                        if u + w > 1.0 {
                            (u, w) = (1.0 - u, 1.0 - w);
                        }
                        let [a, b, cc] = v.map(|x| x.as_dvec3());
                        a + (b - a) * u + (cc - a) * w
                    }
                    Surface::Quad(_) => c + (quad_a * rng.range(-0.95, 0.95) + quad_b * rng.range(-0.95, 0.95)) * s,
                };
                let outward = match surface {
                    Surface::Sphere(_) => (target - c).normalize(),
                    _ => {
                        let nn = quad_a.cross(quad_b).normalize();
                        if rng.coin() { nn } else { -nn }
                    }
                };
                let w = loop {
                    let w = (outward + 0.8 * rng.unit_vector()).normalize();
                    if w.dot(outward) > 0.3 {
                        break w;
                    }
                };
                let o = target + w * s * rng.range(1.0, 3.0);
                let ray = Ray::new(o.as_vec3(), (target - o).as_vec3());
                if let Some((p, nrm)) = surface.hit(&ray) {
                    let nrm = if nrm.dot(ray.dir) > 0.0 { -nrm } else { nrm };
                    points.push((p, nrm));
                }
            }
            let dirs: Vec<(Vec3, Vec3)> = points
                .iter()
                .map(|&(_, nrm)| {
                    let nd = nrm.as_dvec3();
                    let out = (nd + rng.unit_vector()).normalize_or(nd).as_vec3();
                    let inward = (-nd + 0.7 * rng.unit_vector()).normalize_or(-nd).as_vec3();
                    (out, inward)
                })
                .collect();
            for (mname, offset) in methods {
                let (origins, ns) = timed(scale, &points, |&(p, nrm)| offset(p, nrm));
                let rehits = origins
                    .iter()
                    .zip(&dirs)
                    .filter(|&(&o, &(out, _))| surface.hit(&Ray::new(o, out)).is_some())
                    .count();
                let case = format!("{sname} x{label} reflect re-hit");
                rows.push(row("self_intersection", mname, &case, n as u64, rehits as u64, 0, ns));

                let (origins, ns) = timed(scale, &points, |&(p, nrm)| offset(p, -nrm));
                let wrong = origins
                    .iter()
                    .zip(&points)
                    .filter(|&(&o, &(p, nrm))| {
                        // The side −n points to, according to the f64 test at p − n·size.
                        let inside_sign = surface.side((p.as_dvec3() - nrm.as_dvec3() * 0.5 * s).as_vec3()).signum();
                        let side = surface.side(o);
                        side.is_nan() || side * inside_sign <= 0.0
                    })
                    .count();
                let case = format!("{sname} x{label} refract wrong side");
                rows.push(row("self_intersection", mname, &case, n as u64, wrong as u64, 0, ns));
            }
        }
    }
    rows
}
