//! `+refine`: a local search over any strategy's meshlets that removes meshlets.
//!
//! The objective, in order: the meshlet count, the total number of meshlet vertices (a boundary
//! vertex is stored once per meshlet that uses it, so duplicates eat the 64-vertex capacity), and
//! the spread of triangle features around their meshlet's mean: the centroid (a stand-in for the
//! bounding radius that one move can update exactly) and, weighted lower, the normal (for
//! cone culling). Background: a disc-shaped patch with V vertices, B of them on its boundary,
//! holds 2V - B - 2 triangles, so at a vertex limit only shorter boundaries make room
//! (`docs/meshlet-count-bound.md`; the bounds are in results/strategies.md).
//!
//! The state, the cells (a meshlet label per triangle, counts per meshlet, a move journal; how
//! often a meshlet uses a vertex is counted on the fly from the vertex -> triangle rows), is kept
//! apart from the scratch buffers of its queries (`state.rs`). These steps edit it:
//! 1. **Boundary moves** (`moves.rs`; Fiduccia–Mattheyses gains, without FM's negative-gain
//!    passes): a triangle on a meshlet boundary moves to an edge-adjacent meshlet when that lowers
//!    the vertex total, or keeps it and lowers the spread (Hartigan's exact k-means gain), so the
//!    lexicographic objective strictly falls and the search ends. A work queue revisits only
//!    triangles whose gains changed.
//! 2. **Rounder meshlets** ([`Config::spread`], `moves.rs`): the same moves with the spread ranked
//!    first, then step 1 again; k-means-like rounding opens moves that step 1 alone never sees.
//! 3. **Neighbourhood rebuilds** ([`Config::rebuild`], `rebuild.rs`; large-neighbourhood search):
//!    every meshlet with its edge neighbours is rebuilt from scratch by meshoptimizer on that
//!    sub-mesh; a rebuild is kept when it has fewer meshlets, or as many with fewer vertex
//!    references, and no more meshlets in pieces.
//! 4. **Dissolving** the emptiest meshlets (`dissolve.rs`): every triangle of a victim goes to an
//!    edge-adjacent meshlet with room, cheapest (fewest new vertices) first; when none has room,
//!    an augmenting path (a breadth-first search over meshlets, each hop passing one boundary
//!    triangle on) ends at a meshlet with room. A victim that cannot be emptied is rolled back
//!    from the move journal.
//! 5. **Annealing** ([`Config::anneal_steps`], `anneal.rs`; the full effort per victim, the max
//!    effort also globally first): simulated annealing over the same moves. Max first anneals the
//!    whole mesh to shorten boundaries (a cold anneal then drives out any overflow the hot one
//!    left, or the input's boundaries come back). Then meshlets are removed one at a time,
//!    emptiest first: the victim's triangles are handed to their neighbours regardless of the
//!    limits, and an anneal confined to the meshlets within a few edge-adjacency rings of it must
//!    drive the overflow (vertices and triangles over the limits, weighted [`OVERFLOW_WEIGHT`])
//!    back to zero within its budget, or the hand-over is undone. Boundary moves alone cannot move
//!    vertex capacity far (a vertex freed on one side of a meshlet does not help the other);
//!    annealing's uphill moves can, and a few meshlets around the victim hold enough of it.
//!
//! The driver ([`refine_with_stats`]) runs step 1, the global anneal, then up to
//! [`Config::rounds`] rounds of steps 2 to 5, and step 2 once more at the end.
//!
//! [`partition`] is a second strategy on the same cells and boundary moves (a global re-partition
//! packed along ejection chains); it lives here because it is built on these internals.
//!
//! Invariants: the limits hold whenever a step ends (a move is only made when it fits, annealing
//! is undone unless it ends without overflow), no boundary move splits its source meshlet into
//! more edge-connected pieces (a rebuild never ends with more meshlets in pieces), and everything
//! runs in a fixed order on one thread with a seeded generator, so the output does not depend on
//! the thread count or the run.
//!
//! Where we differ from textbook FM/KL: no balance constraint (the limits are the capacity), no
//! negative-gain passes in step 1 (annealing plays that role), and no pair swaps (a swap is two
//! moves, which annealing makes).

mod anneal;
mod dissolve;
mod moves;
pub mod partition;
mod rebuild;
mod state;

use super::Strategy;
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use moves::Rank;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use state::{labels_of, Search};

/// Weight of one unit of overflow (a vertex or triangle over a limit) against one vertex reference
/// in the annealer's energy: above 1, so that shedding overflow always pays, low enough that
/// overflow can still travel through meshlets at a moderate temperature (3 was measured best of
/// 1, 2, 3, 5 on the bunny).
pub const OVERFLOW_WEIGHT: f64 = 3.0;

/// [`Config::search_work`] of the fast effort, in triangles looked at per mesh triangle.
const SEARCH_WORK_FAST: u64 = 100;

/// [`Config::search_work`] of the full and max efforts.
const SEARCH_WORK_FULL: u64 = 200;

/// How hard `+refine` searches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Effort {
    /// One round of boundary moves and dissolving, without rebuilds or annealing. Measured on the
    /// bunny from meshoptimizer's meshlets: about its build time at 64/126 (0.04-0.08 s), but
    /// 0.8-1.1 s at 64/84, where every dissolving search fails and the round spends its whole
    /// `search_work`; from `nvidia`'s poor meshlets 0.5-0.7 s (2284 -> 845 meshlets).
    Fast,
    /// Rounds of rounder-meshlet moves, neighbourhood rebuilds, dissolving and a light anneal per
    /// victim (0.05 to 36 s on the shared meshes at 64/126: `results/build.md`).
    #[default]
    Full,
    /// Full with a global anneal first and a larger budget per victim (seconds per 10 k
    /// triangles; the fewest meshlets).
    Max,
}

impl std::str::FromStr for Effort {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "fast" => Ok(Effort::Fast),
            "full" => Ok(Effort::Full),
            "max" => Ok(Effort::Max),
            _ => Err(format!("refine effort '{s}' is not one of fast, full, max")),
        }
    }
}

/// Search settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Rounds of (rounder-meshlet moves, neighbourhood rebuilds, dissolving, annealing); a round
    /// that removes no meshlet ends the search early.
    pub rounds: u32,
    /// Step 2: alternate spread-first and vertex-first boundary moves at the start of each round.
    pub spread: bool,
    /// Step 3: rebuild every meshlet's neighbourhood with meshoptimizer.
    pub rebuild: bool,
    /// Step 4: most meshlets one augmenting-path search visits (0 = direct hand-overs only).
    pub search_nodes: usize,
    /// Step 4: per triangle of the mesh, how many triangles all augmenting-path searches of one
    /// dissolving pass may look at; no new victim is tried beyond it. Keeps the cost linear
    /// where most victims are hopeless (a triangle-bound preset with little spare room).
    pub search_work: u64,
    /// Step 5: annealing proposals per triangle of the annealed region for each attempt (0 = no
    /// annealing).
    pub anneal_steps: u32,
    /// Step 5: victims in a row that may fail before a round's annealing ends.
    pub anneal_failures: u32,
    /// Step 5: first anneal the whole mesh once for shorter boundaries (`anneal_steps` per
    /// triangle), the capacity the victims' anneals live on.
    pub global_anneal: bool,
    /// Seed of the annealer's generator.
    pub seed: u64,
}

impl Config {
    /// The settings of an effort level.
    pub fn new(effort: Effort) -> Self {
        match effort {
            Effort::Fast => Self {
                rounds: 1,
                spread: false,
                rebuild: false,
                search_nodes: 256,
                search_work: SEARCH_WORK_FAST,
                anneal_steps: 0,
                anneal_failures: 0,
                global_anneal: false,
                seed: 1,
            },
            Effort::Full => Self {
                rounds: 3,
                spread: true,
                rebuild: true,
                search_nodes: 1024,
                search_work: SEARCH_WORK_FULL,
                // A light anneal per victim: on the bunny it takes k-medoids' output from 754
                // meshlets (no annealing) to 721 and meshoptimizer's from 720 to 718, in 2-3 s;
                // 4 failures in a row end it, as later victims rarely go.
                anneal_steps: 200,
                anneal_failures: 4,
                global_anneal: false,
                seed: 1,
            },
            // 430 proposals per triangle: more per victim goes further (bunny, after the global
            // anneal: 200 -> 716, 430 -> 710-712 meshlets); 16 failures in a row, since a failed
            // victim costs only its neighbourhood.
            Effort::Max => Self {
                anneal_steps: 430,
                anneal_failures: 16,
                global_anneal: true,
                ..Self::new(Effort::Full)
            },
        }
    }
}

impl Default for Config {
    fn default() -> Self {
        Self::new(Effort::default())
    }
}

/// Any strategy followed by the refinement.
pub struct Refined {
    /// The strategy whose output is refined.
    pub inner: Box<dyn Strategy>,
    /// Search settings.
    pub config: Config,
    /// The name it was selected by, e.g. `meshopt+refine`.
    pub name: &'static str,
}

impl Strategy for Refined {
    fn name(&self) -> &'static str {
        self.name
    }
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let ml = self.inner.build(mesh, limits);
        refine(mesh, &ml, limits, self.config)
    }
}

/// What a refinement did, for reports.
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
    /// Moves made, counting ones later undone.
    pub moves: usize,
    /// Meshlets dissolved.
    pub dissolved: usize,
    /// Dissolve attempts rolled back.
    pub failed: usize,
    /// Triangles the augmenting-path searches looked at (what [`Config::search_work`] caps).
    pub search_work: u64,
}

/// Refines `ml` (any valid partition of `mesh` within `limits`); the result is valid for the same
/// limits and has at most as many meshlets.
///
/// # Panics
/// When `ml` does not hold every triangle of `mesh` exactly once (check it with
/// [`crate::meshlet::validate`] first when it comes from outside).
pub fn refine(mesh: &Mesh, ml: &Meshlets, limits: Limits, config: Config) -> Meshlets {
    refine_with_stats(mesh, ml, limits, config).0
}

/// [`refine`], also returning what it did.
pub fn refine_with_stats(
    mesh: &Mesh,
    ml: &Meshlets,
    limits: Limits,
    config: Config,
) -> (Meshlets, Stats) {
    let vt = vertex_triangles(mesh);
    let (labels, seq) = labels_of(mesh, &vt, ml);
    let dual = dual_graph(mesh, &vt);
    let mut s = Search::new(mesh, &vt, &dual, labels, ml.len(), limits);
    let mut stats = Stats {
        meshlets_before: ml.len(),
        vertices_before: s.cells.vcount.iter().map(|&v| v as usize).sum(),
        ..Stats::default()
    };
    let all: Vec<u32> = (0..mesh.triangle_count() as u32).collect();
    let mut rng = XorShiftRng::seed_from_u64(config.seed);
    let steps = config.anneal_steps as u64 * mesh.triangle_count() as u64;
    // No partition has fewer meshlets than this: at it, only the cheap vertex-total and
    // roundness passes can still help, so the count-removing stages are skipped.
    let floor = limits.min_meshlets(mesh.triangle_count());
    s.improve(&all, Rank::Vertices);
    if config.global_anneal && steps > 0 && s.cells.live > floor {
        // Shorter boundaries first: the capacity the batches below live on. Its uphill moves may
        // end with a meshlet over a limit, which the output would have to split; a cold anneal
        // drives that overflow out, and when it cannot, the boundaries go back to the input's.
        let snapshot = s.cells.label.clone();
        let scale = s.cells.spread_scale();
        let feasible = s.anneal(None, steps, ((1.0, 0.05), scale), &mut rng, false)
            || s.anneal(None, steps, ((0.05, 0.01), scale), &mut rng, true);
        if !feasible {
            s.cells.restore(&snapshot);
        }
        s.improve(&all, Rank::Vertices);
    }
    for _ in 0..config.rounds {
        if s.cells.live <= floor {
            break;
        }
        let before = s.cells.live;
        if config.spread {
            s.round_off(&all);
        }
        if config.rebuild {
            s.rebuild_all(&mut stats);
            s.improve(&all, Rank::Vertices);
        }
        let budget = config.search_work * mesh.triangle_count() as u64;
        s.dissolve_all(config.search_nodes, budget, &mut stats);
        if steps > 0 {
            s.anneal_dissolve(
                config.anneal_steps as u64,
                config.anneal_failures,
                &mut rng,
                &mut stats,
            );
        }
        if s.cells.live == before {
            break;
        }
    }
    if config.spread {
        s.round_off(&all);
    }
    stats.moves = s.cells.moves;
    let live = s.cells.live;
    let out = s.cells.into_meshlets(&seq);
    // Every step ends within the limits, so no meshlet is split on the way out.
    debug_assert_eq!(out.len(), live, "a refined meshlet broke a limit");
    stats.meshlets_after = out.len();
    stats.vertices_after = out.vertices.len();
    (out, stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::{metrics::is_edge_connected, validate};
    use crate::strategy::{by_name, Options};

    fn build(name: &str, mesh: &Mesh, limits: Limits) -> Meshlets {
        by_name(name, &Options::default())
            .unwrap()
            .build(mesh, limits)
    }

    fn pieces(ml: &Meshlets) -> usize {
        (0..ml.len())
            .filter(|&i| !is_edge_connected(ml.meshlet_triangles(i)))
            .count()
    }

    #[test]
    fn every_effort_keeps_the_limits_and_never_adds_meshlets_or_pieces() {
        let mesh = generate::noisy_sphere(4, 0.3, 7);
        for limits in [
            Limits::DEFAULT,
            Limits::new(64, 84).unwrap(),
            Limits::new(128, 128).unwrap(),
        ] {
            for base in ["nvidia", "greedy", "kmedoids", "meshopt"] {
                let input = build(base, &mesh, limits);
                for effort in [Effort::Fast, Effort::Full, Effort::Max] {
                    let (out, st) = refine_with_stats(&mesh, &input, limits, Config::new(effort));
                    validate(&mesh, &out, limits)
                        .unwrap_or_else(|e| panic!("{base} {effort:?} {limits}: {e}"));
                    assert!(out.len() <= input.len(), "{base} {effort:?} {limits}");
                    assert!(pieces(&out) <= pieces(&input), "{base} {effort:?} {limits}");
                    assert_eq!(st.meshlets_after, out.len());
                }
            }
        }
    }

    #[test]
    fn a_poor_partition_loses_meshlets_and_vertex_references() {
        // The index-order scan leaves long, thin meshlets: refinement must pack them tighter.
        let mesh = generate::noisy_sphere(4, 0.1, 3);
        let input = build("nvidia", &mesh, Limits::DEFAULT);
        let (out, st) = refine_with_stats(&mesh, &input, Limits::DEFAULT, Config::default());
        assert!(
            out.len() * 10 < input.len() * 9,
            "{} -> {}",
            input.len(),
            out.len()
        );
        assert!(st.vertices_after < st.vertices_before);
        assert!(st.dissolved > 0);
    }

    #[test]
    fn refined_names_select_the_effort_and_keep_their_name() {
        for (suffix, effort) in crate::strategy::REFINE_SUFFIXES {
            for base in crate::strategy::NAMES {
                let name = format!("{base}{suffix}");
                assert_eq!(by_name(&name, &Options::default()).unwrap().name(), name);
                let (b, e, full) = crate::strategy::refined(&name).unwrap();
                assert_eq!((b, e, full), (*base, effort, name.as_str()), "{name}");
            }
        }
        assert!(by_name("meshopt+refined", &Options::default()).is_err());
        assert!(by_name("nope+refine", &Options::default()).is_err());
    }

    #[test]
    fn annealing_is_deterministic_for_a_seed() {
        let mesh = generate::terrain(40, 5);
        let input = build("meshopt", &mesh, Limits::DEFAULT);
        let c = Config::new(Effort::Max);
        let a = refine(&mesh, &input, Limits::DEFAULT, c);
        assert_eq!(a, refine(&mesh, &input, Limits::DEFAULT, c));
        let b = refine(&mesh, &input, Limits::DEFAULT, Config { seed: 2, ..c });
        validate(&mesh, &b, Limits::DEFAULT).unwrap();
    }
}
