//! Whitted-style recursive ray tracing (T. Whitted, "An Improved Illumination Model for
//! Shaded Display", CACM 23(6), 1980; the lecture's `traceRay`).

use super::{
    Integrator, Mis, PathCounters, PathSettings, SceneView, Shading, entered_medium, light_contribution, lobe_leaks,
};
use crate::lights::{LightSource, Lights, ONE_MINUS_EPSILON};
use crate::sampler::Sampler;
use brdf::{Bsdf, Frame};
use bvh::Ray;
use glam::Vec2;
use spectral::{SampledSpectrum, SampledWavelengths};

/// The recursion depth when the settings leave it unbounded (`max_depth` 0): a ray may
/// split at every glass surface, so the tree has up to 2^depth leaves.
pub const WHITTED_DEFAULT_DEPTH: u32 = 8;

/// Whitted ray tracing: at a purely specular surface (mirror, smooth conductor, smooth
/// glass) the ray splits deterministically into its reflected and refracted parts,
/// weighted by the exact Fresnel terms of the surface's BSDF (total internal reflection
/// included); at any other surface it gathers direct light only — every point, spot and
/// directional light by its own shadow ray, and one sample over the area lights and the
/// environment — and stops. Emission seen along the way counts, as does the environment
/// where a ray escapes.
///
/// Biased by design: no indirect light off non-specular surfaces (it equals path
/// tracing's `--max-depth 1` on diffuse scenes), nothing reflected by the delta part of a
/// mixed surface, and the recursion stops at `max_depth` ([`WHITTED_DEFAULT_DEPTH`] when
/// unbounded). On scenes whose surfaces are all purely specular it converges to the path
/// tracer at the same depth (tested); what noise is left there comes from the pixel and
/// wavelength samples, not from choosing between reflection and refraction. Scenes with dispersive glass
/// trace a single wavelength per sample (a random one of the sampled set, weighted so
/// that the estimate stays unbiased), since the branches must share their wavelengths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Whitted;

impl Integrator for Whitted {
    fn name(&self) -> &'static str {
        "whitted"
    }

    fn radiance<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        ray: Ray,
        wl: &mut SampledWavelengths<N>,
        settings: &PathSettings,
        sampler: &mut S,
        counters: &mut PathCounters,
    ) -> SampledSpectrum<N> {
        if view.has_dispersion() && !wl.is_rgb() && !wl.is_collapsed() {
            let k = ((sampler.next_1d() * N as f32) as usize).min(N - 1);
            wl.collapse_to(k);
        }
        let max_depth = if settings.max_depth > 0 { settings.max_depth } else { WHITTED_DEFAULT_DEPTH };
        trace(view, ray, wl, settings, max_depth, 0, None, sampler, counters)
    }
}

/// The radiance along `ray`, which has already scattered `depth` times and left its
/// origin into the absorbing material `inside`, if any.
#[allow(clippy::too_many_arguments)]
fn trace<const N: usize, S: Sampler>(
    view: &SceneView,
    ray: Ray,
    wl: &SampledWavelengths<N>,
    settings: &PathSettings,
    max_depth: u32,
    depth: u32,
    inside: Option<&spectral::spectrum::Colour>,
    sampler: &mut S,
    counters: &mut PathCounters,
) -> SampledSpectrum<N> {
    counters.rays += 1;
    let scene = view.scene;
    let Some(hit) = view.intersect(&ray) else {
        return view.escaped_radiance(ray.dir, wl);
    };
    let material = view.material(hit.prim);
    let it = view.interaction(&hit, material, settings.shading_normals);
    let wo_world = -ray.dir;
    let front = wo_world.dot(it.ng) > 0.0;
    let mut l = SampledSpectrum::<N>::zero();
    // Beer–Lambert inside absorbing glass, as in the path tracer.
    let attenuation = if view.absorbing {
        super::segment_transmittance(material, front, hit.t, inside, wl)
    } else {
        SampledSpectrum::one()
    };
    if front && let Some(le) = material.emission_at(it.uv, wl) {
        l += le;
    }
    if depth >= max_depth {
        return l * attenuation;
    }
    let (ng, ns) = super::shading_normals(settings.shading_normals, it.ng, it.ns, wo_world, material.is_two_sided());
    let frame = Frame::from_normal_tangent(ns, it.tangent);
    let wo = frame.to_local(wo_world);
    let bsdf = material.bsdf_at(it.uv, wl);
    let flags = bsdf.flags();
    if flags.is_non_specular() {
        let at = Shading { it: &it, material, ng, wo_world, frame: &frame, wo };
        // Every punctual light deterministically (probability 1 each)…
        // (A sun disk by one direction drawn within it.)
        for (k, light) in scene.punctual_lights.iter().enumerate() {
            let u = if light.disk().is_some() { sampler.next_2d() } else { Vec2::ZERO };
            let ls = Lights::sample_punctual(scene, k, u);
            if let Some((f, le, w)) = light_contribution(view, &at, &bsdf, wl, Mis::None, &ls, counters) {
                l += f * le * w;
            }
        }
        // …and one sample of the rest: a punctual light drawn here counts zero, which
        // keeps the estimate of the others unbiased (each is divided by its own
        // probability).
        if view.lights.emitter_count() > 0 || view.lights.environment_pmf() > 0.0 {
            let u = sampler.next_2d();
            if let Some(ls) = view.lights.sample(scene, u)
                && !matches!(ls.source, LightSource::Punctual(_))
                && let Some((f, le, w)) = light_contribution(view, &at, &bsdf, wl, Mis::None, &ls, counters)
            {
                l += f * le * w;
            }
        }
        return l * attenuation;
    }
    // A purely specular surface: follow each of its lobes. The sample value uc picks the
    // lobe (reflection below the Fresnel reflectance, transmission above), so its two
    // ends give both; f·|cos θ| is a lobe's deterministic weight (f·|cos θ|/pdf would be
    // its weight when chosen with probability pdf).
    let first = bsdf.sample(wo, 0.0, Vec2::ZERO);
    let last = bsdf.sample(wo, ONE_MINUS_EPSILON, Vec2::ZERO);
    let lobes: [Option<_>; 2] = match (first, last) {
        (Some(a), Some(b)) if a.flags == b.flags => [Some(a), None],
        pair => [pair.0, pair.1],
    };
    let split = lobes[1].is_some();
    for s in lobes.into_iter().flatten() {
        if s.pdf <= 0.0 || s.f.is_black() {
            continue;
        }
        let weight = if split { s.f * s.wi.z.abs() } else { s.f * (s.wi.z.abs() / s.pdf) };
        let wi_world = frame.to_world(s.wi);
        if lobe_leaks(material, settings.shading_normals, it.ng, wo_world, wi_world, s.flags) {
            continue;
        }
        let child_ray = Ray::new(it.spawn_origin(wi_world), wi_world);
        let entered = if view.absorbing { entered_medium(material, it.ng, wi_world) } else { None };
        let child = trace(view, child_ray, wl, settings, max_depth, depth + 1, entered, sampler, counters);
        l += weight * child;
    }
    l * attenuation
}
