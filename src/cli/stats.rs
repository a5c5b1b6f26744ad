//! `meshletlab stats`: mesh topology counts, then one validated metrics row per strategy.

use super::{describe, evaluate_all, fail_on_invalid, gpu_for, load, strategies};
use super::{Device, DeviceArgs, StrategyArgs};
use crate::bench::{evaluate_builds, metrics_table, Evaluation};
use crate::gpu::build::{build, warm_up, GPU_STRATEGIES};
use crate::mesh::MeshStats;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `stats`.
#[derive(Args, Debug)]
pub struct StatsArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Strategy name (`meshletlab --help` lists them), a comma-separated list, or "all" (with
    /// `--device gpu`: every strategy with a GPU path).
    #[arg(short, long, default_value = "all")]
    strategy: String,
    /// Builds per strategy; the time column is their median.
    #[arg(long, default_value_t = 1)]
    runs: usize,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    args: StrategyArgs,
    #[command(flatten)]
    device: DeviceArgs,
}

pub(super) fn run(a: StatsArgs, quiet: bool) -> Result<()> {
    let label = a.mesh.display().to_string();
    let (m, rows) = match a.device.device {
        Device::Cpu => {
            let list = strategies(&a.strategy, &a.args.options())?;
            let m = load(&a.mesh, quiet)?;
            let rows = evaluate_all(&m, &list, a.args.limits, a.runs.max(1), &label, quiet);
            (m, rows)
        }
        Device::Gpu => on_gpu(&a, quiet)?,
    };
    let st = MeshStats::of(&m);
    if a.json {
        let out = serde_json::json!({
            "mesh": label,
            "stats": st,
            "limits": a.args.limits.to_string(),
            "device": if a.device.device == Device::Gpu { "gpu" } else { "cpu" },
            "strategies": rows,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!("{}", describe(&label, &st));
        println!("limits {}\n", a.args.limits);
        println!("{}", metrics_table(&rows));
    }
    fail_on_invalid(&rows, &label)
}

/// `stats --device gpu`: the mesh and one row per strategy, each built on the GPU `--runs` times
/// after a warm-up; `setup_ms` is the device's creation plus that warm-up.
fn on_gpu(a: &StatsArgs, quiet: bool) -> Result<(crate::mesh::Mesh, Vec<Evaluation>)> {
    let opts = a.args.options();
    let names: Vec<&str> = if a.strategy == "all" {
        GPU_STRATEGIES.iter().map(|k| k.name()).collect()
    } else {
        a.strategy.split(',').map(str::trim).collect()
    };
    for name in &names {
        crate::strategy::by_name(name, &opts)?;
    }
    let (gpu, device_ms) = gpu_for(&names)?;
    let m = load(&a.mesh, quiet)?;
    let limits = a.args.limits;
    let mut rows = Vec::new();
    for name in names {
        let warm_ms = warm_up(&gpu, name, limits, &opts)? * 1e3;
        let run = || build(&gpu, name, &m, limits, &opts).map(|b| b.meshlets);
        let mut e = evaluate_builds(&m, name, limits, a.runs.max(1), run)?;
        e.device = "gpu";
        e.setup_ms = Some(device_ms + warm_ms);
        rows.push(e);
    }
    Ok((m, rows))
}
