//! Random triangle soups and rays shared by the accelerators' tests (deterministic).

use crate::builders::Prim;
use crate::{Aabb, Ray};
use glam::Vec3;
use rng::Pcg32;

/// `n` triangles of about `size` scattered over a cube of side `spread`.
pub(crate) fn soup(seed: u64, n: usize, spread: f32, size: f32) -> Vec<[Vec3; 3]> {
    let mut rng = Pcg32::seed_from_u64(seed);
    let mut point = move || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    (0..n)
        .map(|_| {
            let c = point() * spread;
            std::array::from_fn(|_| c + (point() - 0.5) * size)
        })
        .collect()
}

/// `n` rays from around a soup of `spread`, half of them finite segments.
pub(crate) fn rays(seed: u64, n: usize, spread: f32) -> Vec<Ray> {
    let pts = soup(seed ^ 0xABCD, n, spread * 1.4, spread);
    pts.iter()
        .map(|p| {
            let o = p[0] - Vec3::splat(0.2 * spread);
            let d = (p[1] - p[2]).normalize_or(Vec3::X);
            Ray::segment(o, d, 0.0, if p[0].x > 0.5 * spread { f32::INFINITY } else { spread })
        })
        .collect()
}

/// `n` boxes as the builders see them, corners in a cube of side `spread`, each up to 1
/// on a side.
pub(crate) fn prims(seed: u64, n: usize, spread: f32) -> Vec<Prim> {
    let mut rng = Pcg32::seed_from_u64(seed);
    let mut point = move || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    (0..n)
        .map(|_| {
            let c = point() * spread;
            Prim::new(Aabb { min: c, max: c + point() })
        })
        .collect()
}
