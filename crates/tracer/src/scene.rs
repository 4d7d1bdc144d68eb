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
    pub fn append(&mut self, other: Scene, transform: &glam::Mat4, material: Option<u32>) -> Result<()> {
        let identity = *transform == glam::Mat4::IDENTITY;
        if !other.shapes.is_empty() && !identity {
            return Err(Error::Setting("analytic shapes cannot be transformed".into()));
        }
        let linear = glam::Mat3::from_mat4(*transform);
        let normal_matrix = linear.inverse().transpose();
        let mirrored = linear.determinant() < 0.0;
        let base = self.positions.len() as u32;
        let first_material = self.materials.len() as u32;
        let count = other.positions.len();
        let place = |p: &[f32; 3]| transform.transform_point3(Vec3::from_array(*p)).to_array();
        self.positions.extend(other.positions.iter().map(place));
        let normals: Vec<Vec3> =
            other.normals.iter().map(|n| (normal_matrix * Vec3::from_array(*n)).normalize_or(Vec3::Z)).collect();
        let tangents: Vec<Vec3> =
            other.tangents.iter().map(|t| (linear * Vec3::from_array(*t)).normalize_or(Vec3::X)).collect();
        extend_attribute(&mut self.normals, base as usize, &normals, count);
        extend_attribute(&mut self.tangents, base as usize, &tangents, count);
        extend_attribute(&mut self.uvs, base as usize, &other.uvs, count);
        self.triangles.extend(other.triangles.iter().map(|t| {
            let t = t.map(|i| i + base);
            if mirrored { [t[0], t[2], t[1]] } else { t }
        }));
        match material {
            Some(id) => self.material_ids.extend(std::iter::repeat_n(id, other.triangles.len())),
            None => {
                self.material_ids.extend(other.material_ids.iter().map(|m| m + first_material));
                self.materials.extend(other.materials);
            }
        }
        for s in other.shapes {
            let id = material.unwrap_or(s.material + first_material);
            self.shapes.push(SceneShape { shape: s.shape, material: id });
        }
        self.punctual_lights.extend(other.punctual_lights.into_iter().map(|l| l.transformed(transform)));
        Ok(())
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

    /// The material index of primitive `prim` (triangles first, then shapes).
    #[inline]
    pub fn material_id(&self, prim: u32) -> u32 {
        match self.material_ids.get(prim as usize) {
            Some(&m) => m,
            None => self.shapes[prim as usize - self.triangles.len()].material,
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
        self.shapes.iter().fold(meshes, |b, s| b.union(s.shape.shape().bounds()))
    }

    /// Checks internal consistency: indices in range, one material id per triangle,
    /// finite coordinates, normals matching positions.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Setting(m));
        if self.material_ids.len() != self.triangles.len() {
            return bad(format!("{} material ids for {} triangles", self.material_ids.len(), self.triangles.len()));
        }
        if !self.normals.is_empty() && self.normals.len() != self.positions.len() {
            return bad(format!("{} normals for {} vertices", self.normals.len(), self.positions.len()));
        }
        if !self.uvs.is_empty() && self.uvs.len() != self.positions.len() {
            return bad(format!("{} texture coordinates for {} vertices", self.uvs.len(), self.positions.len()));
        }
        if self.uvs.iter().any(|uv| !uv.iter().all(|c| c.is_finite())) {
            return bad("a texture coordinate is not finite".into());
        }
        if !self.tangents.is_empty() && self.tangents.len() != self.positions.len() {
            return bad(format!("{} tangents for {} vertices", self.tangents.len(), self.positions.len()));
        }
        if let Some(i) = self.normals.iter().chain(&self.tangents).position(|n| n.iter().any(|c| !c.is_finite())) {
            return bad(format!("normal or tangent {i} is not finite"));
        }
        let nv = self.positions.len() as u32;
        if let Some((i, t)) = self.triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v >= nv)) {
            return bad(format!("triangle {i} indexes vertex {t:?}, but there are {nv} vertices"));
        }
        let nm = self.materials.len() as u32;
        if let Some(i) = self.material_ids.iter().position(|&m| m >= nm) {
            return bad(format!("triangle {i} has material {} of {nm}", self.material_ids[i]));
        }
        if let Some(i) = self.positions.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return bad(format!("vertex {i} has a non-finite coordinate {:?}", self.positions[i]));
        }
        if let Some((i, s)) = self.shapes.iter().enumerate().find(|(_, s)| s.material >= nm) {
            return bad(format!("{} {i} has material {} of {nm}", s.shape.name(), s.material));
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
