//! Continuous spectra: functions of wavelength (nm) that materials and lights are made of.

// Published constants are kept at the precision they were published with.
#![allow(clippy::excessive_precision)]

use crate::SpectralError;
use crate::colour::{spectrum_to_linear_srgb, spectrum_to_xyz, xyz_to_linear_srgb};
use crate::sampled::{SampledSpectrum, SampledWavelengths};
use crate::tables::{D65, D65_LAMBDA_MIN, D65_LAMBDA_STEP, DAYLIGHT_LAMBDA_MIN, DAYLIGHT_LAMBDA_STEP, DAYLIGHT_S};
use crate::uplift::{RgbAlbedoSpectrum, RgbIlluminantSpectrum, d65_normalised};

/// A piecewise-linear spectrum through (λ, value) samples, held constant beyond its ends
/// (so that a table given for 380–770 nm still covers the 360–830 nm the renderer samples).
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedSpectrum {
    lambda: Vec<f32>,
    value: Vec<f32>,
}

impl TabulatedSpectrum {
    /// Builds a table; wavelengths must be finite and strictly increasing, values finite.
    pub fn new(lambda: Vec<f32>, value: Vec<f32>) -> Result<Self, SpectralError> {
        if lambda.is_empty() || lambda.len() != value.len() {
            return Err(SpectralError::BadTable(format!(
                "need as many values as wavelengths (≥ 1), got {} and {}",
                lambda.len(),
                value.len()
            )));
        }
        if let Some(w) = lambda.windows(2).find(|w| w[0] >= w[1] || w[0].is_nan()) {
            return Err(SpectralError::BadTable(format!(
                "wavelengths must increase strictly, found {} then {}",
                w[0], w[1]
            )));
        }
        if let Some(&v) = lambda.iter().chain(&value).find(|v| !v.is_finite()) {
            return Err(SpectralError::BadValue { what: "tabulated spectrum entry", value: v });
        }
        Ok(Self { lambda, value })
    }

    /// Linear interpolation, clamped to the end values.
    pub fn eval(&self, lambda: f32) -> f32 {
        let i = self.lambda.partition_point(|&l| l <= lambda);
        if i == 0 {
            return self.value[0];
        }
        if i == self.lambda.len() {
            return self.value[i - 1];
        }
        let (l0, l1) = (self.lambda[i - 1], self.lambda[i]);
        let t = (lambda - l0) / (l1 - l0);
        self.value[i - 1] + t * (self.value[i] - self.value[i - 1])
    }
}

/// Planck's law: spectral radiance of a black body at `kelvin`, W·sr⁻¹·m⁻²·nm⁻¹.
pub fn planck(lambda_nm: f32, kelvin: f32) -> f32 {
    const H: f64 = 6.626_070_15e-34;
    const C: f64 = 299_792_458.0;
    const KB: f64 = 1.380_649e-23;
    let l = lambda_nm as f64 * 1e-9;
    let v = 2.0 * H * C * C / (l.powi(5) * ((H * C / (l * KB * kelvin as f64)).exp() - 1.0));
    (v * 1e-9) as f32
}

/// A table of samples every `step` nm from `first` nm at `lambda`: linear in between, zero
/// outside.
fn sampled_table(table: &[f32], first: f32, step: f32, lambda: f32) -> f32 {
    let x = (lambda - first) / step;
    if !(0.0..=(table.len() - 1) as f32).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(table.len() - 2);
    let f = x - i as f32;
    table[i] + f * (table[i + 1] - table[i])
}

/// CIE standard illuminant D65, relative power (100 at 560 nm), linear between 5 nm samples.
pub fn d65(lambda: f32) -> f32 {
    sampled_table(&D65, D65_LAMBDA_MIN, D65_LAMBDA_STEP, lambda)
}

/// CIE standard illuminant A: a Planckian radiator at 2856 K with c₂ = 1.4388e-2 m·K
/// (CIE 15:2018 §3.1), relative power 100 at 560 nm.
pub fn illuminant_a(lambda: f32) -> f32 {
    const C2: f64 = 1.4388e-2;
    const T: f64 = 2856.0;
    let f = |l: f64| l.powi(-5) / ((C2 / (l * T)).exp() - 1.0);
    (100.0 * f(lambda as f64 * 1e-9) / f(560e-9)) as f32
}

/// The weights (M₁, M₂) of the daylight components for a CIE D illuminant of correlated
/// colour temperature `kelvin` (CIE 15:2018 §3.1, eqs. 3.3–3.6: the chromaticity x_D of
/// the daylight locus, y_D = −3x_D² + 2.870x_D − 0.275, then M₁ and M₂); 4000–25000 K.
pub fn daylight_weights(kelvin: f64) -> (f64, f64) {
    let t = kelvin.clamp(4000.0, 25_000.0);
    let x = if t <= 7000.0 {
        -4.6070e9 / t.powi(3) + 2.9678e6 / t.powi(2) + 0.09911e3 / t + 0.244063
    } else {
        -2.0064e9 / t.powi(3) + 1.9018e6 / t.powi(2) + 0.24748e3 / t + 0.237040
    };
    let y = -3.0 * x * x + 2.870 * x - 0.275;
    let m = 0.0241 + 0.2562 * x - 0.7341 * y;
    ((-1.3515 - 1.7703 * x + 5.9114 * y) / m, (0.0300 - 31.4424 * x + 30.0717 * y) / m)
}

/// A CIE D illuminant (relative power 100 at 560 nm) of correlated colour temperature
/// `kelvin` from the daylight components, linear between their 10 nm samples; D50 is
/// 5003 K, D55 5503 K, D65 6504 K, D75 7504 K (the 1968 temperatures times 1.4388/1.4380).
pub fn daylight(lambda: f32, kelvin: f32) -> f32 {
    let (m1, m2) = daylight_weights(kelvin as f64);
    let at = |s: &[f32; 3]| s[0] as f64 + m1 * s[1] as f64 + m2 * s[2] as f64;
    let x = (lambda - DAYLIGHT_LAMBDA_MIN) / DAYLIGHT_LAMBDA_STEP;
    if !(0.0..=(DAYLIGHT_S.len() - 1) as f32).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(DAYLIGHT_S.len() - 2);
    let f = (x - i as f32) as f64;
    let v = at(&DAYLIGHT_S[i]) * (1.0 - f) + at(&DAYLIGHT_S[i + 1]) * f;
    // Normalised to 100 at 560 nm, where S₀ = 100 and S₁ = S₂ = 0 (index 26).
    (v * 100.0 / at(&DAYLIGHT_S[26])) as f32
}

/// CIE fluorescent illuminant F`number` (1–12: CIE 15:2018 Table 10) at `lambda`, scaled
/// to luminance Y = 1 (as [`Spectrum::D65`] is), linear between its 5 nm samples and zero
/// outside 380–780 nm; 0 for a number outside 1–12.
pub fn fluorescent(number: u8, lambda: f32) -> f32 {
    use crate::tables::fluorescent::{FLUORESCENT, FLUORESCENT_LAMBDA_MIN, FLUORESCENT_LAMBDA_STEP};
    use std::sync::OnceLock;
    static NORMALISERS: OnceLock<[f32; 12]> = OnceLock::new();
    let raw = |table: &[f32], lambda| sampled_table(table, FLUORESCENT_LAMBDA_MIN, FLUORESCENT_LAMBDA_STEP, lambda);
    let Some(table) = FLUORESCENT.get((number as usize).wrapping_sub(1)) else { return 0.0 };
    let normalisers =
        NORMALISERS.get_or_init(|| std::array::from_fn(|k| 1.0 / spectrum_to_xyz(|l| raw(&FLUORESCENT[k], l))[1]));
    raw(table, lambda) * normalisers[number as usize - 1]
}

/// A spectrum, by kind; every variant evaluates in O(1) or O(log n).
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength (CIE illuminant E when used as a light).
    Constant(f32),
    /// A measured or hand-written table.
    Tabulated(TabulatedSpectrum),
    /// CIE D65 scaled to luminance Y = `0` (so that `D65(1.0)` is an sRGB-white light of Y = 1).
    D65(f32),
    /// CIE illuminant A, relative power 100 at 560 nm, times the factor.
    IlluminantA(f32),
    /// A CIE fluorescent illuminant F1–F12 ([`fluorescent`], luminance 1) times a factor.
    Fluorescent {
        /// 1–12.
        number: u8,
        /// Factor (the luminance).
        scale: f32,
    },
    /// A CIE D illuminant ([`daylight`]: relative power 100 at 560 nm) times a factor.
    Daylight {
        /// Correlated colour temperature, kelvin (5003 for D50).
        kelvin: f32,
        /// Factor.
        scale: f32,
    },
    /// Planck's black body at a temperature (K), normalised to peak 1, times the factor.
    Blackbody {
        /// Temperature, kelvin.
        kelvin: f32,
        /// Factor applied after normalising the peak to 1.
        scale: f32,
    },
    /// A reflectance uplifted from RGB.
    RgbAlbedo(RgbAlbedoSpectrum),
    /// An emission spectrum uplifted from RGB.
    RgbIlluminant(RgbIlluminantSpectrum),
    /// An unbounded non-negative coefficient (e.g. an absorption coefficient) uplifted
    /// from RGB as `scale` × a reflectance-shaped spectrum.
    RgbUnbounded {
        /// The largest RGB component.
        scale: f32,
        /// The shape, uplifted from RGB / scale.
        shape: RgbAlbedoSpectrum,
    },
}

impl Spectrum {
    /// The spectrum's value at `lambda` nm.
    pub fn eval(&self, lambda: f32) -> f32 {
        match self {
            Self::Constant(v) => *v,
            Self::Tabulated(t) => t.eval(lambda),
            Self::D65(s) => s * d65_normalised(lambda),
            Self::IlluminantA(s) => s * illuminant_a(lambda),
            Self::Daylight { kelvin, scale } => scale * daylight(lambda, *kelvin),
            Self::Fluorescent { number, scale } => scale * fluorescent(*number, lambda),
            Self::Blackbody { kelvin, scale } => {
                // Wien's displacement law gives the peak: λ_max = b / T.
                let peak = 2.897_771_955e6 / kelvin;
                scale * planck(lambda, *kelvin) / planck(peak, *kelvin)
            }
            Self::RgbAlbedo(s) => s.eval(lambda),
            Self::RgbIlluminant(s) => s.eval(lambda),
            Self::RgbUnbounded { scale, shape } => scale * shape.eval(lambda),
        }
    }
}

/// Whether a colour reflects light (and is seen under D65) or emits it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourRole {
    /// A reflectance or transmittance in [0, 1].
    Reflectance,
    /// A radiance or power spectrum.
    Illuminant,
}

/// A material or light colour ready for any [`crate::SpectralMode`]: its spectrum for the
/// spectral modes and its linear-sRGB value for RGB mode, both fixed at load time.
#[derive(Clone, Debug, PartialEq)]
pub struct Colour {
    /// The spectrum the spectral modes sample.
    pub spectrum: Spectrum,
    /// The linear-sRGB value RGB mode uses.
    pub rgb: [f32; 3],
}

impl Colour {
    /// A reflectance from linear sRGB, uplifted by Jakob & Hanika 2019; RGB mode uses
    /// `rgb` itself.
    pub fn reflectance_rgb(rgb: [f32; 3]) -> Result<Self, SpectralError> {
        let spectrum = if rgb[0] == rgb[1] && rgb[1] == rgb[2] && (0.0..=1.0).contains(&rgb[0]) {
            Spectrum::Constant(rgb[0])
        } else {
            Spectrum::RgbAlbedo(RgbAlbedoSpectrum::new(rgb)?)
        };
        Ok(Self { spectrum, rgb })
    }

    /// An emitted radiance from linear sRGB: the uplifted colour times D65 (so that
    /// white stays white); RGB mode uses `rgb` itself.
    pub fn illuminant_rgb(rgb: [f32; 3]) -> Result<Self, SpectralError> {
        Ok(Self { spectrum: Spectrum::RgbIlluminant(RgbIlluminantSpectrum::new(rgb)?), rgb })
    }

    /// An unbounded non-negative coefficient from RGB (an absorption coefficient, say):
    /// max(rgb) × the reflectance spectrum of rgb / max(rgb). Not multiplied by any
    /// illuminant, unlike [`Colour::illuminant_rgb`].
    pub fn unbounded_rgb(rgb: [f32; 3]) -> Result<Self, SpectralError> {
        if let Some(&v) = rgb.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(SpectralError::BadValue { what: "coefficient", value: v });
        }
        let scale = rgb.iter().copied().fold(0.0, f32::max);
        if scale == 0.0 {
            return Ok(Self::constant(0.0));
        }
        let shape = RgbAlbedoSpectrum::new(rgb.map(|v| v / scale))?;
        Ok(Self { spectrum: Spectrum::RgbUnbounded { scale, shape }, rgb })
    }

    /// A colour given as a spectrum; its RGB-mode value is the spectrum's sRGB colour:
    /// lit by D65 for a reflectance, as is for an illuminant.
    pub fn from_spectrum(spectrum: Spectrum, role: ColourRole) -> Self {
        let rgb = match role {
            ColourRole::Reflectance => {
                // D65 is sRGB's own white: no chromatic adaptation is needed.
                xyz_to_linear_srgb(spectrum_to_xyz(|l| spectrum.eval(l) * d65_normalised(l)))
            }
            ColourRole::Illuminant => spectrum_to_linear_srgb(|l| spectrum.eval(l)),
        };
        Self { spectrum, rgb }
    }

    /// A constant colour (grey reflectance or equal-energy light of this value in RGB).
    pub fn constant(v: f32) -> Self {
        Self { spectrum: Spectrum::Constant(v), rgb: [v; 3] }
    }

    /// True if the colour is black (its sRGB value is zero): nothing visible to emit.
    pub fn is_black(&self) -> bool {
        self.rgb == [0.0; 3]
    }

    /// The colour at the sampled wavelengths (or channels, in RGB mode).
    #[inline]
    pub fn sample<const N: usize>(&self, wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
        if wl.is_rgb() {
            return SampledSpectrum(std::array::from_fn(|i| self.rgb.get(i).copied().unwrap_or(0.0)));
        }
        match &self.spectrum {
            Spectrum::Constant(v) => SampledSpectrum::splat(*v),
            Spectrum::RgbAlbedo(s) => wl.eval(|l| s.eval(l)),
            Spectrum::RgbIlluminant(s) => wl.eval(|l| s.eval(l)),
            other => wl.eval(|l| other.eval(l)),
        }
    }

    /// Luminance-like scalar for light selection by power: Y of the RGB value.
    pub fn luminance(&self) -> f32 {
        0.212_639 * self.rgb[0] + 0.715_168_7 * self.rgb[1] + 0.072_192_3 * self.rgb[2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::colour::xyz_to_linear_srgb;

    #[test]
    fn daylight_from_its_components_is_the_d65_table_and_d50_has_its_white_point() {
        // D65 at 6504 K from S0, S1, S2 against the tabulated D65 (a typo in either table
        // shows here): within 0.2 % over the visible range at the 10 nm samples.
        for l in (380..=780).step_by(10) {
            let (a, b) = (daylight(l as f32, 6504.0), d65(l as f32));
            assert!((a - b).abs() < 2e-3 * b, "{l} nm: {a} vs D65 {b}");
        }
        // CIE 15:2018 Table T.3 white points (x, y), CIE 1931 observer.
        for (kelvin, x, y) in [(5003.0, 0.34567, 0.35851), (5503.0, 0.33243, 0.34744), (7504.0, 0.29903, 0.31488)] {
            let xyz = spectrum_to_xyz(|l| daylight(l, kelvin));
            let sum = xyz[0] + xyz[1] + xyz[2];
            let (cx, cy) = (xyz[0] / sum, xyz[1] / sum);
            assert!((cx - x).abs() < 3e-4 && (cy - y).abs() < 3e-4, "{kelvin} K: ({cx}, {cy}) vs ({x}, {y})");
        }
        assert_eq!(daylight(560.0, 5003.0), 100.0);
        assert_eq!(daylight(200.0, 5003.0), 0.0);
    }

    #[test]
    fn fluorescent_illuminants_have_their_white_points_and_unit_luminance() {
        // CIE 15:2018 Table T.8 (x, y), CIE 1931 observer.
        for (number, x, y) in [(2u8, 0.37208, 0.37529), (7, 0.31292, 0.32933), (11, 0.38052, 0.37713)] {
            let xyz = spectrum_to_xyz(|l| fluorescent(number, l));
            let sum = xyz[0] + xyz[1] + xyz[2];
            let (cx, cy) = (xyz[0] / sum, xyz[1] / sum);
            assert!((cx - x).abs() < 3e-4 && (cy - y).abs() < 3e-4, "F{number}: ({cx}, {cy}) vs ({x}, {y})");
            assert!((xyz[1] - 1.0).abs() < 1e-4, "F{number}: Y = {}", xyz[1]);
        }
        // F11 is a tri-band lamp: its 545 nm line stands far above its neighbourhood.
        assert!(fluorescent(11, 545.0) > 5.0 * fluorescent(11, 520.0));
        assert_eq!((fluorescent(0, 500.0), fluorescent(13, 500.0), fluorescent(2, 300.0)), (0.0, 0.0, 0.0));
    }

    #[test]
    fn d65_is_neutral_white_in_linear_srgb() {
        let rgb = xyz_to_linear_srgb(spectrum_to_xyz(d65_normalised));
        for c in rgb {
            assert!((c - 1.0).abs() < 1e-3, "D65 → {rgb:?}");
        }
    }

    #[test]
    fn illuminant_a_is_warm_and_e_is_not_white_in_srgb() {
        let a = spectrum_to_linear_srgb(illuminant_a);
        assert!(a[0] > a[1] && a[1] > a[2], "A should be orange: {a:?}");
        // Equal energy is warmer than sRGB's D65 white: about (1.21, 0.95, 0.91) at Y = 1.
        let e = spectrum_to_linear_srgb(|_| 1.0);
        assert!(e[0] > 1.15 && e[1] < 1.0 && e[2] < 1.0, "E: {e:?}");
    }

    #[test]
    fn tabulated_interpolates_and_clamps() {
        let t = TabulatedSpectrum::new(vec![400.0, 500.0, 600.0], vec![0.0, 1.0, 0.5]).unwrap();
        assert_eq!(t.eval(450.0), 0.5);
        assert_eq!(t.eval(550.0), 0.75);
        assert_eq!(t.eval(300.0), 0.0);
        assert_eq!(t.eval(900.0), 0.5);
        assert_eq!(t.eval(500.0), 1.0);
        assert!(TabulatedSpectrum::new(vec![400.0, 400.0], vec![1.0, 1.0]).is_err());
        assert!(TabulatedSpectrum::new(vec![400.0], vec![]).is_err());
        assert!(TabulatedSpectrum::new(vec![400.0], vec![f32::NAN]).is_err());
    }

    #[test]
    fn blackbody_peaks_at_one() {
        let b = Spectrum::Blackbody { kelvin: 5000.0, scale: 1.0 };
        let peak = 2.897_771_955e6 / 5000.0;
        assert!((b.eval(peak) - 1.0).abs() < 1e-5);
        assert!(b.eval(peak - 20.0) < 1.0 && b.eval(peak + 20.0) < 1.0);
    }

    #[test]
    fn grey_reflectance_is_constant_and_rgb_mode_uses_rgb() {
        let c = Colour::reflectance_rgb([0.5; 3]).unwrap();
        assert_eq!(c.spectrum, Spectrum::Constant(0.5));
        let s = c.sample(&SampledWavelengths::<3>::rgb());
        assert_eq!(s.0, [0.5; 3]);
    }
}
