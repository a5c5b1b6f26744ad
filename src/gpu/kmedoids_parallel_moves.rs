//! The boundary moves on the device (`wgsl/kmedoids_parallel_moves.wgsl`, with the shared medoid of
//! `wgsl/medoid.wgsl`): the medoid iteration of `kmedoids-parallel`. The CPU reference is
//! [`crate::strategy::kmedoids::parallel::moves`]; labels, distances, medoids and the counters of
//! [`Moves`] are identical.
//!
//! Every round is a fixed sequence of dispatches recorded into the caller's batch, so the moves
//! add no host round trip: the counters (objective before, triangles moved per round, clusters
//! changed) come back with whatever the caller reads next.

use super::adjacency::DeviceAdjacency;
use super::scan::ScanJob;
use super::{binding_set, param_block, wgsl, Batch, Gpu, GpuError, Kernels, Scan};
use crate::meshlet::Limits;
use crate::strategy::kmedoids::parallel::moves::Moves;

param_block! {
    /// `struct Params` of `wgsl/kmedoids_parallel_moves.wgsl`.
    pub struct Params {
        /// Triangles.
        t,
        /// Clusters.
        k,
        /// Vertex limit.
        max_v,
        /// Triangle limit.
        max_t,
        /// The round (`u32::MAX` in the pass after the last).
        round,
        /// Where the medoids start in `info`.
        medoid_at,
        /// Where the centroid cells start in `centres`.
        centres_at,
        /// Unused.
        pad,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/kmedoids_parallel_moves.wgsl`, in binding order.
    pub struct Buffers {
        adjacency;
        /// Cluster of each triangle.
        labels: ReadWrite,
        /// Hop distance to the medoid.
        dist: ReadWrite,
        /// Per-triangle scratch (seven sections of T).
        arena: ReadWrite,
        /// The medoid's scratch (nine words per triangle).
        cstate: ReadWrite,
        /// Per-cluster sums and flags, then the counters.
        state: ReadWrite,
        /// The medoids at `medoid_at`.
        info: ReadWrite,
        /// The triangles' packed centroid cells (two words each) at `centres_at`.
        centres: Read,
    }
}

/// A clustering on the device, as the moves read and update it.
pub struct DeviceClusters<'a> {
    /// Labels (T words).
    pub labels: &'a wgpu::Buffer,
    /// Hop distances to the medoids (T words).
    pub dist: &'a wgpu::Buffer,
    /// The medoids, at word `medoid_at`.
    pub info: &'a wgpu::Buffer,
    /// Where the medoids start in `info`.
    pub medoid_at: usize,
    /// Clusters.
    pub k: usize,
    /// Scratch of at least 7 T words.
    pub arena: &'a wgpu::Buffer,
    /// Scratch of at least 9 T words.
    pub cstate: &'a wgpu::Buffer,
    /// The triangles' packed centroid cells (`strategy::kmedoids::morton::packed_centres`), two
    /// words each from word `centres_at`: step 2's distance rule reads them.
    pub centres: &'a wgpu::Buffer,
    /// Where the cells start in `centres`.
    pub centres_at: usize,
}

/// The moves of one clustering, bound and ready to record.
pub struct DeviceMoves {
    kernels: Kernels<Params>,
    scan: Scan,
    bind: wgpu::BindGroup,
    lists: ScanJob,
    state: wgpu::Buffer,
    params: Params,
    rounds: u32,
}

impl DeviceMoves {
    /// Binds at most `rounds` rounds over `c` (`rounds` > 0) on the mesh of `adj`.
    pub fn new(
        gpu: &Gpu,
        adj: &DeviceAdjacency,
        c: &DeviceClusters<'_>,
        limits: Limits,
        rounds: u32,
    ) -> Result<Self, GpuError> {
        let t = adj.indices.len / 3;
        let state_len = 7 * (c.k + 1) + 3 + rounds as usize;
        let max = gpu.binding_words();
        if state_len > max {
            return Err(GpuError::TooLarge {
                what: "the moves' cluster state",
                len: state_len,
                max,
            });
        }
        let kernels = Kernels::new::<Buffers>(
            gpu,
            "moves",
            wgsl!("kmedoids_parallel_moves.wgsl", "medoid.wgsl"),
            &[
                "tally",
                "count_members",
                "place",
                "settle",
                "candidates",
                "propose",
                "pick_best",
                "accept",
                "new_medoids",
            ],
        );
        let state = gpu.zeros("moves' cluster state", state_len);
        let bind = kernels.bind(
            gpu,
            &Buffers {
                adj,
                labels: c.labels,
                dist: c.dist,
                arena: c.arena,
                cstate: c.cstate,
                state: &state,
                info: c.info,
                centres: c.centres,
            },
        );
        let scan = Scan::new(gpu);
        let lists = scan.bind(gpu, &state, c.k + 1);
        let params = Params {
            t: t as u32,
            k: c.k as u32,
            max_v: limits.max_vertices,
            max_t: limits.max_triangles,
            round: 0,
            medoid_at: c.medoid_at as u32,
            centres_at: c.centres_at as u32,
            pad: 0,
        };
        Ok(Self {
            kernels,
            scan,
            bind,
            lists,
            state,
            params,
            rounds,
        })
    }

    /// Records every round and the medoids after them into `b`.
    pub fn record<'a>(&'a self, b: &mut Batch<'a>) {
        let (t, k) = (self.params.t as usize, self.params.k as usize);
        let (kn, bind) = (&self.kernels, &self.bind);
        let at = |round| Params {
            round,
            ..self.params
        };
        let lists = |b: &mut Batch<'a>, round| {
            b.threads(kn, "tally", bind, at(round), k + 1);
            b.threads(kn, "count_members", bind, at(round), t);
            self.scan.record(b, &self.lists);
            b.threads(kn, "place", bind, at(round), t);
        };
        for round in 0..self.rounds {
            lists(b, round);
            if round > 0 {
                b.threads(kn, "settle", bind, at(round), k);
            }
            for entry in ["candidates", "propose", "pick_best", "accept"] {
                b.threads(kn, entry, bind, at(round), t);
            }
        }
        // NONE: no round, only the lists.
        lists(b, u32::MAX);
        b.threads(kn, "new_medoids", bind, at(u32::MAX), k);
    }

    /// The counters' words, to read after the batch: `(buffer, offset, len)` in u32.
    pub fn counters(&self) -> (&wgpu::Buffer, usize, usize) {
        let at = 7 * (self.params.k as usize + 1);
        (&self.state, at, 3 + self.rounds as usize)
    }

    /// What the moves did, from the counters' words.
    pub fn moves(&self, words: &[u32]) -> Moves {
        let sum = u64::from(words[0]) | u64::from(words[1]) << 32;
        let moved = &words[3..];
        Moves {
            rounds: moved.iter().filter(|&&m| m > 0).count() as u32,
            moved: moved.iter().map(|&m| u64::from(m)).sum(),
            changed: words[2] as usize,
            objective_before: sum as f64 / f64::from(self.params.t.max(1)),
        }
    }
}
