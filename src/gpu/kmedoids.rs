//! k-medoids on the GPU (`wgsl/kmedoids.wgsl`), step for step the CPU reference
//! [`crate::strategy::kmedoids::cluster`] in fast mode, with identical medoids, labels, distances,
//! iteration and split counts and meshlets.
//!
//! The loop is driven from the host, but the per-triangle data (dual graph, labels, distances,
//! members) stays on the GPU. Per BFS batch the host reads 8 round counters; per iteration 3
//! counters; per split round the per-cluster counts (O(clusters)); labels and distances come back
//! once, at the end, to pack meshlets.

use super::adjacency::{AdjacencyKernels, DeviceAdjacency, Timing};
use super::scan::ScanJob;
use super::{timed, Batch, Gpu, GpuError, Kernels, Params, Scan, PART};
use crate::adjacency::Csr;
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use crate::strategy::kmedoids::{
    add_component_medoids, cluster_size, initial_medoids, overflowing_from_counts, pack,
    split_choice, Clustering, Config, Mode,
};
use std::time::Instant;

/// BFS rounds recorded per submission (their update counters come back together).
const ROUNDS: usize = 8;
const COUNTERS: usize = 8 + ROUNDS;

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
    /// BFS rounds run in total.
    pub bfs_rounds: u32,
    /// Wall time of the whole run in seconds.
    pub seconds: f64,
}

/// Per cluster: triangles, distinct vertices, farthest member.
type ClusterStats = (Vec<u32>, Vec<u32>, Vec<u32>);

struct Run<'a> {
    gpu: &'a Gpu,
    kernels: &'a Kernels,
    scan: &'a Scan,
    bind: wgpu::BindGroup,
    labels: wgpu::Buffer,
    dist: wgpu::Buffer,
    medoids: wgpu::Buffer,
    counters: wgpu::Buffer,
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
    rounds: u32,
}

/// Runs fast-mode k-medoids on the GPU.
pub fn cluster(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    cfg: &Config,
) -> Result<GpuClustering, GpuError> {
    if cfg.mode != Mode::Fast {
        return Err(GpuError::Unsupported(
            "the GPU runs fast-mode k-medoids; paper mode is CPU-only",
        ));
    }
    let start = Instant::now();
    let t = mesh.triangle_count();
    if 2 * t > PART {
        return Err(GpuError::TooLarge {
            what: "k-medoids triangles",
            len: t,
            max: PART / 2,
        });
    }
    let ak = AdjacencyKernels::new(gpu);
    let (adj, adj_timing) = ak.build(gpu, mesh)?;
    let kernels = Kernels::new(
        gpu,
        "kmedoids",
        include_str!("../../wgsl/kmedoids.wgsl"),
        15,
        &[
            "clear",
            "clear_counters",
            "seed",
            "bfs_round",
            "mem_clear",
            "mem_count",
            "mem_scatter",
            "update",
            "mark_clear",
            "mark",
            "place",
            "stats",
            "dist_partial",
        ],
    );
    let scan = Scan::new(gpu);
    let mut run = Run::new(gpu, &kernels, &scan, &adj, limits)?;
    run.timing.upload += adj_timing.upload;
    run.timing.kernel += adj_timing.kernel;
    run.timing.readback += adj_timing.readback;

    let mut medoids = initial_medoids(mesh, cluster_size(limits, Mode::Fast));
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
    let labels = run.read(&run.labels, 0, t)?;
    let distances = run.read(&run.dist, 0, t)?;
    let meshlets = pack(mesh, &labels, &distances, medoids.len(), limits);
    Ok(GpuClustering {
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
            meshlets,
        },
        timing: Timing {
            readback: run.timing.readback + run.readback.get(),
            ..run.timing
        },
        adjacency_kernel: adj_timing.kernel,
        large_updates: run.large,
        bfs_rounds: run.rounds,
        seconds: start.elapsed().as_secs_f64(),
    })
}

impl<'a> Run<'a> {
    fn new(
        gpu: &'a Gpu,
        kernels: &'a Kernels,
        scan: &'a Scan,
        adj: &DeviceAdjacency,
        limits: Limits,
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
        let bind = kernels.bind(
            gpu,
            &[
                &adj.dual_offsets,
                &adj.dual_items.a,
                &adj.dual_items.b,
                &labels,
                &dist,
                &medoids,
                &counters,
                &mem_off,
                &mem_items,
                &cursor,
                &result,
                &flags,
                &scratch,
                &adj.indices.a,
                &adj.indices.b,
            ],
        );
        let flag_scan = scan.bind(gpu, &flags, t + 1);
        Ok(Self {
            gpu,
            kernels,
            scan,
            bind,
            labels,
            dist,
            medoids,
            counters,
            mem_off,
            result,
            scratch,
            t,
            k_cap,
            limits,
            timing: Timing {
                upload: up,
                ..Timing::default()
            },
            readback: std::cell::Cell::new(0.0),
            flag_scan,
            mem_scan: None,
            large: 0,
            rounds: 0,
        })
    }

    fn params(&self, k: usize, d: u32, slot: u32) -> Params {
        Params {
            w: [
                self.t as u32,
                k as u32,
                d,
                slot,
                self.limits.max_vertices,
                self.limits.max_triangles,
                0,
                0,
            ],
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

    /// Multi-source BFS from the k medoids on the GPU; returns the number of unreached triangles.
    fn assign(&mut self, k: usize) -> Result<usize, GpuError> {
        let (kern, bind, t) = (self.kernels, &self.bind, self.t);
        let mut b = Batch::new(self.gpu);
        b.threads(kern, "clear", bind, self.params(k, 0, 0), t);
        b.threads(kern, "seed", bind, self.params(k, 0, 0), k);
        self.timing.kernel += b.run()?;
        let mut reached = k;
        let mut d = 0u32;
        loop {
            let mut b = Batch::new(self.gpu);
            b.threads(kern, "clear_counters", bind, self.params(k, 0, 0), COUNTERS);
            for r in 0..ROUNDS {
                b.threads(
                    kern,
                    "bfs_round",
                    bind,
                    self.params(k, d + r as u32, 8 + r as u32),
                    t,
                );
            }
            self.timing.kernel += b.run()?;
            let c = self.read(&self.counters, 8, ROUNDS)?;
            for (r, &n) in c.iter().enumerate() {
                reached += n as usize;
                if n == 0 {
                    self.rounds += d + r as u32 + 1;
                    return Ok(t - reached);
                }
            }
            d += ROUNDS as u32;
        }
    }

    /// Members CSR of the current labels (recorded into `b`).
    fn record_members<'b>(&'b self, b: &mut Batch<'b>, k: usize, job: &'b ScanJob) {
        let (kern, bind, t) = (self.kernels, &self.bind, self.t);
        b.threads(kern, "mem_clear", bind, self.params(k, 0, 0), k + 1);
        b.threads(kern, "mem_count", bind, self.params(k, 0, 0), t);
        self.scan.record(b, job);
        b.threads(kern, "mem_scatter", bind, self.params(k, 0, 0), t);
    }

    /// The update plus the medoid sort; returns (shift sum, changed count).
    /// Binds the member-offset scan for `k` clusters (once per cluster count).
    fn bind_mem_scan(&mut self, k: usize) {
        if self.mem_scan.as_ref().is_none_or(|(n, _)| *n != k) {
            self.mem_scan = Some((k, self.scan.bind(self.gpu, &self.mem_off, k + 1)));
        }
    }

    fn update(&mut self, k: usize) -> Result<(u64, u32), GpuError> {
        self.bind_mem_scan(k);
        let time = {
            let mem_scan = &self.mem_scan.as_ref().expect("bound").1;
            let (kern, bind, t) = (self.kernels, &self.bind, self.t);
            let mut b = Batch::new(self.gpu);
            b.threads(kern, "clear_counters", bind, self.params(k, 0, 0), COUNTERS);
            self.record_members(&mut b, k, mem_scan);
            b.groups(kern, "update", bind, self.params(k, 0, 0), k as u32);
            b.threads(kern, "mark_clear", bind, self.params(k, 0, 0), t + 1);
            b.threads(kern, "mark", bind, self.params(k, 0, 0), k);
            self.scan.record(&mut b, &self.flag_scan);
            b.threads(kern, "place", bind, self.params(k, 0, 0), k);
            b.run()?
        };
        self.timing.kernel += time;
        let c = self.read(&self.counters, 0, 3)?;
        self.large += c[2];
        Ok((c[0] as u64, c[1]))
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
            let (shift, changed) = self.update(k)?;
            *iterations += 1;
            moved = true;
            self.assign(k)?;
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
        b.threads(
            self.kernels,
            "dist_partial",
            &self.bind,
            self.params(0, 0, 0),
            self.t,
        );
        self.timing.kernel += b.run()?;
        let parts = self.read(&self.scratch, 0, groups)?;
        Ok(parts.iter().map(|&x| x as u64).sum())
    }

    /// Per cluster: triangles, distinct vertices (within the triangle limit), farthest member.
    fn stats(&mut self, k: usize) -> Result<ClusterStats, GpuError> {
        self.bind_mem_scan(k);
        let time = {
            let mem_scan = &self.mem_scan.as_ref().expect("bound").1;
            let mut b = Batch::new(self.gpu);
            self.record_members(&mut b, k, mem_scan);
            b.groups(
                self.kernels,
                "stats",
                &self.bind,
                self.params(k, 0, 0),
                k as u32,
            );
            b.run()?
        };
        self.timing.kernel += time;
        let off = self.read(&self.mem_off, 0, k + 1)?;
        let triangles = off.windows(2).map(|w| w[1] - w[0]).collect();
        let r = self.read(&self.result, 2 * k, 2 * k)?;
        Ok((triangles, r[..k].to_vec(), r[k..].to_vec()))
    }
}
