//! `meshletlab stats`: mesh topology counts, then one validated metrics row per strategy.

use super::clusters::{refuse_instanced, ClusterArgs};
use super::{describe, evaluate_all, fail_on_invalid, gpu_for, load_scene, strategies};
use super::{Device, DeviceArgs, StrategyArgs};
use crate::bench::{evaluate_builds, metrics_table, Evaluation};
use crate::gpu::build::{build, warm_up, GPU_STRATEGIES};
use crate::mesh::{MeshStats, Scene};
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `stats`.
#[derive(Args, Debug)]
pub struct StatsArgs {
    /// Mesh file (an instanced glTF scene or `gen:` scene is measured per mesh).
    mesh: PathBuf,
    /// Strategy name (`meshletlab --help` lists them), a comma-separated list, or "all" (with
    /// `--device gpu`: every strategy with a GPU path).
    #[arg(short, long, default_value = "all")]
    strategy: String,
    /// Builds per strategy; the time column is their median.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    runs: u32,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    args: StrategyArgs,
    #[command(flatten)]
    device: DeviceArgs,
    /// With --labels or --meshlets, one row more, named by the file (`labels:NAME`,
    /// `meshlets:NAME`), measured like the strategies' (its time: reading and packing the file).
    #[command(flatten)]
    clusters: ClusterArgs,
}

pub(super) fn run(a: StatsArgs, quiet: bool) -> Result<()> {
    let label = a.mesh.display().to_string();
    a.clusters.check(false, false)?;
    let scene = load_scene(&a.mesh, quiet)?;
    if scene.is_instanced() {
        if a.clusters.file().is_some() {
            return Err(refuse_instanced(&a.mesh, "--labels and --meshlets"));
        }
        return run_scene(&a, scene, &label, quiet);
    }
    let (m, mut rows) = match a.device.device {
        Device::Cpu => {
            let list = strategies(&a.strategy, &a.args.options())?;
            let m = scene.meshes.into_iter().next().expect("one mesh");
            let rows = evaluate_all(&m, &list, a.args.limits, a.runs as usize, &label, quiet);
            (m, rows)
        }
        Device::Gpu => {
            let m = scene.meshes.into_iter().next().expect("one mesh");
            let rows = on_gpu(&a, &m)?;
            (m, rows)
        }
    };
    let imported = imported_row(&a, &m)?;
    if let Some((row, _)) = &imported {
        rows.push(row.clone());
    }
    let st = MeshStats::of(&m);
    if a.json {
        let mut out = serde_json::json!({
            "mesh": label,
            "stats": st,
            "limits": a.args.limits.to_string(),
            "device": if a.device.device == Device::Gpu { "gpu" } else { "cpu" },
            "strategies": rows,
        });
        if let Some((row, (clusters, split))) = &imported {
            out["imported"] = serde_json::json!({
                "name": row.strategy, "clusters": clusters, "split": split,
            });
        }
        say!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        say!("{}", describe(&label, &st));
        say!("limits {}\n", a.args.limits);
        say!("{}", metrics_table(&rows));
        if let Some((row, (clusters, split))) = &imported {
            say!(
                "{}: {clusters} clusters in the file, {split} of them split by meshopt to fit the limits",
                row.strategy
            );
        }
    }
    fail_on_invalid(&rows, &label)
}

/// The row of `--labels`/`--meshlets`, read and packed `--runs` times like a strategy's builds,
/// with the file's cluster count and how many `--split` divided.
fn imported_row(
    a: &StatsArgs,
    m: &crate::mesh::Mesh,
) -> Result<Option<(Evaluation, (usize, usize))>> {
    let Some(name) = a.clusters.name() else {
        return Ok(None);
    };
    let mut counts = (0, 0);
    let import = || {
        let i = a
            .clusters
            .import(m, a.args.limits)?
            .expect("a file is given");
        counts = (i.clusters, i.split);
        anyhow::Ok(i.meshlets)
    };
    let row = evaluate_builds(m, &name, a.args.limits, a.runs as usize, import)?;
    Ok(Some((row, counts)))
}

/// `stats --device gpu`: the mesh and one row per strategy, each built on the GPU `--runs` times
/// after a warm-up; `setup_ms` is the device's creation plus that warm-up.
fn on_gpu(a: &StatsArgs, m: &crate::mesh::Mesh) -> Result<Vec<Evaluation>> {
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
    let limits = a.args.limits;
    let mut rows = Vec::new();
    for name in names {
        let warm_ms = warm_up(&gpu, name, limits, &opts)? * 1e3;
        let run = || build(&gpu, name, m, limits, &opts).map(|b| b.meshlets);
        let mut e = evaluate_builds(m, name, limits, a.runs as usize, run)?;
        e.device = "gpu";
        e.setup_ms = Some(device_ms + warm_ms);
        rows.push(e);
    }
    Ok(rows)
}

/// `stats` of an instanced scene: each mesh's statistics and one row per strategy (its meshlets
/// are built once per mesh), then, per strategy, the meshlets built and drawn over the instances.
fn run_scene(a: &StatsArgs, scene: Scene, label: &str, quiet: bool) -> Result<()> {
    let mut per_mesh = Vec::new();
    for (i, m) in scene.meshes.iter().enumerate() {
        let mesh_label = format!("{label} mesh {i}");
        let rows = match a.device.device {
            Device::Cpu => {
                let list = strategies(&a.strategy, &a.args.options())?;
                evaluate_all(m, &list, a.args.limits, a.runs as usize, &mesh_label, quiet)
            }
            Device::Gpu => on_gpu(a, m)?,
        };
        fail_on_invalid(&rows, &mesh_label)?;
        per_mesh.push((mesh_label, MeshStats::of(m), rows));
    }
    // Per strategy: (meshlets built, meshlets over the instances).
    let names: Vec<&str> = per_mesh[0].2.iter().map(|e| e.strategy.as_str()).collect();
    let totals: Vec<(String, usize, usize)> = names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let built = per_mesh.iter().map(|p| p.2[k].metrics.meshlets).sum();
            let drawn = scene
                .instances
                .iter()
                .map(|i| per_mesh[i.mesh as usize].2[k].metrics.meshlets)
                .sum();
            (name.to_string(), built, drawn)
        })
        .collect();
    if a.json {
        let out = serde_json::json!({
            "mesh": label,
            "limits": a.args.limits.to_string(),
            "device": if a.device.device == Device::Gpu { "gpu" } else { "cpu" },
            "meshes": scene.meshes.len(),
            "instances": scene.instances.len(),
            "triangles_built": scene.triangles_built(),
            "triangles_drawn": scene.triangles_drawn(),
            "per_mesh": per_mesh.iter().map(|(l, st, rows)| serde_json::json!({
                "mesh": l, "stats": st, "strategies": rows,
            })).collect::<Vec<_>>(),
            "strategies": totals.iter().map(|(n, b, d)| serde_json::json!({
                "name": n, "meshlets_built": b, "meshlets_over_instances": d,
            })).collect::<Vec<_>>(),
        });
        say!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    say!(
        "{label}: {} meshes, {} instances, {} triangles built, {} drawn; limits {}\n",
        scene.meshes.len(),
        scene.instances.len(),
        scene.triangles_built(),
        scene.triangles_drawn(),
        a.args.limits
    );
    for (l, st, rows) in &per_mesh {
        say!("{}", describe(l, st));
        say!("{}", metrics_table(rows));
    }
    for (n, b, d) in totals {
        say!("{n}: {b} meshlets built, {d} drawn over the instances");
    }
    Ok(())
}
