//! Path tracing with its caustics found by light tracing: the integrator `path-caustics`.
//!
//! A path tracer finds a caustic seen on a diffuse surface — light that reached it
//! through glass or off a mirror, paths of the form E D S⁺ L — only when the BSDF sample
//! at the diffuse point happens to leave along a direction that the specular chain
//! carries onto a light: rarely, for a small light, and then with a large weight (the
//! fireflies of a glass sphere's caustic). Next-event estimation cannot help, as no
//! shadow ray passes through the glass. A light path finds the same light easily: it
//! leaves the lamp, follows the specular chain as the light does, and is connected to the
//! camera at the first diffuse point it reaches (light tracing, Veach 1997 § 10.2's t = 1
//! strategy). So the two estimators split path space between them, with no weighting:
//! the path tracer leaves out every E D S⁺ L path that ends on a light the light tracer
//! samples ([`super::Chain`]), and light paths — one per [`LIGHT_PATH_EVERY`] camera
//! samples, weighted by that — add exactly those back. Each path is counted by one
//! estimator, so the sum is unbiased (the `tests` crate's `caustics.rs` compares it with
//! the path tracer). Every other path, including longer caustic ones (E D D S⁺ L), stays
//! with the path tracer and its lanes. One caveat, shared with bidirectional path
//! tracing: `--shading-normals adapted` (the default) bends a shading normal towards the
//! direction a path arrives from, which is the eye's side for a camera path and the
//! light's for a light path, so where the bend acts (grazing views of smooth glass and
//! mirrors) the two estimate slightly different BSDFs; `geometric` makes them agree.
//!
//! Where the split would need more than that — a depth limit (`max_depth` or
//! `max_diffuse_depth`: which path gets cut where is the path tracer's rule), glass that
//! disperses (the light path would need its own wavelengths), no film to splat onto, no
//! material that may scatter specularly (textured materials count as such) — the
//! integrator is the path tracer, unchanged.

use super::bdpt::{SurfaceData, eye_connection, importance_factor};
use super::{
    CameraSample, FilmView, Integrator, PathCounters, PathSettings, PathTracer, SceneView, Splat, entered_medium,
    lobe_leaks, segment_transmittance, shading_normals, survives_roulette,
};
use crate::lights::LightSource;
use crate::sampler::Sampler;
use brdf::sampling::cosine_hemisphere;
use brdf::{Bsdf, Frame};
use bvh::Ray;
use glam::{Vec2, Vec3};
use shapes::offset::offset_ray_origin;
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::PI;

/// One camera sample in this many traces a light path (its splats count this many times).
/// Most light paths leave the lamp towards a diffuse surface and end at once, so every
/// one costs a ray; on the glass and mirror spheres in the Cornell box (64 spp, 4 seeds,
/// `bench/seeds_error.py`) one in 1, 2, 4 and 8 reached a given error 1.36×, 1.48×, 1.52×
/// and 1.54× sooner than the path tracer, the error itself 0.57, 0.58, 0.59 and 0.62 of
/// the path tracer's (docs/figures.md): 4 keeps nearly all of the error's fall.
pub const LIGHT_PATH_EVERY: u32 = 4;

/// The path tracer with the caustics it sees on diffuse surfaces (E D S⁺ L) found by light
/// tracing instead (see the module documentation). `--integrator path-caustics`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CausticPathTracer;

impl CausticPathTracer {
    /// Whether the split applies to a render of `view` with `settings`: a film to splat
    /// onto, no depth limits and no dispersion (else the path tracer runs alone).
    pub fn splits(view: &SceneView, settings: &PathSettings) -> bool {
        view.film().is_some() && settings.max_depth == 0 && settings.max_diffuse_depth == 0 && !view.has_dispersion()
    }
}

impl Integrator for CausticPathTracer {
    fn name(&self) -> &'static str {
        "path-caustics"
    }

    /// Its camera paths' (the path tracer's); its light paths start from emitters chosen
    /// by power.
    fn chooses_lights_per_point(&self) -> bool {
        true
    }

    /// The path tracer's estimate of every path (a caller without a film gets no light
    /// paths, so nothing is left out).
    fn radiance<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        ray: Ray,
        wl: &mut SampledWavelengths<N>,
        settings: &PathSettings,
        sampler: &mut S,
        counters: &mut PathCounters,
    ) -> SampledSpectrum<N> {
        PathTracer.radiance(view, ray, wl, settings, sampler, counters)
    }

    fn kernel(&self, view: &SceneView, settings: &PathSettings) -> Option<&'static str> {
        PathTracer.kernel(view, settings)
    }

    fn radiance_block<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        settings: &PathSettings,
        block: &mut [CameraSample<N, S>],
        counters: &mut PathCounters,
    ) {
        PathTracer.radiance_block(view, settings, block, counters);
    }

    fn splats(&self) -> bool {
        true
    }

    /// Its camera paths are the path tracer's.
    fn extends_specular(&self) -> bool {
        true
    }

    fn limits_diffuse_depth(&self) -> bool {
        true
    }

    /// Each sample's light path draws its first four values (a point on a light and a
    /// direction) before the camera path, so that they sit in the same dimensions for
    /// every sample of a pixel (stratified, with a low-discrepancy sampler); the camera
    /// path follows, leaving out what the light paths add.
    fn radiance_block_splatting<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        settings: &PathSettings,
        block: &mut [CameraSample<N, S>],
        counters: &mut PathCounters,
        splats: &mut Vec<Splat>,
    ) {
        // Which materials may scatter specularly (textured ones are assumed to): without
        // any, there are no caustics to split off.
        let specular: Vec<bool> = match block.first() {
            Some(s) => view
                .scene
                .materials
                .iter()
                .map(|m| m.textures.is_some() || m.bsdf(&s.wl).flags().is_specular())
                .collect(),
            None => return,
        };
        let Some(film) = view.film().copied().filter(|_| Self::splits(view, settings) && specular.contains(&true))
        else {
            PathTracer.radiance_block(view, settings, block, counters);
            return;
        };
        let starts: Vec<(Vec2, Vec2)> = block.iter_mut().map(|s| (s.sampler.next_2d(), s.sampler.next_2d())).collect();
        let leaving = PathSettings { leave_caustics: true, ..*settings };
        PathTracer.radiance_block(view, &leaving, block, counters);
        for (s, &(u_light, u_dir)) in block.iter_mut().zip(&starts) {
            // One sample in LIGHT_PATH_EVERY traces a light path, its splats weighted by
            // that: the first draw decides, and the rest of it chooses the light (so both
            // stay stratified over a pixel's samples).
            let every = LIGHT_PATH_EVERY as f32;
            if u_light.x * every >= 1.0 {
                continue;
            }
            let u_light = Vec2::new(u_light.x * every, u_light.y);
            let first = splats.len();
            let eye = s.ray.origin;
            caustic_path(
                view,
                settings,
                &film,
                &specular,
                eye,
                &s.wl,
                (u_light, u_dir),
                &mut s.sampler,
                counters,
                splats,
            );
            for splat in &mut splats[first..] {
                splat.rgb = splat.rgb.map(|c| c * every);
            }
        }
    }
}

/// One light path from a point on an emitter (chosen by power, as next-event estimation
/// does without a light tree, by `u.0`) along a cosine-distributed direction (`u.1`), followed through specular
/// bounces only; at the first surface with a non-specular lobe after one or more of them
/// it is connected to the eye and splatted. A path whose first surface is non-specular
/// ends there: its light is the path tracer's.
#[allow(clippy::too_many_arguments)]
fn caustic_path<const N: usize, S: Sampler>(
    view: &SceneView,
    settings: &PathSettings,
    film: &FilmView,
    specular: &[bool],
    eye: Vec3,
    wl: &SampledWavelengths<N>,
    u: (Vec2, Vec2),
    sampler: &mut S,
    counters: &mut PathCounters,
    splats: &mut Vec<Splat>,
) {
    let Some(ls) = view.lights.sample(view.scene, u.0) else { return };
    let LightSource::Primitive(prim) = ls.source else { return };
    let Some(emission) = view.material(prim).emission.as_ref() else { return };
    let le = emission.sample(wl);
    if ls.pdf.is_nan() || ls.pdf <= 0.0 || le.is_black() {
        return;
    }
    let dir = Frame::from_normal(ls.normal).to_world(cosine_hemisphere(u.1));
    if dir.dot(ls.normal) <= 0.0 {
        return;
    }
    // Le·cos θ / (p_A · cos θ/π).
    let mut beta = le * (PI / ls.pdf);
    let mut ray = Ray::new(offset_ray_origin(ls.point, ls.normal), dir);
    let mut specular_bounces = 0u32;
    let mut inside = None;
    loop {
        counters.rays += 1;
        let Some(hit) = view.intersect(&ray) else { return };
        let id = view.material_id(hit.prim) as usize;
        // A first surface that cannot scatter specularly ends the path before its shading.
        if specular_bounces == 0 && !specular[id] {
            return;
        }
        let material = &view.scene.materials[id];
        let it = view.interaction(&hit, material, settings.shading_normals);
        let wo_world = -ray.dir;
        if view.absorbing {
            beta *= segment_transmittance(material, wo_world.dot(it.ng) > 0.0, hit.t, inside, wl);
        }
        let (ng, ns) = shading_normals(settings.shading_normals, it.ng, it.ns, wo_world, material.is_two_sided());
        let frame = Frame::from_normal_tangent(ns, it.tangent);
        let bsdf = material.bsdf_at(it.uv, wl);
        let flags = bsdf.flags();
        let s = SurfaceData { it, material, bsdf, frame, ng, wo_world };
        if specular_bounces > 0
            && flags.is_non_specular()
            && let Some((x, y, c)) = eye_connection(view, film, eye, &s, beta, wl, counters)
        {
            splats.push(Splat { x, y, rgb: wl.to_linear_srgb(&c) });
        }
        if !flags.is_specular() {
            return;
        }
        let wo = frame.to_local(wo_world);
        let Some(bs) = s.bsdf.sample(wo, sampler.next_1d(), sampler.next_2d()) else { return };
        // Only the specular lobe continues the chain (a surface with both lobes: its
        // non-specular one was connected above).
        if !bs.flags.is_specular() || bs.pdf <= 0.0 || bs.f.is_black() {
            return;
        }
        let wi_world = frame.to_world(bs.wi);
        if lobe_leaks(material, settings.shading_normals, s.it.ng, wo_world, wi_world, bs.flags) {
            return;
        }
        beta *= bs.f * (bs.wi.z.abs() / bs.pdf * importance_factor(&s, wo_world, wi_world, wo, bs.wi));
        if view.absorbing {
            inside = entered_medium(material, s.it.ng, wi_world);
        }
        specular_bounces += 1;
        if specular_bounces >= settings.rr_depth
            && !survives_roulette(&mut beta, 1.0, settings.rr_scale, sampler.next_1d())
        {
            return;
        }
        if beta.is_black() {
            return;
        }
        ray = Ray::new(s.it.spawn_origin(wi_world), wi_world);
    }
}
