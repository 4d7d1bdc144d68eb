// glTF 2.0 metallic-roughness (crates/brdf/src/models/metallic_roughness.rs,
// MetallicRoughness): GGX specular over a Schlick-Fresnel-mixed Lambertian base, blended
// with a Schlick metal by `metallic`; mixture sampling; reflection only, two-sided.

struct MetallicroughnessState {
    base: vec4f,
    metallic: f32,
    a: vec2f,
    f0: f32,
    mean_base: f32,
}

fn metallicroughness_state(p: MetallicroughnessParams, lambda: vec4f) -> MetallicroughnessState {
    let r = clamp(p.roughness, 0.0, 1.0);
    let ior = max(p.ior, 1.0);
    let q = (ior - 1.0) / (ior + 1.0);
    let base = spectrum_at(p.base_color, lambda);
    return MetallicroughnessState(base, clamp(p.metallic, 0.0, 1.0), mat_ggx_alphas(r * r, 0.0), q * q,
        mat_average(base));
}

// (1 − c)⁵, c clamped to [0, 1].
fn metallicroughness_schlick_weight(c: f32) -> f32 {
    let m = 1.0 - clamp(c, 0.0, 1.0);
    return (m * m) * (m * m) * m;
}

fn metallicroughness_specular_probability(st: MetallicroughnessState, zo: f32) -> f32 {
    let w = metallicroughness_schlick_weight(zo);
    let dielectric = st.f0 + (1.0 - st.f0) * w;
    let wd = (1.0 - st.metallic) * (1.0 - dielectric) * st.mean_base;
    if wd <= 0.0 {
        return 1.0;
    }
    let metal = st.mean_base + (1.0 - st.mean_base) * w;
    let ws = st.metallic * metal + (1.0 - st.metallic) * dielectric;
    return clamp(ws / (ws + wd), MAT_METALLICROUGHNESS_MIN_LOBE_PROBABILITY,
        1.0 - MAT_METALLICROUGHNESS_MIN_LOBE_PROBABILITY);
}

fn metallicroughness_eval_up(st: MetallicroughnessState, wo: vec3f, wi: vec3f) -> vec4f {
    let hv = wo + wi;
    let len2 = dot(hv, hv);
    if !(len2 > 0.0) {
        return vec4f(0.0);
    }
    let h = hv / sqrt(len2);
    let w = metallicroughness_schlick_weight(dot(wo, h));
    let dielectric = st.f0 + (1.0 - st.f0) * w;
    let den = 2.0 * (mat_ggx_s(st.a, wo) * wi.z + mat_ggx_s(st.a, wi) * wo.z);
    var specular = 0.0;
    if den > 0.0 {
        specular = mat_ggx_d(st.a, h) / den;
    }
    let one = vec4f(1.0);
    let metal = st.base + (one - st.base) * w;
    let diffuse = (1.0 - st.metallic) * (1.0 - dielectric) * MAT_FRAC_1_PI;
    return st.base * diffuse + (metal * st.metallic + one * ((1.0 - st.metallic) * dielectric)) * specular;
}

fn metallicroughness_pdf_up(st: MetallicroughnessState, wo: vec3f, wi: vec3f) -> f32 {
    let ps = metallicroughness_specular_probability(st, wo.z);
    var pdf = (1.0 - ps) * mat_cosine_hemisphere_pdf(wi.z);
    let hv = wo + wi;
    let len2 = dot(hv, hv);
    if len2 > 0.0 {
        pdf += ps * mat_ggx_reflection_pdf(st.a, wo, hv / sqrt(len2));
    }
    return pdf;
}

fn metallicroughness_eval(p: MetallicroughnessParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    if wo.z * wi.z <= 0.0 {
        return vec4f(0.0);
    }
    let st = metallicroughness_state(p, lambda);
    if wo.z < 0.0 {
        return metallicroughness_eval_up(st, mat_flip_z(wo), mat_flip_z(wi));
    }
    return metallicroughness_eval_up(st, wo, wi);
}

fn metallicroughness_pdf(p: MetallicroughnessParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    if wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    let st = metallicroughness_state(p, lambda);
    if wo.z < 0.0 {
        return metallicroughness_pdf_up(st, mat_flip_z(wo), mat_flip_z(wi));
    }
    return metallicroughness_pdf_up(st, wo, wi);
}

fn metallicroughness_sample(p: MetallicroughnessParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 || !mat_finite3(wo) {
        return mat_no_sample();
    }
    let st = metallicroughness_state(p, lambda);
    let down = wo.z < 0.0;
    var wo_up = wo;
    if down {
        wo_up = mat_flip_z(wo);
    }
    var wi: vec3f;
    var flags: u32;
    if uc < metallicroughness_specular_probability(st, wo_up.z) {
        let h = mat_ggx_sample_visible(st.a, wo_up, u);
        wi = mat_reflect(wo_up, h);
        flags = SCATTER_REFLECTION | SCATTER_GLOSSY;
    } else {
        wi = mat_cosine_hemisphere(u);
        flags = SCATTER_REFLECTION | SCATTER_DIFFUSE;
    }
    if wi.z <= 0.0 || !mat_finite3(wi) {
        return mat_no_sample();
    }
    let pdf = metallicroughness_pdf_up(st, wo_up, wi);
    if !(pdf > 0.0) {
        return mat_no_sample();
    }
    let f = metallicroughness_eval_up(st, wo_up, wi);
    if down {
        wi = mat_flip_z(wi);
    }
    return BsdfSample(wi, f, pdf, flags);
}

// `bsdf_textured`'s metallic–roughness texel: it multiplies metalness and roughness.
fn metallicroughness_textured(p: MetallicroughnessParams, roughness: f32, metallic: f32) -> MetallicroughnessParams {
    var q = p;
    q.metallic = p.metallic * metallic;
    q.roughness = p.roughness * roughness;
    return q;
}
