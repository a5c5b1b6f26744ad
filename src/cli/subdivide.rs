//! `meshletlab subdivide`: 1->4 midpoint subdivision, for multi-million-triangle inputs.

use super::{load, spinner};
use crate::mesh::{self, subdivide::MAX_TRIANGLES};
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `subdivide`.
#[derive(Args, Debug)]
pub struct SubdivideArgs {
    /// Input mesh file.
    mesh: PathBuf,
    /// Output PLY (binary; zstd-compressed if it ends in .zst): named .ply or .ply.zst.
    #[arg(short, long)]
    output: PathBuf,
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=8),
          help = levels_help())]
    levels: u32,
}

/// The `--levels` help, with the triangle budget the library enforces.
fn levels_help() -> String {
    format!(
        "Subdivision levels (each multiplies the triangle count by 4); the result may have at \
         most {MAX_TRIANGLES} triangles"
    )
}

pub(super) fn run(a: SubdivideArgs, quiet: bool) -> Result<()> {
    // Before the work: a name that would hold PLY under another extension is refused.
    super::output::check_file(&a.output, "binary PLY", &["ply", "ply.zst"])?;
    let m = load(&a.mesh, quiet)?;
    let pb = spinner(quiet, format!("subdividing {} level(s)", a.levels));
    let s = mesh::subdivide::subdivide(&m, a.levels)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.mesh.display()))?;
    pb.set_message(format!("writing {}", a.output.display()));
    mesh::save_ply(&s, &a.output)?;
    pb.finish_and_clear();
    say!(
        "{} -> {}: {} -> {} triangles, {} -> {} vertices",
        a.mesh.display(),
        a.output.display(),
        m.triangle_count(),
        s.triangle_count(),
        m.vertex_count(),
        s.vertex_count()
    );
    Ok(())
}
