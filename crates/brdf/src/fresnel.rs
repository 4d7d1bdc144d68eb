//! Fresnel reflectance at a smooth interface.
//!
//! The seed thesis's R∥ (eq. 5.14) and the lecture slides' ρ⊥ swap numerator and
//! denominator terms; these are the standard forms (Born & Wolf §1.5; pbrt-v4 eq. 9.4–9.5),
//! pinned by the tests below at normal incidence (4 % for n = 1.5), at Brewster's
//! angle (R∥ = 0) and beyond the critical angle (total internal reflection).

use glam::Vec3;

/// The two polarised amplitude reflection coefficients (r∥, r⊥) for light arriving at
/// `cos_i` (> 0: from outside) on an interface of relative index η = n_inside / n_outside;
/// `None` under total internal reflection.
#[inline]
pub fn dielectric_amplitudes(cos_i: f32, eta: f32) -> Option<(f32, f32)> {
    let (cos_i, eta) = if cos_i < 0.0 { (-cos_i, 1.0 / eta) } else { (cos_i, eta) };
    let cos_i = cos_i.min(1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    Some((r_par, r_perp))
}

/// Unpolarised Fresnel reflectance (r∥² + r⊥²)/2 of a dielectric interface; 1 under total
/// internal reflection. `cos_i < 0` means the light arrives from inside.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    match dielectric_amplitudes(cos_i, eta) {
        Some((p, s)) => 0.5 * (p * p + s * s),
        None => 1.0,
    }
}

/// Schlick's approximation R₀ + (1 − R₀)(1 − cos)⁵ (Schlick 1994, eq. 24). From the dense
/// side it uses the transmitted angle, so that total internal reflection is kept.
#[inline]
pub fn fresnel_schlick(cos_i: f32, eta: f32) -> f32 {
    let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let (cos, eta_rel) = if cos_i < 0.0 { (-cos_i, 1.0 / eta) } else { (cos_i, eta) };
    let c = if eta_rel < 1.0 {
        let sin2_t = (1.0 - cos * cos) / (eta_rel * eta_rel);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos
    };
    r0 + (1.0 - r0) * (1.0 - c.min(1.0)).powi(5)
}

/// Refraction of `wo` through the local interface z = 0 by Snell's law, where η is
/// n_inside / n_outside and +z points outside. `None` under total internal reflection.
#[inline]
pub fn refract_local(wo: Vec3, eta: f32) -> Option<Vec3> {
    let (n, etap, cos_i) = if wo.z >= 0.0 { (1.0, eta, wo.z) } else { (-1.0, 1.0 / eta, -wo.z) };
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (etap * etap);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wo / etap + Vec3::new(0.0, 0.0, n * (cos_i / etap - cos_t)))
}

#[cfg(test)]
mod tests {
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
}
