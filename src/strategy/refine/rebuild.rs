//! Step 3: neighbourhood rebuilds (large-neighbourhood search).
//!
//! Every meshlet with its edge neighbours is rebuilt from scratch by meshoptimizer on that
//! sub-mesh; a rebuild is kept when it has fewer meshlets, or as many with fewer vertex
//! references, and no more of them in pieces. A fresh build sees shapes that no sequence of
//! single improving moves reaches.

use super::state::{labels_of, Search};
use super::Stats;
use crate::adjacency::vertex_triangles;
use crate::mesh::Mesh;
use crate::strategy::meshopt::Meshopt;
use crate::strategy::Strategy;

impl Search<'_> {
    /// Every live meshlet, emptiest first, with its neighbours rebuilt from scratch; counts the
    /// meshlets removed as dissolved.
    pub(super) fn rebuild_all(&mut self, stats: &mut Stats) {
        for m in self.cells.emptiest_first() {
            if self.cells.tcount[m as usize] == 0 {
                continue;
            }
            let mut region = self.cells.adjacent_meshlets(m);
            region.push(m);
            region.sort_unstable();
            region.dedup();
            let before = region.len();
            if self.rebuild(&region) {
                stats.dissolved += before - self.cells.live_in(&region);
            }
        }
    }

    /// Rebuilds the union of `region`'s meshlets from scratch with meshoptimizer; keeps the result
    /// when it has fewer meshlets, or as many with fewer vertex references (and no more meshlets
    /// in pieces). True when kept.
    fn rebuild(&mut self, region: &[u32]) -> bool {
        let p = &self.cells;
        let mut tris: Vec<u32> = region
            .iter()
            .flat_map(|&m| p.members[m as usize].iter().copied())
            .collect();
        tris.sort_unstable();
        let mut local = std::collections::HashMap::new();
        let mut positions = Vec::new();
        let mut indices = Vec::with_capacity(3 * tris.len());
        for &t in &tris {
            for v in p.mesh.triangle(t as usize) {
                let l = *local.entry(v).or_insert_with(|| {
                    positions.push(p.mesh.positions[v as usize]);
                    positions.len() as u32 - 1
                });
                indices.push(l);
            }
        }
        let sub = Mesh { positions, indices };
        let ml = Meshopt { cone_weight: 0.0 }.build(&sub, p.limits);
        let old_refs: u32 = region.iter().map(|&m| p.vcount[m as usize]).sum();
        if ml.len() > region.len()
            || (ml.len() == region.len() && ml.vertices.len() as u32 >= old_refs)
        {
            return false;
        }
        let vt = vertex_triangles(&sub);
        let (labels, _) = labels_of(&sub, &vt, &ml);
        let before = (p.live_in(region), old_refs);
        let pieces_before = region.iter().filter(|&&m| !self.is_connected(m)).count();
        let old_labels: Vec<u32> = tris.iter().map(|&t| self.cells.label[t as usize]).collect();
        let new_labels: Vec<u32> = labels.iter().map(|&l| region[l as usize]).collect();
        self.cells
            .relabel(&mut self.scratch, &tris, &new_labels, region);
        // meshoptimizer does not promise one piece per meshlet: hand stray pieces to neighbours,
        // and never end with more meshlets in pieces than before.
        self.mend_pieces(region);
        let pieces_after = region.iter().filter(|&&m| !self.is_connected(m)).count();
        let refs: u32 = region.iter().map(|&m| self.cells.vcount[m as usize]).sum();
        if pieces_after > pieces_before || (self.cells.live_in(region), refs) >= before {
            self.cells
                .relabel(&mut self.scratch, &tris, &old_labels, region);
            return false;
        }
        self.cells.moves += 1;
        for &m in region {
            self.cells.changed_at[m as usize] = self.cells.moves;
        }
        true
    }

    /// Moves every piece but the largest of each meshlet in `region` into other region meshlets
    /// with room, where it can.
    fn mend_pieces(&mut self, region: &[u32]) {
        for &m in region {
            if self.is_connected(m) {
                continue;
            }
            let pieces = self.scratch.pieces(&self.cells, m);
            let largest = (0..pieces.len())
                .max_by_key(|&i| (pieces[i].len(), std::cmp::Reverse(pieces[i][0])))
                .expect("a meshlet in pieces has pieces");
            for (i, piece) in pieces.iter().enumerate() {
                if i == largest {
                    continue;
                }
                let p = &mut self.cells;
                let mut left: Vec<u32> = piece.clone();
                let mut progress = true;
                while !left.is_empty() && progress {
                    progress = false;
                    left.retain(|&t| {
                        let (nb, n) = p.neighbour_labels(t);
                        let to = nb[..n]
                            .iter()
                            .copied()
                            .filter(|b| region.contains(b))
                            .map(|b| (p.added(t, b), b))
                            .filter(|&(add, b)| p.fits(b, add))
                            .min();
                        match to {
                            Some((_, b)) => {
                                p.apply(t, b);
                                progress = true;
                                false
                            }
                            None => true,
                        }
                    });
                }
            }
        }
    }
}
