//! `kmedoids-flat` on the GPU, the baseline data-parallel k-medoids: [`cluster`] runs it step
//! for step as its CPU reference ([`crate::strategy::kmedoids::flat`]) with `wgsl/assign.wgsl`
//! ([`super::assign`]), `wgsl/update.wgsl` and `wgsl/split.wgsl`, with identical medoids, labels,
//! distances, iteration and split counts and meshlets.
//!
//! The loop is driven from the host, but the per-triangle data (dual graph, labels, distances,
//! members) stays on the GPU. One iteration (medoid update, then assignment) is one submission and
//! one host round trip: the host records as many BFS levels as the last assignment needed plus
//! two, and reads the convergence counters and the frontier sizes together; only a deeper
//! assignment costs another round trip. Per split round the host reads per-cluster counts
//! (O(clusters)); labels and distances come back once, at the end, to pack meshlets.
//!
//! Where the CPU caches updates by member list, the GPU marks the clusters whose members changed
//! (`dirty_mark`) and updates only those: same results, same skipped work.

use super::adjacency::{AdjacencyKernels, DeviceAdjacency, Timing};
use super::assemble::{Assembly, DeviceMeshlets, Groups};
use super::assign::{Bfs, Params, COUNTERS};
use super::morton::{self, DeviceInput};
use super::scan::ScanJob;
use super::source::{MeshSource, Placed};
use super::{binding_set, timed, timed_read, wgsl, Batch, Gpu, GpuError, Kernels, Scan, PART};
use crate::adjacency::Csr;
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use crate::strategy::kmedoids::flat::{add_component_medoids, cluster_size, Config};
use crate::strategy::kmedoids::split::{overflowing_from_counts, split_choice};
use crate::strategy::kmedoids::{Clustering, Mode};
use std::time::Instant;

binding_set! {
    /// The storage buffers of `wgsl/update.wgsl` (the medoid update), in binding order.
    pub struct UpdateBuffers {
        /// Dual-graph offsets.
        dual_off: Read,
        /// Dual-graph items, first part.
        dual_a: Read,
        /// Dual-graph items, second part.
        dual_b: Read,
        /// Cluster per triangle.
        labels: Read,
        /// Hop distance to its medoid per triangle.
        dist: Read,
        /// Medoid per cluster (`place` writes the new ones).
        medoids: ReadWrite,
        /// Update counters (shared with assign's frontier ring).
        counters: ReadWrite,
        /// Member offsets per cluster.
        mem_off: ReadWrite,
        /// Members, cluster by cluster.
        mem_items: ReadWrite,
        /// Scatter cursor per cluster.
        cursor: ReadWrite,
        /// New medoid, shift and split statistics per cluster.
        result: ReadWrite,
        /// Changed-cluster and new-medoid flags (scanned).
        flags: ReadWrite,
        /// The large-cluster fallback's BFS distance and queue.
        scratch: ReadWrite,
        /// Each triangle's medoid at the last update, then the dirty flags.
        prev: ReadWrite,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/split.wgsl` (split statistics), in binding order.
    pub struct SplitBuffers {
        /// Member offsets per cluster.
        mem_off: Read,
        /// Members, cluster by cluster.
        mem_items: Read,
        /// Cluster per triangle.
        labels: Read,
        /// Hop distance per triangle.
        dist: Read,
        /// Out: distinct vertices and farthest member per cluster.
        result: ReadWrite,
        /// Index buffer, first part.
        idx_a: Read,
        /// Index buffer, second part.
        idx_b: Read,
        /// Vertex -> triangle offsets.
        vt_off: Read,
        /// Vertex -> triangle items, first part.
        vt_a: Read,
        /// Vertex -> triangle items, second part.
        vt_b: Read,
    }
}

/// Update counters (see `wgsl/update.wgsl`): shift sum, medoids changed, one-thread updates,
/// updates skipped as unchanged.
const SHIFT: usize = 0;
const CHANGED: usize = 1;
const LARGE: usize = 2;
const SKIPPED: usize = 3;
/// A GPU k-medoids run: the same [`Clustering`] as the CPU, plus GPU facts.
pub struct GpuClustering {
    /// The result (its `initial_seconds` is wall time on the host, as on the CPU).
    pub clustering: Clustering,
    /// Upload, kernel and readback time of the whole run, adjacency included.
    pub timing: Timing,
    /// Of which the adjacency kernels.
    pub adjacency_kernel: f64,
    /// Cluster updates that took the one-thread path (over 256 members or a dense local graph).
    pub large_updates: u32,
    /// BFS levels run in total (dispatches of `push` that had a frontier; in capacity mode the
    /// capacity-aware assignment's levels).
    pub bfs_rounds: u32,
    /// Extra submissions for assignments deeper than the levels recorded up front (each one a
    /// host round trip beyond the one per iteration).
    pub deep_submissions: u32,
    /// Cluster updates over all iterations (clusters times iterations), the skipped ones
    /// (`clustering.skipped_updates`) included.
    pub updates: u64,
    /// Wall time of the whole run in seconds.
    pub seconds: f64,
}

/// Per cluster: triangles, distinct vertices, farthest member.
type ClusterStats = (Vec<u32>, Vec<u32>, Vec<u32>);

/// The three kernel modules of a run.
struct Family<'a> {
    update: &'a Kernels<Params>,
    assign: &'a Kernels<Params>,
    split: &'a Kernels<Params>,
}

struct Run<'a> {
    gpu: &'a Gpu,
    family: Family<'a>,
    scan: &'a Scan,
    bind: wgpu::BindGroup,
    /// The assignment, over `labels`, `dist`, `medoids` and its counters (shared with update).
    bfs: Bfs<'a>,
    split_bind: wgpu::BindGroup,
    labels: wgpu::Buffer,
    dist: wgpu::Buffer,
    medoids: wgpu::Buffer,
    mem_off: wgpu::Buffer,
    result: wgpu::Buffer,
    scratch: wgpu::Buffer,
    t: usize,
    k_cap: usize,
    limits: Limits,
    timing: Timing,
    readback: std::cell::Cell<f64>,
    /// Scan of the medoid flags (length T + 1: fixed for the run).
    flag_scan: ScanJob,
    /// Scan of the member offsets, for the cluster count it was bound for (changes per split).
    mem_scan: Option<(usize, ScanJob)>,
    large: u32,
    updates: u64,
    skipped: u64,
}

/// The update kernels' entry points.
const UPDATE_ENTRIES: &[&str] = &[
    "clear_counters",
    "dirty_clear",
    "medoid_index",
    "dirty_mark",
    "remember",
    "mem_clear",
    "mem_count",
    "mem_scatter",
    "update",
    "mark_clear",
    "mark",
    "place",
    "dist_partial",
];

/// The kernel modules of the k-medoids family.
struct Modules {
    update: Kernels<Params>,
    assign: Kernels<Params>,
    split: Kernels<Params>,
    scan: Scan,
}

impl Modules {
    fn new(gpu: &Gpu) -> Self {
        // One SIMD row per update workgroup on lavapipe (see `UW` in the WGSL).
        let uw = if gpu.is_cpu() { 8.0 } else { 64.0 };
        Self {
            update: Kernels::with_constants::<UpdateBuffers>(
                gpu,
                "kmedoids",
                wgsl!("update.wgsl"),
                UPDATE_ENTRIES,
                &[("UW", uw)],
            ),
            assign: Bfs::kernels(gpu),
            split: Kernels::new::<SplitBuffers>(gpu, "split", wgsl!("split.wgsl"), &["stats"]),
            scan: Scan::new(gpu),
        }
    }

    fn family(&self) -> (Family<'_>, &Scan) {
        (
            Family {
                update: &self.update,
                assign: &self.assign,
                split: &self.split,
            },
            &self.scan,
        )
    }
}

/// Checks that `t` triangles fit the k-medoids buffers (two words per triangle in one binding).
fn check_triangles(t: usize) -> Result<(), GpuError> {
    if 2 * t > PART {
        return Err(GpuError::TooLarge {
            what: "k-medoids triangles",
            len: t,
            max: PART / 2,
        });
    }
    Ok(())
}

/// Runs the flat k-medoids (`kmedoids-flat`) on the GPU; `cfg`'s flat settings apply.
pub fn cluster(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    cfg: &Config,
) -> Result<GpuClustering, GpuError> {
    cluster_with(gpu, MeshSource::Host(mesh), limits, cfg, true).map(|(c, _)| c)
}

/// [`cluster`] that also returns the meshlets on the device (`wgsl/assemble.wgsl`); with
/// `read_back` false the labels, distances and meshlets are not read (left empty).
pub fn cluster_with(
    gpu: &Gpu,
    source: MeshSource<'_>,
    limits: Limits,
    cfg: &Config,
    read_back: bool,
) -> Result<(GpuClustering, DeviceMeshlets), GpuError> {
    let start = Instant::now();
    let (t, n) = source.counts();
    check_triangles(t)?;
    let Placed {
        indices,
        positions,
        upload,
        ..
    } = source.place(gpu)?;
    let (adj, mut adj_timing) = AdjacencyKernels::new(gpu).build_from(gpu, indices, n)?;
    adj_timing.upload += upload;
    // The seeds on the device, identical to `flat::initial_medoids`.
    let (mut medoids, seed_timing) = morton::initial_medoids(
        gpu,
        DeviceInput {
            positions: &positions,
            vertices: n,
            indices: &adj.indices,
        },
        cluster_size(limits, Mode::Flat),
    )?;
    adj_timing.upload += seed_timing.upload;
    adj_timing.kernel += seed_timing.kernel;
    adj_timing.readback += seed_timing.readback;
    let modules = Modules::new(gpu);
    let (family, scan) = modules.family();
    let mut run = Run::new(gpu, family, scan, &adj, limits, adj_timing)?;

    let mut host_dual: Option<Csr> = None;
    loop {
        run.upload_medoids(&medoids)?;
        if run.assign(medoids.len())? == 0 {
            break;
        }
        // Components without a medoid (rare): the host floods them, as the CPU does.
        let labels = run.read(&run.labels, 0, t)?;
        if host_dual.is_none() {
            host_dual = Some(adj.read_dual(gpu)?);
        }
        add_component_medoids(host_dual.as_ref().expect("read"), &labels, &mut medoids);
    }
    let mut iterations = 0;
    medoids = run.converge(
        medoids,
        cfg.max_iterations,
        cfg.shift_threshold,
        &mut iterations,
    )?;
    let initial_iterations = iterations;
    let initial_seconds = start.elapsed().as_secs_f64();
    let initial_mean_distance = run.distance_sum()? as f64 / t.max(1) as f64;

    let mut splits = 0;
    for _round in 0..10_000 {
        let k = medoids.len();
        let (triangles, vertices, far) = run.stats(k)?;
        let over = overflowing_from_counts(&triangles, &vertices, limits);
        if over.is_empty() {
            break;
        }
        medoids.extend(
            split_choice(over, cfg.split_fraction)
                .into_iter()
                .map(|c| far[c as usize]),
        );
        medoids.sort_unstable();
        medoids.dedup();
        run.upload_medoids(&medoids)?;
        run.assign(medoids.len())?;
        medoids = run.converge(
            medoids,
            cfg.split_iterations,
            cfg.shift_threshold,
            &mut iterations,
        )?;
        splits += 1;
    }
    // Each cluster in BFS order from its medoid, as the CPU's `pack`.
    let groups = Groups {
        owner: &run.labels,
        key: &run.dist,
        count: medoids.len(),
    };
    let (device, assembly) = Assembly::new(gpu).run(gpu, scan, &adj.indices, groups, limits)?;
    run.bfs.kernel.set(run.bfs.kernel.get() + assembly);
    let (labels, distances, meshlets) = if read_back {
        (
            run.read(&run.labels, 0, t)?,
            run.read(&run.dist, 0, t)?,
            timed_read(&mut run.timing, || device.read(gpu))?,
        )
    } else {
        Default::default()
    };
    let clustering = GpuClustering {
        clustering: Clustering {
            medoids,
            labels,
            distances,
            iterations,
            splits,
            budget_exhausted: false,
            initial_mean_distance,
            initial_iterations,
            initial_seconds,
            skipped_updates: run.skipped as u32,
            meshlets,
        },
        timing: Timing {
            readback: run.timing.readback + run.readback.get(),
            kernel: run.timing.kernel + run.bfs.kernel.get(),
            ..run.timing
        },
        adjacency_kernel: adj_timing.kernel,
        large_updates: run.large,
        bfs_rounds: run.bfs.rounds.get(),
        deep_submissions: run.bfs.deep.get(),
        updates: run.updates,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok((clustering, device))
}

impl<'a> Run<'a> {
    fn new(
        gpu: &'a Gpu,
        family: Family<'a>,
        scan: &'a Scan,
        adj: &DeviceAdjacency,
        limits: Limits,
        adj_timing: Timing,
    ) -> Result<Self, GpuError> {
        let t = adj.triangles;
        // Cluster capacity: every triangle could be a cluster, but the result buffer holds 4 words
        // per cluster in one binding.
        let k_cap = t.clamp(1, PART / 4);
        let ((labels, dist, medoids, counters, mem_off, cursor, result, flags, scratch), up) =
            timed(|| {
                (
                    gpu.zeros("labels", t),
                    gpu.zeros("dist", t),
                    gpu.zeros("medoids", k_cap),
                    gpu.zeros("counters", COUNTERS),
                    gpu.zeros("member offsets", k_cap + 1),
                    gpu.zeros("member cursor", k_cap),
                    gpu.zeros("result", 4 * k_cap),
                    gpu.zeros("flags", t + 1),
                    gpu.zeros("scratch", 2 * t),
                )
            });
        let mem_items = gpu.zeros("members", t);
        // No triangle remembers a medoid before the first update, so dirty_mark finds every
        // cluster changed (the flags after T are written before they are read).
        let prev = gpu.upload("previous medoids", &vec![u32::MAX; t + k_cap]);
        let bind = family.update.bind(
            gpu,
            &UpdateBuffers {
                dual_off: &adj.dual_offsets,
                dual_a: &adj.dual_items.a,
                dual_b: &adj.dual_items.b,
                labels: &labels,
                dist: &dist,
                medoids: &medoids,
                counters: &counters,
                mem_off: &mem_off,
                mem_items: &mem_items,
                cursor: &cursor,
                result: &result,
                flags: &flags,
                scratch: &scratch,
                prev: &prev,
            },
        );
        let split_bind = family.split.bind(
            gpu,
            &SplitBuffers {
                mem_off: &mem_off,
                mem_items: &mem_items,
                labels: &labels,
                dist: &dist,
                result: &result,
                idx_a: &adj.indices.a,
                idx_b: &adj.indices.b,
                vt_off: &adj.vt_offsets,
                vt_a: &adj.vt_items.a,
                vt_b: &adj.vt_items.b,
            },
        );
        let bfs = Bfs::new(
            gpu,
            family.assign,
            adj,
            [&labels, &dist, &medoids],
            counters,
        );
        let flag_scan = scan.bind(gpu, &flags, t + 1);
        Ok(Self {
            gpu,
            family,
            scan,
            bind,
            bfs,
            split_bind,
            labels,
            dist,
            medoids,
            mem_off,
            result,
            scratch,
            t,
            k_cap,
            limits,
            // The run's times start with the adjacency's.
            timing: Timing {
                upload: adj_timing.upload + up,
                ..adj_timing
            },
            readback: std::cell::Cell::new(0.0),
            flag_scan,
            mem_scan: None,
            large: 0,
            updates: 0,
            skipped: 0,
        })
    }

    fn params(&self, k: usize, d: u32, slot: u32) -> Params {
        Params {
            t: self.t as u32,
            k: k as u32,
            d,
            slot,
            max_v: self.limits.max_vertices,
            max_t: self.limits.max_triangles,
        }
    }

    fn read(&self, buf: &wgpu::Buffer, offset: usize, len: usize) -> Result<Vec<u32>, GpuError> {
        let (r, s) = timed(|| self.gpu.read(buf, offset, len));
        self.readback.set(self.readback.get() + s);
        r
    }

    fn upload_medoids(&mut self, medoids: &[u32]) -> Result<(), GpuError> {
        if medoids.len() > self.k_cap {
            return Err(GpuError::TooLarge {
                what: "k-medoids clusters",
                len: medoids.len(),
                max: self.k_cap,
            });
        }
        let (_, s) = timed(|| {
            self.gpu
                .queue
                .write_buffer(&self.medoids, 0, bytemuck::cast_slice(medoids))
        });
        self.timing.upload += s;
        Ok(())
    }

    /// The multi-source BFS alone; returns the number of unreached triangles.
    fn assign(&self, k: usize) -> Result<usize, GpuError> {
        self.bfs.assign(k)
    }

    /// Runs `b`, adding its kernel time, and returns the `reads`.
    fn run(
        &self,
        b: Batch<'_>,
        reads: &[(&wgpu::Buffer, usize, usize)],
    ) -> Result<Vec<Vec<u32>>, GpuError> {
        self.bfs.run(b, reads)
    }

    /// Members CSR of the current labels (recorded into `b`).
    fn record_members<'b>(&'b self, b: &mut Batch<'b>, k: usize, job: &'b ScanJob) {
        let (kern, bind, t) = (self.family.update, &self.bind, self.t);
        b.threads(kern, "mem_clear", bind, self.params(k, 0, 0), k + 1);
        b.threads(kern, "mem_count", bind, self.params(k, 0, 0), t);
        self.scan.record(b, job);
        b.threads(kern, "mem_scatter", bind, self.params(k, 0, 0), t);
    }

    /// Binds the member-offset scan for `k` clusters (once per cluster count).
    fn bind_mem_scan(&mut self, k: usize) {
        if self.mem_scan.as_ref().is_none_or(|(n, _)| *n != k) {
            self.mem_scan = Some((k, self.scan.bind(self.gpu, &self.mem_off, k + 1)));
        }
    }

    /// One iteration as one submission: which clusters changed, the medoid update, the medoid
    /// sort, then the assignment. Returns (shift sum, medoids changed).
    fn iterate(&mut self, k: usize) -> Result<(u64, u32), GpuError> {
        self.bind_mem_scan(k);
        let (kern, bind, t) = (self.family.update, &self.bind, self.t);
        let mem_scan = &self.mem_scan.as_ref().expect("bound").1;
        let p = self.params(k, 0, 0);
        let mut b = Batch::new(self.gpu);
        b.threads(kern, "clear_counters", bind, p, COUNTERS);
        b.threads(kern, "dirty_clear", bind, p, k);
        b.threads(kern, "medoid_index", bind, p, k);
        b.threads(kern, "dirty_mark", bind, p, t);
        self.record_members(&mut b, k, mem_scan);
        b.groups(kern, "update", bind, p, k as u32);
        b.threads(kern, "mark_clear", bind, p, t + 1);
        b.threads(kern, "mark", bind, p, k);
        self.scan.record(&mut b, &self.flag_scan);
        b.threads(kern, "place", bind, p, k);
        b.threads(kern, "remember", bind, p, t);
        self.bfs.record(&mut b, k);
        let (_, c) = self.bfs.finish(b, k)?;
        self.large += c[LARGE];
        self.updates += k as u64;
        self.skipped += c[SKIPPED] as u64;
        Ok((c[SHIFT] as u64, c[CHANGED]))
    }

    /// The CPU's `converge` after its first assign (already run): update, sort, assign, until no
    /// medoid moves, the mean shift is at most `threshold`, or `max_iter`.
    fn converge(
        &mut self,
        medoids: Vec<u32>,
        max_iter: u32,
        threshold: f64,
        iterations: &mut u32,
    ) -> Result<Vec<u32>, GpuError> {
        let k = medoids.len();
        let mut moved = false;
        for _ in 0..max_iter {
            let (shift, changed) = self.iterate(k)?;
            *iterations += 1;
            moved = true;
            let mean_shift = shift as f64 / k.max(1) as f64;
            if changed == 0 || mean_shift <= threshold {
                break;
            }
        }
        if !moved {
            return Ok(medoids);
        }
        self.read(&self.medoids, 0, k)
    }

    /// Sum of hop distances (the k-medoids objective times T).
    fn distance_sum(&mut self) -> Result<u64, GpuError> {
        let groups = self.t.div_ceil(super::WG as usize);
        let mut b = Batch::new(self.gpu);
        let p = self.params(0, 0, 0);
        b.threads(self.family.update, "dist_partial", &self.bind, p, self.t);
        let parts = self.run(b, &[(&self.scratch, 0, groups)])?;
        Ok(parts[0].iter().map(|&x| x as u64).sum())
    }

    /// Per cluster: triangles, distinct vertices (within the triangle limit), farthest member.
    fn stats(&mut self, k: usize) -> Result<ClusterStats, GpuError> {
        self.bind_mem_scan(k);
        let mem_scan = &self.mem_scan.as_ref().expect("bound").1;
        let mut b = Batch::new(self.gpu);
        self.record_members(&mut b, k, mem_scan);
        let p = self.params(k, 0, 0);
        b.threads(self.family.split, "stats", &self.split_bind, p, k);
        let out = self.run(
            b,
            &[(&self.mem_off, 0, k + 1), (&self.result, 2 * k, 2 * k)],
        )?;
        let (off, r) = (&out[0], &out[1]);
        let triangles = off.windows(2).map(|w| w[1] - w[0]).collect();
        Ok((triangles, r[..k].to_vec(), r[k..].to_vec()))
    }
}
