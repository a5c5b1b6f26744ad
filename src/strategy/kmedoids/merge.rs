//! Merging clusters (steps 4 and 4b of the capacity-aware method): neighbours whose union fits
//! the limits become one cluster, and clusters that hold whole small pieces of the mesh join the
//! nearest cluster with room; then clusters are renumbered by medoid and distances refreshed.

use super::assign::{members, UNREACHED};
use super::local_graph::LocalGraph;
use super::seed::centroid;
use crate::adjacency::pieces;
use crate::common::{morton3, sorted, union_len, Csr};
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use rayon::prelude::*;

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

/// Per-cluster sets of a merge pass, built only for the clusters a merge test reads: on most
/// meshes nearly every cluster is full and fails the cheap triangle test, so building every
/// cluster's vertex and piece sets up front cost more than the merges themselves.
struct ClusterSets<'a> {
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

impl ClusterSets<'_> {
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
    let mut sets = ClusterSets {
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
            let union = union_len(&va, vb);
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

/// Step 4b: a cluster that shares no vertex with any other holds whole mesh pieces (a piece
/// smaller than a meshlet: the neurons' 63 four-triangle markers), which [`merge_neighbours`]
/// cannot see. Smallest first (then the lower id), each joins the cluster with the nearest
/// centroid among those near it in Morton order whose union fits. The union is edge-connected
/// wherever the mesh is: its pieces are the two clusters' pieces. Sequential, so deterministic.
pub(crate) fn pack_pieces(
    mesh: &Mesh,
    vt: &Csr,
    limits: Limits,
    medoids: &mut Vec<u32>,
    labels: &mut [u32],
) {
    // How far along the Morton order a cluster looks for a partner (either side).
    const WINDOW: usize = 32;
    let k = medoids.len();
    let mut isolated = vec![true; k];
    for v in 0..vt.rows() {
        let row = vt.row(v);
        if let Some(&first) = row.first() {
            let l = labels[first as usize];
            if row.iter().any(|&t| labels[t as usize] != l) {
                for &t in row {
                    isolated[labels[t as usize] as usize] = false;
                }
            }
        }
    }
    if !isolated.contains(&true) {
        return;
    }
    let mem = members(labels, k);
    let mut tris: Vec<usize> = (0..k).map(|c| mem.row(c).len()).collect();
    // Distinct vertices, counted only for the clusters a test reads (few: most partners fail the
    // triangle test), `usize::MAX` until then.
    let mut verts = vec![usize::MAX; k];
    let count_verts = |verts: &mut [usize], c: usize| {
        if verts[c] == usize::MAX {
            let v = mem.row(c).iter().flat_map(|&t| mesh.triangle(t as usize));
            verts[c] = sorted(v.collect()).len();
        }
    };
    let mut centre: Vec<glam::Vec3> = (0..k)
        .into_par_iter()
        .map(|c| {
            mem.row(c)
                .iter()
                .map(|&t| centroid(mesh, t))
                .sum::<glam::Vec3>()
                / mem.row(c).len() as f32
        })
        .collect();
    let (lo, hi) = mesh.bounding_box();
    let scale = (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let mut by_code: Vec<(u64, u32)> = (0..k as u32)
        .map(|c| {
            let q = ((centre[c as usize] - lo) / scale * 1023.0)
                .clamp(glam::Vec3::ZERO, glam::Vec3::splat(1023.0));
            (morton3(q.x as u32, q.y as u32, q.z as u32), c)
        })
        .collect();
    by_code.sort_unstable();
    let mut at = vec![0usize; k];
    for (i, &(_, c)) in by_code.iter().enumerate() {
        at[c as usize] = i;
    }
    let mut into: Vec<u32> = (0..k as u32).collect();
    let mut order: Vec<u32> = (0..k as u32).filter(|&c| isolated[c as usize]).collect();
    order.sort_unstable_by_key(|&c| (tris[c as usize], c));
    for a in order {
        let ai = a as usize;
        let lo_i = at[ai].saturating_sub(WINDOW);
        let hi_i = (at[ai] + WINDOW + 1).min(k);
        count_verts(&mut verts, ai);
        // The nearest centroid (then the lower id) among partners whose union fits; vertices are
        // counted only for those that pass the triangle test.
        let mut best: Option<(f32, u32)> = None;
        for &(_, b) in &by_code[lo_i..hi_i] {
            let bi = b as usize;
            if b == a || into[bi] != b || tris[ai] + tris[bi] > limits.max_triangles as usize {
                continue;
            }
            count_verts(&mut verts, bi);
            if verts[ai] + verts[bi] > limits.max_vertices as usize {
                continue;
            }
            let d = (centre[bi] - centre[ai]).length_squared();
            if best.is_none_or(|(bd, bb)| d.total_cmp(&bd).then(b.cmp(&bb)).is_lt()) {
                best = Some((d, b));
            }
        }
        let best = best.map(|(_, b)| b);
        if let Some(b) = best {
            let bi = b as usize;
            into[ai] = b;
            centre[bi] = (centre[bi] * tris[bi] as f32 + centre[ai] * tris[ai] as f32)
                / (tris[ai] + tris[bi]) as f32;
            tris[bi] += tris[ai];
            verts[bi] += verts[ai];
        }
    }
    // `into` is one step deep: an isolated cluster that took others joins nobody afterwards only
    // if it was processed first; follow the chain to be safe.
    let find = |mut c: u32| {
        while into[c as usize] != c {
            c = into[c as usize];
        }
        c
    };
    let survivors: Vec<u32> = (0..k as u32).filter(|&c| into[c as usize] == c).collect();
    if survivors.len() == k {
        return;
    }
    let mut new_id = vec![u32::MAX; k];
    for (i, &c) in survivors.iter().enumerate() {
        new_id[c as usize] = i as u32;
    }
    for l in labels.iter_mut() {
        *l = new_id[find(*l) as usize];
    }
    *medoids = survivors.iter().map(|&c| medoids[c as usize]).collect();
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
