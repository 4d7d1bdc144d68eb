// The analytic shapes' hit record, mirroring `SurfaceHit` in crates/shapes/src/lib.rs, and
// the readers of the kernel's tables (`pt_tables`, f32 words: floats, or u32 as their bits)
// that the shape records are read with. Its own file because the implicit surfaces' test
// kernel (crates/gpu/tests/implicit.rs) needs it without the rest of shapes.wgsl.

struct PtShapeHit {
    t: f32,
    p: vec3f,
    n: vec3f,
    hit: bool,
}

fn pt_tv3(i: u32) -> vec3f {
    return vec3f(pt_tables[i], pt_tables[i + 1u], pt_tables[i + 2u]);
}

fn pt_tu(i: u32) -> u32 {
    return bitcast<u32>(pt_tables[i]);
}

fn pt_no_shape_hit() -> PtShapeHit {
    return PtShapeHit(PT_MISS, vec3f(0.0), vec3f(0.0), false);
}
