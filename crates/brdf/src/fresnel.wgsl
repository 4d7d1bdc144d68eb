// Fresnel reflectance, mirroring crates/brdf/src/fresnel.rs and
// models/metal.rs::fresnel_conductor line by line.

// brdf::fresnel::fresnel_dielectric: unpolarised (r∥² + r⊥²)/2, 1 under total internal
// reflection; cos_i < 0: light from inside (η inverted).
fn mat_fresnel_dielectric(cos_i_in: f32, eta_in: f32) -> f32 {
    var cos_i = cos_i_in;
    var eta = eta_in;
    if cos_i < 0.0 {
        cos_i = -cos_i;
        eta = 1.0 / eta;
    }
    cos_i = min(cos_i, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_par * r_par + r_perp * r_perp);
}

// brdf::fresnel::fresnel_schlick: R0 + (1 − R0)(1 − cos)^5, with the transmitted angle
// from the dense side (keeps total internal reflection).
fn mat_fresnel_schlick(cos_i: f32, eta: f32) -> f32 {
    let q = (eta - 1.0) / (eta + 1.0);
    let r0 = q * q;
    var cos_abs = cos_i;
    var eta_rel = eta;
    if cos_i < 0.0 {
        cos_abs = -cos_i;
        eta_rel = 1.0 / eta;
    }
    var c = cos_abs;
    if eta_rel < 1.0 {
        let sin2_t = (1.0 - cos_abs * cos_abs) / (eta_rel * eta_rel);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        c = sqrt(1.0 - sin2_t);
    }
    let m = 1.0 - min(c, 1.0);
    return r0 + (1.0 - r0) * ((m * m) * (m * m) * m);
}

// brdf::models::fresnel_conductor: exact unpolarised reflectance of a complex index
// η + iκ (real closed form, a² without cancellation); either side.
fn mat_fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c = min(abs(cos_i), 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let e2 = eta * eta;
    let k2 = k * k;
    let t0 = e2 - k2 - s2;
    let a2b2 = sqrt(t0 * t0 + 4.0 * e2 * k2);
    var a2: f32;
    if t0 >= 0.0 {
        a2 = 0.5 * (a2b2 + t0);
    } else {
        a2 = 2.0 * e2 * k2 / (a2b2 - t0);
    }
    let a = sqrt(max(a2, 0.0));
    let t1 = a2b2 + c2;
    let t2 = 2.0 * a * c;
    if t1 + t2 <= 0.0 {
        return 1.0;
    }
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    var rp = rs;
    if t3 + t4 > 0.0 {
        rp = rs * (t3 - t4) / (t3 + t4);
    }
    return clamp(0.5 * (rs + rp), 0.0, 1.0);
}
