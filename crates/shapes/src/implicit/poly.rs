//! Polynomials F(x, y, z) in f64: the normalised [`Poly3`] with its evaluation, gradient
//! and restriction to a ray, the builders of the classic surfaces, and the sparse
//! arithmetic (`PolyMap`) the builders and the parser expand with.

use crate::ShapeError;
use glam::DVec3;
use std::collections::BTreeMap;

/// The highest total degree a [`Poly3`] may have: far beyond any surface one would
/// trace, and a guard against `(x + y + z)^200` exploding the parser.
pub const MAX_DEGREE: u32 = 32;

/// One monomial coeff·x^i·y^j·z^k of a [`Poly3`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term {
    /// The coefficient.
    pub coeff: f64,
    /// The exponents (i, j, k) of x, y and z.
    pub exps: [u8; 3],
}

impl Term {
    fn degree(&self) -> u32 {
        self.exps.iter().map(|&e| e as u32).sum()
    }
}

/// A polynomial F(x, y, z) = Σ coeff·x^i·y^j·z^k in f64, kept normalised: like terms
/// combined, zero terms dropped, sorted by exponents.
#[derive(Clone, Debug, PartialEq)]
pub struct Poly3 {
    terms: Vec<Term>,
}

/// Sparse polynomial arithmetic for the parser and the builders.
pub(super) type PolyMap = BTreeMap<[u8; 3], f64>;

fn map_degree(p: &PolyMap) -> u32 {
    p.keys().map(|e| e.iter().map(|&x| x as u32).sum::<u32>()).max().unwrap_or(0)
}

pub(super) fn map_constant(c: f64) -> PolyMap {
    PolyMap::from([([0, 0, 0], c)])
}

pub(super) fn map_var(axis: usize) -> PolyMap {
    let mut e = [0u8; 3];
    e[axis] = 1;
    PolyMap::from([(e, 1.0)])
}

pub(super) fn map_add(mut a: PolyMap, b: &PolyMap, sign: f64) -> PolyMap {
    for (e, c) in b {
        *a.entry(*e).or_insert(0.0) += sign * c;
    }
    a.retain(|_, c| *c != 0.0);
    a
}

pub(super) fn map_scale(mut a: PolyMap, s: f64) -> PolyMap {
    a.values_mut().for_each(|c| *c *= s);
    a.retain(|_, c| *c != 0.0);
    a
}

/// a·b, or `None` if the product's degree would exceed [`MAX_DEGREE`].
pub(super) fn map_mul(a: &PolyMap, b: &PolyMap) -> Option<PolyMap> {
    if map_degree(a) + map_degree(b) > MAX_DEGREE {
        return None;
    }
    let mut out = PolyMap::new();
    for (ea, ca) in a {
        for (eb, cb) in b {
            let e = [ea[0] + eb[0], ea[1] + eb[1], ea[2] + eb[2]];
            *out.entry(e).or_insert(0.0) += ca * cb;
        }
    }
    out.retain(|_, c| *c != 0.0);
    Some(out)
}

/// aⁿ by repeated multiplication (exact powers of small polynomials), `None` past
/// [`MAX_DEGREE`].
pub(super) fn map_pow(a: &PolyMap, n: u32) -> Option<PolyMap> {
    let mut out = map_constant(1.0);
    for _ in 0..n {
        out = map_mul(&out, a)?;
    }
    Some(out)
}

/// x² + y² + z².
fn map_r2() -> PolyMap {
    let mut p = PolyMap::new();
    for axis in 0..3 {
        let mut e = [0u8; 3];
        e[axis] = 2;
        p.insert(e, 1.0);
    }
    p
}

/// Pascal's triangle C(n, k) for n ≤ [`MAX_DEGREE`], exact in f64 (C(32, 16) < 2⁵³).
const BINOMIAL: [[f64; MAX_DEGREE as usize + 1]; MAX_DEGREE as usize + 1] = {
    const N: usize = MAX_DEGREE as usize + 1;
    let mut c = [[0u64; N]; N];
    let mut out = [[0.0f64; N]; N];
    let mut n = 0;
    while n < N {
        c[n][0] = 1;
        let mut k = 1;
        while k <= n {
            c[n][k] = c[n - 1][k - 1] + c[n - 1][k];
            k += 1;
        }
        let mut k = 0;
        while k <= n {
            out[n][k] = c[n][k] as f64;
            k += 1;
        }
        n += 1;
    }
    out
};

impl Poly3 {
    /// A polynomial from its terms. Like terms are combined and zeros dropped; errors
    /// for a non-finite coefficient, a degree above [`MAX_DEGREE`], or no non-zero term
    /// left (F ≡ 0 is not a surface).
    pub fn new(terms: Vec<Term>) -> Result<Self, ShapeError> {
        let mut map = PolyMap::new();
        for t in &terms {
            if !t.coeff.is_finite() {
                return Err(ShapeError::Invalid(format!("polynomial coefficient {} is not finite", t.coeff)));
            }
            if t.degree() > MAX_DEGREE {
                return Err(ShapeError::Invalid(format!(
                    "polynomial term of degree {} exceeds the maximum {MAX_DEGREE}",
                    t.degree()
                )));
            }
            *map.entry(t.exps).or_insert(0.0) += t.coeff;
        }
        Self::from_map(map)
    }

    pub(super) fn from_map(mut map: PolyMap) -> Result<Self, ShapeError> {
        if map.values().any(|c| !c.is_finite()) {
            return Err(ShapeError::Invalid("polynomial coefficient is not finite".into()));
        }
        map.retain(|_, c| *c != 0.0);
        if map.is_empty() {
            return Err(ShapeError::Invalid("polynomial is empty or identically zero".into()));
        }
        Ok(Self { terms: map.into_iter().map(|(exps, coeff)| Term { coeff, exps }).collect() })
    }

    /// Builder helper: the builders' arithmetic cannot fail for valid parameters.
    fn built(map: Option<PolyMap>, what: &str) -> Self {
        map.and_then(|m| Self::from_map(m).ok())
            .unwrap_or_else(|| panic!("{what}: parameters must be finite and positive"))
    }

    /// The normalised terms.
    pub fn terms(&self) -> &[Term] {
        &self.terms
    }

    /// The total degree max(i + j + k).
    pub fn degree(&self) -> u32 {
        self.terms.iter().map(Term::degree).max().unwrap_or(0)
    }

    /// F(p).
    pub fn eval(&self, p: DVec3) -> f64 {
        self.terms.iter().map(|t| t.coeff * monomial(p, t.exps)).sum()
    }

    /// Σ |coeff|·|x|^i|y|^j|z|^k: the scale of the rounding error of [`Poly3::eval`].
    pub fn eval_abs(&self, p: DVec3) -> f64 {
        self.terms.iter().map(|t| t.coeff.abs() * monomial(p.abs(), t.exps)).sum()
    }

    /// ∇F(p), differentiating term by term.
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let mut g = DVec3::ZERO;
        for t in &self.terms {
            for axis in 0..3 {
                let e = t.exps[axis];
                if e == 0 {
                    continue;
                }
                let mut de = t.exps;
                de[axis] -= 1;
                g[axis] += t.coeff * e as f64 * monomial(p, de);
            }
        }
        g
    }

    /// The coefficients (ascending, length degree + 1) of F(o + t·d) as a polynomial in
    /// t: every factor (o_x + t·d_x)^i expanded with binomial coefficients and the
    /// products formed by polynomial multiplication, in f64. No cancellation-prone
    /// evaluation is involved, so the coefficients are accurate to a few ulps of the
    /// terms' magnitudes; well-scaled o and d (as [`Implicit`](super::Implicit) arranges) keep that
    /// small.
    pub fn along_ray(&self, o: DVec3, d: DVec3) -> Vec<f64> {
        let mut out = Vec::new();
        self.along_ray_into(o, d, &mut out);
        out
    }

    /// [`Poly3::along_ray`] into a reused buffer (no other allocation).
    pub fn along_ray_into(&self, o: DVec3, d: DVec3, out: &mut Vec<f64>) {
        const N: usize = MAX_DEGREE as usize + 1;
        let n = self.degree() as usize;
        out.clear();
        out.resize(n + 1, 0.0);
        // Powers o_a^k and d_a^k up to each axis's largest exponent.
        let mut po = [[1.0f64; N]; 3];
        let mut pd = [[1.0f64; N]; 3];
        for axis in 0..3 {
            let m = self.terms.iter().map(|t| t.exps[axis]).max().unwrap_or(0) as usize;
            for k in 1..=m {
                po[axis][k] = po[axis][k - 1] * o[axis];
                pd[axis][k] = pd[axis][k - 1] * d[axis];
            }
        }
        for t in &self.terms {
            // (o_a + t d_a)^e = Σ_j C(e, j) o_a^(e−j) d_a^j t^j for each axis.
            let mut f = [[0.0f64; N]; 3];
            for axis in 0..3 {
                let e = t.exps[axis] as usize;
                for j in 0..=e {
                    f[axis][j] = BINOMIAL[e][j] * po[axis][e - j] * pd[axis][j];
                }
            }
            let [ex, ey, ez] = t.exps.map(|e| e as usize);
            for a in 0..=ex {
                let ca = t.coeff * f[0][a];
                for b in 0..=ey {
                    let cab = ca * f[1][b];
                    for c in 0..=ez {
                        out[a + b + c] += cab * f[2][c];
                    }
                }
            }
        }
    }

    /// The sphere x² + y² + z² − r². Panics unless r is finite and positive (use
    /// [`Implicit::sphere`](super::Implicit::sphere) for a checked surface).
    pub fn sphere(r: f64) -> Self {
        assert!(r.is_finite() && r > 0.0, "sphere radius must be finite and positive");
        Self::built(Some(map_add(map_r2(), &map_constant(r * r), -1.0)), "sphere")
    }

    /// The ellipsoid x²/a² + y²/b² + z²/c² − 1 with semi-axes a, b, c. Panics unless
    /// they are finite and positive.
    pub fn ellipsoid(a: f64, b: f64, c: f64) -> Self {
        assert!([a, b, c].iter().all(|v| v.is_finite() && *v > 0.0), "ellipsoid semi-axes must be finite and positive");
        let mut m = PolyMap::new();
        m.insert([2, 0, 0], 1.0 / (a * a));
        m.insert([0, 2, 0], 1.0 / (b * b));
        m.insert([0, 0, 2], 1.0 / (c * c));
        m.insert([0, 0, 0], -1.0);
        Self::built(Some(m), "ellipsoid")
    }

    /// The infinite cylinder x² + y² − r² around the z axis (an [`Implicit`](super::Implicit)'s bounds
    /// clip it; it has no caps). Panics unless r is finite and positive.
    pub fn cylinder(r: f64) -> Self {
        assert!(r.is_finite() && r > 0.0, "cylinder radius must be finite and positive");
        let m = PolyMap::from([([2, 0, 0], 1.0), ([0, 2, 0], 1.0), ([0, 0, 0], -r * r)]);
        Self::built(Some(m), "cylinder")
    }

    /// The torus (x² + y² + z² + R² − r²)² − 4R²(x² + y²) around the z axis, with major
    /// radius R (centre to tube centre) and minor radius r (tube). Panics unless both are
    /// finite and positive.
    pub fn torus(major: f64, minor: f64) -> Self {
        assert!(
            major.is_finite() && minor.is_finite() && major > 0.0 && minor > 0.0,
            "torus radii must be finite and positive"
        );
        let k = major * major - minor * minor;
        let inner = map_add(map_r2(), &map_constant(k), 1.0);
        let rho2 = PolyMap::from([([2, 0, 0], 1.0), ([0, 2, 0], 1.0)]);
        let m = map_pow(&inner, 2).map(|sq| map_add(sq, &map_scale(rho2, 4.0 * major * major), -1.0));
        Self::built(m, "torus")
    }

    /// The sextic "heart surface" (x² + 9/4·y² + z² − 1)³ − x²z³ − 9/80·y²z³ (Taubin
    /// 1993; it points up the z axis, symmetric in x and y). Singular (∇F = 0) at its two
    /// cusps on the z axis.
    pub fn heart() -> Self {
        let base = PolyMap::from([([2, 0, 0], 1.0), ([0, 2, 0], 2.25), ([0, 0, 2], 1.0), ([0, 0, 0], -1.0)]);
        let tail = PolyMap::from([([2, 0, 3], 1.0), ([0, 2, 3], 9.0 / 80.0)]);
        Self::built(map_pow(&base, 3).map(|c| map_add(c, &tail, -1.0)), "heart")
    }

    /// Goursat's "tangle cube" x⁴ − 5x² + y⁴ − 5y² + z⁴ − 5z² + 11.8, a quartic of genus 5
    /// inside |x|, |y|, |z| ≤ 2.27.
    pub fn tangle_cube() -> Self {
        let m = PolyMap::from([
            ([4, 0, 0], 1.0),
            ([0, 4, 0], 1.0),
            ([0, 0, 4], 1.0),
            ([2, 0, 0], -5.0),
            ([0, 2, 0], -5.0),
            ([0, 0, 2], -5.0),
            ([0, 0, 0], 11.8),
        ]);
        Self::built(Some(m), "tangle cube")
    }
}

#[inline]
fn monomial(p: DVec3, e: [u8; 3]) -> f64 {
    p.x.powi(e[0] as i32) * p.y.powi(e[1] as i32) * p.z.powi(e[2] as i32)
}
