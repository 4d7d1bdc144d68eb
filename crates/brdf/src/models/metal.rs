//! Metals: the exact Fresnel reflectance of a complex index η + iκ and the measured n, k
//! of four metals, for the conductor models.
//!
//! Measured data (linear interpolation in wavelength between the papers' own sample
//! points, clamped outside the table; every table spans at least 360–830 nm):
//!
//! * gold, silver, copper: P. B. Johnson & R. W. Christy, "Optical Constants of the
//!   Noble Metals", Phys. Rev. B 6, 4370 (1972), room temperature, at their photon
//!   energies 3.50, 3.37, …, 1.39 eV (354.2–892.0 nm, 18 points, 14–71 nm apart);
//! * aluminium: A. D. Rakić, "Algorithm for the determination of intrinsic optical
//!   constants of metal films: application to aluminum", Appl. Opt. 34, 4755 (1995),
//!   at its points from 326.3 to 837.7 nm (16 points, 20–48 nm apart).
//!
//! Both were transcribed from the refractiveindex.info database (public domain, CC0;
//! files `data-nk/main/{Au,Ag,Cu}/Johnson.yml` and `data-nk/main/Al/Rakic.yml`),
//! wavelengths converted from µm to nm, values unchanged.
//!
//! In RGB mode (no wavelengths) n and k are taken at [`RGB_LAMBDA`] = 630, 532 and
//! 465 nm for the R, G and B channels: a crude stand-in, as in RGB renderers.

use spectral::{SampledSpectrum, SampledWavelengths};

crate::choice_param! {
    /// The `metal` parameter of the conductor models: a measured metal, or custom constants.
    pub enum MetalPreset {
        /// The parameters' own η and κ, at every wavelength.
        Custom = "custom",
        /// [`Metal::Gold`].
        Gold = "gold",
        /// [`Metal::Silver`].
        Silver = "silver",
        /// [`Metal::Copper`].
        Copper = "copper",
        /// [`Metal::Aluminium`].
        Aluminium = "aluminium",
    }
}

impl MetalPreset {
    /// The measured metal, or `None` for custom constants.
    pub fn metal(self) -> Option<Metal> {
        match self {
            Self::Custom => None,
            Self::Gold => Some(Metal::Gold),
            Self::Silver => Some(Metal::Silver),
            Self::Copper => Some(Metal::Copper),
            Self::Aluminium => Some(Metal::Aluminium),
        }
    }

    /// (η, κ) at the path's wavelengths: the measured metal's, or the constants `eta`, `k`.
    pub fn eta_k<const N: usize>(
        self,
        eta: f32,
        k: f32,
        wl: &SampledWavelengths<N>,
    ) -> (SampledSpectrum<N>, SampledSpectrum<N>) {
        match self.metal() {
            Some(m) => m.sample(wl),
            None => (SampledSpectrum::splat(eta), SampledSpectrum::splat(k)),
        }
    }
}

/// Wavelengths (nm) at which n and k are taken for the R, G and B channels in RGB mode.
pub const RGB_LAMBDA: [f32; 3] = [630.0, 532.0, 465.0];

/// Exact unpolarised Fresnel reflectance (R⊥ + R∥)/2 of a conductor of complex relative
/// index η + iκ, for light at `cos_i` to the normal (either side; |cos_i| is used).
///
/// The real closed form of the complex Fresnel equations (Born & Wolf, *Principles of
/// Optics*, 7th ed., ch. 14 "Optics of metals"; pbrt-v3 §8.2.1; pbrt-v4 §9.3 evaluates the
/// same equations in complex arithmetic, which the tests compare against):
/// a² + b² = √((η² − κ² − sin²θ)² + 4η²κ²), a² = (a² + b² + η² − κ² − sin²θ)/2,
/// R⊥ = (a² + b² − 2a cos θ + cos²θ) / (a² + b² + 2a cos θ + cos²θ),
/// R∥ = R⊥ (cos²θ (a² + b²) − 2a cos θ sin²θ + sin⁴θ) / (cos²θ (a² + b²) + 2a cos θ sin²θ + sin⁴θ).
/// a² is computed without cancellation. κ = 0 gives the dielectric formula, with total
/// internal reflection (R = 1) for η < 1.
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c = cos_i.abs().min(1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let (e2, k2) = (eta * eta, k * k);
    let t0 = e2 - k2 - s2;
    let a2b2 = (t0 * t0 + 4.0 * e2 * k2).sqrt();
    // a² = (a²+b² + t0)/2; for t0 < 0 use the equivalent 2η²κ²/(a²+b² − t0).
    let a2 = if t0 >= 0.0 { 0.5 * (a2b2 + t0) } else { 2.0 * e2 * k2 / (a2b2 - t0) };
    let a = a2.max(0.0).sqrt();
    let (t1, t2) = (a2b2 + c2, 2.0 * a * c);
    if t1 + t2 <= 0.0 {
        // η = 1, κ = 0 exactly at grazing incidence: the grazing limit.
        return 1.0;
    }
    let rs = (t1 - t2) / (t1 + t2);
    let (t3, t4) = (c2 * a2b2 + s2 * s2, t2 * s2);
    let rp = if t3 + t4 > 0.0 { rs * (t3 - t4) / (t3 + t4) } else { rs };
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}

/// A metal with measured optical constants (see the module documentation for sources).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Metal {
    /// Au, Johnson & Christy 1972.
    Gold,
    /// Ag, Johnson & Christy 1972.
    Silver,
    /// Cu, Johnson & Christy 1972.
    Copper,
    /// Al, Rakić 1995.
    Aluminium,
}

/// Au, Johnson & Christy 1972: (λ nm, n, k).
const AU: [[f32; 3]; 18] = [
    [354.2, 1.50, 1.866],
    [367.9, 1.48, 1.895],
    [381.5, 1.46, 1.933],
    [397.4, 1.47, 1.952],
    [413.3, 1.46, 1.958],
    [430.5, 1.45, 1.948],
    [450.9, 1.38, 1.914],
    [471.4, 1.31, 1.849],
    [495.9, 1.04, 1.833],
    [520.9, 0.62, 2.081],
    [548.6, 0.43, 2.455],
    [582.1, 0.29, 2.863],
    [616.8, 0.21, 3.272],
    [659.5, 0.14, 3.697],
    [704.5, 0.13, 4.103],
    [756.0, 0.14, 4.542],
    [821.1, 0.16, 5.083],
    [892.0, 0.17, 5.663],
];

/// Ag, Johnson & Christy 1972: (λ nm, n, k).
const AG: [[f32; 3]; 18] = [
    [354.2, 0.10, 1.419],
    [367.9, 0.07, 1.657],
    [381.5, 0.05, 1.864],
    [397.4, 0.05, 2.070],
    [413.3, 0.05, 2.275],
    [430.5, 0.04, 2.462],
    [450.9, 0.04, 2.657],
    [471.4, 0.05, 2.869],
    [495.9, 0.05, 3.093],
    [520.9, 0.05, 3.324],
    [548.6, 0.06, 3.586],
    [582.1, 0.05, 3.858],
    [616.8, 0.06, 4.152],
    [659.5, 0.05, 4.483],
    [704.5, 0.04, 4.838],
    [756.0, 0.03, 5.242],
    [821.1, 0.04, 5.727],
    [892.0, 0.04, 6.312],
];

/// Cu, Johnson & Christy 1972: (λ nm, n, k).
const CU: [[f32; 3]; 18] = [
    [354.2, 1.37, 1.916],
    [367.9, 1.36, 1.975],
    [381.5, 1.33, 2.045],
    [397.4, 1.32, 2.116],
    [413.3, 1.28, 2.207],
    [430.5, 1.25, 2.305],
    [450.9, 1.24, 2.397],
    [471.4, 1.25, 2.483],
    [495.9, 1.22, 2.564],
    [520.9, 1.18, 2.608],
    [548.6, 1.02, 2.577],
    [582.1, 0.70, 2.704],
    [616.8, 0.30, 3.205],
    [659.5, 0.22, 3.747],
    [704.5, 0.21, 4.205],
    [756.0, 0.24, 4.665],
    [821.1, 0.26, 5.180],
    [892.0, 0.30, 5.768],
];

/// Al, Rakić 1995: (λ nm, n, k).
const AL: [[f32; 3]; 16] = [
    [326.28, 0.31474, 3.9165],
    [364.66, 0.39877, 4.3957],
    [413.28, 0.52135, 5.0008],
    [442.80, 0.60790, 5.3676],
    [476.87, 0.72780, 5.7781],
    [516.60, 0.87340, 6.2418],
    [563.57, 1.0728, 6.7839],
    [619.93, 1.3660, 7.4052],
    [652.25, 1.5724, 7.7354],
    [688.81, 1.8301, 8.0601],
    [729.32, 2.1606, 8.3565],
    [774.91, 2.6154, 8.4914],
    [794.78, 2.7675, 8.3866],
    [815.69, 2.7668, 8.2573],
    [837.74, 2.6945, 8.1878],
    [885.61, 2.2802, 8.1134],
];

/// Linear interpolation in a (λ, n, k) table, clamped to its ends (a loop, no search
/// structure: the tables are short and the same code runs in WGSL).
#[inline]
fn interpolate(table: &[[f32; 3]], lambda: f32) -> (f32, f32) {
    let last = table.len() - 1;
    if lambda.is_nan() || lambda <= table[0][0] {
        // Below the table, or NaN.
        return (table[0][1], table[0][2]);
    }
    if lambda >= table[last][0] {
        return (table[last][1], table[last][2]);
    }
    let mut i = 0;
    while i + 1 < last && table[i + 1][0] <= lambda {
        i += 1;
    }
    let (a, b) = (table[i], table[i + 1]);
    let t = (lambda - a[0]) / (b[0] - a[0]);
    (a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2]))
}

impl Metal {
    /// Every preset, in the order of the `metal` parameter (1, 2, 3, 4).
    pub const ALL: [Metal; 4] = [Metal::Gold, Metal::Silver, Metal::Copper, Metal::Aluminium];

    /// English name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Gold => "gold",
            Self::Silver => "silver",
            Self::Copper => "copper",
            Self::Aluminium => "aluminium",
        }
    }

    /// The measured rows (λ nm, n, k), increasing in λ, that [`Metal::eta_k`]
    /// interpolates: for code generators (the GPU crate uploads them as they are).
    pub fn table(self) -> &'static [[f32; 3]] {
        match self {
            Self::Gold => &AU,
            Self::Silver => &AG,
            Self::Copper => &CU,
            Self::Aluminium => &AL,
        }
    }

    /// (n, k) at `lambda_nm`, linearly interpolated, clamped outside the data.
    #[inline]
    pub fn eta_k(self, lambda_nm: f32) -> (f32, f32) {
        interpolate(self.table(), lambda_nm)
    }

    /// (n, k) at the path's wavelengths, or at [`RGB_LAMBDA`] in RGB mode.
    pub fn sample<const N: usize>(self, wl: &SampledWavelengths<N>) -> (SampledSpectrum<N>, SampledSpectrum<N>) {
        let (mut eta, mut k) = (SampledSpectrum::zero(), SampledSpectrum::zero());
        for i in 0..N {
            let lambda = if wl.is_rgb() { RGB_LAMBDA[i.min(2)] } else { wl.lambda[i] };
            (eta[i], k[i]) = self.eta_k(lambda);
        }
        (eta, k)
    }
}

/// Per-wavelength conductor Fresnel reflectance times a tint.
#[inline]
pub(crate) fn fresnel_spectrum<const N: usize>(
    cos_i: f32,
    eta: &SampledSpectrum<N>,
    k: &SampledSpectrum<N>,
    tint: &SampledSpectrum<N>,
) -> SampledSpectrum<N> {
    let mut f = SampledSpectrum::zero();
    for i in 0..N {
        f[i] = tint[i] * fresnel_conductor(cos_i, eta[i], k[i]);
    }
    f
}

#[cfg(test)]
mod tests;
