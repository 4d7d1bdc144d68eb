// What the 4- and 8-wide traversals (traversal_wide.wgsl, traversal_wide8.wgsl) share, for
// the wide nodes built by crates/gpu/src/wide.rs: the traversal state, the leaf test, the
// slab test of one node's four boxes and the nearest-first order of its child nodes (a
// sorting network: unrolled, no loop over the slots, see wide.rs for why).

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
            (*s).best = PtHit(h.x, h.y, h.z, k, PT_NO_HIT);
            (*s).found = true;
            if any_hit {
                return;
            }
        }
    }
}

// Tests the leaf children `leaf` of node `n` in slot order (stopping at the first hit with
// `any_hit`).
fn pt_wide_leaves(n: PtWideNode, leaf: vec4<bool>, r: PtRay, s: ptr<function, PtWideState>, any_hit: bool) {
    if leaf.x {
        pt_wide_leaf(n.index.x, n.count.x, r, s, any_hit);
    }
    if leaf.y && !(any_hit && (*s).found) {
        pt_wide_leaf(n.index.y, n.count.y, r, s, any_hit);
    }
    if leaf.z && !(any_hit && (*s).found) {
        pt_wide_leaf(n.index.z, n.count.z, r, s, any_hit);
    }
    if leaf.w && !(any_hit && (*s).found) {
        pt_wide_leaf(n.index.w, n.count.w, r, s, any_hit);
    }
}

// The slab test of a node's four children: their entry distances, and which are entered
// within (t_min, t_max] (used slots only).
struct PtBoxes {
    near: vec4f,
    entered: vec4<bool>,
}

fn pt_wide_boxes(n: PtWideNode, r: PtRay, t_max: f32) -> PtBoxes {
    let t0x = (n.lo_x - r.o.x) * r.inv.x;
    let t1x = (n.hi_x - r.o.x) * r.inv.x;
    let t0y = (n.lo_y - r.o.y) * r.inv.y;
    let t1y = (n.hi_y - r.o.y) * r.inv.y;
    let t0z = (n.lo_z - r.o.z) * r.inv.z;
    let t1z = (n.hi_z - r.o.z) * r.inv.z;
    let near = max(max(min(t0x, t1x), min(t0y, t1y)), max(min(t0z, t1z), vec4f(r.t_min)));
    let far = min(min(max(t0x, t1x), max(t0y, t1y)), min(max(t0z, t1z), vec4f(t_max)));
    return PtBoxes(near, (near <= far) & (n.count != vec4u(PT_WIDE_EMPTY)));
}

// A node's child nodes still in reach (entry ≤ t_max), nearest first, as (t, child);
// the others sort last with t = PT_MISS.
struct PtOrder {
    t: vec4f,
    c: vec4u,
}

fn pt_wide_order(n: PtWideNode, b: PtBoxes, t_max: f32) -> PtOrder {
    let inner = b.entered & (n.count == vec4u(0u)) & (b.near <= vec4f(t_max));
    var t = select(vec4f(PT_MISS), b.near, inner);
    var c = n.index;
    if t.y < t.x { t = t.yxzw; c = c.yxzw; }
    if t.w < t.z { t = t.xywz; c = c.xywz; }
    if t.z < t.x { t = t.zyxw; c = c.zyxw; }
    if t.w < t.y { t = t.xwzy; c = c.xwzy; }
    if t.z < t.y { t = t.xzyw; c = c.xzyw; }
    return PtOrder(t, c);
}
