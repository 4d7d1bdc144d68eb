//! A light tree: the emitters in a binary hierarchy whose nodes bound their lights'
//! positions, emission directions and power, so that a shading point chooses a light in
//! proportion to an estimate of what each part of the tree can give it, instead of in
//! proportion to power alone (Conty Estevez & Kulla 2018, "Importance Sampling of Many
//! Lights with Adaptive Tree Splitting"; the bounds, importance and build as pbrt-v4's
//! `BVHLightSampler`, Pharr, Jakob & Humphreys, *Physically Based Rendering*, 4th ed.,
//! §12.6.3). With many lights most of them are far, small or facing away from any given
//! point, and power sampling spends its shadow rays on them.
//!
//! The choice is unbiased however rough the estimate, as long as every light that can
//! light a point has a non-zero probability there: the bounds are conservative (a node's
//! cone holds every direction its lights emit into), so the estimate is zero only where
//! no light of a node can reach the point.

use bvh::Aabb;
use glam::{Quat, Vec3};
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

/// cos(max(0, a − b)) from the sines and cosines of a and b (pbrt-v4's `cosSubClamped`).
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 1.0 } else { cos_a * cos_b + sin_a * sin_b }
}

/// sin(max(0, a − b)) (pbrt-v4's `sinSubClamped`).
#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b { 0.0 } else { sin_a * cos_b - cos_a * sin_b }
}

/// sin θ from cos θ for θ in [0, π].
#[inline]
fn sin_from_cos(c: f32) -> f32 {
    (1.0 - c * c).max(0.0).sqrt()
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

/// What [`Estimate::importance`] reads of a node's [`LightBounds`], precomputed once:
/// the box's centre, its bounding sphere and the cone's sine (a node is estimated at
/// every step of every light choice).
#[derive(Clone, Copy, Debug)]
struct Estimate {
    centre: Vec3,
    /// The bounding sphere's squared radius.
    radius2: f32,
    /// The least squared distance the estimate divides by: half the box's diagonal
    /// (pbrt-v4's clamp), so that a point near or inside the box gets a bounded value.
    min_d2: f32,
    /// As [`LightBounds`]'s, with the cone's sine.
    w: Vec3,
    phi: f32,
    cos_theta_o: f32,
    sin_theta_o: f32,
    cos_theta_e: f32,
}

impl Estimate {
    fn new(b: &LightBounds) -> Self {
        let centre = b.bounds.centre();
        Self {
            centre,
            radius2: centre.distance_squared(b.bounds.max),
            min_d2: 0.5 * b.bounds.extent().length(),
            w: b.w,
            phi: b.phi,
            cos_theta_o: b.cos_theta_o,
            sin_theta_o: sin_from_cos(b.cos_theta_o),
            cos_theta_e: b.cos_theta_e,
        }
    }

    /// An upper estimate of what the node's lights give point `p` with normal `n`
    /// (zero `n`: no cosine there): power over squared distance, times the cosine at the
    /// lights of the smallest angle between their cone and the direction to `p`, and the
    /// cosine at `p` of the smallest angle to the box, each angle reduced by the box's
    /// angular radius seen from `p` (pbrt-v4's `LightBounds::Importance`). Zero only where
    /// no direction the lights emit into reaches `p`; finite and never negative.
    #[inline(always)]
    fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        let d = p - self.centre;
        let dist2 = d.length_squared();
        let wi = if dist2 > 0.0 { d / dist2.sqrt() } else { Vec3::ZERO };
        let cos_theta_w = self.w.dot(wi);
        let sin_theta_w = sin_from_cos(cos_theta_w);
        // The box's angular radius from p, through its bounding sphere.
        let cos_theta_b = if dist2 < self.radius2 { -1.0 } else { (1.0 - self.radius2 / dist2).max(0.0).sqrt() };
        let sin_theta_b = sin_from_cos(cos_theta_b);
        let cos_theta_x = cos_sub_clamped(sin_theta_w, cos_theta_w, self.sin_theta_o, self.cos_theta_o);
        let sin_theta_x = sin_sub_clamped(sin_theta_w, cos_theta_w, self.sin_theta_o, self.cos_theta_o);
        let cos_theta_p = cos_sub_clamped(sin_theta_x, cos_theta_x, sin_theta_b, cos_theta_b);
        if cos_theta_p <= self.cos_theta_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_theta_p / dist2.max(self.min_d2);
        if n != Vec3::ZERO {
            let cos_theta_i = wi.dot(n).abs();
            let sin_theta_i = sin_from_cos(cos_theta_i);
            importance *= cos_sub_clamped(sin_theta_i, cos_theta_i, sin_theta_b, cos_theta_b);
        }
        if importance.is_finite() { importance.max(0.0) } else { 0.0 }
    }
}

/// A node: its estimate and either its light (a leaf) or its second child (the first
/// follows it).
#[derive(Clone, Copy, Debug)]
struct Node {
    estimate: Estimate,
    /// Leaf: the light's index; interior: the second child's node index.
    index: u32,
    leaf: bool,
}

/// The tree over a scene's sampled emitters (indices into `Lights::prims`).
#[derive(Clone, Debug)]
pub(crate) struct LightTree {
    nodes: Vec<Node>,
    /// For each light, the turns from the root to its leaf (bit d: the child taken at
    /// depth d, 1 for the second).
    trails: Vec<u64>,
}

/// Deeper than this the build splits by count, so that every trail fits its 64 bits.
const MAX_SAOH_DEPTH: u32 = 32;
/// Buckets per axis of the build's split search (pbrt-v4's 12).
const BUCKETS: usize = 12;

impl LightTree {
    /// The tree over `lights` (light k's bounds at index k); lights of zero power are
    /// left out (never chosen). Empty if none has power.
    pub(crate) fn new(lights: &[LightBounds]) -> Self {
        let mut tree = Self { nodes: Vec::new(), trails: vec![0; lights.len()] };
        let mut items: Vec<(u32, LightBounds)> =
            lights.iter().enumerate().filter(|(_, b)| b.phi > 0.0).map(|(i, b)| (i as u32, *b)).collect();
        if !items.is_empty() {
            tree.build(&mut items, 0, 0);
        }
        tree
    }

    /// Whether no light can be chosen.
    pub(crate) fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Builds the subtree over `items`, whose trail so far is `trail` at `depth`; returns
    /// its bounds.
    fn build(&mut self, items: &mut [(u32, LightBounds)], trail: u64, depth: u32) -> LightBounds {
        // At most MAX_SAOH_DEPTH levels by cost, then halves: ≤ 64 levels for 2³² lights.
        debug_assert!(depth < 64, "a light tree deeper than its trails' 64 bits");
        if let [(light, b)] = items {
            self.trails[*light as usize] = trail;
            self.nodes.push(Node { estimate: Estimate::new(b), index: *light, leaf: true });
            return *b;
        }
        let mid = Self::split(items, depth);
        let at = self.nodes.len();
        // A placeholder, completed once both children are built.
        self.nodes.push(Node { estimate: Estimate::new(&items[0].1), index: 0, leaf: false });
        let (left, right) = items.split_at_mut(mid);
        let a = self.build(left, trail, depth + 1);
        let second = self.nodes.len() as u32;
        let b = self.build(right, trail | (1 << depth), depth + 1);
        let bounds = a.union(b);
        self.nodes[at] = Node { estimate: Estimate::new(&bounds), index: second, leaf: false };
        bounds
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
        let cost = |b: &Option<LightBounds>| {
            b.map_or(0.0, |b| b.phi as f64 * b.orientation_measure() as f64 * b.bounds.surface_area().max(0.0) as f64)
        };
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

    /// The two children's importance for `p`, `n`, and the second child's index. (Both
    /// inlined here: the two estimates are independent, and the CPU overlaps them.)
    #[inline(always)]
    fn children(&self, node: usize, p: Vec3, n: Vec3) -> ([f32; 2], usize) {
        let second = self.nodes[node].index as usize;
        ([self.nodes[node + 1].estimate.importance(p, n), self.nodes[second].estimate.importance(p, n)], second)
    }

    /// A light for point `p` with normal `n` (zero: none), chosen with `u` ∈ [0, 1)
    /// from the root down in proportion to the children's importance: its index, its
    /// probability and `u` rescaled to [0, 1) within its share (so that it can place
    /// the point on the light). `None` where no light can reach `p`.
    pub(crate) fn sample(&self, p: Vec3, n: Vec3, mut u: f32) -> Option<(usize, f32, f32)> {
        let mut node = 0;
        let mut pmf = 1.0f32;
        loop {
            let current = self.nodes.get(node)?;
            if current.leaf {
                if node > 0 || current.estimate.importance(p, n) > 0.0 {
                    return Some((current.index as usize, pmf, u));
                }
                return None;
            }
            let ([a, b], second) = self.children(node, p, n);
            let total = a + b;
            // (Importances are finite and never negative.)
            if total <= 0.0 {
                return None;
            }
            let p0 = a / total;
            if u < p0 {
                u = super::rescale(u, 0.0, p0);
                pmf *= p0;
                node += 1;
            } else {
                u = super::rescale(u, p0, 1.0);
                // b / total, not 1 − p0: the same factor as `pmf`'s.
                pmf *= b / total;
                node = second;
            }
        }
    }

    /// The probability that [`LightTree::sample`] chooses `light` for `p`, `n`.
    pub(crate) fn pmf(&self, light: usize, p: Vec3, n: Vec3) -> f32 {
        let Some(&trail) = self.trails.get(light) else { return 0.0 };
        let mut node = 0;
        let mut pmf = 1.0f32;
        let mut depth = 0;
        loop {
            let Some(current) = self.nodes.get(node) else { return 0.0 };
            if current.leaf {
                // A light left out of the tree has trail 0 and would end at another leaf.
                if current.index as usize != light {
                    return 0.0;
                }
                if node == 0 && current.estimate.importance(p, n) <= 0.0 {
                    return 0.0;
                }
                return pmf;
            }
            let ([a, b], second) = self.children(node, p, n);
            let total = a + b;
            // (Importances are finite and never negative.)
            if total <= 0.0 {
                return 0.0;
            }
            let right = (trail >> depth) & 1 == 1;
            if right {
                pmf *= b / total;
                node = second;
            } else {
                pmf *= a / total;
                node += 1;
            }
            depth += 1;
        }
    }
}

#[cfg(test)]
mod tests;
