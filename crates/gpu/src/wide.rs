//! The GPU's 4-wide BVH (`--bvh-width 4`): the binary BVH (binned SAH, leaves ≤ 4)
//! collapsed so that each node holds up to four children — a ray tests four boxes per
//! node fetch, and the stack sees fewer pushes (Wald et al. 2008, "Getting rid of
//! packets"; Ylitie et al. 2017 measured compressed 8-wide nodes at 1.5–2× binary ones on
//! GPUs, in a wavefront tracer).
//!
//! Measured here it does not pay: in our path-tracing megakernel on an H100 (1080p, 1
//! spp, depth 5, viewer frames, same run) the binary BVH renders Sponza at 47 frames/s
//! and the 4-wide at 30, the Cornell box at 223 and 151, a 1.1M-triangle mesh at 246 and
//! 209 — the 128-byte nodes and the unrolled child loop cost more than the visits they
//! save (the megakernel's occupancy is bound by its registers). So the binary BVH is the
//! default (`auto`); this layout stays for comparisons and as the starting point for
//! compressed nodes or a wavefront kernel (docs/gpu.md).
//!
//! The collapse is greedy by surface area: starting from a binary node's two children,
//! the child node with the largest box is replaced by its own two children until four
//! slots are filled or only leaves remain. Leaves keep their triangle ranges (the
//! triangles stay in the binary BVH's leaf order), so a wide traversal finds the same
//! triangles as the binary one.

use crate::kernel::{WIDE_EMPTY, WideNode};
use bvh::{Aabb, Bvh, BvhNode};

/// Children per node.
pub const WIDTH: usize = 4;

/// A 4-wide BVH in the kernel's layout.
pub struct WideBvh {
    /// Nodes, the root first.
    pub nodes: Vec<WideNode>,
    /// The most stack entries a traversal can need (see [`WideBvh::stack_bound`]).
    pub stack_bound: u32,
}

fn area(n: &BvhNode) -> f32 {
    Aabb { min: glam::Vec3::from_array(n.min), max: glam::Vec3::from_array(n.max) }.surface_area()
}

impl WideBvh {
    /// Collapses `bvh` (node 0 its root; an internal node's left child follows it, its
    /// right child is `index`).
    pub fn collapse(bvh: &Bvh) -> Self {
        let binary = bvh.nodes();
        let mut wide = Self { nodes: Vec::with_capacity(binary.len() / 2 + 1), stack_bound: 1 };
        if binary.is_empty() {
            return wide;
        }
        // The root is always a wide node, even over a single leaf.
        let root_children = if binary[0].count > 0 { vec![0] } else { Self::children(binary, 0) };
        let need = wide.emit(binary, &root_children);
        wide.stack_bound = need.max(1);
        wide
    }

    /// Up to four binary nodes (indices) under internal node `b`, larger boxes opened
    /// first.
    fn children(binary: &[BvhNode], b: u32) -> Vec<u32> {
        let mut slots = vec![b + 1, binary[b as usize].index];
        while slots.len() < WIDTH {
            let open = slots
                .iter()
                .enumerate()
                .filter(|&(_, &s)| binary[s as usize].count == 0)
                .max_by(|&(_, &a), &(_, &b)| area(&binary[a as usize]).total_cmp(&area(&binary[b as usize])));
            let Some((i, &c)) = open else { break };
            slots[i] = c + 1;
            slots.push(binary[c as usize].index);
        }
        slots
    }

    /// Appends the wide node over `slots` and, depth first, the nodes under it; returns
    /// the most stack entries a traversal from it can hold: at a node, all but one of
    /// its child nodes may be pushed, and the deepest child adds its own.
    fn emit(&mut self, binary: &[BvhNode], slots: &[u32]) -> u32 {
        let me = self.nodes.len();
        let mut node = WideNode { count: [WIDE_EMPTY; 4], index: [0; 4], ..WideNode::default() };
        // Empty slots keep finite (zero) boxes: their count marks them.
        for (i, &b) in slots.iter().enumerate() {
            let c = &binary[b as usize];
            node.lo_x[i] = c.min[0];
            node.lo_y[i] = c.min[1];
            node.lo_z[i] = c.min[2];
            node.hi_x[i] = c.max[0];
            node.hi_y[i] = c.max[1];
            node.hi_z[i] = c.max[2];
            // A leaf's triangle range; a child node's index is set once it is emitted.
            node.index[i] = c.index;
            node.count[i] = c.count;
        }
        self.nodes.push(node);
        let inner: Vec<(usize, u32)> =
            slots.iter().enumerate().filter(|&(_, &s)| binary[s as usize].count == 0).map(|(i, &s)| (i, s)).collect();
        let mut deepest = 0;
        for &(i, b) in &inner {
            let child = self.nodes.len() as u32;
            self.nodes[me].index[i] = child;
            let grandchildren = Self::children(binary, b);
            deepest = deepest.max(self.emit(binary, &grandchildren));
        }
        inner.len().saturating_sub(1) as u32 + deepest
    }
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
        let config = BuildConfig {
            method: SplitMethod::BinnedSah,
            max_leaf_size: 4,
            leaf_by_sah: true,
            ..BuildConfig::default()
        };
        Bvh::build(&soup(n), config).unwrap()
    }

    /// Every triangle is in exactly one leaf slot, every node is reached once, and every
    /// child's box holds what is under it.
    #[test]
    fn the_collapse_keeps_every_triangle_once_and_boxes_nest() {
        for n in [1, 3, 5, 17, 1000, 20_000] {
            let b = binary(n);
            let w = WideBvh::collapse(&b);
            let mut seen = vec![0u32; n];
            let mut reached = vec![0u32; w.nodes.len()];
            let mut stack = vec![0usize];
            reached[0] = 1;
            while let Some(i) = stack.pop() {
                let node = &w.nodes[i];
                for k in 0..4 {
                    match node.count[k] {
                        WIDE_EMPTY => {}
                        0 => {
                            let c = node.index[k] as usize;
                            reached[c] += 1;
                            let child = &w.nodes[c];
                            for j in 0..4 {
                                if child.count[j] != WIDE_EMPTY {
                                    assert!(child.lo_x[j] >= node.lo_x[k] && child.hi_x[j] <= node.hi_x[k]);
                                    assert!(child.lo_y[j] >= node.lo_y[k] && child.hi_y[j] <= node.hi_y[k]);
                                    assert!(child.lo_z[j] >= node.lo_z[k] && child.hi_z[j] <= node.hi_z[k]);
                                }
                            }
                            stack.push(c);
                        }
                        count => {
                            for t in node.index[k]..node.index[k] + count {
                                seen[t as usize] += 1;
                            }
                        }
                    }
                }
            }
            assert!(seen.iter().all(|&s| s == 1), "{n} triangles: some in no leaf or in two");
            assert!(reached.iter().all(|&r| r == 1), "{n} triangles: a node reached twice or never");
            // Wide nodes: about a third of the binary count (each holds up to 4 of them).
            if n >= 1000 {
                assert!(w.nodes.len() * 2 < b.nodes().len(), "{} wide for {} binary", w.nodes.len(), b.nodes().len());
                // Every wide node but those over two leaves is full: the slots hold on
                // average well over three children.
                let slots: usize = w.nodes.iter().map(|n| n.count.iter().filter(|&&c| c != WIDE_EMPTY).count()).sum();
                let mean = slots as f64 / w.nodes.len() as f64;
                println!(
                    "{n} triangles: {} binary nodes, {} wide, {mean:.2} children each",
                    b.nodes().len(),
                    w.nodes.len()
                );
                assert!(mean > 2.8, "{mean:.2} children per node");
            }
        }
    }

    /// The stack bound is what a traversal pushing every child node but one can hold.
    #[test]
    fn the_stack_bound_covers_the_deepest_pushes() {
        let w = WideBvh::collapse(&binary(20_000));
        fn need(w: &WideBvh, i: usize) -> u32 {
            let inner: Vec<usize> =
                (0..4).filter(|&k| w.nodes[i].count[k] == 0).map(|k| w.nodes[i].index[k] as usize).collect();
            inner.len().saturating_sub(1) as u32 + inner.iter().map(|&c| need(w, c)).max().unwrap_or(0)
        }
        assert_eq!(w.stack_bound, need(&w, 0).max(1));
        assert!(w.stack_bound >= 3 && w.stack_bound < 64, "bound {}", w.stack_bound);
        let single = WideBvh::collapse(&binary(1));
        assert_eq!((single.nodes.len(), single.stack_bound), (1, 1));
        assert_eq!(single.nodes[0].count, [1, WIDE_EMPTY, WIDE_EMPTY, WIDE_EMPTY]);
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
        let w = WideBvh::collapse(&b);
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
            assert_eq!(super::tests_support::wide_closest(&w, b.prim_ids(), &tris, &ray), expected, "ray {o:?} {d:?}");
            if expected.is_some() { hits += 1 } else { misses += 1 }
        }
        assert!(hits > 1000 && misses > 1000, "{hits} hits, {misses} misses");
    }
}
#[cfg(test)]
mod tests_support {
    use super::*;
    use glam::Vec3;
    /// `traversal_wide.wgsl`'s algorithm, transcribed: leaves first, child nodes nearest
    /// first, farther ones pushed farthest first, culled against the closest hit.
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
            let n = &w.nodes[node];
            let mut near = [0.0f32; 4];
            let mut hit = [false; 4];
            for i in 0..4 {
                let lo = Vec3::new(n.lo_x[i], n.lo_y[i], n.lo_z[i]);
                let hi = Vec3::new(n.hi_x[i], n.hi_y[i], n.hi_z[i]);
                let (t0, t1) = ((lo - ray.origin) * ray.inv_dir, (hi - ray.origin) * ray.inv_dir);
                near[i] = t0.min(t1).max_element().max(ray.t_min);
                let far = t0.max(t1).min_element().min(t_max);
                hit[i] = near[i] <= far && n.count[i] != WIDE_EMPTY;
            }
            for i in 0..4 {
                if hit[i] && n.count[i] > 0 {
                    for k in n.index[i]..n.index[i] + n.count[i] {
                        let tri = bvh::Triangle::new(&tris[prims[k as usize] as usize]);
                        if let Some((t, _, _)) = bvh::intersect_triangle(&tri, ray, t_max) {
                            t_max = t;
                            best = Some((t, prims[k as usize]));
                        }
                    }
                }
            }
            let mut cand: Vec<(u32, f32)> = (0..4)
                .filter(|&i| hit[i] && n.count[i] == 0 && near[i] <= t_max)
                .map(|i| (n.index[i], near[i]))
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
