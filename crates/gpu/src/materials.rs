//! WGSL generated from the BSDF parameter definitions.
//!
//! [`generate`] turns a scene's materials into a [`MaterialKernel`]: WGSL source for the
//! path kernel to concatenate with its own, and the two storage buffers it reads. What
//! is generated, and from what:
//!
//! * per compiled model, from its [`ModelDef`]: a struct `<Model>Params` with one field per
//!   declared parameter, in declaration order and under the declared name (a scalar is an
//!   `f32`; a spectrum or coefficient is a `u32` offset into `spectra`), and
//!   `load_<model>(base: u32) -> <Model>Params`, which unpacks it from `material_data`;
//!   the Rust side packs each material's [`ResolvedParams`] by walking the same
//!   declarations (`pack_params`), so field order and packing cannot drift apart;
//! * the dispatch `bsdf_eval`/`bsdf_pdf`/`bsdf_sample` (a `switch` over the compiled
//!   models), the material accessors, the scatter-flag constants (from
//!   [`ScatterFlags::bits`]) and the numeric constants the model code shares with the CPU
//!   (GGX's α floor, Schlick's clamps, the Sellmeier coefficients, …);
//! * the measured metal tables ([`Metal::table`]) of the presets the scene uses, copied
//!   into `spectra` as they are.
//!
//! The per-model mathematics is hand-written WGSL that each model ships beside its Rust
//! file in `crates/brdf` ([`brdf::wgsl::ModelWgsl`], a line-by-line transcription taking
//! the generated params struct:
//! `fn <model>_eval(p: <Model>Params, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f`,
//! `<model>_pdf(…) -> f32` and `<model>_sample(p, wo, uc: f32, u: vec2f, lambda) -> BsdfSample`);
//! shared pieces ([`WgslPiece`]: Fresnel, cosine sampling, GGX, metals, dispersion) are
//! compiled in only when a compiled model needs them. This file names no model: it
//! iterates the registry ([`ModelId::ALL`]), so a model registered in `brdf` runs on the
//! GPU without a change here. The GPU tests compare every twin with its Rust model.
//!
//! # Specialisation
//!
//! With `specialise = true` only the models the materials use are compiled in, and only
//! the features they use: the Cauchy/Sellmeier code only if some material disperses
//! (otherwise `mat_dispersion_ior` is a stub returning the constant index), the tables
//! of the metal presets in use only, emission and absorption lookups only if some
//! material emits or absorbs (otherwise the accessors return zero). With
//! `specialise = false` all nine models and every feature are compiled in.
//!
//! # The WGSL contract
//!
//! ```wgsl
//! @group(0) @binding(10) var<storage, read> material_data: array<u32>;
//! @group(0) @binding(11) var<storage, read> spectra: array<f32>;
//! struct BsdfSample { wi: vec3f, f: vec4f, pdf: f32, flags: u32 }   // pdf == 0: no sample
//! const SCATTER_REFLECTION: u32 = 1u; … SCATTER_WAVELENGTH_DEPENDENT: u32 = 32u;
//! fn spectrum_at(offset: u32, lambda: vec4f) -> vec4f;
//! fn material_flags(m: u32) -> u32;
//! fn material_two_sided(m: u32) -> bool;
//! fn material_dispersive(m: u32) -> bool;
//! fn material_emission(m: u32, lambda: vec4f) -> vec4f;
//! fn material_absorption(m: u32, lambda: vec4f) -> vec4f;
//! fn material_absorbing(m: u32) -> bool;
//! fn material_eta(m: u32) -> f32;
//! fn material_eta_at(m: u32, lambda: vec4f) -> f32;
//! fn mat_set_texels(m: u32, base: vec4f, spec: vec4f, roughness: f32, metallic: f32);
//! fn mat_clear_texels();
//! fn bsdf_eval(m: u32, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f;
//! fn bsdf_pdf(m: u32, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32;
//! fn bsdf_sample(m: u32, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample;
//! ```
//!
//! Every other identifier the generated source declares starts with `mat_`, `MAT_`,
//! `SPECTRUM_`, `MATERIAL_`, a model's name (`lambert_…`, `load_lambert`) or ends in
//! `Params`/`State`, so that the path kernel can use any other name.
//!
//! # Buffer layout
//!
//! `material_data` (u32 words; f32 stored by `to_bits`): first one header of
//! [`HEADER_WORDS`] words per material, in scene order (material `m` at
//! `m * HEADER_WORDS`), then each material's parameters:
//!
//! | word | [`header`] | content |
//! |---|---|---|
//! | 0 | `MODEL` | the model's index in [`ModelId::ALL`] ([`model_id`]) |
//! | 1 | `FLAGS` | [`ScatterFlags`] bits: the union of `bsdf.flags()` over 360–830 nm |
//! | 2 | `PROPERTIES` | [`PROPERTY_TWO_SIDED`] \| [`PROPERTY_DISPERSIVE`] |
//! | 3 | `EMISSION` | offset of the emitted radiance in `spectra`, or [`NO_SPECTRUM`] |
//! | 4 | `ABSORPTION` | offset of the absorption coefficient in `spectra`, or [`NO_SPECTRUM`] |
//! | 5 | `PARAMS` | word index of the material's parameters (one word per declared parameter) |
//! | 6 | `BASE_SLOT` | offset in `spectra` of the parameter a base-colour texture multiplies, or [`NO_SPECTRUM`] |
//! | 7 | `SPECULAR_SLOT` | the same for a specular texture |
//! | 8 | `ETA` | f32: `bsdf.eta()` at 587.56 nm (1 for a BSDF that does not refract), which Russian roulette undoes transmission's radiance compression with |
//!
//! `spectra` (f32): every distinct colour the materials use (parameters, emission,
//! absorption), each tabulated at 1 nm from [`SPECTRUM_LAMBDA_MIN`] ([`SPECTRUM_SAMPLES`]
//! values, [`tabulate`]) and followed by its linear-sRGB value (RGB mode reads that:
//! [`COLOUR_FLOATS`] in all), identical entries stored once; then the (λ, n, k) rows of
//! the metal presets in use. Neither vector is ever empty (a zero is stored if nothing else).

use crate::GpuError;
use brdf::models::{Metal, MetalPreset};
use brdf::params::{ModelDef, ParamChoice, ParamKind, Resolved, ResolvedParams};
use brdf::wgsl::{COMMON, ModelWgsl, WgslPiece};
use brdf::{Bsdf, ModelId, ScatterFlags};
use spectral::SampledWavelengths;
use spectral::spectrum::Colour;
use std::collections::HashMap;
use std::fmt::Write as _;
use tracer::material::{Material, Surface};

/// The first wavelength (nm) of every table in `spectra`.
pub const SPECTRUM_LAMBDA_MIN: f32 = spectral::sampled::LAMBDA_MIN;
/// Entries per table: one per nm from 360 to 830 nm inclusive.
pub const SPECTRUM_SAMPLES: usize = (spectral::sampled::LAMBDA_MAX - spectral::sampled::LAMBDA_MIN) as usize + 1;
/// Words per material header in `material_data`.
pub const HEADER_WORDS: u32 = 9;
/// The offset that stands for "no spectrum" (no emission, no absorption).
pub const NO_SPECTRUM: u32 = u32::MAX;
/// Header property bit: the BSDF acts on both faces alike ([`Material::is_two_sided`]).
pub const PROPERTY_TWO_SIDED: u32 = 1;
/// Header property bit: the index of refraction varies with wavelength
/// ([`Material::is_dispersive`]).
pub const PROPERTY_DISPERSIVE: u32 = 2;

/// Word indices within a material header.
pub mod header {
    /// The model id ([`super::model_id`]).
    pub const MODEL: u32 = 0;
    /// The scatter flags.
    pub const FLAGS: u32 = 1;
    /// [`super::PROPERTY_TWO_SIDED`] | [`super::PROPERTY_DISPERSIVE`].
    pub const PROPERTIES: u32 = 2;
    /// Emission spectrum offset or [`super::NO_SPECTRUM`].
    pub const EMISSION: u32 = 3;
    /// Absorption spectrum offset or [`super::NO_SPECTRUM`].
    pub const ABSORPTION: u32 = 4;
    /// Word index of the parameters.
    pub const PARAMS: u32 = 5;
    /// The `spectra` offset of the parameter a base-colour texture multiplies (its own
    /// copy), or [`super::NO_SPECTRUM`] without such a texture.
    pub const BASE_SLOT: u32 = 6;
    /// The same for a specular texture.
    pub const SPECULAR_SLOT: u32 = 7;
    /// The relative index of refraction (f32 bits).
    pub const ETA: u32 = 8;
}

/// The optional code paths a kernel contains besides its models.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Features {
    /// Wavelength-dependent index of refraction (Cauchy, Sellmeier presets).
    pub dispersion: bool,
    /// Beer–Lambert absorption coefficients (`material_absorption` reads them).
    pub absorption: bool,
    /// Emitted radiance (`material_emission` reads it).
    pub emission: bool,
    /// The measured metal presets whose tables are uploaded, in [`Metal::ALL`] order.
    pub metals: Vec<Metal>,
    /// Texels driving BSDF parameters (`mat_set_texels`; without, the code is not compiled in).
    pub textures: bool,
}

impl Features {
    /// Everything (the unspecialised kernel).
    pub fn all() -> Self {
        Self { dispersion: true, absorption: true, emission: true, metals: Metal::ALL.to_vec(), textures: true }
    }

    /// What `materials` use.
    pub fn of(materials: &[Material]) -> Self {
        let mut metals = Vec::new();
        for m in materials {
            if let Some(params) = m.params()
                && let Some((i, _)) = params.model().def().param("metal")
                && let Resolved::Choice(k) = params.to_resolved().values()[i]
                && let Some(metal) = MetalPreset::from_index(k).and_then(MetalPreset::metal)
                && !metals.contains(&metal)
            {
                metals.push(metal);
            }
        }
        metals.sort_by_key(|m| Metal::ALL.iter().position(|a| a == m));
        Self {
            dispersion: materials.iter().any(Material::is_dispersive),
            absorption: materials.iter().any(|m| m.absorption().is_some()),
            emission: materials.iter().any(|m| m.emission.is_some()),
            metals,
            textures: materials.iter().any(|m| m.textures.is_some()),
        }
    }
}

/// The materials part of a GPU kernel: WGSL and the buffers it reads.
#[derive(Clone, Debug)]
pub struct MaterialKernel {
    /// WGSL to concatenate with the path kernel (see the module documentation for what
    /// it declares).
    pub wgsl: String,
    /// The `material_data` buffer (binding 10): headers, then parameters.
    pub data: Vec<u32>,
    /// The `spectra` buffer (binding 11): 1-nm tables, then metal tables.
    pub spectra: Vec<f32>,
    /// The models compiled in, in [`ModelId::ALL`] order.
    pub models: Vec<ModelId>,
    /// The optional code paths compiled in.
    pub features: Features,
}

/// The id of `model` in `material_data` headers: its index in [`ModelId::ALL`].
pub fn model_id(model: ModelId) -> u32 {
    model.index()
}

/// What the generator needs of a model: its id in `material_data` headers, its
/// declaration and its WGSL twin. The generator compiles the models of any registry
/// ([`ModelEntry::of`] for the built-in one; `tests/toy_model.rs` registers another) and
/// the twins custom BSDFs ship ([`brdf::wgsl::WgslTwin`]; ids after the registry's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelEntry {
    /// The id the headers carry (the model's index in its registry).
    pub id: u32,
    /// The parameter declaration.
    pub def: ModelDef,
    /// The hand-written WGSL.
    pub wgsl: ModelWgsl,
}

impl ModelEntry {
    /// The entry of a model of the built-in registry.
    pub fn of(model: ModelId) -> Self {
        Self { id: model_id(model), def: *model.def(), wgsl: *model.wgsl() }
    }
}

/// Whether a resolved value has the kind its declaration says (a custom twin's values
/// come from its builder, unchecked by the registry).
fn kind_matches(kind: ParamKind, value: &Resolved) -> bool {
    matches!(
        (kind, value),
        (ParamKind::Scalar, Resolved::Scalar(_))
            | (ParamKind::Spectrum | ParamKind::Coefficient, Resolved::Colour(_))
            | (ParamKind::Bool, Resolved::Bool(_))
            | (ParamKind::Choice(_), Resolved::Choice(_))
    )
}

/// The entry and values of custom material `m`'s WGSL twin; `twins` holds the twins seen so
/// far (one entry per twin name, ids after the registry's).
fn twin_entry(m: &Material, twins: &mut Vec<ModelEntry>) -> Result<(ModelEntry, ResolvedParams), GpuError> {
    let twin = m.wgsl_twin().ok_or_else(|| {
        GpuError::Unsupported(format!(
            "custom BSDF without a WGSL twin in material '{}' (give its BsdfBuilder a wgsl_twin)",
            m.name
        ))
    })?;
    let bad =
        |what: String| GpuError::Shader(format!("the WGSL twin '{}' of material '{}': {what}", twin.def.name, m.name));
    let values = twin.params.values();
    if values.len() != twin.def.params.len() {
        return Err(bad(format!("{} values for {} declared parameters", values.len(), twin.def.params.len())));
    }
    if let Some((p, v)) = twin.def.params.iter().zip(values).find(|(p, v)| !kind_matches(p.kind, v)) {
        return Err(bad(format!("parameter '{}' is declared {:?} but given {v:?}", p.name, p.kind)));
    }
    if ModelId::ALL.iter().any(|b| b.def().name == twin.def.name) {
        return Err(bad("a registered model has that name (its WGSL identifiers would collide)".into()));
    }
    // Textures never reach a custom BSDF (on the CPU neither).
    let wgsl = ModelWgsl { texture: brdf::wgsl::WgslTextureSlots::NONE, ..twin.wgsl };
    let entry = match twins.iter().find(|e| e.def.name == twin.def.name) {
        Some(e) if e.def == twin.def && e.wgsl == wgsl => *e,
        Some(_) => return Err(bad("another material's twin has that name but other WGSL or parameters".into())),
        None => {
            let id = (ModelId::ALL.len() + twins.len()) as u32;
            twins.push(ModelEntry { id, def: twin.def, wgsl });
            twins[twins.len() - 1]
        }
    };
    Ok((entry, twin.params))
}

/// The name of the generated params struct of a model: its declared name, capitalised,
/// followed by `Params` (`lambert` → `LambertParams`).
pub fn params_struct_name(def: &ModelDef) -> String {
    let mut chars = def.name.chars();
    let first = chars.next().map(|c| c.to_ascii_uppercase()).into_iter();
    first.chain(chars).chain("Params".chars()).collect()
}

/// `colour` at 1-nm steps from [`SPECTRUM_LAMBDA_MIN`]: [`SPECTRUM_SAMPLES`] values of
/// [`Colour::sample`] (spectral mode).
pub fn tabulate(colour: &Colour) -> Vec<f32> {
    (0..SPECTRUM_SAMPLES)
        .map(|i| colour.sample(&SampledWavelengths::<1>::fixed_bins(SPECTRUM_LAMBDA_MIN + i as f32, 1.0)).0[0])
        .collect()
}

/// Floats of a colour's entry in `spectra`: its [`tabulate`] table, then its linear-sRGB
/// value (what `spectrum_at` reads in RGB mode).
pub const COLOUR_FLOATS: usize = SPECTRUM_SAMPLES + 3;

/// A colour's entry ([`COLOUR_FLOATS`]): its [`tabulate`] table, then its linear sRGB —
/// as `spectra` and the path kernel's own tables (`pt_table_spectrum`) hold colours.
pub fn colour_entry(colour: &Colour) -> Vec<f32> {
    let mut entry = tabulate(colour);
    entry.extend(colour.rgb);
    entry
}

/// The line of the generated WGSL that says which mode the materials run in; a kernel for
/// RGB mode takes the WGSL through [`for_mode`].
const HERO_MODE_LINE: &str = "const MAT_RGB: bool = false;\n";

/// The materials WGSL of `generate` for an RGB-mode kernel (`MAT_RGB`: colours as their
/// linear-sRGB values, no dispersion), or unchanged for the spectral modes.
pub fn for_mode(wgsl: &str, rgb: bool) -> String {
    assert!(wgsl.contains(HERO_MODE_LINE), "not the generator's WGSL");
    if rgb { wgsl.replacen(HERO_MODE_LINE, "const MAT_RGB: bool = true;\n", 1) } else { wgsl.to_string() }
}

/// The CPU twin of WGSL `spectrum_at` for one wavelength: linear interpolation in a
/// table made by [`tabulate`], λ clamped to the table.
pub fn spectrum_lookup(table: &[f32], lambda: f32) -> f32 {
    let last = (SPECTRUM_SAMPLES - 1) as f32;
    let x = (lambda - SPECTRUM_LAMBDA_MIN).clamp(0.0, last);
    let i = (x as usize).min(SPECTRUM_SAMPLES - 2);
    let t = x - i as f32;
    table[i] + t * (table[i + 1] - table[i])
}

/// Every spectrum of a kernel, deduplicated by value.
#[derive(Default)]
struct SpectrumPool {
    data: Vec<f32>,
    index: HashMap<Vec<u32>, u32>,
}

impl SpectrumPool {
    fn offset(&self) -> Result<u32, GpuError> {
        u32::try_from(self.data.len()).ok().filter(|&o| o != NO_SPECTRUM).ok_or(GpuError::Limit {
            what: "spectra",
            needed: 4 * self.data.len() as u64,
            limit_name: "u32 offsets",
            limit: 4 * u32::MAX as u64,
        })
    }

    /// The offset of `colour`'s entry ([`COLOUR_FLOATS`]), adding it if new.
    fn colour(&mut self, colour: &Colour) -> Result<u32, GpuError> {
        let table = colour_entry(colour);
        let key: Vec<u32> = table.iter().map(|v| v.to_bits()).collect();
        if let Some(&o) = self.index.get(&key) {
            return Ok(o);
        }
        let o = self.offset()?;
        self.data.extend_from_slice(&table);
        self.index.insert(key, o);
        Ok(o)
    }

    /// Appends raw values, returning their offset.
    fn raw(&mut self, values: impl IntoIterator<Item = f32>) -> Result<u32, GpuError> {
        let o = self.offset()?;
        self.data.extend(values);
        Ok(o)
    }
}

/// One word per declared parameter, in declaration order: a scalar as its f32 bits, a
/// spectrum or coefficient as the offset of its table in `spectra` (added to `pool`; the
/// parameters at `own` get a copy of their own, which a texture may multiply), a switch as
/// 0 or 1, a choice as its index. The layout `load_<model>` reads.
fn pack_params(params: &ResolvedParams, pool: &mut SpectrumPool, own: &[usize]) -> Result<Vec<u32>, GpuError> {
    params
        .values()
        .iter()
        .enumerate()
        .map(|(i, v)| match v {
            Resolved::Colour(c) if own.contains(&i) => pool.raw(colour_entry(c)),
            Resolved::Scalar(x) => Ok(x.to_bits()),
            Resolved::Colour(c) => pool.colour(c),
            Resolved::Bool(b) => Ok(u32::from(*b)),
            Resolved::Choice(k) => Ok(*k),
        })
        .collect()
}

/// The union of the material's CPU `bsdf.flags()` over hero-wavelength sets covering
/// 360–830 nm at 1 nm (flags can depend on the wavelengths: Shirley–Ashikhmin is diffuse
/// only where R_d (1 − R_s) is not zero).
fn material_flags(material: &Material) -> u32 {
    let mut bits = 0u8;
    for first in (0..SPECTRUM_SAMPLES).step_by(4) {
        let wl = SampledWavelengths::<4>::fixed_bins(SPECTRUM_LAMBDA_MIN + first as f32, 1.0);
        bits |= material.bsdf(&wl).flags().bits();
    }
    bits as u32
}

/// The relative index of refraction Russian roulette uses for `material`: its BSDF's at the
/// d line, 587.56 nm (where dispersive presets are anchored). An approximation for a
/// dispersive one is enough: any survival probability keeps the estimate unbiased.
fn material_eta(material: &Material) -> f32 {
    let eta = material.bsdf(&SampledWavelengths::<4>::fixed_bins(587.56, 1.0)).eta();
    if eta.is_finite() && eta > 0.0 { eta } else { 1.0 }
}

/// Builds the WGSL and buffers for `materials` (in scene order: material index `m` in the
/// WGSL is `materials[m]`). `specialise`: compile in only the models and features the
/// materials use (else all). A custom BSDF runs through the WGSL twin its builder ships
/// (compiled in as one more model); one without a twin is refused.
pub fn generate(materials: &[Material], specialise: bool) -> Result<MaterialKernel, GpuError> {
    // Each material's model and values: a registered model's, or its custom BSDF's twin.
    let mut twins = Vec::new();
    let mut resolved = Vec::with_capacity(materials.len());
    for m in materials {
        resolved.push(match &m.surface {
            Surface::Builtin(params) => (ModelEntry::of(params.model()), params.to_resolved()),
            Surface::Custom { .. } => twin_entry(m, &mut twins)?,
        });
    }
    let models: Vec<ModelId> = ModelId::ALL
        .iter()
        .copied()
        .filter(|&model| !specialise || materials.iter().any(|m| m.model() == Some(model)))
        .collect();
    let features = if specialise { Features::of(materials) } else { Features::all() };

    let mut pool = SpectrumPool::default();
    let mut data = vec![0u32; materials.len() * HEADER_WORDS as usize];
    for (k, (material, (entry, values))) in materials.iter().zip(&resolved).enumerate() {
        let h = k * HEADER_WORDS as usize;
        let base =
            u32::try_from(data.len()).map_err(|_| GpuError::Unsupported("over 2³² words of materials".into()))?;
        // The parameters this material's base-colour and specular textures multiply.
        let textures = material.textures.as_deref();
        let slot = |param: Option<&str>, textured: bool| {
            param.filter(|_| textured).and_then(|name| entry.def.param(name)).map(|(i, _)| i)
        };
        let wgsl_slots = entry.wgsl.texture;
        let base_slot = slot(wgsl_slots.base_colour, textures.is_some_and(|t| t.base_colour.is_some()));
        let specular_slot = slot(wgsl_slots.specular, textures.is_some_and(|t| t.specular.is_some()));
        let own: Vec<usize> = base_slot.into_iter().chain(specular_slot).collect();
        let words = pack_params(values, &mut pool, &own)?;
        let slot_offset = |i: Option<usize>| i.map_or(NO_SPECTRUM, |i| words[i]);
        data[h + header::BASE_SLOT as usize] = slot_offset(base_slot);
        data[h + header::SPECULAR_SLOT as usize] = slot_offset(specular_slot);
        data.extend(words);
        let emission = match &material.emission {
            Some(c) => pool.colour(c)?,
            None => NO_SPECTRUM,
        };
        let absorption = match material.absorption() {
            Some(c) => pool.colour(c)?,
            None => NO_SPECTRUM,
        };
        let mut properties = 0;
        if material.is_two_sided() {
            properties |= PROPERTY_TWO_SIDED;
        }
        if material.is_dispersive() {
            properties |= PROPERTY_DISPERSIVE;
        }
        data[h + header::MODEL as usize] = entry.id;
        data[h + header::FLAGS as usize] = material_flags(material);
        data[h + header::PROPERTIES as usize] = properties;
        data[h + header::EMISSION as usize] = emission;
        data[h + header::ABSORPTION as usize] = absorption;
        data[h + header::PARAMS as usize] = base;
        data[h + header::ETA as usize] = material_eta(material).to_bits();
    }
    let entries: Vec<ModelEntry> = models.iter().map(|&m| ModelEntry::of(m)).chain(twins).collect();
    let mut metal_tables = Vec::new();
    if entries.iter().any(|e| e.wgsl.needs.contains(&WgslPiece::Metal)) {
        for &metal in &features.metals {
            let rows = metal.table();
            let offset = pool.raw(rows.iter().flatten().copied())?;
            metal_tables.push((metal, offset, rows.len() as u32));
        }
    }
    let wgsl = wgsl_for(&entries, &features, &metal_tables)?;
    let mut spectra = pool.data;
    if spectra.is_empty() {
        spectra.push(0.0);
    }
    if data.is_empty() {
        data.push(0);
    }
    Ok(MaterialKernel { wgsl, data, spectra, models, features })
}

/// An f32 as a WGSL literal that parses back to the same value.
fn f32_literal(v: f32) -> String {
    assert!(v.is_finite(), "WGSL has no literal for {v}");
    format!("{v:?}f")
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_lowercase() || c == '_')
        && chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

/// The generated struct and loader of one model: a field per declared parameter, named
/// and typed by its declaration.
fn params_wgsl(def: &ModelDef, out: &mut String) -> Result<(), GpuError> {
    let bad = |what: &str| GpuError::Shader(format!("model '{}': {what} is not a WGSL identifier", def.name));
    if !is_identifier(def.name) {
        return Err(bad("the model name"));
    }
    let name = params_struct_name(def);
    let _ = writeln!(out, "// {}: {}", def.name, def.doc.replace('\n', " "));
    let _ = writeln!(out, "struct {name} {{");
    let mut fields = Vec::with_capacity(def.params.len());
    for (i, p) in def.params.iter().enumerate() {
        if !is_identifier(p.name) {
            return Err(bad(&format!("parameter '{}'", p.name)));
        }
        let word = format!("material_data[base + {i}u]");
        let (ty, kind, load) = match p.kind {
            ParamKind::Scalar => ("f32", "scalar".to_string(), format!("bitcast<f32>({word})")),
            ParamKind::Spectrum => ("u32", "spectrum offset".to_string(), word),
            ParamKind::Coefficient => ("u32", "coefficient spectrum offset".to_string(), word),
            ParamKind::Bool => ("bool", "switch".to_string(), format!("{word} != 0u")),
            ParamKind::Choice(names) => {
                let options = names.iter().enumerate().map(|(k, n)| format!("{k} {n}")).collect::<Vec<_>>();
                ("u32", format!("choice ({})", options.join(", ")), word)
            }
        };
        let _ = writeln!(out, "    {}: {ty}, // {kind}: {}", p.name, p.doc.replace('\n', " "));
        fields.push(load);
    }
    let _ = writeln!(out, "}}\n");
    let _ = writeln!(out, "fn load_{}(base: u32) -> {name} {{", def.name);
    let _ = writeln!(out, "    return {name}({});", fields.join(", "));
    let _ = writeln!(out, "}}\n");
    Ok(())
}

/// The materials WGSL for `models` (any registry's; ids must be distinct), with the
/// optional code paths `features` selects and the metal tables' places in `spectra`
/// ((preset, offset, rows)).
pub fn wgsl_for(
    models: &[ModelEntry],
    features: &Features,
    metal_tables: &[(Metal, u32, u32)],
) -> Result<String, GpuError> {
    let mut out = String::new();
    let names: Vec<&str> = models.iter().map(|m| m.def.name).collect();
    let _ = writeln!(out, "// ---- Materials: generated by gpu::materials from brdf's parameter definitions.");
    let _ = writeln!(
        out,
        "// Models: {}. Features: dispersion {}, absorption {}, emission {}, metals [{}].\n",
        names.join(", "),
        features.dispersion,
        features.absorption,
        features.emission,
        metal_tables.iter().map(|(m, ..)| m.name()).collect::<Vec<_>>().join(", ")
    );
    out.push_str("@group(0) @binding(10) var<storage, read> material_data: array<u32>;\n");
    out.push_str("@group(0) @binding(11) var<storage, read> spectra: array<f32>;\n\n");
    out.push_str("// pdf == 0.0: no sample.\nstruct BsdfSample {\n    wi: vec3f,\n    f: vec4f,\n    pdf: f32,\n    flags: u32,\n}\n\n");
    for (name, flag) in [
        ("REFLECTION", ScatterFlags::REFLECTION),
        ("TRANSMISSION", ScatterFlags::TRANSMISSION),
        ("DIFFUSE", ScatterFlags::DIFFUSE),
        ("GLOSSY", ScatterFlags::GLOSSY),
        ("SPECULAR", ScatterFlags::SPECULAR),
        ("WAVELENGTH_DEPENDENT", ScatterFlags::WAVELENGTH_DEPENDENT),
    ] {
        let _ = writeln!(out, "const SCATTER_{name}: u32 = {}u;", flag.bits());
    }
    let _ = writeln!(out, "\nconst SPECTRUM_LAMBDA_MIN: f32 = {};", f32_literal(SPECTRUM_LAMBDA_MIN));
    let _ = writeln!(out, "const SPECTRUM_SAMPLES: u32 = {SPECTRUM_SAMPLES}u;");
    let _ = writeln!(out, "const MATERIAL_HEADER_WORDS: u32 = {HEADER_WORDS}u;");
    let _ = writeln!(out, "const MAT_NO_SPECTRUM: u32 = {NO_SPECTRUM}u;");
    let _ = writeln!(out, "const MAT_PROPERTY_TWO_SIDED: u32 = {PROPERTY_TWO_SIDED}u;");
    let _ = writeln!(out, "const MAT_PROPERTY_DISPERSIVE: u32 = {PROPERTY_DISPERSIVE}u;");
    out.push_str("// RGB mode (`for_mode`): colours are their linear-sRGB values, nothing disperses.\n");
    out.push_str(HERO_MODE_LINE);
    let _ = writeln!(out, "const MAT_TEXTURES: bool = {};", features.textures);
    out.push_str(
        "// The texels at the current hit (`mat_set_texels`): `spectrum_at` multiplies the tables at\n\
         // `mat_tex_base_at` and `mat_tex_spec_at` by them; roughness and metalness reach the\n\
         // models with a metallic-roughness slot through their `_textured` hooks.\n\
         var<private> mat_tex_base_at: u32 = MAT_NO_SPECTRUM;\n\
         var<private> mat_tex_base: vec4f = vec4f(1.0);\n\
         var<private> mat_tex_spec_at: u32 = MAT_NO_SPECTRUM;\n\
         var<private> mat_tex_spec: vec4f = vec4f(1.0);\n\
         var<private> mat_tex_roughness: f32 = 1.0;\n\
         var<private> mat_tex_metallic: f32 = 1.0;\n",
    );
    for m in models {
        let _ = writeln!(out, "const MAT_MODEL_{}: u32 = {}u;", m.def.name.to_ascii_uppercase(), m.id);
    }
    out.push('\n');
    out.push_str(COMMON);

    let mut pieces: Vec<WgslPiece> = models.iter().flat_map(|m| m.wgsl.needs.iter().copied()).collect();
    // The kernel's ambient-occlusion integrator draws cosine-weighted directions itself:
    // without this, a scene of glass and mirrors alone (no model that samples the
    // hemisphere) did not compile.
    pieces.push(WgslPiece::Sampling);
    pieces.sort();
    pieces.dedup();
    for piece in pieces {
        out.push('\n');
        for c in piece.constants() {
            let _ = writeln!(out, "{}", c.declaration());
        }
        match piece {
            WgslPiece::Metal => {
                out.push_str("// (offset, rows) of a metal preset's table in `spectra` (generated).\n");
                out.push_str("fn mat_metal_table(id: u32) -> vec2u {\n    switch id {\n");
                for (metal, offset, rows) in metal_tables {
                    let id = MetalPreset::ALL.iter().position(|p| p.metal() == Some(*metal)).expect("a preset");
                    let _ = writeln!(
                        out,
                        "        case {id}u: {{ return vec2u({offset}u, {rows}u); }} // {}",
                        metal.name()
                    );
                }
                out.push_str("        default: {}\n    }\n    return vec2u(0u, 0u);\n}\n\n");
                out.push_str(piece.source());
            }
            WgslPiece::Dispersion if !features.dispersion => {
                out.push_str("// No material disperses: the index is the same at every wavelength.\n");
                out.push_str("fn mat_dispersion_ior(preset: u32, cauchy_b: f32, ior: f32, lambda_nm: f32) -> f32 {\n");
                out.push_str("    return ior;\n}\n");
            }
            _ => out.push_str(piece.source()),
        }
    }

    for m in models {
        out.push('\n');
        params_wgsl(&m.def, &mut out)?;
        for c in m.wgsl.constants {
            let _ = writeln!(out, "{}", c.declaration());
        }
        out.push_str(m.wgsl.source);
    }

    out.push_str("\n// ---- Material accessors and the per-model dispatch (generated).\n\n");
    out.push_str("fn mat_header(m: u32, word: u32) -> u32 {\n");
    out.push_str("    return material_data[m * MATERIAL_HEADER_WORDS + word];\n}\n\n");
    let _ = writeln!(out, "fn material_flags(m: u32) -> u32 {{\n    return mat_header(m, {}u);\n}}\n", header::FLAGS);
    let _ = writeln!(
        out,
        "fn material_two_sided(m: u32) -> bool {{\n    return (mat_header(m, {}u) & MAT_PROPERTY_TWO_SIDED) != 0u;\n}}\n",
        header::PROPERTIES
    );
    let _ = writeln!(
        out,
        "fn material_dispersive(m: u32) -> bool {{\n    return !MAT_RGB && (mat_header(m, {}u) & MAT_PROPERTY_DISPERSIVE) != 0u;\n}}\n",
        header::PROPERTIES
    );
    for (name, word, enabled) in
        [("emission", header::EMISSION, features.emission), ("absorption", header::ABSORPTION, features.absorption)]
    {
        let _ = writeln!(out, "fn material_{name}(m: u32, lambda: vec4f) -> vec4f {{");
        if enabled {
            let _ = writeln!(out, "    let offset = mat_header(m, {word}u);");
            out.push_str("    if offset != MAT_NO_SPECTRUM {\n        return spectrum_at(offset, lambda);\n    }\n");
        } else {
            let _ = writeln!(out, "    // No material has {name}.");
        }
        out.push_str("    return vec4f(0.0);\n}\n\n");
    }
    let _ = writeln!(
        out,
        "fn material_eta(m: u32) -> f32 {{\n    return bitcast<f32>(mat_header(m, {}u));\n}}\n",
        header::ETA
    );
    // `bsdf.eta()` at the path's wavelengths, as the BSDF samples with it (a dispersive
    // index at lambda.x): bdpt's adjoint scales light subpaths by it exactly.
    out.push_str("fn material_eta_at(m: u32, lambda: vec4f) -> f32 {\n");
    if models.iter().any(|m| m.def.name == "dielectric") {
        let _ = writeln!(
            out,
            "    if mat_header(m, {}u) == MAT_MODEL_DIELECTRIC {{\n        return dielectric_eta(load_dielectric(mat_header(m, \
             {}u)), lambda);\n    }}",
            header::MODEL,
            header::PARAMS
        );
    }
    out.push_str("    return material_eta(m);\n}\n\n");
    // `Material::absorption().is_some()`: the medium test of Beer–Lambert (a constant false
    // when no material absorbs, so that the kernel's absorption code compiles away).
    out.push_str("fn material_absorbing(m: u32) -> bool {\n");
    if features.absorption {
        let _ = writeln!(out, "    return mat_header(m, {}u) != MAT_NO_SPECTRUM;", header::ABSORPTION);
    } else {
        out.push_str("    return false;\n");
    }
    out.push_str("}\n\n");
    // The texels of a hit on material `m` (`Texels`: base colour and specular at the path's
    // wavelengths, roughness and metalness factors), for the BSDF calls that follow.
    out.push_str("fn mat_set_texels(m: u32, base: vec4f, spec: vec4f, roughness: f32, metallic: f32) {\n");
    let _ = writeln!(out, "    mat_tex_base_at = mat_header(m, {}u);", header::BASE_SLOT);
    let _ = writeln!(out, "    mat_tex_spec_at = mat_header(m, {}u);", header::SPECULAR_SLOT);
    out.push_str(
        "    mat_tex_base = base;\n    mat_tex_spec = spec;\n    mat_tex_roughness = roughness;\n    \
         mat_tex_metallic = metallic;\n}\n\n",
    );
    out.push_str(
        "// No texels: the BSDFs of an untextured hit.\nfn mat_clear_texels() {\n    \
         mat_tex_base_at = MAT_NO_SPECTRUM;\n    mat_tex_spec_at = MAT_NO_SPECTRUM;\n    \
         mat_tex_roughness = 1.0;\n    mat_tex_metallic = 1.0;\n}\n\n",
    );
    let dispatch = |out: &mut String, signature: &str, suffix: &str, args: &str, zero: &str| {
        let _ = writeln!(out, "fn bsdf_{suffix}({signature} {{");
        let _ = writeln!(out, "    let base = mat_header(m, {}u);", header::PARAMS);
        let _ = writeln!(out, "    switch mat_header(m, {}u) {{", header::MODEL);
        for m in models {
            let n = m.def.name;
            let load = if features.textures && m.wgsl.texture.metallic_roughness {
                format!("{n}_textured(load_{n}(base), mat_tex_roughness, mat_tex_metallic)")
            } else {
                format!("load_{n}(base)")
            };
            let _ = writeln!(
                out,
                "        case MAT_MODEL_{}: {{ return {n}_{suffix}({load}, {args}); }}",
                n.to_ascii_uppercase()
            );
        }
        let _ = writeln!(out, "        default: {{}}\n    }}\n    return {zero};\n}}\n");
    };
    dispatch(&mut out, "m: u32, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f", "eval", "wo, wi, lambda", "vec4f(0.0)");
    dispatch(&mut out, "m: u32, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32", "pdf", "wo, wi, lambda", "0.0");
    dispatch(
        &mut out,
        "m: u32, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample",
        "sample",
        "wo, uc, u, lambda",
        "mat_no_sample()",
    );
    Ok(out)
}
