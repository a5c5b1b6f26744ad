//! `meshletlab bench lod`: our cluster-LOD DAG beside meshoptimizer 1.3's `clod_build`
//! (`clod_default_config(128)`) on every shared mesh -> results/lod.md, lod.csv, lod_curve.csv and
//! plots.
//!
//! Per mesh: build time (ours on 1 and 2 threads at 64/126 and at clod's 128/128, clod on its one
//! thread; median of interleaved runs), levels, roots, stuck groups, meshlets and triangles per
//! level, the per-level reduction, all levels over the source, triangles per meshlet and
//! monotonicity violations. Then the run-time-against-error curve: at a 1-pixel threshold and
//! camera distances of 1.5 to 48 bounding radii, the triangles each DAG selects (LOD rule only,
//! the same selection code for both, so the DAGs are compared and not the culling) and the frame
//! time of the LOD task shader drawing that cut with culling. clod's output is converted to the
//! CMO's per-meshlet data (own bounds and error = the group that produced the cluster, parent =
//! the group it is in) and drawn by the same task shader. Also: which level-0 strategy makes the
//! best DAG (fewest triangles at equal error), and the dragon subdivided to 14 M triangles.

use super::build::{mesh_files, mesh_name};
use super::plot::{line_chart, Axes, Series};
use super::table::{
    Align::{Left, Right},
    Style, Table,
};
use super::{create_dir, is_lavapipe, median, write_file, write_header, Common, Tag};
use crate::common::one_thread_pool;
use crate::lod::flat::{self, Flat};
use crate::lod::{self, Grouping, Level, LodInfo, NO_GROUP};
use crate::mesh::{self, Mesh};
use crate::meshlet::bounds::Sphere;
use crate::meshlet::{Limits, Meshlet, Meshlets};
use crate::render::{Camera, Context, Pass, Pipeline, RenderError, Shading};
use crate::strategy::{self, Options};
use anyhow::Result;
use indicatif::ProgressBar;
use std::fmt::Write as _;
use std::time::Instant;

/// What to run: the arguments of `meshletlab bench lod`.
#[derive(clap::Args, Clone, Debug)]
pub struct Config {
    /// Mesh folder, output folder, smoke run (one run, two selection views, at most one render
    /// view, no 14 M dragon), quiet.
    #[command(flatten)]
    pub common: Common,
    /// A suffix for the file names, for a run on another device.
    #[command(flatten)]
    pub tag: Tag,
    /// Interleaved build runs per configuration (median reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
    /// Random directions per camera distance for the triangle counts.
    #[arg(long, default_value_t = 16, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub select_views: usize,
    /// Views per camera distance for frame times (0: do not render).
    #[arg(long, default_value_t = 3)]
    pub render_views: usize,
    /// LOD threshold in pixels.
    #[arg(long, default_value_t = 1.0, value_parser = super::positive::<f32>)]
    pub threshold: f32,
    /// Level-0 strategies to compare (comma-separated).
    #[arg(short, long, value_delimiter = ',', value_parser = super::strategy_name, default_values_t = DEFAULT_STRATEGIES.iter().map(|s| s.to_string()))]
    pub strategy: Vec<String>,
    /// Largest mesh (triangles) of the level-0 strategy comparison.
    #[arg(long, default_value_t = 400_000)]
    pub strategy_max_triangles: usize,
    /// Leave out the dragon subdivided to 14 M triangles.
    #[arg(long)]
    pub quick: bool,
    /// Our DAG: target meshlets per group.
    #[arg(long, default_value_t = lod::Config::default().group_size as u32, value_parser = clap::value_parser!(u32).range(2..=64))]
    pub group_size: u32,
    /// Our DAG: permissive simplification (as clod).
    #[arg(long)]
    pub permissive: bool,
    /// Camera distances in bounding radii (not an argument: [`DISTANCES`]).
    #[arg(skip = DISTANCES.to_vec())]
    pub distances: Vec<f32>,
}

impl Config {
    /// Interleaved build runs per configuration: one in a smoke run.
    pub fn runs(&self) -> usize {
        self.common.or_smoke(self.runs as usize, 1)
    }

    /// Views per distance for the triangle counts: two in a smoke run.
    pub fn select_views(&self) -> usize {
        self.common.or_smoke(self.select_views, 2)
    }

    /// Views per distance for frame times (0: no rendering; at most one in a smoke run).
    pub fn render_views(&self) -> usize {
        self.common
            .or_smoke(self.render_views, self.render_views.min(1))
    }

    /// Whether the 14 M-triangle dragon is left out (asked, or a smoke run).
    pub fn quick(&self) -> bool {
        self.quick || self.common.smoke
    }

    /// Our DAG's build settings.
    pub fn lod(&self) -> lod::Config {
        lod::Config {
            group_size: self.group_size as usize,
            permissive: self.permissive,
            ..Default::default()
        }
    }
}

/// The default camera distances (bounding radii): 1.5 to 48 in steps of sqrt(2).
pub const DISTANCES: &[f32] = &[
    1.5, 2.12, 3.0, 4.24, 6.0, 8.49, 12.0, 16.97, 24.0, 33.94, 48.0,
];

/// Level-0 strategies of the DAG comparison.
pub const DEFAULT_STRATEGIES: &[&str] = &[
    "meshopt",
    "meshopt-spatial",
    "bsphere-parallel",
    "greedy",
    "kmedoids",
];

/// One built DAG, ours or clod's, in the CMO's per-meshlet form.
pub struct Dag {
    /// Label ("ours 64/126", "clod 128").
    pub label: String,
    /// Levels, level 0 (the source's clusters) first.
    pub levels: Vec<Level>,
    /// Stuck groups (ours) or groups clod could not simplify below its threshold (not counting
    /// the final one).
    pub stuck: usize,
    /// Median build time on one thread, seconds.
    pub seconds_1t: f64,
    /// Median build time on two threads (ours only).
    pub seconds_2t: Option<f64>,
}

impl Dag {
    /// Triangles per level.
    pub fn level_triangles(&self) -> Vec<usize> {
        self.levels.iter().map(lod::level_triangles).collect()
    }
    /// Meshlets without a parent.
    pub fn roots(&self) -> usize {
        self.levels
            .iter()
            .flat_map(|l| &l.info)
            .filter(|i| i.parent_error == f32::INFINITY)
            .count()
    }
    /// Meshlets whose parent error is below their own or whose parent sphere does not enclose
    /// their own (in f64, no margin): what makes a per-meshlet cut inconsistent.
    pub fn monotonic_violations(&self) -> usize {
        self.levels
            .iter()
            .flat_map(|l| &l.info)
            .filter(|i| i.parent_error != f32::INFINITY)
            .filter(|i| {
                let c = |s: &Sphere| glam::DVec3::from_array(s.center.map(f64::from));
                let d = (c(&i.parent_bounds) - c(&i.bounds)).length();
                i.parent_error < i.error
                    || d + i.bounds.radius as f64 > i.parent_bounds.radius as f64 * (1.0 + 1e-6)
            })
            .count()
    }
}

/// The two-thread pool our builds are timed on beside [`one_thread_pool`].
fn two_thread_pool() -> Result<rayon::ThreadPool> {
    Ok(rayon::ThreadPoolBuilder::new().num_threads(2).build()?)
}

/// Builds our DAG with `strategy` at `limits` in `pool`; (DAG levels, stuck groups, seconds).
fn ours(
    mesh: &Mesh,
    strategy: &str,
    limits: Limits,
    pool: &rayon::ThreadPool,
    lod_cfg: &lod::Config,
) -> Result<(Vec<Level>, usize, f64)> {
    let s = strategy::by_name(strategy, &Options::default())?;
    let t = Instant::now();
    let dag = pool.install(|| lod::build(mesh, s.as_ref(), limits, lod_cfg));
    let secs = t.elapsed().as_secs_f64();
    let stuck = dag.stuck_groups();
    Ok((dag.levels, stuck, secs))
}

/// One cluster as clod emits it, kept until the groups are known.
struct ClodOut {
    depth: usize,
    group: u32,
    own: (Sphere, f32),
    parent: (Sphere, f32),
    indices: Vec<u32>,
}

/// Runs meshoptimizer's `clod_build(clod_default_config(max_triangles))` and converts its output
/// to levels (group depth = level of its member clusters); (levels, terminal groups before the
/// last level, seconds of `clod_build` itself).
pub fn clod(mesh: &Mesh, max_triangles: usize) -> (Vec<Level>, usize, f64) {
    let adapter = meshopt::VertexDataAdapter::new(mesh.position_bytes(), 12, 0)
        .expect("stride 12 over f32x3 positions is valid");
    let cm = meshopt::ClodMesh::new(&mesh.indices, &adapter);
    let config = meshopt::clod_default_config(max_triangles);
    // Group simplified bounds, by group id (the callback's return value).
    let mut groups: Vec<(usize, meshopt::ClodBounds)> = Vec::new();
    let mut raw: Vec<(usize, u32, i32, meshopt::ClodBounds, Vec<u32>)> = Vec::new();
    let t = Instant::now();
    meshopt::clod_build(config, &cm, |g, clusters| {
        let id = groups.len() as u32;
        groups.push((g.depth.max(0) as usize, g.simplified));
        for c in clusters {
            raw.push((
                g.depth.max(0) as usize,
                id,
                c.refined,
                c.bounds,
                c.indices.to_vec(),
            ));
        }
        id as i32
    });
    let secs = t.elapsed().as_secs_f64();
    let sphere = |b: &meshopt::ClodBounds| Sphere {
        center: b.center,
        radius: b.radius,
    };
    let err = |e: f32| if e >= f32::MAX { f32::INFINITY } else { e };
    let outs: Vec<ClodOut> = raw
        .into_iter()
        .map(|(depth, group, refined, bounds, indices)| {
            let parent = &groups[group as usize].1;
            let own = if refined < 0 {
                (sphere(&bounds), 0.0)
            } else {
                let g = &groups[refined as usize].1;
                (sphere(g), err(g.error))
            };
            ClodOut {
                depth,
                group,
                own,
                parent: (sphere(parent), err(parent.error)),
                indices,
            }
        })
        .collect();
    let depth = outs.iter().map(|o| o.depth).max().unwrap_or(0);
    let mut levels: Vec<Level> = (0..=depth)
        .map(|_| Level {
            meshlets: Meshlets::default(),
            info: Vec::new(),
        })
        .collect();
    for o in &outs {
        let l = &mut levels[o.depth];
        let (vertices, triangles) = meshopt::clod_local_indices(&o.indices);
        l.meshlets.meshlets.push(Meshlet {
            vertex_offset: l.meshlets.vertices.len() as u32,
            triangle_offset: l.meshlets.triangles.len() as u32,
            vertex_count: vertices.len() as u32,
            triangle_count: (o.indices.len() / 3) as u32,
        });
        l.meshlets.vertices.extend(vertices);
        l.meshlets.triangles.extend(triangles);
        l.info.push(LodInfo {
            bounds: o.own.0,
            error: o.own.1,
            parent_bounds: o.parent.0,
            parent_error: o.parent.1,
            group: if o.parent.1 == f32::INFINITY {
                NO_GROUP
            } else {
                o.group
            },
        });
    }
    let terminal_early = groups
        .iter()
        .filter(|(d, b)| b.error >= f32::MAX && *d < depth)
        .count();
    (levels, terminal_early, secs)
}

/// Triangles the cut selects for `cam` at `threshold` (LOD rule only, everything loaded).
fn selected_triangles(fl: &Flat, cam: &Camera, threshold: f32) -> usize {
    let q = cam.lod_query(threshold, 0, false);
    flat::select_meshlets(fl, &q)
        .iter()
        .map(|&i| fl.records[i as usize].triangles as usize)
        .sum()
}

/// One mesh's results.
struct MeshResult {
    name: String,
    triangles: usize,
    dags: Vec<Dag>,
    /// Per DAG: mean selected triangles per distance.
    curve: Vec<Vec<f64>>,
    /// Per DAG: median LOD frame time (ms) per distance, and full detail per distance.
    frame_ms: Vec<Vec<f64>>,
    full_ms: Vec<f64>,
}

/// The configurations compared per mesh, in table order (the ratio columns use 1 over 2):
/// (label, ours? (limits, grouping) or clod(128)).
fn configs() -> Vec<(&'static str, Option<(Limits, Grouping)>)> {
    let l128 = Limits::new(128, 128).expect("128/128 is valid");
    vec![
        ("ours 64/126", Some((Limits::DEFAULT, Grouping::Meshopt))),
        ("ours 128/128", Some((l128, Grouping::Meshopt))),
        ("clod 128", None),
        (
            "ours 128/128 k-medoids groups",
            Some((l128, Grouping::KMedoids)),
        ),
    ]
}

fn bench_mesh(
    cfg: &Config,
    name: &str,
    m: &Mesh,
    ctx: Option<&Context>,
    pb: &ProgressBar,
) -> Result<MeshResult> {
    // Builds, interleaved: every configuration once per round.
    let confs = configs();
    let (one, two) = (one_thread_pool(), two_thread_pool()?);
    let mut times: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); confs.len()];
    let mut built: Vec<Option<(Vec<Level>, usize)>> = (0..confs.len()).map(|_| None).collect();
    for _ in 0..cfg.runs().max(1) {
        for (k, (label, limits)) in confs.iter().enumerate() {
            pb.set_message(format!("{name}: building {label}"));
            match limits {
                Some((l, grouping)) => {
                    let lc = lod::Config {
                        grouping: *grouping,
                        ..cfg.lod()
                    };
                    let (levels, stuck, t2) = ours(m, "meshopt", *l, &two, &lc)?;
                    let (levels1, _, t1) = ours(m, "meshopt", *l, &one, &lc)?;
                    anyhow::ensure!(
                        levels1 == levels,
                        "{name} {label}: 1 and 2 threads built different DAGs"
                    );
                    times[k].0.push(t1);
                    times[k].1.push(t2);
                    built[k] = Some((levels, stuck));
                }
                None => {
                    let (levels, stuck, t) = clod(m, 128);
                    times[k].0.push(t);
                    built[k] = Some((levels, stuck));
                }
            }
        }
    }
    let dags: Vec<Dag> = confs
        .iter()
        .zip(built)
        .zip(&times)
        .map(|(((label, _), b), (t1, t2))| {
            let (levels, stuck) = b.expect("built at least once");
            Dag {
                label: label.to_string(),
                levels,
                stuck,
                seconds_1t: median(t1),
                seconds_2t: (!t2.is_empty()).then(|| median(t2)),
            }
        })
        .collect();
    let flats: Vec<Flat> = dags
        .iter()
        .map(|d| Flat::from_levels(m, &d.levels))
        .collect();
    pb.set_message(format!("{name}: selecting"));
    let curve: Vec<Vec<f64>> = flats
        .iter()
        .map(|fl| {
            cfg.distances
                .iter()
                .enumerate()
                .map(|(k, &d)| {
                    let cams = Camera::random_views(m, cfg.select_views(), 0x10d + k as u64, d);
                    let sum: usize = cams
                        .iter()
                        .map(|c| selected_triangles(fl, c, cfg.threshold))
                        .sum();
                    sum as f64 / cams.len().max(1) as f64
                })
                .collect()
        })
        .collect();
    let (mut frame_ms, mut full_ms) = (Vec::new(), Vec::new());
    if let (Some(ctx), true) = (ctx, cfg.render_views() > 0) {
        pb.set_message(format!("{name}: rendering"));
        let passes: Vec<Pass> = flats
            .iter()
            .map(|fl| Pass::with_lod(ctx, m, fl))
            .collect::<Result<_, RenderError>>()?;
        let full = Pass::new(ctx, m, &dags[0].levels[0].meshlets)?;
        let cull = Pipeline::Mesh {
            frustum: true,
            cone: true,
            colour_ids: false,
        };
        frame_ms = vec![Vec::new(); passes.len()];
        for (k, &d) in cfg.distances.iter().enumerate() {
            let cams = Camera::random_views(m, cfg.render_views() + 1, 0x10d + k as u64, d);
            let mut t: Vec<Vec<f64>> = vec![Vec::new(); passes.len()];
            let mut tf = Vec::new();
            // Interleaved per view; the first view warms up and is discarded.
            for (v, cam) in cams.iter().enumerate() {
                let q = cam.lod_query(cfg.threshold, 0, true);
                for (p, pass) in passes.iter().enumerate() {
                    let f = pass.render_lod(cam, &q, false, Shading::Lit)?;
                    if v > 0 {
                        t[p].push(f.gpu_ns * 1e-6);
                    }
                }
                let f = full.render(cam, cull, Shading::Lit)?;
                if v > 0 {
                    tf.push(f.gpu_ns * 1e-6);
                }
            }
            for (p, ts) in t.iter().enumerate() {
                frame_ms[p].push(median(ts));
            }
            full_ms.push(median(&tf));
        }
    }
    Ok(MeshResult {
        name: name.to_string(),
        triangles: m.triangle_count(),
        dags,
        curve,
        frame_ms,
        full_ms,
    })
}

/// Level-0 strategy comparison on one mesh: per strategy, mean selected triangles per distance of
/// its 64/126 DAG (equal error: the same threshold and views).
fn strategy_curve(cfg: &Config, m: &Mesh, strategy: &str) -> Result<(Vec<f64>, usize, f64)> {
    let (levels, _, secs) = ours(
        m,
        strategy,
        Limits::DEFAULT,
        &two_thread_pool()?,
        &cfg.lod(),
    )?;
    let fl = Flat::from_levels(m, &levels);
    let total: usize = levels.iter().map(lod::level_triangles).sum();
    let curve = cfg
        .distances
        .iter()
        .enumerate()
        .map(|(k, &d)| {
            let cams = Camera::random_views(m, cfg.select_views(), 0x10d + k as u64, d);
            cams.iter()
                .map(|c| selected_triangles(&fl, c, cfg.threshold))
                .sum::<usize>() as f64
                / cams.len().max(1) as f64
        })
        .collect();
    Ok((curve, total, secs))
}

/// Points (distance, y).
fn along(distances: &[f32], ys: &[f64]) -> Vec<(f64, f64)> {
    distances
        .iter()
        .map(|&x| x as f64)
        .zip(ys.iter().copied())
        .collect()
}

/// One line per DAG of `r` against camera distance, from `per_dag[k]` (values per distance).
fn dag_series(cfg: &Config, r: &MeshResult, per_dag: &[Vec<f64>]) -> Vec<Series> {
    r.dags
        .iter()
        .zip(per_dag)
        .map(|(d, ys)| Series {
            label: d.label.clone(),
            points: along(&cfg.distances, ys),
        })
        .collect()
}

/// Level ratios are reported over levels whose lower level has at least this many triangles: the
/// last few levels of a DAG hold a handful of triangles, where one triangle more or less moves the
/// ratio by 0.1 (they are all in lod_levels.csv).
const RATIO_MIN_TRIANGLES: usize = 512;

/// One DAG on one mesh, with what its table row derives from it.
struct DagRow<'a> {
    name: &'a str,
    tris: usize,
    d: &'a Dag,
    /// Triangles over all levels.
    total: usize,
    meshlets: usize,
    roots: usize,
    violations: usize,
    /// Smallest and largest level ratio (levels whose lower level has enough triangles).
    ratios: (f64, f64),
    /// The faster build's seconds (2 threads where the 1-thread one is missing).
    best: f64,
}

impl<'a> DagRow<'a> {
    fn new(name: &'a str, tris: usize, d: &'a Dag) -> Self {
        let lt = d.level_triangles();
        let ratios = lt
            .windows(2)
            .filter(|w| w[0] >= RATIO_MIN_TRIANGLES)
            .map(|w| w[1] as f64 / w[0].max(1) as f64)
            .fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(r), b.max(r)));
        let best = d.seconds_2t.unwrap_or(d.seconds_1t).min(d.seconds_1t);
        DagRow {
            name,
            tris,
            d,
            total: lt.iter().sum(),
            meshlets: d.levels.iter().map(|l| l.meshlets.len()).sum(),
            roots: d.roots(),
            violations: d.monotonic_violations(),
            ratios,
            best: if best.is_nan() {
                d.seconds_2t.unwrap_or(f64::NAN)
            } else {
                best
            },
        }
    }
}

/// The builds: lod.md's first table and lod.csv (more digits, the ratios in two columns).
fn dag_table<'a, 'r>() -> Table<'a, DagRow<'r>> {
    Table::new(Style::Compact)
        .col("mesh", Left, |r: &DagRow| r.name.to_string())
        .col("triangles", Right, |r| r.tris.to_string())
        .renamed("DAG", "dag", Left, |r| r.d.label.to_string())
        .split(
            "build s (1 thr)",
            Right,
            |r| match r.d.seconds_1t.is_nan() {
                true => "–".into(),
                false => format!("{:.3}", r.d.seconds_1t),
            },
            "build_s_1t",
            |r| r.d.seconds_1t.to_string(),
        )
        .split(
            "build s (2 thr)",
            Right,
            |r| r.d.seconds_2t.map_or("–".into(), |s| format!("{s:.3}")),
            "build_s_2t",
            |r| r.d.seconds_2t.unwrap_or(f64::NAN).to_string(),
        )
        .split(
            "M tri/s (best)",
            Right,
            |r| format!("{:.2}", r.tris as f64 / r.best / 1e6),
            "mtri_per_s_2t",
            |r| format!("{:.4}", r.tris as f64 / r.best / 1e6),
        )
        .col("levels", Right, |r| r.d.levels.len().to_string())
        .col("roots", Right, |r| r.roots.to_string())
        .col("stuck", Right, |r| r.d.stuck.to_string())
        .renamed("monotonic violations", "monotonic_violations", Right, |r| {
            r.violations.to_string()
        })
        .col("meshlets", Right, |r| r.meshlets.to_string())
        .csv_only("total_triangles", |r| r.total.to_string())
        .split(
            "all levels / source",
            Right,
            |r| fmt_ratio(r.total, r.tris),
            "total_over_source",
            |r| format!("{:.4}", r.total as f64 / r.tris as f64),
        )
        .split(
            "tri/meshlet",
            Right,
            |r| format!("{:.1}", r.total as f64 / r.meshlets.max(1) as f64),
            "triangles_per_meshlet",
            |r| format!("{:.2}", r.total as f64 / r.meshlets.max(1) as f64),
        )
        .split(
            "level ratios",
            Left,
            |r| format!("{:.3}–{:.3}", r.ratios.0, r.ratios.1),
            "min_level_ratio",
            |r| format!("{:.4}", r.ratios.0),
        )
        .csv_only("max_level_ratio", |r| format!("{:.4}", r.ratios.1))
}

fn fmt_ratio(a: usize, b: usize) -> String {
    format!("{:.3}", a as f64 / b.max(1) as f64)
}

/// Runs the benchmark and writes the results.
pub fn run(cfg: &Config) -> Result<()> {
    // A library caller's configuration skips the command line's check.
    if !(cfg.threshold > 0.0 && cfg.threshold.is_finite()) {
        anyhow::bail!("--threshold must be a positive number of pixels");
    }
    let files = mesh_files(&cfg.common.meshes_dir()?)?;
    create_dir(&cfg.common.out)?;
    let ctx = if cfg.render_views() > 0 {
        Some(Context::new(false)?)
    } else {
        None
    };
    let pb = super::progress::bar(cfg.common.quiet, files.len() as u64);
    let mut results = Vec::new();
    let mut meshes = Vec::new();
    for f in &files {
        let name = mesh_name(f);
        pb.set_message(format!("{name}: loading"));
        let m = mesh::load(f)?;
        results.push(bench_mesh(cfg, &name, &m, ctx.as_ref(), &pb)?);
        meshes.push((name, m));
        pb.inc(1);
    }
    // Level-0 strategies on the smaller meshes.
    let mut strat: Vec<(String, String, Vec<f64>, usize, f64)> = Vec::new();
    for (name, m) in meshes
        .iter()
        .filter(|(_, m)| m.triangle_count() <= cfg.strategy_max_triangles)
    {
        for s in &cfg.strategy {
            pb.set_message(format!("{name}: level-0 strategy {s}"));
            let (c, total, secs) = strategy_curve(cfg, m, s)?;
            strat.push((name.clone(), s.clone(), c, total, secs));
        }
    }
    // The dragon at 14 M triangles: builds only (ours on 2 threads, clod on one).
    let mut big = None;
    if !cfg.quick() {
        if let Some((_, dragon)) = meshes.iter().find(|(n, _)| n.contains("dragon")) {
            pb.set_message("dragon x16: subdividing");
            let m = mesh::subdivide::subdivide(dragon, 2).map_err(anyhow::Error::msg)?;
            pb.set_message(format!(
                "dragon x16 ({} triangles): ours",
                m.triangle_count()
            ));
            let (levels, stuck, t2) = ours(
                &m,
                "meshopt",
                Limits::DEFAULT,
                &two_thread_pool()?,
                &cfg.lod(),
            )?;
            let d_ours = Dag {
                label: "ours 64/126".into(),
                levels,
                stuck,
                seconds_1t: f64::NAN,
                seconds_2t: Some(t2),
            };
            pb.set_message("dragon x16: clod");
            let (levels, stuck, t) = clod(&m, 128);
            let d_clod = Dag {
                label: "clod 128".into(),
                levels,
                stuck,
                seconds_1t: t,
                seconds_2t: None,
            };
            big = Some((m.triangle_count(), [d_ours, d_clod]));
        }
    }
    pb.finish_and_clear();
    write_results(
        cfg,
        &results,
        &strat,
        big.as_ref(),
        ctx.as_ref().map(|c| c.name.clone()),
    )
}

/// The command line of the run, for the report's header: the options that change what is
/// measured.
fn lod_command(cfg: &Config) -> String {
    let mut c = format!(
        "meshletlab bench lod --runs {} --threshold {} --strategy {}",
        cfg.runs(),
        cfg.threshold,
        cfg.strategy.join(",")
    );
    if cfg.quick && !cfg.common.smoke {
        c += " --quick";
    }
    c + &cfg.tag.flag()
}

fn write_results(
    cfg: &Config,
    results: &[MeshResult],
    strat: &[(String, String, Vec<f64>, usize, f64)],
    big: Option<&(usize, [Dag; 2])>,
    device: Option<String>,
) -> Result<()> {
    let mut md = String::new();
    write_header(
        &mut md,
        "Cluster LOD: ours beside meshoptimizer's clusterlod",
        &lod_command(cfg),
        "",
        cfg.common.smoke_out(),
    );
    writeln!(
        md,
        "GPU: {}.\n",
        device.as_deref().unwrap_or("not rendered")
    )?;
    writeln!(md, "Ours: `meshletlab::lod::build` with meshoptimizer's splitter (`meshopt` strategy) at 64/126 and at clod's 128/128, groups of 8 (meshoptimizer's partition_clusters; the last row per mesh groups by our k-medoids on the meshlet graph instead, `lod::group`), simplify_with_locks to half. Peer: meshoptimizer 1.3 `clod_build(clod_default_config(128))`, single-threaded by design. Build times: median of {} interleaved runs; ours on 1 and 2 rayon threads (the same DAG on both, checked).\n", cfg.runs())?;
    writeln!(md, "## Builds\n")?;
    let mut dags: Vec<DagRow> = Vec::new();
    for r in results {
        dags.extend(r.dags.iter().map(|d| DagRow::new(&r.name, r.triangles, d)));
    }
    if let Some((tris, big)) = big {
        dags.extend(
            big.iter()
                .map(|d| DagRow::new("dragon x16 (subdivided)", *tris, d)),
        );
    }
    writeln!(md, "{}", dag_table().markdown(&dags))?;
    writeln!(md, "\nLevel ratios: each level's triangles over the level below, over levels whose lower level has at least {RATIO_MIN_TRIANGLES} triangles (all levels: {}).", cfg.tag.name("lod_levels.csv"))?;
    writeln!(md, "\n\"stuck\" for clod: groups it emitted as terminal (simplification above its threshold) before the last level. Monotonic violations: meshlets whose parent error is below their own or whose parent sphere does not enclose their own (f64, 1e-6 slack); clod's cluster bounds follow its own documented rule (it warns that cluster `bounds.error` is not monotonic), and both DAGs are selected here with the group bounds.\n")?;
    // Triangles per level, one table per mesh would be long: the dragon's, and the CSV has all.
    writeln!(md, "## Triangles per level\n")?;
    let mut level_csv = String::from("mesh,dag,level,meshlets,triangles,ratio_to_level_below\n");
    for r in results {
        for d in &r.dags {
            let lt = d.level_triangles();
            for (l, t) in lt.iter().enumerate() {
                let ratio = if l > 0 {
                    format!("{:.4}", *t as f64 / lt[l - 1].max(1) as f64)
                } else {
                    String::new()
                };
                writeln!(
                    level_csv,
                    "{},{},{l},{},{t},{ratio}",
                    r.name,
                    d.label,
                    d.levels[l].meshlets.len()
                )?;
            }
        }
    }
    for r in results.iter().filter(|r| r.name.contains("dragon")) {
        writeln!(
            md,
            "{} (all meshes: {}):\n",
            r.name,
            cfg.tag.name("lod_levels.csv")
        )?;
        writeln!(
            md,
            "| level | {} |",
            r.dags
                .iter()
                .map(|d| d.label.as_str())
                .collect::<Vec<_>>()
                .join(" | ")
        )?;
        writeln!(md, "|---:|{}", "---:|".repeat(r.dags.len()))?;
        let n = r.dags.iter().map(|d| d.levels.len()).max().unwrap_or(0);
        for l in 0..n {
            let cells: Vec<String> = r
                .dags
                .iter()
                .map(|d| {
                    let lt = d.level_triangles();
                    match lt.get(l) {
                        Some(t) if l > 0 => {
                            format!("{t} ({:.3})", *t as f64 / lt[l - 1].max(1) as f64)
                        }
                        Some(t) => t.to_string(),
                        None => String::new(),
                    }
                })
                .collect();
            writeln!(md, "| {l} | {} |", cells.join(" | "))?;
        }
    }
    // The curve.
    writeln!(
        md,
        "\n## Triangles selected against camera distance ({} px threshold)\n",
        cfg.threshold
    )?;
    writeln!(md, "Mean over {} random directions per distance (1280x720, 60 degree field of view), LOD rule only (no culling), the same selection code for every DAG. Ratio = ours 128/128 over clod 128 (same limits); below 1 means fewer triangles at the same error bound.\n", cfg.select_views())?;
    let dist_head: Vec<String> = cfg.distances.iter().map(|d| format!("{d} r")).collect();
    writeln!(md, "| mesh | DAG | {} |", dist_head.join(" | "))?;
    writeln!(md, "|---|---|{}", "---:|".repeat(cfg.distances.len()))?;
    let mut curve_csv =
        String::from("mesh,dag,distance_radii,selected_triangles,frame_ms,full_detail_ms\n");
    let mut ratio_series = Vec::new();
    let mut worst_ratio = 0.0f64;
    for r in results {
        for (k, d) in r.dags.iter().enumerate() {
            let cells: Vec<String> = r.curve[k].iter().map(|t| format!("{t:.0}")).collect();
            writeln!(md, "| {} | {} | {} |", r.name, d.label, cells.join(" | "))?;
            for (j, &dist) in cfg.distances.iter().enumerate() {
                writeln!(
                    curve_csv,
                    "{},{},{dist},{:.1},{},{}",
                    r.name,
                    d.label,
                    r.curve[k][j],
                    r.frame_ms
                        .get(k)
                        .and_then(|f| f.get(j))
                        .map_or(String::new(), |x| format!("{x:.3}")),
                    r.full_ms
                        .get(j)
                        .map_or(String::new(), |x| format!("{x:.3}"))
                )?;
            }
        }
        let ratios: Vec<f64> = (0..cfg.distances.len())
            .map(|j| r.curve[1][j] / r.curve[2][j].max(1.0))
            .collect();
        worst_ratio = ratios.iter().fold(worst_ratio, |a, &b| a.max(b));
        let cells: Vec<String> = ratios.iter().map(|x| format!("**{x:.3}**")).collect();
        writeln!(md, "| {} | ratio | {} |", r.name, cells.join(" | "))?;
        ratio_series.push(Series {
            label: r.name.clone(),
            points: along(&cfg.distances, &ratios),
        });
    }
    let cells: Vec<f64> = ratio_series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .collect();
    let geomean = (cells.iter().map(|r| r.ln()).sum::<f64>() / cells.len().max(1) as f64).exp();
    let above = cells.iter().filter(|&&r| r > 1.0 + 1e-9).count();
    let total = |k: usize| -> f64 { results.iter().map(|r| r.curve[k].iter().sum::<f64>()).sum() };
    writeln!(
        md,
        "\nOver all meshes and distances: ours 128/128 selects **{:.3}x** clod's triangles in total (ours 64/126: {:.3}x); geometric mean of the ratios **{geomean:.3}**; ours selects more than clod in {above} of {} cells, at most **{worst_ratio:.3}x**. Where both draw a few hundred triangles the cut jumps a whole level at once, so single cells swing by 2x either way; the near distances hold most of the triangles.\n",
        total(1) / total(2).max(1.0),
        total(0) / total(2).max(1.0),
        cells.len()
    )?;
    writeln!(md, "![ours / clod]({})\n", cfg.tag.name("lod_ratio.svg"))?;
    line_chart(
        &cfg.common.out.join(cfg.tag.name("lod_ratio.svg")),
        "Triangles selected at 1 px: ours 128/128 / clod 128",
        "camera distance (bounding radii)",
        "ours / clod",
        &ratio_series,
        Axes {
            log_x: true,
            log_y: false,
            zero_y: false,
        },
    )?;
    if let Some(r) = results.iter().find(|r| r.name.contains("dragon")) {
        let series = dag_series(cfg, r, &r.curve);
        line_chart(
            &cfg.common
                .out
                .join(cfg.tag.name("lod_dragon_triangles.svg")),
            &format!("{}: triangles selected at {} px", r.name, cfg.threshold),
            "camera distance (bounding radii)",
            "triangles",
            &series,
            Axes {
                log_x: true,
                log_y: false,
                zero_y: true,
            },
        )?;
        writeln!(
            md,
            "![dragon triangles]({})\n",
            cfg.tag.name("lod_dragon_triangles.svg")
        )?;
    }
    // Frame times.
    if results.iter().any(|r| !r.frame_ms.is_empty()) {
        writeln!(md, "## Frame time against camera distance ({} px, task-shader LOD with frustum and cone culling)\n", cfg.threshold)?;
        writeln!(md, "Median GPU ms per frame over {} views per distance (one discarded first), on {}; \"full\" draws the source's 64/126 meshlets with culling. {}\n", cfg.render_views(), device.as_deref().unwrap_or("?"), if device.as_deref().is_some_and(is_lavapipe) { "On lavapipe the GPU is the CPU: compare ratios, not absolute numbers." } else { "" })?;
        writeln!(md, "| mesh | DAG | {} |", dist_head.join(" | "))?;
        writeln!(md, "|---|---|{}", "---:|".repeat(cfg.distances.len()))?;
        for r in results.iter().filter(|r| !r.frame_ms.is_empty()) {
            for (k, d) in r.dags.iter().enumerate() {
                let cells: Vec<String> = r.frame_ms[k].iter().map(|t| format!("{t:.2}")).collect();
                writeln!(md, "| {} | {} | {} |", r.name, d.label, cells.join(" | "))?;
            }
            let cells: Vec<String> = r.full_ms.iter().map(|t| format!("{t:.2}")).collect();
            writeln!(md, "| {} | full detail | {} |", r.name, cells.join(" | "))?;
        }
        if let Some(r) = results
            .iter()
            .find(|r| r.name.contains("dragon") && !r.frame_ms.is_empty())
        {
            let mut series = dag_series(cfg, r, &r.frame_ms);
            series.push(Series {
                label: "full detail".into(),
                points: along(&cfg.distances, &r.full_ms),
            });
            line_chart(
                &cfg.common
                    .out
                    .join(cfg.tag.name("lod_dragon_frame_time.svg")),
                &format!("{}: frame time at {} px", r.name, cfg.threshold),
                "camera distance (bounding radii)",
                "GPU ms per frame",
                &series,
                Axes {
                    log_x: true,
                    log_y: false,
                    zero_y: true,
                },
            )?;
            writeln!(
                md,
                "\n![dragon frame time]({})\n",
                cfg.tag.name("lod_dragon_frame_time.svg")
            )?;
        }
    }
    // Level-0 strategies.
    if !strat.is_empty() {
        writeln!(md, "## Which level-0 strategy makes the best DAG\n")?;
        writeln!(md, "Our DAG at 64/126 with each strategy for level 0 and every split, on the meshes up to {} triangles: mean triangles selected at {} px per distance (equal error), summed over the distances and relative to `meshopt` (below 1 is better), with all levels over the source and the 2-thread build time.\n", cfg.strategy_max_triangles, cfg.threshold)?;
        writeln!(
            md,
            "| mesh | strategy | selected, relative | all levels / source | build s |"
        )?;
        writeln!(md, "|---|---|---:|---:|---:|")?;
        let mut per_strategy: Vec<(String, Vec<f64>)> = Vec::new();
        for (mesh_name, s, c, total, secs) in strat {
            let base: f64 = strat
                .iter()
                .find(|x| &x.0 == mesh_name && x.1 == "meshopt")
                .map(|x| x.2.iter().sum())
                .unwrap_or(f64::NAN);
            let rel = c.iter().sum::<f64>() / base;
            let tris = results
                .iter()
                .find(|r| &r.name == mesh_name)
                .map_or(1, |r| r.triangles);
            writeln!(
                md,
                "| {mesh_name} | {s} | {rel:.3} | {} | {secs:.3} |",
                fmt_ratio(*total, tris)
            )?;
            match per_strategy.iter_mut().find(|(n, _)| n == s) {
                Some((_, v)) => v.push(rel),
                None => per_strategy.push((s.clone(), vec![rel])),
            }
        }
        writeln!(
            md,
            "\nMedian relative selection per strategy: {}.\n",
            per_strategy
                .iter()
                .map(|(s, v)| format!("{s} {:.3}", median(v)))
                .collect::<Vec<_>>()
                .join(", ")
        )?;
    }
    write_file(cfg.common.out.join(cfg.tag.name("lod.md")), md)?;
    write_file(
        cfg.common.out.join(cfg.tag.name("lod.csv")),
        dag_table().csv(&dags),
    )?;
    write_file(
        cfg.common.out.join(cfg.tag.name("lod_levels.csv")),
        level_csv,
    )?;
    write_file(
        cfg.common.out.join(cfg.tag.name("lod_curve.csv")),
        curve_csv,
    )?;
    Ok(())
}
