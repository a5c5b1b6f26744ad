//! glTF 2.0 (.gltf and .glb): all triangle primitives of all meshes, node transforms applied.
//!
//! The default scene (or every scene when none is marked default) is walked from its roots; each
//! mesh instance is baked with its world transform, and mirrored instances (negative determinant)
//! get their winding flipped so front faces stay front faces. Meshes that no node instances are
//! added untransformed, so every mesh in the file appears at least once. Triangle strips and fans
//! are unrolled; point and line primitives are skipped.

use super::error::{parse_err, MeshErrorKind};
use glam::{Mat4, Vec3};
use gltf::mesh::Mode;
use std::path::Path;

/// Parses a .gltf or .glb file; `base` resolves external buffer URIs.
pub fn parse(data: &[u8], base: Option<&Path>) -> Result<(Vec<[f32; 3]>, Vec<u32>), MeshErrorKind> {
    let gltf = gltf::Gltf::from_slice(data).map_err(|e| parse_err("glTF", e.to_string()))?;
    let doc = &gltf.document;
    let buffers = doc
        .buffers()
        .map(|b| load_buffer(&b, gltf.blob.as_deref(), base))
        .collect::<Result<Vec<_>, _>>()?;
    let mut out = (Vec::new(), Vec::new());
    let mut instanced = vec![false; doc.meshes().len()];

    let roots: Vec<gltf::Node> = match doc.default_scene() {
        Some(s) => s.nodes().collect(),
        None => doc.scenes().flat_map(|s| s.nodes()).collect(),
    };
    // Iterative walk; a depth cap guards against cyclic node graphs in malformed files.
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 1024 {
            return Err(parse_err(
                format!("node {}", node.index()),
                "node hierarchy deeper than 1024 (cycle?)",
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            instanced[mesh.index()] = true;
            append_mesh(&mesh, world, &buffers, &mut out)?;
        }
        stack.extend(node.children().map(|c| (c, world, depth + 1)));
    }
    for mesh in doc.meshes().filter(|m| !instanced[m.index()]) {
        append_mesh(&mesh, Mat4::IDENTITY, &buffers, &mut out)?;
    }
    Ok(out)
}

/// Bytes of one buffer: the GLB binary chunk, a base64 `data:` URI, or a file next to the glTF.
fn load_buffer(
    b: &gltf::Buffer,
    blob: Option<&[u8]>,
    base: Option<&Path>,
) -> Result<Vec<u8>, MeshErrorKind> {
    use base64::Engine as _;
    let loc = || format!("buffer {}", b.index());
    let bytes = match b.source() {
        gltf::buffer::Source::Bin => blob
            .ok_or_else(|| parse_err(loc(), "refers to a GLB binary chunk that is missing"))?
            .to_vec(),
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
            let (_, payload) = uri
                .split_once(";base64,")
                .ok_or_else(|| parse_err(loc(), "data URI is not base64"))?;
            base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map_err(|e| parse_err(loc(), format!("bad base64: {e}")))?
        }
        gltf::buffer::Source::Uri(uri) => {
            let rel = percent_decode(uri);
            let path = base
                .map(|d| d.join(&rel))
                .unwrap_or_else(|| rel.clone().into());
            std::fs::read(&path)
                .map_err(|e| parse_err(loc(), format!("cannot read '{}': {e}", path.display())))?
        }
    };
    if bytes.len() < b.length() {
        return Err(MeshErrorKind::Truncated(format!(
            "{} has {} bytes, {} declared",
            loc(),
            bytes.len(),
            b.length()
        )));
    }
    Ok(bytes)
}

/// Decodes %XX escapes in a relative URI (file names with spaces are written as %20).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn append_mesh(
    mesh: &gltf::Mesh,
    world: Mat4,
    buffers: &[Vec<u8>],
    (positions, indices): &mut (Vec<[f32; 3]>, Vec<u32>),
) -> Result<(), MeshErrorKind> {
    let flip = world.determinant() < 0.0;
    for prim in mesh.primitives() {
        let loc = || format!("mesh {} primitive {}", mesh.index(), prim.index());
        if !matches!(
            prim.mode(),
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            continue;
        }
        let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
        let Some(pos) = reader.read_positions() else {
            return Err(parse_err(loc(), "triangle primitive without POSITION"));
        };
        let base = positions.len();
        positions.extend(pos.map(|p| world.transform_point3(Vec3::from_array(p)).to_array()));
        let n = (positions.len() - base) as u32;
        let local: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..n).collect(),
        };
        if let Some(&bad) = local.iter().find(|&&i| i >= n) {
            return Err(parse_err(
                loc(),
                format!("index {bad} out of range ({n} vertices)"),
            ));
        }
        let tris: Vec<[u32; 3]> = match prim.mode() {
            Mode::Triangles => {
                if !local.len().is_multiple_of(3) {
                    return Err(parse_err(
                        loc(),
                        format!("{} indices is not a multiple of 3", local.len()),
                    ));
                }
                local.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
            }
            Mode::TriangleStrip => (2..local.len())
                .map(|i| {
                    if i % 2 == 0 {
                        [local[i - 2], local[i - 1], local[i]]
                    } else {
                        [local[i - 1], local[i - 2], local[i]]
                    }
                })
                .collect(),
            _ => (2..local.len())
                .map(|i| [local[0], local[i - 1], local[i]])
                .collect(),
        };
        if positions.len() > u32::MAX as usize {
            return Err(MeshErrorKind::TooLarge("more than 2^32 vertices".into()));
        }
        for [a, b, c] in tris {
            let (a, b, c) = (a + base as u32, b + base as u32, c + base as u32);
            indices.extend_from_slice(&if flip { [a, c, b] } else { [a, b, c] });
        }
    }
    Ok(())
}
