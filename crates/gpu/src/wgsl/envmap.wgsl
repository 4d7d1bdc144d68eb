// Environment maps, mirroring crates/tracer/src/envmap.rs (`EnvironmentMap::uv`, `direction`,
// `rgb`, `radiance`, `sample`, `pdf`, `sample_cdf`) and `Lights::environment_pdf`: a
// latitude–longitude map, y up, its centre towards −z, bilinear (wrapping in u, clamped in
// v), importance-sampled by the CPU's own distribution (a marginal over rows, a conditional
// per row). Without a map (PT_HAS_ENV_MAP false) none of it runs.
//
// The record at `pt_params.envmap_offset`: +0 width, +1 height (bits), +2/+3 the rotation's
// cos and sin, +4 the texels (RGB triples), +5 the conditional distributions (width + 1
// entries per row), +6 the marginal (height + 1), +7 the D65 table (bits, offsets in
// `pt_tables`), +8 D65's normalisation 1/N (`d65_normalised`).

const PT_D65_LAMBDA_MIN: f32 = 300.0;
const PT_D65_LAMBDA_STEP: f32 = 5.0;
const PT_D65_SAMPLES: u32 = 107u;

fn pt_env_f(j: u32) -> f32 {
    return pt_tables[pt_params.envmap_offset + j];
}

fn pt_env_u(j: u32) -> u32 {
    return bitcast<u32>(pt_env_f(j));
}

// `EnvironmentMap::uv`: the map's (u, v) of a unit world direction.
fn pt_env_uv(dir: vec3f) -> vec2f {
    let c = pt_env_f(2u);
    let s = pt_env_f(3u);
    let x = c * dir.x - s * dir.z;
    let z = s * dir.x + c * dir.z;
    let u = 0.5 + atan2(x, -z) / (2.0 * PT_PI);
    let v = acos(clamp(dir.y, -1.0, 1.0)) / PT_PI;
    return vec2f(u, v);
}

// `EnvironmentMap::direction`: the world direction at map coordinates `uv`.
fn pt_env_direction(uv: vec2f) -> vec3f {
    let phi = (uv.x - 0.5) * 2.0 * PT_PI;
    let theta = uv.y * PT_PI;
    let sin_t = sin(theta);
    let cos_t = cos(theta);
    let x = sin_t * sin(phi);
    let z = -sin_t * cos(phi);
    let c = pt_env_f(2u);
    let s = pt_env_f(3u);
    return vec3f(c * x + s * z, cos_t, -s * x + c * z);
}

// `EnvironmentMap::rgb`: bilinear linear RGB from `dir`.
fn pt_env_rgb(dir: vec3f) -> vec3f {
    let uv = pt_env_uv(dir);
    let w = i32(pt_env_u(0u));
    let h = i32(pt_env_u(1u));
    let c = pt_texel_coords(uv, u32(w), u32(h));
    let x0 = c.x0;
    let y0 = c.y0;
    let fx = c.fx;
    let fy = c.fy;
    let texels = pt_env_u(4u);
    var out = vec3f(0.0);
    for (var dy = 0; dy < 2; dy++) {
        let wy = select(fy, 1.0 - fy, dy == 0);
        let row = clamp(y0 + dy, 0, h - 1);
        for (var dx = 0; dx < 2; dx++) {
            let wx = select(fx, 1.0 - fx, dx == 0);
            let col = (((x0 + dx) % w) + w) % w;
            out += wy * wx * pt_tv3(texels + 3u * u32(row * w + col));
        }
    }
    return out;
}

// uplift.rs: `d65_normalised`, the D65 table interpolated and normalised to luminance 1.
fn pt_d65_normalised(lambda: vec4f) -> vec4f {
    return pt_d65_at(pt_env_u(7u), pt_env_f(8u), lambda);
}

// The D65 table at `table` (5 nm from 300 nm) interpolated, times `inv_norm`.
fn pt_d65_at(table: u32, inv_norm: f32, lambda: vec4f) -> vec4f {
    var out = vec4f(0.0);
    for (var k = 0u; k < 4u; k++) {
        let x = (lambda[k] - PT_D65_LAMBDA_MIN) / PT_D65_LAMBDA_STEP;
        if x >= 0.0 && x <= f32(PT_D65_SAMPLES - 1u) {
            let i = min(u32(x), PT_D65_SAMPLES - 2u);
            let f = x - f32(i);
            out[k] = (pt_tables[table + i] + f * (pt_tables[table + i + 1u] - pt_tables[table + i])) * inv_norm;
        }
    }
    return out;
}

// `EnvironmentMap::radiance`: the RGB as an illuminant (2·max times the uplifted RGB/(2·max)
// times D65), or the RGB itself in RGB mode; times the environment's own colour.
fn pt_env_radiance(dir: vec3f, lambda: vec4f) -> vec4f {
    let base = pt_environment(lambda);
    if !PT_HAS_ENV_MAP {
        return base;
    }
    let rgb = pt_env_rgb(dir);
    if PT_RGB {
        return base * vec4f(rgb, 0.0);
    }
    let m = max(rgb.x, max(rgb.y, rgb.z));
    if !(m > 0.0) {
        return vec4f(0.0);
    }
    let scale = 2.0 * m;
    return base * (scale * pt_reflectance(rgb / scale, lambda) * pt_d65_normalised(lambda));
}

// `sample_cdf`: the bin of `u` in the cumulative distribution of `n` bins at `at`, and the
// position within it.
fn pt_sample_cdf(at: u32, n: u32, u: f32) -> vec2f {
    // partition_point(|c| c <= u), minus one, within 0..n.
    var lo = 0u;
    var hi = n + 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if pt_tables[at + mid] <= u {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let k = min(select(lo - 1u, 0u, lo == 0u), n - 1u);
    let width = pt_tables[at + k + 1u] - pt_tables[at + k];
    var f = 0.5;
    if width > 0.0 {
        f = clamp((u - pt_tables[at + k]) / width, 0.0, PT_ONE_MINUS_EPSILON);
    }
    return vec2f(f32(k), f);
}

// `EnvironmentMap::density`: the density over [0, 1]² of texel (row, col).
fn pt_env_density(row: u32, col: u32) -> f32 {
    let w = pt_env_u(0u);
    let h = pt_env_u(1u);
    let cdf = pt_env_u(5u) + row * (w + 1u);
    let marginal = pt_env_u(6u);
    let p_col = pt_tables[cdf + col + 1u] - pt_tables[cdf + col];
    let p_row = pt_tables[marginal + row + 1u] - pt_tables[marginal + row];
    return p_row * p_col * f32(w * h);
}

// `EnvironmentMap::sample`: a direction ∝ the map's weights and its solid-angle pdf (w < 0
// at the poles, where there is none).
fn pt_env_sample(u: vec2f) -> vec4f {
    let w = pt_env_u(0u);
    let h = pt_env_u(1u);
    let r = pt_sample_cdf(pt_env_u(6u), h, u.y);
    let row = u32(r.x);
    let c = pt_sample_cdf(pt_env_u(5u) + row * (w + 1u), w, u.x);
    let col = u32(c.x);
    let uv = vec2f((f32(col) + c.y) / f32(w), (f32(row) + r.y) / f32(h));
    let sin_theta = sin(uv.y * PT_PI);
    if !(sin_theta > 0.0) {
        return vec4f(0.0, 0.0, 0.0, -1.0);
    }
    return vec4f(pt_env_direction(uv), pt_env_density(row, col) / (2.0 * PT_PI * PT_PI * sin_theta));
}

// `Lights::environment_pdf`: the solid-angle pdf with which light sampling draws `dir` from
// the environment (its choice included).
fn pt_env_pdf(dir: vec3f) -> f32 {
    if !PT_HAS_ENV_MAP {
        return pt_params.env_pmf * PT_INV_4PI;
    }
    let uv = pt_env_uv(dir);
    let sin_theta = sin(uv.y * PT_PI);
    if !(sin_theta > 0.0) {
        return 0.0;
    }
    let w = pt_env_u(0u);
    let h = pt_env_u(1u);
    let col = min(u32(uv.x * f32(w)), w - 1u);
    let row = min(u32(uv.y * f32(h)), h - 1u);
    return pt_params.env_pmf * pt_env_density(row, col) / (2.0 * PT_PI * PT_PI * sin_theta);
}
