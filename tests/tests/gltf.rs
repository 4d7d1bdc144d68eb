//! The same scene as OBJ + MTL and as glTF renders the same image.
//!
//! The Cornell box's MTL, given the PBR extension's `Pr 1` / `Pm 0`, loads as glTF's
//! metallic–roughness material; this test writes that scene out as a glTF file (one
//! primitive per run of triangles sharing a material, positions in an external `.bin`,
//! the light as `emissiveFactor`, each `Ni` as `KHR_materials_ior`) with its own code —
//! not the loader's — and checks that the glTF loader gives back the same triangles and
//! materials and that both scenes render the same bytes.

use serde_json::json;
use std::path::{Path, PathBuf};
use tracer::gltf_scene::{GltfOptions, load_gltf};
use tracer::material::ModelParams;
use tracer::{Camera, CpuBackend, RenderSettings, Scene, SceneOptions, SpectralMode};

fn cornell_obj() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes/cornell-box/CornellBox-Original.obj");
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: {} is absent", p.display());
        None
    }
}

/// The Cornell box with every material turned into the metallic–roughness model by the
/// MTL's PBR statements, in a temporary directory.
fn pbr_cornell(dir: &Path) -> Option<Scene> {
    let obj = cornell_obj()?;
    let mtl = std::fs::read_to_string(obj.with_extension("mtl")).unwrap();
    let mtl = mtl.replace("newmtl", "Pr 1\nPm 0\nnewmtl").replacen("Pr 1\nPm 0\n", "", 1) + "Pr 1\nPm 0\n";
    std::fs::write(dir.join("CornellBox-Original.mtl"), mtl).unwrap();
    std::fs::copy(&obj, dir.join("CornellBox-Original.obj")).unwrap();
    Some(tracer::obj::load_obj(&dir.join("CornellBox-Original.obj")).unwrap())
}

/// Writes `scene` (triangles, metallic–roughness materials, emission) as `name.gltf` +
/// `name.bin` in `dir`: one non-indexed primitive per run of equal material ids.
fn write_gltf(scene: &Scene, dir: &Path, name: &str) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    let (mut accessors, mut views, mut primitives, mut materials) = (vec![], vec![], vec![], vec![]);
    let mut start = 0;
    while start < scene.triangles.len() {
        let id = scene.material_ids[start];
        let end =
            (start..scene.triangles.len()).find(|&t| scene.material_ids[t] != id).unwrap_or(scene.triangles.len());
        let offset = bin.len();
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for t in start..end {
            for v in scene.triangle_vertices(t) {
                for k in 0..3 {
                    bin.extend_from_slice(&v[k].to_le_bytes());
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
        }
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset}));
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126,
            "count": 3 * (end - start), "type": "VEC3", "min": lo, "max": hi}));
        let m = &scene.materials[id as usize];
        let Some(ModelParams::MetallicRoughness(p)) = m.params() else {
            panic!("{}: not metallic–roughness", m.name)
        };
        let [r, g, b] = p.base_color.rgb;
        let mut material = json!({"name": m.name, "pbrMetallicRoughness": {"baseColorFactor": [r, g, b, 1.0],
            "metallicFactor": p.metallic, "roughnessFactor": p.roughness},
            "extensions": {"KHR_materials_ior": {"ior": p.ior}}});
        if let Some(e) = &m.emission {
            let peak = e.rgb.iter().cloned().fold(0.0f32, f32::max);
            material["emissiveFactor"] = json!(e.rgb.map(|c| c / peak));
            material["extensions"]["KHR_materials_emissive_strength"] = json!({"emissiveStrength": peak});
        }
        materials.push(material);
        primitives.push(json!({"attributes": {"POSITION": accessors.len() - 1}, "material": materials.len() - 1}));
        start = end;
    }
    let doc = json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": primitives}], "materials": materials, "accessors": accessors,
        "bufferViews": views, "buffers": [{"byteLength": bin.len(), "uri": format!("{name}.bin")}],
        "extensionsUsed": ["KHR_materials_ior", "KHR_materials_emissive_strength"],
    });
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    path
}

fn render(scene: Scene) -> tracer::Film {
    let prepared = CpuBackend::new(2).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap();
    let settings = RenderSettings {
        width: 48,
        height: 48,
        spp: 16,
        mode: SpectralMode::Hero,
        camera: Some(Camera {
            eye: glam::Vec3::new(0.0, 1.0, 3.9),
            center: glam::Vec3::new(0.0, 1.0, 0.0),
            up: glam::Vec3::Y,
            fov_y_deg: tracer::camera::DEFAULT_FOV_Y_DEG,
        }),
        ..Default::default()
    };
    tracer::render(&prepared, &settings, &|_| {}).unwrap().0
}

#[test]
fn the_cornell_box_as_gltf_renders_as_it_does_from_obj() {
    let dir = std::env::temp_dir().join(format!("spt-gltf-cornell-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let Some(obj) = pbr_cornell(&dir) else { return };
    assert!(obj.materials.iter().all(|m| matches!(m.params(), Some(ModelParams::MetallicRoughness(_)))));
    let path = write_gltf(&obj, &dir, "cornell");
    let loaded = load_gltf(&path, &GltfOptions::default()).unwrap();
    assert!(loaded.notes.is_empty(), "{:?}", loaded.notes);
    let gltf = loaded.scene;
    assert_eq!(gltf.triangles.len(), obj.triangles.len());
    for t in 0..obj.triangles.len() {
        assert_eq!(gltf.triangle_vertices(t), obj.triangle_vertices(t), "triangle {t}");
        let (a, b) = (&gltf.materials[gltf.material_ids[t] as usize], &obj.materials[obj.material_ids[t] as usize]);
        assert_eq!(a.name, b.name);
        assert_eq!(format!("{:?}", a.params()), format!("{:?}", b.params()), "{}", a.name);
        assert_eq!(a.emission.as_ref().map(|e| e.rgb), b.emission.as_ref().map(|e| e.rgb), "{}", a.name);
    }
    let (a, b) = (render(gltf), render(obj));
    let means = a.channel_means();
    assert!(means.iter().all(|&m| m > 0.01 && m.is_finite()), "{means:?}");
    assert_eq!(a.mean_rgb(), b.mean_rgb(), "the glTF and OBJ renders differ");
    std::fs::remove_dir_all(&dir).ok();
}
