//! Planar polygons, convex or concave (lecture slides "Schnitt Strahl—Polygon"): the ray
//! is intersected with the polygon's plane, then the hit point and the polygon are
//! projected onto the coordinate plane that drops the normal's dominant axis ("einfach
//! eine der 3 Koord fallenlassen") and a 2D point-in-polygon test decides, by crossing
//! number or by winding number.
//!
//! References: E. Haines, "Point in Polygon Strategies", *Graphics Gems IV* (1994);
//! D. Sunday, "Inclusion of a point in a polygon" (2001, geomalgorithms.com), also
//! Hormann & Agathos, "The point in polygon problem for arbitrary polygons", CGTA 20
//! (2001); M. Newell's normal (Sutherland, Sproull & Schumacker 1974; Tampieri,
//! "Newell's Method for Computing the Plane Equation of a Polygon", *Graphics Gems III*);
//! ear clipping (Meisters, "Polygons have ears", 1975; Eberly, "Triangulation by Ear
//! Clipping", Geometric Tools 2002).

use crate::{Aabb, Ray, Shape, ShapeError, SurfaceHit};
use glam::{DVec3, Vec2, Vec3};

/// The 2D point-in-polygon rule a [`Polygon`] uses.
///
/// The two differ only for self-intersecting polygons: the crossing number is the
/// even–odd rule (a point is inside if a half-line from it crosses the boundary an odd
/// number of times), the winding number the non-zero rule (inside if the boundary winds
/// around it at all). In a pentagram's centre the boundary winds twice: even–odd says
/// outside, non-zero inside. With the same half-open conventions (below) they count the
/// very same edges, so for simple polygons they agree exactly, boundary points included.
///
/// The default is [`InsideTest::WindingNumber`]: a self-intersecting polygon is then
/// filled wherever it is drawn around (SVG's and PostScript's default "nonzero" fill
/// rule), and the test costs no more than the crossing number (Sunday 2001).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum InsideTest {
    /// Even–odd rule ([`inside_crossing`]).
    CrossingNumber,
    /// Non-zero rule ([`inside_winding`]).
    #[default]
    WindingNumber,
}

/// A planar polygon (both faces hit), with its projection and, if simple, its
/// triangulation for area sampling.
///
/// The front face is the one from which the vertices turn counter-clockwise; the normal
/// points to it (right-hand rule, as for triangles).
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    vertices: Vec<Vec3>,
    test: InsideTest,
    /// Unit plane normal (Newell).
    normal: Vec3,
    /// A point on the plane (the vertex centroid): plane n·(p − anchor) = 0, and the 2D
    /// coordinates are taken relative to it, which keeps them small.
    anchor: Vec3,
    /// Dropped axis k (largest |normal| component); the 2D coordinates are the axes
    /// (k+1, k+2) mod 3, a cyclic pair, so a polygon counter-clockwise seen from the
    /// front is counter-clockwise in 2D iff normal[k] > 0.
    axis: usize,
    poly2d: Vec<Vec2>,
    area: f32,
    simple: bool,
    triangles: Vec<[Vec3; 3]>,
    /// Cumulative triangle areas, for picking one ∝ area.
    cdf: Vec<f32>,
}

/// (b − a) × (c − a) in f64: positive if a, b, c turn counter-clockwise. The inputs are
/// f32, so differences are exact in f64 for all but extreme exponent ranges and the
/// products nearly so: the sign is reliable far beyond what an f32 evaluation gives.
#[inline]
fn orient(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let (ax, ay) = (a.x as f64, a.y as f64);
    (b.x as f64 - ax) * (c.y as f64 - ay) - (b.y as f64 - ay) * (c.x as f64 - ax)
}

/// Crossing-number (even–odd) test (Haines 1994; Franklin's PNPOLY), division-free.
///
/// A horizontal half-line from `p` towards +x is crossed by edge (a, b) iff exactly one
/// endpoint lies strictly above p (`(a.y > p.y) != (b.y > p.y)`) and p is strictly left
/// of the edge. The first condition is the **half-open rule**: a vertex at exactly p's
/// height counts as below, so a half-line through a vertex is counted once where the
/// boundary passes through it and zero or two times where it only touches it (a local
/// extremum) — the parity is right either way — and horizontal edges are never counted.
/// "Left of the edge" is the sign of an orientation determinant of the edge taken from
/// its lower to its upper endpoint, so an edge gives the identical result whichever
/// direction it is traversed in (two polygons sharing it agree bit for bit), and a point
/// exactly on a non-horizontal edge counts as right of it.
///
/// Consequence for boundary points: they are classified as if moved infinitesimally up
/// and to the right (for an axis-parallel rectangle, the bottom and left edges belong to
/// it, the top and right edges do not). Polygons that tile the plane along shared edges
/// therefore claim every point exactly once when the arithmetic is exact.
pub fn inside_crossing(poly2d: &[Vec2], p: Vec2) -> bool {
    let n = poly2d.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (poly2d[i], poly2d[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let (lo, hi) = if a.y < b.y { (a, b) } else { (b, a) };
            if orient(lo, hi, p) > 0.0 {
                inside = !inside;
            }
        }
    }
    inside
}

/// Winding-number (non-zero) test of Sunday (2001): no angles, no trigonometry, just the
/// signed count of edges crossing the +x half-line from `p`: +1 for an upward edge with
/// p strictly left of it, −1 for a downward edge with p strictly right of it.
///
/// "Upward" means a.y ≤ p.y < b.y and "downward" b.y ≤ p.y < a.y: the same half-open
/// rule as [`inside_crossing`], and the same orientation determinant (taken from the
/// lower endpoint), so both tests count exactly the same edges; the winding number is
/// the signed sum, the crossing number its parity. Boundary points are classified the
/// same way as there.
pub fn inside_winding(poly2d: &[Vec2], p: Vec2) -> bool {
    let n = poly2d.len();
    let mut winding = 0i32;
    for i in 0..n {
        let (a, b) = (poly2d[i], poly2d[(i + 1) % n]);
        if a.y <= p.y {
            if b.y > p.y && orient(a, b, p) > 0.0 {
                winding += 1;
            }
        } else if b.y <= p.y && orient(b, a, p) > 0.0 {
            winding -= 1;
        }
    }
    winding != 0
}

/// True if the closed segments [a, b] and [c, d] share a point.
fn segments_touch(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    let on = |p: Vec2, q: Vec2, r: Vec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0)) && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0)) {
        return true;
    }
    (o1 == 0.0 && on(a, b, c)) || (o2 == 0.0 && on(a, b, d)) || (o3 == 0.0 && on(c, d, a)) || (o4 == 0.0 && on(c, d, b))
}

/// Simplicity in O(n²): no two non-adjacent edges touch, and no two adjacent edges fold
/// back onto each other (collinear with overlap).
fn is_simple_2d(p: &[Vec2]) -> bool {
    let n = p.len();
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        // Adjacent edge (b, c): collinear and pointing back along (b, a) overlaps.
        let c = p[(i + 2) % n];
        if orient(a, b, c) == 0.0 && (a - b).dot(c - b) > 0.0 {
            return false;
        }
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // Adjacent through vertex 0.
            }
            if segments_touch(a, b, p[j], p[(j + 1) % n]) {
                return false;
            }
        }
    }
    true
}

/// Ear clipping (Meisters 1975; Eberly 2002) of a simple polygon, O(n³) worst case,
/// which is fine for the few-vertex polygons of a scene. Returns index triples turning
/// counter-clockwise in 2D, or `None` if no ear can be found (only for polygons that are
/// not simple, or that rounding has made so).
fn ear_clip(p: &[Vec2]) -> Option<Vec<[usize; 3]>> {
    let n = p.len();
    let signed: f64 = (0..n).map(|i| orient(Vec2::ZERO, p[i], p[(i + 1) % n])).sum();
    let mut idx: Vec<usize> = (0..n).collect();
    if signed < 0.0 {
        idx.reverse();
    }
    let mut tris = Vec::with_capacity(n - 2);
    // An ear (a, b, c): convex at b and no other remaining vertex in the closed triangle
    // (strict = false) or in its open interior (strict = true, the fallback for vertices
    // exactly on a diagonal).
    let is_ear = |idx: &[usize], m: usize, strict: bool| {
        let k = idx.len();
        let (ia, ib, ic) = (idx[(m + k - 1) % k], idx[m], idx[(m + 1) % k]);
        let (a, b, c) = (p[ia], p[ib], p[ic]);
        if orient(a, b, c) <= 0.0 {
            return false;
        }
        !idx.iter().any(|&j| {
            if j == ia || j == ib || j == ic {
                return false;
            }
            let q = p[j];
            let (o1, o2, o3) = (orient(a, b, q), orient(b, c, q), orient(c, a, q));
            if strict { o1 > 0.0 && o2 > 0.0 && o3 > 0.0 } else { o1 >= 0.0 && o2 >= 0.0 && o3 >= 0.0 }
        })
    };
    while idx.len() > 3 {
        let k = idx.len();
        let ear = (0..k).find(|&m| is_ear(&idx, m, false)).or_else(|| (0..k).find(|&m| is_ear(&idx, m, true)));
        if let Some(m) = ear {
            tris.push([idx[(m + k - 1) % k], idx[m], idx[(m + 1) % k]]);
            idx.remove(m);
            continue;
        }
        // A vertex between collinear neighbours cuts off nothing: drop it.
        let flat = (0..k).find(|&m| orient(p[idx[(m + k - 1) % k]], p[idx[m]], p[idx[(m + 1) % k]]) == 0.0)?;
        idx.remove(flat);
    }
    if orient(p[idx[0]], p[idx[1]], p[idx[2]]) > 0.0 {
        tris.push([idx[0], idx[1], idx[2]]);
    }
    Some(tris)
}

impl Polygon {
    /// A polygon from its vertices in order (front: counter-clockwise), validated:
    ///
    /// * at least 3 vertices, all finite, no two consecutive ones equal;
    /// * non-zero area: the Newell normal (the polygon's vector area, exact for planar
    ///   polygons of any shape, convex or not, and a least-squares-like fit for slightly
    ///   non-planar ones; Tampieri 1992) must be longer than 10⁻⁶·size², size being the
    ///   bounding-box diagonal — so collinear vertex lists and figure-eights whose lobes
    ///   cancel are rejected, as their plane is undefined;
    /// * planar: every vertex within 10⁻⁴·size of the plane (the error names the vertex).
    ///
    /// Precomputes the dominant axis and the projected 2D vertices, checks simplicity
    /// (O(n²) segment tests) and, for simple polygons, ear-clips them for sampling.
    pub fn new(vertices: Vec<Vec3>, test: InsideTest) -> Result<Self, ShapeError> {
        let n = vertices.len();
        if n < 3 {
            return Err(ShapeError::Invalid(format!("a polygon needs at least 3 vertices, got {n}")));
        }
        if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(ShapeError::Invalid(format!("polygon vertex {i} ({}) is not finite", vertices[i])));
        }
        if let Some(i) = (0..n).find(|&i| vertices[i] == vertices[(i + 1) % n]) {
            return Err(ShapeError::Invalid(format!(
                "polygon vertices {i} and {} coincide ({})",
                (i + 1) % n,
                vertices[i]
            )));
        }
        let centroid = vertices.iter().map(|v| v.as_dvec3()).sum::<DVec3>() / n as f64;
        let bounds = Aabb::from_points(&vertices);
        let size = (bounds.max - bounds.min).as_dvec3().length();
        // Newell's method, relative to the centroid for accuracy.
        let mut newell = DVec3::ZERO;
        for i in 0..n {
            let a = vertices[i].as_dvec3() - centroid;
            let b = vertices[(i + 1) % n].as_dvec3() - centroid;
            newell += DVec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
        }
        let twice_area = newell.length();
        if twice_area.is_nan() || twice_area <= 1e-6 * size * size {
            return Err(ShapeError::Invalid(format!(
                "polygon has (near) zero area ({}, size {size}): collinear or self-cancelling vertices",
                0.5 * twice_area
            )));
        }
        let nd = newell / twice_area;
        for (i, v) in vertices.iter().enumerate() {
            let dist = nd.dot(v.as_dvec3() - centroid).abs();
            if dist > 1e-4 * size {
                return Err(ShapeError::Invalid(format!(
                    "polygon is not planar: vertex {i} ({v}) is {dist:e} from the plane (tolerance {:e})",
                    1e-4 * size
                )));
            }
        }
        let normal = nd.as_vec3();
        let anchor = centroid.as_vec3();
        let an = normal.abs();
        let axis = if an.x >= an.y && an.x >= an.z {
            0
        } else if an.y >= an.z {
            1
        } else {
            2
        };
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let poly2d: Vec<Vec2> = vertices
            .iter()
            .map(|v| {
                let r = *v - anchor;
                Vec2::new(r[i], r[j])
            })
            .collect();
        let mut simple = is_simple_2d(&poly2d);
        let mut triangles = Vec::new();
        let mut cdf = Vec::new();
        if simple {
            match ear_clip(&poly2d) {
                Some(tris) => {
                    let mut acc = 0.0f64;
                    for [a, b, c] in tris {
                        // 2D counter-clockwise ⇔ 3D normal along +axis k: flip if the
                        // polygon's normal points along −k.
                        let t = if normal[axis] > 0.0 {
                            [vertices[a], vertices[b], vertices[c]]
                        } else {
                            [vertices[a], vertices[c], vertices[b]]
                        };
                        acc += 0.5 * (t[1] - t[0]).as_dvec3().cross((t[2] - t[0]).as_dvec3()).length();
                        triangles.push(t);
                        cdf.push(acc as f32);
                    }
                }
                None => simple = false,
            }
        }
        Ok(Self {
            vertices,
            test,
            normal,
            anchor,
            axis,
            poly2d,
            area: (0.5 * twice_area) as f32,
            simple,
            triangles,
            cdf,
        })
    }

    /// The vertices as given.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Unit normal by Newell's method, towards the front (vertices counter-clockwise).
    pub fn normal(&self) -> Vec3 {
        self.normal
    }

    /// The inside test in use.
    pub fn inside_test(&self) -> InsideTest {
        self.test
    }

    /// The point on the plane the 2D coordinates are taken from (the vertex centroid).
    pub fn anchor(&self) -> Vec3 {
        self.anchor
    }

    /// The axis dropped by the projection (the normal's largest component); the 2D
    /// coordinates are the axes (k + 1, k + 2) mod 3 relative to [`Polygon::anchor`].
    pub fn dropped_axis(&self) -> usize {
        self.axis
    }

    /// The vertices projected to the 2D frame the inside test runs in.
    pub fn projected(&self) -> &[Vec2] {
        &self.poly2d
    }

    /// Cumulative areas of [`Polygon::triangles`], for picking one ∝ area.
    pub fn triangle_cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// True if no two edges meet except adjacent ones at their shared vertex. Only simple
    /// polygons have a triangulation, hence area sampling: a self-intersecting polygon
    /// can be rendered but not be a light.
    pub fn is_simple(&self) -> bool {
        self.simple
    }

    /// The ear-clipping triangulation (each triangle's normal along [`Polygon::normal`]);
    /// empty if the polygon is not simple.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// The projection of `p` (assumed on the plane) to the polygon's 2D frame.
    #[inline]
    fn project(&self, p: Vec3) -> Vec2 {
        let r = p - self.anchor;
        Vec2::new(r[(self.axis + 1) % 3], r[(self.axis + 2) % 3])
    }

    /// The 2D inside test for a point on the plane.
    fn contains(&self, p: Vec3) -> bool {
        let q = self.project(p);
        match self.test {
            InsideTest::CrossingNumber => inside_crossing(&self.poly2d, q),
            InsideTest::WindingNumber => inside_winding(&self.poly2d, q),
        }
    }
}

impl Shape for Polygon {
    /// Plane hit t = n·(anchor − o)/(n·d), then the inside test on the projected point.
    ///
    /// Rays parallel to the plane miss: n·d = 0 (which includes rays lying in the plane —
    /// the slides' "shit happens" case: t would be 0/0 or x/0) and also |n·d| ≤ ε·|d|
    /// (f32 ε, a grazing angle below ~10⁻⁷ rad), where the computed n·d is mostly
    /// rounding error and the hit point would be arbitrary. Both faces are hit; the
    /// normal is always the front normal. The point is o + t·d moved onto the plane.
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        let n = self.normal;
        let denom = n.dot(ray.dir);
        if denom.is_nan() || denom.abs() <= f32::EPSILON * ray.dir.length() {
            return None;
        }
        let t = n.dot(self.anchor - ray.origin) / denom;
        if !(t > ray.t_min && t < ray.t_max) {
            return None;
        }
        let p0 = ray.at(t);
        let p = p0 - n * n.dot(p0 - self.anchor);
        self.contains(p).then_some(SurfaceHit { t, p, n })
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }

    /// Half the length of the Newell vector: the shoelace area in the plane. For a
    /// self-intersecting polygon this is the magnitude of the *signed* area (regions
    /// weighted by their winding number: a pentagram's centre counts twice), not the area
    /// covered by either fill rule; such polygons cannot be sampled anyway.
    fn area(&self) -> f32 {
        self.area
    }

    /// Uniform by area over the ear-clipping triangles: `u.x` picks a triangle ∝ its area
    /// and is rescaled to [0, 1), then the square-root parametrisation
    /// (1 − √u₀, √u₀(1 − u₁), √u₀·u₁) gives a uniform point in it (Turk, *Graphics Gems*
    /// 1990; pbrt-v4 §6.5.4). `None` for non-simple polygons.
    fn sample_area(&self, u: Vec2) -> Option<(Vec3, Vec3)> {
        let total = *self.cdf.last()?;
        let x = u.x.clamp(0.0, 1.0) * total;
        let k = self.cdf.partition_point(|&c| c <= x).min(self.cdf.len() - 1);
        let before = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let width = self.cdf[k] - before;
        let u0 = if width > 0.0 { ((x - before) / width).clamp(0.0, 1.0) } else { 0.5 };
        let s = u0.sqrt();
        let (b1, b2) = (s * (1.0 - u.y), s * u.y);
        let [a, b, c] = self.triangles[k];
        let p = a + b1 * (b - a) + b2 * (c - a);
        Some((p, self.normal))
    }
}

#[cfg(test)]
mod tests;
