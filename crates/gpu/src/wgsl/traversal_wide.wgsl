// Ray casting in the 4-wide BVH built by crates/gpu/src/wide.rs (collapsed from the
// binary BVH of crates/bvh/src/build.rs), with the same answers as the binary traversal:
// the four children's boxes are slab-tested at once; leaf children are intersected at
// once (shrinking t_max before anything is pushed); the child nodes hit are visited
// nearest first, the others pushed farthest first with their entry distances, and nodes
// beyond the closest hit are culled on the way back. PT_STACK is the tree's own bound.
// The state, leaf test, slab test and child order are traversal_wide_nodes.wgsl's.

// The closest triangle hit of the ray `r` in (r.t_min, t_max) in the tree whose root is
// node `root` (the world's, 0, or a placed object's), or with `any_hit` the first found
// (shapes.wgsl adds the analytic shapes and the instances).
fn pt_trace_triangles(root: u32, r: PtRay, t_max_in: f32, any_hit: bool) -> PtHit {
    var s = PtWideState(t_max_in, PtHit(t_max_in, 0.0, 0.0, PT_NO_HIT, PT_NO_HIT), false);
    var stack: PtStack;
    var node = root;
    loop {
        let n = pt_nodes[node];
        let boxes = pt_wide_boxes(n, r, s.t_max);
        pt_wide_leaves(n, boxes.entered & (n.count > vec4u(0u)), r, &s, any_hit);
        if any_hit && s.found {
            return s.best;
        }
        let order = pt_wide_order(n, boxes, s.t_max);
        let t = order.t;
        let c = order.c;
        if t.x < PT_MISS {
            // Push the farther ones farthest first; visit the nearest.
            pt_push_reached(&stack, c.w, t.w);
            pt_push_reached(&stack, c.z, t.z);
            pt_push_reached(&stack, c.y, t.y);
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
