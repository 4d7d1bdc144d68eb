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
mod tests {
    use super::*;

    use rng::Pcg32;

    fn sphere(c: Vec3, r: f32) -> Sphere {
        Sphere::new(c, r, SphereMethod::Geometric).unwrap()
    }

    /// All four single-precision variants of one sphere.
    fn all_methods(s: &Sphere, ray: &Ray) -> [Option<f32>; 4] {
        [
            s.intersect_geometric(ray),
            s.intersect_geometric_literal(ray),
            s.intersect_algebraic(ray, false),
            s.intersect_algebraic(ray, true),
        ]
    }

    #[test]
    fn rejects_invalid_parameters() {
        assert!(Sphere::new(Vec3::ZERO, 0.0, SphereMethod::Geometric).is_err());
        assert!(Sphere::new(Vec3::ZERO, -1.0, SphereMethod::Geometric).is_err());
        assert!(Sphere::new(Vec3::ZERO, f32::NAN, SphereMethod::Geometric).is_err());
        assert!(Sphere::new(Vec3::ZERO, f32::INFINITY, SphereMethod::Geometric).is_err());
        assert!(Sphere::new(Vec3::new(f32::NAN, 0.0, 0.0), 1.0, SphereMethod::Geometric).is_err());
        assert_eq!(SphereMethod::default(), SphereMethod::Geometric);
    }

    #[test]
    fn hit_from_outside_is_exact_for_an_axis_ray() {
        let s = sphere(Vec3::ZERO, 2.0);
        let ray = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        for (i, t) in all_methods(&s, &ray).into_iter().enumerate() {
            assert_eq!(t, Some(3.0), "method {i}");
        }
        for method in [SphereMethod::Geometric, SphereMethod::AlgebraicNaive, SphereMethod::AlgebraicStable] {
            let h = Sphere { method, ..s }.intersect(&ray).unwrap();
            assert_eq!(h.t, 3.0);
            assert_eq!(h.p, Vec3::new(0.0, 0.0, -2.0));
            assert_eq!(h.n, Vec3::new(0.0, 0.0, -1.0));
        }
    }

    #[test]
    fn origin_inside_gets_the_far_root() {
        let s = sphere(Vec3::new(1.0, 2.0, 3.0), 1.5);
        let ray = Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::X);
        for (i, t) in all_methods(&s, &ray).into_iter().enumerate() {
            assert_eq!(t, Some(1.5), "method {i}");
        }
        let off_centre = Ray::new(Vec3::new(1.5, 2.0, 3.0), -Vec3::X);
        for (i, t) in all_methods(&s, &off_centre).into_iter().enumerate() {
            assert_eq!(t, Some(2.0), "method {i}");
        }
        let h = s.intersect(&off_centre).unwrap();
        assert!((h.n - (-Vec3::X)).length() < 1e-6, "outward normal even from inside: {}", h.n);
    }

    #[test]
    fn tangent_and_near_tangent_rays() {
        let s = sphere(Vec3::ZERO, 2.0);
        let tangent = Ray::new(Vec3::new(-5.0, 2.0, 0.0), Vec3::X);
        // Robust geometric: d² = |L − t_ca d̂|² = 4 = r² exactly, so a double root at 5.
        assert_eq!(s.intersect_geometric(&tangent), Some(5.0));
        for (i, t) in all_methods(&s, &tangent).into_iter().enumerate() {
            if let Some(t) = t {
                assert!((t - 5.0).abs() < 1e-3, "method {i}: grazing hit at {t}");
            }
        }
        let just_outside = Ray::new(Vec3::new(-5.0, 2.0 * (1.0 + 1e-6), 0.0), Vec3::X);
        assert_eq!(s.intersect_geometric(&just_outside), None);
        let y = 2.0 * (1.0 - 1e-6f32);
        let just_inside = Ray::new(Vec3::new(-5.0, y, 0.0), Vec3::X);
        let expect = 5.0 - (4.0f64 - (y as f64).powi(2)).sqrt();
        let t = s.intersect_geometric(&just_inside).expect("a hit just inside the tangent");
        assert!((t as f64 - expect).abs() < 1e-5, "{t} vs {expect}");
    }

    #[test]
    fn misses_behind_and_segment_limits() {
        let s = sphere(Vec3::ZERO, 2.0);
        let miss = Ray::new(Vec3::new(-5.0, 3.0, 0.0), Vec3::X);
        let behind = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
        for r in [miss, behind] {
            assert_eq!(all_methods(&s, &r), [None; 4]);
            assert!(s.intersect(&r).is_none());
        }
        let o = Vec3::new(0.0, 0.0, -5.0);
        assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 0.0, 2.9)), [None; 4]);
        assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 0.0, 3.1)), [Some(3.0); 4]);
        // t_min past the near root: the far root.
        assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 4.0, 100.0)), [Some(7.0); 4]);
        // t_max exclusive, t_min exclusive.
        assert_eq!(all_methods(&s, &Ray::segment(o, Vec3::Z, 3.0, 7.0)), [None; 4]);
    }

    #[test]
    fn unnormalised_directions_give_the_same_point() {
        let s = sphere(Vec3::new(0.25, -0.5, 1.0), 0.75);
        let o = Vec3::new(-3.0, 1.0, 2.0);
        let d = (Vec3::new(0.3, -0.4, 1.1) - o).normalize();
        let base = s.intersect(&Ray::new(o, d)).unwrap();
        for scale in [0.37f32, 1e-3, 13.0, 1e3] {
            for method in [SphereMethod::Geometric, SphereMethod::AlgebraicNaive, SphereMethod::AlgebraicStable] {
                let h = Sphere { method, ..s }.intersect(&Ray::new(o, d * scale)).unwrap();
                assert!((h.p - base.p).length() < 1e-5, "{method:?} scale {scale}: {} vs {}", h.p, base.p);
                assert!((h.t * scale - base.t).abs() < 1e-5 * base.t, "{method:?} scale {scale}");
                assert!((h.n - base.n).length() < 1e-5);
                assert!(((h.p - s.centre).length() - s.radius).abs() < 1e-6);
            }
        }
    }

    /// 10⁴ random rays: the four methods agree on hit/miss and on the hit point, except
    /// near tangency (the discriminant is then dominated by rounding and each method may
    /// decide either way) or with the origin next to the surface (the near root ≈ 0 may
    /// fall on either side of t_min).
    #[test]
    fn methods_agree_on_random_rays() {
        let mut rng = Pcg32::seed_from_u64(0x9E37_79B9_7F4A_7C15);
        let s = sphere(Vec3::new(0.3, -0.2, 0.5), 1.3);
        let n = 10_000;
        let (mut disagree, mut hits, mut unexplained) = (0, 0, 0);
        for _ in 0..n {
            let o = Vec3::new(rng.range_f32(-4.0, 4.0), rng.range_f32(-4.0, 4.0), rng.range_f32(-4.0, 4.0));
            // Half the rays aimed at a point within 1.5 r of the centre (so many hit, some
            // graze), half in uniformly random directions.
            let len = rng.range_f32(0.1, 10.0);
            let d = if rng.next_f32() < 0.5 {
                (s.centre + 1.5 * s.radius * rng.next_f32() * rng.unit_vector().as_vec3() - o).normalize() * len
            } else {
                rng.unit_vector().as_vec3() * len
            };
            let ray = Ray::new(o, d);
            let ts = all_methods(&s, &ray);
            let pts: Vec<Option<Vec3>> = ts.iter().map(|t| t.map(|t| ray.at(t))).collect();
            let scale = (o - s.centre).length() + s.radius;
            let agree = pts.iter().all(|p| match (p, pts[0]) {
                (None, None) => true,
                (Some(a), Some(b)) => (*a - b).length() <= 1e-4 * scale,
                _ => false,
            });
            hits += usize::from(ts[0].is_some());
            if !agree {
                disagree += 1;
                // Classify with the f64 reference: distance of the line from the centre.
                let f = (o - s.centre).as_dvec3();
                let dd = d.as_dvec3().normalize();
                let miss_dist = (f - f.dot(dd) * dd).length();
                let near_tangent = (miss_dist - s.radius as f64).abs() < 1e-3 * s.radius as f64;
                let near_surface = (f.length() - s.radius as f64).abs() < 1e-4;
                if !(near_tangent || near_surface) {
                    unexplained += 1;
                    eprintln!("unexplained disagreement: o={o} d={d} {ts:?}");
                }
            }
        }
        eprintln!("random rays: {n}, hits {hits}, disagreements {disagree}, unexplained {unexplained}");
        // Not asserted, for the record: rays aimed at distance r(1 ± δ) from the centre.
        for delta in [1e-5f32, 1e-6, 1e-7] {
            let (mut grazing_disagree, m) = (0, 1000);
            let mut wrong = [0usize; 4];
            for i in 0..m {
                // The line through q = c + k·r·side with a direction perpendicular to side
                // passes the centre at distance k·r.
                let d = rng.unit_vector().as_vec3();
                let side = d.cross(rng.unit_vector().as_vec3()).normalize();
                let k = if i % 2 == 0 { 1.0 - delta } else { 1.0 + delta };
                let o = s.centre + k * s.radius * side - 5.0 * d;
                let hit = all_methods(&s, &Ray::new(o, d)).map(|t| t.is_some());
                grazing_disagree += usize::from(hit.iter().any(|&h| h != hit[0]));
                // Right or wrong, by the f64 reference for the same (rounded) f32 ray.
                let truth = reference_roots_f64(s.centre.as_dvec3(), s.radius as f64, o.as_dvec3(), d.as_dvec3())
                    .is_some_and(|(_, t1)| t1 > 0.0);
                for k in 0..4 {
                    wrong[k] += usize::from(hit[k] != truth);
                }
            }
            eprintln!(
                "grazing rays (offset r(1 ± {delta:e})): {grazing_disagree}/{m} with a hit/miss disagreement; wrong \
                 decisions vs f64 [robust geometric, literal geometric, naive, stable]: {wrong:?}"
            );
        }
        assert!(hits > n / 4, "the test should exercise hits: {hits}");
        assert_eq!(unexplained, 0);
        assert!(disagree * 1000 <= n, "{disagree} disagreements out of {n}");
    }

    /// Far origin, small sphere: origin 10⁴ away, radius 10⁻². The robust geometric and
    /// the stable algebraic method stay within 10⁻³ relative of the f64 reference (in
    /// practice a few ulp); the literal geometric and naive algebraic ones lose r² in the
    /// discriminant and miss or wander (printed, not asserted: their failure is the point).
    #[test]
    fn far_origin_accuracy() {
        let mut rng = Pcg32::seed_from_u64(0x0123_4567_89AB_CDEF);
        let c = Vec3::new(1.0, 2.0, 3.0);
        let r = 1e-2f32;
        let s = sphere(c, r);
        let names = ["geometric (robust)", "geometric (literal)", "algebraic naive", "algebraic stable"];
        let mut misses = [0usize; 5];
        let mut max_rel = [0f64; 5];
        // Distance error along the ray, |t − t_ref|·|d|, in units of the radius.
        let mut max_dist_r = [0f64; 5];
        let n = 2000;
        for i in 0..n {
            let o = c + 1e4 * rng.unit_vector().as_vec3();
            // Aim within 0.7 r of the centre: a sure hit even after rounding o and d.
            let target = c + 0.7 * r * rng.next_f32().sqrt() * rng.unit_vector().as_vec3();
            let mut d = target - o;
            if i % 2 == 0 {
                d = d.normalize();
            }
            let ray = Ray::new(o, d);
            let reference =
                reference_roots_f64(c.as_dvec3(), r as f64, o.as_dvec3(), d.as_dvec3()).expect("the reference hits").0;
            assert!(reference > 0.0);
            let ts = all_methods(&s, &ray);
            // The stand-in for roots::quadratic_stable: stable roots, f64 discriminant,
            // but from the f32 coefficients.
            let f = o - c;
            let f64disc = quadratic_stable(d.dot(d), 2.0 * d.dot(f), f.dot(f) - r * r).map(|(t0, _)| t0);
            for (k, t) in ts.into_iter().chain([f64disc]).enumerate() {
                match t {
                    None => misses[k] += 1,
                    Some(t) => {
                        let err = (t as f64 - reference).abs();
                        max_rel[k] = max_rel[k].max(err / reference);
                        max_dist_r[k] = max_dist_r[k].max(err * d.length() as f64 / r as f64);
                    }
                }
            }
        }
        for k in 0..5 {
            let name = names.get(k).copied().unwrap_or("quadratic_stable on f32 coefficients (f64 disc)");
            eprintln!(
                "far origin, {name}: misses {}/{n}, max relative error of t {:.3e} ({:.3e} radii along the ray)",
                misses[k], max_rel[k], max_dist_r[k]
            );
        }
        for k in [0, 3] {
            assert_eq!(misses[k], 0, "{}", names[k]);
            assert!(max_rel[k] < 1e-3, "{}: {}", names[k], max_rel[k]);
        }
    }

    #[test]
    fn reference_roots_are_right() {
        let (t0, t1) =
            reference_roots_f64(DVec3::ZERO, 2.0, DVec3::new(0.0, 0.0, -5.0), DVec3::new(0.0, 0.0, 2.0)).unwrap();
        assert_eq!((t0, t1), (1.5, 3.5));
        assert!(reference_roots_f64(DVec3::ZERO, 1.0, DVec3::new(0.0, 2.0, 0.0), DVec3::X).is_none());
        let (t0, t1) = reference_roots_f64(DVec3::ZERO, 1.0, DVec3::ZERO, DVec3::Y).unwrap();
        assert_eq!((t0, t1), (-1.0, 1.0));
    }

    #[test]
    fn sample_area_is_on_the_sphere_and_unbiased() {
        let s = sphere(Vec3::new(1.0, -2.0, 0.5), 0.8);
        assert!((s.area() - 4.0 * PI * 0.64).abs() < 1e-5);
        let b = s.bounds();
        let mut rng = Pcg32::seed_from_u64(42);
        let n = 20_000;
        let mut sum = glam::DVec3::ZERO;
        for _ in 0..n {
            let (p, nrm) = s.sample_area(Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
            assert!(((p - s.centre).length() - s.radius).abs() < 1e-5);
            assert!((nrm.length() - 1.0).abs() < 1e-5);
            assert!(nrm.dot(p - s.centre) > 0.0, "normal points outward");
            assert!(p.cmpge(b.min - 1e-6).all() && p.cmple(b.max + 1e-6).all());
            sum += p.as_dvec3();
        }
        // Each coordinate of a uniform point on the unit sphere has variance 1/3.
        let sigma = s.radius as f64 * (1.0 / (3.0 * n as f64)).sqrt();
        let err = (sum / n as f64 - s.centre.as_dvec3()).abs().max_element();
        assert!(err < 4.0 * sigma, "mean off by {err}, σ = {sigma}");
    }
}
