// The smooth dielectric (crates/brdf/src/models/dielectric.rs): reflection with
// probability F, Snell refraction otherwise; a dispersive index is taken at lambda.x (the
// CPU's wl.lambda[0]). mat_dispersion_ior is generated: the Cauchy/Sellmeier code when a
// material disperses, else the constant index.

fn dielectric_eta(p: DielectricParams, lambda: vec4f) -> f32 {
    return mat_dispersion_ior(p.dispersion, p.cauchy_b, p.ior, lambda.x);
}

fn dielectric_eval(p: DielectricParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    return vec4f(0.0);
}

fn dielectric_pdf(p: DielectricParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    return 0.0;
}

fn dielectric_sample(p: DielectricParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z == 0.0 {
        return mat_no_sample();
    }
    let eta = dielectric_eta(p, lambda);
    var r: f32;
    if p.schlick {
        r = mat_fresnel_schlick(wo.z, eta);
    } else {
        r = mat_fresnel_dielectric(wo.z, eta);
    }
    let tint = spectrum_at(p.tint, lambda);
    if uc < r {
        let wi = mat_reflect_local(wo);
        return BsdfSample(wi, tint * (r / abs(wi.z)), r, SCATTER_REFLECTION | SCATTER_SPECULAR);
    }
    let refracted = mat_refract_local(wo, eta);
    if refracted.w == 0.0 {
        return mat_no_sample();
    }
    let wi = refracted.xyz;
    let t = 1.0 - r;
    // Radiance is scaled by 1/η'², η' = n on ωi's side over n on ωo's side.
    var etap = eta;
    if !(wo.z > 0.0) {
        etap = 1.0 / eta;
    }
    return BsdfSample(wi, tint * (t / (abs(wi.z) * etap * etap)), t, SCATTER_TRANSMISSION | SCATTER_SPECULAR);
}
