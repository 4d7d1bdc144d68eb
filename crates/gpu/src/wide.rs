//! The GPU's wide BVHs (`--bvh-width 4` and `8`): the binary BVH (binned SAH, leaves ≤ 4)
//! collapsed so that each node holds up to four (eight) children — a ray tests four
//! (eight) boxes per node fetch, and the stack sees fewer pushes (Wald et al. 2008,
//! "Getting rid of packets"; Ylitie et al. 2017 measured compressed 8-wide nodes at
//! 1.5–2× binary ones on GPUs, in a wavefront tracer). An 8-wide node is two consecutive
//! [`WideNode`]s, children 0–3 and 4–7, so that both widths share one node struct and
//! one slab test.
//!
//! Measured, the 4-wide tree does not pay: in our path-tracing megakernel on an H100
//! (1080p, 1 spp, depth 5, viewer frames, same run) the binary BVH renders Sponza at 47
//! frames/s and the 4-wide at 30, the Cornell box at 223 and 151, a 1.1M-triangle mesh at
//! 246 and 209 — the 128-byte nodes and the unrolled child loop cost more than the visits
//! they save (the megakernel's occupancy is bound by its registers). The 8-wide tree is
//! slower still (an H200: 0.12–0.33× the binary tree's samples/s). So the binary BVH is
//! the default (`auto`); the wide layouts stay for comparisons and as the starting point
//! for compressed nodes. In the wavefront (`--wavefront`), whose extension stage holds only
//! the traversal, the 4-wide tree does pay: +24 % on the Cornell box, +10 % on a 1.1M-triangle
//! mesh on an H200 (docs/gpu.md).
//!
//! The collapse is greedy by surface area: starting from a binary node's two children,
//! the child node with the largest box is replaced by its own two children until all
//! slots are filled or only leaves remain. Leaves keep their triangle ranges (the
//! triangles stay in the binary BVH's leaf order), so a wide traversal finds the same
//! triangles as the binary one.

use crate::kernel::{WIDE_EMPTY, WideNode};
use bvh::{Aabb, Bvh, BvhNode};

/// Children per [`WideNode`] (an 8-wide node is two of them).
pub const WIDTH: usize = 4;

/// A 4- or 8-wide BVH in the kernel's layout.
pub struct WideBvh {
    /// Nodes, the root first; with [`WideBvh::width`] 8 each node is two entries, and a
    /// child's index is that of its first.
    pub nodes: Vec<WideNode>,
    /// The most stack entries a traversal can need (see [`WideBvh::stack_bound`]).
    pub stack_bound: u32,
    /// Children per node: 4 or 8.
    pub width: usize,
}

fn area(n: &BvhNode) -> f32 {
    Aabb { min: glam::Vec3::from_array(n.min), max: glam::Vec3::from_array(n.max) }.surface_area()
}

impl WideBvh {
    /// Collapses `bvh` (node 0 its root; an internal node's left child follows it, its
    /// right child is `index`) into nodes of `width` children (4 or 8).
    ///
    /// # Panics
    /// For another width (the kernel traverses these two).
    pub fn collapse(bvh: &Bvh, width: usize) -> Self {
        assert!(width == 4 || width == 8, "a wide GPU BVH has 4 or 8 children per node, not {width}");
        let binary = bvh.nodes();
        let mut wide = Self { nodes: Vec::with_capacity(binary.len() / 2 + 1), stack_bound: 1, width };
        if binary.is_empty() {
            return wide;
        }
        let source = Source { binary, width, subtrees: (width == 8).then(|| subtree_ranges(binary)) };
        // The root is always a wide node, even over a single leaf.
        let root_children = if source.leaf(0).is_some() { vec![0] } else { source.children(0) };
        let need = wide.emit(&source, &root_children);
        wide.stack_bound = need.max(1);
        wide
    }

    /// Appends the wide node over `slots` and, depth first, the nodes under it; returns
    /// the most stack entries a traversal from it can hold: at a node, all but one of
    /// its child nodes may be pushed, and the deepest child adds its own.
    fn emit(&mut self, source: &Source, slots: &[u32]) -> u32 {
        let me = self.nodes.len();
        let empty = WideNode { count: [WIDE_EMPTY; 4], index: [0; 4], ..WideNode::default() };
        // Empty slots keep finite (zero) boxes: their count marks them.
        self.nodes.extend(std::iter::repeat_n(empty, self.width / WIDTH));
        let mut inner = Vec::new();
        for (slot, &b) in slots.iter().enumerate() {
            let c = &source.binary[b as usize];
            let (node, i) = (&mut self.nodes[me + slot / WIDTH], slot % WIDTH);
            node.lo_x[i] = c.min[0];
            node.lo_y[i] = c.min[1];
            node.lo_z[i] = c.min[2];
            node.hi_x[i] = c.max[0];
            node.hi_y[i] = c.max[1];
            node.hi_z[i] = c.max[2];
            // A leaf's triangle range; a child node's index is set once it is emitted.
            match source.leaf(b) {
                Some((first, count)) => (node.index[i], node.count[i]) = (first, count),
                None => {
                    node.count[i] = 0;
                    inner.push((slot, b));
                }
            }
        }
        let mut deepest = 0;
        for &(slot, b) in &inner {
            let child = self.nodes.len() as u32;
            self.nodes[me + slot / WIDTH].index[slot % WIDTH] = child;
            let grandchildren = source.children(b);
            deepest = deepest.max(self.emit(source, &grandchildren));
        }
        inner.len().saturating_sub(1) as u32 + deepest
    }
}

/// The most triangles of a binary subtree that the 8-wide collapse turns into one leaf.
pub const MERGED_LEAF: u32 = 4;

/// The binary tree a [`WideBvh`] is collapsed from, and how.
struct Source<'a> {
    binary: &'a [BvhNode],
    width: usize,
    /// With the 8-wide collapse: each binary node's triangle range (first, count).
    subtrees: Option<Vec<(u32, u32)>>,
}

impl Source<'_> {
    /// The triangle range of binary node `b` if it becomes a leaf slot: a leaf's own, and
    /// in the 8-wide collapse that of any subtree of at most [`MERGED_LEAF`] triangles (a
    /// greedy 8-wide collapse otherwise leaves nodes of two or three leaves at the bottom
    /// of the tree whenever its depth is not a multiple of three).
    fn leaf(&self, b: u32) -> Option<(u32, u32)> {
        let n = &self.binary[b as usize];
        if n.count > 0 {
            return Some((n.index, n.count));
        }
        let range = self.subtrees.as_ref()?[b as usize];
        (range.1 <= MERGED_LEAF).then_some(range)
    }

    /// Up to `width` binary nodes (indices) under internal node `b`, larger boxes opened
    /// first.
    fn children(&self, b: u32) -> Vec<u32> {
        let binary = self.binary;
        let mut slots = vec![b + 1, binary[b as usize].index];
        while slots.len() < self.width {
            let open = slots
                .iter()
                .enumerate()
                .filter(|&(_, &s)| self.leaf(s).is_none())
                .max_by(|&(_, &a), &(_, &b)| area(&binary[a as usize]).total_cmp(&area(&binary[b as usize])));
            let Some((i, &c)) = open else { break };
            slots[i] = c + 1;
            slots.push(binary[c as usize].index);
        }
        slots
    }
}

/// Each binary node's triangles as one range (first, count) of the leaf-ordered triangles:
/// children follow their parent in `binary`, so one pass from the back finds every range.
/// Our builders lay a subtree's leaves out contiguously; where a tree does not (its two
/// children's ranges do not meet), the node gets count `u32::MAX` and is never merged.
fn subtree_ranges(binary: &[BvhNode]) -> Vec<(u32, u32)> {
    let mut ranges = vec![(0, 0); binary.len()];
    for b in (0..binary.len()).rev() {
        let n = &binary[b];
        ranges[b] = if n.count > 0 {
            (n.index, n.count)
        } else {
            let (left, right) = (ranges[b + 1], ranges[n.index as usize]);
            match left.1.checked_add(right.1) {
                Some(count) if left.0.checked_add(left.1) == Some(right.0) => (left.0, count),
                _ => (0, u32::MAX),
            }
        };
    }
    ranges
}

#[cfg(test)]
mod tests {
    use super::*;
    use bvh::{BuildConfig, SplitMethod};
    use glam::Vec3;

    fn soup(n: usize) -> Vec<[Vec3; 3]> {
        // A deterministic scatter of small triangles.
        let mut s = 1u32;
        let mut next = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(next(), next(), next()) * 10.0;
                [c, c + Vec3::new(next(), 0.0, 0.0) * 0.3, c + Vec3::new(0.0, next(), next()) * 0.3]
            })
            .collect()
    }

    fn binary(n: usize) -> Bvh {
        built_by(n, SplitMethod::BinnedSah)
    }

    fn built_by(n: usize, method: SplitMethod) -> Bvh {
        let config = BuildConfig { method, max_leaf_size: 4, leaf_by_sah: true, ..BuildConfig::default() };
        Bvh::build(&soup(n), config).unwrap()
    }

    /// Child `k` of the wide node at entry `node`: (lower corner, upper corner, index, count).
    pub(super) fn slot(w: &WideBvh, node: usize, k: usize) -> (Vec3, Vec3, u32, u32) {
        let n = &w.nodes[node + k / WIDTH];
        let i = k % WIDTH;
        (Vec3::new(n.lo_x[i], n.lo_y[i], n.lo_z[i]), Vec3::new(n.hi_x[i], n.hi_y[i], n.hi_z[i]), n.index[i], n.count[i])
    }

    /// Every triangle is in exactly one leaf slot, every node is reached once, and every
    /// child's box holds what is under it.
    #[test]
    fn the_collapse_keeps_every_triangle_once_and_boxes_nest() {
        for width in [4, 8] {
            for n in [1, 3, 5, 17, 1000, 20_000] {
                let b = binary(n);
                let w = WideBvh::collapse(&b, width);
                let entries = width / WIDTH;
                assert_eq!(w.nodes.len() % entries, 0);
                let mut seen = vec![0u32; n];
                let mut reached = vec![0u32; w.nodes.len()];
                let mut stack = vec![0usize];
                reached[0] = 1;
                while let Some(i) = stack.pop() {
                    for k in 0..width {
                        let (lo, hi, index, count) = slot(&w, i, k);
                        match count {
                            WIDE_EMPTY => {}
                            0 => {
                                let c = index as usize;
                                assert_eq!(c % entries, 0, "a child index inside a node");
                                reached[c] += 1;
                                for j in 0..width {
                                    let (clo, chi, _, ccount) = slot(&w, c, j);
                                    if ccount != WIDE_EMPTY {
                                        assert!(clo.cmpge(lo).all() && chi.cmple(hi).all(), "width {width}");
                                    }
                                }
                                stack.push(c);
                            }
                            count => {
                                for t in index..index + count {
                                    seen[t as usize] += 1;
                                }
                            }
                        }
                    }
                }
                assert!(seen.iter().all(|&s| s == 1), "{n} triangles: some in no leaf or in two");
                let mut firsts = reached.iter().step_by(entries);
                assert!(firsts.all(|&r| r == 1), "{n} triangles: a node reached twice or never");
                // Wide nodes: fewer than half of the binary count; 8-wide ones (with small
                // subtrees merged into leaves) fewer than an eighth.
                let nodes = w.nodes.len() / entries;
                if n >= 1000 {
                    let slots: usize = (0..nodes)
                        .map(|i| (0..width).filter(|&k| slot(&w, i * entries, k).3 != WIDE_EMPTY).count())
                        .sum();
                    let mean = slots as f64 / nodes as f64;
                    println!(
                        "{n} triangles: {} binary nodes, {nodes} {width}-wide, {mean:.2} children each",
                        b.nodes().len()
                    );
                    if width == 4 {
                        assert!(nodes * 2 < b.nodes().len(), "{nodes} 4-wide for {} binary", b.nodes().len());
                        // Every wide node but those over two leaves is full.
                        assert!(mean > 2.8, "{mean:.2} children per node");
                    } else {
                        assert!(nodes * 8 < b.nodes().len(), "{nodes} 8-wide for {} binary", b.nodes().len());
                    }
                }
            }
        }
    }

    /// Every builder's tree lays a subtree's leaves out contiguously, so that the 8-wide
    /// collapse merges small subtrees into single leaves; a tree whose ranges do not meet
    /// is collapsed without merging, every triangle still in one leaf.
    #[test]
    fn small_subtrees_merge_into_leaves_with_every_builder() {
        for method in SplitMethod::ALL {
            let b = built_by(5000, method);
            let ranges = subtree_ranges(b.nodes());
            assert_eq!(ranges[0], (0, 5000), "{method:?}: the root covers every triangle");
            let w = WideBvh::collapse(&b, 8);
            let leaves: Vec<u32> = (0..w.nodes.len())
                .step_by(2)
                .flat_map(|i| (0..8).map(move |k| (i, k)))
                .map(|(i, k)| slot(&w, i, k).3)
                .filter(|&c| c != 0 && c != WIDE_EMPTY)
                .collect();
            assert_eq!(leaves.iter().sum::<u32>(), 5000, "{method:?}");
            let binary_leaves = b.nodes().iter().filter(|n| n.count > 0).count();
            assert!(
                leaves.len() < binary_leaves,
                "{method:?}: {} leaf slots, {binary_leaves} binary leaves",
                leaves.len()
            );
            assert!(leaves.iter().all(|&c| c <= MERGED_LEAF), "{method:?}: a leaf above four triangles");
        }
        // Ranges that do not meet (the right child's leaf starts past the left's end).
        let mut nodes = built_by(40, SplitMethod::BinnedSah).nodes().to_vec();
        let last_leaf = nodes.iter().rposition(|n| n.count > 0).unwrap();
        nodes[last_leaf].index += 1;
        assert!(subtree_ranges(&nodes).iter().any(|r| r.1 == u32::MAX));
        assert_eq!(subtree_ranges(&nodes)[0].1, u32::MAX, "the root's range is broken too");
    }

    /// The stack bound is what a traversal pushing every child node but one can hold.
    #[test]
    fn the_stack_bound_covers_the_deepest_pushes() {
        for width in [4, 8] {
            let w = WideBvh::collapse(&binary(20_000), width);
            fn need(w: &WideBvh, i: usize) -> u32 {
                let inner: Vec<usize> =
                    (0..w.width).map(|k| slot(w, i, k)).filter(|s| s.3 == 0).map(|s| s.2 as usize).collect();
                inner.len().saturating_sub(1) as u32 + inner.iter().map(|&c| need(w, c)).max().unwrap_or(0)
            }
            assert_eq!(w.stack_bound, need(&w, 0).max(1));
            assert!(w.stack_bound >= 3 && w.stack_bound < 64, "bound {}", w.stack_bound);
            let single = WideBvh::collapse(&binary(1), width);
            assert_eq!((single.nodes.len(), single.stack_bound), (width / WIDTH, 1));
            assert_eq!(single.nodes[0].count, [1, WIDE_EMPTY, WIDE_EMPTY, WIDE_EMPTY]);
        }
    }

    /// The transcribed wide traversal finds the binary BVH's closest hit for every ray
    /// (the same triangle and t), and never needs more stack than the bound.
    #[test]
    fn the_wide_traversal_finds_the_binary_hits() {
        use bvh::Accelerator;
        let tris = soup(3000);
        let config = BuildConfig {
            method: SplitMethod::BinnedSah,
            max_leaf_size: 4,
            leaf_by_sah: true,
            ..BuildConfig::default()
        };
        let b = Bvh::build(&tris, config).unwrap();
        let wides = [WideBvh::collapse(&b, 4), WideBvh::collapse(&b, 8)];
        let mut s = 7u32;
        let mut next = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..20_000 {
            let o = Vec3::new(next(), next(), next()) * 14.0 - Vec3::splat(2.0);
            let d = (Vec3::new(next(), next(), next()) - Vec3::splat(0.5)).normalize_or(Vec3::X);
            let ray = bvh::Ray::new(o, d);
            let expected = b.intersect(&ray).map(|h| (h.t, h.prim));
            for w in &wides {
                let found = super::tests_support::wide_closest(w, b.prim_ids(), &tris, &ray);
                assert_eq!(found, expected, "{}-wide, ray {o:?} {d:?}", w.width);
            }
            if expected.is_some() { hits += 1 } else { misses += 1 }
        }
        assert!(hits > 1000 && misses > 1000, "{hits} hits, {misses} misses");
    }
}
#[cfg(test)]
mod tests_support {
    use super::*;
    use glam::Vec3;
    /// `traversal_wide.wgsl`'s and `traversal_wide8.wgsl`'s algorithm, transcribed: leaves
    /// first, child nodes nearest first, farther ones pushed farthest first, culled
    /// against the closest hit (the WGSL's sorting and merge networks are exercised by the
    /// GPU test `wide_and_binary_bvhs_give_the_same_image`, here a sort).
    /// (Found when the WGSL was written with loops over the four slots: lavapipe
    /// rendered the Cornell box with 7 % fewer rays at depth 5 than the binary traversal
    /// while this transcription agreed with the binary BVH on every ray; the unrolled
    /// WGSL with a sorting network gives the binary traversal's image byte for byte.)
    pub fn wide_closest(w: &WideBvh, prims: &[u32], tris: &[[Vec3; 3]], ray: &bvh::Ray) -> Option<(f32, u32)> {
        let mut t_max = ray.t_max;
        let mut best = None;
        let mut stack: Vec<(u32, f32)> = Vec::new();
        let mut node = 0usize;
        loop {
            let slots: Vec<_> = (0..w.width).map(|k| super::tests::slot(w, node, k)).collect();
            let mut near = [0.0f32; 8];
            let mut hit = [false; 8];
            for (i, &(lo, hi, _, count)) in slots.iter().enumerate() {
                let (t0, t1) = ((lo - ray.origin) * ray.inv_dir, (hi - ray.origin) * ray.inv_dir);
                near[i] = t0.min(t1).max_element().max(ray.t_min);
                let far = t0.max(t1).min_element().min(t_max);
                hit[i] = near[i] <= far && count != WIDE_EMPTY;
            }
            for (i, &(_, _, index, count)) in slots.iter().enumerate() {
                if hit[i] && count > 0 {
                    for k in index..index + count {
                        let tri = bvh::Triangle::new(&tris[prims[k as usize] as usize]);
                        if let Some((t, _, _)) = bvh::intersect_triangle(&tri, ray, t_max) {
                            t_max = t;
                            best = Some((t, prims[k as usize]));
                        }
                    }
                }
            }
            let mut cand: Vec<(u32, f32)> = (0..w.width)
                .filter(|&i| hit[i] && slots[i].3 == 0 && near[i] <= t_max)
                .map(|i| (slots[i].2, near[i]))
                .collect();
            cand.sort_by(|a, b| b.1.total_cmp(&a.1));
            if let Some(&(next, _)) = cand.last() {
                stack.extend(&cand[..cand.len() - 1]);
                assert!(
                    stack.len() as u32 <= w.stack_bound,
                    "stack {} beyond the bound {}",
                    stack.len(),
                    w.stack_bound
                );
                node = next as usize;
                continue;
            }
            loop {
                match stack.pop() {
                    None => return best,
                    Some((next, t)) if t <= t_max => {
                        node = next as usize;
                        break;
                    }
                    Some(_) => {}
                }
            }
        }
    }
}
