//! The flat and the paper's k-medoids (`kmedoids-flat`, `kmedoids-paper`): nearest-medoid
//! assignment with no regard to the limits, then overflowing clusters split until they fit. The
//! GPU runs the flat method step for step (`gpu::kmedoids::cluster_flat`).
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
use super::split::{farthest_members, overflowing, split_choice};
use super::update::{update_cached, UpdateCache};
use super::{mean, pack, Clustering, Config, Mode};
use crate::common::{morton3, sorted, Csr};
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use rayon::prelude::*;
use std::time::Instant;

/// Triangles per initial cluster.
pub fn cluster_size(limits: Limits, mode: Mode) -> usize {
    match mode {
        // The paper: k = ceil(T / max_triangles).
        Mode::Paper => limits.max_triangles as usize,
        // A closed 64-vertex patch holds about 1.5 x 64 triangles (Euler: T ~ 2V minus the
        // boundary), so starting at that size leaves far fewer clusters to split.
        Mode::Flat | Mode::Capacity | Mode::Tiled | Mode::Regions => (limits.max_triangles
            as usize)
            .min(3 * limits.max_vertices as usize / 2)
            .max(1),
    }
}

/// Runs the flat or the paper's method (`mode`) over the dual graph; `t0` is when the run began
/// (the adjacency counts into the initial clustering's time).
pub fn cluster(
    mesh: &Mesh,
    dual: &Csr,
    limits: Limits,
    mode: Mode,
    cfg: &Config,
    t0: Instant,
) -> Clustering {
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

/// Triangles in the Morton order of their centroids (10 bits per axis over the bounding box's
/// longest side), ties to the lower id.
pub fn morton_order(mesh: &Mesh) -> Vec<u32> {
    let (lo, hi) = mesh.bounding_box();
    let frame = MortonFrame::new(lo, hi);
    // (key, id) pairs are distinct, so the parallel unstable sort has one result.
    let mut keyed: Vec<(u32, u32)> = (0..mesh.triangle_count())
        .into_par_iter()
        .map(|i| {
            let [a, b, c] = mesh.triangle(i).map(|v| mesh.position(v));
            (frame.key(a, b, c), i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_par_iter().map(|(_, i)| i).collect()
}

/// The frame of the Morton keys, from the mesh's bounding box: a triangle's corner sum minus
/// `lo3`, times `factor`, is its centroid in 0..=1023 along the box's longest side. Only `+`, `-`
/// and `x` touch a triangle, in a fixed order, so `wgsl/morton.wgsl` computes the same keys on
/// any device (the divisions happen once, here, and reach the GPU as these two values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MortonFrame {
    /// Three times the box's low corner.
    pub lo3: glam::Vec3,
    /// 1023 over three times the box's longest side.
    pub factor: f32,
    /// [`FINE_MAX`] over three times the box's longest side.
    pub fine: f32,
}

/// The largest coordinate of a fine centroid cell ([`MortonFrame::fine_cell`], 15 bits per axis):
/// `kmedoids-parallel`'s growth key. The Morton cells (10 bits) are as large as a triangle of a
/// mesh of some million triangles, and ties in the key then leave clusters less round, so more of
/// them (the bit counts measured are in `docs/gpu-clustering.md`); 15 bits is the most whose
/// squared distances still fit a `u32` (three squares of `2^15 - 1` stay under `2^32`).
/// `wgsl/prelude.wgsl` holds the same value.
pub const FINE_MAX: u32 = (1 << 15) - 1;

impl MortonFrame {
    /// The frame of the box `lo`..`hi`.
    pub fn new(lo: glam::Vec3, hi: glam::Vec3) -> Self {
        let scale = (hi - lo).max_element().max(f32::MIN_POSITIVE);
        Self {
            lo3: lo * 3.0,
            factor: 1023.0 / (3.0 * scale),
            fine: FINE_MAX as f32 / (3.0 * scale),
        }
    }

    /// The fine grid cell (0..=[`FINE_MAX`] per axis) of the centroid of `a`, `b`, `c`: as
    /// [`Self::cell`], with `fine` for the factor.
    pub fn fine_cell(&self, a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> [u32; 3] {
        self.quantise(a, b, c, self.fine, FINE_MAX)
    }

    /// The corner sum minus `lo3`, times `factor`, truncated to `0..=top` per axis.
    fn quantise(
        &self,
        a: glam::Vec3,
        b: glam::Vec3,
        c: glam::Vec3,
        factor: f32,
        top: u32,
    ) -> [u32; 3] {
        let q = (((a + b) + c - self.lo3) * factor)
            .clamp(glam::Vec3::ZERO, glam::Vec3::splat(top as f32));
        [q.x as u32, q.y as u32, q.z as u32]
    }

    /// The grid cell (0..=1023 per axis) of the centroid of the triangle `a`, `b`, `c`.
    pub fn cell(&self, a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> [u32; 3] {
        self.quantise(a, b, c, self.factor, 1023)
    }

    /// Morton key (30 bits) of the triangle with corners `a`, `b`, `c`.
    pub fn key(&self, a: glam::Vec3, b: glam::Vec3, c: glam::Vec3) -> u32 {
        let [x, y, z] = self.cell(a, b, c);
        morton3(x, y, z) as u32
    }
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

/// A packed centre: `[x | y << 16, z]`, 15 bits per axis.
pub type Centre = [u32; 2];

/// The three coordinates of a packed centre.
pub(crate) fn unpack(c: Centre) -> [u32; 3] {
    [c[0] & 0xffff, c[0] >> 16, c[1]]
}

/// Squared distance between two cells.
pub(crate) fn distance2(a: [u32; 3], b: [u32; 3]) -> u32 {
    (0..3).map(|j| a[j].abs_diff(b[j]).pow(2)).sum()
}

/// Each triangle's fine centroid cell in the Morton frame ([`MortonFrame::fine_cell`], 15 bits
/// per axis along the box's longest side), packed as a [`Centre`]: the geometric term of
/// `kmedoids-parallel`'s growth key and of the boundary moves' rule.
/// Only `+`, `-` and `x` touch a triangle, so `wgsl/morton.wgsl` computes the same words.
pub fn packed_centres(mesh: &Mesh) -> Vec<Centre> {
    let (lo, hi) = mesh.bounding_box();
    let frame = MortonFrame::new(lo, hi);
    (0..mesh.triangle_count())
        .into_par_iter()
        .map(|t| {
            let [a, b, c] = mesh.triangle(t).map(|v| mesh.position(v));
            let [x, y, z] = frame.fine_cell(a, b, c);
            [x | y << 16, z]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::cluster;
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
