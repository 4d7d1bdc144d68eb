//! Tests of `sampler.rs`: the Sobol points are stratified, uniform and decorrelated across
//! dimensions, and integrate smooth functions with far less error than independent ones.

use super::*;

/// The points of dimensions (d, d+1) of every sample of pixel (x, y).
fn pixel_points(layout: &ZSobolLayout, x: u32, y: u32, spp: u32, skip_dims: u32) -> Vec<Vec2> {
    (0..spp)
        .map(|s| {
            let mut z = layout.sampler(x, y, s);
            for _ in 0..skip_dims {
                z.next_1d();
            }
            z.next_2d()
        })
        .collect()
}

/// True if every elementary interval of area 1/n with power-of-two sides holds exactly one
/// of the n points: a (0, m, 2)-net in base 2.
fn is_net(points: &[Vec2]) -> bool {
    let n = points.len();
    let m = n.trailing_zeros();
    (0..=m).all(|k| {
        let (cols, rows) = (1usize << k, n >> k);
        let mut seen = vec![false; n];
        points.iter().all(|p| {
            let c = ((p.x * cols as f32) as usize).min(cols - 1);
            let r = ((p.y * rows as f32) as usize).min(rows - 1);
            !std::mem::replace(&mut seen[r * cols + c], true)
        })
    })
}

#[test]
fn every_dimension_pair_of_a_pixel_is_stratified() {
    for spp in [4u32, 16, 64] {
        let layout = ZSobolLayout::new(64, 48, spp, 7);
        for (x, y) in [(0, 0), (5, 3), (63, 47)] {
            for skip in [0u32, 2, 3, 7] {
                let pts = pixel_points(&layout, x, y, spp, skip);
                assert!(is_net(&pts), "spp {spp} pixel ({x}, {y}) dims {skip}..: {pts:?}");
            }
        }
    }
    // Independent points are not a net (the check can fail).
    let mut rng = Pcg32::seed_from_u64(3);
    let pts: Vec<Vec2> = (0..16).map(|_| Sampler::next_2d(&mut rng)).collect();
    assert!(!is_net(&pts));
}

#[test]
fn values_are_uniform_and_dimensions_uncorrelated() {
    let layout = ZSobolLayout::new(32, 32, 16, 11);
    let (mut hist, mut n) = ([0u32; 16], 0u32);
    let (mut sxy, mut sx, mut sy, mut sxx, mut syy) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for y in 0..32 {
        for x in 0..32 {
            for s in 0..16 {
                let mut z = layout.sampler(x, y, s);
                let _ = z.next_2d();
                let a = z.next_1d();
                let b = z.next_1d();
                hist[(a * 16.0) as usize] += 1;
                n += 1;
                let (a, b) = (a as f64, b as f64);
                (sxy, sx, sy, sxx, syy) = (sxy + a * b, sx + a, sy + b, sxx + a * a, syy + b * b);
            }
        }
    }
    // Pearson's chi-square over 16 bins (15 dof): far below the 0.999 quantile 37.7.
    let e = n as f64 / 16.0;
    let chi2: f64 = hist.iter().map(|&h| (h as f64 - e).powi(2) / e).sum();
    assert!(chi2 < 37.7, "{hist:?}: chi2 = {chi2}");
    let nf = n as f64;
    let r = (sxy / nf - sx / nf * sy / nf) / ((sxx / nf - (sx / nf).powi(2)) * (syy / nf - (sy / nf).powi(2))).sqrt();
    assert!(r.abs() < 0.02, "dimensions 2 and 3 correlate: r = {r}");
}

#[test]
fn smooth_integrals_converge_faster_than_with_independent_points() {
    // ∫∫ sin(πx) sin(πy) dx dy = 4/π², 64 samples per pixel, mean squared error over pixels.
    let f = |p: Vec2| (std::f32::consts::PI * p.x).sin() * (std::f32::consts::PI * p.y).sin();
    let exact = 4.0 / std::f64::consts::PI.powi(2);
    let layout = ZSobolLayout::new(16, 16, 64, 5);
    let (mut mse_sobol, mut mse_indep) = (0.0f64, 0.0f64);
    for y in 0..16 {
        for x in 0..16 {
            let est: f64 = pixel_points(&layout, x, y, 64, 4).iter().map(|&p| f(p) as f64).sum::<f64>() / 64.0;
            mse_sobol += (est - exact).powi(2);
            let mut rng = Pcg32::for_sample(5, y * 16 + x, 0);
            let est: f64 = (0..64).map(|_| f(Sampler::next_2d(&mut rng)) as f64).sum::<f64>() / 64.0;
            mse_indep += (est - exact).powi(2);
        }
    }
    assert!(mse_sobol < 0.05 * mse_indep, "sobol {mse_sobol:.3e} vs independent {mse_indep:.3e}");
}

#[test]
fn morton_and_sobol_helpers() {
    assert_eq!(morton2(0b11, 0b01), 0b0111);
    assert_eq!(morton2(0, 1), 0b10);
    assert_eq!((0..8).map(sobol_0).map(|v| v >> 29).collect::<Vec<_>>(), [0, 4, 2, 6, 1, 5, 3, 7]);
    assert_eq!((0..4).map(sobol_1).map(|v| v >> 30).collect::<Vec<_>>(), [0, 2, 3, 1]);
    // The one-reversal forms are the composed ones.
    for (i, seed) in [(0u64, 1u32), (5, 0xdead_beef), (1 << 20 | 77, 12345)] {
        assert_eq!(scrambled_sobol_0(i, seed), owen_scramble(sobol_0(i), seed));
        assert_eq!(scrambled_sobol_1(i, seed), owen_scramble(sobol_1(i), seed));
    }
    // Scrambling keeps a stratified set stratified: the 8 first points, scrambled, still
    // have one point per eighth.
    let mut eighths: Vec<u32> = (0..8).map(|i| owen_scramble(sobol_0(i), 0xdead_beef) >> 29).collect();
    eighths.sort();
    assert_eq!(eighths, (0..8).collect::<Vec<u32>>());
}

/// The closed form of the reversed second dimension is the direction-number definition
/// reversed for every index: both are linear over GF(2) in the index's bits, so agreeing
/// on the 32 one-bit indices is agreeing everywhere; mixed indices checked as well.
#[test]
fn sobol_1_reversed_is_the_definition_reversed() {
    for bit in 0..32 {
        assert_eq!(sobol_1_reversed(1 << bit), sobol_1(1 << bit).reverse_bits(), "index bit {bit}");
    }
    let mut rng = rng::Pcg32::new(3, 7);
    let mixed = [0u32, 1, 255, 256, 0x1234_5678, u32::MAX, 0x8000_0001];
    for i in mixed.into_iter().chain((0..10_000).map(|_| rng.next_u32())) {
        assert_eq!(sobol_1_reversed(i), sobol_1(i as u64).reverse_bits(), "index {i:#x}");
    }
}

#[test]
fn padded_sobol_pixels_are_stratified_and_dimensions_shuffled() {
    for spp in [4u32, 16, 64] {
        for (x, y) in [(0, 0), (9, 4)] {
            for skip in [0u32, 2, 5] {
                let pts: Vec<Vec2> = (0..spp)
                    .map(|s| {
                        let mut p = PaddedSobol::new(x, y, s, spp, 3);
                        for _ in 0..skip {
                            p.next_1d();
                        }
                        p.next_2d()
                    })
                    .collect();
                assert!(is_net(&pts), "spp {spp} pixel ({x}, {y}) dims {skip}..");
            }
        }
    }
    // Two dimensions of the same sample are not the same value (shuffled independently).
    let same = (0..64)
        .filter(|&s| {
            let mut p = PaddedSobol::new(1, 2, s, 64, 3);
            p.next_1d() == p.next_1d()
        })
        .count();
    assert!(same < 4, "{same} of 64 samples repeat their value in the next dimension");
}

/// Across two dimensions of a pixel's samples, whether each value lies in [0, ½) must
/// not be tied: for a good scramble about half the samples agree. (The xor-and-multiply
/// index shuffle this sampler first had made all 256 agree, or none.)
#[test]
fn padded_sobol_dimensions_are_not_tied() {
    for (x, y) in [(0, 0), (5, 3), (17, 11)] {
        for (a, b) in [(0u32, 1u32), (1, 4), (3, 9)] {
            let agree = (0..256)
                .filter(|&s| {
                    let mut p = PaddedSobol::new(x, y, s, 256, 7);
                    let values: Vec<f32> = (0..10).map(|_| p.next_1d()).collect();
                    (values[a as usize] < 0.5) == (values[b as usize] < 0.5)
                })
                .count();
            assert!((80..=176).contains(&agree), "pixel ({x}, {y}) dims {a}, {b}: {agree} of 256 agree");
        }
    }
}

/// A 1×1 image at 1 spp leaves no bits for the Morton index: the sampler must not shift
/// by 64 (a panic in debug builds, a wrong index in release) but draw sample 0.
#[test]
fn a_one_pixel_one_sample_zsobol_render_draws_index_zero() {
    let layout = ZSobolLayout::new(1, 1, 1, 3);
    let mut s = layout.sampler(0, 0, 0);
    let a = s.next_2d();
    let b = s.next_1d();
    assert!((0.0..1.0).contains(&a.x) && (0.0..1.0).contains(&a.y) && (0.0..1.0).contains(&b));
    let mut padded = PaddedSobol::new(0, 0, 0, 1, 3);
    assert!((0.0..1.0).contains(&padded.next_1d()));
}

/// Draws the next value (`two`: point) of each of `a` one at a time and of `b` (the same
/// samplers) through `lane_draw_*` and `SobolLanes`, and checks the bits agree; returns
/// how many lanes the 32-bit form computed.
fn lane_round<S: Sampler>(a: &mut [S], b: &mut [S], two: bool) -> usize {
    const L: usize = 16;
    let mut lanes = SobolLanes::<L>::default();
    let mut drawn = [None; L];
    let mut want = [Vec2::ZERO; L];
    for k in 0..L {
        want[k] = if two { a[k].next_2d() } else { Vec2::new(a[k].next_1d(), 0.0) };
        match if two { b[k].lane_draw_2d() } else { b[k].lane_draw_1d() } {
            LaneDraw::Value(v) => drawn[k] = Some(v),
            LaneDraw::Sobol(d) => lanes.set(k, &d),
        }
    }
    let (mut x, mut y) = ([0.0; L], [0.0; L]);
    if two {
        lanes.values_2d(&mut x, &mut y);
    } else {
        lanes.values_1d(&mut x);
    }
    for k in 0..L {
        let got = drawn[k].unwrap_or(Vec2::new(x[k], if two { y[k] } else { 0.0 }));
        assert_eq!(got.to_array().map(f32::to_bits), want[k].to_array().map(f32::to_bits), "lane {k}, 2-D {two}");
    }
    drawn.iter().filter(|d| d.is_none()).count()
}

/// The lanes' Sobol draws (`lane_draw_1d`/`_2d`, then `SobolLanes::values_*`, 32-bit
/// arithmetic that vectorises) give the bits of the one-at-a-time draws wherever the
/// sample index has at most 32 bits — none (1×1 at 1 spp), few, exactly 32 — and hand
/// out the drawn point where it has more.
#[test]
fn lane_draws_give_the_one_at_a_time_values() {
    // (image side, spp, index bits)
    for (side, spp, bits) in [(1, 1, 0), (32, 16, 14), (256, 64, 22), (4096, 256, 32), (65_536, 2, 33)] {
        let layout = ZSobolLayout::new(side, side, spp, 11);
        let make = |k: u32| layout.sampler((k * 7919) % side, (k * 104_729) % side, (k * 13) % spp);
        let mut a: Vec<_> = (0..16).map(make).collect();
        let mut b: Vec<_> = (0..16).map(make).collect();
        // The lanes at different dimensions, as paths at different depths are.
        for k in 0..16 {
            for _ in 0..k % 5 {
                a[k].next_1d();
                b[k].next_1d();
            }
        }
        let mut computed = 0;
        // Past the precomputed dimensions' seeds too.
        for round in 0..PRECOMPUTED_DIMENSIONS / 2 + 20 {
            computed += lane_round(&mut a, &mut b, round % 3 != 0);
        }
        assert_eq!(computed > 0, bits <= 32, "{side}² at {spp} spp");
    }
    for spp in [1, 4, 1 << 20] {
        let make = |k: u32| PaddedSobol::new(k, 3 * k, k % spp, spp, 5);
        let mut a: Vec<_> = (0..16).map(make).collect();
        let mut b: Vec<_> = (0..16).map(make).collect();
        let computed: usize = (0..40).map(|round| lane_round(&mut a, &mut b, round % 2 == 0)).sum();
        assert_eq!(computed, 40 * 16, "padded Sobol at {spp} spp");
    }
}
