//! Mesh connectivity as flat CSR arrays: vertex -> triangles, the edge table, and the triangle dual
//! graph (edge-adjacent triangles).
//!
//! Everything here is deterministic: rows are sorted by triangle id, edges by (min, max) vertex id,
//! whatever the thread count. The GPU adjacency kernels mirror these arrays exactly.

use crate::mesh::Mesh;
use rayon::prelude::*;

/// Compressed sparse rows: row `r` is `items[offsets[r]..offsets[r + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Csr {
    /// Row starts; `offsets.len() == rows + 1`.
    pub offsets: Vec<u32>,
    /// Concatenated rows.
    pub items: Vec<u32>,
}

impl Csr {
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Row `r`.
    #[inline]
    pub fn row(&self, r: usize) -> &[u32] {
        &self.items[self.offsets[r] as usize..self.offsets[r + 1] as usize]
    }

    /// Builds a CSR from (row, item) pairs by count, prefix sum and scatter; pairs keep their input
    /// order within a row, so sorted input gives sorted rows.
    pub fn from_pairs(rows: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> Self {
        let mut offsets = vec![0u32; rows + 1];
        for (r, _) in pairs.clone() {
            offsets[r as usize + 1] += 1;
        }
        for i in 0..rows {
            offsets[i + 1] += offsets[i];
        }
        let mut cursor = offsets.clone();
        let mut items = vec![0u32; offsets[rows] as usize];
        for (r, it) in pairs {
            let c = &mut cursor[r as usize];
            items[*c as usize] = it;
            *c += 1;
        }
        Self { offsets, items }
    }
}

/// Vertex -> incident triangles (each row in ascending triangle order; a degenerate triangle that
/// uses a vertex twice is listed once).
pub fn vertex_triangles(mesh: &Mesh) -> Csr {
    let pairs = (0..mesh.triangle_count() as u32).flat_map(move |t| {
        let [a, b, c] = mesh.triangle(t as usize);
        let uniq = [
            Some(a),
            (b != a).then_some(b),
            (c != a && c != b).then_some(c),
        ];
        uniq.into_iter().flatten().map(move |v| (v, t))
    });
    Csr::from_pairs(mesh.vertex_count(), pairs)
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

/// Sentinel in [`EdgeTable::side_edge`] for a side with two equal vertices.
pub const NO_EDGE: u32 = u32::MAX;

impl EdgeTable {
    /// Builds the edge table by one parallel sort of (edge key, side) pairs.
    pub fn new(mesh: &Mesh) -> Self {
        let sides = mesh.indices.len();
        let mut keys: Vec<(u64, u32)> = (0..sides as u32)
            .into_par_iter()
            .filter_map(|s| {
                let t = (s / 3) as usize;
                let a = mesh.indices[s as usize];
                let b = mesh.indices[3 * t + (s as usize % 3 + 1) % 3];
                (a != b).then(|| (((a.min(b) as u64) << 32) | a.max(b) as u64, s))
            })
            .collect();
        // (key, side) pairs are unique, so the unstable sort is deterministic.
        keys.par_sort_unstable();
        let mut edges = Vec::new();
        let mut side_edge = vec![NO_EDGE; sides];
        let mut pairs = Vec::with_capacity(keys.len());
        for (i, &(k, s)) in keys.iter().enumerate() {
            if i == 0 || keys[i - 1].0 != k {
                edges.push([(k >> 32) as u32, k as u32]);
            }
            let e = edges.len() as u32 - 1;
            side_edge[s as usize] = e;
            pairs.push((e, s / 3));
        }
        let faces = Csr::from_pairs(edges.len(), pairs.iter().copied());
        Self {
            edges,
            faces,
            side_edge,
        }
    }

    /// Number of triangle sides on edge `e`.
    pub fn valence(&self, e: usize) -> usize {
        self.faces.row(e).len()
    }
}

/// The triangle dual graph: triangle -> edge-adjacent triangles, each row sorted, without duplicates
/// or self-loops. Non-manifold edges connect all their triangles pairwise.
pub fn dual_graph(mesh: &Mesh, edges: &EdgeTable) -> Csr {
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for e in 0..edges.edges.len() {
        let row = edges.faces.row(e);
        for (i, &a) in row.iter().enumerate() {
            for &b in &row[i + 1..] {
                if a != b {
                    pairs.push((a, b));
                    pairs.push((b, a));
                }
            }
        }
    }
    pairs.par_sort_unstable();
    pairs.dedup();
    Csr::from_pairs(mesh.triangle_count(), pairs.iter().copied())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_and_fin() -> Mesh {
        // Two triangles sharing edge (0,2), plus a third on the same edge (non-manifold) and a
        // degenerate triangle.
        Mesh {
            positions: vec![[0.0; 3]; 6],
            indices: vec![0, 1, 2, 0, 2, 3, 2, 0, 4, 5, 5, 1],
        }
    }

    #[test]
    fn edge_table_counts_valence_and_collapsed_sides() {
        let m = quad_and_fin();
        let et = EdgeTable::new(&m);
        let e02 = et.edges.iter().position(|&e| e == [0, 2]).unwrap();
        assert_eq!(et.faces.row(e02), &[0, 1, 2]);
        assert_eq!(et.side_edge[9], NO_EDGE); // side (5,5) of the degenerate triangle
        assert!(et.edges.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn dual_graph_and_vertex_rows() {
        let m = quad_and_fin();
        let et = EdgeTable::new(&m);
        let d = dual_graph(&m, &et);
        assert_eq!(d.row(0), &[1, 2]);
        assert_eq!(d.row(2), &[0, 1]);
        // Triangle 3 (5,5,1) shares edge (1,5) with nobody.
        assert!(d.row(3).is_empty());
        let vt = vertex_triangles(&m);
        assert_eq!(vt.row(0), &[0, 1, 2]);
        assert_eq!(vt.row(5), &[3]);
    }
}
