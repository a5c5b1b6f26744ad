//! The cells the search edits (a labelling of the triangles with meshlets), apart from the scratch
//! buffers its queries reuse.
//!
//! [`Cells`] is the search state proper: a meshlet label per triangle and, kept in step by
//! [`Cells::apply`], per-meshlet triangle and distinct-vertex counts, feature sums and member
//! lists. How often a meshlet uses a vertex is not stored: it is counted on the fly from the
//! vertex -> triangle rows (a handful of triangles), which keeps a move O(1) in the mesh size. An
//! optional move journal makes a failed attempt cost its own moves to undo
//! ([`Cells::rollback`]), not a copy of the mesh.
//!
//! [`Scratch`] holds the epoch-stamped buffers of the queries (a buffer is cleared by bumping the
//! epoch, not by a pass over it), with the one flood fill ([`Scratch::flood`]) that every exact
//! connectivity question goes through, and a one-ring shortcut
//! ([`Scratch::stays_connected_locally`]) that may answer no where a detour exists. [`Search`]
//! pairs the two for the steps in the sibling files; which objective the boundary moves rank
//! first is their parameter, not state.

use crate::adjacency::Csr;
use crate::common::{distinct, NONE};
use crate::mesh::Mesh;
use crate::meshlet::{canonical, Limits, MeshletBuilder, Meshlets};

/// Per-triangle features whose spread (sum of squared distances to the meshlet mean) is the third
/// objective: the centroid, scaled to unit RMS spread in the input, and the unit normal.
pub(crate) const FEATURES: usize = 6;

/// Weight of the normal against the scaled centroid in the spread: tight normal cones keep
/// meshlets cone-cullable. Measured on the bunny with `+refine-max`: 0 lost 0.3 % of the
/// cullable meshlets, 0.3 keeps meshoptimizer's share, 1.0 keeps every meshlet cullable but
/// blocks every dissolve.
const NORMAL_WEIGHT: f64 = 0.3;

/// The mesh triangle behind every meshlet triangle, as a label (meshlet index) per mesh triangle.
/// Duplicated triangles are matched in order; a valid partition labels every triangle once.
/// Also returns the mesh triangles in meshlet order.
pub(crate) fn labels_of(mesh: &Mesh, vt: &Csr, ml: &Meshlets) -> (Vec<u32>, Vec<u32>) {
    let mut labels = vec![NONE; mesh.triangle_count()];
    let mut seq = Vec::with_capacity(mesh.triangle_count());
    for m in 0..ml.len() {
        for tri in ml.global_triangles(m) {
            let key = canonical(tri);
            let t = vt
                .row(key[0] as usize)
                .iter()
                .copied()
                .find(|&t| {
                    labels[t as usize] == NONE && canonical(mesh.triangle(t as usize)) == key
                })
                .expect("refine needs a valid partition of the mesh");
            labels[t as usize] = m as u32;
            seq.push(t);
        }
    }
    (labels, seq)
}

/// Distinct vertices of each of the `k` meshlets of the labelling `label` (one pass over the
/// vertex -> triangle rows: a meshlet is counted once per vertex it uses).
pub(crate) fn vertex_counts(vt: &Csr, label: &[u32], k: usize) -> Vec<u32> {
    let mut count = vec![0u32; k];
    let mut last = vec![u32::MAX; k];
    for v in 0..vt.rows() {
        for &t in vt.row(v) {
            let m = label[t as usize] as usize;
            if last[m] != v as u32 {
                last[m] = v as u32;
                count[m] += 1;
            }
        }
    }
    count
}

/// One journaled move: the triangle, where it came from and went, and both meshlets' change
/// stamps before it.
#[derive(Clone, Copy)]
pub(crate) struct Undo {
    pub(crate) t: u32,
    from: u32,
    to: u32,
    stamps: [usize; 2],
}

/// The cells: a meshlet label per triangle of the mesh, with every count a move needs.
pub(crate) struct Cells<'a> {
    pub(crate) mesh: &'a Mesh,
    /// Vertex -> triangles.
    pub(crate) vt: &'a Csr,
    /// Triangle -> edge-adjacent triangles.
    pub(crate) dual: &'a Csr,
    pub(crate) limits: Limits,
    /// The meshlet of each triangle.
    pub(crate) label: Vec<u32>,
    /// Triangles per meshlet (0 = dissolved).
    pub(crate) tcount: Vec<u32>,
    /// Distinct vertices per meshlet.
    pub(crate) vcount: Vec<u32>,
    /// Members of each meshlet, unordered.
    pub(crate) members: Vec<Vec<u32>>,
    /// Sum of member triangle features, per meshlet.
    pub(crate) csum: Vec<[f64; FEATURES]>,
    /// Per triangle, its features ([`FEATURES`]).
    pub(crate) features: Vec<[f64; FEATURES]>,
    /// Meshlets with at least one triangle.
    pub(crate) live: usize,
    /// Moves made (a rollback takes its moves back off).
    pub(crate) moves: usize,
    /// Per meshlet, the move counter when it last changed.
    pub(crate) changed_at: Vec<usize>,
    /// Moves since the journal was opened, for rollback.
    pub(crate) journal: Option<Vec<Undo>>,
}

impl<'a> Cells<'a> {
    /// The labelling `label` (meshlets `0..k`) with every count made.
    pub(crate) fn new(
        mesh: &'a Mesh,
        vt: &'a Csr,
        dual: &'a Csr,
        label: Vec<u32>,
        k: usize,
        limits: Limits,
    ) -> Self {
        let t_count = mesh.triangle_count();
        let features: Vec<[f64; FEATURES]> = (0..t_count)
            .map(|t| {
                let [a, b, c] = mesh
                    .triangle(t)
                    .map(|v| glam::DVec3::from(mesh.positions[v as usize].map(f64::from)));
                let p = (a + b + c) / 3.0;
                let n = (b - a).cross(c - a).normalize_or_zero();
                [p.x, p.y, p.z, n.x, n.y, n.z]
            })
            .collect();
        let mut s = Self {
            mesh,
            vt,
            dual,
            limits,
            label,
            tcount: vec![0; k],
            vcount: vec![0; k],
            members: vec![Vec::new(); k],
            csum: vec![[0.0; FEATURES]; k],
            features,
            live: 0,
            moves: 0,
            changed_at: vec![0; k],
            journal: None,
        };
        // Features: the position over the input's RMS spread (so the spread is scale-free), the
        // normal times NORMAL_WEIGHT.
        s.recount();
        let mut pos = 0.0;
        for (t, &m) in s.label.iter().enumerate() {
            let n = s.tcount[m as usize] as f64;
            pos += (0..3)
                .map(|i| (s.features[t][i] - s.csum[m as usize][i] / n).powi(2))
                .sum::<f64>();
        }
        let scale = 1.0 / (pos / t_count as f64).sqrt().max(f64::MIN_POSITIVE);
        for f in &mut s.features {
            for (i, x) in f.iter_mut().enumerate() {
                *x *= if i < 3 { scale } else { NORMAL_WEIGHT };
            }
        }
        s.recount();
        s
    }

    /// Every per-meshlet count from the labels.
    fn recount(&mut self) {
        let k = self.tcount.len();
        self.tcount.fill(0);
        self.csum.fill([0.0; FEATURES]);
        for m in &mut self.members {
            m.clear();
        }
        for (t, &m) in self.label.iter().enumerate() {
            self.tcount[m as usize] += 1;
            self.members[m as usize].push(t as u32);
            for i in 0..FEATURES {
                self.csum[m as usize][i] += self.features[t][i];
            }
        }
        self.vcount = vertex_counts(self.vt, &self.label, k);
        self.live = self.tcount.iter().filter(|&&c| c > 0).count();
    }

    /// Triangles of meshlet `m` that use vertex `v`.
    #[inline]
    pub(crate) fn uses(&self, v: u32, m: u32) -> usize {
        self.vt
            .row(v as usize)
            .iter()
            .filter(|&&t| self.label[t as usize] == m)
            .count()
    }

    /// Vertices of `t` that meshlet `b` would gain by taking it.
    #[inline]
    pub(crate) fn added(&self, t: u32, b: u32) -> u32 {
        distinct(self.mesh.triangle(t as usize))
            .filter(|&v| self.uses(v, b) == 0)
            .count() as u32
    }

    /// Vertices meshlet `a` would lose by giving `t` away (`t` is its only user of them).
    #[inline]
    pub(crate) fn removed(&self, t: u32, a: u32) -> u32 {
        distinct(self.mesh.triangle(t as usize))
            .filter(|&v| self.uses(v, a) == 1)
            .count() as u32
    }

    /// Whether meshlet `b` has room for `t` (which adds `add` vertices).
    #[inline]
    pub(crate) fn fits(&self, b: u32, add: u32) -> bool {
        self.tcount[b as usize] < self.limits.max_triangles
            && self.vcount[b as usize] + add <= self.limits.max_vertices
    }

    /// Meshlets other than `t`'s own that share an edge with `t`, ascending, without repeats.
    pub(crate) fn neighbour_labels(&self, t: u32) -> ([u32; 8], usize) {
        let own = self.label[t as usize];
        let mut out = [0u32; 8];
        let mut n = 0;
        for &u in self.dual.row(t as usize) {
            let l = self.label[u as usize];
            if l != own && !out[..n].contains(&l) && n < out.len() {
                out[n] = l;
                n += 1;
            }
        }
        out[..n].sort_unstable();
        (out, n)
    }

    /// Meshlets sharing an edge with meshlet `m`, ascending.
    pub(crate) fn adjacent_meshlets(&self, m: u32) -> Vec<u32> {
        let mut out = Vec::new();
        for &t in &self.members[m as usize] {
            let (nb, n) = self.neighbour_labels(t);
            out.extend_from_slice(&nb[..n]);
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The one breadth-first search over meshlet adjacency: meshlet `m` and the meshlets within
    /// `hops` edge-adjacency hops of it, in the order found (`m`, then ring after ring, each in
    /// the order its meshlets were reached). `ring` is shown each ring as it is completed (an
    /// empty one too) and ends the search after it by returning true.
    pub(crate) fn rings(
        &self,
        m: u32,
        hops: usize,
        mut ring: impl FnMut(&[u32]) -> bool,
    ) -> Vec<u32> {
        let mut all = vec![m];
        let mut start = 0;
        for _ in 0..hops {
            let end = all.len();
            for i in start..end {
                for n in self.adjacent_meshlets(all[i]) {
                    if !all.contains(&n) {
                        all.push(n);
                    }
                }
            }
            if ring(&all[end..]) {
                break;
            }
            start = end;
        }
        all
    }

    /// The live meshlets, emptiest first (fewest triangles, then the lowest index): the order in
    /// which victims and neighbourhoods are tried, since the emptiest meshlet is the cheapest to
    /// hand out.
    pub(crate) fn emptiest_first(&self) -> Vec<u32> {
        let mut order: Vec<u32> = (0..self.tcount.len() as u32)
            .filter(|&m| self.tcount[m as usize] > 0)
            .collect();
        order.sort_by_key(|&m| self.emptiness(m));
        order
    }

    /// The key of [`Self::emptiest_first`] (unique per meshlet).
    pub(crate) fn emptiness(&self, m: u32) -> (u32, u32) {
        (self.tcount[m as usize], m)
    }

    /// Live meshlets among `region`.
    pub(crate) fn live_in(&self, region: &[u32]) -> usize {
        region
            .iter()
            .filter(|&&m| self.tcount[m as usize] > 0)
            .count()
    }

    /// Change of the feature spread (sum of squared distances to the meshlet mean) when `t`
    /// moves from `a` to `b` (Hartigan's formula).
    pub(crate) fn sse_delta(&self, t: u32, a: u32, b: u32) -> f64 {
        let x = self.features[t as usize];
        let d2 = |m: u32| {
            let n = self.tcount[m as usize] as f64;
            let c = self.csum[m as usize];
            (0..FEATURES)
                .map(|i| (x[i] - c[i] / n).powi(2))
                .sum::<f64>()
        };
        let (na, nb) = (
            self.tcount[a as usize] as f64,
            self.tcount[b as usize] as f64,
        );
        let gain_b = if nb > 0.0 {
            nb / (nb + 1.0) * d2(b)
        } else {
            0.0
        };
        let loss_a = if na > 1.0 {
            na / (na - 1.0) * d2(a)
        } else {
            0.0
        };
        gain_b - loss_a
    }

    /// Moves `t` to meshlet `b`, keeping every count in step (and the journal, when open).
    pub(crate) fn apply(&mut self, t: u32, b: u32) {
        let a = self.label[t as usize];
        let (rem, add) = (self.removed(t, a), self.added(t, b));
        self.vcount[a as usize] -= rem;
        self.vcount[b as usize] += add;
        self.tcount[a as usize] -= 1;
        self.tcount[b as usize] += 1;
        self.live -= (self.tcount[a as usize] == 0) as usize;
        self.live += (self.tcount[b as usize] == 1) as usize;
        let x = self.features[t as usize];
        for (i, xi) in x.iter().enumerate() {
            self.csum[a as usize][i] -= xi;
            self.csum[b as usize][i] += xi;
        }
        let ma = &mut self.members[a as usize];
        let p = ma.iter().position(|&u| u == t).expect("member");
        ma.swap_remove(p);
        self.members[b as usize].push(t);
        self.label[t as usize] = b;
        if let Some(j) = self.journal.as_mut() {
            j.push(Undo {
                t,
                from: a,
                to: b,
                stamps: [self.changed_at[a as usize], self.changed_at[b as usize]],
            });
        }
        self.moves += 1;
        self.changed_at[a as usize] = self.moves;
        self.changed_at[b as usize] = self.moves;
    }

    /// Undoes the journaled moves in reverse; a rollback is no change, so the stamps come back too.
    pub(crate) fn rollback(&mut self, journal: &[Undo]) {
        for u in journal.iter().rev() {
            self.apply(u.t, u.from);
            self.moves -= 1;
            self.changed_at[u.from as usize] = u.stamps[0];
            self.changed_at[u.to as usize] = u.stamps[1];
        }
    }

    /// Puts the labels of `snapshot` back and recounts everything.
    pub(crate) fn restore(&mut self, snapshot: &[u32]) {
        self.label.copy_from_slice(snapshot);
        self.recount();
        self.moves += 1;
        self.changed_at.fill(self.moves);
    }

    /// Gives the triangles `tris` (exactly the members of the `region` meshlets) the meshlets
    /// `labels` (all in `region`) and recounts the region. Not journaled: the caller keeps the old
    /// labels to put back.
    pub(crate) fn relabel(
        &mut self,
        scratch: &mut Scratch,
        tris: &[u32],
        labels: &[u32],
        region: &[u32],
    ) {
        let live_before = self.live_in(region);
        for &m in region {
            self.members[m as usize].clear();
            self.tcount[m as usize] = 0;
            self.vcount[m as usize] = 0;
            self.csum[m as usize] = [0.0; FEATURES];
        }
        for (&t, &m) in tris.iter().zip(labels) {
            self.label[t as usize] = m;
            self.members[m as usize].push(t);
            self.tcount[m as usize] += 1;
            for k in 0..FEATURES {
                self.csum[m as usize][k] += self.features[t as usize][k];
            }
        }
        for &m in region {
            self.vcount[m as usize] =
                scratch.distinct_vertices(self.mesh, &self.members[m as usize]);
        }
        self.live = self.live - live_before + self.live_in(region);
    }

    /// The cells as meshlets, in the input's meshlet order; inside a meshlet the triangles
    /// keep the input's triangle order (`seq`), received ones where they came from.
    pub(crate) fn into_meshlets(self, seq: &[u32]) -> Meshlets {
        let mut order: Vec<Vec<u32>> = vec![Vec::new(); self.tcount.len()];
        for &t in seq {
            order[self.label[t as usize] as usize].push(t);
        }
        let mut b = MeshletBuilder::new(self.mesh.vertex_count(), self.limits);
        for tris in order.iter().filter(|v| !v.is_empty()) {
            for &t in tris {
                b.push(self.mesh.triangle(t as usize));
            }
            b.flush();
        }
        b.finish()
    }
}

/// Reusable buffers of the queries. A triangle or vertex counts as seen when its stamp equals the
/// current epoch; one epoch counter serves both kinds of stamp.
pub(crate) struct Scratch {
    /// The epoch a triangle was last seen in (flood fills).
    seen: Vec<u32>,
    /// The epoch a vertex was last seen in (vertex counts).
    pub(crate) vseen: Vec<u32>,
    /// An augmenting search's use count of a vertex in the expanded meshlet, valid where `vseen`
    /// holds the search step's epoch.
    pub(crate) vuse: Vec<u32>,
    epoch: u32,
    /// Whether a triangle is in the boundary-move work queue.
    pub(crate) queued: Vec<bool>,
    /// The triangles the last flood fill reached, in the order reached.
    piece: Vec<u32>,
}

/// The edge neighbours of `t` in its own meshlet: what must stay joined when `t` leaves.
fn same_meshlet_neighbours(cells: &Cells, t: u32) -> Vec<u32> {
    let own = cells.label[t as usize];
    cells
        .dual
        .row(t as usize)
        .iter()
        .copied()
        .filter(|&u| cells.label[u as usize] == own)
        .collect()
}

impl Scratch {
    /// Buffers for a mesh of `triangles` triangles and `vertices` vertices.
    pub(crate) fn new(triangles: usize, vertices: usize) -> Self {
        Self {
            seen: vec![0; triangles],
            vseen: vec![0; vertices],
            vuse: vec![0; vertices],
            epoch: 0,
            queued: vec![false; triangles],
            piece: Vec::new(),
        }
    }

    /// Starts a new epoch (nothing is seen in it yet) and returns it.
    pub(crate) fn new_epoch(&mut self) -> u32 {
        self.epoch += 1;
        self.epoch
    }

    /// The one flood fill: the edge-connected piece of `start`'s meshlet around `start`, breadth
    /// first, through triangles not yet seen in the current epoch, which it marks seen (a triangle
    /// marked beforehand is a wall). `reached` is told every triangle after `start` as the fill
    /// reaches it and ends the fill by returning true, and then so does this. The triangles
    /// reached (so far) are left in `piece`, in the order reached.
    fn flood(&mut self, cells: &Cells, start: u32, mut reached: impl FnMut(u32) -> bool) -> bool {
        let m = cells.label[start as usize];
        let e = self.epoch;
        self.seen[start as usize] = e;
        self.piece.clear();
        self.piece.push(start);
        let mut i = 0;
        while i < self.piece.len() {
            let u = self.piece[i];
            i += 1;
            for &w in cells.dual.row(u as usize) {
                if cells.label[w as usize] == m && self.seen[w as usize] != e {
                    self.seen[w as usize] = e;
                    self.piece.push(w);
                    if reached(w) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Whether removing `t` leaves its meshlet's edge-connected piece around `t` in one piece:
    /// a fill from one of `t`'s same-meshlet neighbours, walled at `t`, reaches the others.
    pub(crate) fn stays_connected(&mut self, cells: &Cells, t: u32) -> bool {
        let targets = same_meshlet_neighbours(cells, t);
        if targets.len() <= 1 {
            return true;
        }
        let e = self.new_epoch();
        self.seen[t as usize] = e;
        let mut left = targets.len() - 1;
        self.flood(cells, targets[0], |w| {
            if targets.contains(&w) {
                left -= 1;
                left == 0
            } else {
                false
            }
        })
    }

    /// A sufficient test of [`Self::stays_connected`] that never leaves `t`'s one-ring: whether
    /// `t`'s same-meshlet neighbours are joined without `t` through the meshlet's triangles around
    /// `t`'s corners. False can be wrong (a detour outside the ring), true cannot; it costs a few
    /// dozen steps where the fill walks the whole meshlet to find that `t` is a bridge.
    pub(crate) fn stays_connected_locally(&mut self, cells: &Cells, t: u32) -> bool {
        let own = cells.label[t as usize];
        let targets = same_meshlet_neighbours(cells, t);
        if targets.len() <= 1 {
            return true;
        }
        // The ring is marked with one epoch, the fill with the next.
        let ring = self.new_epoch();
        for x in distinct(cells.mesh.triangle(t as usize)) {
            for &u in cells.vt.row(x as usize) {
                if cells.label[u as usize] == own {
                    self.seen[u as usize] = ring;
                }
            }
        }
        self.seen[t as usize] = 0;
        let fill = self.new_epoch();
        self.seen[targets[0] as usize] = fill;
        self.piece.clear();
        self.piece.push(targets[0]);
        let mut i = 0;
        while i < self.piece.len() {
            let w = self.piece[i];
            i += 1;
            for &z in cells.dual.row(w as usize) {
                if self.seen[z as usize] == ring {
                    self.seen[z as usize] = fill;
                    self.piece.push(z);
                }
            }
        }
        targets.iter().all(|&x| self.seen[x as usize] == fill)
    }

    /// Whether meshlet `m` is one edge-connected piece.
    pub(crate) fn is_connected(&mut self, cells: &Cells, m: u32) -> bool {
        let members = &cells.members[m as usize];
        let Some(&first) = members.first() else {
            return true;
        };
        self.new_epoch();
        self.flood(cells, first, |_| false);
        self.piece.len() == members.len()
    }

    /// The edge-connected pieces of meshlet `m`, each led by its smallest triangle and in the
    /// order the fill reached it, smallest leader first.
    pub(crate) fn pieces(&mut self, cells: &Cells, m: u32) -> Vec<Vec<u32>> {
        let mut members = cells.members[m as usize].clone();
        members.sort_unstable();
        let e = self.new_epoch();
        let mut out = Vec::new();
        for &first in &members {
            if self.seen[first as usize] == e {
                continue;
            }
            self.flood(cells, first, |_| false);
            out.push(self.piece.clone());
        }
        out
    }

    /// Distinct vertices of the triangles `tris` of `mesh`.
    fn distinct_vertices(&mut self, mesh: &Mesh, tris: &[u32]) -> u32 {
        let e = self.new_epoch();
        let mut n = 0;
        for &t in tris {
            for v in mesh.triangle(t as usize) {
                if self.vseen[v as usize] != e {
                    self.vseen[v as usize] = e;
                    n += 1;
                }
            }
        }
        n
    }
}

/// What the steps work on: the cells and the scratch buffers of their queries.
pub(crate) struct Search<'a> {
    pub(crate) cells: Cells<'a>,
    pub(crate) scratch: Scratch,
}

impl<'a> Search<'a> {
    /// The search over the labelling `label` (meshlets `0..k`) of `mesh`.
    pub(crate) fn new(
        mesh: &'a Mesh,
        vt: &'a Csr,
        dual: &'a Csr,
        label: Vec<u32>,
        k: usize,
        limits: Limits,
    ) -> Self {
        Self {
            cells: Cells::new(mesh, vt, dual, label, k, limits),
            scratch: Scratch::new(mesh.triangle_count(), mesh.vertex_count()),
        }
    }

    /// [`Scratch::stays_connected`] on the cells.
    pub(crate) fn stays_connected(&mut self, t: u32) -> bool {
        self.scratch.stays_connected(&self.cells, t)
    }

    /// [`Scratch::stays_connected_locally`] on the cells.
    pub(crate) fn stays_connected_locally(&mut self, t: u32) -> bool {
        self.scratch.stays_connected_locally(&self.cells, t)
    }

    /// [`Scratch::is_connected`] on the cells.
    pub(crate) fn is_connected(&mut self, m: u32) -> bool {
        self.scratch.is_connected(&self.cells, m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjacency::{dual_graph, vertex_triangles};
    use crate::mesh::generate;

    /// The one-ring shortcut is sufficient: where it says a triangle can leave, the fill agrees;
    /// and it does say so for triangles whose neighbours it had to search for.
    #[test]
    fn the_local_test_never_claims_what_the_fill_denies() {
        // meshoptimizer's meshlets: ragged edges with bridges and detours.
        let mesh = generate::terrain(40, 3);
        let vt = vertex_triangles(&mesh);
        let dual = dual_graph(&mesh, &vt);
        let ml = crate::strategy::Kind::Meshopt
            .strategy(&crate::strategy::Options::default())
            .build(&mesh, Limits::DEFAULT);
        let (label, _) = labels_of(&mesh, &vt, &ml);
        let mut s = Search::new(&mesh, &vt, &dual, label, ml.len(), Limits::DEFAULT);
        let (mut yes, mut no) = (0, 0);
        for t in 0..mesh.triangle_count() as u32 {
            let local = s.stays_connected_locally(t);
            let fill = s.stays_connected(t);
            assert!(!local || fill, "triangle {t}: locally joined, but a bridge");
            // Only triangles with two or more neighbours in their meshlet need a search.
            let searched = same_meshlet_neighbours(&s.cells, t).len() >= 2;
            yes += (local && searched) as usize;
            no += (!fill) as usize;
        }
        assert!(yes > 0 && no > 0, "{yes} joined, {no} bridges");
    }

    /// Every exact connectivity query goes through the one flood fill: on a labelling with
    /// meshlets in pieces (triangles dealt out by index), the pieces split each meshlet,
    /// `is_connected` agrees with them, and `stays_connected` agrees with the piece count once `t`
    /// is moved out.
    #[test]
    fn the_flood_fill_answers_every_connectivity_question() {
        let mesh = generate::terrain(12, 3);
        let vt = vertex_triangles(&mesh);
        let dual = dual_graph(&mesh, &vt);
        let k = 9;
        let label: Vec<u32> = (0..mesh.triangle_count() as u32)
            .map(|t| t / 7 % 9)
            .collect();
        let mut s = Search::new(&mesh, &vt, &dual, label, k, Limits::DEFAULT);
        let mut split = 0;
        for m in 0..k as u32 {
            let pieces = s.scratch.pieces(&s.cells, m);
            let mut all: Vec<u32> = pieces.concat();
            all.sort_unstable();
            let mut members = s.cells.members[m as usize].clone();
            members.sort_unstable();
            assert_eq!(all, members, "meshlet {m}");
            assert!(pieces.windows(2).all(|w| w[0][0] < w[1][0]));
            assert_eq!(s.is_connected(m), pieces.len() == 1, "meshlet {m}");
            split += (pieces.len() > 1) as usize;
        }
        assert!(
            split > 0,
            "the test labelling should have meshlets in pieces"
        );
        // `t` leaves its piece whole when moving it out adds no piece to its meshlet.
        let spare = k as u32 - 1;
        for t in (0..mesh.triangle_count() as u32).step_by(5) {
            let own = s.cells.label[t as usize];
            if own == spare {
                continue;
            }
            let before = s.scratch.pieces(&s.cells, own).len();
            let stays = s.stays_connected(t);
            s.cells.apply(t, spare);
            let after = s.scratch.pieces(&s.cells, own).len();
            s.cells.apply(t, own);
            // Without same-meshlet neighbours `t` was a piece of its own and leaves one fewer.
            assert_eq!(
                stays,
                after <= before,
                "triangle {t}: {before} -> {after} pieces"
            );
        }
    }

    /// The ring search: ring 1 is the adjacent meshlets, every ring is new, and stopping after a
    /// ring keeps what was found so far.
    #[test]
    fn rings_grow_by_adjacency() {
        let mesh = generate::terrain(16, 5);
        let vt = vertex_triangles(&mesh);
        let dual = dual_graph(&mesh, &vt);
        let label: Vec<u32> = (0..mesh.triangle_count() as u32).map(|t| t / 24).collect();
        let k = *label.iter().max().unwrap() as usize + 1;
        let p = Cells::new(&mesh, &vt, &dual, label, k, Limits::DEFAULT);
        for m in 0..k as u32 {
            assert_eq!(p.rings(m, 0, |_| false), vec![m]);
            let mut one = p.rings(m, 1, |_| false);
            assert_eq!(one.remove(0), m);
            one.sort_unstable();
            assert_eq!(one, p.adjacent_meshlets(m));
            let mut seen = 0;
            let two = p.rings(m, 2, |ring| {
                seen += ring.len();
                false
            });
            assert_eq!(1 + seen, two.len());
            let mut unique = two.clone();
            unique.sort_unstable();
            unique.dedup();
            assert_eq!(unique.len(), two.len());
            assert_eq!(p.rings(m, 2, |_| true), p.rings(m, 1, |_| false));
        }
        let order = p.emptiest_first();
        assert!(order
            .windows(2)
            .all(|w| p.emptiness(w[0]) < p.emptiness(w[1])));
    }
}
