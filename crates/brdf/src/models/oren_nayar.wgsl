// Oren–Nayar's qualitative model (crates/brdf/src/models/oren_nayar.rs):
// f = R/π (A + B max(0, cos Δφ) sin α tan β), evaluated without trigonometry.

// (A, B) from σ.
fn orennayar_ab(sigma: f32) -> vec2f {
    let s2 = sigma * sigma;
    return vec2f(1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09));
}

fn orennayar_factor(ab: vec2f, wo: vec3f, wi: vec3f) -> f32 {
    let m = max(abs(wo.z), abs(wi.z));
    let c = max(wo.x * wi.x + wo.y * wi.y, 0.0);
    if m > 0.0 && c > 0.0 {
        return ab.x + ab.y * (c / m);
    }
    return ab.x;
}

fn orennayar_eval(p: OrennayarParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    if wo.z * wi.z > 0.0 {
        return spectrum_at(p.reflectance, lambda) * MAT_FRAC_1_PI * orennayar_factor(orennayar_ab(p.sigma), wo, wi);
    }
    return vec4f(0.0);
}

fn orennayar_pdf(p: OrennayarParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    return mat_cosine_two_sided_pdf(wo, wi);
}

fn orennayar_sample(p: OrennayarParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    let s = mat_cosine_two_sided(wo, u);
    if s.w <= 0.0 {
        return mat_no_sample();
    }
    let f = spectrum_at(p.reflectance, lambda) * MAT_FRAC_1_PI * orennayar_factor(orennayar_ab(p.sigma), wo, s.xyz);
    return BsdfSample(s.xyz, f, s.w, SCATTER_REFLECTION | SCATTER_DIFFUSE);
}
