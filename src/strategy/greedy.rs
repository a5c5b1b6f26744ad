//! The JCGT paper's vertex-based greedy grower (Jensen et al. 2023, §3, Listing 1).
//!
//! Vertices are sorted along the longest bounding-box axis. A meshlet grows by breadth-first search
//! over vertices from a seed: each popped vertex contributes its unused triangles while they fit.
//! When the vertex limit is reached before the triangle limit, unused triangles whose three vertices
//! are all inside are added for free. The next meshlet starts from a vertex of the finished one that
//! still has unused triangles (keeping neighbouring meshlets adjacent), or else from the next unused
//! vertex of the sorted list.

use super::{live_counts, mark_used, sorted_vertices, Strategy};
use crate::adjacency::vertex_triangles;
use crate::mesh::Mesh;
use crate::meshlet::{Limits, MeshletBuilder, Meshlets};
use std::collections::VecDeque;

/// The paper's greedy strategy.
pub struct Greedy;

impl Strategy for Greedy {
    fn name(&self) -> &'static str {
        "greedy"
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let vt = vertex_triangles(mesh);
        let order = sorted_vertices(mesh);
        let mut used = vec![false; mesh.triangle_count()];
        let mut live = live_counts(&vt);
        // Generation stamps: `queued[v] == gen` means v was queued for the current meshlet.
        let mut queued = vec![u32::MAX; mesh.vertex_count()];
        let mut b = MeshletBuilder::new(mesh.vertex_count(), limits);
        let mut cursor = 0usize;
        let mut next_seed: Option<u32> = None;
        let mut queue = VecDeque::new();
        let mut gen = 0u32;
        loop {
            let seed = match next_seed.take() {
                Some(v) => v,
                None => {
                    while cursor < order.len() && live[order[cursor] as usize] == 0 {
                        cursor += 1;
                    }
                    match order.get(cursor) {
                        Some(&v) => v,
                        None => break,
                    }
                }
            };
            queue.clear();
            queue.push_back(seed);
            queued[seed as usize] = gen;
            'grow: while let Some(v) = queue.pop_front() {
                for &t in vt.row(v as usize) {
                    if used[t as usize] {
                        continue;
                    }
                    if b.triangles_full() {
                        break 'grow;
                    }
                    let tri = mesh.triangle(t as usize);
                    if !b.fits(tri) {
                        continue; // needs a vertex past the limit; may still come in as a free triangle
                    }
                    b.push(tri);
                    mark_used(mesh, t, &mut used, &mut live);
                    for u in tri {
                        if queued[u as usize] != gen {
                            queued[u as usize] = gen;
                            queue.push_back(u);
                        }
                    }
                }
                if b.vertices_full() {
                    break;
                }
            }
            // Vertex-bound (or stalled a few vertices short): enclosed triangles cost no vertex.
            add_enclosed_triangles(mesh, &vt, &mut b, &mut used, &mut live);
            // The paper: start the next meshlet from a border vertex of this one. (Seeding from the
            // BFS frontier instead was tried: 830 meshlets on the bunny instead of 819.)
            next_seed = b
                .open_vertices()
                .iter()
                .copied()
                .find(|&v| live[v as usize] > 0);
            b.flush();
            gen += 1;
        }
        b.finish()
    }
}

/// Adds unused triangles whose vertices are all in the open meshlet, while the triangle limit allows.
fn add_enclosed_triangles(
    mesh: &Mesh,
    vt: &crate::adjacency::Csr,
    b: &mut MeshletBuilder,
    used: &mut [bool],
    live: &mut [u32],
) {
    let verts: Vec<u32> = b.open_vertices().to_vec();
    for v in verts {
        for &t in vt.row(v as usize) {
            if b.triangles_full() {
                return;
            }
            let tri = mesh.triangle(t as usize);
            if !used[t as usize] && b.new_vertices(tri) == 0 {
                b.push(tri);
                mark_used(mesh, t, used, live);
            }
        }
    }
}

/// `greedy-paper`: the greedy grower as the paper's published code runs it (Senbyo/meshletmaker,
/// `meshletMeshDescriptor.cpp`, strategy 12), which differs from the text (and from [`Greedy`]):
/// - the meshlet is not closed when the breadth-first queue empties: the next unused vertex of the
///   sorted list continues the same meshlet, so meshlets can be disconnected;
/// - every unprocessed vertex of a visited triangle is queued before the fit test (duplicates
///   too), and a vertex counts as processed once all its triangles were visited;
/// - the meshlet closes at the first triangle that does not fit, after one pass over its vertices
///   that adds every unused triangle that still fits (new vertices included, not only enclosed
///   triangles); the triangle that did not fit waits, and the queue restarts at the current vertex.
///
/// `close_on_empty_queue` turns the first difference off (for the ablation in `bench paper`).
pub struct GreedyPaper {
    /// Close the meshlet when the queue empties, as the text (and [`Greedy`]) does.
    pub close_on_empty_queue: bool,
}

impl Strategy for GreedyPaper {
    fn name(&self) -> &'static str {
        if self.close_on_empty_queue {
            "greedy-paper-closing"
        } else {
            "greedy-paper"
        }
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let vt = vertex_triangles(mesh);
        let order = sorted_vertices(mesh);
        let mut used = vec![false; mesh.triangle_count()];
        let mut done = vec![false; mesh.vertex_count()];
        let mut b = MeshletBuilder::new(mesh.vertex_count(), limits);
        let mut queue = VecDeque::new();
        for &seed in &order {
            if done[seed as usize] {
                continue;
            }
            if self.close_on_empty_queue {
                b.flush();
            }
            queue.push_back(seed);
            // Terminates: a vertex is queued only by a visit to an unused triangle, and each such
            // visit either uses the triangle or closes a non-empty meshlet.
            while let Some(&v) = queue.front() {
                for &t in vt.row(v as usize) {
                    if used[t as usize] {
                        continue;
                    }
                    let tri = mesh.triangle(t as usize);
                    for u in tri {
                        if !done[u as usize] {
                            queue.push_back(u);
                        }
                    }
                    if !b.fits(tri) {
                        add_fitting_triangles(mesh, &vt, &mut b, &mut used);
                        b.flush();
                        queue.clear();
                        queue.push_back(v);
                        continue;
                    }
                    b.push(tri);
                    used[t as usize] = true;
                }
                queue.pop_front();
                done[v as usize] = true;
            }
        }
        // A triangle skipped for not fitting is lost in the published code when all its vertices
        // were processed by then (1 of 305,782 on pycortex at 64/126): here it closes the run.
        for (t, _) in used.iter().enumerate().filter(|(_, &u)| !u) {
            b.push(mesh.triangle(t));
        }
        b.finish()
    }
}

/// The published code's last pass before closing a meshlet: over its vertices in order (vertices
/// the pass adds included), every unused triangle that fits goes in.
pub(crate) fn add_fitting_triangles(
    mesh: &Mesh,
    vt: &crate::adjacency::Csr,
    b: &mut MeshletBuilder,
    used: &mut [bool],
) {
    let mut k = 0;
    while k < b.open_size().1 {
        let w = b.open_vertices()[k];
        for &t in vt.row(w as usize) {
            let tri = mesh.triangle(t as usize);
            if !used[t as usize] && b.fits(tri) {
                b.push(tri);
                used[t as usize] = true;
            }
        }
        k += 1;
    }
}
