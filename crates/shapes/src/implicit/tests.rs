use super::*;
use crate::roots::RootSolver;
use crate::roots::eval_poly;
use crate::{Aabb, Ray, Shape, ShapeError};
use glam::{DVec3, Vec2, Vec3};
use rng::Pcg32;

const LAG: RootSolver = RootSolver::Laguerre { polish: true };
const SOLVERS: [RootSolver; 3] =
    [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }, RootSolver::Laguerre { polish: false }];

fn rand_point(rng: &mut Pcg32, s: f64) -> DVec3 {
    DVec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s))
}

fn sample_polys() -> Vec<Poly3> {
    vec![
        Poly3::sphere(1.5),
        Poly3::ellipsoid(1.0, 2.0, 0.5),
        Poly3::cylinder(0.7),
        Poly3::torus(2.0, 0.5),
        Poly3::heart(),
        Poly3::tangle_cube(),
        parse("3 x^3 y - 2.5 x y z^2 + 0.25 z^5 - x + 7").unwrap(),
    ]
}

#[test]
fn along_ray_agrees_with_eval() {
    let mut rng = Pcg32::seed_from_u64(10);
    for poly in sample_polys() {
        for _ in 0..50 {
            let o = rand_point(&mut rng, 3.0);
            let d = rand_point(&mut rng, 1.0);
            let c = poly.along_ray(o, d);
            assert_eq!(c.len(), poly.degree() as usize + 1);
            for t in [-2.0, -0.3, 0.0, 0.7, 1.9, 4.0] {
                let p = o + t * d;
                let (want, got) = (poly.eval(p), eval_poly(&c, t));
                let scale = poly.eval_abs(p).max(1.0);
                assert!((want - got).abs() <= 1e-10 * scale, "{poly:?} at t={t}: {want} vs {got}");
            }
        }
    }
}

#[test]
fn gradient_agrees_with_finite_differences() {
    let mut rng = Pcg32::seed_from_u64(11);
    let h = 1e-5;
    for poly in sample_polys() {
        for _ in 0..50 {
            let p = rand_point(&mut rng, 2.0);
            let g = poly.gradient(p);
            for axis in 0..3 {
                let mut e = DVec3::ZERO;
                e[axis] = h;
                let fd = (poly.eval(p + e) - poly.eval(p - e)) / (2.0 * h);
                let scale = poly.eval_abs(p).max(1.0);
                assert!((fd - g[axis]).abs() <= 1e-6 * scale, "{poly:?} at {p}: ∂{axis} {} vs {fd}", g[axis]);
            }
        }
    }
}

#[test]
fn builders_have_the_documented_values() {
    assert_eq!(Poly3::sphere(2.0).eval(DVec3::new(2.0, 0.0, 0.0)), 0.0);
    assert!(Poly3::sphere(2.0).eval(DVec3::ZERO) < 0.0);
    assert_eq!(Poly3::ellipsoid(1.0, 2.0, 4.0).eval(DVec3::new(0.0, 2.0, 0.0)), 0.0);
    assert_eq!(Poly3::ellipsoid(1.0, 2.0, 4.0).eval(DVec3::new(0.0, 0.0, 4.0)), 0.0);
    assert_eq!(Poly3::cylinder(0.5).eval(DVec3::new(0.0, 0.5, 123.0)), 0.0);
    let torus = Poly3::torus(2.0, 0.5);
    assert_eq!(torus.degree(), 4);
    for p in [DVec3::new(2.5, 0.0, 0.0), DVec3::new(0.0, -1.5, 0.0), DVec3::new(2.0, 0.0, 0.5)] {
        assert_eq!(torus.eval(p), 0.0, "{p}");
    }
    assert!(torus.eval(DVec3::new(2.0, 0.0, 0.0)) < 0.0 && torus.eval(DVec3::ZERO) > 0.0);
    let heart = Poly3::heart();
    assert_eq!(heart.degree(), 6);
    assert!(heart.eval(DVec3::ZERO) < 0.0);
    assert_eq!(heart.eval(DVec3::new(0.0, 0.0, -1.0)), 0.0);
    assert_eq!(Poly3::tangle_cube().degree(), 4);
}

#[test]
fn poly3_new_normalises_and_rejects() {
    let t = |coeff, exps| Term { coeff, exps };
    let p = Poly3::new(vec![t(1.0, [2, 0, 0]), t(2.0, [0, 0, 0]), t(-1.0, [0, 0, 0]), t(0.0, [0, 0, 7])]).unwrap();
    assert_eq!(p.terms().len(), 2);
    assert_eq!(p.degree(), 2);
    assert!(Poly3::new(vec![]).is_err());
    assert!(Poly3::new(vec![t(1.0, [1, 0, 0]), t(-1.0, [1, 0, 0])]).is_err());
    assert!(Poly3::new(vec![t(f64::NAN, [1, 0, 0])]).is_err());
    assert!(Poly3::new(vec![t(f64::INFINITY, [1, 0, 0])]).is_err());
    assert!(Poly3::new(vec![t(1.0, [20, 20, 0])]).is_err());
}

#[test]
fn parse_round_trips_the_builders() {
    let mut rng = Pcg32::seed_from_u64(12);
    let cases = [
        ("(x^2 + y^2 + z^2 + 2^2 - 0.5^2)^2 - 4*2^2 (x^2 + y^2)", Poly3::torus(2.0, 0.5)),
        ("(x^2+y^2+z^2 + 3.75)^2 - 16x^2 - 16 y^2", Poly3::torus(2.0, 0.5)),
        ("(x^2 + 2.25 y^2 + z^2 - 1)^3 - x^2 z^3 - 0.1125 y^2 z^3", Poly3::heart()),
        ("(x^2 + 9/4 y^2 + z^2 - 1)^3 - x^2 z^3 - 9/80 y^2 z^3", Poly3::heart()),
        ("x*x + y y + Z^2 - 2.25", Poly3::sphere(1.5)),
        ("x^4 - 5x^2 + y^4 - 5 y^2 + z^4 - 5 z^2 + 11.8", Poly3::tangle_cube()),
        ("-(-x^2) + y^2 - 0.49", Poly3::cylinder(0.7)),
        ("x^2 + 0.25 y^2 + 4e0 z^2 - 1", Poly3::ellipsoid(1.0, 2.0, 0.5)),
    ];
    for (text, built) in &cases {
        let parsed = parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
        assert_eq!(parsed.degree(), built.degree(), "{text}");
        for _ in 0..100 {
            let p = rand_point(&mut rng, 2.0);
            let (a, b) = (parsed.eval(p), built.eval(p));
            assert!((a - b).abs() <= 1e-12 * built.eval_abs(p).max(1.0), "{text} at {p}: {a} vs {b}");
        }
    }
}

#[test]
fn parse_accepts_the_grammar() {
    let p = parse("2x y^2 * -3 + 1.5e-1 z - +4").unwrap();
    let q = DVec3::new(1.5, -2.0, 3.0);
    assert!((p.eval(q) - (2.0 * 1.5 * 4.0 * -3.0 + 0.15 * 3.0 - 4.0)).abs() < 1e-12);
    let p = parse("(x + 1)^2 (y - 1)").unwrap();
    assert!((p.eval(q) - 6.25 * -3.0).abs() < 1e-12);
    assert_eq!(parse("x^0 + x").unwrap().eval(q), 2.5);
    assert_eq!(parse("x^2/4 - 2/4/2 y").unwrap().eval(q), 1.5 * 1.5 / 4.0 + 0.5);
    assert_eq!(parse("  x\t+\ny ").unwrap().degree(), 1);
}

#[test]
fn parse_rejects_garbage_with_positions() {
    let cases = [
        ("x^^2", 3),
        ("(x+1", 5),
        ("x^-1", 3),
        ("1e999", 1),
        ("x^2.5", 3),
        ("x + w", 5),
        ("x +", 4),
        ("", 1),
        ("x)", 2),
        ("1e", 2),
        ("1/x", 3),
        ("x/(1-1)", 3),
        ("x*/y", 3),
        ("x - x", 0),
        ("(x+y+z)^40", 0),
        ("3 x ^ 99", 7),
    ];
    for (text, pos) in cases {
        let err = parse(text).expect_err(text);
        let ShapeError::Invalid(msg) = &err;
        if pos > 0 {
            assert!(msg.contains(&format!("character {pos}:")), "{text}: {msg}");
        }
    }
}

fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
    Ray::new(Vec3::from(o), Vec3::from(d))
}

#[test]
fn sphere_matches_the_analytic_solution() {
    let mut rng = Pcg32::seed_from_u64(13);
    let r = 1.5f32;
    for solver in SOLVERS {
        let s = Implicit::sphere(r, solver).unwrap();
        let mut hits = 0;
        for _ in 0..500 {
            let o = rand_point(&mut rng, 4.0).as_vec3();
            let d = rand_point(&mut rng, 1.6).as_vec3() - o;
            let ry = Ray::new(o, d);
            // Analytic in f64: |o + t d|² = r².
            let (o64, d64) = (o.as_dvec3(), d.as_dvec3());
            let want = crate::roots::quadratic_f64(d64.dot(d64), 2.0 * o64.dot(d64), o64.dot(o64) - (r as f64).powi(2))
                .and_then(|(t0, t1)| [t0, t1].into_iter().find(|&t| t > 0.0));
            let got = s.intersect(&ry);
            match (want, got) {
                (None, None) => {}
                (Some(t), Some(h)) => {
                    hits += 1;
                    assert!((h.t as f64 - t).abs() <= 1e-5 * t.max(1.0), "{solver:?}: {} vs {t}", h.t);
                    assert!((h.p.length() - r).abs() < 1e-5);
                    assert!((h.n - h.p / r).length() < 1e-5, "normal {} at {}", h.n, h.p);
                }
                _ => panic!("{solver:?} {ry:?}: analytic {want:?}, implicit {got:?}"),
            }
        }
        assert!(hits > 100, "{hits}");
    }
}

#[test]
fn torus_axis_hole_tangent_and_inside_rays() {
    let (big, small) = (2.0f32, 0.5f32);
    for solver in SOLVERS {
        let t = Implicit::torus(big, small, solver).unwrap();
        // Along the x axis from (−5, 0, 0): the outer equator at x = −(R + r).
        let h = t.intersect(&ray([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0])).expect("axis ray");
        assert!((h.t - (5.0 - (big + small))).abs() < 1e-5, "{solver:?} {h:?}");
        assert!((h.n - Vec3::NEG_X).length() < 1e-6);
        // Non-unit direction: t scales.
        let h = t.intersect(&ray([-5.0, 0.0, 0.0], [4.0, 0.0, 0.0])).unwrap();
        assert!((h.t - (5.0 - (big + small)) / 4.0).abs() < 1e-6, "{h:?}");
        // Through the hole along z: misses.
        assert_eq!(t.intersect(&ray([0.0, 0.0, -5.0], [0.0, 0.0, 1.0])), None, "{solver:?}");
        assert_eq!(t.intersect(&ray([0.3, -0.2, 5.0], [0.0, 0.0, -1.0])), None, "{solver:?}");
        // Down onto the tube's top.
        let h = t.intersect(&ray([0.0, 2.0, 5.0], [0.0, 0.0, -1.0])).unwrap();
        assert!((h.t - 4.5).abs() < 1e-5 && (h.n - Vec3::Z).length() < 1e-5, "{h:?}");
        // Tangent: the line z = r touches the tube's top at x = −R (a double root).
        let (h, rep) = t.intersect_report(&ray([-5.0, 0.0, small], [1.0, 0.0, 0.0]));
        let h = h.unwrap_or_else(|| panic!("{solver:?}: tangent ray missed"));
        assert!((h.t - (5.0 - big)).abs() < 1e-4, "{solver:?} {h:?}");
        assert!((h.n - Vec3::Z).length() < 1e-3, "{solver:?} {h:?}");
        assert_eq!(rep.not_converged, 0);
        // Just above the tangent: a miss.
        assert_eq!(t.intersect(&ray([-5.0, 0.0, small + 1e-3], [1.0, 0.0, 0.0])), None);
        // Starting inside the tube at its centre line: exits at distance r, outward normal.
        let h = t.intersect(&ray([big, 0.0, 0.0], [1.0, 0.0, 0.0])).unwrap();
        assert!((h.t - small).abs() < 1e-6 && (h.n - Vec3::X).length() < 1e-6, "{h:?}");
        // Starting inside the box, in the hole: the inner equator at x = R − r.
        let h = t.intersect(&ray([0.0, 0.0, 0.0], [1.0, 0.0, 0.0])).unwrap();
        assert!((h.t - (big - small)).abs() < 1e-6 && (h.n - Vec3::NEG_X).length() < 1e-6, "{h:?}");
    }
}

#[test]
fn segment_limits_are_respected() {
    let t = Implicit::torus(2.0, 0.5, RootSolver::ClosedForm).unwrap();
    let o = Vec3::new(-5.0, 0.0, 0.0);
    // Hits along +x at t = 2.5, 3.5, 6.5, 7.5.
    assert_eq!(t.intersect(&Ray::segment(o, Vec3::X, 0.0, 2.4)), None);
    let h = t.intersect(&Ray::segment(o, Vec3::X, 2.6, 100.0)).unwrap();
    assert!((h.t - 3.5).abs() < 1e-5 && (h.n - Vec3::X).length() < 1e-5, "{h:?}");
    let h = t.intersect(&Ray::segment(o, Vec3::X, 3.6, 100.0)).unwrap();
    assert!((h.t - 6.5).abs() < 1e-5, "{h:?}");
    assert_eq!(t.intersect(&Ray::segment(o, Vec3::X, 7.6, 100.0)), None);
    // A ray that starts on the surface and leaves it does not hit itself.
    let start = Vec3::new(2.5, 0.0, 0.0);
    assert_eq!(t.intersect(&Ray::new(start, Vec3::X)), None);
    let h = t.intersect(&Ray::new(start, Vec3::NEG_X)).unwrap();
    assert!((h.t - 1.0).abs() < 1e-5, "{h:?}");
    // Behind the ray, and pointing away from the box.
    assert_eq!(t.intersect(&Ray::new(o, Vec3::NEG_X)), None);
    assert_eq!(t.intersect(&Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Y)), None);
    // Degenerate directions.
    assert_eq!(t.intersect(&Ray::new(o, Vec3::ZERO)), None);
    assert_eq!(t.intersect(&Ray::new(o, Vec3::new(f32::NAN, 0.0, 0.0))), None);
}

#[test]
fn heart_bounds_enclose_the_surface() {
    let s = Implicit::heart(LAG).unwrap();
    let (lo, hi) = (s.bounds.min.as_dvec3(), s.bounds.max.as_dvec3());
    let n = 60;
    let mut min_f = f64::INFINITY;
    // F > 0 all over the box's surface: sample each face on an n×n grid.
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [lo[axis], hi[axis]] {
            for i in 0..=n {
                for j in 0..=n {
                    let mut p = DVec3::ZERO;
                    p[axis] = side;
                    p[u] = lo[u] + (hi[u] - lo[u]) * i as f64 / n as f64;
                    p[v] = lo[v] + (hi[v] - lo[v]) * j as f64 / n as f64;
                    min_f = min_f.min(s.poly.eval(p));
                }
            }
        }
    }
    println!("heart: min F on the bounding box surface {min_f:e}");
    assert!(min_f > 0.0, "{min_f}");
    // And the surface reaches close to the box (the bounds are reasonably tight):
    // rays along each axis from outside hit within 0.25 of the box.
    for (o, d) in [
        ([-5.0, 0.0, 0.3], [1.0, 0.0, 0.0]),
        ([0.0, -5.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -5.0], [0.0, 0.0, 1.0]),
        ([0.5, 0.0, 5.0], [0.0, 0.0, -1.0]),
    ] {
        let h = s.intersect(&ray(o, d)).expect("axis ray hits the heart");
        let entry = s.bounds.hit(&ray(o, d), f32::INFINITY).unwrap();
        assert!(h.t - entry < 0.25, "{o:?}: hit {} entry {entry}", h.t);
    }
}

#[test]
fn heart_hits_lie_on_the_surface_with_true_normals() {
    let mut rng = Pcg32::seed_from_u64(14);
    for solver in [RootSolver::ClosedForm, LAG] {
        let s = Implicit::heart(solver).unwrap();
        let mut hits = 0;
        for _ in 0..300 {
            let o = (rand_point(&mut rng, 1.0).normalize() * 4.0).as_vec3();
            let target = rand_point(&mut rng, 0.6).as_vec3();
            let r = Ray::new(o, target - o);
            let (h, rep) = s.intersect_report(&r);
            assert!(rep.used_laguerre, "degree 6 always uses Laguerre");
            assert_eq!(rep.not_converged, 0);
            let Some(h) = h else { continue };
            hits += 1;
            let p = h.p.as_dvec3();
            // |F| small relative to its terms, and the normal parallel to a
            // finite-difference gradient.
            assert!(s.poly.eval(p).abs() <= 1e-5 * s.poly.eval_abs(p).max(1.0), "F = {}", s.poly.eval(p));
            let e = 1e-6;
            let fd = DVec3::new(
                s.poly.eval(p + DVec3::X * e) - s.poly.eval(p - DVec3::X * e),
                s.poly.eval(p + DVec3::Y * e) - s.poly.eval(p - DVec3::Y * e),
                s.poly.eval(p + DVec3::Z * e) - s.poly.eval(p - DVec3::Z * e),
            );
            if fd.length() < 1e-9 {
                continue; // near a cusp
            }
            assert!(fd.normalize().dot(h.n.as_dvec3()) > 1.0 - 1e-6, "{} vs {}", h.n, fd.normalize());
            // And perpendicular to finite-difference tangents: neighbouring rays hit at
            // p′ with (p′ − p)·n = O(|p′ − p|²).
            for off in [Vec3::X, Vec3::Y, Vec3::Z] {
                let delta = 1e-3;
                let r2 = Ray::new(o, target + off * delta - o);
                if let Some(h2) = s.intersect(&r2) {
                    let dp = h2.p - h.p;
                    if dp.length() < 1e-2 {
                        assert!(dp.dot(h.n).abs() < 0.05 * dp.length() + 1e-5, "dp {dp} n {}", h.n);
                    }
                }
            }
            // The ray's entry side: the normal faces the ray for a hit from outside.
            assert!(h.n.dot(r.dir) < 0.0 || s.poly.eval(o.as_dvec3()) < 0.0);
        }
        assert!(hits > 100, "{hits}");
    }
}

/// Traces `n` random rays (fixed seed) aimed into `a`'s box with both shapes;
/// returns (hits, disagreements, non-converged roots of `b`). A disagreement is a
/// hit/miss mismatch, a t differing by more than 1e-4 relative, or normals apart.
fn compare(a: &Implicit, b: &Implicit, n: usize, seed: u64) -> (usize, usize, u32) {
    let mut rng = Pcg32::seed_from_u64(seed);
    let (mut disagree, mut hits, mut not_converged) = (0, 0, 0);
    let (lo, hi) = (a.bounds.min.as_dvec3(), a.bounds.max.as_dvec3());
    for _ in 0..n {
        let o = (rand_point(&mut rng, 1.0).normalize() * rng.range(1.5, 4.0) * hi.length()).as_vec3();
        let target = DVec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), rng.range(lo.z, hi.z)).as_vec3();
        let r = Ray::new(o, (target - o) * rng.range(0.1, 3.0) as f32);
        let (x, _) = a.intersect_report(&r);
        let (y, rep) = b.intersect_report(&r);
        not_converged += rep.not_converged;
        match (x, y) {
            (None, None) => {}
            (Some(x), Some(y)) => {
                hits += 1;
                if (x.t - y.t).abs() > 1e-4 * x.t.abs().max(1e-3) || (x.n - y.n).length() > 1e-3 {
                    disagree += 1;
                    println!("disagree: {r:?}: {x:?} vs {y:?}");
                }
            }
            _ => {
                disagree += 1;
                println!("hit/miss disagree: {r:?}: {x:?} vs {y:?}");
            }
        }
    }
    (hits, disagree, not_converged)
}

#[test]
fn closed_form_and_laguerre_agree_on_random_rays() {
    let n = 1000;
    let torus = Implicit::torus(2.0, 0.5, RootSolver::ClosedForm).unwrap();
    let (hits, disagree, not_converged) = compare(&torus, &Implicit { solver: LAG, ..torus.clone() }, n, 15);
    println!(
        "torus, closed form vs Laguerre: {hits} hits of {n} rays, {disagree} disagreements, \
         {not_converged} non-converged roots"
    );
    assert!(hits > 300, "{hits}");
    assert!(disagree <= n / 200, "{disagree}");
    assert_eq!(not_converged, 0);
    // The tangle cube: a quartic of genus 5, many grazing rays.
    let b = Aabb { min: Vec3::splat(-2.27), max: Vec3::splat(2.27) };
    let tangle = Implicit::new(Poly3::tangle_cube(), b, RootSolver::ClosedForm).unwrap();
    let (hits, disagree, not_converged) = compare(&tangle, &Implicit { solver: LAG, ..tangle.clone() }, n, 16);
    println!(
        "tangle cube, closed form vs Laguerre: {hits} hits, {disagree} disagreements, {not_converged} non-converged"
    );
    assert!(hits > 300 && disagree <= n / 200 && not_converged == 0);
    // The sextic heart: Laguerre with and without polishing.
    let heart = Implicit::heart(LAG).unwrap();
    let raw = Implicit { solver: RootSolver::Laguerre { polish: false }, ..heart.clone() };
    let (hits, disagree, not_converged) = compare(&heart, &raw, n, 17);
    println!(
        "heart, polished vs unpolished Laguerre: {hits} hits, {disagree} disagreements, \
         {not_converged} non-converged"
    );
    assert!(hits > 300 && disagree <= n / 200 && not_converged == 0);
}

#[test]
fn implicit_validates_its_parameters() {
    let p = Poly3::sphere(1.0);
    let bad = [
        Aabb::EMPTY,
        Aabb { min: Vec3::ZERO, max: Vec3::new(1.0, f32::INFINITY, 1.0) },
        Aabb { min: Vec3::splat(f32::NAN), max: Vec3::ONE },
        Aabb { min: Vec3::ONE, max: Vec3::ONE },
    ];
    for b in bad {
        assert!(Implicit::new(p.clone(), b, LAG).is_err(), "{b:?}");
    }
    assert!(Implicit::sphere(0.0, LAG).is_err());
    assert!(Implicit::sphere(f32::NAN, LAG).is_err());
    assert!(Implicit::torus(1.0, -0.1, LAG).is_err());
    let s = Implicit::torus(2.0, 0.5, LAG).unwrap();
    assert_eq!(s.bounds(), Aabb { min: Vec3::new(-2.5, -2.5, -0.5), max: Vec3::new(2.5, 2.5, 0.5) });
    assert_eq!(s.area(), 0.0);
    assert_eq!(s.sample_area(Vec2::new(0.5, 0.5)), None);
}

#[test]
fn cylinder_is_clipped_by_its_bounds() {
    let b = Aabb { min: Vec3::new(-1.0, -1.0, -2.0), max: Vec3::new(1.0, 1.0, 2.0) };
    let s = Implicit::new(Poly3::cylinder(1.0), b, RootSolver::ClosedForm).unwrap();
    let h = s.intersect(&ray([-5.0, 0.0, 1.5], [1.0, 0.0, 0.0])).unwrap();
    assert!((h.t - 4.0).abs() < 1e-6 && (h.n - Vec3::NEG_X).length() < 1e-6);
    // Above the box: no surface there.
    assert_eq!(s.intersect(&ray([-5.0, 0.0, 2.5], [1.0, 0.0, 0.0])), None);
    // Along the axis, inside: never reaches the wall (no caps).
    assert_eq!(s.intersect(&ray([0.0, 0.0, -5.0], [0.0, 0.0, 1.0])), None);
}
