//! A BVH over arbitrary boxes, for primitives the crate does not know (analytic shapes,
//! instances): the caller intersects a leaf's primitives through a callback.

use crate::builders::build_over_boxes;
use crate::{Aabb, BuildConfig, BuildError, BvhNode, Ray};

/// A binary BVH over the boxes of opaque primitives, flattened depth-first like
/// [`crate::Bvh`].
#[derive(Clone, Debug, Default)]
pub struct BoxBvh {
    nodes: Vec<BvhNode>,
    /// Leaf slot → primitive index.
    order: Vec<u32>,
    bounds: Aabb,
}

/// Traversal stack depth; the builders stop at 62 levels.
const STACK: usize = 64;

impl BoxBvh {
    /// Builds the tree over `boxes` (one per primitive, in primitive order). Boxes with
    /// NaN or infinite corners are rejected: an unbounded primitive cannot be culled.
    pub fn build(boxes: &[Aabb], config: BuildConfig) -> Result<Self, BuildError> {
        if boxes.len() >= u32::MAX as usize {
            return Err(BuildError::TooManyTriangles(boxes.len()));
        }
        if let Some(index) = boxes.iter().position(|b| !(b.is_empty() || b.min.is_finite() && b.max.is_finite())) {
            let b = boxes[index];
            let bad = if b.min.is_finite() { b.max } else { b.min };
            return Err(BuildError::NonFinite { index, vertex: bad.to_array() });
        }
        let out = build_over_boxes(boxes, &BuildConfig { max_leaf_size: config.max_leaf_size.clamp(1, 255), ..config });
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(*x));
        Ok(Self { nodes: out.nodes, order: out.order, bounds })
    }

    /// The union of all boxes.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Node count.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The nodes (root first, the left child after its parent; a leaf's `index..index +
    /// count` are slots of [`BoxBvh::order`]), for backends that traverse the tree elsewhere
    /// (the GPU).
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// Leaf slot → primitive index.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Visits the leaves `ray` enters within (t_min, `t_max`], nearest box first, calling
    /// `hit(prim, t_max)` for each primitive there; the callback returns the distance of a
    /// hit closer than the `t_max` it was given (which then shrinks) or `None`. With
    /// `any_hit`, stops at the first hit. Returns the final `t_max` if anything was hit.
    pub fn traverse(
        &self,
        ray: &Ray,
        t_max: f32,
        any_hit: bool,
        mut hit: impl FnMut(u32, f32) -> Option<f32>,
    ) -> Option<f32> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut t_max = t_max;
        let mut found = false;
        let mut stack = [(0usize, 0.0f32); STACK];
        let mut sp = 0;
        let root = &self.nodes[0];
        let t0 = node_box(root).hit(ray, t_max)?;
        stack[sp] = (0, t0);
        sp += 1;
        while sp > 0 {
            sp -= 1;
            let (i, t_enter) = stack[sp];
            if t_enter > t_max {
                continue;
            }
            let n = &self.nodes[i];
            if n.count > 0 {
                for &prim in &self.order[n.index as usize..(n.index + n.count) as usize] {
                    if let Some(t) = hit(prim, t_max) {
                        t_max = t;
                        found = true;
                        if any_hit {
                            return Some(t_max);
                        }
                    }
                }
                continue;
            }
            let (l, r) = (i + 1, n.index as usize);
            let tl = node_box(&self.nodes[l]).hit(ray, t_max);
            let tr = node_box(&self.nodes[r]).hit(ray, t_max);
            // Push the far child first so the near one is visited first.
            let mut push = |c: usize, t: f32| {
                stack[sp] = (c, t);
                sp += 1;
            };
            match (tl, tr) {
                (Some(a), Some(b)) if a <= b => {
                    push(r, b);
                    push(l, a);
                }
                (Some(a), Some(b)) => {
                    push(l, a);
                    push(r, b);
                }
                (Some(a), None) => push(l, a),
                (None, Some(b)) => push(r, b),
                (None, None) => {}
            }
        }
        found.then_some(t_max)
    }
}

#[inline]
fn node_box(n: &BvhNode) -> Aabb {
    Aabb { min: glam::Vec3::from_array(n.min), max: glam::Vec3::from_array(n.max) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Unit spheres' boxes on a line; the callback intersects the spheres exactly.
    #[test]
    fn finds_the_nearest_primitive_and_any_hit() {
        let centres: Vec<Vec3> = (0..50).map(|i| Vec3::new(3.0 * i as f32, (i % 7) as f32 * 0.1, 0.0)).collect();
        let boxes: Vec<Aabb> = centres.iter().map(|c| Aabb { min: *c - 1.0, max: *c + 1.0 }).collect();
        let bvh = BoxBvh::build(&boxes, BuildConfig { max_leaf_size: 2, ..Default::default() }).unwrap();
        let sphere_t = |c: Vec3, r: &Ray| {
            let oc = r.origin - c;
            let b = oc.dot(r.dir);
            let disc = b * b - (oc.length_squared() - 1.0);
            (disc >= 0.0).then(|| -b - disc.sqrt()).filter(|t| *t > r.t_min)
        };
        for (k, dir) in [Vec3::X, -Vec3::X].into_iter().enumerate() {
            let o = if k == 0 { Vec3::new(-10.0, 0.0, 0.0) } else { Vec3::new(200.0, 0.0, 0.0) };
            let r = Ray::new(o, dir);
            let mut calls = 0;
            let t = bvh.traverse(&r, r.t_max, false, |p, t_max| {
                calls += 1;
                sphere_t(centres[p as usize], &r).filter(|t| *t < t_max)
            });
            let expected = centres.iter().filter_map(|c| sphere_t(*c, &r)).fold(f32::INFINITY, f32::min);
            assert_eq!(t, Some(expected));
            assert!(calls < 10, "{calls} primitives tested for the nearest of 50");
        }
        let miss = Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::X);
        assert_eq!(bvh.traverse(&miss, f32::INFINITY, false, |_, _| Some(1.0)), None);
        let any = bvh.traverse(&Ray::new(Vec3::new(-10.0, 0.0, 0.0), Vec3::X), f32::INFINITY, true, |_, _| Some(5.0));
        assert_eq!(any, Some(5.0));
    }

    #[test]
    fn empty_and_bad_input() {
        let empty = BoxBvh::build(&[], BuildConfig::default()).unwrap();
        assert_eq!(empty.traverse(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY, false, |_, _| Some(1.0)), None);
        let bad = [Aabb { min: Vec3::ZERO, max: Vec3::new(f32::INFINITY, 1.0, 1.0) }];
        assert!(matches!(BoxBvh::build(&bad, BuildConfig::default()), Err(BuildError::NonFinite { index: 0, .. })));
    }
}
