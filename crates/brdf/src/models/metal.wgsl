// Measured metals, mirroring crates/brdf/src/models/metal.rs: the (λ, n, k) rows of
// each preset a scene uses are uploaded to `spectra` as they are; mat_metal_table (generated)
// says where: (offset, rows), rows = 0 for a preset not compiled in.

struct MatEtaK {
    eta: vec4f,
    k: vec4f,
}

// metal.rs::interpolate: linear in λ, clamped to the first and last rows (also for NaN).
fn mat_metal_interpolate(table: vec2u, lambda: f32) -> vec2f {
    let base = table.x;
    let last = table.y - 1u;
    if !(lambda > spectra[base]) {
        return vec2f(spectra[base + 1u], spectra[base + 2u]);
    }
    let end = base + 3u * last;
    if lambda >= spectra[end] {
        return vec2f(spectra[end + 1u], spectra[end + 2u]);
    }
    var i = 0u;
    while i + 1u < last && spectra[base + 3u * (i + 1u)] <= lambda {
        i += 1u;
    }
    let a = base + 3u * i;
    let b = a + 3u;
    let t = (lambda - spectra[a]) / (spectra[b] - spectra[a]);
    return vec2f(spectra[a + 1u] + t * (spectra[b + 1u] - spectra[a + 1u]),
        spectra[a + 2u] + t * (spectra[b + 2u] - spectra[a + 2u]));
}

// MetalPreset::eta_k: a measured metal (the `metal` choice; 0 = custom) at each
// wavelength, else the constants (eta, k).
fn mat_metal_eta_k(metal: u32, eta: f32, k: f32, lambda: vec4f) -> MatEtaK {
    if metal != 0u {
        let table = mat_metal_table(metal);
        if table.y > 0u {
            let a = mat_metal_interpolate(table, lambda.x);
            let b = mat_metal_interpolate(table, lambda.y);
            let c = mat_metal_interpolate(table, lambda.z);
            let d = mat_metal_interpolate(table, lambda.w);
            return MatEtaK(vec4f(a.x, b.x, c.x, d.x), vec4f(a.y, b.y, c.y, d.y));
        }
    }
    return MatEtaK(vec4f(eta), vec4f(k));
}

// metal.rs::fresnel_spectrum: tint × the conductor Fresnel reflectance per lane.
fn mat_conductor_fresnel4(cos_i: f32, ek: MatEtaK, tint: vec4f) -> vec4f {
    return tint * vec4f(mat_fresnel_conductor(cos_i, ek.eta.x, ek.k.x), mat_fresnel_conductor(cos_i, ek.eta.y, ek.k.y),
        mat_fresnel_conductor(cos_i, ek.eta.z, ek.k.z), mat_fresnel_conductor(cos_i, ek.eta.w, ek.k.w));
}
