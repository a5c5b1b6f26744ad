//! `meshletlab build`: build meshlets, validate them, write the meshlet file.

use super::{build_validated, load, spinner, StrategyArgs};
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
}

pub(super) fn run(a: BuildArgs, quiet: bool) -> Result<()> {
    let name = &a.strategy;
    crate::strategy::by_name(name, &a.args.options())?;
    let m = load(&a.mesh, quiet)?;
    let pb = spinner(quiet, format!("building with {name}"));
    let t0 = std::time::Instant::now();
    let ml = build_validated(&m, &a.mesh, name, &a.args)?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
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
    println!(
        "{}: {} meshlets from {} triangles with {name} at {} in {ms:.1} ms -> {}",
        a.mesh.display(),
        file.meshlets.len(),
        m.triangle_count(),
        a.args.limits,
        a.output.display()
    );
    Ok(())
}
