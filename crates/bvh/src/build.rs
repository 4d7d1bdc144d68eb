//! The BVH: build settings, the flattened node array, statistics and ordered stack
//! traversal. The builders themselves live in [`crate::builders`].

use crate::builders::{self, Prim};
use crate::{Aabb, Accelerator, BuildError, Hit, Ray, RayStats, Triangle, intersect_triangle, validate};
use glam::{Vec3, Vec3A};

/// One node of the flattened tree: 32 bytes, POD, the layout the GPU traverses too.
///
/// An interior node (`count == 0`) has its left child right after it in the array and
/// its right child at `index`; a leaf holds triangles `index .. index + count` of the
/// BVH's reordered triangle array.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct BvhNode {
    /// Lower corner of the node's box.
    pub min: [f32; 3],
    /// Right child (interior) or first triangle (leaf).
    pub index: u32,
    /// Upper corner of the node's box.
    pub max: [f32; 3],
    /// Number of triangles; 0 for an interior node.
    pub count: u32,
}

impl BvhNode {
    #[inline]
    fn aabb(&self) -> Aabb {
        Aabb { min: Vec3::from_array(self.min), max: Vec3::from_array(self.max) }
    }
}

/// How a node's primitives are divided between its children.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SplitMethod {
    /// Full-sweep SAH: every primitive boundary on every axis (the thesis's Algorithm
    /// 8.2), O(n log n) by presorting.
    SweepSah,
    /// Binned SAH with [`BuildConfig::bins`] bins per axis; parallel for large nodes.
    BinnedSah,
    /// Midpoint of the longest centroid axis.
    Midpoint,
    /// Midpoint above `threshold` primitives, full-sweep SAH below (the thesis's hybrid).
    Hybrid {
        /// Node size at and below which the SAH takes over.
        threshold: usize,
    },
}

impl SplitMethod {
    /// Every method, with the thesis's hybrid threshold of 1000 faces.
    pub const ALL: [SplitMethod; 4] =
        [Self::SweepSah, Self::BinnedSah, Self::Midpoint, Self::Hybrid { threshold: 1000 }];

    /// A short name for tables and benchmark ids.
    pub fn name(&self) -> &'static str {
        match self {
            Self::SweepSah => "sweep_sah",
            Self::BinnedSah => "binned_sah",
            Self::Midpoint => "midpoint",
            Self::Hybrid { .. } => "hybrid",
        }
    }
}

/// Build settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildConfig {
    /// How nodes are split.
    pub method: SplitMethod,
    /// Number of SAH bins per axis (binned SAH only).
    pub bins: usize,
    /// Largest leaf the builder may make (a larger node is always split, unless its
    /// primitives cannot be separated or the depth limit is reached).
    pub max_leaf_size: usize,
    /// If true, a node of at most `max_leaf_size` primitives becomes a leaf only when the
    /// SAH says splitting does not pay; if false, nodes are split down to
    /// `max_leaf_size` regardless (the thesis's "max faces per leaf").
    pub leaf_by_sah: bool,
    /// SAH cost of visiting an interior node, relative to one triangle test.
    pub traversal_cost: f32,
    /// SAH cost of one ray–triangle test.
    pub intersection_cost: f32,
    /// Primitives tested together by one SIMD leaf test (rounded up to a power of two):
    /// the SAH counts a set of n primitives as ⌈n / sah_block⌉ · sah_block tests (Embree's
    /// block SAH), so that splits favour full blocks. 1: plain SAH. [`crate::Bvh4`] tests
    /// leaves four triangles at a time, [`crate::Bvh8`] eight with AVX2 (the watertight
    /// test); the default, 4, is also the better block for `Bvh8`, whose collapse merges
    /// sibling leaves up to eight (8: 0.8–4.9 % more traversal instructions;
    /// docs/figures.md).
    pub sah_block: usize,
    /// Extra references triangle pre-splitting may add, as a fraction of the triangles
    /// (Karras & Aila 2013; see `builders::presplit`): long diagonal triangles are cut into
    /// pieces with tighter boxes before the build. 0: none (each triangle in one leaf).
    pub presplit: f32,
    /// Whether a wide tree ([`crate::BvhWide`]) recomputes every closest hit's t in f64
    /// (the default; [`crate::BvhWide::with_exact_t`]). `false` keeps the f32 test's t and
    /// saves building the table of planes (a tenth of Sponza's build time); the binary
    /// [`Bvh`] ignores it.
    pub exact_t: bool,
}

impl Default for BuildConfig {
    fn default() -> Self {
        Self {
            method: SplitMethod::BinnedSah,
            bins: 16,
            max_leaf_size: 8,
            leaf_by_sah: true,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            sah_block: 1,
            presplit: 0.0,
            exact_t: true,
        }
    }
}

/// Figures describing a built tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Total nodes.
    pub nodes: usize,
    /// Leaves among them.
    pub leaves: usize,
    /// Longest root-to-leaf path (root = depth 1).
    pub depth: usize,
    /// Expected cost of a random ray hitting the root box, by the SAH with the build's
    /// cost constants: Σ_interior C_t·A/A_root + Σ_leaves C_i·n·A/A_root.
    pub sah_cost: f32,
}

/// A bounding volume hierarchy over triangles.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    triangles: Vec<Triangle>,
    prim_ids: Vec<u32>,
    config: BuildConfig,
}

const STACK_DEPTH: usize = 64;

/// The leaf order of triangle ids for a tree built over pre-split references (`order`
/// holds references, `refs` maps them to triangles), each leaf holding a triangle once:
/// pieces of one triangle often land in the same leaf, which would test it twice. The
/// leaves' ranges in `nodes` are rewritten to the new order.
fn leaves_without_repeats(nodes: &mut [BvhNode], order: &[u32], refs: &[u32]) -> Vec<u32> {
    let mut ids = Vec::with_capacity(order.len());
    for node in nodes.iter_mut().filter(|n| n.count > 0) {
        let start = ids.len();
        for &r in &order[node.index as usize..(node.index + node.count) as usize] {
            let id = refs[r as usize];
            if !ids[start..].contains(&id) {
                ids.push(id);
            }
        }
        node.index = start as u32;
        node.count = (ids.len() - start) as u32;
    }
    ids
}

impl Bvh {
    /// Builds a tree; rejects non-finite coordinates. Degenerate (zero-area) triangles
    /// are kept (they are never hit). An empty input gives a tree that nothing hits.
    pub fn build(triangles: &[[Vec3; 3]], config: BuildConfig) -> Result<Self, BuildError> {
        let mut bvh = Self::build_topology(triangles, config)?;
        bvh.triangles = bvh.prim_ids.iter().map(|&i| Triangle::new(&triangles[i as usize])).collect();
        Ok(bvh)
    }

    /// [`Bvh::build`] without the leaf-ordered copy of the triangles (`triangles()` is
    /// empty): the nodes and the leaf order are all a wide tree's collapse needs.
    pub(crate) fn build_topology(triangles: &[[Vec3; 3]], config: BuildConfig) -> Result<Self, BuildError> {
        validate(triangles)?;
        let config = BuildConfig {
            bins: config.bins.clamp(2, 256),
            max_leaf_size: config.max_leaf_size.clamp(1, 255),
            sah_block: config.sah_block.clamp(1, 64).next_power_of_two(),
            ..config
        };
        let prim = |t: &[Vec3; 3]| Prim::new(Triangle::bounds(t));
        let prims: Vec<Prim> = if triangles.len() > 64 * 1024 {
            use rayon::prelude::*;
            triangles.par_iter().map(prim).collect()
        } else {
            triangles.iter().map(prim).collect()
        };
        let (prims, refs) = builders::presplit::presplit(triangles, prims, config.presplit);
        let mut ids: Vec<u32> = (0..prims.len() as u32).collect();
        let mut out = builders::build_tree(&prims, &mut ids, &config);
        if let Some(refs) = refs {
            out.order = leaves_without_repeats(&mut out.nodes, &out.order, &refs);
        }
        Ok(Self { nodes: out.nodes, triangles: Vec::new(), prim_ids: out.order, config })
    }

    /// The flattened nodes (root first).
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// The triangles in leaf order.
    pub fn triangles(&self) -> &[Triangle] {
        &self.triangles
    }

    /// For each triangle in leaf order, its index in the input.
    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    /// The settings the tree was built with.
    pub fn config(&self) -> &BuildConfig {
        &self.config
    }

    /// Node count, leaf count, depth and SAH cost.
    pub fn stats(&self) -> BvhStats {
        let mut s = BvhStats { nodes: self.nodes.len(), ..Default::default() };
        let Some(root) = self.nodes.first() else {
            return s;
        };
        let root_area = root.aabb().surface_area().max(f32::MIN_POSITIVE) as f64;
        let mut stack = vec![(0usize, 1usize)];
        let mut cost = 0.0f64;
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            s.depth = s.depth.max(depth);
            let area = n.aabb().surface_area() as f64 / root_area;
            if n.count > 0 {
                s.leaves += 1;
                cost += area * n.count as f64 * self.config.intersection_cost as f64;
            } else {
                cost += area * self.config.traversal_cost as f64;
                stack.push((i + 1, depth + 1));
                stack.push((n.index as usize, depth + 1));
            }
        }
        s.sah_cost = cost as f32;
        s
    }

    #[inline]
    fn traverse<const COUNT: bool>(&self, ray: &Ray, any_hit: bool, stats: &mut RayStats) -> Option<Hit> {
        if COUNT {
            stats.rays += 1;
        }
        let root = self.nodes.first()?;
        let slab = SlabRay::new(ray);
        let mut t_max = ray.t_max;
        if slab.enter(root, t_max) == f32::INFINITY {
            return None;
        }
        // The stack holds far children with their entry distance, so that a pop can be
        // culled against the best hit without a second box test.
        let mut stack = [(0u32, 0.0f32); STACK_DEPTH];
        let mut sp = 0usize;
        let mut node = 0usize;
        let mut best: Option<Hit> = None;
        loop {
            let n = &self.nodes[node];
            if COUNT {
                stats.nodes_visited += 1;
            }
            if n.count > 0 {
                let first = n.index as usize;
                if COUNT {
                    stats.triangles_tested += n.count as u64;
                }
                for i in first..first + n.count as usize {
                    if let Some((t, u, v)) = intersect_triangle(&self.triangles[i], ray, t_max) {
                        t_max = t;
                        best = Some(Hit { prim: self.prim_ids[i], t, u, v });
                        if any_hit {
                            return best;
                        }
                    }
                }
            } else {
                // Visit the nearer child first, push the farther; skip children whose
                // entry lies beyond the best hit so far.
                let (l, r) = (node + 1, n.index as usize);
                let tl = slab.enter(&self.nodes[l], t_max);
                let tr = slab.enter(&self.nodes[r], t_max);
                let (near, t_near, far, t_far) = if tl <= tr { (l, tl, r, tr) } else { (r, tr, l, tl) };
                if t_near != f32::INFINITY {
                    if t_far != f32::INFINITY {
                        stack[sp] = (far as u32, t_far);
                        sp += 1;
                    }
                    node = near;
                    continue;
                }
            }
            // Pop until a node that may still hold a closer hit.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                let (candidate, t_enter) = stack[sp];
                if t_enter <= t_max {
                    node = candidate as usize;
                    break;
                }
            }
        }
    }
}

/// A ray prepared for SIMD slab tests against [`BvhNode`] boxes.
struct SlabRay {
    origin: Vec3A,
    inv_dir: Vec3A,
    t_min: f32,
}

impl SlabRay {
    #[inline]
    fn new(ray: &Ray) -> Self {
        Self { origin: ray.origin.into(), inv_dir: ray.inv_dir.into(), t_min: ray.t_min }
    }

    /// The entry distance into the node's box, or +∞ if the ray misses it within
    /// (t_min, t_max] (a hit's entry distance is always finite). Same conventions as
    /// [`Aabb::hit`]: a closed box; an origin on a slab plane with a zero direction
    /// component counts as inside.
    #[inline]
    fn enter(&self, node: &BvhNode, t_max: f32) -> f32 {
        let t0 = (Vec3A::from_array(node.min) - self.origin) * self.inv_dir;
        let t1 = (Vec3A::from_array(node.max) - self.origin) * self.inv_dir;
        let on_plane = t0.is_nan_mask() | t1.is_nan_mask();
        let near = Vec3A::select(on_plane, Vec3A::NEG_INFINITY, t0.min(t1));
        let far = Vec3A::select(on_plane, Vec3A::INFINITY, t0.max(t1));
        let t_enter = near.max_element().max(self.t_min);
        let t_exit = far.min_element().min(t_max);
        if t_enter <= t_exit { t_enter } else { f32::INFINITY }
    }
}

impl Accelerator for Bvh {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse::<false>(ray, false, &mut RayStats::default())
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<false>(ray, true, &mut RayStats::default()).is_some()
    }

    fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.aabb())
    }

    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        self.traverse::<true>(ray, false, stats)
    }

    fn occluded_counted(&self, ray: &Ray, stats: &mut RayStats) -> bool {
        self.traverse::<true>(ray, true, stats).is_some()
    }
}

#[cfg(test)]
mod tests;
