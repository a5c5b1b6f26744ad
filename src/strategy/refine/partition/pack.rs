//! Step 5 of `partition`: packing, where meshlets are removed. The emptiest cells are emptied one
//! at a time, each triangle handed to a neighbour with room or, when none has any, passed on along
//! an ejection chain (`chains.rs`); a victim that cannot be emptied is rolled back from the move
//! journal.

use super::chains::{run_chain, shortest_path_to_room, Adjacency};
use super::{Config, Stats};
use crate::strategy::refine::state::Search;

/// Step 5: empties the emptiest meshlets while victims go.
pub(super) fn pack(s: &mut Search, adj: &mut Adjacency, config: Config, stats: &mut Stats) {
    let floor = s.cells.limits.min_meshlets(s.cells.label.len());
    let mut failed = vec![false; s.cells.tcount.len()];
    let mut failures = 0;
    while s.cells.live > floor && failures < config.max_failures {
        let Some(v) = s
            .cells
            .emptiest_first()
            .into_iter()
            .find(|&m| !failed[m as usize])
        else {
            break;
        };
        s.cells.journal = Some(Vec::new());
        let ok = empty(s, adj, v, config, stats);
        let journal = s.cells.journal.take().expect("open journal");
        if ok {
            stats.dissolved += 1;
            failures = 0;
            failed.fill(false);
            s.improve_around(journal.iter().map(|u| u.t));
        } else {
            stats.failed += 1;
            failures += 1;
            s.cells.rollback(&journal);
            failed[v as usize] = true;
        }
    }
}

/// Empties meshlet `v`; false (state dirty, to be rolled back) when it cannot.
fn empty(s: &mut Search, adj: &mut Adjacency, v: u32, config: Config, stats: &mut Stats) -> bool {
    let mut chains = config.chains_per_triangle * s.cells.tcount[v as usize];
    let mut blocked: Vec<(u32, u32)> = Vec::new();
    while s.cells.tcount[v as usize] > 0 {
        if hand_over(s, v) {
            continue;
        }
        if chains == 0 {
            return false;
        }
        chains -= 1;
        stats.chains += 1;
        let Some(path) = shortest_path_to_room(s, adj, v, &blocked) else {
            return false;
        };
        run_chain(s, &path, true, &mut blocked, stats);
    }
    true
}

/// Hands one triangle of `v` to an edge neighbour with room, cheapest (fewest added vertices)
/// first, ties to the lowest triangle; false when none fits.
fn hand_over(s: &mut Search, v: u32) -> bool {
    let p = &s.cells;
    let mut best: Option<(u32, u32, u32)> = None;
    for &t in &p.members[v as usize] {
        let (nb, n) = p.neighbour_labels(t);
        for &b in &nb[..n] {
            let add = p.added(t, b);
            if p.fits(b, add) && best.is_none_or(|x| (add, t, b) < x) {
                best = Some((add, t, b));
            }
        }
    }
    let Some((_, t, b)) = best else {
        return false;
    };
    s.cells.apply(t, b);
    true
}
