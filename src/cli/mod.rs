//! The `meshletlab` command line: one file per subcommand. Every failure ends as one readable line
//! on stderr and a non-zero exit status.

/// `println!` for command output: a closed stdout (`| head`) ends the text quietly instead of
/// panicking, and the command still writes its files (see [`output::line`]).
macro_rules! say {
    () => {
        $crate::cli::output::line(format_args!(""))
    };
    ($($t:tt)*) => {
        $crate::cli::output::line(format_args!($($t)*))
    };
}

mod bench;
mod build;
mod check;
mod clusters;
mod compress;
mod demo;
mod export;
mod fuzz_worker;
mod lod;
mod lod_check;
mod output;
mod parity;
mod render;
mod stats;
mod subdivide;

use crate::bench::progress::{bar, spinner};
use crate::bench::{evaluate, Evaluation};
use crate::mesh::{self, Mesh, MeshStats};
use crate::meshlet::order::MeshletOrder;
use crate::meshlet::Limits;
use crate::strategy::{self, Options, Strategy};
use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Build, measure and compare meshlets (triangle clusters for GPU mesh shaders).
#[derive(Parser, Debug)]
#[command(name = "meshletlab", version, about, long_about = long_about())]
pub struct Cli {
    /// No progress bars.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// Worker threads for parallel steps (default: all cores). Results do not depend on it.
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// The subcommand to run.
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
    #[arg(long, default_value_t = 0.5, value_parser = non_negative_f32)]
    pub fill_weight: f32,
    /// k-medoids: most assign/update iterations per clustering (kmedoids-flat, kmedoids-paper);
    /// most re-assignment rounds (kmedoids).
    #[arg(long, default_value_t = 16)]
    pub kmedoids_iterations: u32,
    /// k-medoids: stop when the mean medoid shift (in hops) is at most this.
    #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
    pub kmedoids_threshold: f64,
    /// kmedoids: what a growing cluster prefers among equally cheap triangles: `centre` (nearest its
    /// centroid: smaller spheres) or `hops` (fewest hops from its seed: fewer meshlets).
    #[arg(long, default_value = "centre", value_parser = clap::value_parser!(strategy::kmedoids::Grow))]
    pub kmedoids_grow: strategy::kmedoids::Grow,
    /// kmedoids-parallel: triangles per region (each region is clustered on its own, all at
    /// once; smaller regions give more parallel work and a few more meshlets at their borders).
    #[arg(long, default_value_t = strategy::kmedoids::parallel::DEFAULT_REGION_TRIANGLES, value_parser = clap::value_parser!(u32).range(1..))]
    pub kmedoids_regions: u32,
    /// kmedoids-parallel: most rounds of boundary moves (triangles moved to a neighbouring
    /// cluster whose medoid is nearer, within the limits; 0 turns them off).
    #[arg(long, default_value_t = strategy::kmedoids::parallel::DEFAULT_MOVE_ROUNDS)]
    pub kmedoids_moves: u32,
    /// kmedoids-paper: seconds before the remaining splits are done the flat way.
    #[arg(long, default_value_t = 300.0, value_parser = crate::bench::positive::<f64>)]
    pub paper_budget: f64,
    /// Reorder triangles inside each meshlet for vertex reuse, local vertices in first-use order.
    #[arg(long)]
    pub local_order: bool,
    /// Order of meshlets in the collection: built, triangles (most first), vertices (most first).
    #[arg(long, default_value = "built", value_parser = clap::value_parser!(MeshletOrder))]
    pub meshlet_order: MeshletOrder,
}

impl StrategyArgs {
    /// The ids (field names) of these options, read from their definitions, for the modes that
    /// build no meshlets and refuse them.
    fn ids() -> Vec<String> {
        <StrategyArgs as Args>::augment_args(clap::Command::new("strategy"))
            .get_arguments()
            .map(|a| a.get_id().to_string())
            .collect()
    }

    fn options(&self) -> Options {
        Options {
            cone_weight: self.cone_weight,
            cache_size: self.cache_size,
            fill_weight: self.fill_weight,
            kmedoids: self.kmedoids(),
            local_order: self.local_order,
            meshlet_order: self.meshlet_order,
        }
    }
}

impl StrategyArgs {
    /// The k-medoids settings from the options, each method's block from the options it reads.
    fn kmedoids(&self) -> strategy::kmedoids::Config {
        use strategy::kmedoids::{flat, parallel, sequential};
        strategy::kmedoids::Config {
            sequential: sequential::Config {
                max_rounds: self.kmedoids_iterations,
                grow: self.kmedoids_grow,
            },
            parallel: parallel::Config {
                region_triangles: self.kmedoids_regions,
                move_rounds: self.kmedoids_moves,
            },
            flat: flat::Config {
                max_iterations: self.kmedoids_iterations,
                shift_threshold: self.kmedoids_threshold,
                ..Default::default()
            },
            paper: flat::PaperConfig {
                budget: Duration::from_secs_f64(self.paper_budget),
            },
            threading: Default::default(),
        }
    }
}

/// A finite number at least 0 (a weight, a threshold).
fn non_negative(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} is not a finite number >= 0"))
    }
}

/// [`non_negative`] as an f32 (it must also fit one).
fn non_negative_f32(s: &str) -> Result<f32, String> {
    let v = non_negative(s)?;
    if v > f32::MAX as f64 {
        return Err(format!("{v} does not fit an f32"));
    }
    Ok(v as f32)
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
    Stats(stats::StatsArgs),
    /// Build meshlets and write them to a file (format: see `meshletlab::meshlet::io`).
    Build(build::BuildArgs),
    /// Validate a meshlet file written by `build`, or a compressed file written by `compress`
    /// (every meshlet decoded at random access), against its mesh.
    Check(check::CheckArgs),
    /// The whole pipeline in about a minute on generated meshes: every strategy compared, GPU
    /// adjacency and k-medoids beside their CPU references with the parity verdict, and a
    /// mesh-shader render with culling statistics and a meshlet-coloured PNG.
    Demo(demo::DemoArgs),
    /// 1->4 midpoint subdivision (per level), to make multi-million-triangle inputs from real meshes.
    Subdivide(subdivide::SubdivideArgs),
    /// Runs every GPU kernel and its CPU reference on MESH and compares the outputs (exit 1 on any
    /// difference). Uses the default Vulkan adapter: lavapipe on a machine without a GPU.
    Parity(parity::ParityArgs),
    /// Draws MESH's meshlets with task and mesh shaders (VK_EXT_mesh_shader; lavapipe on a machine
    /// without a GPU) from seeded random views, beside the vertex pipeline: per view the GPU time of
    /// both, the meshlets the task shader culled, and a PNG of the first view coloured by meshlet.
    Render(render::RenderArgs),
    /// Writes MESH's meshlets as a binary glTF (.glb) with one flat colour per meshlet (COLOR_0;
    /// vertices split where meshlets meet), so any glTF viewer shows them.
    Export(export::ExportArgs),
    /// Builds the cluster-LOD DAG (Clustered Meshlet Optimizer): level 0 = a strategy's meshlets,
    /// then groups of meshlets merged, simplified to half with shared borders locked, and split again,
    /// level after level; writes the LOD file.
    Lod(lod::LodArgs),
    /// Validates a LOD file against its mesh: level 0 through the validator, limits on every level,
    /// monotonic errors and bounds, and one meshlet per DAG path for random views and every
    /// streaming prefix (exit 1 on any violation).
    LodCheck(lod_check::LodCheckArgs),
    /// Encodes MESH's meshlets in a compressed format (`--format`: meshoptimizer's meshlet codec,
    /// laced wires, or the paper's comparison formats) within a position tolerance, checks every
    /// meshlet decodes back, and writes the file; prints bytes per triangle by part and the
    /// largest error.
    Compress(compress::CompressArgs),
    /// Benchmarks that write results/.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Internal: runs fuzz cases for `bench robustness` in a child process.
    #[command(hide = true)]
    FuzzWorker(fuzz_worker::FuzzWorkerArgs),
}

/// The top-level `--help` text. The strategy and generated-mesh lists are read from their tables
/// (`strategy::Kind::ALL`, `mesh::generate::NAMES`), so a new entry shows up here by itself.
fn long_about() -> String {
    use std::fmt::Write as _;
    let mut s = format!(
        "Build, measure and compare meshlets (triangle clusters for GPU mesh shaders).\n\n\
         Meshes: PLY (ASCII/binary), OBJ, glTF 2.0 (.gltf/.glb), STL (ASCII/binary), each optionally \
         zstd-compressed (.zst); `gen:NAME` generates one instead ({}; the first {} are the stress \
         meshes), or an instanced scene ({}).\n\nStrategies (-s NAME):\n",
        mesh::generate::NAMES.join(", "),
        mesh::generate::STRESS_NAMES.len(),
        mesh::generate::SCENE_NAMES.join(", ")
    );
    for k in strategy::Kind::ALL {
        let _ = writeln!(s, "  {:<17} {}", k.name(), k.summary());
    }
    let _ = write!(
        s,
        "  {:<17} every strategy above but the slow ones ({})\n\n\
         Any of them followed by +refine (e.g. meshopt+refine) refines its output to fewer meshlets \
         (+refine-fast: one cheap round; +refine-max: with simulated annealing, the fewest), or by \
         +partition (e.g. greedy+partition) re-partitions it as `partition` re-partitions meshopt's.\n\n\
         Limits are VERTICES/TRIANGLES per meshlet; default 64/126 (the JCGT paper's).",
        "all",
        strategy::SLOW.join(", ")
    );
    s
}

/// The default folder of real test meshes.
pub fn default_meshes_dir() -> PathBuf {
    std::env::var_os("MESHLETLAB_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("../shared/meshes"))
}

/// A command line that parses but asks for what the command cannot do: an option its mode does
/// not use, or a selection that leaves nothing to run. Reported in clap's form, exit status 2,
/// like any other usage error.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// A [`UsageError`] for `bail!`/`return Err(..)`.
fn usage(msg: impl Into<String>) -> anyhow::Error {
    UsageError(msg.into()).into()
}

/// Whether option `id` (its field name) was given on the command line, not taken by default.
fn given(m: &clap::ArgMatches, id: &str) -> bool {
    matches!(
        m.try_get_raw(id)
            .ok()
            .flatten()
            .and_then(|_| m.value_source(id)),
        Some(clap::parser::ValueSource::CommandLine)
    )
}

/// Refuses, by name, each of `ids` (field names) given on the command line: options the mode
/// `mode` does not use, which would otherwise be silently ignored.
fn refuse_unused(m: &clap::ArgMatches, ids: &[&str], mode: &str) -> Result<()> {
    let unused: Vec<String> = ids
        .iter()
        .filter(|id| given(m, id))
        .map(|id| format!("--{}", id.replace('_', "-")))
        .collect();
    if unused.is_empty() {
        return Ok(());
    }
    Err(usage(format!(
        "{} {} not used with {mode}",
        unused.join(", "),
        if unused.len() == 1 { "is" } else { "are" }
    )))
}

/// Parses arguments and runs the command.
pub fn run(args: impl IntoIterator<Item = std::ffi::OsString>) -> Result<()> {
    use clap::{CommandFactory, FromArgMatches};
    let parsed = Cli::command()
        .try_get_matches_from(args)
        .and_then(|m| Cli::from_arg_matches(&m).map(|c| (c, m)));
    let (cli, matches) = match parsed {
        Ok(c) => c,
        Err(e) if !e.use_stderr() => {
            // --help and --version; a reader that left early (`| head`) is not an error.
            let _ = e.print();
            return Ok(());
        }
        Err(e) => {
            let _ = e.print();
            std::process::exit(2);
        }
    };
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .context("cannot set thread count")?;
    }
    let q = cli.quiet;
    let sub = matches
        .subcommand()
        .map(|(_, m)| m.clone())
        .unwrap_or_default();
    let result = match cli.command {
        Command::Stats(a) => stats::run(a, q),
        Command::Build(a) => build::run(a, q),
        Command::Check(a) => check::run(a, q),
        Command::Demo(a) => demo::run(a, q),
        Command::Subdivide(a) => subdivide::run(a, q),
        Command::Parity(a) => parity::run(a, q),
        Command::Render(a) => render::run(a, &sub, q),
        Command::Export(a) => export::run(a, q),
        Command::Lod(a) => lod::run(a, q),
        Command::LodCheck(a) => lod_check::run(a, q),
        Command::Compress(a) => compress::run(a, q),
        Command::Bench(b) => bench::run(b, q),
        Command::FuzzWorker(a) => fuzz_worker::run(a),
    };
    match result {
        Err(e) if e.is::<UsageError>() => {
            let sub_name = matches.subcommand_name().unwrap_or_default().to_string();
            let mut cmd = Cli::command();
            let cmd = cmd
                .find_subcommand_mut(&sub_name)
                .cloned()
                .unwrap_or(Cli::command());
            let _ = cmd
                .bin_name(format!("meshletlab {sub_name}"))
                .error(clap::error::ErrorKind::ArgumentConflict, e.to_string())
                .print();
            std::process::exit(2);
        }
        r => r,
    }
}

fn load(path: &Path, quiet: bool) -> Result<Mesh> {
    let pb = spinner(quiet, format!("loading {}", path.display()));
    let m = mesh::load(path);
    pb.finish_and_clear();
    Ok(m?)
}

/// [`mesh::load_scene`] behind a spinner; a scene that places each mesh once comes back baked
/// into one mesh, as [`mesh::load`] reads it.
fn load_scene(path: &Path, quiet: bool) -> Result<mesh::Scene> {
    let pb = spinner(quiet, format!("loading {}", path.display()));
    let s = mesh::load_scene(path);
    pb.finish_and_clear();
    let s = s?;
    Ok(if s.is_instanced() { s } else { s.baked() })
}

fn strategies(spec: &str, opts: &Options) -> Result<Vec<Box<dyn Strategy>>> {
    if spec == "all" {
        return Ok(strategy::all(opts));
    }
    spec.split(',')
        .map(|n| strategy::by_name(n.trim(), opts).map_err(Into::into))
        .collect()
}

/// Where meshlets are built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Device {
    /// On the CPU: every strategy.
    Cpu,
    /// On the GPU: the strategies whose every step is a kernel.
    Gpu,
}

/// `--device`, for the commands that build meshlets (`build`, `stats`, `export`).
#[derive(Args, Debug, Clone, Copy)]
pub struct DeviceArgs {
    /// Where to build (the help text lists the GPU strategies).
    #[arg(long, value_enum, default_value = "cpu", help = device_help())]
    pub device: Device,
}

/// `--device`'s help, the GPU strategies read from their table.
fn device_help() -> String {
    format!(
        "Where to build: cpu, or gpu for the strategies whose every step is a kernel ({}); the \
         same meshlets either way. The GPU is the default Vulkan adapter (lavapipe on a machine \
         without a GPU)",
        crate::gpu::build::GPU_STRATEGIES
            .map(|k| k.name())
            .join(", ")
    )
}

/// A GPU to build with each of `names` on, checked before anything is loaded or run (a strategy
/// without a whole GPU path is refused by name); also the milliseconds its creation took.
fn gpu_for(names: &[&str]) -> Result<(crate::gpu::Gpu, f64)> {
    for name in names {
        crate::gpu::build::gpu_kind(name)?;
    }
    let t0 = std::time::Instant::now();
    let gpu = crate::gpu::Gpu::new()?;
    Ok((gpu, t0.elapsed().as_secs_f64() * 1e3))
}

/// [`build_validated`] on the GPU, after a warm-up build that compiles the pipelines: the
/// meshlets, the build's wall time and the setup time (`device_ms` plus the warm-up), in ms.
fn build_validated_on_gpu(
    gpu: &crate::gpu::Gpu,
    device_ms: f64,
    m: &Mesh,
    path: &Path,
    name: &str,
    args: &StrategyArgs,
) -> Result<(crate::meshlet::Meshlets, f64, f64)> {
    let opts = args.options();
    let warm_ms = crate::gpu::build::warm_up(gpu, name, args.limits, &opts)? * 1e3;
    let b = crate::gpu::build::build(gpu, name, m, args.limits, &opts)?;
    crate::meshlet::validate(m, &b.meshlets, args.limits).with_context(|| {
        format!(
            "{}: {name} built invalid meshlets on the GPU",
            path.display()
        )
    })?;
    Ok((b.meshlets, b.seconds * 1e3, device_ms + warm_ms))
}

/// Builds with strategy `name` and validates the result (an invalid build is an error naming the
/// mesh file).
fn build_validated(
    m: &Mesh,
    path: &Path,
    name: &str,
    args: &StrategyArgs,
) -> Result<crate::meshlet::Meshlets> {
    let s = strategy::by_name(name, &args.options())?;
    let ml = s.build(m, args.limits);
    crate::meshlet::validate(m, &ml, args.limits)
        .with_context(|| format!("{}: {name} built invalid meshlets", path.display()))?;
    Ok(ml)
}

fn evaluate_all(
    mesh: &Mesh,
    list: &[Box<dyn Strategy>],
    limits: Limits,
    runs: usize,
    label: &str,
    quiet: bool,
) -> Vec<Evaluation> {
    let pb = bar(quiet, list.len() as u64);
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
        anyhow::bail!(
            "{mesh}: strategy {} produced invalid meshlets: {}",
            bad.strategy,
            bad.invalid.as_deref().unwrap_or("")
        );
    }
    Ok(())
}
