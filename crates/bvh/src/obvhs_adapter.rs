//! [obvhs](https://github.com/DGriffin91/obvhs) 0.4's BVHs behind our [`Accelerator`] trait, as a
//! yardstick for our own builders:
//!
//! * [`ObvhsBvh2`]: obvhs's binary BVH (PLOC build, reinsertion, leaf collapsing), traversed by
//!   `Bvh2::ray_traverse` / `ray_traverse_miss`;
//! * [`ObvhsCwBvh`]: obvhs's compressed 8-wide BVH (Ylitie et al. 2017), traversed by its SIMD
//!   `CwBvh::ray_traverse` / `ray_traverse_miss`.
//!
//! Both use obvhs only to find candidate triangles: every ray–triangle test is our
//! [`intersect_triangle`] on our [`Ray`], so hits (t, u, v) are bit-identical to ours and
//! [`Hit::prim`] is the index in the input slice.
//!
//! Known difference: obvhs's CWBVH node test clips the ray at t ≥ 10⁻⁴ (a constant of
//! obvhs, not `t_min`), so hits closer than 10⁻⁴ ray-parameter units to the origin can be
//! missed by [`ObvhsCwBvh`]. Offset secondary-ray origins (as ours are) avoid this.

use crate::{
    Aabb, Accelerator, BuildConfig, BuildError, BvhStats, Hit, Ray, RayStats, Triangle, intersect_triangle, validate,
};
use glam::{UVec2, Vec3};
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::RayHit;
use std::time::{Duration, Instant};

/// obvhs's build presets (`BvhBuildParams::*_build`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ObvhsQuality {
    /// `fastest_build`: PLOC with the smallest search distance, no reinsertion, one
    /// triangle per BVH2 leaf.
    Fastest,
    /// `medium_build`: "around the same build time as Embree but with faster traversal";
    /// PLOC search distance 14 (medium), 5 % reinsertion, up to 8 triangles per BVH2 leaf
    /// (3 for the CWBVH).
    Medium,
    /// `slow_build`: spatial pre-splits of large triangles, a wider PLOC search, 20 %
    /// reinsertion, 128-bit Morton codes.
    Slow,
}

impl ObvhsQuality {
    /// Every preset, fastest first.
    pub const ALL: [Self; 3] = [Self::Fastest, Self::Medium, Self::Slow];

    /// obvhs's build parameters for this preset.
    pub fn params(self) -> BvhBuildParams {
        match self {
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::Slow => BvhBuildParams::slow_build(),
        }
    }

    /// A short name for tables and benchmark ids.
    pub fn name(self) -> &'static str {
        match self {
            Self::Fastest => "fastest",
            Self::Medium => "medium",
            Self::Slow => "slow",
        }
    }
}

/// obvhs's own triangle type, used for its AABBs and pre-splits only.
fn obvhs_triangles(triangles: &[[Vec3; 3]]) -> Vec<obvhs::triangle::Triangle> {
    triangles.iter().map(|t| obvhs::triangle::Triangle { v0: t[0].into(), v1: t[1].into(), v2: t[2].into() }).collect()
}

/// The same ray for obvhs. Its slab tests use `safe_inverse` (±1/ε for zero direction
/// components) and only look at `tmax`; `t_min` is enforced by our triangle test.
///
/// −0 direction components become +0: obvhs's CWBVH node test picks near/far planes by
/// `dir < 0` but `safe_inverse(−0)` is −1/ε, so an axis-parallel ray such as −z, whose x
/// and y are −0, would miss every box (obvhs 0.4 bug).
#[inline]
fn obvhs_ray(ray: &Ray) -> obvhs::ray::Ray {
    let dir = glam::Vec3A::from(ray.dir) + glam::Vec3A::ZERO;
    obvhs::ray::Ray::new(ray.origin.into(), dir, ray.t_min, ray.t_max)
}

/// Bounds of the input triangles.
fn bounds_of(triangles: &[[Vec3; 3]]) -> Aabb {
    triangles.iter().fold(Aabb::EMPTY, |b, t| b.union(Triangle::bounds(t)))
}

/// Our triangles laid out in the order of obvhs's `primitive_indices` (so leaves index them
/// directly), with each one's index in the input. With spatial pre-splits a triangle may
/// appear more than once.
#[derive(Clone, Debug, Default)]
struct LeafTriangles {
    triangles: Vec<Triangle>,
    ids: Vec<u32>,
}

impl LeafTriangles {
    /// obvhs's primitive callback for closest-hit traversal: tests leaf slot `i`, keeps
    /// a closer hit in `best`, and returns its t (∞ for none) for obvhs to shrink t_max.
    #[inline]
    fn record(&self, i: usize, ray: &Ray, t_max: f32, best: &mut Option<Hit>) -> f32 {
        match self.hit(i, ray, t_max) {
            Some(h) => {
                *best = Some(h);
                h.t
            }
            None => f32::INFINITY,
        }
    }

    fn new(input: &[[Vec3; 3]], primitive_indices: &[u32]) -> Self {
        Self {
            triangles: primitive_indices.iter().map(|&i| Triangle::new(&input[i as usize])).collect(),
            ids: primitive_indices.to_vec(),
        }
    }

    /// Our Möller–Trumbore test of leaf-order triangle `i` against `ray`, clipped at `t_max`.
    #[inline]
    fn hit(&self, i: usize, ray: &Ray, t_max: f32) -> Option<Hit> {
        intersect_triangle(&self.triangles[i], ray, t_max).map(|(t, u, v)| Hit { prim: self.ids[i], t, u, v })
    }

    /// The hit distance as obvhs's closures want it: +∞ for a miss.
    #[inline]
    fn distance(&self, i: usize, ray: &Ray, t_max: f32) -> f32 {
        intersect_triangle(&self.triangles[i], ray, t_max).map_or(f32::INFINITY, |(t, _, _)| t)
    }
}

/// Area of one of obvhs's boxes (zero if empty or inverted).
fn area(b: &obvhs::aabb::Aabb) -> f64 {
    let e = (b.max - b.min).max(glam::Vec3A::ZERO);
    2.0 * (e.x as f64 * e.y as f64 + e.y as f64 * e.z as f64 + e.z as f64 * e.x as f64)
}

/// obvhs's binary BVH.
#[derive(Clone)]
pub struct ObvhsBvh2 {
    bvh: Bvh2,
    leaves: LeafTriangles,
    bounds: Aabb,
    build_time: Duration,
    core_build_time: Duration,
}

impl std::fmt::Debug for ObvhsBvh2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObvhsBvh2").field("nodes", &self.bvh.nodes.len()).field("bounds", &self.bounds).finish()
    }
}

impl ObvhsBvh2 {
    /// Builds with `obvhs::bvh2::builder::build_bvh2_from_tris` and the preset's parameters;
    /// rejects non-finite coordinates. An empty input gives a structure nothing hits.
    pub fn build(triangles: &[[Vec3; 3]], quality: ObvhsQuality) -> Result<Self, BuildError> {
        // What our own builders reject: NaN/∞ (obvhs has crashed on infinite boxes).
        validate(triangles)?;
        let start = Instant::now();
        let mut core_build_time = Duration::ZERO;
        let bvh = if triangles.is_empty() {
            Bvh2::default()
        } else {
            obvhs::bvh2::builder::build_bvh2_from_tris(
                &obvhs_triangles(triangles),
                quality.params(),
                &mut core_build_time,
            )
        };
        let leaves = LeafTriangles::new(triangles, &bvh.primitive_indices);
        let build_time = start.elapsed();
        Ok(Self { bvh, leaves, bounds: bounds_of(triangles), build_time, core_build_time })
    }

    /// Wall time of [`ObvhsBvh2::build`], conversions included (in debug builds also
    /// obvhs's self-validation).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// obvhs's own "core" build time: PLOC, reinsertion and collapsing, without AABB
    /// set-up or our triangle reordering.
    pub fn core_build_time(&self) -> Duration {
        self.core_build_time
    }

    /// The underlying obvhs tree.
    pub fn inner(&self) -> &Bvh2 {
        &self.bvh
    }

    /// Nodes reachable from the root, leaves among them, depth (root = 1) and the SAH
    /// cost with the given constants, computed exactly as [`crate::Bvh::stats`] does.
    pub fn stats_with_costs(&self, traversal_cost: f32, intersection_cost: f32) -> BvhStats {
        let mut s = BvhStats::default();
        let Some(root) = self.bvh.nodes.first() else {
            return s;
        };
        let root_area = area(root.aabb()).max(f32::MIN_POSITIVE as f64);
        let mut cost = 0.0f64;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.bvh.nodes[i];
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            let a = area(n.aabb()) / root_area;
            if n.is_leaf() {
                s.leaves += 1;
                cost += a * n.prim_count as f64 * intersection_cost as f64;
            } else {
                cost += a * traversal_cost as f64;
                stack.push((n.first_index as usize, depth + 1));
                stack.push((n.first_index as usize + 1, depth + 1));
            }
        }
        s.sah_cost = cost as f32;
        s
    }

    /// [`ObvhsBvh2::stats_with_costs`] with [`BuildConfig::default`]'s cost constants.
    pub fn stats(&self) -> BvhStats {
        let c = BuildConfig::default();
        self.stats_with_costs(c.traversal_cost, c.intersection_cost)
    }

    /// A copy of `Bvh2::ray_traverse_dynamic`'s loop (same order, same box test) that
    /// counts interior nodes whose children are tested and leaves whose triangles are.
    fn traverse_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        stats.rays += 1;
        let nodes = &self.bvh.nodes;
        let root = nodes.first()?;
        let mut oray = obvhs_ray(ray);
        let mut best = None;
        let mut leaf = |node: &obvhs::bvh2::node::Bvh2Node, oray: &mut obvhs::ray::Ray, stats: &mut RayStats| {
            stats.nodes_visited += 1;
            stats.triangles_tested += node.prim_count as u64;
            for i in node.first_index..node.first_index + node.prim_count {
                if let Some(h) = self.leaves.hit(i as usize, ray, oray.tmax) {
                    oray.tmax = h.t;
                    best = Some(h);
                }
            }
        };
        if root.aabb().intersect_ray(&oray) >= oray.tmax {
            return None;
        }
        if root.is_leaf() {
            leaf(root, &mut oray, stats);
            return best;
        }
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        let mut current = root.first_index;
        loop {
            stats.nodes_visited += 1;
            let (mut l, mut r) = (&nodes[current as usize], &nodes[current as usize + 1]);
            let (mut tl, mut tr) = (l.aabb().intersect_ray(&oray), r.aabb().intersect_ray(&oray));
            if tl > tr {
                std::mem::swap(&mut tl, &mut tr);
                std::mem::swap(&mut l, &mut r);
            }
            let hit_l = tl < oray.tmax;
            let go_l = if hit_l && l.is_leaf() {
                leaf(l, &mut oray, stats);
                false
            } else {
                hit_l
            };
            let hit_r = tr < oray.tmax;
            let go_r = if hit_r && r.is_leaf() {
                leaf(r, &mut oray, stats);
                false
            } else {
                hit_r
            };
            current = match (go_l, go_r) {
                (true, true) => {
                    stack.push(r.first_index);
                    l.first_index
                }
                (true, false) => l.first_index,
                (false, true) => r.first_index,
                (false, false) => match stack.pop() {
                    Some(next) => next,
                    None => return best,
                },
            };
        }
    }
}

impl Accelerator for ObvhsBvh2 {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if self.bvh.nodes.is_empty() {
            return None;
        }
        let mut best = None;
        self.bvh.ray_traverse(obvhs_ray(ray), &mut RayHit::none(), |oray, i| {
            self.leaves.record(i, ray, oray.tmax, &mut best)
        });
        best
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        !self.bvh.nodes.is_empty()
            && !self.bvh.ray_traverse_miss(obvhs_ray(ray), |_, i| self.leaves.distance(i, ray, ray.t_max))
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        self.traverse_counted(ray, stats)
    }
}

/// Deepest CWBVH (levels of 8-wide nodes plus the leaf level, as
/// [`ObvhsCwBvh::stats`] counts) that obvhs's 32-entry traversal stack can hold.
const CWBVH_MAX_DEPTH: usize = 32;

/// obvhs's compressed 8-wide BVH (CWBVH).
#[derive(Clone)]
pub struct ObvhsCwBvh {
    bvh: CwBvh,
    leaves: LeafTriangles,
    bounds: Aabb,
    build_time: Duration,
    core_build_time: Duration,
}

impl std::fmt::Debug for ObvhsCwBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObvhsCwBvh").field("nodes", &self.bvh.nodes.len()).field("bounds", &self.bounds).finish()
    }
}

impl ObvhsCwBvh {
    /// Builds with `obvhs::cwbvh::builder::build_cwbvh_from_tris` and the preset's
    /// parameters (at most 3 triangles per leaf, obvhs's clamp); rejects non-finite
    /// coordinates. An empty input gives a structure nothing hits.
    ///
    /// A tree deeper than obvhs's fixed 32-entry traversal stack allows — pathological
    /// inputs such as hundreds of coincident triangles, which traversal would silently
    /// get wrong — is rejected with [`BuildError::TooDeep`] (obvhs's own debug-build
    /// validation panics on it; that panic is caught and reported the same way).
    pub fn build(triangles: &[[Vec3; 3]], quality: ObvhsQuality) -> Result<Self, BuildError> {
        // What our own builders reject: NaN/∞ (obvhs has crashed on infinite boxes).
        validate(triangles)?;
        let start = Instant::now();
        let mut core_build_time = Duration::ZERO;
        let bvh = if triangles.is_empty() {
            CwBvh::default()
        } else {
            let obvhs_tris = obvhs_triangles(triangles);
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                obvhs::cwbvh::builder::build_cwbvh_from_tris(&obvhs_tris, quality.params(), &mut core_build_time)
            }))
            .map_err(|_| BuildError::TooDeep { depth: None, limit: CWBVH_MAX_DEPTH })?
        };
        let leaves = LeafTriangles::new(triangles, &bvh.primitive_indices);
        let build_time = start.elapsed();
        let cw = Self { bvh, leaves, bounds: bounds_of(triangles), build_time, core_build_time };
        // obvhs's traversal stack silently overwrites its top entry when full.
        let depth = cw.stats().depth;
        if depth > CWBVH_MAX_DEPTH {
            return Err(BuildError::TooDeep { depth: Some(depth), limit: CWBVH_MAX_DEPTH });
        }
        Ok(cw)
    }

    /// Wall time of [`ObvhsCwBvh::build`], conversions included (in debug builds also
    /// obvhs's self-validation).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// obvhs's own "core" build time: PLOC, reinsertion and the BVH2 → CWBVH conversion.
    pub fn core_build_time(&self) -> Duration {
        self.core_build_time
    }

    /// The underlying obvhs tree.
    pub fn inner(&self) -> &CwBvh {
        &self.bvh
    }

    /// Figures comparable in spirit with [`crate::Bvh::stats`]: `nodes` counts 8-wide
    /// nodes, `leaves` leaf child slots, `depth` levels including the leaf level (root
    /// = 1), and `sah_cost` = Σ_nodes C_t·A/A_root + Σ_leaves C_i·n·A/A_root over the
    /// quantised child boxes the traversal tests — one traversal step per wide node, so
    /// it is not directly comparable with a binary tree's cost.
    pub fn stats_with_costs(&self, traversal_cost: f32, intersection_cost: f32) -> BvhStats {
        let mut s = BvhStats::default();
        if self.bvh.nodes.is_empty() {
            return s;
        }
        let root_area = area(&self.bvh.total_aabb).max(f32::MIN_POSITIVE as f64);
        let mut cost = 0.0f64;
        let mut stack = vec![(0usize, 1usize, root_area)];
        while let Some((i, depth, node_area)) = stack.pop() {
            let n = &self.bvh.nodes[i];
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            cost += node_area / root_area * traversal_cost as f64;
            for ch in 0..8 {
                if n.is_child_empty(ch) {
                    continue;
                }
                let a = area(&n.child_aabb(ch));
                if n.is_leaf(ch) {
                    s.leaves += 1;
                    s.depth = s.depth.max(depth + 1);
                    cost += a / root_area * n.child_primitives(ch).1 as f64 * intersection_cost as f64;
                } else {
                    stack.push((n.child_node_index(ch) as usize, depth + 1, a));
                }
            }
        }
        s.sah_cost = cost as f32;
        s
    }

    /// [`ObvhsCwBvh::stats_with_costs`] with [`BuildConfig::default`]'s cost constants.
    pub fn stats(&self) -> BvhStats {
        let c = BuildConfig::default();
        self.stats_with_costs(c.traversal_cost, c.intersection_cost)
    }
}

impl Accelerator for ObvhsCwBvh {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if self.bvh.nodes.is_empty() {
            return None;
        }
        let mut best = None;
        self.bvh.ray_traverse(obvhs_ray(ray), &mut RayHit::none(), |oray, i| {
            self.leaves.record(i, ray, oray.tmax, &mut best)
        });
        best
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        !self.bvh.nodes.is_empty()
            && !self.bvh.ray_traverse_miss(obvhs_ray(ray), |_, i| self.leaves.distance(i, ray, ray.t_max))
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// obvhs's own traversal (its `traverse!` macro, as `CwBvh::ray_traverse` uses it),
    /// counting each 8-wide node whose children are tested and each triangle test.
    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        stats.rays += 1;
        if self.bvh.nodes.is_empty() {
            return None;
        }
        let bvh = &self.bvh;
        let mut oray = obvhs_ray(ray);
        let mut state = bvh.new_traversal(oray.direction);
        let mut best = None;
        let mut node;
        obvhs::traverse!(
            bvh,
            node,
            state,
            {
                stats.nodes_visited += 1;
                node.intersect_ray(&oray, state.oct_inv4)
            },
            {
                stats.triangles_tested += 1;
                if let Some(h) = self.leaves.hit(state.primitive_id as usize, ray, oray.tmax) {
                    oray.tmax = h.t;
                    best = Some(h);
                }
            }
        );
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BruteForce;
    use crate::test_util::soup;
    use rng::Pcg32;

    /// A uniform point in [0, 1)³.
    fn point(r: &mut Pcg32) -> Vec3 {
        Vec3::new(r.next_f32(), r.next_f32(), r.next_f32())
    }

    /// Rays from around and inside the soup, some infinite, some finite segments; every
    /// other one aimed at a point inside a random triangle, so that many hit.
    fn rays(seed: u64, n: usize, spread: f32, tris: &[[Vec3; 3]]) -> Vec<Ray> {
        let mut r = Pcg32::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                let o = point(&mut r) * spread * 1.6 - 0.3 * spread;
                let target = match tris.len() {
                    0 => point(&mut r) * spread,
                    len if i % 2 == 0 => {
                        let t = tris[(r.next_f32() * len as f32) as usize % len];
                        let (a, b) = (r.next_f32(), r.next_f32());
                        let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                        t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b
                    }
                    _ => point(&mut r) * spread,
                };
                let d = (target - o).normalize_or(Vec3::X);
                match i % 3 {
                    0 => Ray::new(o, d),
                    1 => Ray::segment(o, d, 0.0, 0.5 * spread),
                    _ => Ray::segment(o, target - o, 0.0, 1.5),
                }
            })
            .collect()
    }

    fn agree(tris: &[[Vec3; 3]], accel: &dyn Accelerator, rays: &[Ray], name: &str) {
        let oracle = BruteForce::new(tris).unwrap();
        let mut hits = 0;
        for r in rays {
            match (accel.intersect(r), oracle.intersect(r)) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a.t - b.t).abs() <= 1e-5 * b.t.abs(), "{name}: t {} vs {} for {r:?}", a.t, b.t);
                    if a.prim != b.prim {
                        assert_eq!(a.t, b.t, "{name}: different triangle at a different t for {r:?}");
                    } else {
                        assert_eq!((a.u, a.v), (b.u, b.v), "{name}: same triangle, same barycentrics");
                    }
                }
                (a, b) => panic!("{name}: {a:?} vs brute force {b:?} for {r:?}"),
            }
            assert_eq!(accel.occluded(r), oracle.occluded(r), "{name}: occlusion for {r:?}");
            let mut stats = RayStats::default();
            assert_eq!(accel.intersect_counted(r, &mut stats), accel.intersect(r), "{name}: counted traversal");
            assert_eq!(stats.rays, 1);
        }
        if !tris.is_empty() {
            assert!(hits > rays.len() / 5, "{name}: only {hits} hits of {}: a weak test", rays.len());
        }
    }

    fn both(tris: &[[Vec3; 3]], quality: ObvhsQuality) -> [(String, Box<dyn Accelerator>); 2] {
        [
            (format!("bvh2/{}", quality.name()), Box::new(ObvhsBvh2::build(tris, quality).unwrap())),
            (format!("cwbvh/{}", quality.name()), Box::new(ObvhsCwBvh::build(tris, quality).unwrap())),
        ]
    }

    #[test]
    fn random_soups_agree_with_brute_force() {
        for (seed, n, size) in [(1u64, 50usize, 1.0f32), (2, 500, 1.5), (3, 3000, 0.8), (4, 200, 6.0)] {
            let tris = soup(seed, n, 10.0, size);
            let rs = rays(seed + 100, 600, 10.0, &tris);
            for quality in ObvhsQuality::ALL {
                for (name, accel) in both(&tris, quality) {
                    agree(&tris, accel.as_ref(), &rs, &format!("{name} n={n}"));
                }
            }
        }
    }

    #[test]
    fn counted_traversal_reports_work() {
        let tris = soup(5, 2000, 10.0, 1.0);
        let rs = rays(6, 300, 10.0, &tris);
        for (name, accel) in both(&tris, ObvhsQuality::Medium) {
            let mut stats = RayStats::default();
            for r in &rs {
                accel.intersect_counted(r, &mut stats);
            }
            assert_eq!(stats.rays, 300, "{name}");
            assert!(stats.nodes_visited > 300 && stats.triangles_tested > 0, "{name}: {stats:?}");
            assert!(stats.triangles_tested < 300 * 2000 / 20, "{name}: {stats:?}");
        }
    }

    #[test]
    fn stats_describe_the_trees() {
        let tris = soup(7, 5000, 20.0, 1.0);
        let b2 = ObvhsBvh2::build(&tris, ObvhsQuality::Medium).unwrap();
        let s = b2.stats();
        assert_eq!(s.nodes, 2 * s.leaves - 1, "a binary tree: {s:?}");
        assert!(s.depth > 5 && s.depth < 64 && s.sah_cost > 0.0 && s.sah_cost < 0.1 * tris.len() as f32, "{s:?}");
        let leaf_prims: u32 = b2.inner().nodes.iter().filter(|n| n.is_leaf()).map(|n| n.prim_count).sum();
        assert_eq!(leaf_prims as usize, tris.len());
        let cw = ObvhsCwBvh::build(&tris, ObvhsQuality::Medium).unwrap();
        let s = cw.stats();
        assert_eq!(s.nodes, cw.inner().nodes.len());
        assert!(s.leaves >= tris.len() / 3 && s.depth > 2 && s.depth < 32, "{s:?}");
        assert!(b2.build_time() >= b2.core_build_time() && cw.build_time() >= cw.core_build_time());
        assert_eq!(b2.bounds(), BruteForce::new(&tris).unwrap().bounds());
    }

    #[test]
    fn empty_and_single_triangle_inputs() {
        let one = soup(9, 1, 2.0, 1.5);
        for quality in ObvhsQuality::ALL {
            for (name, accel) in both(&[], quality) {
                assert!(accel.bounds().is_empty(), "{name}");
                agree(&[], accel.as_ref(), &rays(8, 300, 2.0, &[]), &name);
            }
            for (name, accel) in both(&one, quality) {
                agree(&one, accel.as_ref(), &rays(8, 300, 2.0, &one), &name);
            }
            let hit = Ray::new(one[0].iter().sum::<Vec3>() / 3.0 + Vec3::Z * 5.0, -Vec3::Z);
            for (name, accel) in both(&one, quality) {
                assert_eq!(accel.intersect(&hit).map(|h| h.prim), Some(0), "{name}");
            }
        }
        let s = ObvhsCwBvh::build(&[], ObvhsQuality::Medium).unwrap().stats();
        assert_eq!((s.nodes, s.leaves, s.depth), (0, 0, 0));
    }

    #[test]
    fn duplicates_and_degenerate_triangles() {
        let mut tris = vec![soup(10, 1, 2.0, 1.0)[0]; 20];
        tris.extend(soup(11, 200, 2.0, 0.5));
        tris.extend((0..30).map(|i| [Vec3::splat(i as f32 * 0.01); 3]));
        tris.extend((0..30).map(|i| [Vec3::ZERO, Vec3::X * i as f32, Vec3::X * 2.0 * i as f32]));
        let rs = rays(12, 500, 2.0, &tris);
        for (name, accel) in both(&tris, ObvhsQuality::Medium) {
            agree(&tris, accel.as_ref(), &rs, &name);
        }
        // Hundreds of coincident triangles: fine for the BVH2 ...
        let same = vec![soup(14, 1, 2.0, 1.0)[0]; 1000];
        let b2 = ObvhsBvh2::build(&same, ObvhsQuality::Medium).unwrap();
        agree(&same, &b2, &rays(15, 200, 2.0, &same), "bvh2, coincident");
    }

    #[test]
    fn coincident_triangles_too_deep_for_the_cwbvh_are_an_error() {
        // ... but PLOC chains them into a CWBVH deeper than obvhs's 32-entry traversal
        // stack: an error, not a panic and not silently lost hits.
        let same = vec![soup(14, 1, 2.0, 1.0)[0]; 1000];
        let r = ObvhsCwBvh::build(&same, ObvhsQuality::Medium);
        assert!(matches!(r, Err(BuildError::TooDeep { .. })), "{:?}", r.err());
    }

    #[test]
    fn axis_parallel_rays_with_negative_zero_components() {
        let tris = soup(16, 300, 4.0, 1.0);
        let mut rs = Vec::new();
        for t in tris.iter().step_by(7) {
            let c = t.iter().sum::<Vec3>() / 3.0;
            for d in [Vec3::X, Vec3::Y, Vec3::Z] {
                rs.push(Ray::new(c + d * 10.0, -d));
                rs.push(Ray::new(c - d * 10.0, d));
            }
        }
        for (name, accel) in both(&tris, ObvhsQuality::Medium) {
            agree(&tris, accel.as_ref(), &rs, &name);
        }
    }

    #[test]
    fn rejects_non_finite_coordinates() {
        let mut tris = soup(13, 10, 1.0, 1.0);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            tris[3][1].y = bad;
            for quality in ObvhsQuality::ALL {
                assert!(matches!(ObvhsBvh2::build(&tris, quality), Err(BuildError::NonFinite { index: 3, .. })));
                assert!(matches!(ObvhsCwBvh::build(&tris, quality), Err(BuildError::NonFinite { index: 3, .. })));
            }
        }
    }
}
