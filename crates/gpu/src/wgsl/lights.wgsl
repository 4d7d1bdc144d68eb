// Light sampling, mirroring crates/tracer/src/lights.rs (`Lights::sample`): the
// environment owns [0, env_pmf) of the unit interval, emissive triangles the rest by
// their cdf; with the uniform sphere and triangle maps of crates/brdf/src/sampling.rs.

// `brdf::sampling::uniform_sphere`.
fn pt_uniform_sphere(u: vec2f) -> vec3f {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = 2.0 * PT_PI * u.y;
    return vec3f(r * cos(phi), r * sin(phi), z);
}

// Heitz 2019, as `brdf::sampling::uniform_triangle`: (b0, b1).
fn pt_uniform_triangle(u: vec2f) -> vec2f {
    if u.x < u.y {
        let b0 = u.x / 2.0;
        return vec2f(b0, u.y - b0);
    }
    let b1 = u.y / 2.0;
    return vec2f(u.x - b1, b1);
}

// A spectrum tabulated at 1 nm over 360–830 nm from `offset` in the tables, linearly
// interpolated (as `pt_environment`).
fn pt_table_spectrum(offset: u32, lambda: vec4f) -> vec4f {
    var out = vec4f(0.0);
    for (var k = 0u; k < 4u; k++) {
        let x = clamp(lambda[k] - PT_CIE_LAMBDA_MIN, 0.0, f32(PT_CIE_SAMPLES - 1u));
        let i = min(u32(x), PT_CIE_SAMPLES - 2u);
        let f = x - f32(i);
        let a = pt_tables[offset + i];
        let b = pt_tables[offset + i + 1u];
        out[k] = a + (b - a) * f;
    }
    return out;
}

// The environment's radiance, tabulated at 1 nm over 360–830 nm, linearly interpolated.
fn pt_environment(lambda: vec4f) -> vec4f {
    return pt_table_spectrum(pt_params.env_offset, lambda);
}

struct PtLightSample {
    // Point on a triangle, or the direction for the environment.
    point: vec3f,
    normal: vec3f,
    pdf: f32,
    // Material of the triangle; PT_NO_HIT for the environment.
    material: u32,
    valid: bool,
}

fn pt_light_f(k: u32, j: u32) -> f32 {
    return pt_tables[pt_params.lights_offset + PT_LIGHT_FLOATS * k + j];
}

// `x` in [lo, hi) mapped to [0, 1), kept below 1 (lights.rs: `rescale`).
fn pt_rescale(x: f32, lo: f32, hi: f32) -> f32 {
    let width = hi - lo;
    if width > 0.0 {
        return clamp((x - lo) / width, 0.0, PT_ONE_MINUS_EPSILON);
    }
    return 0.0;
}

// lights.rs: `Lights::sample` — u.x picks the light and is reused, rescaled, for the point.
fn pt_sample_light(u_in: vec2f) -> PtLightSample {
    var ls: PtLightSample;
    ls.valid = false;
    let count = pt_params.light_count;
    if count == 0u && pt_params.env_pmf == 0.0 {
        return ls;
    }
    if u_in.x < pt_params.env_pmf || count == 0u {
        ls.point = pt_uniform_sphere(vec2f(pt_rescale(u_in.x, 0.0, pt_params.env_pmf), u_in.y));
        ls.normal = vec3f(0.0);
        ls.pdf = pt_params.env_pmf * PT_INV_4PI;
        ls.material = PT_NO_HIT;
        ls.valid = true;
        return ls;
    }
    // partition_point(|c| c <= u.x), clamped to the last light.
    var lo = 0u;
    var hi = count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if pt_light_f(mid, PT_LIGHT_CDF) <= u_in.x {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let k = min(lo, count - 1u);
    var below = pt_params.env_pmf;
    if k > 0u {
        below = pt_light_f(k - 1u, PT_LIGHT_CDF);
    }
    let u = vec2f(pt_rescale(u_in.x, below, pt_light_f(k, PT_LIGHT_CDF)), u_in.y);
    let v0 = vec3f(pt_light_f(k, 0u), pt_light_f(k, 1u), pt_light_f(k, 2u));
    let v1 = vec3f(pt_light_f(k, 3u), pt_light_f(k, 4u), pt_light_f(k, 5u));
    let v2 = vec3f(pt_light_f(k, 6u), pt_light_f(k, 7u), pt_light_f(k, 8u));
    let pmf = pt_light_f(k, PT_LIGHT_PMF);
    let b = pt_uniform_triangle(u);
    ls.point = b.x * v0 + b.y * v1 + (1.0 - b.x - b.y) * v2;
    let c = cross(v1 - v0, v2 - v0);
    let area = 0.5 * length(c);
    ls.normal = normalize(c);
    ls.pdf = pmf / area;
    ls.material = bitcast<u32>(pt_light_f(k, PT_LIGHT_MATERIAL));
    ls.valid = true;
    return ls;
}
