// Orthonormal shading frames, mirroring crates/brdf/src/frame.rs.

struct PtFrame {
    s: vec3f,
    t: vec3f,
    n: vec3f,
}

// `Frame::from_normal` (Duff et al. 2017), with copysign's treatment of −0.
fn pt_frame_from_normal(n: vec3f) -> PtFrame {
    let sign = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return PtFrame(
        vec3f(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3f(b, sign + n.y * n.y * a, -n.y),
        n,
    );
}

// `Frame::from_normal_tangent`: Gram–Schmidt of the tangent against n, else `from_normal`.
fn pt_frame_from_normal_tangent(n: vec3f, tangent: vec3f) -> PtFrame {
    let s = tangent - n * dot(n, tangent);
    let len2 = dot(s, s);
    if !(len2 > 1e-8 * dot(tangent, tangent)) {
        return pt_frame_from_normal(n);
    }
    let sn = s / sqrt(len2);
    return PtFrame(sn, cross(n, sn), n);
}

fn pt_to_local(f: PtFrame, v: vec3f) -> vec3f {
    return vec3f(dot(v, f.s), dot(v, f.t), dot(v, f.n));
}

fn pt_to_world(f: PtFrame, v: vec3f) -> vec3f {
    return f.s * v.x + f.t * v.y + f.n * v.z;
}
