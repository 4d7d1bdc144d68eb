//! Analytic ray–shape intersection and the numerics it rests on.
//!
//! * [`roots`]: quadratic (naive and numerically stable), cubic and quartic closed
//!   forms, and Laguerre's method with deflation and polishing for any degree;
//! * [`sphere`]: spheres by the geometric method (with the lecture's early exits) and
//!   by the algebraic method (naive or stable quadratic);
//! * [`boxes`]: axis-aligned and oriented boxes by the slab method;
//! * [`polygon`]: planar convex and concave polygons, inside test by crossing number or
//!   winding number;
//! * [`implicit`]: implicit polynomial surfaces F(x, y, z) = 0 of any degree (quadrics,
//!   torus, a sextic), the ray substituted into F and solved in closed form or by
//!   Laguerre's method, normals from ∇F;
//! * [`offset`]: robust ray origins off a surface (Wächter & Binder 2019);
//! * [`triangle`]: Möller–Trumbore and the watertight test of Woop, Benthin & Wald (2013).
//!
//! Every shape implements [`Shape`]: closest hit with its geometric normal, bounds for
//! the BVH, and uniform area sampling where it can be a light.
//!
//! The adversarial accuracy/speed measurements of all of the above (failure rates against
//! f64 references, ns per test), by which the defaults are chosen, are timed and so live
//! outside this library: `spt stability` (the `cli` crate's `stability` module).
//!
//! Citations: "the thesis", "the lecture" and the papers named in comments are listed in `docs/references.md`.

pub mod boxes;
pub mod implicit;
pub mod offset;
pub mod polygon;
pub mod roots;
pub mod sphere;
pub mod triangle;

pub use bvh::{Aabb, Ray};
use glam::{Vec2, Vec3};

/// A ray–surface hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter of the hit, in (ray.t_min, ray.t_max).
    pub t: f32,
    /// The hit point, refined onto the surface where the shape can (more accurate than
    /// origin + t·dir).
    pub p: Vec3,
    /// Unit geometric normal, pointing to the shape's outside (for closed shapes) or its
    /// front (for polygons: the side from which the vertices turn counter-clockwise).
    pub n: Vec3,
}

/// A surface the tracer can intersect beside triangle meshes.
pub trait Shape: Send + Sync {
    /// The closest hit with t in (`ray.t_min`, `ray.t_max`), if any. `ray.dir` need not
    /// be unit length.
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit>;
    /// A box enclosing the whole surface.
    fn bounds(&self) -> Aabb;
    /// Surface area (of both faces' one side: a polygon's area, a sphere's 4πr²).
    fn area(&self) -> f32;
    /// A point chosen uniformly by area from `u` ∈ [0,1)², with its unit normal (as in
    /// [`SurfaceHit::n`]); `None` for surfaces that cannot be sampled (and so cannot
    /// be lights).
    fn sample_area(&self, u: Vec2) -> Option<(Vec3, Vec3)>;
}

/// Why a shape could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A parameter is NaN, infinite or out of range.
    #[error("{0}")]
    Invalid(String),
}
