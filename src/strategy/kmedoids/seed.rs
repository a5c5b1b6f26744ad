//! Seeding growth (step 1 of the capacity-aware method) and the orphans a finished cluster
//! encloses (step 1b): clusters grown one at a time to the limits from the deepest free triangle.

use crate::common::{Csr, NONE};
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Label of a triangle in no cluster yet.
pub(crate) const FREE: u32 = NONE;

/// The seed order: in each edge-connected piece (pieces by their lowest triangle id), the
/// breadth-first order from that triangle, reversed, so the deepest free triangle seeds next.
/// Within a depth the order follows the neighbour order of `dual`'s rows, which the GPU's dual
/// graph reproduces exactly, so both paths seed alike.
///
/// Why deepest first: in the first growth the free triangles then stay a ball around the piece's
/// root that shrinks from its far side, so a cluster grown from the deepest free triangle rarely
/// cuts a free region off from the rest (an orphan a later seed would turn into a small
/// cluster). On a tree of tubes (the neurons) the clusters start at the branch tips and meet
/// towards the root, as in the bottom-up partition of a tree (Kundu and Misra, SIAM J. Comput.
/// 6(1), 1977), where the tip remainders a sweep leaves behind are what the count loses. It gave
/// fewer meshlets than the order before it (the free frontier triangle with the most taken
/// neighbours, else the next free one in Morton order) at every count preset, for a little more
/// time (the breadth-first pass, and clusters grown further apart in memory); the counts are in
/// `results/kmedoids.md`.
pub(crate) fn seed_order(dual: &Csr) -> Vec<u32> {
    let n = dual.rows();
    let mut seen = vec![false; n];
    let mut order: Vec<u32> = Vec::with_capacity(n);
    for root in 0..n {
        if seen[root] {
            continue;
        }
        seen[root] = true;
        let start = order.len();
        order.push(root as u32);
        let mut i = start;
        while i < order.len() {
            let u = order[i] as usize;
            i += 1;
            for &v in dual.row(u) {
                if !seen[v as usize] {
                    seen[v as usize] = true;
                    order.push(v);
                }
            }
        }
        order[start..].reverse();
    }
    order
}

/// Step 1: grows new clusters over the free triangles of `labels`, one at a time, each to the
/// limits, each taking the orphans it leaves (step 1b), each from the first free triangle of
/// `order` (`seed_order`); appends each cluster's seed to `seeds` (cluster ids continue from
/// `seeds.len()`).
pub fn seed_clusters(
    mesh: &Mesh,
    dual: &Csr,
    limits: Limits,
    grow: Grow,
    order: &[u32],
    labels: &mut [u32],
    seeds: &mut Vec<u32>,
) {
    let (max_v, max_t) = (limits.max_vertices as usize, limits.max_triangles as usize);
    // Keys read a triangle's centroid every time they are (re)computed: compute each once.
    let centroids: Vec<glam::Vec3> = (0..labels.len() as u32)
        .map(|t| centroid(mesh, t))
        .collect();
    // Stamps: the cluster that last marked a vertex / queued a triangle (no clearing per cluster).
    let mut vmark = vec![FREE; mesh.vertex_count()];
    let mut queued = vec![FREE; labels.len()];
    let mut level = vec![0u32; labels.len()];
    let mut heap: BinaryHeap<Reverse<Key>> = BinaryHeap::new();
    let mut rejected = Vec::new();
    let mut orphans = Orphans::new(mesh.vertex_count(), labels.len());
    let mut grown: Vec<u32> = Vec::new();
    let mut frontier: Vec<u32> = Vec::new();
    // Every triangle before `cursor` is taken: a cluster takes free triangles (at or after the
    // cursor) and gives back only its own, so one pass over `order` finds every seed.
    let mut cursor = 0;
    loop {
        while cursor < order.len() && labels[order[cursor] as usize] != FREE {
            cursor += 1;
        }
        let Some(&seed) = order.get(cursor) else {
            break;
        };
        let c = seeds.len() as u32;
        seeds.push(seed);
        let (mut nv, mut nt) = (0usize, 0usize);
        heap.clear();
        rejected.clear();
        grown.clear();
        queued[seed as usize] = c;
        level[seed as usize] = 0;
        let mut sum = glam::Vec3::ZERO;
        let centre = centroids[seed as usize];
        let key =
            |t: u32, vmark: &[u32], labels: &[u32], level: &[u32], centre: glam::Vec3| -> Key {
                (
                    mesh.triangle(t as usize)
                        .iter()
                        .filter(|&&v| vmark[v as usize] != c)
                        .count() as u8,
                    dual.row(t as usize)
                        .iter()
                        .filter(|&&n| labels[n as usize] == FREE)
                        .count() as u8,
                    match grow {
                        Grow::Centre => 0,
                        Grow::Hops => level[t as usize],
                    },
                    // Non-negative floats order as their bits.
                    (centroids[t as usize] - centre).length_squared().to_bits(),
                    t,
                )
            };
        heap.push(Reverse(key(seed, &vmark, labels, &level, centre)));
        while nt < max_t {
            let Some(Reverse(k)) = heap.pop() else { break };
            let t = k.4;
            if labels[t as usize] != FREE {
                continue;
            }
            // Keys only fall (vertices get marked, neighbours taken): a stale entry goes back
            // with its current key.
            let now = key(
                t,
                &vmark,
                labels,
                &level,
                if nt == 0 { centre } else { sum / nt as f32 },
            );
            if now != k {
                heap.push(Reverse(now));
                continue;
            }
            let new = k.0 as usize;
            if nv + new > max_v {
                rejected.push(t);
                if nv == max_v {
                    // Vertex-full and the cheapest candidate adds a vertex: nothing else fits.
                    break;
                }
                continue;
            }
            labels[t as usize] = c;
            grown.push(t);
            nt += 1;
            sum += centroids[t as usize];
            for v in mesh.triangle(t as usize) {
                if vmark[v as usize] != c {
                    vmark[v as usize] = c;
                    nv += 1;
                }
            }
            for &n in dual.row(t as usize) {
                if labels[n as usize] != FREE {
                    continue;
                }
                if queued[n as usize] != c {
                    queued[n as usize] = c;
                    level[n as usize] = level[t as usize] + 1;
                }
                heap.push(Reverse(key(n, &vmark, labels, &level, sum / nt as f32)));
            }
        }
        // Step 1b: the orphans this cluster leaves behind join it.
        frontier.clear();
        frontier.extend(rejected.iter().copied().chain(heap.iter().map(|r| r.0 .4)));
        orphans.absorb(mesh, dual, limits, c, &frontier, &mut grown, labels);
        // The front rule may give the seed back; the medoid steps need a member of each cluster.
        seeds[c as usize] = grown[0];
    }
}

/// Step 1b: the free regions a finished cluster encloses, and their absorption.
///
/// A cluster that fills up while growing past a branch of a thin tube (or around a bump of a
/// surface) leaves the rest of that branch free and reachable only through itself; grown later,
/// such an orphan is a cluster of a few triangles that no neighbour has room to take (on the
/// neurons most light clusters had exactly one neighbour, a full one). So when a cluster stops,
/// every free region next to it of at most half the triangle limit is an orphan, and the cluster
/// takes the orphans, largest first, giving back triangles to make room:
/// - first its last-grown ones ([`Orphans::prefix`]): any prefix of the growth order is
///   edge-connected (each triangle joined next to an earlier one), and an orphan is a whole free
///   region touching the kept prefix, so the cluster stays one piece;
/// - for an orphan that touches only the last-grown triangles (the usual case on the neurons:
///   the orphan lies by the growth front), those nearest the open free region instead, never one
///   next to the orphan ([`Orphans::front_shed`]), kept only when the result is one piece.
///
/// The given-back triangles are free again (later seeds reach them); each rule gives back at most
/// half of the cluster as it stands when the rule runs. Each rule lowered the count at every count
/// preset, the two together most, for spheres a little larger and still under meshoptimizer's.
/// Absorbing only what fits without giving back changed nothing; giving back at most a quarter,
/// or no more than the orphans hold, gained less; re-growing the cluster with the orphans
/// preferred was no better on average.
struct Orphans {
    /// Per triangle: 1 + the cluster whose check visited it last (0: none; zeroed pages are free).
    stamp: Vec<u32>,
    /// Per triangle visited by the current cluster's check: its region's index, or [`OPEN`].
    region: Vec<u32>,
    /// Per vertex: triangles of the cluster being cut back that use it (valid where `vstamp` is
    /// the current attempt).
    vcount: Vec<u32>,
    vstamp: Vec<u32>,
    /// Per vertex: the last attempt whose orphans use it.
    ostamp: Vec<u32>,
    /// Counter behind the per-attempt stamps (`vstamp`, `ostamp`, `tseen`): never reset, so
    /// no clearing between attempts.
    attempt: u32,
    /// Breadth-first queue of the region search.
    queue: Vec<u32>,
    /// Per triangle, in [`Orphans::front_shed`]: queued, given back or flooded (one stamp each).
    tseen: Vec<u32>,
}

/// [`Orphans::region`] of a free triangle whose region is larger than an orphan.
const OPEN: u32 = NONE;

impl Orphans {
    fn new(vertices: usize, triangles: usize) -> Self {
        Self {
            stamp: vec![0; triangles],
            // Read only where `stamp` says this check wrote it.
            region: vec![0; triangles],
            vcount: vec![0; vertices],
            vstamp: vec![0; vertices],
            ostamp: vec![0; vertices],
            attempt: 0,
            queue: Vec::new(),
            tseen: vec![0; triangles],
        }
    }

    /// Starts an attempt: distinct vertices of the orphans `take`, of the cluster `grown`, and of
    /// both; `vcount` then holds each vertex's uses in `grown`. Returns (attempt stamp, orphan
    /// vertices, cluster vertices, shared vertices).
    fn count_vertices(
        &mut self,
        mesh: &Mesh,
        grown: &[u32],
        take: &[u32],
    ) -> (u32, usize, usize, usize) {
        self.attempt += 1;
        let a = self.attempt;
        let mut orphan_v = 0usize;
        for &t in take {
            for v in mesh.triangle(t as usize) {
                if self.ostamp[v as usize] != a {
                    self.ostamp[v as usize] = a;
                    orphan_v += 1;
                }
            }
        }
        let (mut nv, mut shared) = (0usize, 0usize);
        for &t in grown {
            for v in mesh.triangle(t as usize) {
                let vi = v as usize;
                if self.vstamp[vi] != a {
                    self.vstamp[vi] = a;
                    self.vcount[vi] = 0;
                    nv += 1;
                    shared += usize::from(self.ostamp[vi] == a);
                }
                self.vcount[vi] += 1;
            }
        }
        (a, orphan_v, nv, shared)
    }

    /// Takes triangle `u` out of the counts of attempt `a` (from [`Orphans::count_vertices`]):
    /// a vertex no kept triangle uses any more leaves `nv`, and `shared` if the orphans use it.
    fn release(&mut self, mesh: &Mesh, a: u32, u: u32, nv: &mut usize, shared: &mut usize) {
        for v in mesh.triangle(u as usize) {
            let vi = v as usize;
            self.vcount[vi] -= 1;
            if self.vcount[vi] == 0 {
                *nv -= 1;
                *shared -= usize::from(self.ostamp[vi] == a);
            }
        }
    }

    /// Finds the orphans among the free regions of `frontier` (cluster `c`'s free neighbours)
    /// and absorbs those that fit, largest first (then by the triangle the search started from),
    /// by the last-grown rule, then each one left by the front rule; `grown` is the cluster in
    /// growth order, updated. Returns the triangles given back (the seed order reaches them
    /// anyway; the tests check them).
    #[allow(clippy::too_many_arguments)]
    fn absorb(
        &mut self,
        mesh: &Mesh,
        dual: &Csr,
        limits: Limits,
        c: u32,
        frontier: &[u32],
        grown: &mut Vec<u32>,
        labels: &mut [u32],
    ) -> Vec<u32> {
        let regions = self.regions(dual, limits.max_triangles as usize / 2, c, frontier, labels);
        if regions.is_empty() {
            return Vec::new();
        }
        let mut take: Vec<u32> = Vec::new();
        let mut keep = grown.len();
        let mut failed: Vec<&Vec<u32>> = Vec::new();
        for r in &regions {
            let with: Vec<u32> = take.iter().chain(r).copied().collect();
            // Giving back more than half was measured to cost more than it saves.
            match self.prefix(mesh, dual, limits, c, grown, &with, labels) {
                Some(n) if 2 * n >= grown.len() => {
                    take = with;
                    keep = n;
                }
                _ => failed.push(r),
            }
        }
        let mut shed = grown.split_off(keep);
        for &t in &shed {
            labels[t as usize] = FREE;
        }
        for &t in &take {
            labels[t as usize] = c;
        }
        grown.extend(take);
        for r in failed {
            if let Some(more) = self.front_shed(mesh, dual, limits, c, grown, r, labels) {
                shed.extend(more);
            }
        }
        shed
    }

    /// An orphan `r` that no prefix of `grown` can take: the cluster gives back instead the
    /// triangles nearest the open free region (breadth-first inwards from the front), never one
    /// next to `r`, until `r` fits; kept only when at most half is given back and the cluster with
    /// `r` is one edge-connected piece. Returns the triangles given back.
    #[allow(clippy::too_many_arguments)]
    fn front_shed(
        &mut self,
        mesh: &Mesh,
        dual: &Csr,
        limits: Limits,
        c: u32,
        grown: &mut Vec<u32>,
        r: &[u32],
        labels: &mut [u32],
    ) -> Option<Vec<u32>> {
        let check = c + 1;
        let rid = self.region[r[0] as usize];
        let in_r = |stamp: &[u32], region: &[u32], t: u32| {
            labels[t as usize] == FREE && stamp[t as usize] == check && region[t as usize] == rid
        };
        let next_to_r = |stamp: &[u32], region: &[u32], t: u32| {
            dual.row(t as usize).iter().any(|&n| in_r(stamp, region, n))
        };
        // Free and not in a closed region of this check: the open region (or given back).
        let open_free = |stamp: &[u32], region: &[u32], t: u32| {
            labels[t as usize] == FREE && (stamp[t as usize] != check || region[t as usize] == OPEN)
        };
        let (a, orphan_v, mut nv, mut shared) = self.count_vertices(mesh, grown, r);
        let (max_v, max_t) = (limits.max_vertices as usize, limits.max_triangles as usize);
        // Breadth-first from the cluster's triangles on the open front; `tseen` marks visited.
        let mut queue: Vec<u32> = Vec::new();
        for &t in grown.iter() {
            let on_front = dual
                .row(t as usize)
                .iter()
                .any(|&n| open_free(&self.stamp, &self.region, n));
            if on_front && !next_to_r(&self.stamp, &self.region, t) {
                self.tseen[t as usize] = a;
                queue.push(t);
            }
        }
        let mut removed = 0usize;
        let mut i = 0;
        let mut fits = false;
        while i < queue.len() {
            if grown.len() - removed + r.len() <= max_t && nv + orphan_v - shared <= max_v {
                fits = true;
                break;
            }
            if 2 * (removed + 1) > grown.len() {
                break;
            }
            let u = queue[i];
            i += 1;
            removed += 1;
            self.release(mesh, a, u, &mut nv, &mut shared);
            for &n in dual.row(u as usize) {
                if labels[n as usize] == c
                    && self.tseen[n as usize] != a
                    && !next_to_r(&self.stamp, &self.region, n)
                {
                    self.tseen[n as usize] = a;
                    queue.push(n);
                }
            }
        }
        fits |= grown.len() - removed + r.len() <= max_t && nv + orphan_v - shared <= max_v;
        if !fits {
            return None;
        }
        let shed: Vec<u32> = queue[..removed].to_vec();
        // Connected: flood the kept triangles and `r` from `r`'s first triangle (stamps: `gone`
        // marks the given-back triangles, `reached` the flooded ones).
        self.attempt += 2;
        let (gone, reached) = (self.attempt - 1, self.attempt);
        for &t in &shed {
            self.tseen[t as usize] = gone;
        }
        let mut stack = vec![r[0]];
        self.tseen[r[0] as usize] = reached;
        let mut flooded = 1;
        while let Some(u) = stack.pop() {
            for &n in dual.row(u as usize) {
                let ni = n as usize;
                let member = (labels[ni] == c && self.tseen[ni] != gone)
                    || in_r(&self.stamp, &self.region, n);
                if member && self.tseen[ni] != reached {
                    self.tseen[ni] = reached;
                    flooded += 1;
                    stack.push(n);
                }
            }
        }
        if flooded != grown.len() - shed.len() + r.len() {
            return None;
        }
        for &t in &shed {
            labels[t as usize] = FREE;
        }
        for &t in r {
            labels[t as usize] = c;
        }
        grown.retain(|&t| labels[t as usize] == c);
        grown.extend_from_slice(r);
        Some(shed)
    }

    /// The free regions of at most `cap` triangles that contain a triangle of `frontier`, largest
    /// first. One breadth-first search per region; a search that grows past `cap` or meets a
    /// region already found open marks what it saw open, so on a surface (one large free region)
    /// the check costs about `cap` steps per cluster.
    fn regions(
        &mut self,
        dual: &Csr,
        cap: usize,
        c: u32,
        frontier: &[u32],
        labels: &[u32],
    ) -> Vec<Vec<u32>> {
        let mut regions: Vec<Vec<u32>> = Vec::new();
        for &f in frontier {
            if labels[f as usize] != FREE || self.stamp[f as usize] == c + 1 {
                continue;
            }
            let id = regions.len() as u32;
            self.queue.clear();
            self.queue.push(f);
            self.stamp[f as usize] = c + 1;
            self.region[f as usize] = id;
            let mut open = false;
            let mut i = 0;
            while i < self.queue.len() && !open {
                let u = self.queue[i];
                i += 1;
                for &n in dual.row(u as usize) {
                    if labels[n as usize] != FREE {
                        continue;
                    }
                    if self.stamp[n as usize] == c + 1 {
                        open |= self.region[n as usize] == OPEN;
                        continue;
                    }
                    self.stamp[n as usize] = c + 1;
                    self.region[n as usize] = id;
                    self.queue.push(n);
                }
                open |= self.queue.len() > cap;
            }
            if open {
                for &u in &self.queue {
                    self.region[u as usize] = OPEN;
                }
            } else {
                regions.push(self.queue.clone());
            }
        }
        regions.sort_by_key(|r| (Reverse(r.len()), r[0]));
        regions
    }

    /// The longest prefix of `grown` that, with all of `take` (whole orphans of the current
    /// check), fits the limits and touches each of those orphans across an edge.
    #[allow(clippy::too_many_arguments)]
    fn prefix(
        &mut self,
        mesh: &Mesh,
        dual: &Csr,
        limits: Limits,
        c: u32,
        grown: &[u32],
        take: &[u32],
        labels: &[u32],
    ) -> Option<usize> {
        let (a, orphan_v, mut nv, mut shared) = self.count_vertices(mesh, grown, take);
        // Edges from each orphan into the prefix.
        let mut ids: Vec<u32> = take.iter().map(|&t| self.region[t as usize]).collect();
        ids.sort_unstable();
        ids.dedup();
        let slot = |stamp: &[u32], region: &[u32], m: u32| -> Option<usize> {
            if labels[m as usize] != FREE || stamp[m as usize] != c + 1 {
                return None;
            }
            ids.binary_search(&region[m as usize]).ok()
        };
        let mut touch = vec![0u32; ids.len()];
        for &t in take {
            let i = slot(&self.stamp, &self.region, t).expect("an orphan's triangle");
            touch[i] += dual
                .row(t as usize)
                .iter()
                .filter(|&&n| labels[n as usize] == c)
                .count() as u32;
        }
        let (max_v, max_t) = (limits.max_vertices as usize, limits.max_triangles as usize);
        let mut n = grown.len();
        loop {
            let fits = n + take.len() <= max_t && nv + orphan_v - shared <= max_v;
            if fits && touch.iter().all(|&x| x > 0) {
                return Some(n);
            }
            if n <= 1 {
                return None;
            }
            // Give back the last-grown triangle.
            n -= 1;
            let u = grown[n];
            self.release(mesh, a, u, &mut nv, &mut shared);
            for &m in dual.row(u as usize) {
                if let Some(i) = slot(&self.stamp, &self.region, m) {
                    touch[i] -= 1;
                }
            }
        }
    }
}

pub(crate) fn centroid(mesh: &Mesh, t: u32) -> glam::Vec3 {
    mesh.triangle(t as usize)
        .iter()
        .map(|&v| mesh.position(v))
        .sum::<glam::Vec3>()
        / 3.0
}

/// What a growing cluster prefers among frontier triangles that add as many vertices and are as
/// enclosed (the first two keys, which decide fill).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Grow {
    /// The triangle nearest the cluster's running centroid (meshoptimizer's choice too): round
    /// clusters in space, so small bounding spheres; measured: radius at or under meshoptimizer's
    /// on most meshes, a few percent more meshlets than [`Grow::Hops`] (results/kmedoids.md).
    #[default]
    Centre,
    /// The triangle fewest hops from the seed, then nearest the running centroid: round in the
    /// dual graph, the k-medoids metric, so the fewest meshlets, but larger spheres (most on fans
    /// of long thin triangles, whose hop-balls are long wedges; results/kmedoids.md).
    Hops,
}

impl std::str::FromStr for Grow {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "centre" | "center" => Ok(Self::Centre),
            "hops" => Ok(Self::Hops),
            _ => Err(format!("unknown k-medoids growth '{s}' (centre, hops)")),
        }
    }
}

/// Growth priority of a frontier triangle, smallest first: vertices it adds (0 closes a hole),
/// free edge-neighbours it has (fewer = more enclosed: taking it now leaves no sliver behind, the
/// role of meshoptimizer's live-triangle counts), hops from the seed ([`Grow::Hops`] only),
/// squared distance to the cluster's running centroid, then the lower id. The centroid moves as
/// the cluster grows, so a key is re-checked when it is popped and pushed back if it changed.
type Key = (u8, u8, u32, u32, u32);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjacency::{cluster_pieces, dual_graph, vertex_triangles};
    use crate::mesh::generate;

    #[test]
    fn a_full_cluster_takes_the_hole_it_encloses_and_gives_back_its_last_triangle() {
        let (m, dual, order) = terrain_and_order();
        let limits = Limits::new(255, 126).unwrap();
        // Cluster 0 holds the first 127 triangles but the 10th, a hole: triangle-full. Every other
        // triangle is taken, so the hole is a free region of one triangle, enclosed.
        let (c, hole) = (0u32, order[10]);
        let mut labels = vec![7u32; m.triangle_count()];
        let mut grown: Vec<u32> = order[..127]
            .iter()
            .copied()
            .filter(|&t| t != hole)
            .collect();
        for &t in &grown {
            labels[t as usize] = c;
        }
        labels[hole as usize] = FREE;
        let last = *grown.last().unwrap();
        let mut o = Orphans::new(m.vertex_count(), m.triangle_count());
        let shed = o.absorb(&m, &dual, limits, c, &[hole], &mut grown, &mut labels);
        // The hole joins; the last-grown triangle goes back free; the limit still holds.
        assert_eq!(shed, vec![last]);
        assert_eq!(labels[hole as usize], c);
        assert_eq!(labels[last as usize], FREE);
        assert_eq!(grown.len(), 126);
        assert_eq!(*grown.last().unwrap(), hole);
        assert!(grown.iter().all(|&t| labels[t as usize] == c));
        // A free region larger than half the triangle limit is not an orphan: nothing changes.
        let mut labels = vec![FREE; m.triangle_count()];
        let mut grown: Vec<u32> = order[..126].to_vec();
        for &t in &grown {
            labels[t as usize] = c;
        }
        let before = (grown.clone(), labels.clone());
        let shed = o.absorb(&m, &dual, limits, c, &order[126..], &mut grown, &mut labels);
        assert!(shed.is_empty());
        assert_eq!((grown, labels), before);
    }

    #[test]
    fn an_orphan_by_the_front_is_taken_for_triangles_given_back_at_the_open_front() {
        let (m, dual, order) = terrain_and_order();
        let limits = Limits::new(255, 126).unwrap();
        // Cluster 0 is the triangle-full ball of the first 126; the next triangle is enclosed by
        // it and by another cluster's triangles; the rest of the mesh is free (the open front).
        let (c, orphan) = (0u32, order[126]);
        let (mut labels, mut grown) = ball_and_orphan(&m, &dual, &order[..126], orphan);
        let mut o = Orphans::new(m.vertex_count(), m.triangle_count());
        let regions = o.regions(&dual, 63, c, &[orphan], &labels);
        assert_eq!(regions, vec![vec![orphan]]);
        let shed = o
            .front_shed(&m, &dual, limits, c, &mut grown, &regions[0], &mut labels)
            .expect("one triangle on the front can go");
        // One triangle given back (the limit is triangles), on the open front, not next to the
        // orphan; the orphan joined; the cluster fits and is one edge-connected piece.
        assert_eq!(shed.len(), 1);
        let s = shed[0] as usize;
        assert_eq!(labels[s], FREE);
        assert!(!dual.row(s).contains(&orphan));
        assert!(dual
            .row(s)
            .iter()
            .any(|&n| n != orphan && labels[n as usize] == FREE));
        assert_eq!(labels[orphan as usize], c);
        assert_eq!(grown.len(), 126);
        assert!(grown.iter().all(|&t| labels[t as usize] == c));
        let members: Vec<u32> = (0..m.triangle_count() as u32)
            .filter(|&t| labels[t as usize] == c)
            .collect();
        assert_eq!(members.len(), 126);
        assert_eq!(one_piece(&dual, &labels, c), (1, 1));
        // The same with the vertex limit binding: the ball holds exactly the limit, and the
        // orphan (the first triangle after the ball with a vertex outside it) adds a vertex.
        let ball = &order[..126];
        let mut verts: Vec<u32> = ball.iter().flat_map(|&t| m.triangle(t as usize)).collect();
        verts.sort_unstable();
        verts.dedup();
        let orphan = *order[126..]
            .iter()
            .find(|&&t| {
                m.triangle(t as usize)
                    .iter()
                    .any(|v| verts.binary_search(v).is_err())
            })
            .unwrap();
        let limits = Limits::new(verts.len() as u32, 255).unwrap();
        let (mut labels, mut grown) = ball_and_orphan(&m, &dual, ball, orphan);
        let mut o = Orphans::new(m.vertex_count(), m.triangle_count());
        let regions = o.regions(&dual, 63, c, &[orphan], &labels);
        assert_eq!(regions, vec![vec![orphan]]);
        let shed = o
            .front_shed(&m, &dual, limits, c, &mut grown, &regions[0], &mut labels)
            .expect("a vertex on the front can be freed");
        assert!(!shed.is_empty());
        assert!(shed
            .iter()
            .all(|&t| labels[t as usize] == FREE && !dual.row(t as usize).contains(&orphan)));
        assert_eq!(labels[orphan as usize], c);
        let mut now: Vec<u32> = grown.iter().flat_map(|&t| m.triangle(t as usize)).collect();
        now.sort_unstable();
        now.dedup();
        assert!(
            now.len() <= verts.len(),
            "{} vertices over the limit",
            now.len()
        );
        assert_eq!(grown.len(), 127 - shed.len());
        assert_eq!(one_piece(&dual, &labels, c), (1, 1));
    }

    /// The terrain test mesh, its dual graph, and 200 triangles in breadth-first order from
    /// triangle 300 (every prefix edge-connected).
    fn terrain_and_order() -> (Mesh, Csr, Vec<u32>) {
        let m = generate::terrain(24, 5);
        let dual = dual_graph(&m, &vertex_triangles(&m));
        let mut order = vec![300u32];
        let mut seen = vec![false; m.triangle_count()];
        seen[300] = true;
        let mut i = 0;
        while order.len() < 200 {
            for &n in dual.row(order[i] as usize) {
                if !seen[n as usize] {
                    seen[n as usize] = true;
                    order.push(n);
                }
            }
            i += 1;
        }
        (m, dual, order)
    }

    /// Labels with `ball` as cluster 0 and `orphan` enclosed by it and by another cluster's
    /// triangles (7), the rest of the mesh free (the open front); and the ball as `grown`.
    fn ball_and_orphan(m: &Mesh, dual: &Csr, ball: &[u32], orphan: u32) -> (Vec<u32>, Vec<u32>) {
        let mut labels = vec![FREE; m.triangle_count()];
        for &t in ball {
            labels[t as usize] = 0;
        }
        for &n in dual.row(orphan as usize) {
            if labels[n as usize] == FREE {
                labels[n as usize] = 7;
            }
        }
        (labels, ball.to_vec())
    }

    /// Cluster `c`'s (own pieces, mesh pieces), every other triangle counted as a second cluster.
    fn one_piece(dual: &Csr, labels: &[u32], c: u32) -> (usize, usize) {
        let two: Vec<u32> = labels.iter().map(|&l| (l != c) as u32).collect();
        cluster_pieces(dual, &two, 2)[0]
    }
}
