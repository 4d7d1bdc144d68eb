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

// A colour tabulated at 1 nm over 360–830 nm from `offset` in the tables (its
// linear-sRGB value after the table), linearly interpolated (as `pt_environment`).
fn pt_table_spectrum(offset: u32, lambda: vec4f) -> vec4f {
    // RGB mode: the colour's linear-sRGB value, stored after its table.
    if PT_RGB {
        let o = offset + PT_CIE_SAMPLES;
        return vec4f(pt_tables[o], pt_tables[o + 1u], pt_tables[o + 2u], 0.0);
    }
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

// What a light sample was taken on (besides the table's `PT_LIGHT_*` kinds).
const PT_LIGHT_ENVIRONMENT: u32 = 0xffu;

struct PtLightSample {
    // Point on a triangle or shape, a punctual light's position, or the direction for the
    // environment and directional lights.
    point: vec3f,
    normal: vec3f,
    pdf: f32,
    // Material of the triangle or shape; PT_NO_HIT for the others.
    material: u32,
    // PT_LIGHT_* (PT_LIGHT_ENVIRONMENT for the environment) and the table entry.
    kind: u32,
    entry: u32,
    valid: bool,
}

fn pt_light_f(k: u32, j: u32) -> f32 {
    return pt_tables[pt_params.lights_offset + PT_LIGHT_FLOATS * k + j];
}

fn pt_light_u(k: u32, j: u32) -> u32 {
    return bitcast<u32>(pt_light_f(k, j));
}

fn pt_light_v3(k: u32, j: u32) -> vec3f {
    return vec3f(pt_light_f(k, j), pt_light_f(k, j + 1u), pt_light_f(k, j + 2u));
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
    ls.material = PT_NO_HIT;
    let count = pt_params.light_count;
    if count == 0u && pt_params.env_pmf == 0.0 {
        return ls;
    }
    if u_in.x < pt_params.env_pmf || count == 0u {
        let u = vec2f(pt_rescale(u_in.x, 0.0, pt_params.env_pmf), u_in.y);
        ls.normal = vec3f(0.0);
        ls.kind = PT_LIGHT_ENVIRONMENT;
        if PT_HAS_ENV_MAP {
            // By the map's luminance (none at the poles).
            let s = pt_env_sample(u);
            ls.point = s.xyz;
            ls.pdf = pt_params.env_pmf * s.w;
            ls.valid = s.w >= 0.0;
            return ls;
        }
        ls.point = pt_uniform_sphere(u);
        ls.pdf = pt_params.env_pmf * PT_INV_4PI;
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
    let pmf = pt_light_f(k, PT_LIGHT_PMF);
    ls.kind = pt_light_u(k, PT_LIGHT_KIND);
    ls.entry = k;
    ls.material = pt_light_u(k, PT_LIGHT_MATERIAL);
    ls.valid = true;
    if ls.kind == PT_LIGHT_TRIANGLE {
        let v0 = pt_light_v3(k, 0u);
        let v1 = pt_light_v3(k, 3u);
        let v2 = pt_light_v3(k, 6u);
        let b = pt_uniform_triangle(u);
        ls.point = b.x * v0 + b.y * v1 + (1.0 - b.x - b.y) * v2;
        let c = cross(v1 - v0, v2 - v0);
        let area = 0.5 * length(c);
        ls.normal = normalize(c);
        ls.pdf = pmf / area;
        return ls;
    }
    if PT_HAS_SHAPES && ls.kind == PT_LIGHT_SHAPE {
        let rec = pt_light_u(k, 0u);
        let s = pt_shape_sample(rec, u);
        ls.point = s.p;
        ls.normal = s.n;
        ls.pdf = pmf / pt_tables[rec + 3u];
        return ls;
    }
    return pt_sample_punctual(k, u, pmf);
}

// A punctual light, entry `k` of the light table (`Lights::sample_punctual`): its position
// or direction with pdf `pmf` (the probability of choosing it), or a direction in a sun's
// disk by solid angle (pdf `pmf` / the disk's solid angle).
fn pt_sample_punctual(k: u32, u: vec2f, pmf: f32) -> PtLightSample {
    var ls: PtLightSample;
    ls.kind = pt_light_u(k, PT_LIGHT_KIND);
    ls.entry = k;
    ls.material = PT_NO_HIT;
    ls.valid = true;
    ls.normal = vec3f(0.0);
    ls.point = pt_light_v3(k, 0u);
    ls.pdf = pmf;
    if ls.kind == PT_LIGHT_DIRECTIONAL {
        let cos_radius = pt_light_f(k, 3u);
        if cos_radius < 1.0 {
            let t = pt_light_v3(k, 13u);
            let b = pt_light_v3(k, 16u);
            ls.point = pt_uniform_cone(ls.point, t, b, cos_radius, u);
            ls.pdf = (1.0 / pt_light_f(k, 4u)) * pmf;
        }
    }
    return ls;
}

// A direction uniform in the cone of unit `axis` (with the orthonormal tangents `t`, `b`)
// down to cos θ = `cos_max`, by solid angle (a sun's disk, a spot's light).
fn pt_uniform_cone(axis: vec3f, t: vec3f, b: vec3f, cos_max: f32, u: vec2f) -> vec3f {
    let cos_theta = 1.0 - u.x * (1.0 - cos_max);
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let phi = 2.0 * PT_PI * u.y;
    return normalize(cos_theta * axis + sin_theta * (cos(phi) * t + sin(phi) * b));
}

// Whether punctual light `k` is a sun with a disk (its samples draw a direction in it).
fn pt_punctual_has_disk(k: u32) -> bool {
    return pt_light_u(k, PT_LIGHT_KIND) == PT_LIGHT_DIRECTIONAL && pt_light_f(k, 3u) < 1.0;
}

// What a punctual light sends to `p` (`punctual_incidence`): direction, distance (PT_FAR
// for a directional light) and I·falloff/d² (or E, or a sun disk's radiance); `delta`
// for lights no BSDF sample can find.
struct PtIncidence {
    wi: vec3f,
    dist: f32,
    le: vec4f,
    delta: bool,
    valid: bool,
}

fn pt_punctual_incidence(ls: PtLightSample, p: vec3f, lambda: vec4f) -> PtIncidence {
    var out = PtIncidence(vec3f(0.0), 0.0, vec4f(0.0), true, false);
    let k = ls.entry;
    if ls.kind == PT_LIGHT_DIRECTIONAL {
        let e = pt_table_spectrum(pt_light_u(k, 6u), lambda) * pt_light_f(k, 5u);
        return PtIncidence(ls.point, PT_FAR, e, pt_light_f(k, 3u) >= 1.0, true);
    }
    let d = ls.point - p;
    let dist2 = dot(d, d);
    if !(dist2 > 0.0 && dist2 < PT_FAR) {
        return out; // a light on the surface itself: no direction
    }
    let dist = sqrt(dist2);
    let wi = d / dist;
    var falloff = 1.0;
    var spectrum = pt_light_u(k, 3u);
    if ls.kind == PT_LIGHT_SPOT {
        falloff = pt_spot_falloff(-dot(wi, pt_light_v3(k, 3u)), pt_light_f(k, 6u), pt_light_f(k, 7u));
        spectrum = pt_light_u(k, 8u);
    }
    return PtIncidence(wi, dist, pt_table_spectrum(spectrum, lambda) * (falloff / dist2), true, true);
}

// `PunctualLight::spot_falloff`: 1 inside the inner cone, 0 outside the outer, the squared
// linear ramp in cos θ between.
fn pt_spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_theta >= cos_inner {
        return 1.0;
    }
    let width = cos_inner - cos_outer;
    if width <= 0.0 {
        return 0.0;
    }
    let t = clamp((cos_theta - cos_outer) / width, 0.0, 1.0);
    return t * t;
}

// `SceneView::suns_seen`: the sun disks a ray escaping along `dir` sees, each weighted by
// the power heuristic against its light-sampling pdf when `weighted` (a BSDF sample of
// pdf `bsdf_pdf`), else 1.
fn pt_suns_seen(dir: vec3f, lambda: vec4f, bsdf_pdf: f32, weighted: bool) -> vec4f {
    var l = vec4f(0.0);
    if !PT_HAS_PUNCTUAL {
        return l;
    }
    for (var k = pt_params.punctual_first; k < pt_params.light_count; k++) {
        let cos_radius = pt_light_f(k, 3u);
        if pt_light_u(k, PT_LIGHT_KIND) == PT_LIGHT_DIRECTIONAL && cos_radius < 1.0
            && dot(dir, pt_light_v3(k, 0u)) >= cos_radius {
            let le = pt_table_spectrum(pt_light_u(k, 6u), lambda) * pt_light_f(k, 5u);
            var w = 1.0;
            if weighted {
                w = pt_power_heuristic(bsdf_pdf, pt_light_f(k, PT_LIGHT_PMF) / pt_light_f(k, 4u));
            }
            l += le * w;
        }
    }
    return l;
}
