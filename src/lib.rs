//! meshletlab: build, measure, render, compress and level-of-detail meshlets (triangle clusters for
//! GPU mesh shaders).
//!
//! Data flows one way: [`mesh`] (load, validate, generate) -> [`adjacency`] -> [`strategy`] ->
//! [`meshlet`] (model, validator, bounds, metrics) -> [`lod`] / [`compress`] -> [`gpu`] /
//! [`render`] -> [`bench`] results.
//! [`fuzz`] feeds mutated files to every reader.

pub mod adjacency;
pub mod atomic;
pub mod bench;
pub mod cli;
pub mod compress;
pub mod fuzz;
pub mod gpu;
pub mod lod;
pub mod mesh;
pub mod meshlet;
pub mod render;
pub mod strategy;
