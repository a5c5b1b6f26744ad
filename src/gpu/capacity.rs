//! The capacity-aware assignment of the default `kmedoids`
//! ([`crate::strategy::kmedoids_capacity::assign_capacity`]) as kernels (`wgsl/capacity.wgsl`),
//! with labels identical to the CPU's.
//!
//! The CPU takes each BFS level's clusters in ascending id, a cluster skipping what a lower one
//! took in the same level. Here every cluster walks its level at once and the level's walk is
//! repeated until no cluster's takes change, each walk skipping what a lower cluster claimed in
//! the one before: the fixed point of that iteration is the sequential order's result (the WGSL
//! file's header gives the argument). Per level the host records one walk, the `lost` test and
//! two spare walks, and reads their counters in one round trip; only a level whose conflicts
//! chain deeper costs more round trips.

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
    let (adj, _) = AdjacencyKernels::new(gpu).build(gpu, mesh)?;
    let mut a = CapacityAssign::new(gpu, mesh.triangle_count());
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
        /// Counter slots.
        counters: ReadWrite,
    }
}

/// Words of per-cluster state (`STATE` in the WGSL).
const STATE: usize = 6;
/// Counter slots (`clear_counters` clears this many).
const COUNTERS: usize = 8;
/// The slot `seed` and `commit` count open clusters into.
const OPEN: u32 = 7;
/// Walks recorded per level up front: the first, then two spares (a level whose first walk lost
/// nothing is done after one; one with conflicts usually after the second changes nothing).
const WALKS: u32 = 3;

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
}

/// The assignment kernels and the per-triangle buffers they reuse from run to run.
pub struct CapacityAssign {
    kernels: Kernels<Params>,
    labels: wgpu::Buffer,
    claim_a: wgpu::Buffer,
    claim_b: wgpu::Buffer,
    counters: wgpu::Buffer,
    t: usize,
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
                    "clear_claims",
                    "clear_counters",
                    "seed",
                    "walk",
                    "lost",
                    "commit",
                ],
            ),
            labels: gpu.zeros("capacity labels", t),
            claim_a: gpu.zeros("capacity claims a", t),
            claim_b: gpu.zeros("capacity claims b", t),
            counters: gpu.zeros("capacity counters", COUNTERS),
            t,
            kernel_seconds: 0.0,
            stats: AssignStats::default(),
        }
    }

    /// Whether `k` clusters' triangle and vertex lists fit one binding each.
    pub fn fits(k: usize, limits: Limits) -> bool {
        k * (limits.max_triangles.max(limits.max_vertices) as usize) <= PART
    }

    /// The labels [`crate::strategy::kmedoids_capacity::assign_capacity`] gives from `medoids`
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
                len: k * limits.max_triangles.max(limits.max_vertices) as usize,
                max: PART,
            });
        }
        self.stats.runs += 1;
        let (max_v, max_t) = (limits.max_vertices, limits.max_triangles);
        let medoid_buf = gpu.upload("capacity medoids", medoids);
        let ct = gpu.zeros("capacity cluster triangles", k * max_t as usize);
        let cv = gpu.zeros("capacity cluster vertices", k * max_v as usize);
        let state = gpu.zeros("capacity state", k * STATE);
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
        };
        let kern = &self.kernels;
        let t = self.t;
        let mut walks = 0u32;
        let walker = Walker {
            kern,
            bind: &bind,
            base,
            k,
            claim_groups: gpu.stride_groups(t),
        };
        // The first batch seeds the clusters; every later one commits the level before. Then
        // the level's walks.
        let mut b = Batch::new(gpu);
        b.threads(kern, "clear_counters", &bind, base, COUNTERS);
        b.groups(kern, "clear_labels", &bind, base, gpu.stride_groups(t));
        b.threads(kern, "seed", &bind, Params { slot: OPEN, ..base }, k);
        let mut batch = Some(b);
        let mut stats = AssignStats::default();
        while let Some(mut b) = batch.take() {
            // Slot 0: the first walk's `lost`; slots 1.. the spare walks' changes.
            walker.record(&mut b, &mut walks, true, 0);
            for s in 1..WALKS {
                walker.record(&mut b, &mut walks, false, s);
            }
            let (sec, out) = b.run_read(&[(&self.counters, 0, COUNTERS)])?;
            self.kernel_seconds += sec;
            stats.submissions += 1;
            let c = &out[0];
            if c[OPEN as usize] == 0 {
                break;
            }
            stats.levels += 1;
            let mut done = c[..WALKS as usize].contains(&0);
            while !done {
                let mut b = Batch::new(gpu);
                b.threads(kern, "clear_counters", &bind, base, COUNTERS);
                walker.record(&mut b, &mut walks, false, 0);
                walker.record(&mut b, &mut walks, false, 1);
                let (sec, out) = b.run_read(&[(&self.counters, 0, 2)])?;
                self.kernel_seconds += sec;
                stats.submissions += 1;
                done = out[0].contains(&0);
            }
            let mut b = Batch::new(gpu);
            b.threads(kern, "clear_counters", &bind, base, COUNTERS);
            b.threads(kern, "commit", &bind, Params { slot: OPEN, ..base }, k);
            batch = Some(b);
        }
        stats.walks = walks as u64;
        self.stats.levels += stats.levels;
        self.stats.walks += stats.walks;
        self.stats.submissions += stats.submissions + 1;
        gpu.read(&self.labels, 0, self.t)
    }
}

/// Records walks of one run.
struct Walker<'b> {
    kern: &'b Kernels<Params>,
    bind: &'b wgpu::BindGroup,
    base: Params,
    k: usize,
    claim_groups: u32,
}

impl<'b> Walker<'b> {
    /// Records walk number `*walks` counting into `slot` (and `lost` after a level's first walk).
    fn record(&self, b: &mut Batch<'b>, walks: &mut u32, first: bool, slot: u32) {
        let p = Params {
            first: first as u32,
            par: *walks & 1,
            slot,
            ..self.base
        };
        *walks += 1;
        b.groups(self.kern, "clear_claims", self.bind, p, self.claim_groups);
        b.threads(self.kern, "walk", self.bind, p, self.k);
        if first {
            b.threads(self.kern, "lost", self.bind, p, self.k);
        }
    }
}
