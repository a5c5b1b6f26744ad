//! meshletlab: build, measure, render, compress and level-of-detail meshlets (triangle clusters for
//! GPU mesh shaders).
//!
//! # Building meshlets
//!
//! **In:** a [`mesh::Mesh`]: positions only (f32 x 3) and a u32 triangle list, counter-clockwise;
//! normals, UVs and other attributes are not read (a strategy that wants normals computes them from
//! the triangles, and an engine keeps its own vertex attributes, which the meshlets index). Load one
//! from a file with `mesh::load` (feature `io`: PLY, OBJ, glTF/GLB, STL, optionally
//! zstd-compressed) or hand over the arrays an engine holds with [`mesh::Mesh::from_slices`] /
//! [`mesh::Mesh::from_strided`]; every constructor validates (finite positions, indices in range,
//! at least one triangle) and returns a typed [`mesh::MeshError`] that names the source. A scene
//! whose nodes place meshes several times (`mesh::load_scene`, [`mesh::Scene`]) keeps each mesh
//! once: build its meshlets once and draw them per instance.
//!
//! **Sound by construction:** [`mesh::Mesh`], [`meshlet::Limits`], [`meshlet::Meshlets`] and
//! [`mesh::Scene`] keep their fields private and are made only by checked constructors, so safe
//! code cannot hand a strategy, the bounds, the LOD build or a codec (some of which call
//! meshoptimizer's C code) an index out of range or a limit of 0: bad arrays are a typed error at
//! the constructor. Meshlets made elsewhere (another tool, a cache) come in through
//! [`meshlet::Meshlets::new`], checked against their mesh; a clustering made elsewhere (one id
//! per triangle) through [`strategy::labels::from_labels`], which packs it into meshlets and
//! refuses, or splits with meshoptimizer, a cluster over the limits. A struct literal does not compile:
//!
//! ```compile_fail,E0451
//! let mesh = meshletlab::mesh::Mesh { positions: vec![[0.0; 3]; 3], indices: vec![0, 1, 7] };
//! ```
//!
//! ```compile_fail,E0451
//! let limits = meshletlab::meshlet::Limits { max_vertices: 64, max_triangles: 0 };
//! ```
//!
//! ```compile_fail,E0451
//! let ml = meshletlab::meshlet::Meshlets { meshlets: vec![], vertices: vec![], triangles: vec![7] };
//! ```
//!
//! **Out:** [`meshlet::Meshlets`], flat arrays as a mesh shader reads them: per meshlet a
//! [`meshlet::Meshlet`] (offsets and counts), the global vertex indices it uses, and three u8
//! local corners per triangle. Every triangle lands in exactly one meshlet;
//! [`meshlet::validate`] checks that and the limits.
//!
//! **Limits:** at most 256 vertices and 256 triangles per meshlet ([`meshlet::Limits`]; a typed
//! [`meshlet::LimitsError`] otherwise); meshes up to u32 indices. `laced-wires` compression takes
//! at most 64 vertices per meshlet.
//!
//! # Which strategy
//!
//! Chosen by type ([`strategy::Kind`]) or by name ([`strategy::by_name`]). The figures are the
//! Stanford bunny's (69,451 triangles) at 64 vertices / 126 triangles on a 2-core machine, cited
//! from the results file each row names (`meshletlab bench build`, `meshletlab bench kmedoids`
//! write them; a test checks the citations against the files). Other meshes and presets are there.
//!
//! | need | strategy | bunny, 64/126 |
//! |---|---|---|
//! | speed, the usual choice | [`Kind::Meshopt`](strategy::Kind::Meshopt) (`meshopt`, meshoptimizer 1.3) | 720 meshlets in 26.66 ms, radius/diag 0.0261 (`results/strategies.md`) |
//! | fewest meshlets at interactive build times | [`Kind::Partition`](strategy::Kind::Partition) (`partition`): meshoptimizer's meshlets re-partitioned and packed | 718 meshlets in 72.24 ms, radius/diag 0.0255 (`results/strategies.md`) |
//! | smallest spheres at meshoptimizer's count | [`Kind::Kmedoids`](strategy::Kind::Kmedoids) (`kmedoids`, the sequential capacity-aware k-medoids, CPU) | 724 meshlets, 0.79 x meshopt's time, radius 0.959 x meshopt's (`results/kmedoids.md`) |
//! | k-medoids on many cores or on the GPU | [`Kind::KmedoidsParallel`](strategy::Kind::KmedoidsParallel) (`kmedoids-parallel`): regions at once, every step a kernel, identical on the CPU (rayon) and the GPU; from an engine's own buffers by `gpu::build::build_on_device` | 728 meshlets, 0.92 x meshopt's time, radius 0.963 x meshopt's (`results/kmedoids.md`) |
//! | fewest meshlets, offline | `meshopt+refine` or `meshopt+refine-max` ([`strategy::Kind::refined`]) | `meshopt+refine`: 717 meshlets in 1400.06 ms, radius/diag 0.0250 (`results/strategies.md`) |
//! | the plain data-parallel k-medoids, the GPU baseline | `kmedoids-flat` (every step a kernel, `gpu::build::build`; on an engine's own device through `gpu::Gpu::from_device`; meshlets and their culling bounds left in device buffers by `gpu::build::build_resident`, from an engine's own vertex and index buffers by `gpu::build::build_on_device`) | 953 meshlets, 7.41 x meshopt's time, radius 0.948 x meshopt's (`results/kmedoids.md`) |
//! | the JCGT paper's strategies, for comparison | `greedy`, `bsphere`, `kmedoids-paper`, `nvidia` | `results/strategies.md`, `results/fidelity.md` |
//!
//! Every option in [`strategy::Options`] acts on every strategy made from it, the ordering passes
//! included; `meshopt`'s meshlets come already optimised by meshoptimizer inside each meshlet.
//!
//! # Threads
//!
//! Strategies, the LOD build and the codecs run their parallel steps on rayon's current pool:
//! the global one (a thread per core) unless the call runs inside [`rayon::ThreadPool::install`].
//! An engine that keeps its own pool, or wants a build off its frame threads, installs it; the
//! output is the same bytes for any pool size.
//!
//! ```
//! use meshletlab::meshlet::Limits;
//! use meshletlab::strategy::{Kind, Options};
//!
//! let mesh = meshletlab::mesh::generate::noisy_sphere(3, 0.2, 1);
//! let strategy = Kind::KmedoidsParallel.strategy(&Options::default());
//! let two = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
//! let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
//! let a = two.install(|| strategy.build(&mesh, Limits::DEFAULT));
//! let b = one.install(|| strategy.build(&mesh, Limits::DEFAULT));
//! assert_eq!(a, b); // deterministic whatever the pool
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # After building
//!
//! - **Order**: [`meshlet::order::optimize_triangle_order`] reorders triangles inside each meshlet
//!   for vertex reuse, [`meshlet::order::order_meshlets`] orders the meshlets (or ask for both
//!   through [`strategy::Options`] and [`strategy::with_order`]).
//! - **Bounds** for culling: [`meshlet::bounds::compute_bounds`] (sphere and normal cone per
//!   meshlet); quality figures from [`meshlet::Metrics`].
//! - **Upload**: [`meshlet::descriptor::pack`] packs the meshlets in one of the four descriptor
//!   layouts the mesh-shader pass reads ([`meshlet::descriptor::DescriptorFormat`]: split task and mesh
//!   descriptors, NVIDIA's two 128-bit layouts, or self-contained blocks); the GLSL that reads
//!   them is `glsl/descriptors.glsl`. [`compress`] encodes them smaller.
//! - **Level of detail**: [`lod::build`] makes the cluster-LOD DAG and [`lod::select`] the cut
//!   for a view (below).
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
//! let meshlets = Kind::Partition.strategy(&Options::default()).build(&mesh, limits);
//! validate(&mesh, &meshlets, limits)?;
//! assert_eq!(meshlets.len(), 1);
//! assert_eq!(meshlets.triangle_count(), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A level-of-detail DAG and the cut a camera needs, at a one-pixel error threshold:
//!
//! ```
//! use meshletlab::lod::{self, select};
//! use meshletlab::meshlet::Limits;
//! use meshletlab::strategy::{Kind, Options};
//!
//! let mesh = meshletlab::mesh::generate::noisy_sphere(3, 0.2, 1);
//! let strategy = Kind::Meshopt.strategy(&Options::default());
//! let dag = lod::build(&mesh, strategy.as_ref(), Limits::DEFAULT, &lod::Config::default());
//! // 1080 pixels high, 60 degrees vertical field of view, a one-pixel error, from 10 units away.
//! let view = select::View::new(meshletlab::glam::Vec3::new(0.0, 0.0, 10.0), 1080.0, 60f32.to_radians(), 1.0);
//! let cut = select::select_cut(&dag, &view, 0);
//! select::check_cut(&dag, &cut, 0)?; // one meshlet on every path: no crack, no overlap
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! More in `examples/`: writing a meshlet file, an LOD DAG and its cuts for several cameras,
//! laced-wire compression, and k-medoids on the GPU beside the CPU.
//!
//! # Modules
//!
//! Data flows one way, and no module imports one later in this list: [`common`] (shared helpers)
//! -> [`mesh`] (load, validate, generate, edges) -> [`adjacency`] (dual graph) -> [`meshlet`]
//! (model, validator, bounds, metrics, order, files) -> [`strategy`] -> [`lod`] / [`compress`] ->
//! `gpu` / `render` -> `bench` results and the `cli`; `fuzz` feeds mutated files to every reader.
//! `atomic` (feature `io`) writes every output file through a temporary file. Background on the
//! methods is in `docs/`.
//!
//! # Cargo features
//!
//! The core (every module above not in code font) builds with `default-features = false`: its
//! normal dependencies are meshoptimizer (the `meshopt` crate, the only C build), rayon, glam
//! (re-exported as [`glam`]), bytemuck, thiserror and the two small random-number crates of
//! `refine`'s annealing. `io` adds file reading and writing (the mesh loaders, the meshlet, LOD
//! and compressed-meshlet files, the glTF export, `atomic`); `serde` the `Serialize` impls of the
//! figures; `gpu` the wgpu compute kernels (`meshletlab::gpu`); `render` the ash mesh-shader pass
//! (`meshletlab::render`); and `tool` (the default) all of them plus the `meshletlab` command,
//! its benches (`bench`) and the fuzzer (`fuzz`).
//!
//! meshoptimizer's C++ is slow unoptimised, and a crate's profile overrides do not carry over to
//! its dependents: a dependent's debug builds want
//!
//! ```toml
//! [profile.dev.package.meshopt]
//! opt-level = 3
//! [profile.dev.package.meshletlab]
//! opt-level = 2
//! ```

#![warn(missing_docs)]

/// The vector library of the public API ([`lod::select::View::new`] takes a `glam::Vec3`):
/// name it through this re-export and no version needs pinning by hand.
pub use glam;

pub mod adjacency;
#[cfg(feature = "io")]
pub mod atomic;
#[cfg(feature = "tool")]
pub mod bench;
#[cfg(feature = "tool")]
pub mod cli;
pub mod common;
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
