//! `meshletlab export`: meshlets as a glTF binary with one flat colour per meshlet.

use super::{build_validated, build_validated_on_gpu, gpu_for, load_scene};
use super::{Device, DeviceArgs, StrategyArgs};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `export`.
#[derive(Args, Debug)]
pub struct ExportArgs {
    /// Mesh file (an instanced glTF scene or `gen:` scene is written with one mesh per scene
    /// mesh and one node per instance).
    mesh: PathBuf,
    /// Strategy name (`meshletlab --help` lists them, e.g. meshopt, kmedoids, partition).
    #[arg(short, long, default_value = "meshopt")]
    strategy: String,
    /// Output .glb file.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    args: StrategyArgs,
    #[command(flatten)]
    device: DeviceArgs,
}

pub(super) fn run(a: ExportArgs, quiet: bool) -> Result<()> {
    crate::strategy::by_name(&a.strategy, &a.args.options())?;
    // Binary glTF only: a `.gltf` would need its buffer as a second file beside it.
    super::output::check_file(&a.output, "binary glTF (one .glb file)", &["glb"])?;
    let gpu = match a.device.device {
        Device::Cpu => None,
        Device::Gpu => Some(gpu_for(&[&a.strategy])?),
    };
    let scene = load_scene(&a.mesh, quiet)?;
    let build = |m: &crate::mesh::Mesh| match &gpu {
        None => build_validated(m, &a.mesh, &a.strategy, &a.args),
        Some((gpu, ms)) => {
            build_validated_on_gpu(gpu, *ms, m, &a.mesh, &a.strategy, &a.args).map(|b| b.0)
        }
    };
    if scene.is_instanced() {
        // Each mesh's meshlets once, placed by one node per instance.
        let meshlets = scene.meshes.iter().map(build).collect::<Result<Vec<_>>>()?;
        let glb = crate::meshlet::export::glb_scene(&scene, &meshlets);
        crate::atomic::write(&a.output, &glb)
            .with_context(|| format!("{}: cannot write", a.output.display()))?;
        say!(
            "{}: {} meshes, {} instances: {} meshlets built ({}, {}) -> {} ({:.1} KiB)",
            a.mesh.display(),
            scene.meshes.len(),
            scene.instances.len(),
            meshlets.iter().map(|m| m.len()).sum::<usize>(),
            a.strategy,
            a.args.limits,
            a.output.display(),
            glb.len() as f64 / 1024.0
        );
        return Ok(());
    }
    let m = scene.meshes.into_iter().next().expect("one mesh");
    let ml = build(&m)?;
    let glb = crate::meshlet::export::glb(&m, &ml);
    crate::atomic::write(&a.output, &glb)
        .with_context(|| format!("{}: cannot write", a.output.display()))?;
    say!(
        "{}: {} meshlets ({}, {}) -> {} ({} triangles, {} vertices after splitting at meshlet borders, {:.1} KiB)",
        a.mesh.display(),
        ml.len(),
        a.strategy,
        a.args.limits,
        a.output.display(),
        m.triangle_count(),
        ml.vertices.len(),
        glb.len() as f64 / 1024.0
    );
    Ok(())
}
