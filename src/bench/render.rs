//! `meshletlab bench render`: the mesh-shader pass against the vertex pipeline (Jensen et al. 2023
//! §4–5): per mesh × strategy, ms per frame (median, p95) with and without task-shader culling over
//! the seeded random-view protocol (first frame discarded), the share of meshlets and triangles the
//! task shader skipped (frustum and backface), the ns-per-triangle slope of frame time against
//! triangle count across the shared meshes (paper Table 6), and a meshlet-coloured image of the
//! bunny per strategy (paper Figure 1) -> results/render.md, render.csv, render_per_triangle.svg,
//! render_bunny_<strategy>.png.

use super::build::{mesh_files, mesh_name};
use super::plot::{line_chart, Axes, Series};
use super::{machine_note, median, today};
use crate::mesh::{self, Mesh};
use crate::meshlet::{validate, Limits, Meshlets};
use crate::render::{write_png, Camera, Context, Pass, Pipeline, Shading, HEIGHT, WIDTH};
use crate::strategy::{self, Options};
use anyhow::{Context as _, Result};
use indicatif::ProgressBar;
use std::fmt::Write as _;
use std::path::PathBuf;

/// The paper's Table 6: ns per triangle of its linear regressions on an RTX 2080 Ti (range over its
/// strategies).
pub const PAPER_NS_PER_TRIANGLE: (f64, f64) = (0.0899, 0.0974);

/// What to run.
#[derive(Clone, Debug)]
pub struct Config {
    /// Folder of meshes.
    pub meshes: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Meshlet limits.
    pub limits: Limits,
    /// Strategies (names).
    pub strategies: Vec<String>,
    /// Views per mesh (one more is rendered first and discarded).
    pub views: usize,
    /// Seed of the view sequence.
    pub seed: u64,
    /// Camera distance in bounding radii.
    pub distance: f32,
    /// No progress output.
    pub quiet: bool,
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

/// Frame times in ms of `how` over `views` (the first view rendered twice, once discarded), and
/// the summed culling counters.
fn frames(pass: &Pass, views: &[Camera], how: Pipeline) -> Result<(Vec<f64>, [u64; 5])> {
    pass.render(&views[0], how, Shading::Lit)?;
    let mut ms = Vec::with_capacity(views.len());
    let mut counts = [0u64; 5];
    for v in views {
        let f = pass.render(v, how, Shading::Lit)?;
        ms.push(f.gpu_ns * 1e-6);
        counts[0] += f.culled_frustum as u64;
        counts[1] += f.culled_cone as u64;
        counts[2] += f.drawn as u64;
        counts[3] += f.culled_triangles[0] as u64;
        counts[4] += f.culled_triangles[1] as u64;
    }
    Ok((ms, counts))
}

fn p95(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() as f64 * 0.95).ceil() as usize).clamp(1, v.len()) - 1]
}

struct Row {
    mesh: String,
    triangles: usize,
    strategy: String,
    meshlets: usize,
    cull: Vec<f64>,
    no_cull: Vec<f64>,
    vertex: Vec<f64>,
    frustum_pct: f64,
    backface_pct: f64,
    /// Share of the triangles the task shader skipped (frustum + backface).
    skipped_tri_pct: f64,
}

/// Runs the benchmark and writes the results.
pub fn run(cfg: &Config) -> Result<()> {
    let ctx = Context::new(false)?;
    let opts = Options::default();
    let files = mesh_files(&cfg.meshes)?;
    let mut rows = Vec::new();
    std::fs::create_dir_all(&cfg.out)?;
    let pb = if cfg.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new((files.len() * cfg.strategies.len()) as u64)
    };
    for path in &files {
        let name = mesh_name(path);
        let m: Mesh = mesh::load(path).with_context(|| format!("loading {}", path.display()))?;
        let views = Camera::random_views(&m, cfg.views.max(1), cfg.seed, cfg.distance);
        for s in &cfg.strategies {
            pb.set_message(format!("{name}: {s}"));
            let strat = strategy::by_name(s, &opts)?;
            let ml: Meshlets = strat.build(&m, cfg.limits);
            validate(&m, &ml, cfg.limits).with_context(|| format!("{name}: {s}"))?;
            let pass = Pass::new(&ctx, &m, &ml)?;
            let on = Pipeline::Mesh {
                frustum: true,
                cone: true,
                colour_ids: false,
            };
            let off = Pipeline::Mesh {
                frustum: false,
                cone: false,
                colour_ids: false,
            };
            let (cull, counts) = frames(&pass, &views, on)?;
            let (no_cull, _) = frames(&pass, &views, off)?;
            let (vertex, _) = frames(&pass, &views, Pipeline::Vertex)?;
            if name == "stanford_bunny" {
                let img = pass.render(
                    &views[0],
                    Pipeline::Mesh {
                        frustum: true,
                        cone: true,
                        colour_ids: true,
                    },
                    Shading::Lit,
                )?;
                write_png(
                    &cfg.out
                        .join(format!("render_bunny_{}.png", s.replace('+', "_"))),
                    WIDTH,
                    HEIGHT,
                    &img.pixels,
                )?;
            }
            let total = (ml.len() * views.len()).max(1) as f64;
            rows.push(Row {
                mesh: name.clone(),
                triangles: m.triangle_count(),
                strategy: s.clone(),
                meshlets: ml.len(),
                cull,
                no_cull,
                vertex,
                frustum_pct: 100.0 * counts[0] as f64 / total,
                backface_pct: 100.0 * counts[1] as f64 / total,
                skipped_tri_pct: 100.0 * (counts[3] + counts[4]) as f64
                    / (m.triangle_count() * views.len()).max(1) as f64,
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    write(cfg, &ctx, &rows)
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

fn write(cfg: &Config, ctx: &Context, rows: &[Row]) -> Result<()> {
    let mut md = String::new();
    writeln!(md, "# Mesh-shader rendering against the vertex pipeline\n")?;
    writeln!(
        md,
        "Generated by `meshletlab bench render` on {} — {}.",
        today(),
        machine_note()
    )?;
    writeln!(md, "Device: **{}** (Vulkan, VK_EXT_mesh_shader). {}×{}, 4× MSAA resolved, D32 depth, back faces culled by the rasteriser in both pipelines. {} seeded random views per mesh at {} bounding radii (seed {}), the first frame discarded; GPU time from timestamps around the draw. Limits {}/{}.\n", ctx.name, WIDTH, HEIGHT, cfg.views, cfg.distance, cfg.seed, cfg.limits.max_vertices, cfg.limits.max_triangles)?;
    writeln!(md, "On lavapipe the \"GPU\" is this machine's CPU cores running LLVM-compiled shaders: the ratios say how the two pipelines map onto a software rasteriser, not onto a GPU.\n")?;
    writeln!(md, "## ms per frame\n")?;
    writeln!(md, "| mesh | triangles | strategy | meshlets | meshlets culled: frustum % | backface % | triangles skipped % | mesh, culling: median (p95) | mesh, no culling: median (p95) | vertex pipeline: median (p95) | mesh culling / vertex |")?;
    writeln!(md, "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    let mut csv = String::from("mesh,triangles,strategy,meshlets,frustum_culled_pct,backface_culled_pct,triangles_skipped_pct,mesh_cull_ms_median,mesh_cull_ms_p95,mesh_nocull_ms_median,mesh_nocull_ms_p95,vertex_ms_median,vertex_ms_p95\n");
    for r in rows {
        let (a, b, c) = (median(&r.cull), median(&r.no_cull), median(&r.vertex));
        writeln!(
            md,
            "| {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.2} ({:.2}) | {:.2} ({:.2}) | {:.2} ({:.2}) | {:.2}x |",
            r.mesh,
            r.triangles,
            r.strategy,
            r.meshlets,
            r.frustum_pct,
            r.backface_pct,
            r.skipped_tri_pct,
            a,
            p95(&r.cull),
            b,
            p95(&r.no_cull),
            c,
            p95(&r.vertex),
            a / c
        )?;
        writeln!(
            csv,
            "{},{},{},{},{:.3},{:.3},{:.3},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4}",
            r.mesh,
            r.triangles,
            r.strategy,
            r.meshlets,
            r.frustum_pct,
            r.backface_pct,
            r.skipped_tri_pct,
            a,
            p95(&r.cull),
            b,
            p95(&r.no_cull),
            c,
            p95(&r.vertex)
        )?;
    }
    writeln!(md, "\n## Cost per triangle (paper Table 6)\n")?;
    writeln!(md, "Slope of a least-squares line through (triangles, median ms per frame) over the shared meshes, without culling so that every triangle is drawn. Paper (RTX 2080 Ti): {:.4}–{:.4} ns per triangle.\n", PAPER_NS_PER_TRIANGLE.0, PAPER_NS_PER_TRIANGLE.1)?;
    writeln!(md, "| pipeline | ns per triangle | intercept ms |")?;
    writeln!(md, "|---|---:|---:|")?;
    let mut series = Vec::new();
    let mut names: Vec<&str> = cfg.strategies.iter().map(String::as_str).collect();
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
        "\n![ms per frame against triangles](render_per_triangle.svg)\n"
    )?;
    writeln!(
        md,
        "## The bunny coloured by meshlet (paper Figure 1), first view\n"
    )?;
    for s in &cfg.strategies {
        writeln!(
            md,
            "{s}:\n\n![{s}](render_bunny_{}.png)\n",
            s.replace('+', "_")
        )?;
    }
    std::fs::write(cfg.out.join("render.md"), md)?;
    std::fs::write(cfg.out.join("render.csv"), csv)?;
    line_chart(
        &cfg.out.join("render_per_triangle.svg"),
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
