use super::*;
use crate::test_util::{rays, soup};
use crate::{BruteForce, RayStats};
use proptest::prelude::*;

fn agree(tris: &[[Vec3; 3]], config: BuildConfig, rays: &[Ray]) {
    let bvh = Bvh::build(tris, config).unwrap();
    let oracle = BruteForce::new(tris).unwrap();
    for r in rays {
        let (a, b) = (bvh.intersect(r), oracle.intersect(r));
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert!((a.t - b.t).abs() <= 1e-5 * b.t.abs().max(1.0), "t {} vs {}", a.t, b.t);
                if a.prim != b.prim {
                    assert_eq!(a.t, b.t, "different triangle at different t");
                }
            }
            _ => panic!("bvh {a:?} vs brute force {b:?} for {r:?}"),
        }
        assert_eq!(bvh.occluded(r), oracle.occluded(r), "occlusion for {r:?}");
    }
}

fn every_config() -> Vec<BuildConfig> {
    let mut v = Vec::new();
    for method in SplitMethod::ALL.into_iter().chain([SplitMethod::Hybrid { threshold: 64 }]) {
        for leaf_by_sah in [true, false] {
            for max_leaf_size in [1, 2, 3, 4, 8] {
                for sah_block in [1, 4] {
                    v.push(BuildConfig { method, leaf_by_sah, max_leaf_size, sah_block, ..Default::default() });
                }
            }
        }
    }
    v
}

/// Mean triangles per leaf.
fn leaf_fill(bvh: &Bvh) -> f64 {
    let leaves: Vec<u32> = bvh.nodes().iter().filter(|n| n.count > 0).map(|n| n.count).collect();
    leaves.iter().map(|&c| c as f64).sum::<f64>() / leaves.len() as f64
}

#[test]
fn block_sah_fills_leaves_and_rounds_its_block_to_a_power_of_two() {
    // Counting triangles in blocks of four makes a leaf of one to four cost the same, so
    // the builder stops splitting sooner: fuller leaves for the 4-wide leaf test.
    let tris = soup(31, 20_000, 10.0, 1.0);
    let config = BuildConfig { max_leaf_size: 4, ..Default::default() };
    let plain = Bvh::build(&tris, config).unwrap();
    let blocked = Bvh::build(&tris, BuildConfig { sah_block: 4, ..config }).unwrap();
    let (a, b) = (leaf_fill(&plain), leaf_fill(&blocked));
    assert!(b > a + 0.5, "mean leaf fill {b:.2} with blocks of 4 against {a:.2} without");
    assert!(blocked.stats().nodes < plain.stats().nodes);
    let odd = Bvh::build(&tris[..100], BuildConfig { sah_block: 3, ..config }).unwrap();
    assert_eq!(odd.config().sah_block, 4);
}

#[test]
fn matches_brute_force_for_every_builder_and_leaf_size() {
    let tris = soup(1, 2000, 10.0, 1.0);
    let rs = rays(2, 1000, 10.0);
    for config in every_config() {
        agree(&tris, config, &rs);
    }
}

#[test]
fn parallel_binned_build_matches_brute_force_and_is_deterministic() {
    // Above the parallel threshold, subtrees are built by rayon and merged.
    let tris = soup(21, 20_000, 50.0, 1.0);
    let a = Bvh::build(&tris, BuildConfig::default()).unwrap();
    let b = Bvh::build(&tris, BuildConfig::default()).unwrap();
    assert_eq!(a.nodes(), b.nodes());
    agree(&tris, BuildConfig::default(), &rays(22, 500, 50.0));
}

#[test]
fn sah_builders_beat_midpoint_and_binned_is_close_to_sweep() {
    // Small triangles among a few huge ones: the midpoint splits by centroid alone and
    // drags the huge triangles' bounds into both children; the SAH isolates them.
    // Binned over sweep varies from scene to scene (measured over 60 random scenes:
    // 1.005 to 1.13, mean 1.065; midpoint over sweep 1.33 to 1.64), so the bound on
    // binned is on the mean of four scenes, not on one.
    let scene = |seed: u64| {
        let mut tris = soup(seed, 3000, 10.0, 0.1);
        tris.extend(soup(seed + 1, 40, 10.0, 12.0));
        tris
    };
    let mut binned_over_sweep = 0.0;
    for seed in [31, 33, 35, 37] {
        let tris = scene(seed);
        let cost = |method| {
            Bvh::build(&tris, BuildConfig { method, max_leaf_size: 4, ..Default::default() }).unwrap().stats().sah_cost
        };
        let (sweep, binned, mid) =
            (cost(SplitMethod::SweepSah), cost(SplitMethod::BinnedSah), cost(SplitMethod::Midpoint));
        eprintln!("scene {seed}: SAH cost sweep {sweep}, binned {binned}, midpoint {mid}");
        assert!(sweep <= binned * 1.001, "sweep {sweep} binned {binned}");
        assert!(mid > sweep * 1.05, "midpoint {mid} should be worse than sweep {sweep}");
        binned_over_sweep += binned / sweep / 4.0;
    }
    assert!(binned_over_sweep <= 1.10, "binned should be within 10 % of sweep on average: {binned_over_sweep}");
    let tris = scene(31);
    // The hybrid is the sweep below its threshold.
    let hybrid = Bvh::build(
        &tris,
        BuildConfig { method: SplitMethod::Hybrid { threshold: 1_000_000 }, max_leaf_size: 4, ..Default::default() },
    )
    .unwrap();
    let sweep_bvh =
        Bvh::build(&tris, BuildConfig { method: SplitMethod::SweepSah, max_leaf_size: 4, ..Default::default() })
            .unwrap();
    assert_eq!(hybrid.nodes(), sweep_bvh.nodes());
}

#[test]
fn max_leaf_size_is_respected_when_leaves_are_not_chosen_by_sah() {
    let tris = soup(41, 1000, 10.0, 1.0);
    for method in SplitMethod::ALL {
        for max_leaf_size in [1, 3, 8] {
            let bvh =
                Bvh::build(&tris, BuildConfig { method, max_leaf_size, leaf_by_sah: false, ..Default::default() })
                    .unwrap();
            let largest = bvh.nodes().iter().map(|n| n.count).max().unwrap();
            assert!(largest as usize <= max_leaf_size, "{method:?}: leaf of {largest} > {max_leaf_size}");
        }
    }
}

#[test]
fn counted_traversal_reports_work() {
    let tris = soup(51, 2000, 10.0, 1.0);
    let bvh = Bvh::build(&tris, BuildConfig::default()).unwrap();
    let mut stats = RayStats::default();
    let rs = rays(52, 300, 10.0);
    for r in &rs {
        assert_eq!(bvh.intersect_counted(r, &mut stats), bvh.intersect(r));
    }
    assert_eq!(stats.rays, 300);
    assert!(stats.nodes_visited > stats.rays && stats.triangles_tested > 0);
    // Far fewer tests than brute force.
    assert!(stats.triangles_tested < 300 * 2000 / 20, "{stats:?}");
}

#[test]
fn degenerate_duplicate_and_tiny_inputs() {
    let rs = rays(3, 500, 2.0);
    agree(&[], BuildConfig::default(), &rs);
    agree(&soup(4, 1, 2.0, 1.0), BuildConfig::default(), &rs);
    // 1000 copies of one triangle: all centroids coincide.
    let same = vec![soup(5, 1, 2.0, 1.0)[0]; 1000];
    for config in every_config() {
        let bvh = Bvh::build(&same, config).unwrap();
        assert!(bvh.stats().depth < STACK_DEPTH);
    }
    agree(&same, BuildConfig::default(), &rs);
    agree(&same, BuildConfig { method: SplitMethod::SweepSah, ..Default::default() }, &rs);
    // Zero-area triangles mixed in.
    let mut mixed = soup(6, 300, 2.0, 0.5);
    mixed.extend((0..50).map(|i| [Vec3::splat(i as f32 * 0.01); 3]));
    mixed.extend((0..50).map(|i| [Vec3::ZERO, Vec3::X * i as f32, Vec3::X * 2.0 * i as f32]));
    agree(&mixed, BuildConfig::default(), &rs);
}

#[test]
fn rejects_non_finite_coordinates() {
    let mut tris = soup(7, 10, 1.0, 1.0);
    tris[3][1].y = f32::NAN;
    assert!(matches!(Bvh::build(&tris, BuildConfig::default()), Err(BuildError::NonFinite { index: 3, .. })));
    tris[3][1].y = f32::INFINITY;
    assert!(Bvh::build(&tris, BuildConfig::default()).is_err());
    assert!(BruteForce::new(&tris).is_err());
}

#[test]
fn stats_are_consistent() {
    let tris = soup(8, 5000, 20.0, 1.0);
    let bvh = Bvh::build(&tris, BuildConfig::default()).unwrap();
    let s = bvh.stats();
    assert_eq!(s.nodes, 2 * s.leaves - 1, "a binary tree");
    let total: u32 = bvh.nodes().iter().filter(|n| n.count > 0).map(|n| n.count).sum();
    assert_eq!(total as usize, tris.len(), "every triangle in exactly one leaf");
    let mut ids = bvh.prim_ids().to_vec();
    ids.sort_unstable();
    assert!(ids.iter().enumerate().all(|(i, &id)| i as u32 == id));
    assert!(s.depth > 5 && s.depth < 40, "depth {}", s.depth);
    // SAH should beat one big leaf by a wide margin on a spread-out soup.
    assert!(s.sah_cost < 0.1 * tris.len() as f32, "cost {}", s.sah_cost);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn random_soups_agree_with_brute_force(
        seed in any::<u64>(), n in 1usize..300, leaf in 1usize..9, bins in 2usize..33, m in 0usize..4, by_sah in any::<bool>()
    ) {
        let tris = soup(seed, n, 5.0, 1.5);
        let config = BuildConfig { method: SplitMethod::ALL[m], max_leaf_size: leaf, bins, leaf_by_sah: by_sah, ..Default::default() };
        agree(&tris, config, &rays(seed ^ 1, 200, 5.0));
    }
}
