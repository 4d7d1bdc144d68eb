//! glTF 2.0 scenes (`.gltf` with `.bin` files or data URIs, and `.glb`), read with the
//! `gltf` crate.
//!
//! What is converted:
//! * the default scene's node hierarchy, each node's mesh placed by its world transform
//!   (a mirroring transform reverses the winding, so fronts stay fronts); primitives in
//!   triangle, strip and fan modes, indexed or not, with their normals and texture
//!   coordinates (`TEXCOORD_0`);
//! * materials: `pbrMetallicRoughness` factors with `KHR_materials_ior` → the
//!   metallic–roughness BSDF ([`brdf::models::MetallicRoughness`], the specification's
//!   Appendix B); `KHR_materials_transmission` × (1 − metallic) ≥ ½ → a dielectric of
//!   that index (smooth at roughness 0, else GGX with α = roughness²), tinted by the base
//!   colour, absorbing by `KHR_materials_volume`'s attenuation when smooth;
//!   `emissiveFactor` × `KHR_materials_emissive_strength` → an area light (with an
//!   emissive texture: a glow seen by paths, not sampled as a light);
//! * perspective cameras, chosen by index or name ([`GltfOptions::camera`]; the first in
//!   the scene otherwise); the film's width and height set the aspect ratio;
//! * `KHR_lights_punctual` point, spot and directional lights as delta lights.
//!
//! Units: the renderer's radiance is read as luminance in cd/m² (nits), so glTF's candela
//! (point, spot), lux (directional) and emissive nits carry over unchanged.
//!
//! * textures: base colour, metallic–roughness, normal and emissive maps with their
//!   samplers' wrap modes and `KHR_texture_transform` (see [`crate::texture`]), alpha
//!   modes (MASK cut-outs, BLEND as stochastic transparency);
//! * a mesh that several nodes place becomes one object instanced in the two-level BVH
//!   ([`Scene::objects`], [`Scene::instances`]) rather than a copy per node.
//!
//! Not converted, and reported in [`GltfScene::notes`]: occlusion and transmission
//! textures, texture coordinates other than `TEXCOORD_0`, orthographic cameras, points and
//! lines, light `range`.
//!
//! Bad input is an error naming the file and what is wrong, never a panic: the buffers
//! are read only from regular files next to the glTF or from the file itself, indices are
//! checked against the vertices, a node reached twice (a cycle or a second parent) is an
//! error, and the instanced triangle count is bounded before anything is allocated.

use crate::camera::Camera;
use crate::material::{Material, ModelId};
use crate::mesh::Mesh;
use crate::punctual::PunctualLight;
use crate::scene::Scene;
use crate::texture::{Alpha, AlphaMode, Encoding, MaterialTextures, NormalMap, TextureImage, TextureMap, Wrap};
use crate::{Error, Result};
use brdf::TextureSlots;
use brdf::params::ParamValue;
use glam::{Mat3, Mat4, Vec3};
use spectral::spectrum::Colour;
use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How a glTF file is turned into a scene.
#[derive(Clone, Debug, Default)]
pub struct GltfOptions {
    /// The camera to look through: its index among the glTF's cameras, or its name;
    /// `None` picks the first camera the scene places (if any).
    pub camera: Option<String>,
}

/// A camera of the file's scene, as placed by its node.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfCamera {
    /// Its index among the file's cameras.
    pub index: usize,
    /// Its name, if it has one.
    pub name: Option<String>,
    /// The view it gives (perspective cameras only).
    pub camera: Option<Camera>,
}

/// A converted glTF scene.
#[derive(Clone, Debug)]
pub struct GltfScene {
    /// The scene, its camera set to the chosen one.
    pub scene: Scene,
    /// The cameras the scene places, in node order.
    pub cameras: Vec<GltfCamera>,
    /// What the file uses that the conversion ignored, one line each.
    pub notes: Vec<String>,
}

/// The most triangles a scene may expand to with its instances (67 M, about 6 GB as
/// copied meshes): a small file can place a large mesh many times.
pub const MAX_TRIANGLES: u64 = 1 << 26;

/// Loads a `.gltf` or `.glb` file and the buffers it names.
pub fn load_gltf(path: &Path, options: &GltfOptions) -> Result<GltfScene> {
    let bytes = crate::obj::read_file_bytes(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    load_gltf_bytes(&bytes, path, options, &crate::obj::read_file_bytes)
}

/// Converts a glTF file's bytes (JSON or binary): `path` names it in messages and is what
/// buffer URIs are resolved against; `read` returns the bytes of such a resolved path
/// ([`load_gltf`] reads files; a fuzzer or a test drives the loader from memory). Never
/// panics: malformed input is an error.
pub fn load_gltf_bytes(
    bytes: &[u8],
    path: &Path,
    options: &GltfOptions,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<GltfScene> {
    let fail = |message: String| Error::parse(path, message);
    // The last line of defence, as for tobj: should the gltf crate panic on some input,
    // the panic becomes an error naming the file.
    match catch_unwind(AssertUnwindSafe(|| convert(bytes, path, options, read))) {
        Ok(result) => result,
        Err(panic) => Err(fail(format!("the glTF reader panicked: {}", crate::panic_message(panic.as_ref())))),
    }
}

fn convert(
    bytes: &[u8],
    path: &Path,
    options: &GltfOptions,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<GltfScene> {
    let fail = |message: String| Error::parse(path, message);
    let invalid = |e: String| fail(format!("not a valid glTF file: {e}"));
    // gltf 1.4.1 subtracts the 12-byte header from a GLB's declared length unchecked (an
    // overflow panic in builds with overflow checks, found by `examples/fuzz_scenes.rs`).
    if bytes.starts_with(b"glTF") {
        let declared = bytes.get(8..12).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if declared.is_none_or(|n| n < 12) {
            return Err(invalid(format!("GLB header: declared length {declared:?} is shorter than the header")));
        }
    }
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| invalid(e.to_string()))?;
    let gltf::Gltf { document, blob } = gltf;
    // gltf-json 1.4.1's validation indexes a primitive's POSITION accessor before it
    // checks that it exists (a panic found by `examples/fuzz_scenes.rs`): check that first.
    let json = document.into_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(bad) = primitive.attributes.values().find(|a| a.value() >= json.accessors.len()) {
                return Err(invalid(format!("meshes[{m}].primitives[{p}]: accessor {} does not exist", bad.value())));
            }
        }
    }
    // gltf 1.4.1's `Image::source` unwraps a missing `uri` and a buffer view's missing
    // `mimeType` (panics found by `examples/fuzz_scenes.rs`): check both first.
    for (i, image) in json.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (Some(_), None, _) | (None, Some(_), Some(_)) => {}
            (None, Some(_), None) => return Err(invalid(format!("images[{i}]: a buffer view needs a mimeType"))),
            _ => return Err(invalid(format!("images[{i}]: needs either a uri or a bufferView"))),
        }
    }
    let document = gltf::Document::from_json(json).map_err(|e| invalid(e.to_string()))?;
    let buffers = load_buffers(&document, blob, path, read)?;
    let Some(gltf_scene) = document.default_scene().or_else(|| document.scenes().next()) else {
        return Err(fail("the file has no scene".into()));
    };

    let mut converter = Converter {
        path,
        buffers: &buffers,
        out: GltfScene::empty(),
        materials: HashMap::new(),
        read,
        images: HashMap::new(),
        instanced_meshes: HashMap::new(),
    };
    // Count the triangles the scene expands to before converting any.
    let mut triangles = 0u64;
    let mut mesh_uses: HashMap<usize, usize> = HashMap::new();
    walk(&gltf_scene, &mut |node, _| {
        if let Some(mesh) = node.mesh() {
            *mesh_uses.entry(mesh.index()).or_default() += 1;
            for p in mesh.primitives() {
                triangles += primitive_triangle_bound(&p);
            }
        }
        if triangles > MAX_TRIANGLES {
            return Err(fail(format!("the scene expands to more than {MAX_TRIANGLES} triangles")));
        }
        Ok(())
    })
    .map_err(|e| match e {
        WalkError::Revisited(node) => fail(revisited(node)),
        WalkError::Visit(e) => e,
    })?;
    converter.instanced_meshes = mesh_uses.into_iter().filter(|&(_, n)| n > 1).map(|(m, _)| (m, None)).collect();
    walk(&gltf_scene, &mut |node, world| converter.node(node, world)).map_err(|e| match e {
        WalkError::Revisited(node) => fail(revisited(node)),
        WalkError::Visit(e) => e,
    })?;

    let mut out = converter.out;
    let camera_count = document.cameras().count();
    if let Some(wanted) = &options.camera {
        let chosen = out.cameras.iter().find(|c| {
            wanted.parse::<usize>().is_ok_and(|i| i == c.index) || c.name.as_deref() == Some(wanted.as_str())
        });
        let Some(chosen) = chosen else {
            let known: Vec<String> = out
                .cameras
                .iter()
                .map(|c| match &c.name {
                    Some(n) => format!("{} ({n})", c.index),
                    None => c.index.to_string(),
                })
                .collect();
            let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
            return Err(fail(format!("no camera '{wanted}' in the scene (its cameras: {known})")));
        };
        let Some(camera) = chosen.camera else {
            return Err(fail(format!("camera '{wanted}' is orthographic; only perspective cameras are supported")));
        };
        out.scene.camera = Some(camera);
    } else {
        out.scene.camera = out.cameras.iter().find_map(|c| c.camera);
    }
    if out.cameras.len() < camera_count {
        out.notes
            .push(format!("{} of {camera_count} cameras are not placed by any node", camera_count - out.cameras.len()));
    }
    if out.scene.triangles.is_empty() && out.scene.instanced_triangle_count() == 0 {
        return Err(fail("the scene has no triangles".into()));
    }
    out.scene.validate().map_err(|e| fail(e.to_string()))?;
    Ok(out)
}

fn revisited(node: usize) -> String {
    format!("nodes[{node}] is reached twice: the node hierarchy must be trees (one parent per node, no cycles)")
}

impl GltfScene {
    fn empty() -> Self {
        Self { scene: Scene::default(), cameras: Vec::new(), notes: Vec::new() }
    }

    fn note(&mut self, note: String) {
        if !self.notes.contains(&note) {
            self.notes.push(note);
        }
    }
}

/// Reads each buffer: the binary chunk, a data URI, or a regular file next to the glTF.
fn load_buffers(
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    path: &Path,
    read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<Vec<gltf::buffer::Data>> {
    let fail = |message: String| Error::parse(path, message);
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let mut data = match buffer.source() {
            gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                let file: PathBuf = dir.join(percent_decode(uri));
                read(&file).map_err(|e| fail(format!("buffer {i}: cannot read {}: {e}", file.display())))?
            }
            source => {
                gltf::buffer::Data::from_source_and_blob(source, None, &mut blob)
                    .map_err(|e| fail(format!("buffer {i}: {e}")))?
                    .0
            }
        };
        if data.len() < buffer.length() {
            return Err(fail(format!("buffer {i}: {} bytes, but the file declares {}", data.len(), buffer.length())));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        buffers.push(gltf::buffer::Data(data));
    }
    Ok(buffers)
}

/// A URI's percent-escapes decoded (RFC 3986); a malformed escape is kept as written.
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2]))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Why a walk stopped.
enum WalkError {
    /// This node is reached a second time (a cycle, or a second parent).
    Revisited(usize),
    /// The visitor failed.
    Visit(Error),
}

/// Visits every node of `scene` depth-first with its world transform. The specification
/// requires the hierarchy to be disjoint trees; a node reached twice (a cycle or a second
/// parent, which could make a small file expand exponentially) stops the walk.
fn walk(
    scene: &gltf::Scene,
    visit: &mut dyn FnMut(&gltf::Node, Mat4) -> Result<()>,
) -> std::result::Result<(), WalkError> {
    let mut seen = std::collections::HashSet::new();
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        if !seen.insert(node.index()) {
            return Err(WalkError::Revisited(node.index()));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        visit(&node, world).map_err(WalkError::Visit)?;
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(())
}

/// An upper bound on the triangles a primitive makes (from its accessor counts).
fn primitive_triangle_bound(p: &gltf::Primitive) -> u64 {
    let count = p.indices().or_else(|| p.get(&gltf::Semantic::Positions)).map_or(0, |a| a.count()) as u64;
    match p.mode() {
        gltf::mesh::Mode::Triangles => count / 3,
        gltf::mesh::Mode::TriangleStrip | gltf::mesh::Mode::TriangleFan => count.saturating_sub(2),
        _ => 0,
    }
}

/// The conversion's state.
struct Converter<'a> {
    path: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    out: GltfScene,
    /// The scene's material index for each glTF material (None: glTF's default material).
    materials: HashMap<Option<usize>, u32>,
    /// Reads files the glTF names (buffers, images).
    read: &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    /// Decoded images by index (each decoded once, however many textures use it).
    images: HashMap<usize, Arc<TextureImage>>,
    /// Meshes that more than one node places, with their object once converted: they are
    /// instanced (two-level BVH) rather than copied.
    instanced_meshes: HashMap<usize, Option<u32>>,
}

impl Converter<'_> {
    fn fail(&self, message: String) -> Error {
        Error::parse(self.path, message)
    }

    /// Converts what `node` holds, placed by `world`.
    fn node(&mut self, node: &gltf::Node, world: Mat4) -> Result<()> {
        if !world.is_finite() {
            return Err(self.fail(format!("nodes[{}]: its transform is not finite", node.index())));
        }
        if let Some(mesh) = node.mesh() {
            match self.instanced_meshes.get(&mesh.index()).copied() {
                None => {
                    for p in mesh.primitives() {
                        self.primitive(&mesh, &p, world)?;
                    }
                }
                Some(object) => {
                    let object = match object {
                        Some(o) => o,
                        None => {
                            let o = self.object(&mesh)?;
                            self.instanced_meshes.insert(mesh.index(), Some(o));
                            o
                        }
                    };
                    let det = Mat3::from_mat4(world).determinant();
                    if det == 0.0 || !det.is_finite() {
                        // A collapsed placement has no surface to show.
                        return Ok(());
                    }
                    self.out
                        .scene
                        .place(object, world)
                        .map_err(|e| self.fail(format!("nodes[{}]: {e}", node.index())))?;
                }
            }
        }
        if let Some(camera) = node.camera() {
            let view = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let eye = world.transform_point3(Vec3::ZERO);
                    let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
                    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
                    let c = Camera { eye, center: eye + forward, up, fov_y_deg: p.yfov().to_degrees() };
                    c.validate().map_err(|e| self.fail(format!("cameras[{}]: {e}", camera.index())))?;
                    Some(c)
                }
                gltf::camera::Projection::Orthographic(_) => {
                    self.out.note("orthographic cameras are not supported".into());
                    None
                }
            };
            self.out.cameras.push(GltfCamera {
                index: camera.index(),
                name: camera.name().map(str::to_string),
                camera: view,
            });
        }
        if let Some(light) = node.light() {
            let at = |what: &str| {
                let name = light.name().map(|n| format!(" ({n})")).unwrap_or_default();
                format!("KHR_lights_punctual.lights[{}]{name}: {what}", light.index())
            };
            let position = world.transform_point3(Vec3::ZERO);
            let direction = world.transform_vector3(-Vec3::Z);
            let rgb = light.color().map(|c| c * light.intensity());
            let colour = Colour::illuminant_rgb(rgb).map_err(|e| self.fail(at(&e.to_string())))?;
            let l = match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => PunctualLight::point(position, colour),
                gltf::khr_lights_punctual::Kind::Directional => PunctualLight::directional(direction, colour),
                gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                    PunctualLight::spot(position, direction, colour, inner_cone_angle, outer_cone_angle)
                }
            };
            l.validate().map_err(|e| self.fail(at(&e)))?;
            if light.range().is_some() {
                self.out.note("light ranges are ignored (lights fall off by the inverse square law)".into());
            }
            self.out.scene.punctual_lights.push(l);
        }
        Ok(())
    }

    /// Converts one primitive of `mesh` into world-space triangles.
    /// Converts `mesh` once, in its own space, as an object for instances: its primitives
    /// are converted as usual, then moved from the scene's arrays into the object.
    fn object(&mut self, mesh: &gltf::Mesh) -> Result<u32> {
        let scene = &self.out.scene;
        let (vertices, triangles) = (scene.positions.len(), scene.triangles.len());
        for p in mesh.primitives() {
            self.primitive(mesh, &p, Mat4::IDENTITY)?;
        }
        let scene = &mut self.out.scene;
        let tail = |a: &mut Vec<[f32; 3]>| if a.len() > vertices { a.split_off(vertices) } else { Vec::new() };
        let object = crate::scene::SceneObject {
            positions: scene.positions.split_off(vertices),
            normals: tail(&mut scene.normals),
            tangents: tail(&mut scene.tangents),
            uvs: if scene.uvs.len() > vertices { scene.uvs.split_off(vertices) } else { Vec::new() },
            triangles: scene
                .triangles
                .split_off(triangles)
                .into_iter()
                .map(|t| t.map(|i| i - vertices as u32))
                .collect(),
            material_ids: scene.material_ids.split_off(triangles),
            punctual_lights: Vec::new(),
        };
        scene.objects.push(object);
        Ok(scene.objects.len() as u32 - 1)
    }

    fn primitive(&mut self, mesh: &gltf::Mesh, p: &gltf::Primitive, world: Mat4) -> Result<()> {
        let at = |what: String| {
            let name = mesh.name().map(|n| format!(" ({n})")).unwrap_or_default();
            format!("meshes[{}].primitives[{}]{name}: {what}", mesh.index(), p.index())
        };
        let mode = p.mode();
        if !matches!(
            mode,
            gltf::mesh::Mode::Triangles | gltf::mesh::Mode::TriangleStrip | gltf::mesh::Mode::TriangleFan
        ) {
            self.out.note(format!("{mode:?} primitives are skipped (only triangles render)"));
            return Ok(());
        }
        // The gltf crate's reader trusts an accessor's type (it asserts or hits
        // `unreachable!` on others: found by `examples/fuzz_scenes.rs`): check it first.
        use gltf::accessor::{DataType, Dimensions};
        let vec3_f32 = |a: &gltf::Accessor| a.data_type() == DataType::F32 && a.dimensions() == Dimensions::Vec3;
        for (semantic, accessor) in p.attributes() {
            let (t, d) = (accessor.data_type(), accessor.dimensions());
            let needs_vec3 = matches!(semantic, gltf::Semantic::Positions | gltf::Semantic::Normals);
            if needs_vec3 && !vec3_f32(&accessor) {
                return Err(self.fail(at(format!("{semantic:?} must be VEC3 of 32-bit floats, not {d:?} of {t:?}"))));
            }
            let texture_type = matches!(t, DataType::F32 | DataType::U8 | DataType::U16) && d == Dimensions::Vec2;
            if semantic == gltf::Semantic::TexCoords(0) && !texture_type {
                let m = format!("TEXCOORD_0 must be VEC2 of floats or normalised bytes or shorts, not {d:?} of {t:?}");
                return Err(self.fail(at(m)));
            }
        }
        if let Some(a) = p.indices() {
            let integer = matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32);
            if !integer || a.dimensions() != Dimensions::Scalar {
                let (t, d) = (a.data_type(), a.dimensions());
                return Err(self.fail(at(format!("indices must be unsigned integer scalars, not {d:?} of {t:?}"))));
            }
        }
        let used = [
            p.get(&gltf::Semantic::Positions),
            p.get(&gltf::Semantic::Normals),
            p.get(&gltf::Semantic::TexCoords(0)),
            p.indices(),
        ];
        for a in used.into_iter().flatten() {
            self.accessor_in_bounds(&a).map_err(|e| self.fail(at(format!("accessor {}: {e}", a.index()))))?;
        }
        let buffers = self.buffers;
        let reader = p.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
        let Some(positions) = reader.read_positions() else {
            return Err(self.fail(at("no POSITION attribute (or its accessor is not 32-bit float)".into())));
        };
        let positions: Vec<Vec3> = positions.map(|p| world.transform_point3(Vec3::from_array(p))).collect();
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(self.fail(at("a position is not finite".into())));
        }
        let n = positions.len();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(self.fail(at(format!("index {bad} is out of range ({n} vertices)"))));
        }
        let linear = Mat3::from_mat4(world);
        let mirrored = linear.determinant() < 0.0;
        let mut triangles = triangulate(mode, &indices);
        if mirrored {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        let normal_matrix = linear.inverse().transpose();
        let normals: Vec<Vec3> = match reader.read_normals() {
            Some(normals) => normals.map(|v| (normal_matrix * Vec3::from_array(v)).normalize_or_zero()).collect(),
            None => Vec::new(),
        };
        // Unusable normals (wrong count, zero or not finite) leave the primitive flat-shaded.
        let normals = if normals.len() == n && normals.iter().all(|v| v.is_finite() && *v != Vec3::ZERO) {
            normals
        } else {
            Vec::new()
        };
        let uvs: Vec<glam::Vec2> = match reader.read_tex_coords(0) {
            Some(t) => t.into_f32().map(glam::Vec2::from).collect(),
            None => Vec::new(),
        };
        let uvs = if uvs.len() == n && uvs.iter().all(|uv| uv.is_finite()) { uvs } else { Vec::new() };
        let material = self.material(p.material())?;
        let m = Mesh { positions, normals, tangents: Vec::new(), uvs, triangles };
        if !m.triangles.is_empty() {
            self.out.scene.add_with_material(&m, material);
        }
        Ok(())
    }

    /// Checks that an accessor's bytes lie inside its buffer view and that inside its
    /// buffer: the gltf crate's reader slices and asserts without checking (panics found
    /// by `examples/fuzz_scenes.rs`).
    fn accessor_in_bounds(&self, a: &gltf::Accessor) -> std::result::Result<(), String> {
        let elem = a.size();
        if a.count() == 0 {
            // The specification requires ≥ 1; the reader computes count − 1 unchecked.
            return Err("count is 0".into());
        }
        let span = |view: &gltf::buffer::View, offset: usize, stride: usize, n: usize| {
            let data = self.buffers.get(view.buffer().index()).map_or(0, |d| d.0.len());
            if view.offset().checked_add(view.length()).is_none_or(|end| end > data) {
                return Err(format!("bufferView {} ends past its buffer ({data} bytes)", view.index()));
            }
            if stride < elem {
                return Err(format!("byteStride {stride} is less than the element size {elem}"));
            }
            let end = match n {
                0 => Some(0),
                n => (n - 1).checked_mul(stride).and_then(|b| b.checked_add(offset)).and_then(|b| b.checked_add(elem)),
            };
            match end {
                Some(end) if end <= view.length() => Ok(()),
                _ => Err(format!("{n} elements overrun bufferView {} ({} bytes)", view.index(), view.length())),
            }
        };
        if let Some(view) = a.view() {
            span(&view, a.offset(), view.stride().unwrap_or(elem), a.count())?;
        }
        if a.sparse().is_some() {
            // (Rare in static geometry; the reader's sparse path does unchecked arithmetic.)
            return Err("sparse accessors are not supported".into());
        }
        Ok(())
    }

    /// The scene's index of a glTF material, converting it on first use.
    fn material(&mut self, m: gltf::Material) -> Result<u32> {
        if let Some(&id) = self.materials.get(&m.index()) {
            return Ok(id);
        }
        let material = self.convert_material(&m)?;
        let id = self.out.scene.materials.len() as u32;
        self.out.scene.materials.push(material);
        self.materials.insert(m.index(), id);
        Ok(id)
    }

    fn convert_material(&mut self, m: &gltf::Material) -> Result<Material> {
        let name = match (m.index(), m.name()) {
            (_, Some(name)) => name.to_string(),
            (Some(i), None) => format!("material {i}"),
            (None, None) => "(default)".to_string(),
        };
        let path = self.path;
        let fail = |what: String| Error::parse(path, format!("material '{name}': {what}"));
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let base = [r, g, b];
        let roughness = pbr.roughness_factor();
        let ior = m.ior().unwrap_or(1.5);
        let metallic = pbr.metallic_factor();
        // Transmission applies to the dielectric part only (the specification mixes it
        // under `metallic`): a surface mostly transmissive renders as a dielectric.
        let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
        let transmissive = transmission * (1.0 - metallic) >= 0.5;
        let (model, params) = if transmissive {
            let mut params = vec![("ior", ParamValue::Scalar(ior)), ("tint", ParamValue::Rgb(base))];
            if roughness > 0.0 {
                params.push(("alpha", ParamValue::Scalar(roughness * roughness)));
                (ModelId::RoughDielectric, params)
            } else {
                if let Some(volume) = m.volume() {
                    let distance = volume.attenuation_distance();
                    let colour = volume.attenuation_color();
                    if distance.is_finite() && distance > 0.0 && colour.iter().any(|&c| c < 1.0) {
                        // Beer–Lambert: the colour remains after `distance`, σ = −ln(c)/d.
                        let sigma = colour.map(|c| -(c.max(1e-6)).ln() / distance);
                        params.push(("absorption", ParamValue::Rgb(sigma)));
                    }
                }
                (ModelId::Dielectric, params)
            }
        } else {
            let params = vec![
                ("base_color", ParamValue::Rgb(base)),
                ("metallic", ParamValue::Scalar(metallic)),
                ("roughness", ParamValue::Scalar(roughness)),
                ("ior", ParamValue::Scalar(ior)),
            ];
            (ModelId::MetallicRoughness, params)
        };
        let mut material = Material::builtin(&name, model, &params).map_err(|e| fail(e.to_string()))?;
        let slots = material.params().map_or(TextureSlots::NONE, |p| p.texture_slots());
        let mut textures = MaterialTextures::default();
        if let Some(info) = pbr.base_color_texture() {
            if slots.base_colour {
                textures.base_colour = self.texture_info(&name, &info, Encoding::Srgb)?;
            } else {
                self.out.note(format!("material '{name}': base colour texture not applied to a {}", model.name()));
            }
        }
        if let Some(info) = pbr.metallic_roughness_texture() {
            if slots.metallic_roughness {
                textures.metallic_roughness = self.texture_info(&name, &info, Encoding::Linear)?;
            } else {
                self.out
                    .note(format!("material '{name}': metallic-roughness texture not applied to a {}", model.name()));
            }
        }
        if let Some(normal) = m.normal_texture() {
            let map = self.texture(&name, &normal.texture(), normal.tex_coord(), None, Encoding::Linear)?;
            textures.normal = map.map(|map| NormalMap { map, scale: normal.scale() });
        }
        if m.transmission().is_some_and(|t| t.transmission_texture().is_some()) {
            self.out.note(format!(
                "material '{name}': its transmission texture is not applied (the transmission factor decides)"
            ));
        }
        if m.occlusion_texture().is_some() {
            self.out.note("occlusion textures are not applied (paths find occlusion themselves)".into());
        }
        let strength = m.emissive_strength().unwrap_or(1.0);
        let emissive = m.emissive_factor().map(|c| c * strength);
        if let Some(info) = m.emissive_texture() {
            textures.emissive = self.texture_info(&name, &info, Encoding::Srgb)?;
        }
        let emissive_texture_missing = m.emissive_texture().is_some() && textures.emissive.is_none();
        if emissive.iter().any(|&c| c != 0.0) && !emissive_texture_missing {
            material.emission = Some(Colour::illuminant_rgb(emissive).map_err(|e| fail(format!("emission: {e}")))?);
        }
        let mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        if mode != AlphaMode::Opaque {
            let map = textures.base_colour.clone().filter(|m| m.image.has_alpha());
            textures.alpha = Some(Alpha { mode, factor: alpha, map });
        }
        material = material.with_textures(textures);
        let mixed = transmission * (1.0 - metallic);
        if mixed > 0.0 && mixed < 1.0 {
            let as_what = if transmissive { "fully transmissive" } else { "opaque" };
            self.out.note(format!(
                "material '{name}': transmission {transmission} at metallic {metallic} rendered {as_what} (no partial mix yet)"
            ));
        }
        Ok(material)
    }

    /// The texture a material's texture reference names, with its transform.
    fn texture_info(
        &mut self,
        material: &str,
        info: &gltf::texture::Info,
        encoding: Encoding,
    ) -> Result<Option<TextureMap>> {
        let transform = info.texture_transform();
        let tex_coord = transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
        self.texture(material, &info.texture(), tex_coord, transform, encoding)
    }

    /// A glTF texture as a map: its image decoded (once), its sampler's wrap modes and
    /// `KHR_texture_transform` (glTF's uv' = T · R · S · uv, rotation counter-clockwise
    /// in uv space); `None`, with a note, for texture coordinates other than
    /// `TEXCOORD_0`.
    fn texture(
        &mut self,
        material: &str,
        texture: &gltf::Texture,
        tex_coord: u32,
        transform: Option<gltf::texture::TextureTransform>,
        encoding: Encoding,
    ) -> Result<Option<TextureMap>> {
        if tex_coord != 0 {
            self.out.note(format!(
                "material '{material}': a texture on TEXCOORD_{tex_coord} is not applied (only TEXCOORD_0 is read)"
            ));
            return Ok(None);
        }
        let image = self.image(material, &texture.source())?;
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        };
        let sampler = texture.sampler();
        let mut map = TextureMap::new(image, encoding);
        map.wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
        if let Some(t) = transform {
            map.transform = crate::texture::khr_texture_transform(t.offset(), t.rotation(), t.scale());
            if !map.transform.is_finite() {
                return Err(self.fail(format!("material '{material}': KHR_texture_transform is not finite")));
            }
        }
        Ok(Some(map))
    }

    /// `images[i]` decoded: from a buffer view, a data URI or a file next to the glTF.
    fn image(&mut self, material: &str, image: &gltf::Image) -> Result<Arc<TextureImage>> {
        let i = image.index();
        if let Some(decoded) = self.images.get(&i) {
            return Ok(decoded.clone());
        }
        let fail = |message: String| Error::Texture {
            material: material.into(),
            texture: format!("{}: images[{i}]", self.path.display()),
            message,
        };
        let bytes = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let data = self.buffers.get(view.buffer().index()).map_or(&[][..], |d| &d.0[..]);
                let range = view.offset()..view.offset().saturating_add(view.length());
                data.get(range)
                    .ok_or_else(|| fail(format!("bufferViews[{}] lies outside its buffer", view.index())))?
                    .to_vec()
            }
            gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
                gltf::buffer::Data::from_source_and_blob(gltf::buffer::Source::Uri(uri), None, &mut None)
                    .map_err(|e| fail(format!("data URI: {e}")))?
                    .0
            }
            gltf::image::Source::Uri { uri, .. } => {
                let file = self.path.parent().unwrap_or(Path::new("")).join(percent_decode(uri));
                (self.read)(&file).map_err(|e| fail(format!("cannot read {}: {e}", file.display())))?
            }
        };
        let decoded = Arc::new(TextureImage::decode(&bytes).map_err(fail)?);
        self.images.insert(i, decoded.clone());
        Ok(decoded)
    }
}

/// Triangles from a primitive's index list: lists as they are, strips with alternating
/// winding fixed (glTF/OpenGL order), fans around the first vertex; degenerate triangles
/// (a repeated vertex) dropped.
fn triangulate(mode: gltf::mesh::Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    let tris: Vec<[u32; 3]> = match mode {
        gltf::mesh::Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        gltf::mesh::Mode::TriangleFan => (2..indices.len()).map(|i| [indices[0], indices[i - 1], indices[i]]).collect(),
        _ => indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    };
    tris.into_iter().filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]).collect()
}

#[cfg(test)]
mod tests;
