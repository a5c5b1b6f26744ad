//! `meshletlab build`: build meshlets, validate them, write the meshlet file.

use super::{build_validated, build_validated_on_gpu, gpu_for, load, spinner};
use super::{Device, DeviceArgs, StrategyArgs};
use crate::meshlet::io::MeshletFile;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `build`.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Strategy name (`meshletlab --help` lists them, e.g. meshopt, kmedoids, partition).
    #[arg(short, long)]
    strategy: String,
    /// Output file.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    args: StrategyArgs,
    #[command(flatten)]
    device: DeviceArgs,
}

pub(super) fn run(a: BuildArgs, quiet: bool) -> Result<()> {
    let name = &a.strategy;
    crate::strategy::by_name(name, &a.args.options())?;
    super::output::check_file(&a.output, "a meshlet file", &[])?;
    let gpu = match a.device.device {
        Device::Cpu => None,
        Device::Gpu => Some(gpu_for(&[name])?),
    };
    let m = load(&a.mesh, quiet)?;
    let pb = spinner(quiet, format!("building with {name}"));
    let (ml, ms, on) = match &gpu {
        None => {
            let t0 = std::time::Instant::now();
            let ml = build_validated(&m, &a.mesh, name, &a.args)?;
            (ml, t0.elapsed().as_secs_f64() * 1e3, String::new())
        }
        Some((gpu, device_ms)) => {
            let (ml, ms, setup_ms) =
                build_validated_on_gpu(gpu, *device_ms, &m, &a.mesh, name, &a.args)?;
            (
                ml,
                ms,
                format!(" on the GPU ({setup_ms:.0} ms setup before it)"),
            )
        }
    };
    pb.finish_and_clear();
    let file = MeshletFile {
        limits: a.args.limits,
        source_vertices: m.vertex_count() as u32,
        source_triangles: m.triangle_count() as u32,
        fingerprint: m.fingerprint(),
        strategy: name.to_string(),
        meshlets: ml,
    };
    file.save(&a.output)?;
    say!(
        "{}: {} meshlets from {} triangles with {name} at {} in {ms:.1} ms{on} -> {}",
        a.mesh.display(),
        file.meshlets.len(),
        m.triangle_count(),
        a.args.limits,
        a.output.display()
    );
    Ok(())
}
