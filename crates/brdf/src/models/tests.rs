//! Tests of `models/mod.rs`.

use super::*;
use crate::fresnel::fresnel_dielectric;
use crate::validation::{Chi2Config, WithPdf, chi2_test, directional_albedo, pdf_integral, reciprocity_error, sidak};
use crate::{Bsdf, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::SampledSpectrum;
use std::f32::consts::FRAC_1_PI;

fn incidences() -> [Vec3; 4] {
    [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.99875, 0.05), -Vec3::Z]
}

#[test]
fn lambert_sampling_matches_its_pdf() {
    let lambert = Lambert { reflectance: SampledSpectrum([0.8]) };
    let alpha = sidak(0.01, incidences().len());
    for (k, wo) in incidences().into_iter().enumerate() {
        let r = chi2_test(&lambert, wo.normalize(), &Chi2Config::default(), k as u64);
        assert!(r.p_value > alpha && r.inconsistent == 0, "wo={wo}: {r:?}");
    }
}

#[test]
fn a_wrong_pdf_fails_the_chi_square_test() {
    // Lambert with a deliberately wrong pdf (uniform instead of cosine): must fail.
    let broken = WithPdf {
        inner: Lambert { reflectance: SampledSpectrum([0.8]) },
        pdf: |_: &Lambert<1>, wo: Vec3, wi: Vec3| if wo.z * wi.z > 0.0 { 0.5 * FRAC_1_PI } else { 0.0 },
    };
    let r = chi2_test(&broken, Vec3::Z, &Chi2Config::default(), 7);
    assert!(r.p_value < 1e-6, "the broken pdf passed: {r:?}");
}

#[test]
fn lambert_pdf_integrates_to_one_albedo_is_r_and_it_is_reciprocal() {
    let lambert = Lambert { reflectance: SampledSpectrum([0.8]) };
    let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
    assert!((pdf_integral(&lambert, wo, 400) - 1.0).abs() < 1e-3);
    let (albedo, se) = directional_albedo(&lambert, wo, 100_000, 1);
    assert!((albedo - 0.8).abs() < 1e-6 + 4.0 * se, "{albedo} ± {se}");
    assert_eq!(reciprocity_error(&lambert, 1000, 2), 0.0);
}

#[test]
fn dielectric_conserves_energy_and_reaches_both_sides() {
    let glass = Dielectric { eta: 1.5, dispersive: false, fresnel: FresnelModel::Exact, tint: SampledSpectrum([1.0]) };
    for &z in &[1.0f32, 0.7, 0.2, 0.05, -0.05, -0.5, -0.9, -1.0] {
        let wo = Vec3::new((1.0 - z * z).sqrt(), 0.0, z);
        let (mut sum_weight, mut reflected, mut n) = (0.0f64, 0.0f64, 0);
        for i in 0..1000 {
            let s = glass.sample(wo, (i as f32 + 0.5) / 1000.0, Vec2::ZERO).unwrap();
            // Throughput f·|cos|/pdf, undoing the 1/η² radiance scaling, is 1.
            let etap2 = if s.flags.contains(ScatterFlags::TRANSMISSION) {
                let e = if wo.z > 0.0 { 1.5f32 } else { 1.0 / 1.5 };
                e * e
            } else {
                1.0
            };
            sum_weight += (s.f[0] * s.wi.z.abs() / s.pdf * etap2) as f64;
            if s.flags.contains(ScatterFlags::REFLECTION) {
                reflected += 1.0;
                assert!(s.wi.z * wo.z > 0.0);
            } else {
                assert!(s.wi.z * wo.z < 0.0);
            }
            n += 1;
        }
        assert!((sum_weight / n as f64 - 1.0).abs() < 1e-4, "z={z}");
        let expect = fresnel_dielectric(z, 1.5) as f64;
        let got = reflected / n as f64;
        assert!((got - expect).abs() < 2e-3, "z={z}: {got} vs {expect}");
    }
}

#[test]
fn mirror_reflects_about_the_normal() {
    let m = Mirror { reflectance: SampledSpectrum([0.9]) };
    let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
    let s = m.sample(wo, 0.5, Vec2::ZERO).unwrap();
    assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
    assert!((s.f[0] * s.wi.z / s.pdf - 0.9).abs() < 1e-6);
    assert_eq!(m.pdf(wo, s.wi), 0.0);
    let (albedo, _) = directional_albedo(&m, wo, 100, 3);
    assert!((albedo - 0.9).abs() < 1e-5);
}

#[test]
fn every_model_is_registered_with_valid_defaults() {
    let mut names = std::collections::HashSet::new();
    for (k, &model) in ModelId::ALL.iter().enumerate() {
        let def = model.def();
        assert!(names.insert(def.name), "two models called {}", def.name);
        assert_eq!(model.index() as usize, k);
        assert_eq!(ModelId::by_name(def.name), Some(model));
        assert_eq!(ModelId::by_name(&def.name.to_uppercase()), Some(model));
        assert!(def.name.chars().all(|c| c.is_ascii_lowercase()), "{}: not a WGSL-friendly name", def.name);
        let defaults = model.defaults();
        assert_eq!(defaults.model(), model);
        assert_eq!(model.from_resolved(&defaults.to_resolved()), defaults);
        for p in def.params {
            assert!(p.min <= p.default && p.default <= p.max, "{}.{}", def.name, p.name);
            assert!(!p.doc.is_empty());
        }
        assert!(model.wgsl().source.contains(&format!("fn {}_sample(", def.name)), "{}", def.name);
    }
    assert!(ModelId::by_name("nonexistent").is_none());
}
