//! The spheres family: geometric (literal and robust) and algebraic (naive and stable)
//! ray–sphere intersection on far origins, tiny spheres and near-tangent rays.

use super::{Row, Scale, log_uniform, row, timed};
use glam::DVec3;
use rng::Pcg32;
use shapes::Ray;
use shapes::sphere::{Sphere, SphereMethod, reference_roots_f64};

/// Relative tolerance on the hit parameter for [`spheres`].
pub const SPHERE_T_TOL: f64 = 1e-4;

/// Half-width of the tangency band skipped by [`spheres`], in units of
/// f32 ε·(|o − c| + r).
pub const SPHERE_TANGENT_BAND: f64 = 4.0;

/// Ray–sphere intersection: the literal geometric method of the slides
/// ([`Sphere::intersect_geometric_literal`]), the robust geometric one
/// ([`Sphere::intersect_geometric`], the default), and the algebraic method with the naive
/// and the stable quadratic ([`Sphere::intersect_algebraic`]).
///
/// Cases (rays from outside, t ∈ (0, ∞), half of the directions unnormalised): random
/// rays at unit scale; a unit sphere seen from 10³, 10⁴, 10⁵ away; spheres of radius
/// 10⁻³ and 10⁻⁵ seen from 10 away; near-tangent rays at unit scale (miss distance
/// r·(1 ± δ), δ log-uniform in [10⁻⁷, 10⁻²]). Far and tiny cases aim within 1.2 r of the
/// centre, so they mix hits and misses.
///
/// Reference: [`reference_roots_f64`] on the very f32 ray widened to f64; the expected
/// hit is its smallest positive root. **Failure**: hit/miss disagreeing with the
/// reference, or |t − t_ref| > [`SPHERE_T_TOL`]·t_ref. Rays whose line passes within
/// [`SPHERE_TANGENT_BAND`]·ε₃₂·(|o − c| + r) of the silhouette (ε₃₂ = 2⁻²³) are skipped:
/// rounding the intended ray's origin and direction to f32 already moves its line by
/// about ε₃₂·|o − c|, so there the f32 input itself cannot say whether the ray hits.
/// One test = one ray; the time is per ray.
pub fn spheres(scale: Scale) -> Vec<Row> {
    let mut rng = Pcg32::seed_from_u64(0x5EED_0001);
    let n = scale.n(500);
    let c0 = DVec3::new(0.3, -0.2, 0.5);
    let c1 = DVec3::new(1.0, 2.0, 3.0);
    let mut cases: Vec<(String, DVec3, f64, Vec<Ray>)> = Vec::new();

    let random_dir = |rng: &mut Pcg32, o: DVec3, target: DVec3| {
        let d = target - o;
        if rng.coin() { d.normalize() } else { d * log_uniform(rng, 0.1, 10.0) / d.length() }
    };

    let rays = (0..n)
        .map(|_| {
            let o = c0 + rng.unit_vector() * rng.range(1.5, 4.0);
            let target = c0 + rng.unit_vector() * rng.range(0.0, 1.3);
            Ray::new(o.as_vec3(), random_dir(&mut rng, o, target).as_vec3())
        })
        .collect();
    cases.push(("unit random".into(), c0, 1.0, rays));

    let far_or_tiny = |rng: &mut Pcg32, c: DVec3, r: f64, dist: f64| -> Vec<Ray> {
        (0..n)
            .map(|_| {
                let o = c + rng.unit_vector() * dist;
                let target = c + rng.unit_vector() * rng.next_f64().sqrt() * 1.2 * r;
                Ray::new(o.as_vec3(), random_dir(rng, o, target).as_vec3())
            })
            .collect()
    };
    for (label, dist) in [("1e3", 1e3), ("1e4", 1e4), ("1e5", 1e5)] {
        let rays = far_or_tiny(&mut rng, c1, 1.0, dist);
        cases.push((format!("far origin {label}"), c1, 1.0, rays));
    }
    for (label, r) in [("1e-3", 1e-3), ("1e-5", 1e-5)] {
        let rays = far_or_tiny(&mut rng, c1, r, 10.0);
        cases.push((format!("tiny r={label} at 10"), c1, r, rays));
    }

    let rays = (0..n)
        .map(|_| {
            let o = c0 + rng.unit_vector() * rng.range(3.0, 5.0);
            let l = (c0 - o).length();
            let w = (c0 - o) / l;
            let u = rng.unit_vector();
            let p = (u - u.dot(w) * w).normalize();
            let delta = log_uniform(&mut rng, 1e-7, 1e-2);
            let h = if rng.coin() { 1.0 + delta } else { 1.0 - delta };
            // The line from o at distance h from the centre: sin α = h / l.
            let sin = h / l;
            let d = w * (1.0 - sin * sin).sqrt() + p * sin;
            Ray::new(o.as_vec3(), random_dir(&mut rng, o, o + d).as_vec3())
        })
        .collect();
    cases.push(("near tangent".into(), c0, 1.0, rays));

    type SphereFn = fn(&Sphere, &Ray) -> Option<f32>;
    let methods: [(&str, SphereFn); 4] = [
        ("geometric-literal", |s, r| s.intersect_geometric_literal(r)),
        ("geometric-robust", |s, r| s.intersect_geometric(r)),
        ("algebraic-naive", |s, r| s.intersect_algebraic(r, false)),
        ("algebraic-stable", |s, r| s.intersect_algebraic(r, true)),
    ];
    let mut rows = Vec::new();
    for (case, c, r, rays) in &cases {
        let sphere = Sphere::new(c.as_vec3(), *r as f32, SphereMethod::Geometric).expect("valid sphere");
        let (c, r) = (sphere.centre.as_dvec3(), sphere.radius as f64);
        // None: inside the tangency band (skipped); Some(None): miss; Some(Some(t)): hit.
        let reference: Vec<Option<Option<f64>>> = rays
            .iter()
            .map(|ray| {
                let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
                let f = o - c;
                let h = (f - (f.dot(d) / d.dot(d)) * d).length();
                let band = SPHERE_TANGENT_BAND * f32::EPSILON as f64 * (f.length() + r);
                if (h - r).abs() <= band {
                    return None;
                }
                let roots = reference_roots_f64(c, r, o, d);
                Some(roots.and_then(|(t0, t1)| [t0, t1].into_iter().find(|&t| t > 0.0)))
            })
            .collect();
        for (name, f) in methods {
            let (ts, ns) = timed(scale, rays, |ray| f(&sphere, ray));
            let (mut tests, mut failures) = (0, 0);
            for (t, reference) in ts.iter().zip(&reference) {
                let Some(reference) = reference else { continue };
                tests += 1;
                let ok = match (t, reference) {
                    (None, None) => true,
                    (Some(t), Some(tr)) => (*t as f64 - tr).abs() <= SPHERE_T_TOL * tr,
                    _ => false,
                };
                failures += u64::from(!ok);
            }
            rows.push(row("spheres", name, case, tests, failures, 0, ns));
        }
    }
    rows
}
