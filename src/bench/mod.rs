//! Measurement: one evaluation path (build, validate, bounds, metrics) shared by `stats`, `demo` and
//! the `bench` commands, plus machine notes and tables for results/.
//!
//! Each bench's configuration is its command line: it derives [`clap::Args`] (the doc comments are
//! the `--help` text) and flattens [`Common`], so `meshletlab bench` only dispatches and a setting
//! that depends on another (a smoke run's single view, say) is a method of the configuration.

pub mod build;
pub mod compress;
pub mod compress_render;
pub mod fidelity;
pub mod floor;
pub mod gpu;
pub mod kmedoids;
pub mod lod;
pub mod paper;
pub mod plot;
pub mod progress;
pub mod render;
pub mod render_occlusion;
pub mod robustness;
pub mod smoke;
pub mod stability;
pub mod table;

use crate::mesh::Mesh;
use crate::meshlet::{bounds, validate, Limits, Meshlets, Metrics};
use crate::strategy::Strategy;
use anyhow::{Context as _, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Help of every bench's `--smoke`.
pub const SMOKE_HELP: &str =
    "Smoke run: tiny generated meshes, one run, tables into --out (not results/) \
    - checks that the bench runs and writes its files; no number in them is a measurement";

/// The arguments of every bench that reads the mesh folder.
#[derive(clap::Args, Clone, Debug)]
pub struct Common {
    /// Folder of meshes (default: $MESHLETLAB_MESHES or ../shared/meshes).
    // First in `--help` wherever the flatten stands; a bench that lists an argument between it and
    // --out declares that argument before the flatten with `display_order` 1 (or 2), so the help
    // reads as it did when each bench spelled its arguments out.
    #[arg(long, display_order = 0)]
    pub meshes: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// A smoke run ([`SMOKE_HELP`] is its help).
    #[arg(long, help = SMOKE_HELP)]
    pub smoke: bool,
    /// No progress output: the command's global `--quiet`, not an argument of the bench.
    #[arg(skip)]
    pub quiet: bool,
}

impl Common {
    /// The folder of meshes to run on: for a smoke run the smoke meshes, written into `out` now
    /// ([`smoke::prepare`]), else `meshes` (the command fills in its default).
    pub fn meshes_dir(&self) -> Result<PathBuf> {
        match (self.smoke, &self.meshes) {
            (true, _) => smoke::prepare(&self.out),
            (false, Some(dir)) => Ok(dir.clone()),
            (false, None) => anyhow::bail!("no mesh folder given (--meshes)"),
        }
    }

    /// The name and file of a bench's single mesh, `stem` in the mesh folder (`stem.ply.zst`), or
    /// for a smoke run the first smoke mesh (written into `out` now).
    pub fn mesh_file(&self, stem: &str) -> Result<(String, PathBuf)> {
        match self.smoke {
            true => Ok(smoke::first(&smoke::prepare(&self.out)?)),
            false => Ok((
                stem.to_string(),
                self.meshes_dir()?.join(format!("{stem}.ply.zst")),
            )),
        }
    }

    /// `n` for a full run, `smoke` for a smoke run.
    pub fn or_smoke<T>(&self, n: T, smoke: T) -> T {
        if self.smoke {
            smoke
        } else {
            n
        }
    }

    /// The output folder of a smoke run, `None` for a measurement: what [`write_header`] takes.
    pub fn smoke_out(&self) -> Option<&Path> {
        self.smoke.then_some(self.out.as_path())
    }
}

/// The help of every bench's `--tag`: one text, since the flag is one [`Tag`] wherever it appears.
pub const TAG_HELP: &str = "Suffix for every file this bench writes, for a run on another device \
    beside the committed results: `--tag TAG` writes results/<bench>-TAG.md and its tables and \
    plots tagged alike (letters, digits, '-')";

/// The `--tag` of the benches that measure a GPU: a run on another device writes its files beside
/// the committed lavapipe ones instead of over them.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct Tag {
    /// A suffix for the file names ([`TAG_HELP`] is its help).
    #[arg(long, value_name = "TAG", help = TAG_HELP, value_parser = parse_tag)]
    pub tag: Option<String>,
}

impl Tag {
    /// The flag as a command line spells it (` --tag TAG`), or empty: for the reports' headers.
    pub fn flag(&self) -> String {
        self.tag
            .as_ref()
            .map_or(String::new(), |t| format!(" --tag {t}"))
    }

    /// `file` with the tag before its extension (`gpu.md` -> `gpu-h100.md`); `file` untagged.
    pub fn name(&self, file: &str) -> String {
        match (&self.tag, file.rsplit_once('.')) {
            (None, _) => file.to_string(),
            (Some(t), Some((stem, ext))) => format!("{stem}-{t}.{ext}"),
            (Some(t), None) => format!("{file}-{t}"),
        }
    }
}

/// A tag goes into file names and markdown links, so it keeps to characters that need no escaping;
/// and it must not be the last word of a name the benches write (`--tag parallel` would turn
/// `render_bunny_bsphere.png` into the untagged `render_bunny_bsphere-parallel.png`).
fn parse_tag(s: &str) -> std::result::Result<String, String> {
    if s.is_empty() || !s.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
        return Err(format!(
            "tag {s:?}: use letters, digits and '-' only (it becomes part of file names)"
        ));
    }
    let taken = crate::strategy::NAMES
        .iter()
        .copied()
        .chain(crate::strategy::REFINE_SUFFIXES.iter().map(|r| r.0))
        .chain(["compress-render"])
        .any(|n| n.ends_with(&format!("-{s}")));
    if taken {
        return Err(format!(
            "tag {s:?} ends a strategy or bench name: its files would overwrite untagged ones"
        ));
    }
    Ok(s.to_string())
}

/// The value parser of every bench's strategy list (`-s a,b` or `-s a -s b`, with
/// `value_delimiter = ','`): the name trimmed, as `stats` trims it, and known, so that a typo is
/// refused before any mesh loads.
pub fn strategy_name(s: &str) -> std::result::Result<String, String> {
    let s = s.trim();
    if s.is_empty() {
        return Err("empty strategy name".into());
    }
    crate::strategy::by_name(s, &Default::default()).map_err(|e| e.to_string())?;
    Ok(s.to_string())
}

/// [`strategy_name`] for the lists where an empty name means "none" (`--experiment-strategy ''`).
pub fn strategy_name_or_none(s: &str) -> std::result::Result<String, String> {
    match s.trim() {
        "" => Ok(String::new()),
        n => strategy_name(n),
    }
}

/// The value parser of the bench options that are a distance, a threshold or a time: a finite
/// number above 0 (a NaN or an infinity would only fail, or run forever, after the meshes load).
pub fn positive<T>(s: &str) -> std::result::Result<T, String>
where
    T: std::str::FromStr + Into<f64> + Copy,
{
    let v: T = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    let x: f64 = v.into();
    if x.is_finite() && x > 0.0 {
        Ok(v)
    } else {
        Err(format!("{s} is not a finite number above 0"))
    }
}

/// Creates `dir` and its parents; the error names the folder first.
pub fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))
}

/// Writes a report, table or image file whole ([`crate::atomic::write`]); the error names the file
/// first.
pub fn write_file(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> Result<()> {
    let path = path.as_ref();
    crate::atomic::write(path, bytes).with_context(|| format!("{}: cannot write", path.display()))
}

/// Whether a device name is Mesa's lavapipe (whose "GPU" is this machine's CPU cores): the
/// benches say so only then.
pub fn is_lavapipe(device: &str) -> bool {
    device.contains("llvmpipe")
}

/// One strategy's result on one mesh.
#[derive(Clone, Debug, Serialize)]
pub struct Evaluation {
    /// Strategy name.
    pub strategy: String,
    /// Limits used.
    pub limits: Limits,
    /// Quality metrics (build time = median over the runs).
    pub metrics: Metrics,
    /// All measured build times in ms.
    pub times_ms: Vec<f64>,
    /// `None` when the validator accepted the output, else its message.
    pub invalid: Option<String>,
    /// Where the builds ran: `cpu`, or `gpu` (`--device gpu`).
    pub device: &'static str,
    /// Median build time in ms: on the GPU the whole run (uploads, kernels, readbacks and the
    /// host steps between them).
    pub build_ms: f64,
    /// GPU builds only: device creation and the first compilation of the strategy's pipelines,
    /// in ms, kept out of `build_ms`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub setup_ms: Option<f64>,
    /// The meshlets of the last run (not serialised).
    #[serde(skip)]
    pub meshlets: Meshlets,
}

/// Median of a non-empty slice.
/// The 95th percentile (nearest rank) of `xs` (not empty).
pub fn p95(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() as f64 * 0.95).ceil() as usize).clamp(1, v.len()) - 1]
}

/// The median (the mean of the two middle values for an even count; NaN for none).
pub fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// Builds `runs` times (>= 1), then validates the output and computes bounds and metrics.
/// Also checks that repeated builds agree (determinism); a difference is reported as invalid.
pub fn evaluate(mesh: &Mesh, strategy: &dyn Strategy, limits: Limits, runs: usize) -> Evaluation {
    let build = || Ok::<_, std::convert::Infallible>(strategy.build(mesh, limits));
    match evaluate_builds(mesh, strategy.name(), limits, runs, build) {
        Ok(e) => e,
        Err(never) => match never {},
    }
}

/// [`evaluate`] over any build of strategy `name` (on the GPU, say), stopping at its first error.
pub fn evaluate_builds<E>(
    mesh: &Mesh,
    name: &str,
    limits: Limits,
    runs: usize,
    mut build: impl FnMut() -> Result<Meshlets, E>,
) -> Result<Evaluation, E> {
    let mut times = Vec::with_capacity(runs.max(1));
    let mut first: Option<Meshlets> = None;
    let mut nondeterministic = false;
    for _ in 0..runs.max(1) {
        let t0 = Instant::now();
        let ml = build()?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        match &first {
            None => first = Some(ml),
            Some(f) => nondeterministic |= *f != ml,
        }
    }
    let ml = first.expect("at least one run");
    let mut invalid = validate(mesh, &ml, limits).err().map(|e| e.to_string());
    if nondeterministic && invalid.is_none() {
        invalid = Some("repeated builds gave different meshlets".into());
    }
    let b = bounds::compute_bounds(mesh, &ml);
    let med = median(&times);
    let metrics = Metrics::compute(
        mesh,
        &ml,
        limits,
        &b,
        Some(Duration::from_secs_f64(med / 1e3)),
    );
    Ok(Evaluation {
        strategy: name.to_string(),
        limits,
        metrics,
        times_ms: times,
        invalid,
        device: "cpu",
        build_ms: med,
        setup_ms: None,
        meshlets: ml,
    })
}

/// A short description of this machine and build for results/ headers.
pub fn machine_note() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let os = std::fs::read_to_string("/etc/os-release")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("PRETTY_NAME="))
                .map(|l| l[12..].trim_matches('"').to_string())
        })
        .unwrap_or_else(|| std::env::consts::OS.into());
    let profile = match (env!("MESHLETLAB_OPT_LEVEL"), cfg!(debug_assertions)) {
        ("0", _) => "debug build".to_string(),
        (o, false) => format!("release build, opt-level {o}"),
        (o, true) => format!("optimised build, opt-level {o}, with debug assertions"),
    };
    format!(
        "{cpu}, {cores} cores ({} rayon threads), {os}; meshletlab {} ({profile}), meshoptimizer 1.3 via meshopt 0.7",
        rayon::current_num_threads(),
        env!("CARGO_PKG_VERSION")
    )
}

/// Writes the opening every bench's markdown report starts with: the `# title`, the command that
/// wrote it and today's date (`context` follows the date in that sentence: `" (same run as
/// build.md)"`, or empty), and this machine ([`machine_note`]). One format, so that a reader finds
/// where and how any report was made in the same place.
///
/// `smoke` is the output folder of a smoke run ([`Common::smoke_out`]), `None` for a measurement:
/// a smoke report says first that it is one, with the command line that wrote it (`command`, then
/// `--smoke --out DIR`), so that nobody takes its numbers for measurements.
pub fn write_header(
    md: &mut String,
    title: &str,
    command: &str,
    context: &str,
    smoke: Option<&Path>,
) {
    use std::fmt::Write as _;
    // Writing into a String cannot fail.
    let _ = writeln!(md, "# {title}\n");
    match smoke {
        None => {
            let _ = writeln!(
                md,
                "Written by `{command}` on {}{context}. Do not edit: rerun the command.\n",
                today()
            );
        }
        Some(out) => {
            let _ = writeln!(
                md,
                "**{SMOKE_NOTE}.** Written by `{} --smoke --out {}` on {}{context}, on tiny \
                 inputs, to check that the bench runs and writes its files: no number here is a \
                 measurement (the bench without `--smoke` writes the real report).\n",
                command,
                out.display(),
                today()
            );
        }
    }
    let _ = writeln!(md, "Machine: {}.\n", machine_note());
}

/// The words every smoke report opens with ([`write_header`]).
pub const SMOKE_NOTE: &str = "Smoke run, not a measurement";

/// Today's date (UTC) as YYYY-MM-DD, without a date crate.
pub fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() / 86_400)
        .unwrap_or(0) as i64;
    // Civil-from-days (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!("{y:04}-{m:02}-{d:02}")
}

/// The metrics table `stats` and `demo` print: one row per evaluation.
pub fn metrics_table(rows: &[Evaluation]) -> comfy_table::Table {
    let mut t = comfy_table::Table::new();
    t.load_preset(comfy_table::presets::ASCII_MARKDOWN);
    let mut header = vec!["strategy", "meshlets", "verts/ml", "tris/ml"];
    header.extend(QUALITY_HEADER);
    header.extend(["ms", "valid"]);
    t.set_header(header);
    for r in rows {
        let m = &r.metrics;
        let mut row = vec![
            r.strategy.clone(),
            m.meshlets.to_string(),
            format!("{:.1}", m.mean_vertices),
            format!("{:.1}", m.mean_triangles),
        ];
        row.extend(quality_cells(m));
        row.push(format!("{:.2}", m.build_ms.unwrap_or(f64::NAN)));
        row.push(match &r.invalid {
            None => "ok".into(),
            Some(e) => format!("INVALID: {e}"),
        });
        t.add_row(row);
    }
    right_align_numbers(&mut t, 1..12);
    t
}

/// Column names of [`quality_cells`].
pub const QUALITY_HEADER: [&str; 7] = [
    "vfill",
    "pfill",
    "radius/diag",
    "flat/diag",
    "cullable",
    "dup",
    "connected",
];

/// The quality columns every metrics table shows, formatted.
pub fn quality_cells(m: &Metrics) -> [String; 7] {
    [
        format!("{:.3}", m.vertex_fill),
        format!("{:.3}", m.primitive_fill),
        format!("{:.4}", m.mean_radius_rel),
        format!("{:.5}", m.flatness_rel),
        format!("{:.3}", m.cone_cullable),
        format!("{:.3}", m.duplication),
        format!("{:.3}", m.connected),
    ]
}

/// Right-aligns the given columns.
pub fn right_align_numbers(t: &mut comfy_table::Table, cols: std::ops::Range<usize>) {
    for c in cols {
        if let Some(col) = t.column_mut(c) {
            col.set_cell_alignment(comfy_table::CellAlignment::Right);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_date() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        let d = today();
        assert_eq!(d.len(), 10);
        assert!(d.starts_with("20"));
    }

    #[test]
    fn a_smoke_header_says_so_first_with_its_command_line() {
        let mut md = String::new();
        write_header(&mut md, "T", "meshletlab bench x", "", None);
        assert!(
            md.starts_with("# T\n\nWritten by `meshletlab bench x` on "),
            "{md}"
        );
        assert!(!md.contains(SMOKE_NOTE));
        let mut md = String::new();
        write_header(&mut md, "T", "meshletlab bench x", "", Some(Path::new("o")));
        let second = md.lines().nth(2).unwrap_or_default();
        assert!(second.starts_with(&format!("**{SMOKE_NOTE}.**")), "{md}");
        assert!(
            second.contains("`meshletlab bench x --smoke --out o`"),
            "{md}"
        );
    }

    #[test]
    fn options_are_checked_where_they_are_parsed() {
        assert_eq!(positive::<f32>("2.5"), Ok(2.5));
        for bad in ["0", "-1", "nan", "inf", "1e40", "x", ""] {
            assert!(positive::<f32>(bad).is_err(), "{bad}");
        }
        assert_eq!(strategy_name(" meshopt "), Ok("meshopt".into()));
        assert!(strategy_name("").is_err());
        assert!(strategy_name("bogus").is_err());
        assert_eq!(strategy_name_or_none(""), Ok(String::new()));
    }

    #[test]
    fn a_tag_goes_before_the_extension_and_keeps_to_safe_characters() {
        let none = Tag::default();
        assert_eq!(none.name("gpu.md"), "gpu.md");
        let t = Tag {
            tag: Some(parse_tag("h100").unwrap()),
        };
        assert_eq!(t.name("gpu.md"), "gpu-h100.md");
        assert_eq!(t.name("gpu_scaling.svg"), "gpu_scaling-h100.svg");
        assert_eq!(t.name("README"), "README-h100");
        for bad in [
            "", "a b", "../x", "x.md", "h100)", "parallel", "flat", "max", "render",
        ] {
            assert!(parse_tag(bad).is_err(), "{bad:?}");
        }
    }
}
