//! The path-tracing kernel's generated parts against the Rust definitions (no device):
//! struct layouts as naga lays them out, the shared constants' values, the triangle test
//! compiled in, and every hand-written WGSL file naming a Rust file that exists.

use gpu::kernel::{self, FILM_HEADER_BYTES, KernelOptions, Params, PixelAccum, WgslStruct};
use gpu::materials::generate;
use naga::{Literal, TypeInner};
use spectral::spectrum::Colour;
use tracer::material::Material;

fn options(triangle_test: bvh::TriangleTest) -> KernelOptions {
    KernelOptions {
        triangle_test,
        max_bounces: gpu::backend::MAX_BOUNCES,
        nodes: gpu::kernel::NodeLayout::Wide4 { stack: 24 },
        integrator: gpu::kernel::GpuIntegrator::Path,
        sampler: tracer::sampler::SamplerKind::ZSobol,
        shapes: true,
        instances: true,
        punctual_lights: true,
        implicit_coeffs: 0,
        mode: spectral::SpectralMode::Bins40,
        textures: true,
        cutouts: true,
        env_map: true,
        bvh_builder: bvh::SplitMethod::BinnedSah,
        wavefront: false,
        light_sampler: tracer::LightSampler::Tree,
        light_tree: true,
    }
}

/// The whole kernel for a one-material scene, parsed by naga.
fn parsed_kernel(options: &KernelOptions) -> (String, naga::Module) {
    let materials = [Material::diffuse("grey", Colour::constant(0.5)).unwrap()];
    let src = kernel::source(&generate(&materials, true).unwrap().wgsl, options);
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    (src, module)
}

/// Whether naga validates `module` with `capabilities` (the error, rendered, if not).
fn validate(src: &str, module: &naga::Module, capabilities: naga::valid::Capabilities) -> Result<(), String> {
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
        .validate(module)
        .map(|_| ())
        .map_err(|e| e.emit_to_string(src))
}

/// [`parsed_kernel`], validated by naga without optional capabilities (no f64).
fn kernel_module(options: &KernelOptions) -> (String, naga::Module) {
    let (src, module) = parsed_kernel(options);
    validate(&src, &module, naga::valid::Capabilities::default()).unwrap_or_else(|e| panic!("{e}"));
    (src, module)
}

/// (member name, offset) of the WGSL struct `name`, and its size.
fn wgsl_layout(module: &naga::Module, name: &str) -> (Vec<(String, u32)>, u32) {
    let (_, ty) =
        module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).unwrap_or_else(|| panic!("{name}"));
    let TypeInner::Struct { members, span } = &ty.inner else { panic!("{name} is not a struct") };
    (members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect(), *span)
}

/// Where the Rust type `T` and its WGSL declaration disagree: none for a mirror.
fn mismatches<T: WgslStruct>(module: &naga::Module) -> Vec<String> {
    let (members, span) = wgsl_layout(module, T::NAME);
    let mut out = Vec::new();
    if members.len() != T::FIELDS.len() {
        out.push(format!("{}: {} WGSL members, {} Rust fields", T::NAME, members.len(), T::FIELDS.len()));
    }
    for ((wname, woff), (rname, _, roff)) in members.iter().zip(T::FIELDS) {
        if wname != rname || *woff as usize != *roff {
            out.push(format!("{}: WGSL {wname} at {woff}, Rust {rname} at {roff}", T::NAME));
        }
    }
    if span as usize != T::SIZE {
        out.push(format!("{}: WGSL size {span}, Rust size {}", T::NAME, T::SIZE));
    }
    out
}

#[test]
fn generated_structs_have_the_host_layout() {
    let (path_src, module) = kernel_module(&options(bvh::TriangleTest::Watertight));
    let mut problems = mismatches::<Params>(&module);
    problems.extend(mismatches::<gpu::kernel::WideNode>(&module));
    problems.extend(mismatches::<PixelAccum>(&module));
    // (The binary one without shapes and punctual lights: both specialisations parse.)
    let binary = KernelOptions {
        nodes: gpu::kernel::NodeLayout::Binary,
        shapes: false,
        instances: false,
        punctual_lights: false,
        ..options(bvh::TriangleTest::Watertight)
    };
    let (_, binary_module) = kernel_module(&binary);
    problems.extend(mismatches::<bvh::BvhNode>(&binary_module));
    // The 8-wide traversal parses and validates too, over the same node struct.
    let eight =
        KernelOptions { nodes: gpu::kernel::NodeLayout::Wide8 { stack: 40 }, ..options(bvh::TriangleTest::Watertight) };
    let (eight_src, eight_module) = kernel_module(&eight);
    assert!(eight_src.contains("traversal_wide8.wgsl") && !eight_src.contains("// ---- traversal_wide.wgsl"));
    problems.extend(mismatches::<gpu::kernel::WideNode>(&eight_module));
    assert!(problems.is_empty(), "{problems:#?}");
    // bdpt's kernel (its file, splat image and scratch only there) parses and validates.
    let bdpt = KernelOptions { integrator: gpu::kernel::GpuIntegrator::Bdpt, ..options(bvh::TriangleTest::Watertight) };
    let (bdpt_src, _) = kernel_module(&bdpt);
    assert!(bdpt_src.contains("// ---- bdpt.wgsl") && bdpt_src.contains("pt_bdpt_scratch"));
    assert!(!path_src.contains("// ---- bdpt.wgsl") && !path_src.contains("pt_bdpt_scratch"));
    // The film: header words, then the accumulators at the stride the host reads.
    let (members, _) = wgsl_layout(&module, "PtFilm");
    assert_eq!(members.last().unwrap(), &("pixels".to_string(), FILM_HEADER_BYTES as u32));
    println!("PtParams {} bytes, PtNode {}, PtPixel {}", Params::SIZE, bvh::BvhNode::SIZE, PixelAccum::SIZE);
}

/// The layout check can fail: a Rust struct whose second `[f32; 3]` follows the first at
/// byte 12, where WGSL's vec3f alignment puts it at 16.
#[test]
fn a_struct_with_another_layout_is_caught() {
    #[repr(C)]
    struct Packed {
        a: [f32; 3],
        b: [f32; 3],
    }
    impl WgslStruct for Packed {
        const NAME: &'static str = "Packed";
        const FIELDS: &'static [(&'static str, &'static str, usize)] =
            &[("a", "vec3f", std::mem::offset_of!(Packed, a)), ("b", "vec3f", std::mem::offset_of!(Packed, b))];
        const SIZE: usize = std::mem::size_of::<Packed>();
    }
    let src = format!("{}\n@group(0) @binding(0) var<storage, read> p: Packed;\n", Packed::declaration());
    let module = naga::front::wgsl::parse_str(&src).unwrap();
    let problems = mismatches::<Packed>(&module);
    assert!(problems.iter().any(|p| p.contains("b at 16, Rust b at 12")), "{problems:#?}");
    let _ = Packed { a: [0.0; 3], b: [0.0; 3] }.a;
}

/// The value of a module-scope `const` with a scalar or vector initialiser.
fn constant(module: &naga::Module, name: &str) -> Vec<f64> {
    let (_, c) =
        module.constants.iter().find(|(_, c)| c.name.as_deref() == Some(name)).unwrap_or_else(|| panic!("{name}"));
    let literal = |h: naga::Handle<naga::Expression>| match module.global_expressions[h] {
        naga::Expression::Literal(Literal::F32(v)) => v as f64,
        naga::Expression::Literal(Literal::U32(v)) => v as f64,
        naga::Expression::Literal(Literal::F64(v)) => v,
        ref other => panic!("{name}: {other:?}"),
    };
    match &module.global_expressions[c.init] {
        naga::Expression::Compose { components, .. } => components.iter().map(|&h| literal(h)).collect(),
        _ => vec![literal(c.init)],
    }
}

#[test]
fn shared_constants_are_the_rust_values() {
    let (_, module) = kernel_module(&options(bvh::TriangleTest::Watertight));
    let f = |v: f32| vec![v as f64];
    assert_eq!(constant(&module, "PT_MIN_SHADING_COSINE"), f(tracer::shading::MIN_SHADING_COSINE));
    assert_eq!(constant(&module, "PT_RR_MIN_TERMINATION"), f(tracer::integrator::RR_MIN_TERMINATION));
    assert_eq!(constant(&module, "PT_SHADOW_T_MAX"), f(tracer::integrator::SHADOW_T_MAX));
    assert_eq!(constant(&module, "PT_ONE_MINUS_EPSILON"), f(tracer::lights::ONE_MINUS_EPSILON));
    assert_eq!(constant(&module, "PT_VIS_K"), f(spectral::sampled::VIS_K));
    assert_eq!(constant(&module, "PT_VIS_TANH_HI"), f(spectral::sampled::VIS_TANH_HI));
    assert_eq!(constant(&module, "PT_OFFSET_INT_SCALE"), f(shapes::offset::OFFSET_INT_SCALE));
    assert_eq!(constant(&module, "PT_MAX_BOUNCES"), vec![gpu::backend::MAX_BOUNCES as f64]);
    assert_eq!(constant(&module, "PT_TREE_NODE_FLOATS"), vec![tracer::lights::LIGHT_TREE_NODE_FLOATS as f64]);
    let row = spectral::colour::XYZ_TO_SRGB[1];
    assert_eq!(constant(&module, "PT_XYZ_TO_SRGB_G"), row.map(|v| v as f64).to_vec());
    for mode in tracer::shading::ShadingNormals::ALL {
        let name = format!("PT_SHADING_{}", mode.name().to_ascii_uppercase().replace('-', "_"));
        assert_eq!(constant(&module, &name), vec![mode.code() as f64], "{name}");
    }
}

/// Implicit surfaces bring their f64 code into their own kernels only: such a kernel validates
/// with naga's FLOAT64 capability (wgpu's `SHADER_F64`) and not without, the others need no
/// f64; the solver's constants are `shapes`' and the arrays sized as asked.
#[test]
fn implicit_surfaces_compile_in_f64_only_where_a_scene_has_them() {
    use naga::valid::Capabilities;
    let with = KernelOptions { implicit_coeffs: 7, ..options(bvh::TriangleTest::Watertight) };
    let (src, module) = parsed_kernel(&with);
    assert!(src.contains("// ---- implicit.wgsl"));
    validate(&src, &module, Capabilities::default() | Capabilities::FLOAT64).unwrap_or_else(|e| panic!("{e}"));
    let err = validate(&src, &module, Capabilities::default()).unwrap_err();
    assert!(err.contains("FLOAT64"), "{err}");
    assert_eq!(constant(&module, "PT_IMPLICIT_COEFFS"), vec![7.0]);
    assert_eq!(constant(&module, "PT_IM_S_EPS"), vec![shapes::implicit::S_EPS]);
    assert_eq!(constant(&module, "PT_IM_PAD_REL"), vec![shapes::implicit::PAD_REL]);
    assert_eq!(constant(&module, "PT_IM_REAL_IM_TOL"), vec![shapes::roots::REAL_IM_TOL]);
    assert_eq!(constant(&module, "PT_IM_LEAD_TOL"), vec![shapes::roots::LEAD_TOL]);
    let uses_f64 = |m: &naga::Module| {
        m.types.iter().any(|(_, t)| matches!(t.inner, TypeInner::Scalar(s) | TypeInner::Vector { scalar: s, .. } if s == naga::Scalar::F64))
    };
    assert!(uses_f64(&module));
    let (without, module) = kernel_module(&options(bvh::TriangleTest::Watertight));
    assert!(!without.contains("// ---- implicit.wgsl") && !uses_f64(&module));
}

/// An implicit surface's coefficients travel in the f32 tables as 2^e times three f32 whose
/// sum in f64 is the mantissa, exactly: checked over 40 orders of magnitude each way.
#[test]
fn f64_coefficients_split_into_f32_parts_exactly() {
    let mut rng = rng::Pcg32::seed_from_u64(64);
    for k in 0..20_000 {
        let x = (rng.next_f64() - 0.5) * 10f64.powi(k % 81 - 40);
        let (e, [a, b, c]) = gpu::backend::split_f64(x);
        let m = a as f64 + b as f64 + c as f64;
        assert!(x == 0.0 || (1.0..2.0).contains(&m.abs()), "{x}: mantissa {m}");
        assert_eq!(m * 2f64.powi(e), x, "{x} = 2^{e} · ({a} + {b} + {c})");
    }
    assert_eq!(gpu::backend::split_f64(0.0), (0, [0.0; 3]));
}

/// The wavefront's stages are in the kernel only where asked for, validate, and its path
/// state has the size the host allocates per path.
#[test]
fn the_wavefront_kernel_validates_and_its_paths_have_the_host_size() {
    let stages = ["pt_wf_begin", "pt_wf_camera", "pt_wf_extend", "pt_wf_shade", "pt_wf_shadow", "pt_wf_next"];
    let with =
        KernelOptions { wavefront: true, mode: spectral::SpectralMode::Hero, ..options(bvh::TriangleTest::Watertight) };
    let (src, module) = kernel_module(&with);
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
        .validate(&module)
        .unwrap();
    for stage in stages.iter().chain(&["pt_wf_film", "pt_wf_end"]) {
        assert!(module.entry_points.iter().any(|e| e.name == *stage), "{stage}");
        // Each stage as Vulkan gets it: naga's SPIR-V writer once panicked on the shading
        // stage (a pointer into a local struct) where validation passed.
        let pipeline = naga::back::spv::PipelineOptions {
            shader_stage: naga::ShaderStage::Compute,
            entry_point: stage.to_string(),
        };
        let spv = naga::back::spv::write_vec(&module, &info, &Default::default(), Some(&pipeline));
        assert!(spv.is_ok_and(|words| !words.is_empty()), "{stage}");
    }
    assert!(src.contains("// ---- wavefront.wgsl"));
    let (_, size) = wgsl_layout(&module, "PtWfPath");
    assert_eq!(size as u64, gpu::wavefront::PATH_BYTES);
    assert_eq!(constant(&module, "PT_WF_GROUP"), vec![gpu::wavefront::GROUP as f64]);
    let (members, _) = wgsl_layout(&module, "PtWfControl");
    assert_eq!(members.last(), Some(&("queue".to_string(), 16)), "the queues follow a 16-byte header");
    let (without, module) = kernel_module(&KernelOptions { mode: spectral::SpectralMode::Hero, ..with_off(&with) });
    assert!(!without.contains("// ---- wavefront.wgsl"));
    assert!(module.entry_points.iter().all(|e| !e.name.starts_with("pt_wf_")));
}

fn with_off(options: &KernelOptions) -> KernelOptions {
    KernelOptions { wavefront: false, ..*options }
}

#[test]
fn only_the_chosen_triangle_test_is_compiled_in() {
    let (wt, _) = kernel_module(&options(bvh::TriangleTest::Watertight));
    let (mt, _) = kernel_module(&options(bvh::TriangleTest::MollerTrumbore));
    assert!(wt.contains("The watertight test against") && !wt.contains("Möller–Trumbore against"));
    assert!(mt.contains("Möller–Trumbore against") && !mt.contains("The watertight test against"));
}

/// Every hand-written WGSL file (the kernel's and the BSDF models') says in its first
/// lines which Rust file it mirrors, and that file exists.
#[test]
fn every_wgsl_file_names_the_rust_file_it_mirrors() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    for dir in ["crates/gpu/src/wgsl", "crates/brdf/src", "crates/brdf/src/models"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "wgsl") {
                files.push(p);
            }
        }
    }
    assert!(files.len() >= 20, "{} WGSL files", files.len());
    let mut problems = Vec::new();
    for p in &files {
        let text = std::fs::read_to_string(p).unwrap();
        let header: String = text.lines().take_while(|l| l.starts_with("//")).collect::<Vec<_>>().join(" ");
        let named: Vec<&str> = header
            .split(|c: char| c.is_whitespace() || "(),`;".contains(c))
            .map(|w| w.trim_end_matches(['.', ':']))
            .filter(|w| w.starts_with("crates/") && w.ends_with(".rs"))
            .collect();
        if named.is_empty() {
            problems.push(format!("{}: no crates/…/*.rs named in its header", p.display()));
        }
        for n in named {
            if !root.join(n).exists() {
                problems.push(format!("{}: names {n}, which does not exist", p.display()));
            }
        }
    }
    assert!(problems.is_empty(), "{problems:#?}");
}
