//! Wavefront OBJ/MTL scenes, parsed by `tobj`.
//!
//! Material mapping (the thesis's other MTL extensions come with the loaders issue):
//! * `Ke` > 0 → a one-sided area light of radiance `Ke` (front = counter-clockwise);
//! * `bsdf NAME` (our extension) picks any built-in model by name;
//! * the thesis's extensions: `rough`/`p` → Schlick 1994, `nu`/`nv`/`Rs`/`Rd` →
//!   Shirley–Ashikhmin 2000;
//! * else `illum` 4, 6, 7, or `d` < 1 → smooth dielectric;
//! * `illum` 3 or 5 → perfect mirror;
//! * otherwise → Lambertian.
//!
//! Each model's parameters are read from the MTL statements its declaration names
//! (`mtl_key`: e.g. `Kd` for Lambert's reflectance, `Ks` for the mirror's, `Ni` and `Tf`
//! for the dielectric), range-checked, and defaulted where absent (Lambert 0.5 grey,
//! Mitsuba's default).
//!
//! Faces are fan-triangulated. Before `tobj` parses, a line-by-line check finds the
//! first malformed or non-finite `v`/`vn`/`vt`/`f` line and reports its line number,
//! which `tobj`'s errors do not carry.

use crate::material::{BuiltinModel, Material};
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::{Error, Result};
use brdf::params::ParamValue;
use glam::Vec3;
use spectral::spectrum::Colour;
use std::path::Path;

/// Albedo of faces without a material.
pub const DEFAULT_ALBEDO: f32 = 0.5;

/// Loads an OBJ file and the MTL libraries it names.
pub fn load_obj(path: &Path) -> Result<Scene> {
    let text = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let text = String::from_utf8_lossy(&text);
    load_obj_text(&text, path, &|lib| std::fs::read(lib).map(|b| String::from_utf8_lossy(&b).into_owned()))
}

/// Loads an OBJ scene from its text, without touching the disk: `path` names the OBJ in
/// messages and is what `mtllib` names are resolved against; `read_mtl` returns the text
/// of such a resolved MTL path. [`load_obj`] reads files through it; a fuzzer or a test
/// can drive the whole loader from memory.
pub fn load_obj_text(text: &str, path: &Path, read_mtl: &dyn Fn(&Path) -> std::io::Result<String>) -> Result<Scene> {
    if let Some((line, message)) = check_obj_text(text) {
        return Err(Error::Parse { path: path.to_path_buf(), line: Some(line), message });
    }
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let dir = path.parent().unwrap_or(Path::new(""));
    let (models, materials) =
        tobj::load_obj_buf(&mut text.as_bytes(), &options, |lib| match read_mtl(&dir.join(lib)) {
            Ok(mtl) => tobj::load_mtl_buf(&mut mtl.as_bytes()),
            Err(_) => Err(tobj::LoadError::OpenFileFailed),
        })
        .map_err(|e| Error::Parse { path: path.to_path_buf(), line: None, message: e.to_string() })?;
    let materials = match materials {
        Ok(m) => m,
        Err(e) => {
            let lib = find_mtllib(text).map(|l| path.with_file_name(l));
            if let Some(lib) = &lib
                && let Ok(mtl) = read_mtl(lib)
                && let Some((line, message)) = check_mtl_text(&mtl)
            {
                return Err(Error::Parse { path: lib.clone(), line: Some(line), message });
            }
            if lib.is_some() {
                return Err(Error::Parse {
                    path: lib.unwrap_or_else(|| path.to_path_buf()),
                    line: None,
                    message: format!("cannot load the material library named by the OBJ: {e}"),
                });
            }
            Vec::new()
        }
    };
    let converted: Vec<Material> = materials.iter().map(convert_material).collect::<Result<_>>()?;
    let mut scene = Scene::default();
    let default = Material::diffuse("(default)", Colour::constant(DEFAULT_ALBEDO))?;
    for model in &models {
        let mesh = &model.mesh;
        let vec3s = |v: &[f32]| -> Vec<Vec3> { v.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect() };
        let normals = if mesh.normals.len() == mesh.positions.len() { vec3s(&mesh.normals) } else { Vec::new() };
        let m = Mesh {
            positions: vec3s(&mesh.positions),
            normals,
            tangents: Vec::new(),
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

fn convert_material(m: &tobj::Material) -> Result<Material> {
    let emission = match m.emissive {
        Some(ke) if ke.iter().any(|&v| v != 0.0) => {
            Some(Colour::illuminant_rgb(ke).map_err(|source| Error::Material { material: m.name.clone(), source })?)
        }
        _ => None,
    };
    let model = choose_model(m)?;
    let mut params = Vec::new();
    for p in model.def().params {
        if let Some(key) = p.mtl_key
            && let Some(value) = mtl_value(m, key)?
        {
            params.push((p.name, value));
        }
    }
    let mut material = Material::builtin(&m.name, model, &params)?;
    material.emission = emission;
    Ok(material)
}

/// The model an MTL material asks for: an explicit `bsdf NAME` statement (our extension),
/// else by `illum` and `d` as documented at the top of this module.
fn choose_model(m: &tobj::Material) -> Result<BuiltinModel> {
    if let Some(name) = m.unknown_param.get("bsdf") {
        let name = name.trim();
        return BuiltinModel::by_name(name).ok_or_else(|| {
            let known: Vec<&str> = BuiltinModel::ALL.iter().map(|b| b.def().name).collect();
            Error::Setting(format!("material '{}': unknown bsdf '{name}' (known: {})", m.name, known.join(", ")))
        });
    }
    // The thesis's MTL extensions name their model by its parameters.
    let has = |keys: &[&str]| keys.iter().any(|k| m.unknown_param.contains_key(*k));
    if has(&["nu", "nv", "Rs", "Rd"]) {
        return Ok(BuiltinModel::ShirleyAshikhmin);
    }
    if has(&["rough", "p"]) {
        return Ok(BuiltinModel::Schlick);
    }
    let illum = m.illumination_model.unwrap_or(2);
    Ok(if matches!(illum, 4 | 6 | 7) || m.dissolve.unwrap_or(1.0) < 1.0 {
        BuiltinModel::Dielectric
    } else if matches!(illum, 3 | 5) {
        BuiltinModel::Mirror
    } else {
        BuiltinModel::Lambert
    })
}

/// The value of MTL statement `key`, if the material has it.
fn mtl_value(m: &tobj::Material, key: &str) -> Result<Option<ParamValue>> {
    let rgb = |v: Option<[f32; 3]>| v.map(ParamValue::Rgb);
    Ok(match key {
        "Kd" => rgb(m.diffuse),
        "Ks" => rgb(m.specular),
        "Ka" => rgb(m.ambient),
        "Ni" => m.optical_density.map(ParamValue::Scalar),
        "d" => m.dissolve.map(ParamValue::Scalar),
        "Ns" => m.shininess.map(ParamValue::Scalar),
        _ => match m.unknown_param.get(key) {
            None => None,
            Some(text) => {
                let nums: Vec<f32> =
                    text.split_whitespace().map(str::parse).collect::<Result<_, _>>().map_err(|_| {
                        Error::Setting(format!("material '{}': {key} '{text}' is not a list of numbers", m.name))
                    })?;
                match nums.as_slice() {
                    [v] => Some(ParamValue::Scalar(*v)),
                    [r, g, b] => Some(ParamValue::Rgb([*r, *g, *b])),
                    _ => {
                        return Err(Error::Setting(format!(
                            "material '{}': {key} needs 1 or 3 numbers, got {}",
                            m.name,
                            nums.len()
                        )));
                    }
                }
            }
        },
    })
}

fn find_mtllib(text: &str) -> Option<String> {
    text.lines().find_map(|l| l.trim().strip_prefix("mtllib").map(|rest| rest.trim().to_string()))
}

fn parse_floats(rest: &str, min: usize, max: usize, what: &str) -> std::result::Result<(), String> {
    let mut n = 0;
    for tok in rest.split_whitespace() {
        if tok.starts_with('#') {
            break;
        }
        let v: f32 = tok.parse().map_err(|_| format!("{what}: '{tok}' is not a number"))?;
        if !v.is_finite() {
            return Err(format!("{what}: '{tok}' is not finite"));
        }
        n += 1;
    }
    if n < min || n > max {
        return Err(format!("{what}: expected {min}–{max} numbers, found {n}"));
    }
    Ok(())
}

/// The first malformed geometry line of an OBJ text: (1-based line, message).
pub fn check_obj_text(text: &str) -> Option<(usize, String)> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let (key, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let result = match key {
            "v" => parse_floats(rest, 3, 7, "vertex").map(|_| nv += 1),
            "vn" => parse_floats(rest, 3, 3, "normal").map(|_| nn += 1),
            "vt" => parse_floats(rest, 1, 3, "texture coordinate").map(|_| nt += 1),
            "f" => check_face(rest, nv, nt, nn),
            _ => Ok(()),
        };
        if let Err(message) = result {
            return Some((i + 1, message));
        }
    }
    None
}

fn check_face(rest: &str, nv: i64, nt: i64, nn: i64) -> std::result::Result<(), String> {
    let corners: Vec<&str> = rest.split_whitespace().take_while(|t| !t.starts_with('#')).collect();
    if corners.len() < 3 {
        return Err(format!("face: needs at least 3 vertices, found {}", corners.len()));
    }
    for c in corners {
        for (k, (part, count, what)) in c
            .split('/')
            .zip([nv, nt, nn])
            .zip(["vertex", "texture coordinate", "normal"])
            .map(|((p, n), w)| (p, n, w))
            .enumerate()
        {
            if part.is_empty() && k > 0 {
                continue;
            }
            let idx: i64 = part.parse().map_err(|_| format!("face: '{c}' is not a valid vertex reference"))?;
            let resolved = if idx < 0 { count + idx } else { idx - 1 };
            if idx == 0 || resolved < 0 || resolved >= count {
                return Err(format!("face: {what} index {idx} is out of range (only {count} defined so far)"));
            }
        }
    }
    Ok(())
}

/// The first malformed numeric statement of an MTL text: (1-based line, message).
pub fn check_mtl_text(text: &str) -> Option<(usize, String)> {
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let (key, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let result = match key {
            "Ka" | "Kd" | "Ks" | "Ke" | "Tf" => parse_floats(rest, 1, 3, key),
            "Ns" | "Ni" | "d" | "Tr" => parse_floats(rest, 1, 1, key),
            "illum" => rest
                .split_whitespace()
                .next()
                .and_then(|t| t.parse::<u8>().ok())
                .map(|_| ())
                .ok_or_else(|| format!("illum: '{}' is not a model number 0–10", rest.trim())),
            _ => Ok(()),
        };
        if let Err(message) = result {
            return Some((i + 1, message));
        }
    }
    None
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
mod mtl_tests {
    use super::*;
    use crate::material::Surface;

    fn load(mtl: &str) -> Result<Scene> {
        let dir = std::env::temp_dir().join(format!("spt-obj-test-{}-{}", std::process::id(), mtl.len()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("m.mtl"), mtl).unwrap();
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        std::fs::write(dir.join("s.obj"), obj).unwrap();
        load_obj(&dir.join("s.obj"))
    }

    fn model(scene: &Scene) -> BuiltinModel {
        match &scene.materials[0].surface {
            Surface::Builtin { model, .. } => *model,
            Surface::Custom { .. } => panic!("custom"),
        }
    }

    #[test]
    fn thesis_extensions_choose_their_models_and_read_parameters() {
        let s = load("newmtl a\nKd 0.5 0.2 0.1\nrough 0.2\np 0.5\n").unwrap();
        assert_eq!(model(&s), BuiltinModel::Schlick);
        let Surface::Builtin { params, .. } = &s.materials[0].surface else { unreachable!() };
        let def = BuiltinModel::Schlick.def();
        assert_eq!(params.scalar(def.param("roughness").unwrap().0), 0.2);
        assert_eq!(params.scalar(def.param("isotropy").unwrap().0), 0.5);
        let s = load("newmtl a\nnu 1000\nnv 10\nRs 0.1 0.1 0.1\nRd 0.4 0.4 0.4\n").unwrap();
        assert_eq!(model(&s), BuiltinModel::ShirleyAshikhmin);
        let s = load("newmtl a\nbsdf orennayar\nKd 0.5 0.5 0.5\nsigma 0.3\n").unwrap();
        assert_eq!(model(&s), BuiltinModel::OrenNayar);
        let s = load("newmtl a\nillum 7\nNi 1.33\n").unwrap();
        assert_eq!(model(&s), BuiltinModel::Dielectric);
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
}
