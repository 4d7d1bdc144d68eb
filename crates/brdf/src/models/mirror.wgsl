// The perfect mirror (crates/brdf/src/models/mirror.rs): a delta at the mirror direction.

fn mirror_eval(p: MirrorParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    return vec4f(0.0);
}

fn mirror_pdf(p: MirrorParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    return 0.0;
}

fn mirror_sample(p: MirrorParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 {
        return mat_no_sample();
    }
    let wi = mat_reflect_local(wo);
    return BsdfSample(wi, spectrum_at(p.reflectance, lambda) / abs(wi.z), 1.0, SCATTER_REFLECTION | SCATTER_SPECULAR);
}
