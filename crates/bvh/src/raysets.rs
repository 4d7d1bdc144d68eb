//! Benchmark ray sets for a triangle soup: coherent primary rays, incoherent diffuse
//! bounces and shadow segments, made without any camera or material of a scene — only
//! its bounding box and its triangles' geometric normals.
//!
//! Every set is deterministic for a seed (the workspace's PCG32, [`rng::Pcg32`]), so
//! timings of different accelerators trace exactly the same rays.

use crate::{Aabb, Accelerator, Ray, Triangle};
use glam::Vec3;
use rng::Pcg32;

/// The three kinds of benchmark rays for one scene and image size.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RaySets {
    /// One ray per pixel through the pixel centre, row by row from the top left, from a
    /// pinhole camera on the +z side of the bounding box looking down −z at its centre
    /// ([`RaySets::FOV_Y_DEG`] vertically, placed like the tracer's default framing so that the
    /// box's front face fills the frame). Normalised directions, t ∈ (0, ∞). Coherent.
    pub primary: Vec<Ray>,
    /// One ray per primary hit, in primary order: a cosine-weighted direction about the
    /// hit triangle's geometric normal (turned toward the side the primary ray came
    /// from), starting at the hit point offset along that normal by [`RaySets::OFFSET_SCALE`] ×
    /// scene size. Normalised directions, t ∈ (0, ∞). Incoherent, like diffuse bounces.
    pub diffuse: Vec<Ray>,
    /// One segment per primary hit, in primary order: from the same offset hit point to a
    /// pseudo-random point in the upper half (y ≥ centre) of the bounding box, as
    /// origin + t·(target − origin) with t ∈ (0, 1) — for [`Accelerator::occluded`], like
    /// next-event-estimation rays toward a ceiling light. Targets behind the surface are
    /// kept (those segments are blocked by the surface itself).
    pub shadow: Vec<Ray>,
}

impl RaySets {
    /// Vertical field of view of the primary-ray camera, in degrees.
    pub const FOV_Y_DEG: f32 = 40.0;

    /// Secondary-ray origins are moved off the surface by this fraction of the scene's
    /// size (the bounding box's largest edge), along the normal on the incoming side.
    pub const OFFSET_SCALE: f32 = 1e-4;

    /// Total number of rays in the three sets.
    pub fn len(&self) -> usize {
        self.primary.len() + self.diffuse.len() + self.shadow.len()
    }

    /// True if there are no rays at all.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A cosine-weighted direction about the unit vector `n` (Malley's method on an
/// orthonormal basis from Duff et al. 2017).
fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let s = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let z = (1.0 - u1).max(0.0).sqrt();
    (t * (r * phi.cos()) + s * (r * phi.sin()) + n * z).normalize()
}

/// The pinhole camera's primary rays over `bounds`, one per pixel centre.
fn primary_rays(bounds: &Aabb, camera: Option<(Vec3, Vec3)>, width: u32, height: u32) -> Vec<Ray> {
    let centre = bounds.centre();
    let extent = bounds.extent().max(Vec3::splat(1e-6));
    let tan_y = (0.5 * RaySets::FOV_Y_DEG.to_radians()).tan();
    let tan_x = tan_y * width as f32 / height as f32;
    let (eye, look_at) = camera.unwrap_or_else(|| {
        let dist = (0.5 * extent.y / tan_y).max(0.5 * extent.x / tan_x) * 1.025 + 0.5 * extent.z;
        (centre + Vec3::Z * dist, centre)
    });
    let forward = (look_at - eye).normalize_or(-Vec3::Z);
    let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    let up = right.cross(forward);
    let mut rays = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height {
        let sy = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * tan_y;
        for x in 0..width {
            let sx = (2.0 * (x as f32 + 0.5) / width as f32 - 1.0) * tan_x;
            rays.push(Ray::new(eye, (forward + sx * right + sy * up).normalize()));
        }
    }
    rays
}

/// The benchmark ray sets of a `width` × `height` image of `triangles`, whose primary hits
/// are found with `accel` (any accelerator built over the same triangles, in the same
/// order). Deterministic for a `seed`. An empty scene gives empty sets.
pub fn make_ray_sets(triangles: &[[Vec3; 3]], accel: &dyn Accelerator, width: u32, height: u32, seed: u64) -> RaySets {
    make_ray_sets_from(triangles, accel, None, width, height, seed)
}

/// [`make_ray_sets`] with the primary rays from `camera` = (eye, look-at point, +y up)
/// instead of the default framing — for scenes seen from inside, such as Sponza, whose
/// diffuse bounces would otherwise all leave the scene.
pub fn make_ray_sets_from(
    triangles: &[[Vec3; 3]],
    accel: &dyn Accelerator,
    camera: Option<(Vec3, Vec3)>,
    width: u32,
    height: u32,
    seed: u64,
) -> RaySets {
    let bounds = triangles.iter().fold(Aabb::EMPTY, |b, t| b.union(Triangle::bounds(t)));
    if bounds.is_empty() || width == 0 || height == 0 {
        return RaySets::default();
    }
    let primary = primary_rays(&bounds, camera, width, height);
    let offset = RaySets::OFFSET_SCALE * bounds.extent().max_element();
    let (upper_min, upper_max) = (Vec3::new(bounds.min.x, bounds.centre().y, bounds.min.z), bounds.max);
    let mut rng = Pcg32::seed_from_u64(seed);
    let mut diffuse = Vec::with_capacity(primary.len());
    let mut shadow = Vec::with_capacity(primary.len());
    for ray in &primary {
        let Some(hit) = accel.intersect(ray) else {
            continue;
        };
        let [v0, v1, v2] = triangles[hit.prim as usize];
        let mut n = (v1 - v0).cross(v2 - v0).normalize_or(-ray.dir);
        if n.dot(ray.dir) > 0.0 {
            n = -n;
        }
        let origin = ray.at(hit.t) + n * offset;
        let (u1, u2) = (rng.next_f32(), rng.next_f32());
        diffuse.push(Ray::new(origin, cosine_direction(n, u1, u2)));
        let u = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let target = upper_min + (upper_max - upper_min) * u;
        shadow.push(Ray::segment(origin, target - origin, 0.0, 1.0));
    }
    RaySets { primary, diffuse, shadow }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BruteForce;

    /// An open box (floor, ceiling, back and side walls) with a small block inside.
    fn room() -> Vec<[Vec3; 3]> {
        let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| [[a, b, c], [a, c, d]];
        let v = Vec3::new;
        let mut t = Vec::new();
        t.extend(quad(v(-1., 0., -1.), v(1., 0., -1.), v(1., 0., 1.), v(-1., 0., 1.)));
        t.extend(quad(v(-1., 2., -1.), v(-1., 2., 1.), v(1., 2., 1.), v(1., 2., -1.)));
        t.extend(quad(v(-1., 0., -1.), v(-1., 2., -1.), v(1., 2., -1.), v(1., 0., -1.)));
        t.extend(quad(v(-1., 0., -1.), v(-1., 0., 1.), v(-1., 2., 1.), v(-1., 2., -1.)));
        t.extend(quad(v(1., 0., -1.), v(1., 2., -1.), v(1., 2., 1.), v(1., 0., 1.)));
        t.extend(quad(v(-0.3, 0.6, 0.), v(0.3, 0.6, 0.), v(0.3, 0.6, 0.5), v(-0.3, 0.6, 0.5)));
        t
    }

    #[test]
    fn sets_are_filled_and_deterministic() {
        let tris = room();
        let accel = BruteForce::new(&tris).unwrap();
        let a = make_ray_sets(&tris, &accel, 32, 24, 7);
        assert_eq!(a.primary.len(), 32 * 24);
        // The front is open, but the walls fill most of the view.
        assert!(a.diffuse.len() > a.primary.len() / 2, "{} hits", a.diffuse.len());
        assert_eq!(a.diffuse.len(), a.shadow.len());
        assert_eq!(a, make_ray_sets(&tris, &accel, 32, 24, 7), "same seed, same rays");
        let b = make_ray_sets(&tris, &accel, 32, 24, 8);
        assert_eq!(a.primary, b.primary, "primary rays do not depend on the seed");
        assert_ne!(a.diffuse, b.diffuse, "another seed, other bounces");
        assert_ne!(a.shadow, b.shadow);
    }

    #[test]
    fn rays_leave_the_surface_on_the_incoming_side() {
        let tris = room();
        let accel = BruteForce::new(&tris).unwrap();
        let sets = make_ray_sets(&tris, &accel, 16, 16, 1);
        let bounds = accel.bounds();
        let (mut occluded, mut escaped) = (0, 0);
        for ((p, d), s) in
            sets.primary.iter().filter(|r| accel.intersect(r).is_some()).zip(&sets.diffuse).zip(&sets.shadow)
        {
            assert!((d.dir.length() - 1.0).abs() < 1e-4);
            // Cosine-weighted about a normal facing the camera: never back into the surface.
            let hit = accel.intersect(p).unwrap();
            let [v0, v1, v2] = tris[hit.prim as usize];
            let n = (v1 - v0).cross(v2 - v0);
            assert!(n.dot(d.dir) * n.dot(p.dir) <= 0.0, "bounce goes back through the surface");
            // The bounce does not re-hit its own triangle at the origin.
            if let Some(h) = accel.intersect(d) {
                assert!(h.t > 1e-5, "self-hit at t = {}", h.t);
            }
            let target = s.at(1.0);
            assert!(target.y >= bounds.centre().y - 1e-5 && target.y <= bounds.max.y + 1e-5);
            assert_eq!((s.t_min, s.t_max), (0.0, 1.0));
            if accel.occluded(s) { occluded += 1 } else { escaped += 1 }
        }
        assert!(occluded > 0 && escaped > 0, "{occluded} occluded, {escaped} not");
    }

    #[test]
    fn cosine_directions_are_cosine_distributed() {
        let n = Vec3::new(0.3, -0.8, 0.2).normalize();
        let mut rng = Pcg32::seed_from_u64(3);
        let k = 200_000;
        let mean_cos: f64 =
            (0..k).map(|_| cosine_direction(n, rng.next_f32(), rng.next_f32()).dot(n) as f64).sum::<f64>() / k as f64;
        // E[cos θ] = 2/3 for a cosine-weighted hemisphere.
        assert!((mean_cos - 2.0 / 3.0).abs() < 3e-3, "{mean_cos}");
    }

    #[test]
    fn empty_scene_gives_empty_sets() {
        let accel = BruteForce::new(&[]).unwrap();
        assert!(make_ray_sets(&[], &accel, 8, 8, 0).is_empty());
    }
}
