//! `meshletlab compress`: encode a mesh's meshlets in a compressed format and write the file.

use super::clusters::{meshlets_or_build, ClusterArgs};
use super::{load, StrategyArgs};
use crate::compress::file::CompressedFile;
use crate::compress::paper_tolerance;
use crate::compress::Codec;
use anyhow::{bail, Result};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `compress`.
#[derive(Args, Debug)]
pub struct CompressArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Encoding: meshoptimizer's codec (the peer), laced wires (at most 64 vertices per meshlet,
    /// e.g. `--strategy qem --limits 64/84`, the paper's setting), or the paper's comparison
    /// formats: triangle soup (ts), indexed (ix), self-contained (sc) meshlets, global index
    /// buffer (gi).
    #[arg(short, long, value_enum, default_value = "meshopt")]
    format: Codec,
    /// The compact variant of ts, ix, sc or gi (quantised positions, packed indices).
    #[arg(long)]
    compact: bool,
    /// Strategy that builds the meshlets [default: meshopt].
    #[arg(short, long)]
    strategy: Option<String>,
    /// Largest allowed position error, in mesh units (default: the paper's, the error of 14-bit
    /// quantisation of the bounding box).
    #[arg(long, conflicts_with = "relative_tolerance", value_parser = crate::bench::positive::<f64>)]
    tolerance: Option<f64>,
    /// Largest allowed position error as a fraction of the bounding-box diagonal (1e-4 is the
    /// setting of the size comparison with meshoptimizer's codec).
    #[arg(long, value_parser = crate::bench::positive::<f64>)]
    relative_tolerance: Option<f64>,
    /// Output file (format: see `meshletlab::compress::file`).
    #[arg(short, long)]
    output: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    args: StrategyArgs,
    #[command(flatten)]
    clusters: ClusterArgs,
}

/// The position tolerance from `--tolerance` (mesh units) or `--relative-tolerance` (of the
/// bounding-box diagonal), else the paper's.
pub(super) fn tolerance(
    m: &crate::mesh::Mesh,
    absolute: Option<f64>,
    relative: Option<f64>,
) -> Result<f64> {
    Ok(match (absolute, relative) {
        (Some(t), _) if t > 0.0 && t.is_finite() => t,
        (Some(t), _) => bail!("--tolerance must be a positive number, not {t}"),
        (_, Some(r)) if r > 0.0 && r.is_finite() => r * m.bounding_box_diagonal() as f64,
        (_, Some(r)) => bail!("--relative-tolerance must be a positive number, not {r}"),
        (None, None) => paper_tolerance(m),
    })
}

pub(super) fn run(a: CompressArgs, quiet: bool) -> Result<()> {
    let format = match (a.compact, a.format.compact()) {
        (false, _) => a.format,
        (true, Some(f)) => f,
        (true, None) => {
            return Err(super::usage(format!(
                "--compact applies to ts, ix, sc and gi, not {}",
                a.format.name()
            )))
        }
    };
    super::output::check_file(&a.output, "a compressed-meshlet file", &[])?;
    a.clusters.check(a.strategy.is_some(), false)?;
    let strategy = a.strategy.as_deref().unwrap_or("meshopt");
    crate::strategy::by_name(strategy, &a.args.options())?;
    let m = load(&a.mesh, quiet)?;
    let tolerance = tolerance(&m, a.tolerance, a.relative_tolerance)?;
    let imported = meshlets_or_build(&m, &a.mesh, strategy, &a.args, &a.clusters)?;
    let (note, split) = (imported.split_note(), imported.split);
    let (ml, name) = (imported.meshlets, imported.name);
    let t0 = std::time::Instant::now();
    let encoded = format
        .encode(&m, &ml, tolerance)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.mesh.display()))?;
    let seconds = t0.elapsed().as_secs_f64();
    let sizes = encoded.sizes;
    let file = CompressedFile::new(&m, format, tolerance, encoded);
    // Prove the file before writing it: every meshlet decoded at random access and compared.
    let max_error = file.check(&m, &a.output)?;
    file.save(&a.output)?;
    let tris = m.triangle_count().max(1) as f64;
    let verts = m.vertex_count().max(1) as f64;
    if a.json {
        let out = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "triangles": m.triangle_count(),
            "vertices": m.vertex_count(),
            "format": format.name(),
            "strategy": name,
            "split_clusters": split,
            "limits": a.args.limits.to_string(),
            "meshlets": ml.len(),
            "tolerance": tolerance,
            "max_error": max_error,
            "bytes": sizes,
            "total_bytes": sizes.total(),
            "bytes_per_triangle": sizes.total() as f64 / tris,
            "position_bytes_per_vertex": sizes.positions as f64 / verts,
            "encode_seconds": seconds,
            "file": a.output.display().to_string(),
        });
        say!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        say!(
            "{}: {} triangles in {} {} meshlets{note} -> {} bytes, {:.2} bytes/triangle (connectivity {:.2}, positions {:.2}, headers {:.2}, culling {:.2}, padding {:.2}); positions {:.2} bytes/vertex; max error {:.3e} (tolerance {:.3e}); encoded in {:.3} s -> {}",
            a.mesh.display(),
            m.triangle_count(),
            ml.len(),
            name,
            sizes.total(),
            sizes.total() as f64 / tris,
            sizes.connectivity as f64 / tris,
            sizes.positions as f64 / tris,
            sizes.headers as f64 / tris,
            sizes.culling as f64 / tris,
            sizes.padding as f64 / tris,
            sizes.positions as f64 / verts,
            max_error,
            tolerance,
            seconds,
            a.output.display()
        );
    }
    Ok(())
}
