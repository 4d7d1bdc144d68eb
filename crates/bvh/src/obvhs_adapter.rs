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
mod tests;
