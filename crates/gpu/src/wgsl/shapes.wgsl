// Analytic shapes, mirroring crates/shapes/src/sphere.rs, boxes.rs and polygon.rs (implicit
// surfaces: implicit.wgsl)
// (`Shape::intersect`, `Shape::sample_area`) and crates/tracer/src/geometry.rs
// (`Geometry::intersect`/`occluded`: the triangles first, then the shapes' BVH within the
// closest triangle hit). Each shape is a record in `pt_tables` (written by
// `gpu::backend::shape_record`): kind, material id, light pmf, area, the CPU's primitive
// id, then its own numbers.
// A shape hit's primitive id is PT_SHAPE_PRIM_BIT | the record's offset. Without shapes
// (PT_HAS_SHAPES false) none of this runs.
//
// Differences from the CPU: the polygon's orientation determinant is evaluated in f32
// (f64 there), and a box ray component below 1e-38 counts as parallel (the CPU's 1/d
// overflows to infinity only below ~2.9e-39); both matter only for rays within rounding
// of an edge or a face plane.

const PT_F32_EPSILON: f32 = 1.1920929e-7;

// (The hit record `PtShapeHit` and the tables' readers `pt_tv3`, `pt_tu`: shape_hit.wgsl.)

// sphere.rs: `first_in_range` — the first of the two parameters along the unit direction
// (near one first) inside (t_min, t_max), as a ray parameter; PT_MISS if neither.
fn pt_first_in_range(len: f32, near: f32, far: f32, t_min: f32, t_max: f32) -> f32 {
    let a = near / len;
    if a > t_min && a < t_max {
        return a;
    }
    let b = far / len;
    if b > t_min && b < t_max {
        return b;
    }
    return PT_MISS;
}

// `Sphere::intersect_geometric` (the default): early exits, d² as the length of an actual
// vector, t_hc² as (r − |v|)(r + |v|), the roots in cancellation-free form (`stable_pair`).
fn pt_sphere_geometric(c: vec3f, r: f32, o: vec3f, dir: vec3f, t_min: f32, t_max: f32) -> f32 {
    let len = length(dir);
    if !(len > 0.0) {
        return PT_MISS;
    }
    let d = dir / len;
    let l = c - o;
    let l2 = dot(l, l);
    let r2 = r * r;
    let t_ca = dot(l, d);
    if l2 > r2 && t_ca < 0.0 && t_min >= 0.0 {
        return PT_MISS;
    }
    let v = l - t_ca * d;
    let d2 = dot(v, v);
    if d2 > r2 {
        return PT_MISS;
    }
    let vl = sqrt(d2);
    let t_hc = sqrt(max((r - vl) * (r + vl), 0.0));
    let cc = l2 - r2;
    var q = t_ca - t_hc;
    if t_ca >= 0.0 {
        q = t_ca + t_hc;
    }
    var near = 0.0;
    var far = 0.0;
    if q != 0.0 {
        let other = cc / q;
        if other < q {
            near = other;
            far = q;
        } else {
            near = q;
            far = other;
        }
    }
    return pt_first_in_range(len, near, far, t_min, t_max);
}

// `Sphere::intersect_algebraic`: a t² + b t + c = 0, textbook or stable (Lagrange's
// identity for the discriminant, roots q/a and c/q).
fn pt_sphere_algebraic(c: vec3f, r: f32, o: vec3f, dir: vec3f, t_min: f32, t_max: f32, stable: bool) -> f32 {
    let f = o - c;
    let a = dot(dir, dir);
    let b = 2.0 * dot(dir, f);
    let cc = dot(f, f) - r * r;
    if !(a > 0.0) {
        return PT_MISS;
    }
    var t0 = 0.0;
    var t1 = 0.0;
    if stable {
        let v = f - (0.5 * b / a) * dir;
        let vl = length(v);
        let disc = 4.0 * a * ((r - vl) * (r + vl));
        if !(disc >= 0.0) {
            return PT_MISS;
        }
        let s = sqrt(disc);
        var q = -0.5 * (b - s);
        if b >= 0.0 {
            q = -0.5 * (b + s);
        }
        if q != 0.0 {
            let x = q / a;
            let y = cc / q;
            t0 = min(x, y);
            t1 = max(x, y);
        }
    } else {
        let disc = b * b - 4.0 * a * cc;
        if !(disc >= 0.0) {
            return PT_MISS;
        }
        let s = sqrt(disc);
        let x = (-b - s) / (2.0 * a);
        let y = (-b + s) / (2.0 * a);
        t0 = min(x, y);
        t1 = max(x, y);
    }
    if t0 > t_min && t0 < t_max {
        return t0;
    }
    if t1 > t_min && t1 < t_max {
        return t1;
    }
    return PT_MISS;
}

// Record: +5 centre, +8 radius, +9 method. The point is reprojected onto the sphere.
fn pt_sphere_hit(rec: u32, o: vec3f, d: vec3f, t_min: f32, t_max: f32) -> PtShapeHit {
    let c = pt_tv3(rec + 5u);
    let r = pt_tables[rec + 8u];
    let method = pt_tu(rec + 9u);
    var t: f32;
    if method == PT_SPHERE_GEOMETRIC {
        t = pt_sphere_geometric(c, r, o, d, t_min, t_max);
    } else {
        t = pt_sphere_algebraic(c, r, o, d, t_min, t_max, method == PT_SPHERE_ALGEBRAIC_STABLE);
    }
    if t >= PT_MISS {
        return pt_no_shape_hit();
    }
    let v = (o + t * d) - c;
    let len = length(v);
    var n = vec3f(0.0, 0.0, 1.0);
    if len > 0.0 {
        n = v / len;
    }
    return PtShapeHit(t, c + r * n, n, true);
}

// boxes.rs: `slab_bounds` — entry and exit of the closed box [lo, hi] with their axes. A
// component parallel to a slab restricts nothing if the origin lies within the slab
// (on a face plane included) and misses otherwise (the CPU's ±∞ and NaN cases).
struct PtSlab {
    entry: f32,
    exit: f32,
    entry_axis: u32,
    exit_axis: u32,
    ok: bool,
}

fn pt_slab_bounds(o: vec3f, d: vec3f, lo: vec3f, hi: vec3f, t_min: f32, t_max: f32) -> PtSlab {
    var s = PtSlab(-PT_MISS, PT_MISS, 0u, 0u, false);
    for (var i = 0u; i < 3u; i++) {
        if abs(d[i]) < 1e-38 {
            if o[i] < lo[i] || o[i] > hi[i] {
                return s;
            }
            continue;
        }
        let inv = 1.0 / d[i];
        let t0 = (lo[i] - o[i]) * inv;
        let t1 = (hi[i] - o[i]) * inv;
        let near = min(t0, t1);
        let far = max(t0, t1);
        if near > s.entry {
            s.entry = near;
            s.entry_axis = i;
        }
        if far < s.exit {
            s.exit = far;
            s.exit_axis = i;
        }
    }
    s.ok = s.entry <= s.exit && s.exit > t_min && s.entry < t_max;
    return s;
}

// Record: +5 axis-aligned (bits), +6 centre, +9 half extents, +12/+15/+18 the three axes,
// +21 min, +24 max (the exact corners of an axis-aligned box).
fn pt_cuboid_hit(rec: u32, o_world: vec3f, d_world: vec3f, t_min: f32, t_max: f32) -> PtShapeHit {
    let aligned = pt_tu(rec + 5u) != 0u;
    let centre = pt_tv3(rec + 6u);
    let half = pt_tv3(rec + 9u);
    let a0 = pt_tv3(rec + 12u);
    let a1 = pt_tv3(rec + 15u);
    let a2 = pt_tv3(rec + 18u);
    var o = o_world;
    var d = d_world;
    var lo = pt_tv3(rec + 21u);
    var hi = pt_tv3(rec + 24u);
    if !aligned {
        let rel = o_world - centre;
        o = vec3f(dot(a0, rel), dot(a1, rel), dot(a2, rel));
        d = vec3f(dot(a0, d_world), dot(a1, d_world), dot(a2, d_world));
        lo = -half;
        hi = half;
    }
    let s = pt_slab_bounds(o, d, lo, hi, t_min, t_max);
    if !s.ok {
        return pt_no_shape_hit();
    }
    var t: f32;
    var axis: u32;
    var outward: f32;
    if s.entry > t_min && s.entry < t_max {
        t = s.entry;
        axis = s.entry_axis;
        outward = select(1.0, -1.0, d[axis] > 0.0);
    } else if s.exit > t_min && s.exit < t_max {
        t = s.exit;
        axis = s.exit_axis;
        outward = select(-1.0, 1.0, d[axis] > 0.0);
    } else {
        return pt_no_shape_hit();
    }
    var p = o + t * d;
    let e = vec3f(f32(axis == 0u), f32(axis == 1u), f32(axis == 2u));
    var n: vec3f;
    if aligned {
        p[axis] = select(lo[axis], hi[axis], outward > 0.0);
        n = outward * e;
    } else {
        p[axis] = outward * half[axis];
        p = centre + (a0 * p.x + a1 * p.y + a2 * p.z);
        n = outward * (a0 * e.x + a1 * e.y + a2 * e.z);
    }
    return PtShapeHit(t, p, n, true);
}

// polygon.rs: `orient` (in f32 here).
fn pt_orient(a: vec2f, b: vec2f, c: vec2f) -> f32 {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Record: +5 inside test, +6 dropped axis, +7 vertex count n, +8 normal, +11 anchor,
// +14 triangle count, +15 the projected vertices (2n), then per triangle its vertices
// (9) and cumulative area (1).
fn pt_polygon_contains(rec: u32, q: vec2f) -> bool {
    let n = pt_tu(rec + 7u);
    let base = rec + 15u;
    let crossing = pt_tu(rec + 5u) == PT_POLYGON_CROSSING;
    var inside = false;
    var winding = 0i;
    for (var i = 0u; i < n; i++) {
        let j = select(i + 1u, 0u, i + 1u == n);
        let a = vec2f(pt_tables[base + 2u * i], pt_tables[base + 2u * i + 1u]);
        let b = vec2f(pt_tables[base + 2u * j], pt_tables[base + 2u * j + 1u]);
        if crossing {
            if (a.y > q.y) != (b.y > q.y) {
                var lo = b;
                var hi = a;
                if a.y < b.y {
                    lo = a;
                    hi = b;
                }
                if pt_orient(lo, hi, q) > 0.0 {
                    inside = !inside;
                }
            }
        } else if a.y <= q.y {
            if b.y > q.y && pt_orient(a, b, q) > 0.0 {
                winding += 1i;
            }
        } else if b.y <= q.y && pt_orient(b, a, q) > 0.0 {
            winding -= 1i;
        }
    }
    return select(winding != 0i, inside, crossing);
}

fn pt_polygon_hit(rec: u32, o: vec3f, d: vec3f, t_min: f32, t_max: f32) -> PtShapeHit {
    let n = pt_tv3(rec + 8u);
    let denom = dot(n, d);
    if !(abs(denom) > PT_F32_EPSILON * length(d)) {
        return pt_no_shape_hit();
    }
    let anchor = pt_tv3(rec + 11u);
    let t = dot(n, anchor - o) / denom;
    if !(t > t_min && t < t_max) {
        return pt_no_shape_hit();
    }
    let p0 = o + t * d;
    let p = p0 - n * dot(n, p0 - anchor);
    let k = pt_tu(rec + 6u);
    let rel = p - anchor;
    if !pt_polygon_contains(rec, vec2f(rel[(k + 1u) % 3u], rel[(k + 2u) % 3u])) {
        return pt_no_shape_hit();
    }
    return PtShapeHit(t, p, n, true);
}

// `Shape::intersect` of the record at `rec`.
fn pt_shape_hit(rec: u32, o: vec3f, d: vec3f, t_min: f32, t_max: f32) -> PtShapeHit {
    switch pt_tu(rec) {
        case PT_SHAPE_SPHERE: {
            return pt_sphere_hit(rec, o, d, t_min, t_max);
        }
        case PT_SHAPE_CUBOID: {
            return pt_cuboid_hit(rec, o, d, t_min, t_max);
        }
        case PT_SHAPE_IMPLICIT: {
            return pt_implicit_hit(rec, o, d, t_min, t_max);
        }
        default: {
            return pt_polygon_hit(rec, o, d, t_min, t_max);
        }
    }
}

// The surface of the shape at `rec` hit by (o, d) at `t` (the traversal's): intersected again
// (the same root), but an implicit surface's point is taken at t and its normal from ∇F there,
// so that the kernel holds one copy of its root finder less (each call site is one).
fn pt_shape_surface(rec: u32, o: vec3f, d: vec3f, t: f32) -> PtShapeHit {
    switch pt_tu(rec) {
        case PT_SHAPE_SPHERE: {
            return pt_sphere_hit(rec, o, d, 0.0, PT_FAR);
        }
        case PT_SHAPE_CUBOID: {
            return pt_cuboid_hit(rec, o, d, 0.0, PT_FAR);
        }
        case PT_SHAPE_IMPLICIT: {
            return pt_implicit_surface(rec, o, d, t);
        }
        default: {
            return pt_polygon_hit(rec, o, d, 0.0, PT_FAR);
        }
    }
}

// `Shape::sample_area`: a point uniform by area and its normal.
struct PtAreaSample {
    p: vec3f,
    n: vec3f,
}

fn pt_shape_sample(rec: u32, u: vec2f) -> PtAreaSample {
    let kind = pt_tu(rec);
    if kind == PT_SHAPE_SPHERE {
        // Archimedes' hat box, as `brdf::sampling::uniform_sphere`.
        let n = pt_uniform_sphere(u);
        return PtAreaSample(pt_tv3(rec + 5u) + pt_tables[rec + 8u] * n, n);
    }
    if kind == PT_SHAPE_CUBOID {
        // A face ∝ its area with u.x, rescaled to the first in-face coordinate.
        let aligned = pt_tu(rec + 5u) != 0u;
        let centre = pt_tv3(rec + 6u);
        let h = pt_tv3(rec + 9u);
        let face_area = vec3f(h.y * h.z, h.z * h.x, h.x * h.y);
        let total = 2.0 * (face_area.x + face_area.y + face_area.z);
        var x = clamp(u.x, 0.0, 1.0) * total;
        var face = 5u;
        for (var f = 0u; f < 6u; f++) {
            let a = face_area[f / 2u];
            if x < a || f == 5u {
                face = f;
                break;
            }
            x -= a;
        }
        let axis = face / 2u;
        let sign = select(1.0, -1.0, face % 2u == 0u);
        let u0 = clamp(x / face_area[axis], 0.0, 1.0);
        let j = (axis + 1u) % 3u;
        let k = (axis + 2u) % 3u;
        var local = vec3f(0.0);
        local[axis] = sign * h[axis];
        local[j] = (2.0 * u0 - 1.0) * h[j];
        local[k] = (2.0 * u.y - 1.0) * h[k];
        let e = vec3f(f32(axis == 0u), f32(axis == 1u), f32(axis == 2u));
        if aligned {
            var p = centre + local;
            p[axis] = select(pt_tables[rec + 21u + axis], pt_tables[rec + 24u + axis], sign > 0.0);
            return PtAreaSample(p, sign * e);
        }
        let a0 = pt_tv3(rec + 12u);
        let a1 = pt_tv3(rec + 15u);
        let a2 = pt_tv3(rec + 18u);
        let p = centre + (a0 * local.x + a1 * local.y + a2 * local.z);
        return PtAreaSample(p, sign * (a0 * e.x + a1 * e.y + a2 * e.z));
    }
    // A polygon: a triangle of its ear clipping ∝ area, then Turk's square-root map.
    let nv = pt_tu(rec + 7u);
    let count = pt_tu(rec + 14u);
    let tris = rec + 15u + 2u * nv;
    let total = pt_tables[tris + 10u * (count - 1u) + 9u];
    let x = clamp(u.x, 0.0, 1.0) * total;
    var lo = 0u;
    var hi = count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if pt_tables[tris + 10u * mid + 9u] <= x {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let t = min(lo, count - 1u);
    var before = 0.0;
    if t > 0u {
        before = pt_tables[tris + 10u * (t - 1u) + 9u];
    }
    let width = pt_tables[tris + 10u * t + 9u] - before;
    var u0 = 0.5;
    if width > 0.0 {
        u0 = clamp((x - before) / width, 0.0, 1.0);
    }
    let s = sqrt(u0);
    let b1 = s * (1.0 - u.y);
    let b2 = s * u.y;
    let a = pt_tv3(tris + 10u * t);
    let b = pt_tv3(tris + 10u * t + 3u);
    let c = pt_tv3(tris + 10u * t + 6u);
    return PtAreaSample(a + b1 * (b - a) + b2 * (c - a), pt_tv3(rec + 8u));
}

// The box BVHs in `pt_tables` (`bvh::BoxBvh`, binary nodes of 8 words): the analytic
// shapes' and the instances' (instances.wgsl). Ordered stack traversal as for the
// triangles, with its own stack (the triangles' may be sized to a 4-wide tree's bound,
// and an instance's leaf runs a triangle traversal of its own).
struct PtBoxNode {
    lo: vec3f,
    index: u32,
    hi: vec3f,
    count: u32,
}

fn pt_box_node(nodes: u32, i: u32) -> PtBoxNode {
    let b = nodes + 8u * i;
    return PtBoxNode(pt_tv3(b), pt_tu(b + 3u), pt_tv3(b + 4u), pt_tu(b + 7u));
}

const PT_BOX_STACK: u32 = 64u;

// The closest hit in the instances' BVH (`instances`) or the shapes' closer than `best_in`,
// or with `any_hit` the first found. A leaf slot holds a record's offset: a shape is
// intersected, an instance's object traced in its own space.
fn pt_trace_boxes(instances: bool, r: PtRay, best_in: PtHit, any_hit: bool) -> PtHit {
    var best = best_in;
    var t_max = best_in.t;
    let nodes = select(pt_params.shape_nodes_offset, pt_params.instance_nodes_offset, instances);
    let count = select(pt_params.shape_node_count, pt_params.instance_node_count, instances);
    // (The instances' slots follow their nodes.)
    let slots = select(pt_params.shape_slots_offset, nodes + 8u * count, instances);
    if count == 0u {
        return best;
    }
    let root = pt_box_node(nodes, 0u);
    if pt_box_enter(root.lo, root.hi, r, t_max) >= PT_MISS {
        return best;
    }
    var stack_node: array<u32, PT_BOX_STACK>;
    var stack_t: array<f32, PT_BOX_STACK>;
    var sp = 0u;
    var node = 0u;
    loop {
        let n = pt_box_node(nodes, node);
        var descended = false;
        if n.count > 0u {
            for (var i = n.index; i < n.index + n.count; i++) {
                let rec = pt_tu(slots + i);
                // (PT_HAS_INSTANCES: a kernel without compiles the nested traversal away.)
                if PT_HAS_INSTANCES && instances {
                    let h = pt_trace_instance(rec, r, t_max, any_hit);
                    if h.prim != PT_NO_HIT {
                        t_max = h.t;
                        best = h;
                    }
                } else {
                    let h = pt_shape_hit(rec, r.o, r.d, r.t_min, t_max);
                    if h.hit {
                        t_max = h.t;
                        best = PtHit(h.t, 0.0, 0.0, PT_SHAPE_PRIM_BIT | rec, PT_NO_HIT);
                    }
                }
                if any_hit && best.prim != PT_NO_HIT {
                    return best;
                }
            }
        } else {
            let l = pt_box_node(nodes, node + 1u);
            let rn = pt_box_node(nodes, n.index);
            let tl = pt_box_enter(l.lo, l.hi, r, t_max);
            let tr = pt_box_enter(rn.lo, rn.hi, r, t_max);
            var near = node + 1u;
            var t_near = tl;
            var far = n.index;
            var t_far = tr;
            if tr < tl {
                near = n.index;
                t_near = tr;
                far = node + 1u;
                t_far = tl;
            }
            if t_near < PT_MISS {
                if t_far < PT_MISS && sp < PT_BOX_STACK {
                    stack_node[sp] = far;
                    stack_t[sp] = t_far;
                    sp += 1u;
                }
                node = near;
                descended = true;
            }
        }
        if !descended {
            // Pop until a node that may hold a closer hit.
            var found = false;
            while sp > 0u {
                sp -= 1u;
                if stack_t[sp] <= t_max {
                    node = stack_node[sp];
                    found = true;
                    break;
                }
            }
            if !found {
                return best;
            }
        }
    }
    return best;
}

// The closest hit in (t_min, t_max), or with `any_hit` the first found, through the
// surfaces alpha cuts out (`SceneView::intersect`/`occluded`: a closest-hit query per layer).
fn pt_trace(o: vec3f, d: vec3f, t_min: f32, t_max: f32, any_hit: bool) -> PtHit {
    if PT_HAS_CUTOUTS {
        return pt_through_cutouts(o, d, t_max, pt_trace_opaque(o, d, t_min, t_max, false));
    }
    return pt_trace_opaque(o, d, t_min, t_max, any_hit);
}

// The closest hit in (t_min, t_max) among the world's triangles, the instances and the
// shapes, or with `any_hit` the first found (`Geometry::intersect`/`occluded`).
fn pt_trace_opaque(o: vec3f, d: vec3f, t_min: f32, t_max: f32, any_hit: bool) -> PtHit {
    // (The ray is set up once for the world's tree, the instances and the shapes.)
    let r = pt_make_ray(o, d, t_min);
    var best = PtHit(t_max, 0.0, 0.0, PT_NO_HIT, PT_NO_HIT);
    if pt_params.node_count > 0u {
        best = pt_trace_triangles(0u, r, t_max, any_hit);
    }
    if !(PT_HAS_SHAPES || PT_HAS_INSTANCES) || (any_hit && best.prim != PT_NO_HIT) {
        return best;
    }
    if PT_HAS_INSTANCES {
        best = pt_trace_boxes(true, r, best, any_hit);
        if any_hit && best.prim != PT_NO_HIT {
            return best;
        }
    }
    if PT_HAS_SHAPES {
        best = pt_trace_boxes(false, r, best, any_hit);
    }
    return best;
}

// Whether a hit is on a shape (else a triangle).
fn pt_is_shape(prim: u32) -> bool {
    return PT_HAS_SHAPES && prim != PT_NO_HIT && (prim & PT_SHAPE_PRIM_BIT) != 0u;
}
