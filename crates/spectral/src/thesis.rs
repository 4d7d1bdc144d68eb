//! The seed thesis's colour data and its SPD → RGB method (eq. 4.2–4.12), kept so that
//! tests can reproduce its worked example (table 4.1, 4.2, eq. 4.13–4.18) and show why
//! we do not use it: it normalises by X + Y + Z, rescales by an "intensity" I, and uses
//! primaries (0.7355, 0.2645), (0.2658, 0.7243), (0.1669, 0.0085) with an equal-energy
//! white (1/3, 1/3) [the thesis cites Walker 1996] — so D65 daylight comes out light blue
//! (0.712, 0.867, 0.897) instead of neutral.

// Published constants are kept at the precision they were published with.
#![allow(clippy::excessive_precision)]

/// Table 4.1: the thesis's D65 samples at 380, 390, …, 770 nm (normalised to max ≈ 1).
#[rustfmt::skip]
pub const THESIS_D65: [f32; 40] = [
    0.444027773062, 0.583145180457, 0.739486639731, 0.784800359895, 0.764412793264,
    0.812935863919, 0.941635826571, 0.996587783927, 0.987471564866, 0.979458798764,
    0.953782297219, 0.925898889757, 0.921620887516, 0.902251044036, 0.901767222354,
    0.900137507215, 0.884672189590, 0.865981394085, 0.833252130513, 0.815376192578,
    0.782915152956, 0.758376905578, 0.762253420704, 0.752460700098, 0.725678199165,
    0.708704546226, 0.694861304451, 0.680072488371, 0.689625844566, 0.681433130751,
    0.628142294503, 0.599813261807, 0.619453026856, 0.576991308186, 0.558048416121,
    0.615270940142, 0.588563134485, 0.466891318372, 0.480526601704, 0.552525209656,
];

/// Table 4.2: the thesis's observer functions (x̄, ȳ, z̄) at 380, 390, …, 770 nm. These
/// are the Judd–Vos-modified CIE 1931 functions, not the CIE 1931 standard observer.
#[rustfmt::skip]
pub const THESIS_CMF: [[f32; 3]; 40] = [
    [2.6899e-3, 2.0000e-4, 1.2260e-2], [1.0781e-2, 8.0000e-4, 4.9250e-2],
    [3.7981e-2, 2.8000e-3, 1.7409e-1], [9.9941e-2, 7.4000e-3, 4.6053e-1],
    [2.2948e-1, 1.7500e-2, 1.0658e+0], [3.1095e-1, 2.7300e-2, 1.4672e+0],
    [3.3336e-1, 3.7900e-2, 1.6166e+0], [2.8882e-1, 4.6800e-2, 1.4717e+0],
    [2.3276e-1, 6.0000e-2, 1.2917e+0], [1.7476e-1, 9.0980e-2, 1.1138e+0],
    [9.1944e-2, 1.3902e-1, 7.5596e-1], [3.1731e-2, 2.0802e-1, 4.4669e-1],
    [4.8491e-3, 3.2300e-1, 2.6437e-1], [9.2899e-3, 5.0300e-1, 1.5445e-1],
    [6.3791e-2, 7.1000e-1, 7.6585e-2], [1.6692e-1, 8.6200e-1, 4.1366e-2],
    [2.9269e-1, 9.5400e-1, 2.0042e-2], [4.3635e-1, 9.9495e-1, 8.7823e-3],
    [5.9748e-1, 9.9500e-1, 4.0493e-3], [7.6425e-1, 9.5200e-1, 2.2771e-3],
    [9.1635e-1, 8.7000e-1, 1.8066e-3], [1.0230e+0, 7.5700e-1, 1.2348e-3],
    [1.0550e+0, 6.3100e-1, 9.0564e-4], [9.9239e-1, 5.0300e-1, 4.2885e-4],
    [8.4346e-1, 3.8100e-1, 2.5598e-4], [6.3289e-1, 2.6500e-1, 9.7694e-5],
    [4.4062e-1, 1.7500e-1, 5.1165e-5], [2.7862e-1, 1.0700e-1, 2.4238e-5],
    [1.6161e-1, 6.1000e-2, 1.1906e-5], [8.5753e-2, 3.2000e-2, 5.6006e-6],
    [4.5834e-2, 1.7000e-2, 2.7912e-6], [2.2187e-2, 8.2100e-3, 1.3135e-6],
    [1.1098e-2, 4.1020e-3, 6.4767e-7], [5.6531e-3, 2.0910e-3, 3.3304e-7],
    [2.8253e-3, 1.0470e-3, 1.7026e-7], [1.3994e-3, 5.2000e-4, 8.7107e-8],
    [6.6847e-4, 2.4920e-4, 4.3162e-8], [3.2073e-4, 1.2000e-4, 2.1554e-8],
    [1.5973e-4, 6.0000e-5, 1.1204e-8], [7.9513e-5, 3.0000e-5, 5.8340e-9],
];

/// Eq. 4.2: X, Y, Z as plain sums of SPD × observer over the 40 samples.
pub fn thesis_xyz(spd: &[f32; 40]) -> [f64; 3] {
    let mut xyz = [0.0f64; 3];
    for (s, c) in spd.iter().zip(&THESIS_CMF) {
        for k in 0..3 {
            xyz[k] += *s as f64 * c[k] as f64;
        }
    }
    xyz
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

fn solve3(m: &[[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    // Cramer's rule; the matrices here are well conditioned.
    let d = det3(m);
    std::array::from_fn(|col| {
        let mut mc = *m;
        for row in 0..3 {
            mc[row][col] = b[row];
        }
        det3(&mc) / d
    })
}

/// The thesis's whole SPD → RGB method, eq. 4.3–4.12, with its primaries and white.
pub fn thesis_spd_to_rgb(spd: &[f32; 40]) -> [f64; 3] {
    let [x, y, z] = thesis_xyz(spd);
    let n = x + y + z;
    let scaled = [x / n, y / n, z / n]; // eq. 4.3
    let m_max: f64 = THESIS_CMF.iter().map(|c| (c[0] + c[1] + c[2]) as f64).sum();
    let intensity = 1.0 - (m_max - n) / m_max; // eq. 4.4
    let (xr, yr, xg, yg, xb, yb) = (0.7355, 0.2645, 0.2658, 0.7243, 0.1669, 0.0085); // eq. 4.6
    let (xw, yw) = (1.0 / 3.0, 1.0 / 3.0);
    let col = |x: f64, y: f64| [x / y, 1.0, (1.0 - x - y) / y]; // eq. 4.8
    let (r, g, b) = (col(xr, yr), col(xg, yg), col(xb, yb));
    let nmat = [[r[0], g[0], b[0]], [r[1], g[1], b[1]], [r[2], g[2], b[2]]];
    let s = solve3(&nmat, [xw, yw, 1.0 - xw - yw]); // eq. 4.9
    let m = std::array::from_fn(|row| std::array::from_fn(|c| nmat[row][c] * s[c])); // eq. 4.7
    solve3(&m, scaled).map(|v| v * intensity) // eq. 4.5, 4.12
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colour::{spectrum_to_xyz, xyz_to_linear_srgb};
    use crate::spectrum::d65;

    #[test]
    fn reproduces_the_thesis_xyz_sums() {
        // Eq. 4.13: X, Y, Z = 8.4661, 8.93622, 9.5453.
        let [x, y, z] = thesis_xyz(&THESIS_D65);
        assert!((x - 8.4661).abs() < 5e-4, "X = {x}");
        assert!((y - 8.93622).abs() < 5e-4, "Y = {y}");
        assert!((z - 9.5453).abs() < 5e-4, "Z = {z}");
    }

    #[test]
    fn the_thesis_method_turns_d65_light_blue() {
        // Eq. 4.18: (R_s, G_s, B_s) = (0.712091, 0.866718, 0.896577).
        let rgb = thesis_spd_to_rgb(&THESIS_D65);
        for (got, want) in rgb.iter().zip([0.712091, 0.866718, 0.896577]) {
            assert!((got - want).abs() < 2e-3, "thesis RGB {rgb:?}");
        }
        // Not neutral: blue exceeds red by more than 20 %.
        assert!(rgb[2] / rgb[0] > 1.2);
    }

    #[test]
    fn our_method_keeps_the_same_d65_samples_neutral() {
        // The thesis's own 40 D65 samples, interpolated and pushed through CIE 1931 → sRGB:
        // neutral to within the coarse table's error (measured max/min = 1.031), where the
        // thesis's method is off by > 25 %.
        let lambdas: Vec<f32> = (0..40).map(|i| 380.0 + 10.0 * i as f32).collect();
        let table = crate::spectrum::TabulatedSpectrum::new(lambdas, THESIS_D65.to_vec()).unwrap();
        let rgb = xyz_to_linear_srgb(spectrum_to_xyz(|l| table.eval(l)));
        let max = rgb.iter().copied().fold(0.0, f32::max);
        let min = rgb.iter().copied().fold(f32::MAX, f32::min);
        assert!(max / min < 1.05, "{rgb:?}");
        // And the full CIE table is neutral to 1e-3 (scale so that G = 1).
        let full = xyz_to_linear_srgb(spectrum_to_xyz(d65));
        for c in full {
            assert!((c / full[1] - 1.0).abs() < 1e-3, "{full:?}");
        }
    }
}
