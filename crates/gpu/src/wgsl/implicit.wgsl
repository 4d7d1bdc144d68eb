// Implicit polynomial surfaces F(x, y, z) = 0 in f64, mirroring crates/shapes/src/implicit/shape.rs
// (`Implicit::intersect_report`: the ray clipped to the padded bounds, F restricted to it in the
// scaled parameter s, the real roots in [S_EPS, s₁] tried in ascending order, one guarded Newton
// step each, the normal from ∇F) and crates/shapes/src/roots/* (`real_roots_in`: the closed forms
// for degree ≤ 4, Laguerre's method with deflation and polishing otherwise or on request).
// Compiled in only for scenes with implicit surfaces (`KernelOptions::implicit_coeffs`), which the
// capability check admits only on devices with wgpu's SHADER_F64.
//
// Record (`gpu::backend::shape_record`): +5 solver (PT_IMPLICIT_*), +6 bounds min, +9 bounds max,
// +12 degree, +13 term count, +14 the terms, 5 words each: the exponents (x | y << 8 | z << 16),
// the coefficient's binary exponent (i32 bits) and its mantissa (|m| in [1, 2)) as three f32
// whose sum in f64 is exact (WGSL cannot bitcast two words to an f64).
//
// Differences from the CPU (each at the level of rounding; the roots are polished by Newton's
// method in f64 as on the CPU):
// * Vulkan's GLSL.std.450 has no f64 acos, cos, sin or pow: the trigonometric cubic takes
//   θ = acos in f32 (~10⁻⁷ off) and cos, sin of θ/3 from an f64 Taylor series, the other two
//   candidates by the angle-addition formulas; cube roots are an f32 estimate refined by two
//   Newton steps in f64; the quartic's |q|^(2/3) is cbrt(|q|)²; Laguerre's "random" step
//   (where P′ = P″ = 0) takes cos and sin of the iteration count in f32.
// * The polynomial along the ray is expanded by multiplying out its linear factors instead of
//   by binomial coefficients (the same terms up to rounding); ∇F's monomials are multiplied
//   left to right; |z| of a complex number is not libm's hypot.
// * WGSL cannot tell −0.0 from +0.0: Cardano's −sign(R) and the quadratic's sign(b) take +1 for
//   −0.0 (Rust's signum and copysign take −1), which picks the other (equally valid) formula
//   for the same roots.
// * The shading point is taken at the traversal's f32 t (`pt_implicit_surface`).

alias PtImCoeffs = array<f64, PT_IMPLICIT_COEFFS>;
alias PtImComplex = array<vec2<f64>, PT_IMPLICIT_COEFFS>;

const PT_IM_EPSILON: f64 = 2.220446049250313e-16;

// ---- f64 functions GLSL.std.450 lacks

fn pt_im_finite(x: f64) -> bool {
    return abs(x) <= 1.7976931348623157e308;
}

// `nearly_real`: |im| ≤ REAL_IM_TOL·max(1, |re|).
fn pt_im_nearly_real(re: f64, im: f64) -> bool {
    return abs(im) <= PT_IM_REAL_IM_TOL * max(abs(re), 1.0);
}

// cos and sin of x by reduction to [−π/4, π/4] (π/2 in two parts) and Taylor series to the
// 16th/17th power (truncation error below 3e-18 there): (cos x, sin x).
fn pt_im_cos_sin(x: f64) -> vec2<f64> {
    let k = round(x * 0.6366197723675814);
    let r = (x - k * 1.5707963267341256) - k * 6.077100506506192e-11;
    let r2 = r * r;
    var c = 1.0lf;
    var s = 1.0lf;
    // Horner from the highest terms: cos = Σ (−r²)^i/(2i)!, sin = r·Σ (−r²)^i/(2i+1)!.
    for (var i = 8u; i > 0u; i--) {
        let fi = f64(i);
        c = 1.0 - c * r2 / ((2.0 * fi - 1.0) * (2.0 * fi));
        s = 1.0 - s * r2 / ((2.0 * fi) * (2.0 * fi + 1.0));
    }
    s *= r;
    let q = i32(k) & 3;
    if q == 0 {
        return vec2<f64>(c, s);
    } else if q == 1 {
        return vec2<f64>(-s, c);
    } else if q == 2 {
        return vec2<f64>(-c, -s);
    }
    return vec2<f64>(s, -c);
}

// The real cube root: |x| scaled by powers of 2⁶⁰ into [10⁻¹⁸, 10¹⁸] (exactly, the root by
// powers of 2²⁰), f32's root of that, two Newton steps in f64.
fn pt_im_cbrt(x: f64) -> f64 {
    var a = abs(x);
    if a == 0.0 || !pt_im_finite(a) {
        return x;
    }
    var scale = 1.0lf;
    while a > 1e18 {
        a *= 8.673617379884035e-19;
        scale *= 1048576.0;
    }
    while a < 1e-18 {
        a *= 1152921504606846976.0;
        scale *= 9.5367431640625e-7;
    }
    var y = f64(pow(f32(a), 1.0 / 3.0));
    for (var i = 0u; i < 2u; i++) {
        y -= (y * y * y - a) / (3.0 * y * y);
    }
    return select(y * scale, -y * scale, x < 0.0);
}

// ---- The closed forms (quadratic.rs, cubic.rs, quartic.rs, eval.rs) on polynomials of degree
// ≤ 4 held in registers, not arrays. A call site is a copy of its callee in the compiled kernel
// (a lavapipe compile took 464 s with a copy per use), so the large pieces are called once: one
// cubic serves the cubic, the quartic's resolvent and a quartic whose leading coefficient is
// negligible; one low-degree solve serves degrees 1 and 2 and a cubic that is not one; the
// quartic's own roots take a second polishing.

// c.x + c.y t + c.z t² + c.w t³ + c4 t⁴.
struct PtImPoly {
    c: vec4<f64>,
    c4: f64,
}

fn pt_im_poly_coeff(p: PtImPoly, i: u32) -> f64 {
    return select(p.c[min(i, 3u)], p.c4, i == 4u);
}

// (P(t), P′(t)) by Horner's rule (`eval_poly_deriv`; leading zeros change nothing).
fn pt_im_eval5(p: PtImPoly, t: f64) -> vec2<f64> {
    var v = vec2<f64>(p.c4, 0.0);
    for (var i = 4u; i > 0u; i--) {
        v = vec2<f64>(v.x * t + p.c[i - 1u], v.y * t + v.x);
    }
    return v;
}

// `newton_polish`: up to `steps` Newton steps, each kept only if it lowers |P|.
fn pt_im_newton_polish(p: PtImPoly, start: f64, steps: u32) -> f64 {
    var t = start;
    var pd = pt_im_eval5(p, t);
    for (var k = 0u; k < steps; k++) {
        if pd.x == 0.0 || pd.y == 0.0 {
            break;
        }
        let t1 = t - pd.x / pd.y;
        if !pt_im_finite(t1) {
            break;
        }
        let pd1 = pt_im_eval5(p, t1);
        if abs(pd1.x) >= abs(pd.x) {
            break;
        }
        t = t1;
        pd = pd1;
    }
    return t;
}

// `trim_negligible` of the first `len` coefficients: the length without trailing zeros and
// leading coefficients ≤ LEAD_TOL·max|c_i|.
fn pt_im_trim_negligible(p: PtImPoly, len: u32) -> u32 {
    var n = len;
    loop {
        while n > 0u && pt_im_poly_coeff(p, n - 1u) == 0.0 {
            n -= 1u;
        }
        if n <= 1u {
            break;
        }
        var scale = 0.0lf;
        for (var i = 0u; i + 1u < n; i++) {
            scale = max(scale, abs(pt_im_poly_coeff(p, i)));
        }
        if abs(pt_im_poly_coeff(p, n - 1u)) > PT_IM_LEAD_TOL * scale {
            break;
        }
        n -= 1u;
    }
    return n;
}

// Up to four real roots, ascending (`RealRoots`; a double root twice).
struct PtImRoots {
    r: vec4<f64>,
    n: u32,
}

fn pt_im_push(out: ptr<function, PtImRoots>, r: f64) {
    if (*out).n < 4u && pt_im_finite(r) {
        (*out).r[(*out).n] = r;
        (*out).n += 1u;
    }
}

// Ascending by a sorting network, the unused slots at the end.
fn pt_im_sort_roots(out: ptr<function, PtImRoots>) {
    let big = vec4<f64>(1.7976931348623157e308);
    var r = select(big, (*out).r, vec4<u32>(0u, 1u, 2u, 3u) < vec4<u32>((*out).n));
    let a = vec4<f64>(min(r.x, r.y), max(r.x, r.y), min(r.z, r.w), max(r.z, r.w));
    let b = vec4<f64>(min(a.x, a.z), max(a.x, a.z), min(a.y, a.w), max(a.y, a.w));
    (*out).r = vec4<f64>(b.x, min(b.z, b.y), max(b.z, b.y), b.w);
}

// `RealRoots::polish`: two Newton steps on `p` each, then sorted.
fn pt_im_polish_roots(out: ptr<function, PtImRoots>, p: PtImPoly) {
    for (var i = 0u; i < 4u; i++) {
        if i < (*out).n {
            (*out).r[i] = pt_im_newton_polish(p, (*out).r[i], 2u);
        }
    }
    pt_im_sort_roots(out);
}

// Two real roots, ascending, or none (`quadratic_f64`'s Option).
struct PtImPair {
    lo: f64,
    hi: f64,
    ok: bool,
}

// `quadratic_f64`: a t² + b t + c without cancellation, the discriminant with Kahan's FMA.
fn pt_im_quadratic(a: f64, b: f64, c: f64) -> PtImPair {
    let none = PtImPair(0.0, 0.0, false);
    if !(pt_im_finite(a) && pt_im_finite(b) && pt_im_finite(c)) {
        return none;
    }
    if a == 0.0 {
        if b == 0.0 {
            return none;
        }
        let r = -c / b;
        return PtImPair(r, r, true);
    }
    if b == 0.0 && c == 0.0 {
        return PtImPair(0.0, 0.0, true);
    }
    let w = 4.0 * a * c;
    let e = fma(-4.0 * a, c, w);
    let f = fma(b, b, -w);
    let disc = f + e;
    if disc < 0.0 {
        return none;
    }
    let sq = sqrt(disc);
    let q = -0.5 * (b + select(sq, -sq, b < 0.0));
    let r1 = q / a;
    let r2 = c / q;
    return PtImPair(min(r1, r2), max(r1, r2), true);
}

// `monic_quadratic_tol`: t² + b t + c; a nearly real complex pair is a double root.
fn pt_im_monic_quadratic(b: f64, c: f64, out: ptr<function, PtImRoots>) {
    let q = pt_im_quadratic(1.0, b, c);
    if q.ok {
        pt_im_push(out, q.lo);
        pt_im_push(out, q.hi);
        return;
    }
    let re = -0.5 * b;
    let im2 = c - re * re;
    if pt_im_finite(im2) && pt_im_nearly_real(re, sqrt(max(im2, 0.0))) {
        pt_im_push(out, re);
        pt_im_push(out, re);
    }
}

// `real_roots_in`'s closed forms for the `len` (2 to 5, trailing zeros trimmed) coefficients
// of `p`: `low_degree`, `cubic` or `quartic`, their roots polished and ascending.
fn pt_im_closed_form(p: PtImPoly, len: u32) -> PtImRoots {
    // The cubic to solve: `p` itself, the quartic's resolvent, or a quartic whose leading
    // coefficient is negligible (its first coefficients, as `quartic` hands them to `cubic`).
    var cubic = p;
    var quartic = false;
    var qa = 0.0lf;
    var qp = 0.0lf;
    var qq = 0.0lf;
    var qr = 0.0lf;
    if len == 5u {
        let t = pt_im_trim_negligible(p, 5u);
        if t == 5u {
            // Depressed by t = y − a/4: y⁴ + p y² + q y + r.
            quartic = true;
            let inv = 1.0 / p.c4;
            qa = p.c.w * inv;
            let b = p.c.z * inv;
            let cc = p.c.y * inv;
            let d = p.c.x * inv;
            let a2 = qa * qa;
            qp = b - 0.375 * a2;
            qq = cc - 0.5 * qa * b + 0.125 * a2 * qa;
            qr = d - 0.25 * qa * cc + a2 * b / 16.0 - 3.0 * a2 * a2 / 256.0;
            cubic = PtImPoly(vec4<f64>(-0.125 * qq * qq, 0.25 * qp * qp - qr, qp, 1.0), 0.0);
        } else {
            cubic = PtImPoly(select(vec4<f64>(0.0), p.c, vec4<u32>(0u, 1u, 2u, 3u) < vec4<u32>(t)), 0.0);
        }
    }
    var out: PtImRoots;
    var low = p;
    var low_len = len;
    if len >= 4u {
        low_len = pt_im_trim_negligible(cubic, 4u);
        low = cubic;
        if low_len == 4u {
            // `cubic`: one root by the trigonometric formula (the largest in magnitude of the
            // three) or Cardano's with the stable sign, polished and divided out.
            low_len = 0u;
            let inv = 1.0 / cubic.c.w;
            let a = cubic.c.z * inv;
            let b = cubic.c.y * inv;
            let cc = cubic.c.x * inv;
            let q = (a * a - 3.0 * b) / 9.0;
            let r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * cc) / 54.0;
            let a3 = a / 3.0;
            let q3 = q * q * q;
            let r2 = r * r;
            var r1: f64;
            if r2 < q3 {
                // θ = acos in f32 (GLSL.std.450 has no f64 acos; the polishing below makes
                // the root f64's), cos((θ ± 2π)/3) from cos and sin of θ/3.
                let sq = sqrt(q);
                let theta = f64(acos(f32(clamp(r / (sq * sq * sq), -1.0, 1.0))));
                let cs = pt_im_cos_sin(theta / 3.0);
                let m = -2.0 * sq;
                let h = 0.8660254037844386 * cs.y;
                r1 = m * cs.x - a3;
                let plus = m * (-0.5 * cs.x - h) - a3;
                let minus = m * (-0.5 * cs.x + h) - a3;
                if abs(plus) >= abs(r1) {
                    r1 = plus;
                }
                if abs(minus) >= abs(r1) {
                    r1 = minus;
                }
            } else {
                // −sign(R) with Rust's signum: +0 counts as positive.
                let big_a = select(-1.0lf, 1.0lf, r < 0.0) * pt_im_cbrt(abs(r) + sqrt(r2 - q3));
                var big_b = 0.0lf;
                if big_a != 0.0 {
                    big_b = q / big_a;
                }
                r1 = big_a + big_b - a3;
            }
            r1 = pt_im_newton_polish(PtImPoly(vec4<f64>(cc, b, a, 1.0), 0.0), r1, 4u);
            pt_im_push(&out, r1);
            // (t − r₁)(t² + e t + f), f = −c/r₁ (b when r₁ = 0).
            var f = b;
            if r1 != 0.0 {
                f = -cc / r1;
            }
            pt_im_monic_quadratic(a + r1, f, &out);
        }
    }
    // `low_degree` (degree 1 or 2): the polynomial itself, or a cubic that is not one.
    if low_len == 2u {
        pt_im_push(&out, -low.c.x / low.c.y);
    } else if low_len == 3u {
        pt_im_monic_quadratic(low.c.y / low.c.z, low.c.x / low.c.z, &out);
    }
    pt_im_polish_roots(&out, low);
    if !quartic {
        return out;
    }
    // `quartic`: m ≥ 0 the resolvent's largest root, (y² − s y + e₁)(y² + s y + e₂) with
    // e₁,₂ = p/2 + m ± q/(2s), the one where the terms add as a sum, the other as r over it;
    // for m ≈ 0 the roots of z² − (p + 2m) z + r.
    var m = 0.0lf;
    if out.n > 0u {
        m = max(out.r[out.n - 1u], 0.0);
    }
    let s = sqrt(2.0 * m);
    let cbrt_q = pt_im_cbrt(abs(qq));
    let rho2 = max(max(abs(qp), cbrt_q * cbrt_q), sqrt(abs(qr)));
    var e1: f64;
    var e2: f64;
    if m > 1e-4 * rho2 {
        let base = 0.5 * qp + m;
        let dd = qq / (2.0 * s);
        if (base >= 0.0) == (dd >= 0.0) {
            e1 = base + dd;
            e2 = base - dd;
            if e1 != 0.0 {
                e2 = qr / e1;
            }
        } else {
            e2 = base - dd;
            e1 = base + dd;
            if e2 != 0.0 {
                e1 = qr / e2;
            }
        }
    } else {
        let z = pt_im_quadratic(1.0, -(qp + 2.0 * m), qr);
        var lo = 0.5 * (qp + 2.0 * m);
        var hi = lo;
        if z.ok {
            lo = z.lo;
            hi = z.hi;
        }
        e1 = select(lo, hi, qq >= 0.0);
        e2 = select(hi, lo, qq >= 0.0);
    }
    var ys: PtImRoots;
    pt_im_monic_quadratic(-s, e1, &ys);
    pt_im_monic_quadratic(s, e2, &ys);
    var roots: PtImRoots;
    for (var i = 0u; i < 4u; i++) {
        if i < ys.n {
            pt_im_push(&roots, ys.r[i] - 0.25 * qa);
        }
    }
    pt_im_polish_roots(&roots, p);
    return roots;
}

// ---- Horner's rule on the coefficient arrays (any degree)

// (P(t), P′(t)) over the first `len` coefficients (`eval_poly_deriv`).
fn pt_im_eval_deriv(c: ptr<function, PtImCoeffs>, len: u32, t: f64) -> vec2<f64> {
    var p = 0.0lf;
    var dp = 0.0lf;
    for (var i = len; i > 0u; i--) {
        dp = dp * t + p;
        p = p * t + (*c)[i - 1u];
    }
    return vec2<f64>(p, dp);
}

// ---- complex.rs and laguerre.rs

fn pt_im_cmul(a: vec2<f64>, b: vec2<f64>) -> vec2<f64> {
    return vec2<f64>(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

// Smith's division.
fn pt_im_cdiv(a: vec2<f64>, o: vec2<f64>) -> vec2<f64> {
    if abs(o.x) >= abs(o.y) {
        let r = o.y / o.x;
        let den = o.x + r * o.y;
        return vec2<f64>((a.x + r * a.y) / den, (a.y - r * a.x) / den);
    }
    let r = o.x / o.y;
    let den = o.y + r * o.x;
    return vec2<f64>((a.x * r + a.y) / den, (a.y * r - a.x) / den);
}

// |z| scaled by the larger part (no overflow).
fn pt_im_cabs(z: vec2<f64>) -> f64 {
    let x = abs(z.x);
    let y = abs(z.y);
    let big = max(x, y);
    if big == 0.0 {
        return 0.0;
    }
    let small = min(x, y) / big;
    return big * sqrt(1.0 + small * small);
}

// The principal square root, as Numerical Recipes' `csqrt`.
fn pt_im_csqrt(z: vec2<f64>) -> vec2<f64> {
    if z.x == 0.0 && z.y == 0.0 {
        return vec2<f64>(0.0, 0.0);
    }
    let x = abs(z.x);
    let y = abs(z.y);
    var w: f64;
    if x >= y {
        let r = y / x;
        w = sqrt(x) * sqrt(0.5 * (1.0 + sqrt(1.0 + r * r)));
    } else {
        let r = x / y;
        w = sqrt(y) * sqrt(0.5 * (r + sqrt(1.0 + r * r)));
    }
    if z.x >= 0.0 {
        return vec2<f64>(w, z.y / (2.0 * w));
    }
    return vec2<f64>(y / (2.0 * w), select(-w, w, z.y >= 0.0));
}

struct PtImLaguer {
    x: vec2<f64>,
    ok: bool,
}

// `laguer`: one root of the complex polynomial a[0..=m] from x (Numerical Recipes §9.5), every
// 10th step a fractional one.
fn pt_im_laguer(a: ptr<function, PtImComplex>, m: u32, start: vec2<f64>) -> PtImLaguer {
    // NR's fractions of a step (in vectors: a private array costs more to compile).
    let frac_lo = vec4<f64>(0.5, 0.25, 0.75, 0.13);
    let frac_hi = vec4<f64>(0.38, 0.62, 0.88, 1.0);
    let mf = f64(m);
    var x = start;
    for (var iter = 1u; iter <= PT_IM_MAX_ITERATIONS; iter++) {
        var b = (*a)[m];
        var err = pt_im_cabs(b);
        var d = vec2<f64>(0.0, 0.0);
        var f = vec2<f64>(0.0, 0.0);
        let abx = pt_im_cabs(x);
        for (var j = m; j > 0u; j--) {
            f = pt_im_cmul(x, f) + d;
            d = pt_im_cmul(x, d) + b;
            b = pt_im_cmul(x, b) + (*a)[j - 1u];
            err = pt_im_cabs(b) + abx * err;
        }
        err *= PT_IM_EPSILON;
        if pt_im_cabs(b) <= err {
            return PtImLaguer(x, true);
        }
        let g = pt_im_cdiv(d, b);
        let g2 = pt_im_cmul(g, g);
        let h = g2 - 2.0 * pt_im_cdiv(f, b);
        let sq = pt_im_csqrt((mf * h - g2) * (mf - 1.0));
        let gp = g + sq;
        let gm = g - sq;
        let abp = pt_im_cabs(gp);
        let abm = pt_im_cabs(gm);
        var dx: vec2<f64>;
        if max(abp, abm) > 0.0 {
            dx = pt_im_cdiv(vec2<f64>(mf, 0.0), select(gp, gm, abp < abm));
        } else {
            // P′ = P″ = 0: a step in a "random" direction (NR; its cos and sin in f32).
            let it = f32(iter);
            dx = vec2<f64>(f64(cos(it)), f64(sin(it))) * (1.0 + abx);
        }
        let x1 = x - dx;
        if !(pt_im_finite(x1.x) && pt_im_finite(x1.y)) {
            return PtImLaguer(x, false);
        }
        if (x1.x == x.x && x1.y == x.y) || pt_im_cabs(dx) <= 4.0 * PT_IM_EPSILON * pt_im_cabs(x1) {
            return PtImLaguer(x1, true);
        }
        if iter % 10u != 0u {
            x = x1;
        } else {
            let k = (iter / 10u - 1u) % 8u;
            x = x - dx * select(frac_lo[k & 3u], frac_hi[k & 3u], k >= 4u);
        }
    }
    return PtImLaguer(x, false);
}

// `laguerre_roots_from` (every search from `lo`, the first finite end as on the CPU, deflation,
// optional polishing on the original polynomial) followed by `real_roots_in`'s filter: the nearly
// real roots in [lo, hi], ascending, into `out`; their count. `c[0..len]` has a non-zero leading coefficient, len ≥ 2. Searches and
// polishing share one call of `pt_im_laguer` (one copy in the compiled kernel).
fn pt_im_laguerre_real(
    c: ptr<function, PtImCoeffs>,
    len: u32,
    polish: bool,
    lo: f64,
    hi: f64,
    out: ptr<function, PtImCoeffs>,
) -> u32 {
    for (var i = 0u; i < len; i++) {
        if !pt_im_finite((*c)[i]) {
            return 0u;
        }
    }
    let degree = len - 1u;
    var ad: PtImComplex;
    var found: PtImComplex;
    let x0 = vec2<f64>(lo, 0.0);
    // Steps 0 … degree − 1 find a root of the deflated polynomial of degree − step from x0 and
    // divide it out; with polishing, steps degree … 2·degree − 1 run Laguerre again from each
    // root on the original polynomial, restored into `ad`.
    let steps = select(degree, 2u * degree, polish);
    for (var step = 0u; step < steps; step++) {
        if step == 0u || step == degree {
            for (var i = 0u; i < len; i++) {
                ad[i] = vec2<f64>((*c)[i], 0.0);
            }
        }
        let deflating = step < degree;
        let k = select(step - degree, step, deflating);
        let m = select(degree, degree - step, deflating);
        let l = pt_im_laguer(&ad, m, select(found[k], x0, deflating));
        if deflating {
            var x = l.x;
            if abs(x.y) <= 2.0 * PT_IM_EPSILON * abs(x.x) {
                x.y = 0.0;
            }
            found[k] = x;
            // Synthetic division by (t − x): the quotient overwrites ad[0..m].
            var b = ad[m];
            for (var j = m; j > 0u; j--) {
                let cj = ad[j - 1u];
                ad[j - 1u] = b;
                b = pt_im_cmul(x, b) + cj;
            }
        } else if l.ok {
            found[k] = l.x;
        }
    }
    var n = 0u;
    for (var i = 0u; i < degree; i++) {
        let z = found[i];
        if pt_im_nearly_real(z.x, z.y) && z.x >= lo && z.x <= hi {
            // Insertion in ascending order.
            var j = n;
            while j > 0u && (*out)[j - 1u] > z.x {
                (*out)[j] = (*out)[j - 1u];
                j -= 1u;
            }
            (*out)[j] = z.x;
            n += 1u;
        }
    }
    return n;
}

// ---- interval.rs: `real_roots_in`, the real roots of c[0..len] in [lo, hi], ascending, into
// `out`; their count.
fn pt_im_real_roots(
    c: ptr<function, PtImCoeffs>,
    len_in: u32,
    lo: f64,
    hi: f64,
    solver: u32,
    out: ptr<function, PtImCoeffs>,
) -> u32 {
    var len = len_in;
    while len > 0u && (*c)[len - 1u] == 0.0 {
        len -= 1u;
    }
    if len < 2u || !(lo <= hi) {
        return 0u;
    }
    if solver == PT_IMPLICIT_CLOSED_FORM && len <= 5u {
        var p = PtImPoly(vec4<f64>(0.0), 0.0);
        for (var i = 0u; i < 4u; i++) {
            if i < len {
                p.c[i] = (*c)[i];
            }
        }
        if len == 5u {
            p.c4 = (*c)[4];
        }
        let rr = pt_im_closed_form(p, len);
        var n = 0u;
        for (var i = 0u; i < 4u; i++) {
            if i < rr.n && rr.r[i] >= lo && rr.r[i] <= hi {
                (*out)[n] = rr.r[i];
                n += 1u;
            }
        }
        return n;
    }
    // (The closed-form solver's fall-back above degree 4 polishes.)
    return pt_im_laguerre_real(c, len, solver != PT_IMPLICIT_LAGUERRE_PLAIN, lo, hi, out);
}

// ---- implicit/poly.rs and shape.rs

// The coefficient of the term at `at`: its mantissa's three parts summed (exactly) and scaled.
fn pt_im_coeff(at: u32) -> f64 {
    let m = f64(pt_tables[at + 2u]) + f64(pt_tables[at + 3u]) + f64(pt_tables[at + 4u]);
    return ldexp(m, bitcast<i32>(pt_tables[at + 1u]));
}

fn pt_im_powi(x: f64, e: u32) -> f64 {
    var v = 1.0lf;
    for (var i = 0u; i < e; i++) {
        v *= x;
    }
    return v;
}

// `Poly3::along_ray`: the coefficients of F(q + s·u) in s (degree + 1 of them, returned), each
// term's factors (q_a + s·u_a) multiplied out.
fn pt_im_along_ray(rec: u32, q: vec3<f64>, u: vec3<f64>, c: ptr<function, PtImCoeffs>) -> u32 {
    let degree = pt_tu(rec + 12u);
    let terms = pt_tu(rec + 13u);
    for (var k = 0u; k < terms; k++) {
        let at = rec + 14u + 5u * k;
        let exps = pt_tu(at);
        var f: PtImCoeffs;
        f[0] = pt_im_coeff(at);
        var len = 1u;
        for (var axis = 0u; axis < 3u; axis++) {
            let e = (exps >> (8u * axis)) & 0xffu;
            for (var i = 0u; i < e; i++) {
                f[len] = f[len - 1u] * u[axis];
                for (var j = len - 1u; j > 0u; j--) {
                    f[j] = f[j] * q[axis] + f[j - 1u] * u[axis];
                }
                f[0] *= q[axis];
                len += 1u;
            }
        }
        for (var j = 0u; j < len; j++) {
            (*c)[j] += f[j];
        }
    }
    return degree + 1u;
}

// `Poly3::gradient`, term by term.
fn pt_im_gradient(rec: u32, p: vec3<f64>) -> vec3<f64> {
    var g = vec3<f64>(0.0, 0.0, 0.0);
    let terms = pt_tu(rec + 13u);
    for (var k = 0u; k < terms; k++) {
        let at = rec + 14u + 5u * k;
        let exps = pt_tu(at);
        let coeff = pt_im_coeff(at);
        let e = vec3u(exps & 0xffu, (exps >> 8u) & 0xffu, (exps >> 16u) & 0xffu);
        for (var axis = 0u; axis < 3u; axis++) {
            if e[axis] == 0u {
                continue;
            }
            var de = e;
            de[axis] -= 1u;
            g[axis] += coeff * f64(e[axis]) * pt_im_powi(p.x, de.x) * pt_im_powi(p.y, de.y) * pt_im_powi(p.z, de.z);
        }
    }
    return g;
}

// `newton_step`: one Newton step, kept only if it lowers |P|.
fn pt_im_newton_step(c: ptr<function, PtImCoeffs>, len: u32, s: f64) -> f64 {
    let pd = pt_im_eval_deriv(c, len, s);
    if pd.x == 0.0 || pd.y == 0.0 {
        return s;
    }
    let s1 = s - pd.x / pd.y;
    if pt_im_finite(s1) && abs(pt_im_eval_deriv(c, len, s1).x) < abs(pd.x) {
        return s1;
    }
    return s;
}

// `Implicit::intersect`: the first root in (t_min, t_max) with a finite non-zero gradient.
fn pt_implicit_hit(rec: u32, o32: vec3f, d32: vec3f, t_min: f32, t_max: f32) -> PtShapeHit {
    let o = vec3<f64>(o32);
    let d = vec3<f64>(d32);
    let len = sqrt(dot(d, d));
    if !(len > 0.0 && pt_im_finite(len) && pt_im_finite(o.x) && pt_im_finite(o.y) && pt_im_finite(o.z)) {
        return pt_no_shape_hit();
    }
    let lo = vec3<f64>(pt_tv3(rec + 6u));
    let hi = vec3<f64>(pt_tv3(rec + 9u));
    let diag = sqrt(dot(hi - lo, hi - lo));
    let pad = vec3<f64>(PT_IM_PAD_REL * diag);
    let bmin = lo - pad;
    let bmax = hi + pad;
    var t0 = f64(t_min);
    var t1 = f64(t_max);
    for (var a = 0u; a < 3u; a++) {
        if d[a] == 0.0 {
            if o[a] < bmin[a] || o[a] > bmax[a] {
                return pt_no_shape_hit();
            }
        } else {
            let inv = 1.0 / d[a];
            let ta = (bmin[a] - o[a]) * inv;
            let tb = (bmax[a] - o[a]) * inv;
            t0 = max(t0, min(ta, tb));
            t1 = min(t1, max(ta, tb));
        }
    }
    if !(t0 <= t1) {
        return pt_no_shape_hit();
    }
    // t = t0 + s·scale: s runs over [0, ≤ 1] whatever the ray's origin and length.
    let scale = diag / len;
    let q = o + t0 * d;
    let u = d * scale;
    var c: PtImCoeffs;
    let n = pt_im_along_ray(rec, q, u, &c);
    let s_hi = (t1 - t0) / scale;
    var roots: PtImCoeffs;
    let count = pt_im_real_roots(&c, n, PT_IM_S_EPS, s_hi, pt_tu(rec + 5u), &roots);
    for (var i = 0u; i < count; i++) {
        let s = pt_im_newton_step(&c, n, roots[i]);
        if !(s > PT_IM_S_EPS && s <= s_hi) {
            continue;
        }
        let t = f32(t0 + s * scale);
        if !(t > t_min && t < t_max) {
            continue;
        }
        let p = q + s * u;
        let g = pt_im_gradient(rec, p);
        let g2 = dot(g, g);
        if !(g2 > 0.0 && pt_im_finite(g2)) {
            continue;
        }
        return PtShapeHit(t, vec3f(p), vec3f(g / sqrt(g2)), true);
    }
    return pt_no_shape_hit();
}

// The surface at the traversal's hit t (`pt_shape_surface`): the point o + t·d in f64, the
// normal ∇F/|∇F| there (the CPU takes both at the root in f64: they differ by the rounding of
// t to f32, ~10⁻⁷ relative).
fn pt_implicit_surface(rec: u32, o: vec3f, d: vec3f, t: f32) -> PtShapeHit {
    let p = vec3<f64>(o) + f64(t) * vec3<f64>(d);
    let g = pt_im_gradient(rec, p);
    let g2 = dot(g, g);
    var n = -normalize(d);
    if g2 > 0.0 && pt_im_finite(g2) {
        n = vec3f(g / sqrt(g2));
    }
    return PtShapeHit(t, vec3f(p), n, true);
}
