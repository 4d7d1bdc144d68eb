// The GGX rough dielectric (crates/brdf/src/models/microfacet.rs, RoughDielectric):
// Walter et al. 2007 reflection and refraction, separable Smith masking, exact Fresnel,
// visible-normal sampling; transmitted radiance scaled by 1/η'².

// RoughDielectric::evaluate: (f without tint, pdf); ωo below the surface is mirrored
// with η inverted.
fn roughdielectric_evaluate(a: vec2f, eta_in: f32, wo_in: vec3f, wi_in: vec3f) -> vec2f {
    if wo_in.z == 0.0 || wi_in.z == 0.0 || !(eta_in > 0.0) {
        return vec2f(0.0);
    }
    var wo = wo_in;
    var wi = wi_in;
    var eta = eta_in;
    if wo.z < 0.0 {
        wo = mat_flip_z(wo);
        wi = mat_flip_z(wi);
        eta = 1.0 / eta;
    }
    let zo = wo.z;
    let zi = abs(wi.z);
    let inv_o = 1.0 / (zo + mat_ggx_s(a, wo));
    // Separable G2 with both cosines cancelled: G2/(z_o z_i) = 4/((z_o + s_o)(z_i + s_i)).
    let g_over_cos = 4.0 * inv_o / (zi + mat_ggx_s(a, wi));
    if wi.z > 0.0 {
        let h = mat_normalize_or(wo + wi, vec3f(0.0));
        if h.z <= 0.0 {
            return vec2f(0.0);
        }
        let r = mat_fresnel_dielectric(dot(wo, h), eta);
        let d = mat_ggx_d(a, h);
        return vec2f(0.25 * d * g_over_cos * r, 0.5 * r * d * inv_o);
    }
    var h = mat_normalize_or(wo + eta * wi, vec3f(0.0));
    if h.z < 0.0 {
        h = -h;
    }
    let oh = dot(wo, h);
    let ih = dot(wi, h);
    if h.z <= 0.0 || oh <= 0.0 || ih >= 0.0 {
        return vec2f(0.0);
    }
    let t = 1.0 - mat_fresnel_dielectric(oh, eta);
    let den = ih + oh / eta;
    let den2 = den * den;
    if !(den2 > 0.0) {
        return vec2f(0.0);
    }
    let d = mat_ggx_d(a, h);
    let f = d * g_over_cos * t * (-ih * oh) / (den2 * eta * eta);
    let pdf = t * 2.0 * oh * d * inv_o * -ih / den2;
    return vec2f(f, pdf);
}

fn roughdielectric_eval(p: RoughdielectricParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    let e = roughdielectric_evaluate(mat_ggx_alphas(p.alpha, p.alpha_y), p.ior, wo, wi);
    if mat_finite(e.x) {
        return spectrum_at(p.tint, lambda) * e.x;
    }
    return vec4f(0.0);
}

fn roughdielectric_pdf(p: RoughdielectricParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    let e = roughdielectric_evaluate(mat_ggx_alphas(p.alpha, p.alpha_y), p.ior, wo, wi);
    if mat_finite(e.y) {
        return e.y;
    }
    return 0.0;
}

fn roughdielectric_sample(p: RoughdielectricParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 || !mat_finite3(wo) || !(dot(wo, wo) > 0.0) || !(p.ior > 0.0) {
        return mat_no_sample();
    }
    let a = mat_ggx_alphas(p.alpha, p.alpha_y);
    let below = wo.z < 0.0;
    var up = wo;
    var eta = p.ior;
    if below {
        up = mat_flip_z(wo);
        eta = 1.0 / p.ior;
    }
    let h = mat_ggx_sample_visible(a, up, u);
    let c = dot(up, h);
    if c <= 0.0 {
        return mat_no_sample();
    }
    let r = mat_fresnel_dielectric(c, eta);
    var wi: vec3f;
    var flags: u32;
    if uc < r {
        wi = mat_reflect(up, h);
        if wi.z <= 0.0 {
            return mat_no_sample();
        }
        flags = SCATTER_REFLECTION | SCATTER_GLOSSY;
    } else {
        // Snell's law about h (η = n_t / n_i here).
        let sin2_t = max(1.0 - c * c, 0.0) / (eta * eta);
        if sin2_t >= 1.0 {
            return mat_no_sample();
        }
        let cos_t = sqrt(1.0 - sin2_t);
        wi = mat_normalize_or(-up / eta + (c / eta - cos_t) * h, vec3f(0.0));
        if wi.z >= 0.0 {
            return mat_no_sample();
        }
        flags = SCATTER_TRANSMISSION | SCATTER_GLOSSY;
    }
    if below {
        wi = mat_flip_z(wi);
    }
    let e = roughdielectric_evaluate(a, p.ior, wo, wi);
    if !(e.y > 0.0) || !mat_finite(e.y) || !mat_finite(e.x) {
        return mat_no_sample();
    }
    return BsdfSample(wi, spectrum_at(p.tint, lambda) * e.x, e.y, flags);
}

// `bsdf_textured`'s roughness texel: it multiplies the perceptual roughness √α, so α by
// its square, kept above 10⁻³ (the metalness is ignored).
fn roughdielectric_textured(p: RoughdielectricParams, roughness: f32, metallic: f32) -> RoughdielectricParams {
    if roughness == 1.0 {
        return p;
    }
    var q = p;
    let k = roughness * roughness;
    q.alpha = max(p.alpha * k, 1e-3);
    q.alpha_y = select(0.0, max(p.alpha_y * k, 1e-3), p.alpha_y > 0.0);
    return q;
}
