//! meshletlab: build, measure, render, compress and level-of-detail meshlets (triangle clusters for
//! GPU mesh shaders).
//!
//! # Building meshlets
//!
//! **In:** a [`mesh::Mesh`]: f32 positions and a u32 triangle list, counter-clockwise. Load one
//! from a file with [`mesh::load`] (PLY, OBJ, STL, glTF/GLB, optionally zstd-compressed) or hand over
//! the arrays an engine holds with [`mesh::Mesh::from_slices`] / [`mesh::Mesh::from_strided`];
//! every constructor validates (finite positions, indices in range, at least one triangle) and
//! returns a typed [`mesh::MeshError`] that names the source.
//!
//! **Out:** [`meshlet::Meshlets`], flat arrays as a mesh shader reads them: per meshlet a
//! [`meshlet::Meshlet`] (offsets and counts), the global vertex indices it uses, and three u8
//! local corners per triangle. Every triangle lands in exactly one meshlet;
//! [`meshlet::validate`] checks that and the limits. Bounds (sphere, normal cone) come from
//! [`meshlet::bounds::compute_bounds`], quality figures from [`meshlet::Metrics`].
//!
//! **Strategies** are chosen by type ([`strategy::Kind`]) or by name ([`strategy::by_name`]):
//! meshoptimizer 1.3's builders (the peer), the JCGT paper's greedy, bounding-sphere and
//! k-medoids strategies, ours (`compact`, `qem`, the parallel grower) and `+refine`, which
//! refines any of them to fewer meshlets.
//!
//! **Limits:** at most 256 vertices and 256 triangles per meshlet ([`meshlet::Limits`]); meshes
//! up to u32 indices. `laced-wires` compression takes at most 64 vertices per meshlet.
//!
//! **Determinism:** every strategy, the LOD build and every codec give the same bytes for the same
//! input on every run and any thread count (rayon parallelises some steps; results never depend
//! on it), and the GPU kernels match their CPU references exactly.
//!
//! ```
//! use meshletlab::mesh::Mesh;
//! use meshletlab::meshlet::{validate, Limits};
//! use meshletlab::strategy::{Kind, Options};
//!
//! // A unit quad as an engine holds it: two triangles over four vertices.
//! let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
//! let indices = [0, 1, 2, 2, 1, 3];
//! let mesh = Mesh::from_slices(&positions, &indices, "quad")?;
//!
//! let limits = Limits::new(64, 126)?; // the JCGT paper's setting
//! let meshlets = Kind::Meshopt.strategy(&Options::default()).build(&mesh, limits);
//! validate(&mesh, &meshlets, limits)?;
//! assert_eq!(meshlets.len(), 1);
//! assert_eq!(meshlets.triangle_count(), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! More in `examples/`: writing a meshlet file, an LOD DAG and a cut for a camera, laced-wire
//! compression, and k-medoids on the GPU beside the CPU.
//!
//! # Modules
//!
//! Data flows one way: [`mesh`] (load, validate, generate) -> [`adjacency`] -> [`strategy`] ->
//! [`meshlet`] (model, validator, bounds, metrics, files) -> [`lod`] / [`compress`] -> `gpu` /
//! `render` -> `bench` results; `fuzz` feeds mutated files to every reader. [`atomic`] writes
//! every output file through a temporary file.
//!
//! # Cargo features
//!
//! The core (every module above not in code font) builds with `default-features = false` and
//! pulls in no GPU, command-line or plotting crate. `gpu` adds the wgpu compute kernels
//! (`meshletlab::gpu`), `render` the ash mesh-shader pass (`meshletlab::render`), and `tool` (the
//! default) both plus the `meshletlab` command, its benches (`bench`) and the fuzzer (`fuzz`).

#![warn(missing_docs)]

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

/// A rayon pool of exactly `n` threads for the unit tests' thread-count comparisons: on a
/// one-core host the global pool is one thread too, so a test must not compare against it.
#[cfg(test)]
pub(crate) fn test_pool(n: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .expect("a test's thread pool")
}
