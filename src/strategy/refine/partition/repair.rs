//! Step 4 of `partition`: the repair. The re-partition and its boundary moves without the limits
//! leave some cells over a limit; each sheds triangles along ejection chains (`chains.rs`), and
//! the few that no chain fixes are split into empty cells. A re-partition that this cannot bring
//! back within the limits is given up for the fallback.

use super::chains::{run_chain, shortest_path_to_room, Adjacency};
use super::{Config, Stats};
use crate::strategy::refine::state::Search;
use glam::DVec3;
use std::collections::VecDeque;

/// Whether meshlet `m` is over a limit.
pub(super) fn over_limit(s: &Search, m: u32) -> bool {
    let p = &s.cells;
    p.vcount[m as usize] > p.limits.max_vertices || p.tcount[m as usize] > p.limits.max_triangles
}

/// How a repair (step 4) ended.
pub(super) enum Repair {
    /// Every cell within the limits.
    Done,
    /// Some cells still over a limit after the chains and splits.
    Unrepaired,
    /// Stopped in a pass with more failures than the splits could ever take.
    Stopped,
}

/// Step 4: brings every cell back within the limits. A cell that fails is tried once more after
/// the others (their chains change its surroundings), unless more than four times
/// [`Config::max_splits`] failed (then it stops); what still fails is split.
pub(super) fn repair(
    s: &mut Search,
    adj: &mut Adjacency,
    config: Config,
    stats: &mut Stats,
) -> Repair {
    let mut todo: Vec<u32> = (0..s.cells.tcount.len() as u32)
        .filter(|&m| over_limit(s, m))
        .collect();
    // Passes after the first fix few cells (measured: 140 -> 128, 17 -> 5, 14 -> 10, 2 -> 1):
    // far more failures than the splits can take mean a failed re-partition, so stop paying.
    let most_failures = 4 * config.max_splits as usize;
    for _pass in 0..2 {
        let mut left = Vec::new();
        for &o in &todo {
            let mut blocked: Vec<(u32, u32)> = Vec::new();
            let mut chains = config.chains_per_meshlet;
            while over_limit(s, o) && chains > 0 {
                chains -= 1;
                stats.chains += 1;
                let Some(path) = shortest_path_to_room(s, adj, o, &blocked) else {
                    break;
                };
                run_chain(s, &path, false, &mut blocked, stats);
            }
            if over_limit(s, o) {
                left.push(o);
                if left.len() > most_failures {
                    return Repair::Stopped;
                }
            }
        }
        todo = left;
    }
    // What no chain fixed is split into empty cells (the spares after the input's, or cells
    // whose seed was dropped).
    let mut spare: VecDeque<u32> = (0..s.cells.tcount.len() as u32)
        .filter(|&z| s.cells.tcount[z as usize] == 0)
        .take(config.max_splits as usize)
        .collect();
    todo.retain(|&o| {
        while over_limit(s, o) {
            let Some(z) = spare.pop_front() else { break };
            split(s, o, z);
            stats.splits += 1;
        }
        over_limit(s, o)
    });
    // A chain may push a cell that was within its limits over them only through a bug: every
    // hop is a move within its receiver's limits.
    if todo.is_empty() {
        Repair::Done
    } else {
        Repair::Unrepaired
    }
}

/// Moves triangles of the over-full cell `o` into the empty cell `z`, breadth-first inside `o`
/// from its member farthest from its centroid (so `z` is one piece at `o`'s edge), until `o` is
/// within the limits or `z` would break them.
fn split(s: &mut Search, o: u32, z: u32) {
    let p = &s.cells;
    let n = p.tcount[o as usize] as f64;
    let centre = DVec3::new(
        p.csum[o as usize][0],
        p.csum[o as usize][1],
        p.csum[o as usize][2],
    ) / n;
    let far = |t: u32| {
        DVec3::new(
            p.features[t as usize][0],
            p.features[t as usize][1],
            p.features[t as usize][2],
        )
        .distance_squared(centre)
    };
    let Some(&seed) = p.members[o as usize]
        .iter()
        .max_by(|&&a, &&b| far(a).total_cmp(&far(b)).then(b.cmp(&a)))
    else {
        return;
    };
    let mut queue = VecDeque::from([seed]);
    let mut seen = vec![seed];
    while let Some(t) = queue.pop_front() {
        if !over_limit(s, o) {
            break;
        }
        if !s.cells.fits(z, s.cells.added(t, z)) {
            break;
        }
        s.cells.apply(t, z);
        for &u in s.cells.dual.row(t as usize) {
            if s.cells.label[u as usize] == o && !seen.contains(&u) {
                seen.push(u);
                queue.push_back(u);
            }
        }
    }
}
