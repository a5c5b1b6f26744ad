//! meshletlab: build, measure, render, compress and level-of-detail meshlets (triangle clusters for
//! GPU mesh shaders).
//!
//! Data flows one way: [`mesh`] (load, validate, generate) -> [`adjacency`] -> [`strategy`] ->
//! [`meshlet`] (model, validator, bounds, metrics) -> [`lod`] / [`compress`] -> [`gpu`] /
//! [`render`] -> [`bench`] results.
//! [`fuzz`] feeds mutated files to every reader.

//!
//! Cargo features: the core (every module not named below) builds with `--no-default-features`
//! and pulls in no GPU, CLI or plotting crate; `gpu` adds the wgpu kernels, `render` the ash
//! mesh-shader pass, and `tool` (the default) both plus the `meshletlab` command, its benches and
//! the fuzzer.

pub mod adjacency;
pub mod atomic;
#[cfg(feature = "tool")]
pub mod bench;
#[cfg(feature = "tool")]
pub mod cli;
pub mod compress;
#[cfg(feature = "tool")]
pub mod fuzz;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod lod;
pub mod mesh;
pub mod meshlet;
#[cfg(feature = "render")]
pub mod render;
pub mod strategy;
