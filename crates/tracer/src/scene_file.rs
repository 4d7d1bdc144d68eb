//! The native scene file: TOML, read through serde. One file places meshes from OBJ and
//! glTF files (with transforms), analytic shapes, materials by model name, point, spot and
//! sun lights, a sky and a camera:
//!
//! ```toml
//! [camera]
//! eye = [0, 1, 3.9]
//! center = [0, 1, 0]
//! fov = 39.3            # vertical, degrees (default 39.3077); up defaults to [0, 1, 0]
//!
//! [materials.gold]
//! model = "roughconductor"   # any registered model; the rest are its parameters
//! metal = "gold"
//! alpha = 0.2
//!
//! [materials.lamp]
//! model = "lambert"
//! reflectance = 0
//! emission = [17, 12, 4]     # linear sRGB radiance: an area light
//!
//! [[mesh]]
//! file = "../shared/scenes/bunny/bunny.obj"   # relative to this file; .obj, .gltf or .glb
//! material = "gold"          # optional: replaces the file's own materials
//! scale = 10                 # a number or [x, y, z]; then rotate, then translate
//! rotate = { axis = [0, 1, 0], degrees = 30 }
//! translate = [0, -0.3, 0]
//!
//! [[shape]]
//! type = "sphere"            # sphere {center, radius}, box {min, max},
//! center = [0, 1, 0]         # polygon {vertices}, implicit {expression, min, max}
//! radius = 0.5
//! material = "lamp"
//!
//! [[light]]
//! type = "sun"               # point {position, intensity}, spot {position, direction,
//! direction = [-1, -2, -1]   # inner, outer (degrees), intensity}, sun {direction,
//! irradiance = 3             # irradiance, diameter (degrees; 0: a delta direction)}
//! diameter = 0.53
//!
//! [sky]
//! radiance = [0.2, 0.3, 0.5] # a uniform sky (linear sRGB radiance); or
//! # map = "sky.exr"          # a latitude-longitude environment map (EXR, HDR, PNG, JPEG),
//! # rotation = 90            # turned about +y (degrees), times radiance (default 1)
//!
//! [render]                   # defaults for `spt render/bench/view`; their options win
//! width = 640                # also height, spp, seed, max_depth, rr_depth, rr_scale,
//! spectral = "bins40"        # sampler, integrator
//! ```
//!
//! Colours (material colours, emission, light intensities, the sky) are one number (a
//! grey), three (linear sRGB), or a spectrum: `{ spectrum = "D65" }` (also `"D50"`, `"D55"`,
//! `"D75"`, `"A"`, `"E"`, the fluorescent `"F1"` … `"F12"`), `{ daylight = 5000 }` (any CIE D
//! illuminant),
//! `{ blackbody = 3200 }` (peak 1), `{ table = { "400" = 0.2, "700" = 0.6 } }` (nm →
//! value, linear in between) or `{ spd = "golden", file = "metal.spec" }` (an SPD of a
//! SPEC file), each with an optional `scale`. Every error names the file and the line and
//! column of the offending value (`scene.toml:12:9: …`); unknown keys are errors, not
//! silently ignored.

use crate::camera::Camera;
use crate::envmap::EnvironmentMap;
use crate::geometry::ShapeKind;
use crate::gltf_scene::{GltfOptions, load_gltf};
use crate::material::{Material, ModelId};
use crate::obj::load_obj;
use crate::punctual::PunctualLight;
use crate::scene::{Environment, Scene};
use crate::{Error, Result};
use brdf::params::ParamValue;
use glam::{Mat3, Mat4, Quat, Vec3};
use serde::Deserialize;
use shapes::boxes::Cuboid;
use shapes::implicit::Implicit;
use shapes::polygon::{InsideTest, Polygon};
use shapes::roots::RootSolver;
use shapes::sphere::{Sphere, SphereMethod};
use spectral::spectrum::{Colour, ColourRole, Spectrum, TabulatedSpectrum};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// The file as serde reads it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDef {
    camera: Option<Spanned<CameraDef>>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<MaterialDef>>,
    #[serde(default)]
    mesh: Vec<Spanned<MeshDef>>,
    #[serde(default)]
    shape: Vec<Spanned<ShapeDef>>,
    #[serde(default)]
    light: Vec<Spanned<LightDef>>,
    sky: Option<Spanned<SkyDef>>,
    /// Read by [`render_defaults`], not by the scene.
    #[allow(dead_code)]
    render: Option<RenderDefaults>,
}

/// A scene file's `[render]` table: settings the CLI uses where its command line does
/// not give them (its options override them).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderDefaults {
    /// Image width in pixels.
    pub width: Option<u32>,
    /// Image height in pixels.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Random seed.
    pub seed: Option<u64>,
    /// Maximum bounces (0: unbounded).
    pub max_depth: Option<u32>,
    /// Bounces before Russian roulette.
    pub rr_depth: Option<u32>,
    /// Russian roulette's scale of the survival probability (`PathSettings::rr_scale`).
    pub rr_scale: Option<f32>,
    /// Spectral mode: hero, bins40 or rgb.
    pub spectral: Option<String>,
    /// Sampler: zsobol, sobol or independent.
    pub sampler: Option<String>,
    /// Integrator: path, direct, ao or whitted.
    pub integrator: Option<String>,
}

/// The `[render]` table of a scene file (all `None` without one). Errors as
/// [`load_scene_file`]'s.
pub fn render_defaults(path: &Path) -> Result<RenderDefaults> {
    let text = crate::obj::read_text_file(path)?;
    let file: FileDef = toml::from_str(&text).map_err(|e| {
        let (line, column) = line_column(&text, e.span().unwrap_or(0..0).start);
        Error::ParseAt { path: path.to_path_buf(), line, column, message: e.message().to_string() }
    })?;
    Ok(file.render.unwrap_or_default())
}

/// A material table: each value with where it is, for messages.
type MaterialDef = BTreeMap<String, Spanned<toml::Value>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDef {
    eye: [f32; 3],
    center: [f32; 3],
    #[serde(default = "up_y")]
    up: [f32; 3],
    #[serde(default = "default_fov")]
    fov: f32,
}

fn up_y() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

fn default_fov() -> f32 {
    crate::camera::DEFAULT_FOV_Y_DEG
}

/// A colour: a grey (one number), linear sRGB (three), or a spectrum ([`SpectrumDef`]).
#[derive(Clone, Deserialize)]
#[serde(untagged)]
enum ColourDef {
    Grey(f32),
    Rgb([f32; 3]),
    Spectrum(SpectrumDef),
}

/// A spectrum by name (`spectrum = "D65" | "D50" | "D55" | "D75" | "A" | "E" | "F1" … "F12"`;
/// D65 and the fluorescent lamps scaled to luminance 1, A and the other D illuminants to 1
/// at 560 nm), a CIE daylight of any
/// temperature (`daylight = K`, 4000–25000, 1 at 560 nm), a black body (`blackbody = K`,
/// peak 1), a table (`table = { "400" = 0.1, … }`, nm → value) or an SPD of a SPEC file
/// (`spd = NAME, file = "x.spec"`), times `scale` (default 1).
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpectrumDef {
    spectrum: Option<String>,
    daylight: Option<f32>,
    blackbody: Option<f32>,
    table: Option<BTreeMap<String, f32>>,
    spd: Option<String>,
    file: Option<String>,
    scale: Option<f32>,
}

impl ColourDef {
    /// The colour in `role`; spectra from SPEC files are resolved against `dir`.
    fn colour(&self, role: ColourRole, dir: &Path) -> std::result::Result<Colour, String> {
        match self {
            Self::Grey(v) => rgb_colour([*v; 3], role),
            Self::Rgb(c) => rgb_colour(*c, role),
            Self::Spectrum(s) => Ok(Colour::from_spectrum(s.spectrum(dir)?, role)),
        }
    }
}

fn rgb_colour(rgb: [f32; 3], role: ColourRole) -> std::result::Result<Colour, String> {
    match role {
        ColourRole::Reflectance => Colour::reflectance_rgb(rgb),
        ColourRole::Illuminant => Colour::illuminant_rgb(rgb),
    }
    .map_err(|e| e.to_string())
}

impl SpectrumDef {
    fn spectrum(&self, dir: &Path) -> std::result::Result<Spectrum, String> {
        let scale = self.scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("scale {scale} must be a non-negative number"));
        }
        let given = [
            self.spectrum.is_some(),
            self.daylight.is_some(),
            self.blackbody.is_some(),
            self.table.is_some(),
            self.spd.is_some(),
        ];
        if given.iter().filter(|&&g| g).count() != 1 {
            return Err("a spectrum needs exactly one of spectrum, daylight, blackbody, table or spd".into());
        }
        if self.file.is_some() != self.spd.is_some() {
            return Err("spd and file go together: spd = NAME, file = \"x.spec\"".into());
        }
        let table = |lambda: Vec<f32>, value: Vec<f32>| {
            TabulatedSpectrum::new(lambda, value.into_iter().map(|v| v * scale).collect()).map_err(|e| e.to_string())
        };
        if let Some(name) = &self.spectrum {
            return match name.to_ascii_uppercase().as_str() {
                "D65" => Ok(Spectrum::D65(scale)),
                "A" => Ok(Spectrum::IlluminantA(scale / 100.0)),
                "E" => Ok(Spectrum::Constant(scale)),
                // CIE 15:2018's temperatures for the named D illuminants.
                "D50" => Ok(Spectrum::Daylight { kelvin: 5003.0, scale: scale / 100.0 }),
                "D55" => Ok(Spectrum::Daylight { kelvin: 5503.0, scale: scale / 100.0 }),
                "D75" => Ok(Spectrum::Daylight { kelvin: 7504.0, scale: scale / 100.0 }),
                f if f.starts_with('F') && f[1..].parse::<u8>().is_ok_and(|n| (1..=12).contains(&n)) => {
                    Ok(Spectrum::Fluorescent { number: f[1..].parse().unwrap_or(1), scale })
                }
                _ => Err(format!(
                    "unknown spectrum '{name}' (known: D65, D50, D55, D75, A, E, F1 … F12; or daylight, blackbody, table, spd)"
                )),
            };
        }
        if let Some(kelvin) = self.daylight {
            if !(kelvin.is_finite() && (4000.0..=25_000.0).contains(&kelvin)) {
                return Err(format!("daylight {kelvin} K is outside the CIE D series' [4000, 25000]"));
            }
            return Ok(Spectrum::Daylight { kelvin, scale: scale / 100.0 });
        }
        if let Some(kelvin) = self.blackbody {
            if !(kelvin.is_finite() && (100.0..=1.0e6).contains(&kelvin)) {
                return Err(format!("blackbody {kelvin} K is outside [100, 10⁶]"));
            }
            return Ok(Spectrum::Blackbody { kelvin, scale });
        }
        if let Some(t) = &self.table {
            let mut points = Vec::with_capacity(t.len());
            for (l, &v) in t {
                let lambda: f32 = l.trim().parse().map_err(|_| format!("table: '{l}' is not a wavelength in nm"))?;
                points.push((lambda, v));
            }
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (lambda, value) = points.into_iter().unzip();
            return Ok(Spectrum::Tabulated(table(lambda, value)?));
        }
        let (name, file) = (self.spd.as_deref().unwrap_or_default(), self.file.as_deref().unwrap_or_default());
        let spec = crate::spec::load_spec_spectra(&dir.join(file)).map_err(|e| e.to_string())?;
        let t = spec.get(name).ok_or_else(|| {
            format!("{file}: no spectrum '{name}' (defined: {})", spec.keys().cloned().collect::<Vec<_>>().join(", "))
        })?;
        let (lambda, value): (Vec<f32>, Vec<f32>) = (360..=830).map(|l| (l as f32, t.eval(l as f32))).unzip();
        Ok(Spectrum::Tabulated(table(lambda, value)?))
    }
}

#[derive(Deserialize)]
#[serde(untagged)]
enum ScaleDef {
    Uniform(f32),
    Axes([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotateDef {
    axis: [f32; 3],
    degrees: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDef {
    file: String,
    material: Option<String>,
    scale: Option<ScaleDef>,
    rotate: Option<RotateDef>,
    #[serde(default)]
    translate: [f32; 3],
    /// A glTF file's camera to use when the scene file has none.
    camera: Option<String>,
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum ShapeDef {
    Sphere { center: [f32; 3], radius: f32, material: String },
    Box { min: [f32; 3], max: [f32; 3], material: String },
    Polygon { vertices: Vec<[f32; 3]>, material: String },
    Implicit { expression: String, min: [f32; 3], max: [f32; 3], material: String },
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum LightDef {
    Point {
        position: [f32; 3],
        intensity: ColourDef,
    },
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        inner: f32,
        outer: f32,
        intensity: ColourDef,
    },
    Sun {
        direction: [f32; 3],
        irradiance: ColourDef,
        /// Angular diameter in degrees (0: a delta direction; the real sun: 0.53).
        #[serde(default)]
        diameter: f32,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SkyDef {
    /// The uniform radiance, or with a map the colour that multiplies it.
    radiance: Option<ColourDef>,
    /// A latitude–longitude environment map (EXR/HDR, or PNG/JPEG as sRGB).
    map: Option<String>,
    /// Degrees the map turns about the vertical axis (counter-clockwise from above).
    #[serde(default)]
    rotation: f32,
}

/// Loads a scene file and the meshes it names.
pub fn load_scene_file(path: &Path) -> Result<Scene> {
    let text = crate::obj::read_text_file(path)?;
    parse_scene_file(&text, path)
}

/// Loads a scene file with `--set KEY=VALUE` overrides applied first ([`apply_overrides`]).
pub fn load_scene_file_with(path: &Path, overrides: &[String]) -> Result<Scene> {
    if overrides.is_empty() {
        return load_scene_file(path);
    }
    let text = crate::obj::read_text_file(path)?;
    let edited = apply_overrides(&text, overrides).map_err(|message| Error::parse(path, message))?;
    // Positions now refer to the edited text: say so.
    parse_scene_file(&edited, path).map_err(|e| match e {
        Error::ParseAt { path, line, column, message } => {
            Error::ParseAt { path, line, column, message: format!("{message} (in the file as --set changed it)") }
        }
        other => other,
    })
}

/// A scene file's text with `KEY=VALUE` overrides applied: KEY is a dotted path through
/// tables and arrays (`materials.gold.alpha`, `shape.0.radius`, `camera.fov`; missing
/// tables are created), VALUE a TOML value (`0.3`, `[1, 2, 3]`, `"gold"`, or a bare word,
/// taken as a string).
pub fn apply_overrides(text: &str, overrides: &[String]) -> std::result::Result<String, String> {
    let mut doc = toml::Value::Table(toml::from_str(text).map_err(|e| e.message().to_string())?);
    for o in overrides {
        let Some((key, value)) = o.split_once('=') else {
            return Err(format!("--set {o}: expected KEY=VALUE"));
        };
        let value = match toml::from_str::<toml::Table>(&format!("v = {value}")) {
            Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(value.to_string())),
            Err(_) => toml::Value::String(value.trim().to_string()),
        };
        let parts: Vec<&str> = key.trim().split('.').collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err(format!("--set {o}: '{key}' is not a dotted key"));
        }
        set_value(&mut doc, &parts, value).map_err(|e| format!("--set {o}: {e}"))?;
    }
    toml::to_string(&doc).map_err(|e| e.to_string())
}

/// Sets `value` at the dotted path `parts` under `here`: table keys (a missing table is
/// created) and array indices.
fn set_value(here: &mut toml::Value, parts: &[&str], value: toml::Value) -> std::result::Result<(), String> {
    let Some((first, rest)) = parts.split_first() else { return Ok(()) };
    let child = match here {
        toml::Value::Table(t) if rest.is_empty() => {
            t.insert(first.to_string(), value);
            return Ok(());
        }
        toml::Value::Table(t) => t.entry(first.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new())),
        toml::Value::Array(a) => {
            let i: usize = first.parse().map_err(|_| format!("'{first}' indexes an array: it must be a number"))?;
            let len = a.len();
            a.get_mut(i).ok_or_else(|| format!("index {i} is past the array's {len} entries"))?
        }
        _ => return Err(format!("'{first}' is inside a value that is neither a table nor an array")),
    };
    if rest.is_empty() {
        *child = value;
        Ok(())
    } else {
        set_value(child, rest, value)
    }
}

/// The 1-based line and column of byte `offset` in `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

/// Builds the scene a scene file's text describes; `path` names it in messages and is
/// what mesh files are resolved against.
pub fn parse_scene_file(text: &str, path: &Path) -> Result<Scene> {
    let at = |span: Range<usize>, message: String| {
        let (line, column) = line_column(text, span.start);
        Error::ParseAt { path: path.to_path_buf(), line, column, message }
    };
    let file: FileDef = toml::from_str(text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        at(span, e.message().to_string())
    })?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut scene = Scene::default();

    // Materials by name, in the file's (sorted) order.
    let mut materials: BTreeMap<&str, u32> = BTreeMap::new();
    for (name, table) in &file.materials {
        let material = material(name, table, dir).map_err(|(span, m)| at(span, m))?;
        materials.insert(name, scene.materials.len() as u32);
        scene.materials.push(material);
    }
    let material_id = |name: &str, span: Range<usize>| {
        materials.get(name).copied().ok_or_else(|| {
            let known: Vec<&str> = materials.keys().copied().collect();
            at(
                span,
                format!(
                    "no material '{name}' (defined: {})",
                    if known.is_empty() { "none".into() } else { known.join(", ") }
                ),
            )
        })
    };

    let mut mesh_camera = None;
    // A file named by several [[mesh]] tables is loaded once and instanced (two-level BVH)
    // rather than copied; its object, by file and camera.
    let mut uses: BTreeMap<(&str, Option<&str>), usize> = BTreeMap::new();
    for def in &file.mesh {
        let m = def.get_ref();
        *uses.entry((m.file.as_str(), m.camera.as_deref())).or_default() += 1;
    }
    let mut objects: BTreeMap<(&str, Option<&str>), u32> = BTreeMap::new();
    for def in &file.mesh {
        let span = def.span();
        let m = def.get_ref();
        let key = (m.file.as_str(), m.camera.as_deref());
        let transform = mesh_transform(m).map_err(|e| at(span.clone(), e))?;
        let material = m.material.as_deref().map(|name| material_id(name, span.clone())).transpose()?;
        if let Some(&object) = objects.get(&key) {
            scene.place_with(object, transform, material).map_err(|e| at(span.clone(), e.to_string()))?;
            continue;
        }
        let mesh_path = dir.join(&m.file);
        let ext = mesh_path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        let loaded = match ext.as_deref() {
            Some("obj") => {
                if m.camera.is_some() {
                    return Err(at(span, format!("{}: camera: OBJ files have no cameras", m.file)));
                }
                load_obj(&mesh_path)?
            }
            Some("gltf" | "glb") => load_gltf(&mesh_path, &GltfOptions { camera: m.camera.clone() })?.scene,
            _ => return Err(at(span, format!("{}: meshes are .obj, .gltf or .glb files", m.file))),
        };
        if mesh_camera.is_none() {
            mesh_camera = loaded.camera.map(|c| transform_camera(&c, &transform));
        }
        // (A glTF file with instances of its own is copied: objects do not nest.)
        if uses[&key] > 1 && loaded.instances.is_empty() {
            let object = scene.add_object(loaded, None).map_err(|e| at(span.clone(), e.to_string()))?;
            scene.place_with(object, transform, material).map_err(|e| at(span.clone(), e.to_string()))?;
            objects.insert(key, object);
        } else {
            scene.append(loaded, &transform, material).map_err(|e| at(span.clone(), e.to_string()))?;
        }
    }

    for def in &file.shape {
        let span = def.span();
        let shape_error = |e: shapes::ShapeError| at(span.clone(), e.to_string());
        let (shape, material) = match def.get_ref() {
            ShapeDef::Sphere { center, radius, material } => (
                ShapeKind::Sphere(
                    Sphere::new((*center).into(), *radius, SphereMethod::default()).map_err(shape_error)?,
                ),
                material,
            ),
            ShapeDef::Box { min, max, material } => {
                (ShapeKind::Cuboid(Cuboid::axis_aligned((*min).into(), (*max).into()).map_err(shape_error)?), material)
            }
            ShapeDef::Polygon { vertices, material } => {
                let vertices = vertices.iter().map(|&v| Vec3::from(v)).collect();
                (ShapeKind::Polygon(Polygon::new(vertices, InsideTest::default()).map_err(shape_error)?), material)
            }
            ShapeDef::Implicit { expression, min, max, material } => {
                let poly = shapes::implicit::parse(expression).map_err(shape_error)?;
                let bounds = shapes::Aabb { min: (*min).into(), max: (*max).into() };
                (
                    ShapeKind::Implicit(Implicit::new(poly, bounds, RootSolver::ClosedForm).map_err(shape_error)?),
                    material,
                )
            }
        };
        let id = material_id(material, span.clone())?;
        scene.add_shape_with_material(shape, id);
    }

    for def in &file.light {
        let span = def.span();
        let colour = |c: &ColourDef| c.colour(ColourRole::Illuminant, dir).map_err(|e| at(span.clone(), e));
        let light = match def.get_ref() {
            LightDef::Point { position, intensity } => PunctualLight::point((*position).into(), colour(intensity)?),
            LightDef::Spot { position, direction, inner, outer, intensity } => PunctualLight::spot(
                (*position).into(),
                (*direction).into(),
                colour(intensity)?,
                inner.to_radians(),
                outer.to_radians(),
            ),
            LightDef::Sun { direction, irradiance, diameter } => {
                PunctualLight::sun((*direction).into(), colour(irradiance)?, diameter.to_radians())
            }
        };
        light.validate().map_err(|e| at(span.clone(), e))?;
        scene.punctual_lights.push(light);
    }

    if let Some(sky) = &file.sky {
        let def = sky.get_ref();
        let radiance = match &def.radiance {
            Some(c) => Some(c.colour(ColourRole::Illuminant, dir).map_err(|e| at(sky.span(), e))?),
            None => None,
        };
        scene.environment = Some(match &def.map {
            Some(file) => {
                let map =
                    EnvironmentMap::load(&dir.join(file), def.rotation).map_err(|e| at(sky.span(), e.to_string()))?;
                Environment { radiance: radiance.unwrap_or(Colour::constant(1.0)), map: Some(std::sync::Arc::new(map)) }
            }
            None => {
                let Some(radiance) = radiance else {
                    return Err(at(sky.span(), "[sky] needs a radiance, a map, or both".into()));
                };
                Environment::uniform(radiance)
            }
        });
    }

    scene.camera = match &file.camera {
        Some(def) => {
            let c = def.get_ref();
            let camera = Camera { eye: c.eye.into(), center: c.center.into(), up: c.up.into(), fov_y_deg: c.fov };
            camera.validate().map_err(|e| at(def.span(), e.to_string()))?;
            Some(camera)
        }
        None => mesh_camera,
    };
    scene.validate().map_err(|e| Error::parse(path, e.to_string()))?;
    Ok(scene)
}

/// A material table: `model`, an optional `emission`, and the model's parameters; an
/// error comes with the span of the value at fault (the table's for a missing model).
fn material(
    name: &str,
    table: &Spanned<MaterialDef>,
    dir: &Path,
) -> std::result::Result<Material, (Range<usize>, String)> {
    let what = |span: Range<usize>, m: String| (span, format!("material '{name}': {m}"));
    let model = match table.get_ref().get("model") {
        Some(v) => match v.get_ref() {
            toml::Value::String(m) => ModelId::by_name(m)
                .ok_or_else(|| what(v.span(), format!("unknown model '{m}' (known: {})", ModelId::names())))?,
            _ => return Err(what(v.span(), "model must be a string".into())),
        },
        None => return Err(what(table.span(), format!("needs a model (one of {})", ModelId::names()))),
    };
    let mut params = Vec::new();
    let mut emission = None;
    for (key, spanned) in table.get_ref() {
        let number = |v: &toml::Value| match v {
            toml::Value::Float(f) => Some(*f as f32),
            toml::Value::Integer(i) => Some(*i as f32),
            _ => None,
        };
        let value = match spanned.get_ref() {
            v @ (toml::Value::Float(_) | toml::Value::Integer(_)) => ParamValue::Scalar(number(v).unwrap_or(0.0)),
            toml::Value::Boolean(b) => ParamValue::Bool(*b),
            toml::Value::String(s) => ParamValue::Name(s.clone()),
            toml::Value::Array(a) if a.len() == 3 && a.iter().all(|v| number(v).is_some()) => {
                ParamValue::Rgb([0, 1, 2].map(|i| number(&a[i]).unwrap_or(0.0)))
            }
            toml::Value::Table(t) => {
                let fail = |e: String| what(spanned.span(), format!("{key}: {e}"));
                let def: SpectrumDef = toml::Value::Table(t.clone()).try_into().map_err(|e| fail(format!("{e}")))?;
                let role = if key == "emission" { ColourRole::Illuminant } else { ColourRole::Reflectance };
                ParamValue::Colour(ColourDef::Spectrum(def).colour(role, dir).map_err(fail)?)
            }
            _ => {
                let m = format!("{key}: expected a number, three numbers, a spectrum table, a name or true/false");
                return Err(what(spanned.span(), m));
            }
        };
        match key.as_str() {
            "model" => {}
            "emission" => {
                let colour = match value {
                    ParamValue::Scalar(v) => Colour::illuminant_rgb([v; 3]),
                    ParamValue::Rgb(c) => Colour::illuminant_rgb(c),
                    ParamValue::Colour(c) => Ok(c),
                    _ => return Err(what(spanned.span(), "emission: expected a colour or a spectrum".into())),
                };
                emission = Some(colour.map_err(|e| what(spanned.span(), format!("emission: {e}")))?);
            }
            _ => params.push((key.as_str(), value)),
        }
    }
    let mut m = Material::builtin(name, model, &params).map_err(|e| {
        // The message names the material already; point at the parameter's value.
        let span = e.param().and_then(|p| table.get_ref().get(p)).map_or(table.span(), |v| v.span());
        (span, e.to_string())
    })?;
    m.emission = emission.filter(|e| !e.is_black());
    Ok(m)
}

/// The mesh's transform: scale, then rotate, then translate.
fn mesh_transform(m: &MeshDef) -> std::result::Result<Mat4, String> {
    let scale = match m.scale {
        None => Vec3::ONE,
        Some(ScaleDef::Uniform(s)) => Vec3::splat(s),
        Some(ScaleDef::Axes(s)) => s.into(),
    };
    if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() {
        return Err(format!("scale {scale} must be finite and non-zero"));
    }
    let rotation = match &m.rotate {
        None => Quat::IDENTITY,
        Some(r) => {
            let axis = Vec3::from(r.axis)
                .try_normalize()
                .ok_or_else(|| format!("rotate: axis {:?} is not a direction", r.axis))?;
            if !r.degrees.is_finite() {
                return Err("rotate: degrees must be finite".into());
            }
            Quat::from_axis_angle(axis, r.degrees.to_radians())
        }
    };
    let translate = Vec3::from(m.translate);
    if !translate.is_finite() {
        return Err("translate must be finite".into());
    }
    Ok(Mat4::from_scale_rotation_translation(scale, rotation, translate))
}

/// A mesh file's camera moved by the mesh's transform.
fn transform_camera(c: &Camera, t: &Mat4) -> Camera {
    let linear = Mat3::from_mat4(*t);
    Camera {
        eye: t.transform_point3(c.eye),
        center: t.transform_point3(c.center),
        up: (linear * c.up).normalize_or(c.up),
        fov_y_deg: c.fov_y_deg,
    }
}

#[cfg(test)]
mod tests;
