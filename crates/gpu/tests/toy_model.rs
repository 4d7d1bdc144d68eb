//! Adding a model takes its file and one registry line: this one file declares a toy
//! model — parameters, BSDF, WGSL twin — and registers it beside the built-ins with one
//! line, `brdf::with_builtin_models!(brdf::registry, Toy(ToyParams))`. Nothing else in
//! the workspace changes, yet the registry names it, resolves its parameters by name and
//! MTL key, dispatches its BSDF on the CPU, and the GPU generator compiles its twin into a
//! kernel that naga validates.

use brdf::params::{ParamSet, ParamValue};
use brdf::wgsl::{ModelWgsl, WgslPiece};
use brdf::{Bsdf, BsdfSample, Model, ScatterFlags};
use glam::{Vec2, Vec3};
use gpu::materials::{Features, ModelEntry, wgsl_for};
use spectral::{SampledSpectrum, SampledWavelengths};

brdf::model_params! {
    /// A toy: Lambertian reflection scaled by a gain, optionally only on one side.
    pub struct ToyParams for "toy" {
        doc: "A toy model for the registry test: f = gain·R/π.",
        albedo: spectrum { doc: "reflectance R", default: 0.5, mtl: "Kd" },
        gain: scalar { doc: "a factor on R", default: 1.0, min: 0.0, max: 1.0, mtl: "gain" },
        front_only: bool { doc: "reflect from the front side only", default: false },
    }
}

/// The toy bound to a path's wavelengths.
pub struct Toy<const N: usize> {
    r: SampledSpectrum<N>,
    front_only: bool,
}

impl<const N: usize> Bsdf<N> for Toy<N> {
    fn flags(&self) -> ScatterFlags {
        ScatterFlags::REFLECTION | ScatterFlags::DIFFUSE
    }
    fn eval(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum<N> {
        let ok = wo.z * wi.z > 0.0 && (!self.front_only || wo.z > 0.0);
        if ok { self.r * std::f32::consts::FRAC_1_PI } else { SampledSpectrum::zero() }
    }
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        brdf::sampling::cosine_hemisphere_two_sided_pdf(wo, wi)
    }
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<BsdfSample<N>> {
        let (wi, pdf) = brdf::sampling::cosine_hemisphere_two_sided(wo, u)?;
        Some(BsdfSample { wi, f: self.eval(wo, wi), pdf, flags: self.flags() })
    }
}

const TOY_WGSL: &str = "
fn toy_eval(p: ToyParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> vec4f {
    if wo.z * wi.z > 0.0 && (!p.front_only || wo.z > 0.0) {
        return p.gain * spectrum_at(p.albedo, lambda) * MAT_FRAC_1_PI;
    }
    return vec4f(0.0);
}

fn toy_pdf(p: ToyParams, wo: vec3f, wi: vec3f, lambda: vec4f) -> f32 {
    return mat_cosine_two_sided_pdf(wo, wi);
}

fn toy_sample(p: ToyParams, wo: vec3f, uc: f32, u: vec2f, lambda: vec4f) -> BsdfSample {
    let s = mat_cosine_two_sided(wo, u);
    if s.w <= 0.0 {
        return mat_no_sample();
    }
    return BsdfSample(s.xyz, toy_eval(p, wo, s.xyz, lambda), s.w, SCATTER_REFLECTION | SCATTER_DIFFUSE);
}
";

impl Model for ToyParams {
    type Bsdf<const N: usize> = Toy<N>;
    const WGSL: ModelWgsl = ModelWgsl {
        source: TOY_WGSL,
        needs: &[WgslPiece::Sampling],
        constants: &[],
        texture: brdf::wgsl::WgslTextureSlots::NONE,
    };

    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Toy<N> {
        Toy { r: self.albedo.sample(wl) * self.gain, front_only: self.front_only }
    }
}

/// The one registry line.
mod registry {
    use super::ToyParams;
    brdf::with_builtin_models!(brdf::registry, Toy(ToyParams));
}

use registry::{ModelId, ModelParams};

#[test]
fn the_registry_knows_the_toy_beside_the_built_ins() {
    assert_eq!(ModelId::ALL.len(), brdf::ModelId::ALL.len() + 1);
    for (ours, builtin) in ModelId::ALL.iter().zip(brdf::ModelId::ALL) {
        assert_eq!(ours.name(), builtin.name());
    }
    let toy = ModelId::by_name("TOY").unwrap();
    assert_eq!(toy, ModelId::Toy);
    assert_eq!(toy.def().param_by_mtl_key("gain").unwrap().name, "gain");
    // Parameters by name, checked against the declaration.
    let given = [("gain", ParamValue::Scalar(0.5)), ("front_only", ParamValue::Bool(true))];
    let params = toy.resolve("toy material", &given).unwrap();
    assert!(matches!(&params, ModelParams::Toy(p) if p.gain == 0.5 && p.front_only));
    let err = toy.resolve("toy material", &[("gain", ParamValue::Scalar(2.0))]).unwrap_err();
    assert!(err.to_string().contains("gain = 2"), "{err}");
    // The CPU dispatch reaches the toy's BSDF.
    let wl = SampledWavelengths::<4>::fixed_bins(450.0, 100.0);
    let bsdf = params.bsdf(&wl);
    let (up, down) = (Vec3::new(0.0, 0.6, 0.8), Vec3::new(0.0, 0.6, -0.8));
    let expect = 0.5 * 0.5 * std::f32::consts::FRAC_1_PI;
    assert!((bsdf.eval(up, Vec3::Z).0[0] - expect).abs() < 1e-7);
    assert!(bsdf.eval(down, -Vec3::Z).is_black(), "front_only");
    assert!(!params.is_transmissive());
    let back = toy.from_resolved(&params.to_resolved());
    assert_eq!(back, params);
    assert_eq!(ToyParams::default().gain, 1.0);
    assert_eq!(ToyParams::DEF.params.len(), 3);
}

#[test]
fn the_gpu_generator_compiles_the_toy() {
    let entries: Vec<ModelEntry> =
        ModelId::ALL.iter().map(|m| ModelEntry { id: m.index(), def: *m.def(), wgsl: *m.wgsl() }).collect();
    let src = wgsl_for(&entries, &Features::all(), &[]).unwrap();
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    let names: Vec<String> = module.functions.iter().filter_map(|(_, f)| f.name.clone()).collect();
    for f in ["toy_eval", "toy_pdf", "toy_sample", "load_toy"] {
        assert!(names.iter().any(|n| n == f), "{f} missing");
    }
    // The generated struct has the declared fields, typed by kind, and the dispatch a case.
    assert!(src.contains("struct ToyParams {\n    albedo: u32,"), "{src}");
    assert!(src.contains("    front_only: bool,"));
    assert!(src.contains(&format!("const MAT_MODEL_TOY: u32 = {}u;", ModelId::Toy.index())));
    assert!(src.contains("case MAT_MODEL_TOY: { return toy_sample(load_toy(base), wo, uc, u, lambda); }"));
}
