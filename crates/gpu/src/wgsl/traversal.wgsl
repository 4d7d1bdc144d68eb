// Ray casting: ordered stack traversal of the binary BVH, mirroring crates/bvh/src/build.rs
// (`Bvh::traverse`): nearer child first, the farther pushed with its entry distance, and
// nodes beyond the closest hit culled on the way back. The triangle test
// (`pt_intersect_triangle`, from triangle_*.wgsl) is chosen when the kernel is generated.

// Entry distance into a node's box within (t_min, t_max], or PT_MISS.
fn pt_slab_enter(node: PtNode, r: PtRay, t_max: f32) -> f32 {
    return pt_box_enter(node.min, node.max, r, t_max);
}

// The closest triangle hit of the ray `r` in (r.t_min, t_max) in the tree whose root is
// node `root` (the world's, 0, or a placed object's), or with `any_hit` the first found
// (shapes.wgsl adds the analytic shapes and the instances).
fn pt_trace_triangles(root: u32, r: PtRay, t_max_in: f32, any_hit: bool) -> PtHit {
    var best = PtHit(t_max_in, 0.0, 0.0, PT_NO_HIT, PT_NO_HIT);
    var t_max = t_max_in;
    if pt_slab_enter(pt_nodes[root], r, t_max) >= PT_MISS {
        return best;
    }
    var stack: PtStack;
    var node = root;
    loop {
        let n = pt_nodes[node];
        var descended = false;
        if n.count > 0u {
            for (var i = n.index; i < n.index + n.count; i++) {
                let h = pt_intersect_triangle(i, r, t_max);
                if h.x > 0.0 {
                    t_max = h.x;
                    best = PtHit(h.x, h.y, h.z, i, PT_NO_HIT);
                    if any_hit {
                        return best;
                    }
                }
            }
        } else {
            // Nearer child first; push the farther with its entry distance.
            let l = node + 1u;
            let rr = n.index;
            let tl = pt_slab_enter(pt_nodes[l], r, t_max);
            let tr = pt_slab_enter(pt_nodes[rr], r, t_max);
            var near = l;
            var t_near = tl;
            var far = rr;
            var t_far = tr;
            if tr < tl {
                near = rr;
                t_near = tr;
                far = l;
                t_far = tl;
            }
            if t_near < PT_MISS {
                if t_far < PT_MISS && stack.sp < PT_STACK {
                    pt_push(&stack, far, t_far);
                }
                node = near;
                descended = true;
            }
        }
        if !descended {
            node = pt_pop(&stack, t_max);
            if node == PT_NO_HIT {
                return best;
            }
        }
    }
    return best;
}
