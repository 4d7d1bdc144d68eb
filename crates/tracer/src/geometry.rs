//! Everything a ray can hit: the triangle meshes' 4-wide BVH and a BVH over the analytic
//! shapes, queried together. Primitive ids number the triangles first, then the shapes.

use crate::render::SceneOptions;
use crate::scene::Scene;
use crate::{Error, Result};
use bvh::{Accelerator, BoxBvh, BuildConfig, BvhWidth, Instance, Ray, TriangleTest, TwoLevel, WideBvh};
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
    triangle_count: u32,
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
        let config = Self::triangle_build_config_with(options.bvh_builder);
        let triangles = WideBvh::build(&scene.triangle_soup(), config, width)?.with_triangle_test(test);
        let boxes: Vec<_> = scene.shapes.iter().map(|s| s.shape.shape().bounds()).collect();
        let shapes = BoxBvh::build(&boxes, Self::shape_build_config())?;
        let count = scene.triangles.len() as u64 + scene.shapes.len() as u64 + scene.instanced_triangle_count();
        if count >= u32::MAX as u64 {
            return Err(Error::Setting(format!("{count} primitives exceed the 2^32 − 1 a scene can index")));
        }
        let instances =
            if scene.instances.is_empty() { None } else { Some(Self::build_instances(scene, test, width, config)?) };
        Ok(Self { triangles, shapes, instances, triangle_count: scene.triangles.len() as u32 })
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

    /// True if anything is hit in (`ray.t_min`, `ray.t_max`).
    #[inline]
    pub fn occluded(&self, shapes: &[SceneShape], ray: &Ray) -> bool {
        self.triangles.occluded(ray)
            || self.instances.as_ref().is_some_and(|i| i.bvh.occluded(ray))
            || self
                .shapes
                .traverse(ray, ray.t_max, true, |k, t_max| {
                    shapes[k as usize].shape.shape().intersect(&Ray { t_max, ..*ray }).map(|h| h.t)
                })
                .is_some()
    }
}
