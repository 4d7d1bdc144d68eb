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

    /// The next 2-D point, or what computing it needs, for the lanes to compute many
    /// samplers' points at once ([`SobolLanes::values_2d`]): the same point
    /// [`Sampler::next_2d`] would return, the sampler advanced alike. The default draws
    /// the point.
    #[inline]
    fn lane_draw_2d(&mut self) -> LaneDraw {
        LaneDraw::Value(self.next_2d())
    }

    /// As [`Sampler::lane_draw_2d`] for [`Sampler::next_1d`]'s value (a drawn value in
    /// x, y 0; the values computed by [`SobolLanes::values_1d`]).
    #[inline]
    fn lane_draw_1d(&mut self) -> LaneDraw {
        LaneDraw::Value(Vec2::new(self.next_1d(), 0.0))
    }
}

/// One 2-D draw as [`Sampler::lane_draw_2d`] hands it out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LaneDraw {
    /// The point, drawn already.
    Value(Vec2),
    /// A scrambled Sobol point still to be computed, with all it depends on.
    Sobol(SobolLane),
}

/// What one scrambled Sobol 2-D point depends on, in 32 bits: the sample's bit-reversed
/// index, its scramble's seeds, and the seeds that scramble the two values. Exact where
/// the sample indices have at most 32 bits (every render up to 65,536² pixels at one
/// sample, or 4,096² at 256): the index scramble (`laine_karras_64`) only carries upwards,
/// so the low 32 bits of its result, the only ones a 32-bit index keeps, depend only on
/// the low 32 bits of its operands.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SobolLane {
    reversed: u32,
    index_add: u32,
    index_mul: u32,
    /// The index's right shift after the reversal; 32 or more: no index bits (index 0).
    shift: u32,
    value_seeds: u64,
}

/// [`SobolLane`]s side by side, one array per field, so that [`SobolLanes::values_2d`]
/// computes `L` points with vector instructions where its caller is compiled for them
/// (32-bit multiplies and byte shuffles for the bit reversals; the 64-bit multiplies of
/// the one-at-a-time draw have no AVX2 instruction).
#[derive(Clone, Debug)]
pub struct SobolLanes<const L: usize> {
    reversed: [u32; L],
    index_add: [u32; L],
    index_mul: [u32; L],
    shift: [u32; L],
    seed_x: [u32; L],
    seed_y: [u32; L],
}

impl<const L: usize> Default for SobolLanes<L> {
    fn default() -> Self {
        Self { reversed: [0; L], index_add: [0; L], index_mul: [0; L], shift: [32; L], seed_x: [0; L], seed_y: [0; L] }
    }
}

impl<const L: usize> SobolLanes<L> {
    /// Puts `d` in lane `k`.
    #[inline(always)]
    pub fn set(&mut self, k: usize, d: &SobolLane) {
        self.reversed[k] = d.reversed;
        self.index_add[k] = d.index_add;
        self.index_mul[k] = d.index_mul;
        self.shift[k] = d.shift;
        self.seed_x[k] = d.value_seeds as u32;
        self.seed_y[k] = (d.value_seeds >> 32) as u32;
    }

    /// Every lane's 1-D value, the same bits as [`Sampler::next_1d`]'s (see
    /// [`SobolLanes::values_2d`]).
    #[inline(always)]
    pub fn values_1d(&self, x: &mut [f32; L]) {
        let mut index = [0u32; L];
        self.indices_and_x(&mut index, x);
    }

    /// Every lane's 2-D point, the same bits as [`Sampler::next_2d`]'s (lanes never set
    /// hold index 0's point of seed 0). Inlined, so that it is compiled for the vector
    /// instructions of the function that calls it.
    #[inline(always)]
    pub fn values_2d(&self, x: &mut [f32; L], y: &mut [f32; L]) {
        let mut index = [0u32; L];
        self.indices_and_x(&mut index, x);
        for k in 0..L {
            y[k] = to_unit(owen_scramble_reversed(sobol_1_reversed(index[k]), self.seed_y[k]));
        }
    }

    /// Every lane's scrambled Sobol index and first value.
    #[inline(always)]
    fn indices_and_x(&self, index: &mut [u32; L], x: &mut [f32; L]) {
        let [m0, m1, m2] = LAINE_KARRAS_64_MULS.map(|m| m as u32);
        for k in 0..L {
            // `laine_karras_64` on the low 32 bits.
            let mut v = self.reversed[k];
            v ^= v.wrapping_mul(m0);
            v = v.wrapping_add(self.index_add[k]);
            v = v.wrapping_mul(self.index_mul[k]);
            v ^= v.wrapping_mul(m1);
            v ^= v.wrapping_mul(m2);
            let shift = self.shift[k];
            let i = v.reverse_bits() >> shift.min(31);
            index[k] = if shift >= 32 { 0 } else { i };
            x[k] = to_unit(scrambled_sobol_0(index[k] as u64, self.seed_x[k]));
        }
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
    /// Owen-scrambled Sobol per pixel, shuffled per dimension ([`PaddedSobol`]).
    Sobol,
    /// Owen-scrambled Sobol in Morton order ([`ZSobol`]).
    ZSobol,
}

impl SamplerKind {
    /// Every kind.
    pub const ALL: [SamplerKind; 3] = [Self::Independent, Self::Sobol, Self::ZSobol];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Independent => "independent",
            Self::Sobol => "sobol",
            Self::ZSobol => "zsobol",
        }
    }

    /// True if the sampler lays its samples out for the render's sample count, so that a
    /// pass may not go beyond it.
    pub fn needs_sample_budget(self) -> bool {
        !matches!(self, Self::Independent)
    }
}

/// Owen-scrambled Sobol points per pixel, "padded" (pbrt-v4's `PaddedSobolSampler`):
/// every 1-D value and 2-D point of dimension d is the scrambled Sobol point of the
/// sample's index shuffled by a hash of (pixel, d), so that the spp samples of a pixel
/// form, in every dimension pair, a (0, m, 2)-net — stratified like multi-jittered
/// samples — and dimensions are decorrelated. Cheaper than [`ZSobol`] (no Morton digit
/// shuffle), without its blue-noise distribution of the error over the image.
#[derive(Clone, Debug)]
pub struct PaddedSobol {
    pixel: u64,
    /// The sample index at the top of 64 bits, bit-reversed (as the index scramble wants).
    reversed: u64,
    /// 64 minus the bits of the sample indices.
    unused_bits: u32,
    dimension: u32,
}

impl PaddedSobol {
    /// The sampler for sample `index` of pixel (x, y) of a render of `spp` samples per
    /// pixel (rounded up to a power of two) seeded with `seed`.
    #[inline]
    pub fn new(x: u32, y: u32, index: u32, spp: u32, seed: u64) -> Self {
        let bits = (spp.max(1) as u64).next_power_of_two().trailing_zeros();
        let unused_bits = 64 - bits;
        let reversed = if bits == 0 { 0 } else { ((index as u64) << unused_bits).reverse_bits() };
        Self { pixel: mix64(seed ^ mix64(((x as u64) << 32) | y as u64)), reversed, unused_bits, dimension: 0 }
    }
}

impl SobolDraw for PaddedSobol {
    /// The index and the two scrambling seeds for the current dimension. The index gets
    /// a nested (Owen) scramble, as ZSobol's: every bit flipped by a hash of the bits
    /// above it, so each dimension visits the spp indices in its own order (an aligned
    /// block of 2ᵏ indices stays one). An xor-and-odd-multiply shuffle (the first version)
    /// keeps the index's low bit up to a constant, which ties the halves [0, ½) / [½, 1)
    /// of every dimension together: the error of such a render stopped falling at 256 spp
    /// (docs/compare.md).
    #[inline]
    fn draw(&mut self, dims: u32) -> SobolParts {
        let h = mix64(self.pixel ^ (self.dimension as u64).wrapping_mul(DIMENSION_MUL));
        self.dimension += dims;
        SobolParts { reversed: self.reversed, index_seed: h, value_seeds: mix64(h), unused_bits: self.unused_bits }
    }
}

/// One draw of a scrambled Sobol sampler: the sample's bit-reversed index (at the top of
/// 64 bits before the reversal), the seed of the index's scramble, the seeds that
/// scramble the values, and the bits of 64 the index leaves unused.
#[derive(Clone, Copy, Debug)]
struct SobolParts {
    reversed: u64,
    index_seed: u64,
    value_seeds: u64,
    unused_bits: u32,
}

impl SobolParts {
    /// The scrambled Sobol index of the draw.
    #[inline]
    fn index(&self) -> u64 {
        if self.unused_bits == 64 {
            0
        } else {
            laine_karras_64(self.reversed, self.index_seed).reverse_bits() >> self.unused_bits
        }
    }

    /// The 1-D value of the draw.
    #[inline]
    fn point_1d(&self) -> f32 {
        to_unit(scrambled_sobol_0(self.index(), self.value_seeds as u32))
    }

    /// The draw in 32 bits, where its index has at most 32 bits (see [`SobolLane`]).
    #[inline]
    fn lane(&self) -> Option<SobolLane> {
        (self.unused_bits >= 32).then(|| SobolLane {
            reversed: self.reversed as u32,
            index_add: self.index_seed as u32,
            index_mul: ((self.index_seed >> 32) | 1) as u32,
            shift: self.unused_bits - 32,
            value_seeds: self.value_seeds,
        })
    }

    /// The 2-D point of the draw.
    #[inline]
    fn point_2d(&self) -> Vec2 {
        let (index, seeds) = (self.index(), self.value_seeds);
        Vec2::new(
            to_unit(scrambled_sobol_0(index, seeds as u32)),
            to_unit(scrambled_sobol_1(index, (seeds >> 32) as u32)),
        )
    }
}

/// A scrambled Sobol sampler: per draw, what the sample's Sobol index and values depend on
/// in the current dimension (which the draw advances by `dims`).
trait SobolDraw: Clone + Send + std::fmt::Debug {
    fn draw(&mut self, dims: u32) -> SobolParts;
}

impl<T: SobolDraw> Sampler for T {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.draw(1).point_1d()
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        self.draw(2).point_2d()
    }

    /// The parts of the draw where the index has at most 32 bits (see [`SobolLane`]), else
    /// the point.
    #[inline]
    fn lane_draw_2d(&mut self) -> LaneDraw {
        let d = self.draw(2);
        d.lane().map_or_else(|| LaneDraw::Value(d.point_2d()), LaneDraw::Sobol)
    }

    /// As [`Sampler::lane_draw_2d`].
    #[inline]
    fn lane_draw_1d(&mut self) -> LaneDraw {
        let d = self.draw(1);
        d.lane().map_or_else(|| LaneDraw::Value(Vec2::new(d.point_1d(), 0.0)), LaneDraw::Sobol)
    }

    /// The jitter first: the first dimension pair is the best stratified.
    fn camera(&mut self, wavelength: bool) -> (f32, Vec2) {
        let jitter = self.next_2d();
        (if wavelength { self.next_1d() } else { 0.0 }, jitter)
    }
}

/// The layout a [`ZSobol`] sampler needs of the whole render: how many bits its
/// Morton-ordered sample indices have, and the per-dimension seeds (which depend only on
/// the render's seed and the dimension, so they are hashed once per render, not per draw).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ZSobolLayout {
    log2_spp: u32,
    /// 64 minus the bits of the Morton sample indices (which the scramble works on from
    /// the top).
    unused_bits: u32,
    seed: u64,
    /// (index scramble seed, value scramble seeds) for the first [`PRECOMPUTED_DIMENSIONS`].
    seeds: Vec<(u64, u64)>,
}

/// Dimensions whose seeds a [`ZSobolLayout`] precomputes (paths of ~30 bounces); deeper
/// dimensions hash theirs when drawn.
pub const PRECOMPUTED_DIMENSIONS: u32 = 256;

impl ZSobolLayout {
    /// The layout for `spp` samples per pixel (rounded up to a power of two) on an image
    /// of `width` × `height`, with `seed` scrambling every dimension.
    pub fn new(width: u32, height: u32, spp: u32, seed: u64) -> Self {
        let log2_spp = (spp.max(1) as u64).next_power_of_two().trailing_zeros();
        let log2_res = width.max(height).max(1).next_power_of_two().trailing_zeros();
        let seed = mix64(seed);
        let seeds = (0..PRECOMPUTED_DIMENSIONS).map(|d| dimension_seeds(seed, d)).collect();
        Self { log2_spp, unused_bits: 64 - (2 * log2_res + log2_spp), seed, seeds }
    }

    /// The sampler for sample `index` (< the layout's spp) of pixel (x, y).
    #[inline]
    pub fn sampler(&self, x: u32, y: u32, index: u32) -> ZSobol<'_> {
        let morton = (morton2(x, y) << self.log2_spp) | index as u64;
        // A 1×1 image at 1 spp has no index bits at all (and a shift by 64 would overflow).
        let reversed = if self.unused_bits == 64 { 0 } else { (morton << self.unused_bits).reverse_bits() };
        ZSobol { layout: self, reversed, dimension: 0 }
    }

    /// The (index scramble, value scramble) seeds of the first
    /// [`PRECOMPUTED_DIMENSIONS`] dimensions (the GPU uploads them per render).
    pub fn precomputed_seeds(&self) -> &[(u64, u64)] {
        &self.seeds
    }

    /// The seeds of `dimension`.
    #[inline]
    fn seeds(&self, dimension: u32) -> (u64, u64) {
        match self.seeds.get(dimension as usize) {
            Some(&s) => s,
            None => dimension_seeds(self.seed, dimension),
        }
    }
}

/// The golden-ratio multiplier that spreads dimension numbers before they are hashed.
pub const DIMENSION_MUL: u64 = 0x9E37_79B9_7F4A_7C15;

/// Mixed into the value seeds of [`ZSobol`]'s dimensions.
pub const VALUE_SEED_KEY: u64 = 0xA511_E9B3_0000_0000;

/// The multipliers of `laine_karras` (even: each bit depends only on the bits below).
pub const LAINE_KARRAS_MULS: [u32; 3] = [0x3d20_adea, 0x0552_6c56, 0x53a2_2864];

/// The multipliers of `laine_karras_64`.
pub const LAINE_KARRAS_64_MULS: [u64; 3] = [0x3d20_adea_6c5f_e1b2, 0x0552_6c56_a7d4_b3f8, 0x53a2_2864_91e3_c5a4];

/// (the index scramble's seed, the values' scramble seeds) of a dimension.
fn dimension_seeds(seed: u64, dimension: u32) -> (u64, u64) {
    let d = dimension as u64;
    (mix64(seed ^ d.wrapping_mul(DIMENSION_MUL)), mix64((d << 32) ^ seed ^ VALUE_SEED_KEY))
}

/// Owen-scrambled Sobol points in Morton order (see the module documentation). Made by
/// [`ZSobolLayout::sampler`].
#[derive(Clone, Debug)]
pub struct ZSobol<'a> {
    layout: &'a ZSobolLayout,
    /// The Morton sample index, at the top of 64 bits, bit-reversed (as the scramble
    /// wants it; the same in every dimension).
    reversed: u64,
    dimension: u32,
}

impl SobolDraw for ZSobol<'_> {
    /// The index of this sample in the Sobol sequence for the current dimension — the
    /// Morton index nested-scrambled: every bit flipped by a hash of the bits above it and
    /// the dimension, so that every dimension visits the pixels' subtrees in another
    /// order while the samples of a pixel stay a contiguous, aligned, stratified run —
    /// and the seed that scrambles the values. (Ahmed & Wonka shuffle base-4 digits with
    /// one of the 24 permutations each; flipping bits keeps the aligned runs of 2ᵏ that
    /// stratification needs, in O(1) instead of a hash per digit, which cost a third of
    /// the render time.)
    #[inline]
    fn draw(&mut self, dims: u32) -> SobolParts {
        let (index_seed, value_seeds) = self.layout.seeds(self.dimension);
        self.dimension += dims;
        SobolParts { reversed: self.reversed, index_seed, value_seeds, unused_bits: self.layout.unused_bits }
    }
}

/// [`laine_karras`] on 64 bits (even constants, so each bit depends only on the bits
/// below it): applied to a bit-reversed value and reversed back, a nested (Owen) scramble
/// that maps aligned blocks of 2ᵏ values to aligned blocks of 2ᵏ.
#[inline]
fn laine_karras_64(mut v: u64, seed: u64) -> u64 {
    let [m0, m1, m2] = LAINE_KARRAS_64_MULS;
    v ^= v.wrapping_mul(m0);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 32) | 1);
    v ^= v.wrapping_mul(m1);
    v ^= v.wrapping_mul(m2);
    v
}
/// A 32-bit fixed-point fraction as an f32 in [0, 1) (24 bits, never 1).
#[inline(always)]
fn to_unit(v: u32) -> f32 {
    (v >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The first Sobol dimension (van der Corput in base 2): the index's bits reversed.
#[inline]
#[cfg(test)]
fn sobol_0(index: u64) -> u32 {
    (index as u32).reverse_bits()
}

/// The second Sobol dimension (primitive polynomial x + 1, m₁ = 1) by its definition:
/// direction numbers v₁ = 2³¹, vₖ = vₖ₋₁ ⊕ (vₖ₋₁ ≫ 1); the point is the XOR of the vₖ of
/// the index's set bits. With [`sobol_0`] it forms a (0, 2)-sequence in base 2. The
/// oracle of `sobol_1_reversed`, which computes it without a loop.
#[cfg(test)]
fn sobol_1(index: u64) -> u32 {
    let (mut v, mut out, mut i) = (1u32 << 31, 0u32, index as u32);
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
#[cfg(test)]
fn owen_scramble(v: u32, seed: u32) -> u32 {
    owen_scramble_reversed(v.reverse_bits(), seed)
}

/// The Laine–Karras hash on bit-reversed values: each bit is flipped by a hash of the
/// bits below it (multiplications by even constants only carry upwards).
#[inline(always)]
fn laine_karras(mut v: u32, seed: u32) -> u32 {
    let [m0, m1, m2] = LAINE_KARRAS_MULS;
    v ^= v.wrapping_mul(m0);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(m1);
    v ^= v.wrapping_mul(m2);
    v
}

/// `owen_scramble(v, seed)` of the value whose bits `reversed` holds in reverse order:
/// the scramble's first reversal saved.
#[inline(always)]
fn owen_scramble_reversed(reversed: u32, seed: u32) -> u32 {
    laine_karras(reversed, seed).reverse_bits()
}

/// `owen_scramble(sobol_0(index), seed)` in one reversal: van der Corput's reversal and
/// the scramble's first one cancel.
#[inline(always)]
fn scrambled_sobol_0(index: u64, seed: u32) -> u32 {
    owen_scramble_reversed(index as u32, seed)
}

/// `owen_scramble(sobol_1(index), seed)` in one reversal, from [`sobol_1_reversed`].
#[inline]
fn scrambled_sobol_1(index: u64, seed: u32) -> u32 {
    owen_scramble_reversed(sobol_1_reversed(index as u32), seed)
}

/// `sobol_1(i)` bit-reversed, without tables. Reversed, the direction numbers are
/// r₀ = 1, rⱼ = rⱼ₋₁ ⊕ (rⱼ₋₁ ≪ 1): the polynomials (1 + z)ʲ over GF(2), bit k the
/// coefficient of zᵏ. Their XOR over the index's set bits is the index read as a
/// polynomial in y = 1 + z, i(1 + z): a Taylor shift by one, which over GF(2) takes one
/// step per halving (f = lo + zˢ·hi ↦ (lo + hi) + zˢ·hi, as (1 + z)ˢ = 1 + zˢ for s a
/// power of two, then the same within each half). Five shift-and-XORs instead of four
/// table lookups: they vectorise across the lanes, where lookups would be gathers (the
/// lookups, one lane at a time, were 2 % of a Cornell-box render's instructions). Equal to
/// the definition's value for every index (`sobol_1_reversed_is_the_definition_reversed`).
#[inline(always)]
fn sobol_1_reversed(i: u32) -> u32 {
    let mut x = i;
    x ^= (x >> 16) & 0x0000_ffff;
    x ^= (x >> 8) & 0x00ff_00ff;
    x ^= (x >> 4) & 0x0f0f_0f0f;
    x ^= (x >> 2) & 0x3333_3333;
    x ^= (x >> 1) & 0x5555_5555;
    x
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
