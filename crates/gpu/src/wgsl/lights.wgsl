// Light sampling, mirroring crates/tracer/src/lights.rs (`Lights::sample`): the
// environment owns [0, env_pmf) of the unit interval, the light table's entries (emissive
// triangles and shapes, then point and spot lights, then directional ones) the rest by
// their cdf; with the uniform sphere and triangle maps of crates/brdf/src/sampling.rs.
// Where the kernel has a light tree (`PT_LIGHT_TREE`), the tree's stretch of the interval
// (the emitters', then the point and spot lights') is chosen by it for the shading point
// (`Lights::sample_at`; the tree as crates/tracer/src/lights/tree.rs lays it out,
// `LightTreeTables`).

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

// No light sample (`valid` false).
fn pt_no_light_sample() -> PtLightSample {
    var ls: PtLightSample;
    ls.valid = false;
    ls.material = PT_NO_HIT;
    return ls;
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
    var ls = pt_no_light_sample();
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
    return pt_sample_entry(k, u, pt_light_f(k, PT_LIGHT_PMF));
}

// A sample of entry `k` of the light table, chosen with probability `pmf`, from `u`
// (`Lights::sample_prim` and `Lights::sample_punctual`).
fn pt_sample_entry(k: u32, u: vec2f, pmf: f32) -> PtLightSample {
    var ls: PtLightSample;
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

// ---- The light tree (`tracer::lights::tree`): `pt_params.light_tree` holds the offsets in
// `pt_tables` of its nodes (PT_TREE_NODE_FLOATS floats each: twelve rows of four slots,
// then the children and the lights mask), of the primitive → emitter table and of the
// trails (four words per light of the tree), and the end of the tree's stretch of the
// unit interval (bits; it starts at `env_pmf`). The tree's lights are entries of the
// light table: emitters, then point and spot lights.

// The largest finite f32 (the sums of importance are tested against it, as the CPU tests
// them against ∞).
const PT_F32_MAX: f32 = 3.40282347e38;

// Row `row` of node `node`: one value per child slot.
fn pt_tree_row(node: u32, row: u32) -> vec4f {
    let b = pt_params.light_tree.x + PT_TREE_NODE_FLOATS * node + 4u * row;
    return vec4f(pt_tables[b], pt_tables[b + 1u], pt_tables[b + 2u], pt_tables[b + 3u]);
}

// sin θ from cos θ, θ ∈ [0, π] (tree.rs: `sin_from_cos4`).
fn pt_sin_from_cos4(c: vec4f) -> vec4f {
    return sqrt(max(vec4f(1.0) - c * c, vec4f(0.0)));
}

// cos(max(0, a − b)) (tree.rs: `cos_sub_clamped4`, pbrt-v4's `cosSubClamped`).
fn pt_cos_sub_clamped4(sin_a: vec4f, cos_a: vec4f, sin_b: vec4f, cos_b: vec4f) -> vec4f {
    return select(cos_a * cos_b + sin_a * sin_b, vec4f(1.0), cos_a > cos_b);
}

// What each child of `node` can give point `p` with normal `n` (zero: no cosine there), as
// tree.rs's `Node::importance` (pbrt-v4's `LightBounds::Importance`). Zero in unused slots
// and where no direction a child's lights emit into reaches `p`. WGSL does not promise
// NaN or ∞, so the divisions that can meet a zero on the CPU (which then drops the slot
// by its NaN) are kept off it here: the same values wherever the CPU's are finite.
fn pt_tree_importance(node: u32, p: vec3f, n: vec3f) -> vec4f {
    let dx = vec4f(p.x) - pt_tree_row(node, 0u);
    let dy = vec4f(p.y) - pt_tree_row(node, 1u);
    let dz = vec4f(p.z) - pt_tree_row(node, 2u);
    let radius2 = pt_tree_row(node, 3u);
    let min_d2 = pt_tree_row(node, 4u);
    let phi = pt_tree_row(node, 8u);
    let cos_theta_o = pt_tree_row(node, 9u);
    let sin_theta_o = pt_tree_row(node, 10u);
    let cos_theta_e = pt_tree_row(node, 11u);
    let dist2 = dx * dx + dy * dy + dz * dz;
    let positive = dist2 > vec4f(0.0);
    let safe_d2 = select(vec4f(1.0), dist2, positive);
    let inv = select(vec4f(0.0), vec4f(1.0) / sqrt(safe_d2), positive);
    let wx = dx * inv;
    let wy = dy * inv;
    let wz = dz * inv;
    let cos_theta_w = pt_tree_row(node, 5u) * wx + pt_tree_row(node, 6u) * wy + pt_tree_row(node, 7u) * wz;
    let sin_theta_w = pt_sin_from_cos4(cos_theta_w);
    // The box's angular radius from p, through its bounding sphere.
    let outside = sqrt(max(vec4f(1.0) - radius2 / safe_d2, vec4f(0.0)));
    let cos_theta_b = select(outside, vec4f(-1.0), dist2 < radius2);
    let sin_theta_b = pt_sin_from_cos4(cos_theta_b);
    let within = cos_theta_w > cos_theta_o;
    let cos_theta_x = select(cos_theta_w * cos_theta_o + sin_theta_w * sin_theta_o, vec4f(1.0), within);
    let sin_theta_x = select(sin_theta_w * cos_theta_o - cos_theta_w * sin_theta_o, vec4f(0.0), within);
    let cos_theta_p = pt_cos_sub_clamped4(sin_theta_x, cos_theta_x, sin_theta_b, cos_theta_b);
    let d2 = max(dist2, min_d2);
    var importance = phi * cos_theta_p / select(vec4f(1.0), d2, d2 > vec4f(0.0));
    if any(n != vec3f(0.0)) {
        let cos_theta_i = abs(wx * n.x + wy * n.y + wz * n.z);
        importance *= pt_cos_sub_clamped4(pt_sin_from_cos4(cos_theta_i), cos_theta_i, sin_theta_b, cos_theta_b);
    }
    // (Finite, as the CPU keeps only finite importance: its ∞ would need a box at
    // distance zero, which `d2` rules out, or a power of that size.)
    let keep = (cos_theta_p > cos_theta_e) & (phi > vec4f(0.0)) & (d2 > vec4f(0.0)) & (importance > vec4f(0.0))
        & (importance <= vec4f(PT_F32_MAX));
    return select(vec4f(0.0), importance, keep);
}

// The importances' running sums (tree.rs: `Node::ends`): one order of additions for the
// walk and for its probability, so that both see the same totals.
fn pt_tree_ends(e: vec4f) -> vec4f {
    let s1 = e.x + e.y;
    let s2 = s1 + e.z;
    return vec4f(e.x, s1, s2, s2 + e.w);
}

// Child `slot` of `node` (a light where the node's mask has bit `slot`, else a node), and
// whether it is a light.
fn pt_tree_child(node: u32, slot: u32) -> vec2u {
    let b = pt_params.light_tree.x + PT_TREE_NODE_FLOATS * node + 48u;
    let mask = bitcast<u32>(pt_tables[b + 4u]);
    return vec2u(bitcast<u32>(pt_tables[b + slot]), (mask >> slot) & 1u);
}

// The light the tree chooses for `p`, `n` with `u` ∈ [0, 1) (`LightTree::sample`): its
// entry of the light table, the probability of the choice and `u` rescaled within its
// share; `valid` false where no light can reach `p`.
struct PtTreeChoice {
    k: u32,
    pmf: f32,
    u: f32,
    valid: bool,
}

fn pt_tree_sample(p: vec3f, n: vec3f, u_in: f32) -> PtTreeChoice {
    var out = PtTreeChoice(0u, 0.0, 0.0, false);
    var node = 0u;
    var pmf = 1.0;
    var u = u_in;
    // (At most 64 levels: the trails' 128 bits.)
    for (var depth = 0u; depth < 64u; depth++) {
        let e = pt_tree_importance(node, p, n);
        let ends = pt_tree_ends(e);
        let total = ends.w;
        if !(total > 0.0 && total <= PT_F32_MAX) {
            return out;
        }
        let x = u * total;
        // The first slot whose stretch ends past x, but never one of no importance (x may
        // round up to the total, past a last slot of none).
        var slot = u32(ends.x <= x) + u32(ends.y <= x) + u32(ends.z <= x);
        while slot > 0u && e[slot] <= 0.0 {
            slot -= 1u;
        }
        if e[slot] <= 0.0 {
            return out;
        }
        var start = 0.0;
        if slot > 0u {
            start = ends[slot - 1u];
        }
        u = pt_rescale(x, start, ends[slot]);
        pmf *= e[slot] / total;
        let child = pt_tree_child(node, slot);
        if child.y != 0u {
            return PtTreeChoice(child.x, pmf, u, true);
        }
        node = child.x;
    }
    return out;
}

// The probability that `pt_tree_sample` chooses light `k` for `p`, `n` (`LightTree::pmf`):
// the walk down its trail.
fn pt_tree_pmf(k: u32, p: vec3f, n: vec3f) -> f32 {
    let t = pt_params.light_tree.z + 4u * k;
    let trail = vec4u(bitcast<u32>(pt_tables[t]), bitcast<u32>(pt_tables[t + 1u]),
        bitcast<u32>(pt_tables[t + 2u]), bitcast<u32>(pt_tables[t + 3u]));
    var node = 0u;
    var pmf = 1.0;
    for (var depth = 0u; depth < 64u; depth++) {
        let e = pt_tree_importance(node, p, n);
        let total = pt_tree_ends(e).w;
        if !(total > 0.0 && total <= PT_F32_MAX) {
            return 0.0;
        }
        let slot = (trail[depth / 16u] >> (2u * (depth % 16u))) & 3u;
        pmf *= e[slot] / total;
        let child = pt_tree_child(node, slot);
        if child.y != 0u {
            return select(0.0, pmf, child.x == k);
        }
        node = child.x;
    }
    return 0.0;
}

// The upper end of the tree's stretch of the unit interval (the lower: `env_pmf`).
fn pt_tree_hi() -> f32 {
    return bitcast<f32>(pt_params.light_tree.w);
}

// `Lights::sample_at`: a light sample for the shading point `p` with geometric normal `n`;
// by the tree where the kernel has one and the first value falls in its stretch, else as
// `pt_sample_light`.
fn pt_sample_light_at(u_in: vec2f, p: vec3f, n: vec3f) -> PtLightSample {
    if PT_LIGHT_TREE {
        let lo = pt_params.env_pmf;
        let hi = pt_tree_hi();
        if u_in.x >= lo && u_in.x < hi {
            let c = pt_tree_sample(p, n, pt_rescale(u_in.x, lo, hi));
            if !c.valid {
                return pt_no_light_sample();
            }
            return pt_sample_entry(c.k, vec2f(c.u, u_in.y), (hi - lo) * c.pmf);
        }
    }
    return pt_sample_light(u_in);
}

// The probability that next-event estimation at `prev_p` (normal `prev_n`) chooses the
// emitter `sf` lies on (`Lights::prim_pmf_at`): by the tree where the kernel has one, else
// its share of the power. (Only sampled emitters have a share; a placed object's triangle
// never is one, so its own primitive id is not looked up.)
fn pt_emitter_pmf(sf: PtSurface, prev_p: vec3f, prev_n: vec3f) -> f32 {
    if PT_LIGHT_TREE && sf.prim_pmf > 0.0 {
        let k = bitcast<u32>(pt_tables[pt_params.light_tree.y + sf.prim]);
        if k == PT_NO_HIT {
            return 0.0;
        }
        return (pt_tree_hi() - pt_params.env_pmf) * pt_tree_pmf(k, prev_p, prev_n);
    }
    return sf.prim_pmf;
}
