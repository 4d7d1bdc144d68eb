// The smooth conductor (crates/brdf/src/models/conductor.rs): a delta at the mirror
// direction weighted by the conductor Fresnel reflectance per wavelength.

fn conductor_eval(p: ConductorParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    return vec4f(0.0);
}

fn conductor_pdf(p: ConductorParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    return 0.0;
}

fn conductor_sample(p: ConductorParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 || !mat_finite(wo.z) {
        return mat_no_sample();
    }
    let wi = mat_reflect_local(wo);
    let ek = mat_metal_eta_k(p.metal, p.eta, p.k, lambda);
    let f = mat_conductor_fresnel4(wo.z, ek, spectrum_at(p.tint, lambda)) / abs(wi.z);
    return BsdfSample(wi, f, 1.0, SCATTER_REFLECTION | SCATTER_SPECULAR);
}
