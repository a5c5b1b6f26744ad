//! `kmedoids-regions` on the device (`wgsl/regions.wgsl`); the CPU reference is
//! [`crate::strategy::kmedoids::regions`], and labels, distances, medoids and meshlets are
//! identical.
//!
//! The regions (a Morton-seeded BFS at a coarse scale) are still computed on the host, over the
//! dual graph the adjacency kernels built (read back once), and uploaded; everything after them
//! runs in two submissions: the per-triangle setup and one invocation per region growing its
//! clusters, then (after the host reads the cluster count of each region and writes their prefix
//! sums) the global labels, one invocation per cluster for its medoid and distances, and the
//! assembly (`wgsl/assemble.wgsl`).

use super::adjacency::{AdjacencyKernels, Timing};
use super::assemble::{Assembly, DeviceMeshlets, Groups};
use super::{
    binding_set, param_block, timed, timed_read, wgsl, Batch, Gpu, GpuError, Kernels, Scan,
};
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use crate::strategy::kmedoids::{members, parallel, regions, Clustering, Config};
use std::time::Instant;

param_block! {
    /// `struct Params` of `wgsl/regions.wgsl`.
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
    /// The storage buffers of `wgsl/regions.wgsl`, in binding order.
    pub struct Buffers {
        /// Index buffer, first part.
        idx_a: Read,
        /// Index buffer, second part.
        idx_b: Read,
        /// Vertex -> triangle row starts.
        vt_off: Read,
        /// Vertex -> triangle items, first part.
        vt_a: Read,
        /// Vertex -> triangle items, second part.
        vt_b: Read,
        /// Dual-graph row starts.
        dual_off: Read,
        /// Dual-graph items, first part.
        dual_a: Read,
        /// Dual-graph items, second part.
        dual_b: Read,
        /// Region offsets, cluster counts, bases, medoids.
        info: ReadWrite,
        /// Members of each region, ascending.
        items: Read,
        /// Per-triangle state (seven sections).
        tri: ReadWrite,
        /// Canonical corners, then the triangles' quantised centroids.
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

/// A GPU `kmedoids-regions` run.
pub struct GpuRegions {
    /// The result, equal to the CPU's (empty labels, distances and meshlets when not read back).
    pub clustering: Clustering,
    /// Upload, kernel and readback time, the adjacency's included.
    pub timing: Timing,
    /// Host time for the regions (the Morton order and the region BFS on the CPU, over the
    /// device's dual graph read back; that readback is in `timing`).
    pub host_regions: f64,
    /// Regions.
    pub regions: usize,
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

/// Runs `kmedoids-regions` on `gpu`; with `read_back` the labels, distances and meshlets come
/// back to the host, else only the medoids (one word per cluster) do, and the meshlets stay on
/// the device.
pub fn cluster_regions(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    cfg: &Config,
    read_back: bool,
) -> Result<(GpuRegions, DeviceMeshlets), GpuError> {
    let start = Instant::now();
    let t = mesh.triangle_count();
    fits(gpu, "regions' triangle state", 7 * t)?;
    fits(gpu, "regions' corner state", 9 * t)?;
    fits(gpu, "regions' canonical corners and centres", 4 * t)?;
    let (adj, adj_timing) = AdjacencyKernels::new(gpu).build(gpu, mesh)?;
    // Step 1 on the host, over the device's dual graph read back (the same rows as the CPU's).
    let (dual, dual_read) = timed(|| adj.read_dual(gpu));
    let dual = dual?;
    let ((region, k_regions), host_regions) =
        timed(|| parallel::regions(mesh, &dual, cfg.region_triangles as usize));
    let rows = members(&region, k_regions);
    let arena_len = 7 * t + 3 * k_regions * limits.max_triangles as usize;
    fits(gpu, "regions' lists", arena_len)?;
    if rows.offsets.windows(2).any(|w| w[1] - w[0] >= 1 << 24) {
        return Err(GpuError::Unsupported(
            "a region of 2^24 triangles or more (pockets are packed as 24-bit offsets)",
        ));
    }
    let kernels = Kernels::new::<Buffers>(
        gpu,
        "regions",
        wgsl!("regions.wgsl"),
        &["init", "grow", "grow_rows", "relabel", "medoid"],
    );
    let info_len = 3 * k_regions + 2 + t;
    let (bufs, upload) = timed(|| {
        let info = gpu.zeros("region info", info_len);
        gpu.queue
            .write_buffer(&info, 0, bytemuck::cast_slice(&rows.offsets));
        let tri = gpu.zeros("region triangle state", 7 * t);
        gpu.queue
            .write_buffer(&tri, 0, bytemuck::cast_slice(&region));
        let canon = gpu.zeros("canonical corners and centres", 4 * t);
        gpu.queue.write_buffer(
            &canon,
            4 * 3 * t as u64,
            bytemuck::cast_slice(&regions::packed_centres(mesh)),
        );
        (
            info,
            gpu.upload("region members", &rows.items),
            tri,
            canon,
            gpu.zeros("corner state", 9 * t),
            gpu.zeros("region lists", arena_len),
            gpu.zeros("labels", t),
            gpu.zeros("distances", t),
        )
    });
    let (info, items, tri, canon, cstate, arena, labels, dist) = bufs;
    let mut timing = Timing {
        upload: adj_timing.upload + upload,
        readback: adj_timing.readback + dual_read,
        ..adj_timing
    };
    let bind = kernels.bind(
        gpu,
        &Buffers {
            idx_a: &adj.indices.a,
            idx_b: &adj.indices.b,
            vt_off: &adj.vt_offsets,
            vt_a: &adj.vt_items.a,
            vt_b: &adj.vt_items.b,
            dual_off: &adj.dual_offsets,
            dual_a: &adj.dual_items.a,
            dual_b: &adj.dual_items.b,
            info: &info,
            items: &items,
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
    // Step 2, and the cluster count of every region back in the same round trip.
    let mut b = Batch::new(gpu);
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
    let (kernel, mut out) = b.run_read(&[(&info, k_regions + 1, k_regions)])?;
    timing.kernel += kernel;
    let counts = out.remove(0);
    let mut bases = Vec::with_capacity(k_regions + 1);
    let mut k = 0u32;
    for &c in &counts {
        bases.push(k);
        k += c;
    }
    bases.push(k);
    let k = k as usize;
    let (_, up) = timed(|| {
        gpu.queue.write_buffer(
            &info,
            4 * (2 * k_regions + 1) as u64,
            bytemuck::cast_slice(&bases),
        )
    });
    timing.upload += up;
    // Steps 3 and 4, and the medoids.
    let mut b = Batch::new(gpu);
    b.threads(&kernels, "relabel", &bind, params(k), t);
    b.threads(&kernels, "medoid", &bind, params(k), k);
    let (kernel, mut out) = b.run_read(&[(&info, 3 * k_regions + 2, k)])?;
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
    let clustering = regions::clustering(
        medoids,
        labels,
        distances,
        meshlets,
        start.elapsed().as_secs_f64(),
    );
    Ok((
        GpuRegions {
            clustering,
            timing,
            host_regions,
            regions: k_regions,
            seconds: start.elapsed().as_secs_f64(),
        },
        device,
    ))
}
