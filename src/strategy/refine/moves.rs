//! Steps 1 and 2: boundary moves (Fiduccia–Mattheyses gains, without FM's negative-gain passes).
//!
//! A triangle on a meshlet boundary moves to an edge-adjacent meshlet when that lowers the vertex
//! total, or keeps it and lowers the spread (Hartigan's exact k-means gain), so the lexicographic
//! objective strictly falls and the search ends. A work queue revisits only the triangles whose
//! gains a move changed (those sharing a vertex with the moved one). With the spread ranked first
//! the same moves round the meshlets off, which opens moves that vertex-first ranking never sees.

use super::state::Search;
use crate::common::distinct;
use std::collections::VecDeque;

/// Hartigan gains below this (relative to the mesh scale: the features are scale-free) count as
/// no gain.
pub(crate) const SSE_EPS: f64 = 1e-12;

/// Which objective a boundary move must lower first.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Rank {
    /// The vertex total, then the spread (step 1).
    Vertices,
    /// The spread alone, vertex total aside (step 2: rounder meshlets).
    Spread,
}

impl Search<'_> {
    /// The best improving boundary move of `t` under `rank`, if any.
    fn best_move(&mut self, t: u32, rank: Rank) -> Option<u32> {
        let p = &self.cells;
        let a = p.label[t as usize];
        let (nb, n) = p.neighbour_labels(t);
        if n == 0 {
            return None;
        }
        let rem = p.removed(t, a) as i64;
        let mut best: Option<(i64, f64, u32)> = None;
        for &b in &nb[..n] {
            let add = p.added(t, b);
            if !p.fits(b, add) {
                continue;
            }
            let gain = rem - add as i64;
            let sse = p.sse_delta(t, a, b);
            if rank == Rank::Spread {
                if sse >= -SSE_EPS {
                    continue;
                }
                if best.is_none_or(|(_, s, _)| sse < s) {
                    best = Some((gain, sse, b));
                }
                continue;
            }
            if gain < 0 {
                continue;
            }
            if gain == 0 && sse >= -SSE_EPS {
                continue;
            }
            if best.is_none_or(|(g, s, _)| gain > g || (gain == g && sse < s)) {
                best = Some((gain, sse, b));
            }
        }
        let (_, _, b) = best?;
        self.stays_connected(t).then_some(b)
    }

    /// Boundary moves under `rank` until none improves, starting from the triangles in `seeds`.
    pub(crate) fn improve(&mut self, seeds: &[u32], rank: Rank) {
        let mut work: VecDeque<u32> = VecDeque::new();
        for &t in seeds {
            if !self.scratch.queued[t as usize] {
                self.scratch.queued[t as usize] = true;
                work.push_back(t);
            }
        }
        // Every move strictly lowers (vertex total, spread); the cap is only a guard.
        let mut budget = 64 * self.cells.label.len() + 1024;
        while let Some(t) = work.pop_front() {
            self.scratch.queued[t as usize] = false;
            let Some(b) = self.best_move(t, rank) else {
                continue;
            };
            self.cells.apply(t, b);
            budget -= 1;
            if budget == 0 {
                break;
            }
            self.queue_around(t, &mut work);
        }
        for t in work {
            self.scratch.queued[t as usize] = false;
        }
    }

    /// Queues every triangle sharing a vertex with `t` that is not queued yet (their gains may
    /// have changed with `t`'s move); `scratch.queued` marks the queue's members.
    pub(crate) fn queue_around(&mut self, t: u32, work: &mut VecDeque<u32>) {
        for v in distinct(self.cells.mesh.triangle(t as usize)) {
            for &u in self.cells.vt.row(v as usize) {
                if !self.scratch.queued[u as usize] {
                    self.scratch.queued[u as usize] = true;
                    work.push_back(u);
                }
            }
        }
    }

    /// Step 2: spread-first boundary moves, then vertex-first ones.
    pub(super) fn round_off(&mut self, all: &[u32]) {
        self.improve(all, Rank::Spread);
        self.improve(all, Rank::Vertices);
    }

    /// Step 1 around moved triangles: vertex-first boundary moves seeded with every triangle
    /// sharing a vertex with one of `moved`.
    pub(crate) fn improve_around(&mut self, moved: impl IntoIterator<Item = u32>) {
        let mut seeds = Vec::new();
        for t in moved {
            for v in distinct(self.cells.mesh.triangle(t as usize)) {
                seeds.extend_from_slice(self.cells.vt.row(v as usize));
            }
        }
        self.improve(&seeds, Rank::Vertices);
    }
}
