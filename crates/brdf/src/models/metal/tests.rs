//! Tests of `models/metal.rs`.

use super::*;
use crate::fresnel::fresnel_dielectric;
use rng::Pcg32;
use spectral::colour::{spectrum_to_xyz, xyz_to_linear_srgb};
use spectral::uplift::d65_normalised;

/// Reference: the Fresnel equations in complex arithmetic (f64), as pbrt-v4's
/// `FrComplex`: cos θt = √(1 − sin²θi/η²), r∥ = (η cos θi − cos θt)/(η cos θi + cos θt),
/// r⊥ = (cos θi − η cos θt)/(cos θi + η cos θt), R = (|r∥|² + |r⊥|²)/2.
fn fresnel_complex(cos_i: f64, n: f64, k: f64) -> f64 {
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    let mul = |a: C, b: C| C(a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: C, b: C| {
        let d = b.0 * b.0 + b.1 * b.1;
        C((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let sqrt = |a: C| {
        let r = (a.0 * a.0 + a.1 * a.1).sqrt();
        let re = (0.5 * (r + a.0)).max(0.0).sqrt();
        let im = (0.5 * (r - a.0)).max(0.0).sqrt().copysign(a.1);
        C(re, im)
    };
    let eta = C(n, k);
    let sin2_t = div(C(1.0 - cos_i * cos_i, 0.0), mul(eta, eta));
    let cos_t = sqrt(C(1.0 - sin2_t.0, -sin2_t.1));
    let ec = C(n * cos_i, k * cos_i);
    let r_par = div(C(ec.0 - cos_t.0, ec.1 - cos_t.1), C(ec.0 + cos_t.0, ec.1 + cos_t.1));
    let ect = mul(eta, cos_t);
    let r_perp = div(C(cos_i - ect.0, -ect.1), C(cos_i + ect.0, ect.1));
    0.5 * (r_par.0 * r_par.0 + r_par.1 * r_par.1 + r_perp.0 * r_perp.0 + r_perp.1 * r_perp.1)
}

#[test]
fn normal_incidence_matches_the_closed_form() {
    for (n, k) in [(0.2f32, 3.0f32), (1.5, 0.0), (0.05, 4.0), (2.7, 8.3), (1.0, 1.0), (0.5, 0.0)] {
        let expect = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let got = fresnel_conductor(1.0, n, k);
        assert!((got - expect).abs() < 1e-6, "n={n} k={k}: {got} vs {expect}");
        assert_eq!(fresnel_conductor(-1.0, n, k), got, "two-sided");
    }
}

#[test]
fn zero_extinction_is_the_dielectric_formula() {
    for eta in [1.0001f32, 1.33, 1.5, 2.4, 1.0 / 1.5, 0.5] {
        for i in 0..=900 {
            let c = (i as f32 / 10.0).to_radians().cos();
            let (a, b) = (fresnel_conductor(c, eta, 0.0), fresnel_dielectric(c, eta));
            assert!((a - b).abs() < 2e-5, "η={eta} θ={}: {a} vs {b}", i as f32 / 10.0);
        }
    }
    // Beyond the critical angle: total internal reflection.
    assert_eq!(fresnel_conductor(0.3, 1.0 / 1.5, 0.0), 1.0);
}

#[test]
fn closed_form_agrees_with_complex_arithmetic() {
    let mut worst = 0.0f64;
    let mut cases: Vec<(f32, f32)> = vec![(0.2, 3.0), (1.5, 0.0), (0.05, 4.0), (2.7, 8.3), (1.0, 1e-3)];
    for m in Metal::ALL {
        for l in (360..=830).step_by(10) {
            cases.push(m.eta_k(l as f32));
        }
    }
    for (n, k) in cases {
        for i in 0..=180 {
            let c = (i as f32 / 2.0).to_radians().cos();
            let got = fresnel_conductor(c, n, k) as f64;
            let expect = fresnel_complex(c as f64, n as f64, k as f64);
            worst = worst.max((got - expect).abs());
        }
    }
    println!("worst |closed form − complex arithmetic| = {worst:.2e}");
    assert!(worst < 2e-5, "worst |closed form − complex| = {worst}");
}

#[test]
fn reflectance_is_bounded_and_finite_even_for_extreme_inputs() {
    let mut rng = Pcg32::seed_from_u64(11);
    for _ in 0..100_000 {
        let c = 2.0 * rng.next_f32() - 1.0;
        let n = 10.0 * rng.next_f32();
        let k = 20.0 * rng.next_f32();
        let r = fresnel_conductor(c, n, k);
        assert!((0.0..=1.0).contains(&r), "c={c} n={n} k={k}: {r}");
    }
    for (c, n, k) in [(0.0, 1.0, 0.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.5, 0.0, 0.0), (0.0, 0.2, 3.0)] {
        let r = fresnel_conductor(c, n, k);
        assert!(r.is_finite() && (0.0..=1.0).contains(&r), "c={c} n={n} k={k}: {r}");
    }
    assert_eq!(fresnel_conductor(0.0, 0.2, 3.0), 1.0, "grazing reflection is total");
    assert!(fresnel_conductor(1.0, 1.0, 1e4) > 0.9999);
}

#[test]
fn tables_cover_the_visible_range_and_interpolate() {
    for m in Metal::ALL {
        let t = m.table();
        assert!(t[0][0] <= 360.0 && t[t.len() - 1][0] >= 830.0, "{}", m.name());
        for w in t.windows(2) {
            assert!(w[0][0] < w[1][0] && w[1][0] - w[0][0] <= 75.0);
        }
        for row in t {
            assert_eq!(m.eta_k(row[0]), (row[1], row[2]));
        }
        // Midpoints interpolate; ends clamp.
        let (a, b) = (t[3], t[4]);
        let (n, k) = m.eta_k(0.5 * (a[0] + b[0]));
        assert!((n - 0.5 * (a[1] + b[1])).abs() < 1e-5 && (k - 0.5 * (a[2] + b[2])).abs() < 1e-5);
        assert_eq!(m.eta_k(100.0), (t[0][1], t[0][2]));
        assert_eq!(m.eta_k(2000.0), (t[t.len() - 1][1], t[t.len() - 1][2]));
        assert_eq!(m.eta_k(f32::NAN), (t[0][1], t[0][2]));
    }
    // Spot values from the papers: gold at 1.88 eV (659.5 nm), aluminium at 2 eV.
    assert_eq!(Metal::Gold.eta_k(659.5), (0.14, 3.697));
    assert_eq!(Metal::Aluminium.eta_k(619.93), (1.3660, 7.4052));
}

/// Linear sRGB of the normal-incidence reflectance seen under D65.
fn normal_incidence_srgb(m: Metal) -> [f32; 3] {
    xyz_to_linear_srgb(spectrum_to_xyz(|l| {
        let (n, k) = m.eta_k(l);
        fresnel_conductor(1.0, n, k) * d65_normalised(l)
    }))
}

#[test]
fn gold_is_yellow_copper_is_orange_silver_and_aluminium_are_grey() {
    for m in Metal::ALL {
        println!("{} normal-incidence linear sRGB under D65: {:.4?}", m.name(), normal_incidence_srgb(m));
    }
    let au = normal_incidence_srgb(Metal::Gold);
    assert!(au[0] > au[1] && au[1] > au[2] && au[2] < 0.6 * au[0], "gold {au:?}");
    let cu = normal_incidence_srgb(Metal::Copper);
    assert!(cu[0] > cu[1] && cu[1] > cu[2] && cu[1] < 0.8 * cu[0], "copper {cu:?}");
    for m in [Metal::Silver, Metal::Aluminium] {
        let c = normal_incidence_srgb(m);
        let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
        assert!(lo > 0.8 && hi - lo < 0.1, "{} {c:?}", m.name());
    }
}
