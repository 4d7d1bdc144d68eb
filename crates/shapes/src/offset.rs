//! Spawning rays from surfaces without hitting the surface again.

use glam::Vec3;

/// Below this |coordinate| the origin moves by a fixed [`OFFSET_FLOAT_SCALE`]·n instead of
/// by ulps (near zero, ulps are too small to escape the surface's rounding).
pub const OFFSET_ORIGIN: f32 = 1.0 / 32.0;
/// The fixed offset near the origin, per unit of normal.
pub const OFFSET_FLOAT_SCALE: f32 = 1.0 / 65536.0;
/// Ulps moved per unit of normal elsewhere.
pub const OFFSET_INT_SCALE: f32 = 256.0;

/// Moves a ray origin off a surface along the normal `n` (pointing to the side the ray
/// leaves on) by a few ulps of the position — Wächter & Binder, "A Fast and Robust Method
/// for Avoiding Self-Intersection", Ray Tracing Gems (2019), ch. 6.
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = OFFSET_ORIGIN;
    const FLOAT_SCALE: f32 = OFFSET_FLOAT_SCALE;
    const INT_SCALE: f32 = OFFSET_INT_SCALE;
    let shift = |p: f32, n: f32| -> f32 {
        let of = (INT_SCALE * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = f32::from_bits((if p < 0.0 { bits - of } else { bits + of }) as u32);
        if p.abs() < ORIGIN { p + FLOAT_SCALE * n } else { moved }
    };
    Vec3::new(shift(p.x, n.x), shift(p.y, n.y), shift(p.z, n.z))
}

/// The naive alternative: p + ε·n with a fixed ε (the thesis's approach), for the
/// self-intersection measurements. Too small at large coordinates (ε below the spacing of
/// floats there: the origin does not move), too large for small scenes (it jumps over
/// thin features).
#[inline]
pub fn offset_fixed_epsilon(p: Vec3, n: Vec3, epsilon: f32) -> Vec3 {
    p + epsilon * n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_to_the_normal_side_at_every_scale() {
        for scale in [1e-6f32, 1e-3, 1.0, 1e3, 1e6] {
            for n in [Vec3::X, -Vec3::Y, Vec3::new(0.6, -0.8, 0.0)] {
                let p = Vec3::new(0.3, -0.7, 0.5) * scale;
                let q = offset_ray_origin(p, n);
                assert!((q - p).dot(n) > 0.0, "scale {scale}, n {n:?}: {p:?} → {q:?}");
                // A few hundred ulps at most: never a visible jump.
                assert!((q - p).length() <= 1e-3 * scale.max(1.0), "scale {scale}: moved {}", (q - p).length());
            }
        }
        // A fixed ε does not move a point at 1e6 at all.
        let p = Vec3::splat(1e6);
        assert_eq!(offset_fixed_epsilon(p, Vec3::X, 1e-4), p);
    }
}
