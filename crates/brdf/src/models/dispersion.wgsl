// Wavelength-dependent index of refraction, mirroring
// crates/brdf/src/models/dispersion.rs (Dispersion, Sellmeier); the coefficients are
// generated from that file's constants. Only compiled in when a material disperses.

// Sellmeier::ior: n² = 1 + Σ Bᵢλ²/(λ² − Cᵢ), λ in µm.
fn mat_sellmeier(b: vec3f, c: vec3f, lambda_nm: f32) -> f32 {
    let l = lambda_nm * 1e-3;
    let l2 = l * l;
    var n2 = 1.0;
    n2 += b.x * l2 / (l2 - c.x);
    n2 += b.y * l2 / (l2 - c.y);
    n2 += b.z * l2 / (l2 - c.z);
    return sqrt(max(n2, 1e-6));
}

// Dispersion::from_preset(preset, cauchy_b).ior(ior, λ): the DispersionPreset choice
// (none, Cauchy anchored at n(λ_d) = ior, N-BK7, fused silica).
// RGB mode has no wavelengths: the base index, as the CPU's dielectrics use it there.
fn mat_dispersion_ior(preset: u32, cauchy_b: f32, ior: f32, lambda_nm: f32) -> f32 {
    if MAT_RGB {
        return ior;
    }
    if preset == MAT_DISPERSION_CAUCHY {
        let l = lambda_nm * 1e-3;
        let ld = MAT_LAMBDA_D * 1e-3;
        return ior + cauchy_b * (1.0 / (l * l) - 1.0 / (ld * ld));
    }
    if preset == MAT_DISPERSION_BK7 {
        return mat_sellmeier(MAT_BK7_B, MAT_BK7_C, lambda_nm);
    }
    if preset == MAT_DISPERSION_FUSED_SILICA {
        return mat_sellmeier(MAT_FUSED_SILICA_B, MAT_FUSED_SILICA_C, lambda_nm);
    }
    return ior;
}
