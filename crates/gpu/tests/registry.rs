//! The CPU renderer, the scene loaders and the GPU code generator know the same set of
//! models: the registry's. For every registered model, an MTL material naming it
//! (`bsdf NAME`) loads as that model with the parameters its MTL keys set, renders on the
//! CPU, and compiles (naga-validated) into a GPU kernel containing its twin.

use brdf::ModelId;
use brdf::params::{ParamKind, Resolved};
use gpu::materials::generate;
use std::collections::BTreeSet;
use tracer::{Backend, CpuBackend, RenderSettings, SceneOptions};

/// An MTL file for one material of `model`, setting each parameter that has an MTL key
/// to a value inside its range (away from the default where the range allows).
fn mtl_for(model: ModelId) -> String {
    let mut mtl = format!("newmtl m\nbsdf {}\n", model.name());
    for p in model.def().params {
        let Some(key) = p.mtl_key else { continue };
        let value = match p.kind {
            ParamKind::Scalar => {
                let hi = if p.max.is_finite() { p.max } else { p.min + 2.0 };
                format!("{}", p.min + 0.37 * (hi - p.min))
            }
            ParamKind::Spectrum => "0.3 0.6 0.2".into(),
            ParamKind::Coefficient => "0.5 1 2".into(),
            ParamKind::Bool => "1".into(),
            ParamKind::Choice(names) => format!("{}", names.len() - 1),
        };
        mtl.push_str(&format!("{key} {value}\n"));
    }
    mtl
}

#[test]
fn cpu_loaders_and_gpu_know_the_same_models() {
    let dir = std::env::temp_dir().join(format!("spt-registry-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut loaded = BTreeSet::new();
    let mut compiled = BTreeSet::new();
    for &model in ModelId::ALL {
        let name = model.name();
        // The loader: `bsdf NAME` and the model's MTL keys.
        std::fs::write(dir.join("m.mtl"), mtl_for(model)).unwrap();
        let obj = "mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
        std::fs::write(dir.join("s.obj"), obj).unwrap();
        let mut scene = tracer::obj::load_obj(&dir.join("s.obj")).unwrap_or_else(|e| panic!("{name}: {e}"));
        let material = &scene.materials[0];
        assert_eq!(material.model(), Some(model), "{name}");
        let resolved = material.params().unwrap().to_resolved();
        for (p, v) in model.def().params.iter().zip(resolved.values()) {
            if p.mtl_key.is_some() && p.kind == ParamKind::Scalar {
                assert_ne!(*v, Resolved::Scalar(p.default), "{name}.{}: the MTL value was not read", p.name);
            }
        }
        loaded.insert(name);
        // The GPU: a kernel with exactly this model, validated by naga.
        let kernel = generate(&scene.materials, true).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(kernel.models, vec![model]);
        let module = naga::front::wgsl::parse_str(&kernel.wgsl).unwrap_or_else(|e| panic!("{name}: {e}"));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(module.functions.iter().any(|(_, f)| f.name.as_deref() == Some(&format!("{name}_sample"))));
        compiled.insert(name);
        // The CPU: a render that reaches the model (lit by a sky, seen head on).
        scene.environment = Some(tracer::Environment::uniform(spectral::spectrum::Colour::constant(1.0)));
        let prepared = CpuBackend::new(1).unwrap().prepare(scene, &SceneOptions::default()).unwrap();
        let settings = RenderSettings { width: 8, height: 8, spp: 2, ..Default::default() };
        let (film, stats) = tracer::render(prepared.as_ref(), &settings, &|_| {}).unwrap();
        assert_eq!((stats.non_finite, film.samples()), (0, 128), "{name}");
    }
    let registry: BTreeSet<&str> = ModelId::ALL.iter().map(|m| m.name()).collect();
    assert_eq!(loaded, registry);
    assert_eq!(compiled, registry);
    assert_eq!(registry.len(), ModelId::ALL.len(), "model names are unique");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Each model's WGSL twin says where its texture slots act (`ModelWgsl::texture`), and that
/// agrees with its Rust `TEXTURE_SLOTS`: a slot the Rust model has names a spectrum
/// parameter of the model (or, for metallic–roughness, the twin defines the `_textured`
/// hook), and a slot it lacks names nothing.
#[test]
fn wgsl_texture_slots_agree_with_the_models() {
    for &model in ModelId::ALL {
        let slots = model.defaults().texture_slots();
        let wgsl = model.wgsl().texture;
        let name = model.name();
        for (what, has, param) in
            [("base colour", slots.base_colour, wgsl.base_colour), ("specular", slots.specular, wgsl.specular)]
        {
            assert_eq!(has, param.is_some(), "{name}: the {what} slot");
            if let Some(param) = param {
                let (_, def) = model.def().param(param).unwrap_or_else(|| panic!("{name}: no parameter '{param}'"));
                assert!(matches!(def.kind, ParamKind::Spectrum), "{name}: '{param}' is not a spectrum");
            }
        }
        assert_eq!(slots.metallic_roughness, wgsl.metallic_roughness, "{name}: the metallic-roughness slot");
        let hook = format!("fn {name}_textured(");
        assert_eq!(wgsl.metallic_roughness, model.wgsl().source.contains(&hook), "{name}: {hook}");
    }
}
