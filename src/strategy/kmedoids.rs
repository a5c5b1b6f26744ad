//! k-medoids on the triangle dual graph (the JCGT paper's §3; CPU reference for the GPU kernels).
//!
//! This file is the flat method (`kmedoids-flat`, and `kmedoids-paper`) and the steps every variant
//! shares; the default `kmedoids` grows clusters to the limits instead ([`super::kmedoids_capacity`],
//! [`Mode::Capacity`]) and `kmedoids-local` splits inside clusters ([`super::kmedoids_local`]).
//!
//! Triangles are nodes, edge-adjacent triangles are neighbours, distance is hop count. The steps are
//! separate pure functions over flat arrays (CSR adjacency, u32 labels and distances), so a compute
//! kernel can mirror each one and be compared exactly:
//!
//! 1. [`initial_medoids`]: k = ceil(T / max_triangles) triangles spread in Morton order of centroids.
//! 2. [`assign`]: one multi-source BFS from all medoids at once. Each triangle takes the smallest
//!    packed key `(distance << 32) | cluster`, so ties go to the lower cluster id (= lower medoid
//!    triangle id: clusters are numbered by ascending medoid) whatever the processing order; on a GPU
//!    this is one `atomicMin` per relaxation.
//! 3. [`update`]: each cluster's new medoid is the member with the smallest sum of hop distances to
//!    all other members, measured inside the cluster (the paper's definition); ties to the lowest id.
//! 4. Convergence: the mean hop distance between old and new medoids falls to a threshold, or an
//!    iteration cap is reached.
//! 5. Fit: clusters over the vertex or triangle limit get a second medoid at their farthest member.
//!    `paper` mode adds one cluster and re-runs everything (as the paper does, under a time budget);
//!    `fast` mode splits every overflowing cluster at once, then runs a few iterations.
//! 6. [`pack`]: each cluster becomes meshlets in BFS order from its medoid; a cluster that still does
//!    not fit is chunked, so the output is always valid.
//!
//! Serial and parallel runs execute the same steps (serial on a one-thread pool) and give identical
//! results: every parallel step is a deterministic map or an order-independent minimum.

use super::Strategy;
use crate::adjacency::{dual_graph, vertex_triangles, Csr};
use crate::mesh::Mesh;
use crate::meshlet::{Limits, MeshletBuilder, Meshlets};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Label of a triangle no medoid reaches (another component).
pub const UNREACHED: u32 = u32::MAX;

/// How overflowing clusters are split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Add one cluster at a time and re-run everything (the paper's method; slow, kept for comparison).
    Paper,
    /// Split the largest overflowing clusters at once, then a few global iterations
    /// (`kmedoids-flat`; what the GPU kernels run).
    Fast,
    /// Split every overflowing cluster inside itself, with no global re-run
    /// ([`super::kmedoids_local`]).
    Local,
    /// Grow clusters to the limits and assign with capacity, so nothing is split
    /// ([`super::kmedoids_capacity`]).
    Capacity,
}

/// k-medoids settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Splitting mode.
    pub mode: Mode,
    /// Most assign/update iterations per (re)clustering.
    pub max_iterations: u32,
    /// Stop when the mean medoid shift (hops) is at most this.
    pub shift_threshold: f64,
    /// Iterations after each fast split round.
    pub split_iterations: u32,
    /// Fast mode: fraction of the overflowing clusters (largest first) split per round.
    pub split_fraction: f64,
    /// Paper mode only: after this long, finish the remaining splits the fast way.
    pub paper_budget: Duration,
    /// Run on the global rayon pool (true) or on one thread (false); results are identical.
    pub parallel: bool,
    /// Capacity mode: what a growing cluster prefers ([`super::kmedoids_capacity::Grow`]).
    pub grow: super::kmedoids_capacity::Grow,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            mode: Mode::Fast,
            max_iterations: 16,
            shift_threshold: 0.0,
            split_iterations: 2,
            split_fraction: 0.25,
            paper_budget: Duration::from_secs(300),
            parallel: true,
            grow: Default::default(),
        }
    }
}

/// The k-medoids strategy.
pub struct KMedoids {
    /// Settings.
    pub config: Config,
}

impl Strategy for KMedoids {
    fn name(&self) -> &'static str {
        match self.config.mode {
            Mode::Fast => "kmedoids-flat",
            Mode::Paper => "kmedoids-paper",
            Mode::Local => "kmedoids-local",
            Mode::Capacity => "kmedoids",
        }
    }

    fn summary(&self) -> &'static str {
        match self.config.mode {
            Mode::Fast => "k-medoids on the triangle dual graph (hop distance), all overflowing clusters split at once",
            Mode::Paper => "k-medoids as the paper runs it: one cluster added and everything re-run per overflow",
            Mode::Local => "k-medoids whose overflowing clusters are bisected inside themselves, no global re-run",
            Mode::Capacity => "k-medoids whose clusters grow to the limits and take triangles only while they have room",
        }
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let run = || cluster(mesh, limits, &self.config).meshlets;
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
    /// Split rounds (fast) or clusters added (paper).
    pub splits: u32,
    /// Whether paper mode ran out of budget and finished the fast way.
    pub budget_exhausted: bool,
    /// Mean hop distance after the initial clustering, before any split (the k-medoids objective).
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
    pub fn from_grown(
        mesh: &Mesh,
        limits: Limits,
        g: super::kmedoids_capacity::Grown,
        seconds: f64,
    ) -> Self {
        let meshlets = pack(mesh, &g.labels, &g.distances, g.medoids.len(), limits);
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

/// Triangles per initial cluster.
pub fn cluster_size(limits: Limits, mode: Mode) -> usize {
    match mode {
        // The paper: k = ceil(T / max_triangles).
        Mode::Paper => limits.max_triangles as usize,
        // A closed 64-vertex patch holds about 1.5 x 64 triangles (Euler: T ~ 2V minus the
        // boundary), so starting at that size leaves far fewer clusters to split.
        Mode::Fast | Mode::Local | Mode::Capacity => (limits.max_triangles as usize)
            .min(3 * limits.max_vertices as usize / 2)
            .max(1),
    }
}

/// Fast mode's split choice: the largest overflows first (ties to the lower cluster), a fraction
/// per round; returns the clusters to split.
pub fn split_choice(mut over: Vec<(u32, u32)>, fraction: f64) -> Vec<u32> {
    over.sort_unstable_by_key(|&(c, size)| (std::cmp::Reverse(size), c));
    let take = ((over.len() as f64 * fraction).ceil() as usize).clamp(1, over.len());
    over[..take].iter().map(|&(c, _)| c).collect()
}

/// Runs the whole pipeline.
pub fn cluster(mesh: &Mesh, limits: Limits, cfg: &Config) -> Clustering {
    let t0 = Instant::now();
    let vt = vertex_triangles(mesh);
    let dual = dual_graph(mesh, &vt);
    if cfg.mode == Mode::Capacity {
        let g = super::kmedoids_capacity::cluster(
            mesh,
            &dual,
            &vt,
            limits,
            cfg.grow,
            cfg.max_iterations,
        );
        return Clustering::from_grown(mesh, limits, g, t0.elapsed().as_secs_f64());
    }
    let per_cluster = cluster_size(limits, cfg.mode);
    let mut medoids = initial_medoids(mesh, per_cluster);
    let mut iterations = 0;
    cover_components(&dual, &mut medoids);
    let mut cache = UpdateCache::default();
    let mut skipped_updates = 0;
    let mut converge = |medoids: &mut Vec<u32>, max_iter: u32, iterations: &mut u32| {
        let mut state = assign(&dual, medoids);
        for _ in 0..max_iter {
            let up = update_cached(&dual, &state.0, medoids, &mut cache);
            skipped_updates += up.skipped;
            *iterations += 1;
            let changed = up.medoids != *medoids;
            *medoids = sorted(up.medoids);
            state = assign(&dual, medoids);
            if !changed || up.mean_shift <= cfg.shift_threshold {
                break;
            }
        }
        state
    };
    let (mut labels, mut distances) = converge(&mut medoids, cfg.max_iterations, &mut iterations);
    let initial_iterations = iterations;
    let initial_seconds = t0.elapsed().as_secs_f64();
    let initial_mean_distance = mean(&distances);

    let start = Instant::now();
    let mut splits = 0;
    let mut budget_exhausted = false;
    if cfg.mode == Mode::Local {
        // Overflowing clusters are bisected inside themselves: no global re-run.
        splits = super::kmedoids_local::split_until_fit(
            mesh,
            &dual,
            &vt,
            limits,
            cfg.split_iterations,
            &mut medoids,
            &mut labels,
            &mut distances,
        );
    } else {
        let mut paper = cfg.mode == Mode::Paper;
        for _round in 0..10_000 {
            let over = overflowing(mesh, &labels, medoids.len(), limits);
            if over.is_empty() {
                break;
            }
            if paper && start.elapsed() > cfg.paper_budget {
                paper = false;
                budget_exhausted = true;
            }
            let far = farthest_members(&labels, &distances, medoids.len());
            if paper {
                // The paper: one more cluster (at the farthest member of the largest overflow), then
                // everything again.
                let worst = *over
                    .iter()
                    .max_by_key(|&&(c, size)| (size, std::cmp::Reverse(c)))
                    .expect("non-empty");
                medoids.push(far[worst.0 as usize]);
                medoids = sorted(medoids);
                (labels, distances) = converge(&mut medoids, cfg.max_iterations, &mut iterations);
            } else {
                // The largest overflows first, a fraction per round: neighbours re-balance between
                // rounds, so fewer clusters end up split than when all are split at once.
                medoids.extend(
                    split_choice(over, cfg.split_fraction)
                        .into_iter()
                        .map(|c| far[c as usize]),
                );
                medoids = sorted(medoids);
                (labels, distances) = converge(&mut medoids, cfg.split_iterations, &mut iterations);
            }
            splits += 1;
        }
    }
    let meshlets = pack(mesh, &labels, &distances, medoids.len(), limits);
    Clustering {
        medoids,
        labels,
        distances,
        iterations,
        splits,
        budget_exhausted,
        initial_mean_distance,
        initial_iterations,
        initial_seconds,
        skipped_updates,
        meshlets,
    }
}

fn mean(d: &[u32]) -> f64 {
    d.iter().map(|&x| x as f64).sum::<f64>() / d.len().max(1) as f64
}

fn sorted(mut v: Vec<u32>) -> Vec<u32> {
    v.sort_unstable();
    v.dedup();
    v
}

/// k = ceil(T / per_cluster) medoids, spread evenly along the Morton order of triangle centroids.
pub fn initial_medoids(mesh: &Mesh, per_cluster: usize) -> Vec<u32> {
    let t = mesh.triangle_count();
    let k = t.div_ceil(per_cluster.max(1)).max(1);
    let (lo, hi) = mesh.bounding_box();
    let scale = (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let mut keyed: Vec<(u64, u32)> = (0..t)
        .map(|i| {
            let c = mesh
                .triangle(i)
                .iter()
                .map(|&v| mesh.position(v))
                .sum::<glam::Vec3>()
                / 3.0;
            let q = ((c - lo) / scale * 1023.0).clamp(glam::Vec3::ZERO, glam::Vec3::splat(1023.0));
            (morton3(q.x as u32, q.y as u32, q.z as u32), i as u32)
        })
        .collect();
    keyed.sort_unstable();
    // The middle of each of k equal runs of the Morton order.
    sorted((0..k).map(|j| keyed[(j * t + t / 2) / k].1).collect())
}

pub(crate) fn morton3(x: u32, y: u32, z: u32) -> u64 {
    let spread = |v: u32| {
        let mut v = v as u64 & 0x3ff;
        v = (v | (v << 16)) & 0x0300_00ff;
        v = (v | (v << 8)) & 0x0300_f00f;
        v = (v | (v << 4)) & 0x030c_30c3;
        (v | (v << 2)) & 0x0924_9249
    };
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}

/// Assigns, then adds a medoid (the lowest unreached triangle) to every dual-graph component that has
/// none, until all triangles are reached.
fn cover_components(dual: &Csr, medoids: &mut Vec<u32>) {
    loop {
        let (labels, _) = assign(dual, medoids);
        if !add_component_medoids(dual, &labels, medoids) {
            return;
        }
    }
}

/// One medoid (its lowest triangle) for each component of unreached triangles; returns whether any
/// was added. `medoids` stays sorted.
pub fn add_component_medoids(dual: &Csr, labels: &[u32], medoids: &mut Vec<u32>) -> bool {
    let Some(first) = labels.iter().position(|&l| l == UNREACHED) else {
        return false;
    };
    // Flood the unreached triangles component by component, one new medoid each.
    let mut seen = vec![false; labels.len()];
    let mut stack = Vec::new();
    for t in first..labels.len() {
        if labels[t] != UNREACHED || seen[t] {
            continue;
        }
        medoids.push(t as u32);
        seen[t] = true;
        stack.push(t as u32);
        while let Some(u) = stack.pop() {
            for &n in dual.row(u as usize) {
                if !seen[n as usize] {
                    seen[n as usize] = true;
                    stack.push(n);
                }
            }
        }
    }
    *medoids = sorted(std::mem::take(medoids));
    true
}

/// Multi-source BFS from all medoids at once: (labels, distances). Level-synchronous; each
/// relaxation is an order-independent `fetch_min` on `(distance << 32) | cluster`, so the lowest
/// cluster wins ties and the result is the same on any number of threads.
pub fn assign(dual: &Csr, medoids: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let t = dual.rows();
    let key: Vec<AtomicU64> = (0..t).map(|_| AtomicU64::new(u64::MAX)).collect();
    for (c, &m) in medoids.iter().enumerate() {
        key[m as usize].store(c as u64, Ordering::Relaxed);
    }
    let mut frontier: Vec<u32> = medoids.to_vec();
    let mut d: u64 = 0;
    while !frontier.is_empty() {
        let next = (d + 1) << 32;
        frontier.par_iter().for_each(|&u| {
            let label = key[u as usize].load(Ordering::Relaxed) & 0xffff_ffff;
            for &n in dual.row(u as usize) {
                key[n as usize].fetch_min(next | label, Ordering::Relaxed);
            }
        });
        let mut nf: Vec<u32> = frontier
            .par_iter()
            .flat_map_iter(|&u| dual.row(u as usize).iter().copied())
            .filter(|&n| key[n as usize].load(Ordering::Relaxed) >> 32 == d + 1)
            .collect();
        nf.par_sort_unstable();
        nf.dedup();
        frontier = nf;
        d += 1;
    }
    key.into_iter()
        .map(|k| {
            let k = k.into_inner();
            if k == u64::MAX {
                (UNREACHED, UNREACHED)
            } else {
                ((k & 0xffff_ffff) as u32, (k >> 32) as u32)
            }
        })
        .unzip()
}

/// Members of each cluster, ascending (counting sort of the labels).
pub fn members(labels: &[u32], k: usize) -> Csr {
    Csr::from_pairs(
        k,
        labels
            .iter()
            .enumerate()
            .filter(|(_, &l)| l != UNREACHED)
            .map(|(t, &l)| (l, t as u32)),
    )
}

/// Result of the medoid update.
#[derive(Clone, Debug, PartialEq)]
pub struct Update {
    /// New medoid of each cluster (same cluster order as the input).
    pub medoids: Vec<u32>,
    /// Mean hop distance between old and new medoids.
    pub mean_shift: f64,
    /// Clusters whose result came from the cache.
    pub skipped: u32,
}

/// New medoid per cluster: the member with the smallest sum of hop distances to the other members
/// inside the cluster (lowest id on ties). `medoids` are the current ones, which `labels` came from.
pub fn update(dual: &Csr, labels: &[u32], medoids: &[u32]) -> Update {
    update_cached(dual, labels, medoids, &mut UpdateCache::default())
}

/// Results of earlier updates by member set: a cluster whose members did not change since the last
/// iteration has the same medoid, so its all-pairs BFS is skipped. Exact: hits compare the whole
/// member list.
#[derive(Default)]
pub struct UpdateCache {
    /// Old medoid -> (member list, new medoid, shift).
    entries: std::collections::HashMap<u32, (Vec<u32>, u32, u32)>,
}

/// [`update`] with a cache that carries over between iterations.
pub fn update_cached(
    dual: &Csr,
    labels: &[u32],
    medoids: &[u32],
    cache: &mut UpdateCache,
) -> Update {
    let k = medoids.len();
    let mem = members(labels, k);
    let results: Vec<(u32, u32, bool)> = (0..k)
        .into_par_iter()
        .map(|c| {
            let m = mem.row(c);
            if let Some((prev, new, shift)) = cache.entries.get(&medoids[c]) {
                if prev.as_slice() == m {
                    return (*new, *shift, true);
                }
            }
            let local = LocalGraph::new(dual, labels, c as u32, m);
            let mut dist = vec![u32::MAX; m.len()];
            let mut queue = Vec::with_capacity(m.len());
            let old = m
                .binary_search(&medoids[c])
                .expect("a medoid belongs to its own cluster");
            let best = local.medoid_index();
            // Shift: hops from the new medoid to the old one, inside the cluster.
            local.bfs(best, &mut dist, &mut queue);
            (m[best], dist[old], false)
        })
        .collect();
    let skipped = results.iter().filter(|r| r.2).count() as u32;
    let mean_shift = results.iter().map(|r| r.1 as f64).sum::<f64>() / k.max(1) as f64;
    // Keyed by the medoid the next iteration will see for each cluster.
    cache.entries = (0..k)
        .map(|c| (results[c].0, (mem.row(c).to_vec(), results[c].0, 0)))
        .collect();
    Update {
        medoids: results.into_iter().map(|r| r.0).collect(),
        mean_shift,
        skipped,
    }
}

/// A cluster's induced subgraph with local indices (member `i` of the ascending member list is
/// node `i`).
pub(crate) struct LocalGraph {
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl LocalGraph {
    /// The subgraph of cluster `c`, whose members `m` are ascending.
    pub(crate) fn new(dual: &Csr, labels: &[u32], c: u32, m: &[u32]) -> Self {
        let mut offsets = Vec::with_capacity(m.len() + 1);
        let mut items = Vec::with_capacity(m.len() * 3);
        offsets.push(0);
        for &t in m {
            for &n in dual.row(t as usize) {
                if labels[n as usize] == c {
                    items.push(m.binary_search(&n).expect("same label means member") as u32);
                }
            }
            offsets.push(items.len() as u32);
        }
        Self { offsets, items }
    }

    /// Sum of hop distances from every node to all others (an unreachable node counts as the
    /// node count, as in [`Self::bfs`]), all sources at once: `reach_k(x)`, the nodes within k
    /// hops of x, is x's bitset OR its neighbours' `reach_{k-1}`, and sum(x) adds
    /// `n - |reach_k(x)|` per level until no set grows. O(n * degree * n/64 * levels) word
    /// operations without a branch per edge, where n BFS cost O(n * edges) with one; for the
    /// medoid update's clusters (up to a few hundred members) that is several times less work.
    pub(crate) fn distance_sums(&self) -> Vec<u64> {
        let n = self.len();
        if n <= 128 {
            return self.distance_sums_128();
        }
        let w = n.div_ceil(64);
        let mut cur = vec![0u64; n * w];
        for x in 0..n {
            cur[x * w + x / 64] |= 1 << (x % 64);
        }
        let mut next = cur.clone();
        let mut count = vec![1u64; n];
        let mut acc = vec![0u64; n];
        let mut levels = 0u64;
        loop {
            for x in 0..n {
                acc[x] += n as u64 - count[x];
            }
            levels += 1;
            let mut grew = false;
            for x in 0..n {
                let dst = &mut next[x * w..(x + 1) * w];
                if count[x] == n as u64 {
                    // Full: nothing to add.
                    dst.copy_from_slice(&cur[x * w..(x + 1) * w]);
                    continue;
                }
                dst.copy_from_slice(&cur[x * w..(x + 1) * w]);
                for &y in self.row(x) {
                    let src = &cur[y as usize * w..(y as usize + 1) * w];
                    for (d, s) in dst.iter_mut().zip(src) {
                        *d |= s;
                    }
                }
                let c: u64 = dst.iter().map(|b| b.count_ones() as u64).sum();
                if c != count[x] {
                    grew = true;
                    count[x] = c;
                }
            }
            std::mem::swap(&mut cur, &mut next);
            if !grew {
                break;
            }
        }
        // An unreachable node was counted once per level; it counts n instead.
        (0..n)
            .map(|x| {
                let missing = n as u64 - count[x];
                acc[x] - missing * levels + missing * n as u64
            })
            .collect()
    }

    /// [`Self::distance_sums`] for at most 128 nodes (every cluster that fits a meshlet: the
    /// presets' triangle limits are at most 128), each reach set one `u128`: no inner loop over
    /// words, a fifth of the run's medoid time on the dragon. Same sums.
    fn distance_sums_128(&self) -> Vec<u64> {
        let n = self.len();
        let full = n as u32;
        let mut cur: Vec<u128> = (0..n).map(|x| 1u128 << x).collect();
        let mut next = vec![0u128; n];
        let mut count = vec![1u32; n];
        let mut acc = vec![0u64; n];
        let mut levels = 0u64;
        loop {
            for x in 0..n {
                acc[x] += (full - count[x]) as u64;
            }
            levels += 1;
            let mut grew = false;
            for x in 0..n {
                let mut d = cur[x];
                if count[x] != full {
                    for &y in self.row(x) {
                        d |= cur[y as usize];
                    }
                    let c = d.count_ones();
                    if c != count[x] {
                        grew = true;
                        count[x] = c;
                    }
                }
                next[x] = d;
            }
            std::mem::swap(&mut cur, &mut next);
            if !grew {
                break;
            }
        }
        (0..n)
            .map(|x| {
                let missing = (full - count[x]) as u64;
                acc[x] - missing * levels + missing * n as u64
            })
            .collect()
    }

    /// The node with the smallest [`Self::distance_sums`] (lowest index on ties): the paper's
    /// medoid.
    pub(crate) fn medoid_index(&self) -> usize {
        let sums = self.distance_sums();
        (0..self.len())
            .min_by_key(|&x| (sums[x], x))
            .expect("a cluster has members")
    }

    /// Nodes.
    pub(crate) fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Neighbours of node `u` inside the cluster.
    pub(crate) fn row(&self, u: usize) -> &[u32] {
        &self.items[self.offsets[u] as usize..self.offsets[u + 1] as usize]
    }

    /// BFS from local node `s`; returns the sum of distances (unreachable members count as the
    /// member count, so a disconnected cluster is never preferred), and leaves the distances in
    /// `dist` (`u32::MAX` where unreached).
    fn bfs(&self, s: usize, dist: &mut [u32], queue: &mut Vec<u32>) -> u64 {
        let m = dist.len() as u64;
        dist.fill(u32::MAX);
        queue.clear();
        dist[s] = 0;
        queue.push(s as u32);
        let mut head = 0;
        // Sum over queued members (each is added when queued).
        let mut sum = 0u64;
        while head < queue.len() {
            let u = queue[head] as usize;
            head += 1;
            let next = dist[u] + 1;
            for &n in &self.items[self.offsets[u] as usize..self.offsets[u + 1] as usize] {
                if dist[n as usize] == u32::MAX {
                    dist[n as usize] = next;
                    sum += next as u64;
                    queue.push(n);
                }
            }
        }
        sum + (m - queue.len() as u64) * m
    }
}

/// Clusters over a limit, as (cluster, size) where size is triangles, or vertices beyond the limit
/// scaled to triangles (so a larger overflow ranks first).
pub fn overflowing(mesh: &Mesh, labels: &[u32], k: usize, limits: Limits) -> Vec<(u32, u32)> {
    let mem = members(labels, k);
    let triangles: Vec<u32> = (0..k).map(|c| mem.row(c).len() as u32).collect();
    // Distinct vertices only where the triangle limit holds (the rule checks triangles first).
    let vertices: Vec<u32> = (0..k)
        .into_par_iter()
        .map(|c| {
            let m = mem.row(c);
            if m.len() > limits.max_triangles as usize {
                return 0;
            }
            let mut v: Vec<u32> = m.iter().flat_map(|&t| mesh.triangle(t as usize)).collect();
            v.sort_unstable();
            v.dedup();
            v.len() as u32
        })
        .collect();
    overflowing_from_counts(&triangles, &vertices, limits)
}

/// [`overflowing`] from per-cluster triangle and distinct-vertex counts (the GPU `stats` kernel's
/// output; a vertex count is only read for clusters within the triangle limit).
pub fn overflowing_from_counts(
    triangles: &[u32],
    vertices: &[u32],
    limits: Limits,
) -> Vec<(u32, u32)> {
    (0..triangles.len())
        .filter(|&c| triangles[c] > limits.max_triangles || vertices[c] > limits.max_vertices)
        .map(|c| (c as u32, triangles[c]))
        .collect()
}

/// The member farthest (in assign hops) from each cluster's medoid; lowest id on ties.
pub fn farthest_members(labels: &[u32], distances: &[u32], k: usize) -> Vec<u32> {
    let mut far = vec![(0u32, u32::MAX); k];
    for (t, (&l, &d)) in labels.iter().zip(distances).enumerate() {
        if l != UNREACHED {
            let f = &mut far[l as usize];
            if d > f.0 || f.1 == u32::MAX {
                *f = (d, t as u32);
            }
        }
    }
    far.into_iter().map(|f| f.1).collect()
}

/// Meshlets from clusters: each cluster in BFS order from its medoid (distance, then id), chunked
/// by the builder if it does not fit.
pub fn pack(mesh: &Mesh, labels: &[u32], distances: &[u32], k: usize, limits: Limits) -> Meshlets {
    let mem = members(labels, k);
    let mut b = MeshletBuilder::new(mesh.vertex_count(), limits);
    let mut order: Vec<(u32, u32)> = Vec::new();
    for c in 0..k {
        order.clear();
        order.extend(mem.row(c).iter().map(|&t| (distances[t as usize], t)));
        order.sort_unstable();
        for &(_, t) in &order {
            b.push(mesh.triangle(t as usize));
        }
        b.flush();
    }
    b.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::validate;

    #[test]
    fn assign_breaks_ties_to_the_lower_cluster() {
        // A path of 5 triangles 0-1-2-3-4; medoids 0 and 4: triangle 2 is 2 hops from both.
        let dual = Csr::from_pairs(
            5,
            [
                (0, 1),
                (1, 0),
                (1, 2),
                (2, 1),
                (2, 3),
                (3, 2),
                (3, 4),
                (4, 3),
            ]
            .into_iter(),
        );
        let (labels, dist) = assign(&dual, &[0, 4]);
        assert_eq!(labels, vec![0, 0, 0, 1, 1]);
        assert_eq!(dist, vec![0, 1, 2, 1, 0]);
        // Update: the centre of {0,1,2} is 1.
        let up = update(&dual, &labels, &[0, 4]);
        assert_eq!(up.medoids, vec![1, 3]);
        assert_eq!(up.mean_shift, 1.0);
    }

    #[test]
    fn distance_sums_equal_one_bfs_per_member() {
        // A tube (cycles, several paths between members) and a cluster in two pieces (the
        // unreachable members count as the member count); sizes either side of the one-word
        // (128-node) path.
        let m = generate::knot_tube(40, 8, 1);
        let vt = vertex_triangles(&m);
        let dual = dual_graph(&m, &vt);
        for pick in [0..150u32, 0..70u32, 0..128u32, 0..129u32] {
            let mut labels = vec![1u32; m.triangle_count()];
            for t in pick.clone() {
                labels[t as usize] = 0;
            }
            // Drop a band to split the second cluster in two.
            if pick.end == 70 {
                labels[30..40].fill(1);
            }
            let members: Vec<u32> = (0..m.triangle_count() as u32)
                .filter(|&t| labels[t as usize] == 0)
                .collect();
            let g = LocalGraph::new(&dual, &labels, 0, &members);
            let sums = g.distance_sums();
            let (mut dist, mut queue) = (vec![0; members.len()], Vec::new());
            for (s, &sum) in sums.iter().enumerate() {
                assert_eq!(sum, g.bfs(s, &mut dist, &mut queue), "member {s}");
            }
        }
    }

    #[test]
    fn serial_and_parallel_agree_and_output_is_valid() {
        let m = generate::knot_tube(120, 12, 3);
        let limits = Limits::new(32, 40).unwrap();
        let par = crate::test_pool(4).install(|| cluster(&m, limits, &Config::default()));
        let ser = crate::test_pool(1).install(|| cluster(&m, limits, &Config::default()));
        // Everything but the wall-clock time.
        let key = |c: &Clustering| {
            (
                c.medoids.clone(),
                c.labels.clone(),
                c.distances.clone(),
                c.iterations,
                c.splits,
                c.meshlets.clone(),
            )
        };
        assert_eq!(key(&par), key(&ser));
        assert_eq!(par.initial_mean_distance, ser.initial_mean_distance);
        // Converged clusters are not updated again (the cache), the same on one thread.
        assert!(par.skipped_updates > 0);
        assert_eq!(par.skipped_updates, ser.skipped_updates);
        validate(&m, &par.meshlets, limits).unwrap();
        assert!(overflowing(&m, &par.labels, par.medoids.len(), limits).is_empty());
        let paper = cluster(
            &m,
            limits,
            &Config {
                mode: Mode::Paper,
                ..Config::default()
            },
        );
        validate(&m, &paper.meshlets, limits).unwrap();
    }

    #[test]
    fn disconnected_components_each_get_a_medoid() {
        let a = generate::terrain(6, 1);
        let mut m = a.clone();
        let n = a.vertex_count() as u32;
        m.positions
            .extend(a.positions.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
        m.indices.extend(a.indices.iter().map(|i| i + n));
        // One triangle alone, touching nothing.
        m.positions
            .extend([[9.0, 0.0, 0.0], [9.5, 0.0, 0.0], [9.0, 0.5, 0.0]]);
        m.indices.extend([2 * n, 2 * n + 1, 2 * n + 2]);
        let c = cluster(&m, Limits::new(64, 126).unwrap(), &Config::default());
        assert!(c.labels.iter().all(|&l| l != UNREACHED));
        validate(&m, &c.meshlets, Limits::DEFAULT).unwrap();
    }
}
