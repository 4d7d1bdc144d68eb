//! CIE XYZ ↔ linear sRGB (Rec. 709 primaries, D65 white) and the sRGB transfer curve.
//!
//! The matrices follow IEC 61966-2-1 with the primaries' chromaticities (0.64, 0.33),
//! (0.30, 0.60), (0.15, 0.06) and the D65 white (0.3127, 0.3290), derived in full
//! precision rather than the rounded 4-digit matrix, so that D65 maps to (1, 1, 1) to
//! ~1e-7. The thesis (eq. 4.3–4.12) instead normalises by X+Y+Z and uses other
//! primaries with an equal-energy white, which turns D65 light blue; see [`crate::thesis`].

// Published constants are kept at the precision they were published with.
#![allow(clippy::excessive_precision)]

use crate::tables::{CIE_LAMBDA_MIN, CIE_SAMPLES, CIE_X, CIE_Y, CIE_Y_INTEGRAL, CIE_Z};

/// Row-major 3×3 matrix taking CIE XYZ (Y = 1 for the white) to linear sRGB.
pub const XYZ_TO_SRGB: [[f32; 3]; 3] = [
    [3.240_969_9, -1.537_383_2, -0.498_610_76],
    [-0.969_243_6, 1.875_967_5, 0.041_555_06],
    [0.055_630_08, -0.203_976_96, 1.056_971_5],
];

/// Row-major 3×3 matrix taking linear sRGB to CIE XYZ; inverse of [`XYZ_TO_SRGB`].
pub const SRGB_TO_XYZ: [[f32; 3]; 3] = [
    [0.412_390_8, 0.357_584_33, 0.180_480_8],
    [0.212_639, 0.715_168_66, 0.072_192_32],
    [0.019_330_818, 0.119_194_78, 0.950_532_14],
];

/// Applies a row-major 3×3 matrix to a vector.
#[inline]
pub fn mul3(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// CIE XYZ → linear sRGB.
#[inline]
pub fn xyz_to_linear_srgb(xyz: [f32; 3]) -> [f32; 3] {
    mul3(&XYZ_TO_SRGB, xyz)
}

/// Linear sRGB → CIE XYZ.
#[inline]
pub fn linear_srgb_to_xyz(rgb: [f32; 3]) -> [f32; 3] {
    mul3(&SRGB_TO_XYZ, rgb)
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1), for 8-bit output.
#[inline]
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 { 12.92 * linear.max(0.0) } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 }
}

/// Inverse of [`srgb_encode`].
#[inline]
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.040_45 { encoded / 12.92 } else { ((encoded + 0.055) / 1.055).powf(2.4) }
}

/// Linear value → 8-bit sRGB code value, clamped to [0, 255] and rounded.
#[inline]
pub fn srgb_to_u8(linear: f32) -> u8 {
    (srgb_encode(linear).clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// The CIE 1931 colour-matching functions at `lambda` (nm), linearly interpolated
/// from the 1 nm tables; zero outside 360–830 nm. Branch-free (the tables are read at
/// index 0 outside them, and the result replaced by zeros), so that a loop over many
/// wavelengths vectorises.
#[inline]
pub fn cie_xyz(lambda: f32) -> [f32; 3] {
    let x = lambda - CIE_LAMBDA_MIN;
    let inside = (0.0..=(CIE_SAMPLES - 1) as f32).contains(&x);
    let x_in = if inside { x } else { 0.0 };
    // SAFETY: x_in lies in [0, CIE_SAMPLES − 1], which an i32 holds.
    let i = (unsafe { x_in.to_int_unchecked::<i32>() } as usize).min(CIE_SAMPLES - 2);
    let f = x - i as f32;
    let lerp = |t: &[f32; CIE_SAMPLES]| if inside { t[i] + (t[i + 1] - t[i]) * f } else { 0.0 };
    [lerp(&CIE_X), lerp(&CIE_Y), lerp(&CIE_Z)]
}

/// CIE XYZ of a spectral radiance (or of a reflectance seen under an equal-energy
/// light), integrated at 1 nm over 360–830 nm and normalised by ∫ȳ so that a constant
/// spectrum of 1 has Y = 1.
pub fn spectrum_to_xyz(spectrum: impl Fn(f32) -> f32) -> [f32; 3] {
    let mut xyz = [0.0f64; 3];
    for i in 0..CIE_SAMPLES {
        let v = spectrum(CIE_LAMBDA_MIN + i as f32) as f64;
        xyz[0] += v * CIE_X[i] as f64;
        xyz[1] += v * CIE_Y[i] as f64;
        xyz[2] += v * CIE_Z[i] as f64;
    }
    let n = CIE_Y_INTEGRAL as f64;
    [(xyz[0] / n) as f32, (xyz[1] / n) as f32, (xyz[2] / n) as f32]
}

/// Linear sRGB of a spectral radiance: [`spectrum_to_xyz`] then [`xyz_to_linear_srgb`].
pub fn spectrum_to_linear_srgb(spectrum: impl Fn(f32) -> f32) -> [f32; 3] {
    xyz_to_linear_srgb(spectrum_to_xyz(spectrum))
}
