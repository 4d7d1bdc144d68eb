//! Wavelength-dependent indices of refraction: Cauchy's formula and Sellmeier glasses,
//! for the dielectric's `dispersion` parameter.

crate::choice_param! {
    /// The `dispersion` parameter of a dielectric: how its index depends on wavelength.
    pub enum DispersionPreset {
        /// The same index at every wavelength.
        None = "none",
        /// Cauchy's n(λ) = A + B/λ², anchored at n(λ_d) = ior, B = `cauchy_b`.
        Cauchy = "cauchy",
        /// Schott N-BK7 ([`BK7`]; ignores ior).
        Bk7 = "bk7",
        /// Fused silica ([`FUSED_SILICA`]; ignores ior).
        FusedSilica = "fused-silica",
    }
}

/// Sellmeier coefficients n²(λ) = 1 + Σ Bᵢλ²/(λ² − Cᵢ), λ in µm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sellmeier {
    /// B₁, B₂, B₃.
    pub b: [f32; 3],
    /// C₁, C₂, C₃ in µm².
    pub c: [f32; 3],
}

/// Schott N-BK7 (Schott optical glass data sheet): n_d = 1.5168.
pub const BK7: Sellmeier =
    Sellmeier { b: [1.039_612, 0.231_792_34, 1.010_469_5], c: [0.006_000_699, 0.020_017_914, 103.560_65] };

/// Fused silica (Malitson 1965, JOSA 55(10)): n_d = 1.4585.
pub const FUSED_SILICA: Sellmeier =
    Sellmeier { b: [0.696_166_3, 0.407_942_6, 0.897_479_4], c: [0.004_679_148, 0.013_512_063, 97.934_003] };

impl Sellmeier {
    /// The index at `lambda_nm`.
    #[inline]
    pub fn ior(&self, lambda_nm: f32) -> f32 {
        let l2 = (lambda_nm * 1e-3).powi(2);
        let mut n2 = 1.0;
        for i in 0..3 {
            n2 += self.b[i] * l2 / (l2 - self.c[i]);
        }
        n2.max(1e-6).sqrt()
    }
}

/// The helium d-line, nm: where `ior` is the index for Cauchy dispersion (n_d).
pub const LAMBDA_D: f32 = 587.56;

/// How the index of refraction depends on wavelength.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Dispersion {
    /// The same index at every wavelength.
    #[default]
    None,
    /// Cauchy's n(λ) = A + B/λ² with B in µm² and n(λ_d) = the base index.
    Cauchy {
        /// B, µm².
        b: f32,
    },
    /// A Sellmeier glass (the base index is ignored).
    Sellmeier(Sellmeier),
}

impl Dispersion {
    /// The index at `lambda_nm` for base index `ior` (n_d).
    #[inline]
    pub fn ior(&self, ior: f32, lambda_nm: f32) -> f32 {
        match self {
            Self::None => ior,
            Self::Cauchy { b } => {
                let (l, ld) = (lambda_nm * 1e-3, LAMBDA_D * 1e-3);
                ior + b * (1.0 / (l * l) - 1.0 / (ld * ld))
            }
            Self::Sellmeier(s) => s.ior(lambda_nm),
        }
    }

    /// From the `dispersion` and `cauchy_b` parameters.
    pub fn from_preset(preset: DispersionPreset, cauchy_b: f32) -> Self {
        match preset {
            DispersionPreset::None => Self::None,
            DispersionPreset::Cauchy => Self::Cauchy { b: cauchy_b },
            DispersionPreset::Bk7 => Self::Sellmeier(BK7),
            DispersionPreset::FusedSilica => Self::Sellmeier(FUSED_SILICA),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sellmeier_presets_give_the_catalogue_indices() {
        // Catalogue n_d at 587.56 nm: N-BK7 1.5168, fused silica 1.4585.
        assert!((BK7.ior(LAMBDA_D) - 1.5168).abs() < 2e-4, "{}", BK7.ior(LAMBDA_D));
        assert!((FUSED_SILICA.ior(LAMBDA_D) - 1.4585).abs() < 2e-4, "{}", FUSED_SILICA.ior(LAMBDA_D));
        // Normal dispersion: blue bends more than red. Abbe number V_d = (n_d − 1)/(n_F − n_C):
        // N-BK7 64.17, fused silica 67.8.
        for (glass, abbe) in [(BK7, 64.17f32), (FUSED_SILICA, 67.8)] {
            let v = (glass.ior(LAMBDA_D) - 1.0) / (glass.ior(486.13) - glass.ior(656.27));
            assert!((v - abbe).abs() < 0.5, "Abbe {v} vs {abbe}");
        }
    }

    #[test]
    fn cauchy_is_anchored_at_the_d_line() {
        let d = Dispersion::Cauchy { b: 0.0042 };
        assert!((d.ior(1.5, LAMBDA_D) - 1.5).abs() < 1e-6);
        assert!(d.ior(1.5, 450.0) > 1.5 && d.ior(1.5, 650.0) < 1.5);
        assert_eq!(Dispersion::None.ior(1.33, 400.0), 1.33);
    }
}
