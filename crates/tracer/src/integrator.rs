//! Light transport: the [`Integrator`] trait (radiance along camera rays over the shared
//! [`SceneView`]), [`DirectLighting`] and [`AmbientOcclusion`] (biased by design, as their
//! documentation states), and [`PathTracer`]: unidirectional path
//! tracing with next-event estimation and multiple importance sampling (Veach 1997,
//! ch. 9; the thesis's "explicit" and "implicit" paths, ch. 5), Russian roulette and
//! spectral transport at N sampled wavelengths.

use crate::camera::RayGenerator;
use crate::geometry::{Geometry, HitSurface, InstanceTransform, SceneHit};
use crate::lights::{LightSample, LightSource, Lights};
use crate::material::Material;
use crate::punctual::PunctualLight;
use crate::render::PixelRect;
use crate::sampler::Sampler;
use crate::scene::MeshRef;
use crate::scene::Scene;
use brdf::{Bsdf, Frame, ScatterFlags};
use bvh::Ray;
use glam::{Vec2, Vec3};
use shapes::offset::offset_ray_origin;

use spectral::{SampledSpectrum, SampledWavelengths};

pub use crate::film::Splat;
pub use crate::shading::{ShadingNormals, adapt_shading_normal, shading_normals};
pub use atlas::{
    Atlas, AtlasGi, AtlasSettings, AtlasStats, ChartProjection, GatherProblem, GatherTexel,
    SPECULAR_CHAIN as ATLAS_SPECULAR_CHAIN, SeamFix,
};
pub use bdpt::{BDPT_MAX_VERTICES, Bdpt};
pub use caustics::CausticPathTracer;
pub use simple::{AmbientOcclusion, DirectLighting};
pub use whitted::{WHITTED_DEFAULT_DEPTH, Whitted};

mod atlas;
mod bdpt;
mod caustics;
mod lanes;
mod simple;
mod whitted;

/// Integrator settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Maximum number of scattering events; 0 = unbounded (Russian roulette only).
    pub max_depth: u32,
    /// Russian roulette starts after this many bounces.
    pub rr_depth: u32,
    /// Russian roulette keeps a path with probability min(0.95, `rr_scale` × its
    /// throughput), the throughput times the η'² of its transmissions. 1 is Mitsuba 3's
    /// rule (pbrt-v4's but for the 0.95 cap), which treats a throughput of 1 as what a
    /// fresh camera path is worth; but a path that has bounced a few times in a lit
    /// interior still carries much of its pixel's light at a throughput near ρᵏ (ρ the
    /// surfaces' albedo), so that rule cuts most such paths and weighs the few kept
    /// 1/ρᵏ. The default, 2, reached a given relative error as soon or sooner on every
    /// scene measured, by up to 30 %: at `rr_depth` 3 the Cornell box, Sponza, glass and
    /// mirrors in boxes and spheres under a sky; at 5 the Cornell box and two scenes built
    /// on it (docs/figures.md). Unbiased for any value in (0, [`MAX_RR_SCALE`]].
    pub rr_scale: f32,
    /// Path extension (thesis ch. 9, tables 9.2–9.3): up to this many extra bounces beyond
    /// `max_depth` while the path keeps hitting purely specular surfaces (mirrors,
    /// glass), so that a depth limit does not blacken what is seen through glass.
    pub specular_extension: u32,
    /// How interpolated shading normals are reconciled with the geometric normal.
    pub shading_normals: ShadingNormals,
    /// The most non-specular (diffuse or glossy) scattering events a path may have; 0 =
    /// no such limit. Purely specular bounces (mirrors, glass) do not count: 2 is
    /// direct light plus one diffuse bounce of indirect light wherever the camera looks,
    /// also through glass — what the atlas integrator approximates.
    pub max_diffuse_depth: u32,
    /// Whether the path tracer may run its lanes kernel where a scene needs no more than
    /// diffuse triangles (`integrator::lanes`: 8 or 16 paths per vector instruction, the same
    /// image to the bit); false runs the general loop everywhere, to measure what the
    /// specialisation saves.
    pub lanes: bool,
    /// Whether the path tracer leaves out the paths of the form E D S⁺ L that end on a
    /// light it can sample (caustics seen on a diffuse surface): for an integrator that
    /// adds them back by light tracing. [`CausticPathTracer`] sets it on its own copy of
    /// the settings; set on the plain path tracer, the image lacks those caustics.
    pub leave_caustics: bool,
}

impl Default for PathSettings {
    fn default() -> Self {
        Self {
            max_depth: 0,
            rr_depth: 3,
            rr_scale: 2.0,
            specular_extension: 0,
            shading_normals: ShadingNormals::Adapted,
            max_diffuse_depth: 0,
            lanes: true,
            leave_caustics: false,
        }
    }
}

/// Counters a render reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathCounters {
    /// Rays traced (camera, extension and shadow).
    pub rays: u64,
    /// Paths cut short by a backend's hard bounce cap (never on the CPU).
    pub truncated: u64,
}

impl std::ops::AddAssign for PathCounters {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.truncated += o.truncated;
    }
}

/// One camera sample on its way through an integrator: its ray, its wavelengths, its own
/// sample stream (already advanced past the camera's draws), and the radiance found.
#[derive(Clone, Debug)]
pub struct CameraSample<const N: usize, S: Sampler> {
    /// The camera ray.
    pub ray: Ray,
    /// The sampled wavelengths (a dispersive surface may collapse them: convert the
    /// radiance with these, after the integrator has run).
    pub wl: SampledWavelengths<N>,
    /// The sample's stream of sample values.
    pub sampler: S,
    /// The estimate (zero until the integrator has run).
    pub radiance: SampledSpectrum<N>,
}

/// An estimator of the radiance arriving along camera rays: the seam between a backend,
/// which decides where and in what order samples are taken, and light transport.
///
/// Backends hand out blocks of camera samples ([`Integrator::radiance_block`]); the
/// default traces them one at a time with [`Integrator::radiance`]. A wavefront or SIMD
/// integrator overrides the block method to trace the block's rays together (bounce by
/// bounce, sorted, packeted); since every sample carries its own random stream, results
/// do not depend on how samples are blocked.
pub trait Integrator: Send + Sync + 'static {
    /// The name `--integrator` selects it by.
    fn name(&self) -> &'static str;

    /// Estimates the radiance arriving along `ray` at the sampled wavelengths, drawing
    /// sample values from `sampler`. A dispersive surface may collapse `wl` to one
    /// wavelength ([`SampledWavelengths::collapse_to`]): the caller converts the result
    /// with the `wl` it gets back.
    fn radiance<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        ray: Ray,
        wl: &mut SampledWavelengths<N>,
        settings: &PathSettings,
        sampler: &mut S,
        counters: &mut PathCounters,
    ) -> SampledSpectrum<N>;

    /// The integrator prepared for one scene, for integrators that precompute something
    /// per scene (the atlas): backends call it once when they prepare a scene and run
    /// what it returns (`None`: this one, unchanged — the default).
    fn for_scene(&self, view: &SceneView) -> crate::Result<Option<Self>>
    where
        Self: Sized,
    {
        let _ = view;
        Ok(None)
    }

    /// Fills in the radiance of every sample of `block`.
    fn radiance_block<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        settings: &PathSettings,
        block: &mut [CameraSample<N, S>],
        counters: &mut PathCounters,
    ) {
        radiance_each(self, view, settings, block, counters);
    }

    /// The specialised kernel the integrator runs `view`'s scene with `settings` in, if
    /// any, for reports (the path tracer's "lanes"); `None`: its general code.
    fn kernel(&self, view: &SceneView, settings: &PathSettings) -> Option<&'static str> {
        let _ = (view, settings);
        None
    }

    /// Whether the integrator also adds light to pixels other than its samples' own (it
    /// traces paths from the lights to the camera). A backend then runs
    /// [`Integrator::radiance_block_splatting`] with the film in view
    /// ([`SceneView::with_film`]), adds the splats to its [`crate::Film`] and counts one
    /// light path per camera sample; one that cannot refuses the integrator.
    fn splats(&self) -> bool {
        false
    }

    /// Whether its paths are lengthened by [`PathSettings::specular_extension`] (so that a
    /// backend's bounce cap counts it).
    fn extends_specular(&self) -> bool {
        false
    }

    /// Whether it honours [`PathSettings::max_diffuse_depth`] (a backend refuses the limit
    /// for an integrator that would ignore it).
    fn limits_diffuse_depth(&self) -> bool {
        false
    }

    /// Whether its next-event estimation takes the light tree's choice for the shading
    /// point ([`crate::lights::Lights::sample_at`]) where the scene's lights have one. The
    /// others choose by power; the CPU backend builds no tree for them and refuses
    /// [`crate::LightSampler::Tree`].
    fn chooses_lights_per_point(&self) -> bool {
        false
    }

    /// [`Integrator::radiance_block`], pushing contributions to other pixels onto
    /// `splats` (in linear sRGB, to be divided by the number of light paths traced over
    /// the image). The default splats nothing.
    fn radiance_block_splatting<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        settings: &PathSettings,
        block: &mut [CameraSample<N, S>],
        counters: &mut PathCounters,
        splats: &mut Vec<Splat>,
    ) {
        let _ = splats;
        self.radiance_block(view, settings, block, counters);
    }
}

/// [`Integrator::radiance_block`] one sample at a time (the default, and where a
/// specialised block method does not apply).
fn radiance_each<const N: usize, S: Sampler, I: Integrator + ?Sized>(
    integrator: &I,
    view: &SceneView,
    settings: &PathSettings,
    block: &mut [CameraSample<N, S>],
    counters: &mut PathCounters,
) {
    for s in block {
        s.radiance = integrator.radiance(view, s.ray, &mut s.wl, settings, &mut s.sampler, counters);
    }
}

/// The camera and the part of the image being rendered, for integrators that connect
/// paths to the camera.
#[derive(Clone, Copy, Debug)]
pub struct FilmView {
    /// The camera's rays for this image size.
    pub rays: RayGenerator,
    /// The pixels sampled in this pass (splats elsewhere are dropped).
    pub region: PixelRect,
}

impl FilmView {
    /// The pixel of the region that film position `f` lies in, if any.
    #[inline]
    pub fn pixel(&self, f: Vec2) -> Option<(u32, u32)> {
        if !(f.x >= 0.0 && f.y >= 0.0) {
            return None;
        }
        let (x, y) = (f.x as u32, f.y as u32);
        self.region.contains(x, y).then_some((x, y))
    }

    /// The solid-angle density of a camera ray towards `dir` with one sample per pixel of
    /// the region: the pixel's importance W(ω) over the region's pixel count (pbrt's
    /// film-normalised importance; light tracing's splats use the same).
    #[inline]
    pub fn density(&self, dir: Vec3) -> f32 {
        self.rays.pixels_per_steradian(dir) / self.region.pixel_count() as f32
    }
}

/// Unidirectional path tracing with next-event estimation and MIS (see the module
/// documentation): unbiased with an unbounded depth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathTracer;

/// Everything the integrator reads, prepared once per render.
pub struct SceneView<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its accelerators.
    pub geometry: &'a Geometry,
    /// Its emitters.
    pub lights: &'a Lights,
    /// Whether any material disperses (looked up once here, not per sample).
    dispersive: bool,
    /// Whether any material has cut-outs or transparency: rays then pass through
    /// surfaces where its alpha says so (looked up once; scenes without pay nothing).
    cutouts: bool,
    /// Whether any transmissive material absorbs inside (Beer–Lambert).
    absorbing: bool,
    /// The camera and image, where the backend gives them.
    film: Option<FilmView>,
    /// The path tracer's lanes tables for this scene, if it is one for them: found on the
    /// first block that asks, then kept for the view's life (a tile), not per block.
    lanes: std::sync::OnceLock<Option<lanes::LaneScene>>,
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
    /// Interpolated texture coordinates (zero where the mesh has none).
    uv: Vec2,
}

impl Interaction {
    /// The origin of a ray leaving the surface towards `dir`, moved off it on that side of
    /// the geometric normal (Wächter & Binder's offset).
    #[inline(always)]
    fn spawn_origin(&self, dir: Vec3) -> Vec3 {
        offset_ray_origin(self.p, if dir.dot(self.ng) > 0.0 { self.ng } else { -self.ng })
    }
}

impl<'a> SceneView<'a> {
    /// The view of a scene with its accelerators and emitters.
    pub fn new(scene: &'a Scene, geometry: &'a Geometry, lights: &'a Lights) -> Self {
        let dispersive = scene.materials.iter().any(|m| m.is_dispersive());
        let cutouts = scene.materials.iter().any(|m| m.alpha().is_some());
        let absorbing = scene.materials.iter().any(|m| !m.is_two_sided() && m.absorption().is_some());
        let lanes = std::sync::OnceLock::new();
        Self { scene, geometry, lights, dispersive, cutouts, absorbing, film: None, lanes }
    }

    /// This view with the camera and the image region being rendered (for integrators
    /// that trace paths to the camera).
    pub fn with_film(mut self, rays: RayGenerator, region: PixelRect) -> Self {
        self.film = Some(FilmView { rays, region });
        self
    }

    /// The lanes' tables where the path tracer runs this scene with `settings` in lanes.
    fn lane_scene(&self, settings: &PathSettings) -> Option<&lanes::LaneScene> {
        self.lanes.get_or_init(|| lanes::LaneScene::of(self)).as_ref().filter(|l| l.admits(settings))
    }

    /// The camera and image region, if the backend gave them.
    pub fn film(&self) -> Option<&FilmView> {
        self.film.as_ref()
    }

    /// Whether any of the scene's materials disperses light.
    #[inline]
    pub fn has_dispersion(&self) -> bool {
        self.dispersive
    }

    /// The environment's radiance from direction `dir` at the sampled wavelengths (zero
    /// without one).
    #[inline]
    pub fn environment_radiance<const N: usize>(&self, dir: Vec3, wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
        self.scene.environment.as_ref().map_or(SampledSpectrum::zero(), |e| e.radiance_from(dir, wl))
    }

    /// The radiance of the sun disks a ray escaping along `dir` sees; with the pdf of the
    /// BSDF sample that sent it, each is weighted by the power heuristic against the
    /// disk's light-sampling pdf (without, weight 1: a camera ray, or a specular bounce).
    #[cold]
    pub fn suns_seen<const N: usize>(
        &self,
        dir: Vec3,
        wl: &SampledWavelengths<N>,
        bsdf_pdf: Option<f32>,
    ) -> SampledSpectrum<N> {
        let mut l = SampledSpectrum::zero();
        for sun in self.lights.suns() {
            if dir.dot(sun.axis) >= sun.cos_radius {
                let le = self.scene.punctual_lights[sun.index as usize].colour().sample(wl) * sun.radiance_scale;
                l += le * bsdf_pdf.map_or(1.0, |p| power_heuristic(p, sun.pdf));
            }
        }
        l
    }

    /// What a ray that escapes along `dir` sees, unweighted: the environment and any sun
    /// disk (for integrators that do not sample lights by BSDF, at camera rays and
    /// specular bounces).
    #[inline]
    pub fn escaped_radiance<const N: usize>(&self, dir: Vec3, wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
        let env = self.environment_radiance(dir, wl);
        if self.lights.suns().is_empty() { env } else { env + self.suns_seen(dir, wl, None) }
    }

    /// The closest hit along `ray` (passing through cut-outs).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SceneHit> {
        let hit = self.geometry.intersect(&self.scene.shapes, ray);
        if self.cutouts { self.through_cutouts(ray, hit) } else { hit }
    }

    /// True if anything blocks `ray` (cut-outs and transparency let it pass).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if self.cutouts {
            let hit = self.geometry.intersect(&self.scene.shapes, ray);
            self.through_cutouts(ray, hit).is_some()
        } else {
            self.geometry.occluded(&self.scene.shapes, ray)
        }
    }

    /// [`SceneView::occluded`] for a segment between two points of the scene (a shading
    /// point and a point on an emitter or a point or spot light): the triangles on faces
    /// of the scene's convex hull cannot block it and are not tested
    /// ([`crate::geometry::Occluders`]).
    #[inline]
    pub fn occluded_inside(&self, ray: &Ray) -> bool {
        if self.cutouts { self.occluded(ray) } else { self.geometry.occluded_inside(&self.scene.shapes, ray) }
    }

    /// The first hit from `hit` on along `ray` that alpha does not let through: each hit
    /// on a material with alpha is tested at its texture coordinates, and the ray goes on
    /// past it where the surface is absent (a closest-hit query per layer: only scenes
    /// with cut-outs pay for it).
    #[cold]
    fn through_cutouts(&self, ray: &Ray, mut hit: Option<SceneHit>) -> Option<SceneHit> {
        // A bound on the layers: a ray grazing a stack of cut-out cards ends as blocked.
        for _ in 0..256 {
            let h = hit?;
            let Some(alpha) = self.material(h.prim).alpha() else { return Some(h) };
            let uv = self.uv_at(&h);
            if !alpha.passes(uv, || crate::texture::alpha_hash(ray.origin, ray.dir, h.prim)) {
                return Some(h);
            }
            hit = self.geometry.intersect(&self.scene.shapes, &Ray { t_min: h.t, ..*ray });
        }
        hit
    }

    /// Texture coordinates at a hit (zero without any).
    #[inline]
    fn uv_at(&self, hit: &SceneHit) -> Vec2 {
        match hit.surface {
            HitSurface::Triangle { u, v } => {
                let (mesh, tri, _) = self.triangle_source(hit.prim);
                if mesh.uvs.is_empty() {
                    return Vec2::ZERO;
                }
                let [t0, t1, t2] = mesh.triangles[tri as usize].map(|i| Vec2::from_array(mesh.uvs[i as usize]));
                (1.0 - u - v) * t0 + u * t1 + v * t2
            }
            _ => Vec2::ZERO,
        }
    }

    /// Texture coordinates at point `p` on triangle primitive `prim` (zero without any).
    fn uv_at_point(&self, prim: u32, p: Vec3) -> Vec2 {
        let (mesh, tri, xf) = self.triangle_source(prim);
        if mesh.uvs.is_empty() {
            return Vec2::ZERO;
        }
        let t = mesh.triangles[tri as usize];
        let [a, b, c] = t.map(|i| {
            let q = Vec3::from_array(mesh.positions[i as usize]);
            xf.map_or(q, |x| x.to_world.transform_point3(q))
        });
        let n = (b - a).cross(c - a);
        let n2 = n.length_squared();
        if n2 == 0.0 {
            return Vec2::from_array(mesh.uvs[t[0] as usize]);
        }
        let w1 = (p - a).cross(c - a).dot(n) / n2;
        let w2 = (b - a).cross(p - a).dot(n) / n2;
        let [t0, t1, t2] = t.map(|i| Vec2::from_array(mesh.uvs[i as usize]));
        (1.0 - w1 - w2) * t0 + w1 * t1 + w2 * t2
    }

    /// The arrays triangle primitive `prim` lives in, its index there, and the transform
    /// that places it (`None` for the scene's own triangles, already in world space).
    #[inline(always)]
    fn triangle_source(&self, prim: u32) -> (MeshRef<'_>, u32, Option<&InstanceTransform>) {
        let scene = self.scene;
        if prim < self.geometry.triangle_count() {
            return (scene.mesh(), prim, None);
        }
        self.instanced_source(prim)
    }

    #[cold]
    fn instanced_source(&self, prim: u32) -> (MeshRef<'_>, u32, Option<&InstanceTransform>) {
        let instanced = self.geometry.instances.as_ref().expect("an instanced primitive without instances");
        let (k, local) = instanced.locate(prim);
        let xf = &instanced.transforms[k];
        (self.scene.objects[self.scene.instances[k].object as usize].mesh(), local, Some(xf))
    }

    /// Surface data at `hit` on `material`, its shading normal bent by the material's
    /// normal or bump map.
    #[inline(always)]
    fn interaction(&self, hit: &SceneHit, material: &Material, shading: ShadingNormals) -> Interaction {
        let mut it = self.surface_at(hit, shading);
        if material.textures.is_some() {
            self.bend_normal(&mut it, hit, material, shading);
        }
        it
    }

    /// Bends `it`'s shading normal by the material's normal or bump map, if it has one
    /// (out of line: most hits have none).
    #[inline(never)]
    fn bend_normal(&self, it: &mut Interaction, hit: &SceneHit, material: &Material, shading: ShadingNormals) {
        if let Some(t) = &material.textures
            && (t.normal.is_some() || t.bump.is_some())
            && shading != ShadingNormals::Geometric
            && let HitSurface::Triangle { .. } = hit.surface
        {
            let (mesh, tri, xf) = self.triangle_source(hit.prim);
            let tri = mesh.triangles[tri as usize];
            let p = tri.map(|i| {
                let p = Vec3::from_array(mesh.positions[i as usize]);
                xf.map_or(p, |x| x.to_world.transform_point3(p))
            });
            let uv = tri.map(|i| mesh.uvs.get(i as usize).map_or(Vec2::ZERO, |t| Vec2::from_array(*t)));
            let (dpdu, dpdv) = crate::texture::triangle_uv_derivatives(p, uv);
            let n = t.bent_normal(it.uv, it.ns, dpdu, dpdv);
            // Kept on the geometric normal's side, as every shading normal is.
            it.ns = if n.dot(it.ng) < 0.0 { (n - 2.0 * n.dot(it.ng) * it.ng).normalize_or(it.ng) } else { n };
            if it.tangent != Vec3::ZERO || dpdu != Vec3::ZERO {
                it.tangent = dpdu;
            }
        }
    }

    fn surface_at(&self, hit: &SceneHit, shading: ShadingNormals) -> Interaction {
        let (u, v) = match hit.surface {
            HitSurface::Triangle { u, v } => (u, v),
            HitSurface::Shape(h) => {
                let shape = self.scene.shapes[(hit.prim - self.geometry.triangle_count()) as usize].shape.shape();
                return Interaction {
                    p: h.p,
                    ng: h.n,
                    ns: h.n,
                    tangent: Vec3::ZERO,
                    area: shape.area(),
                    uv: Vec2::ZERO,
                };
            }
        };
        let (mesh, tri, xf) = self.triangle_source(hit.prim);
        let tri = mesh.triangles[tri as usize];
        let [mut v0, mut v1, mut v2] = tri.map(|i| Vec3::from_array(mesh.positions[i as usize]));
        if let Some(x) = xf {
            [v0, v1, v2] = [v0, v1, v2].map(|p| x.to_world.transform_point3(p));
        }
        let b0 = 1.0 - u - v;
        let p = b0 * v0 + u * v1 + v * v2;
        let cross = (v1 - v0).cross(v2 - v0);
        let area = 0.5 * cross.length();
        // A mirroring placement reverses the world winding: the object's front stays front.
        let ng = cross / (2.0 * area) * xf.map_or(1.0, |x| x.orientation);
        let mut ns = ng;
        if !mesh.normals.is_empty() && shading != ShadingNormals::Geometric {
            let [n0, n1, n2] = tri.map(|i| Vec3::from_array(mesh.normals[i as usize]));
            let mut n = b0 * n0 + u * n1 + v * n2;
            if let Some(x) = xf {
                n = Vec3::from(x.normal * glam::Vec3A::from(n));
            }
            if n.length_squared() > 1e-12 {
                let n = n.normalize();
                ns = if n.dot(ng) < 0.0 { -n } else { n };
            }
        }
        let tangent = if mesh.tangents.is_empty() {
            Vec3::ZERO
        } else {
            let [t0, t1, t2] = tri.map(|i| Vec3::from_array(mesh.tangents[i as usize]));
            let t = b0 * t0 + u * t1 + v * t2;
            xf.map_or(t, |x| x.to_world.transform_vector3(t))
        };
        let uv = if mesh.uvs.is_empty() {
            Vec2::ZERO
        } else {
            let [t0, t1, t2] = tri.map(|i| Vec2::from_array(mesh.uvs[i as usize]));
            b0 * t0 + u * t1 + v * t2
        };
        Interaction { p, ng, ns, tangent, area, uv }
    }

    #[inline]
    fn material(&self, prim: u32) -> &'a Material {
        &self.scene.materials[self.material_id(prim) as usize]
    }

    /// The index of `prim`'s material in the scene's list.
    #[inline(always)]
    fn material_id(&self, prim: u32) -> u32 {
        let scene = self.scene;
        match scene.material_ids.get(prim as usize) {
            Some(&m) => m,
            None => match scene.shapes.get(prim as usize - scene.triangles.len()) {
                Some(s) => s.material,
                None => self.instanced_material(prim),
            },
        }
    }

    #[cold]
    fn instanced_material(&self, prim: u32) -> u32 {
        let instanced = self.geometry.instances.as_ref().expect("an instanced primitive without instances");
        let (k, local) = instanced.locate(prim);
        let inst = &self.scene.instances[k];
        inst.material_of(&self.scene.objects[inst.object as usize], local as usize)
    }
}

/// η'² (η' the index on ωi's side over ωo's, +z the outside of index 1) if `transmits`,
/// else 1: the factor by which a transmission sampled from `wo` (local) compressed radiance
/// (Veach 1997 §5.2), which Russian roulette and light subpaths undo.
#[inline]
pub(crate) fn compression<const N: usize>(bsdf: &impl Bsdf<N>, wo: Vec3, transmits: bool) -> f32 {
    if !transmits {
        return 1.0;
    }
    let eta = bsdf.eta();
    let etap = if wo.z > 0.0 { eta } else { 1.0 / eta };
    etap * etap
}

/// The smallest probability with which Russian roulette ends a path (so that paths of
/// bright throughput end too).
pub const RR_MIN_TERMINATION: f32 = 0.05;

/// Russian roulette (Arvo & Kirk 1990) with uniform sample `u`: false if the path ends, else
/// true with `beta` divided by its survival probability. The path is judged by the light it
/// carries, `beta` times `eta_scale` (the product of η'² over its transmissions, see
/// [`compression`]), as pbrt-v4's `etaScale` and Mitsuba 3's η² do: inside glass of index
/// 1.5 `beta` alone is 0.44 of that light, and judged by it, paths through glass ended at
/// least 56 % of the time per bounce. `scale` multiplies the survival probability before it is
/// capped ([`PathSettings::rr_scale`]).
#[inline]
pub(crate) fn survives_roulette<const N: usize>(
    beta: &mut SampledSpectrum<N>,
    eta_scale: f32,
    scale: f32,
    u: f32,
) -> bool {
    let q = (1.0 - beta.max_component() * eta_scale * scale).max(RR_MIN_TERMINATION);
    if u < q {
        return false;
    }
    *beta /= 1.0 - q;
    true
}

/// The end of a shadow segment towards a point on a light, as a fraction of the
/// distance: short of the light, so that it does not hit the light itself.
pub const SHADOW_T_MAX: f32 = 1.0 - 1e-4;

/// The largest [`PathSettings::rr_scale`] accepted, a sanity bound: a larger scale only
/// delays the roulette's onset (each factor of 10 by ln 10 / ln(0.95/ρ) bounces, about 8
/// in the Cornell box) and gained nothing measured.
pub const MAX_RR_SCALE: f32 = 100.0;

/// Power heuristic with β = 2 (Veach 1997, eq. 9.13).
#[inline]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 == 0.0 { 0.0 } else { a2 / (a2 + b2) }
}

impl Integrator for PathTracer {
    fn name(&self) -> &'static str {
        "path"
    }

    fn chooses_lights_per_point(&self) -> bool {
        true
    }

    fn extends_specular(&self) -> bool {
        true
    }

    fn limits_diffuse_depth(&self) -> bool {
        true
    }

    #[inline]
    fn radiance<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        ray: Ray,
        wl: &mut SampledWavelengths<N>,
        settings: &PathSettings,
        sampler: &mut S,
        counters: &mut PathCounters,
    ) -> SampledSpectrum<N> {
        path_radiance(view, ray, wl, settings, sampler, counters)
    }

    fn kernel(&self, view: &SceneView, settings: &PathSettings) -> Option<&'static str> {
        Self::runs_in_lanes(view, settings).then_some("lanes")
    }

    /// In lanes where the scene allows it ([`PathSettings::lanes`]), else one path at a
    /// time.
    fn radiance_block<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        settings: &PathSettings,
        block: &mut [CameraSample<N, S>],
        counters: &mut PathCounters,
    ) {
        match view.lane_scene(settings) {
            Some(scene) => lanes::radiance_block(scene, view, settings, block, counters),
            None => radiance_each(self, view, settings, block, counters),
        }
    }
}

impl PathTracer {
    /// Whether the path tracer runs `view`'s scene with `settings` in its lanes kernel
    /// (8 or 16 paths per vector instruction where the scene needs no more than diffuse
    /// triangles; the same image as its general loop, bit for bit): what `spt render`
    /// reports, and what tests check before comparing the two.
    pub fn runs_in_lanes(view: &SceneView, settings: &PathSettings) -> bool {
        view.lane_scene(settings).is_some()
    }
}

/// A surface point ready for light sampling: the interaction, its material, the
/// geometric normal facing the way the shading normals were reconciled, the outgoing
/// direction in world and local coordinates, and the shading frame.
struct Shading<'a> {
    it: &'a Interaction,
    material: &'a Material,
    ng: Vec3,
    wo_world: Vec3,
    frame: &'a Frame,
    wo: Vec3,
}

/// How a light sample is weighted against BSDF sampling of the same light.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mis {
    /// The power heuristic (the path tracer, which also finds lights by BSDF sampling).
    Power,
    /// Weight 1 (an estimator that finds lights only by sampling them).
    None,
}

/// Next-event estimation (the thesis's "explicit path"): one point on a light (chosen by
/// the sample value `u`), one shadow ray; `Some((f, Le, k))` with the contribution
/// f · Le · k (k = |cos θᵢ| · w / pdf) to be multiplied by the path throughput, `None`
/// if the light is occluded or contributes nothing.
#[inline(always)]
fn next_event<const N: usize, B: Bsdf<N>>(
    view: &SceneView,
    at: &Shading,
    bsdf: &B,
    wl: &SampledWavelengths<N>,
    mis: Mis,
    u: Vec2,
    counters: &mut PathCounters,
) -> Option<(SampledSpectrum<N>, SampledSpectrum<N>, f32)> {
    // The geometric normal: the light tree's estimate takes |cos|, so either side's.
    let ls = view.lights.sample_at(view.scene, u, at.it.p, at.it.ng)?;
    light_contribution(view, at, bsdf, wl, mis, &ls, counters)
}

/// [`next_event`]'s estimate for a given light sample (its pdf may be 1 for a punctual
/// light taken deliberately rather than sampled, as the Whitted integrator does).
#[inline(always)]
fn light_contribution<const N: usize, B: Bsdf<N>>(
    view: &SceneView,
    at: &Shading,
    bsdf: &B,
    wl: &SampledWavelengths<N>,
    mis: Mis,
    ls: &LightSample,
    counters: &mut PathCounters,
) -> Option<(SampledSpectrum<N>, SampledSpectrum<N>, f32)> {
    let scene = view.scene;
    let it = at.it;
    // (direction, distance, pdf, radiance or its delta equivalent, whether a delta light)
    let (wi_world, dist, light_pdf, le, delta) = match ls.source {
        LightSource::Primitive(t) => {
            let d = ls.point - it.p;
            let dist2 = d.length_squared();
            let dist = dist2.sqrt();
            let wi = d / dist;
            let cos_l = -wi.dot(ls.normal);
            let emission = view.material(t).emission.as_ref();
            match emission {
                Some(e) if cos_l > 0.0 => (wi, dist, ls.pdf * dist2 / cos_l, e.sample(wl), false),
                _ => (wi, dist, 0.0, SampledSpectrum::zero(), false),
            }
        }
        LightSource::Environment => (ls.point, f32::INFINITY, ls.pdf, view.environment_radiance(ls.point, wl), false),
        // A delta light: I·falloff/d² (or E) stands for the radiance and the pdf is the
        // probability of choosing it, so f·Le·|cos θ|/pdf is the usual estimate.
        LightSource::Punctual(k) => {
            let light = &scene.punctual_lights[k as usize];
            let (wi, dist, le) = punctual_incidence(light, ls.point, it.p, wl)?;
            (wi, dist, ls.pdf, le, light.disk().is_none())
        }
    };
    let wi = at.frame.to_local(wi_world);
    // Reflection must stay on the geometric side it came from (no light leaks).
    let same_side = wi_world.dot(at.ng) * at.wo_world.dot(at.ng) > 0.0;
    // (Written so that a NaN pdf counts as unusable.)
    let usable = light_pdf > 0.0 && !le.is_black() && (same_side || !at.material.is_two_sided());
    if !usable {
        return None;
    }
    let f = bsdf.eval(at.wo, wi);
    if f.is_black() {
        return None;
    }
    // A shadow ray into the back of absorbing glass runs inside it (Beer–Lambert).
    let le = if view.absorbing { shadow_absorption(at, wi_world, dist, wl, le)? } else { le };
    let origin = it.spawn_origin(wi_world);
    let shadow = if dist.is_finite() {
        Ray::segment(origin, ls.point - origin, 0.0, SHADOW_T_MAX)
    } else {
        Ray::new(origin, wi_world)
    };
    counters.rays += 1;
    let blocked = if dist.is_finite() { view.occluded_inside(&shadow) } else { view.occluded(&shadow) };
    if blocked {
        return None;
    }
    let w = match mis {
        // A BSDF-sampled ray can never find a delta light: its sample takes all the weight.
        Mis::Power if !delta => power_heuristic(light_pdf, bsdf.pdf(at.wo, wi)),
        _ => 1.0,
    };
    Some((f, le, wi.z.abs() * w / light_pdf))
}

/// The light a punctual light sends to `p`: direction, distance (∞ for a directional
/// light) and I·falloff/d² (or E), the stand-in for radiance a delta light's estimate
/// uses; `None` for a point light at `p` itself. Out of line and cold: scenes with such
/// lights are rare, and keeping this out of the path tracer's loop kept its speed.
#[cold]
#[inline(never)]
fn punctual_incidence<const N: usize>(
    light: &PunctualLight,
    point: Vec3,
    p: Vec3,
    wl: &SampledWavelengths<N>,
) -> Option<(Vec3, f32, SampledSpectrum<N>)> {
    let (wi, dist, scale) = punctual_geometry(light, point, p)?;
    Some((wi, dist, light.colour().sample(wl) * scale))
}

/// [`punctual_incidence`] before the light's colour: direction, distance and the factor
/// on the colour (falloff/d² for a point or spot light, a sun disk's radiance scale for a
/// directional one), so that the lanes can evaluate the colour across paths and scale it
/// with the same bits.
#[inline(always)]
pub(crate) fn punctual_geometry(light: &PunctualLight, point: Vec3, p: Vec3) -> Option<(Vec3, f32, f32)> {
    let falloff_of = match light {
        // A sun disk's radiance, or a delta direction's irradiance.
        PunctualLight::Directional { .. } => return Some((point, f32::INFINITY, light.disk_radiance_scale())),
        PunctualLight::Point { .. } => None,
        PunctualLight::Spot { direction, cos_inner, cos_outer, .. } => Some((*direction, *cos_inner, *cos_outer)),
    };
    let d = point - p;
    let dist2 = d.length_squared();
    if !(dist2 > 0.0 && dist2.is_finite()) {
        return None; // a light on the surface itself: no direction
    }
    let dist = dist2.sqrt();
    let wi = d / dist;
    let falloff = falloff_of.map_or(1.0, |(axis, ci, co)| PunctualLight::spot_falloff(-wi.dot(axis), ci, co));
    Some((wi, dist, falloff / dist2))
}

/// The absorption inside the surface a ray leaving it along `dir` enters: a direction into
/// the back (against the front normal `ng`) of an absorbing transmissive material runs
/// inside it. With [`segment_transmittance`] (which also looks at where a segment *arrives*)
/// every segment inside an absorbing object is attenuated, whichever way it was traced and
/// whatever it ends on (an object inside the glass, a light). Callers test
/// [`SceneView`]'s `absorbing` first: scenes without absorbing glass skip it.
#[inline(always)]
fn entered_medium(material: &Material, ng: Vec3, dir: Vec3) -> Option<&spectral::spectrum::Colour> {
    if dir.dot(ng) >= 0.0 || material.is_two_sided() {
        return None;
    }
    material.absorption()
}

/// Beer–Lambert: what is left of light after `dist` inside a material of absorption
/// coefficient `alpha`, exp(−α·dist) per wavelength.
#[inline]
fn beer_lambert<const N: usize>(
    alpha: &spectral::spectrum::Colour,
    dist: f32,
    wl: &SampledWavelengths<N>,
) -> SampledSpectrum<N> {
    alpha.sample(wl).map(|a| (-a * dist).exp())
}

/// `le` after a shadow segment of length `dist` from `at` along `wi_world`: attenuated
/// where it runs inside absorbing glass, `None` where it would run inside to infinity.
/// Out of line: only scenes with absorbing glass call it.
#[cold]
#[inline(never)]
fn shadow_absorption<const N: usize>(
    at: &Shading,
    wi_world: Vec3,
    dist: f32,
    wl: &SampledWavelengths<N>,
    le: SampledSpectrum<N>,
) -> Option<SampledSpectrum<N>> {
    match entered_medium(at.material, at.it.ng, wi_world) {
        Some(_) if !dist.is_finite() => None,
        Some(alpha) => Some(le * beer_lambert(alpha, dist, wl)),
        None => Some(le),
    }
}

/// Beer–Lambert over a segment of length `t` that ended on `material`, reached on its
/// front or not: inside if it arrived at the back face of an absorbing transmissive
/// material (rays are unit length, so `t` is the distance), or if it left its previous
/// vertex into the absorbing material `inside` ([`entered_medium`]). Out of line: scenes
/// without absorbing glass never call it.
#[cold]
#[inline(never)]
fn segment_transmittance<const N: usize>(
    material: &Material,
    front: bool,
    t: f32,
    inside: Option<&spectral::spectrum::Colour>,
    wl: &SampledWavelengths<N>,
) -> SampledSpectrum<N> {
    let arrived_inside = (!front && !material.is_two_sided()).then(|| material.absorption()).flatten();
    arrived_inside.or(inside).map_or(SampledSpectrum::one(), |alpha| beer_lambert(alpha, t, wl))
}

/// Whether a sampled lobe disagrees with the geometry, the direction a path must not go:
/// a reflection must stay on ω_o's side of the surface and a transmission cross it
/// (otherwise the shading normal has sent the path through the surface the wrong way, a
/// light leak; face-forwarded normals are exempt, that being their documented flaw), and
/// a two-sided surface never transmits.
#[inline(always)]
fn lobe_leaks(
    material: &Material,
    shading: ShadingNormals,
    ng: Vec3,
    wo_world: Vec3,
    wi_world: Vec3,
    flags: ScatterFlags,
) -> bool {
    let crosses = wi_world.dot(ng) * wo_world.dot(ng) <= 0.0;
    (crosses != flags.contains(ScatterFlags::TRANSMISSION) && shading != ShadingNormals::FaceForward)
        || (material.is_two_sided() && crosses)
}

/// Counts a non-specular hit towards `max_diffuse_depth`; true if this hit is one more
/// than the limit allows (the path ends there, its emission counted). Out of line: only
/// renders with the limit pay for it.
#[cold]
#[inline(never)]
fn diffuse_limit_reached<const N: usize>(
    material: &Material,
    it: &Interaction,
    wl: &SampledWavelengths<N>,
    diffuse_bounces: &mut u32,
    settings: &PathSettings,
) -> bool {
    if !material.bsdf_at(it.uv, wl).flags().is_non_specular() {
        return false;
    }
    *diffuse_bounces += 1;
    *diffuse_bounces > settings.max_diffuse_depth
}

/// A path's state between its vertices: what [`path_radiance`] carries from one bounce to
/// the next, and what the lanes hand to [`path_vertex`] at a surface they do not vectorise.
pub(crate) struct PathState<'a, const N: usize> {
    /// The radiance found so far.
    pub(crate) l: SampledSpectrum<N>,
    /// The throughput.
    pub(crate) beta: SampledSpectrum<N>,
    /// The pdf of the previous BSDF sample, and whether it was a delta (no MIS then).
    pub(crate) prev_pdf: f32,
    pub(crate) prev_specular: bool,
    /// The previous vertex (the camera at first).
    pub(crate) prev_p: Vec3,
    /// Its geometric normal (zero at the camera), where a light tree chose its light.
    pub(crate) prev_n: Vec3,
    /// The bounces so far.
    pub(crate) bounce: u32,
    /// The product of η'² over the transmissions so far, which Russian roulette undoes
    /// (`survives_roulette`).
    pub(crate) eta_scale: f32,
    /// The purely specular bounces left past `max_depth`.
    pub(crate) extension_left: u32,
    /// The non-specular bounces so far (for `max_diffuse_depth`).
    pub(crate) diffuse_bounces: u32,
    /// The absorbing material the last segment left its vertex into, if any.
    pub(crate) inside: Option<&'a spectral::spectrum::Colour>,
    /// Where the path stands in the caustic form E D S⁺ L ([`Chain`]).
    pub(crate) chain: Chain,
}

/// How far a camera path has followed the form E D S⁺ L — its first vertex scattered by a
/// non-specular lobe, every vertex since by a specular one — which [`CausticPathTracer`]
/// finds by light tracing instead: a light it then hits is left out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Chain {
    /// Not of that form (or not yet: the camera ray).
    #[default]
    No,
    /// The first vertex scattered non-specularly.
    Diffuse,
    /// ... and one or more specular vertices followed.
    Caustic,
}

impl Chain {
    /// The chain after a vertex at `bounce` (0: the camera ray's hit) scattered by a
    /// specular lobe or not.
    #[inline(always)]
    pub(crate) fn next(self, bounce: u32, specular: bool) -> Self {
        match (bounce, specular, self) {
            (0, false, _) => Self::Diffuse,
            (0, true, _) => Self::No,
            (_, true, Self::Diffuse | Self::Caustic) => Self::Caustic,
            _ => Self::No,
        }
    }
}

impl<const N: usize> PathState<'_, N> {
    /// A path leaving the camera at `origin`.
    #[inline(always)]
    pub(crate) fn new(origin: Vec3, settings: &PathSettings) -> Self {
        Self {
            l: SampledSpectrum::zero(),
            beta: SampledSpectrum::one(),
            prev_pdf: 0.0,
            prev_specular: true,
            prev_p: origin,
            prev_n: Vec3::ZERO,
            bounce: 0,
            eta_scale: 1.0,
            extension_left: settings.specular_extension,
            diffuse_bounces: 0,
            inside: None,
            chain: Chain::No,
        }
    }
}

/// [`PathTracer`]'s estimate.
fn path_radiance<const N: usize, S: Sampler>(
    view: &SceneView,
    mut ray: Ray,
    wl: &mut SampledWavelengths<N>,
    settings: &PathSettings,
    sampler: &mut S,
    counters: &mut PathCounters,
) -> SampledSpectrum<N> {
    let scene = view.scene;
    let lights = view.lights;
    let mut st = PathState::new(ray.origin, settings);
    loop {
        counters.rays += 1;
        let Some(hit) = view.intersect(&ray) else {
            if let Some(env) = &scene.environment {
                let le = env.radiance_from(ray.dir, wl);
                let w =
                    if st.prev_specular { 1.0 } else { power_heuristic(st.prev_pdf, lights.environment_pdf(ray.dir)) };
                st.l += st.beta * le * w;
            }
            if !lights.suns().is_empty() {
                st.l += st.beta * view.suns_seen(ray.dir, wl, (!st.prev_specular).then_some(st.prev_pdf));
            }
            break;
        };
        match path_vertex(view, &hit, ray.dir, wl, settings, sampler, counters, &mut st) {
            Some(next) => ray = next,
            None => break,
        }
    }
    st.l
}

/// One vertex of [`PathTracer`]'s path, at `hit` of a ray along `dir`: the emission seen
/// there, next-event estimation, the BSDF sample, Russian roulette. The next ray, or
/// `None` where the path ends.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn path_vertex<'a, const N: usize, S: Sampler>(
    view: &SceneView<'a>,
    hit: &SceneHit,
    dir: Vec3,
    wl: &mut SampledWavelengths<N>,
    settings: &PathSettings,
    sampler: &mut S,
    counters: &mut PathCounters,
    st: &mut PathState<'a, N>,
) -> Option<Ray> {
    let lights = view.lights;
    let material = view.material(hit.prim);
    let it = view.interaction(hit, material, settings.shading_normals);
    let wo_world = -dir;
    let front = wo_world.dot(it.ng) > 0.0;

    if view.absorbing {
        st.beta *= segment_transmittance(material, front, hit.t, st.inside, wl);
    }

    // Emission seen by this path (one-sided: front face only).
    if front && let Some(le) = material.emission_at(it.uv, wl) {
        let w = if st.prev_specular {
            1.0
        } else {
            let dist2 = (it.p - st.prev_p).length_squared();
            let cos_l = wo_world.dot(it.ng);
            let light_pdf = lights.prim_pmf_at(hit.prim, st.prev_p, st.prev_n) * dist2 / (cos_l * it.area);
            power_heuristic(st.prev_pdf, light_pdf)
        };
        // A light that light tracing samples, reached along E D S⁺ L: that path's light is
        // added by the light tracer instead.
        let left = settings.leave_caustics && st.chain == Chain::Caustic && lights.prim_pmf(hit.prim) > 0.0;
        if !left {
            st.l += st.beta * le * w;
        }
    }

    if settings.max_depth > 0 && st.bounce >= settings.max_depth {
        // Past the limit, continue only through purely specular surfaces, while the
        // extension lasts.
        let flags = material.bsdf_at(it.uv, wl).flags();
        if st.extension_left == 0 || !flags.is_specular() || flags.is_non_specular() {
            return None;
        }
        st.extension_left -= 1;
    }
    if settings.max_diffuse_depth > 0 && diffuse_limit_reached(material, &it, wl, &mut st.diffuse_bounces, settings) {
        return None;
    }

    // Dispersion: from here on the path follows one wavelength (a random lane, moved
    // to lane 0, so that the BSDF refracts it with its own index).
    if material.is_dispersive() && !wl.is_rgb() && !wl.is_collapsed() {
        let k = ((sampler.next_1d() * N as f32) as usize).min(N - 1);
        wl.collapse_to(k);
        st.beta.0.swap(0, k);
        st.l.0.swap(0, k);
        for b in &mut st.beta.0[1..] {
            *b = 0.0;
        }
    }

    let (ng, ns) = shading_normals(settings.shading_normals, it.ng, it.ns, wo_world, material.is_two_sided());
    let frame = Frame::from_normal_tangent(ns, it.tangent);
    let wo = frame.to_local(wo_world);
    let bsdf = material.bsdf_at(it.uv, wl);
    let flags = bsdf.flags();

    // Next-event estimation: one shadow ray to a point on a light.
    if flags.is_non_specular() {
        let at = Shading { it: &it, material, ng, wo_world, frame: &frame, wo };
        if let Some((f, le, k)) = next_event(view, &at, &bsdf, wl, Mis::Power, sampler.next_2d(), counters) {
            st.l += st.beta * f * le * k;
        }
    }

    // Continue the path by sampling the BSDF.
    let uc = sampler.next_1d();
    let u = sampler.next_2d();
    let s = bsdf.sample(wo, uc, u)?;
    if s.pdf <= 0.0 || s.f.is_black() {
        return None;
    }
    let wi_world = frame.to_world(s.wi);
    if lobe_leaks(material, settings.shading_normals, it.ng, wo_world, wi_world, s.flags) {
        return None;
    }
    st.beta *= s.f * (s.wi.z.abs() / s.pdf);
    st.eta_scale *= compression(&bsdf, wo, s.flags.contains(ScatterFlags::TRANSMISSION));
    st.prev_pdf = s.pdf;
    st.prev_specular = s.flags.is_specular();
    if settings.leave_caustics {
        st.chain = st.chain.next(st.bounce, st.prev_specular);
    }
    st.prev_p = it.p;
    st.prev_n = it.ng;
    if view.absorbing {
        st.inside = entered_medium(material, it.ng, wi_world);
    }
    let ray = Ray::new(it.spawn_origin(wi_world), wi_world);
    st.bounce += 1;

    if st.bounce >= settings.rr_depth
        && !survives_roulette(&mut st.beta, st.eta_scale, settings.rr_scale, sampler.next_1d())
    {
        return None;
    }
    if st.beta.is_black() {
        return None;
    }
    Some(ray)
}

#[cfg(test)]
mod roulette_tests {
    use super::survives_roulette;
    use spectral::SampledSpectrum;

    /// Survival with probability min(0.95, scale × throughput × η'²), and the survivors'
    /// throughput divided by it: the expected throughput after the roulette is the one
    /// before, whatever the scale.
    #[test]
    fn the_roulettes_scale_raises_survival_and_keeps_the_expectation() {
        let beta = SampledSpectrum([0.1f32, 0.05, 0.02, 0.0]);
        for (scale, eta_scale, p) in [(1.0, 1.0, 0.1), (3.0, 1.0, 0.3), (3.0, 0.5, 0.15), (50.0, 1.0, 0.95)] {
            let p: f32 = p;
            // Just inside either side of the termination probability 1 − p.
            let mut b = beta;
            assert!(!survives_roulette(&mut b, eta_scale, scale, 1.0 - p - 1e-4), "scale {scale}: ends");
            let mut b = beta;
            assert!(survives_roulette(&mut b, eta_scale, scale, 1.0 - p + 1e-4), "scale {scale}: survives");
            assert!((b.0[0] - 0.1 / p).abs() < 1e-5 * b.0[0], "scale {scale}: survivor weighs 1/{p}: {b:?}");
            // The expectation over u (midpoints of a fine grid).
            let n = 100_000;
            let mean: f64 = (0..n)
                .map(|i| {
                    let mut b = beta;
                    if survives_roulette(&mut b, eta_scale, scale, (i as f32 + 0.5) / n as f32) {
                        b.0[1] as f64
                    } else {
                        0.0
                    }
                })
                .sum::<f64>()
                / n as f64;
            assert!((mean - 0.05).abs() < 1e-4, "scale {scale}: expected throughput {mean}, not 0.05");
        }
    }
}
