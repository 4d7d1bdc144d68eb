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
//!
//! The fit takes about two CPU seconds, which every textured render paid at start-up (88 %
//! of a short Sponza render's CPU time), so the crate ships the fitted table
//! (`data/uplift_srgb_32.bin`, as Mitsuba 3 ships its `srgb.coeff` and pbrt-v4 generates
//! its tables at build time) and [`uplift_table`] decodes it. [`UpliftTable::fit`] is the
//! fit; a test checks that the shipped table is what it gives, and
//! `cargo run --release -p spectral --example write_uplift_table` writes it anew after a
//! change to the fit.

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

/// The fitted table as [`UpliftTable::to_bytes`] writes it.
const SHIPPED: &[u8] = include_bytes!("../../data/uplift_srgb_32.bin");

/// The first bytes of [`UpliftTable::to_bytes`]: the format and its version.
const MAGIC: [u8; 4] = *b"UPL1";

/// The length of [`UpliftTable::to_bytes`]: the magic, the resolution, the z nodes and
/// three floats per entry.
const ENCODED_LEN: usize = 8 + 4 * (TABLE_RES + 9 * TABLE_RES * TABLE_RES * TABLE_RES);

// A shipped file of another length fails the build, not the first render.
const _: () = assert!(SHIPPED.len() == ENCODED_LEN);

static TABLE: LazyLock<UpliftTable> = LazyLock::new(|| {
    UpliftTable::from_bytes(SHIPPED).expect("the shipped uplift table is checked by the crate's tests")
});

/// The shared table, decoded from the shipped one on first use (about 2 ms; see
/// the tests for its accuracy and `benches/uplift.rs` for its speed).
pub fn uplift_table() -> &'static UpliftTable {
    &TABLE
}

fn smoothstep(x: f64) -> f64 {
    x * x * (3.0 - 2.0 * x)
}

impl UpliftTable {
    /// Fits the table (about two CPU seconds, in parallel over the available cores): what
    /// the shipped table was written from.
    pub fn fit() -> Self {
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

    /// The table as bytes: the magic `UPL1`, [`TABLE_RES`] as a u32, the z nodes, then
    /// every polynomial's c₀, c₁, c₂, all little-endian (what [`Self::from_bytes`] reads).
    pub fn to_bytes(&self) -> Vec<u8> {
        let floats = self.z_nodes.iter().copied().chain(self.coeffs.iter().flat_map(|c| [c.c0, c.c1, c.c2]));
        let head = MAGIC.into_iter().chain((TABLE_RES as u32).to_le_bytes());
        head.chain(floats.flat_map(f32::to_le_bytes)).collect()
    }

    /// A table written by [`Self::to_bytes`]; `None` if `bytes` is not one (another magic,
    /// resolution or length), holds a non-finite number, or its z nodes do not rise
    /// strictly from 0 to 1 (a lookup divides by their steps).
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let n = TABLE_RES;
        let (magic, rest) = bytes.split_first_chunk::<4>()?;
        let (res, body) = rest.split_first_chunk::<4>()?;
        if *magic != MAGIC || u32::from_le_bytes(*res) as usize != n || bytes.len() != ENCODED_LEN {
            return None;
        }
        let floats: Vec<f32> = body.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        if !floats.iter().all(|v| v.is_finite()) {
            return None;
        }
        let z_nodes: [f32; TABLE_RES] = std::array::from_fn(|i| floats[i]);
        if z_nodes[0] != 0.0 || z_nodes[n - 1] != 1.0 || z_nodes.windows(2).any(|w| w[0] >= w[1]) {
            return None;
        }
        let coeffs = floats[n..].chunks_exact(3).map(|c| SigmoidPolynomial { c0: c[0], c1: c[1], c2: c[2] }).collect();
        Some(Self { z_nodes, coeffs })
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

    /// The shipped table is the fit's: each entry's reflectance within 10⁻³ at every 5 nm
    /// (bit for bit on the machine that wrote it; one ulp in a coefficient, as another
    /// libm's exp and cbrt may give, moves it by up to 2.4·10⁻⁴, and the table's own
    /// interpolation error is 10⁻²). A change to the fit fails here until the table is
    /// written anew.
    #[test]
    fn the_shipped_table_is_what_the_fit_gives() {
        let start = std::time::Instant::now();
        let fitted = UpliftTable::fit();
        eprintln!("uplift table: fitted in {:?}, {} kB", start.elapsed(), fitted.size_bytes() / 1000);
        let shipped = uplift_table();
        assert_eq!(shipped.z_nodes, fitted.z_nodes);
        let mut worst = (0.0f32, 0);
        let mut differ = 0;
        for (i, (a, b)) in shipped.coeffs.iter().zip(&fitted.coeffs).enumerate() {
            differ += usize::from(a != b);
            for lambda in (360..=830).step_by(5) {
                let d = (a.eval(lambda as f32) - b.eval(lambda as f32)).abs();
                assert!(d.is_finite(), "entry {i}: {a:?} against the fit's {b:?}");
                if d > worst.0 {
                    worst = (d, i);
                }
            }
        }
        eprintln!(
            "uplift table: {differ} of {} entries differ from the fit's bits, worst |Δs(λ)| {:.1e}",
            shipped.coeffs.len(),
            worst.0
        );
        assert!(
            worst.0 < 1e-3,
            "entry {} of the shipped table is {:?}, the fit gives {:?}: after changing the fit, run \
             `cargo run --release -p spectral --example write_uplift_table`",
            worst.1,
            shipped.coeffs[worst.1],
            fitted.coeffs[worst.1]
        );
    }

    #[test]
    fn tables_round_trip_through_bytes_and_bad_bytes_are_refused() {
        let table = uplift_table();
        let bytes = table.to_bytes();
        assert_eq!(bytes.as_slice(), SHIPPED);
        let again = UpliftTable::from_bytes(&bytes).unwrap();
        assert_eq!(again.coeffs, table.coeffs);
        assert!(UpliftTable::from_bytes(&bytes[..bytes.len() - 4]).is_none(), "short");
        assert!(UpliftTable::from_bytes(&[bytes.as_slice(), &[0; 4]].concat()).is_none(), "long");
        let mut other_magic = bytes.clone();
        other_magic[3] = b'2';
        assert!(UpliftTable::from_bytes(&other_magic).is_none(), "magic");
        let mut other_res = bytes.clone();
        other_res[4] = 16;
        assert!(UpliftTable::from_bytes(&other_res).is_none(), "resolution");
        // A NaN among the z nodes and among the coefficients.
        for at in [8 + 4 * 24, 8 + 4 * (TABLE_RES + 1000)] {
            let mut nan = bytes.clone();
            nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
            assert!(UpliftTable::from_bytes(&nan).is_none(), "NaN at byte {at}");
        }
        // Z nodes that repeat (a lookup would divide by zero) or do not end at 1.
        let node = |k: usize| 8 + 4 * k;
        let mut repeated = bytes.clone();
        repeated.copy_within(node(3)..node(4), node(4));
        assert!(UpliftTable::from_bytes(&repeated).is_none(), "repeated z node");
        let mut short_range = bytes.clone();
        short_range[node(TABLE_RES - 1)..node(TABLE_RES)].copy_from_slice(&0.999f32.to_le_bytes());
        assert!(UpliftTable::from_bytes(&short_range).is_none(), "last z node below 1");
        assert!(UpliftTable::from_bytes(&[]).is_none(), "empty");
    }

    #[test]
    fn table_lookups_reproduce_their_colours_nearly_as_well_as_fits() {
        let table = uplift_table();
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
