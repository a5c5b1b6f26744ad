//! `meshletlab bench gpu`: each GPU kernel family and the whole k-medoids on the GPU against the
//! CPU reference (one thread and rayon), for the bunny, igea, the dragon and the dragon subdivided
//! to 3.5 M and 14 M triangles; run time against error; the paper's Table 4 beside ours ->
//! results/gpu.md, results/gpu.csv, results/gpu_scaling.svg, results/gpu_time_vs_error.svg.
//!
//! Every GPU result is compared with the CPU's before its time is written: a row is only reported
//! if the outputs are identical.

use super::kmedoids::PAPER_TIMES;
use super::plot::{line_chart, Axes, Series};
use super::table::{
    Align::{Left, Right},
    Style, Table,
};
use super::{create_dir, floor, is_lavapipe, write_file, Common, Tag};
use crate::adjacency::{dual_graph, vertex_triangles};
use crate::gpu::source::MeshSource;
use crate::gpu::{self, timed as secs, Gpu, Profile};
use crate::mesh::{self, subdivide::subdivide, Mesh};
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::kmedoids::{cluster, Clustering, Config as KConfig, Mode};
use crate::strategy::{self, grow};
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;

/// What to run: the arguments of `meshletlab bench gpu`.
#[derive(clap::Args, Clone, Debug)]
pub struct Config {
    /// Mesh folder, output folder, smoke run (every mesh in the folder instead of the bunny, igea
    /// and the dragon, the first one profiled, and no subdivided dragons), quiet.
    #[command(flatten)]
    pub common: Common,
    /// A suffix for the file names, for a run on another device.
    #[command(flatten)]
    pub tag: Tag,
    /// Meshlet limits.
    #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
    pub limits: Limits,
    /// Above this many triangles, skip the GPU k-medoids (rayon still runs).
    #[arg(long, default_value_t = 16_000_000)]
    pub kmedoids_gpu_max: usize,
    /// Above this many triangles, skip the flat method's GPU run (on lavapipe its 14 M-triangle
    /// run alone outlasts the rest of the benchmark; its rayon run stays).
    #[arg(long, default_value_t = 4_000_000)]
    pub flat_gpu_max: usize,
    /// Above this many triangles, skip the one-thread CPU runs and the GPU grower.
    #[arg(long, default_value_t = 4_000_000)]
    pub one_thread_max: usize,
    /// Leave out the subdivided dragons (3.5 M and 14 M triangles).
    #[arg(long)]
    pub quick: bool,
}

impl Config {
    /// Whether the subdivided dragons are left out (asked, or a smoke run).
    pub fn quick(&self) -> bool {
        self.quick || self.common.smoke
    }
}

struct Row {
    mesh: String,
    triangles: usize,
    vertices: usize,
    /// Dual-graph items (edge-adjacent pairs, both ways).
    dual_items: usize,
    adj_cpu: f64,
    adj_gpu: gpu::adjacency::Timing,
    km_cpu1: Option<f64>,
    km_rayon: f64,
    km_gpu: Option<KGpu>,
    /// Per-kernel profile of a second GPU k-medoids run (bunny and the dragon).
    profile: Option<Profile>,
    meshlets: usize,
    iterations: u32,
    grow: Vec<GrowRow>,
    /// The sequential default `kmedoids` (CPU only), the reference for `kmedoids-parallel`.
    seq: Seq,
    /// `kmedoids-parallel`.
    reg: Reg,
    /// The library's GPU builds, per GPU strategy that ran here.
    resident: Vec<Resident>,
}

/// `kmedoids-parallel` on one mesh: CPU one thread and rayon, and the GPU (checked identical).
struct Reg {
    meshlets: usize,
    regions: usize,
    cpu1: Option<f64>,
    rayon: f64,
    /// Wall seconds, upload/kernel/readback, host round trips.
    gpu: Option<(f64, gpu::adjacency::Timing, u64)>,
    /// Per-kernel profile of a second GPU run (the profiled meshes).
    profile: Option<Profile>,
}

/// The CPU step each `kmedoids-parallel` kernel mirrors (regions, growth, moves; the adjacency's,
/// the Morton order's, the prefix sums' and the assembly's are in [`STEPS`]). Read first, so a
/// name two modules share (`place`) takes its regions meaning here.
const REGION_STEPS: &[(&str, &str)] = &[
    ("centre_cells", "regions: packed centroid cells"),
    ("pick", "regions: seeds at the middle of each Morton run"),
    ("clear", "regions: BFS labels reset"),
    ("seed", "regions: BFS sources"),
    ("push", "regions: one BFS level"),
    ("piece_init", "regions: pieces no seed reaches"),
    ("piece_round", "regions: pieces no seed reaches"),
    ("offsets_of", "regions: members sorted by region"),
    ("init", "canonical corners, growth state"),
    (
        "grow_rows",
        "grow, pack, absorb, merge, dissolve (one invocation per region)",
    ),
    (
        "grow",
        "grow, pack, absorb, merge, dissolve (one invocation per region)",
    ),
    ("relabel", "global labels"),
    (
        "medoid",
        "medoids_and_distances (one invocation per cluster)",
    ),
    ("tally", "moves: per-cluster counters"),
    ("count_members", "moves: members, vertices, connectivity"),
    ("candidates", "moves step 1"),
    ("propose", "moves step 2"),
    ("pick_best", "moves step 3"),
    ("accept", "moves step 3"),
    (
        "settle",
        "moves step 4: distances where a cluster took a triangle",
    ),
    (
        "new_medoids",
        "moves step 5: medoids of the changed clusters",
    ),
    ("finish", "moves: objective"),
    ("place", "moves and assembly: members into their slots"),
];

/// One GPU strategy built three ways through `gpu::build`: meshlets read back, left on the
/// device, and (where it can) from a mesh already on the device. Wall seconds each.
struct Resident {
    strategy: &'static str,
    /// `build`: meshlets read back (and its readback seconds).
    read: (f64, f64),
    /// `build_resident`: meshlets and their bounds left on the device.
    resident: f64,
    /// `build_on_device`: from position and index buffers already on the device.
    on_device: Option<f64>,
}

/// Times `gpu::build`'s three entry points for `name` on `m`, checking that each gives the CPU's
/// meshlets `cpu` (read back after the timing).
fn resident_builds(
    g: &Gpu,
    name: &'static str,
    m: &Mesh,
    limits: Limits,
    cpu: &Meshlets,
) -> Result<Resident> {
    let opts = strategy::Options::default();
    let read = gpu::build::build(g, name, m, limits, &opts)?;
    if &read.meshlets != cpu {
        bail!("{name}: GPU build differs from the CPU's");
    }
    // The mesh as an engine holds it: uploaded before the timed builds.
    let positions = g.upload("positions", &m.positions);
    let indices = g.upload("indices", &m.indices);
    let r = gpu::build::build_resident(g, name, m, &positions, limits, &opts)?;
    if &r.meshlets.read(g)? != cpu {
        bail!("{name}: meshlets left on the device differ from the CPU's");
    }
    let on_device = if gpu::build::DEVICE_INPUT_STRATEGIES
        .iter()
        .any(|k| k.name() == name)
    {
        let mesh = gpu::DeviceMesh {
            positions: &positions,
            vertices: m.vertex_count(),
            indices: &indices,
            triangles: m.triangle_count(),
        };
        let d = gpu::build::build_on_device(g, name, mesh, limits, &opts)?;
        if &d.meshlets.read(g)? != cpu {
            bail!("{name}: meshlets built from the device mesh differ from the CPU's");
        }
        Some(d.seconds)
    } else {
        None
    };
    Ok(Resident {
        strategy: name,
        read: (read.seconds, read.timing.readback),
        resident: r.seconds,
        on_device,
    })
}

/// The sequential `kmedoids` on one mesh (CPU only): meshlets, one thread and rayon seconds.
struct Seq {
    meshlets: usize,
    cpu1: Option<f64>,
    rayon: f64,
}

/// A timed GPU k-medoids run.
struct KGpu {
    seconds: f64,
    timing: gpu::adjacency::Timing,
    large: u32,
    /// Host-side counts of the timed run (per-kernel timing off).
    host: Profile,
    updates: u64,
    skipped: u64,
}

/// Meshes whose GPU k-medoids is also run with every kernel timed on its own.
const PROFILED: &[&str] = &["stanford_bunny", "stanford_dragon_vrip"];

/// What each k-medoids kernel does, as the CPU step it mirrors.
const STEPS: &[(&str, &str)] = &[
    ("bbox_reduce", "Morton order: the box of the positions"),
    ("keys", "Morton order: keys"),
    ("hist_count", "Morton order: radix sort"),
    ("scatter", "Morton order: radix sort"),
    ("pick", "seeds: one per run of the Morton order"),
    ("vt_count", "adjacency: vertex -> triangle counts"),
    ("vt_scatter", "adjacency: vertex -> triangle rows"),
    ("vt_sort", "adjacency: sort each row"),
    (
        "dual_count",
        "adjacency: dual-graph row sizes and side flags",
    ),
    ("dual_fill", "adjacency: dual-graph rows"),
    ("block_sums", "prefix sum (every CSR)"),
    ("scan_sums", "prefix sum (every CSR)"),
    ("scan_blocks", "prefix sum (every CSR)"),
    ("clear", "assign: reset labels and distances"),
    ("seed", "assign: medoids at distance 0"),
    ("push", "assign: one BFS level from the frontier"),
    ("clear_counters", "update: reset counters"),
    ("dirty_clear", "update: which clusters changed (cache test)"),
    (
        "medoid_index",
        "update: which clusters changed (cache test)",
    ),
    ("dirty_mark", "update: which clusters changed (cache test)"),
    ("mem_clear", "members CSR"),
    ("mem_count", "members CSR"),
    ("mem_scatter", "members CSR"),
    ("update", "update: all-pairs BFS in each changed cluster"),
    ("mark_clear", "update: sort the new medoids"),
    ("mark", "update: sort the new medoids"),
    (
        "place",
        "update: sort the new medoids; assembly: members into their slots",
    ),
    ("remember", "update: remember each triangle's medoid"),
    ("stats", "split: distinct vertices, farthest member"),
    ("dist_partial", "objective"),
    ("count", "assembly: triangles per cluster"),
    (
        "sort_count",
        "assembly: order, distinct vertices, local corners",
    ),
    ("write", "assembly: vertex lists, meshlet records"),
];

/// One strategy's meshlets on one mesh, for the parallel-grower comparison.
struct GrowRow {
    what: String,
    meshlets: usize,
    tris_per: f64,
    verts_per: f64,
    seconds: f64,
    /// Waves and rounds (parallel grower only).
    depth: Option<(u32, u32)>,
}

impl GrowRow {
    fn new(what: &str, ml: &Meshlets, seconds: f64, depth: Option<(u32, u32)>) -> Self {
        let n = ml.len().max(1) as f64;
        Self {
            what: what.into(),
            meshlets: ml.len(),
            tris_per: ml.triangle_count() as f64 / n,
            verts_per: ml.vertices.len() as f64 / n,
            seconds,
            depth,
        }
    }
}

/// The seed-spacing sweep on the bunny: (spacing, CPU rayon row, GPU seconds).
type Sweep = Vec<(f64, GrowRow, f64)>;

/// Runs the benchmark and writes the results.
pub fn run(cfg: &Config) -> Result<()> {
    let meshes = cfg.common.meshes_dir()?;
    let g = Gpu::new()?;
    let say = |m: String| {
        if !cfg.common.quiet {
            eprintln!("{m}");
        }
    };
    say(format!("GPU: {}", g.describe()));
    warm_up(&g, cfg.limits)?;
    // The bandwidths the physical limits are taken at (64 MiB copied on the GPU, 256 MiB on the
    // host; medians).
    say("measuring memory bandwidth".into());
    let copy = gpu::copy::bandwidth(&g, 64 << 20, 7)?;
    let host_copy = floor::memcpy(256 << 20, 5);
    let inputs = load_inputs(cfg, &meshes)?;
    let one = crate::common::one_thread_pool();
    let mut rows = Vec::new();
    for (name, m) in &inputs {
        let profiled = PROFILED.contains(&name.as_str()) || (cfg.common.smoke && rows.is_empty());
        let row = measure_mesh(cfg, &g, &one, name, m, profiled)?;
        let km_gpu = row
            .km_gpu
            .as_ref()
            .map_or("left out".to_string(), |k| format!("{:.2}s", k.seconds));
        say(format!(
            "{name}: adjacency cpu {:.3}s gpu kernel {:.3}s; kmedoids-flat rayon {:.2}s gpu {km_gpu}",
            row.adj_cpu, row.adj_gpu.kernel, row.km_rayon,
        ));
        rows.push(row);
    }
    let bunny = &inputs[0].1;
    let curve = objective_curve(cfg, &g, bunny)?;
    let sweep = spacing_sweep(cfg, &g, bunny)?;
    let floors = Floors { copy, host_copy };
    write(cfg, &g, &rows, &curve, &sweep, &floors)
}

/// Lavapipe compiles each pipeline with LLVM on first use (seconds per kernel family, then cached
/// on disk): a small mesh through every timed path keeps that out of the tables.
fn warm_up(g: &Gpu, limits: Limits) -> Result<()> {
    let warm = mesh::generate::terrain(24, 1);
    let kc = KConfig::default();
    gpu::adjacency::adjacency(g, &warm)?;
    gpu::kmedoids_flat::cluster(g, &warm, limits, &kc.flat)?;
    gpu::grow::grow(g, &warm, limits, grow::DEFAULT_SPACING)?;
    let source = MeshSource::Host(&warm);
    gpu::kmedoids_parallel::cluster(g, source, limits, &kc.parallel, true)?;
    let warm_positions = g.upload("positions", &warm.positions);
    let opts = strategy::Options::default();
    gpu::build::build_resident(g, "kmedoids-flat", &warm, &warm_positions, limits, &opts)?;
    Ok(())
}

/// The meshes of the run: the bunny, igea and the dragon (every shared mesh in a smoke run), then
/// unless `quick` the dragon subdivided once and twice.
fn load_inputs(cfg: &Config, meshes: &std::path::Path) -> Result<Vec<(String, Mesh)>> {
    let load = |stem: &str| -> Result<Mesh> {
        let p = meshes.join(format!("{stem}.ply.zst"));
        // The error names the file first; what needs it follows.
        mesh::load(&p).map_err(|e| {
            anyhow::anyhow!("{e} (bench gpu runs on the bunny, igea and the dragon of --meshes)")
        })
    };
    let mut inputs: Vec<(String, Mesh)> = Vec::new();
    if cfg.common.smoke {
        for p in super::build::mesh_files(meshes)? {
            inputs.push((super::build::mesh_name(&p), mesh::load(&p)?));
        }
    } else {
        for stem in ["stanford_bunny", "igea", "stanford_dragon_vrip"] {
            inputs.push((stem.into(), load(stem)?));
        }
    }
    if !cfg.quick() {
        let dragon = &inputs[2].1;
        let x4 = subdivide(dragon, 1).map_err(anyhow::Error::msg)?;
        let x16 = subdivide(dragon, 2).map_err(anyhow::Error::msg)?;
        inputs.push(("dragon x4 (subdivided)".into(), x4));
        inputs.push(("dragon x16 (subdivided)".into(), x16));
    }
    Ok(inputs)
}

/// Runs `f` on the pool and, where `t` is within `--one-thread-max`, on `one` too, checking that
/// both give the same meshlets; the pool's result, its seconds and the one-thread seconds.
fn on_both_pools(
    cfg: &Config,
    one: &rayon::ThreadPool,
    what: &str,
    t: usize,
    f: &(dyn Fn() -> Clustering + Sync),
) -> Result<(Clustering, f64, Option<f64>)> {
    let (r, rayon_s) = secs(f);
    let one_s = if t <= cfg.one_thread_max {
        let (one_r, s) = secs(|| one.install(f));
        if one_r.meshlets != r.meshlets {
            bail!("{what} differs on one thread");
        }
        Some(s)
    } else {
        None
    };
    Ok((r, rayon_s, one_s))
}

/// A GPU run again with every kernel timed on its own (its pass boundaries cost a little, so its
/// times are not the table's), checked against the CPU's `labels`.
fn profile_run(
    g: &Gpu,
    what: &str,
    run: &dyn Fn() -> Result<Clustering, gpu::GpuError>,
    labels: &[u32],
) -> Result<Profile> {
    g.time_each_kernel(true);
    let before = g.profile();
    let r = run();
    g.time_each_kernel(false);
    if r?.labels != labels {
        bail!("profiled GPU {what} differs from the CPU's");
    }
    Ok(g.profile().since(&before))
}

/// Every measurement of one mesh: adjacency, growers, the k-medoids methods, the library builds.
fn measure_mesh(
    cfg: &Config,
    g: &Gpu,
    one: &rayon::ThreadPool,
    name: &str,
    m: &Mesh,
    profiled: bool,
) -> Result<Row> {
    let t = m.triangle_count();
    let pb = super::progress::spinner(cfg.common.quiet, format!("{name} ({t} triangles)"));
    let step = |what: &str| pb.set_message(format!("{name} ({t} triangles): {what}"));
    step("adjacency");
    // Adjacency: CPU (serial by design), GPU; identical or no row.
    let ((vt, dual), adj_cpu) = secs(|| {
        let vt = vertex_triangles(m);
        let d = dual_graph(m, &vt);
        (vt, d)
    });
    let (host, adj_gpu) = gpu::adjacency::adjacency(g, m)?;
    if host.vertex_triangles != vt || host.dual != dual {
        bail!("{name}: GPU adjacency differs from the CPU's");
    }
    let dual_items = dual.items.len();
    drop((vt, host));
    step("growers");
    let (grow, grow_meshlets) = growers(g, m, &dual, cfg.limits, t <= cfg.one_thread_max, one)
        .with_context(|| format!("{name}: parallel grower"))?;
    drop(dual);
    step("kmedoids-flat");
    let kc = KConfig::default();
    let run_cpu = |mode| move || cluster(m, cfg.limits, mode, &kc);
    let (cr, km_rayon, km_cpu1) = on_both_pools(
        cfg,
        one,
        &format!("{name}: kmedoids-flat"),
        t,
        &run_cpu(Mode::Flat),
    )?;
    let km_gpu = if t <= cfg.kmedoids_gpu_max.min(cfg.flat_gpu_max) {
        let before = g.profile();
        let r = gpu::kmedoids_flat::cluster(g, m, cfg.limits, &kc.flat)?;
        if r.clustering.labels != cr.labels || r.clustering.meshlets != cr.meshlets {
            bail!("{name}: GPU kmedoids-flat differs from the CPU's");
        }
        Some(KGpu {
            seconds: r.seconds,
            timing: r.timing,
            large: r.large_updates,
            host: g.profile().since(&before),
            updates: r.updates,
            skipped: r.clustering.skipped_updates as u64,
        })
    } else {
        None
    };
    let profile = if km_gpu.is_some() && profiled {
        step("kmedoids-flat, GPU profile");
        let run = || gpu::kmedoids_flat::cluster(g, m, cfg.limits, &kc.flat).map(|r| r.clustering);
        Some(profile_run(g, "kmedoids-flat", &run, &cr.labels).context(name.to_string())?)
    } else {
        None
    };
    step("kmedoids (CPU only)");
    let what = format!("{name}: kmedoids");
    let (seq_r, seq_rayon, seq_cpu1) =
        on_both_pools(cfg, one, &what, t, &run_cpu(Mode::Sequential))?;
    let seq = Seq {
        meshlets: seq_r.meshlets.len(),
        cpu1: seq_cpu1,
        rayon: seq_rayon,
    };
    step("kmedoids-parallel");
    let (reg, reg_meshlets) = measure_parallel(cfg, g, one, name, m, profiled)?;
    step("builds left on the device");
    let mut resident = Vec::new();
    if reg.gpu.is_some() {
        let b = resident_builds(g, "kmedoids-parallel", m, cfg.limits, &reg_meshlets)?;
        resident.push(b);
    }
    if t <= cfg.kmedoids_gpu_max.min(cfg.flat_gpu_max) {
        resident.push(resident_builds(
            g,
            "kmedoids-flat",
            m,
            cfg.limits,
            &cr.meshlets,
        )?);
    }
    if t <= cfg.one_thread_max {
        let b = resident_builds(g, "bsphere-parallel", m, cfg.limits, &grow_meshlets)?;
        resident.push(b);
    }
    pb.finish_and_clear();
    Ok(Row {
        mesh: name.to_string(),
        triangles: t,
        vertices: m.vertex_count(),
        dual_items,
        adj_cpu,
        adj_gpu,
        km_cpu1,
        km_rayon,
        km_gpu,
        profile,
        meshlets: cr.meshlets.len(),
        iterations: cr.iterations,
        grow,
        seq,
        reg,
        resident,
    })
}

/// `kmedoids-parallel` on one mesh: CPU one thread and rayon, the GPU (checked identical) and on
/// the profiled meshes its per-kernel profile; returns the CPU's meshlets too.
fn measure_parallel(
    cfg: &Config,
    g: &Gpu,
    one: &rayon::ThreadPool,
    name: &str,
    m: &Mesh,
    profiled: bool,
) -> Result<(Reg, Meshlets)> {
    let t = m.triangle_count();
    let kc = KConfig::default();
    let what = format!("{name}: kmedoids-parallel");
    let run_cpu = || cluster(m, cfg.limits, Mode::Parallel, &kc);
    let (reg_r, reg_rayon, reg_cpu1) = on_both_pools(cfg, one, &what, t, &run_cpu)?;
    let run_gpu =
        || gpu::kmedoids_parallel::cluster(g, MeshSource::Host(m), cfg.limits, &kc.parallel, true);
    // Its state takes nine words per triangle in one binding: meshes past the adapter's binding
    // size are left out (`-`), as the error says.
    let before = g.profile();
    let reg_run = (t <= cfg.kmedoids_gpu_max).then(run_gpu);
    let trips = g.profile().since(&before).round_trips;
    let (reg_gpu, reg_regions) = match reg_run {
        Some(Ok((r, _))) => {
            if r.clustering.labels != reg_r.labels || r.clustering.meshlets != reg_r.meshlets {
                bail!("{what}: the GPU's differs from the CPU's");
            }
            (Some((r.seconds, r.timing, trips)), r.regions)
        }
        Some(Err(gpu::GpuError::TooLarge { what: w, len, max })) => {
            if !cfg.common.quiet {
                eprintln!("{what}: GPU left out: {w} {len} > {max}");
            }
            (None, 0)
        }
        Some(Err(e)) => return Err(e.into()),
        None => (None, 0),
    };
    let profile = if reg_gpu.is_some() && profiled {
        let run = || run_gpu().map(|r| r.0.clustering);
        Some(profile_run(g, "kmedoids-parallel", &run, &reg_r.labels).context(what)?)
    } else {
        None
    };
    let reg = Reg {
        meshlets: reg_r.meshlets.len(),
        regions: reg_regions,
        cpu1: reg_cpu1,
        rayon: reg_rayon,
        gpu: reg_gpu,
        profile,
    };
    Ok((reg, reg_r.meshlets))
}

/// Run time against error on the bunny: the objective after the initial clustering for
/// iteration caps 0..16, CPU (rayon) and GPU.
fn objective_curve(cfg: &Config, g: &Gpu, bunny: &Mesh) -> Result<Vec<Curve>> {
    let mut curve = Vec::new();
    for it in [0u32, 1, 2, 4, 8, 16] {
        let mut c = KConfig::default();
        c.flat.max_iterations = it;
        let (cpu, cs) = secs(|| cluster(bunny, cfg.limits, Mode::Flat, &c));
        let gr = gpu::kmedoids_flat::cluster(g, bunny, cfg.limits, &c.flat)?;
        if gr.clustering.initial_mean_distance != cpu.initial_mean_distance {
            bail!("bunny, {it} iterations: GPU objective differs from the CPU's");
        }
        curve.push((
            it,
            cpu.initial_mean_distance,
            cpu.initial_seconds,
            cs,
            gr.seconds,
            gr.clustering.initial_seconds,
        ));
    }
    Ok(curve)
}

/// Seed spacing against meshlet count and rounds (the parallel grower's time against error).
fn spacing_sweep(cfg: &Config, g: &Gpu, bunny: &Mesh) -> Result<Sweep> {
    let bunny_dual = dual_graph(bunny, &vertex_triangles(bunny));
    let mut sweep = Sweep::new();
    for spacing in [1.0, 2.0, 4.0, 8.0] {
        let (cpu, cs) = secs(|| grow::grow(bunny, &bunny_dual, cfg.limits, spacing));
        let gr = gpu::grow::grow(g, bunny, cfg.limits, spacing)?;
        if gr.owner != cpu.owner || gr.order != cpu.order {
            bail!("bunny, spacing {spacing}: GPU grower differs from the CPU's");
        }
        sweep.push((
            spacing,
            GrowRow::new("", &cpu.meshlets, cs, Some((cpu.waves, cpu.rounds))),
            gr.seconds,
        ));
    }
    Ok(sweep)
}

/// The measured bandwidths the physical limits are taken at.
struct Floors {
    /// The copy kernel on the adapter.
    copy: gpu::copy::Bandwidth,
    /// Host memcpy, bytes per second: one thread, every rayon thread.
    host_copy: (f64, f64),
}

/// The serial growers, meshoptimizer and the parallel grower (CPU one thread, rayon, GPU; the
/// GPU's result checked identical) on one mesh, and the CPU grower's meshlets (the reference
/// of the resident builds).
fn growers(
    g: &Gpu,
    m: &Mesh,
    dual: &crate::adjacency::Csr,
    limits: Limits,
    small: bool,
    one: &rayon::ThreadPool,
) -> Result<(Vec<GrowRow>, Meshlets)> {
    let mut out = Vec::new();
    for name in ["bsphere", "bsphere-coherent", "meshopt"] {
        let s = strategy::by_name(name, &strategy::Options::default())?;
        let (ml, secs_) = secs(|| s.build(m, limits));
        out.push(GrowRow::new(name, &ml, secs_, None));
    }
    let sp = grow::DEFAULT_SPACING;
    let (cpu, cs) = secs(|| grow::grow(m, dual, limits, sp));
    let depth = Some((cpu.waves, cpu.rounds));
    if small {
        let c1 = secs(|| one.install(|| grow::grow(m, dual, limits, sp))).1;
        out.push(GrowRow::new(
            "bsphere-parallel, CPU 1 thread",
            &cpu.meshlets,
            c1,
            depth,
        ));
    }
    out.push(GrowRow::new(
        "bsphere-parallel, CPU rayon",
        &cpu.meshlets,
        cs,
        depth,
    ));
    if small {
        let gr = gpu::grow::grow(g, m, limits, sp)?;
        if gr.owner != cpu.owner || gr.order != cpu.order || gr.meshlets != cpu.meshlets {
            bail!("GPU parallel grower differs from the CPU's");
        }
        out.push(GrowRow::new(
            "bsphere-parallel, GPU",
            &gr.meshlets,
            gr.seconds,
            depth,
        ));
    }
    Ok((out, cpu.meshlets))
}

type Curve = (u32, f64, f64, f64, f64, f64);

/// Where the GPU k-medoids time goes: host traffic per iteration for every mesh, then kernel time
/// per entry point for the profiled meshes.
fn write_profile(md: &mut String, rows: &[Row]) -> Result<()> {
    writeln!(
        md,
        "### Where the GPU time goes
"
    )?;
    writeln!(md, "Host traffic of the timed runs above: submissions, dispatches and round trips (the host blocking until the GPU is idle, every readback being one) per k-medoids iteration; GPU idle = wall time minus kernel time (host work, launches, transfers).
")?;
    writeln!(md, "| mesh | iterations | submissions / iteration | dispatches / iteration | round trips / iteration | host blocked s | kernel s | GPU idle s |")?;
    writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|")?;
    for r in rows {
        let Some(k) = &r.km_gpu else { continue };
        let it = r.iterations.max(1) as f64;
        writeln!(
            md,
            "| {} | {} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {:.2} |",
            r.mesh,
            r.iterations,
            k.host.submissions as f64 / it,
            k.host.dispatches as f64 / it,
            k.host.round_trips as f64 / it,
            k.host.wait_seconds,
            k.timing.kernel,
            (k.seconds - k.timing.kernel).max(0.0)
        )?;
    }
    let profiled: Vec<KernelColumn> = rows
        .iter()
        .filter_map(|r| {
            r.profile
                .as_ref()
                .map(|p| (r.mesh.as_str(), p, Some(r.iterations)))
        })
        .collect();
    if profiled.is_empty() {
        return Ok(());
    }
    writeln!(md, "
Kernel time per entry point (GPU timestamps around each dispatch, in a second run of the same clustering; adjacency included), largest first on the last mesh:
")?;
    write_kernel_table(md, &profiled, STEPS)
}

/// One mesh's column group of a kernel-time table: its name, profile and, where the table shows
/// time per iteration, its iterations.
type KernelColumn<'a> = (&'a str, &'a Profile, Option<u32>);

/// A row per entry point, largest first on the last mesh; per mesh its dispatches, ms, ms per
/// iteration (where the column carries iterations) and share of the kernel time. `steps` names
/// the CPU step each kernel mirrors.
fn write_kernel_table(
    md: &mut String,
    meshes: &[KernelColumn],
    steps: &[(&str, &str)],
) -> Result<()> {
    let Some(&(_, last, _)) = meshes.last() else {
        return Ok(());
    };
    let mut head = String::from("| kernel | CPU step it mirrors |");
    let mut rule = String::from("|---|---|");
    for &(mesh, _, iterations) in meshes {
        write!(head, " {mesh} dispatches | ms |")?;
        rule.push_str("---:|---:|");
        if iterations.is_some() {
            head.push_str(" ms / iteration |");
            rule.push_str("---:|");
        }
        head.push_str(" share |");
        rule.push_str("---:|");
    }
    writeln!(md, "{head}\n{rule}")?;
    let mut names: Vec<&str> = Vec::new();
    for (_, p, _) in meshes {
        for k in p.per_kernel.keys() {
            if !names.contains(k) {
                names.push(k);
            }
        }
    }
    let time = |n: &str| last.per_kernel.get(n).map_or(0.0, |e| e.1);
    names.sort_by(|a, b| time(b).total_cmp(&time(a)).then(a.cmp(b)));
    for name in names {
        let step = steps
            .iter()
            .find(|(k, _)| *k == name)
            .map_or("", |(_, s)| s);
        let mut line = format!("| `{name}` | {step} |");
        for &(_, p, iterations) in meshes {
            let total: f64 = p.per_kernel.values().map(|e| e.1).sum();
            let (n, s) = p.per_kernel.get(name).copied().unwrap_or((0, 0.0));
            write!(line, " {n} | {:.1} |", s * 1e3)?;
            if let Some(it) = iterations {
                write!(line, " {:.2} |", s * 1e3 / it.max(1) as f64)?;
            }
            write!(line, " {:.1} % |", 100.0 * s / total.max(f64::MIN_POSITIVE))?;
        }
        writeln!(md, "{line}")?;
    }
    writeln!(md)?;
    Ok(())
}

/// Kernel time per entry point of `kmedoids-parallel` on the profiled meshes, largest first on
/// the last; the growth kernel's share is what a CPU adapter cannot spread (one invocation runs
/// a region's sequential growth).
fn write_region_profile(md: &mut String, rows: &[Row]) -> Result<()> {
    let profiled: Vec<KernelColumn> = rows
        .iter()
        .filter_map(|r| r.reg.profile.as_ref().map(|p| (r.mesh.as_str(), p, None)))
        .collect();
    if profiled.is_empty() {
        return Ok(());
    }
    writeln!(md, "Kernel time per entry point of `kmedoids-parallel` (GPU timestamps around each dispatch, in a second run checked against the CPU's labels; adjacency and assembly included), largest first on the last mesh. The growth runs one invocation per region (on a CPU adapter eight regions to a workgroup, side by side in its SIMD rows), so its parallelism is the region count.\n")?;
    let steps: Vec<(&str, &str)> = REGION_STEPS.iter().chain(STEPS).copied().collect();
    write_kernel_table(md, &profiled, &steps)
}

/// The physical limit per kernel on the largest profiled mesh (both methods' profiled runs):
/// writes the section, returns its rows for gpu_floor.csv. `cpu`: the adapter is a CPU (lavapipe).
fn write_floors(
    md: &mut String,
    rows: &[Row],
    f: &Floors,
    cpu: bool,
    csv: &str,
) -> Result<Vec<floor::Row>> {
    let gb = |x: f64| x / 1e9;
    writeln!(
        md,
        "## The physical limit per kernel
"
    )?;
    writeln!(md, "Measured bandwidth (bytes read plus bytes written per second, medians): the copy kernel (`wgsl/copy.wgsl`, {:.0} MiB) on the adapter **{:.1} GB/s**; host `memcpy` of 256 MiB on one thread {:.1} GB/s, on {} threads at once {:.1} GB/s.\n",
        f.copy.bytes as f64 / 2.0 / (1u64 << 20) as f64,
        gb(f.copy.per_second()),
        gb(f.host_copy.0),
        rayon::current_num_threads(),
        gb(f.host_copy.1))?;
    let Some(r) = rows.iter().rev().find(|r| r.profile.is_some()) else {
        writeln!(md, "No run was profiled.\n")?;
        return Ok(Vec::new());
    };
    let sizes = |share: f64| floor::Sizes {
        t: r.triangles as u64,
        v: r.vertices as u64,
        e: r.dual_items as u64,
        update_share: share,
    };
    let flat_share = r.km_gpu.as_ref().map_or(1.0, |k| {
        (k.updates - k.skipped) as f64 / k.updates.max(1) as f64
    });
    let mut out = Vec::new();
    if let Some(p) = &r.profile {
        out.extend(floor::rows("kmedoids-flat", p, &sizes(flat_share), &f.copy));
    }
    writeln!(md, "{} ({} triangles, {} vertices, {} dual items; T, V, E below), the profiled runs above. *Must move*: every array the kernel touches, once, in 32-bit words: the least its job allows. The floor is that traffic at the copy kernel's bandwidth; measured / floor says how far a kernel is from being bandwidth-bound (far above 1: bound by dispatches, dependent loads or divergence instead). The flat method's `update` skips unchanged clusters: its share is the {:.2} of cluster updates that ran. The last column is the same traffic at an H100's 3.35 TB/s: **a projection, not a measurement**{}. Kernels left out (prefix sums over arrays of several lengths, per-cluster bookkeeping) are a few percent of the time. Data: {csv}.\n",
        r.mesh, r.triangles, r.vertices, r.dual_items, flat_share,
        if cpu { " (no GPU was lent to this run)" } else { "" })?;
    writeln!(md, "{}", floor::table().markdown(&out))?;
    let run = "kmedoids-flat";
    let (m, fl, b): (f64, f64, f64) = out
        .iter()
        .filter(|x| x.run == run)
        .fold((0.0, 0.0, 0.0), |a, x| {
            (a.0 + x.seconds, a.1 + x.floor(), a.2 + x.bytes)
        });
    if m > 0.0 {
        writeln!(md, "{run}: these kernels take {:.1} ms against a floor of {:.1} ms ({:.1}x); at an H100's bandwidth the floor would be {:.1} µs (projection).\n",
            m * 1e3, fl * 1e3, m / fl.max(f64::MIN_POSITIVE), b / floor::H100_BYTES_PER_S * 1e6)?;
    }
    Ok(out)
}

/// Adjacency per mesh: gpu.md's first table, and gpu.csv with more digits and the k-medoids
/// times too (gpu.md shows those in its second table).
fn adjacency_table<'a>() -> Table<'a, Row> {
    let s6 = |x: fn(&Row) -> f64| move |r: &Row| format!("{:.6}", x(r));
    let s3 = |x: fn(&Row) -> f64| move |r: &Row| format!("{:.3}", x(r));
    let s4 = |x: Option<f64>| x.map(|x| format!("{x:.4}")).unwrap_or_default();
    Table::new(Style::Compact)
        .col("mesh", Left, |r: &Row| r.mesh.clone())
        .col("triangles", Right, |r| r.triangles.to_string())
        .split(
            "CPU (1 thread) s",
            Right,
            s3(|r| r.adj_cpu),
            "adjacency_cpu_s",
            s6(|r| r.adj_cpu),
        )
        .split(
            "GPU kernel s",
            Right,
            s3(|r| r.adj_gpu.kernel),
            "adjacency_gpu_kernel_s",
            s6(|r| r.adj_gpu.kernel),
        )
        .split(
            "GPU upload s",
            Right,
            s3(|r| r.adj_gpu.upload),
            "adjacency_gpu_upload_s",
            s6(|r| r.adj_gpu.upload),
        )
        .split(
            "GPU readback s",
            Right,
            s3(|r| r.adj_gpu.readback),
            "adjacency_gpu_readback_s",
            s6(|r| r.adj_gpu.readback),
        )
        .md("GPU Mtri/s (kernel)", Right, |r| {
            format!("{:.1}", r.triangles as f64 / r.adj_gpu.kernel / 1e6)
        })
        .md("GPU kernel / CPU", Right, |r| {
            format!("{:.2}x", r.adj_gpu.kernel / r.adj_cpu)
        })
        .csv_only("kmedoids_cpu1_s", move |r| s4(r.km_cpu1))
        .csv_only("kmedoids_rayon_s", |r| format!("{:.4}", r.km_rayon))
        .csv_only("kmedoids_gpu_s", move |r| {
            s4(r.km_gpu.as_ref().map(|x| x.seconds))
        })
        .csv_only("kmedoids_gpu_kernel_s", move |r| {
            s4(r.km_gpu.as_ref().map(|x| x.timing.kernel))
        })
        .csv_only("meshlets", |r| r.meshlets.to_string())
        .csv_only("iterations", |r| r.iterations.to_string())
        .csv_only("sequential_meshlets", |r| r.seq.meshlets.to_string())
        .csv_only("sequential_cpu1_s", move |r| s4(r.seq.cpu1))
        .csv_only("sequential_rayon_s", |r| format!("{:.4}", r.seq.rayon))
        .csv_only("parallel_meshlets", |r| r.reg.meshlets.to_string())
        .csv_only("parallel_cpu1_s", move |r| s4(r.reg.cpu1))
        .csv_only("parallel_rayon_s", |r| format!("{:.4}", r.reg.rayon))
        .csv_only("parallel_gpu_s", move |r| s4(r.reg.gpu.map(|x| x.0)))
        .csv_only("parallel_gpu_kernel_s", move |r| {
            s4(r.reg.gpu.map(|x| x.1.kernel))
        })
}

/// A cell: `x` formatted, or "skipped" where the run was left out.
fn opt(x: Option<f64>, f: &dyn Fn(f64) -> String) -> String {
    x.map(f).unwrap_or_else(|| "skipped".into())
}

/// Writes gpu.md, gpu.csv, gpu_floor.csv and the three plots.
fn write(
    cfg: &Config,
    g: &Gpu,
    rows: &[Row],
    curve: &[Curve],
    sweep: &Sweep,
    floors: &Floors,
) -> Result<()> {
    create_dir(&cfg.common.out)?;
    let mut md = String::new();
    let quick = if cfg.quick && !cfg.common.smoke {
        " --quick"
    } else {
        ""
    };
    let command = format!("meshletlab bench gpu{quick}{}", cfg.tag.flag());
    super::write_header(
        &mut md,
        "GPU kernels against their CPU references",
        &command,
        "",
        cfg.common.smoke_out(),
    );
    writeln!(md, "GPU adapter: **{}**{}. Every GPU output below was compared with the CPU reference and is identical (adjacency CSR arrays; k-medoids labels and meshlets; parallel-grower claims, orders and meshlets); a difference aborts the benchmark.\n", g.describe(), if g.timestamps { "; kernel times from GPU timestamp queries" } else { "; no timestamp queries: kernel times are wall time" })?;
    if is_lavapipe(&g.info.name) {
        writeln!(md, "Lavapipe is itself a CPU renderer on this machine's cores: a GPU/CPU ratio here compares LLVM-compiled compute shaders with native Rust on the same {} cores, not a GPU with a CPU.\n", std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1))?;
    }
    write_flat(&mut md, cfg, rows)?;
    write_sequential_and_parallel(&mut md, rows)?;
    write_region_profile(&mut md, rows)?;
    write_resident(&mut md, rows)?;
    write_profile(&mut md, rows)?;
    let floor_rows = write_floors(
        &mut md,
        rows,
        floors,
        g.is_cpu(),
        &cfg.tag.name("gpu_floor.csv"),
    )?;
    write_paper(&mut md, rows)?;
    write_curve_and_growers(&mut md, rows, curve, sweep)?;
    writeln!(
        md,
        "\n![scaling]({})\n\n![time vs error]({})\n\n![grower]({})",
        cfg.tag.name("gpu_scaling.svg"),
        cfg.tag.name("gpu_time_vs_error.svg"),
        cfg.tag.name("gpu_grower_sweep.svg")
    )?;
    write_file(cfg.common.out.join(cfg.tag.name("gpu.md")), md)?;
    write_file(
        cfg.common.out.join(cfg.tag.name("gpu.csv")),
        adjacency_table().csv(rows),
    )?;
    write_file(
        cfg.common.out.join(cfg.tag.name("gpu_floor.csv")),
        floor::table().csv(&floor_rows),
    )?;
    plot(cfg, g, rows, curve, sweep)
}

/// The adjacency and `kmedoids-flat` tables.
fn write_flat(md: &mut String, cfg: &Config, rows: &[Row]) -> Result<()> {
    writeln!(md, "## Adjacency (vertex -> triangle CSR + dual graph)\n")?;
    writeln!(md, "{}", adjacency_table().markdown(rows))?;
    writeln!(md, "\nTarget (set for lavapipe): >= 20 M triangles/s.\n")?;
    writeln!(
        md,
        "## k-medoids-flat (fast mode, {}/{}), whole run including adjacency\n",
        cfg.limits.max_vertices, cfg.limits.max_triangles
    )?;
    writeln!(md, "| mesh | triangles | meshlets | iterations | CPU 1 thread s | CPU rayon s | GPU s | GPU kernel s | GPU / rayon | cluster updates run / skipped | one-thread updates |")?;
    writeln!(
        md,
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for r in rows {
        let k = r.km_gpu.as_ref();
        writeln!(
            md,
            "| {} | {} | {} | {} | {} | {:.2} | {} | {} | {} | {} | {} |",
            r.mesh,
            r.triangles,
            r.meshlets,
            r.iterations,
            opt(r.km_cpu1, &|x| format!("{x:.2}")),
            r.km_rayon,
            opt(k.map(|k| k.seconds), &|x| format!("{x:.2}")),
            opt(k.map(|k| k.timing.kernel), &|x| format!("{x:.2}")),
            opt(k.map(|k| k.seconds / r.km_rayon), &|x| format!("{x:.2}x")),
            k.map(|k| format!("{} / {}", k.updates - k.skipped, k.skipped))
                .unwrap_or_else(|| "-".into()),
            k.map(|k| k.large.to_string()).unwrap_or_else(|| "-".into())
        )?;
    }
    writeln!(md, "\n\"skipped\": above {} triangles the one-thread CPU runs (and the GPU grower) are left out (`--one-thread-max`), above {} the flat method's GPU run (`--flat-gpu-max`: on lavapipe its 14 M-triangle run alone outlasts the rest of the benchmark), above {} every GPU k-medoids (`--kmedoids-gpu-max`), to keep the benchmark short; rayon runs on every mesh. Targets: GPU / rayon <= 1.0. A cluster update is skipped when its members are those it had at the last update (the CPU's cache, the same test on the GPU).\n", cfg.one_thread_max, cfg.flat_gpu_max.min(cfg.kmedoids_gpu_max), cfg.kmedoids_gpu_max)?;
    Ok(())
}

/// The sequential `kmedoids` (CPU only) and `kmedoids-parallel` tables.
fn write_sequential_and_parallel(md: &mut String, rows: &[Row]) -> Result<()> {
    writeln!(
        md,
        "## `kmedoids` (the sequential default, CPU only), whole run including adjacency\n"
    )?;
    writeln!(md, "The reference for `kmedoids-parallel` below: clusters grown one at a time to the limits (src/strategy/kmedoids/sequential.rs). It has no GPU path: its growth and merges are sequential. One thread checked identical to the pool.\n")?;
    writeln!(
        md,
        "| mesh | triangles | meshlets | CPU 1 thread s | CPU rayon s | 1 thread / rayon |"
    )?;
    writeln!(md, "|---|---:|---:|---:|---:|---:|")?;
    for r in rows {
        let c = &r.seq;
        writeln!(
            md,
            "| {} | {} | {} | {} | {:.2} | {} |",
            r.mesh,
            r.triangles,
            c.meshlets,
            opt(c.cpu1, &|x| format!("{x:.2}")),
            c.rayon,
            opt(c.cpu1.map(|x| x / c.rayon), &|x| format!("{x:.2}")),
        )?;
    }
    writeln!(md)?;
    writeln!(md, "## `kmedoids-parallel`: every step on the GPU\n")?;
    writeln!(md, "The region-parallel k-medoids whose per-region growth is a kernel (src/strategy/kmedoids/parallel/, wgsl/kmedoids_parallel.wgsl): one invocation per region grows, packs, absorbs pockets and merges its clusters, then dissolves its smallest across their neighbours; one per cluster finds the medoid; two rounds of boundary moves (wgsl/kmedoids_parallel_moves.wgsl: per-triangle maps and per-cluster atomics, then the medoid of each changed cluster again) are its medoid iteration, in the same submission; the assembly is `wgsl/assemble.wgsl`. The regions are kernels too (wgsl/coarse.wgsl with the Morton sort and the BFS): nothing a kernel reads comes back to the host, only control words (the box, the seeds, frontier sizes, one count per region, one medoid per cluster, the moves' counters); `round trips` counts the host's waits on the device in the whole run, the final readbacks included. The GPU run is checked identical to the CPU's (labels and meshlets); one thread checked identical to the pool. GPU wall time includes the adjacency kernels, uploads and readbacks of labels, distances and meshlets; pipeline compilation is warmed up before. `-`: left out, its state (nine words per triangle in one binding) past the adapter's binding size.\n")?;
    writeln!(
        md,
        "| mesh | triangles | regions | meshlets | CPU 1 thread s | CPU rayon s | GPU s | upload s | kernel s | readback s | round trips | GPU / rayon | meshlets / kmedoids |"
    )?;
    writeln!(
        md,
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for r in rows {
        let g = &r.reg;
        writeln!(
            md,
            "| {} | {} | {} | {} | {} | {:.3} | {} | {} | {} | {} | {} | {} | {:.3} |",
            r.mesh,
            r.triangles,
            opt((g.regions > 0).then_some(g.regions as f64), &|x| format!(
                "{x}"
            )),
            g.meshlets,
            opt(g.cpu1, &|x| format!("{x:.3}")),
            g.rayon,
            opt(g.gpu.map(|x| x.0), &|x| format!("{x:.3}")),
            opt(g.gpu.map(|x| x.1.upload), &|x| format!("{x:.3}")),
            opt(g.gpu.map(|x| x.1.kernel), &|x| format!("{x:.3}")),
            opt(g.gpu.map(|x| x.1.readback), &|x| format!("{x:.3}")),
            opt(g.gpu.map(|x| x.2 as f64), &|x| format!("{x}")),
            opt(g.gpu.map(|x| x.0 / g.rayon), &|x| format!("{x:.2}x")),
            g.meshlets as f64 / r.seq.meshlets as f64,
        )?;
    }
    writeln!(md)?;
    Ok(())
}

/// The library's GPU builds.
fn write_resident(md: &mut String, rows: &[Row]) -> Result<()> {
    writeln!(
        md,
        "## Meshlets left on the device (the library's GPU builds)\n"
    )?;
    writeln!(md, "Wall seconds of `gpu::build`'s entry points, each checked equal to the CPU build: `build` reads the meshlets back (the `--device gpu` path; its readback apart), `build_resident` leaves them and their culling bounds (sphere and cone, the split task layout) in device buffers (assembled by `wgsl/assemble.wgsl`), `build_on_device` also takes the mesh from position and index buffers already on the device (`kmedoids-flat` and `kmedoids-parallel`: seeds and regions from kernels; `bsphere-parallel` quantises on the host, hence `-`). Device creation and pipeline compilation are not in these times (a warm-up build runs first).\n")?;
    writeln!(md, "| mesh | triangles | strategy | build s | of which readback s | build_resident s | build_on_device s |")?;
    writeln!(md, "|---|---:|---|---:|---:|---:|---:|")?;
    for r in rows {
        for b in &r.resident {
            writeln!(
                md,
                "| {} | {} | `{}` | {:.3} | {:.3} | {:.3} | {} |",
                r.mesh,
                r.triangles,
                b.strategy,
                b.read.0,
                b.read.1,
                b.resident,
                b.on_device.map_or("-".into(), |x| format!("{x:.3}")),
            )?;
        }
    }
    writeln!(md)?;
    Ok(())
}

/// Our times beside the paper's Table 4.
fn write_paper(md: &mut String, rows: &[Row]) -> Result<()> {
    writeln!(
        md,
        "### Beside the paper's Table 4 (their k-medoids, their machine)\n"
    )?;
    writeln!(
        md,
        "| paper model | triangles | paper s | ours: nearest mesh | CPU rayon s | GPU s |"
    )?;
    writeln!(md, "|---|---:|---:|---|---:|---:|")?;
    for &(model, tris, s) in PAPER_TIMES {
        let near = rows
            .iter()
            .min_by_key(|r| (r.triangles as i64 - tris as i64).unsigned_abs())
            .context("no rows")?;
        writeln!(
            md,
            "| {model} | {tris} | {s:.1} | {} ({} triangles) | {:.2} | {} |",
            near.mesh,
            near.triangles,
            near.km_rayon,
            opt(near.km_gpu.as_ref().map(|k| k.seconds), &|x| format!(
                "{x:.2}"
            ))
        )?;
    }
    Ok(())
}

/// Run time against error on the bunny, and the parallel grower against the serial ones.
fn write_curve_and_growers(
    md: &mut String,
    rows: &[Row],
    curve: &[Curve],
    sweep: &Sweep,
) -> Result<()> {
    writeln!(md, "\n## Run time against error (bunny)\n")?;
    writeln!(md, "The k-medoids objective (mean hop distance to the medoid after the initial clustering) for each iteration cap; GPU and CPU reach the same objective at every cap (checked).\n")?;
    writeln!(md, "| max iterations | objective (hops) | CPU rayon s (initial clustering) | CPU rayon s (whole run) | GPU s (initial clustering) | GPU s (whole run) |")?;
    writeln!(md, "|---:|---:|---:|---:|---:|---:|")?;
    for &(it, obj, ci, cw, gw, gi) in curve {
        writeln!(
            md,
            "| {it} | {obj:.4} | {ci:.3} | {cw:.3} | {gi:.3} | {gw:.3} |"
        )?;
    }
    writeln!(
        md,
        "\n## Parallel clustering: bsphere-parallel against the serial growers and meshoptimizer\n"
    )?;
    writeln!(md, "Many meshlets grow at once (grid seeds, one GPU workgroup per meshlet scoring its border by the bsphere rule, conflicts by `atomicMin` claims; see `src/strategy/grow.rs`). GPU and CPU give identical claims, orders and meshlets (checked). Seed spacing {}. Waves and rounds are the parallel depth: every round is two dispatches over all meshlets of the wave.\n", grow::DEFAULT_SPACING)?;
    writeln!(md, "| mesh | strategy | meshlets | triangles/meshlet | vertices/meshlet | waves / rounds | s |")?;
    writeln!(md, "|---|---|---:|---:|---:|---:|---:|")?;
    for r in rows {
        for gr in &r.grow {
            writeln!(
                md,
                "| {} | {} | {} | {:.1} | {:.1} | {} | {:.3} |",
                r.mesh,
                gr.what,
                gr.meshlets,
                gr.tris_per,
                gr.verts_per,
                gr.depth
                    .map(|(w, k)| format!("{w} / {k}"))
                    .unwrap_or_else(|| "-".into()),
                gr.seconds
            )?;
        }
    }
    writeln!(
        md,
        "\n### Seed spacing on the bunny: meshlet count against parallel depth\n"
    )?;
    writeln!(md, "| spacing (meshlets per cell) | meshlets | triangles/meshlet | waves | rounds | CPU rayon s | GPU s |")?;
    writeln!(md, "|---:|---:|---:|---:|---:|---:|---:|")?;
    for (sp, r, gs) in sweep {
        let (w, k) = r.depth.unwrap_or_default();
        writeln!(
            md,
            "| {sp} | {} | {:.1} | {w} | {k} | {:.3} | {gs:.3} |",
            r.meshlets, r.tris_per, r.seconds
        )?;
    }
    Ok(())
}

/// gpu_scaling.svg, gpu_time_vs_error.svg and gpu_grower_sweep.svg.
fn plot(cfg: &Config, g: &Gpu, rows: &[Row], curve: &[Curve], sweep: &Sweep) -> Result<()> {
    let pts = |f: &dyn Fn(&Row) -> Option<f64>| {
        rows.iter()
            .filter_map(|r| f(r).map(|y| (r.triangles as f64, y)))
            .collect::<Vec<_>>()
    };
    line_chart(
        &cfg.common.out.join(cfg.tag.name("gpu_scaling.svg")),
        "k-medoids and adjacency run time against mesh size",
        "triangles",
        "seconds",
        &[
            Series {
                label: "kmedoids-flat CPU 1 thread".into(),
                points: pts(&|r| r.km_cpu1),
            },
            Series {
                label: "kmedoids-flat CPU rayon".into(),
                points: pts(&|r| Some(r.km_rayon)),
            },
            Series {
                label: format!("kmedoids-flat GPU ({})", g.info.name),
                points: pts(&|r| r.km_gpu.as_ref().map(|k| k.seconds)),
            },
            Series {
                label: "kmedoids CPU 1 thread".into(),
                points: pts(&|r| r.seq.cpu1),
            },
            Series {
                label: "kmedoids CPU rayon".into(),
                points: pts(&|r| Some(r.seq.rayon)),
            },
            Series {
                label: "kmedoids-parallel CPU 1 thread".into(),
                points: pts(&|r| r.reg.cpu1),
            },
            Series {
                label: "kmedoids-parallel CPU rayon".into(),
                points: pts(&|r| Some(r.reg.rayon)),
            },
            Series {
                label: format!("kmedoids-parallel GPU ({})", g.info.name),
                points: pts(&|r| r.reg.gpu.map(|x| x.0)),
            },
            Series {
                label: "adjacency CPU".into(),
                points: pts(&|r| Some(r.adj_cpu)),
            },
            Series {
                label: "adjacency GPU kernel".into(),
                points: pts(&|r| Some(r.adj_gpu.kernel)),
            },
        ],
        Axes {
            log_x: true,
            log_y: true,
            ..Axes::default()
        },
    )?;
    line_chart(
        &cfg.common.out.join(cfg.tag.name("gpu_time_vs_error.svg")),
        "bunny: k-medoids objective against run time (iteration caps 0..16)",
        "seconds (initial clustering)",
        "mean hops to medoid",
        &[
            Series {
                label: "CPU rayon".into(),
                points: curve.iter().map(|c| (c.2, c.1)).collect(),
            },
            Series {
                label: format!("GPU ({})", g.info.name),
                points: curve.iter().map(|c| (c.5, c.1)).collect(),
            },
        ],
        Axes::default(),
    )?;
    line_chart(
        &cfg.common.out.join(cfg.tag.name("gpu_grower_sweep.svg")),
        "bunny: bsphere-parallel meshlets against rounds (seed spacing 1, 2, 4, 8)",
        "growth rounds (parallel depth)",
        "meshlets",
        &[Series {
            label: "bsphere-parallel".into(),
            points: sweep
                .iter()
                .map(|(_, r, _)| (r.depth.unwrap_or_default().1 as f64, r.meshlets as f64))
                .collect(),
        }],
        Axes::default(),
    )?;
    Ok(())
}
