// Ray casting in the 8-wide BVH built by crates/gpu/src/wide.rs: a node is two PtWideNode
// entries (children 0–3, then 4–7), each slab-tested as in traversal_wide.wgsl. Leaf
// children are intersected first (shrinking t_max before anything is pushed); the child
// nodes hit are sorted nearest first (each half by a sorting network, then Batcher's
// odd–even merge of the two sorted halves), the nearest visited and the others pushed
// farthest first with their entry distances; nodes beyond the closest hit are culled on
// the way back. Everything is unrolled: no loop over the slots (see wide.rs for why).
// The state, leaf test, slab test and each half's order are traversal_wide_nodes.wgsl's.
// PT_STACK is the tree's own bound.

// The closest triangle hit of the ray `r` in (r.t_min, t_max) in the tree whose root is
// node `root` (the world's, 0, or a placed object's), or with `any_hit` the first found
// (shapes.wgsl adds the analytic shapes and the instances).
fn pt_trace_triangles(root: u32, r: PtRay, t_max_in: f32, any_hit: bool) -> PtHit {
    var s = PtWideState(t_max_in, PtHit(t_max_in, 0.0, 0.0, PT_NO_HIT, PT_NO_HIT), false);
    var stack: PtStack;
    var node = root;
    loop {
        let a = pt_nodes[node];
        let b = pt_nodes[node + 1u];
        let ha = pt_wide_boxes(a, r, s.t_max);
        let hb = pt_wide_boxes(b, r, s.t_max);
        pt_wide_leaves(a, ha.entered & (a.count > vec4u(0u)), r, &s, any_hit);
        if !(any_hit && s.found) {
            pt_wide_leaves(b, hb.entered & (b.count > vec4u(0u)), r, &s, any_hit);
        }
        if any_hit && s.found {
            return s.best;
        }
        let sa = pt_wide_order(a, ha, s.t_max);
        let sb = pt_wide_order(b, hb, s.t_max);
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
            pt_push_reached(&stack, c7, t7);
            pt_push_reached(&stack, c6, t6);
            pt_push_reached(&stack, c5, t5);
            pt_push_reached(&stack, c4, t4);
            pt_push_reached(&stack, c3, t3);
            pt_push_reached(&stack, c2, t2);
            pt_push_reached(&stack, c1, t1);
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
