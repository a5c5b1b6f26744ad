//! `kmedoids-parallel` on the device (`wgsl/kmedoids_parallel.wgsl`); the CPU reference is
//! [`crate::strategy::kmedoids::parallel`], and labels, distances, medoids and meshlets are
//! identical.
//!
//! Every step is a kernel, from a mesh uploaded from the host or already on the device: the
//! adjacency, the coarse regions ([`super::coarse`]: Morton order, seeds, BFS, the pieces no seed
//! reaches, members sorted by region) and the packed centroid cells, then the per-triangle setup
//! and one invocation per region growing its clusters; after the host reads the cluster count of
//! each region and writes their prefix sums, the global labels, one invocation per cluster for
//! its medoid and distances, the boundary moves ([`super::kmedoids_parallel_moves`], in the same submission), and
//! the assembly (`wgsl/assemble.wgsl`). The host reads back only control words: the box, the
//! seeds, the BFS's frontier sizes, hooking-round counts where a piece has no seed, one count per
//! region, one medoid per cluster and the moves' counters.

use super::adjacency::{AdjacencyKernels, Timing};
use super::assemble::{Assembly, DeviceMeshlets, Groups};
use super::coarse::DeviceRegions;
use super::kmedoids_parallel_moves::{DeviceClusters, DeviceMoves};
use super::morton::DeviceInput;
use super::source::{MeshSource, Placed};
use super::{
    binding_set, param_block, timed, timed_read, wgsl, Batch, Gpu, GpuError, Kernels, Scan,
};
use crate::meshlet::Limits;
use crate::strategy::kmedoids::coarse::region_count;
use crate::strategy::kmedoids::parallel::moves::Moves;
use crate::strategy::kmedoids::parallel::{self, layout, Config};
use crate::strategy::kmedoids::{mean, Clustering};
use std::time::Instant;

param_block! {
    /// `struct Params` of `wgsl/kmedoids_parallel.wgsl`.
    pub struct Params {
        /// Triangles.
        t,
        /// Regions.
        regions,
        /// Vertex limit.
        max_v,
        /// Triangle limit.
        max_t,
        /// Clusters in all (after the growth).
        k,
        /// Unused.
        pad,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/kmedoids_parallel.wgsl`, in binding order.
    pub struct Buffers {
        adjacency;
        /// Region offsets, cluster counts, bases, medoids.
        info: ReadWrite,
        /// Members of each region, ascending.
        items: Read,
        /// Per-triangle state (eight sections).
        tri: ReadWrite,
        /// Canonical corners, then the triangles' packed centroid cells.
        canon: ReadWrite,
        /// Per-corner state (three sections).
        cstate: ReadWrite,
        /// Per-region lists.
        arena: ReadWrite,
        /// Global labels.
        labels: ReadWrite,
        /// Hop distance to the medoid.
        dist: ReadWrite,
    }
}

/// A GPU `kmedoids-parallel` run.
pub struct GpuRegions {
    /// The result, equal to the CPU's (empty labels, distances and meshlets when not read back).
    pub clustering: Clustering,
    /// Upload, kernel and readback time, the adjacency's and the regions' included.
    pub timing: Timing,
    /// Regions.
    pub regions: usize,
    /// Hooking rounds for the pieces no region seed reached (0 where every piece has a seed).
    pub piece_rounds: u32,
    /// Wall time of the whole run in seconds.
    pub seconds: f64,
}

/// `len` words in one binding of `gpu`, or the error naming `what`.
fn fits(gpu: &Gpu, what: &'static str, len: usize) -> Result<(), GpuError> {
    let max = gpu.binding_words();
    if len > max {
        return Err(GpuError::TooLarge { what, len, max });
    }
    Ok(())
}

/// The words of each buffer of a run (`parallel::layout`'s sections).
struct Sizes {
    tri_len: usize,
    corner_len: usize,
    canon_len: usize,
    arena_len: usize,
    info_len: usize,
}

/// The buffers' sizes for `t` triangles in `k_regions` regions, or the error naming the first
/// that does not fit one binding of `gpu`.
fn sizes(gpu: &Gpu, t: usize, k_regions: usize, limits: Limits) -> Result<Sizes, GpuError> {
    let s = Sizes {
        tri_len: layout::TRI_SECTIONS as usize * t,
        corner_len: 3 * layout::CORNER_SECTIONS as usize * t,
        canon_len: layout::CANON_WORDS as usize * t,
        arena_len: layout::arena_words(t, k_regions, limits.max_triangles as usize),
        info_len: 3 * k_regions + 2 + t,
    };
    fits(gpu, "regions' triangle state", s.tri_len)?;
    fits(gpu, "regions' corner state", s.corner_len)?;
    fits(gpu, "regions' canonical corners and centres", s.canon_len)?;
    fits(gpu, "regions' lists", s.arena_len)?;
    if t.div_ceil(k_regions) >= 1 << 24 {
        // Regions hold at most ceil(T / k) plus the small pieces they take in; checked exactly
        // once the regions are known.
        return Err(GpuError::Unsupported(
            "a region of 2^24 triangles or more (pockets are packed as 24-bit offsets)",
        ));
    }
    Ok(s)
}

/// Writes each region's first cluster (the prefix sums of the regions' cluster `counts`, and the
/// total after them) into `info` after the counts; returns the cluster count and the upload
/// seconds.
fn write_bases(gpu: &Gpu, info: &wgpu::Buffer, counts: &[u32]) -> (usize, f64) {
    let k_regions = counts.len();
    let mut bases = Vec::with_capacity(k_regions + 1);
    let mut k = 0u32;
    for &c in counts {
        bases.push(k);
        k += c;
    }
    bases.push(k);
    let (_, up) = timed(|| {
        gpu.queue.write_buffer(
            info,
            4 * (2 * k_regions + 1) as u64,
            bytemuck::cast_slice(&bases),
        )
    });
    (k as usize, up)
}

/// Runs `kmedoids-parallel` on `gpu` over a mesh on the host or already on the device; with
/// `read_back` the labels, distances and meshlets come back to the host, else only the medoids
/// (one word per cluster) do, and the meshlets stay on the device.
pub fn cluster(
    gpu: &Gpu,
    source: MeshSource<'_>,
    limits: Limits,
    cfg: &Config,
    read_back: bool,
) -> Result<(GpuRegions, DeviceMeshlets), GpuError> {
    let start = Instant::now();
    let (t, n) = source.counts();
    let k_regions = region_count(t, cfg.region_triangles as usize);
    let Sizes {
        tri_len,
        corner_len,
        canon_len,
        arena_len,
        info_len,
    } = sizes(gpu, t, k_regions, limits)?;
    let Placed {
        indices,
        positions,
        upload,
        ..
    } = source.place(gpu)?;
    let (adj, adj_timing) = AdjacencyKernels::new(gpu).build_from(gpu, indices, n)?;
    let kernels = Kernels::new::<Buffers>(
        gpu,
        "regions",
        wgsl!(generated "kmedoids_parallel_layout.wgsl"; "kmedoids_parallel.wgsl", "medoid.wgsl"),
        &["init", "grow", "grow_rows", "relabel", "medoid"],
    );
    let (bufs, up) = timed(|| {
        (
            gpu.zeros("region info", info_len),
            gpu.zeros("region triangle state", tri_len),
            gpu.zeros("canonical corners and centres", canon_len),
            gpu.zeros("corner state", corner_len),
            gpu.zeros("region lists", arena_len),
            gpu.zeros("labels", t),
            gpu.zeros("distances", t),
        )
    });
    let (info, tri, canon, cstate, arena, labels, dist) = bufs;
    // Step 1 on the device: regions into `tri`'s first section and `info`'s offsets, the
    // centroid cells after the canonical corners.
    let coarse = DeviceRegions::new(
        gpu,
        DeviceInput {
            positions: &positions,
            vertices: n,
            indices: &adj.indices,
        },
        &adj,
        cfg.region_triangles as usize,
        [&tri, &info],
        Some((&canon, layout::CANON_CELLS as usize * t)),
    )?;
    let mut timing = Timing {
        upload: upload + adj_timing.upload + up + coarse.timing.upload,
        kernel: adj_timing.kernel + coarse.timing.kernel,
        readback: adj_timing.readback + coarse.timing.readback,
    };
    let bind = kernels.bind(
        gpu,
        &Buffers {
            adj: &adj,
            info: &info,
            items: coarse.members(),
            tri: &tri,
            canon: &canon,
            cstate: &cstate,
            arena: &arena,
            labels: &labels,
            dist: &dist,
        },
    );
    let params = |k: usize| Params {
        t: t as u32,
        regions: k_regions as u32,
        max_v: limits.max_vertices,
        max_t: limits.max_triangles,
        k: k as u32,
        pad: 0,
    };
    // The regions' last step, then step 2, and the member offsets and cluster count of every
    // region back in the same round trip.
    let mut b = Batch::new(gpu);
    coarse.record(&mut b);
    b.threads(&kernels, "init", &bind, params(0), t);
    if gpu.is_cpu() && k_regions > 1 {
        // Several regions per workgroup: a CPU adapter runs a workgroup's invocations side by
        // side in SIMD rows, where one region per workgroup leaves the rest of its row idle (a
        // single region is the same either way, and takes `grow`, so the tests run both entry
        // points on lavapipe).
        b.groups(
            &kernels,
            "grow_rows",
            &bind,
            params(0),
            (k_regions as u32).div_ceil(8),
        );
    } else {
        b.groups(&kernels, "grow", &bind, params(0), k_regions as u32);
    }
    let (kernel, mut out) = b.run_read(&[(&info, 0, 2 * k_regions + 1)])?;
    timing.kernel += kernel;
    let words = out.remove(0);
    let (offsets, counts) = words.split_at(k_regions + 1);
    if offsets.windows(2).any(|w| w[1] - w[0] >= 1 << 24) {
        return Err(GpuError::Unsupported(
            "a region of 2^24 triangles or more (pockets are packed as 24-bit offsets)",
        ));
    }
    let (k, up) = write_bases(gpu, &info, counts);
    timing.upload += up;
    // Steps 3, 4 and 5, then the medoids and the moves' counters back.
    let moves = (cfg.move_rounds > 0)
        .then(|| {
            let clusters = DeviceClusters {
                labels: &labels,
                dist: &dist,
                info: &info,
                medoid_at: 3 * k_regions + 2,
                k,
                arena: &arena,
                cstate: &cstate,
                centres: &canon,
                centres_at: layout::CANON_CELLS as usize * t,
            };
            DeviceMoves::new(gpu, &adj, &clusters, limits, cfg.move_rounds)
        })
        .transpose()?;
    let mut b = Batch::new(gpu);
    b.threads(&kernels, "relabel", &bind, params(k), t);
    b.threads(&kernels, "medoid", &bind, params(k), k);
    let mut reads = vec![(&info, 3 * k_regions + 2, k)];
    if let Some(m) = &moves {
        m.record(&mut b);
        reads.push(m.counters());
    }
    let (kernel, mut out) = b.run_read(&reads)?;
    timing.kernel += kernel;
    let medoids = out.remove(0);
    let scan = Scan::new(gpu);
    let groups = Groups {
        owner: &labels,
        key: &dist,
        count: k,
    };
    let (device, assembly) = Assembly::new(gpu).run(gpu, &scan, &adj.indices, groups, limits)?;
    timing.kernel += assembly;
    let (labels, distances, meshlets) = if read_back {
        let mut read = |buf: &wgpu::Buffer| {
            let (r, s) = timed(|| gpu.read(buf, 0, t));
            timing.readback += s;
            r
        };
        (
            read(&labels)?,
            read(&dist)?,
            timed_read(&mut timing, || device.read(gpu))?,
        )
    } else {
        Default::default()
    };
    let moves = match &moves {
        Some(m) => m.moves(&out[0]),
        None => Moves {
            objective_before: mean(&distances),
            ..Moves::default()
        },
    };
    let clustering = parallel::clustering(
        medoids,
        labels,
        distances,
        meshlets,
        &moves,
        start.elapsed().as_secs_f64(),
    );
    Ok((
        GpuRegions {
            clustering,
            timing,
            regions: k_regions,
            piece_rounds: coarse.piece_rounds,
            seconds: start.elapsed().as_secs_f64(),
        },
        device,
    ))
}
