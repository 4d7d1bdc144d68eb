//! The whole-system tests as one test binary, each file a module: the 19 binaries they
//! were took 787 s to rebuild after a change to the renderer, this one 195 s (2-core
//! machine, `cargo test --workspace --no-run`; docs/figures.md, "CI's time on a slow
//! machine").

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
