//! `meshletlab parity`: every GPU kernel beside its CPU reference on one mesh.

use super::{load, spinner};
use crate::gpu::parity::{Check, Family};
use crate::meshlet::Limits;
use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `parity`.
#[derive(Args, Debug)]
pub struct ParityArgs {
    /// Mesh file (PLY, OBJ, STL, glTF/GLB, optionally .zst).
    mesh: PathBuf,
    /// Meshlet limits for k-medoids.
    #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
    limits: Limits,
    /// Kernel families to leave out (comma-separated), e.g. `--skip kmedoids-flat,grower` on a large mesh
    /// where those two take most of the time.
    #[arg(long, value_delimiter = ',', value_enum)]
    skip: Vec<Family>,
    /// Print JSON (mesh, device, one object per kernel with times and the verdict) instead of text.
    #[arg(long)]
    json: bool,
}

/// Prints one line per check (`name  CPU s  GPU s  verdict`); returns how many differ.
pub(super) fn print_checks(checks: &[Check]) -> usize {
    let mut failed = 0;
    for c in checks {
        let verdict = match &c.mismatch {
            None => "identical".to_string(),
            Some(d) => {
                failed += 1;
                format!("DIFFERS: {d}")
            }
        };
        say!(
            "{:<70} CPU {:>8.3} s  GPU {:>8.3} s  {verdict}",
            c.name,
            c.cpu_seconds,
            c.gpu_seconds
        );
    }
    failed
}

/// Fails when any check differs, naming the mesh.
pub(super) fn verdict(path: &Path, checks: &[Check]) -> Result<()> {
    let failed = checks.iter().filter(|c| c.mismatch.is_some()).count();
    if failed > 0 {
        bail!(
            "{}: {failed} of {} GPU kernels differ from their CPU references",
            path.display(),
            checks.len()
        );
    }
    Ok(())
}

pub(super) fn run(a: ParityArgs, quiet: bool) -> Result<()> {
    if Family::ALL.iter().all(|f| a.skip.contains(f)) {
        // A run that compares nothing must not pass as a parity verdict.
        return Err(super::usage("--skip leaves no kernel family to compare"));
    }
    let m = load(&a.mesh, quiet)?;
    let gpu = crate::gpu::Gpu::new()?;
    if !a.json {
        say!(
            "{}: {} triangles; GPU: {}",
            a.mesh.display(),
            m.triangle_count(),
            gpu.describe()
        );
    }
    let pb = spinner(quiet, "running every kernel on the GPU and the CPU".into());
    let checks = crate::gpu::parity::run_except(&gpu, &m, a.limits, &a.skip)
        .with_context(|| format!("{}: GPU run failed", a.mesh.display()))?
        .checks;
    pb.finish_and_clear();
    if a.json {
        let out = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "triangles": m.triangle_count(),
            "limits": a.limits.to_string(),
            "device": gpu.describe(),
            "skipped": a.skip,
            "identical": checks.iter().all(|c| c.mismatch.is_none()),
            "checks": checks,
        });
        say!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_checks(&checks);
    }
    if gpu.timing_each_kernel() {
        // MESHLETLAB_GPU_PROFILE: where the GPU time of all checks went, to stderr.
        let p = gpu.profile();
        eprintln!(
            "gpu profile: {} submissions, {} dispatches, {} round trips ({:.3} s waiting), {:.3} s kernels",
            p.submissions, p.dispatches, p.round_trips, p.wait_seconds, p.kernel_seconds
        );
        for (k, (n, s)) in &p.per_kernel {
            eprintln!("gpu profile: {k:<16} {n:>7} {:>10.1} ms", s * 1e3);
        }
    }
    verdict(&a.mesh, &checks)
}
