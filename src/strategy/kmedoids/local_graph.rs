//! One cluster's induced subgraph of the dual graph, with local node numbers: the medoid (all
//! members' distance sums at once) and breadth-first distances. Every k-medoids step that looks
//! inside a cluster reads it; the medoid step of the sequential and the parallel method
//! ([`medoids_and_distances`]) is here too.

use super::assign::members;
use crate::common::Csr;
use rayon::prelude::*;

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

    /// The node with the smallest [`Self::distance_sums`] (lowest index on ties): the paper's
    /// medoid.
    pub(crate) fn medoid_index(&self) -> usize {
        if self.len() <= 128 {
            return self.medoid_128();
        }
        let sums = self.distance_sums();
        (0..self.len())
            .min_by_key(|&x| (sums[x], x))
            .expect("a cluster has members")
    }

    /// [`Self::medoid_index`] for at most 128 nodes (every cluster that fits a meshlet: the
    /// presets' triangle limits are at most 128), each reach set one `u128`: no inner loop over
    /// words, the medoid update's hot loop. On x86-64 the loop is compiled a second time with the
    /// `popcnt` instruction, taken where the CPU has it: the default target lacks it, and
    /// counting bits in software was most of this loop's time (integers either way, so the
    /// medoid is the same).
    fn medoid_128(&self) -> usize {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("popcnt") {
            // SAFETY: the CPU has the feature the function is compiled for (checked above).
            return unsafe { self.medoid_128_popcnt() };
        }
        self.least_sum_128()
    }

    /// [`Self::least_sum_128`] compiled with hardware bit counts.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "popcnt")]
    unsafe fn medoid_128_popcnt(&self) -> usize {
        self.least_sum_128()
    }

    /// The reach-set levels of [`Self::distance_sums`] in one `u128` per node, stopped once the
    /// least sum is decided rather than when no set grows. A node whose set is full has its
    /// exact sum; any other's sum is at least what it has plus the next level's term
    /// (`n - |reach|`, already known). When the least (sum, index) among full nodes is below
    /// every other node's (bound, index), it is the medoid. The central node fills at its
    /// eccentricity, about half the diameter, and the others' bounds usually pass it soon after,
    /// so the levels stop well before the diameter. A cluster in pieces never fills a set and
    /// runs to the end.
    #[inline(always)]
    fn least_sum_128(&self) -> usize {
        let n = self.len();
        let full = n as u32;
        let mut cur: Vec<u128> = (0..n).map(|x| 1u128 << x).collect();
        let mut next = vec![0u128; n];
        let mut count = vec![1u32; n];
        let mut acc = vec![0u64; n];
        let mut levels = 0u64;
        loop {
            levels += 1;
            let mut grew = false;
            let mut best = (u64::MAX, usize::MAX);
            let mut bound = (u64::MAX, usize::MAX);
            for x in 0..n {
                acc[x] += (full - count[x]) as u64;
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
                if count[x] == full {
                    best = best.min((acc[x], x));
                } else {
                    bound = bound.min((acc[x] + (full - count[x]) as u64, x));
                }
            }
            std::mem::swap(&mut cur, &mut next);
            if best < bound {
                return best.1;
            }
            if !grew {
                break;
            }
        }
        // In pieces: an unreachable node was counted once per level; it counts n instead.
        (0..n)
            .min_by_key(|&x| {
                let missing = (full - count[x]) as u64;
                (acc[x] - missing * levels + missing * n as u64, x)
            })
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
    pub(crate) fn bfs(&self, s: usize, dist: &mut [u32], queue: &mut Vec<u32>) -> u64 {
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

/// Hop distance of every member of `sub` from member `at`. A cluster joined through a vertex has
/// pieces `at` does not reach: each is numbered on after the previous one, from its lowest member.
pub(crate) fn member_distances(sub: &LocalGraph, at: usize) -> Vec<u32> {
    // A queue BFS: a level-by-level sweep with a list per level took twice as long here.
    let (mut d, mut more, mut queue) = (vec![0; sub.len()], Vec::new(), Vec::new());
    sub.bfs(at, &mut d, &mut queue);
    while let Some(u) = d.iter().position(|&x| x == u32::MAX) {
        let base = d
            .iter()
            .filter(|&&x| x != u32::MAX)
            .max()
            .map_or(0, |&x| x + 1);
        more.resize(sub.len(), 0);
        sub.bfs(u, &mut more, &mut queue);
        for (x, &y) in d.iter_mut().zip(&more) {
            if *x == u32::MAX && y != u32::MAX {
                *x = base + y;
            }
        }
    }
    d
}

/// The paper's medoid of cluster `c` (members `m`, ascending) and each member's hop distance to
/// it inside the cluster.
pub(crate) fn medoid_of(dual: &Csr, labels: &[u32], c: u32, m: &[u32]) -> (u32, Vec<u32>) {
    let sub = LocalGraph::new(dual, labels, c, m);
    let best = sub.medoid_index();
    (m[best], member_distances(&sub, best))
}

/// The paper's medoid of each of the `k` clusters (smallest sum of in-cluster hop distances, ties
/// to the lowest id) and every triangle's in-cluster hop distance to it, from one local graph per
/// cluster (members in other pieces continue the count). One invocation per cluster on the GPU.
pub fn medoids_and_distances(dual: &Csr, labels: &[u32], k: usize) -> (Vec<u32>, Vec<u32>) {
    let mem = members(labels, k);
    let per: Vec<(u32, Vec<u32>)> = (0..k)
        .into_par_iter()
        .map(|c| medoid_of(dual, labels, c as u32, mem.row(c)))
        .collect();
    let mut distances = vec![0; labels.len()];
    let mut medoids = Vec::with_capacity(k);
    for (c, (m, d)) in per.into_iter().enumerate() {
        medoids.push(m);
        for (&t, &x) in mem.row(c).iter().zip(&d) {
            distances[t as usize] = x;
        }
    }
    (medoids, distances)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjacency::{dual_graph, vertex_triangles};
    use crate::mesh::generate;

    #[test]
    fn the_early_stop_finds_the_least_sum_on_many_clusters() {
        // Runs of triangles along a twisted tube: bands, strips and patches whose medoids tie
        // often (symmetric shapes), which is where stopping early could go wrong.
        let m = generate::knot_tube(60, 10, 2);
        let vt = vertex_triangles(&m);
        let dual = dual_graph(&m, &vt);
        let t = m.triangle_count() as u32;
        let mut checked = 0;
        for start in (0..t).step_by(53) {
            for len in [1u32, 2, 7, 33, 64, 100, 127, 128] {
                let members: Vec<u32> = (start..(start + len).min(t)).collect();
                let mut labels = vec![1u32; t as usize];
                for &x in &members {
                    labels[x as usize] = 0;
                }
                let g = LocalGraph::new(&dual, &labels, 0, &members);
                let (mut dist, mut queue) = (vec![0; members.len()], Vec::new());
                let least = (0..members.len())
                    .min_by_key(|&s| (g.bfs(s, &mut dist, &mut queue), s))
                    .unwrap();
                assert_eq!(g.least_sum_128(), least, "start {start}, length {len}");
                checked += 1;
            }
        }
        assert!(checked > 100);
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
            // The medoid, stopped early or not, is the least (sum, index).
            let least = (0..members.len()).min_by_key(|&x| (sums[x], x)).unwrap();
            assert_eq!(g.medoid_index(), least);
            // The portable build of the one-word path, whichever build the CPU took above.
            if members.len() <= 128 {
                assert_eq!(g.least_sum_128(), least);
            }
        }
    }
}
