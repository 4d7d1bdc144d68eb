// Ray casting in the 4-wide BVH built by crates/gpu/src/wide.rs (collapsed from the
// binary BVH of crates/bvh/src/build.rs), with the same answers as the binary traversal:
// the four children's boxes are slab-tested at once; leaf children are intersected at
// once (shrinking t_max before anything is pushed); the child nodes hit are visited
// nearest first, the others pushed farthest first with their entry distances, and nodes
// beyond the closest hit are culled on the way back. PT_STACK is the tree's own bound.

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
        let n = pt_nodes[node];
        let t0x = (n.lo_x - r.o.x) * r.inv.x;
        let t1x = (n.hi_x - r.o.x) * r.inv.x;
        let t0y = (n.lo_y - r.o.y) * r.inv.y;
        let t1y = (n.hi_y - r.o.y) * r.inv.y;
        let t0z = (n.lo_z - r.o.z) * r.inv.z;
        let t1z = (n.hi_z - r.o.z) * r.inv.z;
        let near = max(max(min(t0x, t1x), min(t0y, t1y)), max(min(t0z, t1z), vec4f(r.t_min)));
        let far = min(min(max(t0x, t1x), max(t0y, t1y)), min(max(t0z, t1z), vec4f(s.t_max)));
        let entered = (near <= far) & (n.count != vec4u(PT_WIDE_EMPTY));
        let leaf = entered & (n.count > vec4u(0u));
        if leaf.x {
            pt_wide_leaf(n.index.x, n.count.x, r, &s, any_hit);
        }
        if leaf.y && !(any_hit && s.found) {
            pt_wide_leaf(n.index.y, n.count.y, r, &s, any_hit);
        }
        if leaf.z && !(any_hit && s.found) {
            pt_wide_leaf(n.index.z, n.count.z, r, &s, any_hit);
        }
        if leaf.w && !(any_hit && s.found) {
            pt_wide_leaf(n.index.w, n.count.w, r, &s, any_hit);
        }
        if any_hit && s.found {
            return s.best;
        }
        // Child nodes still in reach; unreached ones sort last with t = PT_MISS.
        let inner = entered & (n.count == vec4u(0u)) & (near <= vec4f(s.t_max));
        var t = select(vec4f(PT_MISS), near, inner);
        var c = n.index;
        // A sorting network on (t, c), nearest first.
        if t.y < t.x { t = t.yxzw; c = c.yxzw; }
        if t.w < t.z { t = t.xywz; c = c.xywz; }
        if t.z < t.x { t = t.zyxw; c = c.zyxw; }
        if t.w < t.y { t = t.xwzy; c = c.xwzy; }
        if t.z < t.y { t = t.xzyw; c = c.xzyw; }
        if t.x < PT_MISS {
            // Push the farther ones farthest first; visit the nearest.
            if t.w < PT_MISS {
                pt_push(&stack, c.w, t.w);
            }
            if t.z < PT_MISS {
                pt_push(&stack, c.z, t.z);
            }
            if t.y < PT_MISS {
                pt_push(&stack, c.y, t.y);
            }
            node = c.x;
            continue;
        }
        node = pt_pop(&stack, s.t_max);
        if node == PT_NO_HIT {
            return s.best;
        }
    }
    return s.best;
}
