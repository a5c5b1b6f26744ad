//! Every kind of bad input gets a typed error naming the file, and the CLI exits non-zero with one
//! readable line — never a panic, never a silently wrong mesh.

mod common;

use meshletlab::mesh::{self, MeshErrorKind};
use std::process::Command;

const HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                      element face 1\nproperty list uchar int vertex_indices\nend_header\n";

fn binary_ply() -> Vec<u8> {
    let m = mesh::generate::terrain(4, 1);
    let mut b = Vec::new();
    mesh::ply::write_binary(m.positions(), m.indices(), &mut b).unwrap();
    b
}

fn binary_stl() -> Vec<u8> {
    let m = mesh::generate::terrain(4, 1);
    let mut b = Vec::new();
    mesh::stl::write_binary(m.positions(), m.indices(), &mut b).unwrap();
    b
}

/// `binary_stl()` with `f` applied.
fn stl_with(f: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut b = binary_stl();
    f(&mut b);
    b
}

/// An ASCII STL of one triangle.
const STL: &str =
    "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n\
                   endloop\nendfacet\nendsolid t\n";

fn zst(data: &[u8]) -> Vec<u8> {
    zstd::stream::encode_all(data, 3).unwrap()
}

/// One bad file: name, contents, and a predicate on the error kind it must give.
type Case = (&'static str, Vec<u8>, fn(&MeshErrorKind) -> bool);

fn cases() -> Vec<Case> {
    let bin = binary_ply();
    let mut long = bin.clone();
    long.extend_from_slice(&[0u8; 13]);
    vec![
        ("nan.ply", format!("{HEADER}0 0 0\nnan 1 0\n0 1 0\n3 0 1 2\n").into_bytes(), |k| matches!(k, MeshErrorKind::NonFinite { vertex: 1, .. })),
        ("inf.ply", format!("{HEADER}0 0 0\n1 1e39 0\n0 1 0\n3 0 1 2\n").into_bytes(), |k| matches!(k, MeshErrorKind::NonFinite { vertex: 1, .. })),
        ("range.ply", format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("negative.ply", format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("empty.ply", HEADER.replace("element face 1", "element face 0").replace("3 0 1 2\n", "").into_bytes()
            .into_iter().chain(b"0 0 0\n1 0 0\n0 1 0\n".iter().copied()).collect(), |k| matches!(k, MeshErrorKind::Empty(_))),
        ("no_vertices.ply", b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n".to_vec(), |k| matches!(k, MeshErrorKind::Empty(_))),
        ("truncated.ply", bin[..bin.len() - 5].to_vec(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("truncated_header.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n".to_vec(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("too_long.ply", long, |k| matches!(k, MeshErrorKind::CountMismatch(_))),
        ("short_ascii.ply", format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n").into_bytes(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("long_ascii.ply", format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n").into_bytes(), |k| matches!(k, MeshErrorKind::CountMismatch(_))),
        ("absurd.ply", HEADER.replace("element vertex 3", "element vertex 4000000000").into_bytes(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("absurd_face.ply", HEADER.replace("element face 1", "element face 18446744073709551615").into_bytes(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("huge.ply", HEADER.replace("element vertex 3", "element vertex 99999999999").into_bytes(), |k| matches!(k, MeshErrorKind::TooLarge(_))),
        ("type.ply", HEADER.replace("property float z", "property half z").into_bytes(), |k| matches!(k, MeshErrorKind::Unsupported(_))),
        ("list_type.ply", HEADER.replace("uchar int", "uchar double").into_bytes(), |k| matches!(k, MeshErrorKind::Unsupported(_))),
        ("format.ply", HEADER.replace("ascii", "binary_middle_endian").into_bytes(), |k| matches!(k, MeshErrorKind::Unsupported(_))),
        ("garbage.ply", b"\x00\x01\x02 not a ply".to_vec(), |k| matches!(k, MeshErrorKind::Parse { .. } | MeshErrorKind::Truncated(_))),
        ("text.ply", format!("{HEADER}0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("line.ply", format!("{HEADER}0 0 0\n1 0 0\n0 1 0\n2 0 1\n").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("mesh.xyz", b"1 2 3\n".to_vec(), |k| matches!(k, MeshErrorKind::UnknownFormat)),
        ("corrupt.ply.zst", b"\x28\xb5\x2f\xfd garbage".to_vec(), |k| matches!(k, MeshErrorKind::Decompress(_))),
        ("cut.ply.zst", { let z = zst(&binary_ply()); z[..z.len() / 2].to_vec() }, |k| matches!(k, MeshErrorKind::Decompress(_))),
        ("nan_in.ply.zst", zst(format!("{HEADER}0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n").as_bytes()), |k| matches!(k, MeshErrorKind::NonFinite { vertex: 2, .. })),
        // OBJ errors name their line (tobj's own errors do not).
        ("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec(), |k| matches!(k, MeshErrorKind::Parse { location, .. } if location == "line 4")),
        ("number.obj", b"v 0 0 0\nv 1 0,5 0\nv 0 1 0\nf 1 2 3\n".to_vec(), |k| matches!(k, MeshErrorKind::Parse { location, .. } if location == "line 2")),
        ("index.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nf 1 2 3.0\n".to_vec(), |k| matches!(k, MeshErrorKind::Parse { location, .. } if location == "line 6")),
        ("nan.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(), |k| matches!(k, MeshErrorKind::Parse { location, message } if location == "line 2" && message.contains("non-finite"))),
        ("empty.obj", b"# nothing\nv 0 0 0\n".to_vec(), |k| matches!(k, MeshErrorKind::Empty(_))),
        ("truncated.stl", stl_with(|b| b.truncate(b.len() - 7)), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("too_long.stl", stl_with(|b| b.extend_from_slice(&[0u8; 13])), |k| matches!(k, MeshErrorKind::CountMismatch(_))),
        // A header beginning with "solid" does not make a cut binary file ASCII.
        ("solid_truncated.stl", stl_with(|b| { b[..5].copy_from_slice(b"solid"); b.truncate(b.len() - 50) }), |k| matches!(k, MeshErrorKind::Truncated(_))),
        // 4 G facets announced by a 1 KiB file: refused before anything is allocated.
        ("absurd.stl", stl_with(|b| b[80..84].copy_from_slice(&u32::MAX.to_le_bytes())), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("no_facets.stl", stl_with(|b| { b.truncate(84); b[80..84].fill(0) }), |k| matches!(k, MeshErrorKind::Empty(_))),
        ("short.stl", b"not an stl".to_vec(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("inf.stl", stl_with(|b| b[84 + 50 + 16..84 + 50 + 20].copy_from_slice(&f32::INFINITY.to_le_bytes())), |k| matches!(k, MeshErrorKind::NonFinite { vertex: 3, .. })),
        ("nan.stl", STL.replace("vertex 1 0 0", "vertex 1 nan 0").into_bytes(), |k| matches!(k, MeshErrorKind::NonFinite { vertex: 1, .. })),
        ("big.stl", STL.replace("vertex 0 1 0", "vertex 0 1 1e39").into_bytes(), |k| matches!(k, MeshErrorKind::NonFinite { vertex: 2, .. })),
        ("keyword.stl", STL.replace("outer loop", "outer lop").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("number.stl", STL.replace("vertex 1 0 0", "vertex 1,5 0 0").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("four_corners.stl", STL.replace("endloop", "vertex 1 1 0\nendloop").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("cut_ascii.stl", STL.as_bytes()[..STL.len() - 30].to_vec(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("empty.stl", b"solid nothing\nendsolid nothing\n".to_vec(), |k| matches!(k, MeshErrorKind::Empty(_))),
        ("trailing.stl", format!("{STL}facet").into_bytes(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("nan_in.stl.zst", zst(&stl_with(|b| b[84 + 24..84 + 28].copy_from_slice(&f32::NAN.to_le_bytes()))), |k| matches!(k, MeshErrorKind::NonFinite { vertex: 1, .. })),
        ("bad.gltf", b"{ not json".to_vec(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("bad.glb", b"glTF\x02\x00\x00\x00\xff\xff\xff\xff".to_vec(), |k| matches!(k, MeshErrorKind::Truncated(_))),
        ("short.glb", b"glTF\x02\x00\x00\x00\x05\x00\x00\x00".to_vec(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("accessor_range.gltf", br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}"#.to_vec(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("node_cycle.gltf", br#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"children":[1]},{"children":[0]}]}"#.to_vec(), |k| matches!(k, MeshErrorKind::Parse { .. })),
        ("empty.gltf", br#"{"asset":{"version":"2.0"}}"#.to_vec(), |k| matches!(k, MeshErrorKind::Empty(_))),
        // Four bytes of meshopt stream announcing 4 G vertices: refused before decoding or allocating.
        ("meshopt_bomb.gltf", br#"{"asset":{"version":"2.0"},"extensionsRequired":["EXT_meshopt_compression"],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
            "buffers":[{"byteLength":4,"uri":"data:application/octet-stream;base64,oAAAAA=="},
                       {"byteLength":48,"extensions":{"EXT_meshopt_compression":{"fallback":true}}}],
            "bufferViews":[{"buffer":1,"byteLength":48,"byteStride":12,"extensions":{"EXT_meshopt_compression":
                {"buffer":0,"byteLength":4,"byteStride":12,"count":4000000000,"mode":"ATTRIBUTES"}}}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}]}"#.to_vec(), |k| matches!(k, MeshErrorKind::TooLarge(_))),
        // An accessor of zeros needs no bytes in the file, but its size is budgeted all the same.
        ("zeros_bomb.gltf", br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
            "accessors":[{"componentType":5126,"count":4000000000,"type":"VEC3"}]}"#.to_vec(), |k| matches!(k, MeshErrorKind::TooLarge(_))),
        ("draco.gltf", br#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"]}"#.to_vec(),
            |k| matches!(k, MeshErrorKind::UnsupportedExtension { name, .. } if name == "KHR_draco_mesh_compression")),
    ]
}

#[test]
fn library_errors_are_typed_and_name_the_file() {
    let dir = common::scratch("bad-lib");
    for (name, data, want) in cases() {
        let path = dir.join(name);
        std::fs::write(&path, &data).unwrap();
        let err = match mesh::load(&path) {
            Ok(m) => panic!(
                "{name}: loaded a mesh with {} triangles",
                m.triangle_count()
            ),
            Err(e) => e,
        };
        assert!(want(&err.kind), "{name}: unexpected error kind: {err}");
        let msg = err.to_string();
        assert!(
            msg.starts_with(&path.display().to_string()),
            "{name}: message does not name the file: {msg}"
        );
        assert!(!msg.contains('\n'), "{name}: multi-line message: {msg}");
    }
    assert!(matches!(
        mesh::load(&dir.join("missing.ply")).unwrap_err().kind,
        MeshErrorKind::Io(_)
    ));
}

fn cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_meshletlab"))
        .args(args)
        .output()
        .expect("binary runs")
}

#[test]
fn cli_exits_nonzero_with_one_line_naming_the_file() {
    let dir = common::scratch("bad-cli");
    let mut all = cases();
    all.push(("missing.ply", Vec::new(), |_| true));
    for (name, data, _) in all {
        let path = dir.join(name);
        if name != "missing.ply" {
            std::fs::write(&path, &data).unwrap();
        }
        for cmd in [
            &["stats", "-q"][..],
            &["build", "-q", "-s", "nvidia", "-o", "/dev/null"][..],
        ] {
            let mut args = cmd.to_vec();
            let p = path.display().to_string();
            args.insert(1, &p);
            let out = cli(&args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "{name}: exit status {}", out.status);
            assert_eq!(
                stderr.trim_end().lines().count(),
                1,
                "{name}: stderr is not one line:\n{stderr}"
            );
            assert!(
                stderr.starts_with("error: ") && stderr.contains(&p),
                "{name}: {stderr}"
            );
            assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        }
    }
}

#[test]
fn degenerate_duplicate_and_non_manifold_input_is_legal_and_counted() {
    // Two identical triangles, one reversed copy, a fin on edge 0-1, a repeated index and a
    // zero-area sliver: all legal, all counted, all placed by every strategy.
    let text = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n\
                element face 6\nproperty list uchar int vertex_indices\nend_header\n\
                0 0 0\n1 0 0\n0 1 0\n0 0 1\n2 0 0\n0.5 0 0\n\
                3 0 1 2\n3 0 1 2\n3 0 2 1\n3 0 1 3\n3 3 3 2\n3 0 5 1\n";
    let dir = common::scratch("legal");
    let path = dir.join("legal.ply");
    std::fs::write(&path, text).unwrap();
    let m = mesh::load(&path).unwrap();
    let s = mesh::MeshStats::of(&m);
    assert_eq!(
        (
            s.degenerate_triangles,
            s.zero_area_triangles,
            s.duplicate_triangles
        ),
        (1, 1, 2)
    );
    assert!(s.non_manifold_edges >= 1);
    let out = cli(&["stats", "-q", &path.display().to_string()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("degenerate 1") && stdout.contains("duplicate 2"),
        "{stdout}"
    );
    let fast = meshletlab::strategy::NAMES.len() - meshletlab::strategy::SLOW.len();
    assert_eq!(stdout.matches("| ok").count(), fast, "{stdout}");
}

#[test]
fn a_directory_is_refused_as_a_directory() {
    let dir = common::scratch("bad-dir");
    // Also one whose name says PLY: the folder is refused before the format is looked at.
    let named = dir.join("folder.ply");
    std::fs::create_dir(&named).unwrap();
    for path in [dir.to_path_buf(), named, dir.join("scene.gltf")] {
        std::fs::create_dir_all(&path).unwrap();
        for e in [
            mesh::load(&path).unwrap_err(),
            mesh::load_scene(&path).unwrap_err(),
        ] {
            assert!(matches!(e.kind, MeshErrorKind::IsDirectory), "{e}");
            assert_eq!(e.to_string(), format!("{}: is a directory", path.display()));
        }
        let p = path.display().to_string();
        let out = cli(&["stats", "-q", &p]);
        assert!(!out.status.success());
        assert_eq!(
            String::from_utf8_lossy(&out.stderr).trim_end(),
            format!("error: {p}: is a directory")
        );
    }
}

#[test]
fn a_failed_write_is_a_write_error() {
    let m = mesh::generate::terrain(4, 1);
    let dir = common::scratch("bad-write");
    for path in [
        std::path::PathBuf::from("/proc/meshletlab.ply"),
        dir.join("no/such/folder.ply"),
    ] {
        let e = mesh::save_ply(&m, &path).unwrap_err();
        assert!(matches!(e.kind, MeshErrorKind::Write(_)), "{e}");
        let msg = e.to_string();
        assert!(
            msg.starts_with(&format!("{}: cannot write: ", path.display())),
            "{msg}"
        );
    }
    let e = mesh::save_ply(&m, &dir).unwrap_err();
    assert!(matches!(e.kind, MeshErrorKind::IsDirectory), "{e}");
}

#[test]
fn subdivide_over_the_budget_is_refused_at_once() {
    use meshletlab::mesh::subdivide::{subdivide, SubdivideError, MAX_TRIANGLES};
    let m = mesh::generate::terrain(4, 1);
    let t0 = std::time::Instant::now();
    // 18 triangles x 4^20 is 2 x 10^13: any allocation or level of work would take far longer.
    let e = subdivide(&m, 20).unwrap_err();
    assert!(t0.elapsed().as_secs() < 1);
    assert!(
        matches!(e, SubdivideError::OverBudget { levels: 20, .. }),
        "{e}"
    );
    assert!(e.to_string().contains(&MAX_TRIANGLES.to_string()), "{e}");
    // The command says so naming the input, and writes nothing.
    let dir = common::scratch("bad-subdivide");
    let out_path = dir.join("out.ply");
    let big = dir.join("big.ply");
    // 2,178 triangles: 8 levels would make 143 M, over 2^27.
    mesh::save_ply(&mesh::generate::terrain(34, 1), &big).unwrap();
    let (b, o) = (big.display().to_string(), out_path.display().to_string());
    let out = cli(&["subdivide", "-q", &b, "-o", &o, "--levels", "8"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.starts_with(&format!(
            "error: {b}: 8 level(s) would turn 2178 triangles into 142737408"
        )) && stderr.contains("at most 7 level(s)"),
        "{stderr}"
    );
    assert!(!out_path.exists());
    let help = cli(&["subdivide", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(
        help.contains(&format!("at most {MAX_TRIANGLES} triangles")),
        "{help}"
    );
}

#[test]
fn subdivide_writes_only_ply_names_and_says_why_a_write_fails() {
    let dir = common::scratch("bad-subdivide-out");
    let input = dir.join("in.ply");
    mesh::save_ply(&mesh::generate::terrain(4, 1), &input).unwrap();
    let i = input.display().to_string();
    for name in ["out.obj", "out.PLY.gz", "out"] {
        let o = dir.join(name).display().to_string();
        let out = cli(&["subdivide", "-q", &i, "-o", &o]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{name}");
        assert!(
            stderr.starts_with(&format!("error: {o}: "))
                && stderr.contains("binary PLY")
                && stderr.contains(".ply or .ply.zst"),
            "{name}: {stderr}"
        );
        assert!(!dir.join(name).exists(), "{name}");
    }
    // Refused before the input is read: a missing input is not what it reports.
    let o = dir.join("out.obj").display().to_string();
    let out = cli(&["subdivide", "-q", "missing.ply", "-o", &o]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("binary PLY"));
    let out = cli(&["subdivide", "-q", &i, "-o", "/proc/x.ply"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.starts_with("error: /proc/x.ply: cannot write") && !stderr.contains("cannot read"),
        "{stderr}"
    );
    // Both accepted names, in any case, are written and read back.
    for name in ["out.PLY", "out.Ply.ZST"] {
        let o = dir.join(name).display().to_string();
        let out = cli(&["subdivide", "-q", &i, "-o", &o]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(
            mesh::load(&dir.join(name)).unwrap().triangle_count(),
            18 * 4
        );
    }
}
