//! glTF as the ecosystem writes it: fixtures made by gltfpack 1.3 and glTF-Transform 4.5 from one
//! `meshletlab export` (tests/fixtures/gltf, commands in make.sh there) load to the original's
//! triangles with positions within one quantisation step; Draco and any other required extension
//! that is not read are refused with their names; sparse accessors, accessors without a
//! bufferView, the meshopt filters and corrupt meshopt streams behave as the spec says.

mod common;

use meshletlab::mesh::{self, gltf_io, Mesh, MeshErrorKind};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/gltf")
        .join(name)
}

/// The position bits gltfpack (`-vp`) and glTF-Transform (`quantize`, `meshopt`) use by default.
const POSITION_BITS: i32 = 14;

/// How a fixture's positions were quantised, which sets the error allowed.
#[derive(Clone, Copy, Debug)]
enum Step {
    /// Not at all: positions are the original's bit for bit.
    Exact,
    /// On a grid of `POSITION_BITS` over the bounding box's largest extent (integer attributes).
    Grid,
    /// As floats with a `POSITION_BITS` mantissa (the EXPONENTIAL filter): the step grows with
    /// the coordinates' magnitude.
    Mantissa,
}

/// The fixtures that must load, with the extension each one exercises.
const LOADABLE: [(&str, &str, Step); 10] = [
    (
        "gltfpack.glb",
        "KHR_mesh_quantization, u16 positions",
        Step::Grid,
    ),
    (
        "gltfpack-vpn.glb",
        "KHR_mesh_quantization, normalised u16",
        Step::Grid,
    ),
    ("gltfpack-c.glb", "EXT_meshopt_compression", Step::Grid),
    ("gltfpack-cc.glb", "EXT_meshopt_compression", Step::Grid),
    (
        "gltfpack-cc-khr.glb",
        "KHR_meshopt_compression, COLOR filter",
        Step::Grid,
    ),
    (
        "gltfpack-cc-vpf.glb",
        "EXPONENTIAL filter on float positions",
        Step::Mantissa,
    ),
    (
        "gltfpack-c-cf.glb",
        "meshopt with a fallback file that is absent",
        Step::Grid,
    ),
    (
        "gltf-transform-quantize.glb",
        "KHR_mesh_quantization, i16",
        Step::Grid,
    ),
    (
        "gltf-transform-meshopt.glb",
        "EXT_meshopt_compression, i16",
        Step::Grid,
    ),
    ("original.glb", "plain float positions", Step::Exact),
];

/// Exact unique positions of `m`, and each vertex's index among them.
fn unique_positions(m: &Mesh) -> (Vec<[f32; 3]>, Vec<usize>) {
    let mut ids = std::collections::HashMap::new();
    let mut unique = Vec::new();
    let of = m
        .positions()
        .iter()
        .map(|p| {
            *ids.entry(p.map(f32::to_bits)).or_insert_with(|| {
                unique.push(*p);
                unique.len() - 1
            })
        })
        .collect();
    (unique, of)
}

/// Triangles as position ids, each rotated to start at its smallest id (winding kept), sorted.
fn canonical(m: &Mesh, id: impl Fn(u32) -> usize) -> Vec<[usize; 3]> {
    let mut tris: Vec<[usize; 3]> = (0..m.triangle_count())
        .map(|t| {
            let mut c = m.triangle(t).map(&id);
            let r = (0..3).min_by_key(|&k| c[k]).unwrap();
            c.rotate_left(r);
            c
        })
        .collect();
    tris.sort_unstable();
    tris
}

#[test]
fn fixtures_from_gltfpack_and_gltf_transform_give_the_original_triangles() {
    let original = mesh::load(&fixture("original.glb")).unwrap();
    let (unique, of) = unique_positions(&original);
    let want = canonical(&original, |v| of[v as usize]);
    let (lo, hi) = original.bounding_box();
    let grid = (hi - lo).max_element() / ((1 << POSITION_BITS) - 1) as f32;
    // A mantissa of POSITION_BITS (sign included) at the largest coordinate's binary exponent.
    let largest = lo.abs().max(hi.abs()).max_element();
    let mantissa = 2f32.powi(largest.log2().ceil() as i32 + 1 - POSITION_BITS);
    let raw = std::fs::read(fixture("original.glb")).unwrap();
    let original_colours = gltf_io::colours(&raw, None).unwrap();
    for (name, what, quantised) in LOADABLE {
        let step = match quantised {
            Step::Exact => 0.0,
            Step::Grid => grid,
            Step::Mantissa => mantissa,
        };
        let m = mesh::load(&fixture(name)).unwrap_or_else(|e| panic!("{name} ({what}): {e}"));
        assert_eq!(m.triangle_count(), original.triangle_count(), "{name}");
        // Each vertex lands on the original position nearest to it, within one step per axis.
        let mut worst = 0f32;
        let nearest: Vec<usize> = m
            .positions()
            .iter()
            .map(|p| {
                let d = |u: &[f32; 3]| (0..3).map(|k| (p[k] - u[k]).abs()).fold(0f32, f32::max);
                let (i, e) = unique
                    .iter()
                    .map(d)
                    .enumerate()
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .unwrap();
                worst = worst.max(e);
                i
            })
            .collect();
        assert!(
            worst <= step,
            "{name} ({what}): a position is {worst} off, the {POSITION_BITS}-bit step ({quantised:?}) is {step}"
        );
        assert_eq!(
            canonical(&m, |v| nearest[v as usize]),
            want,
            "{name} ({what}): not the original's triangles"
        );
        // Colours (u8 in the original, 8 bits in every tool's output): each vertex carries a
        // colour the original has at that position, so vertices were not mixed up.
        let bytes = std::fs::read(fixture(name)).unwrap();
        let colours = gltf_io::colours(&bytes, None).unwrap();
        assert_eq!(colours.len(), m.vertex_count(), "{name}");
        for (v, c) in colours.iter().enumerate() {
            let found = of.iter().zip(&original_colours).any(|(&u, oc)| {
                u == nearest[v] && (0..4).all(|k| (c[k] - oc[k]).abs() <= 1.5 / 255.0)
            });
            assert!(
                found,
                "{name}: vertex {v} has colour {c:?}, not one of its position's"
            );
        }
    }
}

#[test]
fn draco_is_refused_with_its_name_and_the_way_out() {
    let e = mesh::load(&fixture("gltf-transform-draco.glb")).unwrap_err();
    assert!(
        matches!(&e.kind, MeshErrorKind::UnsupportedExtension { name, .. } if name == "KHR_draco_mesh_compression"),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.starts_with(&fixture("gltf-transform-draco.glb").display().to_string()),
        "{text}"
    );
    assert!(text.contains("gltf-transform cp"), "{text}");
}

// ---- hand-made documents: the spec's accessor rules and the extension checks ----

/// `bin` as a glTF buffer embedded in a data URI.
fn embedded(bin: &[u8]) -> Value {
    use base64::Engine as _;
    json!({"byteLength": bin.len(), "uri": format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bin)
    )})
}

/// A .gltf with one triangle primitive over `bin` (embedded as a data URI), and `doc` merged in.
fn gltf_file(dir: &Path, name: &str, bin: &[u8], doc: Value) -> PathBuf {
    let mut j = json!({
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [embedded(bin)],
    });
    for (k, v) in doc.as_object().unwrap() {
        j[k] = v.clone();
    }
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(&j).unwrap()).unwrap();
    path
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn sparse_accessors_and_accessors_without_a_buffer_view() {
    let dir = common::scratch("gltf-sparse");
    // Base: two triangles' worth of positions (6 vertices); sparse: vertices 1 and 4 replaced.
    let base: Vec<f32> = (0..18).map(|i| i as f32).collect();
    let mut bin = f32_bytes(&base);
    let idx_at = bin.len();
    bin.extend_from_slice(&[1u16, 4].map(u16::to_le_bytes).concat());
    let val_at = bin.len();
    bin.extend(f32_bytes(&[-1.0, -2.0, -3.0, -4.0, -5.0, -6.0]));
    let views = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 72},
        {"buffer": 0, "byteOffset": idx_at, "byteLength": 4},
        {"buffer": 0, "byteOffset": val_at, "byteLength": 24}
    ]);
    let sparse = json!({"count": 2, "indices": {"bufferView": 1, "componentType": 5123},
                        "values": {"bufferView": 2}});
    let mut expect: Vec<[f32; 3]> = base.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    expect[1] = [-1.0, -2.0, -3.0];
    expect[4] = [-4.0, -5.0, -6.0];

    let with_base = gltf_file(
        &dir,
        "sparse.gltf",
        &bin,
        json!({"bufferViews": views, "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3", "sparse": sparse}
        ]}),
    );
    assert_eq!(mesh::load(&with_base).unwrap().positions(), expect);

    // No bufferView: zeros, then the substitutions (vertices 1 and 4 only; the rest stay 0).
    let zeros = gltf_file(
        &dir,
        "zeros.gltf",
        &bin,
        json!({"bufferViews": views, "accessors": [
            {"componentType": 5126, "count": 6, "type": "VEC3", "sparse": sparse}
        ]}),
    );
    let m = mesh::load(&zeros).unwrap();
    for (v, p) in m.positions().iter().enumerate() {
        let want = if v == 1 || v == 4 {
            expect[v]
        } else {
            [0.0; 3]
        };
        assert_eq!(*p, want, "vertex {v}");
    }

    // Sparse indices must increase strictly and stay in range: both faults are typed errors.
    for (name, indices) in [("unsorted", [4u16, 1]), ("outside", [1, 6])] {
        let mut b = bin.clone();
        b[idx_at..idx_at + 4].copy_from_slice(&indices.map(u16::to_le_bytes).concat());
        let p = gltf_file(
            &dir,
            &format!("{name}.gltf"),
            &b,
            json!({"bufferViews": views, "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC3", "sparse": sparse}
            ]}),
        );
        let e = mesh::load(&p).unwrap_err();
        assert!(matches!(e.kind, MeshErrorKind::Parse { .. }), "{name}: {e}");
        assert!(e.to_string().contains("sparse"), "{name}: {e}");
    }
}

#[test]
fn required_extensions_are_refused_by_name_unless_read_or_geometry_neutral() {
    let dir = common::scratch("gltf-required");
    let bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let doc = |required: &[&str]| {
        json!({
            "extensionsUsed": required, "extensionsRequired": required,
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}]
        })
    };
    for neutral in [
        "KHR_texture_basisu",
        "KHR_materials_unlit",
        "KHR_mesh_quantization",
        // Read: a node without the extension's attributes is placed once.
        "EXT_mesh_gpu_instancing",
    ] {
        let p = gltf_file(&dir, &format!("{neutral}.gltf"), &bin, doc(&[neutral]));
        assert_eq!(mesh::load(&p).unwrap().triangle_count(), 1, "{neutral}");
    }
    for refused in ["KHR_draco_mesh_compression", "VENDOR_made_up"] {
        let p = gltf_file(&dir, &format!("{refused}.gltf"), &bin, doc(&[refused]));
        let e = mesh::load(&p).unwrap_err();
        assert!(
            matches!(&e.kind, MeshErrorKind::UnsupportedExtension { name, .. } if name == refused),
            "{refused}: {e}"
        );
        assert!(e.to_string().contains(refused), "{e}");
    }
}

#[test]
fn draco_used_but_not_required_reads_the_fallback_or_is_refused_without_one() {
    let dir = common::scratch("gltf-draco-optional");
    let bin = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let draco =
        json!({"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}});
    let doc = |view: bool| {
        let mut acc = json!({"componentType": 5126, "count": 3, "type": "VEC3"});
        if view {
            acc["bufferView"] = json!(0);
        }
        json!({
            "extensionsUsed": ["KHR_draco_mesh_compression"],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "extensions": draco}]}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [acc]
        })
    };
    // With an uncompressed fallback, the fallback is read.
    let p = gltf_file(&dir, "fallback.gltf", &bin, doc(true));
    assert_eq!(mesh::load(&p).unwrap().positions()[1], [1.0, 0.0, 0.0]);
    // Without one, the accessor would read as zeros: refused, naming Draco.
    let p = gltf_file(&dir, "no-fallback.gltf", &bin, doc(false));
    let e = mesh::load(&p).unwrap_err();
    assert!(
        matches!(&e.kind, MeshErrorKind::UnsupportedExtension { name, .. } if name == "KHR_draco_mesh_compression"),
        "{e}"
    );
}

/// A .gltf whose POSITION (and indices) live in meshopt-compressed views.
fn meshopt_file(
    dir: &Path,
    name: &str,
    stream: &[u8],
    position: Value,
    compressed: Value,
    stride: usize,
) -> PathBuf {
    let count = compressed["count"].as_u64().unwrap() as usize;
    gltf_file(
        dir,
        name,
        stream,
        json!({
            "extensionsUsed": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
            "extensionsRequired": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
            "buffers": [
                embedded(stream),
                {"byteLength": count * stride, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
            ],
            "bufferViews": [{"buffer": 1, "byteLength": count * stride, "byteStride": stride,
                             "extensions": {"EXT_meshopt_compression": compressed}}],
            "accessors": [position]
        }),
    )
}

#[test]
fn octahedral_positions_and_quaternion_streams_decode_through_meshoptimizer() {
    // Unit vectors (an icosphere's vertices) stored as octahedral i16, the way gltfpack stores
    // normals; read as normalised i16 POSITION they are the sphere again, within the filter's error.
    let sphere = mesh::generate::noisy_sphere(1, 0.0, 1);
    let dir = common::scratch("gltf-filters");
    let n = sphere.vertex_count();
    for (bits, stride, component) in [(8, 4usize, 5120), (16, 8, 5122)] {
        let units: Vec<[f32; 4]> = sphere
            .positions()
            .iter()
            .map(|p| {
                let v = glam::Vec3::from_array(*p).normalize();
                [v.x, v.y, v.z, 0.0]
            })
            .collect();
        let encoded = if stride == 4 {
            let e: Vec<[i8; 4]> = meshopt::encode_filter_oct(&units, bits);
            meshopt::encode_vertex_buffer(&e).unwrap()
        } else {
            let e: Vec<[i16; 4]> = meshopt::encode_filter_oct(&units, bits);
            meshopt::encode_vertex_buffer(&e).unwrap()
        };
        let p = meshopt_file(
            &dir,
            &format!("oct{bits}.gltf"),
            &encoded,
            json!({"bufferView": 0, "componentType": component, "normalized": true, "count": n, "type": "VEC3"}),
            json!({"buffer": 0, "byteLength": encoded.len(), "byteStride": stride, "count": n,
                   "mode": "ATTRIBUTES", "filter": "OCTAHEDRAL"}),
            stride,
        );
        let got = mesh::load(&p).unwrap();
        let tolerance = if bits == 8 { 0.02 } else { 1e-3 };
        for (a, b) in got.positions().iter().zip(&units) {
            for k in 0..3 {
                assert!(
                    (a[k] - b[k]).abs() < tolerance,
                    "{bits} bits: {a:?} vs {b:?}"
                );
            }
        }
    }
    // QUATERNION: the xyz of unit quaternions, read back as normalised i16 VEC3.
    let quats: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let q =
                glam::Quat::from_euler(glam::EulerRot::XYZ, i as f32 * 0.3, i as f32 * 0.7, 0.2);
            q.to_array()
        })
        .collect();
    let encoded = meshopt::encode_vertex_buffer(&meshopt::encode_filter_quat(&quats, 12)).unwrap();
    let p = meshopt_file(
        &dir,
        "quat.gltf",
        &encoded,
        json!({"bufferView": 0, "componentType": 5122, "normalized": true, "count": n, "type": "VEC3"}),
        json!({"buffer": 0, "byteLength": encoded.len(), "byteStride": 8, "count": n,
               "mode": "ATTRIBUTES", "filter": "QUATERNION"}),
        8,
    );
    // The decoder may return q or -q; compare up to sign.
    let got = mesh::load(&p).unwrap();
    for (a, q) in got.positions().iter().zip(&quats) {
        let close = |s: f32| (0..3).all(|k| (a[k] - s * q[k]).abs() < 2e-3);
        assert!(close(1.0) || close(-1.0), "{a:?} vs {q:?}");
    }
    // A filter on a stride it does not take is a typed error, not meshoptimizer's assert.
    let p = meshopt_file(
        &dir,
        "bad-stride.gltf",
        &encoded,
        json!({"bufferView": 0, "componentType": 5122, "normalized": true, "count": n, "type": "VEC3"}),
        json!({"buffer": 0, "byteLength": encoded.len(), "byteStride": 12, "count": n,
               "mode": "ATTRIBUTES", "filter": "QUATERNION"}),
        12,
    );
    let e = mesh::load(&p).unwrap_err();
    assert!(
        e.to_string().contains("QUATERNION") || e.to_string().contains("Quaternion"),
        "{e}"
    );
}

/// The JSON and BIN chunks of a GLB.
fn glb_parts(bytes: &[u8]) -> (Value, usize) {
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let j: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    (j, 20 + json_len + 8)
}

#[test]
fn a_corrupt_meshopt_stream_is_a_typed_error_naming_file_mesh_and_view() {
    let dir = common::scratch("gltf-corrupt");
    let mut bytes = std::fs::read(fixture("gltfpack-cc.glb")).unwrap();
    let (j, bin_at) = glb_parts(&bytes);
    // The index stream's first byte is its codec header; zero is no valid header.
    let view = j["accessors"]
        [j["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize]["bufferView"]
        .as_u64()
        .unwrap();
    let ext = &j["bufferViews"][view as usize]["extensions"]["EXT_meshopt_compression"];
    assert_eq!(ext["mode"], "TRIANGLES");
    let at = bin_at + ext["byteOffset"].as_u64().unwrap() as usize;
    bytes[at] = 0;
    let path = dir.join("corrupt.glb");
    std::fs::write(&path, &bytes).unwrap();
    let e = mesh::load(&path).unwrap_err();
    assert!(matches!(e.kind, MeshErrorKind::Parse { .. }), "{e}");
    let text = e.to_string();
    for part in [
        path.display().to_string(),
        "mesh 0".into(),
        format!("bufferView {view}"),
        "does not decode".into(),
    ] {
        assert!(text.contains(&part), "'{part}' missing from: {text}");
    }
}
