//! A 4-wide BVH ([`Bvh4`]) collapsed from a binary [`Bvh`], traversed with SIMD.
//!
//! * Nodes: each [`Bvh4Node`] holds the boxes of up to four children in
//!   structure-of-arrays form, so that one ray is tested against all four at once (SSE on
//!   x86_64, a scalar loop with the same semantics elsewhere).
//! * Collapse: the children of a wide node are found greedily — starting from a binary
//!   node's two children, the interior child with the largest surface area is replaced by
//!   its own two children until there are four or only leaves are left.
//! * Leaves: binary subtrees of at most four triangles become one leaf where an SAH that
//!   counts one 4-wide triangle test per leaf says so. A leaf's triangles are stored in
//!   structure-of-arrays form and tested four at a time with the operations of
//!   [`intersect_triangle`], lane by lane, so hits are bit-identical to it.
//! * Traversal is ordered: the children a ray enters are visited nearest first, the
//!   others are pushed with their entry distance and culled on pop against the closest
//!   hit so far.

use crate::{
    Aabb, Accelerator, BuildConfig, BuildError, Bvh, BvhNode, Hit, Ray, RayStats, Triangle, TriangleTest,
    WatertightRay, intersect_triangle, intersect_triangle_watertight,
};
use glam::Vec3;
use std::mem::MaybeUninit;

/// Children per wide node.
const WIDTH: usize = 4;

/// Entries of the traversal stack: a wide node pushes at most `WIDTH − 1` children and
/// the binary trees our builders make are at most 62 levels deep, so a path holds at
/// most 62 wide nodes; [`Bvh4::from_bvh`] checks the bound.
const STACK_DEPTH: usize = (WIDTH - 1) * 64;

/// One node of a [`Bvh4`]: the boxes of up to four children as structure of arrays,
/// 128 bytes (two cache lines), 64-byte aligned, POD.
///
/// Slot `i` is a leaf of triangles `child[i] .. child[i] + count[i]` in the tree's leaf
/// order ([`Bvh4::prim_ids`]) if `count[i] > 0`, else the interior node `child[i]`.
/// Unused slots have an empty box (min = +∞, max = −∞) that no ray enters.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(64))]
pub struct Bvh4Node {
    /// Lower x of each child's box.
    pub min_x: [f32; 4],
    /// Lower y of each child's box.
    pub min_y: [f32; 4],
    /// Lower z of each child's box.
    pub min_z: [f32; 4],
    /// Upper x of each child's box.
    pub max_x: [f32; 4],
    /// Upper y of each child's box.
    pub max_y: [f32; 4],
    /// Upper z of each child's box.
    pub max_z: [f32; 4],
    /// Interior child: its node index; leaf child: its first triangle.
    pub child: [u32; 4],
    /// Triangles in a leaf child; 0 for an interior child or an unused slot.
    pub count: [u32; 4],
}

impl Bvh4Node {
    /// A node whose four slots are all unused.
    pub const EMPTY: Self = Self {
        min_x: [f32::INFINITY; 4],
        min_y: [f32::INFINITY; 4],
        min_z: [f32::INFINITY; 4],
        max_x: [f32::NEG_INFINITY; 4],
        max_y: [f32::NEG_INFINITY; 4],
        max_z: [f32::NEG_INFINITY; 4],
        child: [0; 4],
        count: [0; 4],
    };

    /// The box of slot `i` (empty for an unused slot).
    pub fn child_bounds(&self, i: usize) -> Aabb {
        Aabb {
            min: Vec3::new(self.min_x[i], self.min_y[i], self.min_z[i]),
            max: Vec3::new(self.max_x[i], self.max_y[i], self.max_z[i]),
        }
    }

    /// The union of the children's boxes.
    pub fn bounds(&self) -> Aabb {
        (0..WIDTH).fold(Aabb::EMPTY, |b, i| b.union(self.child_bounds(i)))
    }

    fn set_child(&mut self, i: usize, bounds: &Aabb, child: u32, count: u32) {
        (self.min_x[i], self.min_y[i], self.min_z[i]) = bounds.min.into();
        (self.max_x[i], self.max_y[i], self.max_z[i]) = bounds.max.into();
        self.child[i] = child;
        self.count[i] = count;
    }

    /// The node's six plane rows, in field order (min x, y, z, max x, y, z).
    #[inline(always)]
    fn planes(&self) -> &[[f32; 4]; 8] {
        bytemuck::cast_ref(self)
    }
}

/// Figures describing a built [`Bvh4`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bvh4Stats {
    /// Wide nodes.
    pub nodes: usize,
    /// Leaf child slots: the source tree's leaves, some merged (see [`Bvh4::from_bvh`]).
    pub leaves: usize,
    /// Levels including the leaf level (a root whose children are all leaves gives 2).
    pub depth: usize,
    /// Σ_nodes C_t·A/A_root + Σ_leaves C_i·n·A/A_root with the source tree's cost
    /// constants: one traversal step per wide node, as for obvhs's CWBVH, and one test per
    /// triangle (although a leaf's triangles are tested four at a time).
    pub sah_cost: f32,
}

/// A 4-wide BVH over triangles, collapsed from a binary [`Bvh`].
#[derive(Clone, Debug)]
pub struct Bvh4 {
    nodes: Vec<Bvh4Node>,
    /// The triangles leaf by leaf in structure of arrays: a leaf of n triangles starting
    /// at triangle `first` holds v0.x × n, v0.y × n, …, v2.z × n from float 9·first; three
    /// floats of padding at the end let 4-wide loads run past the last leaf. Vertices,
    /// not edges, so that the watertight test sees each shared vertex bit for bit.
    soa: Vec<f32>,
    prim_ids: Vec<u32>,
    costs: (f32, f32),
    test: TriangleTest,
}

impl Bvh4 {
    /// Builds a binary [`Bvh`] with `config` and collapses it; rejects non-finite
    /// coordinates. An empty input gives a tree that nothing hits.
    pub fn build(triangles: &[[Vec3; 3]], config: BuildConfig) -> Result<Self, BuildError> {
        let bvh = Bvh::build(triangles, config)?;
        Ok(Self::collapse(&bvh, |i| triangles[bvh.prim_ids()[i] as usize]))
    }

    /// The triangle test this tree runs ([`TriangleTest::Watertight`] by default).
    pub fn triangle_test(&self) -> TriangleTest {
        self.test
    }

    /// Selects the triangle test.
    pub fn with_triangle_test(mut self, test: TriangleTest) -> Self {
        self.test = test;
        self
    }

    /// Collapses a binary tree into a 4-wide one (greedy by surface area), copying its
    /// leaf-ordered triangles. A binary subtree of at most four triangles becomes a single
    /// leaf when that lowers an SAH in which a leaf costs one 4-wide triangle test and a
    /// binary interior node 0.3 of one; trees whose leaves were split down to at most four
    /// triangles regardless of the SAH (`leaf_by_sah: false`, `max_leaf_size ≤ 4`) keep
    /// their leaves exactly.
    ///
    /// # Panics
    ///
    /// If the tree is deeper than the traversal stack allows, which our builders never
    /// produce (they stop at 62 levels).
    ///
    /// The binary tree keeps vertex 0 and two edges; the vertices are rebuilt as v0 + e,
    /// which may differ from the mesh's in the last bit, so that the watertight guarantee
    /// holds only for trees made by [`Bvh4::build`].
    pub fn from_bvh(bvh: &Bvh) -> Self {
        Self::collapse(bvh, |i| {
            let t = &bvh.triangles()[i];
            let v0 = Vec3::from_array(t.v0);
            [v0, v0 + Vec3::from_array(t.e1), v0 + Vec3::from_array(t.e2)]
        })
    }

    /// Collapses `bvh`, taking the vertices of its `i`-th leaf-ordered triangle from
    /// `vertices(i)`.
    fn collapse(bvh: &Bvh, vertices: impl Fn(usize) -> [Vec3; 3]) -> Self {
        let mut collapse = Collapse::new(bvh.nodes());
        if !bvh.nodes().is_empty() {
            collapse.node(0);
        }
        let nodes = collapse.out;
        let config = bvh.config();
        let mut soa = vec![0.0; 9 * bvh.triangles().len() + 3];
        for n in &nodes {
            for (&first, &count) in n.child.iter().zip(&n.count).filter(|(_, c)| **c > 0) {
                let (first, count) = (first as usize, count as usize);
                for i in 0..count {
                    for (k, x) in vertices(first + i).iter().flat_map(|v| v.to_array()).enumerate() {
                        soa[9 * first + k * count + i] = x;
                    }
                }
            }
        }
        let wide = Self {
            nodes,
            soa,
            prim_ids: bvh.prim_ids().to_vec(),
            costs: (config.traversal_cost, config.intersection_cost),
            test: TriangleTest::default(),
        };
        let depth = wide.stats().depth;
        assert!(
            depth.saturating_sub(1) * (WIDTH - 1) <= STACK_DEPTH,
            "BVH4 of depth {depth} overflows the traversal stack"
        );
        wide
    }

    /// The wide nodes (root first).
    pub fn nodes(&self) -> &[Bvh4Node] {
        &self.nodes
    }

    /// For each triangle in leaf order, its index in the input.
    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    /// Node count, leaf count, depth and SAH cost.
    pub fn stats(&self) -> Bvh4Stats {
        let mut s = Bvh4Stats { nodes: self.nodes.len(), ..Default::default() };
        let Some(root) = self.nodes.first() else {
            return s;
        };
        let root_area = root.bounds().surface_area().max(f32::MIN_POSITIVE) as f64;
        let (c_t, c_i) = (self.costs.0 as f64, self.costs.1 as f64);
        let mut cost = 0.0f64;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            s.depth = s.depth.max(depth);
            cost += c_t * n.bounds().surface_area() as f64 / root_area;
            for slot in 0..WIDTH {
                let b = n.child_bounds(slot);
                if b.is_empty() {
                    continue;
                }
                if n.count[slot] > 0 {
                    s.leaves += 1;
                    s.depth = s.depth.max(depth + 1);
                    cost += c_i * n.count[slot] as f64 * b.surface_area() as f64 / root_area;
                } else {
                    stack.push((n.child[slot] as usize, depth + 1));
                }
            }
        }
        s.sah_cost = cost as f32;
        s
    }

    #[inline(always)]
    fn traverse<K: RayKernel, const COUNT: bool, const ANY_HIT: bool>(
        &self,
        ray: &Ray,
        stats: &mut RayStats,
    ) -> Option<Hit> {
        if COUNT {
            stats.rays += 1;
        }
        // Such rays hit no triangle (Möller–Trumbore's determinant is not finite), and
        // they are the only ones that could enter an unused slot's empty box.
        if self.nodes.is_empty() || !ray.origin.is_finite() || !ray.dir.is_finite() {
            return None;
        }
        let kernel = K::new(ray);
        let watertight = (self.test == TriangleTest::Watertight).then(|| WatertightRay::new(ray));
        let mut t_max = ray.t_max;
        let mut best: Option<Hit> = None;
        // Uninitialised: zeroing 2 KiB would cost more than a short traversal.
        let mut stack = [MaybeUninit::<Entry>::uninit(); STACK_DEPTH];
        let mut sp = 0usize;
        let mut current = Entry::default();
        loop {
            if current.count == 0 {
                let node = &self.nodes[current.child as usize];
                if COUNT {
                    stats.nodes_visited += 1;
                }
                let (mask, t) = kernel.enter(node, t_max);
                if mask != 0 {
                    let entry = |i: usize| Entry { child: node.child[i], count: node.count[i], t: t[i] };
                    if mask & (mask - 1) == 0 {
                        current = entry(mask.trailing_zeros() as usize);
                        continue;
                    }
                    // Two to four children: nearest first, the others pushed far to near.
                    let mut hits = [Entry::default(); WIDTH];
                    let mut k = 0;
                    let mut m = mask;
                    while m != 0 {
                        hits[k] = entry(m.trailing_zeros() as usize);
                        self.prefetch(&hits[k]);
                        k += 1;
                        m &= m - 1;
                    }
                    sort_by_entry(&mut hits, k);
                    for e in hits[1..k].iter().rev() {
                        stack[sp] = MaybeUninit::new(*e);
                        sp += 1;
                    }
                    current = hits[0];
                    continue;
                }
            } else {
                let first = current.child as usize;
                let count = current.count as usize;
                if COUNT {
                    stats.triangles_tested += count as u64;
                }
                let leaf = Leaf { soa: &self.soa[9 * first..], ids: &self.prim_ids[first..first + count] };
                let done = match &watertight {
                    Some(w) => kernel.watertight::<ANY_HIT>(w, leaf, &mut t_max, &mut best),
                    None => kernel.triangles::<ANY_HIT>(ray, leaf, &mut t_max, &mut best),
                };
                if done {
                    return best;
                }
            }
            // Pop until a child that may still hold a closer hit.
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were all written by the pushes above.
                let e = unsafe { stack[sp].assume_init() };
                if e.t <= t_max {
                    current = e;
                    break;
                }
            }
        }
    }

    /// Starts loading a child's node or triangles into the cache, ahead of its visit.
    #[inline(always)]
    fn prefetch(&self, e: &Entry) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let (first, last) = if e.count == 0 {
                let p = self.nodes.as_ptr().wrapping_add(e.child as usize).cast::<i8>();
                (p, p.wrapping_add(size_of::<Bvh4Node>() - 1))
            } else {
                let p = self.soa.as_ptr().wrapping_add(9 * e.child as usize).cast::<i8>();
                (p, p.wrapping_add(e.count as usize * 9 * size_of::<f32>() - 1))
            };
            // SAFETY: SSE is baseline on x86_64, and a prefetch never faults.
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(first);
                _mm_prefetch::<_MM_HINT_T0>(last);
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = e;
    }
}

/// Subtrees of at most this many triangles may become one leaf: the SIMD triangle test
/// costs about the same for one to four triangles.
const MERGE: u32 = 4;

/// Cost of a binary interior node, relative to one 4-wide triangle test, in the SAH that
/// decides whether to merge a small subtree into one leaf (a wide node tests up to three
/// binary nodes' children at once).
const MERGE_NODE_COST: f32 = 0.3;

/// The greedy collapse of a binary tree.
struct Collapse<'a> {
    src: &'a [BvhNode],
    /// Per binary node: the first triangle and the number of triangles of its subtree
    /// (a contiguous range, as the builders append leaves depth-first; only used for
    /// leaves, where it is checked).
    range: Vec<(u32, u32)>,
    /// Per binary node: true if its subtree becomes one leaf of the wide tree.
    leaf: Vec<bool>,
    out: Vec<Bvh4Node>,
}

impl<'a> Collapse<'a> {
    fn new(src: &'a [BvhNode]) -> Self {
        // Children follow their parents, so one backward pass sees them first.
        let mut range = vec![(0u32, 0u32); src.len()];
        let mut leaf = vec![false; src.len()];
        // SAH cost (times the root's area) of each subtree with leaves tested 4 at a time.
        let mut cost = vec![0.0f32; src.len()];
        for (i, n) in src.iter().enumerate().rev() {
            let area = binary_bounds(n).surface_area();
            if n.count > 0 {
                range[i] = (n.index, n.count);
                leaf[i] = true;
                cost[i] = area * n.count.div_ceil(4) as f32;
            } else {
                let (l, r) = (i + 1, n.index as usize);
                let contiguous = range[l].0 + range[l].1 == range[r].0;
                range[i] = (range[l].0, range[l].1 + range[r].1);
                let split = MERGE_NODE_COST * area + cost[l] + cost[r];
                leaf[i] = contiguous && range[i].1 <= MERGE && area <= split;
                cost[i] = if leaf[i] { area } else { split };
            }
        }
        Self { src, range, leaf, out: Vec::with_capacity(src.len() / 2 + 1) }
    }

    /// True if binary node `i` becomes a leaf of the wide tree.
    fn is_leaf(&self, i: usize) -> bool {
        self.leaf[i]
    }

    /// Collapses the binary subtree at `root` (an interior node, or a root that is a leaf)
    /// into wide node(s) appended depth-first; returns the wide node's index.
    fn node(&mut self, root: usize) -> u32 {
        let src = self.src;
        let index = self.out.len();
        self.out.push(Bvh4Node::EMPTY);
        let area = |i: usize| binary_bounds(&src[i]).surface_area();
        let mut slots = [0usize; WIDTH];
        let mut n = if self.is_leaf(root) {
            slots[0] = root;
            1
        } else {
            slots[0] = root + 1;
            slots[1] = src[root].index as usize;
            2
        };
        while n < WIDTH {
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
        let mut node = Bvh4Node::EMPTY;
        for (i, &s) in slots[..n].iter().enumerate() {
            let (child, count) = if self.is_leaf(s) { self.range[s] } else { (self.node(s), 0) };
            node.set_child(i, &binary_bounds(&src[s]), child, count);
        }
        self.out[index] = node;
        index as u32
    }
}

fn binary_bounds(n: &BvhNode) -> Aabb {
    Aabb { min: Vec3::from_array(n.min), max: Vec3::from_array(n.max) }
}

/// A child to visit: a node (`count == 0`) or a leaf's triangle range, with the ray's
/// entry distance into its box.
#[derive(Clone, Copy, Default)]
struct Entry {
    child: u32,
    count: u32,
    t: f32,
}

/// Sorts the first `k` (≤ 4) entries by entry distance, nearest first (a sorting network).
#[inline(always)]
fn sort_by_entry(e: &mut [Entry; WIDTH], k: usize) {
    #[inline(always)]
    fn order(e: &mut [Entry; WIDTH], a: usize, b: usize) {
        if e[b].t < e[a].t {
            e.swap(a, b);
        }
    }
    match k {
        0 | 1 => {}
        2 => order(e, 0, 1),
        3 => {
            order(e, 0, 1);
            order(e, 1, 2);
            order(e, 0, 1);
        }
        4 => {
            order(e, 0, 1);
            order(e, 2, 3);
            order(e, 0, 2);
            order(e, 1, 3);
            order(e, 1, 2);
        }
        _ => unreachable!("at most four children"),
    }
}

/// A ray prepared for testing the four boxes of a [`Bvh4Node`] at once, and a leaf's
/// triangles.
///
/// Box conventions as in `SlabRay::enter` and [`Aabb::hit`]: closed boxes, entry in
/// (t_min, ∞) ∩ (−∞, t_max], and an origin on a slab plane with a zero direction component
/// (0·∞ = NaN) counts as inside that slab. The near and far planes are picked per axis by
/// the sign of the reciprocal direction (so −0 picks the max plane first), and every
/// slab distance is folded into an accumulator that starts at t_min or t_max with an
/// operation that keeps the accumulator when the distance is NaN, which ignores
/// exactly the on-plane slabs. Picking planes by sign also makes an unused slot's
/// inverted box (+∞, −∞) give an entry of +∞ and an exit of −∞ on every axis.
trait RayKernel {
    fn new(ray: &Ray) -> Self;
    /// Bit `i` set if the ray enters child `i`'s box within (t_min, t_max]; lane `i` of
    /// the array is then its entry distance.
    fn enter(&self, node: &Bvh4Node, t_max: f32) -> (u32, [f32; 4]);

    /// Tests a leaf's triangles in order as [`intersect_triangle`] would, lowering
    /// `t_max` and setting `best` at each closer hit; with `ANY_HIT`, returns true at the
    /// first hit.
    fn triangles<const ANY_HIT: bool>(&self, ray: &Ray, leaf: Leaf, t_max: &mut f32, best: &mut Option<Hit>) -> bool {
        let n = leaf.ids.len();
        for (i, &prim) in leaf.ids.iter().enumerate() {
            let row =
                |k: usize| [leaf.soa[3 * k * n + i], leaf.soa[(3 * k + 1) * n + i], leaf.soa[(3 * k + 2) * n + i]];
            let tri = Triangle::new(&[0, 1, 2].map(|k| Vec3::from_array(row(k))));
            if let Some((t, u, v)) = intersect_triangle(&tri, ray, *t_max) {
                *t_max = t;
                *best = Some(Hit { prim, t, u, v });
                if ANY_HIT {
                    return true;
                }
            }
        }
        false
    }

    /// As [`RayKernel::triangles`] with the watertight test.
    #[inline(always)]
    fn watertight<const ANY_HIT: bool>(
        &self,
        ray: &WatertightRay,
        leaf: Leaf,
        t_max: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool {
        for (i, &prim) in leaf.ids.iter().enumerate() {
            if let Some((t, u, v)) = intersect_triangle_watertight(&leaf.vertices(i), ray, *t_max) {
                *t_max = t;
                *best = Some(Hit { prim, t, u, v });
                if ANY_HIT {
                    return true;
                }
            }
        }
        false
    }
}

impl Leaf<'_> {
    /// The vertices of the leaf's `i`-th triangle.
    #[inline(always)]
    fn vertices(&self, i: usize) -> [Vec3; 3] {
        let n = self.ids.len();
        let c = |row: usize| self.soa[row * n + i];
        [0, 1, 2].map(|k| Vec3::new(c(3 * k), c(3 * k + 1), c(3 * k + 2)))
    }
}

/// A leaf's triangles as [`RayKernel::triangles`] sees them: `soa` from the leaf's first
/// float to the end of the array, `ids` the triangles' input indices.
struct Leaf<'a> {
    soa: &'a [f32],
    ids: &'a [u32],
}

/// Plane rows of [`Bvh4Node::planes`] to use for the near and far planes on each axis.
#[inline(always)]
fn plane_rows(inv_dir: Vec3) -> ([usize; 3], [usize; 3]) {
    let neg = inv_dir.is_negative_bitmask() as usize;
    let near = std::array::from_fn(|a| a + 3 * ((neg >> a) & 1));
    let far = std::array::from_fn(|a| a + 3 * (1 - ((neg >> a) & 1)));
    (near, far)
}

/// The portable [`RayKernel`]: four lanes in scalar code.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
struct ScalarKernel {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    near: [usize; 3],
    far: [usize; 3],
    t_min: f32,
}

impl RayKernel for ScalarKernel {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let (near, far) = plane_rows(ray.inv_dir);
        Self { origin: ray.origin.to_array(), inv_dir: ray.inv_dir.to_array(), near, far, t_min: ray.t_min }
    }

    #[inline(always)]
    fn enter(&self, node: &Bvh4Node, t_max: f32) -> (u32, [f32; 4]) {
        // SSE's maxps/minps: the second operand unless the first is strictly greater
        // (smaller), so a NaN first operand yields the second.
        let max = |a: f32, acc: f32| if a > acc { a } else { acc };
        let min = |a: f32, acc: f32| if a < acc { a } else { acc };
        let planes = node.planes();
        let mut mask = 0;
        let mut t = [0.0; 4];
        for lane in 0..WIDTH {
            let (mut enter, mut exit) = (self.t_min, t_max);
            for axis in (0..3).rev() {
                let near = (planes[self.near[axis] & 7][lane] - self.origin[axis]) * self.inv_dir[axis];
                let far = (planes[self.far[axis] & 7][lane] - self.origin[axis]) * self.inv_dir[axis];
                enter = max(near, enter);
                exit = min(far, exit);
            }
            t[lane] = enter;
            mask |= ((enter <= exit) as u32) << lane;
        }
        (mask, t)
    }
}

#[cfg(target_arch = "x86_64")]
mod sse {
    use super::{Bvh4Node, Leaf, RayKernel, plane_rows};
    use crate::{Hit, Ray, WatertightRay, intersect_triangle_watertight};
    use std::arch::x86_64::*;

    /// The SSE [`RayKernel`] (SSE2 is part of the x86_64 baseline).
    pub(super) struct SseKernel {
        origin: [__m128; 3],
        dir: [__m128; 3],
        inv_dir: [__m128; 3],
        near: [usize; 3],
        far: [usize; 3],
        t_min: __m128,
    }

    impl RayKernel for SseKernel {
        #[inline(always)]
        fn new(ray: &Ray) -> Self {
            let (near, far) = plane_rows(ray.inv_dir);
            // SAFETY (all `unsafe` blocks here): SSE and SSE2 are part of the x86_64
            // baseline, so the intrinsics are always available.
            let splat = |v: glam::Vec3| unsafe { [_mm_set1_ps(v.x), _mm_set1_ps(v.y), _mm_set1_ps(v.z)] };
            Self {
                origin: splat(ray.origin),
                dir: splat(ray.dir),
                inv_dir: splat(ray.inv_dir),
                near: near.map(|r| r * 4),
                far: far.map(|r| r * 4),
                t_min: unsafe { _mm_set1_ps(ray.t_min) },
            }
        }

        #[inline(always)]
        fn enter(&self, node: &Bvh4Node, t_max: f32) -> (u32, [f32; 4]) {
            let base = node.planes().as_ptr().cast::<f32>();
            let mut t = [0.0f32; 4];
            // SAFETY: the intrinsics are baseline (see `new`); a plane row is a multiple of
            // 4 below 24, i.e. a 16-byte-aligned row of the 64-byte-aligned node's six
            // plane rows; `t` has room for four floats.
            let mask = unsafe {
                let slab = |row: usize, axis: usize| {
                    let plane = _mm_load_ps(base.add(row));
                    _mm_mul_ps(_mm_sub_ps(plane, self.origin[axis]), self.inv_dir[axis])
                };
                // maxps/minps return their second operand when either is NaN: the
                // accumulator, which is never NaN for a non-NaN t_min / t_max.
                let mut enter = self.t_min;
                let mut exit = _mm_set1_ps(t_max);
                for axis in (0..3).rev() {
                    enter = _mm_max_ps(slab(self.near[axis], axis), enter);
                    exit = _mm_min_ps(slab(self.far[axis], axis), exit);
                }
                _mm_storeu_ps(t.as_mut_ptr(), enter);
                _mm_movemask_ps(_mm_cmple_ps(enter, exit)) as u32
            };
            (mask, t)
        }

        #[inline(always)]
        fn triangles<const ANY_HIT: bool>(
            &self,
            _ray: &Ray,
            leaf: Leaf,
            t_max: &mut f32,
            best: &mut Option<Hit>,
        ) -> bool {
            let n = leaf.ids.len();
            // Four triangles at a time, lane by lane the operations of `intersect_triangle`
            // (bit-identical: no fused multiply-adds), then the lanes' hits in order.
            for j in (0..n).step_by(4) {
                let mut t = [0.0f32; 4];
                let mut u = [0.0f32; 4];
                let mut v = [0.0f32; 4];
                // SAFETY: intrinsics as in `new`; row k of this group starts at float
                // k·n + j ≤ 9n − 1 of `leaf.soa`, and the array has three floats of padding
                // after the last leaf, so every 4-wide load stays inside it.
                let mask = unsafe {
                    debug_assert!(leaf.soa.len() >= 9 * n + 3);
                    let ld = |k: usize| _mm_loadu_ps(leaf.soa.as_ptr().add(k * n + j));
                    let [dx, dy, dz] = self.dir;
                    let [ox, oy, oz] = self.origin;
                    let (add, sub, mul) = (_mm_add_ps, _mm_sub_ps, _mm_mul_ps);
                    // The edges as `Triangle::new` computes them.
                    let (v0x, v0y, v0z) = (ld(0), ld(1), ld(2));
                    let (e1x, e1y, e1z) = (sub(ld(3), v0x), sub(ld(4), v0y), sub(ld(5), v0z));
                    let (e2x, e2y, e2z) = (sub(ld(6), v0x), sub(ld(7), v0y), sub(ld(8), v0z));
                    let dot = |ax, ay, az, bx, by, bz| add(add(mul(ax, bx), mul(ay, by)), mul(az, bz));
                    // p = dir × e2, det = e1 · p.
                    let px = sub(mul(dy, e2z), mul(e2y, dz));
                    let py = sub(mul(dz, e2x), mul(e2z, dx));
                    let pz = sub(mul(dx, e2y), mul(e2x, dy));
                    let det = dot(e1x, e1y, e1z, px, py, pz);
                    let inv_det = _mm_div_ps(_mm_set1_ps(1.0), det);
                    let (sx, sy, sz) = (sub(ox, v0x), sub(oy, v0y), sub(oz, v0z));
                    let uu = mul(dot(sx, sy, sz, px, py, pz), inv_det);
                    // q = s × e1.
                    let qx = sub(mul(sy, e1z), mul(e1y, sz));
                    let qy = sub(mul(sz, e1x), mul(e1z, sx));
                    let qz = sub(mul(sx, e1y), mul(e1x, sy));
                    let vv = mul(dot(dx, dy, dz, qx, qy, qz), inv_det);
                    let tt = mul(dot(e2x, e2y, e2z, qx, qy, qz), inv_det);
                    let abs_det = _mm_andnot_ps(_mm_set1_ps(-0.0), det);
                    let zero = _mm_setzero_ps();
                    let one = _mm_set1_ps(1.0);
                    let and = _mm_and_ps;
                    let ok = and(
                        and(_mm_cmpneq_ps(det, zero), _mm_cmplt_ps(abs_det, _mm_set1_ps(f32::INFINITY))),
                        and(_mm_cmpge_ps(uu, zero), _mm_cmple_ps(uu, one)),
                    );
                    let ok = and(ok, and(_mm_cmpnlt_ps(vv, zero), _mm_cmpngt_ps(add(uu, vv), one)));
                    let ok = and(ok, and(_mm_cmpgt_ps(tt, self.t_min), _mm_cmplt_ps(tt, _mm_set1_ps(*t_max))));
                    _mm_storeu_ps(t.as_mut_ptr(), tt);
                    _mm_storeu_ps(u.as_mut_ptr(), uu);
                    _mm_storeu_ps(v.as_mut_ptr(), vv);
                    _mm_movemask_ps(ok) as u32 & (0b1111 >> 4usize.saturating_sub(n - j))
                };
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if t[i] < *t_max {
                        *t_max = t[i];
                        *best = Some(Hit { prim: leaf.ids[j + i], t: t[i], u: u[i], v: v[i] });
                        if ANY_HIT {
                            return true;
                        }
                    }
                }
            }
            false
        }

        #[inline(always)]
        fn watertight<const ANY_HIT: bool>(
            &self,
            ray: &WatertightRay,
            leaf: Leaf,
            t_max: &mut f32,
            best: &mut Option<Hit>,
        ) -> bool {
            let n = leaf.ids.len();
            let [kx, ky, kz] = ray.k;
            let o = ray.origin.to_array();
            // Four triangles at a time, lane by lane the operations of
            // `intersect_triangle_watertight` (bit-identical: no fused multiply-adds); a lane
            // with an edge function of exactly zero is redone by the scalar test, which
            // falls back to double precision.
            for j in (0..n).step_by(4) {
                let lanes = 0b1111u32 >> 4usize.saturating_sub(n - j);
                let mut t = [0.0f32; 4];
                let mut u = [0.0f32; 4];
                let mut v = [0.0f32; 4];
                // SAFETY: intrinsics as in `new`; loads as in `triangles`.
                let (mask, zero_lanes) = unsafe {
                    debug_assert!(leaf.soa.len() >= 9 * n + 3);
                    let ld = |k: usize| _mm_loadu_ps(leaf.soa.as_ptr().add(k * n + j));
                    let (add, sub, mul) = (_mm_add_ps, _mm_sub_ps, _mm_mul_ps);
                    let (sx, sy, sz) =
                        (_mm_set1_ps(ray.shear[0]), _mm_set1_ps(ray.shear[1]), _mm_set1_ps(ray.shear[2]));
                    let (ox, oy, oz) = (_mm_set1_ps(o[kx]), _mm_set1_ps(o[ky]), _mm_set1_ps(o[kz]));
                    // Vertex `v` relative to the origin, permuted and sheared.
                    let rel = |v: usize| {
                        let px = sub(ld(3 * v + kx), ox);
                        let py = sub(ld(3 * v + ky), oy);
                        let pz = sub(ld(3 * v + kz), oz);
                        (sub(px, mul(sx, pz)), sub(py, mul(sy, pz)), mul(sz, pz))
                    };
                    let (ax, ay, az) = rel(0);
                    let (bx, by, bz) = rel(1);
                    let (cx, cy, cz) = rel(2);
                    let e0 = sub(mul(cx, by), mul(cy, bx));
                    let e1 = sub(mul(ax, cy), mul(ay, cx));
                    let e2 = sub(mul(bx, ay), mul(by, ax));
                    let zero = _mm_setzero_ps();
                    let any_zero =
                        _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(e0, zero), _mm_cmpeq_ps(e1, zero)), _mm_cmpeq_ps(e2, zero));
                    let neg =
                        _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(e0, zero), _mm_cmplt_ps(e1, zero)), _mm_cmplt_ps(e2, zero));
                    let pos =
                        _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(e0, zero), _mm_cmpgt_ps(e1, zero)), _mm_cmpgt_ps(e2, zero));
                    let det = add(add(e0, e1), e2);
                    let inv_det = _mm_div_ps(_mm_set1_ps(1.0), det);
                    let tt = mul(add(add(mul(e0, az), mul(e1, bz)), mul(e2, cz)), inv_det);
                    let uu = mul(e1, inv_det);
                    let vv = mul(e2, inv_det);
                    let abs_t = _mm_andnot_ps(_mm_set1_ps(-0.0), tt);
                    let ok = _mm_andnot_ps(_mm_and_ps(neg, pos), _mm_cmpneq_ps(det, zero));
                    let ok = _mm_and_ps(ok, _mm_cmplt_ps(abs_t, _mm_set1_ps(f32::INFINITY)));
                    let ok = _mm_and_ps(
                        ok,
                        _mm_and_ps(_mm_cmpgt_ps(tt, _mm_set1_ps(ray.t_min)), _mm_cmplt_ps(tt, _mm_set1_ps(*t_max))),
                    );
                    _mm_storeu_ps(t.as_mut_ptr(), tt);
                    _mm_storeu_ps(u.as_mut_ptr(), uu);
                    _mm_storeu_ps(v.as_mut_ptr(), vv);
                    (_mm_movemask_ps(ok) as u32 & lanes, _mm_movemask_ps(any_zero) as u32 & lanes)
                };
                let mut m = mask | zero_lanes;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let hit = if zero_lanes & (1 << i) != 0 {
                        intersect_triangle_watertight(&leaf.vertices(j + i), ray, *t_max)
                    } else {
                        (t[i] < *t_max).then_some((t[i], u[i], v[i]))
                    };
                    if let Some((t, u, v)) = hit {
                        *t_max = t;
                        *best = Some(Hit { prim: leaf.ids[j + i], t, u, v });
                        if ANY_HIT {
                            return true;
                        }
                    }
                }
            }
            false
        }
    }
}

#[cfg(target_arch = "x86_64")]
type Kernel = sse::SseKernel;
#[cfg(not(target_arch = "x86_64"))]
type Kernel = ScalarKernel;

impl Accelerator for Bvh4 {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse::<Kernel, false, false>(ray, &mut RayStats::default())
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<Kernel, false, true>(ray, &mut RayStats::default()).is_some()
    }

    fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, Bvh4Node::bounds)
    }

    /// Closest hit, counting wide nodes whose children are tested and triangle tests.
    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        self.traverse::<Kernel, true, false>(ray, stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{rays, soup};
    use crate::{BruteForce, SplitMethod};
    use proptest::prelude::*;

    /// The scalar box test, so that the portable path is exercised on x86_64 too.
    fn intersect_scalar(bvh: &Bvh4, ray: &Ray) -> Option<Hit> {
        bvh.traverse::<ScalarKernel, false, false>(ray, &mut RayStats::default())
    }

    fn occluded_scalar(bvh: &Bvh4, ray: &Ray) -> bool {
        bvh.traverse::<ScalarKernel, false, true>(ray, &mut RayStats::default()).is_some()
    }

    fn same_hit(a: Option<Hit>, b: Option<Hit>, r: &Ray) {
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert!((a.t - b.t).abs() <= 1e-5 * b.t.abs().max(1.0), "t {} vs {} for {r:?}", a.t, b.t);
                if a.prim != b.prim {
                    assert_eq!(a.t, b.t, "different triangle at different t for {r:?}");
                }
            }
            _ => panic!("bvh4 {a:?} vs brute force {b:?} for {r:?}"),
        }
    }

    fn agree_with(bvh: &Bvh4, oracle: &BruteForce, rays: &[Ray]) {
        for r in rays {
            let expected = oracle.intersect(r);
            let hit = bvh.intersect(r);
            same_hit(hit, expected, r);
            assert_eq!(intersect_scalar(bvh, r), hit, "scalar and SIMD box tests for {r:?}");
            let blocked = oracle.occluded(r);
            assert_eq!(bvh.occluded(r), blocked, "occlusion for {r:?}");
            assert_eq!(occluded_scalar(bvh, r), blocked, "scalar occlusion for {r:?}");
        }
    }

    fn agree(tris: &[[Vec3; 3]], config: BuildConfig, rays: &[Ray]) {
        agree_with(&Bvh4::build(tris, config).unwrap(), &BruteForce::new(tris).unwrap(), rays);
    }

    fn every_config() -> Vec<BuildConfig> {
        let mut v = Vec::new();
        for method in SplitMethod::ALL.into_iter().chain([SplitMethod::Hybrid { threshold: 64 }]) {
            for leaf_by_sah in [true, false] {
                for max_leaf_size in 1..=8 {
                    v.push(BuildConfig { method, leaf_by_sah, max_leaf_size, ..Default::default() });
                }
            }
        }
        v
    }

    /// Checks the tree's structure: every triangle in exactly one leaf, children's boxes
    /// inside the parent's, unused slots empty.
    fn check_structure(bvh: &Bvh4, n_tris: usize) {
        let mut seen = vec![false; n_tris];
        let mut reached = vec![false; bvh.nodes().len()];
        let mut stack = if bvh.nodes().is_empty() { vec![] } else { vec![0usize] };
        while let Some(i) = stack.pop() {
            assert!(!reached[i], "node {i} reached twice");
            reached[i] = true;
            let n = &bvh.nodes()[i];
            let used = (0..WIDTH).filter(|&s| !n.child_bounds(s).is_empty()).count();
            assert!(used >= 1 && (i == 0 || used >= 2), "node {i} has {used} children");
            for s in 0..WIDTH {
                let b = n.child_bounds(s);
                if b.is_empty() {
                    assert_eq!((n.child[s], n.count[s]), (0, 0));
                    assert_eq!(b, Aabb::EMPTY, "unused slot must be +inf/-inf");
                    continue;
                }
                if n.count[s] > 0 {
                    for t in n.child[s]..n.child[s] + n.count[s] {
                        let id = bvh.prim_ids()[t as usize] as usize;
                        assert!(!seen[id], "triangle {id} twice");
                        seen[id] = true;
                    }
                } else {
                    let c = n.child[s] as usize;
                    assert!(c > i, "children follow their parent");
                    let cb = bvh.nodes()[c].bounds();
                    assert!(b.min.cmple(cb.min).all() && cb.max.cmple(b.max).all(), "child box escapes");
                    stack.push(c);
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "every triangle in a leaf");
        assert!(reached.iter().all(|&r| r), "every node reachable");
    }

    #[test]
    fn node_layout() {
        assert_eq!(std::mem::size_of::<Bvh4Node>(), 128);
        assert_eq!(std::mem::align_of::<Bvh4Node>(), 64);
        let n = Bvh4Node::EMPTY;
        assert_eq!(n.planes()[3], [f32::NEG_INFINITY; 4], "row 3 is max_x");
    }

    #[test]
    fn matches_brute_force_for_every_builder_and_leaf_size() {
        let tris = soup(1, 2000, 10.0, 1.0);
        let rs = rays(2, 600, 10.0);
        let oracle = BruteForce::new(&tris).unwrap();
        for config in every_config() {
            let bvh = Bvh4::build(&tris, config).unwrap();
            check_structure(&bvh, tris.len());
            agree_with(&bvh, &oracle, &rs);
        }
    }

    #[test]
    fn parallel_build_collapses_and_matches_brute_force() {
        let tris = soup(21, 20_000, 50.0, 1.0);
        let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
        check_structure(&bvh, tris.len());
        agree_with(&bvh, &BruteForce::new(&tris).unwrap(), &rays(22, 500, 50.0));
    }

    #[test]
    fn collapse_is_wide_and_shallow() {
        let tris = soup(8, 5000, 20.0, 1.0);
        let bin = Bvh::build(&tris, BuildConfig { max_leaf_size: 4, ..Default::default() }).unwrap();
        let wide = Bvh4::from_bvh(&bin);
        let (b, w) = (bin.stats(), wide.stats());
        assert!(w.leaves <= b.leaves && w.leaves * 2 > b.leaves, "some leaves merged: {w:?} from {b:?}");
        assert_eq!(w.nodes, wide.nodes().len());
        assert!(w.nodes < b.nodes - b.leaves, "{w:?} from {b:?}");
        assert!(w.depth < b.depth, "{w:?} from {b:?}");
        assert!(w.sah_cost < b.sah_cost, "{w:?} from {b:?}");
        assert_eq!(wide.bounds(), Accelerator::bounds(&bin));
        // Leaves split down to four triangles regardless of the SAH are kept as they are,
        // and each wide node absorbs one to three binary interior nodes.
        let forced = BuildConfig { max_leaf_size: 4, leaf_by_sah: false, ..Default::default() };
        let bin = Bvh::build(&tris, forced).unwrap();
        let wide = Bvh4::from_bvh(&bin);
        let (b, w) = (bin.stats(), wide.stats());
        let mut leaves: Vec<(u32, u32)> =
            bin.nodes().iter().filter(|n| n.count > 0).map(|n| (n.index, n.count)).collect();
        let mut wide_leaves: Vec<(u32, u32)> =
            wide.nodes().iter().flat_map(|n| n.child.into_iter().zip(n.count).filter(|(_, c)| *c > 0)).collect();
        leaves.sort_unstable();
        wide_leaves.sort_unstable();
        assert_eq!(leaves, wide_leaves);
        assert_eq!(w.leaves, b.leaves);
        assert!(w.nodes * 3 >= b.nodes - b.leaves && w.nodes < b.nodes - b.leaves, "{w:?} from {b:?}");
    }

    #[test]
    fn counted_traversal_reports_work() {
        let tris = soup(51, 2000, 10.0, 1.0);
        let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
        let bin = Bvh::build(&tris, BuildConfig::default()).unwrap();
        let (mut stats, mut bin_stats) = (RayStats::default(), RayStats::default());
        let rs = rays(52, 300, 10.0);
        for r in &rs {
            assert_eq!(bvh.intersect_counted(r, &mut stats), bvh.intersect(r));
            bin.intersect_counted(r, &mut bin_stats);
        }
        assert_eq!(stats.rays, 300);
        assert!(stats.nodes_visited >= stats.rays && stats.triangles_tested > 0);
        assert!(stats.nodes_visited < bin_stats.nodes_visited, "{stats:?} vs binary {bin_stats:?}");
        assert!(stats.triangles_tested < 300 * 2000 / 20, "{stats:?}");
    }

    #[test]
    fn axis_parallel_rays_and_origins_on_slab_planes() {
        // A grid of unit squares in z = 0, z = 1 and z = 2 (split into triangles), so that box
        // planes at x, y ∈ {0, 1, 2, …} and z ∈ {0, 1, 2} are shared by many nodes.
        let mut tris = Vec::new();
        for z in 0..3 {
            for i in 0..6 {
                for j in 0..6 {
                    let (x, y, z) = (i as f32, j as f32, z as f32);
                    let [a, b, c, d] = [
                        Vec3::new(x, y, z),
                        Vec3::new(x + 1.0, y, z),
                        Vec3::new(x + 1.0, y + 1.0, z),
                        Vec3::new(x, y + 1.0, z),
                    ];
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                }
            }
        }
        let oracle = BruteForce::new(&tris).unwrap();
        let mut rs = Vec::new();
        for zero in [0.0f32, -0.0] {
            for &x in &[0.0f32, 0.5, 1.0, 3.0, 6.0, -0.0] {
                for &y in &[0.0f32, 0.25, 2.0, 6.0] {
                    // Along ±z with ±0 x and y components, from outside and from on a plane.
                    for (oz, dz) in [(-1.0, 1.0), (3.0, -1.0), (0.0, 1.0), (1.0, -1.0), (2.0, 1.0)] {
                        rs.push(Ray::new(Vec3::new(x, y, oz), Vec3::new(zero, zero, dz)));
                    }
                    // Along ±x and ±y inside the planes z = 0 / 1 (the triangles are edge-on and
                    // never hit) and between them.
                    for z in [0.0f32, 1.0, 0.5] {
                        rs.push(Ray::new(Vec3::new(-1.0, y, z), Vec3::new(1.0, zero, zero)));
                        rs.push(Ray::new(Vec3::new(7.0, y, z), Vec3::new(-1.0, zero, zero)));
                        rs.push(Ray::new(Vec3::new(x, -1.0, z), Vec3::new(zero, 1.0, zero)));
                    }
                    // Oblique in x and z with a zero y, the origin on a y plane.
                    rs.push(Ray::new(Vec3::new(x, y, -0.5), Vec3::new(0.3, zero, 1.0)));
                }
            }
        }
        for config in every_config() {
            let bvh = Bvh4::build(&tris, config).unwrap();
            agree_with(&bvh, &oracle, &rs);
        }
        // By hand: a ray in the plane y = 0 (the min plane of the front boxes) with a zero y
        // component hits the edge of the first square at t = 1.
        let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
        let r = Ray::new(Vec3::new(0.5, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0));
        let (a, b) = (bvh.intersect(&r), oracle.intersect(&r));
        assert_eq!(a.map(|h| h.t), b.map(|h| h.t));
        assert_eq!(a.map(|h| h.t), Some(1.0));
    }

    /// A leaf of `n` triangles (from the third on, with a degenerate one and one sharing
    /// an edge), its SoA floats and ids, and random rays plus rays exactly through
    /// vertices and edge points, oblique and axis-aligned (the latter give edge functions
    /// of exactly zero: the watertight test's double-precision path).
    #[allow(clippy::type_complexity)]
    fn leaf_fixture(n: usize, seed: u64, ray_seed: u64) -> (Vec<[Vec3; 3]>, Vec<f32>, Vec<u32>, Vec<Ray>) {
        let mut tris = soup(seed, n, 1.0, 1.5);
        if n > 2 {
            tris[1] = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
            tris[2] = [tris[0][0], tris[0][2], tris[0][0] + Vec3::Y];
        }
        let mut soa: Vec<f32> =
            (0..9).flat_map(|k| tris.iter().map(move |t| t[k / 3][k % 3]).collect::<Vec<_>>()).collect();
        soa.extend([f32::NAN; 3]);
        let ids: Vec<u32> = (0..n as u32).map(|i| 100 + i).collect();
        let mut rs = rays(ray_seed, 400, 1.0);
        for t in &tris {
            for p in [t[0], t[1], 0.5 * (t[0] + t[2])] {
                rs.push(Ray::new(p + Vec3::new(0.1, 0.2, 1.0), -Vec3::new(0.1, 0.2, 1.0)));
                rs.push(Ray::new(p + Vec3::Z, -Vec3::Z));
            }
        }
        (tris, soa, ids, rs)
    }

    /// Checks the SIMD leaf kernel for `test` against the scalar test applied to each
    /// triangle in order, on leaves of 1 to 9 triangles (1 to 3 groups of four, partial
    /// groups included) with degenerate and edge-sharing triangles: same hit, same
    /// shrunk t_max, any-hit stopping at the first.
    fn leaf_kernel_matches_the_scalar_test(test: TriangleTest, seed: u64) {
        let mut hits = 0;
        for n in 1..=9usize {
            let (tris, soa, ids, rs) = leaf_fixture(n, n as u64 + seed, n as u64 ^ (5 + seed));
            for r in &rs {
                let w = WatertightRay::new(r);
                let scalar = |t: &[Vec3; 3], limit: f32| match test {
                    TriangleTest::MollerTrumbore => intersect_triangle(&Triangle::new(t), r, limit),
                    TriangleTest::Watertight => intersect_triangle_watertight(t, &w, limit),
                };
                for t_max in [r.t_max, 0.7] {
                    for any_hit in [false, true] {
                        let mut expected = None;
                        let mut limit = t_max;
                        for (i, t) in tris.iter().enumerate() {
                            if let Some((t, u, v)) = scalar(t, limit) {
                                limit = t;
                                expected = Some(Hit { prim: 100 + i as u32, t, u, v });
                                if any_hit {
                                    break;
                                }
                            }
                        }
                        let (mut got, mut got_t_max) = (None, t_max);
                        let leaf = Leaf { soa: &soa, ids: &ids };
                        let k = Kernel::new(r);
                        let found = match (test, any_hit) {
                            (TriangleTest::MollerTrumbore, true) => {
                                k.triangles::<true>(r, leaf, &mut got_t_max, &mut got)
                            }
                            (TriangleTest::MollerTrumbore, false) => {
                                k.triangles::<false>(r, leaf, &mut got_t_max, &mut got)
                            }
                            (TriangleTest::Watertight, true) => {
                                k.watertight::<true>(&w, leaf, &mut got_t_max, &mut got)
                            }
                            (TriangleTest::Watertight, false) => {
                                k.watertight::<false>(&w, leaf, &mut got_t_max, &mut got)
                            }
                        };
                        assert_eq!(got, expected, "{test:?}, {n} triangles, {r:?}");
                        assert_eq!(found, any_hit && expected.is_some());
                        assert_eq!(got_t_max, limit);
                        hits += found as usize;
                    }
                }
            }
        }
        assert!(hits > 200, "{test:?}: {hits} any-hit hits");
    }

    #[test]
    fn leaf_kernel_is_bit_identical_to_intersect_triangle() {
        leaf_kernel_matches_the_scalar_test(TriangleTest::MollerTrumbore, 0);
    }

    #[test]
    fn watertight_leaf_kernel_is_bit_identical_to_the_scalar_test() {
        leaf_kernel_matches_the_scalar_test(TriangleTest::Watertight, 40);
    }

    #[test]
    fn unused_slots_are_never_entered() {
        // Two triangles: the root has two used slots and two unused ones.
        let tris = vec![
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::new(5.0, 0.0, 0.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(5.0, 1.0, 0.0)],
        ];
        let bvh = Bvh4::build(&tris, BuildConfig { max_leaf_size: 1, ..Default::default() }).unwrap();
        assert_eq!(bvh.nodes().len(), 1);
        let node = &bvh.nodes()[0];
        for dir in [Vec3::X, -Vec3::X, Vec3::new(0.0, -0.0, 1.0), Vec3::new(-0.0, 0.0, -0.0), Vec3::new(1.0, -2.0, 3.0)]
        {
            for origin in [Vec3::ZERO, Vec3::splat(-3.0), Vec3::new(5.0, 0.0, 0.0)] {
                let r = Ray::new(origin, dir);
                let (mask, _) = Kernel::new(&r).enter(node, f32::INFINITY);
                let (scalar, _) = ScalarKernel::new(&r).enter(node, f32::INFINITY);
                assert_eq!(mask, scalar);
                assert_eq!(mask & 0b1100, 0, "unused slot entered by {r:?}");
            }
        }
    }

    #[test]
    fn degenerate_duplicate_and_tiny_inputs() {
        let rs = rays(3, 500, 2.0);
        agree(&[], BuildConfig::default(), &rs);
        let empty = Bvh4::build(&[], BuildConfig::default()).unwrap();
        assert_eq!(empty.stats(), Bvh4Stats::default());
        assert!(empty.bounds().is_empty());
        let one = soup(4, 1, 2.0, 1.0);
        let single = Bvh4::build(&one, BuildConfig::default()).unwrap();
        assert_eq!((single.stats().nodes, single.stats().leaves, single.stats().depth), (1, 1, 2));
        agree(&one, BuildConfig::default(), &rs);
        // A ray straight at the single triangle hits it.
        let c = (one[0][0] + one[0][1] + one[0][2]) / 3.0;
        let n = (one[0][1] - one[0][0]).cross(one[0][2] - one[0][0]).normalize();
        assert!(single.intersect(&Ray::new(c + n, -n)).is_some());
        // 1000 copies of one triangle: all centroids coincide, the binary tree halves by
        // position; depth and the stack must stay bounded.
        let same = vec![soup(5, 1, 2.0, 1.0)[0]; 1000];
        let towards: Vec<Ray> = {
            let t = same[0];
            let c = (t[0] + t[1] + t[2]) / 3.0;
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            (0..50).map(|i| Ray::new(c + n * (1.0 + i as f32), -n)).collect()
        };
        for config in every_config() {
            let bvh = Bvh4::build(&same, config).unwrap();
            let s = bvh.stats();
            assert!(s.depth.saturating_sub(1) * (WIDTH - 1) <= STACK_DEPTH && s.depth < 64, "{s:?}");
            check_structure(&bvh, same.len());
            for r in &towards {
                assert!(bvh.intersect(r).is_some() && bvh.occluded(r));
            }
        }
        agree(&same, BuildConfig::default(), &rs);
        agree(&same, BuildConfig { method: SplitMethod::SweepSah, max_leaf_size: 1, ..Default::default() }, &towards);
        // Zero-area triangles mixed in.
        let mut mixed = soup(6, 300, 2.0, 0.5);
        mixed.extend((0..50).map(|i| [Vec3::splat(i as f32 * 0.01); 3]));
        mixed.extend((0..50).map(|i| [Vec3::ZERO, Vec3::X * i as f32, Vec3::X * 2.0 * i as f32]));
        for config in every_config() {
            agree(&mixed, config, &rs);
        }
    }

    #[test]
    fn non_finite_rays_hit_nothing_and_terminate() {
        let tris = soup(9, 500, 5.0, 1.0);
        let bvh = Bvh4::build(&tris, BuildConfig::default()).unwrap();
        let oracle = BruteForce::new(&tris).unwrap();
        for (o, d) in [
            (Vec3::splat(2.0), Vec3::new(f32::NAN, 1.0, 0.0)),
            (Vec3::splat(2.0), Vec3::new(f32::INFINITY, 0.0, 0.0)),
            (Vec3::new(f32::NAN, 2.0, 2.0), Vec3::X),
            (Vec3::new(f32::NEG_INFINITY, 2.0, 2.0), Vec3::X),
        ] {
            let r = Ray::new(o, d);
            assert_eq!(bvh.intersect(&r), None);
            assert_eq!(oracle.intersect(&r), None);
            assert!(!bvh.occluded(&r));
        }
        // NaN segment bounds: nothing is hit either.
        let r = Ray::segment(Vec3::splat(-1.0), Vec3::ONE, f32::NAN, f32::INFINITY);
        assert_eq!((bvh.intersect(&r), oracle.intersect(&r)), (None, None));
        let r = Ray::segment(Vec3::splat(-1.0), Vec3::ONE, 0.0, f32::NAN);
        assert_eq!((bvh.intersect(&r), oracle.intersect(&r)), (None, None));
    }

    #[test]
    fn rejects_non_finite_coordinates() {
        let mut tris = soup(7, 10, 1.0, 1.0);
        tris[3][1].y = f32::NAN;
        assert!(matches!(Bvh4::build(&tris, BuildConfig::default()), Err(BuildError::NonFinite { index: 3, .. })));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn random_soups_agree_with_brute_force(
            seed in any::<u64>(), n in 1usize..300, leaf in 1usize..9, bins in 2usize..33, m in 0usize..4,
            by_sah in any::<bool>()
        ) {
            let tris = soup(seed, n, 5.0, 1.5);
            let method = SplitMethod::ALL[m];
            let config = BuildConfig { method, max_leaf_size: leaf, bins, leaf_by_sah: by_sah, ..Default::default() };
            let bvh = Bvh4::build(&tris, config).unwrap();
            check_structure(&bvh, tris.len());
            agree_with(&bvh, &BruteForce::new(&tris).unwrap(), &rays(seed ^ 1, 200, 5.0));
        }
    }
}
