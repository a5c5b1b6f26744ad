//! The command-line contract: every subcommand and render mode, run with `-o`/`--out` (and
//! `--json` where it has one) on generated meshes, writes every file its text or JSON names, and
//! each file is what it says (a PNG, a glTF that loads back, meshlet, compressed and LOD files
//! their checkers accept); a reader that closes stdout early ends a command quietly with its
//! files still written; values and option sets that mean nothing are refused, usage errors with
//! exit status 2, file errors as one `error: FILE: ...` line with exit status 1.

mod common;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// A small generated mesh: every mode runs on it in a fraction of a second on lavapipe.
const MESH: &str = "gen:cad-part-400";

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_meshletlab"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Runs a command that must succeed; its stdout.
fn ok(args: &[&str]) -> String {
    let out = run(args);
    assert!(
        out.status.success(),
        "{args:?} failed ({}): {}",
        out.status,
        text(&out.stderr)
    );
    text(&out.stdout)
}

/// Every path under `dir` that `stdout` names (as a word of text or a JSON string) exists, and
/// how many it named.
fn named_files_exist(stdout: &str, dir: &Path, args: &[&str]) -> usize {
    let root = dir.to_str().unwrap();
    let mut named = 0;
    for word in stdout.split(|c: char| c.is_whitespace() || "\",()".contains(c)) {
        if let Some(i) = word.find(root) {
            let path = Path::new(word[i..].trim_end_matches([':', ';', '.']));
            assert!(
                path.exists(),
                "{args:?} names {} but did not write it",
                path.display()
            );
            named += 1;
        }
    }
    named
}

/// A PNG: the signature, and an IHDR of the render size.
fn assert_png(p: &Path) {
    let b = std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    assert!(
        b.starts_with(b"\x89PNG\r\n\x1a\n"),
        "{}: not a PNG",
        p.display()
    );
    let (w, h) = (
        u32::from_be_bytes(b[16..20].try_into().unwrap()),
        u32::from_be_bytes(b[20..24].try_into().unwrap()),
    );
    assert_eq!(
        (w, h),
        (meshletlab::render::WIDTH, meshletlab::render::HEIGHT),
        "{}",
        p.display()
    );
}

fn path(dir: &Path, name: &str) -> PathBuf {
    dir.join(name)
}

/// Every render mode writes its `-o` PNG, names it in its text and JSON, and the JSON parses.
#[test]
fn every_render_mode_writes_the_png_it_names() {
    let dir = common::scratch("contract-render");
    let compressed = path(&dir, "lw.mlc");
    let c = compressed.to_str().unwrap();
    ok(&["compress", "-q", MESH, "-f", "laced-wires", "-o", c]);
    let modes: &[(&str, &[&str])] = &[
        ("split", &[]),
        ("nvidia-a", &["--descriptor", "nvidia-a"]),
        ("no-cull", &["--no-cull"]),
        ("lod", &["--lod"]),
        ("occlusion", &["--occlusion", "--frames", "2"]),
        ("lod-occlusion", &["--lod", "--occlusion", "--frames", "2"]),
        ("grid", &["--grid", "2"]),
        (
            "grid-occlusion",
            &["--grid", "2", "--occlusion", "--frames", "2"],
        ),
        ("format", &["--format", "laced-wires"]),
        ("compact", &["--format", "sc-compact"]),
        ("compressed", &["--compressed", c]),
        ("scene", &["SCENE"]),
    ];
    for (name, extra) in modes {
        for json in [false, true] {
            let png = path(&dir, &format!("{name}-{json}.png"));
            let p = png.to_str().unwrap();
            let mesh = if extra == &["SCENE"] {
                "gen:scene-small"
            } else {
                MESH
            };
            let mut args = vec!["render", "-q", mesh, "--views", "1", "-o", p];
            args.extend(extra.iter().filter(|a| **a != "SCENE"));
            if json {
                args.push("--json");
            }
            let out = ok(&args);
            assert_png(&png);
            if json {
                let v: serde_json::Value = serde_json::from_str(&out)
                    .unwrap_or_else(|e| panic!("{args:?}: JSON: {e}\n{out}"));
                assert_eq!(v["png"].as_str(), Some(p), "{args:?}");
            }
            assert!(
                named_files_exist(&out, &dir, &args) >= 1,
                "{args:?} does not name its PNG:\n{out}"
            );
        }
    }
}

/// Every command that writes a file writes it where asked, and its checker accepts it; `demo`
/// writes its files into `--out`, named by the input's stem, not next to the input.
#[test]
fn every_written_file_is_what_it_says() {
    let dir = common::scratch("contract-files");
    let p = |n: &str| path(&dir, n).to_str().unwrap().to_string();
    let (meshlets, lod, packed, glb, ply) = (
        p("m.mlt"),
        p("m.lod"),
        p("m.mlc"),
        p("m.glb"),
        p("m.ply.zst"),
    );
    for (args, check) in [
        (
            vec!["build", "-q", MESH, "-s", "kmedoids", "-o", &meshlets],
            vec!["check", "-q", MESH, &meshlets],
        ),
        (
            vec!["lod", "-q", MESH, "-o", &lod, "--json"],
            vec!["lod-check", "-q", MESH, &lod, "--views", "8"],
        ),
        (
            vec!["compress", "-q", MESH, "-o", &packed, "--json"],
            vec!["check", "-q", MESH, &packed],
        ),
    ] {
        let out = ok(&args);
        if args.contains(&"--json") {
            serde_json::from_str::<serde_json::Value>(&out)
                .unwrap_or_else(|e| panic!("{args:?}: {e}"));
        }
        assert!(named_files_exist(&out, &dir, &args) >= 1, "{args:?}: {out}");
        assert!(ok(&check).contains("valid"), "{check:?}");
    }
    // The glTF loads back with every triangle; the subdivided PLY has four times as many.
    let source = meshletlab::mesh::load(Path::new(MESH)).unwrap();
    let out = ok(&["export", "-q", MESH, "-o", &glb]);
    assert!(named_files_exist(&out, &dir, &["export"]) >= 1, "{out}");
    let back = meshletlab::mesh::load(Path::new(&glb)).unwrap();
    assert_eq!(back.triangle_count(), source.triangle_count());
    let out = ok(&["subdivide", "-q", MESH, "-o", &ply]);
    assert!(named_files_exist(&out, &dir, &["subdivide"]) >= 1, "{out}");
    let sub = meshletlab::mesh::load(Path::new(&ply)).unwrap();
    assert_eq!(sub.triangle_count(), 4 * source.triangle_count());
    // JSON commands without files parse.
    for args in [
        vec!["stats", "-q", MESH, "-s", "meshopt,kmedoids", "--json"],
        vec![
            "parity",
            "-q",
            MESH,
            "--skip",
            "kmedoids-flat,grower,lod",
            "--json",
        ],
    ] {
        serde_json::from_str::<serde_json::Value>(&ok(&args))
            .unwrap_or_else(|e| panic!("{args:?}: {e}"));
    }
    // demo: a mesh in a subfolder, its files in --out under the mesh's stem.
    let input = path(&dir, "in/part.ply.zst");
    std::fs::create_dir_all(input.parent().unwrap()).unwrap();
    ok(&[
        "subdivide",
        "-q",
        "gen:cad-part-128",
        "-o",
        input.to_str().unwrap(),
    ]);
    let out_dir = path(&dir, "demo");
    let out = ok(&[
        "demo",
        "-q",
        "--mesh",
        input.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(named_files_exist(&out, &dir, &["demo"]) >= 2, "{out}");
    assert_png(&out_dir.join("part_meshopt.png"));
    assert!(meshletlab::mesh::load(&out_dir.join("part_meshopt.glb")).is_ok());
    let beside: Vec<_> = std::fs::read_dir(input.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(beside.len(), 1, "demo wrote beside its input: {beside:?}");
}

/// A reader that leaves at once (`| head -0`): the command exits 0 (or by SIGPIPE), says nothing
/// on stderr, and still writes its `-o` file.
#[test]
fn a_closed_stdout_ends_a_command_quietly() {
    let dir = common::scratch("contract-pipe");
    let png = path(&dir, "r.png");
    let demo = path(&dir, "demo");
    for args in [
        vec!["stats", "-q", MESH],
        vec!["--help"],
        vec![
            "render",
            "-q",
            MESH,
            "--views",
            "2",
            "-o",
            png.to_str().unwrap(),
        ],
        vec!["demo", "-q", "--no-gpu", "--out", demo.to_str().unwrap()],
    ] {
        let _ = std::fs::remove_file(&png);
        let mut child = Command::new(env!("CARGO_BIN_EXE_meshletlab"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        let status = child.wait().unwrap();
        use std::os::unix::process::ExitStatusExt;
        assert!(
            status.success() || status.signal() == Some(13),
            "{args:?}: {status}: {err}"
        );
        assert!(err.is_empty(), "{args:?} wrote to stderr: {err}");
        if args[0] == "render" {
            assert_png(&png);
        }
    }
}

/// Values and option sets that mean nothing are refused before any work: usage errors in clap's
/// form with status 2; file errors as one line naming the file first, status 1.
#[test]
fn meaningless_values_are_refused() {
    let dir = common::scratch("contract-refused");
    let png = path(&dir, "r.png");
    let p = png.to_str().unwrap();
    let usage: &[&[&str]] = &[
        &["render", MESH, "--views", "0"],
        &["render", MESH, "--distance", "0"],
        &["render", MESH, "--distance", "nan"],
        &["render", MESH, "--distance", "inf"],
        &["render", MESH, "--distance", "1e30"],
        &["render", MESH, "--distance", "-1"],
        &["render", MESH, "--lod", "--threshold", "0"],
        &["render", MESH, "--lod", "--tolerance", "0.01"],
        &["render", MESH, "--lod", "--descriptor", "nvidia-a"],
        &["render", MESH, "--occlusion", "--no-cull"],
        &["render", MESH, "--compressed", "x.mlc", "-s", "kmedoids"],
        &["render", MESH, "--compressed", "x.mlc", "-l", "32/64"],
        &["render", MESH, "--grid", "2", "--spacing", "nan"],
        &["stats", MESH, "--runs", "0"],
        &["stats", MESH, "--kmedoids-threshold", "nan"],
        &["stats", MESH, "--fill-weight", "-1"],
        &["stats", MESH, "--paper-budget", "0"],
        &["stats", MESH, "--threads", "0"],
        &["lod-check", MESH, "x.lod", "--views", "0"],
        &[
            "parity",
            MESH,
            "--skip",
            "adjacency,kmedoids-flat,kmedoids-parallel,bounds,grower,lod",
        ],
        &[
            "compress",
            MESH,
            "-o",
            "x.mlc",
            "-f",
            "laced-wires",
            "--compact",
        ],
        &["compress", MESH, "-o", "x.mlc", "--tolerance", "nan"],
        &["subdivide", MESH, "-o", "x.ply", "--levels", "0"],
    ];
    for args in usage {
        let out = run(args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?} not refused: {err}");
        assert!(
            err.starts_with("error: ") && err.contains("--help"),
            "{args:?}: {err}"
        );
    }
    let unwritable = "/proc/meshletlab/x.png";
    let file_errors: &[(&[&str], &str)] = &[
        (&["render", MESH, "-o", unwritable], unwritable),
        (
            &["render", MESH, "-o", dir.to_str().unwrap()],
            "is a directory",
        ),
        (&["render", MESH, "-o", "r.jpg"], "r.jpg: "),
        (&["export", MESH, "-o", "e.gltf"], "e.gltf: "),
        (
            &["build", MESH, "-s", "meshopt", "-o", unwritable],
            unwritable,
        ),
        (&["subdivide", MESH, "-o", "out.obj"], "out.obj: "),
        (&["stats", "/tmp"], "/tmp: is a directory"),
        (&["render", "missing.ply", "-o", p], "missing.ply: "),
    ];
    for (args, says) in file_errors {
        let out = run(args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(says) && err.lines().count() == 1,
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    assert!(!png.exists(), "a refused command wrote its output");
}
