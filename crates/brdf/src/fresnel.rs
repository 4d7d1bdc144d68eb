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
mod tests;
