//! `kmedoids-parallel`: the region-parallel k-medoids with a grower one GPU invocation runs per
//! region (CPU reference of `wgsl/regions.wgsl`, driven on the GPU by `gpu::regions`).
//!
//! [`super::tiled`] (`kmedoids-tiled`) runs the capacity-aware method per region; its growth
//! keys divide (the running centroid) and its merges and piece packing sort and allocate, so no
//! kernel runs it.
//! This method keeps the regions and replaces the per-region step with a grower made of integer
//! keys, linear scans and fixed arrays, which a kernel runs line for line:
//!
//! 1. **Regions**: [`super::coarse`] (the Morton-seeded multi-source BFS).
//! 2. **Growth per region**, one invocation each ([`grow_region`]):
//!    - pieces of the region's dual graph, each in reversed BFS order from its lowest triangle,
//!      so seeds come deepest first (a piece's far end, where a grower would strand leftovers);
//!    - a cluster grows from the first free triangle in that order by the frontier triangle of
//!      least (vertices added, free neighbours, squared distance to the cluster's centre, hops
//!      from the seed, triangle id): the first key fills the vertex limit, the second closes
//!      pockets, the third keeps the cluster round. Distances are between the triangles'
//!      centroid cells in the Morton order's frame (15 bits per axis, [`packed_centres`]), and the
//!      centre is their integer mean, so the key is the same integer on every device;
//!    - a cluster whose piece ran out while it still has room continues in another piece (small
//!      pieces packed together instead of one part-filled meshlet each): of the next
//!      [`PACK_WINDOW`] pieces in seed order, the one whose seed is nearest the cluster's centre
//!      and fits, if it is a whole piece of the mesh (one the region's border cuts could put the
//!      cluster in two parts of one mesh piece). Taking the next piece instead packed pieces far
//!      apart where a lattice's struts come in rows;
//!    - when a cluster stops, free pockets next to it of at most half the triangle limit are
//!      absorbed, largest first, if giving back its last-grown triangles (at most half of them)
//!      makes room: the pocket would otherwise become a meshlet of its own; each pocket that
//!      rule cannot take is tried by the front rule (`shed_front`), which gives back the
//!      triangles nearest the open free side instead;
//!    - then clusters merge into a neighbour across an edge whose union fits, smallest first
//!      (what tube ends and enclosed leftovers need: on the neurons a sixth fewer meshlets);
//!    - then a cluster made only of whole small pieces is dissolved into the clusters nearest
//!      its pieces that have room, where the targets' bounding radii grow by no more, summed,
//!      than its own (`pack_pieces`): the growth packs pieces only into a cluster whose own
//!      piece ran out, so detached pieces seeded among a large piece's clusters would otherwise
//!      stay meshlets of their own;
//!    - then a cluster whose members all find room in the clusters across its edges is dissolved
//!      into them, smallest first, member by member from its border inwards
//!      (`dissolve_clusters`): the merges move a cluster whole into one neighbour, while on
//!      branching tubes a cluster between two part-filled ones often fits neither alone but
//!      splits across both.
//! 3. **Labels**: cluster `c` of region `r` is `base[r] + c`, regions in order.
//! 4. **Medoids**: the paper's medoid of each cluster and its members' in-cluster hop distances
//!    (one invocation per cluster on the GPU), which order the members when packing.
//! 5. **Medoid iteration**: [`super::moves`]' boundary moves, as in `kmedoids-tiled`
//!    (`wgsl/moves.wgsl` on the GPU): border triangles move to a neighbouring cluster whose
//!    medoid is nearer while the limits hold, then changed clusters take the paper's medoid
//!    again. The objective falls and the count stays.
//!
//! Where it differs from the paper (section 3): k comes out of the growth, nothing is split, and
//! the iteration moves only border triangles, within the limits (the growth keys, not
//! nearest-medoid assignment, shape the clusters); where it differs from `kmedoids-tiled`:
//! merges only inside a region (none across region borders), whole pieces packed during the
//! growth (nearest within a window) and, after the merges, into the region's clusters with room
//! under the radius rule (not nearest over all clusters), clusters dissolved across their
//! neighbours (which that method does not do), the orphan rules
//! over pockets of the region only, and the running centroid in quantised integers. Every
//! cluster is edge-connected except where small whole pieces are packed together. Determinism:
//! regions share no state and every choice is a strict minimum over integer keys (the moves'
//! sums are order-independent), so the result is the same for any thread count and on the GPU.
//!
//! A vertex is tracked through its canonical corner in the region ([`canonical_corners`]): the
//! first corner, in triangle order, of the region's lowest triangle using it. Per-corner state
//! then needs no per-region vertex numbering, and two regions sharing a vertex never touch the
//! same word (which a kernel needs: regions run concurrently).

use super::assign::{members, UNREACHED};
use super::capacity::{medoid_of, Grown};
use super::coarse::regions;
use super::flat::{distance2, packed_centres, unpack, Centre};
use super::moves::{move_boundaries, Moves};
use super::{pack, Clustering, Config};
use crate::common::Csr;
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use rayon::prelude::*;
use std::time::Instant;

const NONE: u32 = UNREACHED;
/// Marks a pocket stamp whose free component is too large to absorb.
const BIG: u32 = 1 << 31;
/// How many pieces, in seed order from the first free one, a packing cluster weighs for its next
/// piece: pieces come in runs along the mesh (the order a generator or a scanner wrote them), so
/// the nearest is usually a few ahead, and the bound keeps a region of many pieces linear.
/// `wgsl/regions.wgsl` holds the same value.
pub const PACK_WINDOW: usize = 32;

/// Runs steps 1-5 over the dual graph; `t0` is when the run began (the adjacency counts in).
pub fn cluster(
    mesh: &Mesh,
    dual: &Csr,
    vt: &Csr,
    limits: Limits,
    cfg: &Config,
    t0: Instant,
) -> Clustering {
    let t = mesh.triangle_count();
    let (region, k_regions) = regions(mesh, dual, cfg.region_triangles as usize);
    let rows = members(&region, k_regions);
    let local = local_index(&rows, t);
    let canon = canonical_corners(mesh, vt, &region);
    let centres = packed_centres(mesh);
    let input = RegionInput {
        mesh,
        dual,
        vt,
        region: &region,
        local: &local,
        canon: &canon,
        centres: &centres,
        limits,
    };
    let runs: Vec<(Vec<u32>, u32)> = (0..k_regions)
        .into_par_iter()
        .map(|r| grow_region(&input, r as u32, rows.row(r)))
        .collect();
    // Step 3.
    let mut labels = vec![NONE; t];
    let mut k = 0u32;
    for (r, (local_labels, count)) in runs.iter().enumerate() {
        for (&tri, &l) in rows.row(r).iter().zip(local_labels) {
            labels[tri as usize] = k + l;
        }
        k += count;
    }
    // Step 4.
    let (mut medoids, mut distances) = medoids_and_distances(dual, &labels, k as usize);
    // Step 5.
    let moves = move_boundaries(
        mesh,
        dual,
        vt,
        limits,
        &centres,
        &mut labels,
        &mut medoids,
        &mut distances,
        cfg.move_rounds,
    );
    let meshlets = pack(mesh, &labels, &distances, k as usize, limits);
    clustering(
        medoids,
        labels,
        distances,
        meshlets,
        &moves,
        t0.elapsed().as_secs_f64(),
    )
}

/// A run's result (CPU or GPU): the clusters after the moves and their meshlets, with the
/// objective before the moves and the rounds that moved triangles; `seconds` is its wall time.
pub fn clustering(
    medoids: Vec<u32>,
    labels: Vec<u32>,
    distances: Vec<u32>,
    meshlets: Meshlets,
    moves: &Moves,
    seconds: f64,
) -> Clustering {
    let grown = Grown {
        medoids,
        labels,
        distances,
        iterations: moves.rounds,
    };
    Clustering {
        initial_mean_distance: moves.objective_before,
        ..Clustering::grown(grown, meshlets, seconds)
    }
}

/// Each triangle's position in its region's (ascending) member list.
pub fn local_index(rows: &Csr, triangles: usize) -> Vec<u32> {
    let mut local = vec![0; triangles];
    for r in 0..rows.rows() {
        for (i, &t) in rows.row(r).iter().enumerate() {
            local[t as usize] = i as u32;
        }
    }
    local
}

/// Per corner `3t + j`: the canonical corner of its vertex in `t`'s region, the corner `3u + i`
/// of the lowest triangle `u` of that region using the vertex, `i` its first such corner.
pub fn canonical_corners(mesh: &Mesh, vt: &Csr, region: &[u32]) -> Vec<u32> {
    (0..mesh.triangle_count())
        .into_par_iter()
        .flat_map_iter(|t| {
            let r = region[t];
            mesh.triangle(t).map(|v| {
                // Rows are ascending: the first in the region is the lowest.
                let u = vt
                    .row(v as usize)
                    .iter()
                    .copied()
                    .find(|&x| region[x as usize] == r)
                    .expect("a vertex's triangles include this one");
                let i = mesh
                    .triangle(u as usize)
                    .iter()
                    .position(|&w| w == v)
                    .expect("the vertex is a corner");
                3 * u + i as u32
            })
        })
        .collect()
}

/// The growth key: (vertices added, free neighbours, squared distance to the centre, hops,
/// local triangle); the least grows next.
type GrowKey = (usize, usize, u32, u32, usize);

/// What every region's growth reads.
pub struct RegionInput<'a> {
    /// The mesh.
    pub mesh: &'a Mesh,
    /// Its dual graph.
    pub dual: &'a Csr,
    /// Its vertex -> triangles rows.
    pub vt: &'a Csr,
    /// Region of each triangle.
    pub region: &'a [u32],
    /// [`local_index`].
    pub local: &'a [u32],
    /// [`canonical_corners`].
    pub canon: &'a [u32],
    /// [`packed_centres`].
    pub centres: &'a [Centre],
    /// Meshlet limits.
    pub limits: Limits,
}

/// One region's mutable state, indexed by local triangle (`i`) or local canonical corner
/// (`3i + j`). The kernel keeps the same words in global arrays.
struct State {
    label: Vec<u32>,
    /// Cluster that last put the triangle on its frontier.
    inq: Vec<u32>,
    /// Hops from the seed, set when put on the frontier.
    hop: Vec<u32>,
    /// Free neighbours while on the frontier (the growth key's second term): counted when put on
    /// the frontier and decremented as neighbours are grown, so that choosing the next triangle
    /// does not walk every frontier triangle's neighbours again.
    free: Vec<u32>,
    /// Position in the growing cluster (while grown) or the pocket stamp `c + 1` (while free).
    aux: Vec<u32>,
    piece: Vec<u32>,
    /// Position in the seed order.
    opos: Vec<u32>,
    /// Per corner: the cluster that last used the vertex, and the position in that cluster of
    /// the first triangle using it.
    mark: Vec<u32>,
    first: Vec<u32>,
    /// Per corner: the pocket evaluation that last counted the vertex.
    wmark: Vec<u32>,
}

impl State {
    /// A region of `n` triangles before its growth: everything free, no piece found yet.
    fn new(n: usize) -> Self {
        Self {
            label: vec![NONE; n],
            inq: vec![NONE; n],
            hop: vec![0; n],
            free: vec![0; n],
            aux: vec![0; n],
            piece: vec![NONE; n],
            opos: vec![0; n],
            mark: vec![NONE; 3 * n],
            first: vec![0; 3 * n],
            wmark: vec![0; 3 * n],
        }
    }
}

/// Step 2 for region `r` (members `tris`, ascending): each member's cluster, numbered from 0 in
/// the order clusters close, and the cluster count.
pub fn grow_region(input: &RegionInput<'_>, r: u32, tris: &[u32]) -> (Vec<u32>, u32) {
    let n = tris.len();
    let (mv, mt) = (
        input.limits.max_vertices as usize,
        input.limits.max_triangles as usize,
    );
    let mut s = State::new(n);
    // The region's dual graph, canonical corners and centres in local numbers, gathered once: the
    // growth reads them for every frontier triangle at every step (the kernel reads the global
    // arrays instead; the values are the same).
    let mut local_dual = Csr {
        offsets: Vec::with_capacity(n + 1),
        items: Vec::with_capacity(3 * n),
    };
    local_dual.offsets.push(0);
    for &t in tris {
        let row = input.dual.row(t as usize).iter();
        let inside = row.filter(|&&x| input.region[x as usize] == r);
        local_dual
            .items
            .extend(inside.map(|&x| input.local[x as usize]));
        local_dual.offsets.push(local_dual.items.len() as u32);
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
    let lc: Vec<Centre> = tris.iter().map(|&t| input.centres[t as usize]).collect();
    // Neighbours of local triangle `i` inside the region, as local indices.
    let nbrs = |i: usize| local_dual.row(i).iter().map(|&x| x as usize);
    // Local canonical corners of local triangle `i`.
    let corners = |i: usize| local_corners[i];
    // Pieces in reversed BFS order, the seed order.
    let mut order = Vec::with_capacity(n);
    let mut left = Vec::new();
    // Whether a piece is a whole piece of the mesh (no edge leaves the region).
    let mut closed: Vec<bool> = Vec::new();
    // Where each piece starts in the seed order (pieces are contiguous there).
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
            whole &= local_dual.row(u).len() == input.dual.row(tris[u] as usize).len();
            for j in nbrs(u) {
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
    // Distinct corners of `i` whose vertex cluster `c` does not use yet.
    let added = |s: &State, i: usize, c: u32| {
        let k = corners(i);
        (0..3)
            .filter(|&j| s.mark[k[j]] != c && !k[..j].contains(&k[j]))
            .count()
    };
    let free_neighbours = |s: &State, i: usize| nbrs(i).filter(|&j| s.label[j] == NONE).count();
    let mut front: Vec<usize> = Vec::new();
    let mut grown: Vec<usize> = Vec::new();
    // Cluster vertices after each grown triangle.
    let mut vcount: Vec<u32> = Vec::new();
    let (mut cursor, mut c, mut open) = (0usize, 0u32, false);
    let mut nv = 0usize;
    let mut serial = 0u32;
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
                order: &order,
                starts: &starts,
                left: &left,
                closed: &closed,
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
            for k in corners(i) {
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
            for j in nbrs(i) {
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
        if let Some(earliest) = absorb_pockets(
            &mut s,
            &nbrs,
            &corners,
            &mut grown,
            &vcount,
            &mut left,
            c,
            mv,
            mt,
            &mut serial,
        ) {
            // Triangles before the cursor are taken, but those given back: seeds resume there.
            cursor = cursor.min(earliest);
        }
        c += 1;
        open = false;
    }
    let mut clusters = merge_neighbours(&mut s, &nbrs, &corners, n, c, mv, mt, &mut serial);
    pack_pieces(
        &mut s,
        &mut clusters,
        &nbrs,
        &corners,
        &lc,
        &closed,
        mv,
        mt,
        &mut serial,
    );
    // Local triangles of the region using the vertex of local corner `kk`.
    let users = |kk: usize| {
        let v = input.mesh.indices[3 * tris[kk / 3] as usize + kk % 3];
        input
            .vt
            .row(v as usize)
            .iter()
            .filter(move |&&y| input.region[y as usize] == r)
            .map(|&y| input.local[y as usize] as usize)
    };
    dissolve_clusters(&mut s, &mut clusters, &nbrs, &corners, &users, mv, mt);
    let k = clusters.renumber(&mut s.label);
    (s.label, k)
}

/// Where a packing cluster may go on: the region's pieces in seed order and its centre.
struct Packing<'a> {
    order: &'a [usize],
    starts: &'a [usize],
    left: &'a [u32],
    closed: &'a [bool],
    /// The first free triangle's position in `order`.
    cursor: usize,
    centre: [u32; 3],
}

impl Packing<'_> {
    /// The seed of the piece nearest the cluster's centre (ties to the earlier piece) among the
    /// [`PACK_WINDOW`] pieces from the cursor's: the cursor's own, or an untouched one after it
    /// (its first triangle in the seed order), if it is a whole piece of the mesh (a piece the
    /// region's border cuts could put the cluster in two parts of one mesh piece) and its seed
    /// `fits` the cluster.
    fn nearest(
        &self,
        piece: &[u32],
        centre_of: &impl Fn(usize) -> Centre,
        fits: &impl Fn(usize) -> bool,
    ) -> Option<usize> {
        let first = piece[self.order[self.cursor]] as usize;
        let mut best: Option<(u32, usize)> = None;
        for p in first..(first + PACK_WINDOW).min(self.starts.len()) {
            let seed = if p == first {
                self.order[self.cursor]
            } else {
                let end = self.starts.get(p + 1).copied().unwrap_or(self.order.len());
                if self.left[p] as usize != end - self.starts[p] {
                    continue;
                }
                self.order[self.starts[p]]
            };
            if !self.closed[p] || !fits(seed) {
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

/// A region's clusters between the growth and the renumbering: members (local indices), distinct
/// vertices, and whether a merge has emptied them.
struct Clusters {
    mem: Vec<Vec<usize>>,
    nverts: Vec<usize>,
    alive: Vec<bool>,
}

impl Clusters {
    /// The survivors renumbered in order; returns their count.
    fn renumber(&self, label: &mut [u32]) -> u32 {
        let mut new_id = vec![NONE; self.alive.len()];
        let mut next = 0;
        for (c, &alive) in self.alive.iter().enumerate() {
            if alive {
                new_id[c] = next;
                next += 1;
            }
        }
        for l in label.iter_mut() {
            *l = new_id[*l as usize];
        }
        next
    }

    /// Distinct vertices of the clusters `cs` and the triangles `extra` together (a stamp per
    /// evaluation).
    fn vertices(
        &self,
        s: &mut State,
        corners: &impl Fn(usize) -> [usize; 3],
        cs: &[usize],
        extra: &[usize],
        serial: &mut u32,
    ) -> usize {
        *serial += 1;
        let mut nv = 0;
        let lists = cs.iter().map(|&c| &self.mem[c][..]).chain([extra]);
        for &i in lists.flatten() {
            for kk in corners(i) {
                if s.wmark[kk] != *serial {
                    s.wmark[kk] = *serial;
                    nv += 1;
                }
            }
        }
        nv
    }
}

/// Step 2b for one region: clusters merged into a neighbour across an edge whose union fits,
/// smallest first (ties to the lower id; among neighbours, the one sharing most vertices, then
/// the lower id).
#[allow(clippy::too_many_arguments)]
fn merge_neighbours<N, I>(
    s: &mut State,
    nbrs: &N,
    corners: &impl Fn(usize) -> [usize; 3],
    n: usize,
    k: u32,
    mv: usize,
    mt: usize,
    serial: &mut u32,
) -> Clusters
where
    N: Fn(usize) -> I,
    I: Iterator<Item = usize>,
{
    let k = k as usize;
    let mut cl = Clusters {
        mem: vec![Vec::new(); k],
        nverts: Vec::new(),
        alive: vec![true; k],
    };
    for i in 0..n {
        cl.mem[s.label[i] as usize].push(i);
    }
    cl.nverts = (0..k)
        .map(|c| cl.vertices(s, corners, &[c], &[], serial))
        .collect();
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
            for j in nbrs(i) {
                let b = s.label[j] as usize;
                if b == a || cstamp[b] == a {
                    continue;
                }
                cstamp[b] = a;
                if cl.mem[a].len() + cl.mem[b].len() > mt {
                    continue;
                }
                let union = cl.vertices(s, corners, &[a, b], &[], serial);
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
#[allow(clippy::too_many_arguments)]
fn dissolve_clusters<N, I, U, J>(
    s: &mut State,
    cl: &mut Clusters,
    nbrs: &N,
    corners: &impl Fn(usize) -> [usize; 3],
    users: &U,
    mv: usize,
    mt: usize,
) where
    N: Fn(usize) -> I,
    I: Iterator<Item = usize>,
    U: Fn(usize) -> J,
    J: Iterator<Item = usize>,
{
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
            .filter(|&x| nbrs(x).any(|y| s.label[y] != a32))
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
            for y in nbrs(x) {
                let b = s.label[y];
                if b == a32 || cl.mem[b as usize].len() + extra_t[b as usize] + 1 > mt {
                    continue;
                }
                // Distinct corners whose vertex no member of b (moved ones included) uses.
                let k3 = corners(x);
                let added = (0..3)
                    .filter(|&j| {
                        !k3[..j].contains(&k3[j]) && !users(k3[j]).any(|u| s.label[u] == b)
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
            for y in nbrs(x) {
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
#[allow(clippy::too_many_arguments)]
fn pack_pieces<N, I>(
    s: &mut State,
    cl: &mut Clusters,
    nbrs: &N,
    corners: &impl Fn(usize) -> [usize; 3],
    centres: &[Centre],
    closed: &[bool],
    mv: usize,
    mt: usize,
    serial: &mut u32,
) where
    N: Fn(usize) -> I,
    I: Iterator<Item = usize>,
{
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
            .all(|&i| closed[s.piece[i] as usize] && nbrs(i).all(|j| s.label[j] as usize == a));
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
            let pv = cl.vertices(s, corners, &[], tris, serial);
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
            cl.nverts[b] = cl.vertices(s, corners, &[b], &[], serial);
            centre[b] = centre_of(&mut cl.mem[b].iter().copied());
            radius[b] = radius_of(&mut cl.mem[b].iter().copied(), centre[b]);
        }
    }
}

/// The pocket rule for cluster `c` as it stops (see the module doc), keeping `left` (free
/// triangles per piece) up to date; returns the earliest seed-order position of a triangle it
/// freed (`usize::MAX` if none), or `None` when it changed nothing. `vcount[p]` is the cluster's
/// vertex count after `grown[p]`.
#[allow(clippy::too_many_arguments)]
fn absorb_pockets<N, I>(
    s: &mut State,
    nbrs: &N,
    corners: &impl Fn(usize) -> [usize; 3],
    grown: &mut Vec<usize>,
    vcount: &[u32],
    left: &mut [u32],
    c: u32,
    mv: usize,
    mt: usize,
    serial: &mut u32,
) -> Option<usize>
where
    N: Fn(usize) -> I,
    I: Iterator<Item = usize>,
{
    let cap = mt / 2;
    let stamp = c + 1;
    // Pockets: triangles in `q`, each (start, size); larger free components are dropped.
    let mut q: Vec<usize> = Vec::new();
    let mut pockets: Vec<(usize, usize)> = Vec::new();
    for &g in grown.iter() {
        for f in nbrs(g) {
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
                for j in nbrs(u) {
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
            .flat_map(|&i| nbrs(i))
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
        *serial += 1;
        hist.fill(0);
        let mut outside = 0u32;
        for &x in taken.iter().chain([&p]) {
            let (start, sz) = pockets[x];
            for &i in &q[start..start + sz] {
                for k in corners(i) {
                    if s.wmark[k] != *serial {
                        s.wmark[k] = *serial;
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
            let Some(shed) = shed_front(s, nbrs, corners, grown, pocket, c, mv, mt, serial) else {
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

/// Marks the pocket being tried by the front rule in `aux`, beside its stamp `c + 1`.
const TRYING: u32 = 1 << 30;
/// Marks the front rule's per-attempt stamps in `hop`, apart from hop counts.
const ATTEMPT: u32 = 1 << 31;

/// The front rule for a pocket the last-grown rule could not take (free, stamped `c + 1`): the
/// cluster gives back instead its triangles nearest the open free side (breadth-first inwards from
/// the front), never one next to the pocket, until the pocket fits; kept only when at most half is
/// given back and the cluster with the pocket is one piece (the pocket usually lies by the growth
/// front, where the last-grown rule would have to give back the triangles touching it; tube ends
/// on the neurons). Returns the triangles given back, or `None` with nothing changed. Scratch:
/// `hop` (attempt stamps; hop counts are set again when a triangle next joins a frontier),
/// `first` (per vertex, the kept members using it) and `wmark`.
#[allow(clippy::too_many_arguments)]
fn shed_front<N, I>(
    s: &mut State,
    nbrs: &N,
    corners: &impl Fn(usize) -> [usize; 3],
    grown: &mut Vec<usize>,
    pocket: &[usize],
    c: u32,
    mv: usize,
    mt: usize,
    serial: &mut u32,
) -> Option<Vec<usize>>
where
    N: Fn(usize) -> I,
    I: Iterator<Item = usize>,
{
    let stamp = c + 1;
    for &i in pocket {
        s.aux[i] = stamp | TRYING;
    }
    // Stamps: cluster vertex (`a`), also the pocket's (`a + 1`), the pocket's only (`a + 2`).
    let a = *serial + 1;
    *serial += 3;
    let (seen, gone, reached) = (ATTEMPT | a, ATTEMPT | (a + 1), ATTEMPT | (a + 2));
    let mut nv = 0usize;
    for &g in grown.iter() {
        for k in corners(g) {
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
        for k in corners(i) {
            if s.wmark[k] == a {
                s.wmark[k] = a + 1;
            } else if s.wmark[k] != a + 1 && s.wmark[k] != a + 2 {
                s.wmark[k] = a + 2;
                outside += 1;
            }
        }
    }
    let in_pocket = |s: &State, j: usize| s.label[j] == NONE && s.aux[j] == stamp | TRYING;
    let next_to_pocket = |s: &State, i: usize| nbrs(i).any(|j| in_pocket(s, j));
    // Free and in no pocket of this cluster: the open side (or given back, or a large component).
    let open =
        |s: &State, j: usize| s.label[j] == NONE && s.aux[j] != stamp && s.aux[j] != stamp | TRYING;
    let mut queue: Vec<usize> = Vec::new();
    for &g in grown.iter() {
        if nbrs(g).any(|j| open(s, j)) && !next_to_pocket(s, g) {
            s.hop[g] = seen;
            queue.push(g);
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
        for k in corners(u) {
            s.first[k] -= 1;
            if s.first[k] == 0 {
                nv -= 1;
                if s.wmark[k] == a + 1 {
                    outside += 1;
                }
            }
        }
        for j in nbrs(u) {
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
        for j in nbrs(u) {
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
    grown.retain(|&g| s.label[g] == c);
    grown.extend_from_slice(pocket);
    Some(queue)
}

/// Step 4: the paper's medoid of every cluster and each triangle's in-cluster hop distance to it
/// (members in other pieces continue the count, as [`super::capacity`] numbers them).
pub fn medoids_and_distances(dual: &Csr, labels: &[u32], k: usize) -> (Vec<u32>, Vec<u32>) {
    let mem = members(labels, k);
    let per: Vec<(u32, Vec<u32>)> = (0..k)
        .into_par_iter()
        .map(|c| medoid_of(dual, labels, c as u32, mem.row(c)))
        .collect();
    let mut distances = vec![0; labels.len()];
    let mut medoids = Vec::with_capacity(k);
    for (c, (m, d)) in per.into_iter().enumerate() {
        medoids.push(m);
        for (&t, &x) in mem.row(c).iter().zip(&d) {
            distances[t as usize] = x;
        }
    }
    (medoids, distances)
}

#[cfg(test)]
mod tests {
    use super::super::{cluster as run, Mode};
    use super::*;
    use crate::adjacency::{cluster_pieces, dual_graph, vertex_triangles};
    use crate::mesh::generate;
    use crate::meshlet::validate;

    #[test]
    fn same_output_on_any_thread_count_valid_and_within_the_limits() {
        let m = generate::knot_tube(160, 12, 3);
        for limits in [Limits::new(32, 40).unwrap(), Limits::new(8, 6).unwrap()] {
            let cfg = Config {
                region_triangles: 300,
                ..Config::default()
            };
            let go = |n| crate::test_pool(n).install(|| run(&m, limits, Mode::Regions, &cfg));
            let (a, b) = (go(1), go(4));
            assert_eq!(
                (&a.medoids, &a.labels, &a.distances),
                (&b.medoids, &b.labels, &b.distances)
            );
            assert_eq!(a.meshlets, b.meshlets);
            validate(&m, &a.meshlets, limits).unwrap();
            // Growth respects both limits: packing never had to chunk a cluster.
            assert_eq!(a.meshlets.len(), a.medoids.len());
        }
    }

    #[test]
    fn clusters_are_connected_wherever_the_mesh_is() {
        // Pieces cut by region borders, small whole pieces to pack, tiny limits and small regions.
        for g in generate::stress_set(3) {
            let dual = dual_graph(&g.mesh, &vertex_triangles(&g.mesh));
            for limits in [Limits::DEFAULT, Limits::new(8, 6).unwrap()] {
                let cfg = Config {
                    region_triangles: 700,
                    ..Config::default()
                };
                let out = run(&g.mesh, limits, Mode::Regions, &cfg);
                validate(&g.mesh, &out.meshlets, limits).unwrap();
                let k = out.medoids.len();
                for (c, (own, mesh)) in cluster_pieces(&dual, &out.labels, k).iter().enumerate() {
                    assert_eq!(own, mesh, "{} at {limits}: cluster {c}", g.name);
                }
            }
        }
    }

    /// Two strips of 8 triangles, of one piece the region cuts (so not whole), their centres
    /// along x from 0 and from `far`: cluster 0 the first, clusters 1 and 3 the second's first
    /// `len1` and the rest; cluster 2 two tetrahedra (whole pieces 1 and 2) at `tets`. Runs step
    /// 2c at 64 vertices and `mt` triangles; returns the labels and which clusters are left.
    fn pack_two_tets(
        len1: usize,
        far: u32,
        tets: [[u32; 3]; 2],
        mt: usize,
    ) -> (Vec<u32>, Vec<bool>) {
        let n = 16 + 8;
        let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut corners: Vec<[usize; 3]> = Vec::new();
        let mut centres: Vec<Centre> = Vec::new();
        let mut s = State::new(n);
        let pack = |c: [u32; 3]| [c[0] | c[1] << 16, c[2]];
        for (strip, x0) in [(0usize, 0u32), (1, far)] {
            for i in 0..8 {
                let t = 8 * strip + i;
                let v = 10 * strip + i;
                corners.push([v, v + 1, v + 2]);
                centres.push(pack([x0 + 100 * i as u32, 0, 0]));
                if i > 0 {
                    adj[t].push(t - 1);
                    adj[t - 1].push(t);
                }
                s.piece[t] = 0;
                s.label[t] = if strip == 1 && i >= len1 {
                    3
                } else {
                    strip as u32
                };
            }
        }
        for (q, c) in tets.iter().enumerate() {
            let v = 20 + 4 * q;
            let faces = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
            for (f, face) in faces.iter().enumerate() {
                let t = 16 + 4 * q + f;
                corners.push(face.map(|j| v + j));
                centres.push(pack([c[0] + f as u32, c[1], c[2]]));
                adj[t] = (0..4).filter(|&g| g != f).map(|g| 16 + 4 * q + g).collect();
                s.piece[t] = 1 + q as u32;
                s.label[t] = 2;
            }
        }
        // Piece 0 (the strips) is cut by the region; the tetrahedra are whole.
        let closed = [false, true, true];
        let nbrs = |i: usize| adj[i].clone().into_iter();
        let corner = |i: usize| corners[i];
        let mut serial = 0;
        let mut cl = Clusters {
            mem: vec![Vec::new(); 4],
            nverts: Vec::new(),
            alive: vec![true; 4],
        };
        for i in 0..n {
            cl.mem[s.label[i] as usize].push(i);
        }
        cl.nverts = (0..4)
            .map(|c| cl.vertices(&mut s, &corner, &[c], &[], &mut serial))
            .collect();
        cl.alive[3] = !cl.mem[3].is_empty();
        pack_pieces(
            &mut s,
            &mut cl,
            &nbrs,
            &corner,
            &centres,
            &closed,
            64,
            mt,
            &mut serial,
        );
        (s.label, cl.alive)
    }

    #[test]
    fn whole_pieces_join_the_nearest_clusters_with_room() {
        // Each tetrahedron beside one strip: their cluster dissolves, one into each.
        let (labels, alive) = pack_two_tets(8, 10_000, [[350, 40, 0], [10_350, 40, 0]], 126);
        assert_eq!(alive, [true, true, false, false]);
        assert_eq!(&labels[16..20], &[0; 4]);
        assert_eq!(&labels[20..24], &[1; 4]);
        // Room for one tetrahedron in strip 0: the second goes on to the nearest with room.
        let (labels, alive) = pack_two_tets(4, 700, [[0, 40, 0], [560, 40, 0]], 12);
        assert_eq!(alive, [true, true, false, true]);
        assert_eq!(&labels[16..20], &[0; 4]);
        assert_eq!(&labels[20..24], &[1; 4]);
    }

    #[test]
    fn whole_pieces_stay_where_moving_them_would_grow_the_spheres() {
        // Both tetrahedra beside strip 0, which has no room; cluster 1 has room for both but is
        // far: its sphere would grow far more than the tetrahedra's own.
        let (labels, alive) = pack_two_tets(2, 20_000, [[350, 40, 0], [360, 40, 0]], 10);
        assert_eq!(alive, [true, true, true, true]);
        assert_eq!(&labels[16..24], &[2; 8]);
        // Room for one tetrahedron only: the plan fails and nothing moves.
        let (labels, alive) = pack_two_tets(2, 400, [[350, 40, 0], [360, 40, 0]], 8);
        assert_eq!(alive, [true, true, true, true]);
        assert_eq!(&labels[16..24], &[2; 8]);
    }

    /// Step 2d on a strip of 12 triangles (triangle `t` has vertices `t, t + 1, t + 2` and
    /// neighbours `t - 1` and `t + 1`) in three clusters of four; the labels and survivors after.
    fn dissolve_strip(mv: usize, mt: usize) -> (Vec<u32>, Vec<bool>) {
        let n = 12;
        let mut s = State::new(n);
        let corner = |i: usize| [i, i + 1, i + 2];
        let nbrs = |i: usize| (i.saturating_sub(1)..(i + 2).min(n)).filter(move |&j| j != i);
        let users = |v: usize| (0..n).filter(move |&t| corner(t).contains(&v));
        let mut cl = Clusters {
            mem: vec![Vec::new(); 3],
            nverts: vec![6; 3],
            alive: vec![true; 3],
        };
        for i in 0..n {
            s.label[i] = (i / 4) as u32;
            cl.mem[i / 4].push(i);
        }
        dissolve_clusters(&mut s, &mut cl, &nbrs, &corner, &users, mv, mt);
        (s.label, cl.alive)
    }

    #[test]
    fn a_cluster_dissolves_across_its_neighbours_when_every_member_finds_room() {
        // Cluster 0 goes first: two members fit cluster 1, then triangle 1 has no cluster with
        // room beside it, so all stay. Cluster 1 then splits: 4 and 5 into cluster 0 (5 next to
        // the moved 4), 7 and 6 into cluster 2.
        let (labels, alive) = dissolve_strip(64, 6);
        assert_eq!(alive, [true, false, true]);
        assert_eq!(labels, [0, 0, 0, 0, 0, 0, 2, 2, 2, 2, 2, 2]);
        // Every move across adds a vertex to clusters already at the vertex limit: none moves.
        let (labels, alive) = dissolve_strip(6, 126);
        assert_eq!(alive, [true; 3]);
        assert_eq!(labels, [0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2]);
    }

    #[test]
    fn canonical_corners_are_shared_inside_a_region_only() {
        let m = generate::terrain(4, 1);
        let vt = vertex_triangles(&m);
        let t = m.triangle_count();
        // Two regions: the first half of the triangles and the rest.
        let region: Vec<u32> = (0..t as u32)
            .map(|x| (x as usize >= t / 2) as u32)
            .collect();
        let canon = canonical_corners(&m, &vt, &region);
        for a in 0..3 * t {
            let ka = canon[a] as usize;
            // The canonical corner is of the same vertex and region.
            assert_eq!(m.indices[ka], m.indices[a]);
            assert_eq!(region[ka / 3], region[a / 3]);
            for b in 0..3 * t {
                let same = m.indices[a] == m.indices[b] && region[a / 3] == region[b / 3];
                assert_eq!(same, canon[a] == canon[b]);
            }
        }
    }

    /// The terrain as one region with cluster 0 the ball of the first `ball` triangles in
    /// breadth-first order from triangle 300 (grown in that order), the next triangle in that
    /// order (or the first after it passing `pick`) a free pocket of cluster 0 (stamped), its
    /// other neighbours in cluster 7, and the rest free (the open side). Returns the mesh, its
    /// dual graph, the canonical corners, the state, the ball and the pocket.
    fn ball_and_pocket(
        ball: usize,
        pick: impl Fn(&Mesh, &[u32], u32) -> bool,
    ) -> (Mesh, Csr, Vec<u32>, State, Vec<usize>, usize) {
        let m = generate::terrain(24, 5);
        let vt = vertex_triangles(&m);
        let dual = dual_graph(&m, &vt);
        let t = m.triangle_count();
        let canon = canonical_corners(&m, &vt, &vec![0; t]);
        let mut order = vec![300u32];
        let mut seen = vec![false; t];
        seen[300] = true;
        let mut i = 0;
        while order.len() < ball + 100 {
            for &x in dual.row(order[i] as usize) {
                if !seen[x as usize] {
                    seen[x as usize] = true;
                    order.push(x);
                }
            }
            i += 1;
        }
        let pocket = *order[ball..]
            .iter()
            .find(|&&x| pick(&m, &order[..ball], x))
            .unwrap() as usize;
        let mut s = State::new(t);
        // One piece: the whole terrain.
        s.piece.fill(0);
        let grown: Vec<usize> = order[..ball].iter().map(|&x| x as usize).collect();
        for (p, &g) in grown.iter().enumerate() {
            s.label[g] = 0;
            s.aux[g] = p as u32;
        }
        for &x in dual.row(pocket) {
            if s.label[x as usize] == NONE {
                s.label[x as usize] = 7;
            }
        }
        s.aux[pocket] = 1;
        (m, dual, canon, s, grown, pocket)
    }

    /// Runs the front rule for cluster 0 on [`ball_and_pocket`]'s state.
    fn front(
        dual: &Csr,
        canon: &[u32],
        s: &mut State,
        grown: &mut Vec<usize>,
        pocket: usize,
        limits: Limits,
    ) -> Option<Vec<usize>> {
        let nbrs = |i: usize| dual.row(i).iter().map(|&x| x as usize);
        let corners = |i: usize| [0, 1, 2].map(|j| canon[3 * i + j] as usize);
        let (mv, mt) = (limits.max_vertices as usize, limits.max_triangles as usize);
        shed_front(s, &nbrs, &corners, grown, &[pocket], 0, mv, mt, &mut 0)
    }

    /// Checks what the front rule promises after taking `pocket`: the given-back triangles are
    /// free, none next to the pocket; the pocket joined; the cluster within `limits`, one piece.
    fn check_taken(
        m: &Mesh,
        dual: &Csr,
        s: &State,
        grown: &[usize],
        pocket: usize,
        shed: &[usize],
        limits: Limits,
    ) {
        assert!(!shed.is_empty());
        for &x in shed {
            assert_eq!(s.label[x], NONE);
            assert!(!dual.row(x).contains(&(pocket as u32)));
        }
        assert_eq!(s.label[pocket], 0);
        let members: Vec<usize> = (0..m.triangle_count())
            .filter(|&x| s.label[x] == 0)
            .collect();
        let mut sorted = grown.to_vec();
        sorted.sort_unstable();
        assert_eq!(sorted, members);
        let mut verts: Vec<u32> = members.iter().flat_map(|&x| m.triangle(x)).collect();
        verts.sort_unstable();
        verts.dedup();
        assert!(members.len() <= limits.max_triangles as usize);
        assert!(verts.len() <= limits.max_vertices as usize);
        let two: Vec<u32> = s.label.iter().map(|&l| (l != 0) as u32).collect();
        assert_eq!(cluster_pieces(dual, &two, 2)[0], (1, 1));
    }

    #[test]
    fn a_pocket_by_the_front_is_taken_for_triangles_given_back_at_the_open_side() {
        // Triangle limit: the ball holds 126, one triangle on the open side goes.
        let limits = Limits::new(255, 126).unwrap();
        let (m, dual, canon, mut s, mut grown, pocket) = ball_and_pocket(126, |_, _, _| true);
        let shed = front(&dual, &canon, &mut s, &mut grown, pocket, limits).expect("fits");
        assert_eq!(shed.len(), 1);
        assert!(dual
            .row(shed[0])
            .iter()
            .any(|&x| s.label[x as usize] == NONE));
        check_taken(&m, &dual, &s, &grown, pocket, &shed, limits);
        // Vertex limit: the ball holds exactly the limit and the pocket adds a vertex.
        let uses_new = |m: &Mesh, ball: &[u32], x: u32| {
            let inside: Vec<u32> = ball.iter().flat_map(|&b| m.triangle(b as usize)).collect();
            m.triangle(x as usize).iter().any(|v| !inside.contains(v))
        };
        let (m, dual, canon, mut s, mut grown, pocket) = ball_and_pocket(126, uses_new);
        let mut verts: Vec<u32> = grown.iter().flat_map(|&x| m.triangle(x)).collect();
        verts.sort_unstable();
        verts.dedup();
        let limits = Limits::new(verts.len() as u32, 255).unwrap();
        let shed = front(&dual, &canon, &mut s, &mut grown, pocket, limits).expect("fits");
        check_taken(&m, &dual, &s, &grown, pocket, &shed, limits);
    }

    #[test]
    fn the_front_rule_gives_back_at_most_half_and_otherwise_changes_nothing() {
        // Room for the pocket needs 67 of the 126 triangles back: more than half.
        let limits = Limits::new(255, 60).unwrap();
        let (_, dual, canon, mut s, mut grown, pocket) = ball_and_pocket(126, |_, _, _| true);
        let before = (s.label.clone(), s.aux.clone(), grown.clone());
        assert!(front(&dual, &canon, &mut s, &mut grown, pocket, limits).is_none());
        assert_eq!((s.label, s.aux, grown), before);
    }

    #[test]
    fn a_packing_cluster_goes_on_at_the_nearest_piece_not_the_next() {
        // Three quads written near, far, near: a cluster holds two, and the first quad's cluster
        // takes the third (near it), not the second (next in the seed order).
        let quad = |x: f32, base: u32| {
            let p = [
                [x, 0.0, 0.0],
                [x + 1.0, 0.0, 0.0],
                [x + 1.0, 1.0, 0.0],
                [x, 1.0, 0.0],
            ];
            let i = [0, 1, 2, 0, 2, 3].map(|v| base + v);
            (p, i)
        };
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        for (q, x) in [0.0, 100.0, 2.0].into_iter().enumerate() {
            let (p, i) = quad(x, 4 * q as u32);
            positions.extend(p);
            indices.extend(i);
        }
        let m = Mesh::from_slices(&positions, &indices, "three quads").unwrap();
        let limits = Limits::new(8, 4).unwrap();
        let out = run(&m, limits, Mode::Regions, &Config::default());
        validate(&m, &out.meshlets, limits).unwrap();
        let l = &out.labels;
        assert_eq!((l[0], l[1], l[4], l[5]), (l[0], l[0], l[0], l[0]));
        assert_eq!(l[2], l[3]);
        assert_ne!(l[0], l[2]);
    }

    #[test]
    fn a_small_grid_is_covered_within_two_meshlets_of_the_triangle_bound() {
        // A 9 x 9 grid of quads at 8 triangles per meshlet: growth, pockets and merges together
        // leave at most two meshlets beyond the fewest any partition can have.
        let m = generate::terrain(10, 1);
        let limits = Limits::new(64, 8).unwrap();
        let cfg = Config::default();
        let out = run(&m, limits, Mode::Regions, &cfg);
        validate(&m, &out.meshlets, limits).unwrap();
        assert!(out.meshlets.len() <= limits.min_meshlets(m.triangle_count()) + 2);
    }
}
