//! Random numbers: PCG32 (O'Neill 2014) seeded per pixel sample, so that every sample's
//! random stream depends only on (seed, pixel, sample index) — never on which thread
//! draws it. (The thesis's sine hash, listing 8.1, correlates badly; see the tests.)

/// The PCG32 generator (XSH-RR output, 64-bit state, selectable stream).
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

const MULT: u64 = 6_364_136_223_846_793_005;

impl Pcg32 {
    /// A generator on stream `stream` started from `seed` (the reference `pcg32_srandom`).
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self { state: 0, inc: (stream << 1) | 1 };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The generator for one pixel sample: its stream and seed are hashes of all inputs.
    pub fn for_sample(seed: u64, pixel: u32, sample: u32) -> Self {
        let key = mix64(seed ^ mix64(((pixel as u64) << 32) | sample as u64));
        Self::new(key, mix64(key ^ 0xDA94_2042_E4DD_58B5))
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

    /// A uniform float in [0, 1) (24 random mantissa bits, never 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Two uniform floats.
    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        glam::Vec2::new(self.next_f32(), self.next_f32())
    }
}

/// A 64-bit finaliser (splitmix64 / Stafford's mix13) to decorrelate seeds.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
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
}
