//! The wide node: four child boxes as structure of arrays, laid out so that each plane
//! row is one aligned 16-byte SSE load.

use super::WIDTH;
use crate::Aabb;
use glam::Vec3;

/// One node of a [`Bvh4`](super::Bvh4): the boxes of up to four children as structure of arrays,
/// 128 bytes (two cache lines), 64-byte aligned, POD.
///
/// Slot `i` is a leaf of triangles `child[i] .. child[i] + count[i]` in the tree's leaf
/// order ([`Bvh4::prim_ids`](super::Bvh4::prim_ids)) if `count[i] > 0`, else the interior node `child[i]`.
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

    pub(super) fn set_child(&mut self, i: usize, bounds: &Aabb, child: u32, count: u32) {
        (self.min_x[i], self.min_y[i], self.min_z[i]) = bounds.min.into();
        (self.max_x[i], self.max_y[i], self.max_z[i]) = bounds.max.into();
        self.child[i] = child;
        self.count[i] = count;
    }

    /// The node's six plane rows, in field order (min x, y, z, max x, y, z).
    #[inline(always)]
    pub(super) fn planes(&self) -> &[[f32; 4]; 8] {
        bytemuck::cast_ref(self)
    }
}
