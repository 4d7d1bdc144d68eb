//! Unidirectional path tracing with next-event estimation and multiple importance
//! sampling (Veach 1997, ch. 9; the thesis's "explicit" and "implicit" paths, ch. 5),
//! Russian roulette and spectral transport at N sampled wavelengths.

use crate::lights::Lights;
use crate::material::Material;
use crate::sampler::Pcg32;
use crate::scene::Scene;
use brdf::{Bsdf, Frame};
use bvh::{Accelerator, Hit, Ray};
use glam::Vec3;
use spectral::{SampledSpectrum, SampledWavelengths};

/// Integrator settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Maximum number of scattering events; 0 = unbounded (Russian roulette only).
    pub max_depth: u32,
    /// Russian roulette starts after this many bounces.
    pub rr_depth: u32,
    /// Path extension (thesis ch. 8.2): up to this many extra bounces beyond
    /// `max_depth` while the path keeps hitting purely specular surfaces (mirrors,
    /// glass), so that a depth limit does not blacken what is seen through glass.
    pub specular_extension: u32,
}

impl Default for PathSettings {
    fn default() -> Self {
        Self { max_depth: 0, rr_depth: 3, specular_extension: 0 }
    }
}

/// Counters a render reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathCounters {
    /// Rays traced (camera, extension and shadow).
    pub rays: u64,
}

impl std::ops::AddAssign for PathCounters {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
    }
}

/// Everything the integrator reads, prepared once per render.
pub struct SceneView<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its accelerator.
    pub accel: &'a dyn Accelerator,
    /// Its emitters.
    pub lights: &'a Lights,
}

/// Surface data at a hit.
struct Interaction {
    /// Position, interpolated from the vertices (more accurate than o + t·d).
    p: Vec3,
    /// Unit geometric normal from the winding (front = counter-clockwise).
    ng: Vec3,
    /// Unit shading normal on the same side as `ng`.
    ns: Vec3,
    /// Interpolated tangent (zero where the mesh has none).
    tangent: Vec3,
    /// Triangle area (for light pdfs).
    area: f32,
}

impl SceneView<'_> {
    fn interaction(&self, hit: &Hit) -> Interaction {
        let scene = self.scene;
        let tri = scene.triangles[hit.prim as usize];
        let [v0, v1, v2] = tri.map(|i| Vec3::from_array(scene.positions[i as usize]));
        let b0 = 1.0 - hit.u - hit.v;
        let p = b0 * v0 + hit.u * v1 + hit.v * v2;
        let cross = (v1 - v0).cross(v2 - v0);
        let area = 0.5 * cross.length();
        let ng = cross / (2.0 * area);
        let mut ns = ng;
        if !scene.normals.is_empty() {
            let [n0, n1, n2] = tri.map(|i| Vec3::from_array(scene.normals[i as usize]));
            let n = b0 * n0 + hit.u * n1 + hit.v * n2;
            if n.length_squared() > 1e-12 {
                let n = n.normalize();
                ns = if n.dot(ng) < 0.0 { -n } else { n };
            }
        }
        let tangent = if scene.tangents.is_empty() {
            Vec3::ZERO
        } else {
            let [t0, t1, t2] = tri.map(|i| Vec3::from_array(scene.tangents[i as usize]));
            b0 * t0 + hit.u * t1 + hit.v * t2
        };
        Interaction { p, ng, ns, tangent, area }
    }

    #[inline]
    fn material(&self, prim: u32) -> &Material {
        &self.scene.materials[self.scene.material_ids[prim as usize] as usize]
    }
}

/// Moves a ray origin off a surface along the normal `n` (pointing to the side the ray
/// leaves on) by a few ulps of the position — Wächter & Binder, "A Fast and Robust Method
/// for Avoiding Self-Intersection", Ray Tracing Gems (2019), ch. 6.
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let shift = |p: f32, n: f32| -> f32 {
        let of = (INT_SCALE * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = f32::from_bits((if p < 0.0 { bits - of } else { bits + of }) as u32);
        if p.abs() < ORIGIN { p + FLOAT_SCALE * n } else { moved }
    };
    Vec3::new(shift(p.x, n.x), shift(p.y, n.y), shift(p.z, n.z))
}

/// Power heuristic with β = 2 (Veach 1997, eq. 9.13).
#[inline]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 == 0.0 { 0.0 } else { a2 / (a2 + b2) }
}

/// Estimates the radiance arriving along `ray` at the sampled wavelengths. A dispersive
/// surface collapses `wl` to a single wavelength ([`SampledWavelengths::collapse_to`]);
/// the caller must convert the result with the `wl` it gets back.
pub fn radiance<const N: usize>(
    view: &SceneView,
    mut ray: Ray,
    wl: &mut SampledWavelengths<N>,
    settings: &PathSettings,
    rng: &mut Pcg32,
    counters: &mut PathCounters,
) -> SampledSpectrum<N> {
    let scene = view.scene;
    let lights = view.lights;
    let mut l = SampledSpectrum::<N>::zero();
    let mut beta = SampledSpectrum::<N>::one();
    // The pdf of the previous BSDF sample, and whether it was a delta (no MIS then).
    let mut prev_pdf = 0.0f32;
    let mut prev_specular = true;
    let mut prev_p = ray.origin;
    let mut bounce = 0u32;
    let mut extension_left = settings.specular_extension;
    loop {
        counters.rays += 1;
        let Some(hit) = view.accel.intersect(&ray) else {
            if let Some(env) = &scene.environment {
                let le = env.radiance.sample(wl);
                let w = if prev_specular { 1.0 } else { power_heuristic(prev_pdf, lights.environment_pdf()) };
                l += beta * le * w;
            }
            break;
        };
        let it = view.interaction(&hit);
        let material = view.material(hit.prim);
        let wo_world = -ray.dir;
        let front = wo_world.dot(it.ng) > 0.0;

        // Beer–Lambert: a ray reaching the back of a transmissive surface travelled
        // inside it (rays are unit length, so t is the distance).
        if !front
            && !material.is_two_sided()
            && let Some(alpha) = material.absorption()
        {
            let a = alpha.sample(wl);
            beta *= a.map(|a| (-a * hit.t).exp());
        }

        // Emission seen by this path (one-sided: front face only).
        if let Some(e) = &material.emission
            && front
        {
            let le = e.sample(wl);
            let w = if prev_specular {
                1.0
            } else {
                let dist2 = (it.p - prev_p).length_squared();
                let cos_l = wo_world.dot(it.ng);
                let light_pdf = lights.triangle_pmf(hit.prim) * dist2 / (cos_l * it.area);
                power_heuristic(prev_pdf, light_pdf)
            };
            l += beta * le * w;
        }

        if settings.max_depth > 0 && bounce >= settings.max_depth {
            // Past the limit, continue only through purely specular surfaces, while the
            // extension lasts.
            let flags = material.bsdf(wl).flags();
            if extension_left == 0 || !flags.is_specular() || flags.is_non_specular() {
                break;
            }
            extension_left -= 1;
        }

        // Dispersion: from here on the path follows one wavelength (a random lane, moved
        // to lane 0, so that the BSDF refracts it with its own index).
        if material.is_dispersive() && !wl.is_rgb() && !wl.is_collapsed() {
            let k = ((rng.next_f32() * N as f32) as usize).min(N - 1);
            wl.collapse_to(k);
            beta.0.swap(0, k);
            l.0.swap(0, k);
            for b in &mut beta.0[1..] {
                *b = 0.0;
            }
        }

        // The shading frame: two-sided BSDFs see the side the path arrived on as front.
        let flip = material.is_two_sided() && !front;
        let (ng, ns) = if flip { (-it.ng, -it.ns) } else { (it.ng, it.ns) };
        let frame = Frame::from_normal_tangent(ns, it.tangent);
        let wo = frame.to_local(wo_world);
        let bsdf = material.bsdf(wl);
        let flags = bsdf.flags();

        // Next-event estimation: one shadow ray to a point on a light.
        if flags.is_non_specular()
            && let Some(ls) = lights.sample(scene, rng.next_f32(), rng.next_2d())
        {
            let (wi_world, dist, light_pdf, le) = match ls.triangle {
                Some(t) => {
                    let d = ls.point - it.p;
                    let dist2 = d.length_squared();
                    let dist = dist2.sqrt();
                    let wi = d / dist;
                    let cos_l = -wi.dot(ls.normal);
                    let emission = scene.materials[scene.material_ids[t as usize] as usize].emission.as_ref();
                    match emission {
                        Some(e) if cos_l > 0.0 => (wi, dist, ls.pdf * dist2 / cos_l, e.sample(wl)),
                        _ => (wi, dist, 0.0, SampledSpectrum::zero()),
                    }
                }
                None => {
                    let le = scene.environment.as_ref().map_or(SampledSpectrum::zero(), |e| e.radiance.sample(wl));
                    (ls.point, f32::INFINITY, ls.pdf, le)
                }
            };
            let wi = frame.to_local(wi_world);
            // Reflection must stay on the geometric side it came from (no light leaks).
            let same_side = wi_world.dot(ng) * wo_world.dot(ng) > 0.0;
            if light_pdf > 0.0 && !le.is_black() && (same_side || !material.is_two_sided()) {
                let f = bsdf.eval(wo, wi);
                if !f.is_black() {
                    let origin = offset_ray_origin(it.p, if wi_world.dot(it.ng) > 0.0 { it.ng } else { -it.ng });
                    let shadow = if dist.is_finite() {
                        Ray::segment(origin, ls.point - origin, 0.0, 1.0 - 1e-4)
                    } else {
                        Ray::new(origin, wi_world)
                    };
                    counters.rays += 1;
                    if !view.accel.occluded(&shadow) {
                        let w = power_heuristic(light_pdf, bsdf.pdf(wo, wi));
                        l += beta * f * le * (wi.z.abs() * w / light_pdf);
                    }
                }
            }
        }

        // Continue the path by sampling the BSDF.
        let uc = rng.next_f32();
        let u = rng.next_2d();
        let Some(s) = bsdf.sample(wo, uc, u) else { break };
        if s.pdf <= 0.0 || s.f.is_black() {
            break;
        }
        let wi_world = frame.to_world(s.wi);
        if material.is_two_sided() && wi_world.dot(ng) * wo_world.dot(ng) <= 0.0 {
            break;
        }
        beta *= s.f * (s.wi.z.abs() / s.pdf);
        prev_pdf = s.pdf;
        prev_specular = s.flags.is_specular();
        prev_p = it.p;
        let origin = offset_ray_origin(it.p, if wi_world.dot(it.ng) > 0.0 { it.ng } else { -it.ng });
        ray = Ray::new(origin, wi_world);
        bounce += 1;

        // Russian roulette (Arvo & Kirk 1990): unbiased termination of dim paths.
        if bounce >= settings.rr_depth {
            let q = (1.0 - beta.max_component()).max(0.05);
            if rng.next_f32() < q {
                break;
            }
            beta /= 1.0 - q;
        }
        if beta.is_black() {
            break;
        }
    }
    l
}
