use super::*;
use crate::colour::{XYZ_TO_SRGB, mul3, spectrum_to_xyz};

/// Linear sRGB of a reflectance lit by normalised D65 (1 nm sums over 360–830 nm):
/// the integral the fit inverts, evaluated through the public `f32` path.
fn reflectance_rgb(s: impl Fn(f32) -> f32) -> [f32; 3] {
    mul3(&XYZ_TO_SRGB, spectrum_to_xyz(|l| s(l) * d65_normalised(l)))
}

/// Linear sRGB of a radiance: ∫ L·x̄ / ∫ȳ at 1 nm, then XYZ → sRGB.
fn radiance_rgb(s: impl Fn(f32) -> f32) -> [f32; 3] {
    mul3(&XYZ_TO_SRGB, spectrum_to_xyz(s))
}

const CORNELL: [[f32; 3]; 4] = [[0.725, 0.71, 0.68], [0.63, 0.065, 0.05], [0.14, 0.45, 0.091], [0.78, 0.78, 0.78]];

/// The 9³ grid over [0, 1]³ plus the Cornell-box colours.
fn test_colours() -> Vec<[f32; 3]> {
    let mut v = Vec::new();
    for r in 0..9 {
        for g in 0..9 {
            for b in 0..9 {
                v.push([r as f32 / 8.0, g as f32 / 8.0, b as f32 / 8.0]);
            }
        }
    }
    v.extend(CORNELL);
    v
}

#[test]
fn sigmoid_limits_and_known_coefficients() {
    assert_eq!(sigmoid(0.0), 0.5);
    assert_eq!(sigmoid(f32::INFINITY), 1.0);
    assert_eq!(sigmoid(f32::NEG_INFINITY), 0.0);
    assert_eq!(sigmoid(1e20), 1.0);
    assert_eq!(sigmoid(-1e20), 0.0);
    assert_eq!(sigmoid(f32::MAX), 1.0);
    assert!((sigmoid(1.0) - (0.5 + 0.5 / 2f32.sqrt())).abs() < 1e-7);
    assert!((sigmoid(-1.0) - (0.5 - 0.5 / 2f32.sqrt())).abs() < 1e-7);
    // S(x) + S(−x) = 1 and S is increasing.
    for x in [-1e4f32, -30.0, -2.0, -0.3, 0.1, 3.0, 100.0] {
        assert!((sigmoid(x) + sigmoid(-x) - 1.0).abs() < 1e-6);
        assert!(sigmoid(x) <= sigmoid(x + x.abs() * 0.01 + 0.01));
    }
    // x(λ) = 1e-4 λ² − 0.1 λ + 25 = (λ/100 − 5)²: 0 at 500 nm, 1 at 600 nm and 400 nm.
    let p = SigmoidPolynomial { c0: 1e-4, c1: -0.1, c2: 25.0 };
    assert!((p.eval(500.0) - 0.5).abs() < 1e-5);
    assert!((p.eval(600.0) - 0.853_553_4).abs() < 1e-4);
    assert!((p.eval(400.0) - 0.853_553_4).abs() < 1e-4);
    // Its negation peaks at the vertex, 500 nm, with S(0) = ½.
    let n = SigmoidPolynomial { c0: -1e-4, c1: 0.1, c2: -25.0 };
    assert!((n.max_value() - 0.5).abs() < 1e-5);
    assert!((p.max_value() - p.eval(830.0)).abs() < 1e-7 && p.max_value() > 0.99);
    // Infinite constants give exact 0 / 1, not NaN.
    let one = SigmoidPolynomial { c0: 0.0, c1: 0.0, c2: f32::INFINITY };
    let zero = SigmoidPolynomial { c0: 0.0, c1: 0.0, c2: f32::NEG_INFINITY };
    assert_eq!((one.eval(550.0), one.max_value()), (1.0, 1.0));
    assert_eq!((zero.eval(550.0), zero.max_value()), (0.0, 0.0));
}

#[test]
fn nanometre_expansion_matches_normalised_polynomial() {
    for c in [[3.0, -2.0, 0.5], [-150.0, 140.0, -30.0], [1e3, -900.0, 200.0]] {
        let p = to_nanometres(c);
        for lambda in [360.0f64, 412.0, 555.5, 700.0, 830.0] {
            let t = (lambda - 360.0) / 470.0;
            let want = sigmoid64((c[0] * t + c[1]) * t + c[2]);
            let got = p.eval(lambda as f32) as f64;
            // f32 rounding of the expanded coefficients; S' ≤ ½.
            assert!((got - want).abs() < 2e-4, "{c:?} at {lambda}: {got} vs {want}");
        }
    }
}

#[test]
fn greys_are_constant_in_closed_form() {
    for v in [0.0f32, 0.02, 0.5, 0.78, 1.0] {
        let p = fit_reflectance([v; 3]).unwrap();
        assert_eq!((p.c0, p.c1), (0.0, 0.0));
        assert!(p.c2.is_finite());
        for l in [360.0, 500.0, 830.0] {
            assert!((p.eval(l) - v).abs() < 1e-6, "{v}: {}", p.eval(l));
        }
    }
}

/// The linear sRGB of s ≡ 1 under the tabulated D65: the fit's white.
fn table_white_rgb() -> [f32; 3] {
    reflectance_rgb(|_| 1.0)
}

#[test]
fn table_white_is_close_to_srgb_white() {
    // The 2.4e-4 offset the fit's target compensates (see the module docs).
    let w = table_white_rgb();
    for c in w {
        assert!((c - 1.0).abs() < 3e-4, "{w:?}");
    }
}

#[test]
fn round_trip_over_the_srgb_cube() {
    let colours = test_colours();
    let white = table_white_rgb();
    let _ = fit_reflectance([0.3, 0.2, 0.1]); // Build the tables outside the timing.
    let start = std::time::Instant::now();
    let fits: Vec<_> = colours.iter().map(|&c| fit_reflectance(c).unwrap()).collect();
    let per_colour = start.elapsed() / colours.len() as u32;
    // Raw: rgb → spectrum → D65-lit XYZ → XYZ_TO_SRGB. Relative: the same divided by
    // the table white's rgb (what the fit matches by construction).
    let (mut max_raw, mut sum_raw, mut worst_raw) = (0.0f32, 0.0f64, [0.0f32; 3]);
    let (mut max_rel, mut sum_rel, mut worst_rel) = (0.0f32, 0.0f64, [0.0f32; 3]);
    for (rgb, p) in colours.iter().zip(&fits) {
        let back = reflectance_rgb(|l| p.eval(l));
        let raw = (0..3).map(|k| (back[k] - rgb[k]).abs()).fold(0.0, f32::max);
        let rel = (0..3).map(|k| (back[k] / white[k] - rgb[k]).abs()).fold(0.0, f32::max);
        sum_raw += raw as f64;
        sum_rel += rel as f64;
        if raw > max_raw {
            (max_raw, worst_raw) = (raw, *rgb);
        }
        if rel > max_rel {
            (max_rel, worst_rel) = (rel, *rgb);
        }
    }
    let n = colours.len() as f64;
    let (mean_raw, mean_rel) = (sum_raw / n, sum_rel / n);
    println!(
        "round trip over {} colours, {per_colour:?} per fit: raw max {max_raw:.3e} at \
         {worst_raw:?}, mean {mean_raw:.3e}; white-relative max {max_rel:.3e} at \
         {worst_rel:?}, mean {mean_rel:.3e}",
        colours.len()
    );
    // Measured: raw max 2.45e-4 at (0.5, 0, 1), mean 1.43e-4 (the table white's
    // offset from (1, 1, 1), which the fit keeps); white-relative max 5.7e-6 at
    // (0, 1, 0.125), mean 1.1e-6 (f32 evaluation and the 1e-6 clamp of 0/1 channels).
    assert!(max_raw < 5e-4, "raw max {max_raw} at {worst_raw:?}");
    assert!(mean_raw < 3e-4, "raw mean {mean_raw}");
    assert!(max_rel < 5e-5, "relative max {max_rel} at {worst_rel:?}");
    assert!(mean_rel < 2e-5, "relative mean {mean_rel}");
}

#[test]
fn cornell_colours_round_trip_tightly() {
    let white = table_white_rgb();
    for rgb in CORNELL {
        let s = RgbAlbedoSpectrum::new(rgb).unwrap();
        let back = reflectance_rgb(|l| s.eval(l));
        for k in 0..3 {
            // Measured ≤ 2e-4 raw, ≤ 2e-6 relative to the table white.
            assert!((back[k] - rgb[k]).abs() < 4e-4, "{rgb:?} → {back:?}");
            assert!((back[k] / white[k] - rgb[k]).abs() < 2e-5, "{rgb:?} → {back:?}");
        }
    }
}

#[test]
fn random_and_edge_colours_all_converge() {
    // Deterministic random colours, some with a channel at 0 or 1, some very dark,
    // some near white and some a hair away from grey.
    let mut rng = rng::Pcg32::seed_from_u64(1);
    let mut rnd = || rng.next_f32();
    let mut colours = Vec::new();
    for i in 0..1500 {
        let mut c = [rnd(), rnd(), rnd()];
        match i % 5 {
            0 => c[i / 5 % 3] = if rnd() < 0.5 { 0.0 } else { 1.0 },
            1 => c = c.map(|v| v * 1e-3),
            2 => c = c.map(|v| 1.0 - v * 1e-3),
            3 => c = [c[0], c[0] + 1e-6, c[0]].map(|v| v.min(1.0)),
            _ => {}
        }
        colours.push(c);
    }
    for v in [1e-6f32, 1e-3, 0.999, 0.9999] {
        colours.extend([[v, 0.0, 0.0], [0.0, v, 0.0], [0.0, 0.0, v]]);
        colours.extend([[v, 1.0, 1.0], [1.0, v, 1.0], [1.0, 1.0, v]]);
    }
    let white = table_white_rgb();
    let mut max_rel = 0.0f32;
    for rgb in colours {
        let p = fit_reflectance(rgb).unwrap_or_else(|e| panic!("{rgb:?}: {e}"));
        let back = reflectance_rgb(|l| p.eval(l));
        let rel = (0..3).map(|k| (back[k] / white[k] - rgb[k]).abs()).fold(0.0, f32::max);
        max_rel = max_rel.max(rel);
        assert!(rel < 5e-5, "{rgb:?} → {back:?}");
    }
    // Measured: 5.8e-6.
    println!("random and edge colours: white-relative max {max_rel:.3e}");
}

#[test]
fn fitted_spectra_are_bounded_reflectances() {
    for rgb in test_colours() {
        let p = fit_reflectance(rgb).unwrap();
        let m = p.max_value();
        assert!((0.0..=1.0).contains(&m), "{rgb:?}: max {m}");
        // max_value agrees with dense sampling (it is the true maximum over 360–830).
        let mut dense = 0.0f32;
        for i in 0..=4700 {
            let v = p.eval(360.0 + i as f32 * 0.1);
            assert!((0.0..=1.0).contains(&v), "{rgb:?} at {i}: {v}");
            dense = dense.max(v);
        }
        // (f32 rounding of `eval` for coefficients up to ~1e3: a few 1e-6.)
        assert!((m - dense).abs() < 2e-5, "{rgb:?}: {m} vs {dense}");
    }
}

#[test]
fn illuminant_white_and_bright_colours_reproduce_their_rgb() {
    let white = RgbIlluminantSpectrum::new([1.0; 3]).unwrap();
    assert_eq!(white.scale, 2.0);
    let rgb = radiance_rgb(|l| white.eval(l));
    for c in rgb {
        assert!((c - 1.0).abs() < 2e-3, "white emitter → {rgb:?}");
    }
    let target = [17.0f32, 12.0, 4.0];
    let s = RgbIlluminantSpectrum::new(target).unwrap();
    let rgb = radiance_rgb(|l| s.eval(l));
    for k in 0..3 {
        assert!((rgb[k] / target[k] - 1.0).abs() < 0.01, "{target:?} → {rgb:?}");
    }
    let black = RgbIlluminantSpectrum::new([0.0; 3]).unwrap();
    assert!((360..=830).all(|l| black.eval(l as f32) == 0.0));
}

#[test]
fn d65_normalised_has_unit_luminance() {
    let xyz = spectrum_to_xyz(d65_normalised);
    assert!((xyz[1] - 1.0).abs() < 1e-5, "Y = {}", xyz[1]);
    assert_eq!(d65_normalised(299.0), 0.0);
    assert_eq!(d65_normalised(831.0), 0.0);
    assert_eq!(d65_normalised(f32::NAN), 0.0);
    // Relative shape preserved: D65 is 100 at 560 nm, 117.812 at 460 nm, and linear
    // in between samples.
    let ratio = d65_normalised(460.0) / d65_normalised(560.0);
    assert!((ratio - 1.178_12).abs() < 1e-5, "{ratio}");
    let mid = d65_normalised(462.5) / d65_normalised(560.0);
    assert!((mid - 0.5 * (1.178_12 + 1.163_36)).abs() < 1e-5, "{mid}");
}

#[test]
fn out_of_range_inputs_are_errors() {
    for rgb in [[-0.1, 0.5, 0.5], [0.5, 1.01, 0.5], [0.5, 0.5, f32::NAN], [f32::INFINITY, 0.0, 0.0]] {
        assert!(matches!(fit_reflectance(rgb), Err(SpectralError::ReflectanceOutOfRange { .. })), "{rgb:?}");
        assert!(RgbAlbedoSpectrum::new(rgb).is_err());
    }
    for rgb in [[-1.0, 2.0, 2.0], [f32::NAN, 1.0, 1.0], [1.0, f32::INFINITY, 1.0]] {
        assert!(matches!(RgbIlluminantSpectrum::new(rgb), Err(SpectralError::BadValue { .. })), "{rgb:?}");
    }
    assert!(RgbIlluminantSpectrum::new([f32::MAX, 0.0, 0.0]).is_err());
    // Large but finite radiances are fine.
    assert!(RgbIlluminantSpectrum::new([1e6, 0.0, 3.0]).is_ok());
}
