use super::kernel::{Leaf, RayKernel, ScalarKernel};
#[cfg(target_arch = "x86_64")]
use super::sse::SseKernel as Kernel;
use super::*;
use crate::test_util::{rays, soup};
use crate::{
    Aabb, Accelerator, Hit, Ray, RayStats, Triangle, WatertightRay, intersect_triangle, intersect_triangle_watertight,
};
use crate::{BruteForce, SplitMethod};
#[cfg(not(target_arch = "x86_64"))]
use ScalarKernel as Kernel;
use proptest::prelude::*;

/// The scalar box test, so that the portable path is exercised on x86_64 too.
fn intersect_scalar<const W: usize>(bvh: &BvhWide<W>, ray: &Ray) -> Option<Hit> {
    bvh.traverse::<ScalarKernel, false, false>(ray, &mut RayStats::default())
}

fn occluded_scalar<const W: usize>(bvh: &BvhWide<W>, ray: &Ray) -> bool {
    bvh.traverse::<ScalarKernel, false, true>(ray, &mut RayStats::default()).is_some()
}

/// How far two correct f32 ray–triangle tests (the tree's watertight one, the oracle's
/// Möller–Trumbore) may put a hit on `tri` apart in t: 10⁻⁵ relative, plus the rounding
/// of the plane distance (a few ulps of the coordinates) divided by |n̂·d|, since a
/// grazing hit's t is ill-conditioned (a ray 89.7° off the normal moved t by 2·10⁻⁵
/// relative between the two tests).
fn t_tolerance(tri: &[Vec3; 3], r: &Ray, t: f32) -> f32 {
    let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
    let scale = tri.iter().chain([&r.origin]).map(|v| v.abs().max_element()).fold(0.0, f32::max);
    1e-5 * t.abs().max(1.0) + 4.0 * f32::EPSILON * scale / n.dot(r.dir).abs()
}

fn same_hit(a: Option<Hit>, b: Option<Hit>, r: &Ray, tris: &[[Vec3; 3]]) {
    match (a, b) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            let tol = t_tolerance(&tris[b.prim as usize], r, b.t);
            assert!((a.t - b.t).abs() <= tol, "t {} vs {} (tolerance {tol}) for {r:?}", a.t, b.t);
            if a.prim != b.prim {
                // Only where both triangles meet the ray at one point (a shared edge): the
                // tree's t, refined in f64 on its triangle's plane, is then the f64 t on the
                // oracle's triangle's plane, to an ulp or two.
                let exact_b = plane_t(&tris[b.prim as usize], r) as f32;
                assert!(
                    (a.t - exact_b).abs() <= 2.0 * f32::EPSILON * a.t.abs(),
                    "different triangle at different t ({} vs the oracle's triangle's {exact_b}) for {r:?}",
                    a.t
                );
            }
        }
        _ => panic!("wide BVH {a:?} vs brute force {b:?} for {r:?}"),
    }
}

fn agree_with<const W: usize>(bvh: &BvhWide<W>, oracle: &BruteForce, tris: &[[Vec3; 3]], rays: &[Ray])
where
    BvhWide<W>: Accelerator,
{
    for r in rays {
        let expected = oracle.intersect(r);
        let hit = bvh.intersect(r);
        same_hit(hit, expected, r, tris);
        assert_eq!(intersect_scalar(bvh, r), hit, "scalar and SIMD box tests for {r:?}");
        let blocked = oracle.occluded(r);
        assert_eq!(bvh.occluded(r), blocked, "occlusion for {r:?}");
        assert_eq!(occluded_scalar(bvh, r), blocked, "scalar occlusion for {r:?}");
    }
}

/// Both widths, built with `config`, are well formed and agree with `oracle`.
fn check_widths(tris: &[[Vec3; 3]], config: BuildConfig, oracle: &BruteForce, rays: &[Ray]) {
    let bvh4 = Bvh4::build(tris, config).unwrap();
    check_structure(&bvh4, tris.len());
    agree_with(&bvh4, oracle, tris, rays);
    let bvh8 = Bvh8::build(tris, config).unwrap();
    check_structure(&bvh8, tris.len());
    agree_with(&bvh8, oracle, tris, rays);
}

/// Both widths agree with brute force.
fn agree(tris: &[[Vec3; 3]], config: BuildConfig, rays: &[Ray]) {
    check_widths(tris, config, &BruteForce::new(tris).unwrap(), rays);
}

fn every_config() -> Vec<BuildConfig> {
    let mut v = Vec::new();
    for method in SplitMethod::ALL.into_iter().chain([SplitMethod::Hybrid { threshold: 64 }]) {
        for leaf_by_sah in [true, false] {
            for max_leaf_size in 1..=8 {
                v.push(BuildConfig { method, leaf_by_sah, max_leaf_size, ..Default::default() });
            }
        }
    }
    v
}

/// Checks the tree's structure: every triangle in exactly one leaf, children's boxes
/// inside the parent's, unused slots empty.
fn check_structure<const W: usize>(bvh: &BvhWide<W>, n_tris: usize) {
    let mut seen = vec![false; n_tris];
    let mut reached = vec![false; bvh.nodes().len()];
    let mut stack = if bvh.nodes().is_empty() { vec![] } else { vec![0usize] };
    while let Some(i) = stack.pop() {
        assert!(!reached[i], "node {i} reached twice");
        reached[i] = true;
        let n = &bvh.nodes()[i];
        let used = (0..W).filter(|&s| !n.child_bounds(s).is_empty()).count();
        assert!(used >= 1 && (i == 0 || used >= 2), "node {i} has {used} children");
        for s in 0..W {
            let b = n.child_bounds(s);
            if b.is_empty() {
                assert_eq!((n.child[s], n.count[s]), (0, 0));
                assert_eq!(b, Aabb::EMPTY, "unused slot must be +inf/-inf");
                continue;
            }
            if n.count[s] > 0 {
                for t in n.child[s]..n.child[s] + n.count[s] {
                    let id = bvh.prim_ids()[t as usize] as usize;
                    assert!(!seen[id], "triangle {id} twice");
                    seen[id] = true;
                }
            } else {
                let c = n.child[s] as usize;
                assert!(c > i, "children follow their parent");
                let cb = bvh.nodes()[c].bounds();
                assert!(b.min.cmple(cb.min).all() && cb.max.cmple(b.max).all(), "child box escapes");
                stack.push(c);
            }
        }
    }
    assert!(seen.iter().all(|&s| s), "every triangle in a leaf");
    assert!(reached.iter().all(|&r| r), "every node reachable");
}

#[test]
fn node_layout() {
    assert_eq!(std::mem::size_of::<Bvh4Node>(), 128);
    assert_eq!(std::mem::align_of::<Bvh4Node>(), 64);
    let n = Bvh4Node::EMPTY;
    assert_eq!(n.planes()[3], [f32::NEG_INFINITY; 4], "row 3 is max_x");
    assert_eq!(std::mem::size_of::<Bvh8Node>(), 256);
    assert_eq!(std::mem::align_of::<Bvh8Node>(), 64);
    let mut n = Bvh8Node::EMPTY;
    n.max_y[7] = 2.0;
    assert_eq!(n.planes()[4][7], 2.0, "row 4 is max_y");
    assert_eq!(bytemuck::bytes_of(&n).len(), 256);
}

#[test]
fn matches_brute_force_for_every_builder_and_leaf_size() {
    let tris = soup(1, 2000, 10.0, 1.0);
    let rs = rays(2, 600, 10.0);
    let oracle = BruteForce::new(&tris).unwrap();
    for config in every_config() {
        check_widths(&tris, config, &oracle, &rs);
    }
}

#[test]
fn parallel_build_collapses_and_matches_brute_force() {
    let tris = soup(21, 20_000, 50.0, 1.0);
    let oracle = BruteForce::new(&tris).unwrap();
    let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
    check_structure(&bvh, tris.len());
    agree_with(&bvh, &oracle, &tris, &rays(22, 500, 50.0));
    let bvh8 = Bvh8::build(&tris, BuildConfig::default()).unwrap();
    check_structure(&bvh8, tris.len());
    agree_with(&bvh8, &oracle, &tris, &rays(22, 500, 50.0));
    // Fewer, wider nodes: at most about half of the 4-wide tree's; fewer leaves, as
    // sibling leaves merge up to eight triangles.
    let (s4, s8) = (bvh.stats(), bvh8.stats());
    assert!(s8.leaves < s4.leaves, "{s8:?} vs {s4:?}");
    assert!(s8.nodes * 3 < s4.nodes * 2 && s8.depth < s4.depth, "{s8:?} vs {s4:?}");
}

#[test]
fn collapse_is_wide_and_shallow() {
    let tris = soup(8, 5000, 20.0, 1.0);
    let bin = Bvh::build(&tris, BuildConfig { max_leaf_size: 4, ..Default::default() }).unwrap();
    let wide = Bvh4::from_bvh(&bin);
    let (b, w) = (bin.stats(), wide.stats());
    assert!(w.leaves <= b.leaves && w.leaves * 2 > b.leaves, "some leaves merged: {w:?} from {b:?}");
    assert_eq!(w.nodes, wide.nodes().len());
    assert!(w.nodes < b.nodes - b.leaves, "{w:?} from {b:?}");
    assert!(w.depth < b.depth, "{w:?} from {b:?}");
    assert!(w.sah_cost < b.sah_cost, "{w:?} from {b:?}");
    assert_eq!(wide.bounds(), Accelerator::bounds(&bin));
    // Leaves split down to four triangles regardless of the SAH are kept as they are,
    // and each wide node absorbs one to three binary interior nodes.
    let forced = BuildConfig { max_leaf_size: 4, leaf_by_sah: false, ..Default::default() };
    let bin = Bvh::build(&tris, forced).unwrap();
    let wide = Bvh4::from_bvh(&bin);
    let (b, w) = (bin.stats(), wide.stats());
    let mut leaves: Vec<(u32, u32)> = bin.nodes().iter().filter(|n| n.count > 0).map(|n| (n.index, n.count)).collect();
    let mut wide_leaves: Vec<(u32, u32)> =
        wide.nodes().iter().flat_map(|n| n.child.into_iter().zip(n.count).filter(|(_, c)| *c > 0)).collect();
    leaves.sort_unstable();
    wide_leaves.sort_unstable();
    assert_eq!(leaves, wide_leaves);
    assert_eq!(w.leaves, b.leaves);
    assert!(w.nodes * 3 >= b.nodes - b.leaves && w.nodes < b.nodes - b.leaves, "{w:?} from {b:?}");
}

#[test]
fn an_8_wide_collapse_merges_leaves_of_up_to_eight() {
    let tris = soup(8, 5000, 20.0, 1.0);
    let leaf_sizes = |counts: Vec<u32>| {
        let mut sizes = [0usize; 9];
        counts.into_iter().filter(|&c| c > 0).for_each(|c| sizes[c as usize] += 1);
        sizes
    };
    // By the SAH: leaves of up to eight (one AVX test), larger ones than the 4-wide tree's.
    let bin = Bvh::build(&tris, BuildConfig::default()).unwrap();
    let (w4, w8) = (Bvh4::from_bvh(&bin), Bvh8::from_bvh(&bin));
    let s4 = leaf_sizes(w4.nodes().iter().flat_map(|n| n.count).collect());
    let s8 = leaf_sizes(w8.nodes().iter().flat_map(|n| n.count).collect());
    assert!(s4[5..].iter().all(|&c| c == 0), "4-wide leaves {s4:?}");
    assert!(s8[5..].iter().sum::<usize>() > 0, "8-wide leaves {s8:?}");
    assert!(w8.stats().leaves < w4.stats().leaves, "{:?} {:?}", w8.stats(), w4.stats());
    assert_eq!(s4.iter().enumerate().map(|(c, n)| c * n).sum::<usize>(), tris.len());
    assert_eq!(s8.iter().enumerate().map(|(c, n)| c * n).sum::<usize>(), tris.len());
    // Leaves made regardless of the SAH with at least eight triangles each are kept.
    let forced = Bvh::build(&tris, BuildConfig { max_leaf_size: 8, leaf_by_sah: false, ..Default::default() }).unwrap();
    let wide = Bvh8::from_bvh(&forced);
    assert_eq!(wide.stats().leaves, forced.stats().leaves);
}

/// The 36 triangles of the Cornell box (`CornellBox-Original-fixed.obj` of the shared
/// scenes, as `spt rays export` writes them): a room whose rays all start inside it.
const CORNELL_BOX: [[f32; 9]; 36] = [
    [-1.01, 0.0, 0.99, 1.0, 0.0, 0.99, 1.0, 0.0, -1.04],
    [-1.01, 0.0, 0.99, 1.0, 0.0, -1.04, -0.99, 0.0, -1.04],
    [-1.02, 1.99, 0.99, -1.02, 1.99, -1.04, 1.0, 1.99, -1.04],
    [-1.02, 1.99, 0.99, 1.0, 1.99, -1.04, 1.0, 1.99, 0.99],
    [-0.99, 0.0, -1.04, 1.0, 0.0, -1.04, 1.0, 1.99, -1.04],
    [-0.99, 0.0, -1.04, 1.0, 1.99, -1.04, -1.02, 1.99, -1.04],
    [1.0, 0.0, -1.04, 1.0, 0.0, 0.99, 1.0, 1.99, 0.99],
    [1.0, 0.0, -1.04, 1.0, 1.99, 0.99, 1.0, 1.99, -1.04],
    [-1.01, 0.0, 0.99, -0.99, 0.0, -1.04, -1.02, 1.99, -1.04],
    [-1.01, 0.0, 0.99, -1.02, 1.99, -1.04, -1.02, 1.99, 0.99],
    [0.53, 0.6, 0.75, 0.7, 0.6, 0.17, 0.13, 0.6, 0.0],
    [0.53, 0.6, 0.75, 0.13, 0.6, 0.0, -0.05, 0.6, 0.57],
    [-0.05, 0.0, 0.57, -0.05, 0.6, 0.57, 0.13, 0.6, 0.0],
    [-0.05, 0.0, 0.57, 0.13, 0.6, 0.0, 0.13, 0.0, 0.0],
    [0.53, 0.0, 0.75, 0.53, 0.6, 0.75, -0.05, 0.6, 0.57],
    [0.53, 0.0, 0.75, -0.05, 0.6, 0.57, -0.05, 0.0, 0.57],
    [0.7, 0.0, 0.17, 0.7, 0.6, 0.17, 0.53, 0.6, 0.75],
    [0.7, 0.0, 0.17, 0.53, 0.6, 0.75, 0.53, 0.0, 0.75],
    [0.13, 0.0, 0.0, 0.13, 0.6, 0.0, 0.7, 0.6, 0.17],
    [0.13, 0.0, 0.0, 0.7, 0.6, 0.17, 0.7, 0.0, 0.17],
    [0.53, 0.0, 0.75, 0.7, 0.0, 0.17, 0.13, 0.0, 0.0],
    [0.53, 0.0, 0.75, 0.13, 0.0, 0.0, -0.05, 0.0, 0.57],
    [-0.53, 1.2, 0.09, 0.04, 1.2, -0.09, -0.14, 1.2, -0.67],
    [-0.53, 1.2, 0.09, -0.14, 1.2, -0.67, -0.71, 1.2, -0.49],
    [-0.53, 0.0, 0.09, -0.53, 1.2, 0.09, -0.71, 1.2, -0.49],
    [-0.53, 0.0, 0.09, -0.71, 1.2, -0.49, -0.71, 0.0, -0.49],
    [-0.71, 0.0, -0.49, -0.71, 1.2, -0.49, -0.14, 1.2, -0.67],
    [-0.71, 0.0, -0.49, -0.14, 1.2, -0.67, -0.14, 0.0, -0.67],
    [-0.14, 0.0, -0.67, -0.14, 1.2, -0.67, 0.04, 1.2, -0.09],
    [-0.14, 0.0, -0.67, 0.04, 1.2, -0.09, 0.04, 0.0, -0.09],
    [0.04, 0.0, -0.09, 0.04, 1.2, -0.09, -0.53, 1.2, 0.09],
    [0.04, 0.0, -0.09, -0.53, 1.2, 0.09, -0.53, 0.0, 0.09],
    [-0.53, 0.0, 0.09, 0.04, 0.0, -0.09, -0.14, 0.0, -0.67],
    [-0.53, 0.0, 0.09, -0.14, 0.0, -0.67, -0.71, 0.0, -0.49],
    [-0.24, 1.98, 0.16, -0.24, 1.98, -0.22, 0.23, 1.98, -0.22],
    [-0.24, 1.98, 0.16, 0.23, 1.98, -0.22, 0.23, 1.98, 0.16],
];

#[test]
fn merged_leaves_do_not_span_a_room_seen_from_inside() {
    // Merging any subtree of up to eight triangles put four of the box's walls and a face
    // of its tall block into one leaf as large as the room, which every ray entered
    // (+17 % traversal instructions): only sibling leaves may merge.
    let tris: Vec<[Vec3; 3]> = CORNELL_BOX
        .iter()
        .map(|t| [Vec3::new(t[0], t[1], t[2]), Vec3::new(t[3], t[4], t[5]), Vec3::new(t[6], t[7], t[8])])
        .collect();
    let bvh = Bvh8::build(&tris, BuildConfig::default()).unwrap();
    let room = bvh.bounds().surface_area();
    let mut merged = 0;
    for n in bvh.nodes() {
        for slot in (0..8).filter(|&s| n.count[s] > 2) {
            merged += 1;
            let area = n.child_bounds(slot).surface_area();
            assert!(area < 0.5 * room, "a leaf of {} triangles spans {area} of the room's {room}", n.count[slot]);
        }
    }
    assert!(merged > 0, "no leaf merged");
}

#[test]
fn counted_traversal_reports_work() {
    let tris = soup(51, 2000, 10.0, 1.0);
    let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
    let bin = Bvh::build(&tris, BuildConfig::default()).unwrap();
    let (mut stats, mut bin_stats) = (RayStats::default(), RayStats::default());
    let rs = rays(52, 300, 10.0);
    for r in &rs {
        assert_eq!(bvh.intersect_counted(r, &mut stats), bvh.intersect(r));
        bin.intersect_counted(r, &mut bin_stats);
    }
    assert_eq!(stats.rays, 300);
    assert!(stats.nodes_visited >= stats.rays && stats.triangles_tested > 0);
    assert!(stats.nodes_visited < bin_stats.nodes_visited, "{stats:?} vs binary {bin_stats:?}");
    assert!(stats.triangles_tested < 300 * 2000 / 20, "{stats:?}");
}

#[test]
fn axis_parallel_rays_and_origins_on_slab_planes() {
    // A grid of unit squares in z = 0, z = 1 and z = 2 (split into triangles), so that box
    // planes at x, y ∈ {0, 1, 2, …} and z ∈ {0, 1, 2} are shared by many nodes.
    let mut tris = Vec::new();
    for z in 0..3 {
        for i in 0..6 {
            for j in 0..6 {
                let (x, y, z) = (i as f32, j as f32, z as f32);
                let [a, b, c, d] = [
                    Vec3::new(x, y, z),
                    Vec3::new(x + 1.0, y, z),
                    Vec3::new(x + 1.0, y + 1.0, z),
                    Vec3::new(x, y + 1.0, z),
                ];
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
    }
    let oracle = BruteForce::new(&tris).unwrap();
    let mut rs = Vec::new();
    for zero in [0.0f32, -0.0] {
        for &x in &[0.0f32, 0.5, 1.0, 3.0, 6.0, -0.0] {
            for &y in &[0.0f32, 0.25, 2.0, 6.0] {
                // Along ±z with ±0 x and y components, from outside and from on a plane.
                for (oz, dz) in [(-1.0, 1.0), (3.0, -1.0), (0.0, 1.0), (1.0, -1.0), (2.0, 1.0)] {
                    rs.push(Ray::new(Vec3::new(x, y, oz), Vec3::new(zero, zero, dz)));
                }
                // Along ±x and ±y inside the planes z = 0 / 1 (the triangles are edge-on and
                // never hit) and between them.
                for z in [0.0f32, 1.0, 0.5] {
                    rs.push(Ray::new(Vec3::new(-1.0, y, z), Vec3::new(1.0, zero, zero)));
                    rs.push(Ray::new(Vec3::new(7.0, y, z), Vec3::new(-1.0, zero, zero)));
                    rs.push(Ray::new(Vec3::new(x, -1.0, z), Vec3::new(zero, 1.0, zero)));
                }
                // Oblique in x and z with a zero y, the origin on a y plane.
                rs.push(Ray::new(Vec3::new(x, y, -0.5), Vec3::new(0.3, zero, 1.0)));
            }
        }
    }
    for config in every_config() {
        check_widths(&tris, config, &oracle, &rs);
    }
    // By hand: a ray in the plane y = 0 (the min plane of the front boxes) with a zero y
    // component hits the edge of the first square at t = 1.
    let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
    let r = Ray::new(Vec3::new(0.5, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0));
    let (a, b) = (bvh.intersect(&r), oracle.intersect(&r));
    assert_eq!(a.map(|h| h.t), b.map(|h| h.t));
    assert_eq!(a.map(|h| h.t), Some(1.0));
}

/// A leaf of `n` triangles (from the third on, with a degenerate one and one sharing
/// an edge), its SoA floats and ids, and random rays plus rays exactly through
/// vertices and edge points, oblique and axis-aligned (the latter give edge functions
/// of exactly zero: the watertight test's double-precision path).
#[allow(clippy::type_complexity)]
fn leaf_fixture(n: usize, seed: u64, ray_seed: u64) -> (Vec<[Vec3; 3]>, Vec<f32>, Vec<u32>, Vec<Ray>) {
    let mut tris = soup(seed, n, 1.0, 1.5);
    if n > 2 {
        tris[1] = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        tris[2] = [tris[0][0], tris[0][2], tris[0][0] + Vec3::Y];
    }
    let mut soa: Vec<f32> =
        (0..9).flat_map(|k| tris.iter().map(move |t| t[k / 3][k % 3]).collect::<Vec<_>>()).collect();
    soa.extend([f32::NAN; 7]);
    let ids: Vec<u32> = (0..n as u32).map(|i| 100 + i).collect();
    let mut rs = rays(ray_seed, 400, 1.0);
    for t in &tris {
        for p in [t[0], t[1], 0.5 * (t[0] + t[2])] {
            rs.push(Ray::new(p + Vec3::new(0.1, 0.2, 1.0), -Vec3::new(0.1, 0.2, 1.0)));
            rs.push(Ray::new(p + Vec3::Z, -Vec3::Z));
        }
    }
    (tris, soa, ids, rs)
}

/// Checks leaf kernel `K` for `test` against the scalar test applied to each triangle in
/// order, on leaves of 1 to 17 triangles (one to three groups of four or eight, partial
/// groups included) with degenerate and edge-sharing triangles: same hit, same shrunk
/// t_max, any-hit stopping at the first.
fn leaf_kernel_matches_the_scalar_test<K: RayKernel<W>, const W: usize>(test: TriangleTest, seed: u64) {
    let mut hits = 0;
    for n in 1..=17usize {
        let (tris, soa, ids, rs) = leaf_fixture(n, n as u64 + seed, n as u64 ^ (5 + seed));
        for r in &rs {
            let w = WatertightRay::new(r);
            let scalar = |t: &[Vec3; 3], limit: f32| match test {
                TriangleTest::MollerTrumbore => intersect_triangle(&Triangle::new(t), r, limit),
                TriangleTest::Watertight => intersect_triangle_watertight(t, &w, limit),
            };
            for t_max in [r.t_max, 0.7] {
                for any_hit in [false, true] {
                    let mut expected = None;
                    let mut limit = t_max;
                    for (i, t) in tris.iter().enumerate() {
                        if let Some((t, u, v)) = scalar(t, limit) {
                            limit = t;
                            expected = Some(Hit { prim: 100 + i as u32, t, u, v });
                            if any_hit {
                                break;
                            }
                        }
                    }
                    let (mut got, mut got_t_max) = (None, t_max);
                    let leaf = Leaf { soa: &soa, ids: &ids };
                    let k = K::new(r);
                    let found = match (test, any_hit) {
                        (TriangleTest::MollerTrumbore, true) => k.triangles::<true>(r, leaf, &mut got_t_max, &mut got),
                        (TriangleTest::MollerTrumbore, false) => {
                            k.triangles::<false>(r, leaf, &mut got_t_max, &mut got)
                        }
                        (TriangleTest::Watertight, true) => k.watertight::<true>(&w, leaf, &mut got_t_max, &mut got),
                        (TriangleTest::Watertight, false) => k.watertight::<false>(&w, leaf, &mut got_t_max, &mut got),
                    };
                    assert_eq!(got, expected, "{W} lanes, {test:?}, {n} triangles, {r:?}");
                    assert_eq!(found, any_hit && expected.is_some());
                    assert_eq!(got_t_max, limit);
                    hits += found as usize;
                }
            }
        }
    }
    assert!(hits > 400, "{W} lanes, {test:?}: {hits} any-hit hits");
}

/// Both tests in both leaf kernels of x86_64: SSE's four lanes, and AVX's eight where
/// this CPU has AVX2 (said on stderr where it has not).
fn leaf_kernels_match_the_scalar_test(test: TriangleTest, seed: u64) {
    leaf_kernel_matches_the_scalar_test::<Kernel, 4>(test, seed);
    #[cfg(target_arch = "x86_64")]
    if wide8_accelerated() {
        leaf_kernel_matches_the_scalar_test::<super::avx::AvxKernel, 8>(test, seed);
    } else {
        eprintln!("this CPU has no AVX2: the 8-lane leaf kernel is not tested");
    }
}

#[test]
fn leaf_kernel_is_bit_identical_to_intersect_triangle() {
    leaf_kernels_match_the_scalar_test(TriangleTest::MollerTrumbore, 0);
}

#[test]
fn watertight_leaf_kernel_is_bit_identical_to_the_scalar_test() {
    leaf_kernels_match_the_scalar_test(TriangleTest::Watertight, 40);
}

#[test]
fn unused_slots_are_never_entered() {
    // Two triangles: the root has two used slots and two unused ones.
    let tris = vec![
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        [Vec3::new(5.0, 0.0, 0.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(5.0, 1.0, 0.0)],
    ];
    let bvh = Bvh4::build(&tris, BuildConfig { max_leaf_size: 1, ..Default::default() }).unwrap();
    assert_eq!(bvh.nodes().len(), 1);
    let node = &bvh.nodes()[0];
    for dir in [Vec3::X, -Vec3::X, Vec3::new(0.0, -0.0, 1.0), Vec3::new(-0.0, 0.0, -0.0), Vec3::new(1.0, -2.0, 3.0)] {
        for origin in [Vec3::ZERO, Vec3::splat(-3.0), Vec3::new(5.0, 0.0, 0.0)] {
            let r = Ray::new(origin, dir);
            let (mask, _) = <Kernel as RayKernel<4>>::new(&r).enter(node, f32::INFINITY);
            let (scalar, _) = <ScalarKernel as RayKernel<4>>::new(&r).enter(node, f32::INFINITY);
            assert_eq!(mask, scalar);
            assert_eq!(mask & 0b1100, 0, "unused slot entered by {r:?}");
        }
    }
}

/// The AVX kernel's watertight set-up, bit for bit [`WatertightRay::new`]'s: random
/// directions and every direction with components in {−2, −1, −0.5, −0, 0, 0.5, 1, 2} (ties
/// between the axes, ±0, the zero direction), from origins of both signs.
#[test]
#[cfg(target_arch = "x86_64")]
fn the_avx_watertight_ray_is_the_portable_one() {
    if !wide8_accelerated() {
        eprintln!("skipped: this CPU has no AVX2");
        return;
    }
    #[target_feature(enable = "avx2")]
    unsafe fn avx(ray: &Ray) -> WatertightRay {
        // SAFETY: the caller's guarantee (AVX2, checked above).
        unsafe { super::avx::watertight_ray(ray) }
    }
    let bits = |w: &WatertightRay| (w.origin.map(f32::to_bits), w.k, w.shear.map(f32::to_bits), w.t_min.to_bits());
    let mut rng = rng::Pcg32::seed_from_u64(5);
    let mut f = || rng.next_f32() * 2.0 - 1.0;
    let mut dirs: Vec<Vec3> = (0..20_000).map(|_| Vec3::new(f(), f(), f())).collect();
    let values = [-2.0f32, -1.0, -0.5, -0.0, 0.0, 0.5, 1.0, 2.0];
    for a in values {
        for b in values {
            for c in values {
                dirs.push(Vec3::new(a, b, c));
            }
        }
    }
    let mut flipped = [0; 3];
    for (i, d) in dirs.into_iter().enumerate() {
        let origin = Vec3::new(1.5, -2.25, 3.125) * if i % 2 == 0 { 1.0 } else { -7.0 };
        let ray = Ray::segment(origin, d, 0.25, 10.0);
        let portable = WatertightRay::new(&ray);
        // SAFETY: AVX2 was detected above.
        let fast = unsafe { avx(&ray) };
        assert_eq!(bits(&fast), bits(&portable), "{d}");
        if portable.k[0] != (portable.k[2] + 1) % 3 {
            flipped[portable.k[2]] += 1;
        }
    }
    assert!(flipped.iter().all(|&n| n > 1000), "every axis flipped: {flipped:?}");
}

#[test]
#[cfg(target_arch = "x86_64")]
fn unused_slots_of_an_8_wide_node_are_never_entered() {
    if !wide8_accelerated() {
        eprintln!("skipped: this CPU has no AVX2 (the 8-wide tree runs the portable kernel)");
        return;
    }
    // Three triangles: the root has three used slots and five unused ones.
    let tris: Vec<[Vec3; 3]> = (0..3)
        .map(|i| [0.0, 1.0, 0.0].map(|y| Vec3::new(5.0 * i as f32 + y, y, 0.0)))
        .map(|[a, b, _]| [a, b, a + Vec3::Y])
        .collect();
    let bvh = Bvh8::build(&tris, BuildConfig { max_leaf_size: 1, ..Default::default() }).unwrap();
    assert_eq!(bvh.nodes().len(), 1);
    let node = &bvh.nodes()[0];
    for dir in [Vec3::X, -Vec3::X, Vec3::new(0.0, -0.0, 1.0), Vec3::new(-0.0, 0.0, -0.0), Vec3::new(1.0, -2.0, 3.0)] {
        for origin in [Vec3::ZERO, Vec3::splat(-3.0), Vec3::new(5.0, 0.0, 0.0)] {
            let r = Ray::new(origin, dir);
            // SAFETY of calling the AVX kernel here: AVX2 was detected above.
            let (mask, t) = <super::avx::AvxKernel as RayKernel<8>>::new(&r).enter(node, f32::INFINITY);
            let (scalar, scalar_t) = <ScalarKernel as RayKernel<8>>::new(&r).enter(node, f32::INFINITY);
            assert_eq!(mask, scalar);
            assert_eq!(mask & !0b111, 0, "unused slot entered by {r:?}");
            for i in 0..8 {
                if mask & (1 << i) != 0 {
                    assert_eq!(t[i], scalar_t[i]);
                }
            }
        }
    }
}

#[test]
fn degenerate_duplicate_and_tiny_inputs() {
    let rs = rays(3, 500, 2.0);
    agree(&[], BuildConfig::default(), &rs);
    let empty = Bvh4::build(&[], BuildConfig::default()).unwrap();
    assert_eq!(empty.stats(), WideStats::default());
    assert!(empty.bounds().is_empty());
    let one = soup(4, 1, 2.0, 1.0);
    let single = Bvh4::build(&one, BuildConfig::default()).unwrap();
    assert_eq!((single.stats().nodes, single.stats().leaves, single.stats().depth), (1, 1, 2));
    agree(&one, BuildConfig::default(), &rs);
    // A ray straight at the single triangle hits it.
    let c = (one[0][0] + one[0][1] + one[0][2]) / 3.0;
    let n = (one[0][1] - one[0][0]).cross(one[0][2] - one[0][0]).normalize();
    assert!(single.intersect(&Ray::new(c + n, -n)).is_some());
    // 1000 copies of one triangle: all centroids coincide, the binary tree halves by
    // position; depth and the stack must stay bounded.
    let same = vec![soup(5, 1, 2.0, 1.0)[0]; 1000];
    let towards: Vec<Ray> = {
        let t = same[0];
        let c = (t[0] + t[1] + t[2]) / 3.0;
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        (0..50).map(|i| Ray::new(c + n * (1.0 + i as f32), -n)).collect()
    };
    for config in every_config() {
        let bvh = Bvh4::build(&same, config).unwrap();
        let s = bvh.stats();
        assert!(s.depth.saturating_sub(1) * 3 <= STACK_DEPTH && s.depth < 64, "{s:?}");
        check_structure(&bvh, same.len());
        let bvh8 = Bvh8::build(&same, config).unwrap();
        let s = bvh8.stats();
        assert!(s.depth.saturating_sub(1) * 7 <= STACK_DEPTH && s.depth < 64, "{s:?}");
        check_structure(&bvh8, same.len());
        for r in &towards {
            assert!(bvh.intersect(r).is_some() && bvh.occluded(r));
            assert!(bvh8.intersect(r).is_some() && bvh8.occluded(r));
        }
    }
    agree(&same, BuildConfig::default(), &rs);
    agree(&same, BuildConfig { method: SplitMethod::SweepSah, max_leaf_size: 1, ..Default::default() }, &towards);
    // Zero-area triangles mixed in.
    let mut mixed = soup(6, 300, 2.0, 0.5);
    mixed.extend((0..50).map(|i| [Vec3::splat(i as f32 * 0.01); 3]));
    mixed.extend((0..50).map(|i| [Vec3::ZERO, Vec3::X * i as f32, Vec3::X * 2.0 * i as f32]));
    for config in every_config() {
        agree(&mixed, config, &rs);
    }
}

#[test]
fn non_finite_rays_hit_nothing_and_terminate() {
    let tris = soup(9, 500, 5.0, 1.0);
    let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
    let bvh8 = Bvh8::build(&tris, BuildConfig::default()).unwrap();
    let oracle = BruteForce::new(&tris).unwrap();
    for (o, d) in [
        (Vec3::splat(2.0), Vec3::new(f32::NAN, 1.0, 0.0)),
        (Vec3::splat(2.0), Vec3::new(f32::INFINITY, 0.0, 0.0)),
        (Vec3::new(f32::NAN, 2.0, 2.0), Vec3::X),
        (Vec3::new(f32::NEG_INFINITY, 2.0, 2.0), Vec3::X),
    ] {
        let r = Ray::new(o, d);
        assert_eq!(bvh.intersect(&r), None);
        assert_eq!(oracle.intersect(&r), None);
        assert!(!bvh.occluded(&r));
        assert_eq!(bvh8.intersect(&r), None);
        assert!(!bvh8.occluded(&r));
    }
    // NaN segment bounds: nothing is hit either.
    let r = Ray::segment(Vec3::splat(-1.0), Vec3::ONE, f32::NAN, f32::INFINITY);
    assert_eq!((bvh.intersect(&r), oracle.intersect(&r)), (None, None));
    let r = Ray::segment(Vec3::splat(-1.0), Vec3::ONE, 0.0, f32::NAN);
    assert_eq!((bvh.intersect(&r), oracle.intersect(&r)), (None, None));
}

/// `Ray::inv_dir` is public: a ray whose reciprocal has a zero or NaN component (set apart
/// from its direction) would make every unused slot's empty box NaN in the box test and so
/// enter it — the root again, round and round, past the unchecked stack's end. Such rays,
/// and those with a subnormal reciprocal, are not traced, single or in packets, in every
/// tree and with every kernel; an infinite reciprocal (a zero direction component) is.
#[test]
fn a_ray_whose_reciprocal_is_zero_nan_or_subnormal_is_not_traced() {
    // Two triangles: the root's two other slots are unused (4 wide), six of eight (8 wide).
    let tris = vec![
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        [Vec3::new(5.0, 0.0, 0.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(5.0, 1.0, 0.0)],
    ];
    let config = BuildConfig { max_leaf_size: 1, ..Default::default() };
    let (bvh4, bvh8) = (Bvh4::build(&tris, config).unwrap(), Bvh8::build(&tris, config).unwrap());
    let good = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
    assert!(bvh4.intersect(&good).is_some() && bvh8.intersect(&good).is_some());
    // A subnormal reciprocal reads as zero where denormals are treated as zero.
    let subnormal = f32::MIN_POSITIVE / 4.0;
    for inv_dir in [
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::splat(f32::NAN),
        Vec3::new(-0.0, 1.0, 1.0),
        Vec3::new(1.0, -subnormal, 1.0),
    ] {
        let r = Ray { inv_dir, ..good };
        assert_eq!(bvh4.intersect(&r), None, "{inv_dir}");
        assert!(!bvh4.occluded(&r));
        assert_eq!(intersect_scalar(&bvh4, &r), None);
        assert!(!occluded_scalar(&bvh8, &r));
        assert_eq!(bvh8.intersect(&r), None);
        assert!(!bvh8.occluded(&r));
        let rays = [r, good, r];
        let mut hits = [None; 3];
        let mut blocked = [false; 3];
        bvh8.intersect_packet(&rays, &mut hits);
        bvh8.occluded_packet(&rays, &mut blocked);
        assert_eq!((hits[0], hits[2], blocked), (None, None, [false, true, false]));
        assert_eq!(hits[1], bvh8.intersect(&good));
    }
}

/// A hit at t = 0 (the plane through the origin, reached with t_min < 0) has the scalar
/// test's +0, not −0, in every kernel: the leaf tests take vertex minus origin on the
/// permuted z axis, whose zero's sign reaches t (the review of the subtraction's order).
#[test]
fn a_hit_at_zero_keeps_the_scalar_tests_sign() {
    let tris = vec![[Vec3::ZERO, Vec3::X, Vec3::Y]];
    let r = Ray::segment(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, -1.0, f32::INFINITY);
    let scalar = intersect_triangle_watertight(&tris[0], &WatertightRay::new(&r), f32::INFINITY).unwrap();
    assert_eq!(scalar.0.to_bits(), 0.0f32.to_bits());
    let config = BuildConfig::default();
    let (bvh4, bvh8) = (Bvh4::build(&tris, config).unwrap(), Bvh8::build(&tris, config).unwrap());
    for hit in [bvh4.intersect(&r), bvh8.intersect(&r), intersect_scalar(&bvh8, &r)] {
        let hit = hit.expect("the plane is hit at t = 0");
        assert_eq!(
            (hit.t.to_bits(), hit.u.to_bits(), hit.v.to_bits()),
            (0.0f32.to_bits(), scalar.1.to_bits(), scalar.2.to_bits())
        );
    }
}

#[test]
fn rejects_non_finite_coordinates() {
    let mut tris = soup(7, 10, 1.0, 1.0);
    tris[3][1].y = f32::NAN;
    assert!(matches!(Bvh4::build(&tris, BuildConfig::default()), Err(BuildError::NonFinite { index: 3, .. })));
    // Above 64K triangles the check runs in parallel chunks: the first bad triangle is
    // still the one reported, and an infinity counts as much as a NaN.
    let mut big: Vec<[Vec3; 3]> = (0..70_000).map(|i| tris[i % tris.len()]).collect();
    big.iter_mut().filter(|t| !t[1].y.is_finite()).for_each(|t| t[1].y = 0.5);
    big[69_999][0].x = f32::NAN;
    big[50_001][2].z = f32::NEG_INFINITY;
    match Bvh8::build(&big, BuildConfig::default()) {
        Err(BuildError::NonFinite { index, vertex }) => assert_eq!((index, vertex[2]), (50_001, f32::NEG_INFINITY)),
        other => panic!("expected NonFinite at 50001, got {:?}", other.map(|b| b.nodes().len())),
    }
    big[50_001][2].z = 0.25;
    big[69_999][0].x = 0.25;
    assert!(Bvh8::build(&big, BuildConfig::default()).is_ok());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn random_soups_agree_with_brute_force(
        seed in any::<u64>(), n in 1usize..300, leaf in 1usize..9, bins in 2usize..33, m in 0usize..4,
        by_sah in any::<bool>()
    ) {
        let tris = soup(seed, n, 5.0, 1.5);
        let method = SplitMethod::ALL[m];
        let config = BuildConfig { method, max_leaf_size: leaf, bins, leaf_by_sah: by_sah, ..Default::default() };
        agree(&tris, config, &rays(seed ^ 1, 200, 5.0));
    }
}

/// The ray's parameter at the plane of triangle `tri`, in f64.
fn plane_t(tri: &[Vec3; 3], r: &Ray) -> f64 {
    let [a, b, c] = tri.map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a);
    n.dot(a - r.origin.as_dvec3()) / n.dot(r.dir.as_dvec3())
}

/// The relative error of a hit's t against the f64 plane intersection of its triangle.
fn t_error(tris: &[[Vec3; 3]], r: &Ray, h: &Hit) -> f64 {
    let exact = plane_t(&tris[h.prim as usize], r);
    (h.t as f64 - exact).abs() / exact
}

/// Checks that 4- and 8-wide trees over `tris`, with their table of planes and without it
/// (as trees too large for one refine from the hit leaf's vertices), hit where the f32
/// test does and give every closest hit's t correctly rounded from f64 (within 6·10⁻⁸
/// relative); returns how many hits there were and the worst relative error of the f32
/// test's own t (`with_exact_t(false)`), which the refinement is there to mend.
fn assert_t_correctly_rounded(tris: &[[Vec3; 3]], config: BuildConfig, rays: &[Ray]) -> (usize, f64) {
    let bvh4 = Bvh4::build(tris, config).unwrap();
    let bvh8 = Bvh8::build(tris, config).unwrap();
    assert!(bvh4.has_plane_table() && bvh8.has_plane_table());
    let raw = Bvh8::build(tris, config).unwrap().with_exact_t(false);
    // Built without the refinement: no table, and the f32 test's hits to the bit.
    let raw_built = Bvh8::build(tris, BuildConfig { exact_t: false, ..config }).unwrap();
    assert!(!raw_built.has_plane_table());
    let trees: [&dyn Accelerator; 4] =
        [&bvh4, &bvh8, &bvh4.clone().without_plane_table(), &bvh8.clone().without_plane_table()];
    let (mut hits, mut raw_worst) = (0, 0.0f64);
    for (i, r) in rays.iter().enumerate() {
        let built_hit = raw_built.intersect(r).map(|h| (h.prim, h.t.to_bits()));
        assert_eq!(built_hit, raw.intersect(r).map(|h| (h.prim, h.t.to_bits())), "ray {i}");
        let Some(f32_hit) = raw.intersect(r) else {
            assert!(trees.iter().all(|t| t.intersect(r).is_none()), "ray {i}");
            continue;
        };
        hits += 1;
        raw_worst = raw_worst.max(t_error(tris, r, &f32_hit));
        for (k, tree) in trees.iter().enumerate() {
            let h = tree.intersect(r).unwrap_or_else(|| panic!("ray {i}, tree {k}: missed"));
            assert_eq!(h.prim, f32_hit.prim, "ray {i}, tree {k}");
            let e = t_error(tris, r, &h);
            assert!(e <= 6e-8, "ray {i}, tree {k}: relative t error {e:e}");
        }
    }
    (hits, raw_worst)
}

#[test]
fn near_hits_far_from_the_origin_have_a_precise_t() {
    // Sponza's worst case: slivers 11 long and 0.015–0.03 wide (its mouldings) at |x| up to
    // 11, rays starting 0.01–0.05 above them at random angles. The f32 tests alone were
    // off by up to 1.2·10⁻² relative on such rays: a sliver's plane is ill-conditioned in
    // f32, while the f64 plane of its (exact) float vertices is not.
    let mut rng = rng::Pcg32::seed_from_u64(77);
    let mut u = || rng.next_f32();
    let mut tris = Vec::new();
    for i in 0..200 {
        let c = Vec3::new(-10.9 + 0.01 * u(), 5.7 + 0.05 * u(), -2.5 + 0.05 * i as f32);
        let w = 0.015 + 0.015 * u();
        tris.push([c, c + Vec3::new(-0.014, -0.006, -w), c + Vec3::new(10.9, 0.0, 0.0)]);
    }
    let mut rs = Vec::new();
    for t in &tris {
        let p = t[0] + (0.05 + 0.2 * u()) * (t[1] - t[0]) + (0.3 + 0.3 * u()) * (t[2] - t[0]);
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        let h = 0.01 + 0.04 * u();
        let dir = (-n + Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5) * 0.2).normalize();
        rs.push(Ray::new(p + n * h, dir));
    }
    // Sponza's three worst diffuse rays and their triangles, verbatim (f32 errors 1.2·10⁻²,
    // 1.1·10⁻² and 7.5·10⁻³ before the refinement).
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let sponza = [
        (
            [v(-10.89876, 5.729312, -2.504511), v(-10.91276, 5.723312, -2.518511), v(0.00724, 5.729312, -2.504511)],
            v(-3.8075209, 5.7216897, -2.5150287),
            v(0.71017015, 0.43610707, 0.5526926),
        ),
        (
            [v(0.00724, 5.745312, 2.497489), v(-10.89876, 5.729313, 2.507489), v(-10.88876, 5.745312, 2.497488)],
            v(-4.872304, 5.8262396, 2.442445),
            v(-0.774138, -0.5234432, 0.35597414),
        ),
        (
            [v(0.00724, 5.789812, 2.488489), v(-10.88531, 5.758312, 2.494038), v(-10.87976, 5.789812, 2.488489)],
            v(-4.0142655, 5.788555, 2.4850748),
            v(-0.675923, -0.6420054, 0.36188003),
        ),
    ];
    for (t, o, d) in sponza {
        tris.push(t);
        rs.push(Ray::new(o, d));
    }
    let (hits, raw_worst) = assert_t_correctly_rounded(&tris, BuildConfig::default(), &rs);
    assert!(hits > 150, "{hits} hits");
    assert!(raw_worst > 1e-3, "the f32 test's own worst relative t error {raw_worst:e}");
}

#[test]
fn grazing_hits_and_hits_beside_large_triangles_have_a_precise_t() {
    // What the ray sets' last misses were: rays grazing a wall of the Cornell box (cos θ
    // down to 10⁻⁴), and rays from near a wall to the wall beside it, close to the origin
    // while the wall's far corners are two units away (R/D ≈ 10–20). The walls are the
    // box's, 2 × 2 from the origin's side.
    let mut rng = rng::Pcg32::seed_from_u64(35);
    let mut u = || rng.next_f32();
    let (a, b, c, d) =
        (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0));
    let floor = [[a, b, c], [a, c, d]];
    let wall = floor.map(|t| t.map(|v| Vec3::new(-1.0, v.x + 1.0, v.z)));
    let tris: Vec<[Vec3; 3]> = floor.into_iter().chain(wall).collect();
    let mut rays = Vec::new();
    for _ in 0..400 {
        // Grazing the floor from 0.001–0.02 above it, at cos θ 10⁻⁴–0.05 to its normal.
        let o = Vec3::new(0.9 - 0.5 * u(), 0.001 + 0.019 * u(), 0.9 - 1.8 * u());
        let cos = 1e-4 + 0.05 * u();
        let along = Vec3::new(-1.0, 0.0, 0.6 * u() - 0.3).normalize();
        rays.push(Ray::new(o, (along * (1.0 - cos * cos).sqrt() - Vec3::Y * cos).normalize()));
        // From the floor beside the wall to the wall, 0.02–0.2 away.
        let o = Vec3::new(-0.98 + 0.18 * u(), 1e-4, 0.9 - 1.8 * u());
        rays.push(Ray::new(o, Vec3::new(-1.0, 0.3 + u(), u() - 0.5).normalize()));
    }
    let (hits, raw_worst) = assert_t_correctly_rounded(&tris, BuildConfig::default(), &rays);
    assert!(hits > 700, "{hits} hits");
    assert!(raw_worst > 1e-6, "the f32 test's own worst relative t error {raw_worst:e}");
}

/// Sponza's worst primary and diffuse rays on slivers, far from their origins (t ≈ 7.5–9.4
/// from origins whose largest coordinate is 5.5–12), verbatim: slivers 10.8 long
/// and 0.01 wide, where the f32 test's t was off by 2.6·10⁻⁴, 2.2·10⁻⁴, 1.9·10⁻⁴, 2.7·10⁻⁵
/// and 2.1·10⁻⁵ relative: (triangle, ray origin, ray direction).
#[allow(clippy::excessive_precision, reason = "the rays' directions as Sponza's ray set has them")]
fn sponza_slivers() -> Vec<([Vec3; 3], Vec3, Vec3)> {
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    vec![
        (
            [v(0.00724, 5.873312, -2.426511), v(-10.81276, 5.863312, -2.41851), v(0.00724, 5.863312, -2.418511)],
            v(-12.0, 3.0, 0.0),
            v(0.8675533, 0.37994948, -0.32091981),
        ),
        (
            [v(0.00724, 5.873312, -2.426511), v(-10.82076, 5.873312, -2.42651), v(-10.81276, 5.863312, -2.41851)],
            v(-12.0, 3.0, 0.0),
            v(0.86531675, 0.38292941, -0.32340685),
        ),
        (
            [v(0.00724, 5.863312, 2.421489), v(-10.81276, 5.863312, 2.421488), v(0.00724, 5.873313, 2.429489)],
            v(-12.0, 3.0, 0.0),
            v(0.87782466, 0.3657459, 0.30927944),
        ),
        (
            [v(10.90324, 5.745312, -2.49451), v(0.00724, 5.758312, -2.491061), v(0.00724, 5.745312, -2.494511)],
            v(10.923757, 10.069008, 1.109654),
            v(-0.65544206, -0.58006668, -0.48365104),
        ),
        (
            [v(0.00724, 11.018312, -2.418512), v(-10.82076, 11.008312, -2.426511), v(0.00724, 11.008312, -2.426511)],
            v(-0.530056, 5.493672, 2.518007),
            v(-0.62023997, 0.58429176, -0.52335984),
        ),
    ]
}

#[test]
fn hits_on_slivers_have_a_precise_t_at_any_distance() {
    // Hits on slivers have their t refined in f64 (the plane found by the hit's primitive
    // id): alone, among other triangles (their ids and leaf order no longer the slivers'
    // own), and cut into pieces by the pre-split, which share their triangle's plane.
    let cases = sponza_slivers();
    // Small triangles far from the rays, before, between and after the slivers.
    let filler = |k: usize| {
        let c = Vec3::new(100.0 + k as f32, -50.0, 30.0 * (k % 3) as f32);
        [c, c + Vec3::X, c + Vec3::Y]
    };
    let mut mixed = Vec::new();
    let mut ids = Vec::new();
    for (k, case) in cases.iter().enumerate() {
        mixed.extend((0..7 * k + 3).map(|j| filler(10 * k + j)));
        ids.push(mixed.len() as u32);
        mixed.push(case.0);
    }
    mixed.extend((0..11).map(|j| filler(90 + j)));
    let alone: Vec<[Vec3; 3]> = cases.iter().map(|c| c.0).collect();
    // The Sponza slivers lie along an axis, where the pre-split finds nothing to cut: a
    // further sliver along the cube's diagonal, away from the rays, is cut into pieces.
    let mut split = mixed.clone();
    let mut split_ids = ids.clone();
    let corner = Vec3::new(200.0, 0.0, 0.0);
    split_ids.push(split.len() as u32);
    split.push([corner, corner + Vec3::splat(10.0), corner + Vec3::new(0.01, 0.0, 0.0)]);
    let presplit = BuildConfig { presplit: 0.3, ..BuildConfig::default() };
    for (tris, ids, config) in [
        (&alone, (0..cases.len() as u32).collect::<Vec<_>>(), BuildConfig::default()),
        (&mixed, ids, BuildConfig::default()),
        (&split, split_ids, presplit),
    ] {
        if config.presplit > 0.0 {
            let bvh8 = Bvh8::build(tris, config).unwrap();
            assert!(bvh8.prim_ids().len() > tris.len(), "the diagonal sliver is cut");
        }
        let rays: Vec<Ray> = cases.iter().map(|&(_, o, d)| Ray::new(o, d)).collect();
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(Bvh8::build(tris, config).unwrap().intersect(r).map(|h| h.prim), Some(ids[i]), "ray {i}");
        }
        let (hits, raw_worst) = assert_t_correctly_rounded(tris, config, &rays);
        assert_eq!(hits, cases.len());
        assert!(raw_worst > 1e-4, "the f32 test's own worst relative t error {raw_worst:e}");
    }
}

/// Long diagonal triangles (not slivers, whose t the tree refines in f64 and the oracle
/// does not) spanning a cube of side `spread` (what pre-splitting cuts).
fn long_triangles(seed: u64, n: usize, spread: f32) -> Vec<[Vec3; 3]> {
    let mut rng = rng::Pcg32::seed_from_u64(seed);
    let mut point = move || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    (0..n)
        .map(|_| {
            let (a, b) = (point() * spread, point() * spread);
            [a, b, b + (point() - 0.5) * 0.3 * spread]
        })
        .collect()
}

/// Rays at points of the first `n` triangles on the planes x = min + extent·j/8 of the
/// scene's box (the pre-split grid's three coarsest levels), where the pieces' boxes meet.
fn rays_at_the_cuts(tris: &[[Vec3; 3]], n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = rng::Pcg32::seed_from_u64(seed);
    let mut point = move || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    let scene = tris.iter().flatten().fold(Aabb::EMPTY, |b, &p| b.grow(p));
    let reach = scene.extent().max_element();
    let mut rays = Vec::new();
    for t in &tris[..n] {
        for j in 1..8 {
            let c = scene.min.x + scene.extent().x * j as f32 / 8.0;
            let crossings: Vec<Vec3> = (0..3)
                .filter_map(|i| {
                    let (a, b) = (t[i], t[(i + 1) % 3]);
                    ((a.x - c) * (b.x - c) < 0.0).then(|| a + (b - a) * ((c - a.x) / (b.x - a.x)))
                })
                .collect();
            // Targets well inside the triangle: at a sliver's tip, the two tests may each
            // be right about an edge.
            if let [p, q, ..] = crossings[..]
                && p.distance(q) > 0.01 * reach
            {
                let target = 0.5 * (p + q);
                let origin = target + (point() - 0.5).normalize_or(Vec3::Y) * reach;
                rays.push(Ray::new(origin, (target - origin).normalize()));
            }
        }
    }
    rays
}

#[test]
fn presplit_trees_cut_long_triangles_and_find_every_hit() {
    let spread = 20.0;
    let mut tris = long_triangles(41, 150, spread);
    tris.extend(soup(43, 3000, spread, 0.5));
    let mut rs = rays_at_the_cuts(&tris, 150, 42);
    assert!(rs.len() > 300, "{} rays at the cuts", rs.len());
    rs.extend(rays(44, 1000, spread));
    // The oracle's test (Möller–Trumbore, bit for bit the leaves'), so that rays crossing
    // an edge at the cuts are judged alike; the watertight test is checked elsewhere.
    let oracle = BruteForce::new(&tris).unwrap();
    let mt = TriangleTest::MollerTrumbore;
    let config = BuildConfig { presplit: 0.5, max_leaf_size: 4, sah_block: 4, ..Default::default() };
    let plain = Bvh8::build(&tris, BuildConfig { presplit: 0.0, ..config }).unwrap().with_triangle_test(mt);
    agree_with(&plain, &oracle, &tris, &rs);
    {
        let bvh = Bvh8::build(&tris, config).unwrap().with_triangle_test(mt);
        let refs = bvh.prim_ids().len();
        assert!(refs > tris.len() + 500, "{refs} references for {} triangles", tris.len());
        assert!(refs <= tris.len() * 3 / 2, "{refs} references: over the budget");
        let mut seen = vec![false; tris.len()];
        bvh.prim_ids().iter().for_each(|&p| seen[p as usize] = true);
        assert!(seen.iter().all(|&s| s), "every triangle in some leaf");
        // A triangle's pieces that share a binary leaf are merged there (177 repeats of
        // 4,646 references without); a wide leaf made of several binary leaves may still
        // repeat one (76 of 4,501 here, with sibling leaves merged up to eight triangles:
        // a repeat takes a lane of the leaf's one 8-wide test, not another test).
        let mut repeats = 0;
        for n in bvh.nodes() {
            for slot in (0..8).filter(|&s| n.count[s] > 0) {
                let ids = &bvh.prim_ids()[n.child[slot] as usize..(n.child[slot] + n.count[slot]) as usize];
                repeats += ids.iter().enumerate().filter(|(i, p)| ids[..*i].contains(p)).count();
            }
        }
        assert!(repeats * 50 < refs, "{repeats} triangles repeated in a leaf, of {refs} references");
        let (a, b) = (bvh.stats().sah_cost, plain.stats().sah_cost);
        assert!(a < 0.8 * b, "SAH cost {a} with pre-splitting against {b} without");
        agree_with(&bvh, &oracle, &tris, &rs);
    }
    let bvh4 = Bvh4::build(&tris, config).unwrap().with_triangle_test(mt);
    assert!(bvh4.prim_ids().len() > tris.len());
    agree_with(&bvh4, &oracle, &tris, &rs);
}

/// Shadow rays counted by their own walk: the same answer as `occluded`, one ray per query,
/// and per ray no more work than the closest hit's walk, which takes the same path up to
/// the first hit and goes on from there (strictly less in all, in a dense soup).
#[test]
fn counted_shadow_rays_stop_at_their_first_hit() {
    let tris = soup(53, 4000, 10.0, 2.0);
    let rs = rays(54, 400, 10.0);
    let instance = crate::Instance { object: 0, transform: glam::Affine3A::IDENTITY, prim_offset: 0 };
    let two_level = crate::TwoLevel::new(
        vec![Bvh8::build(&tris, BuildConfig::default()).unwrap()],
        &[instance],
        BuildConfig::default(),
    )
    .unwrap();
    let accels: [(&str, Box<dyn Accelerator>); 4] = [
        ("binary", Box::new(Bvh::build(&tris, BuildConfig::default()).unwrap())),
        ("4-wide", Box::new(Bvh4::build(&tris, BuildConfig::default()).unwrap())),
        ("8-wide", Box::new(Bvh8::build(&tris, BuildConfig::default()).unwrap())),
        ("two-level", Box::new(two_level)),
    ];
    for (name, accel) in &accels {
        let (mut any, mut closest) = (RayStats::default(), RayStats::default());
        let mut blocked = 0;
        for r in &rs {
            let (any_before, closest_before) = (any, closest);
            let occluded = accel.occluded_counted(r, &mut any);
            assert_eq!(occluded, accel.occluded(r), "{name}");
            blocked += occluded as u32;
            accel.intersect_counted(r, &mut closest);
            assert_eq!(any.rays, any_before.rays + 1, "{name}: one ray per query");
            let (a, c) = (
                any.triangles_tested - any_before.triangles_tested,
                closest.triangles_tested - closest_before.triangles_tested,
            );
            assert!(a <= c, "{name}: {a} triangles tested by a shadow ray, {c} by its closest hit");
            assert!(
                any.nodes_visited - any_before.nodes_visited <= closest.nodes_visited - closest_before.nodes_visited,
                "{name}: nodes"
            );
        }
        assert!(blocked > 150, "{name}: {blocked} of 400 rays blocked");
        assert!(any.triangles_tested < closest.triangles_tested, "{name}: {any:?} against {closest:?}");
        assert!(
            any.nodes_visited > 0 && any.nodes_visited < closest.nodes_visited,
            "{name}: {any:?} against {closest:?}"
        );
    }
}
