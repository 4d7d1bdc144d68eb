//! The film: per-pixel running mean and variance of linear-sRGB samples.
//!
//! Each pixel keeps the thesis's progressive running mean g_i = g_{i−1} + (f_i − g_{i−1})/i
//! (eq. 7.2, written in the numerically stable order) together with Welford's sum of
//! squared deviations, so the standard error of the mean comes with every image.

/// One pixel's accumulator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelStats {
    /// Samples accumulated.
    pub count: u32,
    /// Running mean per channel.
    pub mean: [f64; 3],
    /// Welford's M2: Σ (x − mean)² per channel.
    pub m2: [f64; 3],
}

impl PixelStats {
    /// Adds one sample.
    #[inline]
    pub fn add(&mut self, rgb: [f32; 3]) {
        self.count += 1;
        let n = self.count as f64;
        for c in 0..3 {
            let x = rgb[c] as f64;
            let delta = x - self.mean[c];
            self.mean[c] += delta / n;
            self.m2[c] += delta * (x - self.mean[c]);
        }
    }

    /// Merges another accumulator of independent samples into this one (Chan, Golub &
    /// LeVeque's pairwise update of count, mean and M2), as if its samples had been
    /// [`PixelStats::add`]ed here; backends that accumulate a pass elsewhere (the GPU)
    /// merge it with this.
    pub fn merge(&mut self, other: &PixelStats) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 {
            *self = *other;
            return;
        }
        let (na, nb) = (self.count as f64, other.count as f64);
        let n = na + nb;
        for c in 0..3 {
            let delta = other.mean[c] - self.mean[c];
            self.mean[c] += delta * nb / n;
            self.m2[c] += other.m2[c] + delta * delta * na * nb / n;
        }
        self.count += other.count;
    }

    /// The standard error of the mean per channel (0 below two samples).
    pub fn std_error(&self) -> [f64; 3] {
        if self.count < 2 {
            return [0.0; 3];
        }
        let n = self.count as f64;
        self.m2.map(|m2| (m2 / (n - 1.0) / n).sqrt())
    }
}

/// A width × height grid of [`PixelStats`], row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    pixels: Vec<PixelStats>,
    /// Samples that were NaN or infinite and were dropped.
    pub non_finite: u64,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![PixelStats::default(); width as usize * height as usize], non_finite: 0 }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// All pixels, row-major.
    pub fn pixels(&self) -> &[PixelStats] {
        &self.pixels
    }

    /// Mutable pixels, row-major (backends write tiles through this).
    pub fn pixels_mut(&mut self) -> &mut [PixelStats] {
        &mut self.pixels
    }

    /// The pixel at (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> &PixelStats {
        &self.pixels[(y * self.width + x) as usize]
    }

    /// The mean image as linear-sRGB floats, row-major RGB.
    pub fn mean_rgb(&self) -> Vec<f32> {
        self.pixels.iter().flat_map(|p| p.mean.map(|v| v as f32)).collect()
    }

    /// The per-pixel standard error of the mean, row-major RGB.
    pub fn std_error_rgb(&self) -> Vec<f32> {
        self.pixels.iter().flat_map(|p| p.std_error().map(|v| v as f32)).collect()
    }

    /// The image-wide mean of each channel.
    pub fn channel_means(&self) -> [f64; 3] {
        let n = self.pixels.len().max(1) as f64;
        let mut sum = [0.0; 3];
        for p in &self.pixels {
            for c in 0..3 {
                sum[c] += p.mean[c];
            }
        }
        sum.map(|s| s / n)
    }

    /// Total accepted samples.
    pub fn samples(&self) -> u64 {
        self.pixels.iter().map(|p| p.count as u64).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_the_two_pass_formulas() {
        let xs = [0.5f32, 2.0, -1.0, 4.0, 3.5, 0.0];
        let mut p = PixelStats::default();
        for x in xs {
            p.add([x, 2.0 * x, 1.0]);
        }
        let mean = xs.iter().map(|&x| x as f64).sum::<f64>() / 6.0;
        let var = xs.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / 5.0;
        assert!((p.mean[0] - mean).abs() < 1e-12);
        assert!((p.std_error()[0] - (var / 6.0).sqrt()).abs() < 1e-12);
        assert!((p.std_error()[1] - 2.0 * (var / 6.0).sqrt()).abs() < 1e-12);
        assert_eq!(p.std_error()[2], 0.0);
    }
}
