//! Adjacency on the GPU (`wgsl/adjacency.wgsl`): vertex -> triangle CSR and the triangle dual
//! graph, identical to [`crate::adjacency::vertex_triangles`] and [`crate::adjacency::dual_graph`],
//! plus per-side edge flags equal to [`crate::adjacency::side_flags`].

use super::{binding_set, param_block, timed, wgsl, Batch, Gpu, GpuError, Kernels, Scan, Split};
use crate::adjacency::Csr;
use crate::mesh::Mesh;

/// Upload, kernel and readback times of one GPU job, in seconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct Timing {
    /// Host -> device copies (buffer creation included).
    pub upload: f64,
    /// Kernel time (GPU timestamps when the adapter has them).
    pub kernel: f64,
    /// Device -> host copies.
    pub readback: f64,
}

impl Timing {
    /// Sum of the three.
    pub fn total(&self) -> f64 {
        self.upload + self.kernel + self.readback
    }
}

param_block! {
    /// `struct Params` of `wgsl/adjacency.wgsl`.
    pub struct Params {
        /// Vertices.
        n,
        /// Triangles.
        t,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/adjacency.wgsl`, in binding order.
    pub struct Buffers {
        /// Index buffer, first part.
        idx_a: Read,
        /// Index buffer, second part.
        idx_b: Read,
        /// Vertex -> triangle offsets (counted, then scanned).
        vt_off: ReadWrite,
        /// Vertex -> triangle items, first part.
        vt_a: ReadWrite,
        /// Vertex -> triangle items, second part.
        vt_b: ReadWrite,
        /// Scatter cursor per vertex.
        cursor: ReadWrite,
        /// Dual-graph offsets.
        dual_off: ReadWrite,
        /// Dual-graph items, first part (a placeholder until the count is known).
        dual_a: ReadWrite,
        /// Dual-graph items, second part.
        dual_b: ReadWrite,
        /// Per-side edge flags.
        side_flags: ReadWrite,
        /// 1 for a degenerate triangle.
        degenerate: ReadWrite,
        /// Gathered neighbours, first part.
        near_a: ReadWrite,
        /// Gathered neighbours, second part.
        near_b: ReadWrite,
    }
}

/// The adjacency kernels.
pub struct AdjacencyKernels {
    kernels: Kernels<Params>,
    scan: Scan,
}

/// Adjacency resident on the GPU (inputs to the k-medoids and grower kernels).
pub struct DeviceAdjacency {
    /// The index buffer.
    pub indices: Split,
    /// Vertex -> triangle row starts (`vertices + 1`).
    pub vt_offsets: wgpu::Buffer,
    /// Vertex -> triangle items.
    pub vt_items: Split,
    /// Dual-graph row starts (`triangles + 1`).
    pub dual_offsets: wgpu::Buffer,
    /// Dual-graph items.
    pub dual_items: Split,
    /// Per-triangle side flags (see [`crate::adjacency::side_flags`]).
    pub side_flags: wgpu::Buffer,
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    vt_len: usize,
}

/// Adjacency read back to the host.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HostAdjacency {
    /// Vertex -> triangles.
    pub vertex_triangles: Csr,
    /// Triangle -> edge-adjacent triangles.
    pub dual: Csr,
    /// Per-triangle side flags.
    pub side_flags: Vec<u32>,
}

impl AdjacencyKernels {
    /// Compiles the kernels.
    pub fn new(gpu: &Gpu) -> Self {
        Self {
            kernels: Kernels::new::<Buffers>(
                gpu,
                "adjacency",
                wgsl!("adjacency.wgsl"),
                &[
                    "vt_count",
                    "vt_scatter",
                    "vt_sort",
                    "dual_count",
                    "dual_fill",
                ],
            ),
            scan: Scan::new(gpu),
        }
    }

    /// Uploads the mesh and builds both CSRs on the GPU.
    pub fn build(&self, gpu: &Gpu, mesh: &Mesh) -> Result<(DeviceAdjacency, Timing), GpuError> {
        let (indices, up) = timed(|| Split::upload(gpu, "indices", &mesh.indices));
        let (adj, mut timing) = self.build_from(gpu, indices?, mesh.vertex_count())?;
        timing.upload += up;
        Ok((adj, timing))
    }

    /// Builds both CSRs over an index buffer already on the device (`vertices` vertices).
    pub fn build_from(
        &self,
        gpu: &Gpu,
        indices: Split,
        vertices: usize,
    ) -> Result<(DeviceAdjacency, Timing), GpuError> {
        let (n, t) = (vertices, indices.len / 3);
        let mut timing = Timing::default();
        let (uploaded, up) = timed(|| -> Result<_, GpuError> {
            let vt_items = Split::zeros(gpu, "vt items", 3 * t)?;
            let r = (
                gpu.zeros("vt offsets", n + 1),
                vt_items,
                gpu.zeros("vt cursor", n),
                gpu.zeros("dual offsets", t + 1),
                gpu.zeros("side flags", t),
                gpu.zeros("degenerate", t),
                Split::zeros(gpu, "gathered neighbours", 3 * t)?,
            );
            gpu.wait()?;
            Ok(r)
        });
        let (vt_offsets, vt_items, cursor, dual_offsets, side_flags, degenerate, near) = uploaded?;
        timing.upload += up;
        let placeholder = (gpu.zeros("dual a", 1), gpu.zeros("dual b", 1));
        let bind = |da: &wgpu::Buffer, db: &wgpu::Buffer| {
            self.kernels.bind(
                gpu,
                &Buffers {
                    idx_a: &indices.a,
                    idx_b: &indices.b,
                    vt_off: &vt_offsets,
                    vt_a: &vt_items.a,
                    vt_b: &vt_items.b,
                    cursor: &cursor,
                    dual_off: &dual_offsets,
                    dual_a: da,
                    dual_b: db,
                    side_flags: &side_flags,
                    degenerate: &degenerate,
                    near_a: &near.a,
                    near_b: &near.b,
                },
            )
        };
        let first = bind(&placeholder.0, &placeholder.1);
        let p = Params {
            n: n as u32,
            t: t as u32,
        };
        let scan_vt = self.scan.bind(gpu, &vt_offsets, n + 1);
        let scan_dual = self.scan.bind(gpu, &dual_offsets, t + 1);
        let mut b = Batch::new(gpu);
        let k = &self.kernels;
        b.threads(k, "vt_count", &first, p, t);
        self.scan.record(&mut b, &scan_vt);
        b.threads(k, "vt_scatter", &first, p, t);
        b.threads(k, "vt_sort", &first, p, n);
        b.threads(k, "dual_count", &first, p, t);
        self.scan.record(&mut b, &scan_dual);
        timing.kernel += b.run()?;
        let (totals, rb) = timed(|| -> Result<_, GpuError> {
            Ok((
                gpu.read(&vt_offsets, n, 1)?[0] as usize,
                gpu.read(&dual_offsets, t, 1)?[0] as usize,
            ))
        });
        let (vt_len, dual_len) = totals?;
        timing.readback += rb;
        let dual_items = Split::zeros(gpu, "dual items", dual_len)?;
        let second = bind(&dual_items.a, &dual_items.b);
        let mut b = Batch::new(gpu);
        b.threads(k, "dual_fill", &second, p, t);
        timing.kernel += b.run()?;
        Ok((
            DeviceAdjacency {
                indices,
                vt_offsets,
                vt_items,
                dual_offsets,
                dual_items,
                side_flags,
                vertices: n,
                triangles: t,
                vt_len,
            },
            timing,
        ))
    }
}

impl DeviceAdjacency {
    /// Reads everything back.
    pub fn read(&self, gpu: &Gpu) -> Result<HostAdjacency, GpuError> {
        let mut vt_items = self.vt_items.read(gpu)?;
        vt_items.truncate(self.vt_len);
        Ok(HostAdjacency {
            vertex_triangles: Csr {
                offsets: gpu.read(&self.vt_offsets, 0, self.vertices + 1)?,
                items: vt_items,
            },
            dual: self.read_dual(gpu)?,
            side_flags: gpu.read(&self.side_flags, 0, self.triangles)?,
        })
    }

    /// Reads the dual graph back.
    pub fn read_dual(&self, gpu: &Gpu) -> Result<Csr, GpuError> {
        Ok(Csr {
            offsets: gpu.read(&self.dual_offsets, 0, self.triangles + 1)?,
            items: self.dual_items.read(gpu)?,
        })
    }
}

/// Builds the adjacency on the GPU and reads it back, with timings.
pub fn adjacency(gpu: &Gpu, mesh: &Mesh) -> Result<(HostAdjacency, Timing), GpuError> {
    let k = AdjacencyKernels::new(gpu);
    let (dev, mut timing) = k.build(gpu, mesh)?;
    let (host, rb) = timed(|| dev.read(gpu));
    timing.readback += rb;
    Ok((host?, timing))
}
