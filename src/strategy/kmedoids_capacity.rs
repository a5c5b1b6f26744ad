//! Capacity-aware k-medoids (the default `kmedoids`): clusters are grown to the limits instead of
//! being split until they fit.
//!
//! The flat method ([`super::kmedoids`], `kmedoids-flat`) assigns every triangle to its nearest
//! medoid with no regard to the limits, then splits overflowing clusters and re-runs the whole
//! mesh; Voronoi cells split until they fit come out part-filled (0.49-0.83 vertex fill, 1.25-2x
//! meshoptimizer's count) and two thirds of the iterations are global re-runs
//! (../shared/notes/kmedoids-scale.md). Here the limits are part of the assignment:
//!
//! 1. [`seed_clusters`]: one cluster at a time grows from a seed while both limits hold, taking
//!    the frontier triangle that adds the fewest vertices, then the most enclosed one, then
//!    ([`Grow`]) the one nearest the cluster's running centroid, or the one fewest hops from the
//!    seed. The next seed is the deepest free triangle (hop distance from its piece's root,
//!    `seed_order`), so in the first growth the free triangles stay one shrinking ball and the
//!    neurons' branches are clustered from their tips inwards. Step 1b (`Orphans`): a cluster
//!    that stops takes the small enclosed free regions next to it, giving back triangles at its
//!    growth front to make room.
//! 2. [`medoids_and_distances`]: the paper's medoid of each cluster (smallest sum of in-cluster
//!    hop distances, ties to the lowest id), all members' sums at once by bitset reachability,
//!    and every member's distance to it from the same local graph.
//! 3. [`assign_capacity`]: a level-synchronous multi-source BFS from all medoids at once in which
//!    a triangle joins the nearest medoid *whose cluster still has room* (ties to the lower
//!    cluster). Triangles no cluster has room for are grown into new clusters as in step 1.
//! 4. `merge_neighbours` (shared with `kmedoids-local`): neighbouring clusters whose union fits
//!    are merged, smallest first; then clusters that share no vertex with any other (whole small
//!    pieces of the mesh) join the nearest cluster whose union fits.
//! 5. Steps 2-4 repeat while the cluster count does not grow and the objective (mean hop distance
//!    to the medoid) falls; the best clustering seen is kept. They run only where at least a
//!    third of the clusters are light (`worth_a_round`): on surfaces the first round adds
//!    clusters (regions grown all at once leave gaps no cluster has room for) and was always
//!    rejected, at a third of the run time; with step 1b and the deepest-first seeds no shared
//!    mesh opens the gate (the neurons at 64/126, 64/84 and 128/128 included).
//!
//! Where it differs from the paper (§3): the paper's k is fixed by ceil(T / max_triangles) and
//! grows by one per overflow with a global re-run each; here k comes out of the capacity-bounded
//! growth, no cluster ever overflows, and nothing is split. The medoid is the paper's. Every
//! cluster is edge-connected (it grows across edges) and the merge keeps it so wherever the mesh
//! is. Determinism: the growth and the merge are sequential in a fixed order; the medoid update is a
//! parallel map. The same input gives the same output for any thread count.
//!
//! On the GPU (`gpu::kmedoids::cluster_capacity`) the adjacency, the medoid updates (step 2,
//! parallel per cluster) and the capacity-aware assignment (step 3: every cluster walks a level at
//! once, repeated to the fixed point that equals the sequential order, `wgsl/capacity.wgsl`; only
//! in the rounds step 5 runs) run as kernels and the rest on the host between them, through
//! [`cluster_with`]; the output is identical.

#[cfg(test)]
use super::kmedoids::UNREACHED;
use super::kmedoids::{members, LocalGraph};
use super::kmedoids_local::{
    member_distances, merge_neighbours, refresh_distances, renumber, Pieces,
};
use crate::adjacency::Csr;
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Free triangle (not yet in a cluster).
const FREE: u32 = u32::MAX;

/// What a capacity-aware run produced.
pub struct Grown {
    /// Medoid of each cluster, ascending.
    pub medoids: Vec<u32>,
    /// Cluster of each triangle.
    pub labels: Vec<u32>,
    /// Hop distance of each triangle to its medoid inside its cluster.
    pub distances: Vec<u32>,
    /// Re-assignment rounds tried (capacity-aware assignments run; 0 where `worth_a_round` found
    /// too few light clusters for a round to pay).
    pub iterations: u32,
}

/// Runs steps 1-5 with at most `max_iterations` update/assign rounds (none where
/// `worth_a_round` says they cannot pay).
pub fn cluster(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
    limits: Limits,
    grow: Grow,
    max_iterations: u32,
) -> Grown {
    cluster_with(
        mesh,
        dual,
        vt,
        limits,
        grow,
        max_iterations,
        &mut |labels, medoids| medoids_and_distances(dual, labels, medoids.len()),
        &mut |medoids, labels| assign_capacity(mesh, dual, limits, medoids, labels),
    )
}

/// The paper's medoid of every cluster: `(labels, any member of each cluster) -> (medoids, each
/// triangle's hop distance to its new medoid if computed)`, same cluster order.
/// [`medoids_and_distances`] on the CPU; the GPU's `update` kernel in
/// `gpu::kmedoids::cluster_capacity` (no distances: the host finds them). Both are exact, so the
/// results are identical.
pub type MedoidUpdate<'a> = dyn FnMut(&[u32], &[u32]) -> (Vec<u32>, Option<Vec<u32>>) + 'a;

/// Step 2 on the CPU: each of the `k` clusters' paper medoid (as [`super::kmedoids::update`]
/// finds it) and every member's distance to it, from one local graph per cluster (a separate
/// update and distance pass built each twice).
pub fn medoids_and_distances(dual: &Csr, labels: &[u32], k: usize) -> (Vec<u32>, Option<Vec<u32>>) {
    let mem = members(labels, k);
    let rows: Vec<(u32, Vec<u32>)> = (0..k)
        .into_par_iter()
        .map(|c| {
            let m = mem.row(c);
            let sub = LocalGraph::new(dual, labels, c as u32, m);
            let best = sub.medoid_index();
            (m[best], member_distances(&sub, best))
        })
        .collect();
    let mut distances = vec![0; labels.len()];
    for (c, (_, d)) in rows.iter().enumerate() {
        for (&t, &x) in mem.row(c).iter().zip(d) {
            distances[t as usize] = x;
        }
    }
    (rows.into_iter().map(|r| r.0).collect(), Some(distances))
}

/// Step 3, the capacity-aware assignment: `(medoids, labels all FREE) -> labels`.
/// [`assign_capacity`] on the CPU; `gpu::capacity::CapacityAssign` on the GPU, with identical
/// labels.
pub type Assign<'a> = dyn FnMut(&[u32], &mut [u32]) + 'a;

/// [`cluster`] with the medoid update (step 2) and the capacity-aware assignment (step 3)
/// supplied: the steps that run on the GPU there.
#[allow(clippy::too_many_arguments)]
pub fn cluster_with(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
    limits: Limits,
    grow: Grow,
    max_iterations: u32,
    medoids_of: &mut MedoidUpdate<'_>,
    assign: &mut Assign<'_>,
) -> Grown {
    let order = seed_order(dual);
    let pieces = Pieces::new(dual, vt);
    // Steps 1 and 4 over the free triangles of `labels`, clusters numbered on from `medoids`.
    let grow_and_merge = |labels: &mut Vec<u32>, medoids: &mut Vec<u32>| {
        seed_clusters(mesh, dual, limits, grow, &order, labels, medoids);
        merge_neighbours(mesh, dual, vt, &pieces, limits, medoids, labels);
        pack_pieces(mesh, vt, limits, medoids, labels);
    };
    let mut labels = vec![FREE; mesh.triangle_count()];
    let mut medoids = Vec::new();
    grow_and_merge(&mut labels, &mut medoids);
    let mut best = finish(dual, medoids, labels, medoids_of);
    let mut iterations = 0;
    let rounds = if worth_a_round(&best.1, best.0.len(), limits) {
        max_iterations
    } else {
        0
    };
    for _ in 0..rounds {
        iterations += 1;
        // `best`'s medoids are already the paper's medoids of its clusters (step 2 is `finish`).
        let mut labels = vec![FREE; mesh.triangle_count()];
        let mut medoids = best.0.clone();
        assign(&medoids, &mut labels);
        // Triangles no cluster had room for start new clusters, grown as in the seeding.
        grow_and_merge(&mut labels, &mut medoids);
        if medoids.len() > best.0.len() {
            // More clusters: rejected before the exact medoids are paid for.
            break;
        }
        let next = finish(dual, medoids, labels, medoids_of);
        let better = (next.0.len(), objective(&next.2)) < (best.0.len(), objective(&best.2));
        if !better {
            break;
        }
        best = next;
    }
    let (medoids, labels, distances) = best;
    Grown {
        medoids,
        labels,
        distances,
        iterations,
    }
}

/// Whether steps 2-4 may pay for themselves: at least a third of the `k` clusters are light
/// (at most half the triangle limit). Light clusters are what a re-assignment can absorb; where
/// fewer are light, growing all clusters at once from their medoids leaves more gaps than it
/// closes. Measured (64/126, 64/84, 128/128; ten shared and six generated meshes) before step 1b:
/// rounds were accepted only on the neurons (40-55 % light, 3-4 rounds, a fifth fewer clusters);
/// every other mesh (at most 29 % light) rejected the first round, which cost a third of the run
/// (the 14 M-triangle dragon: 6.8 s of 23 s). Step 1b leaves fewer light clusters: with the
/// corner-first seeds the gate then opened with centre growth only on neuron 722817260 at 128/128
/// (5 rounds), and rounds forced on at 64/126 and 64/84 were all rejected; with the deepest-first
/// seeds ([`seed_order`]) it opens on neither neuron at 64/126, 64/84 or 128/128.
fn worth_a_round(labels: &[u32], k: usize, limits: Limits) -> bool {
    let mut tris = vec![0u32; k];
    for &l in labels {
        tris[l as usize] += 1;
    }
    let light = tris
        .iter()
        .filter(|&&n| 2 * n <= limits.max_triangles)
        .count();
    3 * light >= k
}

/// Sum of hop distances to the medoids (the objective, unnormalised so it compares exactly).
fn objective(distances: &[u32]) -> u64 {
    distances.iter().map(|&d| d as u64).sum()
}

/// Step 4b: a cluster that shares no vertex with any other holds whole mesh pieces (a piece
/// smaller than a meshlet: the neurons' 63 four-triangle markers), which [`merge_neighbours`]
/// cannot see. Smallest first (then the lower id), each joins the cluster with the nearest
/// centroid among those near it in Morton order whose union fits. The union is edge-connected
/// wherever the mesh is: its pieces are the two clusters' pieces. Sequential, so deterministic.
fn pack_pieces(mesh: &Mesh, vt: &Csr, limits: Limits, medoids: &mut Vec<u32>, labels: &mut [u32]) {
    // How far along the Morton order a cluster looks for a partner (either side).
    const WINDOW: usize = 32;
    let k = medoids.len();
    let mut isolated = vec![true; k];
    for v in 0..vt.rows() {
        let row = vt.row(v);
        if let Some(&first) = row.first() {
            let l = labels[first as usize];
            if row.iter().any(|&t| labels[t as usize] != l) {
                for &t in row {
                    isolated[labels[t as usize] as usize] = false;
                }
            }
        }
    }
    if !isolated.contains(&true) {
        return;
    }
    let mem = members(labels, k);
    let mut tris: Vec<usize> = (0..k).map(|c| mem.row(c).len()).collect();
    // Distinct vertices, counted only for the clusters a test reads (few: most partners fail the
    // triangle test), `usize::MAX` until then.
    let mut verts = vec![usize::MAX; k];
    let count_verts = |verts: &mut [usize], c: usize| {
        if verts[c] == usize::MAX {
            let mut v: Vec<u32> = mem
                .row(c)
                .iter()
                .flat_map(|&t| mesh.triangle(t as usize))
                .collect();
            v.sort_unstable();
            v.dedup();
            verts[c] = v.len();
        }
    };
    let mut centre: Vec<glam::Vec3> = (0..k)
        .into_par_iter()
        .map(|c| {
            mem.row(c)
                .iter()
                .map(|&t| centroid(mesh, t))
                .sum::<glam::Vec3>()
                / mem.row(c).len() as f32
        })
        .collect();
    let (lo, hi) = mesh.bounding_box();
    let scale = (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let mut by_code: Vec<(u64, u32)> = (0..k as u32)
        .map(|c| {
            let q = ((centre[c as usize] - lo) / scale * 1023.0)
                .clamp(glam::Vec3::ZERO, glam::Vec3::splat(1023.0));
            (
                super::kmedoids::morton3(q.x as u32, q.y as u32, q.z as u32),
                c,
            )
        })
        .collect();
    by_code.sort_unstable();
    let mut at = vec![0usize; k];
    for (i, &(_, c)) in by_code.iter().enumerate() {
        at[c as usize] = i;
    }
    let mut into: Vec<u32> = (0..k as u32).collect();
    let mut order: Vec<u32> = (0..k as u32).filter(|&c| isolated[c as usize]).collect();
    order.sort_unstable_by_key(|&c| (tris[c as usize], c));
    for a in order {
        let ai = a as usize;
        let lo_i = at[ai].saturating_sub(WINDOW);
        let hi_i = (at[ai] + WINDOW + 1).min(k);
        count_verts(&mut verts, ai);
        // The nearest centroid (then the lower id) among partners whose union fits; vertices are
        // counted only for those that pass the triangle test.
        let mut best: Option<(f32, u32)> = None;
        for &(_, b) in &by_code[lo_i..hi_i] {
            let bi = b as usize;
            if b == a || into[bi] != b || tris[ai] + tris[bi] > limits.max_triangles as usize {
                continue;
            }
            count_verts(&mut verts, bi);
            if verts[ai] + verts[bi] > limits.max_vertices as usize {
                continue;
            }
            let d = (centre[bi] - centre[ai]).length_squared();
            if best.is_none_or(|(bd, bb)| d.total_cmp(&bd).then(b.cmp(&bb)).is_lt()) {
                best = Some((d, b));
            }
        }
        let best = best.map(|(_, b)| b);
        if let Some(b) = best {
            let bi = b as usize;
            into[ai] = b;
            centre[bi] = (centre[bi] * tris[bi] as f32 + centre[ai] * tris[ai] as f32)
                / (tris[ai] + tris[bi]) as f32;
            tris[bi] += tris[ai];
            verts[bi] += verts[ai];
        }
    }
    // `into` is one step deep: an isolated cluster that took others joins nobody afterwards only
    // if it was processed first; follow the chain to be safe.
    let find = |mut c: u32| {
        while into[c as usize] != c {
            c = into[c as usize];
        }
        c
    };
    let survivors: Vec<u32> = (0..k as u32).filter(|&c| into[c as usize] == c).collect();
    if survivors.len() == k {
        return;
    }
    let mut new_id = vec![u32::MAX; k];
    for (i, &c) in survivors.iter().enumerate() {
        new_id[c as usize] = i as u32;
    }
    for l in labels.iter_mut() {
        *l = new_id[find(*l) as usize];
    }
    *medoids = survivors.iter().map(|&c| medoids[c as usize]).collect();
}

/// Medoids made exact (the paper's, in their final clusters), clusters numbered by ascending
/// medoid, and in-cluster distances.
fn finish(
    dual: &Csr,
    medoids: Vec<u32>,
    mut labels: Vec<u32>,
    medoids_of: &mut MedoidUpdate<'_>,
) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let (mut medoids, distances) = medoids_of(&labels, &medoids);
    // Renumbering changes cluster ids, not a triangle's distance to its medoid.
    renumber(&mut medoids, &mut labels);
    let distances = distances.unwrap_or_else(|| {
        let mut d = vec![0; labels.len()];
        refresh_distances(dual, &medoids, &labels, &mut d);
        d
    });
    (medoids, labels, distances)
}

/// The seed order: in each edge-connected piece (pieces by their lowest triangle id), the
/// breadth-first order from that triangle, reversed, so the deepest free triangle seeds next.
/// Within a depth the order follows the neighbour order of `dual`'s rows, which the GPU's dual
/// graph reproduces exactly, so both paths seed alike.
///
/// Why deepest first: in the first growth the free triangles then stay a ball around the piece's
/// root that shrinks from its far side, so a cluster grown from the deepest free triangle rarely
/// cuts a free region off from the rest (an orphan a later seed would turn into a small
/// cluster). On a tree of tubes (the neurons) the clusters start at the branch tips and meet
/// towards the root, as in the bottom-up partition of a tree (Kundu and Misra, SIAM J. Comput.
/// 6(1), 1977), where the tip remainders a sweep leaves behind are what the count loses. Measured
/// (mean count over meshoptimizer's, ten shared and six generated meshes, 64/126, 64/84,
/// 128/128): 1.074, 1.097, 1.102 with the seed order before it (the free frontier triangle with
/// the most taken neighbours, else the next free one in Morton order); 1.045, 1.050, 1.051 with
/// it. The dragon's run takes about 15 % longer (the breadth-first pass, and clusters grown
/// further apart in memory).
fn seed_order(dual: &Csr) -> Vec<u32> {
    let n = dual.rows();
    let mut seen = vec![false; n];
    let mut order: Vec<u32> = Vec::with_capacity(n);
    for root in 0..n {
        if seen[root] {
            continue;
        }
        seen[root] = true;
        let start = order.len();
        order.push(root as u32);
        let mut i = start;
        while i < order.len() {
            let u = order[i] as usize;
            i += 1;
            for &v in dual.row(u) {
                if !seen[v as usize] {
                    seen[v as usize] = true;
                    order.push(v);
                }
            }
        }
        order[start..].reverse();
    }
    order
}

/// Step 1: grows new clusters over the free triangles of `labels`, one at a time, each to the
/// limits, each taking the orphans it leaves (step 1b), each from the first free triangle of
/// `order` (`seed_order`); appends each cluster's seed to `seeds` (cluster ids continue from
/// `seeds.len()`).
pub fn seed_clusters(
    mesh: &Mesh,
    dual: &Csr,
    limits: Limits,
    grow: Grow,
    order: &[u32],
    labels: &mut [u32],
    seeds: &mut Vec<u32>,
) {
    let (max_v, max_t) = (limits.max_vertices as usize, limits.max_triangles as usize);
    // Keys read a triangle's centroid every time they are (re)computed: compute each once.
    let centroids: Vec<glam::Vec3> = (0..labels.len() as u32)
        .map(|t| centroid(mesh, t))
        .collect();
    // Stamps: the cluster that last marked a vertex / queued a triangle (no clearing per cluster).
    let mut vmark = vec![FREE; mesh.vertex_count()];
    let mut queued = vec![FREE; labels.len()];
    let mut level = vec![0u32; labels.len()];
    let mut heap: BinaryHeap<Reverse<Key>> = BinaryHeap::new();
    let mut rejected = Vec::new();
    let mut orphans = Orphans::new(mesh.vertex_count(), labels.len());
    let mut grown: Vec<u32> = Vec::new();
    let mut frontier: Vec<u32> = Vec::new();
    // Every triangle before `cursor` is taken: a cluster takes free triangles (at or after the
    // cursor) and gives back only its own, so one pass over `order` finds every seed.
    let mut cursor = 0;
    loop {
        while cursor < order.len() && labels[order[cursor] as usize] != FREE {
            cursor += 1;
        }
        let Some(&seed) = order.get(cursor) else {
            break;
        };
        let c = seeds.len() as u32;
        seeds.push(seed);
        let (mut nv, mut nt) = (0usize, 0usize);
        heap.clear();
        rejected.clear();
        grown.clear();
        queued[seed as usize] = c;
        level[seed as usize] = 0;
        let mut sum = glam::Vec3::ZERO;
        let centre = centroids[seed as usize];
        let key =
            |t: u32, vmark: &[u32], labels: &[u32], level: &[u32], centre: glam::Vec3| -> Key {
                (
                    mesh.triangle(t as usize)
                        .iter()
                        .filter(|&&v| vmark[v as usize] != c)
                        .count() as u8,
                    dual.row(t as usize)
                        .iter()
                        .filter(|&&n| labels[n as usize] == FREE)
                        .count() as u8,
                    match grow {
                        Grow::Centre => 0,
                        Grow::Hops => level[t as usize],
                    },
                    // Non-negative floats order as their bits.
                    (centroids[t as usize] - centre).length_squared().to_bits(),
                    t,
                )
            };
        heap.push(Reverse(key(seed, &vmark, labels, &level, centre)));
        while nt < max_t {
            let Some(Reverse(k)) = heap.pop() else { break };
            let t = k.4;
            if labels[t as usize] != FREE {
                continue;
            }
            // Keys only fall (vertices get marked, neighbours taken): a stale entry goes back
            // with its current key.
            let now = key(
                t,
                &vmark,
                labels,
                &level,
                if nt == 0 { centre } else { sum / nt as f32 },
            );
            if now != k {
                heap.push(Reverse(now));
                continue;
            }
            let new = k.0 as usize;
            if nv + new > max_v {
                rejected.push(t);
                if nv == max_v {
                    // Vertex-full and the cheapest candidate adds a vertex: nothing else fits.
                    break;
                }
                continue;
            }
            labels[t as usize] = c;
            grown.push(t);
            nt += 1;
            sum += centroids[t as usize];
            for v in mesh.triangle(t as usize) {
                if vmark[v as usize] != c {
                    vmark[v as usize] = c;
                    nv += 1;
                }
            }
            for &n in dual.row(t as usize) {
                if labels[n as usize] != FREE {
                    continue;
                }
                if queued[n as usize] != c {
                    queued[n as usize] = c;
                    level[n as usize] = level[t as usize] + 1;
                }
                heap.push(Reverse(key(n, &vmark, labels, &level, sum / nt as f32)));
            }
        }
        // Step 1b: the orphans this cluster leaves behind join it.
        frontier.clear();
        frontier.extend(rejected.iter().copied().chain(heap.iter().map(|r| r.0 .4)));
        orphans.absorb(mesh, dual, limits, c, &frontier, &mut grown, labels);
        // The front rule may give the seed back; the medoid steps need a member of each cluster.
        seeds[c as usize] = grown[0];
    }
}

/// Step 1b: the free regions a finished cluster encloses, and their absorption.
///
/// A cluster that fills up while growing past a branch of a thin tube (or around a bump of a
/// surface) leaves the rest of that branch free and reachable only through itself; grown later,
/// such an orphan is a cluster of a few triangles that no neighbour has room to take (on the
/// neurons most light clusters had exactly one neighbour, a full one). So when a cluster stops,
/// every free region next to it of at most half the triangle limit is an orphan, and the cluster
/// takes the orphans, largest first, giving back triangles to make room:
/// - first its last-grown ones ([`Orphans::prefix`]): any prefix of the growth order is
///   edge-connected (each triangle joined next to an earlier one), and an orphan is a whole free
///   region touching the kept prefix, so the cluster stays one piece;
/// - for an orphan that touches only the last-grown triangles (the usual case on the neurons:
///   the orphan lies by the growth front), those nearest the open free region instead, never one
///   next to the orphan ([`Orphans::front_shed`]), kept only when the result is one piece.
///
/// The given-back triangles are free again (later seeds reach them); each rule gives back at most
/// half of the cluster as it stands when the rule runs. Measured with the seed order before
/// [`seed_order`] (corners first) on the ten shared and six generated meshes, mean count over
/// meshoptimizer's at 64/126, 64/84 and 128/128: 1.135, 1.141, 1.166 without step 1b; 1.090,
/// 1.115, 1.113 with the last-grown rule alone; 1.074, 1.097, 1.102 with the front rule after it
/// (the front rule alone: 1.101, 1.093, 1.099). Spheres grow a few percent, still under
/// meshoptimizer's. Absorbing only what fits without giving back changed
/// nothing; giving back at most a quarter, or no more than the orphans hold, gained less than
/// half; re-growing the cluster with the orphans preferred was no better on average.
struct Orphans {
    /// Per triangle: 1 + the cluster whose check visited it last (0: none; zeroed pages are free).
    stamp: Vec<u32>,
    /// Per triangle visited by the current cluster's check: its region's index, or [`OPEN`].
    region: Vec<u32>,
    /// Per vertex: triangles of the cluster being cut back that use it (valid where `vstamp` is
    /// the current attempt).
    vcount: Vec<u32>,
    vstamp: Vec<u32>,
    /// Per vertex: the last attempt whose orphans use it.
    ostamp: Vec<u32>,
    /// Counter behind the per-attempt stamps (`vstamp`, `ostamp`, `tseen`): never reset, so
    /// no clearing between attempts.
    attempt: u32,
    /// Breadth-first queue of the region search.
    queue: Vec<u32>,
    /// Per triangle, in [`Orphans::front_shed`]: queued, given back or flooded (one stamp each).
    tseen: Vec<u32>,
}

/// [`Orphans::region`] of a free triangle whose region is larger than an orphan.
const OPEN: u32 = u32::MAX;

impl Orphans {
    fn new(vertices: usize, triangles: usize) -> Self {
        Self {
            stamp: vec![0; triangles],
            // Read only where `stamp` says this check wrote it.
            region: vec![0; triangles],
            vcount: vec![0; vertices],
            vstamp: vec![0; vertices],
            ostamp: vec![0; vertices],
            attempt: 0,
            queue: Vec::new(),
            tseen: vec![0; triangles],
        }
    }

    /// Starts an attempt: distinct vertices of the orphans `take`, of the cluster `grown`, and of
    /// both; `vcount` then holds each vertex's uses in `grown`. Returns (attempt stamp, orphan
    /// vertices, cluster vertices, shared vertices).
    fn count_vertices(
        &mut self,
        mesh: &Mesh,
        grown: &[u32],
        take: &[u32],
    ) -> (u32, usize, usize, usize) {
        self.attempt += 1;
        let a = self.attempt;
        let mut orphan_v = 0usize;
        for &t in take {
            for v in mesh.triangle(t as usize) {
                if self.ostamp[v as usize] != a {
                    self.ostamp[v as usize] = a;
                    orphan_v += 1;
                }
            }
        }
        let (mut nv, mut shared) = (0usize, 0usize);
        for &t in grown {
            for v in mesh.triangle(t as usize) {
                let vi = v as usize;
                if self.vstamp[vi] != a {
                    self.vstamp[vi] = a;
                    self.vcount[vi] = 0;
                    nv += 1;
                    shared += usize::from(self.ostamp[vi] == a);
                }
                self.vcount[vi] += 1;
            }
        }
        (a, orphan_v, nv, shared)
    }

    /// Takes triangle `u` out of the counts of attempt `a` (from [`Orphans::count_vertices`]):
    /// a vertex no kept triangle uses any more leaves `nv`, and `shared` if the orphans use it.
    fn release(&mut self, mesh: &Mesh, a: u32, u: u32, nv: &mut usize, shared: &mut usize) {
        for v in mesh.triangle(u as usize) {
            let vi = v as usize;
            self.vcount[vi] -= 1;
            if self.vcount[vi] == 0 {
                *nv -= 1;
                *shared -= usize::from(self.ostamp[vi] == a);
            }
        }
    }

    /// Finds the orphans among the free regions of `frontier` (cluster `c`'s free neighbours)
    /// and absorbs those that fit, largest first (then by the triangle the search started from),
    /// by the last-grown rule, then each one left by the front rule; `grown` is the cluster in
    /// growth order, updated. Returns the triangles given back (the seed order reaches them
    /// anyway; the tests check them).
    #[allow(clippy::too_many_arguments)]
    fn absorb(
        &mut self,
        mesh: &Mesh,
        dual: &Csr,
        limits: Limits,
        c: u32,
        frontier: &[u32],
        grown: &mut Vec<u32>,
        labels: &mut [u32],
    ) -> Vec<u32> {
        let regions = self.regions(dual, limits.max_triangles as usize / 2, c, frontier, labels);
        if regions.is_empty() {
            return Vec::new();
        }
        let mut take: Vec<u32> = Vec::new();
        let mut keep = grown.len();
        let mut failed: Vec<&Vec<u32>> = Vec::new();
        for r in &regions {
            let with: Vec<u32> = take.iter().chain(r).copied().collect();
            // Giving back more than half was measured to cost more than it saves.
            match self.prefix(mesh, dual, limits, c, grown, &with, labels) {
                Some(n) if 2 * n >= grown.len() => {
                    take = with;
                    keep = n;
                }
                _ => failed.push(r),
            }
        }
        let mut shed = grown.split_off(keep);
        for &t in &shed {
            labels[t as usize] = FREE;
        }
        for &t in &take {
            labels[t as usize] = c;
        }
        grown.extend(take);
        for r in failed {
            if let Some(more) = self.front_shed(mesh, dual, limits, c, grown, r, labels) {
                shed.extend(more);
            }
        }
        shed
    }

    /// An orphan `r` that no prefix of `grown` can take: the cluster gives back instead the
    /// triangles nearest the open free region (breadth-first inwards from the front), never one
    /// next to `r`, until `r` fits; kept only when at most half is given back and the cluster with
    /// `r` is one edge-connected piece. Returns the triangles given back.
    #[allow(clippy::too_many_arguments)]
    fn front_shed(
        &mut self,
        mesh: &Mesh,
        dual: &Csr,
        limits: Limits,
        c: u32,
        grown: &mut Vec<u32>,
        r: &[u32],
        labels: &mut [u32],
    ) -> Option<Vec<u32>> {
        let check = c + 1;
        let rid = self.region[r[0] as usize];
        let in_r = |stamp: &[u32], region: &[u32], t: u32| {
            labels[t as usize] == FREE && stamp[t as usize] == check && region[t as usize] == rid
        };
        let next_to_r = |stamp: &[u32], region: &[u32], t: u32| {
            dual.row(t as usize).iter().any(|&n| in_r(stamp, region, n))
        };
        // Free and not in a closed region of this check: the open region (or given back).
        let open_free = |stamp: &[u32], region: &[u32], t: u32| {
            labels[t as usize] == FREE && (stamp[t as usize] != check || region[t as usize] == OPEN)
        };
        let (a, orphan_v, mut nv, mut shared) = self.count_vertices(mesh, grown, r);
        let (max_v, max_t) = (limits.max_vertices as usize, limits.max_triangles as usize);
        // Breadth-first from the cluster's triangles on the open front; `tseen` marks visited.
        let mut queue: Vec<u32> = Vec::new();
        for &t in grown.iter() {
            let on_front = dual
                .row(t as usize)
                .iter()
                .any(|&n| open_free(&self.stamp, &self.region, n));
            if on_front && !next_to_r(&self.stamp, &self.region, t) {
                self.tseen[t as usize] = a;
                queue.push(t);
            }
        }
        let mut removed = 0usize;
        let mut i = 0;
        let mut fits = false;
        while i < queue.len() {
            if grown.len() - removed + r.len() <= max_t && nv + orphan_v - shared <= max_v {
                fits = true;
                break;
            }
            if 2 * (removed + 1) > grown.len() {
                break;
            }
            let u = queue[i];
            i += 1;
            removed += 1;
            self.release(mesh, a, u, &mut nv, &mut shared);
            for &n in dual.row(u as usize) {
                if labels[n as usize] == c
                    && self.tseen[n as usize] != a
                    && !next_to_r(&self.stamp, &self.region, n)
                {
                    self.tseen[n as usize] = a;
                    queue.push(n);
                }
            }
        }
        fits |= grown.len() - removed + r.len() <= max_t && nv + orphan_v - shared <= max_v;
        if !fits {
            return None;
        }
        let shed: Vec<u32> = queue[..removed].to_vec();
        // Connected: flood the kept triangles and `r` from `r`'s first triangle (stamps: `gone`
        // marks the given-back triangles, `reached` the flooded ones).
        self.attempt += 2;
        let (gone, reached) = (self.attempt - 1, self.attempt);
        for &t in &shed {
            self.tseen[t as usize] = gone;
        }
        let mut stack = vec![r[0]];
        self.tseen[r[0] as usize] = reached;
        let mut flooded = 1;
        while let Some(u) = stack.pop() {
            for &n in dual.row(u as usize) {
                let ni = n as usize;
                let member = (labels[ni] == c && self.tseen[ni] != gone)
                    || in_r(&self.stamp, &self.region, n);
                if member && self.tseen[ni] != reached {
                    self.tseen[ni] = reached;
                    flooded += 1;
                    stack.push(n);
                }
            }
        }
        if flooded != grown.len() - shed.len() + r.len() {
            return None;
        }
        for &t in &shed {
            labels[t as usize] = FREE;
        }
        for &t in r {
            labels[t as usize] = c;
        }
        grown.retain(|&t| labels[t as usize] == c);
        grown.extend_from_slice(r);
        Some(shed)
    }

    /// The free regions of at most `cap` triangles that contain a triangle of `frontier`, largest
    /// first. One breadth-first search per region; a search that grows past `cap` or meets a
    /// region already found open marks what it saw open, so on a surface (one large free region)
    /// the check costs about `cap` steps per cluster.
    fn regions(
        &mut self,
        dual: &Csr,
        cap: usize,
        c: u32,
        frontier: &[u32],
        labels: &[u32],
    ) -> Vec<Vec<u32>> {
        let mut regions: Vec<Vec<u32>> = Vec::new();
        for &f in frontier {
            if labels[f as usize] != FREE || self.stamp[f as usize] == c + 1 {
                continue;
            }
            let id = regions.len() as u32;
            self.queue.clear();
            self.queue.push(f);
            self.stamp[f as usize] = c + 1;
            self.region[f as usize] = id;
            let mut open = false;
            let mut i = 0;
            while i < self.queue.len() && !open {
                let u = self.queue[i];
                i += 1;
                for &n in dual.row(u as usize) {
                    if labels[n as usize] != FREE {
                        continue;
                    }
                    if self.stamp[n as usize] == c + 1 {
                        open |= self.region[n as usize] == OPEN;
                        continue;
                    }
                    self.stamp[n as usize] = c + 1;
                    self.region[n as usize] = id;
                    self.queue.push(n);
                }
                open |= self.queue.len() > cap;
            }
            if open {
                for &u in &self.queue {
                    self.region[u as usize] = OPEN;
                }
            } else {
                regions.push(self.queue.clone());
            }
        }
        regions.sort_by_key(|r| (Reverse(r.len()), r[0]));
        regions
    }

    /// The longest prefix of `grown` that, with all of `take` (whole orphans of the current
    /// check), fits the limits and touches each of those orphans across an edge.
    #[allow(clippy::too_many_arguments)]
    fn prefix(
        &mut self,
        mesh: &Mesh,
        dual: &Csr,
        limits: Limits,
        c: u32,
        grown: &[u32],
        take: &[u32],
        labels: &[u32],
    ) -> Option<usize> {
        let (a, orphan_v, mut nv, mut shared) = self.count_vertices(mesh, grown, take);
        // Edges from each orphan into the prefix.
        let mut ids: Vec<u32> = take.iter().map(|&t| self.region[t as usize]).collect();
        ids.sort_unstable();
        ids.dedup();
        let slot = |stamp: &[u32], region: &[u32], m: u32| -> Option<usize> {
            if labels[m as usize] != FREE || stamp[m as usize] != c + 1 {
                return None;
            }
            ids.binary_search(&region[m as usize]).ok()
        };
        let mut touch = vec![0u32; ids.len()];
        for &t in take {
            let i = slot(&self.stamp, &self.region, t).expect("an orphan's triangle");
            touch[i] += dual
                .row(t as usize)
                .iter()
                .filter(|&&n| labels[n as usize] == c)
                .count() as u32;
        }
        let (max_v, max_t) = (limits.max_vertices as usize, limits.max_triangles as usize);
        let mut n = grown.len();
        loop {
            let fits = n + take.len() <= max_t && nv + orphan_v - shared <= max_v;
            if fits && touch.iter().all(|&x| x > 0) {
                return Some(n);
            }
            if n <= 1 {
                return None;
            }
            // Give back the last-grown triangle.
            n -= 1;
            let u = grown[n];
            self.release(mesh, a, u, &mut nv, &mut shared);
            for &m in dual.row(u as usize) {
                if let Some(i) = slot(&self.stamp, &self.region, m) {
                    touch[i] -= 1;
                }
            }
        }
    }
}

fn centroid(mesh: &Mesh, t: u32) -> glam::Vec3 {
    mesh.triangle(t as usize)
        .iter()
        .map(|&v| mesh.position(v))
        .sum::<glam::Vec3>()
        / 3.0
}

/// What a growing cluster prefers among frontier triangles that add as many vertices and are as
/// enclosed (the first two keys, which decide fill).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Grow {
    /// The triangle nearest the cluster's running centroid (meshoptimizer's choice too): round
    /// clusters in space, so small bounding spheres; measured: radius at or under meshoptimizer's
    /// on most meshes, a few percent more meshlets than [`Grow::Hops`] (results/kmedoids.md).
    #[default]
    Centre,
    /// The triangle fewest hops from the seed, then nearest the running centroid: round in the
    /// dual graph, the k-medoids metric, so the fewest meshlets, but 5-40 % larger spheres (more
    /// on fans of long thin triangles, whose hop-balls are long wedges).
    Hops,
}

impl std::str::FromStr for Grow {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "centre" | "center" => Ok(Self::Centre),
            "hops" => Ok(Self::Hops),
            _ => Err(format!("unknown k-medoids growth '{s}' (centre, hops)")),
        }
    }
}

/// Growth priority of a frontier triangle, smallest first: vertices it adds (0 closes a hole),
/// free edge-neighbours it has (fewer = more enclosed: taking it now leaves no sliver behind, the
/// role of meshoptimizer's live-triangle counts), hops from the seed ([`Grow::Hops`] only),
/// squared distance to the cluster's running centroid, then the lower id. The centroid moves as
/// the cluster grows, so a key is re-checked when it is popped and pushed back if it changed.
type Key = (u8, u8, u32, u32, u32);

/// Step 3: capacity-aware assignment. Level by level from all `medoids` at once, each cluster in
/// ascending id takes the free neighbours of its last level (ascending) that fit its limits; so a
/// triangle joins the nearest medoid with room, ties to the lower cluster. Triangles no cluster
/// reaches with room stay free.
pub fn assign_capacity(
    mesh: &Mesh,
    dual: &Csr,
    limits: Limits,
    medoids: &[u32],
    labels: &mut [u32],
) {
    let (max_v, max_t) = (limits.max_vertices as usize, limits.max_triangles as usize);
    let k = medoids.len();
    let mut verts: Vec<Vec<u32>> = vec![Vec::with_capacity(max_v); k];
    let mut count = vec![0usize; k];
    let mut frontier: Vec<(u32, u32)> = Vec::new();
    for (c, &m) in medoids.iter().enumerate() {
        labels[m as usize] = c as u32;
        count[c] = 1;
        verts[c].extend(mesh.triangle(m as usize));
        frontier.push((c as u32, m));
    }
    let mut candidates: Vec<(u32, u32)> = Vec::new();
    while !frontier.is_empty() {
        candidates.clear();
        for &(c, t) in &frontier {
            if count[c as usize] >= max_t {
                continue;
            }
            for &n in dual.row(t as usize) {
                if labels[n as usize] == FREE {
                    candidates.push((c, n));
                }
            }
        }
        candidates.sort_unstable();
        candidates.dedup();
        frontier.clear();
        for &(c, t) in &candidates {
            let ci = c as usize;
            if labels[t as usize] != FREE || count[ci] >= max_t {
                continue;
            }
            let tri = mesh.triangle(t as usize);
            let new = tri.iter().filter(|v| !verts[ci].contains(v)).count();
            if verts[ci].len() + new > max_v {
                continue;
            }
            for v in tri {
                if !verts[ci].contains(&v) {
                    verts[ci].push(v);
                }
            }
            labels[t as usize] = c;
            count[ci] += 1;
            frontier.push((c, t));
        }
    }
}

/// Edge-connected pieces per cluster (test helper shared with the strategy tests).
#[cfg(test)]
fn pieces_per_cluster(dual: &Csr, labels: &[u32], k: usize) -> Vec<usize> {
    let mem = members(labels, k);
    (0..k)
        .map(|c| {
            let m = mem.row(c);
            let sub = LocalGraph::new(dual, labels, c as u32, m);
            let mut seen = vec![false; m.len()];
            let mut n = 0;
            for s in 0..m.len() {
                if seen[s] {
                    continue;
                }
                n += 1;
                let mut stack = vec![s];
                seen[s] = true;
                while let Some(u) = stack.pop() {
                    for &v in sub.row(u) {
                        if !seen[v as usize] {
                            seen[v as usize] = true;
                            stack.push(v as usize);
                        }
                    }
                }
            }
            n
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::adjacency::{dual_graph, vertex_triangles};
    use crate::mesh::generate;
    use crate::meshlet::{validate, MeshletBuilder};

    #[test]
    fn clusters_fit_are_connected_and_do_not_depend_on_threads() {
        let meshes = [
            generate::knot_tube(120, 12, 3),
            generate::terrain(24, 5),
            generate::cad_part(128, 1),
        ];
        for m in &meshes {
            for (limits, grow) in [
                (Limits::new(64, 126).unwrap(), Grow::Centre),
                (Limits::new(32, 40).unwrap(), Grow::Centre),
                (Limits::new(64, 126).unwrap(), Grow::Hops),
            ] {
                let vt = vertex_triangles(m);
                let dual = dual_graph(m, &vt);
                let a = crate::test_pool(1).install(|| cluster(m, &dual, &vt, limits, grow, 4));
                let b = crate::test_pool(4).install(|| cluster(m, &dual, &vt, limits, grow, 4));
                assert_eq!(
                    (&a.medoids, &a.labels, &a.distances),
                    (&b.medoids, &b.labels, &b.distances)
                );
                assert!(a
                    .labels
                    .iter()
                    .all(|&l| l != UNREACHED && (l as usize) < a.medoids.len()));
                // Every cluster fits the limits: one meshlet each.
                let mem = members(&a.labels, a.medoids.len());
                let mut builder = MeshletBuilder::new(m.vertex_count(), limits);
                for c in 0..a.medoids.len() {
                    for &t in mem.row(c) {
                        assert!(
                            builder.fits(m.triangle(t as usize)),
                            "cluster {c} overflows"
                        );
                        builder.push(m.triangle(t as usize));
                    }
                    builder.flush();
                }
                let out = builder.finish();
                validate(m, &out, limits).unwrap();
                assert_eq!(out.len(), a.medoids.len());
                // These meshes are one edge-connected piece, so every cluster is one piece too.
                assert!(pieces_per_cluster(&dual, &a.labels, a.medoids.len())
                    .iter()
                    .all(|&p| p == 1));
                // Medoids are members, at distance 0.
                for (c, &md) in a.medoids.iter().enumerate() {
                    assert_eq!(a.labels[md as usize], c as u32);
                    assert_eq!(a.distances[md as usize], 0);
                }
            }
        }
    }

    #[test]
    fn a_full_cluster_takes_the_hole_it_encloses_and_gives_back_its_last_triangle() {
        let (m, dual, order) = terrain_and_order();
        let limits = Limits::new(255, 126).unwrap();
        // Cluster 0 holds the first 127 triangles but the 10th, a hole: triangle-full. Every other
        // triangle is taken, so the hole is a free region of one triangle, enclosed.
        let (c, hole) = (0u32, order[10]);
        let mut labels = vec![7u32; m.triangle_count()];
        let mut grown: Vec<u32> = order[..127]
            .iter()
            .copied()
            .filter(|&t| t != hole)
            .collect();
        for &t in &grown {
            labels[t as usize] = c;
        }
        labels[hole as usize] = FREE;
        let last = *grown.last().unwrap();
        let mut o = Orphans::new(m.vertex_count(), m.triangle_count());
        let shed = o.absorb(&m, &dual, limits, c, &[hole], &mut grown, &mut labels);
        // The hole joins; the last-grown triangle goes back free; the limit still holds.
        assert_eq!(shed, vec![last]);
        assert_eq!(labels[hole as usize], c);
        assert_eq!(labels[last as usize], FREE);
        assert_eq!(grown.len(), 126);
        assert_eq!(*grown.last().unwrap(), hole);
        assert!(grown.iter().all(|&t| labels[t as usize] == c));
        // A free region larger than half the triangle limit is not an orphan: nothing changes.
        let mut labels = vec![FREE; m.triangle_count()];
        let mut grown: Vec<u32> = order[..126].to_vec();
        for &t in &grown {
            labels[t as usize] = c;
        }
        let before = (grown.clone(), labels.clone());
        let shed = o.absorb(&m, &dual, limits, c, &order[126..], &mut grown, &mut labels);
        assert!(shed.is_empty());
        assert_eq!((grown, labels), before);
    }

    #[test]
    fn an_orphan_by_the_front_is_taken_for_triangles_given_back_at_the_open_front() {
        let (m, dual, order) = terrain_and_order();
        let limits = Limits::new(255, 126).unwrap();
        // Cluster 0 is the triangle-full ball of the first 126; the next triangle is enclosed by
        // it and by another cluster's triangles; the rest of the mesh is free (the open front).
        let (c, orphan) = (0u32, order[126]);
        let (mut labels, mut grown) = ball_and_orphan(&m, &dual, &order[..126], orphan);
        let mut o = Orphans::new(m.vertex_count(), m.triangle_count());
        let regions = o.regions(&dual, 63, c, &[orphan], &labels);
        assert_eq!(regions, vec![vec![orphan]]);
        let shed = o
            .front_shed(&m, &dual, limits, c, &mut grown, &regions[0], &mut labels)
            .expect("one triangle on the front can go");
        // One triangle given back (the limit is triangles), on the open front, not next to the
        // orphan; the orphan joined; the cluster fits and is one edge-connected piece.
        assert_eq!(shed.len(), 1);
        let s = shed[0] as usize;
        assert_eq!(labels[s], FREE);
        assert!(!dual.row(s).contains(&orphan));
        assert!(dual
            .row(s)
            .iter()
            .any(|&n| n != orphan && labels[n as usize] == FREE));
        assert_eq!(labels[orphan as usize], c);
        assert_eq!(grown.len(), 126);
        assert!(grown.iter().all(|&t| labels[t as usize] == c));
        let members: Vec<u32> = (0..m.triangle_count() as u32)
            .filter(|&t| labels[t as usize] == c)
            .collect();
        assert_eq!(members.len(), 126);
        assert_eq!(
            pieces_per_cluster(&dual, &labels_only(&labels, c), 1),
            vec![1]
        );
        // The same with the vertex limit binding: the ball holds exactly the limit, and the
        // orphan (the first triangle after the ball with a vertex outside it) adds a vertex.
        let ball = &order[..126];
        let mut verts: Vec<u32> = ball.iter().flat_map(|&t| m.triangle(t as usize)).collect();
        verts.sort_unstable();
        verts.dedup();
        let orphan = *order[126..]
            .iter()
            .find(|&&t| {
                m.triangle(t as usize)
                    .iter()
                    .any(|v| verts.binary_search(v).is_err())
            })
            .unwrap();
        let limits = Limits::new(verts.len() as u32, 255).unwrap();
        let (mut labels, mut grown) = ball_and_orphan(&m, &dual, ball, orphan);
        let mut o = Orphans::new(m.vertex_count(), m.triangle_count());
        let regions = o.regions(&dual, 63, c, &[orphan], &labels);
        assert_eq!(regions, vec![vec![orphan]]);
        let shed = o
            .front_shed(&m, &dual, limits, c, &mut grown, &regions[0], &mut labels)
            .expect("a vertex on the front can be freed");
        assert!(!shed.is_empty());
        assert!(shed
            .iter()
            .all(|&t| labels[t as usize] == FREE && !dual.row(t as usize).contains(&orphan)));
        assert_eq!(labels[orphan as usize], c);
        let mut now: Vec<u32> = grown.iter().flat_map(|&t| m.triangle(t as usize)).collect();
        now.sort_unstable();
        now.dedup();
        assert!(
            now.len() <= verts.len(),
            "{} vertices over the limit",
            now.len()
        );
        assert_eq!(grown.len(), 127 - shed.len());
        assert_eq!(
            pieces_per_cluster(&dual, &labels_only(&labels, c), 1),
            vec![1]
        );
    }

    /// The terrain test mesh, its dual graph, and 200 triangles in breadth-first order from
    /// triangle 300 (every prefix edge-connected).
    fn terrain_and_order() -> (Mesh, Csr, Vec<u32>) {
        let m = generate::terrain(24, 5);
        let dual = dual_graph(&m, &vertex_triangles(&m));
        let mut order = vec![300u32];
        let mut seen = vec![false; m.triangle_count()];
        seen[300] = true;
        let mut i = 0;
        while order.len() < 200 {
            for &n in dual.row(order[i] as usize) {
                if !seen[n as usize] {
                    seen[n as usize] = true;
                    order.push(n);
                }
            }
            i += 1;
        }
        (m, dual, order)
    }

    /// Labels with `ball` as cluster 0 and `orphan` enclosed by it and by another cluster's
    /// triangles (7), the rest of the mesh free (the open front); and the ball as `grown`.
    fn ball_and_orphan(m: &Mesh, dual: &Csr, ball: &[u32], orphan: u32) -> (Vec<u32>, Vec<u32>) {
        let mut labels = vec![FREE; m.triangle_count()];
        for &t in ball {
            labels[t as usize] = 0;
        }
        for &n in dual.row(orphan as usize) {
            if labels[n as usize] == FREE {
                labels[n as usize] = 7;
            }
        }
        (labels, ball.to_vec())
    }

    /// `labels` with cluster `c` as 0 and every other triangle as `UNREACHED` (one cluster to
    /// count pieces of).
    fn labels_only(labels: &[u32], c: u32) -> Vec<u32> {
        labels
            .iter()
            .map(|&l| if l == c { 0 } else { UNREACHED })
            .collect()
    }

    #[test]
    fn rounds_run_only_where_a_third_of_the_clusters_are_light() {
        let limits = Limits::new(64, 126).unwrap();
        let labels = |sizes: &[usize]| -> Vec<u32> {
            sizes
                .iter()
                .enumerate()
                .flat_map(|(c, &n)| std::iter::repeat_n(c as u32, n))
                .collect()
        };
        // 63 triangles is light (at most half of 126), 64 is not.
        assert!(worth_a_round(&labels(&[63, 64, 126]), 3, limits));
        assert!(!worth_a_round(&labels(&[63, 64, 64, 126]), 4, limits));
        assert!(worth_a_round(&labels(&[1, 2, 64, 64, 126]), 5, limits));
        // A closed surface grows nearly full clusters: no round runs.
        let m = generate::noisy_sphere(4, 0.2, 7);
        let vt = vertex_triangles(&m);
        let dual = dual_graph(&m, &vt);
        assert_eq!(
            cluster(&m, &dual, &vt, limits, Grow::Centre, 16).iterations,
            0
        );
        // A tube of three-vertex rings fills 32 vertices with about 60 triangles, so every
        // cluster is light at 32/126: rounds run, and the result is the same on any thread count.
        let m = generate::knot_tube(400, 3, 5);
        let vt = vertex_triangles(&m);
        let dual = dual_graph(&m, &vt);
        let limits = Limits::new(32, 126).unwrap();
        let run = |threads| {
            crate::test_pool(threads).install(|| cluster(&m, &dual, &vt, limits, Grow::Centre, 16))
        };
        let (a, b) = (run(1), run(3));
        assert!(a.iterations > 0);
        assert_eq!(
            (&a.medoids, &a.labels, &a.distances, a.iterations),
            (&b.medoids, &b.labels, &b.distances, b.iterations)
        );
    }
}
