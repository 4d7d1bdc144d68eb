//! Wavefront OBJ/MTL scenes: OBJ geometry assembled by `tobj`, MTL libraries read by our
//! own parser ([`crate::mtl`]; tobj never parses an MTL file).
//!
//! Material mapping (the thesis's other MTL extensions come with the loaders issue):
//! * `Ke` > 0 → a one-sided area light of radiance `Ke` (front = counter-clockwise);
//! * `bsdf NAME` (our extension) picks any built-in model by name;
//! * the thesis's extensions: `rough`/`p` → Schlick 1994, `nu`/`nv`/`Rs`/`Rd` →
//!   Shirley–Ashikhmin 2000;
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
//! Faces are fan-triangulated. Before `tobj` parses, a line-by-line check finds the
//! first malformed or non-finite `v`/`vn`/`vt`/`f` line and reports its line number,
//! which `tobj`'s errors do not carry.

use crate::material::{BuiltinModel, Material};
use crate::mesh::Mesh;
use crate::mtl::{self, MtlMaterial, Numbers, Statement, quote};
use crate::scene::Scene;
use crate::{Error, Result};
use brdf::params::{ParamError, ParamValue};
use glam::Vec3;
use spectral::spectrum::Colour;
use std::cell::RefCell;
use std::path::{Path, PathBuf};

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
/// drives the whole loader from memory. Never panics: malformed input is an error.
pub fn load_obj_text(text: &str, path: &Path, read_mtl: &dyn Fn(&Path) -> std::io::Result<String>) -> Result<Scene> {
    let obj_error = |line: Option<usize>, message: String| Error::Parse { path: path.to_path_buf(), line, message };
    if let Some((line, message)) = check_obj_text(text) {
        return Err(obj_error(Some(line), message));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    // The libraries in the order tobj merged them (tobj's material ids index their
    // concatenation), and the first library that failed.
    let libraries: RefCell<Vec<(PathBuf, Vec<MtlMaterial>)>> = RefCell::new(Vec::new());
    let failure: RefCell<Option<Error>> = RefCell::new(None);
    let load_library = |name: &Path| -> tobj::MTLLoadResult {
        let lib = dir.join(name);
        if failure.borrow().is_some() {
            return Err(tobj::LoadError::MaterialParseError);
        }
        if libraries.borrow().iter().any(|(p, _)| *p == lib) {
            // Named again: its names already map to its materials.
            return Ok(Default::default());
        }
        let parsed = read_mtl(&lib)
            .map_err(|e| Error::Parse {
                path: lib.clone(),
                line: None,
                message: format!("cannot read the material library named by the OBJ: {e}"),
            })
            .and_then(|text| {
                mtl::parse_mtl(&text).map_err(|e| Error::Parse {
                    path: lib.clone(),
                    line: Some(e.line),
                    message: e.message,
                })
            });
        match parsed {
            Ok(materials) => {
                // tobj only maps `usemtl` names to ids; the last of a repeated name wins.
                let ids = materials.iter().enumerate().map(|(i, m)| (m.name.clone(), i)).collect();
                let named = materials.iter().map(|m| tobj::Material { name: m.name.clone(), ..Default::default() });
                let named = named.collect();
                libraries.borrow_mut().push((lib, materials));
                Ok((named, ids))
            }
            Err(e) => {
                *failure.borrow_mut() = Some(e);
                Err(tobj::LoadError::MaterialParseError)
            }
        }
    };
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let loaded = tobj::load_obj_buf(&mut text.as_bytes(), &options, load_library);
    if let Some(e) = failure.into_inner() {
        return Err(e);
    }
    let (models, _) = loaded.map_err(|e| obj_error(None, e.to_string()))?;
    let mut converted = Vec::new();
    for (lib, materials) in libraries.into_inner() {
        for m in &materials {
            converted.push(to_material(&lib, m)?);
        }
    }
    let default = MtlMaterial {
        name: "(default)".into(),
        line: 0,
        statements: vec![Statement { key: "Kd".into(), values: DEFAULT_ALBEDO.to_string(), line: 0 }],
    };
    let default = to_material(path, &default)?;
    let mut scene = Scene::default();
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

/// An MTL material as a [`Material`]: the model chosen as the module doc says, its
/// parameters read from the statements its declaration names. The one place this module
/// uses the material API (`Material::builtin`, `BuiltinModel`, the parameter
/// declarations), so that changes there touch one function. Errors name `lib`, the
/// line and the material.
fn to_material(lib: &Path, m: &MtlMaterial) -> Result<Material> {
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
        BuiltinModel::by_name(name).ok_or_else(|| {
            let known: Vec<&str> = BuiltinModel::ALL.iter().map(|b| b.def().name).collect();
            at(bsdf.line, format!("unknown bsdf '{}' (known: {})", quote(name), known.join(", ")))
        })?
    } else if ["nu", "nv", "Rs", "Rd"].iter().any(|k| m.has(k)) {
        // The thesis's MTL extensions name their model by its parameters.
        BuiltinModel::ShirleyAshikhmin
    } else if ["rough", "p"].iter().any(|k| m.has(k)) {
        BuiltinModel::Schlick
    } else {
        let illum = m.get("illum").map(Statement::illum).transpose().map_err(syntax)?.unwrap_or(2);
        let opacity = m.dissolve().map_err(syntax)?.unwrap_or(1.0);
        if matches!(illum, 4 | 6 | 7) || opacity < 1.0 {
            BuiltinModel::Dielectric
        } else if matches!(illum, 3 | 5) {
            BuiltinModel::Mirror
        } else {
            BuiltinModel::Lambert
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
        let param = match &e {
            ParamError::OutOfRange { param, .. }
            | ParamError::NotScalar { param, .. }
            | ParamError::Spectrum { param, .. } => Some(*param),
            _ => None,
        };
        let line = lines.iter().find(|(name, _)| Some(*name) == param).map_or(m.line, |&(_, line)| line);
        Error::Parse { path: lib.to_path_buf(), line: Some(line), message: e.to_string() }
    })?;
    material.emission = emission;
    Ok(material)
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

    /// Loads a one-triangle OBJ using material `a` of `mtl`, from memory.
    fn load_text(mtl: &str) -> Result<Scene> {
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
        load_obj_text(obj, Path::new("dir/s.obj"), &|p| {
            assert_eq!(p, Path::new("dir/m.mtl"));
            Ok(mtl.to_string())
        })
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

    #[test]
    fn one_value_kd_is_grey_and_renders() {
        use crate::render::PreparedScene;
        use crate::{CpuBackend, RenderSettings, SpectralMode};
        // A floor in `Kd 0.5`, lit by a lamp in `Ke 4` above it (one-value forms both).
        let mtl = "newmtl floor\nKd 0.5\nnewmtl lamp\nKd 0\nKe 4\n";
        let obj = "mtllib m.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n\
                   v -0.3 1 -0.3\nv -0.3 1 0.3\nv 0.3 1 0.3\nv 0.3 1 -0.3\n\
                   usemtl floor\nf 4 3 2 1\nusemtl lamp\nf 8 7 6 5\n";
        let scene = load_obj_text(obj, Path::new("s.obj"), &|_| Ok(mtl.to_string())).unwrap();
        let floor = &scene.materials[0];
        assert_eq!(model(&scene), BuiltinModel::Lambert);
        let Surface::Builtin { params, .. } = &floor.surface else { unreachable!() };
        let reflectance = params.colour(BuiltinModel::Lambert.def().param("reflectance").unwrap().0);
        assert_eq!(reflectance, Colour::constant(0.5));
        assert_eq!(scene.materials[1].emission.as_ref().map(|e| e.rgb), Some([4.0; 3]));
        // The same as the three-value form.
        let three = load_text("newmtl a\nKd 0.5 0.5 0.5\n").unwrap();
        let one = load_text("newmtl a\nKd 0.5\n").unwrap();
        assert_eq!(format!("{:?}", three.materials[0].surface), format!("{:?}", one.materials[0].surface));

        let prepared = PreparedScene::new(scene).unwrap();
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
        let (film, _) = crate::render(&CpuBackend::new(1).unwrap(), &prepared, &settings, &|_| {}).unwrap();
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
        assert!(e.starts_with("gone.mtl: cannot read the material library"), "{e}");
    }

    #[test]
    fn tr_is_one_minus_d_and_d_wins() {
        assert_eq!(model(&load_text("newmtl a\nTr 0.3\n").unwrap()), BuiltinModel::Dielectric);
        assert_eq!(model(&load_text("newmtl a\nTr 0\n").unwrap()), BuiltinModel::Lambert);
        assert_eq!(model(&load_text("newmtl a\nd 1\nTr 0.3\n").unwrap()), BuiltinModel::Lambert);
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
    }
}
