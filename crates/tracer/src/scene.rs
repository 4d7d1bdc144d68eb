//! The scene: flat arrays of geometry plus materials, lights, camera and environment.

use crate::camera::Camera;
use crate::geometry::{SceneShape, ShapeKind};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::punctual::PunctualLight;
use crate::{Error, Result};
use bvh::Aabb;
use glam::Vec3;
use spectral::spectrum::{Colour, ColourRole, Spectrum};

/// Light arriving from infinitely far away in every direction that hits nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    /// Radiance, the same from every direction (the thesis's "sky" SPD); with a map, the
    /// factor that multiplies the map's radiance.
    pub radiance: Colour,
    /// A latitude–longitude map of the radiance by direction, or `None` for a uniform sky.
    pub map: Option<std::sync::Arc<crate::envmap::EnvironmentMap>>,
}

/// A renderable scene. Geometry is a triangle soup over shared vertices, kept as flat,
/// `bytemuck`-castable arrays (`[f32; 3]`, `[u32; 3]`, `u32`) so that a GPU backend can
/// upload exactly what the CPU traverses.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals (same length as `positions`), or empty for flat
    /// shading; a zero normal means "use the geometric normal" for that vertex.
    pub normals: Vec<[f32; 3]>,
    /// Per-vertex tangents that orient anisotropic BSDFs (same length as `positions`), or
    /// empty; a zero tangent means "any tangent" for that vertex.
    pub tangents: Vec<[f32; 3]>,
    /// Per-vertex texture coordinates (same length as `positions`), or empty; (0, 0) is
    /// the image's top-left corner (glTF's convention; OBJ's v is flipped on loading).
    pub uvs: Vec<[f32; 2]>,
    /// Triangles as vertex indices; counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle.
    pub material_ids: Vec<u32>,
    /// Analytic shapes (spheres, boxes, polygons, implicit surfaces); their primitive
    /// ids follow the triangles'.
    pub shapes: Vec<SceneShape>,
    /// Materials.
    pub materials: Vec<Material>,
    /// The camera, if the scene file gave one.
    pub camera: Option<Camera>,
    /// Uniform environment light, if any.
    pub environment: Option<Environment>,
    /// Point, spot and directional lights (no geometry: seen only by light sampling).
    pub punctual_lights: Vec<PunctualLight>,
    /// Meshes placed more than once, each kept once in its own space ([`Scene::add_object`]).
    pub objects: Vec<SceneObject>,
    /// Placements of [`Scene::objects`]: the renderer traces them through a two-level BVH
    /// (one bottom-level tree per object) instead of copying their triangles. Their
    /// primitive ids follow the shapes', instance by instance.
    pub instances: Vec<ObjectInstance>,
}

/// A triangle mesh in its own coordinates, for placing by [`ObjectInstance`]s: the same
/// flat arrays as [`Scene`]'s, material ids indexing the scene's materials.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneObject {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals, or empty.
    pub normals: Vec<[f32; 3]>,
    /// Per-vertex tangents, or empty.
    pub tangents: Vec<[f32; 3]>,
    /// Per-vertex texture coordinates, or empty.
    pub uvs: Vec<[f32; 2]>,
    /// Triangles, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's material (an index into [`Scene::materials`]).
    pub material_ids: Vec<u32>,
    /// Point, spot and directional lights that come with the mesh (object space), placed
    /// with each instance.
    pub punctual_lights: Vec<PunctualLight>,
}

impl SceneObject {
    /// Its arrays, borrowed.
    pub fn mesh(&self) -> MeshRef<'_> {
        MeshRef {
            positions: &self.positions,
            normals: &self.normals,
            tangents: &self.tangents,
            uvs: &self.uvs,
            triangles: &self.triangles,
            material_ids: &self.material_ids,
        }
    }

    /// The three vertices of triangle `i`, in object space.
    #[inline]
    pub fn triangle_vertices(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|v| Vec3::from_array(self.positions[v as usize]))
    }

    /// Its bounds in object space.
    pub fn bounds(&self) -> Aabb {
        self.positions.iter().fold(Aabb::EMPTY, |b, p| b.grow(Vec3::from_array(*p)))
    }
}

/// One placement of a [`SceneObject`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectInstance {
    /// Index into [`Scene::objects`].
    pub object: u32,
    /// Object-to-world transform (invertible; a mirroring one keeps fronts as fronts, as
    /// [`Scene::append`] does).
    pub transform: glam::Mat4,
    /// A material of the scene that replaces every material of the object in this
    /// placement, or `None` for the object's own.
    pub material: Option<u32>,
}

impl ObjectInstance {
    /// The material of the object's triangle `i` in this placement.
    #[inline]
    pub fn material_of(&self, object: &SceneObject, i: usize) -> u32 {
        self.material.unwrap_or(object.material_ids[i])
    }
}

/// The luminance of the default sky ([`Environment::white_sky`]) that lights scenes
/// without lights: a white diffuse surface under it has radiance 1 (linear sRGB (1, 1, 1)).
pub const DEFAULT_SKY_LUMINANCE: f32 = 1.0;

impl Environment {
    /// A uniform white sky: CIE D65 scaled to luminance Y = `luminance`, sRGB's own white,
    /// so its linear-sRGB radiance is (`luminance`, `luminance`, `luminance`).
    pub fn white_sky(luminance: f32) -> Self {
        Self::uniform(Colour::from_spectrum(Spectrum::D65(luminance), ColourRole::Illuminant))
    }

    /// The same radiance from every direction.
    pub fn uniform(radiance: Colour) -> Self {
        Self { radiance, map: None }
    }

    /// An environment map times a grey `scale`.
    pub fn from_map(map: crate::envmap::EnvironmentMap, scale: f32) -> Self {
        Self { radiance: Colour::constant(scale), map: Some(std::sync::Arc::new(map)) }
    }

    /// Luminance-like power per unit solid angle, averaged over directions (for light
    /// selection).
    pub fn mean_luminance(&self) -> f32 {
        self.radiance.luminance() * self.map.as_ref().map_or(1.0, |m| m.mean_luminance())
    }

    /// Whether it sends no light at all.
    pub fn is_black(&self) -> bool {
        self.radiance.is_black() || self.map.as_ref().is_some_and(|m| m.mean_luminance() == 0.0)
    }

    /// The radiance arriving from direction `dir` at the path's wavelengths.
    #[inline]
    pub fn radiance_from<const N: usize>(
        &self,
        dir: glam::Vec3,
        wl: &spectral::SampledWavelengths<N>,
    ) -> spectral::SampledSpectrum<N> {
        let base = self.radiance.sample(wl);
        match &self.map {
            None => base,
            Some(m) => base * m.radiance(dir, wl),
        }
    }
}

impl Scene {
    /// Whether anything lights the scene: a non-black environment or punctual light, or a
    /// triangle or shape whose material has a non-black emission. A scene without lights
    /// renders black. Emission through an emissive texture (screens, decals, glTF's
    /// DamagedHelmet) does not count: it is seen, but it is not sampled as a light, and a
    /// model that has only such glow still needs a light to be seen.
    pub fn has_lights(&self) -> bool {
        let emits = |m: u32| {
            self.materials
                .get(m as usize)
                .filter(|m| !m.has_textured_emission())
                .and_then(|m| m.emission.as_ref())
                .is_some_and(|e| !e.is_black())
        };
        self.environment.as_ref().is_some_and(|e| !e.is_black())
            || self.material_ids.iter().any(|&m| emits(m))
            || self.instances.iter().any(|i| {
                let o = &self.objects[i.object as usize];
                (0..o.triangles.len()).any(|t| emits(i.material_of(o, t)))
            })
            || self.shapes.iter().any(|s| emits(s.material))
            || self.punctual_lights.iter().any(|l| !l.colour().is_black())
    }

    /// The distinct texture images the materials read (each once, however many maps share
    /// it) and the bytes their texels take.
    pub fn texture_images(&self) -> (usize, usize) {
        let mut seen = std::collections::HashSet::new();
        let mut bytes = 0;
        for t in self.materials.iter().filter_map(|m| m.textures.as_deref()) {
            for map in t.maps() {
                if seen.insert(std::sync::Arc::as_ptr(&map.image)) {
                    bytes += map.image.size_bytes();
                }
            }
        }
        (seen.len(), bytes)
    }

    /// Drops every material's textures (they render with their factors alone); returns
    /// how many materials had any.
    pub fn strip_textures(&mut self) -> usize {
        self.materials.iter_mut().filter_map(|m| m.textures.take()).count()
    }

    /// Appends a mesh with one material (flat-shaded if its normals are empty; tangents
    /// derived from the normal if its tangents are empty); returns the material's index.
    pub fn add(&mut self, mesh: &Mesh, material: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.materials.push(material);
        self.add_with_material(mesh, id);
        id
    }

    /// Appends a mesh using material `material` (an index into [`Self::materials`]), as
    /// [`Self::add`] does: for many meshes sharing one material.
    pub fn add_with_material(&mut self, mesh: &Mesh, material: u32) {
        let base = self.positions.len();
        let count = mesh.positions.len();
        self.positions.extend(mesh.positions.iter().map(|p| p.to_array()));
        extend_attribute(&mut self.normals, base, &mesh.normals, count);
        extend_attribute(&mut self.tangents, base, &mesh.tangents, count);
        extend_attribute(&mut self.uvs, base, &mesh.uvs, count);
        self.triangles.extend(mesh.triangles.iter().map(|t| t.map(|i| i + base as u32)));
        self.material_ids.extend(std::iter::repeat_n(material, mesh.triangles.len()));
    }

    /// Appends another scene's triangles placed by `transform` (a mirroring transform
    /// reverses their winding, so that fronts stay fronts; normals go through its inverse
    /// transpose), its punctual lights moved by it, and its materials — or, with
    /// `material`, every appended triangle uses that material of this scene instead. Its
    /// camera and environment are not taken; analytic shapes only under the identity
    /// (a transformed shape is not a shape of the same kind in general).
    pub fn append(&mut self, mut other: Scene, transform: &glam::Mat4, material: Option<u32>) -> Result<()> {
        let identity = *transform == glam::Mat4::IDENTITY;
        if !other.shapes.is_empty() && !identity {
            return Err(Error::Setting("analytic shapes cannot be transformed".into()));
        }
        other.flatten_instances();
        let first_material = self.materials.len() as u32;
        let triangles = other.triangles.len();
        let material_ids = std::mem::take(&mut other.material_ids);
        let materials = std::mem::take(&mut other.materials);
        let shapes = std::mem::take(&mut other.shapes);
        let lights = std::mem::take(&mut other.punctual_lights);
        self.append_geometry(other.mesh(), transform);
        match material {
            Some(id) => self.material_ids.extend(std::iter::repeat_n(id, triangles)),
            None => {
                self.material_ids.extend(material_ids.iter().map(|m| m + first_material));
                self.materials.extend(materials);
            }
        }
        for s in shapes {
            let id = material.unwrap_or(s.material + first_material);
            self.shapes.push(SceneShape { shape: s.shape, material: id });
        }
        self.punctual_lights.extend(lights.into_iter().map(|l| l.transformed(transform)));
        Ok(())
    }

    /// Appends `other`'s vertices and triangles placed by `transform` (winding reversed
    /// by a mirroring one), without material ids.
    fn append_geometry(&mut self, other: MeshRef, transform: &glam::Mat4) {
        let linear = glam::Mat3::from_mat4(*transform);
        let normal_matrix = linear.inverse().transpose();
        let mirrored = linear.determinant() < 0.0;
        let base = self.positions.len() as u32;
        let count = other.positions.len();
        let place = |p: &[f32; 3]| transform.transform_point3(Vec3::from_array(*p)).to_array();
        self.positions.extend(other.positions.iter().map(place));
        let normals: Vec<Vec3> =
            other.normals.iter().map(|n| (normal_matrix * Vec3::from_array(*n)).normalize_or(Vec3::Z)).collect();
        let tangents: Vec<Vec3> =
            other.tangents.iter().map(|t| (linear * Vec3::from_array(*t)).normalize_or(Vec3::X)).collect();
        extend_attribute(&mut self.normals, base as usize, &normals, count);
        extend_attribute(&mut self.tangents, base as usize, &tangents, count);
        extend_attribute(&mut self.uvs, base as usize, other.uvs, count);
        self.triangles.extend(other.triangles.iter().map(|t| {
            let t = t.map(|i| i + base);
            if mirrored { [t[0], t[2], t[1]] } else { t }
        }));
    }

    /// Keeps `other`'s triangles once as an object to place with [`Scene::place`]: its
    /// materials are appended (or, with `material`, every triangle uses that material of
    /// this scene), its punctual lights travel with each placement, its camera and
    /// environment are dropped. Analytic shapes cannot be instanced (an error).
    pub fn add_object(&mut self, other: Scene, material: Option<u32>) -> Result<u32> {
        if !other.shapes.is_empty() || !other.instances.is_empty() {
            return Err(Error::Setting("only triangle meshes can be instanced (not shapes or instances)".into()));
        }
        let first_material = self.materials.len() as u32;
        let material_ids = match material {
            Some(id) => vec![id; other.triangles.len()],
            None => {
                self.materials.extend(other.materials);
                other.material_ids.iter().map(|m| m + first_material).collect()
            }
        };
        self.objects.push(SceneObject {
            positions: other.positions,
            normals: other.normals,
            tangents: other.tangents,
            uvs: other.uvs,
            triangles: other.triangles,
            material_ids,
            punctual_lights: other.punctual_lights,
        });
        Ok(self.objects.len() as u32 - 1)
    }

    /// Places object `object` by `transform` (with its punctual lights, moved).
    pub fn place(&mut self, object: u32, transform: glam::Mat4) -> Result<()> {
        self.place_with(object, transform, None)
    }

    /// [`Scene::place`], every triangle of this placement using `material` (a material
    /// of this scene) instead of the object's own where given.
    pub fn place_with(&mut self, object: u32, transform: glam::Mat4, material: Option<u32>) -> Result<()> {
        if let Some(m) = material
            && m as usize >= self.materials.len()
        {
            return Err(Error::Setting(format!("material {m} of {}", self.materials.len())));
        }
        let Some(o) = self.objects.get(object as usize) else {
            return Err(Error::Setting(format!("object {object} of {}", self.objects.len())));
        };
        let det = glam::Mat3::from_mat4(transform).determinant();
        if !(transform.is_finite() && det.is_finite() && det != 0.0) {
            return Err(Error::Setting("an instance's transform is singular or not finite".into()));
        }
        let lights: Vec<PunctualLight> = o.punctual_lights.iter().map(|l| l.clone().transformed(&transform)).collect();
        self.punctual_lights.extend(lights);
        self.instances.push(ObjectInstance { object, transform, material });
        Ok(())
    }

    /// Copies every instance's triangles into the flat arrays and drops the objects: the
    /// same surfaces as one mesh (for backends without two-level traversal, and as the
    /// reference the instanced scene is tested against).
    pub fn flatten_instances(&mut self) {
        self.flatten_instances_where(|_| true);
        self.objects.clear();
    }

    /// Copies the placements on lights that light sampling draws
    /// ([`Scene::instance_has_light`]) into the flat arrays and keeps the others (and the
    /// objects): for a backend that traces placements two-level but samples emitters from
    /// a table of world-space triangles (the GPU's).
    pub fn flatten_light_instances(&mut self) {
        let lights: Vec<bool> = self.instances.iter().map(|i| self.instance_has_light(i)).collect();
        self.flatten_instances_where(|k| lights[k]);
    }

    /// Copies the instances whose index `copy` picks into the flat arrays, in order, and
    /// keeps the others as placements (the objects stay).
    fn flatten_instances_where(&mut self, copy: impl Fn(usize) -> bool) {
        let objects = std::mem::take(&mut self.objects);
        let mut kept = Vec::new();
        for (k, inst) in std::mem::take(&mut self.instances).into_iter().enumerate() {
            let o = &objects[inst.object as usize];
            if !copy(k) {
                kept.push(inst);
                continue;
            }
            // (Its lights were placed with it already.)
            self.append_geometry(o.mesh(), &inst.transform);
            self.material_ids.extend((0..o.triangles.len()).map(|i| inst.material_of(o, i)));
        }
        self.objects = objects;
        self.instances = kept;
    }

    /// Whether some triangle of `inst`'s placement is a light that light sampling draws:
    /// on an emissive material without an emissive texture (those are left to the paths
    /// that hit them, see `Lights::new`).
    pub fn instance_has_light(&self, inst: &ObjectInstance) -> bool {
        let emits = |m: u32| {
            let m = &self.materials[m as usize];
            m.emission.is_some() && !m.has_textured_emission()
        };
        match inst.material {
            Some(m) => emits(m),
            None => self.objects[inst.object as usize].material_ids.iter().any(|&m| emits(m)),
        }
    }

    /// Triangles the instances place (counting each placement).
    pub fn instanced_triangle_count(&self) -> u64 {
        self.instances.iter().map(|i| self.objects[i.object as usize].triangles.len() as u64).sum()
    }

    /// Appends an analytic shape with its own material; returns the material's index.
    pub fn add_shape(&mut self, shape: ShapeKind, material: Material) -> u32 {
        let id = self.materials.len() as u32;
        self.materials.push(material);
        self.shapes.push(SceneShape { shape, material: id });
        id
    }

    /// Appends an analytic shape with an existing material.
    pub fn add_shape_with_material(&mut self, shape: ShapeKind, material: u32) {
        self.shapes.push(SceneShape { shape, material });
    }

    /// The scene's own mesh arrays (not its instances), borrowed.
    pub fn mesh(&self) -> MeshRef<'_> {
        MeshRef {
            positions: &self.positions,
            normals: &self.normals,
            tangents: &self.tangents,
            uvs: &self.uvs,
            triangles: &self.triangles,
            material_ids: &self.material_ids,
        }
    }

    /// The three vertices of triangle `i`.
    #[inline]
    pub fn triangle_vertices(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|v| Vec3::from_array(self.positions[v as usize]))
    }

    /// Every triangle's vertices, in order (the accelerator's input).
    pub fn triangle_soup(&self) -> Vec<[Vec3; 3]> {
        (0..self.triangles.len()).map(|i| self.triangle_vertices(i)).collect()
    }

    /// The bounds of all geometry.
    pub fn bounds(&self) -> Aabb {
        let meshes = self.positions.iter().fold(Aabb::EMPTY, |b, p| b.grow(Vec3::from_array(*p)));
        let shapes = self.shapes.iter().fold(meshes, |b, s| b.union(s.shape.shape().bounds()));
        self.instances.iter().fold(shapes, |b, i| {
            b.union(self.objects[i.object as usize].bounds().transformed(&glam::Affine3A::from_mat4(i.transform)))
        })
    }

    /// Checks internal consistency: indices in range, one material id per triangle,
    /// finite coordinates, normals matching positions.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Setting(m));
        let nm = self.materials.len() as u32;
        check_mesh(self.mesh(), nm).map_err(Error::Setting)?;
        if let Some((i, s)) = self.shapes.iter().enumerate().find(|(_, s)| s.material >= nm) {
            return bad(format!("{} {i} has material {} of {nm}", s.shape.name(), s.material));
        }
        for (k, o) in self.objects.iter().enumerate() {
            check_mesh(o.mesh(), nm).map_err(|e| Error::Setting(format!("object {k}: {e}")))?;
        }
        for (k, i) in self.instances.iter().enumerate() {
            let det = glam::Mat3::from_mat4(i.transform).determinant();
            if i.object as usize >= self.objects.len()
                || !(i.transform.is_finite() && det.is_finite() && det != 0.0)
                || i.material.is_some_and(|m| m as usize >= self.materials.len())
            {
                return bad(format!(
                    "instance {k}: object {} of {}, a singular transform, or a missing material",
                    i.object,
                    self.objects.len()
                ));
            }
        }
        let prims = self.triangles.len() as u64 + self.shapes.len() as u64 + self.instanced_triangle_count();
        if prims >= u32::MAX as u64 {
            return bad(format!("{prims} primitives exceed the 2^32 − 1 a scene can index"));
        }
        if let Some(camera) = &self.camera {
            camera.validate().map_err(Error::Setting)?;
        }
        for light in &self.punctual_lights {
            light.validate().map_err(Error::Setting)?;
        }
        Ok(())
    }
}

/// A mesh's flat arrays, borrowed: the scene's own ([`Scene::mesh`]) or an instanced
/// object's ([`SceneObject::mesh`]), for code that treats both alike.
#[derive(Clone, Copy, Debug)]
pub struct MeshRef<'a> {
    /// Vertex positions.
    pub positions: &'a [[f32; 3]],
    /// Per-vertex shading normals, or empty.
    pub normals: &'a [[f32; 3]],
    /// Per-vertex tangents, or empty.
    pub tangents: &'a [[f32; 3]],
    /// Per-vertex texture coordinates, or empty.
    pub uvs: &'a [[f32; 2]],
    /// Triangles as vertex indices.
    pub triangles: &'a [[u32; 3]],
    /// Each triangle's material.
    pub material_ids: &'a [u32],
}

/// Checks a mesh's arrays against each other and `materials` materials: one material id
/// per triangle, attributes as long as the positions (or empty), indices in range, finite
/// values.
fn check_mesh(m: MeshRef, materials: u32) -> std::result::Result<(), String> {
    if m.material_ids.len() != m.triangles.len() {
        return Err(format!("{} material ids for {} triangles", m.material_ids.len(), m.triangles.len()));
    }
    let nv = m.positions.len();
    for (what, len) in
        [("normals", m.normals.len()), ("texture coordinates", m.uvs.len()), ("tangents", m.tangents.len())]
    {
        if len != 0 && len != nv {
            return Err(format!("{len} {what} for {nv} vertices"));
        }
    }
    if m.uvs.iter().any(|uv| !uv.iter().all(|c| c.is_finite())) {
        return Err("a texture coordinate is not finite".into());
    }
    if let Some(i) = m.normals.iter().chain(m.tangents).position(|n| n.iter().any(|c| !c.is_finite())) {
        return Err(format!("normal or tangent {i} is not finite"));
    }
    if let Some((i, t)) = m.triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= nv)) {
        return Err(format!("triangle {i} indexes vertex {t:?}, but there are {nv} vertices"));
    }
    if let Some(i) = m.material_ids.iter().position(|&id| id >= materials) {
        return Err(format!("triangle {i} has material {} of {materials}", m.material_ids[i]));
    }
    if let Some(i) = m.positions.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        return Err(format!("vertex {i} has a non-finite coordinate {:?}", m.positions[i]));
    }
    Ok(())
}

/// Appends a per-vertex attribute for `count` new vertices starting at `base`, keeping
/// the array either empty (no mesh has the attribute) or as long as the positions, with
/// zeros where a mesh lacks it.
fn extend_attribute<const K: usize, T: Copy + Into<[f32; K]>>(
    attr: &mut Vec<[f32; K]>,
    base: usize,
    values: &[T],
    count: usize,
) {
    if !values.is_empty() {
        attr.resize(base, [0.0; K]);
        attr.extend(values.iter().map(|&v| v.into()));
    } else if !attr.is_empty() {
        attr.resize(base + count, [0.0; K]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::quad;

    #[test]
    fn lights_are_found_where_they_are() {
        let mut scene = Scene::default();
        let grey = Material::diffuse("grey", Colour::constant(0.5)).unwrap();
        scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), grey.clone());
        assert!(!scene.has_lights());
        // An emissive material no primitive uses, or a black emission, lights nothing.
        scene.materials.push(grey.clone().with_emission(Colour::constant(3.0)));
        scene.add(&quad(Vec3::Y, -Vec3::Y, 0.2), grey.clone().with_emission(Colour::constant(0.0)));
        assert!(!scene.has_lights());
        scene.environment = Some(Environment::uniform(Colour::constant(0.0)));
        assert!(!scene.has_lights());
        let mut lamp = scene.clone();
        lamp.add(&quad(Vec3::Y, -Vec3::Y, 0.2), grey.clone().with_emission(Colour::constant(3.0)));
        assert!(lamp.has_lights());
        let mut sky = scene.clone();
        sky.environment = Some(Environment::white_sky(2.0));
        assert!(sky.has_lights());
        let mut point = scene.clone();
        point.punctual_lights.push(PunctualLight::point(Vec3::Y, Colour::constant(1.0)));
        assert!(point.has_lights());
        point.punctual_lights[0] = PunctualLight::point(Vec3::Y, Colour::constant(0.0));
        assert!(!point.has_lights());
        let mut sphere = scene;
        sphere.add_shape(
            crate::ShapeKind::Sphere(
                shapes::sphere::Sphere::new(Vec3::ZERO, 1.0, shapes::sphere::SphereMethod::default()).unwrap(),
            ),
            grey.with_emission(Colour::constant(1.0)),
        );
        assert!(sphere.has_lights());
    }

    #[test]
    fn the_white_sky_is_srgb_white_of_its_luminance() {
        let sky = Environment::white_sky(2.5);
        for c in sky.radiance.rgb {
            assert!((c - 2.5).abs() < 2.5e-3, "{:?}", sky.radiance.rgb);
        }
        assert!((sky.radiance.luminance() - 2.5).abs() < 2.5e-3);
    }
}
