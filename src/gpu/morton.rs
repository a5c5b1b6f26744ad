//! The flat k-medoids' seeds on the device (`wgsl/morton.wgsl`): the positions' box, Morton keys of
//! the triangles, a stable radix sort, and the triangles at the ranks
//! [`crate::strategy::kmedoids::flat::initial_medoids`] takes. The CPU reference is
//! [`crate::strategy::kmedoids::flat::morton_order`]; the order and the seeds are identical.
//!
//! Host traffic: the box (six words, from which the host computes the [`MortonFrame`] as the CPU
//! does), then the seeds (one word each).

use super::adjacency::Timing;
use super::scan::Scan;
use super::{binding_set, param_block, timed, wgsl, Batch, Gpu, GpuError, Kernels, Split};
use crate::common::sorted;
use crate::strategy::kmedoids::flat::MortonFrame;
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
    }
}

/// Elements per sort block (`BLOCK` in the WGSL).
const BLOCK: usize = 256;
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
    let kernels = Kernels::new::<Buffers>(
        gpu,
        "morton",
        wgsl!("morton.wgsl"),
        &["bbox_reduce", "keys", "hist_count", "scatter", "pick"],
    );
    let scan = Scan::new(gpu);
    let blocks = t.div_ceil(BLOCK).max(1);
    let mut timing = Timing::default();
    let (bufs, up) = timed(|| {
        (
            gpu.upload("box", &[u32::MAX, u32::MAX, u32::MAX, 0, 0, 0]),
            [0, 1, 2, 3].map(|_| gpu.zeros("sort", t)),
            gpu.zeros("digit counts", 16 * blocks),
            gpu.upload("ranks", ranks),
            gpu.zeros("picked", ranks.len()),
        )
    });
    timing.upload += up;
    let (bbox, [key_a, id_a, key_b, id_b], hist, rank_buf, picked) = bufs;
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
    };
    let mut b = Batch::new(gpu);
    b.threads(&kernels, "bbox_reduce", &bind, params, mesh.vertices);
    let (kernel, r) = b.run_read(&[(&bbox, 0, 6)])?;
    timing.kernel += kernel;
    let w = &r[0];
    let corner = |o: usize| Vec3::new(unordered(w[o]), unordered(w[o + 1]), unordered(w[o + 2]));
    let frame = MortonFrame::new(corner(0), corner(3));
    params.lo_x = frame.lo3.x.to_bits();
    params.lo_y = frame.lo3.y.to_bits();
    params.lo_z = frame.lo3.z.to_bits();
    params.factor = frame.factor.to_bits();
    let hist_scan = scan.bind(gpu, &hist, 16 * blocks);
    let mut b = Batch::new(gpu);
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
    let mut reads = vec![(&picked, 0, ranks.len())];
    if want_order {
        reads.push((&id_a, 0, t));
    }
    let (kernel, mut r) = b.run_read(&reads)?;
    timing.kernel += kernel;
    let order = want_order.then(|| r.remove(1));
    Ok(Picked {
        triangles: r.remove(0),
        order,
        timing,
    })
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
