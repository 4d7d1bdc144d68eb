//! The smooth conductor: a metal mirror weighted by the exact conductor Fresnel
//! reflectance of a measured metal ([`crate::models::metal`]) or of constants η + iκ.

use crate::frame::reflect_local;
use crate::models::metal::{Metal, MetalPreset, fresnel_spectrum};
use crate::wgsl::{ModelWgsl, WgslPiece, WgslTextureSlots};
use crate::{Bsdf, BsdfSample, Model, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};

crate::model_params! {
    /// The smooth conductor's parameters.
    pub struct ConductorParams for "conductor" {
        doc: "Smooth conductor: specular reflection weighted by the exact conductor Fresnel reflectance of a \
              complex index η + iκ per wavelength (Born & Wolf, Principles of Optics, 7th ed., ch. 14; pbrt-v3 \
              §8.2.1), two-sided.",
        metal: choice(MetalPreset) {
            doc: "measured metal: custom (eta, k), gold, silver, copper (default, as pbrt-v4's conductor), aluminium",
            default: MetalPreset::Copper,
        },
        eta: scalar {
            doc: "real part n of the complex index of refraction, at every wavelength (used when metal = custom)",
            default: 1.5,
            min: 0.0,
            max: 10.0,
        },
        k: scalar {
            doc: "extinction coefficient κ (imaginary part of the index), at every wavelength (used when metal = \
                  custom)",
            default: 3.0,
            min: 0.0,
            max: 20.0,
        },
        tint: spectrum { doc: "colour filter multiplying the Fresnel reflectance (1 for a physical metal)", default: 1.0 },
    }
}

impl Model for ConductorParams {
    type Bsdf<const N: usize> = Conductor<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        texture: WgslTextureSlots::NONE,
        source: include_str!("conductor.wgsl"),
        needs: &[WgslPiece::Fresnel, WgslPiece::Metal],
        constants: &[],
    };

    #[inline]
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Conductor<N> {
        let (eta, k) = self.metal.eta_k(self.eta, self.k, wl);
        Conductor { eta, k, tint: self.tint.sample(wl) }
    }
}

/// A smooth metal: a Dirac delta at the mirror direction weighted by the conductor
/// Fresnel reflectance per wavelength. Two-sided, like [`crate::Mirror`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor<const N: usize> {
    /// Real part n of the complex index, per wavelength.
    pub eta: SampledSpectrum<N>,
    /// Extinction coefficient κ, per wavelength.
    pub k: SampledSpectrum<N>,
    /// Colour filter on the reflectance (1 for a physical metal).
    pub tint: SampledSpectrum<N>,
}

impl<const N: usize> Conductor<N> {
    /// A conductor of index η + iκ (per wavelength), untinted.
    pub fn new(eta: SampledSpectrum<N>, k: SampledSpectrum<N>) -> Self {
        Self { eta, k, tint: SampledSpectrum::one() }
    }

    /// A measured metal at the path's wavelengths.
    pub fn metal(metal: Metal, wl: &SampledWavelengths<N>) -> Self {
        let (eta, k) = metal.sample(wl);
        Self::new(eta, k)
    }
}

impl<const N: usize> Bsdf<N> for Conductor<N> {
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
        if wo.z == 0.0 || !wo.z.is_finite() {
            return None;
        }
        let wi = reflect_local(wo);
        let f = fresnel_spectrum(wo.z, &self.eta, &self.k, &self.tint) / wi.z.abs();
        Some(BsdfSample { wi, f, pdf: 1.0, flags: self.flags() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::metal::{RGB_LAMBDA, fresnel_conductor};
    use crate::params::{ParamSet, ParamValue};
    use crate::validation::directional_albedo;

    #[test]
    fn smooth_conductor_reflects_its_fresnel_reflectance() {
        let wl = SampledWavelengths::<4>::fixed_bins(450.0, 100.0);
        let au = Conductor::metal(Metal::Gold, &wl);
        let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
        let s = au.sample(wo, 0.5, Vec2::ZERO).unwrap();
        assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
        for i in 0..4 {
            let (n, k) = Metal::Gold.eta_k(wl.lambda[i]);
            let expect = fresnel_conductor(wo.z, n, k);
            assert!((s.f[i] * s.wi.z / s.pdf - expect).abs() < 1e-6);
        }
        assert!(s.flags.is_specular() && au.pdf(wo, s.wi) == 0.0 && au.eval(wo, s.wi).is_black());
        // Two-sided.
        let below = au.sample(-wo, 0.5, Vec2::ZERO).unwrap();
        assert!((below.f[0] - s.f[0]).abs() < 1e-6 && below.wi.z < 0.0);
        assert!(au.sample(Vec3::X, 0.5, Vec2::ZERO).is_none());
        // Single-wavelength albedo is the Fresnel reflectance.
        let one = Conductor::<1>::new(SampledSpectrum([0.2]), SampledSpectrum([3.0]));
        let (a, _) = directional_albedo(&one, wo, 10, 1);
        assert!((a - fresnel_conductor(wo.z, 0.2, 3.0) as f64).abs() < 1e-6);
    }

    #[test]
    fn parameters_choose_a_preset_or_custom_constants() {
        let wl = SampledWavelengths::<4>::fixed_bins(450.0, 100.0);
        let gold = ConductorParams::resolve("m", &[("metal", ParamValue::Scalar(1.0))]).unwrap();
        let c = gold.bsdf(&wl);
        assert_eq!(c, Conductor::metal(Metal::Gold, &wl));
        let by_name = ConductorParams::resolve("m", &[("metal", ParamValue::Name("gold".into()))]).unwrap();
        assert_eq!(by_name, gold);
        let custom = ConductorParams::resolve(
            "m",
            &[("metal", ParamValue::Scalar(0.0)), ("eta", ParamValue::Scalar(0.3)), ("k", ParamValue::Scalar(2.0))],
        )
        .unwrap();
        let c = custom.bsdf(&wl);
        assert_eq!(
            (c.eta, c.k, c.tint),
            (SampledSpectrum::splat(0.3), SampledSpectrum::splat(2.0), SampledSpectrum::one())
        );
        // Default: copper. RGB mode: n, k at 630, 532, 465 nm.
        let rgb: Conductor<3> = ConductorParams::default().bsdf(&SampledWavelengths::rgb());
        for i in 0..3 {
            assert_eq!((rgb.eta[i], rgb.k[i]), Metal::Copper.eta_k(RGB_LAMBDA[i]));
        }
        assert!(ConductorParams::resolve("m", &[("metal", ParamValue::Scalar(5.0))]).is_err());
        assert!(ConductorParams::resolve("m", &[("metal", ParamValue::Scalar(4.2))]).is_err());
        assert_eq!(MetalPreset::Custom.metal(), None);
        assert_eq!(MetalPreset::Aluminium.metal(), Some(Metal::Aluminium));
    }
}
