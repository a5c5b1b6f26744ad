//! `kmedoids-tiled`: the capacity-aware method run on many regions of the mesh at once, then
//! the light clusters on region borders merged in matching rounds.
//!
//! The capacity-aware method ([`super::capacity`]) grows one cluster at a time, each into the
//! space its predecessors left; that order is what fills clusters to the vertex limit (fills and
//! counts in results/kmedoids.md), and it is sequential. Two data-parallel designs measured here
//! while looking for a parallel one lost on the count (`docs/gpu-clustering.md`): nearest-medoid
//! cells balanced by additive per-cluster weights (a power diagram on the dual graph), and
//! vertex-gain label propagation under the limits; both leave a quarter or more of the cells over
//! the vertex limit, and splitting those costs more meshlets than the order saves. So the
//! parallelism is one level up:
//!
//! 1. **Regions** ([`super::coarse`]): the flat method's seeding and assignment at a coarse scale,
//!    [`Config::region_triangles`] per region: seeds spread along the Morton order of centroids,
//!    one multi-source BFS. Each BFS cell is edge-connected; small pieces no seed reaches join the
//!    region nearest in Morton order.
//! 2. **Clusters per region**, all regions at once: the capacity-aware method on the region's
//!    triangles alone (growth, orphans, merges, re-assignment rounds where they pay). Regions
//!    share no state, so the result does not depend on which thread runs which region.
//! 3. **Border merges** ([`merge_borders`], where there are two regions or more): a cluster that
//!    did not fill (the growth ran into the region's edge) proposes to the neighbouring cluster
//!    with which it shares the most vertices among those whose union fits both limits (ties to
//!    the pair of lower ids); mutual proposals merge, in rounds until none does. Each round is a
//!    map over the clusters and a map over the pairs.
//! 4. **Medoids**: the paper's medoid and the in-cluster hop distances of every cluster a merge
//!    made (a parallel map; the others keep their region's).
//! 5. **Boundary moves** ([`super::moves`]), the medoid iteration: border triangles move to a
//!    neighbouring cluster whose medoid is nearer, in rounds of per-triangle maps and
//!    per-cluster sums, within the limits and keeping every cluster edge-connected; the changed
//!    clusters get the paper's medoid again. The objective falls and the count stays
//!    ([`Config::move_rounds`] rounds). Clusters numbered by ascending medoid.
//!
//! [`Config::region_triangles`] trades count for parallelism: every region ends with a partly
//! filled cluster or two at its border, which step 3 recovers only in part (the sweep in
//! results/kmedoids.md). Where it differs from the paper (section 3): as the capacity-aware
//! method (k comes out of the growth, nothing is split), the growth runs per region, so its
//! order is local, and its iteration moves only border triangles, and only where the limits let
//! them (the paper re-assigns every triangle to its nearest medoid and splits what overflows). Every cluster is edge-connected wherever the mesh is: the per-region method's
//! clusters are (whole small pieces packed together are the exception it makes), and the border
//! merges join clusters across an edge only. Determinism: regions, per-region runs and matching
//! rounds depend on the input alone.
//!
//! No GPU path: step 2 is the sequential code. [`super::regions`] keeps steps 1 and 4 and
//! replaces step 2 with a grower a kernel runs (`kmedoids-parallel`); `docs/gpu-clustering.md`
//! says which of this method's steps that grower still lacks.

use super::assign::{members, UNREACHED};
use super::capacity::{self, medoid_of, Grown};
use super::coarse::regions;
use super::flat::packed_centres;
use super::merge::renumber;
use super::moves::move_boundaries;
use super::{pack, Clustering, Config};
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::common::{sorted, union_len, Csr};
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use rayon::prelude::*;
use std::cmp::Reverse;
use std::time::Instant;

/// Runs steps 1-4 over the dual graph; `t0` is when the run began (the adjacency counts in).
pub fn cluster(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
    limits: Limits,
    cfg: &Config,
    t0: Instant,
) -> Clustering {
    let (region, k_regions) = regions(mesh, dual, cfg.region_triangles as usize);
    let rows = members(&region, k_regions);
    // Step 2: every region on its own; results in region order. One region is the whole mesh:
    // its own copy would only cost time (the same triangles in the same order).
    let runs: Vec<Grown> = if k_regions == 1 {
        vec![capacity::cluster(
            mesh,
            dual,
            vt,
            limits,
            cfg.grow,
            cfg.max_iterations,
        )]
    } else {
        (0..k_regions)
            .into_par_iter()
            .map(|r| cluster_region(mesh, rows.row(r), limits, cfg))
            .collect()
    };
    let mut labels = vec![UNREACHED; mesh.triangle_count()];
    let mut distances = vec![0u32; mesh.triangle_count()];
    let mut medoids = Vec::new();
    let mut iterations = 0;
    for (r, run) in runs.into_iter().enumerate() {
        let (tris, base) = (rows.row(r), medoids.len() as u32);
        for ((&t, &l), &d) in tris.iter().zip(&run.labels).zip(&run.distances) {
            labels[t as usize] = base + l;
            distances[t as usize] = d;
        }
        medoids.extend(run.medoids.iter().map(|&m| tris[m as usize]));
        iterations += run.iterations;
    }
    let initial_seconds = t0.elapsed().as_secs_f64();
    // One region has no borders: its clusters already had the per-region method's merges.
    let (rounds, merged) = if k_regions == 1 {
        (0, vec![false; medoids.len()])
    } else {
        merge_borders(mesh, dual, limits, &mut labels, &mut medoids)
    };
    // Step 4, for the merged clusters only: the others keep their region's medoid and distances.
    let mem = members(&labels, medoids.len());
    let fresh: Vec<(u32, u32, Vec<u32>)> = (0..medoids.len() as u32)
        .into_par_iter()
        .filter(|&c| merged[c as usize])
        .map(|c| {
            let (medoid, d) = medoid_of(dual, &labels, c, mem.row(c as usize));
            (c, medoid, d)
        })
        .collect();
    for (c, medoid, d) in fresh {
        medoids[c as usize] = medoid;
        for (&t, &x) in mem.row(c as usize).iter().zip(&d) {
            distances[t as usize] = x;
        }
    }
    // Step 5.
    let moves = move_boundaries(
        mesh,
        dual,
        vt,
        limits,
        &packed_centres(mesh),
        &mut labels,
        &mut medoids,
        &mut distances,
        cfg.move_rounds,
    );
    renumber(&mut medoids, &mut labels);
    let meshlets = pack(mesh, &labels, &distances, medoids.len(), limits);
    Clustering {
        medoids,
        labels,
        distances,
        iterations: iterations + moves.rounds,
        splits: rounds,
        budget_exhausted: false,
        initial_mean_distance: moves.objective_before,
        initial_iterations: 0,
        initial_seconds,
        skipped_updates: 0,
        meshlets,
    }
}

/// Step 2 for one region (`tris`, ascending): its triangles as a mesh of their own, clustered by
/// the capacity-aware method (labels, distances and medoids in the region's local numbers).
fn cluster_region(mesh: &Mesh, tris: &[u32], limits: Limits, cfg: &Config) -> Grown {
    let verts = sorted(
        tris.iter()
            .flat_map(|&t| mesh.triangle(t as usize))
            .collect(),
    );
    let local = |v: u32| verts.binary_search(&v).expect("region vertex") as u32;
    let sub = Mesh {
        positions: verts.iter().map(|&v| mesh.positions[v as usize]).collect(),
        indices: tris
            .iter()
            .flat_map(|&t| mesh.triangle(t as usize).map(local))
            .collect(),
    };
    let vt = vertex_triangles(&sub);
    let dual = dual_graph(&sub, &vt);
    capacity::cluster(&sub, &dual, &vt, limits, cfg.grow, cfg.max_iterations)
}

/// Step 3: merges clusters that did not fill with a neighbour, in rounds of mutual proposals
/// (each cluster proposes to the neighbour sharing the most vertices whose union fits the limits,
/// ties to the pair of lower ids). Clusters are renumbered `0..k'` in the order of the lower id
/// of each merged pair, which keeps its entry in `medoids` (a placeholder until the medoid is
/// recomputed). Returns the rounds that merged something and which clusters a merge made.
pub fn merge_borders(
    mesh: &Mesh,
    dual: &Csr,
    limits: Limits,
    labels: &mut [u32],
    medoids: &mut Vec<u32>,
) -> (u32, Vec<bool>) {
    let mut k = medoids.len();
    let mut merged_into = vec![false; k];
    let mut rounds = 0;
    loop {
        let mem = members(labels, k);
        let verts: Vec<Vec<u32>> = (0..k)
            .into_par_iter()
            .map(|c| {
                sorted(
                    mem.row(c)
                        .iter()
                        .flat_map(|&t| mesh.triangle(t as usize))
                        .collect(),
                )
            })
            .collect();
        // A full cluster (at a limit) takes part in no merge: nothing fits with it.
        let open = |c: usize| {
            (verts[c].len() as u32) < limits.max_vertices
                && (mem.row(c).len() as u32) < limits.max_triangles
        };
        let choice: Vec<u32> = (0..k)
            .into_par_iter()
            .map(|c| {
                if !open(c) {
                    return UNREACHED;
                }
                let mut next: Vec<u32> = mem
                    .row(c)
                    .iter()
                    .flat_map(|&t| dual.row(t as usize).iter().map(|&n| labels[n as usize]))
                    .filter(|&d| d != c as u32 && d != UNREACHED && open(d as usize))
                    .collect();
                next.sort_unstable();
                next.dedup();
                let mut best = ((0usize, Reverse(0usize), Reverse(0usize)), UNREACHED);
                for d in next {
                    let tris = mem.row(c).len() + mem.row(d as usize).len();
                    if tris > limits.max_triangles as usize {
                        continue;
                    }
                    let union = union_len(&verts[c], &verts[d as usize]);
                    if union > limits.max_vertices as usize {
                        continue;
                    }
                    let shared = verts[c].len() + verts[d as usize].len() - union;
                    // Most shared vertices: the merged cluster's boundary is shortest. The key
                    // is the pair's, the same from both sides, so the best pair overall is
                    // always mutual and a round merges something while any pair fits.
                    let key = (
                        shared,
                        Reverse(c.min(d as usize)),
                        Reverse(c.max(d as usize)),
                    );
                    if best.1 == UNREACHED || key > best.0 {
                        best = (key, d);
                    }
                }
                best.1
            })
            .collect();
        // Mutual pairs: the higher id joins the lower.
        let mut into: Vec<u32> = (0..k as u32).collect();
        let mut merged = 0;
        for c in 0..k {
            let d = choice[c];
            if d != UNREACHED && (d as usize) > c && choice[d as usize] == c as u32 {
                into[d as usize] = c as u32;
                merged += 1;
            }
        }
        if merged == 0 {
            return (rounds, merged_into);
        }
        rounds += 1;
        // Survivors keep their order, their medoid entry and whether a merge made them.
        let mut new_id = vec![UNREACHED; k];
        let mut next = 0;
        for c in 0..k {
            if into[c] == c as u32 {
                new_id[c] = next;
                medoids[next as usize] = medoids[c];
                let absorbed = choice[c] != UNREACHED && into[choice[c] as usize] == c as u32;
                merged_into[next as usize] = merged_into[c] || absorbed;
                next += 1;
            }
        }
        medoids.truncate(next as usize);
        merged_into.truncate(next as usize);
        labels.par_iter_mut().for_each(|l| {
            if *l != UNREACHED {
                *l = new_id[into[*l as usize] as usize];
            }
        });
        k = next as usize;
    }
}

#[cfg(test)]
mod tests {
    use super::super::{cluster, Mode};
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::validate;

    #[test]
    fn same_output_on_any_thread_count_and_valid() {
        let m = generate::knot_tube(160, 12, 3);
        let limits = Limits::new(32, 40).unwrap();
        let cfg = Config {
            region_triangles: 300,
            ..Config::default()
        };
        let run = |n| crate::test_pool(n).install(|| cluster(&m, limits, Mode::Tiled, &cfg));
        let (a, b) = (run(1), run(4));
        assert_eq!(
            (&a.medoids, &a.labels, &a.distances, a.iterations, a.splits),
            (&b.medoids, &b.labels, &b.distances, b.iterations, b.splits)
        );
        assert_eq!(a.meshlets, b.meshlets);
        validate(&m, &a.meshlets, limits).unwrap();
        // Several regions, so the border merges had work.
        assert!(regions(&m, &dual_graph(&m, &vertex_triangles(&m)), 300).1 >= 4);
        // Every cluster fits: packing never had to chunk one.
        assert_eq!(a.meshlets.len(), a.medoids.len());
    }

    #[test]
    fn border_merges_only_join_neighbours_that_fit() {
        // A 3 x 3 grid of quads cut into 9 one-quad clusters: everything fits in one.
        let m = generate::terrain(4, 1);
        let vt = vertex_triangles(&m);
        let dual = dual_graph(&m, &vt);
        let mut labels: Vec<u32> = (0..m.triangle_count() as u32).map(|t| t / 2).collect();
        let k = m.triangle_count() / 2;
        let mut medoids: Vec<u32> = (0..k as u32).map(|c| 2 * c).collect();
        let (rounds, merged) = merge_borders(
            &m,
            &dual,
            Limits::new(64, 126).unwrap(),
            &mut labels,
            &mut medoids,
        );
        assert!(rounds >= 1);
        assert!(labels.iter().all(|&l| l == 0), "{labels:?}");
        assert_eq!((medoids.len(), merged), (1, vec![true]));
        // Under a 4-vertex limit no two triangles pairs can join (a quad has 4 vertices already).
        let mut labels: Vec<u32> = (0..m.triangle_count() as u32).map(|t| t / 2).collect();
        let before = labels.clone();
        let mut medoids: Vec<u32> = (0..k as u32).map(|c| 2 * c).collect();
        let (rounds, merged) = merge_borders(
            &m,
            &dual,
            Limits::new(4, 126).unwrap(),
            &mut labels,
            &mut medoids,
        );
        assert_eq!((rounds, merged), (0, vec![false; k]));
        assert_eq!(labels, before);
    }
}
