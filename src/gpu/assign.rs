//! The multi-source BFS of `wgsl/assign.wgsl` (`Bfs`, CPU reference
//! [`mod@crate::strategy::kmedoids::assign`]): `kmedoids-flat`'s assignment ([`super::kmedoids_flat`])
//! and the coarse regions' ([`super::coarse`]). Its parameter block is the one the flat method's
//! three kernel modules share.

use super::adjacency::DeviceAdjacency;
use super::{binding_set, param_block, wgsl, Batch, Gpu, GpuError, Kernels};

param_block! {
    /// `struct Params` of the k-medoids family: `wgsl/update.wgsl`, `assign.wgsl` and
    /// `split.wgsl` (one dispatch's parameters serve all three).
    pub struct Params {
        /// Triangles.
        t,
        /// Clusters.
        k,
        /// BFS level (assign's `push`).
        d,
        /// Counter slot this dispatch counts into.
        slot,
        /// Meshlet vertex limit.
        max_v,
        /// Meshlet triangle limit.
        max_t,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/assign.wgsl` (the multi-source BFS), in binding order.
    pub struct AssignBuffers {
        /// Dual-graph offsets.
        dual_off: Read,
        /// Dual-graph items, first part.
        dual_a: Read,
        /// Dual-graph items, second part.
        dual_b: Read,
        /// Out: cluster per triangle.
        labels: ReadWrite,
        /// Out: hop distance per triangle.
        dist: ReadWrite,
        /// Medoid per cluster.
        medoids: Read,
        /// Update counters and the frontier-size ring.
        counters: ReadWrite,
        /// Two frontier lists.
        frontier: ReadWrite,
    }
}

/// Frontier-size counters (a ring in `wgsl/assign.wgsl`, after [`SIZES`] update counters, which
/// `wgsl/update.wgsl` counts into).
pub(crate) const RING: usize = 64;
pub(crate) const SIZES: usize = 8;
pub(crate) const COUNTERS: usize = SIZES + RING;
/// Most BFS levels recorded in one submission (fewer than the ring, so no slot is reused before
/// the host reads it).
const MAX_LEVELS: usize = RING - 4;

/// The multi-source BFS of `wgsl/assign.wgsl` (CPU reference [`crate::strategy::kmedoids::assign`])
/// over its caller's label, distance and medoid buffers: many levels per submission, the frontier
/// sizes read back together, more levels recorded only when the frontier outlasts them.
pub(crate) struct Bfs<'a> {
    gpu: &'a Gpu,
    kernels: &'a Kernels<Params>,
    bind: wgpu::BindGroup,
    /// Update counters, then the frontier-size ring.
    pub(crate) counters: wgpu::Buffer,
    t: usize,
    /// BFS levels run in total.
    pub(crate) rounds: std::cell::Cell<u32>,
    /// See [`GpuClustering::deep_submissions`].
    pub(crate) deep: std::cell::Cell<u32>,
    /// BFS levels to record up front: the last assignment's depth plus two.
    levels: std::cell::Cell<usize>,
    /// Kernel seconds of every batch run through [`Bfs::run`].
    pub(crate) kernel: std::cell::Cell<f64>,
}

impl<'a> Bfs<'a> {
    /// A BFS over `adj`'s dual graph writing `labels` and `dist` (one word per triangle each)
    /// from the seeds in `medoids`; `counters` holds [`COUNTERS`] words.
    pub(crate) fn new(
        gpu: &'a Gpu,
        kernels: &'a Kernels<Params>,
        adj: &DeviceAdjacency,
        buffers: [&wgpu::Buffer; 3],
        counters: wgpu::Buffer,
    ) -> Self {
        let [labels, dist, medoids] = buffers;
        let frontier = gpu.zeros("frontier", 2 * adj.triangles);
        let bind = kernels.bind(
            gpu,
            &AssignBuffers {
                dual_off: &adj.dual_offsets,
                dual_a: &adj.dual_items.a,
                dual_b: &adj.dual_items.b,
                labels,
                dist,
                medoids,
                counters: &counters,
                frontier: &frontier,
            },
        );
        Self {
            gpu,
            kernels,
            bind,
            counters,
            t: adj.triangles,
            rounds: std::cell::Cell::new(0),
            deep: std::cell::Cell::new(0),
            levels: std::cell::Cell::new(16),
            kernel: std::cell::Cell::new(0.0),
        }
    }

    /// The assign kernels (cached per device).
    pub(crate) fn kernels(gpu: &Gpu) -> Kernels<Params> {
        Kernels::new::<AssignBuffers>(
            gpu,
            "assign",
            wgsl!("assign.wgsl"),
            &["clear", "seed", "push"],
        )
    }

    /// The counter words to allocate for [`Bfs::new`].
    pub(crate) const COUNTERS: usize = COUNTERS;

    fn params(&self, k: usize, d: u32) -> Params {
        Params {
            t: self.t as u32,
            k: k as u32,
            d,
            slot: 0,
            max_v: 0,
            max_t: 0,
        }
    }

    /// Records the multi-source BFS from the k medoids: clear, seed and the expected number of
    /// levels (the host checks the frontier sizes afterwards, [`Bfs::finish`]).
    pub(crate) fn record<'b>(&'b self, b: &mut Batch<'b>, k: usize) {
        let p = self.params(k, 0);
        b.groups(
            self.kernels,
            "clear",
            &self.bind,
            p,
            self.gpu.stride_groups(self.t),
        );
        b.groups(
            self.kernels,
            "seed",
            &self.bind,
            p,
            self.gpu.stride_groups(k),
        );
        self.record_levels(b, k, 0, self.levels.get().min(MAX_LEVELS));
    }

    pub(crate) fn record_levels<'b>(&'b self, b: &mut Batch<'b>, k: usize, from: usize, n: usize) {
        let groups = self.gpu.stride_groups(self.t);
        for d in from..from + n {
            b.groups(
                self.kernels,
                "push",
                &self.bind,
                self.params(k, d as u32),
                groups,
            );
        }
    }

    /// The multi-source BFS alone from the first `k` medoids; returns the number of unreached
    /// triangles.
    pub(crate) fn assign(&self, k: usize) -> Result<usize, GpuError> {
        let mut b = Batch::new(self.gpu);
        self.record(&mut b, k);
        Ok(self.finish(b, k)?.0)
    }

    /// Runs `b` (which ends with [`Bfs::record`]) and reads the update counters and the
    /// frontier sizes in the same round trip; records more levels while the frontier is not
    /// empty. Returns the unreached triangles and the counters.
    pub(crate) fn finish(&self, b: Batch<'_>, k: usize) -> Result<(usize, Vec<u32>), GpuError> {
        let counters = self.run(b, &[(&self.counters, 0, COUNTERS)])?.remove(0);
        let mut recorded = self.levels.get().min(MAX_LEVELS);
        let mut sizes = counters.clone();
        // Level d's frontier size is slot d % RING; level 0's is k.
        let mut reached = k;
        let mut d = 1;
        loop {
            if d > recorded {
                // Deeper than recorded: more levels, another round trip.
                let more = MAX_LEVELS;
                let mut b = Batch::new(self.gpu);
                self.record_levels(&mut b, k, recorded, more);
                sizes = self.run(b, &[(&self.counters, 0, COUNTERS)])?.remove(0);
                recorded += more;
                self.deep.set(self.deep.get() + 1);
            }
            let n = sizes[SIZES + d % RING] as usize;
            reached += n;
            if n == 0 {
                self.rounds.set(self.rounds.get() + d as u32);
                self.levels.set(d + 2);
                return Ok((self.t - reached, counters));
            }
            d += 1;
        }
    }

    /// Kernel seconds of every batch this BFS ran.
    pub(crate) fn kernel_seconds(&self) -> f64 {
        self.kernel.get()
    }

    /// Runs `b`, adding its kernel time, and returns the `reads`.
    pub(crate) fn run(
        &self,
        b: Batch<'_>,
        reads: &[(&wgpu::Buffer, usize, usize)],
    ) -> Result<Vec<Vec<u32>>, GpuError> {
        let (time, out) = b.run_read(reads)?;
        self.kernel.set(self.kernel.get() + time);
        Ok(out)
    }
}
