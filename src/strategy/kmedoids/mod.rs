//! k-medoids on the triangle dual graph (the JCGT paper's section 3), as one family of four
//! methods over shared steps.
//!
//! Triangles are nodes, edge-adjacent triangles are neighbours, distance is hop count; a medoid is
//! the member with the smallest sum of in-cluster hop distances. The paper fixes
//! k = ceil(T / max_triangles), assigns every triangle to its nearest medoid, and adds one cluster
//! per overflow with a global re-run. Background: `docs/kmedoids.md`.
//!
//! | method ([`Mode`]) | name | driver | settings | on the GPU |
//! |---|---|---|---|---|
//! | [`Mode::Sequential`] (the default) | `kmedoids` | [`sequential`]: clusters grow to the limits one at a time, nothing is split | [`sequential::Config`] | none: a CPU method |
//! | [`Mode::Parallel`] | `kmedoids-parallel` | [`parallel`]: coarse regions at once, every step a kernel | [`parallel::Config`] | `gpu::kmedoids_parallel` |
//! | [`Mode::Flat`] | `kmedoids-flat` | [`flat`]: nearest-medoid assignment, overflows split a fraction at a time | [`flat::Config`] | `gpu::kmedoids_flat` (the baseline) |
//! | [`Mode::Paper`] | `kmedoids-paper` | [`flat`]: one cluster added and everything re-run per overflow | [`flat::Config`], [`flat::PaperConfig`] | none: slow by design |
//!
//! The files, lowest first (a file reads only those above it in this list):
//! - [`mod@assign`]: the flat multi-source BFS and member lists (CPU reference of `wgsl/assign.wgsl`);
//! - [`morton`]: the Morton frame and the centroid cells (CPU reference of `wgsl/morton.wgsl`);
//! - `local_graph`: one cluster's induced subgraph: medoids and distances;
//! - [`update`]: the medoid update with its cache (CPU reference of `wgsl/update.wgsl`);
//! - [`split`]: the flat method's overflow statistics (CPU reference of `wgsl/split.wgsl`);
//! - [`seed`]: the sequential method's seeding growth and its orphans;
//! - [`merge`]: the sequential method's merges of neighbours and small pieces, renumbering;
//! - [`sequential`]: the default's driver and its capacity-aware assignment;
//! - [`flat`]: the flat and paper drivers;
//! - [`coarse`]: the coarse regions of `kmedoids-parallel` (CPU reference of `wgsl/coarse.wgsl`);
//! - [`parallel`]: the region-parallel method, a folder with one file per step (CPU reference of
//!   `wgsl/kmedoids_parallel.wgsl` and `wgsl/kmedoids_parallel_moves.wgsl`);
//! - this file: the strategy, its settings, [`cluster`] and [`pack`].
//!
//! Every step is a function over flat arrays (CSR adjacency, u32 labels and distances), so a
//! compute kernel mirrors it and is compared exactly. Determinism: every parallel step is a
//! deterministic map or an order-independent minimum, and the sequential steps run in a fixed
//! order, so the output is the same for any thread count and on the GPU.

pub mod assign;
pub mod coarse;
pub mod flat;
mod local_graph;
pub mod merge;
pub mod morton;
pub mod parallel;
pub mod seed;
pub mod sequential;
pub mod split;
pub mod update;

pub use assign::{assign, members, UNREACHED};
pub use local_graph::medoids_and_distances;
pub use seed::Grow;

use super::Strategy;
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use std::time::Instant;

/// Which k-medoids method runs; the strategy name selects it, so it is not a setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Grow clusters to the limits one at a time and assign with capacity, so nothing is split
    /// ([`sequential`], `kmedoids`, the default).
    Sequential,
    /// Coarse regions at once, each grown by integer keys, every step a kernel
    /// ([`parallel`], `kmedoids-parallel`).
    Parallel,
    /// Split the largest overflowing clusters a fraction at a time, then a few global iterations
    /// ([`flat`], `kmedoids-flat`).
    Flat,
    /// Add one cluster at a time and re-run everything (the paper's method; slow, kept for
    /// comparison: `kmedoids-paper`).
    Paper,
}

impl Mode {
    /// Every method, in the strategy table's order.
    pub const ALL: [Mode; 4] = [Mode::Sequential, Mode::Parallel, Mode::Flat, Mode::Paper];

    /// The strategy name of this method.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Sequential => "kmedoids",
            Mode::Parallel => "kmedoids-parallel",
            Mode::Flat => "kmedoids-flat",
            Mode::Paper => "kmedoids-paper",
        }
    }
}

/// Where a method's parallel steps run. The output is the same either way.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Threading {
    /// On the current rayon pool: the global one, or a caller's under `pool.install`.
    #[default]
    Pool,
    /// On a one-thread pool of its own (one-thread timings and determinism checks).
    OneThread,
}

/// The k-medoids settings: one block per method (each documents what its fields feed and why
/// its defaults are what they are), plus where the parallel steps run. The method itself is a
/// [`Mode`], chosen by the strategy name; a method reads only its own block.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Config {
    /// `kmedoids`.
    pub sequential: sequential::Config,
    /// `kmedoids-parallel`.
    pub parallel: parallel::Config,
    /// `kmedoids-flat`, and `kmedoids-paper`'s iterations and its splits after the budget.
    pub flat: flat::Config,
    /// `kmedoids-paper`'s budget.
    pub paper: flat::PaperConfig,
    /// Where the parallel steps run.
    pub threading: Threading,
}

/// The k-medoids strategy: one [`Mode`] with its [`Config`].
pub struct KMedoids {
    /// The method (and so the name).
    pub mode: Mode,
    /// Settings.
    pub config: Config,
}

impl Strategy for KMedoids {
    fn name(&self) -> &'static str {
        self.mode.name()
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let run = || cluster(mesh, limits, self.mode, &self.config).meshlets;
        match self.config.threading {
            Threading::Pool => run(),
            Threading::OneThread => crate::common::one_thread_pool().install(run),
        }
    }
}

/// Runs one method on `mesh`: the dual graph, then the method's driver, then [`pack`].
pub fn cluster(mesh: &Mesh, limits: Limits, mode: Mode, cfg: &Config) -> Clustering {
    if rayon::current_thread_index().is_none() {
        // Called from outside the pool: run the whole method on a pool thread. Otherwise each
        // parallel step hands its work over from this thread and sleeps until it is done, a
        // wake-up per step that shows on small meshes, whose runs take milliseconds. The output
        // does not depend on where it runs.
        return rayon::scope(|_| cluster_on_pool(mesh, limits, mode, cfg));
    }
    cluster_on_pool(mesh, limits, mode, cfg)
}

/// [`cluster`] on the current thread.
fn cluster_on_pool(mesh: &Mesh, limits: Limits, mode: Mode, cfg: &Config) -> Clustering {
    let t0 = Instant::now();
    let vt = vertex_triangles(mesh);
    let dual = dual_graph(mesh, &vt);
    match mode {
        Mode::Sequential => {
            let g = sequential::cluster(mesh, &dual, &vt, limits, &cfg.sequential);
            Clustering::from_grown(mesh, limits, g, t0.elapsed().as_secs_f64())
        }
        Mode::Parallel => parallel::cluster(mesh, &dual, &vt, limits, &cfg.parallel, t0),
        Mode::Flat => flat::cluster(mesh, &dual, limits, &cfg.flat, None, t0),
        Mode::Paper => flat::cluster(mesh, &dual, limits, &cfg.flat, Some(&cfg.paper), t0),
    }
}

/// What a growing method (sequential or parallel, CPU or GPU) produced.
pub struct Grown {
    /// Medoid of each cluster, ascending.
    pub medoids: Vec<u32>,
    /// Cluster of each triangle.
    pub labels: Vec<u32>,
    /// Hop distance of each triangle to its medoid inside its cluster.
    pub distances: Vec<u32>,
    /// Re-assignment rounds tried (sequential; 0 where too few clusters were light for a round
    /// to pay) or boundary-move rounds that moved triangles (parallel).
    pub iterations: u32,
}

/// Everything a k-medoids run produces, for tests, benches and GPU parity. (No `PartialEq`: it
/// carries wall-clock time; compare the result fields.)
#[derive(Clone, Debug)]
pub struct Clustering {
    /// Medoid triangle of each cluster, ascending.
    pub medoids: Vec<u32>,
    /// Cluster of each triangle.
    pub labels: Vec<u32>,
    /// Hop distance of each triangle to its medoid.
    pub distances: Vec<u32>,
    /// Assign/update iterations run in total.
    pub iterations: u32,
    /// Split rounds (flat) or clusters added (paper).
    pub splits: u32,
    /// Whether the paper's method ran out of budget and finished the flat way.
    pub budget_exhausted: bool,
    /// Mean hop distance after the initial clustering, before any split (the k-medoids
    /// objective); for the parallel method, that before its boundary moves ([`parallel::moves`]).
    pub initial_mean_distance: f64,
    /// Iterations of the initial clustering.
    pub initial_iterations: u32,
    /// Wall time of the initial clustering (adjacency, seeding, iterations), in seconds.
    pub initial_seconds: f64,
    /// Cluster updates skipped because the members were those of the last update (cache hits;
    /// the GPU's changed-cluster test must find the same).
    pub skipped_updates: u32,
    /// The packed meshlets.
    pub meshlets: Meshlets,
}

impl Clustering {
    /// A growing run's clusters, packed into meshlets; `seconds` is its wall time. It has no
    /// initial clustering and no splits: its objective is that of the result.
    pub fn from_grown(mesh: &Mesh, limits: Limits, g: Grown, seconds: f64) -> Self {
        let meshlets = pack(mesh, &g.labels, &g.distances, g.medoids.len(), limits);
        Self::grown(g, meshlets, seconds)
    }

    /// Grown clusters (`kmedoids` or `kmedoids-parallel`, CPU or GPU) and their meshlets: no
    /// initial clustering and no splits, so the objective is that of the result.
    pub fn grown(g: Grown, meshlets: Meshlets, seconds: f64) -> Self {
        Clustering {
            initial_mean_distance: mean(&g.distances),
            medoids: g.medoids,
            labels: g.labels,
            distances: g.distances,
            iterations: g.iterations,
            splits: 0,
            budget_exhausted: false,
            initial_iterations: 0,
            initial_seconds: seconds,
            skipped_updates: 0,
            meshlets,
        }
    }

    /// Mean hop distance of a triangle to its medoid (the k-medoids objective per triangle).
    pub fn mean_distance(&self) -> f64 {
        mean(&self.distances)
    }
}

/// Mean of hop distances (0 for none).
pub(crate) fn mean(d: &[u32]) -> f64 {
    d.iter().map(|&x| x as f64).sum::<f64>() / d.len().max(1) as f64
}

/// Meshlets from clusters: each cluster in BFS order from its medoid (distance, then id), chunked
/// by the builder if it does not fit ([`crate::meshlet::assemble::assemble`] with the distances as
/// keys, which the GPU runs as `wgsl/assemble.wgsl`).
pub fn pack(mesh: &Mesh, labels: &[u32], distances: &[u32], k: usize, limits: Limits) -> Meshlets {
    crate::meshlet::assemble::assemble(mesh, labels, distances, k, limits)
}
