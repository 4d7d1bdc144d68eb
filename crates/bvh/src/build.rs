//! A binned-SAH BVH (Wald 2007, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies"), flattened depth-first, with ordered stack traversal.

use crate::{Aabb, Accelerator, BuildError, Hit, Ray, Triangle, intersect_triangle, validate};
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

/// Build settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildConfig {
    /// Number of SAH bins per axis.
    pub bins: usize,
    /// Largest leaf the builder may make (a node above this is always split).
    pub max_leaf_size: usize,
    /// SAH cost of visiting an interior node, relative to one triangle test.
    pub traversal_cost: f32,
    /// SAH cost of one ray–triangle test.
    pub intersection_cost: f32,
}

impl Default for BuildConfig {
    fn default() -> Self {
        Self { bins: 16, max_leaf_size: 8, traversal_cost: 1.0, intersection_cost: 1.0 }
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
    /// SAH cost of the tree with the build's cost constants, relative to the root's area.
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

struct Item {
    bounds: Aabb,
    centre: Vec3,
    id: u32,
}

const STACK_DEPTH: usize = 64;

impl Bvh {
    /// Builds a tree; rejects non-finite coordinates. Degenerate (zero-area) triangles
    /// are kept (they are never hit). An empty input gives a tree that nothing hits.
    pub fn build(triangles: &[[Vec3; 3]], config: BuildConfig) -> Result<Self, BuildError> {
        validate(triangles)?;
        let config = BuildConfig {
            bins: config.bins.clamp(2, 256),
            max_leaf_size: config.max_leaf_size.clamp(1, 255),
            ..config
        };
        let mut items: Vec<Item> = triangles
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let bounds = Triangle::bounds(t);
                Item { bounds, centre: bounds.centre(), id: i as u32 }
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * items.len().max(1));
        if !items.is_empty() {
            let mut builder = Builder { nodes: &mut nodes, config, depth_limit: STACK_DEPTH - 2 };
            builder.build(&mut items, 0, 1);
        }
        let prim_ids: Vec<u32> = items.iter().map(|it| it.id).collect();
        let triangles = prim_ids.iter().map(|&i| Triangle::new(&triangles[i as usize])).collect();
        Ok(Self { nodes, triangles, prim_ids, config })
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

    /// Node count, leaf count, depth and SAH cost.
    pub fn stats(&self) -> BvhStats {
        let mut s = BvhStats { nodes: self.nodes.len(), ..Default::default() };
        let Some(root) = self.nodes.first() else {
            return s;
        };
        let root_area = root.aabb().surface_area().max(f32::MIN_POSITIVE);
        let mut stack = vec![(0usize, 1usize)];
        let mut cost = 0.0f64;
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            s.depth = s.depth.max(depth);
            let area = (n.aabb().surface_area() / root_area) as f64;
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
    fn traverse(&self, ray: &Ray, any_hit: bool) -> Option<Hit> {
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
            if n.count > 0 {
                let first = n.index as usize;
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
    /// (t_min, t_max] (a hit's entry distance is always finite). Same conventions as [`Aabb::hit`] (closed box; an origin on a slab
    /// plane with a zero direction component counts as inside).
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
        self.traverse(ray, false)
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse(ray, true).is_some()
    }

    fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.aabb())
    }
}

struct Builder<'a> {
    nodes: &'a mut Vec<BvhNode>,
    config: BuildConfig,
    depth_limit: usize,
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: usize,
}

impl Builder<'_> {
    /// Builds the subtree over `items` (whose triangles will sit at `offset..`) and
    /// returns its node index.
    fn build(&mut self, items: &mut [Item], offset: usize, depth: usize) -> usize {
        let bounds = items.iter().fold(Aabb::EMPTY, |b, it| b.union(it.bounds));
        let index = self.nodes.len();
        self.nodes.push(BvhNode {
            min: bounds.min.to_array(),
            index: offset as u32,
            max: bounds.max.to_array(),
            count: items.len() as u32,
        });
        let n = items.len();
        if n == 1 {
            return index;
        }
        let split = self.find_split(items, &bounds);
        let mid = match split {
            Some((axis, pos, cost)) => {
                let leaf_cost = self.config.intersection_cost * n as f32;
                if cost >= leaf_cost && n <= self.config.max_leaf_size {
                    return index;
                }
                let mid = partition(items, |it| it.centre[axis] < pos);
                if mid == 0 || mid == n { n / 2 } else { mid }
            }
            None => {
                // All centroids coincide: no spatial split separates them.
                if n <= self.config.max_leaf_size {
                    return index;
                }
                n / 2
            }
        };
        if depth >= self.depth_limit {
            // Keep the traversal stack bounded whatever the input (e.g. thousands of
            // identical triangles): make an oversized leaf instead of a deeper tree.
            return index;
        }
        self.build_children(items, offset, depth, index, mid)
    }

    fn build_children(&mut self, items: &mut [Item], offset: usize, depth: usize, index: usize, mid: usize) -> usize {
        let (left, right) = items.split_at_mut(mid);
        self.build(left, offset, depth + 1);
        let right_index = self.build(right, offset + mid, depth + 1);
        self.nodes[index].index = right_index as u32;
        self.nodes[index].count = 0;
        index
    }

    /// The best binned-SAH split: (axis, centroid threshold, cost), or `None` when the
    /// centroids span no extent.
    fn find_split(&self, items: &[Item], bounds: &Aabb) -> Option<(usize, f32, f32)> {
        let cb = items.iter().fold(Aabb::EMPTY, |b, it| b.grow(it.centre));
        let extent = cb.extent();
        let parent_area = bounds.surface_area().max(f32::MIN_POSITIVE);
        let nb = self.config.bins;
        let mut best: Option<(usize, f32, f32)> = None;
        let mut bins = vec![Bin { bounds: Aabb::EMPTY, count: 0 }; nb];
        let mut right_area = vec![0.0f32; nb];
        let mut right_count = vec![0usize; nb];
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            bins.fill(Bin { bounds: Aabb::EMPTY, count: 0 });
            let scale = nb as f32 / extent[axis];
            for it in items {
                let b = (((it.centre[axis] - cb.min[axis]) * scale) as usize).min(nb - 1);
                bins[b].bounds = bins[b].bounds.union(it.bounds);
                bins[b].count += 1;
            }
            // Sweep from the right, then from the left, evaluating the n−1 planes.
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for i in (1..nb).rev() {
                acc = acc.union(bins[i].bounds);
                cnt += bins[i].count;
                right_area[i] = acc.surface_area();
                right_count[i] = cnt;
            }
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for i in 0..nb - 1 {
                acc = acc.union(bins[i].bounds);
                cnt += bins[i].count;
                if cnt == 0 || right_count[i + 1] == 0 {
                    continue;
                }
                let cost = self.config.traversal_cost
                    + self.config.intersection_cost
                        * (acc.surface_area() * cnt as f32 + right_area[i + 1] * right_count[i + 1] as f32)
                        / parent_area;
                if best.is_none_or(|(_, _, c)| cost < c) {
                    let pos = cb.min[axis] + (i + 1) as f32 / scale;
                    best = Some((axis, pos, cost));
                }
            }
        }
        best
    }
}

/// In-place partition; returns the number of items for which `pred` holds.
fn partition(items: &mut [Item], pred: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if pred(&items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BruteForce;
    use proptest::prelude::*;

    fn soup(seed: u64, n: usize, spread: f32, size: f32) -> Vec<[Vec3; 3]> {
        let mut s = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(next(), next(), next()) * spread;
                std::array::from_fn(|_| c + (Vec3::new(next(), next(), next()) - 0.5) * size)
            })
            .collect()
    }

    fn agree(tris: &[[Vec3; 3]], config: BuildConfig, rays: &[Ray]) {
        let bvh = Bvh::build(tris, config).unwrap();
        let oracle = BruteForce::new(tris).unwrap();
        for r in rays {
            let (a, b) = (bvh.intersect(r), oracle.intersect(r));
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert!((a.t - b.t).abs() <= 1e-5 * b.t.abs().max(1.0), "t {} vs {}", a.t, b.t);
                    if a.prim != b.prim {
                        assert_eq!(a.t, b.t, "different triangle at different t");
                    }
                }
                _ => panic!("bvh {a:?} vs brute force {b:?} for {r:?}"),
            }
            assert_eq!(bvh.occluded(r), oracle.occluded(r), "occlusion for {r:?}");
        }
    }

    fn rays(seed: u64, n: usize, spread: f32) -> Vec<Ray> {
        let pts = soup(seed ^ 0xABCD, n, spread * 1.4, spread);
        pts.iter()
            .map(|p| {
                let o = p[0] - Vec3::splat(0.2 * spread);
                let d = (p[1] - p[2]).normalize_or(Vec3::X);
                Ray::segment(o, d, 0.0, if p[0].x > 0.5 * spread { f32::INFINITY } else { spread })
            })
            .collect()
    }

    #[test]
    fn matches_brute_force_for_every_leaf_size() {
        let tris = soup(1, 2000, 10.0, 1.0);
        let rs = rays(2, 2000, 10.0);
        for max_leaf_size in [1, 2, 3, 4, 8] {
            agree(&tris, BuildConfig { max_leaf_size, ..Default::default() }, &rs);
        }
    }

    #[test]
    fn degenerate_duplicate_and_tiny_inputs() {
        let rs = rays(3, 500, 2.0);
        agree(&[], BuildConfig::default(), &rs);
        agree(&soup(4, 1, 2.0, 1.0), BuildConfig::default(), &rs);
        // 1000 copies of one triangle: all centroids coincide.
        let same = vec![soup(5, 1, 2.0, 1.0)[0]; 1000];
        let bvh = Bvh::build(&same, BuildConfig::default()).unwrap();
        assert!(bvh.stats().depth < STACK_DEPTH);
        agree(&same, BuildConfig::default(), &rs);
        // Zero-area triangles mixed in.
        let mut mixed = soup(6, 300, 2.0, 0.5);
        mixed.extend((0..50).map(|i| [Vec3::splat(i as f32 * 0.01); 3]));
        mixed.extend((0..50).map(|i| [Vec3::ZERO, Vec3::X * i as f32, Vec3::X * 2.0 * i as f32]));
        agree(&mixed, BuildConfig::default(), &rs);
    }

    #[test]
    fn rejects_non_finite_coordinates() {
        let mut tris = soup(7, 10, 1.0, 1.0);
        tris[3][1].y = f32::NAN;
        assert!(matches!(Bvh::build(&tris, BuildConfig::default()), Err(BuildError::NonFinite { index: 3, .. })));
        tris[3][1].y = f32::INFINITY;
        assert!(Bvh::build(&tris, BuildConfig::default()).is_err());
        assert!(BruteForce::new(&tris).is_err());
    }

    #[test]
    fn stats_are_consistent() {
        let tris = soup(8, 5000, 20.0, 1.0);
        let bvh = Bvh::build(&tris, BuildConfig::default()).unwrap();
        let s = bvh.stats();
        assert_eq!(s.nodes, 2 * s.leaves - 1, "a binary tree");
        let total: u32 = bvh.nodes().iter().filter(|n| n.count > 0).map(|n| n.count).sum();
        assert_eq!(total as usize, tris.len(), "every triangle in exactly one leaf");
        let mut ids = bvh.prim_ids().to_vec();
        ids.sort_unstable();
        assert!(ids.iter().enumerate().all(|(i, &id)| i as u32 == id));
        assert!(s.depth > 5 && s.depth < 40, "depth {}", s.depth);
        // SAH should beat one big leaf by a wide margin on a spread-out soup.
        assert!(s.sah_cost < 0.1 * tris.len() as f32, "cost {}", s.sah_cost);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn random_soups_agree_with_brute_force(seed in any::<u64>(), n in 1usize..300, leaf in 1usize..9, bins in 2usize..33) {
            let tris = soup(seed, n, 5.0, 1.5);
            agree(&tris, BuildConfig { max_leaf_size: leaf, bins, ..Default::default() }, &rays(seed ^ 1, 200, 5.0));
        }
    }
}
