// Robust ray origins, mirroring crates/shapes/src/offset.rs (Wächter & Binder, Ray
// Tracing Gems ch. 6); PT_OFFSET_* are generated from its constants.

// Wächter & Binder (Ray Tracing Gems ch. 6), as `shapes::offset::offset_ray_origin`.
fn pt_offset_ray_origin(p: vec3f, n: vec3f) -> vec3f {
    let shift = vec3i(PT_OFFSET_INT_SCALE * n);
    let bits = bitcast<vec3i>(p);
    let moved = bitcast<vec3f>(select(bits + shift, bits - shift, p < vec3f(0.0)));
    return select(moved, p + PT_OFFSET_FLOAT_SCALE * n, abs(p) < vec3f(PT_OFFSET_ORIGIN));
}
