//! Light sources for next-event estimation: emissive triangles and analytic shapes
//! chosen in proportion to their power, plus the uniform environment.

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
    /// Probability density: per unit area for triangles and shapes (including the choice
    /// of the primitive), per solid angle for the environment.
    pub pdf: f32,
    /// The emitting primitive (triangle or shape id), or `None` for the environment.
    pub prim: Option<u32>,
}

/// An emissive triangle as light sampling needs it, computed once per scene instead of
/// per shadow ray (vertex lookups, a cross product and two square roots per sample).
#[derive(Clone, Copy, Debug)]
struct LightTriangle {
    vertices: [Vec3; 3],
    /// Unit front-face normal (counter-clockwise winding).
    normal: Vec3,
    area: f32,
}

/// The scene's emitters and the discrete distribution that picks among them.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// Emissive primitives (triangles, then shapes).
    prims: Vec<u32>,
    /// For each entry of `prims` that is a triangle (they come first), its geometry.
    triangles: Vec<LightTriangle>,
    cdf: Vec<f32>,
    /// Probability of choosing each primitive (0 for non-emitters), for MIS when a
    /// BSDF-sampled ray hits an emitter.
    prim_pmf: Vec<f32>,
    environment_pmf: f32,
}

impl Lights {
    /// Collects emitters and weights them by power: π·A·Y(Le) for a one-sided triangle
    /// or shape (emitting from its front or outside), 4π²·r²·Y(Le) for the environment
    /// seen by a scene of bounding radius r (pbrt-v4's uniform infinite light). Shapes
    /// that cannot be sampled by area (implicit surfaces, self-intersecting polygons)
    /// still glow when a path hits them, but are never sampled: their MIS weight is 1.
    pub fn new(scene: &Scene) -> Self {
        let triangles = scene.triangles.len();
        let mut prims = Vec::new();
        let mut power = Vec::new();
        let mut prim_pmf = vec![0.0; triangles + scene.shapes.len()];
        let mut push = |prim: usize, area: f32, material: u32| {
            if let Some(e) = &scene.materials[material as usize].emission {
                let p = PI * area * e.luminance().max(0.0);
                if p > 0.0 && p.is_finite() {
                    prims.push(prim as u32);
                    power.push(p as f64);
                }
            }
        };
        for (i, &m) in scene.material_ids.iter().enumerate() {
            let v = scene.triangle_vertices(i);
            push(i, 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length(), m);
        }
        for (k, s) in scene.shapes.iter().enumerate() {
            let shape = s.shape.shape();
            if shape.sample_area(Vec2::splat(0.5)).is_some() {
                push(triangles + k, shape.area(), s.material);
            }
        }
        let env_power = scene.environment.as_ref().map_or(0.0, |env| {
            let r = 0.5 * scene.bounds().extent().length().max(1e-3);
            (4.0 * PI * PI * r * r * env.radiance.luminance().max(0.0)) as f64
        });
        let total: f64 = power.iter().sum::<f64>() + env_power;
        if total <= 0.0 {
            return Self { prim_pmf, ..Default::default() };
        }
        // The environment owns [0, pmf_env) of the unit interval, primitives the rest.
        let mut acc = env_power;
        let cdf = power
            .iter()
            .map(|p| {
                acc += p;
                (acc / total) as f32
            })
            .collect();
        for (&t, p) in prims.iter().zip(&power) {
            prim_pmf[t as usize] = (p / total) as f32;
        }
        let triangles = prims
            .iter()
            .take_while(|&&p| (p as usize) < triangles)
            .map(|&p| {
                let vertices = scene.triangle_vertices(p as usize);
                let cross = (vertices[1] - vertices[0]).cross(vertices[2] - vertices[0]);
                LightTriangle { vertices, normal: cross.normalize(), area: 0.5 * cross.length() }
            })
            .collect();
        Self { prims, triangles, cdf, prim_pmf, environment_pmf: (env_power / total) as f32 }
    }

    /// True if there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.prims.is_empty() && self.environment_pmf == 0.0
    }

    /// Number of emissive primitives that are sampled.
    pub fn emitter_count(&self) -> usize {
        self.prims.len()
    }

    /// The sampled emissive primitives (triangles first, then shapes), in the order of
    /// [`Lights::cdf`]; for backends that rebuild the distribution elsewhere (the GPU).
    pub fn prims(&self) -> &[u32] {
        &self.prims
    }

    /// The cumulative distribution over [`Lights::prims`]: entry k is the probability of
    /// picking the environment or one of primitives 0..=k (the environment owns
    /// [0, [`Lights::environment_pmf`])). [`Lights::sample`] picks the first k with
    /// `cdf[k] > u` (clamped to the last).
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// The probability of picking each primitive, indexed by primitive id (0 for
    /// primitives that are not sampled); [`Lights::prim_pmf`] for all of them at once.
    pub fn prim_pmfs(&self) -> &[f32] {
        &self.prim_pmf
    }

    /// The probability that [`Lights::sample`] picks primitive `prim`.
    #[inline]
    pub fn prim_pmf(&self, prim: u32) -> f32 {
        self.prim_pmf.get(prim as usize).copied().unwrap_or(0.0)
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
    #[inline(always)]
    pub fn sample(&self, scene: &Scene, u_light: f32, u: Vec2) -> Option<LightSample> {
        if self.is_empty() {
            return None;
        }
        if u_light < self.environment_pmf || self.prims.is_empty() {
            return Some(LightSample {
                point: uniform_sphere(u),
                normal: Vec3::ZERO,
                pdf: self.environment_pdf(),
                prim: None,
            });
        }
        let k = self.cdf.partition_point(|&c| c <= u_light).min(self.prims.len() - 1);
        let prim = self.prims[k];
        let pmf = self.prim_pmf[prim as usize];
        if let Some(t) = self.triangles.get(k) {
            let v = &t.vertices;
            let (b0, b1) = uniform_triangle(u);
            let point = b0 * v[0] + b1 * v[1] + (1.0 - b0 - b1) * v[2];
            return Some(LightSample { point, normal: t.normal, pdf: pmf / t.area, prim: Some(prim) });
        }
        let shape = scene.shapes[prim as usize - scene.triangles.len()].shape.shape();
        let (point, normal) = shape.sample_area(u)?;
        Some(LightSample { point, normal, pdf: pmf / shape.area(), prim: Some(prim) })
    }
}
