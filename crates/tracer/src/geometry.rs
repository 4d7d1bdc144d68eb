//! Everything a ray can hit: the triangle meshes' wide BVH and a BVH over the analytic
//! shapes, queried together, and for shadow rays between points of the scene a second
//! tree without the triangles on its convex hull ([`Occluders`]). Primitive ids number the
//! triangles first, then the shapes.

use crate::render::SceneOptions;
use crate::scene::Scene;
use crate::{Error, Result};
use bvh::{Accelerator, BoxBvh, BuildConfig, BvhWidth, Instance, Ray, TriangleTest, TwoLevel, WideBvh};
use glam::Vec3;
use shapes::boxes::Cuboid;
use shapes::implicit::Implicit;
use shapes::polygon::Polygon;
use shapes::sphere::Sphere;
use shapes::{Shape, SurfaceHit};

/// An analytic surface of a scene (enum dispatch: the tracer knows every kind).
#[derive(Clone, Debug)]
pub enum ShapeKind {
    /// A sphere.
    Sphere(Sphere),
    /// An axis-aligned or oriented box.
    Cuboid(Cuboid),
    /// A planar polygon.
    Polygon(Polygon),
    /// An implicit polynomial surface F(x, y, z) = 0 within a box.
    Implicit(Implicit),
}

impl ShapeKind {
    /// The shape behind the common interface.
    #[inline]
    pub fn shape(&self) -> &dyn Shape {
        match self {
            Self::Sphere(s) => s,
            Self::Cuboid(s) => s,
            Self::Polygon(s) => s,
            Self::Implicit(s) => s,
        }
    }

    /// Every kind's [`ShapeKind::name`].
    pub const NAMES: [&'static str; 4] = ["sphere", "box", "polygon", "implicit surface"];

    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Sphere(_) => Self::NAMES[0],
            Self::Cuboid(_) => Self::NAMES[1],
            Self::Polygon(_) => Self::NAMES[2],
            Self::Implicit(_) => Self::NAMES[3],
        }
    }
}

/// A shape with its material.
#[derive(Clone, Debug)]
pub struct SceneShape {
    /// The surface.
    pub shape: ShapeKind,
    /// Index into the scene's materials.
    pub material: u32,
}

/// Where on the primitive a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HitSurface {
    /// A triangle, with the barycentric weights of its vertices 1 and 2.
    Triangle {
        /// Weight of vertex 1.
        u: f32,
        /// Weight of vertex 2.
        v: f32,
    },
    /// An analytic shape, with its point and normal.
    Shape(SurfaceHit),
}

/// A ray–scene hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneHit {
    /// Primitive id: a triangle index, or the triangle count plus a shape index.
    pub prim: u32,
    /// Ray parameter.
    pub t: f32,
    /// The surface data.
    pub surface: HitSurface,
}

/// The scene's accelerators.
pub struct Geometry {
    /// Triangles: binned-SAH BVH collapsed to 4- or 8-wide SIMD nodes (the fastest of the
    /// `bvh` crate's structures on every scene measured; see `spt bvh` and `spt rays`).
    pub triangles: WideBvh,
    /// Analytic shapes, by their boxes.
    pub shapes: BoxBvh,
    /// Instanced objects: a two-level BVH (a wide BVH per object, a binary one over the
    /// instances), or `None` for a scene without instances.
    pub instances: Option<Instanced>,
    /// The triangles that can block a segment between two points of the scene
    /// ([`Occluders`]): shadow rays towards lights in the scene test these alone.
    pub occluders: Occluders,
    hull_triangles: usize,
    triangle_count: u32,
}

/// What shadow rays between two points of the scene test of its triangles.
///
/// A triangle whose plane has the whole scene on one side (a wall, floor or ceiling of a
/// room, the bottom of a box standing on the floor: a face of the scene's convex hull)
/// cannot come between two points of the scene: a segment between two points of one
/// closed half-space stays in it. Shadow rays towards a point on an emitter or a point or
/// spot light (the lights' positions count as points of the scene) need not test such
/// triangles; rays towards the environment, a directional light or the camera do.
pub enum Occluders {
    /// No triangle lies on a face of the hull: test the whole tree.
    All,
    /// A tree over the triangles that can block such a segment (primitive ids are its
    /// own, so it answers occlusion alone).
    Some(WideBvh),
    /// No triangle can block such a segment (a bare room).
    None,
}

/// The two-level structure over a scene's instances, and what shading needs to turn an
/// instanced hit back into world space.
pub struct Instanced {
    /// Bottom level per object, top level over the placements.
    pub bvh: TwoLevel<WideBvh>,
    /// The first primitive id of each instance (ascending; after the triangles and
    /// shapes).
    pub first_prim: Vec<u32>,
    /// Per instance: object-to-world, its normal matrix (inverse transpose) and whether it
    /// mirrors.
    pub transforms: Vec<InstanceTransform>,
}

/// An instance's transforms as shading uses them (its object and material are in
/// [`Scene::instances`], by the same index).
#[derive(Clone, Copy, Debug)]
pub struct InstanceTransform {
    /// Object to world.
    pub to_world: glam::Affine3A,
    /// Inverse transpose of the linear part, for normals.
    pub normal: glam::Mat3A,
    /// −1 where the transform mirrors (the winding's front flips), else 1.
    pub orientation: f32,
}

impl Instanced {
    /// The instance and the object's triangle that primitive `prim` (an instanced one)
    /// names.
    #[inline]
    pub fn locate(&self, prim: u32) -> (usize, u32) {
        let k = self.first_prim.partition_point(|&f| f <= prim) - 1;
        (k, prim - self.first_prim[k])
    }
}

impl Geometry {
    /// Builds both accelerators, the triangles' with the options' ray–triangle test, node
    /// width and split method.
    pub fn build(scene: &Scene, options: &SceneOptions) -> Result<Self> {
        let (test, width) = (options.triangle_test, options.bvh_width);
        // The f32 test's own t, not the tree's f64 refinement (`BuildConfig::exact_t`):
        // shading reads a hit's barycentrics, not its t, and a cut-out's re-trace from the
        // hit (`through_cutouts`) must start at the t the test itself computes, or it meets
        // the same surface again a few ulps on. No tree builds its table of planes.
        let config = BuildConfig { exact_t: false, ..Self::triangle_build_config_with(options.bvh_builder) };
        let soup = scene.triangle_soup();
        let triangles = WideBvh::build(&soup, config, width)?.with_triangle_test(test);
        let boxes: Vec<_> = scene.shapes.iter().map(|s| s.shape.shape().bounds()).collect();
        let shapes = BoxBvh::build(&boxes, Self::shape_build_config())?;
        let count = scene.triangles.len() as u64 + scene.shapes.len() as u64 + scene.instanced_triangle_count();
        if count >= u32::MAX as u64 {
            return Err(Error::Setting(format!("{count} primitives exceed the 2^32 − 1 a scene can index")));
        }
        let instances =
            if scene.instances.is_empty() { None } else { Some(Self::build_instances(scene, test, width, config)?) };
        let interior = interior_triangles(scene, &soup);
        let hull_triangles = interior.as_ref().map_or(0, |soup| scene.triangles.len() - soup.len());
        let occluders = match interior {
            None => Occluders::All,
            Some(soup) if soup.is_empty() => Occluders::None,
            Some(soup) => Occluders::Some(WideBvh::build(&soup, config, width)?.with_triangle_test(test)),
        };
        let triangle_count = scene.triangles.len() as u32;
        Ok(Self { triangles, shapes, instances, occluders, hull_triangles, triangle_count })
    }

    /// How many of the scene's triangles shadow rays towards lights in the scene leave
    /// out ([`Occluders`]; 0 where they test them all).
    pub fn hull_triangles(&self) -> usize {
        self.hull_triangles
    }

    fn build_instances(scene: &Scene, test: TriangleTest, width: BvhWidth, config: BuildConfig) -> Result<Instanced> {
        let objects = scene
            .objects
            .iter()
            .map(|o| {
                let soup: Vec<_> = (0..o.triangles.len()).map(|i| o.triangle_vertices(i)).collect();
                Ok(WideBvh::build(&soup, config, width)?.with_triangle_test(test))
            })
            .collect::<Result<Vec<_>>>()?;
        let mut first = (scene.triangles.len() + scene.shapes.len()) as u32;
        let mut placements = Vec::with_capacity(scene.instances.len());
        let mut first_prim = Vec::with_capacity(scene.instances.len());
        let mut transforms = Vec::with_capacity(scene.instances.len());
        for inst in &scene.instances {
            let to_world = glam::Affine3A::from_mat4(inst.transform);
            let linear = glam::Mat3::from_mat4(inst.transform);
            placements.push(Instance { object: inst.object, transform: to_world, prim_offset: first });
            first_prim.push(first);
            transforms.push(InstanceTransform {
                to_world,
                normal: glam::Mat3A::from(linear.inverse().transpose()),
                orientation: if linear.determinant() < 0.0 { -1.0 } else { 1.0 },
            });
            first += scene.objects[inst.object as usize].triangles.len() as u32;
        }
        let bvh = TwoLevel::new(objects, &placements, BuildConfig::default())?;
        Ok(Instanced { bvh, first_prim, transforms })
    }

    /// How the triangles' binary BVH is built before it is collapsed: binned SAH counting
    /// triangles in blocks of four, leaves of at most four triangles (one SIMD test).
    pub fn triangle_build_config() -> BuildConfig {
        BuildConfig { max_leaf_size: 4, sah_block: 4, ..BuildConfig::default() }
    }

    /// [`Geometry::triangle_build_config`] with another split method (`None`: the default).
    pub fn triangle_build_config_with(method: Option<bvh::SplitMethod>) -> BuildConfig {
        let config = Self::triangle_build_config();
        BuildConfig { method: method.unwrap_or(config.method), ..config }
    }

    /// How the analytic shapes' BVH is built (two shapes per leaf at most).
    pub fn shape_build_config() -> BuildConfig {
        BuildConfig { max_leaf_size: 2, ..BuildConfig::default() }
    }

    /// Number of triangles (the first shape's primitive id).
    pub fn triangle_count(&self) -> u32 {
        self.triangle_count
    }

    /// The closest hit in (`ray.t_min`, `ray.t_max`). `shapes` must be the scene's.
    #[inline]
    pub fn intersect(&self, shapes: &[SceneShape], ray: &Ray) -> Option<SceneHit> {
        let mut triangle = self.triangles.intersect(ray);
        if let Some(instanced) = &self.instances {
            let t_max = triangle.map_or(ray.t_max, |h| h.t);
            if let Some(h) = instanced.bvh.intersect(&Ray { t_max, ..*ray }) {
                triangle = Some(h);
            }
        }
        let t_max = triangle.map_or(ray.t_max, |h| h.t);
        let mut best =
            triangle.map(|h| SceneHit { prim: h.prim, t: h.t, surface: HitSurface::Triangle { u: h.u, v: h.v } });
        self.shapes.traverse(ray, t_max, false, |k, t_max| {
            let h = shapes[k as usize].shape.shape().intersect(&Ray { t_max, ..*ray })?;
            best = Some(SceneHit { prim: self.triangle_count + k, t: h.t, surface: HitSurface::Shape(h) });
            Some(h.t)
        });
        best
    }

    /// [`Geometry::occluded`] for a segment whose ends both lie in the scene's convex
    /// hull (points on its surfaces, a point or spot light's position): the triangles on
    /// the hull's faces are left out ([`Occluders`]).
    #[inline]
    pub fn occluded_inside(&self, shapes: &[SceneShape], ray: &Ray) -> bool {
        self.triangles_occlude_inside(ray) || self.others_occlude(shapes, ray)
    }

    /// Whether the scene's own triangles block a segment between two points of the
    /// scene ([`Geometry::occluded_inside`] without the instances and shapes).
    #[inline]
    pub fn triangles_occlude_inside(&self, ray: &Ray) -> bool {
        match &self.occluders {
            Occluders::All => self.triangles.occluded(ray),
            Occluders::Some(tree) => tree.occluded(ray),
            Occluders::None => false,
        }
    }

    /// True if anything is hit in (`ray.t_min`, `ray.t_max`).
    #[inline]
    pub fn occluded(&self, shapes: &[SceneShape], ray: &Ray) -> bool {
        self.triangles.occluded(ray) || self.others_occlude(shapes, ray)
    }

    /// Whether the instances or the shapes block `ray`.
    #[inline]
    fn others_occlude(&self, shapes: &[SceneShape], ray: &Ray) -> bool {
        self.instances.as_ref().is_some_and(|i| i.bvh.occluded(ray))
            || self
                .shapes
                .traverse(ray, ray.t_max, true, |k, t_max| {
                    shapes[k as usize].shape.shape().intersect(&Ray { t_max, ..*ray }).map(|h| h.t)
                })
                .is_some()
    }
}

/// The scene's own triangles that can come between two points of the scene
/// ([`Occluders`]), or `None` where leaving out the others would not pay: the scene has
/// more than [`HULL_MAX_TRIANGLES`], fewer than one triangle in [`HULL_SHARE`] lies on its
/// convex hull, or finding them would cost more than [`HULL_TEST_BUDGET`].
///
/// The points: every vertex, the corners of every shape's and instance's box, and the
/// point and spot lights' positions. A triangle is left out where all of them lie on one
/// side of its plane ([`hull_faces`]): a segment between two of them, or between points of
/// the surfaces they span, cannot cross the plane.
fn interior_triangles(scene: &Scene, triangles: &[[Vec3; 3]]) -> Option<Vec<[Vec3; 3]>> {
    use glam::DVec3;
    if triangles.len() > HULL_MAX_TRIANGLES {
        return None;
    }
    let enough = triangles.len().div_ceil(HULL_SHARE).max(1);
    let mut points: Vec<DVec3> = scene.positions.iter().map(|&p| Vec3::from_array(p).as_dvec3()).collect();
    let mut corners = |b: bvh::Aabb| {
        for k in 0..8 {
            let pick = |bit: usize, lo: f32, hi: f32| f64::from(if k >> bit & 1 == 0 { lo } else { hi });
            points.push(DVec3::new(pick(0, b.min.x, b.max.x), pick(1, b.min.y, b.max.y), pick(2, b.min.z, b.max.z)));
        }
    };
    for s in &scene.shapes {
        corners(s.shape.shape().bounds());
    }
    for i in &scene.instances {
        corners(scene.objects[i.object as usize].bounds().transformed(&glam::Affine3A::from_mat4(i.transform)));
    }
    for l in &scene.punctual_lights {
        if !matches!(l, crate::punctual::PunctualLight::Directional { .. }) {
            points.push(l.towards().as_dvec3());
        }
    }
    let on_hull = hull_faces(triangles, &points, enough)?;
    Some(triangles.iter().zip(&on_hull).filter(|&(_, &h)| !h).map(|(t, _)| *t).collect())
}

/// Which of `triangles` have every one of `points` on one side of their plane, within
/// 10⁻⁶ of the largest coordinate (f32 vertices of one wall are coplanar to about 10⁻⁷ of
/// it); `None` where fewer than `enough` do, or where the test would cost more than
/// [`HULL_TEST_BUDGET`]. Each triangle is first tested against the points that reach
/// furthest along 13 directions, which settles nearly every triangle that is not on the
/// hull after a few points; the others are tested against all of them.
fn hull_faces(triangles: &[[Vec3; 3]], points: &[glam::DVec3], enough: usize) -> Option<Vec<bool>> {
    use glam::DVec3;
    use rayon::prelude::*;
    let scale = points.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    if triangles.is_empty() || !scale.is_finite() {
        return None;
    }
    let tolerance = 1e-6 * scale;
    // The points furthest along ±x, ±y, ±z, the 4 body diagonals and the 6 face diagonals.
    let axes = [(1, 0, 0), (0, 1, 0), (0, 0, 1)];
    let diagonals = [(1, 1, 1), (1, 1, -1), (1, -1, 1), (-1, 1, 1), (1, 1, 0), (1, -1, 0), (1, 0, 1), (1, 0, -1)];
    let mut probes = Vec::new();
    for (x, y, z) in axes.into_iter().chain(diagonals).chain([(0, 1, 1), (0, 1, -1)]) {
        let d = DVec3::new(f64::from(x), f64::from(y), f64::from(z));
        let by = |a: &&DVec3, b: &&DVec3| a.dot(d).total_cmp(&b.dot(d));
        probes.extend(points.iter().min_by(by).copied());
        probes.extend(points.iter().max_by(by).copied());
    }
    // Whether all of `set` lies on one side of the triangle's plane (false for a
    // degenerate triangle, which has none: it is kept).
    let one_side = |t: &[Vec3; 3], set: &[DVec3]| -> bool {
        let [a, b, c] = t.map(|v| v.as_dvec3());
        let n = (b - a).cross(c - a);
        let len = n.length();
        // (A NaN length, from a non-finite vertex, counts as degenerate.)
        if len.is_nan() || len <= 0.0 {
            return false;
        }
        let n = n / len;
        let (mut above, mut below) = (false, false);
        for p in set {
            let d = n.dot(*p - a);
            above |= d > tolerance;
            below |= d < -tolerance;
            if above && below {
                return false;
            }
        }
        true
    };
    let candidates: Vec<bool> = triangles.par_iter().map(|t| one_side(t, &probes)).collect();
    let count = candidates.iter().filter(|&&c| c).count();
    if count < enough || (count as u64).saturating_mul(points.len() as u64) > HULL_TEST_BUDGET {
        return None;
    }
    let on_hull: Vec<bool> = triangles.par_iter().zip(&candidates).map(|(t, &c)| c && one_side(t, points)).collect();
    (on_hull.iter().filter(|&&h| h).count() >= enough).then_some(on_hull)
}

/// Shadow rays leave the hull's triangles out ([`Occluders::Some`]) where they are at
/// least one in this many of the scene's: in a small scene they share leaves with the rest (the
/// Cornell box's walls with its boxes), and shadow rays test them in every leaf they
/// visit; in a large one the tree already keeps them apart, and a second tree would
/// cost its build and memory for little.
pub const HULL_SHARE: usize = 16;

/// The most triangles a scene may have for its hull's faces to be looked for: in larger
/// scenes the tree keeps a room's few large triangles in leaves of their own (they could
/// not be one in [`HULL_SHARE`] anyway, short of a finely tessellated convex mesh), and
/// the test would add a fifth to every build (Sponza's 66K triangles: 10 of 50 ms).
pub const HULL_MAX_TRIANGLES: usize = 1 << 14;

/// The most point-against-plane tests [`hull_faces`] makes after the first pass (a few
/// milliseconds): a scanned mesh, many of whose triangles have the furthest points all
/// behind them, or a finely tessellated convex one keeps the whole tree for its shadow
/// rays instead of paying for the test in every build (the bunny's 69K triangles cost
/// 0.1–0.2 s with no bound).
const HULL_TEST_BUDGET: u64 = 20_000_000;

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::material::Material;
    use crate::mesh::quad;
    use crate::punctual::PunctualLight;
    use spectral::spectrum::Colour;

    /// A Cornell-like room: floor, ceiling and three walls 2 wide (10 triangles on the
    /// hull), a block standing on the floor with all six faces (its bottom, 2 triangles,
    /// on the hull too), a panel hanging in the room, and a lamp facing down just under the
    /// ceiling: 26 triangles, 12 of them on the hull.
    pub(crate) fn box_room() -> Scene {
        let mut scene = Scene::default();
        let white = || Material::diffuse("white", Colour::constant(0.7)).unwrap();
        scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), white());
        scene.add(&quad(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, 1.0), white());
        scene.add(&quad(Vec3::new(-1.0, 1.0, 0.0), Vec3::X, 1.0), white());
        scene.add(&quad(Vec3::new(1.0, 1.0, 0.0), -Vec3::X, 1.0), white());
        scene.add(&quad(Vec3::new(0.0, 1.0, -1.0), Vec3::Z, 1.0), white());
        let (c, h) = (Vec3::new(0.3, 0.3, -0.2), 0.3);
        for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            scene.add(&quad(c + n * h, n, h), white());
        }
        scene.add(&quad(Vec3::new(-0.4, 1.1, 0.1), Vec3::Z, 0.25), white());
        let lamp = Material::diffuse("lamp", Colour::constant(0.0)).unwrap().with_emission(Colour::constant(5.0));
        scene.add(&quad(Vec3::new(0.0, 1.98, 0.0), -Vec3::Y, 0.3), lamp);
        scene
    }

    /// A point uniformly distributed over triangle `t` from two uniform numbers.
    fn on_triangle(t: &[Vec3; 3], u: f32, v: f32) -> Vec3 {
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0])
    }

    /// The hull's faces are found, and leaving them out changes no answer for segments
    /// between points of the scene's surfaces and points on its lamp.
    #[test]
    fn hull_faces_are_left_out_of_shadow_rays_between_scene_points() {
        let scene = box_room();
        let geometry = Geometry::build(&scene, &SceneOptions::default()).unwrap();
        assert_eq!(scene.triangles.len(), 26);
        assert_eq!(geometry.hull_triangles(), 12);
        let Occluders::Some(tree) = &geometry.occluders else { panic!("a tree of the interior triangles") };
        assert_eq!(tree.references(), 14);
        let soup = scene.triangle_soup();
        let lamp = &soup[24..];
        let mut rng = rng::Pcg32::new(3, 1);
        let mut blocked = 0;
        for i in 0..20_000 {
            let from = on_triangle(&soup[rng.next_u32() as usize % 24], rng.next_f32(), rng.next_f32());
            // Half to the lamp (next-event estimation), half between any two surfaces.
            let to = if i % 2 == 0 { lamp } else { &soup[..24] };
            let to = on_triangle(&to[rng.next_u32() as usize % to.len()], rng.next_f32(), rng.next_f32());
            let ray = Ray::segment(from, to - from, 1e-4, 1.0 - 1e-4);
            let full = geometry.occluded(&scene.shapes, &ray);
            assert_eq!(geometry.occluded_inside(&scene.shapes, &ray), full, "segment {from} → {to}");
            blocked += usize::from(full);
        }
        // The block and the panel shadow a good share (the answers are not all "clear").
        assert!((4_000..16_000).contains(&blocked), "{blocked} of 20000 segments blocked");
    }

    /// A point light outside a closed room is a point of the scene: the wall between it
    /// and the room is not on the hull and still blocks its light; the far walls are.
    #[test]
    fn a_point_light_outside_keeps_the_wall_it_shines_through() {
        let mut scene = box_room();
        scene.add(
            &quad(Vec3::new(0.0, 1.0, 1.0), -Vec3::Z, 1.0),
            Material::diffuse("front", Colour::constant(0.5)).unwrap(),
        );
        scene.punctual_lights.push(PunctualLight::point(Vec3::new(3.0, 1.0, 0.0), Colour::constant(10.0)));
        let geometry = Geometry::build(&scene, &SceneOptions::default()).unwrap();
        // Floor, ceiling, back, front, left wall and the block's bottom; not the right wall.
        assert_eq!(geometry.hull_triangles(), 12);
        let ray = Ray::segment(Vec3::new(0.0, 1.0, 0.0), Vec3::new(3.0, 0.0, 0.0), 0.0, 1.0 - 1e-4);
        assert!(geometry.occluded_inside(&scene.shapes, &ray), "the right wall stands between");
    }

    /// A point just behind a triangle's plane that reaches furthest along none of the
    /// 13 directions the first test looks at: the full test still finds it, and the
    /// triangle is not on the hull.
    #[test]
    fn the_hull_test_looks_past_the_furthest_points() {
        use glam::DVec3;
        let n = DVec3::new(1.0, 2.0, 3.0).normalize();
        let (u, v) = (n.any_orthonormal_pair().0, n.any_orthonormal_pair().1);
        let corner = |a: f64, b: f64| (u * a + v * b).as_vec3();
        let triangle = [corner(0.0, 0.0), corner(1.0, 0.0), corner(0.0, 1.0)];
        // A half ball of radius 10 in front of the plane, its rim in the plane.
        let mut rng = rng::Pcg32::new(9, 2);
        let mut points: Vec<DVec3> = Vec::new();
        while points.len() < 2000 {
            let p = DVec3::new(rng.next_f32().into(), rng.next_f32().into(), rng.next_f32().into()) * 20.0 - 10.0;
            if p.length() < 10.0 {
                points.push(if p.dot(n) < 0.0 { p - 2.0 * p.dot(n) * n } else { p });
            }
        }
        points.extend((0..16).map(|k| (u * (k as f64).cos() + v * (k as f64).sin()) * 10.0));
        assert_eq!(hull_faces(&[triangle], &points, 1), Some(vec![true]));
        points.push(-0.001 * n);
        assert_eq!(hull_faces(&[triangle], &points, 1), None, "a point behind the plane");
    }

    /// Where the hull's faces are few among many triangles (a room around a fine mesh),
    /// shadow rays test the whole tree: no second tree is built.
    #[test]
    fn a_few_hull_faces_among_many_triangles_keep_one_tree() {
        let mut scene = box_room();
        let sphere = crate::mesh::uv_sphere(Vec3::new(0.0, 0.8, 0.3), 0.3, 16, 32, false);
        scene.add(&sphere, Material::diffuse("ball", Colour::constant(0.5)).unwrap());
        assert!(scene.triangles.len() > 12 * HULL_SHARE);
        let geometry = Geometry::build(&scene, &SceneOptions::default()).unwrap();
        assert!(matches!(geometry.occluders, Occluders::All));
        assert_eq!(geometry.hull_triangles(), 0);
    }

    /// A convex mesh has every triangle on its hull: a small one leaves them all out of
    /// shadow rays between its points (none can block one), a large one is not tested.
    #[test]
    fn a_convex_mesh_blocks_no_segment_between_its_points_unless_too_large_to_test() {
        let ball = |rings: u32| {
            let mut scene = Scene::default();
            let mesh = crate::mesh::uv_sphere(Vec3::ZERO, 1.0, rings, 2 * rings, false);
            scene.add(&mesh, Material::diffuse("ball", Colour::constant(0.5)).unwrap());
            let geometry = Geometry::build(&scene, &SceneOptions::default()).unwrap();
            (scene.triangles.len(), geometry)
        };
        let (count, small) = ball(12);
        assert!(matches!(small.occluders, Occluders::None));
        assert_eq!(small.hull_triangles(), count);
        let through = Ray::segment(Vec3::new(0.0, 0.0, -0.99), Vec3::new(0.0, 0.0, 1.98), 0.0, 1.0);
        assert!(!small.occluded_inside(&[], &through) && !small.occluded(&[], &through));
        let (count, large) = ball(100);
        assert!(count > HULL_MAX_TRIANGLES);
        assert!(matches!(large.occluders, Occluders::All));
    }
}
