//! Bidirectional path tracing with multiple importance sampling (Veach & Guibas 1995;
//! Veach 1997, ch. 10; the organisation of pbrt-v3 §16.3): a camera subpath and a light
//! subpath per sample, every pair of their prefixes connected, each connection weighted
//! by the power heuristic over all the ways the same path could have been sampled.

use super::{
    Interaction, Mis, PathCounters, PathSettings, SHADOW_T_MAX, SceneView, Shading, beer_lambert, compression,
    entered_medium, light_contribution, lobe_leaks, power_heuristic, segment_transmittance, shading_normals,
    survives_roulette,
};
use crate::integrator::{CameraSample, Integrator, Splat};
use crate::lights::{LightSample, LightSource};
use crate::material::{Material, MaterialBsdf};
use crate::punctual::PunctualLight;
use crate::sampler::Sampler;
use brdf::sampling::{UNIFORM_SPHERE_PDF, cosine_hemisphere, uniform_sphere};
use brdf::{Bsdf, Frame, ScatterFlags};
use bvh::Ray;
use glam::Vec3;
use shapes::offset::offset_ray_origin;
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{FRAC_1_PI, TAU};

/// The most vertices a camera subpath holds (the eye and 64 surfaces) when the settings
/// leave the depth unbounded: Russian roulette ends nearly every path long before, and a
/// path cut here is counted in [`PathCounters::truncated`].
pub const BDPT_MAX_VERTICES: usize = 66;

/// Bidirectional path tracing (`--integrator bdpt`).
///
/// Each camera sample traces a camera subpath z₀…z_{t−1} (z₀ the eye) and a light
/// subpath y₀…y_{s−1} (y₀ on an area, point or spot light chosen by power), both by
/// BSDF sampling with Russian roulette, and evaluates every strategy (s, t): the camera
/// path hitting a light (s = 0), next-event estimation from each camera vertex (s = 1,
/// with a fresh light sample), connections of the two subpaths' vertices (s, t ≥ 2), and
/// light tracing, each light vertex connected to the eye and *splatted* onto the pixel
/// it is seen in (t = 1). Each is weighted by the power heuristic over all strategies
/// that generate the same path (Veach 1997, eq. 10.9), from the per-vertex densities of
/// both directions (pbrt-v3's `MISWeight`). Light subpaths carry importance: the 1/η²
/// scaling of radiance refracted through glass is undone ([`Bsdf::eta`]) and shading
/// normals get Veach's adjoint correction (1997, eq. 5.17).
///
/// Lights at infinity (the environment, directional lights and sun disks) start no
/// light subpaths: the paths that end on them are sampled as the path tracer samples
/// them, by next-event estimation and by escaping camera paths, weighted against each
/// other by the power heuristic. So on a scene lit only by a sky it equals the path
/// tracer (at a higher cost per sample); where it pays is small lights and caustics seen
/// through glass on a diffuse surface, which only light tracing finds efficiently.
///
/// Unbiased with an unbounded depth (up to [`BDPT_MAX_VERTICES`] − 2 bounces; paths cut
/// there are counted as truncated); with `max_depth` D, paths of at most D bounces, as
/// the path tracer's. Point lights are not visible to
/// the camera directly (as in the path tracer); `specular_extension` is ignored. Where
/// shading normals are bent ([`crate::integrator::ShadingNormals::Adapted`] at
/// silhouettes) the densities used for the weights are those of the frame the subpath
/// built, a small inconsistency between strategies (exact with geometric normals). A
/// backend that cannot splat runs it without light tracing ([`Integrator::radiance`]:
/// the other strategies, weighted among themselves), which is still unbiased.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Bdpt;

/// How radiance at a surface vertex is carried: towards the camera (radiance) or from
/// the lights (importance, the adjoint).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Transport {
    Radiance,
    Importance,
}

/// What a subpath vertex lies on.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Camera,
    /// A point sampled on an emissive primitive, or a point or spot light.
    Light(LightSource),
    Surface,
}

/// A surface vertex's shading: where it is and the BSDF it scatters with.
pub(super) struct SurfaceData<'a, const N: usize> {
    pub(super) it: Interaction,
    pub(super) material: &'a Material,
    pub(super) bsdf: MaterialBsdf<'a, N>,
    pub(super) frame: Frame,
    /// The geometric normal as the BSDF sees it (flipped to the arriving side for
    /// two-sided materials).
    pub(super) ng: Vec3,
    /// Unit direction towards the previous vertex of its subpath.
    pub(super) wo_world: Vec3,
}

/// One vertex of a camera or light subpath.
struct Vertex<'a, const N: usize> {
    kind: Kind,
    p: Vec3,
    /// Unit front-face normal for surfaces and area lights; zero for the eye and point
    /// lights (no area, no cosine).
    n: Vec3,
    surface: Option<SurfaceData<'a, N>>,
    /// Throughput from the subpath's start up to this vertex, over its density.
    beta: SampledSpectrum<N>,
    /// Area density of sampling this vertex from the one before it on its subpath.
    pdf_fwd: f32,
    /// Area density of sampling it from the one after it (the other direction).
    pdf_rev: f32,
    /// Scattered by a delta lobe (it cannot be connected to).
    delta: bool,
    /// A point or spot light: the strategy that hits the light cannot find it.
    delta_light: bool,
    /// The density with which light sampling picks this point (area measure, choice of
    /// the light included); 0 where the light is never sampled.
    origin_pdf: f32,
}

impl<const N: usize> Vertex<'_, N> {
    fn camera(eye: Vec3) -> Self {
        Self {
            kind: Kind::Camera,
            p: eye,
            n: Vec3::ZERO,
            surface: None,
            beta: SampledSpectrum::one(),
            pdf_fwd: 1.0,
            pdf_rev: 0.0,
            delta: false,
            delta_light: false,
            origin_pdf: 0.0,
        }
    }

    /// Whether a connection can end here: not on a purely specular surface.
    fn connectible(&self) -> bool {
        self.surface.as_ref().is_none_or(|s| s.bsdf.flags().is_non_specular())
    }

    /// Where a ray towards `target` leaves this vertex (off the surface on its side).
    fn origin_towards(&self, target: Vec3) -> Vec3 {
        match &self.surface {
            Some(s) => s.it.spawn_origin(target - self.p),
            None if self.n != Vec3::ZERO => {
                offset_ray_origin(self.p, if (target - self.p).dot(self.n) > 0.0 { self.n } else { -self.n })
            }
            None => self.p,
        }
    }
}

/// 0 → 1, for the density ratios of delta vertices (whose densities are stored as 0 and
/// which are skipped anyway).
#[inline]
fn remap0(x: f32) -> f32 {
    if x != 0.0 { x } else { 1.0 }
}

/// A solid-angle density at `from` turned into an area density at the point `to` with
/// normal `n` (zero: a point, no cosine).
#[inline]
fn to_area(pdf_dir: f32, from: Vec3, to: Vec3, n: Vec3) -> f32 {
    let d = to - from;
    let dist2 = d.length_squared();
    if dist2.is_nan() || dist2 <= 0.0 {
        return 0.0;
    }
    let cos = if n == Vec3::ZERO { 1.0 } else { n.dot(d).abs() / dist2.sqrt() };
    pdf_dir * cos / dist2
}

/// The spot light's cone, if `light` is one: (axis, cos of its outer angle).
fn spot_cone(light: &PunctualLight) -> Option<(Vec3, f32)> {
    match *light {
        PunctualLight::Spot { direction, cos_outer, .. } => Some((direction, cos_outer.max(-1.0))),
        _ => None,
    }
}

/// Solid-angle density of the direction in which a light emits from a sampled point:
/// uniform over the sphere for a point light and over the outer cone for a spot, and
/// cos θ / π from a point on an emitter (`kind` a sampled area light or a surface; front
/// side only).
fn emission_pdf(view: &SceneView, kind: Kind, n: Vec3, dir: Vec3) -> f32 {
    match kind {
        Kind::Light(LightSource::Punctual(k)) => match spot_cone(&view.scene.punctual_lights[k as usize]) {
            None => UNIFORM_SPHERE_PDF,
            Some((axis, cos_outer)) => {
                if dir.dot(axis) >= cos_outer {
                    1.0 / (TAU * (1.0 - cos_outer))
                } else {
                    0.0
                }
            }
        },
        _ => dir.dot(n).max(0.0) * FRAC_1_PI,
    }
}

/// The camera's density for a ray towards `dir`, per solid angle ([`super::FilmView::density`]),
/// 0 outside the region rendered (or without a film).
fn camera_pdf(view: &SceneView, dir: Vec3) -> f32 {
    let Some(film) = view.film() else { return 0.0 };
    match film.rays.film_position(film.rays.eye() + dir).and_then(|f| film.pixel(f)) {
        Some(_) => film.density(dir),
        None => 0.0,
    }
}

/// f at a surface vertex for light arriving from `wi` and leaving towards `wo` (world,
/// unit), in the given transport mode; zero where the geometry forbids it.
fn surface_f<const N: usize>(s: &SurfaceData<'_, N>, wo: Vec3, wi: Vec3, mode: Transport) -> SampledSpectrum<N> {
    // A two-sided surface reflects only on the side it was reached from.
    if s.material.is_two_sided() && wo.dot(s.ng) * wi.dot(s.ng) <= 0.0 {
        return SampledSpectrum::zero();
    }
    let (wo_l, wi_l) = (s.frame.to_local(wo), s.frame.to_local(wi));
    let f = s.bsdf.eval(wo_l, wi_l);
    if mode == Transport::Radiance || f.is_black() {
        return f;
    }
    f * importance_factor(s, wo, wi, wo_l, wi_l)
}

/// What turns a radiance BSDF value into the adjoint's at a light-subpath vertex (ωo
/// towards the light side, ωi towards the camera side): η'² for a transmission (the
/// BSDF divided radiance by it) times Veach's shading-normal correction
/// |ωo·n_s| |ωi·n_g| / (|ωo·n_g| |ωi·n_s|) (1997, eq. 5.17).
pub(super) fn importance_factor<const N: usize>(
    s: &SurfaceData<'_, N>,
    wo: Vec3,
    wi: Vec3,
    wo_l: Vec3,
    wi_l: Vec3,
) -> f32 {
    let k = compression(&s.bsdf, wo_l, wo_l.z * wi_l.z < 0.0);
    let (ng, ns) = (s.it.ng, s.frame.n);
    let den = wo.dot(ng).abs() * wi.dot(ns).abs();
    if den == 0.0 {
        return 0.0;
    }
    k * wo.dot(ns).abs() * wi.dot(ng).abs() / den
}

/// The area density at `next` of sampling it from `v`, which was reached from `prev`
/// (a point; `None` at a subpath's start).
fn pdf_to<const N: usize>(view: &SceneView, v: &Vertex<'_, N>, prev: Option<Vec3>, next: &Vertex<'_, N>) -> f32 {
    let d = next.p - v.p;
    let dist = d.length();
    if dist.is_nan() || dist <= 0.0 {
        return 0.0;
    }
    let dir = d / dist;
    let pdf_dir = match (v.kind, &v.surface) {
        (Kind::Camera, _) => camera_pdf(view, dir),
        (Kind::Light(_), _) => emission_pdf(view, v.kind, v.n, dir),
        (Kind::Surface, Some(s)) => {
            let Some(prev) = prev else { return 0.0 };
            let wo = (prev - v.p).normalize_or_zero();
            s.bsdf.pdf(s.frame.to_local(wo), s.frame.to_local(dir))
        }
        (Kind::Surface, None) => 0.0,
    };
    to_area(pdf_dir, v.p, next.p, next.n)
}

/// The area density at `next` of a light at `v` (a light vertex, or a surface vertex on
/// an emitter) emitting towards it.
fn pdf_light_to<const N: usize>(view: &SceneView, v: &Vertex<'_, N>, next: &Vertex<'_, N>) -> f32 {
    let dir = (next.p - v.p).normalize_or_zero();
    to_area(emission_pdf(view, v.kind, v.n, dir), v.p, next.p, next.n)
}

/// The densities of one vertex that a strategy's weight reads.
#[derive(Clone, Copy)]
struct Densities {
    fwd: f32,
    rev: f32,
    delta: bool,
}

/// The strategy being weighted: s light and t camera vertices, with `sampled` standing
/// in for the light subpath's only vertex when s = 1 (a fresh light sample).
struct Strategy<'v, 'a, const N: usize> {
    light: &'v [Vertex<'a, N>],
    camera: &'v [Vertex<'a, N>],
    sampled: Option<&'v Vertex<'a, N>>,
    s: usize,
    t: usize,
    /// Whether light tracing (t = 1) is among the strategies.
    light_tracing: bool,
}

impl<const N: usize> Strategy<'_, '_, N> {
    /// The power heuristic's weight of this strategy among all that sample the same path
    /// (Veach 1997, eq. 10.9, with β = 2): 1 / Σᵢ (pᵢ / p_s)², the ratios walked vertex by
    /// vertex from the connection outwards (pbrt-v3 §16.3.4).
    fn weight(&self, view: &SceneView) -> f32 {
        let (s, t) = (self.s, self.t);
        if s + t == 2 {
            return 1.0;
        }
        let qs = match s {
            0 => None,
            1 => self.sampled.or(self.light.first()),
            _ => Some(&self.light[s - 1]),
        };
        let pt = &self.camera[t - 1];
        let qs_minus = (s > 1).then(|| &self.light[s - 2]);
        let pt_minus = (t > 1).then(|| &self.camera[t - 2]);

        // The densities of the connection's end points and their neighbours as this
        // strategy sees them (the end points connectible, reached from the other side);
        // every other vertex's as its subpath stored them.
        let (pt_rev, pt_minus_rev, qs_rev, qs_minus_rev) = match qs {
            Some(qs) => (
                pdf_to(view, qs, qs_minus.map(|v| v.p), pt),
                pt_minus.map(|pm| pdf_to(view, pt, Some(qs.p), pm)),
                pdf_to(view, pt, pt_minus.map(|v| v.p), qs),
                qs_minus.map(|qm| pdf_to(view, qs, Some(pt.p), qm)),
            ),
            None => (pt.origin_pdf, pt_minus.map(|pm| pdf_light_to(view, pt, pm)), 0.0, None),
        };
        let cam = |i: usize| -> Densities {
            let v = &self.camera[i];
            match t - 1 - i {
                0 => Densities { fwd: v.pdf_fwd, rev: pt_rev, delta: false },
                1 => Densities { fwd: v.pdf_fwd, rev: pt_minus_rev.unwrap_or(v.pdf_rev), delta: v.delta },
                _ => Densities { fwd: v.pdf_fwd, rev: v.pdf_rev, delta: v.delta },
            }
        };
        let lig = |i: usize| -> Densities {
            match s - 1 - i {
                0 => Densities { fwd: qs.map_or(0.0, |q| q.pdf_fwd), rev: qs_rev, delta: false },
                1 => {
                    let v = &self.light[i];
                    Densities { fwd: v.pdf_fwd, rev: qs_minus_rev.unwrap_or(v.pdf_rev), delta: v.delta }
                }
                _ => {
                    let v = &self.light[i];
                    Densities { fwd: v.pdf_fwd, rev: v.pdf_rev, delta: v.delta }
                }
            }
        };
        // Whether the light subpath starts on a point or spot light (the camera path
        // cannot hit one).
        let light0_delta = match s {
            0 => false,
            1 => qs.is_some_and(|q| q.delta_light),
            _ => self.light[0].delta_light,
        };

        let mut sum = 0.0f32;
        let mut ratio = 1.0f32;
        let mut here = cam(t - 1);
        for i in (1..t).rev() {
            let before = cam(i - 1);
            ratio *= remap0(here.rev) / remap0(here.fwd);
            if !here.delta && !before.delta && (i > 1 || self.light_tracing) {
                sum += ratio * ratio;
            }
            here = before;
        }
        ratio = 1.0;
        for i in (0..s).rev() {
            let here = lig(i);
            ratio *= remap0(here.rev) / remap0(here.fwd);
            let delta_before = if i > 0 { lig(i - 1).delta } else { light0_delta };
            if !here.delta && !delta_before {
                sum += ratio * ratio;
            }
        }
        let w = 1.0 / (1.0 + sum);
        if w.is_finite() { w } else { 0.0 }
    }
}

/// Per-sample state shared by the walks and the connections.
struct Context<'c, 'v> {
    view: &'c SceneView<'v>,
    settings: &'c PathSettings,
    /// Vertices a camera subpath may hold (the eye included).
    camera_vertices: usize,
    light_tracing: bool,
}

impl Integrator for Bdpt {
    fn name(&self) -> &'static str {
        "bdpt"
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
        let (mut camera, mut light) = (Vec::new(), Vec::new());
        let mut splats = Vec::new();
        let cx = context(view, settings, false);
        sample_radiance(&cx, ray, wl, sampler, counters, &mut camera, &mut light, &mut splats)
    }

    fn splats(&self) -> bool {
        true
    }

    fn radiance_block_splatting<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        settings: &PathSettings,
        block: &mut [CameraSample<N, S>],
        counters: &mut PathCounters,
        splats: &mut Vec<Splat>,
    ) {
        let cx = context(view, settings, view.film().is_some());
        // The subpaths' storage, reused across the block.
        let mut camera = Vec::with_capacity(16);
        let mut light = Vec::with_capacity(16);
        for s in block {
            s.radiance =
                sample_radiance(&cx, s.ray, &mut s.wl, &mut s.sampler, counters, &mut camera, &mut light, splats);
        }
    }
}

fn context<'c, 'v>(view: &'c SceneView<'v>, settings: &'c PathSettings, light_tracing: bool) -> Context<'c, 'v> {
    let camera_vertices = if settings.max_depth > 0 {
        (settings.max_depth as usize + 2).min(BDPT_MAX_VERTICES)
    } else {
        BDPT_MAX_VERTICES
    };
    Context { view, settings, camera_vertices, light_tracing }
}

/// One camera sample's estimate (splats pushed onto `splats`).
#[allow(clippy::too_many_arguments)]
fn sample_radiance<'v, const N: usize, S: Sampler>(
    cx: &Context<'_, 'v>,
    ray: Ray,
    wl: &mut SampledWavelengths<N>,
    sampler: &mut S,
    counters: &mut PathCounters,
    camera: &mut Vec<Vertex<'v, N>>,
    light: &mut Vec<Vertex<'v, N>>,
    splats: &mut Vec<Splat>,
) -> SampledSpectrum<N> {
    let view = cx.view;
    // Both subpaths must share their wavelengths: where glass disperses, the sample
    // follows one of them (weighted to stay unbiased), as the Whitted integrator does.
    if view.has_dispersion() && !wl.is_rgb() && !wl.is_collapsed() {
        let k = ((sampler.next_1d() * N as f32) as usize).min(N - 1);
        wl.collapse_to(k);
    }
    let wl = &*wl;
    camera.clear();
    light.clear();
    let mut l = SampledSpectrum::zero();

    // The camera subpath, and what its escape sees of the lights at infinity.
    camera.push(Vertex::camera(ray.origin));
    let escape = walk(
        cx,
        ray,
        SampledSpectrum::one(),
        camera_pdf(view, ray.dir),
        Transport::Radiance,
        wl,
        sampler,
        counters,
        camera,
        cx.camera_vertices,
    );
    if let Some(e) = escape {
        l += e.beta * escaped(view, e, wl);
    }
    // The light subpath (none for a light at infinity).
    let light_vertices = cx.camera_vertices - 1;
    if let Some((start, beta, pdf_dir)) = start_light_path(view, wl, sampler, light) {
        walk(cx, start, beta, pdf_dir, Transport::Importance, wl, sampler, counters, light, light_vertices);
    }

    let max_depth = cx.settings.max_depth as usize;
    // s = 1 draws its own light sample: it runs even where the light subpath is empty.
    for t in 1..=camera.len() {
        for s in 0..=light.len().max(1) {
            let depth = (s + t) as isize - 2;
            if (s == 1 && t == 1) || depth < 0 || (max_depth > 0 && depth as usize > max_depth) {
                continue;
            }
            if t == 1 {
                if cx.light_tracing && s >= 2 {
                    splat_to_eye(cx, light, s, wl, counters, splats, camera);
                }
                continue;
            }
            l += match s {
                0 => hit_light(cx, camera, t, wl),
                1 => next_event(cx, camera, t, wl, sampler, counters),
                _ => connect(cx, light, camera, s, t, wl, counters),
            };
        }
    }
    l
}

/// Where a camera subpath left the scene: the throughput of its last ray, its direction,
/// and the density with which the BSDF sampled it (`None`: the camera ray, or a delta
/// lobe, which light sampling cannot reproduce).
#[derive(Clone, Copy)]
struct Escape<const N: usize> {
    beta: SampledSpectrum<N>,
    dir: Vec3,
    bsdf_pdf: Option<f32>,
}

/// The environment and sun disks an escaping camera path sees, weighted against
/// next-event estimation of them by the power heuristic (as the path tracer does).
fn escaped<const N: usize>(view: &SceneView, e: Escape<N>, wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
    let mut l = SampledSpectrum::zero();
    if let Some(env) = &view.scene.environment {
        let w = e.bsdf_pdf.map_or(1.0, |p| power_heuristic(p, view.lights.environment_pdf(e.dir)));
        l += env.radiance_from(e.dir, wl) * w;
    }
    if !view.lights.suns().is_empty() {
        l += view.suns_seen(e.dir, wl, e.bsdf_pdf);
    }
    l
}

/// Picks a light by power and a point on it, as next-event estimation does: the light
/// subpath's first vertex, the ray it emits along, the throughput Le·cos/(p_pos·p_dir)
/// and the emission's solid-angle density. `None` for a light at infinity.
fn start_light_path<'v, const N: usize, S: Sampler>(
    view: &SceneView<'v>,
    wl: &SampledWavelengths<N>,
    sampler: &mut S,
    light: &mut Vec<Vertex<'v, N>>,
) -> Option<(Ray, SampledSpectrum<N>, f32)> {
    let ls = view.lights.sample(view.scene, sampler.next_2d());
    let u = sampler.next_2d();
    let ls = ls?;
    let vertex = light_vertex(view, &ls, wl)?;
    // (direction, its density, what the light sends along it: Le·cos θ, or I·falloff)
    let (dir, pdf_dir, emitted) = match ls.source {
        LightSource::Primitive(_) => {
            let dir = Frame::from_normal(ls.normal).to_world(cosine_hemisphere(u));
            let cos = dir.dot(ls.normal);
            (dir, cos * FRAC_1_PI, vertex.beta * (ls.pdf * cos))
        }
        LightSource::Punctual(k) => {
            let light_def = &view.scene.punctual_lights[k as usize];
            let (dir, pdf) = match spot_cone(light_def) {
                None => (uniform_sphere(u), UNIFORM_SPHERE_PDF),
                Some((axis, cos_outer)) => {
                    let cos = 1.0 - u.x * (1.0 - cos_outer);
                    let sin = (1.0 - cos * cos).max(0.0).sqrt();
                    let (sp, cp) = (TAU * u.y).sin_cos();
                    let (a, b) = axis.any_orthonormal_pair();
                    ((cos * axis + sin * (cp * a + sp * b)).normalize(), 1.0 / (TAU * (1.0 - cos_outer)))
                }
            };
            let falloff = match *light_def {
                PunctualLight::Spot { direction, cos_inner, cos_outer, .. } => {
                    PunctualLight::spot_falloff(dir.dot(direction), cos_inner, cos_outer)
                }
                _ => 1.0,
            };
            (dir, pdf, vertex.beta * (ls.pdf * falloff))
        }
        LightSource::Environment => return None,
    };
    if pdf_dir.is_nan() || pdf_dir <= 0.0 {
        return None;
    }
    let beta = emitted / (ls.pdf * pdf_dir);
    let origin = vertex.origin_towards(vertex.p + dir);
    light.push(vertex);
    Some((Ray::new(origin, dir), beta, pdf_dir))
}

/// A light sample as the first vertex of a light subpath (or the stand-in for one in
/// next-event estimation): its throughput Le/p (I/p for a point light) and densities.
/// `None` for lights at infinity and emitters that emit nothing here.
fn light_vertex<'v, const N: usize>(
    view: &SceneView<'v>,
    ls: &LightSample,
    wl: &SampledWavelengths<N>,
) -> Option<Vertex<'v, N>> {
    let (le, delta_light) = match ls.source {
        LightSource::Primitive(prim) => (view.material(prim).emission.as_ref()?.sample(wl), false),
        LightSource::Punctual(k) => match &view.scene.punctual_lights[k as usize] {
            PunctualLight::Point { intensity, .. } | PunctualLight::Spot { intensity, .. } => {
                (intensity.sample(wl), true)
            }
            PunctualLight::Directional { .. } => return None,
        },
        LightSource::Environment => return None,
    };
    if (ls.pdf.is_nan() || ls.pdf <= 0.0) || le.is_black() {
        return None;
    }
    Some(Vertex {
        kind: Kind::Light(ls.source),
        p: ls.point,
        n: ls.normal,
        surface: None,
        beta: le / ls.pdf,
        pdf_fwd: ls.pdf,
        pdf_rev: 0.0,
        delta: false,
        delta_light,
        origin_pdf: ls.pdf,
    })
}

/// Extends a subpath whose last vertex sent `ray` with throughput `beta` and solid-angle
/// density `pdf_dir`, by BSDF sampling and Russian roulette, up to `max_vertices`; for a
/// camera subpath, returns where it escaped the scene.
#[allow(clippy::too_many_arguments)]
fn walk<'v, const N: usize, S: Sampler>(
    cx: &Context<'_, 'v>,
    mut ray: Ray,
    mut beta: SampledSpectrum<N>,
    mut pdf_dir: f32,
    mode: Transport,
    wl: &SampledWavelengths<N>,
    sampler: &mut S,
    counters: &mut PathCounters,
    path: &mut Vec<Vertex<'v, N>>,
    max_vertices: usize,
) -> Option<Escape<N>> {
    let view = cx.view;
    let settings = cx.settings;
    let mut specular = true;
    // The absorbing material the last segment left its vertex into, if any.
    let mut inside: Option<&spectral::spectrum::Colour> = None;
    // A camera subpath's radiance compression so far, which Russian roulette undoes
    // (`survives_roulette`).
    let mut eta_scale = 1.0f32;
    loop {
        counters.rays += 1;
        let Some(hit) = view.intersect(&ray) else {
            let bsdf_pdf = (!specular).then_some(pdf_dir);
            return (mode == Transport::Radiance).then_some(Escape { beta, dir: ray.dir, bsdf_pdf });
        };
        let material = view.material(hit.prim);
        let it = view.interaction(&hit, material, settings.shading_normals);
        let wo_world = -ray.dir;
        let front = wo_world.dot(it.ng) > 0.0;
        if view.absorbing {
            beta *= segment_transmittance(material, front, hit.t, inside, wl);
        }
        let (ng, ns) = shading_normals(settings.shading_normals, it.ng, it.ns, wo_world, material.is_two_sided());
        let frame = Frame::from_normal_tangent(ns, it.tangent);
        let bsdf = material.bsdf_at(it.uv, wl);
        let prev = path.last().expect("a subpath starts with a vertex");
        let pdf_fwd = to_area(pdf_dir, prev.p, it.p, it.ng);
        // Camera paths that hit an emitter: the density with which light sampling finds
        // the point (0 for emitters it never samples: textured or unsampleable shapes).
        let origin_pdf = if mode == Transport::Radiance && front && material.emission.is_some() {
            let pmf = view.lights.prim_pmf(hit.prim);
            if pmf > 0.0 && it.area > 0.0 { pmf / it.area } else { 0.0 }
        } else {
            0.0
        };
        let p = it.p;
        let n = it.ng;
        let wo = frame.to_local(wo_world);
        path.push(Vertex {
            kind: Kind::Surface,
            p,
            n,
            surface: Some(SurfaceData { it, material, bsdf, frame, ng, wo_world }),
            beta,
            pdf_fwd,
            pdf_rev: 0.0,
            delta: false,
            delta_light: false,
            origin_pdf,
        });
        if path.len() >= max_vertices {
            // The depth asked for ends here; the cap (unbounded or deeper than it) cuts.
            if settings.max_depth == 0 || settings.max_depth as usize + 2 > BDPT_MAX_VERTICES {
                counters.truncated += 1;
            }
            return None;
        }
        let uc = sampler.next_1d();
        let u = sampler.next_2d();
        let k = path.len() - 1;
        let v = &path[k];
        let s = v.surface.as_ref().expect("just pushed a surface");
        let bs = s.bsdf.sample(wo, uc, u)?;
        if bs.pdf <= 0.0 || bs.f.is_black() {
            return None;
        }
        let wi_world = frame.to_world(bs.wi);
        if lobe_leaks(s.material, settings.shading_normals, s.it.ng, wo_world, wi_world, bs.flags) {
            return None;
        }
        specular = bs.flags.is_specular();
        let mut factor = bs.f * (bs.wi.z.abs() / bs.pdf);
        if mode == Transport::Importance {
            factor *= importance_factor(s, wo_world, wi_world, wo, bs.wi);
        } else {
            eta_scale *= compression(&s.bsdf, wo, bs.flags.contains(ScatterFlags::TRANSMISSION));
        }
        let (fwd, rev) = if specular { (0.0, 0.0) } else { (bs.pdf, s.bsdf.pdf(bs.wi, wo)) };
        let origin = s.it.spawn_origin(wi_world);
        if view.absorbing {
            inside = entered_medium(s.material, s.it.ng, wi_world);
        }
        path[k].delta = specular;
        let prev_p = path[k - 1].p;
        let prev_n = path[k - 1].n;
        path[k - 1].pdf_rev = to_area(rev, p, prev_p, prev_n);
        beta *= factor;
        pdf_dir = fwd;
        // Russian roulette, counted in bounces as the path tracer does.
        if k as u32 >= settings.rr_depth
            && !survives_roulette(&mut beta, eta_scale, settings.rr_scale, sampler.next_1d())
        {
            return None;
        }
        if beta.is_black() {
            return None;
        }
        ray = Ray::new(origin, wi_world);
    }
}

/// s = 0: the camera subpath's vertex t−1 lies on an emitter's front face.
fn hit_light<const N: usize>(
    cx: &Context,
    camera: &[Vertex<'_, N>],
    t: usize,
    wl: &SampledWavelengths<N>,
) -> SampledSpectrum<N> {
    let pt = &camera[t - 1];
    let Some(s) = &pt.surface else { return SampledSpectrum::zero() };
    if s.wo_world.dot(s.it.ng) <= 0.0 {
        return SampledSpectrum::zero();
    }
    let Some(le) = s.material.emission_at(s.it.uv, wl) else { return SampledSpectrum::zero() };
    // An emitter that light sampling never picks is found by this strategy alone.
    let w = if pt.origin_pdf > 0.0 {
        Strategy { light: &[], camera, sampled: None, s: 0, t, light_tracing: cx.light_tracing }.weight(cx.view)
    } else {
        1.0
    };
    pt.beta * le * w
}

/// s = 1: a fresh light sample connected to camera vertex t−1 (next-event estimation).
/// A light at infinity drawn here is weighted as the path tracer weighs it.
fn next_event<const N: usize, S: Sampler>(
    cx: &Context,
    camera: &[Vertex<'_, N>],
    t: usize,
    wl: &SampledWavelengths<N>,
    sampler: &mut S,
    counters: &mut PathCounters,
) -> SampledSpectrum<N> {
    let view = cx.view;
    let pt = &camera[t - 1];
    let u = sampler.next_2d();
    let Some(s) = pt.surface.as_ref().filter(|_| pt.connectible()) else { return SampledSpectrum::zero() };
    let Some(ls) = view.lights.sample(view.scene, u) else { return SampledSpectrum::zero() };
    let at = Shading {
        it: &s.it,
        material: s.material,
        ng: s.ng,
        wo_world: s.wo_world,
        frame: &s.frame,
        wo: s.frame.to_local(s.wo_world),
    };
    let at_infinity = match ls.source {
        LightSource::Environment => true,
        LightSource::Punctual(k) => matches!(view.scene.punctual_lights[k as usize], PunctualLight::Directional { .. }),
        LightSource::Primitive(_) => false,
    };
    if at_infinity {
        // The path tracer's estimate, weighted against escaping camera paths.
        return match light_contribution(view, &at, &s.bsdf, wl, Mis::Power, &ls, counters) {
            Some((f, le, k)) => pt.beta * f * le * k,
            None => SampledSpectrum::zero(),
        };
    }
    let Some(sampled) = light_vertex(view, &ls, wl) else { return SampledSpectrum::zero() };
    let Some((f, le, k)) = light_contribution(view, &at, &s.bsdf, wl, Mis::None, &ls, counters) else {
        return SampledSpectrum::zero();
    };
    let w =
        Strategy { light: &[], camera, sampled: Some(&sampled), s: 1, t, light_tracing: cx.light_tracing }.weight(view);
    pt.beta * f * le * (k * w)
}

/// Beer–Lambert along a connection that leaves vertex `v` along `dir` into the back of
/// an absorbing material (with the other end's test, the rule the walks use).
fn connection_transmittance<const N: usize>(
    v: &Vertex<'_, N>,
    dir: Vec3,
    dist: f32,
    wl: &SampledWavelengths<N>,
) -> Option<SampledSpectrum<N>> {
    let s = v.surface.as_ref()?;
    entered_medium(s.material, s.it.ng, dir).map(|alpha| beer_lambert(alpha, dist, wl))
}

/// Whether nothing blocks the segment between two vertices on the scene's surfaces (the
/// triangles on its hull cannot: [`SceneView::occluded_inside`]).
fn visible<const N: usize>(
    view: &SceneView,
    a: &Vertex<'_, N>,
    b: &Vertex<'_, N>,
    counters: &mut PathCounters,
) -> bool {
    let from = a.origin_towards(b.p);
    let to = b.origin_towards(a.p);
    counters.rays += 1;
    !view.occluded_inside(&Ray::segment(from, to - from, 0.0, SHADOW_T_MAX))
}

/// s, t ≥ 2: light vertex s−1 connected to camera vertex t−1.
fn connect<const N: usize>(
    cx: &Context,
    light: &[Vertex<'_, N>],
    camera: &[Vertex<'_, N>],
    s: usize,
    t: usize,
    wl: &SampledWavelengths<N>,
    counters: &mut PathCounters,
) -> SampledSpectrum<N> {
    let (qs, pt) = (&light[s - 1], &camera[t - 1]);
    let (Some(sq), Some(sp)) = (&qs.surface, &pt.surface) else { return SampledSpectrum::zero() };
    if !qs.connectible() || !pt.connectible() {
        return SampledSpectrum::zero();
    }
    let d = pt.p - qs.p;
    let dist2 = d.length_squared();
    if dist2.is_nan() || dist2 <= 0.0 {
        return SampledSpectrum::zero();
    }
    let dist = dist2.sqrt();
    let w = d / dist;
    let f_q = surface_f(sq, sq.wo_world, w, Transport::Importance);
    let f_p = surface_f(sp, sp.wo_world, -w, Transport::Radiance);
    let g = sq.frame.n.dot(w).abs() * sp.frame.n.dot(w).abs() / dist2;
    let mut c = qs.beta * f_q * f_p * pt.beta * g;
    if c.is_black() || !c.0.iter().all(|v| v.is_finite()) || !visible(cx.view, qs, pt, counters) {
        return SampledSpectrum::zero();
    }
    if let Some(tr) = connection_transmittance(qs, w, dist, wl).or_else(|| connection_transmittance(pt, -w, dist, wl)) {
        c *= tr;
    }
    let strategy = Strategy { light, camera, sampled: None, s, t, light_tracing: cx.light_tracing };
    c * strategy.weight(cx.view)
}

/// t = 1 (light tracing): light vertex s−1 connected to the eye and splatted onto the
/// pixel it is seen in.
fn splat_to_eye<const N: usize>(
    cx: &Context,
    light: &[Vertex<'_, N>],
    s: usize,
    wl: &SampledWavelengths<N>,
    counters: &mut PathCounters,
    splats: &mut Vec<Splat>,
    camera: &[Vertex<'_, N>],
) {
    let view = cx.view;
    let Some(film) = view.film() else { return };
    let qs = &light[s - 1];
    let Some(sq) = qs.surface.as_ref().filter(|_| qs.connectible()) else { return };
    let Some((x, y, c)) = eye_connection(view, film, camera[0].p, sq, qs.beta, wl, counters) else { return };
    let weight = Strategy { light, camera, sampled: None, s, t: 1, light_tracing: true }.weight(view);
    splats.push(Splat { x, y, rgb: wl.to_linear_srgb(&(c * weight)) });
}

/// Light tracing's connection (t = 1) of surface point `sq`, reached from the lights with
/// throughput `beta`, to the eye at `eye`: the pixel it is seen in and the light it adds
/// there (before any MIS weight) — the adjoint BSDF towards the eye, W(ω) over the
/// region's pixel count (the film divides by the light paths per pixel), the cosine and
/// distance, and Beer–Lambert where the way leaves into an absorbing medium; `None` where
/// it lands off the region, adds nothing, or something blocks the way.
pub(super) fn eye_connection<const N: usize>(
    view: &SceneView,
    film: &super::FilmView,
    eye: Vec3,
    sq: &SurfaceData<'_, N>,
    beta: SampledSpectrum<N>,
    wl: &SampledWavelengths<N>,
    counters: &mut PathCounters,
) -> Option<(u32, u32, SampledSpectrum<N>)> {
    let p = sq.it.p;
    let (x, y) = film.rays.film_position(p).and_then(|f| film.pixel(f))?;
    let d = eye - p;
    let dist2 = d.length_squared();
    if dist2.is_nan() || dist2 <= 0.0 {
        return None;
    }
    let dist = dist2.sqrt();
    let w = d / dist;
    let f = surface_f(sq, sq.wo_world, w, Transport::Importance);
    let mut c = beta * f * (sq.frame.n.dot(w).abs() * film.density(-w) / dist2);
    if c.is_black() || !c.0.iter().all(|v| v.is_finite()) {
        return None;
    }
    let from = sq.it.spawn_origin(d);
    counters.rays += 1;
    if view.occluded(&Ray::segment(from, eye - from, 0.0, SHADOW_T_MAX)) {
        return None;
    }
    if let Some(alpha) = entered_medium(sq.material, sq.it.ng, w) {
        c *= beer_lambert(alpha, dist, wl);
    }
    Some((x, y, c))
}
