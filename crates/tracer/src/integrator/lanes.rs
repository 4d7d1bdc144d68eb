//! The path tracer over lanes, for scenes of triangles: 64 paths side by side in
//! structure-of-arrays form, so that everything between the ray queries on diffuse
//! surfaces — surface data and shading normals, emission and its MIS weight, the shading
//! frame, the light sample's geometry, the Lambertian sample, the spectra at the paths'
//! wavelengths, Russian roulette, the Sobol samplers' values — runs as vector
//! instructions across the paths (AVX-512 or AVX2 where the machine has it, chosen at run
//! time), while the rays go through the same BVH queries one at a time. A path at any
//! other surface (glass, a mirror, a textured or rough material) is shaded there by the
//! general loop's own code ([`path_vertex`]), one lane at a time, and goes on in its lane.
//! A path that ends hands its lane to the block's next camera sample.
//!
//! Why 64 lanes, not 8 (one AVX2 register): LLVM unrolls a loop of 8 completely before
//! its loop vectoriser runs, and the straight-line vectoriser that is left packed only
//! part of the work; loops of 64 are vectorised as loops, eight lanes per instruction
//! with the selects and gathers they need (Cornell box, one thread, against the general
//! loop: 8 lanes +10–20 %, 64 lanes +24 %, docs/figures.md).
//!
//! It is [`super::PathTracer`]'s estimator, not an approximation of it: every value is computed
//! by the same operations in the same order as the general loop (`path_radiance`), from
//! the same sample values drawn in the same order per path, so the image is the same to
//! the bit (`lanes_compute_the_general_loops_estimate_bit_for_bit` checks it; Rust never
//! contracts a·b + c into a fused multiply-add, so the AVX2 build rounds as the baseline).
//!
//! The specialisation ("model no more than a scene needs") applies where the scene is
//! triangles only (no analytic shapes or instances), lit by its emissive triangles and
//! its point, spot and delta directional lights (no environment or sun disks; chosen by
//! power or by a light tree for the shading point, one lane at a time, a punctual light's
//! estimate made one lane at a time too), every emitter's and light's colour an RGB
//! uplift or a constant, no material disperses or absorbs, at least one material is an untextured
//! [`brdf::Lambert`] with such colours (the surfaces the lanes shade), and there is no
//! diffuse-depth limit ([`LaneScene::of`], [`LaneScene::admits`]). Anything else runs the
//! general loop. `spt render --no-lanes` (`PathSettings::lanes`) runs the general loop
//! everywhere, to measure the difference.

use super::{
    CameraSample, Chain, PathCounters, PathSettings, PathState, RR_MIN_TERMINATION, SHADOW_T_MAX, SceneView,
    ShadingNormals, path_vertex, power_heuristic, punctual_geometry,
};
use crate::geometry::{HitSurface, SceneHit};
use crate::lights::{LightSource, on_triangle};
use crate::material::{ModelParams, Surface};
use crate::punctual::PunctualLight;
use crate::sampler::{LaneDraw, Sampler, SobolLanes};
use crate::shading::MIN_SHADING_COSINE;
use brdf::sampling::{sin_cos_quarter, uniform_triangle};
use bvh::isa::Isa;
use bvh::{Accelerator, Ray};
use glam::{Vec2, Vec3};
use shapes::offset::{OFFSET_FLOAT_SCALE, OFFSET_INT_SCALE, OFFSET_ORIGIN};
use spectral::spectrum::{Colour, Spectrum};
use spectral::uplift::d65_normalised;
use spectral::{SampledSpectrum, SigmoidPolynomial};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};
use std::hint::select_unpredictable;

/// Paths side by side (eight to an AVX2 instruction; see the module documentation).
pub const LANES: usize = 64;

/// One f32 per lane.
type F = [f32; LANES];
/// One flag per lane.
type M = [bool; LANES];

/// A colour as the lanes evaluate it: `Colour::sample`'s three cases in one branch-free
/// form, `(scale · S(c₀λ² + c₁λ + c₂)) · D65(λ)` (D65 only for an illuminant, scale 1 for a
/// reflectance: both multiplications by 1 are exact) or a constant.
#[derive(Clone, Copy, Debug, Default)]
struct LaneColour {
    poly: [f32; 3],
    scale: f32,
    illuminant: bool,
    constant: Option<f32>,
    rgb: [f32; 3],
}

impl LaneColour {
    /// The lanes' form of `c`, or `None` for a spectrum they do not evaluate.
    fn of(c: &Colour) -> Option<Self> {
        let base = Self { rgb: c.rgb, scale: 1.0, ..Self::default() };
        let p = |p: &SigmoidPolynomial| [p.c0, p.c1, p.c2];
        match &c.spectrum {
            Spectrum::Constant(v) => Some(Self { constant: Some(*v), ..base }),
            Spectrum::RgbAlbedo(s) => Some(Self { poly: p(&s.poly), ..base }),
            Spectrum::RgbIlluminant(s) => Some(Self { poly: p(&s.poly), scale: s.scale, illuminant: true, ..base }),
            _ => None,
        }
    }
}

/// What the lanes need of a scene, per material: its albedo where the lanes shade it
/// (`None`: one lane at a time, by the general loop's [`path_vertex`]) and its emission.
pub(crate) struct LaneScene {
    albedo: Vec<Option<LaneColour>>,
    emission: Vec<Option<LaneColour>>,
    /// Each punctual light's colour (intensity or irradiance), by its index in
    /// [`crate::scene::Scene::punctual_lights`]: point, spot and delta directional lights,
    /// whose next-event estimates the lanes make too.
    punctual: Vec<LaneColour>,
    /// Whether the mesh has shading normals, interpolated unless geometric shading ignores them.
    normals: bool,
    /// Whether the mesh has tangents, which orient the BSDF's frame about its normal.
    tangents: bool,
}

impl LaneScene {
    /// The lanes' tables for `view`'s scene, or `None` where the scene needs the general
    /// loop (see the module documentation). Computed once per view
    /// ([`SceneView::lane_scene`]); [`LaneScene::admits`] checks the settings.
    pub(crate) fn of(view: &SceneView) -> Option<Self> {
        let scene = view.scene;
        let plain = scene.shapes.is_empty()
            && scene.instances.is_empty()
            && view.geometry.instances.is_none()
            && scene.environment.is_none()
            && view.lights.suns().is_empty()
            && view.lights.environment_pmf() == 0.0
            && !view.dispersive
            && !view.absorbing
            && scene.material_ids.len() == scene.triangles.len();
        if !plain {
            return None;
        }
        let mut albedo = Vec::with_capacity(scene.materials.len());
        let mut emission = Vec::with_capacity(scene.materials.len());
        for m in &scene.materials {
            albedo.push(match &m.surface {
                Surface::Builtin(ModelParams::Lambert(p)) if m.textures.is_none() => LaneColour::of(&p.reflectance),
                _ => None,
            });
            // Every emitter's colour, which next-event estimation evaluates in the lanes.
            emission.push(match &m.emission {
                Some(e) => Some(LaneColour::of(e)?),
                None => None,
            });
        }
        let punctual = scene.punctual_lights.iter().map(|l| LaneColour::of(l.colour())).collect::<Option<Vec<_>>>()?;
        // Without a surface for the lanes, the general loop is the faster.
        let (normals, tangents) = (!scene.normals.is_empty(), !scene.tangents.is_empty());
        albedo.iter().any(Option::is_some).then_some(Self { albedo, emission, punctual, normals, tangents })
    }

    /// Whether the lanes render this scene with `settings` (the switch on, no
    /// diffuse-depth limit).
    pub(crate) fn admits(&self, settings: &PathSettings) -> bool {
        settings.lanes && settings.max_diffuse_depth == 0
    }
}

/// The colours of the lanes' materials gathered into one array per coefficient, so that
/// their evaluation vectorises across the lanes.
#[derive(Clone, Copy)]
struct Gathered {
    c0: F,
    c1: F,
    c2: F,
    scale: F,
    illuminant: M,
    is_constant: M,
    constant: F,
    rgb: [F; 3],
}

impl Default for Gathered {
    fn default() -> Self {
        let (z, no) = ([0.0; LANES], [false; LANES]);
        Self { c0: z, c1: z, c2: z, scale: z, illuminant: no, is_constant: no, constant: z, rgb: [z; 3] }
    }
}

impl Gathered {
    #[inline(always)]
    fn set(&mut self, k: usize, c: &LaneColour) {
        [self.c0[k], self.c1[k], self.c2[k]] = c.poly;
        self.scale[k] = c.scale;
        self.illuminant[k] = c.illuminant;
        self.is_constant[k] = c.constant.is_some();
        self.constant[k] = c.constant.unwrap_or(0.0);
        for (i, v) in c.rgb.iter().enumerate() {
            self.rgb[i][k] = *v;
        }
    }

    /// The colours at wavelengths `lambda` (per lane, with `d65` the normalised D65 there),
    /// as `Colour::sample` computes them; in RGB mode the colours' channels.
    #[inline(always)]
    fn eval<const N: usize>(&self, lambda: &[F; N], d65: &[F; N], rgb: bool) -> [F; N] {
        let mut out = [[0.0; LANES]; N];
        if rgb {
            for (i, o) in out.iter_mut().enumerate().take(3) {
                *o = self.rgb[i];
            }
            return out;
        }
        for i in 0..N {
            for k in 0..LANES {
                let l = lambda[i][k];
                let s = SigmoidPolynomial { c0: self.c0[k], c1: self.c1[k], c2: self.c2[k] }.eval(l);
                let d = if self.illuminant[k] { d65[i][k] } else { 1.0 };
                let v = self.scale[k] * s * d;
                out[i][k] = if self.is_constant[k] { self.constant[k] } else { v };
            }
        }
        out
    }
}

/// One coordinate of `shapes::offset::offset_ray_origin(p, n)`, the same value, with the
/// ulp count converted without Rust's saturating `as i32` (which LLVM leaves scalar): for
/// |256·n| < 257 — every unit normal — the truncation is the same; anything else (NaN, or
/// garbage in a lane without a path) moves 0 ulps, as `as i32` does for NaN. The integer
/// steps wrap, as they do in the release build of the original.
#[inline(always)]
fn offset_coordinate(p: f32, n: f32) -> f32 {
    let x = OFFSET_INT_SCALE * n;
    let x = if x.abs() < OFFSET_INT_SCALE + 1.0 { x } else { 0.0 };
    // SAFETY: x is finite and below 257 in magnitude, so it fits an i32.
    let of = unsafe { x.to_int_unchecked::<i32>() };
    let bits = p.to_bits() as i32;
    let moved = f32::from_bits((if p < 0.0 { bits.wrapping_sub(of) } else { bits.wrapping_add(of) }) as u32);
    if p.abs() < OFFSET_ORIGIN { p + OFFSET_FLOAT_SCALE * n } else { moved }
}

/// Three coordinates per lane.
#[derive(Clone, Copy)]
struct V3 {
    x: F,
    y: F,
    z: F,
}

impl Default for V3 {
    fn default() -> Self {
        Self { x: [0.0; LANES], y: [0.0; LANES], z: [0.0; LANES] }
    }
}

impl V3 {
    #[inline(always)]
    fn get(&self, k: usize) -> Vec3 {
        Vec3::new(self.x[k], self.y[k], self.z[k])
    }

    #[inline(always)]
    fn set(&mut self, k: usize, v: Vec3) {
        (self.x[k], self.y[k], self.z[k]) = (v.x, v.y, v.z);
    }
}

/// Lane `k` of the vertex values `at` interpolated at barycentrics (u, v): glam's
/// `(1 − u − v)·a + u·b + v·c`, as `SceneView::surface_at` computes it.
#[inline(always)]
fn interpolate(u: f32, v: f32, at: [&V3; 3], k: usize) -> (f32, f32, f32) {
    let b0 = 1.0 - u - v;
    let [a, b, c] = at;
    (
        b0 * a.x[k] + u * b.x[k] + v * c.x[k],
        b0 * a.y[k] + u * b.y[k] + v * c.y[k],
        b0 * a.z[k] + u * b.z[k] + v * c.z[k],
    )
}

/// glam's `Vec3::dot`, per lane.
#[inline(always)]
fn dot(a: &V3, b: &V3, k: usize) -> f32 {
    (a.x[k] * b.x[k]) + (a.y[k] * b.y[k]) + (a.z[k] * b.z[k])
}

/// glam's `Vec3::dot` of a vector with lane `k` of `b`.
#[inline(always)]
fn dot_with(a: (f32, f32, f32), b: &V3, k: usize) -> f32 {
    (a.0 * b.x[k]) + (a.1 * b.y[k]) + (a.2 * b.z[k])
}

/// `SampledSpectrum::is_black` of lane `k`.
#[inline(always)]
fn black<const N: usize>(s: &[F; N], k: usize) -> bool {
    // Without the early exit of `all`, which would keep the lanes' loops from vectorising.
    s.iter().fold(true, |b, v| b & (v[k] == 0.0))
}

/// The lanes where `m` is set, in order, into `out`; returns how many. Built without a
/// branch per lane, so that the loops that run one lane at a time on some of the lanes
/// (shadow rays, sample draws, light choices, ended paths) branch once per listed lane,
/// not once per lane on a flag that flips as often as the lanes' paths differ (those
/// branches were 2.8 M of a Cornell-box render's 7.2 M mispredictions in cachegrind's
/// branch simulation, docs/figures.md).
#[inline(always)]
fn lanes_where(m: &M, out: &mut [u8; LANES]) -> usize {
    let mut n = 0;
    for (k, &set) in m.iter().enumerate() {
        out[n] = k as u8;
        n += set as usize;
    }
    n
}

/// The paths in the lanes.
struct Lanes<const N: usize> {
    /// The block index of each lane's camera sample (`None`: the lane is free).
    slot: [Option<usize>; LANES],
    origin: V3,
    dir: V3,
    lambda: [F; N],
    /// The normalised D65 at each path's wavelengths (illuminants' factor, fixed per path).
    d65: [F; N],
    beta: [F; N],
    radiance: [F; N],
    prev_pdf: F,
    prev_specular: M,
    prev_p: V3,
    /// `PathState::prev_n`: the previous vertex's geometric normal, which a light tree's
    /// MIS weight reads (kept current by the lanes only where the scene's lights have a
    /// tree; a vertex shaded one lane at a time sets it regardless).
    prev_n: V3,
    bounce: [u32; LANES],
    /// `PathState::eta_scale`, changed only at surfaces shaded one lane at a time.
    eta_scale: F,
    /// `PathState::extension_left`, likewise.
    extension_left: [u32; LANES],
    /// `PathState::chain`.
    chain: [Chain; LANES],
}

/// [`super::PathTracer`]'s estimate for every sample of `block`, in lanes (see the module
/// documentation), with the widest vector instructions the machine has.
pub(crate) fn radiance_block<const N: usize, S: Sampler>(
    lanes: &LaneScene,
    view: &SceneView,
    settings: &PathSettings,
    block: &mut [CameraSample<N, S>],
    counters: &mut PathCounters,
) {
    #[cfg(target_arch = "x86_64")]
    match bvh::isa::active() {
        // SAFETY: `active` is at most what the CPU has (detected), and each level has the
        // features its function is compiled for.
        Isa::Avx512 => return unsafe { radiance_block_avx512(lanes, view, settings, block, counters) },
        // SAFETY: as above.
        Isa::Avx2 => return unsafe { radiance_block_avx2(lanes, view, settings, block, counters) },
        Isa::Baseline => {}
    }
    run(lanes, view, settings, block, counters);
}

/// [`run`] compiled for more vector instructions than the baseline: one function per
/// instruction set, chosen by [`radiance_block`] at run time. (No `fma`: Rust never
/// contracts a·b + c, so it would change nothing.)
macro_rules! compiled_for {
    ($($(#[$doc:meta])* $name:ident: $features:literal;)*) => {$(
        $(#[$doc])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        unsafe fn $name<const N: usize, S: Sampler>(
            lanes: &LaneScene,
            view: &SceneView,
            settings: &PathSettings,
            block: &mut [CameraSample<N, S>],
            counters: &mut PathCounters,
        ) {
            run(lanes, view, settings, block, counters);
        }
    )*};
}

compiled_for! {
    /// Sixteen lanes to a register, the width Mitsuba 3's LLVM back end uses on such machines.
    radiance_block_avx512: "avx2,avx512f,avx512vl,avx512bw,avx512dq";
    /// Eight lanes to a register.
    radiance_block_avx2: "avx2";
}

/// The lanes' loop: one bounce of every lane per turn.
#[inline(always)]
fn run<const N: usize, S: Sampler>(
    ls: &LaneScene,
    view: &SceneView,
    settings: &PathSettings,
    block: &mut [CameraSample<N, S>],
    counters: &mut PathCounters,
) {
    let scene = view.scene;
    let lights = view.lights;
    // Whether a light tree chooses the emitters by the shading point (`Lights::sample_at`).
    let tree = lights.has_tree();
    let rgb = block.first().is_some_and(|s| s.wl.is_rgb());
    let mut st = Lanes::<N> {
        slot: [None; LANES],
        origin: V3::default(),
        dir: V3::default(),
        lambda: [[0.0; LANES]; N],
        d65: [[0.0; LANES]; N],
        beta: [[0.0; LANES]; N],
        radiance: [[0.0; LANES]; N],
        prev_pdf: [0.0; LANES],
        prev_specular: [true; LANES],
        prev_p: V3::default(),
        prev_n: V3::default(),
        bounce: [0; LANES],
        eta_scale: [1.0; LANES],
        extension_left: [0; LANES],
        chain: [Chain::No; LANES],
    };
    let mesh = scene.mesh();
    // Whether the shading normals are interpolated (`SceneView::surface_at`).
    let smooth = ls.normals && settings.shading_normals != ShadingNormals::Geometric;
    // Each turn's working arrays, made once (zeroing them per turn cost 2–3 %): every
    // value a live lane reads is written in its turn; the other lanes' stale values are
    // computed on and never used.
    let (mut bu, mut bv): (F, F) = ([0.0; LANES], [0.0; LANES]);
    let (mut v0, mut v1, mut v2) = (V3::default(), V3::default(), V3::default());
    let (mut n0, mut n1, mut n2) = (V3::default(), V3::default(), V3::default());
    let (mut t0, mut t1, mut t2) = (V3::default(), V3::default(), V3::default());
    let mut albedo = Gathered::default();
    let mut emission = Gathered::default();
    // The chance that light sampling picks the emitter hit: by power (the MIS weight's,
    // and whether light tracing samples it), and by a light tree from the previous vertex
    // (the MIS weight's where there is a tree).
    let mut pmf: F = [0.0; LANES];
    let mut tree_pmf: F = [0.0; LANES];
    let (mut p, mut ng, mut wo) = (V3::default(), V3::default(), V3::default());
    let mut area: F = [0.0; LANES];
    // ω_o · n_g: which side the path arrived on, the emitter's cosine, the leak test's.
    let mut cos_o: F = [0.0; LANES];
    let (mut nf, mut fs, mut ft) = (V3::default(), V3::default(), V3::default());
    let mut wol = V3::default();
    let (mut lp, mut ln) = (V3::default(), V3::default());
    // The chosen light triangles' corners.
    let (mut lv0, mut lv1, mut lv2) = (V3::default(), V3::default(), V3::default());
    let mut lpdf: F = [0.0; LANES];
    let mut light_colour = Gathered::default();
    // The chosen punctual lights (by index in the scene) and their samples' points (a
    // position, or the direction towards a directional light), where `ldelta` says a
    // lane has one.
    let mut lpunctual = [0u32; LANES];
    let mut lpoint = V3::default();
    let mut weight: F = [0.0; LANES];
    let mut origin = V3::default();
    // The direction samples, one array per coordinate (interleaved pairs kept the loop
    // that uses them scalar).
    let (mut ux, mut uy): (F, F) = ([0.0; LANES], [0.0; LANES]);
    let mut draws = Draws::new();
    // Lanes listed by `lanes_where`.
    let mut list = [0u8; LANES];
    let mut next = 0;
    // Ends lane k's path: its estimate goes to its camera sample, the lane is free.
    let finish = |st: &mut Lanes<N>, block: &mut [CameraSample<N, S>], k: usize| {
        if let Some(b) = st.slot[k].take() {
            block[b].radiance = SampledSpectrum(std::array::from_fn(|i| st.radiance[i][k]));
        }
    };
    loop {
        // Free lanes take the block's next camera samples.
        let mut fresh: M = [false; LANES];
        let free: M = std::array::from_fn(|k| st.slot[k].is_none());
        let n = lanes_where(&free, &mut list);
        for &k in &list[..n.min(block.len() - next)] {
            let k = k as usize;
            let s = &block[next];
            fresh[k] = true;
            st.slot[k] = Some(next);
            st.origin.set(k, s.ray.origin);
            st.dir.set(k, s.ray.dir);
            st.prev_p.set(k, s.ray.origin);
            st.prev_n.set(k, Vec3::ZERO);
            for i in 0..N {
                st.lambda[i][k] = s.wl.lambda[i];
                st.beta[i][k] = 1.0;
                st.radiance[i][k] = 0.0;
                // The new path's D65 at its wavelengths (zero in RGB mode), here for
                // the new paths alone: a pass over all the lanes with gathers, every turn,
                // was 3 % slower (Cornell box and bunny, one thread, docs/figures.md).
                st.d65[i][k] = if rgb { 0.0 } else { d65_normalised(s.wl.lambda[i]) };
            }
            st.prev_pdf[k] = 0.0;
            st.prev_specular[k] = true;
            st.bounce[k] = 0;
            st.chain[k] = Chain::No;
            st.eta_scale[k] = 1.0;
            st.extension_left[k] = settings.specular_extension;
            next += 1;
        }
        if st.slot.iter().all(Option::is_none) {
            break;
        }

        // The closest hits, one query per path; a path that leaves the scene ends (no
        // environment). A hit on a surface the lanes do not shade is shaded there and then,
        // one lane at a time, by the general loop's code; the lanes shade the others
        // (`live`). Lanes without such a hit carry zeros, never used.
        let mut live: M = [false; LANES];
        let mut emissive: M = [false; LANES];
        for k in 0..LANES {
            let Some(b) = st.slot[k] else { continue };
            counters.rays += 1;
            let ray = if st.bounce[k] == 0 { block[b].ray } else { Ray::new(st.origin.get(k), st.dir.get(k)) };
            let Some(hit) = closest_hit(view, &ray) else {
                finish(&mut st, block, k);
                continue;
            };
            let (u, v) = (hit.u, hit.v);
            let m = scene.material_ids[hit.prim as usize] as usize;
            let Some(a) = &ls.albedo[m] else {
                let hit = SceneHit { prim: hit.prim, t: hit.t, surface: HitSurface::Triangle { u, v } };
                if !vertex_in_one_lane(&mut st, k, view, settings, &hit, ray.dir, &mut block[b], counters) {
                    finish(&mut st, block, k);
                }
                continue;
            };
            live[k] = true;
            (bu[k], bv[k]) = (u, v);
            let tri = mesh.triangles[hit.prim as usize];
            v0.set(k, Vec3::from_array(mesh.positions[tri[0] as usize]));
            v1.set(k, Vec3::from_array(mesh.positions[tri[1] as usize]));
            v2.set(k, Vec3::from_array(mesh.positions[tri[2] as usize]));
            if smooth {
                n0.set(k, Vec3::from_array(mesh.normals[tri[0] as usize]));
                n1.set(k, Vec3::from_array(mesh.normals[tri[1] as usize]));
                n2.set(k, Vec3::from_array(mesh.normals[tri[2] as usize]));
            }
            if ls.tangents {
                t0.set(k, Vec3::from_array(mesh.tangents[tri[0] as usize]));
                t1.set(k, Vec3::from_array(mesh.tangents[tri[1] as usize]));
                t2.set(k, Vec3::from_array(mesh.tangents[tri[2] as usize]));
            }
            albedo.set(k, a);
            if let Some(e) = &ls.emission[m] {
                emissive[k] = true;
                emission.set(k, e);
                pmf[k] = lights.prim_pmf(hit.prim);
                if tree && !st.prev_specular[k] {
                    tree_pmf[k] = lights.prim_pmf_at(hit.prim, st.prev_p.get(k), st.prev_n.get(k));
                }
            }
        }

        // The surface at the hits (`SceneView::surface_at`), the emission the paths see
        // with its MIS weight, and the shading frame.
        for k in 0..LANES {
            (p.x[k], p.y[k], p.z[k]) = interpolate(bu[k], bv[k], [&v0, &v1, &v2], k);
            let e1 = (v1.x[k] - v0.x[k], v1.y[k] - v0.y[k], v1.z[k] - v0.z[k]);
            let e2 = (v2.x[k] - v0.x[k], v2.y[k] - v0.y[k], v2.z[k] - v0.z[k]);
            let c = (e1.1 * e2.2 - e2.1 * e1.2, e1.2 * e2.0 - e2.2 * e1.0, e1.0 * e2.1 - e2.0 * e1.1);
            let a = 0.5 * ((c.0 * c.0) + (c.1 * c.1) + (c.2 * c.2)).sqrt();
            area[k] = a;
            let twice = 2.0 * a;
            (ng.x[k], ng.y[k], ng.z[k]) = (c.0 / twice, c.1 / twice, c.2 / twice);
            (wo.x[k], wo.y[k], wo.z[k]) = (-st.dir.x[k], -st.dir.y[k], -st.dir.z[k]);
            cos_o[k] = dot(&wo, &ng, k);
        }
        // The shading normal: interpolated, normalised and turned to n_g's side where it
        // is long enough, n_g otherwise.
        let mut ns = ng;
        if smooth {
            for k in 0..LANES {
                let n = interpolate(bu[k], bv[k], [&n0, &n1, &n2], k);
                let len2 = (n.0 * n.0) + (n.1 * n.1) + (n.2 * n.2);
                let r = 1.0 / len2.sqrt();
                let n = (n.0 * r, n.1 * r, n.2 * r);
                let n = if dot_with(n, &ng, k) < 0.0 { (-n.0, -n.1, -n.2) } else { n };
                let long = len2 > 1e-12;
                ns.x[k] = if long { n.0 } else { ng.x[k] };
                ns.y[k] = if long { n.1 } else { ng.y[k] };
                ns.z[k] = if long { n.2 } else { ng.z[k] };
            }
        }
        if emissive.iter().any(|&e| e) {
            let le = emission.eval(&st.lambda, &st.d65, rgb);
            for k in 0..LANES {
                let w = if st.prev_specular[k] {
                    1.0
                } else {
                    let d = (p.x[k] - st.prev_p.x[k], p.y[k] - st.prev_p.y[k], p.z[k] - st.prev_p.z[k]);
                    let dist2 = (d.0 * d.0) + (d.1 * d.1) + (d.2 * d.2);
                    let chance = if tree { tree_pmf[k] } else { pmf[k] };
                    let light_pdf = chance * dist2 / (cos_o[k] * area[k]);
                    power_heuristic(st.prev_pdf[k], light_pdf)
                };
                // As `path_vertex`: light that light tracing finds instead is left out.
                let left = settings.leave_caustics && st.chain[k] == Chain::Caustic && pmf[k] > 0.0;
                let seen = live[k] && cos_o[k] > 0.0 && emissive[k] && !left;
                for i in 0..N {
                    let add = st.beta[i][k] * le[i][k] * w;
                    st.radiance[i][k] = if seen { st.radiance[i][k] + add } else { st.radiance[i][k] };
                }
            }
        }
        if settings.max_depth > 0 {
            // A Lambertian surface is not specular: no extension past the limit.
            for k in 0..LANES {
                if live[k] && st.bounce[k] >= settings.max_depth {
                    live[k] = false;
                    finish(&mut st, block, k);
                }
            }
        }

        // The normals the BSDF sees (`shading_normals`, two-sided) and its frame
        // (`Frame::from_normal_tangent`), ω_o in it, and the albedo.
        let face_forward = settings.shading_normals == ShadingNormals::FaceForward;
        for k in 0..LANES {
            let side = if cos_o[k] >= 0.0 { 1.0 } else { -1.0 };
            let a = side * dot(&wo, &ns, k);
            let s = (MIN_SHADING_COSINE - a) * side;
            let bent = (ns.x[k] + s * wo.x[k], ns.y[k] + s * wo.y[k], ns.z[k] + s * wo.z[k]);
            let rcp = 1.0 / ((bent.0 * bent.0) + (bent.1 * bent.1) + (bent.2 * bent.2)).sqrt();
            let ok = rcp.is_finite() && rcp > 0.0;
            let adapted = if ok { (bent.0 * rcp, bent.1 * rcp, bent.2 * rcp) } else { (ng.x[k], ng.y[k], ng.z[k]) };
            let keep = face_forward || a >= MIN_SHADING_COSINE;
            let n = if keep { (ns.x[k], ns.y[k], ns.z[k]) } else { adapted };
            // Two-sided: the side the path arrived on is the front.
            let n = if cos_o[k] > 0.0 { n } else { (-n.0, -n.1, -n.2) };
            (nf.x[k], nf.y[k], nf.z[k]) = n;
            let sign = 1.0f32.copysign(n.2);
            let a = -1.0 / (sign + n.2);
            let b = n.0 * n.1 * a;
            (fs.x[k], fs.y[k], fs.z[k]) = (1.0 + sign * n.0 * n.0 * a, sign * b, -sign * n.0);
            (ft.x[k], ft.y[k], ft.z[k]) = (b, sign + n.1 * n.1 * a, -n.1);
        }
        if ls.tangents {
            // `Frame::from_normal_tangent`: the interpolated tangent made orthogonal to the
            // normal (Gram–Schmidt), where it is not (nearly) parallel to it.
            for k in 0..LANES {
                let t = interpolate(bu[k], bv[k], [&t0, &t1, &t2], k);
                let n = (nf.x[k], nf.y[k], nf.z[k]);
                let d = (n.0 * t.0) + (n.1 * t.1) + (n.2 * t.2);
                let s = (t.0 - n.0 * d, t.1 - n.1 * d, t.2 - n.2 * d);
                let len2 = (s.0 * s.0) + (s.1 * s.1) + (s.2 * s.2);
                let parallel = len2.is_nan() || len2 <= 1e-8 * ((t.0 * t.0) + (t.1 * t.1) + (t.2 * t.2));
                let len = len2.sqrt();
                let s = (s.0 / len, s.1 / len, s.2 / len);
                let t = (n.1 * s.2 - s.1 * n.2, n.2 * s.0 - s.2 * n.0, n.0 * s.1 - s.0 * n.1);
                fs.x[k] = if parallel { fs.x[k] } else { s.0 };
                fs.y[k] = if parallel { fs.y[k] } else { s.1 };
                fs.z[k] = if parallel { fs.z[k] } else { s.2 };
                ft.x[k] = if parallel { ft.x[k] } else { t.0 };
                ft.y[k] = if parallel { ft.y[k] } else { t.1 };
                ft.z[k] = if parallel { ft.z[k] } else { t.2 };
            }
        }
        for k in 0..LANES {
            (wol.x[k], wol.y[k], wol.z[k]) = (dot(&wo, &fs, k), dot(&wo, &ft, k), dot(&wo, &nf, k));
        }
        // f = R/π (`Lambert::eval` on the same hemisphere, and its sample's value).
        let mut fr = albedo.eval(&st.lambda, &st.d65, rgb);
        for v in fr.iter_mut().flatten() {
            *v *= FRAC_1_PI;
        }

        // Next-event estimation: the light samples (one query each into the lights'
        // distribution), then their geometry, MIS weight and BSDF across the lanes.
        draws.draw(2, &st, &live, block, &mut ux, &mut uy);
        // `Lights::sample_at` in two steps: the choice of a light (by power, or by the light
        // tree for the hit point) and its data, one lane at a time, then the points across
        // the lanes. A lane scene's lights are triangles and punctual lights (no
        // environment, shapes or sun disks); a lane without a light keeps `lemissive` and
        // `ldelta` false and its stale values are never used. A punctual light's lane
        // (`ldelta`) is left out of the triangles' vector loop and made after it.
        let mut lemissive: M = [false; LANES];
        let (mut ldelta, mut linfinite): (M, M) = ([false; LANES], [false; LANES]);
        if !lights.is_empty() {
            let n = lanes_where(&live, &mut list);
            for &k in &list[..n] {
                let k = k as usize;
                let Some((i, x, pdf)) = lights.choose_at(ux[k], p.get(k), ng.get(k)) else { continue };
                let Some(t) = lights.triangle_light(i) else {
                    // A punctual light: `Lights::sample_entry`'s own sample (its position
                    // or direction, and the choice's probability).
                    if let Some(s) = lights.punctual_entry(scene, i, Vec2::new(x, uy[k]), pdf)
                        && let LightSource::Punctual(index) = s.source
                    {
                        ldelta[k] = true;
                        lpunctual[k] = index;
                        lpdf[k] = s.pdf;
                        lpoint.set(k, s.point);
                        light_colour.set(k, &ls.punctual[index as usize]);
                    }
                    continue;
                };
                ux[k] = x;
                lv0.set(k, t.vertices[0]);
                lv1.set(k, t.vertices[1]);
                lv2.set(k, t.vertices[2]);
                ln.set(k, t.normal);
                lpdf[k] = pdf.unwrap_or(t.pdf);
                if let Some(e) = &ls.emission[scene.material_ids[t.prim as usize] as usize] {
                    lemissive[k] = true;
                    light_colour.set(k, e);
                }
            }
        }
        for k in 0..LANES {
            let (b0, b1) = uniform_triangle(Vec2::new(ux[k], uy[k]));
            lp.x[k] = on_triangle(b0, b1, [lv0.x[k], lv1.x[k], lv2.x[k]]);
            lp.y[k] = on_triangle(b0, b1, [lv0.y[k], lv1.y[k], lv2.y[k]]);
            lp.z[k] = on_triangle(b0, b1, [lv0.z[k], lv1.z[k], lv2.z[k]]);
        }
        let mut lle = light_colour.eval(&st.lambda, &st.d65, rgb);
        let mut shadow: M = [false; LANES];
        for k in 0..LANES {
            let d = (lp.x[k] - p.x[k], lp.y[k] - p.y[k], lp.z[k] - p.z[k]);
            let dist2 = (d.0 * d.0) + (d.1 * d.1) + (d.2 * d.2);
            let dist = dist2.sqrt();
            let wi = (d.0 / dist, d.1 / dist, d.2 / dist);
            let cos_l = -dot_with(wi, &ln, k);
            let emits = lemissive[k] && cos_l > 0.0;
            let light_pdf = if emits { lpdf[k] * dist2 / cos_l } else { 0.0 };
            let le_black = !emits || black(&lle, k);
            let wil = (dot_with(wi, &fs, k), dot_with(wi, &ft, k), dot_with(wi, &nf, k));
            // On ω_o's side of n_g (`light_contribution` flips n_g to that side first, which
            // negates both factors: the same product).
            let cos_i = dot_with(wi, &ng, k);
            let same_side = cos_i * cos_o[k] > 0.0;
            let same_hemisphere = wol.z[k] * wil.2 > 0.0;
            let f_black = !same_hemisphere || black(&fr, k);
            shadow[k] = live[k] && lemissive[k] && light_pdf > 0.0 && !le_black && same_side && !f_black;
            let pdf = if same_hemisphere { wil.2.abs().max(0.0) * FRAC_1_PI } else { 0.0 };
            let w = power_heuristic(light_pdf, pdf);
            weight[k] = wil.2.abs() * w / light_pdf;
            let s = if cos_i > 0.0 { 1.0 } else { -1.0 };
            origin.x[k] = offset_coordinate(p.x[k], s * ng.x[k]);
            origin.y[k] = offset_coordinate(p.y[k], s * ng.y[k]);
            origin.z[k] = offset_coordinate(p.z[k], s * ng.z[k]);
        }
        if !ls.punctual.is_empty() {
            let n = lanes_where(&ldelta, &mut list);
            for &k in &list[..n] {
                let k = k as usize;
                let light = &scene.punctual_lights[lpunctual[k] as usize];
                let frame = [&fs, &ft, &nf];
                let wo = (wol.z[k], cos_o[k]);
                let Some(e) =
                    delta_light_in_one_lane(light, lpoint.get(k), k, p.get(k), &mut lle, &fr, frame, &ng, wo, lpdf[k])
                else {
                    continue; // a point light at the shading point: no shadow ray
                };
                (shadow[k], weight[k], linfinite[k]) = (e.shadow_ray, e.weight, e.at_infinity);
                origin.set(k, e.origin);
                lp.set(k, e.point);
            }
        }
        let n = lanes_where(&shadow, &mut list);
        counters.rays += n as u64;
        for &k in &list[..n] {
            let k = k as usize;
            let o = origin.get(k);
            let ray =
                if linfinite[k] { Ray::new(o, lp.get(k)) } else { Ray::segment(o, lp.get(k) - o, 0.0, SHADOW_T_MAX) };
            shadow[k] = !occluded(view, &ray, !linfinite[k]);
        }
        for k in 0..LANES {
            for i in 0..N {
                let add = st.beta[i][k] * fr[i][k] * lle[i][k] * weight[k];
                st.radiance[i][k] = if shadow[k] { st.radiance[i][k] + add } else { st.radiance[i][k] };
            }
        }

        // The next direction: cosine-weighted on ω_o's side (`Lambert::sample`).
        let n = lanes_where(&live, &mut list);
        for &k in &list[..n] {
            if let Some(b) = st.slot[k as usize] {
                let _ = block[b].sampler.next_1d(); // the lobe choice, which a Lambertian BSDF ignores
            }
        }
        draws.draw(2, &st, &live, block, &mut ux, &mut uy);
        // The direction and whether the path takes it, the next origins, then the path's
        // state: three loops, each of which vectorises (as one, the loop stayed scalar).
        // The state's updates are `select_unpredictable`: written as `if`, the compiler
        // turned each select of two loads into a load through a selected pointer and the
        // loop into scalar code with a branch per lane (5 % of a Cornell-box render's
        // instructions).
        let mut go: M = [false; LANES];
        let (mut pdf, mut k_beta, mut side): (F, F, F) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        let mut wi = V3::default();
        for k in 0..LANES {
            let (ox, oy) = (2.0 * ux[k] - 1.0, 2.0 * uy[k] - 1.0);
            let x_major = ox.abs() > oy.abs();
            let (r, minor) = if x_major { (ox, oy) } else { (oy, ox) };
            let (s, c) = sin_cos_quarter(FRAC_PI_4 * (minor / r));
            let (cos_t, sin_t) = if x_major { (c, s) } else { (s, c) };
            let centre = (ox == 0.0) & (oy == 0.0);
            let (dx, dy) = if centre { (0.0, 0.0) } else { (r * cos_t, r * sin_t) };
            let z = (1.0 - ((dx * dx) + (dy * dy))).max(0.0).sqrt();
            let z = if wol.z[k] < 0.0 { -z } else { z };
            pdf[k] = z.abs().max(0.0) * FRAC_1_PI;
            wi.x[k] = fs.x[k] * dx + ft.x[k] * dy + nf.x[k] * z;
            wi.y[k] = fs.y[k] * dx + ft.y[k] * dy + nf.y[k] * z;
            wi.z[k] = fs.z[k] * dx + ft.z[k] * dy + nf.z[k] * z;
            let cos_ng = dot(&wi, &ng, k);
            let crosses = cos_ng * cos_o[k] <= 0.0;
            go[k] = live[k] & (wol.z[k] != 0.0) & (pdf[k] > 0.0) & !black(&fr, k) & !crosses;
            k_beta[k] = z.abs() / pdf[k];
            side[k] = if cos_ng > 0.0 { 1.0 } else { -1.0 };
        }
        for k in 0..LANES {
            let s = side[k];
            origin.x[k] = offset_coordinate(p.x[k], s * ng.x[k]);
            origin.y[k] = offset_coordinate(p.y[k], s * ng.y[k]);
            origin.z[k] = offset_coordinate(p.z[k], s * ng.z[k]);
        }
        // `PathState::chain` where the caustics are left to light tracing (else unused).
        if settings.leave_caustics {
            for k in 0..LANES {
                st.chain[k] = if go[k] { st.chain[k].next(st.bounce[k], false) } else { st.chain[k] };
            }
        }
        for k in 0..LANES {
            let g = go[k];
            for i in 0..N {
                let b = st.beta[i][k] * (fr[i][k] * k_beta[k]);
                st.beta[i][k] = select_unpredictable(g, b, st.beta[i][k]);
            }
            st.prev_pdf[k] = select_unpredictable(g, pdf[k], st.prev_pdf[k]);
            st.prev_specular[k] &= !g;
            st.prev_p.x[k] = select_unpredictable(g, p.x[k], st.prev_p.x[k]);
            st.prev_p.y[k] = select_unpredictable(g, p.y[k], st.prev_p.y[k]);
            st.prev_p.z[k] = select_unpredictable(g, p.z[k], st.prev_p.z[k]);
            st.origin.x[k] = select_unpredictable(g, origin.x[k], st.origin.x[k]);
            st.origin.y[k] = select_unpredictable(g, origin.y[k], st.origin.y[k]);
            st.origin.z[k] = select_unpredictable(g, origin.z[k], st.origin.z[k]);
            st.dir.x[k] = select_unpredictable(g, wi.x[k], st.dir.x[k]);
            st.dir.y[k] = select_unpredictable(g, wi.y[k], st.dir.y[k]);
            st.dir.z[k] = select_unpredictable(g, wi.z[k], st.dir.z[k]);
            st.bounce[k] += g as u32;
        }
        if tree {
            for k in 0..LANES {
                let g = go[k];
                st.prev_n.x[k] = select_unpredictable(g, ng.x[k], st.prev_n.x[k]);
                st.prev_n.y[k] = select_unpredictable(g, ng.y[k], st.prev_n.y[k]);
                st.prev_n.z[k] = select_unpredictable(g, ng.z[k], st.prev_n.z[k]);
            }
        }

        // Russian roulette (`survives_roulette`): the sample values first.
        let mut roulette: M = [false; LANES];
        for k in 0..LANES {
            roulette[k] = live[k] && go[k] && st.bounce[k] >= settings.rr_depth;
        }
        draws.draw(1, &st, &roulette, block, &mut ux, &mut uy);
        // Then across the lanes: which paths end (not taken, stopped by the roulette, or
        // left without throughput) and the survivors' throughput; the ended paths after.
        let mut ends: M = [false; LANES];
        for k in 0..LANES {
            let max = (0..N).map(|i| st.beta[i][k]).fold(f32::NEG_INFINITY, f32::max);
            let q = (1.0 - max * st.eta_scale[k] * settings.rr_scale).max(RR_MIN_TERMINATION);
            let stopped = roulette[k] & (ux[k] < q);
            let survives = roulette[k] & !stopped;
            for i in 0..N {
                st.beta[i][k] = select_unpredictable(survives, st.beta[i][k] / (1.0 - q), st.beta[i][k]);
            }
            ends[k] = live[k] & (!go[k] | stopped | black(&st.beta, k));
        }
        let n = lanes_where(&ends, &mut list);
        for &k in &list[..n] {
            finish(&mut st, block, k as usize);
        }
    }
}

/// The lanes' sample draws: the Sobol draws' parts, computed across the lanes, and the
/// points samplers drew themselves (lane, point), kept from turn to turn.
struct Draws {
    sobol: SobolLanes<LANES>,
    drawn: Vec<(usize, Vec2)>,
    /// The lanes that draw, listed by [`lanes_where`].
    list: [u8; LANES],
}

impl Draws {
    fn new() -> Self {
        Self { sobol: SobolLanes::default(), drawn: Vec::with_capacity(LANES), list: [0; LANES] }
    }

    /// The next sample value (`dims` 1, in `ux`) or 2-D point (`dims` 2, in `ux`, `uy`)
    /// of each lane where `which` is set (the other lanes get values never used): drawn
    /// from its sample's sampler in the order the general loop draws it, the scrambled
    /// Sobol points computed across the lanes ([`SobolLanes::values_2d`]) from the parts
    /// the samplers hand out, the points a sampler drew itself put in after.
    #[inline(always)]
    fn draw<const N: usize, S: Sampler>(
        &mut self,
        dims: u32,
        st: &Lanes<N>,
        which: &M,
        block: &mut [CameraSample<N, S>],
        ux: &mut F,
        uy: &mut F,
    ) {
        self.drawn.clear();
        let mut any_sobol = false;
        let n = lanes_where(which, &mut self.list);
        for &k in &self.list[..n] {
            let k = k as usize;
            let Some(b) = st.slot[k] else { continue };
            let sampler = &mut block[b].sampler;
            match if dims == 1 { sampler.lane_draw_1d() } else { sampler.lane_draw_2d() } {
                LaneDraw::Value(u) => self.drawn.push((k, u)),
                LaneDraw::Sobol(d) => {
                    self.sobol.set(k, &d);
                    any_sobol = true;
                }
            }
        }
        // (Independent samplers hand out points only: nothing to compute.)
        if any_sobol {
            if dims == 1 {
                self.sobol.values_1d(ux);
            } else {
                self.sobol.values_2d(ux, uy);
            }
        }
        for &(k, u) in &self.drawn {
            (ux[k], uy[k]) = (u.x, u.y);
        }
    }
}

/// `view.intersect` in a scene of triangles alone (no shapes, no instances: the lanes'
/// scenes): straight from the triangles' BVH where no material has cut-outs. The scene
/// query's dispatch and its scene-hit assembly (piecewise stores, then a 16-byte reload
/// that stalled store forwarding) were 4.5 % of a one-thread Cornell-box profile.
#[inline(always)]
fn closest_hit(view: &SceneView, ray: &Ray) -> Option<bvh::Hit> {
    if !view.cutouts {
        return view.geometry.triangles.intersect(ray);
    }
    let hit = view.intersect(ray)?;
    let HitSurface::Triangle { u, v } = hit.surface else { unreachable!("a scene of triangles only") };
    Some(bvh::Hit { prim: hit.prim, t: hit.t, u, v })
}

/// `view.occluded` in the lanes' scenes, as [`closest_hit`]; `inside`: the ray is a
/// segment between two points of the scene ([`crate::geometry::Occluders`]).
#[inline(always)]
fn occluded(view: &SceneView, ray: &Ray, inside: bool) -> bool {
    if view.cutouts {
        return view.occluded(ray);
    }
    if inside { view.geometry.triangles_occlude_inside(ray) } else { view.geometry.triangles.occluded(ray) }
}

/// One lane's next-event estimate towards a punctual light ([`delta_light_in_one_lane`]).
struct DeltaEstimate {
    /// Whether the light can contribute, so that a shadow ray goes.
    shadow_ray: bool,
    /// The estimate's |cos θᵢ| / pdf (no MIS weight).
    weight: f32,
    /// The shadow ray's origin.
    origin: Vec3,
    /// The light's position, or for a directional light the direction towards it.
    point: Vec3,
    /// Whether the light is at infinity (a directional light: an unbounded shadow ray).
    at_infinity: bool,
}

/// Next-event estimation towards a punctual light sampled at `point` in lane `k`, as `light_contribution`'s
/// delta case: `lle`'s lane scaled by the light's falloff/d² (or a directional light's
/// factor), and the estimate; `None` for a point light at the shading point. A delta light
/// takes no MIS weight: no BSDF sample can find it. `wo` is (ω_o's z in the shading frame,
/// ω_o · n_g).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn delta_light_in_one_lane<const N: usize>(
    light: &PunctualLight,
    point: Vec3,
    k: usize,
    p: Vec3,
    lle: &mut [F; N],
    fr: &[F; N],
    [fs, ft, nf]: [&V3; 3],
    ng: &V3,
    (wo_z, cos_o): (f32, f32),
    light_pdf: f32,
) -> Option<DeltaEstimate> {
    let (wi, dist, scale) = punctual_geometry(light, point, p)?;
    for v in lle.iter_mut() {
        v[k] *= scale;
    }
    let wi = (wi.x, wi.y, wi.z);
    let wil = (dot_with(wi, fs, k), dot_with(wi, ft, k), dot_with(wi, nf, k));
    let cos_i = dot_with(wi, ng, k);
    let same_side = cos_i * cos_o > 0.0;
    let same_hemisphere = wo_z * wil.2 > 0.0;
    let s = if cos_i > 0.0 { 1.0 } else { -1.0 };
    let origin = Vec3::new(
        offset_coordinate(p.x, s * ng.x[k]),
        offset_coordinate(p.y, s * ng.y[k]),
        offset_coordinate(p.z, s * ng.z[k]),
    );
    // (Written so that a NaN pdf counts as unusable, as in `light_contribution`.)
    let shadow_ray = light_pdf > 0.0 && !black(lle, k) && same_side && same_hemisphere && !black(fr, k);
    Some(DeltaEstimate { shadow_ray, weight: wil.2.abs() / light_pdf, origin, point, at_infinity: !dist.is_finite() })
}

/// Lane `k`'s vertex at `hit` (of a ray along `dir`) on a surface the lanes do not shade,
/// by the general loop's [`path_vertex`]: the lane's state goes in and comes out with the
/// next ray; false where the path ends there. Out of line: it is the rarer case, and
/// inlined it would crowd the lanes' loop.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn vertex_in_one_lane<const N: usize, S: Sampler>(
    st: &mut Lanes<N>,
    k: usize,
    view: &SceneView,
    settings: &PathSettings,
    hit: &SceneHit,
    dir: Vec3,
    sample: &mut CameraSample<N, S>,
    counters: &mut PathCounters,
) -> bool {
    let mut path = PathState {
        l: SampledSpectrum(std::array::from_fn(|i| st.radiance[i][k])),
        beta: SampledSpectrum(std::array::from_fn(|i| st.beta[i][k])),
        prev_pdf: st.prev_pdf[k],
        prev_specular: st.prev_specular[k],
        prev_p: st.prev_p.get(k),
        prev_n: st.prev_n.get(k),
        bounce: st.bounce[k],
        eta_scale: st.eta_scale[k],
        extension_left: st.extension_left[k],
        // No diffuse-depth limit and no absorbing media in the lanes' scenes.
        diffuse_bounces: 0,
        inside: None,
        chain: st.chain[k],
    };
    let next = path_vertex(view, hit, dir, &mut sample.wl, settings, &mut sample.sampler, counters, &mut path);
    for i in 0..N {
        st.radiance[i][k] = path.l.0[i];
        st.beta[i][k] = path.beta.0[i];
    }
    st.prev_pdf[k] = path.prev_pdf;
    st.prev_specular[k] = path.prev_specular;
    st.prev_p.set(k, path.prev_p);
    st.prev_n.set(k, path.prev_n);
    st.bounce[k] = path.bounce;
    st.eta_scale[k] = path.eta_scale;
    st.extension_left[k] = path.extension_left;
    st.chain[k] = path.chain;
    match next {
        Some(ray) => {
            st.origin.set(k, ray.origin);
            st.dir.set(k, ray.dir);
            true
        }
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Geometry, Occluders};
    use crate::lights::{LightSampler, Lights};
    use crate::material::Material;
    use crate::mesh::{quad, uv_sphere};
    use crate::render::SceneOptions;
    use crate::sampler::Pcg32;
    use crate::scene::Scene;
    use spectral::SampledWavelengths;

    /// A black Lambertian lamp that emits `c`.
    fn lamp(c: Colour) -> Material {
        Material::diffuse("lamp", Colour::constant(0.0)).unwrap().with_emission(c)
    }

    /// A room: coloured diffuse walls (RGB uplifts), a grey constant, a smooth diffuse
    /// sphere, two lamps (one a coloured uplift, one a constant) and what the lanes shade
    /// one lane at a time: a glass sphere, a mirror and a rough (Oren–Nayar) panel. Walls
    /// are seen edge-on, so that grazing hits and adapted normals occur.
    fn room() -> Scene {
        let mut scene = Scene::default();
        let wall = |rgb: [f32; 3]| Material::diffuse("wall", Colour::reflectance_rgb(rgb).unwrap()).unwrap();
        scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), wall([0.7, 0.7, 0.7]));
        scene.add(&quad(Vec3::new(-1.0, 1.0, 0.0), Vec3::X, 1.0), wall([0.6, 0.1, 0.1]));
        scene.add(&quad(Vec3::new(1.0, 1.0, 0.0), -Vec3::X, 1.0), wall([0.1, 0.6, 0.1]));
        scene.add(&quad(Vec3::new(0.0, 1.0, -1.0), Vec3::Z, 1.0), wall([0.2, 0.3, 0.8]));
        scene.add(&uv_sphere(Vec3::new(0.2, 0.4, 0.0), 0.4, 12, 24, false), wall([0.9, 0.8, 0.2]));
        scene.add(
            &uv_sphere(Vec3::new(-0.55, 0.3, 0.45), 0.25, 10, 20, false),
            Material::dielectric("glass", 1.5).unwrap(),
        );
        let mirror = Material::builtin("mirror", brdf::ModelId::Mirror, &[]).unwrap();
        scene.add(&quad(Vec3::new(0.99, 0.8, -0.4), -Vec3::X, 0.25), mirror);
        let rough = Material::builtin("rough", brdf::ModelId::OrenNayar, &[]).unwrap();
        scene.add(&quad(Vec3::new(0.4, 1.3, -0.99), Vec3::Z, 0.25), rough);
        scene.add(
            &quad(Vec3::new(0.0, 1.99, 0.0), -Vec3::Y, 0.3),
            lamp(Colour::illuminant_rgb([4.0, 3.0, 2.0]).unwrap()),
        );
        scene.add(&quad(Vec3::new(-0.6, 1.0, -0.99), Vec3::Z, 0.1), lamp(Colour::constant(2.0)));
        scene
    }

    /// Camera samples of a pinhole at (0, 1, 3) over the room, each with its own stream
    /// (`sampler(i)` for sample i).
    fn block<const N: usize, S: Sampler>(
        wl: impl Fn(f32) -> SampledWavelengths<N>,
        sampler: &impl Fn(u32) -> S,
    ) -> Vec<CameraSample<N, S>> {
        (0..600)
            .map(|i| {
                let mut sampler = sampler(i);
                let (u_wl, jitter) = sampler.camera(true);
                let target = Vec3::new(2.4 * jitter.x - 1.2, 2.2 * jitter.y - 0.1, 0.0);
                let origin = Vec3::new(0.0, 1.0, 3.0);
                let ray = Ray::new(origin, (target - origin).normalize());
                CameraSample { ray, wl: wl(u_wl), sampler, radiance: SampledSpectrum::zero() }
            })
            .collect()
    }

    /// Every sample's estimate from the general loop, from the lanes compiled for the
    /// baseline and (where the machine has them) for AVX2 and AVX-512, compared bit for bit.
    fn lanes_equal_the_general_loop<const N: usize>(
        scene: &Scene,
        wl: impl Fn(f32) -> SampledWavelengths<N>,
        settings: PathSettings,
    ) {
        lanes_equal_the_general_loop_with(scene, wl, settings, &|i| Pcg32::for_sample(7, i, 0), LightSampler::Power);
    }

    /// As `lanes_equal_the_general_loop`, every sample drawing from `sampler(i)`, the
    /// emitters chosen by `light_sampler`.
    fn lanes_equal_the_general_loop_with<const N: usize, S: Sampler>(
        scene: &Scene,
        wl: impl Fn(f32) -> SampledWavelengths<N>,
        settings: PathSettings,
        sampler: &impl Fn(u32) -> S,
        light_sampler: LightSampler,
    ) {
        let geometry = Geometry::build(scene, &SceneOptions::default()).unwrap();
        let lights = Lights::with_sampler(scene, light_sampler);
        assert_eq!(lights.has_tree(), light_sampler == LightSampler::Tree);
        let view = SceneView::new(scene, &geometry, &lights);
        let lanes = view.lane_scene(&settings).expect("a scene for the lanes");
        let mut general = block(&wl, sampler);
        let mut rays = PathCounters::default();
        for s in &mut general {
            s.radiance = super::super::path_radiance(&view, s.ray, &mut s.wl, &settings, &mut s.sampler, &mut rays);
        }
        assert!(general.iter().filter(|s| !s.radiance.is_black()).count() > 300, "the room is lit");
        let (mut b, mut c) = (block(&wl, sampler), PathCounters::default());
        run(lanes, &view, &settings, &mut b, &mut c);
        let mut variants = vec![("baseline", b, c)];
        #[cfg(target_arch = "x86_64")]
        if bvh::isa::detected() >= Isa::Avx2 {
            let (mut b, mut c) = (block(&wl, sampler), PathCounters::default());
            // SAFETY: the features were just detected.
            unsafe { radiance_block_avx2(lanes, &view, &settings, &mut b, &mut c) };
            variants.push(("avx2", b, c));
        }
        #[cfg(target_arch = "x86_64")]
        if bvh::isa::detected() >= Isa::Avx512 {
            let (mut b, mut c) = (block(&wl, sampler), PathCounters::default());
            // SAFETY: the features were just detected.
            unsafe { radiance_block_avx512(lanes, &view, &settings, &mut b, &mut c) };
            variants.push(("avx512", b, c));
        } else {
            eprintln!("(no AVX-512 on this machine: its build of the lanes is not compared)");
        }
        for (name, b, c) in &variants {
            assert_eq!(c.rays, rays.rays, "{name}: rays traced");
            for (i, (g, l)) in general.iter().zip(b).enumerate() {
                let (g, l) = (g.radiance.0.map(f32::to_bits), l.radiance.0.map(f32::to_bits));
                assert_eq!(g, l, "{name}: sample {i} ({settings:?})");
            }
        }
    }

    #[test]
    fn lanes_compute_the_general_loops_estimate_bit_for_bit() {
        let base = PathSettings { rr_depth: 2, ..Default::default() };
        let scene = room();
        assert!(!scene.normals.is_empty() && !scene.tangents.is_empty());
        lanes_equal_the_general_loop(&scene, SampledWavelengths::<4>::sample_hero, base);
        lanes_equal_the_general_loop(&scene, |_| SampledWavelengths::<3>::rgb(), base);
        lanes_equal_the_general_loop(&scene, |_| SampledWavelengths::<40>::fixed_bins(380.0, 10.0), base);
        // Past a depth limit only the specular surfaces (one lane at a time) go on.
        let limited = PathSettings { max_depth: 2, specular_extension: 3, ..base };
        lanes_equal_the_general_loop(&scene, SampledWavelengths::<4>::sample_hero, limited);
        for shading_normals in [ShadingNormals::FaceForward, ShadingNormals::Geometric] {
            let settings = PathSettings { shading_normals, ..base };
            lanes_equal_the_general_loop(&scene, SampledWavelengths::<4>::sample_hero, settings);
        }
        // Without tangents (the frame from the normal alone), and without normals.
        let mut plain = room();
        plain.tangents.clear();
        lanes_equal_the_general_loop(&plain, SampledWavelengths::<4>::sample_hero, base);
        plain.normals.clear();
        lanes_equal_the_general_loop(&plain, SampledWavelengths::<4>::sample_hero, base);
        // A see-through sphere (stochastic transparency): the scene's queries go through
        // the cut-outs' code, and the sphere is shaded one lane at a time.
        use crate::texture::{Alpha, AlphaMode, MaterialTextures};
        let mut cut = room();
        let alpha = Alpha { mode: AlphaMode::Blend, factor: 0.5, map: None };
        cut.materials[4] =
            cut.materials[4].clone().with_textures(MaterialTextures { alpha: Some(alpha), ..Default::default() });
        lanes_equal_the_general_loop(&cut, SampledWavelengths::<4>::sample_hero, base);
    }

    /// A small room whose walls shadow rays leave out (`Occluders`): the lanes and the
    /// general loop test the same triangles.
    #[test]
    fn lanes_leave_out_the_hulls_triangles_as_the_general_loop() {
        let scene = crate::geometry::tests::box_room();
        let geometry = Geometry::build(&scene, &SceneOptions::default()).unwrap();
        assert!(matches!(geometry.occluders, Occluders::Some(_)));
        let base = PathSettings { rr_depth: 2, ..Default::default() };
        lanes_equal_the_general_loop(&scene, SampledWavelengths::<4>::sample_hero, base);
        lanes_equal_the_general_loop(&scene, |_| SampledWavelengths::<3>::rgb(), base);
    }

    /// The Sobol samplers' points are computed across the lanes (`SobolLanes`), from
    /// draws that interleave 1-D values and 2-D points: the same bits as one at a time.
    #[test]
    fn lanes_draw_the_sobol_samplers_values_bit_for_bit() {
        use crate::sampler::{PaddedSobol, ZSobolLayout};
        let base = PathSettings { rr_depth: 2, ..Default::default() };
        let scene = room();
        let hero = SampledWavelengths::<4>::sample_hero;
        // 32×32 pixels at 16 spp (14 index bits), and 65,536² at 2 spp (33 bits: the
        // samplers hand out drawn points, the 32-bit form not being exact).
        for (size, spp) in [(32, 16), (65_536, 2)] {
            let layout = ZSobolLayout::new(size, size, spp, 5);
            let zsobol = |i: u32| layout.sampler(i % 32, (i / 32) % 32, (i / 1024) % spp);
            lanes_equal_the_general_loop_with(&scene, hero, base, &zsobol, LightSampler::Power);
        }
        let padded = |i: u32| PaddedSobol::new(i % 32, i / 32, i % 4, 4, 9);
        lanes_equal_the_general_loop_with(&scene, hero, base, &padded, LightSampler::Power);
        let rgb = |_| SampledWavelengths::<3>::rgb();
        lanes_equal_the_general_loop_with(&scene, rgb, base, &padded, LightSampler::Power);
    }

    /// With a light tree the lanes choose each path's light for its hit point and weigh
    /// the emitters their paths hit by the previous vertex's choice, as the general loop:
    /// the same bits, in a room of 15 lamps (two facing away from much of it, one on the
    /// glass sphere's side of the room, one a rough emitter that the general loop shades
    /// one lane at a time, with the normal the lanes hand it), through paths that pass the
    /// surfaces shaded one lane at a time.
    #[test]
    fn lanes_choose_lights_by_a_tree_bit_for_bit() {
        let base = PathSettings { rr_depth: 2, ..Default::default() };
        let mut scene = room();
        let rough = Material::builtin("rough lamp", brdf::ModelId::OrenNayar, &[]).unwrap();
        scene.add(&quad(Vec3::new(-0.99, 1.5, 0.3), Vec3::X, 0.2), rough.with_emission(Colour::constant(3.0)));
        for i in 0..12 {
            let (x, z) = (-0.75 + 0.3 * (i % 6) as f32, if i < 6 { -0.5 } else { 0.5 });
            let (at, facing) = if i % 5 == 4 { (1.0, Vec3::Y) } else { (1.98, -Vec3::Y) };
            let colour = Colour::illuminant_rgb([1.0 + 0.2 * i as f32, 1.0, 0.5]).unwrap();
            scene.add(&quad(Vec3::new(x, at, z), facing, 0.06), lamp(colour));
        }
        let hero = SampledWavelengths::<4>::sample_hero;
        let pcg = |i: u32| Pcg32::for_sample(7, i, 0);
        let layout = crate::sampler::ZSobolLayout::new(32, 32, 16, 5);
        let zsobol = |i: u32| layout.sampler(i % 32, (i / 32) % 32, (i / 1024) % 16);
        lanes_equal_the_general_loop_with(&scene, hero, base, &zsobol, LightSampler::Tree);
        let rgb = |_| SampledWavelengths::<3>::rgb();
        lanes_equal_the_general_loop_with(&scene, rgb, base, &pcg, LightSampler::Tree);
        lanes_equal_the_general_loop_with(&scene, hero, base, &pcg, LightSampler::Tree);
    }

    /// Point, spot and delta directional lights beside the room's lamps: the lanes make
    /// their next-event estimates one lane at a time, with the general loop's bits, whether
    /// the lights are chosen by power or by a light tree (which holds the point and spot
    /// lights, not the directional one). One point light sits on the floor (its samples
    /// there have no direction) and one spot shines away from most of the room.
    #[test]
    fn lanes_light_by_point_spot_and_directional_lights_bit_for_bit() {
        use crate::punctual::PunctualLight;
        let base = PathSettings { rr_depth: 2, ..Default::default() };
        let mut scene = room();
        scene.punctual_lights = vec![
            PunctualLight::point(Vec3::new(0.3, 1.6, 0.4), Colour::illuminant_rgb([1.0, 0.8, 0.4]).unwrap()),
            PunctualLight::point(Vec3::new(-0.5, 0.0, 0.2), Colour::constant(0.5)),
            PunctualLight::spot(
                Vec3::new(-0.6, 1.8, 0.6),
                Vec3::new(0.3, -1.0, -0.2).normalize(),
                Colour::constant(3.0),
                0.4,
                0.7,
            ),
            PunctualLight::spot(
                Vec3::new(0.6, 0.5, -0.6),
                Vec3::Y,
                Colour::illuminant_rgb([0.2, 0.5, 2.0]).unwrap(),
                0.6,
                1.2,
            ),
            PunctualLight::directional(
                Vec3::new(0.2, -1.0, -0.5).normalize(),
                Colour::illuminant_rgb([0.5, 0.5, 0.4]).unwrap(),
            ),
        ];
        let hero = SampledWavelengths::<4>::sample_hero;
        let pcg = |i: u32| Pcg32::for_sample(7, i, 0);
        let layout = crate::sampler::ZSobolLayout::new(32, 32, 16, 5);
        let zsobol = |i: u32| layout.sampler(i % 32, (i / 32) % 32, (i / 1024) % 16);
        for light_sampler in [LightSampler::Power, LightSampler::Tree] {
            lanes_equal_the_general_loop_with(&scene, hero, base, &pcg, light_sampler);
            lanes_equal_the_general_loop_with(&scene, hero, base, &zsobol, light_sampler);
            let rgb = |_| SampledWavelengths::<3>::rgb();
            lanes_equal_the_general_loop_with(&scene, rgb, base, &pcg, light_sampler);
        }
        // Punctual lights alone (no emissive triangle).
        for m in &mut scene.materials {
            m.emission = None;
        }
        lanes_equal_the_general_loop_with(&scene, hero, base, &pcg, LightSampler::Power);
        lanes_equal_the_general_loop_with(&scene, hero, base, &zsobol, LightSampler::Tree);
    }

    #[test]
    fn the_lanes_offset_equals_the_library_offset() {
        let mut rng = Pcg32::for_sample(3, 0, 0);
        for i in 0..200_000 {
            let scale = [1e-3, 0.03, 1.0, 30.0, 1e4][i % 5];
            let p = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5) * 2.0 * scale;
            let n = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5).normalize();
            // Unit normals, and ones rounded a little long (|256·n| just above 256).
            let n = if i % 7 == 0 { n * (1.0 + 4.0 * f32::EPSILON) } else { n };
            let want = shapes::offset::offset_ray_origin(p, n);
            let got = Vec3::new(offset_coordinate(p.x, n.x), offset_coordinate(p.y, n.y), offset_coordinate(p.z, n.z));
            assert_eq!(want.to_array().map(f32::to_bits), got.to_array().map(f32::to_bits), "p {p}, n {n}");
        }
        assert_eq!(
            offset_coordinate(1.0, f32::NAN).to_bits(),
            shapes::offset::offset_ray_origin(Vec3::ONE, Vec3::NAN).x.to_bits()
        );
    }

    #[test]
    fn only_scenes_of_triangles_with_diffuse_surfaces_run_in_lanes() {
        let runs = super::super::PathTracer::runs_in_lanes;
        let scene = room();
        let geometry = Geometry::build(&scene, &SceneOptions::default()).unwrap();
        let lights = Lights::new(&scene);
        let view = SceneView::new(&scene, &geometry, &lights);
        for shading_normals in [ShadingNormals::Adapted, ShadingNormals::FaceForward, ShadingNormals::Geometric] {
            assert!(runs(&view, &PathSettings { shading_normals, ..Default::default() }), "{shading_normals:?}");
        }
        // The emitters chosen by a light tree.
        let tree = Lights::with_sampler(&scene, LightSampler::Tree);
        assert!(runs(&SceneView::new(&scene, &geometry, &tree), &PathSettings::default()), "with a light tree");
        // A diffuse-depth limit, or the switch off.
        assert!(!runs(&view, &PathSettings { max_diffuse_depth: 2, ..Default::default() }));
        assert!(!runs(&view, &PathSettings { lanes: false, ..Default::default() }));
        // No surface for the lanes, a spectrum they do not evaluate, an environment,
        // a sun disk (which escaping rays see), dispersive glass, absorbing glass.
        for change in 0..6 {
            let mut other = room();
            match change {
                0 => {
                    for m in &mut other.materials {
                        let emission = m.emission.take();
                        *m = Material::builtin("mirror", brdf::ModelId::Mirror, &[]).unwrap();
                        m.emission = emission;
                    }
                }
                1 => {
                    let sun = Spectrum::Blackbody { kelvin: 5800.0, scale: 1.0 };
                    let lamp = other.materials.len() - 1;
                    other.materials[lamp].emission =
                        Some(Colour::from_spectrum(sun, spectral::spectrum::ColourRole::Illuminant));
                }
                2 => other.environment = Some(crate::scene::Environment::uniform(Colour::constant(0.1))),
                3 => other.punctual_lights.push(crate::punctual::PunctualLight::sun(
                    Vec3::new(0.0, -1.0, 0.2).normalize(),
                    Colour::constant(1.0),
                    0.1,
                )),
                _ => {
                    use brdf::params::ParamValue;
                    let param = if change == 4 {
                        ("dispersion", ParamValue::Name("bk7".into()))
                    } else {
                        ("absorption", ParamValue::Rgb([0.5, 0.2, 0.1]))
                    };
                    other.materials[0] = Material::builtin("glass", brdf::ModelId::Dielectric, &[param]).unwrap();
                }
            }
            let geometry = Geometry::build(&other, &SceneOptions::default()).unwrap();
            let lights = Lights::new(&other);
            let view = SceneView::new(&other, &geometry, &lights);
            assert!(!runs(&view, &PathSettings::default()), "change {change}");
        }
    }
}
