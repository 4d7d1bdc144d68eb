//! Two biased integrators that isolate one part of light transport: [`DirectLighting`]
//! (light that reaches the camera after at most one reflection) and [`AmbientOcclusion`]
//! (how open the hemisphere above the first surface is). Each states its bias and is
//! tested against what it should equal (`tests/tests/integrators.rs`).

use super::{Integrator, Mis, PathCounters, PathSettings, SceneView, Shading, next_event};
use crate::sampler::Sampler;
use brdf::sampling::cosine_hemisphere;
use brdf::{Bsdf, Frame};
use bvh::Ray;
use shapes::offset::offset_ray_origin;
use spectral::spectrum::{Colour, ColourRole, Spectrum};
use spectral::{SampledSpectrum, SampledWavelengths};

/// Direct lighting: the emission the camera sees plus, at the first surface, light
/// sampled on the emitters (one shadow ray, no MIS: lights are found only by sampling
/// them). Its expectation is path tracing's at `--max-depth 1` wherever the first surface
/// is not purely specular; it is biased by design against the full solution (no indirect
/// light) and sees nothing through mirrors and glass. Cheaper per sample than path
/// tracing, noisier than it on glossy surfaces near large lights (where BSDF sampling,
/// which the path tracer's MIS adds, does better).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DirectLighting;

impl Integrator for DirectLighting {
    fn name(&self) -> &'static str {
        "direct"
    }

    fn chooses_lights_per_point(&self) -> bool {
        true
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
        counters.rays += 1;
        let Some(hit) = view.intersect(&ray) else {
            return view.escaped_radiance(ray.dir, wl);
        };
        let material = view.material(hit.prim);
        let it = view.interaction(&hit, material, settings.shading_normals);
        let wo_world = -ray.dir;
        let mut l = SampledSpectrum::zero();
        if wo_world.dot(it.ng) > 0.0
            && let Some(le) = material.emission_at(it.uv, wl)
        {
            l += le;
        }
        let (ng, ns) =
            super::shading_normals(settings.shading_normals, it.ng, it.ns, wo_world, material.is_two_sided());
        let frame = Frame::from_normal_tangent(ns, it.tangent);
        let bsdf = material.bsdf_at(it.uv, wl);
        if bsdf.flags().is_non_specular() {
            let at = Shading { it: &it, material, ng, wo_world, frame: &frame, wo: frame.to_local(wo_world) };
            if let Some((f, le, k)) = next_event(view, &at, &bsdf, wl, Mis::None, sampler.next_2d(), counters) {
                l += f * le * k;
            }
        }
        l
    }
}

/// Ambient occlusion: at the first surface the camera sees, the probability that a
/// cosine-distributed direction on the viewer's side of the shading normal reaches
/// `max_distance` without hitting anything, as a grey of that value (linear sRGB (v, v,
/// v); pixels that see no surface are black). Not light transport: a measure of
/// openness, the classic preview and the source document's stand-in for indirect light.
/// For a floor under an infinite ceiling at height h it is (h / d)² for d ≥ h, 1 below
/// (tested).
#[derive(Clone, Debug, PartialEq)]
pub struct AmbientOcclusion {
    /// Occluders farther than this do not count (∞: any occluder).
    pub max_distance: f32,
    /// White (D65 at luminance 1): the unoccluded value.
    white: Colour,
}

impl AmbientOcclusion {
    /// Ambient occlusion up to `max_distance` (positive; `f32::INFINITY` for any).
    pub fn new(max_distance: f32) -> Self {
        Self { max_distance, white: Self::white() }
    }

    /// The value of an unoccluded sample: D65 at luminance 1 (the GPU tabulates it).
    pub fn white() -> Colour {
        Colour::from_spectrum(Spectrum::D65(1.0), ColourRole::Illuminant)
    }
}

impl Default for AmbientOcclusion {
    fn default() -> Self {
        Self::new(f32::INFINITY)
    }
}

impl Integrator for AmbientOcclusion {
    fn name(&self) -> &'static str {
        "ao"
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
        counters.rays += 1;
        let Some(hit) = view.intersect(&ray) else { return SampledSpectrum::zero() };
        let it = view.interaction(&hit, view.material(hit.prim), settings.shading_normals);
        // The hemisphere on the viewer's side.
        let side = if ray.dir.dot(it.ng) < 0.0 { 1.0 } else { -1.0 };
        let (ng, mut ns) = (it.ng * side, it.ns * side);
        if ns.dot(ng) <= 0.0 {
            ns = ng;
        }
        let wi = Frame::from_normal_tangent(ns, it.tangent).to_world(cosine_hemisphere(sampler.next_2d()));
        if wi.dot(ng) <= 0.0 {
            // A shading normal tilted the sample under the surface: it is blocked.
            return SampledSpectrum::zero();
        }
        let origin = offset_ray_origin(it.p, ng);
        let probe = if self.max_distance.is_finite() {
            Ray::segment(origin, wi, 0.0, self.max_distance)
        } else {
            Ray::new(origin, wi)
        };
        counters.rays += 1;
        if view.occluded(&probe) { SampledSpectrum::zero() } else { self.white.sample(wl) }
    }
}
