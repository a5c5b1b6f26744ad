//! `meshletlab bench render`: the mesh-shader pass against the vertex pipeline (Jensen et al. 2023
//! §4–5): per mesh × strategy, ms per frame (median, p95) with and without task-shader culling over
//! the seeded random-view protocol (first frame discarded), the share of meshlets and triangles the
//! task shader skipped (frustum and backface), the ns-per-triangle slope of frame time against
//! triangle count across the shared meshes (paper Table 6), and a meshlet-coloured image of the
//! bunny per strategy (paper Figure 1) -> results/render.md, render.csv, render_per_triangle.svg,
//! `render_bunny_<strategy>.png`.

use super::build::{mesh_files, mesh_name};
use super::plot::{bar_chart, line_chart, Axes, Bars, Series};
use super::table::{
    Align::{Left, Right},
    Style, Table,
};
use super::{create_dir, is_lavapipe, median, p95, smoke, write_file, write_header, Common, Tag};
use crate::mesh::{self, Mesh};
use crate::meshlet::descriptor::DescriptorFormat;
use crate::meshlet::order::{
    local_miss_rate, optimize_triangle_order, order_meshlets, MeshletOrder,
};
use crate::meshlet::{validate, Limits, Meshlets};
use crate::render::{Camera, Context, Pass, Pipeline, RenderError, Shading, HEIGHT, WIDTH};
use crate::strategy::{self, Options};
use anyhow::{Context as _, Result};
use std::fmt::Write as _;

/// The paper's Table 6: ns per triangle of its linear regressions on an RTX 2080 Ti (range over its
/// strategies).
pub const PAPER_NS_PER_TRIANGLE: (f64, f64) = (0.0899, 0.0974);

/// What to run: the arguments of `meshletlab bench render`.
#[derive(clap::Args, Clone, Debug)]
pub struct Config {
    /// Mesh folder, output folder, smoke run (one view per mesh), quiet.
    #[command(flatten)]
    pub common: Common,
    /// A suffix for the file names, for a run on another device.
    #[command(flatten)]
    pub tag: Tag,
    /// Meshlet limits.
    #[arg(short, long, default_value = "64/126", value_parser = clap::value_parser!(Limits))]
    pub limits: Limits,
    /// Strategies (comma-separated).
    #[arg(short, long, value_delimiter = ',', value_parser = super::strategy_name, default_values_t = DEFAULT_STRATEGIES.iter().map(|s| s.to_string()))]
    pub strategy: Vec<String>,
    /// Strategies of the experiments: the four descriptor layouts, meshlets ordered by
    /// primitive count, triangle order inside meshlets (comma-separated; empty: none).
    #[arg(long, value_delimiter = ',', value_parser = super::strategy_name_or_none, default_values_t = DEFAULT_EXPERIMENT_STRATEGIES.iter().map(|s| s.to_string()))]
    pub experiment_strategy: Vec<String>,
    /// Views per mesh (sized for lavapipe; the paper used 100,000 frames on a GPU).
    #[arg(long, default_value_t = 10, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub views: usize,
    /// Seed of the view sequence.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Camera distance from the mesh centre in bounding radii (every view sees the whole mesh).
    #[arg(long, default_value_t = 2.5, value_parser = super::positive::<f32>)]
    pub distance: f32,
    /// Distance of the close views for the culling shares (inside the bounding sphere, so the
    /// frustum culls).
    #[arg(long, default_value_t = 0.9, value_parser = super::positive::<f32>)]
    pub near_distance: f32,
    /// The occlusion-culling scenes.
    #[command(flatten)]
    pub occlusion: super::render_occlusion::OcclusionArgs,
}

impl Config {
    /// Views per mesh (one more is rendered first and discarded): one in a smoke run.
    pub fn views(&self) -> usize {
        self.common.or_smoke(self.views, 1)
    }

    /// The mesh of the Figure-1 images (file stem) and the name their files carry
    /// (`render_<name>_<strategy>.png`): the bunny, or in a smoke run the first smoke mesh, so that
    /// the smoke run writes the images it links.
    pub fn figure_mesh(&self) -> (&'static str, &'static str) {
        if self.common.smoke {
            (smoke::FIRST, smoke::FIRST)
        } else {
            ("stanford_bunny", "bunny")
        }
    }

    /// The Figure-1 image of strategy `s`.
    fn figure_file(&self, s: &str) -> String {
        let short = self.figure_mesh().1;
        self.tag
            .name(&format!("render_{short}_{}.png", s.replace('+', "_")))
    }

    /// Strategies of the layout and ordering experiments (Figures 10 and 12, triangle order), the
    /// empty names of `--experiment-strategy ''` left out.
    pub fn experiment_strategies(&self) -> Vec<String> {
        let mut v = self.experiment_strategy.clone();
        v.retain(|s| !s.is_empty());
        v
    }
}

/// The default strategies: the paper's, the peer, and ours.
pub const DEFAULT_STRATEGIES: &[&str] = &[
    "nvidia",
    "greedy",
    "bsphere",
    "kmedoids",
    "meshopt",
    "compact",
    "bsphere-parallel",
];

/// The default strategies of the experiments: the index-buffer scan (small meshlets) and the peer.
pub const DEFAULT_EXPERIMENT_STRATEGIES: &[&str] = &["nvidia", "meshopt"];

const CULL: Pipeline = Pipeline::Mesh {
    frustum: true,
    cone: true,
    colour_ids: false,
};
const NO_CULL: Pipeline = Pipeline::Mesh {
    frustum: false,
    cone: false,
    colour_ids: false,
};

/// What the task shader and the queries counted, summed over the views.
#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    frustum: u64,
    cone: u64,
    drawn: u64,
    tris_frustum: u64,
    tris_cone: u64,
    task_invocations: u64,
    mesh_invocations: u64,
    primitives: u64,
}

impl Counts {
    fn add(&mut self, f: &crate::render::Frame) {
        self.frustum += f.culled_frustum as u64;
        self.cone += f.culled_cone as u64;
        self.drawn += f.drawn as u64;
        self.tris_frustum += f.culled_triangles[0] as u64;
        self.tris_cone += f.culled_triangles[1] as u64;
        if let Some(q) = f.queries {
            self.task_invocations += q.task_invocations;
            self.mesh_invocations += q.mesh_invocations;
            self.primitives += q.primitives;
        }
    }

    /// Meshlets culled by the frustum and by the cone, and triangles skipped, in % (of
    /// `meshlets` and `triangles` per view over `views`).
    fn shares(&self, meshlets: usize, triangles: usize, views: usize) -> [f64; 3] {
        let m = (meshlets * views).max(1) as f64;
        let t = (triangles * views).max(1) as f64;
        [
            100.0 * self.frustum as f64 / m,
            100.0 * self.cone as f64 / m,
            100.0 * (self.tris_frustum + self.tris_cone) as f64 / t,
        ]
    }
}

/// Frame times in ms of `how` for each pass over `views`, interleaved (view 0 on every pass, then
/// view 1, ...) so that a slow spell of a noisy machine hits every variant alike. One frame per pass
/// is rendered first and discarded.
fn frames(passes: &[&Pass], views: &[Camera], how: Pipeline) -> Result<Vec<(Vec<f64>, Counts)>> {
    for p in passes {
        p.render(&views[0], how, Shading::Lit)?;
    }
    let mut out = vec![(Vec::with_capacity(views.len()), Counts::default()); passes.len()];
    for v in views {
        for (p, (ms, counts)) in passes.iter().zip(out.iter_mut()) {
            let f = p.render(v, how, Shading::Lit)?;
            ms.push(f.gpu_ns * 1e-6);
            counts.add(&f);
        }
    }
    Ok(out)
}

struct Row {
    mesh: String,
    triangles: usize,
    strategy: String,
    meshlets: usize,
    cull: Vec<f64>,
    no_cull: Vec<f64>,
    vertex: Vec<f64>,
    /// Far views: meshlets culled by frustum and backface, triangles skipped (%).
    far: [f64; 3],
    /// Close views: the same.
    near: [f64; 3],
    /// Per frame with culling (far views): task and mesh invocations, primitives generated.
    invocations: [f64; 3],
    /// The Figure-1 image written for this row (the figure mesh's rows only).
    image: Option<String>,
}

/// One variant of an experiment on one mesh and strategy.
struct Variant {
    mesh: String,
    strategy: String,
    experiment: &'static str,
    variant: String,
    /// Device bytes per triangle of the meshlet data (descriptors, indices, positions).
    bytes_per_triangle: f64,
    /// Mean new vertices per triangle through an 8-entry FIFO inside each meshlet.
    miss_rate: f64,
    cull: Vec<f64>,
    no_cull: Vec<f64>,
    /// Far views: meshlets culled by frustum and backface, triangles skipped (%).
    shares: [f64; 3],
    /// Why the variant could not run (a layout's field too narrow for the mesh); nothing measured.
    unfit: Option<String>,
}

fn load(path: &std::path::Path) -> Result<Mesh> {
    // The error names the file.
    Ok(mesh::load(path)?)
}

fn build(m: &Mesh, s: &str, limits: Limits, name: &str) -> Result<Meshlets> {
    let ml = strategy::by_name(s, &Options::default())?.build(m, limits);
    validate(m, &ml, limits).with_context(|| format!("{name}: {s}"))?;
    Ok(ml)
}

/// Runs the benchmark and writes the results.
pub fn run(cfg: &Config) -> Result<()> {
    let meshes = cfg.common.meshes_dir()?;
    let ctx = Context::new(false)?;
    let files = mesh_files(&meshes)?;
    create_dir(&cfg.common.out)?;
    let per_mesh = cfg.strategy.len() + cfg.experiment_strategies().len();
    let pb = super::progress::bar(cfg.common.quiet, (files.len() * per_mesh) as u64);
    let mut rows = Vec::new();
    let mut variants = Vec::new();
    for path in &files {
        let name = mesh_name(path);
        let m = load(path)?;
        let views = Camera::random_views(&m, cfg.views().max(1), cfg.seed, cfg.distance);
        let near = Camera::random_views(&m, cfg.views().max(1), cfg.seed, cfg.near_distance);
        for s in &cfg.strategy {
            pb.set_message(format!("{name}: {s}"));
            let ml = build(&m, s, cfg.limits, &name)?;
            rows.push(strategy_row(cfg, &ctx, &m, &name, s, &ml, &views, &near)?);
            pb.inc(1);
        }
        for s in &cfg.experiment_strategies() {
            pb.set_message(format!("{name}: {s}, layouts and orders"));
            variants.extend(experiments(cfg, &ctx, &m, &name, s, &views)?);
            pb.inc(1);
        }
    }
    let occlusion =
        super::render_occlusion::run(&cfg.occlusion, &cfg.common, &ctx, cfg.limits, |msg| {
            pb.set_message(msg.to_string())
        })?;
    pb.finish_and_clear();
    write(cfg, &ctx, &rows, &variants, &occlusion)
}

/// The main table's row: culling on and off, the vertex pipeline, close-view culling, and the
/// Figure-1 image for the bunny.
#[allow(clippy::too_many_arguments)]
fn strategy_row(
    cfg: &Config,
    ctx: &Context,
    m: &Mesh,
    name: &str,
    s: &str,
    ml: &Meshlets,
    views: &[Camera],
    near: &[Camera],
) -> Result<Row> {
    let pass = Pass::new(ctx, m, ml)?;
    let one = |how| -> Result<(Vec<f64>, Counts)> { Ok(frames(&[&pass], views, how)?.remove(0)) };
    let (cull, counts) = one(CULL)?;
    let (no_cull, _) = one(NO_CULL)?;
    let (vertex, _) = one(Pipeline::Vertex)?;
    // Close views: culling counters only (every frame is rendered, its time is not reported).
    let mut near_counts = Counts::default();
    for v in near {
        near_counts.add(&pass.render(v, CULL, Shading::Lit)?);
    }
    let image = if name == cfg.figure_mesh().0 {
        // Figure 1: the first view's direction, framed so the mesh fills the picture.
        let fig = Camera::framed(
            m,
            views[0].eye - views[0].target,
            WIDTH as f32 / HEIGHT as f32,
            crate::render::FRAME_FILL,
        );
        let file = cfg.figure_file(s);
        crate::render::write_meshlet_png(&pass, &fig, true, &cfg.common.out.join(&file))?;
        Some(file)
    } else {
        None
    };
    let n = views.len() as f64;
    Ok(Row {
        mesh: name.to_string(),
        triangles: m.triangle_count(),
        strategy: s.to_string(),
        meshlets: ml.len(),
        cull,
        no_cull,
        vertex,
        far: counts.shares(ml.len(), m.triangle_count(), views.len()),
        near: near_counts.shares(ml.len(), m.triangle_count(), near.len()),
        invocations: [
            counts.task_invocations as f64 / n,
            counts.mesh_invocations as f64 / n,
            counts.primitives as f64 / n,
        ],
        image,
    })
}

/// The experiments on one mesh and strategy, each variant against its baseline in interleaved
/// frames: the four descriptor layouts (Figure 12), meshlets ordered by primitive count (Figure
/// 10), and the within-meshlet triangle order.
fn experiments(
    cfg: &Config,
    ctx: &Context,
    m: &Mesh,
    name: &str,
    s: &str,
    views: &[Camera],
) -> Result<Vec<Variant>> {
    let base = build(m, s, cfg.limits, name)?;
    // The variants reorder the same meshlets (what `--meshlet-order` and `--local-order` do after
    // any strategy), so they are derived from `base` rather than built again.
    let mut by_triangles = base.clone();
    order_meshlets(&mut by_triangles, MeshletOrder::Triangles);
    let mut local = base.clone();
    optimize_triangle_order(&mut local);
    for ml in [&by_triangles, &local] {
        validate(m, ml, cfg.limits).with_context(|| format!("{name}: {s}, reordered"))?;
    }
    let mut out = Vec::new();
    // Layouts: a meshlet set too large for a layout's fields is reported, not measured.
    let mut passes = Vec::new();
    let mut unfit = Vec::new();
    for f in DescriptorFormat::ALL {
        match Pass::with_format(ctx, m, &base, f) {
            Ok(p) => passes.push((f.name().to_string(), &base, p)),
            Err(RenderError::Descriptor(e)) => unfit.push(Variant {
                mesh: name.to_string(),
                strategy: s.to_string(),
                experiment: "descriptor",
                variant: f.name().to_string(),
                bytes_per_triangle: f64::NAN,
                miss_rate: local_miss_rate(&base, 8),
                cull: Vec::new(),
                no_cull: Vec::new(),
                shares: [f64::NAN; 3],
                unfit: Some(e.to_string()),
            }),
            Err(e) => return Err(e.into()),
        }
    }
    out.extend(measure(m, name, s, "descriptor", &passes, views)?);
    out.extend(unfit);
    drop(passes);
    let passes = vec![
        ("as built".to_string(), &base, Pass::new(ctx, m, &base)?),
        (
            "most triangles first".to_string(),
            &by_triangles,
            Pass::new(ctx, m, &by_triangles)?,
        ),
    ];
    out.extend(measure(m, name, s, "meshlet order", &passes, views)?);
    drop(passes);
    let passes = vec![
        ("as built".to_string(), &base, Pass::new(ctx, m, &base)?),
        ("optimised".to_string(), &local, Pass::new(ctx, m, &local)?),
    ];
    out.extend(measure(m, name, s, "triangle order", &passes, views)?);
    Ok(out)
}

fn measure(
    m: &Mesh,
    name: &str,
    s: &str,
    experiment: &'static str,
    passes: &[(String, &Meshlets, Pass)],
    views: &[Camera],
) -> Result<Vec<Variant>> {
    let refs: Vec<&Pass> = passes.iter().map(|(_, _, p)| p).collect();
    let cull = frames(&refs, views, CULL)?;
    let no_cull = frames(&refs, views, NO_CULL)?;
    Ok(passes
        .iter()
        .zip(cull)
        .zip(no_cull)
        .map(
            |(((variant, ml, pass), (cull, counts)), (no_cull, _))| Variant {
                mesh: name.to_string(),
                strategy: s.to_string(),
                experiment,
                variant: variant.clone(),
                bytes_per_triangle: pass.device_bytes() as f64 / m.triangle_count().max(1) as f64,
                miss_rate: local_miss_rate(ml, 8),
                cull,
                no_cull,
                shares: counts.shares(ml.len(), m.triangle_count(), views.len()),
                unfit: None,
            },
        )
        .collect())
}

/// `s` with its first letter upper-case (a heading that starts with a name).
fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map_or(String::new(), |f| f.to_uppercase().chain(c).collect())
}

/// Least-squares slope and intercept of y on x.
fn fit(pts: &[(f64, f64)]) -> (f64, f64) {
    let n = pts.len() as f64;
    let (sx, sy) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = pts.iter().map(|&(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = pts.iter().map(|&(x, y)| (x - mx) * (y - my)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { f64::NAN };
    (slope, my - slope * mx)
}

/// Geometric mean (of ratios).
fn geomean(xs: &[f64]) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    (xs.iter().map(|x| x.ln()).sum::<f64>() / xs.len() as f64).exp()
}

fn write(
    cfg: &Config,
    ctx: &Context,
    rows: &[Row],
    variants: &[Variant],
    occlusion: &[super::render_occlusion::SceneRow],
) -> Result<()> {
    let mut md = String::new();
    write_header(
        &mut md,
        "Mesh-shader rendering against the vertex pipeline",
        &format!(
            "meshletlab bench render --views {} --strategy {}{}",
            cfg.views(),
            cfg.strategy.join(","),
            cfg.tag.flag()
        ),
        "",
        cfg.common.smoke_out(),
    );
    writeln!(md, "Device: **{}** (Vulkan, VK_EXT_mesh_shader). {}×{}, 4× MSAA resolved, D32 depth, back faces culled by the rasteriser in both pipelines. {} seeded random views per mesh at {} bounding radii (seed {}; every view sees the whole mesh), the first frame discarded; GPU time from timestamps around the draw. Close views for the culling shares: the same directions at {} radii. Limits {}/{}. Meshlets in the split layout unless a table says otherwise.\n", ctx.name, WIDTH, HEIGHT, cfg.views(), cfg.distance, cfg.seed, cfg.near_distance, cfg.limits.max_vertices, cfg.limits.max_triangles)?;
    if is_lavapipe(&ctx.name) {
        writeln!(md, "On lavapipe the \"GPU\" is this machine's CPU cores running LLVM-compiled shaders: the ratios say how the two pipelines map onto a software rasteriser, not onto a GPU.\n")?;
    }
    writeln!(md, "## ms per frame\n")?;
    writeln!(md, "{}", frame_table().markdown(rows))?;
    write_culling(cfg, &mut md, rows)?;
    writeln!(md, "\n## Cost per triangle (paper Table 6)\n")?;
    writeln!(md, "Slope of a least-squares line through (triangles, median ms per frame) over the shared meshes, without culling so that every triangle is drawn. Paper (RTX 2080 Ti): {:.4}–{:.4} ns per triangle.\n", PAPER_NS_PER_TRIANGLE.0, PAPER_NS_PER_TRIANGLE.1)?;
    writeln!(md, "| pipeline | ns per triangle | intercept ms |")?;
    writeln!(md, "|---|---:|---:|")?;
    let mut series = Vec::new();
    let mut names: Vec<&str> = cfg.strategy.iter().map(String::as_str).collect();
    names.push("vertex pipeline");
    for s in names {
        let pts: Vec<(f64, f64)> = if s == "vertex pipeline" {
            // One vertex-pipeline point per mesh (the same draw whatever the strategy).
            let mut v: Vec<(f64, f64)> = Vec::new();
            for r in rows {
                if !v.iter().any(|p| p.0 == r.triangles as f64) {
                    v.push((r.triangles as f64, median(&r.vertex)));
                }
            }
            v
        } else {
            rows.iter()
                .filter(|r| r.strategy == s)
                .map(|r| (r.triangles as f64, median(&r.no_cull)))
                .collect()
        };
        let (slope, icept) = fit(&pts);
        let label = if s == "vertex pipeline" {
            s.to_string()
        } else {
            format!("mesh shaders, {s}")
        };
        writeln!(md, "| {label} | {:.3} | {:.3} |", slope * 1e6, icept)?;
        let mut pts = pts;
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        series.push(Series { label, points: pts });
    }
    writeln!(
        md,
        "\n![ms per frame against triangles]({})\n",
        cfg.tag.name("render_per_triangle.svg")
    )?;
    // Only the images this run wrote: none when the folder has no figure mesh.
    let images: Vec<(&str, &str)> = rows
        .iter()
        .filter_map(|r| Some((r.strategy.as_str(), r.image.as_deref()?)))
        .collect();
    if !images.is_empty() {
        let (what, note) = match cfg.figure_mesh() {
            (mesh, _) if cfg.common.smoke => (mesh.to_string(), "; the bunny in a full run"),
            (_, short) => (format!("the {short}"), ""),
        };
        writeln!(
            md,
            "## {} coloured by meshlet (paper Figure 1{note})\n\nThe first view's direction, the camera moved in until {what} fills {:.0} % of the frame's height or width; task-shader culling on, so culled meshlets are absent.\n",
            capitalised(&what),
            100.0 * crate::render::FRAME_FILL
        )?;
        for (s, file) in images {
            writeln!(md, "{s}:\n\n![{s}]({file})\n")?;
        }
    }
    super::render_occlusion::write(&mut md, &cfg.occlusion, occlusion)?;
    write_experiments(cfg, &mut md, variants)?;
    write_file(cfg.common.out.join(cfg.tag.name("render.md")), md)?;
    write_file(
        cfg.common.out.join(cfg.tag.name("render.csv")),
        frame_table().csv(rows),
    )?;
    line_chart(
        &cfg.common.out.join(cfg.tag.name("render_per_triangle.svg")),
        "median ms per frame against triangles (no culling)",
        "triangles",
        "ms per frame",
        &series,
        Axes {
            zero_y: true,
            ..Axes::default()
        },
    )?;
    Ok(())
}

/// ms per frame per mesh and strategy: render.md's first table, and render.csv with the culling
/// shares and pipeline statistics too (render.md shows those in its second table).
fn frame_table<'a>() -> Table<'a, Row> {
    let ms = |times: fn(&Row) -> &Vec<f64>| {
        move |r: &Row| format!("{:.2} ({:.2})", median(times(r)), p95(times(r)))
    };
    let ms4 = |x: fn(&Row) -> f64| move |r: &Row| format!("{:.4}", x(r));
    let mut t = Table::new(Style::Compact)
        .col("mesh", Left, |r: &Row| r.mesh.clone())
        .col("triangles", Right, |r| r.triangles.to_string())
        .col("strategy", Left, |r| r.strategy.clone())
        .col("meshlets", Right, |r| r.meshlets.to_string());
    for (k, name) in [
        "frustum_culled_pct",
        "backface_culled_pct",
        "triangles_skipped_pct",
    ]
    .into_iter()
    .enumerate()
    {
        t = t.csv_only(name, move |r| format!("{:.3}", r.far[k]));
    }
    for (k, name) in [
        "near_frustum_culled_pct",
        "near_backface_culled_pct",
        "near_triangles_skipped_pct",
    ]
    .into_iter()
    .enumerate()
    {
        t = t.csv_only(name, move |r| format!("{:.3}", r.near[k]));
    }
    for (k, name) in ["task_invocations", "mesh_invocations", "primitives"]
        .into_iter()
        .enumerate()
    {
        t = t.csv_only(name, move |r| format!("{:.1}", r.invocations[k]));
    }
    t.md("mesh, culling: median (p95)", Right, ms(|r| &r.cull))
        .csv_only("mesh_cull_ms_median", ms4(|r| median(&r.cull)))
        .csv_only("mesh_cull_ms_p95", ms4(|r| p95(&r.cull)))
        .md("mesh, no culling: median (p95)", Right, ms(|r| &r.no_cull))
        .csv_only("mesh_nocull_ms_median", ms4(|r| median(&r.no_cull)))
        .csv_only("mesh_nocull_ms_p95", ms4(|r| p95(&r.no_cull)))
        .md("vertex pipeline: median (p95)", Right, ms(|r| &r.vertex))
        .csv_only("vertex_ms_median", ms4(|r| median(&r.vertex)))
        .csv_only("vertex_ms_p95", ms4(|r| p95(&r.vertex)))
        .md("mesh culling / vertex", Right, |r| {
            format!("{:.2}x", median(&r.cull) / median(&r.vertex))
        })
}

/// What the task shader skipped (the paper's Figure 7), far and close, with the pipeline
/// statistics, and the Figure-7 plot.
fn write_culling(cfg: &Config, md: &mut String, rows: &[Row]) -> Result<()> {
    writeln!(md, "\n## What the task shader skipped (paper Figure 7)\n")?;
    writeln!(md, "Share of meshlets culled by the frustum and by the normal cone (backface), and of triangles never sent to the mesh shader, per view; task and mesh-shader invocations and MESH_PRIMITIVES_GENERATED per frame (far views) from the pipeline queries. Far views see the whole mesh, so only close views give the frustum work.\n")?;
    writeln!(md, "| mesh | strategy | meshlets | far: frustum % | backface % | triangles skipped % | close: frustum % | backface % | triangles skipped % | task invocations | mesh invocations | primitives |")?;
    writeln!(
        md,
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for r in rows {
        writeln!(
            md,
            "| {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.0} | {:.0} | {:.0} |",
            r.mesh,
            r.strategy,
            r.meshlets,
            r.far[0],
            r.far[1],
            r.far[2],
            r.near[0],
            r.near[1],
            r.near[2],
            r.invocations[0],
            r.invocations[1],
            r.invocations[2]
        )?;
    }
    // Mean over the meshes per strategy.
    let mean = |s: &str, f: &dyn Fn(&Row) -> f64| {
        let v: Vec<f64> = rows.iter().filter(|r| r.strategy == s).map(f).collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    let cats: Vec<String> = cfg.strategy.clone();
    let series = |label: &str, stack: usize, f: &dyn Fn(&Row) -> f64| Bars {
        label: label.to_string(),
        values: cats.iter().map(|s| mean(s, f)).collect(),
        stack,
    };
    let bars = [
        series("far: frustum", 0, &|r| r.far[0]),
        series("far: backface", 0, &|r| r.far[1]),
        series("close: frustum", 1, &|r| r.near[0]),
        series("close: backface", 1, &|r| r.near[1]),
    ];
    writeln!(md, "\nMean over the meshes (left bar of each pair: far views; right: close views):\n\n![culled meshlets]({})\n", cfg.tag.name("render_culling.svg"))?;
    bar_chart(
        &cfg.common.out.join(cfg.tag.name("render_culling.svg")),
        "meshlets culled by the task shader, % (mean over the meshes)",
        "% of meshlets",
        &cats,
        &bars,
    )
}

/// The layout, meshlet-order and triangle-order experiments (Figures 12 and 10), with the
/// Figure-12 plot and render_experiments.csv.
fn write_experiments(cfg: &Config, md: &mut String, variants: &[Variant]) -> Result<()> {
    if variants.is_empty() {
        return Ok(());
    }
    let find = |v: &Variant, variant: &str| {
        variants.iter().find(|o| {
            o.mesh == v.mesh
                && o.strategy == v.strategy
                && o.experiment == v.experiment
                && o.variant == variant
        })
    };
    let mut csv = String::from("mesh,strategy,experiment,variant,bytes_per_triangle,local_miss_rate,frustum_culled_pct,backface_culled_pct,triangles_skipped_pct,cull_ms_median,cull_ms_p95,nocull_ms_median,nocull_ms_p95\n");
    for v in variants.iter().filter(|v| v.unfit.is_none()) {
        writeln!(
            csv,
            "{},{},{},{},{:.3},{:.4},{:.3},{:.3},{:.3},{:.4},{:.4},{:.4},{:.4}",
            v.mesh,
            v.strategy,
            v.experiment,
            v.variant,
            v.bytes_per_triangle,
            v.miss_rate,
            v.shares[0],
            v.shares[1],
            v.shares[2],
            median(&v.cull),
            p95(&v.cull),
            median(&v.no_cull),
            p95(&v.no_cull)
        )?;
    }
    write_file(
        cfg.common.out.join(cfg.tag.name("render_experiments.csv")),
        csv,
    )?;
    writeln!(md, "\n## Experiments\n")?;
    writeln!(md, "Each experiment renders its variants of the same meshlets over the same far views in interleaved order (view 0 for every variant, then view 1, ...), so machine noise hits them alike; ratios are of medians against the first variant (< 1: faster). Strategies: {}.\n", cfg.experiment_strategies().join(", "))?;

    writeln!(
        md,
        "### Descriptor layouts (paper §2, Tables 1–2, Figure 12)\n"
    )?;
    writeln!(md, "split: task descriptor with the exact f32 sphere and apex cone (48 B) + mesh descriptor (16 B); nvidia-a: 16 B with 20-bit offsets, 8-bit box and 24-bit cone (culling without an apex: the sphere-centre test); nvidia-b: 16 B with one 32-bit offset into a buffer of 16-bit indices where a meshlet's fit; monolithic: per-meshlet blocks with copied positions. Bytes per triangle count everything the mesh shader reads: descriptors, indices, triangles and positions.\n")?;
    writeln!(md, "| mesh | strategy | layout | bytes / triangle | backface culled % | culling: ms | / split | no culling: ms | / split |")?;
    writeln!(md, "|---|---|---|---:|---:|---:|---:|---:|---:|")?;
    let mut ratios: std::collections::BTreeMap<(String, String), Vec<f64>> = Default::default();
    for v in variants.iter().filter(|v| v.experiment == "descriptor") {
        if let Some(why) = &v.unfit {
            writeln!(
                md,
                "| {} | {} | {} | does not fit: {why} | | | | | |",
                v.mesh, v.strategy, v.variant
            )?;
            continue;
        }
        let Some(base) = find(v, DescriptorFormat::Split.name()) else {
            continue;
        };
        let (rc, rn) = (
            median(&v.cull) / median(&base.cull),
            median(&v.no_cull) / median(&base.no_cull),
        );
        ratios
            .entry((v.strategy.clone(), v.variant.clone()))
            .or_default()
            .push(rc);
        writeln!(
            md,
            "| {} | {} | {} | {:.1} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} |",
            v.mesh,
            v.strategy,
            v.variant,
            v.bytes_per_triangle,
            v.shares[1],
            median(&v.cull),
            rc,
            median(&v.no_cull),
            rn
        )?;
    }
    writeln!(
        md,
        "\nGeometric mean over the meshes of ms with culling relative to split:\n"
    )?;
    writeln!(
        md,
        "| strategy | {} |",
        DescriptorFormat::ALL.map(|f| f.name()).join(" | ")
    )?;
    writeln!(md, "|---|{}", "---:|".repeat(DescriptorFormat::ALL.len()))?;
    for s in &cfg.experiment_strategies() {
        let cells: Vec<String> = DescriptorFormat::ALL
            .iter()
            .map(|f| {
                ratios
                    .get(&(s.clone(), f.name().to_string()))
                    .map_or("–".into(), |r| format!("{:.3}", geomean(r)))
            })
            .collect();
        writeln!(md, "| {s} | {} |", cells.join(" | "))?;
    }
    let bars: Vec<Bars> = DescriptorFormat::ALL
        .iter()
        .enumerate()
        .map(|(i, f)| Bars {
            label: f.name().to_string(),
            values: cfg
                .experiment_strategies()
                .iter()
                .map(|s| {
                    ratios
                        .get(&(s.clone(), f.name().to_string()))
                        .map_or(0.0, |r| geomean(r))
                })
                .collect(),
            stack: i,
        })
        .collect();
    bar_chart(
        &cfg.common.out.join(cfg.tag.name("render_descriptors.svg")),
        "ms per frame with culling relative to split (geometric mean over the meshes)",
        "ratio to split",
        &cfg.experiment_strategies(),
        &bars,
    )?;
    writeln!(
        md,
        "\n![descriptor layouts]({})\n",
        cfg.tag.name("render_descriptors.svg")
    )?;

    for (experiment, other, title, note) in [
        (
            "meshlet order",
            "most triangles first",
            "### Meshlets ordered by primitive count (paper Figure 10)\n",
            "The same meshlets, their descriptors sorted by triangle count (most first, stable) against the build order.\n",
        ),
        (
            "triangle order",
            "optimised",
            "### Triangle order inside each meshlet (seed: \"Meshlet triangle locality matters\")\n",
            "Each meshlet's triangles reordered for vertex reuse (`--local-order`), local vertices renumbered in first use; the seed measured 10–15 % on NVIDIA when rasteriser bound. Miss rate: new vertices per triangle through an 8-entry FIFO inside each meshlet.\n",
        ),
    ] {
        writeln!(md, "{title}")?;
        writeln!(md, "{note}")?;
        writeln!(md, "| mesh | strategy | miss rate: as built | {other} | culling: ms as built | {other} | ratio | no culling: ms as built | {other} | ratio |")?;
        writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
        let mut all = Vec::new();
        for v in variants
            .iter()
            .filter(|v| v.experiment == experiment && v.variant == other)
        {
            let Some(base) = find(v, "as built") else {
                continue;
            };
            let (c0, c1, n0, n1) = (
                median(&base.cull),
                median(&v.cull),
                median(&base.no_cull),
                median(&v.no_cull),
            );
            all.push((v.strategy.clone(), c1 / c0, n1 / n0));
            writeln!(
                md,
                "| {} | {} | {:.3} | {:.3} | {:.2} | {:.2} | {:.3} | {:.2} | {:.2} | {:.3} |",
                v.mesh,
                v.strategy,
                base.miss_rate,
                v.miss_rate,
                c0,
                c1,
                c1 / c0,
                n0,
                n1,
                n1 / n0
            )?;
        }
        for s in &cfg.experiment_strategies() {
            let (c, n): (Vec<f64>, Vec<f64>) = all
                .iter()
                .filter(|a| &a.0 == s)
                .map(|a| (a.1, a.2))
                .unzip();
            writeln!(
                md,
                "| **geometric mean** | {s} | | | | | **{:.3}** | | | **{:.3}** |",
                geomean(&c),
                geomean(&n)
            )?;
        }
        writeln!(md)?;
    }
    Ok(())
}
