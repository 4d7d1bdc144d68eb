//! A BRDF written outside the workspace, plugged into the renderer without touching it:
//! the modified Phong model of Lafortune & Willems 1994 (energy-conserving:
//! f = k_d/π + k_s·(n+2)/(2π)·cos^n α, α the angle between ωi and the mirror direction of
//! ωo), with its own importance sampling. It implements `brdf::Bsdf<N>` for any number of
//! wavelengths and `brdf::BsdfBuilder` to be instantiated at each hit; then it replaces
//! the material of the Cornell box's two blocks and renders.
//!
//! ```sh
//! cargo run --release -p tracer --example custom_brdf -- ../shared/scenes/cornell-box/CornellBox-Original.obj
//! ```

use brdf::{Bsdf, BsdfBuilder, BsdfSample, ScatterFlags};
use glam::{Vec2, Vec3};
use spectral::spectrum::Colour;
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{FRAC_1_PI, TAU};
use std::sync::Arc;
use tracer::material::Material;
use tracer::output::write_image;
use tracer::{Backend, CpuBackend, RenderSettings, SceneOptions};

/// The modified Phong BRDF at one hit.
struct Phong<const N: usize> {
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

/// The material-level description: colours as spectra, built into a `Phong` per hit.
struct PhongMaterial {
    kd: Colour,
    ks: Colour,
    exponent: f32,
}

impl BsdfBuilder for PhongMaterial {
    fn build<const N: usize>(&self, wl: &SampledWavelengths<N>) -> impl Bsdf<N> + 'static {
        let (kd, ks) = (self.kd.sample(wl), self.ks.sample(wl));
        let p_spec = ks.average() / (kd.average() + ks.average()).max(1e-6);
        Phong { kd, ks, exponent: self.exponent, p_spec }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).unwrap_or_else(|| "../shared/scenes/cornell-box/CornellBox-Original.obj".into());
    let mut scene = tracer::obj::load_obj(path.as_ref())?;
    let phong = Arc::new(PhongMaterial {
        kd: Colour::reflectance_rgb([0.35, 0.3, 0.25])?,
        ks: Colour::reflectance_rgb([0.5, 0.5, 0.5])?,
        exponent: 60.0,
    });
    let mut replaced = 0;
    for m in &mut scene.materials {
        if m.name == "shortBox" || m.name == "tallBox" {
            *m = Material::custom(&m.name, phong.clone(), false);
            replaced += 1;
        }
    }
    let prepared = CpuBackend::new(0)?.prepare(scene, &SceneOptions::default())?;
    let settings = RenderSettings { width: 256, height: 256, spp: 64, ..Default::default() };
    let (film, stats) = tracer::render(prepared.as_ref(), &settings, &|_| {})?;
    write_image("custom-brdf.png".as_ref(), film.width(), film.height(), &film.mean_rgb())?;
    println!(
        "replaced {replaced} materials with the custom Phong BRDF; wrote custom-brdf.png ({:.3} M samples/s, {} NaN/Inf)",
        stats.samples_per_second() / 1e6,
        stats.non_finite
    );
    Ok(())
}
