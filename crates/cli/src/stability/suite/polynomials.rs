//! The polynomials family: closed forms against Laguerre's method (polished or not) on
//! implicit surfaces (a torus, tangent rays, the sextic heart) and on random polynomials
//! with known, exactly representable roots.

use super::{Row, Scale, row, slab_reference, timed};
use glam::{DVec3, Vec3};
use rng::Pcg32;
use shapes::implicit::{Implicit, Poly3};
use shapes::roots::{RootSolver, real_roots_in};
use shapes::{Aabb, Ray};

/// Relative tolerance on the hit parameter for the surfaces of [`polynomials`].
pub const POLY_T_TOL: f64 = 1e-6;

/// Roots of the random polynomials of [`polynomials`] must be found within this many
/// times their perturbation bound δ (see there).
pub const POLY_ROOT_TOL_FACTOR: f64 = 100.0;

/// What the reference says about a ray and an implicit surface.
#[derive(Clone, Copy, Debug, PartialEq)]
enum SurfaceRef {
    Hit(f64),
    Miss,
    /// Grazes the surface so closely that a hit and a miss are both right.
    Ambiguous,
}

/// Samples F along the clipped ray and returns the first crossing, refined by bisection.
fn surface_reference(poly: &Poly3, bounds: Aabb, ray: &Ray, samples: usize) -> SurfaceRef {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
    let diag = (hi - lo).length();
    let pad = DVec3::splat(1e-6 * diag);
    let Some((entry, exit)) = slab_reference(o, d, lo - pad, hi + pad) else { return SurfaceRef::Miss };
    let (t0, t1) = (entry.max(0.0), exit);
    if t0.is_nan() || t1.is_nan() || t0 >= t1 {
        return SurfaceRef::Miss;
    }
    let f = |t: f64| poly.eval(o + t * d);
    let bisect = |mut a: f64, mut b: f64| {
        let fa = f(a);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            if (f(m) > 0.0) == (fa > 0.0) {
                a = m;
            } else {
                b = m;
            }
        }
        0.5 * (a + b)
    };
    let ts: Vec<f64> = (0..=samples).map(|k| t0 + (t1 - t0) * k as f64 / samples as f64).collect();
    let fs: Vec<f64> = ts.iter().map(|&t| f(t)).collect();
    // A grazing miss closer than this (in distance from the surface) is ambiguous.
    let graze = 1e-7 * diag;
    for k in 0..samples {
        if k > 0 {
            let (a, m, b) = (fs[k - 1], fs[k], fs[k + 1]);
            let same = (a > 0.0) == (m > 0.0) && (m > 0.0) == (b > 0.0);
            if same && m.abs() <= a.abs() && m.abs() <= b.abs() {
                // A dip towards zero: golden-section search for the minimum of |F|.
                let s = m.signum();
                let (mut x0, mut x1) = (ts[k - 1], ts[k + 1]);
                let g = 0.5 * (5f64.sqrt() - 1.0);
                for _ in 0..100 {
                    let (xa, xb) = (x1 - g * (x1 - x0), x0 + g * (x1 - x0));
                    if s * f(xa) < s * f(xb) {
                        x1 = xb;
                    } else {
                        x0 = xa;
                    }
                }
                let tm = 0.5 * (x0 + x1);
                let fm = f(tm);
                if s * fm <= 0.0 {
                    return SurfaceRef::Hit(bisect(ts[k - 1], tm));
                }
                let grad = poly.gradient(o + tm * d).length();
                if fm.abs() <= graze * grad {
                    return SurfaceRef::Ambiguous;
                }
            }
        }
        if (fs[k] > 0.0) != (fs[k + 1] > 0.0) {
            return SurfaceRef::Hit(bisect(ts[k], ts[k + 1]));
        }
    }
    SurfaceRef::Miss
}

/// The roots' numerators k (roots k/2⁸), expanded exactly.
const ROOT_DENOM_LOG2: u32 = 8;

/// ∏(2⁸·t − kᵢ)/2⁸ⁿ: the monic polynomial with roots kᵢ/256, expanded exactly in i128
/// (|kᵢ| ≤ 768 and n ≤ 12 keep every coefficient below 2¹²⁰) and then rounded once per
/// coefficient to f64 — the smallest perturbation any f64 representation has.
fn poly_from_roots(ks: &[i64]) -> Vec<f64> {
    let mut c: Vec<i128> = vec![1];
    let d = 1i128 << ROOT_DENOM_LOG2;
    for &k in ks {
        let mut next = vec![0i128; c.len() + 1];
        for (j, &cj) in c.iter().enumerate() {
            next[j + 1] += d * cj;
            next[j] -= k as i128 * cj;
        }
        c = next;
    }
    let scale = 2f64.powi(-((ROOT_DENOM_LOG2 as usize * ks.len()) as i32));
    c.iter().map(|&x| x as f64 * scale).collect()
}

/// (root, tolerance) per distinct root of the polynomial with roots kᵢ/256: the
/// perturbation bound δ = (u·S(r)/|q(r)|)^(1/m) for a root r of multiplicity m, with
/// u = 2⁻⁵³, S(r) = Σ|cⱼ||r|ʲ and q(r) = p⁽ᵐ⁾(r)/m! the product over the other roots
/// (rounding the coefficients by u relative moves the root by about δ), times
/// [`POLY_ROOT_TOL_FACTOR`], and at least 10⁻¹²·max(1, |r|).
fn root_tolerances(ks: &[i64], c: &[f64]) -> Vec<(f64, f64)> {
    let mut distinct: Vec<i64> = ks.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    let scale = (1u64 << ROOT_DENOM_LOG2) as f64;
    distinct
        .iter()
        .map(|&k| {
            let r = k as f64 / scale;
            let m = ks.iter().filter(|&&x| x == k).count() as f64;
            let q: f64 = ks.iter().filter(|&&x| x != k).map(|&x| r - x as f64 / scale).product();
            let s: f64 = c.iter().enumerate().map(|(j, cj)| cj.abs() * r.abs().powi(j as i32)).sum();
            let delta = (f64::EPSILON / 2.0 * s / q.abs()).powf(1.0 / m);
            (r, (POLY_ROOT_TOL_FACTOR * delta).max(1e-12 * r.abs().max(1.0)))
        })
        .collect()
}

/// Numerators for `count` well-separated roots in [−3, 3] (gaps ≥ 64/256 = 0.25).
fn separated_roots(rng: &mut Pcg32, count: usize) -> Vec<i64> {
    let width = 1536 / count as i64;
    (0..count as i64).map(|i| -768 + i * width + rng.below((width - 64) as u64) as i64).collect()
}

/// Root numerators: `others` separated roots with one of them replaced by a cluster of
/// `size` roots spaced `gap`/256 apart.
fn clustered_roots(rng: &mut Pcg32, others: usize, size: usize, gap: i64) -> Vec<i64> {
    let mut ks = separated_roots(rng, others);
    let i = rng.below(others as u64) as usize;
    let k0 = ks.remove(i);
    ks.extend((0..size as i64).map(|j| k0 + j * gap));
    ks
}

/// Implicit surfaces and random polynomials: the closed forms ([`RootSolver::ClosedForm`],
/// [`shapes::roots::cubic`]/[`shapes::roots::quartic`]) against Laguerre's method with and
/// without polishing ([`RootSolver::Laguerre`]).
///
/// Surface cases (one test = one ray through [`Implicit::intersect_report`], timed per
/// ray): a torus R = 1, r = 0.25 hit by generic rays; the same torus hit by **tangent**
/// rays — rays in its top/bottom tangent plane z = ±r (along which F = (ρ² − R²)², a
/// double root where the ray crosses the circle ρ = R) and rays through its outermost
/// point (R + r, 0, 0) inside the tangent plane x = R + r (a touching double root),
/// built from dyadic numbers so that the f32 ray is exactly tangent; and the degree-6
/// heart surface, where the closed-form solver falls back to Laguerre (its row says so).
/// Reference for generic rays: F sampled densely (256 steps over the clipped ray) in f64
/// with [`Poly3::eval`], the first sign change refined by bisection; dips of F towards
/// zero between samples are searched (golden section) for a hidden pair of roots, and a
/// miss closer than 10⁻⁷ of the box diagonal to the surface is ambiguous and skipped. For
/// tangent rays the reference is the analytic tangent parameter of the construction.
/// **Failure**: hit/miss wrong, or |t − t_ref| > [`POLY_T_TOL`]·t_ref.
///
/// Polynomial cases (one test = one polynomial through [`real_roots_in`] on [−4, 4],
/// timed per polynomial): a quartic with a double root (closed form against Laguerre),
/// and degree 8 and 12 with well separated roots and with a cluster of 3 (degree 8,
/// spacing 2–6/256) or 4 (degree 12, spacing 8–16/256) roots (Laguerre only: the closed
/// form does not exist there). Roots are dyadic k/256, the coefficients expanded exactly
/// and rounded once; each root r of multiplicity m gets the tolerance
/// [`POLY_ROOT_TOL_FACTOR`]·δ with δ = (u·Σ|cⱼ||r|ʲ / |q(r)|)^(1/m), the distance that
/// rounding the coefficients alone can move it (u = 2⁻⁵³, q the product over the other
/// roots; floor 10⁻¹²·max(1, |r|)). **Failure**: a root not found within its tolerance,
/// or a reported real root within no root's tolerance.
///
/// `not_converged` counts tests in which some Laguerre search hit its iteration limit
/// ([`shapes::roots::SolveReport::not_converged`] > 0).
pub fn polynomials(scale: Scale) -> Vec<Row> {
    let mut rng = Pcg32::seed_from_u64(0x5EED_0002);
    let mut rows = Vec::new();
    let solvers = [
        ("closed-form", RootSolver::ClosedForm),
        ("laguerre-polished", RootSolver::Laguerre { polish: true }),
        ("laguerre-unpolished", RootSolver::Laguerre { polish: false }),
    ];
    let (major, minor) = (1.0f32, 0.25f32);

    // Surfaces: (case, is the heart, rays, references).
    let mut surface_cases: Vec<(&str, bool, Vec<Ray>, Vec<SurfaceRef>)> = Vec::new();
    let torus = Implicit::torus(major, minor, RootSolver::ClosedForm).expect("valid torus");
    let n = scale.n(150);
    let rays: Vec<Ray> = (0..n)
        .map(|_| {
            let o = rng.unit_vector() * rng.range(2.5, 4.0);
            let (rho, phi) = (rng.range(0.6, 1.4), rng.range(0.0, std::f64::consts::TAU));
            let target = DVec3::new(rho * phi.cos(), rho * phi.sin(), rng.range(-0.35, 0.35));
            Ray::new(o.as_vec3(), (target - o).as_vec3())
        })
        .collect();
    let refs = rays.iter().map(|r| surface_reference(&torus.poly, torus.bounds, r, 256)).collect();
    surface_cases.push(("torus generic", false, rays, refs));

    // Tangent plane z = ±r: F = (ρ² − R²)² along the ray; the first crossing of ρ = R.
    let (mut rays, mut refs) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let z = if rng.coin() { minor } else { -minor };
        let phi = rng.range(0.0, std::f64::consts::TAU);
        let o = Vec3::new((3.0 * phi.cos()) as f32, (3.0 * phi.sin()) as f32, z);
        let (rho, psi) = (rng.range(0.0, 0.8), rng.range(0.0, std::f64::consts::TAU));
        let target = Vec3::new((rho * psi.cos()) as f32, (rho * psi.sin()) as f32, z);
        let d = Vec3::new(target.x - o.x, target.y - o.y, 0.0);
        let (o2, d2) = (o.truncate().as_dvec2(), d.truncate().as_dvec2());
        let (t_near, _) = shapes::roots::quadratic_f64(d2.dot(d2), 2.0 * o2.dot(d2), o2.dot(o2) - 1.0)
            .expect("the ray crosses the circle ρ = R");
        rays.push(Ray::new(o, d));
        refs.push(SurfaceRef::Hit(t_near));
    }
    // Through the outermost point P in the tangent plane there: o = P − 4·d exactly.
    for _ in 0..n {
        let along = rng.below(4);
        let a = (rng.below(17) as f32 - 8.0) / 8.0;
        let b = (rng.below(7) as f32 + 2.0) / 8.0 * if rng.coin() { 1.0 } else { -1.0 };
        let (p, d) = match along {
            0 => (Vec3::new(major + minor, 0.0, 0.0), Vec3::new(0.0, a, b)),
            1 => (Vec3::new(-(major + minor), 0.0, 0.0), Vec3::new(0.0, a, b)),
            2 => (Vec3::new(0.0, major + minor, 0.0), Vec3::new(a, 0.0, b)),
            _ => (Vec3::new(0.0, -(major + minor), 0.0), Vec3::new(a, 0.0, b)),
        };
        rays.push(Ray::new(p - 4.0 * d, d));
        refs.push(SurfaceRef::Hit(4.0));
    }
    surface_cases.push(("torus tangent (double roots)", false, rays, refs));

    let heart = Implicit::heart(RootSolver::ClosedForm).expect("valid heart");
    let centre = DVec3::new(0.0, 0.0, 0.1);
    let rays: Vec<Ray> = (0..n)
        .map(|_| {
            let o = centre + rng.unit_vector() * 3.0;
            let target = DVec3::new(rng.range(-0.9, 0.9), rng.range(-0.5, 0.5), rng.range(-0.8, 1.0));
            Ray::new(o.as_vec3(), (target - o).as_vec3())
        })
        .collect();
    let refs = rays.iter().map(|r| surface_reference(&heart.poly, heart.bounds, r, 256)).collect();
    surface_cases.push(("heart (degree 6)", true, rays, refs));

    for (case, is_heart, rays, refs) in &surface_cases {
        for (name, solver) in solvers {
            let shape = if *is_heart {
                Implicit::heart(solver).expect("valid heart")
            } else {
                Implicit::torus(major, minor, solver).expect("valid torus")
            };
            let (res, ns) = timed(scale, rays, |ray| {
                let (hit, report) = shape.intersect_report(ray);
                (hit.map(|h| h.t), report.not_converged)
            });
            let (mut tests, mut failures, mut nc) = (0, 0, 0);
            for ((t, not_conv), reference) in res.iter().zip(refs) {
                let ok = match (reference, t) {
                    (SurfaceRef::Ambiguous, _) => continue,
                    (SurfaceRef::Miss, None) => true,
                    (SurfaceRef::Hit(tr), Some(t)) => (*t as f64 - tr).abs() <= POLY_T_TOL * tr,
                    _ => false,
                };
                tests += 1;
                failures += u64::from(!ok);
                nc += u64::from(*not_conv > 0);
            }
            let method = if *is_heart && solver == RootSolver::ClosedForm {
                "closed-form (falls back to laguerre)"
            } else {
                name
            };
            rows.push(row("polynomials", method, case, tests, failures, nc, ns));
        }
    }

    // Random polynomials with known roots.
    let np = scale.n(150);
    let mut poly_cases: Vec<(&str, Vec<Vec<i64>>)> = Vec::new();
    let quartics = (0..np)
        .map(|_| {
            let mut ks = separated_roots(&mut rng, 3);
            let i = rng.below(3) as usize;
            ks.push(ks[i]);
            ks
        })
        .collect();
    poly_cases.push(("degree 4, a double root", quartics));
    let fourfold = (0..np)
        .map(|_| {
            // Multiples of 32/256 = 1/8: coefficients below 2⁴⁰·2⁻²⁴, exact in f64.
            let mut ks: Vec<i64> = separated_roots(&mut rng, 5).iter().map(|k| k.div_euclid(32) * 32).collect();
            let i = rng.below(5) as usize;
            ks.extend([ks[i]; 3]);
            ks
        })
        .collect();
    poly_cases.push(("degree 8, a 4-fold root", fourfold));
    poly_cases.push(("degree 8 separated", (0..np).map(|_| separated_roots(&mut rng, 8)).collect()));
    let clustered = (0..np)
        .map(|_| {
            let gap = 2 + rng.below(5) as i64;
            clustered_roots(&mut rng, 6, 3, gap)
        })
        .collect();
    poly_cases.push(("degree 8 cluster of 3", clustered));
    poly_cases.push(("degree 12 separated", (0..np).map(|_| separated_roots(&mut rng, 12)).collect()));
    let clustered = (0..np)
        .map(|_| {
            let gap = 8 + rng.below(9) as i64;
            clustered_roots(&mut rng, 9, 4, gap)
        })
        .collect();
    poly_cases.push(("degree 12 cluster of 4", clustered));

    for (case, sets) in &poly_cases {
        let polys: Vec<Vec<f64>> = sets.iter().map(|ks| poly_from_roots(ks)).collect();
        let tols: Vec<Vec<(f64, f64)>> = sets.iter().zip(&polys).map(|(ks, c)| root_tolerances(ks, c)).collect();
        for (name, solver) in solvers {
            if solver == RootSolver::ClosedForm && polys[0].len() > 5 {
                continue;
            }
            let mut out = Vec::new();
            let (res, ns) = timed(scale, &polys, |c| {
                let report = real_roots_in(c, -4.0, 4.0, solver, &mut out);
                (out.clone(), report.not_converged)
            });
            let (mut failures, mut nc) = (0, 0);
            for ((found, not_conv), tol) in res.iter().zip(&tols) {
                let all_found = tol.iter().all(|&(r, e)| found.iter().any(|&x| (x - r).abs() <= e));
                let no_spurious = found.iter().all(|&x| tol.iter().any(|&(r, e)| (x - r).abs() <= e));
                failures += u64::from(!(all_found && no_spurious));
                nc += u64::from(*not_conv > 0);
            }
            rows.push(row("polynomials", name, case, polys.len() as u64, failures, nc, ns));
        }
    }
    rows
}
