//! The generated materials WGSL (`gpu::materials`).
//!
//! * Generator tests (no GPU): specialisation keeps exactly the models and features a
//!   scene uses, the packing follows the parameter declarations, custom BSDFs without a
//!   WGSL twin (or with a malformed one) are refused, and the generated WGSL parses and
//!   validates with naga.
//! * GPU tests (lavapipe in CI; `SPT_REQUIRE_GPU=1` makes a missing adapter a failure):
//!   every model's hand-written WGSL `eval`/`pdf`/`sample` — and the twin of the custom
//!   Phong BSDF of the tracer's `examples/custom_brdf.rs` — the Fresnel routines and the
//!   spectrum lookup are run on the GPU and compared with the CPU crates for the same
//!   inputs.
//!
//! # How GPU and CPU are compared
//!
//! The GPU reads spectra from 1-nm tables; the CPU reference materials are the same
//! materials with every colour replaced by the same 1-nm table (as a
//! `TabulatedSpectrum`), so that both sides see identical inputs at any wavelength. How
//! far a table is from the exact spectrum is measured separately
//! (`spectrum_lookup_matches_the_cpu`).
//!
//! Errors are relative, `|gpu − cpu| / max(|cpu|, FLOOR)` with `FLOOR` = 1e-6 (values
//! below it are compared absolutely), and must stay below `TOLERANCE` = 1e-4, except
//! where the CPU function itself is ill-conditioned in f32: there the allowance is the
//! spread of the CPU's own result when its inputs are moved by a few ulp
//! ([`f32_noise`]), since no f32 evaluation can agree more closely than that. Sampled
//! directions are compared as vectors (`|Δωi|`, absolute, unit vectors); a sample's f and
//! pdf are compared with the CPU's eval and pdf at the GPU's direction (for delta
//! lobes, with the CPU sample itself), so that a direction that differs by rounding does
//! not count as an error in f. Flags, and whether a sample exists, must agree exactly.

use brdf::Bsdf;
use brdf::params::Resolved;
use brdf::params::{ParamKind, ParamValue, ResolvedParams};
use glam::{Vec2, Vec3};
use gpu::materials::{self, MaterialKernel, generate};
use spectral::SampledWavelengths;
use spectral::spectrum::{Colour, Spectrum, TabulatedSpectrum};
use std::collections::BTreeMap;
use std::time::Instant;
use tracer::material::{Material, ModelId};
use wgpu::util::DeviceExt;

#[path = "../../tracer/examples/support/phong.rs"]
mod phong;

/// Relative tolerance of every GPU–CPU comparison.
const TOLERANCE: f64 = 1e-4;
/// Below this magnitude values are compared absolutely.
const FLOOR: f32 = 1e-6;
/// The floor of the Fresnel comparisons: reflectances in [0, 1] are differences of terms
/// of order 1, so that their absolute precision is a few 1e-8 however small they are.
const FRESNEL_FLOOR: f32 = 1e-3;
/// The stand-in for an unbounded maximum (the absorption coefficient's).
const UNBOUNDED_MAX: f32 = 1.0e3;

// ---------------------------------------------------------------------------------------
// Scenes.

fn lambert(name: &str, rgb: [f32; 3]) -> Material {
    Material::diffuse(name, Colour::reflectance_rgb(rgb).unwrap()).unwrap()
}

fn builtin(name: &str, model: ModelId, params: &[(&str, ParamValue)]) -> Material {
    Material::builtin(name, model, params).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Every model: defaults; every spectrum parameter coloured (and an emission); every
/// parameter at its declared minimum and maximum (iterating the declarations); then a
/// few hand-picked combinations the extremes do not reach (presets, anisotropy, explicit
/// Schlick weights).
fn test_materials() -> Vec<Material> {
    const COLOURS: [[f32; 3]; 3] = [[0.8, 0.35, 0.1], [0.15, 0.6, 0.9], [0.3, 0.9, 0.25]];
    let mut out = Vec::new();
    for &model in ModelId::ALL {
        let def = model.def();
        out.push(builtin(&format!("{} defaults", def.name), model, &[]));
        let coloured: Vec<(&str, ParamValue)> = def
            .params
            .iter()
            .enumerate()
            .filter(|(_, p)| p.kind.is_colour())
            .map(|(i, p)| {
                let v = match p.kind {
                    ParamKind::Coefficient => ParamValue::Rgb([0.5, 1.0, 2.0]),
                    _ => ParamValue::Rgb(COLOURS[i % COLOURS.len()]),
                };
                (p.name, v)
            })
            .collect();
        out.push(
            builtin(&format!("{} coloured", def.name), model, &coloured)
                .with_emission(Colour::illuminant_rgb([2.0, 1.0, 0.5]).unwrap()),
        );
        for p in def.params {
            let max = if p.max.is_finite() { p.max } else { UNBOUNDED_MAX };
            for (label, v) in [("min", p.min), ("max", max)] {
                out.push(builtin(
                    &format!("{} {}={label}", def.name, p.name),
                    model,
                    &[(p.name, ParamValue::Scalar(v))],
                ));
            }
        }
    }
    use ModelId as B;
    use ParamValue::{Rgb, Scalar};
    type Extra = (&'static str, ModelId, Vec<(&'static str, ParamValue)>);
    let extras: Vec<Extra> = vec![
        ("gold", B::Conductor, vec![("metal", Scalar(1.0))]),
        ("silver", B::Conductor, vec![("metal", Scalar(2.0)), ("tint", Rgb([0.9, 0.8, 0.7]))]),
        ("rough gold", B::RoughConductor, vec![("metal", Scalar(1.0)), ("alpha", Scalar(0.3))]),
        (
            "brushed silver",
            B::RoughConductor,
            vec![("metal", Scalar(2.0)), ("alpha", Scalar(0.05)), ("alpha_y", Scalar(0.4))],
        ),
        ("rough custom", B::RoughConductor, vec![("metal", Scalar(0.0)), ("eta", Scalar(0.2)), ("k", Scalar(3.0))]),
        ("cauchy", B::Dielectric, vec![("dispersion", Scalar(1.0)), ("cauchy_b", Scalar(0.02))]),
        ("bk7", B::Dielectric, vec![("dispersion", Scalar(2.0)), ("absorption", Rgb([0.1, 0.5, 2.0]))]),
        ("bk7 schlick", B::Dielectric, vec![("dispersion", Scalar(2.0)), ("schlick", Scalar(1.0))]),
        ("water", B::Dielectric, vec![("ior", Scalar(1.33)), ("tint", Rgb([0.7, 0.9, 1.0]))]),
        ("frosted", B::RoughDielectric, vec![("alpha", Scalar(0.3)), ("ior", Scalar(1.33))]),
        (
            "frosted aniso",
            B::RoughDielectric,
            vec![("alpha", Scalar(0.05)), ("alpha_y", Scalar(0.3)), ("ior", Scalar(2.4))],
        ),
        ("schlick weights", B::Schlick, vec![("a", Scalar(0.3)), ("b", Scalar(0.5)), ("c", Scalar(0.4))]),
        (
            "schlick aniso b1",
            B::Schlick,
            vec![
                ("a", Scalar(0.2)),
                ("b", Scalar(0.3)),
                ("c", Scalar(0.1)),
                ("roughness", Scalar(0.05)),
                ("isotropy", Scalar(0.1)),
                ("geometric", Scalar(0.0)),
            ],
        ),
        ("schlick rough", B::Schlick, vec![("roughness", Scalar(0.7)), ("isotropy", Scalar(0.5))]),
        ("sa aniso", B::Ashikhmin, vec![("nu", Scalar(10.0)), ("nv", Scalar(1000.0))]),
        (
            "sa sharp",
            B::Ashikhmin,
            vec![("nu", Scalar(1.0e4)), ("nv", Scalar(10.0)), ("rs", Scalar(0.9)), ("rd", Scalar(0.0))],
        ),
        ("sa metal", B::Ashikhmin, vec![("rs", Scalar(1.0)), ("rd", Rgb([0.2, 0.5, 0.8]))]),
        (
            "gltf plastic",
            B::MetallicRoughness,
            vec![("metallic", Scalar(0.0)), ("roughness", Scalar(0.4)), ("base_color", Rgb([0.8, 0.3, 0.1]))],
        ),
        (
            "gltf rough gold",
            B::MetallicRoughness,
            vec![("roughness", Scalar(0.7)), ("base_color", Rgb([1.0, 0.78, 0.34]))],
        ),
        (
            "gltf half metal",
            B::MetallicRoughness,
            vec![("metallic", Scalar(0.5)), ("roughness", Scalar(0.1)), ("ior", Scalar(1.8))],
        ),
        ("oren-nayar rough", B::OrenNayar, vec![("sigma", Scalar(1.2)), ("reflectance", Rgb([0.9, 0.5, 0.3]))]),
    ];
    for (name, model, params) in extras {
        out.push(builtin(name, model, &params));
    }
    // A custom BSDF through its WGSL twin: broad, glossy and sharp lobes.
    for (name, exponent, kd, ks) in [
        ("phong broad", 1.0, [0.5; 3], [0.3; 3]),
        ("phong", 60.0, COLOURS[0], COLOURS[1]),
        ("phong sharp", 2000.0, [0.1; 3], COLOURS[2]),
    ] {
        out.push(phong_material(name, exponent, kd, ks));
    }
    out
}

/// A material of the custom Phong BSDF.
fn phong_material(name: &str, exponent: f32, kd: [f32; 3], ks: [f32; 3]) -> Material {
    let reflectance = |c| Colour::reflectance_rgb(c).unwrap();
    let params = phong::PhongParams { kd: reflectance(kd), ks: reflectance(ks), exponent };
    Material::custom(name, std::sync::Arc::new(params), false)
}

/// The model's name (a registered model's, or the custom BSDF's twin's).
fn model_name(m: &Material) -> &'static str {
    match m.model() {
        Some(model) => model.def().name,
        None => m.wgsl_twin().expect("a WGSL twin").def.name,
    }
}

/// The material's declaration and values (a registered model's, or its twin's).
fn declaration(m: &Material) -> (brdf::params::ModelDef, ResolvedParams) {
    match m.params() {
        Some(p) => (*p.model().def(), p.to_resolved()),
        None => {
            let twin = m.wgsl_twin().expect("a WGSL twin");
            (twin.def, twin.params)
        }
    }
}

/// The CPU reference for `m`: every colour replaced by its 1-nm table, as the GPU sees it.
fn tabulated(c: &Colour) -> Colour {
    let table = materials::tabulate(c);
    let lambda = (0..table.len()).map(|i| materials::SPECTRUM_LAMBDA_MIN + i as f32).collect();
    Colour { spectrum: Spectrum::Tabulated(TabulatedSpectrum::new(lambda, table).unwrap()), rgb: c.rgb }
}

fn reference(m: &Material) -> Material {
    let (_, params) = declaration(m);
    let values = params
        .values()
        .iter()
        .map(|v| match v {
            Resolved::Colour(c) => Resolved::Colour(tabulated(c)),
            other => other.clone(),
        })
        .collect();
    let values = ResolvedParams::from_values(values);
    let material = match m.params() {
        Some(params) => Material::from_params(&m.name, params.model().from_resolved(&values)),
        None => {
            use brdf::params::ParamSet;
            Material::custom(&m.name, std::sync::Arc::new(phong::PhongParams::from_resolved(&values)), false)
        }
    };
    Material { emission: m.emission.as_ref().map(tabulated), ..material }
}

fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// ωo: normal, oblique, near-grazing (cos θ = 1e-3 and 0.05), near-normal, and the same
/// kinds below the surface.
fn outgoing() -> Vec<Vec3> {
    let grazing = |z: f32, phi: f32| {
        let s = (1.0 - z * z).sqrt();
        let p = phi.to_radians();
        Vec3::new(s * p.cos(), s * p.sin(), z)
    };
    vec![
        Vec3::Z,
        dir(30.0, 20.0),
        dir(60.0, 135.0),
        dir(85.0, 250.0),
        grazing(0.05, 80.0),
        grazing(1e-3, 300.0),
        Vec3::new(1e-4, -2e-4, 1.0).normalize(),
        -Vec3::Z,
        dir(120.0, 300.0),
        dir(150.0, 45.0),
        grazing(-1e-3, 170.0),
        grazing(-0.05, 10.0),
    ]
}

/// ωi for a given ωo: a fixed spread over both hemispheres, grazing ones, the mirror
/// direction, a direction 0.02 rad off it, and the smooth-glass refraction.
fn incident(wo: Vec3) -> Vec<Vec3> {
    let mut v = vec![
        Vec3::Z,
        dir(20.0, 200.0),
        dir(45.0, 30.0),
        dir(70.0, 160.0),
        dir(89.0, 95.0),
        -Vec3::Z,
        dir(110.0, 10.0),
        dir(135.0, 210.0),
        dir(175.0, 60.0),
    ];
    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
    v.push(mirror);
    v.push(Vec3::new(mirror.x + 0.02, mirror.y, mirror.z).normalize());
    if let Some(t) = brdf::fresnel::refract_local(wo, 1.5) {
        v.push(t);
    }
    v
}

/// Hero-wavelength sets, plus one with the table's ends and the d line.
fn wavelength_sets() -> Vec<SampledWavelengths<4>> {
    let mut sets: Vec<SampledWavelengths<4>> =
        [0.0, 0.137, 0.291, 0.5, 0.73, 0.9999].iter().map(|&u| SampledWavelengths::sample_hero(u)).collect();
    let mut ends = SampledWavelengths::<4>::fixed_bins(360.0, 1.0);
    ends.lambda = [360.0, 830.0, 587.56, 450.5];
    sets.push(ends);
    sets
}

// ---------------------------------------------------------------------------------------
// naga.

fn naga_validate(src: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
        .validate(&module)
        .map_err(|e| e.emit_to_string(src))?;
    Ok(module)
}

fn function_names(module: &naga::Module) -> Vec<String> {
    module.functions.iter().filter_map(|(_, f)| f.name.clone()).collect()
}

// ---------------------------------------------------------------------------------------
// Generator tests (no GPU).

#[test]
fn a_lambert_only_scene_compiles_only_lambert() {
    let scene = [lambert("white", [0.8; 3]), lambert("red", [0.8, 0.1, 0.1])];
    let k = generate(&scene, true).unwrap();
    assert_eq!(k.models, vec![ModelId::Lambert]);
    let module = naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("{e}"));
    let names = function_names(&module);
    assert!(names.iter().any(|n| n == "lambert_eval") && names.iter().any(|n| n == "load_lambert"));
    for model in ModelId::ALL.iter().copied().filter(|&m| m != ModelId::Lambert) {
        let prefix = format!("{}_", model.def().name);
        assert!(!names.iter().any(|n| n.starts_with(&prefix)), "{prefix}* compiled into a Lambert-only kernel");
        assert!(!k.wgsl.contains(&materials::params_struct_name(model.def())));
    }
    // No features either: no Fresnel, GGX, metals, dispersion; emission/absorption stubs.
    for absent in ["mat_fresnel_dielectric", "mat_ggx_d", "mat_metal_eta_k", "mat_sellmeier", "mat_dispersion_ior"] {
        assert!(!names.iter().any(|n| n == absent), "{absent} in a Lambert-only kernel");
    }
    assert_eq!(k.features, materials::Features::default());
    assert!(k.wgsl.contains("No material has emission") && k.wgsl.contains("No material has absorption"));
    println!("Lambert-only kernel: {} lines of WGSL, {} functions", k.wgsl.lines().count(), names.len());
}

#[test]
fn unspecialised_kernels_contain_every_model_and_feature() {
    let scene = [lambert("white", [0.8; 3])];
    let k = generate(&scene, false).unwrap();
    assert_eq!(k.models, ModelId::ALL.to_vec());
    assert_eq!(k.features, materials::Features::all());
    let names = function_names(&naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("{e}")));
    for &model in ModelId::ALL {
        for f in ["eval", "pdf", "sample"] {
            let name = format!("{}_{f}", model.def().name);
            assert!(names.contains(&name), "{name} missing");
        }
        assert!(names.contains(&format!("load_{}", model.def().name)));
    }
    assert!(names.iter().any(|n| n == "mat_sellmeier"), "dispersion code missing");
    println!("unspecialised kernel: {} lines of WGSL, {} functions", k.wgsl.lines().count(), names.len());
}

#[test]
fn features_follow_the_materials() {
    let plain = [builtin("glass", ModelId::Dielectric, &[])];
    let k = generate(&plain, true).unwrap();
    assert!(!k.features.dispersion && !k.features.absorption);
    assert!(!k.wgsl.contains("fn mat_sellmeier") && k.wgsl.contains("No material disperses"));
    naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("{e}"));

    let dispersive = [builtin(
        "bk7",
        ModelId::Dielectric,
        &[("dispersion", ParamValue::Scalar(2.0)), ("absorption", ParamValue::Rgb([0.1, 0.2, 0.3]))],
    )];
    let k = generate(&dispersive, true).unwrap();
    assert!(k.features.dispersion && k.features.absorption && !k.features.emission);
    assert!(k.wgsl.contains("fn mat_sellmeier"));
    naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("{e}"));

    // Only the metal presets in use are uploaded; custom (eta, k) needs none.
    let metals = [
        builtin("gold", ModelId::Conductor, &[("metal", ParamValue::Scalar(1.0))]),
        builtin("al", ModelId::RoughConductor, &[("metal", ParamValue::Scalar(4.0))]),
        builtin("custom", ModelId::Conductor, &[("metal", ParamValue::Scalar(0.0))]),
    ];
    let k = generate(&metals, true).unwrap();
    assert_eq!(k.features.metals, vec![brdf::models::Metal::Gold, brdf::models::Metal::Aluminium]);
    let rows: usize = k.features.metals.iter().map(|m| m.table().len()).sum();
    assert_eq!(k.spectra.len(), 3 * rows + materials::COLOUR_FLOATS, "two metal tables and one (white) tint");
    naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn every_model_and_feature_combination_validates() {
    let all = test_materials();
    for specialise in [true, false] {
        let k = generate(&all, specialise).unwrap();
        naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("specialise={specialise}: {e}"));
    }
    for &model in ModelId::ALL {
        let one: Vec<Material> = all.iter().filter(|m| m.model() == Some(model)).take(1).cloned().collect();
        let k = generate(&one, true).unwrap();
        assert_eq!(k.models, vec![model]);
        naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("{} alone: {e}", model.def().name));
    }
    // A custom twin alone: no registered model compiled in.
    let k = generate(&[phong_material("phong", 60.0, [0.5; 3], [0.3; 3])], true).unwrap();
    assert!(k.models.is_empty() && k.wgsl.contains("struct PhongParams"));
    naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("phong alone: {e}"));
    naga_validate(&generate(&[], true).unwrap().wgsl).unwrap_or_else(|e| panic!("empty scene: {e}"));
}

#[test]
fn params_are_packed_in_declaration_order() {
    let all = test_materials();
    let k = generate(&all, true).unwrap();
    let module = naga_validate(&k.wgsl).unwrap();
    for (index, m) in all.iter().enumerate() {
        let (def, params) = declaration(m);
        let h = index * materials::HEADER_WORDS as usize;
        // Custom twins take the ids after the registry's.
        let id = m.model().map_or(ModelId::ALL.len() as u32, materials::model_id);
        assert_eq!(k.data[h + materials::header::MODEL as usize], id);
        let base = k.data[h + materials::header::PARAMS as usize] as usize;
        for (i, (p, value)) in def.params.iter().zip(params.values()).enumerate() {
            let word = k.data[base + i];
            match value {
                Resolved::Scalar(v) => assert_eq!(f32::from_bits(word), *v, "{}.{}", m.name, p.name),
                Resolved::Bool(b) => assert_eq!(word, u32::from(*b), "{}.{}", m.name, p.name),
                Resolved::Choice(c) => assert_eq!(word, *c, "{}.{}", m.name, p.name),
                Resolved::Colour(c) => {
                    let table = &k.spectra[word as usize..word as usize + materials::SPECTRUM_SAMPLES];
                    assert_eq!(table, materials::tabulate(c).as_slice(), "{}.{}", m.name, p.name);
                }
            }
        }
        let props = k.data[h + materials::header::PROPERTIES as usize];
        assert_eq!(props & materials::PROPERTY_TWO_SIDED != 0, m.is_two_sided());
        assert_eq!(props & materials::PROPERTY_DISPERSIVE != 0, m.is_dispersive());
        assert_eq!(k.data[h + materials::header::EMISSION as usize] != materials::NO_SPECTRUM, m.emission.is_some());
        assert_eq!(
            k.data[h + materials::header::ABSORPTION as usize] != materials::NO_SPECTRUM,
            m.absorption().is_some()
        );
    }
    // The generated structs have the declared fields, in order, with the declared types.
    let twin = phong_material("phong", 60.0, [0.5; 3], [0.3; 3]).wgsl_twin().unwrap().def;
    for def in ModelId::ALL.iter().map(|m| m.def()).chain([&twin]) {
        let name = materials::params_struct_name(def);
        let ty = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name.as_str())).map(|(_, t)| t);
        let Some(naga::Type { inner: naga::TypeInner::Struct { members, .. }, .. }) = ty else {
            panic!("no struct {name}")
        };
        let fields: Vec<&str> = members.iter().filter_map(|m| m.name.as_deref()).collect();
        let declared: Vec<&str> = def.params.iter().map(|p| p.name).collect();
        assert_eq!(fields, declared, "{name}");
    }
}

#[test]
fn custom_bsdfs_without_a_twin_are_refused_with_the_material_name() {
    struct Black;
    impl brdf::BsdfBuilder for Black {
        fn build<const N: usize>(&self, _: &SampledWavelengths<N>) -> impl Bsdf<N> + 'static {
            brdf::Lambert { reflectance: spectral::SampledSpectrum::zero() }
        }
    }
    let scene = [lambert("white", [0.8; 3]), Material::custom("phong floor", std::sync::Arc::new(Black), false)];
    let e = generate(&scene, true).unwrap_err();
    assert!(matches!(e, gpu::GpuError::Unsupported(_)), "{e:?}");
    assert!(e.to_string().contains("custom BSDF without a WGSL twin in material 'phong floor'"), "{e}");
    // The backend's capability check says so before any work, with the way in.
    let mut s = tracer::scene::Scene { materials: scene.to_vec(), ..Default::default() };
    let e = gpu::backend::capabilities().check_scene(&s, &Default::default()).unwrap_err().to_string();
    assert!(e.contains("without a WGSL twin (material 'phong floor')") && e.contains("wgsl_twin"), "{e}");
    s.materials = vec![phong_material("phong", 60.0, [0.5; 3], [0.3; 3])];
    gpu::backend::capabilities().check_scene(&s, &Default::default()).unwrap();
}

/// A change to a twin.
type TwinChange = fn(&mut brdf::wgsl::WgslTwin);

/// A builder whose twin is the Phong one changed by `change` (a malformed twin).
struct Tampered(TwinChange);

impl brdf::BsdfBuilder for Tampered {
    fn build<const N: usize>(&self, _: &SampledWavelengths<N>) -> impl Bsdf<N> + 'static {
        brdf::Lambert { reflectance: spectral::SampledSpectrum::zero() }
    }
    fn wgsl_twin(&self) -> Option<brdf::wgsl::WgslTwin> {
        let mut twin = brdf::BsdfBuilder::wgsl_twin(&phong::PhongParams::default())?;
        (self.0)(&mut twin);
        Some(twin)
    }
}

#[test]
fn malformed_twins_are_named_errors() {
    let tampered = |change| Material::custom("odd", std::sync::Arc::new(Tampered(change)), false);
    let cases: [(TwinChange, &str); 4] = [
        (|t| t.def.name = "lambert", "a registered model has that name"),
        (|t| t.params = ResolvedParams::from_values(vec![Resolved::Scalar(1.0)]), "1 values for 3 declared"),
        (
            |t| t.params = ResolvedParams::from_values(vec![Resolved::Scalar(1.0); 3]),
            "parameter 'kd' is declared Spectrum",
        ),
        (|t| t.wgsl.source = "", "another material's twin has that name"),
    ];
    for (change, expected) in cases {
        let scene = [phong_material("phong", 60.0, [0.5; 3], [0.3; 3]), tampered(change)];
        let e = generate(&scene, true).unwrap_err().to_string();
        assert!(e.contains(expected) && e.contains("material 'odd'"), "{e}");
    }
    // Two materials of one twin share its code.
    let two = [phong_material("a", 60.0, [0.5; 3], [0.3; 3]), phong_material("b", 5.0, [0.2; 3], [0.1; 3])];
    let k = generate(&two, true).unwrap();
    assert_eq!(k.wgsl.matches("fn phong_eval").count(), 1);
    naga_validate(&k.wgsl).unwrap_or_else(|e| panic!("{e}"));
}

// ---------------------------------------------------------------------------------------
// The GPU harness.

/// Entry points the tests append to the materials WGSL. `test_bsdf` reads 16 floats per
/// case (m, uc, u, ωo, ωi, λ) and writes 32 (eval, pdf, sample wi/f/pdf/flags, material
/// flags and properties, emission, absorption).
const TEST_ENTRIES: &str = r#"
@group(0) @binding(0) var<storage, read> cases: array<f32>;
@group(0) @binding(1) var<storage, read_write> results: array<f32>;

@compute @workgroup_size(64)
fn test_bsdf(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if i >= arrayLength(&cases) / 16u {
        return;
    }
    let c = i * 16u;
    let o = i * 32u;
    let m = bitcast<u32>(cases[c]);
    let uc = cases[c + 1u];
    let u = vec2f(cases[c + 2u], cases[c + 3u]);
    let wo = vec3f(cases[c + 4u], cases[c + 5u], cases[c + 6u]);
    let wi = vec3f(cases[c + 8u], cases[c + 9u], cases[c + 10u]);
    let lambda = vec4f(cases[c + 12u], cases[c + 13u], cases[c + 14u], cases[c + 15u]);
    let f = bsdf_eval(m, wo, wi, lambda);
    let s = bsdf_sample(m, wo, uc, u, lambda);
    let e = material_emission(m, lambda);
    let a = material_absorption(m, lambda);
    var props = 0u;
    if material_two_sided(m) {
        props |= 1u;
    }
    if material_dispersive(m) {
        props |= 2u;
    }
    let values = array<f32, 24>(f.x, f.y, f.z, f.w, bsdf_pdf(m, wo, wi, lambda), s.wi.x, s.wi.y, s.wi.z,
        s.f.x, s.f.y, s.f.z, s.f.w, s.pdf, bitcast<f32>(s.flags), bitcast<f32>(material_flags(m)),
        bitcast<f32>(props), e.x, e.y, e.z, e.w, a.x, a.y, a.z, a.w);
    for (var k = 0u; k < 24u; k++) {
        results[o + k] = values[k];
    }
}

// (cos θ, η, κ, _) → (dielectric, Schlick, conductor, _).
@compute @workgroup_size(64)
fn test_fresnel(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if i >= arrayLength(&cases) / 4u {
        return;
    }
    let c = cases[4u * i];
    let eta = cases[4u * i + 1u];
    let k = cases[4u * i + 2u];
    results[4u * i] = mat_fresnel_dielectric(c, eta);
    results[4u * i + 1u] = mat_fresnel_schlick(c, eta);
    results[4u * i + 2u] = mat_fresnel_conductor(c, eta, k);
}

// (offset, _, _, _, λ × 4) → spectrum_at.
@compute @workgroup_size(64)
fn test_spectrum(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if i >= arrayLength(&cases) / 8u {
        return;
    }
    let offset = bitcast<u32>(cases[8u * i]);
    let lambda = vec4f(cases[8u * i + 4u], cases[8u * i + 5u], cases[8u * i + 6u], cases[8u * i + 7u]);
    let v = spectrum_at(offset, lambda);
    results[4u * i] = v.x;
    results[4u * i + 1u] = v.y;
    results[4u * i + 2u] = v.z;
    results[4u * i + 3u] = v.w;
}
"#;

struct Harness {
    ctx: gpu::GpuContext,
    layout: wgpu::PipelineLayout,
    bgl: wgpu::BindGroupLayout,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl Harness {
    fn new() -> Option<Self> {
        let ctx = gpu::require_gpu()?;
        println!("adapter: {} ({:?}, driver {})", ctx.info.name, ctx.info.backend, ctx.info.driver);
        let bgl = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("materials test"),
            entries: &[
                storage_entry(0, true),
                storage_entry(1, false),
                storage_entry(10, true),
                storage_entry(11, true),
            ],
        });
        let layout = ctx.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("materials test"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });
        Some(Self { ctx, layout, bgl })
    }

    /// The shader module, or the device's validation error.
    fn module(&self, src: &str) -> Result<wgpu::ShaderModule, String> {
        let scope = self.ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = self.ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("materials test"),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        });
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(e.to_string()),
            None => Ok(module),
        }
    }

    fn pipeline(&self, module: &wgpu::ShaderModule, entry: &str) -> Result<wgpu::ComputePipeline, String> {
        let scope = self.ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = self.ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&self.layout),
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(e.to_string()),
            None => Ok(pipeline),
        }
    }

    /// Runs `pipeline` over `invocations` threads and returns `out_len` floats, with the
    /// GPU time (submit to completion).
    fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        kernel: &MaterialKernel,
        input: &[f32],
        invocations: u32,
        out_len: usize,
    ) -> (Vec<f32>, f64) {
        let device = &self.ctx.device;
        let init = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let cases = init("cases", bytemuck::cast_slice(input));
        let data = init("material_data", bytemuck::cast_slice(&kernel.data));
        let spectra = init("spectra", bytemuck::cast_slice(&kernel.spectra));
        let size = (out_len.max(1) * 4) as u64;
        let results = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("results"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.bgl,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: cases.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: results.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 10, resource: data.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 11, resource: spectra.as_entire_binding() },
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(invocations.div_ceil(64), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&results, 0, &readback, 0, size);
        let start = Instant::now();
        self.ctx.queue.submit([encoder.finish()]);
        readback.map_async(wgpu::MapMode::Read, .., |r| r.expect("map"));
        device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
        let seconds = start.elapsed().as_secs_f64();
        let out = bytemuck::cast_slice(&readback.get_mapped_range(..).expect("mapped")).to_vec();
        readback.unmap();
        (out, seconds)
    }
}

// ---------------------------------------------------------------------------------------
// Error bookkeeping.

/// |g − c| / max(|c|, floor).
fn rel_floor(g: f32, c: f32, floor: f32) -> f64 {
    ((g as f64 - c as f64).abs()) / (c.abs().max(floor) as f64)
}

fn rel(g: f32, c: f32) -> f64 {
    rel_floor(g, c, FLOOR)
}

/// The largest error of one quantity and where it occurred.
#[derive(Default, Clone)]
struct Worst {
    err: f64,
    at: String,
}

impl Worst {
    fn add(&mut self, err: f64, at: impl FnOnce() -> String) {
        if err > self.err || err.is_nan() {
            self.err = if err.is_nan() { f64::INFINITY } else { err };
            self.at = at();
        }
    }
}

/// How far the CPU's own f32 result moves when ωo and ωi move by a few ulp (4 ε per
/// component, eight ways): the precision any f32 evaluation of the function shares.
fn f32_noise(f: impl Fn(Vec3, Vec3) -> [f32; 5], wo: Vec3, wi: Vec3) -> [f64; 5] {
    let base = f(wo, wi);
    let mut spread = [0.0f64; 5];
    let eps = 4.0 * f32::EPSILON;
    let jitters =
        [Vec3::new(eps, -eps, eps), Vec3::new(-eps, eps, eps), Vec3::new(eps, eps, -eps), Vec3::new(-eps, -eps, -eps)];
    for j in jitters {
        for (a, b) in [(wo * (Vec3::ONE + j), wi), (wo, wi * (Vec3::ONE - j))] {
            let v = f(a, b);
            for k in 0..5 {
                spread[k] = spread[k].max(rel(v[k], base[k]));
            }
        }
    }
    spread
}

/// One compared quantity of one model.
#[derive(Default)]
struct Quantity {
    /// The largest error, whatever allowance applied.
    raw: Worst,
    /// How many values exceeded TOLERANCE but stayed within 4 × the CPU's own f32 noise.
    ill_conditioned: usize,
    /// The materials and |cos θo| (rounded) where that happened.
    ill_where: std::collections::BTreeSet<String>,
}

impl Quantity {
    /// Records `gpu` against `cpu` with the f32-noise allowance `noise`; false if it fails.
    fn check(
        &mut self,
        gpu: f32,
        cpu: f32,
        noise: f64,
        at: impl FnOnce() -> String,
        place: impl FnOnce() -> String,
    ) -> bool {
        let e = rel(gpu, cpu);
        self.raw.add(e, at);
        if e <= TOLERANCE {
            return true;
        }
        if e <= 4.0 * noise {
            self.ill_conditioned += 1;
            self.ill_where.insert(place());
            return true;
        }
        false
    }
}

#[derive(Default)]
struct ModelReport {
    eval: Quantity,
    pdf: Quantity,
    /// |Δωi| of samples.
    sample_wi: Worst,
    /// Sample f and pdf against the CPU's eval and pdf at the GPU's direction.
    sample_f: Quantity,
    sample_pdf: Quantity,
    /// Sample f against the CPU sample's own f (direction differences included).
    sample_f_direct: Worst,
    /// Samples whose lobe choice sat on a threshold (the CPU picks the GPU's lobe with uc
    /// moved by 4 ulp).
    lobe_ties: usize,
    cases: usize,
    samples: usize,
}

struct Case {
    m: u32,
    wo: Vec3,
    wi: Vec3,
    uc: f32,
    u: Vec2,
    wl: usize,
}

/// eval's four lanes and pdf.
fn eval_pdf<B: Bsdf<4>>(bsdf: &B, wo: Vec3, wi: Vec3) -> [f32; 5] {
    let f = bsdf.eval(wo, wi);
    [f[0], f[1], f[2], f[3], bsdf.pdf(wo, wi)]
}

#[test]
fn every_model_matches_the_cpu_on_the_gpu() {
    let Some(h) = Harness::new() else { return };
    let all = test_materials();
    let refs: Vec<Material> = all.iter().map(reference).collect();
    let kernel = generate(&all, true).unwrap();
    let src = format!("{}\n{TEST_ENTRIES}", kernel.wgsl);
    let t = Instant::now();
    let module = h.module(&src).unwrap_or_else(|e| panic!("{e}"));
    let pipeline = h.pipeline(&module, "test_bsdf").unwrap_or_else(|e| panic!("{e}"));
    println!("all-model kernel ({} materials) compiled in {:.2} s", all.len(), t.elapsed().as_secs_f64());

    // Cases: every ωo × ωi for eval/pdf, and every ωo × a (uc, u) grid for sample.
    let wls = wavelength_sets();
    let ucs = [0.02f32, 0.31, 0.62, 0.97];
    let us = [0.07f32, 0.33, 0.58, 0.91];
    let mut cases = Vec::new();
    for m in 0..all.len() as u32 {
        for (a, wo) in outgoing().into_iter().enumerate() {
            for (b, wi) in incident(wo).into_iter().enumerate() {
                let wl = (a + b + m as usize) % wls.len();
                cases.push(Case { m, wo, wi, uc: 0.5, u: Vec2::new(0.45, 0.55), wl });
            }
            for (i, &uc) in ucs.iter().enumerate() {
                for (j, &ux) in us.iter().enumerate() {
                    for (k, &uy) in us.iter().enumerate() {
                        let wl = (a + i + j + k + m as usize) % wls.len();
                        let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                        cases.push(Case { m, wo, wi, uc, u: Vec2::new(ux, uy), wl });
                    }
                }
            }
        }
    }
    let mut input = Vec::with_capacity(cases.len() * 16);
    for c in &cases {
        let l = wls[c.wl].lambda;
        #[rustfmt::skip]
        input.extend_from_slice(&[
            f32::from_bits(c.m), c.uc, c.u.x, c.u.y,
            c.wo.x, c.wo.y, c.wo.z, 0.0,
            c.wi.x, c.wi.y, c.wi.z, 0.0,
            l[0], l[1], l[2], l[3],
        ]);
    }
    let (out, seconds) = h.run(&pipeline, &kernel, &input, cases.len() as u32, cases.len() * 32);
    println!("{} cases on the GPU in {seconds:.3} s", cases.len());

    let mut reports: BTreeMap<&str, ModelReport> = BTreeMap::new();
    let mut failures = Vec::new();
    let mut accessor_worst = Worst::default();
    for (n, c) in cases.iter().enumerate() {
        let g = &out[n * 32..n * 32 + 32];
        let material = &refs[c.m as usize];
        let wl = &wls[c.wl];
        let bsdf = material.bsdf(wl);
        let r = reports.entry(model_name(material)).or_default();
        r.cases += 1;
        let at =
            || format!("'{}' wo={:?} wi={:?} uc={} u={:?} λ={:?}", material.name, c.wo, c.wi, c.uc, c.u, wl.lambda);
        let place = || format!("'{}' |cos θo| = {}", material.name, c.wo.z.abs());

        // eval and pdf.
        let cpu = eval_pdf(&bsdf, c.wo, c.wi);
        let noise = f32_noise(|a, b| eval_pdf(&bsdf, a, b), c.wo, c.wi);
        for k in 0..5 {
            let q = if k < 4 { &mut r.eval } else { &mut r.pdf };
            if !q.check(g[k], cpu[k], noise[k], at, place) {
                let what = if k < 4 { "eval" } else { "pdf" };
                failures.push(format!(
                    "{what}[{k}]: gpu {} cpu {} (f32 noise {:.1e}) at {}",
                    g[k],
                    cpu[k],
                    noise[k],
                    at()
                ));
            }
        }

        // sample: existence, flags, direction, then f and pdf.
        let gs_pdf = g[12];
        let gs_flags = g[13].to_bits();
        let gwi = Vec3::new(g[5], g[6], g[7]);
        let agrees = |t: &Option<brdf::BsdfSample<4>>| match t {
            None => gs_pdf == 0.0,
            Some(t) => {
                gs_pdf != 0.0 && t.flags.bits() as u32 == gs_flags && ((gwi - t.wi).length() as f64) <= TOLERANCE
            }
        };
        let mut cpu_sample = bsdf.sample(c.wo, c.uc, c.u);
        if !agrees(&cpu_sample) {
            // The lobe is chosen by comparing uc with sums of quotients of the lobe
            // weights, which a GPU's division (in Vulkan not correctly rounded: 2.5 ulp)
            // may round to the other side of uc; the chosen lobe may then fail to sample
            // where the other succeeds. Where moving uc by 4 ulp makes the CPU do what the
            // GPU did, the two agree up to that rounding.
            let eps = 4.0 * f32::EPSILON;
            if let Some(t) =
                [1.0 - eps, 1.0 + eps].into_iter().map(|k| bsdf.sample(c.wo, c.uc * k, c.u)).find(|t| agrees(t))
            {
                r.lobe_ties += 1;
                cpu_sample = t;
            }
        }
        match cpu_sample {
            None if gs_pdf == 0.0 => {}
            None => failures.push(format!("sample: the GPU sampled (pdf {gs_pdf}) where the CPU did not, at {}", at())),
            Some(s) if gs_pdf == 0.0 => {
                failures.push(format!("sample: the CPU sampled {s:?} where the GPU did not, at {}", at()))
            }
            Some(s) => {
                r.samples += 1;
                if s.flags.bits() as u32 != gs_flags {
                    failures.push(format!("sample flags: gpu {gs_flags} cpu {} at {}", s.flags.bits(), at()));
                }
                let dwi = (gwi - s.wi).length() as f64;
                r.sample_wi.add(dwi, at);
                if dwi > TOLERANCE {
                    failures.push(format!("sample wi: gpu {gwi:?} cpu {:?} at {}", s.wi, at()));
                }
                for k in 0..4 {
                    r.sample_f_direct.add(rel(g[8 + k], s.f[k]), at);
                }
                let (cpu, noise) = if s.flags.is_specular() {
                    ([s.f[0], s.f[1], s.f[2], s.f[3], s.pdf], [0.0; 5])
                } else {
                    (eval_pdf(&bsdf, c.wo, gwi), f32_noise(|a, b| eval_pdf(&bsdf, a, b), c.wo, gwi))
                };
                let gpu = [g[8], g[9], g[10], g[11], gs_pdf];
                for k in 0..5 {
                    let q = if k < 4 { &mut r.sample_f } else { &mut r.sample_pdf };
                    if !q.check(gpu[k], cpu[k], noise[k], at, place) {
                        let what = if k < 4 { "sample f" } else { "sample pdf" };
                        failures.push(format!("{what}[{k}]: gpu {} cpu {} at {}", gpu[k], cpu[k], at()));
                    }
                }
            }
        }

        // Material accessors. Flags: the GPU's are the union over all wavelengths, so
        // Shirley–Ashikhmin may add DIFFUSE where R_d (1 − R_s) vanishes at these λ only.
        let flags = g[14].to_bits();
        let cpu_flags = bsdf.flags().bits() as u32;
        let extra = flags & !cpu_flags;
        let diffuse = brdf::ScatterFlags::DIFFUSE.bits() as u32;
        let ashikhmin = material.model() == Some(ModelId::Ashikhmin);
        if cpu_flags & !flags != 0 || (extra != 0 && !(ashikhmin && extra == diffuse)) {
            failures.push(format!("material flags: gpu {flags} cpu {cpu_flags} at {}", at()));
        }
        let props = g[15].to_bits();
        if (props & 1 != 0) != material.is_two_sided() || (props & 2 != 0) != material.is_dispersive() {
            failures.push(format!("properties {props} at {}", at()));
        }
        let zero = spectral::SampledSpectrum::zero();
        let emission = material.emission.as_ref().map_or(zero, |e| e.sample(wl));
        let absorption = material.absorption().map_or(zero, |a| a.sample(wl));
        for k in 0..4 {
            for (gv, cv) in [(g[16 + k], emission[k]), (g[20 + k], absorption[k])] {
                let e = rel(gv, cv);
                accessor_worst.add(e, at);
                if e > TOLERANCE {
                    failures.push(format!("emission/absorption[{k}]: gpu {gv} cpu {cv} at {}", at()));
                }
            }
        }
    }

    println!("\nmax GPU–CPU errors per model (relative, floor {FLOOR:e}; smp wi = |Δωi|; ill = values beyond");
    println!("{TOLERANCE:e} within 4× the CPU's own f32 noise; smp f direct = against the CPU sample's f):");
    println!(
        "{:<15} {:>6} {:>6} {:>9} {:>9} {:>9} {:>9} {:>9} {:>12} {:>5}",
        "model", "cases", "samp.", "eval", "pdf", "smp wi", "smp f", "smp pdf", "smp f direct", "ill"
    );
    for (name, r) in &reports {
        let ill =
            r.eval.ill_conditioned + r.pdf.ill_conditioned + r.sample_f.ill_conditioned + r.sample_pdf.ill_conditioned;
        println!(
            "{name:<15} {:>6} {:>6} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>12.2e} {:>5}",
            r.cases,
            r.samples,
            r.eval.raw.err,
            r.pdf.raw.err,
            r.sample_wi.err,
            r.sample_f.raw.err,
            r.sample_pdf.raw.err,
            r.sample_f_direct.err,
            ill
        );
    }
    for (name, r) in &reports {
        for (what, w) in [
            ("eval", &r.eval.raw),
            ("pdf", &r.pdf.raw),
            ("sample f", &r.sample_f.raw),
            ("sample pdf", &r.sample_pdf.raw),
            ("sample wi", &r.sample_wi),
        ] {
            if w.err > TOLERANCE / 10.0 {
                println!("  {name} {what}: worst {:.2e} at {}", w.err, w.at);
            }
        }
    }
    for (name, r) in &reports {
        let mut places = std::collections::BTreeSet::new();
        for q in [&r.eval, &r.pdf, &r.sample_f, &r.sample_pdf] {
            places.extend(q.ill_where.iter().cloned());
        }
        if !places.is_empty() {
            println!("  {name}: ill-conditioned (accepted as f32 noise) at {places:?}");
        }
        if r.lobe_ties > 0 {
            println!("  {name}: {} samples chose their lobe on a threshold (uc ± 4 ulp)", r.lobe_ties);
        }
    }
    println!("emission/absorption: max error {:.2e}", accessor_worst.err);
    assert_eq!(reports.len(), ModelId::ALL.len() + 1, "every registered model and the custom twin");
    if !failures.is_empty() {
        for f in failures.iter().take(40) {
            println!("FAIL {f}");
        }
        panic!("{} GPU–CPU mismatches (first ones above)", failures.len());
    }
}

#[test]
fn fresnel_routines_match_the_cpu_on_the_gpu() {
    let Some(h) = Harness::new() else { return };
    let kernel = generate(&test_materials(), true).unwrap();
    let src = format!("{}\n{TEST_ENTRIES}", kernel.wgsl);
    let module = h.module(&src).unwrap_or_else(|e| panic!("{e}"));
    let pipeline = h.pipeline(&module, "test_fresnel").unwrap_or_else(|e| panic!("{e}"));
    let mut cosines: Vec<f32> = (-20..=20).map(|i| i as f32 / 20.0).collect();
    cosines.extend([1e-4, -1e-4, 0.999_9, -0.999_9, 1.5f32.atan().cos(), 0.05, -0.05]);
    let etas = [1e-3f32, 0.5, 1.0 / 1.5, 1.0, 1.0001, 1.33, 1.5, 2.4, 10.0];
    let ks = [0.0f32, 1e-3, 1.0, 3.0, 8.3, 20.0];
    let mut input = Vec::new();
    for &c in &cosines {
        for &eta in &etas {
            for &k in &ks {
                input.extend_from_slice(&[c, eta, k, 0.0]);
            }
        }
    }
    let n = input.len() / 4;
    let (out, _) = h.run(&pipeline, &kernel, &input, n as u32, n * 4);
    let mut worst = [Worst::default(), Worst::default(), Worst::default()];
    let mut ill = [0usize; 3];
    let mut failures = Vec::new();
    let fresnel = |c: f32, eta: f32, k: f32| {
        [
            brdf::fresnel::fresnel_dielectric(c, eta),
            brdf::fresnel::fresnel_schlick(c, eta),
            brdf::models::fresnel_conductor(c, eta, k),
        ]
    };
    for i in 0..n {
        let (c, eta, k) = (input[4 * i], input[4 * i + 1], input[4 * i + 2]);
        let cpu = fresnel(c, eta, k);
        // The CPU's own spread when cos θ and η move by 4 ulp: near η = 1 the reflectance
        // is a difference of nearly equal terms, which no f32 evaluation pins down better
        // (the GPU's sqrt and division are not correctly rounded).
        let eps = 4.0 * f32::EPSILON;
        let mut noise = [0.0f64; 3];
        for (dc, de) in [(1.0 + eps, 1.0), (1.0 - eps, 1.0), (1.0, 1.0 + eps), (1.0, 1.0 - eps)] {
            let moved = fresnel(c * dc, eta * de, k);
            for j in 0..3 {
                noise[j] = noise[j].max(rel_floor(moved[j], cpu[j], FRESNEL_FLOOR));
            }
        }
        for j in 0..3 {
            let e = rel_floor(out[4 * i + j], cpu[j], FRESNEL_FLOOR);
            let at =
                || format!("cos={c} η={eta} κ={k}: gpu {} cpu {} (f32 noise {:.1e})", out[4 * i + j], cpu[j], noise[j]);
            worst[j].add(e, at);
            if e > TOLERANCE && e <= 4.0 * noise[j] {
                ill[j] += 1;
            } else if e > TOLERANCE {
                failures.push(at());
            }
        }
    }
    for ((name, w), ill) in ["dielectric", "schlick", "conductor"].iter().zip(&worst).zip(ill) {
        println!(
            "Fresnel {name}: max relative error {:.2e} ({n} inputs, {ill} beyond {TOLERANCE:e} within 4× the CPU's f32 \
             noise; worst {})",
            w.err, w.at
        );
    }
    assert!(failures.is_empty(), "Fresnel beyond the tolerance and the f32 noise: {failures:#?}");
}

#[test]
fn spectrum_lookup_matches_the_cpu() {
    let Some(h) = Harness::new() else { return };
    let all = test_materials();
    let kernel = generate(&all, true).unwrap();
    let src = format!("{}\n{TEST_ENTRIES}", kernel.wgsl);
    let module = h.module(&src).unwrap_or_else(|e| panic!("{e}"));
    let pipeline = h.pipeline(&module, "test_spectrum").unwrap_or_else(|e| panic!("{e}"));
    // Every distinct colour of the test materials (and some emitters), with its offset.
    let mut colours: Vec<Colour> = Vec::new();
    for m in &all {
        if let Some(params) = m.params() {
            for v in params.to_resolved().values() {
                if let Resolved::Colour(c) = v {
                    colours.push(c.clone());
                }
            }
        }
        colours.extend(m.emission.clone());
    }
    colours.push(Colour::illuminant_rgb([0.2, 0.9, 0.4]).unwrap());
    colours.push(Colour::from_spectrum(
        Spectrum::Blackbody { kelvin: 2700.0, scale: 1.0 },
        spectral::spectrum::ColourRole::Illuminant,
    ));
    let scene: Vec<Material> =
        colours.iter().enumerate().map(|(i, c)| lambert(&format!("m{i}"), [0.5; 3]).with_emission(c.clone())).collect();
    let kernel_e = generate(&scene, true).unwrap();
    let offsets: Vec<u32> = (0..scene.len())
        .map(|i| kernel_e.data[i * materials::HEADER_WORDS as usize + materials::header::EMISSION as usize])
        .collect();
    // Wavelengths: fractional ones over the range, integers, and beyond both ends.
    let mut lambdas: Vec<f32> = (0..400).map(|i| 355.0 + i as f32 * 1.2031).collect();
    lambdas.extend([360.0, 361.0, 587.0, 829.0, 830.0, 300.0, 900.0, 829.999, 360.001]);
    while !lambdas.len().is_multiple_of(4) {
        lambdas.push(500.25);
    }
    let mut input = Vec::new();
    for &o in &offsets {
        for l in lambdas.chunks(4) {
            input.extend_from_slice(&[f32::from_bits(o), 0.0, 0.0, 0.0, l[0], l[1], l[2], l[3]]);
        }
    }
    let n = input.len() / 8;
    let (out, _) = h.run(&pipeline, &kernel_e, &input, n as u32, n * 4);
    let _ = kernel; // the all-model kernel compiled the same spectrum_at
    let (mut vs_table, mut vs_exact_int, mut table_error) = (Worst::default(), Worst::default(), Worst::default());
    for (ci, colour) in colours.iter().enumerate() {
        let table = materials::tabulate(colour);
        let scale = table.iter().fold(0.0f32, |a, &v| a.max(v.abs())).max(FLOOR);
        for (li, &lambda) in lambdas.iter().enumerate() {
            let g = out[(ci * lambdas.len() / 4 + li / 4) * 4 + li % 4];
            let cpu_table = materials::spectrum_lookup(&table, lambda);
            let exact = colour.sample(&SampledWavelengths::<1>::fixed_bins(lambda.clamp(360.0, 830.0), 1.0)).0[0];
            let at = || format!("colour {ci} ({:?}) λ={lambda}: gpu {g} table {cpu_table} exact {exact}", colour.rgb);
            vs_table.add(rel(g, cpu_table), at);
            if lambda.fract() == 0.0 {
                vs_exact_int.add(rel(g, exact), at);
            }
            // The 1-nm table against the exact spectrum, relative to the spectrum's peak.
            table_error.add((cpu_table as f64 - exact as f64).abs() / scale as f64, at);
        }
    }
    println!("spectrum_at vs the CPU's 1-nm interpolation: max relative error {:.2e} ({})", vs_table.err, vs_table.at);
    println!("spectrum_at vs the exact spectrum at integer λ: max relative error {:.2e}", vs_exact_int.err);
    println!(
        "1-nm table vs the exact spectrum at any λ: max error {:.2e} of the peak ({})",
        table_error.err, table_error.at
    );
    assert!(vs_table.err <= TOLERANCE, "{}", vs_table.at);
    assert!(vs_exact_int.err <= TOLERANCE, "{}", vs_exact_int.at);
    assert!(table_error.err <= 1e-3, "the 1-nm tables lose more than 0.1 %: {}", table_error.at);
}

/// Prints (does not assert) shader-module and pipeline creation times, and the time of a
/// fixed workload, for a two-model scene with and without specialisation.
#[test]
fn specialisation_compile_time_and_speed() {
    let Some(h) = Harness::new() else { return };
    let scene = [
        lambert("white", [0.8; 3]),
        lambert("red", [0.8, 0.1, 0.1]),
        builtin("glass", ModelId::Dielectric, &[("ior", ParamValue::Scalar(1.5))]),
    ];
    let mut report = Vec::new();
    for specialise in [true, false] {
        let kernel = generate(&scene, specialise).unwrap();
        let naga_start = Instant::now();
        naga_validate(&kernel.wgsl).unwrap();
        let naga_s = naga_start.elapsed().as_secs_f64();
        let (mut module_s, mut pipeline_s, mut first_s) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut pipeline = None;
        for rep in 0..3 {
            // A different constant each time (and each run), so that no driver or disk
            // cache can answer.
            let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().subsec_nanos();
            let salt = nanos / 16 * 16 + rep + 4 * specialise as u32;
            let src = format!("{}\n{TEST_ENTRIES}\nconst MAT_TEST_SALT: u32 = {salt}u;\n", kernel.wgsl);
            let src = src.replacen(
                "    for (var k = 0u; k < 24u; k++) {",
                "    results[o + 31u] = f32(MAT_TEST_SALT);\n    for (var k = 0u; k < 24u; k++) {",
                1,
            );
            let t = Instant::now();
            let module = h.module(&src).unwrap();
            module_s = module_s.min(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let p = h.pipeline(&module, "test_bsdf").unwrap();
            pipeline_s = pipeline_s.min(t.elapsed().as_secs_f64());
            // One invocation: catches a driver that compiles lazily at the first dispatch.
            let one = [0.0f32, 0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 500.0, 500.0, 500.0, 500.0];
            first_s = first_s.min(h.run(&p, &kernel, &one, 1, 32).1);
            pipeline = Some(p);
        }
        // Workload: 2^16 eval + pdf + sample calls spread over the three materials.
        let n = 1 << 16;
        let mut input = Vec::with_capacity(n * 16);
        for i in 0..n {
            let wo = dir(5.0 + (i % 80) as f32, (i % 360) as f32);
            let wi = dir(5.0 + ((i / 7) % 170) as f32, ((i * 13) % 360) as f32);
            let u = ((i * 7919) % 1000) as f32 / 1000.0;
            input.extend_from_slice(&[
                f32::from_bits((i % 3) as u32),
                u,
                1.0 - u,
                0.5 * u,
                wo.x,
                wo.y,
                wo.z,
                0.0,
                wi.x,
                wi.y,
                wi.z,
                0.0,
                400.0 + u * 300.0,
                450.0,
                550.0,
                650.0,
            ]);
        }
        let p = pipeline.unwrap();
        let _ = h.run(&p, &kernel, &input, n as u32, n * 32);
        let mut run_s = f64::INFINITY;
        for _ in 0..3 {
            run_s = run_s.min(h.run(&p, &kernel, &input, n as u32, n * 32).1);
        }
        report.push((
            specialise,
            kernel.models.len(),
            kernel.wgsl.lines().count(),
            naga_s,
            module_s,
            pipeline_s,
            first_s,
            run_s,
        ));
    }
    println!("\ntwo-model scene (lambert + dielectric) on {}:", h.ctx.info.name);
    for (specialise, models, lines, naga_s, module_s, pipeline_s, first_s, run_s) in report {
        println!(
            "  specialise={specialise:<5} models={models} WGSL lines={lines:>5}  naga parse+validate {:.1} ms  \
             create_shader_module {:.1} ms  create_compute_pipeline {:.1} ms  first 1-thread dispatch {:.1} ms  \
             65536 × (eval + pdf + sample) {:.2} ms",
            naga_s * 1e3,
            module_s * 1e3,
            pipeline_s * 1e3,
            first_s * 1e3,
            run_s * 1e3
        );
    }
}
