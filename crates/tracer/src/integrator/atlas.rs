//! Atlas-based one-bounce global illumination (the atlas thesis, §4): the scene's
//! triangles unwrapped into a texture atlas, a G-buffer of positions, normals and
//! reflected direct light per texel, and one diffuse bounce gathered per texel from
//! Hammersley points over the atlas, with or without visibility. The camera image is
//! direct light computed per pixel plus a lookup of the gathered light: the atlas does
//! not depend on the view, so a moving camera keeps it.

use super::{
    Interaction, Mis, PathCounters, PathSettings, SceneView, Shading, entered_medium, light_contribution, lobe_leaks,
    shading_normals,
};
use crate::integrator::Integrator;
use crate::lights::ONE_MINUS_EPSILON;
use crate::sampler::Sampler;
use crate::{Error, Result};
use brdf::{Bsdf, Frame};
use bvh::Ray;
use glam::{UVec2, Vec2, Vec3};
use rayon::prelude::*;
use shapes::offset::offset_ray_origin;
use spectral::{SampledSpectrum, SampledWavelengths};
use std::collections::HashMap;
use std::f32::consts::FRAC_1_PI;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How the lookup treats the texels around a chart (its gutter).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SeamFix {
    /// The gutter stays empty: bilinear lookups at a chart's border blend with it and
    /// darken the border (the seams of the atlas thesis).
    None,
    /// The gathered light is dilated into the gutter (each empty texel takes the mean of
    /// its filled neighbours, as many rounds as the gutter is wide), so lookups at a
    /// border see the chart's own values.
    #[default]
    Dilate,
}

impl SeamFix {
    /// The name the command line uses.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Dilate => "dilate",
        }
    }
}

/// How the atlas is built and gathered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasSettings {
    /// Texels per scene unit; 0 chooses the largest density whose charts fit
    /// `resolution` × `resolution` texels.
    pub density: f32,
    /// The atlas's side in texels when `density` is 0 (grown if its charts cannot fit).
    pub resolution: u32,
    /// Points gathered per texel for the indirect light (the thesis's N).
    pub samples: u32,
    /// Whether a shadow ray tests each gathered point (the thesis does not: light leaks
    /// through walls).
    pub visibility: bool,
    /// What the lookup does at chart borders.
    pub seams: SeamFix,
    /// Light samples per texel for its direct light (shadow rays, not a shadow map).
    pub direct_samples: u32,
    /// Seeds the per-texel rotations of the point sets.
    pub seed: u64,
}

impl Default for AtlasSettings {
    fn default() -> Self {
        Self {
            density: 0.0,
            resolution: 512,
            samples: 256,
            visibility: true,
            seams: SeamFix::Dilate,
            direct_samples: 16,
            seed: 0,
        }
    }
}

impl AtlasSettings {
    /// Rejects absurd values with a message naming the setting.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Setting(m));
        if !(self.density.is_finite() && self.density >= 0.0) {
            return bad(format!("atlas density {} must be a finite number ≥ 0 (0: from the resolution)", self.density));
        }
        if !(8..=16384).contains(&self.resolution) {
            return bad(format!("atlas resolution {} must be between 8 and 16384 texels", self.resolution));
        }
        if !(1..=1 << 20).contains(&self.samples) {
            return bad(format!("atlas samples {} must be between 1 and 2^20", self.samples));
        }
        if !(1..=4096).contains(&self.direct_samples) {
            return bad(format!("atlas direct samples {} must be between 1 and 4096", self.direct_samples));
        }
        Ok(())
    }
}

/// The least distance, in texels, the gather's form factor uses.
const MIN_DISTANCE_TEXELS: f32 = 2.0;

/// Empty texels between charts (each side): room for bilinear lookups and dilation.
pub const GUTTER: u32 = 2;

/// A planar chart: connected coplanar triangles, projected orthographically onto their
/// plane and placed in the atlas at a uniform scale.
#[derive(Clone, Copy, Debug)]
pub struct Chart {
    origin: Vec3,
    u: Vec3,
    v: Vec3,
    /// The projected triangles' lower corner, in scene units along (u, v).
    min: Vec2,
    /// Extent in scene units.
    size: Vec2,
    /// Its lower corner in the atlas (texels), gutter included.
    offset: UVec2,
}

impl Chart {
    /// Size in texels, gutter included.
    fn texels(&self, density: f32) -> UVec2 {
        // Clamped far below u32's range: pack() refuses atlases beyond 2²⁸ texels.
        (self.size * density).ceil().min(Vec2::splat(1_048_576.0)).as_uvec2().max(UVec2::ONE) + UVec2::splat(2 * GUTTER)
    }

    /// Continuous atlas coordinates (texel centres at i + ½) of a point on its plane.
    #[inline]
    fn atlas_point(&self, p: Vec3, density: f32) -> Vec2 {
        self.projection().atlas_point(p, density)
    }

    /// Where it maps points.
    #[inline]
    fn projection(&self) -> ChartProjection {
        let corner = self.offset.as_vec2() + Vec2::splat(GUTTER as f32);
        ChartProjection { origin: self.origin, u: self.u, v: self.v, min: self.min, corner }
    }
}

/// Where a chart maps a point ([`ChartProjection::atlas_point`]), also for a backend that
/// looks the atlas up itself (the GPU).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChartProjection {
    /// A point of the chart's plane.
    pub origin: Vec3,
    /// The plane's first axis.
    pub u: Vec3,
    /// Its second axis.
    pub v: Vec3,
    /// The projected triangles' lower corner, in scene units along (u, v).
    pub min: Vec2,
    /// The chart's first texel inside its gutter, in atlas texels.
    pub corner: Vec2,
}

impl ChartProjection {
    /// Continuous atlas coordinates (texel centres at i + ½) of a point on the chart's
    /// plane: `corner + ((p − origin)·(u, v) − min) · density`.
    #[inline]
    pub fn atlas_point(&self, p: Vec3, density: f32) -> Vec2 {
        let d = p - self.origin;
        let local = Vec2::new(d.dot(self.u), d.dot(self.v)) - self.min;
        self.corner + local * density
    }
}

/// What a texel of the G-buffer holds.
#[derive(Clone, Copy, Debug)]
struct Texel {
    /// The triangle it lies on (`u32::MAX`: empty).
    prim: u32,
    position: Vec3,
    /// Unit front-face normal.
    normal: Vec3,
}

const EMPTY: u32 = u32::MAX;

/// Times and sizes of an atlas build.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AtlasStats {
    /// Atlas width and height in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels per scene unit.
    pub density: f32,
    /// Charts.
    pub charts: usize,
    /// Texels on a triangle.
    pub texels_used: usize,
    /// Unwrapping, packing and rasterising the G-buffer.
    pub unwrap: Duration,
    /// Direct light per texel.
    pub direct: Duration,
    /// The gather of one bounce per texel (the thesis's table measures this).
    pub gather: Duration,
}

/// The atlas of a scene: charts, G-buffer, direct light and gathered irradiance.
pub struct Atlas {
    width: u32,
    height: u32,
    density: f32,
    charts: Vec<Chart>,
    /// Per triangle primitive (flat, then shapes — none —, then instanced): its chart.
    prim_chart: Vec<u32>,
    texels: Vec<Texel>,
    /// Light leaving each texel towards any direction after one reflection of direct
    /// light (linear sRGB radiance; the surface taken as diffuse).
    direct: Vec<[f32; 3]>,
    /// Irradiance from one diffuse bounce (linear sRGB), dilated into the gutter.
    irradiance: Vec<[f32; 3]>,
    seams: SeamFix,
    /// How it was built.
    pub stats: AtlasStats,
}

/// The i-th of n points of the 2-D Hammersley set, (i/n, Φ₂(i)) (atlas thesis §4.5).
#[inline]
pub fn hammersley(i: u32, n: u32) -> Vec2 {
    Vec2::new(i as f32 / n as f32, (i.reverse_bits() as f64 / 4_294_967_296.0) as f32)
}

/// A per-texel shift of a point set (Cranley–Patterson rotation), from a hash.
fn rotation(seed: u64, index: u64) -> Vec2 {
    let mut r = rng::Pcg32::new(seed, index);
    Vec2::new(r.next_f32(), r.next_f32())
}

/// A texel of [`GatherProblem`]: where it is, the chart axes its square spans, the light
/// it reflects and the shift of its point set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherTexel {
    /// Its centre on its triangle.
    pub position: Vec3,
    /// Unit front-face normal.
    pub normal: Vec3,
    /// Its chart's first axis (the texel is a square along both, 1/density wide).
    pub chart_u: Vec3,
    /// Its chart's second axis.
    pub chart_v: Vec3,
    /// The light it reflects after one bounce of direct light (linear sRGB radiance).
    pub direct: [f32; 3],
    /// The Cranley–Patterson rotation of its Hammersley points.
    pub shift: Vec2,
}

/// The atlas's gather (one diffuse bounce per texel) as data: what
/// [`Atlas::gather`] computes on the CPU's threads and a GPU computes in a kernel of
/// its own, [`GatherProblem::gather`] per texel either way.
#[derive(Clone, Debug)]
pub struct GatherProblem {
    /// The texels that lie on a triangle, in row order.
    pub texels: Vec<GatherTexel>,
    /// Each one's index in the atlas.
    pub index: Vec<u32>,
    /// Points per texel.
    pub samples: u32,
    /// Texels per scene unit.
    pub density: f32,
    /// The least squared distance the form factor uses (two texels).
    pub min_r2: f32,
    /// (texels · texel area) / samples.
    pub estimator_scale: f32,
    /// Whether each point's visibility is traced.
    pub visibility: bool,
}

impl GatherProblem {
    /// The irradiance gathered at texel `k` (linear sRGB): `samples` points drawn over
    /// all texels (a Hammersley set shifted by the texel's rotation; the first
    /// coordinate picks the texel, its remainder and the second the point within it),
    /// each adding B cos θₓ cos θ_y / r² where `occluded` (the shadow ray from `k` to the
    /// point) is false.
    pub fn gather(&self, k: usize, occluded: impl Fn(&Ray) -> bool) -> [f32; 3] {
        let used = self.texels.len();
        let x = &self.texels[k];
        let mut sum = [0.0f32; 3];
        let from = offset_ray_origin(x.position, x.normal);
        for s in 0..self.samples {
            let mut a = hammersley(s, self.samples) + x.shift;
            a -= a.floor();
            let pick = a.x * used as f32;
            let slot = (pick as usize).min(used - 1);
            if slot == k {
                continue;
            }
            let y = &self.texels[slot];
            let b = y.direct;
            if b == [0.0; 3] {
                continue;
            }
            // The drawn point: the texel's position moved within the texel along its
            // chart's axes (by the first coordinate's remainder and the second).
            let within = (Vec2::new(pick - slot as f32, a.y) - 0.5) / self.density;
            let py = y.position + within.x * y.chart_u + within.y * y.chart_v;
            let d = py - x.position;
            let r2 = d.length_squared().max(self.min_r2);
            let r = r2.sqrt();
            let (cos_x, cos_y) = (x.normal.dot(d) / r, -y.normal.dot(d) / r);
            if cos_x <= 0.0 || cos_y <= 0.0 {
                continue;
            }
            if self.visibility {
                let to = offset_ray_origin(py, y.normal);
                if occluded(&Ray::segment(from, to - from, 0.0, super::SHADOW_T_MAX)) {
                    continue;
                }
            }
            let g = cos_x * cos_y / r2;
            for c in 0..3 {
                sum[c] += b[c] * g;
            }
        }
        sum.map(|s| s * self.estimator_scale)
    }
}

impl Atlas {
    /// Builds the atlas of `view`'s triangles: charts, packing, G-buffer, direct light
    /// and the gather (in parallel on the current rayon pool).
    pub fn build(view: &SceneView, settings: &AtlasSettings) -> Result<Self> {
        let mut atlas = Self::build_ungathered(view, settings)?;
        atlas.gather(view, settings);
        Ok(atlas)
    }

    /// [`Atlas::build`] without the gather: its irradiance is zero until
    /// [`Atlas::gather`] or [`Atlas::set_gathered`] (for a backend that gathers itself,
    /// from [`Atlas::gather_problem`]).
    pub fn build_ungathered(view: &SceneView, settings: &AtlasSettings) -> Result<Self> {
        settings.validate()?;
        let start = Instant::now();
        let triangles = world_triangles(view);
        let (mut charts, prim_chart) = make_charts(&triangles);
        // Without triangles (analytic shapes only) the atlas is empty: no indirect light.
        let (width, height, density) = if charts.is_empty() { (1, 1, 1.0) } else { pack(&mut charts, settings)? };
        let texels = rasterise(&triangles, &charts, &prim_chart, width, height, density);
        let unwrap = start.elapsed();

        let start = Instant::now();
        let direct = direct_light(view, &texels, settings);
        let direct_time = start.elapsed();

        Ok(Atlas {
            width,
            height,
            density,
            stats: AtlasStats {
                width,
                height,
                density,
                charts: charts.len(),
                texels_used: texels.iter().filter(|t| t.prim != EMPTY).count(),
                unwrap,
                direct: direct_time,
                gather: Duration::ZERO,
            },
            charts,
            prim_chart,
            irradiance: vec![[0.0; 3]; texels.len()],
            texels,
            direct,
            seams: settings.seams,
        })
    }

    /// (Re)computes the gathered irradiance with `settings`' samples, visibility and
    /// seam treatment, keeping the charts and direct light (the thesis's table varies
    /// only this).
    pub fn gather(&mut self, view: &SceneView, settings: &AtlasSettings) {
        let start = Instant::now();
        let problem = self.gather_problem(settings);
        let sums: Vec<[f32; 3]> =
            (0..problem.texels.len()).into_par_iter().map(|k| problem.gather(k, |ray| view.occluded(ray))).collect();
        self.set_gathered(&problem, &sums, settings.seams, start.elapsed());
    }

    /// The gather with `settings`, as a backend that runs it itself needs it (the GPU's
    /// `atlas_gather`): the texels that lie on a triangle with what each contributes.
    pub fn gather_problem(&self, settings: &AtlasSettings) -> GatherProblem {
        let n = settings.samples;
        // The points are drawn over the texels that lie on a triangle (in row order, so
        // that the first coordinate's strata stay local), each a square of the same world
        // area: the estimate is Σ B cos θₓ cos θ_y / r² · (texels · area) / N. (The thesis
        // draws over the whole atlas and wastes the share that falls into gaps.)
        let texel_area = 1.0 / (self.density * self.density);
        let index: Vec<u32> =
            (0..self.texels.len() as u32).filter(|&i| self.texels[i as usize].prim != EMPTY).collect();
        let texels = index
            .iter()
            .map(|&i| {
                let x = &self.texels[i as usize];
                let chart = &self.charts[self.prim_chart[x.prim as usize] as usize];
                GatherTexel {
                    position: x.position,
                    normal: x.normal,
                    chart_u: chart.u,
                    chart_v: chart.v,
                    direct: self.direct[i as usize],
                    shift: rotation(settings.seed ^ 0x61746c6173, i as u64),
                }
            })
            .collect();
        GatherProblem {
            estimator_scale: index.len() as f32 * texel_area / n as f32,
            texels,
            index,
            samples: n,
            density: self.density,
            // Points closer than two texels are taken as two texels away: the 1/r² of the
            // form factor is not resolved below the atlas's size, and unclamped it turns
            // corners into fireflies (a bias within two texels of where surfaces meet).
            min_r2: MIN_DISTANCE_TEXELS * MIN_DISTANCE_TEXELS * texel_area,
            visibility: settings.visibility,
        }
    }

    /// Takes the gather's results, one per texel of `problem` ([`GatherProblem::gather`]),
    /// as the atlas's irradiance, dilated into the gutter with `seams`' treatment; `time`
    /// is what the gather took (the dilation's time is added).
    ///
    /// # Panics
    /// If `sums` has not one entry per texel of `problem`.
    pub fn set_gathered(&mut self, problem: &GatherProblem, sums: &[[f32; 3]], seams: SeamFix, time: Duration) {
        let start = Instant::now();
        assert_eq!(sums.len(), problem.index.len(), "one gathered value per texel of the problem");
        let mut irradiance = vec![[0.0f32; 3]; self.texels.len()];
        for (&i, sum) in problem.index.iter().zip(sums) {
            irradiance[i as usize] = *sum;
        }
        if seams == SeamFix::Dilate {
            dilate(&mut irradiance, &self.texels, self.width, self.height, GUTTER + 1);
        }
        self.irradiance = irradiance;
        self.seams = seams;
        self.stats.gather = time + start.elapsed();
    }

    /// The gathered irradiance (linear sRGB) at point `p` on triangle primitive `prim`,
    /// bilinear between texel centres; `None` off the atlas (shapes).
    #[inline]
    pub fn irradiance_at(&self, prim: u32, p: Vec3) -> Option<[f32; 3]> {
        let chart = *self.prim_chart.get(prim as usize)?;
        if chart == EMPTY {
            return None;
        }
        let a = self.charts[chart as usize].atlas_point(p, self.density) - Vec2::splat(0.5);
        let (x0, y0) = (a.x.floor(), a.y.floor());
        let (fx, fy) = (a.x - x0, a.y - y0);
        let mut e = [0.0f32; 3];
        for (dx, dy, w) in
            [(0, 0, (1.0 - fx) * (1.0 - fy)), (1, 0, fx * (1.0 - fy)), (0, 1, (1.0 - fx) * fy), (1, 1, fx * fy)]
        {
            let (x, y) = (x0 as i64 + dx, y0 as i64 + dy);
            if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
                continue;
            }
            let t = self.irradiance[(y as u32 * self.width + x as u32) as usize];
            for c in 0..3 {
                e[c] += w * t[c];
            }
        }
        Some(e)
    }

    /// Each chart's projection, by chart index ([`Atlas::prim_charts`]).
    pub fn chart_projections(&self) -> Vec<ChartProjection> {
        self.charts.iter().map(Chart::projection).collect()
    }

    /// Per primitive (the renderer's ids: triangles, shapes, instanced triangles) the index
    /// of its chart, `u32::MAX` for none (shapes).
    pub fn prim_charts(&self) -> &[u32] {
        &self.prim_chart
    }

    /// The gathered irradiance per texel (linear sRGB, row-major), what
    /// [`Atlas::irradiance_at`] interpolates.
    pub fn irradiance(&self) -> &[[f32; 3]] {
        &self.irradiance
    }

    /// Texels per scene unit.
    pub fn density(&self) -> f32 {
        self.density
    }

    /// Width and height in texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The G-buffer and results as images (linear, row-major RGB): `"normal"` (mapped to
    /// [0, 1]), `"position"` (normalised to the scene's bounds), `"direct"` (reflected
    /// direct light) and `"indirect"` (gathered irradiance / π, as radiance from a white
    /// surface); empty texels black.
    pub fn image(&self, what: &str) -> Option<Vec<f32>> {
        let (lo, hi) = self
            .texels
            .iter()
            .filter(|t| t.prim != EMPTY)
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), t| {
                (lo.min(t.position), hi.max(t.position))
            });
        let extent = (hi - lo).max(Vec3::splat(1e-6));
        let px = |i: usize| -> [f32; 3] {
            let t = &self.texels[i];
            match what {
                "indirect" => self.irradiance[i].map(|e| e * FRAC_1_PI),
                _ if t.prim == EMPTY => [0.0; 3],
                "normal" => (t.normal * 0.5 + 0.5).to_array(),
                "position" => ((t.position - lo) / extent).to_array(),
                "direct" => self.direct[i],
                _ => [0.0; 3],
            }
        };
        matches!(what, "normal" | "position" | "direct" | "indirect")
            .then(|| (0..self.texels.len()).flat_map(px).collect())
    }
}

/// Every triangle primitive in world space, indexed by primitive id (shapes' ids hold
/// `None`).
fn world_triangles(view: &SceneView) -> Vec<Option<[Vec3; 3]>> {
    let flat = view.geometry.triangle_count() as usize;
    let shapes = view.scene.shapes.len();
    let instanced = view.scene.instanced_triangle_count() as usize;
    (0..flat + shapes + instanced)
        .into_par_iter()
        .map(|prim| {
            if prim < flat {
                return Some(view.scene.triangle_vertices(prim));
            }
            if prim < flat + shapes {
                return None;
            }
            let (mesh, tri, xf) = view.triangle_source(prim as u32);
            let t = mesh.triangles[tri as usize];
            let [a, b, c] = t.map(|i| {
                let p = Vec3::from_array(mesh.positions[i as usize]);
                xf.map_or(p, |x| x.to_world.transform_point3(p))
            });
            // A mirroring placement reverses the world winding; the object's front stays
            // its front (as the renderer and the lights see it).
            Some(if xf.is_some_and(|x| x.orientation < 0.0) { [a, c, b] } else { [a, b, c] })
        })
        .collect()
}

/// The largest angle between a chart's triangles and its first one (cos 5°): nearly
/// planar charts keep the projection's area distortion below 0.4 %.
const CHART_COS: f32 = 0.996_194_7;

/// Grows charts over shared edges from seed triangles, taking in neighbours whose normal
/// is within 5° of the seed's ([`CHART_COS`]): walls modelled as two slightly skewed
/// triangles (the Cornell box's) share a chart, gently curved regions too; a sharply
/// curved mesh ends up with small charts.
fn make_charts(triangles: &[Option<[Vec3; 3]>]) -> (Vec<Chart>, Vec<u32>) {
    let n = triangles.len();
    let normals: Vec<Option<Vec3>> =
        triangles.iter().map(|t| t.and_then(|[a, b, c]| (b - a).cross(c - a).try_normalize())).collect();
    // Triangles by edge (vertex positions compared exactly, so split vertices join).
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut edges: HashMap<([u32; 3], [u32; 3]), Vec<u32>> = HashMap::new();
    for (i, t) in triangles.iter().enumerate() {
        let (Some(v), Some(_)) = (t, normals[i]) else { continue };
        for e in 0..3 {
            let (a, b) = (key(v[e]), key(v[(e + 1) % 3]));
            edges.entry(if a < b { (a, b) } else { (b, a) }).or_default().push(i as u32);
        }
    }
    let mut charts: Vec<Chart> = Vec::new();
    let mut prim_chart = vec![EMPTY; n];
    let mut queue = Vec::new();
    for seed in 0..n {
        let (Some(_), Some(normal)) = (triangles[seed], normals[seed]) else { continue };
        if prim_chart[seed] != EMPTY {
            continue;
        }
        let c = charts.len() as u32;
        let frame = Frame::from_normal(normal);
        let mut chart = Chart {
            origin: triangles[seed].expect("a triangle")[0],
            u: frame.s,
            v: frame.t,
            min: Vec2::splat(f32::INFINITY),
            size: Vec2::splat(f32::NEG_INFINITY),
            offset: UVec2::ZERO,
        };
        prim_chart[seed] = c;
        queue.push(seed as u32);
        while let Some(i) = queue.pop() {
            let v = triangles[i as usize].expect("a triangle");
            for p in v {
                let d = p - chart.origin;
                let q = Vec2::new(d.dot(chart.u), d.dot(chart.v));
                chart.min = chart.min.min(q);
                chart.size = chart.size.max(q); // the maximum, until below
            }
            for e in 0..3 {
                let (a, b) = (key(v[e]), key(v[(e + 1) % 3]));
                for &j in &edges[&if a < b { (a, b) } else { (b, a) }] {
                    let j = j as usize;
                    if prim_chart[j] == EMPTY && normals[j].is_some_and(|nj| nj.dot(normal) >= CHART_COS) {
                        prim_chart[j] = c;
                        queue.push(j as u32);
                    }
                }
            }
        }
        chart.size -= chart.min;
        charts.push(chart);
    }
    (charts, prim_chart)
}

/// Shelf-packs the charts (tallest first) at the settings' density, or at the largest
/// that fits `resolution`²; grows the atlas where even tiny charts do not fit. Returns
/// (width, height, density).
fn pack(charts: &mut [Chart], settings: &AtlasSettings) -> Result<(u32, u32, f32)> {
    let area: f32 = charts.iter().map(|c| c.size.x.max(0.0) * c.size.y.max(0.0)).sum::<f32>().max(1e-12);
    let mut side = settings.resolution;
    let mut density =
        if settings.density > 0.0 { settings.density } else { (0.7 * (side * side) as f32 / area).sqrt() };
    let mut order: Vec<usize> = (0..charts.len()).collect();
    for _ in 0..200 {
        order.sort_by_key(|&i| std::cmp::Reverse(charts[i].texels(density).y));
        let width = if settings.density > 0.0 {
            // A fixed density: a square-ish atlas that holds the charts.
            let texels: f32 = charts.iter().map(|c| c.texels(density).as_vec2().element_product()).sum();
            let widest = charts.iter().map(|c| c.texels(density).x).max().unwrap_or(1);
            ((texels.sqrt() * 1.1) as u32).max(widest)
        } else {
            side
        };
        let (mut x, mut y, mut shelf) = (0u32, 0u32, 0u32);
        let mut fits = true;
        for &i in &order {
            let t = charts[i].texels(density);
            if t.x > width {
                fits = false;
                break;
            }
            if x + t.x > width {
                x = 0;
                y = y.saturating_add(shelf);
                shelf = 0;
            }
            charts[i].offset = UVec2::new(x, y);
            x += t.x;
            shelf = shelf.max(t.y);
        }
        let height = y.saturating_add(shelf);
        if settings.density > 0.0 {
            if height as u64 * width as u64 > 1 << 28 {
                return Err(Error::Setting(format!(
                    "an atlas at {density} texels per unit would need {width}×{height} texels: lower --atlas-density"
                )));
            }
            return Ok((width, height.max(1), density));
        }
        if fits && height <= side {
            return Ok((side, side, density));
        }
        // Too large: a lower density, unless charts are already at their minimum size
        // (then the atlas grows).
        let minimum = charts.iter().all(|c| (c.size * density).max_element() < 1.0);
        if minimum {
            side = side + side / 4;
            if side > 16384 {
                return Err(Error::Setting(format!(
                    "{} charts do not fit a 16384² atlas (a curved mesh has a chart per triangle)",
                    charts.len()
                )));
            }
        } else {
            density *= 0.9;
        }
    }
    Err(Error::Setting("the atlas charts could not be packed".into()))
}

/// The G-buffer: for each texel whose centre lies on a triangle (edges included), the
/// triangle and the texel centre's position on it.
fn rasterise(
    triangles: &[Option<[Vec3; 3]>],
    charts: &[Chart],
    prim_chart: &[u32],
    width: u32,
    height: u32,
    density: f32,
) -> Vec<Texel> {
    let empty = Texel { prim: EMPTY, position: Vec3::ZERO, normal: Vec3::ZERO };
    let normals: Vec<Vec3> = triangles
        .iter()
        .map(|t| t.and_then(|[a, b, c]| (b - a).cross(c - a).try_normalize()).unwrap_or(Vec3::Z))
        .collect();
    let mut texels = vec![empty; width as usize * height as usize];
    for (prim, t) in triangles.iter().enumerate() {
        let (Some(v), c) = (t, prim_chart[prim]) else { continue };
        if c == EMPTY {
            continue;
        }
        let chart = &charts[c as usize];
        let a = v.map(|p| chart.atlas_point(p, density));
        let lo = a[0].min(a[1]).min(a[2]).floor().max(Vec2::ZERO);
        let hi = a[0].max(a[1]).max(a[2]).ceil().min(Vec2::new(width as f32, height as f32));
        let area = (a[1] - a[0]).perp_dot(a[2] - a[0]);
        if area == 0.0 {
            continue;
        }
        for y in lo.y as u32..hi.y as u32 {
            for x in lo.x as u32..hi.x as u32 {
                let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let w0 = (a[1] - q).perp_dot(a[2] - q) / area;
                let w1 = (a[2] - q).perp_dot(a[0] - q) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 >= -1e-6 && w1 >= -1e-6 && w2 >= -1e-6 {
                    // On the triangle itself (a chart's triangles may lie off its plane).
                    let position = w0 * v[0] + w1 * v[1] + w2 * v[2];
                    texels[(y * width + x) as usize] = Texel { prim: prim as u32, position, normal: normals[prim] };
                }
            }
        }
    }
    texels
}

/// Light leaving each texel after one reflection of direct light, in linear sRGB: the
/// surface's BSDF seen along its normal, lit by `direct_samples` light samples with
/// shadow rays.
fn direct_light(view: &SceneView, texels: &[Texel], settings: &AtlasSettings) -> Vec<[f32; 3]> {
    let wl = SampledWavelengths::<3>::rgb();
    let k = settings.direct_samples;
    texels
        .par_iter()
        .enumerate()
        .map(|(i, t)| {
            if t.prim == EMPTY {
                return [0.0; 3];
            }
            let material = view.material(t.prim);
            let uv = view.uv_at_point(t.prim, t.position);
            let it = Interaction { p: t.position, ng: t.normal, ns: t.normal, tangent: Vec3::ZERO, area: 0.0, uv };
            let bsdf = material.bsdf_at(uv, &wl);
            if !bsdf.flags().is_non_specular() {
                return [0.0; 3];
            }
            let frame = Frame::from_normal(t.normal);
            let at = Shading { it: &it, material, ng: t.normal, wo_world: t.normal, frame: &frame, wo: Vec3::Z };
            let shift = rotation(settings.seed ^ 0x646972656374, i as u64);
            let mut counters = PathCounters::default();
            let mut sum = SampledSpectrum::<3>::zero();
            for s in 0..k {
                let mut u = hammersley(s, k) + shift;
                u -= u.floor();
                let u = u.min(Vec2::splat(ONE_MINUS_EPSILON));
                if let Some(ls) = view.lights.sample(view.scene, u)
                    && let Some((f, le, w)) = light_contribution(view, &at, &bsdf, &wl, Mis::None, &ls, &mut counters)
                {
                    sum += f * le * w;
                }
            }
            let b = sum / k as f32;
            [b.0[0], b.0[1], b.0[2]]
        })
        .collect()
}

/// Fills empty texels next to filled ones with their filled neighbours' mean, `rounds`
/// times (each round reaches one texel further into the gutter).
fn dilate(values: &mut [[f32; 3]], texels: &[Texel], width: u32, height: u32, rounds: u32) {
    let mut filled: Vec<bool> = texels.iter().map(|t| t.prim != EMPTY).collect();
    for _ in 0..rounds {
        let mut updates = Vec::new();
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let i = (y * width as i64 + x) as usize;
                if filled[i] {
                    continue;
                }
                let (mut sum, mut count) = ([0.0f32; 3], 0);
                for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1)] {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= width as i64 || ny >= height as i64 {
                        continue;
                    }
                    let j = (ny * width as i64 + nx) as usize;
                    if filled[j] {
                        for c in 0..3 {
                            sum[c] += values[j][c];
                        }
                        count += 1;
                    }
                }
                if count > 0 {
                    updates.push((i, sum.map(|s| s / count as f32)));
                }
            }
        }
        if updates.is_empty() {
            break;
        }
        for (i, v) in updates {
            values[i] = v;
            filled[i] = true;
        }
    }
}

/// Atlas-based one-bounce global illumination (`--integrator atlas`).
///
/// Built once per scene ([`Integrator::for_scene`]): every triangle is unwrapped into
/// a planar chart of the atlas (connected coplanar triangles share one), each texel holds
/// its position, normal and the light it reflects after one bounce of direct light
/// (computed with shadow rays, where the thesis used a shadow map), and each texel
/// gathers one diffuse bounce from [`AtlasSettings::samples`] Hammersley points spread
/// over the atlas's texels — an area integral, E(x) = Σ B(y) cos θₓ cos θ_y / r² · A/N
/// with A the texels' area in scene units (the thesis's eq. 9, B(y) cos θₓ · 2π / N,
/// treats atlas points as uniformly distributed *directions* and is wrong by the missing
/// cos θ_y A / r²: +75 % on a lit square above a point, tested). With [`AtlasSettings::visibility`] each point is tested by a shadow
/// ray; without, light leaks through walls, as in the thesis.
///
/// A camera sample follows mirrors and glass to the first diffuse or glossy surface,
/// takes its emission and direct light there (one light sample, as
/// [`crate::integrator::DirectLighting`]), and adds the atlas's irradiance times the
/// surface's albedo (from one BSDF sample) over π. With visibility and enough samples it
/// converges to the path tracer limited to one diffuse bounce (`max_diffuse_depth` 2)
/// up to the atlas's discretisation: the reflected direct light is constant per texel,
/// points closer than two texels are clamped, and the lookup interpolates. Biased by design:
/// one bounce only, surfaces taken as diffuse in the gather, only each triangle's front
/// (winding) side in the atlas, no indirect light on analytic shapes (they are not in the
/// atlas), and light reflected by mirrors into the gather is lost. The atlas is built in
/// linear sRGB; spectral renders turn its irradiance into a spectrum through the
/// Jakob–Hanika table.
#[derive(Clone, Default)]
pub struct AtlasGi {
    settings: AtlasSettings,
    atlas: Option<Arc<Atlas>>,
}

impl std::fmt::Debug for AtlasGi {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AtlasGi").field("settings", &self.settings).field("built", &self.atlas.is_some()).finish()
    }
}

impl AtlasGi {
    /// An atlas integrator with these settings (the atlas is built per scene).
    pub fn new(settings: AtlasSettings) -> Self {
        Self { settings, atlas: None }
    }

    /// The scene's atlas, once built.
    pub fn atlas(&self) -> Option<&Atlas> {
        self.atlas.as_deref()
    }
}

/// The most specular bounces a camera path follows before it reaches a diffuse surface.
pub const SPECULAR_CHAIN: u32 = 16;

impl Integrator for AtlasGi {
    fn name(&self) -> &'static str {
        "atlas"
    }

    /// Its per-pixel direct light and the texels' gather; the bake's light paths start
    /// from emitters chosen by power.
    fn chooses_lights_per_point(&self) -> bool {
        true
    }

    fn for_scene(&self, view: &SceneView) -> Result<Option<Self>> {
        let atlas = Atlas::build(view, &self.settings)?;
        // Spectral lookups uplift through the Jakob–Hanika table: decoded here, not in the
        // first render's samples.
        spectral::uplift::uplift_table();
        Ok(Some(Self { settings: self.settings, atlas: Some(Arc::new(atlas)) }))
    }

    fn radiance<const N: usize, S: Sampler>(
        &self,
        view: &SceneView,
        mut ray: Ray,
        wl: &mut SampledWavelengths<N>,
        settings: &PathSettings,
        sampler: &mut S,
        counters: &mut PathCounters,
    ) -> SampledSpectrum<N> {
        let mut l = SampledSpectrum::<N>::zero();
        let mut beta = SampledSpectrum::<N>::one();
        // Dispersive glass on the way: one wavelength per sample, as the Whitted
        // integrator does.
        if view.has_dispersion() && !wl.is_rgb() && !wl.is_collapsed() {
            let k = ((sampler.next_1d() * N as f32) as usize).min(N - 1);
            wl.collapse_to(k);
        }
        let wl = &*wl;
        // The absorbing material the last segment left its vertex into, if any.
        let mut inside = None;
        for _ in 0..=SPECULAR_CHAIN {
            counters.rays += 1;
            let Some(hit) = view.intersect(&ray) else {
                return l + beta * view.escaped_radiance(ray.dir, wl);
            };
            let material = view.material(hit.prim);
            let it = view.interaction(&hit, material, settings.shading_normals);
            let wo_world = -ray.dir;
            let front = wo_world.dot(it.ng) > 0.0;
            if view.absorbing {
                beta *= super::segment_transmittance(material, front, hit.t, inside, wl);
            }
            if front && let Some(le) = material.emission_at(it.uv, wl) {
                l += beta * le;
            }
            let (ng, ns) = shading_normals(settings.shading_normals, it.ng, it.ns, wo_world, material.is_two_sided());
            let frame = Frame::from_normal_tangent(ns, it.tangent);
            let wo = frame.to_local(wo_world);
            let bsdf = material.bsdf_at(it.uv, wl);
            if bsdf.flags().is_non_specular() {
                // Direct light, per pixel.
                let at = Shading { it: &it, material, ng, wo_world, frame: &frame, wo };
                if let Some((f, le, k)) =
                    super::next_event(view, &at, &bsdf, wl, Mis::None, sampler.next_2d(), counters)
                {
                    l += beta * f * le * k;
                }
                // One bounce of indirect light, from the atlas: E/π times the albedo
                // (one BSDF sample: f |cos| / pdf; exact for a Lambertian surface).
                let uc = sampler.next_1d();
                let u = sampler.next_2d();
                let front_side = front || !material.is_two_sided();
                if let Some(atlas) = &self.atlas
                    && front_side
                    && let Some(e) = atlas.irradiance_at(hit.prim, it.p)
                    && let Some(s) = bsdf.sample(wo, uc, u)
                    && s.pdf > 0.0
                {
                    let wi_world = frame.to_world(s.wi);
                    if !lobe_leaks(material, settings.shading_normals, it.ng, wo_world, wi_world, s.flags) {
                        let albedo = s.f * (s.wi.z.abs() / s.pdf);
                        l += beta * albedo * irradiance_spectrum(e, wl) * FRAC_1_PI;
                    }
                }
                return l;
            }
            // A mirror or glass: follow it.
            let Some(s) = bsdf.sample(wo, sampler.next_1d(), sampler.next_2d()) else { return l };
            if s.pdf <= 0.0 || s.f.is_black() {
                return l;
            }
            let wi_world = frame.to_world(s.wi);
            if lobe_leaks(material, settings.shading_normals, it.ng, wo_world, wi_world, s.flags) {
                return l;
            }
            beta *= s.f * (s.wi.z.abs() / s.pdf);
            if view.absorbing {
                inside = entered_medium(material, it.ng, wi_world);
            }
            ray = Ray::new(it.spawn_origin(wi_world), wi_world);
        }
        l
    }
}

/// A linear-sRGB irradiance at the path's wavelengths: itself in RGB mode, else the
/// Jakob–Hanika spectrum of its chromaticity under the D65 illuminant, scaled.
fn irradiance_spectrum<const N: usize>(rgb: [f32; 3], wl: &SampledWavelengths<N>) -> SampledSpectrum<N> {
    if wl.is_rgb() {
        return SampledSpectrum(std::array::from_fn(|i| rgb.get(i).copied().unwrap_or(0.0)));
    }
    let scale = rgb.iter().copied().fold(0.0f32, f32::max);
    if scale <= 0.0 || !scale.is_finite() {
        return SampledSpectrum::zero();
    }
    let reflectance = crate::texture::reflectance_spectrum(rgb.map(|c| c.max(0.0) / scale), wl);
    reflectance * wl.eval(spectral::uplift::d65_normalised) * scale
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Geometry;
    use crate::lights::Lights;
    use crate::material::Material;
    use crate::mesh::quad;
    use crate::scene::Scene;
    use spectral::spectrum::Colour;

    /// A small receiver facing up under a 2 × 2 square facing down at height 1 whose
    /// texels are set to reflect radiance 1: the gather (no visibility) must give the
    /// closed-form irradiance of a uniform Lambertian square above a point on its axis,
    /// E = 4 X/√(1+X²) · atan(X/√(1+X²)) with X = half-side/height (Howell's catalogue,
    /// C-11, summed over the four corner rectangles) = 1.7408 for X = 1. The atlas
    /// thesis's eq. 9 — B cos θₓ · 2π averaged over the same atlas points, as if they
    /// were uniform directions — gives another number (pinned here as wrong by > 20 %).
    #[test]
    fn the_gather_is_an_area_integral_and_the_thesis_eq_9_is_not() {
        let grey = Material::diffuse("grey", Colour::constant(0.5)).unwrap();
        let mut scene = Scene::default();
        scene.add(&quad(Vec3::ZERO, Vec3::Y, 0.05), grey.clone());
        scene.add(&quad(Vec3::new(0.0, 1.0, 0.0), -Vec3::Y, 1.0), grey);
        let geometry = Geometry::build(&scene, &Default::default()).unwrap();
        let lights = Lights::new(&scene);
        let view = SceneView::new(&scene, &geometry, &lights);
        let settings = AtlasSettings {
            density: 16.0,
            samples: 1 << 16,
            visibility: false,
            direct_samples: 1,
            ..Default::default()
        };
        let mut atlas = Atlas::build(&view, &settings).unwrap();
        for (t, d) in atlas.texels.iter().zip(atlas.direct.iter_mut()) {
            *d = if t.prim != EMPTY && t.normal.y < 0.0 { [1.0; 3] } else { [0.0; 3] };
        }
        atlas.gather(&view, &settings);
        let x = 1.0f64 / 2f64.sqrt();
        let expected = 4.0 * x * x.atan();
        let e = atlas.irradiance_at(0, Vec3::ZERO).unwrap()[1] as f64;
        assert!((e / expected - 1.0).abs() < 0.02, "gathered {e}, closed form {expected}");
        // Eq. 9 over the same points (the receiver's centre texel's rotation aside).
        let (w, h) = atlas.size();
        let n = settings.samples;
        let mut sum = 0.0f64;
        for k in 0..n {
            let a = hammersley(k, n);
            let j = ((a.y * h as f32) as u32).min(h - 1) * w + ((a.x * w as f32) as u32).min(w - 1);
            let y = &atlas.texels[j as usize];
            if y.prim != EMPTY && atlas.direct[j as usize][1] > 0.0 {
                sum += (y.position.normalize().y as f64) * std::f64::consts::TAU;
            }
        }
        let thesis = sum / n as f64;
        assert!((thesis / expected - 1.0).abs() > 0.2, "eq. 9 gives {thesis}, closed form {expected}");
    }

    #[test]
    fn a_scene_of_shapes_alone_has_an_empty_atlas() {
        let mut scene = Scene::default();
        let grey = Material::diffuse("grey", Colour::constant(0.5)).unwrap();
        scene.add_shape(
            crate::geometry::ShapeKind::Sphere(
                shapes::sphere::Sphere::new(Vec3::ZERO, 1.0, Default::default()).unwrap(),
            ),
            grey,
        );
        let geometry = Geometry::build(&scene, &Default::default()).unwrap();
        let lights = Lights::new(&scene);
        let view = SceneView::new(&scene, &geometry, &lights);
        let atlas = Atlas::build(&view, &AtlasSettings::default()).unwrap();
        assert_eq!((atlas.stats.charts, atlas.stats.texels_used), (0, 0));
        assert_eq!(atlas.irradiance_at(0, Vec3::X), None, "the sphere is not in the atlas");
    }

    #[test]
    fn hammersley_points_are_the_radical_inverse_and_stratified() {
        assert_eq!(hammersley(0, 8), Vec2::new(0.0, 0.0));
        assert_eq!(hammersley(1, 8), Vec2::new(0.125, 0.5));
        assert_eq!(hammersley(3, 8), Vec2::new(0.375, 0.75));
        assert_eq!(hammersley(6, 8), Vec2::new(0.75, 0.375));
        // One point per cell of a 16 × 16 grid of elementary intervals (1/16 × 1/16).
        let mut rows = [0; 16];
        for i in 0..16 {
            rows[(hammersley(i, 16).y * 16.0) as usize] += 1;
        }
        assert!(rows.iter().all(|&r| r == 1), "{rows:?}");
    }
}
