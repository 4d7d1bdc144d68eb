//! Random numbers: PCG32 (O'Neill 2014) seeded per pixel sample, so that every sample's
//! random stream depends only on (seed, pixel, sample index) — never on which thread
//! draws it. (The thesis's sine hash, listing 8.1, correlates badly; see the tests of the
//! `rng` crate.)
//!
//! The generator lives in the `rng` crate, the workspace's one generator; it is
//! re-exported here so that the integrator and the renderer keep their paths.

pub use rng::{Pcg32, mix64};
