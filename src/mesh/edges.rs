//! The mesh's edges as flat arrays: vertex -> triangles and the edge table (unique undirected
//! edges, the triangles on each, the edge of every triangle side). They sit with the mesh because
//! the mesh's own statistics and subdivision read them; the dual graph built on them is in
//! `crate::adjacency`, one room up.
//!
//! Deterministic: rows are sorted by triangle id, edges by (min, max) vertex id.

use super::Mesh;
use crate::common::{distinct, Csr, NONE};

/// Vertex -> incident triangles (each row in ascending triangle order; a degenerate triangle that
/// uses a vertex twice is listed once).
pub fn vertex_triangles(mesh: &Mesh) -> Csr {
    // Count, prefix sum, scatter in triangle order (so rows come out sorted).
    let n = mesh.vertex_count();
    let mut offsets = vec![0u32; n + 1];
    for t in 0..mesh.triangle_count() {
        for v in distinct(mesh.triangle(t)) {
            offsets[v as usize + 1] += 1;
        }
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    let mut cursor = offsets.clone();
    let mut items = vec![0u32; offsets[n] as usize];
    for t in 0..mesh.triangle_count() {
        for v in distinct(mesh.triangle(t)) {
            items[cursor[v as usize] as usize] = t as u32;
            cursor[v as usize] += 1;
        }
    }
    Csr { offsets, items }
}

/// Undirected edges of the mesh and the triangles on each.
#[derive(Clone, Debug, Default)]
pub struct EdgeTable {
    /// Unique edges as (min, max) vertex pairs, sorted.
    pub edges: Vec<[u32; 2]>,
    /// Edge -> triangles that have it as a side, ascending; a row of 1 is a boundary edge, more than
    /// 2 is non-manifold.
    pub faces: Csr,
    /// Edge id of side `i` of triangle `t` (vertices `i` and `(i + 1) % 3`) at `3 * t + i`;
    /// `u32::MAX` for a collapsed side whose two vertices are the same.
    pub side_edge: Vec<u32>,
}

/// Calls `f(a, sides)` for every vertex `a` with the triangle sides whose smaller vertex is `a`, as
/// `(other vertex, side)` pairs sorted ascending (side = 3 * triangle + corner; collapsed sides
/// skipped). Runs of equal other vertex are the sides on one edge. Shared by the edge table and the
/// dual graph so both see edges in the same deterministic order.
pub(crate) fn for_each_vertex_sides(mesh: &Mesh, vt: &Csr, f: impl FnMut(u32, &[(u32, u32)])) {
    for_each_vertex_sides_in(mesh, vt, 0..mesh.vertex_count() as u32, f);
}

/// [`for_each_vertex_sides`] over the vertices in `range` only.
pub(crate) fn for_each_vertex_sides_in(
    mesh: &Mesh,
    vt: &Csr,
    range: std::ops::Range<u32>,
    mut f: impl FnMut(u32, &[(u32, u32)]),
) {
    let idx = &mesh.indices;
    let mut local: Vec<(u32, u32)> = Vec::new();
    for a in range {
        local.clear();
        for &t in vt.row(a as usize) {
            for s in 0..3 {
                let side = 3 * t as usize + s;
                let (x, y) = (idx[side], idx[3 * t as usize + (s + 1) % 3]);
                if x != y && x.min(y) == a {
                    local.push((x.max(y), side as u32));
                }
            }
        }
        local.sort_unstable();
        f(a, &local);
    }
}

/// Sentinel in [`EdgeTable::side_edge`] for a side with two equal vertices.
pub const NO_EDGE: u32 = NONE;

impl EdgeTable {
    /// Builds the edge table without a global sort: sides are grouped by their smaller vertex through
    /// the vertex -> triangle CSR, and only each vertex's few sides are sorted. Edges therefore come
    /// out sorted by (min, max) and each edge's triangles in ascending order.
    pub fn new(mesh: &Mesh) -> Self {
        Self::with_vertex_triangles(mesh, &vertex_triangles(mesh))
    }

    /// As [`EdgeTable::new`], reusing the mesh's [`vertex_triangles`].
    ///
    /// Serial: a parallel version over vertex blocks (stitched in order) showed no clear gain on 2
    /// cores in back-to-back runs on a noisy machine, so the simpler code stays.
    pub fn with_vertex_triangles(mesh: &Mesh, vt: &Csr) -> Self {
        let idx = &mesh.indices;
        let mut edges = Vec::with_capacity(idx.len() / 2);
        let mut side_edge = vec![NO_EDGE; idx.len()];
        let mut offsets = Vec::with_capacity(idx.len() / 2 + 1);
        let mut items = Vec::with_capacity(idx.len());
        offsets.push(0u32);
        for_each_vertex_sides(mesh, vt, |a, local| {
            for (i, &(b, side)) in local.iter().enumerate() {
                if i == 0 || local[i - 1].0 != b {
                    if i > 0 {
                        offsets.push(items.len() as u32);
                    }
                    edges.push([a, b]);
                }
                side_edge[side as usize] = edges.len() as u32 - 1;
                items.push(side / 3);
            }
            if !local.is_empty() {
                offsets.push(items.len() as u32);
            }
        });
        Self {
            edges,
            faces: Csr { offsets, items },
            side_edge,
        }
    }

    /// Number of triangle sides on edge `e`.
    pub fn valence(&self, e: usize) -> usize {
        self.faces.row(e).len()
    }
}
