//! Tests of `scene_file.rs`.

use super::*;
use crate::material::ModelParams;

/// A temporary directory with a one-triangle OBJ (`tri.obj`, front facing +z, its own
/// material `red`) and the scene `text` as `scene.toml`; returns the scene's path.
fn write(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("spt-scene-file-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.mtl"), "newmtl red\nKd 0.8 0.1 0.1\n").unwrap();
    std::fs::write(dir.join("tri.obj"), "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n").unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

const FULL: &str = r#"
[camera]
eye = [0, 1, 5]
center = [0, 1, 0]
fov = 45

[materials.gold]
model = "roughconductor"
metal = "gold"
alpha = 0.2

[materials.lamp]
model = "lambert"
reflectance = 0
emission = [4, 3, 2]

[materials.glass]
model = "dielectric"
ior = 1.33

[[mesh]]
file = "tri.obj"
scale = 2
rotate = { axis = [0, 1, 0], degrees = 90 }
translate = [0, 0, -1]

[[mesh]]
file = "tri.obj"
material = "gold"
scale = [-1, 1, 1]

[[shape]]
type = "sphere"
center = [0, 3, 0]
radius = 0.25
material = "lamp"

[[shape]]
type = "box"
min = [-1, 0, -1]
max = [-0.5, 0.5, -0.5]
material = "gold"

[[shape]]
type = "polygon"
vertices = [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]
material = "gold"

[[shape]]
type = "implicit"
expression = "x^2 + y^2 + z^2 - 0.25"
min = [-0.5, -0.5, -0.5]
max = [0.5, 0.5, 0.5]
material = "glass"

[[light]]
type = "point"
position = [1, 2, 3]
intensity = 5

[[light]]
type = "spot"
position = [0, 4, 0]
direction = [0, -1, 0]
inner = 10
outer = 20
intensity = [1, 2, 3]

[[light]]
type = "sun"
direction = [-1, -2, -1]
irradiance = 3

[sky]
radiance = [0.1, 0.2, 0.3]
"#;

#[test]
fn a_scene_file_places_everything_it_names() {
    let s = load_scene_file(&write("full", FULL)).unwrap();
    // Materials: the three declared (sorted by name), then the first OBJ's own.
    let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["glass", "gold", "lamp", "red"]);
    assert_eq!(s.materials[2].emission.as_ref().map(|e| e.rgb), Some([4.0, 3.0, 2.0]));
    let Some(ModelParams::RoughConductor(gold)) = s.materials[1].params() else { unreachable!() };
    assert_eq!(gold.alpha, 0.2);
    // The OBJ is named twice: one object, two instances; copied out, the first triangle
    // is scaled by 2, turned 90° about y ((x, y, z) → (z, y, −x)), moved to z − 1; the
    // second mirrored in x, its winding reversed, in gold.
    assert_eq!((s.triangles.len(), s.objects.len(), s.instances.len()), (0, 1, 2));
    let mut s = s;
    s.flatten_instances();
    assert_eq!(s.triangles.len(), 2);
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    let [a, b, c] = s.triangle_vertices(0);
    assert!(close(a, Vec3::new(0.0, 0.0, -1.0)) && close(b, Vec3::new(0.0, 0.0, -3.0)), "{a} {b}");
    assert!(close(c, Vec3::new(0.0, 2.0, -1.0)), "{c}");
    let [a, b, c] = s.triangle_vertices(1);
    assert!((b - a).cross(c - a).z > 0.0, "the mirrored triangle's front must still face +z");
    assert_eq!(s.material_ids, [3, 1]);
    let kinds: Vec<&str> = s.shapes.iter().map(|x| x.shape.name()).collect();
    assert_eq!(kinds, ["sphere", "box", "polygon", "implicit surface"]);
    assert_eq!(s.shapes.iter().map(|x| x.material).collect::<Vec<_>>(), [2, 1, 1, 0]);
    assert_eq!(s.punctual_lights.len(), 3);
    assert!(
        matches!(&s.punctual_lights[1], PunctualLight::Spot { cos_outer, .. } if (cos_outer - 20f32.to_radians().cos()).abs() < 1e-6)
    );
    assert_eq!(s.environment.as_ref().map(|e| e.radiance.rgb), Some([0.1, 0.2, 0.3]));
    let camera = s.camera.unwrap();
    assert_eq!((camera.eye, camera.fov_y_deg), (Vec3::new(0.0, 1.0, 5.0), 45.0));
}

#[test]
fn the_cornell_box_through_a_scene_file_is_the_obj() {
    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/cornell-box/CornellBox-Original.obj");
    if !obj.exists() {
        eprintln!("skipped: {} is absent", obj.display());
        return;
    }
    let text = format!("[[mesh]]\nfile = {:?}\n", obj.to_str().unwrap());
    let from_file = parse_scene_file(&text, Path::new("/elsewhere/scene.toml")).unwrap();
    let direct = load_obj(&obj).unwrap();
    assert_eq!(from_file.positions, direct.positions);
    assert_eq!(from_file.triangles, direct.triangles);
    assert_eq!(from_file.material_ids, direct.material_ids);
    assert_eq!(format!("{:?}", from_file.materials), format!("{:?}", direct.materials));
}

#[test]
fn errors_name_the_line_and_column_of_what_is_wrong() {
    for (text, line_col, needle) in [
        ("[camera]\neye = [0, 1, 5]\ncentre = [0, 0, 0]\n", "scene.toml:3:1: ", "unknown field `centre`"),
        ("[[shape]]\ntype = \"cone\"\n", "scene.toml:", "unknown variant `cone`"),
        ("[materials.a]\nmodel = \"velvet\"\n", "scene.toml:2:9: ", "unknown model 'velvet'"),
        ("[materials.a]\nmodel = \"schlick\"\nroughness = 1.5\n", "scene.toml:3:13: ", "roughness = 1.5"),
        ("[materials.a]\nreflectance = 0.5\n", "scene.toml:1:1: ", "material 'a': needs a model"),
        (
            "[materials.a]\nmodel = \"lambert\"\n\n[[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"b\"\n",
            "scene.toml:4:1: ",
            "no material 'b' (defined: a)",
        ),
        (
            "[materials.a]\nmodel = \"lambert\"\n[[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\nmaterial = \"a\"\n",
            "scene.toml:3:1: ",
            "radius",
        ),
        ("[[mesh]]\nfile = \"tri.obj\"\nscale = 0\n", "scene.toml:1:1: ", "scale"),
        ("[[mesh]]\nfile = \"tri.png\"\n", "scene.toml:1:1: ", "meshes are .obj, .gltf or .glb files"),
        (
            "[[light]]\ntype = \"point\"\nposition = [0, 0, 0]\nintensity = -1\n",
            "scene.toml:1:1: ",
            "non-negative, got -1",
        ),
        ("[camera]\neye = [0, 0, 0]\ncenter = [0, 0, 0]\n", "scene.toml:1:1: ", "eye and center coincide"),
        ("[sky]\nradiance = \"blue\"\n", "scene.toml:2:12: ", "did not match any variant"),
        ("sky = 3 3\n", "scene.toml:1:7: ", "expected"),
    ] {
        let path = write("errors", text);
        let e = load_scene_file(&path).unwrap_err().to_string();
        let shown =
            e.strip_prefix(&format!("{}", path.parent().unwrap().display())).unwrap_or(&e).trim_start_matches('/');
        assert!(shown.starts_with(line_col) && shown.contains(needle), "{text}\n→ {e}");
    }
    // A missing mesh file names itself.
    let e = load_scene_file(&write("missing", "[[mesh]]\nfile = \"gone.obj\"\n")).unwrap_err().to_string();
    assert!(e.contains("gone.obj") && e.to_lowercase().contains("no such file"), "{e}");
}

#[test]
fn colours_can_be_spectra_by_name_black_body_table_or_spec_file() {
    let path = write("spectra", "");
    let dir = path.parent().unwrap();
    std::fs::write(dir.join("m.spec"), r#"{ "spectra": { "golden": { "400": 0.3, "700": 0.9 } } }"#).unwrap();
    let text = r#"
[materials.tabled]
model = "lambert"
reflectance = { table = { "400" = 0.2, "700" = 0.6 } }

[materials.golden]
model = "lambert"
reflectance = { spd = "golden", file = "m.spec", scale = 0.5 }

[materials.warm]
model = "lambert"
reflectance = 0
emission = { blackbody = 3000, scale = 5 }

[[light]]
type = "point"
position = [0, 2, 0]
intensity = { spectrum = "A", scale = 2 }

[sky]
radiance = { spectrum = "D65", scale = 0.5 }
"#;
    std::fs::write(&path, text).unwrap();
    let s = load_scene_file(&path).unwrap();
    let reflectance = |i: usize| match s.materials[i].params() {
        Some(ModelParams::Lambert(p)) => p.reflectance.spectrum.clone(),
        other => panic!("{other:?}"),
    };
    // Sorted by name: golden, tabled, warm.
    assert!((reflectance(0).eval(550.0) - 0.5 * 0.6).abs() < 1e-6, "{}", reflectance(0).eval(550.0));
    assert!((reflectance(1).eval(550.0) - 0.4).abs() < 1e-6);
    let warm = s.materials[2].emission.as_ref().unwrap();
    assert_eq!(warm.spectrum, Spectrum::Blackbody { kelvin: 3000.0, scale: 5.0 });
    // A 3000 K black body is reddish: its sRGB value has more red than blue.
    assert!(warm.rgb[0] > 2.0 * warm.rgb[2], "{:?}", warm.rgb);
    assert!(matches!(&s.punctual_lights[0], PunctualLight::Point { intensity, .. }
        if (intensity.spectrum.eval(560.0) - 2.0).abs() < 1e-4));
    assert_eq!(s.environment.as_ref().unwrap().radiance.spectrum, Spectrum::D65(0.5));
    for (bad, needle) in [
        ("[sky]\nradiance = { spectrum = \"F13\" }\n", "unknown spectrum 'F13'"),
        ("[sky]\nradiance = { spectrum = \"D65\", blackbody = 5000 }\n", "exactly one of"),
        ("[sky]\nradiance = { spd = \"golden\" }\n", "spd and file go together"),
        ("[sky]\nradiance = { spd = \"silver\", file = \"m.spec\" }\n", "no spectrum 'silver' (defined: golden)"),
        (
            "[materials.a]\nmodel = \"lambert\"\nreflectance = { table = { \"blue\" = 0.5 } }\n",
            "'blue' is not a wavelength",
        ),
        ("[materials.a]\nmodel = \"lambert\"\nreflectance = { colour = 1 }\n", "unknown field `colour`"),
    ] {
        std::fs::write(&path, bad).unwrap();
        let e = load_scene_file(&path).unwrap_err().to_string();
        assert!(e.contains(needle), "{bad}\n→ {e}");
    }
}

#[test]
fn set_overrides_change_values_by_dotted_path() {
    let text = FULL;
    let edited = apply_overrides(
        text,
        &[
            "materials.gold.alpha=0.35".into(),
            "shape.0.radius=0.4".into(),
            "camera.fov = 30".into(),
            "materials.gold.metal=silver".into(),
            "sky.radiance=[0.5, 0.5, 0.5]".into(),
            "materials.new.model=\"lambert\"".into(),
        ],
    )
    .unwrap();
    // The meshes resolve against the scene file's directory: load it from there.
    let s = load_scene_file(&write("overrides", &edited)).unwrap();
    let gold = s.materials.iter().find(|m| m.name == "gold").unwrap();
    let Some(ModelParams::RoughConductor(p)) = gold.params() else { unreachable!() };
    assert_eq!((p.alpha, p.metal.name()), (0.35, "silver"));
    assert!(s.materials.iter().any(|m| m.name == "new"));
    assert_eq!(s.camera.unwrap().fov_y_deg, 30.0);
    assert_eq!(s.environment.unwrap().radiance.rgb, [0.5; 3]);
    let ShapeKind::Sphere(sphere) = &s.shapes[0].shape else { unreachable!() };
    assert_eq!(sphere.radius, 0.4);
    for (bad, needle) in [
        ("shape.9.radius=1", "index 9 is past the array's 4 entries"),
        ("shape.x.radius=1", "'x' indexes an array"),
        ("camera.fov.deg=1", "neither a table nor an array"),
        ("camera", "expected KEY=VALUE"),
        ("camera..fov=1", "not a dotted key"),
    ] {
        let e = apply_overrides(text, &[bad.into()]).unwrap_err();
        assert!(e.contains(needle), "{bad}: {e}");
    }
}

#[test]
fn the_sky_can_be_an_environment_map_turned_and_scaled() {
    let path =
        write("sky-map", "[[mesh]]\nfile = \"tri.obj\"\n\n[sky]\nmap = \"sky.exr\"\nrotation = 90\nradiance = 2\n");
    let sky = image::Rgb32FImage::from_fn(4, 2, |x, y| image::Rgb([x as f32, y as f32, 1.0]));
    sky.save(path.with_file_name("sky.exr")).unwrap();
    let s = load_scene_file(&path).unwrap();
    let env = s.environment.as_ref().unwrap();
    let map = env.map.as_ref().expect("a map");
    assert_eq!((map.width(), map.height(), env.radiance.rgb), (4, 2, [2.0; 3]));
    // Turned 90°: the map's centre (u = ½) now lies towards −x.
    let centre = map.uv(Vec3::NEG_X);
    assert!((centre.x - 0.5).abs() < 1e-5, "{centre}");
    // A sky with neither radiance nor map, and a map that is not there, are errors.
    let empty = write("sky-empty", "[[mesh]]\nfile = \"tri.obj\"\n\n[sky]\nrotation = 3\n");
    let e = load_scene_file(&empty).unwrap_err().to_string();
    assert!(e.contains("needs a radiance, a map, or both") && e.contains(":4:"), "{e}");
    let missing = write("sky-missing", "[[mesh]]\nfile = \"tri.obj\"\n\n[sky]\nmap = \"gone.hdr\"\n");
    let e = load_scene_file(&missing).unwrap_err().to_string();
    assert!(e.contains("gone.hdr"), "{e}");
}

#[test]
fn daylight_spectra_by_name_and_by_temperature() {
    let path = write(
        "daylight",
        "[[mesh]]\nfile = \"tri.obj\"\n\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\n\
         intensity = { spectrum = \"D50\", scale = 2 }\n\n[[light]]\ntype = \"point\"\nposition = [0, 3, 0]\n\
         intensity = { daylight = 5003 }\n",
    );
    let s = load_scene_file(&path).unwrap();
    let d50 = s.punctual_lights[0].colour();
    assert_eq!(d50.spectrum, Spectrum::Daylight { kelvin: 5003.0, scale: 0.02 });
    // D50 is warmer than sRGB's D65 white: more red than blue.
    assert!(d50.rgb[0] > d50.rgb[2], "{:?}", d50.rgb);
    assert_eq!(s.punctual_lights[1].colour().spectrum, Spectrum::Daylight { kelvin: 5003.0, scale: 0.01 });
    let f11 = write("f11", "[[mesh]]\nfile = \"tri.obj\"\n\n[sky]\nradiance = { spectrum = \"F11\", scale = 0.5 }\n");
    let sky = load_scene_file(&f11).unwrap().environment.unwrap().radiance;
    assert_eq!(sky.spectrum, Spectrum::Fluorescent { number: 11, scale: 0.5 });
    let bad = write(
        "daylight-bad",
        "[[mesh]]\nfile = \"tri.obj\"\n\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = { daylight = 2000 }\n",
    );
    let e = load_scene_file(&bad).unwrap_err().to_string();
    assert!(e.contains("daylight 2000 K is outside"), "{e}");
}

#[test]
fn a_mesh_file_named_twice_is_loaded_once_and_instanced() {
    let path = write(
        "instanced",
        "[materials.grey]\nmodel = \"lambert\"\nreflectance = 0.5\n\n\
         [[mesh]]\nfile = \"tri.obj\"\n\n[[mesh]]\nfile = \"tri.obj\"\ntranslate = [2, 0, 0]\nmaterial = \"grey\"\n\n\
         [[mesh]]\nfile = \"tri.obj\"\nscale = [-1, 1, 1]\n",
    );
    let s = load_scene_file(&path).unwrap();
    assert!(s.triangles.is_empty());
    assert_eq!((s.objects.len(), s.instances.len()), (1, 3));
    // The second placement wears "grey" instead of the file's red.
    let grey = s.materials.iter().position(|m| m.name == "grey").unwrap() as u32;
    assert_eq!(s.instances.iter().map(|i| i.material).collect::<Vec<_>>(), [None, Some(grey), None]);
    let b = s.bounds();
    assert_eq!((b.min.x, b.max.x), (-1.0, 3.0));
    // Named once: copied into the flat arrays as before.
    let once = write("once", "[[mesh]]\nfile = \"tri.obj\"\n");
    let s = load_scene_file(&once).unwrap();
    assert_eq!((s.triangles.len(), s.instances.len()), (1, 0));
}
