//! Light sources for next-event estimation: emissive triangles and analytic shapes,
//! point, spot and directional lights, chosen in proportion to their power, plus the
//! environment (uniform, or importance-sampled by its map's luminance) — or, with a light
//! tree ([`LightSampler::Tree`], module `tree`), the emitters and the point and spot
//! lights chosen by what each can give the shading point.

use crate::envmap::EnvironmentMap;
use crate::punctual::PunctualLight;
use crate::scene::Scene;
use brdf::sampling::{UNIFORM_SPHERE_PDF, uniform_sphere, uniform_triangle};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

mod tree;

pub use tree::NODE_FLOATS as LIGHT_TREE_NODE_FLOATS;

/// What a light sample was taken on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightSource {
    /// An emissive triangle or shape (its primitive id).
    Primitive(u32),
    /// The environment.
    Environment,
    /// A point, spot or directional light (its index in [`Scene::punctual_lights`]).
    Punctual(u32),
}

/// A point (or direction, for the environment and directional lights) chosen on a light.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The sampled point (a point or spot light's position), or the unit direction
    /// towards the light for the environment and directional lights.
    pub point: Vec3,
    /// The light's front-face normal at the point (zero for the others).
    pub normal: Vec3,
    /// Probability density: per unit area for triangles and shapes (including the choice
    /// of the primitive), per solid angle for the environment; for a punctual light the
    /// probability of choosing it (a delta light has no density).
    pub pdf: f32,
    /// What was sampled.
    pub source: LightSource,
}

/// An emissive triangle as light sampling needs it, computed once per scene instead of
/// per shadow ray (vertex lookups, a cross product, two square roots and a division per
/// sample). The lanes' next-event estimation gathers these one lane at a time
/// ([`Lights::triangle_light`]) and places the points across the lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightTriangle {
    /// Its corners: a sample's point is [`on_triangle`] of them.
    pub(crate) vertices: [Vec3; 3],
    /// Unit front-face normal (counter-clockwise winding).
    pub(crate) normal: Vec3,
    /// Its area.
    pub(crate) area: f32,
    /// Density per unit area of its points, the choice of the light included: its
    /// probability of being chosen over its area.
    pub(crate) pdf: f32,
    /// The primitive.
    pub(crate) prim: u32,
}

/// One coordinate of the point with barycentrics `b0`, `b1` (`uniform_triangle`'s) on the
/// triangle whose corners have coordinates `v`: `b0·v0 + b1·v1 + (1 − b0 − b1)·v2`, in
/// this order of operations, per coordinate so that the lanes compute it across paths
/// with the same bits as [`Lights::sample`].
#[inline(always)]
pub(crate) fn on_triangle(b0: f32, b1: f32, v: [f32; 3]) -> f32 {
    (b0 * v[0] + b1 * v[1]) + (1.0 - b0 - b1) * v[2]
}

/// The scene's emitters and the discrete distribution that picks among them.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// Emissive primitives (triangles, then shapes).
    prims: Vec<u32>,
    /// For each entry of `prims` that is a triangle (they come first), its geometry.
    triangles: Vec<LightTriangle>,
    /// The environment's share of the unit interval, then [`Lights::cdf`]: entry k and
    /// k + 1 bound entry k's stretch, with no special case for the first (a branch that
    /// the Cornell box's two equal lights mispredicted half the time). Empty without
    /// lights.
    bounds: Vec<f32>,
    /// Probability of choosing each primitive (0 for non-emitters), for MIS when a
    /// BSDF-sampled ray hits an emitter.
    prim_pmf: Vec<f32>,
    /// Probability of choosing each of the scene's punctual lights, by its index in
    /// [`Scene::punctual_lights`].
    punctual_pmf: Vec<f32>,
    /// The punctual lights in the order of their entries in `cdf` (after the
    /// primitives'): the point and spot lights, then the directional ones, each in the
    /// scene's order — so that the lights a tree can hold are one stretch.
    punctual_order: Vec<u32>,
    /// Each punctual light's place in `punctual_order` (by its index in the scene).
    punctual_rank: Vec<u32>,
    /// How many of `punctual_order`'s lights have a position (point and spot lights).
    positioned: usize,
    /// The environment's map, sampled by luminance (uniform directions without one).
    environment_map: Option<std::sync::Arc<EnvironmentMap>>,
    /// The sun disks among the punctual lights, which escaping rays can see.
    suns: Vec<SunDisk>,
    /// The light tree over `prims` and the positioned punctual lights
    /// ([`Lights::with_tree`]), which then chooses among them by what each can give the
    /// shading point.
    tree: Option<LightChoice>,
}

/// What choosing among the emitters and positioned punctual lights by a
/// [`tree::LightTree`] needs besides the tree. Its lights are entries of the cdf: those of
/// `prims`, then the point and spot lights.
#[derive(Clone, Debug)]
struct LightChoice {
    tree: tree::LightTree,
    /// Each light's reciprocal area (an emitter's points are drawn uniformly on it; 1 for
    /// a point or spot light, whose choice is its probability).
    inv_areas: Vec<f32>,
    /// For each primitive id, its index in `prims` (`u32::MAX`: not an emitter).
    slot: Vec<u32>,
    /// The tree's stretch of the unit interval, `[lo, hi)`: after the environment's,
    /// before the directional lights' (where [`Lights::choose`] puts them). Its length is
    /// its lights' summed probability.
    lo: f32,
    hi: f32,
}

impl LightChoice {
    /// Whether the first sample value `x` falls in the tree's stretch.
    #[inline(always)]
    fn holds(&self, x: f32) -> bool {
        x >= self.lo && x < self.hi
    }

    /// The light the tree chooses for `p`, `n` with `x` (in its stretch), `x`
    /// rescaled within the choice, and the choice's probability over the light's area
    /// (for a point or spot light the probability itself).
    #[inline(always)]
    fn choose(&self, x: f32, p: Vec3, n: Vec3) -> Option<(usize, f32, f32)> {
        let (k, pmf, x) = self.tree.sample(p, n, rescale(x, self.lo, self.hi))?;
        Some((k, x, (self.hi - self.lo) * pmf * self.inv_areas[k]))
    }
}

/// A light tree as flat arrays, for a backend that walks it elsewhere (the GPU's
/// `wgsl/lights.wgsl`), from [`Lights::tree_tables`].
#[derive(Clone, Debug, PartialEq)]
pub struct LightTreeTables {
    /// The nodes, root first, [`LIGHT_TREE_NODE_FLOATS`] floats each: twelve rows of four
    /// floats, one per child slot — the slot's box centre x, y, z, its bounding sphere's
    /// squared radius, the least squared distance the estimate divides by, its cone axis
    /// x, y, z, power (0: an unused slot), cos θo, sin θo, cos θe — then the four children
    /// (u32 bits: a light where the mask's bit is set, else a node), the mask (bit i:
    /// slot i holds a light) and three zeros. A light is an entry of [`Lights::cdf`]: one
    /// of [`Lights::prims`], or past them a point or spot light.
    pub nodes: Vec<f32>,
    /// For each light of the tree (the entries of [`Lights::prims`], then the point and
    /// spot lights' entries of [`Lights::cdf`]), the slots from the root to it: four
    /// words, low bits first, bits 2d and 2d + 1 the slot taken at depth d.
    pub trails: Vec<[u32; 4]>,
    /// For each primitive id, its entry in [`Lights::prims`] (`u32::MAX`: not sampled).
    pub slots: Vec<u32>,
    /// The tree's stretch `[lo, hi)` of the unit interval the first sample value falls in
    /// (after the environment's, before the directional lights'); its length is its
    /// lights' summed probability, by which the tree's own probabilities are scaled.
    pub lo: f32,
    /// See `lo`.
    pub hi: f32,
}

/// How next-event estimation chooses among a scene's emitters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSampler {
    /// In proportion to power, the same for every shading point (Mitsuba 3's choice).
    Power,
    /// By a light tree (Conty Estevez & Kulla 2018): by what each emitter, point or spot
    /// light can give the shading point, estimated from bounds on position, orientation
    /// and power. The environment and directional lights keep their power shares.
    Tree,
    /// The tree where the scene has at least [`LightSampler::TREE_FROM`] emitters, point
    /// and spot lights (and the backend and integrator take one), else power.
    #[default]
    Auto,
}

impl LightSampler {
    /// The lights a tree would hold (emissive triangles and shapes, point and spot lights
    /// with power) from which [`LightSampler::Auto`] takes the tree: at 8 emitters (four
    /// lamps) the four-wide tree in the lanes reached a given error 1.15× sooner than power
    /// sampling, at 2 (one lamp) about as soon (0.9–1.2×, within
    /// the runs' spread); 3 to 7 were not measured, so 8 is the fewest where it was seen
    /// to win (docs/figures.md, "The light tree four wide and in the lanes").
    pub const TREE_FROM: usize = 8;
}

/// A sun disk as escaping rays need it: which light, where and how large, and the
/// solid-angle pdf with which [`Lights::sample`] draws a direction in it.
#[derive(Clone, Copy, Debug)]
pub struct SunDisk {
    /// Its index in [`Scene::punctual_lights`].
    pub index: u32,
    /// Unit direction towards its centre.
    pub axis: Vec3,
    /// Cosine of its angular radius.
    pub cos_radius: f32,
    /// Radiance / irradiance: 1/(π sin² r).
    pub radiance_scale: f32,
    /// Solid-angle pdf of [`Lights::sample`] drawing a direction inside it (choice of the
    /// light included).
    pub pdf: f32,
}

impl Lights {
    /// Collects emitters and weights them by power: π·A·Y(Le) for a one-sided triangle
    /// or shape (emitting from its front or outside), 4π²·r²·Y(Le) for the environment
    /// seen by a scene of bounding radius r (pbrt-v4's uniform infinite light), and
    /// [`PunctualLight::power`] for point, spot and directional lights. Shapes
    /// that cannot be sampled by area (implicit surfaces, self-intersecting polygons)
    /// still glow when a path hits them, but are never sampled: their MIS weight is 1.
    pub fn new(scene: &Scene) -> Self {
        let triangles = scene.triangles.len();
        let mut prims = Vec::new();
        let mut power = Vec::new();
        // Emissive triangles (the scene's, then instanced ones in world space) come first
        // in `prims`, aligned with `light_triangles`; shapes follow.
        let mut light_triangles = Vec::new();
        let total_prims = triangles + scene.shapes.len() + scene.instanced_triangle_count() as usize;
        let mut prim_pmf = vec![0.0; total_prims];
        let mut push = |prim: usize, area: f32, material: u32| -> bool {
            let m = &scene.materials[material as usize];
            // An emissive texture varies the power over the surface: such emitters are
            // left to the paths that hit them (weight 1), not sampled.
            if let Some(e) = m.emission.as_ref().filter(|_| !m.has_textured_emission()) {
                let p = PI * area * e.luminance().max(0.0);
                if p > 0.0 && p.is_finite() {
                    prims.push(prim as u32);
                    power.push(p as f64);
                    return true;
                }
            }
            false
        };
        // Each light triangle with its area (its pdf follows once the power is summed).
        let mut triangle_light = |prim: usize, vertices: [Vec3; 3], orientation: f32, material: u32| {
            let cross = (vertices[1] - vertices[0]).cross(vertices[2] - vertices[0]);
            let area = 0.5 * cross.length();
            if push(prim, area, material) {
                let normal = cross.normalize() * orientation;
                light_triangles.push(LightTriangle { vertices, normal, area, pdf: 0.0, prim: prim as u32 });
            }
        };
        for (i, &m) in scene.material_ids.iter().enumerate() {
            triangle_light(i, scene.triangle_vertices(i), 1.0, m);
        }
        let mut first = triangles + scene.shapes.len();
        for inst in &scene.instances {
            let o = &scene.objects[inst.object as usize];
            let orientation = if glam::Mat3::from_mat4(inst.transform).determinant() < 0.0 { -1.0 } else { 1.0 };
            for i in 0..o.triangles.len() {
                let m = inst.material_of(o, i);
                let emits = scene.materials[m as usize].emission.is_some();
                if emits {
                    let v = o.triangle_vertices(i).map(|p| inst.transform.transform_point3(p));
                    triangle_light(first + i, v, orientation, m);
                }
            }
            first += o.triangles.len();
        }
        for (k, s) in scene.shapes.iter().enumerate() {
            let shape = s.shape.shape();
            if shape.sample_area(Vec2::splat(0.5)).is_some() {
                push(triangles + k, shape.area(), s.material);
            }
        }
        let needs_radius = scene.environment.is_some()
            || scene.punctual_lights.iter().any(|l| matches!(l, PunctualLight::Directional { .. }));
        let r = if needs_radius { 0.5 * scene.bounds().extent().length().max(1e-3) } else { 1.0 };
        let env_power = scene
            .environment
            .as_ref()
            .map_or(0.0, |env| (4.0 * PI * PI * r * r * env.mean_luminance().max(0.0)) as f64);
        let punctual_power: Vec<f64> = scene
            .punctual_lights
            .iter()
            .map(|l| {
                let p = l.power(r);
                if p > 0.0 && p.is_finite() { p as f64 } else { 0.0 }
            })
            .collect();
        let total: f64 = power.iter().sum::<f64>() + punctual_power.iter().sum::<f64>() + env_power;
        if total <= 0.0 {
            return Self { prim_pmf, ..Default::default() };
        }
        // Point and spot lights first (a stable sort keeps the scene's order within each
        // kind), so that a tree's lights are one stretch.
        let directional = |i: &u32| matches!(scene.punctual_lights[*i as usize], PunctualLight::Directional { .. });
        let mut punctual_order: Vec<u32> = (0..scene.punctual_lights.len() as u32).collect();
        punctual_order.sort_by_key(directional);
        let positioned = punctual_order.partition_point(|i| !directional(i));
        let mut punctual_rank = vec![0; punctual_order.len()];
        for (rank, &i) in punctual_order.iter().enumerate() {
            punctual_rank[i as usize] = rank as u32;
        }
        // The environment owns [0, pmf_env) of the unit interval, primitives the next
        // stretch, punctual lights the rest.
        let mut acc = env_power;
        let bounds = std::iter::once(env_power)
            .chain(power.iter().chain(punctual_order.iter().map(|&i| &punctual_power[i as usize])).map(|p| {
                acc += p;
                acc
            }))
            .map(|a| (a / total) as f32)
            .collect();
        let punctual_pmf: Vec<f32> = punctual_power.iter().map(|p| (p / total) as f32).collect();
        for (&t, p) in prims.iter().zip(&power) {
            prim_pmf[t as usize] = (p / total) as f32;
        }
        let triangles = light_triangles
            .into_iter()
            .map(|t| LightTriangle { pdf: prim_pmf[t.prim as usize] / t.area, ..t })
            .collect();
        let suns = scene
            .punctual_lights
            .iter()
            .enumerate()
            .filter_map(|(k, l)| {
                let (axis, cos_radius, solid_angle) = l.disk()?;
                let pdf = punctual_pmf[k] / solid_angle;
                Some(SunDisk { index: k as u32, axis, cos_radius, radiance_scale: l.disk_radiance_scale(), pdf })
            })
            .collect();
        let environment_map = scene.environment.as_ref().and_then(|e| e.map.clone());
        Self {
            prims,
            triangles,
            bounds,
            prim_pmf,
            punctual_pmf,
            punctual_order,
            punctual_rank,
            positioned,
            environment_map,
            suns,
            tree: None,
        }
    }

    /// [`Lights::new`] with the emitters chosen as `sampler` says.
    pub fn with_sampler(scene: &Scene, sampler: LightSampler) -> Self {
        let lights = Self::new(scene);
        let tree = match sampler {
            LightSampler::Power => false,
            LightSampler::Tree => true,
            LightSampler::Auto => lights.prims.len() + lights.lit_positioned() >= LightSampler::TREE_FROM,
        };
        if tree { lights.with_tree(scene) } else { lights }
    }

    /// The point and spot lights with a share of the power (those a tree holds).
    fn lit_positioned(&self) -> usize {
        self.punctual_order[..self.positioned].iter().filter(|&&i| self.punctual_pmf[i as usize] > 0.0).count()
    }

    /// These lights (of `scene`) with the emitters, point and spot lights chosen by a
    /// light tree ([`LightSampler::Tree`]): [`Lights::sample_at`] and
    /// [`Lights::prim_pmf_at`] then depend on the shading point; [`Lights::sample`] and
    /// [`Lights::prim_pmf`] stay by power. The environment and the directional lights keep
    /// their shares of the unit interval.
    fn with_tree(mut self, scene: &Scene) -> Self {
        if self.prims.len() + self.positioned == 0 {
            return self;
        }
        let mut inv_areas = Vec::with_capacity(self.prims.len() + self.positioned);
        let mut slot = vec![u32::MAX; self.prim_pmf.len()];
        let mut bounds: Vec<tree::LightBounds> = self
            .prims
            .iter()
            .enumerate()
            .map(|(k, &prim)| {
                slot[prim as usize] = k as u32;
                let phi = self.prim_pmf[prim as usize];
                match self.triangles.get(k) {
                    // A triangle emits from its front, within π/2 of its normal.
                    Some(t) => {
                        inv_areas.push(1.0 / t.area);
                        tree::LightBounds {
                            bounds: bvh::Aabb::from_points(&t.vertices),
                            w: t.normal,
                            phi,
                            cos_theta_o: 1.0,
                            cos_theta_e: 0.0,
                        }
                    }
                    // A shape emits from its outside, in every direction.
                    None => {
                        let shape = scene.shapes[prim as usize - scene.triangles.len()].shape.shape();
                        inv_areas.push(1.0 / shape.area());
                        tree::LightBounds {
                            bounds: shape.bounds(),
                            w: Vec3::Z,
                            phi,
                            cos_theta_o: -1.0,
                            cos_theta_e: 0.0,
                        }
                    }
                }
            })
            .collect();
        // The point and spot lights follow, their power in the emitters' units: an
        // emitter's π·A·L is π times the intensity L·A it sends along its normal, so a
        // light of intensity I weighs π·I (pbrt-v4 weighs 4π·I against L·A, which
        // favours punctual lights fourfold).
        for &index in &self.punctual_order[..self.positioned] {
            let light = &scene.punctual_lights[index as usize];
            let (power, pmf) = (light.power(1.0), self.punctual_pmf[index as usize]);
            let phi = if power > 0.0 { pmf * PI * light.colour().luminance().max(0.0) / power } else { 0.0 };
            inv_areas.push(1.0);
            bounds.push(punctual_bounds(light, phi));
        }
        let tree = tree::LightTree::new(&bounds);
        if !tree.is_empty() {
            let (lo, hi) = (self.bounds[0], self.bounds[self.prims.len() + self.positioned]);
            self.tree = Some(LightChoice { tree, inv_areas, slot, lo, hi });
        }
        self
    }

    /// The light tree as flat arrays, for a backend that walks it elsewhere; `None`
    /// without one. Its walk there is [`Lights::sample_at`]'s and its probabilities
    /// [`Lights::prim_pmf_at`]'s.
    pub fn tree_tables(&self) -> Option<LightTreeTables> {
        let c = self.tree.as_ref()?;
        let (nodes, trails) = c.tree.flatten();
        Some(LightTreeTables { nodes, trails, slots: c.slot.clone(), lo: c.lo, hi: c.hi })
    }

    /// Whether the emitters, point and spot lights are chosen by a light tree
    /// ([`LightSampler::Tree`]).
    pub fn has_tree(&self) -> bool {
        self.tree.is_some()
    }

    /// [`Lights::sample`] for a shading point `p` with normal `n` (zero: none): with a
    /// light tree an emitter, point or spot light is chosen by it, with the pdf of that
    /// choice.
    #[inline]
    pub fn sample_at(&self, scene: &Scene, u: Vec2, p: Vec3, n: Vec3) -> Option<LightSample> {
        let Some(c) = &self.tree else { return self.sample(scene, u) };
        if !c.holds(u.x) {
            // The environment's or a directional light's stretch, as without the tree.
            return self.sample(scene, u);
        }
        let (k, x, pdf) = c.choose(u.x, p, n)?;
        self.sample_entry(scene, k, Vec2::new(x, u.y), Some(pdf))
    }

    /// [`Lights::choose`] for a shading point `p` with normal `n`, as [`Lights::sample_at`]
    /// chooses: the light's index, `x` rescaled within its stretch and, where a light tree
    /// chose it, the choice's probability over the light's area (a point or spot light's:
    /// the probability; `None`: the light's own by power). `None`
    /// where the tree's walk finds nothing to choose. The caller checks as `choose` asks.
    #[inline(always)]
    pub(crate) fn choose_at(&self, x: f32, p: Vec3, n: Vec3) -> Option<(usize, f32, Option<f32>)> {
        match &self.tree {
            Some(c) if c.holds(x) => c.choose(x, p, n).map(|(k, x, pdf)| (k, x, Some(pdf))),
            _ => {
                let (k, x) = self.choose(x);
                Some((k, x, None))
            }
        }
    }

    /// The probability that [`Lights::sample_at`] picks primitive `prim` for `p`, `n`.
    #[inline]
    pub fn prim_pmf_at(&self, prim: u32, p: Vec3, n: Vec3) -> f32 {
        let Some(choice) = &self.tree else { return self.prim_pmf(prim) };
        match choice.slot.get(prim as usize) {
            Some(&k) if k != u32::MAX => (choice.hi - choice.lo) * choice.tree.pmf(k as usize, p, n),
            _ => 0.0,
        }
    }

    /// The probability that [`Lights::sample_at`] picks punctual light `index` (of
    /// [`Scene::punctual_lights`]) for `p`, `n`: by the tree for a point or spot light
    /// where there is one, else its share of the power.
    pub fn punctual_pmf_at(&self, index: usize, p: Vec3, n: Vec3) -> f32 {
        let rank = self.punctual_rank.get(index).map(|&r| r as usize);
        match (&self.tree, rank) {
            (Some(c), Some(j)) if j < self.positioned => (c.hi - c.lo) * c.tree.pmf(self.prims.len() + j, p, n),
            _ => self.punctual_pmf(index),
        }
    }

    /// The sun disks (directional lights with an angular size), which escaping rays see.
    #[inline]
    pub fn suns(&self) -> &[SunDisk] {
        &self.suns
    }

    /// A light sample on punctual light `index` given that it was chosen: its position or
    /// direction with pdf 1 for a delta light; for a sun disk a direction drawn uniformly
    /// within it from `u`, with the solid-angle pdf 1/(2π(1 − cos r)).
    #[inline]
    pub fn sample_punctual(scene: &Scene, index: usize, u: Vec2) -> LightSample {
        let light = &scene.punctual_lights[index];
        let source = LightSource::Punctual(index as u32);
        match light.disk() {
            None => LightSample { point: light.towards(), normal: Vec3::ZERO, pdf: 1.0, source },
            Some((axis, cos_radius, solid_angle)) => {
                let cos_theta = 1.0 - u.x * (1.0 - cos_radius);
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                let (s, c) = (std::f32::consts::TAU * u.y).sin_cos();
                let (t, b) = axis.any_orthonormal_pair();
                let dir = (cos_theta * axis + sin_theta * (c * t + s * b)).normalize();
                LightSample { point: dir, normal: Vec3::ZERO, pdf: 1.0 / solid_angle, source }
            }
        }
    }

    /// True if there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        // With any light, the environment's share (possibly 0) leads the bounds.
        self.bounds.is_empty()
    }

    /// The probability that [`Lights::sample`] picks punctual light `index`.
    pub fn punctual_pmf(&self, index: usize) -> f32 {
        self.punctual_pmf.get(index).copied().unwrap_or(0.0)
    }

    /// The punctual lights (indices into [`Scene::punctual_lights`]) in the order of their
    /// entries in [`Lights::cdf`], which follow the primitives': the point and spot
    /// lights, then the directional ones, each in the scene's order.
    pub fn punctual_entries(&self) -> &[u32] {
        &self.punctual_order
    }

    /// Number of emissive primitives that are sampled.
    pub fn emitter_count(&self) -> usize {
        self.prims.len()
    }

    /// The sampled emissive primitives (triangles first, then shapes), in the order of
    /// [`Lights::cdf`]; for backends that rebuild the distribution elsewhere (the GPU).
    pub fn prims(&self) -> &[u32] {
        &self.prims
    }

    /// The cumulative distribution over [`Lights::prims`], then the scene's punctual
    /// lights in the order of [`Lights::punctual_entries`]: entry k is the probability of
    /// picking the environment or one of entries 0..=k (the environment owns [0, [`Lights::environment_pmf`])). [`Lights::sample`]
    /// picks the first k with `cdf[k] > u` (clamped to the last).
    pub fn cdf(&self) -> &[f32] {
        self.bounds.get(1..).unwrap_or_default()
    }

    /// The probability of picking each primitive, indexed by primitive id (0 for
    /// primitives that are not sampled); [`Lights::prim_pmf`] for all of them at once.
    pub fn prim_pmfs(&self) -> &[f32] {
        &self.prim_pmf
    }

    /// The probability that [`Lights::sample`] picks primitive `prim`.
    #[inline]
    pub fn prim_pmf(&self, prim: u32) -> f32 {
        self.prim_pmf.get(prim as usize).copied().unwrap_or(0.0)
    }

    /// The probability that [`Lights::sample`] picks the environment.
    #[inline]
    pub fn environment_pmf(&self) -> f32 {
        self.bounds.first().copied().unwrap_or(0.0)
    }

    /// Solid-angle pdf with which [`Lights::sample`] draws environment direction `dir`
    /// (choice of the environment included): uniform, or by the map's luminance.
    #[inline]
    pub fn environment_pdf(&self, dir: Vec3) -> f32 {
        self.environment_pmf() * self.environment_map.as_ref().map_or(UNIFORM_SPHERE_PDF, |m| m.pdf(dir))
    }

    /// The light whose stretch of the unit interval holds `x` (the first coordinate of
    /// [`Lights::sample`]'s sample: index k into the primitives, then the punctual lights
    /// in the order of [`Lights::punctual_entries`]), and `x` rescaled to [0, 1) within that stretch. The caller checks that
    /// there is a light and that `x` is past the environment's share.
    #[inline(always)]
    pub(crate) fn choose(&self, x: f32) -> (usize, f32) {
        let cdf = self.cdf();
        let k = cdf.partition_point(|&c| c <= x).min(cdf.len() - 1);
        (k, rescale(x, self.bounds[k], cdf[k]))
    }

    /// [`Lights::sample_entry`]'s sample of light `k` if it is a punctual light: its
    /// sample from `u` ([`Lights::sample_punctual`]), chosen with probability `pdf` (by
    /// power where `None`).
    #[inline(always)]
    pub(crate) fn punctual_entry(&self, scene: &Scene, k: usize, u: Vec2, pdf: Option<f32>) -> Option<LightSample> {
        let index = *k.checked_sub(self.prims.len()).and_then(|j| self.punctual_order.get(j))? as usize;
        let ls = Self::sample_punctual(scene, index, u);
        Some(LightSample { pdf: ls.pdf * pdf.unwrap_or(self.punctual_pmf[index]), ..ls })
    }

    /// Light `k` of [`Lights::choose`] if it is one of the emissive triangles.
    #[inline(always)]
    pub(crate) fn triangle_light(&self, k: usize) -> Option<&LightTriangle> {
        self.triangles.get(k)
    }

    /// Picks a light with `u.x`, then a point on it with `u`, `u.x` rescaled to [0, 1)
    /// within the chosen light's share of the unit interval (sample reuse, as Mitsuba 3
    /// does): one 2-D sample covers all the lights, so a stratified `u` stays stratified over
    /// their union — over both triangles of a quad light, instead of per triangle with a
    /// separate 1-D choice.
    #[inline(always)]
    pub fn sample(&self, scene: &Scene, u: Vec2) -> Option<LightSample> {
        if self.is_empty() {
            return None;
        }
        let cdf = self.cdf();
        let environment_pmf = self.environment_pmf();
        if u.x < environment_pmf || cdf.is_empty() {
            // Without other lights the environment's share is the whole interval (pmf 1).
            let u = Vec2::new(rescale(u.x, 0.0, environment_pmf), u.y);
            let (point, pdf) = match &self.environment_map {
                None => (uniform_sphere(u), UNIFORM_SPHERE_PDF),
                Some(map) => map.sample(u)?,
            };
            return Some(LightSample {
                point,
                normal: Vec3::ZERO,
                pdf: environment_pmf * pdf,
                source: LightSource::Environment,
            });
        }
        let (k, x) = self.choose(u.x);
        self.sample_entry(scene, k, Vec2::new(x, u.y), None)
    }

    /// A sample of entry `k` of [`Lights::cdf`] from `u`: a point on an emitter (an index
    /// into the primitives) with density `pdf` per unit area (the choice's probability
    /// over the area), or with the choice by power where `None` (a triangle's
    /// precomputed density, a shape's probability over its area); past the primitives a
    /// punctual light's sample, chosen with probability `pdf` (by power where `None`).
    #[inline(always)]
    fn sample_entry(&self, scene: &Scene, k: usize, u: Vec2, pdf: Option<f32>) -> Option<LightSample> {
        if let Some(ls) = self.punctual_entry(scene, k, u, pdf) {
            return Some(ls);
        }
        if let Some(t) = self.triangle_light(k) {
            let [v0, v1, v2] = t.vertices;
            let (b0, b1) = uniform_triangle(u);
            let point = Vec3::new(
                on_triangle(b0, b1, [v0.x, v1.x, v2.x]),
                on_triangle(b0, b1, [v0.y, v1.y, v2.y]),
                on_triangle(b0, b1, [v0.z, v1.z, v2.z]),
            );
            return Some(LightSample {
                point,
                normal: t.normal,
                pdf: pdf.unwrap_or(t.pdf),
                source: LightSource::Primitive(t.prim),
            });
        }
        let prim = self.prims[k];
        let source = LightSource::Primitive(prim);
        let shape = scene.shapes[prim as usize - scene.triangles.len()].shape.shape();
        let (point, normal) = shape.sample_area(u)?;
        let pdf = pdf.unwrap_or_else(|| self.prim_pmf[prim as usize] / shape.area());
        Some(LightSample { point, normal, pdf, source })
    }
}

/// A point or spot light's bounds in a light tree, with power `phi` (pbrt-v4's
/// `PointLight::Bounds` and `SpotLight::Bounds`): at one point, emitting in every
/// direction (θo = π), or, for a spot, fully within its inner cone (θo) and fading to
/// nothing at its outer one (θe = θ_outer − θ_inner). Two cases pbrt-v4 gets wrong are
/// kept conservative, as the tree's estimate must be (zero only where the light gives
/// nothing): a cone widened by more than π/2 would give directions past θo + π/2 a
/// negative cosine and an estimate of zero, so θo takes the excess (θe ≤ π/2); and a
/// hard-edged spot (θe = 0, cos θe = 1) would never pass the estimate's test cos θ' >
/// cos θe, so cos θe stays just below 1.
fn punctual_bounds(light: &PunctualLight, phi: f32) -> tree::LightBounds {
    let point = light.towards();
    let bounds = bvh::Aabb { min: point, max: point };
    match *light {
        PunctualLight::Spot { direction, cos_inner, cos_outer, .. } => {
            let angle = |c: f32| c.clamp(-1.0, 1.0).acos();
            let inner = angle(cos_inner);
            let outer = angle(cos_outer).max(inner);
            let theta_o = inner.max(outer - std::f32::consts::FRAC_PI_2);
            let cos_theta_e = (outer - theta_o).cos().min(ONE_MINUS_EPSILON);
            tree::LightBounds { bounds, w: direction, phi, cos_theta_o: theta_o.cos(), cos_theta_e }
        }
        _ => tree::LightBounds { bounds, w: Vec3::Z, phi, cos_theta_o: -1.0, cos_theta_e: 0.0 },
    }
}

/// The largest f32 below 1: where a rescaled sample value is clamped.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// `x` ∈ [lo, hi) mapped to [0, 1), kept below 1 where rounding would reach it.
#[inline]
fn rescale(x: f32, lo: f32, hi: f32) -> f32 {
    let width = hi - lo;
    if width > 0.0 { ((x - lo) / width).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::mesh::quad;
    use crate::scene::Environment;
    use spectral::spectrum::Colour;

    /// A quad light (two triangles, 1×1), a dimmer and smaller one (0.5×0.5) and a sky.
    fn scene() -> Scene {
        let mut s = Scene::default();
        let lamp = |name: &str, e: f32| {
            Material::diffuse(name, Colour::constant(0.0)).unwrap().with_emission(Colour::constant(e))
        };
        s.add(&quad(Vec3::new(0.0, 2.0, 0.0), -Vec3::Y, 0.5), lamp("big", 4.0));
        s.add(&quad(Vec3::new(3.0, 2.0, 0.0), -Vec3::Y, 0.25), lamp("small", 2.0));
        s.environment = Some(Environment::uniform(Colour::constant(0.01)));
        s
    }

    #[test]
    fn one_stratified_2d_sample_covers_all_lights_in_proportion_and_each_uniformly() {
        let scene = scene();
        let lights = Lights::new(&scene);
        assert_eq!(lights.emitter_count(), 4);
        // Jittered u, one per cell of a 256 × 256 grid: every light is picked in proportion
        // to its share of the unit interval, and the points on the big quad fill its 8 × 8
        // cells evenly across both triangles (u.x reused within each light).
        let n = 256;
        let mut rng = rng::Pcg32::seed_from_u64(5);
        let mut env = 0usize;
        let mut per_prim = [0usize; 4];
        let mut cells = [[0usize; 8]; 8];
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + rng.next_f32()) / n as f32, (j as f32 + rng.next_f32()) / n as f32);
                let ls = lights.sample(&scene, u).unwrap();
                assert!(ls.pdf > 0.0 && ls.pdf.is_finite() && ls.point.is_finite());
                match ls.source {
                    LightSource::Punctual(_) => unreachable!("the scene has none"),
                    LightSource::Environment => {
                        env += 1;
                        assert!((ls.point.length() - 1.0).abs() < 1e-5, "a unit direction");
                    }
                    LightSource::Primitive(p) => {
                        per_prim[p as usize] += 1;
                        assert_eq!(ls.pdf, lights.prim_pmf(p) / if p < 2 { 0.5 } else { 0.125 });
                        if p < 2 {
                            let (x, z) = (ls.point.x + 0.5, ls.point.z + 0.5);
                            assert!((0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&z), "{:?}", ls.point);
                            cells[((x * 8.0) as usize).min(7)][((z * 8.0) as usize).min(7)] += 1;
                        }
                    }
                }
            }
        }
        let total = (n * n) as f64;
        assert!((env as f64 / total - lights.environment_pmf() as f64).abs() < 2.0 / n as f64, "{env}");
        for p in 0..4u32 {
            let share = per_prim[p as usize] as f64 / total;
            assert!((share - lights.prim_pmf(p) as f64).abs() < 2.0 / n as f64, "light {p}: {share}");
        }
        let big = (per_prim[0] + per_prim[1]) as f64 / 64.0;
        for row in &cells {
            for &c in row {
                // Uniform: each cell within 4.5 binomial standard deviations of its share.
                assert!((c as f64 - big).abs() < 4.5 * big.sqrt(), "cell {c} vs {big}: {cells:?}");
            }
        }
    }

    #[test]
    fn an_environment_alone_takes_the_sample_unchanged() {
        let scene = Scene { environment: Some(Environment::uniform(Colour::constant(1.0))), ..Scene::default() };
        let lights = Lights::new(&scene);
        assert_eq!(lights.environment_pmf(), 1.0);
        for u in [Vec2::new(0.0, 0.3), Vec2::new(0.37, 0.9), Vec2::new(ONE_MINUS_EPSILON, 0.5)] {
            let ls = lights.sample(&scene, u).unwrap();
            assert_eq!((ls.point, ls.source), (uniform_sphere(u), LightSource::Environment));
        }
    }

    #[test]
    fn punctual_lights_are_chosen_by_power_beside_the_emitters() {
        let mut scene = scene();
        // A sun of irradiance 2 over the scene's disc (power 2πr²) and a point light of
        // intensity 1 (power 4π), whose entry comes first (point and spot lights lead).
        scene.punctual_lights.push(PunctualLight::directional(Vec3::new(0.0, -2.0, 0.0), Colour::constant(2.0)));
        scene.punctual_lights.push(PunctualLight::point(Vec3::new(0.0, 5.0, 0.0), Colour::constant(1.0)));
        let lights = Lights::new(&scene);
        assert_eq!(lights.punctual_entries(), [1, 0]);
        let r = 0.5 * scene.bounds().extent().length();
        let powers = [2.0 * PI * r * r, 4.0 * PI];
        let emitters = PI * (1.0 * 4.0 + 0.25 * 2.0);
        let sky = 4.0 * PI * PI * r * r * 0.01;
        let total = powers[0] + powers[1] + emitters + sky;
        for (i, p) in powers.iter().enumerate() {
            assert!((lights.punctual_pmf(i) - p / total).abs() < 1e-5, "{i}: {}", lights.punctual_pmf(i));
        }
        let n = 4096;
        let mut picked = [0usize; 2];
        for i in 0..n {
            let ls = lights.sample(&scene, Vec2::new((i as f32 + 0.5) / n as f32, 0.5)).unwrap();
            if let LightSource::Punctual(k) = ls.source {
                picked[k as usize] += 1;
                assert_eq!(ls.pdf, lights.punctual_pmf(k as usize));
                let expect = if k == 1 { Vec3::new(0.0, 5.0, 0.0) } else { Vec3::Y };
                assert!((ls.point - expect).length() < 1e-6, "towards the light: {}", ls.point);
            }
        }
        for k in 0..2 {
            let share = picked[k] as f32 / n as f32;
            assert!((share - lights.punctual_pmf(k)).abs() < 2.0 / n as f32, "{k}: {share}");
        }
    }

    /// With a light tree beside a sky and a sun, `sample_at` over a fine grid of the first
    /// sample value picks the sky and the sun with their power shares (the same as without
    /// the tree) and each emitter and the point light with the tree's probability for the
    /// shading point (`prim_pmf_at`, `punctual_pmf_at`), their frequencies summing to at
    /// most their share; each emitter's area density is that probability over its area,
    /// the point light's sample has it as its pdf.
    #[test]
    fn a_light_tree_chooses_within_its_lights_share_only() {
        let mut scene = scene();
        scene.punctual_lights.push(PunctualLight::directional(Vec3::new(0.3, -2.0, 0.0), Colour::constant(0.1)));
        scene.punctual_lights.push(PunctualLight::point(Vec3::new(0.0, 5.0, 0.0), Colour::constant(1.0)));
        let lights = Lights::with_sampler(&scene, LightSampler::Tree);
        assert!(lights.has_tree());
        let (p, n) = (Vec3::new(2.5, 0.0, 0.3), Vec3::Y);
        let count = 1 << 16;
        let (mut sky, mut sun, mut point, mut none) = (0usize, 0usize, 0usize, 0usize);
        let mut prims = vec![0usize; scene.triangles.len()];
        for i in 0..count {
            let u = Vec2::new((i as f32 + 0.5) / count as f32, 0.31);
            match lights.sample_at(&scene, u, p, n).map(|ls| (ls.source, ls.pdf)) {
                Some((LightSource::Environment, _)) => sky += 1,
                Some((LightSource::Punctual(0), pdf)) => {
                    assert_eq!(pdf, lights.punctual_pmf(0));
                    sun += 1
                }
                Some((LightSource::Punctual(k), pdf)) => {
                    assert_eq!((k, pdf), (1, lights.punctual_pmf_at(1, p, n)));
                    point += 1
                }
                Some((LightSource::Primitive(t), pdf)) => {
                    let [a, b, c] = scene.triangle_vertices(t as usize);
                    let area = 0.5 * (b - a).cross(c - a).length();
                    let pmf = lights.prim_pmf_at(t, p, n);
                    assert!((pdf * area - pmf).abs() <= 1e-5 * pmf, "triangle {t}: pdf {pdf}, pmf {pmf}");
                    prims[t as usize] += 1
                }
                None => none += 1,
            }
        }
        let frequency = |k: usize| k as f32 / count as f32;
        let tolerance = 2.0 / count as f32;
        assert!((frequency(sky) - lights.environment_pmf()).abs() < tolerance, "sky {}", frequency(sky));
        assert!((frequency(sun) - lights.punctual_pmf(0)).abs() < tolerance, "sun {}", frequency(sun));
        let point_pmf = lights.punctual_pmf_at(1, p, n);
        assert!((frequency(point) - point_pmf).abs() < 1e-3, "point {} against {point_pmf}", frequency(point));
        assert!(point_pmf > 0.0 && point_pmf != lights.punctual_pmf(1), "the tree's own probability");
        let mut sum = point_pmf;
        for (t, &k) in prims.iter().enumerate() {
            let pmf = lights.prim_pmf_at(t as u32, p, n);
            // Stratified draws: within a few cells of the walk's nested rescalings.
            assert!((frequency(k) - pmf).abs() < 1e-3, "triangle {t}: drawn {}, pmf {pmf}", frequency(k));
            sum += pmf;
        }
        let share = 1.0 - lights.environment_pmf() - lights.punctual_pmf(0);
        assert!(sum <= share + 1e-5 && (frequency(none) - (share - sum)).abs() < 1e-3, "{sum} of {share}, none {none}");
        // Both lamps face down over the point: all four triangles are chosen.
        assert!(prims.iter().all(|&k| k > 0), "{prims:?}");
        // The tables another backend walks: the stretch, and each emitter's entry by id.
        let t = lights.tree_tables().expect("a tree");
        assert_eq!(t.lo, lights.environment_pmf());
        assert!((t.hi - t.lo - share).abs() < 1e-6, "{t:?}");
        assert_eq!(t.slots.len(), scene.triangles.len());
        for (id, &k) in t.slots.iter().enumerate() {
            assert_eq!(lights.prims().iter().position(|&p| p as usize == id).map_or(u32::MAX, |k| k as u32), k);
        }
        // The point light is the tree's light after the emitters, the sun in none.
        assert_eq!(t.trails.len(), lights.prims().len() + 1);
        assert!(Lights::with_sampler(&scene, LightSampler::Power).tree_tables().is_none());
    }

    /// A tree holding only point and spot lights chooses by what each gives the shading
    /// point: a near light more often than an equal far one, a spot aimed away never
    /// (its cone bounds it), one aimed at the point in proportion; the probabilities over
    /// the lights that can reach the point sum to one.
    #[test]
    fn point_and_spot_lights_in_a_tree_are_chosen_by_what_they_give_the_point() {
        let mut scene = Scene::default();
        let white = Colour::constant(1.0);
        let (near, far) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 4.0, 0.0));
        scene.punctual_lights.push(PunctualLight::point(near, white.clone()));
        scene.punctual_lights.push(PunctualLight::point(far, white.clone()));
        let (inner, outer) = (0.3, 0.5);
        scene.punctual_lights.push(PunctualLight::spot(Vec3::new(1.0, 1.0, 0.0), Vec3::Y, white.clone(), inner, outer));
        let aimed = Vec3::new(-1.0, -1.0, 0.0).normalize();
        scene.punctual_lights.push(PunctualLight::spot(Vec3::new(1.0, 1.0, 0.0), aimed, white, inner, outer));
        let lights = Lights::with_sampler(&scene, LightSampler::Tree);
        assert!(lights.has_tree() && lights.emitter_count() == 0);
        let (p, n) = (Vec3::ZERO, Vec3::Y);
        let pmf: Vec<f32> = (0..4).map(|k| lights.punctual_pmf_at(k, p, n)).collect();
        // Power sampling would take the two points equally.
        assert!(pmf[0] > 4.0 * pmf[1], "near {} against far {}", pmf[0], pmf[1]);
        assert_eq!(pmf[2], 0.0, "a spot aimed away");
        assert!(pmf[3] > 0.0);
        assert!((pmf.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{pmf:?}");
        // The walk draws them so.
        let count = 1 << 14;
        let mut drawn = [0usize; 4];
        for i in 0..count {
            let u = Vec2::new((i as f32 + 0.5) / count as f32, 0.5);
            let ls = lights.sample_at(&scene, u, p, n).expect("a light reaches the point");
            let LightSource::Punctual(k) = ls.source else { panic!("{:?}", ls.source) };
            assert_eq!(ls.pdf, pmf[k as usize]);
            drawn[k as usize] += 1;
        }
        for k in 0..4 {
            assert!((drawn[k] as f32 / count as f32 - pmf[k]).abs() < 1e-3, "light {k}: {drawn:?} against {pmf:?}");
        }
    }

    /// The tree's estimate for a spot is zero only where it gives nothing: around spots
    /// of every shape — hard-edged (inner = outer, and inner > outer, which `spot` makes
    /// hard-edged), a falloff wider than a right angle (0° to 120°), an ordinary one — a
    /// point in each direction (every degree from the axis to behind it) where the
    /// falloff is positive has a positive probability, and one more than a degree past the
    /// outer cone has none.
    #[test]
    fn spots_of_every_shape_are_chosen_wherever_they_shine() {
        let (at, axis) = (Vec3::new(0.5, 2.0, -1.0), Vec3::new(0.3, -1.0, 0.2).normalize());
        let side = axis.any_orthonormal_vector();
        for (inner, outer) in [(25.0f32, 25.0f32), (40.0, 30.0), (0.0, 120.0), (20.0, 45.0)] {
            let mut scene = Scene::default();
            let spot = PunctualLight::spot(at, axis, Colour::constant(2.0), inner.to_radians(), outer.to_radians());
            let PunctualLight::Spot { cos_inner, cos_outer, .. } = spot else { unreachable!() };
            scene.punctual_lights.push(spot);
            let lights = Lights::with_sampler(&scene, LightSampler::Tree);
            for degrees in 0..=180 {
                let theta = (degrees as f32).to_radians();
                let p = at + 2.0 * (theta.cos() * axis + theta.sin() * side);
                let falloff = PunctualLight::spot_falloff(theta.cos(), cos_inner, cos_outer);
                let pmf = lights.punctual_pmf_at(0, p, Vec3::ZERO);
                let past = degrees as f32 > inner.max(outer) + 1.0;
                assert!(pmf.is_finite() && (falloff <= 0.0 || pmf > 0.0), "{inner}°/{outer}° at {degrees}°: {pmf}");
                assert!(!past || pmf == 0.0, "{inner}°/{outer}° at {degrees}°: {pmf} past the cone");
            }
        }
    }

    /// A point light without power is left out of the tree (never drawn, probability 0,
    /// not counted towards `auto`'s threshold), and a shading point at a point light's
    /// position gets another light with a finite pdf, not a NaN.
    #[test]
    fn dark_point_lights_and_points_at_a_light_are_harmless() {
        let mut scene = Scene::default();
        let at = |i: usize| Vec3::new(i as f32, 2.0, 0.0);
        for i in 0..LightSampler::TREE_FROM - 1 {
            scene.punctual_lights.push(PunctualLight::point(at(i), Colour::constant(1.0)));
        }
        scene.punctual_lights.push(PunctualLight::point(at(9), Colour::constant(0.0)));
        assert!(!Lights::with_sampler(&scene, LightSampler::Auto).has_tree(), "7 lit point lights and a dark one");
        let lights = Lights::with_sampler(&scene, LightSampler::Tree);
        let dark = LightSampler::TREE_FROM - 1;
        let count = 4096;
        // (Points without a normal: the lights lie in the plane at y = 2 through the last two.)
        for p in [Vec3::new(3.2, 0.0, 0.5), at(9), at(2)] {
            assert_eq!(lights.punctual_pmf_at(dark, p, Vec3::ZERO), 0.0);
            for i in 0..count {
                let u = Vec2::new((i as f32 + 0.5) / count as f32, 0.5);
                let ls = lights.sample_at(&scene, u, p, Vec3::ZERO).expect("a lit light");
                assert!(ls.pdf > 0.0 && ls.pdf.is_finite(), "{p}: {ls:?}");
                assert_ne!(ls.source, LightSource::Punctual(dark as u32));
                assert!(p != at(2) || ls.source != LightSource::Punctual(2), "the light at the point itself");
            }
        }
    }

    #[test]
    fn rescaled_values_stay_below_one() {
        assert_eq!(rescale(0.75, 0.5, 0.75), ONE_MINUS_EPSILON);
        assert_eq!(rescale(0.5, 0.5, 0.75), 0.0);
        assert_eq!(rescale(0.6, 0.5, 0.5), 0.0, "an empty interval");
        const { assert!(ONE_MINUS_EPSILON < 1.0 && ONE_MINUS_EPSILON + f32::EPSILON / 2.0 == 1.0) };
    }
}
