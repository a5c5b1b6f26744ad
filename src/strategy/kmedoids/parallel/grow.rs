//! Step 2 of `kmedoids-parallel`: one region's growth ([`grow_region`]), which gathers the
//! region's local arrays, orders its pieces into the seed order, grows clusters by integer keys,
//! and runs the pocket rules, merges, piece packing and dissolving that the other step files
//! hold. The `grow` kernel of `wgsl/kmedoids_parallel.wgsl` runs it line for line.

use super::super::morton::{distance2, unpack};
use super::dissolve::dissolve_clusters;
use super::merge::merge_neighbours;
use super::pack::{pack_pieces, Packing, Pieces};
use super::pockets::absorb_pockets;
use super::region::{Region, State};
use super::{RegionInput, NONE};
use crate::common::Csr;

/// The growth key: (vertices added, free neighbours, squared distance to the centre, hops,
/// local triangle); the least grows next.
type GrowKey = (usize, usize, u32, u32, usize);

/// Step 2 for region `r` (members `tris`, ascending): each member's cluster, numbered from 0 in
/// the order clusters close, and the cluster count.
pub fn grow_region(input: &RegionInput<'_>, r: u32, tris: &[u32]) -> (Vec<u32>, u32) {
    let n = tris.len();
    let reg = gather_region(input, r, tris);
    let mut s = State::new(n);
    let (pieces, mut left) = order_pieces(&reg, &mut s);
    let order = &pieces.order;
    // Distinct corners of `i` whose vertex cluster `c` does not use yet.
    let (mv, mt, lc) = (reg.mv, reg.mt, &reg.cells);
    let added = |s: &State, i: usize, c: u32| {
        let k = reg.corners(i);
        (0..3)
            .filter(|&j| s.mark[k[j]] != c && !k[..j].contains(&k[j]))
            .count()
    };
    let free_neighbours = |s: &State, i: usize| reg.nbrs(i).filter(|&j| s.label[j] == NONE).count();
    let mut front: Vec<usize> = Vec::new();
    let mut grown: Vec<usize> = Vec::new();
    // Cluster vertices after each grown triangle.
    let mut vcount: Vec<u32> = Vec::new();
    let (mut cursor, mut c, mut open) = (0usize, 0u32, false);
    let mut nv = 0usize;
    let mut sum = [0u32; 3];
    loop {
        while cursor < n && s.label[order[cursor]] != NONE {
            cursor += 1;
        }
        if cursor == n {
            if open {
                c += 1;
            }
            break;
        }
        let seed = if open {
            // A packing cluster (its piece ran out while it had room) goes on at the nearest
            // piece that fits among the next ones, or closes as it is.
            let g = grown.len() as u32;
            let pack = Packing {
                pieces: &pieces,
                left: &left,
                cursor,
                centre: sum.map(|x| x / g),
            };
            let fits = |i: usize| nv + added(&s, i, c) <= mv;
            match pack.nearest(&s.piece, &|i| lc[i], &fits) {
                Some(i) => i,
                None => {
                    c += 1;
                    open = false;
                    continue;
                }
            }
        } else {
            (nv, open) = (0, true);
            sum = [0; 3];
            grown.clear();
            vcount.clear();
            order[cursor]
        };
        front.clear();
        front.push(seed);
        s.inq[seed] = c;
        s.hop[seed] = 0;
        s.free[seed] = free_neighbours(&s, seed) as u32;
        while grown.len() < mt {
            // The cluster's centre so far (integer division: exact on every device).
            let centre = if grown.is_empty() {
                unpack(lc[seed])
            } else {
                let g = grown.len() as u32;
                sum.map(|x| x / g)
            };
            let mut best: Option<(GrowKey, usize)> = None;
            for (fi, &i) in front.iter().enumerate() {
                let (a, free) = (added(&s, i, c), s.free[i] as usize);
                if nv + a > mv {
                    continue;
                }
                let d2 = distance2(unpack(lc[i]), centre);
                let key = (a, free, d2, s.hop[i], i);
                if best.is_none_or(|(b, _)| key < b) {
                    best = Some((key, fi));
                }
            }
            let Some((_, fi)) = best else { break };
            let i = front.swap_remove(fi);
            s.label[i] = c;
            s.aux[i] = grown.len() as u32;
            left[s.piece[i] as usize] -= 1;
            for k in reg.corners(i) {
                if s.mark[k] != c {
                    s.mark[k] = c;
                    s.first[k] = grown.len() as u32;
                    nv += 1;
                }
            }
            grown.push(i);
            for (x, q) in sum.iter_mut().zip(unpack(lc[i])) {
                *x += q;
            }
            vcount.push(nv as u32);
            // Dual rows have no repeats, so each neighbour is seen once: on the frontier it
            // has one free neighbour fewer, else it joins with its count taken afresh.
            for j in reg.nbrs(i) {
                if s.label[j] != NONE {
                    continue;
                }
                if s.inq[j] == c {
                    s.free[j] -= 1;
                } else {
                    s.inq[j] = c;
                    s.hop[j] = s.hop[i] + 1;
                    s.free[j] = free_neighbours(&s, j) as u32;
                    front.push(j);
                }
            }
        }
        let exhausted = front.is_empty() && left[s.piece[seed] as usize] == 0;
        if exhausted && grown.len() < mt && nv < mv {
            continue;
        }
        if let Some(earliest) = absorb_pockets(&reg, &mut s, &mut grown, &vcount, &mut left, c) {
            // Triangles before the cursor are taken, but those given back: seeds resume there.
            cursor = cursor.min(earliest);
        }
        c += 1;
        open = false;
    }
    let mut clusters = merge_neighbours(&reg, &mut s, c);
    pack_pieces(&reg, &mut s, &mut clusters, &pieces.closed);
    dissolve_clusters(&reg, &mut s, &mut clusters);
    let k = clusters.renumber(&mut s.label);
    (s.label, k)
}

/// The region's dual graph, canonical corners and centres in local numbers, gathered once: the
/// growth reads them for every frontier triangle at every step (the kernel reads the global
/// arrays instead; the values are the same).
fn gather_region(input: &RegionInput<'_>, r: u32, tris: &[u32]) -> Region {
    let n = tris.len();
    let mut local_dual = Csr {
        offsets: Vec::with_capacity(n + 1),
        items: Vec::with_capacity(3 * n),
    };
    local_dual.offsets.push(0);
    let mut inner = Vec::with_capacity(n);
    for &t in tris {
        let row = input.dual.row(t as usize);
        let inside = row.iter().filter(|&&x| input.region[x as usize] == r);
        let before = local_dual.items.len();
        local_dual
            .items
            .extend(inside.map(|&x| input.local[x as usize]));
        local_dual.offsets.push(local_dual.items.len() as u32);
        inner.push(local_dual.items.len() - before == row.len());
    }
    let local_corners: Vec<[usize; 3]> = tris
        .iter()
        .map(|&t| {
            [0, 1, 2].map(|j| {
                let k = input.canon[3 * t as usize + j];
                (3 * input.local[(k / 3) as usize] + k % 3) as usize
            })
        })
        .collect();
    let cells = tris.iter().map(|&t| input.centres[t as usize]).collect();
    Region::new(local_dual, local_corners, cells, inner, input.limits)
}

/// The seed order: the region's pieces, each in reversed BFS order from its lowest triangle (so
/// seeds come deepest first: a piece's far end, where a grower would strand leftovers). Sets each
/// triangle's piece and seed-order position in `s`; returns the pieces and the free triangles of
/// each.
fn order_pieces(g: &Region, s: &mut State) -> (Pieces, Vec<u32>) {
    let n = g.len();
    let mut order = Vec::with_capacity(n);
    let mut left = Vec::new();
    let mut closed: Vec<bool> = Vec::new();
    let mut starts: Vec<usize> = Vec::new();
    for root in 0..n {
        if s.piece[root] != NONE {
            continue;
        }
        let (p, start) = (left.len() as u32, order.len());
        s.piece[root] = p;
        order.push(root);
        let mut head = start;
        let mut whole = true;
        while head < order.len() {
            let u = order[head];
            head += 1;
            whole &= g.inner[u];
            for j in g.nbrs(u) {
                if s.piece[j] == NONE {
                    s.piece[j] = p;
                    order.push(j);
                }
            }
        }
        left.push((order.len() - start) as u32);
        starts.push(start);
        closed.push(whole);
        order[start..].reverse();
    }
    for (o, &i) in order.iter().enumerate() {
        s.opos[i] = o as u32;
    }
    let pieces = Pieces {
        order,
        starts,
        closed,
    };
    (pieces, left)
}
