//! Grouping a level's meshlets by k-medoids on the meshlet graph: our alternative to
//! meshoptimizer's `partition_clusters`, measured beside it by `bench lod`.
//!
//! The graph joins two meshlets that share a welded vertex, weighted by nothing: distances are hop
//! counts, as in the JCGT paper's k-medoids over the triangle graph (`strategy::kmedoids`). With
//! `k = ceil(n / size)` medoids seeded at even steps along the Morton order of the meshlet
//! spheres' centres, each round assigns every meshlet to its nearest medoid (one multi-source BFS;
//! ties go to the medoid listed first) and moves each medoid to the member with the smallest
//! eccentricity inside its group. A connected piece no medoid reaches gets its own. Four rounds:
//! the assignment rarely changes after the second on the shared meshes. Unlike the partitioner,
//! nothing balances group sizes, which is the point of measuring it.

use super::Cluster;
use std::collections::VecDeque;

/// Assignment rounds.
const ROUNDS: usize = 4;

/// Meshlet adjacency as CSR: meshlets sharing a welded vertex (`vertices` = welded vertex count
/// bound).
fn graph(vertices: usize, clusters: &[Cluster]) -> (Vec<u32>, Vec<u32>) {
    // Vertex -> meshlets CSR first.
    let mut count = vec![0u32; vertices + 1];
    let mut per: Vec<Vec<u32>> = Vec::with_capacity(clusters.len());
    for c in clusters {
        let mut vs: Vec<u32> = c.tris.iter().flatten().copied().collect();
        vs.sort_unstable();
        vs.dedup();
        for &v in &vs {
            count[v as usize + 1] += 1;
        }
        per.push(vs);
    }
    for i in 0..vertices {
        count[i + 1] += count[i];
    }
    let mut fill = count.clone();
    let mut items = vec![0u32; count[vertices] as usize];
    for (m, vs) in per.iter().enumerate() {
        for &v in vs {
            items[fill[v as usize] as usize] = m as u32;
            fill[v as usize] += 1;
        }
    }
    let mut offsets = vec![0u32];
    let mut adj = Vec::new();
    for (m, vs) in per.iter().enumerate() {
        let start = adj.len();
        for &v in vs {
            let (a, b) = (count[v as usize] as usize, count[v as usize + 1] as usize);
            adj.extend(items[a..b].iter().copied().filter(|&o| o as usize != m));
        }
        crate::common::sort_dedup_tail(&mut adj, start);
        offsets.push(adj.len() as u32);
    }
    (offsets, adj)
}

/// Groups of about `size` meshlets, listed in order of their first meshlet.
pub(crate) fn kmedoids(vertices: usize, clusters: &[Cluster], size: usize) -> Vec<Vec<usize>> {
    let n = clusters.len();
    if n == 0 {
        return Vec::new();
    }
    let (off, adj) = graph(vertices, clusters);
    let nb = |m: usize| &adj[off[m] as usize..off[m + 1] as usize];
    // Seeds: even steps along the Morton order of the sphere centres.
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for c in clusters {
        for a in 0..3 {
            lo[a] = lo[a].min(c.bounds.center[a]);
            hi[a] = hi[a].max(c.bounds.center[a]);
        }
    }
    let scale = (0..3)
        .map(|a| hi[a] - lo[a])
        .fold(f32::MIN_POSITIVE, f32::max);
    let q = |c: &Cluster, a: usize| ((c.bounds.center[a] - lo[a]) / scale * 2_097_151.0) as u32;
    let mut order: Vec<(u64, usize)> = clusters
        .iter()
        .enumerate()
        .map(|(i, c)| (crate::common::morton3(q(c, 0), q(c, 1), q(c, 2)), i))
        .collect();
    order.sort_unstable();
    let k = n.div_ceil(size.max(1));
    let mut medoids: Vec<usize> = (0..k).map(|i| order[i * n / k].1).collect();
    medoids.dedup();
    let mut label = vec![u32::MAX; n];
    for _ in 0..ROUNDS {
        assign(&medoids, &nb, &mut label);
        // Pieces no medoid reaches get one each (the first unreached meshlet).
        while let Some(m) = label.iter().position(|&l| l == u32::MAX) {
            medoids.push(m);
            assign(&medoids, &nb, &mut label);
        }
        let mut members = vec![Vec::new(); medoids.len()];
        for (m, &l) in label.iter().enumerate() {
            members[l as usize].push(m);
        }
        for (g, ms) in members.iter().enumerate() {
            if let Some(best) = centre(ms, &nb, &label, g as u32) {
                medoids[g] = best;
            }
        }
    }
    let mut groups = vec![Vec::new(); medoids.len()];
    for (m, &l) in label.iter().enumerate() {
        groups[l as usize].push(m);
    }
    groups.retain(|g| !g.is_empty());
    groups.sort_by_key(|g| g[0]);
    groups
}

/// Multi-source BFS: each meshlet gets the index of its nearest medoid (ties: the medoid listed
/// first reaches it first); unreachable meshlets keep `u32::MAX`.
fn assign<'a>(medoids: &[usize], nb: &impl Fn(usize) -> &'a [u32], label: &mut [u32]) {
    label.fill(u32::MAX);
    let mut queue = VecDeque::new();
    for (g, &m) in medoids.iter().enumerate() {
        if label[m] == u32::MAX {
            label[m] = g as u32;
            queue.push_back(m);
        }
    }
    while let Some(m) = queue.pop_front() {
        for &o in nb(m) {
            if label[o as usize] == u32::MAX {
                label[o as usize] = label[m];
                queue.push_back(o as usize);
            }
        }
    }
}

/// The member of group `g` with the smallest eccentricity inside the group (hop distances over
/// members only); ties to the lowest index.
fn centre<'a>(
    members: &[usize],
    nb: &impl Fn(usize) -> &'a [u32],
    label: &[u32],
    g: u32,
) -> Option<usize> {
    let mut best: Option<(usize, usize)> = None;
    let mut dist = std::collections::HashMap::new();
    for &s in members {
        dist.clear();
        dist.insert(s, 0usize);
        let mut queue = VecDeque::from([s]);
        let mut ecc = 0;
        while let Some(m) = queue.pop_front() {
            let d = dist[&m];
            ecc = ecc.max(d);
            for &o in nb(m) {
                let o = o as usize;
                if label[o] == g && !dist.contains_key(&o) {
                    dist.insert(o, d + 1);
                    queue.push_back(o);
                }
            }
        }
        // A member the others cannot reach inside the group is a poor centre.
        let ecc = if dist.len() < members.len() {
            usize::MAX
        } else {
            ecc
        };
        if best.is_none_or(|(e, _)| ecc < e) {
            best = Some((ecc, s));
        }
    }
    best.map(|(_, s)| s)
}
