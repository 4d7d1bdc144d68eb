//! Implicit polynomial surfaces F(x, y, z) = 0 of any degree.
//!
//! The lecture's recipe ("Schnitt Strahl – implizite Fläche"): substitute the ray
//! P(t) = O + t·d into F, which gives a polynomial in t of the surface's degree n, and
//! find its smallest root in the ray's range — in closed form for n < 5, otherwise (or on
//! request) by Laguerre's method starting from the ray's entry into the surface's
//! bounding box ([`crate::roots`]).
//!
//! Convention: F < 0 inside, F > 0 outside, so ∇F points outward and the normal is
//! ∇F/|∇F| (not flipped towards the ray). All builders here follow it.

use crate::roots::{RootSolver, SolveReport, eval_poly_deriv, real_roots_in};
use crate::{Aabb, Ray, Shape, ShapeError, SurfaceHit};
use glam::{DVec3, Vec2, Vec3};
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
type PolyMap = BTreeMap<[u8; 3], f64>;

fn map_degree(p: &PolyMap) -> u32 {
    p.keys().map(|e| e.iter().map(|&x| x as u32).sum::<u32>()).max().unwrap_or(0)
}

fn map_constant(c: f64) -> PolyMap {
    PolyMap::from([([0, 0, 0], c)])
}

fn map_var(axis: usize) -> PolyMap {
    let mut e = [0u8; 3];
    e[axis] = 1;
    PolyMap::from([(e, 1.0)])
}

fn map_add(mut a: PolyMap, b: &PolyMap, sign: f64) -> PolyMap {
    for (e, c) in b {
        *a.entry(*e).or_insert(0.0) += sign * c;
    }
    a.retain(|_, c| *c != 0.0);
    a
}

fn map_scale(mut a: PolyMap, s: f64) -> PolyMap {
    a.values_mut().for_each(|c| *c *= s);
    a.retain(|_, c| *c != 0.0);
    a
}

/// a·b, or `None` if the product's degree would exceed [`MAX_DEGREE`].
fn map_mul(a: &PolyMap, b: &PolyMap) -> Option<PolyMap> {
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
fn map_pow(a: &PolyMap, n: u32) -> Option<PolyMap> {
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

    fn from_map(mut map: PolyMap) -> Result<Self, ShapeError> {
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
    /// terms' magnitudes; well-scaled o and d (as [`Implicit`] arranges) keep that
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
    /// [`Implicit::sphere`] for a checked surface).
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

    /// The infinite cylinder x² + y² − r² around the z axis (an [`Implicit`]'s bounds
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

// ---------------------------------------------------------------------------------------
// Parser
// ---------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, PartialEq)]
enum Tok {
    /// A number, and whether its literal was a plain unsigned integer.
    Num(f64, bool),
    Var(usize),
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    LParen,
    RParen,
    End,
}

fn parse_err(pos: usize, msg: impl std::fmt::Display) -> ShapeError {
    ShapeError::Invalid(format!("polynomial syntax error at character {pos}: {msg}"))
}

/// Tokens with their 1-based character positions.
fn tokenize(s: &str) -> Result<Vec<(Tok, usize)>, ShapeError> {
    let chars: Vec<char> = s.chars().collect();
    let mut toks = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let ch = chars[i];
        let pos = i + 1;
        let simple = match ch {
            c if c.is_whitespace() => {
                i += 1;
                continue;
            }
            '+' => Some(Tok::Plus),
            '-' => Some(Tok::Minus),
            '*' => Some(Tok::Star),
            '/' => Some(Tok::Slash),
            '^' => Some(Tok::Caret),
            '(' => Some(Tok::LParen),
            ')' => Some(Tok::RParen),
            'x' | 'X' => Some(Tok::Var(0)),
            'y' | 'Y' => Some(Tok::Var(1)),
            'z' | 'Z' => Some(Tok::Var(2)),
            _ => None,
        };
        if let Some(t) = simple {
            toks.push((t, pos));
            i += 1;
            continue;
        }
        if ch.is_ascii_digit() || ch == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // Exponent: e/E, optional sign, at least one digit.
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    while j < chars.len() && chars[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                } else {
                    return Err(parse_err(i + 1, "exponent of a number needs digits"));
                }
            }
            let text: String = chars[start..i].iter().collect();
            let v: f64 = text.parse().map_err(|_| parse_err(pos, format!("invalid number '{text}'")))?;
            if !v.is_finite() {
                return Err(parse_err(pos, format!("number '{text}' is out of range")));
            }
            let integer = text.chars().all(|c| c.is_ascii_digit());
            toks.push((Tok::Num(v, integer), pos));
            continue;
        }
        return Err(parse_err(pos, format!("unexpected character '{ch}'")));
    }
    toks.push((Tok::End, chars.len() + 1));
    Ok(toks)
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    at: usize,
}

impl Parser {
    fn peek(&self) -> (Tok, usize) {
        self.toks[self.at]
    }

    fn bump(&mut self) -> (Tok, usize) {
        let t = self.toks[self.at];
        if t.0 != Tok::End {
            self.at += 1;
        }
        t
    }

    /// expr := ['+'|'-'] term {('+'|'-') term}  (the sign is handled by `unary`).
    fn expr(&mut self) -> Result<PolyMap, ShapeError> {
        let mut acc = self.term()?;
        loop {
            let sign = match self.peek().0 {
                Tok::Plus => 1.0,
                Tok::Minus => -1.0,
                _ => return Ok(acc),
            };
            self.bump();
            let t = self.term()?;
            acc = map_add(acc, &t, sign);
        }
    }

    /// term := unary {('*' unary) | ('/' unary) | power}: explicit or implicit
    /// (juxtaposition) products, and division by non-zero constants.
    fn term(&mut self) -> Result<PolyMap, ShapeError> {
        let mut acc = self.unary()?;
        loop {
            let (tok, pos) = self.peek();
            let rhs = match tok {
                Tok::Star => {
                    self.bump();
                    self.unary()?
                }
                Tok::Slash => {
                    self.bump();
                    let at = self.peek().1;
                    let div = self.unary()?;
                    let c = match (div.len(), div.get(&[0, 0, 0])) {
                        (1, Some(&c)) => c,
                        _ => return Err(parse_err(at, "division only by a non-zero number")),
                    };
                    let q = 1.0 / c;
                    if !q.is_finite() {
                        return Err(parse_err(at, "division by a number too close to zero"));
                    }
                    acc = map_scale(acc, q);
                    continue;
                }
                Tok::Num(..) | Tok::Var(_) | Tok::LParen => self.power()?,
                _ => return Ok(acc),
            };
            acc = map_mul(&acc, &rhs)
                .ok_or_else(|| parse_err(pos, format!("product exceeds the maximum degree {MAX_DEGREE}")))?;
        }
    }

    /// unary := ('+'|'-') unary | power.
    fn unary(&mut self) -> Result<PolyMap, ShapeError> {
        match self.peek().0 {
            Tok::Minus => {
                self.bump();
                Ok(map_scale(self.unary()?, -1.0))
            }
            Tok::Plus => {
                self.bump();
                self.unary()
            }
            _ => self.power(),
        }
    }

    /// power := primary ['^' unsigned-integer].
    fn power(&mut self) -> Result<PolyMap, ShapeError> {
        let base = self.primary()?;
        if self.peek().0 != Tok::Caret {
            return Ok(base);
        }
        let (_, caret) = self.bump();
        match self.bump() {
            (Tok::Num(v, true), pos) => {
                if v > MAX_DEGREE as f64 {
                    return Err(parse_err(pos, format!("exponent {v} exceeds the maximum degree {MAX_DEGREE}")));
                }
                map_pow(&base, v as u32)
                    .ok_or_else(|| parse_err(caret, format!("power exceeds the maximum degree {MAX_DEGREE}")))
            }
            (_, pos) => Err(parse_err(pos, "expected a non-negative integer exponent after '^'")),
        }
    }

    /// primary := number | x | y | z | '(' expr ')'.
    fn primary(&mut self) -> Result<PolyMap, ShapeError> {
        match self.bump() {
            (Tok::Num(v, _), _) => Ok(map_constant(v)),
            (Tok::Var(a), _) => Ok(map_var(a)),
            (Tok::LParen, open) => {
                let inner = self.expr()?;
                match self.bump() {
                    (Tok::RParen, _) => Ok(inner),
                    (_, pos) => Err(parse_err(pos, format!("expected ')' to close the '(' at character {open}"))),
                }
            }
            (Tok::End, pos) => Err(parse_err(pos, "unexpected end of input")),
            (t, pos) => Err(parse_err(pos, format!("unexpected {}", tok_name(t)))),
        }
    }
}

fn tok_name(t: Tok) -> &'static str {
    match t {
        Tok::Num(..) => "number",
        Tok::Var(_) => "variable",
        Tok::Plus => "'+'",
        Tok::Minus => "'-'",
        Tok::Star => "'*'",
        Tok::Slash => "'/'",
        Tok::Caret => "'^'",
        Tok::LParen => "'('",
        Tok::RParen => "')'",
        Tok::End => "end of input",
    }
}

/// Parses a polynomial in x, y, z, e.g. `"(x^2 + y^2 + z^2 + 3.75)^2 - 16 (x^2 + y^2)"`.
///
/// Grammar: sums and differences of products; factors are numbers (`2`, `3.5`, `1e-3`),
/// the variables `x`, `y`, `z`, or parenthesised sub-expressions, each optionally raised
/// to a non-negative integer power `^n`; products by `*` or by juxtaposition (`2 x y`,
/// `2xy`); division by a non-zero constant (`9/4 y^2`, `x^2/(2^2)`); unary `-`/`+`.
/// Everything is expanded exactly by polynomial arithmetic.
/// Errors name the (1-based) character position: unknown characters, `x^^2`, `x^-1`,
/// `x^2.5`, `1/x`, unbalanced parentheses, numbers that overflow (`1e999`), a degree above
/// [`MAX_DEGREE`], or a polynomial that is identically zero.
pub fn parse(s: &str) -> Result<Poly3, ShapeError> {
    let mut p = Parser { toks: tokenize(s)?, at: 0 };
    let map = p.expr()?;
    match p.peek() {
        (Tok::End, _) => {}
        (Tok::RParen, pos) => return Err(parse_err(pos, "unmatched ')'")),
        (t, pos) => return Err(parse_err(pos, format!("unexpected {}", tok_name(t)))),
    }
    Poly3::from_map(map)
}

// ---------------------------------------------------------------------------------------
// The shape
// ---------------------------------------------------------------------------------------

/// The clipping box is the bounds grown by this fraction of their diagonal on every
/// side, so that a surface touching its tight box (a sphere in [−r, r]³) has its root
/// strictly inside the parameter interval, not on its rounded end.
const PAD_REL: f64 = 1e-6;

/// Roots at s ≤ `S_EPS` (in units of the box diagonal from the clipped start) are
/// ignored: only the spurious root at the ray's own origin when that lies on the surface
/// to solver precision. It is no substitute for offsetting secondary rays' origins (the
/// tracer's job): f32 offsets are ~1e-7 relative, 100× larger.
const S_EPS: f64 = 1e-9;

/// An implicit polynomial surface F = 0 inside a bounding box.
#[derive(Clone, Debug, PartialEq)]
pub struct Implicit {
    /// F, negative inside.
    pub poly: Poly3,
    /// A box enclosing the part of the surface to render; rays are clipped to it (so it
    /// also cuts open unbounded surfaces such as [`Poly3::cylinder`]).
    pub bounds: Aabb,
    /// The root finder.
    pub solver: RootSolver,
}

impl Implicit {
    /// The surface F = 0 within `bounds` (finite, non-empty, not a single point).
    pub fn new(poly: Poly3, bounds: Aabb, solver: RootSolver) -> Result<Self, ShapeError> {
        if !(bounds.min.is_finite() && bounds.max.is_finite()) || bounds.is_empty() {
            return Err(ShapeError::Invalid(format!(
                "implicit surface bounds {bounds:?} must be finite and non-empty"
            )));
        }
        if bounds.min == bounds.max {
            return Err(ShapeError::Invalid("implicit surface bounds must not be a single point".into()));
        }
        Ok(Self { poly, bounds, solver })
    }

    /// A sphere of radius r at the origin, bounded by [−r, r]³.
    pub fn sphere(r: f32, solver: RootSolver) -> Result<Self, ShapeError> {
        if !(r.is_finite() && r > 0.0) {
            return Err(ShapeError::Invalid(format!("sphere radius {r} must be finite and positive")));
        }
        Self::new(Poly3::sphere(r as f64), Aabb { min: Vec3::splat(-r), max: Vec3::splat(r) }, solver)
    }

    /// A torus around the z axis with major radius R and tube radius r, bounded by
    /// [−(R + r), R + r]² × [−r, r].
    pub fn torus(major: f32, minor: f32, solver: RootSolver) -> Result<Self, ShapeError> {
        if !(major.is_finite() && minor.is_finite() && major > 0.0 && minor > 0.0) {
            return Err(ShapeError::Invalid(format!("torus radii {major}, {minor} must be finite and positive")));
        }
        let e = Vec3::new(major + minor, major + minor, minor);
        Self::new(Poly3::torus(major as f64, minor as f64), Aabb { min: -e, max: e }, solver)
    }

    /// The degree-6 heart surface ([`Poly3::heart`]) in [−1.2, 1.2] × [−0.8, 0.8] ×
    /// [−1.05, 1.3] (its extent is about ±1.14, ±0.69, [−1, 1.24]; a test checks that
    /// F > 0 all over the box's surface). The closed-form solver falls back to Laguerre.
    pub fn heart(solver: RootSolver) -> Result<Self, ShapeError> {
        let bounds = Aabb { min: Vec3::new(-1.2, -0.8, -1.05), max: Vec3::new(1.2, 0.8, 1.3) };
        Self::new(Poly3::heart(), bounds, solver)
    }

    /// [`Shape::intersect`] with the root finder's report (for counting non-convergence).
    ///
    /// The ray is clipped to the (slightly padded) bounds in f64, giving [t₀, t₁]
    /// within (t_min, t_max). The polynomial is then set up in a shifted, scaled
    /// parameter s with t = t₀ + s·L/|d|, L the box diagonal: the origin moves to the
    /// entry point o + t₀·d and the direction becomes d/|d|·L, so that s runs over
    /// [0, ≤ 1] whatever the ray's origin distance and direction length, the
    /// coefficients are well scaled, and Laguerre's start value s = 0 is the lecture's
    /// "entry into the bounding box". Real roots in [ε, s₁] (ε = 1e-9, see `S_EPS`) are
    /// tried in ascending order; each gets one guarded Newton step, must map to an f32
    /// t strictly inside (t_min, t_max) and must have a finite non-zero ∇F (singular
    /// points such as the heart's cusps are skipped).
    pub fn intersect_report(&self, ray: &Ray) -> (Option<SurfaceHit>, SolveReport) {
        let mut report = SolveReport::default();
        let o = ray.origin.as_dvec3();
        let d = ray.dir.as_dvec3();
        let len = d.length();
        if !(len > 0.0 && len.is_finite() && o.is_finite()) {
            return (None, report);
        }
        let bmin = self.bounds.min.as_dvec3();
        let bmax = self.bounds.max.as_dvec3();
        let diag = (bmax - bmin).length();
        let pad = DVec3::splat(PAD_REL * diag);
        let (bmin, bmax) = (bmin - pad, bmax + pad);
        let mut t0 = ray.t_min as f64;
        let mut t1 = ray.t_max as f64;
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < bmin[a] || o[a] > bmax[a] {
                    return (None, report);
                }
            } else {
                let inv = 1.0 / d[a];
                let (ta, tb) = ((bmin[a] - o[a]) * inv, (bmax[a] - o[a]) * inv);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0.is_nan() || t1.is_nan() || t0 > t1 {
            return (None, report);
        }
        let scale = diag / len; // t = t0 + s·scale
        let q = o + t0 * d;
        let u = d * scale;
        let coeffs = self.poly.along_ray(q, u);
        let s_hi = (t1 - t0) / scale;
        let mut roots = Vec::with_capacity(coeffs.len());
        report = real_roots_in(&coeffs, S_EPS, s_hi, self.solver, &mut roots);
        for &s in &roots {
            let s = newton_step(&coeffs, s);
            if !(s > S_EPS && s <= s_hi) {
                continue;
            }
            let t = t0 + s * scale;
            let t32 = t as f32;
            if !(t32 > ray.t_min && t32 < ray.t_max) {
                continue;
            }
            let p = q + s * u;
            let g = self.poly.gradient(p);
            let g2 = g.length_squared();
            if !(g2 > 0.0 && g2.is_finite()) {
                continue;
            }
            let n = (g / g2.sqrt()).as_vec3();
            return (Some(SurfaceHit { t: t32, p: p.as_vec3(), n }), report);
        }
        (None, report)
    }
}

/// One Newton step on the ray polynomial, kept only if it lowers |P|.
fn newton_step(c: &[f64], s: f64) -> f64 {
    let (p, dp) = eval_poly_deriv(c, s);
    if p == 0.0 || dp == 0.0 {
        return s;
    }
    let s1 = s - p / dp;
    if s1.is_finite() && eval_poly_deriv(c, s1).0.abs() < p.abs() { s1 } else { s }
}

impl Shape for Implicit {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.intersect_report(ray).0
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// 0: the area of an implicit surface has no closed form and it cannot be sampled,
    /// so implicit surfaces cannot be lights.
    fn area(&self) -> f32 {
        0.0
    }

    /// `None`: implicit surfaces cannot be sampled by area (see [`Shape::area`]).
    fn sample_area(&self, _u: Vec2) -> Option<(Vec3, Vec3)> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::eval_poly;
    use rng::Pcg32;

    const LAG: RootSolver = RootSolver::Laguerre { polish: true };
    const SOLVERS: [RootSolver; 3] =
        [RootSolver::ClosedForm, RootSolver::Laguerre { polish: true }, RootSolver::Laguerre { polish: false }];

    fn rand_point(rng: &mut Pcg32, s: f64) -> DVec3 {
        DVec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s))
    }

    fn sample_polys() -> Vec<Poly3> {
        vec![
            Poly3::sphere(1.5),
            Poly3::ellipsoid(1.0, 2.0, 0.5),
            Poly3::cylinder(0.7),
            Poly3::torus(2.0, 0.5),
            Poly3::heart(),
            Poly3::tangle_cube(),
            parse("3 x^3 y - 2.5 x y z^2 + 0.25 z^5 - x + 7").unwrap(),
        ]
    }

    #[test]
    fn along_ray_agrees_with_eval() {
        let mut rng = Pcg32::seed_from_u64(10);
        for poly in sample_polys() {
            for _ in 0..50 {
                let o = rand_point(&mut rng, 3.0);
                let d = rand_point(&mut rng, 1.0);
                let c = poly.along_ray(o, d);
                assert_eq!(c.len(), poly.degree() as usize + 1);
                for t in [-2.0, -0.3, 0.0, 0.7, 1.9, 4.0] {
                    let p = o + t * d;
                    let (want, got) = (poly.eval(p), eval_poly(&c, t));
                    let scale = poly.eval_abs(p).max(1.0);
                    assert!((want - got).abs() <= 1e-10 * scale, "{poly:?} at t={t}: {want} vs {got}");
                }
            }
        }
    }

    #[test]
    fn gradient_agrees_with_finite_differences() {
        let mut rng = Pcg32::seed_from_u64(11);
        let h = 1e-5;
        for poly in sample_polys() {
            for _ in 0..50 {
                let p = rand_point(&mut rng, 2.0);
                let g = poly.gradient(p);
                for axis in 0..3 {
                    let mut e = DVec3::ZERO;
                    e[axis] = h;
                    let fd = (poly.eval(p + e) - poly.eval(p - e)) / (2.0 * h);
                    let scale = poly.eval_abs(p).max(1.0);
                    assert!((fd - g[axis]).abs() <= 1e-6 * scale, "{poly:?} at {p}: ∂{axis} {} vs {fd}", g[axis]);
                }
            }
        }
    }

    #[test]
    fn builders_have_the_documented_values() {
        assert_eq!(Poly3::sphere(2.0).eval(DVec3::new(2.0, 0.0, 0.0)), 0.0);
        assert!(Poly3::sphere(2.0).eval(DVec3::ZERO) < 0.0);
        assert_eq!(Poly3::ellipsoid(1.0, 2.0, 4.0).eval(DVec3::new(0.0, 2.0, 0.0)), 0.0);
        assert_eq!(Poly3::ellipsoid(1.0, 2.0, 4.0).eval(DVec3::new(0.0, 0.0, 4.0)), 0.0);
        assert_eq!(Poly3::cylinder(0.5).eval(DVec3::new(0.0, 0.5, 123.0)), 0.0);
        let torus = Poly3::torus(2.0, 0.5);
        assert_eq!(torus.degree(), 4);
        for p in [DVec3::new(2.5, 0.0, 0.0), DVec3::new(0.0, -1.5, 0.0), DVec3::new(2.0, 0.0, 0.5)] {
            assert_eq!(torus.eval(p), 0.0, "{p}");
        }
        assert!(torus.eval(DVec3::new(2.0, 0.0, 0.0)) < 0.0 && torus.eval(DVec3::ZERO) > 0.0);
        let heart = Poly3::heart();
        assert_eq!(heart.degree(), 6);
        assert!(heart.eval(DVec3::ZERO) < 0.0);
        assert_eq!(heart.eval(DVec3::new(0.0, 0.0, -1.0)), 0.0);
        assert_eq!(Poly3::tangle_cube().degree(), 4);
    }

    #[test]
    fn poly3_new_normalises_and_rejects() {
        let t = |coeff, exps| Term { coeff, exps };
        let p = Poly3::new(vec![t(1.0, [2, 0, 0]), t(2.0, [0, 0, 0]), t(-1.0, [0, 0, 0]), t(0.0, [0, 0, 7])]).unwrap();
        assert_eq!(p.terms().len(), 2);
        assert_eq!(p.degree(), 2);
        assert!(Poly3::new(vec![]).is_err());
        assert!(Poly3::new(vec![t(1.0, [1, 0, 0]), t(-1.0, [1, 0, 0])]).is_err());
        assert!(Poly3::new(vec![t(f64::NAN, [1, 0, 0])]).is_err());
        assert!(Poly3::new(vec![t(f64::INFINITY, [1, 0, 0])]).is_err());
        assert!(Poly3::new(vec![t(1.0, [20, 20, 0])]).is_err());
    }

    #[test]
    fn parse_round_trips_the_builders() {
        let mut rng = Pcg32::seed_from_u64(12);
        let cases = [
            ("(x^2 + y^2 + z^2 + 2^2 - 0.5^2)^2 - 4*2^2 (x^2 + y^2)", Poly3::torus(2.0, 0.5)),
            ("(x^2+y^2+z^2 + 3.75)^2 - 16x^2 - 16 y^2", Poly3::torus(2.0, 0.5)),
            ("(x^2 + 2.25 y^2 + z^2 - 1)^3 - x^2 z^3 - 0.1125 y^2 z^3", Poly3::heart()),
            ("(x^2 + 9/4 y^2 + z^2 - 1)^3 - x^2 z^3 - 9/80 y^2 z^3", Poly3::heart()),
            ("x*x + y y + Z^2 - 2.25", Poly3::sphere(1.5)),
            ("x^4 - 5x^2 + y^4 - 5 y^2 + z^4 - 5 z^2 + 11.8", Poly3::tangle_cube()),
            ("-(-x^2) + y^2 - 0.49", Poly3::cylinder(0.7)),
            ("x^2 + 0.25 y^2 + 4e0 z^2 - 1", Poly3::ellipsoid(1.0, 2.0, 0.5)),
        ];
        for (text, built) in &cases {
            let parsed = parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(parsed.degree(), built.degree(), "{text}");
            for _ in 0..100 {
                let p = rand_point(&mut rng, 2.0);
                let (a, b) = (parsed.eval(p), built.eval(p));
                assert!((a - b).abs() <= 1e-12 * built.eval_abs(p).max(1.0), "{text} at {p}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn parse_accepts_the_grammar() {
        let p = parse("2x y^2 * -3 + 1.5e-1 z - +4").unwrap();
        let q = DVec3::new(1.5, -2.0, 3.0);
        assert!((p.eval(q) - (2.0 * 1.5 * 4.0 * -3.0 + 0.15 * 3.0 - 4.0)).abs() < 1e-12);
        let p = parse("(x + 1)^2 (y - 1)").unwrap();
        assert!((p.eval(q) - 6.25 * -3.0).abs() < 1e-12);
        assert_eq!(parse("x^0 + x").unwrap().eval(q), 2.5);
        assert_eq!(parse("x^2/4 - 2/4/2 y").unwrap().eval(q), 1.5 * 1.5 / 4.0 + 0.5);
        assert_eq!(parse("  x\t+\ny ").unwrap().degree(), 1);
    }

    #[test]
    fn parse_rejects_garbage_with_positions() {
        let cases = [
            ("x^^2", 3),
            ("(x+1", 5),
            ("x^-1", 3),
            ("1e999", 1),
            ("x^2.5", 3),
            ("x + w", 5),
            ("x +", 4),
            ("", 1),
            ("x)", 2),
            ("1e", 2),
            ("1/x", 3),
            ("x/(1-1)", 3),
            ("x*/y", 3),
            ("x - x", 0),
            ("(x+y+z)^40", 0),
            ("3 x ^ 99", 7),
        ];
        for (text, pos) in cases {
            let err = parse(text).expect_err(text);
            let ShapeError::Invalid(msg) = &err;
            if pos > 0 {
                assert!(msg.contains(&format!("character {pos}:")), "{text}: {msg}");
            }
        }
    }

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(Vec3::from(o), Vec3::from(d))
    }

    #[test]
    fn sphere_matches_the_analytic_solution() {
        let mut rng = Pcg32::seed_from_u64(13);
        let r = 1.5f32;
        for solver in SOLVERS {
            let s = Implicit::sphere(r, solver).unwrap();
            let mut hits = 0;
            for _ in 0..500 {
                let o = rand_point(&mut rng, 4.0).as_vec3();
                let d = rand_point(&mut rng, 1.6).as_vec3() - o;
                let ry = Ray::new(o, d);
                // Analytic in f64: |o + t d|² = r².
                let (o64, d64) = (o.as_dvec3(), d.as_dvec3());
                let want =
                    crate::roots::quadratic_f64(d64.dot(d64), 2.0 * o64.dot(d64), o64.dot(o64) - (r as f64).powi(2))
                        .and_then(|(t0, t1)| [t0, t1].into_iter().find(|&t| t > 0.0));
                let got = s.intersect(&ry);
                match (want, got) {
                    (None, None) => {}
                    (Some(t), Some(h)) => {
                        hits += 1;
                        assert!((h.t as f64 - t).abs() <= 1e-5 * t.max(1.0), "{solver:?}: {} vs {t}", h.t);
                        assert!((h.p.length() - r).abs() < 1e-5);
                        assert!((h.n - h.p / r).length() < 1e-5, "normal {} at {}", h.n, h.p);
                    }
                    _ => panic!("{solver:?} {ry:?}: analytic {want:?}, implicit {got:?}"),
                }
            }
            assert!(hits > 100, "{hits}");
        }
    }

    #[test]
    fn torus_axis_hole_tangent_and_inside_rays() {
        let (big, small) = (2.0f32, 0.5f32);
        for solver in SOLVERS {
            let t = Implicit::torus(big, small, solver).unwrap();
            // Along the x axis from (−5, 0, 0): the outer equator at x = −(R + r).
            let h = t.intersect(&ray([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0])).expect("axis ray");
            assert!((h.t - (5.0 - (big + small))).abs() < 1e-5, "{solver:?} {h:?}");
            assert!((h.n - Vec3::NEG_X).length() < 1e-6);
            // Non-unit direction: t scales.
            let h = t.intersect(&ray([-5.0, 0.0, 0.0], [4.0, 0.0, 0.0])).unwrap();
            assert!((h.t - (5.0 - (big + small)) / 4.0).abs() < 1e-6, "{h:?}");
            // Through the hole along z: misses.
            assert_eq!(t.intersect(&ray([0.0, 0.0, -5.0], [0.0, 0.0, 1.0])), None, "{solver:?}");
            assert_eq!(t.intersect(&ray([0.3, -0.2, 5.0], [0.0, 0.0, -1.0])), None, "{solver:?}");
            // Down onto the tube's top.
            let h = t.intersect(&ray([0.0, 2.0, 5.0], [0.0, 0.0, -1.0])).unwrap();
            assert!((h.t - 4.5).abs() < 1e-5 && (h.n - Vec3::Z).length() < 1e-5, "{h:?}");
            // Tangent: the line z = r touches the tube's top at x = −R (a double root).
            let (h, rep) = t.intersect_report(&ray([-5.0, 0.0, small], [1.0, 0.0, 0.0]));
            let h = h.unwrap_or_else(|| panic!("{solver:?}: tangent ray missed"));
            assert!((h.t - (5.0 - big)).abs() < 1e-4, "{solver:?} {h:?}");
            assert!((h.n - Vec3::Z).length() < 1e-3, "{solver:?} {h:?}");
            assert_eq!(rep.not_converged, 0);
            // Just above the tangent: a miss.
            assert_eq!(t.intersect(&ray([-5.0, 0.0, small + 1e-3], [1.0, 0.0, 0.0])), None);
            // Starting inside the tube at its centre line: exits at distance r, outward normal.
            let h = t.intersect(&ray([big, 0.0, 0.0], [1.0, 0.0, 0.0])).unwrap();
            assert!((h.t - small).abs() < 1e-6 && (h.n - Vec3::X).length() < 1e-6, "{h:?}");
            // Starting inside the box, in the hole: the inner equator at x = R − r.
            let h = t.intersect(&ray([0.0, 0.0, 0.0], [1.0, 0.0, 0.0])).unwrap();
            assert!((h.t - (big - small)).abs() < 1e-6 && (h.n - Vec3::NEG_X).length() < 1e-6, "{h:?}");
        }
    }

    #[test]
    fn segment_limits_are_respected() {
        let t = Implicit::torus(2.0, 0.5, RootSolver::ClosedForm).unwrap();
        let o = Vec3::new(-5.0, 0.0, 0.0);
        // Hits along +x at t = 2.5, 3.5, 6.5, 7.5.
        assert_eq!(t.intersect(&Ray::segment(o, Vec3::X, 0.0, 2.4)), None);
        let h = t.intersect(&Ray::segment(o, Vec3::X, 2.6, 100.0)).unwrap();
        assert!((h.t - 3.5).abs() < 1e-5 && (h.n - Vec3::X).length() < 1e-5, "{h:?}");
        let h = t.intersect(&Ray::segment(o, Vec3::X, 3.6, 100.0)).unwrap();
        assert!((h.t - 6.5).abs() < 1e-5, "{h:?}");
        assert_eq!(t.intersect(&Ray::segment(o, Vec3::X, 7.6, 100.0)), None);
        // A ray that starts on the surface and leaves it does not hit itself.
        let start = Vec3::new(2.5, 0.0, 0.0);
        assert_eq!(t.intersect(&Ray::new(start, Vec3::X)), None);
        let h = t.intersect(&Ray::new(start, Vec3::NEG_X)).unwrap();
        assert!((h.t - 1.0).abs() < 1e-5, "{h:?}");
        // Behind the ray, and pointing away from the box.
        assert_eq!(t.intersect(&Ray::new(o, Vec3::NEG_X)), None);
        assert_eq!(t.intersect(&Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Y)), None);
        // Degenerate directions.
        assert_eq!(t.intersect(&Ray::new(o, Vec3::ZERO)), None);
        assert_eq!(t.intersect(&Ray::new(o, Vec3::new(f32::NAN, 0.0, 0.0))), None);
    }

    #[test]
    fn heart_bounds_enclose_the_surface() {
        let s = Implicit::heart(LAG).unwrap();
        let (lo, hi) = (s.bounds.min.as_dvec3(), s.bounds.max.as_dvec3());
        let n = 60;
        let mut min_f = f64::INFINITY;
        // F > 0 all over the box's surface: sample each face on an n×n grid.
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in [lo[axis], hi[axis]] {
                for i in 0..=n {
                    for j in 0..=n {
                        let mut p = DVec3::ZERO;
                        p[axis] = side;
                        p[u] = lo[u] + (hi[u] - lo[u]) * i as f64 / n as f64;
                        p[v] = lo[v] + (hi[v] - lo[v]) * j as f64 / n as f64;
                        min_f = min_f.min(s.poly.eval(p));
                    }
                }
            }
        }
        println!("heart: min F on the bounding box surface {min_f:e}");
        assert!(min_f > 0.0, "{min_f}");
        // And the surface reaches close to the box (the bounds are reasonably tight):
        // rays along each axis from outside hit within 0.25 of the box.
        for (o, d) in [
            ([-5.0, 0.0, 0.3], [1.0, 0.0, 0.0]),
            ([0.0, -5.0, 0.0], [0.0, 1.0, 0.0]),
            ([0.0, 0.0, -5.0], [0.0, 0.0, 1.0]),
            ([0.5, 0.0, 5.0], [0.0, 0.0, -1.0]),
        ] {
            let h = s.intersect(&ray(o, d)).expect("axis ray hits the heart");
            let entry = s.bounds.hit(&ray(o, d), f32::INFINITY).unwrap();
            assert!(h.t - entry < 0.25, "{o:?}: hit {} entry {entry}", h.t);
        }
    }

    #[test]
    fn heart_hits_lie_on_the_surface_with_true_normals() {
        let mut rng = Pcg32::seed_from_u64(14);
        for solver in [RootSolver::ClosedForm, LAG] {
            let s = Implicit::heart(solver).unwrap();
            let mut hits = 0;
            for _ in 0..300 {
                let o = (rand_point(&mut rng, 1.0).normalize() * 4.0).as_vec3();
                let target = rand_point(&mut rng, 0.6).as_vec3();
                let r = Ray::new(o, target - o);
                let (h, rep) = s.intersect_report(&r);
                assert!(rep.used_laguerre, "degree 6 always uses Laguerre");
                assert_eq!(rep.not_converged, 0);
                let Some(h) = h else { continue };
                hits += 1;
                let p = h.p.as_dvec3();
                // |F| small relative to its terms, and the normal parallel to a
                // finite-difference gradient.
                assert!(s.poly.eval(p).abs() <= 1e-5 * s.poly.eval_abs(p).max(1.0), "F = {}", s.poly.eval(p));
                let e = 1e-6;
                let fd = DVec3::new(
                    s.poly.eval(p + DVec3::X * e) - s.poly.eval(p - DVec3::X * e),
                    s.poly.eval(p + DVec3::Y * e) - s.poly.eval(p - DVec3::Y * e),
                    s.poly.eval(p + DVec3::Z * e) - s.poly.eval(p - DVec3::Z * e),
                );
                if fd.length() < 1e-9 {
                    continue; // near a cusp
                }
                assert!(fd.normalize().dot(h.n.as_dvec3()) > 1.0 - 1e-6, "{} vs {}", h.n, fd.normalize());
                // And perpendicular to finite-difference tangents: neighbouring rays hit at
                // p′ with (p′ − p)·n = O(|p′ − p|²).
                for off in [Vec3::X, Vec3::Y, Vec3::Z] {
                    let delta = 1e-3;
                    let r2 = Ray::new(o, target + off * delta - o);
                    if let Some(h2) = s.intersect(&r2) {
                        let dp = h2.p - h.p;
                        if dp.length() < 1e-2 {
                            assert!(dp.dot(h.n).abs() < 0.05 * dp.length() + 1e-5, "dp {dp} n {}", h.n);
                        }
                    }
                }
                // The ray's entry side: the normal faces the ray for a hit from outside.
                assert!(h.n.dot(r.dir) < 0.0 || s.poly.eval(o.as_dvec3()) < 0.0);
            }
            assert!(hits > 100, "{hits}");
        }
    }

    /// Traces `n` random rays (fixed seed) aimed into `a`'s box with both shapes;
    /// returns (hits, disagreements, non-converged roots of `b`). A disagreement is a
    /// hit/miss mismatch, a t differing by more than 1e-4 relative, or normals apart.
    fn compare(a: &Implicit, b: &Implicit, n: usize, seed: u64) -> (usize, usize, u32) {
        let mut rng = Pcg32::seed_from_u64(seed);
        let (mut disagree, mut hits, mut not_converged) = (0, 0, 0);
        let (lo, hi) = (a.bounds.min.as_dvec3(), a.bounds.max.as_dvec3());
        for _ in 0..n {
            let o = (rand_point(&mut rng, 1.0).normalize() * rng.range(1.5, 4.0) * hi.length()).as_vec3();
            let target = DVec3::new(rng.range(lo.x, hi.x), rng.range(lo.y, hi.y), rng.range(lo.z, hi.z)).as_vec3();
            let r = Ray::new(o, (target - o) * rng.range(0.1, 3.0) as f32);
            let (x, _) = a.intersect_report(&r);
            let (y, rep) = b.intersect_report(&r);
            not_converged += rep.not_converged;
            match (x, y) {
                (None, None) => {}
                (Some(x), Some(y)) => {
                    hits += 1;
                    if (x.t - y.t).abs() > 1e-4 * x.t.abs().max(1e-3) || (x.n - y.n).length() > 1e-3 {
                        disagree += 1;
                        println!("disagree: {r:?}: {x:?} vs {y:?}");
                    }
                }
                _ => {
                    disagree += 1;
                    println!("hit/miss disagree: {r:?}: {x:?} vs {y:?}");
                }
            }
        }
        (hits, disagree, not_converged)
    }

    #[test]
    fn closed_form_and_laguerre_agree_on_random_rays() {
        let n = 1000;
        let torus = Implicit::torus(2.0, 0.5, RootSolver::ClosedForm).unwrap();
        let (hits, disagree, not_converged) = compare(&torus, &Implicit { solver: LAG, ..torus.clone() }, n, 15);
        println!(
            "torus, closed form vs Laguerre: {hits} hits of {n} rays, {disagree} disagreements, \
             {not_converged} non-converged roots"
        );
        assert!(hits > 300, "{hits}");
        assert!(disagree <= n / 200, "{disagree}");
        assert_eq!(not_converged, 0);
        // The tangle cube: a quartic of genus 5, many grazing rays.
        let b = Aabb { min: Vec3::splat(-2.27), max: Vec3::splat(2.27) };
        let tangle = Implicit::new(Poly3::tangle_cube(), b, RootSolver::ClosedForm).unwrap();
        let (hits, disagree, not_converged) = compare(&tangle, &Implicit { solver: LAG, ..tangle.clone() }, n, 16);
        println!(
            "tangle cube, closed form vs Laguerre: {hits} hits, {disagree} disagreements, {not_converged} non-converged"
        );
        assert!(hits > 300 && disagree <= n / 200 && not_converged == 0);
        // The sextic heart: Laguerre with and without polishing.
        let heart = Implicit::heart(LAG).unwrap();
        let raw = Implicit { solver: RootSolver::Laguerre { polish: false }, ..heart.clone() };
        let (hits, disagree, not_converged) = compare(&heart, &raw, n, 17);
        println!(
            "heart, polished vs unpolished Laguerre: {hits} hits, {disagree} disagreements, \
             {not_converged} non-converged"
        );
        assert!(hits > 300 && disagree <= n / 200 && not_converged == 0);
    }

    #[test]
    fn implicit_validates_its_parameters() {
        let p = Poly3::sphere(1.0);
        let bad = [
            Aabb::EMPTY,
            Aabb { min: Vec3::ZERO, max: Vec3::new(1.0, f32::INFINITY, 1.0) },
            Aabb { min: Vec3::splat(f32::NAN), max: Vec3::ONE },
            Aabb { min: Vec3::ONE, max: Vec3::ONE },
        ];
        for b in bad {
            assert!(Implicit::new(p.clone(), b, LAG).is_err(), "{b:?}");
        }
        assert!(Implicit::sphere(0.0, LAG).is_err());
        assert!(Implicit::sphere(f32::NAN, LAG).is_err());
        assert!(Implicit::torus(1.0, -0.1, LAG).is_err());
        let s = Implicit::torus(2.0, 0.5, LAG).unwrap();
        assert_eq!(s.bounds(), Aabb { min: Vec3::new(-2.5, -2.5, -0.5), max: Vec3::new(2.5, 2.5, 0.5) });
        assert_eq!(s.area(), 0.0);
        assert_eq!(s.sample_area(Vec2::new(0.5, 0.5)), None);
    }

    #[test]
    fn cylinder_is_clipped_by_its_bounds() {
        let b = Aabb { min: Vec3::new(-1.0, -1.0, -2.0), max: Vec3::new(1.0, 1.0, 2.0) };
        let s = Implicit::new(Poly3::cylinder(1.0), b, RootSolver::ClosedForm).unwrap();
        let h = s.intersect(&ray([-5.0, 0.0, 1.5], [1.0, 0.0, 0.0])).unwrap();
        assert!((h.t - 4.0).abs() < 1e-6 && (h.n - Vec3::NEG_X).length() < 1e-6);
        // Above the box: no surface there.
        assert_eq!(s.intersect(&ray([-5.0, 0.0, 2.5], [1.0, 0.0, 0.0])), None);
        // Along the axis, inside: never reaches the wall (no caps).
        assert_eq!(s.intersect(&ray([0.0, 0.0, -5.0], [0.0, 0.0, 1.0])), None);
    }
}
