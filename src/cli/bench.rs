//! `meshletlab bench ...`: the benchmarks that write results/.

use super::{default_meshes_dir, load, spinner, StrategyArgs};
use crate::bench;
use crate::meshlet::Limits;
use anyhow::{bail, Result};
use clap::Subcommand;
use std::path::PathBuf;
use std::time::Duration;

/// Help of every bench's `--smoke`.
const SMOKE: &str = "Smoke run: tiny generated meshes, one run, tables into --out (not results/) \
    - checks that the bench runs and writes its files; no number in them is a measurement";

/// Benchmarks.
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Every mesh x strategy: time (median), meshlet count, fills, culling, radius -> build.md, build.csv.
    Build {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Builds per mesh and strategy (>= 5 for reported numbers).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
        runs: u32,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Only these strategies (repeatable; default all but the slow kmedoids-paper, plus the
        /// `+refine` rows and the per-preset count comparison).
        #[arg(short, long)]
        strategy: Vec<String>,
        /// Skip the `+refine` rows and the per-preset count comparison (64/84, 128/128).
        #[arg(long)]
        no_refined: bool,
        /// Skip the `+refine-max` rows (they take minutes on the biggest meshes).
        #[arg(long)]
        no_refine_max: bool,
        #[command(flatten)]
        args: StrategyArgs,
    },
    /// GPU kernels against their CPU references (bunny, igea, dragon, dragon x4 and x16) -> gpu.md.
    Gpu {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Meshlet limits.
        #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
        limits: Limits,
        /// Above this many triangles, skip the GPU k-medoids (rayon still runs).
        #[arg(long, default_value_t = 16_000_000)]
        kmedoids_gpu_max: usize,
        /// Above this many triangles, skip the one-thread CPU runs and the GPU grower.
        #[arg(long, default_value_t = 4_000_000)]
        one_thread_max: usize,
        /// Leave out the subdivided dragons (3.5 M and 14 M triangles).
        #[arg(long)]
        quick: bool,
    },
    /// Mesh shaders against the vertex pipeline on every shared mesh: ms per frame with and without
    /// task-shader culling, culled shares, ns per triangle, bunny images -> render.md.
    Render {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Meshlet limits.
        #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
        limits: Limits,
        /// Strategies (comma-separated).
        #[arg(short, long, value_delimiter = ',', default_values_t = bench::render::DEFAULT_STRATEGIES.iter().map(|s| s.to_string()))]
        strategy: Vec<String>,
        /// Strategies of the experiments: the four descriptor layouts, meshlets ordered by
        /// primitive count, triangle order inside meshlets (comma-separated; empty: none).
        #[arg(long, value_delimiter = ',', default_values_t = bench::render::DEFAULT_EXPERIMENT_STRATEGIES.iter().map(|s| s.to_string()))]
        experiment_strategy: Vec<String>,
        /// Views per mesh (sized for lavapipe; the paper used 100,000 frames on a GPU).
        #[arg(long, default_value_t = 10)]
        views: usize,
        /// Seed of the view sequence.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Camera distance from the mesh centre in bounding radii (every view sees the whole mesh).
        #[arg(long, default_value_t = 2.5)]
        distance: f32,
        /// Distance of the close views for the culling shares (inside the bounding sphere, so the
        /// frustum culls).
        #[arg(long, default_value_t = 0.9)]
        near_distance: f32,
    },
    /// GPU/CPU agreement and conservative bounds on a mesh translated, scaled, flattened, with
    /// duplicate vertices and a huge coordinate range -> stability.md.
    Stability {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Base mesh (file stem in the folder).
        #[arg(long, default_value = "stanford_bunny")]
        mesh: String,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Meshlet limits.
        #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
        limits: Limits,
    },
    /// Paper fidelity: greedy and bounding sphere on the bunny as the paper's text describes them,
    /// as its published code runs them, and with one of the code's traits reverted, at 64/126 and
    /// the code's 64/125, beside the paper's Tables 4, 7, 8 -> fidelity.md, fidelity.csv.
    Fidelity {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// The bunny (file stem in the folder; the paper's figures are for it).
        #[arg(long, default_value = "stanford_bunny")]
        mesh: String,
        /// Builds per row (median time).
        #[arg(long, default_value_t = 9)]
        runs: usize,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
    },
    /// k-medoids at scale (fast and paper modes, every mesh) and a run-time-vs-error sweep -> kmedoids.md.
    Kmedoids {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Meshlet limits.
        #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
        limits: Limits,
        /// Seconds paper mode may spend per mesh before finishing the fast way.
        #[arg(long, default_value_t = 60.0)]
        paper_budget: f64,
        /// Run only the fast mode.
        #[arg(long)]
        skip_paper: bool,
        /// Mesh (file stem) for the iteration/threshold sweep.
        #[arg(long, default_value = "stanford_bunny")]
        sweep_mesh: String,
    },
    /// Cluster LOD: our DAG beside meshoptimizer's clod_build(clod_default_config(128)) on every
    /// shared mesh: build time on 1 and 2 threads, levels, roots, stuck groups, per-level ratios,
    /// triangles selected and frame time against camera distance at a 1-pixel threshold, the best
    /// level-0 strategy, the dragon at 14 M triangles -> lod.md, lod.csv, lod_levels.csv,
    /// lod_curve.csv, plots.
    Lod {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Interleaved build runs per configuration (median reported).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        runs: u32,
        /// Random directions per camera distance for the triangle counts.
        #[arg(long, default_value_t = 16)]
        select_views: usize,
        /// Views per camera distance for frame times (0: do not render).
        #[arg(long, default_value_t = 3)]
        render_views: usize,
        /// LOD threshold in pixels.
        #[arg(long, default_value_t = 1.0)]
        threshold: f32,
        /// Level-0 strategies to compare (comma-separated).
        #[arg(short, long, value_delimiter = ',', default_values_t = bench::lod::DEFAULT_STRATEGIES.iter().map(|s| s.to_string()))]
        strategy: Vec<String>,
        /// Largest mesh (triangles) of the level-0 strategy comparison.
        #[arg(long, default_value_t = 400_000)]
        strategy_max_triangles: usize,
        /// Leave out the dragon subdivided to 14 M triangles.
        #[arg(long)]
        quick: bool,
        /// Our DAG: target meshlets per group.
        #[arg(long, default_value_t = crate::lod::Config::default().group_size as u32, value_parser = clap::value_parser!(u32).range(2..=64))]
        group_size: u32,
        /// Our DAG: permissive simplification (as clod).
        #[arg(long)]
        permissive: bool,
    },
    /// Compressed meshlets: laced wires and meshoptimizer's codec on every shared mesh and a
    /// multi-mesh scene, at the paper's 14-bit tolerance and at 1e-4 of the diagonal: bytes per
    /// triangle split by kind, errors, duplication, encode/decode speed on 1 and 2 threads, the
    /// paper's Figure 8 (bits per vertex against error) -> compress.md, compress.csv,
    /// compress_fig8.csv, plots.
    Compress {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Interleaved timing runs (median reported).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
        runs: u32,
    },
    /// Compressed meshlets drawn from their encoded bytes (laced wires, SC/IX/GI/TS compact)
    /// against the uncompressed split layout and the vertex pipeline, per shared mesh and on a
    /// multi-mesh scene: bytes resident, ms per frame, the targets' ratios, size against speed
    /// -> compress-render.md, compress-render.csv, compress_render_tradeoff.svg.
    CompressRender {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Views per mesh (framed random directions).
        #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u64).range(1..))]
        views: u64,
        /// Seed of the view sequence.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Copies of the ten shared meshes in the scene (5: the most for
        /// which GI compact's one buffer stays under lavapipe's 128 MiB storage binding).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..))]
        scene_copies: u64,
    },
    /// Mutation fuzzer over every file reader (PLY ASCII/LE/BE, OBJ, glTF, GLB, .zst, meshlet
    /// files): >= 1 M seeded cases in child processes; panics, hangs and allocations over the bound
    /// are counted -> robustness.md, robustness.csv. Exit 1 if any case is a defect.
    Robustness {
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        #[arg(long, help = SMOKE)]
        smoke: bool,
        /// Number of cases.
        #[arg(long, default_value_t = 1_000_000)]
        cases: u64,
        /// Run seed (case k of seed s is always the same file).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Worker processes (default: one per core).
        #[arg(long)]
        workers: Option<usize>,
        /// Write case K's file to -o instead of running (to reproduce a reported case).
        #[arg(long, value_name = "K")]
        dump: Option<u64>,
        /// Folder for --dump.
        #[arg(short, long, default_value = ".")]
        output: PathBuf,
    },
}

/// The mesh folder of a bench: the smoke meshes (written into `out`) for `--smoke`, else `meshes`
/// or the default shared folder.
fn meshes_for(smoke: bool, meshes: Option<PathBuf>, out: &std::path::Path) -> Result<PathBuf> {
    match smoke {
        true => bench::smoke::prepare(out),
        false => Ok(meshes.unwrap_or_else(default_meshes_dir)),
    }
}

pub(super) fn run(cmd: BenchCommand, q: bool) -> Result<()> {
    match cmd {
        BenchCommand::Stability {
            meshes,
            mesh,
            out,
            smoke,
            limits,
        } => {
            let (mesh, path) = match smoke {
                true => bench::smoke::first(&bench::smoke::prepare(&out)?),
                false => {
                    let p = meshes
                        .unwrap_or_else(default_meshes_dir)
                        .join(format!("{mesh}.ply.zst"));
                    (mesh, p)
                }
            };
            let m = load(&path, q)?;
            let pb = spinner(q, format!("stress variants of {mesh}"));
            let reports = bench::stability::run(&mesh, &m, limits, &out)?;
            pb.finish_and_clear();
            let bad: Vec<_> = reports.iter().filter(|r| !r.ok()).map(|r| r.name).collect();
            println!("wrote {}", out.join("stability.md").display());
            if !bad.is_empty() {
                bail!("stability checks failed for: {}", bad.join(", "));
            }
            Ok(())
        }
        BenchCommand::Gpu {
            meshes,
            out,
            smoke,
            limits,
            kmedoids_gpu_max,
            one_thread_max,
            quick,
        } => {
            let cfg = bench::gpu::Config {
                meshes: meshes_for(smoke, meshes, &out)?,
                out,
                limits,
                kmedoids_gpu_max,
                one_thread_max,
                quick: quick || smoke,
                smoke,
                quiet: q,
            };
            bench::gpu::run(&cfg)?;
            println!("wrote {}", cfg.out.join("gpu.md").display());
            Ok(())
        }
        BenchCommand::Render {
            meshes,
            out,
            smoke,
            limits,
            strategy,
            experiment_strategy,
            views,
            seed,
            distance,
            near_distance,
        } => {
            let cfg = bench::render::Config {
                meshes: meshes_for(smoke, meshes, &out)?,
                out,
                limits,
                strategies: strategy,
                experiment_strategies: experiment_strategy
                    .into_iter()
                    .filter(|s| !s.is_empty())
                    .collect(),
                views: if smoke { 1 } else { views },
                seed,
                distance,
                near_distance,
                quiet: q,
            };
            bench::render::run(&cfg)?;
            println!("wrote {}", cfg.out.join("render.md").display());
            Ok(())
        }
        BenchCommand::Fidelity {
            meshes,
            mesh,
            runs,
            out,
            smoke,
        } => {
            let (mesh, runs) = match smoke {
                true => (bench::smoke::first(&bench::smoke::prepare(&out)?).1, 1),
                false => (
                    meshes
                        .unwrap_or_else(default_meshes_dir)
                        .join(format!("{mesh}.ply.zst")),
                    runs.max(1),
                ),
            };
            let cfg = bench::fidelity::Config { mesh, runs, out };
            bench::fidelity::run(&cfg)?;
            println!("wrote {}", cfg.out.join("fidelity.md").display());
            Ok(())
        }
        BenchCommand::Kmedoids {
            meshes,
            out,
            smoke,
            limits,
            paper_budget,
            skip_paper,
            sweep_mesh,
        } => {
            let meshes = meshes_for(smoke, meshes, &out)?;
            let (sweep_mesh, paper_budget) = match smoke {
                true => (bench::smoke::first(&meshes).0, 0.5),
                false => (sweep_mesh, paper_budget),
            };
            let cfg = bench::kmedoids::Config {
                meshes,
                out,
                limits,
                paper_budget: Duration::from_secs_f64(paper_budget.max(0.0)),
                skip_paper,
                sweep_mesh,
                quiet: q,
            };
            bench::kmedoids::run(&cfg)?;
            println!("wrote {}", cfg.out.join("kmedoids.md").display());
            Ok(())
        }
        BenchCommand::Build {
            meshes,
            runs,
            out,
            smoke,
            strategy,
            no_refined,
            no_refine_max,
            args,
        } => {
            let cfg = bench::build::Config {
                meshes: meshes_for(smoke, meshes, &out)?,
                runs: if smoke { 1 } else { runs as usize },
                out,
                limits: args.limits,
                strategies: strategy,
                options: args.options(),
                quiet: q,
                refined: !no_refined,
                refine_max: !no_refine_max && !smoke,
            };
            let rows = bench::build::run(&cfg)?;
            println!(
                "wrote {} and {} ({} rows)",
                cfg.out.join("build.md").display(),
                cfg.out.join("build.csv").display(),
                rows.len()
            );
            Ok(())
        }
        BenchCommand::Lod {
            meshes,
            out,
            smoke,
            runs,
            select_views,
            render_views,
            threshold,
            strategy,
            strategy_max_triangles,
            quick,
            group_size,
            permissive,
        } => {
            if !(threshold > 0.0 && threshold.is_finite()) {
                bail!("--threshold must be a positive number of pixels");
            }
            let cfg = bench::lod::Config {
                meshes: meshes_for(smoke, meshes, &out)?,
                out,
                runs: if smoke { 1 } else { runs as usize },
                distances: bench::lod::DISTANCES.to_vec(),
                select_views: if smoke { 2 } else { select_views.max(1) },
                render_views: if smoke {
                    render_views.min(1)
                } else {
                    render_views
                },
                threshold,
                strategies: strategy,
                strategy_max_triangles,
                quick: quick || smoke,
                lod: crate::lod::Config {
                    group_size: group_size as usize,
                    permissive,
                    ..Default::default()
                },
                quiet: q,
            };
            bench::lod::run(&cfg)?;
            println!("wrote {}", cfg.out.join("lod.md").display());
            Ok(())
        }
        BenchCommand::Compress {
            meshes,
            out,
            smoke,
            runs,
        } => {
            let cfg = bench::compress::Config {
                meshes: meshes_for(smoke, meshes, &out)?,
                out,
                runs: if smoke { 1 } else { runs as usize },
                quiet: q,
            };
            let rows = bench::compress::run(&cfg)?;
            println!(
                "wrote {} ({} encodings)",
                cfg.out.join("compress.md").display(),
                rows.len()
            );
            Ok(())
        }
        BenchCommand::CompressRender {
            meshes,
            out,
            smoke,
            views,
            seed,
            scene_copies,
        } => {
            let cfg = bench::compress_render::Config {
                meshes: meshes_for(smoke, meshes, &out)?,
                out,
                views: if smoke { 1 } else { views as usize },
                seed,
                scene_copies: if smoke { 1 } else { scene_copies as usize },
                quiet: q,
            };
            let rows = bench::compress_render::run(&cfg)?;
            println!(
                "wrote {} ({} rows)",
                cfg.out.join("compress-render.md").display(),
                rows.len()
            );
            Ok(())
        }
        BenchCommand::Robustness {
            out,
            smoke,
            cases,
            seed,
            workers,
            dump,
            output,
        } => {
            if let Some(k) = dump {
                let p = crate::fuzz::harness::dump(seed, k, &output)?;
                println!("case {k} of seed {seed} -> {}", p.display());
                return Ok(());
            }
            if smoke {
                bench::smoke::prepare(&out)?;
            }
            let cfg = bench::robustness::Config {
                out,
                cases: if smoke { 2000 } else { cases },
                seed,
                workers: workers.unwrap_or_else(rayon::current_num_threads),
                quiet: q,
            };
            let report = bench::robustness::run(&cfg)?;
            let t = report.totals();
            println!(
                "{} cases in {:.0} s: {} valid, {} typed errors, {} defects; wrote {}",
                report.cases,
                report.seconds,
                t.get(crate::fuzz::harness::Verdict::Valid),
                t.get(crate::fuzz::harness::Verdict::Error),
                t.defects(),
                cfg.out.join("robustness.md").display()
            );
            if t.defects() > 0 {
                bail!(
                    "{} fuzz cases were defects (see robustness.md)",
                    t.defects()
                );
            }
            Ok(())
        }
    }
}
