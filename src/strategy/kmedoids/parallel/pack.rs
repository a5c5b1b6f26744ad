//! Piece packing in `kmedoids-parallel`'s growth: a cluster whose piece ran out goes on in the
//! nearest small piece that fits (`Packing`, step 2), and after the merges a cluster made only
//! of whole small pieces is dissolved into the nearest clusters with room (`pack_pieces`, step
//! 2c). The `grow` kernel's `nearest_piece` and `pack_pieces` mirror them.

use super::super::morton::{distance2, unpack, Centre};
use super::layout;
use super::region::{Clusters, Region, State};

/// How many pieces a packing cluster weighs for its next piece ([`layout::PACK_WINDOW`]).
pub const PACK_WINDOW: usize = layout::PACK_WINDOW as usize;

/// A region's pieces of its dual graph in seed order (each in reversed BFS order from its lowest
/// triangle, so seeds come deepest first).
pub(super) struct Pieces {
    /// Local triangles, piece by piece.
    pub order: Vec<usize>,
    /// Where each piece starts in `order`.
    pub starts: Vec<usize>,
    /// Whether each piece is a whole piece of the mesh (no edge leaves the region).
    pub closed: Vec<bool>,
}

/// Where a packing cluster may go on: the region's pieces in seed order and its centre.
pub(super) struct Packing<'a> {
    /// The region's pieces in seed order.
    pub pieces: &'a Pieces,
    /// Free triangles per piece.
    pub left: &'a [u32],
    /// The first free triangle's position in `order`.
    pub cursor: usize,
    /// The cluster's centre.
    pub centre: [u32; 3],
}

impl Packing<'_> {
    /// The seed of the piece nearest the cluster's centre (ties to the earlier piece) among the
    /// [`PACK_WINDOW`] pieces from the cursor's: the cursor's own, or an untouched one after it
    /// (its first triangle in the seed order), if it is a whole piece of the mesh (a piece the
    /// region's border cuts could put the cluster in two parts of one mesh piece) and its seed
    /// `fits` the cluster.
    pub fn nearest(
        &self,
        piece: &[u32],
        centre_of: &impl Fn(usize) -> Centre,
        fits: &impl Fn(usize) -> bool,
    ) -> Option<usize> {
        let first = piece[self.pieces.order[self.cursor]] as usize;
        let mut best: Option<(u32, usize)> = None;
        for p in first..(first + PACK_WINDOW).min(self.pieces.starts.len()) {
            let seed = if p == first {
                self.pieces.order[self.cursor]
            } else {
                let end = self
                    .pieces
                    .starts
                    .get(p + 1)
                    .copied()
                    .unwrap_or(self.pieces.order.len());
                if self.left[p] as usize != end - self.pieces.starts[p] {
                    continue;
                }
                self.pieces.order[self.pieces.starts[p]]
            };
            if !self.pieces.closed[p] || !fits(seed) {
                continue;
            }
            let d = distance2(unpack(centre_of(seed)), self.centre);
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, seed));
            }
        }
        best.map(|(_, seed)| seed)
    }
}

/// Step 2c for one region: a cluster made of whole pieces of the mesh (each piece without an
/// edge leaving the region, and no member with a neighbour in another cluster) is dissolved when
/// each of its pieces, in piece order, finds a cluster with room, the one whose centre is nearest
/// the piece's (ties to the lower id), and the radii its targets gain sum to at most its own.
/// Clusters go smallest first, in their order after the merges. Room is checked against the
/// target's vertices plus the piece's as if they shared none, so a plan never overfills. A radius
/// is the integer square root of the largest squared distance from a cluster's centre to a
/// member's centroid cell (integers, so exact on every device). `closed[p]`: piece `p` has no
/// edge leaving the region.
///
/// Why: the growth packs pieces only into a cluster whose own piece ran out, so small pieces
/// seeded among a large piece's clusters (the neurons' detached tetrahedra) end as clusters of
/// their own; here they join the large piece's part-filled clusters. The radius rule keeps a
/// dissolution only where the bounding spheres, summed, do not grow: scattered pieces moved into
/// far clusters would cost culling more than the one meshlet saves.
pub(super) fn pack_pieces(g: &Region, s: &mut State, cl: &mut Clusters, closed: &[bool]) {
    let (mv, mt, centres) = (g.mv, g.mt, &g.cells);
    let k = cl.mem.len();
    // The integer mean of the members' centroid cells.
    let centre_of = |members: &mut dyn Iterator<Item = usize>| {
        let (mut sum, mut n) = ([0u32; 3], 0u32);
        for i in members {
            for (x, q) in sum.iter_mut().zip(unpack(centres[i])) {
                *x += q;
            }
            n += 1;
        }
        sum.map(|x| x / n.max(1))
    };
    // The radius around `c`: isqrt of the largest squared distance to a member.
    let radius_of = |members: &mut dyn Iterator<Item = usize>, c: [u32; 3]| {
        members
            .map(|i| distance2(unpack(centres[i]), c))
            .max()
            .unwrap_or(0)
            .isqrt()
    };
    let mut centre: Vec<[u32; 3]> = (0..k)
        .map(|c| centre_of(&mut cl.mem[c].iter().copied()))
        .collect();
    let mut radius: Vec<u32> = (0..k)
        .map(|c| radius_of(&mut cl.mem[c].iter().copied(), centre[c]))
        .collect();
    let mut order: Vec<usize> = (0..k).filter(|&c| cl.alive[c]).collect();
    order.sort_by_key(|&c| (cl.mem[c].len(), c));
    let (mut extra_t, mut extra_v) = (vec![0usize; k], vec![0usize; k]);
    for a in order {
        let whole_pieces = cl.mem[a]
            .iter()
            .all(|&i| closed[s.piece[i] as usize] && g.nbrs(i).all(|j| s.label[j] as usize == a));
        if !whole_pieces {
            continue;
        }
        let mut pieces: Vec<u32> = cl.mem[a].iter().map(|&i| s.piece[i]).collect();
        pieces.sort_unstable();
        pieces.dedup();
        // Members of `a` by piece (the pieces ascending).
        let by_piece: Vec<Vec<usize>> = pieces
            .iter()
            .map(|&p| {
                cl.mem[a]
                    .iter()
                    .copied()
                    .filter(|&i| s.piece[i] == p)
                    .collect()
            })
            .collect();
        // The plan: a target per piece while each finds one with room.
        let mut plan = Vec::with_capacity(pieces.len());
        for tris in &by_piece {
            let pv = cl.vertices(g, s, &[], tris);
            let pc = centre_of(&mut tris.iter().copied());
            let mut best: Option<(u32, usize)> = None;
            for b in 0..k {
                if b == a
                    || !cl.alive[b]
                    || cl.mem[b].len() + extra_t[b] + tris.len() > mt
                    || cl.nverts[b] + extra_v[b] + pv > mv
                {
                    continue;
                }
                let d = distance2(centre[b], pc);
                if best.is_none_or(|(bd, bb)| (d, b) < (bd, bb)) {
                    best = Some((d, b));
                }
            }
            let Some((_, b)) = best else { break };
            extra_t[b] += tris.len();
            extra_v[b] += pv;
            plan.push(b);
        }
        for &b in &plan {
            (extra_t[b], extra_v[b]) = (0, 0);
        }
        if plan.len() < pieces.len() {
            continue;
        }
        // The radii the targets gain, each target counted once (at its first piece).
        let mut gain = 0i64;
        for (x, &b) in plan.iter().enumerate() {
            if plan[..x].contains(&b) {
                continue;
            }
            let mut union = cl.mem[b].clone();
            for (tris, _) in by_piece.iter().zip(&plan).filter(|&(_, &t)| t == b) {
                union.extend_from_slice(tris);
            }
            let c = centre_of(&mut union.iter().copied());
            gain += radius_of(&mut union.iter().copied(), c) as i64 - radius[b] as i64;
        }
        if gain > radius[a] as i64 {
            continue;
        }
        for i in std::mem::take(&mut cl.mem[a]) {
            let b = plan[pieces.binary_search(&s.piece[i]).expect("a member's piece")];
            s.label[i] = b as u32;
            cl.mem[b].push(i);
        }
        cl.alive[a] = false;
        for &b in &plan {
            cl.nverts[b] = cl.vertices(g, s, &[b], &[]);
            centre[b] = centre_of(&mut cl.mem[b].iter().copied());
            radius[b] = radius_of(&mut cl.mem[b].iter().copied(), centre[b]);
        }
    }
}
