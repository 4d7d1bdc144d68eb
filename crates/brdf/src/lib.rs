//! BSDF models behind one trait, evaluated at a path's sampled wavelengths.
//!
//! Every model works in a local shading frame ([`Frame`]) whose z axis is the shading
//! normal: `cos θ = w.z`. Directions point away from the surface (ωo towards the
//! viewer, ωi towards the light), as in pbrt. Values are [`SampledSpectrum<N>`], one
//! per sampled wavelength (or colour channel), so a model never knows which spectral
//! mode is rendering.
//!
//! This crate knows spectra and directions, nothing of rays or scenes.
//!
//! Citations: "the thesis", "the lecture" and the papers named in comments are listed in `docs/references.md`.

pub mod frame;
pub mod fresnel;
pub mod models;
pub mod params;
pub mod registry;
pub mod sampling;
pub mod validation;
pub mod wgsl;

pub use frame::Frame;
pub use models::{Dielectric, Lambert, Mirror, ModelBsdf, ModelId, ModelParams};
pub use registry::{Model, Texels, TextureSlots};

// For the exported macros, so that their users need not depend on glam and spectral.
#[doc(hidden)]
pub use {glam, spectral};

use glam::{Vec2, Vec3};
use spectral::SampledSpectrum;

/// What kind of scattering a BSDF (or one of its samples) does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ScatterFlags(u8);

impl ScatterFlags {
    /// Light leaves on the side it arrived.
    pub const REFLECTION: Self = Self(1);
    /// Light crosses the surface.
    pub const TRANSMISSION: Self = Self(2);
    /// Spread over the hemisphere (Lambert-like).
    pub const DIFFUSE: Self = Self(4);
    /// Spread around a preferred direction.
    pub const GLOSSY: Self = Self(8);
    /// A Dirac delta: one outgoing direction, not reachable by light sampling.
    pub const SPECULAR: Self = Self(16);
    /// The sampled direction depends on wavelength (dispersion): the integrator must
    /// follow one wavelength only from here on.
    pub const WAVELENGTH_DEPENDENT: Self = Self(32);

    /// The raw bits (the values of the constants above), for code generators: the GPU
    /// crate's WGSL uses the same bit values.
    #[inline]
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// True if every flag of `other` is set.
    #[inline]
    pub fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }
    /// True if the scattering is a Dirac delta.
    #[inline]
    pub fn is_specular(self) -> bool {
        self.contains(Self::SPECULAR)
    }
    /// True if light sampling can reach it (it has a non-delta part).
    #[inline]
    pub fn is_non_specular(self) -> bool {
        self.0 & (Self::DIFFUSE.0 | Self::GLOSSY.0) != 0
    }
}

impl std::ops::BitOr for ScatterFlags {
    type Output = Self;
    #[inline]
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// One importance sample of a BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample<const N: usize> {
    /// The sampled incident direction, local frame.
    pub wi: Vec3,
    /// The BSDF value f(ωo, ωi) for that direction (for a delta lobe: its weight divided
    /// by |cos θi|, so that f·|cos θi|/pdf is the throughput either way).
    pub f: SampledSpectrum<N>,
    /// The pdf with respect to solid angle (for a delta lobe: the discrete probability of
    /// choosing it).
    pub pdf: f32,
    /// What kind of event was sampled.
    pub flags: ScatterFlags,
}

/// A BSDF at one surface point, already bound to the path's wavelengths.
///
/// `eval` and `pdf` must agree with `sample`: the chi-square tests in this crate check
/// that samples are distributed by `pdf` and that `sample` returns `eval` and `pdf`.
pub trait Bsdf<const N: usize> {
    /// What this BSDF can do.
    fn flags(&self) -> ScatterFlags;
    /// f(ωo, ωi), without the cosine; zero for delta lobes.
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N>;
    /// The solid-angle pdf of sampling ωi given ωo; zero for delta lobes.
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32;
    /// Samples ωi given ωo: `uc` picks a lobe, `u` the direction within it.
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<N>>;
    /// The relative index of refraction n_inside / n_outside of a transmissive BSDF (1
    /// for one that only reflects). `eval` and `sample` give transmitted *radiance*,
    /// scaled by 1/η'² (η' the index on ωi's side over ωo's); light carried the other
    /// way, from the lights (bidirectional path tracing's light subpaths: importance
    /// transport, Veach 1997 §5.2), is not scaled, and this is what undoes it. A custom
    /// transmissive BSDF must override it.
    fn eta(&self) -> f32 {
        1.0
    }
}

/// Builds a BSDF at a hit for any number of sampled wavelengths: the one generic method a
/// model from outside the workspace implements to plug into the renderer (see
/// `examples/custom_brdf.rs` in the tracer crate).
pub trait BsdfBuilder: Send + Sync + 'static {
    /// The BSDF for the path's wavelengths (or RGB channels).
    fn build<const N: usize>(&self, wl: &spectral::SampledWavelengths<N>) -> impl Bsdf<N> + 'static;

    /// Its GPU twin, if it ships one: WGSL `eval`/`pdf`/`sample` over a declared parameter
    /// set and this material's values. Without one, a GPU backend refuses the material
    /// (and says so); with one, it compiles the twin into its kernel like a registered
    /// model's (see `examples/custom_brdf.rs` in the tracer crate).
    fn wgsl_twin(&self) -> Option<wgsl::WgslTwin> {
        None
    }
}

/// The object-safe form of [`BsdfBuilder`] for the lane counts the renderer uses (3 for
/// RGB, 4 for hero wavelengths, 40 for the thesis's bins); implemented for every
/// `BsdfBuilder`.
pub trait DynBsdfBuilder: Send + Sync {
    /// Hero-wavelength BSDF.
    fn build_4(&self, wl: &spectral::SampledWavelengths<4>) -> Box<dyn Bsdf<4>>;
    /// RGB BSDF.
    fn build_3(&self, wl: &spectral::SampledWavelengths<3>) -> Box<dyn Bsdf<3>>;
    /// 40-bin BSDF.
    fn build_40(&self, wl: &spectral::SampledWavelengths<40>) -> Box<dyn Bsdf<40>>;
    /// [`BsdfBuilder::wgsl_twin`].
    fn wgsl_twin(&self) -> Option<wgsl::WgslTwin>;
}

impl<T: BsdfBuilder> DynBsdfBuilder for T {
    fn build_4(&self, wl: &spectral::SampledWavelengths<4>) -> Box<dyn Bsdf<4>> {
        Box::new(self.build(wl))
    }
    fn build_3(&self, wl: &spectral::SampledWavelengths<3>) -> Box<dyn Bsdf<3>> {
        Box::new(self.build(wl))
    }
    fn build_40(&self, wl: &spectral::SampledWavelengths<40>) -> Box<dyn Bsdf<40>> {
        Box::new(self.build(wl))
    }
    fn wgsl_twin(&self) -> Option<wgsl::WgslTwin> {
        BsdfBuilder::wgsl_twin(self)
    }
}

/// Calls the [`DynBsdfBuilder`] method matching N from generic code (N ∈ {3, 4, 40});
/// panics for other lane counts, which the renderer never uses.
pub fn instantiate<const N: usize>(
    builder: &dyn DynBsdfBuilder,
    wl: &spectral::SampledWavelengths<N>,
) -> Box<dyn Bsdf<N>> {
    use std::any::Any;
    fn cast<const M: usize, const N: usize>(b: Box<dyn Bsdf<M>>) -> Box<dyn Bsdf<N>> {
        let any: Box<dyn Any> = Box::new(b);
        *any.downcast::<Box<dyn Bsdf<N>>>().expect("M == N checked by the caller")
    }
    let any: &dyn Any = wl;
    if let Some(w) = any.downcast_ref::<spectral::SampledWavelengths<4>>() {
        cast::<4, N>(builder.build_4(w))
    } else if let Some(w) = any.downcast_ref::<spectral::SampledWavelengths<3>>() {
        cast::<3, N>(builder.build_3(w))
    } else if let Some(w) = any.downcast_ref::<spectral::SampledWavelengths<40>>() {
        cast::<40, N>(builder.build_40(w))
    } else {
        panic!("no custom BSDF instantiation for {N} lanes")
    }
}
