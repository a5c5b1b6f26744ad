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

/// `meshletlab bench BENCH --smoke [extra] --out OUT` (without -q: the progress messages too),
/// which must succeed; its stdout and stderr together.
fn smoke(bench: &str, extra: &[&str], out: &Path) -> String {
    let mut args = vec!["bench", bench, "--smoke"];
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

/// `file` with `tag` before its extension (`gpu.md` -> `gpu-t1.md`), as `--tag` names it.
fn tagged(file: &str, tag: Option<&str>) -> String {
    match (tag, file.rsplit_once('.')) {
        (Some(t), Some((stem, ext))) => format!("{stem}-{t}.{ext}"),
        _ => file.to_string(),
    }
}

/// Runs `bench` in smoke mode into `root/bench` (with `--tag TAG` when given) and checks what it
/// wrote: every report it wrote (listed or not) is a smoke report whose embedded files exist,
/// every listed file is there (the first markdown under its title, with a table; each CSV with a
/// header and rows; each image not empty). With a tag, every file and every link of its markdown
/// carries the tag, and the linked plots and images exist.
fn check_bench(root: &Path, (bench, title, files): (&str, &str, &[&str]), tag: Option<&str>) {
    let out = root.join(bench);
    let extra: Vec<&str> = tag.map_or(vec![], |t| vec!["--tag", t]);
    // Without -q: what a bench prints on the way is checked too.
    let said = smoke(bench, &extra, &out);
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
    for (i, listed) in files.iter().enumerate() {
        let f = &tagged(listed, tag);
        if f.ends_with(".svg") || f.ends_with(".png") {
            let len = std::fs::metadata(out.join(f)).map_or(0, |m| m.len());
            assert!(len > 0, "bench {bench}: {f} not written");
            continue;
        }
        let text = std::fs::read_to_string(out.join(f))
            .unwrap_or_else(|e| panic!("bench {bench}: {f}: {e}"));
        if f.ends_with(".md") {
            assert!(
                i != 0 || text.starts_with(title),
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
    let Some(tag) = tag else { return };
    let mark = format!("-{tag}.");
    let written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().unwrap().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(written.len() >= 3, "bench {bench}: {written:?}");
    for f in &written {
        assert!(f.contains(&mark), "bench {bench}: untagged file {f}");
    }
    // Every plot and image the markdown links to is there, tagged.
    let md = std::fs::read_to_string(out.join(tagged(&format!("{bench}.md"), Some(tag)))).unwrap();
    for link in md.split("](").skip(1).filter_map(|r| r.split(')').next()) {
        assert!(link.contains(&mark), "bench {bench}: untagged link {link}");
        if link.ends_with(".svg") || link.ends_with(".png") {
            assert!(out.join(link).is_file(), "bench {bench}: {link} missing");
        }
    }
}

/// The two benches that measure a GPU and take `--tag`: their smoke runs are tagged. (`--tag` is
/// one naming function shared by every bench that takes it, so the untagged names the other
/// benches are checked under and the tagged ones checked here cover both of its cases; an
/// untagged run of these two as well would only repeat their smoke runs, the render bench's the
/// slowest of all.)
const TAGGED: [&str; 2] = ["gpu", "render"];

/// The render bench's smoke run is about half of all the smoke runs' time: it has its own test,
/// so that the test threads share the work.
const ALONE: &str = "render";

/// Runs and checks ([`check_bench`]) the benches `pick` selects, which must be `expected` of them;
/// the [`TAGGED`] ones with the tag `t1`.
fn check_benches(root: &Path, pick: impl Fn(&str) -> bool, expected: usize) {
    let mut checked = 0;
    for b in BENCHES.iter().filter(|b| pick(b.0)) {
        check_bench(root, *b, TAGGED.contains(&b.0).then_some("t1"));
        checked += 1;
    }
    assert_eq!(checked, expected, "benches checked");
}

#[test]
fn every_bench_writes_its_tables_in_smoke_mode() {
    let root = common::scratch("bench-smoke");
    check_benches(&root, |b| b != ALONE, BENCHES.len() - 1);
}

/// The render bench's smoke run, tagged ([`every_bench_writes_its_tables_in_smoke_mode`] checks
/// the others); and a tag that ends a strategy's name is refused.
#[test]
fn the_render_bench_writes_its_tables_and_tags_every_file_and_link() {
    let root = common::scratch("bench-render");
    check_benches(&root, |b| b == ALONE, 1);
    // A tag that ends a strategy's name would overwrite that strategy's untagged image.
    let o = meshletlab(&["-q", "bench", "render", "--smoke", "--tag", "parallel"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("overwrite"));
}

#[test]
fn smoke_runs_never_write_into_results() {
    let o = meshletlab(&["-q", "bench", "build", "--smoke"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--smoke") && err.contains("results"), "{err}");
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
