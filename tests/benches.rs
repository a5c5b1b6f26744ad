//! Every `meshletlab bench` subcommand in its smoke mode (tiny generated meshes, one run): it
//! exits 0 and writes its results files, each markdown file with its title and its tables, a
//! header that says it is a smoke run, and every image it embeds. A bench whose writer breaks is
//! found here, not at the next full bench run. The numbers are not checked: a smoke run measures
//! nothing.

mod common;

use std::path::Path;
use std::process::Command;

/// (subcommand, title of its markdown, the files it must write).
const BENCHES: [(&str, &str, &[&str]); 10] = [
    (
        "build",
        "# Meshlet build benchmark",
        &[
            "build.md",
            "build.csv",
            "strategies.md",
            "figure9_vertices.svg",
            "figure9_triangles.svg",
        ],
    ),
    (
        "fidelity",
        "# Paper fidelity",
        &["fidelity.md", "fidelity.csv"],
    ),
    (
        "kmedoids",
        "# k-medoids at scale",
        &["kmedoids.md", "kmedoids.csv", "kmedoids_sweep.csv"],
    ),
    (
        "gpu",
        "# GPU kernels against their CPU references",
        &["gpu.md", "gpu.csv", "gpu_floor.csv"],
    ),
    (
        "render",
        "# Mesh-shader rendering",
        &[
            "render.md",
            "render.csv",
            "render_experiments.csv",
            "render_sphere_meshopt.png",
        ],
    ),
    (
        "stability",
        "# Numerical stability under stress",
        &["stability.md"],
    ),
    (
        "lod",
        "# Cluster LOD",
        &["lod.md", "lod.csv", "lod_levels.csv", "lod_curve.csv"],
    ),
    (
        "compress",
        "# Compressed meshlets",
        &["compress.md", "compress.csv", "compress_fig8.csv"],
    ),
    (
        "compress-render",
        "# Compressed meshlets rendered",
        &["compress-render.md", "compress-render.csv"],
    ),
    (
        "robustness",
        "# Robustness",
        &["robustness.md", "robustness.csv"],
    ),
];

fn meshletlab(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_meshletlab"))
        .args(args)
        .output()
        .expect("meshletlab runs")
}

/// `meshletlab -q bench BENCH --smoke [extra] --out OUT`, which must succeed; its stdout and
/// stderr together.
fn smoke(bench: &str, extra: &[&str], out: &Path) -> String {
    smoke_with(&["-q"], bench, extra, out)
}

/// [`smoke`] with `global` options before `bench` (none: the progress messages too).
fn smoke_with(global: &[&str], bench: &str, extra: &[&str], out: &Path) -> String {
    let mut args = global.to_vec();
    args.extend(["bench", bench, "--smoke"]);
    args.extend_from_slice(extra);
    args.extend(["--out", out.to_str().unwrap()]);
    let o = meshletlab(&args);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        o.status.success(),
        "bench {bench} --smoke {extra:?}: {text}"
    );
    text
}

/// The files a markdown report embeds: `![alt](file)` and `<img src="file">`, as written.
fn embedded(md: &str) -> Vec<String> {
    let mut out = Vec::new();
    for rest in md.split("![").skip(1) {
        if let Some(link) = rest.split_once("](").and_then(|(_, r)| r.split(')').next()) {
            out.push(link.trim().to_string());
        }
    }
    for rest in md.split("<img").skip(1) {
        let tag = rest.split('>').next().unwrap_or_default();
        if let Some(src) = tag.split("src=").nth(1) {
            let src = src.trim_start_matches(['"', '\'']);
            let end = src.find(['"', '\'', ' ', '/']).unwrap_or(src.len());
            out.push(src[..end].to_string());
        }
    }
    out
}

/// A smoke report, `file` in `out`: its header (the lines before the first section or table)
/// says that it is a smoke run and gives the smoke command line, and every file it embeds is
/// there, beside it.
fn check_smoke_report(bench: &str, out: &Path, file: &str, text: &str) {
    let header: Vec<&str> = text
        .lines()
        .skip(1)
        .take_while(|l| !l.starts_with('#') && !l.starts_with('|'))
        .collect();
    let header = header.join("\n");
    assert!(
        header.contains("Smoke run, not a measurement")
            && header.contains(&format!("meshletlab bench {bench}"))
            && header.contains("--smoke"),
        "bench {bench}: {file} does not say in its header that it is a smoke run: {header}"
    );
    for link in embedded(text) {
        let path = out.join(&link);
        assert!(
            path.is_file() && std::fs::metadata(&path).unwrap().len() > 0,
            "bench {bench}: {file} embeds {link}, which the smoke run did not write"
        );
    }
}

#[test]
fn every_bench_writes_its_tables_in_smoke_mode() {
    let root = common::scratch("bench-smoke");
    for (bench, title, files) in BENCHES {
        let out = root.join(bench);
        // Without -q: what a bench prints on the way is checked too.
        let said = smoke_with(&[], bench, &[], &out);
        assert!(
            !said.contains("Some(") && !said.contains("None"),
            "bench {bench} printed a Rust value: {said}"
        );
        // Every report the run wrote, listed or not.
        for e in std::fs::read_dir(&out).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "md") {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                check_smoke_report(bench, &out, &name, &std::fs::read_to_string(&p).unwrap());
            }
        }
        for f in files {
            if f.ends_with(".svg") || f.ends_with(".png") {
                let len = std::fs::metadata(out.join(f)).map_or(0, |m| m.len());
                assert!(len > 0, "bench {bench}: {f} not written");
                continue;
            }
            let text = std::fs::read_to_string(out.join(f))
                .unwrap_or_else(|e| panic!("bench {bench}: {f}: {e}"));
            if f.ends_with(".md") {
                let md = f == &files[0];
                assert!(
                    !md || text.starts_with(title),
                    "bench {bench}: {f} starts {:?}",
                    text.lines().next()
                );
                // A table: a header row followed by its separator row.
                let lines: Vec<&str> = text.lines().collect();
                // Every profiled kernel names the CPU step it mirrors.
                if bench == "gpu" {
                    let blank: Vec<&&str> = lines
                        .iter()
                        .filter(|l| l.starts_with("| `") && l.contains("` |  |"))
                        .collect();
                    assert!(
                        blank.is_empty(),
                        "bench gpu: kernels without a CPU step: {blank:?}"
                    );
                }
                assert!(
                    lines.windows(2).any(|w| w[0].starts_with('|')
                        && ["|-", "| -", "|:"].iter().any(|s| w[1].starts_with(s))),
                    "bench {bench}: {f} has no table"
                );
            } else {
                // CSV: a header line of several fields and at least one row.
                let mut lines = text.lines();
                let fields = lines.next().map_or(0, |h| h.split(',').count());
                let rows: Vec<&str> = lines.collect();
                assert!(
                    fields > 1 && !rows.is_empty(),
                    "bench {bench}: {f} is empty"
                );
            }
        }
    }
}

#[test]
fn smoke_runs_never_write_into_results() {
    let o = meshletlab(&["-q", "bench", "build", "--smoke"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--smoke") && err.contains("results"), "{err}");
}

#[test]
fn a_tagged_run_names_every_file_and_link_with_its_tag() {
    let root = common::scratch("bench-tag");
    for bench in ["gpu", "render"] {
        let out = root.join(bench);
        smoke(bench, &["--tag", "t1"], &out);
        let files: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap())
            .filter(|e| e.file_type().unwrap().is_file())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        assert!(files.len() >= 3, "bench {bench}: {files:?}");
        for f in &files {
            assert!(f.contains("-t1."), "bench {bench}: untagged file {f}");
        }
        // Every plot and image the markdown links to is there, tagged.
        let md = std::fs::read_to_string(out.join(format!("{bench}-t1.md"))).unwrap();
        for link in md.split("](").skip(1).filter_map(|r| r.split(')').next()) {
            assert!(link.contains("-t1."), "bench {bench}: untagged link {link}");
            if link.ends_with(".svg") || link.ends_with(".png") {
                assert!(out.join(link).is_file(), "bench {bench}: {link} missing");
            }
        }
    }
    // A tag that ends a strategy's name would overwrite that strategy's untagged image.
    let o = meshletlab(&["-q", "bench", "render", "--smoke", "--tag", "parallel"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("overwrite"));
}

/// Options that would make a bench run nothing, or fail after the meshes load, are refused while
/// the command line is parsed; strategy lists take commas; errors name the file first.
#[test]
fn bench_options_are_checked_as_they_are_parsed() {
    let refused = |args: &[&str], says: &str| {
        let o = meshletlab(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    };
    refused(
        &["bench", "robustness", "--smoke", "--cases", "0"],
        "--cases",
    );
    refused(&["bench", "robustness", "--workers", "0"], "--workers");
    refused(&["bench", "render", "--views", "0"], "--views");
    refused(&["bench", "render", "--distance", "nan"], "--distance");
    refused(&["bench", "lod", "--threshold", "inf"], "--threshold");
    refused(&["bench", "lod", "--select-views", "0"], "--select-views");
    refused(&["bench", "kmedoids", "--runs", "0"], "--runs");
    refused(
        &["bench", "kmedoids", "--paper-budget=-1"],
        "--paper-budget",
    );
    refused(
        &["bench", "kmedoids", "--paper-budget", "0"],
        "--paper-budget",
    );
    refused(&["bench", "fidelity", "--runs", "0"], "--runs");
    // A comma-separated list is split: the unknown name is reported alone, the known one passed.
    for bench in ["build", "render", "lod"] {
        refused(
            &["bench", bench, "-s", "meshopt,bogus"],
            "unknown strategy 'bogus'",
        );
    }
}

#[test]
fn tag_help_names_no_device_and_is_the_same_on_every_bench() {
    let help = |bench: &str| {
        let o = meshletlab(&["bench", bench, "--help"]);
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        // The flag's help (clap lays it out beside the flag or below it).
        let at = text.find("--tag <TAG>").expect("--tag in the help") + "--tag <TAG>".len();
        let rest = text[at..].trim_start();
        rest.lines().next().unwrap_or_default().to_string()
    };
    let gpu = help("gpu");
    assert!(!gpu.contains("h100") && gpu.contains("<bench>"), "{gpu}");
    for bench in ["kmedoids", "render", "lod", "compress-render"] {
        assert_eq!(help(bench), gpu, "bench {bench}");
    }
}

#[test]
fn a_dump_that_cannot_be_written_names_the_folder_first() {
    let o = meshletlab(&["bench", "robustness", "--dump", "3", "-o", "/proc/xx"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.starts_with("error: /proc/xx: cannot "), "{err}");
}
