use super::*;
use crate::BruteForce;
use crate::test_util::soup;
use rng::Pcg32;

/// A uniform point in [0, 1)³.
fn point(r: &mut Pcg32) -> Vec3 {
    Vec3::new(r.next_f32(), r.next_f32(), r.next_f32())
}

/// Rays from around and inside the soup, some infinite, some finite segments; every
/// other one aimed at a point inside a random triangle, so that many hit.
fn rays(seed: u64, n: usize, spread: f32, tris: &[[Vec3; 3]]) -> Vec<Ray> {
    let mut r = Pcg32::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            let o = point(&mut r) * spread * 1.6 - 0.3 * spread;
            let target = match tris.len() {
                0 => point(&mut r) * spread,
                len if i % 2 == 0 => {
                    let t = tris[(r.next_f32() * len as f32) as usize % len];
                    let (a, b) = (r.next_f32(), r.next_f32());
                    let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                    t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b
                }
                _ => point(&mut r) * spread,
            };
            let d = (target - o).normalize_or(Vec3::X);
            match i % 3 {
                0 => Ray::new(o, d),
                1 => Ray::segment(o, d, 0.0, 0.5 * spread),
                _ => Ray::segment(o, target - o, 0.0, 1.5),
            }
        })
        .collect()
}

fn agree(tris: &[[Vec3; 3]], accel: &dyn Accelerator, rays: &[Ray], name: &str) {
    let oracle = BruteForce::new(tris).unwrap();
    let mut hits = 0;
    for r in rays {
        match (accel.intersect(r), oracle.intersect(r)) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                hits += 1;
                assert!((a.t - b.t).abs() <= 1e-5 * b.t.abs(), "{name}: t {} vs {} for {r:?}", a.t, b.t);
                if a.prim != b.prim {
                    assert_eq!(a.t, b.t, "{name}: different triangle at a different t for {r:?}");
                } else {
                    assert_eq!((a.u, a.v), (b.u, b.v), "{name}: same triangle, same barycentrics");
                }
            }
            (a, b) => panic!("{name}: {a:?} vs brute force {b:?} for {r:?}"),
        }
        assert_eq!(accel.occluded(r), oracle.occluded(r), "{name}: occlusion for {r:?}");
        let mut stats = RayStats::default();
        assert_eq!(accel.intersect_counted(r, &mut stats), accel.intersect(r), "{name}: counted traversal");
        assert_eq!(stats.rays, 1);
    }
    if !tris.is_empty() {
        assert!(hits > rays.len() / 5, "{name}: only {hits} hits of {}: a weak test", rays.len());
    }
}

fn both(tris: &[[Vec3; 3]], quality: ObvhsQuality) -> [(String, Box<dyn Accelerator>); 2] {
    [
        (format!("bvh2/{}", quality.name()), Box::new(ObvhsBvh2::build(tris, quality).unwrap())),
        (format!("cwbvh/{}", quality.name()), Box::new(ObvhsCwBvh::build(tris, quality).unwrap())),
    ]
}

#[test]
fn random_soups_agree_with_brute_force() {
    for (seed, n, size) in [(1u64, 50usize, 1.0f32), (2, 500, 1.5), (3, 3000, 0.8), (4, 200, 6.0)] {
        let tris = soup(seed, n, 10.0, size);
        let rs = rays(seed + 100, 600, 10.0, &tris);
        for quality in ObvhsQuality::ALL {
            for (name, accel) in both(&tris, quality) {
                agree(&tris, accel.as_ref(), &rs, &format!("{name} n={n}"));
            }
        }
    }
}

#[test]
fn counted_traversal_reports_work() {
    let tris = soup(5, 2000, 10.0, 1.0);
    let rs = rays(6, 300, 10.0, &tris);
    for (name, accel) in both(&tris, ObvhsQuality::Medium) {
        let mut stats = RayStats::default();
        for r in &rs {
            accel.intersect_counted(r, &mut stats);
        }
        assert_eq!(stats.rays, 300, "{name}");
        assert!(stats.nodes_visited > 300 && stats.triangles_tested > 0, "{name}: {stats:?}");
        assert!(stats.triangles_tested < 300 * 2000 / 20, "{name}: {stats:?}");
    }
}

#[test]
fn stats_describe_the_trees() {
    let tris = soup(7, 5000, 20.0, 1.0);
    let b2 = ObvhsBvh2::build(&tris, ObvhsQuality::Medium).unwrap();
    let s = b2.stats();
    assert_eq!(s.nodes, 2 * s.leaves - 1, "a binary tree: {s:?}");
    assert!(s.depth > 5 && s.depth < 64 && s.sah_cost > 0.0 && s.sah_cost < 0.1 * tris.len() as f32, "{s:?}");
    let leaf_prims: u32 = b2.inner().nodes.iter().filter(|n| n.is_leaf()).map(|n| n.prim_count).sum();
    assert_eq!(leaf_prims as usize, tris.len());
    let cw = ObvhsCwBvh::build(&tris, ObvhsQuality::Medium).unwrap();
    let s = cw.stats();
    assert_eq!(s.nodes, cw.inner().nodes.len());
    assert!(s.leaves >= tris.len() / 3 && s.depth > 2 && s.depth < 32, "{s:?}");
    assert!(b2.build_time() >= b2.core_build_time() && cw.build_time() >= cw.core_build_time());
    assert_eq!(b2.bounds(), BruteForce::new(&tris).unwrap().bounds());
}

#[test]
fn empty_and_single_triangle_inputs() {
    let one = soup(9, 1, 2.0, 1.5);
    for quality in ObvhsQuality::ALL {
        for (name, accel) in both(&[], quality) {
            assert!(accel.bounds().is_empty(), "{name}");
            agree(&[], accel.as_ref(), &rays(8, 300, 2.0, &[]), &name);
        }
        for (name, accel) in both(&one, quality) {
            agree(&one, accel.as_ref(), &rays(8, 300, 2.0, &one), &name);
        }
        let hit = Ray::new(one[0].iter().sum::<Vec3>() / 3.0 + Vec3::Z * 5.0, -Vec3::Z);
        for (name, accel) in both(&one, quality) {
            assert_eq!(accel.intersect(&hit).map(|h| h.prim), Some(0), "{name}");
        }
    }
    let s = ObvhsCwBvh::build(&[], ObvhsQuality::Medium).unwrap().stats();
    assert_eq!((s.nodes, s.leaves, s.depth), (0, 0, 0));
}

#[test]
fn duplicates_and_degenerate_triangles() {
    let mut tris = vec![soup(10, 1, 2.0, 1.0)[0]; 20];
    tris.extend(soup(11, 200, 2.0, 0.5));
    tris.extend((0..30).map(|i| [Vec3::splat(i as f32 * 0.01); 3]));
    tris.extend((0..30).map(|i| [Vec3::ZERO, Vec3::X * i as f32, Vec3::X * 2.0 * i as f32]));
    let rs = rays(12, 500, 2.0, &tris);
    for (name, accel) in both(&tris, ObvhsQuality::Medium) {
        agree(&tris, accel.as_ref(), &rs, &name);
    }
    // Hundreds of coincident triangles: fine for the BVH2 ...
    let same = vec![soup(14, 1, 2.0, 1.0)[0]; 1000];
    let b2 = ObvhsBvh2::build(&same, ObvhsQuality::Medium).unwrap();
    agree(&same, &b2, &rays(15, 200, 2.0, &same), "bvh2, coincident");
}

#[test]
fn coincident_triangles_too_deep_for_the_cwbvh_are_an_error() {
    // ... but PLOC chains them into a CWBVH deeper than obvhs's 32-entry traversal
    // stack: an error, not a panic and not silently lost hits.
    let same = vec![soup(14, 1, 2.0, 1.0)[0]; 1000];
    let r = ObvhsCwBvh::build(&same, ObvhsQuality::Medium);
    assert!(matches!(r, Err(BuildError::TooDeep { .. })), "{:?}", r.err());
}

#[test]
fn axis_parallel_rays_with_negative_zero_components() {
    let tris = soup(16, 300, 4.0, 1.0);
    let mut rs = Vec::new();
    for t in tris.iter().step_by(7) {
        let c = t.iter().sum::<Vec3>() / 3.0;
        for d in [Vec3::X, Vec3::Y, Vec3::Z] {
            rs.push(Ray::new(c + d * 10.0, -d));
            rs.push(Ray::new(c - d * 10.0, d));
        }
    }
    for (name, accel) in both(&tris, ObvhsQuality::Medium) {
        agree(&tris, accel.as_ref(), &rs, &name);
    }
}

#[test]
fn rejects_non_finite_coordinates() {
    let mut tris = soup(13, 10, 1.0, 1.0);
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        tris[3][1].y = bad;
        for quality in ObvhsQuality::ALL {
            assert!(matches!(ObvhsBvh2::build(&tris, quality), Err(BuildError::NonFinite { index: 3, .. })));
            assert!(matches!(ObvhsCwBvh::build(&tris, quality), Err(BuildError::NonFinite { index: 3, .. })));
        }
    }
}
