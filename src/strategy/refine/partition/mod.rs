//! `partition`: fewer meshlets by re-partitioning the whole mesh at a fixed count and packing the
//! result with ejection chains over the meshlet graph.
//!
//! Background (`docs/meshlet-count-bound.md`): at a vertex limit a disc-shaped patch with V
//! vertices, B of them on its boundary, holds 2V - B - 2 triangles, so only shorter boundaries
//! make room. meshoptimizer's greedy growth leaves meshlets whose boundaries are longer than a
//! hexagon's, because each meshlet grows into the ragged space its predecessors left. A global
//! partition places all cells at once.
//!
//! The steps, on the cells of `+refine` (`refine::state`: labels, counts, move journal), each in
//! its own file; this one holds the driver ([`partition_with_stats`]) and its settings:
//! 1. **Start**: the input strategy's meshlets (meshoptimizer's for `partition`), then the
//!    vertex-gain boundary moves of `+refine` step 1. This state is kept as the fallback.
//! 2. **Global re-partition** (`lloyd.rs`, [`Config::lloyd_iterations`]): balanced geodesic Lloyd
//!    over the dual graph at the same count or a little below it (the drops below). Seeds are the
//!    triangles nearest each cell's centroid; a multi-source Dijkstra over centroid distances
//!    assigns every triangle; each cell's distance carries an additive weight that grows with its
//!    vertex count over the limit ([`Config::balance_step`]), so cells head for equal vertex
//!    counts (a power diagram on the surface). [`Config::drops`]: the first attempt leaves out the
//!    seeds of the emptiest 0.3 % of the cells (at least one, which small inputs need, where
//!    0.3 % rounds to none), so the repair and packing start from fewer cells and end with fewer
//!    meshlets than with every seed (measured in results/strategies.md (`meshletlab bench
//!    build`); more than 0.3 %, see [`Config::default`]). Further entries are further attempts,
//!    tried only when the repair fails even with splits; a repair that succeeds (with or without
//!    splits) or stops early ends the attempts (measured on the shared and stress meshes: after an
//!    early stop the attempt with every seed stopped early too, and after a repair with splits it
//!    packed to no fewer meshlets). The default's second attempt, with every seed, seldom runs on
//!    the shared meshes and was not kept where it did, but a smooth sphere keeps it, so it stays.
//!    The Dijkstra settles one band of distances at a time ([`Config::band`]) in triangle order:
//!    its pops otherwise jump across the whole mesh, and the cache misses cost a large share of
//!    meshoptimizer's whole build.
//! 3. **Boundary moves without the limits** (here): the same vertex-gain moves with the limits
//!    lifted, which shortens the Voronoi cells' ragged boundaries. Cells may now be over the
//!    vertex limit.
//! 4. **Repair** (`repair.rs`, with the ejection chains of `chains.rs`): every cell over a limit
//!    sheds triangles along an ejection chain: the shortest path in the meshlet adjacency graph to
//!    a cell with room, one boundary triangle (or a small fan) passed per hop, executed from the
//!    far end back so that every hop is a move within the limits of its receiver. The few cells no
//!    chain repairs within [`Config::chains_per_meshlet`] are split ([`Config::max_splits`]); a
//!    re-partition that needed splits is packed (step 5) and kept only when it then beats the
//!    packed fallback. Too many unrepaired cells end the attempt early, fall back to step 1's
//!    state and end the attempts.
//! 5. **Packing** (`pack.rs`): the emptiest cells are emptied one at a time, every triangle handed
//!    to a neighbour with room or, when none has any, through an ejection chain as in step 4; a
//!    victim that cannot be emptied is rolled back from the journal. [`Config::max_failures`]
//!    failures in a row end it.
//! 6. **Round-off** ([`Config::round_off`]): `+refine`'s spread-first boundary moves at the final
//!    count, within the limits: rounder meshlets and tighter normal cones (mean radius against
//!    meshoptimizer's: measured in results/strategies.md (`meshletlab bench build`)). Where the
//!    triangle limit binds (64/84, 128/128) every cell is full and no single move fits, so
//!    exchanges follow (`exchanges.rs`, [`Config::swaps`]): a boundary triangle moves to a full
//!    neighbour and one of the neighbour's comes back, where that lowers the spread. They keep the
//!    counts and lower the mean radius where cells are full, at some extra partition time; at
//!    64/126 few cells are full (duplicated triangles, thin tubes), so few exchanges run there.
//! 7. **Cones** (`cones.rs`, [`Config::cone_repair`]): a cell whose normals spread over (almost) a
//!    half-space has no backface cone (`meshlet::bounds::cone_axis`, the bounds' own test). It
//!    hands the boundary triangles most opposed to its mean normal to neighbours, never taking a
//!    neighbour's cone away, a quarter of the cell at most, and is rolled back unless it ends
//!    cullable. This leaves fewer non-cullable meshlets, at a cost that grows with the number of
//!    cells to repair (non-cullable meshlets against meshoptimizer's: measured in
//!    results/strategies.md (`meshletlab bench build`)).
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

mod chains;
mod cones;
mod exchanges;
mod lloyd;
mod pack;
mod repair;

use super::moves::Rank;
use super::state::{labels_of, Search};
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::Strategy;
use chains::Adjacency;
use cones::cone_repair;
use exchanges::swaps;
use lloyd::lloyd;
use pack::pack;
use repair::{over_limit, repair, Repair};

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
    /// Measured on the shared meshes at 64/126: one Lloyd iteration removed as many meshlets as
    /// two or six and is the cheapest; 64 chains per over-full cell repaired meshes where 16
    /// failed; 2 chains per victim triangle removed as many as 4, in less time; a 4th to 8th
    /// failed victim in a row never went. A band of half an edge gave the exact order's counts
    /// and about halved the Lloyd step. Dropping 0.3 % of the seeds first: see the module doc;
    /// 0.6 % and 1 % removed more on some meshes but failed on others, where each failed attempt
    /// costs about as much as meshoptimizer's whole build.
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
        .filter(|&m| over_limit(s, m))
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
