//! Tests of `spec.rs`.

use super::*;
use crate::material::ModelParams;
use crate::obj::load_obj_text;

/// The thesis's listing 8.7, completed: its two D65 values as printed, a golden SPD.
const LISTING_8_7: &str = r#"{
    "materials": {
        "Metal": { "diff": "golden", "spec": "golden" }
    },
    "sky": "CIE_D65",
    "spectra": {
        "CIE_D65": {
            "380": 0.444027773062, "385": 0.463859369164,
            "770": 0.552525209656, "775": 0.537999524666
        },
        "golden": { "380": 0.2, "500": 0.35, "600": 0.8, "775": 0.95 },
        "grey": { "380": 0.5, "775": 0.5 }
    }
}"#;

/// A scene with a mirror `Metal` and a Lambertian `Wall` (and `Other`).
fn scene() -> Scene {
    let mtl = "newmtl Metal\nillum 3\nKs 0.9 0.9 0.9\nnewmtl Wall\nKd 0.5 0.5 0.5\nnewmtl Other\nKd 0.2\n";
    let obj =
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl Metal\nf 1 2 3\nusemtl Wall\nf 1 2 3\nusemtl Other\nf 1 2 3\n";
    load_obj_text(obj, Path::new("s.obj"), &|_| Ok(mtl.to_string())).unwrap()
}

#[test]
fn the_thesis_listing_reads_and_lights_and_colours_the_scene() {
    let spec = parse_spec(LISTING_8_7, Path::new("s.spec")).unwrap();
    let (name, d65) = spec.sky.clone().unwrap();
    assert_eq!(name, "CIE_D65");
    // The listing's values as f32 (the file's digits exceed f32's precision).
    let (first, last) = ("0.444027773062".parse::<f32>().unwrap(), "0.537999524666".parse::<f32>().unwrap());
    assert_eq!((d65.eval(380.0), d65.eval(775.0)), (first, last));
    // Linear in between, the end values beyond.
    assert!((d65.eval(382.5) - 0.5 * (first + 0.463_859_37)).abs() < 1e-6);
    assert_eq!(d65.eval(830.0), last);
    let mut s = scene();
    let notes = spec.apply(&mut s).unwrap();
    // The mirror takes the golden SPD as its reflectance; it has no diffuse colour.
    let Some(ModelParams::Mirror(m)) = s.materials[0].params() else { unreachable!() };
    assert_eq!(m.reflectance.spectrum.eval(600.0), 0.8);
    assert_eq!(notes, ["material 'Metal' (mirror) has no diffuse colour: its diff spectrum 'golden' is unused"]);
    let sky = s.environment.as_ref().unwrap();
    assert_eq!(sky.radiance.spectrum.eval(380.0), first);
    // Other materials keep their colours.
    assert_eq!(format!("{:?}", s.materials[1]), format!("{:?}", scene().materials[1]));
}

#[test]
fn a_constant_spd_renders_exactly_as_the_same_grey() {
    use crate::{Camera, CpuBackend, RenderSettings, SceneOptions, SpectralMode};
    let render = |s: Scene| {
        let mut s = s;
        s.environment = Some(Environment::white_sky(1.0));
        let prepared = CpuBackend::new(1).unwrap().prepare_cpu(s, &SceneOptions::default()).unwrap();
        let settings = RenderSettings {
            width: 12,
            height: 12,
            spp: 8,
            mode: SpectralMode::Hero,
            camera: Some(Camera {
                eye: glam::Vec3::new(0.3, 0.3, 1.5),
                center: glam::Vec3::new(0.3, 0.3, 0.0),
                up: glam::Vec3::Y,
                fov_y_deg: 40.0,
            }),
            ..Default::default()
        };
        crate::render(&prepared, &settings, &|_| {}).unwrap().0.mean_rgb()
    };
    let spec = LISTING_8_7
        .replace(r#""Metal": { "diff": "golden", "spec": "golden" }"#, r#""Wall": { "diff": "grey" }"#)
        .replace(r#""sky": "CIE_D65","#, "");
    let spec = parse_spec(&spec, Path::new("s.spec")).unwrap();
    let mut with_spd = scene();
    assert!(spec.apply(&mut with_spd).unwrap().is_empty());
    assert_ne!(format!("{:?}", with_spd.materials[1]), format!("{:?}", scene().materials[1]));
    let (a, b) = (render(with_spd), render(scene()));
    assert!(a.iter().any(|&v| v > 0.0));
    assert_eq!(a, b);
}

#[test]
fn bad_spec_files_say_what_is_wrong() {
    let path = Path::new("s.spec");
    for (text, needle) in [
        (
            r#"{ "materials": { "Metal": { "diff": "gold" } }, "spectra": { "golden": { "400": 0.5 } } }"#,
            "materials.Metal.diff: no spectrum 'gold' in spectra (defined: golden)",
        ),
        (r#"{ "sky": "D65" }"#, "sky: no spectrum 'D65' in spectra (defined: none)"),
        (
            r#"{ "materials": { "M": { "spec": "hot" } }, "spectra": { "hot": { "400": 0.5, "500": 1.5 } } }"#,
            "materials.M.spec: 'hot' is a reflectance but is 1.5 > 1 at 500 nm",
        ),
        (r#"{ "spectra": { "x": { "blue": 0.5 } } }"#, "spectra.x: 'blue' is not a wavelength in nm"),
        (r#"{ "spectra": { "x": { "400": -1 } } }"#, "spectra.x.400: -1 is not a non-negative number"),
        (r#"{ "spectra": { "x": { "400": 0.1, "400.0": 0.2 } } }"#, "spectra.x: wavelength 400 is given twice"),
        ("{\n  \"sky\": \"a\",\n  \"skies\": 1\n}", "s.spec:3:"),
        ("{\n  \"spectra\": { \"x\": { \"400\": 0.5, } }\n}", "s.spec:2:"),
    ] {
        let e = parse_spec(text, path).unwrap_err().to_string();
        assert!(e.starts_with("s.spec") && e.contains(needle), "{text}\n→ {e}");
    }
    let spec = parse_spec(r#"{ "materials": { "Nope": { "diff": "g" } }, "spectra": { "g": { "400": 0.5 } } }"#, path)
        .unwrap();
    let e = spec.apply(&mut scene()).unwrap_err().to_string();
    assert!(e.contains("materials.Nope: no such material in the scene (it has: Metal, Wall, Other)"), "{e}");
}

#[test]
fn only_regular_files_are_read() {
    // /dev/zero never ends: reading it whole would never return.
    for e in [
        load_spec(Path::new("/dev/zero")).unwrap_err(),
        crate::scene_file::load_scene_file(Path::new("/dev/zero")).unwrap_err(),
    ] {
        assert!(e.to_string().starts_with("/dev/zero: not a regular file"), "{e}");
    }
}
