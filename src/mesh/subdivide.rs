//! 1 -> 4 midpoint subdivision: every edge gets one new vertex at its midpoint, shared by the
//! triangles on that edge, so the output keeps the input's topology (boundaries, non-manifold edges,
//! components). Multi-million-triangle test inputs come from subdividing a real mesh.

use super::edges::{EdgeTable, NO_EDGE};
use super::Mesh;
use thiserror::Error;

/// The most triangles [`subdivide`] makes: 2^27 = 134,217,728. The last level holds its input,
/// the input's edge table and the output: about 36 bytes per output triangle (4.5 for the input,
/// 14 for the edge table, 18 for the output's indices and vertices; fandisk to 53 M triangles
/// peaked at 1.66 GiB), so a result at the budget peaks near 4.5 GiB and leaves a 24 GiB machine
/// room for the commands that read it back. One level more (x4) would peak near 18 GiB.
pub const MAX_TRIANGLES: u64 = 1 << 27;

/// Why [`subdivide`] refused to subdivide.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
pub enum SubdivideError {
    /// The result would have more than [`MAX_TRIANGLES`] triangles; refused before any work.
    #[error(
        "{levels} level(s) would turn {triangles} triangles into {}, over the budget of \
         {MAX_TRIANGLES}; this mesh allows at most {} level(s)",
        result_text(*.triangles, *.levels),
        max_levels(*.triangles)
    )]
    OverBudget {
        /// Triangles of the input.
        triangles: usize,
        /// Levels asked for.
        levels: u32,
    },
    /// The result would need vertex indices beyond 32 bits.
    #[error(
        "subdivision would exceed 32-bit indices ({vertices} vertices, {triangles} triangles)"
    )]
    IndexOverflow {
        /// Vertices of the next level.
        vertices: u64,
        /// Triangles of the next level.
        triangles: u64,
    },
}

/// Triangles after `levels` levels of `triangles`, or `None` past u128.
fn result_triangles(triangles: usize, levels: u32) -> Option<u128> {
    4u128
        .checked_pow(levels)
        .and_then(|p| p.checked_mul(triangles as u128))
}

/// [`result_triangles`] as text.
fn result_text(triangles: usize, levels: u32) -> String {
    result_triangles(triangles, levels).map_or_else(|| "more than 2^128".into(), |t| t.to_string())
}

/// The most levels that keep `triangles` within [`MAX_TRIANGLES`].
fn max_levels(triangles: usize) -> u32 {
    (0..)
        .take_while(|&k| result_triangles(triangles, k).is_some_and(|t| t <= MAX_TRIANGLES as u128))
        .last()
        .unwrap_or(0)
}

/// Subdivides `levels` times (x4 triangles per level). Refuses, before allocating anything, a
/// result over [`MAX_TRIANGLES`]; fails if the result would not fit u32 indices.
pub fn subdivide(mesh: &Mesh, levels: u32) -> Result<Mesh, SubdivideError> {
    let triangles = mesh.triangle_count();
    if levels > 0 && result_triangles(triangles, levels).is_none_or(|t| t > MAX_TRIANGLES as u128) {
        return Err(SubdivideError::OverBudget { triangles, levels });
    }
    let mut m = mesh.clone();
    for _ in 0..levels {
        m = subdivide_once(&m)?;
    }
    Ok(m)
}

fn subdivide_once(mesh: &Mesh) -> Result<Mesh, SubdivideError> {
    let et = EdgeTable::new(mesh);
    let n = mesh.vertex_count();
    if (n + et.edges.len()) as u64 > u32::MAX as u64
        || mesh.indices.len() as u64 * 4 > u32::MAX as u64 * 3
    {
        return Err(SubdivideError::IndexOverflow {
            vertices: (n + et.edges.len()) as u64,
            triangles: mesh.triangle_count() as u64 * 4,
        });
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

    #[test]
    fn over_budget_is_refused_before_any_work() {
        let m = crate::mesh::generate::terrain(8, 1);
        let t = m.triangle_count();
        // 4^1000 triangles: computing even one level of that would never return.
        for levels in [1000, u32::MAX] {
            let e = subdivide(&m, levels).unwrap_err();
            assert_eq!(
                e,
                SubdivideError::OverBudget {
                    triangles: t,
                    levels
                }
            );
            assert!(e.to_string().contains("more than 2^128"), "{e}");
        }
        let allowed = max_levels(t);
        assert!((t as u64) << (2 * allowed) <= MAX_TRIANGLES);
        assert!((t as u64) << (2 * allowed + 2) > MAX_TRIANGLES);
        let e = subdivide(&m, allowed + 1).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("at most {allowed} level(s)")),
            "{e}"
        );
        assert_eq!(subdivide(&m, 0).unwrap(), m);
    }
}
