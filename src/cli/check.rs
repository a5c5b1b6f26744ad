//! `meshletlab check`: validate a meshlet file or a compressed-meshlet file against its mesh.

use super::load;
use crate::compress::file::CompressedFile;
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
    let data = crate::meshlet::io::read_file(&a.file)?;
    if CompressedFile::sniff(&data) {
        let f = CompressedFile::from_bytes(&data, &a.file)?;
        let m = load(&a.mesh, quiet)?;
        let worst = f.check(&m, &a.file)?;
        say!(
            "{}: valid — {} compressed meshlets ({}), every one of {} triangles exactly once, every position within {:.3e} (largest error {worst:.3e})",
            a.file.display(),
            f.encoded.offsets.len(),
            f.format.name(),
            m.triangle_count(),
            f.tolerance
        );
        return Ok(());
    }
    let f = MeshletFile::from_bytes(&data, &a.file)?;
    let m = load(&a.mesh, quiet)?;
    f.check(&m, &a.file)?;
    say!(
        "{}: valid — {} meshlets ({}), limits {}, every one of {} triangles exactly once",
        a.file.display(),
        f.meshlets.len(),
        f.strategy,
        f.limits,
        m.triangle_count()
    );
    Ok(())
}
