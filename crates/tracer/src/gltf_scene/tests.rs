//! Tests of `gltf_scene.rs`: the shared glTF models, and small files written here.

use super::*;
use crate::material::ModelParams;

const SCENES: &str = "../../../shared/scenes";

fn shared(rel: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENES).join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: {} is absent", p.display());
        None
    }
}

/// Standard base64 (RFC 4648) for data URIs.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A glTF with one triangle (0,0,0), (1,0,0), (0,1,0) facing +z, indexed, in a data URI;
/// `nodes`, `extra` (more top-level members) and the material are the caller's.
fn triangle_gltf(nodes: &str, material: &str, extra: &str) -> String {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":{nodes},
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
        "materials":[{material}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
        "buffers":[{{"byteLength":44,"uri":"data:application/octet-stream;base64,{}"}}]{extra}}}"#,
        base64(&bin)
    )
}

fn load_text(text: &str, options: &GltfOptions) -> Result<GltfScene> {
    load_gltf_bytes(text.as_bytes(), Path::new("t/s.gltf"), options, &|p| {
        Err(std::io::Error::new(std::io::ErrorKind::NotFound, format!("{} not here", p.display())))
    })
}

fn load(text: &str) -> Result<GltfScene> {
    load_text(text, &GltfOptions::default())
}

#[test]
fn the_box_loads_the_same_from_gltf_and_glb() {
    let (Some(gltf), Some(glb)) = (shared("gltf-box/Box.gltf"), shared("gltf-box/Box.glb")) else { return };
    let a = load_gltf(&gltf, &GltfOptions::default()).unwrap();
    let b = load_gltf(&glb, &GltfOptions::default()).unwrap();
    assert_eq!(a.scene.triangles.len(), 12);
    assert_eq!(a.scene.positions, b.scene.positions);
    assert_eq!(a.scene.triangles, b.scene.triangles);
    // The root's matrix turns y into z; the box stays the unit cube about the origin.
    let bounds = a.scene.bounds();
    assert!((bounds.min + Vec3::splat(0.5)).abs().max_element() < 1e-6, "{bounds:?}");
    assert!((bounds.max - Vec3::splat(0.5)).abs().max_element() < 1e-6, "{bounds:?}");
    // Normals point out of the box (away from its centre) after the transform.
    for (p, n) in a.scene.positions.iter().zip(&a.scene.normals) {
        assert!(Vec3::from_array(*p).dot(Vec3::from_array(*n)) > 0.0, "{p:?} {n:?}");
    }
    // Its one material: a red-brown dielectric-ish metallic–roughness.
    let Some(ModelParams::MetallicRoughness(p)) = a.scene.materials[0].params() else { unreachable!() };
    assert_eq!(p.metallic, 0.0);
    assert!(a.scene.camera.is_none() && a.scene.punctual_lights.is_empty());
    assert!(a.scene.uvs.is_empty(), "the box has no texture coordinates");
}

#[test]
fn every_shared_model_converts_with_its_triangle_count() {
    for (rel, triangles) in [
        ("gltf-suzanne/Suzanne.gltf", 3936),
        ("gltf-damaged-helmet/DamagedHelmet.glb", 15452),
        ("gltf-transmission-test/TransmissionTest.glb", 128_775),
    ] {
        let Some(path) = shared(rel) else { continue };
        let s = load_gltf(&path, &GltfOptions::default()).unwrap();
        assert_eq!(s.scene.triangles.len(), triangles, "{rel}");
        // Each has TEXCOORD_0: one coordinate per vertex, finite.
        assert_eq!(s.scene.uvs.len(), s.scene.positions.len(), "{rel}");
        // … and textures, each image decoded once.
        let (images, bytes) = s.scene.texture_images();
        assert!(images >= 2 && bytes > 0, "{rel}: {images} images");
        if rel.contains("Transmission") {
            assert!(
                s.scene
                    .materials
                    .iter()
                    .any(|m| matches!(m.model(), Some(ModelId::Dielectric | ModelId::RoughDielectric))),
                "{rel}"
            );
        }
    }
}

#[test]
fn world_transforms_place_and_mirror_the_mesh() {
    // Translated by (0, 0, 5) under a parent that mirrors x: the triangle lands at
    // x ≤ 0, z = 5, and its winding is reversed so that its front still faces +z.
    let nodes = r#"[{"scale":[-1,1,1],"children":[1]},{"translation":[0,0,5],"mesh":0}]"#;
    let s = load(&triangle_gltf(nodes, "{}", "")).unwrap().scene;
    let [a, b, c] = s.triangle_vertices(0);
    assert_eq!([a, b, c].map(|v| v.z), [5.0; 3]);
    assert!([a, b, c].iter().all(|v| v.x <= 0.0));
    assert!((b - a).cross(c - a).z > 0.0, "the front must face +z: {a} {b} {c}");
    // Unmirrored, the same winding as in the file.
    let s = load(&triangle_gltf(r#"[{"mesh":0}]"#, "{}", "")).unwrap().scene;
    assert_eq!(s.triangles, [[0, 1, 2]]);
}

#[test]
fn materials_map_to_models_and_lights() {
    let glass = r#"{"name":"glass","pbrMetallicRoughness":{"baseColorFactor":[1,0.9,0.8,1],"roughnessFactor":0,"metallicFactor":0},
        "extensions":{"KHR_materials_transmission":{"transmissionFactor":1},"KHR_materials_ior":{"ior":1.33},
        "KHR_materials_volume":{"attenuationDistance":2,"attenuationColor":[0.5,1,1]}}}"#;
    let ext = r#","extensionsUsed":["KHR_materials_transmission","KHR_materials_ior","KHR_materials_volume"]"#;
    let s = load(&triangle_gltf(r#"[{"mesh":0}]"#, glass, ext)).unwrap().scene;
    let Some(ModelParams::Dielectric(p)) = s.materials[0].params() else { panic!("{:?}", s.materials[0]) };
    assert_eq!(p.ior, 1.33);
    assert_eq!(p.tint.rgb, [1.0, 0.9, 0.8]);
    // σ = −ln(0.5)/2 in red, 0 elsewhere.
    let sigma = p.absorption.rgb;
    assert!((sigma[0] - std::f32::consts::LN_2 / 2.0).abs() < 1e-6 && sigma[1] == 0.0, "{sigma:?}");
    // Transmission applies to the dielectric part: at glTF's default metallic = 1 the
    // surface is a metal.
    let metal = glass.replace(r#","metallicFactor":0"#, "");
    let s = load(&triangle_gltf(r#"[{"mesh":0}]"#, &metal, ext)).unwrap().scene;
    assert_eq!(s.materials[0].model(), Some(ModelId::MetallicRoughness));

    let lamp = r#"{"name":"lamp","emissiveFactor":[1,0.5,0.25],
        "extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}}}"#;
    let ext = r#","extensionsUsed":["KHR_materials_emissive_strength"]"#;
    let s = load(&triangle_gltf(r#"[{"mesh":0}]"#, lamp, ext)).unwrap().scene;
    assert_eq!(s.materials[0].emission.as_ref().map(|e| e.rgb), Some([4.0, 2.0, 1.0]));
    // glTF's defaults: white, fully metallic, fully rough.
    let Some(ModelParams::MetallicRoughness(p)) = s.materials[0].params() else { unreachable!() };
    assert_eq!((p.base_color.rgb, p.metallic, p.roughness, p.ior), ([1.0; 3], 1.0, 1.0, 1.5));
}

#[test]
fn cameras_and_punctual_lights_are_placed_by_their_nodes() {
    // Camera 0 ("side") at (3, 0, 0) turned +90° about y (looking along −x); camera 1
    // ("front") at (0, 0, 4) looking along −z. A spot at (0, 2, 0) pointing down
    // (rotated −90° about x), a sun and a point light.
    let s = (0.5f32).sqrt();
    let nodes = format!(
        r#"[{{"mesh":0,"children":[1,2,3,4,5]}},
        {{"camera":0,"translation":[3,0,0],"rotation":[0,{s},0,{s}]}},
        {{"camera":1,"translation":[0,0,4]}},
        {{"translation":[0,2,0],"rotation":[-{s},0,0,{s}],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}},
        {{"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}},
        {{"translation":[1,1,1],"extensions":{{"KHR_lights_punctual":{{"light":2}}}}}}]"#
    );
    let extra = r#","cameras":[
        {"name":"side","type":"perspective","perspective":{"yfov":0.5,"znear":0.1}},
        {"name":"front","type":"perspective","perspective":{"yfov":1.0,"znear":0.1,"aspectRatio":1.5}}],
      "extensionsUsed":["KHR_lights_punctual"],
      "extensions":{"KHR_lights_punctual":{"lights":[
        {"type":"spot","color":[1,1,1],"intensity":10,"spot":{"innerConeAngle":0.2,"outerConeAngle":0.4}},
        {"type":"directional","intensity":3},
        {"type":"point","color":[1,0,0],"intensity":2,"range":5}]}}"#;
    let text = triangle_gltf(&nodes, "{}", extra);
    let g = load(&text).unwrap();
    assert_eq!(g.cameras.len(), 2);
    let side = g.scene.camera.unwrap();
    assert!((side.eye - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-6);
    assert!(((side.center - side.eye) - Vec3::NEG_X).length() < 1e-6, "{side:?}");
    assert!((side.fov_y_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    for wanted in ["1", "front"] {
        let front = load_text(&text, &GltfOptions { camera: Some(wanted.into()) }).unwrap().scene.camera.unwrap();
        assert_eq!(front.eye, Vec3::new(0.0, 0.0, 4.0));
        assert!(((front.center - front.eye) - Vec3::NEG_Z).length() < 1e-6);
    }
    let e = load_text(&text, &GltfOptions { camera: Some("top".into()) }).unwrap_err().to_string();
    assert!(e.contains("no camera 'top'") && e.contains("0 (side), 1 (front)"), "{e}");

    let lights = &g.scene.punctual_lights;
    assert_eq!(lights.len(), 3);
    match &lights[0] {
        PunctualLight::Spot { position, direction, intensity, cos_inner, cos_outer } => {
            assert!((*position - Vec3::new(0.0, 2.0, 0.0)).length() < 1e-6);
            assert!((*direction - Vec3::NEG_Y).length() < 1e-6, "{direction}");
            assert_eq!(intensity.rgb, [10.0; 3]);
            assert!((cos_inner - 0.2f32.cos()).abs() < 1e-6 && (cos_outer - 0.4f32.cos()).abs() < 1e-6);
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(&lights[1], PunctualLight::Directional { direction, irradiance, cos_radius: 1.0 }
        if *direction == Vec3::NEG_Z && irradiance.rgb == [3.0; 3]));
    assert!(matches!(&lights[2], PunctualLight::Point { position, intensity }
        if *position == Vec3::ONE && intensity.rgb == [2.0, 0.0, 0.0]));
    assert!(g.notes.iter().any(|n| n.contains("range")), "{:?}", g.notes);
}

#[test]
fn strips_and_fans_triangulate_with_consistent_winding() {
    use gltf::mesh::Mode;
    assert_eq!(triangulate(Mode::TriangleStrip, &[0, 1, 2, 3, 4]), [[0, 1, 2], [2, 1, 3], [2, 3, 4]]);
    assert_eq!(triangulate(Mode::TriangleFan, &[0, 1, 2, 3]), [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(triangulate(Mode::Triangles, &[0, 1, 2, 3, 3, 4, 5]), [[0, 1, 2]]);
    assert_eq!(percent_decode("a%20b%2Fc%zz%4"), "a b/c%zz%4");
}

#[test]
fn bad_files_are_errors_that_say_what_is_wrong() {
    let ok = triangle_gltf(r#"[{"mesh":0}]"#, "{}", "");
    let cases: Vec<(String, &str)> = vec![
        ("{".into(), "not a valid glTF file"),
        ("glTF\u{2}\0\0\0\u{ff}\0\0\0".into(), "not a valid glTF file"),
        (ok.replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":7}]"#), "not a valid glTF file"),
        (ok.replace("data:application/octet-stream;base64,", "missing.bin#"), "buffer 0: cannot read t/missing.bin#"),
        (ok.replace(r#""byteLength":44"#, r#""byteLength":4400"#), "declares 4400"),
        (ok.replace(r#""scene":0,"scenes":[{"nodes":[0]}]"#, r#""scenes":[]"#), "no scene"),
        (
            ok.replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"children":[1]},{"children":[0],"mesh":0}]"#),
            "nodes[0] is reached twice",
        ),
        (
            ok.replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"children":[1,2]},{"children":[2]},{"mesh":0}]"#),
            "nodes[2] is reached twice",
        ),
        (ok.replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"scale":[1e38,1e38,1e38],"children":[1]},{"mesh":0,"scale":[1e38,1,1]}]"#), "not finite"),
        (ok.replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"camera":0,"mesh":0}],"cameras":[{"type":"orthographic","orthographic":{"xmag":1,"ymag":1,"znear":0,"zfar":1}}]"#), ""),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        match load(text) {
            Ok(s) if i == cases.len() - 1 => {
                // An orthographic camera loads (with a note) but cannot be chosen.
                assert!(s.notes.iter().any(|n| n.contains("orthographic")), "{:?}", s.notes);
                let e = load_text(text, &GltfOptions { camera: Some("0".into()) }).unwrap_err().to_string();
                assert!(e.contains("orthographic"), "{e}");
            }
            Ok(_) => panic!("case {i} loaded: {text}"),
            Err(e) => {
                let e = e.to_string();
                assert!(e.starts_with("t/s.gltf: ") && e.contains(needle), "case {i}: {e}");
            }
        }
    }
    // What the fuzzer found the gltf crate panicking on, each now an error.
    for (from, to, needle) in [
        (r#""POSITION":0"#, r#""POSITION":9"#, "accessor 9 does not exist"),
        (r#""byteLength":36}"#, r#""byteLength":36,"byteStride":8}"#, "byteStride 8 is less than the element size 12"),
        (r#""componentType":5123"#, r#""componentType":5126"#, "indices must be unsigned integer scalars"),
        (r#""type":"VEC3","min""#, r#""type":"VEC4","min""#, "Positions must be VEC3 of 32-bit floats, not Vec4"),
        (r#""count":3,"type":"VEC3""#, r#""count":4,"type":"VEC3""#, "4 elements overrun bufferView 0 (36 bytes)"),
    ] {
        assert!(ok.contains(from), "{from}");
        let e = load(&ok.replace(from, to)).unwrap_err().to_string();
        assert!(e.contains(needle) && !e.contains("panicked"), "{to}: {e}");
    }
    // Indices past the vertices.
    let bad = ok.replace(
        r#""count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]"#,
        r#""count":2,"type":"VEC3","min":[0,0,0],"max":[1,0,0]"#,
    );
    let e = load(&bad).unwrap_err().to_string();
    assert!(e.contains("index 2 is out of range (2 vertices)"), "{e}");
}

#[test]
fn every_truncation_of_a_binary_gltf_is_an_error() {
    let Some(path) = shared("gltf-box/Box.glb") else { return };
    let bytes = std::fs::read(path).unwrap();
    for len in 0..bytes.len() {
        let r = load_gltf_bytes(&bytes[..len], Path::new("b.glb"), &GltfOptions::default(), &|_| {
            Err(std::io::ErrorKind::NotFound.into())
        });
        assert!(r.is_err(), "{len} of {} bytes loaded", bytes.len());
    }
}

#[test]
fn a_mesh_placed_by_several_nodes_is_instanced_not_copied() {
    // Node 0 places the mesh and has children placing it twice more (one mirrored); a
    // fourth node places it with a singular scale, which shows nothing.
    let nodes = r#"[{"mesh":0,"children":[1,2,3]},{"mesh":0,"translation":[2,0,0]},
        {"mesh":0,"scale":[-1,1,1]},{"mesh":0,"scale":[0,1,1]}]"#;
    let s = load_text(&triangle_gltf(nodes, r#"{"name":"m"}"#, ""), &GltfOptions::default()).unwrap().scene;
    assert!(s.triangles.is_empty(), "no copies in the flat arrays");
    assert_eq!((s.objects.len(), s.instances.len(), s.objects[0].triangles.len()), (1, 3, 1));
    assert_eq!(s.materials.len(), 1);
    s.validate().unwrap();
    let b = s.bounds();
    assert_eq!((b.min.x, b.max.x), (-1.0, 3.0));
    // Flattened, the same three triangles, the mirrored one rewound to face +z still.
    let mut flat = s.clone();
    flat.flatten_instances();
    assert_eq!(flat.triangles.len(), 3);
    for i in 0..3 {
        let v = flat.triangle_vertices(i);
        assert!((v[1] - v[0]).cross(v[2] - v[0]).z > 0.0, "triangle {i} faces away");
    }
}
