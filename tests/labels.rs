//! Clusterings made elsewhere: per-triangle ids and `.npz` meshlets in, measured like a
//! strategy's output; any meshlets back out as ids. Library calls first, then the command line.

mod common;

use common::{cli, ok};
use meshletlab::mesh::{generate, Mesh};
use meshletlab::meshlet::npz::{load_meshlets, save_npz};
use meshletlab::meshlet::{validate, Limits, Meshlets};
use meshletlab::strategy::labels::{from_labels, split_meshlets, triangle_labels, LabelsError};
use meshletlab::strategy::{Kind, Options};
use std::collections::BTreeSet;

/// Each meshlet's triangles as a set of canonical triangles: what a clustering is, whatever
/// order its meshlets list their triangles and vertices in.
fn clusters(ml: &Meshlets) -> BTreeSet<BTreeSet<[u32; 3]>> {
    (0..ml.len())
        .map(|i| {
            ml.global_triangles(i)
                .map(meshletlab::meshlet::canonical)
                .collect()
        })
        .collect()
}

fn sphere() -> Mesh {
    generate::noisy_sphere(4, 0.2, 3)
}

#[test]
fn a_strategys_labels_give_back_its_clusters_on_real_and_stress_meshes() {
    let meshes = [
        common::load("fandisk"),
        generate::named("cad-part-128").unwrap(),
    ];
    for m in &meshes {
        for kind in [Kind::Meshopt, Kind::Kmedoids] {
            let ml = kind.strategy(&Options::default()).build(m, Limits::DEFAULT);
            let labels = triangle_labels(m, &ml).unwrap();
            assert_eq!(labels.len(), m.triangle_count());
            // Ids scattered with gaps: the same clusters, in ascending id order.
            let ids: Vec<u64> = labels.iter().map(|&l| 1000 * l as u64 + 7).collect();
            let c = from_labels(m, &ids, Limits::DEFAULT, false).unwrap();
            validate(m, &c.meshlets, Limits::DEFAULT).unwrap();
            assert_eq!((c.clusters, c.split), (ml.len(), 0));
            assert_eq!(clusters(&c.meshlets), clusters(&ml), "{}", kind.name());
            // Meshlet i holds the triangles labelled i.
            assert_eq!(triangle_labels(m, &c.meshlets).unwrap(), labels);
        }
    }
}

#[test]
fn an_over_limit_cluster_is_refused_by_id_or_split_by_meshopt() {
    let m = sphere();
    let t = m.triangle_count();
    // Triangles 0..200 in cluster 42, the rest one triangle each.
    let ids: Vec<u64> = (0..t as u64)
        .map(|i| if i < 200 { 42 } else { 100 + i })
        .collect();
    let err = from_labels(&m, &ids, Limits::DEFAULT, false).unwrap_err();
    let LabelsError::OverLimits {
        id,
        triangles,
        vertices,
        ..
    } = err
    else {
        panic!("expected OverLimits, got {err:?}");
    };
    assert_eq!((id, triangles), (42, 200));
    assert!(
        vertices > 64,
        "200 triangles of a sphere use more than 64 vertices: {vertices}"
    );
    assert!(
        err.to_string().contains("cluster 42: 200 triangles"),
        "{err}"
    );

    let c = from_labels(&m, &ids, Limits::DEFAULT, true).unwrap();
    validate(&m, &c.meshlets, Limits::DEFAULT).unwrap();
    assert_eq!(c.split, 1);
    assert_eq!(c.clusters, 1 + (t - 200));
    // The split cluster alone became several meshlets; every single-triangle cluster stayed one.
    assert!(
        c.meshlets.len() > c.clusters,
        "{} meshlets",
        c.meshlets.len()
    );
    // The whole mesh as one cluster, split, is meshoptimizer's own partition.
    let all = from_labels(&m, &vec![0; t], Limits::DEFAULT, true).unwrap();
    let peer = Kind::Meshopt
        .strategy(&Options::default())
        .build(&m, Limits::DEFAULT);
    assert_eq!(clusters(&all.meshlets), clusters(&peer));
}

#[test]
fn a_label_array_of_the_wrong_length_is_refused() {
    let m = sphere();
    let e = from_labels(&m, &[0; 5], Limits::DEFAULT, true).unwrap_err();
    assert_eq!(
        e,
        LabelsError::Length {
            expected: m.triangle_count(),
            found: 5
        }
    );
}

#[test]
fn clusters_in_pieces_show_in_the_connected_metric() {
    let m = sphere();
    let ml = Kind::Meshopt
        .strategy(&Options::default())
        .build(&m, Limits::DEFAULT);
    let mut labels: Vec<u64> = triangle_labels(&m, &ml)
        .unwrap()
        .iter()
        .map(|&l| l as u64)
        .collect();
    let measure = |labels: &[u64]| {
        let c = from_labels(&m, labels, Limits::DEFAULT, true).unwrap();
        let b = meshletlab::meshlet::bounds::compute_bounds(&m, &c.meshlets);
        meshletlab::meshlet::Metrics::compute(&m, &c.meshlets, Limits::DEFAULT, &b, None).connected
    };
    let whole = measure(&labels);
    // Swap one triangle between two far-apart clusters: both are now in two pieces.
    let (a, b) = (0, m.triangle_count() - 1);
    assert_ne!(labels[a], labels[b]);
    labels.swap(a, b);
    let broken = measure(&labels);
    assert!(broken < whole, "connected {broken} vs {whole}");
}

#[test]
fn meshlets_round_trip_through_npz_and_over_limit_ones_are_split() {
    let m = common::load("fandisk");
    let dir = common::scratch("labels");
    let path = dir.join("m.npz");
    // meshoptimizer's arrays pad each meshlet's corners: the padding reads back.
    let big = Limits::new(128, 256).unwrap();
    let ml = Kind::Meshopt.strategy(&Options::default()).build(&m, big);
    save_npz(&path, &ml).unwrap();
    let back = load_meshlets(&path, &m).unwrap();
    assert_eq!(back, ml);
    let err = split_meshlets(&m, back.clone(), Limits::DEFAULT, false).unwrap_err();
    assert!(matches!(err, LabelsError::OverLimits { .. }), "{err:?}");
    let (split, n) = split_meshlets(&m, back, Limits::DEFAULT, true).unwrap();
    validate(&m, &split, Limits::DEFAULT).unwrap();
    assert!(n > 0 && split.len() > ml.len());
    // Meshlets for another mesh are refused, naming the file.
    let other = sphere();
    let e = load_meshlets(&path, &other).unwrap_err().to_string();
    assert!(e.starts_with(&path.display().to_string()), "{e}");
}

/// The `stats --json` rows by name: their metrics without the build time.
fn rows(json: &str) -> Vec<(String, serde_json::Value)> {
    let v: serde_json::Value = serde_json::from_str(json).unwrap();
    v["strategies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let mut m = r["metrics"].clone();
            m.as_object_mut().unwrap().remove("build_ms");
            (r["strategy"].as_str().unwrap().to_string(), m)
        })
        .collect()
}

/// Two metrics objects of the same clusters: counts and histograms equal, means equal up to the
/// rounding of summing a meshlet's vertices in another order.
fn same_metrics(a: &serde_json::Value, b: &serde_json::Value) {
    let (a, b) = (a.as_object().unwrap(), b.as_object().unwrap());
    assert_eq!(a.len(), b.len());
    for (k, x) in a {
        let y = &b[k];
        match (x.as_u64(), x.as_f64()) {
            (None, Some(f)) => {
                let g = y.as_f64().unwrap();
                assert!((f - g).abs() <= 1e-12 * f.abs().max(1.0), "{k}: {f} vs {g}");
            }
            _ => assert_eq!(x, y, "{k}"),
        }
    }
}

#[test]
fn labels_out_then_labels_in_measures_the_same_meshlets_on_every_command() {
    let dir = common::scratch("labels");
    let d = |f: &str| dir.join(f).display().to_string();
    let mesh = "gen:cad-part-128";
    // The same clusters as text and as .npy.
    ok(&[
        "build",
        mesh,
        "-s",
        "kmedoids",
        "-o",
        &d("k.mlt"),
        "--labels-out",
        &d("k.txt"),
    ]);
    ok(&[
        "build",
        mesh,
        "-s",
        "kmedoids",
        "-o",
        &d("k2.mlt"),
        "--labels-out",
        &d("k.npy"),
    ]);
    // Each file's row equals kmedoids' own, which `stats` lists first.
    for (flag, file) in [
        ("--labels", "k.txt"),
        ("--labels", "k.npy"),
        ("--meshlets", "k.mlt"),
    ] {
        let r = rows(&ok(&[
            "stats",
            mesh,
            "-s",
            "kmedoids",
            flag,
            &d(file),
            "--json",
        ]));
        assert_eq!(r.len(), 2);
        assert_eq!(r[1].0, format!("{}:{file}", &flag[2..]));
        same_metrics(&r[0].1, &r[1].1);
    }
    // build from labels writes a meshlet file `check` accepts.
    ok(&["build", mesh, "--labels", &d("k.txt"), "-o", &d("l.mlt")]);
    assert!(ok(&["check", mesh, &d("l.mlt")]).contains("valid"));
    // export, compress, lod.
    ok(&["export", mesh, "--labels", &d("k.npy"), "-o", &d("l.glb")]);
    assert!(meshletlab::mesh::load(&dir.join("l.glb")).is_ok());
    let c = ok(&[
        "compress",
        mesh,
        "--labels",
        &d("k.txt"),
        "-o",
        &d("l.cmp"),
        "--json",
    ]);
    let c: serde_json::Value = serde_json::from_str(&c).unwrap();
    assert_eq!(c["strategy"], "labels:k.txt");
    assert!(ok(&["check", mesh, &d("l.cmp")]).contains("valid"));
    let l = ok(&[
        "lod",
        mesh,
        "--labels",
        &d("k.txt"),
        "-o",
        &d("l.lod"),
        "--json",
    ]);
    let l: serde_json::Value = serde_json::from_str(&l).unwrap();
    assert_eq!(l["level0"], "labels:k.txt");
    let built = meshletlab::meshlet::io::MeshletFile::load(&dir.join("k.mlt")).unwrap();
    assert_eq!(l["levels"][0]["meshlets"], built.meshlets.len());
    ok(&["lod-check", mesh, &d("l.lod")]);
}

#[test]
fn render_draws_labels_plain_compressed_and_as_lod_level_zero() {
    let dir = common::scratch("labels");
    let d = |f: &str| dir.join(f).display().to_string();
    let mesh = "gen:cad-part-128";
    ok(&[
        "build",
        mesh,
        "-s",
        "meshopt",
        "-o",
        &d("m.mlt"),
        "--labels-out",
        &d("m.txt"),
    ]);
    let plain = ok(&[
        "render",
        mesh,
        "--labels",
        &d("m.txt"),
        "--views",
        "1",
        "--json",
        "-o",
        &d("a.png"),
    ]);
    let plain: serde_json::Value = serde_json::from_str(&plain).unwrap();
    assert_eq!(plain["strategy"], "labels:m.txt");
    // The same clusters draw the same image as the strategy that made them.
    ok(&[
        "render",
        mesh,
        "-s",
        "meshopt",
        "--views",
        "1",
        "-o",
        &d("b.png"),
    ]);
    assert_eq!(
        std::fs::read(dir.join("a.png")).unwrap(),
        std::fs::read(dir.join("b.png")).unwrap()
    );
    ok(&[
        "render",
        mesh,
        "--labels",
        &d("m.txt"),
        "--format",
        "sc-compact",
        "--views",
        "1",
    ]);
    let lod = ok(&[
        "render",
        mesh,
        "--meshlets",
        &d("m.mlt"),
        "--lod",
        "--views",
        "1",
    ]);
    assert!(lod.contains("meshlets:m.mlt"), "{lod}");
}

#[test]
fn bad_label_and_meshlet_files_get_one_line_naming_the_file() {
    let dir = common::scratch("labels");
    let d = |f: &str| dir.join(f).display().to_string();
    let mesh = "gen:noisy-sphere";
    let t = meshletlab::mesh::load(std::path::Path::new(mesh))
        .unwrap()
        .triangle_count();
    let lines = |ids: Vec<String>| ids.join("\n") + "\n";
    let write = |f: &str, s: &[u8]| std::fs::write(dir.join(f), s).unwrap();
    write("short.txt", lines(vec!["1".into(); t - 1]).as_bytes());
    let mut neg = vec!["1".to_string(); t];
    neg[10] = "-3".into();
    write("neg.txt", lines(neg).as_bytes());
    let mut word = vec!["1".to_string(); t];
    word[4] = "one".into();
    write("word.txt", lines(word).as_bytes());
    write("one.txt", lines(vec!["9".into(); t]).as_bytes());
    write("lying.npy", &npy_header("<i8", "(99999999999,)"));
    write("junk.npz", b"PK\x03\x04 not a zip");
    for (file, flag, says) in [
        (
            "short.txt",
            "--labels",
            format!("{} cluster ids for a mesh of {t} triangles", t - 1),
        ),
        (
            "neg.txt",
            "--labels",
            "line 11: negative cluster id -3".into(),
        ),
        (
            "word.txt",
            "--labels",
            "line 5: 'one' is not a cluster id".into(),
        ),
        ("one.txt", "--labels", format!("cluster 9: {t} triangles")),
        ("lying.npy", "--labels", "larger than".into()),
        ("junk.npz", "--meshlets", "not an .npz".into()),
    ] {
        let out = cli(&["stats", mesh, "-s", "meshopt", flag, &d(file)]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{file}: {err}");
        assert_eq!(err.lines().count(), 1, "{file}: {err}");
        assert!(
            err.contains(&format!("{}: ", d(file))) && err.contains(&says),
            "{file}: {err}"
        );
    }
    // --split divides what was refused.
    let s = ok(&[
        "stats",
        mesh,
        "-s",
        "meshopt",
        "--labels",
        &d("one.txt"),
        "--split",
    ]);
    assert!(s.contains("1 clusters in the file, 1 of them split"), "{s}");
    // Usage errors: --split alone, a strategy beside a file, an instanced scene.
    for args in [
        vec!["build", mesh, "--split", "-s", "meshopt", "-o", "x.mlt"],
        vec![
            "export", mesh, "-s", "meshopt", "--labels", "x.txt", "-o", "x.glb",
        ],
        vec!["render", mesh, "--labels", "x.txt", "--occlusion"],
    ] {
        assert_eq!(cli(&args).status.code(), Some(2), "{args:?}");
    }
    let out = cli(&["stats", "gen:scene-small", "--labels", &d("one.txt")]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("instanced scene"));
}

/// A `.npy` header (version 1) and no data: what a file that lies about its size starts with.
fn npy_header(descr: &str, shape: &str) -> Vec<u8> {
    let mut h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + h.len() + 1) % 64 != 0 {
        h.push(' ');
    }
    h.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(h.len() as u16).to_le_bytes());
    out.extend_from_slice(h.as_bytes());
    out
}
