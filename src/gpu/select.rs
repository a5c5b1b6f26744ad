//! LOD selection on the GPU (`wgsl/select.wgsl`): for a batch of views, decide every loaded meshlet
//! of a flattened DAG ([`crate::lod::flat`]), then compact the drawn ones in order. The CPU mirror
//! is [`crate::lod::flat::select_meshlets`]; the two agree bit for bit (see [`crate::lod::select`] for how
//! the arithmetic is made exact), so parity is checked by equality of the selected sets.

use super::scan::Scan;
use super::{binding_set, param_block, wgsl, Batch, Gpu, GpuError, Kernels};
use crate::lod::flat::Flat;
pub use crate::lod::flat::ViewData;

/// (view, meshlet) pairs per submission: keeps each buffer at 16 MiB, far below lavapipe's
/// 128 MiB binding limit, and the readback small.
const PAIRS_PER_BATCH: usize = 1 << 22;

param_block! {
    /// `struct Params` of `wgsl/select.wgsl`.
    pub struct Params {
        /// (view, meshlet) pairs.
        n,
        /// Meshlets per view.
        per_view,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/select.wgsl`, in binding order.
    pub struct Buffers {
        /// The flattened DAG's records.
        records: Read,
        /// One view per camera.
        views: Read,
        /// 1 where a (view, meshlet) pair is drawn.
        flags: ReadWrite,
        /// The flags' exclusive scan.
        offsets: ReadWrite,
        /// Out: drawn pairs, compacted.
        ids: ReadWrite,
    }
}

/// A flattened DAG on the GPU with the selection kernels.
pub struct Selector<'a> {
    gpu: &'a Gpu,
    kernels: Kernels<Params>,
    scan: Scan,
    records: wgpu::Buffer,
    meshlets: usize,
}

impl<'a> Selector<'a> {
    /// Uploads `flat`'s records and compiles the kernels.
    pub fn new(gpu: &'a Gpu, flat: &Flat) -> Self {
        Self {
            gpu,
            kernels: Kernels::new::<Buffers>(
                gpu,
                "select",
                wgsl!("select.wgsl"),
                &["decide", "compact"],
            ),
            scan: Scan::new(gpu),
            records: gpu.upload("lod records", &flat.records),
            meshlets: flat.records.len(),
        }
    }

    /// The drawn meshlets of every view (ascending flat indices) and the summed kernel time in
    /// seconds.
    pub fn select(&self, views: &[ViewData]) -> Result<(Vec<Vec<u32>>, f64), GpuError> {
        let n = self.meshlets.max(1);
        let per_batch = (PAIRS_PER_BATCH / n).max(1);
        let mut out = Vec::with_capacity(views.len());
        let mut time = 0.0;
        for chunk in views.chunks(per_batch) {
            let (ids, t) = self.run(chunk, n)?;
            time += t;
            out.extend(ids);
        }
        Ok((out, time))
    }

    fn run(&self, views: &[ViewData], n: usize) -> Result<(Vec<Vec<u32>>, f64), GpuError> {
        let gpu = self.gpu;
        let pairs = views.len() * n;
        let view_buf = gpu.upload("views", views);
        let flags = gpu.zeros("flags", pairs);
        let offsets = gpu.zeros("offsets", pairs);
        let ids = gpu.zeros("ids", pairs);
        let bind = self.kernels.bind(
            gpu,
            &Buffers {
                records: &self.records,
                views: &view_buf,
                flags: &flags,
                offsets: &offsets,
                ids: &ids,
            },
        );
        let scan = self.scan.bind(gpu, &offsets, pairs);
        let p = Params {
            n: pairs as u32,
            per_view: n as u32,
        };
        let mut b = Batch::new(gpu);
        b.threads(&self.kernels, "decide", &bind, p, pairs);
        self.scan.record(&mut b, &scan);
        b.threads(&self.kernels, "compact", &bind, p, pairs);
        let t = b.run()?;
        let last_offset = gpu.read(&offsets, pairs - 1, 1)?[0];
        let last_flag = gpu.read(&flags, pairs - 1, 1)?[0];
        let total = (last_offset + last_flag) as usize;
        let all = if total > 0 {
            gpu.read(&ids, 0, total)?
        } else {
            Vec::new()
        };
        let mut per_view = vec![Vec::new(); views.len()];
        for id in all {
            per_view[id as usize / n].push(id % n as u32);
        }
        Ok((per_view, t))
    }
}
