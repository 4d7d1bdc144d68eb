//! The path-tracing kernel's WGSL: what it shares with Rust is generated here, the rest is
//! hand-written, one file per Rust file it mirrors (`src/wgsl/*.wgsl`, each naming its
//! Rust twin in its header).
//!
//! Generated from the Rust definitions, so that nothing is mirrored by hand:
//!
//! * the structs the host and the kernel exchange — the uniform block [`Params`]
//!   (`PtParams`), the BVH node ([`bvh::BvhNode`], `PtNode`) and the per-pixel accumulator
//!   [`PixelAccum`] (`PtPixel`) — declared once with `wgsl_struct!` or
//!   `wgsl_layout!` (macros private to this module), whose field offsets a test checks against naga's layout of the
//!   generated WGSL;
//! * the constants the kernel shares with the CPU code: shading-normal codes
//!   ([`ShadingNormals::code`]), scene flags, the visible-wavelength pdf, the CIE tables'
//!   range, XYZ → sRGB, PCG32's and splitmix64's multipliers, the shading-normal margin, Russian roulette's floor, the shadow
//!   segment's end, the ray-offset scales, the light table's layout and the bounce cap;
//! * the choice of triangle test (only the one a scene asks for is compiled in).

use bvh::{BvhNode, TriangleTest};
use spectral::SpectralMode;
use spectral::colour::XYZ_TO_SRGB;
use spectral::sampled::{LAMBDA_MAX, LAMBDA_MIN, VIS_CENTRE, VIS_K, VIS_TANH_HI, VIS_TANH_LO};
use spectral::tables::{CIE_LAMBDA_MIN, CIE_SAMPLES, CIE_Y_INTEGRAL};
use std::fmt::Write as _;
use tracer::integrator::{RR_MIN_TERMINATION, SHADOW_T_MAX};
use tracer::sampler::SamplerKind;
use tracer::shading::{MIN_SHADING_COSINE, ShadingNormals};

/// A Rust type whose layout a WGSL struct mirrors.
pub trait WgslStruct {
    /// The WGSL struct's name.
    const NAME: &'static str;
    /// Its fields: (name, WGSL type, byte offset in the Rust type).
    const FIELDS: &'static [(&'static str, &'static str, usize)];
    /// The Rust type's size in bytes.
    const SIZE: usize;

    /// The WGSL declaration.
    fn declaration() -> String {
        let mut out = format!("struct {} {{\n", Self::NAME);
        for (name, ty, _) in Self::FIELDS {
            let _ = writeln!(out, "    {name}: {ty},");
        }
        out.push_str("}\n");
        out
    }
}

/// The WGSL type of a Rust field type.
macro_rules! wgsl_type {
    (u32) => {
        "u32"
    };
    (f32) => {
        "f32"
    };
    ([f32; 2]) => {
        "vec2f"
    };
    ([f32; 3]) => {
        "vec3f"
    };
    ([f32; 4]) => {
        "vec4f"
    };
    ([u32; 4]) => {
        "vec4u"
    };
}

/// Declares a `#[repr(C)]`, `Pod` Rust struct and the WGSL struct that mirrors it.
macro_rules! wgsl_struct {
    (
        $(#[$meta:meta])*
        $vis:vis struct $Name:ident as $wgsl:literal {
            $( $(#[$fmeta:meta])* $field:ident : $ty:tt ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $Name {
            $( $(#[$fmeta])* pub $field: $ty, )+
        }
        wgsl_layout!($Name as $wgsl { $($field: $ty),+ });
    };
}

/// Implements [`WgslStruct`] for an existing `#[repr(C)]` type (fields named and typed
/// as given; a test compares the offsets with naga's).
macro_rules! wgsl_layout {
    ($Name:ty as $wgsl:literal { $($field:ident : $ty:tt),+ $(,)? }) => {
        impl WgslStruct for $Name {
            const NAME: &'static str = $wgsl;
            const FIELDS: &'static [(&'static str, &'static str, usize)] =
                &[$((stringify!($field), wgsl_type!($ty), std::mem::offset_of!($Name, $field))),+];
            const SIZE: usize = std::mem::size_of::<$Name>();
        }
    };
}

wgsl_struct! {
    /// The kernel's uniform block: the pass (band, samples), the settings and the camera.
    pub struct Params as "PtParams" {
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
        /// First row of the band.
        band_y0: u32,
        /// Rows in the band.
        band_rows: u32,
        /// Index of the dispatch's first sample.
        first_sample: u32,
        /// Samples per pixel in the dispatch.
        samples: u32,
        /// Seed, low word.
        seed_lo: u32,
        /// Seed, high word.
        seed_hi: u32,
        /// `PathSettings::max_depth` (0 = unbounded).
        max_depth: u32,
        /// `PathSettings::rr_depth`.
        rr_depth: u32,
        /// `PathSettings::specular_extension`.
        specular_extension: u32,
        /// [`ShadingNormals::code`].
        shading: u32,
        /// [`HAS_NORMALS`] | [`HAS_TANGENTS`] | [`HAS_ENVIRONMENT`].
        scene_flags: u32,
        /// Nodes of the world's triangle BVH (an 8-wide node counts once, though it is two
        /// [`WideNode`] entries); placed objects' trees follow in the node array.
        node_count: u32,
        /// Entries of the light table (emissive triangles and shapes, then punctual lights).
        light_count: u32,
        /// Probability of sampling the environment in next-event estimation.
        env_pmf: f32,
        /// Camera position.
        eye: [f32; 4],
        /// Camera forward vector (to the image centre).
        forward: [f32; 4],
        /// Camera right vector (half the image width).
        right: [f32; 4],
        /// Camera up vector (half the image height).
        up: [f32; 4],
        /// 1 / width, 1 / height.
        inv_size: [f32; 2],
        /// Offset of the light table in `pt_tables`.
        lights_offset: u32,
        /// Offset of the environment's spectrum in `pt_tables`.
        env_offset: u32,
        /// Offset of the ambient-occlusion white (D65, luminance 1) in `pt_tables`.
        white_offset: u32,
        /// The ambient-occlusion probe's reach (finite: `PT_FAR` stands for ∞).
        ao_distance: f32,
        /// Offset in `pt_tables` of the atlas's record (`wgsl/atlas.wgsl`; the atlas
        /// integrator only).
        atlas_offset: u32,
        /// `PathSettings::rr_scale` (also keeps `region` at the 16-byte offset WGSL
        /// gives a `vec4<u32>`).
        rr_scale: f32,
        /// ZSobol: log₂ of the samples per pixel (rounded up to a power of two).
        log2_spp: u32,
        /// Sobol samplers: 64 minus the bits of their sample indices.
        unused_bits: u32,
        /// ZSobol: `mix64(seed)`, low word.
        zseed_lo: u32,
        /// ZSobol: `mix64(seed)`, high word.
        zseed_hi: u32,
        /// Offset in `pt_tables` of the analytic shapes' BVH (binary nodes of 8 words).
        shape_nodes_offset: u32,
        /// Nodes of the shapes' BVH (0: no shapes).
        shape_node_count: u32,
        /// Offset in `pt_tables` of the shapes' leaf slots: slot → the offset of its
        /// shape's record (bits).
        shape_slots_offset: u32,
        /// Entries of the light table before the punctual lights (emissive triangles and
        /// shapes); `light_count` counts all.
        punctual_first: u32,
        /// Offset in `pt_tables` of the material → texture record table (`wgsl/textures.wgsl`).
        material_textures_offset: u32,
        /// Offset in `pt_tables` of the uplift table: 32 z nodes, then the coefficients.
        uplift_offset: u32,
        /// Offset in `pt_tables` of the texel decode tables (sRGB, then linear; 256 each).
        decode_offset: u32,
        /// Offset in `pt_tables` of the environment map's record (`wgsl/envmap.wgsl`).
        envmap_offset: u32,
        /// `PathSettings::max_diffuse_depth` (0 = no limit; the path tracer).
        max_diffuse_depth: u32,
        /// The camera's importance along its axis over the region's pixel count
        /// (`CameraRays::pixels_per_steradian` there / `PixelRect::pixel_count`): bdpt's
        /// W(ω) is this over cos³ θ.
        film_density: f32,
        /// Offset in `pt_tables` of the instances' box BVH (binary nodes of 8 words, then
        /// its leaf slots: slot → the offset of its instance's record, bits).
        instance_nodes_offset: u32,
        /// Nodes of the instances' BVH (0: no instances).
        instance_node_count: u32,
        /// The region rendered (x, y, width, height; the whole image but for a crop
        /// window): bdpt's splats land only there and its camera density counts its pixels.
        region: [u32; 4],
        /// The light tree (`wgsl/lights.wgsl`, `tracer::lights::LightTreeTables`): the
        /// offsets in `pt_tables` of its nodes, of the primitive → emitter table and of the
        /// trails, and the upper end of the tree's stretch of the unit interval (f32
        /// bits; the lower is `env_pmf`). Zeros without a tree.
        light_tree: [u32; 4],
    }
}

/// The code of a sampler in `Params::sampler` and `PT_SAMPLER_*`.
pub fn sampler_code(kind: SamplerKind) -> u32 {
    match kind {
        SamplerKind::Independent => 0,
        SamplerKind::Sobol => 1,
        SamplerKind::ZSobol => 2,
    }
}

/// The integrator a kernel runs (compiled in: the others' code is not in the kernel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GpuIntegrator {
    /// `tracer::PathTracer` (`wgsl/path.wgsl`).
    Path,
    /// `tracer::DirectLighting` (`wgsl/simple.wgsl`).
    Direct,
    /// `tracer::AmbientOcclusion` with this reach (`wgsl/simple.wgsl`).
    AmbientOcclusion {
        /// Occluders farther than this do not count (∞: any).
        max_distance: f32,
    },
    /// `tracer::Whitted` (`wgsl/whitted.wgsl`), its recursion at most [`WHITTED_MAX_DEPTH`]
    /// deep.
    Whitted,
    /// `tracer::Bdpt` (`wgsl/bdpt.wgsl`): light tracing's splats are added to an image of
    /// exact fixed-point sums on the device ([`SPLAT_HEADER_WORDS`], nine words per pixel);
    /// the subpaths are kept in a scratch buffer ([`BDPT_SLOT_BYTES`] per invocation).
    Bdpt,
    /// `tracer::AtlasGi` with these settings (`wgsl/atlas.wgsl`): the atlas is built on the
    /// CPU when the scene is prepared and gathered on the GPU (`wgsl/atlas_gather.wgsl`),
    /// each pixel's specular chain, direct light and atlas lookup on the GPU.
    Atlas(tracer::integrator::AtlasSettings),
}

/// The deepest Whitted recursion the GPU traces: its branches wait on a stack of this
/// many entries in each invocation's private memory (one per level; 2¹⁶ leaves per sample
/// are far past any useful depth — the CPU's default is [`tracer::integrator::WHITTED_DEFAULT_DEPTH`]).
pub const WHITTED_MAX_DEPTH: u32 = 16;

impl GpuIntegrator {
    /// The `--integrator` name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Path => "path",
            Self::Direct => "direct",
            Self::AmbientOcclusion { .. } => "ao",
            Self::Whitted => "whitted",
            Self::Bdpt => "bdpt",
            Self::Atlas(_) => "atlas",
        }
    }

    /// Whether its light paths splat onto the image (bdpt): its kernel binds a splat image
    /// and the subpaths' scratch (bindings 13 and 14) and its film takes splat sums.
    pub fn splats(self) -> bool {
        self == Self::Bdpt
    }

    /// Whether its next-event estimation chooses lights by a light tree where the scene
    /// has one (`pt_sample_light_at`; as the CPU's integrators that declare
    /// `Integrator::chooses_lights_per_point`): the path tracer, direct light and the
    /// atlas's direct light. bdpt's and Whitted's light samples stay by power, as on the
    /// CPU.
    pub fn takes_light_tree(self) -> bool {
        matches!(self, Self::Path | Self::Direct | Self::Atlas(_))
    }

    /// The code `PT_INTEGRATOR` holds.
    fn code(self) -> u32 {
        match self {
            Self::Path => 0,
            Self::Direct => 1,
            Self::AmbientOcclusion { .. } => 2,
            Self::Whitted => 3,
            Self::Atlas(_) => 4,
            Self::Bdpt => 5,
        }
    }
}

wgsl_struct! {
    /// One pixel's accumulator on the device (f32 Welford over one read-back interval).
    pub struct PixelAccum as "PtPixel" {
        /// Running mean, linear sRGB.
        mean: [f32; 3],
        /// Samples added.
        count: u32,
        /// Sum of squared deviations.
        m2: [f32; 3],
        /// Samples dropped as NaN or infinite.
        non_finite: u32,
    }
}

wgsl_layout!(BvhNode as "PtNode" { min: [f32; 3], index: u32, max: [f32; 3], count: u32 });

wgsl_struct! {
    /// A node of the 4-wide BVH ([`crate::wide`]): its children's boxes as structure of
    /// arrays (one slab test of four boxes is a handful of vector operations) and their
    /// references.
    pub struct WideNode as "PtWideNode" {
        /// Children's lower x.
        lo_x: [f32; 4],
        /// Children's lower y.
        lo_y: [f32; 4],
        /// Children's lower z.
        lo_z: [f32; 4],
        /// Children's upper x.
        hi_x: [f32; 4],
        /// Children's upper y.
        hi_y: [f32; 4],
        /// Children's upper z.
        hi_z: [f32; 4],
        /// A child node's index, or a leaf's first triangle.
        index: [u32; 4],
        /// 0 for a child node, a leaf's triangle count, or [`WIDE_EMPTY`] for no child.
        count: [u32; 4],
    }
}

/// Where the ZSobol dimension seeds start in the uniform buffer, after [`Params`] (a
/// multiple of every device's uniform-offset alignment).
pub const SEEDS_OFFSET: u64 = 256;

/// Bytes of the uniform buffer: [`Params`], then one (index seed, value seed) word
/// quadruple per precomputed ZSobol dimension.
pub const UNIFORM_BYTES: u64 = SEEDS_OFFSET + 16 * tracer::sampler::PRECOMPUTED_DIMENSIONS as u64;

const _: () = assert!(std::mem::size_of::<Params>() as u64 <= SEEDS_OFFSET);

/// The ZSobol dimension seeds of a render as the kernel reads them (`pt_dims`): per
/// dimension the index seed's and the value seed's (lo, hi) words — computed once per
/// render, as the CPU's `ZSobolLayout` does, instead of hashed in every draw.
pub fn zsobol_seed_words(settings: &tracer::RenderSettings) -> Vec<[u32; 4]> {
    let layout = tracer::sampler::ZSobolLayout::new(settings.width, settings.height, settings.spp, settings.seed);
    let words = |v: u64| [v as u32, (v >> 32) as u32];
    layout
        .precomputed_seeds()
        .iter()
        .map(|&(i, v)| {
            let (i, v) = (words(i), words(v));
            [i[0], i[1], v[0], v[1]]
        })
        .collect()
}

/// [`WideNode::count`] of an unused child slot.
pub const WIDE_EMPTY: u32 = u32::MAX;

/// The BVH layout a kernel traverses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeLayout {
    /// The binary BVH (`bvh::BvhNode`), nearer child first; 64 stack entries.
    Binary,
    /// The 4-wide BVH ([`WideNode`]) with a stack of `stack` entries (what the tree can
    /// need at most: [`crate::wide::WideBvh::stack_bound`]).
    Wide4 {
        /// Stack entries.
        stack: u32,
    },
    /// The 8-wide BVH (two [`WideNode`]s per node) with a stack of `stack` entries.
    Wide8 {
        /// Stack entries.
        stack: u32,
    },
}

impl NodeLayout {
    /// This layout with the larger stack of the two (the trees of a two-level scene share
    /// one traversal, so its stack is the deepest tree's).
    pub fn max_stack(self, other: NodeLayout) -> NodeLayout {
        match (self, other) {
            (Self::Wide4 { stack: a }, Self::Wide4 { stack: b }) => Self::Wide4 { stack: a.max(b) },
            (Self::Wide8 { stack: a }, Self::Wide8 { stack: b }) => Self::Wide8 { stack: a.max(b) },
            _ => self,
        }
    }
}

/// Bytes of the film buffer before the accumulators: the 64-bit ray counter (two words),
/// the truncated-path counter and a pad word (`PtFilm`'s header).
pub const FILM_HEADER_BYTES: u64 = 16;

/// Words of bdpt's splat image before its pixels: the count of splats dropped (not
/// finite, or beyond [`tracer::film::MAX_SAMPLE_MAGNITUDE`]) and three pad words. Each
/// pixel then has three channels of three words: round(x · 2³²) summed in 96-bit two's
/// complement, low word first.
pub const SPLAT_HEADER_WORDS: u32 = 4;

/// Bytes of bdpt's scratch per invocation (`wgsl/bdpt.wgsl`): eight vec4s per light-subpath
/// vertex and one per camera-subpath vertex.
pub const BDPT_SLOT_BYTES: u64 =
    16 * (8 * (tracer::integrator::BDPT_MAX_VERTICES as u64 - 1) + tracer::integrator::BDPT_MAX_VERTICES as u64);

/// Scene flag: vertices have shading normals.
pub const HAS_NORMALS: u32 = 1;
/// Scene flag: vertices have tangents.
pub const HAS_TANGENTS: u32 = 2;
/// Scene flag: the scene has an environment light.
pub const HAS_ENVIRONMENT: u32 = 4;
/// Scene flag: vertices have texture coordinates (in the `w` of their attributes).
pub const HAS_UVS: u32 = 8;
/// Scene flag: some material disperses light (`SceneView::has_dispersion`).
pub const HAS_DISPERSION: u32 = 16;

/// Floats per light in the light table: nine of the light's own (a triangle's vertices,
/// a shape's record offset, a punctual light's position, axis, cone and spectrum), cdf,
/// pmf, material id (bits), kind ([`LightKind`], bits) and seven more of its own.
pub const LIGHT_FLOATS: usize = 20;
/// Index of the cdf within a light's floats.
pub const LIGHT_CDF: u32 = 9;
/// Index of the pmf within a light's floats.
pub const LIGHT_PMF: u32 = 10;
/// Index of the material id (bits) within a light's floats.
pub const LIGHT_MATERIAL: u32 = 11;
/// Index of the kind (bits) within a light's floats.
pub const LIGHT_KIND: usize = 12;

/// What an entry of the light table is (`PT_LIGHT_*`), and what its own floats hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    /// An emissive triangle: its vertices (0..9).
    Triangle = 0,
    /// An emissive analytic shape: its record's offset in `pt_tables` (0, bits).
    Shape = 1,
    /// A point light: position (0..3), its intensity's spectrum table (3, bits).
    Point = 2,
    /// A spot light: position (0..3), axis (3..6), cos of the inner and outer cones (6, 7),
    /// its intensity's spectrum table (8, bits).
    Spot = 3,
    /// A directional light or sun: direction towards it (0..3), cos of its angular radius
    /// (3; 1 for a delta direction), solid angle (4), radiance / irradiance (5), its
    /// irradiance's spectrum table (6, bits), the sampling frame's two tangents (13..16,
    /// 16..19).
    Directional = 4,
}

/// What a record of the analytic-shape table is (`PT_SHAPE_*`). Every record starts with
/// the kind, the material id (bits), the light pmf and the area; see
/// `crate::backend::shape_record` for the rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeCode {
    /// `shapes::sphere::Sphere`.
    Sphere = 0,
    /// `shapes::boxes::Cuboid`.
    Cuboid = 1,
    /// `shapes::polygon::Polygon`.
    Polygon = 2,
    /// `shapes::implicit::Implicit` (`wgsl/implicit.wgsl`, in f64).
    Implicit = 3,
}

/// An implicit surface's root finder in its record (`PT_IMPLICIT_*`).
pub fn root_solver_code(solver: shapes::roots::RootSolver) -> u32 {
    use shapes::roots::RootSolver;
    match solver {
        RootSolver::ClosedForm => 0,
        RootSolver::Laguerre { polish: true } => 1,
        RootSolver::Laguerre { polish: false } => 2,
    }
}

/// A shape hit's primitive id in the kernel: this bit set, the record's offset below it.
pub const SHAPE_PRIM_BIT: u32 = 0x8000_0000;

/// Entries of the traversal stack (the BVH builders' depth limit is 62).
const STACK_ENTRIES: u32 = 64;

/// What a kernel is specialised for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelOptions {
    /// The triangle test compiled in.
    pub triangle_test: TriangleTest,
    /// The most scattering events a path may have.
    pub max_bounces: u32,
    /// The BVH layout traversed.
    pub nodes: NodeLayout,
    /// The integrator compiled in.
    pub integrator: GpuIntegrator,
    /// The sampler compiled in (`PT_SAMPLER`): a render with another gets another kernel.
    pub sampler: SamplerKind,
    /// Whether the scene has analytic shapes (`PT_HAS_SHAPES`: without, their traversal
    /// and surfaces are not in the kernel).
    pub shapes: bool,
    /// Whether the scene places instances (`PT_HAS_INSTANCES`: without, the two-level
    /// traversal and the instance transforms in shading are not in the kernel).
    pub instances: bool,
    /// Whether the scene has point, spot or directional lights (`PT_HAS_PUNCTUAL`).
    pub punctual_lights: bool,
    /// The length of the implicit surfaces' coefficient arrays (`PT_IMPLICIT_COEFFS`: the
    /// highest degree + 1, at least 5 for the quartic), 0 without implicit surfaces — then
    /// `wgsl/implicit.wgsl` and its f64 are not in the kernel, which therefore compiles on
    /// devices without wgpu's `SHADER_F64`.
    pub implicit_coeffs: u32,
    /// The spectral mode (`PT_RGB`, the materials' `MAT_RGB`: three colour channels;
    /// `PT_BINS40`: the 40 fixed bins as ten paths of four per sample); a render in another
    /// mode gets another kernel.
    pub mode: SpectralMode,
    /// Whether materials read textures (`PT_HAS_TEXTURES`, and the texel buffer at binding
    /// 12).
    pub textures: bool,
    /// Whether some material is cut out or transparent by its alpha (`PT_HAS_CUTOUTS`).
    pub cutouts: bool,
    /// Whether the environment is a map (`PT_HAS_ENV_MAP`).
    pub env_map: bool,
    /// How the triangle BVH's nodes are split (`SceneOptions::bvh_builder`; the scene
    /// data's, not the kernel source's).
    pub bvh_builder: bvh::SplitMethod,
    /// Whether the path tracer runs as a wavefront (`wgsl/wavefront.wgsl`: its stages'
    /// entry points and their buffers, bindings 15 and 16 and group 1) rather than as
    /// `pt_main`'s megakernel alone.
    pub wavefront: bool,
    /// How next-event estimation chooses lights, as asked (`SceneOptions::light_sampler`;
    /// `SceneData::new` takes a tree only for an integrator that walks one,
    /// [`GpuIntegrator::takes_light_tree`], and power for the others).
    pub light_sampler: tracer::LightSampler,
    /// Whether the scene's emitters, point and spot lights are chosen by a light tree
    /// (`PT_LIGHT_TREE`; set by `SceneData::new` from `light_sampler` and the scene's
    /// lights).
    pub light_tree: bool,
}

/// A default kernel: the watertight test, the binary tree, the path tracer, ZSobol, hero
/// wavelengths (the backend's prepared kernel takes its sampler and mode from
/// `SceneOptions::first_render` instead); the scene features (shapes … `env_map`) are set by
/// `SceneData::new` from the scene itself.
impl Default for KernelOptions {
    fn default() -> Self {
        Self {
            triangle_test: TriangleTest::Watertight,
            max_bounces: crate::backend::MAX_BOUNCES,
            nodes: NodeLayout::Binary,
            integrator: GpuIntegrator::Path,
            sampler: SamplerKind::ZSobol,
            shapes: false,
            instances: false,
            punctual_lights: false,
            implicit_coeffs: 0,
            mode: SpectralMode::Hero,
            textures: false,
            cutouts: false,
            env_map: false,
            bvh_builder: crate::backend::triangle_build_config().method,
            wavefront: false,
            light_sampler: tracer::LightSampler::Power,
            light_tree: false,
        }
    }
}

/// A sphere method's code in a shape record (`PT_SPHERE_*`).
pub fn sphere_method_code(method: shapes::sphere::SphereMethod) -> u32 {
    match method {
        shapes::sphere::SphereMethod::Geometric => 0,
        shapes::sphere::SphereMethod::AlgebraicNaive => 1,
        shapes::sphere::SphereMethod::AlgebraicStable => 2,
    }
}

/// A polygon inside test's code in a shape record (`PT_POLYGON_*`).
pub fn polygon_test_code(test: shapes::polygon::InsideTest) -> u32 {
    match test {
        shapes::polygon::InsideTest::WindingNumber => 0,
        shapes::polygon::InsideTest::CrossingNumber => 1,
    }
}

/// An f32 as a WGSL literal that parses back to the same value.
fn f(v: f32) -> String {
    assert!(v.is_finite(), "WGSL has no literal for {v}");
    format!("{v:?}f")
}

/// The generated part: structs, bindings, constants.
pub fn header(options: &KernelOptions) -> String {
    let mut out = String::from("// ---- Generated by gpu::kernel from the Rust definitions.\n\n");
    out.push_str(&Params::declaration());
    out.push('\n');
    let (node_struct, stack) = match options.nodes {
        NodeLayout::Binary => {
            out.push_str(&BvhNode::declaration());
            ("PtNode", STACK_ENTRIES)
        }
        NodeLayout::Wide4 { stack } | NodeLayout::Wide8 { stack } => {
            out.push_str(&WideNode::declaration());
            ("PtWideNode", stack.max(1))
        }
    };
    out.push('\n');
    out.push_str(&PixelAccum::declaration());
    out.push_str(
        "\nstruct PtFilm {\n    rays_lo: atomic<u32>,\n    rays_hi: atomic<u32>,\n    truncated: atomic<u32>,\n    \
         pad: u32,\n    pixels: array<PtPixel>,\n}\n\n",
    );
    out.push_str(
        &"@group(0) @binding(0) var<uniform> pt_params: PtParams;\n\
         @group(0) @binding(1) var<storage, read> pt_nodes: array<NODE_STRUCT>;\n\
         @group(0) @binding(2) var<storage, read> pt_tri_verts: array<vec4f>;\n\
         @group(0) @binding(3) var<storage, read> pt_tri_vidx: array<vec4u>;\n\
         @group(0) @binding(4) var<storage, read> pt_attrs: array<vec4f>;\n\
         @group(0) @binding(5) var<storage, read> pt_tables: array<f32>;\n\
         @group(0) @binding(6) var<storage, read_write> pt_film: PtFilm;\n\
         @group(0) @binding(7) var<uniform> pt_dims: array<vec4u, PT_SEED_DIMENSIONS>;\n\n"
            .replace("NODE_STRUCT", node_struct),
    );
    // bdpt's splat image and its subpaths' scratch (nothing else binds them).
    if options.integrator.splats() {
        out.push_str(
            "@group(0) @binding(13) var<storage, read_write> pt_splats: array<atomic<u32>>;\n\
             @group(0) @binding(14) var<storage, read_write> pt_bdpt_scratch: array<vec4f>;\n\n",
        );
    }
    // The texels only where a material reads them (a binding more than the device may have).
    out.push_str(if options.textures {
        "@group(0) @binding(12) var<storage, read> pt_texels: array<u32>;\n\n"
    } else {
        "var<private> pt_texels: array<u32, 1>; // (no textures)\n\n"
    });
    let mut u = |name: &str, v: u32| {
        let _ = writeln!(out, "const {name}: u32 = {v}u;");
    };
    for mode in ShadingNormals::ALL {
        u(&format!("PT_SHADING_{}", mode.name().to_ascii_uppercase().replace('-', "_")), mode.code());
    }
    u("PT_HAS_NORMALS", HAS_NORMALS);
    u("PT_HAS_TANGENTS", HAS_TANGENTS);
    u("PT_HAS_ENVIRONMENT", HAS_ENVIRONMENT);
    u("PT_HAS_UVS", HAS_UVS);
    u("PT_HAS_DISPERSION", HAS_DISPERSION);
    u("PT_CIE_SAMPLES", CIE_SAMPLES as u32);
    u("PT_LIGHT_FLOATS", LIGHT_FLOATS as u32);
    u("PT_LIGHT_CDF", LIGHT_CDF);
    u("PT_LIGHT_PMF", LIGHT_PMF);
    u("PT_LIGHT_MATERIAL", LIGHT_MATERIAL);
    u("PT_LIGHT_KIND", LIGHT_KIND as u32);
    for kind in [LightKind::Triangle, LightKind::Shape, LightKind::Point, LightKind::Spot, LightKind::Directional] {
        u(&format!("PT_LIGHT_{}", format!("{kind:?}").to_ascii_uppercase()), kind as u32);
    }
    for code in [ShapeCode::Sphere, ShapeCode::Cuboid, ShapeCode::Polygon, ShapeCode::Implicit] {
        u(&format!("PT_SHAPE_{}", format!("{code:?}").to_ascii_uppercase()), code as u32);
    }
    u("PT_SHAPE_PRIM_BIT", SHAPE_PRIM_BIT);
    for (name, method) in [
        ("GEOMETRIC", shapes::sphere::SphereMethod::Geometric),
        ("ALGEBRAIC_NAIVE", shapes::sphere::SphereMethod::AlgebraicNaive),
        ("ALGEBRAIC_STABLE", shapes::sphere::SphereMethod::AlgebraicStable),
    ] {
        u(&format!("PT_SPHERE_{name}"), sphere_method_code(method));
    }
    u("PT_POLYGON_WINDING", polygon_test_code(shapes::polygon::InsideTest::WindingNumber));
    u("PT_POLYGON_CROSSING", polygon_test_code(shapes::polygon::InsideTest::CrossingNumber));
    u("PT_STACK", stack);
    u("PT_INTEGRATOR", options.integrator.code());
    u("PT_TREE_NODE_FLOATS", tracer::lights::LIGHT_TREE_NODE_FLOATS as u32);
    u("PT_SAMPLER", sampler_code(options.sampler));
    u("PT_SEED_DIMENSIONS", tracer::sampler::PRECOMPUTED_DIMENSIONS);
    for kind in SamplerKind::ALL {
        u(&format!("PT_SAMPLER_{}", kind.name().to_ascii_uppercase()), sampler_code(kind));
    }
    for (i, m) in tracer::sampler::LAINE_KARRAS_MULS.into_iter().enumerate() {
        u(&format!("PT_LK_MUL{i}"), m);
    }
    u("PT_INTEGRATOR_PATH", GpuIntegrator::Path.code());
    u("PT_INTEGRATOR_DIRECT", GpuIntegrator::Direct.code());
    u("PT_INTEGRATOR_AO", GpuIntegrator::AmbientOcclusion { max_distance: 0.0 }.code());
    u("PT_INTEGRATOR_WHITTED", GpuIntegrator::Whitted.code());
    u("PT_INTEGRATOR_ATLAS", GpuIntegrator::Atlas(Default::default()).code());
    u("PT_INTEGRATOR_BDPT", GpuIntegrator::Bdpt.code());
    u("PT_BDPT_MAX_VERTICES", tracer::integrator::BDPT_MAX_VERTICES as u32);
    u("PT_SPLAT_HEADER_WORDS", SPLAT_HEADER_WORDS);
    u("PT_ATLAS_SPECULAR_CHAIN", tracer::integrator::ATLAS_SPECULAR_CHAIN);
    u("PT_WHITTED_DEFAULT_DEPTH", tracer::integrator::WHITTED_DEFAULT_DEPTH);
    // (The stack only where it is used: private arrays cost registers or local memory.)
    u("PT_WHITTED_STACK", if options.integrator == GpuIntegrator::Whitted { WHITTED_MAX_DEPTH } else { 1 });
    u("PT_WIDE_EMPTY", WIDE_EMPTY);
    u("PT_MAX_BOUNCES", options.max_bounces);
    let _ = writeln!(out, "const PT_HAS_SHAPES: bool = {};", options.shapes);
    let _ = writeln!(out, "const PT_HAS_INSTANCES: bool = {};", options.instances);
    let _ = writeln!(out, "const PT_HAS_PUNCTUAL: bool = {};", options.punctual_lights);
    let _ = writeln!(out, "const PT_LIGHT_TREE: bool = {};", options.light_tree);
    let _ = writeln!(out, "const PT_RGB: bool = {};", options.mode == SpectralMode::Rgb);
    let _ = writeln!(out, "const PT_BINS40: bool = {};", options.mode == SpectralMode::Bins40);
    let _ = writeln!(out, "const PT_HAS_TEXTURES: bool = {};", options.textures);
    let _ = writeln!(out, "const PT_HAS_CUTOUTS: bool = {};", options.cutouts);
    let _ = writeln!(out, "const PT_HAS_ENV_MAP: bool = {};", options.env_map);
    let [r, g, b] = brdf::models::metal::RGB_LAMBDA;
    // RGB mode's "wavelengths": where metals take their (n, k) per channel (`RGB_LAMBDA`).
    let _ = writeln!(out, "const PT_RGB_LAMBDA: vec4f = vec4f({}, {}, {}, {});", f(r), f(g), f(b), f(b));
    for (name, v) in [
        ("PT_LAMBDA_MIN", LAMBDA_MIN),
        ("PT_LAMBDA_MAX", LAMBDA_MAX),
        ("PT_VIS_K", VIS_K),
        ("PT_VIS_CENTRE", VIS_CENTRE),
        ("PT_VIS_TANH_LO", VIS_TANH_LO),
        ("PT_VIS_TANH_HI", VIS_TANH_HI),
        ("PT_CIE_LAMBDA_MIN", CIE_LAMBDA_MIN),
        ("PT_CIE_Y_INTEGRAL", CIE_Y_INTEGRAL),
        ("PT_MIN_SHADING_COSINE", MIN_SHADING_COSINE),
        ("PT_RR_MIN_TERMINATION", RR_MIN_TERMINATION),
        ("PT_SHADOW_T_MAX", SHADOW_T_MAX),
        ("PT_MAX_SAMPLE_MAGNITUDE", tracer::film::MAX_SAMPLE_MAGNITUDE),
        ("PT_ONE_MINUS_EPSILON", tracer::lights::ONE_MINUS_EPSILON),
        ("PT_OFFSET_ORIGIN", shapes::offset::OFFSET_ORIGIN),
        ("PT_OFFSET_FLOAT_SCALE", shapes::offset::OFFSET_FLOAT_SCALE),
        ("PT_OFFSET_INT_SCALE", shapes::offset::OFFSET_INT_SCALE),
    ] {
        let _ = writeln!(out, "const {name}: f32 = {};", f(v));
    }
    for (name, v) in [
        ("PT_PCG_MULT", rng::MULT),
        ("PT_PCG_SAMPLE_STREAM_KEY", rng::SAMPLE_STREAM_KEY),
        ("PT_MIX64_MUL1", rng::MIX64_MUL1),
        ("PT_MIX64_MUL2", rng::MIX64_MUL2),
        ("PT_DIMENSION_MUL", tracer::sampler::DIMENSION_MUL),
        ("PT_VALUE_SEED_KEY", tracer::sampler::VALUE_SEED_KEY),
        ("PT_LK64_MUL0", tracer::sampler::LAINE_KARRAS_64_MULS[0]),
        ("PT_LK64_MUL1", tracer::sampler::LAINE_KARRAS_64_MULS[1]),
        ("PT_LK64_MUL2", tracer::sampler::LAINE_KARRAS_64_MULS[2]),
    ] {
        let _ = writeln!(out, "const {name}: vec2u = vec2u({:#010x}u, {:#010x}u);", v as u32, (v >> 32) as u32);
    }
    for (row, name) in XYZ_TO_SRGB.iter().zip(["R", "G", "B"]) {
        let _ =
            writeln!(out, "const PT_XYZ_TO_SRGB_{name}: vec3f = vec3f({}, {}, {});", f(row[0]), f(row[1]), f(row[2]));
    }
    out.push('\n');
    out
}

/// The analytic shapes' hit record and the tables' readers (`wgsl/shape_hit.wgsl`), which
/// [`implicit_source`] needs: a test kernel of implicit surfaces binds `pt_tables` and
/// declares `PT_MISS` and takes these two pieces.
pub const SHAPE_HIT_SOURCE: &str = include_str!("wgsl/shape_hit.wgsl");

/// The hand-written files, in the order they are concatenated.
const FILES: [(&str, &str); 17] = [
    ("rng.wgsl", include_str!("wgsl/rng.wgsl")),
    ("sampler.wgsl", include_str!("wgsl/sampler.wgsl")),
    ("spectral.wgsl", include_str!("wgsl/spectral.wgsl")),
    ("frame.wgsl", include_str!("wgsl/frame.wgsl")),
    ("offset.wgsl", include_str!("wgsl/offset.wgsl")),
    ("shading.wgsl", include_str!("wgsl/shading.wgsl")),
    ("ray.wgsl", include_str!("wgsl/ray.wgsl")),
    ("shape_hit.wgsl", SHAPE_HIT_SOURCE),
    ("shapes.wgsl", include_str!("wgsl/shapes.wgsl")),
    ("instances.wgsl", include_str!("wgsl/instances.wgsl")),
    ("textures.wgsl", include_str!("wgsl/textures.wgsl")),
    ("envmap.wgsl", include_str!("wgsl/envmap.wgsl")),
    ("lights.wgsl", include_str!("wgsl/lights.wgsl")),
    ("path.wgsl", include_str!("wgsl/path.wgsl")),
    ("simple.wgsl", include_str!("wgsl/simple.wgsl")),
    ("whitted.wgsl", include_str!("wgsl/whitted.wgsl")),
    ("atlas.wgsl", include_str!("wgsl/atlas.wgsl")),
];

/// `wgsl/implicit.wgsl` with its constants (from `shapes`) for coefficient arrays of
/// `coeffs` entries, or, with 0, a stub that never hits: the f64 code only where a scene has
/// implicit surfaces.
pub fn implicit_source(coeffs: u32) -> String {
    use shapes::roots::RootSolver;
    if coeffs == 0 {
        return "\n// ---- implicit surfaces (none in this scene)\nfn pt_implicit_hit(rec: u32, o: vec3f, d: vec3f, \
                t_min: f32, t_max: f32) -> PtShapeHit {\n    return pt_no_shape_hit();\n}\n\
                fn pt_implicit_surface(rec: u32, o: vec3f, d: vec3f, t: f32) -> PtShapeHit {\n    \
                return pt_no_shape_hit();\n}\n"
            .to_string();
    }
    let mut out = String::from("\n// ---- implicit.wgsl\n");
    let _ = writeln!(out, "const PT_IMPLICIT_COEFFS: u32 = {coeffs}u;");
    for (name, solver) in [
        ("CLOSED_FORM", RootSolver::ClosedForm),
        ("LAGUERRE_POLISH", RootSolver::Laguerre { polish: true }),
        ("LAGUERRE_PLAIN", RootSolver::Laguerre { polish: false }),
    ] {
        let _ = writeln!(out, "const PT_IMPLICIT_{name}: u32 = {}u;", root_solver_code(solver));
    }
    let _ = writeln!(
        out,
        "const PT_IM_MAX_ITERATIONS: u32 = {}u;",
        shapes::roots::LaguerreSettings::default().max_iterations
    );
    for (name, v) in [
        ("PT_IM_PAD_REL", shapes::implicit::PAD_REL),
        ("PT_IM_S_EPS", shapes::implicit::S_EPS),
        ("PT_IM_REAL_IM_TOL", shapes::roots::REAL_IM_TOL),
        ("PT_IM_LEAD_TOL", shapes::roots::LEAD_TOL),
    ] {
        let _ = writeln!(out, "const {name}: f64 = {v:e};");
    }
    out.push_str(include_str!("wgsl/implicit.wgsl"));
    out
}

/// The kernel's entry point, last.
const MAIN: &str = include_str!("wgsl/main.wgsl");

/// The display kernel ([`crate::accumulation`]): the running mean of a device-resident
/// accumulation as 0x00RRGGBB pixels, for a viewer.
pub fn display_source() -> String {
    let mut out = String::from("// ---- Generated by gpu::kernel from the Rust definitions.\n\n");
    out.push_str(&PixelAccum::declaration());
    let _ = write!(out, "\n// ---- display.wgsl\n{}", include_str!("wgsl/display.wgsl"));
    out
}

/// The whole kernel: the material WGSL (from [`crate::materials`]), the generated
/// header, the hand-written files and the chosen triangle test.
pub fn source(material_wgsl: &str, options: &KernelOptions) -> String {
    let triangle = match options.triangle_test {
        TriangleTest::Watertight => include_str!("wgsl/triangle_watertight.wgsl"),
        TriangleTest::MollerTrumbore => include_str!("wgsl/triangle_moller_trumbore.wgsl"),
    };
    let mut out = String::with_capacity(material_wgsl.len() + 64 * 1024);
    out.push_str(&crate::materials::for_mode(material_wgsl, options.mode == SpectralMode::Rgb));
    out.push('\n');
    out.push_str(&header(options));
    out.push_str("\nconst PT_PI: f32 = 3.14159265358979323846;\nconst PT_INV_4PI: f32 = 0.07957747154594767;\n");
    out.push_str(
        "// \"Infinity\" for ray extents (WGSL has no infinite literal) and the slab test's miss marker,\n\
         // larger than any extent.\nconst PT_FAR: f32 = 3.0e38;\nconst PT_MISS: f32 = 3.4e38;\n\
         const PT_NO_HIT: u32 = 0xffffffffu;\n",
    );
    for (name, text) in FILES {
        let _ = write!(out, "\n// ---- {name}\n{text}");
    }
    let wide_nodes = ("traversal_wide_nodes.wgsl", include_str!("wgsl/traversal_wide_nodes.wgsl"));
    let traversal: &[(&str, &str)] = match options.nodes {
        NodeLayout::Binary => &[("traversal.wgsl", include_str!("wgsl/traversal.wgsl"))],
        NodeLayout::Wide4 { .. } => &[wide_nodes, ("traversal_wide.wgsl", include_str!("wgsl/traversal_wide.wgsl"))],
        NodeLayout::Wide8 { .. } => &[wide_nodes, ("traversal_wide8.wgsl", include_str!("wgsl/traversal_wide8.wgsl"))],
    };
    for (name, text) in traversal {
        let _ = write!(out, "\n// ---- {name}\n{text}");
    }
    if options.integrator.splats() {
        let _ = write!(out, "\n// ---- bdpt.wgsl\n{}", include_str!("wgsl/bdpt.wgsl"));
    } else {
        // (Its arrays and splat image exist only in its own kernel.)
        out.push_str(
            "\nfn pt_bdpt(o: vec3f, d: vec3f, wl: ptr<function, PtWavelengths>, smp: ptr<function, PtSampler>, \
             rays: ptr<function, u32>, truncated: ptr<function, u32>) -> vec4f {\n    return vec4f(0.0);\n}\n",
        );
    }
    out.push_str(&implicit_source(options.implicit_coeffs));
    let _ = write!(out, "\n// ---- triangle test\n{triangle}\n// ---- main.wgsl\n{MAIN}");
    if options.wavefront {
        let _ = write!(out, "\n// ---- wavefront.wgsl\n{}", include_str!("wgsl/wavefront.wgsl"));
    }
    if matches!(options.integrator, GpuIntegrator::Atlas(_)) {
        let _ = write!(out, "\n// ---- atlas_gather.wgsl\n{}", include_str!("wgsl/atlas_gather.wgsl"));
    }
    out
}
