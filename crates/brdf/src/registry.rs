//! Models by name: the [`Model`] trait a model's typed parameters implement, and the
//! [`registry!`](macro@crate::registry) macro that turns a list of models into the types every
//! consumer dispatches on.
//!
//! A model is three things, all in its own file: its parameters declared with
//! [`model_params!`](crate::model_params), an `impl Model` saying which [`Bsdf`] they
//! build and where its WGSL twin is, and the BSDF itself. Registering it is one line in
//! [`with_builtin_models!`](crate::with_builtin_models); scene loaders (by name and MTL
//! key), the renderer's material dispatch and the GPU's code generator all iterate the
//! registry, so none of them names a model.

use crate::Bsdf;
use crate::params::ParamSet;
use crate::wgsl::ModelWgsl;
use spectral::spectrum::Colour;
use spectral::{SampledSpectrum, SampledWavelengths};

/// Which of a model's parameters textures may drive (see [`Model::TEXTURE_SLOTS`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TextureSlots {
    /// The diffuse or base colour (MTL `map_Kd`, glTF `baseColorTexture`).
    pub base_colour: bool,
    /// The specular colour (MTL `map_Ks`).
    pub specular: bool,
    /// Roughness and metalness (glTF `metallicRoughnessTexture`).
    pub metallic_roughness: bool,
}

impl TextureSlots {
    /// No parameter is texturable.
    pub const NONE: Self = Self { base_colour: false, specular: false, metallic_roughness: false };
    /// Only the base colour.
    pub const BASE_COLOUR: Self = Self { base_colour: true, ..Self::NONE };
}

/// A material's texture values at one hit, each multiplying the parameter it drives
/// (glTF 2.0 § 3.9.2: "the texture value is multiplied by the factor"); `None` and 1 leave
/// the parameter as it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texels<const N: usize> {
    /// Multiplies the diffuse or base colour.
    pub base_colour: Option<SampledSpectrum<N>>,
    /// Multiplies the specular colour.
    pub specular: Option<SampledSpectrum<N>>,
    /// Multiplies the perceptual roughness (a texture's green channel in glTF).
    pub roughness: f32,
    /// Multiplies the metalness (a texture's blue channel in glTF).
    pub metallic: f32,
}

impl<const N: usize> Default for Texels<N> {
    fn default() -> Self {
        Self { base_colour: None, specular: None, roughness: 1.0, metallic: 1.0 }
    }
}

impl<const N: usize> Texels<N> {
    /// `value` (a parameter sampled at the path's wavelengths) times the base-colour texel.
    #[inline]
    pub fn base(&self, value: SampledSpectrum<N>) -> SampledSpectrum<N> {
        self.base_colour.map_or(value, |t| t * value)
    }

    /// `value` times the specular texel.
    #[inline]
    pub fn spec(&self, value: SampledSpectrum<N>) -> SampledSpectrum<N> {
        self.specular.map_or(value, |t| t * value)
    }
}

/// A BSDF model, implemented by its typed parameter struct.
pub trait Model: ParamSet + Clone + std::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// The BSDF bound to a path's wavelengths.
    type Bsdf<const N: usize>: Bsdf<N>;

    /// Its WGSL twin (see [`crate::wgsl`]).
    const WGSL: ModelWgsl;

    /// The BSDF at the path's wavelengths (or RGB channels).
    fn bsdf<const N: usize>(&self, wl: &SampledWavelengths<N>) -> Self::Bsdf<N>;

    /// The parameters textures may drive; a loader refuses a texture for any other.
    const TEXTURE_SLOTS: TextureSlots = TextureSlots::NONE;

    /// The BSDF with its [`TEXTURE_SLOTS`](Model::TEXTURE_SLOTS) parameters multiplied by
    /// a hit's texels; a model without slots ignores them.
    fn bsdf_textured<const N: usize>(&self, wl: &SampledWavelengths<N>, texels: &Texels<N>) -> Self::Bsdf<N> {
        let _ = texels;
        self.bsdf(wl)
    }

    /// True if light can pass through the surface: the BSDF then sees both sides as they
    /// are (no two-sided flipping), and the geometric normal marks the outside.
    fn is_transmissive(&self) -> bool {
        false
    }

    /// True if the index of refraction varies with wavelength: paths through the surface
    /// must follow a single wavelength.
    fn is_dispersive(&self) -> bool {
        false
    }

    /// The Beer–Lambert absorption coefficient inside a transmissive material, if any
    /// (borrowed: the integrator asks at every hit inside glass).
    fn absorption(&self) -> Option<&Colour> {
        None
    }
}

/// Generates, in the invoking module, the registry of the listed models
/// (`Variant(ParamsType)`, each `ParamsType: Model`):
///
/// * `ModelId` — names a model; `ALL` in list order (the GPU's model ids are indices
///   into it), `def()`, `wgsl()`, `name()`, `by_name()`, `resolve()`, `defaults()`,
///   `from_resolved()`;
/// * `ModelParams` — a model with its typed parameters (`From` each `ParamsType`), with
///   `bsdf::<N>()` and the surface properties;
/// * `ModelBsdf<N>` — the built BSDF, dispatched by `match`.
///
/// The built-in list is [`with_builtin_models!`](crate::with_builtin_models); a program
/// can register its own models beside them (see `tests/toy_model.rs`).
#[macro_export]
macro_rules! registry {
    ($( $Variant:ident($Params:ty) ),+ $(,)?) => {
        /// Names a registered BSDF model.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum ModelId {
            $(
                #[doc = concat!("The model whose parameters are [`", stringify!($Params), "`].")]
                $Variant,
            )+
        }

        impl ModelId {
            /// Every registered model, in registry order.
            pub const ALL: &'static [ModelId] = &[$(ModelId::$Variant),+];

            /// The model's parameter declaration.
            pub fn def(self) -> &'static $crate::params::ModelDef {
                match self {
                    $(Self::$Variant => &<$Params as $crate::params::ParamSet>::DEF,)+
                }
            }

            /// The model's WGSL twin.
            pub fn wgsl(self) -> &'static $crate::wgsl::ModelWgsl {
                match self {
                    $(Self::$Variant => &<$Params as $crate::Model>::WGSL,)+
                }
            }

            /// The model's name in scene files.
            pub fn name(self) -> &'static str {
                self.def().name
            }

            /// The model's position in [`ModelId::ALL`].
            pub fn index(self) -> u32 {
                self as u32
            }

            /// The model called `name` (case-insensitive).
            pub fn by_name(name: &str) -> Option<Self> {
                Self::ALL.iter().copied().find(|m| m.name().eq_ignore_ascii_case(name))
            }

            /// Every model's name, comma-separated (for messages).
            pub fn names() -> String {
                Self::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ")
            }

            /// Checks named values against the declaration and fills defaults.
            pub fn resolve(
                self,
                material: &str,
                given: &[(&str, $crate::params::ParamValue)],
            ) -> Result<ModelParams, $crate::params::ParamError> {
                Ok(match self {
                    $(Self::$Variant => ModelParams::$Variant(
                        <$Params as $crate::params::ParamSet>::resolve(material, given)?,
                    ),)+
                })
            }

            /// The typed form of parameters resolved against [`ModelId::def`].
            pub fn from_resolved(self, params: &$crate::params::ResolvedParams) -> ModelParams {
                match self {
                    $(Self::$Variant => ModelParams::$Variant(
                        <$Params as $crate::params::ParamSet>::from_resolved(params),
                    ),)+
                }
            }

            /// The model with all defaults.
            pub fn defaults(self) -> ModelParams {
                self.from_resolved(&self.def().defaults())
            }
        }

        /// A registered model with its typed parameters.
        #[derive(Clone, Debug, PartialEq)]
        #[allow(clippy::large_enum_variant)]
        pub enum ModelParams {
            $(
                #[doc = concat!("[`", stringify!($Params), "`].")]
                $Variant($Params),
            )+
        }

        $(
            impl From<$Params> for ModelParams {
                fn from(p: $Params) -> Self {
                    Self::$Variant(p)
                }
            }
        )+

        impl ModelParams {
            /// Which model.
            pub fn model(&self) -> ModelId {
                match self {
                    $(Self::$Variant(_) => ModelId::$Variant,)+
                }
            }

            /// The declaration-ordered form (what the GPU packs).
            pub fn to_resolved(&self) -> $crate::params::ResolvedParams {
                match self {
                    $(Self::$Variant(p) => $crate::params::ParamSet::to_resolved(p),)+
                }
            }

            /// The BSDF at the path's wavelengths.
            #[inline]
            pub fn bsdf<const N: usize>(&self, wl: &$crate::spectral::SampledWavelengths<N>) -> ModelBsdf<N> {
                match self {
                    $(Self::$Variant(p) => ModelBsdf::$Variant($crate::Model::bsdf(p, wl)),)+
                }
            }

            /// The BSDF with a hit's texture values (see [`Model::bsdf_textured`]($crate::Model::bsdf_textured)).
            #[inline]
            pub fn bsdf_textured<const N: usize>(
                &self,
                wl: &$crate::spectral::SampledWavelengths<N>,
                texels: &$crate::registry::Texels<N>,
            ) -> ModelBsdf<N> {
                match self {
                    $(Self::$Variant(p) => ModelBsdf::$Variant($crate::Model::bsdf_textured(p, wl, texels)),)+
                }
            }

            /// See [`Model::TEXTURE_SLOTS`]($crate::Model::TEXTURE_SLOTS).
            #[inline]
            pub fn texture_slots(&self) -> $crate::registry::TextureSlots {
                match self {
                    $(Self::$Variant(_) => <$Params as $crate::Model>::TEXTURE_SLOTS,)+
                }
            }

            /// See [`Model::is_transmissive`]($crate::Model::is_transmissive).
            #[inline]
            pub fn is_transmissive(&self) -> bool {
                match self {
                    $(Self::$Variant(p) => $crate::Model::is_transmissive(p),)+
                }
            }

            /// See [`Model::is_dispersive`]($crate::Model::is_dispersive).
            #[inline]
            pub fn is_dispersive(&self) -> bool {
                match self {
                    $(Self::$Variant(p) => $crate::Model::is_dispersive(p),)+
                }
            }

            /// See [`Model::absorption`]($crate::Model::absorption).
            #[inline]
            pub fn absorption(&self) -> Option<&$crate::params::Colour> {
                match self {
                    $(Self::$Variant(p) => $crate::Model::absorption(p),)+
                }
            }
        }

        /// The BSDF of a registered model, bound to a path's wavelengths.
        #[allow(clippy::large_enum_variant)]
        pub enum ModelBsdf<const N: usize> {
            $(
                #[doc = concat!("The BSDF of [`", stringify!($Params), "`].")]
                $Variant(<$Params as $crate::Model>::Bsdf<N>),
            )+
        }

        impl<const N: usize> $crate::Bsdf<N> for ModelBsdf<N> {
            #[inline]
            fn flags(&self) -> $crate::ScatterFlags {
                match self {
                    $(Self::$Variant(b) => b.flags(),)+
                }
            }
            #[inline]
            fn eval(&self, wo: $crate::glam::Vec3, wi: $crate::glam::Vec3) -> $crate::spectral::SampledSpectrum<N> {
                match self {
                    $(Self::$Variant(b) => b.eval(wo, wi),)+
                }
            }
            #[inline]
            fn pdf(&self, wo: $crate::glam::Vec3, wi: $crate::glam::Vec3) -> f32 {
                match self {
                    $(Self::$Variant(b) => b.pdf(wo, wi),)+
                }
            }
            #[inline]
            fn sample(
                &self,
                wo: $crate::glam::Vec3,
                uc: f32,
                u: $crate::glam::Vec2,
            ) -> Option<$crate::BsdfSample<N>> {
                match self {
                    $(Self::$Variant(b) => b.sample(wo, uc, u),)+
                }
            }
            #[inline]
            fn eta(&self) -> f32 {
                match self {
                    $(Self::$Variant(b) => b.eta(),)+
                }
            }
        }
    };
}
