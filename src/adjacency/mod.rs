//! Mesh connectivity as flat CSR arrays: the triangle dual graph (edge-adjacent triangles), its
//! per-side flags and its edge-connected pieces, built on the mesh's edges (vertex -> triangles and
//! the edge table live in `mesh::edges`, one room down, and are re-exported here).
//!
//! Everything here is deterministic: rows are sorted by triangle id, edges by (min, max) vertex id,
//! whatever the thread count. The GPU adjacency kernels mirror these arrays exactly.

pub use crate::common::Csr;
use crate::common::{sort_dedup_tail, NONE};
use crate::mesh::edges::for_each_vertex_sides_in;
pub use crate::mesh::edges::{vertex_triangles, EdgeTable, NO_EDGE};
use crate::mesh::Mesh;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// The triangle dual graph: triangle -> edge-adjacent triangles, each row sorted, without duplicates
/// or self-loops. Non-manifold edges connect all their triangles pairwise. `vt` must be
/// [`vertex_triangles`] of the same mesh.
///
/// Sides are grouped by their smaller vertex (as in [`EdgeTable`]); a manifold edge's two sides
/// write each other's triangle into a fixed slot per side, so no edge table is materialised and rows
/// need no merging. Only non-manifold runs go through a side list. (Intersecting the two vertex rows
/// of each edge was measured slower: 8.5 against 7.0 ms on the bunny.)
///
/// Both passes run over blocks in parallel: vertex blocks fill the slots (each side belongs to one
/// vertex, so no two blocks write one slot), triangle blocks build their rows, stitched in block
/// order. The output is the same for any thread count. It is the largest sequential step left in
/// the region-parallel k-medoids otherwise (a sixth of its two-thread time on the dragon).
pub fn dual_graph(mesh: &Mesh, vt: &Csr) -> Csr {
    let t_count = mesh.triangle_count();
    let v_count = mesh.vertex_count() as u32;
    let slot: Vec<AtomicU32> = (0..mesh.indices.len())
        .into_par_iter()
        .map(|_| AtomicU32::new(NONE))
        .collect();
    let extra: Vec<Vec<(u32, u32)>> = (0..v_count.div_ceil(BLOCK as u32))
        .into_par_iter()
        .map(|b| {
            let range = b * BLOCK as u32..((b + 1) * BLOCK as u32).min(v_count);
            let mut extra = Vec::new();
            for_each_vertex_sides_in(mesh, vt, range, |_, local| {
                pair_sides(local, &slot, &mut extra)
            });
            extra
        })
        .collect();
    // Counting sort by triangle (linear; non-manifold meshes can have millions of pairs). The
    // order within a row does not matter: rows are sorted below.
    let extra = Csr::from_pairs(t_count, extra.iter().flatten().copied());
    let blocks: Vec<(Vec<u32>, Vec<u32>)> = (0..t_count.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let rows = b * BLOCK..((b + 1) * BLOCK).min(t_count);
            let mut lens = Vec::with_capacity(rows.len());
            let mut items = Vec::with_capacity(3 * rows.len());
            for t in rows {
                let start = items.len();
                items.extend(
                    slot[3 * t..3 * t + 3]
                        .iter()
                        .map(|s| s.load(Ordering::Relaxed))
                        .filter(|&n| n != NONE),
                );
                items.extend_from_slice(extra.row(t));
                sort_dedup_tail(&mut items, start);
                lens.push((items.len() - start) as u32);
            }
            (lens, items)
        })
        .collect();
    let mut offsets = Vec::with_capacity(t_count + 1);
    let mut items = Vec::with_capacity(blocks.iter().map(|b| b.1.len()).sum());
    offsets.push(0u32);
    for (lens, block) in &blocks {
        for &l in lens {
            offsets.push(offsets[offsets.len() - 1] + l);
        }
        items.extend_from_slice(block);
    }
    Csr { offsets, items }
}

/// Vertices or triangles per block of [`dual_graph`]'s parallel passes: large enough that a block
/// (tens of microseconds) costs far more than scheduling it, small enough that a mesh of ten
/// thousand triangles already spreads over the threads (at 16384 such a mesh was one block, and
/// the dual graph a seventh of its two-thread build time).
const BLOCK: usize = 2048;

/// One vertex's sides (`local`, runs of equal other vertex are one edge): a manifold edge's two
/// sides take each other's triangle in `slot`, a non-manifold edge's triangles pair up in `extra`.
fn pair_sides(local: &[(u32, u32)], slot: &[AtomicU32], extra: &mut Vec<(u32, u32)>) {
    let mut i = 0;
    while i < local.len() {
        let mut j = i + 1;
        while j < local.len() && local[j].0 == local[i].0 {
            j += 1;
        }
        if j - i == 2 {
            let (s0, s1) = (local[i].1, local[i + 1].1);
            if s0 / 3 != s1 / 3 {
                slot[s0 as usize].store(s1 / 3, Ordering::Relaxed);
                slot[s1 as usize].store(s0 / 3, Ordering::Relaxed);
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

/// Edge-connected piece of each triangle: labels `0..pieces`, numbered in order of each piece's
/// lowest triangle. Every "is it in one piece" question in the crate is answered from these labels
/// (of the whole dual graph, or of a subgraph given as its own CSR).
pub fn pieces(dual: &Csr) -> Vec<u32> {
    let mut piece = vec![NONE; dual.rows()];
    let mut stack = Vec::new();
    let mut next = 0;
    for s in 0..dual.rows() {
        if piece[s] != NONE {
            continue;
        }
        piece[s] = next;
        stack.push(s as u32);
        while let Some(u) = stack.pop() {
            for &v in dual.row(u as usize) {
                if piece[v as usize] == NONE {
                    piece[v as usize] = next;
                    stack.push(v);
                }
            }
        }
        next += 1;
    }
    piece
}

/// Per cluster of `labels` (ids below `k`, every triangle labelled): how many edge-connected pieces
/// its triangles form, and how many pieces of the whole mesh they lie in. A cluster is connected
/// wherever the mesh is when the two are equal (a mesh joined only at vertices, like a strut
/// lattice, cannot give every full cluster one piece).
pub fn cluster_pieces(dual: &Csr, labels: &[u32], k: usize) -> Vec<(usize, usize)> {
    let mesh = pieces(dual);
    let same = Csr::from_pairs(
        dual.rows(),
        (0..dual.rows() as u32).flat_map(|t| {
            dual.row(t as usize)
                .iter()
                .filter(move |&&u| labels[u as usize] == labels[t as usize])
                .map(move |&u| (t, u))
        }),
    );
    let own = pieces(&same);
    let mut per: Vec<Vec<(u32, u32)>> = vec![Vec::new(); k];
    for (t, &l) in labels.iter().enumerate() {
        per[l as usize].push((own[t], mesh[t]));
    }
    per.into_iter()
        .map(|p| {
            let count =
                |f: fn(&(u32, u32)) -> u32| crate::common::sorted(p.iter().map(f).collect()).len();
            (count(|x| x.0), count(|x| x.1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_number_components_by_lowest_triangle_and_clusters_count_theirs() {
        // Triangles 0-1-2 form a path, 3-4 another, 5 stands alone.
        let pairs = [(0, 1), (1, 0), (1, 2), (2, 1), (3, 4), (4, 3)];
        let dual = Csr::from_pairs(6, pairs.into_iter());
        assert_eq!(pieces(&dual), vec![0, 0, 0, 1, 1, 2]);
        // Cluster 0 = {0, 2}: two pieces of its own (1 lies between them) in one mesh piece.
        // Cluster 1 = {1, 3, 4, 5}: pieces {1}, {3, 4}, {5} in three mesh pieces.
        let labels = [0, 1, 0, 1, 1, 1];
        assert_eq!(cluster_pieces(&dual, &labels, 2), vec![(2, 1), (3, 3)]);
        // An empty cluster has neither.
        assert_eq!(cluster_pieces(&dual, &labels, 3)[2], (0, 0));
    }

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
        assert_eq!(d, dual_by_edges(&m));
        assert_eq!(vt.row(5), &[3]);
    }

    /// The triangles of every edge in the edge table paired up: the dual graph by another route.
    fn dual_by_edges(m: &Mesh) -> Csr {
        let et = EdgeTable::new(m);
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
        Csr::from_pairs(m.triangle_count(), pairs.into_iter())
    }

    #[test]
    fn the_parallel_blocks_give_one_dual_graph_on_any_thread_count() {
        // Several vertex and triangle blocks, a fin on one edge of every third triangle (non-manifold
        // edges in every block, block boundaries included) and a degenerate triangle.
        let mut m = crate::mesh::generate::terrain(160, 3);
        let n = m.vertex_count() as u32;
        let extra: Vec<u32> = (0..m.triangle_count() as u32)
            .step_by(3)
            .flat_map(|t| {
                let [a, b, _] = m.triangle(t as usize);
                [a, b, n]
            })
            .collect();
        m.positions.push([0.5, 0.5, 9.0]);
        m.indices.extend(extra);
        m.indices.extend([0, 0, 1]);
        let t = m.triangle_count();
        assert!(t > 3 * BLOCK && m.vertex_count() > BLOCK, "{t}");
        let vt = vertex_triangles(&m);
        let pool = |k| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(k)
                .build()
                .unwrap()
        };
        let one = pool(1).install(|| dual_graph(&m, &vt));
        assert_eq!(one, pool(3).install(|| dual_graph(&m, &vt)));
        assert_eq!(one, dual_by_edges(&m));
        assert!(
            (0..t).any(|r| one.row(r).len() > 3),
            "the fins make non-manifold rows"
        );
    }
}
