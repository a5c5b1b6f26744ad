//! Exclusive prefix sum on the GPU (`wgsl/scan.wgsl`), the building block of every CSR.

use super::{binding_set, param_block, wgsl, Batch, Gpu, Kernels};

/// Block size of the scan kernels (64 threads x 16 items).
const BLOCK: usize = 1024;

param_block! {
    /// `struct Params` of `wgsl/scan.wgsl`.
    pub struct Params {
        /// Elements to scan.
        n,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/scan.wgsl`, in binding order.
    pub struct Buffers {
        /// The array scanned in place.
        data: ReadWrite,
        /// Block sums (scratch).
        sums: ReadWrite,
    }
}

/// The scan kernels and their block-sum scratch.
pub struct Scan {
    kernels: Kernels<Params>,
}

impl Scan {
    /// Compiles the kernels.
    pub fn new(gpu: &Gpu) -> Self {
        Self {
            kernels: Kernels::new::<Buffers>(
                gpu,
                "scan",
                wgsl!("scan.wgsl"),
                &["block_sums", "scan_sums", "scan_blocks"],
            ),
        }
    }

    /// Records an in-place exclusive scan of the first `n` u32 of `data` into `batch`. The caller
    /// keeps the returned bind group alive until the batch has run.
    pub fn bind(&self, gpu: &Gpu, data: &wgpu::Buffer, n: usize) -> ScanJob {
        let sums = gpu.zeros("scan sums", n.div_ceil(BLOCK));
        ScanJob {
            bind: self.kernels.bind(gpu, &Buffers { data, sums: &sums }),
            _sums: sums,
            n,
        }
    }

    /// Adds the three passes of `job` to `batch`.
    pub fn record<'a>(&'a self, batch: &mut Batch<'a>, job: &'a ScanJob) {
        let p = Params { n: job.n as u32 };
        let blocks = job.n.div_ceil(BLOCK) as u32;
        batch.groups(&self.kernels, "block_sums", &job.bind, p, blocks);
        batch.groups(&self.kernels, "scan_sums", &job.bind, p, 1);
        batch.groups(&self.kernels, "scan_blocks", &job.bind, p, blocks);
    }
}

/// A bound scan over one buffer.
pub struct ScanJob {
    bind: wgpu::BindGroup,
    _sums: wgpu::Buffer,
    n: usize,
}
