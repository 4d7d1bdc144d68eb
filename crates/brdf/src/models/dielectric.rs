//! The smooth dielectric interface.

use crate::frame::reflect_local;
use crate::fresnel::{fresnel_dielectric, fresnel_schlick, refract_local};
use crate::models::dispersion::{Dispersion, DispersionPreset};
use crate::params::Colour;
use crate::wgsl::{ModelWgsl, WgslPiece, WgslTextureSlots};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags, Texels, TextureSlots};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};

crate::model_params! {
    /// The smooth dielectric's parameters.
    pub struct DielectricParams for "dielectric" {
        doc: "Smooth dielectric: specular reflection with Fresnel probability, Snell refraction, total internal \
              reflection.",
        ior: scalar {
            doc: "index of refraction inside (the normal points outside, index 1)",
            default: 1.5,
            min: 1.0e-3,
            max: 10.0,
            mtl: "Ni",
        },
        tint: spectrum { doc: "colour filter on reflection and transmission", default: 1.0, mtl: "Tf" },
        schlick: bool { doc: "Schlick's Fresnel approximation instead of the exact formula", default: false },
        dispersion: choice(DispersionPreset) {
            doc: "how the index varies with wavelength: none (ior at every wavelength), cauchy (with cauchy_b), \
                  bk7 (Schott N-BK7 Sellmeier), fused-silica (Malitson 1965); the Sellmeier presets ignore ior",
            default: DispersionPreset::None,
            mtl: "dispersion",
        },
        cauchy_b: scalar {
            doc: "Cauchy's B in µm² for n(λ) = A + B/λ², A chosen so that n(587.56 nm) = ior",
            default: 0.004_2,
            min: 0.0,
            max: 1.0,
            mtl: "cauchy_b",
        },
        absorption: coefficient {
            doc: "Beer–Lambert absorption coefficient α per scene unit inside: I(s) = I₀·e^(−αs)",
            default: 0.0,
            mtl: "absorption",
        },
    }
}

impl Model for DielectricParams {
    type Bsdf<const N: usize> = Dielectric<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots::base("tint"),
        source: include_str!("dielectric.wgsl"),
        needs: &[WgslPiece::Fresnel, WgslPiece::Dispersion],
        constants: &[],
    };

    /// glTF's base colour tints transmission (`KHR_materials_transmission`).
    const TEXTURE_SLOTS: TextureSlots = TextureSlots::BASE_COLOUR;

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Dielectric<N> {
        self.bsdf_textured(wl, &Texels::default())
    }

    #[inline]
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> Dielectric<N> {
        let fresnel = if self.schlick { FresnelModel::Schlick } else { FresnelModel::Exact };
        // RGB mode has no wavelengths: it uses the base index (n_d) without dispersion.
        let (eta, dispersive) = if wl.is_rgb() || self.dispersion == DispersionPreset::None {
            (self.ior, false)
        } else {
            (Dispersion::from_preset(self.dispersion, self.cauchy_b).ior(self.ior, wl.lambda[0]), N > 1)
        };
        Dielectric { eta, dispersive, fresnel, tint: texels.base(self.tint.sample(wl)) }
    }

    fn is_transmissive(&self) -> bool {
        true
    }

    fn is_dispersive(&self) -> bool {
        self.dispersion != DispersionPreset::None
    }

    fn absorption(&self) -> Option<&Colour> {
        Some(&self.absorption).filter(|a| !a.is_black())
    }
}

/// How a dielectric computes its Fresnel reflectance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FresnelModel {
    /// The exact unpolarised formula (both polarisations).
    #[default]
    Exact,
    /// Schlick's approximation.
    Schlick,
}

/// A smooth dielectric interface (glass, water): specular reflection with probability F
/// and refraction by Snell's law with probability 1 − F, including total internal
/// reflection. +z is the outside; η = n_inside / n_outside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric<const N: usize> {
    /// Relative index of refraction n_inside / n_outside (at the path's first wavelength).
    pub eta: f32,
    /// True if the index varies with wavelength: the sampled direction then holds for
    /// the first wavelength only, and the integrator must follow that one alone.
    pub dispersive: bool,
    /// Fresnel formula.
    pub fresnel: FresnelModel,
    /// Colour filter on both reflection and transmission (1 for clear glass).
    pub tint: SampledSpectrum<N>,
}

impl<const N: usize> Dielectric<N> {
    #[inline]
    fn reflectance(&self, cos_o: f32) -> f32 {
        match self.fresnel {
            FresnelModel::Exact => fresnel_dielectric(cos_o, self.eta),
            FresnelModel::Schlick => fresnel_schlick(cos_o, self.eta),
        }
    }
}

impl<const N: usize> Bsdf<N> for Dielectric<N> {
    fn eta(&self) -> f32 {
        self.eta
    }
    fn flags(&self) -> ScatterFlags {
        let f = ScatterFlags::REFLECTION | ScatterFlags::TRANSMISSION | ScatterFlags::SPECULAR;
        if self.dispersive { f | ScatterFlags::WAVELENGTH_DEPENDENT } else { f }
    }
    fn eval(&self, _wo: Vec3, _wi: Vec3) -> SampledSpectrum<N> {
        SampledSpectrum::zero()
    }
    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    #[inline]
    fn sample(&self, wo: Vec3, uc: f32, _u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        if uc < r {
            let wi = reflect_local(wo);
            return Some(BsdfSample {
                wi,
                f: self.tint * (r / wi.z.abs()),
                pdf: r,
                flags: ScatterFlags::REFLECTION | ScatterFlags::SPECULAR,
            });
        }
        let wi = refract_local(wo, self.eta)?;
        let t = 1.0 - r;
        // Radiance is compressed by (n_i/n_t)² on entering a denser medium (Veach 1997
        // §5.2); η' is the index on ωi's side over the index on ωo's side.
        let etap = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        Some(BsdfSample {
            wi,
            f: self.tint * (t / (wi.z.abs() * etap * etap)),
            pdf: t,
            flags: ScatterFlags::TRANSMISSION | ScatterFlags::SPECULAR,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dispersive_glass_flags_wavelength_dependence_except_in_rgb() {
        use crate::params::{ParamSet, ParamValue};
        let p = DielectricParams::resolve("glass", &[("dispersion", ParamValue::Scalar(2.0))]).unwrap();
        assert_eq!(p.dispersion, DispersionPreset::Bk7);
        let hero = SampledWavelengths::<4>::sample_hero(0.3);
        let d = p.bsdf(&hero);
        assert!(d.flags().contains(ScatterFlags::WAVELENGTH_DEPENDENT));
        assert!((d.eta - crate::models::dispersion::BK7.ior(hero.lambda[0])).abs() < 1e-6);
        let rgb = p.bsdf(&SampledWavelengths::<3>::rgb());
        assert!(!rgb.flags().contains(ScatterFlags::WAVELENGTH_DEPENDENT));
        let plain = DielectricParams::default();
        assert!(!plain.bsdf(&hero).flags().contains(ScatterFlags::WAVELENGTH_DEPENDENT));
        assert!(plain.absorption().is_none() && !plain.is_dispersive() && p.is_dispersive());
        let named = DielectricParams::resolve("glass", &[("dispersion", ParamValue::Name("fused-silica".into()))]);
        assert_eq!(named.unwrap().dispersion, DispersionPreset::FusedSilica);
    }
}
