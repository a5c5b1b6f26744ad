//! Step 2 of `partition`: the global re-partition, balanced geodesic Lloyd over the dual graph.
//! Cells grown all at once from central seeds get shorter boundaries than cells grown one after
//! another into the space their predecessors left, and shorter boundaries are what make room for
//! fewer meshlets. Additive weights steer the cells towards equal vertex counts; the Dijkstra
//! settles a band of distances at a time in triangle order, so it sweeps memory instead of
//! jumping across the mesh.

use super::Config;
use crate::strategy::refine::state::{vertex_counts, Search};
use glam::DVec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Step 2: balanced geodesic Lloyd from the current cells; the new label of every triangle.
pub(super) fn lloyd(s: &Search, config: Config, dropped: usize) -> Vec<u32> {
    let p = &s.cells;
    let n = p.label.len();
    let k = p.tcount.len();
    // The features start with the centroid, scaled to unit spread: scale-free distances.
    let pos: Vec<DVec3> = p
        .features
        .iter()
        .map(|f| DVec3::new(f[0], f[1], f[2]))
        .collect();
    // Arcs (neighbour, centroid distance) once, in the dual graph's item order: the search reads
    // a triangle's neighbours and lengths from one cache line.
    let mut arcs = Vec::with_capacity(p.dual.items.len());
    for t in 0..n {
        for &u in p.dual.row(t) {
            arcs.push((u, pos[t].distance(pos[u as usize]) as f32));
        }
    }
    let h = arcs.iter().map(|a| a.1 as f64).sum::<f64>() / arcs.len().max(1) as f64;
    let mut label = p.label.clone();
    let mut weight = vec![0.0f64; k];
    let target = p.limits.max_vertices as f64 - 1.0;
    for it in 0..config.lloyd_iterations {
        // The weights start at 0 and follow the previous step's cells.
        if it > 0 {
            let vc = vertex_counts(p.vt, &label, k);
            for c in 0..k {
                weight[c] += config.balance_step * h * (vc[c] as f64 - target);
            }
        }
        let mut seeds = central_triangles(&pos, &label, k);
        if it == 0 {
            for m in p.emptiest_first().into_iter().take(dropped) {
                seeds[m as usize] = u32::MAX;
            }
        }
        label = voronoi(
            config.band * h,
            &p.dual.offsets,
            &arcs,
            &seeds,
            &weight,
            &label,
        );
    }
    label
}

/// Per cell, the member triangle nearest the cell's centroid (`u32::MAX` for an empty cell).
fn central_triangles(pos: &[DVec3], label: &[u32], k: usize) -> Vec<u32> {
    let mut sum = vec![(DVec3::ZERO, 0.0f64); k];
    for (t, &l) in label.iter().enumerate() {
        sum[l as usize].0 += pos[t];
        sum[l as usize].1 += 1.0;
    }
    let mut best = vec![(f64::MAX, u32::MAX); k];
    for (t, &l) in label.iter().enumerate() {
        let (s, c) = sum[l as usize];
        let d = pos[t].distance(s / c);
        if d < best[l as usize].0 {
            best[l as usize] = (d, t as u32);
        }
    }
    best.into_iter().map(|b| b.1).collect()
}

/// Multi-source Dijkstra over the dual graph (`offsets` into `arcs`: neighbour, length) from
/// `seeds`, each cell's distances offset by its weight. Triangles no seed reaches (a mesh piece
/// whose cells all emptied) keep `old`. `band` is the width of distance settled at once, in the
/// lengths' units ([`Config::band`] times the mean length).
fn voronoi(
    band: f64,
    offsets: &[u32],
    arcs: &[(u32, f32)],
    seeds: &[u32],
    weight: &[f64],
    old: &[u32],
) -> Vec<u32> {
    /// A triangle's search state in one cache line's quarter: the pops visit triangles all over
    /// the mesh (every cell grows at once), so each separate array read was a cache miss.
    #[derive(Clone, Copy)]
    struct Node {
        dist: f64,
        label: u32,
        settled: bool,
    }
    let n = old.len();
    // Offsets start at 0: the heap orders the distances' bit patterns, which only works for
    // non-negative floats.
    let low = weight.iter().copied().fold(f64::MAX, f64::min);
    let mut node = vec![
        Node {
            dist: f64::MAX,
            label: u32::MAX,
            settled: false,
        };
        n
    ];
    let mut heap = BinaryHeap::new();
    for (c, &t) in seeds.iter().enumerate() {
        if t == u32::MAX {
            continue;
        }
        let d = weight[c] - low;
        if d < node[t as usize].dist {
            node[t as usize] = Node {
                dist: d,
                label: c as u32,
                settled: false,
            };
            heap.push(Reverse((d.to_bits(), t, c as u32)));
        }
    }
    let mut batch: Vec<(u32, u64, u32)> = Vec::new();
    while let Some(Reverse((bits, t, c))) = heap.pop() {
        // One band of distances, settled in triangle order (then distance, then cell).
        batch.clear();
        batch.push((t, bits, c));
        let top = f64::from_bits(bits) + band;
        while let Some(&Reverse((next, t, c))) = heap.peek() {
            if f64::from_bits(next) > top {
                break;
            }
            heap.pop();
            batch.push((t, next, c));
        }
        batch.sort_unstable();
        for &(t, bits, c) in &batch {
            let d = f64::from_bits(bits);
            let here = &mut node[t as usize];
            if here.settled || d > here.dist {
                continue;
            }
            here.settled = true;
            here.label = c;
            let row = &arcs[offsets[t as usize] as usize..offsets[t as usize + 1] as usize];
            for &(u, len) in row {
                let nd = d + len as f64;
                let there = &mut node[u as usize];
                if !there.settled && nd < there.dist {
                    there.dist = nd;
                    heap.push(Reverse((nd.to_bits(), u, c)));
                }
            }
        }
    }
    node.iter()
        .zip(old)
        .map(|(x, &o)| if x.settled { x.label } else { o })
        .collect()
}
