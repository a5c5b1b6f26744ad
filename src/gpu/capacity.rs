//! The capacity-aware assignment of the default `kmedoids`
//! ([`crate::strategy::kmedoids::capacity::assign_capacity`]) as kernels (`wgsl/capacity.wgsl`),
//! with labels identical to the CPU's.
//!
//! The CPU takes each BFS level's clusters in ascending id, a cluster skipping what a lower one
//! took in the same level. Here every cluster walks its level at once and the level's walk is
//! repeated, each walk skipping what a lower cluster claimed in the one before, until no cluster's
//! takes change: the fixed point of that iteration is the sequential order's result (the WGSL
//! file's header gives the argument). A repeat redoes only the clusters whose inputs changed (one
//! that lost a triangle, or one whose skipped triangle was freed); the rest re-claim their takes.
//! Per level the host records three walks and reads their counters in one round trip; only a
//! level whose conflicts chain deeper costs more round trips.

use super::adjacency::{AdjacencyKernels, DeviceAdjacency};
use super::{binding_set, param_block, wgsl, Batch, Gpu, GpuError, Kernels, PART};
use crate::mesh::Mesh;
use crate::meshlet::Limits;

/// The assignment alone on `mesh` from `medoids` (its adjacency built on the GPU first): the
/// labels and what the kernels did. For parity checks; a k-medoids run keeps one
/// [`CapacityAssign`] over its rounds instead.
pub fn assign(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    medoids: &[u32],
) -> Result<(Vec<u32>, AssignStats), GpuError> {
    assign_with_stamps(gpu, mesh, limits, medoids, TOP)
}

/// [`assign`] with claim stamps from `top` (1..=125) down: a small `top` makes the stamps start
/// again every few walks, mid-level, which the tests use to check that path.
pub fn assign_with_stamps(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    medoids: &[u32],
    top: u32,
) -> Result<(Vec<u32>, AssignStats), GpuError> {
    let (adj, _) = AdjacencyKernels::new(gpu).build(gpu, mesh)?;
    let mut a = CapacityAssign::new(gpu, mesh.triangle_count());
    a.top = top.clamp(1, TOP);
    let labels = a.run(gpu, &adj, limits, medoids)?;
    Ok((labels, a.stats))
}

param_block! {
    /// `struct Params` of `wgsl/capacity.wgsl`.
    pub struct Params {
        /// Triangles.
        t,
        /// Clusters.
        k,
        /// Meshlet vertex limit.
        max_v,
        /// Meshlet triangle limit.
        max_t,
        /// 1 for a level's first walk (which reads no claims).
        first,
        /// Walk parity: the claim array this walk writes (0: `claim_a`).
        par,
        /// Counter slot this dispatch counts into.
        slot,
        /// This walk's claim stamp (falls by one per walk).
        code,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/capacity.wgsl`, in binding order.
    pub struct Buffers {
        /// Dual-graph offsets.
        dual_off: Read,
        /// Dual-graph items, first part.
        dual_a: Read,
        /// Dual-graph items, second part.
        dual_b: Read,
        /// Index buffer, first part.
        idx_a: Read,
        /// Index buffer, second part.
        idx_b: Read,
        /// Medoid per cluster.
        medoids: Read,
        /// Out: cluster per triangle.
        labels: ReadWrite,
        /// Claims of even walks.
        claim_a: ReadWrite,
        /// Claims of odd walks.
        claim_b: ReadWrite,
        /// Each cluster's triangles, `max_t` slots per cluster.
        ct: ReadWrite,
        /// Each cluster's vertices, `max_v` slots per cluster.
        cv: ReadWrite,
        /// Per-cluster state (`STATE` words).
        state: ReadWrite,
        /// Triangles each cluster's last walk skipped, `SKIP` slots per cluster.
        skipped: ReadWrite,
        /// Counter slots.
        counters: ReadWrite,
    }
}

/// Words of per-cluster state (`STATE` in the WGSL; `gpu::shaders_test` checks both agree).
pub(crate) const STATE: usize = 8;
/// Skipped triangles kept per cluster (`SKIP` in the WGSL; checked likewise).
pub(crate) const SKIP: usize = 16;
/// Counter slots (`clear_counters` clears this many).
const COUNTERS: usize = 8;
/// The slot `seed` and `commit` count open clusters into.
const OPEN: u32 = 7;
/// Walks recorded per level up front: most levels end after the first (nothing contested) or
/// the second; three cover nearly all in one round trip.
const WALKS: u32 = 3;
/// The first walk's claim stamp; stamps fall by one per walk, and at 0 `restamp` starts them
/// again (claims keep 7 bits of stamp above 25 of cluster id; 127 marks no claim).
pub const TOP: u32 = 125;

/// Words per cluster of the largest per-cluster buffer.
fn per_cluster(limits: Limits) -> usize {
    (limits.max_triangles.max(limits.max_vertices) as usize)
        .max(SKIP)
        .max(STATE)
}

/// What the kernels did over the runs of one [`CapacityAssign`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AssignStats {
    /// Assignments run.
    pub runs: u64,
    /// BFS levels.
    pub levels: u64,
    /// Walks recorded (spare ones included).
    pub walks: u64,
    /// Submissions (one host round trip each).
    pub submissions: u64,
    /// Levels whose first walk left a cluster to redo (a lower cluster took one of its takes).
    pub contested: u64,
    /// Submissions beyond the one per level, for levels whose conflicts chained deeper than
    /// the walks recorded up front.
    pub extra: u64,
}

/// The assignment kernels and the per-triangle buffers they reuse from run to run.
pub struct CapacityAssign {
    kernels: Kernels<Params>,
    labels: wgpu::Buffer,
    claim_a: wgpu::Buffer,
    claim_b: wgpu::Buffer,
    counters: wgpu::Buffer,
    t: usize,
    /// The first claim stamp ([`TOP`] but in tests).
    top: u32,
    /// Kernel seconds over all runs.
    pub kernel_seconds: f64,
    /// Work counters over all runs.
    pub stats: AssignStats,
}

impl CapacityAssign {
    /// Kernels and buffers for meshes of `t` triangles.
    pub fn new(gpu: &Gpu, t: usize) -> Self {
        Self {
            kernels: Kernels::new::<Buffers>(
                gpu,
                "capacity",
                wgsl!("capacity.wgsl"),
                &[
                    "clear_labels",
                    "restamp",
                    "clear_counters",
                    "seed",
                    "walk",
                    "check",
                    "commit",
                ],
            ),
            labels: gpu.zeros("capacity labels", t),
            claim_a: gpu.zeros("capacity claims a", t),
            claim_b: gpu.zeros("capacity claims b", t),
            counters: gpu.zeros("capacity counters", COUNTERS),
            t,
            top: TOP,
            kernel_seconds: 0.0,
            stats: AssignStats::default(),
        }
    }

    /// Whether `k` clusters' triangle, vertex, skipped and state lists fit one binding each.
    pub fn fits(k: usize, limits: Limits) -> bool {
        k * per_cluster(limits) <= PART
    }

    /// The labels [`crate::strategy::kmedoids::capacity::assign_capacity`] gives from `medoids`
    /// (`u32::MAX` where no cluster had room) on the mesh of `adj`.
    pub fn run(
        &mut self,
        gpu: &Gpu,
        adj: &DeviceAdjacency,
        limits: Limits,
        medoids: &[u32],
    ) -> Result<Vec<u32>, GpuError> {
        let k = medoids.len();
        if !Self::fits(k, limits) {
            return Err(GpuError::TooLarge {
                what: "capacity-assignment cluster lists",
                len: k * per_cluster(limits),
                max: PART,
            });
        }
        let mut sorted = medoids.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        if sorted.len() != k || sorted.last().is_some_and(|&m| m as usize >= self.t) {
            // Two clusters seeding one triangle would race on its label.
            return Err(GpuError::Unsupported(
                "capacity assignment needs distinct medoids that are triangles of the mesh",
            ));
        }
        self.stats.runs += 1;
        let (max_v, max_t) = (limits.max_vertices, limits.max_triangles);
        let medoid_buf = gpu.upload("capacity medoids", medoids);
        let ct = gpu.zeros("capacity cluster triangles", k * max_t as usize);
        let cv = gpu.zeros("capacity cluster vertices", k * max_v as usize);
        let state = gpu.zeros("capacity state", k * STATE);
        let skipped = gpu.zeros("capacity skipped", k * SKIP);
        let bind = self.kernels.bind(
            gpu,
            &Buffers {
                dual_off: &adj.dual_offsets,
                dual_a: &adj.dual_items.a,
                dual_b: &adj.dual_items.b,
                idx_a: &adj.indices.a,
                idx_b: &adj.indices.b,
                medoids: &medoid_buf,
                labels: &self.labels,
                claim_a: &self.claim_a,
                claim_b: &self.claim_b,
                ct: &ct,
                cv: &cv,
                state: &state,
                skipped: &skipped,
                counters: &self.counters,
            },
        );
        let base = Params {
            t: self.t as u32,
            k: k as u32,
            max_v,
            max_t,
            first: 0,
            par: 0,
            slot: 0,
            code: self.top,
        };
        let kern = &self.kernels;
        let t = self.t;
        let mut walker = Walker {
            kern,
            bind: &bind,
            base,
            k,
            stride_groups: gpu.stride_groups(t),
            walks: 0,
            last_code: None,
            top: self.top,
        };
        // The first batch seeds the clusters; every later one commits the level before. Then
        // the level's walks, each followed by `check`: walk j counts changed clusters into slot
        // 2j, `check` the clusters to redo into 2j + 1.
        let mut b = Batch::new(gpu);
        b.threads(kern, "clear_counters", &bind, base, COUNTERS);
        b.groups(kern, "clear_labels", &bind, base, gpu.stride_groups(t));
        b.threads(kern, "seed", &bind, Params { slot: OPEN, ..base }, k);
        let mut batch = Some(b);
        let mut stats = AssignStats::default();
        while let Some(mut b) = batch.take() {
            for j in 0..WALKS {
                walker.record(&mut b, j == 0, 2 * j);
            }
            let (sec, out) = b.run_read(&[(&self.counters, 0, COUNTERS)])?;
            self.kernel_seconds += sec;
            stats.submissions += 1;
            let c = &out[0];
            if c[OPEN as usize] == 0 {
                break;
            }
            stats.levels += 1;
            stats.contested += (c[1] > 0) as u64;
            // Done after walk j when no cluster is to be redone, or (after the first) when the
            // walk changed nothing.
            let settled = |c: &[u32], j: usize, first: bool| {
                c[2 * j + 1] == 0 || (!(first && j == 0) && c[2 * j] == 0)
            };
            let mut done = (0..WALKS as usize).any(|j| settled(c, j, true));
            while !done {
                let mut b = Batch::new(gpu);
                b.threads(kern, "clear_counters", &bind, base, COUNTERS);
                walker.record(&mut b, false, 0);
                walker.record(&mut b, false, 2);
                let (sec, out) = b.run_read(&[(&self.counters, 0, 4)])?;
                self.kernel_seconds += sec;
                stats.submissions += 1;
                stats.extra += 1;
                done = (0..2).any(|j| settled(&out[0], j, false));
            }
            let mut b = Batch::new(gpu);
            b.threads(kern, "clear_counters", &bind, base, COUNTERS);
            b.threads(kern, "commit", &bind, Params { slot: OPEN, ..base }, k);
            batch = Some(b);
        }
        let walks = walker.walks;
        stats.walks = walks as u64;
        self.stats.levels += stats.levels;
        self.stats.walks += stats.walks;
        self.stats.submissions += stats.submissions + 1;
        self.stats.contested += stats.contested;
        self.stats.extra += stats.extra;
        gpu.read(&self.labels, 0, self.t)
    }
}

/// Records the walks of one run, with their parities and stamps.
struct Walker<'b> {
    kern: &'b Kernels<Params>,
    bind: &'b wgpu::BindGroup,
    base: Params,
    k: usize,
    stride_groups: u32,
    /// Walks recorded so far (the next one's parity is `walks & 1`).
    walks: u32,
    /// The previous walk's stamp.
    last_code: Option<u32>,
    /// The first stamp.
    top: u32,
}

impl<'b> Walker<'b> {
    /// Records the next walk (a level's first when `first`: it reads no claims) counting changed
    /// clusters into `slot`, then `check` counting the clusters to redo into `slot + 1`.
    fn record(&mut self, b: &mut Batch<'b>, first: bool, slot: u32) {
        let par = self.walks & 1;
        let code = match self.last_code {
            None => self.top,
            Some(0) => {
                // Stamps ran out: the previous walk's claims move to top + 1, the rest go.
                let p = Params {
                    par,
                    code: 0,
                    first: self.top + 1,
                    ..self.base
                };
                b.groups(self.kern, "restamp", self.bind, p, self.stride_groups);
                self.top
            }
            Some(c) => c - 1,
        };
        let p = Params {
            first: first as u32,
            par,
            slot,
            code,
            ..self.base
        };
        b.threads(self.kern, "walk", self.bind, p, self.k);
        b.threads(
            self.kern,
            "check",
            self.bind,
            Params {
                slot: slot + 1,
                ..p
            },
            self.k,
        );
        self.walks += 1;
        self.last_code = Some(code);
    }
}
