use super::*;
use glam::Quat;

use rng::Pcg32;

fn v2(pts: &[(f32, f32)]) -> Vec<Vec2> {
    pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect()
}

fn xy(pts: &[Vec2]) -> Vec<Vec3> {
    pts.iter().map(|p| p.extend(0.0)).collect()
}

fn square() -> Vec<Vec2> {
    v2(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])
}

fn l_shape() -> Vec<Vec2> {
    v2(&[(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)])
}

/// The regular star polygon {5/2}, circumradius 1.
fn pentagram() -> Vec<Vec2> {
    (0..5)
        .map(|k| {
            let a = (90.0f32 + 144.0 * k as f32).to_radians();
            Vec2::new(a.cos(), a.sin())
        })
        .collect()
}

/// A simple (non-self-intersecting) 10-vertex star: five reflex vertices.
fn simple_star() -> Vec<Vec2> {
    (0..10)
        .map(|k| {
            let a = (90.0f32 + 36.0 * k as f32).to_radians();
            let r = if k % 2 == 0 { 1.0 } else { 0.4 };
            Vec2::new(r * a.cos(), r * a.sin())
        })
        .collect()
}

fn both(poly: &[Vec2], p: Vec2) -> (bool, bool) {
    (inside_crossing(poly, p), inside_winding(poly, p))
}

#[test]
fn inside_tests_on_square_l_shape_and_star() {
    let sq = square();
    assert_eq!(both(&sq, Vec2::new(0.5, 0.5)), (true, true));
    assert_eq!(both(&sq, Vec2::new(1.5, 0.5)), (false, false));
    assert_eq!(both(&sq, Vec2::new(-0.5, 0.5)), (false, false));
    assert_eq!(both(&sq, Vec2::new(0.5, 2.0)), (false, false));
    let l = l_shape();
    for (p, expect) in
        [((0.5, 0.5), true), ((1.5, 0.5), true), ((0.5, 1.5), true), ((1.5, 1.5), false), ((2.5, 0.5), false)]
    {
        assert_eq!(both(&l, Vec2::new(p.0, p.1)), (expect, expect), "{p:?}");
    }
    let star = simple_star();
    assert_eq!(both(&star, Vec2::ZERO), (true, true));
    assert_eq!(both(&star, Vec2::new(0.0, 0.9)), (true, true)); // In the top point.
    assert_eq!(both(&star, Vec2::new(0.5, 0.6)), (false, false)); // Between points.
    // Orientation does not matter.
    let rev: Vec<Vec2> = l.iter().rev().copied().collect();
    assert_eq!(both(&rev, Vec2::new(1.5, 0.5)), (true, true));
    assert_eq!(both(&rev, Vec2::new(1.5, 1.5)), (false, false));
}

#[test]
fn crossing_and_winding_differ_only_in_the_pentagrams_centre() {
    let star = pentagram();
    assert_eq!(both(&star, Vec2::ZERO), (false, true), "winding number 2: even–odd out, non-zero in");
    // Inner pentagon: circumradius cos 72°/cos 36° ≈ 0.382, inradius cos 72° ≈ 0.309.
    let (r_out, r_in) = (0.382f32 + 1e-3, 0.309 - 1e-3);
    let (mut differ, mut agree_inside) = (0, 0);
    let m = 121;
    for a in 0..m {
        for b in 0..m {
            let p = Vec2::new(-1.2 + 2.4 * a as f32 / (m - 1) as f32, -1.2 + 2.4 * b as f32 / (m - 1) as f32);
            let (c, w) = both(&star, p);
            if c != w {
                differ += 1;
                assert!(p.length() < r_out, "differ outside the inner pentagon at {p}");
                assert!(!c && w);
            } else if c {
                agree_inside += 1;
            }
            if p.length() < r_in {
                assert!(c != w, "inner pentagon point {p} should differ");
            }
        }
    }
    assert!(differ > 100 && agree_inside > 100, "{differ} {agree_inside}");
    // For simple polygons the two agree everywhere on the grid, boundary included.
    for poly in [square(), l_shape(), simple_star()] {
        for a in 0..41 {
            for b in 0..41 {
                let p = Vec2::new(-0.5 + a as f32 * 0.0625, -0.5 + b as f32 * 0.0625);
                let (c, w) = both(&poly, p);
                assert_eq!(c, w, "{p}");
            }
        }
    }
}

#[test]
fn half_line_through_vertices_and_along_edges() {
    // Diamond: the +x half-line from the centre passes through vertex (1, 0), where the
    // boundary passes through: counted once, inside. From (−2, 0) it passes two
    // vertices: counted twice, outside.
    let diamond = v2(&[(0.0, -1.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0)]);
    assert_eq!(both(&diamond, Vec2::ZERO), (true, true));
    assert_eq!(both(&diamond, Vec2::new(-2.0, 0.0)), (false, false));
    assert_eq!(both(&diamond, Vec2::new(2.0, 0.0)), (false, false));
    // V notch: the half-line from (0.5, 1) touches the notch's bottom vertex (1, 1), a
    // local minimum of the boundary: counted twice (parity unchanged), inside.
    let notch = v2(&[(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (1.0, 1.0), (0.0, 2.0)]);
    assert_eq!(both(&notch, Vec2::new(0.5, 1.0)), (true, true));
    assert_eq!(both(&notch, Vec2::new(0.5, 2.0)), (false, false));
    assert_eq!(both(&notch, Vec2::new(1.0, 1.5)), (false, false));
    // Along an edge: the half-line from (−1, 0) runs along the bottom edge: outside.
    let sq = square();
    assert_eq!(both(&sq, Vec2::new(-1.0, 0.0)), (false, false));
    assert_eq!(both(&sq, Vec2::new(-1.0, 1.0)), (false, false));
    // Boundary points: bottom and left edges in, top and right out.
    assert_eq!(both(&sq, Vec2::new(0.5, 0.0)), (true, true));
    assert_eq!(both(&sq, Vec2::new(0.0, 0.5)), (true, true));
    assert_eq!(both(&sq, Vec2::new(0.5, 1.0)), (false, false));
    assert_eq!(both(&sq, Vec2::new(1.0, 0.5)), (false, false));
    assert_eq!(both(&sq, Vec2::new(0.0, 0.0)), (true, true));
    assert_eq!(both(&sq, Vec2::new(1.0, 1.0)), (false, false));
}

#[test]
fn polygons_sharing_an_edge_claim_it_exactly_once() {
    // 2D: two triangles sharing the diagonal of the unit square, in both traversal
    // directions; points exactly on the diagonal (k/16, k/16) are in exactly one.
    let lower = v2(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)]);
    let upper = v2(&[(0.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
    for k in 1..16 {
        let p = Vec2::splat(k as f32 / 16.0);
        for f in [inside_crossing, inside_winding] {
            assert_eq!(u8::from(f(&lower, p)) + u8::from(f(&upper, p)), 1, "{p}");
        }
    }
    // 3D: four unit squares in z = 0 around the origin; rays down through a shared
    // edge or the shared corner hit exactly one of them (half-open rule).
    let quads: Vec<Polygon> = [(-1.0, -1.0), (0.0, -1.0), (0.0, 0.0), (-1.0, 0.0)]
        .iter()
        .flat_map(|&(x, y)| {
            let q = [(x, y), (x + 1.0, y), (x + 1.0, y + 1.0), (x, y + 1.0)];
            [InsideTest::CrossingNumber, InsideTest::WindingNumber].map(|t| Polygon::new(xy(&v2(&q)), t).unwrap())
        })
        .collect();
    for (x, y) in [(0.0, 0.0), (0.0, 0.5), (0.0, -0.5), (0.5, 0.0), (-0.5, 0.0), (0.0, 0.25)] {
        for d in [Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 2.0)] {
            let ray = Ray::new(Vec3::new(x, y, 0.0) - d, d);
            for test in 0..2 {
                let hits = quads.iter().skip(test).step_by(2).filter(|q| q.intersect(&ray).is_some()).count();
                assert_eq!(hits, 1, "ray through ({x}, {y}), dir {d}");
            }
        }
    }
}

#[test]
fn rays_hit_a_tilted_concave_polygon_from_both_sides() {
    let rot = Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.3, 0.9);
    let offset = Vec3::new(3.0, -2.0, 1.0);
    let to3 = |p: Vec2| rot * p.extend(0.0) + offset;
    let l = l_shape();
    for test in [InsideTest::CrossingNumber, InsideTest::WindingNumber] {
        let poly = Polygon::new(l.iter().map(|&p| to3(p)).collect(), test).unwrap();
        let n = rot * Vec3::Z;
        assert!((poly.normal() - n).length() < 1e-6, "counter-clockwise ⇒ normal along +z before rotation");
        assert!((poly.area() - 3.0).abs() < 1e-5);
        for (p, expect) in [((0.5, 0.5), true), ((1.5, 0.5), true), ((0.5, 1.5), true), ((1.5, 1.5), false)] {
            let target = to3(Vec2::new(p.0, p.1));
            for side in [1.0f32, -1.0] {
                let o = target + side * 3.0 * (n + 0.2 * (rot * Vec3::X));
                let ray = Ray::new(o, (target - o) * 0.5);
                let hit = poly.intersect(&ray);
                assert_eq!(hit.is_some(), expect, "{p:?} side {side}");
                if let Some(h) = hit {
                    assert!((h.t - 2.0).abs() < 1e-5, "{}", h.t);
                    assert!((h.p - target).length() < 1e-5);
                    assert_eq!(h.n, poly.normal(), "front normal from both sides");
                }
            }
        }
        // Segment limits.
        let target = to3(Vec2::new(0.5, 0.5));
        let ray = Ray::segment(target + n, -n, 0.0, 0.99);
        assert!(poly.intersect(&ray).is_none());
    }
}

#[test]
fn parallel_rays_miss() {
    let poly = Polygon::new(xy(&square()), InsideTest::default()).unwrap();
    // In the plane, through the polygon: n·d = 0.
    assert!(poly.intersect(&Ray::new(Vec3::new(-1.0, 0.5, 0.0), Vec3::X)).is_none());
    assert!(poly.intersect(&Ray::new(Vec3::new(0.5, 0.5, 0.0), Vec3::new(1.0, 1.0, 0.0))).is_none());
    // Above the plane, parallel.
    assert!(poly.intersect(&Ray::new(Vec3::new(-1.0, 0.5, 1.0), Vec3::X)).is_none());
    // Grazing below the threshold (|n·d| ≤ ε|d|).
    assert!(poly.intersect(&Ray::new(Vec3::new(-1.0, 0.5, 1e-8), Vec3::new(1.0, 0.0, -1e-8))).is_none());
    // A shallow but resolvable angle still hits.
    let h = poly.intersect(&Ray::new(Vec3::new(-1.0, 0.5, 1e-3), Vec3::new(1.0, 0.0, -1e-3))).unwrap();
    assert!((h.t - 1.0).abs() < 1e-4 && h.p.z == 0.0);
}

#[test]
fn invalid_polygons_are_rejected() {
    let nonplanar = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.1), Vec3::Y];
    match Polygon::new(nonplanar, InsideTest::default()) {
        Err(ShapeError::Invalid(msg)) => assert!(msg.contains("not planar") && msg.contains("vertex"), "{msg}"),
        Ok(_) => panic!("non-planar polygon accepted"),
    }
    // A lifted fifth vertex is named.
    let lifted =
        vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 1.0, 0.0), Vec3::new(1.0, 2.0, 0.0), Vec3::new(0.0, 1.0, 0.5)];
    let Err(ShapeError::Invalid(msg)) = Polygon::new(lifted, InsideTest::default()) else { panic!() };
    assert!(msg.contains("vertex"), "{msg}");
    // Within tolerance: accepted.
    let almost = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 1e-6), Vec3::Y];
    assert!(Polygon::new(almost, InsideTest::default()).is_ok());
    let collinear = vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0)];
    assert!(
        matches!(Polygon::new(collinear, InsideTest::default()), Err(ShapeError::Invalid(m)) if m.contains("zero area"))
    );
    assert!(Polygon::new(vec![Vec3::ZERO, Vec3::X], InsideTest::default()).is_err());
    assert!(Polygon::new(vec![Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)], InsideTest::default()).is_err());
    assert!(Polygon::new(vec![Vec3::ZERO, Vec3::X, Vec3::X, Vec3::Y], InsideTest::default()).is_err());
    // A figure-eight with cancelling lobes has no defined plane.
    let bowtie = xy(&v2(&[(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]));
    assert!(Polygon::new(bowtie, InsideTest::default()).is_err());
}

#[test]
fn ear_clipping_sums_to_the_shoelace_area() {
    let rot = Quat::from_euler(glam::EulerRot::XYZ, -1.1, 0.2, 0.7);
    for (pts, area) in [(l_shape(), 3.0f32), (square(), 1.0), (simple_star(), 0.0)] {
        for reversed in [false, true] {
            let mut v: Vec<Vec3> = pts.iter().map(|p| rot * p.extend(0.0) + Vec3::new(1.0, 2.0, 3.0)).collect();
            if reversed {
                v.reverse();
            }
            let poly = Polygon::new(v, InsideTest::CrossingNumber).unwrap();
            assert!(poly.is_simple());
            assert_eq!(poly.triangles().len(), pts.len() - 2);
            let mut sum = 0.0;
            for t in poly.triangles() {
                let c = (t[1] - t[0]).cross(t[2] - t[0]);
                assert!(c.dot(poly.normal()) > 0.0, "triangle orientation follows the normal");
                sum += 0.5 * c.length();
            }
            assert!((sum - poly.area()).abs() < 1e-5 * poly.area(), "{sum} vs {}", poly.area());
            if area > 0.0 {
                assert!((poly.area() - area).abs() < 1e-5);
            }
        }
    }
    // The simple star's area: 10 triangles centre–outer–inner, each ½·1·0.4·sin 36°.
    let star = Polygon::new(xy(&simple_star()), InsideTest::default()).unwrap();
    assert!((star.area() - 10.0 * 0.5 * 0.4 * 36f32.to_radians().sin()).abs() < 1e-5);
}

#[test]
fn self_intersecting_polygons_render_but_cannot_be_sampled() {
    let star = Polygon::new(xy(&pentagram()), InsideTest::WindingNumber).unwrap();
    assert!(!star.is_simple());
    assert!(star.triangles().is_empty());
    assert!(star.sample_area(Vec2::splat(0.5)).is_none());
    // Signed area: the 5 tips once plus the inner pentagon twice, which the shoelace
    // formula gives as ½·Σ sin 144° = 2.5·sin 144° ≈ 1.47 (the star covers ≈ 1.12).
    let pent = |r: f32| 2.5 * r * r * 72f32.to_radians().sin();
    let r_inner = 72f32.to_radians().cos() / 36f32.to_radians().cos();
    let signed = 2.5 * 144f32.to_radians().sin();
    assert!((star.area() - signed).abs() < 1e-5, "{}", star.area());
    assert!(star.area() > pent(r_inner) * 2.0 && star.area() < pent(1.0));
    let down = Ray::new(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z);
    assert!(star.intersect(&down).is_some());
    let even_odd = Polygon::new(xy(&pentagram()), InsideTest::CrossingNumber).unwrap();
    assert!(even_odd.intersect(&down).is_none());
}

#[test]
fn sample_area_points_are_inside_with_the_right_normal() {
    let rot = Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.2, -0.5);
    let mut rng = Pcg32::seed_from_u64(2024);
    for pts in [l_shape(), simple_star()] {
        for reversed in [false, true] {
            let mut v: Vec<Vec3> = pts.iter().map(|p| rot * p.extend(0.0) + Vec3::new(-4.0, 0.5, 2.0)).collect();
            if reversed {
                v.reverse();
            }
            let cross = Polygon::new(v.clone(), InsideTest::CrossingNumber).unwrap();
            let wind = Polygon::new(v, InsideTest::WindingNumber).unwrap();
            let n = 20_000;
            let mut mean = DVec3::ZERO;
            for _ in 0..n {
                let (p, nrm) = cross.sample_area(Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
                assert_eq!(nrm, cross.normal());
                assert!((p - cross.anchor).dot(nrm).abs() < 1e-5, "on the plane");
                assert!(cross.contains(p) && wind.contains(p), "sample {p} outside");
                mean += p.as_dvec3();
            }
            // The sample mean approaches the area centroid; for the star (5-fold
            // symmetric) that is its centre.
            if pts.len() == 10 {
                let c = (rot * Vec3::ZERO + Vec3::new(-4.0, 0.5, 2.0)).as_dvec3();
                assert!((mean / n as f64 - c).length() < 0.02, "{}", (mean / n as f64 - c).length());
            }
        }
    }
}
