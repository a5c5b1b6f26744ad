//! The `meshletlab` command line. Every failure ends as one readable line on stderr and a non-zero
//! exit status.

use crate::bench::{self, evaluate, metrics_table, Evaluation};
use crate::mesh::{self, generate, Mesh, MeshStats};
use crate::meshlet::descriptor::Format;
use crate::meshlet::order::MeshletOrder;
use crate::meshlet::{io::MeshletFile, validate, Limits};
use crate::strategy::{self, Options, Strategy};
use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Build, measure and compare meshlets (triangle clusters for GPU mesh shaders).
///
/// Meshes: PLY (ASCII/binary), OBJ, glTF 2.0 (.gltf/.glb), each optionally zstd-compressed (.zst).
/// Strategies: nvidia, nvidia+tipsify, greedy, bsphere, bsphere-coherent, bsphere-parallel, kmedoids, kmedoids-paper,
/// compact, meshopt, meshopt-scan, meshopt-spatial ("all" = all but the slow kmedoids-paper).
/// Limits are VERTICES/TRIANGLES per meshlet; default 64/126 (the JCGT paper's).
#[derive(Parser, Debug)]
#[command(name = "meshletlab", version, about, long_about)]
pub struct Cli {
    /// No progress bars.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// Worker threads for parallel steps (default: all cores). Results do not depend on it.
    #[arg(long, global = true, value_name = "N")]
    pub threads: Option<usize>,
    #[command(subcommand)]
    pub command: Command,
}

/// Strategy selection and options shared by several commands.
#[derive(Args, Debug, Clone)]
pub struct StrategyArgs {
    /// Meshlet limits as VERTICES/TRIANGLES (max 256/256); presets: 64/126, 64/124, 64/84.
    #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
    pub limits: Limits,
    /// meshoptimizer cone weight in 0..=1 (0 = fewest meshlets, higher = tighter normal cones).
    #[arg(long, default_value_t = 0.0, value_parser = unit_interval)]
    pub cone_weight: f32,
    /// Vertex-cache size that tipsify optimises for (nvidia+tipsify).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub cache_size: u32,
    /// meshoptimizer spatial builder fill weight (>= 0).
    #[arg(long, default_value_t = 0.5)]
    pub fill_weight: f32,
    /// k-medoids: most assign/update iterations per clustering.
    #[arg(long, default_value_t = 16)]
    pub kmedoids_iterations: u32,
    /// k-medoids: stop when the mean medoid shift (in hops) is at most this.
    #[arg(long, default_value_t = 0.0)]
    pub kmedoids_threshold: f64,
    /// kmedoids-paper: seconds before the remaining splits are done the fast way.
    #[arg(long, default_value_t = 300.0)]
    pub paper_budget: f64,
    /// Reorder triangles inside each meshlet for vertex reuse, local vertices in first-use order.
    #[arg(long)]
    pub local_order: bool,
    /// Order of meshlets in the collection: built, triangles (most first), vertices (most first).
    #[arg(long, default_value = "built", value_parser = clap::value_parser!(MeshletOrder))]
    pub meshlet_order: MeshletOrder,
}

impl StrategyArgs {
    fn options(&self) -> Options {
        Options {
            cone_weight: self.cone_weight,
            cache_size: self.cache_size,
            fill_weight: self.fill_weight.max(0.0),
            kmedoids: strategy::kmedoids::Config {
                max_iterations: self.kmedoids_iterations,
                shift_threshold: self.kmedoids_threshold,
                paper_budget: Duration::from_secs_f64(self.paper_budget),
                ..Default::default()
            },
            local_order: self.local_order,
            meshlet_order: self.meshlet_order,
        }
    }
}

fn unit_interval(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is outside 0..=1"))
    }
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Mesh statistics and a metrics table per strategy (every row validated).
    Stats {
        /// Mesh file.
        mesh: PathBuf,
        /// Strategy name, a comma-separated list, or "all".
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
    },
    /// Build meshlets and write them to a file (format: see `meshletlab::meshlet::io`).
    Build {
        /// Mesh file.
        mesh: PathBuf,
        /// Strategy name.
        #[arg(short, long)]
        strategy: String,
        /// Output file.
        #[arg(short, long)]
        output: PathBuf,
        #[command(flatten)]
        args: StrategyArgs,
    },
    /// Validate a meshlet file written by `build` against its mesh.
    Check {
        /// Mesh file the meshlets were built from.
        mesh: PathBuf,
        /// Meshlet file.
        file: PathBuf,
    },
    /// Compare all strategies on generated meshes (no files needed), or on --mesh files.
    Demo {
        /// Use these mesh files instead of the generated set (repeatable).
        #[arg(long)]
        mesh: Vec<PathBuf>,
        /// Seed of the generated meshes.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[command(flatten)]
        args: StrategyArgs,
    },
    /// 1->4 midpoint subdivision (per level), to make multi-million-triangle inputs from real meshes.
    Subdivide {
        /// Input mesh file.
        mesh: PathBuf,
        /// Output PLY (binary; zstd-compressed if it ends in .zst).
        #[arg(short, long)]
        output: PathBuf,
        /// Subdivision levels (each multiplies the triangle count by 4).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=8))]
        levels: u32,
    },
    /// Runs every GPU kernel and its CPU reference on MESH and compares the outputs (exit 1 on any
    /// difference). Uses the default Vulkan adapter: lavapipe on a machine without a GPU.
    Parity {
        /// Mesh file (PLY, OBJ, glTF/GLB, optionally .zst).
        mesh: PathBuf,
        /// Meshlet limits for k-medoids.
        #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
        limits: Limits,
    },
    /// Draws MESH's meshlets with task and mesh shaders (VK_EXT_mesh_shader; lavapipe on a machine
    /// without a GPU) from seeded random views, beside the vertex pipeline: per view the GPU time of
    /// both, the meshlets the task shader culled, and a PNG of the first view coloured by meshlet.
    Render {
        /// Mesh file.
        mesh: PathBuf,
        /// Strategy name.
        #[arg(short, long, default_value = "meshopt")]
        strategy: String,
        /// Views (random directions around the mesh, the paper's protocol).
        #[arg(long, default_value_t = 5)]
        views: usize,
        /// Seed of the view sequence (the same for every strategy).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Camera distance from the mesh centre in bounding radii.
        #[arg(long, default_value_t = 2.5)]
        distance: f32,
        /// No task-shader culling.
        #[arg(long)]
        no_cull: bool,
        /// Meshlet descriptor layout on the GPU: split (exact bounds), nvidia-a, nvidia-b
        /// (quantised bounds), monolithic (per-meshlet vertex copies).
        #[arg(short, long, default_value = "split", value_parser = clap::value_parser!(Format))]
        descriptor: Format,
        /// Write the first view, coloured by meshlet (the paper's Figure 1), to this PNG.
        #[arg(short, long = "output", visible_alias = "png", value_name = "PNG")]
        output: Option<PathBuf>,
        /// Enable the Khronos validation layer and fail on any error it reports.
        #[arg(long)]
        validate: bool,
        #[command(flatten)]
        args: StrategyArgs,
    },
    /// Benchmarks that write results/.
    #[command(subcommand)]
    Bench(BenchCommand),
}

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
        /// Only these strategies (repeatable; default all but the slow kmedoids-paper).
        #[arg(short, long)]
        strategy: Vec<String>,
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
        /// Meshlet limits.
        #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
        limits: Limits,
        /// Above this many triangles, skip the GPU and one-thread k-medoids (rayon still runs).
        #[arg(long, default_value_t = 4_000_000)]
        kmedoids_gpu_max: usize,
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
        /// Meshlet limits.
        #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
        limits: Limits,
    },
    /// k-medoids at scale (fast and paper modes, every mesh) and a run-time-vs-error sweep -> kmedoids.md.
    Kmedoids {
        /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
        #[arg(long)]
        meshes: Option<PathBuf>,
        /// Output folder.
        #[arg(long, default_value = "results")]
        out: PathBuf,
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
}

/// The default folder of real test meshes.
pub fn default_meshes_dir() -> PathBuf {
    std::env::var_os("MESHLETLAB_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("../shared/meshes"))
}

/// Parses arguments and runs the command.
pub fn run(args: impl IntoIterator<Item = std::ffi::OsString>) -> Result<()> {
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) if !e.use_stderr() => {
            // --help and --version.
            e.print()?;
            return Ok(());
        }
        Err(e) => {
            e.print()?;
            std::process::exit(2);
        }
    };
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .context("cannot set thread count")?;
    }
    let q = cli.quiet;
    match cli.command {
        Command::Stats {
            mesh,
            strategy,
            runs,
            json,
            args,
        } => stats(&mesh, &strategy, runs, json, &args, q),
        Command::Build {
            mesh,
            strategy,
            output,
            args,
        } => build(&mesh, &strategy, &output, &args, q),
        Command::Check { mesh, file } => check(&mesh, &file, q),
        Command::Demo { mesh, seed, args } => demo(&mesh, seed, &args, q),
        Command::Subdivide {
            mesh,
            output,
            levels,
        } => subdivide(&mesh, &output, levels, q),
        Command::Parity { mesh, limits } => parity(&mesh, limits, q),
        Command::Render {
            mesh,
            strategy,
            views,
            seed,
            distance,
            no_cull,
            descriptor,
            output,
            validate,
            args,
        } => render(
            &mesh,
            &strategy,
            RenderOpts {
                views,
                seed,
                distance,
                cull: !no_cull,
                descriptor,
                png: output,
                validate,
            },
            &args,
            q,
        ),
        Command::Bench(BenchCommand::Stability {
            meshes,
            mesh,
            out,
            limits,
        }) => {
            let path = meshes
                .unwrap_or_else(default_meshes_dir)
                .join(format!("{mesh}.ply.zst"));
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
        Command::Bench(BenchCommand::Gpu {
            meshes,
            out,
            limits,
            kmedoids_gpu_max,
            quick,
        }) => {
            let cfg = bench::gpu::Config {
                meshes: meshes.unwrap_or_else(default_meshes_dir),
                out,
                limits,
                kmedoids_gpu_max,
                quick,
                quiet: q,
            };
            bench::gpu::run(&cfg)?;
            println!("wrote {}", cfg.out.join("gpu.md").display());
            Ok(())
        }
        Command::Bench(BenchCommand::Render {
            meshes,
            out,
            limits,
            strategy,
            experiment_strategy,
            views,
            seed,
            distance,
            near_distance,
        }) => {
            let cfg = bench::render::Config {
                meshes: meshes.unwrap_or_else(default_meshes_dir),
                out,
                limits,
                strategies: strategy,
                experiment_strategies: experiment_strategy
                    .into_iter()
                    .filter(|s| !s.is_empty())
                    .collect(),
                views,
                seed,
                distance,
                near_distance,
                quiet: q,
            };
            bench::render::run(&cfg)?;
            println!("wrote {}", cfg.out.join("render.md").display());
            Ok(())
        }
        Command::Bench(BenchCommand::Kmedoids {
            meshes,
            out,
            limits,
            paper_budget,
            skip_paper,
            sweep_mesh,
        }) => {
            let cfg = bench::kmedoids::Config {
                meshes: meshes.unwrap_or_else(default_meshes_dir),
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
        Command::Bench(BenchCommand::Build {
            meshes,
            runs,
            out,
            strategy,
            args,
        }) => {
            let cfg = bench::build::Config {
                meshes: meshes.unwrap_or_else(default_meshes_dir),
                runs: runs as usize,
                out,
                limits: args.limits,
                strategies: strategy,
                options: args.options(),
                quiet: q,
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
    }
}

fn spinner(quiet: bool, msg: String) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("static template"),
    );
    pb.set_message(msg);
    pb.enable_steady_tick(Duration::from_millis(120));
    pb
}

fn load(path: &Path, quiet: bool) -> Result<Mesh> {
    let pb = spinner(quiet, format!("loading {}", path.display()));
    let m = mesh::load(path);
    pb.finish_and_clear();
    Ok(m?)
}

fn strategies(spec: &str, opts: &Options) -> Result<Vec<Box<dyn Strategy>>> {
    if spec == "all" {
        return Ok(strategy::all(opts));
    }
    spec.split(',')
        .map(|n| strategy::by_name(n.trim(), opts).map_err(Into::into))
        .collect()
}

fn evaluate_all(
    mesh: &Mesh,
    list: &[Box<dyn Strategy>],
    limits: Limits,
    runs: usize,
    label: &str,
    quiet: bool,
) -> Vec<Evaluation> {
    let pb = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(list.len() as u64)
    };
    pb.set_style(
        ProgressStyle::with_template("[{bar:20}] {pos}/{len} {msg}")
            .expect("static template")
            .progress_chars("=> "),
    );
    let rows = list
        .iter()
        .map(|s| {
            pb.set_message(format!("{label}: {}", s.name()));
            let e = evaluate(mesh, s.as_ref(), limits, runs);
            pb.inc(1);
            e
        })
        .collect();
    pb.finish_and_clear();
    rows
}

fn describe(name: &str, s: &MeshStats) -> String {
    format!(
        "{name}: {} triangles, {} vertices ({} unreferenced); degenerate {}, zero-area {}, duplicate {}; \
         edges {} (boundary {}, non-manifold {}); components {}",
        s.triangles,
        s.vertices,
        s.unreferenced_vertices,
        s.degenerate_triangles,
        s.zero_area_triangles,
        s.duplicate_triangles,
        s.edges,
        s.boundary_edges,
        s.non_manifold_edges,
        s.components
    )
}

fn fail_on_invalid(rows: &[Evaluation], mesh: &str) -> Result<()> {
    if let Some(bad) = rows.iter().find(|r| r.invalid.is_some()) {
        bail!(
            "{mesh}: strategy {} produced invalid meshlets: {}",
            bad.strategy,
            bad.invalid.as_deref().unwrap_or("")
        );
    }
    Ok(())
}

fn stats(
    path: &Path,
    spec: &str,
    runs: usize,
    json: bool,
    args: &StrategyArgs,
    quiet: bool,
) -> Result<()> {
    let list = strategies(spec, &args.options())?;
    let m = load(path, quiet)?;
    let st = MeshStats::of(&m);
    let rows = evaluate_all(
        &m,
        &list,
        args.limits,
        runs.max(1),
        &path.display().to_string(),
        quiet,
    );
    if json {
        let out = serde_json::json!({
            "mesh": path.display().to_string(),
            "stats": st,
            "limits": args.limits.to_string(),
            "strategies": rows,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!("{}", describe(&path.display().to_string(), &st));
        println!("limits {}\n", args.limits);
        println!("{}", metrics_table(&rows));
    }
    fail_on_invalid(&rows, &path.display().to_string())
}

fn build(path: &Path, name: &str, output: &Path, args: &StrategyArgs, quiet: bool) -> Result<()> {
    let s = strategy::by_name(name, &args.options())?;
    let m = load(path, quiet)?;
    let pb = spinner(quiet, format!("building with {name}"));
    let t0 = std::time::Instant::now();
    let ml = s.build(&m, args.limits);
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    pb.finish_and_clear();
    validate(&m, &ml, args.limits).with_context(|| {
        format!(
            "{}: strategy {name} produced invalid meshlets",
            path.display()
        )
    })?;
    let file = MeshletFile {
        limits: args.limits,
        source_vertices: m.vertex_count() as u32,
        source_triangles: m.triangle_count() as u32,
        fingerprint: m.fingerprint(),
        strategy: name.to_string(),
        meshlets: ml,
    };
    file.save(output)?;
    println!(
        "{}: {} meshlets from {} triangles with {name} at {} in {ms:.1} ms -> {}",
        path.display(),
        file.meshlets.len(),
        m.triangle_count(),
        args.limits,
        output.display()
    );
    Ok(())
}

fn check(path: &Path, file: &Path, quiet: bool) -> Result<()> {
    let f = MeshletFile::load(file)?;
    let m = load(path, quiet)?;
    if f.source_vertices as usize != m.vertex_count()
        || f.source_triangles as usize != m.triangle_count()
    {
        bail!(
            "{}: built from a mesh with {} vertices / {} triangles, but {} has {} / {}",
            file.display(),
            f.source_vertices,
            f.source_triangles,
            path.display(),
            m.vertex_count(),
            m.triangle_count()
        );
    }
    if f.fingerprint != m.fingerprint() {
        bail!(
            "{}: built from a different mesh than {} (fingerprint differs)",
            file.display(),
            path.display()
        );
    }
    validate(&m, &f.meshlets, f.limits).with_context(|| format!("{}: invalid", file.display()))?;
    println!(
        "{}: valid — {} meshlets ({}), limits {}, every one of {} triangles exactly once",
        file.display(),
        f.meshlets.len(),
        f.strategy,
        f.limits,
        m.triangle_count()
    );
    Ok(())
}

fn demo(files: &[PathBuf], seed: u64, args: &StrategyArgs, quiet: bool) -> Result<()> {
    let list = strategy::all(&args.options());
    let meshes: Vec<(String, Mesh)> = if files.is_empty() {
        println!(
            "meshletlab demo: all strategies on generated meshes (seed {seed}), limits {}.",
            args.limits
        );
        println!("Pass --mesh FILE to use real meshes instead.\n");
        generate::demo_set(seed)
            .into_iter()
            .map(|g| (g.name.to_string(), g.mesh))
            .collect()
    } else {
        files
            .iter()
            .map(|p| Ok((p.display().to_string(), load(p, quiet)?)))
            .collect::<Result<_>>()?
    };
    let mut totals: Vec<(String, usize)> = list.iter().map(|s| (s.name().to_string(), 0)).collect();
    for (name, m) in &meshes {
        let st = MeshStats::of(m);
        println!("{}", describe(name, &st));
        let rows = evaluate_all(m, &list, args.limits, 3, name, quiet);
        println!("{}\n", metrics_table(&rows));
        fail_on_invalid(&rows, name)?;
        for (t, r) in totals.iter_mut().zip(&rows) {
            t.1 += r.metrics.meshlets;
        }
    }
    let reference = totals
        .iter()
        .find(|t| t.0 == "meshopt")
        .map(|t| t.1)
        .unwrap_or(1)
        .max(1);
    println!(
        "Total meshlets over {} meshes (fewer is better; relative to meshopt):",
        meshes.len()
    );
    for (n, c) in &totals {
        println!("  {n:<16} {c:>8}  {:>6.3}", *c as f64 / reference as f64);
    }
    println!("\nAll outputs validated: every triangle exactly once, limits respected.");
    Ok(())
}

fn parity(path: &Path, limits: Limits, quiet: bool) -> Result<()> {
    let m = load(path, quiet)?;
    let gpu = crate::gpu::Gpu::new()?;
    println!(
        "{}: {} triangles; GPU: {}",
        path.display(),
        m.triangle_count(),
        gpu.describe()
    );
    let pb = spinner(quiet, "running every kernel on the GPU and the CPU".into());
    let checks = crate::gpu::parity::run(&gpu, &m, limits)
        .with_context(|| format!("{}: GPU run failed", path.display()))?
        .checks;
    pb.finish_and_clear();
    let mut failed = 0;
    for c in &checks {
        let verdict = match &c.mismatch {
            None => "identical".to_string(),
            Some(d) => {
                failed += 1;
                format!("DIFFERS: {d}")
            }
        };
        println!(
            "{:<70} CPU {:>8.3} s  GPU {:>8.3} s  {verdict}",
            c.name, c.cpu_seconds, c.gpu_seconds
        );
    }
    if failed > 0 {
        bail!(
            "{}: {failed} of {} GPU kernels differ from their CPU references",
            path.display(),
            checks.len()
        );
    }
    Ok(())
}

struct RenderOpts {
    views: usize,
    seed: u64,
    distance: f32,
    cull: bool,
    descriptor: Format,
    png: Option<PathBuf>,
    validate: bool,
}

fn render(path: &Path, name: &str, o: RenderOpts, args: &StrategyArgs, quiet: bool) -> Result<()> {
    use crate::render::{Camera, Context, Pass, Pipeline, Shading};
    let s = strategy::by_name(name, &args.options())?;
    let m = load(path, quiet)?;
    let ml = s.build(&m, args.limits);
    validate(&m, &ml, args.limits)
        .with_context(|| format!("{}: {name} built invalid meshlets", path.display()))?;
    let ctx = Context::new(o.validate)?;
    let pass = Pass::with_format(&ctx, &m, &ml, o.descriptor)
        .with_context(|| format!("{}: {name}", path.display()))?;
    println!(
        "{}: {} triangles, {name}: {} meshlets, {} descriptors: {:.1} bytes per triangle; device: {}",
        path.display(),
        m.triangle_count(),
        ml.len(),
        o.descriptor,
        pass.device_bytes() as f64 / m.triangle_count().max(1) as f64,
        ctx.name
    );
    let how = Pipeline::Mesh {
        frustum: o.cull,
        cone: o.cull,
        colour_ids: false,
    };
    for (i, cam) in Camera::random_views(&m, o.views, o.seed, o.distance)
        .iter()
        .enumerate()
    {
        let f = pass.render(cam, how, Shading::Lit)?;
        let v = pass.render(cam, Pipeline::Vertex, Shading::Lit)?;
        let pct = |x: u32| 100.0 * x as f64 / ml.len().max(1) as f64;
        let prims = f
            .queries
            .map(|q| format!("  mesh primitives generated {}", q.primitives))
            .unwrap_or_default();
        println!(
            "view {i}: mesh shaders {:8.3} ms  vertex pipeline {:8.3} ms  culled: frustum {:5.1} %  backface {:5.1} %{prims}",
            f.gpu_ns * 1e-6,
            v.gpu_ns * 1e-6,
            pct(f.culled_frustum),
            pct(f.culled_cone)
        );
        if i == 0 {
            if let Some(p) = &o.png {
                let img = pass.render(
                    cam,
                    Pipeline::Mesh {
                        frustum: o.cull,
                        cone: o.cull,
                        colour_ids: true,
                    },
                    Shading::Lit,
                )?;
                crate::render::write_png(
                    p,
                    crate::render::WIDTH,
                    crate::render::HEIGHT,
                    &img.pixels,
                )
                .with_context(|| format!("cannot write {}", p.display()))?;
            }
        }
    }
    if let Some(v) = &ctx.validation {
        let (errors, first) = v.errors();
        if errors > 0 {
            bail!("the validation layer reported {errors} errors, first: {first:#?}");
        }
        println!("validation layer: no errors");
    }
    Ok(())
}

fn subdivide(path: &Path, output: &Path, levels: u32, quiet: bool) -> Result<()> {
    let m = load(path, quiet)?;
    let pb = spinner(quiet, format!("subdividing {} level(s)", levels));
    let s = mesh::subdivide::subdivide(&m, levels)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    pb.set_message(format!("writing {}", output.display()));
    mesh::save_ply(&s, output)?;
    pb.finish_and_clear();
    println!(
        "{} -> {}: {} -> {} triangles, {} -> {} vertices",
        path.display(),
        output.display(),
        m.triangle_count(),
        s.triangle_count(),
        m.vertex_count(),
        s.vertex_count()
    );
    Ok(())
}
