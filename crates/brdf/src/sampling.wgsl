// Cosine-weighted hemisphere sampling, mirroring crates/brdf/src/sampling.rs.

// Shirley & Chiu's concentric map of [0,1)² to the unit disk.
fn mat_concentric_disk(u: vec2f) -> vec2f {
    let o = 2.0 * u - vec2f(1.0);
    if o.x == 0.0 && o.y == 0.0 {
        return vec2f(0.0);
    }
    var r: f32;
    var theta: f32;
    if abs(o.x) > abs(o.y) {
        r = o.x;
        theta = MAT_FRAC_PI_4 * (o.y / o.x);
    } else {
        r = o.y;
        theta = MAT_FRAC_PI_2 - MAT_FRAC_PI_4 * (o.x / o.y);
    }
    return r * vec2f(cos(theta), sin(theta));
}

// Malley's method: cosine-weighted direction on the +z hemisphere.
fn mat_cosine_hemisphere(u: vec2f) -> vec3f {
    let d = mat_concentric_disk(u);
    let z = sqrt(max(1.0 - (d.x * d.x + d.y * d.y), 0.0));
    return vec3f(d.x, d.y, z);
}

fn mat_cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    return max(cos_theta, 0.0) * MAT_FRAC_1_PI;
}

// Cosine sampling on ωo's side: (ωi, pdf), or all zero for ωo on the horizon.
fn mat_cosine_two_sided(wo: vec3f, u: vec2f) -> vec4f {
    if wo.z == 0.0 {
        return vec4f(0.0);
    }
    var wi = mat_cosine_hemisphere(u);
    if wo.z < 0.0 {
        wi.z = -wi.z;
    }
    let pdf = mat_cosine_hemisphere_pdf(abs(wi.z));
    if pdf > 0.0 {
        return vec4f(wi, pdf);
    }
    return vec4f(0.0);
}

fn mat_cosine_two_sided_pdf(wo: vec3f, wi: vec3f) -> f32 {
    if wo.z * wi.z > 0.0 {
        return mat_cosine_hemisphere_pdf(abs(wi.z));
    }
    return 0.0;
}
