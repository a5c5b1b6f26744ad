//! `meshletlab bench compress-render`: compressed meshlets drawn from their encoded bytes against
//! the uncompressed layouts, per shared mesh and on a multi-mesh scene -> results/
//! compress-render.md, compress-render.csv and compress_render_tradeoff.svg (Mlakar et al. 2024,
//! Table 2's memory and Table 6's size against speed).
//!
//! Every variant draws the same meshopt 64/126 meshlets (laced wires take at most 64 vertices) at
//! the paper's 14-bit tolerance, from the same framed random views, interleaved view by view so
//! that a slow spell of a noisy machine hits every variant alike; one frame per variant is drawn
//! first and discarded. Variants: the uncompressed split layout (task + mesh shaders, with and
//! without culling) and the vertex pipeline (indexed f32 positions), laced wires (with and without
//! culling from its records), SC and IX compact (mesh shaders; no culling data in these formats),
//! GI and TS compact (vertex pulling). meshoptimizer's codec has no shader decoder (a byte stream
//! for the CPU): its size is listed, not its speed. Before any timing every variant's first view
//! is compared with its reference image (the uncompressed pass over the CPU-decoded meshlets) and
//! the run stops on a difference.

use super::build::{mesh_files, mesh_name};
use super::plot::{line_chart, Axes, Series};
use super::{create_dir, is_lavapipe, median, p95, write_file, write_header, Common, Tag};
use crate::compress::paper_tolerance;
use crate::compress::Codec;
use crate::mesh::{self, Mesh};
use crate::meshlet::{Limits, Meshlets};
use crate::render::compressed::{decoded_reference, prepare, FORMATS};
use crate::render::{Camera, Context, Pass, Pipeline, Shading, HEIGHT, WIDTH};
use crate::strategy::{self, Options};
use anyhow::{bail, Context as _, Result};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The paper's figures (Mlakar et al. 2024, RTX 4090, large scene, Tables 2 and 6).
pub mod paper {
    /// Laced wires, ms per frame on the large scene.
    pub const LACED_MS: f64 = 8.18;
    /// SC compact, ms per frame on the large scene.
    pub const SC_COMPACT_MS: f64 = 3.3;
    /// Laced wires' memory as a share of SC compact's.
    pub const LACED_MEMORY_OF_SC: f64 = 0.63;
    /// Kuth et al. (VMV 2024): strip-compressed meshlets decoded at about this many G triangles/s
    /// on an RX 7900 XTX.
    pub const KUTH_GTRIS: f64 = 26.0;
}

/// What to run: the arguments of `meshletlab bench compress-render`.
#[derive(clap::Args, Clone, Debug)]
pub struct Config {
    /// Mesh folder, output folder, smoke run (one view, one copy of the meshes in the scene),
    /// quiet.
    #[command(flatten)]
    pub common: Common,
    /// A suffix for the file names, for a run on another device.
    #[command(flatten)]
    pub tag: Tag,
    /// Views per mesh (framed random directions).
    #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u64).range(1..))]
    pub views: u64,
    /// Seed of the view sequence.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Copies of the ten shared meshes in the scene (5: the most for
    /// which GI compact's one buffer stays under lavapipe's 128 MiB storage binding).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..))]
    pub scene_copies: u64,
}

impl Config {
    /// Views per mesh: one in a smoke run.
    pub fn views(&self) -> usize {
        self.common.or_smoke(self.views as usize, 1)
    }

    /// Copies of the ten-mesh set in the scene: one in a smoke run.
    pub fn scene_copies(&self) -> usize {
        self.common.or_smoke(self.scene_copies as usize, 1)
    }
}

/// A variant: how a mesh's meshlets are held and drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Variant {
    SplitCull,
    SplitNoCull,
    VertexPipeline,
    Compressed(Codec, bool),
}

impl Variant {
    fn name(self) -> String {
        match self {
            Variant::SplitCull => "uncompressed split + culling".into(),
            Variant::SplitNoCull => "uncompressed split".into(),
            Variant::VertexPipeline => "uncompressed vertex pipeline".into(),
            Variant::Compressed(f, true) => format!("{} + culling", f.name()),
            Variant::Compressed(f, false) => f.name(),
        }
    }
}

/// One variant measured on one mesh.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Mesh name.
    pub mesh: String,
    /// Triangles.
    pub triangles: usize,
    /// Meshlets.
    pub meshlets: usize,
    /// Variant.
    pub variant: String,
    /// Bytes resident on the device (meshlet data, positions, tables).
    pub bytes: usize,
    /// ms per frame, one per view.
    pub ms: Vec<f64>,
    /// Meshlets culled by the task shader per frame (mean).
    pub culled: f64,
    /// The largest single storage buffer the variant binds (0 when not drawn).
    pub largest_binding: usize,
}

impl Row {
    fn median(&self) -> f64 {
        median(&self.ms)
    }
    fn bits_per_triangle(&self) -> f64 {
        8.0 * self.bytes as f64 / self.triangles.max(1) as f64
    }
}

/// Every shared mesh scaled to a unit diagonal on a grid, `copies` times over, as one mesh.
fn scene(files: &[PathBuf], copies: usize) -> Result<(String, Mesh)> {
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut indices = Vec::new();
    let mut k = 0usize;
    for _ in 0..copies {
        for f in files {
            let m = mesh::load(f)?;
            let (lo, _) = m.bounding_box();
            let scale = 1.0 / m.bounding_box_diagonal().max(f32::MIN_POSITIVE);
            let (gx, gz) = ((k % 6) as f32 * 1.1, (k / 6) as f32 * 1.1);
            let base = positions.len() as u32;
            positions.extend(m.positions.iter().map(|p| {
                [
                    gx + (p[0] - lo.x) * scale,
                    (p[1] - lo.y) * scale,
                    gz + (p[2] - lo.z) * scale,
                ]
            }));
            indices.extend(m.indices.iter().map(|&i| i + base));
            k += 1;
        }
    }
    let m = Mesh::new(positions, indices, std::path::Path::new("scene"))?;
    Ok((format!("scene ({} meshes)", k), m))
}

fn meshlets(m: &Mesh) -> Meshlets {
    strategy::by_name("meshopt", &Options::default())
        .expect("meshopt strategy")
        .build(m, Limits::DEFAULT)
}

/// Measures every variant on one mesh.
fn measure(ctx: &Context, name: &str, m: &Mesh, cfg: &Config) -> Result<Vec<Row>> {
    let ml = meshlets(m);
    let tolerance = paper_tolerance(m);
    let views = Camera::framed_views(
        m,
        cfg.views(),
        cfg.seed,
        WIDTH as f32 / HEIGHT as f32,
        crate::render::FRAME_FILL,
    );
    let split = Pass::new(ctx, m, &ml)?;
    let mut passes: Vec<(Variant, &Pass, usize)> = vec![
        (Variant::SplitCull, &split, split.device_bytes()),
        (Variant::SplitNoCull, &split, split.device_bytes()),
        (
            Variant::VertexPipeline,
            &split,
            12 * m.vertex_count() + 4 * m.indices.len(),
        ),
    ];
    let mut owned = Vec::new();
    for format in FORMATS {
        let enc = format.encode(m, &ml, tolerance)?;
        let up = prepare(&enc, format).with_context(|| format!("{name}: {}", format.name()))?;
        let pass =
            Pass::compressed(ctx, &up).with_context(|| format!("{name}: {}", format.name()))?;
        // The image check: the shaders decode what the CPU decodes.
        let (rm, rml) = decoded_reference(&enc, format)?;
        let reference = Pass::new(ctx, &rm, &rml)?;
        let how = pass.native(false);
        let ids = match how {
            Pipeline::Vertex => how,
            _ => Pipeline::mesh_ids(false),
        };
        let a = pass.render(&views[0], ids, Shading::Lit)?;
        let b = reference.render(&views[0], ids, Shading::Lit)?;
        if a.pixels != b.pixels {
            bail!(
                "{name}: {} draws a different image from its CPU-decoded reference",
                format.name()
            );
        }
        drop(reference);
        owned.push((format, pass, up.device_bytes()));
    }
    for (format, pass, bytes) in &owned {
        passes.push((Variant::Compressed(*format, false), pass, *bytes));
        if *format == Codec::LacedWires {
            passes.push((Variant::Compressed(*format, true), pass, *bytes));
        }
    }
    let how = |v: Variant, p: &Pass| match v {
        Variant::SplitCull => Pipeline::mesh(true),
        Variant::SplitNoCull => Pipeline::mesh(false),
        Variant::VertexPipeline => Pipeline::Vertex,
        Variant::Compressed(_, cull) => p.native(cull),
    };
    for (v, p, ..) in &passes {
        p.render(&views[0], how(*v, p), Shading::Lit)?;
    }
    let mut ms = vec![Vec::new(); passes.len()];
    let mut culled = vec![0u64; passes.len()];
    for view in &views {
        for (k, (v, p, ..)) in passes.iter().enumerate() {
            let f = p.render(view, how(*v, p), Shading::Lit)?;
            ms[k].push(f.gpu_ns * 1e-6);
            culled[k] += (f.culled_frustum + f.culled_cone) as u64;
        }
    }
    let meshopt = Codec::Meshopt.encode(m, &ml, tolerance)?;
    let mut rows: Vec<Row> = passes
        .iter()
        .zip(ms)
        .zip(culled)
        .map(|(((v, p, bytes), ms), culled)| Row {
            mesh: name.to_string(),
            triangles: m.triangle_count(),
            meshlets: ml.len(),
            variant: v.name(),
            bytes: *bytes,
            ms,
            culled: culled as f64 / views.len() as f64,
            largest_binding: p.largest_storage_binding() as usize,
        })
        .collect();
    rows.push(Row {
        mesh: name.to_string(),
        triangles: m.triangle_count(),
        meshlets: ml.len(),
        variant: "meshopt (no shader decoder)".into(),
        bytes: meshopt.sizes.total(),
        ms: Vec::new(),
        culled: 0.0,
        // Not drawn, so nothing bound.
        largest_binding: 0,
    });
    Ok(rows)
}

/// Runs the benchmark and writes results/.
pub fn run(cfg: &Config) -> Result<Vec<Row>> {
    let files = mesh_files(&cfg.common.meshes_dir()?)?;
    create_dir(&cfg.common.out)?;
    let ctx = Context::new(false)?;
    let bar = super::progress::bar(cfg.common.quiet, files.len() as u64 + 1);
    let mut rows = Vec::new();
    for f in &files {
        let name = mesh_name(f);
        bar.set_message(name.clone());
        let m = mesh::load(f)?;
        rows.extend(measure(&ctx, &name, &m, cfg)?);
        bar.inc(1);
    }
    bar.set_message("scene");
    let (name, m) = scene(&files, cfg.scene_copies())?;
    rows.extend(measure(&ctx, &name, &m, cfg)?);
    bar.finish_and_clear();
    write(cfg, &ctx, &rows)?;
    Ok(rows)
}

fn find<'a>(rows: &'a [Row], mesh: &str, variant: &str) -> Option<&'a Row> {
    rows.iter().find(|r| r.mesh == mesh && r.variant == variant)
}

fn geomean(xs: &[f64]) -> f64 {
    (xs.iter().map(|x| x.ln()).sum::<f64>() / xs.len().max(1) as f64).exp()
}

/// What the report's sections read: the rows, the meshes in run order (the scene last) and the
/// variants in the order the first mesh lists them.
struct Report<'a> {
    cfg: &'a Config,
    ctx: &'a Context,
    rows: &'a [Row],
    meshes: Vec<&'a str>,
    variants: Vec<&'a str>,
    scene: &'a str,
}

impl<'a> Report<'a> {
    fn new(cfg: &'a Config, ctx: &'a Context, rows: &'a [Row]) -> Self {
        let mut meshes: Vec<&str> = Vec::new();
        for r in rows {
            if !meshes.contains(&r.mesh.as_str()) {
                meshes.push(&r.mesh);
            }
        }
        let variants: Vec<&str> = rows
            .iter()
            .filter(|r| r.mesh == meshes[0])
            .map(|r| r.variant.as_str())
            .collect();
        let scene = *meshes.last().expect("the scene");
        Self {
            cfg,
            ctx,
            rows,
            meshes,
            variants,
            scene,
        }
    }

    /// The row of `variant` on `mesh`, which every run measures.
    fn row(&self, mesh: &str, variant: &str) -> &'a Row {
        find(self.rows, mesh, variant).expect("row")
    }

    /// Writes the setup: device, views, meshlets, scene and the shader decoders.
    fn write_setup(&self, md: &mut String) -> Result<()> {
        writeln!(md, "Device: **{}**. {}×{}, 4× MSAA, D32 depth, back faces culled by the rasteriser. {} framed random views per mesh (seed {}), interleaved across variants, one discarded warm-up frame per variant; GPU time from timestamps around the draw. Meshlets: meshopt 64/126 at the paper's tolerance (14-bit quantisation of the bounding box), the same for every variant. Scene: the ten shared meshes, each scaled to a unit diagonal, {} times over on a grid, as one mesh. Every compressed variant's first view was checked pixel for pixel against the uncompressed pass over its CPU-decoded meshlets before timing.\n", self.ctx.name, WIDTH, HEIGHT, self.cfg.views(), self.cfg.seed, self.cfg.scene_copies())?;
        if is_lavapipe(&self.ctx.name) {
            writeln!(md, "**Lavapipe's figures.** The \"GPU\" here is this machine's CPU cores running LLVM-compiled shaders and a software rasteriser at 1280×720 with 4× MSAA: rasterisation and shading take most of every frame, so decoding costs show up diluted, and a real GPU's balance (where the paper's laced wires take 2.5× SC compact's time) is not what these ratios measure. The memory columns are device-independent.\n")?;
        }
        writeln!(md, "Shader decoders: laced wires in the mesh shader ({}; parallel: item offsets by popcount, wire bases and lace cursors by prefix sums, delta wires by one prefix sum of their differences, strip corners by a scan over composed corner maps; four symbols per invocation, so no serial chain beyond four steps and a 32-wide scan per 128 symbols), SC and IX compact in the mesh shader, GI and TS compact by vertex pulling in the vertex shader. Culling: only laced wires carry culling data (8-byte records); the split layout has its exact spheres and cones.\n", if self.ctx.mesh_subgroups { format!("scans with subgroup operations, {} wide", self.ctx.subgroup_size) } else { "scans in workgroup memory".to_string() })?;
        Ok(())
    }

    /// Writes the bytes-per-triangle table (paper Table 2) and the scene's memory figures.
    fn write_bytes(&self, md: &mut String) -> Result<()> {
        writeln!(
            md,
            "## Bytes resident on the device per triangle (paper Table 2)\n"
        )?;
        let mut head = String::from("| mesh | triangles |");
        let mut sep = String::from("|---|---:|");
        let sized: Vec<&str> = self
            .variants
            .iter()
            .copied()
            .filter(|v| !v.ends_with(" + culling"))
            .collect();
        for v in &sized {
            write!(head, " {v} |")?;
            sep.push_str("---:|");
        }
        writeln!(md, "{head}\n{sep}")?;
        for mesh in &self.meshes {
            let first = self.row(mesh, self.variants[0]);
            write!(md, "| {mesh} | {} |", first.triangles)?;
            for v in &sized {
                let r = self.row(mesh, v);
                write!(md, " {:.2} |", r.bytes as f64 / r.triangles as f64)?;
            }
            writeln!(md)?;
        }
        let lw = self.row(self.scene, "laced-wires");
        let sc = self.row(self.scene, "sc-compact");
        let widest = self
            .rows
            .iter()
            .filter(|r| r.mesh == self.scene)
            .max_by_key(|r| r.largest_binding)
            .expect("rows");
        writeln!(md, "\nThe scene's largest storage binding is {}'s, {:.0} MiB of the device's {:.0} MiB limit (the pass draws one binding per buffer, unchunked): the scene is sized to fit it. The paper's scenes go to 109 M triangles on a 24 GB GPU.", widest.variant, widest.largest_binding as f64 / 1048576.0, self.ctx.max_storage_range as f64 / 1048576.0)?;
        writeln!(
            md,
            "\nOn the scene laced wires hold **{:.0} %** of SC compact's bytes (paper: {:.0} %).\n",
            100.0 * lw.bytes as f64 / sc.bytes as f64,
            100.0 * paper::LACED_MEMORY_OF_SC
        )?;
        Ok(())
    }

    /// Writes the ms-per-frame table, median and p95 per mesh and variant.
    fn write_frame_times(&self, md: &mut String) -> Result<()> {
        writeln!(md, "## ms per frame: median (p95)\n")?;
        let timed: Vec<&str> = self
            .variants
            .iter()
            .copied()
            .filter(|v| find(self.rows, self.meshes[0], v).is_some_and(|r| !r.ms.is_empty()))
            .collect();
        let mut head = String::from("| mesh |");
        let mut sep = String::from("|---|");
        for v in &timed {
            write!(head, " {v} |")?;
            sep.push_str("---:|");
        }
        writeln!(md, "{head}\n{sep}")?;
        for mesh in &self.meshes {
            write!(md, "| {mesh} |")?;
            for v in &timed {
                let r = self.row(mesh, v);
                write!(md, " {:.2} ({:.2}) |", r.median(), p95(&r.ms))?;
            }
            writeln!(md)?;
        }
        Ok(())
    }

    /// Writes the culled-meshlets table: laced wires' records against the split layout's bounds.
    fn write_culled(&self, md: &mut String) -> Result<()> {
        writeln!(md, "\nMeshlets culled per frame (mean over the views): laced wires' 8-byte records against the split layout's exact spheres and apex cones.\n")?;
        writeln!(
            md,
            "| mesh | meshlets | uncompressed split + culling | laced-wires + culling |"
        )?;
        writeln!(md, "|---|---:|---:|---:|")?;
        for mesh in &self.meshes {
            let a = self.row(mesh, "uncompressed split + culling");
            let b = self.row(mesh, "laced-wires + culling");
            writeln!(
                md,
                "| {mesh} | {} | {:.0} | {:.0} |",
                a.meshlets, a.culled, b.culled
            )?;
        }
        Ok(())
    }

    /// Writes the frame-time ratios against the targets, per mesh and as geometric means.
    fn write_ratios(&self, md: &mut String) -> Result<()> {
        let ratios: [(&str, &str, &str); 5] = [
            ("laced wires / SC compact", "laced-wires", "sc-compact"),
            (
                "laced wires + culling / SC compact",
                "laced-wires + culling",
                "sc-compact",
            ),
            (
                "laced wires / uncompressed split",
                "laced-wires",
                "uncompressed split",
            ),
            (
                "laced wires + culling / uncompressed split + culling",
                "laced-wires + culling",
                "uncompressed split + culling",
            ),
            (
                "SC compact / uncompressed split",
                "sc-compact",
                "uncompressed split",
            ),
        ];
        writeln!(md, "\n## Frame-time ratios (targets: laced wires ≤ 2× SC compact, ≤ 1.5× the uncompressed split layout, goal ≤ 1.15×)\n")?;
        writeln!(md, "Paper (RTX 4090, large scene): laced wires {:.2} ms against {:.1} ms for SC compact, {:.2}×.\n", paper::LACED_MS, paper::SC_COMPACT_MS, paper::LACED_MS / paper::SC_COMPACT_MS)?;
        let mut head = String::from("| mesh |");
        let mut sep = String::from("|---|");
        for (label, ..) in &ratios {
            write!(head, " {label} |")?;
            sep.push_str("---:|");
        }
        writeln!(md, "{head}\n{sep}")?;
        let ratio =
            |mesh: &str, a: &str, b: &str| self.row(mesh, a).median() / self.row(mesh, b).median();
        for mesh in &self.meshes {
            write!(md, "| {mesh} |")?;
            for (_, a, b) in &ratios {
                write!(md, " {:.2}× |", ratio(mesh, a, b))?;
            }
            writeln!(md)?;
        }
        write!(md, "| geometric mean |")?;
        for (_, a, b) in &ratios {
            let xs: Vec<f64> = self.meshes.iter().map(|m| ratio(m, a, b)).collect();
            write!(md, " **{:.2}×** |", geomean(&xs))?;
        }
        writeln!(md)?;
        Ok(())
    }

    /// Writes the size-against-speed table (paper Table 6) and its plot.
    fn write_tradeoff(&self, md: &mut String) -> Result<()> {
        writeln!(md, "\n## Size against speed (paper Table 6)\n")?;
        writeln!(md, "Scene ({} triangles): bits per triangle resident against million triangles per second (triangles / median frame time; with culling, triangles of culled meshlets count as handled). Kuth et al. decode strip-compressed meshlets at about {} G triangles/s on an RX 7900 XTX.\n", self.row(self.scene, "laced-wires").triangles, paper::KUTH_GTRIS)?;
        writeln!(md, "| variant | bits per triangle | M triangles/s |")?;
        writeln!(md, "|---|---:|---:|")?;
        let mut series = Vec::new();
        for v in &self.variants {
            let r = self.row(self.scene, v);
            if r.ms.is_empty() {
                writeln!(md, "| {v} | {:.1} | — |", r.bits_per_triangle())?;
                continue;
            }
            let speed = r.triangles as f64 / r.median() / 1e3;
            writeln!(md, "| {v} | {:.1} | {:.1} |", r.bits_per_triangle(), speed)?;
            series.push(Series {
                label: v.to_string(),
                points: vec![(r.bits_per_triangle(), speed)],
            });
        }
        line_chart(
            &self
                .cfg
                .common
                .out
                .join(self.cfg.tag.name("compress_render_tradeoff.svg")),
            &format!("{}: size against speed ({})", self.scene, self.ctx.name),
            "bits per triangle resident",
            "M triangles / s",
            &series,
            Axes::default(),
        )?;
        writeln!(
            md,
            "\n![size against speed]({})",
            self.cfg.tag.name("compress_render_tradeoff.svg")
        )?;
        Ok(())
    }

    /// Writes compress-render.csv: one line per mesh and variant.
    fn write_csv(&self) -> Result<()> {
        let mut csv = String::from(
            "mesh,triangles,meshlets,variant,bytes,ms_median,ms_p95,meshlets_culled_per_frame\n",
        );
        for r in self.rows {
            let (m, p) = if r.ms.is_empty() {
                (String::new(), String::new())
            } else {
                (format!("{:.4}", r.median()), format!("{:.4}", p95(&r.ms)))
            };
            writeln!(
                csv,
                "{},{},{},{},{},{m},{p},{:.1}",
                r.mesh, r.triangles, r.meshlets, r.variant, r.bytes, r.culled
            )?;
        }
        write_file(
            self.cfg
                .common
                .out
                .join(self.cfg.tag.name("compress-render.csv")),
            csv,
        )?;
        Ok(())
    }
}

/// Writes compress-render.md, its plot and compress-render.csv.
fn write(cfg: &Config, ctx: &Context, rows: &[Row]) -> Result<()> {
    let report = Report::new(cfg, ctx, rows);
    let mut md = String::new();
    write_header(
        &mut md,
        "Compressed meshlets rendered from their encoded bytes",
        &format!(
            "meshletlab bench compress-render --views {} --scene-copies {}{}",
            cfg.views(),
            cfg.scene_copies(),
            cfg.tag.flag()
        ),
        "",
        cfg.common.smoke_out(),
    );
    report.write_setup(&mut md)?;
    report.write_bytes(&mut md)?;
    report.write_frame_times(&mut md)?;
    report.write_culled(&mut md)?;
    report.write_ratios(&mut md)?;
    report.write_tradeoff(&mut md)?;
    write_file(cfg.common.out.join(cfg.tag.name("compress-render.md")), md)?;
    report.write_csv()
}
