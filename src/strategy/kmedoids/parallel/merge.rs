//! Step 2b of `kmedoids-parallel`'s growth: clusters merged into a neighbour whose union fits
//! (what tube ends and enclosed leftovers need). The `grow` kernel's merge section mirrors it.

use super::region::{Clusters, Region, State};

/// Step 2b for one region: clusters merged into a neighbour across an edge whose union fits,
/// smallest first (ties to the lower id; among neighbours, the one sharing most vertices, then
/// the lower id).
pub(super) fn merge_neighbours(g: &Region, s: &mut State, k: u32) -> Clusters {
    let (k, n, mv, mt) = (k as usize, g.len(), g.mv, g.mt);
    let mut cl = Clusters {
        mem: vec![Vec::new(); k],
        nverts: Vec::new(),
        alive: vec![true; k],
    };
    for i in 0..n {
        cl.mem[s.label[i] as usize].push(i);
    }
    cl.nverts = (0..k).map(|c| cl.vertices(g, s, &[c], &[])).collect();
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by_key(|&c| (cl.mem[c].len(), c));
    let mut cstamp = vec![usize::MAX; k];
    for a in order {
        if !cl.alive[a] || cl.mem[a].len() >= mt || cl.nverts[a] >= mv {
            continue;
        }
        let mut best: Option<(usize, usize, usize)> = None;
        for idx in 0..cl.mem[a].len() {
            let i = cl.mem[a][idx];
            for j in g.nbrs(i) {
                let b = s.label[j] as usize;
                if b == a || cstamp[b] == a {
                    continue;
                }
                cstamp[b] = a;
                if cl.mem[a].len() + cl.mem[b].len() > mt {
                    continue;
                }
                let union = cl.vertices(g, s, &[a, b], &[]);
                if union > mv {
                    continue;
                }
                let shared = cl.nverts[a] + cl.nverts[b] - union;
                if best.is_none_or(|(sh, c, _)| {
                    (shared, std::cmp::Reverse(b)) > (sh, std::cmp::Reverse(c))
                }) {
                    best = Some((shared, b, union));
                }
            }
        }
        let Some((_, b, union)) = best else { continue };
        let (keep, gone) = (a.min(b), a.max(b));
        let moved = std::mem::take(&mut cl.mem[gone]);
        for &i in &moved {
            s.label[i] = keep as u32;
        }
        cl.mem[keep].extend(moved);
        cl.nverts[keep] = union;
        cl.alive[gone] = false;
    }
    cl
}
