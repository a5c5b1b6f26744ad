//! The flat and the paper's k-medoids (`kmedoids-flat`, `kmedoids-paper`): nearest-medoid
//! assignment with no regard to the limits, then overflowing clusters split until they fit. The
//! GPU runs the flat method step for step (`gpu::kmedoids_flat::cluster`).
//!
//! 1. [`initial_medoids`]: k = ceil(T / per_cluster) triangles spread in Morton order of
//!    centroids; every dual-graph component gets one ([`add_component_medoids`]).
//! 2. [`assign`]: one multi-source BFS from all medoids at once. Each
//!    triangle takes the smallest packed key `(distance << 32) | cluster`, so ties go to the lower
//!    cluster id (= lower medoid triangle id: clusters are numbered by ascending medoid) whatever
//!    the processing order; on a GPU this is one `atomicMin` per relaxation.
//! 3. [`update`](super::update::update): each cluster's new medoid is the member with the smallest
//!    sum of hop distances to all other members, inside the cluster; ties to the lowest id.
//! 4. Convergence: the mean hop distance between old and new medoids falls to a threshold, or an
//!    iteration cap is reached.
//! 5. Fit ([`super::split`]): clusters over the vertex or triangle limit get a second medoid at
//!    their farthest member. The paper adds one cluster and re-runs everything (under a time
//!    budget here); the flat method splits the largest overflows a fraction at a time, then runs
//!    a few iterations.
//! 6. [`pack`](super::pack()): each cluster becomes meshlets in BFS order from its medoid; a
//!    cluster that still does not fit is chunked, so the output is always valid.
//!
//! Where it differs from the paper (section 3): the flat method starts from clusters of the size
//! a closed patch at the vertex limit holds (not `max_triangles`) and splits many clusters per
//! round, so far fewer global re-runs are needed; the paper's mode is the paper's loop.

use super::assign::{assign, UNREACHED};
use super::morton::morton_order;
use super::split::{farthest_members, overflowing, split_choice};
use super::update::{update_cached, UpdateCache};
use super::{mean, pack, Clustering, Mode};
use crate::common::{sorted, Csr};
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use std::time::{Duration, Instant};

/// Settings of `kmedoids-flat`; `kmedoids-paper` reads them too (its iterations, and its splits
/// once its budget is spent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Most assign/update iterations per (re)clustering (steps 2-4). The medoids of the shared
    /// meshes settle within a few; 16 bounds the rare oscillation between two medoids.
    pub max_iterations: u32,
    /// Stop when the mean medoid shift (hops) is at most this (step 4); 0 runs to a fixed point.
    pub shift_threshold: f64,
    /// Iterations after each split round (step 5): neighbours re-balance a little between
    /// rounds, and two do most of that.
    pub split_iterations: u32,
    /// Fraction of the overflowing clusters, largest first, split per round (step 5): splitting
    /// all at once splits clusters that a neighbour's split would have relieved.
    pub split_fraction: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            max_iterations: 16,
            shift_threshold: 0.0,
            split_iterations: 2,
            split_fraction: 0.25,
        }
    }
}

/// Settings of `kmedoids-paper` beside [`Config`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperConfig {
    /// After this long, the remaining splits are done the flat way: the paper's loop re-runs
    /// everything per added cluster, which on large meshes takes hours.
    pub budget: Duration,
}

impl Default for PaperConfig {
    fn default() -> Self {
        Self {
            budget: Duration::from_secs(300),
        }
    }
}

/// Triangles per initial cluster.
pub fn cluster_size(limits: Limits, mode: Mode) -> usize {
    match mode {
        // The paper: k = ceil(T / max_triangles).
        Mode::Paper => limits.max_triangles as usize,
        // A closed 64-vertex patch holds about 1.5 x 64 triangles (Euler: T ~ 2V minus the
        // boundary), so starting at that size leaves far fewer clusters to split.
        Mode::Flat | Mode::Sequential | Mode::Parallel => (limits.max_triangles as usize)
            .min(3 * limits.max_vertices as usize / 2)
            .max(1),
    }
}

/// Runs the flat method, or with `paper` the paper's, over the dual graph; `t0` is when the run
/// began (the adjacency counts into the initial clustering's time).
pub fn cluster(
    mesh: &Mesh,
    dual: &Csr,
    limits: Limits,
    cfg: &Config,
    paper: Option<&PaperConfig>,
    t0: Instant,
) -> Clustering {
    let mode = if paper.is_some() {
        Mode::Paper
    } else {
        Mode::Flat
    };
    let budget = paper.map_or(Duration::ZERO, |p| p.budget);
    let per_cluster = cluster_size(limits, mode);
    let mut medoids = initial_medoids(mesh, per_cluster);
    let mut iterations = 0;
    cover_components(dual, &mut medoids);
    let mut cache = UpdateCache::default();
    let mut skipped_updates = 0;
    let mut converge = |medoids: &mut Vec<u32>, max_iter: u32, iterations: &mut u32| {
        let mut state = assign(dual, medoids);
        for _ in 0..max_iter {
            let up = update_cached(dual, &state.0, medoids, &mut cache);
            skipped_updates += up.skipped;
            *iterations += 1;
            let changed = up.medoids != *medoids;
            *medoids = sorted(up.medoids);
            state = assign(dual, medoids);
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
    let mut paper = mode == Mode::Paper;
    for _round in 0..10_000 {
        let over = overflowing(mesh, &labels, medoids.len(), limits);
        if over.is_empty() {
            break;
        }
        if paper && start.elapsed() > budget {
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

/// k = ceil(T / per_cluster) medoids, spread evenly along the Morton order of triangle centroids.
pub fn initial_medoids(mesh: &Mesh, per_cluster: usize) -> Vec<u32> {
    let t = mesh.triangle_count();
    let k = t.div_ceil(per_cluster.max(1)).max(1);
    let order = morton_order(mesh);
    // The middle of each of k equal runs of the Morton order.
    sorted((0..k).map(|j| order[(j * t + t / 2) / k]).collect())
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

#[cfg(test)]
mod tests {
    use super::super::{cluster, Config};
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::validate;

    const FLAT: Mode = Mode::Flat;

    #[test]
    fn serial_and_parallel_agree_and_output_is_valid() {
        let m = generate::knot_tube(120, 12, 3);
        let limits = Limits::new(32, 40).unwrap();
        let par = crate::test_pool(4).install(|| cluster(&m, limits, FLAT, &Config::default()));
        let ser = crate::test_pool(1).install(|| cluster(&m, limits, FLAT, &Config::default()));
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
        let paper = cluster(&m, limits, Mode::Paper, &Config::default());
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
        let c = cluster(&m, Limits::new(64, 126).unwrap(), FLAT, &Config::default());
        assert!(c.labels.iter().all(|&l| l != UNREACHED));
        validate(&m, &c.meshlets, Limits::DEFAULT).unwrap();
    }
}
