//! `bsphere-parallel`: the parallel-clustering experiment. Many meshlets grow at once, each by the
//! bounding-sphere grower's rule, and compete for triangles through claims. This file is the CPU
//! reference of exactly the algorithm in `wgsl/grow.wgsl` (driver: `gpu::grow`); both give
//! identical owners, orders and meshlets.
//!
//! **Waves.** A wave seeds meshlets on unclaimed triangles: the triangle nearest the centre of each
//! cell of a uniform grid (cells sized to hold about one meshlet, so seeds are spatially
//! separated), and from the second wave on also the lowest triangle of every unclaimed connected
//! component (so gaps and small islands get a seed even inside an already-seeded cell). Meshlet
//! ids follow the seed's triangle id within a wave and increase from wave to wave.
//!
//! **Rounds.** In each round every open meshlet (1) accepts last round's proposal if its claim
//! won, (2) scores its border, the unclaimed edge neighbours of its triangles, in parallel: the
//! `bsphere` score (vertices inside, +1 if the candidate closes an island), ties to the smaller
//! new radius, then the lower triangle id, and proposes the best that fits; a meshlet with
//! nothing to propose closes. (3) Every proposal claims its triangle with `atomicMin` on the
//! meshlet id, so the lowest id wins a conflict whatever the thread order; losers propose again.
//!
//! **Exact radius.** `bsphere`'s Ritter sphere needs a square root, which WGSL only bounds to
//! a few ulps, so a tie between two radii could break differently on two GPUs. Here the sphere's
//! centre is fixed at the seed's first vertex and the "radius" is the largest squared distance to
//! it in 15-bit quantised coordinates: an exact u32 on every device. A fixed centre also makes a
//! meshlet grow round about its seed, which is what the spatially separated seeds want.

use super::Strategy;
use crate::adjacency::{dual_graph, vertex_triangles, Csr};
use crate::common::{distinct, NONE};
use crate::mesh::Mesh;
use crate::meshlet::assemble::assemble;
use crate::meshlet::{Limits, Meshlets};
use rayon::prelude::*;
use std::collections::HashMap;

/// The parallel grower as a strategy (the CPU reference).
pub struct ParallelGrower {
    /// Seed spacing in meshlets per grid cell ([`DEFAULT_SPACING`]).
    pub spacing: f64,
}

impl Strategy for ParallelGrower {
    fn name(&self) -> &'static str {
        "bsphere-parallel"
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let dual = dual_graph(mesh, &vertex_triangles(mesh));
        grow(mesh, &dual, limits, self.spacing).meshlets
    }
}

/// Seed spacing of the strategy, in meshlets per grid cell. The trade-off of the experiment: one
/// seed per meshlet's worth of surface runs in the fewest rounds but leaves many slivers between
/// meshlets that grew into each other; sparser seeds leave bigger gaps that later waves fill whole
/// (fewer, fuller meshlets, more waves and rounds). `bench gpu` sweeps it (results/gpu.md).
pub const DEFAULT_SPACING: f64 = 4.0;

/// Largest quantised coordinate (15 bits): squared distances of three axes fit a u32.
pub const QMAX: u32 = 32_767;
/// Most grid cells (two u32 each on the GPU: 64 MiB).
pub const MAX_CELLS: u64 = 1 << 23;

/// The inputs both sides share, computed once on the host.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Setup {
    /// Quantised positions, three per vertex, each in 0..=QMAX.
    pub q: Vec<u32>,
    /// Grid cell side in quantised units.
    pub cell: u32,
    /// Cells per axis.
    pub grid: u32,
}

impl Setup {
    /// Quantises `mesh` and sizes the grid so that a cell holds about `spacing` meshlets of
    /// `limits`.
    pub fn new(mesh: &Mesh, limits: Limits, spacing: f64) -> Self {
        let (lo, hi) = mesh.bounding_box();
        let ext = (hi - lo).max_element() as f64;
        let scale = if ext > 0.0 { QMAX as f64 / ext } else { 0.0 };
        let q: Vec<u32> = mesh
            .positions
            .iter()
            .flat_map(|p| {
                (0..3)
                    .map(move |k| (((p[k] as f64 - lo[k] as f64) * scale).round() as u32).min(QMAX))
            })
            .collect();
        // Mean triangle area in quantised units; a cell of side s crossed by a surface holds about
        // s^2 of it. The unit target is what one meshlet of these limits holds on a closed manifold
        // (about two triangles per vertex); `spacing` scales it (see [`DEFAULT_SPACING`]).
        let t = mesh.triangle_count().max(1) as f64;
        let area: f64 = (0..mesh.triangle_count())
            .map(|i| {
                let [a, b, c] = mesh.triangle(i).map(|v| {
                    let o = 3 * v as usize;
                    glam::DVec3::new(q[o] as f64, q[o + 1] as f64, q[o + 2] as f64)
                });
                (b - a).cross(c - a).length() * 0.5
            })
            .sum();
        let target = limits.max_triangles.min(2 * limits.max_vertices) as f64 * spacing;
        let mut cell = ((area / t * target).sqrt().round() as u32).clamp(1, 16_384);
        // Keep the grid within MAX_CELLS (big meshes get bigger cells and more waves).
        while ((QMAX / cell + 1) as u64).pow(3) > MAX_CELLS {
            cell += cell.div_ceil(8);
        }
        Self {
            grid: QMAX / cell + 1,
            q,
            cell,
        }
    }

    /// Quantised position of `v`.
    #[inline]
    fn pos(&self, v: u32) -> [u32; 3] {
        let o = 3 * v as usize;
        [self.q[o], self.q[o + 1], self.q[o + 2]]
    }

    /// Squared distance between the quantised positions of `a` and `b` (exact; at most 3 * QMAX^2).
    #[inline]
    pub fn d2(&self, a: u32, b: u32) -> u32 {
        let (pa, pb) = (self.pos(a), self.pos(b));
        (0..3).map(|k| pa[k].abs_diff(pb[k]).pow(2)).sum()
    }

    /// Grid cell of triangle `tri` and the squared distance (in units of a third) from its
    /// centroid to the cell's centre: integers, as on the GPU.
    pub fn cell_of(&self, tri: [u32; 3]) -> (u32, u32) {
        let s3 = 3 * self.cell;
        let mut cell = 0u32;
        let mut d2 = 0u32;
        for k in 0..3 {
            let c3: u32 = tri.iter().map(|&v| self.q[3 * v as usize + k]).sum();
            let i = c3 / s3;
            d2 += c3.abs_diff(i * s3 + s3 / 2).pow(2);
            cell = cell * self.grid + i;
        }
        (cell, d2)
    }
}

/// Whether the key (score, r2, t) beats (score', r2', t'): higher score, then smaller radius, then
/// lower id.
#[inline]
pub fn better(a: (u32, u32, u32), b: (u32, u32, u32)) -> bool {
    a.0 > b.0 || (a.0 == b.0 && (a.1 < b.1 || (a.1 == b.1 && a.2 < b.2)))
}

/// The result of a run: per triangle its meshlet and its position in it, and the meshlets.
#[derive(Clone, Debug)]
pub struct Growth {
    /// Meshlet of every triangle.
    pub owner: Vec<u32>,
    /// Position of every triangle in its meshlet (acceptance order).
    pub order: Vec<u32>,
    /// Meshlets in id order.
    pub meshlets: Meshlets,
    /// Waves run.
    pub waves: u32,
    /// Growth rounds run over all waves.
    pub rounds: u32,
}

/// One growing meshlet.
struct Open {
    id: u32,
    tris: Vec<u32>,
    verts: Vec<u32>,
    centre: u32,
    r2: u32,
    proposal: u32,
    open: bool,
}

impl Open {
    fn new(id: u32, seed: u32, mesh: &Mesh, s: &Setup) -> Self {
        let tri = mesh.triangle(seed as usize);
        let verts: Vec<u32> = distinct(tri).collect();
        let r2 = verts.iter().map(|&v| s.d2(tri[0], v)).max().unwrap_or(0);
        Self {
            id,
            tris: vec![seed],
            verts,
            centre: tri[0],
            r2,
            proposal: NONE,
            open: true,
        }
    }

    /// One round's steps (1) and (2) for this meshlet; mirrors the `propose` kernel.
    fn step(&mut self, mesh: &Mesh, dual: &Csr, s: &Setup, owner: &[u32], limits: Limits) {
        let p = std::mem::replace(&mut self.proposal, NONE);
        if p != NONE && owner[p as usize] == self.id {
            self.tris.push(p);
            for v in distinct(mesh.triangle(p as usize)) {
                if !self.verts.contains(&v) {
                    self.verts.push(v);
                    self.r2 = self.r2.max(s.d2(self.centre, v));
                }
            }
        }
        let (nt, nv) = (self.tris.len() as u32, self.verts.len() as u32);
        let mut best = (0, NONE, NONE);
        for &t in &self.tris {
            for &n in dual.row(t as usize) {
                if owner[n as usize] != NONE {
                    continue;
                }
                let (mut inside, mut count, mut r2) = (0, 0, self.r2);
                for v in distinct(mesh.triangle(n as usize)) {
                    count += 1;
                    if self.verts.contains(&v) {
                        inside += 1;
                    } else {
                        r2 = r2.max(s.d2(self.centre, v));
                    }
                }
                if nt >= limits.max_triangles || nv + count - inside > limits.max_vertices {
                    continue;
                }
                let island = dual
                    .row(n as usize)
                    .iter()
                    .all(|&x| owner[x as usize] == self.id);
                let key = (inside + island as u32, r2, n);
                if better(key, best) {
                    best = key;
                }
            }
        }
        self.proposal = best.2;
        self.open = best.2 != NONE;
    }
}

/// Seeds of the next wave (ascending triangle ids): grid-cell nearest unclaimed triangles, and
/// from the second wave on component minima.
pub fn seeds(mesh: &Mesh, dual: &Csr, s: &Setup, owner: &[u32], first: bool) -> Vec<u32> {
    let t = mesh.triangle_count();
    let mut best: HashMap<u32, (u32, u32)> = HashMap::new();
    for i in (0..t).filter(|&i| owner[i] == NONE) {
        let (cell, d2) = s.cell_of(mesh.triangle(i));
        let e = best.entry(cell).or_insert((u32::MAX, NONE));
        *e = (*e).min((d2, i as u32));
    }
    let mut seed = vec![false; t];
    for &(_, i) in best.values() {
        seed[i as usize] = true;
    }
    if !first {
        // Component minima: a flood from each unclaimed triangle in ascending order reaches its
        // component first from the component's lowest id.
        let mut seen = vec![false; t];
        let mut stack = Vec::new();
        for i in 0..t {
            if owner[i] != NONE || seen[i] {
                continue;
            }
            seed[i] = true;
            seen[i] = true;
            stack.push(i as u32);
            while let Some(x) = stack.pop() {
                for &n in dual.row(x as usize) {
                    if owner[n as usize] == NONE && !seen[n as usize] {
                        seen[n as usize] = true;
                        stack.push(n);
                    }
                }
            }
        }
    }
    (0..t as u32).filter(|&i| seed[i as usize]).collect()
}

/// Runs the parallel grower (rounds in parallel over meshlets with rayon; the result does not
/// depend on the thread count, since a round reads only the previous round's claims).
pub fn grow(mesh: &Mesh, dual: &Csr, limits: Limits, spacing: f64) -> Growth {
    let s = Setup::new(mesh, limits, spacing);
    let t = mesh.triangle_count();
    let mut owner = vec![NONE; t];
    let mut order = vec![0u32; t];
    let (mut base, mut waves, mut rounds) = (0u32, 0u32, 0u32);
    loop {
        let seeds = seeds(mesh, dual, &s, &owner, waves == 0);
        if seeds.is_empty() {
            break;
        }
        let mut open: Vec<Open> = seeds
            .iter()
            .enumerate()
            .map(|(j, &seed)| {
                owner[seed as usize] = base + j as u32;
                Open::new(base + j as u32, seed, mesh, &s)
            })
            .collect();
        loop {
            open.par_iter_mut()
                .filter(|m| m.open)
                .for_each(|m| m.step(mesh, dual, &s, &owner, limits));
            rounds += 1;
            let mut proposals = 0;
            for m in open.iter().filter(|m| m.proposal != NONE) {
                let o = &mut owner[m.proposal as usize];
                *o = (*o).min(m.id);
                proposals += 1;
            }
            if proposals == 0 {
                break;
            }
        }
        for m in &open {
            for (i, &tri) in m.tris.iter().enumerate() {
                order[tri as usize] = i as u32;
            }
        }
        base += seeds.len() as u32;
        waves += 1;
    }
    let meshlets = assemble(mesh, &owner, &order, base as usize, limits);
    Growth {
        owner,
        order,
        meshlets,
        waves,
        rounds,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::validate;

    #[test]
    fn covers_every_triangle_within_limits_and_is_deterministic() {
        let mesh = generate::noisy_sphere(4, 0.2, 7);
        let dual = dual_graph(&mesh, &vertex_triangles(&mesh));
        for limits in Limits::PRESETS {
            let g = crate::test_pool(4).install(|| grow(&mesh, &dual, limits, DEFAULT_SPACING));
            validate(&mesh, &g.meshlets, limits).unwrap();
            assert!(g.owner.iter().all(|&o| o != NONE));
            assert!(g.waves >= 1 && g.rounds as usize >= limits.max_triangles as usize / 2);
            // The same run on one thread gives the same result.
            let one = crate::test_pool(1).install(|| grow(&mesh, &dual, limits, DEFAULT_SPACING));
            assert_eq!(one.owner, g.owner);
            assert_eq!(one.order, g.order);
        }
    }

    #[test]
    fn meshlets_are_edge_connected() {
        // Growth only follows dual edges and a meshlet never takes a triangle it did not win, so
        // every meshlet is one edge-connected piece.
        let mesh = generate::knot_tube(96, 12, 3);
        let dual = dual_graph(&mesh, &vertex_triangles(&mesh));
        let g = grow(&mesh, &dual, Limits::DEFAULT, DEFAULT_SPACING);
        validate(&mesh, &g.meshlets, Limits::DEFAULT).unwrap();
        for i in 0..g.meshlets.len() {
            assert!(crate::meshlet::metrics::is_edge_connected(
                g.meshlets.meshlet_triangles(i)
            ));
        }
    }

    #[test]
    fn cell_distances_fit_u32() {
        let mesh = generate::terrain(8, 1);
        let mut s = Setup::new(&mesh, Limits::DEFAULT, 1.0);
        s.cell = 16_384;
        s.grid = QMAX / s.cell + 1;
        let far = [0u32; 3];
        // The worst centroid in a full-size cell is half a cell (in thirds) from the centre.
        let (_, d2) = s.cell_of(far);
        assert!(d2 <= 3 * (3 * 16_384u32 / 2).pow(2));
    }
}
