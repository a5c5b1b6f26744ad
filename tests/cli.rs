//! End-to-end runs of the `meshletlab` binary.

mod common;

use common::{cli, ok};
use std::process::Command;

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
fn compress_then_check_round_trips_and_check_catches_damage() {
    let dir = common::scratch("compress-check");
    let mesh = common::meshes_dir().join("stellarium_gaspra.ply.zst");
    let other = common::meshes_dir().join("fandisk.ply.zst");
    let (mesh, other) = (mesh.to_str().unwrap(), other.to_str().unwrap());
    for (format, strategy, limits) in [
        ("meshopt", "meshopt", "128/128"),
        ("laced-wires", "qem", "64/84"),
    ] {
        let file = dir.join(format!("gaspra-{format}.cmp"));
        let f = file.to_str().unwrap();
        let out = ok(&[
            "compress",
            "-q",
            mesh,
            "-o",
            f,
            "--json",
            "--format",
            format,
            "--strategy",
            strategy,
            "--limits",
            limits,
        ]);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let bpt = v["bytes_per_triangle"].as_f64().unwrap();
        assert!(bpt > 1.0 && bpt < 8.0, "{out}");
        assert!(v["max_error"].as_f64().unwrap() <= v["tolerance"].as_f64().unwrap());
        let out = ok(&["check", "-q", mesh, f]);
        assert!(out.contains("valid") && out.contains("compressed"), "{out}");
        // Against another mesh: refused, naming the file.
        let out = cli(&["check", "-q", other, f]);
        assert!(!out.status.success());
        assert!(String::from_utf8_lossy(&out.stderr).contains("gaspra-"));
        // A position bit flipped near the end of the encoding (before the provenance tables):
        // decoded beyond the tolerance, or other triangles.
        let mut bytes = std::fs::read(&file).unwrap();
        let parsed = meshletlab::compress::file::CompressedFile::from_bytes(&bytes, &file).unwrap();
        let tables =
            8 + 4 * (parsed.encoded.wire_base.len() + parsed.encoded.stored_to_source.len());
        let n = bytes.len() - tables;
        bytes[n - 5] ^= 0x10;
        std::fs::write(&file, &bytes).unwrap();
        let out = cli(&["check", "-q", mesh, f]);
        assert!(!out.status.success(), "{format}: damage not caught");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("gaspra-") && err.lines().count() == 1, "{err}");
    }
    // A bad tolerance is refused before any work.
    let f = dir.join("bad.cmp");
    let out = cli(&[
        "compress",
        "-q",
        mesh,
        "-o",
        f.to_str().unwrap(),
        "--tolerance",
        "-1",
    ]);
    assert!(!out.status.success());
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
    let dir = common::scratch("demo");
    let out = ok(&["demo", "-q", "--out", dir.to_str().unwrap()]);
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
    // The GPU part on lavapipe: the parity verdict, culling statistics and the files it names.
    let families = meshletlab::gpu::parity::Family::ALL.len();
    let verdict = format!("Parity: all {families} GPU kernels identical");
    assert!(out.contains(&verdict), "{out}");
    assert!(out.contains("by their normal cones"), "{out}");
    for f in ["noisy-sphere_meshopt.png", "noisy-sphere_meshopt.glb"] {
        assert!(out.contains(f) && dir.join(f).is_file(), "{f}:\n{out}");
    }
    assert_eq!(
        meshletlab::mesh::load(&dir.join("noisy-sphere_meshopt.glb"))
            .unwrap()
            .triangle_count(),
        20480
    );
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
fn help_lists_every_strategy_and_generated_mesh_with_its_summary() {
    let out = ok(&["--help"]);
    for k in meshletlab::strategy::Kind::ALL {
        let line = format!("{:<17} {}", k.name(), k.summary());
        assert!(out.contains(&line), "--help lacks `{line}`:\n{out}");
    }
    // Exactly the four k-medoids methods, one name each.
    let kmedoids: Vec<&str> = out
        .lines()
        .filter_map(|l| l.strip_prefix("  ")?.split_whitespace().next())
        .filter(|n| n.starts_with("kmedoids"))
        .collect();
    assert_eq!(
        kmedoids,
        [
            "kmedoids",
            "kmedoids-parallel",
            "kmedoids-flat",
            "kmedoids-paper"
        ],
        "{out}"
    );
    for name in meshletlab::mesh::generate::NAMES {
        assert!(out.contains(name), "--help lacks gen:{name}:\n{out}");
    }
    for suffix in ["+refine", "+refine-fast", "+refine-max", "+partition"] {
        assert!(out.contains(suffix), "--help lacks {suffix}:\n{out}");
    }
    assert!(!out.contains("kmedoids-local"), "{out}");
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
            out.contains("view 1 (") && out.contains("validation layer: no errors"),
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

#[test]
fn render_draws_compressed_meshlets_and_refuses_a_damaged_file() {
    let dir = common::scratch("render-compressed");
    let mesh = common::meshes_dir().join("fandisk.ply.zst");
    let m = mesh.to_str().unwrap();
    let png = dir.join("laced.png");
    for format in ["laced-wires", "gi-compact"] {
        let out = ok(&[
            "render",
            "-q",
            m,
            "--format",
            format,
            "--views",
            "2",
            "--validate",
            "--json",
            "-o",
            png.to_str().unwrap(),
        ]);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["format"], format, "{out}");
        assert_eq!(v["validation_errors"], 0, "{out}");
        assert!(
            v["device_bytes"].as_u64().unwrap() < v["uncompressed_device_bytes"].as_u64().unwrap()
        );
        let views = v["views"].as_array().unwrap();
        assert_eq!(views.len(), 2);
        assert!(
            views
                .iter()
                .all(|x| x["identical_to_decoded_reference"] == true),
            "{out}"
        );
    }
    // A file from `compress`, drawn as it is; then one byte of it damaged: refused, naming the
    // file, before anything reaches the GPU.
    let file = dir.join("fandisk.cmp");
    let f = file.to_str().unwrap();
    ok(&["compress", "-q", m, "--format", "laced-wires", "-o", f]);
    let out = ok(&["render", "-q", m, "--compressed", f, "--views", "1"]);
    assert!(
        out.contains("laced-wires") && out.contains("identical to the CPU-decoded reference"),
        "{out}"
    );
    let mut bytes = std::fs::read(&file).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&file, &bytes).unwrap();
    let out = cli(&["render", "-q", m, "--compressed", f, "--views", "1"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("fandisk.cmp"));
    // A format without a shader decoder: said so.
    let out = cli(&["render", "-q", m, "--format", "meshopt"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no shader decoder for meshopt"));
}

#[test]
fn export_writes_a_glb_the_loader_reads_back() {
    let dir = common::scratch("export-cli");
    let mesh = common::meshes_dir().join("stellarium_gaspra.ply.zst");
    let out = dir.join("gaspra.glb");
    let text = ok(&[
        "export",
        "-q",
        mesh.to_str().unwrap(),
        "--strategy",
        "bsphere",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        text.contains("meshlets") && text.contains("gaspra.glb"),
        "{text}"
    );
    let back = meshletlab::mesh::load(&out).unwrap();
    assert_eq!(back.triangle_count(), 32040);
    let colours = meshletlab::mesh::gltf_io::colours(&std::fs::read(&out).unwrap(), None).unwrap();
    let distinct: std::collections::HashSet<[u32; 4]> =
        colours.iter().map(|c| c.map(f32::to_bits)).collect();
    assert!(distinct.len() > 100, "{} colours", distinct.len());
    // A bad output path: one error line naming it.
    let out = cli(&[
        "export",
        "-q",
        mesh.to_str().unwrap(),
        "-o",
        "/nonexistent/x.glb",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.glb"));
}

#[test]
fn parity_and_render_print_json() {
    let dir = common::scratch("json");
    let mesh = common::meshes_dir().join("fandisk.ply.zst");
    let m = mesh.to_str().unwrap();
    let v: serde_json::Value = serde_json::from_str(&ok(&["parity", "-q", m, "--json"])).unwrap();
    assert_eq!(v["triangles"], 12946);
    assert_eq!(v["identical"], true);
    let checks = v["checks"].as_array().unwrap();
    // Every kernel family's check, each once.
    let families: Vec<&str> = checks
        .iter()
        .map(|c| c["name"].as_str().unwrap().split(':').next().unwrap())
        .collect();
    assert_eq!(
        families,
        [
            "adjacency",
            "k-medoids",
            "kmedoids-parallel",
            "bounds",
            "parallel grower",
            "LOD selection"
        ],
        "{v}"
    );
    for c in checks {
        assert!(
            c["mismatch"].is_null() && c["gpu_seconds"].as_f64().unwrap() > 0.0,
            "{c}"
        );
    }
    // The family names of the JSON, in order; `--skip` leaves exactly the named ones out.
    let names = |v: &serde_json::Value| -> Vec<String> {
        v["checks"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["family"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(
        names(&v),
        [
            "adjacency",
            "kmedoids-flat",
            "kmedoids-parallel",
            "bounds",
            "grower",
            "lod"
        ]
    );
    let skip = [
        "parity",
        "-q",
        m,
        "--json",
        "--skip",
        "kmedoids-flat,grower",
    ];
    let skipped: serde_json::Value = serde_json::from_str(&ok(&skip)).unwrap();
    assert_eq!(
        names(&skipped),
        ["adjacency", "kmedoids-parallel", "bounds", "lod"]
    );
    assert_eq!(
        skipped["skipped"],
        serde_json::json!(["kmedoids-flat", "grower"])
    );
    assert_eq!(skipped["identical"], true);
    let png = dir.join("f.png");
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "render",
        "-q",
        m,
        "--views",
        "3",
        "--json",
        "-o",
        png.to_str().unwrap(),
    ]))
    .unwrap();
    let views = v["views"].as_array().unwrap();
    assert_eq!(views.len(), 3);
    let meshlets = v["meshlets"].as_u64().unwrap();
    for w in views {
        let culled = w["meshlets_culled_frustum"].as_u64().unwrap()
            + w["meshlets_culled_backface"].as_u64().unwrap();
        assert_eq!(
            culled + w["meshlets_drawn"].as_u64().unwrap(),
            meshlets,
            "{w}"
        );
        // Framed: the camera sits just far enough that the mesh fits.
        let d = w["distance_radii"].as_f64().unwrap();
        assert!(d > 0.5 && d < 2.5, "{w}");
    }
    // The first view fills most of the frame: the drawn pixels span > 80 % of its height or width.
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut px = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut px).unwrap();
    let (w, h) = (info.width as usize, info.height as usize);
    let bg = px[..4].to_vec();
    let (mut x0, mut x1, mut y0, mut y1) = (w, 0, h, 0);
    for (i, p) in px.chunks_exact(4).enumerate() {
        if p != &bg[..] {
            let (x, y) = (i % w, i / w);
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
    }
    let fill = ((x1 - x0) as f64 / w as f64).max((y1 - y0) as f64 / h as f64);
    assert!(fill > 0.8, "the mesh spans {fill:.2} of the frame");
}

#[test]
fn lod_builds_a_dag_and_lod_check_validates_it() {
    let dir = common::scratch("lod-cli");
    let mesh = common::meshes_dir().join("stellarium_gaspra.ply.zst");
    let m = mesh.to_str().unwrap();
    let file = dir.join("gaspra.lod");
    let f = file.to_str().unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&ok(&["lod", "-q", m, "-o", f, "--json"])).unwrap();
    let levels = v["levels"].as_array().unwrap();
    assert!(levels.len() >= 6, "{v}");
    assert_eq!(levels[0]["triangles"], 32040);
    assert_eq!(v["roots"], 1);
    assert_eq!(v["stuck_groups"], 0);
    let out = ok(&["lod-check", "-q", m, f, "--views", "50"]);
    assert!(
        out.contains("valid") && out.contains("exactly one meshlet per DAG path"),
        "{out}"
    );
    // Another mesh, and a corrupted file: one error line naming the file.
    let other = common::meshes_dir().join("fandisk.ply.zst");
    let out = cli(&["lod-check", "-q", other.to_str().unwrap(), f]);
    assert!(!out.status.success());
    let mut bytes = std::fs::read(&file).unwrap();
    let n = bytes.len();
    bytes.truncate(n - 3);
    std::fs::write(&file, &bytes).unwrap();
    let out = cli(&["lod-check", "-q", m, f]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("gaspra.lod") && err.lines().count() == 1,
        "{err}"
    );
}

/// `render --lod` end to end on lavapipe: the DAG, the task-shader cut for each view checked
/// against the CPU reference by the command itself (exit 1 otherwise), the JSON report, the PNG,
/// and streaming (`--levels`).
#[test]
fn render_lod_runs_end_to_end() {
    let dir = common::scratch("render-lod");
    let mesh = common::meshes_dir().join("fandisk.ply.zst");
    let png = dir.join("lod.png");
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "render",
        "-q",
        mesh.to_str().unwrap(),
        "--lod",
        "--views",
        "3",
        "--validate",
        "--json",
        "-o",
        png.to_str().unwrap(),
    ]))
    .unwrap();
    assert_eq!(v["triangles"], 12946);
    let levels = v["levels"].as_u64().unwrap();
    assert!(levels > 2, "{v}");
    assert_eq!(v["levels_loaded"], levels);
    assert_eq!(v["validation_errors"], 0);
    let views = v["views"].as_array().unwrap();
    assert_eq!(views.len(), 3);
    for r in views {
        assert!(r["meshlets_drawn"].as_u64().unwrap() > 0, "{r}");
        assert_eq!(r["meshlets_drawn"], r["cpu_reference_drawn"], "{r}");
    }
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    // Streaming: only the two coarsest levels loaded.
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "render",
        "-q",
        mesh.to_str().unwrap(),
        "--lod",
        "--levels",
        "2",
        "--views",
        "2",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["levels_loaded"], 2);
    for r in v["views"].as_array().unwrap() {
        assert_eq!(r["meshlets_drawn"], r["cpu_reference_drawn"], "{r}");
    }
}

#[test]
fn building_on_the_gpu_writes_the_cpu_files_byte_for_byte() {
    let dir = common::scratch("device");
    let orders: [&[&str]; 2] = [&[], &["--local-order", "--meshlet-order", "triangles"]];
    for s in ["kmedoids-flat", "bsphere-parallel", "kmedoids-parallel"] {
        for (i, order) in orders.iter().enumerate() {
            for (what, ext) in [("build", "mlt"), ("export", "glb")] {
                let file = |device: &str| dir.join(format!("{s}-{i}-{device}.{ext}"));
                for device in ["cpu", "gpu"] {
                    let f = file(device);
                    let mut args =
                        vec![what, "-q", "gen:cad-part-128", "-s", s, "--device", device];
                    args.extend(["-o", f.to_str().unwrap()]);
                    args.extend_from_slice(order);
                    ok(&args);
                }
                let (cpu, gpu) = (file("cpu"), file("gpu"));
                assert_eq!(
                    std::fs::read(&cpu).unwrap(),
                    std::fs::read(&gpu).unwrap(),
                    "{what} {s} {order:?}: the GPU's file differs from the CPU's"
                );
            }
        }
    }
}

#[test]
fn stats_on_the_gpu_keeps_the_names_and_reports_build_and_setup_time() {
    let out = ok(&["stats", "-q", "gen:terrain", "--device", "gpu", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["device"], "gpu");
    let rows = v["strategies"].as_array().unwrap();
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["strategy"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["bsphere-parallel", "kmedoids-flat", "kmedoids-parallel"]
    );
    for r in rows {
        assert_eq!(r["device"], "gpu", "{r}");
        assert!(r["invalid"].is_null(), "{r}");
        assert!(r["build_ms"].as_f64().unwrap() > 0.0, "{r}");
        assert!(r["setup_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
    // The CPU rows carry the device too, and no setup time.
    let out = ok(&[
        "stats",
        "-q",
        "gen:terrain",
        "-s",
        "kmedoids-flat",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["strategies"][0]["device"], "cpu");
    assert!(v["strategies"][0].get("setup_ms").is_none());
}

#[test]
fn the_gpu_refuses_strategies_without_a_gpu_path_and_says_when_there_is_no_adapter() {
    let dir = common::scratch("device-refused");
    let f = dir.join("x.mlt");
    for s in ["meshopt", "kmedoids", "kmedoids-flat+refine"] {
        let out = cli(&["build", "gen:terrain", "-s", s, "--device", "gpu"]
            .into_iter()
            .chain(["-o", f.to_str().unwrap()])
            .collect::<Vec<_>>());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(
            err.contains(&format!("'{s}'")) && err.contains("no GPU path"),
            "{err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!f.exists());
    }
    // No Vulkan driver at all: the one-line error that names the way out.
    let out = Command::new(env!("CARGO_BIN_EXE_meshletlab"))
        .args(["stats", "gen:terrain", "--device", "gpu"])
        .env("VK_DRIVER_FILES", "/nonexistent.json")
        .env("VK_ICD_FILENAMES", "/nonexistent.json")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("no Vulkan adapter"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn kmedoids_regions_and_moves_knobs_reach_their_methods() {
    // gaspra (32 k triangles) is one region by default and many at 1024 triangles per region.
    let mesh = common::meshes_dir().join("stellarium_gaspra.ply.zst");
    // The JSON rows of `stats -s strategies` with one k-medoids option set, every row valid.
    let rows = |strategies: &str, option: &str, value: &str| {
        let out = ok(&[
            "stats",
            "-q",
            mesh.to_str().unwrap(),
            "--json",
            "-s",
            strategies,
            option,
            value,
        ]);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let rows = v["strategies"].as_array().unwrap().clone();
        assert!(rows.iter().all(|r| r["invalid"].is_null()), "{out}");
        rows
    };
    let meshlets = |regions: &str| {
        let rows = rows("kmedoids,kmedoids-parallel", "--kmedoids-regions", regions);
        let n = |i: usize| rows[i]["metrics"]["meshlets"].as_u64().unwrap();
        (n(0), n(1))
    };
    let (seq, whole) = meshlets("65536");
    let (seq_again, cut) = meshlets("1024");
    // The knob does not touch `kmedoids`.
    assert_eq!(seq_again, seq);
    // Many regions: part-filled clusters at their borders, a few more meshlets.
    assert!(cut > whole, "{cut} vs {whole}");
    // `--kmedoids-moves` reaches `kmedoids-parallel` (other clusters, the same count), not
    // `kmedoids`.
    let metrics = |moves: &str| {
        let rows = rows("kmedoids,kmedoids-parallel", "--kmedoids-moves", moves);
        let m = |i: usize| {
            let m = &rows[i]["metrics"];
            (
                m["meshlets"].as_u64().unwrap(),
                m["mean_radius_rel"].as_f64().unwrap(),
            )
        };
        [m(0), m(1)]
    };
    let ([s0, p0], [s2, p2]) = (metrics("0"), metrics("2"));
    assert_eq!(s0, s2);
    assert_eq!(p0.0, p2.0);
    assert_ne!(p0.1, p2.1);
    let out = cli(&[
        "stats",
        "-q",
        mesh.to_str().unwrap(),
        "--kmedoids-regions",
        "0",
    ]);
    assert!(!out.status.success());
}

#[test]
fn an_instanced_scene_is_built_once_per_mesh_by_stats_export_and_render() {
    let dir = common::scratch("scene-cli");
    let scene = meshletlab::mesh::load_scene("gen:scene-small".as_ref()).unwrap();
    let ml = |m: &meshletlab::mesh::Mesh| {
        meshletlab::strategy::by_name("meshopt", &Default::default())
            .unwrap()
            .build(m, meshletlab::meshlet::Limits::DEFAULT)
            .len()
    };
    let built: usize = scene.meshes().iter().map(ml).sum();
    let over: usize = scene
        .instances()
        .iter()
        .map(|i| ml(&scene.meshes()[i.mesh as usize]))
        .sum();
    let stats: serde_json::Value = serde_json::from_str(&ok(&[
        "stats",
        "-q",
        "gen:scene-small",
        "-s",
        "meshopt",
        "--json",
    ]))
    .unwrap();
    assert_eq!(stats["instances"], 9);
    assert_eq!(stats["strategies"][0]["meshlets_built"], built);
    assert_eq!(stats["strategies"][0]["meshlets_over_instances"], over);
    assert_eq!(stats["per_mesh"].as_array().unwrap().len(), 2);
    // Export keeps the instances; the file reads back as the same scene.
    let out = dir.join("scene.glb");
    ok(&[
        "export",
        "-q",
        "gen:scene-small",
        "-o",
        out.to_str().unwrap(),
    ]);
    let back = meshletlab::mesh::load_scene(&out).unwrap();
    assert_eq!((back.meshes().len(), back.instances().len()), (2, 9));
    assert_eq!(back.triangles_drawn(), scene.triangles_drawn());
    // Render draws each mesh's meshlets per instance.
    let r: serde_json::Value = serde_json::from_str(&ok(&[
        "render",
        "-q",
        "gen:scene-small",
        "--views",
        "2",
        "--json",
    ]))
    .unwrap();
    assert_eq!(r["meshlets_built"], built);
    assert_eq!(r["meshlets_over_instances"], over);
    for v in r["views"].as_array().unwrap() {
        let drawn = v["meshlets_drawn"].as_u64().unwrap();
        assert!(drawn > 0 && drawn <= over as u64, "{v}");
    }
}

#[test]
fn render_occlusion_checks_every_frame_and_reports_json() {
    let out = ok(&[
        "render",
        "-q",
        "gen:scene-small",
        "--occlusion",
        "--views",
        "1",
        "--frames",
        "3",
        "--json",
    ]);
    let r: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r["images_identical"], true, "{r}");
    assert_eq!(r["frames"], 2, "frames after the first");
    let (occ, full, oracle) = (
        r["triangles_occlusion"].as_u64().unwrap(),
        r["triangles_frustum_cone"].as_u64().unwrap(),
        r["triangles_oracle"].as_u64().unwrap(),
    );
    assert!(oracle > 0 && oracle <= occ && occ <= full, "{r}");
    let scene = meshletlab::mesh::load_scene("gen:scene-small".as_ref()).unwrap();
    let built: usize = scene
        .meshes()
        .iter()
        .map(|m| {
            meshletlab::strategy::by_name("meshopt", &Default::default())
                .unwrap()
                .build(m, meshletlab::meshlet::Limits::DEFAULT)
                .len()
        })
        .sum();
    assert_eq!(r["meshlets_built"], built);
    assert!(r["device_bytes_scene"].as_u64().unwrap() > 0);
    let views = r["views"].as_array().unwrap();
    assert_eq!(views.len(), 1);
    assert_eq!(views[0]["warm_up"]["meshlets_early"], 0);
    // With the LOD cut: the same report and check.
    let lod: serde_json::Value = serde_json::from_str(&ok(&[
        "render",
        "-q",
        "gen:scene-small",
        "--lod",
        "--threshold",
        "4",
        "--occlusion",
        "--views",
        "1",
        "--frames",
        "3",
        "--json",
    ]))
    .unwrap();
    assert_eq!(lod["images_identical"], true, "{lod}");
    assert!(lod["lod_levels"].as_u64().unwrap() > 1);
    assert!(lod["triangles_occlusion"].as_u64() <= lod["triangles_frustum_cone"].as_u64());
    // Occlusion is drawn in the split layout only, and never without frustum and cone culling.
    let bad = cli(&[
        "render",
        "-q",
        "gen:scene-small",
        "--occlusion",
        "--no-cull",
    ]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--no-cull"));
}
