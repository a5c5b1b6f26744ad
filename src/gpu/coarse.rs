//! The coarse regions of the region-parallel k-medoids on the device (`wgsl/coarse.wgsl`, with
//! the Morton order of [`super::morton`] and the BFS of `wgsl/assign.wgsl`); the CPU reference is
//! [`crate::strategy::kmedoids::coarse`], and the regions and member lists are identical.
//!
//! Nothing the later kernels read comes back to the host. Host traffic: the box (six words) and
//! the seeds (one word per region, sorted on the host and written back), the BFS's frontier
//! sizes, and, where a piece of the mesh has no seed, one change count per eight hooking rounds.

use super::adjacency::{DeviceAdjacency, Timing};
use super::assign::Bfs;
use super::morton::{self, DeviceInput, PairSort};
use super::{binding_set, param_block, timed, wgsl, Batch, Gpu, GpuError, Kernels};
use crate::common::sorted;
use crate::strategy::kmedoids::coarse::{region_count, seed_rank};

param_block! {
    /// `struct Params` of `wgsl/coarse.wgsl`.
    pub struct Params {
        /// Triangles.
        t,
        /// Regions.
        k,
        /// Counter slot of a hooking round; in `offsets_of`, 1 where the sorted keys are in
        /// `sorted`.
        slot,
        /// Unused.
        pad,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/coarse.wgsl`, in binding order.
    pub struct Buffers {
        /// Dual-graph row starts.
        dual_off: Read,
        /// Dual-graph items, first part.
        dual_a: Read,
        /// Dual-graph items, second part.
        dual_b: Read,
        /// Triangles in Morton order.
        order: Read,
        /// First rank of each run, then the rank of each run's seed.
        runs: Read,
        /// BFS label per triangle.
        bfs: Read,
        /// Least Morton rank of each unreached triangle's piece.
        least: ReadWrite,
        /// Label changes per hooking round.
        counters: ReadWrite,
        /// Out: region per triangle.
        region: ReadWrite,
        /// Out: sort keys (regions).
        key: ReadWrite,
        /// Out: sort ids (triangles).
        id: ReadWrite,
        /// Sorted keys, where the sort ends in its own buffers.
        sorted: Read,
        /// Out: member offsets of the regions.
        offsets: ReadWrite,
    }
}

/// Hooking rounds per submission (the host reads their change counts once).
const ROUNDS: u32 = 8;

/// The regions of a mesh on the device, up to the last step: [`DeviceRegions::record`] adds the
/// regions themselves, their member lists and offsets to a batch of the caller's.
pub struct DeviceRegions {
    kernels: Kernels<Params>,
    bind: wgpu::BindGroup,
    sort: PairSort,
    ids: wgpu::Buffer,
    t: usize,
    /// Regions.
    pub count: usize,
    /// Upload, kernel and readback time so far.
    pub timing: Timing,
    /// Hooking rounds run for the pieces no seed reached (0 where every piece has a seed).
    pub piece_rounds: u32,
}

impl DeviceRegions {
    /// Runs steps 1-3 of [`crate::strategy::kmedoids::coarse::regions`] for regions of about
    /// `size` triangles over `mesh` and its adjacency `adj`, and binds step 4 to write the region
    /// of every triangle into `region` (words `0..T`) and the member offsets into `offsets`
    /// (words `0..=count`). With `centres`, the Morton pass also writes each triangle's packed
    /// centroid cell into that buffer from the given word on.
    pub fn new(
        gpu: &Gpu,
        mesh: DeviceInput<'_>,
        adj: &DeviceAdjacency,
        size: usize,
        out: [&wgpu::Buffer; 2],
        centres: Option<(&wgpu::Buffer, usize)>,
    ) -> Result<Self, GpuError> {
        let [region, offsets] = out;
        let t = adj.triangles;
        let k = region_count(t, size);
        // Step 1: the Morton order (left on the device) and the seeds (k words back).
        let seed_ranks: Vec<u32> = (0..k).map(|j| seed_rank(j, t, k) as u32).collect();
        // One region needs no order: every triangle is in it (only the cells, where asked for).
        let (mut ordered, mut timing) = if k > 1 {
            let o = morton::order(gpu, mesh, &seed_ranks, centres)?;
            let timing = o.timing;
            (Some(o), timing)
        } else {
            let timing = match centres {
                Some(c) => morton::cells(gpu, mesh, c)?,
                None => Timing::default(),
            };
            (None, timing)
        };
        // First rank of run j: the least i with i * k >= j * t.
        let runs: Vec<u32> = (0..k)
            .map(|j| (j as u64 * t as u64).div_ceil(k as u64) as u32)
            .chain(seed_ranks.iter().copied())
            .collect();
        let kernels = Kernels::new::<Buffers>(
            gpu,
            "coarse",
            wgsl!("coarse.wgsl"),
            &["piece_init", "piece_round", "finish", "offsets_of"],
        );
        let (bufs, up) = timed(|| {
            (
                gpu.upload("runs", &runs),
                gpu.zeros("bfs labels", if k > 1 { t } else { 1 }),
                gpu.zeros("least ranks", if k > 1 { t } else { 1 }),
                gpu.zeros("hooking counters", ROUNDS as usize),
                gpu.zeros("sort keys", t),
                gpu.zeros("sort ids", t),
            )
        });
        timing.upload += up;
        let (runs, bfs_labels, least, counters, keys, ids) = bufs;
        // Step 2: the multi-source BFS from the seeds in ascending order.
        let mut unreached = 0;
        if k > 1 {
            let assign = Bfs::kernels(gpu);
            let picked = ordered.as_mut().map(|o| std::mem::take(&mut o.picked));
            let (medoids, up) = timed(|| gpu.upload("seeds", &sorted(picked.unwrap_or_default())));
            timing.upload += up;
            let bfs = Bfs::new(
                gpu,
                &assign,
                adj,
                [&bfs_labels, &gpu.zeros("bfs distances", t), &medoids],
                gpu.zeros("bfs counters", Bfs::COUNTERS),
            );
            unreached = bfs.assign(k)?;
            timing.kernel += bfs.kernel_seconds();
        }
        let bits = u32::BITS - (k as u32 - 1).leading_zeros();
        let sort = PairSort::new(gpu, &keys, &ids, t, bits);
        let unused = gpu.zeros("unused", 1);
        let sorted_keys = sort.sorted().map_or(&unused, |(k, _)| k);
        let order = ordered.as_ref().map_or(&unused, |o| &o.order);
        let bind = kernels.bind(
            gpu,
            &Buffers {
                dual_off: &adj.dual_offsets,
                dual_a: &adj.dual_items.a,
                dual_b: &adj.dual_items.b,
                order,
                runs: &runs,
                bfs: &bfs_labels,
                least: &least,
                counters: &counters,
                region,
                key: &keys,
                id: &ids,
                sorted: sorted_keys,
                offsets,
            },
        );
        let mut regions = Self {
            kernels,
            bind,
            sort,
            ids,
            t,
            count: k,
            timing,
            piece_rounds: 0,
        };
        if unreached > 0 {
            regions.least_ranks(gpu, &counters)?;
        }
        Ok(regions)
    }

    fn params(&self, slot: u32) -> Params {
        Params {
            t: self.t as u32,
            k: self.count as u32,
            slot,
            pad: 0,
        }
    }

    /// Step 3: hooking rounds until one changes no label.
    fn least_ranks(&mut self, gpu: &Gpu, counters: &wgpu::Buffer) -> Result<(), GpuError> {
        for submission in 0.. {
            gpu.queue
                .write_buffer(counters, 0, bytemuck::cast_slice(&[0u32; ROUNDS as usize]));
            let mut b = Batch::new(gpu);
            if submission == 0 {
                b.threads(
                    &self.kernels,
                    "piece_init",
                    &self.bind,
                    self.params(0),
                    self.t,
                );
            }
            for r in 0..ROUNDS {
                b.threads(
                    &self.kernels,
                    "piece_round",
                    &self.bind,
                    self.params(r),
                    self.t,
                );
            }
            let (kernel, out) = b.run_read(&[(counters, 0, ROUNDS as usize)])?;
            self.timing.kernel += kernel;
            self.piece_rounds += ROUNDS;
            if out[0].contains(&0) {
                break;
            }
        }
        Ok(())
    }

    /// Records step 4 into `b`: every triangle's region, its members sorted by region, and the
    /// offsets.
    pub fn record<'b>(&'b self, b: &mut Batch<'b>) {
        b.threads(&self.kernels, "finish", &self.bind, self.params(0), self.t);
        self.sort.record(b);
        let slot = self.sort.sorted().is_some() as u32;
        b.threads(
            &self.kernels,
            "offsets_of",
            &self.bind,
            self.params(slot),
            self.t,
        );
    }

    /// The members of each region, ascending, once [`DeviceRegions::record`] has run.
    pub fn members(&self) -> &wgpu::Buffer {
        self.sort.sorted().map_or(&self.ids, |(_, ids)| ids)
    }
}
