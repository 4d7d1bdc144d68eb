// The watertight ray–triangle test (Woop, Benthin & Wald, JCGT 2013), mirroring
// `bvh::intersect_triangle_watertight` (crates/bvh/src/triangle.rs); compiled in for
// `--triangle-test watertight`.

// The watertight test against leaf-order triangle i: (t, u, v), t < 0 for a miss.
//
// No f64 in WGSL: where the CPU redoes an edge function that came out exactly 0 in double
// precision, this keeps the f32 zero, which the sign test treats as "on the edge" — a hit
// for both triangles sharing it (closest-hit picks either), never a leak.
fn pt_intersect_triangle(i: u32, r: PtRay, t_max: f32) -> vec3f {
    let pa = pt_tri_verts[3u * i].xyz - r.o;
    let pb = pt_tri_verts[3u * i + 1u].xyz - r.o;
    let pc = pt_tri_verts[3u * i + 2u].xyz - r.o;
    let ax = pa[r.kx] - r.shear.x * pa[r.kz];
    let ay = pa[r.ky] - r.shear.y * pa[r.kz];
    let az = r.shear.z * pa[r.kz];
    let bx = pb[r.kx] - r.shear.x * pb[r.kz];
    let by = pb[r.ky] - r.shear.y * pb[r.kz];
    let bz = r.shear.z * pb[r.kz];
    let cx = pc[r.kx] - r.shear.x * pc[r.kz];
    let cy = pc[r.ky] - r.shear.y * pc[r.kz];
    let cz = r.shear.z * pc[r.kz];
    let e0 = cx * by - cy * bx;
    let e1 = ax * cy - ay * cx;
    let e2 = bx * ay - by * ax;
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return vec3f(-1.0);
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return vec3f(-1.0);
    }
    let inv_det = 1.0 / det;
    let t = (e0 * az + e1 * bz + e2 * cz) * inv_det;
    if t > r.t_min && t < t_max {
        return vec3f(t, e1 * inv_det, e2 * inv_det);
    }
    return vec3f(-1.0);
}
