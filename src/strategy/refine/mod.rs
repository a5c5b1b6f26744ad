//! `+refine`: a local search over any strategy's meshlets that removes meshlets.
//!
//! The objective, in order: the meshlet count, the total number of meshlet vertices (a boundary
//! vertex is stored once per meshlet that uses it, so duplicates eat the 64-vertex capacity), and
//! the spread of triangle centroids around their meshlet's centroid (a stand-in for the bounding
//! radius that one move can update exactly). Background: a disc-shaped patch with V vertices, B of
//! them on its boundary, holds 2V - B - 2 triangles, so at a vertex limit only shorter boundaries
//! make room (`../shared/notes/meshlet-count-bound.md`; the bounds are in results/strategies.md).
//!
//! One flat state (a meshlet label per triangle, counts per meshlet; how often a meshlet uses a
//! vertex is counted on the fly from the vertex -> triangle rows) and these steps:
//! 1. **Boundary moves** (Fiduccia–Mattheyses gains, without FM's negative-gain passes): a triangle
//!    on a meshlet boundary moves to an edge-adjacent meshlet when that lowers the vertex total, or
//!    keeps it and lowers the spread (Hartigan's exact k-means gain), so the lexicographic objective
//!    strictly falls and the search ends. A work queue revisits only triangles whose gains changed.
//! 2. **Rounder meshlets** (`spread`): the same moves with the spread ranked first, then step 1
//!    again; k-means-like rounding opens moves that step 1 alone never sees.
//! 3. **Neighbourhood rebuilds** (`rebuild`, large-neighbourhood search): every meshlet with its
//!    edge neighbours is rebuilt from scratch by meshoptimizer on that sub-mesh; a rebuild is kept
//!    when it has fewer meshlets, or as many with fewer vertex references.
//! 4. **Dissolving** the emptiest meshlets: every triangle of a victim goes to an edge-adjacent
//!    meshlet with room, cheapest (fewest new vertices) first; when none has room, an augmenting
//!    path (a breadth-first search over meshlets, each hop passing one boundary triangle on) ends
//!    at a meshlet with room. A victim that cannot be emptied is rolled back from a move journal.
//! 5. **Annealing** (`anneal_steps`; the full effort per victim, the max effort also globally
//!    first): simulated annealing over the same moves. Max first anneals the whole mesh to shorten
//!    boundaries (a cold anneal then drives out any overflow the hot one left, or the input's
//!    boundaries come back). Then meshlets are removed one at a time, emptiest first: the victim's
//!    triangles are handed to their neighbours regardless of the limits, and an anneal confined to
//!    the meshlets within `ANNEAL_RINGS` of it must drive the overflow (vertices and triangles over
//!    the limits, weighted [`OVERFLOW_WEIGHT`]) back to zero within its budget, or the hand-over is
//!    undone. Boundary moves alone cannot move vertex capacity far (a vertex freed on one side of a
//!    meshlet does not help the other); annealing's uphill moves can, and a few meshlets around the
//!    victim hold enough of it.
//!
//! Invariants: the limits hold whenever a step ends (a move is only made when it fits, annealing
//! is undone unless it ends without overflow), no move splits its source meshlet into more
//! edge-connected pieces, and everything runs in a fixed order on one thread with a seeded
//! generator, so the output does not depend on the thread count or the run.
//!
//! Where we differ from textbook FM/KL: no balance constraint (the limits are the capacity), no
//! negative-gain passes in step 1 (annealing plays that role), and no pair swaps (a swap is two
//! moves, which annealing makes).

use super::parallel::distinct;
use super::Strategy;
use crate::adjacency::{dual_graph, vertex_triangles, Csr};
use crate::mesh::Mesh;
use crate::meshlet::{canonical, Limits, MeshletBuilder, Meshlets};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use std::collections::VecDeque;

/// Weight of one unit of overflow (a vertex or triangle over a limit) against one vertex reference
/// in the annealer's energy: above 1, so that shedding overflow always pays, low enough that
/// overflow can still travel through meshlets at a moderate temperature (3 was measured best of
/// 1, 2, 3, 5 on the bunny).
pub const OVERFLOW_WEIGHT: f64 = 3.0;

/// Weight of the spread change in the annealer's energy: keeps annealed meshlets as round as the
/// input (at 0 the mean radius grew 3 % on the bunny).
const SPREAD_WEIGHT: f64 = 0.25;

/// Per-triangle features whose spread (sum of squared distances to the meshlet mean) is the third
/// objective: the centroid, scaled to unit RMS spread in the input, and the unit normal.
const F: usize = 6;

/// Weight of the normal against the scaled centroid in the spread: tight normal cones keep
/// meshlets cone-cullable. Measured on the bunny with `+refine-max`: 0 lost 0.3 % of the
/// cullable meshlets, 0.3 keeps meshoptimizer's share, 1.0 keeps every meshlet cullable but
/// blocks every dissolve.
const NORMAL_WEIGHT: f64 = 0.3;

/// [`Config::search_work`] of the fast effort, in triangles looked at per mesh triangle.
const SEARCH_WORK_FAST: u64 = 100;

/// [`Config::search_work`] of the full and max efforts.
const SEARCH_WORK_FULL: u64 = 200;

/// Step 5 anneals only the meshlets within this many edge-adjacency hops of the victim (about 45
/// meshlets): on the bunny 2 rings dissolved 3 meshlets, 3 rings 6 to 9, 4 rings 10, 5 rings 10
/// at more cost; capacity has to come from a few meshlets away.
const ANNEAL_RINGS: usize = 4;

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
    fn summary(&self) -> &'static str {
        "any strategy, then boundary moves and dissolving the emptiest meshlets (fewer meshlets)"
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
    let mut s = State::new(mesh, &vt, &dual, labels, ml.len(), limits);
    let mut stats = Stats {
        meshlets_before: ml.len(),
        vertices_before: s.vcount.iter().map(|&v| v as usize).sum(),
        ..Stats::default()
    };
    let all: Vec<u32> = (0..mesh.triangle_count() as u32).collect();
    let mut rng = XorShiftRng::seed_from_u64(config.seed);
    let steps = config.anneal_steps as u64 * mesh.triangle_count() as u64;
    // No partition has fewer meshlets than this: at it, only the cheap vertex-total and
    // roundness passes can still help, so the count-removing stages are skipped.
    let floor = limits.min_meshlets(mesh.triangle_count());
    s.improve(&all);
    if config.global_anneal && steps > 0 && s.live > floor {
        // Shorter boundaries first: the capacity the batches below live on. Its uphill moves may
        // end with a meshlet over a limit, which the output would have to split; a cold anneal
        // drives that overflow out, and when it cannot, the boundaries go back to the input's.
        let snapshot = s.label.clone();
        let scale = s.spread_scale();
        let feasible = s.anneal(None, steps, ((1.0, 0.05), scale), &mut rng, false)
            || s.anneal(None, steps, ((0.05, 0.01), scale), &mut rng, true);
        if !feasible {
            s.restore(&snapshot);
        }
        s.improve(&all);
    }
    for _ in 0..config.rounds {
        if s.live <= floor {
            break;
        }
        let before = s.live;
        if config.spread {
            s.round_off(&all);
        }
        if config.rebuild {
            s.rebuild_all(&mut stats);
            s.improve(&all);
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
        if s.live == before {
            break;
        }
    }
    if config.spread {
        s.round_off(&all);
    }
    stats.moves = s.moves;
    stats.search_work = s.work;
    let live = s.live;
    let out = s.into_meshlets(&seq);
    // Every step ends within the limits, so no meshlet is split on the way out.
    debug_assert_eq!(out.len(), live, "a refined meshlet broke a limit");
    stats.meshlets_after = out.len();
    stats.vertices_after = out.vertices.len();
    (out, stats)
}

/// The mesh triangle behind every meshlet triangle, as a label (meshlet index) per mesh triangle.
/// Duplicated triangles are matched in order; a valid partition labels every triangle once.
/// Also returns the mesh triangles in meshlet order.
fn labels_of(mesh: &Mesh, vt: &Csr, ml: &Meshlets) -> (Vec<u32>, Vec<u32>) {
    const NONE: u32 = u32::MAX;
    let mut labels = vec![NONE; mesh.triangle_count()];
    let mut seq = Vec::with_capacity(mesh.triangle_count());
    for m in 0..ml.len() {
        for tri in ml.global_triangles(m) {
            let key = canonical(tri);
            let t = vt
                .row(key[0] as usize)
                .iter()
                .copied()
                .find(|&t| {
                    labels[t as usize] == NONE && canonical(mesh.triangle(t as usize)) == key
                })
                .expect("refine needs a valid partition of the mesh");
            labels[t as usize] = m as u32;
            seq.push(t);
        }
    }
    (labels, seq)
}

/// One journaled move: the triangle, where it came from and went, and both meshlets' change
/// stamps before it.
#[derive(Clone, Copy)]
struct Undo {
    t: u32,
    from: u32,
    to: u32,
    stamps: [usize; 2],
}

struct State<'a> {
    mesh: &'a Mesh,
    vt: &'a Csr,
    dual: &'a Csr,
    limits: Limits,
    label: Vec<u32>,
    /// Triangles per meshlet (0 = dissolved).
    tcount: Vec<u32>,
    /// Distinct vertices per meshlet.
    vcount: Vec<u32>,
    /// Members of each meshlet, unordered.
    members: Vec<Vec<u32>>,
    /// Sum of member triangle centroids, per meshlet.
    csum: Vec<[f64; F]>,
    centroid: Vec<[f64; F]>,
    /// Scratch for connectivity searches: the epoch a triangle was last seen in.
    seen: Vec<u32>,
    /// Scratch for vertex counts: the epoch a vertex was last seen in.
    vseen: Vec<u32>,
    /// Scratch for an augmenting search: a vertex's triangles in the expanded meshlet, valid
    /// where `vseen` holds the search step's epoch.
    vuse: Vec<u32>,
    epoch: u32,
    /// Triangles the augmenting-path searches have looked at.
    work: u64,
    queued: Vec<bool>,
    /// Per meshlet, the move counter when it last changed.
    changed_at: Vec<usize>,
    /// Moves since the journal was opened, for rollback.
    journal: Option<Vec<Undo>>,
    moves: usize,
    /// Boundary moves rank the spread first (rounder meshlets) instead of the vertex total.
    spread_first: bool,
    /// Meshlets with at least one triangle.
    live: usize,
    /// Hartigan gains below this (relative to the mesh scale) count as no gain.
    sse_eps: f64,
}

impl<'a> State<'a> {
    fn new(
        mesh: &'a Mesh,
        vt: &'a Csr,
        dual: &'a Csr,
        label: Vec<u32>,
        k: usize,
        limits: Limits,
    ) -> Self {
        let t_count = mesh.triangle_count();
        let centroid: Vec<[f64; F]> = (0..t_count)
            .map(|t| {
                let [a, b, c] = mesh
                    .triangle(t)
                    .map(|v| glam::DVec3::from(mesh.positions[v as usize].map(f64::from)));
                let p = (a + b + c) / 3.0;
                let n = (b - a).cross(c - a).normalize_or_zero();
                [p.x, p.y, p.z, n.x, n.y, n.z]
            })
            .collect();
        let mut s = Self {
            mesh,
            vt,
            dual,
            limits,
            label,
            tcount: vec![0; k],
            vcount: vec![0; k],
            members: vec![Vec::new(); k],
            csum: vec![[0.0; F]; k],
            centroid,
            seen: vec![0; t_count],
            vseen: vec![0; mesh.vertex_count()],
            vuse: vec![0; mesh.vertex_count()],
            epoch: 0,
            work: 0,
            queued: vec![false; t_count],
            changed_at: vec![0; k],
            journal: None,
            moves: 0,
            sse_eps: 1e-12,
            spread_first: false,
            live: 0,
        };
        // Features: the position over the input's RMS spread (so the spread is scale-free), the
        // normal times NORMAL_WEIGHT.
        s.recount();
        let mut pos = 0.0;
        for (t, &m) in s.label.iter().enumerate() {
            let n = s.tcount[m as usize] as f64;
            pos += (0..3)
                .map(|i| (s.centroid[t][i] - s.csum[m as usize][i] / n).powi(2))
                .sum::<f64>();
        }
        let scale = 1.0 / (pos / t_count as f64).sqrt().max(f64::MIN_POSITIVE);
        for f in &mut s.centroid {
            for (i, x) in f.iter_mut().enumerate() {
                *x *= if i < 3 { scale } else { NORMAL_WEIGHT };
            }
        }
        s.recount();
        s
    }

    /// Every per-meshlet count from the labels.
    fn recount(&mut self) {
        let k = self.tcount.len();
        self.tcount.fill(0);
        self.vcount.fill(0);
        self.csum.fill([0.0; F]);
        for m in &mut self.members {
            m.clear();
        }
        for (t, &m) in self.label.iter().enumerate() {
            self.tcount[m as usize] += 1;
            self.members[m as usize].push(t as u32);
            for i in 0..F {
                self.csum[m as usize][i] += self.centroid[t][i];
            }
        }
        let mut last = vec![u32::MAX; k];
        for v in 0..self.vt.rows() {
            for &t in self.vt.row(v) {
                let m = self.label[t as usize] as usize;
                if last[m] != v as u32 {
                    last[m] = v as u32;
                    self.vcount[m] += 1;
                }
            }
        }
        self.live = self.tcount.iter().filter(|&&c| c > 0).count();
    }

    /// Triangles of meshlet `m` that use vertex `v`.
    #[inline]
    fn uses(&self, v: u32, m: u32) -> usize {
        self.vt
            .row(v as usize)
            .iter()
            .filter(|&&t| self.label[t as usize] == m)
            .count()
    }

    /// Vertices of `t` that meshlet `b` would gain by taking it.
    #[inline]
    fn added(&self, t: u32, b: u32) -> u32 {
        distinct(self.mesh.triangle(t as usize))
            .filter(|&v| self.uses(v, b) == 0)
            .count() as u32
    }

    /// Vertices meshlet `a` would lose by giving `t` away (`t` is its only user of them).
    #[inline]
    fn removed(&self, t: u32, a: u32) -> u32 {
        distinct(self.mesh.triangle(t as usize))
            .filter(|&v| self.uses(v, a) == 1)
            .count() as u32
    }

    /// Whether meshlet `b` has room for `t` (which adds `add` vertices).
    #[inline]
    fn fits(&self, b: u32, add: u32) -> bool {
        self.tcount[b as usize] < self.limits.max_triangles
            && self.vcount[b as usize] + add <= self.limits.max_vertices
    }

    /// Meshlets other than `t`'s own that share an edge with `t`, ascending, without repeats.
    fn neighbour_labels(&self, t: u32) -> ([u32; 8], usize) {
        let own = self.label[t as usize];
        let mut out = [0u32; 8];
        let mut n = 0;
        for &u in self.dual.row(t as usize) {
            let l = self.label[u as usize];
            if l != own && !out[..n].contains(&l) && n < out.len() {
                out[n] = l;
                n += 1;
            }
        }
        out[..n].sort_unstable();
        (out, n)
    }

    /// Change of the centroid spread (sum of squared distances to the meshlet centroid) when `t`
    /// moves from `a` to `b` (Hartigan's formula).
    fn sse_delta(&self, t: u32, a: u32, b: u32) -> f64 {
        let x = self.centroid[t as usize];
        let d2 = |m: u32| {
            let n = self.tcount[m as usize] as f64;
            let c = self.csum[m as usize];
            (0..F).map(|i| (x[i] - c[i] / n).powi(2)).sum::<f64>()
        };
        let (na, nb) = (
            self.tcount[a as usize] as f64,
            self.tcount[b as usize] as f64,
        );
        let gain_b = if nb > 0.0 {
            nb / (nb + 1.0) * d2(b)
        } else {
            0.0
        };
        let loss_a = if na > 1.0 {
            na / (na - 1.0) * d2(a)
        } else {
            0.0
        };
        gain_b - loss_a
    }

    /// Whether removing `t` leaves its meshlet's edge-connected piece around `t` in one piece.
    fn stays_connected(&mut self, t: u32) -> bool {
        let own = self.label[t as usize];
        let dual = self.dual;
        let targets: Vec<u32> = dual
            .row(t as usize)
            .iter()
            .copied()
            .filter(|&u| self.label[u as usize] == own)
            .collect();
        if targets.len() <= 1 {
            return true;
        }
        self.epoch += 1;
        let e = self.epoch;
        self.seen[t as usize] = e;
        self.seen[targets[0] as usize] = e;
        let mut stack = vec![targets[0]];
        let mut left = targets.len() - 1;
        while let Some(u) = stack.pop() {
            for &w in dual.row(u as usize) {
                if self.label[w as usize] == own && self.seen[w as usize] != e {
                    self.seen[w as usize] = e;
                    if targets.contains(&w) {
                        left -= 1;
                        if left == 0 {
                            return true;
                        }
                    }
                    stack.push(w);
                }
            }
        }
        false
    }

    /// Whether meshlet `m` is one edge-connected piece.
    fn is_connected(&mut self, m: u32) -> bool {
        let members = &self.members[m as usize];
        let Some(&first) = members.first() else {
            return true;
        };
        self.epoch += 1;
        let e = self.epoch;
        self.seen[first as usize] = e;
        let mut stack = vec![first];
        let mut reached = 1;
        while let Some(u) = stack.pop() {
            for &w in self.dual.row(u as usize) {
                if self.label[w as usize] == m && self.seen[w as usize] != e {
                    self.seen[w as usize] = e;
                    reached += 1;
                    stack.push(w);
                }
            }
        }
        reached == members.len()
    }

    /// Moves `t` to meshlet `b`, keeping every count in step.
    fn apply(&mut self, t: u32, b: u32) {
        let a = self.label[t as usize];
        let (rem, add) = (self.removed(t, a), self.added(t, b));
        self.vcount[a as usize] -= rem;
        self.vcount[b as usize] += add;
        self.tcount[a as usize] -= 1;
        self.tcount[b as usize] += 1;
        self.live -= (self.tcount[a as usize] == 0) as usize;
        self.live += (self.tcount[b as usize] == 1) as usize;
        let x = self.centroid[t as usize];
        for (i, xi) in x.iter().enumerate() {
            self.csum[a as usize][i] -= xi;
            self.csum[b as usize][i] += xi;
        }
        let ma = &mut self.members[a as usize];
        let p = ma.iter().position(|&u| u == t).expect("member");
        ma.swap_remove(p);
        self.members[b as usize].push(t);
        self.label[t as usize] = b;
        if let Some(j) = self.journal.as_mut() {
            j.push(Undo {
                t,
                from: a,
                to: b,
                stamps: [self.changed_at[a as usize], self.changed_at[b as usize]],
            });
        }
        self.moves += 1;
        self.changed_at[a as usize] = self.moves;
        self.changed_at[b as usize] = self.moves;
    }

    /// The best improving boundary move of `t`, if any.
    fn best_move(&mut self, t: u32) -> Option<u32> {
        let a = self.label[t as usize];
        let (nb, n) = self.neighbour_labels(t);
        if n == 0 {
            return None;
        }
        let rem = self.removed(t, a) as i64;
        let mut best: Option<(i64, f64, u32)> = None;
        for &b in &nb[..n] {
            let add = self.added(t, b);
            if !self.fits(b, add) {
                continue;
            }
            let gain = rem - add as i64;
            let sse = self.sse_delta(t, a, b);
            if self.spread_first {
                if sse >= -self.sse_eps {
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
            if gain == 0 && sse >= -self.sse_eps {
                continue;
            }
            if best.is_none_or(|(g, s, _)| gain > g || (gain == g && sse < s)) {
                best = Some((gain, sse, b));
            }
        }
        let (_, _, b) = best?;
        self.stays_connected(t).then_some(b)
    }

    /// Boundary moves until none improves, starting from the triangles in `seeds`.
    fn improve(&mut self, seeds: &[u32]) {
        let mut work: VecDeque<u32> = VecDeque::new();
        for &t in seeds {
            if !self.queued[t as usize] {
                self.queued[t as usize] = true;
                work.push_back(t);
            }
        }
        // Every move strictly lowers (vertex total, spread); the cap is only a guard.
        let mut budget = 64 * self.label.len() + 1024;
        while let Some(t) = work.pop_front() {
            self.queued[t as usize] = false;
            let Some(b) = self.best_move(t) else {
                continue;
            };
            self.apply(t, b);
            budget -= 1;
            if budget == 0 {
                break;
            }
            for v in distinct(self.mesh.triangle(t as usize)) {
                for &u in self.vt.row(v as usize) {
                    if !self.queued[u as usize] {
                        self.queued[u as usize] = true;
                        work.push_back(u);
                    }
                }
            }
        }
        for t in work {
            self.queued[t as usize] = false;
        }
    }

    /// Tries every live meshlet as a victim, emptiest first, until a whole round removes none.
    fn dissolve_all(&mut self, search_nodes: usize, budget: u64, stats: &mut Stats) {
        let stop = self.work.saturating_add(budget);
        // A victim that failed is tried again only once it or a neighbour has changed since.
        let mut failed_at: Vec<Option<usize>> = vec![None; self.tcount.len()];
        loop {
            let mut order: Vec<u32> = (0..self.tcount.len() as u32)
                .filter(|&m| self.tcount[m as usize] > 0)
                .collect();
            order.sort_by_key(|&m| (self.tcount[m as usize], m));
            let mut any = false;
            for m in order {
                // At the hard bound no victim can go.
                if self.work >= stop || self.live <= self.limits.min_meshlets(self.label.len()) {
                    return;
                }
                if self.tcount[m as usize] == 0 {
                    continue;
                }
                if let Some(at) = failed_at[m as usize] {
                    let last = self
                        .adjacent_meshlets(m)
                        .iter()
                        .chain([&m])
                        .map(|&r| self.changed_at[r as usize])
                        .max()
                        .unwrap_or(0);
                    if last <= at {
                        continue;
                    }
                }
                if !self.may_dissolve(m) {
                    failed_at[m as usize] = Some(self.moves);
                    continue;
                }
                self.journal = Some(Vec::new());
                let ok = self.dissolve(m, search_nodes);
                let journal = self.journal.take().expect("open journal");
                if ok {
                    stats.dissolved += 1;
                    any = true;
                    let touched: Vec<u32> = journal.iter().map(|u| u.t).collect();
                    let mut seeds = Vec::new();
                    for &t in &touched {
                        for v in distinct(self.mesh.triangle(t as usize)) {
                            seeds.extend_from_slice(self.vt.row(v as usize));
                        }
                    }
                    self.improve(&seeds);
                } else {
                    stats.failed += 1;
                    self.rollback(&journal);
                    failed_at[m as usize] = Some(self.moves);
                }
            }
            if !any {
                break;
            }
        }
    }

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
        let mut ring = vec![m];
        let mut seen = vec![m];
        let mut free_v = 0u32;
        for _ in 0..2 {
            let mut next = Vec::new();
            for &r in &ring {
                for n in self.adjacent_meshlets(r) {
                    if !seen.contains(&n) {
                        seen.push(n);
                        next.push(n);
                        free_v += self.limits.max_vertices - self.vcount[n as usize];
                    }
                }
            }
            if free_v >= interior {
                return true;
            }
            ring = next;
        }
        false
    }

    /// Hands every triangle of meshlet `m` to its neighbours; false (state dirty, to be rolled
    /// back) when some triangle finds no room even through an ejection chain.
    fn dissolve(&mut self, m: u32, search_nodes: usize) -> bool {
        while self.tcount[m as usize] > 0 {
            // Cheapest hand-overs first: a triangle whose vertices a neighbour already has costs it
            // nothing, and filling such notches first keeps the neighbours round.
            let mut done = false;
            for cost in 0..=3 {
                let list = self.members[m as usize].clone();
                for t in list {
                    let (nb, n) = self.neighbour_labels(t);
                    for &b in &nb[..n] {
                        let add = self.added(t, b);
                        if add <= cost && self.fits(b, add) {
                            self.apply(t, b);
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
            let list = self.members[m as usize].clone();
            let mut made = false;
            let mut dead: Vec<(u32, u32)> = Vec::new();
            'outer: for t in list {
                let (nb, n) = self.neighbour_labels(t);
                let mut cands: Vec<(u32, u32)> =
                    nb[..n].iter().map(|&b| (self.added(t, b), b)).collect();
                cands.sort_unstable();
                for (add, b) in cands {
                    if dead.iter().any(|&(d, k)| d == b && k <= add) {
                        continue;
                    }
                    let ok = search_nodes > 0 && self.augment(b, t, m, search_nodes);
                    if ok {
                        let add = self.added(t, b);
                        if self.fits(b, add) {
                            self.apply(t, b);
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
    /// fits into `b`.
    fn augment(&mut self, b: u32, t: u32, m: u32, max_nodes: usize) -> bool {
        // (meshlet, incoming triangle, parent node)
        let mut nodes: Vec<(u32, u32, usize)> = vec![(b, t, usize::MAX)];
        let mut visited = vec![m, b];
        let mut head = 0;
        let mut goal = None;
        while head < nodes.len() && nodes.len() < max_nodes {
            let (y, s_in, _) = nodes[head];
            let in_v: Vec<u32> = distinct(self.mesh.triangle(s_in as usize)).collect();
            let add_in = self.added(s_in, y);
            if head > 0 && self.fits(y, add_in) {
                goal = Some(head);
                break;
            }
            self.work += self.members[y as usize].len() as u64;
            // y's use count of each of its vertices, counted once for all its members (nothing
            // moves during the search): scanning each vertex's triangles per member cost about
            // 15 % of openfoam_motorbike's refinement (41 s -> 35 s without it).
            self.epoch += 1;
            let e = self.epoch;
            for &s in &self.members[y as usize] {
                for v in distinct(self.mesh.triangle(s as usize)) {
                    let v = v as usize;
                    if self.vseen[v] != e {
                        self.vseen[v] = e;
                        self.vuse[v] = 0;
                    }
                    self.vuse[v] += 1;
                }
            }
            for i in 0..self.members[y as usize].len() {
                let s = self.members[y as usize][i];
                // s_in must still touch y when it arrives: never pass on one of its neighbours.
                if self.dual.row(s_in as usize).contains(&s) {
                    continue;
                }
                // The stamp is this step's: stays_connected below bumps the epoch but only
                // stamps triangles.
                let freed = distinct(self.mesh.triangle(s as usize))
                    .filter(|&v| !in_v.contains(&v) && self.vuse[v as usize] == 1)
                    .count() as u32;
                if self.vcount[y as usize] + add_in > self.limits.max_vertices + freed {
                    continue;
                }
                let (nb, n) = self.neighbour_labels(s);
                // Whether s may leave y at all, asked once (a search inside y) and only if needed.
                let mut leaves: Option<bool> = None;
                for &z in &nb[..n] {
                    if visited.contains(&z)
                        || self.added(s, z) + self.vcount[z as usize] > self.limits.max_vertices
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
            let add = self.added(s, z);
            if !self.fits(z, add) {
                return false;
            }
            self.apply(s, z);
            g = parent;
        }
        let add = self.added(t, b);
        self.fits(b, add)
    }

    /// Meshlets sharing an edge with meshlet `m`, ascending.
    /// Step 2: spread-first boundary moves, then vertex-first ones.
    fn round_off(&mut self, all: &[u32]) {
        self.spread_first = true;
        self.improve(all);
        self.spread_first = false;
        self.improve(all);
    }

    /// How far meshlet `m` is over the limits (vertices plus triangles).
    fn overflow(&self, m: u32) -> i64 {
        let (v, t) = (self.vcount[m as usize], self.tcount[m as usize]);
        (v as i64 - self.limits.max_vertices as i64).max(0)
            + (t as i64 - self.limits.max_triangles as i64).max(0)
    }

    /// [`SPREAD_WEIGHT`] over the mean squared distance of a triangle centroid to its meshlet's
    /// centroid: the weight of a spread change in the annealer's energy. A pass over the mesh, so
    /// it is measured once per annealing stage, not per victim (on the 871 k-triangle dragon that
    /// pass cost more than a victim's anneal).
    fn spread_scale(&self) -> f64 {
        let mut sum = 0.0;
        for (t, &m) in self.label.iter().enumerate() {
            let n = self.tcount[m as usize] as f64;
            let c = self.csum[m as usize];
            sum += (0..F)
                .map(|i| (self.centroid[t][i] - c[i] / n).powi(2))
                .sum::<f64>();
        }
        SPREAD_WEIGHT / (sum / self.label.len() as f64).max(f64::MIN_POSITIVE)
    }

    /// Simulated annealing over boundary moves of the triangles in `pool` (all when `None`) with
    /// the energy vertex total + overflow × weight + spread × `scale` ([`Self::spread_scale`]),
    /// temperature falling geometrically from `temps.0` to `temps.1`. Never empties a meshlet.
    /// With `stop_when_feasible` it ends as soon as nothing overflows. True when it ends without
    /// overflow.
    fn anneal(
        &mut self,
        pool: Option<&[u32]>,
        steps: u64,
        (temps, scale): ((f64, f64), f64),
        rng: &mut XorShiftRng,
        stop_when_feasible: bool,
    ) -> bool {
        let mut over: i64 = (0..self.tcount.len() as u32)
            .map(|m| self.overflow(m))
            .sum();
        let n = self.label.len() as u64;
        let (mv, mt) = (
            self.limits.max_vertices as i64,
            self.limits.max_triangles as i64,
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
            let (nb, k) = self.neighbour_labels(t);
            if k == 0 {
                continue;
            }
            let b = nb[(rng.next_u64() % k as u64) as usize];
            let a = self.label[t as usize];
            if self.tcount[a as usize] == 1 {
                continue;
            }
            let (add, rem) = (self.added(t, b) as i64, self.removed(t, a) as i64);
            let (ua, ub) = (a as usize, b as usize);
            let ov_before = self.overflow(a) + self.overflow(b);
            let ov_after = (self.vcount[ua] as i64 - rem - mv).max(0)
                + (self.vcount[ub] as i64 + add - mv).max(0)
                + (self.tcount[ua] as i64 - 1 - mt).max(0)
                + (self.tcount[ub] as i64 + 1 - mt).max(0);
            let delta = (add - rem) as f64
                + OVERFLOW_WEIGHT * (ov_after - ov_before) as f64
                + scale * self.sse_delta(t, a, b);
            if delta > 0.0 {
                let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
                if u >= (-delta / temp).exp() {
                    continue;
                }
            }
            if !self.stays_connected(t) {
                continue;
            }
            self.apply(t, b);
            over += ov_after - ov_before;
        }
        over == 0
    }

    /// Step 5: removes meshlets one at a time, emptiest first: a victim's triangles are handed to
    /// its neighbours regardless of the limits, then an anneal confined to the meshlets within
    /// [`ANNEAL_RINGS`] of it drives the overflow back to zero within `steps_per_triangle`
    /// proposals per triangle there, or the hand-over is undone. Ends after `failures` victims in
    /// a row could not go. Confining the anneal makes a failed victim cost its neighbourhood, not
    /// the mesh: on the bunny the same budget per triangle dissolves more (720 -> 710-712
    /// meshlets instead of 714) in two thirds of the time of annealing the whole mesh per attempt.
    fn anneal_dissolve(
        &mut self,
        steps_per_triangle: u64,
        failures: u32,
        rng: &mut XorShiftRng,
        stats: &mut Stats,
    ) {
        let mut failed = vec![false; self.tcount.len()];
        let mut in_a_row = 0;
        let scale = self.spread_scale();
        while in_a_row < failures {
            if self.live <= self.limits.min_meshlets(self.label.len()) {
                return;
            }
            let Some(victim) = (0..self.tcount.len() as u32)
                .filter(|&m| self.tcount[m as usize] > 0 && !failed[m as usize])
                .min_by_key(|&m| (self.tcount[m as usize], m))
            else {
                return;
            };
            let region = self.rings(victim, ANNEAL_RINGS);
            // A journal, not a snapshot: undoing costs the moves made, not the mesh.
            self.journal = Some(Vec::new());
            let mut ok = self.hand_over(victim);
            let pool: Vec<u32> = region
                .iter()
                .flat_map(|&m| self.members[m as usize].iter().copied())
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
            let journal = self.journal.take().expect("open journal");
            if ok {
                stats.dissolved += 1;
                in_a_row = 0;
                self.improve(&pool);
            } else {
                stats.failed += 1;
                self.rollback(&journal);
                failed[victim as usize] = true;
                in_a_row += 1;
            }
        }
    }

    /// Meshlet `m` and every live meshlet within `rings` edge-adjacency hops of it, ascending.
    fn rings(&self, m: u32, rings: usize) -> Vec<u32> {
        let mut all = vec![m];
        let mut ring = vec![m];
        for _ in 0..rings {
            let mut next = Vec::new();
            for &r in &ring {
                for n in self.adjacent_meshlets(r) {
                    if !all.contains(&n) && !next.contains(&n) {
                        next.push(n);
                    }
                }
            }
            all.extend_from_slice(&next);
            ring = next;
        }
        all.sort_unstable();
        all
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

    /// Undoes the journaled moves in reverse; a rollback is no change, so the stamps come back too.
    fn rollback(&mut self, journal: &[Undo]) {
        for u in journal.iter().rev() {
            self.apply(u.t, u.from);
            self.moves -= 1;
            self.changed_at[u.from as usize] = u.stamps[0];
            self.changed_at[u.to as usize] = u.stamps[1];
        }
    }

    /// Puts the labels of `snapshot` back and recounts everything.
    fn restore(&mut self, snapshot: &[u32]) {
        self.label.copy_from_slice(snapshot);
        self.recount();
        self.moves += 1;
        self.changed_at.fill(self.moves);
    }

    /// Meshlets sharing an edge with meshlet `m`, ascending.
    fn adjacent_meshlets(&self, m: u32) -> Vec<u32> {
        let mut out = Vec::new();
        for &t in &self.members[m as usize] {
            let (nb, n) = self.neighbour_labels(t);
            out.extend_from_slice(&nb[..n]);
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Rebuilds the union of `region`'s meshlets from scratch with meshoptimizer; keeps the result
    /// when it has fewer meshlets, or as many with fewer vertex references. True when kept.
    fn rebuild(&mut self, region: &[u32]) -> bool {
        let mut tris: Vec<u32> = region
            .iter()
            .flat_map(|&m| self.members[m as usize].iter().copied())
            .collect();
        tris.sort_unstable();
        let mut local = std::collections::HashMap::new();
        let mut positions = Vec::new();
        let mut indices = Vec::with_capacity(3 * tris.len());
        for &t in &tris {
            for v in self.mesh.triangle(t as usize) {
                let l = *local.entry(v).or_insert_with(|| {
                    positions.push(self.mesh.positions[v as usize]);
                    positions.len() as u32 - 1
                });
                indices.push(l);
            }
        }
        let sub = Mesh { positions, indices };
        let ml = super::meshopt::Meshopt { cone_weight: 0.0 }.build(&sub, self.limits);
        let old_refs: u32 = region.iter().map(|&m| self.vcount[m as usize]).sum();
        if ml.len() > region.len()
            || (ml.len() == region.len() && ml.vertices.len() as u32 >= old_refs)
        {
            return false;
        }
        let vt = vertex_triangles(&sub);
        let (labels, _) = labels_of(&sub, &vt, &ml);
        let before = (self.live_in(region), old_refs);
        let pieces_before = region.iter().filter(|&&m| !self.is_connected(m)).count();
        let old_labels: Vec<u32> = tris.iter().map(|&t| self.label[t as usize]).collect();
        let new_labels: Vec<u32> = labels.iter().map(|&l| region[l as usize]).collect();
        self.relabel(&tris, &new_labels, region);
        // meshoptimizer does not promise one piece per meshlet: hand stray pieces to neighbours,
        // and never end with more meshlets in pieces than before.
        self.mend_pieces(region);
        let pieces_after = region.iter().filter(|&&m| !self.is_connected(m)).count();
        let refs: u32 = region.iter().map(|&m| self.vcount[m as usize]).sum();
        if pieces_after > pieces_before || (self.live_in(region), refs) >= before {
            self.relabel(&tris, &old_labels, region);
            return false;
        }
        self.moves += 1;
        for &m in region {
            self.changed_at[m as usize] = self.moves;
        }
        true
    }

    /// Live meshlets among `region`.
    fn live_in(&self, region: &[u32]) -> usize {
        region
            .iter()
            .filter(|&&m| self.tcount[m as usize] > 0)
            .count()
    }

    /// Gives the triangles `tris` (exactly the members of the `region` meshlets) the meshlets
    /// `labels` (all in `region`) and recounts the region.
    fn relabel(&mut self, tris: &[u32], labels: &[u32], region: &[u32]) {
        let live_before = self.live_in(region);
        for &m in region {
            self.members[m as usize].clear();
            self.tcount[m as usize] = 0;
            self.vcount[m as usize] = 0;
            self.csum[m as usize] = [0.0; F];
        }
        for (&t, &m) in tris.iter().zip(labels) {
            self.label[t as usize] = m;
            self.members[m as usize].push(t);
            self.tcount[m as usize] += 1;
            for k in 0..F {
                self.csum[m as usize][k] += self.centroid[t as usize][k];
            }
        }
        for &m in region {
            self.epoch += 1;
            let e = self.epoch;
            let mut n = 0;
            for &t in &self.members[m as usize] {
                for v in self.mesh.triangle(t as usize) {
                    if self.vseen[v as usize] != e {
                        self.vseen[v as usize] = e;
                        n += 1;
                    }
                }
            }
            self.vcount[m as usize] = n;
        }
        self.live = self.live - live_before + self.live_in(region);
    }

    /// Moves every piece but the largest of each meshlet in `region` into other region meshlets
    /// with room, where it can.
    fn mend_pieces(&mut self, region: &[u32]) {
        for &m in region {
            if self.is_connected(m) {
                continue;
            }
            let pieces = self.pieces(m);
            let largest = (0..pieces.len())
                .max_by_key(|&i| (pieces[i].len(), std::cmp::Reverse(pieces[i][0])))
                .expect("a meshlet in pieces has pieces");
            for (i, piece) in pieces.iter().enumerate() {
                if i == largest {
                    continue;
                }
                let mut left: Vec<u32> = piece.clone();
                let mut progress = true;
                while !left.is_empty() && progress {
                    progress = false;
                    left.retain(|&t| {
                        let (nb, n) = self.neighbour_labels(t);
                        let to = nb[..n]
                            .iter()
                            .copied()
                            .filter(|b| region.contains(b))
                            .map(|b| (self.added(t, b), b))
                            .filter(|&(add, b)| self.fits(b, add))
                            .min();
                        match to {
                            Some((_, b)) => {
                                self.apply(t, b);
                                progress = true;
                                false
                            }
                            None => true,
                        }
                    });
                }
            }
        }
    }

    /// The edge-connected pieces of meshlet `m`, each led by its smallest triangle, in order.
    fn pieces(&mut self, m: u32) -> Vec<Vec<u32>> {
        let mut members = self.members[m as usize].clone();
        members.sort_unstable();
        self.epoch += 1;
        let e = self.epoch;
        let mut out = Vec::new();
        for &first in &members {
            if self.seen[first as usize] == e {
                continue;
            }
            self.seen[first as usize] = e;
            let mut piece = vec![first];
            let mut i = 0;
            while i < piece.len() {
                let u = piece[i];
                i += 1;
                for &w in self.dual.row(u as usize) {
                    if self.label[w as usize] == m && self.seen[w as usize] != e {
                        self.seen[w as usize] = e;
                        piece.push(w);
                    }
                }
            }
            out.push(piece);
        }
        out
    }

    /// Large-neighbourhood search: every meshlet with its neighbours rebuilt from scratch.
    fn rebuild_all(&mut self, stats: &mut Stats) {
        let mut order: Vec<u32> = (0..self.tcount.len() as u32)
            .filter(|&m| self.tcount[m as usize] > 0)
            .collect();
        order.sort_by_key(|&m| (self.tcount[m as usize], m));
        for m in order {
            if self.tcount[m as usize] == 0 {
                continue;
            }
            let mut region = self.adjacent_meshlets(m);
            region.push(m);
            region.sort_unstable();
            region.dedup();
            let before = region.len();
            if self.rebuild(&region) {
                let after = region
                    .iter()
                    .filter(|&&r| self.tcount[r as usize] > 0)
                    .count();
                stats.dissolved += before - after;
            }
        }
    }

    /// The refined partition as meshlets, in the input's meshlet order; inside a meshlet the
    /// triangles keep the input's triangle order (`seq`), received ones where they came from.
    fn into_meshlets(self, seq: &[u32]) -> Meshlets {
        let mut order: Vec<Vec<u32>> = vec![Vec::new(); self.tcount.len()];
        for &t in seq {
            order[self.label[t as usize] as usize].push(t);
        }
        let mut b = MeshletBuilder::new(self.mesh.vertex_count(), self.limits);
        for tris in order.iter().filter(|v| !v.is_empty()) {
            for &t in tris {
                b.push(self.mesh.triangle(t as usize));
            }
            b.flush();
        }
        b.finish()
    }
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
