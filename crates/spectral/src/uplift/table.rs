//! A precomputed RGB → sigmoid-polynomial table, so that uplifting a colour costs a
//! lookup and a trilinear interpolation instead of a Gauss–Newton fit (~20 µs): what
//! textures and environment maps need, with a spectrum per texel.
//!
//! The layout is Jakob & Hanika 2019's (§ 4, and pbrt-v4's `RGBToSpectrumTable`): for
//! each choice of the largest component l, a grid over z = that component (at the
//! nodes smoothstep(smoothstep(i/(n−1))), dense near 0 and 1 where the coefficients
//! change fastest) and over the two others divided by z (uniform in [0, 1]). Each entry
//! is fitted by [`super::fit_reflectance`]'s optimiser, warm-started from its neighbour
//! along z (a fresh continuation fit where that fails), in parallel over the columns.
//! A lookup interpolates the eight surrounding entries' coefficients; greys are exact.

use super::{FIT, SigmoidPolynomial, TARGET_EPS, TOL_ACCEPT, TOL_FINAL, fit_normalised, lab, newton, to_nanometres};
use std::sync::LazyLock;

/// Grid points per axis.
pub const TABLE_RES: usize = 32;

/// The table: coefficients (in nm) per largest component, z, y, x.
pub struct UpliftTable {
    /// The z nodes, increasing from 0 to 1.
    z_nodes: [f32; TABLE_RES],
    /// 3 × TABLE_RES³ polynomials, index ((l·n + zi)·n + yi)·n + xi.
    coeffs: Vec<SigmoidPolynomial>,
}

static TABLE: LazyLock<UpliftTable> = LazyLock::new(UpliftTable::build);

/// The shared table, built on first use (about a second on two cores; see the tests for
/// its accuracy and `benches/uplift.rs` for its speed).
pub fn uplift_table() -> &'static UpliftTable {
    &TABLE
}

fn smoothstep(x: f64) -> f64 {
    x * x * (3.0 - 2.0 * x)
}

impl UpliftTable {
    fn build() -> Self {
        let n = TABLE_RES;
        let z_nodes: [f64; TABLE_RES] = std::array::from_fn(|i| smoothstep(smoothstep(i as f64 / (n - 1) as f64)));
        // Columns (l, yi, xi), each fitted along z from the middle outwards.
        let columns: Vec<(usize, usize, usize)> =
            (0..3).flat_map(|l| (0..n).flat_map(move |yi| (0..n).map(move |xi| (l, yi, xi)))).collect();
        let threads = std::thread::available_parallelism().map_or(1, |p| p.get()).min(16);
        let chunk = columns.len().div_ceil(threads);
        let fitted: Vec<Vec<(usize, [SigmoidPolynomial; TABLE_RES])>> = std::thread::scope(|scope| {
            let handles: Vec<_> = columns
                .chunks(chunk)
                .map(|part| {
                    scope.spawn(move || {
                        part.iter().map(|&(l, yi, xi)| (l, column(l, yi, xi, &z_nodes))).collect::<Vec<_>>()
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("an uplift-table thread panicked")).collect()
        });
        let mut coeffs = vec![SigmoidPolynomial { c0: 0.0, c1: 0.0, c2: 0.0 }; 3 * n * n * n];
        for (&(l, yi, xi), (_, col)) in columns.iter().zip(fitted.into_iter().flatten()) {
            for (zi, c) in col.into_iter().enumerate() {
                coeffs[((l * n + zi) * n + yi) * n + xi] = c;
            }
        }
        Self { z_nodes: z_nodes.map(|z| z as f32), coeffs }
    }

    /// The sigmoid polynomial for a linear-sRGB reflectance (components clamped to
    /// [0, 1]): exact for greys, interpolated from the table otherwise.
    #[inline]
    pub fn lookup(&self, rgb: [f32; 3]) -> SigmoidPolynomial {
        let rgb = rgb.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) });
        if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
            return SigmoidPolynomial::grey(rgb[0]);
        }
        let n = TABLE_RES;
        let l = if rgb[0] >= rgb[1] && rgb[0] >= rgb[2] {
            0
        } else if rgb[1] >= rgb[2] {
            1
        } else {
            2
        };
        let z = rgb[l];
        let scale = (n - 1) as f32 / z;
        let x = rgb[(l + 1) % 3] * scale;
        let y = rgb[(l + 2) % 3] * scale;
        let zi = self.z_nodes.partition_point(|&node| node <= z).clamp(1, n - 1) - 1;
        let tz = ((z - self.z_nodes[zi]) / (self.z_nodes[zi + 1] - self.z_nodes[zi])).clamp(0.0, 1.0);
        let (xi, yi) = ((x as usize).min(n - 2), (y as usize).min(n - 2));
        let (tx, ty) = (x - xi as f32, y - yi as f32);
        let at = |dz: usize, dy: usize, dx: usize| &self.coeffs[((l * n + zi + dz) * n + yi + dy) * n + xi + dx];
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let mut out = [0.0f32; 3];
        for (k, o) in out.iter_mut().enumerate() {
            let c = |dz, dy, dx| {
                let p = at(dz, dy, dx);
                [p.c0, p.c1, p.c2][k]
            };
            let plane = |dz| lerp(lerp(c(dz, 0, 0), c(dz, 0, 1), tx), lerp(c(dz, 1, 0), c(dz, 1, 1), tx), ty);
            *o = lerp(plane(0), plane(1), tz);
        }
        SigmoidPolynomial { c0: out[0], c1: out[1], c2: out[2] }
    }

    /// The z nodes (the largest component's grid), increasing from 0 to 1.
    pub fn z_nodes(&self) -> &[f32; TABLE_RES] {
        &self.z_nodes
    }

    /// The 3 × TABLE_RES³ polynomials, entry ((l·n + zi)·n + yi)·n + xi for the largest
    /// component l (for backends that look the table up elsewhere: the GPU).
    pub fn coefficients(&self) -> &[SigmoidPolynomial] {
        &self.coeffs
    }

    /// Bytes the table occupies.
    pub fn size_bytes(&self) -> usize {
        std::mem::size_of_val(self.coeffs.as_slice()) + std::mem::size_of_val(&self.z_nodes)
    }
}

/// The linear-sRGB target of entry (l, z, y, x): the largest component z at l, the others
/// x·z and y·z after it.
fn target(l: usize, z: f64, x: f64, y: f64) -> [f64; 3] {
    let mut rgb = [0.0; 3];
    rgb[l] = z;
    rgb[(l + 1) % 3] = x * z;
    rgb[(l + 2) % 3] = y * z;
    rgb
}

/// One column of the table along z: a continuation fit in the middle, then Newton from
/// each neighbour outwards (a continuation fit again where that does not converge).
fn column(l: usize, yi: usize, xi: usize, z_nodes: &[f64; TABLE_RES]) -> [SigmoidPolynomial; TABLE_RES] {
    let n = TABLE_RES;
    let (x, y) = (xi as f64 / (n - 1) as f64, yi as f64 / (n - 1) as f64);
    let tables = &*FIT;
    let clamp = |rgb: [f64; 3]| rgb.map(|v| v.clamp(TARGET_EPS, 1.0 - TARGET_EPS));
    let fit_fresh = |zi: usize| -> [f64; 3] {
        // Every colour of the cube fits (the uplift's tests); should one not, its best
        // coefficients still beat a hole in the table.
        fit_normalised(clamp(target(l, z_nodes[zi], x, y))).unwrap_or([0.0, 0.0, 0.0])
    };
    let fit_from = |guess: [f64; 3], zi: usize| -> [f64; 3] {
        let rgb = clamp(target(l, z_nodes[zi], x, y));
        let xyz = tables.rgb_to_target.map(|row| super::dot3(row, rgb));
        let mut c = guess;
        if newton(&mut c, lab(xyz, tables.white), TOL_FINAL, tables) < TOL_ACCEPT { c } else { fit_fresh(zi) }
    };
    let mut out = [[0.0f64; 3]; TABLE_RES];
    let mid = n / 2;
    out[mid] = fit_fresh(mid);
    for zi in mid + 1..n {
        out[zi] = fit_from(out[zi - 1], zi);
    }
    for zi in (0..mid).rev() {
        out[zi] = fit_from(out[zi + 1], zi);
    }
    out.map(to_nanometres)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::{Colour, ColourRole, Spectrum};
    use crate::uplift::{RgbAlbedoSpectrum, fit_reflectance};

    /// The linear sRGB a polynomial's reflectance shows under D65.
    fn shown(poly: SigmoidPolynomial) -> [f32; 3] {
        Colour::from_spectrum(Spectrum::RgbAlbedo(RgbAlbedoSpectrum { poly }), ColourRole::Reflectance).rgb
    }

    #[test]
    fn table_lookups_reproduce_their_colours_nearly_as_well_as_fits() {
        let start = std::time::Instant::now();
        let table = uplift_table();
        eprintln!("uplift table: built in {:?}, {} kB", start.elapsed(), table.size_bytes() / 1000);
        let mut rng = rng::Pcg32::seed_from_u64(3);
        let (mut worst, mut sum, mut worst_fit) = (0.0f32, 0.0f64, 0.0f32);
        let n = 3000;
        for i in 0..n {
            // Uniform in the cube, plus saturated colours on its faces and edges.
            let mut rgb = [rng.next_f32(), rng.next_f32(), rng.next_f32()];
            if i % 3 == 0 {
                rgb[i % 3] = if i % 2 == 0 { 0.0 } else { 1.0 };
            }
            let err = |p: SigmoidPolynomial| {
                let s = shown(p);
                (0..3).map(|k| (s[k] - rgb[k]).abs()).fold(0.0, f32::max)
            };
            let e = err(table.lookup(rgb));
            worst = worst.max(e);
            sum += e as f64;
            worst_fit = worst_fit.max(err(fit_reflectance(rgb).unwrap()));
        }
        eprintln!(
            "uplift table: |Δrgb| mean {:.2e}, worst {worst:.2e} (direct fits: worst {worst_fit:.2e})",
            sum / n as f64
        );
        assert!(worst < 0.01 && sum / (n as f64) < 1e-3, "worst {worst}, mean {}", sum / n as f64);
        // Greys are exact, black and white included.
        for v in [0.0f32, 0.18, 0.5, 1.0] {
            assert_eq!(table.lookup([v; 3]), fit_reflectance([v; 3]).unwrap());
        }
    }
}
