//! Tests of `fresnel.rs`.

use super::*;

#[test]
fn four_percent_at_normal_incidence_for_glass() {
    assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
    assert!((fresnel_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
    assert!((fresnel_schlick(1.0, 1.5) - 0.04).abs() < 1e-6);
}

#[test]
fn parallel_reflection_vanishes_at_brewsters_angle() {
    for eta in [1.33f32, 1.5, 2.4] {
        let theta_b = eta.atan();
        let (r_par, r_perp) = dielectric_amplitudes(theta_b.cos(), eta).unwrap();
        assert!(r_par.abs() < 1e-6, "η={eta}: r∥={r_par}");
        assert!(r_perp.abs() > 0.1);
        // Slightly off Brewster, r∥ is not zero: the test can tell.
        let (off, _) = dielectric_amplitudes((theta_b + 0.1).cos(), eta).unwrap();
        assert!(off.abs() > 1e-2);
    }
}

#[test]
fn total_internal_reflection_beyond_the_critical_angle() {
    let eta = 1.5f32;
    let critical = (1.0 / eta).asin();
    assert_eq!(fresnel_dielectric(-(critical + 0.01).cos(), eta), 1.0);
    assert!(fresnel_dielectric(-(critical - 0.01).cos(), eta) < 1.0);
    assert_eq!(fresnel_schlick(-(critical + 0.01).cos(), eta), 1.0);
    let wo = Vec3::new((critical + 0.01).sin(), 0.0, -(critical + 0.01).cos());
    assert!(refract_local(wo, eta).is_none());
}

#[test]
fn reflectance_is_symmetric_in_the_direction_of_travel() {
    // Stokes relations: R is the same for the refracted pair of angles.
    let eta = 1.5f32;
    for i in 1..89 {
        let ti = (i as f32).to_radians();
        let tt = (ti.sin() / eta).asin();
        let a = fresnel_dielectric(ti.cos(), eta);
        let b = fresnel_dielectric(-tt.cos(), eta);
        assert!((a - b).abs() < 1e-4, "θ={i}: {a} vs {b}");
    }
}

#[test]
fn snell_holds_and_refraction_is_reversible() {
    let eta = 1.5f32;
    for i in 1..89 {
        let t = (i as f32).to_radians();
        let wo = Vec3::new(t.sin(), 0.0, t.cos());
        let wt = refract_local(wo, eta).unwrap();
        assert!((wt.length() - 1.0).abs() < 1e-5);
        assert!(wt.z < 0.0);
        let sin_t = (wt.x * wt.x + wt.y * wt.y).sqrt();
        assert!((t.sin() - eta * sin_t).abs() < 1e-5, "Snell at {i}°");
        // Light retracing the path from inside leaves along the original direction.
        let back = refract_local(wt, eta).unwrap();
        assert!((back - wo).length() < 1e-4, "{i}°: {back} vs {wo}");
    }
}

/// The thesis's printed R∥ (eq. 5.14): numerator and denominator swapped.
fn thesis_r_parallel(cos_i: f32, eta: f32) -> f32 {
    let cos_t = (1.0 - (1.0 - cos_i * cos_i) / (eta * eta)).sqrt();
    ((eta * cos_i + cos_t) / (eta * cos_i - cos_t)).powi(2)
}

/// The lecture slides' ρ⊥: the denominator pairs the indices the wrong way round.
fn slides_rho_perp(cos_i: f32, eta: f32) -> f32 {
    let cos_t = (1.0 - (1.0 - cos_i * cos_i) / (eta * eta)).sqrt();
    (cos_i - eta * cos_t) / (eta * cos_i + cos_t)
}

#[test]
fn the_seeds_fresnel_formulas_fail_the_pins() {
    let eta = 1.5f32;
    // Thesis R∥: 25 instead of 4 % at normal incidence, and a pole instead of a zero
    // at Brewster's angle.
    assert!((thesis_r_parallel(1.0, eta) - 0.04).abs() > 1.0);
    let brewster = eta.atan().cos();
    assert!(thesis_r_parallel(brewster, eta) > 1e3 || !thesis_r_parallel(brewster, eta).is_finite());
    let (ours, _) = dielectric_amplitudes(brewster, eta).unwrap();
    assert!(ours.abs() < 1e-6);
    // Slides ρ⊥: right at normal incidence (their worked 4 % example), wrong beyond.
    let (_, perp) = dielectric_amplitudes(1.0, eta).unwrap();
    assert!((slides_rho_perp(1.0, eta) - perp).abs() < 1e-6);
    let c60 = 60f32.to_radians().cos();
    let (_, perp60) = dielectric_amplitudes(c60, eta).unwrap();
    // Measured: −0.463 against the correct −0.420.
    assert!((slides_rho_perp(c60, eta) - perp60).abs() > 0.03, "{} vs {perp60}", slides_rho_perp(c60, eta));
}

#[test]
fn schlick_error_against_exact_is_bounded() {
    // Max |Schlick − exact| over incidence angles from outside for n = 1.5:
    // measured 0.0357 (at 85°), i.e. Schlick is within 4 % absolute everywhere.
    let mut worst = 0.0f32;
    for i in 0..=900 {
        let c = (i as f32 / 10.0).to_radians().cos();
        worst = worst.max((fresnel_schlick(c, 1.5) - fresnel_dielectric(c, 1.5)).abs());
    }
    assert!(worst < 0.04 && worst > 0.03, "worst {worst}");
}
