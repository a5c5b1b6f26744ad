//! The coarse regions that `kmedoids-parallel` clusters at once (CPU
//! reference of `wgsl/coarse.wgsl`, driven on the GPU by `gpu::coarse`).
//!
//! The flat method's seeding and assignment ([`super::flat`], [`mod@super::assign`]) at a coarse
//! scale, about `size` triangles per region:
//!
//! 1. **Seeds**: the Morton order of centroids ([`morton_order`]) cut into `k = ceil(T / size)`
//!    runs; the middle triangle of run `j` seeds region candidate `j`.
//! 2. **One multi-source BFS** from the seeds in ascending order: a triangle's region is its
//!    nearest seed's position in that order (ties to the lower). Every region is edge-connected
//!    and holds its seed, so none is empty.
//! 3. **Pieces no seed reaches** (small pieces of the mesh): a piece joins the region of the run
//!    its first triangle in Morton order falls in, so nearby small pieces share a region and the
//!    per-region method packs them together (a region per piece would leave one part-filled
//!    cluster per piece). The kernel finds each piece's first rank by min-label hooking; any
//!    method that finds the minimum gives the same regions.
//!
//! Determinism: the Morton order breaks ties by id, the BFS by seed position, and a minimum does
//! not depend on the order it is taken in.

use super::assign::{assign, UNREACHED};
use super::morton::morton_order;
use crate::adjacency::pieces;
use crate::common::{sorted, Csr};
use crate::mesh::Mesh;

/// Regions of about `size` triangles for `t` triangles (at least one).
pub fn region_count(t: usize, size: usize) -> usize {
    t.div_ceil(size.max(1)).max(1)
}

/// Rank in the Morton order of run `j`'s seed: the middle of the run (`k` runs over `t`).
pub fn seed_rank(j: usize, t: usize, k: usize) -> usize {
    (j * t + t / 2) / k
}

/// The run the Morton rank `i` falls in (`k` runs over `t`).
pub fn run_of(i: usize, t: usize, k: usize) -> usize {
    i * k / t
}

/// The region of every triangle and the region count (steps 1-3).
pub fn regions(mesh: &Mesh, dual: &Csr, size: usize) -> (Vec<u32>, usize) {
    let t = mesh.triangle_count();
    if t == 0 {
        return (Vec::new(), 0);
    }
    let k = region_count(t, size);
    if k == 1 {
        // One region: no BFS (its levels are many tiny parallel steps on a long thin mesh).
        return (vec![0; t], 1);
    }
    let order = morton_order(mesh);
    let seeds: Vec<u32> = (0..k).map(|j| order[seed_rank(j, t, k)]).collect();
    let (mut labels, _) = assign(dual, &sorted(seeds.clone()));
    if labels.contains(&UNREACHED) {
        // Step 3: the first triangle of each unreached piece in Morton order decides its run.
        let piece = pieces(dual);
        let mut region_of_piece = vec![UNREACHED; t];
        for (i, &x) in order.iter().enumerate() {
            let p = piece[x as usize] as usize;
            if labels[x as usize] == UNREACHED && region_of_piece[p] == UNREACHED {
                // Run j's region is the label its seed took (seeds are distinct triangles).
                region_of_piece[p] = labels[seeds[run_of(i, t, k)] as usize];
            }
        }
        for (l, &p) in labels.iter_mut().zip(&piece) {
            if *l == UNREACHED {
                *l = region_of_piece[p as usize];
            }
        }
    }
    (labels, k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_of_inverts_the_seed_ranks_and_runs_cover_every_rank() {
        for (t, k) in [(10, 3), (7, 7), (100_003, 17), (5, 1)] {
            for j in 0..k {
                assert_eq!(run_of(seed_rank(j, t, k), t, k), j, "t {t} k {k}");
            }
            let runs: Vec<usize> = (0..t).map(|i| run_of(i, t, k)).collect();
            assert!(runs.windows(2).all(|w| w[1] == w[0] || w[1] == w[0] + 1));
            assert_eq!((runs[0], runs[t - 1]), (0, k - 1));
        }
    }

    #[test]
    fn unreached_pieces_join_the_run_of_their_first_morton_triangle() {
        // Ten separate triangles in a row: two seeds reach only themselves, and every other
        // triangle (a piece of its own) joins the run its Morton rank falls in.
        let mut mesh = Mesh::empty();
        for i in 0..10u32 {
            let x = i as f32 * 3.0;
            mesh.positions
                .extend([[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]]);
            mesh.indices.extend([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let dual = crate::adjacency::dual_graph(&mesh, &crate::adjacency::vertex_triangles(&mesh));
        let (region, k) = regions(&mesh, &dual, 5);
        assert_eq!(k, 2);
        let order = morton_order(&mesh);
        for (i, &x) in order.iter().enumerate() {
            assert_eq!(region[x as usize], run_of(i, 10, 2) as u32, "rank {i}");
        }
    }
}
