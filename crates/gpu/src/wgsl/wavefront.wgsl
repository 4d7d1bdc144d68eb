// The path tracer as a wavefront (Laine, Karras & Aila 2013, "Megakernels considered
// harmful"), mirroring crates/tracer/src/integrator.rs (`PathTracer`) as path.wgsl does
// and driven by crates/gpu/src/wavefront.rs: one kernel per stage instead of one loop per
// camera ray, the paths' state in device memory between them. A wave is one sample of every pixel of the band (slot =
// pixel of the band, as the megakernel's invocations): the camera kernel starts every
// path, then per bounce the extension kernel traces the closest hits of the paths still
// going, the shading kernel runs `pt_path_step` (the megakernel's loop body: the same
// code, the same random numbers) and queues the paths that go on, the shadow kernel traces
// the shadow rays that step asked for, and a one-invocation kernel swaps the queues and
// sizes the next indirect dispatch; the film kernel then adds each pixel's sample in the
// megakernel's order, so both give the same statistics. Each stage's kernel holds only its
// own code (the traversal without the materials, the materials without the traversal),
// which is what the design trades the state's memory traffic for.

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
@compute @workgroup_size(64)
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
@compute @workgroup_size(64)
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
@compute @workgroup_size(64)
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
    var rays = 0u;
    var truncated = 0u;
    let more = pt_path_step(&path, state.hit, &wl, &smp, &shadow, &rays, &truncated);
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
@compute @workgroup_size(64)
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
@compute @workgroup_size(64)
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
