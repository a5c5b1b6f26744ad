//! Meshlets built on the GPU, for `--device gpu` and the library: one entry point over the
//! strategies whose every step is a kernel, with the same meshlets (and so the same files) as their
//! CPU runs.
//!
//! A strategy qualifies when the GPU runs all of it and the host only orders the work between
//! kernels: `bsphere-parallel` ([`super::grow`]) and `kmedoids-flat` ([`super::kmedoids`]'s flat
//! driver). The default `kmedoids` does not: its seeding growth, merges and packing are sequential
//! host code, so a GPU run of it would mostly measure the host. The ordering post-passes
//! (`--local-order`, `--meshlet-order`) run on the host after the build, exactly as after a CPU
//! build.

use super::adjacency::Timing;
use super::{Gpu, GpuError};
use crate::mesh::Mesh;
use crate::meshlet::order::{optimize_triangle_order, order_meshlets};
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::{grow, Kind, Options};
use std::time::Instant;

/// The strategies with a whole GPU path, in table order.
pub const GPU_STRATEGIES: [Kind; 2] = [Kind::BsphereParallel, Kind::KmedoidsFlat];

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
    let (mut meshlets, timing) = match kind {
        Kind::KmedoidsFlat => {
            let r = super::kmedoids::cluster_flat(gpu, mesh, limits, &opts.kmedoids)?;
            (r.clustering.meshlets, r.timing)
        }
        Kind::BsphereParallel => {
            let r = super::grow::grow(gpu, mesh, limits, grow::DEFAULT_SPACING)?;
            (r.meshlets, r.timing)
        }
        _ => unreachable!("gpu_kind admits only GPU_STRATEGIES"),
    };
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

/// Compiles `name`'s pipelines by a build of a small generated mesh, so that a timed build after
/// it measures the run and not the shader compiler (drivers cache compiled pipelines: lavapipe
/// compiles each with LLVM on first use, seconds per kernel family). Returns its wall time.
pub fn warm_up(gpu: &Gpu, name: &str, limits: Limits, opts: &Options) -> Result<f64, GpuError> {
    let t0 = Instant::now();
    build(
        gpu,
        name,
        &crate::mesh::generate::terrain(24, 1),
        limits,
        opts,
    )?;
    Ok(t0.elapsed().as_secs_f64())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_whole_gpu_strategies_are_accepted_and_the_error_names_the_strategy() {
        assert_eq!(gpu_kind("kmedoids-flat").unwrap(), Kind::KmedoidsFlat);
        assert_eq!(gpu_kind("bsphere-parallel").unwrap(), Kind::BsphereParallel);
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
