//! Tests of `models/ashikhmin.rs`.

use super::*;
use crate::validation::{
    Chi2Case, Chi2Config, Chi2Grid, WithPdf, Zoom, assert_finite_everywhere, chi2_test, direction as dir,
    directional_albedo, pdf_integral, reciprocity_error,
};
use rng::Pcg32;

fn sa(nu: f32, nv: f32, rs: f32, rd: f32) -> Ashikhmin<1> {
    Ashikhmin::new(nu, nv, SampledSpectrum([rs]), SampledSpectrum([rd]))
}

const D45: f32 = std::f32::consts::FRAC_1_SQRT_2;
const GRAZING: f32 = 0.05;

/// A zoom for the specular lobe at ωo in the xz plane (cos θo = `z`): ωi spreads about
/// 2/√(n_u + 1) in the plane of incidence and 2 cos θo/√(n_v + 1) across it, scaled to
/// about 0.3 in gnomonic units.
fn zoom_xz(nu: f32, nv: f32, z: f32, q: usize) -> Chi2Grid {
    let (su, sv) = (2.0 / ((nu + 1.0) as f64).sqrt(), 2.0 * z.abs() as f64 / ((nv + 1.0) as f64).sqrt());
    Chi2Grid::Zoom(0.3 / su, 0.3 / sv, q)
}

/// Every chi-square case of this file (the Šidák correction counts them all).
fn cases() -> Vec<Chi2Case<Ashikhmin<1>>> {
    let mut v = Vec::new();
    let wos =
        [("n", dir(1.0, 0.0)), ("45°", dir(D45, 0.0)), ("grazing", dir(GRAZING, 0.0)), ("below 45°", -dir(D45, 0.0))];
    // Broad lobes, with the default diffuse + specular mix.
    for n in [1.0f32, 10.0] {
        for (wn, wo) in wos {
            v.push(Chi2Case {
                name: format!("n={n} Rs=0.05 Rd=0.5 wo={wn}"),
                bsdf: sa(n, n, 0.05, 0.5),
                wo,
                grid: Chi2Grid::Default,
            });
        }
    }
    for (wn, wo) in [("45°", dir(D45, 20.0)), ("grazing", dir(GRAZING, 0.0))] {
        v.push(Chi2Case {
            name: format!("n=100 Rs=0.05 Rd=0.5 wo={wn}"),
            bsdf: sa(100.0, 100.0, 0.05, 0.5),
            wo,
            grid: Chi2Grid::Default,
        });
    }
    // The specular lobe alone (R_d = 0): n = 1000 on a 1° grid (a finer one at grazing
    // incidence, where it is 0.4° across the plane of incidence and meets the horizon),
    // n = 10⁵ zoomed.
    for (wn, wo) in wos {
        let grid = if wo.z.abs() < 0.1 { Chi2Grid::Finer } else { Chi2Grid::Fine(6) };
        v.push(Chi2Case { name: format!("n=1000 specular wo={wn}"), bsdf: sa(1000.0, 1000.0, 0.05, 0.0), wo, grid });
    }
    for (wn, wo) in wos {
        v.push(Chi2Case {
            name: format!("n=1e5 specular wo={wn} (zoom)"),
            bsdf: sa(1e5, 1e5, 0.05, 0.0),
            wo,
            grid: zoom_xz(1e5, 1e5, wo.z, 6),
        });
    }
    // Anisotropic: 10 × 1000 on the 1° grid; 10⁴ × 10 zoomed across u at normal incidence
    // and on the 1° grid at 45°, where its wide arc meets the horizon (a zoom would
    // squeeze that edge into a few cells).
    for (wn, wo) in [("n", dir(1.0, 0.0)), ("45° in xz", dir(D45, 0.0)), ("45° in yz", dir(D45, 90.0))] {
        v.push(Chi2Case {
            name: format!("nu=10 nv=1000 wo={wn}"),
            bsdf: sa(10.0, 1000.0, 0.05, 0.5),
            wo,
            grid: Chi2Grid::Fine(6),
        });
    }
    for (wn, wo) in [("n (zoom)", dir(1.0, 0.0)), ("45° in xz", dir(D45, 0.0)), ("below n (zoom)", -Vec3::Z)] {
        let grid = if wn.ends_with("(zoom)") {
            Chi2Grid::Zoom(0.3 * 101.0 / 2.0, 0.3 * 3.3 / 2.0, 6)
        } else {
            Chi2Grid::Fine(6)
        };
        v.push(Chi2Case { name: format!("nu=1e4 nv=10 specular wo={wn}"), bsdf: sa(1e4, 10.0, 0.05, 0.0), wo, grid });
    }
    // Extremes of the parameters: n = 0 (a uniform half-vector density), R_s = 1.
    v.push(Chi2Case {
        name: "n=0 Rs=0.05 Rd=0.5 wo=45°".into(),
        bsdf: sa(0.0, 0.0, 0.05, 0.5),
        wo: dir(D45, 0.0),
        grid: Chi2Grid::Default,
    });
    v.push(Chi2Case {
        name: "nu=1e6 nv=0 Rs=1 wo=n (zoom)".into(),
        bsdf: sa(1e6, 0.0, 1.0, 1.0),
        wo: Vec3::Z,
        grid: Chi2Grid::Zoom(150.0, 0.15, 6),
    });
    v
}

crate::chi2_tests!("ashikhmin", cases(), seed 2000, parts [sampling_matches_pdf_part_1, sampling_matches_pdf_part_2, sampling_matches_pdf_part_3]);

/// (n_u, n_v) pairs for the albedo measurements: isotropic from 0 to 10⁵, and anisotropic.
const EXPONENTS: [(f32, f32); 8] =
    [(0.0, 0.0), (1.0, 1.0), (10.0, 10.0), (100.0, 100.0), (1e4, 1e4), (1e5, 1e5), (10.0, 1000.0), (1e4, 10.0)];

/// Prints the directional albedo over exponents, reflectances and cos θo, for reports:
/// `cargo test -p brdf --lib ashikhmin_albedo_table -- --ignored --nocapture`.
#[test]
#[ignore]
fn ashikhmin_albedo_table() {
    for (rs, rd) in [(1.0f32, 1.0f32), (0.0, 1.0), (0.05, 1.0), (0.05, 0.5), (1.0, 0.0), (0.5, 1.0)] {
        for (nu, nv) in EXPONENTS {
            let b = sa(nu, nv, rs, rd);
            let row: Vec<String> = [1.0f32, 0.7, 0.4, 0.2, 0.1, 0.05, 0.01]
                .iter()
                .map(|&z| {
                    let (a, se) = directional_albedo(&b, dir(z, 30.0), 200_000, 5);
                    format!("{a:6.4}±{se:.4}")
                })
                .collect();
            eprintln!("Rs={rs:<4} Rd={rd:<4} nu={nu:<6} nv={nv:<6} | {}", row.join(" "));
        }
    }
}

/// The specular lobe's pdf without the reflection's Jacobian 1/(4 ωo·h): must fail.
fn pdf_without_jacobian(b: &Ashikhmin<1>, wo: Vec3, wi: Vec3) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }

    let ps = b.specular_probability(wo.z);
    let h = (wo + wi).normalize();
    ps * b.norm * (0.5 * FRAC_1_PI) * phong_lobe(b.nu, b.nv, h) + (1.0 - ps) * cosine_hemisphere_pdf(wi.z)
}

#[test]
fn a_pdf_without_the_half_vector_jacobian_fails() {
    for (k, (b, wo)) in
        [(sa(100.0, 100.0, 0.05, 0.5), dir(0.8, 20.0)), (sa(10.0, 1000.0, 0.05, 0.0), Vec3::Z)].into_iter().enumerate()
    {
        let r = chi2_test(&WithPdf { inner: b, pdf: pdf_without_jacobian }, wo, &Chi2Config::default(), 31 + k as u64);
        eprintln!("chi2 ashikhmin broken (no Jacobian) {k} | p = {:.3e}", r.p_value);
        assert!(r.p_value < 1e-6, "the broken pdf passed: {r:?}");
    }
}

/// The fraction of `sample` calls that return a direction.
fn accepted(b: &Ashikhmin<1>, wo: Vec3, n: usize, seed: u64) -> f64 {
    let mut rng = Pcg32::seed_from_u64(seed);
    let k =
        (0..n).filter(|_| b.sample(wo, rng.next_f32(), Vec2::new(rng.next_f32(), rng.next_f32())).is_some()).count();
    k as f64 / n as f64
}

#[test]
fn pdf_integrates_to_the_probability_of_a_sample() {
    let wos = [dir(1.0, 0.0), dir(D45, 30.0), dir(GRAZING, 0.0), -dir(D45, 0.0)];
    let bsdfs = [
        sa(0.0, 0.0, 0.05, 0.5),
        sa(1.0, 1.0, 0.05, 0.5),
        sa(10.0, 10.0, 0.5, 0.5),
        sa(100.0, 100.0, 0.05, 0.0),
        sa(10.0, 1000.0, 0.05, 0.5),
        sa(1000.0, 1000.0, 0.05, 0.0),
    ];
    for (i, b) in bsdfs.iter().enumerate() {
        for (j, &wo) in wos.iter().enumerate() {
            // The n = 1000 lobes are too narrow for a 1000² grid: zoomed (the same
            // integral) away from the horizon, a 4000² grid at grazing incidence, where
            // they meet the horizon and are 0.2° across the plane of incidence.
            let integral = match (i >= 4, wo.z.abs() < 0.1) {
                (false, _) => pdf_integral(b, wo, 1000),
                (true, true) => pdf_integral(b, wo, 4000),
                (true, false) => {
                    let Chi2Grid::Zoom(a_s, a_t, _) = zoom_xz(b.nu, b.nv, wo.z, 6) else { unreachable!() };
                    pdf_integral(&Zoom::mirror(*b, wo, a_s, a_t), wo, 1000)
                }
            };
            let expect = accepted(b, wo, 500_000, (10 * i + j) as u64);
            assert!(integral <= 1.0 + 2e-3, "{i} {wo}: {integral}");
            assert!((integral - expect).abs() < 3e-3, "{i} {wo}: ∫pdf = {integral}, accepted {expect}");
        }
    }
    // Far too narrow for the grid: integrate the zoomed pdf (the same integral).
    for (j, &wo) in wos.iter().enumerate() {
        let b = sa(1e5, 1e5, 0.05, 0.0);
        let Chi2Grid::Zoom(a_s, a_t, _) = zoom_xz(1e5, 1e5, wo.z, 6) else { unreachable!() };
        let integral = pdf_integral(&Zoom::mirror(b, wo, a_s, a_t), wo, 1000);
        let expect = accepted(&b, wo, 500_000, 90 + j as u64);
        assert!((integral - expect).abs() < 3e-3, "n=1e5 {wo}: ∫pdf = {integral}, accepted {expect}");
    }
    // Nothing is lost at normal incidence with a narrow lobe.
    let zoomed = Zoom::mirror(bsdfs[5], Vec3::Z, 5.0, 5.0);
    assert!((pdf_integral(&zoomed, Vec3::Z, 1000) - 1.0).abs() < 2e-3);
}

#[test]
fn energy_is_conserved() {
    let mut seed = 0;
    for (rs, rd) in [(1.0f32, 1.0f32), (0.0, 1.0), (0.05, 1.0), (0.5, 1.0)] {
        for (nu, nv) in EXPONENTS {
            for z in [1.0f32, 0.7, 0.4, 0.1, 0.01] {
                seed += 1;
                let (albedo, se) = directional_albedo(&sa(nu, nv, rs, rd), dir(z, 30.0), 20_000, seed);
                assert!(albedo <= 1.0 + 4.0 * se + 1e-5, "Rs={rs} Rd={rd} n=({nu}, {nv}) z={z}: {albedo} ± {se}");
            }
        }
    }
    // The bound is reached: with F ≡ 1 and a narrow lobe at normal incidence nothing is
    // lost, and the diffuse term alone gives 1 − (1 − v₂/2)⁵ ≈ 0.969 at v₂ = 1.
    let (albedo, se) = directional_albedo(&sa(1e5, 1e5, 1.0, 0.0), Vec3::Z, 100_000, 1);
    assert!(albedo > 0.999 && albedo <= 1.0 + 4.0 * se, "{albedo} ± {se}");
    // But broad lobes lose most of it: ρ_s n·k₁ = p(ωi) F n·k₁/max(n·k₁, n·k₂), and the
    // half-vector density sends much of p below the horizon (n = 0: 86 % lost).
    let (albedo, se) = directional_albedo(&sa(0.0, 0.0, 1.0, 0.0), Vec3::Z, 100_000, 2);
    assert!((albedo - 0.1385).abs() < 4.0 * se + 2e-3, "{albedo} ± {se}");
}

#[test]
fn reciprocal() {
    for (k, b) in [
        sa(100.0, 100.0, 0.05, 0.5),
        sa(10.0, 1000.0, 0.5, 0.2),
        sa(1e4, 10.0, 0.0, 1.0),
        sa(0.0, 0.0, 1.0, 0.0),
        sa(3.0, 30.0, 0.9, 0.9),
    ]
    .iter()
    .enumerate()
    {
        let e = reciprocity_error(b, 20_000, k as u64);
        assert!(e < 1e-4, "case {k}: {e}");
    }
}

#[test]
fn no_nan_or_inf_anywhere() {
    let mut bsdfs = Vec::new();
    for nu in [0.0f32, 1.0, 1e3, MAX_EXPONENT] {
        for nv in [0.0f32, 10.0, MAX_EXPONENT] {
            for (rs, rd) in [(0.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.05, 0.5)] {
                bsdfs.push(sa(nu, nv, rs, rd));
            }
        }
    }
    let mut rng = Pcg32::seed_from_u64(99);
    let per = 1_000_000 / bsdfs.len() + 1;
    for b in &bsdfs {
        assert_finite_everywhere(b, per, &mut rng, &format!("{b:?}"));
    }
}

#[test]
fn half_vector_sampling_follows_the_paper() {
    // With n_u = n_v the azimuth is uniform and cos θ_h = (1 − ξ₂)^{1/(n + 1)}.
    let h = sample_half(10.0, 10.0, 1.0, Vec2::new(0.1, 0.5));
    assert!((h.z - 0.5f32.powf(1.0 / 11.0)).abs() < 1e-6);
    assert!((h.y.atan2(h.x) - 0.4 * FRAC_PI_2).abs() < 1e-5);
    // p_h integrates to 1 over the hemisphere of half vectors (the paper's normalisation).
    for (nu, nv) in [(0.0f32, 0.0f32), (10.0, 1000.0), (100.0, 100.0)] {
        let norm = ((nu + 1.0) * (nv + 1.0)).sqrt() as f64 * 0.5 / std::f64::consts::PI;
        let n = 2000;
        let mut sum = 0.0;
        for i in 0..n {
            let z = (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            for j in 0..n {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n as f64;
                let h = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                sum += norm * phong_lobe(nu, nv, h) as f64;
            }
        }
        let integral = sum * std::f64::consts::TAU / (n * n) as f64;
        assert!((integral - 1.0).abs() < 2e-3, "({nu}, {nv}): {integral}");
    }
    // Huge exponents near h = n: no 0/0, and the value matches t^e in f64.
    let h = Vec3::new(1e-3, 2e-3, 1.0).normalize();
    let (hx2, hy2) = ((h.x as f64).powi(2), (h.y as f64).powi(2));
    let (t, e) = ((1.0 - hx2 - hy2).sqrt(), (1e5 * hx2 + 1e6 * hy2) / (hx2 + hy2));
    assert!((phong_lobe(1e5, 1e6, h) as f64 - t.powf(e)).abs() < 1e-4 * t.powf(e));
    assert_eq!(phong_lobe(1e6, 1e6, Vec3::Z), 1.0);
}

#[test]
fn parameters_resolve() {
    use crate::params::{ParamSet, ParamValue};
    let wl = SampledWavelengths::<1>::fixed_bins(550.0, 10.0);
    let b = AshikhminParams::default().bsdf(&wl);
    assert_eq!((b.nu, b.nv), (100.0, 100.0));
    assert!((b.rs[0] - 0.05).abs() < 0.01 && (b.rd[0] - 0.5).abs() < 0.05, "{b:?}");
    let given =
        AshikhminParams::resolve("m", &[("nu", ParamValue::Scalar(1e6)), ("nv", ParamValue::Scalar(0.0))]).unwrap();
    let b = given.bsdf(&wl);
    assert_eq!((b.nu, b.nv), (1e6, 0.0));
    assert!(AshikhminParams::resolve("m", &[("nu", ParamValue::Scalar(2e6))]).is_err());
    for key in ["nu", "nv", "Rs", "Rd"] {
        assert!(AshikhminParams::DEF.param_by_mtl_key(key).is_some(), "{key}");
    }
}
