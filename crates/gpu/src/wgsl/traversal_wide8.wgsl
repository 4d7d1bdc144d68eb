// Ray casting in the 8-wide BVH built by crates/gpu/src/wide.rs: a node is two PtWideNode
// entries (children 0–3, then 4–7), each slab-tested as in traversal_wide.wgsl. Leaf
// children are intersected first (shrinking t_max before anything is pushed); the child
// nodes hit are sorted nearest first (each half by a sorting network, then Batcher's
// odd–even merge of the two sorted halves), the nearest visited and the others pushed
// farthest first with their entry distances; nodes beyond the closest hit are culled on
// the way back. Everything is unrolled: no loop over the slots (see wide.rs for why).
// Shares PtWideState and pt_wide_leaf's contract with traversal_wide.wgsl (repeated here,
// since a kernel includes one traversal). PT_STACK is the tree's own bound.

struct PtWideState {
    t_max: f32,
    best: PtHit,
    found: bool,
}

// Tests a leaf child's triangles (`count` from `first`) against the closest hit so far.
fn pt_wide_leaf(first: u32, count: u32, r: PtRay, s: ptr<function, PtWideState>, any_hit: bool) {
    for (var k = first; k < first + count; k++) {
        let h = pt_intersect_triangle(k, r, (*s).t_max);
        if h.x > 0.0 {
            (*s).t_max = h.x;
            (*s).best = PtHit(h.x, h.y, h.z, k);
            (*s).found = true;
            if any_hit {
                return;
            }
        }
    }
}

// The slab test of one half's four children: (near, entered) with near ≤ far.
struct PtHalf {
    near: vec4f,
    entered: vec4<bool>,
}

fn pt_half(n: PtWideNode, r: PtRay, t_max: f32) -> PtHalf {
    let t0x = (n.lo_x - r.o.x) * r.inv.x;
    let t1x = (n.hi_x - r.o.x) * r.inv.x;
    let t0y = (n.lo_y - r.o.y) * r.inv.y;
    let t1y = (n.hi_y - r.o.y) * r.inv.y;
    let t0z = (n.lo_z - r.o.z) * r.inv.z;
    let t1z = (n.hi_z - r.o.z) * r.inv.z;
    let near = max(max(min(t0x, t1x), min(t0y, t1y)), max(min(t0z, t1z), vec4f(r.t_min)));
    let far = min(min(max(t0x, t1x), max(t0y, t1y)), min(max(t0z, t1z), vec4f(t_max)));
    return PtHalf(near, (near <= far) & (n.count != vec4u(PT_WIDE_EMPTY)));
}

// One half's child nodes still in reach, sorted nearest first; unreached ones last with
// t = PT_MISS. Returns (t, child) as a vec4f and a vec4u.
struct PtSorted {
    t: vec4f,
    c: vec4u,
}

fn pt_sorted_half(n: PtWideNode, h: PtHalf, t_max: f32) -> PtSorted {
    let inner = h.entered & (n.count == vec4u(0u)) & (h.near <= vec4f(t_max));
    var t = select(vec4f(PT_MISS), h.near, inner);
    var c = n.index;
    if t.y < t.x { t = t.yxzw; c = c.yxzw; }
    if t.w < t.z { t = t.xywz; c = c.xywz; }
    if t.z < t.x { t = t.zyxw; c = c.zyxw; }
    if t.w < t.y { t = t.xwzy; c = c.xwzy; }
    if t.z < t.y { t = t.xzyw; c = c.xzyw; }
    return PtSorted(t, c);
}

// The closest triangle hit in (t_min, t_max), or with `any_hit` the first found (shapes.wgsl
// adds the analytic shapes).
fn pt_trace_triangles(o: vec3f, d: vec3f, t_min: f32, t_max_in: f32, any_hit: bool) -> PtHit {
    var s = PtWideState(t_max_in, PtHit(t_max_in, 0.0, 0.0, PT_NO_HIT), false);
    if pt_params.node_count == 0u {
        return s.best;
    }
    let r = pt_make_ray(o, d, t_min);
    var stack: PtStack;
    var node = 0u;
    loop {
        let a = pt_nodes[node];
        let b = pt_nodes[node + 1u];
        let ha = pt_half(a, r, s.t_max);
        let hb = pt_half(b, r, s.t_max);
        let la = ha.entered & (a.count > vec4u(0u));
        let lb = hb.entered & (b.count > vec4u(0u));
        if la.x {
            pt_wide_leaf(a.index.x, a.count.x, r, &s, any_hit);
        }
        if la.y && !(any_hit && s.found) {
            pt_wide_leaf(a.index.y, a.count.y, r, &s, any_hit);
        }
        if la.z && !(any_hit && s.found) {
            pt_wide_leaf(a.index.z, a.count.z, r, &s, any_hit);
        }
        if la.w && !(any_hit && s.found) {
            pt_wide_leaf(a.index.w, a.count.w, r, &s, any_hit);
        }
        if lb.x && !(any_hit && s.found) {
            pt_wide_leaf(b.index.x, b.count.x, r, &s, any_hit);
        }
        if lb.y && !(any_hit && s.found) {
            pt_wide_leaf(b.index.y, b.count.y, r, &s, any_hit);
        }
        if lb.z && !(any_hit && s.found) {
            pt_wide_leaf(b.index.z, b.count.z, r, &s, any_hit);
        }
        if lb.w && !(any_hit && s.found) {
            pt_wide_leaf(b.index.w, b.count.w, r, &s, any_hit);
        }
        if any_hit && s.found {
            return s.best;
        }
        let sa = pt_sorted_half(a, ha, s.t_max);
        let sb = pt_sorted_half(b, hb, s.t_max);
        // Batcher's odd–even merge of the sorted halves (t0..t3, t4..t7): compare–exchange
        // (0,4) (1,5) (2,6) (3,7), then (2,4) (3,5), then (1,2) (3,4) (5,6).
        let swap1 = sb.t < sa.t;
        var lo_t = select(sa.t, sb.t, swap1);
        var lo_c = select(sa.c, sb.c, swap1);
        var hi_t = select(sb.t, sa.t, swap1);
        var hi_c = select(sb.c, sa.c, swap1);
        var t0 = lo_t.x; var t1 = lo_t.y; var t2 = lo_t.z; var t3 = lo_t.w;
        var t4 = hi_t.x; var t5 = hi_t.y; var t6 = hi_t.z; var t7 = hi_t.w;
        var c0 = lo_c.x; var c1 = lo_c.y; var c2 = lo_c.z; var c3 = lo_c.w;
        var c4 = hi_c.x; var c5 = hi_c.y; var c6 = hi_c.z; var c7 = hi_c.w;
        var tt: f32;
        var cc: u32;
        if t4 < t2 { tt = t2; t2 = t4; t4 = tt; cc = c2; c2 = c4; c4 = cc; }
        if t5 < t3 { tt = t3; t3 = t5; t5 = tt; cc = c3; c3 = c5; c5 = cc; }
        if t2 < t1 { tt = t1; t1 = t2; t2 = tt; cc = c1; c1 = c2; c2 = cc; }
        if t4 < t3 { tt = t3; t3 = t4; t4 = tt; cc = c3; c3 = c4; c4 = cc; }
        if t6 < t5 { tt = t5; t5 = t6; t6 = tt; cc = c5; c5 = c6; c6 = cc; }
        if t0 < PT_MISS {
            // Push the farther ones farthest first; visit the nearest.
            if t7 < PT_MISS {
                pt_push(&stack, c7, t7);
            }
            if t6 < PT_MISS {
                pt_push(&stack, c6, t6);
            }
            if t5 < PT_MISS {
                pt_push(&stack, c5, t5);
            }
            if t4 < PT_MISS {
                pt_push(&stack, c4, t4);
            }
            if t3 < PT_MISS {
                pt_push(&stack, c3, t3);
            }
            if t2 < PT_MISS {
                pt_push(&stack, c2, t2);
            }
            if t1 < PT_MISS {
                pt_push(&stack, c1, t1);
            }
            node = c0;
            continue;
        }
        node = pt_pop(&stack, s.t_max);
        if node == PT_NO_HIT {
            return s.best;
        }
    }
    return s.best;
}
