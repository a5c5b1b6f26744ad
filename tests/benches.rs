//! Every `meshletlab bench` subcommand in its smoke mode (tiny generated meshes, one run): it
//! exits 0 and writes its results files, each markdown file with its title and its tables. A bench
//! whose writer breaks is found here, not at the next full bench run. The numbers are not checked:
//! a smoke run measures nothing.

mod common;

use std::process::Command;

/// (subcommand, title of its markdown, the files it must write).
const BENCHES: [(&str, &str, &[&str]); 10] = [
    (
        "build",
        "# Meshlet build benchmark",
        &["build.md", "build.csv", "strategies.md"],
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
        &["render.md", "render.csv", "render_experiments.csv"],
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

/// `meshletlab -q bench BENCH --smoke [extra] --out OUT`, which must succeed.
fn smoke(bench: &str, extra: &[&str], out: &std::path::Path) {
    let mut args = vec!["-q", "bench", bench, "--smoke"];
    args.extend_from_slice(extra);
    args.extend(["--out", out.to_str().unwrap()]);
    let o = meshletlab(&args);
    assert!(
        o.status.success(),
        "bench {bench} --smoke {extra:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn every_bench_writes_its_tables_in_smoke_mode() {
    let root = common::scratch("bench-smoke");
    for (bench, title, files) in BENCHES {
        let out = root.join(bench);
        smoke(bench, &[], &out);
        for f in files {
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
        // Every plot the markdown links to is there (the smoke meshes hold no bunny, so the
        // render bench writes no bunny images).
        let md = std::fs::read_to_string(out.join(format!("{bench}-t1.md"))).unwrap();
        for link in md.split("](").skip(1).filter_map(|r| r.split(')').next()) {
            assert!(link.contains("-t1."), "bench {bench}: untagged link {link}");
            if link.ends_with(".svg") {
                assert!(out.join(link).is_file(), "bench {bench}: {link} missing");
            }
        }
    }
    // A tag that ends a strategy's name would overwrite that strategy's untagged image.
    let o = meshletlab(&["-q", "bench", "render", "--smoke", "--tag", "parallel"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("overwrite"));
}
