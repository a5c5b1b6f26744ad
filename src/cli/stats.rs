//! `meshletlab stats`: mesh topology counts, then one validated metrics row per strategy.

use super::{describe, evaluate_all, fail_on_invalid, load, strategies, StrategyArgs};
use crate::bench::metrics_table;
use crate::mesh::MeshStats;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `stats`.
#[derive(Args, Debug)]
pub struct StatsArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Strategy name (`meshletlab --help` lists them), a comma-separated list, or "all".
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
}

pub(super) fn run(a: StatsArgs, quiet: bool) -> Result<()> {
    let list = strategies(&a.strategy, &a.args.options())?;
    let m = load(&a.mesh, quiet)?;
    let st = MeshStats::of(&m);
    let label = a.mesh.display().to_string();
    let rows = evaluate_all(&m, &list, a.args.limits, a.runs.max(1), &label, quiet);
    if a.json {
        let out = serde_json::json!({
            "mesh": label,
            "stats": st,
            "limits": a.args.limits.to_string(),
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
