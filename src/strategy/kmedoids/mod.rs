//! k-medoids on the triangle dual graph (the JCGT paper's section 3), as one family of three
//! methods over shared steps.
//!
//! Triangles are nodes, edge-adjacent triangles are neighbours, distance is hop count; a medoid is
//! the member with the smallest sum of in-cluster hop distances. The paper fixes
//! k = ceil(T / max_triangles), assigns every triangle to its nearest medoid, and adds one cluster
//! per overflow with a global re-run. Background: `docs/kmedoids.md`.
//!
//! | method ([`Mode`]) | name | driver | on the GPU |
//! |---|---|---|---|
//! | [`Mode::Capacity`] (the default) | `kmedoids` | [`capacity`]: clusters grow to the limits, nothing is split | `gpu::kmedoids::cluster_capacity` |
//! | [`Mode::Flat`] | `kmedoids-flat` | [`flat`]: nearest-medoid assignment, overflows split a fraction at a time | `gpu::kmedoids::cluster_flat` |
//! | [`Mode::Tiled`] | `kmedoids-tiled` | [`tiled`]: the capacity-aware method on many regions at once, border clusters merged in matching rounds | (none: the per-region growth is host code) |
//! | [`Mode::Regions`] | `kmedoids-parallel` | [`regions`]: regions at once, each grown by integer keys a kernel runs | `gpu::regions` |
//! | [`Mode::Paper`] | `kmedoids-paper` | [`flat`]: one cluster added and everything re-run per overflow | (none: slow by design) |
//!
//! The files, lowest first (a file reads only those above it in this list):
//! - [`mod@assign`]: the flat multi-source BFS and member lists (CPU reference of `wgsl/assign.wgsl`);
//! - `local_graph`: one cluster's induced subgraph: medoids and distances;
//! - [`update`]: the medoid update with its cache (CPU reference of `wgsl/update.wgsl`);
//! - [`split`]: the flat method's overflow statistics (CPU reference of `wgsl/split.wgsl`);
//! - [`seed`]: capacity-aware seeding growth and its orphans;
//! - [`merge`]: merging neighbours and small pieces, renumbering;
//! - [`capacity`]: the default's driver and its capacity-aware assignment (CPU reference of
//!   `wgsl/capacity.wgsl`);
//! - [`flat`]: the flat and paper drivers, the Morton frame and the centroid cells;
//! - [`moves`]: boundary moves, the parallel method's medoid iteration;
//! - [`coarse`]: the coarse regions of the two region-parallel methods (CPU reference of
//!   `wgsl/coarse.wgsl`);
//! - [`tiled`]: the region-parallel driver over the capacity-aware one;
//! - [`regions`]: the region-parallel driver with a kernel-shaped grower (CPU reference of
//!   `wgsl/regions.wgsl`);
//! - this file: the strategy, its settings, [`cluster`] and [`pack`].
//!
//! Every step is a function over flat arrays (CSR adjacency, u32 labels and distances), so a
//! compute kernel mirrors it and is compared exactly. Determinism: every parallel step is a
//! deterministic map or an order-independent minimum, and the sequential steps run in a fixed
//! order, so the output is the same for any thread count and on the GPU.

pub mod assign;
pub mod capacity;
pub mod coarse;
pub mod flat;
mod local_graph;
pub mod merge;
pub mod moves;
pub mod regions;
pub mod seed;
pub mod split;
pub mod tiled;
pub mod update;

pub use assign::{assign, members, UNREACHED};
pub use seed::Grow;

use super::Strategy;
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use std::time::{Duration, Instant};

/// Which k-medoids method runs; the strategy name selects it, so it is not a setting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Grow clusters to the limits and assign with capacity, so nothing is split
    /// ([`capacity`], `kmedoids`, the default).
    Capacity,
    /// Split the largest overflowing clusters a fraction at a time, then a few global iterations
    /// ([`flat`], `kmedoids-flat`).
    Flat,
    /// Add one cluster at a time and re-run everything (the paper's method; slow, kept for
    /// comparison: `kmedoids-paper`).
    Paper,
    /// The capacity-aware method on regions of the mesh at once, then border merges
    /// ([`tiled`], `kmedoids-tiled`).
    Tiled,
    /// Regions at once, each grown by integer keys one GPU invocation runs
    /// ([`regions`], `kmedoids-parallel`).
    Regions,
}

impl Mode {
    /// The strategy name of this method.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Capacity => "kmedoids",
            Mode::Flat => "kmedoids-flat",
            Mode::Paper => "kmedoids-paper",
            Mode::Tiled => "kmedoids-tiled",
            Mode::Regions => "kmedoids-parallel",
        }
    }
}

/// Triangles per region of `kmedoids-parallel` and `kmedoids-tiled` by default: on the shared meshes, regions of this
/// size cost about a percent of meshlets over one region per mesh while leaving dozens of regions
/// from a million triangles up (the region-size sweep of `meshletlab bench kmedoids`).
pub const DEFAULT_REGION_TRIANGLES: u32 = 16384;

/// Rounds of boundary moves of `kmedoids-tiled` and `kmedoids-parallel` by default: two take
/// their objective (mean hop distance to the medoid) below the sequential method's on the shared
/// meshes, where the later rounds gain less for the same cost (the sweep of
/// `meshletlab bench kmedoids`).
pub const DEFAULT_MOVE_ROUNDS: u32 = 2;

/// k-medoids tunables; each names the methods that read it. The method itself is a [`Mode`],
/// chosen by the strategy name, never by these settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Most assign/update iterations per (re)clustering (flat, paper); most re-assignment rounds
    /// (capacity).
    pub max_iterations: u32,
    /// Stop when the mean medoid shift (hops) is at most this (flat, paper).
    pub shift_threshold: f64,
    /// Iterations after each split round (flat).
    pub split_iterations: u32,
    /// Fraction of the overflowing clusters (largest first) split per round (flat).
    pub split_fraction: f64,
    /// After this long, finish the remaining splits the flat way (paper).
    pub paper_budget: Duration,
    /// Run on the global rayon pool (true) or on one thread (false); results are identical.
    pub parallel: bool,
    /// What a growing cluster prefers (capacity, parallel).
    pub grow: Grow,
    /// Triangles per region, each clustered on its own (parallel, regions): smaller regions give more
    /// parallel work and more partly filled clusters at their borders.
    pub region_triangles: u32,
    /// Most rounds of boundary moves, the medoid iteration that lowers the objective without
    /// changing the count (parallel, regions; [`moves`]). The first rounds gain the most; the
    /// cost and the gain per round are in `results/kmedoids.md`'s run-time-against-error sweep.
    pub move_rounds: u32,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            max_iterations: 16,
            shift_threshold: 0.0,
            split_iterations: 2,
            split_fraction: 0.25,
            paper_budget: Duration::from_secs(300),
            parallel: true,
            grow: Default::default(),
            region_triangles: DEFAULT_REGION_TRIANGLES,
            move_rounds: DEFAULT_MOVE_ROUNDS,
        }
    }
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

    fn summary(&self) -> &'static str {
        match self.mode {
            Mode::Flat => "k-medoids on the triangle dual graph (hop distance), overflowing clusters split a fraction at a time",
            Mode::Paper => "k-medoids as the paper runs it: one cluster added and everything re-run per overflow",
            Mode::Capacity => "k-medoids whose clusters grow to the limits and take triangles only while they have room",
            Mode::Tiled => "the capacity-aware k-medoids on regions of the mesh at once, border clusters merged in parallel rounds",
            Mode::Regions => "k-medoids on regions of the mesh at once, each grown by integer keys (the same on the GPU, one invocation per region)",
        }
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let run = || cluster(mesh, limits, self.mode, &self.config).meshlets;
        if self.config.parallel {
            run()
        } else {
            rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .expect("one-thread pool")
                .install(run)
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
        Mode::Capacity => {
            let g = capacity::cluster(mesh, &dual, &vt, limits, cfg.grow, cfg.max_iterations);
            Clustering::from_grown(mesh, limits, g, t0.elapsed().as_secs_f64())
        }
        Mode::Flat | Mode::Paper => flat::cluster(mesh, &dual, limits, mode, cfg, t0),
        Mode::Tiled => tiled::cluster(mesh, &dual, &vt, limits, cfg, t0),
        Mode::Regions => regions::cluster(mesh, &dual, &vt, limits, cfg, t0),
    }
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
    /// Split rounds (flat), clusters added (paper) or border-merge rounds that merged (tiled).
    pub splits: u32,
    /// Whether the paper's method ran out of budget and finished the flat way.
    pub budget_exhausted: bool,
    /// Mean hop distance after the initial clustering, before any split (the k-medoids
    /// objective); for the parallel method, that before its boundary moves ([`moves`]).
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
    /// A capacity-aware run's clusters (CPU or GPU), packed into meshlets; `seconds` is its wall
    /// time. It has no initial clustering and no splits: its objective is that of the result.
    pub fn from_grown(mesh: &Mesh, limits: Limits, g: capacity::Grown, seconds: f64) -> Self {
        let meshlets = pack(mesh, &g.labels, &g.distances, g.medoids.len(), limits);
        Self::grown(g, meshlets, seconds)
    }

    /// Grown clusters (capacity-aware or `kmedoids-parallel`, CPU or GPU) and their meshlets:
    /// no initial clustering and no splits, so the objective is that of the result.
    pub fn grown(g: capacity::Grown, meshlets: Meshlets, seconds: f64) -> Self {
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
