//! The flat method's split choice (CPU reference of `wgsl/split.wgsl`, which computes the
//! per-cluster counts and farthest members): which clusters are over a limit, and where each gets
//! its second medoid.

use super::assign::{members, UNREACHED};
use crate::common::sorted;
use crate::mesh::Mesh;
use crate::meshlet::Limits;
use rayon::prelude::*;

/// The flat method's split choice: the largest overflows first (ties to the lower cluster), a
/// fraction per round; returns the clusters to split.
pub fn split_choice(mut over: Vec<(u32, u32)>, fraction: f64) -> Vec<u32> {
    over.sort_unstable_by_key(|&(c, size)| (std::cmp::Reverse(size), c));
    let take = ((over.len() as f64 * fraction).ceil() as usize).clamp(1, over.len());
    over[..take].iter().map(|&(c, _)| c).collect()
}

/// Clusters over a limit, as (cluster, size) where size is triangles, or vertices beyond the limit
/// scaled to triangles (so a larger overflow ranks first).
pub fn overflowing(mesh: &Mesh, labels: &[u32], k: usize, limits: Limits) -> Vec<(u32, u32)> {
    let mem = members(labels, k);
    let triangles: Vec<u32> = (0..k).map(|c| mem.row(c).len() as u32).collect();
    // Distinct vertices only where the triangle limit holds (the rule checks triangles first).
    let vertices: Vec<u32> = (0..k)
        .into_par_iter()
        .map(|c| {
            let m = mem.row(c);
            if m.len() > limits.max_triangles as usize {
                return 0;
            }
            sorted(m.iter().flat_map(|&t| mesh.triangle(t as usize)).collect()).len() as u32
        })
        .collect();
    overflowing_from_counts(&triangles, &vertices, limits)
}

/// [`overflowing`] from per-cluster triangle and distinct-vertex counts (the GPU `stats` kernel's
/// output; a vertex count is only read for clusters within the triangle limit).
pub fn overflowing_from_counts(
    triangles: &[u32],
    vertices: &[u32],
    limits: Limits,
) -> Vec<(u32, u32)> {
    (0..triangles.len())
        .filter(|&c| triangles[c] > limits.max_triangles || vertices[c] > limits.max_vertices)
        .map(|c| (c as u32, triangles[c]))
        .collect()
}

/// The member farthest (in assign hops) from each cluster's medoid; lowest id on ties.
pub fn farthest_members(labels: &[u32], distances: &[u32], k: usize) -> Vec<u32> {
    let mut far = vec![(0u32, u32::MAX); k];
    for (t, (&l, &d)) in labels.iter().zip(distances).enumerate() {
        if l != UNREACHED {
            let f = &mut far[l as usize];
            if d > f.0 || f.1 == u32::MAX {
                *f = (d, t as u32);
            }
        }
    }
    far.into_iter().map(|f| f.1).collect()
}
