use super::*;
use std::f32::consts::FRAC_PI_4;

use rng::Pcg32;

fn unit_box() -> Cuboid {
    Cuboid::axis_aligned(Vec3::ZERO, Vec3::ONE).unwrap()
}

#[test]
fn rejects_invalid_boxes() {
    assert!(Cuboid::axis_aligned(Vec3::ONE, Vec3::ZERO).is_err());
    assert!(Cuboid::axis_aligned(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0)).is_err());
    assert!(Cuboid::axis_aligned(Vec3::ZERO, Vec3::new(1.0, f32::NAN, 1.0)).is_err());
    assert!(Cuboid::oriented(Vec3::ZERO, Vec3::new(1.0, -1.0, 1.0), Quat::IDENTITY).is_err());
    assert!(Cuboid::oriented(Vec3::ZERO, Vec3::ONE, Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)).is_err());
    assert!(Cuboid::oriented(Vec3::INFINITY, Vec3::ONE, Quat::IDENTITY).is_err());
    let b = Cuboid::oriented(Vec3::ONE, Vec3::ONE, Quat::IDENTITY).unwrap();
    assert!(b.is_axis_aligned());
    assert!(!Cuboid::oriented(Vec3::ONE, Vec3::ONE, Quat::from_rotation_z(0.1)).unwrap().is_axis_aligned());
}

#[test]
fn axis_rays_with_zero_and_negative_zero_components() {
    let b = unit_box();
    for z in [0.0f32, -0.0] {
        let inside = Ray::new(Vec3::new(0.5, -1.0, 0.5), Vec3::new(z, 1.0, z));
        let h = b.intersect(&inside).unwrap();
        assert_eq!((h.t, h.p, h.n), (1.0, Vec3::new(0.5, 0.0, 0.5), -Vec3::Y));
        let outside = Ray::new(Vec3::new(0.5, -1.0, 1.5), Vec3::new(z, 1.0, z));
        assert!(b.intersect(&outside).is_none());
        let down = Ray::new(Vec3::new(0.25, 3.0, 0.75), Vec3::new(z, -2.0, z));
        let h = b.intersect(&down).unwrap();
        assert_eq!((h.t, h.n), (1.0, Vec3::Y));
        // Through the slab function directly.
        let s = slab(Vec3::new(0.0, -3.0, 0.0), Vec3::new(z, 1.0, -z), Vec3::ONE, 0.0, f32::INFINITY);
        assert_eq!(s, Some((2.0, 4.0, 1, 1)));
    }
}

#[test]
fn origin_on_a_face_plane_moving_parallel_is_inside_the_closed_slab() {
    let b = unit_box();
    for z in [0.0f32, -0.0] {
        // On x = 0 (a face plane), moving along y: the x slab yields 0·∞ = NaN.
        let r = Ray::new(Vec3::new(0.0, -1.0, 0.5), Vec3::new(z, 1.0, z));
        let h = b.intersect(&r).expect("a ray within a face plane hits the closed box");
        assert_eq!((h.t, h.n), (1.0, -Vec3::Y));
        // On x = 1, moving along −z.
        let r = Ray::new(Vec3::new(1.0, 0.5, 2.0), Vec3::new(z, z, -1.0));
        let h = b.intersect(&r).unwrap();
        assert_eq!((h.t, h.n), (1.0, Vec3::Z));
        // Along an edge line (x = 0 and y = 1), two NaN slabs.
        let r = Ray::new(Vec3::new(0.0, 1.0, -4.0), Vec3::new(z, z, 2.0));
        assert_eq!(b.intersect(&r).map(|h| h.t), Some(2.0));
        // Just off the plane: a miss.
        let r = Ray::new(Vec3::new(-1e-7, -1.0, 0.5), Vec3::new(z, 1.0, z));
        assert!(b.intersect(&r).is_none());
    }
    assert_eq!(
        slab(Vec3::new(1.0, -3.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::ONE, 0.0, f32::INFINITY),
        Some((2.0, 4.0, 1, 1))
    );
}

#[test]
fn origin_inside_hits_the_exit() {
    let b = unit_box();
    let r = Ray::new(Vec3::new(0.5, 0.25, 0.5), Vec3::new(0.0, 0.5, 0.0));
    let h = b.intersect(&r).unwrap();
    assert_eq!((h.t, h.p, h.n), (1.5, Vec3::new(0.5, 1.0, 0.5), Vec3::Y));
    let r = Ray::new(Vec3::new(0.5, 0.25, 0.5), Vec3::new(-1.0, 0.0, 0.0));
    let h = b.intersect(&r).unwrap();
    assert_eq!((h.t, h.n), (0.5, -Vec3::X));
    // The slab reports the (negative) entry behind the origin.
    let s = slab(Vec3::ZERO, Vec3::X, Vec3::ONE, 0.0, f32::INFINITY).unwrap();
    assert_eq!(s, (-1.0, 1.0, 0, 0));
    // Segment ends before the exit: no hit.
    assert!(b.intersect(&Ray::segment(Vec3::splat(0.5), Vec3::X, 0.0, 0.25)).is_none());
    // t_min past the entry: the exit.
    let r = Ray::segment(Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 1.5, 10.0);
    assert_eq!(b.intersect(&r).map(|h| (h.t, h.n)), Some((2.0, Vec3::X)));
    // Box behind.
    assert!(b.intersect(&Ray::new(Vec3::new(2.0, 0.5, 0.5), Vec3::X)).is_none());
}

#[test]
fn huge_and_tiny_boxes_give_exact_t() {
    let huge = Cuboid::axis_aligned(Vec3::splat(-1e6), Vec3::splat(1e6)).unwrap();
    let r = Ray::new(Vec3::new(-3e6, 0.5, -0.25), Vec3::X);
    let h = huge.intersect(&r).unwrap();
    assert_eq!((h.t, h.p, h.n), (2e6, Vec3::new(-1e6, 0.5, -0.25), -Vec3::X));
    let r = Ray::new(Vec3::new(1e5, 2e5, 3e6), Vec3::new(0.0, 0.0, -0.5));
    assert_eq!(huge.intersect(&r).map(|h| (h.t, h.n)), Some((4e6, Vec3::Z)));

    let (lo, hi) = (Vec3::new(1e-6, 2e-6, 3e-6), Vec3::new(2e-6, 4e-6, 6e-6));
    let tiny = Cuboid::axis_aligned(lo, hi).unwrap();
    let o = Vec3::new(1.5e-6, 3e-6, -1e-6);
    let h = tiny.intersect(&Ray::new(o, Vec3::Z)).unwrap();
    assert_eq!(h.t, 3e-6 - (-1e-6f32)); // One correctly rounded subtraction.
    assert_eq!(h.p, Vec3::new(1.5e-6, 3e-6, 3e-6));
    assert_eq!(h.n, -Vec3::Z);
    let h = tiny.intersect(&Ray::new(Vec3::new(1.5e-6, 3e-6, 4e-6), Vec3::Z)).unwrap();
    assert_eq!((h.t, h.p.z, h.n), (6e-6 - 4e-6f32, 6e-6, Vec3::Z));
}

#[test]
fn oriented_box_rotated_45_degrees() {
    // Unit half extents rotated 45° about z: a diamond in xy with corners at ±√2 on
    // the axes, faces at distance 1 from the centre with normals (±1, ±1, 0)/√2.
    let c = Vec3::new(2.0, -1.0, 0.5);
    let b = Cuboid::oriented(c, Vec3::ONE, Quat::from_rotation_z(FRAC_PI_4)).unwrap();
    assert!(!b.is_axis_aligned());
    // Along +x through the centre, from x = c.x − 5: the ray meets the diamond's
    // vertical edge (where two faces meet) at x = c.x − √2.
    let r = Ray::new(c - Vec3::new(5.0, 0.0, 0.0), Vec3::X);
    let h = b.intersect(&r).unwrap();
    assert!((h.t - (5.0 - 2f32.sqrt())).abs() < 1e-5, "{}", h.t);
    // Off-centre at y = c.y + 0.5: the face with normal (−1, 1, 0)/√2. The face plane
    // is (p − c)·n = 1, i.e. −x + y = √2 in centred coordinates: x = 0.5 − √2.
    let r = Ray::new(c + Vec3::new(-5.0, 0.5, 0.0), Vec3::X);
    let h = b.intersect(&r).unwrap();
    let expect_t = 5.0 + 0.5 - 2f32.sqrt();
    assert!((h.t - expect_t).abs() < 1e-5, "{} vs {expect_t}", h.t);
    let n = Vec3::new(-1.0, 1.0, 0.0).normalize();
    assert!((h.n - n).length() < 1e-6, "{}", h.n);
    assert!(((h.p - c).dot(n) - 1.0).abs() < 1e-5);
    // From inside, downward: exits through the face with normal (±1, −1, 0)/√2.
    let r = Ray::new(c + Vec3::new(0.25, 0.0, 0.0), -Vec3::Y);
    let h = b.intersect(&r).unwrap();
    assert!((h.t - (2f32.sqrt() - 0.25)).abs() < 1e-5);
    assert!((h.n - Vec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-6);
    // The top face (z) is still axis-aligned.
    let r = Ray::new(c + Vec3::new(0.1, 0.2, 3.0), -Vec3::Z);
    let h = b.intersect(&r).unwrap();
    assert!((h.t - 2.0).abs() < 1e-6 && (h.n - Vec3::Z).length() < 1e-6);
    // Bounds hold the diamond: ±√2 in x and y.
    let bb = b.bounds();
    assert!((bb.max.x - c.x - 2f32.sqrt()).abs() < 1e-5 && (bb.min.z - (c.z - 1.0)).abs() < 1e-5);
}

#[test]
fn area_and_sampling() {
    let h = Vec3::new(0.5, 1.0, 2.0);
    for b in [
        Cuboid::axis_aligned(Vec3::new(1.0, 2.0, 3.0) - h, Vec3::new(1.0, 2.0, 3.0) + h).unwrap(),
        Cuboid::oriented(Vec3::new(1.0, 2.0, 3.0), h, Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1)).unwrap(),
    ] {
        let area = b.area();
        assert!((area - 8.0 * (0.5 + 2.0 + 1.0)).abs() < 1e-5);
        let bb = b.bounds();
        let mut rng = Pcg32::seed_from_u64(7);
        let n = 60_000;
        let mut counts = [0usize; 6];
        for _ in 0..n {
            let (p, nrm) = b.sample_area(Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
            assert!(p.cmpge(bb.min).all() && p.cmple(bb.max).all());
            let local = b.local_of(p - b.centre());
            let axis = (0..3).find(|&i| (nrm.dot(b.axes()[i]).abs() - 1.0).abs() < 1e-5).unwrap();
            let sign = nrm.dot(b.axes()[axis]).signum();
            // On the face plane, inside the face rectangle.
            assert!((local[axis] - sign * h[axis]).abs() < 1e-5, "{local} {nrm}");
            assert!((local.abs() - h).max_element() < 1e-5);
            counts[2 * axis + usize::from(sign > 0.0)] += 1;
        }
        for (f, &count) in counts.iter().enumerate() {
            let a = 4.0 * h[(f / 2 + 1) % 3] * h[(f / 2 + 2) % 3];
            let p = (a / area) as f64;
            let mean = n as f64 * p;
            let sigma = (n as f64 * p * (1.0 - p)).sqrt();
            assert!((count as f64 - mean).abs() < 3.0 * sigma, "face {f}: {count} vs {mean} ± {sigma}");
        }
    }
}

#[test]
fn bounds_and_the_axis_aligned_box_agree_with_aabb_hit() {
    let b = Cuboid::axis_aligned(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 0.5, 3.0)).unwrap();
    let aabb = b.bounds();
    let mut rng = Pcg32::seed_from_u64(99);
    for _ in 0..1000 {
        let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 8.0 - 4.0;
        let d = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let r = Ray::new(o, d);
        let mine = b.intersect(&r).map(|h| h.t);
        let theirs = aabb.hit(&r, r.t_max);
        // Aabb::hit returns the clamped entry (t_min when inside); compare hit/miss.
        assert_eq!(mine.is_some(), theirs.is_some(), "{o} {d}");
    }
}
