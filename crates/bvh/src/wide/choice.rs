//! [`WideBvh`]: the wide tree a renderer should use on the CPU it runs on, chosen at run
//! time ([`BvhWidth::Auto`]) or by the user.

use super::{Bvh4, Bvh8, wide8_accelerated};
use crate::{Aabb, Accelerator, BuildConfig, BuildError, Hit, Ray, RayStats, TriangleTest};
use glam::Vec3;

/// How many children per node a [`WideBvh`] has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BvhWidth {
    /// 8 where the CPU has AVX2 ([`wide8_accelerated`]), else 4.
    #[default]
    Auto,
    /// The binary tree ([`crate::Bvh`]) as it is: the GPU backend can traverse it (for
    /// comparisons with its wide nodes); the CPU backend has no kernel for it and refuses
    /// it.
    Two,
    /// [`Bvh4`]: SSE, every x86_64 CPU.
    Four,
    /// [`Bvh8`]: AVX2 (the portable kernel without it).
    Eight,
}

impl BvhWidth {
    /// Every choice.
    pub const ALL: [BvhWidth; 4] = [Self::Auto, Self::Two, Self::Four, Self::Eight];

    /// The choices the CPU's wide kernels serve.
    pub const CPU: [BvhWidth; 3] = [Self::Auto, Self::Four, Self::Eight];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Two => "2",
            Self::Four => "4",
            Self::Eight => "8",
        }
    }

    /// The width of the CPU's wide tree this choice gives on this CPU: 4 or 8 (4 for
    /// [`BvhWidth::Two`], which the CPU backend refuses before building anything).
    pub fn resolve(self) -> u32 {
        match self {
            Self::Auto if wide8_accelerated() => 8,
            Self::Auto | Self::Two | Self::Four => 4,
            Self::Eight => 8,
        }
    }
}

/// A [`Bvh4`] or a [`Bvh8`], by [`BvhWidth`]: one branch per query on which.
#[derive(Clone, Debug)]
pub enum WideBvh {
    /// 4 children per node.
    Four(Bvh4),
    /// 8 children per node.
    Eight(Bvh8),
}

impl WideBvh {
    /// Builds a binary tree with `config` and collapses it to `width` (see
    /// [`BvhWide::build`](super::BvhWide::build)).
    pub fn build(triangles: &[[Vec3; 3]], config: BuildConfig, width: BvhWidth) -> Result<Self, BuildError> {
        Ok(match width.resolve() {
            8 => Self::Eight(Bvh8::build(triangles, config)?),
            _ => Self::Four(Bvh4::build(triangles, config)?),
        })
    }

    /// Selects the triangle test.
    pub fn with_triangle_test(self, test: TriangleTest) -> Self {
        match self {
            Self::Four(b) => Self::Four(b.with_triangle_test(test)),
            Self::Eight(b) => Self::Eight(b.with_triangle_test(test)),
        }
    }

    /// [`Bvh8::occluded_packet`] of the tree: up to [`super::PACKET`] shadow rays at
    /// once, the same answers as [`Accelerator::occluded`] ray by ray.
    pub fn occluded_packet(&self, rays: &[Ray], occluded: &mut [bool]) {
        match self {
            Self::Four(b) => b.occluded_packet(rays, occluded),
            Self::Eight(b) => b.occluded_packet(rays, occluded),
        }
    }

    /// [`Bvh8::intersect_packet`] of the tree: the closest hits of up to
    /// [`super::PACKET`] rays at once, the same as [`Accelerator::intersect`] ray by ray.
    pub fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        match self {
            Self::Four(b) => b.intersect_packet(rays, hits),
            Self::Eight(b) => b.intersect_packet(rays, hits),
        }
    }

    /// The tree and the kernel that traverses it on this CPU, for messages.
    pub fn description(&self) -> &'static str {
        match self {
            Self::Eight(_) if crate::isa::active() == crate::isa::Isa::Avx512 => "8-wide BVH (AVX-512)",
            Self::Eight(_) if wide8_accelerated() => "8-wide BVH (AVX2)",
            Self::Eight(_) => "8-wide BVH (portable kernel)",
            Self::Four(_) if cfg!(target_arch = "x86_64") => "4-wide BVH (SSE)",
            Self::Four(_) => "4-wide BVH (portable kernel)",
        }
    }

    /// Whether closest hits' t is recomputed in f64, the default ([`BvhWide::with_exact_t`](super::BvhWide::with_exact_t)).
    pub fn with_exact_t(self, exact: bool) -> Self {
        match self {
            Self::Four(b) => Self::Four(b.with_exact_t(exact)),
            Self::Eight(b) => Self::Eight(b.with_exact_t(exact)),
        }
    }

    /// Node count, leaf count, depth and SAH cost ([`BvhWide::stats`](super::BvhWide::stats)).
    pub fn stats(&self) -> super::WideStats {
        match self {
            Self::Four(b) => b.stats(),
            Self::Eight(b) => b.stats(),
        }
    }

    /// Triangle references in the leaves: the triangle count, more where triangles were
    /// pre-split ([`crate::BuildConfig::presplit`]).
    pub fn references(&self) -> usize {
        match self {
            Self::Four(b) => b.prim_ids().len(),
            Self::Eight(b) => b.prim_ids().len(),
        }
    }

    /// Children per node: 4 or 8.
    pub fn width(&self) -> u32 {
        match self {
            Self::Four(_) => 4,
            Self::Eight(_) => 8,
        }
    }
}

impl Accelerator for WideBvh {
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        match self {
            Self::Four(b) => b.intersect(ray),
            Self::Eight(b) => b.intersect(ray),
        }
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        match self {
            Self::Four(b) => b.occluded(ray),
            Self::Eight(b) => b.occluded(ray),
        }
    }

    fn bounds(&self) -> Aabb {
        match self {
            Self::Four(b) => b.bounds(),
            Self::Eight(b) => b.bounds(),
        }
    }

    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        match self {
            Self::Four(b) => b.intersect_counted(ray, stats),
            Self::Eight(b) => b.intersect_counted(ray, stats),
        }
    }

    fn occluded_counted(&self, ray: &Ray, stats: &mut RayStats) -> bool {
        match self {
            Self::Four(b) => b.occluded_counted(ray, stats),
            Self::Eight(b) => b.occluded_counted(ray, stats),
        }
    }
}
