//! Ordered traversal of a [`BvhWide`]: the children a ray enters are visited nearest
//! first, the others pushed with their entry distance and culled on pop against the
//! closest hit so far; boxes and leaves are tested by a [`RayKernel`] — for [`Bvh4`] the
//! SSE kernel (x86_64 baseline), for [`Bvh8`] the AVX one where the CPU has AVX2 (checked
//! at run time; the traversal is then compiled with AVX2 enabled), else the portable one.

use super::kernel::{Leaf, RayKernel, ScalarKernel};
use super::{Bvh4, Bvh8, BvhWide, STACK_DEPTH, WideNode};
use crate::{Aabb, Accelerator, Hit, Ray, RayStats, TriangleTest};
use std::mem::MaybeUninit;

/// A child to visit: a node (`count == 0`) or a leaf's triangle range, with the ray's
/// entry distance into its box.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u32,
    t: f32,
}

/// Pushes `e` onto the traversal's stack of `*sp` entries, unchecked.
///
/// # Safety
///
/// `*sp` must be below [`STACK_DEPTH`]: the traversal's bound (see its stack), checked by
/// debug builds.
#[inline(always)]
unsafe fn push(stack: &mut [MaybeUninit<Entry>; STACK_DEPTH], sp: &mut usize, e: Entry) {
    debug_assert!(*sp < STACK_DEPTH);
    // SAFETY: the caller's guarantee.
    unsafe { *stack.get_unchecked_mut(*sp) = MaybeUninit::new(e) };
    *sp += 1;
}

/// Sorts the first `k` (≤ W) slots by their entry distance `t[slot]`, nearest first
/// (insertion: a few steps for the three or four children most nodes enter).
#[inline(always)]
fn sort_slots<const W: usize>(slots: &mut [u8; W], k: usize, t: &[f32; W]) {
    for i in 1..k {
        let x = slots[i];
        let key = t[x as usize];
        let mut j = i;
        while j > 0 && key < t[slots[j - 1] as usize] {
            slots[j] = slots[j - 1];
            j -= 1;
        }
        slots[j] = x;
    }
}

/// The slot of primitive `prim` in a leaf's ids: every slot compared, with no exit at the
/// match, whose position varies from hit to hit and mispredicted a branch.
#[inline(always)]
fn slot_of(ids: &[u32], prim: u32) -> Option<usize> {
    let mut slot = usize::MAX;
    for (i, &p) in ids.iter().enumerate() {
        slot = if p == prim { i } else { slot };
    }
    (slot != usize::MAX).then_some(slot)
}

/// The ray's parameter at the plane of triangle `v`, in f64 (the f32 inputs' differences
/// and products are exact there): within an ulp of the exact value unless the ray grazes
/// the plane. Keeps `t` where the plane is parallel to the ray or the result not finite.
#[inline]
fn refine_t(ray: &Ray, v: [glam::Vec3; 3], t: f32) -> f32 {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let v0 = v[0].as_dvec3();
    let n = (v[1].as_dvec3() - v0).cross(v[2].as_dvec3() - v0);
    let exact = n.dot(v0 - o) / n.dot(d);
    if exact.is_finite() && exact > 0.0 { exact as f32 } else { t }
}

/// A copy of `ray` read one float at a time. Callers often store a ray piecewise (the
/// renderer's lanes build it from structure-of-arrays state), and a wider load that spans
/// several stores cannot be forwarded from them: it waits until they reach the cache, at
/// the start of every ray (+3 % on the Cornell box's render, docs/figures.md). Each 4-byte
/// load lies inside one store whatever the caller's pattern; volatile keeps the compiler
/// from merging them.
#[inline(always)]
fn fieldwise(ray: &Ray) -> Ray {
    // SAFETY: reads of the fields of a valid reference.
    let f = |p: &f32| unsafe { std::ptr::read_volatile(p) };
    let v = |p: &glam::Vec3| glam::Vec3::new(f(&p.x), f(&p.y), f(&p.z));
    Ray {
        origin: v(&ray.origin),
        dir: v(&ray.dir),
        inv_dir: v(&ray.inv_dir),
        t_min: f(&ray.t_min),
        t_max: f(&ray.t_max),
    }
}

/// True if the ray can be traced: its origin and direction finite, and each component of
/// `inv_dir` (a public field, which callers may set apart from `dir`) normal or infinite —
/// not zero, NaN or subnormal (a subnormal one, which `Ray::new` makes for |d| > 8.5·10³⁷,
/// reads as zero where denormals are treated as zero). Other rays are answered "no hit":
/// with a non-finite origin or direction no triangle test reports a finite hit, and only
/// such rays and those with a zero or NaN reciprocal could enter an unused slot's empty box
/// ((±∞ − origin)·0 or ·NaN is NaN, which the box test ignores) — the root again, which
/// would overflow the traversal's stack.
///
/// The magnitudes' bit patterns in two comparisons instead of nine branches: the origin's
/// and direction's below infinity's, the reciprocals' from the smallest normal's to
/// infinity's (less the smallest normal, so that smaller ones wrap round to the largest).
#[inline(always)]
pub(super) fn traceable(ray: &Ray) -> bool {
    const NORMAL: u32 = f32::MIN_POSITIVE.to_bits();
    const INFINITY: u32 = f32::INFINITY.to_bits();
    let (o, d, inv) = (ray.origin, ray.dir, ray.inv_dir);
    let bits = |c: f32| c.to_bits() & 0x7fff_ffff;
    let largest = [o.x, o.y, o.z, d.x, d.y, d.z].iter().fold(0, |m, &c| m.max(bits(c)));
    let reciprocal = [inv.x, inv.y, inv.z].iter().fold(0, |m, &c| m.max(bits(c).wrapping_sub(NORMAL)));
    (largest < INFINITY) & (reciprocal <= INFINITY - NORMAL)
}

impl<const W: usize> BvhWide<W> {
    #[inline(always)]
    pub(super) fn traverse<K: RayKernel<W>, const COUNT: bool, const ANY_HIT: bool>(
        &self,
        ray: &Ray,
        stats: &mut RayStats,
    ) -> Option<Hit> {
        self.traverse_from::<K, COUNT, ANY_HIT>(ray, stats, (0, 0))
    }

    /// [`Self::traverse`] from the child `start` (its index or first triangle, and its
    /// triangle count: `(0, 0)` is the root): a packet's ray that goes on alone.
    #[inline(always)]
    pub(super) fn traverse_from<K: RayKernel<W>, const COUNT: bool, const ANY_HIT: bool>(
        &self,
        ray: &Ray,
        stats: &mut RayStats,
        start: (u32, u32),
    ) -> Option<Hit> {
        if COUNT {
            stats.rays += 1;
        }
        let ray = &fieldwise(ray);
        // See `traceable`: the stack bound below relies on it.
        if self.nodes.is_empty() || !traceable(ray) {
            return None;
        }
        let kernel = K::new(ray);
        // The leaf of the closest hit so far, for `refine`.
        let mut best_leaf = Leaf { soa: &[], ids: &[] };
        let watertight = (self.test == TriangleTest::Watertight).then(|| K::watertight_ray(ray));
        let mut t_max = ray.t_max;
        let mut best: Option<Hit> = None;
        // Uninitialised: zeroing its 5 KiB would cost more than a short traversal. It never
        // overflows, so it is indexed unchecked: a traceable ray enters no unused slot, so
        // only interior nodes push, each at most W − 1 of its children, and the stack holds
        // at most W − 1 entries per interior node on the path from the root (pops follow
        // visits) — at most (depth − 1)(W − 1) entries, which the collapse, the only maker
        // of trees, asserts is within STACK_DEPTH.
        let mut stack = [MaybeUninit::<Entry>::uninit(); STACK_DEPTH];
        let mut sp = 0usize;
        let mut current = Entry { child: start.0, count: start.1, t: 0.0 };
        loop {
            if current.count == 0 {
                debug_assert!((current.child as usize) < self.nodes.len());
                // SAFETY: `current` is the root (the tree is not empty), a start the caller
                // took from a node, or an interior child a node holds: the collapse, which
                // makes every tree, writes only indices into `nodes` there.
                let node = unsafe { self.nodes.get_unchecked(current.child as usize) };
                if COUNT {
                    stats.nodes_visited += 1;
                }
                let (mask, t) = kernel.enter(node, t_max);
                if mask != 0 {
                    // `% W` (an `and`: W is 4 or 8) tells the compiler what the mask's W
                    // bits already say, instead of a bounds check per child.
                    let entry = |i: usize| {
                        let i = i % W;
                        Entry { child: node.child[i], count: node.count[i], t: t[i] }
                    };
                    if mask & (mask - 1) == 0 {
                        current = entry(mask.trailing_zeros() as usize);
                        continue;
                    }
                    let rest = mask & (mask - 1);
                    if rest & (rest - 1) == 0 {
                        // Two children, the commonest case after one: the nearer next, the
                        // other pushed, without the general sort.
                        let (a, b) = (entry(mask.trailing_zeros() as usize), entry(rest.trailing_zeros() as usize));
                        let (near, far) = if b.t < a.t { (b, a) } else { (a, b) };
                        self.prefetch(&far);
                        // SAFETY: see the stack's declaration.
                        unsafe { push(&mut stack, &mut sp, far) };
                        current = near;
                        continue;
                    }
                    // Three or more children: nearest first, the others pushed far to
                    // near. The slots are sorted, not entries: an entry written field by
                    // field and then moved whole (the sort's swaps, the pushes) would be
                    // loaded across several of its stores, which store forwarding cannot
                    // serve.
                    let mut slots = [0u8; W];
                    let mut k = 0;
                    let mut m = mask;
                    while m != 0 {
                        let i = m.trailing_zeros() as usize;
                        slots[k] = i as u8;
                        self.prefetch(&entry(i));
                        k += 1;
                        m &= m - 1;
                    }
                    sort_slots(&mut slots, k, &t);
                    for &i in slots[1..k].iter().rev() {
                        // SAFETY: see the stack's declaration.
                        unsafe { push(&mut stack, &mut sp, entry(i as usize)) };
                    }
                    current = entry(slots[0] as usize);
                    continue;
                }
            } else {
                let first = current.child as usize;
                let count = current.count as usize;
                if COUNT {
                    stats.triangles_tested += count as u64;
                }
                let leaf = self.leaf(first, count);
                let before = t_max;
                let done = match &watertight {
                    Some(w) => kernel.watertight::<ANY_HIT>(w, leaf, &mut t_max, &mut best),
                    None => kernel.triangles::<ANY_HIT>(ray, leaf, &mut t_max, &mut best),
                };
                if done {
                    return best;
                }
                if t_max < before {
                    best_leaf = leaf;
                }
            }
            // Pop until a child that may still hold a closer hit.
            loop {
                if sp == 0 {
                    return if ANY_HIT { best } else { self.refine(ray, best, best_leaf) };
                }
                sp -= 1;
                // SAFETY: entries below `sp` (≤ STACK_DEPTH) were all written by the pushes
                // above.
                let e = unsafe { stack.get_unchecked(sp).assume_init() };
                if e.t <= t_max {
                    current = e;
                    break;
                }
            }
        }
    }

    /// `best` with its t recomputed in f64 ([`BvhWide::with_exact_t`], the default): from
    /// the tree's table of planes where it keeps one, else from the hit leaf's vertices
    /// (`leaf`: the leaf that holds it), which the leaf test has just loaded.
    #[inline(always)]
    pub(super) fn refine(&self, ray: &Ray, mut best: Option<Hit>, leaf: Leaf) -> Option<Hit> {
        if let Some(hit) = &mut best
            && self.exact_t
        {
            if self.planes.is_empty() {
                if let Some(i) = slot_of(leaf.ids, hit.prim) {
                    hit.t = refine_t(ray, leaf.vertices(i), hit.t);
                }
            } else {
                hit.t = self.plane_t(ray, hit.prim, hit.t);
            }
        }
        best
    }

    /// The ray's parameter at primitive `prim`'s plane from the table, in f64 (`t` where it
    /// is not finite and positive). Out of line: inlined, its values took registers from the
    /// traversal loop (the Cornell box's primary rays −20 % against −4 %).
    #[inline(never)]
    fn plane_t(&self, ray: &Ray, prim: u32, t: f32) -> f32 {
        let p = self.planes[prim as usize];
        let n = glam::DVec3::new(p[0], p[1], p[2]);
        let exact = (p[3] - n.dot(ray.origin.as_dvec3())) / n.dot(ray.dir.as_dvec3());
        if exact.is_finite() && exact > 0.0 { exact as f32 } else { t }
    }

    /// The leaf of `count` triangles from `first`.
    #[inline(always)]
    pub(super) fn leaf(&self, first: usize, count: usize) -> Leaf<'_> {
        Leaf { soa: &self.soa[9 * first..], ids: &self.prim_ids[first..first + count] }
    }

    /// Starts loading a child's node or triangles into the cache, ahead of its visit.
    #[inline(always)]
    fn prefetch(&self, e: &Entry) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let (first, last) = if e.count == 0 {
                let p = self.nodes.as_ptr().wrapping_add(e.child as usize).cast::<i8>();
                (p, p.wrapping_add(size_of::<WideNode<W>>() - 1))
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

/// The kernel of a [`Bvh4`]: SSE on x86_64, else the portable one.
#[cfg(target_arch = "x86_64")]
type Kernel4 = super::sse::SseKernel;
#[cfg(not(target_arch = "x86_64"))]
type Kernel4 = ScalarKernel;

impl Accelerator for Bvh4 {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse::<Kernel4, false, false>(ray, &mut RayStats::default())
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<Kernel4, false, true>(ray, &mut RayStats::default()).is_some()
    }

    fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, WideNode::bounds)
    }

    /// Closest hit, counting wide nodes whose children are tested and triangle tests.
    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        self.traverse::<Kernel4, true, false>(ray, stats)
    }

    /// Any hit, counting as [`Bvh4::intersect_counted`].
    fn occluded_counted(&self, ray: &Ray, stats: &mut RayStats) -> bool {
        self.traverse::<Kernel4, true, true>(ray, stats).is_some()
    }
}

impl Bvh8 {
    /// The traversal with the AVX kernel where the CPU has AVX2, else the portable one.
    #[inline(always)]
    fn traverse_best<const COUNT: bool, const ANY_HIT: bool>(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        match crate::isa::active() {
            // SAFETY: `active` is at most what the CPU has (detected).
            crate::isa::Isa::Avx512 => return unsafe { self.traverse_avx512::<COUNT, ANY_HIT>(ray, stats) },
            // SAFETY: as above.
            crate::isa::Isa::Avx2 => return unsafe { self.traverse_avx2::<COUNT, ANY_HIT>(ray, stats) },
            crate::isa::Isa::Baseline => {}
        }
        self.traverse::<ScalarKernel, COUNT, ANY_HIT>(ray, stats)
    }

    /// The AVX kernel's traversal compiled for AVX-512 (VL): the same 256-bit
    /// operations, with compares into mask registers and 32 vector registers.
    ///
    /// # Safety
    ///
    /// The CPU must have AVX-512 F, VL, BW and DQ.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
    unsafe fn traverse_avx512<const COUNT: bool, const ANY_HIT: bool>(
        &self,
        ray: &Ray,
        stats: &mut RayStats,
    ) -> Option<Hit> {
        self.traverse::<super::avx::AvxKernel, COUNT, ANY_HIT>(ray, stats)
    }

    /// The traversal compiled with AVX2 enabled, the AVX kernel inlined into it.
    ///
    /// # Safety
    ///
    /// The CPU must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn traverse_avx2<const COUNT: bool, const ANY_HIT: bool>(
        &self,
        ray: &Ray,
        stats: &mut RayStats,
    ) -> Option<Hit> {
        self.traverse::<super::avx::AvxKernel, COUNT, ANY_HIT>(ray, stats)
    }
}

impl Accelerator for Bvh8 {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse_best::<false, false>(ray, &mut RayStats::default())
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse_best::<false, true>(ray, &mut RayStats::default()).is_some()
    }

    fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, WideNode::bounds)
    }

    /// Closest hit, counting wide nodes whose children are tested and triangle tests.
    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        self.traverse_best::<true, false>(ray, stats)
    }

    /// Any hit, counting as [`Bvh8::intersect_counted`].
    fn occluded_counted(&self, ray: &Ray, stats: &mut RayStats) -> bool {
        self.traverse_best::<true, true>(ray, stats).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::sort_slots;

    /// The slots of every subset of eight children, ordered by entry distance with ties
    /// in slot order: what a stable sort of the entries gives (the visit order only costs
    /// time when wrong — the tie rule keeps the hits — so it is pinned here).
    #[test]
    fn slots_are_sorted_nearest_first_and_stably() {
        let t: [f32; 8] = [3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0];
        for mask in 0u32..256 {
            let mut slots = [0u8; 8];
            let mut k = 0;
            for i in (0..8).filter(|i| mask & (1 << i) != 0) {
                slots[k] = i as u8;
                k += 1;
            }
            let mut expected = slots[..k].to_vec();
            expected.sort_by(|a, b| t[*a as usize].total_cmp(&t[*b as usize]));
            sort_slots(&mut slots, k, &t);
            assert_eq!(slots[..k], expected[..], "children {mask:#010b}");
        }
    }
}
