// Helpers every BSDF model may use: hand-written, mirroring crates/brdf/src/frame.rs
// (flip_z, reflect, reflect_local), crates/brdf/src/fresnel.rs (refract_local) and Rust's
// f32 library where WGSL lacks a function. Everything
// here is named mat_* / MAT_* so that it cannot collide with the path kernel.

const MAT_PI: f32 = 3.14159265358979323846264338327950288;
const MAT_TAU: f32 = 6.28318530717958647692528676655900577;
const MAT_FRAC_1_PI: f32 = 0.318309886183790671537767526745028724;
const MAT_FRAC_PI_2: f32 = 1.57079632679489661923132169163975144;
const MAT_FRAC_PI_4: f32 = 0.785398163397448309615660845819875721;

// The linear interpolation in a 1-nm table the contract promises: `offset` is the
// table's first entry in `spectra` (λ = SPECTRUM_LAMBDA_MIN), λ is clamped to the table.
// In RGB mode (MAT_RGB, declared by the generated code) a colour's linear-sRGB value,
// stored after its table, instead (`Colour::sample`'s RGB case).
// With textures (MAT_TEXTURES, generated), the tables of a textured parameter (its own
// copy) come out multiplied by the hit's texel.
fn spectrum_at(offset: u32, lambda: vec4f) -> vec4f {
    let v = mat_table_at(offset, lambda);
    if MAT_TEXTURES {
        if offset == mat_tex_base_at {
            return v * mat_tex_base;
        }
        if offset == mat_tex_spec_at {
            return v * mat_tex_spec;
        }
    }
    return v;
}

fn mat_table_at(offset: u32, lambda: vec4f) -> vec4f {
    if MAT_RGB {
        let o = offset + SPECTRUM_SAMPLES;
        return vec4f(spectra[o], spectra[o + 1u], spectra[o + 2u], 0.0);
    }
    let last = f32(SPECTRUM_SAMPLES - 1u);
    let x = clamp(lambda - vec4f(SPECTRUM_LAMBDA_MIN), vec4f(0.0), vec4f(last));
    let i = min(vec4u(x), vec4u(SPECTRUM_SAMPLES - 2u));
    let t = x - vec4f(i);
    let o = vec4u(offset) + i;
    let a = vec4f(spectra[o.x], spectra[o.y], spectra[o.z], spectra[o.w]);
    let b = vec4f(spectra[o.x + 1u], spectra[o.y + 1u], spectra[o.z + 1u], spectra[o.w + 1u]);
    return a + t * (b - a);
}

// Rust's f32::is_finite, by the exponent bits (WGSL has no isnan/isinf, and drivers may
// fold `x != x` away).
fn mat_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn mat_finite3(v: vec3f) -> bool {
    return mat_finite(v.x) && mat_finite(v.y) && mat_finite(v.z);
}

fn mat_finite4(v: vec4f) -> bool {
    return mat_finite(v.x) && mat_finite(v.y) && mat_finite(v.z) && mat_finite(v.w);
}

// ln(1 + x) for x > -1, accurate to a few ulp near 0 (Rust's ln_1p; WGSL has none, and
// GPU `log` is only absolutely accurate near 1: Vulkan allows 2^-21 on [0.5, 2]).
// |x| < 1/2: ln(1 + x) = 2 atanh(z) = 2 Σ z^(2n+1)/(2n+1) with z = x/(2 + x), |z| ≤ 1/3;
// the terms up to z^17 leave a relative error below 2e-10.
fn mat_log1p(x: f32) -> f32 {
    if abs(x) < 0.5 {
        let z = x / (2.0 + x);
        let z2 = z * z;
        let s = 1.0 + z2 * (1.0 / 3.0 + z2 * (1.0 / 5.0 + z2 * (1.0 / 7.0 + z2 * (1.0 / 9.0 + z2 * (1.0 / 11.0
            + z2 * (1.0 / 13.0 + z2 * (1.0 / 15.0 + z2 * (1.0 / 17.0))))))));
        return 2.0 * z * s;
    }
    return log(1.0 + x);
}

// e^x − 1, accurate near 0 (Rust's exp_m1): |x| < 1/2 by its Taylor series to x^11/11!
// (relative error below 1e-10), else exp(x) − 1, which does not cancel there.
fn mat_expm1(x: f32) -> f32 {
    if abs(x) < 0.5 {
        return x * (1.0 + x / 2.0 * (1.0 + x / 3.0 * (1.0 + x / 4.0 * (1.0 + x / 5.0 * (1.0 + x / 6.0 * (1.0
            + x / 7.0 * (1.0 + x / 8.0 * (1.0 + x / 9.0 * (1.0 + x / 10.0 * (1.0 + x / 11.0))))))))));
    }
    return exp(x) - 1.0;
}

// (cos φ, sin φ) for φ in [0, 2π]: reduced to [−π, π] first (exactly: φ − 2π is exact
// there), the range in which Vulkan bounds the error of sin and cos.
fn mat_cos_sin(phi: f32) -> vec2f {
    var x = phi;
    if x > MAT_PI {
        x = x - MAT_TAU;
    }
    return vec2f(cos(x), sin(x));
}

// glam's Vec3::normalize: v times the reciprocal of its length.
fn mat_normalize(v: vec3f) -> vec3f {
    return v * (1.0 / length(v));
}

// glam's Vec3::normalize_or: the fallback where the length is zero or not finite.
fn mat_normalize_or(v: vec3f, fallback: vec3f) -> vec3f {
    let rcp = 1.0 / length(v);
    if mat_finite(rcp) && rcp > 0.0 {
        return v * rcp;
    }
    return fallback;
}

fn mat_flip_z(w: vec3f) -> vec3f {
    return vec3f(w.x, w.y, -w.z);
}

// brdf::fresnel::reflect_local: the mirror direction about the normal (0, 0, 1).
fn mat_reflect_local(wo: vec3f) -> vec3f {
    return vec3f(-wo.x, -wo.y, wo.z);
}

// Reflection of w about the unit vector h (microfacet models).
fn mat_reflect(w: vec3f, h: vec3f) -> vec3f {
    return 2.0 * dot(w, h) * h - w;
}

// brdf::fresnel::refract_local: Snell refraction through z = 0, η = n_inside/n_outside,
// +z outside; (ωt, 1), or all zero under total internal reflection.
fn mat_refract_local(wo: vec3f, eta: f32) -> vec4f {
    var n = 1.0;
    var etap = eta;
    var cos_i = wo.z;
    if wo.z < 0.0 {
        n = -1.0;
        etap = 1.0 / eta;
        cos_i = -wo.z;
    }
    let sin2_t = max(1.0 - cos_i * cos_i, 0.0) / (etap * etap);
    if sin2_t >= 1.0 {
        return vec4f(0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return vec4f(-wo / etap + vec3f(0.0, 0.0, n * (cos_i / etap - cos_t)), 1.0);
}

// "No sample" (the CPU's None).
fn mat_no_sample() -> BsdfSample {
    return BsdfSample(vec3f(0.0), vec4f(0.0), 0.0, 0u);
}

// The mean of the lanes (four; three in RGB mode), summed in the order
// SampledSpectrum::average sums.
fn mat_average(v: vec4f) -> f32 {
    // RGB mode has three lanes (the CPU's N = 3).
    if MAT_RGB {
        return ((v.x + v.y) + v.z) / 3.0;
    }
    return (((v.x + v.y) + v.z) + v.w) / 4.0;
}
