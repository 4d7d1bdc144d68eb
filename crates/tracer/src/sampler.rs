//! Where an integrator's random numbers come from: a [`Sampler`] is the stream of one
//! pixel sample, consumed dimension by dimension (a 1-D value for a choice, a 2-D point
//! for a direction or a position).
//!
//! * [`Pcg32`] — independent uniform numbers: PCG32 (O'Neill 2014) seeded per pixel
//!   sample, so that every sample's stream depends only on (seed, pixel, sample index) —
//!   never on which thread draws it. (The thesis's sine hash, listing 8.1, correlates
//!   badly; see the tests of the `rng` crate.) The generator lives in the `rng` crate.
//! * [`ZSobol`] — Owen-scrambled Sobol points in Morton order over the image (Ahmed &
//!   Wonka 2020, "Screen-Space Blue-Noise Diffusion of Monte Carlo Sampling Error via
//!   Hierarchical Ordering of Pixels", SIGGRAPH Asia; pbrt-v4's `ZSobolSampler`): every
//!   2-D dimension pair of a pixel's samples is a (0, 2)-sequence — stratified at every
//!   power-of-two prefix — scrambled independently per dimension, and neighbouring pixels'
//!   samples continue one another's sequence, which spreads the error as blue noise.

use glam::Vec2;
pub use rng::{Pcg32, mix64};

/// One pixel sample's stream of sample values.
pub trait Sampler: Clone + Send + std::fmt::Debug {
    /// The next value in [0, 1).
    fn next_1d(&mut self) -> f32;

    /// The next 2-D point in [0, 1)².
    fn next_2d(&mut self) -> Vec2;

    /// The camera's values: the wavelength sample (drawn only if `wavelength`, else 0) and
    /// the jitter within the pixel. The independent sampler draws them in this order;
    /// samplers whose first dimensions are best stratified give those to the jitter.
    fn camera(&mut self, wavelength: bool) -> (f32, Vec2) {
        let u = if wavelength { self.next_1d() } else { 0.0 };
        (u, self.next_2d())
    }
}

impl Sampler for Pcg32 {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.next_f32()
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        Pcg32::next_2d(self)
    }
}

/// How a render draws its sample values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// Independent uniform numbers ([`Pcg32`]).
    #[default]
    Independent,
    /// Owen-scrambled Sobol in Morton order ([`ZSobol`]).
    ZSobol,
}

impl SamplerKind {
    /// Every kind.
    pub const ALL: [SamplerKind; 2] = [Self::Independent, Self::ZSobol];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Independent => "independent",
            Self::ZSobol => "zsobol",
        }
    }
}

/// The layout a [`ZSobol`] sampler needs of the whole render: how many base-4 digits its
/// Morton-ordered sample indices have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ZSobolLayout {
    log2_spp: u32,
    base4_digits: u32,
    seed: u32,
}

impl ZSobolLayout {
    /// The layout for `spp` samples per pixel (rounded up to a power of two) on an image
    /// of `width` × `height`, with `seed` scrambling every dimension.
    pub fn new(width: u32, height: u32, spp: u32, seed: u64) -> Self {
        let log2_spp = (spp.max(1) as u64).next_power_of_two().trailing_zeros();
        let res = width.max(height).max(1).next_power_of_two();
        let log2_res = res.trailing_zeros();
        Self { log2_spp, base4_digits: log2_res + log2_spp.div_ceil(2), seed: mix64(seed) as u32 }
    }

    /// The sampler for sample `index` (< the layout's spp) of pixel (x, y).
    #[inline]
    pub fn sampler(&self, x: u32, y: u32, index: u32) -> ZSobol {
        let morton = (morton2(x, y) << self.log2_spp) | index as u64;
        ZSobol { layout: *self, morton, dimension: 0 }
    }
}

/// Owen-scrambled Sobol points in Morton order (see the module documentation). Made by
/// [`ZSobolLayout::sampler`].
#[derive(Clone, Debug)]
pub struct ZSobol {
    layout: ZSobolLayout,
    morton: u64,
    dimension: u32,
}

/// All 24 permutations of (0, 1, 2, 3), for shuffling base-4 digits.
const PERMUTATIONS: [[u8; 4]; 24] = [
    [0, 1, 2, 3],
    [0, 1, 3, 2],
    [0, 2, 1, 3],
    [0, 2, 3, 1],
    [0, 3, 2, 1],
    [0, 3, 1, 2],
    [1, 0, 2, 3],
    [1, 0, 3, 2],
    [1, 2, 0, 3],
    [1, 2, 3, 0],
    [1, 3, 2, 0],
    [1, 3, 0, 2],
    [2, 1, 0, 3],
    [2, 1, 3, 0],
    [2, 0, 1, 3],
    [2, 0, 3, 1],
    [2, 3, 0, 1],
    [2, 3, 1, 0],
    [3, 1, 2, 0],
    [3, 1, 0, 2],
    [3, 2, 1, 0],
    [3, 2, 0, 1],
    [3, 0, 2, 1],
    [3, 0, 1, 2],
];

impl ZSobol {
    /// The index of this sample in the Sobol sequence for the current dimension: the
    /// Morton index with each base-4 digit permuted by a hash of the digits above it and
    /// the dimension (so that every dimension visits the pixels' quadrants in another
    /// order, and the samples of a pixel are a contiguous, stratified run).
    #[inline]
    fn sample_index(&self) -> u64 {
        let odd = self.layout.log2_spp & 1 == 1;
        let last_digit = u32::from(odd);
        let dim_mix = 0x5555_5555u64.wrapping_mul(self.dimension as u64);
        let mut index = 0u64;
        let mut i = self.layout.base4_digits;
        while i > last_digit {
            i -= 1;
            let shift = 2 * i - u32::from(odd);
            let digit = (self.morton >> shift) & 3;
            let higher = self.morton >> (shift + 2);
            let p = ((mix64(higher ^ dim_mix) >> 24) % 24) as usize;
            index |= (PERMUTATIONS[p][digit as usize] as u64) << shift;
        }
        if odd {
            let digit = self.morton & 1;
            index |= digit ^ (mix64((self.morton >> 1) ^ dim_mix) & 1);
        }
        index
    }

    /// A hash of the dimension and the render's seed, for the scrambling.
    #[inline]
    fn hash(&self) -> u64 {
        mix64(((self.dimension as u64) << 32) ^ self.layout.seed as u64 ^ 0xA511_E9B3_0000_0000)
    }
}

impl Sampler for ZSobol {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        let index = self.sample_index();
        let hash = self.hash() as u32;
        self.dimension += 1;
        to_unit(owen_scramble(sobol_0(index), hash))
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let index = self.sample_index();
        let hash = self.hash();
        self.dimension += 2;
        Vec2::new(
            to_unit(owen_scramble(sobol_0(index), hash as u32)),
            to_unit(owen_scramble(sobol_1(index), (hash >> 32) as u32)),
        )
    }

    /// The jitter first: the first dimension pair is the best stratified.
    fn camera(&mut self, wavelength: bool) -> (f32, Vec2) {
        let jitter = self.next_2d();
        (if wavelength { self.next_1d() } else { 0.0 }, jitter)
    }
}

/// A 32-bit fixed-point fraction as an f32 in [0, 1) (24 bits, never 1).
#[inline]
fn to_unit(v: u32) -> f32 {
    (v >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The first Sobol dimension (van der Corput in base 2): the index's bits reversed.
#[inline]
fn sobol_0(index: u64) -> u32 {
    (index as u32).reverse_bits()
}

/// The second Sobol dimension (primitive polynomial x + 1, m₁ = 1): direction numbers
/// v₁ = 2³¹, vₖ = vₖ₋₁ ⊕ (vₖ₋₁ ≫ 1); the point is the XOR of the vₖ of the index's set bits.
/// With [`sobol_0`] it forms a (0, 2)-sequence in base 2.
#[inline]
fn sobol_1(index: u64) -> u32 {
    let mut v = 1u32 << 31;
    let mut out = 0u32;
    let mut i = index as u32;
    while i != 0 {
        if i & 1 != 0 {
            out ^= v;
        }
        v ^= v >> 1;
        i >>= 1;
    }
    out
}

/// Owen scrambling by hashing (pbrt-v4's `FastOwenScrambler`, after Laine & Karras 2011
/// and Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)): every bit is
/// flipped by a hash of the bits above it, so stratification is kept and the points are
/// uniformly distributed for a random seed.
#[inline]
fn owen_scramble(v: u32, seed: u32) -> u32 {
    let mut v = v.reverse_bits();
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v.reverse_bits()
}

/// The Morton (Z-order) code of (x, y): their bits interleaved, x in the even bits.
#[inline]
fn morton2(x: u32, y: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = v as u64;
        v = (v | (v << 16)) & 0x0000_FFFF_0000_FFFF;
        v = (v | (v << 8)) & 0x00FF_00FF_00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    }
    spread(x) | (spread(y) << 1)
}

#[cfg(test)]
mod tests;
