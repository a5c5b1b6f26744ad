//! Meshlets as a glTF 2.0 binary (`meshletlab export`): one primitive whose vertices are the
//! meshlets' vertex lists laid end to end (so a vertex shared by two meshlets is split), each with
//! its meshlet's flat colour in `COLOR_0`. Any glTF viewer then shows the meshlets.
//!
//! Layout of the binary chunk: positions (f32 x 3), colours (u8 x 4, normalised; 4-byte aligned as
//! glTF requires of vertex attributes), indices (u16 when the vertices fit, else u32), triangles in
//! meshlet order with their winding. The mesh's `extras` record the meshlet and triangle counts.
//! A scene ([`glb_scene`]) is written with one such mesh per scene mesh and one node per instance.

use super::Meshlets;
use crate::mesh::{Mesh, Scene};
use serde_json::json;

/// The colour of meshlet `i`: hues spaced by the golden ratio (neighbouring indices, which are
/// usually neighbouring meshlets, land far apart on the colour wheel) at two lightness levels.
pub fn colour(i: usize) -> [u8; 4] {
    let h = (i as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let (s, v) = if i.is_multiple_of(2) {
        (0.65, 0.95)
    } else {
        (0.85, 0.70)
    };
    let c = v * s;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    let to = |f: f64| ((f + m) * 255.0).round() as u8;
    [to(r), to(g), to(b), 255]
}

/// The GLB file for `ml` over `mesh`.
pub fn glb(mesh: &Mesh, ml: &Meshlets) -> Vec<u8> {
    write(&[(mesh, ml)], &[None])
}

/// The GLB file of a scene: one glTF mesh per scene mesh (`meshlets[i]` over `scene.meshes[i]`,
/// built once) and one node per instance, with its transform as the node's matrix, so a viewer
/// draws each mesh's meshlets at every placement.
pub fn glb_scene(scene: &Scene, meshlets: &[Meshlets]) -> Vec<u8> {
    let meshes: Vec<(&Mesh, &Meshlets)> = scene.meshes.iter().zip(meshlets).collect();
    let nodes: Vec<Option<(u32, glam::Mat4)>> = scene
        .instances
        .iter()
        .map(|i| Some((i.mesh, i.transform)))
        .collect();
    write(&meshes, &nodes)
}

/// The file of `meshes` placed by `nodes` (`None`: mesh 0, untransformed, the single-mesh file).
fn write(meshes: &[(&Mesh, &Meshlets)], nodes: &[Option<(u32, glam::Mat4)>]) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let (mut accessors, mut views, mut json_meshes) = (Vec::new(), Vec::new(), Vec::new());
    for (k, (mesh, ml)) in meshes.iter().enumerate() {
        let nv: usize = ml.meshlets.iter().map(|m| m.vertex_count as usize).sum();
        let nt: usize = ml.meshlets.iter().map(|m| m.triangle_count as usize).sum();
        let mut positions = Vec::with_capacity(nv * 12);
        let mut colours = Vec::with_capacity(nv * 4);
        let mut indices: Vec<u32> = Vec::with_capacity(nt * 3);
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for i in 0..ml.len() {
            let base = (positions.len() / 12) as u32;
            let c = colour(i);
            for &v in ml.meshlet_vertices(i) {
                let p = mesh.positions[v as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                    positions.extend_from_slice(&p[k].to_le_bytes());
                }
                colours.extend_from_slice(&c);
            }
            indices.extend(ml.meshlet_triangles(i).iter().map(|&l| base + l as u32));
        }
        // 65535 is the primitive-restart value, which glTF forbids in u16 indices.
        let short = nv <= u16::MAX as usize;
        let pos_at = bin.len();
        bin.extend_from_slice(&positions);
        let colour_at = bin.len();
        bin.extend_from_slice(&colours);
        let index_at = bin.len();
        if short {
            bin.extend(indices.iter().flat_map(|&i| (i as u16).to_le_bytes()));
        } else {
            bin.extend(indices.iter().flat_map(|&i| i.to_le_bytes()));
        }
        let index_len = bin.len() - index_at;
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let (a, v) = (3 * k, 3 * k);
        json_meshes.push(json!({
            "name": if meshes.len() == 1 { "meshlets".to_string() } else { format!("meshlets {k}") },
            "primitives": [{"attributes": {"POSITION": a, "COLOR_0": a + 1}, "indices": a + 2, "mode": 4}],
            "extras": {"meshlets": ml.len(), "triangles": nt, "vertices": nv}
        }));
        accessors.extend([
            json!({"bufferView": v, "componentType": 5126, "count": nv, "type": "VEC3", "min": lo, "max": hi}),
            json!({"bufferView": v + 1, "componentType": 5121, "normalized": true, "count": nv, "type": "VEC4"}),
            json!({"bufferView": v + 2, "componentType": if short { 5123 } else { 5125 }, "count": indices.len(), "type": "SCALAR"}),
        ]);
        views.extend([
            json!({"buffer": 0, "byteOffset": pos_at, "byteLength": colour_at - pos_at, "target": 34962}),
            json!({"buffer": 0, "byteOffset": colour_at, "byteLength": index_at - colour_at, "target": 34962}),
            json!({"buffer": 0, "byteOffset": index_at, "byteLength": index_len, "target": 34963}),
        ]);
    }
    let json_nodes: Vec<serde_json::Value> = nodes
        .iter()
        .map(|n| match n {
            None => json!({"mesh": 0, "name": "meshlets"}),
            Some((m, t)) => json!({"mesh": m, "matrix": t.to_cols_array()}),
        })
        .collect();
    let doc = json!({
        "asset": {"version": "2.0", "generator": "meshletlab export"},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": json_nodes,
        "meshes": json_meshes,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}]
    });
    let text = serde_json::to_vec(&doc).expect("a Value always serialises");
    crate::mesh::gltf_io::write_glb(&text, &bin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_file_keeps_its_instances_and_reads_back() {
        use crate::meshlet::{Limits, MeshletBuilder};
        let scene = crate::mesh::generate::named_scene("scene-small").unwrap();
        let meshlets: Vec<Meshlets> = scene
            .meshes
            .iter()
            .map(|m| {
                let mut b = MeshletBuilder::new(m.vertex_count(), Limits::DEFAULT);
                for t in 0..m.triangle_count() {
                    b.push(m.triangle(t));
                }
                b.finish()
            })
            .collect();
        let bytes = glb_scene(&scene, &meshlets);
        let back = crate::mesh::scene_from_bytes(&bytes, std::path::Path::new("s.glb")).unwrap();
        assert_eq!(back.instances.len(), scene.instances.len());
        assert_eq!(back.meshes.len(), 2);
        for (a, b) in back.instances.iter().zip(&scene.instances) {
            assert_eq!((a.mesh, a.transform), (b.mesh, b.transform));
        }
        for (m, ml) in back.meshes.iter().zip(&meshlets) {
            assert_eq!(m.triangle_count(), ml.triangle_count());
        }
    }

    #[test]
    fn neighbouring_indices_get_distinct_colours() {
        for i in 0..1000 {
            for d in 1..4 {
                let (a, b) = (colour(i), colour(i + d));
                let dist: i32 = (0..3).map(|k| (a[k] as i32 - b[k] as i32).abs()).sum();
                assert!(
                    dist > 40,
                    "meshlets {i} and {} look alike: {a:?} {b:?}",
                    i + d
                );
            }
        }
    }
}
