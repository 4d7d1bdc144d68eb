//! Spectral colour for a physically based renderer.
//!
//! * [`tables`]: CIE 1931 2° colour-matching functions and the D65 illuminant;
//! * [`colour`]: CIE XYZ ↔ linear sRGB (D65 white) and the sRGB transfer curve;
//! * [`spectrum`]: continuous spectra (constant, tabulated, blackbody, CIE illuminants);
//! * [`uplift`]: RGB → spectrum (Jakob & Hanika 2019 sigmoid polynomials) for
//!   reflectances and emitters;
//! * [`sampled`]: spectra at a few sampled wavelengths, the per-path currency of the
//!   integrator, and the wavelength-sampling strategies ([`SpectralMode`]);
//! * [`thesis`]: the seed thesis's own tables and SPD → RGB method, kept to show where
//!   it goes wrong.
//!
//! This crate knows nothing of rays or scenes.
//!
//! Citations: "the thesis", "the lecture" and the papers named in comments are listed in `docs/references.md`.

pub mod colour;
pub mod sampled;
pub mod spectrum;
pub mod tables;
pub mod thesis;
pub mod uplift;

pub use colour::{srgb_encode, srgb_to_u8, xyz_to_linear_srgb};
pub use sampled::{SampledSpectrum, SampledWavelengths, SpectralMode};
pub use spectrum::Spectrum;
pub use uplift::{RgbAlbedoSpectrum, RgbIlluminantSpectrum, SigmoidPolynomial};

/// Errors from building spectra.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectralError {
    /// A tabulated spectrum needs at least one sample and strictly increasing wavelengths.
    #[error("tabulated spectrum: {0}")]
    BadTable(String),
    /// A value that must be finite (and, where said, non-negative) was not.
    #[error("{what} must be finite and non-negative, got {value}")]
    BadValue {
        /// What the value is.
        what: &'static str,
        /// The offending value.
        value: f32,
    },
    /// An RGB reflectance outside [0, 1]³ cannot be uplifted to a reflectance spectrum.
    #[error("RGB reflectance {rgb:?} is outside [0, 1]: reflectances must lie in [0, 1]")]
    ReflectanceOutOfRange {
        /// The offending colour.
        rgb: [f32; 3],
    },
    /// The Gauss–Newton fit of the sigmoid polynomial did not converge.
    #[error("RGB → spectrum fit did not converge for {rgb:?} (residual {residual})")]
    UpliftDidNotConverge {
        /// The colour being fitted.
        rgb: [f32; 3],
        /// The remaining CIELAB residual norm.
        residual: f32,
    },
}
