//! Light sources for next-event estimation: emissive triangles chosen in proportion to
//! their power, plus the uniform environment.

use crate::scene::Scene;
use brdf::sampling::{UNIFORM_SPHERE_PDF, uniform_sphere, uniform_triangle};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A point (or direction, for the environment) chosen on a light.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The sampled point, or a unit direction for the environment.
    pub point: Vec3,
    /// The light's front-face normal at the point (zero for the environment).
    pub normal: Vec3,
    /// Probability density: per unit area for triangles (including the choice of the
    /// triangle), per solid angle for the environment.
    pub pdf: f32,
    /// The emitting triangle, or `None` for the environment.
    pub triangle: Option<u32>,
}

/// The scene's emitters and the discrete distribution that picks among them.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    triangles: Vec<u32>,
    cdf: Vec<f32>,
    /// Probability of choosing each scene triangle (0 for non-emitters), for MIS when a
    /// BSDF-sampled ray hits an emitter.
    triangle_pmf: Vec<f32>,
    environment_pmf: f32,
}

impl Lights {
    /// Collects emitters and weights them by power: π·A·Y(Le) for a one-sided triangle,
    /// 4π²·r²·Y(Le) for the environment seen by a scene of bounding radius r (pbrt-v4's
    /// uniform infinite light).
    pub fn new(scene: &Scene) -> Self {
        let mut triangles = Vec::new();
        let mut power = Vec::new();
        let mut triangle_pmf = vec![0.0; scene.triangles.len()];
        for (i, &m) in scene.material_ids.iter().enumerate() {
            if let Some(e) = &scene.materials[m as usize].emission {
                let v = scene.triangle_vertices(i);
                let area = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
                let p = PI * area * e.luminance().max(0.0);
                if p > 0.0 && p.is_finite() {
                    triangles.push(i as u32);
                    power.push(p as f64);
                }
            }
        }
        let env_power = scene.environment.as_ref().map_or(0.0, |env| {
            let r = 0.5 * scene.bounds().extent().length().max(1e-3);
            (4.0 * PI * PI * r * r * env.radiance.luminance().max(0.0)) as f64
        });
        let total: f64 = power.iter().sum::<f64>() + env_power;
        if total <= 0.0 {
            return Self { triangle_pmf, ..Default::default() };
        }
        // The environment owns [0, pmf_env) of the unit interval, triangles the rest.
        let mut acc = env_power;
        let cdf = power
            .iter()
            .map(|p| {
                acc += p;
                (acc / total) as f32
            })
            .collect();
        for (&t, p) in triangles.iter().zip(&power) {
            triangle_pmf[t as usize] = (p / total) as f32;
        }
        Self { triangles, cdf, triangle_pmf, environment_pmf: (env_power / total) as f32 }
    }

    /// True if there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty() && self.environment_pmf == 0.0
    }

    /// Number of emissive triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The probability that [`Lights::sample`] picks scene triangle `t`.
    #[inline]
    pub fn triangle_pmf(&self, t: u32) -> f32 {
        self.triangle_pmf.get(t as usize).copied().unwrap_or(0.0)
    }

    /// The probability that [`Lights::sample`] picks the environment.
    #[inline]
    pub fn environment_pmf(&self) -> f32 {
        self.environment_pmf
    }

    /// Solid-angle pdf of sampling environment direction (any direction: uniform).
    #[inline]
    pub fn environment_pdf(&self) -> f32 {
        self.environment_pmf * UNIFORM_SPHERE_PDF
    }

    /// Picks a light with `u_light`, then a point on it with `u`.
    #[inline]
    pub fn sample(&self, scene: &Scene, u_light: f32, u: Vec2) -> Option<LightSample> {
        if self.is_empty() {
            return None;
        }
        if u_light < self.environment_pmf || self.triangles.is_empty() {
            return Some(LightSample {
                point: uniform_sphere(u),
                normal: Vec3::ZERO,
                pdf: self.environment_pdf(),
                triangle: None,
            });
        }
        let target = u_light;
        let k = self.cdf.partition_point(|&c| c <= target).min(self.triangles.len() - 1);
        let t = self.triangles[k];
        let v = scene.triangle_vertices(t as usize);
        let (b0, b1) = uniform_triangle(u);
        let point = b0 * v[0] + b1 * v[1] + (1.0 - b0 - b1) * v[2];
        let cross = (v[1] - v[0]).cross(v[2] - v[0]);
        let area = 0.5 * cross.length();
        Some(LightSample {
            point,
            normal: cross.normalize(),
            pdf: self.triangle_pmf[t as usize] / area,
            triangle: Some(t),
        })
    }
}
