//! The workspace's one random-number generator: PCG32 (M. E. O'Neill, "PCG: A family of
//! simple fast space-efficient statistically good algorithms for random number
//! generation", HMC-CS-2014-0905, 2014), XSH-RR output on a 64-bit LCG state with a
//! selectable stream.
//!
//! The renderer seeds one generator per pixel sample ([`Pcg32::for_sample`]), so that
//! every sample's random stream depends only on (seed, pixel, sample index) — never on
//! which thread draws it — and a render is bit-identical for a seed whatever the thread
//! count. Benchmark ray sets and tests seed one from a single `u64`
//! ([`Pcg32::seed_from_u64`]). Seeds are decorrelated by splitmix64's output function
//! ([`mix64`]: G. L. Steele, D. Lea, C. H. Flood, "Fast splittable pseudorandom number
//! generators", OOPSLA 2014, with Stafford's "Mix13" constants as in Vigna's
//! `splitmix64.c`).
//!
//! Small conveniences (uniform floats, ranges, integers below a bound, coins, 2-D samples,
//! unit vectors) live here too so that no crate grows its own generator again; they are
//! deterministic functions of the stream, so fixed seeds give fixed cases everywhere.

use glam::{DVec3, Vec2};

/// The PCG32 generator (XSH-RR output, 64-bit state, selectable stream).
///
/// Not cryptographic; small, fast and statistically good, which is what Monte Carlo
/// sampling and reproducible test cases need.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

/// The LCG multiplier of PCG32 (O'Neill's reference implementation).
pub const MULT: u64 = 6_364_136_223_846_793_005;

/// The key [`Pcg32::for_sample`] mixes into a sample's seed to choose its stream.
pub const SAMPLE_STREAM_KEY: u64 = 0xDA94_2042_E4DD_58B5;

/// The first multiplier of [`mix64`].
pub const MIX64_MUL1: u64 = 0xBF58_476D_1CE4_E5B9;
/// The second multiplier of [`mix64`].
pub const MIX64_MUL2: u64 = 0x94D0_49BB_1331_11EB;

/// splitmix64's increment (2⁶⁴/φ, odd), added to its state before each output.
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

impl Pcg32 {
    /// A generator on stream `stream` started from `seed` (the reference `pcg32_srandom`),
    /// so that the reference implementation's published sequences can be checked.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self { state: 0, inc: (stream << 1) | 1 };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The generator for one pixel sample: its stream and seed are hashes of all inputs,
    /// so neighbouring pixels and samples get unrelated streams.
    pub fn for_sample(seed: u64, pixel: u32, sample: u32) -> Self {
        let key = mix64(seed ^ mix64(((pixel as u64) << 32) | sample as u64));
        Self::new(key, mix64(key ^ SAMPLE_STREAM_KEY))
    }

    /// A generator from one `u64` (any value, 0 included): its seed and stream are the
    /// first two outputs of splitmix64 started at `seed`, so that nearby seeds (1, 2, 3,
    /// …) give unrelated streams — what tests and benchmarks with small fixed seeds need.
    pub fn seed_from_u64(seed: u64) -> Self {
        let state = mix64(seed.wrapping_add(GOLDEN_GAMMA));
        let stream = mix64(seed.wrapping_add(GOLDEN_GAMMA.wrapping_mul(2)));
        Self::new(state, stream)
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// The next 64 random bits: two outputs, the first in the high half (for integer
    /// ranges and 53-bit floats, which one 32-bit output cannot fill).
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let hi = self.next_u32() as u64;
        let lo = self.next_u32() as u64;
        (hi << 32) | lo
    }

    /// A uniform float in [0, 1) (24 random mantissa bits, never 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// A uniform double in [0, 1) (53 random mantissa bits from [`Pcg32::next_u64`], never
    /// 1), for references computed in f64.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniform floats in [0, 1), x drawn first: a sample of the unit square.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        Vec2::new(self.next_f32(), self.next_f32())
    }

    /// Uniform in [lo, hi) in f64 (lo + (hi − lo)·[`Pcg32::next_f64`]).
    #[inline]
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    /// Uniform in [lo, hi) in f32 (lo + (hi − lo)·[`Pcg32::next_f32`]).
    #[inline]
    pub fn range_f32(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }

    /// Uniform in 0..n by a widening multiply (Lemire 2019, without the rejection step:
    /// the bias is below n/2⁶⁴, far beneath anything a test can see); 0 for n = 0.
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }

    /// A fair coin (the top bit of one output).
    #[inline]
    pub fn coin(&mut self) -> bool {
        self.next_u32() >> 31 == 1
    }

    /// A direction uniform on the unit sphere, by rejection from the cube [−1, 1)³ (points
    /// too close to the centre are rejected too, so the normalisation is accurate).
    pub fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            let l2 = v.length_squared();
            if l2 > 1e-4 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
    }
}

/// splitmix64's 64-bit output function (Stafford's "Mix13" finaliser): a bijection that
/// scrambles every input bit into every output bit, used to decorrelate seeds.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(MIX64_MUL1);
    z = (z ^ (z >> 27)).wrapping_mul(MIX64_MUL2);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_pcg32_reference_sequence() {
        // pcg32-demo with seed 42, stream 54 prints these first values.
        let mut r = Pcg32::new(42, 54);
        let got: Vec<u32> = (0..6).map(|_| r.next_u32()).collect();
        assert_eq!(got, [0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e]);
    }

    #[test]
    fn mix64_is_the_splitmix64_output() {
        // Vigna's splitmix64.c started at 1234567 outputs these first values; its n-th
        // output is mix64(seed + n·γ).
        let want = [6457827717110365317u64, 3203168211198807973, 9817491932198370423];
        for (n, w) in want.into_iter().enumerate() {
            assert_eq!(mix64(1234567u64.wrapping_add(GOLDEN_GAMMA.wrapping_mul(n as u64 + 1))), w);
        }
    }

    #[test]
    fn floats_are_uniform_and_below_one() {
        let mut r = Pcg32::for_sample(1, 2, 3);
        let n = 100_000;
        let mut hist = [0u32; 10];
        for _ in 0..n {
            let x = r.next_f32();
            assert!((0.0..1.0).contains(&x));
            hist[(x * 10.0) as usize] += 1;
        }
        // χ² with 9 dof; 21.67 is the 0.99 quantile.
        let e = n as f64 / 10.0;
        let chi2: f64 = hist.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 21.67, "χ² = {chi2}");
    }

    #[test]
    fn neighbouring_pixels_are_uncorrelated() {
        // Correlation of the first draw across adjacent pixels must be ~0.
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|p| Pcg32::for_sample(7, p, 0).next_f32() as f64).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        let cov = xs.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum::<f64>() / (n - 1) as f64;
        assert!((cov / var).abs() < 0.03, "lag-1 correlation {}", cov / var);
    }

    #[test]
    fn neighbouring_u64_seeds_are_uncorrelated() {
        let n = 20_000u64;
        let xs: Vec<f64> = (0..n).map(|s| Pcg32::seed_from_u64(s).next_f64()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        let cov = xs.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum::<f64>() / (n - 1) as f64;
        assert!((mean - 0.5).abs() < 0.01 && (var - 1.0 / 12.0).abs() < 0.003, "mean {mean}, variance {var}");
        assert!((cov / var).abs() < 0.03, "lag-1 correlation {}", cov / var);
        assert_eq!(Pcg32::seed_from_u64(9).next_u64(), Pcg32::seed_from_u64(9).next_u64(), "deterministic");
    }

    #[test]
    fn wide_outputs_are_composed_of_narrow_ones() {
        let (mut a, mut b) = (Pcg32::new(5, 6), Pcg32::new(5, 6));
        let (hi, lo) = (b.next_u32() as u64, b.next_u32() as u64);
        assert_eq!(a.next_u64(), (hi << 32) | lo);
        let (x, y) = (b.next_f32(), b.next_f32());
        assert_eq!(a.next_2d(), Vec2::new(x, y));
        let bits = b.next_u64() >> 11;
        assert_eq!(a.next_f64(), bits as f64 / (1u64 << 53) as f64);
    }

    #[test]
    fn ranges_integers_coins_and_directions() {
        let mut r = Pcg32::seed_from_u64(3);
        let n = 60_000;
        let mut counts = [0u32; 6];
        let (mut heads, mut sum) = (0u32, DVec3::ZERO);
        for _ in 0..n {
            let x = r.range(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
            let y = r.range_f32(0.5, 0.75);
            assert!((0.5..0.75).contains(&y));
            counts[r.below(6) as usize] += 1;
            heads += r.coin() as u32;
            let v = r.unit_vector();
            assert!((v.length() - 1.0).abs() < 1e-12);
            sum += v;
        }
        assert_eq!(r.below(0), 0);
        // χ² with 5 dof; 15.09 is the 0.99 quantile.
        let e = n as f64 / 6.0;
        let chi2: f64 = counts.iter().map(|&o| (o as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 15.09, "χ² = {chi2}: {counts:?}");
        // Six standard deviations: 0.5·√n coins, √(n/3) per component of the vector sum.
        assert!((heads as f64 - 0.5 * n as f64).abs() < 6.0 * 0.5 * (n as f64).sqrt(), "{heads} heads");
        assert!(sum.abs().max_element() < 6.0 * (n as f64 / 3.0).sqrt(), "{sum}");
    }
}
