//! Orderings that do not change which triangles form a meshlet: the triangle order inside each
//! meshlet (for vertex reuse, like `meshopt_optimizeMeshlet`; seed: "Meshlet triangle locality
//! matters") and the order of meshlets in the collection (the paper's Figure 10).

use super::Meshlets;
use crate::mesh::tipsify::fifo_misses;
use std::str::FromStr;

/// Reorders each meshlet's triangles so that consecutive triangles share vertices, then renumbers
/// the local vertices in first-use order. The triangle set and each triangle's winding (up to
/// rotation) are unchanged.
///
/// Greedy: the next triangle is the unused one with the most corners among the vertices of the last
/// two emitted triangles (an edge-neighbour of the last triangle scores highest), ties to the lower
/// position; with no such triangle, the first unused one. A meshlet whose greedy order misses an
/// 8-entry FIFO more often than its built order keeps the built order (meshoptimizer already emits
/// triangles in adjacency order), so the pass never makes locality worse.
pub fn optimize_triangle_order(ml: &mut Meshlets) {
    for i in 0..ml.len() {
        let m = ml.meshlets[i];
        let (vo, to) = (m.vertex_offset as usize, m.triangle_offset as usize);
        let (vc, tc) = (m.vertex_count as usize, m.triangle_count as usize);
        let tris: Vec<[u8; 3]> = ml.triangles[to..to + 3 * tc]
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let mut done = vec![false; tc];
        let mut order = Vec::with_capacity(tc);
        // Recency: the step at which each local vertex was last used (0 = never).
        let mut last_used = vec![0usize; vc];
        let mut step = 0usize;
        while order.len() < tc {
            let mut best: Option<(usize, usize)> = None; // (score, index)
            for (k, t) in tris.iter().enumerate() {
                if done[k] {
                    continue;
                }
                // A corner used by one of the last two triangles counts.
                let score = t
                    .iter()
                    .filter(|&&c| last_used[c as usize] + 2 > step && last_used[c as usize] > 0)
                    .count();
                if best.is_none_or(|(s, _)| score > s) {
                    best = Some((score, k));
                }
                if score == 3 {
                    break;
                }
            }
            let (_, k) = best.expect("an unused triangle remains");
            done[k] = true;
            step += 1;
            for &c in &tris[k] {
                last_used[c as usize] = step;
            }
            order.push(k);
        }
        let misses = |o: &[usize]| fifo_misses(o.iter().flat_map(|&k| tris[k]), LOCAL_CACHE);
        let built: Vec<usize> = (0..tc).collect();
        if misses(&order) >= misses(&built) {
            order = built;
        }
        // Renumber local vertices in first-use order.
        let mut remap = vec![u8::MAX; vc];
        let mut new_vertices = Vec::with_capacity(vc);
        let old_vertices = ml.vertices[vo..vo + vc].to_vec();
        for (slot, &k) in order.iter().enumerate() {
            for (j, &c) in tris[k].iter().enumerate() {
                if remap[c as usize] == u8::MAX {
                    remap[c as usize] = new_vertices.len() as u8;
                    new_vertices.push(old_vertices[c as usize]);
                }
                ml.triangles[to + 3 * slot + j] = remap[c as usize];
            }
        }
        ml.vertices[vo..vo + vc].copy_from_slice(&new_vertices);
    }
}

/// FIFO size of the locality test in [`optimize_triangle_order`] (the 8 of the benches' miss rate).
const LOCAL_CACHE: usize = 8;

/// The order of meshlets in a collection.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum MeshletOrder {
    /// As the strategy built them.
    #[default]
    AsBuilt,
    /// Most triangles first (the paper's Figure 10).
    Triangles,
    /// Most vertices first.
    Vertices,
}

impl FromStr for MeshletOrder {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "built" | "as-built" => Ok(Self::AsBuilt),
            "triangles" => Ok(Self::Triangles),
            "vertices" => Ok(Self::Vertices),
            _ => Err(format!(
                "unknown meshlet order '{s}' (built, triangles, vertices)"
            )),
        }
    }
}

/// Reorders the meshlet descriptors (the vertex and triangle arrays stay where they are). Stable, so
/// meshlets of equal size keep their build order.
pub fn order_meshlets(ml: &mut Meshlets, order: MeshletOrder) {
    match order {
        MeshletOrder::AsBuilt => {}
        MeshletOrder::Triangles => ml
            .meshlets
            .sort_by_key(|m| std::cmp::Reverse(m.triangle_count)),
        MeshletOrder::Vertices => ml
            .meshlets
            .sort_by_key(|m| std::cmp::Reverse(m.vertex_count)),
    }
}

/// Mean number of new vertices per triangle when each meshlet's triangles are drawn in order through
/// a FIFO cache of `cache` local vertices: lower means better locality. 1/3 per corner is a miss.
pub fn local_miss_rate(ml: &Meshlets, cache: usize) -> f64 {
    let misses: usize = (0..ml.len())
        .map(|i| fifo_misses(ml.meshlet_triangles(i).iter().copied(), cache))
        .sum();
    misses as f64 / ml.triangle_count().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::meshlet::{validate, Limits};
    use crate::strategy::{by_name, Options};

    #[test]
    fn reordering_keeps_the_meshlets_valid_and_improves_locality() {
        let mesh = crate::mesh::generate::noisy_sphere(3, 0.1, 2);
        let mut ml = by_name("nvidia", &Options::default())
            .unwrap()
            .build(&mesh, Limits::DEFAULT);
        // Scramble each meshlet's triangle order first.
        for i in 0..ml.len() {
            let m = ml.meshlets[i];
            let to = m.triangle_offset as usize;
            let n = m.triangle_count as usize;
            let mut t: Vec<[u8; 3]> = ml.triangles[to..to + 3 * n]
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect();
            t.reverse();
            t.rotate_left(n / 3);
            for (k, c) in t.iter().enumerate() {
                ml.triangles[to + 3 * k..to + 3 * k + 3].copy_from_slice(c);
            }
        }
        let before = local_miss_rate(&ml, 8);
        let per_meshlet = |ml: &Meshlets| -> Vec<usize> {
            (0..ml.len())
                .map(|i| fifo_misses(ml.meshlet_triangles(i).iter().copied(), 8))
                .collect()
        };
        let misses_before = per_meshlet(&ml);
        let sets_before: Vec<Vec<u32>> = (0..ml.len())
            .map(|i| {
                let mut v = ml.meshlet_vertices(i).to_vec();
                v.sort();
                v
            })
            .collect();
        optimize_triangle_order(&mut ml);
        validate(&mesh, &ml, Limits::DEFAULT).unwrap();
        let sets_after: Vec<Vec<u32>> = (0..ml.len())
            .map(|i| {
                let mut v = ml.meshlet_vertices(i).to_vec();
                v.sort();
                v
            })
            .collect();
        assert_eq!(sets_before, sets_after);
        let after = local_miss_rate(&ml, 8);
        assert!(after < before, "miss rate {before} -> {after}");
        // Never worse for any meshlet.
        for (a, b) in per_meshlet(&ml).iter().zip(&misses_before) {
            assert!(a <= b);
        }
        // Local vertices are numbered in first-use order.
        for i in 0..ml.len() {
            let mut next = 0u8;
            for &c in ml.meshlet_triangles(i) {
                assert!(c <= next);
                next = next.max(c + 1);
            }
        }
    }

    #[test]
    fn collection_order_is_a_stable_permutation() {
        let mesh = crate::mesh::generate::terrain(30, 2);
        let ml = by_name("greedy", &Options::default())
            .unwrap()
            .build(&mesh, Limits::DEFAULT);
        let mut by_tris = ml.clone();
        order_meshlets(&mut by_tris, MeshletOrder::Triangles);
        validate(&mesh, &by_tris, Limits::DEFAULT).unwrap();
        assert!(by_tris
            .meshlets
            .windows(2)
            .all(|w| w[0].triangle_count >= w[1].triangle_count));
        let mut by_verts = ml.clone();
        order_meshlets(&mut by_verts, MeshletOrder::Vertices);
        assert!(by_verts
            .meshlets
            .windows(2)
            .all(|w| w[0].vertex_count >= w[1].vertex_count));
    }
}
