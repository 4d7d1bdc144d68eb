// Rays as the traversals take them, mirroring crates/bvh/src/build.rs (`Bvh::traverse`'s
// reciprocal direction and the watertight test's permutation and shear, set up once per
// ray): shared by the binary (traversal.wgsl), 4-wide (traversal_wide.wgsl) and 8-wide
// (traversal_wide8.wgsl) traversals, and by the instances' (instances.wgsl).

// `prim` indexes the triangle arrays (or is a shape's record, PT_SHAPE_PRIM_BIT set);
// `inst` is the offset of the instance's record for a triangle of a placed object
// (instances.wgsl), else PT_NO_HIT.
struct PtHit {
    t: f32,
    u: f32,
    v: f32,
    prim: u32,
    inst: u32,
}

struct PtRay {
    o: vec3f,
    d: vec3f,
    inv: vec3f,
    // Watertight test: permutation (kz = the direction's largest axis) and shear.
    kx: u32,
    ky: u32,
    kz: u32,
    shear: vec3f,
    t_min: f32,
}

fn pt_make_ray(o: vec3f, d: vec3f, t_min: f32) -> PtRay {
    // Zero direction components get a tiny finite stand-in (WGSL promises no infinities):
    // the slab test then behaves as the CPU's on-plane rule.
    let tiny = select(vec3f(1e-30), vec3f(-1e-30), d < vec3f(0.0));
    let dd = select(d, tiny, abs(d) < vec3f(1e-30));
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if d[kz] < 0.0 {
        let t = kx;
        kx = ky;
        ky = t;
    }
    let shear = vec3f(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    return PtRay(o, d, 1.0 / dd, kx, ky, kz, shear, t_min);
}

// Entry distance into the box [lo, hi] within (t_min, t_max], or PT_MISS (the slab test
// of the binary traversal and of the shapes' BVH).
fn pt_box_enter(lo: vec3f, hi: vec3f, r: PtRay, t_max: f32) -> f32 {
    let t0 = (lo - r.o) * r.inv;
    let t1 = (hi - r.o) * r.inv;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let t_enter = max(max(max(near.x, near.y), near.z), r.t_min);
    let t_exit = min(min(min(far.x, far.y), far.z), t_max);
    if t_enter <= t_exit {
        return t_enter;
    }
    return PT_MISS;
}

// A traversal stack (both traversals'): nodes still to visit with their entry distances.
struct PtStack {
    node: array<u32, PT_STACK>,
    t: array<f32, PT_STACK>,
    sp: u32,
}

fn pt_push(s: ptr<function, PtStack>, node: u32, t: f32) {
    (*s).node[(*s).sp] = node;
    (*s).t[(*s).sp] = t;
    (*s).sp += 1u;
}

// Pushes a child node entered at `t`, unless `t` is PT_MISS (a slot not to visit).
fn pt_push_reached(s: ptr<function, PtStack>, node: u32, t: f32) {
    if t < PT_MISS {
        pt_push(s, node, t);
    }
}

// Pops until a node whose entry distance is within `t_max` (it may hold a closer hit);
// PT_NO_HIT once the stack is empty.
fn pt_pop(s: ptr<function, PtStack>, t_max: f32) -> u32 {
    loop {
        if (*s).sp == 0u {
            return PT_NO_HIT;
        }
        (*s).sp -= 1u;
        if (*s).t[(*s).sp] <= t_max {
            return (*s).node[(*s).sp];
        }
    }
    return PT_NO_HIT; // (naga wants a return after the loop)
}
