//! Triangle pre-splitting (Karras & Aila 2013, "Fast Parallel Construction of High-Quality
//! Bounding Volume Hierarchies", §4): before the build, triangles whose box is much larger
//! than the triangle (long diagonal triangles, as in architecture) are cut into several
//! references with tighter boxes, so that the SAH can separate what their one box would
//! have made overlap. The builder then sees references; a triangle may sit in several
//! leaves, and a ray finds it in whichever it reaches first.
//!
//! Splits are spent where they pay most: a triangle's priority is the cube root of
//! 2^(−level) · (A_box − A_ideal) / A_scene, with A_box its box's surface area, A_ideal the
//! area its boxes would have if it were cut infinitely fine (2·A·(|nₓ|+|n_y|+|n_z|)), and
//! `level` that of the coarsest plane of the scene's dyadic grid crossing its box (a
//! triangle across the scene's middle blocks the top splits). Unlike Karras & Aila, who
//! always spend the budget, triangles below [`MIN_PRIORITY`] are left whole, so that meshes
//! of small even triangles build as without. A budget of `fraction · n` extra references
//! is shared in proportion to priority; each triangle is cut at the
//! coarsest grid plane across its box's longest axis, again and again, its splits shared
//! between the halves by their boxes' areas.

use super::Prim;
use crate::Aabb;
use glam::{DVec3, Vec3};

/// Finest grid level looked at: planes 2⁻²⁰ of the scene apart.
const GRID_BITS: u32 = 20;

/// Triangles whose weighted excess area (2^(−level) · (A_box − A_ideal), over the scene's
/// surface area) is below this are never split. Measured: Sponza has 1,635 triangles above
/// it (its floor, walls and arches), the bunny and a 1.1M-triangle subdivided bunny none
/// (their largest: 8.6·10⁻⁵, 5.4·10⁻⁶) — on such meshes a budget spread over every
/// triangle bought no ray speed and cost up to 40 % more build time.
const MIN_PRIORITY: f32 = 1e-4;

/// A piece's box is padded outward by this fraction of its coordinates' magnitude plus
/// its extent ([`padded`]).
const PAD: f32 = 1.0 / (1 << 21) as f32;

/// References for the build: boxes, and the triangle each bounds (`None`: one reference
/// per triangle, in order, as when `fraction` ≤ 0 or the scene is a point). At most
/// `fraction · n` references are added.
pub(crate) fn presplit(triangles: &[[Vec3; 3]], prims: Vec<Prim>, fraction: f32) -> (Vec<Prim>, Option<Vec<u32>>) {
    let n = triangles.len();
    let budget = (fraction.max(0.0) * n as f32) as usize;
    if budget == 0 {
        return (prims, None);
    }
    let scene = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(p.bounds()));
    let Some(grid) = Grid::new(&scene) else {
        return (prims, None);
    };
    let area = scene.surface_area();
    let priority: Vec<f32> = triangles
        .iter()
        .zip(&prims)
        .map(|(t, p)| {
            let b = p.bounds();
            let q = excess_area(t, &b) / area * (-(grid.level(&b) as f32)).exp2();
            if q > MIN_PRIORITY { q.cbrt() } else { 0.0 }
        })
        .collect();
    let total: f64 = priority.iter().map(|&p| p as f64).sum();
    if total.is_nan() || total <= 0.0 {
        return (prims, None);
    }
    let scale = budget as f64 / total;
    let mut out = Vec::with_capacity(n + budget);
    let mut refs = Vec::with_capacity(n + budget);
    for (i, (t, p)) in triangles.iter().zip(prims).enumerate() {
        let splits = (priority[i] as f64 * scale) as usize;
        if splits == 0 {
            // Left whole: its own box, exactly as without pre-splitting.
            out.push(p);
            refs.push(i as u32);
            continue;
        }
        let before = out.len();
        split(&grid, t, p.bounds(), splits, &mut out);
        refs.extend(std::iter::repeat_n(i as u32, out.len() - before));
    }
    (out, Some(refs))
}

/// The surface area a triangle's box has beyond what its boxes would have if it were cut
/// infinitely fine: the sum over the axes of twice its area projected along that axis.
fn excess_area(t: &[Vec3; 3], b: &Aabb) -> f32 {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    // |n| is twice the area; the projections' sum is ½(|nₓ|+|n_y|+|n_z|), counted on both
    // faces of the box.
    b.surface_area() - (n.x.abs() + n.y.abs() + n.z.abs())
}

/// The scene's dyadic grid: on each axis, planes at min + j·extent/2^level.
struct Grid {
    min: Vec3,
    extent: Vec3,
}

impl Grid {
    /// `None` for an empty or infinite scene.
    fn new(scene: &Aabb) -> Option<Self> {
        let extent = scene.extent();
        (scene.min.is_finite() && extent.is_finite() && extent.max_element() > 0.0)
            .then_some(Self { min: scene.min, extent })
    }

    /// The coarsest grid plane strictly inside `b` on `axis`: (coordinate, level); `None`
    /// if no plane down to 2⁻²⁰ crosses it there.
    fn plane_on(&self, b: &Aabb, axis: usize) -> Option<(f32, u32)> {
        let ext = self.extent[axis];
        if ext <= 0.0 {
            return None;
        }
        let cells = (1u64 << GRID_BITS) as f64;
        let q = |x: f32| (x - self.min[axis]) as f64 / ext as f64 * cells;
        // Grid lines j with lo < j ≤ hi lie strictly inside the box.
        let lo = q(b.min[axis]).floor().clamp(0.0, cells) as u64;
        let hi = (q(b.max[axis]).ceil() - 1.0).clamp(0.0, cells) as u64;
        if hi <= lo {
            return None;
        }
        // The largest power of two with a multiple in (lo, hi]: the coarsest plane.
        let k = 63 - (lo ^ hi).leading_zeros();
        let j = hi >> k << k;
        let c = (self.min[axis] as f64 + j as f64 / cells * ext as f64) as f32;
        (c > b.min[axis] && c < b.max[axis]).then_some((c, GRID_BITS - k))
    }

    /// The level of the coarsest grid plane crossing `b` on any axis (2⁻²⁰ + 1 if none):
    /// how high in the tree the box gets in the way.
    fn level(&self, b: &Aabb) -> u32 {
        (0..3).filter_map(|axis| self.plane_on(b, axis)).map(|(_, l)| l).min().unwrap_or(GRID_BITS + 1)
    }

    /// Where to cut `b`: the coarsest grid plane across its longest axis (the box shrinks
    /// most), else across the next longest; (axis, coordinate).
    fn cut(&self, b: &Aabb) -> Option<(usize, f32)> {
        let e = b.extent();
        let mut axes = [0usize, 1, 2];
        axes.sort_by(|&x, &y| e[y].total_cmp(&e[x]));
        axes.into_iter().find_map(|axis| self.plane_on(b, axis).map(|(c, _)| (axis, c)))
    }
}

/// Appends `splits + 1` references (fewer where no grid plane is left to cut at) covering
/// the part of triangle `t` inside `b` (that part's bounding box, unpadded: the planes are
/// chosen and the triangle clipped against it).
fn split(grid: &Grid, t: &[Vec3; 3], b: Aabb, splits: usize, out: &mut Vec<Prim>) {
    let plane = if splits == 0 { None } else { grid.cut(&b) };
    let Some((axis, c)) = plane else {
        out.push(Prim::new(padded(b)));
        return;
    };
    let (left, right) = clip(t, &b, axis, c);
    let (Some(left), Some(right)) = (left, right) else {
        // Within `b` the triangle lies on one side: that side's box, still to be cut
        // (it no longer crosses this plane), or `b` itself if it is no smaller.
        match left.or(right).filter(|side| *side != b) {
            Some(side) => split(grid, t, side, splits, out),
            None => out.push(Prim::new(padded(b))),
        }
        return;
    };
    // The remaining splits go to the halves by their boxes' areas.
    let (al, ar) = (left.surface_area(), right.surface_area());
    let rest = splits - 1;
    let to_left = if al + ar > 0.0 { ((rest as f32 * al / (al + ar)).round() as usize).min(rest) } else { rest / 2 };
    split(grid, t, left, to_left, out);
    split(grid, t, right, rest - to_left, out);
}

/// `b` grown by a few ulps of its coordinates: the two boxes on either side of a split
/// plane overlap, so that a ray crossing the triangle at the plane enters at least one of
/// them whatever the rounding of its slab test.
fn padded(b: Aabb) -> Aabb {
    let pad = (b.min.abs().max(b.max.abs()) + b.extent()) * PAD;
    Aabb { min: b.min - pad, max: b.max + pad }
}

/// The boxes of the parts of triangle `t` inside `b` below and above the plane
/// x_axis = c (`None`: no part strictly on that side), rounded outward from f64 and kept
/// within `b`. The triangle is clipped to `b` first (Sutherland–Hodgman), so that each
/// side's box bounds only the piece this reference stands for.
fn clip(t: &[Vec3; 3], b: &Aabb, axis: usize, c: f32) -> (Option<Aabb>, Option<Aabb>) {
    let mut piece: Vec<DVec3> = t.iter().map(|p| p.as_dvec3()).collect();
    for k in 0..3 {
        piece = clip_polygon(&piece, k, b.min[k] as f64, true);
        piece = clip_polygon(&piece, k, b.max[k] as f64, false);
    }
    let cd = c as f64;
    let side = |below: bool| {
        let part = clip_polygon(&piece, axis, cd, !below);
        // A part with no vertex strictly on its side is the cut itself (or nothing).
        let strictly = |p: &DVec3| if below { p[axis] < cd } else { p[axis] > cd };
        if !part.iter().any(strictly) {
            return None;
        }
        let (mn, mx) = part.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, z), p| (a.min(*p), z.max(*p)));
        let boxed = Aabb { min: round_down(mn).max(b.min), max: round_up(mx).min(b.max) };
        boxed.min.cmple(boxed.max).all().then_some(boxed)
    };
    (side(true), side(false))
}

/// The part of convex polygon `poly` with x_axis ≥ c (`keep_above`) or ≤ c (one pass of
/// Sutherland–Hodgman); crossing points lie exactly on the plane.
fn clip_polygon(poly: &[DVec3], axis: usize, c: f64, keep_above: bool) -> Vec<DVec3> {
    let inside = |p: &DVec3| if keep_above { p[axis] >= c } else { p[axis] <= c };
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, a) in poly.iter().enumerate() {
        let e = &poly[(i + 1) % poly.len()];
        if inside(a) {
            out.push(*a);
        }
        if (a[axis] < c && e[axis] > c) || (a[axis] > c && e[axis] < c) {
            let mut p = *a + (*e - *a) * ((c - a[axis]) / (e[axis] - a[axis]));
            p[axis] = c;
            out.push(p);
        }
    }
    out
}

/// The largest f32 point at or below `p` in every coordinate.
fn round_down(p: DVec3) -> Vec3 {
    let down = |x: f64| {
        let f = x as f32;
        if f as f64 > x { f.next_down() } else { f }
    };
    Vec3::new(down(p.x), down(p.y), down(p.z))
}

/// The smallest f32 point at or above `p` in every coordinate.
fn round_up(p: DVec3) -> Vec3 {
    let up = |x: f64| {
        let f = x as f32;
        if (f as f64) < x { f.next_up() } else { f }
    };
    Vec3::new(up(p.x), up(p.y), up(p.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Triangle;

    fn prims(tris: &[[Vec3; 3]]) -> Vec<Prim> {
        tris.iter().map(|t| Prim::new(Triangle::bounds(t))).collect()
    }

    /// A long diagonal triangle across the scene and a small one in a corner.
    fn scene() -> Vec<[Vec3; 3]> {
        vec![
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(10.0, 10.0, 0.0), Vec3::new(10.0, 10.0, 0.5)],
            [Vec3::new(0.0, 9.0, 0.0), Vec3::new(0.5, 9.0, 0.0), Vec3::new(0.0, 9.5, 0.0)],
        ]
    }

    #[test]
    fn the_budget_goes_to_the_triangle_whose_box_is_loosest() {
        let tris = scene();
        let (refs, ids) = presplit(&tris, prims(&tris), 4.0);
        let ids = ids.expect("split");
        assert_eq!(refs.len(), ids.len());
        let diagonal = ids.iter().filter(|&&i| i == 0).count();
        let small = ids.iter().filter(|&&i| i == 1).count();
        assert!(diagonal >= 6, "the diagonal triangle got {diagonal} references");
        assert_eq!(small, 1, "the small axis-aligned triangle is left whole");
        assert!(refs.len() <= tris.len() + 8, "{} references for a budget of 8 extra", refs.len());
    }

    #[test]
    fn references_cover_the_triangle_and_are_tighter_than_its_box() {
        let tris = scene();
        let (refs, ids) = presplit(&tris, prims(&tris), 4.0);
        let ids = ids.expect("split");
        let whole = Triangle::bounds(&tris[0]);
        let pieces: Vec<Aabb> = refs.iter().zip(&ids).filter(|(_, i)| **i == 0).map(|(p, _)| p.bounds()).collect();
        let area: f32 = pieces.iter().map(Aabb::surface_area).sum();
        assert!(area < 0.5 * whole.surface_area(), "pieces' area {area} against the box's {}", whole.surface_area());
        // Every point of the triangle lies in some piece.
        let t = tris[0];
        for i in 0..=40 {
            for j in 0..=(40 - i) {
                let (u, v) = (i as f32 / 40.0, j as f32 / 40.0);
                let p = (1.0 - u - v) * t[0] + u * t[1] + v * t[2];
                assert!(
                    pieces.iter().any(|b| b.min.cmple(p).all() && p.cmple(b.max).all()),
                    "point {p:?} of the triangle is in no piece"
                );
            }
        }
    }

    #[test]
    fn no_budget_or_a_flat_scene_leaves_every_triangle_whole() {
        let tris = scene();
        let (refs, ids) = presplit(&tris, prims(&tris), 0.0);
        assert_eq!((refs.len(), ids), (2, None));
        let point = [Vec3::ONE; 3];
        let (refs, ids) = presplit(&[point], prims(&[point]), 1.0);
        assert_eq!((refs.len(), ids), (1, None));
    }
}
