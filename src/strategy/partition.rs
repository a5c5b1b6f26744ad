//! `partition`: fewer meshlets by re-partitioning the whole mesh at a fixed count and packing the
//! result with ejection chains over the meshlet graph (issue 33).
//!
//! Background (`../shared/notes/meshlet-count-bound.md`): at a vertex limit a disc-shaped patch
//! with V vertices, B of them on its boundary, holds 2V - B - 2 triangles, so only shorter
//! boundaries make room. meshoptimizer's greedy growth leaves meshlets whose boundaries are about
//! 4 vertices longer than a hexagon's, because each meshlet grows into the ragged space its
//! predecessors left. A global partition places all cells at once.
//!
//! The steps, on the state of `+refine` (`refine::state`: labels, counts, move journal):
//! 1. **Start**: the input strategy's meshlets (meshoptimizer's for `partition`), then the
//!    vertex-gain boundary moves of `+refine` step 1. This state is kept as the fallback.
//! 2. **Global re-partition** ([`Config::lloyd_iterations`]): balanced geodesic Lloyd over the dual
//!    graph at the same count or a little below it (the drops below). Seeds are the triangles
//!    nearest each cell's centroid; a multi-source Dijkstra over centroid distances assigns every
//!    triangle; each cell's distance carries an additive weight that grows with its vertex count
//!    over the limit ([`Config::balance_step`]), so cells head for equal vertex counts (a power
//!    diagram on the surface). [`Config::drops`]: the first attempt leaves out the seeds of the
//!    emptiest 0.3 % of the cells (at least one), so the repair and packing start from fewer cells
//!    (one probe run at 64/126: igea 2769 meshlets against 2775 without, pycortex 3178 against
//!    3185; with at least one, fandisk 133 and cad-part-400 102 where 0.3 % rounded to none and
//!    left 134 and 103; more than 0.3 %, see [`Config::default`]). Further entries are further
//!    attempts, tried only when the repair fails even with splits; a repair that succeeds (with or
//!    without splits) or stops early ends the attempts (measured on the shared and stress meshes:
//!    after an early stop the attempt with every seed stopped early too, and after a repair with
//!    splits it packed to no fewer meshlets). The default's second attempt, with every seed, ran
//!    only on the two neurons at 64/126 and was not kept there (a third of their time), but a
//!    smooth sphere keeps it, so it stays. The Dijkstra settles one band of distances at a time
//!    ([`Config::band`]) in triangle order: its pops otherwise jump across the whole mesh, and on
//!    igea it took 0.7x meshoptimizer's whole build in cache misses.
//! 3. **Boundary moves without the limits**: the same vertex-gain moves with the limits lifted,
//!    which shortens the Voronoi cells' ragged boundaries. Cells may now be over the vertex limit.
//! 4. **Repair**: every cell over a limit sheds triangles along an ejection chain: the shortest
//!    path in the meshlet adjacency graph to a cell with room, one boundary triangle (or a small
//!    fan) passed per hop, executed from the far end back so that every hop is a move within the
//!    limits of its receiver. The few cells no chain repairs within
//!    [`Config::chains_per_meshlet`] are split ([`Config::max_splits`]); a re-partition that needed
//!    splits is packed (step 5) and kept only when it then beats the packed fallback. Too many
//!    unrepaired cells end the attempt early, fall back to step 1's state and end the attempts.
//! 5. **Packing**: the emptiest cells are emptied one at a time, every triangle handed to a
//!    neighbour with room or, when none has any, through an ejection chain as in step 4; a victim
//!    that cannot be emptied is rolled back from the journal. [`Config::max_failures`] failures in
//!    a row end it.
//! 6. **Round-off** ([`Config::round_off`]): `+refine`'s spread-first boundary moves at the final
//!    count, within the limits: rounder meshlets and tighter normal cones (measured on the shared
//!    meshes at 64/126: mean radius over meshoptimizer's 0.97-1.02 where it was 0.98-1.04).
//!    Where the triangle limit binds (64/84, 128/128) every cell is full and no single move
//!    fits, so exchanges follow ([`Config::swaps`]): a boundary triangle moves to a full
//!    neighbour and one of the neighbour's comes back, where that lowers the spread. Measured
//!    (one run, mean radius over meshoptimizer's): at 64/84 the bunny 1.003 -> 0.970, igea 1.017
//!    -> 0.982, pycortex 1.086 -> 1.044, cad-part-400 1.846 -> 1.779; at 128/128 cad-part-400
//!    1.962 -> 1.907; at 64/126 few cells are full (the motorbike's duplicated triangles, the
//!    neurons' tubes), the motorbike 0.994 -> 0.987. Counts are unchanged; the cost is about a
//!    quarter more partition time on the bunny and igea at 64/84, two fifths on the motorbike.
//! 7. **Cones** ([`Config::cone_repair`]): a cell whose normals spread over (almost) a half-space
//!    has no backface cone (`meshlet::bounds::cone_axis`, the bounds' own test). It hands the
//!    boundary triangles most opposed to its mean normal to neighbours, never taking a
//!    neighbour's cone away, a quarter of the cell at most, and is rolled back unless it ends
//!    cullable. Measured at
//!    64/126: the bunny keeps 2 non-cullable meshlets instead of 3 (meshoptimizer: 2), pycortex
//!    868 instead of 982 (meshoptimizer: 1265); igea's one is not fixed (meshoptimizer: 0). Time
//!    (`partition_with_stats` alone, 3 interleaved runs): pycortex 335-350 ms -> 420-448 ms, its
//!    982 cells to repair; the dragon within the noise.
//!
//! An input already at the hard bound ceil(T / max triangles) is returned as it is: no step can
//! remove a meshlet there, and the moves only cost time and the input's shapes.
//!
//! Where this differs from textbook multilevel partitioners (METIS, KaHIP): one level only (the
//! dual graph itself; the cells are few hundred triangles), the balance constraint is the hard
//! vertex and triangle limits rather than a size tolerance, and the gain of a boundary move is
//! the meshlet-vertex total rather than the edge cut. Where it differs from `+refine`: no
//! annealing; capacity travels along whole chains of meshlets instead of one neighbourhood.
//!
//! Determinism: one thread, a fixed order everywhere, ties broken by index; the heap's keys are
//! (distance bits, triangle, cell). The output depends neither on the thread count nor the run.

use super::refine::moves::{Rank, SSE_EPS};
use super::refine::state::{labels_of, vertex_counts, Search};
use super::Strategy;
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::mesh::Mesh;
use crate::meshlet::bounds::{cone_axis, triangle_normal};
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::parallel::distinct;
use glam::DVec3;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// Search settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Step 2: Lloyd iterations (0 = no re-partition, only packing the input).
    pub lloyd_iterations: u32,
    /// Step 2: width of the distance band the Dijkstra settles at once, in mean
    /// centroid-to-centroid edge lengths (0 = exact order). A band's triangles are settled in index
    /// order, which sweeps memory instead of jumping across the mesh with every pop; within a band
    /// a triangle may go to a cell up to this much farther than its nearest.
    pub band: f64,
    /// Step 2: growth of a cell's additive weight per vertex over (limit - 1), in mean
    /// centroid-to-centroid edge lengths.
    pub balance_step: f64,
    /// Step 4: ejection chains one over-full cell may start before it is split.
    pub chains_per_meshlet: u32,
    /// Step 2: re-partitions to try in turn, each with the seeds of this share of the cells (the
    /// emptiest; at least one where the share is above 0) left out, largest first, until one is
    /// repaired (with or without splits) or a repair stops early (its failures far beyond what
    /// fewer dropped seeds could take). A dropped seed of a cell that is a whole mesh piece drops
    /// nothing: no other seed reaches the piece, so it keeps its cell.
    pub drops: &'static [f64],
    /// Step 4: cells the repair may split off over-full cells that no chain fixes. With splits
    /// the re-partition is kept only when, packed, it ends with fewer meshlets than the packed
    /// fallback.
    pub max_splits: u32,
    /// Step 5: victims in a row that may fail before the packing ends.
    pub max_failures: u32,
    /// Step 5: ejection chains one victim may start per triangle it holds.
    pub chains_per_triangle: u32,
    /// Step 6: spread-first boundary moves at the final count (rounder meshlets, tighter normal
    /// cones).
    pub round_off: bool,
    /// Step 7: cells whose normals span (almost) a half-space (no backface cone) give their most
    /// opposed boundary triangles to neighbours until their cone can cull (a quarter of the cell
    /// at most; rolled back where that is not enough).
    pub cone_repair: bool,
    /// Step 6, after the single moves (so only with [`Self::round_off`]): exchanges of boundary
    /// triangles between neighbouring cells that lower the spread where the receiver is full
    /// (rounder meshlets where the triangle limit binds, as at 64/84).
    pub swaps: bool,
}

impl Default for Config {
    /// Measured on the shared meshes at 64/126 (issue 33 note): one Lloyd iteration removed as
    /// many meshlets as two or six and is the cheapest; 64 chains per over-full cell repaired the
    /// bunny, igea and the aneurysm where 16 failed on the aneurysm; 2 chains per victim triangle
    /// removed as many as 4, in less time; a 4th to 8th failed victim in a row never went. A band
    /// of half an edge gave the exact order's counts on the bunny, igea, gaspra and the aneurysm
    /// and about halved the Lloyd step on igea (210 against 110 ms, one run each). Dropping 0.3 %
    /// of the seeds first: see the module doc; 0.6 % and 1 % removed more on the bunny and
    /// pycortex but failed on igea, where each failed attempt costs about 1x meshoptimizer.
    fn default() -> Self {
        Self {
            lloyd_iterations: 1,
            band: 0.5,
            balance_step: 0.05,
            chains_per_meshlet: 64,
            max_splits: 4,
            drops: &[0.003, 0.0],
            max_failures: 3,
            chains_per_triangle: 2,
            round_off: true,
            cone_repair: true,
            swaps: true,
        }
    }
}

/// What a run did, for reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Meshlets before.
    pub meshlets_before: usize,
    /// Meshlets after.
    pub meshlets_after: usize,
    /// Meshlet vertex references before.
    pub vertices_before: usize,
    /// Meshlet vertex references after.
    pub vertices_after: usize,
    /// Re-partitions tried (steps 2-4; at most one per entry of [`Config::drops`]).
    pub attempts: usize,
    /// Cells over a limit after the re-partition's boundary moves (step 3), before the repair.
    pub overfull: usize,
    /// Whether the global re-partition was kept (false: it could not be repaired, or it packed
    /// no better than the fallback).
    pub repartitioned: bool,
    /// Cells the repair split off over-full ones. This and the counts below sum the work of
    /// every attempt, also of re-partitions that were then dropped; the meshlet counts above are
    /// the result's.
    pub splits: usize,
    /// Meshlets emptied by the packing.
    pub dissolved: usize,
    /// Victims rolled back.
    pub failed: usize,
    /// Ejection chains started (repair and packing).
    pub chains: usize,
    /// Hops of those chains that moved triangles.
    pub hops: usize,
    /// Cells step 7 made cone-cullable.
    pub cones_fixed: usize,
    /// Exchanges step 6 made.
    pub swaps: usize,
}

/// Any strategy followed by the re-partition and packing.
pub struct Partitioned {
    /// The strategy whose output is re-partitioned.
    pub inner: Box<dyn Strategy>,
    /// Search settings.
    pub config: Config,
    /// The name it was selected by, e.g. `partition` or `greedy+partition`.
    pub name: &'static str,
}

impl Strategy for Partitioned {
    fn name(&self) -> &'static str {
        self.name
    }
    fn summary(&self) -> &'static str {
        "meshoptimizer's meshlets (or any strategy's), re-partitioned globally by balanced Lloyd and packed along ejection chains (fewer meshlets)"
    }
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let ml = self.inner.build(mesh, limits);
        partition(mesh, &ml, limits, self.config)
    }
}

/// Re-partitions `ml` (a valid partition of `mesh` within `limits`); the result is valid for the
/// same limits and has at most as many meshlets.
///
/// # Panics
/// When `ml` does not hold every triangle of `mesh` exactly once (check it with
/// [`crate::meshlet::validate`] first when it comes from outside).
pub fn partition(mesh: &Mesh, ml: &Meshlets, limits: Limits, config: Config) -> Meshlets {
    partition_with_stats(mesh, ml, limits, config).0
}

/// [`partition`], also returning what it did.
pub fn partition_with_stats(
    mesh: &Mesh,
    ml: &Meshlets,
    limits: Limits,
    config: Config,
) -> (Meshlets, Stats) {
    // At the hard bound nothing can be removed, and the input's shapes are kept as they are.
    let floor = limits.min_meshlets(mesh.triangle_count());
    if ml.len() <= floor {
        let stats = Stats {
            meshlets_before: ml.len(),
            meshlets_after: ml.len(),
            vertices_before: ml.vertices.len(),
            vertices_after: ml.vertices.len(),
            ..Stats::default()
        };
        return (ml.clone(), stats);
    }
    let vt = vertex_triangles(mesh);
    let (labels, seq) = labels_of(mesh, &vt, ml);
    let dual = dual_graph(mesh, &vt);
    // Spare (empty) cells after the input's, for the repair's splits.
    let k = ml.len() + config.max_splits as usize;
    let mut s = Search::new(mesh, &vt, &dual, labels, k, limits);
    let mut stats = Stats {
        meshlets_before: ml.len(),
        vertices_before: s.cells.vcount.iter().map(|&v| v as usize).sum(),
        ..Stats::default()
    };
    let all: Vec<u32> = (0..mesh.triangle_count() as u32).collect();
    s.improve(&all, Rank::Vertices);
    let mut adj = Adjacency::new(k);
    // A re-partition repaired with splits, packed: weighed against the packed fallback below.
    let mut candidate: Option<(Vec<u32>, usize)> = None;
    // At the hard bound nothing can be removed: skip the search.
    if config.lloyd_iterations > 0 && s.cells.live > floor {
        let fallback = s.cells.label.clone();
        let mut tried = Vec::new();
        for &drop in config.drops {
            // Near the hard bound every cell is needed: drop at most a quarter of the slack.
            let slack = s.cells.live - floor;
            // At least one where any is asked for: under 167 cells 0.3 % rounds to none, and
            // fandisk (134 at 64/126) lost one meshlet only with one seed dropped.
            let share = (drop * s.cells.live as f64).round() as usize;
            let dropped = (if drop > 0.0 { share.max(1) } else { 0 }).min(slack / 4);
            if tried.contains(&dropped) {
                continue;
            }
            tried.push(dropped);
            stats.attempts += 1;
            match repartition(&mut s, &mut adj, config, dropped, &fallback, &mut stats) {
                // Kept: done. Hopeless: far more unrepaired cells than the next attempt's few
                // extra seeds could take (the drops fall from one attempt to the next).
                Outcome::Kept | Outcome::Hopeless => break,
                Outcome::Failed => {}
                // Repaired with splits. The next attempt keeps more seeds; on the shared and
                // stress meshes at 64/126, 64/84 and 128/128 one followed only on pycortex and
                // gaspra at 64/126, and it packed to more meshlets (3185 against 3175, 338
                // against 337) at the cost of a whole attempt (pycortex: 40 % of the run).
                Outcome::Packed(labels, live) => {
                    candidate = Some((labels, live));
                    break;
                }
            }
        }
    }
    pack(&mut s, &mut adj, config, &mut stats);
    // A re-partition that needed splits, packed, against the packed fallback.
    if let Some((labels, live)) = candidate {
        if live < s.cells.live {
            s.cells.restore(&labels);
            stats.repartitioned = true;
        }
    }
    if config.round_off {
        // Spread-first moves, then vertex-first ones where those moved (the packing left none
        // elsewhere).
        s.cells.journal = Some(Vec::new());
        s.improve(&all, Rank::Spread);
        let moved = s.cells.journal.take().expect("open journal");
        s.improve_around(moved.iter().map(|u| u.t));
        if config.swaps {
            stats.swaps = swaps(&mut s);
        }
    }
    if config.cone_repair {
        stats.cones_fixed = cone_repair(&mut s);
    }
    let live = s.cells.live;
    let out = s.cells.into_meshlets(&seq);
    // Every step ends within the limits, so no meshlet is split on the way out.
    debug_assert_eq!(out.len(), live, "a partitioned meshlet broke a limit");
    stats.meshlets_after = out.len();
    stats.vertices_after = out.vertices.len();
    (out, stats)
}

/// What one re-partition attempt left.
enum Outcome {
    /// Repaired without splits: the state is the re-partition.
    Kept,
    /// Not repaired: the state is the fallback again.
    Failed,
    /// Not repaired, and the repair stopped early (far more failures than the splits can take):
    /// the state is the fallback again, and no further attempt is made. Measured on the shared
    /// meshes at 64/126, 64/84 and 128/128: where the first attempt's repair stopped early
    /// (the motorbike, the dragon), the next attempt, with every seed, stopped early too.
    Hopeless,
    /// Repaired with splits (more cells than the input), then packed: its labels and live
    /// count, to compare with the packed fallback. The state is the fallback again.
    Packed(Vec<u32>, usize),
}

/// Steps 2-4 from the cells `fallback` (the state on entry), with the seeds of the `dropped`
/// emptiest cells left out (fewer cells for the repair to fill).
fn repartition(
    s: &mut Search,
    adj: &mut Adjacency,
    config: Config,
    dropped: usize,
    fallback: &[u32],
    stats: &mut Stats,
) -> Outcome {
    let limits = s.cells.limits;
    let all: Vec<u32> = (0..s.cells.label.len() as u32).collect();
    let labels = lloyd(s, config, dropped);
    s.cells.restore(&labels);
    // Step 3: the limits are lifted to the largest the format allows (cells are near the real
    // limits, far from these).
    s.cells.limits = Limits::new(256, 256).expect("the largest limits");
    s.improve(&all, Rank::Vertices);
    s.cells.limits = limits;
    stats.overfull = (0..s.cells.tcount.len() as u32)
        .filter(|&m| over(s, m))
        .count();
    let splits = stats.splits;
    match repair(s, adj, config, stats) {
        Repair::Done => {}
        Repair::Unrepaired => {
            s.cells.restore(fallback);
            return Outcome::Failed;
        }
        Repair::Stopped => {
            s.cells.restore(fallback);
            return Outcome::Hopeless;
        }
    }
    // All triangles, not only the repair's: zero-gain moves that lower the spread reach
    // anywhere (the cells' means moved), and they feed the packing (pycortex at 64/84: the hard
    // bound with them, one above it with moves around the repair only).
    s.improve(&all, Rank::Vertices);
    if stats.splits == splits {
        stats.repartitioned = true;
        return Outcome::Kept;
    }
    pack(s, adj, config, stats);
    let packed = Outcome::Packed(s.cells.label.clone(), s.cells.live);
    s.cells.restore(fallback);
    adj.forget();
    packed
}

/// Step 7's view of the cones: triangle normals and the cone test as `meshlet::bounds` computes
/// them, so a cell found cullable here gets a cone there (up to rounding right at the test's
/// thresholds: the bounds see the normals in another order).
struct Cones<'a> {
    mesh: &'a Mesh,
}

/// Smallest dot product of every normal with the mean normal at which a cell passes without the
/// exact test: the bounds' axis maximises the smallest dot product, and their test asks for more
/// than about 0.0045 (cutoff sqrt(1 - d^2) plus its margin under 1), so this is sure. It spares
/// the smallest-sphere search on most cells (step 7 checks every cell: 5-10 % of the dragon's
/// partition time without it).
const SURELY_CULLABLE_DOT: f64 = 0.01;

impl Cones<'_> {
    /// Unit normal of triangle `t`, `None` at zero area.
    fn normal(&self, t: u32) -> Option<DVec3> {
        let p = self
            .mesh
            .triangle(t as usize)
            .map(|v| DVec3::from(self.mesh.positions[v as usize].map(f64::from)));
        triangle_normal(&p)
    }

    /// The mean unit normal of cell `m` (zero where it has none).
    fn mean(&self, s: &Search, m: u32) -> DVec3 {
        s.cells.members[m as usize]
            .iter()
            .filter_map(|&t| self.normal(t))
            .sum::<DVec3>()
            .normalize_or_zero()
    }

    /// Whether cell `m`'s cone can cull. The exact test reads its normals in triangle order, so
    /// the answer does not depend on the order moves left the members in.
    fn culls(&self, s: &Search, m: u32) -> bool {
        let members = &s.cells.members[m as usize];
        let mean = self.mean(s, m);
        let sure = mean != DVec3::ZERO
            && members
                .iter()
                .filter_map(|&t| self.normal(t))
                .all(|n| n.dot(mean) > SURELY_CULLABLE_DOT);
        if sure {
            return true;
        }
        let mut tris = members.clone();
        tris.sort_unstable();
        let normals: Vec<DVec3> = tris.iter().filter_map(|&t| self.normal(t)).collect();
        cone_axis(&normals).is_some()
    }

    /// Whether cell `m` has a triangle of non-zero area (one without has nothing to fix).
    fn has_normals(&self, s: &Search, m: u32) -> bool {
        s.cells.members[m as usize]
            .iter()
            .any(|&t| self.normal(t).is_some())
    }
}

/// Step 7: every cell whose cone cannot cull hands boundary triangles to neighbours, those most
/// opposed to the cell's mean normal first, each to the neighbour whose mean normal is nearest
/// its own; within the limits, the cell staying one piece, never taking a neighbour's cone away.
/// At most a quarter of the cell moves, and a cell that does not become cullable is rolled back.
/// Returns the cells fixed.
fn cone_repair(s: &mut Search) -> usize {
    // Candidates tried per step: the most opposed triangles are usually inside the cell or on a
    // full neighbour's border, so a few more than one.
    const TRIES: usize = 8;
    let cones = Cones { mesh: s.cells.mesh };
    let mut fixed = 0;
    for m in 0..s.cells.tcount.len() as u32 {
        // Under 4 triangles the budget below is 0.
        if s.cells.tcount[m as usize] < 4 || !cones.has_normals(s, m) || cones.culls(s, m) {
            continue;
        }
        s.cells.journal = Some(Vec::new());
        let mut budget = s.cells.tcount[m as usize] / 4;
        while budget > 0 && !cones.culls(s, m) {
            budget -= 1;
            let axis = cones.mean(s, m);
            let mut worst: Vec<(f64, u32)> = s.cells.members[m as usize]
                .iter()
                .filter_map(|&t| cones.normal(t).map(|n| (n.dot(axis), t)))
                .collect();
            worst.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut moved = false;
            for &(_, t) in worst.iter().take(TRIES) {
                let (nb, n) = s.cells.neighbour_labels(t);
                let nt = cones.normal(t).expect("a normal");
                let mut to: Vec<(f64, u32)> = nb[..n]
                    .iter()
                    .map(|&b| (-nt.dot(cones.mean(s, b)), b))
                    .collect();
                to.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                for (_, b) in to {
                    let add = s.cells.added(t, b);
                    if !s.cells.fits(b, add) || !s.stays_connected(t) {
                        continue;
                    }
                    let had = cones.culls(s, b);
                    s.cells.apply(t, b);
                    if had && !cones.culls(s, b) {
                        // Out of the journal first: a rollback journals its own moves.
                        let mut j = s.cells.journal.take().expect("open journal");
                        let last = j.pop().expect("the move just made");
                        s.cells.rollback(&[last]);
                        s.cells.journal = Some(j);
                        continue;
                    }
                    moved = true;
                    break;
                }
                if moved {
                    break;
                }
            }
            if !moved {
                break;
            }
        }
        let journal = s.cells.journal.take().expect("open journal");
        if cones.culls(s, m) {
            fixed += 1;
        } else {
            s.cells.rollback(&journal);
        }
    }
    fixed
}

/// Step 6's exchanges: boundary triangle `t` goes from its cell `a` to a neighbour `b` where that
/// lowers the spread, and a triangle `u` of `b` next to `a` comes back, the pair kept when the
/// spread falls in all, both cells stay within the vertex limit and in one piece. Triangle counts
/// do not change, so this works where every cell is full (at 64/84 the cells hold 84 triangles
/// and single moves find no room). A work queue in triangle order revisits the triangles around
/// each exchange. Returns the exchanges made.
fn swaps(s: &mut Search) -> usize {
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

/// Step 2: balanced geodesic Lloyd from the current cells; the new label of every triangle.
fn lloyd(s: &Search, config: Config, dropped: usize) -> Vec<u32> {
    let p = &s.cells;
    let n = p.label.len();
    let k = p.tcount.len();
    // The features start with the centroid, scaled to unit spread: scale-free distances.
    let pos: Vec<DVec3> = p
        .features
        .iter()
        .map(|f| DVec3::new(f[0], f[1], f[2]))
        .collect();
    // Arcs (neighbour, centroid distance) once, in the dual graph's item order: the search reads
    // a triangle's neighbours and lengths from one cache line.
    let mut arcs = Vec::with_capacity(p.dual.items.len());
    for t in 0..n {
        for &u in p.dual.row(t) {
            arcs.push((u, pos[t].distance(pos[u as usize]) as f32));
        }
    }
    let h = arcs.iter().map(|a| a.1 as f64).sum::<f64>() / arcs.len().max(1) as f64;
    let mut label = p.label.clone();
    let mut weight = vec![0.0f64; k];
    let target = p.limits.max_vertices as f64 - 1.0;
    for it in 0..config.lloyd_iterations {
        // The weights start at 0 and follow the previous step's cells.
        if it > 0 {
            let vc = vertex_counts(p.vt, &label, k);
            for c in 0..k {
                weight[c] += config.balance_step * h * (vc[c] as f64 - target);
            }
        }
        let mut seeds = central_triangles(&pos, &label, k);
        if it == 0 {
            for m in p.emptiest_first().into_iter().take(dropped) {
                seeds[m as usize] = u32::MAX;
            }
        }
        label = voronoi(
            config.band * h,
            &p.dual.offsets,
            &arcs,
            &seeds,
            &weight,
            &label,
        );
    }
    label
}

/// Per cell, the member triangle nearest the cell's centroid (`u32::MAX` for an empty cell).
fn central_triangles(pos: &[DVec3], label: &[u32], k: usize) -> Vec<u32> {
    let mut sum = vec![(DVec3::ZERO, 0.0f64); k];
    for (t, &l) in label.iter().enumerate() {
        sum[l as usize].0 += pos[t];
        sum[l as usize].1 += 1.0;
    }
    let mut best = vec![(f64::MAX, u32::MAX); k];
    for (t, &l) in label.iter().enumerate() {
        let (s, c) = sum[l as usize];
        let d = pos[t].distance(s / c);
        if d < best[l as usize].0 {
            best[l as usize] = (d, t as u32);
        }
    }
    best.into_iter().map(|b| b.1).collect()
}

/// Multi-source Dijkstra over the dual graph (`offsets` into `arcs`: neighbour, length) from
/// `seeds`, each cell's distances offset by its weight. Triangles no seed reaches (a mesh piece
/// whose cells all emptied) keep `old`. `band` is the width of distance settled at once, in the
/// lengths' units ([`Config::band`] times the mean length).
fn voronoi(
    band: f64,
    offsets: &[u32],
    arcs: &[(u32, f32)],
    seeds: &[u32],
    weight: &[f64],
    old: &[u32],
) -> Vec<u32> {
    /// A triangle's search state in one cache line's quarter: the pops visit triangles all over
    /// the mesh (every cell grows at once), so each separate array read was a cache miss.
    #[derive(Clone, Copy)]
    struct Node {
        dist: f64,
        label: u32,
        settled: bool,
    }
    let n = old.len();
    // Offsets start at 0: the heap orders the distances' bit patterns, which only works for
    // non-negative floats.
    let low = weight.iter().copied().fold(f64::MAX, f64::min);
    let mut node = vec![
        Node {
            dist: f64::MAX,
            label: u32::MAX,
            settled: false,
        };
        n
    ];
    let mut heap = BinaryHeap::new();
    for (c, &t) in seeds.iter().enumerate() {
        if t == u32::MAX {
            continue;
        }
        let d = weight[c] - low;
        if d < node[t as usize].dist {
            node[t as usize] = Node {
                dist: d,
                label: c as u32,
                settled: false,
            };
            heap.push(Reverse((d.to_bits(), t, c as u32)));
        }
    }
    let mut batch: Vec<(u32, u64, u32)> = Vec::new();
    while let Some(Reverse((bits, t, c))) = heap.pop() {
        // One band of distances, settled in triangle order (then distance, then cell).
        batch.clear();
        batch.push((t, bits, c));
        let top = f64::from_bits(bits) + band;
        while let Some(&Reverse((next, t, c))) = heap.peek() {
            if f64::from_bits(next) > top {
                break;
            }
            heap.pop();
            batch.push((t, next, c));
        }
        batch.sort_unstable();
        for &(t, bits, c) in &batch {
            let d = f64::from_bits(bits);
            let here = &mut node[t as usize];
            if here.settled || d > here.dist {
                continue;
            }
            here.settled = true;
            here.label = c;
            let row = &arcs[offsets[t as usize] as usize..offsets[t as usize + 1] as usize];
            for &(u, len) in row {
                let nd = d + len as f64;
                let there = &mut node[u as usize];
                if !there.settled && nd < there.dist {
                    there.dist = nd;
                    heap.push(Reverse((nd.to_bits(), u, c)));
                }
            }
        }
    }
    node.iter()
        .zip(old)
        .map(|(x, &o)| if x.settled { x.label } else { o })
        .collect()
}

/// Meshlet adjacency lists, recomputed for a meshlet when it has changed since (its
/// `changed_at` stamp). A neighbour that changed alone can leave a list stale by a meshlet; a
/// stale entry only costs a hop that finds nothing to pass (and is then blocked), a missing one
/// a longer path. Recomputing every list per search cost half the run time on the shared meshes.
struct Adjacency {
    lists: Vec<(usize, Vec<u32>)>,
}

impl Adjacency {
    fn new(k: usize) -> Self {
        Self {
            lists: vec![(usize::MAX, Vec::new()); k],
        }
    }

    /// Forgets every list. Needed after a restore that follows a rollback: a rollback turns the
    /// move counter back, so a restore's fresh stamp can equal one a list was cached under on a
    /// partition since undone.
    fn forget(&mut self) {
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

/// Whether meshlet `m` is over a limit.
fn over(s: &Search, m: u32) -> bool {
    let p = &s.cells;
    p.vcount[m as usize] > p.limits.max_vertices || p.tcount[m as usize] > p.limits.max_triangles
}

/// How a repair (step 4) ended.
enum Repair {
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
fn repair(s: &mut Search, adj: &mut Adjacency, config: Config, stats: &mut Stats) -> Repair {
    let mut todo: Vec<u32> = (0..s.cells.tcount.len() as u32)
        .filter(|&m| over(s, m))
        .collect();
    // Passes after the first fix few cells (measured: 140 -> 128, 17 -> 5, 14 -> 10, 2 -> 1):
    // far more failures than the splits can take mean a failed re-partition, so stop paying.
    let most_failures = 4 * config.max_splits as usize;
    for _pass in 0..2 {
        let mut left = Vec::new();
        for &o in &todo {
            let mut blocked: Vec<(u32, u32)> = Vec::new();
            let mut chains = config.chains_per_meshlet;
            while over(s, o) && chains > 0 {
                chains -= 1;
                stats.chains += 1;
                let Some(path) = shortest_path_to_room(s, adj, o, &blocked) else {
                    break;
                };
                run_chain(s, &path, false, &mut blocked, stats);
            }
            if over(s, o) {
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
        while over(s, o) {
            let Some(z) = spare.pop_front() else { break };
            split(s, o, z);
            stats.splits += 1;
        }
        over(s, o)
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
        if !over(s, o) {
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

/// Step 5: empties the emptiest meshlets while victims go.
fn pack(s: &mut Search, adj: &mut Adjacency, config: Config, stats: &mut Stats) {
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

/// Passes one triangle (or fan) along every hop of `path` from the far end back; the first hop
/// that finds nothing to pass is blocked for the rest of this cell's turn.
fn run_chain(
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

/// Whether meshlet `m` can take a triangle that adds a vertex.
fn has_room(s: &Search, m: u32) -> bool {
    let p = &s.cells;
    p.tcount[m as usize] > 0
        && p.tcount[m as usize] < p.limits.max_triangles
        && p.vcount[m as usize] < p.limits.max_vertices
}

/// The shortest chain of edge-adjacent meshlets from `v` to one with room, avoiding `blocked`
/// hops: `[v, .., goal]`.
fn shortest_path_to_room(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::validate;
    use crate::strategy::{by_name, Options};

    fn build(name: &str, mesh: &Mesh, limits: Limits) -> Meshlets {
        by_name(name, &Options::default())
            .unwrap()
            .build(mesh, limits)
    }

    #[test]
    fn keeps_the_limits_and_never_adds_meshlets() {
        let meshes = [
            generate::noisy_sphere(4, 0.3, 7),
            generate::terrain(40, 5),
            generate::cad_part(128, 3),
        ];
        for mesh in &meshes {
            for limits in Limits::COUNT_PRESETS {
                for base in ["nvidia", "greedy", "meshopt"] {
                    let input = build(base, mesh, limits);
                    for lloyd_iterations in [0, 1, 3] {
                        let config = Config {
                            lloyd_iterations,
                            ..Config::default()
                        };
                        let (out, st) = partition_with_stats(mesh, &input, limits, config);
                        let what = format!("{base} {limits} lloyd {lloyd_iterations}");
                        validate(mesh, &out, limits).unwrap_or_else(|e| panic!("{what}: {e}"));
                        assert!(out.len() <= input.len(), "{what}");
                        assert_eq!(st.meshlets_after, out.len(), "{what}");
                        assert!(out.len() >= limits.min_meshlets(mesh.triangle_count()));
                    }
                }
            }
        }
    }

    #[test]
    fn a_poor_partition_loses_meshlets() {
        // The index-order scan leaves long, thin meshlets: the packing must empty some.
        let mesh = generate::noisy_sphere(4, 0.1, 3);
        let input = build("nvidia", &mesh, Limits::DEFAULT);
        let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, Config::default());
        assert!(out.len() < input.len(), "{} -> {}", input.len(), out.len());
        assert!(st.dissolved > 0 && st.chains > 0 && st.hops > 0, "{st:?}");
        assert!(st.vertices_after < st.vertices_before, "{st:?}");
    }

    #[test]
    fn the_repartition_is_kept_or_undone_whole() {
        // Either way the output validates; on a smooth sphere the repair succeeds.
        let mesh = generate::noisy_sphere(5, 0.0, 1);
        let input = build("meshopt", &mesh, Limits::DEFAULT);
        let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, Config::default());
        validate(&mesh, &out, Limits::DEFAULT).unwrap();
        assert!(st.overfull > 0 && st.repartitioned, "{st:?}");
        // No chains at all: a cell over the limits cannot be repaired, so the input is kept.
        let none = Config {
            chains_per_meshlet: 0,
            ..Config::default()
        };
        let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, none);
        validate(&mesh, &out, Limits::DEFAULT).unwrap();
        assert!(!st.repartitioned, "{st:?}");
    }

    #[test]
    fn exchanges_round_off_full_cells() {
        // At 64/84 the cells fill up with triangles, and only exchanges can reshape them.
        let limits = Limits::COUNT_PRESETS[1];
        let mesh = generate::cad_part(128, 3);
        let input = build("meshopt", &mesh, limits);
        // Step 7 moves triangles one way: off here, so the exchanges alone make the difference.
        let plain = Config {
            cone_repair: false,
            swaps: false,
            ..Config::default()
        };
        let with = Config {
            swaps: true,
            ..plain
        };
        let (a, _) = partition_with_stats(&mesh, &input, limits, plain);
        let (b, st) = partition_with_stats(&mesh, &input, limits, with);
        validate(&mesh, &b, limits).unwrap();
        assert!(st.swaps > 0, "{st:?}");
        // Triangle counts per meshlet are the same, as a multiset.
        let counts = |ml: &Meshlets| {
            let mut c: Vec<usize> = (0..ml.len())
                .map(|i| ml.meshlet_triangles(i).len())
                .collect();
            c.sort_unstable();
            c
        };
        assert_eq!(counts(&a), counts(&b));
        let radius = |ml: &Meshlets| {
            let bounds = crate::meshlet::bounds::compute_bounds(&mesh, ml);
            bounds.iter().map(|x| x.sphere.radius as f64).sum::<f64>()
        };
        assert!(radius(&b) < radius(&a), "{} >= {}", radius(&b), radius(&a));
        let pieces = |ml: &Meshlets| {
            (0..ml.len())
                .filter(|&i| !crate::meshlet::metrics::is_edge_connected(ml.meshlet_triangles(i)))
                .count()
        };
        assert!(pieces(&b) <= pieces(&a));
    }

    #[test]
    fn an_input_at_the_hard_bound_is_returned_as_it_is() {
        // 128/128 on a terrain: meshoptimizer sits at ceil(T / 128), and the moves would only
        // reshape its meshlets.
        let mesh = generate::terrain(40, 5);
        let limits = Limits::new(128, 128).unwrap();
        let input = build("meshopt", &mesh, limits);
        assert_eq!(input.len(), limits.min_meshlets(mesh.triangle_count()));
        let (out, st) = partition_with_stats(&mesh, &input, limits, Config::default());
        assert_eq!(out, input);
        assert_eq!((st.chains, st.repartitioned), (0, false), "{st:?}");
    }

    #[test]
    fn the_banded_and_exact_dijkstra_both_hold_the_limits() {
        // The band only reorders the settling; the round-off only moves within the limits.
        let mesh = generate::noisy_sphere(5, 0.1, 2);
        let input = build("meshopt", &mesh, Limits::DEFAULT);
        for band in [0.0, 0.5, 4.0] {
            for round_off in [false, true] {
                let config = Config {
                    band,
                    round_off,
                    ..Config::default()
                };
                let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, config);
                validate(&mesh, &out, Limits::DEFAULT).unwrap();
                assert!(out.len() <= input.len(), "band {band}");
                assert!(st.overfull > 0, "band {band}: the Lloyd step ran: {st:?}");
            }
        }
    }

    #[test]
    fn splits_and_dropped_seeds_keep_the_limits() {
        let mesh = generate::noisy_sphere(5, 0.1, 2);
        let input = build("meshopt", &mesh, Limits::DEFAULT);
        // No chains: every over-full cell is split, and the split re-partition, packed, is
        // weighed against the packed fallback.
        let split_all = Config {
            chains_per_meshlet: 0,
            max_splits: 100_000,
            ..Config::default()
        };
        // Many seeds dropped: the repair has to fill the gaps, or the next drop is tried (unless
        // the repair needed splits or stopped early).
        let drop_many = Config {
            drops: &[0.05, 0.01, 0.0],
            ..Config::default()
        };
        for config in [split_all, drop_many] {
            let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, config);
            validate(&mesh, &out, Limits::DEFAULT).unwrap();
            assert!(out.len() <= input.len(), "{st:?}");
            assert_eq!(out.len(), st.meshlets_after);
        }
        let (_, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, split_all);
        assert!(st.splits > 0, "{st:?}");
    }

    #[test]
    fn a_small_input_drops_at_least_one_seed() {
        // cad-part-400 at 64/126: meshoptimizer's 112 meshlets, where 0.3 % of the seeds rounds
        // to none. One dropped seed packs to fewer meshlets than keeping every seed.
        let mesh = generate::named("cad-part-400").unwrap();
        let input = build("meshopt", &mesh, Limits::DEFAULT);
        let share = Config::default().drops[0];
        assert!(
            (share * input.len() as f64).round() < 1.0,
            "{}",
            input.len()
        );
        let every_seed = Config {
            drops: &[0.0],
            ..Config::default()
        };
        let kept = partition(&mesh, &input, Limits::DEFAULT, every_seed);
        let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, Config::default());
        validate(&mesh, &out, Limits::DEFAULT).unwrap();
        assert!(st.repartitioned, "{st:?}");
        assert!(
            out.len() < kept.len(),
            "{} against {}",
            out.len(),
            kept.len()
        );
    }

    #[test]
    fn a_repair_that_stops_early_ends_the_attempts() {
        let mesh = generate::noisy_sphere(5, 0.1, 2);
        let input = build("meshopt", &mesh, Limits::DEFAULT);
        // No chains and no splits: the first cell left over a limit stops the repair, and the
        // drops after the first are not tried.
        let hopeless = Config {
            chains_per_meshlet: 0,
            max_splits: 0,
            drops: &[0.05, 0.01, 0.0],
            ..Config::default()
        };
        let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, hopeless);
        assert!(st.overfull > 0, "{st:?}");
        assert_eq!(st.attempts, 1, "{st:?}");
        assert!(!st.repartitioned, "{st:?}");
        validate(&mesh, &out, Limits::DEFAULT).unwrap();
        assert!(out.len() <= input.len());
    }

    #[test]
    fn a_repair_with_splits_ends_the_attempts() {
        let mesh = generate::noisy_sphere(5, 0.1, 2);
        let input = build("meshopt", &mesh, Limits::DEFAULT);
        // No chains: every over-full cell is split, so the first attempt is repaired with splits
        // and packed; the drops after it are not tried.
        let split_all = Config {
            chains_per_meshlet: 0,
            max_splits: 100_000,
            drops: &[0.05, 0.01, 0.0],
            ..Config::default()
        };
        let (out, st) = partition_with_stats(&mesh, &input, Limits::DEFAULT, split_all);
        assert!(st.splits > 0, "{st:?}");
        assert_eq!(st.attempts, 1, "{st:?}");
        validate(&mesh, &out, Limits::DEFAULT).unwrap();
        assert!(out.len() <= input.len());
    }

    #[test]
    fn names_select_the_base_strategy() {
        assert_eq!(
            by_name("partition", &Options::default()).unwrap().name(),
            "partition"
        );
        for base in crate::strategy::NAMES.iter().filter(|&&n| n != "partition") {
            let name = format!("{base}+partition");
            assert_eq!(by_name(&name, &Options::default()).unwrap().name(), name);
        }
        assert!(by_name("partition+partition", &Options::default()).is_err());
        let mesh = generate::terrain(30, 2);
        assert_eq!(
            build("meshopt+partition", &mesh, Limits::DEFAULT),
            build("partition", &mesh, Limits::DEFAULT)
        );
        assert!(by_name("nope+partition", &Options::default()).is_err());
    }
}
