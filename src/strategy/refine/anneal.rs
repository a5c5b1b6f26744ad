//! Step 5: simulated annealing over boundary moves, globally and per victim.
//!
//! Boundary moves alone cannot move vertex capacity far (a vertex freed on one side of a meshlet
//! does not help the other); annealing's uphill moves can. The energy is the vertex total, plus
//! the overflow (vertices and triangles over the limits) times [`OVERFLOW_WEIGHT`], plus the
//! feature spread times a scale ([`Cells::spread_scale`]). A victim's triangles are handed to
//! their neighbours regardless of the limits, and an anneal confined to the meshlets within
//! [`ANNEAL_RINGS`] of it must drive the overflow back to zero, or the hand-over is undone.

use super::moves::Rank;
use super::state::{Cells, Search, FEATURES};
use super::{Stats, OVERFLOW_WEIGHT};
use rand_core::Rng;
use rand_xorshift::XorShiftRng;

/// Weight of the spread change in the annealer's energy: keeps annealed meshlets as round as the
/// input (at 0 the mean radius grew 3 % on the bunny).
const SPREAD_WEIGHT: f64 = 0.25;

/// Step 5 anneals only the meshlets within this many edge-adjacency hops of the victim (about 45
/// meshlets): on the bunny 2 rings dissolved 3 meshlets, 3 rings 6 to 9, 4 rings 10, 5 rings 10
/// at more cost; capacity has to come from a few meshlets away.
const ANNEAL_RINGS: usize = 4;

impl Cells<'_> {
    /// How far meshlet `m` is over the limits (vertices plus triangles).
    fn overflow(&self, m: u32) -> i64 {
        let (v, t) = (self.vcount[m as usize], self.tcount[m as usize]);
        (v as i64 - self.limits.max_vertices as i64).max(0)
            + (t as i64 - self.limits.max_triangles as i64).max(0)
    }

    /// [`SPREAD_WEIGHT`] over the mean squared distance of a triangle's features to its meshlet's
    /// mean: the weight of a spread change in the annealer's energy. A pass over the mesh, so
    /// it is measured once per annealing stage, not per victim (on the 871 k-triangle dragon that
    /// pass cost more than a victim's anneal).
    pub(super) fn spread_scale(&self) -> f64 {
        let mut sum = 0.0;
        for (t, &m) in self.label.iter().enumerate() {
            let n = self.tcount[m as usize] as f64;
            let c = self.csum[m as usize];
            sum += (0..FEATURES)
                .map(|i| (self.features[t][i] - c[i] / n).powi(2))
                .sum::<f64>();
        }
        SPREAD_WEIGHT / (sum / self.label.len() as f64).max(f64::MIN_POSITIVE)
    }

    /// Hands every triangle of meshlet `m` to an edge-adjacent meshlet, fewest new vertices first,
    /// limits ignored. False when some triangle has no such neighbour (an isolated piece).
    fn hand_over(&mut self, m: u32) -> bool {
        while self.tcount[m as usize] > 0 {
            let mut progress = false;
            for t in self.members[m as usize].clone() {
                // Neighbour labels never include `t`'s own meshlet, so none is `m` itself.
                let (nb, n) = self.neighbour_labels(t);
                let best = nb[..n]
                    .iter()
                    .min_by_key(|&&b| (self.added(t, b), self.tcount[b as usize], b))
                    .copied();
                if let Some(b) = best {
                    self.apply(t, b);
                    progress = true;
                }
            }
            if !progress {
                return false;
            }
        }
        true
    }
}

impl Search<'_> {
    /// Simulated annealing over boundary moves of the triangles in `pool` (all when `None`) with
    /// the energy vertex total + overflow × weight + spread × `scale` ([`Cells::spread_scale`]),
    /// temperature falling geometrically from `temps.0` to `temps.1`. Never empties a meshlet.
    /// With `stop_when_feasible` it ends as soon as nothing overflows. True when it ends without
    /// overflow.
    pub(super) fn anneal(
        &mut self,
        pool: Option<&[u32]>,
        steps: u64,
        (temps, scale): ((f64, f64), f64),
        rng: &mut XorShiftRng,
        stop_when_feasible: bool,
    ) -> bool {
        let mut over: i64 = (0..self.cells.tcount.len() as u32)
            .map(|m| self.cells.overflow(m))
            .sum();
        let n = self.cells.label.len() as u64;
        let (mv, mt) = (
            self.cells.limits.max_vertices as i64,
            self.cells.limits.max_triangles as i64,
        );
        let mut temp = temps.0;
        // The temperature is updated every 1024 proposals (a power per proposal costs more than
        // the proposal).
        let factor = (temps.1 / temps.0).powf(1024.0 / steps.max(1) as f64);
        for i in 0..steps {
            if stop_when_feasible && over == 0 {
                return true;
            }
            if i % 1024 == 1023 {
                temp *= factor;
            }
            let t = match pool {
                Some(p) => p[(rng.next_u64() % p.len() as u64) as usize],
                None => (rng.next_u64() % n) as u32,
            };
            let p = &self.cells;
            let (nb, k) = p.neighbour_labels(t);
            if k == 0 {
                continue;
            }
            let b = nb[(rng.next_u64() % k as u64) as usize];
            let a = p.label[t as usize];
            if p.tcount[a as usize] == 1 {
                continue;
            }
            let (add, rem) = (p.added(t, b) as i64, p.removed(t, a) as i64);
            let (ua, ub) = (a as usize, b as usize);
            let ov_before = p.overflow(a) + p.overflow(b);
            let ov_after = (p.vcount[ua] as i64 - rem - mv).max(0)
                + (p.vcount[ub] as i64 + add - mv).max(0)
                + (p.tcount[ua] as i64 - 1 - mt).max(0)
                + (p.tcount[ub] as i64 + 1 - mt).max(0);
            let delta = (add - rem) as f64
                + OVERFLOW_WEIGHT * (ov_after - ov_before) as f64
                + scale * p.sse_delta(t, a, b);
            if delta > 0.0 {
                let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
                if u >= (-delta / temp).exp() {
                    continue;
                }
            }
            if !self.stays_connected(t) {
                continue;
            }
            self.cells.apply(t, b);
            over += ov_after - ov_before;
        }
        over == 0
    }

    /// Removes meshlets one at a time, emptiest first: a victim's triangles are handed to its
    /// neighbours regardless of the limits, then an anneal confined to the meshlets within
    /// [`ANNEAL_RINGS`] of it drives the overflow back to zero within `steps_per_triangle`
    /// proposals per triangle there, or the hand-over is undone. Ends after `failures` victims in
    /// a row could not go. Confining the anneal makes a failed victim cost its neighbourhood, not
    /// the mesh: on the bunny the same budget per triangle dissolves more (720 -> 710-712
    /// meshlets instead of 714) in two thirds of the time of annealing the whole mesh per attempt.
    pub(super) fn anneal_dissolve(
        &mut self,
        steps_per_triangle: u64,
        failures: u32,
        rng: &mut XorShiftRng,
        stats: &mut Stats,
    ) {
        let mut failed = vec![false; self.cells.tcount.len()];
        let mut in_a_row = 0;
        let scale = self.cells.spread_scale();
        while in_a_row < failures {
            let p = &self.cells;
            if p.live <= p.limits.min_meshlets(p.label.len()) {
                return;
            }
            let Some(victim) = (0..p.tcount.len() as u32)
                .filter(|&m| p.tcount[m as usize] > 0 && !failed[m as usize])
                .min_by_key(|&m| p.emptiness(m))
            else {
                return;
            };
            let mut region = p.rings(victim, ANNEAL_RINGS, |_| false);
            region.sort_unstable();
            // A journal, not a snapshot: undoing costs the moves made, not the mesh.
            self.cells.journal = Some(Vec::new());
            let mut ok = self.cells.hand_over(victim);
            let pool: Vec<u32> = region
                .iter()
                .flat_map(|&m| self.cells.members[m as usize].iter().copied())
                .collect();
            // Moderate, nearly constant temperature: hot enough to carry overflow through full
            // meshlets, cool enough to keep the boundaries shortened so far.
            ok = ok
                && !pool.is_empty()
                && self.anneal(
                    Some(&pool),
                    steps_per_triangle * pool.len() as u64,
                    ((0.4, 0.2), scale),
                    rng,
                    true,
                );
            let journal = self.cells.journal.take().expect("open journal");
            if ok {
                stats.dissolved += 1;
                in_a_row = 0;
                self.improve(&pool, Rank::Vertices);
            } else {
                stats.failed += 1;
                self.cells.rollback(&journal);
                failed[victim as usize] = true;
                in_a_row += 1;
            }
        }
    }
}
