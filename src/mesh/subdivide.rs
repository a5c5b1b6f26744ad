//! 1 -> 4 midpoint subdivision: every edge gets one new vertex at its midpoint, shared by the
//! triangles on that edge, so the output keeps the input's topology (boundaries, non-manifold edges,
//! components). Multi-million-triangle test inputs come from subdividing a real mesh.

use super::edges::{EdgeTable, NO_EDGE};
use super::Mesh;

/// Subdivides `levels` times (x4 triangles per level). Fails if the result would not fit u32 indices.
pub fn subdivide(mesh: &Mesh, levels: u32) -> Result<Mesh, String> {
    let mut m = mesh.clone();
    for _ in 0..levels {
        m = subdivide_once(&m)?;
    }
    Ok(m)
}

fn subdivide_once(mesh: &Mesh) -> Result<Mesh, String> {
    let et = EdgeTable::new(mesh);
    let n = mesh.vertex_count();
    if (n + et.edges.len()) as u64 > u32::MAX as u64
        || mesh.indices.len() as u64 * 4 > u32::MAX as u64 * 3
    {
        return Err(format!(
            "subdivision would exceed 32-bit indices ({} vertices, {} triangles)",
            n + et.edges.len(),
            mesh.triangle_count() * 4
        ));
    }
    let mut positions = Vec::with_capacity(n + et.edges.len());
    positions.extend_from_slice(&mesh.positions);
    positions.extend(et.edges.iter().map(|&[a, b]| {
        let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        // Midpoint in f64 keeps it exactly between the endpoints for large coordinates.
        [0, 1, 2].map(|i| ((pa[i] as f64 + pb[i] as f64) * 0.5) as f32)
    }));
    let mut indices = Vec::with_capacity(mesh.indices.len() * 4);
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(t);
        // A collapsed side (two equal vertices) has its "midpoint" at that vertex.
        let mid = |side: usize, v: u32| match et.side_edge[3 * t + side] {
            NO_EDGE => v,
            e => n as u32 + e,
        };
        let (ab, bc, ca) = (mid(0, a), mid(1, b), mid(2, c));
        indices.extend_from_slice(&[a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
    }
    Ok(Mesh { positions, indices })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_edges_share_midpoints() {
        let m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
        };
        let s = subdivide(&m, 2).unwrap();
        assert_eq!(s.triangle_count(), 32);
        // Level 1: 4 + 5 edges = 9 vertices; level 2: 9 + 16 edges = 25 vertices (a 5x5 grid).
        assert_eq!(s.vertex_count(), 25);
        let st = crate::mesh::MeshStats::of(&s);
        assert_eq!(
            (st.components, st.non_manifold_edges, st.boundary_edges),
            (1, 0, 16)
        );
    }
}
