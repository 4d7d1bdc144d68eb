//! Tests of `params.rs`.

use super::*;

crate::choice_param! {
    /// Test options.
    enum Shade {
        /// First.
        Light = "light",
        /// Second.
        Dark = "dark",
    }
}

crate::model_params! {
    /// A test model.
    struct TestParams for "test" {
        doc: "a test model",
        albedo: spectrum { doc: "reflectance", default: 0.5, mtl: "Kd" },
        roughness: scalar { doc: "roughness", default: 0.3, min: 0.0, max: 1.0, mtl: "rough" },
        glossy: bool { doc: "a switch", default: true },
        shade: choice(Shade) { doc: "an option", default: Shade::Dark },
    }
}

const DEF: ModelDef = <TestParams as ParamSet>::DEF;

#[test]
fn defaults_fill_gaps_and_values_are_checked() {
    let r = DEF.resolve("m", &[("roughness", ParamValue::Scalar(0.7))]).unwrap();
    assert_eq!(r.scalar(1), 0.7);
    assert_eq!(r.colour(0).rgb, [0.5; 3]);
    let e = DEF.resolve("floor", &[("roughness", ParamValue::Scalar(1.5))]).unwrap_err();
    assert!(e.to_string().contains("material 'floor'") && e.to_string().contains("roughness = 1.5"), "{e}");
    let e = DEF.resolve("floor", &[("albedo", ParamValue::Rgb([0.2, 1.2, 0.2]))]).unwrap_err();
    assert!(e.to_string().contains("albedo = 1.2"), "{e}");
    let e = DEF.resolve("floor", &[("shininess", ParamValue::Scalar(1.0))]).unwrap_err();
    assert!(e.to_string().contains("no parameter 'shininess'") && e.to_string().contains("albedo, roughness"));
    let e = DEF.resolve("floor", &[("roughness", ParamValue::Rgb([0.1; 3]))]).unwrap_err();
    assert!(matches!(e, ParamError::WrongKind { .. }), "{e}");
    assert!(DEF.resolve("floor", &[("roughness", ParamValue::Scalar(f32::NAN))]).is_err());
    assert_eq!(DEF.param_by_mtl_key("rough").map(|p| p.name), Some("roughness"));
}

#[test]
fn the_typed_struct_mirrors_the_declaration() {
    let p = TestParams::default();
    assert_eq!((p.roughness, p.glossy, p.shade), (0.3, true, Shade::Dark));
    assert_eq!((Shade::Dark.name(), Shade::Light.index()), ("dark", 0));
    assert_eq!(p.albedo, Colour::constant(0.5));
    assert_eq!(DEF.params.iter().map(|d| d.name).collect::<Vec<_>>(), ["albedo", "roughness", "glossy", "shade"]);
    assert_eq!(DEF.params[3].kind, ParamKind::Choice(&["light", "dark"]));
    assert_eq!((DEF.params[3].max, DEF.params[3].default), (1.0, 1.0));
    let p =
        TestParams::resolve("m", &[("glossy", ParamValue::Scalar(0.0)), ("shade", ParamValue::Name("LIGHT".into()))])
            .unwrap();
    assert_eq!((p.glossy, p.shade), (false, Shade::Light));
    assert_eq!(TestParams::from_resolved(&p.to_resolved()), p);
    let p = TestParams::resolve("m", &[("shade", ParamValue::Scalar(1.0))]).unwrap();
    assert_eq!(p.shade, Shade::Dark);
}

#[test]
fn switches_and_choices_reject_what_is_not_an_option() {
    for (name, value) in [
        ("glossy", ParamValue::Scalar(0.5)),
        ("glossy", ParamValue::Name("yes".into())),
        ("shade", ParamValue::Scalar(2.0)),
        ("shade", ParamValue::Scalar(0.5)),
        ("shade", ParamValue::Name("grey".into())),
    ] {
        let e = TestParams::resolve("m", &[(name, value)]).unwrap_err();
        assert!(matches!(e, ParamError::NotAnOption { .. }), "{e}");
        assert!(e.to_string().contains("0 = "), "{e}");
    }
    let e = TestParams::resolve("m", &[("shade", ParamValue::Rgb([0.5; 3]))]).unwrap_err();
    assert!(e.to_string().contains("shade is a choice"), "{e}");
}
