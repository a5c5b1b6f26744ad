//! GPU compute with wgpu: a headless context, shared buffer and timing helpers, and one driver per
//! kernel family next to its WGSL file in `wgsl/`.
//!
//! Every kernel has a CPU reference elsewhere in the crate over the same flat arrays (CSR offsets
//! and items, u32 labels), so parity is a direct comparison (`tests/gpu_parity.rs`,
//! `meshletlab parity`). Driver, shader and CPU reference share a name wherever they can:
//!
//! | driver | shader (`wgsl/`) | CPU reference |
//! |---|---|---|
//! | [`adjacency`] | `adjacency.wgsl` | `crate::adjacency` (and `mesh::edges`) |
//! | [`assign`] | `assign.wgsl` | `strategy::kmedoids::assign` (the multi-source BFS of `kmedoids-flat` and the coarse regions) |
//! | [`kmedoids_flat`] | `update.wgsl`, `split.wgsl` (with `assign.wgsl`) | `strategy::kmedoids::{update, split}`, driven as `strategy::kmedoids::flat` (`kmedoids-flat`) |
//! | [`morton`] | `morton.wgsl` | `strategy::kmedoids::morton` (the flat method's seeds, `flat::initial_medoids`; the fine centroid cells) |
//! | [`coarse`] | `coarse.wgsl` (with `morton.wgsl`, `assign.wgsl`) | `strategy::kmedoids::coarse` (the regions of `kmedoids-parallel`) |
//! | [`kmedoids_parallel`] | `kmedoids_parallel.wgsl` (with `medoid.wgsl`) | `strategy::kmedoids::parallel` (`kmedoids-parallel`) |
//! | [`kmedoids_parallel_moves`] | `kmedoids_parallel_moves.wgsl` (with `medoid.wgsl`) | `strategy::kmedoids::parallel::moves` (the medoid iteration of `kmedoids-parallel`) |
//! | [`grow`] | `grow.wgsl` | `strategy::grow` (`bsphere-parallel`) |
//! | [`assemble`] | `assemble.wgsl` | `meshlet::assemble` (meshlets from a clustering) |
//! | [`bounds`] | `bounds.wgsl` | [`bounds::sphere_f32`], checked against `meshlet::bounds`; the cones of `task_bounds` checked conservative (`meshlet::bounds::check_cones`) |
//! | [`select`] | `select.wgsl` | `lod::select` |
//! | `scan` | `scan.wgsl` | a prefix sum (used by the others) |
//! | [`copy`] | `copy.wgsl` | none: the bandwidth probe of `bench gpu` |
//!
//! [`build::build`] builds meshlets on the GPU with any strategy whose every step is a kernel
//! (`meshletlab build --device gpu`); [`build::build_resident`] leaves them, with their culling
//! bounds (sphere and cone), in device buffers for a renderer, and [`build::build_on_device`] builds them from a
//! mesh already on the device ([`DeviceMesh`]: an engine's vertex and index buffers);
//! `examples/gpu_draw.rs` draws from them with no readback in between.
//!
//! Why integer keys and exactly rounded arithmetic make the parity exact: `docs/gpu-clustering.md`. Kernels run on any Vulkan adapter; on a machine without a GPU that is
//! Mesa's lavapipe, which the project's setup installs.
//!
//! Buffers: lavapipe binds at most 128 MiB per storage binding, so arrays that can exceed it
//! (index buffer, vertex->triangle items, dual-graph items) are split into two physical buffers
//! ([`Split`]) and the WGSL reads them through an accessor. Two parts of 2^25 u32 each carry meshes
//! up to about 21 M triangles.

pub mod adjacency;
pub mod assemble;
pub mod assign;
pub mod bounds;
pub mod build;
pub mod coarse;
pub mod copy;
pub mod grow;
pub mod kmedoids_flat;
pub mod kmedoids_parallel;
pub mod kmedoids_parallel_moves;
pub mod morton;
pub mod parity;
mod scan;
pub mod select;
pub mod source;

use bytemuck::Pod;
use std::any::{Any, TypeId};
use std::collections::{BTreeMap, HashMap};
use std::sync::Mutex;
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
        /// The most the buffers hold.
        max: usize,
    },
    /// The GPU path does not offer this.
    #[error("{0}")]
    Unsupported(&'static str),
    /// A strategy without a whole GPU path was asked to build on the GPU.
    #[error("strategy '{0}' has no GPU path; --device gpu builds {list}", list = build::GPU_STRATEGIES.map(|k| k.name()).join(", "))]
    NoGpuPath(String),
    /// A readback failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
    /// A kernel's output is not what it must be (a driver fault).
    #[error("GPU kernel output is wrong: {0}")]
    Wrong(String),
}

/// Elements per part of a [`Split`] array: 2^25 u32 = 128 MiB, lavapipe's storage-binding limit.
pub const PART: usize = 1 << 25;

/// Storage buffers the widest kernel binds in one stage (`kmedoids_parallel.wgsl`: 16, lavapipe's limit; a
/// test counts them).
pub const MIN_STORAGE_BUFFERS: u32 = 16;

/// Workgroup memory the largest kernel declares, in bytes (`update.wgsl`'s medoid update: 6657
/// words, rounded up to whole KiB; a test sums the declarations).
pub const MIN_WORKGROUP_STORAGE: u32 = 27 * 1024;

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
    /// Per-dispatch [`ParamBlock`]s at a 256-byte stride, bound with dynamic offsets.
    params: wgpu::Buffer,
    /// Running host-side counts (see [`Gpu::profile`]).
    profile: Mutex<Profile>,
    /// Whether every dispatch gets its own timestamps (see [`Gpu::time_each_kernel`]).
    per_kernel: std::sync::atomic::AtomicBool,
    /// Kernel families already built on this device (see [`Kernels::with_constants`]).
    kernel_cache: Mutex<HashMap<KernelKey, Box<dyn Any + Send + Sync>>>,
    /// Kernel families built so far (see [`Gpu::kernel_families`]).
    families_built: std::sync::atomic::AtomicUsize,
}

/// What makes two kernel families the same: the module's source (a static text, by address and
/// length), its parameter block and binding set types, the entry points, and the `override`
/// values (as bits).
type KernelKey = (
    usize,
    usize,
    TypeId,
    &'static str,
    Vec<&'static str>,
    Vec<(String, u64)>,
);

/// Where GPU time went: host-side counts of submissions, dispatches and round trips, and, when
/// [`Gpu::time_each_kernel`] is on, GPU time per kernel entry point.
#[derive(Clone, Debug, Default)]
pub struct Profile {
    /// Command-buffer submissions.
    pub submissions: u64,
    /// Compute dispatches recorded.
    pub dispatches: u64,
    /// Times the host blocked until the GPU was idle (every readback is one).
    pub round_trips: u64,
    /// Host wall time spent blocked in those waits, in seconds.
    pub wait_seconds: f64,
    /// Kernel time from timestamps, in seconds (whole passes, or the sum of the per-kernel times).
    pub kernel_seconds: f64,
    /// Per entry point: dispatches and GPU seconds (only filled while timing each kernel).
    pub per_kernel: BTreeMap<&'static str, (u64, f64)>,
}

impl Profile {
    /// The difference `self - earlier` (counts since `earlier` was taken).
    pub fn since(&self, earlier: &Profile) -> Profile {
        let mut per_kernel = self.per_kernel.clone();
        for (k, (n, s)) in &earlier.per_kernel {
            let e = per_kernel.entry(k).or_insert((0, 0.0));
            e.0 -= n;
            e.1 -= s;
        }
        per_kernel.retain(|_, e| e.0 > 0);
        Profile {
            submissions: self.submissions - earlier.submissions,
            dispatches: self.dispatches - earlier.dispatches,
            round_trips: self.round_trips - earlier.round_trips,
            wait_seconds: self.wait_seconds - earlier.wait_seconds,
            kernel_seconds: self.kernel_seconds - earlier.kernel_seconds,
            per_kernel,
        }
    }
}

impl Gpu {
    /// Opens the default adapter (lavapipe on a machine without a GPU) with timestamps if offered.
    pub fn new() -> Result<Self, GpuError> {
        let adapter = Self::default_adapter()?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("meshletlab"),
            required_features: Self::wanted_features(&adapter),
            required_limits: Self::required_limits(&adapter.limits()),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: info.name.clone(),
            reason: e.to_string(),
        })?;
        Self::from_device(device, queue, info)
    }

    /// The adapter [`Gpu::new`] opens: Vulkan's default (lavapipe on a machine without a GPU).
    pub fn default_adapter() -> Result<wgpu::Adapter, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        // DEBUG makes the validation layer log a false "Invalid source language operand" error.
        desc.flags = wgpu::InstanceFlags::empty();
        let instance = wgpu::Instance::new(desc);
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
            .map_err(|e| GpuError::NoAdapter(e.to_string()))
    }

    /// The optional features the kernels use where `adapter` offers them (GPU timestamps, for
    /// kernel times); an engine adds them to its own device request.
    pub fn wanted_features(adapter: &wgpu::Adapter) -> wgpu::Features {
        adapter.features() & wgpu::Features::TIMESTAMP_QUERY
    }

    /// The limits to request for a device the kernels run on, from the adapter's: wgpu's
    /// defaults, raised to what the kernels bind (storage buffers per stage, the medoid update's
    /// workgroup memory) and to the adapter's buffer sizes and grid. An engine that passes its own
    /// device to [`Gpu::from_device`] requests at least these.
    pub fn required_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
        wgpu::Limits {
            max_storage_buffers_per_shader_stage: 16
                .min(adapter.max_storage_buffers_per_shader_stage),
            max_storage_buffer_binding_size: adapter.max_storage_buffer_binding_size,
            max_buffer_size: adapter.max_buffer_size,
            max_compute_workgroups_per_dimension: adapter.max_compute_workgroups_per_dimension,
            max_compute_workgroup_storage_size: adapter.max_compute_workgroup_storage_size,
            ..wgpu::Limits::default()
        }
    }

    /// Runs the kernels on a device the caller already holds (an engine's own `Device` and
    /// `Queue`, cloned handles of them), with `info` from its adapter for reports. The device
    /// must have been requested with at least [`Gpu::required_limits`]; one that has less is
    /// refused with the limit named, before any pipeline is created. Kernel times come from GPU
    /// timestamps when the device was requested with [`Gpu::wanted_features`].
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        info: wgpu::AdapterInfo,
    ) -> Result<Self, GpuError> {
        let have = device.limits();
        let short = |what: &str, has: u64, needs: u64| {
            GpuError::Device {
            adapter: info.name.clone(),
            reason: format!(
                "the device's {what} is {has}, the kernels need {needs} (request Gpu::required_limits)"
            ),
        }
        };
        if have.max_storage_buffers_per_shader_stage < MIN_STORAGE_BUFFERS {
            return Err(short(
                "max_storage_buffers_per_shader_stage",
                have.max_storage_buffers_per_shader_stage as u64,
                MIN_STORAGE_BUFFERS as u64,
            ));
        }
        if have.max_compute_workgroup_storage_size < MIN_WORKGROUP_STORAGE {
            return Err(short(
                "max_compute_workgroup_storage_size",
                have.max_compute_workgroup_storage_size as u64,
                MIN_WORKGROUP_STORAGE as u64,
            ));
        }
        if (have.max_storage_buffer_binding_size as usize) < PART * 4 {
            return Err(short(
                "max_storage_buffer_binding_size",
                have.max_storage_buffer_binding_size,
                (PART * 4) as u64,
            ));
        }
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
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
            profile: Mutex::new(Profile::default()),
            per_kernel: std::sync::atomic::AtomicBool::new(
                std::env::var_os("MESHLETLAB_GPU_PROFILE").is_some(),
            ),
            kernel_cache: Mutex::new(HashMap::new()),
            families_built: std::sync::atomic::AtomicUsize::new(0),
        })
    }

    /// The most u32 one storage binding of this device holds (its binding and buffer size
    /// limits, at least [`PART`]). Arrays that are not split over two bindings are checked
    /// against it, so a GPU with larger bindings runs larger meshes.
    pub fn binding_words(&self) -> usize {
        let l = self.device.limits();
        (l.max_storage_buffer_binding_size.min(l.max_buffer_size) / 4) as usize
    }

    /// Kernel families (a module's pipelines) built on this device so far, every time one was
    /// created: a build that finds its families in the cache adds none.
    pub fn kernel_families(&self) -> usize {
        self.families_built
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Times every dispatch on its own (one compute pass each, same submissions), so the
    /// [`Profile`] splits kernel time by entry point. Costs a little: passes end in barriers.
    /// `MESHLETLAB_GPU_PROFILE=1` turns it on from the start and prints the profile at exit of
    /// `parity`.
    pub fn time_each_kernel(&self, on: bool) {
        self.per_kernel
            .store(on, std::sync::atomic::Ordering::Relaxed);
    }

    /// Whether each dispatch is timed on its own.
    pub fn timing_each_kernel(&self) -> bool {
        self.per_kernel.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The counts so far (they keep running; diff two with [`Profile::since`]).
    pub fn profile(&self) -> Profile {
        self.profile.lock().expect("profile lock").clone()
    }

    fn count(&self, f: impl FnOnce(&mut Profile)) {
        f(&mut self.profile.lock().expect("profile lock"));
    }

    /// Whether the adapter is a CPU rasteriser (lavapipe): it runs a workgroup's invocations as
    /// 8-wide SIMD rows on the host's cores, so kernels size their workgroups and grids for that.
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Workgroups for a grid-stride kernel over `threads` elements: one per 64 on a GPU; on a CPU
    /// adapter a few per core, since each workgroup costs a coroutine start there and the
    /// elements are looped over anyway.
    pub fn stride_groups(&self, threads: usize) -> u32 {
        let groups = (threads as u32).div_ceil(WG).max(1);
        if self.is_cpu() {
            groups.min(32)
        } else {
            groups
        }
    }

    /// "name (driver, type)".
    pub fn describe(&self) -> String {
        let kind = match self.info.device_type {
            wgpu::DeviceType::Cpu => "software renderer on the CPU",
            wgpu::DeviceType::IntegratedGpu => "integrated GPU",
            wgpu::DeviceType::DiscreteGpu => "discrete GPU",
            wgpu::DeviceType::VirtualGpu => "virtual GPU",
            wgpu::DeviceType::Other => "other device",
        };
        format!(
            "{} ({} {}, {kind})",
            self.info.name, self.info.driver, self.info.driver_info
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

    /// Reads `len` u32 from `buf` at element `offset` (an empty [`Batch`] with one read).
    pub fn read(
        &self,
        buf: &wgpu::Buffer,
        offset: usize,
        len: usize,
    ) -> Result<Vec<u32>, GpuError> {
        if len == 0 {
            return Ok(Vec::new());
        }
        let (_, mut out) = Batch::new(self).run_read(&[(buf, offset, len)])?;
        Ok(out.remove(0))
    }

    fn submit(&self, enc: wgpu::CommandEncoder) {
        self.count(|p| p.submissions += 1);
        self.queue.submit([enc.finish()]);
    }

    /// Maps `staging` (already submitted to be filled), waits, and returns its words.
    fn map_read(&self, staging: &wgpu::Buffer) -> Result<Vec<u32>, GpuError> {
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

    /// Blocks until all submitted work is done (one host round trip).
    pub fn wait(&self) -> Result<(), GpuError> {
        let t = Instant::now();
        let r = self
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()));
        let s = t.elapsed().as_secs_f64();
        self.count(|p| {
            p.round_trips += 1;
            p.wait_seconds += s;
        });
        r
    }
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// A mesh already on the device, as an engine holds it: `positions` three f32 per vertex, tightly
/// packed, and `indices` three u32 per triangle, both created with `wgpu::BufferUsages::STORAGE`
/// on the device the [`Gpu`] runs on ([`Gpu::from_device`]). The GPU paths that take one read
/// nothing of the mesh on the host.
#[derive(Clone, Copy)]
pub struct DeviceMesh<'a> {
    /// Three f32 per vertex.
    pub positions: &'a wgpu::Buffer,
    /// Vertices.
    pub vertices: usize,
    /// Three u32 per triangle.
    pub indices: &'a wgpu::Buffer,
    /// Triangles.
    pub triangles: usize,
}

impl DeviceMesh<'_> {
    /// The index buffer as a [`Split`] array (the caller's buffer and an empty second part);
    /// refused above [`PART`] indices, one storage binding's worth.
    pub fn split_indices(&self, gpu: &Gpu) -> Result<Split, GpuError> {
        let len = 3 * self.triangles;
        if len > PART {
            return Err(GpuError::TooLarge {
                what: "index buffer on the device (one binding)",
                len,
                max: PART,
            });
        }
        Ok(Split {
            a: self.indices.clone(),
            b: gpu.zeros("indices (second part)", 0),
            len,
        })
    }
}

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

/// A kernel family's uniform parameters: a Pod struct of named u32 fields in the order of the
/// WGSL `struct Params` of its modules (`gpu::shaders_test` checks names, offsets and size
/// against naga's reflection of every module). Declared with `param_block!`.
pub trait ParamBlock: Pod {
    /// Field names, in declaration (= WGSL member) order; field `i` sits at byte `4 i`.
    const FIELDS: &'static [&'static str];
}

/// Declares a [`ParamBlock`]: `param_block! { /// doc\n pub struct X { /// doc\n a, /// doc\n b } }`
/// makes a `#[repr(C)]` Pod struct of `u32` fields.
macro_rules! param_block {
    ($(#[$m:meta])* pub struct $name:ident { $($(#[$fm:meta])* $field:ident),* $(,)? }) => {
        $(#[$m])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
        pub struct $name { $($(#[$fm])* pub $field: u32,)* }
        impl $crate::gpu::ParamBlock for $name {
            const FIELDS: &'static [&'static str] = &[$(stringify!($field)),*];
        }
    };
}
pub(crate) use param_block;

/// How a kernel family's modules use a storage binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Only read: declared `var<storage, read>` and bound read-only.
    Read,
    /// Written (or atomic) somewhere in the family: `var<storage, read_write>`.
    ReadWrite,
}

/// The storage buffers of a kernel family, one named field per binding in binding order (1..):
/// the field names are the WGSL variable names (checked by naga in `gpu::shaders_test`).
/// Declared with `binding_set!`.
pub trait BindingSet<'a> {
    /// (WGSL name, access) of bindings 1, 2, ...
    const LAYOUT: &'static [(&'static str, Access)];
    /// The buffers in binding order.
    fn buffers(&self) -> Vec<&'a wgpu::Buffer>;
}

/// Declares a [`BindingSet`]: `binding_set! { /// doc\n pub struct X { /// doc\n a: Read, b: ReadWrite } }`
/// makes a struct of `&wgpu::Buffer` fields. Written `pub struct X { adjacency; /// doc\n a: Read }`,
/// the set opens with the eight read-only buffers of a [`adjacency::DeviceAdjacency`] (indices,
/// vertex -> triangle rows, dual graph, as `idx_a`, `idx_b`, `vt_off`, `vt_a`, `vt_b`, `dual_off`,
/// `dual_a`, `dual_b`) from its `adj` field.
macro_rules! binding_set {
    ($(#[$m:meta])* pub struct $name:ident { adjacency; $($(#[$fm:meta])* $field:ident: $access:ident),* $(,)? }) => {
        $(#[$m])*
        pub struct $name<'a> {
            /// The mesh's adjacency on the device: bindings 1-8.
            pub adj: &'a $crate::gpu::adjacency::DeviceAdjacency,
            $($(#[$fm])* pub $field: &'a wgpu::Buffer,)*
        }
        impl<'a> $crate::gpu::BindingSet<'a> for $name<'a> {
            const LAYOUT: &'static [(&'static str, $crate::gpu::Access)] = &[
                ("idx_a", $crate::gpu::Access::Read),
                ("idx_b", $crate::gpu::Access::Read),
                ("vt_off", $crate::gpu::Access::Read),
                ("vt_a", $crate::gpu::Access::Read),
                ("vt_b", $crate::gpu::Access::Read),
                ("dual_off", $crate::gpu::Access::Read),
                ("dual_a", $crate::gpu::Access::Read),
                ("dual_b", $crate::gpu::Access::Read),
                $((stringify!($field), $crate::gpu::Access::$access)),*
            ];
            fn buffers(&self) -> Vec<&'a wgpu::Buffer> {
                let a = self.adj;
                vec![
                    &a.indices.a,
                    &a.indices.b,
                    &a.vt_offsets,
                    &a.vt_items.a,
                    &a.vt_items.b,
                    &a.dual_offsets,
                    &a.dual_items.a,
                    &a.dual_items.b,
                    $(self.$field),*
                ]
            }
        }
    };
    ($(#[$m:meta])* pub struct $name:ident { $($(#[$fm:meta])* $field:ident: $access:ident),* $(,)? }) => {
        $(#[$m])*
        pub struct $name<'a> { $($(#[$fm])* pub $field: &'a wgpu::Buffer,)* }
        impl<'a> $crate::gpu::BindingSet<'a> for $name<'a> {
            const LAYOUT: &'static [(&'static str, $crate::gpu::Access)] =
                &[$((stringify!($field), $crate::gpu::Access::$access)),*];
            fn buffers(&self) -> Vec<&'a wgpu::Buffer> {
                vec![$(self.$field),*]
            }
        }
    };
}
pub(crate) use binding_set;

/// The WGSL source of `wgsl/<file>` behind the shared prelude (`wgsl/prelude.wgsl`: the split
/// part size, `NONE` and the flat-id helpers every module uses), followed by the shared parts it
/// names (each listed in [`WGSL_PARTS`]). With `generated "<name>";` first, the file `build.rs`
/// wrote under that name comes before it all (each listed in [`WGSL_GENERATED`]).
macro_rules! wgsl {
    (generated $gen:literal; $file:literal $(, $part:literal)*) => {
        concat!(
            include_str!(concat!(env!("OUT_DIR"), "/", $gen)),
            $crate::gpu::wgsl!($file $(, $part)*)
        )
    };
    ($file:literal $(, $part:literal)*) => {
        concat!(
            include_str!("../../wgsl/prelude.wgsl"),
            include_str!(concat!("../../wgsl/", $file))
            $(, include_str!(concat!("../../wgsl/", $part)))*
        )
    };
}
pub(crate) use wgsl;

/// Files `build.rs` writes from Rust definitions (in `OUT_DIR`), with the module each goes in
/// front of: the drivers name them in their `wgsl!` calls; `gpu::shaders_test` reads this list.
#[cfg(test)]
pub(crate) const WGSL_GENERATED: &[(&str, &str)] =
    &[("kmedoids_parallel_layout.wgsl", "kmedoids_parallel.wgsl")];

/// WGSL files that are not modules but parts of several (functions over bindings each includer
/// declares), with the modules that include them: one definition where two kernel families run
/// the same step. The drivers name the parts in their `wgsl!` calls; `gpu::shaders_test` reads
/// this list.
#[cfg(test)]
pub(crate) const WGSL_PARTS: &[(&str, &[&str])] = &[(
    "medoid.wgsl",
    &["kmedoids_parallel.wgsl", "kmedoids_parallel_moves.wgsl"],
)];

/// Bytes between the parameter blocks of consecutive dispatches in the uniform buffer (dynamic
/// offsets must be multiples of 256).
const PARAM_STRIDE: u64 = 256;

/// One WGSL module, its pipelines and its fixed bind-group layout: binding 0 is the `P` uniform
/// (dynamic offset), bindings 1..=n the storage buffers of one [`BindingSet`], read-only where it
/// says so. Every entry point sees the same layout, so one bind group serves the whole module.
/// A clone shares the pipelines.
#[derive(Clone)]
pub struct Kernels<P: ParamBlock> {
    layout: wgpu::BindGroupLayout,
    bindings: &'static [(&'static str, Access)],
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
    _params: std::marker::PhantomData<fn() -> P>,
}

impl<P: ParamBlock> Kernels<P> {
    /// Compiles `source` for the bindings of `B` and builds a pipeline per entry point.
    pub fn new<'b, B: BindingSet<'b>>(
        gpu: &Gpu,
        label: &str,
        source: &'static str,
        entries: &[&'static str],
    ) -> Self {
        Self::with_constants::<B>(gpu, label, source, entries, &[])
    }

    /// [`Kernels::new`] with values for the module's `override` constants.
    pub fn with_constants<'b, B: BindingSet<'b>>(
        gpu: &Gpu,
        label: &str,
        source: &'static str,
        entries: &[&'static str],
        constants: &[(&str, f64)],
    ) -> Self {
        // Built once per device: a driver runs the same families build after build, and
        // re-creating them (parsing, validation, the driver's translation) is setup, not run time.
        let key: KernelKey = (
            source.as_ptr() as usize,
            source.len(),
            TypeId::of::<P>(),
            std::any::type_name::<B>(),
            entries.to_vec(),
            constants
                .iter()
                .map(|&(n, v)| (n.to_string(), v.to_bits()))
                .collect(),
        );
        let found = gpu
            .kernel_cache
            .lock()
            .expect("kernel cache lock")
            .get(&key)
            .and_then(|k| k.downcast_ref::<Self>())
            .cloned();
        if let Some(k) = found {
            return k;
        }
        let built = Self::build::<B>(gpu, label, source, entries, constants);
        gpu.families_built
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        // Another thread may have built the same family meanwhile: the first one stored is kept.
        let mut cache = gpu.kernel_cache.lock().expect("kernel cache lock");
        match cache.entry(key) {
            std::collections::hash_map::Entry::Occupied(e) => e
                .get()
                .downcast_ref::<Self>()
                .cloned()
                .expect("same key, same type"),
            std::collections::hash_map::Entry::Vacant(e) => {
                e.insert(Box::new(built.clone()));
                built
            }
        }
    }

    fn build<'b, B: BindingSet<'b>>(
        gpu: &Gpu,
        label: &str,
        source: &str,
        entries: &[&'static str],
        constants: &[(&str, f64)],
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
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<P>() as u64),
            },
            count: None,
        }];
        layout_entries.extend(B::LAYOUT.iter().zip(1..).map(|(&(_, access), b)| {
            wgpu::BindGroupLayoutEntry {
                binding: b,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage {
                        read_only: access == Access::Read,
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }
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
                        constants,
                    },
                    cache: None,
                });
                (e, p)
            })
            .collect();
        Self {
            layout,
            bindings: B::LAYOUT,
            pipelines,
            _params: std::marker::PhantomData,
        }
    }

    /// The bind group for `set` (bindings 1..) with the params buffer at binding 0. `set` must be
    /// of the binding set the kernels were built for.
    pub fn bind<'b, B: BindingSet<'b>>(&self, gpu: &Gpu, set: &B) -> wgpu::BindGroup {
        assert_eq!(
            B::LAYOUT,
            self.bindings,
            "a bind group of another kernel family"
        );
        let params = &gpu.params;
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: params,
                offset: 0,
                size: wgpu::BufferSize::new(std::mem::size_of::<P>() as u64),
            }),
        }];
        entries.extend(set.buffers().into_iter().zip(1..).map(|(b, binding)| {
            wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }
        }));
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
    pipeline: &'a wgpu::ComputePipeline,
    entry: &'static str,
    bind: &'a wgpu::BindGroup,
    /// The dispatch's [`ParamBlock`] as bytes.
    params: Vec<u8>,
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
    pub fn threads<P: ParamBlock>(
        &mut self,
        k: &'a Kernels<P>,
        entry: &'static str,
        bind: &'a wgpu::BindGroup,
        params: P,
        threads: usize,
    ) {
        self.groups(k, entry, bind, params, (threads as u32).div_ceil(WG));
    }

    /// Adds a dispatch of `groups` workgroups, split over y above 65535 (kernels rebuild the flat
    /// workgroup id as `x + y * 65535`).
    pub fn groups<P: ParamBlock>(
        &mut self,
        k: &'a Kernels<P>,
        entry: &'static str,
        bind: &'a wgpu::BindGroup,
        params: P,
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
            pipeline: k.pipeline(entry),
            entry,
            bind,
            params: bytemuck::bytes_of(&params).to_vec(),
            dims,
        });
    }

    /// Records, submits and waits; returns the kernel time in seconds: GPU timestamps around the
    /// pass when available, else wall time from submit to idle.
    pub fn run(self) -> Result<f64, GpuError> {
        Ok(self.run_read(&[])?.0)
    }

    /// [`Batch::run`], then copies each `(buffer, offset, len)` range (in u32) back to the host
    /// in the same submission: one host round trip for the dispatches, the timestamps and the
    /// reads together.
    pub fn run_read(
        self,
        reads: &[(&wgpu::Buffer, usize, usize)],
    ) -> Result<(f64, Vec<Vec<u32>>), GpuError> {
        let per_kernel = self.gpu.timing_each_kernel();
        // Two timestamps per step when timing each kernel; a query set holds at most 4096.
        let chunk = if per_kernel {
            2048
        } else {
            PARAM_SLOTS as usize
        };
        let mut total = 0.0;
        let mut out = Vec::new();
        let n = self.steps.len().div_ceil(chunk).max(1);
        for i in 0..n {
            let steps = &self.steps
                [(i * chunk).min(self.steps.len())..((i + 1) * chunk).min(self.steps.len())];
            let last = i + 1 == n;
            let (t, r) = self.run_chunk(steps, if last { reads } else { &[] }, per_kernel)?;
            total += t;
            out = r;
        }
        Ok((total, out))
    }

    fn run_chunk(
        &self,
        steps: &[Step<'a>],
        reads: &[(&wgpu::Buffer, usize, usize)],
        per_kernel: bool,
    ) -> Result<(f64, Vec<Vec<u32>>), GpuError> {
        let gpu = self.gpu;
        let mut bytes = vec![0u8; PARAM_STRIDE as usize * steps.len()];
        for (i, s) in steps.iter().enumerate() {
            let o = i * PARAM_STRIDE as usize;
            bytes[o..o + s.params.len()].copy_from_slice(&s.params);
        }
        if !bytes.is_empty() {
            gpu.queue.write_buffer(&gpu.params, 0, &bytes);
        }
        // Timestamps: around the one pass, or around each dispatch's own pass.
        let stamps = if per_kernel { 2 * steps.len() } else { 2 };
        let queries = (gpu.timestamps && !steps.is_empty()).then(|| {
            gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel time"),
                ty: wgpu::QueryType::Timestamp,
                count: stamps as u32,
            })
        });
        let stamp_words = if queries.is_some() { 2 * stamps } else { 0 };
        let read_words: usize = reads.iter().map(|r| r.2).sum();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        // Pass i writes timestamps 2i and 2i + 1 (the one pass of a batch is pass 0).
        let writes = |i: usize| {
            queries
                .as_ref()
                .map(|set| wgpu::ComputePassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(2 * i as u32),
                    end_of_pass_write_index: Some(2 * i as u32 + 1),
                })
        };
        let dispatch = |pass: &mut wgpu::ComputePass, i: usize, s: &Step| {
            pass.set_pipeline(s.pipeline);
            pass.set_bind_group(0, s.bind, &[(i as u64 * PARAM_STRIDE) as u32]);
            pass.dispatch_workgroups(s.dims[0], s.dims[1], s.dims[2]);
        };
        if per_kernel {
            for (i, s) in steps.iter().enumerate() {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(s.entry),
                    timestamp_writes: writes(i),
                });
                dispatch(&mut pass, i, s);
            }
        } else if !steps.is_empty() {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: writes(0),
            });
            for (i, s) in steps.iter().enumerate() {
                dispatch(&mut pass, i, s);
            }
        }
        // One staging buffer: the requested ranges, then the timestamps.
        let staging_words = read_words + stamp_words;
        let staging = (staging_words > 0).then(|| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: 4 * staging_words as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        if let Some(staging) = &staging {
            let mut at = 0u64;
            for &(buf, offset, len) in reads {
                if len > 0 {
                    enc.copy_buffer_to_buffer(buf, 4 * offset as u64, staging, at, 4 * len as u64);
                }
                at += 4 * len as u64;
            }
            if let Some(set) = &queries {
                let resolve = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: 8 * stamps as u64,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                enc.resolve_query_set(set, 0..stamps as u32, &resolve, 0);
                enc.copy_buffer_to_buffer(&resolve, 0, staging, at, 8 * stamps as u64);
            }
        }
        gpu.count(|p| p.dispatches += steps.len() as u64);
        let t = Instant::now();
        gpu.submit(enc);
        let words = match &staging {
            Some(staging) => gpu.map_read(staging)?,
            None => {
                gpu.wait()?;
                Vec::new()
            }
        };
        let wall = t.elapsed().as_secs_f64();
        let mut out = Vec::with_capacity(reads.len());
        let mut at = 0;
        for r in reads {
            out.push(words[at..at + r.2].to_vec());
            at += r.2;
        }
        let stamp = |q: usize| words[at + 2 * q] as u64 | (words[at + 2 * q + 1] as u64) << 32;
        let ns = gpu.period_ns as f64 * 1e-9;
        let time = if steps.is_empty() {
            0.0
        } else if queries.is_none() {
            wall
        } else if per_kernel {
            let mut total = 0.0;
            let mut times = Vec::with_capacity(steps.len());
            for (i, s) in steps.iter().enumerate() {
                let dt = stamp(2 * i + 1).saturating_sub(stamp(2 * i)) as f64 * ns;
                total += dt;
                times.push((s.entry, dt));
            }
            gpu.count(|p| {
                for (e, dt) in times {
                    let k = p.per_kernel.entry(e).or_insert((0, 0.0));
                    k.0 += 1;
                    k.1 += dt;
                }
            });
            total
        } else {
            stamp(1).saturating_sub(stamp(0)) as f64 * ns
        };
        gpu.count(|p| p.kernel_seconds += time);
        Ok((time, out))
    }
}

/// Parameter slots per submission.
const PARAM_SLOTS: u64 = 4096;
const MAX_X: u32 = 65535;

/// Runs `f` (a readback), adding its wall time to `timing`'s readback.
pub(crate) fn timed_read<T>(
    timing: &mut adjacency::Timing,
    f: impl FnOnce() -> Result<T, GpuError>,
) -> Result<T, GpuError> {
    let (r, s) = timed(f);
    timing.readback += s;
    r
}

/// Wall time of `f` in seconds.
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let r = f();
    (r, t.elapsed().as_secs_f64())
}

#[cfg(test)]
mod shaders_test;
