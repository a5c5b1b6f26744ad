//! `meshletlab bench compress`: compressed-meshlet sizes, errors and speeds on every shared mesh
//! and a multi-mesh scene -> results/compress.md, compress.csv, compress_fig8.csv and plots.
//!
//! Rows per mesh: laced wires and meshoptimizer's codec on the same qem 64/84 meshlets at the
//! paper's tolerance (the paper's setting, Tables 2, 4, 5), then both at 1e-4 of the
//! bounding-box diagonal, meshoptimizer's codec on its own best meshlets (meshopt 128/128, the
//! comparison the project sets). Every size is split into connectivity (topology and vertex
//! references), positions, headers and padding; errors are measured on the decoded positions;
//! encode and decode speeds are medians of interleaved runs on 1 and 2 threads. Figure 8 of the
//! paper: bits per vertex against maximum error for 8- to 16-bit quantisation, global (b bits
//! per axis over the bounding box) against local (laced wires' per-wire boxes, box headers included)
//! and meshoptimizer's per-meshlet anchors, with encode time.

use super::build::{mesh_files, mesh_name};
use super::plot::{bar_chart, line_chart, Axes, Bars, Series};
use super::table::{
    Align::{Left, Right},
    Style, Table,
};
use super::{create_dir, median, write_file, write_header, Common};
use crate::compress::Codec;
use crate::compress::{Encoded, Sizes};
use crate::mesh::{self, Mesh};
use crate::meshlet::{Limits, Meshlets};
use crate::strategy::{self, Options};
use anyhow::Result;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// What to run: the arguments of `meshletlab bench compress`.
#[derive(clap::Args, Clone, Debug)]
pub struct Config {
    /// Mesh folder, output folder, smoke run (one timing run), quiet.
    #[command(flatten)]
    pub common: Common,
    /// Interleaved timing runs (median reported).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
}

impl Config {
    /// Interleaved timing runs: one in a smoke run.
    pub fn runs(&self) -> usize {
        self.common.or_smoke(self.runs as usize, 1)
    }
}

/// The paper's published sizes (Mlakar et al. 2024, Tables 2, 4, 5; averages over their scanned
/// meshes at 14-bit quantisation).
pub mod paper {
    /// Laced wires: connectivity, bytes per triangle.
    pub const LACED_CONNECTIVITY: f64 = 2.01;
    /// Laced wires: geometry, bytes per vertex.
    pub const LACED_GEOMETRY: f64 = 5.14;
    /// IX and SC compact: bytes per triangle of connectivity.
    pub const IX_SC_COMPACT: f64 = 3.13;
    /// GI: bytes per triangle (three 32-bit indices) and quantised bytes per vertex.
    pub const GI: (f64, f64) = (12.0, 5.63);
}

/// meshoptimizer's codec with anchored positions measured out of tree at about 1e-4 of the
/// diagonal with 128/128 meshlets (figures measured outside this repository, bytes per triangle), and AMD's DGF range.
pub const OUT_OF_TREE: &[(&str, f64)] = &[
    ("stanford_bunny", 3.15),
    ("igea", 3.02),
    ("stanford_dragon_vrip", 2.76),
];

/// One measured encoding.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Mesh name.
    pub mesh: String,
    /// Triangles.
    pub triangles: usize,
    /// Vertices used by a triangle.
    pub vertices: usize,
    /// Codec (serialised by its command-line name).
    #[serde(serialize_with = "codec_name")]
    pub format: Codec,
    /// Strategy and limits of the meshlets.
    pub meshlets_from: String,
    /// Meshlet count.
    pub meshlets: usize,
    /// "paper" (14-bit tolerance) or "1e-4" (of the diagonal).
    pub setting: &'static str,
    /// Tolerance over the diagonal.
    pub tolerance_rel: f64,
    /// Bytes by kind.
    pub sizes: Sizes,
    /// Largest decoded position error over the diagonal.
    pub max_error_rel: f64,
    /// Mean decoded position error over the diagonal.
    pub mean_error_rel: f64,
    /// Stored vertices over used vertices.
    pub duplication: f64,
    /// Encode speed, M triangles/s on 1 and 2 threads.
    pub encode_mtps: [f64; 2],
    /// Decode speed (every meshlet at random access), M triangles/s on 1 and 2 threads.
    pub decode_mtps: [f64; 2],
}

/// A codec as the command line names it (`laced-wires`), not as Rust does.
fn codec_name<S: serde::Serializer>(c: &Codec, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(&c.name())
}

impl Row {
    fn per_tri(&self, bytes: usize) -> f64 {
        bytes as f64 / self.triangles.max(1) as f64
    }
    fn total_per_tri(&self) -> f64 {
        self.per_tri(self.sizes.total())
    }
}

fn build(mesh: &Mesh, strategy: &str, limits: Limits) -> Result<Meshlets> {
    let s = strategy::by_name(strategy, &Options::default())?;
    let ml = s.build(mesh, limits);
    crate::meshlet::validate(mesh, &ml, limits)
        .map_err(|e| anyhow::anyhow!("{strategy} {limits}: {e}"))?;
    Ok(ml)
}

fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?)
}

/// Decodes every meshlet; (max, mean) error against the source and the decoded-vertex count.
fn errors(mesh: &Mesh, format: Codec, enc: &Encoded) -> Result<(f64, f64)> {
    let mut worst = 0.0f64;
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for i in 0..enc.offsets.len() {
        let d = format.decode(enc, i)?;
        for (k, &v) in d.vertices.iter().enumerate() {
            let o = mesh.positions[v as usize];
            let e = (0..3)
                .map(|a| (d.positions[k][a] as f64 - o[a] as f64).powi(2))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(e);
            sum += e;
            n += 1;
        }
    }
    Ok((worst, sum / n.max(1) as f64))
}

/// Measures one configuration.
#[allow(clippy::too_many_arguments)]
fn measure(
    name: &str,
    mesh: &Mesh,
    ml: &Meshlets,
    from: &str,
    format: Codec,
    (setting, tolerance): (&'static str, f64),
    runs: usize,
    pools: &[rayon::ThreadPool; 2],
) -> Result<Row> {
    let enc = format.encode(mesh, ml, tolerance)?;
    let mut enc_t = [Vec::new(), Vec::new()];
    let mut dec_t = [Vec::new(), Vec::new()];
    for _ in 0..runs {
        for (k, p) in pools.iter().enumerate() {
            let t = Instant::now();
            let e = p.install(|| format.encode(mesh, ml, tolerance))?;
            enc_t[k].push(t.elapsed().as_secs_f64());
            std::hint::black_box(e);
            let t = Instant::now();
            let ok = p.install(|| {
                (0..enc.offsets.len())
                    .into_par_iter()
                    .all(|i| format.decode(&enc, i).is_ok())
            });
            dec_t[k].push(t.elapsed().as_secs_f64());
            anyhow::ensure!(ok, "{name}: a meshlet does not decode");
        }
    }
    let diag = mesh.bounding_box_diagonal() as f64;
    let (worst, mean) = errors(mesh, format, &enc)?;
    anyhow::ensure!(
        worst <= tolerance * 3f64.sqrt() * (1.0 + 1e-6),
        "{name}: error {worst} above the tolerance {tolerance} (per axis)"
    );
    let used = {
        let mut u = vec![false; mesh.vertex_count()];
        for &v in &mesh.indices {
            u[v as usize] = true;
        }
        u.iter().filter(|&&b| b).count()
    };
    // Positions stored: once per vertex (laced wires, IX, GI), per meshlet vertex (meshopt,
    // SC), per corner (TS).
    let stored = match format {
        Codec::LacedWires | Codec::Ix | Codec::IxCompact | Codec::Gi | Codec::GiCompact => used,
        Codec::Ts | Codec::TsCompact => 3 * mesh.triangle_count(),
        Codec::Meshopt | Codec::Sc | Codec::ScCompact => ml.vertices.len(),
    };
    let tris = mesh.triangle_count() as f64 / 1e6;
    Ok(Row {
        mesh: name.to_string(),
        triangles: mesh.triangle_count(),
        vertices: used,
        format,
        meshlets_from: from.to_string(),
        meshlets: ml.len(),
        setting,
        tolerance_rel: tolerance / diag,
        sizes: enc.sizes,
        max_error_rel: worst / diag,
        mean_error_rel: mean / diag,
        duplication: stored as f64 / used.max(1) as f64,
        encode_mtps: [0, 1].map(|k| tris / median(&enc_t[k])),
        decode_mtps: [0, 1].map(|k| tris / median(&dec_t[k])),
    })
}

/// A scene of the meshes under 100 k triangles side by side, each scaled to a unit diagonal (a
/// set of similar-sized objects), as one mesh.
fn scene(files: &[PathBuf]) -> Result<(String, Mesh)> {
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut indices = Vec::new();
    let mut names = Vec::new();
    let mut x = 0.0f32;
    for f in files {
        let m = mesh::load(f)?;
        if m.triangle_count() > 100_000 {
            continue;
        }
        let (lo, hi) = m.bounding_box();
        let scale = 1.0 / m.bounding_box_diagonal().max(f32::MIN_POSITIVE);
        let base = positions.len() as u32;
        positions.extend(m.positions.iter().map(|p| {
            [
                x + (p[0] - lo.x) * scale,
                (p[1] - lo.y) * scale,
                (p[2] - lo.z) * scale,
            ]
        }));
        indices.extend(m.indices.iter().map(|&i| i + base));
        x += (hi.x - lo.x) * scale * 1.1;
        names.push(mesh_name(f));
    }
    let m = Mesh::new(positions, indices, std::path::Path::new("scene"))?;
    Ok((format!("scene ({})", names.len()), m))
}

/// Runs the benchmark.
pub fn run(cfg: &Config) -> Result<Vec<Row>> {
    let files = mesh_files(&cfg.common.meshes_dir()?)?;
    create_dir(&cfg.common.out)?;
    let pools = [crate::common::one_thread_pool(), pool(2)?];
    let mut meshes: Vec<(String, Mesh)> = Vec::new();
    for f in &files {
        meshes.push((mesh_name(f), mesh::load(f)?));
    }
    meshes.push(scene(&files)?);
    let bar = super::progress::bar(cfg.common.quiet, meshes.len() as u64);
    let paper = Limits::new(64, 84).expect("paper limits");
    let big = Limits::new(128, 128).expect("128/128");
    let mut rows = Vec::new();
    let mut fig8 = Vec::new();
    for (name, m) in &meshes {
        bar.set_message(name.clone());
        let diag = m.bounding_box_diagonal() as f64;
        let qem = build(m, "qem", paper)?;
        let mo = build(m, "meshopt", big)?;
        let full = build(m, "meshopt", Limits::new(64, 126).expect("64/126"))?;
        let t14 = ("paper", crate::compress::paper_tolerance(m));
        let t4 = ("1e-4", 1e-4 * diag);
        for (ml, from, format, t) in [
            (&qem, "qem 64/84", Codec::LacedWires, t14),
            (&qem, "qem 64/84", Codec::Meshopt, t14),
            (&qem, "qem 64/84", Codec::LacedWires, t4),
            (&full, "meshopt 64/126", Codec::LacedWires, t4),
            (&qem, "qem 64/84", Codec::Meshopt, t4),
            (&mo, "meshopt 128/128", Codec::Meshopt, t4),
        ] {
            rows.push(measure(name, m, ml, from, format, t, cfg.runs(), &pools)?);
        }
        // The paper's comparison formats on the same meshlets (Tables 2, 4, 5).
        for format in Codec::ALL.into_iter().skip(2) {
            rows.push(measure(
                name,
                m,
                &qem,
                "qem 64/84",
                format,
                t14,
                cfg.runs(),
                &pools,
            )?);
        }
        // Figure 8: b bits per axis over the largest extent.
        let (lo, hi) = m.bounding_box();
        let extent = (hi - lo).max_element() as f64;
        for b in 8..=16u32 {
            let t = extent / (1u64 << b) as f64 / 2.0;
            for (ml, format, label) in [
                (&qem, Codec::LacedWires, "local: laced wires (qem 64/84)"),
                (&mo, Codec::Meshopt, "local: meshopt anchors (128/128)"),
            ] {
                let t0 = Instant::now();
                let enc = format.encode(m, ml, t)?;
                let secs = t0.elapsed().as_secs_f64();
                let (worst, _) = errors(m, format, &enc)?;
                let vertices = rows.last().map_or(1, |r: &Row| r.vertices) as f64;
                // Geometry: positions plus the boxes (wire or meshlet headers hold the anchors).
                let bits =
                    8.0 * (enc.sizes.positions + enc.sizes.geometry_headers) as f64 / vertices;
                fig8.push((name.clone(), b, label, worst / diag, bits, secs));
            }
            // Global: b bits per axis for every vertex; error of the same grid.
            let e = crate::compress::grid_exponent(t);
            let o = lo.to_array();
            let worst = m
                .positions
                .iter()
                .map(|p| {
                    (0..3)
                        .map(|a| {
                            let q = crate::compress::quantise(p[a], o[a], e);
                            (crate::compress::dequantise(q, o[a], e) as f64 - p[a] as f64).powi(2)
                        })
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max);
            fig8.push((name.clone(), b, "global", worst / diag, 3.0 * b as f64, 0.0));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    write(cfg, &rows, &fig8)?;
    Ok(rows)
}

type Fig8 = (String, u32, &'static str, f64, f64, f64);

fn write(cfg: &Config, rows: &[Row], fig8: &[Fig8]) -> Result<()> {
    write_file(cfg.common.out.join("compress.csv"), encodings().csv(rows))?;
    let mut f8 = String::from(
        "mesh,bits_per_axis,series,max_error_rel,geometry_bits_per_vertex,encode_seconds\n",
    );
    for (m, b, s, e, bits, secs) in fig8 {
        writeln!(f8, "{m},{b},{s},{e:.4e},{bits:.3},{secs:.4}")?;
    }
    write_file(cfg.common.out.join("compress_fig8.csv"), f8)?;

    // Figure 8 per mesh.
    let mut names: Vec<&String> = fig8.iter().map(|f| &f.0).collect();
    names.dedup();
    let mut plots = Vec::new();
    for name in &names {
        let series: Vec<Series> = [
            "global",
            "local: laced wires (qem 64/84)",
            "local: meshopt anchors (128/128)",
        ]
        .iter()
        .map(|&s| Series {
            label: s.to_string(),
            points: fig8
                .iter()
                .filter(|f| &f.0 == *name && f.2 == s)
                .map(|f| (f.3, f.4))
                .collect(),
        })
        .collect();
        let file = format!(
            "compress_fig8_{}.svg",
            name.split(' ').next().unwrap_or(name)
        );
        line_chart(
            &cfg.common.out.join(&file),
            &format!("{name}: geometry bits per vertex against maximum error (8-16 bits)"),
            "maximum error / bounding-box diagonal",
            "bits per vertex (positions and boxes)",
            &series,
            Axes {
                log_x: true,
                log_y: false,
                zero_y: true,
            },
        )?;
        plots.push(file);
    }
    // Total bytes per triangle at 1e-4: laced wires against the peer.
    let at4: Vec<&Row> = rows.iter().filter(|r| r.setting == "1e-4").collect();
    let cats: Vec<String> = names.iter().map(|s| s.to_string()).collect();
    let pick = |f: Codec, from: &str| -> Vec<f64> {
        cats.iter()
            .map(|c| {
                at4.iter()
                    .find(|r| &r.mesh == c && r.format == f && r.meshlets_from == from)
                    .map_or(0.0, |r| r.total_per_tri())
            })
            .collect()
    };
    bar_chart(
        &cfg.common.out.join("compress_sizes.svg"),
        "Bytes per triangle at 1e-4 of the diagonal (all bytes)",
        "bytes per triangle",
        &cats,
        &[
            Bars {
                label: "laced wires (qem 64/84)".into(),
                values: pick(Codec::LacedWires, "qem 64/84"),
                stack: 0,
            },
            Bars {
                label: "laced wires (meshopt 64/126)".into(),
                values: pick(Codec::LacedWires, "meshopt 64/126"),
                stack: 3,
            },
            Bars {
                label: "meshopt codec (meshopt 128/128)".into(),
                values: pick(Codec::Meshopt, "meshopt 128/128"),
                stack: 1,
            },
            Bars {
                label: "meshopt codec (qem 64/84)".into(),
                values: pick(Codec::Meshopt, "qem 64/84"),
                stack: 2,
            },
        ],
    )?;

    let mut md = String::new();
    write_header(
        &mut md,
        "Compressed meshlets",
        &format!("meshletlab bench compress --runs {}", cfg.runs()),
        "",
        cfg.common.smoke_out(),
    );
    writeln!(
        md,
        "Sizes count every byte of the encoding: connectivity (topology and vertex references), positions, headers (per-meshlet and per-wire headers, offset tables), culling records (laced wires' 8 bytes per meshlet; the other formats carry none) and padding (the paper's 32-bit words). Errors are Euclidean, measured on decoded positions, over the bounding-box diagonal; the tolerance is per axis. Duplication: stored vertices over used vertices. Speeds: M triangles/s, median of {} interleaved runs on 1 and 2 threads; decode = every meshlet decoded at random access.\n",
        cfg.runs()
    )?;
    writeln!(
        md,
        "## The paper's setting: qem 64/84 meshlets, 14-bit tolerance\n"
    )?;
    writeln!(md, "Paper (Mlakar et al. 2024, Tables 2, 4, 5): laced wires {:.2} B/triangle connectivity, {:.2} B/vertex geometry; IX/SC compact {:.2} B/triangle; GI {:.0} B/triangle, {:.2} B/vertex quantised. Ours: geometry = positions and the boxes that place them (anchors, bit widths, the wire table) per vertex; the other headers (counts, item lists, offsets) are counted apart.\n", paper::LACED_CONNECTIVITY, paper::LACED_GEOMETRY, paper::IX_SC_COMPACT, paper::GI.0, paper::GI.1)?;
    let is_paper =
        |r: &&Row| r.setting == "paper" && matches!(r.format, Codec::LacedWires | Codec::Meshopt);
    writeln!(md, "{}", encodings().markdown(rows.iter().filter(is_paper)))?;
    writeln!(
        md,
        "\n### The paper's comparison formats on the same meshlets\n"
    )?;
    writeln!(md, "Each cell: connectivity B/triangle / geometry B/vertex (positions and boxes) / total B/triangle. Basic formats store f32 positions (error 0); compact ones quantise on the same grid as laced wires. Paper: IX/SC compact {:.2} B/triangle connectivity, GI {:.0} B/triangle and {:.2} B/vertex quantised; laced wires {:.2} / {:.2}.\n", paper::IX_SC_COMPACT, paper::GI.0, paper::GI.1, paper::LACED_CONNECTIVITY, paper::LACED_GEOMETRY)?;
    let formats: Vec<Codec> = Codec::ALL.into_iter().skip(1).collect();
    writeln!(
        md,
        "| mesh | {} |",
        formats
            .iter()
            .map(|f| f.name())
            .collect::<Vec<_>>()
            .join(" | ")
    )?;
    writeln!(md, "|---|{}", "---:|".repeat(formats.len()))?;
    for c in &names {
        let cells: Vec<String> = formats
            .iter()
            .map(|&f| {
                rows.iter()
                    .find(|r| {
                        &r.mesh == *c
                            && r.format == f
                            && r.setting == "paper"
                            && r.meshlets_from == "qem 64/84"
                    })
                    .map_or("-".into(), |r| {
                        let v = r.vertices.max(1) as f64;
                        format!(
                            "{:.2} / {:.2} / **{:.2}**",
                            r.per_tri(r.sizes.connectivity),
                            (r.sizes.positions + r.sizes.geometry_headers) as f64 / v,
                            r.total_per_tri()
                        )
                    })
            })
            .collect();
        writeln!(md, "| {c} | {} |", cells.join(" | "))?;
    }
    writeln!(
        md,
        "\n## At 1e-4 of the diagonal: laced wires against meshoptimizer's codec\n"
    )?;
    writeln!(md, "The goal: laced wires no larger than meshoptimizer's codec with anchored positions at the same maximum error (both use one grid, so the error is the same). Out-of-tree measurement for meshoptimizer's codec at 128/128: {}; AMD's DGF blocks need 3.8-5.0 B/triangle on the same meshes (quoted, not built).\n", OUT_OF_TREE.iter().map(|(m, b)| format!("{m} {b:.2}")).collect::<Vec<_>>().join(", "))?;
    writeln!(md, "{}", encodings().markdown(at4.iter().copied()))?;
    writeln!(md, "\nBest laced-wire meshlets against the peer at its best setting (ratio < 1: laced wires smaller). The peer carries no culling data; laced wires carry 8 bytes per meshlet, so the ratio is given without and with them:\n")?;
    writeln!(md, "| mesh | laced wires B/tri | from | without culling | meshopt codec 128/128 B/tri | ratio without culling | ratio with | out-of-tree peer |")?;
    writeln!(md, "|---|---:|---|---:|---:|---:|---:|---:|")?;
    for c in &cats {
        let l = at4
            .iter()
            .filter(|r| &r.mesh == c && r.format == Codec::LacedWires)
            .min_by(|a, b| a.total_per_tri().total_cmp(&b.total_per_tri()));
        let p = at4.iter().find(|r| {
            &r.mesh == c && r.format == Codec::Meshopt && r.meshlets_from == "meshopt 128/128"
        });
        if let (Some(l), Some(p)) = (l, p) {
            let oot = OUT_OF_TREE
                .iter()
                .find(|o| o.0 == c.as_str())
                .map_or("-".to_string(), |o| format!("{:.2}", o.1));
            writeln!(
                md,
                "| {c} | {:.2} | {} | {:.2} | {:.2} | {:.3} | {:.3} | {oot} |",
                l.total_per_tri(),
                l.meshlets_from,
                l.per_tri(l.sizes.total() - l.sizes.culling),
                p.total_per_tri(),
                l.per_tri(l.sizes.total() - l.sizes.culling) / p.total_per_tri(),
                l.total_per_tri() / p.total_per_tri()
            )?;
        }
    }
    writeln!(md, "\n![bytes per triangle](compress_sizes.svg)\n")?;
    writeln!(
        md,
        "## Figure 8: geometry bits per vertex against maximum error\n"
    )?;
    writeln!(md, "8- to 16-bit quantisation of the largest extent; global = b bits per axis for every vertex; local = the per-wire (laced wires) or per-meshlet (meshoptimizer, duplicates counted) anchored boxes, box headers included. Data: compress_fig8.csv (with encode times).\n")?;
    for p in &plots {
        writeln!(md, "![{p}]({p})")?;
    }
    write_file(cfg.common.out.join("compress.md"), md)?;
    Ok(())
}

/// Every encoding: compress.csv in bytes, and compress.md's tables of the paper's setting and of
/// 1e-4 of the diagonal in bits per triangle.
fn encodings<'a>() -> Table<'a, Row> {
    let bytes = |part: fn(&Sizes) -> usize| move |r: &Row| part(&r.sizes).to_string();
    let bits = |part: fn(&Sizes) -> usize| {
        move |r: &Row| format!("{:.1}", 8.0 * r.per_tri(part(&r.sizes)))
    };
    let per_vertex = |part: fn(&Sizes) -> usize| {
        move |r: &Row| format!("{:.2}", part(&r.sizes) as f64 / r.vertices.max(1) as f64)
    };
    let mtps = |x: fn(&Row) -> [f64; 2]| move |r: &Row| format!("{:.1} / {:.1}", x(r)[0], x(r)[1]);
    let mtps_k = |x: fn(&Row) -> [f64; 2], k: usize| move |r: &Row| format!("{:.2}", x(r)[k]);
    Table::new(Style::Compact)
        .col("mesh", Left, |r: &Row| r.mesh.clone())
        .csv_only("triangles", |r| r.triangles.to_string())
        .csv_only("vertices", |r| r.vertices.to_string())
        .col("format", Left, |r| r.format.name())
        .renamed("meshlets from", "meshlets_from", Left, |r| {
            r.meshlets_from.to_string()
        })
        .col("meshlets", Right, |r| r.meshlets.to_string())
        .csv_only("setting", |r| r.setting.to_string())
        .csv_only("tolerance_rel", |r| format!("{:.3e}", r.tolerance_rel))
        .csv_only("connectivity_bytes", bytes(|s| s.connectivity))
        .csv_only("position_bytes", bytes(|s| s.positions))
        .csv_only("header_bytes", bytes(|s| s.headers))
        .csv_only("geometry_header_bytes", bytes(|s| s.geometry_headers))
        .csv_only("culling_bytes", bytes(|s| s.culling))
        .csv_only("padding_bytes", bytes(|s| s.padding))
        .csv_only("total_bytes", bytes(Sizes::total))
        .split(
            "B/tri",
            Right,
            |r| format!("**{:.2}**", r.total_per_tri()),
            "bytes_per_triangle",
            |r| format!("{:.4}", r.total_per_tri()),
        )
        .md("connectivity bits/tri", Right, bits(|s| s.connectivity))
        .md("position bits/tri", Right, bits(|s| s.positions))
        .md("header bits/tri", Right, bits(|s| s.headers))
        .md("culling bits/tri", Right, bits(|s| s.culling))
        .md("padding bits/tri", Right, bits(|s| s.padding))
        .md("position B/vertex", Right, per_vertex(|s| s.positions))
        .md(
            "geometry B/vertex",
            Right,
            per_vertex(|s| s.positions + s.geometry_headers),
        )
        .split(
            "max err",
            Right,
            |r| format!("{:.2e}", r.max_error_rel),
            "max_error_rel",
            |r| format!("{:.3e}", r.max_error_rel),
        )
        .split(
            "mean err",
            Right,
            |r| format!("{:.2e}", r.mean_error_rel),
            "mean_error_rel",
            |r| format!("{:.3e}", r.mean_error_rel),
        )
        .split(
            "dup",
            Right,
            |r| format!("{:.2}", r.duplication),
            "duplication",
            |r| format!("{:.3}", r.duplication),
        )
        .md("encode 1t / 2t", Right, mtps(|r| r.encode_mtps))
        .csv_only("encode_mtps_1t", mtps_k(|r| r.encode_mtps, 0))
        .csv_only("encode_mtps_2t", mtps_k(|r| r.encode_mtps, 1))
        .md("decode 1t / 2t", Right, mtps(|r| r.decode_mtps))
        .csv_only("decode_mtps_1t", mtps_k(|r| r.decode_mtps, 0))
        .csv_only("decode_mtps_2t", mtps_k(|r| r.decode_mtps, 1))
}
