use super::*;
use proptest::prelude::*;
use rng::Pcg32;

/// Ascending coefficients of lead·Π(t − rᵢ).
fn poly_from_roots(roots: &[f64], lead: f64) -> Vec<f64> {
    let mut c = vec![lead];
    for &r in roots {
        c = mul(&c, &[-r, 1.0]);
    }
    c
}

fn mul(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

/// Multiplies by (t − z)(t − z̄) = t² − 2 Re z·t + |z|².
fn times_pair(c: &[f64], z: Complex) -> Vec<f64> {
    mul(c, &[z.re * z.re + z.im * z.im, -2.0 * z.re, 1.0])
}

fn rel_err(x: f64, truth: f64) -> f64 {
    (x - truth).abs() / truth.abs().max(1e-300)
}

/// Greedy matching: for each expected root the nearest unused computed root; the
/// largest distance relative to max(1, |expected|).
fn match_roots(expected: &[Complex], got: &[Complex]) -> f64 {
    assert_eq!(expected.len(), got.len(), "root count: expected {expected:?}, got {got:?}");
    let mut used = vec![false; got.len()];
    let mut worst = 0.0f64;
    for e in expected {
        let (k, d) = got
            .iter()
            .enumerate()
            .filter(|(k, _)| !used[*k])
            .map(|(k, g)| (k, (*g - *e).abs()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        used[k] = true;
        worst = worst.max(d / e.abs().max(1.0));
    }
    worst
}

fn min_separation(roots: &[f64]) -> f64 {
    let mut s = roots.to_vec();
    s.sort_by(f64::total_cmp);
    s.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min)
}

#[test]
fn quadratic_known_roots() {
    // (t − 2)(t + 3) = t² + t − 6, and scaled by −2.
    assert_eq!(quadratic_naive(1.0, 1.0, -6.0), Some((-3.0, 2.0)));
    assert_eq!(quadratic_stable(1.0, 1.0, -6.0), Some((-3.0, 2.0)));
    assert_eq!(quadratic_f64(-2.0, -2.0, 12.0), Some((-3.0, 2.0)));
    assert_eq!(quadratic_stable(-2.0, -2.0, 12.0), Some((-3.0, 2.0)));
    assert_eq!(quadratic_naive(1.0, 0.0, 1.0), None);
    assert_eq!(quadratic_stable(1.0, 0.0, 1.0), None);
    assert_eq!(quadratic_f64(1.0, 2.0, 5.0), None);
}

#[test]
fn quadratic_degenerate_coefficients() {
    // a = 0: linear 2t − 4 = 0.
    assert_eq!(quadratic_naive(0.0, 2.0, -4.0), Some((2.0, 2.0)));
    assert_eq!(quadratic_stable(0.0, 2.0, -4.0), Some((2.0, 2.0)));
    assert_eq!(quadratic_f64(0.0, 2.0, -4.0), Some((2.0, 2.0)));
    // a = b = 0: no root (or every t); None.
    assert_eq!(quadratic_naive(0.0, 0.0, 1.0), None);
    assert_eq!(quadratic_stable(0.0, 0.0, 1.0), None);
    assert_eq!(quadratic_stable(0.0, 0.0, 0.0), None);
    // b = 0: ±√(−c/a).
    assert_eq!(quadratic_stable(1.0, 0.0, -4.0), Some((-2.0, 2.0)));
    assert_eq!(quadratic_f64(2.0, 0.0, -8.0), Some((-2.0, 2.0)));
    // c = 0: 0 and −b/a, sorted, no NaN.
    assert_eq!(quadratic_stable(1.0, 3.0, 0.0), Some((-3.0, 0.0)));
    assert_eq!(quadratic_stable(1.0, -3.0, 0.0), Some((0.0, 3.0)));
    // b = c = 0: the double root 0.
    assert_eq!(quadratic_stable(5.0, 0.0, 0.0), Some((0.0, 0.0)));
    assert_eq!(quadratic_f64(f64::NAN, 1.0, 1.0), None);
}

#[test]
fn quadratic_discriminant_zero() {
    // (t − 3)² = t² − 6t + 9: a double root, reported twice.
    assert_eq!(quadratic_naive(1.0, -6.0, 9.0), Some((3.0, 3.0)));
    assert_eq!(quadratic_stable(1.0, -6.0, 9.0), Some((3.0, 3.0)));
    assert_eq!(quadratic_f64(4.0, 4.0, 1.0), Some((-0.5, -0.5)));
}

#[test]
fn quadratic_catastrophic_cancellation() {
    // t² + 1e4·t + 1 = 0: roots −1.00000001e-4 and −9999.9999.
    let (a, b, c) = (1.0f32, 1e4f32, 1.0f32);
    let small_true = -2.0 / (1e4 + (1e8f64 - 4.0).sqrt()); // = 2c / (−b − √disc), exact enough
    let large_true = -(1e4 + (1e8f64 - 4.0).sqrt()) / 2.0;
    let (n_small, n_large) = (quadratic_naive(a, b, c).unwrap().1, quadratic_naive(a, b, c).unwrap().0);
    let (s_small, s_large) = (quadratic_stable(a, b, c).unwrap().1, quadratic_stable(a, b, c).unwrap().0);
    let naive_err = rel_err(n_small as f64, small_true);
    let stable_err = rel_err(s_small as f64, small_true);
    println!(
        "small root {small_true:e}: naive {n_small:e} (rel err {naive_err:e}), \
         stable {s_small:e} (rel err {stable_err:e})"
    );
    assert!(stable_err < 1e-6, "stable small root error {stable_err}");
    assert!(naive_err > 0.1, "naive small root should lose its digits, error {naive_err}");
    assert!(rel_err(s_large as f64, large_true) < 1e-6);
    assert!(rel_err(n_large as f64, large_true) < 1e-6, "the large root is fine either way");
    // In f64 the same happens at b = 1e9.
    let (s, _) = quadratic_f64(1.0, 1e9, 1.0).map(|(l, s)| (s, l)).unwrap();
    assert!(rel_err(s, -1e-9) < 1e-15, "{s:e}");
}

#[test]
fn eval_poly_and_derivative() {
    // 1 − 2t + 3t²: P(2) = 9, P′(2) = −2 + 12 = 10.
    let c = [1.0, -2.0, 3.0];
    assert_eq!(eval_poly(&c, 2.0), 9.0);
    assert_eq!(eval_poly_deriv(&c, 2.0), (9.0, 10.0));
    assert_eq!(eval_poly(&[], 2.0), 0.0);
    assert_eq!(eval_poly_deriv(&[7.0], 2.0), (7.0, 0.0));
}

#[test]
fn complex_arithmetic() {
    let z = Complex::new(3.0, 4.0);
    assert_eq!(z.abs(), 5.0);
    assert_eq!(Complex::real(-4.0).sqrt(), Complex::new(0.0, 2.0));
    let s = Complex::new(-3.0, -4.0).sqrt(); // ±(1 − 2i), principal has re ≥ 0
    assert!((s - Complex::new(1.0, -2.0)).abs() < 1e-15, "{s:?}");
    assert!((s * s - Complex::new(-3.0, -4.0)).abs() < 1e-14);
    let w = Complex::new(-1.5, 0.25);
    assert!(((z * w) / w - z).abs() < 1e-14);
    assert!(((z / w) * w - z).abs() < 1e-14);
    assert_eq!(z + w - w, z);
    assert_eq!(-z, Complex::new(-3.0, -4.0));
    assert_eq!(z.conj(), Complex::new(3.0, -4.0));
    // No overflow in |z| or √z for huge parts.
    let big = Complex::new(1e300, 1e300);
    assert!(big.abs().is_finite() && big.sqrt().is_finite());
}

#[test]
fn cubic_random_polynomials_with_known_roots() {
    let mut rng = Pcg32::seed_from_u64(1);
    let mut worst = 0.0f64;
    let mut tested = 0;
    while tested < 500 {
        let roots: Vec<f64> = (0..3).map(|_| rng.range(-10.0, 10.0)).collect();
        if min_separation(&roots) < 0.1 {
            continue;
        }
        let lead = rng.range(0.1, 10.0) * if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
        let c = poly_from_roots(&roots, lead);
        let got = cubic([c[0], c[1], c[2], c[3]]);
        let mut want = roots.clone();
        want.sort_by(f64::total_cmp);
        assert_eq!(got.len(), 3, "roots {want:?} got {got:?}");
        for (g, w) in got.as_slice().iter().zip(&want) {
            worst = worst.max((g - w).abs() / w.abs().max(1.0));
        }
        tested += 1;
    }
    println!("cubic: worst relative root error over 500 polynomials {worst:e}");
    assert!(worst < 1e-9, "{worst}");
}

#[test]
fn cubic_special_cases() {
    // One real root and a complex pair: (t − 1)(t² + 1).
    let r = cubic([-1.0, 1.0, -1.0, 1.0]);
    assert_eq!(r.len(), 1);
    assert!((r.as_slice()[0] - 1.0).abs() < 1e-14);
    // Double root (t − 1)²(t + 2) = t³ − 3t + 2: reported twice.
    let r = cubic([2.0, -3.0, 0.0, 1.0]);
    assert_eq!(r.len(), 3, "{r:?}");
    let s = r.as_slice();
    assert!((s[0] + 2.0).abs() < 1e-12 && (s[1] - 1.0).abs() < 1e-7 && (s[2] - 1.0).abs() < 1e-7, "{s:?}");
    // A double root from rounded coefficients: (t − 0.3)²(t − 2).
    let c = poly_from_roots(&[0.3, 0.3, 2.0], 1.0);
    let r = cubic([c[0], c[1], c[2], c[3]]);
    assert_eq!(r.len(), 3, "{r:?}");
    assert!((r.as_slice()[0] - 0.3).abs() < 1e-7 && (r.as_slice()[1] - 0.3).abs() < 1e-7, "{r:?}");
    // Triple root (t − 1)³.
    let r = cubic([-1.0, 3.0, -3.0, 1.0]);
    assert_eq!(r.len(), 3);
    assert!(r.as_slice().iter().all(|x| (x - 1.0).abs() < 1e-5), "{r:?}");
    // Degenerate leading coefficient: the quadratic t² + t − 6.
    let r = cubic([-6.0, 1.0, 1.0, 0.0]);
    assert_eq!(r.as_slice(), &[-3.0, 2.0]);
    let r = cubic([-6.0, 1.0, 1.0, 1e-20]);
    assert_eq!(r.len(), 2);
    assert!((r.as_slice()[0] + 3.0).abs() < 1e-12 && (r.as_slice()[1] - 2.0).abs() < 1e-12);
    // Linear and constant.
    assert_eq!(cubic([-6.0, 3.0, 0.0, 0.0]).as_slice(), &[2.0]);
    assert!(cubic([1.0, 0.0, 0.0, 0.0]).is_empty());
    assert!(cubic([0.0; 4]).is_empty());
    // A root at zero and a tiny root next to big ones.
    let c = poly_from_roots(&[0.0, 1e-6, 1e3], 1.0);
    let r = cubic([c[0], c[1], c[2], c[3]]);
    assert_eq!(r.len(), 3);
    assert!(r.as_slice()[0].abs() < 1e-18 && rel_err(r.as_slice()[1], 1e-6) < 1e-9, "{r:?}");
}

#[test]
fn quartic_random_polynomials_with_known_roots() {
    let mut rng = Pcg32::seed_from_u64(2);
    let mut worst = 0.0f64;
    let mut tested = 0;
    while tested < 500 {
        let roots: Vec<f64> = (0..4).map(|_| rng.range(-10.0, 10.0)).collect();
        if min_separation(&roots) < 0.1 {
            continue;
        }
        let lead = rng.range(0.1, 10.0) * if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
        let c = poly_from_roots(&roots, lead);
        let got = quartic([c[0], c[1], c[2], c[3], c[4]]);
        let mut want = roots.clone();
        want.sort_by(f64::total_cmp);
        assert_eq!(got.len(), 4, "roots {want:?} got {got:?}");
        for (g, w) in got.as_slice().iter().zip(&want) {
            worst = worst.max((g - w).abs() / w.abs().max(1.0));
        }
        tested += 1;
    }
    println!("quartic: worst relative root error over 500 polynomials {worst:e}");
    assert!(worst < 1e-9, "{worst}");
}

#[test]
fn quartic_special_cases() {
    // Two complex pairs: (t² + 1)(t² + 2t + 5) → no real root.
    let c = times_pair(&times_pair(&[1.0], Complex::new(0.0, 1.0)), Complex::new(-1.0, 2.0));
    assert!(quartic([c[0], c[1], c[2], c[3], c[4]]).is_empty());
    // One real pair, one complex pair: (t − 1)(t − 3)(t² + 1).
    let c = times_pair(&poly_from_roots(&[1.0, 3.0], 1.0), Complex::new(0.0, 1.0));
    let r = quartic([c[0], c[1], c[2], c[3], c[4]]);
    assert_eq!(r.len(), 2);
    assert!((r.as_slice()[0] - 1.0).abs() < 1e-13 && (r.as_slice()[1] - 3.0).abs() < 1e-13);
    // Biquadratic (q = 0): (t² − 1)(t² − 4).
    let r = quartic([4.0, 0.0, -5.0, 0.0, 1.0]);
    assert_eq!(r.len(), 4);
    for (g, w) in r.as_slice().iter().zip([-2.0, -1.0, 1.0, 2.0]) {
        assert!((g - w).abs() < 1e-14, "{r:?}");
    }
    // Two double roots (a ray tangent to a torus twice): (t − 1)²(t + 2)².
    let c = poly_from_roots(&[1.0, 1.0, -2.0, -2.0], 1.0);
    let r = quartic([c[0], c[1], c[2], c[3], c[4]]);
    assert_eq!(r.len(), 4, "{r:?}");
    for (g, w) in r.as_slice().iter().zip([-2.0, -2.0, 1.0, 1.0]) {
        assert!((g - w).abs() < 1e-7, "{r:?}");
    }
    // A double root with a complex pair: (t − 0.7)²(t² + 1), coefficients rounded.
    let c = times_pair(&poly_from_roots(&[0.7, 0.7], 1.0), Complex::new(0.0, 1.0));
    let r = quartic([c[0], c[1], c[2], c[3], c[4]]);
    assert_eq!(r.len(), 2, "{r:?}");
    assert!(r.as_slice().iter().all(|x| (x - 0.7).abs() < 1e-7), "{r:?}");
    // Degenerate leading coefficient falls back to the cubic.
    let r = quartic([2.0, -3.0, 0.0, 1.0, 0.0]);
    assert_eq!(r.len(), 3);
    assert!(quartic([0.0; 5]).is_empty());
}

#[test]
fn laguerre_random_polynomials_with_known_roots() {
    let mut rng = Pcg32::seed_from_u64(3);
    let mut worst = 0.0f64;
    for degree in 2..=10usize {
        let mut done = 0;
        while done < 40 {
            // Some roots real, some complex pairs.
            let mut expected = Vec::new();
            let mut c = vec![rng.range(0.5, 2.0)];
            while expected.len() < degree {
                if expected.len() + 2 <= degree && rng.next_f64() < 0.3 {
                    let z = Complex::new(rng.range(-5.0, 5.0), rng.range(0.2, 3.0));
                    c = times_pair(&c, z);
                    expected.extend([z, z.conj()]);
                } else {
                    let r = rng.range(-5.0, 5.0);
                    c = mul(&c, &[-r, 1.0]);
                    expected.push(Complex::real(r));
                }
            }
            let sep = expected
                .iter()
                .enumerate()
                .flat_map(|(i, a)| expected[i + 1..].iter().map(move |b| (*a - *b).abs()))
                .fold(f64::INFINITY, f64::min);
            if sep < 0.3 {
                continue;
            }
            let out = laguerre_roots(&c, &LaguerreSettings::default());
            assert_eq!(out.not_converged, 0, "degree {degree}: {expected:?}");
            let err = match_roots(&expected, &out.roots);
            assert!(err < 1e-8, "degree {degree}: error {err:e}, expected {expected:?}, got {:?}", out.roots);
            worst = worst.max(err);
            done += 1;
        }
    }
    println!("laguerre degree 2..10: worst relative root error {worst:e}");
}

#[test]
fn laguerre_complex_roots_and_deflation_count() {
    // (t² + 1)(t − 2) = t³ − 2t² + t − 2.
    let out = laguerre_roots(&[-2.0, 1.0, -2.0, 1.0], &LaguerreSettings::default());
    assert_eq!(out.roots.len(), 3);
    assert_eq!(out.not_converged, 0);
    let want = [Complex::new(0.0, -1.0), Complex::new(0.0, 1.0), Complex::real(2.0)];
    assert!(match_roots(&want, &out.roots) < 1e-14, "{:?}", out.roots);
    // Multiple roots keep the count: (t − 1)³(t + 1)² has 5 roots.
    let c = poly_from_roots(&[1.0, 1.0, 1.0, -1.0, -1.0], 1.0);
    let out = laguerre_roots(&c, &LaguerreSettings::default());
    assert_eq!(out.roots.len(), 5);
    assert_eq!(out.not_converged, 0);
    assert!(out.roots[..2].iter().all(|z| (*z - Complex::real(-1.0)).abs() < 1e-6), "{:?}", out.roots);
    assert!(out.roots[2..].iter().all(|z| (*z - Complex::real(1.0)).abs() < 1e-4), "{:?}", out.roots);
    // Zero roots: t³(t − 1).
    let out = laguerre_roots(&[0.0, 0.0, 0.0, -1.0, 1.0], &LaguerreSettings::default());
    assert_eq!(out.roots.len(), 4);
    assert_eq!(out.roots[..3], [Complex::ZERO; 3]);
    assert!((out.roots[3] - Complex::ONE).abs() < 1e-15);
}

#[test]
fn laguerre_trims_leading_zeros_and_degenerate_input() {
    let out = laguerre_roots(&[1.0, 2.0, 0.0, 0.0], &LaguerreSettings::default());
    assert_eq!(out.roots, vec![Complex::real(-0.5)]);
    assert!(laguerre_roots(&[0.0, 0.0, 0.0], &LaguerreSettings::default()).roots.is_empty());
    assert!(laguerre_roots(&[5.0], &LaguerreSettings::default()).roots.is_empty());
    assert!(laguerre_roots(&[], &LaguerreSettings::default()).roots.is_empty());
    assert!(laguerre_roots(&[1.0, f64::NAN, 1.0], &LaguerreSettings::default()).roots.is_empty());
    // A start far from every root still converges.
    let c = poly_from_roots(&[1.0, 2.0, 3.0], 1.0);
    let out = laguerre_roots_from(&c, 1e6, &LaguerreSettings::default());
    assert_eq!(out.not_converged, 0);
    let want: Vec<_> = [1.0, 2.0, 3.0].map(Complex::real).to_vec();
    assert!(match_roots(&want, &out.roots) < 1e-13);
    // Too few iterations: counted.
    let c = poly_from_roots(&[1.0, 2.0, 3.0, 4.0, 5.0], 1.0);
    let out = laguerre_roots_from(&c, 1e9, &LaguerreSettings { max_iterations: 2, polish: false });
    assert!(out.not_converged > 0);
    assert_eq!(out.roots.len(), 5);
}

#[test]
fn laguerre_wilkinson_degree_10() {
    let roots: Vec<f64> = (1..=10).map(f64::from).collect();
    let c = poly_from_roots(&roots, 1.0);
    for polish in [false, true] {
        let out = laguerre_roots(&c, &LaguerreSettings { polish, ..Default::default() });
        assert_eq!(out.not_converged, 0);
        let want: Vec<_> = roots.iter().map(|&r| Complex::real(r)).collect();
        let err = match_roots(&want, &out.roots);
        println!("Wilkinson 10, polish {polish}: worst relative error {err:e}");
        assert!(err < 1e-8, "{err:e} {:?}", out.roots);
        assert!(out.roots.iter().all(|z| z.im.abs() < 1e-8));
    }
}

#[test]
fn laguerre_polishing_improves_clustered_roots() {
    // A cluster of four roots 0.01 apart beside larger ones. Started at 10, beyond all
    // roots, Laguerre finds the large roots first, and deflating by them (forward
    // deflation in decreasing magnitude, the unstable order, NR §9.5) spoils the
    // quotients from which the cluster is then found; polishing on the original
    // polynomial repairs that. (Started at 0 the order is stable and polishing has
    // nothing left to improve: the roots already meet its stopping criterion.)
    let roots = [0.5, 0.51, 0.52, 0.53, 3.0, -4.0, 5.0, 6.0];
    let c = poly_from_roots(&roots, 1.0);
    let want: Vec<_> = roots.iter().map(|&r| Complex::real(r)).collect();
    let err = |start, polish| {
        let out = laguerre_roots_from(&c, start, &LaguerreSettings { polish, ..Default::default() });
        assert_eq!(out.not_converged, 0);
        match_roots(&want, &out.roots)
    };
    let (raw, polished) = (err(10.0, false), err(10.0, true));
    println!(
        "clustered roots from 10: unpolished error {raw:e}, polished {polished:e}; from 0: {:e}, {:e}",
        err(0.0, false),
        err(0.0, true)
    );
    assert!(polished < raw, "polished {polished:e} unpolished {raw:e}");
    assert!(polished < 1e-9 && raw > 1e-8, "polished {polished:e} unpolished {raw:e}");
    assert!(err(0.0, true) < 1e-9);
}

#[test]
fn real_roots_in_filters_and_solvers_agree() {
    // (t + 2)(t − 0.5)(t − 1)(t − 3) in [0, 2].
    let c = poly_from_roots(&[-2.0, 0.5, 1.0, 3.0], 1.0);
    let mut out = Vec::new();
    for solver in
        [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }, RootSolver::Laguerre { polish: false }]
    {
        let rep = real_roots_in(&c, 0.0, 2.0, solver, &mut out);
        assert_eq!(out.len(), 2, "{solver:?} {out:?}");
        assert!((out[0] - 0.5).abs() < 1e-12 && (out[1] - 1.0).abs() < 1e-12, "{out:?}");
        assert_eq!(rep.used_laguerre, solver != RootSolver::ClosedForm);
        assert_eq!(rep.not_converged, 0);
    }
    // Closed intervals: the end points count.
    real_roots_in(&c, 0.5, 1.0, RootSolver::ClosedForm, &mut out);
    assert_eq!(out, vec![0.5, 1.0]);
    // Empty and inverted intervals, constant polynomials.
    real_roots_in(&c, 1.5, 2.5, RootSolver::ClosedForm, &mut out);
    assert!(out.is_empty());
    real_roots_in(&c, 2.0, 0.0, RootSolver::ClosedForm, &mut out);
    assert!(out.is_empty());
    real_roots_in(&[3.0, 0.0], -1.0, 1.0, RootSolver::Laguerre { polish: true }, &mut out);
    assert!(out.is_empty());
    // Degree 5 with ClosedForm falls back to Laguerre.
    let c = poly_from_roots(&[-2.0, -1.0, 0.25, 1.0, 3.0], 2.0);
    let rep = real_roots_in(&c, -1.5, 10.0, RootSolver::ClosedForm, &mut out);
    assert!(rep.used_laguerre);
    assert_eq!(out.len(), 4);
    // Random degree ≤ 4 polynomials (real roots and complex pairs): both solvers agree.
    let mut rng = Pcg32::seed_from_u64(4);
    let (mut lag, mut cf) = (Vec::new(), Vec::new());
    for _ in 0..2000 {
        let degree = 1 + (rng.next_u64() % 4) as usize;
        let mut c = vec![rng.range(-3.0, 3.0)];
        let mut k = 0;
        while k < degree {
            if k + 2 <= degree && rng.next_f64() < 0.3 {
                c = times_pair(&c, Complex::new(rng.range(-3.0, 3.0), rng.range(0.01, 2.0)));
                k += 2;
            } else {
                c = mul(&c, &[-rng.range(-3.0, 3.0), 1.0]);
                k += 1;
            }
        }
        let rep = real_roots_in(&c, -1.0, 2.0, RootSolver::ClosedForm, &mut cf);
        assert!(!rep.used_laguerre);
        real_roots_in(&c, -1.0, 2.0, RootSolver::Laguerre { polish: true }, &mut lag);
        // Roots within 1e-9 of an end may fall either side; compare the rest.
        let inner =
            |v: &Vec<f64>| v.iter().copied().filter(|r| *r > -1.0 + 1e-9 && *r < 2.0 - 1e-9).collect::<Vec<_>>();
        let (a, b) = (inner(&cf), inner(&lag));
        assert_eq!(a.len(), b.len(), "{c:?}: closed form {cf:?}, laguerre {lag:?}");
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-6 * x.abs().max(1.0), "{c:?}: {cf:?} vs {lag:?}");
        }
    }
}

#[test]
fn tangent_double_root_is_reported_by_every_solver() {
    // (t − 0.3)²(t − 2)(t + 1): the coefficients are rounded, so the double root may
    // come out as a complex pair with a tiny imaginary part.
    let c = poly_from_roots(&[0.3, 0.3, 2.0, -1.0], 1.0);
    let mut out = Vec::new();
    for solver in
        [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }, RootSolver::Laguerre { polish: false }]
    {
        real_roots_in(&c, 0.0, 1.0, solver, &mut out);
        assert!(!out.is_empty(), "{solver:?}");
        assert!(out.iter().all(|r| (r - 0.3).abs() < 1e-7), "{solver:?} {out:?}");
    }
    // A genuinely complex pair well off the axis is not reported.
    let c = times_pair(&[1.0], Complex::new(0.3, 1e-3));
    for solver in [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }] {
        real_roots_in(&c, 0.0, 1.0, solver, &mut out);
        assert!(out.is_empty(), "{solver:?} {out:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn laguerre_recovers_random_real_roots(
        roots in proptest::collection::vec(-10.0f64..10.0, 2..=6),
        lead in 0.1f64..10.0,
    ) {
        let sep = min_separation(&roots);
        prop_assume!(sep > 1e-3);
        let c = poly_from_roots(&roots, lead);
        let out = laguerre_roots(&c, &LaguerreSettings::default());
        prop_assert_eq!(out.not_converged, 0);
        prop_assert_eq!(out.roots.len(), roots.len());
        let mut want = roots.clone();
        want.sort_by(f64::total_cmp);
        for &r in &want {
            // First-order error bound of a simple root: ε·Σ|cᵢ||r|ⁱ / |P′(r)|, with
            // |P′(r)| = lead·Π|r − rⱼ| (small when roots crowd), times a safety factor.
            let abs_eval: f64 = c.iter().enumerate().map(|(i, ci)| ci.abs() * r.abs().powi(i as i32)).sum();
            let dp: f64 = lead * want.iter().filter(|&&x| x != r).map(|x| (r - x).abs()).product::<f64>();
            let tol = 1e-12 * r.abs().max(1.0) + 1e3 * f64::EPSILON * abs_eval / dp;
            let best = out.roots.iter().map(|z| (*z - Complex::real(r)).abs()).fold(f64::INFINITY, f64::min);
            prop_assert!(best <= tol, "root {} off by {:e} > {:e}; got {:?}", r, best, tol, out.roots);
        }
    }
}
