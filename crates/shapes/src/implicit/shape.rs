//! The implicit surface as a [`Shape`]: the ray clipped to the bounds, substituted into F
//! in a well-scaled parameter, solved by the chosen [`RootSolver`], the hit refined and
//! its normal taken from ∇F.

use super::Poly3;
use crate::roots::{RootSolver, SolveReport, eval_poly_deriv, real_roots_in};
use crate::{Aabb, Ray, Shape, ShapeError, SurfaceHit};
use glam::{DVec3, Vec2, Vec3};

/// The clipping box is the bounds grown by this fraction of their diagonal on every
/// side, so that a surface touching its tight box (a sphere in [−r, r]³) has its root
/// strictly inside the parameter interval, not on its rounded end.
pub const PAD_REL: f64 = 1e-6;

/// Roots at s ≤ `S_EPS` (in units of the box diagonal from the clipped start) are
/// ignored: only the spurious root at the ray's own origin when that lies on the surface
/// to solver precision. It is no substitute for offsetting secondary rays' origins (the
/// tracer's job): f32 offsets are ~1e-7 relative, 100× larger.
pub const S_EPS: f64 = 1e-9;

/// An implicit polynomial surface F = 0 inside a bounding box.
#[derive(Clone, Debug, PartialEq)]
pub struct Implicit {
    /// F, negative inside.
    pub poly: Poly3,
    /// A box enclosing the part of the surface to render; rays are clipped to it (so it
    /// also cuts open unbounded surfaces such as [`Poly3::cylinder`]).
    pub bounds: Aabb,
    /// The root finder.
    pub solver: RootSolver,
}

impl Implicit {
    /// The surface F = 0 within `bounds` (finite, non-empty, not a single point).
    pub fn new(poly: Poly3, bounds: Aabb, solver: RootSolver) -> Result<Self, ShapeError> {
        if !(bounds.min.is_finite() && bounds.max.is_finite()) || bounds.is_empty() {
            return Err(ShapeError::Invalid(format!(
                "implicit surface bounds {bounds:?} must be finite and non-empty"
            )));
        }
        if bounds.min == bounds.max {
            return Err(ShapeError::Invalid("implicit surface bounds must not be a single point".into()));
        }
        Ok(Self { poly, bounds, solver })
    }

    /// A sphere of radius r at the origin, bounded by [−r, r]³.
    pub fn sphere(r: f32, solver: RootSolver) -> Result<Self, ShapeError> {
        if !(r.is_finite() && r > 0.0) {
            return Err(ShapeError::Invalid(format!("sphere radius {r} must be finite and positive")));
        }
        Self::new(Poly3::sphere(r as f64), Aabb { min: Vec3::splat(-r), max: Vec3::splat(r) }, solver)
    }

    /// A torus around the z axis with major radius R and tube radius r, bounded by
    /// [−(R + r), R + r]² × [−r, r].
    pub fn torus(major: f32, minor: f32, solver: RootSolver) -> Result<Self, ShapeError> {
        if !(major.is_finite() && minor.is_finite() && major > 0.0 && minor > 0.0) {
            return Err(ShapeError::Invalid(format!("torus radii {major}, {minor} must be finite and positive")));
        }
        let e = Vec3::new(major + minor, major + minor, minor);
        Self::new(Poly3::torus(major as f64, minor as f64), Aabb { min: -e, max: e }, solver)
    }

    /// The degree-6 heart surface ([`Poly3::heart`]) in [−1.2, 1.2] × [−0.8, 0.8] ×
    /// [−1.05, 1.3] (its extent is about ±1.14, ±0.69, [−1, 1.24]; a test checks that
    /// F > 0 all over the box's surface). The closed-form solver falls back to Laguerre.
    pub fn heart(solver: RootSolver) -> Result<Self, ShapeError> {
        let bounds = Aabb { min: Vec3::new(-1.2, -0.8, -1.05), max: Vec3::new(1.2, 0.8, 1.3) };
        Self::new(Poly3::heart(), bounds, solver)
    }

    /// [`Shape::intersect`] with the root finder's report (for counting non-convergence).
    ///
    /// The ray is clipped to the (slightly padded) bounds in f64, giving [t₀, t₁]
    /// within (t_min, t_max). The polynomial is then set up in a shifted, scaled
    /// parameter s with t = t₀ + s·L/|d|, L the box diagonal: the origin moves to the
    /// entry point o + t₀·d and the direction becomes d/|d|·L, so that s runs over
    /// [0, ≤ 1] whatever the ray's origin distance and direction length, the
    /// coefficients are well scaled, and Laguerre's start value s = 0 is the lecture's
    /// "entry into the bounding box". Real roots in [ε, s₁] (ε = 1e-9, see `S_EPS`) are
    /// tried in ascending order; each gets one guarded Newton step, must map to an f32
    /// t strictly inside (t_min, t_max) and must have a finite non-zero ∇F (singular
    /// points such as the heart's cusps are skipped).
    pub fn intersect_report(&self, ray: &Ray) -> (Option<SurfaceHit>, SolveReport) {
        let mut report = SolveReport::default();
        let o = ray.origin.as_dvec3();
        let d = ray.dir.as_dvec3();
        let len = d.length();
        if !(len > 0.0 && len.is_finite() && o.is_finite()) {
            return (None, report);
        }
        let bmin = self.bounds.min.as_dvec3();
        let bmax = self.bounds.max.as_dvec3();
        let diag = (bmax - bmin).length();
        let pad = DVec3::splat(PAD_REL * diag);
        let (bmin, bmax) = (bmin - pad, bmax + pad);
        let mut t0 = ray.t_min as f64;
        let mut t1 = ray.t_max as f64;
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < bmin[a] || o[a] > bmax[a] {
                    return (None, report);
                }
            } else {
                let inv = 1.0 / d[a];
                let (ta, tb) = ((bmin[a] - o[a]) * inv, (bmax[a] - o[a]) * inv);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0.is_nan() || t1.is_nan() || t0 > t1 {
            return (None, report);
        }
        let scale = diag / len; // t = t0 + s·scale
        let q = o + t0 * d;
        let u = d * scale;
        let coeffs = self.poly.along_ray(q, u);
        let s_hi = (t1 - t0) / scale;
        let mut roots = Vec::with_capacity(coeffs.len());
        report = real_roots_in(&coeffs, S_EPS, s_hi, self.solver, &mut roots);
        for &s in &roots {
            let s = newton_step(&coeffs, s);
            if !(s > S_EPS && s <= s_hi) {
                continue;
            }
            let t = t0 + s * scale;
            let t32 = t as f32;
            if !(t32 > ray.t_min && t32 < ray.t_max) {
                continue;
            }
            let p = q + s * u;
            let g = self.poly.gradient(p);
            let g2 = g.length_squared();
            if !(g2 > 0.0 && g2.is_finite()) {
                continue;
            }
            let n = (g / g2.sqrt()).as_vec3();
            return (Some(SurfaceHit { t: t32, p: p.as_vec3(), n }), report);
        }
        (None, report)
    }
}

/// One Newton step on the ray polynomial, kept only if it lowers |P|.
fn newton_step(c: &[f64], s: f64) -> f64 {
    let (p, dp) = eval_poly_deriv(c, s);
    if p == 0.0 || dp == 0.0 {
        return s;
    }
    let s1 = s - p / dp;
    if s1.is_finite() && eval_poly_deriv(c, s1).0.abs() < p.abs() { s1 } else { s }
}

impl Shape for Implicit {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.intersect_report(ray).0
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// 0: the area of an implicit surface has no closed form and it cannot be sampled,
    /// so implicit surfaces cannot be lights.
    fn area(&self) -> f32 {
        0.0
    }

    /// `None`: implicit surfaces cannot be sampled by area (see [`Shape::area`]).
    fn sample_area(&self, _u: Vec2) -> Option<(Vec3, Vec3)> {
        None
    }
}
