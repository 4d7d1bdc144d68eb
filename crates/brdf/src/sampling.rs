//! Warping uniform samples to directions, with their pdfs.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};

/// Uniform point on the unit disk by Shirley & Chiu's concentric map (JGT 1997), which
/// keeps strata compact.
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // θ = φ or π/2 − φ with φ = π/4 · (ratio of the coordinates) ∈ [−π/4, π/4], so that
    // (cos θ, sin θ) is (cos φ, sin φ) or (sin φ, cos φ): short series, no libm call.
    // Both cases through one path with selects: the case is a coin flip per sample, and
    // a mispredicted branch cost more than the series.
    let x_major = o.x.abs() > o.y.abs();
    let (r, minor) = if x_major { (o.x, o.y) } else { (o.y, o.x) };
    let (s, c) = sin_cos_quarter(FRAC_PI_4 * (minor / r));
    let (cos_theta, sin_theta) = if x_major { (c, s) } else { (s, c) };
    r * Vec2::new(cos_theta, sin_theta)
}

/// (sin φ, cos φ) for |φ| ≤ π/4 by their Taylor series to φ⁹ and φ¹⁰: the first omitted
/// terms are below 2·10⁻⁹ there, under half an ulp of the results. `sincosf` from libm
/// (a call, range reduction) was 3.5 % of a Cornell-box render, most of it from here.
#[inline]
pub fn sin_cos_quarter(phi: f32) -> (f32, f32) {
    let x2 = phi * phi;
    let s = phi * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let c =
        1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0)))));
    (s, c)
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
    fn quarter_sin_cos_is_within_an_ulp_of_f64() {
        let n = 100_000;
        let mut worst = 0.0f64;
        for i in 0..=n {
            let phi = -FRAC_PI_4 + std::f32::consts::FRAC_PI_2 * i as f32 / n as f32;
            let (s, c) = sin_cos_quarter(phi);
            let (s64, c64) = (phi as f64).sin_cos();
            worst = worst.max((s as f64 - s64).abs()).max((c as f64 - c64).abs());
        }
        // An ulp of values up to 1 is 1.2e-7 (6e-8 below ½).
        assert!(worst < 1.2e-7, "worst error {worst:e}");
    }

    #[test]
    fn concentric_disk_keeps_the_radius_and_angle_of_the_map() {
        // Shirley & Chiu: r = max(|a|, |b|) and θ = π/4 · b/a (or π/2 − π/4 · a/b).
        for (a, b) in [(0.5f32, 0.2f32), (-0.7, 0.1), (0.3, 0.9), (-0.2, -0.6), (1.0, -1.0 + 1e-3)] {
            let p = concentric_disk(Vec2::new((a + 1.0) / 2.0, (b + 1.0) / 2.0));
            let (r, theta) = if a.abs() > b.abs() {
                (a as f64, std::f64::consts::FRAC_PI_4 * (b / a) as f64)
            } else {
                (b as f64, std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b) as f64)
            };
            assert!((p.x as f64 - r * theta.cos()).abs() < 3e-7, "{a} {b}: {p}");
            assert!((p.y as f64 - r * theta.sin()).abs() < 3e-7, "{a} {b}: {p}");
        }
    }

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
