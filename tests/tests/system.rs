//! The whole-system tests as one test binary: each file a module, so that the renderer's
//! generic code is compiled once rather than once per file (CI's test build on a 2-core
//! machine: 32 min with 19 binaries, 21 min with one; docs/figures.md, "CI's time on a
//! slow machine").

mod common;

mod analytic;
mod atlas;
mod bdpt;
mod caustics;
mod determinism;
mod environment;
mod furnace;
mod glass;
mod gltf;
mod instances;
mod integrators;
mod lanes;
mod light_tree;
mod models;
mod punctual;
mod reference;
mod shapes;
mod textures;
