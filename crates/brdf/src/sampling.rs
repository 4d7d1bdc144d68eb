//! Warping uniform samples to directions, with their pdfs.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4};

/// Uniform point on the unit disk by Shirley & Chiu's concentric map (JGT 1997), which
/// keeps strata compact.
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) =
        if o.x.abs() > o.y.abs() { (o.x, FRAC_PI_4 * (o.y / o.x)) } else { (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y)) };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction on the +z hemisphere (Malley's method).
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// The solid-angle pdf of [`cosine_hemisphere`]: cos θ / π.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Cosine-weighted sampling on ωo's side of the surface (two-sided diffuse models):
/// (ωi, pdf), or `None` for ωo on the horizon.
#[inline]
pub fn cosine_hemisphere_two_sided(wo: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
    if wo.z == 0.0 {
        return None;
    }
    let mut wi = cosine_hemisphere(u);
    if wo.z < 0.0 {
        wi.z = -wi.z;
    }
    let pdf = cosine_hemisphere_pdf(wi.z.abs());
    (pdf > 0.0).then_some((wi, pdf))
}

/// The pdf of [`cosine_hemisphere_two_sided`]: cos θi / π on ωo's side, else 0.
#[inline]
pub fn cosine_hemisphere_two_sided_pdf(wo: Vec3, wi: Vec3) -> f32 {
    if wo.z * wi.z > 0.0 { cosine_hemisphere_pdf(wi.z.abs()) } else { 0.0 }
}

/// Uniform direction on the unit sphere.
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The solid-angle pdf of [`uniform_sphere`]: 1 / 4π.
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

/// Uniform barycentrics on a triangle (Heitz 2019, "A Low-Distortion Map Between
/// Triangle and Square"): returns (b0, b1), with b2 = 1 − b0 − b1.
#[inline]
pub fn uniform_triangle(u: Vec2) -> (f32, f32) {
    let (b0, b1);
    if u.x < u.y {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    (b0, b1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_disk_stays_in_disk_and_covers_it() {
        let n = 64;
        let mut area_hits = [0u32; 4];
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let p = concentric_disk(u);
                assert!(p.length() <= 1.0 + 1e-6);
                area_hits[(p.x > 0.0) as usize * 2 + (p.y > 0.0) as usize] += 1;
            }
        }
        // Equal area per quadrant.
        for h in area_hits {
            assert_eq!(h, (n * n / 4) as u32);
        }
    }

    #[test]
    fn triangle_barycentrics_are_valid_and_uniform() {
        let n = 200;
        let mut left = 0;
        for i in 0..n {
            for j in 0..n {
                let (b0, b1) = uniform_triangle(Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32));
                assert!(b0 >= 0.0 && b1 >= 0.0 && b0 + b1 <= 1.0 + 1e-6);
                if b0 > 0.5 {
                    left += 1;
                }
            }
        }
        // The region b0 > 1/2 is a quarter of the triangle.
        let frac = left as f32 / (n * n) as f32;
        assert!((frac - 0.25).abs() < 0.01, "{frac}");
    }
}
