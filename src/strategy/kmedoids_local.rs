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

/// Splits every overflowing cluster inside itself until none overflows, merges neighbours whose
/// union fits (`merge_neighbours`), then renumbers clusters by
/// ascending medoid and measures each member's hop distance from its medoid. Returns the number
/// of rounds.
// The flat arrays the CPU steps and the GPU kernels share, passed as they are.
#[allow(clippy::too_many_arguments)]
pub fn split_until_fit(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
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
    merge_neighbours(
        mesh,
        dual,
        vt,
        &Pieces::new(dual, vt),
        limits,
        medoids,
        labels,
    );
    renumber(medoids, labels);
    refresh_distances(dual, medoids, labels, distances);
    rounds
}

/// The edge-connected pieces of a mesh: computed once per run, read by every merge.
pub(crate) struct Pieces {
    /// Piece of each triangle (ids in order of first triangle).
    pub of: Vec<u32>,
    /// Whether the mesh is one piece (then every merge goes across an edge).
    pub one: bool,
    /// Per vertex: whether triangles of more than one piece meet there (the only places two
    /// clusters can touch without sharing an edge and without sharing a piece).
    pub joint: Vec<bool>,
}

impl Pieces {
    pub(crate) fn new(dual: &Csr, vt: &Csr) -> Self {
        let of = pieces(dual);
        let one = of.iter().all(|&p| p == 0);
        let joint = (0..vt.rows())
            .map(|v| {
                let row = vt.row(v);
                !one && row.iter().any(|&t| of[t as usize] != of[row[0] as usize])
            })
            .collect();
        Self { of, one, joint }
    }
}

/// Edge-connected piece of the mesh each triangle lies in (ids in order of first triangle).
pub(crate) fn pieces(dual: &Csr) -> Vec<u32> {
    let mut piece = vec![u32::MAX; dual.rows()];
    let mut queue = Vec::new();
    let mut next = 0;
    for s in 0..dual.rows() {
        if piece[s] != u32::MAX {
            continue;
        }
        piece[s] = next;
        queue.clear();
        queue.push(s as u32);
        while let Some(u) = queue.pop() {
            for &v in dual.row(u as usize) {
                if piece[v as usize] == u32::MAX {
                    piece[v as usize] = next;
                    queue.push(v);
                }
            }
        }
        next += 1;
    }
    piece
}

fn sorted(mut v: Vec<u32>) -> Vec<u32> {
    v.sort_unstable();
    v.dedup();
    v
}

/// Per-cluster sets of a merge pass, built only for the clusters a merge test reads: on most
/// meshes nearly every cluster is full and fails the cheap triangle test, so building every
/// cluster's vertex and piece sets up front cost more than the merges (a sixth of the whole run
/// on the dragon).
struct Sets<'a> {
    mesh: &'a Mesh,
    piece: &'a [u32],
    mem: Csr,
    /// Members of a merged cluster; `None`: its row of `mem`.
    tris: Vec<Option<Vec<u32>>>,
    /// Sorted distinct vertices, once asked for.
    verts: Vec<Option<Vec<u32>>>,
    /// Sorted distinct pieces, once asked for.
    parts: Vec<Option<Vec<u32>>>,
}

impl Sets<'_> {
    fn tris(&self, c: u32) -> &[u32] {
        self.tris[c as usize]
            .as_deref()
            .unwrap_or_else(|| self.mem.row(c as usize))
    }

    fn verts(&mut self, c: u32) -> &[u32] {
        if self.verts[c as usize].is_none() {
            let v = self
                .tris(c)
                .iter()
                .flat_map(|&t| self.mesh.triangle(t as usize))
                .collect();
            self.verts[c as usize] = Some(sorted(v));
        }
        self.verts[c as usize].as_deref().expect("just set")
    }

    fn parts(&mut self, c: u32) -> &[u32] {
        if self.parts[c as usize].is_none() {
            let p = self
                .tris(c)
                .iter()
                .map(|&t| self.piece[t as usize])
                .collect();
            self.parts[c as usize] = Some(sorted(p));
        }
        self.parts[c as usize].as_deref().expect("just set")
    }

    /// Whether no piece of the mesh holds members of both.
    fn disjoint_parts(&mut self, a: u32, b: u32) -> bool {
        self.parts(a);
        self.parts(b);
        let (x, y) = (&self.parts[a as usize], &self.parts[b as usize]);
        let (x, y) = (x.as_deref().expect("set"), y.as_deref().expect("set"));
        x.iter().all(|p| y.binary_search(p).is_err())
    }

    /// `gone` joins `keep`: the union's members and vertices (both were read by the test that
    /// chose the merge); its pieces are rebuilt if asked for.
    fn merge(&mut self, keep: u32, gone: u32) {
        let t = sorted([self.tris(keep), self.tris(gone)].concat());
        let mut v = self.verts(keep).to_vec();
        v.extend_from_slice(self.verts(gone));
        let v = sorted(v);
        let (k, g) = (keep as usize, gone as usize);
        self.tris[k] = Some(t);
        self.tris[g] = Some(Vec::new());
        self.verts[k] = Some(v);
        self.verts[g] = None;
        self.parts[k] = None;
        self.parts[g] = None;
    }
}

/// Merges neighbouring clusters whose union fits the limits, smallest first (ties to the lower
/// id; among neighbours, the one sharing most vertices, then the lower id). Bisection leaves
/// half-full parts, and a mesh whose pieces touch only at vertices (a strut lattice) leaves one
/// cluster per piece; both are what this recovers. Two clusters may merge when they share an
/// edge (the union stays edge-connected) or when no edge-connected piece of the mesh holds
/// members of both (the union is then connected wherever the mesh is). Sequential and in a fixed
/// order, so deterministic. Merged clusters get the paper's medoid of their union.
pub(crate) fn merge_neighbours(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
    pieces: &Pieces,
    limits: Limits,
    medoids: &mut Vec<u32>,
    labels: &mut [u32],
) {
    let k = medoids.len();
    let mem = members(labels, k);
    let mut sets = Sets {
        mesh,
        piece: &pieces.of,
        mem,
        tris: vec![None; k],
        verts: vec![None; k],
        parts: vec![None; k],
    };
    // Current cluster of a triangle: follow `into` from its label.
    let mut into: Vec<u32> = (0..k as u32).collect();
    let find = |into: &[u32], mut c: u32| {
        while into[c as usize] != c {
            c = into[c as usize];
        }
        c
    };
    let mut order: Vec<u32> = (0..k as u32).collect();
    order.sort_unstable_by_key(|&c| (sets.tris(c).len(), c));
    let mut merged = vec![false; k];
    let mut cand: Vec<(u32, bool)> = Vec::new();
    // The cluster that last listed a neighbour, and where in `cand` it sits.
    let mut stamp = vec![u32::MAX; k];
    let mut slot = vec![0u32; k];
    for a in order {
        if into[a as usize] != a {
            continue;
        }
        // Candidates: clusters across an edge, and (on a mesh of several pieces) clusters met
        // at a vertex where pieces join; any other neighbour shares a piece and no edge with
        // `a`, which would leave the union in more pieces than the mesh. Reading labels across
        // the joints only, not around every vertex, is most of this pass's saving.
        // One entry per neighbour, edge-adjacent if any meeting is across an edge (deduplicated
        // by stamps, not a sort: the choice below does not depend on the candidates' order).
        cand.clear();
        let mut add = |b: u32, edge: bool, cand: &mut Vec<(u32, bool)>| {
            if stamp[b as usize] != a {
                stamp[b as usize] = a;
                slot[b as usize] = cand.len() as u32;
                cand.push((b, edge));
            } else {
                cand[slot[b as usize] as usize].1 |= edge;
            }
        };
        for &t in sets.tris(a) {
            for &u in dual.row(t as usize) {
                let b = find(&into, labels[u as usize]);
                if b != a {
                    add(b, true, &mut cand);
                }
            }
        }
        if !pieces.one {
            for &v in sets.verts(a) {
                if pieces.joint[v as usize] {
                    for &u in vt.row(v as usize) {
                        let b = find(&into, labels[u as usize]);
                        if b != a {
                            add(b, false, &mut cand);
                        }
                    }
                }
            }
        }
        let mut best: Option<(u32, u32)> = None;
        for &(b, edge) in &cand {
            // Triangles first, then vertices, then pieces: each test reads only what the
            // previous ones let through.
            if sets.tris(a).len() + sets.tris(b).len() > limits.max_triangles as usize {
                continue;
            }
            let va = sets.verts(a).to_vec();
            let vb = sets.verts(b);
            let union = super::qem::union_len(&va, vb);
            if union > limits.max_vertices as usize {
                continue;
            }
            let shared = va.len() + vb.len() - union;
            if !edge && !sets.disjoint_parts(a, b) {
                continue;
            }
            let shared = shared as u32;
            if best.is_none_or(|(s, c)| (shared, std::cmp::Reverse(b)) > (s, std::cmp::Reverse(c)))
            {
                best = Some((shared, b));
            }
        }
        let Some((_, b)) = best else { continue };
        let (keep, gone) = (a.min(b), a.max(b));
        into[gone as usize] = keep;
        merged[keep as usize] = true;
        sets.merge(keep, gone);
    }
    // Relabel to the survivors, compact the ids, and give merged clusters their union's medoid.
    let survivors: Vec<u32> = (0..k as u32).filter(|&c| into[c as usize] == c).collect();
    let mut new_id = vec![u32::MAX; k];
    for (i, &c) in survivors.iter().enumerate() {
        new_id[c as usize] = i as u32;
    }
    for l in labels.iter_mut().filter(|l| **l != UNREACHED) {
        *l = new_id[find(&into, *l) as usize];
    }
    let fresh: Vec<u32> = survivors
        .par_iter()
        .enumerate()
        .map(|(i, &c)| {
            if !merged[c as usize] {
                return medoids[c as usize];
            }
            let m = sets.tris(c);
            // All members' distance sums at once (the same medoid as a BFS from each).
            m[LocalGraph::new(dual, labels, i as u32, m).medoid_index()]
        })
        .collect();
    *medoids = fresh;
}

/// Renumbers clusters by ascending medoid (the order `assign` numbers them in).
pub(crate) fn renumber(medoids: &mut Vec<u32>, labels: &mut [u32]) {
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
pub(crate) fn refresh_distances(
    dual: &Csr,
    medoids: &[u32],
    labels: &[u32],
    distances: &mut [u32],
) {
    let mem = members(labels, medoids.len());
    let rows: Vec<(u32, Vec<u32>)> = (0..medoids.len() as u32)
        .into_par_iter()
        .map(|c| {
            let m = mem.row(c as usize);
            let sub = LocalGraph::new(dual, labels, c, m);
            let at = m.binary_search(&medoids[c as usize]).expect("member");
            (c, member_distances(&sub, at))
        })
        .collect();
    for (c, d) in rows {
        for (&t, &x) in mem.row(c as usize).iter().zip(&d) {
            distances[t as usize] = x;
        }
    }
}

/// Hop distance of every member of `sub` from member `at`. A cluster joined through a vertex has
/// pieces `at` does not reach: each is numbered on after the previous one, from its lowest member.
pub(crate) fn member_distances(sub: &LocalGraph, at: usize) -> Vec<u32> {
    let mut d = sub.flood(&[at], None).1;
    while let Some(u) = d.iter().position(|&x| x == u32::MAX) {
        let base = d
            .iter()
            .filter(|&&x| x != u32::MAX)
            .max()
            .map_or(0, |&x| x + 1);
        let more = sub.flood(&[u], None).1;
        for (x, &y) in d.iter_mut().zip(&more) {
            if *x == u32::MAX && y != u32::MAX {
                *x = base + y;
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::super::kmedoids::{cluster, Config, Mode};
    use super::Sub;
    use crate::adjacency::{dual_graph, vertex_triangles};
    use crate::mesh::generate;
    use crate::meshlet::{validate, Limits};

    /// Every cluster is edge-connected wherever the mesh is: it has as many edge-connected
    /// pieces as the mesh pieces its members lie in.
    fn connected(dual: &crate::adjacency::Csr, labels: &[u32], k: usize) -> bool {
        let mem = super::members(labels, k);
        let piece = super::pieces(dual);
        (0..k).all(|c| {
            let m = mem.row(c);
            let sub = super::LocalGraph::new(dual, labels, c as u32, m);
            let mut own = vec![false; m.len()];
            let mut count = 0;
            while let Some(u) = own.iter().position(|&x| !x) {
                for (o, d) in own.iter_mut().zip(sub.flood(&[u], None).1) {
                    *o |= d != u32::MAX;
                }
                count += 1;
            }
            let mut p: Vec<u32> = m.iter().map(|&t| piece[t as usize]).collect();
            p.sort_unstable();
            p.dedup();
            count == p.len()
        })
    }

    #[test]
    fn local_splits_fit_stay_connected_and_do_not_depend_on_threads() {
        let cfg = Config {
            mode: Mode::Local,
            ..Config::default()
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
                let a = crate::test_pool(1).install(|| cluster(m, limits, &cfg));
                let b = crate::test_pool(4).install(|| cluster(m, limits, &cfg));
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
