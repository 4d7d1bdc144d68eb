// Bidirectional path tracing, mirroring crates/tracer/src/integrator/bdpt.rs (`Bdpt`):
// a light subpath stored whole, then the camera subpath walked vertex by vertex, each new
// camera vertex connected to every light-subpath prefix (s = 0: the camera path on an
// emitter; s = 1: a fresh light sample; s ≥ 2: light vertex s−1), and every light vertex
// connected to the eye and splatted (t = 1), each weighted by the power heuristic over
// all strategies that sample the same path (Veach 1997, eq. 10.9; pbrt-v3's MISWeight).
//
// Streaming the camera path keeps only its densities per vertex (`bd_cam`), not its
// vertices: a strategy (s, t) reads the camera side's vertices t−1 and t−2 in full and
// only the stored densities of the others, which are final by the time vertex t−1 exists.
// The CPU stores both subpaths and connects after the walks; the strategies, weights and
// estimates are the same (the sampler's dimensions are drawn in another order).
//
// Splats go to `pt_splats` as exact 96-bit fixed-point sums (2⁻³² units, three words per
// channel; see `bd_add_splat`), which the host adds to the film's splat image.

const BD_CAMERA: u32 = 0u;
// A point sampled on an emissive triangle or shape.
const BD_AREA_LIGHT: u32 = 1u;
// A point or spot light (`entry` in the light table).
const BD_PUNCTUAL: u32 = 2u;
const BD_SURFACE: u32 = 3u;
const BD_NONE: u32 = 4u;

// Flags: scattered by a delta lobe; starts on a point or spot light.
const BD_DELTA: u32 = 1u;
const BD_DELTA_LIGHT: u32 = 2u;

// One subpath vertex (bdpt.rs: `Vertex` with its `SurfaceData`).
struct BdVertex {
    p: vec3f,
    kind: u32,
    // Geometric normal (surfaces and area lights; zero for the eye and punctual lights).
    n: vec3f,
    // Material (surfaces).
    m: u32,
    // The shading frame (surfaces).
    fs: vec3f,
    // Area density of sampling this vertex from the previous one on its subpath.
    pdf_fwd: f32,
    ft: vec3f,
    // Area density of sampling it from the next one (the other direction).
    pdf_rev: f32,
    fz: vec3f,
    // The density with which light sampling picks this point (area measure).
    origin_pdf: f32,
    // Unit direction towards the previous vertex (surfaces).
    wo: vec3f,
    flags: u32,
    // Throughput from the subpath's start, over its density.
    beta: vec4f,
    uv: vec2f,
    // The light table's entry (punctual lights).
    entry: u32,
}

// The light subpath's vertices and the camera subpath's densities live in `pt_bdpt_scratch`
// (a storage buffer), not in private arrays: a shader compiler may lower dynamically
// indexed private arrays to a branch per element (lavapipe took nine minutes to compile
// the kernel with 66-vertex private arrays). Each invocation of a dispatch owns a slot;
// the slots are interleaved (entry e of slot i at e · slots + i), so that neighbouring
// invocations touch neighbouring memory. Per slot: eight vec4s per light vertex
// (`bd_load_light`), then one (fwd, rev, delta) per camera vertex (0: the eye).
var<private> bd_slot: u32;

fn bd_slots() -> u32 {
    return pt_params.width * pt_params.band_rows;
}

fn bd_scratch(entry: u32) -> u32 {
    return entry * bd_slots() + bd_slot;
}

fn bd_load_light(k: u32) -> BdVertex {
    let e = 8u * k;
    let a = pt_bdpt_scratch[bd_scratch(e)];
    let b = pt_bdpt_scratch[bd_scratch(e + 1u)];
    let c = pt_bdpt_scratch[bd_scratch(e + 2u)];
    let d = pt_bdpt_scratch[bd_scratch(e + 3u)];
    let f = pt_bdpt_scratch[bd_scratch(e + 4u)];
    let g = pt_bdpt_scratch[bd_scratch(e + 5u)];
    let h = pt_bdpt_scratch[bd_scratch(e + 6u)];
    let i = pt_bdpt_scratch[bd_scratch(e + 7u)];
    return BdVertex(
        a.xyz, bitcast<u32>(a.w),
        b.xyz, bitcast<u32>(b.w),
        c.xyz, c.w,
        d.xyz, d.w,
        f.xyz, f.w,
        g.xyz, bitcast<u32>(g.w),
        h,
        i.xy, bitcast<u32>(i.z),
    );
}

fn bd_store_light(k: u32, v: BdVertex) {
    let e = 8u * k;
    pt_bdpt_scratch[bd_scratch(e)] = vec4f(v.p, bitcast<f32>(v.kind));
    pt_bdpt_scratch[bd_scratch(e + 1u)] = vec4f(v.n, bitcast<f32>(v.m));
    pt_bdpt_scratch[bd_scratch(e + 2u)] = vec4f(v.fs, v.pdf_fwd);
    pt_bdpt_scratch[bd_scratch(e + 3u)] = vec4f(v.ft, v.pdf_rev);
    pt_bdpt_scratch[bd_scratch(e + 4u)] = vec4f(v.fz, v.origin_pdf);
    pt_bdpt_scratch[bd_scratch(e + 5u)] = vec4f(v.wo, bitcast<f32>(v.flags));
    pt_bdpt_scratch[bd_scratch(e + 6u)] = v.beta;
    pt_bdpt_scratch[bd_scratch(e + 7u)] = vec4f(v.uv, bitcast<f32>(v.entry), 0.0);
}

// Light vertex k's densities (fwd, rev) and flags, as the weights read them; its reverse
// density is set one vertex later, when the walk scatters from the next.
fn bd_light_densities(k: u32) -> vec2f {
    return vec2f(pt_bdpt_scratch[bd_scratch(8u * k + 2u)].w, pt_bdpt_scratch[bd_scratch(8u * k + 3u)].w);
}

fn bd_light_flags(k: u32) -> u32 {
    return bitcast<u32>(pt_bdpt_scratch[bd_scratch(8u * k + 5u)].w);
}

fn bd_set_light_rev(k: u32, rev: f32) {
    pt_bdpt_scratch[bd_scratch(8u * k + 3u)].w = rev;
}

// Camera vertex i's densities: (fwd, rev, delta as 0 or 1).
fn bd_cam(i: u32) -> vec3f {
    return pt_bdpt_scratch[bd_scratch(8u * (PT_BDPT_MAX_VERTICES - 1u) + i)].xyz;
}

fn bd_set_cam(i: u32, v: vec3f) {
    pt_bdpt_scratch[bd_scratch(8u * (PT_BDPT_MAX_VERTICES - 1u) + i)] = vec4f(v, 0.0);
}

fn bd_no_vertex() -> BdVertex {
    var v: BdVertex;
    v.kind = BD_NONE;
    return v;
}

// The eye: a point without area (its densities are the camera's, `bd_camera_pdf`).
fn bd_eye(origin: vec3f) -> BdVertex {
    var v: BdVertex;
    v.p = origin;
    v.kind = BD_CAMERA;
    return v;
}

fn bd_local(v: BdVertex, w: vec3f) -> vec3f {
    return vec3f(dot(w, v.fs), dot(w, v.ft), dot(w, v.fz));
}

fn bd_normalize_or_zero(d: vec3f) -> vec3f {
    let len2 = dot(d, d);
    if len2 > 0.0 && len2 < PT_FAR {
        return d / sqrt(len2);
    }
    return vec3f(0.0);
}

fn bd_is_black(c: vec4f) -> bool {
    return all(c == vec4f(0.0));
}

fn bd_is_finite4(v: vec4f) -> bool {
    let e = bitcast<vec4u>(v) & vec4u(0x7f800000u);
    return all(e != vec4u(0x7f800000u));
}

// 0 → 1 (`remap0`): the densities of delta vertices are stored as 0 and skipped anyway.
fn bd_remap0(x: f32) -> f32 {
    return select(1.0, x, x != 0.0);
}

// `to_area`: a solid-angle density at `from` as an area density at `to` (normal `n`;
// zero: a point, no cosine).
fn bd_to_area(pdf_dir: f32, p_from: vec3f, p_to: vec3f, n: vec3f) -> f32 {
    let d = p_to - p_from;
    let dist2 = dot(d, d);
    if !(dist2 > 0.0) {
        return 0.0;
    }
    var cos = 1.0;
    if any(n != vec3f(0.0)) {
        cos = abs(dot(n, d)) / sqrt(dist2);
    }
    return pdf_dir * cos / dist2;
}

// ---- The camera (camera.rs: `film_position`, `pixels_per_steradian`; FilmView::density)

// Whether `(x, y)` lies in the region rendered (`pt_params.region`: x, y, width, height).
fn bd_in_region(x: u32, y: u32) -> bool {
    let r = pt_params.region;
    return x >= r.x && y >= r.y && x - r.x < r.z && y - r.y < r.w;
}

// The pixel a point projects to (`film_position` then `FilmView::pixel`), or
// (PT_NO_HIT, PT_NO_HIT) outside the region or behind the eye.
fn bd_pixel_of(p: vec3f) -> vec2u {
    let none = vec2u(PT_NO_HIT);
    let d = p - pt_params.eye.xyz;
    let z = dot(d, pt_params.forward.xyz);
    if !(z > 0.0) {
        return none;
    }
    let right = pt_params.right.xyz;
    let up = pt_params.up.xyz;
    let ndc_x = dot(d, right) / (z * dot(right, right));
    let ndc_y = dot(d, up) / (z * dot(up, up));
    let f = vec2f(0.5 * (ndc_x + 1.0) / pt_params.inv_size.x, 0.5 * (1.0 - ndc_y) / pt_params.inv_size.y);
    if !(f.x >= 0.0 && f.y >= 0.0 && f.x < 4.0e9 && f.y < 4.0e9) {
        return none;
    }
    let px = vec2u(u32(f.x), u32(f.y));
    if !bd_in_region(px.x, px.y) {
        return none;
    }
    return px;
}

// W(ω) of a unit direction over the region's pixel count (`FilmView::density`).
fn bd_camera_density(dir: vec3f) -> f32 {
    let cos = dot(dir, pt_params.forward.xyz);
    if !(cos > 0.0) {
        return 0.0;
    }
    return pt_params.film_density / (cos * cos * cos);
}

// `camera_pdf`: the density of a camera ray towards `dir`, 0 outside the region.
fn bd_camera_pdf(dir: vec3f) -> f32 {
    if bd_pixel_of(pt_params.eye.xyz + dir).x == PT_NO_HIT {
        return 0.0;
    }
    return bd_camera_density(dir);
}

// ---- Densities and BSDFs at vertices

// A spot light's outer cone (`spot_cone`) and the density of a direction drawn uniformly
// in it.
fn bd_spot_cos_outer(k: u32) -> f32 {
    return max(pt_light_f(k, 7u), -1.0);
}

fn bd_spot_pdf(cos_outer: f32) -> f32 {
    return 1.0 / (2.0 * PT_PI * (1.0 - cos_outer));
}

// `emission_pdf`: the solid-angle density of a light (or an emitter's surface point)
// emitting towards `dir`.
fn bd_emission_pdf(v: BdVertex, dir: vec3f) -> f32 {
    if v.kind == BD_PUNCTUAL {
        if pt_light_u(v.entry, PT_LIGHT_KIND) == PT_LIGHT_SPOT {
            let cos_outer = bd_spot_cos_outer(v.entry);
            if dot(dir, pt_light_v3(v.entry, 3u)) >= cos_outer {
                return bd_spot_pdf(cos_outer);
            }
            return 0.0;
        }
        return PT_INV_4PI;
    }
    return max(dot(dir, v.n), 0.0) / PT_PI;
}

fn bd_bsdf_eval(v: BdVertex, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    pt_set_texels(v.m, v.uv, lambda);
    return bsdf_eval(v.m, wo, wi, lambda);
}

fn bd_bsdf_pdf(v: BdVertex, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    pt_set_texels(v.m, v.uv, lambda);
    return bsdf_pdf(v.m, wo, wi, lambda);
}

// `pdf_to`: the area density at `next` (point, normal) of sampling it from `v`, which
// was reached from `prev` (`has_prev` false at a subpath's start).
fn bd_pdf_to(v: BdVertex, prev: vec3f, has_prev: bool, next_p: vec3f, next_n: vec3f, lambda: vec4f) -> f32 {
    let d = next_p - v.p;
    let dist = length(d);
    if !(dist > 0.0) {
        return 0.0;
    }
    let dir = d / dist;
    var pdf_dir = 0.0;
    if v.kind == BD_CAMERA {
        pdf_dir = bd_camera_pdf(dir);
    } else if v.kind == BD_SURFACE {
        if !has_prev {
            return 0.0;
        }
        let wo = bd_normalize_or_zero(prev - v.p);
        pdf_dir = bd_bsdf_pdf(v, bd_local(v, wo), bd_local(v, dir), lambda);
    } else {
        pdf_dir = bd_emission_pdf(v, dir);
    }
    return bd_to_area(pdf_dir, v.p, next_p, next_n);
}

// `compression`: η'² for a transmission (the BSDF divided radiance by it), with the BSDF's
// own η (a dispersive glass's at the path's wavelength).
fn bd_compression(m: u32, wo: vec3f, transmits: bool, lambda: vec4f) -> f32 {
    if !transmits {
        return 1.0;
    }
    let eta = material_eta_at(m, lambda);
    let etap = select(1.0 / eta, eta, wo.z > 0.0);
    return etap * etap;
}

// `importance_factor`: η'² for a transmission times Veach's shading-normal correction
// |ωo·n_s| |ωi·n_g| / (|ωo·n_g| |ωi·n_s|) (1997, eq. 5.17).
fn bd_importance_factor(v: BdVertex, wo: vec3f, wi: vec3f, wo_l: vec3f, wi_l: vec3f, lambda: vec4f) -> f32 {
    let k = bd_compression(v.m, wo_l, wo_l.z * wi_l.z < 0.0, lambda);
    let den = abs(dot(wo, v.n)) * abs(dot(wi, v.fz));
    if den == 0.0 {
        return 0.0;
    }
    return k * abs(dot(wo, v.fz)) * abs(dot(wi, v.n)) / den;
}

// `surface_f`: f at a surface vertex for light from `wi` leaving towards its `wo`
// (radiance), or the adjoint's (importance).
fn bd_surface_f(v: BdVertex, wi: vec3f, importance: bool, lambda: vec4f) -> vec4f {
    if material_two_sided(v.m) && dot(v.wo, v.n) * dot(wi, v.n) <= 0.0 {
        return vec4f(0.0);
    }
    let wo_l = bd_local(v, v.wo);
    let wi_l = bd_local(v, wi);
    let f = bd_bsdf_eval(v, wo_l, wi_l, lambda);
    if !importance || bd_is_black(f) {
        return f;
    }
    return f * bd_importance_factor(v, v.wo, wi, wo_l, wi_l, lambda);
}

// `Vertex::connectible`: not on a purely specular surface.
fn bd_connectible(v: BdVertex) -> bool {
    return v.kind != BD_SURFACE || pt_is_non_specular(material_flags(v.m));
}

// `Vertex::origin_towards`: where a ray towards `goal` leaves `v`.
fn bd_origin_towards(v: BdVertex, goal: vec3f) -> vec3f {
    if any(v.n != vec3f(0.0)) {
        return pt_offset_ray_origin(v.p, select(-v.n, v.n, dot(goal - v.p, v.n) > 0.0));
    }
    return v.p;
}

// `visible`: whether nothing blocks the segment between two vertices.
fn bd_visible(a: BdVertex, b: BdVertex, rays: ptr<function, u32>) -> bool {
    let o = bd_origin_towards(a, b.p);
    let goal = bd_origin_towards(b, a.p);
    *rays += 1u;
    return pt_trace(o, goal - o, 0.0, PT_SHADOW_T_MAX, true).prim == PT_NO_HIT;
}

// `connection_transmittance`: Beer–Lambert along a connection leaving surface vertex `v`
// along `dir` into the back of absorbing glass (`entered` false otherwise).
struct BdTransmittance {
    tr: vec4f,
    entered: bool,
}

fn bd_connection_transmittance(v: BdVertex, dir: vec3f, dist: f32, lambda: vec4f) -> BdTransmittance {
    if v.kind != BD_SURFACE || dot(dir, v.n) >= 0.0 || material_two_sided(v.m) || !material_absorbing(v.m) {
        return BdTransmittance(vec4f(1.0), false);
    }
    return BdTransmittance(exp(-material_absorption(v.m, lambda) * dist), true);
}

// ---- The strategies' weights (`Strategy::weight`)

// The power heuristic's weight of strategy (s, t): `qs` the light side's last vertex
// (light vertex s−1, or the fresh light sample for s = 1; unused for s = 0), `pt` and `pm`
// the camera side's vertices t−1 and t−2 (`pm` unused for t = 1). Light vertices before
// s−1 are read from the scratch, camera densities before t−1 too.
fn bd_weight(s: u32, t: u32, qs: BdVertex, pt: BdVertex, pm: BdVertex, lambda: vec4f) -> f32 {
    if s + t == 2u {
        return 1.0;
    }
    var qm = bd_no_vertex();
    if s > 1u {
        qm = bd_load_light(s - 2u);
    }
    // The densities of the connection's end points and their neighbours as this strategy
    // sees them.
    var pt_rev = 0.0;
    var pt_minus_rev = 0.0;
    var qs_rev = 0.0;
    var qs_minus_rev = 0.0;
    if s > 0u {
        // One call of `bd_pdf_to` in a loop, not four calls: shader compilers inline every
        // call, and each copy carries every material's pdf. The trip count depends on s
        // and t, so the loop is not unrolled back into copies either.
        // Entries: 0 pt_rev, 1 qs_rev (always), 2 pt_minus_rev (t > 1), 3 qs_minus_rev
        // (s > 1).
        let needed = 2u + select(0u, 1u, t > 1u) + select(0u, 1u, s > 1u);
        var rev = vec4f(0.0);
        for (var k = 0u; k < needed; k++) {
            let entry = select(k, 3u, k == 2u && t <= 1u);
            // `bd_pdf_to(v, prev, has_prev, next)` of each entry; entry 1's by default.
            var v = pt;
            var prev = pm.p;
            var has_prev = t > 1u;
            var next = qs;
            if entry == 0u {
                v = qs;
                prev = qm.p;
                has_prev = s > 1u;
                next = pt;
            } else if entry == 2u {
                prev = qs.p;
                has_prev = true;
                next = pm;
            } else if entry == 3u {
                v = qs;
                prev = pt.p;
                has_prev = true;
                next = qm;
            }
            rev[entry] = bd_pdf_to(v, prev, has_prev, next.p, next.n, lambda);
        }
        pt_rev = rev[0];
        qs_rev = rev[1];
        pt_minus_rev = rev[2];
        qs_minus_rev = rev[3];
    } else {
        pt_rev = pt.origin_pdf;
        if t > 1u {
            pt_minus_rev = bd_to_area(bd_emission_pdf(pt, bd_normalize_or_zero(pm.p - pt.p)), pt.p, pm.p, pm.n);
        }
    }

    var sum = 0.0;
    var ratio = 1.0;
    // The camera side, from the connection towards the eye.
    // (Vertex t−1's forward density is its own; its stored entry is written only once
    // the walk scatters from it.)
    var here = vec3f(pt.pdf_fwd, 0.0, 0.0);
    for (var i = t - 1u; i >= 1u; i--) {
        let before = bd_cam(i - 1u);
        var rev = here.y;
        var delta = here.z != 0.0;
        if i + 1u == t {
            rev = pt_rev;
            delta = false;
        } else if i + 2u == t {
            rev = pt_minus_rev;
        }
        ratio *= bd_remap0(rev) / bd_remap0(here.x);
        // Light tracing (t = 1) is always among the strategies of a render.
        if !delta && before.z == 0.0 {
            sum += ratio * ratio;
        }
        here = before;
    }
    // The light side, from the connection towards the light.
    var light0_delta = false;
    if s == 1u {
        light0_delta = (qs.flags & BD_DELTA_LIGHT) != 0u;
    } else if s > 1u {
        light0_delta = (bd_light_flags(0u) & BD_DELTA_LIGHT) != 0u;
    }
    ratio = 1.0;
    for (var j = 0u; j < s; j++) {
        let i = s - 1u - j;
        var fwd = qs.pdf_fwd;
        var rev = qs_rev;
        var delta = false;
        if i + 1u < s {
            let stored = bd_light_densities(i);
            fwd = stored.x;
            rev = select(stored.y, qs_minus_rev, i + 2u == s);
            delta = (bd_light_flags(i) & BD_DELTA) != 0u;
        }
        ratio *= bd_remap0(rev) / bd_remap0(fwd);
        var delta_before = light0_delta;
        if i > 0u {
            delta_before = (bd_light_flags(i - 1u) & BD_DELTA) != 0u;
        }
        if !delta && !delta_before {
            sum += ratio * ratio;
        }
    }
    let w = 1.0 / (1.0 + sum);
    return select(0.0, w, pt_is_finite(w));
}

// ---- The walks (`walk`)

// A subpath's walk between vertices: the ray its last vertex sent, its throughput and
// solid-angle density, the absorbing material it left into, its radiance compression
// (camera paths; Russian roulette undoes it) and whether its last scattering was a delta.
struct BdWalk {
    o: vec3f,
    d: vec3f,
    beta: vec4f,
    pdf_dir: f32,
    inside: u32,
    eta_scale: f32,
    specular: bool,
}

// The surface vertex a walk's ray hit (its throughput after the segment's absorption),
// with the shading set-up next-event estimation reads (`at`).
fn bd_hit_vertex(
    hit: PtHit,
    w: ptr<function, BdWalk>,
    last_p: vec3f,
    radiance: bool,
    lambda: vec4f,
    at: ptr<function, PtShading>,
) -> BdVertex {
    var sf: PtSurface;
    let uv = pt_hit_surface(hit, (*w).o, (*w).d, &sf);
    let m = sf.m;
    let wo_world = -(*w).d;
    let front = dot(wo_world, sf.ng) > 0.0;
    let two_sided = material_two_sided(m);
    (*w).beta *= pt_segment_transmittance(m, front, two_sided, (*w).inside, hit.t, lambda);
    *at = pt_shading(sf, wo_world, two_sided);
    var v: BdVertex;
    v.p = sf.p;
    v.kind = BD_SURFACE;
    v.n = sf.ng;
    v.m = m;
    v.fs = (*at).frame.s;
    v.ft = (*at).frame.t;
    v.fz = (*at).frame.n;
    v.pdf_fwd = bd_to_area((*w).pdf_dir, last_p, sf.p, sf.ng);
    v.pdf_rev = 0.0;
    // Camera paths on an emitter: the density with which light sampling finds the point.
    v.origin_pdf = 0.0;
    if radiance && front && sf.prim_pmf > 0.0 && sf.area > 0.0 {
        v.origin_pdf = sf.prim_pmf / sf.area;
    }
    v.wo = wo_world;
    v.flags = 0u;
    v.beta = (*w).beta;
    v.uv = uv;
    v.entry = 0u;
    return v;
}

// What scattering at a vertex did: whether it continues the walk, and the area density
// of sampling the previous vertex from this one (`prev_rev`, valid where `scattered`).
struct BdScatter {
    scattered: bool,
    alive: bool,
    prev_rev: f32,
}

// Samples the BSDF at vertex `v` (index `k` of its subpath; the previous vertex at
// `prev_p` with normal `prev_n`) and moves the walk on, with Russian roulette.
fn bd_scatter(
    v: ptr<function, BdVertex>,
    w: ptr<function, BdWalk>,
    prev_p: vec3f,
    prev_n: vec3f,
    k: u32,
    importance: bool,
    lambda: vec4f,
    smp: ptr<function, PtSampler>,
) -> BdScatter {
    var out = BdScatter(false, false, 0.0);
    let uc = pt_next_1d(smp);
    let u = pt_next_2d(smp);
    let vv = *v;
    let m = vv.m;
    let wo = bd_local(vv, vv.wo);
    pt_set_texels(m, vv.uv, lambda);
    let bs = bsdf_sample(m, wo, uc, u, lambda);
    if bs.pdf <= 0.0 || bd_is_black(bs.f) {
        return out;
    }
    let frame = PtFrame(vv.fs, vv.ft, vv.fz);
    let wi_world = pt_to_world(frame, bs.wi);
    let two_sided = material_two_sided(m);
    if pt_lobe_leaks(vv.n, vv.wo, wi_world, bs.flags, two_sided) {
        return out;
    }
    let specular = pt_is_specular(bs.flags);
    var factor = bs.f * (abs(bs.wi.z) / bs.pdf);
    if importance {
        factor *= bd_importance_factor(vv, vv.wo, wi_world, wo, bs.wi, lambda);
    } else {
        (*w).eta_scale *= bd_compression(m, wo, (bs.flags & SCATTER_TRANSMISSION) != 0u, lambda);
    }
    var fwd = 0.0;
    var rev = 0.0;
    if !specular {
        fwd = bs.pdf;
        rev = bsdf_pdf(m, bs.wi, wo, lambda);
    }
    out.scattered = true;
    if specular {
        (*v).flags |= BD_DELTA;
    }
    out.prev_rev = bd_to_area(rev, vv.p, prev_p, prev_n);
    (*w).inside = select(PT_NO_HIT, m, dot(wi_world, vv.n) < 0.0 && !two_sided && material_absorbing(m));
    (*w).o = pt_offset_ray_origin(vv.p, select(-vv.n, vv.n, dot(wi_world, vv.n) > 0.0));
    (*w).d = wi_world;
    (*w).beta *= factor;
    (*w).pdf_dir = fwd;
    (*w).specular = specular;
    // Russian roulette, counted in bounces as the path tracer does.
    if k >= pt_params.rr_depth {
        let b = (*w).beta;
        let q = max(1.0 - max(max(b.x, b.y), max(b.z, b.w)) * (*w).eta_scale * pt_params.rr_scale, PT_RR_MIN_TERMINATION);
        if pt_next_1d(smp) < q {
            return out;
        }
        (*w).beta /= 1.0 - q;
    }
    out.alive = !bd_is_black((*w).beta);
    return out;
}

// Whether a walk that reached `max_vertices` was cut by the cap rather than by the depth
// asked for (counted as truncated).
fn bd_cut_by_cap() -> bool {
    return pt_params.max_depth == 0u || pt_params.max_depth + 2u > PT_BDPT_MAX_VERTICES;
}

// `light_vertex`: a light sample as a light subpath's first vertex (or the stand-in for
// one in next-event estimation); BD_NONE for lights at infinity and emitters that send
// nothing here.
fn bd_light_vertex(ls: PtLightSample, lambda: vec4f) -> BdVertex {
    var v = bd_no_vertex();
    var le = vec4f(0.0);
    var kind = BD_AREA_LIGHT;
    var flags = 0u;
    if ls.kind == PT_LIGHT_TRIANGLE || ls.kind == PT_LIGHT_SHAPE {
        le = material_emission(ls.material, lambda);
    } else if PT_HAS_PUNCTUAL && ls.kind == PT_LIGHT_POINT {
        le = pt_table_spectrum(pt_light_u(ls.entry, 3u), lambda);
        kind = BD_PUNCTUAL;
        flags = BD_DELTA_LIGHT;
    } else if PT_HAS_PUNCTUAL && ls.kind == PT_LIGHT_SPOT {
        le = pt_table_spectrum(pt_light_u(ls.entry, 8u), lambda);
        kind = BD_PUNCTUAL;
        flags = BD_DELTA_LIGHT;
    } else {
        return v;
    }
    if !(ls.pdf > 0.0) || bd_is_black(le) {
        return v;
    }
    v.p = ls.point;
    v.kind = kind;
    v.n = ls.normal;
    v.beta = le / ls.pdf;
    v.pdf_fwd = ls.pdf;
    v.pdf_rev = 0.0;
    v.origin_pdf = ls.pdf;
    v.flags = flags;
    v.entry = ls.entry;
    return v;
}

// `start_light_path`: the light subpath's first vertex (BD_NONE where the light sample
// gives none) and the walk leaving it (`w`). Both sample pairs are drawn either way.
fn bd_start_light_path(lambda: vec4f, smp: ptr<function, PtSampler>, w: ptr<function, BdWalk>) -> BdVertex {
    let ls = pt_sample_light(pt_next_2d(smp));
    let u = pt_next_2d(smp);
    if !ls.valid {
        return bd_no_vertex();
    }
    let v0 = bd_light_vertex(ls, lambda);
    if v0.kind == BD_NONE {
        return v0;
    }
    var dir: vec3f;
    var pdf_dir: f32;
    // What the light sends along `dir` per unit of Le (or I): cos θ, or the spot's falloff.
    var emitted = 1.0;
    if v0.kind == BD_AREA_LIGHT {
        dir = pt_to_world(pt_frame_from_normal(ls.normal), mat_cosine_hemisphere(u));
        emitted = dot(dir, ls.normal);
        pdf_dir = emitted / PT_PI;
    } else if pt_light_u(ls.entry, PT_LIGHT_KIND) == PT_LIGHT_SPOT {
        let axis = pt_light_v3(ls.entry, 3u);
        let cos_outer = bd_spot_cos_outer(ls.entry);
        let f = pt_frame_from_normal(axis);
        dir = pt_uniform_cone(axis, f.s, f.t, cos_outer, u);
        pdf_dir = bd_spot_pdf(cos_outer);
        emitted = pt_spot_falloff(dot(dir, axis), pt_light_f(ls.entry, 6u), pt_light_f(ls.entry, 7u));
    } else {
        dir = pt_uniform_sphere(u);
        pdf_dir = PT_INV_4PI;
    }
    if !(pdf_dir > 0.0) {
        return bd_no_vertex();
    }
    // β = Le·cos θ / (p_pos · p_dir), v0's β being Le / p_pos.
    *w = BdWalk(bd_origin_towards(v0, v0.p + dir), dir, v0.beta * (emitted / pdf_dir), pdf_dir, PT_NO_HIT, 1.0, false);
    return v0;
}

// ---- The strategies

// Splats `rgb` (one light path's contribution over the region's pixel count) onto pixel
// (x, y): each channel as round(x · 2³²) in 96-bit two's complement, added word by word
// with the carries propagated, so the sums are exact and do not depend on the order
// (the film's splat sums are the same numbers in 2⁻⁶⁴ units). Splats that are not
// finite or beyond PT_MAX_SAMPLE_MAGNITUDE are dropped and counted, as the film does.
fn bd_add_splat(x: u32, y: u32, rgb: vec3f) {
    if !pt_is_finite3(rgb) || !all(abs(rgb) < vec3f(PT_MAX_SAMPLE_MAGNITUDE)) {
        atomicAdd(&pt_splats[0], 1u);
        return;
    }
    let base = PT_SPLAT_HEADER_WORDS + 9u * (y * pt_params.width + x);
    for (var c = 0u; c < 3u; c++) {
        let bits = bitcast<u32>(rgb[c]);
        let biased = (bits >> 23u) & 0xffu;
        if biased == 0u {
            continue; // zero or subnormal: below 2⁻³² by far
        }
        // |x| = m · 2^(biased − 150), so |x| · 2³² = m · 2^(biased − 118).
        let m = (bits & 0x7fffffu) | 0x800000u;
        let shift = i32(biased) - 118;
        var w0 = 0u;
        var w1 = 0u;
        var w2 = 0u;
        if shift < 0 {
            let r = u32(-shift);
            if r <= 24u {
                // Round half up.
                w0 = (m + (1u << (r - 1u))) >> r;
            }
        } else if shift < 32 {
            let r = u32(shift);
            w0 = m << r;
            w1 = select(0u, m >> (32u - r), r > 0u);
        } else {
            let r = u32(shift - 32);
            w1 = m << r;
            w2 = select(0u, m >> (32u - r), r > 0u);
        }
        if (bits >> 31u) != 0u {
            // Negate: invert and add one, carrying.
            w0 = ~w0;
            w1 = ~w1;
            w2 = ~w2;
            w0 += 1u;
            if w0 == 0u {
                w1 += 1u;
                if w1 == 0u {
                    w2 += 1u;
                }
            }
        }
        let i = base + 3u * c;
        let old0 = atomicAdd(&pt_splats[i], w0);
        var carry1 = select(0u, 1u, old0 + w0 < old0);
        let old1 = atomicAdd(&pt_splats[i + 1u], w1);
        var carry2 = select(0u, 1u, old1 + w1 < old1);
        if carry1 != 0u {
            let old1b = atomicAdd(&pt_splats[i + 1u], 1u);
            carry2 += select(0u, 1u, old1b == 0xffffffffu);
        }
        atomicAdd(&pt_splats[i + 2u], w2 + carry2);
    }
}

// A strategy's estimate before its MIS weight, with what the weight needs: the light
// side's last vertex `qs`, and whether to weight at all; for light tracing (t = 1) the
// pixel it splats onto. The camera loop weighs every strategy at one call of `bd_weight`
// (each call is an inlined copy of it).
struct BdEstimate {
    c: vec4f,
    qs: BdVertex,
    weighted: bool,
    pixel: vec2u,
}

fn bd_no_estimate() -> BdEstimate {
    return BdEstimate(vec4f(0.0), bd_no_vertex(), false, vec2u(PT_NO_HIT));
}

// s = 0 (`hit_light`): camera vertex t−1 on an emitter's front face.
fn bd_hit_light(pt: BdVertex, lambda: vec4f) -> BdEstimate {
    if dot(pt.wo, pt.n) <= 0.0 {
        return bd_no_estimate();
    }
    let le = pt_emission_at(pt.m, pt.uv, lambda);
    if bd_is_black(le) {
        return bd_no_estimate();
    }
    // An emitter that light sampling never picks is found by this strategy alone.
    return BdEstimate(pt.beta * le, bd_no_vertex(), pt.origin_pdf > 0.0, vec2u(PT_NO_HIT));
}

// s = 1 (`next_event`): a fresh light sample connected to camera vertex t−1; a light at
// infinity is weighted as the path tracer weighs it.
fn bd_next_event(
    pt: BdVertex,
    at: PtShading,
    lambda: vec4f,
    smp: ptr<function, PtSampler>,
    rays: ptr<function, u32>,
) -> BdEstimate {
    let u = pt_next_2d(smp);
    if !bd_connectible(pt) {
        return bd_no_estimate();
    }
    let ls = pt_sample_light(u);
    if !ls.valid {
        return bd_no_estimate();
    }
    pt_set_texels(pt.m, pt.uv, lambda);
    // A light at infinity is weighted by the path tracer's MIS inside the contribution;
    // one call for both kinds (each call is a copy of the shadow ray's traversal).
    let at_infinity = ls.kind == PT_LIGHT_ENVIRONMENT || ls.kind == PT_LIGHT_DIRECTIONAL;
    var sampled = bd_no_vertex();
    if !at_infinity {
        sampled = bd_light_vertex(ls, lambda);
        if sampled.kind == BD_NONE {
            return bd_no_estimate();
        }
    }
    let e = pt_light_contribution(at, lambda, ls, at_infinity, rays);
    if !e.valid {
        return bd_no_estimate();
    }
    return BdEstimate(pt.beta * e.f * e.le * e.k, sampled, !at_infinity, vec2u(PT_NO_HIT));
}

// s ≥ 2 (`connect`): light vertex s−1 connected to camera vertex t−1; for t = 1, the
// eye (`splat_to_eye`: the estimate is splatted onto the pixel the vertex is seen in).
// One function for both: every call is an inlined copy of the shadow ray's traversal and
// of every material's BSDF.
fn bd_connect(s: u32, t: u32, pt: BdVertex, lambda: vec4f, rays: ptr<function, u32>) -> BdEstimate {
    let qs = bd_load_light(s - 1u);
    if qs.kind != BD_SURFACE || !bd_connectible(qs) || !bd_connectible(pt) {
        return bd_no_estimate();
    }
    var pixel = vec2u(PT_NO_HIT);
    if t == 1u {
        pixel = bd_pixel_of(qs.p);
        if pixel.x == PT_NO_HIT {
            return bd_no_estimate();
        }
    }
    let d = pt.p - qs.p;
    let dist2 = dot(d, d);
    if !(dist2 > 0.0) {
        return bd_no_estimate();
    }
    let dist = sqrt(dist2);
    let w = d / dist;
    let f_q = bd_surface_f(qs, w, true, lambda);
    var c: vec4f;
    if t == 1u {
        c = qs.beta * f_q * (abs(dot(qs.fz, w)) * bd_camera_density(-w) / dist2);
    } else {
        let f_p = bd_surface_f(pt, -w, false, lambda);
        let g = abs(dot(qs.fz, w)) * abs(dot(pt.fz, w)) / dist2;
        c = qs.beta * f_q * f_p * pt.beta * g;
    }
    if bd_is_black(c) || !bd_is_finite4(c) || !bd_visible(qs, pt, rays) {
        return bd_no_estimate();
    }
    // (The eye is no surface: its side gives 1.)
    let from_q = bd_connection_transmittance(qs, w, dist, lambda);
    if from_q.entered {
        c *= from_q.tr;
    } else {
        c *= bd_connection_transmittance(pt, -w, dist, lambda).tr;
    }
    return BdEstimate(c, qs, true, pixel);
}

// Whether strategy (s, t) makes a path deeper than `max_depth` allows.
fn bd_too_deep(s: u32, t: u32) -> bool {
    return pt_params.max_depth > 0u && s + t - 2u > pt_params.max_depth;
}

// One camera sample's estimate (`sample_radiance`); light tracing's splats go to
// `pt_splats`. Pixels outside the region (a crop window's rows are rendered whole) trace
// nothing: their light paths must not splat.
fn pt_bdpt(
    origin: vec3f,
    dir: vec3f,
    wl: ptr<function, PtWavelengths>,
    smp: ptr<function, PtSampler>,
    rays: ptr<function, u32>,
    truncated: ptr<function, u32>,
) -> vec4f {
    if !bd_in_region(pt_pixel.x, pt_pixel.y) {
        return vec4f(0.0);
    }
    bd_slot = (pt_pixel.y - pt_params.band_y0) * pt_params.width + pt_pixel.x;
    // Both subpaths share their wavelengths: where glass disperses, one of them.
    pt_collapse_if_dispersive(wl, smp);
    let lambda = (*wl).lambda;
    var camera_vertices = PT_BDPT_MAX_VERTICES;
    if pt_params.max_depth > 0u {
        camera_vertices = min(pt_params.max_depth + 2u, PT_BDPT_MAX_VERTICES);
    }
    let light_vertices = camera_vertices - 1u;
    var l = vec4f(0.0);
    bd_set_cam(0u, vec3f(1.0, 0.0, 0.0));

    // One loop walks both subpaths: the light's, stored whole, then the camera's, each
    // vertex connected to every light-subpath prefix as it is reached (at the eye, t = 1,
    // that is light tracing, splatted). With one call of each piece (the trace, the hit,
    // the scattering, each strategy, the weight) the compiled kernel stays small: shader
    // compilers inline every call (docs/gpu.md, "BDPT's compile time").
    var w: BdWalk;
    var cur = bd_start_light_path(lambda, smp, &w);
    var camera = false;
    // Where the light walk ends, the camera walk starts from the eye.
    var to_camera = cur.kind == BD_NONE;
    var light_len = 0u;
    var last = bd_no_vertex();
    var t = 1u;
    var at: PtShading;
    loop {
        if to_camera {
            to_camera = false;
            camera = true;
            w = BdWalk(origin, dir, pt_unit_throughput(), bd_camera_pdf(dir), PT_NO_HIT, 1.0, true);
            cur = bd_eye(origin);
            last = bd_no_vertex();
        }
        // `cur` is the walk's newest vertex, index `k` on its subpath.
        let k = select(light_len, t - 1u, camera);
        let at_cap = k + 1u >= select(light_vertices, camera_vertices, camera);
        if camera {
            // s = 1 draws its own light sample: it runs even where the light subpath is
            // empty.
            for (var s = select(0u, 2u, t == 1u); s <= max(light_len, 1u); s++) {
                if bd_too_deep(s, t) {
                    continue;
                }
                var e: BdEstimate;
                if s == 0u {
                    e = bd_hit_light(cur, lambda);
                } else if s == 1u {
                    e = bd_next_event(cur, at, lambda, smp, rays);
                } else {
                    e = bd_connect(s, t, cur, lambda, rays);
                }
                if e.weighted && !bd_is_black(e.c) {
                    e.c *= bd_weight(s, t, e.qs, cur, last, lambda);
                }
                if t > 1u {
                    l += e.c;
                } else if !bd_is_black(e.c) {
                    bd_add_splat(e.pixel.x, e.pixel.y, pt_to_linear_srgb(e.c, *wl));
                }
            }
        }
        if at_cap && bd_cut_by_cap() {
            *truncated += 1u;
        }
        // A walk's start (the light's vertex, the eye) has its direction already.
        var alive = !at_cap;
        if alive && k > 0u {
            let sc = bd_scatter(&cur, &w, last.p, last.n, k, !camera, lambda, smp);
            alive = sc.alive;
            if sc.scattered && camera {
                let before = bd_cam(k - 1u);
                bd_set_cam(k - 1u, vec3f(before.x, sc.prev_rev, before.z));
                bd_set_cam(k, vec3f(cur.pdf_fwd, 0.0, select(0.0, 1.0, (cur.flags & BD_DELTA) != 0u)));
            } else if sc.scattered {
                bd_set_light_rev(k - 1u, sc.prev_rev);
            }
        }
        if !camera {
            // Stored after its scattering, which sets its delta flag.
            bd_store_light(k, cur);
            light_len = k + 1u;
        }
        if !alive {
            if camera {
                break;
            }
            to_camera = true;
            continue;
        }
        last = cur;
        *rays += 1u;
        let hit = pt_trace(w.o, w.d, 0.0, PT_FAR, false);
        if hit.prim == PT_NO_HIT {
            if camera {
                // The lights at infinity, weighted as the path tracer weighs them.
                l += w.beta * pt_escaped(w.d, lambda, w.pdf_dir, w.specular);
                break;
            }
            to_camera = true;
            continue;
        }
        cur = bd_hit_vertex(hit, &w, last.p, camera, lambda, &at);
        t += select(0u, 1u, camera);
    }
    return l;
}
