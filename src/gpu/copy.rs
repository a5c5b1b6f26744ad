//! The memory-bandwidth probe (`wgsl/copy.wgsl`): a copy kernel whose bytes moved over its time
//! is the device's bandwidth, the floor `bench gpu` puts under every kernel (`docs/gpu-clustering.md`).

use super::{binding_set, param_block, wgsl, Batch, Gpu, GpuError, Kernels};

param_block! {
    /// `struct Params` of `wgsl/copy.wgsl`.
    pub struct Params {
        /// Elements to copy, in 16-byte vec4s.
        n,
    }
}

binding_set! {
    /// The storage buffers of `wgsl/copy.wgsl`, in binding order.
    pub struct Buffers {
        /// Source.
        src: Read,
        /// Destination.
        dst: ReadWrite,
    }
}

/// A measured bandwidth.
#[derive(Clone, Copy, Debug)]
pub struct Bandwidth {
    /// Bytes read plus bytes written per copy.
    pub bytes: u64,
    /// Median kernel time of one copy, in seconds.
    pub seconds: f64,
}

impl Bandwidth {
    /// Bytes per second (read and written together).
    pub fn per_second(&self) -> f64 {
        self.bytes as f64 / self.seconds.max(f64::MIN_POSITIVE)
    }
}

/// Copies `bytes` (rounded down to whole 16-byte elements, at most 128 MiB: lavapipe's binding
/// limit) from one buffer to another `runs` times, checks the copy once, and returns the median.
pub fn bandwidth(gpu: &Gpu, bytes: usize, runs: usize) -> Result<Bandwidth, GpuError> {
    let words = (bytes.min(super::PART * 4) / 16) * 4;
    // A pattern, not zeros: a driver may treat untouched or zero pages specially.
    let data: Vec<u32> = (0..words as u32)
        .map(|i| i.wrapping_mul(0x9E37_79B9))
        .collect();
    let src = gpu.upload("copy src", &data);
    let dst = gpu.zeros("copy dst", words);
    let k = Kernels::<Params>::new::<Buffers>(gpu, "copy", wgsl!("copy.wgsl"), &["copy"]);
    let bind = k.bind(
        gpu,
        &Buffers {
            src: &src,
            dst: &dst,
        },
    );
    let p = Params {
        n: (words / 4) as u32,
    };
    let mut times = Vec::with_capacity(runs.max(1));
    for _ in 0..runs.max(1) {
        let mut b = Batch::new(gpu);
        b.groups(&k, "copy", &bind, p, gpu.stride_groups(words / 4));
        times.push(b.run()?);
    }
    // The copy is checked at both ends and the middle (a whole readback would double the time).
    for at in [0, words / 2, words.saturating_sub(4)] {
        let n = 4.min(words - at);
        if gpu.read(&dst, at, n)? != data[at..at + n] {
            return Err(GpuError::Wrong(format!("copy kernel: word {at} differs")));
        }
    }
    times.sort_by(f64::total_cmp);
    Ok(Bandwidth {
        bytes: 2 * 4 * words as u64,
        seconds: times[times.len() / 2],
    })
}
