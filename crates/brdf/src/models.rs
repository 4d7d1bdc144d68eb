//! The first BSDF models: Lambert, perfect mirror, smooth dielectric.

use crate::fresnel::{fresnel_dielectric, fresnel_schlick, reflect_local, refract_local};
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::{Bsdf, BsdfSample, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::SampledSpectrum;
use std::f32::consts::FRAC_1_PI;

#[inline]
fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// Lambertian reflection f = R/π, sampled by cosine-weighted hemisphere sampling. It
/// reflects on the side ωo is on, so it is two-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert<const N: usize> {
    /// Albedo R per wavelength, in [0, 1].
    pub reflectance: SampledSpectrum<N>,
}

impl<const N: usize> Bsdf<N> for Lambert<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE
    }

    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        if same_hemisphere(wo, wi) { self.reflectance * FRAC_1_PI } else { SampledSpectrum::zero() }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if same_hemisphere(wo, wi) { cosine_hemisphere_pdf(wi.z.abs()) } else { 0.0 }
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        let mut wi = cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf = cosine_hemisphere_pdf(wi.z.abs());
        if pdf <= 0.0 || wo.z == 0.0 {
            return None;
        }
        Some(BsdfSample { wi, f: self.reflectance * FRAC_1_PI, pdf, flags: self.flags() })
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
    /// Relative index of refraction n_inside / n_outside.
    pub eta: f32,
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
        ScatterFlags::REFLECTION | ScatterFlags::TRANSMISSION | ScatterFlags::SPECULAR
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
        // §5.2); η' is n on ωi's side over n on ωo's side... here n_t/n_i for ωo → ωi.
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
    use crate::sampling::uniform_sphere;

    /// Pearson chi-square test of `sample` against `pdf` on a θ×φ grid over the sphere
    /// (the method of pbrt-v4's and Mitsuba 3's BSDF tests): returns the p-value.
    fn chi2_pvalue(bsdf: &impl Bsdf<1>, wo: Vec3, samples: usize, seed: u64) -> f64 {
        const THETA: usize = 40;
        const PHI: usize = 80;
        let mut observed = vec![0.0f64; THETA * PHI];
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        let cell = |w: Vec3| {
            let theta = w.z.clamp(-1.0, 1.0).acos();
            let phi = w.y.atan2(w.x).rem_euclid(std::f32::consts::TAU);
            let i = ((theta / std::f32::consts::PI) * THETA as f32) as usize;
            let j = ((phi / std::f32::consts::TAU) * PHI as f32) as usize;
            i.min(THETA - 1) * PHI + j.min(PHI - 1)
        };
        for _ in 0..samples {
            let (uc, u) = (next(), Vec2::new(next(), next()));
            if let Some(s) = bsdf.sample(wo, uc, u) {
                // sample() must agree with eval()/pdf().
                assert!((s.pdf - bsdf.pdf(wo, s.wi)).abs() <= 1e-3 * s.pdf.max(1e-3));
                assert!((s.f[0] - bsdf.eval(wo, s.wi)[0]).abs() <= 1e-4);
                observed[cell(s.wi)] += 1.0;
            }
        }
        // Expected counts: integrate the pdf over each cell with a 6×6 midpoint rule in
        // (cos θ, φ), which is exact in solid angle.
        let mut expected = vec![0.0f64; THETA * PHI];
        for i in 0..THETA {
            let (t0, t1) =
                (i as f64 * std::f64::consts::PI / THETA as f64, (i + 1) as f64 * std::f64::consts::PI / THETA as f64);
            for j in 0..PHI {
                let (p0, p1) = (
                    j as f64 * std::f64::consts::TAU / PHI as f64,
                    (j + 1) as f64 * std::f64::consts::TAU / PHI as f64,
                );
                let q = 6;
                let mut sum = 0.0;
                for a in 0..q {
                    let z = t0.cos() + (t1.cos() - t0.cos()) * (a as f64 + 0.5) / q as f64;
                    for b in 0..q {
                        let phi = p0 + (p1 - p0) * (b as f64 + 0.5) / q as f64;
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                        sum += bsdf.pdf(wo, w) as f64;
                    }
                }
                let area = (t0.cos() - t1.cos()) * (p1 - p0);
                expected[i * PHI + j] = sum / (q * q) as f64 * area * samples as f64;
            }
        }
        // Pool cells with expected count < 5, then Pearson's statistic.
        let (mut chi2, mut dof, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
        for (o, e) in observed.iter().zip(&expected) {
            if *e < 5.0 {
                pool_o += o;
                pool_e += e;
            } else {
                chi2 += (o - e) * (o - e) / e;
                dof += 1;
            }
        }
        if pool_e > 0.0 {
            chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(1e-9);
            dof += 1;
        }
        chi2_survival(chi2, (dof - 1) as f64)
    }

    /// P(χ²_k > x) via the Wilson–Hilferty normal approximation (accurate for k ≫ 1).
    fn chi2_survival(x: f64, k: f64) -> f64 {
        let z = ((x / k).powf(1.0 / 3.0) - (1.0 - 2.0 / (9.0 * k))) / (2.0 / (9.0 * k)).sqrt();
        0.5 * erfc(z / std::f64::consts::SQRT_2)
    }

    fn erfc(x: f64) -> f64 {
        // Numerical Recipes' Chebyshev fit, |error| < 1.2e-7.
        let z = x.abs();
        let t = 1.0 / (1.0 + 0.5 * z);
        let r = t
            * (-z * z - 1.265_512_23
                + t * (1.000_023_68
                    + t * (0.374_091_96
                        + t * (0.096_784_18
                            + t * (-0.186_288_06
                                + t * (0.278_868_07
                                    + t * (-1.135_203_98
                                        + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
                .exp();
        if x >= 0.0 { r } else { 2.0 - r }
    }

    /// Lambert with a deliberately wrong pdf (uniform instead of cosine): must fail.
    struct WrongPdfLambert(Lambert<1>);
    impl Bsdf<1> for WrongPdfLambert {
        fn flags(&self) -> ScatterFlags {
            self.0.flags()
        }
        fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<1> {
            self.0.eval(wo, wi)
        }
        fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
            if same_hemisphere(wo, wi) { 0.5 * FRAC_1_PI } else { 0.0 }
        }
        fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<1>> {
            self.0.sample(wo, uc, u).map(|s| BsdfSample { pdf: self.pdf(wo, s.wi), ..s })
        }
    }

    const ALPHA: f64 = 0.01;

    #[test]
    fn lambert_sampling_matches_its_pdf() {
        let lambert = Lambert { reflectance: SampledSpectrum([0.8]) };
        let cases = [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.9987, 0.05).normalize(), -Vec3::Z];
        // Šidák correction over the cases.
        let alpha = 1.0 - (1.0 - ALPHA).powf(1.0 / cases.len() as f64);
        for (k, wo) in cases.into_iter().enumerate() {
            let p = chi2_pvalue(&lambert, wo, 1_000_000, k as u64);
            assert!(p > alpha, "wo={wo}: p = {p}");
        }
    }

    #[test]
    fn a_wrong_pdf_fails_the_chi_square_test() {
        let broken = WrongPdfLambert(Lambert { reflectance: SampledSpectrum([0.8]) });
        let p = chi2_pvalue(&broken, Vec3::Z, 1_000_000, 7);
        assert!(p < 1e-6, "the broken pdf passed: p = {p}");
    }

    #[test]
    fn lambert_pdf_integrates_to_one_and_albedo_is_r() {
        let lambert = Lambert { reflectance: SampledSpectrum([0.8]) };
        let wo = Vec3::new(0.3, 0.2, 0.9).normalize();
        let n = 200_000;
        let (mut pdf_sum, mut albedo) = (0.0f64, 0.0f64);
        for i in 0..n {
            let u = Vec2::new(((i as f64 + 0.5) / n as f64) as f32, ((i as f64 * 0.618_034) % 1.0) as f32);
            let w = uniform_sphere(u);
            pdf_sum += lambert.pdf(wo, w) as f64;
            albedo += (lambert.eval(wo, w)[0] * w.z.abs()) as f64;
        }
        let four_pi = 4.0 * std::f64::consts::PI;
        assert!((pdf_sum / n as f64 * four_pi - 1.0).abs() < 0.01);
        assert!((albedo / n as f64 * four_pi - 0.8).abs() < 0.01);
    }

    #[test]
    fn dielectric_conserves_energy_and_reaches_both_sides() {
        let glass = Dielectric { eta: 1.5, fresnel: FresnelModel::Exact, tint: SampledSpectrum([1.0]) };
        for &z in &[1.0f32, 0.7, 0.2, 0.05, -0.05, -0.5, -0.9, -1.0] {
            let wo = Vec3::new((1.0 - z * z).sqrt(), 0.0, z);
            let (mut sum_weight, mut reflected, mut n) = (0.0f64, 0.0f64, 0);
            for i in 0..1000 {
                let s = glass.sample(wo, (i as f32 + 0.5) / 1000.0, Vec2::ZERO).unwrap();
                // Throughput f·|cos|/pdf, undoing the 1/η² radiance scaling, is 1.
                let etap2 = if s.flags.contains(ScatterFlags::TRANSMISSION) {
                    let e = if wo.z > 0.0 { 1.5f32 } else { 1.0 / 1.5 };
                    e * e
                } else {
                    1.0
                };
                sum_weight += (s.f[0] * s.wi.z.abs() / s.pdf * etap2) as f64;
                if s.flags.contains(ScatterFlags::REFLECTION) {
                    reflected += 1.0;
                    assert!(s.wi.z * wo.z > 0.0);
                } else {
                    assert!(s.wi.z * wo.z < 0.0);
                }
                n += 1;
            }
            assert!((sum_weight / n as f64 - 1.0).abs() < 1e-4, "z={z}");
            let expect = fresnel_dielectric(z, 1.5) as f64;
            assert!((reflected / n as f64 - expect).abs() < 2e-3, "z={z}: {} vs {expect}", reflected / n as f64);
        }
    }

    #[test]
    fn mirror_reflects_about_the_normal() {
        let m = Mirror { reflectance: SampledSpectrum([0.9]) };
        let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
        let s = m.sample(wo, 0.5, Vec2::ZERO).unwrap();
        assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
        assert!((s.f[0] * s.wi.z / s.pdf - 0.9).abs() < 1e-6);
        assert_eq!(m.pdf(wo, s.wi), 0.0);
    }
}
