//! Step 5 of `kmedoids-parallel`, boundary moves: its medoid iteration, data-parallel and within
//! the limits (the CPU reference of `wgsl/kmedoids_parallel_moves.wgsl`).
//!
//! The paper's iteration (section 3) re-assigns every triangle to its nearest medoid and moves
//! each medoid to its cluster's centre, with no regard to the limits. Here, with the medoids held
//! fixed, a triangle on a cluster's border moves to a neighbouring cluster whose medoid it is
//! nearer, in rounds that are per-triangle maps and per-cluster sums:
//!
//! 1. **Candidates**: a triangle, not a medoid, with a neighbour in another cluster whose hop
//!    distance + 1 is below its own.
//! 2. **Proposals**: its target is the nearest such neighbour's cluster (then the lower id),
//!    counting only neighbours that are not candidates themselves, so the one it attaches to
//!    stays, and only clusters whose medoid's centroid cell is no farther from the triangle's
//!    than its own medoid's (squared distances between
//!    [`packed_centres`](super::super::morton::packed_centres) cells, integers on every device): by hop
//!    distance alone triangles moved along long thin fans towards a medoid across them, and the
//!    bounding spheres grew. Kept only if taking it out leaves every other member's distance as
//!    it was: each of its neighbours one level further out has another parent in the cluster
//!    that is not a candidate.
//! 3. **Acceptance per target**: all of a cluster's proposals if their triangles and new vertices
//!    (summed: an upper bound where two share a vertex) fit the limits at the sizes the round
//!    began with, else the one of greatest gain (then the lowest triangle id) if it fits alone.
//! 4. **Distances** of every cluster that took a triangle, by BFS from its medoid (one that only
//!    gave keeps its members' distances, by step 2's rule).
//!
//! Every accepted move lowers the sum of hop distances to the fixed medoids by its gain: sources
//! keep their distances (step 2), targets can only get shorter paths, and the moved triangle sits
//! one hop from a member that stayed. So the objective falls every round, the cluster count never
//! changes and clusters stay edge-connected. Afterwards the caller gives every changed cluster the
//! paper's medoid again, which can only lower its sum further. Clusters that are not
//! edge-connected (whole small pieces packed together) neither give nor take: their distances are
//! not shortest paths. Determinism: each step depends on the previous round's state alone, and the
//! sums are order-independent.
//!
//! Measured while designing it (the counts in `results/kmedoids.md`): the objective keeps falling
//! for a dozen rounds or more, by less each round, so [`move_boundaries`] takes a round limit.

use super::super::assign::{members, UNREACHED};
use super::super::local_graph::{medoid_of, LocalGraph};
use super::super::mean;
use super::super::morton::{distance2, unpack, Centre};
use crate::common::Csr;
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use rayon::prelude::*;
use std::cmp::Reverse;

/// What [`move_boundaries`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Moves {
    /// Rounds that moved at least one triangle.
    pub rounds: u32,
    /// Triangles moved in all.
    pub moved: u64,
    /// Clusters that gave or took a triangle (their medoid was computed again).
    pub changed: usize,
    /// Mean hop distance to the medoid before the moves.
    pub objective_before: f64,
}

/// A vertex count not taken yet.
const UNCOUNTED: u32 = u32::MAX;

/// A proposal from step 2: the target cluster, the moving triangle's distance there, its gain and
/// the vertices the target does not use yet.
#[derive(Clone, Copy)]
struct Proposal {
    target: u32,
    distance: u32,
    gain: u32,
    new_vertices: u32,
}

/// Runs at most `max_rounds` rounds of steps 1-4 over `labels` and `distances` (hop distances to
/// `medoids` inside each cluster, as the paper's medoid update gives them), then step 5: the
/// paper's medoid of every cluster that changed, and its members' distances. `centres`: every
/// triangle's centroid cell ([`packed_centres`](super::super::morton::packed_centres)).
#[allow(clippy::too_many_arguments)]
pub fn move_boundaries(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
    limits: Limits,
    centres: &[Centre],
    labels: &mut [u32],
    medoids: &mut [u32],
    distances: &mut [u32],
    max_rounds: u32,
) -> Moves {
    let (t, k) = (labels.len(), medoids.len());
    let (mv, mt) = (limits.max_vertices, limits.max_triangles);
    let mut out = Moves {
        objective_before: mean(distances),
        ..Moves::default()
    };
    if max_rounds == 0 {
        return out;
    }
    // A cluster is edge-connected iff each member but the medoid has a parent one hop nearer.
    let orphan: Vec<bool> = (0..t)
        .into_par_iter()
        .map(|x| {
            let (a, d) = (labels[x], distances[x]);
            a != UNREACHED
                && d > 0
                && !dual
                    .row(x)
                    .iter()
                    .any(|&u| labels[u as usize] == a && distances[u as usize] + 1 == d)
        })
        .collect();
    let mut movable = vec![true; k];
    for x in (0..t).filter(|&x| orphan[x]) {
        movable[labels[x] as usize] = false;
    }
    let rows = members(labels, k);
    // Members per cluster, ascending, kept up to date by the moves.
    let mut mem: Vec<Vec<u32>> = (0..k).map(|c| rows.row(c).to_vec()).collect();
    // Vertex counts, taken only for clusters a proposal targets (most clusters are never one).
    let mut vcount = vec![UNCOUNTED; k];
    let mut changed = vec![false; k];
    for round in 0..max_rounds {
        let labels_now: &[u32] = labels;
        let dist_now: &[u32] = distances;
        let open = |u: u32| {
            let b = labels_now[u as usize];
            b != UNREACHED && movable[b as usize]
        };
        // Step 1.
        let candidate: Vec<bool> = (0..t)
            .into_par_iter()
            .map(|x| {
                let (a, d) = (labels_now[x], dist_now[x]);
                d > 0
                    && open(x as u32)
                    && dual.row(x).iter().any(|&u| {
                        labels_now[u as usize] != a && open(u) && dist_now[u as usize] + 1 < d
                    })
            })
            .collect();
        // Step 2's distance rule: b's medoid no farther from x's cell than x's own medoid.
        let medoids_now: &[u32] = medoids;
        let from = |x: u32, c: u32| {
            let medoid = medoids_now[c as usize] as usize;
            distance2(unpack(centres[x as usize]), unpack(centres[medoid]))
        };
        // Step 2.
        let proposals: Vec<(u32, Proposal)> = (0..t as u32)
            .into_par_iter()
            .filter(|&x| candidate[x as usize])
            .filter_map(|x| {
                let own = from(x, labels_now[x as usize]);
                let allowed = |u: u32| open(u) && from(x, labels_now[u as usize]) <= own;
                propose(
                    mesh, dual, vt, labels_now, dist_now, &candidate, &allowed, x,
                )
                .map(|p| (x, p))
            })
            .collect();
        let mut targets: Vec<u32> = proposals
            .iter()
            .map(|(_, p)| p.target)
            .filter(|&b| vcount[b as usize] == UNCOUNTED)
            .collect();
        targets.sort_unstable();
        targets.dedup();
        let counted: Vec<u32> = targets
            .par_iter()
            .map(|&b| vertex_count(mesh, vt, labels_now, b, &mem[b as usize]))
            .collect();
        for (&b, n) in targets.iter().zip(counted) {
            vcount[b as usize] = n;
        }
        // One that cannot fit alone is no demand on its target.
        let fits_alone = |p: &Proposal| {
            let b = p.target as usize;
            (mem[b].len() as u32) < mt && vcount[b] + p.new_vertices <= mv
        };
        let proposals: Vec<(u32, Proposal)> = proposals
            .into_iter()
            .filter(|(_, p)| fits_alone(p))
            .collect();
        // Step 3: per target, the summed demand and the best single proposal.
        let mut demand = vec![(0u32, 0u32); k];
        let mut best: Vec<Option<(u32, Reverse<u32>)>> = vec![None; k];
        for &(x, p) in &proposals {
            let b = p.target as usize;
            demand[b].0 += 1;
            demand[b].1 += p.new_vertices;
            let key = (p.gain, Reverse(x));
            if best[b].is_none_or(|k| key > k) {
                best[b] = Some(key);
            }
        }
        let mut changed_now = vec![false; k];
        let mut took = vec![false; k];
        let mut moved = Vec::new();
        for &(x, p) in &proposals {
            let b = p.target as usize;
            let all_fit = mem[b].len() as u32 + demand[b].0 <= mt && vcount[b] + demand[b].1 <= mv;
            if !all_fit && best[b] != Some((p.gain, Reverse(x))) {
                continue;
            }
            let a = labels[x as usize] as usize;
            labels[x as usize] = p.target;
            distances[x as usize] = p.distance;
            changed_now[a] = true;
            changed_now[b] = true;
            took[b] = true;
            moved.push((a, b, x));
        }
        if moved.is_empty() {
            break;
        }
        out.rounds += 1;
        out.moved += moved.len() as u64;
        // Member lists after every decision: the fit tests read the sizes the round began with.
        for (a, b, x) in moved {
            let i = mem[a].binary_search(&x).expect("a member");
            mem[a].remove(i);
            let i = mem[b].binary_search(&x).expect_err("not yet a member");
            mem[b].insert(i, x);
        }
        for (c, &now) in changed_now.iter().enumerate() {
            changed[c] |= now;
        }
        if round + 1 == max_rounds {
            break;
        }
        // Step 4 (step 5 does it for the last round), for the clusters that took a triangle: one
        // that only gave keeps its members' distances (step 2's rule).
        let labels_now: &[u32] = labels;
        let fresh: Vec<(usize, Vec<u32>)> = (0..k)
            .into_par_iter()
            .filter(|&c| took[c])
            .map(|c| (c, bfs_distances(dual, labels_now, &mem[c], medoids[c])))
            .collect();
        debug_assert!((0..k).filter(|&c| changed_now[c] && !took[c]).all(|c| {
            let d = bfs_distances(dual, labels_now, &mem[c], medoids[c]);
            mem[c]
                .iter()
                .zip(&d)
                .all(|(&x, &h)| distances[x as usize] == h)
        }));
        for (c, d) in fresh {
            for (&x, &h) in mem[c].iter().zip(&d) {
                distances[x as usize] = h;
            }
        }
        for (c, &now) in changed_now.iter().enumerate() {
            if now {
                vcount[c] = UNCOUNTED;
            }
        }
    }
    // Step 5.
    let labels_now: &[u32] = labels;
    let fresh: Vec<(usize, u32, Vec<u32>)> = (0..k)
        .into_par_iter()
        .filter(|&c| changed[c])
        .map(|c| {
            let (medoid, d) = medoid_of(dual, labels_now, c as u32, &mem[c]);
            (c, medoid, d)
        })
        .collect();
    out.changed = fresh.len();
    for (c, medoid, d) in fresh {
        medoids[c] = medoid;
        for (&x, &h) in mem[c].iter().zip(&d) {
            distances[x as usize] = h;
        }
    }
    out
}

/// Step 2 for candidate `x`.
#[allow(clippy::too_many_arguments)]
fn propose(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
    labels: &[u32],
    distances: &[u32],
    candidate: &[bool],
    allowed: &impl Fn(u32) -> bool,
    x: u32,
) -> Option<Proposal> {
    let (a, d) = (labels[x as usize], distances[x as usize]);
    let (distance, target) = dual
        .row(x as usize)
        .iter()
        .filter(|&&u| labels[u as usize] != a && allowed(u) && !candidate[u as usize])
        .map(|&u| (distances[u as usize] + 1, labels[u as usize]))
        .min()?;
    if distance >= d {
        return None;
    }
    // Every member one level further out keeps a parent that stays.
    let keeps = dual.row(x as usize).iter().all(|&u| {
        labels[u as usize] != a
            || distances[u as usize] != d + 1
            || dual.row(u as usize).iter().any(|&w| {
                w != x
                    && labels[w as usize] == a
                    && distances[w as usize] == d
                    && !candidate[w as usize]
            })
    });
    if !keeps {
        return None;
    }
    let corners = mesh.triangle(x as usize);
    let new_vertices = (0..3)
        .filter(|&j| {
            let v = corners[j];
            !corners[..j].contains(&v)
                && !vt
                    .row(v as usize)
                    .iter()
                    .any(|&y| labels[y as usize] == target)
        })
        .count() as u32;
    Some(Proposal {
        target,
        distance,
        gain: d - distance,
        new_vertices,
    })
}

/// Distinct vertices of cluster `c`, whose members `labels` gives as `m`: each counted at the
/// lowest member using it (vertex rows are ascending), with no list to sort.
fn vertex_count(mesh: &Mesh, vt: &Csr, labels: &[u32], c: u32, m: &[u32]) -> u32 {
    let lowest = |v: u32, x: u32| {
        let row = vt.row(v as usize);
        row.iter().find(|&&y| labels[y as usize] == c) == Some(&x)
    };
    m.iter()
        .map(|&x| {
            let corners = mesh.triangle(x as usize);
            (0..3)
                .filter(|&j| !corners[..j].contains(&corners[j]) && lowest(corners[j], x))
                .count() as u32
        })
        .sum()
}

/// Hop distances from `root` inside the cluster whose members are `m` (ascending; the cluster is
/// edge-connected), in member order.
fn bfs_distances(dual: &Csr, labels: &[u32], m: &[u32], root: u32) -> Vec<u32> {
    let sub = LocalGraph::new(dual, labels, labels[root as usize], m);
    let mut d = vec![0; m.len()];
    let at = m.binary_search(&root).expect("the root is a member");
    sub.bfs(at, &mut d, &mut Vec::new());
    debug_assert!(d.iter().all(|&x| x != u32::MAX), "a connected cluster");
    d
}

#[cfg(test)]
mod tests {
    use super::super::super::morton::packed_centres;
    use super::super::super::{cluster, Config, Mode};
    use super::super::Config as ParallelConfig;
    use super::*;
    use crate::adjacency::{cluster_pieces, dual_graph, vertex_triangles};
    use crate::mesh::generate;
    use crate::meshlet::validate;

    #[test]
    fn moves_lower_the_objective_keep_the_count_and_stay_connected() {
        let m = generate::knot_tube(160, 12, 3);
        let dual = dual_graph(&m, &vertex_triangles(&m));
        for limits in [Limits::new(64, 126).unwrap(), Limits::new(16, 12).unwrap()] {
            let run = |rounds| {
                let cfg = Config {
                    parallel: ParallelConfig {
                        region_triangles: 500,
                        move_rounds: rounds,
                    },
                    ..Config::default()
                };
                cluster(&m, limits, Mode::Parallel, &cfg)
            };
            let (before, after) = (run(0), run(4));
            assert!(after.iterations > before.iterations, "no round moved");
            assert_eq!(after.initial_mean_distance, before.mean_distance());
            assert!(after.mean_distance() < before.mean_distance());
            assert_eq!(after.medoids.len(), before.medoids.len());
            validate(&m, &after.meshlets, limits).unwrap();
            assert_eq!(after.meshlets.len(), after.medoids.len());
            // One piece per cluster: the tube is one piece, so every cluster is edge-connected.
            let k = after.medoids.len();
            assert!(cluster_pieces(&dual, &after.labels, k)
                .iter()
                .all(|&(pieces, _)| pieces == 1));
            // Each distance is the in-cluster hop distance to the medoid.
            let rows = members(&after.labels, k);
            for c in 0..k {
                let d = bfs_distances(&dual, &after.labels, rows.row(c), after.medoids[c]);
                for (&x, &h) in rows.row(c).iter().zip(&d) {
                    assert_eq!(after.distances[x as usize], h);
                }
            }
        }
    }

    #[test]
    fn triangles_move_only_into_a_cluster_with_room() {
        // A grid cut in two halves by triangle id: triangles near the cut are nearer the other
        // half's medoid than their own.
        let m = generate::terrain(9, 1);
        let t = m.triangle_count() as u32;
        let vt = vertex_triangles(&m);
        let dual = dual_graph(&m, &vt);
        let labels: Vec<u32> = (0..t).map(|x| u32::from(x >= t / 2)).collect();
        let rows = members(&labels, 2);
        let mut distances = vec![0; t as usize];
        let medoids = [0, 1].map(|c| {
            let (md, d) = medoid_of(&dual, &labels, c, rows.row(c as usize));
            for (&x, &h) in rows.row(c as usize).iter().zip(&d) {
                distances[x as usize] = h;
            }
            md
        });
        let cells = packed_centres(&m);
        let run = |limits, cells: &[Centre]| {
            let (mut l, mut md, mut d) = (labels.clone(), medoids, distances.clone());
            let out = move_boundaries(&m, &dual, &vt, limits, cells, &mut l, &mut md, &mut d, 4);
            (out, l, d)
        };
        let room = Limits::new(256, 256).unwrap();
        // With room, triangles move and the objective falls.
        let (out, _, d) = run(room, &cells);
        assert!(out.moved > 0 && out.changed == 2);
        assert!(d.iter().sum::<u32>() < distances.iter().sum::<u32>());
        // At the triangle limit, nothing moves.
        let (out, l, d) = run(Limits::new(256, t / 2).unwrap(), &cells);
        assert_eq!((out.rounds, out.moved, out.changed), (0, 0, 0));
        assert_eq!((&l, &d), (&labels, &distances));
        // Each half's cells far from the other's: no medoid across is nearer in space.
        let apart: Vec<Centre> = labels.iter().map(|&c| [1000 * c, 0]).collect();
        let (out, l, _) = run(room, &apart);
        assert_eq!((out.rounds, out.moved), (0, 0));
        assert_eq!(l, labels);
    }
}
