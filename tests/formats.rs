//! Every input format gives the same mesh as the reference binary PLY, and glTF node transforms are
//! applied (including mirrored instances, whose winding is flipped to keep front faces).

mod common;

use meshletlab::mesh::{self, Mesh};
use std::fmt::Write as _;

fn real() -> Mesh {
    common::load("fandisk")
}

/// Same triangles in the same order with bit-identical corner positions; vertex numbering may differ
/// (tobj renumbers vertices in first-use order).
fn same_geometry(a: &Mesh, b: &Mesh) {
    assert_eq!(a.triangle_count(), b.triangle_count());
    assert_eq!(
        a.vertex_count(),
        b.vertex_count(),
        "every vertex is referenced, so none is dropped"
    );
    for t in 0..a.triangle_count() {
        let pa = a.triangle(t).map(|v| a.positions()[v as usize]);
        let pb = b.triangle(t).map(|v| b.positions()[v as usize]);
        assert_eq!(pa, pb, "triangle {t}");
    }
}

#[test]
fn obj_ascii_ply_and_big_endian_ply_match_binary_ply() {
    let m = real();
    let dir = common::scratch("formats");
    // OBJ: one object, every vertex referenced, so tobj keeps the vertex order.
    let mut obj = String::new();
    for p in m.positions() {
        writeln!(obj, "v {:?} {:?} {:?}", p[0], p[1], p[2]).unwrap();
    }
    for t in m.indices().chunks_exact(3) {
        writeln!(obj, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    std::fs::write(dir.join("m.obj"), &obj).unwrap();
    same_geometry(&mesh::load(&dir.join("m.obj")).unwrap(), &m);
    std::fs::write(
        dir.join("m.obj.zst"),
        zstd::encode_all(obj.as_bytes(), 1).unwrap(),
    )
    .unwrap();
    same_geometry(&mesh::load(&dir.join("m.obj.zst")).unwrap(), &m);

    let header = |fmt: &str| {
        format!(
            "ply\nformat {fmt} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            m.vertex_count(),
            m.triangle_count()
        )
    };
    let mut ascii = header("ascii");
    for p in m.positions() {
        writeln!(ascii, "{:?} {:?} {:?}", p[0], p[1], p[2]).unwrap();
    }
    for t in m.indices().chunks_exact(3) {
        writeln!(ascii, "3 {} {} {}", t[0], t[1], t[2]).unwrap();
    }
    std::fs::write(dir.join("a.ply"), ascii).unwrap();
    assert_eq!(mesh::load(&dir.join("a.ply")).unwrap(), m);

    let mut be = header("binary_big_endian").into_bytes();
    for p in m.positions() {
        for c in p {
            be.extend_from_slice(&c.to_be_bytes());
        }
    }
    for t in m.indices().chunks_exact(3) {
        be.push(3);
        for i in t {
            be.extend_from_slice(&i.to_be_bytes());
        }
    }
    std::fs::write(dir.join("be.PLY"), be).unwrap();
    assert_eq!(mesh::load(&dir.join("be.PLY")).unwrap(), m);
}

/// A glTF with one triangle mesh instanced twice (identity; mirrored in x and moved +5 y under a
/// parent node moved +10 x),
/// a second mesh no node uses (a 4-vertex strip), and a points primitive that must be skipped.
fn gltf_json(bin_len: usize, uri: Option<&str>) -> String {
    let uri = uri.map(|u| format!(r#","uri":"{u}""#)).unwrap_or_default();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
  "nodes":[{{"mesh":0}},{{"translation":[10,0,0],"children":[2]}},{{"mesh":0,"scale":[-1,1,1],"translation":[0,5,0]}}],
  "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}},{{"attributes":{{"POSITION":0}},"mode":0}}]}},
            {{"primitives":[{{"attributes":{{"POSITION":2}},"mode":5}}]}}],
  "buffers":[{{"byteLength":{bin_len}{uri}}}],
  "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}},
                 {{"buffer":0,"byteOffset":44,"byteLength":48}}],
  "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
               {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}},
               {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,2],"max":[1,1,2]}}]}}"#
    )
}

fn gltf_bin() -> Vec<u8> {
    let mut b = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b.extend_from_slice(&[0, 0]); // align to 4
    for v in [
        0.0f32, 0.0, 2.0, 1.0, 0.0, 2.0, 0.0, 1.0, 2.0, 1.0, 1.0, 2.0,
    ] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b
}

fn check_gltf_mesh(m: &Mesh) {
    // 2 instances of the triangle + 2 strip triangles; the points primitive is skipped.
    assert_eq!(m.triangle_count(), 4, "{m:?}");
    let normal = |t: usize| {
        let [a, b, c] = m.triangle(t);
        (m.position(b) - m.position(a))
            .cross(m.position(c) - m.position(a))
            .normalize()
    };
    let centroid = |t: usize| {
        m.triangle(t)
            .iter()
            .map(|&v| m.position(v))
            .sum::<glam::Vec3>()
            / 3.0
    };
    // Every instance still faces +z: the mirrored one had its winding flipped.
    for t in 0..2 {
        assert!(
            (normal(t) - glam::Vec3::Z).length() < 1e-6,
            "triangle {t} normal {}",
            normal(t)
        );
    }
    let cs: Vec<glam::Vec3> = (0..2).map(centroid).collect();
    assert!(
        cs.iter()
            .any(|c| (c.x - 1.0 / 3.0).abs() < 1e-6 && c.y.abs() < 0.5),
        "identity instance: {cs:?}"
    );
    // Mirrored in x, then moved +5 y, under a parent moved +10 x.
    assert!(
        cs.iter()
            .any(|c| (c.x - (10.0 - 1.0 / 3.0)).abs() < 1e-5
                && (c.y - (5.0 + 1.0 / 3.0)).abs() < 1e-5),
        "{cs:?}"
    );
    // The strip: both triangles face +z as well (alternating winding handled).
    assert!(
        (normal(2) - glam::Vec3::Z).length() < 1e-6 && (normal(3) - glam::Vec3::Z).length() < 1e-6
    );
}

#[test]
fn gltf_with_external_buffer_and_glb() {
    let dir = common::scratch("gltf");
    let bin = gltf_bin();
    std::fs::write(dir.join("scene.bin"), &bin).unwrap();
    let json = gltf_json(bin.len(), Some("scene.bin"));
    std::fs::write(dir.join("scene.gltf"), &json).unwrap();
    check_gltf_mesh(&mesh::load(&dir.join("scene.gltf")).unwrap());
    std::fs::write(
        dir.join("scene.gltf.zst"),
        zstd::encode_all(json.as_bytes(), 1).unwrap(),
    )
    .unwrap();
    check_gltf_mesh(&mesh::load(&dir.join("scene.gltf.zst")).unwrap());

    // GLB: header, JSON chunk (space-padded), BIN chunk (zero-padded).
    let mut j = gltf_json(bin.len(), None).into_bytes();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.clone();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(j.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&j);
    glb.extend_from_slice(&(b.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&b);
    std::fs::write(dir.join("scene.glb"), &glb).unwrap();
    check_gltf_mesh(&mesh::load(&dir.join("scene.glb")).unwrap());

    // Buffer as a base64 data URI, and an external file whose name needs %-escaping.
    use base64::Engine as _;
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    std::fs::write(dir.join("inline.gltf"), gltf_json(bin.len(), Some(&uri))).unwrap();
    check_gltf_mesh(&mesh::load(&dir.join("inline.gltf")).unwrap());
    std::fs::write(dir.join("my scene.bin"), &bin).unwrap();
    std::fs::write(
        dir.join("spaced.gltf"),
        gltf_json(bin.len(), Some("my%20scene.bin")),
    )
    .unwrap();
    check_gltf_mesh(&mesh::load(&dir.join("spaced.gltf")).unwrap());
    // A buffer shorter than declared is an error, not a silent read of garbage.
    std::fs::write(
        dir.join("short.gltf"),
        gltf_json(bin.len() + 100, Some("scene.bin")),
    )
    .unwrap();
    assert!(mesh::load(&dir.join("short.gltf")).is_err());

    // A missing external buffer is an error naming the file.
    std::fs::remove_file(dir.join("scene.bin")).unwrap();
    let e = mesh::load(&dir.join("scene.gltf")).unwrap_err().to_string();
    assert!(e.contains("scene.gltf"), "{e}");
}

/// Reads an exported GLB back with the project's own loader and checks it against the meshlets:
/// the same triangles in meshlet order (corner positions bit-identical, winding kept), and every
/// corner of meshlet k's triangles coloured `export::colour(k)`.
fn check_export(m: &Mesh, ml: &meshletlab::meshlet::Meshlets, path: &std::path::Path) {
    use meshletlab::meshlet::export;
    let glb = export::glb(m, ml);
    std::fs::write(path, &glb).unwrap();
    let back = mesh::load(path).unwrap();
    assert_eq!(back.triangle_count(), m.triangle_count());
    let dup: usize = ml.meshlets().iter().map(|x| x.vertex_count as usize).sum();
    assert_eq!(
        back.vertex_count(),
        dup,
        "vertices split where meshlets meet"
    );
    let colours = mesh::gltf_io::colours(&glb, None).unwrap();
    assert_eq!(colours.len(), back.vertex_count());
    let mut t = 0;
    for k in 0..ml.len() {
        let want = export::colour(k).map(|c| c as f32 / 255.0);
        for tri in ml.global_triangles(k) {
            let src = tri.map(|v| m.positions()[v as usize]);
            let got = back.triangle(t);
            assert_eq!(
                got.map(|v| back.positions()[v as usize]),
                src,
                "triangle {t}"
            );
            for v in got {
                assert_eq!(colours[v as usize], want, "triangle {t} of meshlet {k}");
            }
            t += 1;
        }
    }
    assert_eq!(t, m.triangle_count());
}

#[test]
fn export_round_trips_through_the_gltf_loader() {
    let dir = common::scratch("export");
    let opts = Default::default();
    let limits = meshletlab::meshlet::Limits::DEFAULT;
    // A real scan (16-bit indices) and a terrain whose split vertices need 32-bit indices.
    for (name, m) in [
        ("fandisk", real()),
        ("terrain", meshletlab::mesh::generate::terrain(260, 3)),
    ] {
        for s in ["meshopt", "kmedoids"] {
            let ml = meshletlab::strategy::by_name(s, &opts)
                .unwrap()
                .build(&m, limits);
            meshletlab::meshlet::validate(&m, &ml, limits).unwrap();
            check_export(&m, &ml, &dir.join(format!("{name}-{s}.glb")));
        }
    }
}

/// The triangles of `m` as corner positions, and the number of distinct positions they use (-0.0
/// and 0.0 counted as one): what an STL round trip must give back.
fn welded(m: &Mesh) -> (Vec<[[f32; 3]; 3]>, usize) {
    let key = |p: [f32; 3]| p.map(|c| if c == 0.0 { 0 } else { c.to_bits() });
    let corners: Vec<[[f32; 3]; 3]> = (0..m.triangle_count())
        .map(|t| m.triangle(t).map(|v| m.positions()[v as usize]))
        .collect();
    let distinct: std::collections::HashSet<[u32; 3]> =
        corners.iter().flatten().map(|&p| key(p)).collect();
    (corners, distinct.len())
}

#[test]
fn stl_ascii_binary_and_zst_round_trip_through_load() {
    let dir = common::scratch("stl");
    for (name, m) in [
        ("terrain", mesh::generate::terrain(40, 2)),
        ("cad-part", mesh::generate::named("cad-part-128").unwrap()),
    ] {
        let (corners, distinct) = welded(&m);
        let check = |file: &str| {
            let back = mesh::load(&dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
            let (got, _) = welded(&back);
            assert_eq!(got, corners, "{file}: corners, winding and order kept");
            assert_eq!(back.vertex_count(), distinct, "{file}: welded exactly");
        };
        let mut bin = Vec::new();
        mesh::stl::write_binary(m.positions(), m.indices(), &mut bin).unwrap();
        std::fs::write(dir.join(format!("{name}.stl")), &bin).unwrap();
        check(&format!("{name}.stl"));
        std::fs::write(
            dir.join(format!("{name}.STL.zst")),
            zstd::encode_all(&bin[..], 1).unwrap(),
        )
        .unwrap();
        check(&format!("{name}.STL.zst"));
        // The same header starting with "solid", as many CAD exporters write it.
        bin[..16].copy_from_slice(b"solid part      ");
        std::fs::write(dir.join(format!("{name}-solid.stl")), &bin).unwrap();
        check(&format!("{name}-solid.stl"));

        let mut ascii = format!("solid {name}\n");
        for c in &corners {
            ascii += " facet normal 0 0 0\n  outer loop\n";
            for p in c {
                writeln!(ascii, "   vertex {:?} {:?} {:?}", p[0], p[1], p[2]).unwrap();
            }
            ascii += "  endloop\n endfacet\n";
        }
        ascii += &format!("endsolid {name}\n");
        std::fs::write(dir.join(format!("{name}-ascii.stl")), &ascii).unwrap();
        check(&format!("{name}-ascii.stl"));
        assert_eq!(
            mesh::load(&dir.join(format!("{name}-ascii.stl"))).unwrap(),
            mesh::load(&dir.join(format!("{name}.stl"))).unwrap(),
            "ASCII and binary give the same mesh"
        );
    }
}
