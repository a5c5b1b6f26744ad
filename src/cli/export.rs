//! `meshletlab export`: meshlets as a glTF binary with one flat colour per meshlet.

use super::clusters::{meshlets_or_build, refuse_instanced, ClusterArgs};
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
    /// Strategy name (`meshletlab --help` lists them, e.g. meshopt, kmedoids, partition)
    /// [default: meshopt].
    #[arg(short, long)]
    strategy: Option<String>,
    /// Output .glb file.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    args: StrategyArgs,
    #[command(flatten)]
    clusters: ClusterArgs,
    #[command(flatten)]
    device: DeviceArgs,
}

pub(super) fn run(a: ExportArgs, quiet: bool) -> Result<()> {
    a.clusters
        .check(a.strategy.is_some(), a.device.device == Device::Gpu)?;
    let strategy = a.strategy.as_deref().unwrap_or("meshopt");
    crate::strategy::by_name(strategy, &a.args.options())?;
    // Binary glTF only: a `.gltf` would need its buffer as a second file beside it.
    super::output::check_file(&a.output, "binary glTF (one .glb file)", &["glb"])?;
    let gpu = match a.device.device {
        Device::Cpu => None,
        Device::Gpu => Some(gpu_for(&[strategy])?),
    };
    let scene = load_scene(&a.mesh, quiet)?;
    let build = |m: &crate::mesh::Mesh| match &gpu {
        None => build_validated(m, &a.mesh, strategy, &a.args),
        Some((gpu, ms)) => {
            build_validated_on_gpu(gpu, *ms, m, &a.mesh, strategy, &a.args).map(|b| b.0)
        }
    };
    if scene.is_instanced() && a.clusters.file().is_some() {
        return Err(refuse_instanced(&a.mesh, "--labels and --meshlets"));
    }
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
            strategy,
            a.args.limits,
            a.output.display(),
            glb.len() as f64 / 1024.0
        );
        return Ok(());
    }
    let m = scene.meshes.into_iter().next().expect("one mesh");
    let (ml, name, note) = match a.clusters.file() {
        Some(_) => {
            let i = meshlets_or_build(&m, &a.mesh, strategy, &a.args, &a.clusters)?;
            let note = i.split_note();
            (i.meshlets, i.name, note)
        }
        None => (build(&m)?, strategy.to_string(), String::new()),
    };
    let glb = crate::meshlet::export::glb(&m, &ml);
    crate::atomic::write(&a.output, &glb)
        .with_context(|| format!("{}: cannot write", a.output.display()))?;
    say!(
        "{}: {} meshlets ({name}, {}){note} -> {} ({} triangles, {} vertices after splitting at meshlet borders, {:.1} KiB)",
        a.mesh.display(),
        ml.len(),
        a.args.limits,
        a.output.display(),
        m.triangle_count(),
        ml.vertices.len(),
        glb.len() as f64 / 1024.0
    );
    Ok(())
}
