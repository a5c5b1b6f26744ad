//! Step 2d of `kmedoids-parallel`'s growth: a cluster whose members all find room in the
//! clusters across their edges is spread over them. The `grow` kernel's dissolve section mirrors
//! it.

use super::region::{Clusters, Region, State};

/// Step 2d for one region: a cluster is dissolved into its neighbours when every member finds a
/// neighbouring cluster with room. Clusters go smallest first (ties to the lower id), in their
/// order after step 2c. A queue starts with the cluster's members that have a neighbour in another
/// cluster, ascending; a member taken from it joins, of the clusters across its edges,
/// the one it adds the fewest vertices to (then the lower id) among those it fits, counting the
/// members already moved; a member that moves queues its neighbours still in the cluster. If the
/// queue runs dry with a member left, nothing moves. The moved members join their targets' lists
/// in the dissolved cluster's list order. Each target stays edge-connected (a member joins next
/// to one of the target's).
///
/// Why: the merges move whole clusters, into one neighbour. On branching tubes (the neurons) a
/// cluster between two part-filled ones often fits neither alone but splits across both. On
/// surfaces it rarely acts: their clusters meet the vertex limit, so a triangle bringing a new
/// vertex fits none of them.
pub(super) fn dissolve_clusters(g: &Region, s: &mut State, cl: &mut Clusters) {
    let (mv, mt) = (g.mv, g.mt);
    let k = cl.alive.len();
    let mut order: Vec<usize> = (0..k).filter(|&c| cl.alive[c]).collect();
    order.sort_by_key(|&c| (cl.mem[c].len(), c));
    // Triangles and vertices the current plan adds to each cluster.
    let (mut extra_t, mut extra_v) = (vec![0usize; k], vec![0usize; k]);
    let mut queued = vec![false; s.label.len()];
    let mut queue = std::collections::VecDeque::new();
    for a in order {
        if !cl.alive[a] {
            continue;
        }
        let a32 = a as u32;
        let mut start: Vec<usize> = cl.mem[a]
            .iter()
            .copied()
            .filter(|&x| g.nbrs(x).any(|y| s.label[y] != a32))
            .collect();
        start.sort_unstable();
        for x in start {
            queued[x] = true;
            queue.push_back(x);
        }
        let mut moved = 0;
        while let Some(x) = queue.pop_front() {
            queued[x] = false;
            let mut best: Option<(usize, u32)> = None;
            for y in g.nbrs(x) {
                let b = s.label[y];
                if b == a32 || cl.mem[b as usize].len() + extra_t[b as usize] + 1 > mt {
                    continue;
                }
                // Distinct corners whose vertex no member of b (moved ones included) uses.
                let k3 = g.corners(x);
                let added = (0..3)
                    .filter(|&j| {
                        !k3[..j].contains(&k3[j]) && !g.users(k3[j]).any(|u| s.label[u] == b)
                    })
                    .count();
                if cl.nverts[b as usize] + extra_v[b as usize] + added > mv {
                    continue;
                }
                if best.is_none_or(|key| (added, b) < key) {
                    best = Some((added, b));
                }
            }
            let Some((added, b)) = best else { continue };
            s.label[x] = b;
            extra_t[b as usize] += 1;
            extra_v[b as usize] += added;
            moved += 1;
            for y in g.nbrs(x) {
                if s.label[y] == a32 && !queued[y] {
                    queued[y] = true;
                    queue.push_back(y);
                }
            }
        }
        let members = std::mem::take(&mut cl.mem[a]);
        let done = moved == members.len();
        for &x in &members {
            let b = s.label[x] as usize;
            if b == a {
                continue;
            }
            if done {
                cl.mem[b].push(x);
                // Added once: extra_v[b] is zeroed below after b's first member.
                cl.nverts[b] += extra_v[b];
            } else {
                s.label[x] = a32;
            }
            extra_t[b] = 0;
            extra_v[b] = 0;
        }
        if done {
            cl.alive[a] = false;
        } else {
            cl.mem[a] = members;
        }
    }
}
