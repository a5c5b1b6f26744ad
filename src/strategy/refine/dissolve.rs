//! Step 4: dissolving the emptiest meshlets within the limits.
//!
//! Every triangle of a victim goes to an edge-adjacent meshlet with room, cheapest (fewest new
//! vertices) first; when none has room, an augmenting path (a breadth-first search over meshlets,
//! each hop passing one boundary triangle on, as in an ejection chain) ends at a meshlet with
//! room. A victim that cannot be emptied is rolled back from the move journal. The limits hold
//! after every move, so this step never needs repairing.

use super::state::{Cells, Search};
use super::Stats;
use crate::common::distinct;

impl Search<'_> {
    /// Tries every live meshlet as a victim, emptiest first, until a whole round removes none or
    /// the searches have looked at `budget` more triangles (counted in `stats.search_work`).
    pub(super) fn dissolve_all(&mut self, search_nodes: usize, budget: u64, stats: &mut Stats) {
        let stop = stats.search_work.saturating_add(budget);
        // A victim that failed is tried again only once it or a neighbour has changed since.
        let mut failed_at: Vec<Option<usize>> = vec![None; self.cells.tcount.len()];
        loop {
            let order = self.cells.emptiest_first();
            let mut any = false;
            for m in order {
                let p = &self.cells;
                // At the hard bound no victim can go.
                if stats.search_work >= stop || p.live <= p.limits.min_meshlets(p.label.len()) {
                    return;
                }
                if p.tcount[m as usize] == 0 {
                    continue;
                }
                if let Some(at) = failed_at[m as usize] {
                    let last = p
                        .adjacent_meshlets(m)
                        .iter()
                        .chain([&m])
                        .map(|&r| p.changed_at[r as usize])
                        .max()
                        .unwrap_or(0);
                    if last <= at {
                        continue;
                    }
                }
                if !p.may_dissolve(m) {
                    failed_at[m as usize] = Some(p.moves);
                    continue;
                }
                self.cells.journal = Some(Vec::new());
                let ok = self.dissolve(m, search_nodes, &mut stats.search_work);
                let journal = self.cells.journal.take().expect("open journal");
                if ok {
                    stats.dissolved += 1;
                    any = true;
                    self.improve_around(journal.iter().map(|u| u.t));
                } else {
                    stats.failed += 1;
                    self.cells.rollback(&journal);
                    failed_at[m as usize] = Some(self.cells.moves);
                }
            }
            if !any {
                break;
            }
        }
    }

    /// Hands every triangle of meshlet `m` to its neighbours; false (state dirty, to be rolled
    /// back) when some triangle finds no room even through an ejection chain. `work` counts the
    /// triangles the augmenting searches look at.
    fn dissolve(&mut self, m: u32, search_nodes: usize, work: &mut u64) -> bool {
        while self.cells.tcount[m as usize] > 0 {
            // Cheapest hand-overs first: a triangle whose vertices a neighbour already has costs it
            // nothing, and filling such notches first keeps the neighbours round.
            let mut done = false;
            for cost in 0..=3 {
                let list = self.cells.members[m as usize].clone();
                for t in list {
                    let (nb, n) = self.cells.neighbour_labels(t);
                    for &b in &nb[..n] {
                        let add = self.cells.added(t, b);
                        if add <= cost && self.cells.fits(b, add) {
                            self.cells.apply(t, b);
                            done = true;
                            break;
                        }
                    }
                }
                if done {
                    break;
                }
            }
            if done {
                continue;
            }
            // No neighbour has room: make some with an ejection chain. A search from `b` that
            // failed for a triangle adding k vertices to it is not repeated for one adding k or
            // more: it would explore the same meshlets with no more room. Without this pruning a
            // hopeless victim costs a full search per triangle and neighbour (16 s instead of
            // 0.1 s for a fast refinement of a 20 k-triangle mesh at 128/128).
            let list = self.cells.members[m as usize].clone();
            let mut made = false;
            let mut dead: Vec<(u32, u32)> = Vec::new();
            'outer: for t in list {
                let (nb, n) = self.cells.neighbour_labels(t);
                let mut cands: Vec<(u32, u32)> = nb[..n]
                    .iter()
                    .map(|&b| (self.cells.added(t, b), b))
                    .collect();
                cands.sort_unstable();
                for (add, b) in cands {
                    if dead.iter().any(|&(d, k)| d == b && k <= add) {
                        continue;
                    }
                    let ok = search_nodes > 0 && self.augment(b, t, m, search_nodes, work);
                    if ok {
                        let add = self.cells.added(t, b);
                        if self.cells.fits(b, add) {
                            self.cells.apply(t, b);
                            made = true;
                            break 'outer;
                        }
                    }
                    dead.push((b, add));
                }
            }
            if !made {
                return false;
            }
        }
        true
    }

    /// Makes room in meshlet `b` for triangle `t` (from the victim `m`) along an augmenting path:
    /// a breadth-first search over meshlets where each hop passes one boundary triangle on, until
    /// a meshlet with a free triangle slot and vertex room takes the last one. True when `t` then
    /// fits into `b`. Adds the triangles looked at to `work`.
    fn augment(&mut self, b: u32, t: u32, m: u32, max_nodes: usize, work: &mut u64) -> bool {
        // (meshlet, incoming triangle, parent node)
        let mut nodes: Vec<(u32, u32, usize)> = vec![(b, t, usize::MAX)];
        let mut visited = vec![m, b];
        let mut head = 0;
        let mut goal = None;
        while head < nodes.len() && nodes.len() < max_nodes {
            let (y, s_in, _) = nodes[head];
            let in_v: Vec<u32> = distinct(self.cells.mesh.triangle(s_in as usize)).collect();
            let add_in = self.cells.added(s_in, y);
            if head > 0 && self.cells.fits(y, add_in) {
                goal = Some(head);
                break;
            }
            *work += self.cells.members[y as usize].len() as u64;
            // y's use count of each of its vertices, counted once for all its members (nothing
            // moves during the search): scanning each vertex's triangles per member cost about
            // 15 % of openfoam_motorbike's refinement (41 s -> 35 s without it).
            let e = self.scratch.new_epoch();
            for &s in &self.cells.members[y as usize] {
                for v in distinct(self.cells.mesh.triangle(s as usize)) {
                    let v = v as usize;
                    if self.scratch.vseen[v] != e {
                        self.scratch.vseen[v] = e;
                        self.scratch.vuse[v] = 0;
                    }
                    self.scratch.vuse[v] += 1;
                }
            }
            for i in 0..self.cells.members[y as usize].len() {
                let s = self.cells.members[y as usize][i];
                // s_in must still touch y when it arrives: never pass on one of its neighbours.
                if self.cells.dual.row(s_in as usize).contains(&s) {
                    continue;
                }
                // The stamp is this step's: stays_connected below bumps the epoch but only
                // stamps triangles.
                let freed = distinct(self.cells.mesh.triangle(s as usize))
                    .filter(|&v| !in_v.contains(&v) && self.scratch.vuse[v as usize] == 1)
                    .count() as u32;
                let limits = self.cells.limits;
                if self.cells.vcount[y as usize] + add_in > limits.max_vertices + freed {
                    continue;
                }
                let (nb, n) = self.cells.neighbour_labels(s);
                // Whether s may leave y at all, asked once (a search inside y) and only if needed.
                let mut leaves: Option<bool> = None;
                for &z in &nb[..n] {
                    if visited.contains(&z)
                        || self.cells.added(s, z) + self.cells.vcount[z as usize]
                            > limits.max_vertices
                    {
                        continue;
                    }
                    if !*leaves.get_or_insert_with(|| self.stays_connected(s)) {
                        break;
                    }
                    visited.push(z);
                    nodes.push((z, s, head));
                }
            }
            head += 1;
        }
        let Some(mut g) = goal else {
            return false;
        };
        // Apply from the far end back to b.
        while g != 0 {
            let (z, s, parent) = nodes[g];
            let add = self.cells.added(s, z);
            if !self.cells.fits(z, add) {
                return false;
            }
            self.cells.apply(s, z);
            g = parent;
        }
        let add = self.cells.added(t, b);
        self.cells.fits(b, add)
    }
}

impl Cells<'_> {
    /// A cheap test before trying to dissolve `m`: the other meshlets have room for its triangles,
    /// and the meshlets up to two hops away have room for the vertices only it uses (each must
    /// join some other meshlet; hand-overs further out mostly just pass a vertex on). A pruning
    /// heuristic: measured to skip most hopeless victims without losing a dissolve.
    fn may_dissolve(&self, m: u32) -> bool {
        let others = (self.live - 1) as u64 * self.limits.max_triangles as u64;
        let placed = (self.label.len() - self.tcount[m as usize] as usize) as u64;
        if others < self.label.len() as u64 || others - placed < self.tcount[m as usize] as u64 {
            return false;
        }
        let interior = self.members[m as usize]
            .iter()
            .flat_map(|&t| distinct(self.mesh.triangle(t as usize)))
            .filter(|&v| {
                self.vt
                    .row(v as usize)
                    .iter()
                    .all(|&u| self.label[u as usize] == m)
            })
            .collect::<std::collections::BTreeSet<u32>>()
            .len() as u32;
        let mut free_v = 0u32;
        let mut room = false;
        self.rings(m, 2, |ring| {
            for &n in ring {
                free_v += self.limits.max_vertices - self.vcount[n as usize];
            }
            room = free_v >= interior;
            room
        });
        room
    }
}
