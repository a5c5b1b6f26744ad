//! The Morton order on the device (`wgsl/morton.wgsl`): the positions' box, Morton keys of the
//! triangles, a stable radix sort, and the triangles at the ranks the seeds take
//! ([`crate::strategy::kmedoids::flat::initial_medoids`], [`crate::strategy::kmedoids::coarse`]);
//! also each triangle's centroid cell packed as `kmedoids-parallel` keys it
//! ([`crate::strategy::kmedoids::morton::packed_centres`]), and the radix sort alone for other
//! keys ([`PairSort`]). The CPU reference is [`crate::strategy::kmedoids::morton::morton_order`];
//! the order, the seeds and the cells are identical.
//!
//! Host traffic: the box (six words, from which the host computes the [`MortonFrame`] as the CPU
//! does), then the seeds (one word each).

use super::adjacency::Timing;
use super::scan::Scan;
use super::{binding_set, param_block, timed, wgsl, Batch, Gpu, GpuError, Kernels, Split};
use crate::common::sorted;
use crate::strategy::kmedoids::morton::MortonFrame;
use glam::Vec3;

param_block! {
    /// `struct Params` of `wgsl/morton.wgsl`.
    pub struct Params {
        /// Triangles.
        t,
        /// Vertices.
        n,
        /// Bit shift of this radix pass.
        shift,
        /// Blocks of the sort.
        blocks,
        /// `MortonFrame::lo3.x` as bits.
        lo_x,
        /// `MortonFrame::lo3.y` as bits.
        lo_y,
        /// `MortonFrame::lo3.z` as bits.
        lo_z,
        /// `MortonFrame::factor` as bits.
        factor,
        /// Ranks to pick.
        k,
        /// First word of the packed centroid cells in `centres`.
        base,
        /// `MortonFrame::fine` as bits.
        fine,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/morton.wgsl`, in binding order.
    pub struct Buffers {
        /// Three f32 per vertex.
        positions: Read,
        /// Index buffer, first part.
        idx_a: Read,
        /// Index buffer, second part.
        idx_b: Read,
        /// The box as order-preserving integers.
        bbox: ReadWrite,
        /// Keys, buffer a.
        key_a: ReadWrite,
        /// Ids, buffer a.
        id_a: ReadWrite,
        /// Keys, buffer b.
        key_b: ReadWrite,
        /// Ids, buffer b.
        id_b: ReadWrite,
        /// Per-block digit counts.
        hist: ReadWrite,
        /// Ranks to pick.
        ranks: Read,
        /// The picked triangles.
        medoids: ReadWrite,
        /// Packed centroid cells, from word `base`.
        centres: ReadWrite,
    }
}

/// Elements per sort block (`BLOCK` in the WGSL).
pub(crate) const BLOCK: usize = 4096;
/// Radix passes of 4 bits over the 30-bit keys.
const PASSES: u32 = 8;

/// The mesh on the device, as the seeding reads it.
pub struct DeviceInput<'a> {
    /// Three f32 per vertex.
    pub positions: &'a wgpu::Buffer,
    /// Vertices.
    pub vertices: usize,
    /// The index buffer.
    pub indices: &'a Split,
}

/// Inverse of the shader's `ordered`.
fn unordered(u: u32) -> f32 {
    f32::from_bits(if u & 0x8000_0000 != 0 {
        u & 0x7fff_ffff
    } else {
        !u
    })
}

/// The Morton order on the device ([`order`]).
pub struct Ordered {
    /// Triangles in Morton order (ties by id).
    pub order: wgpu::Buffer,
    /// The triangle at each requested rank.
    pub picked: Vec<u32>,
    /// Upload, kernel and readback time.
    pub timing: Timing,
}

/// The Morton order of `mesh`'s triangles, left on the device, and the triangles at `ranks`
/// (read back); with `centres`, also every triangle's packed centroid cell written to that buffer
/// from the given word on.
pub fn order(
    gpu: &Gpu,
    mesh: DeviceInput<'_>,
    ranks: &[u32],
    centres: Option<(&wgpu::Buffer, usize)>,
) -> Result<Ordered, GpuError> {
    run(gpu, mesh, ranks, centres, true)
}

/// Only every triangle's packed centroid cell, written to `centres` from the given word on: the
/// box and the cells without the sort, for a caller that needs no order (one region).
pub fn cells(
    gpu: &Gpu,
    mesh: DeviceInput<'_>,
    centres: (&wgpu::Buffer, usize),
) -> Result<Timing, GpuError> {
    Ok(run(gpu, mesh, &[0], Some(centres), false)?.timing)
}

/// [`order`], or with `sort` false only the box and the centroid cells (`order` and `picked`
/// then mean nothing).
fn run(
    gpu: &Gpu,
    mesh: DeviceInput<'_>,
    ranks: &[u32],
    centres: Option<(&wgpu::Buffer, usize)>,
    sort: bool,
) -> Result<Ordered, GpuError> {
    let t = mesh.indices.len / 3;
    let kernels = kernels(gpu);
    let scan = Scan::new(gpu);
    let blocks = t.div_ceil(BLOCK).max(1);
    let mut timing = Timing::default();
    let (bufs, up) = timed(|| {
        (
            gpu.upload("box", &[u32::MAX, u32::MAX, u32::MAX, 0, 0, 0]),
            [0, 1, 2, 3].map(|_| gpu.zeros("sort", if sort { t } else { 1 })),
            gpu.zeros("digit counts", if sort { 16 * blocks } else { 1 }),
            gpu.upload("ranks", ranks),
            gpu.zeros("picked", ranks.len()),
            centres.is_none().then(|| gpu.zeros("unused", 1)),
        )
    });
    timing.upload += up;
    let (bbox, [key_a, id_a, key_b, id_b], hist, rank_buf, picked, unused) = bufs;
    let (centre_buf, base) = match (centres, &unused) {
        (Some((buf, base)), _) => (buf, base),
        (None, Some(u)) => (u, 0),
        (None, None) => unreachable!("allocated when no centres are asked for"),
    };
    let bind = kernels.bind(
        gpu,
        &Buffers {
            positions: mesh.positions,
            idx_a: &mesh.indices.a,
            idx_b: &mesh.indices.b,
            bbox: &bbox,
            key_a: &key_a,
            id_a: &id_a,
            key_b: &key_b,
            id_b: &id_b,
            hist: &hist,
            ranks: &rank_buf,
            medoids: &picked,
            centres: centre_buf,
        },
    );
    let mut params = Params {
        t: t as u32,
        n: mesh.vertices as u32,
        shift: 0,
        blocks: blocks as u32,
        lo_x: 0,
        lo_y: 0,
        lo_z: 0,
        factor: 0,
        k: ranks.len() as u32,
        base: base as u32,
        fine: 0,
    };
    let mut b = Batch::new(gpu);
    let groups = gpu.stride_groups(mesh.vertices);
    b.groups(&kernels, "bbox_reduce", &bind, params, groups);
    let (kernel, r) = b.run_read(&[(&bbox, 0, 6)])?;
    timing.kernel += kernel;
    let w = &r[0];
    let corner = |o: usize| Vec3::new(unordered(w[o]), unordered(w[o + 1]), unordered(w[o + 2]));
    let frame = MortonFrame::new(corner(0), corner(3));
    params.lo_x = frame.lo3.x.to_bits();
    params.lo_y = frame.lo3.y.to_bits();
    params.lo_z = frame.lo3.z.to_bits();
    params.factor = frame.factor.to_bits();
    params.fine = frame.fine.to_bits();
    let mut b = Batch::new(gpu);
    if centres.is_some() {
        b.threads(&kernels, "centre_cells", &bind, params, t);
    }
    if !sort {
        timing.kernel += b.run()?;
        return Ok(Ordered {
            order: id_a,
            picked: Vec::new(),
            timing,
        });
    }
    let hist_scan = scan.bind(gpu, &hist, 16 * blocks);
    b.threads(&kernels, "keys", &bind, params, t);
    for pass in 0..PASSES {
        let p = Params {
            shift: 4 * pass,
            ..params
        };
        b.groups(&kernels, "hist_count", &bind, p, blocks as u32);
        scan.record(&mut b, &hist_scan);
        b.groups(&kernels, "scatter", &bind, p, blocks as u32);
    }
    b.threads(&kernels, "pick", &bind, params, ranks.len());
    let (kernel, mut r) = b.run_read(&[(&picked, 0, ranks.len())])?;
    timing.kernel += kernel;
    Ok(Ordered {
        order: id_a,
        picked: r.remove(0),
        timing,
    })
}

/// The kernels of `morton.wgsl` (cached per device).
fn kernels(gpu: &Gpu) -> Kernels<Params> {
    Kernels::new::<Buffers>(
        gpu,
        "morton",
        wgsl!("morton.wgsl"),
        &[
            "bbox_reduce",
            "keys",
            "centre_cells",
            "hist_count",
            "scatter",
            "pick",
        ],
    )
}

/// What [`pick`] read back.
pub struct Picked {
    /// The triangle at each requested rank.
    pub triangles: Vec<u32>,
    /// The whole Morton order, where asked for.
    pub order: Option<Vec<u32>>,
    /// Upload, kernel and readback time.
    pub timing: Timing,
}

/// The triangles at `ranks` of the Morton order, and the whole order when `want_order` (for the
/// parity checks).
pub fn pick(
    gpu: &Gpu,
    mesh: DeviceInput<'_>,
    ranks: &[u32],
    want_order: bool,
) -> Result<Picked, GpuError> {
    let t = mesh.indices.len / 3;
    let mut o = order(gpu, mesh, ranks, None)?;
    let order = if want_order {
        let (r, s) = timed(|| gpu.read(&o.order, 0, t));
        o.timing.readback += s;
        Some(r?)
    } else {
        None
    };
    Ok(Picked {
        triangles: o.picked,
        order,
        timing: o.timing,
    })
}

/// A stable sort of `t` (key, id) pairs on the device by the keys' low `bits` bits: the radix
/// passes of `morton.wgsl` over the caller's key and id buffers (`hist_count`, scan, `scatter`,
/// 4 bits a pass), so equal keys keep their ids' order.
pub struct PairSort {
    kernels: Kernels<Params>,
    scan: Scan,
    bind: wgpu::BindGroup,
    hist_scan: super::scan::ScanJob,
    key_b: wgpu::Buffer,
    id_b: wgpu::Buffer,
    t: usize,
    blocks: usize,
    passes: u32,
}

impl PairSort {
    /// Binds the sort of `t` pairs in `keys` and `ids` by their low `bits` key bits.
    pub fn new(gpu: &Gpu, keys: &wgpu::Buffer, ids: &wgpu::Buffer, t: usize, bits: u32) -> Self {
        let kernels = kernels(gpu);
        let scan = Scan::new(gpu);
        let blocks = t.div_ceil(BLOCK).max(1);
        let (key_b, id_b, hist) = (
            gpu.zeros("sort keys", t),
            gpu.zeros("sort ids", t),
            gpu.zeros("digit counts", 16 * blocks),
        );
        // The seeding's buffers, unused by the sort passes (distinct, so no two writable
        // bindings share a buffer).
        let [read, bbox, picked, centres] = [0; 4].map(|_| gpu.zeros("unused", 1));
        let bind = kernels.bind(
            gpu,
            &Buffers {
                positions: &read,
                idx_a: &read,
                idx_b: &read,
                bbox: &bbox,
                key_a: keys,
                id_a: ids,
                key_b: &key_b,
                id_b: &id_b,
                hist: &hist,
                ranks: &read,
                medoids: &picked,
                centres: &centres,
            },
        );
        let hist_scan = scan.bind(gpu, &hist, 16 * blocks);
        Self {
            kernels,
            scan,
            bind,
            hist_scan,
            key_b,
            id_b,
            t,
            blocks,
            passes: bits.div_ceil(4),
        }
    }

    /// Records the passes into `b`.
    pub fn record<'b>(&'b self, b: &mut Batch<'b>) {
        for pass in 0..self.passes {
            let p = Params {
                t: self.t as u32,
                shift: 4 * pass,
                blocks: self.blocks as u32,
                ..Params::default()
            };
            b.groups(
                &self.kernels,
                "hist_count",
                &self.bind,
                p,
                self.blocks as u32,
            );
            self.scan.record(b, &self.hist_scan);
            b.groups(&self.kernels, "scatter", &self.bind, p, self.blocks as u32);
        }
    }

    /// Where the sorted keys and ids end: `None` in the caller's buffers (an even number of
    /// passes), else in the sort's own.
    pub fn sorted(&self) -> Option<(&wgpu::Buffer, &wgpu::Buffer)> {
        (self.passes % 2 == 1).then_some((&self.key_b, &self.id_b))
    }
}

/// [`crate::strategy::kmedoids::flat::initial_medoids`] on the device: `ceil(T / per_cluster)`
/// seeds in the middle of equal runs of the Morton order, ascending. Identical to the CPU's.
pub fn initial_medoids(
    gpu: &Gpu,
    mesh: DeviceInput<'_>,
    per_cluster: usize,
) -> Result<(Vec<u32>, Timing), GpuError> {
    let t = (mesh.indices.len / 3) as u64;
    let k = t.div_ceil(per_cluster.max(1) as u64).max(1);
    let ranks: Vec<u32> = (0..k).map(|j| ((j * t + t / 2) / k) as u32).collect();
    let p = pick(gpu, mesh, &ranks, false)?;
    Ok((sorted(p.triangles), p.timing))
}
