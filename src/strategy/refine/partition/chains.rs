//! Ejection chains, shared by step 4 (repair, `repair.rs`) and step 5 (packing, `pack.rs`) of
//! `partition`: the shortest path in the meshlet adjacency graph from a cell to one with room, and
//! the hops that pass a boundary triangle (or a small vertex fan) along it, from the far end back
//! so that every hop is a move within its receiver's limits. Capacity travels across many cells
//! this way, where a single boundary move only reaches a neighbour.

use super::Stats;
use crate::common::distinct;
use crate::strategy::refine::state::Search;
use std::collections::VecDeque;

/// Meshlet adjacency lists, recomputed for a meshlet when it has changed since (its
/// `changed_at` stamp). A neighbour that changed alone can leave a list stale by a meshlet; a
/// stale entry only costs a hop that finds nothing to pass (and is then blocked), a missing one
/// a longer path. Recomputing every list per search cost half the run time on the shared meshes.
pub(super) struct Adjacency {
    lists: Vec<(usize, Vec<u32>)>,
}

impl Adjacency {
    pub(super) fn new(k: usize) -> Self {
        Self {
            lists: vec![(usize::MAX, Vec::new()); k],
        }
    }

    /// Forgets every list. Needed after a restore that follows a rollback: a rollback turns the
    /// move counter back, so a restore's fresh stamp can equal one a list was cached under on a
    /// partition since undone.
    pub(super) fn forget(&mut self) {
        for entry in &mut self.lists {
            entry.0 = usize::MAX;
        }
    }

    fn of(&mut self, s: &Search, m: u32) -> &[u32] {
        let stamp = s.cells.changed_at[m as usize];
        let entry = &mut self.lists[m as usize];
        if entry.0 != stamp {
            *entry = (stamp, s.cells.adjacent_meshlets(m));
        }
        &entry.1
    }
}

/// Whether meshlet `m` can take a triangle that adds a vertex.
fn has_room(s: &Search, m: u32) -> bool {
    let p = &s.cells;
    p.tcount[m as usize] > 0
        && p.tcount[m as usize] < p.limits.max_triangles
        && p.vcount[m as usize] < p.limits.max_vertices
}

/// The shortest chain of edge-adjacent meshlets from `v` to one with room, avoiding `blocked`
/// hops: `[v, .., goal]`.
pub(super) fn shortest_path_to_room(
    s: &Search,
    adj: &mut Adjacency,
    v: u32,
    blocked: &[(u32, u32)],
) -> Option<Vec<u32>> {
    let mut parent = vec![u32::MAX; s.cells.tcount.len()];
    parent[v as usize] = v;
    let mut queue = VecDeque::from([v]);
    while let Some(y) = queue.pop_front() {
        for &z in adj.of(s, y) {
            if parent[z as usize] != u32::MAX || blocked.contains(&(y, z)) {
                continue;
            }
            parent[z as usize] = y;
            if has_room(s, z) {
                let mut path = vec![z];
                let mut c = z;
                while c != v {
                    c = parent[c as usize];
                    path.push(c);
                }
                path.reverse();
                return Some(path);
            }
            queue.push_back(z);
        }
    }
    None
}

/// Passes one triangle (or fan) along every hop of `path` from the far end back; the first hop
/// that finds nothing to pass is blocked for the rest of this cell's turn.
pub(super) fn run_chain(
    s: &mut Search,
    path: &[u32],
    victim: bool,
    blocked: &mut Vec<(u32, u32)>,
    stats: &mut Stats,
) {
    for i in (0..path.len() - 1).rev() {
        let (y, z) = (path[i], path[i + 1]);
        if pass_one(s, y, z, victim && i == 0) {
            stats.hops += 1;
        } else {
            blocked.push((y, z));
            return;
        }
    }
}

/// Moves boundary triangles of `y` into its neighbour `z` within `z`'s limits, keeping `y`
/// edge-connected unless `y` is the victim being emptied. A link inside a chain must free a
/// vertex of `y` for what comes in next, so those go first: a single triangle, cheapest first;
/// then the fan of `y` around a vertex it shares with `z` (all of `y`'s triangles there, 2 to 4:
/// it frees that vertex, which a single triangle rarely does once boundaries are short); then a
/// single triangle that frees nothing.
fn pass_one(s: &mut Search, y: u32, z: u32, victim: bool) -> bool {
    let p = &s.cells;
    // (frees nothing, vertices added - freed, triangle)
    let mut singles: Vec<(bool, i64, u32)> = Vec::new();
    let mut shared: Vec<u32> = Vec::new();
    for &t in &p.members[y as usize] {
        let (nb, n) = p.neighbour_labels(t);
        if !nb[..n].contains(&z) {
            continue;
        }
        for w in distinct(p.mesh.triangle(t as usize)) {
            if p.uses(w, z) > 0 && !shared.contains(&w) {
                shared.push(w);
            }
        }
        let add = p.added(t, z);
        if p.fits(z, add) {
            let rem = p.removed(t, y);
            singles.push((!victim && rem == 0, add as i64 - rem as i64, t));
        }
    }
    singles.sort_unstable();
    for &(frees_none, _, t) in &singles {
        if !frees_none && (victim || s.stays_connected(t)) {
            s.cells.apply(t, z);
            return true;
        }
    }
    shared.sort_unstable();
    let mut fans: Vec<(i64, usize, u32)> = Vec::new();
    for &w in &shared {
        if let Some((net, size)) = fan_cost(s, y, z, w, victim) {
            fans.push((net, size, w));
        }
    }
    fans.sort_unstable();
    for &(_, _, w) in &fans {
        if move_fan(s, y, z, w, victim) {
            return true;
        }
    }
    for &(frees_none, _, t) in &singles {
        if frees_none && s.stays_connected(t) {
            s.cells.apply(t, z);
            return true;
        }
    }
    false
}

/// `y`'s triangles around vertex `w`.
fn fan(s: &Search, y: u32, w: u32) -> Vec<u32> {
    let p = &s.cells;
    p.vt.row(w as usize)
        .iter()
        .copied()
        .filter(|&t| p.label[t as usize] == y)
        .collect()
}

/// (vertices `z` gains - vertices `y` frees, size) of moving `y`'s fan around `w` into `z`, when
/// it fits `z` and frees a vertex of `y` (always needed unless `y` is the victim).
fn fan_cost(s: &Search, y: u32, z: u32, w: u32, victim: bool) -> Option<(i64, usize)> {
    let p = &s.cells;
    let f = fan(s, y, w);
    if f.len() < 2
        || f.len() > 4
        || p.tcount[z as usize] as usize + f.len() > p.limits.max_triangles as usize
    {
        return None;
    }
    let mut verts: Vec<u32> = f
        .iter()
        .flat_map(|&t| distinct(p.mesh.triangle(t as usize)))
        .collect();
    verts.sort_unstable();
    let (mut added, mut freed) = (0i64, 0i64);
    for run in verts.chunk_by(|a, b| a == b) {
        let u = run[0];
        added += (p.uses(u, z) == 0) as i64;
        // Every use of u in y is in the fan.
        freed += (p.uses(u, y) == run.len()) as i64;
    }
    let fits = p.vcount[z as usize] as i64 + added <= p.limits.max_vertices as i64;
    (fits && (victim || freed > 0)).then_some((added - freed, f.len()))
}

/// Moves `y`'s fan around `w` into `z`, each triangle while it touches `z` by an edge; undone
/// (false) when that leaves part of the fan behind or `y` in pieces.
fn move_fan(s: &mut Search, y: u32, z: u32, w: u32, victim: bool) -> bool {
    let mut rest = fan(s, y, w);
    let mut moved: Vec<u32> = Vec::new();
    while let Some(i) = rest.iter().position(|&t| {
        let (nb, n) = s.cells.neighbour_labels(t);
        nb[..n].contains(&z)
    }) {
        let t = rest.swap_remove(i);
        s.cells.apply(t, z);
        moved.push(t);
    }
    if rest.is_empty() && (victim || s.cells.tcount[y as usize] == 0 || s.is_connected(y)) {
        return true;
    }
    for &t in moved.iter().rev() {
        s.cells.apply(t, y);
    }
    false
}
