//! SPEC files: the thesis's JSON format for spectral power distributions (its § 8.5 and
//! listing 8.7), which go beside an OBJ and its MTL:
//!
//! ```json
//! {
//!     "materials": { "Metal": { "diff": "golden", "spec": "golden" } },
//!     "sky": "CIE_D65",
//!     "spectra": {
//!         "CIE_D65": { "380": 0.444027773062, "385": 0.463859369164, "775": 0.537999524666 },
//!         "golden": { "380": 0.2, "500": 0.35, "600": 0.8, "775": 0.95 }
//!     }
//! }
//! ```
//!
//! `spectra` defines SPDs as wavelength (nm) → value tables (linear in between, the end
//! values beyond: the thesis samples 380–775 nm); `materials` gives an MTL material a
//! diffuse SPD (`diff`: the colour its model reads from `Kd` or `Rd`) and a specular one
//! (`spec`: from `Ks`, `Rs` or `Tf`, or a conductor's tint); `sky` lights the scene with
//! a uniform environment of that SPD. Diffuse and specular SPDs are reflectances, so their
//! values must lie in [0, 1]. A role the material's model lacks (a mirror has no diffuse
//! colour) is reported, not an error; a material or SPD name that does not exist is.

use crate::material::{Material, Surface};
use crate::scene::{Environment, Scene};
use crate::{Error, Result};
use brdf::params::Resolved;
use serde::Deserialize;
use spectral::spectrum::{Colour, ColourRole, Spectrum, TabulatedSpectrum};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecDef {
    #[serde(default)]
    materials: BTreeMap<String, RolesDef>,
    sky: Option<String>,
    #[serde(default)]
    spectra: BTreeMap<String, BTreeMap<String, f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RolesDef {
    diff: Option<String>,
    spec: Option<String>,
}

/// A named SPD.
pub type NamedSpectrum = (String, TabulatedSpectrum);

/// A SPEC file, its SPD names resolved.
#[derive(Clone, Debug)]
pub struct SpecFile {
    /// Where it was read from (for messages).
    pub path: PathBuf,
    /// Per material name: its diffuse and specular SPDs (name and spectrum).
    pub materials: BTreeMap<String, (Option<NamedSpectrum>, Option<NamedSpectrum>)>,
    /// The sky's SPD, if the file names one.
    pub sky: Option<NamedSpectrum>,
}

/// The MTL keys of the parameters a `diff` SPD sets.
const DIFFUSE_KEYS: [&str; 2] = ["Kd", "Rd"];
/// The MTL keys of the parameters a `spec` SPD sets (and a conductor's key-less `tint`).
const SPECULAR_KEYS: [&str; 3] = ["Ks", "Rs", "Tf"];

/// The SPEC file the thesis's convention puts beside `obj`: the same name with the
/// extension `.spec`, if it exists.
pub fn spec_beside(obj: &Path) -> Option<PathBuf> {
    let spec = obj.with_extension("spec");
    spec.is_file().then_some(spec)
}

/// Reads a SPEC file.
pub fn load_spec(path: &Path) -> Result<SpecFile> {
    let text = crate::obj::read_text_file(path)?;
    parse_spec(&text, path)
}

/// The SPDs of a SPEC file by name (its `materials` and `sky` are not checked), for scene
/// files that take one of its spectra.
pub fn load_spec_spectra(path: &Path) -> Result<BTreeMap<String, TabulatedSpectrum>> {
    let text = crate::obj::read_text_file(path)?;
    Ok(parse_spectra(&text, path)?.0)
}

/// Parses a SPEC file's text; `path` names it in messages.
pub fn parse_spec(text: &str, path: &Path) -> Result<SpecFile> {
    let fail = |message: String| Error::parse(path, message);
    let (spectra, above_one, def) = parse_spectra(text, path)?;
    let lookup = |what: String, name: &str| {
        spectra.get(name).cloned().map(|t| (name.to_string(), t)).ok_or_else(|| {
            let known: Vec<&str> = spectra.keys().map(String::as_str).collect();
            let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
            fail(format!("{what}: no spectrum '{name}' in spectra (defined: {known})"))
        })
    };
    let reflectance = |what: String, name: &str| {
        let (name, t) = lookup(what.clone(), name)?;
        match above_one.get(&name) {
            Some((l, v)) => Err(fail(format!("{what}: '{name}' is a reflectance but is {v} > 1 at {l} nm"))),
            None => Ok((name, t)),
        }
    };
    let mut materials = BTreeMap::new();
    for (material, roles) in &def.materials {
        let diff = roles.diff.as_deref().map(|n| reflectance(format!("materials.{material}.diff"), n)).transpose()?;
        let spec = roles.spec.as_deref().map(|n| reflectance(format!("materials.{material}.spec"), n)).transpose()?;
        materials.insert(material.clone(), (diff, spec));
    }
    let sky = def.sky.as_deref().map(|n| lookup("sky".into(), n)).transpose()?;
    Ok(SpecFile { path: path.to_path_buf(), materials, sky })
}

/// A SPEC text's SPDs by name, each SPD's first value above 1, and the file as read.
type Spectra = (BTreeMap<String, TabulatedSpectrum>, BTreeMap<String, (f32, f32)>, SpecDef);

fn parse_spectra(text: &str, path: &Path) -> Result<Spectra> {
    let fail = |message: String| Error::parse(path, message);
    let def: SpecDef = serde_json::from_str(text).map_err(|e| match e.line() {
        0 => fail(e.to_string()),
        line => Error::ParseAt { path: path.to_path_buf(), line, column: e.column(), message: e.to_string() },
    })?;
    let mut spectra = BTreeMap::new();
    // Each SPD's first value above 1 (a reflectance cannot have one).
    let mut above_one = BTreeMap::new();
    for (name, table) in &def.spectra {
        let mut points = Vec::with_capacity(table.len());
        for (lambda, &value) in table {
            let l: f32 = lambda
                .trim()
                .parse()
                .ok()
                .filter(|l: &f32| l.is_finite() && *l > 0.0)
                .ok_or_else(|| fail(format!("spectra.{name}: '{lambda}' is not a wavelength in nm")))?;
            if !value.is_finite() || value < 0.0 {
                return Err(fail(format!("spectra.{name}.{lambda}: {value} is not a non-negative number")));
            }
            points.push((l, value as f32));
        }
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(w) = points.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(fail(format!("spectra.{name}: wavelength {} is given twice", w[0].0)));
        }
        if let Some(&p) = points.iter().find(|p| p.1 > 1.0) {
            above_one.insert(name.clone(), p);
        }
        let (lambda, value) = points.into_iter().unzip();
        let table = TabulatedSpectrum::new(lambda, value).map_err(|e| fail(format!("spectra.{name}: {e}")))?;
        spectra.insert(name.clone(), table);
    }
    Ok((spectra, above_one, def))
}

impl SpecFile {
    /// Gives the scene's materials their SPDs and the scene the sky; returns notes on roles
    /// a material's model has no colour for. Every material the file names must exist.
    pub fn apply(&self, scene: &mut Scene) -> Result<Vec<String>> {
        let fail = |message: String| Error::parse(&self.path, message);
        let mut notes = Vec::new();
        for (name, (diff, spec)) in &self.materials {
            if !scene.materials.iter().any(|m| &m.name == name) {
                let known: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
                return Err(fail(format!(
                    "materials.{name}: no such material in the scene (it has: {})",
                    known.join(", ")
                )));
            }
            for m in scene.materials.iter_mut().filter(|m| &m.name == name) {
                let roles =
                    [("diff", "diffuse", &DIFFUSE_KEYS[..], diff), ("spec", "specular", &SPECULAR_KEYS[..], spec)];
                for (role, colour, keys, spd) in roles {
                    let Some((spd_name, table)) = spd else { continue };
                    if !set_colours(m, keys, role == "spec", table) {
                        let model = m.model().map_or("custom", |id| id.name());
                        notes.push(format!(
                            "material '{name}' ({model}) has no {colour} colour: its {role} spectrum '{spd_name}' is unused"
                        ));
                    }
                }
            }
        }
        if let Some(radiance) = self.sky_radiance() {
            scene.environment = Some(Environment::uniform(radiance));
        }
        Ok(notes)
    }

    /// The sky's radiance, if the file names a sky SPD.
    pub fn sky_radiance(&self) -> Option<Colour> {
        self.sky
            .as_ref()
            .map(|(_, table)| Colour::from_spectrum(Spectrum::Tabulated(table.clone()), ColourRole::Illuminant))
    }
}

/// Sets every spectrum parameter of `m` whose MTL key is one of `keys` (and, for the
/// specular role, a key-less `tint`) to `table`; false if it has none.
fn set_colours(m: &mut Material, keys: &[&str], specular: bool, table: &TabulatedSpectrum) -> bool {
    let Some(params) = m.params() else { return false };
    let model = params.model();
    let mut values = params.to_resolved().values().to_vec();
    let colour = Colour::from_spectrum(Spectrum::Tabulated(table.clone()), ColourRole::Reflectance);
    let mut any = false;
    for (value, def) in values.iter_mut().zip(model.def().params) {
        let matches = match def.mtl_key {
            Some(key) => keys.contains(&key),
            None => specular && def.name == "tint",
        };
        if matches && matches!(value, Resolved::Colour(_)) {
            *value = Resolved::Colour(colour.clone());
            any = true;
        }
    }
    if any {
        m.surface = Surface::Builtin(model.from_resolved(&brdf::params::ResolvedParams::from_values(values)));
    }
    any
}

#[cfg(test)]
mod tests;
