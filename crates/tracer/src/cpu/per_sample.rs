//! A block's per-sample spectral work — its hero wavelengths before the integrator runs,
//! its radiance's colour after — done for the whole block at once, sixteen samples at a
//! time across vector lanes, with the widest vector instructions the machine has.
//!
//! One sample at a time these were 8 % of a Cornell-box render (perf, one thread:
//! `sample_hero` 4.4 %, a chain of dependent divisions per sample, and `to_linear_srgb`
//! 3.5 %, table lookups behind a branch per wavelength). The many-sample forms
//! ([`SampledWavelengths::sample_hero_each`], [`SampledWavelengths::to_linear_srgb_each`])
//! compute the same values by the same operations, so the image is the same to the bit.
//! The render gained 1.1 %, not 8: much of that latency moved to the camera's rays, and
//! computing those (and the camera's draws) in steps of sixteen as well gained nothing
//! (docs/figures.md).
//!
//! The colours' conversion to the film's fixed point goes the same way
//! ([`crate::film::add_samples`]): one sample at a time it was 2.4 % of the render's
//! time, in chunks of sixteen 1.2 % (perf, one thread, Cornell box).

use crate::film::PixelStats;
use crate::integrator::CameraSample;
use crate::sampler::Sampler;
use bvh::isa::Isa;
use spectral::{SampledSpectrum, SampledWavelengths};

/// Samples per step: one AVX-512 register of f32.
const STEP: usize = 16;

/// Sets each sample's wavelengths to [`SampledWavelengths::sample_hero`] of its value in `u`
/// (`u[k]` for `block[k]`).
pub(super) fn hero_wavelengths<const N: usize, S: Sampler>(u: &[f32], block: &mut [CameraSample<N, S>]) {
    assert_eq!(u.len(), block.len(), "one sample value per camera sample");
    #[cfg(target_arch = "x86_64")]
    match bvh::isa::active() {
        // SAFETY: `active` is at most what the CPU has (detected), and each level has the
        // features its function is compiled for.
        Isa::Avx512 => return unsafe { hero_avx512(u, block) },
        // SAFETY: as above.
        Isa::Avx2 => return unsafe { hero_avx2(u, block) },
        Isa::Baseline => {}
    }
    hero(u, block);
}

/// The linear-sRGB colour of each sample's radiance ([`SampledWavelengths::to_linear_srgb`]),
/// into `rgb` (`rgb[k]` for `block[k]`).
pub(super) fn linear_srgb<const N: usize, S: Sampler>(block: &[CameraSample<N, S>], rgb: &mut Vec<[f32; 3]>) {
    rgb.clear();
    rgb.resize(block.len(), [0.0; 3]);
    #[cfg(target_arch = "x86_64")]
    match bvh::isa::active() {
        // SAFETY: as in `hero_wavelengths`.
        Isa::Avx512 => return unsafe { colour_avx512(block, rgb) },
        // SAFETY: as above.
        Isa::Avx2 => return unsafe { colour_avx2(block, rgb) },
        Isa::Baseline => {}
    }
    colour(block, rgb);
}

/// Adds sample `rgb[k]` (as [`linear_srgb`] leaves them) to `pixels[owners[k]]`; returns
/// how many were refused ([`crate::film::add_samples`]).
pub(super) fn add_to_pixels(pixels: &mut [PixelStats], owners: &[u32], rgb: &[[f32; 3]]) -> u64 {
    #[cfg(target_arch = "x86_64")]
    match bvh::isa::active() {
        // SAFETY: as in `hero_wavelengths`.
        Isa::Avx512 => unsafe { add_avx512(pixels, owners, rgb) },
        // SAFETY: as above.
        Isa::Avx2 => unsafe { add_avx2(pixels, owners, rgb) },
        // SSE2 has no instruction for the conversion's floors.
        Isa::Baseline => crate::film::add_samples_one_at_a_time(pixels, owners, rgb),
    }
    #[cfg(not(target_arch = "x86_64"))]
    crate::film::add_samples(pixels, owners, rgb)
}

#[inline(always)]
fn hero<const N: usize, S: Sampler>(u: &[f32], block: &mut [CameraSample<N, S>]) {
    let mut samples = block.chunks_exact_mut(STEP);
    let mut values = u.chunks_exact(STEP);
    for (samples, values) in (&mut samples).zip(&mut values) {
        let wl = SampledWavelengths::<N>::sample_hero_each::<STEP>(values.try_into().expect("a full step"));
        for (s, wl) in samples.iter_mut().zip(wl) {
            s.wl = wl;
        }
    }
    for (s, &u) in samples.into_remainder().iter_mut().zip(values.remainder()) {
        s.wl = SampledWavelengths::sample_hero(u);
    }
}

#[inline(always)]
fn colour<const N: usize, S: Sampler>(block: &[CameraSample<N, S>], rgb: &mut [[f32; 3]]) {
    let mut samples = block.chunks_exact(STEP);
    let mut out = rgb.chunks_exact_mut(STEP);
    for (samples, out) in (&mut samples).zip(&mut out) {
        let wl: [SampledWavelengths<N>; STEP] = std::array::from_fn(|k| samples[k].wl);
        let radiance: [SampledSpectrum<N>; STEP] = std::array::from_fn(|k| samples[k].radiance);
        out.copy_from_slice(&SampledWavelengths::to_linear_srgb_each(&wl, &radiance));
    }
    for (s, out) in samples.remainder().iter().zip(out.into_remainder()) {
        *out = s.wl.to_linear_srgb(&s.radiance);
    }
}

/// `hero`, `colour` and `add_samples` compiled for more vector instructions than the
/// baseline, chosen at run time. (No `fma`: Rust never contracts a·b + c, so it would
/// change nothing.)
macro_rules! compiled_for {
    ($($hero:ident, $colour:ident, $add:ident: $features:literal;)*) => {$(
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        unsafe fn $hero<const N: usize, S: Sampler>(u: &[f32], block: &mut [CameraSample<N, S>]) {
            hero(u, block);
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        unsafe fn $colour<const N: usize, S: Sampler>(block: &[CameraSample<N, S>], rgb: &mut [[f32; 3]]) {
            colour(block, rgb);
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        unsafe fn $add(pixels: &mut [PixelStats], owners: &[u32], rgb: &[[f32; 3]]) -> u64 {
            crate::film::add_samples(pixels, owners, rgb)
        }
    )*};
}

compiled_for! {
    hero_avx512, colour_avx512, add_avx512: "avx2,avx512f,avx512vl,avx512bw,avx512dq";
    hero_avx2, colour_avx2, add_avx2: "avx2";
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vector form the machine runs adds the same samples to the same bits as one
    /// sample at a time, refusing the same ones.
    #[test]
    fn the_machines_addition_equals_one_sample_at_a_time() {
        let mut rng = rng::Pcg32::new(21, 4);
        let owners: Vec<u32> = (0..3_000).map(|k| (k / 7) % 50).collect();
        let rgb: Vec<[f32; 3]> = (0..3_000)
            .map(|k| {
                if k % 97 == 0 {
                    [f32::NAN, 1.0, 1.0]
                } else {
                    [0.0; 3].map(|_| (rng.next_f32() - 0.1) * 10f32.powf(rng.next_f32() * 8.0 - 4.0))
                }
            })
            .collect();
        let mut expected = vec![PixelStats::default(); 50];
        let refused = crate::film::add_samples_one_at_a_time(&mut expected, &owners, &rgb);
        let mut pixels = vec![PixelStats::default(); 50];
        assert_eq!(add_to_pixels(&mut pixels, &owners, &rgb), refused);
        assert_eq!(refused, 31);
        assert_eq!(pixels, expected);
    }
}
