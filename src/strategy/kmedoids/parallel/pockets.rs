//! The pocket rules of `kmedoids-parallel`'s growth, as a cluster stops: small free pockets
//! next to it are absorbed for its last-grown triangles (`absorb_pockets`), or for triangles
//! given back at its open side (`shed_front`). The `grow` kernel's pocket section mirrors them.

use super::layout::{ATTEMPT, BIG, TRYING};
use super::region::{Region, State};
use super::NONE;

/// The pocket rule for cluster `c` as it stops (see the module doc), keeping `left` (free
/// triangles per piece) up to date; returns the earliest seed-order position of a triangle it
/// freed (`usize::MAX` if none), or `None` when it changed nothing. `vcount[p]` is the cluster's
/// vertex count after `grown[p]`.
pub(super) fn absorb_pockets(
    g: &Region,
    s: &mut State,
    grown: &mut Vec<usize>,
    vcount: &[u32],
    left: &mut [u32],
    c: u32,
) -> Option<usize> {
    let (mv, mt) = (g.mv, g.mt);
    let cap = mt / 2;
    let stamp = c + 1;
    // Pockets: triangles in `q`, each (start, size); larger free components are dropped.
    let mut q: Vec<usize> = Vec::new();
    let mut pockets: Vec<(usize, usize)> = Vec::new();
    for &x in grown.iter() {
        for f in g.nbrs(x) {
            if s.label[f] != NONE || s.aux[f] == stamp || s.aux[f] == stamp | BIG {
                continue;
            }
            let start = q.len();
            s.aux[f] = stamp;
            q.push(f);
            let mut head = start;
            let mut big = false;
            // A free component stops being explored once it is known to be too large: more
            // than `cap` triangles, or one an earlier search from this cluster found large.
            while head < q.len() && !big {
                let u = q[head];
                head += 1;
                for j in g.nbrs(u) {
                    if s.label[j] != NONE {
                        continue;
                    }
                    if s.aux[j] == stamp | BIG {
                        big = true;
                    } else if s.aux[j] != stamp {
                        s.aux[j] = stamp;
                        q.push(j);
                    }
                }
                big |= q.len() - start > cap;
            }
            if big {
                for &i in &q[start..] {
                    s.aux[i] = stamp | BIG;
                }
                q.truncate(start);
            } else {
                pockets.push((start, q.len() - start));
            }
        }
    }
    if pockets.is_empty() {
        return None;
    }
    let len = grown.len();
    // Earliest grown position next to pocket `p`.
    let touch = |s: &State, (start, size): (usize, usize)| {
        q[start..start + size]
            .iter()
            .flat_map(|&i| g.nbrs(i))
            .filter(|&j| s.label[j] == c)
            .map(|j| s.aux[j] as usize)
            .min()
            .unwrap_or(usize::MAX)
    };
    let mut taken: Vec<usize> = Vec::new();
    let mut taken_size = 0usize;
    // The latest of the taken pockets' earliest touches: a prefix must reach every pocket.
    let mut taken_touch = 0;
    let mut keep = len;
    let mut hist = vec![0u32; len];
    let mut done = vec![false; pockets.len()];
    for _ in 0..pockets.len() {
        // Largest first, ties in discovery order.
        let p = (0..pockets.len())
            .filter(|&p| !done[p])
            .min_by_key(|&p| (std::cmp::Reverse(pockets[p].1), p))
            .expect("one left");
        done[p] = true;
        let size = taken_size + pockets[p].1;
        let touch = taken_touch.max(touch(s, pockets[p]));
        // Vertices of the taken pockets and this one, by the first grown position using them.
        s.serial += 1;
        let serial = s.serial;
        hist.fill(0);
        let mut outside = 0u32;
        for &x in taken.iter().chain([&p]) {
            let (start, sz) = pockets[x];
            for &i in &q[start..start + sz] {
                for k in g.corners(i) {
                    if s.wmark[k] != serial {
                        s.wmark[k] = serial;
                        if s.mark[k] == c {
                            hist[s.first[k] as usize] += 1;
                        } else {
                            outside += 1;
                        }
                    }
                }
            }
        }
        // The longest prefix of at least half the cluster, still touching the pockets, that
        // fits with them.
        let mut m = len;
        let mut extra = outside;
        while 2 * m >= len && m > touch {
            let verts = vcount[m - 1] + extra;
            if m + size <= mt && verts as usize <= mv {
                taken.push(p);
                (taken_size, taken_touch, keep) = (size, touch, m);
                break;
            }
            m -= 1;
            extra += hist[m];
        }
    }
    let mut earliest = usize::MAX;
    for &i in &grown[keep..] {
        s.label[i] = NONE;
        s.aux[i] = 0;
        left[s.piece[i] as usize] += 1;
        earliest = earliest.min(s.opos[i] as usize);
    }
    grown.truncate(keep);
    for &p in &taken {
        let (start, size) = pockets[p];
        for &i in &q[start..start + size] {
            s.label[i] = c;
            left[s.piece[i] as usize] -= 1;
            grown.push(i);
        }
    }
    // The front rule for each pocket left, in the same order (largest first).
    let mut changed = !taken.is_empty();
    for size in (1..=cap).rev() {
        for &(start, sz) in &pockets {
            let pocket = &q[start..start + sz];
            if sz != size || s.label[pocket[0]] == c {
                continue;
            }
            let Some(shed) = shed_front(g, s, grown, pocket, c) else {
                continue;
            };
            for i in shed {
                left[s.piece[i] as usize] += 1;
                earliest = earliest.min(s.opos[i] as usize);
            }
            for &i in pocket {
                left[s.piece[i] as usize] -= 1;
            }
            changed = true;
        }
    }
    changed.then_some(earliest)
}

/// The front rule for a pocket the last-grown rule could not take (free, stamped `c + 1`): the
/// cluster gives back instead its triangles nearest the open free side (breadth-first inwards from
/// the front), never one next to the pocket, until the pocket fits; kept only when at most half is
/// given back and the cluster with the pocket is one piece (the pocket usually lies by the growth
/// front, where the last-grown rule would have to give back the triangles touching it; tube ends
/// on the neurons). Returns the triangles given back, or `None` with nothing changed. Scratch:
/// `hop` (attempt stamps; hop counts are set again when a triangle next joins a frontier),
/// `first` (per vertex, the kept members using it) and `wmark`.
pub(super) fn shed_front(
    g: &Region,
    s: &mut State,
    grown: &mut Vec<usize>,
    pocket: &[usize],
    c: u32,
) -> Option<Vec<usize>> {
    let (mv, mt) = (g.mv, g.mt);
    let stamp = c + 1;
    for &i in pocket {
        s.aux[i] = stamp | TRYING;
    }
    // Stamps: cluster vertex (`a`), also the pocket's (`a + 1`), the pocket's only (`a + 2`).
    let a = s.serial + 1;
    s.serial += 3;
    let (seen, gone, reached) = (ATTEMPT | a, ATTEMPT | (a + 1), ATTEMPT | (a + 2));
    let mut nv = 0usize;
    for &x in grown.iter() {
        for k in g.corners(x) {
            if s.wmark[k] != a {
                s.wmark[k] = a;
                s.first[k] = 0;
                nv += 1;
            }
            s.first[k] += 1;
        }
    }
    let mut outside = 0usize;
    for &i in pocket {
        for k in g.corners(i) {
            if s.wmark[k] == a {
                s.wmark[k] = a + 1;
            } else if s.wmark[k] != a + 1 && s.wmark[k] != a + 2 {
                s.wmark[k] = a + 2;
                outside += 1;
            }
        }
    }
    let in_pocket = |s: &State, j: usize| s.label[j] == NONE && s.aux[j] == stamp | TRYING;
    let next_to_pocket = |s: &State, i: usize| g.nbrs(i).any(|j| in_pocket(s, j));
    // Free and in no pocket of this cluster: the open side (or given back, or a large component).
    let open =
        |s: &State, j: usize| s.label[j] == NONE && s.aux[j] != stamp && s.aux[j] != stamp | TRYING;
    let mut queue: Vec<usize> = Vec::new();
    for &x in grown.iter() {
        if g.nbrs(x).any(|j| open(s, j)) && !next_to_pocket(s, x) {
            s.hop[x] = seen;
            queue.push(x);
        }
    }
    let len = grown.len();
    let fits = |removed: usize, nv: usize, outside: usize| {
        len - removed + pocket.len() <= mt && nv + outside <= mv
    };
    let mut removed = 0;
    while !fits(removed, nv, outside) && removed < queue.len() && 2 * (removed + 1) <= len {
        let u = queue[removed];
        removed += 1;
        for k in g.corners(u) {
            s.first[k] -= 1;
            if s.first[k] == 0 {
                nv -= 1;
                if s.wmark[k] == a + 1 {
                    outside += 1;
                }
            }
        }
        for j in g.nbrs(u) {
            if s.label[j] == c && s.hop[j] != seen && !next_to_pocket(s, j) {
                s.hop[j] = seen;
                queue.push(j);
            }
        }
    }
    let restore = |s: &mut State| {
        for &i in pocket {
            s.aux[i] = stamp;
        }
    };
    if !fits(removed, nv, outside) {
        restore(s);
        return None;
    }
    queue.truncate(removed);
    for &u in &queue {
        s.hop[u] = gone;
    }
    // One piece: flood the kept members and the pocket from the pocket.
    let mut stack = vec![pocket[0]];
    s.hop[pocket[0]] = reached;
    let mut flooded = 1;
    while let Some(u) = stack.pop() {
        for j in g.nbrs(u) {
            let member = (s.label[j] == c && s.hop[j] != gone) || in_pocket(s, j);
            if member && s.hop[j] != reached {
                s.hop[j] = reached;
                flooded += 1;
                stack.push(j);
            }
        }
    }
    if flooded != len - removed + pocket.len() {
        restore(s);
        return None;
    }
    for &u in &queue {
        s.label[u] = NONE;
        s.aux[u] = 0;
    }
    for &i in pocket {
        s.label[i] = c;
    }
    grown.retain(|&x| s.label[x] == c);
    grown.extend_from_slice(pocket);
    Some(queue)
}
