// Lambert (crates/brdf/src/models/lambert.rs): f = R/π on ωo's side, cosine sampling.

fn lambert_eval(p: LambertParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    if wo.z * wi.z > 0.0 {
        return spectrum_at(p.reflectance, lambda) * MAT_FRAC_1_PI;
    }
    return vec4f(0.0);
}

fn lambert_pdf(p: LambertParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    return mat_cosine_two_sided_pdf(wo, wi);
}

fn lambert_sample(p: LambertParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    let s = mat_cosine_two_sided(wo, u);
    if s.w <= 0.0 {
        return mat_no_sample();
    }
    return BsdfSample(s.xyz, spectrum_at(p.reflectance, lambda) * MAT_FRAC_1_PI, s.w,
        SCATTER_REFLECTION | SCATTER_DIFFUSE);
}
