//! The slabs family: the slab test of `shapes::boxes`, the bvh crate's `Aabb::hit` and
//! the textbook version on ±0 direction components, origins on slab planes and boxes
//! from 10⁻⁶ to 10⁶.

use super::{Row, Scale, row, slab_reference, timed, ulp32};
use glam::{DVec3, Vec3};
use rng::Pcg32;
use shapes::boxes::slab;
use shapes::{Aabb, Ray};

/// Tolerance on the entry parameter for [`slabs`], in f32 ulps of the reference.
pub const SLAB_ULPS: f64 = 4.0;

/// The slab test: [`slab`] (unclamped entry/exit, open interval (t_min, t_max)),
/// [`Aabb::hit`] (the bvh crate's; entry clamped to t_min, closed at both ends) and, as
/// the baseline, the textbook version without a guard for 0/0 (`textbook_slab`: divide
/// by the direction, `f32::min`/`max`, same contract as [`Aabb::hit`]).
///
/// The box is [−h, h] with h = s·(1, ½, 2). Cases: directions with one or two components
/// exactly +0 or −0 (origins inside or outside those slabs, and on their planes); origins
/// exactly on a slab plane (one or two coordinates = ±hᵢ), moving along any direction
/// including ±0 components; general rays at box scales s = 10⁻⁶, 1, 10⁶ (a quarter of
/// them with a ±0 component). Directions' non-zero components are at least 0.05 in
/// magnitude (subnormal components, which f32 treats as parallel while the exact
/// reference does not, are not among the cases).
///
/// Reference: entry/exit per plane in f64 from the f32 inputs (the differences are exact,
/// one rounding in the division), zero components handled exactly; the expected result
/// follows each method's contract: [`slab`] hits iff entry ≤ exit, exit > 0 and
/// entry < ∞, returning the entry; [`Aabb::hit`] and the textbook test hit iff
/// max(0, entry) ≤ exit, returning max(0, entry). **Failure**: wrong hit/miss, or the returned entry off by
/// more than [`SLAB_ULPS`] f32 ulps of the reference (three correctly rounded f32
/// operations give at most about 1.5). Rays whose entry and exit differ by less than
/// 8 ulps without being equal graze an edge within rounding and are skipped. One test =
/// one ray–box test.
pub fn slabs(scale: Scale) -> Vec<Row> {
    let mut rng = Pcg32::seed_from_u64(0x5EED_0004);
    let n = scale.n(1000);
    let mut rows = Vec::new();
    let signed_zero = |rng: &mut Pcg32| if rng.coin() { 0.0f32 } else { -0.0 };
    let component = |rng: &mut Pcg32| (rng.range(0.05, 1.0) * if rng.coin() { 1.0 } else { -1.0 }) as f32;

    let mut cases: Vec<(String, f64, Vec<Ray>)> = Vec::new();
    // Rays aimed at a target in the box grown by 30 %, `zeros` direction components
    // forced to ±0, the origin 1 to 4 box sizes back.
    let aimed = |rng: &mut Pcg32, s: f64, zeros: usize| {
        let h = DVec3::new(1.0, 0.5, 2.0) * s;
        let target = DVec3::new(rng.range(-1.3, 1.3), rng.range(-1.3, 1.3), rng.range(-1.3, 1.3)) * h;
        let mut d = Vec3::new(component(rng), component(rng), component(rng));
        let first = rng.below(3) as usize;
        for z in 0..zeros {
            d[(first + z) % 3] = signed_zero(rng);
        }
        let back = rng.range(1.0, 4.0) * 2.0 * s;
        let o = target - d.as_dvec3() * back;
        Ray::new(o.as_vec3(), d)
    };
    let rays = (0..n).map(|i| aimed(&mut rng, 1.0, 1 + i % 2)).collect();
    cases.push(("axis-parallel +-0".into(), 1.0, rays));
    let rays = (0..n)
        .map(|i| {
            let mut ray = aimed(&mut rng, 1.0, i % 3);
            let h = Vec3::new(1.0, 0.5, 2.0);
            let first = rng.below(3) as usize;
            for k in 0..1 + i % 2 {
                let a = (first + k) % 3;
                ray.origin[a] = if rng.coin() { h[a] } else { -h[a] };
            }
            Ray::new(ray.origin, ray.dir)
        })
        .collect();
    cases.push(("origin on slab plane".into(), 1.0, rays));
    for (label, s) in [("1e-6", 1e-6), ("1", 1.0), ("1e6", 1e6)] {
        let rays = (0..n).map(|i| aimed(&mut rng, s, usize::from(i % 4 == 0))).collect();
        cases.push((format!("scale {label}"), s, rays));
    }

    for (case, s, rays) in &cases {
        let half = (DVec3::new(1.0, 0.5, 2.0) * *s).as_vec3();
        let aabb = Aabb { min: -half, max: half };
        let (lo, hi) = (aabb.min.as_dvec3(), aabb.max.as_dvec3());
        let refs: Vec<Option<(f64, f64)>> =
            rays.iter().map(|r| slab_reference(r.origin.as_dvec3(), r.dir.as_dvec3(), lo, hi)).collect();
        let ambiguous = |r: &Option<(f64, f64)>| match *r {
            Some((a, b)) if a.is_finite() && b.is_finite() => a != b && b - a <= 8.0 * ulp32(a.abs().max(b.abs())),
            _ => false,
        };
        let close = |t: f32, tr: f64| (t as f64 - tr).abs() <= SLAB_ULPS * ulp32(tr);

        // (tests, failures) of entry distances `got` against the references, where
        // `expect` turns a reference (entry, exit) into the entry the method should report.
        let score = |got: &[Option<f32>], expect: &dyn Fn((f64, f64)) -> Option<f64>| {
            let (mut tests, mut failures) = (0, 0);
            for (got, r) in got.iter().zip(&refs) {
                if ambiguous(r) {
                    continue;
                }
                tests += 1;
                let ok = match (got, r.and_then(expect)) {
                    (None, None) => true,
                    (Some(t), Some(tr)) => close(*t, tr),
                    _ => false,
                };
                failures += u64::from(!ok);
            }
            (tests, failures)
        };
        // `slab` reports the unclamped entry of a box the ray meets ahead; the others
        // the entry clamped to t_min = 0.
        let unclamped = |(a, b): (f64, f64)| (b > 0.0 && a < f64::INFINITY).then_some(a);
        let clamped = |(a, b): (f64, f64)| (a.max(0.0) <= b).then_some(a.max(0.0));

        let (res, ns) = timed(scale, rays, |r| slab(r.origin, r.dir, half, r.t_min, r.t_max).map(|h| h.0));
        let (tests, failures) = score(&res, &unclamped);
        rows.push(row("slabs", "boxes::slab", case, tests, failures, 0, ns));
        let (res, ns) = timed(scale, rays, |r| aabb.hit(r, f32::INFINITY));
        let (tests, failures) = score(&res, &clamped);
        rows.push(row("slabs", "Aabb::hit", case, tests, failures, 0, ns));
        let (res, ns) = timed(scale, rays, |r| textbook_slab(r, half));
        let (tests, failures) = score(&res, &clamped);
        rows.push(row("slabs", "textbook (divide, no NaN guard)", case, tests, failures, 0, ns));
    }
    rows
}

/// The slab test as often written: (plane − o)/d per axis, `f32::min`/`max`, entry clamped
/// to 0 and closed at both ends like [`Aabb::hit`]. An origin on a plane with a ±0
/// direction component gives 0/0 = NaN, which `min`/`max` silently drop — the baseline
/// that shows what [`slab`]'s explicit guard is for.
fn textbook_slab(ray: &Ray, half: Vec3) -> Option<f32> {
    let (mut entry, mut exit) = (0.0f32, f32::INFINITY);
    for i in 0..3 {
        let t0 = (-half[i] - ray.origin[i]) / ray.dir[i];
        let t1 = (half[i] - ray.origin[i]) / ray.dir[i];
        entry = entry.max(t0.min(t1));
        exit = exit.min(t0.max(t1));
    }
    (entry <= exit).then_some(entry)
}
