use crate::{Aabb, Accelerator, BuildError, Hit, Ray, Triangle, intersect_triangle, validate};
use glam::Vec3;

/// Tests every triangle: O(n) per ray, trivially correct — the oracle for the tests.
#[derive(Clone, Debug)]
pub struct BruteForce {
    triangles: Vec<Triangle>,
    bounds: Aabb,
}

impl BruteForce {
    /// Stores the triangles; rejects non-finite coordinates.
    pub fn new(triangles: &[[Vec3; 3]]) -> Result<Self, BuildError> {
        validate(triangles)?;
        Ok(Self {
            triangles: triangles.iter().map(Triangle::new).collect(),
            bounds: triangles.iter().fold(Aabb::EMPTY, |b, t| b.union(Triangle::bounds(t))),
        })
    }
}

impl Accelerator for BruteForce {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for (i, tri) in self.triangles.iter().enumerate() {
            if let Some((t, u, v)) = intersect_triangle(tri, ray, t_max) {
                t_max = t;
                best = Some(Hit { prim: i as u32, t, u, v });
            }
        }
        best
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.triangles.iter().any(|tri| intersect_triangle(tri, ray, ray.t_max).is_some())
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}
