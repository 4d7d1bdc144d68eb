//! The GPU backend: the tracer's integrator as a wgpu compute kernel.
//!
//! # Design
//!
//! * [`GpuBackend::prepare`] (the [`Backend`] impl) checks the scene against the
//!   backend's [`Capabilities`], lays it out as flat arrays ([`SceneData`]: a binary BVH — binned SAH,
//!   leaves of at most 4 triangles — in `bvh`'s 32-byte node layout, the triangles'
//!   vertices in leaf order, per-vertex normals and tangents with the triangle → vertex
//!   map, the CIE 1931 tables, the environment's spectrum, the light distribution, and
//!   the material kernel from [`crate::materials`]), checks every buffer against the
//!   device's limits, uploads it and compiles the kernel ([`crate::kernel`]) for the
//!   scene's materials, the requested triangle test, and whether it has analytic shapes,
//!   instances and punctual lights (without, their code is not in the kernel). The result, a [`GpuScene`], owns
//!   all of that: an interactive viewer calling `render_pass` once per frame pays only
//!   for the frame's samples.
//! * A pass renders the image in bands of rows (so that the per-pixel accumulators fit
//!   the device's buffer limits whatever the image size), each band in dispatches of at
//!   most [`DISPATCH_BUDGET`] pixel-samples (1–64 samples per pixel; short dispatches
//!   stay clear of GPU watchdogs and feed the progress callback). Each invocation adds
//!   its pixel's samples to an f32 count / mean / M2 (Welford); after the band (or
//!   at every multiple of [`SAMPLES_PER_READBACK`] in the sample index) the
//!   accumulators are read back, converted to the film's exact fixed-point sums
//!   ([`PixelStats::from_moments`]) and added, so a film may mix CPU and GPU passes, and
//!   passes split at those multiples give the same bytes as one.
//! * Rays (camera, extension and shadow, counted as the CPU counts them) are summed
//!   per invocation and added to a 64-bit atomic counter; paths cut by the bounce cap
//!   likewise ([`PathCounters::truncated`]).
//!
//! # Differences from the CPU integrator
//!
//! The backend runs one integrator, compiled into its kernel ([`GpuBackend::with_integrator`]):
//! `wgsl/path.wgsl` is a line-by-line port of `tracer`'s `PathTracer`, `wgsl/simple.wgsl`
//! of `DirectLighting` and `AmbientOcclusion`, `wgsl/whitted.wgsl` of `Whitted` (its
//! recursion as a depth-first walk with a stack of [`crate::kernel::WHITTED_MAX_DEPTH`]
//! entries, in the CPU's order), `wgsl/atlas.wgsl` of `AtlasGi`'s per-pixel part (its atlas
//! built by the CPU's code when the scene is prepared, its gather run on the device by
//! `wgsl/atlas_gather.wgsl`); all share the path
//! tracer's interaction and light sampling code, as the CPU's do. The path kernel is the one described here. It draws
//! the CPU's own sample values (`wgsl/sampler.wgsl`: `Pcg32::for_sample`, `PaddedSobol`
//! and `ZSobol`, with the 64-bit arithmetic emulated on word pairs) in the CPU's order, so
//! a GPU path starts as the CPU path of the same pixel sample and usually stays on it.
//! What differs:
//!
//! * Hero mode (four wavelengths), RGB mode (three channels, a kernel of its own: colours
//!   as their linear-sRGB values, metals at the CPU's channel wavelengths, no dispersion)
//!   and bins40 (a kernel tracing each sample as ten paths of four of the 40 bins from the
//!   same sample values; the CPU carries all 40 in one path). Refused up front by the
//!   capability check: custom (out-of-workspace) BSDFs that ship no WGSL twin
//!   (`brdf::BsdfBuilder::wgsl_twin`; those that do are compiled in as one more model), and
//!   implicit surfaces on a device without wgpu's `SHADER_F64` (their root finder works in
//!   f64; [`capabilities_on`]).
//! * Spheres, boxes and polygons (`wgsl/shapes.wgsl`) are records in the tables with a
//!   binary BVH of their own, traversed after the triangles' as on the CPU; the polygon's
//!   inside test evaluates its orientation determinant in f32 (f64 on the CPU), which can
//!   differ for points within rounding of an edge. Implicit surfaces (`wgsl/implicit.wgsl`)
//!   are solved in f64 as on the CPU — clipping, the closed forms, Laguerre's method with
//!   deflation and polishing — in kernels of their own (only scenes with implicit surfaces
//!   carry f64 code, its arrays sized to their highest degree); Vulkan lacks f64 `acos`,
//!   `cos` and `pow`, so the trigonometric cubic's angle is taken in f32 and its cosines and
//!   the cube root in f64 by the kernel's own code, the roots then polished in f64 as on the
//!   CPU (`wgsl/implicit.wgsl` lists every difference). Point, spot and directional lights
//!   (with a sun's disk) are entries of the light table; their spectra are tabulated at
//!   1 nm, as the environment's.
//! * Instances (`wgsl/instances.wgsl`) are traced two-level, as `bvh::TwoLevel` on the
//!   CPU: each placed object's triangles and tree (in the scene's node layout) are
//!   uploaded once after the world's, their references rebased into the shared arrays; a
//!   box BVH over the placements' world bounds, in the tables as the shapes' is, leads a
//!   ray into an object's space (direction not renormalised, so t stays the world's).
//!   Placements on sampled area lights (emissive, without an emissive texture) are
//!   copied into the world's triangles first
//!   ([`tracer::Scene::flatten_light_instances`]): light sampling reads world-space
//!   triangles from the light table. The atlas integrator flattens every placement (its
//!   charts are per world triangle).
//! * Bidirectional path tracing (`wgsl/bdpt.wgsl`) keeps the light subpath and the camera
//!   subpath's densities in a scratch buffer of [`BDPT_SLOT_BYTES`] per invocation (bands
//!   of rows as many as 1 GiB of scratch holds) and sums light tracing's splats in an
//!   image of 96-bit fixed-point words with atomics (exact, in any order), read back into
//!   the film's splat sums after each pass; its paths are capped as the CPU's
//!   (`BDPT_MAX_VERTICES`). Device accumulations (a viewer) of bdpt read the film back
//!   each frame ([`tracer::FilmAccumulation`]).
//! * A path has at most [`MAX_BOUNCES`] scattering events (bdpt: its own cap, as above). A `max_depth` beyond it is
//!   refused; with `max_depth` 0 (unbounded on the CPU) paths that reach it are counted
//!   ([`PathCounters::truncated`], printed by the CLI): with Russian roulette
//!   (q ≥ 0.05) the probability of reaching it is below 0.95²⁵⁶ ≈ 2·10⁻⁶ per path.
//! * Rounding: the driver may contract multiply–adds into FMAs, and `atanh`, `sqrt`,
//!   `exp`, `sin`/`cos` are the GPU's, so values differ in the last bits and a path
//!   occasionally takes another branch (a Russian-roulette or Fresnel decision on the
//!   threshold, a ray grazing an edge) and decorrelates from the CPU's from there on;
//!   images are close to the CPU's, not bit-identical.
//! * Triangles are traced in a binary BVH (binned SAH unless `--bvh-builder` says
//!   otherwise, leaves ≤ 4; or the 4- or 8-wide trees [`crate::wide`] collapses from it,
//!   with `--bvh-width`) instead of the CPU's wide BVH; with hits at exactly equal
//!   distances the two may report different triangles.
//! * The specular extension past `max_depth` and the `max_diffuse_depth` count judge a hit
//!   by its material's flags: the union over 360–830 nm of its untextured BSDF's
//!   (`material_flags`); the CPU asks the BSDF at the hit's texel and wavelengths. They
//!   differ only for a material whose lobes depend on either (a texture that makes a
//!   surface purely specular in places, say), where the GPU may count or extend
//!   differently.
//! * The watertight triangle test has no double-precision fallback (WGSL has no f64):
//!   an edge function that rounds to exactly zero counts as "on the edge", which can
//!   add a hit but never lose one; with FMA contraction the two triangles of a shared
//!   edge might disagree in the last bit for rays within an ulp of the edge.
//! * The environment's radiance spectrum is tabulated at 1 nm (360–830 nm) and
//!   interpolated linearly (exact for constant spectra; for uplifted RGB the error is
//!   far below the noise).
//! * WGSL has no infinities: ray extents are finite (3·10³⁸), and zero direction
//!   components become ±10⁻³⁰ in the slab test (the CPU's "on a slab plane counts as
//!   inside" rule, reached another way). Non-finite samples are found from their bits,
//!   immune to fast-math folding, and dropped and counted as on the CPU.
//! * Each pixel's mean and M2 are accumulated in f32 over at most
//!   [`SAMPLES_PER_READBACK`] samples (relative rounding ≲ 1024 · 2⁻²⁴ ≈ 6·10⁻⁵ in the
//!   worst case), then added to the film's exact sums.

use crate::accumulation::DeviceAccumulation;
use crate::kernel::{
    BDPT_SLOT_BYTES, FILM_HEADER_BYTES, GpuIntegrator, HAS_DISPERSION, HAS_ENVIRONMENT, HAS_NORMALS, HAS_TANGENTS,
    HAS_UVS, KernelOptions, LIGHT_CDF, LIGHT_FLOATS, LIGHT_KIND, LIGHT_MATERIAL, LIGHT_PMF, LightKind, NodeLayout,
    Params, PixelAccum, SEEDS_OFFSET, SPLAT_HEADER_WORDS, ShapeCode, UNIFORM_BYTES, WideNode,
};
use crate::materials::colour_entry;
use crate::wavefront;
use crate::wide::WideBvh;
use crate::{GpuContext, GpuError};
use bvh::{Aabb, BuildConfig, Bvh, BvhNode, BvhWidth, SplitMethod, TriangleTest};
use rayon::prelude::*;
use spectral::SpectralMode;
use spectral::tables::{CIE_SAMPLES, CIE_X, CIE_Y, CIE_Z};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};
use tracer::accumulation::{Accumulation, FilmAccumulation};
use tracer::film::{Film, PixelStats};
use tracer::integrator::PathCounters;
use tracer::punctual::PunctualLight;
use tracer::render::{
    Backend, Capabilities, PixelRect, PrepareStats, PreparedScene, RenderSettings, SceneOptions, check_pass,
    check_sample_range,
};
use tracer::render::{CustomBsdfs, ShapeSupport};
use tracer::sampler::SamplerKind;
use tracer::{Scene, ShapeKind};
use wgpu::util::DeviceExt;

/// The most scattering events a GPU path may have, whatever `max_depth` says (paths cut
/// by it are counted).
pub const MAX_BOUNCES: u32 = 256;

/// The most pixel-samples one dispatch traces (fewer samples per pixel for larger
/// images, never less than one).
pub const DISPATCH_BUDGET: u64 = 1 << 18;

/// The most samples per pixel in one dispatch.
const MAX_SAMPLES_PER_DISPATCH: u32 = 64;

/// The most samples per pixel in one dispatch on a software rasteriser (Mesa's lavapipe
/// and llvmpipe): their shader compiler most likely bounds the iterations of each loop
/// (gallivm's loop limiter), and an invocation tracing many samples of deep paths through
/// a deep tree ran its traversal past that bound — lost hits. At 64 samples per dispatch
/// `textured_sponza_matches_the_cpu` finds Sponza 6 % too bright; at one, it agrees
/// (docs/gpu.md).
const SOFTWARE_SAMPLES_PER_DISPATCH: u32 = 1;

/// The most samples per pixel accumulated in f32 on the device before they are read
/// back and added to the film's exact sums (read-backs fall on multiples of it in the
/// sample index).
pub const SAMPLES_PER_READBACK: u32 = 1024;

/// The kernel's workgroup side (8 × 8 invocations, one per pixel).
const WORKGROUP: u32 = 8;

/// The record of an analytic shape in the kernel's tables (`wgsl/shapes.wgsl`): kind,
/// material id, light pmf, area and the CPU's primitive id, then the shape's own numbers.
pub fn shape_record(shape: &ShapeKind, material: u32, pmf: f32, prim: u32) -> Vec<f32> {
    let bits = f32::from_bits;
    let (code, own): (ShapeCode, Vec<f32>) = match shape {
        ShapeKind::Sphere(s) => {
            let mut v = s.centre.to_array().to_vec();
            v.extend([s.radius, bits(crate::kernel::sphere_method_code(s.method))]);
            (ShapeCode::Sphere, v)
        }
        ShapeKind::Cuboid(b) => {
            let mut v = vec![bits(b.is_axis_aligned() as u32)];
            v.extend(b.centre().to_array());
            v.extend(b.half_extent().to_array());
            v.extend(b.axes().iter().flat_map(|a| a.to_array()));
            let corners = if b.is_axis_aligned() { shapes::Shape::bounds(b) } else { bvh::Aabb::EMPTY };
            v.extend(corners.min.to_array());
            v.extend(corners.max.to_array());
            (ShapeCode::Cuboid, v)
        }
        ShapeKind::Polygon(p) => {
            let mut v = vec![
                bits(crate::kernel::polygon_test_code(p.inside_test())),
                bits(p.dropped_axis() as u32),
                bits(p.projected().len() as u32),
            ];
            v.extend(p.normal().to_array());
            v.extend(p.anchor().to_array());
            v.push(bits(p.triangles().len() as u32));
            v.extend(p.projected().iter().flat_map(|q| q.to_array()));
            for (t, &cdf) in p.triangles().iter().zip(p.triangle_cdf()) {
                v.extend(t.iter().flat_map(|q| q.to_array()));
                v.push(cdf);
            }
            (ShapeCode::Polygon, v)
        }
        ShapeKind::Implicit(s) => {
            let terms = s.poly.terms();
            let mut v = vec![bits(crate::kernel::root_solver_code(s.solver))];
            v.extend(s.bounds.min.to_array());
            v.extend(s.bounds.max.to_array());
            v.extend([bits(s.poly.degree()), bits(terms.len() as u32)]);
            for t in terms {
                let [x, y, z] = t.exps.map(u32::from);
                let (exponent, mantissa) = split_f64(t.coeff);
                v.extend([bits(x | y << 8 | z << 16), bits(exponent as u32)]);
                v.extend(mantissa);
            }
            (ShapeCode::Implicit, v)
        }
    };
    let mut record = vec![bits(code as u32), bits(material), pmf, shape.shape().area(), bits(prim)];
    record.extend(own);
    record
}

/// `x` as 2^e · (a + b + c) with a, b, c f32 and |a + b + c| ∈ [1, 2) (or 0) — exactly:
/// a holds the mantissa's first 24 bits, b the next 24, c the last 5, so their sum in f64 is
/// `x`'s mantissa. How an f64 travels in the kernel's f32 tables (WGSL cannot bitcast two
/// words to an f64); `wgsl/implicit.wgsl` sums the parts and applies `ldexp`.
pub fn split_f64(x: f64) -> (i32, [f32; 3]) {
    if x == 0.0 || !x.is_finite() {
        return (0, [x as f32, 0.0, 0.0]);
    }
    let (mut m, mut e) = (x, 0i32);
    // (Halving a number ≥ 2 and doubling any are exact.)
    while m.abs() >= 2.0 {
        m *= 0.5;
        e += 1;
    }
    while m.abs() < 1.0 {
        m *= 2.0;
        e -= 1;
    }
    let a = m as f32;
    let rest = m - a as f64;
    let b = rest as f32;
    let c = (rest - b as f64) as f32;
    (e, [a, b, c])
}

/// Fills a punctual light's floats of its light-table entry (`LightKind`'s layout), its
/// spectrum table at `spectrum` (bits), and returns its kind.
fn punctual_entry(light: &PunctualLight, spectrum: f32, entry: &mut [f32; LIGHT_FLOATS]) -> LightKind {
    let put =
        |entry: &mut [f32; LIGHT_FLOATS], at: usize, v: glam::Vec3| entry[at..at + 3].copy_from_slice(&v.to_array());
    match *light {
        PunctualLight::Point { position, .. } => {
            put(entry, 0, position);
            entry[3] = spectrum;
            LightKind::Point
        }
        PunctualLight::Spot { position, direction, cos_inner, cos_outer, .. } => {
            put(entry, 0, position);
            put(entry, 3, direction);
            entry[6] = cos_inner;
            entry[7] = cos_outer;
            entry[8] = spectrum;
            LightKind::Spot
        }
        PunctualLight::Directional { .. } => {
            let towards = light.towards();
            // The sampling frame of a sun's disk, as `Lights::sample_punctual` builds it.
            let (t, b) = towards.any_orthonormal_pair();
            let (cos_radius, solid_angle) = light.disk().map_or((1.0, 0.0), |(_, c, sa)| (c, sa));
            put(entry, 0, towards);
            entry[3] = cos_radius;
            entry[4] = solid_angle;
            entry[5] = light.disk_radiance_scale();
            entry[6] = spectrum;
            put(entry, 13, t);
            put(entry, 16, b);
            LightKind::Directional
        }
    }
}

/// [`KernelOptions::implicit_coeffs`] for `scene`: its implicit surfaces' highest degree + 1
/// (at least 5, the quartic's), 0 without.
fn implicit_coeffs(scene: &Scene) -> u32 {
    let degrees = scene.shapes.iter().filter_map(|s| match &s.shape {
        ShapeKind::Implicit(i) => Some(i.poly.degree() + 1),
        _ => None,
    });
    degrees.max().map_or(0, |n| n.max(5))
}

/// How the kernel's triangle BVH is built (binned SAH, leaves of at most four triangles
/// chosen by SAH); the 4- and 8-wide trees are collapsed from it.
pub fn triangle_build_config() -> BuildConfig {
    BuildConfig { method: SplitMethod::BinnedSah, max_leaf_size: 4, leaf_by_sah: true, ..BuildConfig::default() }
}

/// The textures of a scene as the kernel reads them (`wgsl/textures.wgsl`): each image's
/// texels once, however many maps use it, and the maps' descriptors and the materials'
/// records in the tables.
#[derive(Default)]
struct TexelUpload {
    /// RGBA8 texels, red in the lowest byte.
    texels: Vec<u32>,
    /// Each image's first texel, by its address.
    images: std::collections::HashMap<*const tracer::texture::TextureImage, u32>,
}

impl TexelUpload {
    /// Appends `textures`' record (and its maps' descriptors) to `tables`; its offset.
    fn material(&mut self, textures: &tracer::texture::MaterialTextures, tables: &mut Vec<f32>) -> u32 {
        use tracer::texture::AlphaMode;
        let none = f32::from_bits(u32::MAX);
        let mut map = |m: Option<&tracer::texture::TextureMap>, tables: &mut Vec<f32>| {
            m.map_or(none, |m| f32::from_bits(self.map(m, tables)))
        };
        let own = [
            map(textures.base_colour.as_ref(), tables),
            map(textures.specular.as_ref(), tables),
            map(textures.metallic_roughness.as_ref(), tables),
            map(textures.emissive.as_ref(), tables),
            map(textures.normal.as_ref().map(|n| &n.map), tables),
            textures.normal.as_ref().map_or(1.0, |n| n.scale),
            map(textures.bump.as_ref().map(|b| &b.map), tables),
            textures.bump.as_ref().map_or(1.0, |b| b.scale),
        ];
        let alpha = textures.alpha.as_ref();
        let (mode, cutoff) = match alpha.map(|a| a.mode) {
            None | Some(AlphaMode::Opaque) => (0, 0.0),
            Some(AlphaMode::Mask { cutoff }) => (1, cutoff),
            Some(AlphaMode::Blend) => (2, 0.0),
        };
        let alpha_map = map(alpha.and_then(|a| a.map.as_ref()), tables);
        let record = tables.len() as u32;
        tables.extend(own);
        tables.extend([f32::from_bits(mode), cutoff, alpha.map_or(1.0, |a| a.factor), alpha_map]);
        record
    }

    /// Appends the descriptor of `map` to `tables` (and its image's texels, the first
    /// time); its offset.
    fn map(&mut self, map: &tracer::texture::TextureMap, tables: &mut Vec<f32>) -> u32 {
        use tracer::texture::{Encoding, Wrap};
        let image = &*map.image;
        let texels = &mut self.texels;
        let first = *self.images.entry(image as *const _).or_insert_with(|| {
            let first = texels.len() as u32;
            for y in 0..image.height() {
                texels.extend((0..image.width()).map(|x| u32::from_le_bytes(image.texel(x, y))));
            }
            first
        });
        let wrap = |w: Wrap| match w {
            Wrap::Repeat => 0,
            Wrap::Clamp => 1,
            Wrap::Mirror => 2,
        };
        let bits = f32::from_bits;
        let t = map.transform;
        let offset = tables.len() as u32;
        tables.extend([
            bits(first),
            bits(image.width()),
            bits(image.height()),
            bits(wrap(map.wrap[0])),
            bits(wrap(map.wrap[1])),
            bits(if map.encoding == Encoding::Srgb { 0 } else { 1 }),
            bits(image.has_alpha() as u32),
            bits((t == glam::Mat3::IDENTITY) as u32),
            t.x_axis.x,
            t.x_axis.y,
            t.y_axis.x,
            t.y_axis.y,
            t.z_axis.x,
            t.z_axis.y,
        ]);
        offset
    }
}

/// log₂ of `n` rounded up to a power of two (at least 1): the bits of a Sobol index or a
/// Morton coordinate below `n`.
fn sobol_bits(n: u32) -> u32 {
    (n.max(1) as u64).next_power_of_two().trailing_zeros()
}

/// Bytes of one pixel's accumulator.
const PIXEL_BYTES: u64 = std::mem::size_of::<PixelAccum>() as u64;

/// The largest accumulator buffer a band uses (the device's limits may make it smaller).
const FILM_BAND_CAP: u64 = 64 << 20;

/// Storage buffers the kernel binds (six of ours, two of the material kernel's).
const STORAGE_BUFFERS: u32 = 8;

/// The analytic shapes the kernel intersects on any device (`wgsl/shapes.wgsl`).
const GPU_SHAPES: [&str; 3] = ["sphere", "box", "polygon"];

/// The kind of shape that needs f64 in the kernel (`wgsl/implicit.wgsl`).
const IMPLICIT: &str = "implicit surface";

/// Why implicit surfaces are refused on a device without f64.
const IMPLICIT_NEEDS_F64: &str = "this device lacks wgpu's SHADER_F64 feature (64-bit floats in shaders), in which the \
     implicit surfaces' root finder works (as on the CPU)";

/// What the GPU backend running the path tracer can render on a device with wgpu's
/// `SHADER_F64` (lavapipe and the Vulkan drivers of most desktop GPUs have it, wgpu's Metal
/// backend and many mobile and web adapters do not; see [`capabilities_on`]): hero, RGB and
/// 40-bin wavelengths, triangle meshes and every analytic shape, registered models and custom
/// BSDFs with a WGSL twin, both triangle tests, at most [`MAX_BOUNCES`] bounces.
pub fn capabilities() -> Capabilities {
    capabilities_for(GpuIntegrator::Path)
}

/// [`capabilities`] of a backend running `integrator` (on a device with `SHADER_F64`).
pub fn capabilities_for(integrator: GpuIntegrator) -> Capabilities {
    capabilities_with(integrator, true)
}

/// [`capabilities_for`] on the device of `ctx`: without `SHADER_F64`
/// ([`GpuContext::shader_f64`]) implicit surfaces are refused.
pub fn capabilities_on(integrator: GpuIntegrator, ctx: &GpuContext) -> Capabilities {
    capabilities_with(integrator, ctx.shader_f64())
}

fn capabilities_with(integrator: GpuIntegrator, shader_f64: bool) -> Capabilities {
    let mut kinds = GPU_SHAPES.to_vec();
    if shader_f64 {
        kinds.push(IMPLICIT);
    }
    Capabilities {
        backend: "gpu",
        spectral_modes: vec![SpectralMode::Hero, SpectralMode::Rgb, SpectralMode::Bins40],
        // ZSobol first (the default): on an H100 it reaches the independent sampler's error
        // 1.76× sooner on the Cornell box (docs/gpu.md).
        samplers: vec![SamplerKind::ZSobol, SamplerKind::Sobol, SamplerKind::Independent],
        analytic_shapes: ShapeSupport { kinds, why_not: IMPLICIT_NEEDS_F64 },
        custom_bsdfs: CustomBsdfs::WithWgslTwin,
        punctual_lights: true,
        textures: true,
        environment_maps: true,
        triangle_tests: vec![TriangleTest::Watertight, TriangleTest::MollerTrumbore],
        // Auto is the binary tree: in this megakernel the 4-wide one (`crate::wide`) renders
        // 1.2–1.8× slower on an H100 and the 8-wide one 3–8× slower on an H200 (docs/gpu.md);
        // both stay selectable for comparisons (the 4-wide pays in the wavefront).
        bvh_widths: vec![BvhWidth::Auto, BvhWidth::Two, BvhWidth::Four, BvhWidth::Eight],
        integrator: integrator.name(),
        // bdpt has no backend cap: its subpaths' own (`BDPT_MAX_VERTICES`), as on the CPU.
        max_bounces: match integrator {
            GpuIntegrator::Whitted => Some(crate::kernel::WHITTED_MAX_DEPTH),
            GpuIntegrator::Bdpt => None,
            _ => Some(MAX_BOUNCES),
        },
        extension: integrator == GpuIntegrator::Path,
        diffuse_depth: integrator == GpuIntegrator::Path,
        bvh_builders: true,
        sample_block: SAMPLES_PER_READBACK,
        // The path tracer alone has a wavefront (wgsl/wavefront.wgsl).
        wavefront: integrator == GpuIntegrator::Path,
        splats: integrator.splats(),
        light_tree: integrator.takes_light_tree(),
    }
}

/// The atlas of `scene` (already flattened) for the atlas integrator, built as the CPU
/// backend builds it (`AtlasGi::for_scene`: its own BVH with the render's triangle test,
/// lights and view), all but its gather, which the device runs.
fn build_atlas(
    scene: &Scene,
    settings: &tracer::integrator::AtlasSettings,
    triangle_test: TriangleTest,
) -> Result<tracer::integrator::Atlas, GpuError> {
    with_atlas_view(scene, triangle_test, |view| tracer::integrator::Atlas::build_ungathered(view, settings))?
        .map_err(atlas_failed)
}

/// Runs `f` on the view the CPU's atlas code sees `scene` through: its own BVH with the
/// render's triangle test, its lights.
fn with_atlas_view<R>(
    scene: &Scene,
    triangle_test: TriangleTest,
    f: impl FnOnce(&tracer::integrator::SceneView) -> R,
) -> Result<R, GpuError> {
    let options = tracer::SceneOptions { triangle_test, ..Default::default() };
    let geometry = tracer::geometry::Geometry::build(scene, &options).map_err(atlas_failed)?;
    let lights = tracer::lights::Lights::new(scene);
    Ok(f(&tracer::integrator::SceneView::new(scene, &geometry, &lights)))
}

/// The error of an atlas the CPU's code could not build.
fn atlas_failed(e: tracer::Error) -> GpuError {
    GpuError::Unsupported(format!("an atlas of this scene ({e})"))
}

/// One triangle BVH in the kernel's node layout (the world's, or a placed object's),
/// its child and leaf references already offset to where it lands in the node and
/// triangle arrays.
struct TriangleTree {
    nodes: Vec<u8>,
    /// Bytes per node.
    node_bytes: usize,
    /// Nodes as the kernel counts them (an 8-wide node once).
    node_count: usize,
    /// Entries of the node array it takes (an 8-wide node two).
    entries: usize,
    /// The layout with this tree's stack bound.
    layout: NodeLayout,
    /// Its triangles in leaf order (indices into the soup it was built from).
    prim_ids: Vec<u32>,
}

impl TriangleTree {
    /// Builds the tree over `soup` in `layout`, for node entries from `node_base` and
    /// triangles from `tri_base` on.
    fn build(
        soup: &[[glam::Vec3; 3]],
        config: BuildConfig,
        layout: NodeLayout,
        node_base: u32,
        tri_base: u32,
    ) -> Result<Self, GpuError> {
        let bvh = Bvh::build(soup, config).map_err(|e| GpuError::Unsupported(format!("this geometry ({e})")))?;
        let prim_ids = bvh.prim_ids().to_vec();
        Ok(match layout {
            NodeLayout::Binary => {
                // An inner node's left child follows it; `index` is its right child or a
                // leaf's first triangle.
                let nodes: Vec<BvhNode> = bvh
                    .nodes()
                    .iter()
                    .map(|n| BvhNode { index: n.index + if n.count > 0 { tri_base } else { node_base }, ..*n })
                    .collect();
                let entries = nodes.len();
                let bytes = bytemuck::cast_slice(&nodes).to_vec();
                Self {
                    nodes: bytes,
                    node_bytes: std::mem::size_of::<BvhNode>(),
                    node_count: entries,
                    entries,
                    layout,
                    prim_ids,
                }
            }
            NodeLayout::Wide4 { .. } | NodeLayout::Wide8 { .. } => {
                let width = if matches!(layout, NodeLayout::Wide4 { .. }) { 4 } else { 8 };
                let mut wide = WideBvh::collapse(&bvh, width);
                for node in &mut wide.nodes {
                    for (index, &count) in node.index.iter_mut().zip(&node.count) {
                        *index += match count {
                            0 => node_base,
                            crate::kernel::WIDE_EMPTY => 0,
                            _ => tri_base,
                        };
                    }
                }
                let stack = wide.stack_bound;
                let layout = if width == 4 { NodeLayout::Wide4 { stack } } else { NodeLayout::Wide8 { stack } };
                Self {
                    nodes: bytemuck::cast_slice(&wide.nodes).to_vec(),
                    node_bytes: std::mem::size_of::<WideNode>() * (width / crate::wide::WIDTH),
                    node_count: wide.nodes.len() * crate::wide::WIDTH / width,
                    entries: wide.nodes.len(),
                    layout,
                    prim_ids,
                }
            }
        })
    }
}

/// Floats of an instance's record in the tables (`wgsl/instances.wgsl`): world-to-object
/// and object-to-world as three rows of four (0..12, 12..24), the normal matrix's rows
/// (24..27, 28..31, 32..35) with the orientation (27: −1 for a mirroring placement), the
/// object tree's root entry (31, bits), the material replacing the object's (35, bits;
/// `u32::MAX` for none) and the CPU primitive id of its first triangle (36, bits).
pub const INSTANCE_FLOATS: usize = 40;

/// Appends the instances' records, the box BVH over their world bounds (binary nodes of
/// eight floats, as the shapes') and its leaf slots (record offsets, bits) right after
/// the nodes; returns the nodes' offset and count (0: no instances).
fn instance_tables(
    scene: &Scene,
    object_trees: &[Option<(u32, Vec<u32>)>],
    tables: &mut Vec<f32>,
) -> Result<(u32, u32), GpuError> {
    let bits = f32::from_bits;
    let rows = |m: glam::Affine3A| {
        let m = glam::Mat4::from(m).transpose();
        [m.x_axis, m.y_axis, m.z_axis].into_iter().flat_map(|r| r.to_array()).collect::<Vec<f32>>()
    };
    let mut records = Vec::with_capacity(scene.instances.len());
    let mut boxes = Vec::with_capacity(scene.instances.len());
    let mut first_prim = (scene.triangles.len() + scene.shapes.len()) as u32;
    for inst in &scene.instances {
        let object = &scene.objects[inst.object as usize];
        // (Objects without triangles have no tree: nothing to hit.)
        let Some((root, _)) = &object_trees[inst.object as usize] else { continue };
        let to_world = glam::Affine3A::from_mat4(inst.transform);
        let normal = to_world.matrix3.inverse().transpose();
        let orientation = if to_world.matrix3.determinant() < 0.0 { -1.0 } else { 1.0 };
        records.push(tables.len() as u32);
        tables.extend(rows(to_world.inverse()));
        tables.extend(rows(to_world));
        let n = glam::Mat3::from(normal).transpose();
        tables.extend(n.x_axis.to_array().into_iter().chain([orientation]));
        tables.extend(n.y_axis.to_array().into_iter().chain([bits(*root)]));
        tables.extend(n.z_axis.to_array().into_iter().chain([bits(inst.material.unwrap_or(u32::MAX))]));
        tables.extend([bits(first_prim), 0.0, 0.0, 0.0]);
        first_prim += object.triangles.len() as u32;
        boxes.push(object.bounds().transformed(&to_world));
    }
    if boxes.is_empty() {
        return Ok((0, 0));
    }
    let bvh = bvh::BoxBvh::build(&boxes, tracer::Geometry::shape_build_config())
        .map_err(|e| GpuError::Unsupported(format!("these instances ({e})")))?;
    let nodes_offset = tables.len() as u32;
    for n in bvh.nodes() {
        tables.extend(n.min);
        tables.push(bits(n.index));
        tables.extend(n.max);
        tables.push(bits(n.count));
    }
    tables.extend(bvh.order().iter().map(|&k| bits(records[k as usize])));
    Ok((nodes_offset, bvh.node_count() as u32))
}

/// What the kernel's uniforms and the camera need of a scene besides its buffers, kept
/// from [`SceneData`] into [`GpuScene`].
#[derive(Clone, Copy, Debug)]
struct SceneConstants {
    integrator: GpuIntegrator,
    white_offset: u32,
    node_count: u32,
    light_count: u32,
    punctual_first: u32,
    lights_offset: u32,
    shape_nodes_offset: u32,
    shape_node_count: u32,
    shape_slots_offset: u32,
    instance_nodes_offset: u32,
    instance_node_count: u32,
    material_textures_offset: u32,
    uplift_offset: u32,
    decode_offset: u32,
    envmap_offset: u32,
    atlas_offset: u32,
    env_offset: u32,
    env_pmf: f32,
    scene_flags: u32,
    emitters: usize,
    /// `Params::light_tree`.
    light_tree: [u32; 4],
}

/// A scene as the flat arrays the kernel reads, built on the CPU; see the module docs.
pub struct SceneData {
    /// The BVH nodes in the layout of `options.nodes`, as bytes.
    nodes: Vec<u8>,
    /// Bytes per node.
    node_bytes: usize,
    tri_verts: Vec<[f32; 4]>,
    tri_vidx: Vec<[u32; 4]>,
    /// The textures' texels (RGBA8 words), empty without textures.
    texels: Vec<u32>,
    attrs: Vec<[f32; 4]>,
    tables: Vec<f32>,
    material_wgsl: String,
    material_data: Vec<u32>,
    spectra: Vec<f32>,
    constants: SceneConstants,
    options: KernelOptions,
    build_time: Duration,
    /// The atlas integrator's atlas, waiting for its gather on the device.
    atlas: Option<PendingGather>,
}

/// An atlas whose gather the device runs once the scene is uploaded
/// ([`GpuScene::gather_atlas`]), and where its irradiance goes in the tables.
struct PendingGather {
    atlas: tracer::integrator::Atlas,
    problem: tracer::integrator::GatherProblem,
    settings: tracer::integrator::AtlasSettings,
    /// The float index of the irradiance in the tables.
    irradiance_at: usize,
}

impl SceneData {
    /// Flattens `scene` (validated, within the backend's capabilities) for a kernel with
    /// `options`: builds its BVH and light distribution and generates its materials.
    /// Fails with [`GpuError::Unsupported`] for what the kernel cannot trace (custom BSDFs
    /// without a WGSL twin) and passes on the material code generator's errors. A scene with
    /// implicit surfaces gets a kernel that needs `SHADER_F64` (the backend's capability
    /// check refuses it on devices without).
    pub fn new(scene: &Scene, options: KernelOptions) -> Result<Self, GpuError> {
        if scene.instances.iter().any(|i| scene.instance_has_light(i)) {
            return Err(GpuError::Unsupported(
                "instances on sampled area lights (flatten them first: Scene::flatten_light_instances)".into(),
            ));
        }
        let kernel = crate::materials::generate(&scene.materials, true)?;
        let start = Instant::now();
        let config = BuildConfig { method: options.bvh_builder, ..triangle_build_config() };
        // The world's tree first, then one per placed object (two-level traversal: the
        // instances' box BVH in the tables leads to them).
        let world = TriangleTree::build(&scene.triangle_soup(), config, options.nodes, 0, 0)?;
        let placed: Vec<bool> = {
            let mut placed = vec![false; scene.objects.len()];
            scene.instances.iter().for_each(|i| placed[i.object as usize] = true);
            placed
        };
        let mut nodes = world.nodes;
        let (mut entries, mut triangles) = (world.entries, world.prim_ids.len());
        let mut layout = world.layout;
        let mut object_trees = vec![None; scene.objects.len()];
        // (An object without triangles gets no tree: its placements are left out.)
        for (k, o) in scene.objects.iter().enumerate().filter(|&(k, o)| placed[k] && !o.triangles.is_empty()) {
            let soup: Vec<_> = (0..o.triangles.len()).map(|i| o.triangle_vertices(i)).collect();
            let tree = TriangleTree::build(&soup, config, options.nodes, entries as u32, triangles as u32)?;
            layout = layout.max_stack(tree.layout);
            nodes.extend(tree.nodes);
            let root = entries as u32;
            entries += tree.entries;
            triangles += tree.prim_ids.len();
            object_trees[k] = Some((root, tree.prim_ids));
        }
        let node_bytes = world.node_bytes;
        let node_count = world.node_count;
        let textured = scene.materials.iter().any(|m| m.textures.is_some());
        let env_map = scene.environment.as_ref().and_then(|e| e.map.as_deref());
        let options = KernelOptions {
            nodes: layout,
            shapes: !scene.shapes.is_empty(),
            instances: !scene.instances.is_empty(),
            punctual_lights: !scene.punctual_lights.is_empty(),
            implicit_coeffs: implicit_coeffs(scene),
            textures: textured,
            cutouts: scene.materials.iter().any(|m| m.alpha().is_some()),
            env_map: env_map.is_some(),
            ..options
        };
        let build_time = start.elapsed();
        // (Power sampling's probabilities stay those of `Lights::new`, with a tree too.) A
        // tree only for the integrators whose kernels walk one.
        let sampler = match options.integrator.takes_light_tree() {
            true => options.light_sampler,
            false => tracer::LightSampler::Power,
        };
        let lights = tracer::lights::Lights::with_sampler(scene, sampler);
        let pmfs = lights.prim_pmfs();

        // Per triangle in leaf order: its vertices, material, light pmf and the CPU's
        // primitive id (an object's: its own index, the instance adds its first id).
        let mut tri_verts = Vec::with_capacity(3 * triangles);
        let mut push_triangle = |v: [glam::Vec3; 3], material: u32, pmf: f32, prim: u32| {
            tri_verts.push([v[0].x, v[0].y, v[0].z, f32::from_bits(material)]);
            tri_verts.push([v[1].x, v[1].y, v[1].z, pmf]);
            tri_verts.push([v[2].x, v[2].y, v[2].z, f32::from_bits(prim)]);
        };
        for &prim in &world.prim_ids {
            let pmf = pmfs.get(prim as usize).copied().unwrap_or(0.0);
            push_triangle(scene.triangle_vertices(prim as usize), scene.material_ids[prim as usize], pmf, prim);
        }
        for (o, tree) in scene.objects.iter().zip(&object_trees) {
            for &i in tree.iter().flat_map(|(_, ids)| ids) {
                // (Placements on sampled lights were flattened: no instanced triangle is sampled.)
                push_triangle(o.triangle_vertices(i as usize), o.material_ids[i as usize], 0.0, i);
            }
        }
        let uploaded = scene.objects.iter().zip(&object_trees).filter(|(_, t)| t.is_some()).map(|(o, _)| o.mesh());
        let meshes: Vec<tracer::scene::MeshRef> = std::iter::once(scene.mesh()).chain(uploaded).collect();
        let mut scene_flags = 0;
        if meshes.iter().any(|m| !m.normals.is_empty()) {
            scene_flags |= HAS_NORMALS;
        }
        if meshes.iter().any(|m| !m.tangents.is_empty()) {
            scene_flags |= HAS_TANGENTS;
        }
        // Texture coordinates only where a material reads textures.
        if textured && meshes.iter().any(|m| !m.uvs.is_empty()) {
            scene_flags |= HAS_UVS;
        }
        let (tri_vidx, attrs) = if scene_flags & (HAS_NORMALS | HAS_TANGENTS | HAS_UVS) != 0 {
            let (mut vidx, mut attrs) = (Vec::with_capacity(triangles), Vec::new());
            let mut append = |mesh: &tracer::scene::MeshRef, order: &[u32]| {
                let base = (attrs.len() / 2) as u32;
                vidx.extend(order.iter().map(|&p| {
                    let t = mesh.triangles[p as usize];
                    [t[0] + base, t[1] + base, t[2] + base, 0]
                }));
                // Per vertex: normal and u, tangent and v (zeros where the mesh has none).
                let uvs = if scene_flags & HAS_UVS != 0 { mesh.uvs } else { &[] };
                attrs.extend((0..mesh.positions.len()).flat_map(|i| {
                    let n = mesh.normals.get(i).copied().unwrap_or([0.0; 3]);
                    let t = mesh.tangents.get(i).copied().unwrap_or([0.0; 3]);
                    let uv = uvs.get(i).copied().unwrap_or([0.0; 2]);
                    [[n[0], n[1], n[2], uv[0]], [t[0], t[1], t[2], uv[1]]]
                }));
            };
            append(&scene.mesh(), &world.prim_ids);
            for (o, tree) in scene.objects.iter().zip(&object_trees) {
                if let Some((_, ids)) = tree {
                    append(&o.mesh(), ids);
                }
            }
            (vidx, attrs)
        } else {
            (Vec::new(), Vec::new())
        };

        // Tables: CIE x̄ȳz̄ interleaved, the environment's spectrum, the lights.
        let mut tables = Vec::with_capacity(4 * CIE_SAMPLES + LIGHT_FLOATS * lights.prims().len());
        for i in 0..CIE_SAMPLES {
            tables.extend([CIE_X[i], CIE_Y[i], CIE_Z[i]]);
        }
        let env_offset = tables.len() as u32;
        let black = spectral::spectrum::Colour::constant(0.0);
        tables.extend(colour_entry(scene.environment.as_ref().map_or(&black, |e| &e.radiance)));
        if scene.environment.is_some() {
            scene_flags |= HAS_ENVIRONMENT;
        }
        if kernel.features.dispersion {
            scene_flags |= HAS_DISPERSION;
        }
        // Ambient occlusion's white: the CPU's `AmbientOcclusion` value, tabulated.
        let white_offset = tables.len() as u32;
        if let GpuIntegrator::AmbientOcclusion { .. } = options.integrator {
            tables.extend(colour_entry(&tracer::AmbientOcclusion::white()));
        }
        // The analytic shapes: their records, the slot table in the BVH's leaf order, and
        // the BVH's nodes.
        let mut shape_records = vec![0u32; scene.shapes.len()];
        for (k, shape) in scene.shapes.iter().enumerate() {
            shape_records[k] = tables.len() as u32;
            let prim = scene.triangles.len() + k;
            let pmf = pmfs.get(prim).copied().unwrap_or(0.0);
            tables.extend(shape_record(&shape.shape, shape.material, pmf, prim as u32));
        }
        let (shape_nodes_offset, shape_node_count, shape_slots_offset) = if scene.shapes.is_empty() {
            (0, 0, 0)
        } else {
            let boxes: Vec<_> = scene.shapes.iter().map(|s| s.shape.shape().bounds()).collect();
            let shape_bvh = bvh::BoxBvh::build(&boxes, tracer::Geometry::shape_build_config())
                .map_err(|e| GpuError::Unsupported(format!("these shapes ({e})")))?;
            let nodes_offset = tables.len() as u32;
            for n in shape_bvh.nodes() {
                tables.extend(n.min);
                tables.push(f32::from_bits(n.index));
                tables.extend(n.max);
                tables.push(f32::from_bits(n.count));
            }
            let slots_offset = tables.len() as u32;
            tables.extend(shape_bvh.order().iter().map(|&k| f32::from_bits(shape_records[k as usize])));
            (nodes_offset, shape_bvh.node_count() as u32, slots_offset)
        };
        let (instance_nodes_offset, instance_node_count) = instance_tables(scene, &object_trees, &mut tables)?;

        // The atlas integrator's atlas, built here by the CPU's code (the same atlas the
        // CPU renders with, for the same scene and settings); its gather runs on the device
        // after the upload (`GpuScene::gather_atlas`).
        let atlas = match options.integrator {
            GpuIntegrator::Atlas(settings) => Some((build_atlas(scene, &settings, options.triangle_test)?, settings)),
            _ => None,
        };
        // The uplift table (textures, environment maps and the atlas's irradiance turn RGB
        // into spectra by it).
        let mut uplift_offset = 0;
        if textured || env_map.is_some() || atlas.is_some() {
            uplift_offset = tables.len() as u32;
            let uplift = spectral::uplift::uplift_table();
            tables.extend(uplift.z_nodes());
            tables.extend(uplift.coefficients().iter().flat_map(|c| [c.c0, c.c1, c.c2]));
        }
        // Where the next entry of the tables goes, as a record stores it (bits).
        let at = |tables: &Vec<f32>| f32::from_bits(tables.len() as u32);
        // The D65 table the environment map's and the atlas's RGB illuminants are uplifted
        // with (once for both).
        let d65_at = (env_map.is_some() || atlas.is_some()).then(|| {
            let d65_at = at(&tables);
            tables.extend(spectral::tables::D65);
            d65_at
        });
        // An environment map: its texels, its sampling distribution, the D65 table.
        let mut envmap_offset = 0;
        if let Some(map) = env_map {
            let parts = map.parts();
            let (texels, (cos, sin), conditional, marginal) =
                (parts.texels, parts.rotation, parts.conditional, parts.marginal);
            let record = tables.len();
            tables.extend([0.0; 9]);
            let texels_at = at(&tables);
            tables.extend(texels.iter().flatten());
            let conditional_at = at(&tables);
            tables.extend(conditional);
            let marginal_at = at(&tables);
            tables.extend(marginal);
            let bits = f32::from_bits;
            tables[record..record + 9].copy_from_slice(&[
                bits(map.width()),
                bits(map.height()),
                cos,
                sin,
                texels_at,
                conditional_at,
                marginal_at,
                d65_at.expect("uploaded for the map"),
                spectral::uplift::d65_inv_norm(),
            ]);
            envmap_offset = record as u32;
        }
        // The atlas: its record, each primitive's chart, the charts' projections, the
        // gathered irradiance, the D65 table its lookups are uplifted with.
        let mut atlas_offset = 0;
        let mut pending_gather = None;
        if let Some((atlas, settings)) = atlas {
            atlas_offset = tables.len() as u32;
            let record = tables.len();
            tables.extend([0.0; 9]);
            let prim_charts_at = at(&tables);
            tables.extend(atlas.prim_charts().iter().map(|&c| f32::from_bits(c)));
            let charts_at = at(&tables);
            for c in atlas.chart_projections() {
                tables.extend(c.origin.to_array().into_iter().chain(c.u.to_array()).chain(c.v.to_array()));
                tables.extend(c.min.to_array().into_iter().chain(c.corner.to_array()));
            }
            let texels_at = at(&tables);
            let irradiance_at = tables.len();
            tables.extend(atlas.irradiance().iter().flatten());
            let (width, height) = atlas.size();
            tables[record..record + 9].copy_from_slice(&[
                f32::from_bits(width),
                f32::from_bits(height),
                atlas.density(),
                prim_charts_at,
                charts_at,
                texels_at,
                d65_at.expect("uploaded for the atlas"),
                spectral::uplift::d65_inv_norm(),
                f32::from_bits(atlas.prim_charts().len() as u32),
            ]);
            let problem = atlas.gather_problem(&settings);
            pending_gather = Some(PendingGather { atlas, problem, settings, irradiance_at });
        }
        // Textures: the texel decode tables, each material's maps.
        let (mut decode_offset, mut material_textures_offset) = (0, 0);
        let mut texels = TexelUpload::default();
        if textured {
            decode_offset = tables.len() as u32;
            tables.extend((0..256).map(|i| spectral::colour::srgb_decode(i as f32 / 255.0)));
            tables.extend((0..256).map(|i| i as f32 / 255.0));
            let records: Vec<u32> = scene
                .materials
                .iter()
                .map(|m| m.textures.as_deref().map_or(u32::MAX, |t| texels.material(t, &mut tables)))
                .collect();
            material_textures_offset = tables.len() as u32;
            tables.extend(records.into_iter().map(f32::from_bits));
        }

        // The light table, in the order of the CPU's cdf: emissive triangles and shapes,
        // then the punctual lights, point and spot lights first (each with its spectrum
        // tabulated at 1 nm after the table). The tree's lights are entries of this table.
        let lights_offset = tables.len() as u32;
        let mut punctual_spectra = Vec::new();
        let entries = lights.cdf().len();
        let spectra_offset = lights_offset as usize + LIGHT_FLOATS * entries;
        for (k, &cdf) in lights.cdf().iter().enumerate() {
            let mut entry = [0.0f32; LIGHT_FLOATS];
            let (kind, material, pmf) = match lights.prims().get(k) {
                Some(&prim) if (prim as usize) < scene.triangles.len() => {
                    let v = scene.triangle_vertices(prim as usize);
                    for (i, p) in v.iter().enumerate() {
                        entry[3 * i..3 * i + 3].copy_from_slice(&p.to_array());
                    }
                    (LightKind::Triangle, scene.material_ids[prim as usize], pmfs[prim as usize])
                }
                Some(&prim) => {
                    let shape = prim as usize - scene.triangles.len();
                    entry[0] = f32::from_bits(shape_records[shape]);
                    (LightKind::Shape, scene.shapes[shape].material, pmfs[prim as usize])
                }
                None => {
                    let index = lights.punctual_entries()[k - lights.prims().len()] as usize;
                    let light = &scene.punctual_lights[index];
                    let spectrum = f32::from_bits((spectra_offset + punctual_spectra.len()) as u32);
                    punctual_spectra.extend(colour_entry(light.colour()));
                    let kind = punctual_entry(light, spectrum, &mut entry);
                    (kind, u32::MAX, lights.punctual_pmf(index))
                }
            };
            entry[LIGHT_CDF as usize] = cdf;
            entry[LIGHT_PMF as usize] = pmf;
            entry[LIGHT_MATERIAL as usize] = f32::from_bits(material);
            entry[LIGHT_KIND] = f32::from_bits(kind as u32);
            tables.extend(entry);
        }
        tables.extend(punctual_spectra);

        // The light tree: its nodes, the primitive → emitter table, the trails.
        let mut light_tree = [0; 4];
        let tree = lights.tree_tables();
        if let Some(t) = &tree {
            // (The kernel's lower end of the stretch is `env_pmf`.)
            debug_assert_eq!(t.lo, lights.environment_pmf());
            light_tree[0] = tables.len() as u32;
            tables.extend_from_slice(&t.nodes);
            light_tree[1] = tables.len() as u32;
            // Only the ids an emitter can have: the world's triangles and the shapes (placed
            // objects' triangles are never sampled, and the kernel never looks them up).
            let ids = scene.triangles.len() + scene.shapes.len();
            tables.extend(t.slots[..ids].iter().map(|&k| f32::from_bits(k)));
            light_tree[2] = tables.len() as u32;
            tables.extend(t.trails.iter().flatten().map(|&w| f32::from_bits(w)));
            light_tree[3] = t.hi.to_bits();
        }
        let options = KernelOptions { light_tree: tree.is_some(), ..options };

        let constants = SceneConstants {
            integrator: options.integrator,
            white_offset,
            node_count: node_count as u32,
            light_count: lights.cdf().len() as u32,
            punctual_first: lights.prims().len() as u32,
            lights_offset,
            shape_nodes_offset,
            shape_node_count,
            shape_slots_offset,
            instance_nodes_offset,
            instance_node_count,
            material_textures_offset,
            uplift_offset,
            decode_offset,
            envmap_offset,
            atlas_offset,
            env_offset,
            env_pmf: lights.environment_pmf(),
            scene_flags,
            emitters: lights.emitter_count(),
            light_tree,
        };
        Ok(Self {
            constants,
            nodes,
            node_bytes,
            tri_verts,
            tri_vidx,
            texels: texels.texels,
            attrs,
            tables,
            material_wgsl: kernel.wgsl,
            material_data: kernel.data,
            spectra: kernel.spectra,
            options,
            build_time,
            atlas: pending_gather,
        })
    }

    /// The light table's entries as the kernel reads them ([`LIGHT_FLOATS`] each; see
    /// [`LightKind`] for what each kind's floats hold).
    pub fn light_entries(&self) -> impl Iterator<Item = &[f32]> {
        let first = self.constants.lights_offset as usize;
        let end = first + LIGHT_FLOATS * self.constants.light_count as usize;
        self.tables[first..end].chunks_exact(LIGHT_FLOATS)
    }

    /// The kernel options with the scene's own features filled in.
    pub fn options(&self) -> &KernelOptions {
        &self.options
    }

    /// The BVH nodes as uploaded (binary, 4- or 8-wide, [`KernelOptions::nodes`]).
    pub fn node_bytes(&self) -> &[u8] {
        &self.nodes
    }

    /// What each storage buffer holds and how many bytes it needs, in binding order
    /// (the per-pixel accumulators are not included: their size follows the image and
    /// is split into bands to fit).
    pub fn buffer_sizes(&self) -> [(&'static str, u64); 8] {
        let bytes = |n: usize, each: usize| (n * each) as u64;
        [
            ("BVH nodes", self.nodes.len() as u64),
            ("triangle vertices", bytes(self.tri_verts.len(), 16)),
            ("triangle vertex indices", bytes(self.tri_vidx.len(), 16)),
            ("vertex normals and tangents", bytes(self.attrs.len(), 16)),
            ("spectral tables and lights", bytes(self.tables.len(), 4)),
            ("material parameters", bytes(self.material_data.len(), 4)),
            ("material spectra", bytes(self.spectra.len(), 4)),
            ("texels", bytes(self.texels.len(), 4)),
        ]
    }

    /// Checks every buffer against `limits` (`max_storage_buffer_binding_size`,
    /// `max_buffer_size`) and the number of storage buffers the kernel binds against
    /// `max_storage_buffers_per_shader_stage`; the error names the buffer, the limit and
    /// both sizes.
    pub fn check_limits(&self, limits: &wgpu::Limits) -> Result<(), GpuError> {
        // One more for the texels where a material reads textures, two for bdpt's splats
        // and scratch, three for the wavefront's paths, queues and dispatch sizes (its
        // control stages bind all three).
        let splats = self.options.integrator.splats();
        let wavefront = self.options.wavefront;
        let storage_buffers =
            STORAGE_BUFFERS + u32::from(self.options.textures) + 2 * u32::from(splats) + 3 * u32::from(wavefront);
        if limits.max_storage_buffers_per_shader_stage < storage_buffers {
            return Err(GpuError::Unsupported(format!(
                "a device with {} storage buffers per shader stage (max_storage_buffers_per_shader_stage; the kernel \
                 binds {storage_buffers}{}{}{})",
                limits.max_storage_buffers_per_shader_stage,
                if self.options.textures { ", one of them for the textures" } else { "" },
                if splats { ", two for bdpt's splat image and scratch" } else { "" },
                if wavefront { ", three for the wavefront's paths, queues and dispatch sizes" } else { "" }
            )));
        }
        for (what, needed) in self.buffer_sizes() {
            check_size(what, needed, limits)?;
        }
        Ok(())
    }

    /// The WGSL of the whole kernel: the generated materials, the generated header and
    /// the hand-written integrator ([`crate::kernel::source`]).
    pub fn shader_source(&self) -> String {
        crate::kernel::source(&self.material_wgsl, &self.options)
    }
}

/// One buffer of `needed` bytes against the binding and allocation limits.
pub(crate) fn check_size(what: &'static str, needed: u64, limits: &wgpu::Limits) -> Result<(), GpuError> {
    let checks = [
        ("max_storage_buffer_binding_size", limits.max_storage_buffer_binding_size),
        ("max_buffer_size", limits.max_buffer_size),
    ];
    for (limit_name, limit) in checks {
        if needed > limit {
            return Err(GpuError::Limit { what, needed, limit_name, limit });
        }
    }
    Ok(())
}

/// The per-band accumulators, their read-back copy and the bind group that uses them.
struct FilmBuffers {
    pixels: u64,
    accum: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// A wavefront kernel's paths and queues (in the bind group).
    wavefront: Option<wavefront::Buffers>,
    /// `None` for bdpt (see [`GpuScene::render_gpu`]).
    bind_group: Option<wgpu::BindGroup>,
}

/// A compiled kernel: its main pipeline (the megakernel's `pt_main`, or the wavefront's
/// shading stage) and, for a wavefront, its other stages.
#[derive(Clone)]
pub(crate) struct Kernel {
    /// The main pipeline and its module (held: the device finds the kernel again while
    /// a scene holds it).
    main: Arc<crate::context::CompiledKernel>,
    stages: Option<Arc<wavefront::Stages>>,
}

/// bdpt's buffers: its splat image (`wgsl/bdpt.wgsl`: [`SPLAT_HEADER_WORDS`], then nine
/// words per pixel of the whole image), the image's read-back copy, and the subpaths'
/// scratch for `slots` invocations ([`BDPT_SLOT_BYTES`] each).
pub(crate) struct BdptBuffers {
    pixels: u64,
    slots: u64,
    sums: wgpu::Buffer,
    readback: wgpu::Buffer,
    scratch: wgpu::Buffer,
}

/// The most bytes of scratch bdpt's bands use (less where the device's limits say so).
const BDPT_SCRATCH_CAP: u64 = 1 << 30;

/// Bytes of a splat image of `pixels` pixels.
fn splat_bytes(pixels: u64) -> u64 {
    4 * (SPLAT_HEADER_WORDS as u64 + 9 * pixels)
}

/// A splat image's channel sum as the film keeps it: the kernel's 96-bit two's complement
/// in 2⁻³² units (low word first) in 2⁻⁶⁴ units.
fn splat_sum(words: &[u32]) -> i128 {
    let v = words[0] as u128 | (words[1] as u128) << 32 | (words[2] as u128) << 64;
    // Sign-extend the 96 bits, then scale by 2³² (exact: |v| < 2⁹⁵).
    (((v << 32) as i128) >> 32) << 32
}

/// The wavefront follows one path per camera ray, as hero wavelengths and RGB do; the
/// 40-bin mode's ten paths per sample are the megakernel's. (Checked when a scene is
/// prepared for its first render; a prepared wavefront's capabilities lack the mode.)
fn check_wavefront_mode(options: &KernelOptions) -> Result<(), GpuError> {
    if options.wavefront && options.mode == SpectralMode::Bins40 {
        return Err(GpuError::Unsupported(
            "the 40-bin spectral mode in the wavefront (its ten paths per sample run in the megakernel: drop \
             --wavefront, or render in hero or RGB mode)"
                .into(),
        ));
    }
    Ok(())
}

/// A scene on the device, made by [`GpuBackend::prepare`]: its buffers, the compiled
/// pipeline and the scene itself (for the camera and for messages).
pub struct GpuScene {
    ctx: Arc<GpuContext>,
    scene: Scene,
    bounds: Aabb,
    /// The kernels compiled so far, by (sampler, spectral mode) (both are compiled in).
    pipelines: Mutex<Vec<((SamplerKind, SpectralMode), Kernel)>>,
    pipeline_layout: wgpu::PipelineLayout,
    /// A wavefront kernel's group 1 (its dispatch sizes) and the control stages' layout.
    wavefront_layouts: Option<(wgpu::BindGroupLayout, wgpu::PipelineLayout)>,
    /// The entries of `layout` (with the source, what a compiled kernel is found by).
    layout_entries: Vec<wgpu::BindGroupLayoutEntry>,
    /// What another sampler's kernel is generated from.
    material_wgsl: String,
    kernel_options: KernelOptions,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// Scene buffers in binding order 1–5, then the material buffers (10, 11).
    buffers: Vec<wgpu::Buffer>,
    film: Mutex<Option<FilmBuffers>>,
    /// bdpt's splat image and scratch, kept across passes of the same size.
    splats: Mutex<Option<BdptBuffers>>,
    constants: SceneConstants,
    stats: PrepareStats,
    /// Where the atlas integrator's gathered irradiance lies in the tables.
    atlas_irradiance: Option<AtlasIrradiance>,
}

/// Where a [`GpuScene`]'s atlas irradiance lies in its tables, and who gathered it.
#[derive(Clone, Copy, Debug)]
struct AtlasIrradiance {
    /// The float index of the first texel.
    at: usize,
    /// Texels (three floats each).
    texels: usize,
    /// Whether the device gathered it (else the CPU did).
    on_device: bool,
}

/// The tracer's [`Backend`] on a wgpu device (cloning shares the device).
#[derive(Clone)]
pub struct GpuBackend {
    ctx: Arc<GpuContext>,
    integrator: GpuIntegrator,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A compute-stage buffer binding of a bind group layout.
pub(crate) fn buffer_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// The path kernel `source` as a pipeline of its `entry` point with `layout` (made of
/// `entries`) and its shader module (for the kernel's other entry points): the one the
/// device keeps from the same source and entries, else compiled.
fn kernel(
    ctx: &GpuContext,
    layout: &wgpu::PipelineLayout,
    entries: &[wgpu::BindGroupLayoutEntry],
    source: &str,
    entry: &str,
) -> Result<Arc<crate::context::CompiledKernel>, GpuError> {
    ctx.kernels.get_or_compile(source, entries, || compile_kernel(ctx, layout, source, entry))
}

/// The entry point a kernel's main pipeline runs: `pt_main` (the megakernel), or the
/// wavefront's shading stage (its other stages are pipelines of the same module).
fn main_entry(options: &KernelOptions) -> &'static str {
    if options.wavefront { "pt_wf_shade" } else { "pt_main" }
}

/// Compiles `source`'s `entry` with `layout` (what [`kernel`] keeps).
pub(crate) fn compile_kernel(
    ctx: &GpuContext,
    layout: &wgpu::PipelineLayout,
    source: &str,
    entry: &str,
) -> Result<crate::context::CompiledKernel, GpuError> {
    let device = &ctx.device;
    // (Out of memory caught here too: a pipeline that failed must not be kept.)
    let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("spt path tracer"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("spt path tracer"),
        layout: Some(layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    });
    let compiled = pop_scope(scope, "the path-tracing kernel does not compile");
    pop_scope(memory, "out of GPU memory compiling the path-tracing kernel")?;
    compiled?;
    Ok(crate::context::CompiledKernel { pipeline, module })
}

/// Waits for an error scope and turns what it caught into a [`GpuError::Shader`].
fn pop_scope(scope: wgpu::ErrorScopeGuard, what: &str) -> Result<(), GpuError> {
    match pollster::block_on(scope.pop()) {
        None => Ok(()),
        Some(e) => Err(GpuError::Shader(format!("{what}: {e}"))),
    }
}

impl GpuBackend {
    /// Opens the default adapter ([`GpuContext::new`]).
    pub fn new() -> Result<Self, GpuError> {
        Ok(Self::with_context(GpuContext::new()?))
    }

    /// A backend on an already open device, running the path tracer.
    pub fn with_context(ctx: GpuContext) -> Self {
        Self { ctx: Arc::new(ctx), integrator: GpuIntegrator::Path }
    }

    /// The same device running `integrator` (the kernel is compiled for it).
    pub fn with_integrator(self, integrator: GpuIntegrator) -> Self {
        Self { integrator, ..self }
    }

    /// The device the backend renders on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The kernel options a scene prepared with `options` is uploaded and compiled with
    /// (the scene's own features are filled in by [`SceneData::new`]).
    pub fn kernel_options(&self, options: &SceneOptions) -> KernelOptions {
        // The kernel the first render needs (others compile on demand), where the
        // integrator runs it.
        let caps = capabilities_on(self.integrator, &self.ctx);
        let defaults = RenderSettings::default();
        let (sampler, mode) = options.first_render.unwrap_or((defaults.sampler, defaults.mode));
        let sampler = if caps.samplers.contains(&sampler) { sampler } else { caps.samplers[0] };
        let mode = if caps.spectral_modes.contains(&mode) { mode } else { KernelOptions::default().mode };
        KernelOptions {
            triangle_test: options.triangle_test,
            nodes: match options.bvh_width {
                BvhWidth::Four => NodeLayout::Wide4 { stack: 0 },
                BvhWidth::Eight => NodeLayout::Wide8 { stack: 0 },
                _ => NodeLayout::Binary,
            },
            integrator: self.integrator,
            sampler,
            mode,
            bvh_builder: options.bvh_builder.unwrap_or(KernelOptions::default().bvh_builder),
            wavefront: options.wavefront,
            light_sampler: options.light_sampler,
            ..KernelOptions::default()
        }
    }

    /// Checks `scene` against the capabilities, uploads it and compiles its kernel.
    pub fn prepare_gpu(&self, mut scene: Scene, options: &SceneOptions) -> Result<GpuScene, tracer::Error> {
        capabilities_on(self.integrator, &self.ctx).check_scene(&scene, options)?;
        scene.validate()?;
        if matches!(self.integrator, GpuIntegrator::Atlas(_)) {
            // The atlas charts world-space triangles (its primitive ids are the flattened
            // scene's).
            scene.flatten_instances();
        } else {
            // Placements traced two-level, each object's triangles and tree uploaded once;
            // those on area lights are copied into the world's triangles, which light sampling
            // draws from (a table of world-space triangles).
            scene.flatten_light_instances();
        }
        Ok(self.upload(scene, options)?)
    }

    fn upload(&self, scene: Scene, options: &SceneOptions) -> Result<GpuScene, GpuError> {
        let start = Instant::now();
        let kernel_options = self.kernel_options(options);
        check_wavefront_mode(&kernel_options)?;
        let mut data = SceneData::new(&scene, kernel_options)?;
        data.check_limits(&self.ctx.limits)?;
        let pending_gather = data.atlas.take();
        let device = &self.ctx.device;
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);

        // Bindings may not be empty: pad every array to at least one element (16 bytes;
        // one node for the nodes: 32, 128 or 256 bytes), which the kernel never reads (its
        // counts say so).
        let storage = |label: &str, bytes: &[u8], min: usize| {
            let mut contents = bytes.to_vec();
            if contents.len() < min {
                contents.resize(min, 0);
            }
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &contents,
                // (COPY_DST: the atlas's gathered irradiance is written into the tables.)
                // (COPY_SRC: `GpuScene::atlas_irradiance` reads it back.)
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            })
        };
        let buffers = vec![
            storage("bvh nodes", &data.nodes, data.node_bytes),
            storage("triangle vertices", bytemuck::cast_slice(&data.tri_verts), 48),
            storage("triangle vertex indices", bytemuck::cast_slice(&data.tri_vidx), 16),
            storage("vertex attributes", bytemuck::cast_slice(&data.attrs), 32),
            storage("tables", bytemuck::cast_slice(&data.tables), 16),
            storage("material data", bytemuck::cast_slice(&data.material_data), 16),
            storage("material spectra", bytemuck::cast_slice(&data.spectra), 16),
        ]
        .into_iter()
        .chain(data.options.textures.then(|| storage("texels", bytemuck::cast_slice(&data.texels), 16)))
        .collect::<Vec<_>>();
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: UNIFORM_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });

        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let write = wgpu::BufferBindingType::Storage { read_only: false };
        let entries: Vec<_> = [(0, wgpu::BufferBindingType::Uniform), (7, wgpu::BufferBindingType::Uniform)]
            .into_iter()
            .chain([1, 2, 3, 4, 5, 10, 11].map(|b| (b, read)))
            .chain(data.options.textures.then_some((12, read)))
            .chain(data.options.integrator.splats().then_some([(13, write), (14, write)]).into_iter().flatten())
            .chain([(6, write)])
            .map(|(b, ty)| buffer_entry(b, ty))
            .chain(data.options.wavefront.then(wavefront::group_zero_entries).into_iter().flatten())
            .collect();
        let layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("spt"), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("spt"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let wavefront_layouts = data.options.wavefront.then(|| {
            let group_one = wavefront::group_one_layout(device);
            let control = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("spt wavefront control"),
                bind_group_layouts: &[Some(&layout), Some(&group_one)],
                immediate_size: 0,
            });
            (group_one, control)
        });

        let compile_start = Instant::now();
        let shader_result =
            kernel(&self.ctx, &pipeline_layout, &entries, &data.shader_source(), main_entry(&data.options));
        let stages = match (&shader_result, &wavefront_layouts) {
            (Ok(compiled), Some((_, control))) => {
                Some(wavefront::Stages::new(&self.ctx, &compiled.module, &pipeline_layout, control))
            }
            _ => None,
        };
        let compile_time = compile_start.elapsed();
        let memory_result = pop_scope(memory, "out of GPU memory uploading the scene");
        let validation_result = pop_scope(validation, "uploading the scene");
        let compiled = shader_result?;
        let stages = stages.transpose()?;
        memory_result?;
        validation_result?;

        let stats = PrepareStats {
            build: data.build_time,
            compile: Some(compile_time),
            integrator: None,
            total: start.elapsed(),
            emitters: data.constants.emitters,
            light_tree: data.options.light_tree,
            accelerator: match data.options.nodes {
                NodeLayout::Binary => "binary BVH",
                NodeLayout::Wide4 { .. } => "4-wide BVH",
                NodeLayout::Wide8 { .. } => "8-wide BVH",
            },
            hull_triangles: 0,
        };
        let mut prepared = GpuScene {
            ctx: Arc::clone(&self.ctx),
            bounds: scene.bounds(),
            scene,
            pipelines: Mutex::new(vec![(
                (data.options.sampler, data.options.mode),
                Kernel { main: Arc::clone(&compiled), stages },
            )]),
            pipeline_layout,
            wavefront_layouts,
            layout_entries: entries,
            material_wgsl: data.material_wgsl,
            kernel_options: data.options,
            layout,
            params,
            buffers,
            film: Mutex::new(None),
            splats: Mutex::new(None),
            constants: data.constants,
            stats,
            atlas_irradiance: None,
        };
        if let Some(pending) = pending_gather {
            let at = pending.irradiance_at;
            let (s, on_device) = prepared.gather_atlas(pending, &compiled.module)?;
            prepared.stats.integrator = Some(s.unwrap + s.direct + s.gather);
            prepared.stats.total = start.elapsed();
            let texels = s.width as usize * s.height as usize;
            prepared.atlas_irradiance = Some(AtlasIrradiance { at, texels, on_device });
        }
        Ok(prepared)
    }
}

/// Bytes per texel of the atlas gather's input (five vec4s).
const GATHER_TEXEL_BYTES: u64 = std::mem::size_of::<GatherRecord>() as u64;

/// A texel of the gather as `wgsl/atlas_gather.wgsl` reads it: (position, direct r),
/// (normal, direct g), (chart u, direct b), (chart v, 0), (shift, 0, 0).
type GatherRecord = [[f32; 4]; 5];

fn gather_record(t: &tracer::integrator::GatherTexel) -> GatherRecord {
    let (p, n, u, v, b) = (t.position, t.normal, t.chart_u, t.chart_v, t.direct);
    [
        [p.x, p.y, p.z, b[0]],
        [n.x, n.y, n.z, b[1]],
        [u.x, u.y, u.z, b[2]],
        [v.x, v.y, v.z, 0.0],
        [t.shift.x, t.shift.y, 0.0, 0.0],
    ]
}

/// About the most shadow rays (texels × points) one dispatch of the atlas's gather traces
/// (at least one point per texel).
const GATHER_DISPATCH_RAYS: u64 = 1 << 22;

/// The most points per texel one dispatch of the gather traces on a software rasteriser
/// (whose loop limiter would cut longer invocations short: "Found: lavapipe's loop
/// limiter" in docs/gpu.md).
const SOFTWARE_GATHER_POINTS: u32 = 4;

impl GpuScene {
    /// Runs the atlas's gather on the device (`wgsl/atlas_gather.wgsl`, the CPU's
    /// `GatherProblem::gather` per texel; on the CPU's threads where the device cannot
    /// hold the gather's texels), dilates the result as the CPU does and writes it into
    /// the tables, where the kernel's lookups read it; returns the atlas's statistics and
    /// whether the device gathered.
    fn gather_atlas(
        &self,
        pending: PendingGather,
        module: &wgpu::ShaderModule,
    ) -> Result<(tracer::integrator::AtlasStats, bool), GpuError> {
        let PendingGather { mut atlas, problem, settings, irradiance_at } = pending;
        let start = Instant::now();
        let count = problem.texels.len();
        let fits = check_size("the atlas gather's texels", GATHER_TEXEL_BYTES * count as u64, &self.ctx.limits);
        if fits.is_err() {
            // Too many texels for one binding: the CPU gathers, as the CPU backend does.
            with_atlas_view(&self.scene, self.kernel_options.triangle_test, |view| atlas.gather(view, &settings))?;
        } else {
            let mut sums = vec![[0.0f32; 3]; count];
            if count > 0 {
                let raw = self.run_gather(&problem, module)?;
                for (sum, r) in sums.iter_mut().zip(raw.chunks_exact(4)) {
                    *sum = [r[0], r[1], r[2]].map(|v| v * problem.estimator_scale);
                }
            }
            atlas.set_gathered(&problem, &sums, settings.seams, start.elapsed());
        }
        let irradiance: Vec<f32> = atlas.irradiance().iter().flatten().copied().collect();
        self.ctx.queue.write_buffer(&self.buffers[4], 4 * irradiance_at as u64, bytemuck::cast_slice(&irradiance));
        Ok((atlas.stats, fits.is_ok()))
    }

    /// The gather's raw sums (four floats per texel, unscaled).
    fn run_gather(
        &self,
        problem: &tracer::integrator::GatherProblem,
        module: &wgpu::ShaderModule,
    ) -> Result<Vec<f32>, GpuError> {
        let device = &self.ctx.device;
        let queue = &self.ctx.queue;
        let count = problem.texels.len();
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let uniform = wgpu::BufferBindingType::Uniform;
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let write = wgpu::BufferBindingType::Storage { read_only: false };
        let gather_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("spt atlas gather"),
            entries: &[buffer_entry(0, uniform), buffer_entry(1, read), buffer_entry(2, write)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("spt atlas gather"),
            bind_group_layouts: &[Some(&self.layout), Some(&gather_layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("spt atlas gather"),
            layout: Some(&pipeline_layout),
            module,
            entry_point: Some("pt_atlas_gather"),
            compilation_options: Default::default(),
            cache: None,
        });
        pop_scope(scope, "the atlas's gather kernel does not compile")?;

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        // The scene's bindings as the path kernel has them: parameters for a 1×1 image (the
        // gather reads only the scene's), accumulators it never touches.
        let settings = RenderSettings { width: 1, height: 1, spp: 1, ..RenderSettings::default() };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&self.kernel_params(&settings)));
        let accum = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("unused accumulators"),
            size: FILM_HEADER_BYTES + PIXEL_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let scene_group = self.bind_group(&self.params, &accum, None, None);
        let texels: Vec<GatherRecord> = problem.texels.iter().map(gather_record).collect();
        let texel_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("atlas gather texels"),
            contents: bytemuck::cast_slice(&texels),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let sums_bytes = 16 * count as u64;
        let sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("atlas gather sums"),
            size: sums_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("atlas gather read-back"),
            size: sums_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("atlas gather parameters"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let gather_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("spt atlas gather"),
            layout: &gather_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: texel_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: sums.as_entire_binding() },
            ],
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.clear_buffer(&sums, 0, None);
        queue.submit([encoder.finish()]);
        // Points per dispatch: a budget of rays, fewer on a software rasteriser.
        let budget = (GATHER_DISPATCH_RAYS / count as u64).clamp(1, problem.samples as u64) as u32;
        let per_dispatch = if self.ctx.info.device_type == wgpu::DeviceType::Cpu {
            budget.min(SOFTWARE_GATHER_POINTS)
        } else {
            budget
        };
        // Workgroups of 64 texels, in rows within the device's per-dimension limit.
        let groups = (count as u32).div_ceil(64);
        let groups_x = groups.min(self.ctx.limits.max_compute_workgroups_per_dimension.max(1));
        let groups_y = groups.div_ceil(groups_x);
        let mut first = 0;
        while first < problem.samples {
            let end = (first + per_dispatch).min(problem.samples);
            let words: [u32; 8] = [
                count as u32,
                problem.samples,
                first,
                end,
                problem.density.to_bits(),
                problem.min_r2.to_bits(),
                u32::from(problem.visibility),
                64 * groups_x,
            ];
            queue.write_buffer(&uniforms, 0, bytemuck::cast_slice(&words));
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &scene_group, &[]);
                pass.set_bind_group(1, &gather_group, &[]);
                pass.dispatch_workgroups(groups_x, groups_y, 1);
            }
            let index = queue.submit([encoder.finish()]);
            device
                .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
                .map_err(|e| GpuError::Shader(format!("waiting for the GPU: {e}")))?;
            first = end;
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.copy_buffer_to_buffer(&sums, 0, &readback, 0, sums_bytes);
        queue.submit([encoder.finish()]);
        let values = {
            let view = map_read(&self.ctx, &readback, sums_bytes, "reading the atlas's gather back")?;
            bytemuck::cast_slice::<u8, f32>(&view).to_vec()
        };
        readback.unmap();
        pop_scope(memory, "out of GPU memory gathering the atlas")?;
        pop_scope(scope, "the atlas's gather")?;
        Ok(values)
    }
}

impl GpuScene {
    /// Whether the device gathered the atlas integrator's atlas (`false`: its texels did
    /// not fit the device's buffers and the CPU gathered); `None` for other integrators.
    pub fn atlas_gathered_on_device(&self) -> Option<bool> {
        self.atlas_irradiance.map(|a| a.on_device)
    }

    /// The atlas integrator's gathered irradiance per texel (linear sRGB, row-major, as
    /// `Atlas::irradiance`), read back from the device; `None` for the other integrators.
    pub fn atlas_irradiance(&self) -> Result<Option<Vec<[f32; 3]>>, GpuError> {
        let Some(AtlasIrradiance { at, texels, .. }) = self.atlas_irradiance else { return Ok(None) };
        let bytes = 12 * texels as u64;
        let device = &self.ctx.device;
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("atlas irradiance read-back"),
            size: bytes.max(4),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.copy_buffer_to_buffer(&self.buffers[4], 4 * at as u64, &readback, 0, bytes);
        self.ctx.queue.submit([encoder.finish()]);
        let values: Vec<f32> = {
            let view = map_read(&self.ctx, &readback, bytes, "reading the atlas back")?;
            bytemuck::cast_slice(&view).to_vec()
        };
        readback.unmap();
        Ok(Some(values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()))
    }

    /// The device the scene lives on.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Time spent compiling the shader and creating the pipeline.
    pub fn compile_time(&self) -> Duration {
        self.stats.compile.unwrap_or_default()
    }

    /// Time spent preparing the scene in all: flattening (BVH build, material code
    /// generation), upload and compilation.
    pub fn prepare_time(&self) -> Duration {
        self.stats.total
    }

    /// Writes the render's ZSobol dimension seeds into the uniform buffer `params` (after
    /// the parameters), where the ZSobol kernel reads them.
    pub(crate) fn write_seeds(&self, params: &wgpu::Buffer, settings: &RenderSettings) {
        if settings.sampler == SamplerKind::ZSobol {
            let words = crate::kernel::zsobol_seed_words(settings);
            self.ctx.queue.write_buffer(params, SEEDS_OFFSET, bytemuck::cast_slice(&words));
        }
    }

    /// The kernel's uniforms for `settings` (the band and the samples are the caller's).
    pub(crate) fn kernel_params(&self, settings: &RenderSettings) -> Params {
        let (width, height) = (settings.width, settings.height);
        let zseed = tracer::sampler::mix64(settings.seed);
        let rays = PreparedScene::camera(self, settings).rays(width, height);
        let (eye, forward, right, up) = rays.basis();
        let region = settings.region();
        let v4 = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        let shading = settings.path.shading_normals.code();
        Params {
            width,
            height,
            seed_lo: settings.seed as u32,
            seed_hi: (settings.seed >> 32) as u32,
            max_depth: settings.path.max_depth,
            rr_depth: settings.path.rr_depth,
            rr_scale: settings.path.rr_scale,
            specular_extension: settings.path.specular_extension,
            shading,
            scene_flags: self.constants.scene_flags,
            node_count: self.constants.node_count,
            light_count: self.constants.light_count,
            punctual_first: self.constants.punctual_first,
            shape_nodes_offset: self.constants.shape_nodes_offset,
            shape_node_count: self.constants.shape_node_count,
            shape_slots_offset: self.constants.shape_slots_offset,
            instance_nodes_offset: self.constants.instance_nodes_offset,
            instance_node_count: self.constants.instance_node_count,
            material_textures_offset: self.constants.material_textures_offset,
            uplift_offset: self.constants.uplift_offset,
            decode_offset: self.constants.decode_offset,
            envmap_offset: self.constants.envmap_offset,
            atlas_offset: self.constants.atlas_offset,
            env_pmf: self.constants.env_pmf,
            eye: v4(eye),
            forward: v4(forward),
            right: v4(right),
            up: v4(up),
            inv_size: [1.0 / width as f32, 1.0 / height as f32],
            lights_offset: self.constants.lights_offset,
            env_offset: self.constants.env_offset,
            white_offset: self.constants.white_offset,
            ao_distance: match self.constants.integrator {
                GpuIntegrator::AmbientOcclusion { max_distance } => max_distance.min(3.0e38),
                _ => 0.0,
            },
            log2_spp: sobol_bits(settings.spp),
            unused_bits: match settings.sampler {
                // `ZSobolLayout::new`: Morton bits of the image's power-of-two square, then the
                // sample bits.
                SamplerKind::ZSobol => 64 - (2 * sobol_bits(width.max(height)) + sobol_bits(settings.spp)),
                // `PaddedSobol::new`.
                _ => 64 - sobol_bits(settings.spp),
            },
            zseed_lo: zseed as u32,
            zseed_hi: (zseed >> 32) as u32,
            max_diffuse_depth: settings.path.max_diffuse_depth,
            region: [region.x, region.y, region.width, region.height],
            light_tree: self.constants.light_tree,
            film_density: rays.pixels_per_steradian(forward) / region.pixel_count() as f32,
            ..Params::default()
        }
    }

    /// Adds samples `first_sample .. first_sample + spp` of every pixel to `film`, as
    /// [`PreparedScene::render_pass`] does, returning the GPU's own errors.
    pub fn render_gpu(
        &self,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<PathCounters, GpuError> {
        let (width, height) = (settings.width, settings.height);
        if spp == 0 || width == 0 || height == 0 {
            return Ok(PathCounters::default());
        }
        let device = &self.ctx.device;
        let queue = &self.ctx.queue;
        let limits = &self.ctx.limits;

        // Bands of whole rows whose accumulators fit one buffer.
        let row_bytes = PIXEL_BYTES * width as u64;
        let cap = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size).min(FILM_BAND_CAP);
        check_size("one image row of per-pixel accumulators", FILM_HEADER_BYTES + row_bytes, limits)?;
        let mut band_rows_max = ((cap.saturating_sub(FILM_HEADER_BYTES) / row_bytes).max(1) as u32).min(height);
        if self.splatting() {
            // bdpt's bands are as many rows as its scratch holds.
            let scratch_row = BDPT_SLOT_BYTES * width as u64;
            check_size("one image row of bdpt's scratch", scratch_row, limits)?;
            let scratch_cap = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size).min(BDPT_SCRATCH_CAP);
            band_rows_max = band_rows_max.min((scratch_cap / scratch_row).max(1) as u32);
        }
        if self.kernel_options.wavefront {
            // A wave holds the band's paths (a row too wide for one is refused by
            // `wavefront::Buffers::new`).
            band_rows_max = band_rows_max.min((wavefront::max_slots(limits) / width as u64).max(1) as u32);
        }
        let band_pixels_max = band_rows_max as u64 * width as u64;

        let mut film_slot = lock(&self.film);
        if film_slot.as_ref().is_none_or(|f| f.pixels < band_pixels_max) {
            *film_slot = Some(self.film_buffers(band_pixels_max)?);
        }
        let fb = film_slot.as_ref().expect("just made");

        let mut params = self.kernel_params(settings);
        let kernel = self.kernel_for(settings)?;
        self.write_seeds(&self.params, settings);

        // bdpt: the whole image's splat image, cleared, in a bind group of its own.
        let mut splat_slot = lock(&self.splats);
        let splat_bind = if self.splatting() {
            let pixels = width as u64 * height as u64;
            let slots = band_pixels_max;
            check_size("bdpt's splat image (36 bytes per pixel)", splat_bytes(pixels), limits)?;
            if splat_slot.as_ref().is_none_or(|b| b.pixels != pixels || b.slots < slots) {
                *splat_slot = Some(self.bdpt_buffers(pixels, slots)?);
            }
            let sb = splat_slot.as_ref().expect("just made");
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            encoder.clear_buffer(&sb.sums, 0, None);
            queue.submit([encoder.finish()]);
            Some(self.bind_group(&self.params, &fb.accum, Some(sb), None))
        } else {
            None
        };
        let bind_group = splat_bind.as_ref().or(fb.bind_group.as_ref()).expect("a bind group for every integrator");

        // A crop window renders its rows whole; only its columns reach the film.
        let region = settings.region();
        let y_end = region.y + region.height;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut counters = PathCounters::default();
        let mut y0 = region.y;
        while y0 < y_end {
            let rows = band_rows_max.min(y_end - y0);
            let band_pixels = rows as u64 * width as u64;
            let band_bytes = FILM_HEADER_BYTES + band_pixels * PIXEL_BYTES;
            let per_dispatch = (DISPATCH_BUDGET / band_pixels).clamp(1, self.max_samples_per_dispatch() as u64) as u32;
            params.band_y0 = y0;
            params.band_rows = rows;
            // Read-backs fall on multiples of SAMPLES_PER_READBACK in the sample index, not
            // in the pass: passes that split a render there give the film's exact sums
            // the same f32 partial statistics, hence the same bytes.
            let absolute = |done: u32| first_sample.wrapping_add(done) % SAMPLES_PER_READBACK;
            let mut done = 0;
            while done < spp {
                let n = per_dispatch.min(spp - done).min(SAMPLES_PER_READBACK - absolute(done));
                params.first_sample = first_sample.wrapping_add(done);
                params.samples = n;
                queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
                let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
                if done == 0 || absolute(done) == 0 {
                    encoder.clear_buffer(&fb.accum, 0, Some(band_bytes));
                }
                let index =
                    self.submit_samples(encoder, &kernel, bind_group, fb.wavefront.as_ref(), width, rows, &params)?;
                device
                    .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })
                    .map_err(|e| GpuError::Shader(format!("waiting for the GPU: {e}")))?;
                progress(rows as u64 * region.width as u64 * n as u64);
                done += n;
                if absolute(done) == 0 || done == spp {
                    counters += self.read_back(&fb.accum, &fb.readback, band_bytes, film, y0, rows, region)?;
                }
            }
            y0 += rows;
        }
        if let Some(sb) = splat_slot.as_ref().filter(|_| self.splatting()) {
            self.read_splats(sb, film)?;
            // One light path per sample of every pixel of the region: the splats' divisor.
            film.count_light_paths(spp as u64);
        }
        pop_scope(scope, "rendering")?;
        Ok(counters)
    }

    /// Whether the kernel splats ([`GpuIntegrator::splats`]).
    fn splatting(&self) -> bool {
        self.constants.integrator.splats()
    }

    /// A splat image of `pixels` pixels, its read-back copy, and scratch for `slots`
    /// invocations.
    fn bdpt_buffers(&self, pixels: u64, slots: u64) -> Result<BdptBuffers, GpuError> {
        let device = &self.ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let (sums, readback) = read_back_pair(device, "splat image", splat_bytes(pixels));
        let scratch = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bdpt scratch"),
            size: slots * BDPT_SLOT_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        pop_scope(scope, "out of GPU memory for bdpt's splat image and scratch")?;
        Ok(BdptBuffers { pixels, slots, sums, readback, scratch })
    }

    /// Reads the splat image back and adds its sums (and the splats it dropped) to `film`.
    fn read_splats(&self, sb: &BdptBuffers, film: &mut Film) -> Result<(), GpuError> {
        let bytes = splat_bytes(sb.pixels);
        let mut encoder = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.copy_buffer_to_buffer(&sb.sums, 0, &sb.readback, 0, Some(bytes));
        self.ctx.queue.submit([encoder.finish()]);
        {
            let view = map_read(&self.ctx, &sb.readback, bytes, "reading the splat image back")?;
            let words: &[u32] = bytemuck::cast_slice(&view);
            let (header, pixels) = words.split_at(SPLAT_HEADER_WORDS as usize);
            film.non_finite += header[0] as u64;
            for (i, px) in pixels.chunks_exact(9).enumerate() {
                let sum = [splat_sum(&px[0..3]), splat_sum(&px[3..6]), splat_sum(&px[6..9])];
                film.add_splat_sum(i, sum);
            }
        }
        sb.readback.unmap();
        Ok(())
    }

    /// The path kernel's bind group: the scene's buffers with the uniforms `params`
    /// ([`UNIFORM_BYTES`]: the parameters, then the ZSobol seeds), the accumulators
    /// `accum` and, for bdpt (whose layout has it), the splat image.
    pub(crate) fn bind_group(
        &self,
        params: &wgpu::Buffer,
        accum: &wgpu::Buffer,
        bdpt: Option<&BdptBuffers>,
        wavefront: Option<&wavefront::Buffers>,
    ) -> wgpu::BindGroup {
        let b = &self.buffers;
        let range = |offset: u64, size: u64| {
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: params,
                offset,
                size: wgpu::BufferSize::new(size),
            })
        };
        let uniforms = [
            wgpu::BindGroupEntry { binding: 0, resource: range(0, std::mem::size_of::<Params>() as u64) },
            wgpu::BindGroupEntry { binding: 7, resource: range(SEEDS_OFFSET, UNIFORM_BYTES - SEEDS_OFFSET) },
        ];
        let mut bindings =
            vec![(1, &b[0]), (2, &b[1]), (3, &b[2]), (4, &b[3]), (5, &b[4]), (6, accum), (10, &b[5]), (11, &b[6])];
        if let Some(texels) = b.get(7) {
            bindings.push((12, texels));
        }
        if let Some(bdpt) = bdpt {
            bindings.push((13, &bdpt.sums));
            bindings.push((14, &bdpt.scratch));
        }
        if let Some(w) = wavefront {
            bindings.push((15, &w.paths));
            bindings.push((16, &w.control));
        }
        let entries: Vec<_> = uniforms
            .into_iter()
            .chain(
                bindings
                    .iter()
                    .map(|&(binding, buffer)| wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }),
            )
            .collect();
        self.ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("spt"),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Accumulator and read-back buffers for `pixels` pixels (with a wavefront's paths),
    /// with their bind group.
    fn film_buffers(&self, pixels: u64) -> Result<FilmBuffers, GpuError> {
        let device = &self.ctx.device;
        let (accum, readback) = read_back_pair(device, "accumulators", FILM_HEADER_BYTES + pixels * PIXEL_BYTES);
        let wavefront = self.wavefront_buffers(pixels)?;
        // bdpt's bind group also holds the splat image: made per pass (`render_gpu`).
        let bind_group = (!self.splatting()).then(|| self.bind_group(&self.params, &accum, None, wavefront.as_ref()));
        Ok(FilmBuffers { pixels, accum, readback, wavefront, bind_group })
    }

    /// A wavefront kernel's paths and queues for waves of `slots` paths (`None` for a
    /// megakernel).
    pub(crate) fn wavefront_buffers(&self, slots: u64) -> Result<Option<wavefront::Buffers>, GpuError> {
        self.wavefront_layouts
            .as_ref()
            .map(|(group_one, _)| wavefront::Buffers::new(&self.ctx, slots, group_one))
            .transpose()
    }

    /// The most samples per pixel one dispatch may trace on this device
    /// ([`SOFTWARE_SAMPLES_PER_DISPATCH`] on a software rasteriser).
    pub(crate) fn max_samples_per_dispatch(&self) -> u32 {
        if self.ctx.info.device_type == wgpu::DeviceType::Cpu {
            SOFTWARE_SAMPLES_PER_DISPATCH
        } else {
            MAX_SAMPLES_PER_DISPATCH
        }
    }

    /// The samplers whose kernels are compiled, in the order they were (one per sampler
    /// and spectral mode).
    pub fn compiled_samplers(&self) -> Vec<SamplerKind> {
        lock(&self.pipelines).iter().map(|((s, _), _)| *s).collect()
    }

    /// The kernel for the settings' sampler and spectral mode, compiled on first use (the
    /// scene's buffers and layout stay; only those constants differ).
    pub(crate) fn kernel_for(&self, settings: &RenderSettings) -> Result<Kernel, GpuError> {
        let key = (settings.sampler, settings.mode);
        let mut pipelines = lock(&self.pipelines);
        if let Some((_, p)) = pipelines.iter().find(|(k, _)| *k == key) {
            return Ok(p.clone());
        }
        let options = KernelOptions { sampler: key.0, mode: key.1, ..self.kernel_options };
        let source = crate::kernel::source(&self.material_wgsl, &options);
        let main = kernel(&self.ctx, &self.pipeline_layout, &self.layout_entries, &source, main_entry(&options))?;
        let stages = match &self.wavefront_layouts {
            Some((_, control)) => {
                Some(wavefront::Stages::new(&self.ctx, &main.module, &self.pipeline_layout, control)?)
            }
            None => None,
        };
        let compiled = Kernel { main, stages };
        pipelines.push((key, compiled.clone()));
        Ok(compiled)
    }

    /// Records `params.samples` samples of every pixel of the band (`rows` rows of `width`
    /// pixels, as in `params`) into `encoder` and submits it: one dispatch of the
    /// megakernel, or the wavefront's stages with `wavefront`'s paths (which `bind_group`
    /// binds).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn submit_samples(
        &self,
        mut encoder: wgpu::CommandEncoder,
        kernel: &Kernel,
        bind_group: &wgpu::BindGroup,
        wavefront: Option<&wavefront::Buffers>,
        width: u32,
        rows: u32,
        params: &Params,
    ) -> Result<wgpu::SubmissionIndex, GpuError> {
        match (&kernel.stages, wavefront) {
            (Some(stages), Some(buffers)) => {
                return wavefront::submit(
                    &self.ctx,
                    stages,
                    &kernel.main.pipeline,
                    bind_group,
                    buffers,
                    encoder,
                    params,
                );
            }
            (None, None) => {}
            _ => return Err(GpuError::Shader("a wavefront kernel without its paths, or paths without one".into())),
        }
        {
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("spt"), timestamp_writes: None });
            pass.set_pipeline(&kernel.main.pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.dispatch_workgroups(width.div_ceil(WORKGROUP), rows.div_ceil(WORKGROUP), 1);
        }
        Ok(self.ctx.queue.submit([encoder.finish()]))
    }

    /// Copies `bytes` of the accumulators `accum` (a band of `rows` rows from `y0`) back
    /// through `readback`, merges the pixels of `region`'s columns into `film` (row by
    /// row in parallel: a 1080p film is 2M pixel merges) and returns the band's
    /// counters.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn read_back(
        &self,
        accum: &wgpu::Buffer,
        readback: &wgpu::Buffer,
        bytes: u64,
        film: &mut Film,
        y0: u32,
        rows: u32,
        region: PixelRect,
    ) -> Result<PathCounters, GpuError> {
        let device = &self.ctx.device;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        encoder.copy_buffer_to_buffer(accum, 0, readback, 0, Some(bytes));
        self.ctx.queue.submit([encoder.finish()]);
        let counters;
        {
            let view = map_read(&self.ctx, readback, bytes, "reading the accumulators back")?;
            let (header, pixels) = view.split_at(FILM_HEADER_BYTES as usize);
            let words: &[u32] = bytemuck::cast_slice(header);
            counters = PathCounters { rays: words[0] as u64 | (words[1] as u64) << 32, truncated: words[2] as u64 };
            let pixels: &[PixelAccum] = bytemuck::cast_slice(pixels);
            let width = film.width() as usize;
            let first = y0 as usize * width;
            let (x0, x1) = (region.x as usize, (region.x + region.width) as usize);
            let band = &mut film.pixels_mut()[first..first + rows as usize * width];
            let non_finite: u64 = band
                .par_chunks_mut(width)
                .zip(pixels.par_chunks(width))
                .map(|(film_row, device_row)| {
                    let mut dropped = 0u64;
                    for (f, px) in film_row[x0..x1].iter_mut().zip(&device_row[x0..x1]) {
                        f.merge(&PixelStats::from_moments(px.count, px.mean.map(f64::from), px.m2.map(f64::from)));
                        dropped += px.non_finite as u64;
                    }
                    dropped
                })
                .sum();
            film.non_finite += non_finite;
        }
        readback.unmap();
        Ok(counters)
    }
}

/// A storage buffer the kernel writes (and the host clears and copies out of) and its
/// read-back copy, both of `size` bytes.
fn read_back_pair(device: &wgpu::Device, label: &str, size: u64) -> (wgpu::Buffer, wgpu::Buffer) {
    let buffer = |label: &str, usage| {
        device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
    };
    use wgpu::BufferUsages as U;
    (
        buffer(label, U::STORAGE | U::COPY_SRC | U::COPY_DST),
        buffer(&format!("{label} read-back"), U::MAP_READ | U::COPY_DST),
    )
}

/// Maps the first `bytes` of `buffer` (MAP_READ, its copy already submitted) and waits
/// for it; the caller unmaps after dropping the view.
pub(crate) fn map_read(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    bytes: u64,
    what: &str,
) -> Result<wgpu::BufferView, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, 0..bytes, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| GpuError::Shader(format!("waiting for the GPU: {e}")))?;
    rx.recv()
        .map_err(|e| GpuError::Shader(format!("{what}: {e}")))?
        .map_err(|e| GpuError::Shader(format!("{what}: {e}")))?;
    buffer.get_mapped_range(0..bytes).map_err(|e| GpuError::Shader(format!("{what}: {e}")))
}

impl From<GpuError> for tracer::Error {
    fn from(e: GpuError) -> Self {
        tracer::Error::Backend(e.to_string())
    }
}

impl Backend for GpuBackend {
    fn capabilities(&self) -> Capabilities {
        capabilities_on(self.integrator, &self.ctx)
    }

    fn prepare(&self, scene: Scene, options: &SceneOptions) -> tracer::Result<Box<dyn PreparedScene>> {
        Ok(Box::new(self.prepare_gpu(scene, options)?))
    }
}

impl PreparedScene for GpuScene {
    /// The device's capabilities, less the 40-bin mode for a wavefront
    /// (`check_wavefront_mode`): its renders are refused as any mode a backend lacks.
    fn capabilities(&self) -> Capabilities {
        let mut caps = capabilities_on(self.constants.integrator, &self.ctx);
        if self.kernel_options.wavefront {
            caps.spectral_modes.retain(|&m| m != SpectralMode::Bins40);
        }
        caps
    }

    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn stats(&self) -> PrepareStats {
        self.stats
    }

    fn render_pass(
        &self,
        settings: &RenderSettings,
        film: &mut Film,
        first_sample: u32,
        spp: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> tracer::Result<PathCounters> {
        check_pass(self, settings, film)?;
        check_sample_range(settings, first_sample, spp)?;
        Ok(self.render_gpu(settings, film, first_sample, spp, progress)?)
    }

    /// Compiles the kernel for the settings' sampler and mode (one per pair, kept).
    fn warm_up(&self, settings: &RenderSettings) -> tracer::Result<()> {
        self.kernel_for(settings)?;
        Ok(())
    }

    /// Statistics on the device ([`DeviceAccumulation`]) where the whole image's
    /// accumulators fit one buffer, else passes into a film on the CPU.
    fn accumulate(self: Arc<Self>, settings: &RenderSettings) -> tracer::Result<Box<dyn Accumulation>> {
        // bdpt's splats land anywhere: its frames go through the film (read back each); so
        // do a wavefront's where one wave cannot hold the whole image (the film's passes
        // go in bands).
        let pixels = settings.width as u64 * settings.height as u64;
        let wave_fits = !self.kernel_options.wavefront || pixels <= wavefront::max_slots(&self.ctx.limits);
        if !self.splatting() && wave_fits && DeviceAccumulation::fits(&self.ctx.limits, settings.width, settings.height)
        {
            Ok(Box::new(DeviceAccumulation::new(self, settings)?))
        } else {
            Ok(Box::new(FilmAccumulation::new(self, settings)?))
        }
    }
}
