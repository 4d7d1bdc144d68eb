use super::*;

use rng::Pcg32;

fn sphere(c: Vec3, r: f32) -> Sphere {
    Sphere::new(c, r, SphereMethod::Geometric).unwrap()
}

/// All four single-precision variants of one sphere.
fn all_methods(s: &Sphere, ray: &Ray) -> [Option<f32>; 4] {
    [
        s.intersect_geometric(ray),
        s.intersect_geometric_literal(ray),
        s.intersect_algebraic(ray, false),
        s.intersect_algebraic(ray, true),
    ]
}

#[test]
fn rejects_invalid_parameters() {
    assert!(Sphere::new(Vec3::ZERO, 0.0, SphereMethod::Geometric).is_err());
    assert!(Sphere::new(Vec3::ZERO, -1.0, SphereMethod::Geometric).is_err());
    assert!(Sphere::new(Vec3::ZERO, f32::NAN, SphereMethod::Geometric).is_err());
    assert!(Sphere::new(Vec3::ZERO, f32::INFINITY, SphereMethod::Geometric).is_err());
    assert!(Sphere::new(Vec3::new(f32::NAN, 0.0, 0.0), 1.0, SphereMethod::Geometric).is_err());
    assert_eq!(SphereMethod::default(), SphereMethod::Geometric);
}

#[test]
fn hit_from_outside_is_exact_for_an_axis_ray() {
    let s = sphere(Vec3::ZERO, 2.0);
    let ray = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
    for (i, t) in all_methods(&s, &ray).into_iter().enumerate() {
        assert_eq!(t, Some(3.0), "method {i}");
    }
    for method in [SphereMethod::Geometric, SphereMethod::AlgebraicNaive, SphereMethod::AlgebraicStable] {
        let h = Sphere { method, ..s }.intersect(&ray).unwrap();
        assert_eq!(h.t, 3.0);
        assert_eq!(h.p, Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(h.n, Vec3::new(0.0, 0.0, -1.0));
    }
}

#[test]
fn origin_inside_gets_the_far_root() {
    let s = sphere(Vec3::new(1.0, 2.0, 3.0), 1.5);
    let ray = Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::X);
    for (i, t) in all_methods(&s, &ray).into_iter().enumerate() {
        assert_eq!(t, Some(1.5), "method {i}");
    }
    let off_centre = Ray::new(Vec3::new(1.5, 2.0, 3.0), -Vec3::X);
    for (i, t) in all_methods(&s, &off_centre).into_iter().enumerate() {
        assert_eq!(t, Some(2.0), "method {i}");
    }
    let h = s.intersect(&off_centre).unwrap();
    assert!((h.n - (-Vec3::X)).length() < 1e-6, "outward normal even from inside: {}", h.n);
}

#[test]
fn tangent_and_near_tangent_rays() {
    let s = sphere(Vec3::ZERO, 2.0);
    let tangent = Ray::new(Vec3::new(-5.0, 2.0, 0.0), Vec3::X);
    // Robust geometric: d² = |L − t_ca d̂|² = 4 = r² exactly, so a double root at 5.
    assert_eq!(s.intersect_geometric(&tangent), Some(5.0));
    for (i, t) in all_methods(&s, &tangent).into_iter().enumerate() {
        if let Some(t) = t {
            assert!((t - 5.0).abs() < 1e-3, "method {i}: grazing hit at {t}");
        }
    }
    let just_outside = Ray::new(Vec3::new(-5.0, 2.0 * (1.0 + 1e-6), 0.0), Vec3::X);
    assert_eq!(s.intersect_geometric(&just_outside), None);
    let y = 2.0 * (1.0 - 1e-6f32);
    let just_inside = Ray::new(Vec3::new(-5.0, y, 0.0), Vec3::X);
    let expect = 5.0 - (4.0f64 - (y as f64).powi(2)).sqrt();
    let t = s.intersect_geometric(&just_inside).expect("a hit just inside the tangent");
    assert!((t as f64 - expect).abs() < 1e-5, "{t} vs {expect}");
}

#[test]
fn misses_behind_and_segment_limits() {
    let s = sphere(Vec3::ZERO, 2.0);
    let miss = Ray::new(Vec3::new(-5.0, 3.0, 0.0), Vec3::X);
    let behind = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
    for r in [miss, behind] {
        assert_eq!(all_methods(&s, &r), [None; 4]);
        assert!(s.intersect(&r).is_none());
    }
    let o = Vec3::new(0.0, 0.0, -5.0);
    assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 0.0, 2.9)), [None; 4]);
    assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 0.0, 3.1)), [Some(3.0); 4]);
    // t_min past the near root: the far root.
    assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 4.0, 100.0)), [Some(7.0); 4]);
    // t_max exclusive, t_min exclusive.
    assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 3.0, 7.0)), [None; 4]);
}

#[test]
fn unnormalised_directions_give_the_same_point() {
    let s = sphere(Vec3::new(0.25, -0.5, 1.0), 0.75);
    let o = Vec3::new(-3.0, 1.0, 2.0);
    let d = (Vec3::new(0.3, -0.4, 1.1) - o).normalize();
    let base = s.intersect(&Ray::new(o, d)).unwrap();
    for scale in [0.37f32, 1e-3, 13.0, 1e3] {
        for method in [SphereMethod::Geometric, SphereMethod::AlgebraicNaive, SphereMethod::AlgebraicStable] {
            let h = Sphere { method, ..s }.intersect(&Ray::new(o, d * scale)).unwrap();
            assert!((h.p - base.p).length() < 1e-5, "{method:?} scale {scale}: {} vs {}", h.p, base.p);
            assert!((h.t * scale - base.t).abs() < 1e-5 * base.t, "{method:?} scale {scale}");
            assert!((h.n - base.n).length() < 1e-5);
            assert!(((h.p - s.centre).length() - s.radius).abs() < 1e-6);
        }
    }
}

/// 10⁴ random rays: the four methods agree on hit/miss and on the hit point, except
/// near tangency (the discriminant is then dominated by rounding and each method may
/// decide either way) or with the origin next to the surface (the near root ≈ 0 may
/// fall on either side of t_min).
#[test]
fn methods_agree_on_random_rays() {
    let mut rng = Pcg32::seed_from_u64(0x9E37_79B9_7F4A_7C15);
    let s = sphere(Vec3::new(0.3, -0.2, 0.5), 1.3);
    let n = 10_000;
    let (mut disagree, mut hits, mut unexplained) = (0, 0, 0);
    for _ in 0..n {
        let o = Vec3::new(rng.range_f32(-4.0, 4.0), rng.range_f32(-4.0, 4.0), rng.range_f32(-4.0, 4.0));
        // Half the rays aimed at a point within 1.5 r of the centre (so many hit, some
        // graze), half in uniformly random directions.
        let len = rng.range_f32(0.1, 10.0);
        let d = if rng.next_f32() < 0.5 {
            (s.centre + 1.5 * s.radius * rng.next_f32() * rng.unit_vector().as_vec3() - o).normalize() * len
        } else {
            rng.unit_vector().as_vec3() * len
        };
        let ray = Ray::new(o, d);
        let ts = all_methods(&s, &ray);
        let pts: Vec<Option<Vec3>> = ts.iter().map(|t| t.map(|t| ray.at(t))).collect();
        let scale = (o - s.centre).length() + s.radius;
        let agree = pts.iter().all(|p| match (p, pts[0]) {
            (None, None) => true,
            (Some(a), Some(b)) => (*a - b).length() <= 1e-4 * scale,
            _ => false,
        });
        hits += usize::from(ts[0].is_some());
        if !agree {
            disagree += 1;
            // Classify with the f64 reference: distance of the line from the centre.
            let f = (o - s.centre).as_dvec3();
            let dd = d.as_dvec3().normalize();
            let miss_dist = (f - f.dot(dd) * dd).length();
            let near_tangent = (miss_dist - s.radius as f64).abs() < 1e-3 * s.radius as f64;
            let near_surface = (f.length() - s.radius as f64).abs() < 1e-4;
            if !(near_tangent || near_surface) {
                unexplained += 1;
                eprintln!("unexplained disagreement: o={o} d={d} {ts:?}");
            }
        }
    }
    eprintln!("random rays: {n}, hits {hits}, disagreements {disagree}, unexplained {unexplained}");
    // Not asserted, for the record: rays aimed at distance r(1 ± δ) from the centre.
    for delta in [1e-5f32, 1e-6, 1e-7] {
        let (mut grazing_disagree, m) = (0, 1000);
        let mut wrong = [0usize; 4];
        for i in 0..m {
            // The line through q = c + k·r·side with a direction perpendicular to side
            // passes the centre at distance k·r.
            let d = rng.unit_vector().as_vec3();
            let side = d.cross(rng.unit_vector().as_vec3()).normalize();
            let k = if i % 2 == 0 { 1.0 - delta } else { 1.0 + delta };
            let o = s.centre + k * s.radius * side - 5.0 * d;
            let hit = all_methods(&s, &Ray::new(o, d)).map(|t| t.is_some());
            grazing_disagree += usize::from(hit.iter().any(|&h| h != hit[0]));
            // Right or wrong, by the f64 reference for the same (rounded) f32 ray.
            let truth = reference_roots_f64(s.centre.as_dvec3(), s.radius as f64, o.as_dvec3(), d.as_dvec3())
                .is_some_and(|(_, t1)| t1 > 0.0);
            for k in 0..4 {
                wrong[k] += usize::from(hit[k] != truth);
            }
        }
        eprintln!(
            "grazing rays (offset r(1 ± {delta:e})): {grazing_disagree}/{m} with a hit/miss disagreement; wrong \
             decisions vs f64 [robust geometric, literal geometric, naive, stable]: {wrong:?}"
        );
    }
    assert!(hits > n / 4, "the test should exercise hits: {hits}");
    assert_eq!(unexplained, 0);
    assert!(disagree * 1000 <= n, "{disagree} disagreements out of {n}");
}

/// Far origin, small sphere: origin 10⁴ away, radius 10⁻². The robust geometric and
/// the stable algebraic method stay within 10⁻³ relative of the f64 reference (in
/// practice a few ulp); the literal geometric and naive algebraic ones lose r² in the
/// discriminant and miss or wander (printed, not asserted: their failure is the point).
#[test]
fn far_origin_accuracy() {
    let mut rng = Pcg32::seed_from_u64(0x0123_4567_89AB_CDEF);
    let c = Vec3::new(1.0, 2.0, 3.0);
    let r = 1e-2f32;
    let s = sphere(c, r);
    let names = ["geometric (robust)", "geometric (literal)", "algebraic naive", "algebraic stable"];
    let mut misses = [0usize; 5];
    let mut max_rel = [0f64; 5];
    // Distance error along the ray, |t − t_ref|·|d|, in units of the radius.
    let mut max_dist_r = [0f64; 5];
    let n = 2000;
    for i in 0..n {
        let o = c + 1e4 * rng.unit_vector().as_vec3();
        // Aim within 0.7 r of the centre: a sure hit even after rounding o and d.
        let target = c + 0.7 * r * rng.next_f32().sqrt() * rng.unit_vector().as_vec3();
        let mut d = target - o;
        if i % 2 == 0 {
            d = d.normalize();
        }
        let ray = Ray::new(o, d);
        let reference =
            reference_roots_f64(c.as_dvec3(), r as f64, o.as_dvec3(), d.as_dvec3()).expect("the reference hits").0;
        assert!(reference > 0.0);
        let ts = all_methods(&s, &ray);
        // The stand-in for roots::quadratic_stable: stable roots, f64 discriminant,
        // but from the f32 coefficients.
        let f = o - c;
        let f64disc = quadratic_stable(d.dot(d), 2.0 * d.dot(f), f.dot(f) - r * r).map(|(t0, _)| t0);
        for (k, t) in ts.into_iter().chain([f64disc]).enumerate() {
            match t {
                None => misses[k] += 1,
                Some(t) => {
                    let err = (t as f64 - reference).abs();
                    max_rel[k] = max_rel[k].max(err / reference);
                    max_dist_r[k] = max_dist_r[k].max(err * d.length() as f64 / r as f64);
                }
            }
        }
    }
    for k in 0..5 {
        let name = names.get(k).copied().unwrap_or("quadratic_stable on f32 coefficients (f64 disc)");
        eprintln!(
            "far origin, {name}: misses {}/{n}, max relative error of t {:.3e} ({:.3e} radii along the ray)",
            misses[k], max_rel[k], max_dist_r[k]
        );
    }
    for k in [0, 3] {
        assert_eq!(misses[k], 0, "{}", names[k]);
        assert!(max_rel[k] < 1e-3, "{}: {}", names[k], max_rel[k]);
    }
}

#[test]
fn reference_roots_are_right() {
    let (t0, t1) =
        reference_roots_f64(DVec3::ZERO, 2.0, DVec3::new(0.0, 0.0, -5.0), DVec3::new(0.0, 0.0, 2.0)).unwrap();
    assert_eq!((t0, t1), (1.5, 3.5));
    assert!(reference_roots_f64(DVec3::ZERO, 1.0, DVec3::new(0.0, 2.0, 0.0), DVec3::X).is_none());
    let (t0, t1) = reference_roots_f64(DVec3::ZERO, 1.0, DVec3::ZERO, DVec3::Y).unwrap();
    assert_eq!((t0, t1), (-1.0, 1.0));
}

#[test]
fn sample_area_is_on_the_sphere_and_unbiased() {
    let s = sphere(Vec3::new(1.0, -2.0, 0.5), 0.8);
    assert!((s.area() - 4.0 * PI * 0.64).abs() < 1e-5);
    let b = s.bounds();
    let mut rng = Pcg32::seed_from_u64(42);
    let n = 20_000;
    let mut sum = glam::DVec3::ZERO;
    for _ in 0..n {
        let (p, nrm) = s.sample_area(Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
        assert!(((p - s.centre).length() - s.radius).abs() < 1e-5);
        assert!((nrm.length() - 1.0).abs() < 1e-5);
        assert!(nrm.dot(p - s.centre) > 0.0, "normal points outward");
        assert!(p.cmpge(b.min - 1e-6).all() && p.cmple(b.max + 1e-6).all());
        sum += p.as_dvec3();
    }
    // Each coordinate of a uniform point on the unit sphere has variance 1/3.
    let sigma = s.radius as f64 * (1.0 / (3.0 * n as f64)).sqrt();
    let err = (sum / n as f64 - s.centre.as_dvec3()).abs().max_element();
    assert!(err < 4.0 * sigma, "mean off by {err}, σ = {sigma}");
}
