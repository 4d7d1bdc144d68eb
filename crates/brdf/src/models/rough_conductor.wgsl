// The GGX rough conductor (crates/brdf/src/models/microfacet.rs, RoughConductor):
// height-correlated Smith masking, conductor Fresnel, visible-normal sampling; two-sided.

// RoughConductor::configuration: (ωo, ωi, h) moved to the upper hemisphere; `ok` false
// if not a reflection.
struct MatRcConfig {
    wo: vec3f,
    wi: vec3f,
    h: vec3f,
    ok: bool,
}

fn roughconductor_configuration(wo_in: vec3f, wi_in: vec3f) -> MatRcConfig {
    var c = MatRcConfig(vec3f(0.0), vec3f(0.0), vec3f(0.0), false);
    if wo_in.z * wi_in.z <= 0.0 || !mat_finite3(wo_in) || !mat_finite3(wi_in) {
        return c;
    }
    var wo = wo_in;
    var wi = wi_in;
    if wo.z < 0.0 {
        wo = mat_flip_z(wo);
        wi = mat_flip_z(wi);
    }
    let h = mat_normalize_or(wo + wi, vec3f(0.0));
    if h.z <= 0.0 {
        return c;
    }
    c = MatRcConfig(wo, wi, h, true);
    return c;
}

fn roughconductor_eval(p: RoughconductorParams, wo_in: vec3f, wi_in: vec3f, lambda: vec4f) -> vec4f {
    let c = roughconductor_configuration(wo_in, wi_in);
    if !c.ok {
        return vec4f(0.0);
    }
    let a = mat_ggx_alphas(p.alpha, p.alpha_y);
    // D G2 / (4 z_o z_i) with G2 = 2 z_o z_i / (s_o z_i + s_i z_o).
    let den = 2.0 * (mat_ggx_s(a, c.wo) * c.wi.z + mat_ggx_s(a, c.wi) * c.wo.z);
    if !(den > 0.0) {
        return vec4f(0.0);
    }
    let ek = mat_metal_eta_k(p.metal, p.eta, p.k, lambda);
    return mat_conductor_fresnel4(dot(c.wo, c.h), ek, spectrum_at(p.tint, lambda)) * (mat_ggx_d(a, c.h) / den);
}

fn roughconductor_pdf(p: RoughconductorParams, wo_in: vec3f, wi_in: vec3f, lambda: vec4f) -> f32 {
    let c = roughconductor_configuration(wo_in, wi_in);
    if !c.ok {
        return 0.0;
    }
    return mat_ggx_reflection_pdf(mat_ggx_alphas(p.alpha, p.alpha_y), c.wo, c.h);
}

fn roughconductor_sample(p: RoughconductorParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 || !mat_finite3(wo) || !(dot(wo, wo) > 0.0) {
        return mat_no_sample();
    }
    var up = wo;
    if wo.z < 0.0 {
        up = mat_flip_z(wo);
    }
    let h = mat_ggx_sample_visible(mat_ggx_alphas(p.alpha, p.alpha_y), up, u);
    var wi = mat_reflect(up, h);
    if wi.z <= 0.0 {
        return mat_no_sample();
    }
    if wo.z < 0.0 {
        wi = mat_flip_z(wi);
    }
    let pdf = roughconductor_pdf(p, wo, wi, lambda);
    if !(pdf > 0.0) {
        return mat_no_sample();
    }
    return BsdfSample(wi, roughconductor_eval(p, wo, wi, lambda), pdf, SCATTER_REFLECTION | SCATTER_GLOSSY);
}
