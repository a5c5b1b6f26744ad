//! The flat assignment (CPU reference of `wgsl/assign.wgsl`): one multi-source BFS over the dual
//! graph from all medoids at once, each triangle taking the nearest medoid (ties to the lower
//! cluster), and the member lists every other step reads.

use crate::common::{Csr, NONE};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Label of a triangle no medoid reaches (another component).
pub const UNREACHED: u32 = NONE;

/// Frontier size from which a BFS level is spread over the rayon pool.
const PARALLEL_LEVEL: usize = 4096;

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
        let push = |&u: &u32| {
            let label = key[u as usize].load(Ordering::Relaxed) & 0xffff_ffff;
            for &n in dual.row(u as usize) {
                key[n as usize].fetch_min(next | label, Ordering::Relaxed);
            }
        };
        let reached = |n: &u32| key[*n as usize].load(Ordering::Relaxed) >> 32 == d + 1;
        // Small levels (long thin meshes have hundreds of them) run on the calling thread: a
        // fork and join per level costs more than the level. The result is the same either way.
        let mut nf: Vec<u32> = if frontier.len() < PARALLEL_LEVEL {
            frontier.iter().for_each(push);
            let mut nf: Vec<u32> = frontier
                .iter()
                .flat_map(|&u| dual.row(u as usize).iter().copied())
                .filter(reached)
                .collect();
            nf.sort_unstable();
            nf
        } else {
            frontier.par_iter().for_each(push);
            let mut nf: Vec<u32> = frontier
                .par_iter()
                .flat_map_iter(|&u| dual.row(u as usize).iter().copied())
                .filter(reached)
                .collect();
            nf.par_sort_unstable();
            nf
        };
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
