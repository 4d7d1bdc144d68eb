//! Wavefront OBJ/MTL scenes: OBJ geometry assembled by `tobj`, MTL libraries read by our
//! own parser ([`crate::mtl`]; tobj never parses an MTL file).
//!
//! Material mapping (the thesis's other MTL extensions come with the loaders issue):
//! * `Ke` > 0 → a one-sided area light of radiance `Ke` (front = counter-clockwise);
//! * `bsdf NAME` (our extension) picks any built-in model by name;
//! * the thesis's extensions: `rough`/`p` → Schlick 1994, `nu`/`nv`/`Rs`/`Rd` →
//!   Shirley–Ashikhmin 2000;
//! * the PBR extension's `Pr`/`Pm` → glTF's metallic–roughness model (`Kd` its base colour);
//! * else `illum` 4, 6, 7, or opacity < 1 (`d`, else 1 − `Tr`) → smooth dielectric;
//! * `illum` 3 or 5 → perfect mirror;
//! * otherwise → Lambertian.
//!
//! Each model's parameters are read from the MTL statements its declaration names
//! (`mtl_key`: e.g. `Kd` for Lambert's reflectance, `Ks` for the mirror's, `Ni` and `Tf`
//! for the dielectric), range-checked, and defaulted where absent (Lambert 0.5 grey,
//! Mitsuba's default). A one-value colour (`Kd 0.5`) is that grey. Every error in an MTL
//! value names the file and line (`scene.mtl:7: material 'floor': …`).
//!
//! Faces are fan-triangulated. Before `tobj` sees the OBJ, a line-by-line pass reports
//! the first malformed or non-finite `v`/`vn`/`vt`/`f` line with its number (which
//! tobj's errors lack) and hands tobj only what it reads without error or panic: index
//! references checked against the vertices defined so far, comments cut, vertex colours
//! and polylines (`l`, which tobj turns into triangles) dropped. Everything the loader
//! allocates is then proportional to the input's size (the fuzzer,
//! `examples/fuzz_obj.rs`, measures at most ~72 bytes per input byte): faces can only
//! reference vertices the text defines, and each MTL library is parsed once however
//! often, and by whatever path, `mtllib` names it.

use crate::material::{Material, ModelId};
use crate::mesh::Mesh;
use crate::mtl::{self, MtlMaterial, Numbers, Statement, quote, shorten};
use crate::scene::Scene;
use crate::texture::{
    Alpha, AlphaMode, BumpMap, Encoding, MaterialTextures, NormalMap, TextureCache, TextureMap, Wrap,
};
use crate::{Error, Result};
use brdf::params::ParamValue;
use glam::Vec3;
use spectral::spectrum::Colour;
use std::cell::RefCell;
use std::collections::HashSet;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

/// Albedo of faces without a material.
pub const DEFAULT_ALBEDO: f32 = 0.5;

/// Loads an OBJ file and the MTL libraries it names.
pub fn load_obj(path: &Path) -> Result<Scene> {
    load_obj_text(&read_text_file(path)?, path, &read_text)
}

/// [`read_text`] with the error naming the file: how every text scene format (OBJ, MTL,
/// scene files, SPEC files) is read.
pub(crate) fn read_text_file(path: &Path) -> Result<String> {
    read_text(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })
}

/// A scene file's text (invalid UTF-8 replaced). Only regular files: a mutated `mtllib`
/// can name anything, and a FIFO would block and `/dev/zero` never end.
fn read_text(path: &Path) -> std::io::Result<String> {
    let bytes = read_file_bytes(path)?;
    Ok(match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    })
}

/// A regular file's bytes: a name from a scene file can name anything, and a FIFO would
/// block and `/dev/zero` never end.
pub(crate) fn read_file_bytes(path: &Path) -> std::io::Result<Vec<u8>> {
    if !std::fs::metadata(path)?.is_file() {
        return Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file"));
    }
    std::fs::read(path)
}

/// Loads an OBJ scene from its text, without touching the disk: `path` names the OBJ in
/// messages and is what `mtllib` names are resolved against; `read_mtl` returns the text
/// of such a resolved MTL path. [`load_obj`] reads files through it; a fuzzer or a test
/// drives the whole loader from memory. Never panics: malformed input is an error.
pub fn load_obj_text(text: &str, path: &Path, read_mtl: &dyn Fn(&Path) -> std::io::Result<String>) -> Result<Scene> {
    load_obj_text_with(text, path, read_mtl, &read_file_bytes)
}

/// [`load_obj_text`] with texture images read by `read_image` too (resolved paths in,
/// bytes out): the whole loader driven from memory.
pub fn load_obj_text_with(
    text: &str,
    path: &Path,
    read_mtl: &dyn Fn(&Path) -> std::io::Result<String>,
    read_image: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<Scene> {
    let obj_error = |line: Option<usize>, message: String| Error::Parse { path: path.to_path_buf(), line, message };
    let PreparedObj { text: tobj_text, mtllibs } =
        prepare_obj(text).map_err(|(line, message)| obj_error(Some(line), message))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    // The libraries in the order tobj merged them (tobj's material ids index their
    // concatenation), and the first library that failed.
    let libraries: RefCell<Vec<Library>> = RefCell::new(Vec::new());
    let failure: RefCell<Option<Error>> = RefCell::new(None);
    // The paths and texts of the libraries read so far.
    let seen: RefCell<(HashSet<PathBuf>, HashSet<String>)> = RefCell::default();
    let load_library = |name: &Path| -> tobj::MTLLoadResult {
        let path = dir.join(name);
        if failure.borrow().is_some() {
            return Err(tobj::LoadError::MaterialParseError);
        }
        // A library named again, by the same path or by another to the same text, is
        // not parsed again: a mutated OBJ can name one library in every line. (Its names
        // keep the materials they map to, even where a library between redefined them.)
        if !seen.borrow_mut().0.insert(path.clone()) {
            return Ok(Default::default());
        }
        let text = match read_mtl(&path) {
            Ok(text) => text,
            Err(e) => {
                // The fault is the `mtllib` statement's: name its line.
                let line = mtllibs.iter().find(|(_, n)| Path::new(n) == name).map(|&(line, _)| line);
                let shown = shorten(&path.display().to_string(), 200).into_owned();
                *failure.borrow_mut() = Some(obj_error(line, format!("mtllib: cannot read {shown}: {e}")));
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        if seen.borrow().1.contains(&text) {
            return Ok(Default::default());
        }
        let parsed = mtl::parse_mtl(&text);
        seen.borrow_mut().1.insert(text);
        match parsed {
            Ok(materials) => {
                // tobj only maps `usemtl` names to ids; the last of a repeated name wins.
                let ids = materials.iter().enumerate().map(|(i, m)| (m.name.clone(), i)).collect();
                let named = materials.iter().map(|m| tobj::Material { name: m.name.clone(), ..Default::default() });
                let named = named.collect();
                libraries.borrow_mut().push(Library { path, materials });
                Ok((named, ids))
            }
            Err(e) => {
                *failure.borrow_mut() = Some(Error::Parse { path, line: Some(e.line), message: e.message });
                Err(tobj::LoadError::MaterialParseError)
            }
        }
    };
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    // The last line of defence: `prepare_obj` hands tobj only input it reads without
    // panicking (the fuzzer finds none), but should a tobj panic remain, it becomes an
    // error naming the file rather than taking the caller down. (The panic hook still
    // prints it.)
    let loaded =
        catch_unwind(AssertUnwindSafe(|| tobj::load_obj_buf(&mut tobj_text.as_bytes(), &options, load_library)));
    if let Some(e) = failure.into_inner() {
        return Err(e);
    }
    let models = match loaded {
        Ok(Ok((models, _))) => models,
        Ok(Err(e)) => return Err(obj_error(None, e.to_string())),
        Err(panic) => {
            let what = crate::panic_message(panic.as_ref());
            return Err(obj_error(None, format!("the OBJ reader (tobj) panicked: {}", quote(&what))));
        }
    };
    let mut converted = Vec::new();
    let mut textures = TextureCache::default();
    for library in libraries.into_inner() {
        for m in &library.materials {
            converted.push(to_material(&library.path, m, &mut textures, read_image)?);
        }
    }
    let default = MtlMaterial {
        name: "(default)".into(),
        line: 0,
        statements: vec![Statement { key: "Kd".into(), values: DEFAULT_ALBEDO.to_string(), line: 0 }],
    };
    let default = to_material(path, &default, &mut textures, read_image)?;
    let mut scene = Scene::default();
    for model in &models {
        let mesh = &model.mesh;
        let vec3s = |v: &[f32]| -> Vec<Vec3> { v.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect() };
        let normals = if mesh.normals.len() == mesh.positions.len() { vec3s(&mesh.normals) } else { Vec::new() };
        // OBJ's v grows upwards; the scene's (glTF's) downwards.
        let uvs = if 3 * mesh.texcoords.len() == 2 * mesh.positions.len() {
            mesh.texcoords.chunks_exact(2).map(|t| glam::Vec2::new(t[0], 1.0 - t[1])).collect()
        } else {
            Vec::new()
        };
        let m = Mesh {
            positions: vec3s(&mesh.positions),
            normals,
            tangents: Vec::new(),
            uvs,
            triangles: mesh.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        };
        if m.triangles.is_empty() {
            continue;
        }
        let material = mesh.material_id.and_then(|i| converted.get(i)).cloned().unwrap_or_else(|| default.clone());
        scene.add(&m, material);
    }
    Ok(scene)
}

/// An MTL library as loaded for one OBJ.
struct Library {
    /// Where `mtllib` found it.
    path: PathBuf,
    /// Its materials.
    materials: Vec<MtlMaterial>,
}

/// An MTL material as a [`Material`]: the model chosen as the module doc says, its
/// parameters read from the statements its declaration names. The one place this module
/// uses the material API (`Material::builtin`, `ModelId`, the parameter
/// declarations), so that changes there touch one function. Errors name `lib`, the
/// line and the material.
fn to_material(
    lib: &Path,
    m: &MtlMaterial,
    cache: &mut TextureCache,
    read_image: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<Material> {
    let at = |line: usize, message: String| Error::Parse {
        path: lib.to_path_buf(),
        line: Some(line),
        message: format!("material '{}': {message}", m.name),
    };
    let syntax = |e: mtl::MtlError| at(e.line, e.message);
    let emission = match m.get("Ke") {
        Some(ke) => {
            let rgb = ke.colour().map_err(syntax)?;
            if rgb.iter().any(|&v| v != 0.0) {
                Some(Colour::illuminant_rgb(rgb).map_err(|e| at(ke.line, e.to_string()))?)
            } else {
                None
            }
        }
        None => None,
    };
    let model = if let Some(bsdf) = m.get("bsdf") {
        let name = bsdf.values.trim();
        ModelId::by_name(name)
            .ok_or_else(|| at(bsdf.line, format!("unknown bsdf '{}' (known: {})", quote(name), ModelId::names())))?
    } else if ["nu", "nv", "Rs", "Rd"].iter().any(|k| m.has(k)) {
        // The thesis's MTL extensions name their model by its parameters.
        ModelId::Ashikhmin
    } else if ["rough", "p"].iter().any(|k| m.has(k)) {
        ModelId::Schlick
    } else if ["Pr", "Pm"].iter().any(|k| m.has(k)) {
        // The PBR extension of MTL (roughness `Pr`, metalness `Pm`, as Blender and
        // Clara.io write them) is glTF's metallic–roughness model.
        ModelId::MetallicRoughness
    } else {
        let illum = m.get("illum").map(Statement::illum).transpose().map_err(syntax)?.unwrap_or(2);
        let opacity = m.dissolve().map_err(syntax)?.unwrap_or(1.0);
        // With `map_d`, `d` scales a cut-out's alpha rather than making glass.
        if matches!(illum, 4 | 6 | 7) || (opacity < 1.0 && !m.has("map_d")) {
            ModelId::Dielectric
        } else if matches!(illum, 3 | 5) {
            ModelId::Mirror
        } else {
            ModelId::Lambert
        }
    };
    let mut params = Vec::new();
    let mut lines = Vec::new();
    for p in model.def().params {
        let Some(statement) = p.mtl_key.and_then(|key| m.get(key)) else { continue };
        let value = match statement.key.as_str() {
            "Ka" | "Kd" | "Ks" | "Ke" | "Tf" => ParamValue::Rgb(statement.colour().map_err(syntax)?),
            "Ns" | "Ni" | "d" | "Tr" => ParamValue::Scalar(statement.scalar().map_err(syntax)?),
            _ => match statement.one_or_three().map_err(syntax)? {
                Numbers::One(v) => ParamValue::Scalar(v),
                Numbers::Three(rgb) => ParamValue::Rgb(rgb),
            },
        };
        params.push((p.name, value));
        lines.push((p.name, statement.line));
    }
    let mut material = Material::builtin(&m.name, model, &params).map_err(|e| {
        // The message names the material already; add where the value came from.
        let line = lines.iter().find(|(name, _)| Some(*name) == e.param()).map_or(m.line, |&(_, line)| line);
        Error::Parse { path: lib.to_path_buf(), line: Some(line), message: e.to_string() }
    })?;
    material.emission = emission;
    let textures = material_textures(lib, m, &material, cache, read_image)?;
    Ok(material.with_textures(textures))
}

/// The texture maps an MTL material names, read relative to its library: `map_Kd` and
/// `map_Ks` where the model has a base or specular colour to multiply (ignored
/// otherwise), `map_d` as stochastic transparency times `d`, `norm`/`map_Kn` as a
/// tangent-space normal map (`-bm` scales its slopes) and `bump`/`map_bump` as a height
/// map (`-bm` world units per unit of height). A missing or unreadable image is an error
/// naming the material and the file.
fn material_textures(
    lib: &Path,
    m: &MtlMaterial,
    material: &Material,
    cache: &mut TextureCache,
    read_image: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
) -> Result<MaterialTextures> {
    let dir = lib.parent().unwrap_or(Path::new(""));
    let slots = material.params().map_or(brdf::TextureSlots::NONE, |p| p.texture_slots());
    let mut map = |key: &str, encoding: Encoding| -> Result<Option<(TextureMap, f32)>> {
        let Some(statement) = m.get(key) else { return Ok(None) };
        let t = statement.texture().map_err(|e| Error::Parse {
            path: lib.to_path_buf(),
            line: Some(e.line),
            message: format!("material '{}': {}", m.name, e.message),
        })?;
        // A texture that cannot be read is named with the statement's line.
        let image = cache.load_with(&dir.join(t.file.replace('\\', "/")), &m.name, read_image).map_err(|e| {
            Error::Parse { path: lib.to_path_buf(), line: Some(statement.line), message: e.to_string() }
        })?;
        let mut map = TextureMap::new(image, encoding);
        if t.clamp {
            map.wrap = [Wrap::Clamp; 2];
        }
        if t.offset[..2] != [0.0; 2] || t.scale[..2] != [1.0; 2] {
            // uv' = uv·s + o in OBJ's coordinates (v upwards); ours have v' = 1 − v.
            let [su, sv, _] = t.scale;
            let [ou, ov, _] = t.offset;
            map.transform = glam::Mat3::from_cols(
                Vec3::new(su, 0.0, 0.0),
                Vec3::new(0.0, sv, 0.0),
                Vec3::new(ou, 1.0 - sv - ov, 1.0),
            );
        }
        Ok(Some((map, t.bump)))
    };
    let mut textures = MaterialTextures::default();
    if slots.base_colour {
        textures.base_colour = map("map_Kd", Encoding::Srgb)?.map(|(m, _)| m);
    }
    if slots.specular {
        textures.specular = map("map_Ks", Encoding::Srgb)?.map(|(m, _)| m);
    }
    if let Some((map, _)) = map("map_d", Encoding::Linear)? {
        let factor = m.dissolve().ok().flatten().unwrap_or(1.0);
        textures.alpha = Some(Alpha { mode: AlphaMode::Blend, factor, map: Some(map) });
    }
    let normal = if m.has("norm") { "norm" } else { "map_Kn" };
    textures.normal = map(normal, Encoding::Linear)?.map(|(map, scale)| NormalMap { map, scale });
    let bump = if m.has("map_bump") { "map_bump" } else { "bump" };
    textures.bump = map(bump, Encoding::Linear)?.map(|(map, scale)| BumpMap { map, scale });
    Ok(textures)
}

/// Checks an OBJ text line by line and returns the text `tobj` is given, or the first
/// malformed line (1-based) and what is wrong with it.
///
/// The text for tobj keeps one line per input line and holds only what tobj reads
/// without error or panic: `v` as x y z [w] (vertex colours dropped: a file that colours
/// only some vertices makes tobj fail), `vt` with two numbers (`vt u` is `vt u 0`),
/// `vn`, faces whose references all resolve, `o`/`g`, and `usemtl`/`mtllib` with a name;
/// comments, polylines, points and other statements become empty lines.
fn prepare_obj(text: &str) -> std::result::Result<PreparedObj<'_>, (usize, String)> {
    let mut out = String::with_capacity(text.len() + text.len() / 8);
    let mut mtllibs = Vec::new();
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let (key, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let fail = |message: String| (i + 1, message);
        match key {
            "v" => {
                let (n, v) = numbers(rest, "vertex").map_err(fail)?;
                if !matches!(n, 3 | 4 | 6) {
                    return Err(fail(format!(
                        "vertex: expected 3 numbers (x y z), 4 (x y z w) or 6 (x y z r g b), found {n}"
                    )));
                }
                let kept = if n == 4 { 4 } else { 3 };
                if kept == 4 && (v[3] == 0.0 || v[..3].iter().any(|c| !(c / v[3]).is_finite())) {
                    return Err(fail(format!("vertex: w = {} makes a coordinate infinite", v[3])));
                }
                push_statement(&mut out, "v", rest.split_whitespace().take(kept));
                nv += 1;
            }
            "vn" => {
                match numbers(rest, "normal").map_err(fail)? {
                    (3, _) => push_statement(&mut out, "vn", rest.split_whitespace().take(3)),
                    (n, _) => return Err(fail(format!("normal: expected 3 numbers, found {n}"))),
                }
                nn += 1;
            }
            "vt" => {
                match numbers(rest, "texture coordinate").map_err(fail)? {
                    (1, _) => push_statement(&mut out, "vt", rest.split_whitespace().take(1).chain(["0"])),
                    (2 | 3, _) => push_statement(&mut out, "vt", rest.split_whitespace().take(2)),
                    (n, _) => return Err(fail(format!("texture coordinate: expected 1–3 numbers, found {n}"))),
                }
                nt += 1;
            }
            "f" => {
                check_face(rest, nv, nt, nn).map_err(fail)?;
                push_statement(&mut out, "f", corners(rest));
            }
            "usemtl" | "mtllib" => {
                let name = rest.trim();
                if name.is_empty() {
                    return Err(fail(format!("{key}: missing name")));
                }
                push_statement(&mut out, key, [name]);
                if key == "mtllib" {
                    mtllibs.push((i + 1, name));
                }
            }
            "o" | "g" => push_statement(&mut out, key, [rest.trim()]),
            _ => {}
        }
        out.push('\n');
    }
    Ok(PreparedObj { text: out, mtllibs })
}

/// What [`prepare_obj`] makes of an OBJ text.
struct PreparedObj<'a> {
    /// The text for tobj.
    text: String,
    /// Each `mtllib` statement's line and name, for messages.
    mtllibs: Vec<(usize, &'a str)>,
}

/// Appends `key` and its values, space-separated (no newline).
fn push_statement<'a>(out: &mut String, key: &str, values: impl IntoIterator<Item = &'a str>) {
    out.push_str(key);
    for v in values {
        out.push(' ');
        out.push_str(v);
    }
}

/// How many numbers `rest` holds (up to a comment) and the first four, or why one is not
/// a finite number.
fn numbers(rest: &str, what: &str) -> std::result::Result<(usize, [f32; 4]), String> {
    let mut first = [0.0f32; 4];
    let mut n = 0;
    for tok in rest.split_whitespace() {
        if tok.starts_with('#') {
            break;
        }
        let v: f32 = tok.parse().map_err(|_| format!("{what}: '{}' is not a number", quote(tok)))?;
        if !v.is_finite() {
            return Err(format!("{what}: '{}' is not finite", quote(tok)));
        }
        if n < 4 {
            first[n] = v;
        }
        n += 1;
    }
    Ok((n, first))
}

/// A face's corner tokens, up to a comment.
fn corners(rest: &str) -> impl Iterator<Item = &str> {
    rest.split_whitespace().take_while(|t| !t.starts_with('#'))
}

/// The first malformed geometry line of an OBJ text: (1-based line, message).
pub fn check_obj_text(text: &str) -> Option<(usize, String)> {
    prepare_obj(text).err()
}

/// Checks one face: at least three corners, each `v`, `v/vt`, `v//vn` or `v/vt/vn` with
/// indices (1-based, or negative: relative to the end) among those defined so far.
fn check_face(rest: &str, nv: i64, nt: i64, nn: i64) -> std::result::Result<(), String> {
    let n = corners(rest).count();
    if n < 3 {
        return Err(format!("face: needs at least 3 vertices, found {n}"));
    }
    for c in corners(rest) {
        let invalid = || format!("face: '{}' is not a valid vertex reference", quote(c));
        if c.split('/').count() > 3 {
            return Err(invalid());
        }
        let defined = [(nv, "vertex"), (nt, "texture coordinate"), (nn, "normal")];
        for (k, (part, (defined, what))) in c.split('/').zip(defined).enumerate() {
            if part.is_empty() && k > 0 {
                continue;
            }
            let idx: i64 = part.parse().map_err(|_| invalid())?;
            let resolved = if idx < 0 { defined + idx } else { idx - 1 };
            if idx == 0 || resolved < 0 || resolved >= defined {
                return Err(format!("face: {what} index {idx} is out of range (only {defined} defined so far)"));
            }
        }
    }
    Ok(())
}

/// The first malformed statement of an MTL text: (1-based line, message).
pub fn check_mtl_text(text: &str) -> Option<(usize, String)> {
    mtl::parse_mtl(text).err().map(|e| (e.line, e.message))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_bad_line() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 1 x 0\n";
        assert_eq!(check_obj_text(obj).map(|(l, _)| l), Some(5));
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
        let (line, msg) = check_obj_text(obj).unwrap();
        assert_eq!(line, 4);
        assert!(msg.contains("out of range"), "{msg}");
        assert_eq!(check_obj_text("v 0 0 nan\n").map(|(l, _)| l), Some(1));
        assert_eq!(check_obj_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1/1 2/2 3/3\n").map(|(l, _)| l), Some(5));
        assert_eq!(check_obj_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 # c\n"), None);
        assert_eq!(check_obj_text("f 1 2\n").map(|(l, _)| l), Some(1));
        assert_eq!(check_mtl_text("newmtl a\nKd 0.5 0.5 zz\n").map(|(l, _)| l), Some(2));
        assert_eq!(check_mtl_text("newmtl a\nKd 0.5 0.5 0.5\nillum 2\n"), None);
    }
}

#[cfg(test)]
mod obj_tests {
    use super::*;

    /// A textured quad's OBJ and MTL in a fresh directory, with a 2×1 PNG `tex.png`.
    fn textured_dir(name: &str, mtl: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("spt-obj-textures-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = "mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl q\nf 1/1 2/2 3/3\n";
        std::fs::write(dir.join("q.obj"), obj).unwrap();
        std::fs::write(dir.join("q.mtl"), mtl).unwrap();
        image::RgbaImage::from_fn(2, 1, |x, _| image::Rgba([if x == 0 { 255 } else { 0 }, 0, 0, 128]))
            .save(dir.join("tex.png"))
            .unwrap();
        dir
    }

    #[test]
    fn mtl_texture_maps_become_material_textures() {
        let dir = textured_dir(
            "maps",
            "newmtl q\nKd 0.5 0.5 0.5\nd 0.8\nmap_Kd -s 2 1 tex.png\nmap_d tex.png\nnorm tex.png\nmap_bump -bm 0.1 tex.png\nmap_Ka tex.png\n",
        );
        let scene = load_obj(&dir.join("q.obj")).unwrap();
        let t = scene.materials[0].textures.as_deref().expect("textures");
        let base = t.base_colour.as_ref().unwrap();
        assert_eq!((base.encoding, base.image.width()), (Encoding::Srgb, 2));
        // -s 2 1: u doubled, so u = 0.125 reads the texel centre at 0.25 (red).
        assert_eq!(base.sample(glam::Vec2::new(0.125, 0.5))[0], 1.0);
        let alpha = t.alpha.as_ref().unwrap();
        assert_eq!((alpha.mode, alpha.factor), (AlphaMode::Blend, 0.8));
        assert!((alpha.value(glam::Vec2::new(0.25, 0.5)) - 0.8 * 128.0 / 255.0).abs() < 1e-6);
        assert_eq!(t.normal.as_ref().map(|n| n.scale), Some(1.0));
        assert_eq!(t.bump.as_ref().map(|b| b.scale), Some(0.1));
        // Every map shares the one decoded image.
        assert_eq!(scene.texture_images().0, 1);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_missing_texture_is_an_error_naming_the_material_and_the_file() {
        let dir = textured_dir("missing", "newmtl q\nmap_Kd nowhere/brick.jpg\n");
        let e = load_obj(&dir.join("q.obj")).unwrap_err().to_string();
        assert!(e.contains("material 'q'") && e.contains("brick.jpg"), "{e}");
        let dir2 = textured_dir("broken", "newmtl q\nmap_Kd q.obj\n");
        let e = load_obj(&dir2.join("q.obj")).unwrap_err().to_string();
        assert!(e.contains("material 'q'") && e.contains("q.obj") && e.contains("not a PNG"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
        std::fs::remove_dir_all(&dir2).ok();
    }

    fn load(obj: &str) -> Result<Scene> {
        load_obj_text(obj, Path::new("s.obj"), &|_| Err(std::io::ErrorKind::NotFound.into()))
    }

    const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

    #[test]
    fn what_tobj_failed_or_panicked_on_loads_or_fails_with_a_line() {
        // tobj turned 3-corner polylines into triangles, and overflowed (a panic with
        // overflow checks) on their out-of-range texture and normal references.
        for l in ["l 1/-5 2/-5 3/-5", "l 1//-7 2//-7 3//-7", "l 1 2 9", "l 1 2"] {
            let scene = load(&format!("{TRIANGLE}vt 0 0\nvn 0 0 1\n{l}\n")).unwrap();
            assert!(scene.triangles.is_empty(), "{l}");
        }
        // Valid files tobj rejected: one-number texture coordinates, colours on some
        // vertices only, comments after a face.
        for obj in [
            format!("{TRIANGLE}vt 0.5\nf 1/1 2/1 3/1\n"),
            "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_string(),
            format!("{TRIANGLE}f 1 2 3 # a comment\n"),
            format!("{TRIANGLE}  usemtl\tnone\n  f 1 2 3\n"),
        ] {
            assert_eq!(load(&obj).unwrap().triangles.len(), 1, "{obj}");
        }
        // Malformed lines tobj reported without a line.
        for (obj, line, needle) in [
            (format!("{TRIANGLE}v 0 1 0 0\n"), 4, "w = 0"),
            (format!("{TRIANGLE}v 1e38 1 0 1e-5\n"), 4, "infinite"),
            (format!("{TRIANGLE}v 1 2 3 4 5\n"), 4, "found 5"),
            (format!("{TRIANGLE}usemtl\n"), 4, "usemtl: missing name"),
            (format!("{TRIANGLE}mtllib \n"), 4, "mtllib: missing name"),
            (format!("{TRIANGLE}f 1/1/1/1 2 3\n"), 4, "'1/1/1/1' is not a valid vertex reference"),
        ] {
            let e = load(&obj).unwrap_err().to_string();
            assert!(e.starts_with(&format!("s.obj:{line}: ")) && e.contains(needle), "{obj:?}: {e}");
        }
    }

    #[test]
    fn vertices_with_w_and_colours_keep_their_positions() {
        let s = load("v 2 4 6 2\nv 1 0 0 0.1 0.2 0.3\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(s.positions, [[1.0, 2.0, 3.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    }

    #[test]
    fn texture_coordinates_are_kept_with_v_flipped() {
        let s = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0.25\nvt 0 1\nf 1/1 2/2 3/3\n").unwrap();
        assert_eq!(s.uvs, [[0.0, 1.0], [1.0, 0.75], [0.0, 0.0]]);
        assert!(load(&format!("{TRIANGLE}f 1 2 3\n")).unwrap().uvs.is_empty());
    }

    #[test]
    fn a_face_with_many_corners_is_a_fan() {
        let corners: String = (1..=3).cycle().take(100_000).map(|i| format!(" {i}")).collect();
        let s = load(&format!("{TRIANGLE}f{corners}\n")).unwrap();
        assert_eq!(s.triangles.len(), 100_000 - 2);
        assert_eq!(s.positions.len(), 3);
    }

    #[test]
    fn only_regular_files_are_read() {
        let e = read_text(Path::new("/dev/null")).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        let e = load_obj(Path::new("/nonexistent/s.obj")).unwrap_err().to_string();
        assert!(e.starts_with("/nonexistent/s.obj: ") && e.to_lowercase().contains("no such file"), "{e}");
    }
}

#[cfg(test)]
mod mtl_tests {
    use super::*;
    use crate::material::ModelParams;

    fn load(mtl: &str) -> Result<Scene> {
        let dir = std::env::temp_dir().join(format!("spt-obj-test-{}-{}", std::process::id(), mtl.len()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("m.mtl"), mtl).unwrap();
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        std::fs::write(dir.join("s.obj"), obj).unwrap();
        load_obj(&dir.join("s.obj"))
    }

    /// Loads a one-triangle OBJ using material `a` of `mtl`, from memory.
    fn load_text(mtl: &str) -> Result<Scene> {
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        load_obj_text(obj, Path::new("dir/s.obj"), &|p| {
            assert_eq!(p, Path::new("dir/m.mtl"));
            Ok(mtl.to_string())
        })
    }

    fn model(scene: &Scene) -> ModelId {
        scene.materials[0].model().expect("a registered model")
    }

    #[test]
    fn thesis_extensions_choose_their_models_and_read_parameters() {
        let s = load("newmtl a\nKd 0.5 0.2 0.1\nrough 0.2\np 0.5\n").unwrap();
        assert_eq!(model(&s), ModelId::Schlick);
        let Some(ModelParams::Schlick(params)) = s.materials[0].params() else { unreachable!() };
        assert_eq!((params.roughness, params.isotropy), (0.2, 0.5));
        let s = load("newmtl a\nnu 1000\nnv 10\nRs 0.1 0.1 0.1\nRd 0.4 0.4 0.4\n").unwrap();
        assert_eq!(model(&s), ModelId::Ashikhmin);
        let s = load("newmtl a\nbsdf orennayar\nKd 0.5 0.5 0.5\nsigma 0.3\n").unwrap();
        assert_eq!(model(&s), ModelId::OrenNayar);
        let s = load("newmtl a\nillum 7\nNi 1.33\n").unwrap();
        assert_eq!(model(&s), ModelId::Dielectric);
        let s = load("newmtl a\nKd 0.8 0.2 0.1\nPr 0.4\nPm 0\n").unwrap();
        assert_eq!(model(&s), ModelId::MetallicRoughness);
        let Some(ModelParams::MetallicRoughness(params)) = s.materials[0].params() else { unreachable!() };
        assert_eq!((params.roughness, params.metallic, params.base_color.rgb), (0.4, 0.0, [0.8, 0.2, 0.1]));
    }

    #[test]
    fn bad_parameters_name_the_material() {
        let e = load("newmtl a\nrough 1.5\n").unwrap_err().to_string();
        assert!(e.contains("material 'a'") && e.contains("roughness = 1.5"), "{e}");
        let e = load("newmtl a\nbsdf velvet\n").unwrap_err().to_string();
        assert!(e.contains("unknown bsdf 'velvet'") && e.contains("schlick"), "{e}");
        let e = load("newmtl a\nnu 1 2\n").unwrap_err().to_string();
        assert!(e.contains("nu needs 1 or 3 numbers"), "{e}");
    }

    #[test]
    fn one_value_kd_is_grey_and_renders() {
        use crate::{CpuBackend, RenderSettings, SpectralMode};
        // A floor in `Kd 0.5`, lit by a lamp in `Ke 4` above it (one-value forms both).
        let mtl = "newmtl floor\nKd 0.5\nnewmtl lamp\nKd 0\nKe 4\n";
        let obj = "mtllib m.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n\
                   v -0.3 1 -0.3\nv -0.3 1 0.3\nv 0.3 1 0.3\nv 0.3 1 -0.3\n\
                   usemtl floor\nf 4 3 2 1\nusemtl lamp\nf 8 7 6 5\n";
        let scene = load_obj_text(obj, Path::new("s.obj"), &|_| Ok(mtl.to_string())).unwrap();
        let floor = &scene.materials[0];
        assert_eq!(model(&scene), ModelId::Lambert);
        let Some(ModelParams::Lambert(params)) = floor.params() else { unreachable!() };
        assert_eq!(params.reflectance, Colour::constant(0.5));
        assert_eq!(scene.materials[1].emission.as_ref().map(|e| e.rgb), Some([4.0; 3]));
        // The same as the three-value form.
        let three = load_text("newmtl a\nKd 0.5 0.5 0.5\n").unwrap();
        let one = load_text("newmtl a\nKd 0.5\n").unwrap();
        assert_eq!(format!("{:?}", three.materials[0].surface), format!("{:?}", one.materials[0].surface));

        let prepared = CpuBackend::new(1).unwrap().prepare_cpu(scene, &crate::SceneOptions::default()).unwrap();
        let settings = RenderSettings {
            width: 16,
            height: 16,
            spp: 4,
            mode: SpectralMode::Hero,
            camera: Some(crate::Camera {
                eye: Vec3::new(0.0, 0.6, 2.5),
                center: Vec3::new(0.0, 0.2, 0.0),
                up: Vec3::Y,
                fov_y_deg: 50.0,
            }),
            ..Default::default()
        };
        let (film, _) = crate::render(&prepared, &settings, &|_| {}).unwrap();
        let means = film.channel_means();
        assert!(means.iter().all(|m| m.is_finite() && *m > 0.0), "the lit grey floor is visible: {means:?}");
    }

    #[test]
    fn mtl_errors_name_the_file_and_line() {
        let e = load_text("newmtl a\nKd 0.5\nNs x\n").unwrap_err().to_string();
        assert!(e.starts_with("dir/m.mtl:3: ") && e.contains("Ns: 'x' is not a number"), "{e}");
        let e = load_text("newmtl a\n\nKd 0.5 0.5\n").unwrap_err().to_string();
        assert!(e.starts_with("dir/m.mtl:3: ") && e.contains("Kd needs 1 or 3 numbers, got 2"), "{e}");
        let e = load_text("newmtl a\nillum 12\n").unwrap_err().to_string();
        assert!(e.starts_with("dir/m.mtl:2: ") && e.contains("illum"), "{e}");
        // Values read later (range checks, extension statements, models) keep their line.
        let e = load_text("newmtl a\nKd 0.5\nrough 1.5\n").unwrap_err().to_string();
        assert!(e.starts_with("dir/m.mtl:3: material 'a': roughness = 1.5"), "{e}");
        let e = load_text("newmtl a\nKd 1.5 0.5 0.5\n").unwrap_err().to_string();
        assert!(e.starts_with("dir/m.mtl:2: material 'a': reflectance = 1.5"), "{e}");
        let e = load_text("newmtl a\n# c\nnu 1 2\n").unwrap_err().to_string();
        assert!(e.starts_with("dir/m.mtl:3: material 'a': nu needs 1 or 3 numbers, got 2"), "{e}");
        let e = load_text("newmtl a\nbsdf velvet\n").unwrap_err().to_string();
        assert!(e.starts_with("dir/m.mtl:2: material 'a': unknown bsdf 'velvet'"), "{e}");
        let e = load_obj_text("mtllib gone.mtl\n", Path::new("s.obj"), &|_| Err(std::io::ErrorKind::NotFound.into()))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.obj:1: mtllib: cannot read gone.mtl: "), "{e}");
    }

    #[test]
    fn tr_is_one_minus_d_and_d_wins() {
        assert_eq!(model(&load_text("newmtl a\nTr 0.3\n").unwrap()), ModelId::Dielectric);
        assert_eq!(model(&load_text("newmtl a\nTr 0\n").unwrap()), ModelId::Lambert);
        assert_eq!(model(&load_text("newmtl a\nd 1\nTr 0.3\n").unwrap()), ModelId::Lambert);
    }

    #[test]
    fn a_library_named_twice_is_read_once_and_names_map_as_before() {
        let reads = std::cell::Cell::new(0);
        let obj = "mtllib m.mtl\nmtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl b\nf 1 2 3\nmtllib m.mtl\n\
                   usemtl a\nf 1 2 3\nusemtl nothing\nf 1 2 3\n";
        let mtl = "newmtl a\nKd 0.1\nnewmtl b\nKd 0.2\n";
        let scene = load_obj_text(obj, Path::new("s.obj"), &|_| {
            reads.set(reads.get() + 1);
            Ok(mtl.to_string())
        })
        .unwrap();
        assert_eq!(reads.get(), 1);
        let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["b", "a", "(default)"]);
        // Other paths to the same text are read but add no materials; another library's
        // names map to its own materials.
        let obj = "mtllib m.mtl\nmtllib ./m.mtl\nmtllib n.mtl\nmtllib x/../m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
                   usemtl c\nf 1 2 3\nusemtl a\nf 1 2 3\n";
        let scene = load_obj_text(obj, Path::new("s.obj"), &|p| {
            reads.set(reads.get() + 1);
            Ok(if p.ends_with("n.mtl") { "newmtl c\nKd 0.3\n".into() } else { mtl.to_string() })
        })
        .unwrap();
        assert_eq!(reads.get(), 1 + 4);
        let albedo: Vec<[f32; 3]> = scene
            .materials
            .iter()
            .map(|m| match m.params() {
                Some(ModelParams::Lambert(p)) => p.reflectance.rgb,
                other => unreachable!("{other:?}"),
            })
            .collect();
        assert_eq!(albedo, [[0.3; 3], [0.1; 3]]);
    }
}
