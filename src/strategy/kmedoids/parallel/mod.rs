//! `kmedoids-parallel`: the region-parallel k-medoids, every step a kernel (CPU reference of
//! `wgsl/kmedoids_parallel.wgsl` and `wgsl/kmedoids_parallel_moves.wgsl`, driven on the GPU by
//! `gpu::kmedoids_parallel`).
//!
//! The sequential method ([`super::sequential`]) grows one cluster at a time by keys that divide
//! (the running centroid), and its merges and piece packing sort and allocate, so no kernel runs
//! it. This method cuts the mesh into coarse regions and grows each with integer keys, linear
//! scans and fixed arrays, which a kernel runs line for line. One file per step:
//! [`mod@grow`] (step 2's growth), [`pockets`], [`mod@pack`] (piece packing), [`merge`],
//! [`dissolve`], [`moves`] (step 5); [`region`] holds the context they share.
//!
//! 1. **Regions**: [`super::coarse`] (the Morton-seeded multi-source BFS).
//! 2. **Growth per region**, one invocation each ([`grow::grow_region`]):
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
//!      [`pack::PACK_WINDOW`] pieces in seed order, the one whose seed is nearest the cluster's centre
//!      and fits, if it is a whole piece of the mesh (one the region's border cuts could put the
//!      cluster in two parts of one mesh piece). Taking the next piece instead packed pieces far
//!      apart where a lattice's struts come in rows;
//!    - when a cluster stops, free pockets next to it of at most half the triangle limit are
//!      absorbed, largest first, if giving back its last-grown triangles (at most half of them)
//!      makes room: the pocket would otherwise become a meshlet of its own; each pocket that
//!      rule cannot take is tried by the front rule (`pockets::shed_front`), which gives back the
//!      triangles nearest the open free side instead;
//!    - then clusters merge into a neighbour across an edge whose union fits, smallest first
//!      (what tube ends and enclosed leftovers need: on the neurons a sixth fewer meshlets);
//!    - then a cluster made only of whole small pieces is dissolved into the clusters nearest
//!      its pieces that have room, where the targets' bounding radii grow by no more, summed,
//!      than its own (`pack::pack_pieces`): the growth packs pieces only into a cluster whose own
//!      piece ran out, so detached pieces seeded among a large piece's clusters would otherwise
//!      stay meshlets of their own;
//!    - then a cluster whose members all find room in the clusters across its edges is dissolved
//!      into them, smallest first, member by member from its border inwards
//!      (`dissolve::dissolve_clusters`): the merges move a cluster whole into one neighbour, while on
//!      branching tubes a cluster between two part-filled ones often fits neither alone but
//!      splits across both.
//! 3. **Labels**: cluster `c` of region `r` is `base[r] + c`, regions in order.
//! 4. **Medoids**: the paper's medoid of each cluster and its members' in-cluster hop distances
//!    (one invocation per cluster on the GPU), which order the members when packing.
//! 5. **Medoid iteration**: [`moves`]' boundary moves
//!    (`wgsl/kmedoids_parallel_moves.wgsl` on the GPU): border triangles move to a neighbouring cluster whose
//!    medoid is nearer while the limits hold, then changed clusters take the paper's medoid
//!    again. The objective falls and the count stays.
//!
//! Where it differs from the paper (section 3): k comes out of the growth, nothing is split, and
//! the iteration moves only border triangles, within the limits (the growth keys, not
//! nearest-medoid assignment, shape the clusters). Every
//! cluster is edge-connected except where small whole pieces are packed together. Determinism:
//! regions share no state and every choice is a strict minimum over integer keys (the moves'
//! sums are order-independent), so the result is the same for any thread count and on the GPU.
//!
//! A vertex is tracked through its canonical corner in the region ([`canonical_corners`]): the
//! first corner, in triangle order, of the region's lowest triangle using it. Per-corner state
//! then needs no per-region vertex numbering, and two regions sharing a vertex never touch the
//! same word (which a kernel needs: regions run concurrently).

pub mod dissolve;
pub mod grow;
pub mod layout;
pub mod merge;
pub mod moves;
pub mod pack;
pub mod pockets;
pub mod region;

pub use grow::grow_region;
pub use pack::PACK_WINDOW;

use super::assign::{members, UNREACHED};
use super::coarse::regions;
use super::local_graph::medoids_and_distances;
use super::morton::{packed_centres, Centre};
use super::{pack, Clustering, Grown};
use crate::common::Csr;
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlets};
use moves::{move_boundaries, Moves};
use rayon::prelude::*;
use std::time::Instant;

/// The "no value" word of the region's arrays (free, not on a frontier, no piece yet).
const NONE: u32 = UNREACHED;

/// Triangles per region by default: on the shared meshes, regions of this size cost about a
/// percent of meshlets over one region per mesh while leaving dozens of regions from a million
/// triangles up (the region-size sweep of `meshletlab bench kmedoids`).
pub const DEFAULT_REGION_TRIANGLES: u32 = 16384;

/// Rounds of boundary moves by default: two take the objective (mean hop distance to the medoid)
/// below the sequential method's on the shared meshes, where later rounds gain less for the same
/// cost (the move-round sweep of `meshletlab bench kmedoids`).
pub const DEFAULT_MOVE_ROUNDS: u32 = 2;

/// Settings of `kmedoids-parallel`, the same on the CPU and the GPU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Triangles per region (step 1), each grown on its own, all at once: smaller regions give
    /// more parallel work and more part-filled clusters at their borders
    /// ([`DEFAULT_REGION_TRIANGLES`]).
    pub region_triangles: u32,
    /// Most rounds of boundary moves (step 5, [`moves`]): the medoid iteration that lowers the
    /// objective without changing the count; the first rounds gain the most
    /// ([`DEFAULT_MOVE_ROUNDS`]).
    pub move_rounds: u32,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            region_triangles: DEFAULT_REGION_TRIANGLES,
            move_rounds: DEFAULT_MOVE_ROUNDS,
        }
    }
}

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
    /// [`packed_centres`]: the fine centroid cells.
    pub centres: &'a [Centre],
    /// Meshlet limits.
    pub limits: Limits,
}

#[cfg(test)]
mod tests {
    use super::super::{cluster as run_with, Mode};
    use super::dissolve::dissolve_clusters;
    use super::pack::pack_pieces;
    use super::pockets::shed_front;
    use super::region::{Clusters, Region, State};
    use super::*;
    use crate::adjacency::{cluster_pieces, dual_graph, vertex_triangles};
    use crate::mesh::generate;
    use crate::meshlet::validate;

    /// `kmedoids-parallel` on `m` with `cfg`.
    fn run(m: &Mesh, limits: Limits, cfg: &Config) -> Clustering {
        let family = super::super::Config {
            parallel: *cfg,
            ..Default::default()
        };
        run_with(m, limits, Mode::Parallel, &family)
    }

    /// A region from adjacency lists, canonical corners and cells, at `mv` / `mt`.
    fn region_of(
        adj: &[Vec<usize>],
        corners: Vec<[usize; 3]>,
        cells: Vec<Centre>,
        mv: usize,
        mt: usize,
    ) -> Region {
        let pairs = adj
            .iter()
            .enumerate()
            .flat_map(|(i, row)| row.iter().map(move |&j| (i as u32, j as u32)));
        let dual = Csr::from_pairs(adj.len(), pairs);
        let limits = Limits::new(mv as u32, mt as u32).unwrap();
        Region::new(dual, corners, cells, vec![true; adj.len()], limits)
    }

    #[test]
    fn same_output_on_any_thread_count_valid_and_within_the_limits() {
        let m = generate::knot_tube(160, 12, 3);
        for limits in [Limits::new(32, 40).unwrap(), Limits::new(8, 6).unwrap()] {
            let cfg = Config {
                region_triangles: 300,
                ..Config::default()
            };
            let go = |n| crate::test_pool(n).install(|| run(&m, limits, &cfg));
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
                let out = run(&g.mesh, limits, &cfg);
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
        // Adjacency lists ascend, as dual-graph rows do.
        for row in &mut adj {
            row.sort_unstable();
        }
        let g = region_of(&adj, corners, centres, 64, mt);
        let mut cl = Clusters {
            mem: vec![Vec::new(); 4],
            nverts: Vec::new(),
            alive: vec![true; 4],
        };
        for i in 0..n {
            cl.mem[s.label[i] as usize].push(i);
        }
        cl.nverts = (0..4).map(|c| cl.vertices(&g, &mut s, &[c], &[])).collect();
        cl.alive[3] = !cl.mem[3].is_empty();
        pack_pieces(&g, &mut s, &mut cl, &closed);
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
        let corners = (0..n).map(|i| [i, i + 1, i + 2]).collect();
        let adj: Vec<Vec<usize>> = (0..n)
            .map(|i| {
                (i.saturating_sub(1)..(i + 2).min(n))
                    .filter(|&j| j != i)
                    .collect()
            })
            .collect();
        let g = region_of(&adj, corners, vec![[0, 0]; n], mv, mt);
        let mut cl = Clusters {
            mem: vec![Vec::new(); 3],
            nverts: vec![6; 3],
            alive: vec![true; 3],
        };
        for i in 0..n {
            s.label[i] = (i / 4) as u32;
            cl.mem[i / 4].push(i);
        }
        dissolve_clusters(&g, &mut s, &mut cl);
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
        let t = dual.rows();
        let corners = (0..t)
            .map(|i| [0, 1, 2].map(|j| canon[3 * i + j] as usize))
            .collect();
        let g = Region::new(
            dual.clone(),
            corners,
            vec![[0, 0]; t],
            vec![true; t],
            limits,
        );
        shed_front(&g, s, grown, &[pocket], 0)
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
        let out = run(&m, limits, &Config::default());
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
        let out = run(&m, limits, &cfg);
        validate(&m, &out.meshlets, limits).unwrap();
        assert!(out.meshlets.len() <= limits.min_meshlets(m.triangle_count()) + 2);
    }
}
