use super::*;

/// A small deterministic generator for the tests' points and lights.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * (hi - lo) + Vec3::splat(lo)
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

/// A one-sided emitter as the scene's triangles are: its box, its normal (θo = 0) and
/// θe = π/2.
fn emitter(centre: Vec3, size: f32, normal: Vec3, phi: f32) -> LightBounds {
    let h = Vec3::splat(0.5 * size);
    LightBounds {
        bounds: Aabb { min: centre - h, max: centre + h },
        w: normal,
        phi,
        cos_theta_o: 1.0,
        cos_theta_e: 0.0,
    }
}

/// Many small lights scattered in a box, facing every way, of unequal power.
fn scattered(n: usize, seed: u64) -> Vec<LightBounds> {
    let mut r = Lcg(seed);
    (0..n).map(|_| emitter(r.vec(-5.0, 5.0), 0.1 + r.next(), r.unit(), 0.1 + 10.0 * r.next())).collect()
}

/// The chance that `tree.sample` returns a light at `p`, `n`: the fraction of `count`
/// stratified values that give one.
fn found(tree: &LightTree, p: Vec3, n: Vec3, count: u32) -> f64 {
    let some = (0..count).filter(|&i| tree.sample(p, n, (i as f32 + 0.5) / count as f32).is_some()).count();
    some as f64 / count as f64
}

/// The lights' probabilities at a point sum to the chance that a light is chosen at all:
/// 1 unless a branch the walk enters holds no light that reaches the point (a node's
/// bounds are looser than its children's), which the walk then reports as no light.
#[test]
fn the_probabilities_of_all_lights_sum_to_the_chance_of_choosing_one() {
    for (n, seed) in [(1, 1), (2, 2), (7, 3), (100, 4), (1000, 5)] {
        let lights = scattered(n, seed);
        let tree = LightTree::new(&lights);
        let mut r = Lcg(seed + 100);
        let (mut reached, mut full, mut lost) = (0, 0, 0.0);
        for _ in 0..50 {
            let (p, normal) = (r.vec(-6.0, 6.0), if r.next() < 0.5 { r.unit() } else { Vec3::ZERO });
            let sum: f64 = (0..n).map(|k| tree.pmf(k, p, normal) as f64).sum();
            let chance = found(&tree, p, normal, 20_000);
            assert!(sum <= 1.0 + 1e-4, "{n} lights at {p}: probabilities sum to {sum}");
            assert!((sum - chance).abs() < 2e-3, "{n} lights at {p}: probabilities sum to {sum}, chosen {chance}");
            reached += (sum > 0.0) as u32;
            full += ((sum - 1.0).abs() < 1e-4) as u32;
            lost += (1.0 - sum).max(0.0) * (sum > 0.0) as u32 as f64;
        }
        assert!(reached >= 10, "{n} lights: only {reached} of 50 points reached");
        let lost = lost / reached as f64;
        assert!(
            lost < 0.2,
            "{n} lights: the walk found no light {lost:.3} of the time ({} of {reached} points)",
            reached - full
        );
    }
}

/// Chi-square of the sampled lights' counts (and of "no light") against `pmf` at a few
/// points: the sampler draws what the density says, and reports the density's bits (with
/// a child's share taken from its neighbour's slot in the density, or the sample value
/// scaled short of the total, this fails).
#[test]
fn sampled_lights_follow_their_probabilities() {
    let lights = scattered(40, 7);
    let tree = LightTree::new(&lights);
    let samples = 200_000;
    for (p, normal) in
        [(Vec3::ZERO, Vec3::Y), (Vec3::new(4.0, -3.0, 1.0), Vec3::ZERO), (Vec3::new(-5.5, 5.0, 0.0), Vec3::X)]
    {
        let mut counts = vec![0u32; lights.len() + 1];
        for i in 0..samples {
            // Stratified values: the chi-square's expected counts are then an upper
            // bound on its variance, and a wrong density still shows by far.
            let u = (i as f32 + 0.5) / samples as f32;
            match tree.sample(p, normal, u) {
                Some((k, pmf, rest)) => {
                    assert!((0.0..1.0).contains(&rest), "rescaled value {rest}");
                    let expected = tree.pmf(k, p, normal);
                    assert_eq!(pmf.to_bits(), expected.to_bits(), "light {k}: sampled pmf {pmf}, density {expected}");
                    counts[k] += 1;
                }
                None => counts[lights.len()] += 1,
            }
        }
        let mut expected: Vec<f64> = (0..lights.len()).map(|k| tree.pmf(k, p, normal) as f64).collect();
        expected.push((1.0 - expected.iter().sum::<f64>()).max(0.0));
        assert!(expected[lights.len()] < 0.5, "at {p}: most of the walks found no light");
        let mut chi2 = 0.0;
        let mut bins = 0;
        for (k, &c) in counts.iter().enumerate() {
            let e = expected[k] * samples as f64;
            if e > 5.0 {
                chi2 += (c as f64 - e).powi(2) / e;
                bins += 1;
            } else {
                assert!(c as f64 <= e + 10.0, "light {k}: {c} samples where {e:.2} were expected");
            }
        }
        // 99.9 % quantile of chi-square with ≤ 40 degrees of freedom is below 74.
        assert!(chi2 < 74.0, "at {p}: chi-square {chi2:.1} over {bins} bins");
    }
}

#[test]
fn a_point_behind_every_light_gets_none_and_one_in_front_gets_the_nearest_more_often() {
    // Two one-sided lights in the plane y = 0, facing up, equal power.
    let lights =
        [emitter(Vec3::new(-1.0, 0.0, 0.0), 0.2, Vec3::Y, 1.0), emitter(Vec3::new(3.0, 0.0, 0.0), 0.2, Vec3::Y, 1.0)];
    let tree = LightTree::new(&lights);
    assert!(tree.sample(Vec3::new(0.0, -2.0, 0.0), Vec3::ZERO, 0.3).is_none());
    assert_eq!(tree.pmf(0, Vec3::new(0.0, -2.0, 0.0), Vec3::ZERO), 0.0);
    let above_first = Vec3::new(-1.0, 1.0, 0.0);
    assert!(tree.pmf(0, above_first, Vec3::ZERO) > 0.8, "the near light: {}", tree.pmf(0, above_first, Vec3::ZERO));
    assert!(tree.pmf(1, above_first, Vec3::ZERO) > 0.0, "the far light must keep a chance");
}

#[test]
fn a_union_of_cones_holds_both() {
    let mut r = Lcg(11);
    for _ in 0..2000 {
        let (a, b) = ((r.unit(), 2.0 * r.next() - 1.0), (r.unit(), 2.0 * r.next() - 1.0));
        let (w, cos_o) = cone_union(a, b);
        if cos_o <= -1.0 {
            // The whole sphere holds every cone.
            continue;
        }
        for (axis, cos) in [a, b] {
            // The edge of each cone lies within the union: angle(w, axis) + θ ≤ θ_union.
            let inside = w.dot(axis).clamp(-1.0, 1.0).acos() + cos.acos();
            assert!(inside <= cos_o.acos() + 1e-3, "cone ({axis}, {cos}) not inside ({w}, {cos_o})");
        }
    }
}

#[test]
fn lights_in_one_place_and_lights_without_power_build_a_usable_tree() {
    // A thousand lights at one point (no split separates them), then with every other
    // one dark: the dark ones are never chosen, the others share the point's probability.
    let mut lights = vec![emitter(Vec3::ONE, 0.1, Vec3::Y, 1.0); 1000];
    let tree = LightTree::new(&lights);
    let p = Vec3::new(1.0, 3.0, 1.0);
    let sum: f32 = (0..1000).map(|k| tree.pmf(k, p, Vec3::ZERO)).sum();
    assert!((sum - 1.0).abs() < 1e-3, "{sum}");
    for (k, l) in lights.iter_mut().enumerate() {
        if k % 2 == 1 {
            l.phi = 0.0;
        }
    }
    let tree = LightTree::new(&lights);
    assert_eq!(tree.pmf(1, p, Vec3::ZERO), 0.0);
    assert!((tree.pmf(0, p, Vec3::ZERO) - 1.0 / 500.0).abs() < 1e-5);
    assert!(LightTree::new(&[]).is_empty());
    assert!(LightTree::new(&[emitter(Vec3::ZERO, 1.0, Vec3::Y, 0.0)]).is_empty());
}

/// Lights at x = 1.6ᵏ: each split by cost peels off the few farthest lights, a tree
/// ten and more levels deep (the depth limit, after which the build halves by count,
/// guards its 128-bit trails: a debug assertion); the deep lights' trails still lead to
/// them and the tree still samples what it says.
#[test]
fn lopsided_lights_build_a_deep_tree_whose_trails_hold() {
    let lights: Vec<LightBounds> =
        (0..80).map(|k| emitter(Vec3::new(1.6f32.powi(k), 0.0, 0.0), 0.1, Vec3::Y, 1.0)).collect();
    let tree = LightTree::new(&lights);
    let deepest = tree.trails.iter().map(|t| (128 - t.leading_zeros()).div_ceil(2)).max().unwrap();
    assert!(deepest >= 8, "a shallow tree (deepest turn off the first slot at depth {deepest})");
    let p = Vec3::new(3.0, 2.0, 0.0);
    let sum: f64 = (0..lights.len()).map(|k| tree.pmf(k, p, Vec3::ZERO) as f64).sum();
    assert!((sum - 1.0).abs() < 1e-4, "{sum}");
    let mut drawn = vec![false; lights.len()];
    let mut none = 0;
    for i in 0..100_000 {
        // (A walk may end where no light reaches: as often as the pmfs fall short of 1.)
        let Some((k, pmf, _)) = tree.sample(p, Vec3::ZERO, (i as f32 + 0.5) / 100_000.0) else {
            none += 1;
            continue;
        };
        assert_eq!(pmf.to_bits(), tree.pmf(k, p, Vec3::ZERO).to_bits(), "light {k}");
        drawn[k] = true;
    }
    assert!(none as f64 / 1e5 <= 1.0 - sum + 1e-4, "{none} walks found no light");
    assert!(drawn[..8].iter().all(|&d| d), "the lights near the point are drawn");
}

/// `flatten` loses nothing and lays the nodes out as documented (what the GPU's
/// `wgsl/lights.wgsl` reads): each node read back from its floats by that layout is the
/// node, bit for bit, and each trail's four words are the trail.
#[test]
fn the_flat_tables_hold_the_tree_in_the_documented_layout() {
    for tree in [LightTree::new(&scattered(300, 11)), LightTree::new(&scattered(5, 3))] {
        let (nodes, trails) = tree.flatten();
        assert_eq!(nodes.len(), NODE_FLOATS * tree.nodes.len());
        for (flat, node) in nodes.chunks_exact(NODE_FLOATS).zip(&tree.nodes) {
            let row = |r: usize| Vec4::from_slice(&flat[4 * r..4 * r + 4]);
            let bits = |i: usize| flat[i].to_bits();
            let read = Node {
                centre: [row(0), row(1), row(2)],
                radius2: row(3),
                min_d2: row(4),
                w: [row(5), row(6), row(7)],
                phi: row(8),
                cos_theta_o: row(9),
                sin_theta_o: row(10),
                cos_theta_e: row(11),
                child: [bits(48), bits(49), bits(50), bits(51)],
                lights: bits(52) as u8,
            };
            assert_eq!(format!("{read:?}"), format!("{node:?}"));
            assert_eq!(bits(52) >> 4, 0, "four slots, four mask bits");
            assert_eq!(&flat[53..], &[0.0; 3]);
        }
        assert_eq!(trails.len(), tree.trails.len());
        for (words, &trail) in trails.iter().zip(&tree.trails) {
            let joined = words.iter().enumerate().fold(0u128, |t, (i, &w)| t | (w as u128) << (32 * i));
            assert_eq!(joined, trail);
        }
    }
}
