// Which normal a BSDF sees, mirroring crates/tracer/src/shading.rs
// (`adapt_shading_normal`, `shading_normals`); PT_SHADING_* and PT_MIN_SHADING_COSINE are
// generated from the Rust enum and constant.

// `shading::adapt_shading_normal`.
fn pt_adapt_shading_normal(ns: vec3f, ng: vec3f, wo: vec3f) -> vec3f {
    let side = select(-1.0, 1.0, dot(wo, ng) >= 0.0);
    let a = side * dot(wo, ns);
    if a >= PT_MIN_SHADING_COSINE {
        return ns;
    }
    let bent = ns + (PT_MIN_SHADING_COSINE - a) * side * wo;
    let len = length(bent);
    if !(len > 1e-30 && len < PT_FAR) {
        return ng;
    }
    return bent / len;
}

struct PtNormals {
    ng: vec3f,
    ns: vec3f,
}

// `shading::shading_normals`.
fn pt_shading_normals(ng: vec3f, ns: vec3f, wo: vec3f, two_sided: bool) -> PtNormals {
    let front = dot(wo, ng) > 0.0;
    if pt_params.shading == PT_SHADING_FACE_FORWARD {
        if !front {
            return PtNormals(-ng, -ns);
        }
        return PtNormals(ng, ns);
    }
    let a = pt_adapt_shading_normal(ns, ng, wo);
    if two_sided && !front {
        return PtNormals(-ng, -a);
    }
    return PtNormals(ng, a);
}
