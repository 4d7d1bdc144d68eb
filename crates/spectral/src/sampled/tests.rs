use super::*;

#[test]
fn precomputed_cdf_ends_match_the_formula() {
    assert!((VIS_TANH_LO - (VIS_K * (LAMBDA_MIN - VIS_CENTRE)).tanh()).abs() < 1e-6);
    assert!((VIS_TANH_HI - (VIS_K * (LAMBDA_MAX - VIS_CENTRE)).tanh()).abs() < 1e-6);
    for l in [380.0f32, 500.0, 700.0] {
        let u = ((VIS_K * (l - VIS_CENTRE)).tanh() - VIS_TANH_LO) / (VIS_TANH_HI - VIS_TANH_LO);
        let (back, pdf) = sample_visible(u);
        assert!((back - l).abs() < 0.05 && (pdf - visible_wavelength_pdf(l)).abs() < 1e-7, "{l}");
    }
}

#[test]
fn visible_pdf_integrates_to_one() {
    // Midpoint rule at 0.01 nm over the support.
    let n = 47_000;
    let h = (LAMBDA_MAX - LAMBDA_MIN) as f64 / n as f64;
    let integral: f64 =
        (0..n).map(|i| visible_wavelength_pdf(LAMBDA_MIN + ((i as f64 + 0.5) * h) as f32) as f64 * h).sum();
    assert!((integral - 1.0).abs() < 1e-4, "∫pdf = {integral}");
}

#[test]
fn sampling_inverts_the_cdf() {
    // The fraction of samples below λ must equal ∫pdf up to λ (a Kolmogorov–Smirnov
    // style check on a deterministic, uniform grid of u).
    let n = 100_000;
    let mut lambdas: Vec<f32> = (0..n).map(|i| sample_visible_wavelength((i as f32 + 0.5) / n as f32)).collect();
    lambdas.sort_by(f32::total_cmp);
    for probe in [400.0f32, 500.0, 538.0, 600.0, 700.0, 800.0] {
        let below = lambdas.partition_point(|&l| l < probe) as f64 / n as f64;
        let steps = 20_000;
        let h = (probe - LAMBDA_MIN) as f64 / steps as f64;
        let cdf: f64 =
            (0..steps).map(|i| visible_wavelength_pdf(LAMBDA_MIN + ((i as f64 + 0.5) * h) as f32) as f64 * h).sum();
        assert!((below - cdf).abs() < 1e-3, "λ={probe}: empirical {below}, cdf {cdf}");
    }
}

#[test]
fn hero_wavelengths_are_stratified_and_in_range() {
    for k in 0..100 {
        // Midpoints: u = 0 would put a wavelength exactly on a stratum boundary.
        let u = (k as f32 + 0.5) / 100.0;
        let wl = SampledWavelengths::<4>::sample_hero(u);
        for (&l, &w) in wl.lambda.iter().zip(&wl.weight) {
            assert!((LAMBDA_MIN..=LAMBDA_MAX).contains(&l));
            assert!(w.is_finite() && w > 0.0);
        }
        let mut sorted = wl.lambda;
        sorted.sort_by(f32::total_cmp);
        // One wavelength in each quarter of the CDF: no two share a stratum.
        let strata: Vec<usize> = sorted
            .iter()
            .map(|&l| {
                let (lo, hi) = (VIS_TANH_LO, VIS_TANH_HI);
                let u = ((VIS_K * (l - VIS_CENTRE)).tanh() - lo) / (hi - lo);
                ((u * 4.0) as usize).min(3)
            })
            .collect();
        let mut s = strata.clone();
        s.dedup();
        assert_eq!(s.len(), 4, "strata {strata:?} for u = {u}");
    }
}

#[test]
fn hero_estimate_of_a_constant_spectrum_is_unbiased() {
    // E[XYZ] of a constant spectrum 1 is the CMF integral / ∫ȳ → Y = 1.
    let n = 20_000;
    let mut y = 0.0f64;
    for i in 0..n {
        let wl = SampledWavelengths::<4>::sample_hero((i as f32 + 0.5) / n as f32);
        let rgb = wl.to_linear_srgb(&SampledSpectrum::one());
        y += (0.212_639 * rgb[0] + 0.715_168_7 * rgb[1] + 0.072_192_3 * rgb[2]) as f64;
    }
    let y = y / n as f64;
    assert!((y - 1.0).abs() < 2e-3, "Y = {y}");
}

#[test]
fn collapsing_keeps_the_estimate_unbiased() {
    // A spectrum that is 1 at every wavelength: collapsing to any lane must leave
    // the expected colour unchanged.
    let n = 20_000;
    let mut full = [0.0f64; 3];
    let mut collapsed = [0.0f64; 3];
    for i in 0..n {
        let u = (i as f32 + 0.5) / n as f32;
        let wl = SampledWavelengths::<4>::sample_hero(u);
        let mut c = wl;
        c.collapse_to(i % 4);
        assert!(c.is_collapsed() && !wl.is_collapsed());
        let a = wl.to_linear_srgb(&SampledSpectrum::one());
        let b = c.to_linear_srgb(&SampledSpectrum::one());
        for k in 0..3 {
            full[k] += a[k] as f64 / n as f64;
            collapsed[k] += b[k] as f64 / n as f64;
        }
    }
    for k in 0..3 {
        assert!((full[k] - collapsed[k]).abs() < 5e-3, "{full:?} vs {collapsed:?}");
    }
}

#[test]
fn rgb_mode_passes_channels_through() {
    let wl = SampledWavelengths::<3>::rgb();
    assert_eq!(wl.to_linear_srgb(&SampledSpectrum([0.1, 0.2, 0.3])), [0.1, 0.2, 0.3]);
}

#[test]
fn mode_names_round_trip() {
    for m in SpectralMode::ALL {
        assert_eq!(m.name().parse::<SpectralMode>().unwrap(), m);
    }
    assert!("rgb8".parse::<SpectralMode>().is_err());
}

#[test]
fn fast_atanh_matches_f64() {
    // Every 1/4096 of (-1, 1) and points near the clamp of `sample_visible`.
    let mut worst = (0.0f64, 0.0f32);
    let grid = (-4095..4096).map(|i| i as f32 / 4096.0);
    for t in grid.chain([-0.999_999, 0.999_999, 1e-8, -1e-8, 0.0, VIS_TANH_LO, VIS_TANH_HI]) {
        let exact = (t as f64).atanh();
        let err = (atanh(t) as f64 - exact).abs();
        assert!(err <= 2e-7 + 1e-7 * exact.abs(), "atanh({t}) = {} vs {exact}", atanh(t));
        if err > worst.0 {
            worst = (err, t);
        }
    }
    assert!(worst.0 > 0.0, "the test compares something");
    // ln over many octaves, including values just below and above √2.
    let sqrt2 = std::f32::consts::SQRT_2;
    let around_sqrt2 = [f32::from_bits(sqrt2.to_bits() - 1), sqrt2, f32::from_bits(sqrt2.to_bits() + 1)];
    for x in [1e-30f32, 1e-3, 0.5, 0.999_999, 1.0, 1.000_001, 2.0, 3.7, 1e6, 3e38].into_iter().chain(around_sqrt2) {
        let exact = (x as f64).ln();
        assert!((ln_positive(x) as f64 - exact).abs() <= 1e-7 * exact.abs().max(1.0), "ln({x})");
    }
}

/// The many-sample forms are the one-sample ones to the bit: hero wavelengths from sample
/// values across [0, 1) (with its ends), and colours of radiances that are zero, tiny,
/// large, NaN or infinite at wavelengths inside and outside the tables.
#[test]
fn many_sample_forms_equal_the_one_sample_forms_bit_for_bit() {
    const L: usize = 16;
    let mut rng = rng::Pcg32::new(5, 9);
    // (A NaN's payload may differ with the order of operations; the film drops NaNs.)
    let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    let specials = [0.0, -0.0, 1e-30, 3.5e4, f32::NAN, f32::INFINITY, -2.0];
    for round in 0..2_000 {
        let mut u: [f32; L] = std::array::from_fn(|_| rng.next_f32());
        if round == 0 {
            u[0] = 0.0;
            u[1] = f32::from_bits(1.0f32.to_bits() - 1);
        }
        let each = SampledWavelengths::<4>::sample_hero_each(&u);
        for k in 0..L {
            let one = SampledWavelengths::<4>::sample_hero(u[k]);
            assert!(each[k].lambda.iter().zip(&one.lambda).all(|(a, b)| same(*a, *b)), "λ of u = {}", u[k]);
            assert!(each[k].weight.iter().zip(&one.weight).all(|(a, b)| same(*a, *b)), "weight of u = {}", u[k]);
        }
        // Some wavelengths beyond the tables, as a collapsed or fixed set may hold.
        let mut wl = each;
        wl[3].lambda[1] = 200.0;
        wl[4].lambda[2] = 900.0;
        wl[5].lambda[0] = f32::NAN;
        let radiance: [SampledSpectrum<4>; L] = std::array::from_fn(|_| {
            SampledSpectrum(std::array::from_fn(|_| {
                let r = rng.next_u32();
                if r.is_multiple_of(5) { specials[(r / 5) as usize % specials.len()] } else { 10.0 * rng.next_f32() }
            }))
        });
        let rgb = SampledWavelengths::to_linear_srgb_each(&wl, &radiance);
        for k in 0..L {
            let one = wl[k].to_linear_srgb(&radiance[k]);
            assert!(rgb[k].iter().zip(&one).all(|(a, b)| same(*a, *b)), "{:?} {:?}", rgb[k], one);
        }
    }
    // RGB mode passes the channels through, as one sample at a time.
    let rgb = [SampledWavelengths::<3>::rgb(); 2];
    let radiance = [SampledSpectrum([1.0, 2.0, 3.0]), SampledSpectrum([0.5, 0.0, -1.0])];
    assert_eq!(SampledWavelengths::to_linear_srgb_each(&rgb, &radiance), [[1.0, 2.0, 3.0], [0.5, 0.0, -1.0]]);
}
