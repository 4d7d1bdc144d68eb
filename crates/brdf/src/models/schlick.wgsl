// Schlick 1994 (crates/brdf/src/models/schlick.rs): R = S(u)·(a/π + b·B + c·mirror) with
// the normalised azimuth factor, exact zenith sampling, Schlick's azimuth sampling and
// the four-lobe mixture. schlick_state does what Schlick::new does on the CPU.

struct SchlickState {
    refl: vec4f,
    r: f32,
    p: f32,
    a: f32,
    b: f32,
    c: f32,
    b2: bool,
    agm: f32,
    g_mean: f32,
}

// Thesis eq. 6.5: b = 4r(1 − r); a = 0, c = 1 − b below r = ½, a = 1 − b, c = 0 above.
fn schlick_derived_weights(r: f32) -> vec3f {
    let b = 4.0 * r * (1.0 - r);
    if r < 0.5 {
        return vec3f(0.0, b, 1.0 - b);
    }
    return vec3f(1.0 - b, b, 0.0);
}

fn schlick_agm1(x: f32) -> f32 {
    var a = 1.0;
    var g = x;
    for (var i = 0; i < 6; i++) {
        let m = 0.5 * (a + g);
        g = sqrt(a * g);
        a = m;
    }
    return 0.5 * (a + g);
}

fn schlick_shadowing(r: f32, v: f32) -> f32 {
    return v / (r - r * v + v);
}

// Ḡ = ∫₀¹ G(v) dv, closed form or series.
fn schlick_shadowing_mean(r: f32) -> f32 {
    let k = 1.0 - r;
    if k > 0.25 {
        return (1.0 + r / k * log(r)) / k;
    }
    var sum = 0.0;
    var kn = 1.0;
    for (var n = 0; n < 14; n++) {
        sum += kn / f32((n + 1) * (n + 2));
        kn *= k;
    }
    return sum;
}

fn schlick_state(p: SchlickParams, lambda: vec4f) -> SchlickState {
    var w = vec3f(p.a, p.b, p.c);
    if p.a < 0.0 || p.b < 0.0 || p.c < 0.0 {
        w = schlick_derived_weights(clamp(p.roughness, 0.0, 1.0));
    } else {
        w = max(w, vec3f(0.0));
        let sum = w.x + w.y + w.z;
        if sum > 1.0 {
            w = vec3f(w.x / sum, w.y / sum, w.z / sum);
        }
    }
    let r = clamp(p.roughness, MAT_SCHLICK_MIN_ROUGHNESS, 1.0);
    let iso = clamp(p.isotropy, MAT_SCHLICK_MIN_ISOTROPY, 1.0);
    return SchlickState(spectrum_at(p.reflectance, lambda), r, iso, w.x, w.y, w.z, p.geometric == MAT_SCHLICK_B2,
        schlick_agm1(iso), schlick_shadowing_mean(r));
}

fn schlick_zenith(r: f32, t2: f32, s2: f32) -> f32 {
    let d = s2 + r * t2;
    return (r / d) / d;
}

fn schlick_azimuth(p: f32, agm: f32, hx2: f32, hy2: f32) -> f32 {
    let s2 = hx2 + hy2;
    if s2 <= 0.0 {
        return 1.0;
    }
    return agm * sqrt(s2 / (hx2 + p * p * hy2));
}

fn schlick_azimuth_pdf(p: f32, hx: f32, hy: f32) -> f32 {
    // Rust's atan2(0, 0) is 0; WGSL leaves atan2 undefined there (h = n).
    var s = 0.0;
    if hx != 0.0 || hy != 0.0 {
        s = atan2(abs(hx), abs(hy)) * (2.0 * MAT_FRAC_1_PI);
    }
    let p2 = p * p;
    let d = p2 + (1.0 - p2) * s * s;
    return p2 / (d * sqrt(d)) * (0.5 * MAT_FRAC_1_PI);
}

fn schlick_sample_half(r: f32, p: f32, u: vec2f) -> vec3f {
    let den = r * (1.0 - u.x) + u.x;
    let t2 = u.x / den;
    let s2 = r * (1.0 - u.x) / den;
    let v4 = 4.0 * u.y;
    let quadrant = min(u32(v4), 3u);
    let frac = v4 - f32(quadrant);
    var xi = 1.0 - frac;
    if (quadrant & 1u) == 0u {
        xi = frac;
    }
    let psi = MAT_FRAC_PI_2 * p * xi / sqrt((1.0 - xi) * (1.0 + xi) + xi * xi * p * p);
    var sx = 1.0;
    var sy = 1.0;
    if quadrant == 1u {
        sy = -1.0;
    } else if quadrant == 2u {
        sx = -1.0;
        sy = -1.0;
    } else if quadrant == 3u {
        sx = -1.0;
    }
    let s = sqrt(s2);
    return vec3f(sx * s * sin(psi), sy * s * cos(psi), sqrt(t2));
}

fn schlick_half_pdf(r: f32, p: f32, h: vec3f) -> f32 {
    let s2 = min(h.x * h.x + h.y * h.y, 1.0);
    return 2.0 * max(h.z, 0.0) * schlick_zenith(r, h.z * h.z, s2) * schlick_azimuth_pdf(p, h.x, h.y);
}

fn schlick_uniform_hemisphere(u: vec2f) -> vec3f {
    let z = 1.0 - u.x;
    let s = sqrt(max(1.0 - z * z, 0.0));
    let cs = mat_cos_sin(MAT_TAU * u.y);
    return vec3f(s * cs.x, s * cs.y, z);
}

// S(u) = C + (1 − C)(1 − u)⁵ given m = 1 − u.
fn schlick_fresnel(st: SchlickState, m_in: f32) -> vec4f {
    let m = clamp(m_in, 0.0, 1.0);
    let m5 = (m * m) * (m * m) * m;
    return st.refl + (vec4f(1.0) - st.refl) * m5;
}

// (diffuse, glossy, multiple-reflection, mirror) lobe probabilities.
fn schlick_lobe_probabilities(st: SchlickState, v2: f32) -> vec4f {
    var wm = 0.0;
    if st.b2 {
        let v = max(v2, 1e-3);
        wm = st.b * max(1.0 - schlick_shadowing(st.r, v) * st.g_mean, 0.0) / (2.0 * v);
    }
    let w = vec4f(st.a, st.b, wm, st.c);
    let sum = w.x + w.y + w.z + w.w;
    if sum > 0.0 {
        return vec4f(w.x / sum, w.y / sum, w.z / sum, w.w / sum);
    }
    return vec4f(0.0);
}

fn schlick_eval_up(st: SchlickState, wo: vec3f, wi: vec3f) -> vec4f {
    let hv = wo + wi;
    let len2 = dot(hv, hv);
    if len2 <= 0.0 {
        return vec4f(0.0);
    }
    let h = hv / sqrt(len2);
    let v1 = max(wi.z, MAT_SCHLICK_MIN_COS);
    let v2 = max(wo.z, MAT_SCHLICK_MIN_COS);
    let hx2 = h.x * h.x;
    let hy2 = h.y * h.y;
    let za = schlick_zenith(st.r, h.z * h.z, min(hx2 + hy2, 1.0)) * schlick_azimuth(st.p, st.agm, hx2, hy2);
    var x = 1.0;
    var y = 0.0;
    if st.b2 {
        let gg = schlick_shadowing(st.r, v1) * schlick_shadowing(st.r, v2);
        x = gg;
        y = 1.0 - gg;
    }
    let d = st.a * MAT_FRAC_1_PI + st.b * (x * za + y) / (4.0 * MAT_PI * v1 * v2);
    let u = 0.5 * sqrt(len2);
    let dw = wo - wi;
    return schlick_fresnel(st, dot(dw, dw) / (4.0 * (1.0 + u))) * d;
}

fn schlick_pdf_up(st: SchlickState, wo: vec3f, wi: vec3f) -> f32 {
    let pr = schlick_lobe_probabilities(st, wo.z);
    var pdf = pr.x * mat_cosine_hemisphere_pdf(wi.z) + pr.z * (0.5 * MAT_FRAC_1_PI);
    let hv = wo + wi;
    let len2 = dot(hv, hv);
    if pr.y > 0.0 && len2 > 0.0 {
        let h = hv / sqrt(len2);
        let oh = dot(wo, h);
        if oh > 0.0 {
            pdf += pr.y * schlick_half_pdf(st.r, st.p, h) / (4.0 * oh);
        }
    }
    return pdf;
}

fn schlick_eval(p: SchlickParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    if wo.z * wi.z <= 0.0 {
        return vec4f(0.0);
    }
    let st = schlick_state(p, lambda);
    if wo.z < 0.0 {
        return schlick_eval_up(st, mat_flip_z(wo), mat_flip_z(wi));
    }
    return schlick_eval_up(st, wo, wi);
}

fn schlick_pdf(p: SchlickParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    if wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    let st = schlick_state(p, lambda);
    if wo.z < 0.0 {
        return schlick_pdf_up(st, mat_flip_z(wo), mat_flip_z(wi));
    }
    return schlick_pdf_up(st, wo, wi);
}

fn schlick_sample(p: SchlickParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 || !mat_finite3(wo) {
        return mat_no_sample();
    }
    let st = schlick_state(p, lambda);
    let down = wo.z < 0.0;
    var wo_up = wo;
    if down {
        wo_up = mat_flip_z(wo);
    }
    let pr = schlick_lobe_probabilities(st, wo_up.z);
    let pd = pr.x;
    let pg = pr.y;
    let pm = pr.z;
    let ps = pr.w;
    if uc < ps {
        // The mirror lobe c·δ: h = n, so u = v₂; weight c·S(v₂).
        var wi = vec3f(-wo_up.x, -wo_up.y, wo_up.z);
        let f = schlick_fresnel(st, 1.0 - wo_up.z) * (st.c / wi.z);
        if down {
            wi = mat_flip_z(wi);
        }
        return BsdfSample(wi, f, ps, SCATTER_REFLECTION | SCATTER_SPECULAR);
    }
    // The last lobe with a non-zero probability also takes what rounding leaves over.
    let x = uc - ps;
    var wi: vec3f;
    var flags: u32;
    if pd > 0.0 && (x < pd || pg + pm <= 0.0) {
        wi = mat_cosine_hemisphere(u);
        flags = SCATTER_REFLECTION | SCATTER_DIFFUSE;
    } else if pg > 0.0 && (x < pd + pg || pm <= 0.0) {
        let h = schlick_sample_half(st.r, st.p, u);
        let oh = dot(wo_up, h);
        if oh <= 0.0 {
            return mat_no_sample();
        }
        wi = mat_normalize(2.0 * oh * h - wo_up);
        flags = SCATTER_REFLECTION | SCATTER_GLOSSY;
    } else if pm > 0.0 {
        wi = schlick_uniform_hemisphere(u);
        flags = SCATTER_REFLECTION | SCATTER_DIFFUSE;
    } else {
        return mat_no_sample();
    }
    if wi.z <= 0.0 {
        return mat_no_sample();
    }
    let pdf = schlick_pdf_up(st, wo_up, wi);
    if !(pdf > 0.0) {
        return mat_no_sample();
    }
    let f = schlick_eval_up(st, wo_up, wi);
    if down {
        wi = mat_flip_z(wi);
    }
    return BsdfSample(wi, f, pdf, flags);
}
