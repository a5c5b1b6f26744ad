//! Step 6 of `partition`, after the round-off's single moves: exchanges of boundary triangles
//! between neighbouring cells. Where the triangle limit binds every cell is full and no single
//! move fits; an exchange keeps both cells' triangle counts and can still lower the spread
//! (rounder meshlets, tighter normal cones).

use crate::common::distinct;
use crate::strategy::refine::moves::SSE_EPS;
use crate::strategy::refine::state::Search;
use std::collections::VecDeque;

/// Step 6's exchanges: boundary triangle `t` goes from its cell `a` to a neighbour `b` where that
/// lowers the spread, and a triangle `u` of `b` next to `a` comes back, the pair kept when the
/// spread falls in all, both cells stay within the vertex limit and in one piece. Triangle counts
/// do not change, so this works where every cell is full (at 64/84 the cells hold 84 triangles
/// and single moves find no room). A work queue in triangle order revisits the triangles around
/// each exchange. Returns the exchanges made.
pub(super) fn swaps(s: &mut Search) -> usize {
    let (max_v, max_t) = (s.cells.limits.max_vertices, s.cells.limits.max_triangles);
    let n_tris = s.cells.label.len();
    let mut work: VecDeque<u32> = (0..n_tris as u32).collect();
    s.scratch.queued.fill(true);
    // Every exchange lowers the spread; the cap is only a guard.
    let mut budget = 4 * n_tris;
    let mut made = 0;
    let mut cand: Vec<(f64, u32)> = Vec::new();
    while let Some(t) = work.pop_front() {
        s.scratch.queued[t as usize] = false;
        let a = s.cells.label[t as usize];
        let (nb, n) = s.cells.neighbour_labels(t);
        let mut partner = None;
        for &b in &nb[..n] {
            // A cell with a free triangle slot took the single moves it could in step 6; at
            // 64/126 exchanges with those changed the mean radius by 0.1 % at 10 % of the time.
            if s.cells.tcount[b as usize] < max_t {
                continue;
            }
            let d1 = s.cells.sse_delta(t, a, b);
            if d1 >= -SSE_EPS {
                continue;
            }
            // Triangles of `b` around `t` with an edge into `a` other than through `t`, ranked
            // by the spread change as if `t` had not moved (exact once it has, below).
            cand.clear();
            let p = &s.cells;
            for x in distinct(p.mesh.triangle(t as usize)) {
                for &u in p.vt.row(x as usize) {
                    if p.label[u as usize] != b || cand.iter().any(|c| c.1 == u) {
                        continue;
                    }
                    let row = p.dual.row(u as usize);
                    if !row.iter().any(|&w| w != t && p.label[w as usize] == a) {
                        continue;
                    }
                    let total = d1 + p.sse_delta(u, b, a);
                    if total < -SSE_EPS {
                        cand.push((total, u));
                    }
                }
            }
            if cand.is_empty() {
                continue;
            }
            if !s.stays_connected_locally(t) {
                break;
            }
            s.cells.apply(t, b);
            for c in cand.iter_mut() {
                c.0 = d1 + s.cells.sse_delta(c.1, b, a);
            }
            cand.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            for &(total, u) in &cand {
                // Sorted: no later candidate gains either.
                if total >= -SSE_EPS {
                    break;
                }
                if !s.stays_connected_locally(u) {
                    continue;
                }
                s.cells.apply(u, a);
                if s.cells.vcount[a as usize] <= max_v && s.cells.vcount[b as usize] <= max_v {
                    partner = Some(u);
                    break;
                }
                s.cells.apply(u, b);
            }
            if partner.is_some() {
                break;
            }
            s.cells.apply(t, a);
        }
        let Some(u) = partner else {
            continue;
        };
        made += 1;
        budget -= 1;
        if budget == 0 {
            break;
        }
        s.queue_around(t, &mut work);
        s.queue_around(u, &mut work);
    }
    // The queue's marks are shared with the boundary moves: leave none behind.
    for t in work {
        s.scratch.queued[t as usize] = false;
    }
    made
}
