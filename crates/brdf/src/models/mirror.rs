//! The perfect mirror.

use crate::frame::reflect_local;
use crate::wgsl::{ModelWgsl, WgslTextureSlots};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};

crate::model_params! {
    /// The mirror's parameters.
    pub struct MirrorParams for "mirror" {
        doc: "Perfect specular reflection (a Dirac delta at the mirror direction), two-sided.",
        reflectance: spectrum { doc: "reflectance at every angle", default: 1.0, mtl: "Ks" },
    }
}

impl Model for MirrorParams {
    type Bsdf<const N: usize> = Mirror<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots { specular: Some("reflectance"), ..WgslTextureSlots::NONE },
        source: include_str!("mirror.wgsl"),
        needs: &[],
        constants: &[],
    };

    const TEXTURE_SLOTS: TextureSlots = TextureSlots { specular: true, ..TextureSlots::NONE };

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Mirror<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> Mirror<N> {
        Mirror { reflectance: texels.spec(self.reflectance.sample(wl)) }
    }
}

/// A perfect mirror with reflectance R (1 for an ideal mirror): a Dirac delta at the
/// mirror direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror<const N: usize> {
    /// Reflectance per wavelength.
    pub reflectance: SampledSpectrum<N>,
}

impl<const N: usize> Bsdf<N> for Mirror<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::SPECULAR
    }
    fn eval(&self, _wo: Vec3, _wi: Vec3) -> SampledSpectrum<N> {
        SampledSpectrum::zero()
    }
    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }
    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, _u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 {
            return None;
        }
        let wi = reflect_local(wo);
        Some(BsdfSample { wi, f: self.reflectance / wi.z.abs(), pdf: 1.0, flags: self.flags() })
    }
}
