//! The smooth dielectric interface.

use crate::fresnel::{fresnel_dielectric, fresnel_schlick, reflect_local, refract_local};
use crate::params::{ModelDef, ParamDef, ParamKind, ResolvedParams};
use crate::{Bsdf, BsdfSample, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};

/// The smooth dielectric's declaration.
pub const DEF: ModelDef = ModelDef {
    name: "dielectric",
    doc: "Smooth dielectric: specular reflection with Fresnel probability, Snell refraction, total internal reflection.",
    params: &[
        ParamDef {
            name: "ior",
            kind: ParamKind::Scalar,
            min: 1.0e-3,
            max: 10.0,
            default: 1.5,
            mtl_key: Some("Ni"),
            doc: "index of refraction inside (the normal points outside, index 1)",
        },
        ParamDef {
            name: "tint",
            kind: ParamKind::Spectrum,
            min: 0.0,
            max: 1.0,
            default: 1.0,
            mtl_key: Some("Tf"),
            doc: "colour filter on reflection and transmission",
        },
        ParamDef {
            name: "schlick",
            kind: ParamKind::Scalar,
            min: 0.0,
            max: 1.0,
            default: 0.0,
            mtl_key: None,
            doc: "1 for Schlick's Fresnel approximation, 0 for the exact formula",
        },
        ParamDef {
            name: "dispersion",
            kind: ParamKind::Scalar,
            min: 0.0,
            max: 3.0,
            default: 0.0,
            mtl_key: Some("dispersion"),
            doc: "0 none (ior at every wavelength), 1 Cauchy with cauchy_b, 2 Schott N-BK7 Sellmeier, 3 fused-silica Sellmeier (Malitson 1965); the presets ignore ior",
        },
        ParamDef {
            name: "cauchy_b",
            kind: ParamKind::Scalar,
            min: 0.0,
            max: 1.0,
            default: 0.004_2,
            mtl_key: Some("cauchy_b"),
            doc: "Cauchy's B in µm² for n(λ) = A + B/λ², A chosen so that n(587.56 nm) = ior",
        },
        ParamDef {
            name: "absorption",
            kind: ParamKind::Coefficient,
            min: 0.0,
            max: f32::INFINITY,
            default: 0.0,
            mtl_key: Some("absorption"),
            doc: "Beer–Lambert absorption coefficient α per scene unit inside: I(s) = I₀·e^(−αs)",
        },
    ],
};

/// Sellmeier coefficients n²(λ) = 1 + Σ Bᵢλ²/(λ² − Cᵢ), λ in µm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sellmeier {
    /// B₁, B₂, B₃.
    pub b: [f32; 3],
    /// C₁, C₂, C₃ in µm².
    pub c: [f32; 3],
}

/// Schott N-BK7 (Schott optical glass data sheet): n_d = 1.5168.
pub const BK7: Sellmeier =
    Sellmeier { b: [1.039_612, 0.231_792_34, 1.010_469_5], c: [0.006_000_699, 0.020_017_914, 103.560_65] };

/// Fused silica (Malitson 1965, JOSA 55(10)): n_d = 1.4585.
pub const FUSED_SILICA: Sellmeier =
    Sellmeier { b: [0.696_166_3, 0.407_942_6, 0.897_479_4], c: [0.004_679_148, 0.013_512_063, 97.934_003] };

impl Sellmeier {
    /// The index at `lambda_nm`.
    #[inline]
    pub fn ior(&self, lambda_nm: f32) -> f32 {
        let l2 = (lambda_nm * 1e-3).powi(2);
        let mut n2 = 1.0;
        for i in 0..3 {
            n2 += self.b[i] * l2 / (l2 - self.c[i]);
        }
        n2.max(1e-6).sqrt()
    }
}

/// The helium d-line, nm: where `ior` is the index for Cauchy dispersion (n_d).
pub const LAMBDA_D: f32 = 587.56;

/// How the index of refraction depends on wavelength.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Dispersion {
    /// The same index at every wavelength.
    #[default]
    None,
    /// Cauchy's n(λ) = A + B/λ² with B in µm² and n(λ_d) = the base index.
    Cauchy {
        /// B, µm².
        b: f32,
    },
    /// A Sellmeier glass (the base index is ignored).
    Sellmeier(Sellmeier),
}

impl Dispersion {
    /// The index at `lambda_nm` for base index `ior` (n_d).
    #[inline]
    pub fn ior(&self, ior: f32, lambda_nm: f32) -> f32 {
        match self {
            Self::None => ior,
            Self::Cauchy { b } => {
                let (l, ld) = (lambda_nm * 1e-3, LAMBDA_D * 1e-3);
                ior + b * (1.0 / (l * l) - 1.0 / (ld * ld))
            }
            Self::Sellmeier(s) => s.ior(lambda_nm),
        }
    }

    /// From the `dispersion` and `cauchy_b` parameters.
    pub fn from_preset(preset: f32, cauchy_b: f32) -> Self {
        match preset.round() as i32 {
            1 => Self::Cauchy { b: cauchy_b },
            2 => Self::Sellmeier(BK7),
            3 => Self::Sellmeier(FUSED_SILICA),
            _ => Self::None,
        }
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

impl<const N: usize> Dielectric<N> {
    /// From parameters resolved against [`DEF`], at the path's wavelengths.
    pub fn from_params(p: &ResolvedParams, wl: &SampledWavelengths<N>) -> Self {
        let fresnel = if p.scalar(2) >= 0.5 { FresnelModel::Schlick } else { FresnelModel::Exact };
        let dispersion = Dispersion::from_preset(p.scalar(3), p.scalar(4));
        // RGB mode has no wavelengths: it uses the base index (n_d) without dispersion.
        let (eta, dispersive) = if wl.is_rgb() || dispersion == Dispersion::None {
            (p.scalar(0), false)
        } else {
            (dispersion.ior(p.scalar(0), wl.lambda[0]), N > 1)
        };
        Self { eta, dispersive, fresnel, tint: p.colour(1).sample(wl) }
    }

    /// The Beer–Lambert absorption coefficient inside, if any (index 5 of [`DEF`]).
    pub fn absorption(p: &ResolvedParams) -> Option<&spectral::spectrum::Colour> {
        // Borrowed, not cloned: the integrator asks at every hit inside glass.
        match &p.values()[5] {
            crate::params::Resolved::Colour(a) if !a.is_black() => Some(a),
            _ => None,
        }
    }

    /// True if the parameters ask for wavelength-dependent refraction.
    pub fn is_dispersive(p: &ResolvedParams) -> bool {
        Dispersion::from_preset(p.scalar(3), p.scalar(4)) != Dispersion::None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sellmeier_presets_give_the_catalogue_indices() {
        // Catalogue n_d at 587.56 nm: N-BK7 1.5168, fused silica 1.4585.
        assert!((BK7.ior(LAMBDA_D) - 1.5168).abs() < 2e-4, "{}", BK7.ior(LAMBDA_D));
        assert!((FUSED_SILICA.ior(LAMBDA_D) - 1.4585).abs() < 2e-4, "{}", FUSED_SILICA.ior(LAMBDA_D));
        // Normal dispersion: blue bends more than red. Abbe number V_d = (n_d − 1)/(n_F − n_C):
        // N-BK7 64.17, fused silica 67.8.
        for (glass, abbe) in [(BK7, 64.17f32), (FUSED_SILICA, 67.8)] {
            let v = (glass.ior(LAMBDA_D) - 1.0) / (glass.ior(486.13) - glass.ior(656.27));
            assert!((v - abbe).abs() < 0.5, "Abbe {v} vs {abbe}");
        }
    }

    #[test]
    fn cauchy_is_anchored_at_the_d_line() {
        let d = Dispersion::Cauchy { b: 0.0042 };
        assert!((d.ior(1.5, LAMBDA_D) - 1.5).abs() < 1e-6);
        assert!(d.ior(1.5, 450.0) > 1.5 && d.ior(1.5, 650.0) < 1.5);
        assert_eq!(Dispersion::None.ior(1.33, 400.0), 1.33);
    }

    #[test]
    fn dispersive_glass_flags_wavelength_dependence_except_in_rgb() {
        let p = DEF.resolve("glass", &[("dispersion", crate::params::ParamValue::Scalar(2.0))]).unwrap();
        let hero = SampledWavelengths::<4>::sample_hero(0.3);
        let d = Dielectric::from_params(&p, &hero);
        assert!(d.flags().contains(ScatterFlags::WAVELENGTH_DEPENDENT));
        assert!((d.eta - BK7.ior(hero.lambda[0])).abs() < 1e-6);
        let rgb = Dielectric::from_params(&p, &SampledWavelengths::<3>::rgb());
        assert!(!rgb.flags().contains(ScatterFlags::WAVELENGTH_DEPENDENT));
        let plain = Dielectric::from_params(&DEF.defaults(), &hero);
        assert!(!plain.flags().contains(ScatterFlags::WAVELENGTH_DEPENDENT));
        assert!(Dielectric::<4>::absorption(&DEF.defaults()).is_none());
    }
}
