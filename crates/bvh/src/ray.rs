use glam::Vec3;

/// A ray segment origin + t·dir, t ∈ (t_min, t_max). `dir` need not be normalised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction.
    pub dir: Vec3,
    /// Per-component reciprocal of `dir` (±∞ for zero components, keeping the sign of
    /// ±0), precomputed for the slab test.
    pub inv_dir: Vec3,
    /// Hits at t ≤ t_min are ignored.
    pub t_min: f32,
    /// Hits at t ≥ t_max are ignored.
    pub t_max: f32,
}

impl Ray {
    /// A ray over (0, ∞).
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::segment(origin, dir, 0.0, f32::INFINITY)
    }

    /// A ray over (t_min, t_max).
    #[inline]
    pub fn segment(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Self { origin, dir, inv_dir: dir.recip(), t_min, t_max }
    }

    /// The point at parameter t.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// A ray–triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Index of the triangle in the accelerator's input order.
    pub prim: u32,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2 (vertex 0 has 1 − u − v).
    pub v: f32,
}
