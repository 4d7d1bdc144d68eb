// Hero-wavelength sampling and the conversion to linear sRGB, mirroring
// crates/spectral/src/sampled.rs (`SampledWavelengths::<4>::sample_hero`,
// `to_linear_srgb`) and colour.rs (`cie_xyz`). PT_VIS_*, PT_CIE_* and PT_XYZ_TO_SRGB are
// generated from the Rust constants.

struct PtWavelengths {
    lambda: vec4f,
    weight: vec4f,
    collapsed: bool,
}

// `SampledWavelengths::<4>::sample_hero`.
fn pt_sample_hero(u: f32) -> PtWavelengths {
    var wl: PtWavelengths;
    for (var i = 0u; i < 4u; i++) {
        let ui = fract(u + f32(i) / 4.0);
        let t = clamp(PT_VIS_TANH_LO + ui * (PT_VIS_TANH_HI - PT_VIS_TANH_LO), -0.999999, 0.999999);
        wl.lambda[i] = clamp(PT_VIS_CENTRE + atanh(t) / PT_VIS_K, PT_LAMBDA_MIN, PT_LAMBDA_MAX);
        let pdf = PT_VIS_K * (1.0 - t * t) / (PT_VIS_TANH_HI - PT_VIS_TANH_LO);
        wl.weight[i] = 1.0 / (4.0 * pdf);
    }
    wl.collapsed = false;
    return wl;
}

// `SampledWavelengths::rgb` for the kernel: RGB mode's channels carry the wavelengths at
// which metals take their (n, k) per channel (`RGB_LAMBDA`; the fourth lane repeats blue
// and carries nothing: its weight is 0).
fn pt_rgb_wavelengths() -> PtWavelengths {
    return PtWavelengths(PT_RGB_LAMBDA, vec4f(1.0, 1.0, 1.0, 0.0), false);
}

// Group `g` of bins40's fixed wavelengths (`SampledWavelengths::fixed_bins(380, 10)`):
// lanes 4g..4g+3, each with the Riemann weight of its 10-nm bin.
fn pt_bins_wavelengths(g: u32) -> PtWavelengths {
    let first = 380.0 + 40.0 * f32(g);
    return PtWavelengths(first + vec4f(0.0, 10.0, 20.0, 30.0), vec4f(10.0), false);
}

// `spectral::colour::cie_xyz`: the 1 nm tables, linearly interpolated.
fn pt_cie_xyz(lambda: f32) -> vec3f {
    let x = lambda - PT_CIE_LAMBDA_MIN;
    if !(x >= 0.0 && x <= f32(PT_CIE_SAMPLES - 1u)) {
        return vec3f(0.0);
    }
    let i = min(u32(x), PT_CIE_SAMPLES - 2u);
    let f = x - f32(i);
    let a = vec3f(pt_tables[3u * i], pt_tables[3u * i + 1u], pt_tables[3u * i + 2u]);
    let b = vec3f(pt_tables[3u * i + 3u], pt_tables[3u * i + 4u], pt_tables[3u * i + 5u]);
    return a + (b - a) * f;
}

// `SampledWavelengths::to_linear_srgb` (RGB mode: the channels themselves).
fn pt_to_linear_srgb(l: vec4f, wl: PtWavelengths) -> vec3f {
    if PT_RGB {
        return l.xyz;
    }
    var xyz = vec3f(0.0);
    for (var i = 0u; i < 4u; i++) {
        let v = l[i] * wl.weight[i];
        if v != 0.0 {
            xyz += v * pt_cie_xyz(wl.lambda[i]);
        }
    }
    xyz = xyz / PT_CIE_Y_INTEGRAL;
    return vec3f(dot(PT_XYZ_TO_SRGB_R, xyz), dot(PT_XYZ_TO_SRGB_G, xyz), dot(PT_XYZ_TO_SRGB_B, xyz));
}

// True if x is finite, judged on the bits (immune to fast-math folding).
fn pt_is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// True if every component is finite, judged on the bits (immune to fast-math folding).
fn pt_is_finite3(v: vec3f) -> bool {
    let e = bitcast<vec3u>(v) & vec3u(0x7f800000u);
    return all(e != vec3u(0x7f800000u));
}
