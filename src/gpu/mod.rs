//! GPU compute with wgpu: a headless context, shared buffer and timing helpers, and one driver per
//! kernel family next to its WGSL file in `wgsl/`.
//!
//! Every kernel has a CPU reference elsewhere in the crate over the same flat arrays (CSR offsets
//! and items, u32 labels), so parity is a direct comparison (`tests/gpu_parity.rs`,
//! `meshletlab parity`). Kernels run on any Vulkan adapter; on a machine without a GPU that is
//! Mesa's lavapipe, which the project's setup installs.
//!
//! Buffers: lavapipe binds at most 128 MiB per storage binding, so arrays that can exceed it
//! (index buffer, vertex->triangle items, dual-graph items) are split into two physical buffers
//! ([`Split`]) and the WGSL reads them through an accessor. Two parts of 2^25 u32 each carry meshes
//! up to about 21 M triangles.

pub mod adjacency;
pub mod bounds;
pub mod grow;
pub mod kmedoids;
pub mod parity;
mod scan;
pub mod select;

use bytemuck::Pod;
use std::time::Instant;
use wgpu::util::DeviceExt;

pub use scan::Scan;

/// Why the GPU path could not run.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan adapter at all.
    #[error(
        "no Vulkan adapter found ({0}); install Mesa's lavapipe with `make setup` \
         (scripts/setup.sh) or a GPU driver; the CPU strategies work without one"
    )]
    NoAdapter(String),
    /// The adapter refused the device (a missing feature or limit).
    #[error("the Vulkan adapter {adapter} cannot run the kernels: {reason}; `make setup` installs lavapipe, which can")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's reason.
        reason: String,
    },
    /// The input is larger than the kernels' buffers can address.
    #[error("{what}: {len} elements exceed the GPU path's limit of {max}")]
    TooLarge {
        /// Which array.
        what: &'static str,
        /// Its length.
        len: usize,
        /// The most the split buffers hold.
        max: usize,
    },
    /// The GPU path does not offer this.
    #[error("{0}")]
    Unsupported(&'static str),
    /// A readback failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
}

/// Elements per part of a [`Split`] array: 2^25 u32 = 128 MiB, lavapipe's storage-binding limit.
pub const PART: usize = 1 << 25;

/// A GPU context: one adapter, device and queue, plus timestamp support.
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter name, driver and type.
    pub info: wgpu::AdapterInfo,
    /// Whether kernel time comes from GPU timestamps (else from wall time around the dispatches).
    pub timestamps: bool,
    period_ns: f32,
    /// Per-dispatch [`Params`] at a 256-byte stride, bound with dynamic offsets.
    params: wgpu::Buffer,
}

impl Gpu {
    /// Opens the default adapter (lavapipe on a machine without a GPU) with timestamps if offered.
    pub fn new() -> Result<Self, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        // DEBUG makes the validation layer log a false "Invalid source language operand" error.
        desc.flags = wgpu::InstanceFlags::empty();
        let instance = wgpu::Instance::new(desc);
        let adapter =
            pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
                .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut features = wgpu::Features::empty();
        if timestamps {
            features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        let al = adapter.limits();
        let limits = wgpu::Limits {
            max_storage_buffers_per_shader_stage: 16.min(al.max_storage_buffers_per_shader_stage),
            max_storage_buffer_binding_size: al.max_storage_buffer_binding_size,
            max_buffer_size: al.max_buffer_size,
            max_compute_workgroups_per_dimension: al.max_compute_workgroups_per_dimension,
            max_compute_workgroup_storage_size: al.max_compute_workgroup_storage_size,
            ..wgpu::Limits::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("meshletlab"),
            required_features: features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: info.name.clone(),
            reason: e.to_string(),
        })?;
        if (device.limits().max_storage_buffer_binding_size as usize) < PART * 4 {
            return Err(GpuError::Device {
                adapter: info.name.clone(),
                reason: "storage bindings under 128 MiB".into(),
            });
        }
        let period_ns = queue.get_timestamp_period();
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: PARAM_SLOTS * PARAM_STRIDE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            params,
            device,
            queue,
            info,
            timestamps,
            period_ns,
        })
    }

    /// "name (driver, type)".
    pub fn describe(&self) -> String {
        format!(
            "{} ({} {}, {:?})",
            self.info.name, self.info.driver, self.info.driver_info, self.info.device_type
        )
    }

    /// A storage buffer holding `data` (at least 4 bytes, so empty arrays still bind).
    pub fn upload<T: Pod>(&self, label: &str, data: &[T]) -> wgpu::Buffer {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let contents = if bytes.is_empty() {
            &[0u8; 4][..]
        } else {
            bytes
        };
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: STORAGE,
            })
    }

    /// A zeroed storage buffer of `len` u32 (at least one).
    pub fn zeros(&self, label: &str, len: usize) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: 4 * len.max(1) as u64,
            usage: STORAGE,
            mapped_at_creation: false,
        })
    }

    /// Reads `len` u32 from `buf` at element `offset`.
    pub fn read(
        &self,
        buf: &wgpu::Buffer,
        offset: usize,
        len: usize,
    ) -> Result<Vec<u32>, GpuError> {
        if len == 0 {
            return Ok(Vec::new());
        }
        let size = 4 * len as u64;
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buf, 4 * offset as u64, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let out = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| GpuError::Readback(format!("{e:?}")))?;
            bytemuck::cast_slice::<u8, u32>(&view).to_vec()
        };
        staging.unmap();
        Ok(out)
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()))
    }
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// An array stored as two buffers of at most [`PART`] u32 each; WGSL reads it through an accessor
/// (`x < PART ? a[x] : b[x - PART]`).
pub struct Split {
    /// Elements `0..PART`.
    pub a: wgpu::Buffer,
    /// Elements `PART..` (a 4-byte placeholder when unused).
    pub b: wgpu::Buffer,
    /// Element count.
    pub len: usize,
}

impl Split {
    /// Uploads `data`.
    pub fn upload(gpu: &Gpu, what: &'static str, data: &[u32]) -> Result<Self, GpuError> {
        check_len(what, data.len())?;
        let cut = data.len().min(PART);
        Ok(Self {
            a: gpu.upload(what, &data[..cut]),
            b: gpu.upload(what, &data[cut..]),
            len: data.len(),
        })
    }

    /// A zeroed array of `len` elements.
    pub fn zeros(gpu: &Gpu, what: &'static str, len: usize) -> Result<Self, GpuError> {
        check_len(what, len)?;
        Ok(Self {
            a: gpu.zeros(what, len.min(PART)),
            b: gpu.zeros(what, len.saturating_sub(PART)),
            len,
        })
    }

    /// Reads the whole array back.
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<u32>, GpuError> {
        let mut v = gpu.read(&self.a, 0, self.len.min(PART))?;
        v.extend(gpu.read(&self.b, 0, self.len.saturating_sub(PART))?);
        Ok(v)
    }
}

fn check_len(what: &'static str, len: usize) -> Result<(), GpuError> {
    if len > 2 * PART {
        return Err(GpuError::TooLarge {
            what,
            len,
            max: 2 * PART,
        });
    }
    Ok(())
}

/// Parameters of one dispatch, at a 256-byte stride in a uniform buffer (dynamic offsets).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Params {
    /// Kernel-specific words (counts, the BFS level, limits, ...).
    pub w: [u32; 8],
}

const PARAM_STRIDE: u64 = 256;

/// One WGSL module, its pipelines and its fixed bind-group layout: binding 0 is the [`Params`]
/// uniform (dynamic offset), bindings 1..=n read-write storage buffers. Every entry point sees
/// the same layout, so one bind group serves the whole family.
pub struct Kernels {
    layout: wgpu::BindGroupLayout,
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
}

impl Kernels {
    /// Compiles `source` with `storage` storage bindings and builds a pipeline per entry point.
    pub fn new(
        gpu: &Gpu,
        label: &str,
        source: &str,
        storage: u32,
        entries: &[&'static str],
    ) -> Self {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let mut layout_entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
            },
            count: None,
        }];
        layout_entries.extend((1..=storage).map(|b| wgpu::BindGroupLayoutEntry {
            binding: b,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &layout_entries,
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipelines = entries
            .iter()
            .map(|&e| {
                let p = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(e),
                    layout: Some(&pl),
                    module: &module,
                    entry_point: Some(e),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        // Every kernel writes its workgroup memory before reading it; zeroing
                        // 25 KiB per workgroup cost more than the medoid update itself on lavapipe.
                        zero_initialize_workgroup_memory: false,
                        ..Default::default()
                    },
                    cache: None,
                });
                (e, p)
            })
            .collect();
        Self { layout, pipelines }
    }

    /// The bind group for `buffers` (bindings 1..) with the params buffer at binding 0.
    pub fn bind(&self, gpu: &Gpu, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let params = &gpu.params;
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: params,
                offset: 0,
                size: wgpu::BufferSize::new(std::mem::size_of::<Params>() as u64),
            }),
        }];
        entries.extend(
            buffers
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry {
                    binding: i as u32 + 1,
                    resource: b.as_entire_binding(),
                }),
        );
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.layout,
            entries: &entries,
        })
    }

    fn pipeline(&self, entry: &str) -> &wgpu::ComputePipeline {
        &self
            .pipelines
            .iter()
            .find(|(e, _)| *e == entry)
            .unwrap_or_else(|| panic!("kernel {entry} not built"))
            .1
    }
}

/// Workgroup size of the one-thread-per-element kernels (matches `@workgroup_size(64)` in WGSL).
pub const WG: u32 = 64;

/// A batch of dispatches recorded into one compute pass (WebGPU orders storage writes between
/// dispatches), timed by GPU timestamps around the pass when the adapter has them.
pub struct Batch<'a> {
    gpu: &'a Gpu,
    steps: Vec<Step<'a>>,
}

struct Step<'a> {
    kernels: &'a Kernels,
    entry: &'static str,
    bind: &'a wgpu::BindGroup,
    params: Params,
    dims: [u32; 3],
}

impl<'a> Batch<'a> {
    /// An empty batch.
    pub fn new(gpu: &'a Gpu) -> Self {
        Self {
            gpu,
            steps: Vec::new(),
        }
    }

    /// Adds a dispatch of `threads` threads of a `@workgroup_size(64)` kernel.
    pub fn threads(
        &mut self,
        k: &'a Kernels,
        entry: &'static str,
        bind: &'a wgpu::BindGroup,
        params: Params,
        threads: usize,
    ) {
        self.groups(k, entry, bind, params, (threads as u32).div_ceil(WG));
    }

    /// Adds a dispatch of `groups` workgroups, split over y above 65535 (kernels rebuild the flat
    /// workgroup id as `x + y * 65535`).
    pub fn groups(
        &mut self,
        k: &'a Kernels,
        entry: &'static str,
        bind: &'a wgpu::BindGroup,
        params: Params,
        groups: u32,
    ) {
        if groups == 0 {
            return;
        }
        let dims = if groups <= MAX_X {
            [groups, 1, 1]
        } else {
            [MAX_X, groups.div_ceil(MAX_X), 1]
        };
        self.steps.push(Step {
            kernels: k,
            entry,
            bind,
            params,
            dims,
        });
    }

    /// Records, submits and waits; returns the kernel time in seconds: GPU timestamps around the
    /// pass when available, else wall time from submit to idle.
    pub fn run(self) -> Result<f64, GpuError> {
        let mut total = 0.0;
        if std::env::var_os("MESHLETLAB_GPU_PROFILE").is_some() {
            // One submission per dispatch, each timed: a profile, not a benchmark.
            for s in &self.steps {
                let t = self.run_chunk(std::slice::from_ref(s))?;
                eprintln!("gpu profile: {:<14} {:>9.3} ms", s.entry, t * 1e3);
                total += t;
            }
            return Ok(total);
        }
        for chunk in self.steps.chunks(PARAM_SLOTS as usize) {
            total += self.run_chunk(chunk)?;
        }
        Ok(total)
    }

    fn run_chunk(&self, steps: &[Step<'a>]) -> Result<f64, GpuError> {
        let gpu = self.gpu;
        let mut bytes = vec![0u8; PARAM_STRIDE as usize * steps.len()];
        for (i, s) in steps.iter().enumerate() {
            let o = i * PARAM_STRIDE as usize;
            bytes[o..o + std::mem::size_of::<Params>()]
                .copy_from_slice(bytemuck::bytes_of(&s.params));
        }
        if !bytes.is_empty() {
            gpu.queue.write_buffer(&gpu.params, 0, &bytes);
        }
        let queries = gpu.timestamps.then(|| {
            let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel time"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: queries.as_ref().map(|(set, _)| {
                    wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    }
                }),
            });
            for (i, s) in steps.iter().enumerate() {
                pass.set_pipeline(s.kernels.pipeline(s.entry));
                pass.set_bind_group(0, s.bind, &[(i as u64 * PARAM_STRIDE) as u32]);
                pass.dispatch_workgroups(s.dims[0], s.dims[1], s.dims[2]);
            }
        }
        if let Some((set, resolve)) = &queries {
            enc.resolve_query_set(set, 0..2, resolve, 0);
        }
        let t = Instant::now();
        gpu.queue.submit([enc.finish()]);
        gpu.wait()?;
        let wall = t.elapsed().as_secs_f64();
        match &queries {
            Some((_, resolve)) => {
                let ts = gpu.read(resolve, 0, 4)?;
                let begin = ts[0] as u64 | (ts[1] as u64) << 32;
                let end = ts[2] as u64 | (ts[3] as u64) << 32;
                Ok(end.saturating_sub(begin) as f64 * gpu.period_ns as f64 * 1e-9)
            }
            None => Ok(wall),
        }
    }
}

/// Parameter slots per submission.
const PARAM_SLOTS: u64 = 4096;
const MAX_X: u32 = 65535;

/// Wall time of `f` in seconds.
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let r = f();
    (r, t.elapsed().as_secs_f64())
}

#[cfg(test)]
mod shaders_test;
