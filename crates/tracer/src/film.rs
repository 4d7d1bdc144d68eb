//! The film: per-pixel sums of linear-sRGB samples, kept exactly.
//!
//! Each pixel keeps its sample count, the sum of its samples and the sum of their squares
//! as **fixed-point integers**: a sample `x` adds `round(x · 2⁶⁴)` to the sum and
//! `round(x² · 2³⁶)` to the sum of squares, both computed exactly from the f32 sample.
//! Integer addition is associative, so the film's bits do not depend on how the samples
//! were grouped: passes of any size, tiles in any order, shards rendered on other
//! machines and merged later all give the same bytes as one uninterrupted render. A
//! floating-point running mean (the thesis's eq. 7.2, or Welford's update) would differ
//! in its last bits with every grouping.
//!
//! The range is bounded by the widths: a sample must satisfy |x| < 2³⁴ ≈ 1.7·10¹⁰
//! ([`MAX_SAMPLE_MAGNITUDE`]; beyond it the sample is dropped and counted with the NaN
//! and infinite ones) and a pixel holds at most 2²⁴ samples ([`MAX_PIXEL_SAMPLES`]), so
//! |Σx|·2⁶⁴ < 2¹²² fits an `i128` and Σx²·2³⁶ < 2¹²⁸ a `u128`. The mean's resolution is
//! 2⁻⁶⁴ ≈ 5·10⁻²⁰ per sample; a square's is 2⁻³⁶ ≈ 1.5·10⁻¹¹, which bounds the error of
//! a variance by 7·10⁻¹² (negligible beside any sample noise worth measuring).

/// Fraction bits of the per-pixel sums.
pub const SUM_FRACTION_BITS: i32 = 64;

/// Fraction bits of the per-pixel sums of squares.
pub const SQUARE_FRACTION_BITS: i32 = 36;

/// Samples whose magnitude reaches this (2³⁴) in any channel are dropped (counted in
/// [`Film::non_finite`]): beyond it the fixed-point sums could overflow.
pub const MAX_SAMPLE_MAGNITUDE: f32 = 17_179_869_184.0;

/// The most samples one pixel may accumulate (2²⁴): renders and merges refuse more.
pub const MAX_PIXEL_SAMPLES: u32 = 1 << 24;

/// `round(x · 2⁶⁴)` and `round(x² · 2³⁶)` (halves away from zero) for a finite `x` with
/// |x| < [`MAX_SAMPLE_MAGNITUDE`], from the f32's bits with integer arithmetic only: x is
/// m · 2ᵉ with a 24-bit m, so both are m or m² shifted, then rounded. (The same values as
/// `(x as f64 * 2⁶⁴).round()`, which is exact up to its one rounding — tested — but the
/// float → i128 conversions are library calls and cost 3 % of a Cornell-box render.)
#[inline]
fn fixed_point(x: f32) -> (i128, u128) {
    let bits = x.to_bits();
    let biased = ((bits >> 23) & 0xff) as i32;
    // Subnormals have no implicit bit and the exponent of the smallest normals.
    let (m, e) = if biased == 0 { (bits & 0x7f_ffff, -149) } else { ((bits & 0x7f_ffff) | 0x80_0000, biased - 150) };
    let m = m as u64;
    let magnitude = shift_round(m, e + SUM_FRACTION_BITS) as i128;
    let value = if bits >> 31 == 1 { -magnitude } else { magnitude };
    (value, shift_round(m * m, 2 * e + SQUARE_FRACTION_BITS))
}

/// `round(m · 2^shift)`, halves away from zero, for m < 2⁴⁸ and a result < 2¹²⁸.
#[inline]
fn shift_round(m: u64, shift: i32) -> u128 {
    if shift >= 0 {
        (m as u128) << shift
    } else if shift > -64 {
        let k = -shift as u32;
        (m as u128 + (1u128 << (k - 1))) >> k
    } else {
        0
    }
}

/// Samples whose channels a [`FixedPointChunk`] converts at a time.
const CHUNK_SAMPLES: usize = 16;

/// The film's fixed-point values (round(x · 2⁶⁴), round(x² · 2³⁶), as [`PixelStats::add`]
/// computes them from the f32's bits) of the channels of up to [`CHUNK_SAMPLES`] samples
/// at once, by floating-point operations that vector instructions do for four or eight
/// values at a time: one at a time, the integer form cost about 190 instructions per
/// sample of a Cornell-box render (callgrind), 2.7 % of it. The same values to the bit
/// (tested against the integer form).
///
/// Each product is split into two integers below 2⁵², each rounded and converted exactly
/// in f64: for a = |x| (exact in f64), round(a · 2⁶⁴) = h · 2⁴⁹ + round((a · 2¹⁵ − h) · 2⁴⁹)
/// with h = ⌊a · 2¹⁵⌋ < 2⁴⁹, and round(x² · 2³⁶) = h · 2⁵² + round((x² · 2⁻¹⁶ − h) · 2⁵²)
/// with h = ⌊x² · 2⁻¹⁶⌋ < 2⁵². Every step is exact: a has 24 significant bits and x² 48,
/// scaling by powers of two loses none, t − ⌊t⌋ keeps t's bits below the point, and
/// ⌊v + ½⌋ is v rounded half up (half away from zero, as v ≥ 0) for 0 ≤ v < 2⁵², where
/// v + ½ is exact. An integer r ≤ 2⁵² is the difference of the bit patterns of r + 2⁵²
/// and 2⁵² (AVX2 has no conversion from f64 to 64-bit integers).
#[derive(Clone, Debug)]
struct FixedPointChunk {
    /// Low and high 64 bits of each value's round(x · 2⁶⁴), two's complement.
    sum_low: [u64; 3 * CHUNK_SAMPLES],
    sum_high: [u64; 3 * CHUNK_SAMPLES],
    /// Low and high 64 bits of each value's round(x² · 2³⁶).
    square_low: [u64; 3 * CHUNK_SAMPLES],
    square_high: [u64; 3 * CHUNK_SAMPLES],
}

impl FixedPointChunk {
    /// Converts `values` (at most 3 × [`CHUNK_SAMPLES`]; each finite with |x| <
    /// [`MAX_SAMPLE_MAGNITUDE`] for a meaningful result, others give unspecified bits,
    /// never a panic). Inlined, so that it is compiled for the vector instructions of its
    /// caller; without SSE4.1 the floors are library calls, and [`PixelStats::add`] is
    /// the faster form.
    #[inline(always)]
    fn convert(values: &[f32]) -> Self {
        debug_assert!(values.len() <= 3 * CHUNK_SAMPLES);
        const TWO_52: f64 = 4_503_599_627_370_496.0;
        // r as an integer, for an integer 0 ≤ r ≤ 2⁵² held in an f64.
        let integer = |r: f64| (r + TWO_52).to_bits().wrapping_sub(TWO_52.to_bits());
        let mut c = FixedPointChunk {
            sum_low: [0; 3 * CHUNK_SAMPLES],
            sum_high: [0; 3 * CHUNK_SAMPLES],
            square_low: [0; 3 * CHUNK_SAMPLES],
            square_high: [0; 3 * CHUNK_SAMPLES],
        };
        for (i, &x) in values.iter().enumerate().take(3 * CHUNK_SAMPLES) {
            let a = (x as f64).abs();
            let t = a * 32_768.0; // a · 2¹⁵
            let high = t.floor();
            let low = ((t - high) * 562_949_953_421_312.0 + 0.5).floor(); // (t − h) · 2⁴⁹, rounded
            let (high, low) = (integer(high), integer(low));
            // h · 2⁴⁹ + l in 128 bits (an or: l ≤ (1 − 2⁻²⁴) · 2⁴⁹, as t − h has at most
            // 24 significant bits), then negated for negative x (all ones in `negative`).
            let lo = (high << 49) | low;
            let hi = high >> 15;
            let negative = 0u64.wrapping_sub((x.to_bits() >> 31) as u64);
            let lo_n = (lo ^ negative).wrapping_sub(negative);
            c.sum_low[i] = lo_n;
            c.sum_high[i] = (hi ^ negative).wrapping_add((lo_n == 0) as u64 & negative & 1);
            let s = a * a * (1.0 / 65_536.0); // x² · 2⁻¹⁶
            let high = s.floor();
            let low = ((s - high) * TWO_52 + 0.5).floor();
            let (high, low) = (integer(high), integer(low));
            // l ≤ (1 − 2⁻⁴⁸) · 2⁵²: x² · 2⁻¹⁶ − h has at most 48 significant bits.
            c.square_low[i] = (high << 52) | low;
            c.square_high[i] = high >> 12;
        }
        c
    }

    /// Value `k`'s round(x · 2⁶⁴) and round(x² · 2³⁶).
    #[inline(always)]
    fn get(&self, k: usize) -> (i128, u128) {
        let value = ((self.sum_high[k] as u128) << 64 | self.sum_low[k] as u128) as i128;
        (value, (self.square_high[k] as u128) << 64 | self.square_low[k] as u128)
    }
}

/// Adds sample `rgb[k]` to `pixels[owners[k]]` for every k, one at a time by
/// [`PixelStats::add`]; returns how many were refused. The form for machines without
/// SSE4.1, and what [`add_samples`] must equal.
pub(crate) fn add_samples_one_at_a_time(pixels: &mut [PixelStats], owners: &[u32], rgb: &[[f32; 3]]) -> u64 {
    assert_eq!(owners.len(), rgb.len(), "one owner per sample");
    owners.iter().zip(rgb).filter(|&(&i, rgb)| !pixels[i as usize].add(*rgb)).count() as u64
}

/// [`add_samples_one_at_a_time`], converting the samples' channels [`CHUNK_SAMPLES`] at a
/// time ([`FixedPointChunk`]): the same pixels to the bit. Inlined, as
/// [`FixedPointChunk::convert`].
#[inline(always)]
pub(crate) fn add_samples(pixels: &mut [PixelStats], owners: &[u32], rgb: &[[f32; 3]]) -> u64 {
    assert_eq!(owners.len(), rgb.len(), "one owner per sample");
    let mut refused = 0;
    for (owners, rgb) in owners.chunks(CHUNK_SAMPLES).zip(rgb.chunks(CHUNK_SAMPLES)) {
        let chunk = FixedPointChunk::convert(rgb.as_flattened());
        for (k, (&i, rgb)) in owners.iter().zip(rgb).enumerate() {
            if !pixels[i as usize].add_with(*rgb, |c| chunk.get(3 * k + c)) {
                refused += 1;
            }
        }
    }
    refused
}

/// One pixel's accumulator: count, sum and sum of squares per channel, in fixed point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PixelStats {
    /// Samples accumulated.
    pub count: u32,
    /// Σ round(x · 2⁶⁴) per channel.
    pub sum: [i128; 3],
    /// Σ round(x² · 2³⁶) per channel.
    pub sum_sq: [u128; 3],
}

impl PixelStats {
    /// Adds one sample; returns `false` (and adds nothing) if a channel is NaN, infinite
    /// or beyond [`MAX_SAMPLE_MAGNITUDE`].
    #[inline]
    pub fn add(&mut self, rgb: [f32; 3]) -> bool {
        self.add_with(rgb, |c| fixed_point(rgb[c]))
    }

    /// Adds sample `rgb` whose channel c has the fixed-point values `fixed(c)` (computed
    /// from `rgb[c]`, by [`fixed_point`] or a [`FixedPointChunk`]), unless `rgb` is refused.
    #[inline(always)]
    fn add_with(&mut self, rgb: [f32; 3], fixed: impl Fn(usize) -> (i128, u128)) -> bool {
        if !rgb.iter().all(|v| v.abs() < MAX_SAMPLE_MAGNITUDE) {
            return false;
        }
        self.count += 1;
        for c in 0..3 {
            let (value, square) = fixed(c);
            self.sum[c] += value;
            self.sum_sq[c] += square;
        }
        true
    }

    /// Adds another accumulator's samples (exact: the result does not depend on how the
    /// samples were split between accumulators, nor on the order of merging).
    #[inline]
    pub fn merge(&mut self, other: &PixelStats) {
        self.count += other.count;
        for c in 0..3 {
            self.sum[c] += other.sum[c];
            self.sum_sq[c] += other.sum_sq[c];
        }
    }

    /// An accumulator from a count, mean and M2 = Σ(x − mean)² computed elsewhere (the
    /// GPU's per-pass f32 statistics); deterministic, so passes converted this way still
    /// merge to the same bytes in any grouping.
    pub fn from_moments(count: u32, mean: [f64; 3], m2: [f64; 3]) -> Self {
        let n = count as f64;
        let mut p = PixelStats { count, ..Default::default() };
        for c in 0..3 {
            p.sum[c] = (mean[c] * n * 2f64.powi(SUM_FRACTION_BITS)).round() as i128;
            p.sum_sq[c] = ((m2[c].max(0.0) + n * mean[c] * mean[c]) * 2f64.powi(SQUARE_FRACTION_BITS)).round() as u128;
        }
        p
    }

    /// The mean per channel (0 without samples).
    pub fn mean(&self) -> [f64; 3] {
        if self.count == 0 {
            return [0.0; 3];
        }
        let n = self.count as f64;
        self.sum.map(|s| s as f64 * 2f64.powi(-SUM_FRACTION_BITS) / n)
    }

    /// Σ(x − mean)² per channel: Σx² − (Σx)²/n, never negative.
    pub fn m2(&self) -> [f64; 3] {
        if self.count == 0 {
            return [0.0; 3];
        }
        let n = self.count as f64;
        std::array::from_fn(|c| {
            let s = self.sum[c] as f64 * 2f64.powi(-SUM_FRACTION_BITS);
            let s2 = self.sum_sq[c] as f64 * 2f64.powi(-SQUARE_FRACTION_BITS);
            (s2 - s * s / n).max(0.0)
        })
    }

    /// The standard error of the mean per channel (0 below two samples).
    pub fn std_error(&self) -> [f64; 3] {
        if self.count < 2 {
            return [0.0; 3];
        }
        let n = self.count as f64;
        self.m2().map(|m2| (m2 / (n - 1.0) / n).sqrt())
    }
}

/// A width × height grid of [`PixelStats`], row-major from the top-left, and for
/// integrators that trace paths from the lights to the camera (bidirectional path
/// tracing), a *splat* image beside it.
///
/// A light path's contribution lands on whatever pixel its last vertex projects to, not
/// on the pixel whose sample started it: each pixel's splat sum, in the same exact fixed
/// point as the samples, is divided by the number of light paths traced per pixel
/// ([`Film::count_light_paths`]; each splat was divided by the region's pixel count) and
/// added to the pixel's mean (Veach 1997, §10.3.4). The standard errors ([`Film::std_error_rgb`]) cover the pixel samples only.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    pixels: Vec<PixelStats>,
    /// Σ round(x · 2⁶⁴) of the splats per pixel and channel (empty until the first).
    splats: Vec<[i128; 3]>,
    /// Light paths traced, each of which could have splatted anywhere.
    light_paths: u64,
    /// Samples that were NaN, infinite or beyond [`MAX_SAMPLE_MAGNITUDE`] and were
    /// dropped (splats included).
    pub non_finite: u64,
}

/// `a + b` per channel, or `None` if a channel overflows.
fn checked_sum(a: [i128; 3], b: [i128; 3]) -> Option<[i128; 3]> {
    Some([a[0].checked_add(b[0])?, a[1].checked_add(b[1])?, a[2].checked_add(b[2])?])
}

/// Adds `splats` to the row-major `sums` of a `width` × `height` image in fixed point;
/// returns how many were dropped (outside, not finite, too large, or overflowing).
fn accumulate_splats(sums: &mut [[i128; 3]], width: u32, height: u32, splats: &[Splat]) -> u64 {
    let mut dropped = 0;
    for s in splats {
        if s.x >= width || s.y >= height || !s.rgb.iter().all(|v| v.abs() < MAX_SAMPLE_MAGNITUDE) {
            dropped += 1;
            continue;
        }
        let sum = &mut sums[(s.y * width + s.x) as usize];
        match checked_sum(*sum, s.rgb.map(|v| fixed_point(v).0)) {
            Some(new) => *sum = new,
            None => dropped += 1,
        }
    }
    dropped
}

/// Splat sums gathered apart from a film (a backend's threads flush theirs into one,
/// so that a render holds at most a few blocks of splats in memory), then added to it
/// with [`Film::add_splat_image`].
#[derive(Clone, Debug, PartialEq)]
pub struct SplatImage {
    width: u32,
    height: u32,
    sums: Vec<[i128; 3]>,
    /// Splats dropped (outside, not finite, too large or overflowing).
    pub dropped: u64,
}

impl SplatImage {
    /// An empty image of the film's size.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, sums: vec![[0; 3]; width as usize * height as usize], dropped: 0 }
    }

    /// Adds splats (exactly: the sums do not depend on the order).
    pub fn add(&mut self, splats: &[Splat]) {
        self.dropped += accumulate_splats(&mut self.sums, self.width, self.height, splats);
    }
}

/// One light-path contribution to a pixel, in linear sRGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Column.
    pub x: u32,
    /// Row.
    pub y: u32,
    /// The contribution divided by the rendered region's pixel count, before division
    /// by the light paths traced per pixel ([`Film::count_light_paths`]).
    pub rgb: [f32; 3],
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![PixelStats::default(); width as usize * height as usize],
            splats: Vec::new(),
            light_paths: 0,
            non_finite: 0,
        }
    }

    /// Adds the sums a backend's threads gathered into a [`SplatImage`] of this size.
    pub fn add_splat_image(&mut self, image: &SplatImage) {
        assert_eq!((image.width, image.height), (self.width, self.height), "a splat image of the film's size");
        for (i, &sum) in image.sums.iter().enumerate() {
            self.add_splat_sum(i, sum);
        }
        self.non_finite += image.dropped;
    }

    /// Records that `n` more light paths were traced from each pixel of the region
    /// rendered (one per pixel sample: the splats' divisor; the integrator has divided
    /// each splat by the region's pixel count already).
    pub fn count_light_paths(&mut self, n: u64) {
        self.light_paths += n;
    }

    /// Light paths traced so far, per pixel of the region rendered.
    pub fn light_paths(&self) -> u64 {
        self.light_paths
    }

    /// Whether any light path has splatted onto this film.
    pub fn has_splats(&self) -> bool {
        !self.splats.is_empty()
    }

    /// Each pixel's splat sums (Σ round(x · 2⁶⁴) per channel, row-major), if any light
    /// path has splatted: for partial renders on disk.
    pub fn splat_sums(&self) -> Option<&[[i128; 3]]> {
        (!self.splats.is_empty()).then_some(&self.splats[..])
    }

    /// Adds splat sums (read back from disk, or gathered by a backend) to pixel `index`
    /// (row-major); sums that would overflow are dropped and counted in
    /// [`Film::non_finite`].
    pub fn add_splat_sum(&mut self, index: usize, sum: [i128; 3]) {
        if sum == [0; 3] {
            return;
        }
        if self.splats.is_empty() {
            self.splats = vec![[0; 3]; self.pixels.len()];
        }
        let old = self.splats[index];
        match checked_sum(old, sum) {
            Some(new) => self.splats[index] = new,
            None => self.non_finite += 1,
        }
    }

    /// The estimate at pixel index `i` (row-major): its samples' mean plus its splats
    /// over the light paths traced.
    #[inline]
    pub fn pixel_mean(&self, i: usize) -> [f64; 3] {
        let mut m = self.pixels[i].mean();
        if let Some(s) = self.splats.get(i).filter(|_| self.light_paths > 0) {
            let scale = 2f64.powi(-SUM_FRACTION_BITS) / self.light_paths as f64;
            for c in 0..3 {
                m[c] += s[c] as f64 * scale;
            }
        }
        m
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// All pixels, row-major.
    pub fn pixels(&self) -> &[PixelStats] {
        &self.pixels
    }

    /// Mutable pixels, row-major (backends write tiles through this).
    pub fn pixels_mut(&mut self) -> &mut [PixelStats] {
        &mut self.pixels
    }

    /// The pixel at (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> &PixelStats {
        &self.pixels[(y * self.width + x) as usize]
    }

    /// Forgets every sample (keeps the allocation: a viewer restarts its film at every
    /// camera move).
    pub fn clear(&mut self) {
        self.pixels.fill(PixelStats::default());
        self.splats.fill([0; 3]);
        self.light_paths = 0;
        self.non_finite = 0;
    }

    /// The mean image packed for display: one 0x00RRGGBB word per pixel, each channel
    /// sRGB-encoded and clamped ([`spectral::srgb_to_u8`]), row-major; `out` has one
    /// element per pixel.
    pub fn display_pixels(&self, out: &mut [u32]) {
        use rayon::prelude::*;
        // Rows in parallel: a 1080p film is 2M divisions of 128-bit sums.
        let row = self.width.max(1) as usize;
        out.par_chunks_mut(row).enumerate().for_each(|(y, out)| {
            for (x, o) in out.iter_mut().enumerate() {
                let [r, g, b] = self.pixel_mean(y * row + x).map(|v| spectral::srgb_to_u8(v as f32) as u32);
                *o = (r << 16) | (g << 8) | b;
            }
        });
    }

    /// The mean image as linear-sRGB floats, row-major RGB.
    pub fn mean_rgb(&self) -> Vec<f32> {
        (0..self.pixels.len()).flat_map(|i| self.pixel_mean(i).map(|v| v as f32)).collect()
    }

    /// The per-pixel standard error of the mean, row-major RGB.
    pub fn std_error_rgb(&self) -> Vec<f32> {
        self.pixels.iter().flat_map(|p| p.std_error().map(|v| v as f32)).collect()
    }

    /// The image-wide mean of each channel.
    pub fn channel_means(&self) -> [f64; 3] {
        let n = self.pixels.len().max(1) as f64;
        let mut sum = [0.0; 3];
        for i in 0..self.pixels.len() {
            let m = self.pixel_mean(i);
            for c in 0..3 {
                sum[c] += m[c];
            }
        }
        sum.map(|s| s / n)
    }

    /// Total accepted samples.
    pub fn samples(&self) -> u64 {
        self.pixels.iter().map(|p| p.count as u64).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_pixels_are_srgb_encoded_0rgb() {
        let mut film = Film::new(3, 1);
        let px = film.pixels_mut();
        assert!(px[0].add([1.0, 0.0, 0.5]));
        assert!(px[1].add([7.0, -1.0, 0.0]));
        let mut out = vec![0xdead_beef; 3];
        film.display_pixels(&mut out);
        let half = spectral::srgb_to_u8(0.5) as u32;
        assert_eq!(half, 188);
        assert_eq!(out, [0xff_00_00 | half, 0xff_00_00, 0]);
        film.clear();
        assert_eq!(film, Film::new(3, 1));
    }

    #[test]
    fn sums_match_the_two_pass_formulas() {
        let xs = [0.5f32, 2.0, -1.0, 4.0, 3.5, 0.0, 1e-9, 3e7];
        let mut p = PixelStats::default();
        for x in xs {
            assert!(p.add([x, 2.0 * x, 1.0]));
        }
        let n = xs.len() as f64;
        let mean = xs.iter().map(|&x| x as f64).sum::<f64>() / n;
        let var = xs.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0);
        assert!((p.mean()[0] - mean).abs() <= 1e-15 * mean.abs());
        assert!((p.std_error()[0] / (var / n).sqrt() - 1.0).abs() < 1e-12);
        assert!((p.std_error()[1] / (2.0 * (var / n).sqrt()) - 1.0).abs() < 1e-12);
        assert_eq!(p.mean()[2], 1.0);
        assert_eq!(p.std_error()[2], 0.0);
    }

    /// The point of fixed point: any grouping and any order of merging gives the same
    /// bits.
    #[test]
    fn grouping_and_order_do_not_change_a_bit() {
        let mut rng = rng::Pcg32::new(7, 1);
        let xs: Vec<[f32; 3]> = (0..1000)
            .map(|_| {
                let u = rng.next_f32();
                [u, (1.0 / (u + 1e-6)).powi(2), -u * 1e-7]
            })
            .collect();
        let mut whole = PixelStats::default();
        xs.iter().for_each(|&x| assert!(whole.add(x)));
        for (k, chunk) in [1usize, 7, 64, 333].into_iter().enumerate() {
            let mut parts: Vec<PixelStats> = xs
                .chunks(chunk)
                .map(|c| {
                    let mut p = PixelStats::default();
                    c.iter().for_each(|&x| assert!(p.add(x)));
                    p
                })
                .collect();
            if k % 2 == 1 {
                parts.reverse();
            }
            let mut merged = PixelStats::default();
            parts.iter().for_each(|p| merged.merge(p));
            assert_eq!(merged, whole, "chunks of {chunk}");
        }
    }

    #[test]
    fn out_of_range_samples_are_refused_whole() {
        let mut p = PixelStats::default();
        assert!(!p.add([1.0, f32::NAN, 1.0]));
        assert!(!p.add([1.0, 1.0, f32::INFINITY]));
        assert!(!p.add([-MAX_SAMPLE_MAGNITUDE, 0.0, 0.0]));
        assert_eq!(p, PixelStats::default());
        let below = f32::from_bits(MAX_SAMPLE_MAGNITUDE.to_bits() - 1);
        assert!(p.add([below, -below, 0.0]));
        // The largest pixel the caps allow does not overflow.
        let mut big = PixelStats::default();
        for _ in 0..64 {
            big.merge(&p);
        }
        let mut full = PixelStats::default();
        for _ in 0..MAX_PIXEL_SAMPLES / 64 {
            full.merge(&big);
        }
        assert_eq!(full.count, MAX_PIXEL_SAMPLES);
        assert!((full.mean()[0] / below as f64 - 1.0).abs() < 1e-12);
        assert_eq!(full.std_error()[2], 0.0);
    }

    /// The integer rounding equals the f64 one (exact product, one rounding) on edge
    /// cases and a million random bit patterns in range.
    #[test]
    fn fixed_point_equals_the_exact_float_rounding() {
        let reference = |x: f32| {
            let x = x as f64;
            (
                (x * 2f64.powi(SUM_FRACTION_BITS)).round() as i128,
                (x * x * 2f64.powi(SQUARE_FRACTION_BITS)).round() as u128,
            )
        };
        let below_max = f32::from_bits(MAX_SAMPLE_MAGNITUDE.to_bits() - 1);
        let edges = [0.0, -0.0, 1.0, -1.0, 0.5, 1.5, -2.5, f32::MIN_POSITIVE, 1e-45, -1e-45, 2f32.powi(-18), below_max];
        // Values at exactly half a unit of the squares' grid: x² · 2³⁶ = k + ½.
        let halves = [2f32.powi(-18) * 1.5, 2f32.powi(-19) * 3.0, 3.0 * 2f32.powi(-19) * 1.0000001];
        for x in edges.into_iter().chain(halves) {
            assert_eq!(fixed_point(x), reference(x), "{x:e}");
        }
        let mut rng = rng::Pcg32::new(11, 3);
        let mut checked = 0;
        while checked < 1_000_000 {
            let x = f32::from_bits(rng.next_u32());
            if x.is_finite() && x.abs() < MAX_SAMPLE_MAGNITUDE {
                assert_eq!(fixed_point(x), reference(x), "{x:e}");
                checked += 1;
            }
        }
    }

    /// The chunked floating-point conversion gives the integer conversion's bits: on the
    /// edge cases above, both signs of values at half a unit of either grid, a million
    /// random bit patterns in range, and in chunks that are not full.
    #[test]
    fn chunks_convert_to_the_integer_conversions_bits() {
        let check = |values: &[f32]| {
            let chunk = FixedPointChunk::convert(values);
            for (k, &x) in values.iter().enumerate() {
                assert_eq!(chunk.get(k), fixed_point(x), "{x:e}");
            }
        };
        let below_max = f32::from_bits(MAX_SAMPLE_MAGNITUDE.to_bits() - 1);
        let mut edges = vec![0.0, -0.0, 1.0, 0.5, 1.5, 2.5, f32::MIN_POSITIVE, 1e-45, 2f32.powi(-18), below_max];
        // Halves of the sums' grid (x · 2⁶⁴ = k + ½) and of the squares' (x² · 2³⁶ = k + ½),
        // values whose sum has a zero low word (negated, the carry into the high word), and
        // neighbours of powers of two.
        edges.extend([2f32.powi(-65), 3.0 * 2f32.powi(-66), 2f32.powi(-18) * 1.5, 2f32.powi(-19) * 3.0]);
        edges.extend([f32::from_bits(1.0f32.to_bits() - 1), 2f32.powi(-15) * (1.0 - 2f32.powi(-24)), 65_536.0]);
        edges.extend([2f32.powi(34 - 1) * 1.999_999_9, 4096.0 * (1.0 + f32::EPSILON)]);
        let negated: Vec<f32> = edges.iter().map(|x| -x).collect();
        edges.extend(negated);
        for values in edges.chunks(3 * CHUNK_SAMPLES) {
            check(values);
        }
        let mut rng = rng::Pcg32::new(12, 5);
        let mut values = Vec::new();
        while values.len() < 1_000_000 {
            let x = f32::from_bits(rng.next_u32());
            if x.is_finite() && x.abs() < MAX_SAMPLE_MAGNITUDE {
                values.push(x);
            }
        }
        for values in values.chunks(3 * CHUNK_SAMPLES) {
            check(values);
        }
        // Samples of a render's magnitudes, in short chunks.
        let values: Vec<f32> = (0..100_000).map(|_| (rng.next_f32() - 0.1) * 4.0).collect();
        for values in values.chunks(7) {
            check(values);
        }
    }

    /// Adding a block of samples by chunks gives the pixels one-at-a-time addition gives,
    /// and refuses the same samples (NaN, infinite, too large) whole.
    #[test]
    fn samples_added_by_chunks_equal_samples_added_one_at_a_time() {
        let mut rng = rng::Pcg32::new(13, 7);
        let bad = [f32::NAN, f32::INFINITY, -f32::INFINITY, MAX_SAMPLE_MAGNITUDE, -1e30];
        let (mut owners, mut rgb) = (Vec::new(), Vec::new());
        let mut owner = 0u32;
        for _ in 0..5_000 {
            if rng.next_f32() < 0.1 {
                owner = (rng.next_f32() * 37.0) as u32;
            }
            let mut c = [0.0f32; 3].map(|_| (rng.next_f32() - 0.05) * 10f32.powf(rng.next_f32() * 12.0 - 6.0));
            if rng.next_f32() < 0.02 {
                c[(rng.next_f32() * 3.0) as usize % 3] = bad[(rng.next_f32() * 5.0) as usize % 5];
            }
            owners.push(owner);
            rgb.push(c);
        }
        let mut expected = vec![PixelStats::default(); 37];
        let refused_expected = add_samples_one_at_a_time(&mut expected, &owners, &rgb);
        assert!(refused_expected > 50, "the test has refused samples: {refused_expected}");
        for len in [rgb.len(), 1, 16, 17, 1_000] {
            let mut pixels = vec![PixelStats::default(); 37];
            let mut refused = 0;
            for (o, c) in owners.chunks(len).zip(rgb.chunks(len)) {
                refused += add_samples(&mut pixels, o, c);
            }
            assert_eq!(refused, refused_expected);
            assert_eq!(pixels, expected, "blocks of {len}");
        }
    }

    /// Adds `splats` to `film` through a splat image, as a backend does.
    fn add_splats(film: &mut Film, splats: &[Splat]) {
        let mut image = SplatImage::new(film.width(), film.height());
        image.add(splats);
        film.add_splat_image(&image);
    }

    #[test]
    fn splats_add_exactly_over_the_light_paths_and_bad_ones_are_dropped() {
        let mut film = Film::new(3, 2);
        film.pixels_mut()[4].add([0.5, 0.5, 0.5]);
        let splats = [
            Splat { x: 1, y: 1, rgb: [2.0, 4.0, 0.25] },
            Splat { x: 1, y: 1, rgb: [1.0, 0.0, 0.25] },
            Splat { x: 0, y: 0, rgb: [3.0, 3.0, 3.0] },
        ];
        let mut reversed = film.clone();
        add_splats(&mut film, &splats);
        for s in splats.iter().rev() {
            add_splats(&mut reversed, std::slice::from_ref(s));
        }
        for f in [&mut film, &mut reversed] {
            f.count_light_paths(4);
            add_splats(
                f,
                &[
                    Splat { x: 3, y: 0, rgb: [1.0; 3] },
                    Splat { x: 0, y: 1, rgb: [f32::NAN, 0.0, 0.0] },
                    Splat { x: 0, y: 1, rgb: [MAX_SAMPLE_MAGNITUDE, 0.0, 0.0] },
                ],
            );
        }
        assert_eq!(film, reversed, "order does not matter");
        assert_eq!(film.non_finite, 3);
        assert!(film.has_splats() && film.light_paths() == 4);
        assert_eq!(film.pixel_mean(4), [0.5 + 0.75, 0.5 + 1.0, 0.5 + 0.125]);
        assert_eq!(film.pixel_mean(0), [0.75; 3]);
        assert_eq!(film.pixel_mean(1), [0.0; 3]);
        let rgb = film.mean_rgb();
        assert_eq!(&rgb[12..15], &[1.25, 1.5, 0.625]);
        film.clear();
        assert_eq!((film.pixel_mean(4), film.light_paths()), ([0.0; 3], 0));
    }

    #[test]
    fn splat_images_add_exactly_and_overflow_is_dropped() {
        let splats = [Splat { x: 2, y: 0, rgb: [1.5, 0.25, 3.0] }, Splat { x: 2, y: 0, rgb: [0.5, 0.0, 1.0] }];
        let mut direct = Film::new(3, 2);
        add_splats(&mut direct, &splats);
        let mut via = Film::new(3, 2);
        add_splats(&mut via, &splats[1..]);
        add_splats(&mut via, &splats[..1]);
        assert_eq!(direct, via, "one image or two, in any order");
        // Sums that would overflow an i128 are dropped, not wrapped.
        let mut film = Film::new(1, 1);
        film.add_splat_sum(0, [i128::MAX - 5, 0, 0]);
        film.add_splat_sum(0, [10, 0, 0]);
        assert_eq!((film.splat_sums().unwrap()[0][0], film.non_finite), (i128::MAX - 5, 1));
    }

    #[test]
    fn moments_convert_back() {
        let mut p = PixelStats::default();
        for x in [0.25f32, 0.5, 1.75, 3.0] {
            p.add([x, x * 0.1, -x]);
        }
        let q = PixelStats::from_moments(p.count, p.mean(), p.m2());
        for c in 0..3 {
            assert!((q.mean()[c] - p.mean()[c]).abs() < 1e-15);
            assert!((q.m2()[c] - p.m2()[c]).abs() < 1e-9);
        }
    }
}
