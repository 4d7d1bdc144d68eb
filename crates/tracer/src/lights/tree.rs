//! A light tree: the emitters, point and spot lights in a hierarchy whose nodes bound their lights' positions,
//! emission directions and power, so that a shading point chooses a light in proportion
//! to an estimate of what each part of the tree can give it, instead of in proportion to
//! power alone (Conty Estevez & Kulla 2018, "Importance Sampling of Many Lights with
//! Adaptive Tree Splitting"; the bounds, importance and build as pbrt-v4's
//! `BVHLightSampler`, Pharr, Jakob & Humphreys, *Physically Based Rendering*, 4th ed.,
//! §12.6.3). With many lights most of them are far, small or facing away from any given
//! point, and power sampling spends its shadow rays on them.
//!
//! Built binary (pbrt-v4's split by cost), then collapsed to four children per node, whose
//! estimates one pass of four-wide vector instructions computes: the walk takes half the
//! levels, each choice is arithmetic instead of a branch, and a node's children are
//! estimated from their own bounds rather than through their parents' looser ones
//! (docs/figures.md, "The light tree four wide and in the lanes").
//!
//! The choice is unbiased however rough the estimate, as long as every light that can
//! light a point has a non-zero probability there: the bounds are conservative (a node's
//! cone holds every direction its lights emit into), so the estimate is zero only where
//! no light of a node can reach the point.

use bvh::Aabb;
use glam::{Quat, Vec3, Vec4};
use std::f32::consts::PI;

/// What a node of the tree knows about its lights: where they are, into which directions
/// they emit (a cone of normals, axis `w` and half-angle θo, widened by θe, the angle
/// past a normal into which a light still emits: π/2 for a surface that emits on its
/// front), and their power.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightBounds {
    /// Where the lights are.
    pub(crate) bounds: Aabb,
    /// The axis of their normals' cone.
    pub(crate) w: Vec3,
    /// Their power (any common scale: only ratios count).
    pub(crate) phi: f32,
    /// cos θo: the normals' cone (1: one normal; −1: all directions).
    pub(crate) cos_theta_o: f32,
    /// cos θe: how far past a normal they emit (0: a hemisphere).
    pub(crate) cos_theta_e: f32,
}

/// The angle between unit vectors `a` and `b`, accurate where they are nearly parallel
/// or opposite (where `acos` of their dot product loses ~10⁻³ rad; pbrt-v4's
/// `AngleBetween`).
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((a - b).length() * 0.5).min(1.0).asin()
    }
}

/// The smallest cone (axis, cos of its half-angle) holding cones `a` and `b` (pbrt-v4's
/// `DirectionCone::Union`).
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let theta_a = a.1.clamp(-1.0, 1.0).acos();
    let theta_b = b.1.clamp(-1.0, 1.0).acos();
    let theta_d = angle_between(a.0, b.0);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return (a.0, -1.0);
    }
    let axis = a.0.cross(b.0);
    if axis.length_squared() == 0.0 {
        return (a.0, -1.0);
    }
    let w = Quat::from_axis_angle(axis.normalize(), theta_o - theta_a) * a.0;
    (w.normalize(), theta_o.cos())
}

impl LightBounds {
    /// Bounds holding both.
    pub(crate) fn union(self, o: Self) -> Self {
        if self.phi == 0.0 {
            return o;
        }
        if o.phi == 0.0 {
            return self;
        }
        let (w, cos_theta_o) = cone_union((self.w, self.cos_theta_o), (o.w, o.cos_theta_o));
        Self {
            bounds: self.bounds.union(o.bounds),
            w,
            phi: self.phi + o.phi,
            cos_theta_o,
            cos_theta_e: self.cos_theta_e.min(o.cos_theta_e),
        }
    }

    /// The orientation measure M_Ω of the build's cost (Conty Estevez & Kulla 2018,
    /// eq. 1): the solid angle of the cone widened by θe, weighted by cosine.
    fn orientation_measure(&self) -> f32 {
        let theta_o = self.cos_theta_o.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + self.cos_theta_e.clamp(-1.0, 1.0).acos()).min(PI);
        let sin_o = theta_o.sin();
        2.0 * PI * (1.0 - self.cos_theta_o)
            + 0.5
                * PI
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + self.cos_theta_o)
    }
}

/// The build's cost of a node (Conty Estevez & Kulla 2018, §4.4): power × orientation
/// measure × surface area. The split minimises its sum over both sides; the collapse to
/// four children opens the costliest child first.
fn saoh_cost(b: &LightBounds) -> f64 {
    b.phi as f64 * b.orientation_measure() as f64 * b.bounds.surface_area().max(0.0) as f64
}

/// sin θ from cos θ for four angles in [0, π].
#[inline(always)]
fn sin_from_cos4(c: Vec4) -> Vec4 {
    (Vec4::ONE - c * c).max(Vec4::ZERO).sqrt()
}

/// cos(max(0, a − b)) for four pairs (pbrt-v4's `cosSubClamped`).
#[inline(always)]
fn cos_sub_clamped4(sin_a: Vec4, cos_a: Vec4, sin_b: Vec4, cos_b: Vec4) -> Vec4 {
    Vec4::select(cos_a.cmpgt(cos_b), Vec4::ONE, cos_a * cos_b + sin_a * sin_b)
}

/// A node of the tree: up to four children, each a light or another node, with what the
/// importance estimate reads of each child's [`LightBounds`] precomputed (the box's
/// centre, its bounding sphere, the cone's sine) and laid out as structure of arrays, so
/// that one pass of four-wide vector instructions estimates all four children. A walk
/// down a binary tree estimated two children per level, one level after the other, and
/// mispredicted its branch to the next level half of the time; four children per level
/// halve the levels, and the choice among them is arithmetic.
#[derive(Clone, Copy, Debug)]
struct Node {
    centre: [Vec4; 3],
    /// The bounding sphere's squared radius.
    radius2: Vec4,
    /// The least squared distance the estimate divides by: half the box's diagonal
    /// (pbrt-v4's clamp), so that a point near or inside the box gets a bounded value.
    min_d2: Vec4,
    /// The cone's axis, as [`LightBounds::w`].
    w: [Vec4; 3],
    /// Power; zero in an unused slot, whose importance is then zero.
    phi: Vec4,
    cos_theta_o: Vec4,
    sin_theta_o: Vec4,
    cos_theta_e: Vec4,
    /// Each slot's light (index into the tree's lights) or node.
    child: [u32; 4],
    /// Bit i: slot i holds a light.
    lights: u8,
}

impl Node {
    /// A node with no children (every slot's power zero).
    const EMPTY: Self = Self {
        centre: [Vec4::ZERO; 3],
        radius2: Vec4::ZERO,
        min_d2: Vec4::ZERO,
        w: [Vec4::ZERO; 3],
        phi: Vec4::ZERO,
        cos_theta_o: Vec4::ZERO,
        sin_theta_o: Vec4::ZERO,
        cos_theta_e: Vec4::ZERO,
        child: [0; 4],
        lights: 0,
    };

    /// Puts bounds `b` in slot `i`, for a light (`light`) or a node.
    fn set(&mut self, i: usize, b: &LightBounds, child: u32, light: bool) {
        let centre = b.bounds.centre();
        for (axis, row) in self.centre.iter_mut().enumerate() {
            row[i] = centre[axis];
        }
        for (axis, row) in self.w.iter_mut().enumerate() {
            row[i] = b.w[axis];
        }
        self.radius2[i] = centre.distance_squared(b.bounds.max);
        self.min_d2[i] = 0.5 * b.bounds.extent().length();
        self.phi[i] = b.phi;
        self.cos_theta_o[i] = b.cos_theta_o;
        self.cos_theta_e[i] = b.cos_theta_e;
        self.child[i] = child;
        self.lights |= (light as u8) << i;
    }

    /// An upper estimate of what each child's lights give point `p` with normal `n`
    /// (zero `n`: no cosine there): power over squared distance, times the cosine at the
    /// lights of the smallest angle between their cone and the direction to `p`, and the
    /// cosine at `p` of the smallest angle to the box, each angle reduced by the box's
    /// angular radius seen from `p` (pbrt-v4's `LightBounds::Importance`). Zero only where
    /// no direction a child's lights emit into reaches `p` (and in unused slots); finite
    /// and never negative.
    #[inline(always)]
    fn importance(&self, p: Vec3, n: Vec3) -> Vec4 {
        let [cx, cy, cz] = &self.centre;
        let (dx, dy, dz) = (Vec4::splat(p.x) - *cx, Vec4::splat(p.y) - *cy, Vec4::splat(p.z) - *cz);
        let dist2 = dx * dx + dy * dy + dz * dz;
        let inv = Vec4::select(dist2.cmpgt(Vec4::ZERO), dist2.sqrt().recip(), Vec4::ZERO);
        let (wx, wy, wz) = (dx * inv, dy * inv, dz * inv);
        let cos_theta_w = self.w[0] * wx + self.w[1] * wy + self.w[2] * wz;
        let sin_theta_w = sin_from_cos4(cos_theta_w);
        // The box's angular radius from p, through its bounding sphere.
        let outside = (Vec4::ONE - self.radius2 / dist2).max(Vec4::ZERO).sqrt();
        let cos_theta_b = Vec4::select(dist2.cmplt(self.radius2), Vec4::NEG_ONE, outside);
        let sin_theta_b = sin_from_cos4(cos_theta_b);
        let within = cos_theta_w.cmpgt(self.cos_theta_o);
        let cos_theta_x =
            Vec4::select(within, Vec4::ONE, cos_theta_w * self.cos_theta_o + sin_theta_w * self.sin_theta_o);
        let sin_theta_x =
            Vec4::select(within, Vec4::ZERO, sin_theta_w * self.cos_theta_o - cos_theta_w * self.sin_theta_o);
        let cos_theta_p = cos_sub_clamped4(sin_theta_x, cos_theta_x, sin_theta_b, cos_theta_b);
        let mut importance = self.phi * cos_theta_p / dist2.max(self.min_d2);
        if n != Vec3::ZERO {
            let cos_theta_i = (wx * n.x + wy * n.y + wz * n.z).abs();
            let sin_theta_i = sin_from_cos4(cos_theta_i);
            importance *= cos_sub_clamped4(sin_theta_i, cos_theta_i, sin_theta_b, cos_theta_b);
        }
        // (NaN, from an unused slot's 0/0 or a point at a light's centre, fails both.)
        let keep =
            cos_theta_p.cmpgt(self.cos_theta_e) & importance.cmpge(Vec4::ZERO) & importance.cmplt(Vec4::INFINITY);
        Vec4::select(keep, importance, Vec4::ZERO)
    }

    /// The children's importance for `p`, `n` as the ends of their stretches of
    /// [0, total): `ends[i]` = the sum of slots 0..=i (`ends[3]` the total), in this order
    /// of additions for [`LightTree::sample`] and [`LightTree::pmf`] alike.
    #[inline(always)]
    fn ends(&self, p: Vec3, n: Vec3) -> ([f32; 4], [f32; 4]) {
        let e = self.importance(p, n).to_array();
        let s1 = e[0] + e[1];
        let s2 = s1 + e[2];
        (e, [e[0], s1, s2, s2 + e[3]])
    }
}

/// The tree over a scene's sampled emitters and its point and spot lights (indices into
/// `Lights::cdf`'s entries: those of `Lights::prims`, then the point and spot lights').
#[derive(Clone, Debug)]
pub(crate) struct LightTree {
    /// The root first.
    nodes: Vec<Node>,
    /// For each light, the slots from the root to it (bits 2d and 2d + 1: the slot taken
    /// at depth d).
    trails: Vec<u128>,
}

/// Deeper than this the binary build splits by count, so that the four-wide tree is at
/// most 64 levels deep and every trail fits its 128 bits.
const MAX_SAOH_DEPTH: u32 = 32;
/// Floats per node of the flat tree another backend walks
/// ([`crate::lights::LightTreeTables::nodes`]).
pub const NODE_FLOATS: usize = 56;
/// Buckets per axis of the build's split search (pbrt-v4's 12).
const BUCKETS: usize = 12;

/// A node of the binary tree the build makes before it is collapsed to four children.
struct BinaryNode {
    bounds: LightBounds,
    kind: BinaryKind,
}

/// What a [`BinaryNode`] holds.
#[derive(Clone, Copy)]
enum BinaryKind {
    /// A light, by its index.
    Light(u32),
    /// Two children, by their node indices.
    Split(usize, usize),
}

impl LightTree {
    /// The tree over `lights` (light k's bounds at index k); lights of zero power are
    /// left out (never chosen). Empty if none has power.
    pub(crate) fn new(lights: &[LightBounds]) -> Self {
        let mut tree = Self { nodes: Vec::new(), trails: vec![0; lights.len()] };
        let mut items: Vec<(u32, LightBounds)> =
            lights.iter().enumerate().filter(|(_, b)| b.phi > 0.0).map(|(i, b)| (i as u32, *b)).collect();
        if !items.is_empty() {
            let mut binary = Vec::with_capacity(2 * items.len());
            let root = Self::build(&mut binary, &mut items, 0);
            tree.collapse(&binary, root, 0, 0);
        }
        tree
    }

    /// Whether no light can be chosen.
    pub(crate) fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Builds the binary subtree over `items` at `depth` into `nodes`; returns its index.
    fn build(nodes: &mut Vec<BinaryNode>, items: &mut [(u32, LightBounds)], depth: u32) -> usize {
        // At most MAX_SAOH_DEPTH levels by cost, then halves: < 64 levels for 2³² lights.
        debug_assert!(depth < 64, "a light tree deeper than its trails' 64 levels");
        let node = if let [(light, b)] = items {
            BinaryNode { bounds: *b, kind: BinaryKind::Light(*light) }
        } else {
            let mid = Self::split(items, depth);
            let (left, right) = items.split_at_mut(mid);
            let a = Self::build(nodes, left, depth + 1);
            let b = Self::build(nodes, right, depth + 1);
            BinaryNode { bounds: nodes[a].bounds.union(nodes[b].bounds), kind: BinaryKind::Split(a, b) }
        };
        nodes.push(node);
        nodes.len() - 1
    }

    /// Makes the four-wide node for binary node `at` (whose trail so far is `trail`, at
    /// `depth`): its children, opened costliest first until there are four (or only
    /// lights); returns its index.
    fn collapse(&mut self, binary: &[BinaryNode], at: usize, trail: u128, depth: u32) -> u32 {
        let children = |s: usize| match binary[s].kind {
            BinaryKind::Light(_) => None,
            BinaryKind::Split(a, b) => Some((a, b)),
        };
        let mut slots = match children(at) {
            None => vec![at],
            Some((a, b)) => vec![a, b],
        };
        while slots.len() < 4 {
            let costliest = (0..slots.len())
                .filter(|&i| children(slots[i]).is_some())
                .max_by(|&i, &j| saoh_cost(&binary[slots[i]].bounds).total_cmp(&saoh_cost(&binary[slots[j]].bounds)));
            let Some(i) = costliest else { break };
            let (a, b) = children(slots[i]).expect("an interior node");
            slots[i] = a;
            slots.insert(i + 1, b);
        }
        let index = self.nodes.len();
        self.nodes.push(Node::EMPTY);
        let mut node = Node::EMPTY;
        for (i, &s) in slots.iter().enumerate() {
            let trail = trail | (i as u128) << (2 * depth);
            match binary[s].kind {
                BinaryKind::Light(light) => {
                    self.trails[light as usize] = trail;
                    node.set(i, &binary[s].bounds, light, true);
                }
                BinaryKind::Split(..) => {
                    let child = self.collapse(binary, s, trail, depth + 1);
                    node.set(i, &binary[s].bounds, child, false);
                }
            }
        }
        node.sin_theta_o = sin_from_cos4(node.cos_theta_o);
        self.nodes[index] = node;
        index as u32
    }

    /// Orders `items` and returns where the first child's end: the bucket boundary of
    /// least cost Kr · Φ · M_Ω · area summed over both sides (Conty Estevez & Kulla 2018,
    /// §4.4; pbrt-v4's `EvaluateCost`, Kr the box's largest extent over the split axis's),
    /// or half the lights where no boundary separates any (or the tree is deep).
    fn split(items: &mut [(u32, LightBounds)], depth: u32) -> usize {
        let half = items.len() / 2;
        let by_count = |items: &mut [(u32, LightBounds)], axis: usize| {
            items.select_nth_unstable_by(half, |a, b| a.1.bounds.centre()[axis].total_cmp(&b.1.bounds.centre()[axis]));
            half
        };
        let bounds = items.iter().fold(Aabb::EMPTY, |acc, (_, b)| acc.union(b.bounds));
        let centroids = items.iter().fold(Aabb::EMPTY, |acc, (_, b)| acc.grow(b.bounds.centre()));
        let extent = centroids.extent();
        let widest = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        if depth >= MAX_SAOH_DEPTH || extent.max_element() <= 0.0 {
            return by_count(items, widest);
        }
        let diagonal = bounds.extent();
        let cost = |b: &Option<LightBounds>| b.as_ref().map_or(0.0, saoh_cost);
        let bucket = |c: f32, axis: usize| -> usize {
            let f = (c - centroids.min[axis]) / extent[axis];
            ((f * BUCKETS as f32) as usize).min(BUCKETS - 1)
        };
        let mut best: Option<(f64, usize, usize)> = None;
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
            for (_, b) in items.iter() {
                let k = bucket(b.bounds.centre()[axis], axis);
                buckets[k] = Some(buckets[k].map_or(*b, |x| x.union(*b)));
            }
            let kr = (diagonal.max_element() / diagonal[axis].max(f32::MIN_POSITIVE)) as f64;
            for split in 1..BUCKETS {
                let join = |s: &[Option<LightBounds>]| {
                    s.iter().flatten().fold(None, |acc: Option<LightBounds>, b| Some(acc.map_or(*b, |a| a.union(*b))))
                };
                let (below, above) = (join(&buckets[..split]), join(&buckets[split..]));
                if below.is_none() || above.is_none() {
                    continue;
                }
                let c = kr * (cost(&below) + cost(&above));
                if best.is_none_or(|(bc, _, _)| c < bc) {
                    best = Some((c, axis, split));
                }
            }
        }
        let Some((_, axis, split)) = best else { return by_count(items, widest) };
        let mut mid = 0;
        for i in 0..items.len() {
            if bucket(items[i].1.bounds.centre()[axis], axis) < split {
                items.swap(i, mid);
                mid += 1;
            }
        }
        if mid == 0 || mid == items.len() { by_count(items, axis) } else { mid }
    }

    /// A light for point `p` with normal `n` (zero: none), chosen with `u` ∈ [0, 1)
    /// from the root down in proportion to the children's importance: its index, its
    /// probability and `u` rescaled to [0, 1) within its share (so that it can place
    /// the point on the light). `None` where no light can reach `p`.
    pub(crate) fn sample(&self, p: Vec3, n: Vec3, mut u: f32) -> Option<(usize, f32, f32)> {
        let mut node = self.nodes.first()?;
        let mut pmf = 1.0f32;
        loop {
            let (e, ends) = node.ends(p, n);
            let total = ends[3];
            // (Importances are finite and never negative; their sum is tested for
            // overflow too, as in `pmf`.)
            if !(total > 0.0 && total < f32::INFINITY) {
                return None;
            }
            let x = u * total;
            // The first slot whose stretch ends past x (a slot of no importance has an
            // empty stretch and is passed over) …
            let mut slot = (ends[0] <= x) as usize + (ends[1] <= x) as usize + (ends[2] <= x) as usize;
            // … but x may round up to the total, past a last slot of no importance.
            while slot > 0 && e[slot] <= 0.0 {
                slot -= 1;
            }
            if e[slot] <= 0.0 {
                // Only for a `u` outside [0, 1) (NaN): nothing to choose.
                return None;
            }
            let start = if slot == 0 { 0.0 } else { ends[slot - 1] };
            u = super::rescale(x, start, ends[slot]);
            pmf *= e[slot] / total;
            let child = node.child[slot];
            if node.lights & (1 << slot) != 0 {
                return Some((child as usize, pmf, u));
            }
            node = &self.nodes[child as usize];
        }
    }

    /// The tree as flat arrays for another backend (the GPU's `wgsl/lights.wgsl`): the
    /// nodes, root first, [`NODE_FLOATS`] floats each — twelve rows of four (one per slot):
    /// the centre's x, y and z, the squared radius, the least squared distance, the cone
    /// axis's x, y and z, power, cos θo, sin θo and cos θe — then the four children (bits),
    /// the lights bitmask (bits) and three zeros; and each light's trail as four words,
    /// low bits first (bits 2d and 2d + 1: the slot taken at depth d).
    pub(crate) fn flatten(&self) -> (Vec<f32>, Vec<[u32; 4]>) {
        let mut nodes = Vec::with_capacity(NODE_FLOATS * self.nodes.len());
        for n in &self.nodes {
            let rows = [
                n.centre[0],
                n.centre[1],
                n.centre[2],
                n.radius2,
                n.min_d2,
                n.w[0],
                n.w[1],
                n.w[2],
                n.phi,
                n.cos_theta_o,
                n.sin_theta_o,
                n.cos_theta_e,
            ];
            nodes.extend(rows.iter().flat_map(|r| r.to_array()));
            nodes.extend(n.child.map(f32::from_bits));
            nodes.extend([f32::from_bits(n.lights as u32), 0.0, 0.0, 0.0]);
        }
        let trails = self.trails.iter().map(|&t| std::array::from_fn(|i| (t >> (32 * i)) as u32)).collect();
        (nodes, trails)
    }

    /// The probability that [`LightTree::sample`] chooses `light` for `p`, `n`.
    pub(crate) fn pmf(&self, light: usize, p: Vec3, n: Vec3) -> f32 {
        let (Some(&trail), Some(mut node)) = (self.trails.get(light), self.nodes.first()) else { return 0.0 };
        let mut pmf = 1.0f32;
        let mut depth = 0;
        loop {
            let (e, ends) = node.ends(p, n);
            let total = ends[3];
            // (Importances are finite and never negative; their sum may overflow.)
            if !(total > 0.0 && total < f32::INFINITY) {
                return 0.0;
            }
            let slot = (trail >> (2 * depth)) as usize & 3;
            pmf *= e[slot] / total;
            let child = node.child[slot];
            if node.lights & (1 << slot) != 0 {
                // A light left out of the tree has trail 0 and ends at another light.
                return if child as usize == light { pmf } else { 0.0 };
            }
            node = &self.nodes[child as usize];
            depth += 1;
        }
    }
}

#[cfg(test)]
mod tests;
