//! Adversarial accuracy and speed measurements of the intersection routines: for every
//! routine a suite of hard cases, each method's failure count against a double-precision
//! (or exact) reference, and its time per test — the figures the defaults are chosen by.
//!
//! Five families, each a function taking a [`Scale`] and returning one [`Row`] per
//! (method, case set):
//!
//! * [`spheres`](fn@spheres): the literal and robust geometric methods and the naive and stable
//!   algebraic ones on far origins, tiny spheres and near-tangent rays;
//! * [`polynomials`](fn@polynomials): closed forms against Laguerre's method (polished or not) on a torus
//!   (generic rays and rays tangent to it: double roots), the sextic heart surface and
//!   random degree-4/8/12 polynomials with known real roots;
//! * [`triangles`](fn@triangles): Möller–Trumbore against the watertight test on rays through shared
//!   vertices and edges of closed icospheres at several scales and offsets (leaks);
//! * [`slabs`](fn@slabs): [`shapes::boxes::slab`] and [`Aabb::hit`](shapes::Aabb::hit) with ±0 direction components,
//!   origins on slab planes and boxes from 10⁻⁶ to 10⁶;
//! * [`self_intersection`](fn@self_intersection): secondary rays spawned from f32 hit points with a fixed ε
//!   against the robust offset of Wächter & Binder, across scene scales.
//!
//! Every case set is generated deterministically (fixed seeds, the workspace's PCG32
//! from the `rng` crate), so failure counts are reproducible; the times (`ns_per_test`,
//! best of a few passes measured with [`std::time::Instant`], inputs passed through
//! [`black_box`]) depend on the machine and are never asserted. The tests assert failure
//! bounds for the defaults (robust geometric sphere, stable quadratic, polished Laguerre,
//! watertight triangles, robust offsets) and that every baseline does fail somewhere,
//! which shows the suite can detect failures.
//!
//! The suite lives in the CLI, not in the `shapes` library: it times routines and is run
//! by `spt stability`, which prints [`Row`]s as a table and writes a CSV and charts. One
//! file per family; the tests in `suite/tests.rs` run every family at [`Scale::Quick`].

mod polynomials;
mod self_intersection;
mod slabs;
mod spheres;
#[cfg(test)]
mod tests;
mod triangles;

use glam::DVec3;
use polynomials::polynomials;
use rng::Pcg32;
use self_intersection::self_intersection;
use slabs::slabs;
use spheres::spheres;
use std::hint::black_box;
use std::time::Instant;
use triangles::triangles;

/// One method measured on one case set.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The family: one of [`FAMILIES`].
    pub family: &'static str,
    /// The method (algorithm and variant), e.g. `"geometric-robust"`.
    pub method: String,
    /// The case set, e.g. `"far origin 1e4"`.
    pub case: String,
    /// Number of tests counted (cases inside a documented ambiguity band are not).
    pub tests: u64,
    /// Tests the method got wrong (the family's documentation defines "wrong").
    pub failures: u64,
    /// Tests in which a Laguerre search hit its iteration limit (0 for methods without
    /// an iteration).
    pub not_converged: u64,
    /// Mean time per test in nanoseconds (best of the measured passes); what one test is
    /// (one ray, one ray–triangle test, one offset) is stated per family.
    pub ns_per_test: f64,
}

impl Row {
    /// failures / tests (0 when there were no tests).
    pub fn failure_rate(&self) -> f64 {
        if self.tests == 0 { 0.0 } else { self.failures as f64 / self.tests as f64 }
    }
}

/// How many cases to generate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scale {
    /// Small sets for the unit tests: every family together well under a second in an
    /// optimised test build; one timing pass.
    #[default]
    Quick,
    /// 20× more cases and the best of three timing passes, for the command-line report.
    Full,
}

impl Scale {
    /// The count multiplier: 1 for [`Scale::Quick`], 20 for [`Scale::Full`].
    pub fn factor(self) -> usize {
        match self {
            Self::Quick => 1,
            Self::Full => 20,
        }
    }

    fn n(self, base: usize) -> usize {
        base * self.factor()
    }

    fn passes(self) -> u32 {
        match self {
            Self::Quick => 1,
            Self::Full => 3,
        }
    }
}

/// The family names, in the order the command runs them.
pub const FAMILIES: [&str; 5] = ["spheres", "polynomials", "triangles", "slabs", "self_intersection"];

/// Runs one family by name (one of [`FAMILIES`]); `None` for an unknown name.
pub fn run_family(name: &str, scale: Scale) -> Option<Vec<Row>> {
    Some(match name {
        "spheres" => spheres(scale),
        "polynomials" => polynomials(scale),
        "triangles" => triangles(scale),
        "slabs" => slabs(scale),
        "self_intersection" => self_intersection(scale),
        _ => return None,
    })
}

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

/// Runs `f` on every input (passed through [`black_box`]) `scale.passes()` times and
/// returns the results of the last pass and the best time per input in nanoseconds.
fn timed<I, T>(scale: Scale, inputs: &[I], mut f: impl FnMut(&I) -> T) -> (Vec<T>, f64) {
    let mut out = Vec::with_capacity(inputs.len());
    let mut best = f64::INFINITY;
    for _ in 0..scale.passes() {
        out.clear();
        let start = Instant::now();
        for x in inputs {
            out.push(f(black_box(x)));
        }
        best = best.min(start.elapsed().as_nanos() as f64);
        black_box(&out);
    }
    (out, best / inputs.len().max(1) as f64)
}

/// Log-uniform in [lo, hi) (0 < lo < hi): scales spread evenly over the decades.
fn log_uniform(rng: &mut Pcg32, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.next_f64() * (hi.ln() - lo.ln())).exp()
}

fn row(family: &'static str, method: &str, case: &str, tests: u64, failures: u64, not_converged: u64, ns: f64) -> Row {
    Row { family, method: method.into(), case: case.into(), tests, failures, not_converged, ns_per_test: ns }
}

/// The spacing of f32 values at |x| (the subnormal spacing below the normal range).
fn ulp32(x: f64) -> f64 {
    let a = x.abs() as f32;
    if a.is_nan() || a < f32::MIN_POSITIVE {
        return f32::from_bits(1) as f64;
    }
    let e = ((a.to_bits() >> 23) & 0xff) as i32 - 127;
    2f64.powi(e - 23)
}

/// (entry, exit) of the line o + t·d through the box [lo, hi], exact up to one rounding
/// per plane (differences of f32 values are exact in f64, one division); a zero
/// direction component keeps the slab unrestricted if the origin lies in it (its planes
/// included) and empties it otherwise. `None` if the slabs do not overlap.
fn slab_reference(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> Option<(f64, f64)> {
    let (mut entry, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
    for i in 0..3 {
        if d[i] == 0.0 {
            if o[i] < lo[i] || o[i] > hi[i] {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((lo[i] - o[i]) / d[i], (hi[i] - o[i]) / d[i]);
        entry = entry.max(t0.min(t1));
        exit = exit.min(t0.max(t1));
    }
    (entry <= exit).then_some((entry, exit))
}
