//! k-medoids with local splits (`kmedoids-local`): the first lever of the k-medoids speed issue.
//!
//! The fast mode of [`super::kmedoids`] splits overflowing clusters by adding medoids and re-running
//! assign/update over the whole mesh; about two thirds of all its iterations are those global
//! re-runs, most of them over regions no split touched (../shared/notes/kmedoids-scale.md). Here
//! the initial clustering is the same (global assign/update to convergence), but an overflowing
//! cluster is then split inside itself: 2-medoid k-medoids on its own induced subgraph, seeded at
//! its member farthest from the medoid and the member farthest from that one, for
//! `split_iterations` local assign/update steps. A part that still overflows is split again in the
//! next round. Nothing outside an overflowing cluster is visited again.
//!
//! Where it differs from the paper (§3): the medoid is the paper's (smallest sum of in-cluster hop
//! distances, ties to the lowest triangle id), but the paper adds one medoid at a time and
//! re-clusters everything; clusters here never exchange triangles after the initial clustering,
//! so each split is a bisection, which can leave two half-filled parts where a global re-run would
//! have let neighbours absorb the excess.
//!
//! Every part is edge-connected: a local BFS from two seeds inside a connected cluster labels each
//! member through a path of its own part. Determinism: each split is a pure function of the
//! cluster; they run in parallel and are applied in cluster order.

use super::kmedoids::{members, overflowing, LocalGraph, UNREACHED};
use crate::adjacency::Csr;
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use rayon::prelude::*;

/// Searches inside one cluster's induced subgraph.
trait Sub {
    fn flood(&self, seeds: &[usize], part: Option<(&[u32], u32)>) -> (Vec<u32>, Vec<u32>);
    fn medoid(&self, part: &[u32], k: u32) -> usize;
}

impl Sub for LocalGraph {
    /// BFS from the local `seeds` over the nodes whose `part` is `keep` (all nodes for `None`),
    /// each node taking the lowest seed index among those at its distance (a level-synchronous
    /// sweep in ascending node order, so the result is the same on every run). Returns per node
    /// (seed index, distance), `u32::MAX` where unreached.
    fn flood(&self, seeds: &[usize], part: Option<(&[u32], u32)>) -> (Vec<u32>, Vec<u32>) {
        let n = self.len();
        let (mut owner, mut dist) = (vec![u32::MAX; n], vec![u32::MAX; n]);
        let allowed = |u: usize| part.is_none_or(|(p, k)| p[u] == k);
        let mut frontier: Vec<usize> = Vec::new();
        for (i, &s) in seeds.iter().enumerate() {
            if owner[s] == u32::MAX {
                owner[s] = i as u32;
                dist[s] = 0;
                frontier.push(s);
            }
        }
        let mut d = 0;
        while !frontier.is_empty() {
            let mut next = Vec::new();
            for &u in &frontier {
                for &v in self.row(u) {
                    let v = v as usize;
                    if !allowed(v) {
                        continue;
                    }
                    if dist[v] == u32::MAX {
                        dist[v] = d + 1;
                        owner[v] = owner[u];
                        next.push(v);
                    } else if dist[v] == d + 1 && owner[u] < owner[v] {
                        owner[v] = owner[u];
                    }
                }
            }
            next.sort_unstable();
            frontier = next;
            d += 1;
        }
        (owner, dist)
    }

    /// The member of part `k` with the smallest sum of in-part hop distances (lowest index on ties).
    fn medoid(&self, part: &[u32], k: u32) -> usize {
        let nodes: Vec<usize> = (0..part.len()).filter(|&u| part[u] == k).collect();
        let mut best = (u64::MAX, usize::MAX);
        for &s in &nodes {
            let (_, dist) = self.flood(&[s], Some((part, k)));
            let sum: u64 = nodes
                .iter()
                .map(|&u| match dist[u] {
                    u32::MAX => nodes.len() as u64,
                    x => x as u64,
                })
                .sum();
            if (sum, s) < best {
                best = (sum, s);
            }
        }
        best.1
    }
}

/// The member farthest from `s` (lowest index on ties).
fn farthest(dist: &[u32]) -> usize {
    let mut best = (0u32, 0usize);
    for (u, &d) in dist.iter().enumerate() {
        if d != u32::MAX && d > best.0 {
            best = (d, u);
        }
    }
    best.1
}

/// One bisection: (medoids of the two parts as local indices, part of each member).
fn bisect(sub: &LocalGraph, medoid: usize, iterations: u32) -> ([usize; 2], Vec<u32>) {
    let (_, from_medoid) = sub.flood(&[medoid], None);
    let a = farthest(&from_medoid);
    let (_, from_a) = sub.flood(&[a], None);
    let b = farthest(&from_a);
    let mut seeds = [a.min(b), a.max(b)];
    let (mut part, _) = sub.flood(&seeds, None);
    for _ in 0..iterations {
        let next = [sub.medoid(&part, 0), sub.medoid(&part, 1)];
        if next == seeds {
            break;
        }
        // Parts keep their order by medoid index, as clusters do by medoid id.
        seeds = [next[0].min(next[1]), next[0].max(next[1])];
        part = sub.flood(&seeds, None).0;
    }
    (seeds, part)
}

/// Splits every overflowing cluster inside itself until none overflows, then renumbers clusters by
/// ascending medoid and measures each member's hop distance from its medoid. Returns the number
/// of rounds.
pub fn split_until_fit(
    mesh: &Mesh,
    dual: &Csr,
    limits: Limits,
    iterations: u32,
    medoids: &mut Vec<u32>,
    labels: &mut [u32],
    distances: &mut [u32],
) -> u32 {
    let mut rounds = 0;
    loop {
        let over = overflowing(mesh, labels, medoids.len(), limits);
        if over.is_empty() {
            break;
        }
        let mem = members(labels, medoids.len());
        let splits: Vec<(u32, [u32; 2], Vec<u32>)> = over
            .par_iter()
            .map(|&(c, _)| {
                let m = mem.row(c as usize);
                let sub = LocalGraph::new(dual, labels, c, m);
                let at = m
                    .binary_search(&medoids[c as usize])
                    .expect("a medoid belongs to its cluster");
                let (seeds, part) = bisect(&sub, at, iterations);
                (c, [m[seeds[0]], m[seeds[1]]], part)
            })
            .collect();
        for (c, [m0, m1], part) in splits {
            let k = medoids.len() as u32;
            medoids[c as usize] = m0;
            medoids.push(m1);
            let m = mem.row(c as usize);
            for (&t, &p) in m.iter().zip(&part) {
                labels[t as usize] = if p == 1 { k } else { c };
            }
        }
        rounds += 1;
    }
    renumber(medoids, labels);
    refresh_distances(dual, medoids, labels, distances);
    rounds
}

/// Renumbers clusters by ascending medoid (the order `assign` numbers them in).
fn renumber(medoids: &mut Vec<u32>, labels: &mut [u32]) {
    let mut order: Vec<u32> = (0..medoids.len() as u32).collect();
    order.sort_unstable_by_key(|&c| medoids[c as usize]);
    let mut new_id = vec![0u32; medoids.len()];
    for (i, &c) in order.iter().enumerate() {
        new_id[c as usize] = i as u32;
    }
    for l in labels.iter_mut().filter(|l| **l != UNREACHED) {
        *l = new_id[*l as usize];
    }
    *medoids = order.iter().map(|&c| medoids[c as usize]).collect();
}

/// Hop distances from each cluster's medoid inside the cluster (what `pack` orders by).
fn refresh_distances(dual: &Csr, medoids: &[u32], labels: &[u32], distances: &mut [u32]) {
    let mem = members(labels, medoids.len());
    let rows: Vec<(u32, Vec<u32>)> = (0..medoids.len() as u32)
        .into_par_iter()
        .map(|c| {
            let m = mem.row(c as usize);
            let sub = LocalGraph::new(dual, labels, c, m);
            let at = m.binary_search(&medoids[c as usize]).expect("member");
            (c, sub.flood(&[at], None).1)
        })
        .collect();
    for (c, d) in rows {
        for (&t, &x) in mem.row(c as usize).iter().zip(&d) {
            distances[t as usize] = x;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::kmedoids::{cluster, Config, Mode};
    use super::Sub;
    use crate::adjacency::{dual_graph, vertex_triangles};
    use crate::mesh::generate;
    use crate::meshlet::{validate, Limits};

    /// Every cluster is one edge-connected piece of the dual graph.
    fn connected(dual: &crate::adjacency::Csr, labels: &[u32], k: usize) -> bool {
        let mem = super::members(labels, k);
        (0..k).all(|c| {
            let m = mem.row(c);
            let sub = super::LocalGraph::new(dual, labels, c as u32, m);
            m.is_empty() || sub.flood(&[0], None).1.iter().all(|&d| d != u32::MAX)
        })
    }

    #[test]
    fn local_splits_fit_stay_connected_and_do_not_depend_on_threads() {
        let cfg = Config {
            mode: Mode::Local,
            ..Config::default()
        };
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        let meshes = [
            generate::knot_tube(120, 12, 3),
            generate::terrain(40, 2),
            generate::cad_part(200, 1),
            generate::strut_lattice(3, 6, 2),
        ];
        for (i, m) in meshes.iter().enumerate() {
            let dual = dual_graph(m, &vertex_triangles(m));
            for limits in [Limits::DEFAULT, Limits::new(32, 40).unwrap()] {
                let a = pool(1).install(|| cluster(m, limits, &cfg));
                let b = pool(4).install(|| cluster(m, limits, &cfg));
                assert_eq!(a.labels, b.labels, "mesh {i} {limits}");
                assert_eq!(a.meshlets, b.meshlets, "mesh {i} {limits}");
                validate(m, &a.meshlets, limits).unwrap();
                assert!(
                    connected(&dual, &a.labels, a.medoids.len()),
                    "mesh {i} {limits}"
                );
                // Local splits leave no cluster over the limits: pack chunks nothing.
                assert_eq!(a.meshlets.len(), a.medoids.len(), "mesh {i} {limits}");
                // Medoids are sorted and each labels itself at distance 0.
                assert!(a.medoids.windows(2).all(|w| w[0] < w[1]));
                for (c, &t) in a.medoids.iter().enumerate() {
                    assert_eq!(
                        (a.labels[t as usize], a.distances[t as usize]),
                        (c as u32, 0)
                    );
                }
            }
        }
    }
}
