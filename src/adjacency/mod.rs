//! Mesh connectivity as flat CSR arrays: vertex -> triangles, the edge table, and the triangle dual
//! graph (edge-adjacent triangles).
//!
//! Everything here is deterministic: rows are sorted by triangle id, edges by (min, max) vertex id,
//! whatever the thread count. The GPU adjacency kernels mirror these arrays exactly.

use crate::mesh::Mesh;

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
    // Count, prefix sum, scatter in triangle order (so rows come out sorted).
    let n = mesh.vertex_count();
    let mut offsets = vec![0u32; n + 1];
    let distinct = |t: usize| {
        let [a, b, c] = mesh.triangle(t);
        [
            Some(a),
            (b != a).then_some(b),
            (c != a && c != b).then_some(c),
        ]
    };
    for t in 0..mesh.triangle_count() {
        for v in distinct(t).into_iter().flatten() {
            offsets[v as usize + 1] += 1;
        }
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    let mut cursor = offsets.clone();
    let mut items = vec![0u32; offsets[n] as usize];
    for t in 0..mesh.triangle_count() {
        for v in distinct(t).into_iter().flatten() {
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
fn for_each_vertex_sides(mesh: &Mesh, vt: &Csr, mut f: impl FnMut(u32, &[(u32, u32)])) {
    let idx = &mesh.indices;
    let mut local: Vec<(u32, u32)> = Vec::new();
    for a in 0..mesh.vertex_count() as u32 {
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
pub const NO_EDGE: u32 = u32::MAX;

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

/// The triangle dual graph: triangle -> edge-adjacent triangles, each row sorted, without duplicates
/// or self-loops. Non-manifold edges connect all their triangles pairwise. `vt` must be
/// [`vertex_triangles`] of the same mesh.
///
/// Sides are grouped by their smaller vertex (as in [`EdgeTable`]); a manifold edge's two sides
/// write each other's triangle into a fixed slot per side, so no edge table is materialised and rows
/// need no merging. Only non-manifold runs go through a side list. (Intersecting the two vertex rows
/// of each edge was measured slower: 8.5 against 7.0 ms on the bunny.)
pub fn dual_graph(mesh: &Mesh, vt: &Csr) -> Csr {
    const NONE: u32 = u32::MAX;
    let idx = &mesh.indices;
    let t_count = mesh.triangle_count();
    let mut slot = vec![NONE; idx.len()];
    let mut extra: Vec<(u32, u32)> = Vec::new();
    for_each_vertex_sides(mesh, vt, |_, local| {
        let mut i = 0;
        while i < local.len() {
            let mut j = i + 1;
            while j < local.len() && local[j].0 == local[i].0 {
                j += 1;
            }
            if j - i == 2 {
                let (s0, s1) = (local[i].1, local[i + 1].1);
                if s0 / 3 != s1 / 3 {
                    slot[s0 as usize] = s1 / 3;
                    slot[s1 as usize] = s0 / 3;
                }
            } else if j - i > 2 {
                for p in i..j {
                    for q in i..j {
                        let (tp, tq) = (local[p].1 / 3, local[q].1 / 3);
                        if tp != tq {
                            extra.push((tp, tq));
                        }
                    }
                }
            }
            i = j;
        }
    });
    // Counting sort by triangle (linear; non-manifold meshes can have millions of pairs).
    let extra = Csr::from_pairs(t_count, extra.iter().copied());
    let mut offsets = Vec::with_capacity(t_count + 1);
    let mut items = Vec::with_capacity(idx.len());
    offsets.push(0u32);
    for t in 0..t_count {
        let start = items.len();
        items.extend(slot[3 * t..3 * t + 3].iter().filter(|&&n| n != NONE));
        items.extend_from_slice(extra.row(t));
        items[start..].sort_unstable();
        let mut w = start;
        for r in start..items.len() {
            if r == start || items[r] != items[w - 1] {
                items[w] = items[r];
                w += 1;
            }
        }
        items.truncate(w);
        offsets.push(items.len() as u32);
    }
    Csr { offsets, items }
}

/// Per-triangle side flags from the edge table: bit `i` marks side `i` (vertices `i`, `i + 1`) as a
/// boundary edge (valence 1), bit `3 + i` as non-manifold (valence above 2), bit `6 + i` as
/// collapsed (both vertices equal). CPU reference of the GPU `dual_count` kernel's flags.
pub fn side_flags(mesh: &Mesh, edges: &EdgeTable) -> Vec<u32> {
    (0..mesh.triangle_count())
        .map(|t| {
            (0..3).fold(0u32, |f, i| match edges.side_edge[3 * t + i] {
                NO_EDGE => f | 1 << (6 + i),
                e => match edges.valence(e as usize) {
                    1 => f | 1 << i,
                    v if v > 2 => f | 1 << (3 + i),
                    _ => f,
                },
            })
        })
        .collect()
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
        let d = dual_graph(&m, &vertex_triangles(&m));
        assert_eq!(d.row(0), &[1, 2]);
        assert_eq!(d.row(2), &[0, 1]);
        // Triangle 3 (5,5,1) shares edge (1,5) with nobody.
        assert!(d.row(3).is_empty());
        let vt = vertex_triangles(&m);
        assert_eq!(vt.row(0), &[0, 1, 2]);
        // Same as pairing up the triangles of every edge in the edge table.
        let et = EdgeTable::new(&m);
        let mut pairs = Vec::new();
        for e in 0..et.edges.len() {
            for &a in et.faces.row(e) {
                for &b in et.faces.row(e) {
                    if a != b {
                        pairs.push((a, b));
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        assert_eq!(d, Csr::from_pairs(m.triangle_count(), pairs.into_iter()));
        assert_eq!(vt.row(5), &[3]);
    }
}
