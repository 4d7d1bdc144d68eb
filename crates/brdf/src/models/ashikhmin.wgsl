// Ashikhmin & Shirley 2000 (crates/brdf/src/models/ashikhmin.rs): anisotropic Phong
// specular lobe with Schlick Fresnel over the coupled diffuse term; the half vector is
// sampled by the paper's recipe. ln_1p / exp_m1 are emulated by mat_log1p / mat_expm1.

struct AshikhminState {
    nu: f32,
    nv: f32,
    rs: vec4f,
    rd: vec4f,
    norm: f32,
    aspect: f32,
    mean_rs: f32,
    mean_rd: f32,
}

fn ashikhmin_state(p: AshikhminParams, lambda: vec4f) -> AshikhminState {
    let nu = clamp(p.nu, 0.0, MAT_ASHIKHMIN_MAX_EXPONENT);
    let nv = clamp(p.nv, 0.0, MAT_ASHIKHMIN_MAX_EXPONENT);
    let rs = spectrum_at(p.rs, lambda);
    let rd = spectrum_at(p.rd, lambda);
    return AshikhminState(nu, nv, rs, rd, sqrt((nu + 1.0) * (nv + 1.0)), sqrt((nu + 1.0) / (nv + 1.0)), mat_average(rs),
        mat_average(rd * (vec4f(1.0) - rs)));
}

// (n·h)^{(n_u h_x² + n_v h_y²)/(1 − h_z²)} = exp(½ q ln(1 − s²)/s²).
fn ashikhmin_phong_lobe(nu: f32, nv: f32, h: vec3f) -> f32 {
    let hx2 = h.x * h.x;
    let hy2 = h.y * h.y;
    let q = nu * hx2 + nv * hy2;
    if q <= 0.0 {
        return 1.0;
    }
    let s2 = hx2 + hy2;
    if s2 >= 1.0 {
        return 0.0;
    }
    return exp(0.5 * q * (mat_log1p(-s2) / s2));
}

fn ashikhmin_sample_half(nu: f32, nv: f32, aspect: f32, u: vec2f) -> vec3f {
    let v4 = 4.0 * u.x;
    let quadrant = min(u32(v4), 3u);
    let frac = v4 - f32(quadrant);
    var xi = 1.0 - frac;
    if (quadrant & 1u) == 0u {
        xi = frac;
    }
    let a = MAT_FRAC_PI_2 * xi;
    let c = max(cos(a), 0.0);
    let s = aspect * sin(a);
    let len = sqrt(c * c + s * s);
    let cos_phi = c / len;
    let sin_phi = s / len;
    var sx = 1.0;
    var sy = 1.0;
    if quadrant == 1u {
        sx = -1.0;
    } else if quadrant == 2u {
        sx = -1.0;
        sy = -1.0;
    } else if quadrant == 3u {
        sy = -1.0;
    }
    let e = nu * cos_phi * cos_phi + nv * sin_phi * sin_phi + 1.0;
    let l = mat_log1p(-u.y) / e;
    let cos_theta = exp(l);
    let sin_theta = sqrt(clamp(-mat_expm1(2.0 * l), 0.0, 1.0));
    return vec3f(sx * sin_theta * cos_phi, sy * sin_theta * sin_phi, cos_theta);
}

fn ashikhmin_diffuse_factor(x: f32) -> f32 {
    let m = 1.0 - 0.5 * x;
    return 1.0 - (m * m) * (m * m) * m;
}

fn ashikhmin_specular_probability(st: AshikhminState, v2: f32) -> f32 {
    if st.mean_rd <= 0.0 {
        return 1.0;
    }
    let m = 1.0 - clamp(v2, 0.0, 1.0);
    let ws = st.mean_rs + (1.0 - st.mean_rs) * (m * m) * (m * m) * m;
    let wd = st.mean_rd * ashikhmin_diffuse_factor(v2);
    return clamp(ws / (ws + wd), MAT_ASHIKHMIN_MIN_LOBE_PROBABILITY, 1.0 - MAT_ASHIKHMIN_MIN_LOBE_PROBABILITY);
}

fn ashikhmin_eval_up(st: AshikhminState, wo: vec3f, wi: vec3f) -> vec4f {
    let one = vec4f(1.0);
    let diffuse = st.rd * (one - st.rs) * ((28.0f / 23.0f) * MAT_FRAC_1_PI * ashikhmin_diffuse_factor(wi.z)
        * ashikhmin_diffuse_factor(wo.z));
    let hv = wo + wi;
    let len2 = dot(hv, hv);
    if len2 <= 0.0 {
        return diffuse;
    }
    let h = hv / sqrt(len2);
    // k·h = |ωo + ωi|/2 and 1 − k·h = |ωo − ωi|²/(4(1 + k·h)).
    let kh = 0.5 * sqrt(len2);
    let dw = wo - wi;
    let m = clamp(dot(dw, dw) / (4.0 * (1.0 + kh)), 0.0, 1.0);
    let fresnel = st.rs + (one - st.rs) * ((m * m) * (m * m) * m);
    let denom = max(kh, MAT_ASHIKHMIN_MIN_COS) * max(max(wi.z, wo.z), MAT_ASHIKHMIN_MIN_COS);
    let spec = st.norm * (0.125 * MAT_FRAC_1_PI) * ashikhmin_phong_lobe(st.nu, st.nv, h) / denom;
    return fresnel * spec + diffuse;
}

fn ashikhmin_pdf_up(st: AshikhminState, wo: vec3f, wi: vec3f) -> f32 {
    let ps = ashikhmin_specular_probability(st, wo.z);
    var pdf = (1.0 - ps) * mat_cosine_hemisphere_pdf(wi.z);
    let hv = wo + wi;
    let len2 = dot(hv, hv);
    if len2 > 0.0 {
        let h = hv / sqrt(len2);
        let kh = 0.5 * sqrt(len2);
        let ph = st.norm * (0.5 * MAT_FRAC_1_PI) * ashikhmin_phong_lobe(st.nu, st.nv, h);
        pdf += ps * ph / (4.0 * max(kh, MAT_ASHIKHMIN_MIN_COS));
    }
    return pdf;
}

fn ashikhmin_eval(p: AshikhminParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    if wo.z * wi.z <= 0.0 {
        return vec4f(0.0);
    }
    let st = ashikhmin_state(p, lambda);
    if wo.z < 0.0 {
        return ashikhmin_eval_up(st, mat_flip_z(wo), mat_flip_z(wi));
    }
    return ashikhmin_eval_up(st, wo, wi);
}

fn ashikhmin_pdf(p: AshikhminParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    if wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    let st = ashikhmin_state(p, lambda);
    if wo.z < 0.0 {
        return ashikhmin_pdf_up(st, mat_flip_z(wo), mat_flip_z(wi));
    }
    return ashikhmin_pdf_up(st, wo, wi);
}

fn ashikhmin_sample(p: AshikhminParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 || !mat_finite3(wo) {
        return mat_no_sample();
    }
    let st = ashikhmin_state(p, lambda);
    let down = wo.z < 0.0;
    var wo_up = wo;
    if down {
        wo_up = mat_flip_z(wo);
    }
    var wi: vec3f;
    var flags: u32;
    if uc < ashikhmin_specular_probability(st, wo_up.z) {
        let h = ashikhmin_sample_half(st.nu, st.nv, st.aspect, u);
        let oh = dot(wo_up, h);
        if oh <= 0.0 {
            return mat_no_sample();
        }
        wi = mat_normalize(2.0 * oh * h - wo_up);
        flags = SCATTER_REFLECTION | SCATTER_GLOSSY;
    } else {
        wi = mat_cosine_hemisphere(u);
        flags = SCATTER_REFLECTION | SCATTER_DIFFUSE;
    }
    if wi.z <= 0.0 {
        return mat_no_sample();
    }
    let pdf = ashikhmin_pdf_up(st, wo_up, wi);
    if !(pdf > 0.0) {
        return mat_no_sample();
    }
    let f = ashikhmin_eval_up(st, wo_up, wi);
    if down {
        wi = mat_flip_z(wi);
    }
    return BsdfSample(wi, f, pdf, flags);
}
