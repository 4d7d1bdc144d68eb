// The anisotropic GGX distribution, mirroring crates/brdf/src/models/microfacet.rs (Ggx).
// a = (α_x, α_y).

// Ggx::from_alphas: α_y = 0 means α_x; both raised to ALPHA_MIN.
fn mat_ggx_alphas(alpha: f32, alpha_y: f32) -> vec2f {
    let ay = select(alpha, alpha_y, alpha_y > 0.0);
    return vec2f(max(alpha, MAT_GGX_ALPHA_MIN), max(ay, MAT_GGX_ALPHA_MIN));
}

fn mat_ggx_d(a: vec2f, h: vec3f) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let x = h.x / a.x;
    let y = h.y / a.y;
    let e = x * x + y * y + h.z * h.z;
    return 1.0 / (MAT_PI * a.x * a.y * e * e);
}

// s(ω) = √(α_x² ω_x² + α_y² ω_y² + ω_z²).
fn mat_ggx_s(a: vec2f, w: vec3f) -> f32 {
    let x = a.x * w.x;
    let y = a.y * w.y;
    return sqrt(x * x + y * y + w.z * w.z);
}

// D(h) / (2 (|z_o| + s(ωo))): the pdf of the reflected direction.
fn mat_ggx_reflection_pdf(a: vec2f, wo: vec3f, h: vec3f) -> f32 {
    let d = abs(wo.z) + mat_ggx_s(a, wo);
    if d > 0.0 {
        return mat_ggx_d(a, h) / (2.0 * d);
    }
    return 0.0;
}

// Heitz 2018 visible-normal sampling (Ggx::sample_visible), ω_z ≥ 0.
fn mat_ggx_sample_visible(a: vec2f, w: vec3f, u: vec2f) -> vec3f {
    let vh = mat_normalize_or(vec3f(a.x * w.x, a.y * w.y, w.z), vec3f(0.0, 0.0, 1.0));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3f(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3f(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let cs = mat_cos_sin(MAT_TAU * u.y);
    let p1 = r * cs.x;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * cs.y;
    let nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    return mat_normalize(vec3f(a.x * nh.x, a.y * nh.y, max(nh.z, 1.0e-6)));
}
