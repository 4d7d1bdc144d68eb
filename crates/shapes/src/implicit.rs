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
//!
//! Split by concern: the polynomial algebra ([`Poly3`], its builders and its restriction
//! to a ray) in `poly`, the expression parser ([`parse`]) in `parser`, and the surface
//! ([`Implicit`]: clipping, solving, normals) in `shape`.

mod parser;
mod poly;
mod shape;
#[cfg(test)]
mod tests;

pub use parser::parse;
pub use poly::{MAX_DEGREE, Poly3, Term};
pub use shape::{Implicit, PAD_REL, S_EPS};
