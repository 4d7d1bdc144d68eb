use crate::{Aabb, Ray};
use glam::{BVec3A, Vec3, Vec3A, Vec3Swizzles};
use std::hint::select_unpredictable;

/// A triangle stored for Möller–Trumbore: vertex 0 and the two edges from it.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Triangle {
    /// Vertex 0.
    pub v0: [f32; 3],
    /// v1 − v0.
    pub e1: [f32; 3],
    /// v2 − v0.
    pub e2: [f32; 3],
}

impl Triangle {
    /// From three vertices.
    #[inline]
    pub fn new(v: &[Vec3; 3]) -> Self {
        Self { v0: v[0].to_array(), e1: (v[1] - v[0]).to_array(), e2: (v[2] - v[0]).to_array() }
    }

    /// The triangle's bounding box.
    pub fn bounds(v: &[Vec3; 3]) -> Aabb {
        Aabb::from_points(v)
    }
}

/// Möller–Trumbore ray–triangle intersection (JGT 1997), as in the thesis: returns
/// (t, u, v) for a hit with t in (t_min, t_max). Both faces are hit; degenerate
/// (zero-area) triangles never are.
#[inline]
pub fn intersect_triangle(tri: &Triangle, ray: &Ray, t_max: f32) -> Option<(f32, f32, f32)> {
    let e1 = Vec3::from_array(tri.e1);
    let e2 = Vec3::from_array(tri.e2);
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - Vec3::from_array(tri.v0);
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t > ray.t_min && t < t_max).then_some((t, u, v))
}

/// Which ray–triangle test an accelerator runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TriangleTest {
    /// Möller–Trumbore (JGT 1997), the thesis's test: fast, but a ray through an edge or
    /// vertex shared by two triangles can miss both (each rounds its barycentrics
    /// differently), leaking light through closed meshes.
    MollerTrumbore,
    /// Woop, Benthin & Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013): edge
    /// functions of the vertices in a ray-aligned sheared space, evaluated the same way
    /// for both triangles of a shared edge, with a double-precision fallback when one is
    /// exactly zero — a ray never passes between adjacent triangles.
    #[default]
    Watertight,
}

impl TriangleTest {
    /// The name used on the command line and in tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::MollerTrumbore => "moller-trumbore",
            Self::Watertight => "watertight",
        }
    }
}

/// The per-ray part of the watertight test: the dominant axis and the shear that maps
/// the ray direction onto +z (Woop et al. 2013, §3, steps 1–2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WatertightRay {
    /// The origin's coordinates on the new x, y and z axes (`origin[k[i]]`).
    pub(crate) origin: [f32; 3],
    /// Permutation: the new x, y and z axes (z is the direction's largest component).
    pub(crate) k: [usize; 3],
    /// Shear constants (S_x, S_y, S_z).
    pub(crate) shear: [f32; 3],
    pub(crate) t_min: f32,
}

impl WatertightRay {
    /// Precomputes the permutation and shear for `ray`.
    ///
    /// Written without indexing the direction by a computed axis: the indexed form went
    /// through the stack (a store, then loads whose addresses waited on the axis choice),
    /// and this runs once per ray, which on small scenes is a fair part of a ray's cost.
    ///
    /// The shear's three quotients are those of every possible dominant axis, divided
    /// before the axis is known and then selected: the same divisions of the same
    /// operands, so the same bits, but the divider no longer waits for the axis choice
    /// (a ray's first triangle test waits for the shear). The reciprocals are divided here
    /// too rather than taken from `ray.inv_dir`, so that the test's bits never depend on a
    /// caller's `inv_dir` matching its `dir`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let dv = Vec3A::from(d);
        // Lane i: the quotients with d[i] as denominator, for z' = i (x' = i + 1, y' = i + 2).
        let (over_x, over_y, over_z) = (dv.yzx() / dv, dv.zxy() / dv, Vec3A::ONE / dv);
        // The dominant axis z' and the two that follow it cyclically (x' = z' + 1,
        // y' = z' + 2, mod 3), with the direction's components and the origin's.
        let o = ray.origin;
        // Chosen by vector selects, not branches: the axis is as good as random for
        // diffuse rays, and the branches LLVM made of `if`s here (and of scalar float
        // selects, without AVX-512's masked moves) were mispredicted that often.
        let (x_dominant, y_dominant) = dominant_axis(d);
        let permute = |v: Vec3A| {
            Vec3A::select(BVec3A::splat(x_dominant), v.yzx(), Vec3A::select(BVec3A::splat(y_dominant), v.zxy(), v))
        };
        let (d, o) = (permute(d.into()), permute(o.into()));
        // Lane z' of each: d[x'] / d[z'], d[y'] / d[z'] and 1 / d[z'].
        let shear = Vec3A::new(permute(over_x).z, permute(over_y).z, permute(over_z).z);
        // Swapping x and y keeps the winding when the ray points along −z.
        let flip = d.z < 0.0;
        let swap = BVec3A::splat(flip);
        let (shear, o) = (Vec3A::select(swap, shear.yxz(), shear), Vec3A::select(swap, o.yxz(), o));
        let kz = select_unpredictable(x_dominant, 0, select_unpredictable(y_dominant, 1, 2));
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let (kx, ky) = (select_unpredictable(flip, ky, kx), select_unpredictable(flip, kx, ky));
        let shear = shear.to_array();
        let [ox, oy, oz] = o.to_array();
        Self { origin: [ox, oy, oz], k: [kx, ky, kz], shear, t_min: ray.t_min }
    }
}

/// Whether x, else whether y, is the direction's dominant axis (the largest |d| — ties
/// go to x, then y): the rule of [`WatertightRay::new`] and of the kernels' faster forms
/// of it, which must agree with it to the bit.
#[inline(always)]
pub(crate) fn dominant_axis(d: Vec3) -> (bool, bool) {
    let a = d.abs();
    let x_dominant = (a.x >= a.y) & (a.x >= a.z);
    (x_dominant, !x_dominant & (a.y >= a.z))
}

/// The watertight ray–triangle test (Woop, Benthin & Wald, JCGT 2(1), 2013, Fig. 2):
/// (t, u, v) with u, v the barycentric weights of vertices 1 and 2, for a hit with t in
/// (t_min, t_max). Both faces are hit; degenerate triangles never are; a ray exactly
/// through a shared edge or vertex hits at least one of the triangles that share it.
/// The vertices must be the mesh's own (not reconstructed from edges), so that adjacent
/// triangles compute the same edge function for their shared edge.
#[inline]
pub fn intersect_triangle_watertight(v: &[Vec3; 3], ray: &WatertightRay, t_max: f32) -> Option<(f32, f32, f32)> {
    let [kx, ky, kz] = ray.k;
    let [sx, sy, sz] = ray.shear;
    let [ox, oy, oz] = ray.origin;
    let rel = |p: Vec3| {
        let p = p.to_array();
        let (px, py, pz) = (p[kx] - ox, p[ky] - oy, p[kz] - oz);
        (px - sx * pz, py - sy * pz, sz * pz)
    };
    let (ax, ay, az) = rel(v[0]);
    let (bx, by, bz) = rel(v[1]);
    let (cx, cy, cz) = rel(v[2]);
    let e0 = cx * by - cy * bx;
    let e1 = ax * cy - ay * cx;
    let e2 = bx * ay - by * ax;
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        // An edge function of exactly zero may hide a sign that rounding took away: redo
        // the test in double precision, where products of two floats are exact.
        let f = |a: f32, b: f32, c: f32, d: f32| a as f64 * b as f64 - c as f64 * d as f64;
        let e = [f(cx, by, cy, bx), f(ax, cy, ay, cx), f(bx, ay, by, ax)];
        return finish(e, [az as f64, bz as f64, cz as f64], ray.t_min, t_max);
    }
    finish([e0, e1, e2], [az, bz, cz], ray.t_min, t_max)
}

/// The end of the watertight test in either precision: the sign test on the edge
/// functions (a hit needs all of one sign, zero allowed), the determinant, and t.
#[inline(always)]
fn finish<F>(e: [F; 3], z: [F; 3], t_min: f32, t_max: f32) -> Option<(f32, f32, f32)>
where
    F: Copy
        + PartialOrd
        + Default
        + std::ops::Add<Output = F>
        + std::ops::Mul<Output = F>
        + std::ops::Div<Output = F>
        + From<f32>
        + Into<f64>,
{
    let zero = F::default();
    if (e[0] < zero || e[1] < zero || e[2] < zero) && (e[0] > zero || e[1] > zero || e[2] > zero) {
        return None;
    }
    let det = e[0] + e[1] + e[2];
    if det == zero {
        return None;
    }
    let inv_det = F::from(1.0) / det;
    let t = ((e[0] * z[0] + e[1] * z[1] + e[2] * z[2]) * inv_det).into() as f32;
    let (u, v) = ((e[1] * inv_det).into() as f32, (e[2] * inv_det).into() as f32);
    (t > t_min && t < t_max && t.is_finite()).then_some((t, u, v))
}

#[cfg(test)]
mod tests;
