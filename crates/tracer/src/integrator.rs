//! Unidirectional path tracing with next-event estimation and multiple importance
//! sampling (Veach 1997, ch. 9; the thesis's "explicit" and "implicit" paths, ch. 5),
//! Russian roulette and spectral transport at N sampled wavelengths.

use crate::geometry::{Geometry, HitSurface, SceneHit};
use crate::lights::Lights;
use crate::material::Material;
use crate::sampler::Pcg32;
use crate::scene::Scene;
use brdf::{Bsdf, Frame, ScatterFlags};
use bvh::Ray;
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
    /// How interpolated shading normals are reconciled with the geometric normal.
    pub shading_normals: ShadingNormals,
}

impl Default for PathSettings {
    fn default() -> Self {
        Self { max_depth: 0, rr_depth: 3, specular_extension: 0, shading_normals: ShadingNormals::Adapted }
    }
}

/// Which normal a BSDF sees — the lecture's question "which is the right normal?".
///
/// The geometric normal n_g (from the winding) decides on which side of the surface a
/// direction lies: whether a path arrives from outside or inside glass, and whether a
/// reflected direction stays above the surface. The interpolated shading normal n_s
/// only orients the BSDF's local frame. Near silhouettes of smooth meshes the two
/// disagree: the viewer may be above the surface but below the shading hemisphere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadingNormals {
    /// n_s, bent towards the outgoing direction where it disagrees with n_g about the side
    /// of ω_o ([`adapt_shading_normal`]); the side itself always comes from n_g, so
    /// glass knows when a path leaves it. No black silhouettes, exits kept.
    #[default]
    Adapted,
    /// The thesis's workaround: both normals turned to face the incoming path. Opaque
    /// surfaces look right, but every hit on glass becomes an entry — a path inside
    /// glass refracts with the inverted index and Beer–Lambert absorption never applies.
    FaceForward,
    /// Ignore shading normals (flat shading): exact, but faceted.
    Geometric,
}

impl ShadingNormals {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Adapted => "adapted",
            Self::FaceForward => "face-forward",
            Self::Geometric => "geometric",
        }
    }
}

/// The smallest |ω_o · n_s| an adapted shading normal keeps, so that the BSDF's frame is
/// never edge-on to the outgoing direction.
const MIN_SHADING_COSINE: f32 = 0.01;

/// Bends the unit shading normal `ns` so that the outgoing direction `wo` lies on the same
/// side of it as of the geometric normal `ng` (both unit, `ns` on `ng`'s side), with
/// |ω_o · n_s| ≥ a small margin: n_s' = normalize(n_s + k·s·ω_o), s = sign(ω_o · n_g),
/// with k the least that reaches the margin. It moves continuously with ω_o (no seams),
/// changes nothing where the normals agree, and stays on n_g's side of the plane. Where
/// ω_o is on the other side of n_s than of n_g, a BSDF in n_s's frame would see the
/// viewer below its surface (black silhouettes on smooth meshes) or, for glass, mistake
/// an exit for an entry.
#[inline]
pub fn adapt_shading_normal(ns: Vec3, ng: Vec3, wo: Vec3) -> Vec3 {
    let side = if wo.dot(ng) >= 0.0 { 1.0 } else { -1.0 };
    let a = side * wo.dot(ns);
    if a >= MIN_SHADING_COSINE {
        return ns;
    }
    let bent = ns + (MIN_SHADING_COSINE - a) * side * wo;
    bent.try_normalize().unwrap_or(ng)
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
    /// Its accelerators.
    pub geometry: &'a Geometry,
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
    /// The closest hit along `ray`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SceneHit> {
        self.geometry.intersect(&self.scene.shapes, ray)
    }

    /// True if anything blocks `ray`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.geometry.occluded(&self.scene.shapes, ray)
    }

    fn interaction(&self, hit: &SceneHit, shading: ShadingNormals) -> Interaction {
        let (u, v) = match hit.surface {
            HitSurface::Triangle { u, v } => (u, v),
            HitSurface::Shape(h) => {
                let shape = self.scene.shapes[(hit.prim - self.geometry.triangle_count()) as usize].shape.shape();
                return Interaction { p: h.p, ng: h.n, ns: h.n, tangent: Vec3::ZERO, area: shape.area() };
            }
        };
        let scene = self.scene;
        let tri = scene.triangles[hit.prim as usize];
        let [v0, v1, v2] = tri.map(|i| Vec3::from_array(scene.positions[i as usize]));
        let b0 = 1.0 - u - v;
        let p = b0 * v0 + u * v1 + v * v2;
        let cross = (v1 - v0).cross(v2 - v0);
        let area = 0.5 * cross.length();
        let ng = cross / (2.0 * area);
        let mut ns = ng;
        if !scene.normals.is_empty() && shading != ShadingNormals::Geometric {
            let [n0, n1, n2] = tri.map(|i| Vec3::from_array(scene.normals[i as usize]));
            let n = b0 * n0 + u * n1 + v * n2;
            if n.length_squared() > 1e-12 {
                let n = n.normalize();
                ns = if n.dot(ng) < 0.0 { -n } else { n };
            }
        }
        let tangent = if scene.tangents.is_empty() {
            Vec3::ZERO
        } else {
            let [t0, t1, t2] = tri.map(|i| Vec3::from_array(scene.tangents[i as usize]));
            b0 * t0 + u * t1 + v * t2
        };
        Interaction { p, ng, ns, tangent, area }
    }

    #[inline]
    fn material(&self, prim: u32) -> &Material {
        &self.scene.materials[self.scene.material_id(prim) as usize]
    }
}

pub use shapes::offset::offset_ray_origin;

/// The geometric and shading normals a BSDF at a hit sees, from the surface's `ng` and
/// `ns` (on the same side) and the outgoing direction `wo`: two-sided (opaque) BSDFs see
/// the side the path arrived on as their front; transmissive ones keep the geometric
/// orientation, which tells an entry from an exit. The shading normal is adapted per
/// [`ShadingNormals`].
#[inline]
pub fn shading_normals(mode: ShadingNormals, ng: Vec3, ns: Vec3, wo: Vec3, two_sided: bool) -> (Vec3, Vec3) {
    let front = wo.dot(ng) > 0.0;
    match mode {
        ShadingNormals::FaceForward if !front => (-ng, -ns),
        ShadingNormals::FaceForward => (ng, ns),
        _ => {
            let ns = adapt_shading_normal(ns, ng, wo);
            if two_sided && !front { (-ng, -ns) } else { (ng, ns) }
        }
    }
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
        let Some(hit) = view.intersect(&ray) else {
            if let Some(env) = &scene.environment {
                let le = env.radiance.sample(wl);
                let w = if prev_specular { 1.0 } else { power_heuristic(prev_pdf, lights.environment_pdf()) };
                l += beta * le * w;
            }
            break;
        };
        let it = view.interaction(&hit, settings.shading_normals);
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
                let light_pdf = lights.prim_pmf(hit.prim) * dist2 / (cos_l * it.area);
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

        let (ng, ns) = shading_normals(settings.shading_normals, it.ng, it.ns, wo_world, material.is_two_sided());
        let frame = Frame::from_normal_tangent(ns, it.tangent);
        let wo = frame.to_local(wo_world);
        let bsdf = material.bsdf(wl);
        let flags = bsdf.flags();

        // Next-event estimation: one shadow ray to a point on a light.
        if flags.is_non_specular()
            && let Some(ls) = lights.sample(scene, rng.next_f32(), rng.next_2d())
        {
            let (wi_world, dist, light_pdf, le) = match ls.prim {
                Some(t) => {
                    let d = ls.point - it.p;
                    let dist2 = d.length_squared();
                    let dist = dist2.sqrt();
                    let wi = d / dist;
                    let cos_l = -wi.dot(ls.normal);
                    let emission = view.material(t).emission.as_ref();
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
                    if !view.occluded(&shadow) {
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
        // The sampled lobe must agree with the geometry: a reflection stays on ω_o's side
        // of the surface, a transmission crosses it (otherwise the shading normal has
        // sent the path through the surface the wrong way: a light leak).
        let crosses = wi_world.dot(it.ng) * wo_world.dot(it.ng) <= 0.0;
        if crosses != s.flags.contains(ScatterFlags::TRANSMISSION)
            && settings.shading_normals != ShadingNormals::FaceForward
        {
            break;
        }
        if material.is_two_sided() && crosses {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use spectral::SampledWavelengths;

    fn unit(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3::new(x, y, z).normalize()
    }

    #[test]
    fn adapted_normal_keeps_agreeing_normals_and_fixes_disagreeing_ones() {
        let ng = Vec3::Z;
        let ns = unit(0.5, 0.0, 1.0);
        // Agreeing: unchanged.
        let wo = unit(0.0, 0.3, 1.0);
        assert_eq!(adapt_shading_normal(ns, ng, wo), ns);
        // A grazing viewer above the geometry but below the shading hemisphere.
        let wo = unit(-1.0, 0.0, 0.2);
        assert!(wo.dot(ng) > 0.0 && wo.dot(ns) < 0.0);
        let bent = adapt_shading_normal(ns, ng, wo);
        assert!(bent.dot(wo) > 0.004 && bent.dot(ng) > 0.0, "{bent:?}");
        assert!((bent.length() - 1.0).abs() < 1e-5);
        // From inside (below the geometry) but above the shading normal: bent below.
        let wo = unit(1.0, 0.0, -0.2);
        assert!(wo.dot(ng) < 0.0 && wo.dot(ns) > 0.0);
        let bent = adapt_shading_normal(ns, ng, wo);
        assert!(bent.dot(wo) < -0.004 && bent.dot(ng) > 0.0, "{bent:?}");
        // Continuous in ω_o: no seam where the bending starts.
        let mut prev = adapt_shading_normal(ns, ng, unit(-1.0, 0.0, 1.0));
        for k in 1..=400 {
            let z = 1.0 - k as f32 / 400.0 * 0.99;
            let n = adapt_shading_normal(ns, ng, unit(-1.0, 0.0, z));
            assert!((n - prev).length() < 0.02, "jump at z = {z}: {prev:?} → {n:?}");
            prev = n;
        }
    }

    /// Refracts `wo` through glass (index 1.5 outside → in) with the frame the integrator
    /// would build, and returns (sin θ_o, sin θ_t) about the geometric normal.
    fn refract_through(mode: ShadingNormals, ng: Vec3, ns: Vec3, wo: Vec3) -> Option<(f32, f32)> {
        let glass = Material::dielectric("glass", 1.5).unwrap();
        let wl = SampledWavelengths::<4>::fixed_bins(550.0, 0.0);
        let (_, ns) = shading_normals(mode, ng, ns, wo, glass.is_two_sided());
        let frame = Frame::from_normal_tangent(ns, Vec3::ZERO);
        let bsdf = glass.bsdf(&wl);
        (0..100).find_map(|k| {
            let s = bsdf.sample(frame.to_local(wo), k as f32 / 100.0, glam::Vec2::splat(0.5))?;
            if !s.flags.contains(ScatterFlags::TRANSMISSION) {
                return None;
            }
            let wi = frame.to_world(s.wi);
            let sin = |w: Vec3| w.cross(ns).length();
            Some((sin(wo), sin(wi)))
        })
    }

    #[test]
    fn glass_keeps_its_exits_with_adapted_normals_but_not_face_forward() {
        // A path inside glass reaching its surface: ω_o points back inside (below n_g).
        let ng = Vec3::Z;
        let ns = unit(0.1, 0.0, 1.0);
        let wo = unit(0.3, 0.2, -1.0);
        // Leaving the dense medium, the ray bends away from the normal: sin θ_t = 1.5 sin θ_o.
        let (so, st) = refract_through(ShadingNormals::Adapted, ng, ns, wo).expect("no TIR at this angle");
        assert!((st - 1.5 * so).abs() < 1e-4, "exit: sin θ_o {so}, sin θ_t {st}");
        // The thesis's workaround turns the normal to the viewer: the exit is taken for an
        // entry and bends towards the normal — wrong.
        let (so, st) = refract_through(ShadingNormals::FaceForward, ng, ns, wo).unwrap();
        assert!((st - so / 1.5).abs() < 1e-4, "face-forward: sin θ_o {so}, sin θ_t {st}");
        // Entering from outside, both agree: sin θ_t = sin θ_o / 1.5.
        let wo = unit(0.3, 0.2, 1.0);
        for mode in [ShadingNormals::Adapted, ShadingNormals::FaceForward] {
            let (so, st) = refract_through(mode, ng, ns, wo).unwrap();
            assert!((st - so / 1.5).abs() < 1e-4, "{mode:?} entry: {so} {st}");
        }
    }

    #[test]
    fn reflection_from_either_side_sees_the_viewer_above_its_surface() {
        // Opaque (two-sided) surfaces: from the front and from the back, and at a
        // silhouette where ω_o is below n_s, the BSDF's frame has ω_o above it.
        let ng = Vec3::Z;
        let ns = unit(0.6, 0.0, 1.0);
        for wo in [unit(0.2, 0.1, 1.0), unit(0.2, 0.1, -1.0), unit(-1.0, 0.0, 0.1), unit(1.0, 0.0, -0.1)] {
            let (g, n) = shading_normals(ShadingNormals::Adapted, ng, ns, wo, true);
            assert!(wo.dot(g) > 0.0, "geometric side for {wo:?}");
            assert!(wo.dot(n) > 0.0, "shading side for {wo:?}: {n:?}");
            assert!(n.dot(g) > 0.0);
        }
        // Without adaptation the silhouette case is below the shading hemisphere: black.
        let wo = unit(-1.0, 0.0, 0.1);
        let (_, n) = shading_normals(ShadingNormals::FaceForward, ng, ns, wo, true);
        assert!(wo.dot(n) < 0.0);
    }
}
