//! The collapse of a binary [`Bvh`] into a [`BvhWide`]: greedy by surface area, with small
//! sibling leaves merged into one where an SAH with `W`-wide triangle tests says so, and the
//! leaves' triangles copied into structure-of-arrays form.

use super::{BvhWide, STACK_DEPTH, WideNode};
use crate::{Aabb, Bvh, BvhNode, TriangleTest};
use glam::Vec3;

impl<const W: usize> BvhWide<W> {
    /// Collapses a binary tree into a `W`-wide one (greedy by surface area), copying its
    /// leaf-ordered triangles. Two sibling leaves (the binary tree's, or leaves merged so)
    /// of at most `W` triangles together become one leaf when that lowers an SAH in which
    /// a leaf costs one `W`-wide triangle test per `W` triangles and a binary interior node
    /// 0.3 of one; trees whose leaves were made
    /// regardless of the SAH (`leaf_by_sah: false`) with `max_leaf_size ≥ W` keep their
    /// leaves exactly, as each of their interior nodes holds more than `W` triangles.
    ///
    /// # Panics
    ///
    /// If the tree is deeper than the traversal stack allows, which our builders never
    /// produce (they stop at 62 levels).
    ///
    /// The binary tree keeps vertex 0 and two edges; the vertices are rebuilt as v0 + e,
    /// which may differ from the mesh's in the last bit, so that the watertight guarantee
    /// holds only for trees made by [`BvhWide::build`].
    pub fn from_bvh(bvh: &Bvh) -> Self {
        Self::collapse(bvh, |i| {
            let t = &bvh.triangles()[i];
            let v0 = Vec3::from_array(t.v0);
            [v0, v0 + Vec3::from_array(t.e1), v0 + Vec3::from_array(t.e2)]
        })
    }

    /// Collapses `bvh`, taking the vertices of its `i`-th leaf-ordered triangle from
    /// `vertices(i)`.
    pub(super) fn collapse(bvh: &Bvh, vertices: impl Fn(usize) -> [Vec3; 3] + Sync) -> Self {
        let mut collapse = Collapse::new(bvh.nodes(), bvh.prim_ids().len());
        if !bvh.nodes().is_empty() {
            collapse.node(0, 1);
        }
        let (nodes, depth, count_at) = (collapse.out, collapse.depth, collapse.count_at);
        let config = bvh.config();
        let triangles = bvh.prim_ids().len();
        let mut soa = vec![0.0; 9 * triangles + 7];
        // Each triangle's plane in leaf order, where the tree keeps a table of planes
        // (`PLANE_TABLE_MAX`), scattered to primitive ids below.
        let plane_table =
            config.exact_t && bvh.prim_ids().iter().max().is_some_and(|&m| (m as usize) < PLANE_TABLE_MAX);
        let mut leaf_planes = vec![[0.0f64; 4]; if plane_table { triangles } else { 0 }];
        // The leaves cover the triangles in contiguous ranges (`count_at`, made by the
        // collapse: a sort or a list of the leaves cost more, mostly in page faults;
        // docs/figures.md). Cut the arrays at leaf boundaries into segments of about
        // `SEGMENT` triangles and fill them in parallel (a gather from the input order,
        // cache-missing).
        const SEGMENT: usize = 16 * 1024;
        let mut segments = Vec::with_capacity(triangles / SEGMENT + 1);
        let (mut soa_rest, mut planes_rest, mut counts_rest) = (&mut soa[..], &mut leaf_planes[..], &count_at[..]);
        let mut at = 0;
        while at < triangles {
            let mut end = (at + SEGMENT).min(triangles);
            while end < triangles && count_at[end] == 0 {
                end += 1;
            }
            let (s, rest) = soa_rest.split_at_mut(9 * (end - at));
            let (p, planes) = planes_rest.split_at_mut(if plane_table { end - at } else { 0 });
            let (c, counts) = counts_rest.split_at(end - at);
            segments.push((at, s, p, c));
            (soa_rest, planes_rest, counts_rest) = (rest, planes, counts);
            at = end;
        }
        let fill = |(start, soa, planes, counts): (usize, &mut [f32], &mut [[f64; 4]], &[u32])| {
            let mut first = 0;
            while first < counts.len() {
                let count = counts[first] as usize;
                assert!(count > 0, "the wide leaves tile the triangles");
                let leaf = &mut soa[9 * first..9 * (first + count)];
                for i in 0..count {
                    let v = vertices(start + first + i);
                    for (k, x) in v.iter().flat_map(|v| v.to_array()).enumerate() {
                        leaf[k * count + i] = x;
                    }
                    if plane_table {
                        planes[first + i] = plane(&v);
                    }
                }
                first += count;
            }
        };
        if segments.len() > 1 {
            use rayon::prelude::*;
            segments.into_par_iter().for_each(fill);
        } else {
            segments.into_iter().for_each(fill);
        }
        // By primitive id (pre-split pieces share their triangle's plane).
        let mut planes = Vec::new();
        if plane_table {
            let ids = bvh.prim_ids();
            planes = vec![[0.0; 4]; ids.iter().max().map_or(0, |&m| m as usize + 1)];
            for (&id, p) in ids.iter().zip(&leaf_planes) {
                planes[id as usize] = *p;
            }
        }
        let wide = Self {
            nodes,
            soa,
            prim_ids: bvh.prim_ids().to_vec(),
            planes,
            costs: (config.traversal_cost, config.intersection_cost),
            test: TriangleTest::default(),
            exact_t: config.exact_t,
        };
        debug_assert_eq!(depth, wide.stats().depth);
        assert!(
            W <= super::MAX_WIDTH && depth.saturating_sub(1) * (W - 1) <= STACK_DEPTH,
            "{W}-wide BVH of depth {depth} overflows the traversal stack"
        );
        wide
    }
}

/// Primitive ids below which a tree keeps a table of its triangles' planes in f64 (32 bytes
/// each, 8 MiB at most), from which every closest hit's t is recomputed
/// (`traverse::refine`). Above it the table's lookups miss the caches: on the
/// 1.1M-triangle mesh it traced 6 % fewer primary rays/s than refining from the hit leaf's
/// vertices, which the leaf test has just loaded, where on the Cornell box it traced 21 %
/// more (docs/figures.md, thirty-fifth session).
pub(super) const PLANE_TABLE_MAX: usize = 1 << 18;

/// Triangle `v`'s plane in f64: the normal (v1 − v0) × (v2 − v0) and its dot product with
/// v0. From f32 vertices the differences are exact in f64 and the products nearly so.
fn plane(v: &[Vec3; 3]) -> [f64; 4] {
    let [a, b, c] = v.map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a);
    [n.x, n.y, n.z, n.dot(a)]
}

/// Cost of a binary interior node, relative to one `W`-wide triangle test, in the SAH that
/// decides whether to merge two sibling leaves into one (a wide node tests up to three
/// binary nodes' children at once).
const MERGE_NODE_COST: f32 = 0.3;

/// The greedy collapse of a binary tree.
struct Collapse<'a, const W: usize> {
    src: &'a [BvhNode],
    /// Per binary node: the first triangle and the number of triangles of its subtree
    /// (a contiguous range, as the builders append leaves depth-first; only used for
    /// leaves, where it is checked).
    range: Vec<(u32, u32)>,
    /// Per binary node: true if its subtree becomes one leaf of the wide tree.
    leaf: Vec<bool>,
    /// Per binary node: its box's surface area (which child to open next).
    area: Vec<f32>,
    out: Vec<WideNode<W>>,
    /// Levels of the wide tree so far, its leaves counted (as [`super::WideStats::depth`]).
    depth: usize,
    /// Per triangle in leaf order: the number of triangles of the wide leaf that starts
    /// at it, 0 inside a leaf.
    count_at: Vec<u32>,
}

impl<'a, const W: usize> Collapse<'a, W> {
    /// The collapse of `src`, a tree over `triangles` triangles.
    fn new(src: &'a [BvhNode], triangles: usize) -> Self {
        // Children follow their parents, so one backward pass sees them first.
        let mut range = vec![(0u32, 0u32); src.len()];
        let mut leaf = vec![false; src.len()];
        let mut areas = vec![0.0f32; src.len()];
        // Two sibling leaves of at most `W` triangles together may become one leaf, its
        // triangles tested `W` at a time (the node's width is the leaf test's: 4 with SSE,
        // 8 with AVX2), which costs about the same for one to `W` triangles. SAH cost
        // (times the root's area) of each subtree with its leaves tested so.
        let group = W as u32;
        let mut cost = vec![0.0f32; src.len()];
        for (i, n) in src.iter().enumerate().rev() {
            let area = binary_bounds(n).surface_area();
            areas[i] = area;
            if n.count > 0 {
                range[i] = (n.index, n.count);
                leaf[i] = true;
                cost[i] = area * n.count.div_ceil(group) as f32;
            } else {
                let (l, r) = (i + 1, n.index as usize);
                let contiguous = range[l].0 + range[l].1 == range[r].0;
                range[i] = (range[l].0, range[l].1 + range[r].1);
                let split = MERGE_NODE_COST * area + cost[l] + cost[r];
                // Only two leaves merge: a subtree with interior nodes merged into one
                // leaf looks cheaper to the SAH, which counts rays from outside its box,
                // but rays from inside enter it every time (on the Cornell box, four
                // walls became one leaf of the room's size, for 17 % more traversal
                // instructions).
                leaf[i] = contiguous && leaf[l] && leaf[r] && range[i].1 <= group && area <= split;
                cost[i] = if leaf[i] { area } else { split };
            }
        }
        let count_at = vec![0; triangles];
        Self { src, range, leaf, area: areas, out: Vec::with_capacity(src.len() / 2 + 1), depth: 0, count_at }
    }

    /// True if binary node `i` becomes a leaf of the wide tree.
    fn is_leaf(&self, i: usize) -> bool {
        self.leaf[i]
    }

    /// Collapses the binary subtree at `root` (an interior node, or a root that is a leaf)
    /// into wide node(s) appended depth-first, the node on level `depth`; returns the wide
    /// node's index.
    fn node(&mut self, root: usize, depth: usize) -> u32 {
        let src = self.src;
        let index = self.out.len();
        self.out.push(WideNode::EMPTY);
        self.depth = self.depth.max(depth);
        let area = |i: usize| self.area[i];
        let mut slots = [0usize; W];
        let mut n = if self.is_leaf(root) {
            slots[0] = root;
            1
        } else {
            slots[0] = root + 1;
            slots[1] = src[root].index as usize;
            2
        };
        while n < W {
            // Open the interior child with the largest surface area.
            let Some(open) =
                (0..n).filter(|&i| !self.is_leaf(slots[i])).max_by(|&a, &b| area(slots[a]).total_cmp(&area(slots[b])))
            else {
                break;
            };
            let opened = slots[open];
            slots[open] = opened + 1;
            slots[n] = src[opened].index as usize;
            n += 1;
        }
        let mut node = WideNode::EMPTY;
        for (i, &s) in slots[..n].iter().enumerate() {
            let (child, count) = if self.is_leaf(s) {
                self.depth = self.depth.max(depth + 1);
                let (first, count) = self.range[s];
                self.count_at[first as usize] = count;
                (first, count)
            } else {
                (self.node(s, depth + 1), 0)
            };
            node.set_child(i, &binary_bounds(&src[s]), child, count);
        }
        self.out[index] = node;
        index as u32
    }
}

fn binary_bounds(n: &BvhNode) -> Aabb {
    Aabb { min: Vec3::from_array(n.min), max: Vec3::from_array(n.max) }
}
