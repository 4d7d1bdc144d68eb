//! Environment maps: light from every direction read from a latitude–longitude image
//! (EXR or HDR for high dynamic range; PNG and JPEG are read as sRGB), importance-sampled
//! in proportion to luminance × sin θ.
//!
//! Directions map to the image with y up: v = θ/π from the zenith (top row) to the nadir
//! (bottom row), u = ½ + φ/2π with φ = atan2(x, −z), so that the image's centre lies in
//! the −z direction (where the default camera looks) and u grows towards +x. A rotation
//! about the vertical axis turns the map (degrees, counter-clockwise seen from above).
//!
//! Radiance is bilinear in the texels (wrapping in u, clamped in v); sampling picks a
//! texel from a piecewise-constant distribution over the image (a marginal over rows,
//! a conditional over the columns of each: pbrt-v4's `PiecewiseConstant2D`, §A.5), then a
//! point uniformly within it, so that the solid-angle pdf is p(u, v) / (2π² sin θ)
//! (pbrt-v4 eq. 12.5 for the equirectangular map). Texels are weighted by the largest
//! luminance of their 3×3 neighbourhood (which bounds the bilinear radiance within them)
//! plus a small floor (1 % of the mean), so that no direction the lookup lights has a
//! density far below its share: the halo of a bright sun would otherwise be found only by
//! BSDF samples, as fireflies.
//!
//! In the spectral modes a texel's RGB becomes an illuminant spectrum as emitters' colours
//! do (Jakob & Hanika 2019 times D65, scaled by 2·max), through the precomputed uplift
//! table; RGB mode uses the RGB.

use crate::{Error, Result};
use glam::{Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::f32::consts::{PI, TAU};
use std::path::Path;

/// The largest width or height of an environment map we read.
pub const MAX_ENVIRONMENT_SIZE: u32 = 16_384;

/// A latitude–longitude environment map with its sampling distribution.
#[derive(Clone)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    /// Linear RGB radiance, rows from the top (the zenith).
    texels: Vec<[f32; 3]>,
    /// Rotation about +y, as (cos, sin).
    rotation: (f32, f32),
    /// Per row, the cumulative distribution over its columns (width + 1 entries each).
    conditional: Vec<f32>,
    /// The cumulative distribution over rows (height + 1 entries).
    marginal: Vec<f32>,
    /// Mean luminance over the sphere (solid-angle weighted), for light selection.
    mean_luminance: f32,
}

impl std::fmt::Debug for EnvironmentMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvironmentMap")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("mean_luminance", &self.mean_luminance)
            .finish()
    }
}

impl PartialEq for EnvironmentMap {
    fn eq(&self, other: &Self) -> bool {
        (self.width, self.height, self.rotation) == (other.width, other.height, other.rotation)
            && self.texels == other.texels
    }
}

/// Rec. 709 / linear-sRGB luminance.
#[inline]
fn luminance(rgb: [f32; 3]) -> f32 {
    0.212_639 * rgb[0] + 0.715_168_7 * rgb[1] + 0.072_192_3 * rgb[2]
}

impl EnvironmentMap {
    /// A map from linear RGB texels (`width` × `height`, rows from the zenith), turned by
    /// `rotation_deg` about the vertical axis. Texels must be finite and non-negative.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 3]>, rotation_deg: f32) -> std::result::Result<Self, String> {
        if width == 0 || height == 0 || width > MAX_ENVIRONMENT_SIZE || height > MAX_ENVIRONMENT_SIZE {
            return Err(format!("{width}×{height} texels (each side must be 1 to {MAX_ENVIRONMENT_SIZE})"));
        }
        if texels.len() != width as usize * height as usize {
            return Err(format!("{} texels for a {width}×{height} map", texels.len()));
        }
        if let Some(i) = texels.iter().position(|t| t.iter().any(|c| !(c.is_finite() && *c >= 0.0))) {
            let (x, y) = (i % width as usize, i / width as usize);
            return Err(format!("texel ({x}, {y}) is {:?}: radiance must be finite and non-negative", texels[i]));
        }
        if !rotation_deg.is_finite() {
            return Err(format!("rotation {rotation_deg}° is not finite"));
        }
        let (w, h) = (width as usize, height as usize);
        // sin θ at each row's centre: the solid angle a texel covers is ∝ it.
        let sin_theta: Vec<f32> = (0..h).map(|y| (PI * (y as f32 + 0.5) / h as f32).sin()).collect();
        let mean_luminance = texels.iter().enumerate().map(|(i, t)| luminance(*t) * sin_theta[i / w]).sum::<f32>()
            / sin_theta.iter().sum::<f32>().max(f32::MIN_POSITIVE)
            / w as f32;
        let floor = 0.01 * mean_luminance.max(f32::MIN_POSITIVE);
        // The bilinear lookup spreads a texel over its neighbours' halves: weight each texel
        // by the brightest of its 3×3 neighbourhood (wrapping in u, clamped in v), which
        // bounds the radiance anywhere in it (pbrt-v4 builds its distribution from the
        // filtered image likewise), so that a bright sun's halo is sampled too.
        let lum: Vec<f32> = texels.iter().map(|t| luminance(*t)).collect();
        let neighbourhood_max = |x: usize, y: usize| {
            let mut m = 0.0f32;
            for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                for dx in [w - 1, 0, 1] {
                    m = m.max(lum[yy * w + (x + dx) % w]);
                }
            }
            m
        };
        let mut conditional = Vec::with_capacity(h * (w + 1));
        let mut row_weight = Vec::with_capacity(h);
        for y in 0..h {
            let mut sum = 0.0f64;
            conditional.push(0.0);
            for x in 0..w {
                sum += ((neighbourhood_max(x, y) + floor) * sin_theta[y]) as f64;
                conditional.push(sum as f32);
            }
            let row = &mut conditional[y * (w + 1)..];
            for c in &mut row[1..=w] {
                *c /= sum as f32;
            }
            row[w] = 1.0;
            row_weight.push(sum as f32);
        }
        let mut marginal = Vec::with_capacity(h + 1);
        let mut sum = 0.0f64;
        marginal.push(0.0);
        for &r in &row_weight {
            sum += r as f64;
            marginal.push(sum as f32);
        }
        for m in &mut marginal[1..=h] {
            *m /= sum as f32;
        }
        marginal[h] = 1.0;
        let (sin, cos) = rotation_deg.to_radians().sin_cos();
        Ok(Self { width, height, texels, rotation: (cos, sin), conditional, marginal, mean_luminance })
    }

    /// Reads an EXR or HDR file (linear), or a PNG or JPEG (sRGB-decoded).
    pub fn load(path: &Path, rotation_deg: f32) -> Result<Self> {
        let fail = |message: String| Error::Setting(format!("environment map '{}': {message}", path.display()));
        let bytes = crate::obj::read_file_bytes(path).map_err(|e| fail(e.to_string()))?;
        Self::decode(&bytes, rotation_deg).map_err(fail)
    }

    /// [`EnvironmentMap::load`] from bytes in memory; the error says why not.
    pub fn decode(bytes: &[u8], rotation_deg: f32) -> std::result::Result<Self, String> {
        let decoded = crate::texture::decode_image(bytes, MAX_ENVIRONMENT_SIZE)?;
        let linear = matches!(decoded, image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_));
        let (width, height) = (decoded.width(), decoded.height());
        let texels = decoded
            .into_rgb32f()
            .pixels()
            .map(|p| if linear { p.0 } else { p.0.map(spectral::colour::srgb_decode) })
            .collect();
        Self::new(width, height, texels, rotation_deg)
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Mean luminance over the sphere (each direction weighted by its solid angle).
    pub fn mean_luminance(&self) -> f32 {
        self.mean_luminance
    }

    /// What the map is made of, for backends that look it up and sample it elsewhere
    /// (the GPU).
    pub fn parts(&self) -> EnvironmentMapParts<'_> {
        EnvironmentMapParts {
            texels: &self.texels,
            rotation: self.rotation,
            conditional: &self.conditional,
            marginal: &self.marginal,
        }
    }

    /// Bytes the texels and the distribution take.
    pub fn size_bytes(&self) -> usize {
        self.texels.len() * 12 + (self.conditional.len() + self.marginal.len()) * 4
    }

    /// The map's (u, v) of world direction `dir` (unit length).
    #[inline]
    pub fn uv(&self, dir: Vec3) -> Vec2 {
        let (c, s) = self.rotation;
        // Undo the rotation: the map's own frame.
        let (x, z) = (c * dir.x - s * dir.z, s * dir.x + c * dir.z);
        let u = 0.5 + x.atan2(-z) / TAU;
        let v = dir.y.clamp(-1.0, 1.0).acos() / PI;
        Vec2::new(u, v)
    }

    /// The world direction at map coordinates `uv`.
    #[inline]
    pub fn direction(&self, uv: Vec2) -> Vec3 {
        let phi = (uv.x - 0.5) * TAU;
        let theta = uv.y * PI;
        let (sin_t, cos_t) = theta.sin_cos();
        let (x, z) = (sin_t * phi.sin(), -sin_t * phi.cos());
        let (c, s) = self.rotation;
        // Turned counter-clockwise seen from above (about +y, right-handed).
        Vec3::new(c * x + s * z, cos_t, -s * x + c * z)
    }

    /// Linear RGB radiance arriving from direction `dir` (bilinear).
    #[inline]
    pub fn rgb(&self, dir: Vec3) -> [f32; 3] {
        let uv = self.uv(dir);
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * w as f32 - 0.5;
        let y = uv.y * h as f32 - 0.5;
        let (x, y) = (if x.is_finite() { x } else { 0.0 }, if y.is_finite() { y } else { 0.0 });
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut out = [0.0f32; 3];
        for (dy, wy) in [(0, 1.0 - fy), (1, fy)] {
            let row = (y0 + dy).clamp(0, h - 1) as usize;
            for (dx, wx) in [(0, 1.0 - fx), (1, fx)] {
                let col = (x0 + dx).rem_euclid(w) as usize;
                let t = self.texels[row * w as usize + col];
                for c in 0..3 {
                    out[c] += wy * wx * t[c];
                }
            }
        }
        out
    }

    /// The radiance from `dir` at the path's wavelengths.
    #[inline]
    pub fn radiance<const N: usize>(&self, dir: Vec3, wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
        let rgb = self.rgb(dir);
        if wl.is_rgb() {
            return SampledSpectrum(std::array::from_fn(|i| rgb.get(i).copied().unwrap_or(0.0)));
        }
        let m = rgb[0].max(rgb[1]).max(rgb[2]);
        if m <= 0.0 {
            return SampledSpectrum::zero();
        }
        // RgbIlluminantSpectrum's construction, with the fit replaced by the table.
        let scale = 2.0 * m;
        let poly = spectral::uplift::uplift_table().lookup(rgb.map(|c| c / scale));
        wl.eval(|l| scale * poly.eval(l) * spectral::uplift::d65_normalised(l))
    }

    /// A direction drawn with density ∝ luminance × solid angle, and its solid-angle pdf
    /// (`None` at the poles, where the density is undefined).
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (w, h) = (self.width as usize, self.height as usize);
        let (row, fy) = sample_cdf(&self.marginal, u.y);
        let cdf = &self.conditional[row * (w + 1)..(row + 1) * (w + 1)];
        let (col, fx) = sample_cdf(cdf, u.x);
        let uv = Vec2::new((col as f32 + fx) / w as f32, (row as f32 + fy) / h as f32);
        let sin_theta = (uv.y * PI).sin();
        if sin_theta <= 0.0 {
            return None;
        }
        let pdf = self.density(row, col) / (2.0 * PI * PI * sin_theta);
        Some((self.direction(uv), pdf))
    }

    /// The solid-angle pdf of [`EnvironmentMap::sample`] drawing `dir`.
    #[inline]
    pub fn pdf(&self, dir: Vec3) -> f32 {
        let uv = self.uv(dir);
        let sin_theta = (uv.y * PI).sin();
        if sin_theta.is_nan() || sin_theta <= 0.0 {
            return 0.0;
        }
        let (w, h) = (self.width as usize, self.height as usize);
        let col = ((uv.x * w as f32) as usize).min(w - 1);
        let row = ((uv.y * h as f32) as usize).min(h - 1);
        self.density(row, col) / (2.0 * PI * PI * sin_theta)
    }

    /// The density over [0, 1]² of texel (row, col): its weight × texel count / total.
    #[inline]
    fn density(&self, row: usize, col: usize) -> f32 {
        let w = self.width as usize;
        let cdf = &self.conditional[row * (w + 1)..];
        let p_col = cdf[col + 1] - cdf[col];
        let p_row = self.marginal[row + 1] - self.marginal[row];
        p_row * p_col * (w * self.height as usize) as f32
    }
}

/// An [`EnvironmentMap`]'s texels, rotation and sampling distribution.
#[derive(Clone, Copy, Debug)]
pub struct EnvironmentMapParts<'a> {
    /// Linear RGB radiance, rows from the top (the zenith).
    pub texels: &'a [[f32; 3]],
    /// The rotation about +y as (cos, sin).
    pub rotation: (f32, f32),
    /// Per row, the cumulative distribution over its columns (width + 1 entries each).
    pub conditional: &'a [f32],
    /// The cumulative distribution over the rows (height + 1 entries).
    pub marginal: &'a [f32],
}

/// The bin of a sample `u` ∈ [0, 1) in a cumulative distribution (first entry 0, last 1)
/// and its position within the bin in [0, 1); empty bins are never chosen.
#[inline]
fn sample_cdf(cdf: &[f32], u: f32) -> (usize, f32) {
    let n = cdf.len() - 1;
    let k = cdf.partition_point(|&c| c <= u).saturating_sub(1).min(n - 1);
    let width = cdf[k + 1] - cdf[k];
    let f = if width > 0.0 { ((u - cdf[k]) / width).clamp(0.0, crate::lights::ONE_MINUS_EPSILON) } else { 0.5 };
    (k, f)
}

#[cfg(test)]
mod tests;
