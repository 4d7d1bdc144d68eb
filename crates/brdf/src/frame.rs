//! Orthonormal shading frames.

use glam::Vec3;

/// An orthonormal basis (s, t, n): world ↔ local, with n the local z axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Tangent (local x).
    pub s: Vec3,
    /// Bitangent (local y).
    pub t: Vec3,
    /// Normal (local z).
    pub n: Vec3,
}

impl Frame {
    /// A frame around unit normal `n`, branchless and continuous except at one point
    /// (Duff et al. 2017, "Building an Orthonormal Basis, Revisited", JCGT 6(1)).
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            s: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// A frame around unit normal `n` whose x axis follows `tangent` projected into the
    /// tangent plane (Gram–Schmidt), so that anisotropic BSDFs are oriented by the
    /// surface; falls back to [`Frame::from_normal`] for a zero or normal-parallel tangent.
    #[inline]
    pub fn from_normal_tangent(n: Vec3, tangent: Vec3) -> Self {
        let s = tangent - n * n.dot(tangent);
        let len2 = s.length_squared();
        if len2.is_nan() || len2 <= 1e-8 * tangent.length_squared() {
            return Self::from_normal(n);
        }
        let s = s / len2.sqrt();
        Self { s, t: n.cross(s), n }
    }

    /// World direction → local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local coordinates → world direction.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Mirror reflection of `wo` about the local normal (0, 0, 1).
#[inline]
pub fn reflect_local(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// Reflection of `w` about the unit vector `h` (a microfacet normal): 2 (w·h) h − w.
#[inline]
pub fn reflect(w: Vec3, h: Vec3) -> Vec3 {
    2.0 * w.dot(h) * h - w
}

/// A local direction mirrored to the other side of the surface (z negated): models that
/// act alike on both sides evaluate the upper side only.
#[inline]
pub fn flip_z(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

/// For reflection models that act alike on both sides: (ωo, ωi) mirrored to the upper
/// hemisphere, or `None` where they lie on opposite sides (or on the horizon).
#[inline]
pub fn upper_pair(wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3)> {
    if wo.z * wi.z <= 0.0 {
        None
    } else if wo.z < 0.0 {
        Some((flip_z(wo), flip_z(wi)))
    } else {
        Some((wo, wi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_and_round_trip() {
        let normals = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.0, 0.0, -0.999_999),
            Vec3::new(1.0, 2.0, 3.0).normalize(),
            Vec3::new(-0.3, 0.1, -0.9).normalize(),
        ];
        for n in normals {
            let f = Frame::from_normal(n);
            for (a, b) in [(f.s, f.t), (f.t, f.n), (f.s, f.n)] {
                assert!(a.dot(b).abs() < 1e-5, "{n}");
            }
            for v in [f.s, f.t, f.n] {
                assert!((v.length() - 1.0).abs() < 1e-5, "{n}");
            }
            assert!(f.s.cross(f.t).dot(f.n) > 0.99, "right-handed for {n}");
            let w = Vec3::new(0.2, -0.5, 0.7);
            assert!((f.to_world(f.to_local(w)) - w).length() < 1e-5);
            let g = Frame::from_normal_tangent(n, Vec3::new(0.3, 0.9, -0.2));
            assert!(g.s.dot(n).abs() < 1e-5 && g.t.dot(n).abs() < 1e-5 && (g.s.length() - 1.0).abs() < 1e-5);
            assert!(g.s.cross(g.t).dot(g.n) > 0.99, "right-handed for {n}");
            assert_eq!(Frame::from_normal_tangent(n, n), Frame::from_normal(n));
        }
    }
}
