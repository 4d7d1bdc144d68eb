//! The wide node: the boxes of up to `W` children as structure of arrays, laid out so
//! that each plane row is one aligned SIMD load (16 bytes for 4 lanes, 32 for 8).

use crate::Aabb;
use glam::Vec3;

/// One node of a [`BvhWide`](super::BvhWide): the boxes of up to `W` children as structure
/// of arrays, 32·`W` bytes (two cache lines for 4 children, four for 8), 64-byte aligned.
///
/// Slot `i` is a leaf of triangles `child[i] .. child[i] + count[i]` in the tree's leaf
/// order ([`BvhWide::prim_ids`](super::BvhWide::prim_ids)) if `count[i] > 0`, else the interior
/// node `child[i]`. Unused slots have an empty box (min = +∞, max = −∞) that no ray enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNode<const W: usize> {
    /// Lower x of each child's box.
    pub min_x: [f32; W],
    /// Lower y of each child's box.
    pub min_y: [f32; W],
    /// Lower z of each child's box.
    pub min_z: [f32; W],
    /// Upper x of each child's box.
    pub max_x: [f32; W],
    /// Upper y of each child's box.
    pub max_y: [f32; W],
    /// Upper z of each child's box.
    pub max_z: [f32; W],
    /// Interior child: its node index; leaf child: its first triangle.
    pub child: [u32; W],
    /// Triangles in a leaf child; 0 for an interior child or an unused slot.
    pub count: [u32; W],
}

/// A node of a [`Bvh4`](super::Bvh4): 128 bytes.
pub type Bvh4Node = WideNode<4>;

/// A node of a [`Bvh8`](super::Bvh8): 256 bytes.
pub type Bvh8Node = WideNode<8>;

// SAFETY: eight arrays of W 4-byte plain values, repr(C); for W = 4 and 8 the size
// (32·W bytes) is a multiple of the 64-byte alignment, so there is no padding, and every
// bit pattern is a valid node.
unsafe impl bytemuck::Zeroable for WideNode<4> {}
unsafe impl bytemuck::Pod for WideNode<4> {}
unsafe impl bytemuck::Zeroable for WideNode<8> {}
unsafe impl bytemuck::Pod for WideNode<8> {}

impl<const W: usize> WideNode<W> {
    /// A node whose slots are all unused.
    pub const EMPTY: Self = Self {
        min_x: [f32::INFINITY; W],
        min_y: [f32::INFINITY; W],
        min_z: [f32::INFINITY; W],
        max_x: [f32::NEG_INFINITY; W],
        max_y: [f32::NEG_INFINITY; W],
        max_z: [f32::NEG_INFINITY; W],
        child: [0; W],
        count: [0; W],
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
        (0..W).fold(Aabb::EMPTY, |b, i| b.union(self.child_bounds(i)))
    }

    pub(super) fn set_child(&mut self, i: usize, bounds: &Aabb, child: u32, count: u32) {
        (self.min_x[i], self.min_y[i], self.min_z[i]) = bounds.min.into();
        (self.max_x[i], self.max_y[i], self.max_z[i]) = bounds.max.into();
        self.child[i] = child;
        self.count[i] = count;
    }

    /// The node's six plane rows, in field order (min x, y, z, max x, y, z).
    #[inline(always)]
    pub(super) fn planes(&self) -> &[[f32; W]; 6] {
        // SAFETY: repr(C) puts the six `[f32; W]` plane fields first, contiguous and
        // without padding between them (equal size and alignment).
        unsafe { &*(self as *const Self).cast::<[[f32; W]; 6]>() }
    }
}
