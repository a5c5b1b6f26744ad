//! End-to-end runs of the `meshletlab` binary.

mod common;

use std::process::{Command, Output};

fn cli(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_meshletlab"))
        .args(args)
        .output()
        .expect("binary runs")
}

fn ok(args: &[&str]) -> String {
    let out = cli(args);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn build_then_check_round_trips_and_check_catches_mismatches() {
    let dir = common::scratch("build-check");
    let mesh = common::meshes_dir().join("fandisk.ply.zst");
    let other = common::meshes_dir().join("gmsh_aneurysm.ply.zst");
    let (mesh, other) = (mesh.to_str().unwrap(), other.to_str().unwrap());
    let file = dir.join("fandisk.mlt");
    let f = file.to_str().unwrap();
    for s in meshletlab::strategy::NAMES {
        let out = ok(&["build", "-q", mesh, "-s", s, "-o", f, "--limits", "64/84"]);
        assert!(out.contains("meshlets"), "{out}");
        let out = ok(&["check", "-q", mesh, f]);
        assert!(out.contains("valid") && out.contains(s), "{out}");
    }
    // Against another mesh: refused.
    let out = cli(&["check", "-q", other, f]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("vertices"));
    // A corrupted file: one corner of the last triangle changed -> the validator objects. (nvidia
    // writes no padding; meshoptimizer pads each meshlet's triangle bytes to 4, and padding is free.)
    ok(&["build", "-q", mesh, "-s", "nvidia", "-o", f]);
    let mut bytes = std::fs::read(&file).unwrap();
    let n = bytes.len();
    bytes[n - 2] = bytes[n - 2].wrapping_add(1);
    std::fs::write(&file, &bytes).unwrap();
    let out = cli(&["check", "-q", mesh, f]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("fandisk.mlt") && err.lines().count() == 1,
        "{err}"
    );
}

#[test]
fn stats_json_lists_every_strategy_with_metrics() {
    let mesh = common::meshes_dir().join("stellarium_gaspra.ply.zst");
    let out = ok(&[
        "stats",
        "-q",
        mesh.to_str().unwrap(),
        "--json",
        "--limits",
        "64/124",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["stats"]["triangles"], 32040);
    let rows = v["strategies"].as_array().unwrap();
    assert_eq!(
        rows.len(),
        meshletlab::strategy::NAMES.len() - meshletlab::strategy::SLOW.len()
    );
    for r in rows {
        assert!(r["invalid"].is_null(), "{r}");
        assert!(r["metrics"]["meshlets"].as_u64().unwrap() >= 32040 / 124);
        assert_eq!(
            r["metrics"]["triangle_histogram"].as_array().unwrap().len(),
            125
        );
    }
}

#[test]
fn demo_compares_strategies_on_generated_meshes() {
    let out = ok(&["demo", "-q"]);
    for name in ["noisy-sphere", "knot-tube", "terrain"] {
        assert!(out.contains(name), "{out}");
    }
    for s in meshletlab::strategy::NAMES
        .iter()
        .filter(|n| !meshletlab::strategy::SLOW.contains(n))
    {
        assert!(out.contains(s), "{s} missing:\n{out}");
    }
    assert!(out.contains("All outputs validated"));
    assert!(!out.contains("INVALID"));
}

#[test]
fn subdivide_quadruples_and_keeps_topology() {
    let dir = common::scratch("subdivide");
    let src = common::meshes_dir().join("gmsh_aneurysm.ply.zst");
    let dst = dir.join("aneurysm_x4.ply.zst");
    ok(&[
        "subdivide",
        "-q",
        src.to_str().unwrap(),
        "-o",
        dst.to_str().unwrap(),
    ]);
    let a = meshletlab::mesh::MeshStats::of(&meshletlab::mesh::load(&src).unwrap());
    let b = meshletlab::mesh::MeshStats::of(&meshletlab::mesh::load(&dst).unwrap());
    assert_eq!(b.triangles, 4 * a.triangles);
    assert_eq!(b.vertices, a.vertices + a.edges);
    assert_eq!(b.components, a.components);
    // Each edge splits in two; boundaries stay boundaries; the Euler characteristic is unchanged.
    assert_eq!(b.edges, 2 * a.edges + 3 * a.triangles);
    assert_eq!(b.boundary_edges, 2 * a.boundary_edges);
    let euler =
        |s: &meshletlab::mesh::MeshStats| s.vertices as i64 - s.edges as i64 + s.triangles as i64;
    assert_eq!(euler(&b), euler(&a));
}

#[test]
fn help_explains_commands() {
    let out = ok(&["--help"]);
    for c in ["stats", "build", "check", "demo", "subdivide", "bench"] {
        assert!(out.contains(c), "{out}");
    }
    let out = ok(&["stats", "--help"]);
    assert!(out.contains("--limits") && out.contains("64/126"), "{out}");
}

#[test]
fn render_writes_a_meshlet_coloured_png_for_each_descriptor() {
    let dir = common::scratch("render-png");
    let mesh = common::meshes_dir().join("fandisk.ply.zst");
    let mut images = Vec::new();
    for d in ["split", "nvidia-b"] {
        let png = dir.join(format!("fandisk-{d}.png"));
        let out = ok(&[
            "render",
            "-q",
            mesh.to_str().unwrap(),
            "--strategy",
            "bsphere",
            "--views",
            "2",
            "-d",
            d,
            "-o",
            png.to_str().unwrap(),
            "--validate",
        ]);
        assert!(
            out.contains("view 1:") && out.contains("validation layer: no errors"),
            "{out}"
        );
        assert!(out.contains(&format!("{d} descriptors")), "{out}");
        // A 1280x720 RGBA image with many meshlet colours on a black background.
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        assert_eq!((info.width, info.height), (1280, 720));
        let colours: std::collections::HashSet<&[u8]> = pixels.chunks_exact(4).collect();
        assert!(colours.len() > 50, "{d}: {} colours", colours.len());
        images.push(pixels);
    }
    assert_eq!(images[0], images[1], "layouts draw the same meshlets");
    // A layout the meshlets do not fit, or an unknown one: a clear error, no panic.
    let out = cli(&["render", "-q", mesh.to_str().unwrap(), "-d", "nvidia-c"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("split, nvidia-a, nvidia-b, monolithic"));
}
