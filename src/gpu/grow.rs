//! The parallel bounding-sphere grower on the GPU (`wgsl/grow.wgsl`): bsphere candidate scoring for
//! many meshlets at once, one workgroup per meshlet, conflicts by atomic claims. Step for step the
//! CPU reference [`crate::strategy::grow::grow`], with identical owners, orders, wave and round
//! counts and meshlets.
//!
//! Host traffic: per wave the seed count (one word) and per 8 growth or component rounds their
//! counters; owners and orders come back once, at the end.

use super::adjacency::{AdjacencyKernels, Timing};
use super::assemble::{Assembly, DeviceMeshlets, Groups};
use super::scan::ScanJob;
use super::{
    binding_set, param_block, timed, timed_read, wgsl, Batch, Gpu, GpuError, Kernels, Scan, PART,
};
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::grow::Setup;
use std::time::Instant;

param_block! {
    /// `struct Params` of `wgsl/grow.wgsl`.
    pub struct Params {
        /// Triangles.
        t,
        /// Meshlets in the wave (or seeds to place).
        n,
        /// First meshlet id of the wave.
        base,
        /// Counter slot this dispatch counts into.
        slot,
        /// Meshlet vertex limit.
        max_v,
        /// Meshlet triangle limit.
        max_t,
        /// Grid cell size in quantised units.
        cell,
        /// Grid cells per axis.
        grid,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/grow.wgsl`, in binding order.
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
        /// Quantised positions.
        q: Read,
        /// Owner meshlet per triangle.
        claim: ReadWrite,
        /// Position of each triangle in its meshlet.
        order: ReadWrite,
        /// Component labels.
        label: ReadWrite,
        /// Grid cells: best distance and its triangle.
        cells: ReadWrite,
        /// Seed flags (scanned into seed slots).
        flags: ReadWrite,
        /// Per-meshlet growth state of the wave.
        state: ReadWrite,
        /// Meshlet triangles of the wave.
        mt: ReadWrite,
        /// Meshlet vertices of the wave.
        mv: ReadWrite,
        /// Proposal and label-change counters.
        counters: ReadWrite,
    }
}

/// Rounds recorded per submission (their counters come back together).
const ROUNDS: u32 = 8;

/// A GPU run of the parallel grower.
pub struct GpuGrowth {
    /// Meshlet of every triangle.
    pub owner: Vec<u32>,
    /// Position of every triangle in its meshlet.
    pub order: Vec<u32>,
    /// The meshlets (assembled on the device, `wgsl/assemble.wgsl`, and read back).
    pub meshlets: Meshlets,
    /// Waves run.
    pub waves: u32,
    /// Growth rounds run.
    pub rounds: u32,
    /// Upload, kernel and readback time, adjacency included.
    pub timing: Timing,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// Per-wave meshlet state, sized for the largest wave so far.
struct WaveBuffers {
    cap: usize,
    state: wgpu::Buffer,
    mt: wgpu::Buffer,
    mv: wgpu::Buffer,
}

impl WaveBuffers {
    fn new(gpu: &Gpu, cap: usize, limits: Limits) -> Result<Self, GpuError> {
        let words = cap * limits.max_triangles.max(limits.max_vertices) as usize;
        if words > PART {
            return Err(GpuError::TooLarge {
                what: "parallel grower meshlets in one wave",
                len: cap,
                max: PART / limits.max_triangles.max(limits.max_vertices) as usize,
            });
        }
        Ok(Self {
            cap,
            state: gpu.zeros("grow state", 8 * cap),
            mt: gpu.zeros("grow triangles", cap * limits.max_triangles as usize),
            mv: gpu.zeros("grow vertices", cap * limits.max_vertices as usize),
        })
    }
}

/// Runs the parallel grower on the GPU with seed spacing `spacing` (see
/// [`crate::strategy::grow::DEFAULT_SPACING`]).
pub fn grow(gpu: &Gpu, mesh: &Mesh, limits: Limits, spacing: f64) -> Result<GpuGrowth, GpuError> {
    grow_with(gpu, mesh, limits, spacing, true).map(|(g, _)| g)
}

/// [`grow`] that also returns the meshlets on the device; with `read` false nothing is read back
/// (`owner`, `order` and `meshlets` stay empty).
pub fn grow_with(
    gpu: &Gpu,
    mesh: &Mesh,
    limits: Limits,
    spacing: f64,
    read_back: bool,
) -> Result<(GpuGrowth, DeviceMeshlets), GpuError> {
    let start = Instant::now();
    let t = mesh.triangle_count();
    if t + 1 > PART {
        return Err(GpuError::TooLarge {
            what: "parallel grower triangles",
            len: t,
            max: PART - 1,
        });
    }
    let setup = Setup::new(mesh, limits, spacing);
    let ak = AdjacencyKernels::new(gpu);
    let (adj, adj_timing) = ak.build(gpu, mesh)?;
    let kernels = Kernels::new::<Buffers>(
        gpu,
        "grow",
        wgsl!("grow.wgsl"),
        &[
            "init",
            "clear_counters",
            "label_init",
            "label_round",
            "clear_cells",
            "cell_dist",
            "cell_pick",
            "seed_flags",
            "place",
            "propose",
            "claim_best",
        ],
    );
    let scan = Scan::new(gpu);
    let cells = (setup.grid as usize).pow(3);
    let ((q, claim, order, label, cell_buf, flags, counters), upload) = timed(|| {
        (
            gpu.upload("quantised positions", &setup.q),
            gpu.zeros("claim", t),
            gpu.zeros("order", t),
            gpu.zeros("labels", t),
            gpu.zeros("cells", 2 * cells),
            gpu.zeros("seed flags", t + 1),
            gpu.zeros("counters", 16),
        )
    });
    let mut timing = Timing {
        upload: adj_timing.upload + upload,
        kernel: adj_timing.kernel,
        readback: adj_timing.readback,
    };
    let flag_scan: ScanJob = scan.bind(gpu, &flags, t + 1);
    let mut wave = WaveBuffers::new(gpu, 1, limits)?;
    let bind_for = |w: &WaveBuffers| {
        kernels.bind(
            gpu,
            &Buffers {
                dual_off: &adj.dual_offsets,
                dual_a: &adj.dual_items.a,
                dual_b: &adj.dual_items.b,
                idx_a: &adj.indices.a,
                idx_b: &adj.indices.b,
                q: &q,
                claim: &claim,
                order: &order,
                label: &label,
                cells: &cell_buf,
                flags: &flags,
                state: &w.state,
                mt: &w.mt,
                mv: &w.mv,
                counters: &counters,
            },
        )
    };
    let mut bind = bind_for(&wave);
    let params = |n: usize, base: u32, slot: u32| Params {
        t: t as u32,
        n: n as u32,
        base,
        slot,
        max_v: limits.max_vertices,
        max_t: limits.max_triangles,
        cell: setup.cell,
        grid: setup.grid,
    };
    let mut read = |buf: &wgpu::Buffer, off: usize, len: usize| {
        let (r, s) = timed(|| gpu.read(buf, off, len));
        timing.readback += s;
        r
    };
    let mut kernel = 0.0;
    {
        let mut b = Batch::new(gpu);
        b.threads(&kernels, "init", &bind, params(0, 0, 0), t);
        kernel += b.run()?;
    }
    let (mut base, mut waves, mut rounds) = (0u32, 0u32, 0u32);
    loop {
        let first = waves == 0;
        if !first {
            // Unclaimed components, until a round changes no label.
            let mut b = Batch::new(gpu);
            b.threads(&kernels, "label_init", &bind, params(0, 0, 0), t);
            kernel += b.run()?;
            'labels: loop {
                let mut b = Batch::new(gpu);
                b.threads(&kernels, "clear_counters", &bind, params(0, 0, 0), 16);
                for r in 0..ROUNDS {
                    b.threads(&kernels, "label_round", &bind, params(0, 0, 8 + r), t);
                }
                kernel += b.run()?;
                if read(&counters, 8, ROUNDS as usize)?.contains(&0) {
                    break 'labels;
                }
            }
        }
        let mut b = Batch::new(gpu);
        b.threads(&kernels, "clear_cells", &bind, params(0, 0, 0), 2 * cells);
        b.threads(&kernels, "cell_dist", &bind, params(0, 0, 0), t);
        b.threads(&kernels, "cell_pick", &bind, params(0, 0, 0), t);
        b.threads(
            &kernels,
            "seed_flags",
            &bind,
            params(0, 0, u32::from(!first)),
            t + 1,
        );
        scan.record(&mut b, &flag_scan);
        kernel += b.run()?;
        let n = read(&flags, t, 1)?[0] as usize;
        if n == 0 {
            break;
        }
        if n > wave.cap {
            wave = WaveBuffers::new(gpu, n, limits)?;
            bind = bind_for(&wave);
        }
        let mut b = Batch::new(gpu);
        b.threads(&kernels, "place", &bind, params(n, base, 0), t);
        kernel += b.run()?;
        'grow: loop {
            let mut b = Batch::new(gpu);
            b.threads(&kernels, "clear_counters", &bind, params(0, 0, 0), 16);
            for r in 0..ROUNDS {
                b.groups(&kernels, "propose", &bind, params(n, base, r), n as u32);
                b.threads(&kernels, "claim_best", &bind, params(n, base, r), n);
            }
            kernel += b.run()?;
            for c in read(&counters, 0, ROUNDS as usize)? {
                rounds += 1;
                if c == 0 {
                    break 'grow;
                }
            }
        }
        base += n as u32;
        waves += 1;
    }
    let groups = Groups {
        owner: &claim,
        key: &order,
        count: base as usize,
    };
    let (device, assembly) = Assembly::new(gpu).run(gpu, &scan, &adj.indices, groups, limits)?;
    kernel += assembly;
    let (owner, order, meshlets) = if read_back {
        (
            read(&claim, 0, t)?,
            read(&order, 0, t)?,
            timed_read(&mut timing, || device.read(gpu))?,
        )
    } else {
        Default::default()
    };
    timing.kernel += kernel;
    Ok((
        GpuGrowth {
            owner,
            order,
            meshlets,
            waves,
            rounds,
            timing,
            seconds: start.elapsed().as_secs_f64(),
        },
        device,
    ))
}
