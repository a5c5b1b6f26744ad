//! The medoid update (CPU reference of `wgsl/update.wgsl`): each cluster's new medoid is the
//! member with the smallest sum of in-cluster hop distances (the paper's definition, ties to the
//! lowest id), with a cache that skips clusters whose members did not change.

use super::assign::members;
use super::local_graph::LocalGraph;
use crate::common::Csr;
use rayon::prelude::*;

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

#[cfg(test)]
mod tests {
    use super::super::assign::assign;
    use super::*;

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
}
