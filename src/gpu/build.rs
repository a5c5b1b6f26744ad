//! Meshlets built on the GPU, for `--device gpu` and the library: one entry point over the
//! strategies whose every step is a kernel, with the same meshlets (and so the same files) as their
//! CPU runs.
//!
//! A strategy qualifies when the GPU runs all of it and the host only orders the work between
//! kernels: `bsphere-parallel` ([`super::grow`]), `kmedoids-flat` ([`super::kmedoids_flat`])
//! and `kmedoids-parallel` ([`super::kmedoids_parallel`]). The default `kmedoids` does not: its
//! seeding growth, merges and packing are sequential host code, so a GPU run of it would mostly
//! measure the host. The ordering post-passes
//! (`--local-order`, `--meshlet-order`) run on the host after the build, exactly as after a CPU
//! build.

use super::adjacency::Timing;
use super::assemble::DeviceMeshlets;
use super::bounds::task_on_device;
use super::source::MeshSource;
use super::{timed_read, DeviceMesh, Gpu, GpuError};
use crate::mesh::Mesh;
use crate::meshlet::order::{optimize_triangle_order, order_meshlets};
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::{grow, Kind, Options};
use std::time::Instant;

/// The strategies with a whole GPU path, in table order.
pub const GPU_STRATEGIES: [Kind; 3] = [
    Kind::BsphereParallel,
    Kind::KmedoidsFlat,
    Kind::KmedoidsParallel,
];

/// One GPU build.
#[derive(Clone, Debug)]
pub struct DeviceBuild {
    /// The meshlets, equal to the CPU run's.
    pub meshlets: Meshlets,
    /// Upload, kernel and readback time (kernel time from GPU timestamps where the adapter has
    /// them), in seconds.
    pub timing: Timing,
    /// Wall time of the whole build (uploads, kernels, readbacks, the host steps between them and
    /// the ordering post-passes), in seconds.
    pub seconds: f64,
}

/// The strategy `name` as one with a whole GPU path, or why not.
pub fn gpu_kind(name: &str) -> Result<Kind, GpuError> {
    Kind::from_name(name)
        .filter(|k| GPU_STRATEGIES.contains(k))
        .ok_or_else(|| GpuError::NoGpuPath(name.to_string()))
}

/// Builds `mesh`'s meshlets with strategy `name` on `gpu`, reading the same tunables in `opts`
/// as the CPU strategy does; the result equals `strategy::by_name(name, opts)`'s.
pub fn build(
    gpu: &Gpu,
    name: &str,
    mesh: &Mesh,
    limits: Limits,
    opts: &Options,
) -> Result<DeviceBuild, GpuError> {
    let kind = gpu_kind(name)?;
    let t0 = Instant::now();
    // Assembled on the device; only the meshlets come back.
    let (device, mut timing) = run_strategy(gpu, kind, mesh, limits, opts)?;
    let mut meshlets = timed_read(&mut timing, || device.read(gpu))?;
    if opts.local_order {
        optimize_triangle_order(&mut meshlets);
    }
    order_meshlets(&mut meshlets, opts.meshlet_order);
    Ok(DeviceBuild {
        meshlets,
        timing,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Meshlets built on the GPU and left there ([`build_resident`]).
pub struct ResidentBuild {
    /// The meshlets, in [`Meshlets`]' layout, in build order (no ordering post-pass).
    pub meshlets: DeviceMeshlets,
    /// Culling bounds in the mesh-shader pass's split task layout: per meshlet three vec4 of f32,
    /// (sphere centre, radius), (cone apex, cutoff), (cone axis, triangle count as bits)
    /// ([`super::bounds::task_on_device`]; conservative: see [`super::bounds`]).
    pub task: wgpu::Buffer,
    /// Upload, kernel and readback time (the readbacks are the control words the kernels' loops
    /// need), in seconds.
    pub timing: Timing,
    /// Wall time of the whole build, in seconds.
    pub seconds: f64,
}

/// Builds `mesh`'s meshlets with strategy `name` on `gpu` and leaves them, with their culling
/// bounds (sphere and normal cone) over `positions` (the mesh's positions on the device, three
/// f32 per vertex), in device buffers for a renderer: nothing of the result comes back to the
/// host unless the caller reads it ([`DeviceMeshlets::read`]). The meshlets equal [`build`]'s where `opts` asks for no ordering
/// post-pass (those run on the host, so they are not applied here). The strategy's own inputs
/// (the index buffer, the quantised positions) are still uploaded from `mesh`.
pub fn build_resident(
    gpu: &Gpu,
    name: &str,
    mesh: &Mesh,
    positions: &wgpu::Buffer,
    limits: Limits,
    opts: &Options,
) -> Result<ResidentBuild, GpuError> {
    let kind = gpu_kind(name)?;
    let t0 = Instant::now();
    let (meshlets, timing) = run_strategy(gpu, kind, mesh, limits, opts)?;
    with_bounds(gpu, positions, meshlets, timing, t0)
}

/// The culling bounds of `meshlets` added on the device: the end of both resident builds.
fn with_bounds(
    gpu: &Gpu,
    positions: &wgpu::Buffer,
    meshlets: DeviceMeshlets,
    mut timing: Timing,
    t0: Instant,
) -> Result<ResidentBuild, GpuError> {
    let (task, kernel) = task_on_device(gpu, positions, &meshlets)?;
    timing.kernel += kernel;
    Ok(ResidentBuild {
        meshlets,
        task,
        timing,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// The strategies [`build_on_device`] runs: those whose setup reads no mesh data on the host.
/// `bsphere-parallel` is not one: its quantised positions and grid are computed on the host.
pub const DEVICE_INPUT_STRATEGIES: [Kind; 2] = [Kind::KmedoidsFlat, Kind::KmedoidsParallel];

/// [`build_resident`] from a mesh already on the device (an engine's vertex and index buffers):
/// nothing of the mesh is read on the host, and nothing of the result comes back unless the
/// caller reads it. The host reads only the control words the kernels' loops need (the box of
/// the positions, the seeds, counts per round and per region) and, for `kmedoids-flat` where a
/// piece of the mesh has no seed, the dual graph and labels to seed it, as [`build`] does. Strategies: [`DEVICE_INPUT_STRATEGIES`];
/// the meshlets equal [`build_resident`]'s on the same mesh.
pub fn build_on_device(
    gpu: &Gpu,
    name: &str,
    mesh: DeviceMesh<'_>,
    limits: Limits,
    opts: &Options,
) -> Result<ResidentBuild, GpuError> {
    let kind = gpu_kind(name)?;
    if !DEVICE_INPUT_STRATEGIES.contains(&kind) {
        return Err(GpuError::Unsupported(
            "only kmedoids-flat and kmedoids-parallel build from a mesh on the device: bsphere-parallel's setup runs on the host (use build_resident)",
        ));
    }
    let t0 = Instant::now();
    let (meshlets, timing) = run_kmedoids(gpu, kind, MeshSource::Device(mesh), limits, opts)?;
    with_bounds(gpu, mesh.positions, meshlets, timing, t0)
}

/// Runs `kmedoids-parallel` or `kmedoids-flat` (`kind`) from `source`, its meshlets left on the
/// device.
fn run_kmedoids(
    gpu: &Gpu,
    kind: Kind,
    source: MeshSource<'_>,
    limits: Limits,
    opts: &Options,
) -> Result<(DeviceMeshlets, Timing), GpuError> {
    let cfg = &opts.kmedoids;
    Ok(if kind == Kind::KmedoidsParallel {
        let (r, d) = super::kmedoids_parallel::cluster(gpu, source, limits, &cfg.parallel, false)?;
        (d, r.timing)
    } else {
        let (r, d) = super::kmedoids_flat::cluster_with(gpu, source, limits, &cfg.flat, false)?;
        (d, r.timing)
    })
}

/// Runs strategy `kind` (one of [`GPU_STRATEGIES`]) with its meshlets assembled on the device and
/// nothing read back but the control words its loops need.
fn run_strategy(
    gpu: &Gpu,
    kind: Kind,
    mesh: &Mesh,
    limits: Limits,
    opts: &Options,
) -> Result<(DeviceMeshlets, Timing), GpuError> {
    Ok(match kind {
        Kind::KmedoidsFlat | Kind::KmedoidsParallel => {
            run_kmedoids(gpu, kind, MeshSource::Host(mesh), limits, opts)?
        }
        Kind::BsphereParallel => {
            let (r, d) = super::grow::grow_with(gpu, mesh, limits, grow::DEFAULT_SPACING, false)?;
            (d, r.timing)
        }
        _ => unreachable!("gpu_kind admits only GPU_STRATEGIES"),
    })
}

/// Compiles `name`'s pipelines by a build of a small generated mesh, so that a timed build after
/// it measures the run and not the shader compiler (drivers cache compiled pipelines: lavapipe
/// compiles each with LLVM on first use, seconds per kernel family). Returns its wall time.
pub fn warm_up(gpu: &Gpu, name: &str, limits: Limits, opts: &Options) -> Result<f64, GpuError> {
    let t0 = Instant::now();
    let mesh = crate::mesh::generate::terrain(24, 1);
    build(gpu, name, &mesh, limits, opts)?;
    if gpu_kind(name)? == Kind::KmedoidsParallel {
        // One region takes `grow`, several take `grow_rows` on a CPU adapter; lavapipe compiles a
        // pipeline on its first dispatch, so both run here (the mesh is 1152 triangles).
        let mut regions = *opts;
        regions.kmedoids.parallel.region_triangles = 256;
        build(gpu, name, &mesh, limits, &regions)?;
    }
    Ok(t0.elapsed().as_secs_f64())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_whole_gpu_strategies_are_accepted_and_the_error_names_the_strategy() {
        assert_eq!(gpu_kind("kmedoids-flat").unwrap(), Kind::KmedoidsFlat);
        assert_eq!(gpu_kind("bsphere-parallel").unwrap(), Kind::BsphereParallel);
        assert_eq!(
            gpu_kind("kmedoids-parallel").unwrap(),
            Kind::KmedoidsParallel
        );
        for name in ["kmedoids", "meshopt", "kmedoids-flat+refine", "nope"] {
            let e = gpu_kind(name).unwrap_err().to_string();
            assert!(e.contains(&format!("'{name}'")), "{e}");
            assert!(
                e.contains("kmedoids-flat") && e.contains("bsphere-parallel"),
                "{e}"
            );
        }
    }
}
