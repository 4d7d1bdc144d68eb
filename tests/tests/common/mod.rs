//! Statistics shared by the whole-system tests.
#![allow(dead_code)]

use tracer::film::Film;

pub mod batched;
pub mod room;

pub use brdf::validation::{erfc, sidak_z, z_threshold};

/// Result of comparing an image against expected values.
#[derive(Debug)]
pub struct Comparison {
    /// Fraction of pixel-channels with |z| below the threshold.
    pub pass_fraction: f64,
    /// The threshold used.
    pub z_max: f64,
    /// Worst |z|.
    pub worst: f64,
}

/// Per pixel-channel z = (a − b)/√(se_a² + se_b²), Šidák-corrected at α = 0.01.
pub fn z_test(a: &[f32], se_a: &[f32], b: &[f32], se_b: &[f32]) -> Comparison {
    assert_eq!(a.len(), b.len());
    let z_max = sidak_z(0.01, a.len());
    let mut pass = 0usize;
    let mut worst = 0.0f64;
    for i in 0..a.len() {
        let se = ((se_a[i] as f64).powi(2) + (se_b[i] as f64).powi(2)).sqrt();
        let d = (a[i] - b[i]) as f64;
        let z = if se > 0.0 {
            d.abs() / se
        } else if d.abs() < 1e-6 {
            0.0
        } else {
            f64::INFINITY
        };
        worst = worst.max(z);
        if z <= z_max {
            pass += 1;
        }
    }
    Comparison { pass_fraction: pass as f64 / a.len() as f64, z_max, worst }
}

/// Image-wide mean of a film channel and its standard error (pixels are independent).
pub fn channel_mean_and_se(film: &Film, c: usize) -> (f64, f64) {
    let n = film.pixels().len() as f64;
    let mean = film.pixels().iter().map(|p| p.mean()[c]).sum::<f64>() / n;
    let var = film.pixels().iter().map(|p| p.std_error()[c].powi(2)).sum::<f64>();
    (mean, var.sqrt() / n)
}

#[test]
fn quantiles_are_right() {
    assert!((z_threshold(0.05) - 1.959964).abs() < 1e-4);
    assert!((z_threshold(0.01) - 2.575829).abs() < 1e-4);
    assert!((erfc(3.0) - 2.209049699858544e-5).abs() < 1e-12);
}
