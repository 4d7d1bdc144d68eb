// Möller–Trumbore ray–triangle intersection (JGT 1997), mirroring
// `bvh::intersect_triangle` (crates/bvh/src/triangle.rs); compiled in for
// `--triangle-test moller-trumbore`. Edges are formed from the leaf-order vertices as
// the CPU's `Triangle` forms them (v1 − v0, v2 − v0).

// Möller–Trumbore against leaf-order triangle i: (t, u, v), t < 0 for a miss.
fn pt_intersect_triangle(i: u32, r: PtRay, t_max: f32) -> vec3f {
    let v0 = pt_tri_verts[3u * i].xyz;
    let e1 = pt_tri_verts[3u * i + 1u].xyz - v0;
    let e2 = pt_tri_verts[3u * i + 2u].xyz - v0;
    let p = cross(r.d, e2);
    let det = dot(e1, p);
    if det == 0.0 || !pt_is_finite(det) {
        return vec3f(-1.0);
    }
    let inv_det = 1.0 / det;
    let s = r.o - v0;
    let u = dot(s, p) * inv_det;
    if !(u >= 0.0 && u <= 1.0) {
        return vec3f(-1.0);
    }
    let q = cross(s, e1);
    let v = dot(r.d, q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return vec3f(-1.0);
    }
    let t = dot(e2, q) * inv_det;
    if t > r.t_min && t < t_max {
        return vec3f(t, u, v);
    }
    return vec3f(-1.0);
}
