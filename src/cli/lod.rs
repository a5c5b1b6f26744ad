//! `meshletlab lod`: build the cluster-LOD DAG and write the LOD file.

use super::clusters::ClusterArgs;
use super::{load, spinner, StrategyArgs};
use crate::lod::{self, io::LodFile};
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `lod`.
#[derive(Args, Debug)]
pub struct LodArgs {
    /// Mesh file.
    mesh: PathBuf,
    /// Strategy of level 0 and of every split (with --labels or --meshlets: of every split).
    #[arg(short, long, default_value = "meshopt")]
    strategy: String,
    /// Output LOD file (format: see `meshletlab::lod::io`).
    #[arg(short, long)]
    output: PathBuf,
    /// Target meshlets per group.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..=64))]
    group_size: u32,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    args: StrategyArgs,
    /// With --labels or --meshlets, the file's clusters are level 0.
    #[command(flatten)]
    clusters: ClusterArgs,
}

/// One level's row.
#[derive(serde::Serialize)]
struct Row {
    level: usize,
    meshlets: usize,
    triangles: usize,
    ratio_to_level_below: Option<f64>,
    groups: usize,
    stuck_groups: usize,
}

pub(super) fn run(a: LodArgs, quiet: bool) -> Result<()> {
    let s = crate::strategy::by_name(&a.strategy, &a.args.options())?;
    super::output::check_file(&a.output, "a LOD file", &[])?;
    a.clusters.check(false, false)?;
    let m = load(&a.mesh, quiet)?;
    let level0 = a.clusters.import(&m, a.args.limits)?;
    let cfg = lod::Config {
        group_size: a.group_size as usize,
        ..Default::default()
    };
    let pb = spinner(quiet, format!("building the LOD DAG with {}", a.strategy));
    let t0 = std::time::Instant::now();
    let (dag, level0_name) = match level0 {
        Some(i) => {
            let name = i.name.clone() + &i.split_note();
            (
                lod::build_from(&m, i.meshlets, s.as_ref(), a.args.limits, &cfg),
                name,
            )
        }
        None => (
            lod::build(&m, s.as_ref(), a.args.limits, &cfg),
            a.strategy.clone(),
        ),
    };
    let seconds = t0.elapsed().as_secs_f64();
    pb.finish_and_clear();
    let rows: Vec<Row> = dag
        .levels
        .iter()
        .enumerate()
        .map(|(n, l)| {
            let t = lod::level_triangles(l);
            let groups: Vec<_> = dag
                .groups
                .iter()
                .filter(|g| g.level as usize == n)
                .collect();
            Row {
                level: n,
                meshlets: l.meshlets.len(),
                triangles: t,
                ratio_to_level_below: (n > 0)
                    .then(|| t as f64 / lod::level_triangles(&dag.levels[n - 1]).max(1) as f64),
                groups: groups.len(),
                stuck_groups: groups.iter().filter(|g| g.stuck).count(),
            }
        })
        .collect();
    let file = LodFile {
        source_vertices: m.vertex_count() as u32,
        source_triangles: m.triangle_count() as u32,
        fingerprint: m.fingerprint(),
        lod: dag,
    };
    file.save(&a.output)?;
    let dag = &file.lod;
    let total = dag.triangle_count() as f64 / m.triangle_count().max(1) as f64;
    if a.json {
        let out = serde_json::json!({
            "mesh": a.mesh.display().to_string(),
            "triangles": m.triangle_count(),
            "strategy": a.strategy,
            "level0": level0_name,
            "limits": a.args.limits.to_string(),
            "seconds": seconds,
            "levels": rows,
            "roots": dag.roots(),
            "stuck_groups": dag.stuck_groups(),
            "all_levels_over_source": total,
            "output": a.output.display().to_string(),
        });
        say!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    say!(
        "{}: {} triangles ({level0_name} at level 0) -> {} levels in {seconds:.3} s ({:.2} M triangles/s, {} threads); {} root(s), {} stuck group(s); all levels {total:.3}x the source -> {}",
        a.mesh.display(),
        m.triangle_count(),
        dag.levels.len(),
        m.triangle_count() as f64 / seconds / 1e6,
        rayon::current_num_threads(),
        dag.roots(),
        dag.stuck_groups(),
        a.output.display()
    );
    say!("level  meshlets  triangles  ratio  groups  stuck");
    for r in &rows {
        say!(
            "{:>5}  {:>8}  {:>9}  {:>5}  {:>6}  {:>5}",
            r.level,
            r.meshlets,
            r.triangles,
            r.ratio_to_level_below
                .map(|x| format!("{x:.3}"))
                .unwrap_or_else(|| "-".into()),
            r.groups,
            r.stuck_groups
        );
    }
    Ok(())
}
