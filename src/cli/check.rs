//! `meshletlab check`: validate a meshlet file against its mesh.

use super::load;
use crate::meshlet::io::MeshletFile;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `check`.
#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Mesh file the meshlets were built from.
    mesh: PathBuf,
    /// Meshlet file.
    file: PathBuf,
}

pub(super) fn run(a: CheckArgs, quiet: bool) -> Result<()> {
    let f = MeshletFile::load(&a.file)?;
    let m = load(&a.mesh, quiet)?;
    f.check(&m, &a.file)?;
    println!(
        "{}: valid — {} meshlets ({}), limits {}, every one of {} triangles exactly once",
        a.file.display(),
        f.meshlets.len(),
        f.strategy,
        f.limits,
        m.triangle_count()
    );
    Ok(())
}
