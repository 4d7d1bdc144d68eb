//! Parameter definitions as data: every model declares its parameters once (name, kind,
//! valid range, default, MTL key, documentation). Scene loaders, range validation and
//! the GPU crate's WGSL generator all read these declarations, so no parameter list is
//! maintained twice.

use spectral::spectrum::Colour;

/// What a parameter holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamKind {
    /// One number.
    Scalar,
    /// A colour or spectrum in [0, 1] (a reflectance or similar, sampled at the path's
    /// wavelengths; RGB is uplifted by Jakob & Hanika 2019).
    Spectrum,
    /// A non-negative, unbounded spectrum such as an absorption coefficient (RGB is
    /// uplifted as max(rgb) × the reflectance spectrum of rgb / max(rgb)).
    Coefficient,
}

/// One declared parameter of a BSDF model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamDef {
    /// Name used in code and scene files.
    pub name: &'static str,
    /// Scalar or spectrum.
    pub kind: ParamKind,
    /// Smallest valid value (per component for spectra).
    pub min: f32,
    /// Largest valid value (per component for spectra; `f32::INFINITY` for unbounded).
    pub max: f32,
    /// Value when a scene does not give one (grey of this value for spectra).
    pub default: f32,
    /// The MTL statement that sets it, where there is one.
    pub mtl_key: Option<&'static str>,
    /// What it means.
    pub doc: &'static str,
}

/// A BSDF model's declaration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelDef {
    /// Name used in scene files and messages.
    pub name: &'static str,
    /// What it is, with its source.
    pub doc: &'static str,
    /// Its parameters, in the order [`ModelDef::resolve`] returns them.
    pub params: &'static [ParamDef],
}

/// A parameter value as given by a scene or by code.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// A number (for a spectrum parameter: a grey of this value).
    Scalar(f32),
    /// A linear-sRGB colour (for a spectrum parameter; uplifted to a spectrum).
    Rgb([f32; 3]),
    /// A colour with its spectrum already built.
    Colour(Colour),
}

/// A parameter set resolved against a [`ModelDef`]: one value per declared parameter, in
/// declaration order, validated.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedParams {
    values: Vec<Resolved>,
}

/// One resolved value.
#[derive(Clone, Debug, PartialEq)]
pub enum Resolved {
    /// A scalar parameter.
    Scalar(f32),
    /// A spectrum parameter.
    Colour(Colour),
}

impl ResolvedParams {
    /// The scalar at declaration index `i` (0 if the parameter is a spectrum).
    #[inline]
    pub fn scalar(&self, i: usize) -> f32 {
        match &self.values[i] {
            Resolved::Scalar(v) => *v,
            Resolved::Colour(c) => c.luminance(),
        }
    }

    /// The colour at declaration index `i` (a grey for a scalar parameter).
    pub fn colour(&self, i: usize) -> Colour {
        match &self.values[i] {
            Resolved::Scalar(v) => Colour::constant(*v),
            Resolved::Colour(c) => c.clone(),
        }
    }

    /// All values in declaration order.
    pub fn values(&self) -> &[Resolved] {
        &self.values
    }
}

/// Why parameters were rejected; every message names the material and the parameter.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// A parameter name the model does not declare.
    #[error("material '{material}': model '{model}' has no parameter '{param}' (it has: {known})")]
    Unknown {
        /// Material name.
        material: String,
        /// Model name.
        model: &'static str,
        /// The unknown name.
        param: String,
        /// The declared names.
        known: String,
    },
    /// A value outside its declared range, or not finite.
    #[error("material '{material}': {param} = {value} is outside its valid range [{min}, {max}]")]
    OutOfRange {
        /// Material name.
        material: String,
        /// Parameter name.
        param: &'static str,
        /// The offending value.
        value: f32,
        /// Lower bound.
        min: f32,
        /// Upper bound.
        max: f32,
    },
    /// A colour given for a scalar parameter.
    #[error("material '{material}': {param} is a number, not a colour")]
    NotScalar {
        /// Material name.
        material: String,
        /// Parameter name.
        param: &'static str,
    },
    /// A colour that could not be turned into a spectrum.
    #[error("material '{material}': {param}: {source}")]
    Spectrum {
        /// Material name.
        material: String,
        /// Parameter name.
        param: &'static str,
        /// Why.
        source: spectral::SpectralError,
    },
}

impl ModelDef {
    /// The declaration of parameter `name`.
    pub fn param(&self, name: &str) -> Option<(usize, &ParamDef)> {
        self.params.iter().enumerate().find(|(_, p)| p.name == name)
    }

    /// The declaration whose MTL key is `key`.
    pub fn param_by_mtl_key(&self, key: &str) -> Option<&ParamDef> {
        self.params.iter().find(|p| p.mtl_key == Some(key))
    }

    /// Checks `given` (name → value) against the declarations, fills defaults, and
    /// uplifts colours; errors name `material` and the parameter.
    pub fn resolve(&self, material: &str, given: &[(&str, ParamValue)]) -> Result<ResolvedParams, ParamError> {
        let mut values: Vec<Option<Resolved>> = vec![None; self.params.len()];
        for (name, value) in given {
            let Some((i, def)) = self.param(name) else {
                return Err(ParamError::Unknown {
                    material: material.into(),
                    model: self.name,
                    param: name.to_string(),
                    known: self.params.iter().map(|p| p.name).collect::<Vec<_>>().join(", "),
                });
            };
            values[i] = Some(resolve_one(material, def, value)?);
        }
        let values = values
            .into_iter()
            .zip(self.params)
            .map(|(v, def)| {
                v.unwrap_or_else(|| match def.kind {
                    ParamKind::Scalar => Resolved::Scalar(def.default),
                    ParamKind::Spectrum | ParamKind::Coefficient => Resolved::Colour(Colour::constant(def.default)),
                })
            })
            .collect();
        Ok(ResolvedParams { values })
    }

    /// All defaults.
    pub fn defaults(&self) -> ResolvedParams {
        self.resolve("(defaults)", &[]).expect("defaults are valid by construction")
    }
}

fn check_range(material: &str, def: &ParamDef, v: f32) -> Result<(), ParamError> {
    if v.is_finite() && v >= def.min && v <= def.max {
        Ok(())
    } else {
        Err(ParamError::OutOfRange { material: material.into(), param: def.name, value: v, min: def.min, max: def.max })
    }
}

fn resolve_one(material: &str, def: &ParamDef, value: &ParamValue) -> Result<Resolved, ParamError> {
    match (def.kind, value) {
        (ParamKind::Scalar, ParamValue::Scalar(v)) => {
            check_range(material, def, *v)?;
            Ok(Resolved::Scalar(*v))
        }
        (ParamKind::Scalar, _) => Err(ParamError::NotScalar { material: material.into(), param: def.name }),
        (_, ParamValue::Scalar(v)) => {
            check_range(material, def, *v)?;
            Ok(Resolved::Colour(Colour::constant(*v)))
        }
        (kind, ParamValue::Rgb(rgb)) => {
            for &c in rgb {
                check_range(material, def, c)?;
            }
            let colour = if kind == ParamKind::Coefficient {
                Colour::unbounded_rgb(*rgb)
            } else {
                Colour::reflectance_rgb(*rgb)
            };
            colour.map(Resolved::Colour).map_err(|source| ParamError::Spectrum {
                material: material.into(),
                param: def.name,
                source,
            })
        }
        (_, ParamValue::Colour(c)) => {
            for &v in &c.rgb {
                check_range(material, def, v)?;
            }
            Ok(Resolved::Colour(c.clone()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEF: ModelDef = ModelDef {
        name: "test",
        doc: "a test model",
        params: &[
            ParamDef {
                name: "albedo",
                kind: ParamKind::Spectrum,
                min: 0.0,
                max: 1.0,
                default: 0.5,
                mtl_key: Some("Kd"),
                doc: "reflectance",
            },
            ParamDef {
                name: "roughness",
                kind: ParamKind::Scalar,
                min: 0.0,
                max: 1.0,
                default: 0.3,
                mtl_key: Some("rough"),
                doc: "roughness",
            },
        ],
    };

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
        assert!(matches!(e, ParamError::NotScalar { .. }));
        assert!(DEF.resolve("floor", &[("roughness", ParamValue::Scalar(f32::NAN))]).is_err());
        assert_eq!(DEF.param_by_mtl_key("rough").map(|p| p.name), Some("roughness"));
    }
}
