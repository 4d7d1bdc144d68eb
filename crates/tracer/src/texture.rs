//! Image textures and what a material reads from them at a hit.
//!
//! Texels are kept as the file stores them, 8 bits per channel (RGBA8: 4 bytes a texel;
//! 16-bit images are rounded to 8 bits), and decoded at lookup through a 256-entry table
//! (sRGB's transfer function for colours, ÷255 for data such as normals and roughness).
//! A lookup filters bilinearly in linear values, so that a colour is the texels' weighted
//! mean in light, and only then becomes a spectrum: by the precomputed Jakob–Hanika
//! uplift table ([`spectral::uplift::uplift_table`], a trilinear lookup of three sigmoid
//! coefficients) for the spectral modes, as the linear-sRGB value itself in RGB mode. Per
//! texel that costs nothing at load time beyond decoding; per hit one table lookup and
//! N sigmoid evaluations (`cargo bench -p tracer --bench texture`).
//!
//! Texture coordinates have their origin at the image's top-left corner (glTF's
//! convention; OBJ's are flipped on loading), texel centres at half-integers. No
//! mip-maps: a path tracer's many samples per pixel filter the texture over the pixel
//! footprint already (box-filtered supersampling), at the price of more samples where a
//! texture is minified strongly.

use crate::{Error, Result};
use glam::{Mat3, Vec2, Vec3};
use spectral::{SampledSpectrum, SampledWavelengths};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The largest width or height of a texture we read (larger claims are refused before
/// any texel is decoded).
pub const MAX_TEXTURE_SIZE: u32 = 16_384;

/// A decoded image: RGBA8 texels, row by row from the top.
#[derive(Clone, PartialEq, Eq)]
pub struct TextureImage {
    width: u32,
    height: u32,
    texels: Vec<[u8; 4]>,
    /// Whether the file had an alpha channel (else alpha is 255 everywhere).
    has_alpha: bool,
}

impl std::fmt::Debug for TextureImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TextureImage")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("has_alpha", &self.has_alpha)
            .finish_non_exhaustive()
    }
}

impl TextureImage {
    /// An image from RGBA8 texels (`width` × `height`, rows from the top).
    /// It has alpha if any texel is not fully opaque.
    pub fn from_rgba8(width: u32, height: u32, texels: Vec<[u8; 4]>) -> std::result::Result<Self, String> {
        let has_alpha = texels.iter().any(|t| t[3] != 255);
        Self::with_alpha(width, height, texels, has_alpha)
    }

    /// The image after checking its size against its texels.
    fn with_alpha(width: u32, height: u32, texels: Vec<[u8; 4]>, has_alpha: bool) -> std::result::Result<Self, String> {
        if width == 0 || height == 0 || width > MAX_TEXTURE_SIZE || height > MAX_TEXTURE_SIZE {
            return Err(format!("{width}×{height} texels (each side must be 1 to {MAX_TEXTURE_SIZE})"));
        }
        if texels.len() != width as usize * height as usize {
            return Err(format!("{} texels for a {width}×{height} texture", texels.len()));
        }
        Ok(Self { width, height, texels, has_alpha })
    }

    /// Decodes a PNG, JPEG, EXR or HDR file held in memory; the error says why not.
    /// Sizes beyond [`MAX_TEXTURE_SIZE`] and decoder allocations beyond 1 GiB are refused.
    pub fn decode(bytes: &[u8]) -> std::result::Result<Self, String> {
        let decoded = decode_image(bytes, MAX_TEXTURE_SIZE)?;
        // Alpha as the file declares it (an RGBA file that happens to be opaque still has
        // alpha; a grey or RGB one gives its first channel as alpha, MTL's `map_d` use).
        let has_alpha = decoded.color().has_alpha();
        let (width, height) = (decoded.width(), decoded.height());
        let texels: Vec<[u8; 4]> = decoded.into_rgba8().pixels().map(|p| p.0).collect();
        Self::with_alpha(width, height, texels, has_alpha)
    }

    /// Reads and decodes an image file; the error says why not.
    pub fn load(path: &Path) -> std::result::Result<Self, String> {
        let bytes = crate::obj::read_file_bytes(path).map_err(|e| e.to_string())?;
        Self::decode(&bytes)
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Whether the file had an alpha channel.
    pub fn has_alpha(&self) -> bool {
        self.has_alpha
    }

    /// Bytes its texels take.
    pub fn size_bytes(&self) -> usize {
        self.texels.len() * 4
    }

    /// The texel at column `x`, row `y` (from the top).
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> [u8; 4] {
        self.texels[y as usize * self.width as usize + x as usize]
    }
}

/// Decodes an image held in memory with the `image` crate, within bounds: each side at
/// most `max_side`, and no more pixels than the file could hold — 1 M plus 1024 per byte
/// of file (deflate's best ratio is about 1032 : 1, so even a one-channel PNG of a single
/// colour stays within it; JPEG and EXR compress less) — so that a forged header of a
/// small file cannot make the decoder allocate gigabytes (`fuzz_scenes` found a 448-byte
/// EXR that did). A decoder panic becomes an error.
pub(crate) fn decode_image(bytes: &[u8], max_side: u32) -> std::result::Result<image::DynamicImage, String> {
    let reader = || image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format();
    let probe = reader().map_err(|e| e.to_string())?;
    if probe.format().is_none() {
        return Err("not a PNG, JPEG, EXR or HDR image".into());
    }
    if probe.format() == Some(image::ImageFormat::OpenExr) {
        check_exr_tiles(bytes)?;
    }
    let (width, height) = guarded(|| probe.into_dimensions().map_err(|e| e.to_string()))?;
    if width == 0 || height == 0 || width > max_side || height > max_side {
        return Err(format!("{width}×{height} pixels (each side must be 1 to {max_side})"));
    }
    let pixels = width as u64 * height as u64;
    if pixels > (1 << 20) + 1024 * bytes.len() as u64 {
        return Err(format!("{width}×{height} pixels is more than a {}-byte file can hold", bytes.len()));
    }
    guarded(|| {
        let mut r = reader().map_err(|e| e.to_string())?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(max_side);
        limits.max_image_height = Some(max_side);
        limits.max_alloc = Some(4 << 30);
        r.limits(limits);
        r.decode().map_err(|e| e.to_string())
    })
}

/// `f()`, a decoder panic turned into an error (the last line of defence, as for tobj and
/// gltf).
fn guarded<T>(f: impl FnOnce() -> std::result::Result<T, String>) -> std::result::Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f))
        .map_err(|p| format!("the decoder failed: {}", crate::panic_message(&p)))?
}

/// The most pixels an OpenEXR tile may cover beyond its image's own: tiles larger than
/// the image are legal (a 64 × 64 tile over an 8 × 4 image), but the `exr` crate
/// allocates a whole tile's bytes before reading them, so a forged `tiles` attribute
/// (found by `fuzz_scenes`: a 64 × 2.6 M tile in a 448-byte file, 1.3 GB) must be refused
/// first.
const MAX_EXR_TILE_PIXELS: u64 = 1 << 16;

/// Walks the header attributes of every part of an OpenEXR file (name, type, size, value,
/// until an empty name) and refuses a tile that covers more than its data window and
/// [`MAX_EXR_TILE_PIXELS`]; a header it cannot walk is left to the decoder.
fn check_exr_tiles(bytes: &[u8]) -> std::result::Result<(), String> {
    let multipart = bytes.get(5).is_some_and(|flags| flags & 0x10 != 0);
    let mut at = 8;
    loop {
        let (mut window, mut tile) = (None, None);
        loop {
            let Some(name_end) = bytes.get(at..).and_then(|b| b.iter().position(|&c| c == 0)) else { return Ok(()) };
            if name_end == 0 {
                at += 1;
                break;
            }
            let name = &bytes[at..at + name_end];
            at += name_end + 1;
            let Some(type_end) = bytes.get(at..).and_then(|b| b.iter().position(|&c| c == 0)) else { return Ok(()) };
            at += type_end + 1;
            let Some(size) = bytes.get(at..at + 4).map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]])) else {
                return Ok(());
            };
            at += 4;
            let Some(value) = usize::try_from(size).ok().and_then(|n| bytes.get(at..at.checked_add(n)?)) else {
                return Ok(());
            };
            at += value.len();
            let word = |k: usize| value.get(4 * k..4 * k + 4).map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            match name {
                b"dataWindow" => {
                    if let (Some(x0), Some(y0), Some(x1), Some(y1)) = (word(0), word(1), word(2), word(3)) {
                        let w = (x1 as i64 - x0 as i64 + 1).max(0) as u64;
                        let h = (y1 as i64 - y0 as i64 + 1).max(0) as u64;
                        window = Some(w * h);
                    }
                }
                b"tiles" => {
                    if let (Some(w), Some(h)) = (word(0), word(1)) {
                        tile = Some(w as u32 as u64 * h as u32 as u64);
                    }
                }
                _ => {}
            }
        }
        if let Some(tile) = tile
            && tile > window.unwrap_or(0).max(MAX_EXR_TILE_PIXELS)
        {
            return Err(format!("an OpenEXR tile of {tile} pixels is larger than its image"));
        }
        // A multi-part file lists its headers one after another, then an empty one.
        if !multipart || bytes.get(at) == Some(&0) {
            return Ok(());
        }
    }
}

/// How coordinates outside [0, 1] map into the image (glTF's sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Tiled (glTF `REPEAT`, MTL's default).
    #[default]
    Repeat,
    /// The edge texel continues (glTF `CLAMP_TO_EDGE`, MTL `-clamp on`).
    Clamp,
    /// Tiled with every other copy mirrored (glTF `MIRRORED_REPEAT`).
    Mirror,
}

impl Wrap {
    /// Texel index `i` (any integer) folded into 0..n.
    #[inline]
    fn index(self, i: i64, n: u32) -> u32 {
        let n = n as i64;
        (match self {
            Self::Repeat => i.rem_euclid(n),
            Self::Clamp => i.clamp(0, n - 1),
            Self::Mirror => {
                let k = i.rem_euclid(2 * n);
                if k < n { k } else { 2 * n - 1 - k }
            }
        }) as u32
    }
}

/// How texel bytes become values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// sRGB-encoded colour (IEC 61966-2-1): base and emissive colours. Alpha is linear.
    Srgb,
    /// Linear data: normals, roughness, metalness, heights, alpha.
    Linear,
}

fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| spectral::colour::srgb_decode(i as f32 / 255.0)))
}

/// An image placed on a surface: the image, its wrap modes, its encoding and an affine
/// map of texture coordinates (glTF's `KHR_texture_transform`, MTL's `-o`/`-s`).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureMap {
    /// The texels (shared by every material using the file).
    pub image: Arc<TextureImage>,
    /// Wrap modes along u and v.
    pub wrap: [Wrap; 2],
    /// How texel bytes become values.
    pub encoding: Encoding,
    /// uv ↦ `transform` · (u, v, 1): the first two rows of a 3×3 affine matrix, columns
    /// first as glam stores them (identity: no transform).
    pub transform: Mat3,
}

impl TextureMap {
    /// `image` tiled over the unit square.
    pub fn new(image: Arc<TextureImage>, encoding: Encoding) -> Self {
        Self { image, wrap: [Wrap::Repeat; 2], encoding, transform: Mat3::IDENTITY }
    }

    /// The filtered RGB at `uv` as a reflectance at the path's wavelengths
    /// ([`reflectance_spectrum`]).
    #[inline]
    pub fn reflectance<const N: usize>(&self, uv: Vec2, wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
        let t = self.sample(uv);
        reflectance_spectrum([t[0], t[1], t[2]], wl)
    }

    /// The bilinearly filtered value at `uv`: RGB decoded by the encoding, alpha linear.
    #[inline]
    pub fn sample(&self, uv: Vec2) -> [f32; 4] {
        let uv = if self.transform == Mat3::IDENTITY { uv } else { self.transform.transform_point2(uv) };
        let image = &*self.image;
        let (w, h) = (image.width, image.height);
        // Texel centres at half-integers; a NaN coordinate reads texel 0.
        let x = uv.x * w as f32 - 0.5;
        let y = uv.y * h as f32 - 0.5;
        let (x, y) = (if x.is_finite() { x } else { 0.0 }, if y.is_finite() { y } else { 0.0 });
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // Coordinates beyond ±2^40 lose their fraction anyway; the clamp keeps i64 exact.
        let (x0, y0) = (x0.clamp(-1e12, 1e12) as i64, y0.clamp(-1e12, 1e12) as i64);
        let xs = [self.wrap[0].index(x0, w), self.wrap[0].index(x0 + 1, w)];
        let ys = [self.wrap[1].index(y0, h), self.wrap[1].index(y0 + 1, h)];
        let weights = [(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy];
        let decode: &[f32; 256] = match self.encoding {
            Encoding::Srgb => srgb_table(),
            Encoding::Linear => linear_table(),
        };
        let mut out = [0.0f32; 4];
        for (k, &wk) in weights.iter().enumerate() {
            let t = image.texel(xs[k & 1], ys[k >> 1]);
            out[0] += wk * decode[t[0] as usize];
            out[1] += wk * decode[t[1] as usize];
            out[2] += wk * decode[t[2] as usize];
            out[3] += wk * f32::from(t[3]) * (1.0 / 255.0);
        }
        out
    }
}

fn linear_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|i| i as f32 / 255.0))
}

/// glTF's `KHR_texture_transform` as a uv matrix: uv' = T · R · S · uv with
/// R = [[cos, sin], [−sin, cos]] (the extension's matrix, rows), `rotation` in radians.
pub fn khr_texture_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Mat3 {
    let (sin, cos) = rotation.sin_cos();
    let ([ox, oy], [sx, sy]) = (offset, scale);
    // Columns of T·R·S.
    Mat3::from_cols(Vec3::new(cos * sx, -sin * sx, 0.0), Vec3::new(sin * sy, cos * sy, 0.0), Vec3::new(ox, oy, 1.0))
}

/// A reflectance given as linear sRGB in [0, 1] at the path's wavelengths: the RGB
/// itself in RGB mode, else its Jakob–Hanika spectrum from the precomputed table.
#[inline]
pub fn reflectance_spectrum<const N: usize>(rgb: [f32; 3], wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
    if wl.is_rgb() {
        return SampledSpectrum(std::array::from_fn(|i| rgb.get(i).copied().unwrap_or(0.0)));
    }
    let rgb = rgb.map(|c| c.clamp(0.0, 1.0));
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return SampledSpectrum::splat(rgb[0]);
    }
    let poly = spectral::uplift::uplift_table().lookup(rgb);
    wl.eval(|l| poly.eval(l))
}

/// How a material's alpha makes it transparent (glTF 2.0 `alphaMode`; MTL `map_d`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// A cut-out: the surface is absent where alpha < `cutoff`, fully there elsewhere.
    Mask {
        /// glTF's `alphaCutoff` (0.5 by default).
        cutoff: f32,
    },
    /// Stochastic transparency: a ray passes with probability 1 − alpha (decided by a
    /// hash of the ray and the primitive, as pbrt-v4 does, so shadow rays agree on
    /// average with camera paths), which is unbiased for blending's coverage meaning.
    Blend,
}

/// Where a material's alpha comes from.
#[derive(Clone, Debug, PartialEq)]
pub struct Alpha {
    /// How alpha is used.
    pub mode: AlphaMode,
    /// A constant factor (glTF baseColorFactor's alpha, MTL `d`).
    pub factor: f32,
    /// A texture whose alpha channel (or, for an image without one, its first channel)
    /// multiplies the factor; `None` when only the factor counts.
    pub map: Option<TextureMap>,
}

impl Alpha {
    /// The alpha at `uv`.
    #[inline]
    pub fn value(&self, uv: Vec2) -> f32 {
        self.map.as_ref().map_or(self.factor, |m| {
            let t = m.sample(uv);
            self.factor * if m.image.has_alpha() { t[3] } else { t[0] }
        })
    }

    /// Whether a ray passes through the surface at `uv`; `coin` gives its value in
    /// [0, 1) for stochastic transparency (asked only in `Blend` mode).
    #[inline]
    pub fn passes(&self, uv: Vec2, coin: impl FnOnce() -> f32) -> bool {
        match self.mode {
            AlphaMode::Opaque => false,
            AlphaMode::Mask { cutoff } => self.value(uv) < cutoff,
            AlphaMode::Blend => coin() >= self.value(uv),
        }
    }
}

/// A normal map in tangent space (glTF `normalTexture`, MTL `norm`): RGB ↦ n = 2·rgb − 1
/// with +x along increasing u, +y along *decreasing* v (up in the image: OpenGL's
/// convention, which glTF uses) and +z the surface normal; x and y scaled by `scale`.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The map (linear).
    pub map: TextureMap,
    /// glTF `normalTexture.scale`.
    pub scale: f32,
}

/// A height map (MTL `bump`/`map_bump`): the surface displaced along its normal by
/// `scale` × height (world units; height in [0, 1] from the first channel), applied as a
/// bump map by finite differences (Blinn 1978; pbrt-v4's `BumpMap`).
#[derive(Clone, Debug, PartialEq)]
pub struct BumpMap {
    /// The heights (linear).
    pub map: TextureMap,
    /// MTL `-bm`: world units per unit of height.
    pub scale: f32,
}

/// Everything a material reads from textures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    /// Multiplies the diffuse or base colour (sRGB).
    pub base_colour: Option<TextureMap>,
    /// Multiplies the specular colour (sRGB).
    pub specular: Option<TextureMap>,
    /// glTF's metallic–roughness texture: G multiplies roughness, B metalness (linear).
    pub metallic_roughness: Option<TextureMap>,
    /// Multiplies the emitted radiance (sRGB).
    pub emissive: Option<TextureMap>,
    /// Bends the shading normal.
    pub normal: Option<NormalMap>,
    /// Bends the shading normal by the slope of a height map.
    pub bump: Option<BumpMap>,
    /// Cut-outs and transparency.
    pub alpha: Option<Alpha>,
}

impl MaterialTextures {
    /// Whether nothing is textured.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// Every map it reads.
    pub fn maps(&self) -> impl Iterator<Item = &TextureMap> {
        [self.base_colour.as_ref(), self.specular.as_ref(), self.metallic_roughness.as_ref(), self.emissive.as_ref()]
            .into_iter()
            .flatten()
            .chain(self.normal.as_ref().map(|n| &n.map))
            .chain(self.bump.as_ref().map(|b| &b.map))
            .chain(self.alpha.as_ref().and_then(|a| a.map.as_ref()))
    }

    /// The texels that drive the BSDF's parameters at `uv`.
    #[inline]
    pub fn texels<const N: usize>(&self, uv: Vec2, wl: &SampledWavelengths<N>) -> brdf::Texels<N> {
        let (roughness, metallic) = self.metallic_roughness.as_ref().map_or((1.0, 1.0), |m| {
            let t = m.sample(uv);
            (t[1], t[2])
        });
        brdf::Texels {
            base_colour: self.base_colour.as_ref().map(|m| m.reflectance(uv, wl)),
            specular: self.specular.as_ref().map(|m| m.reflectance(uv, wl)),
            roughness,
            metallic,
        }
    }

    /// The emissive texel at `uv` as a reflectance-like spectrum that multiplies the
    /// material's emission (1 without an emissive texture).
    #[inline]
    pub fn emission_scale<const N: usize>(&self, uv: Vec2, wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
        self.emissive.as_ref().map_or(SampledSpectrum::one(), |m| m.reflectance(uv, wl))
    }

    /// The shading normal bent by the normal or bump map at `uv`, given the interpolated
    /// shading normal `ns` and the surface's uv derivatives ∂p/∂u, ∂p/∂v (zero where the
    /// mesh has no usable uvs: then `ns` is returned). The result is unit length.
    #[inline]
    pub fn bent_normal(&self, uv: Vec2, ns: Vec3, dpdu: Vec3, dpdv: Vec3) -> Vec3 {
        let mut n = ns;
        if let Some(bump) = &self.bump {
            n = bump_normal(bump, uv, n, dpdu, dpdv);
        }
        if let Some(normal) = &self.normal {
            n = mapped_normal(normal, uv, n, dpdu, dpdv);
        }
        n
    }
}

/// The tangent frame (T, B) at a shading normal: T = ∂p/∂u made perpendicular to `n`,
/// B along −∂p/∂v's part perpendicular to both (up in the image), so that a left-handed
/// uv layout (mirrored texture) flips B as MikkTSpace's sign does; `None` without usable
/// derivatives.
#[inline]
fn tangent_frame(n: Vec3, dpdu: Vec3, dpdv: Vec3) -> Option<(Vec3, Vec3)> {
    let t = (dpdu - n * n.dot(dpdu)).try_normalize()?;
    let b = n.cross(t);
    // up in the image is −∂p/∂v (v grows downwards).
    let sign = if b.dot(-dpdv) < 0.0 { -1.0 } else { 1.0 };
    Some((t, b * sign))
}

fn mapped_normal(normal: &NormalMap, uv: Vec2, n: Vec3, dpdu: Vec3, dpdv: Vec3) -> Vec3 {
    let Some((t, b)) = tangent_frame(n, dpdu, dpdv) else { return n };
    let texel = normal.map.sample(uv);
    let x = (2.0 * texel[0] - 1.0) * normal.scale;
    let y = (2.0 * texel[1] - 1.0) * normal.scale;
    let z = 2.0 * texel[2] - 1.0;
    (x * t + y * b + z.max(1e-3) * n).try_normalize().unwrap_or(n)
}

fn bump_normal(bump: &BumpMap, uv: Vec2, n: Vec3, dpdu: Vec3, dpdv: Vec3) -> Vec3 {
    if dpdu == Vec3::ZERO || dpdv == Vec3::ZERO {
        return n;
    }
    // Finite differences over half a texel (pbrt-v4 uses the ray footprint; we have no
    // differentials, and a texel is the scale the heights are given at).
    let image = &bump.map.image;
    let du = 0.5 / image.width() as f32;
    let dv = 0.5 / image.height() as f32;
    let h = |uv: Vec2| bump.map.sample(uv)[0] * bump.scale;
    let h0 = h(uv);
    let dhdu = (h(uv + Vec2::new(du, 0.0)) - h0) / du;
    let dhdv = (h(uv + Vec2::new(0.0, dv)) - h0) / dv;
    // Displaced surface p + h·n (ignoring ∂n/∂u, as pbrt does for meshes):
    let pu = dpdu + dhdu * n;
    let pv = dpdv + dhdv * n;
    let bent = pu.cross(pv);
    match bent.try_normalize() {
        Some(b) if b.dot(n) < 0.0 => -b,
        Some(b) => b,
        None => n,
    }
}

/// ∂p/∂u and ∂p/∂v of a triangle from its positions and texture coordinates (pbrt-v4
/// §6.5.3); zeros for degenerate uvs.
#[inline]
pub fn triangle_uv_derivatives(p: [Vec3; 3], uv: [Vec2; 3]) -> (Vec3, Vec3) {
    let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
    let (dp02, dp12) = (p[0] - p[2], p[1] - p[2]);
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    if det.abs() < 1e-12 || !det.is_finite() {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let inv = 1.0 / det;
    let dpdu = (duv12.y * dp02 - duv02.y * dp12) * inv;
    let dpdv = (duv02.x * dp12 - duv12.x * dp02) * inv;
    if dpdu.is_finite() && dpdv.is_finite() { (dpdu, dpdv) } else { (Vec3::ZERO, Vec3::ZERO) }
}

/// A stable hash of a ray and a primitive to [0, 1): the coin of stochastic alpha (the
/// same ray meets the same surface the same way, whatever else it hits).
#[inline]
pub fn alpha_hash(origin: Vec3, dir: Vec3, prim: u32) -> f32 {
    let mut h: u64 = 0x9e37_79b9_7f4a_7c15 ^ u64::from(prim);
    for v in [origin.x, origin.y, origin.z, dir.x, dir.y, dir.z] {
        h ^= u64::from(v.to_bits());
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
    }
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^= h >> 33;
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// Loads each image file once, however many materials name it.
#[derive(Default)]
pub struct TextureCache {
    images: HashMap<PathBuf, Arc<TextureImage>>,
}

impl TextureCache {
    /// The image at `path`, read on first use; errors name `material`.
    pub fn load(&mut self, path: &Path, material: &str) -> Result<Arc<TextureImage>> {
        self.load_with(path, material, &crate::obj::read_file_bytes)
    }

    /// [`TextureCache::load`] with the file's bytes from `read` (a fuzzer or a test serves
    /// them from memory).
    pub fn load_with(
        &mut self,
        path: &Path,
        material: &str,
        read: &dyn Fn(&Path) -> std::io::Result<Vec<u8>>,
    ) -> Result<Arc<TextureImage>> {
        if let Some(image) = self.images.get(path) {
            return Ok(image.clone());
        }
        let decoded = read(path).map_err(|e| e.to_string()).and_then(|bytes| TextureImage::decode(&bytes));
        let image = decoded.map_err(|message| Error::Texture {
            material: material.into(),
            texture: path.display().to_string(),
            message,
        })?;
        let image = Arc::new(image);
        self.images.insert(path.to_path_buf(), image.clone());
        Ok(image)
    }

    /// Images loaded and the bytes their texels take.
    pub fn stats(&self) -> (usize, usize) {
        (self.images.len(), self.images.values().map(|i| i.size_bytes()).sum())
    }
}

#[cfg(test)]
mod tests;
