//! Ray–sphere intersection, three ways (lecture slides "Schnitt Strahl—Kugel"):
//!
//! * the **geometric** method with the slides' early exits (origin outside and looking
//!   away; closest approach farther than r), in two forms: the slides' literal one
//!   ([`Sphere::intersect_geometric_literal`]) and a robust one
//!   ([`Sphere::intersect_geometric`]) that computes the squared closest-approach distance
//!   as |L − t_ca·d̂|² instead of |L|² − t_ca² (Haines, Günther & Akenine-Möller,
//!   "Precision Improvements for Ray/Sphere Intersection", *Ray Tracing Gems* ch. 7,
//!   2019; pbrt-v4 §6.8.1);
//! * the **algebraic** method: the ray substituted into |p − c|² = r², a quadratic in t,
//!   solved naively or stably ([`Sphere::intersect_algebraic`]).
//!
//! [`reference_roots_f64`] gives double-precision reference roots for measuring how far
//! each single-precision method strays.

use crate::{Aabb, Ray, Shape, ShapeError, SurfaceHit};
use glam::{DVec3, Vec2, Vec3};
use std::f32::consts::PI;

/// Which ray–sphere algorithm [`Shape::intersect`] uses for a [`Sphere`].
///
/// The default is [`SphereMethod::Geometric`]: the slides call it the faster one (its
/// early exits reject rays pointing away without a square root), and in its robust form
/// it is also the most accurate of the three in single precision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SphereMethod {
    /// The geometric method with early exits and the robust closest-approach distance
    /// ([`Sphere::intersect_geometric`]).
    #[default]
    Geometric,
    /// The algebraic method with the textbook quadratic formula (−b ± √(b² − 4ac))/2a in
    /// single precision: loses the near root to cancellation and the discriminant to
    /// rounding for far origins. Kept for the stability measurements.
    AlgebraicNaive,
    /// The algebraic method with the cancellation-free root pair q/a, c/q and the
    /// discriminant of Haines et al. ([`Sphere::intersect_algebraic`] with `stable`).
    AlgebraicStable,
}

/// A sphere |p − centre| = radius, both faces hit, normal pointing outward.
///
/// Spheres are the classic analytic primitive ("so simple that every ray tracer has
/// them", lecture slides); here also the test bed for the numerical behaviour of the
/// geometric and algebraic intersection methods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub centre: Vec3,
    /// Radius, finite and > 0.
    pub radius: f32,
    /// The algorithm [`Shape::intersect`] uses.
    pub method: SphereMethod,
}

impl Sphere {
    /// A sphere, validated: the centre must be finite and the radius finite and > 0 (a
    /// NaN or zero radius would make every later formula silently produce NaN or divide
    /// by zero).
    pub fn new(centre: Vec3, radius: f32, method: SphereMethod) -> Result<Self, ShapeError> {
        if !centre.is_finite() {
            return Err(ShapeError::Invalid(format!("sphere centre {centre} is not finite")));
        }
        if !radius.is_finite() || radius <= 0.0 || !(radius * radius).is_finite() {
            return Err(ShapeError::Invalid(format!("sphere radius {radius} must be finite and > 0")));
        }
        Ok(Self { centre, radius, method })
    }

    /// The ray's direction normalised, with its length (to convert a distance t̂ along
    /// the unit direction back to the ray's parameter t = t̂ / |dir|). `None` for a zero,
    /// infinite or NaN direction.
    #[inline]
    fn unit_dir(ray: &Ray) -> Option<(Vec3, f32)> {
        let len = ray.dir.length();
        (len > 0.0 && len.is_finite()).then(|| (ray.dir / len, len))
    }

    /// The first of two candidate parameters (given along the unit direction, near one
    /// first) that lies in the ray's open interval (t_min, t_max).
    #[inline]
    fn first_in_range(ray: &Ray, len: f32, near: f32, far: f32) -> Option<f32> {
        [near, far].into_iter().map(|t| t / len).find(|&t| t > ray.t_min && t < ray.t_max)
    }

    /// The geometric method exactly as on the lecture slides, for comparison.
    ///
    /// With m = c − o, d̂ = dir/|dir| and b = m·d̂ (the slides' notation; t_ca elsewhere):
    /// exit if m² − r² ≥ 0 (origin outside) and b ≤ 0 (looking away); D = b² − m² + r²,
    /// exit if D < 0; the roots are b ∓ √D. D = b² − m² + r² subtracts two nearly equal
    /// large numbers when the origin is far from a small sphere (|m| ≫ r), so all of r²
    /// can be lost: the far-origin test measures that.
    ///
    /// The slides return the near root if the origin is outside by more than ε, else the
    /// far one; here both are tried in order against the ray's interval (t_min, t_max),
    /// which gives the slides' choice for t_min = 0 and also handles segments. The
    /// early exit is skipped when t_min < 0 (then roots behind the origin count).
    pub fn intersect_geometric_literal(&self, ray: &Ray) -> Option<f32> {
        let (d, len) = Self::unit_dir(ray)?;
        let m = self.centre - ray.origin;
        let m2 = m.dot(m);
        let r2 = self.radius * self.radius;
        let b = m.dot(d);
        if m2 - r2 >= 0.0 && b <= 0.0 && ray.t_min >= 0.0 {
            return None;
        }
        let disc = b * b - m2 + r2;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        Self::first_in_range(ray, len, b - s, b + s)
    }

    /// The geometric method with the slides' early exits, made robust (the default).
    ///
    /// L = c − o, t_ca = L·d̂; exit if the origin is outside (|L|² > r²) and t_ca < 0.
    /// The squared distance of closest approach is computed as d² = |L − t_ca·d̂|², the
    /// length of an actual vector, instead of |L|² − t_ca², which cancels
    /// catastrophically when |L| ≫ r (Haines et al., *Ray Tracing Gems* ch. 7, eq. 7.5;
    /// pbrt-v4 §6.8.1). Exit if d² > r²; t_hc² = r² − d² is formed as (r − |v|)(r + |v|)
    /// (pbrt-v4), which is accurate near tangency. The roots t_ca ∓ t_hc are taken in the
    /// cancellation-free form q = t_ca + sign(t_ca)·t_hc, roots q and (|L|² − r²)/q
    /// (Haines et al. eq. 7.4 / Press et al., *Numerical Recipes* §5.6), so the near root
    /// stays accurate when the origin is close to the surface. An origin inside gets the
    /// far root (the near one is negative).
    pub fn intersect_geometric(&self, ray: &Ray) -> Option<f32> {
        let (d, len) = Self::unit_dir(ray)?;
        let l = self.centre - ray.origin;
        let l2 = l.dot(l);
        let r = self.radius;
        let r2 = r * r;
        let t_ca = l.dot(d);
        if l2 > r2 && t_ca < 0.0 && ray.t_min >= 0.0 {
            return None;
        }
        let v = l - t_ca * d;
        let d2 = v.dot(v);
        if d2 > r2 {
            return None;
        }
        let vl = d2.sqrt();
        let t_hc = ((r - vl) * (r + vl)).max(0.0).sqrt();
        let c = l2 - r2;
        let (near, far) = stable_pair(t_ca, t_hc, c);
        Self::first_in_range(ray, len, near, far)
    }

    /// The algebraic method: with f = o − c, a = dir·dir, b = 2 dir·f, c' = f·f − r², solve
    /// a t² + b t + c' = 0 and return the nearest root in (t_min, t_max).
    ///
    /// * `stable == false`: the textbook (−b ± √(b² − 4ac'))/2a in f32. Cancels in
    ///   −b + √disc for the near root, and in b² − 4ac' for far origins.
    /// * `stable == true`: the roots as q/a and c'/q with q = −½(b + sign(b)√disc), free
    ///   of the first cancellation (*Numerical Recipes* §5.6). The second one cannot be
    ///   fixed by evaluating b² − 4ac' in f64, because the f32 coefficients themselves
    ///   have already lost the information (for |f| = 10⁴, r = 10⁻², f·f − r² rounds to
    ///   f·f); so the discriminant is formed by Lagrange's identity
    ///   b² − 4ac' = 4a(r² − |f − (b/2a)·dir|²), as recommended by Haines et al.
    ///   (*Ray Tracing Gems* ch. 7, eq. 7.5). The test `far_origin_accuracy` measures both.
    pub fn intersect_algebraic(&self, ray: &Ray, stable: bool) -> Option<f32> {
        let f = ray.origin - self.centre;
        let dir = ray.dir;
        let a = dir.dot(dir);
        let b = 2.0 * dir.dot(f);
        let r2 = self.radius * self.radius;
        let c = f.dot(f) - r2;
        if !(a > 0.0 && a.is_finite()) {
            return None;
        }
        let (t0, t1) = if stable {
            let v = f - (0.5 * b / a) * dir;
            let vl = v.length();
            let r = self.radius;
            let disc = 4.0 * a * ((r - vl) * (r + vl));
            stable_roots_from_disc(a, b, c, disc)?
        } else {
            quadratic_naive(a, b, c)?
        };
        [t0, t1].into_iter().find(|&t| t > ray.t_min && t < ray.t_max)
    }

    /// The parameter of the closest hit by the configured [`SphereMethod`].
    #[inline]
    fn intersect_t(&self, ray: &Ray) -> Option<f32> {
        match self.method {
            SphereMethod::Geometric => self.intersect_geometric(ray),
            SphereMethod::AlgebraicNaive => self.intersect_algebraic(ray, false),
            SphereMethod::AlgebraicStable => self.intersect_algebraic(ray, true),
        }
    }
}

/// For the roots m ∓ h of t² − 2mt + c = 0 (c = m² − h²): (near, far), each computed
/// without cancellation: q = m + sign(m)·h is a sum of like-signed terms, the other root
/// is c/q (Vieta).
#[inline]
fn stable_pair(m: f32, h: f32, c: f32) -> (f32, f32) {
    let q = if m >= 0.0 { m + h } else { m - h };
    if q == 0.0 {
        return (0.0, 0.0);
    }
    let other = c / q;
    if other < q { (other, q) } else { (q, other) }
}

/// Textbook quadratic formula in f32, roots ascending. Private stand-in for
/// `roots::quadratic_naive` (to be deduplicated once that module is in).
#[inline]
fn quadratic_naive(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let t0 = (-b - s) / (2.0 * a);
    let t1 = (-b + s) / (2.0 * a);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// Stable quadratic with the discriminant evaluated in f64 from the f32 coefficients:
/// q = −½(b + sign(b)√disc), roots q/a and c/q, ascending. Private stand-in for
/// `roots::quadratic_stable` (to be deduplicated); the sphere itself uses
/// [`stable_roots_from_disc`] with Haines et al.'s discriminant, this one is measured
/// against it in the tests.
#[cfg(test)]
fn quadratic_stable(a: f32, b: f32, c: f32) -> Option<(f32, f32)> {
    let disc = (b as f64) * (b as f64) - 4.0 * (a as f64) * (c as f64);
    stable_roots_from_disc(a, b, c, disc as f32)
}

/// The stable root pair q/a, c/q with q = −½(b + sign(b)√disc) for a given discriminant
/// disc = b² − 4ac (however it was computed), ascending; `None` if disc < 0 or a = 0.
#[inline]
fn stable_roots_from_disc(a: f32, b: f32, c: f32, disc: f32) -> Option<(f32, f32)> {
    if disc.is_nan() || disc < 0.0 || a == 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let q = -0.5 * if b >= 0.0 { b + s } else { b - s };
    if q == 0.0 {
        // b = 0 and disc = 0: the double root 0 (c = 0 too).
        return Some((0.0, 0.0));
    }
    let t0 = q / a;
    let t1 = c / q;
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// Double-precision reference roots (ascending) of the ray o + t·d against the sphere
/// |p − centre| = radius, for measuring the single-precision methods: pass the f32
/// inputs converted to f64 (exactly), so the reference answers for the very same ray.
///
/// Solved with the formulation of Haines et al. (*Ray Tracing Gems* ch. 7): f = o − c,
/// a = d·d, b' = d·f; discriminant a·(r² − |f − (b'/a)d|²) (Lagrange's identity, no
/// cancellation of |f|² against b'²/a); q = −(b' + sign(b')√disc); roots q/a and c/q
/// with c = |f|² − r² (no cancellation in −b' ± √disc). `None` if the line misses or d
/// is zero. Both roots are returned, whatever their sign.
pub fn reference_roots_f64(centre: DVec3, radius: f64, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
    let f = o - centre;
    let a = d.dot(d);
    if !(a > 0.0 && a.is_finite()) {
        return None;
    }
    let bh = d.dot(f);
    let v = f - (bh / a) * d;
    let vl = v.length();
    let disc = a * ((radius - vl) * (radius + vl));
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let q = -(bh + if bh >= 0.0 { s } else { -s });
    if q == 0.0 {
        return Some((0.0, 0.0));
    }
    let c = f.dot(f) - radius * radius;
    let (t0, t1) = (q / a, c / q);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

impl Shape for Sphere {
    /// Closest hit by [`Sphere::method`]. The point is reprojected onto the sphere,
    /// p = c + r·(p₀ − c)/|p₀ − c| with p₀ = o + t·dir (pbrt-v4 §6.8.1: this removes the
    /// error of t, which grows with the distance travelled, from the point), and
    /// n = (p₀ − c)/|p₀ − c| (equal to (p − c)/r, but without re-rounding through p).
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        let t = self.intersect_t(ray)?;
        let v = ray.at(t) - self.centre;
        let len = v.length();
        let n = if len > 0.0 && len.is_finite() { v / len } else { Vec3::Z };
        let p = self.centre + self.radius * n;
        Some(SurfaceHit { t, p, n })
    }

    fn bounds(&self) -> Aabb {
        let r = Vec3::splat(self.radius);
        Aabb { min: self.centre - r, max: self.centre + r }
    }

    fn area(&self) -> f32 {
        4.0 * PI * self.radius * self.radius
    }

    /// Uniform on the sphere by Archimedes' hat-box theorem: z = 1 − 2u is uniform in
    /// [−1, 1], φ = 2πv (pbrt-v4 §A.5.2, `SampleUniformSphere`).
    fn sample_area(&self, u: Vec2) -> Option<(Vec3, Vec3)> {
        let z = 1.0 - 2.0 * u.x;
        let rxy = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let (s, c) = phi.sin_cos();
        let n = Vec3::new(rxy * c, rxy * s, z);
        Some((self.centre + self.radius * n, n))
    }
}

#[cfg(test)]
mod tests;
