//! A BRDF written outside the workspace: the modified Phong model of Lafortune & Willems
//! 1994 (energy-conserving: f = k_d/π + k_s·(n+2)/(2π)·cos^n α, α the angle between ωi and
//! the mirror direction of ωo), with its own importance sampling and its WGSL twin for the
//! GPU. Shared by `examples/custom_brdf.rs` and the GPU's equivalence tests
//! (`crates/gpu/tests/materials.rs` and `equivalence.rs` include this file), so the twin the
//! example ships is the one checked against its Rust.

use brdf::params::ParamSet;
use brdf::wgsl::{ModelWgsl, WgslPiece, WgslTextureSlots, WgslTwin};
use brdf::{Bsdf, BsdfBuilder, BsdfSample, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{FRAC_1_PI, TAU};

brdf::model_params! {
    /// The material-level description: colours as spectra, built into a [`Phong`] per hit.
    /// Declared with `brdf::model_params!` (as registered models are) so that its WGSL twin
    /// gets a generated parameter struct; it is not registered.
    pub struct PhongParams for "phong" {
        doc: "Modified Phong (Lafortune & Willems 1994), a custom BSDF outside the registry.",
        kd: spectrum { doc: "diffuse reflectance k_d", default: 0.5 },
        ks: spectrum { doc: "specular reflectance k_s", default: 0.5 },
        exponent: scalar { doc: "Phong exponent n", default: 60.0, min: 1.0, max: 100000.0 },
    }
}

/// The modified Phong BRDF at one hit.
pub struct Phong<const N: usize> {
    kd: SampledSpectrum<N>,
    ks: SampledSpectrum<N>,
    exponent: f32,
    /// Probability of sampling the specular lobe.
    p_spec: f32,
}

impl<const N: usize> Phong<N> {
    fn lobe_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let r = Vec3::new(-wo.x, -wo.y, wo.z);
        let cos_a = r.dot(wi).max(0.0);
        (self.exponent + 1.0) / TAU * cos_a.powf(self.exponent)
    }
}

impl<const N: usize> Bsdf<N> for Phong<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE | ScatterFlags::GLOSSY
    }

    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return SampledSpectrum::zero();
        }
        let r = Vec3::new(-wo.x, -wo.y, wo.z);
        let spec = (self.exponent + 2.0) / TAU * r.dot(wi).max(0.0).powf(self.exponent);
        self.kd * FRAC_1_PI + self.ks * spec
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        (1.0 - self.p_spec) * wi.z * FRAC_1_PI + self.p_spec * self.lobe_pdf(wo, wi)
    }

    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if uc < self.p_spec {
            // cos α distributed ∝ cos^n α around the mirror direction.
            let cos_a = u.x.powf(1.0 / (self.exponent + 1.0));
            let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
            let phi = TAU * u.y;
            let r = Vec3::new(-wo.x, -wo.y, wo.z);
            let frame = brdf::Frame::from_normal(r);
            frame.to_world(Vec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a))
        } else {
            brdf::sampling::cosine_hemisphere(u)
        };
        let pdf = self.pdf(wo, wi);
        (wi.z > 0.0 && pdf > 0.0).then(|| BsdfSample { wi, f: self.eval(wo, wi), pdf, flags: self.flags() })
    }
}

/// The twin, line for line: `phong_eval`, `phong_pdf`, `phong_sample` over the generated
/// `PhongParams` (colours as offsets read by `spectrum_at`), with the shared cosine
/// sampling (`WgslPiece::Sampling`).
const PHONG_WGSL: &str = "
// cos^n α, 0 for cos α ≤ 0 (pow is undefined there in WGSL).
fn phong_pow(cos_a: f32, n: f32) -> f32 {
    return select(0.0, pow(cos_a, n), cos_a > 0.0);
}

fn phong_p_spec(p: PhongParams, lambda: vec4f) -> f32 {
    let kd = mat_average(spectrum_at(p.kd, lambda));
    let ks = mat_average(spectrum_at(p.ks, lambda));
    return ks / max(kd + ks, 1e-6);
}

fn phong_eval(p: PhongParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return vec4f(0.0);
    }
    let r = vec3f(-wo.x, -wo.y, wo.z);
    let spec = (p.exponent + 2.0) / MAT_TAU * phong_pow(max(dot(r, wi), 0.0), p.exponent);
    return spectrum_at(p.kd, lambda) * MAT_FRAC_1_PI + spectrum_at(p.ks, lambda) * spec;
}

fn phong_pdf(p: PhongParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let r = vec3f(-wo.x, -wo.y, wo.z);
    let lobe = (p.exponent + 1.0) / MAT_TAU * phong_pow(max(dot(r, wi), 0.0), p.exponent);
    let ps = phong_p_spec(p, lambda);
    return (1.0 - ps) * wi.z * MAT_FRAC_1_PI + ps * lobe;
}

fn phong_sample(p: PhongParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    if wo.z <= 0.0 {
        return mat_no_sample();
    }
    var wi: vec3f;
    if uc < phong_p_spec(p, lambda) {
        let cos_a = pow(u.x, 1.0 / (p.exponent + 1.0));
        let sin_a = sqrt(max(1.0 - cos_a * cos_a, 0.0));
        let phi = MAT_TAU * u.y;
        let r = vec3f(-wo.x, -wo.y, wo.z);
        // `brdf::Frame::from_normal` (Duff et al. 2017); r.z = wo.z > 0, so the sign is +1.
        let a = -1.0 / (1.0 + r.z);
        let b = r.x * r.y * a;
        let s = vec3f(1.0 + r.x * r.x * a, b, -r.x);
        let t = vec3f(b, 1.0 + r.y * r.y * a, -r.y);
        wi = s * (sin_a * cos(phi)) + t * (sin_a * sin(phi)) + r * cos_a;
    } else {
        wi = mat_cosine_hemisphere(u);
    }
    let pdf = phong_pdf(p, wo, wi, lambda);
    if !(wi.z > 0.0 && pdf > 0.0) {
        return mat_no_sample();
    }
    return BsdfSample(wi, phong_eval(p, wo, wi, lambda), pdf, SCATTER_REFLECTION | SCATTER_DIFFUSE | SCATTER_GLOSSY);
}
";

impl BsdfBuilder for PhongParams {
    fn build<const N: usize>(&self, wl: &SampledWavelengths<N>) -> impl Bsdf<N> + 'static {
        let (kd, ks) = (self.kd.sample(wl), self.ks.sample(wl));
        let p_spec = ks.average() / (kd.average() + ks.average()).max(1e-6);
        Phong { kd, ks, exponent: self.exponent, p_spec }
    }

    /// The GPU runs the material through this (without it `--backend gpu` refuses it).
    fn wgsl_twin(&self) -> Option<WgslTwin> {
        Some(WgslTwin {
            def: Self::DEF,
            wgsl: ModelWgsl {
                source: PHONG_WGSL,
                needs: &[WgslPiece::Sampling],
                constants: &[],
                texture: WgslTextureSlots::NONE,
            },
            params: self.to_resolved(),
        })
    }
}
