//! Parameter declarations: every model declares its parameters once, with
//! [`model_params!`](crate::model_params), and that one declaration yields
//!
//! * the typed parameter struct the model's Rust code reads (named fields; `f32`,
//!   [`Colour`], `bool` or a [`choice_param!`](crate::choice_param) enum),
//! * its [`ModelDef`] (name, kind, range, default, MTL key, documentation), which scene
//!   loaders, range validation, contact sheets and the GPU crate's WGSL generator read,
//! * the conversions between the typed struct and [`ResolvedParams`], the by-name,
//!   declaration-ordered form loaders produce and the GPU packs.
//!
//! So no parameter list is maintained twice, and no code reads a parameter by position.

pub use spectral::spectrum::Colour;

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
    /// A switch: given as `true`/`false` or as the number 0 or 1.
    Bool,
    /// One of a fixed list of options, named here in index order: given by name or by
    /// its index (MTL files give numbers).
    Choice(&'static [&'static str]),
}

impl ParamKind {
    /// True for the kinds stored as a colour (spectrum or coefficient).
    pub fn is_colour(self) -> bool {
        matches!(self, Self::Spectrum | Self::Coefficient)
    }
}

/// One declared parameter of a BSDF model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamDef {
    /// Name used in code and scene files.
    pub name: &'static str,
    /// What it holds.
    pub kind: ParamKind,
    /// Smallest valid value (per component for spectra; 0 for switches and choices).
    pub min: f32,
    /// Largest valid value (per component for spectra; `f32::INFINITY` for unbounded; 1
    /// for switches; the last index for choices).
    pub max: f32,
    /// Value when a scene does not give one (grey of this value for spectra; 0 or 1 for
    /// switches; the index for choices).
    pub default: f32,
    /// The MTL statement that sets it, where there is one.
    pub mtl_key: Option<&'static str>,
    /// What it means.
    pub doc: &'static str,
}

/// A BSDF model's declaration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelDef {
    /// Name used in scene files and messages (also the stem of the GPU's generated
    /// identifiers, so a lower-case identifier).
    pub name: &'static str,
    /// What it is, with its source.
    pub doc: &'static str,
    /// Its parameters, in the order [`ModelDef::resolve`] returns them.
    pub params: &'static [ParamDef],
}

/// A parameter value as given by a scene or by code.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// A number (for a spectrum parameter: a grey of this value; for a switch: 0 or 1;
    /// for a choice: its index).
    Scalar(f32),
    /// A linear-sRGB colour (for a spectrum parameter; uplifted to a spectrum).
    Rgb([f32; 3]),
    /// A colour with its spectrum already built.
    Colour(Colour),
    /// A switch.
    Bool(bool),
    /// A choice by name (or a switch as `true`/`false`).
    Name(String),
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
    /// A spectrum or coefficient parameter.
    Colour(Colour),
    /// A switch.
    Bool(bool),
    /// A choice, by index into [`ParamKind::Choice`]'s names.
    Choice(u32),
}

impl ResolvedParams {
    /// Values in declaration order, as they are (for code that walks a [`ModelDef`]
    /// generically, such as the GPU's packing).
    pub fn from_values(values: Vec<Resolved>) -> Self {
        Self { values }
    }

    /// The value at declaration index `i` as a number: a scalar as it is, a switch as 0
    /// or 1, a choice as its index, a colour as its luminance.
    #[inline]
    pub fn scalar(&self, i: usize) -> f32 {
        match &self.values[i] {
            Resolved::Scalar(v) => *v,
            Resolved::Colour(c) => c.luminance(),
            Resolved::Bool(b) => f32::from(u8::from(*b)),
            Resolved::Choice(k) => *k as f32,
        }
    }

    /// The colour at declaration index `i` (a grey for any other kind, of the value
    /// [`ResolvedParams::scalar`] gives).
    pub fn colour(&self, i: usize) -> Colour {
        match &self.values[i] {
            Resolved::Colour(c) => c.clone(),
            _ => Colour::constant(self.scalar(i)),
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
    /// A value of the wrong kind (a colour for a number, a name for a colour, …).
    #[error("material '{material}': {param} is {expected}, not {given}")]
    WrongKind {
        /// Material name.
        material: String,
        /// Parameter name.
        param: &'static str,
        /// What the parameter takes.
        expected: &'static str,
        /// What was given.
        given: &'static str,
    },
    /// A switch or choice given a value that is none of its options.
    #[error("material '{material}': {param} = {value} is not one of its options ({options})")]
    NotAnOption {
        /// Material name.
        material: String,
        /// Parameter name.
        param: &'static str,
        /// The offending value, as given.
        value: String,
        /// The options, with their numbers.
        options: String,
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

impl ParamError {
    /// The declared parameter whose value is at fault (`None` for an unknown name), for
    /// loaders that point at where that value was written.
    pub fn param(&self) -> Option<&'static str> {
        match self {
            Self::OutOfRange { param, .. }
            | Self::WrongKind { param, .. }
            | Self::NotAnOption { param, .. }
            | Self::Spectrum { param, .. } => Some(param),
            Self::Unknown { .. } => None,
        }
    }
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
        let values = values.into_iter().zip(self.params).map(|(v, def)| v.unwrap_or_else(|| default_of(def))).collect();
        Ok(ResolvedParams { values })
    }

    /// All defaults.
    pub fn defaults(&self) -> ResolvedParams {
        ResolvedParams { values: self.params.iter().map(default_of).collect() }
    }
}

fn default_of(def: &ParamDef) -> Resolved {
    match def.kind {
        ParamKind::Scalar => Resolved::Scalar(def.default),
        ParamKind::Spectrum | ParamKind::Coefficient => Resolved::Colour(Colour::constant(def.default)),
        ParamKind::Bool => Resolved::Bool(def.default != 0.0),
        ParamKind::Choice(_) => Resolved::Choice(def.default as u32),
    }
}

fn check_range(material: &str, def: &ParamDef, v: f32) -> Result<(), ParamError> {
    if v.is_finite() && v >= def.min && v <= def.max {
        Ok(())
    } else {
        Err(ParamError::OutOfRange { material: material.into(), param: def.name, value: v, min: def.min, max: def.max })
    }
}

fn given_kind(value: &ParamValue) -> &'static str {
    match value {
        ParamValue::Scalar(_) => "a number",
        ParamValue::Rgb(_) | ParamValue::Colour(_) => "a colour",
        ParamValue::Bool(_) => "a switch",
        ParamValue::Name(_) => "a name",
    }
}

fn resolve_one(material: &str, def: &ParamDef, value: &ParamValue) -> Result<Resolved, ParamError> {
    let wrong = |expected| ParamError::WrongKind {
        material: material.into(),
        param: def.name,
        expected,
        given: given_kind(value),
    };
    match def.kind {
        ParamKind::Scalar => match value {
            ParamValue::Scalar(v) => check_range(material, def, *v).map(|()| Resolved::Scalar(*v)),
            _ => Err(wrong("a number")),
        },
        ParamKind::Bool => {
            let b = match value {
                ParamValue::Bool(b) => Some(*b),
                ParamValue::Scalar(v) if *v == 0.0 || *v == 1.0 => Some(*v == 1.0),
                ParamValue::Name(n) if n == "true" || n == "false" => Some(n == "true"),
                ParamValue::Scalar(_) | ParamValue::Name(_) => None,
                _ => return Err(wrong("a switch (true/false or 1/0)")),
            };
            b.map(Resolved::Bool).ok_or_else(|| not_an_option(material, def, value, &["false", "true"]))
        }
        ParamKind::Choice(names) => {
            let k = match value {
                ParamValue::Scalar(v) if v.fract() == 0.0 && *v >= 0.0 && (*v as usize) < names.len() => {
                    Some(*v as u32)
                }
                ParamValue::Name(n) => names.iter().position(|o| o.eq_ignore_ascii_case(n)).map(|k| k as u32),
                ParamValue::Scalar(_) => None,
                _ => return Err(wrong("a choice (by name or number)")),
            };
            k.map(Resolved::Choice).ok_or_else(|| not_an_option(material, def, value, names))
        }
        kind @ (ParamKind::Spectrum | ParamKind::Coefficient) => match value {
            ParamValue::Scalar(v) => check_range(material, def, *v).map(|()| Resolved::Colour(Colour::constant(*v))),
            ParamValue::Rgb(rgb) => {
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
            ParamValue::Colour(c) => {
                for &v in &c.rgb {
                    check_range(material, def, v)?;
                }
                Ok(Resolved::Colour(c.clone()))
            }
            ParamValue::Bool(_) | ParamValue::Name(_) => Err(wrong("a colour")),
        },
    }
}

fn not_an_option(material: &str, def: &ParamDef, value: &ParamValue, names: &[&str]) -> ParamError {
    let value = match value {
        ParamValue::Scalar(v) => v.to_string(),
        ParamValue::Name(n) => format!("'{n}'"),
        other => format!("{other:?}"),
    };
    let options = names.iter().enumerate().map(|(k, n)| format!("{k} = {n}")).collect::<Vec<_>>().join(", ");
    ParamError::NotAnOption { material: material.into(), param: def.name, value, options }
}

/// A model's typed parameter struct: generated, with its [`ModelDef`], by
/// [`model_params!`](crate::model_params).
pub trait ParamSet: Sized {
    /// The declaration the struct was generated from.
    const DEF: ModelDef;

    /// The typed form of parameters resolved against [`ParamSet::DEF`].
    ///
    /// # Panics
    /// If `params` were resolved against another declaration (a kind mismatch).
    fn from_resolved(params: &ResolvedParams) -> Self;

    /// The declaration-ordered form (what loaders produce and the GPU packs).
    fn to_resolved(&self) -> ResolvedParams;

    /// Checks named values against [`ParamSet::DEF`] and fills defaults.
    fn resolve(material: &str, given: &[(&str, ParamValue)]) -> Result<Self, ParamError> {
        Ok(Self::from_resolved(&Self::DEF.resolve(material, given)?))
    }
}

/// A field type of a typed parameter struct: how it is read from and written to a
/// [`Resolved`] value.
pub trait ParamField: Sized {
    /// The value of a resolved parameter of this field's kind.
    ///
    /// # Panics
    /// On a kind mismatch (a declaration bug, not user input: values are checked by
    /// [`ModelDef::resolve`] first).
    fn from_resolved(value: &Resolved) -> Self;
    /// The resolved form of the value.
    fn to_resolved(&self) -> Resolved;
}

impl ParamField for f32 {
    fn from_resolved(value: &Resolved) -> Self {
        match value {
            Resolved::Scalar(v) => *v,
            other => panic!("a scalar parameter resolved as {other:?}"),
        }
    }
    fn to_resolved(&self) -> Resolved {
        Resolved::Scalar(*self)
    }
}

impl ParamField for bool {
    fn from_resolved(value: &Resolved) -> Self {
        match value {
            Resolved::Bool(v) => *v,
            other => panic!("a switch parameter resolved as {other:?}"),
        }
    }
    fn to_resolved(&self) -> Resolved {
        Resolved::Bool(*self)
    }
}

impl ParamField for Colour {
    fn from_resolved(value: &Resolved) -> Self {
        match value {
            Resolved::Colour(c) => c.clone(),
            other => panic!("a colour parameter resolved as {other:?}"),
        }
    }
    fn to_resolved(&self) -> Resolved {
        Resolved::Colour(self.clone())
    }
}

/// An enum usable as a [`ParamKind::Choice`] parameter: generated by
/// [`choice_param!`](crate::choice_param).
pub trait ParamChoice: Copy + 'static {
    /// Option names in index order.
    const NAMES: &'static [&'static str];
    /// The option at `index` (< `NAMES.len()`).
    fn from_index(index: u32) -> Option<Self>;
    /// This option's index.
    fn index(self) -> u32;
}

/// Declares an enum whose variants are the options of a [`ParamKind::Choice`] parameter,
/// in index order, each with the name scene files use:
///
/// ```
/// brdf::choice_param! {
///     /// How hard to try.
///     pub enum Effort {
///         /// A little.
///         Low = "low",
///         /// A lot.
///         High = "high",
///     }
/// }
/// assert_eq!(<Effort as brdf::params::ParamChoice>::NAMES, &["low", "high"]);
/// assert_eq!(Effort::High.index(), 1);
/// ```
#[macro_export]
macro_rules! choice_param {
    (
        $(#[$meta:meta])*
        $vis:vis enum $Name:ident {
            $( $(#[$vmeta:meta])* $Variant:ident = $label:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[repr(u32)]
        $vis enum $Name {
            $( $(#[$vmeta])* $Variant ),+
        }

        impl $Name {
            /// Every option, in index order.
            pub const ALL: &'static [$Name] = &[$($Name::$Variant),+];

            /// The option's index (its number in MTL files, and on the GPU).
            pub const fn index(self) -> u32 {
                self as u32
            }

            /// The option's name in scene files.
            pub fn name(self) -> &'static str {
                <Self as $crate::params::ParamChoice>::NAMES[self as usize]
            }
        }

        impl $crate::params::ParamChoice for $Name {
            const NAMES: &'static [&'static str] = &[$($label),+];
            fn from_index(index: u32) -> Option<Self> {
                Self::ALL.get(index as usize).copied()
            }
            fn index(self) -> u32 {
                self as u32
            }
        }

        impl $crate::params::ParamField for $Name {
            fn from_resolved(value: &$crate::params::Resolved) -> Self {
                match value {
                    $crate::params::Resolved::Choice(k) => <Self as $crate::params::ParamChoice>::from_index(*k)
                        .unwrap_or_else(|| panic!("option {k} of {} does not exist", stringify!($Name))),
                    other => panic!("a choice parameter resolved as {other:?}"),
                }
            }
            fn to_resolved(&self) -> $crate::params::Resolved {
                $crate::params::Resolved::Choice(*self as u32)
            }
        }
    };
}

/// Declares a model's typed parameter struct and its [`ModelDef`] in one place.
///
/// Each parameter is `name: kind { doc: "…", default: …, [min: …, max: …,] [mtl: "Key"] }`
/// with kind `scalar` (an `f32`; `min` and `max` required), `spectrum` (a [`Colour`] in
/// [0, 1]), `coefficient` (an unbounded non-negative [`Colour`]), `bool`, or
/// `choice(Enum)` (an enum from [`choice_param!`](crate::choice_param); the default is a
/// variant). Fields appear in the struct, and parameters in the declaration, in the
/// order given.
///
/// ```
/// brdf::model_params! {
///     /// Parameters of a toy model.
///     pub struct ToyParams for "toy" {
///         doc: "A toy.",
///         albedo: spectrum { doc: "reflectance", default: 0.5, mtl: "Kd" },
///         gain: scalar { doc: "a factor", default: 1.0, min: 0.0, max: 2.0 },
///         flipped: bool { doc: "upside down", default: false },
///     }
/// }
/// use brdf::params::{ParamSet, ParamValue};
/// let p = ToyParams::resolve("m", &[("gain", ParamValue::Scalar(1.5))]).unwrap();
/// assert_eq!(p.gain, 1.5);
/// assert_eq!(ToyParams::DEF.param_by_mtl_key("Kd").unwrap().name, "albedo");
/// ```
#[macro_export]
macro_rules! model_params {
    (
        $(#[$meta:meta])*
        $vis:vis struct $Name:ident for $model:literal {
            doc: $model_doc:expr,
            $( $field:ident : $kind:ident $(($Choice:ty))? { $($body:tt)* } ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, PartialEq)]
        $vis struct $Name {
            $(
                #[doc = $crate::__param_doc!($($body)*)]
                pub $field: $crate::__param_type!($kind $(($Choice))?),
            )+
        }

        impl $crate::params::ParamSet for $Name {
            const DEF: $crate::params::ModelDef = $crate::params::ModelDef {
                name: $model,
                doc: $model_doc,
                params: &[$($crate::__param_def!($field, $kind $(($Choice))?, $($body)*)),+],
            };

            fn from_resolved(params: &$crate::params::ResolvedParams) -> Self {
                let values = params.values();
                assert_eq!(values.len(), Self::DEF.params.len(), "parameters of another model");
                let mut i = 0usize;
                $(
                    let $field = <$crate::__param_type!($kind $(($Choice))?) as $crate::params::ParamField>::from_resolved(&values[i]);
                    i += 1;
                )+
                let _ = i;
                Self { $($field),+ }
            }

            fn to_resolved(&self) -> $crate::params::ResolvedParams {
                $crate::params::ResolvedParams::from_values(vec![
                    $($crate::params::ParamField::to_resolved(&self.$field)),+
                ])
            }
        }

        impl Default for $Name {
            fn default() -> Self {
                <Self as $crate::params::ParamSet>::from_resolved(
                    &<Self as $crate::params::ParamSet>::DEF.defaults(),
                )
            }
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __param_doc {
    (doc: $doc:literal $(, $($rest:tt)*)?) => {
        $doc
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __param_type {
    (scalar) => {
        f32
    };
    (spectrum) => {
        $crate::params::Colour
    };
    (coefficient) => {
        $crate::params::Colour
    };
    (bool) => {
        bool
    };
    (choice($Choice:ty)) => {
        $Choice
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __param_def {
    ($field:ident, scalar, doc: $doc:literal, default: $default:expr, min: $min:expr, max: $max:expr $(, mtl: $mtl:literal)? $(,)?) => {
        $crate::params::ParamDef {
            name: stringify!($field),
            kind: $crate::params::ParamKind::Scalar,
            min: $min,
            max: $max,
            default: $default,
            mtl_key: $crate::__mtl_key!($($mtl)?),
            doc: $doc,
        }
    };
    ($field:ident, spectrum, doc: $doc:literal, default: $default:expr $(, mtl: $mtl:literal)? $(,)?) => {
        $crate::params::ParamDef {
            name: stringify!($field),
            kind: $crate::params::ParamKind::Spectrum,
            min: 0.0,
            max: 1.0,
            default: $default,
            mtl_key: $crate::__mtl_key!($($mtl)?),
            doc: $doc,
        }
    };
    ($field:ident, coefficient, doc: $doc:literal, default: $default:expr $(, mtl: $mtl:literal)? $(,)?) => {
        $crate::params::ParamDef {
            name: stringify!($field),
            kind: $crate::params::ParamKind::Coefficient,
            min: 0.0,
            max: f32::INFINITY,
            default: $default,
            mtl_key: $crate::__mtl_key!($($mtl)?),
            doc: $doc,
        }
    };
    ($field:ident, bool, doc: $doc:literal, default: $default:expr $(, mtl: $mtl:literal)? $(,)?) => {
        $crate::params::ParamDef {
            name: stringify!($field),
            kind: $crate::params::ParamKind::Bool,
            min: 0.0,
            max: 1.0,
            default: if $default { 1.0 } else { 0.0 },
            mtl_key: $crate::__mtl_key!($($mtl)?),
            doc: $doc,
        }
    };
    ($field:ident, choice($Choice:ty), doc: $doc:literal, default: $default:expr $(, mtl: $mtl:literal)? $(,)?) => {
        $crate::params::ParamDef {
            name: stringify!($field),
            kind: $crate::params::ParamKind::Choice(<$Choice as $crate::params::ParamChoice>::NAMES),
            min: 0.0,
            max: (<$Choice as $crate::params::ParamChoice>::NAMES.len() - 1) as f32,
            default: <$Choice>::index($default) as f32,
            mtl_key: $crate::__mtl_key!($($mtl)?),
            doc: $doc,
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __mtl_key {
    () => {
        None
    };
    ($mtl:literal) => {
        Some($mtl)
    };
}

#[cfg(test)]
mod tests;
