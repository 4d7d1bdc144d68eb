//! The thesis's two-level structure (ch. 8.3): a bottom-level accelerator per object and
//! a top-level BVH over object instances, each with its own object-to-world transform.

use crate::builders::build_over_boxes;
use crate::{Aabb, Accelerator, BuildConfig, BuildError, BvhNode, Hit, Ray, RayStats};
use glam::{Affine3A, Vec3};

/// One placement of a bottom-level structure in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index of the bottom-level structure.
    pub object: u32,
    /// Object-to-world transform (any invertible affine map).
    pub transform: Affine3A,
    /// Added to the object's primitive indices in reported hits, so that hits name a
    /// primitive of the whole scene.
    pub prim_offset: u32,
}

struct Placed {
    object: u32,
    world_to_object: Affine3A,
    prim_offset: u32,
}

/// A top-level BVH over instances of bottom-level accelerators `A`.
pub struct TwoLevel<A: Accelerator> {
    objects: Vec<A>,
    instances: Vec<Placed>,
    nodes: Vec<BvhNode>,
    bounds: Aabb,
}

impl<A: Accelerator> TwoLevel<A> {
    /// Builds the top level over `instances` of `objects`. Non-invertible or non-finite
    /// transforms and instances naming a missing object are rejected.
    pub fn new(objects: Vec<A>, instances: &[Instance], config: BuildConfig) -> Result<Self, BuildError> {
        let mut boxes = Vec::with_capacity(instances.len());
        let mut placed = Vec::with_capacity(instances.len());
        for (index, inst) in instances.iter().enumerate() {
            let object = objects.get(inst.object as usize).ok_or(BuildError::BadInstance {
                index,
                reason: format!("object {} of {}", inst.object, objects.len()),
            })?;
            let det = inst.transform.matrix3.determinant();
            if !(det.is_finite() && det != 0.0 && inst.transform.translation.is_finite()) {
                return Err(BuildError::BadInstance {
                    index,
                    reason: "the transform is singular or not finite".into(),
                });
            }
            boxes.push(object.bounds().transformed(&inst.transform));
            placed.push(Placed {
                object: inst.object,
                world_to_object: inst.transform.inverse(),
                prim_offset: inst.prim_offset,
            });
        }
        let out =
            build_over_boxes(&boxes, &BuildConfig { max_leaf_size: config.max_leaf_size.clamp(1, 255), ..config });
        let instances = out.order.iter().map(|&i| std::mem::replace(&mut placed[i as usize], Placed::EMPTY)).collect();
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(*x));
        Ok(Self { objects, instances, nodes: out.nodes, bounds })
    }

    /// The bottom-level structures.
    pub fn objects(&self) -> &[A] {
        &self.objects
    }

    /// Top-level node count.
    pub fn top_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// [`TwoLevel::traverse`] counting into `stats`, one ray per top-level query.
    fn counted(&self, ray: &Ray, any_hit: bool, stats: &mut RayStats) -> Option<Hit> {
        stats.rays += 1;
        let before = stats.rays;
        let hit = self.traverse(ray, any_hit, Some(stats));
        // Bottom-level calls count their own rays; report one ray per top-level query.
        stats.rays = before;
        hit
    }

    fn traverse(&self, ray: &Ray, any_hit: bool, stats: Option<&mut RayStats>) -> Option<Hit> {
        let counting = stats.is_some();
        let mut local_stats = RayStats::default();
        let stats = stats.unwrap_or(&mut local_stats);
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        // A fixed stack for the usual depths, spilling to the heap beyond (no allocation
        // per ray in practice).
        let mut fixed = [0usize; 64];
        let mut depth = 1;
        let mut spill: Vec<usize> = Vec::new();
        let push = |fixed: &mut [usize; 64], depth: &mut usize, spill: &mut Vec<usize>, i: usize| {
            if *depth < fixed.len() {
                fixed[*depth] = i;
                *depth += 1;
            } else {
                spill.push(i);
            }
        };
        loop {
            let i = if let Some(i) = spill.pop() {
                i
            } else if depth > 0 {
                depth -= 1;
                fixed[depth]
            } else {
                break;
            };
            let n = &self.nodes[i];
            let aabb = Aabb { min: Vec3::from_array(n.min), max: Vec3::from_array(n.max) };
            if aabb.hit(ray, t_max).is_none() {
                continue;
            }
            if n.count == 0 {
                push(&mut fixed, &mut depth, &mut spill, n.index as usize);
                push(&mut fixed, &mut depth, &mut spill, i + 1);
                continue;
            }
            for inst in &self.instances[n.index as usize..(n.index + n.count) as usize] {
                // The direction is transformed but not renormalised, so t is the same
                // parameter in both spaces.
                let local = Ray::segment(
                    inst.world_to_object.transform_point3(ray.origin),
                    inst.world_to_object.transform_vector3(ray.dir),
                    ray.t_min,
                    t_max,
                );
                let object = &self.objects[inst.object as usize];
                if any_hit {
                    let blocked =
                        if counting { object.occluded_counted(&local, stats) } else { object.occluded(&local) };
                    if blocked {
                        return Some(Hit { prim: inst.prim_offset, t: 0.0, u: 0.0, v: 0.0 });
                    }
                } else if let Some(h) = object.intersect_counted(&local, stats) {
                    t_max = h.t;
                    best = Some(Hit { prim: h.prim + inst.prim_offset, ..h });
                }
            }
        }
        best
    }
}

impl Placed {
    const EMPTY: Self = Self { object: 0, world_to_object: Affine3A::IDENTITY, prim_offset: 0 };
}

impl<A: Accelerator> Accelerator for TwoLevel<A> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse(ray, false, None)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.traverse(ray, true, None).is_some()
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn intersect_counted(&self, ray: &Ray, stats: &mut RayStats) -> Option<Hit> {
        self.counted(ray, false, stats)
    }

    fn occluded_counted(&self, ray: &Ray, stats: &mut RayStats) -> bool {
        self.counted(ray, true, stats).is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn soup(seed: u64, n: usize) -> Vec<[Vec3; 3]> {
        crate::test_util::soup(seed, n, 2.0, 0.6)
    }
    use crate::{BruteForce, Bvh};
    use glam::Quat;

    #[test]
    fn instances_agree_with_brute_force_on_the_transformed_soup() {
        let objects: Vec<Vec<[Vec3; 3]>> = (0..3).map(|k| soup(k, 200)).collect();
        let mut instances = Vec::new();
        let mut world = Vec::new();
        let mut offset = 0u32;
        for i in 0..6u32 {
            let object = i % 3;
            let transform = Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.5 + 0.3 * i as f32),
                Quat::from_euler(glam::EulerRot::XYZ, 0.3 * i as f32, 0.7, -0.2 * i as f32),
                Vec3::new(3.0 * i as f32, -1.0 + i as f32, 0.5 * i as f32),
            );
            instances.push(Instance { object, transform, prim_offset: offset });
            world.extend(objects[object as usize].iter().map(|t| t.map(|v| transform.transform_point3(v))));
            offset += objects[object as usize].len() as u32;
        }
        let blas: Vec<Bvh> = objects.iter().map(|o| Bvh::build(o, BuildConfig::default()).unwrap()).collect();
        let tlas = TwoLevel::new(blas, &instances, BuildConfig::default()).unwrap();
        let oracle = BruteForce::new(&world).unwrap();
        let probes = soup(99, 2000);
        let mut hits = 0;
        for (k, p) in probes.iter().enumerate() {
            // From a random point, towards (or near) a random world triangle.
            let target = world[(k * 7919) % world.len()][0] + (p[2] - p[1]) * 0.3;
            let origin = p[0] * 8.0 - Vec3::new(2.0, 2.0, 2.0);
            let ray = Ray::new(origin, (target - origin).normalize_or(Vec3::X));
            let (a, b) = (tlas.intersect(&ray), oracle.intersect(&ray));
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a.t - b.t).abs() <= 1e-4 * b.t.max(1.0), "t {} vs {}", a.t, b.t);
                    assert!(a.prim == b.prim || (a.t - b.t).abs() <= 1e-4 * b.t.max(1.0));
                }
                // A hit exactly on an edge may be found in one space and not the other.
                (a, b) => {
                    let t = a.or(b).unwrap().t;
                    let edge_case = oracle.intersect(&Ray::segment(ray.origin, ray.dir, 0.0, t * 1.0001)).is_some()
                        != tlas.intersect(&Ray::segment(ray.origin, ray.dir, 0.0, t * 1.0001)).is_some();
                    assert!(edge_case, "tlas {a:?} vs brute force {b:?}");
                }
            }
            assert_eq!(tlas.occluded(&ray), oracle.occluded(&ray));
        }
        assert!(hits > 1000, "{hits} hits: the test must exercise hits");
        assert_eq!(tlas.objects().len(), 3);
    }

    #[test]
    fn bad_instances_are_rejected() {
        let blas = vec![Bvh::build(&soup(1, 10), BuildConfig::default()).unwrap()];
        let bad_object = [Instance { object: 3, transform: Affine3A::IDENTITY, prim_offset: 0 }];
        assert!(TwoLevel::new(blas.clone(), &bad_object, BuildConfig::default()).is_err());
        let singular =
            [Instance { object: 0, transform: Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)), prim_offset: 0 }];
        assert!(TwoLevel::new(blas.clone(), &singular, BuildConfig::default()).is_err());
        let empty = TwoLevel::new(blas, &[], BuildConfig::default()).unwrap();
        assert!(empty.intersect(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
    }
}
