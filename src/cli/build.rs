//! `meshletlab build`: build meshlets, validate them, write the meshlet file.

use super::clusters::ClusterArgs;
use super::{build_validated, build_validated_on_gpu, gpu_for, load, spinner};
use super::{Device, DeviceArgs, StrategyArgs};
use crate::meshlet::io::MeshletFile;
use crate::meshlet::Meshlets;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `build`.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Strategy name (`meshletlab --help` lists them, e.g. meshopt, kmedoids, partition);
    /// needed unless --labels or --meshlets brings the clusters.
    #[arg(short, long, required_unless_present_any = ["labels", "meshlets"])]
    strategy: Option<String>,
    /// Output file.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the meshlets as one cluster id per triangle (each triangle's meshlet, in the
    /// mesh's triangle order), for another tool or `--labels`: a numpy .npy (u32) when FILE ends
    /// in .npy, else text, one id a line.
    #[arg(long, value_name = "FILE")]
    labels_out: Option<PathBuf>,
    #[command(flatten)]
    args: StrategyArgs,
    #[command(flatten)]
    device: DeviceArgs,
    #[command(flatten)]
    clusters: ClusterArgs,
}

pub(super) fn run(a: BuildArgs, quiet: bool) -> Result<()> {
    a.clusters
        .check(a.strategy.is_some(), a.device.device == Device::Gpu)?;
    super::output::check_file(&a.output, "a meshlet file", &[])?;
    if let Some(p) = &a.labels_out {
        super::output::check_file(p, "a label file", &[])?;
    }
    let Some(name) = a.strategy.as_deref() else {
        return from_file(&a, quiet);
    };
    crate::strategy::by_name(name, &a.args.options())?;
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
    save(
        &a,
        &m,
        name,
        ml,
        &format!("with {name}"),
        &format!("in {ms:.1} ms{on}"),
    )
}

/// `build --labels`/`--meshlets`: the file's clusters, held to the limits, as a meshlet file.
fn from_file(a: &BuildArgs, quiet: bool) -> Result<()> {
    let m = load(&a.mesh, quiet)?;
    let i = a
        .clusters
        .import(&m, a.args.limits)?
        .expect("a file is given");
    let how = format!("from {}{}", i.name, i.split_note());
    let name = i.name.clone();
    save(
        a,
        &m,
        &name,
        i.meshlets,
        &how,
        &format!("in {:.1} ms", i.ms),
    )
}

/// Writes the meshlet file (strategy `name`) and, with `--labels-out`, the per-triangle ids, then
/// the summary line: how the meshlets were made and what it took.
fn save(
    a: &BuildArgs,
    m: &crate::mesh::Mesh,
    name: &str,
    ml: Meshlets,
    how: &str,
    took: &str,
) -> Result<()> {
    if let Some(p) = &a.labels_out {
        let labels = crate::strategy::labels::triangle_labels(m, &ml)?;
        crate::strategy::labels::file::write_labels(p, &labels)?;
    }
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
        "{}: {} meshlets from {} triangles {how} at {} {took} -> {}",
        a.mesh.display(),
        file.meshlets.len(),
        m.triangle_count(),
        a.args.limits,
        a.output.display()
    );
    Ok(())
}
