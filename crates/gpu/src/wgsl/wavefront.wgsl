// The path tracer as a wavefront (Laine, Karras & Aila 2013, "Megakernels considered
// harmful"), mirroring crates/tracer/src/integrator.rs (`PathTracer`) as path.wgsl does
// and driven by crates/gpu/src/wavefront.rs: one kernel per stage instead of one loop per
// camera ray, the paths' state in device memory between them. A wave is one sample of
// every pixel of the band (slot = pixel of the band, as the megakernel's invocations): the
// camera kernel starts every path, then per bounce the extension kernel traces the closest
// hits of the paths still going, the shading kernel runs `pt_path_step` and queues the
// paths that go on, the shadow kernel traces the shadow rays that step asked for, and a
// one-invocation kernel swaps the queues and sizes the next indirect dispatch; the film
// kernel then adds each pixel's sample in the megakernel's order. Each stage's kernel
// holds only its own code (the traversal without the materials, the materials without the
// traversal), which is what the design trades the state's memory traffic for.
//
// `pt_path_step` and `pt_light_link` are path.wgsl's `pt_radiance` loop body and
// `pt_light_contribution` restated with the shadow ray deferred, not shared with them: the
// megakernel written around them ran 0.6–3 % slower on an H200 on every scene timed, or,
// with its shadow ray traced inside the step, 3 % faster on the Cornell box and 3.5–4.5 %
// slower on Sponza and a large mesh (docs/gpu.md), so the megakernel keeps its own code. The two draw the same random
// numbers in the same order, so they give the same film bit for bit, which
// `the_wavefront_gives_the_megakernels_image` (tests/equivalence.rs) checks: a change to
// one that is not made to the other fails it.

// A light sample joined to a shading point (path.wgsl's `pt_light_contribution` with MIS,
// up to its shadow ray, the weight taken before it): f, Le and |cos θi| · w / pdf (`e`,
// valid only if the light can contribute), and the shadow ray that decides whether it
// does, for the shadow stage to trace.
struct PtLightLink {
    e: PtNextEvent,
    o: vec3f,
    d: vec3f,
    t_max: f32,
}

fn pt_light_link(at: PtShading, lambda: vec4f, ls: PtLightSample) -> PtLightLink {
    var out = PtLightLink(PtNextEvent(vec4f(0.0), vec4f(0.0), 0.0, false), vec3f(0.0), vec3f(0.0), 0.0);
    let sf = at.sf;
    let m = sf.m;
    let p = sf.p;
    var wi_world: vec3f;
    var finite_light = true;
    var dist = 0.0;
    var light_pdf = 0.0;
    var le = vec4f(0.0);
    var delta = false;
    if ls.kind == PT_LIGHT_TRIANGLE || ls.kind == PT_LIGHT_SHAPE {
        let dl = ls.point - p;
        let dist2 = dot(dl, dl);
        dist = sqrt(dist2);
        wi_world = dl / dist;
        let cos_l = -dot(wi_world, ls.normal);
        if cos_l > 0.0 {
            light_pdf = ls.pdf * dist2 / cos_l;
            le = material_emission(ls.material, lambda);
        }
    } else if ls.kind == PT_LIGHT_ENVIRONMENT {
        wi_world = ls.point;
        finite_light = false;
        light_pdf = ls.pdf;
        if (pt_params.scene_flags & PT_HAS_ENVIRONMENT) != 0u {
            le = pt_env_radiance(wi_world, lambda);
        }
    } else if PT_HAS_PUNCTUAL {
        // A delta light: I·falloff/d² (or E) stands for the radiance and the pdf is the
        // probability of choosing it.
        let inc = pt_punctual_incidence(ls, p, lambda);
        if !inc.valid {
            return out;
        }
        wi_world = inc.wi;
        dist = inc.dist;
        finite_light = inc.dist < PT_FAR;
        light_pdf = ls.pdf;
        le = inc.le;
        delta = inc.delta;
    }
    let wi = pt_to_local(at.frame, wi_world);
    // Reflection must stay on the geometric side it came from (no light leaks).
    let same_side = dot(wi_world, at.ng) * dot(at.wo_world, at.ng) > 0.0;
    if !(light_pdf > 0.0 && any(le != vec4f(0.0)) && (same_side || !at.two_sided)) {
        return out;
    }
    let f = bsdf_eval(m, at.wo, wi, lambda);
    if all(f == vec4f(0.0)) {
        return out;
    }
    // A shadow ray into the back of absorbing glass runs inside it (Beer–Lambert), and
    // never reaches a light at infinity.
    if material_absorbing(m) && !at.two_sided && dot(wi_world, sf.ng) < 0.0 {
        if !finite_light {
            return out;
        }
        le *= exp(-material_absorption(m, lambda) * dist);
    }
    let off = pt_offset_ray_origin(p, select(-sf.ng, sf.ng, dot(wi_world, sf.ng) > 0.0));
    // (One ray for both kinds of light: every trace call site is a copy of the traversal in
    // the compiled kernel.)
    out.o = off;
    out.d = select(wi_world, ls.point - off, finite_light);
    out.t_max = select(PT_FAR, PT_SHADOW_T_MAX, finite_light);
    var w = 1.0;
    if !delta {
        w = pt_power_heuristic(light_pdf, bsdf_pdf(m, at.wo, wi, lambda));
    }
    out.e = PtNextEvent(f, le, abs(wi.z) * w / light_pdf, true);
    return out;
}

// A camera path between two stages (the state of `pt_radiance`'s loop): the ray to trace
// next, the radiance gathered and the throughput, and what Russian roulette, MIS and the
// depth limits need of the vertices before. Plain words only (no bool), so that it can
// stay in device memory between the kernels.
struct PtPath {
    o: vec3f,
    // η'² over the transmissions so far, which Russian roulette undoes (the CPU's
    // `eta_scale`).
    eta_scale: f32,
    d: vec3f,
    // The pdf of the previous BSDF sample.
    prev_pdf: f32,
    prev_p: vec3f,
    // Whether the previous BSDF sample was a delta (no MIS then): 0 or 1.
    prev_specular: u32,
    // The previous vertex's geometric normal, which a light tree's estimate reads.
    prev_n: vec3f,
    l: vec4f,
    beta: vec4f,
    bounce: u32,
    extension_left: u32,
    // Non-specular hits so far, against `max_diffuse_depth` (the CPU's `diffuse_bounces`).
    diffuse_bounces: u32,
    // The absorbing material the last segment left its vertex into (PT_NO_HIT: none).
    inside: u32,
}

fn pt_path_start(origin: vec3f, dir: vec3f) -> PtPath {
    return PtPath(origin, 1.0, dir, 0.0, origin, 1u, vec3f(0.0), vec4f(0.0), pt_unit_throughput(), 0u,
        pt_params.specular_extension, 0u, PT_NO_HIT);
}

// A shadow ray that a path's vertex asked for, and what it adds to the path's radiance if
// nothing blocks it (`valid` 0: none asked for).
struct PtShadowRay {
    o: vec3f,
    t_max: f32,
    d: vec3f,
    valid: u32,
    contribution: vec4f,
}

// One vertex of a path: what the trace of `(*p).o, (*p).d` found (`hit`) is shaded — the
// emission seen, next-event estimation (its shadow ray left in `shadow` for the shadow
// stage, which adds `contribution` to the path's radiance if nothing blocks it) and the
// BSDF-sampled continuation with Russian roulette. Returns whether the path goes on (`*p`
// then holds the next ray). `pt_radiance`'s loop body (path.wgsl), statement for
// statement, with its state in `PtPath` and its shadow ray deferred.
fn pt_path_step(
    p: ptr<function, PtPath>,
    hit: PtHit,
    wl: ptr<function, PtWavelengths>,
    smp: ptr<function, PtSampler>,
    shadow: ptr<function, PtShadowRay>,
    truncated: ptr<function, u32>,
) -> bool {
    (*shadow).valid = 0u;
    let o = (*p).o;
    let d = (*p).d;
    let prev_specular = (*p).prev_specular != 0u;
    var beta = (*p).beta;
    if hit.prim == PT_NO_HIT {
        (*p).l += beta * pt_escaped(d, (*wl).lambda, (*p).prev_pdf, prev_specular);
        return false;
    }

    var sf: PtSurface;
    let uv = pt_hit_surface(hit, o, d, &sf);
    let m = sf.m;
    let wo_world = -d;
    let front = dot(wo_world, sf.ng) > 0.0;
    let two_sided = material_two_sided(m);

    beta *= pt_segment_transmittance(m, front, two_sided, (*p).inside, hit.t, (*wl).lambda);

    // Emission seen by this path (one-sided: front face only).
    if front {
        let le = pt_emission_at(m, uv, (*wl).lambda);
        if any(le != vec4f(0.0)) {
            var w = 1.0;
            if !prev_specular {
                let dp = sf.p - (*p).prev_p;
                let dist2 = dot(dp, dp);
                let cos_l = dot(wo_world, sf.ng);
                let light_pdf = pt_emitter_pmf(sf, (*p).prev_p, (*p).prev_n) * dist2 / (cos_l * sf.area);
                w = pt_power_heuristic((*p).prev_pdf, light_pdf);
            }
            (*p).l += beta * le * w;
        }
    }

    if pt_params.max_depth > 0u && (*p).bounce >= pt_params.max_depth {
        // Past the limit, continue only through purely specular surfaces, while the
        // extension lasts.
        let f = material_flags(m);
        if (*p).extension_left == 0u || !pt_is_specular(f) || pt_is_non_specular(f) {
            return false;
        }
        (*p).extension_left -= 1u;
    }
    // A non-specular hit one more than `max_diffuse_depth` allows ends the path (its
    // emission counted), as the CPU's `diffuse_limit_reached` does.
    if pt_params.max_diffuse_depth > 0u && pt_is_non_specular(material_flags(m)) {
        (*p).diffuse_bounces += 1u;
        if (*p).diffuse_bounces > pt_params.max_diffuse_depth {
            return false;
        }
    }

    // Dispersion: from here on the path follows one wavelength (a random lane, moved
    // to lane 0).
    if material_dispersive(m) && !(*wl).collapsed {
        let k = min(u32(pt_next_1d(smp) * 4.0), 3u);
        pt_collapse_wavelengths(wl, k);
        let bk = beta[k];
        beta[k] = beta[0];
        beta[0] = bk;
        var l = (*p).l;
        let lk2 = l[k];
        l[k] = l[0];
        l[0] = lk2;
        (*p).l = l;
        beta = vec4f(beta[0], 0.0, 0.0, 0.0);
    }
    let lambda = (*wl).lambda;
    // The texels the BSDF calls of this hit read (`Material::bsdf_at`).
    pt_set_texels(m, uv, lambda);

    let at = pt_shading(sf, wo_world, two_sided);
    let flags = material_flags(m);

    // Next-event estimation: one shadow ray to a point on a light.
    if pt_is_non_specular(flags) {
        let ls = pt_sample_light_at(pt_next_2d(smp), sf.p, sf.ng);
        if ls.valid {
            let link = pt_light_link(at, lambda, ls);
            if link.e.valid {
                *shadow = PtShadowRay(link.o, link.t_max, link.d, 1u, beta * link.e.f * link.e.le * link.e.k);
            }
        }
    }

    // Continue the path by sampling the BSDF.
    let uc = pt_next_1d(smp);
    let u = pt_next_2d(smp);
    let s = bsdf_sample(m, at.wo, uc, u, lambda);
    if s.pdf <= 0.0 || all(s.f == vec4f(0.0)) {
        return false;
    }
    let wi_world = pt_to_world(at.frame, s.wi);
    // The sampled lobe must agree with the geometry.
    if pt_lobe_leaks(sf.ng, wo_world, wi_world, s.flags, two_sided) {
        return false;
    }
    beta *= s.f * (abs(s.wi.z) / s.pdf);
    if (s.flags & SCATTER_TRANSMISSION) != 0u {
        let eta = material_eta(m);
        let etap = select(1.0 / eta, eta, at.wo.z > 0.0);
        (*p).eta_scale *= etap * etap;
    }
    (*p).prev_pdf = s.pdf;
    (*p).prev_specular = select(0u, 1u, pt_is_specular(s.flags));
    (*p).prev_p = sf.p;
    (*p).prev_n = sf.ng;
    (*p).inside = select(PT_NO_HIT, m, dot(wi_world, sf.ng) < 0.0 && !two_sided && material_absorbing(m));
    (*p).o = pt_offset_ray_origin(sf.p, select(-sf.ng, sf.ng, dot(wi_world, sf.ng) > 0.0));
    (*p).d = wi_world;
    (*p).bounce += 1u;
    (*p).beta = beta;

    // Russian roulette (Arvo & Kirk 1990), judged by the throughput times η'² and rr_scale (the CPU's).
    if (*p).bounce >= pt_params.rr_depth {
        let q = max(1.0 - max(max(beta.x, beta.y), max(beta.z, beta.w)) * (*p).eta_scale * pt_params.rr_scale, PT_RR_MIN_TERMINATION);
        if pt_next_1d(smp) < q {
            return false;
        }
        (*p).beta = beta / (1.0 - q);
    }
    if all((*p).beta == vec4f(0.0)) {
        return false;
    }
    // The hard cap (also for an unbounded max_depth): counted, so that it is never silent.
    if (*p).bounce >= PT_MAX_BOUNCES {
        *truncated += 1u;
        return false;
    }
    return true;
}

// The paths waiting for a stage: two queues of slots (the one being traced, the one the
// shading kernel fills for the next bounce) and their lengths.
struct PtWfControl {
    // The wave's sample, counted from `pt_params.first_sample` (advanced by `pt_wf_end`).
    sample: u32,
    // Which queue holds the paths to trace now (0 or 1).
    cur: u32,
    count: array<atomic<u32>, 2>,
    // Queue q's entries at q · slots.
    queue: array<u32>,
}

// A path between two stages.
struct PtWfPath {
    path: PtPath,
    shadow: PtShadowRay,
    lambda: vec4f,
    weight: vec4f,
    smp: PtSampler,
    hit: PtHit,
    // Whether the wavelengths collapsed to one (0 or 1).
    collapsed: u32,
    rays: u32,
    truncated: u32,
}

@group(0) @binding(15) var<storage, read_write> pt_wf_paths: array<PtWfPath>;
@group(0) @binding(16) var<storage, read_write> pt_wf: PtWfControl;
// The indirect dispatch's workgroup counts, written by the control kernels only (their own
// bind group: a buffer read as dispatch arguments may not be bound for writing there).
@group(1) @binding(0) var<storage, read_write> pt_wf_groups: array<u32, 3>;

const PT_WF_GROUP: u32 = 64u;

// The band's pixels: one path each.
fn pt_wf_slots() -> u32 {
    return pt_params.band_rows * pt_params.width;
}

// The path that invocation `i` of an indirect stage works on (PT_NO_HIT: none).
fn pt_wf_queued(i: u32) -> u32 {
    let cur = pt_wf.cur;
    if i >= atomicLoad(&pt_wf.count[cur]) {
        return PT_NO_HIT;
    }
    return pt_wf.queue[cur * pt_wf_slots() + i];
}

fn pt_wf_set_groups(n: u32) {
    pt_wf_groups[0] = (n + PT_WF_GROUP - 1u) / PT_WF_GROUP;
    pt_wf_groups[1] = 1u;
    pt_wf_groups[2] = 1u;
}

// A wave begins: every slot's path is queued (the camera kernel fills the queue).
@compute @workgroup_size(1)
fn pt_wf_begin() {
    pt_wf.cur = 0u;
    atomicStore(&pt_wf.count[0], pt_wf_slots());
    atomicStore(&pt_wf.count[1], 0u);
    pt_wf_set_groups(pt_wf_slots());
}

// The camera ray of every slot, as `pt_main` draws it.
@compute @workgroup_size(PT_WF_GROUP)
fn pt_wf_camera(@builtin(global_invocation_id) gid: vec3u) {
    let slot = gid.x;
    if slot >= pt_wf_slots() {
        return;
    }
    let x = slot % pt_params.width;
    let y = pt_params.band_y0 + slot / pt_params.width;
    var smp = pt_sampler_for(x, y, y * pt_params.width + x, pt_params.first_sample + pt_wf.sample);
    let cam = pt_camera(&smp, !PT_RGB);
    var wl: PtWavelengths;
    if PT_RGB {
        wl = pt_rgb_wavelengths();
    } else {
        wl = pt_sample_hero(cam.x);
    }
    let no_shadow = PtShadowRay(vec3f(0.0), 0.0, vec3f(0.0), 0u, vec4f(0.0));
    let no_hit = PtHit(0.0, 0.0, 0.0, PT_NO_HIT, PT_NO_HIT);
    pt_wf_paths[slot] = PtWfPath(
        pt_path_start(pt_params.eye.xyz, pt_camera_direction(x, y, cam.yz)),
        no_shadow,
        wl.lambda,
        wl.weight,
        smp,
        no_hit,
        select(0u, 1u, wl.collapsed),
        0u,
        0u,
    );
    pt_wf.queue[slot] = slot;
}

// The closest hits of the queued paths.
@compute @workgroup_size(PT_WF_GROUP)
fn pt_wf_extend(@builtin(global_invocation_id) gid: vec3u) {
    let slot = pt_wf_queued(gid.x);
    if slot == PT_NO_HIT {
        return;
    }
    let o = pt_wf_paths[slot].path.o;
    let d = pt_wf_paths[slot].path.d;
    pt_wf_paths[slot].hit = pt_trace(o, d, 0.0, PT_FAR, false);
    pt_wf_paths[slot].rays += 1u;
}

// The queued paths' vertices shaded (`pt_path_step`); those that go on are queued for the
// next bounce.
@compute @workgroup_size(PT_WF_GROUP)
fn pt_wf_shade(@builtin(global_invocation_id) gid: vec3u) {
    let slot = pt_wf_queued(gid.x);
    if slot == PT_NO_HIT {
        return;
    }
    // (Locals of their own: naga's SPIR-V writer fails on pointers into a local struct.)
    let state = pt_wf_paths[slot];
    var path = state.path;
    var smp = state.smp;
    var wl = PtWavelengths(state.lambda, state.weight, state.collapsed != 0u);
    var shadow: PtShadowRay;
    var truncated = 0u;
    let more = pt_path_step(&path, state.hit, &wl, &smp, &shadow, &truncated);
    pt_wf_paths[slot].path = path;
    pt_wf_paths[slot].shadow = shadow;
    pt_wf_paths[slot].lambda = wl.lambda;
    pt_wf_paths[slot].weight = wl.weight;
    pt_wf_paths[slot].smp = smp;
    pt_wf_paths[slot].collapsed = select(0u, 1u, wl.collapsed);
    pt_wf_paths[slot].truncated = state.truncated + truncated;
    if more {
        let next = 1u - pt_wf.cur;
        let at = atomicAdd(&pt_wf.count[next], 1u);
        pt_wf.queue[next * pt_wf_slots() + at] = slot;
    }
}

// The shadow rays the shading kernel asked for: each one's contribution added to its
// path's radiance where nothing blocks it.
@compute @workgroup_size(PT_WF_GROUP)
fn pt_wf_shadow(@builtin(global_invocation_id) gid: vec3u) {
    let slot = pt_wf_queued(gid.x);
    if slot == PT_NO_HIT {
        return;
    }
    let shadow = pt_wf_paths[slot].shadow;
    if shadow.valid == 0u {
        return;
    }
    pt_wf_paths[slot].rays += 1u;
    if pt_trace(shadow.o, shadow.d, 0.0, shadow.t_max, true).prim == PT_NO_HIT {
        pt_wf_paths[slot].path.l += shadow.contribution;
    }
}

// Between bounces: the queue the shading kernel filled becomes the one traced, the other
// is emptied, and the next stages' dispatch is sized to it.
@compute @workgroup_size(1)
fn pt_wf_next() {
    let next = 1u - pt_wf.cur;
    pt_wf.cur = next;
    atomicStore(&pt_wf.count[1u - next], 0u);
    pt_wf_set_groups(atomicLoad(&pt_wf.count[next]));
}

// The wave's radiance added to the film, pixel by pixel (`pt_main`'s statistics).
@compute @workgroup_size(PT_WF_GROUP)
fn pt_wf_film(@builtin(global_invocation_id) gid: vec3u) {
    let slot = gid.x;
    if slot >= pt_wf_slots() {
        return;
    }
    let state = pt_wf_paths[slot];
    let wl = PtWavelengths(state.lambda, state.weight, state.collapsed != 0u);
    var acc = pt_film.pixels[slot];
    pt_film_add(&acc, pt_to_linear_srgb(state.path.l, wl));
    pt_film.pixels[slot] = acc;
    pt_film_count(state.rays, state.truncated);
}

// A wave ends: the next one draws the next sample.
@compute @workgroup_size(1)
fn pt_wf_end() {
    pt_wf.sample += 1u;
}
