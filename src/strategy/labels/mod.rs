//! Meshlets from a clustering made elsewhere: one cluster id per triangle (a numpy prototype, a
//! graph partitioner, another engine's builder), packed into the same [`Meshlets`] every strategy
//! here returns, so the validator, the metrics, the bounds, the LOD build, the codecs and the
//! renderer measure it like ours.
//!
//! Ids are any `u64`, gaps allowed; each distinct id is one cluster and the meshlets come in
//! ascending id order. A cluster's triangles keep the mesh's order and its vertices are numbered
//! in first-use order. A cluster over the limits is refused (its id, triangle and vertex count),
//! or, with `split`, divided by meshoptimizer's `meshopt_buildMeshlets` over that cluster's
//! triangles alone, so the rest of the clustering is measured as it was made.
//! [`triangle_labels`] is the way back: any meshlets' per-triangle ids, for the other tool.

#[cfg(feature = "io")]
pub mod file;

use crate::mesh::Mesh;
use crate::meshlet::{canonical, validate, Limits, MeshletBuilder, Meshlets, ValidationError};
use meshopt::VertexDataAdapter;
use rayon::prelude::*;
use thiserror::Error;

/// Meshlets made from a clustering.
#[derive(Clone, Debug, PartialEq)]
pub struct Clustered {
    /// The meshlets: every triangle once, within the limits (by construction).
    pub meshlets: Meshlets,
    /// Distinct cluster ids in the labels.
    pub clusters: usize,
    /// Clusters over the limits that were divided by meshoptimizer (0 without `split`).
    pub split: usize,
}

/// Why a clustering cannot become meshlets.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum LabelsError {
    /// Not one label per triangle.
    #[error(
        "{found} cluster ids for a mesh of {expected} triangles (one id per triangle, in the order the mesh loads)"
    )]
    Length {
        /// The mesh's triangle count.
        expected: usize,
        /// Labels given.
        found: usize,
    },
    /// A cluster that does not fit one meshlet, and `split` was not asked for.
    #[error(
        "cluster {id}: {triangles} triangles and {vertices} vertices, over the limits {limits} (--split divides such clusters with meshopt)"
    )]
    OverLimits {
        /// The cluster's id as given.
        id: u64,
        /// Its triangles.
        triangles: usize,
        /// Its distinct vertices.
        vertices: usize,
        /// The limits.
        limits: Limits,
    },
}

/// Packs one meshlet per cluster: `labels[t]` is triangle `t`'s cluster id. With `split`, a
/// cluster over `limits` becomes meshoptimizer's meshlets of its triangles (counted in
/// [`Clustered::split`]); without it, the first such cluster (by id) is an error.
pub fn from_labels(
    mesh: &Mesh,
    labels: &[u64],
    limits: Limits,
    split: bool,
) -> Result<Clustered, LabelsError> {
    if labels.len() != mesh.triangle_count() {
        return Err(LabelsError::Length {
            expected: mesh.triangle_count(),
            found: labels.len(),
        });
    }
    let (ids, members, start) = group_by_cluster(labels);
    let mut builder = MeshletBuilder::new(mesh.vertex_count(), limits);
    let mut seen = vec![u32::MAX; mesh.vertex_count()];
    let mut divided = 0;
    for (c, &id) in ids.iter().enumerate() {
        let tris = &members[start[c]..start[c + 1]];
        let vertices = count_vertices(mesh, tris, &mut seen, c as u32);
        if tris.len() <= limits.max_triangles as usize && vertices <= limits.max_vertices as usize {
            for &t in tris {
                builder.push(mesh.triangle(t as usize));
            }
            builder.flush();
        } else if split {
            divided += 1;
            let global = tris.iter().map(|&t| mesh.triangle(t as usize));
            split_cluster(mesh, global, limits, &mut builder);
        } else {
            return Err(LabelsError::OverLimits {
                id,
                triangles: tris.len(),
                vertices,
                limits,
            });
        }
    }
    Ok(Clustered {
        meshlets: builder.finish(),
        clusters: ids.len(),
        split: divided,
    })
}

/// The distinct ids ascending, then the triangles of each (ascending) as one array with row
/// starts: a counting sort over the ids' ranks.
fn group_by_cluster(labels: &[u64]) -> (Vec<u64>, Vec<u32>, Vec<usize>) {
    let mut ids = labels.to_vec();
    ids.par_sort_unstable();
    ids.dedup();
    let rank: Vec<u32> = labels
        .par_iter()
        .map(|l| ids.binary_search(l).expect("every label is among the ids") as u32)
        .collect();
    let mut start = vec![0usize; ids.len() + 1];
    for &r in &rank {
        start[r as usize + 1] += 1;
    }
    for c in 0..ids.len() {
        start[c + 1] += start[c];
    }
    let mut slot = start.clone();
    let mut members = vec![0u32; labels.len()];
    for (t, &r) in rank.iter().enumerate() {
        members[slot[r as usize]] = t as u32;
        slot[r as usize] += 1;
    }
    (ids, members, start)
}

/// Distinct vertices of `tris`; `seen` holds the last cluster that counted each vertex, so it is
/// never cleared between clusters.
fn count_vertices(mesh: &Mesh, tris: &[u32], seen: &mut [u32], cluster: u32) -> usize {
    let mut n = 0;
    for &t in tris {
        for v in mesh.triangle(t as usize) {
            if seen[v as usize] != cluster {
                seen[v as usize] = cluster;
                n += 1;
            }
        }
    }
    n
}

/// Meshlets made elsewhere, held to `limits`: those within them kept as they are, each one over
/// them divided as [`from_labels`] divides a cluster with `split` (or, without it, the first one
/// an error, its index as the id). Also how many were divided.
pub fn split_meshlets(
    mesh: &Mesh,
    ml: Meshlets,
    limits: Limits,
    split: bool,
) -> Result<(Meshlets, usize), LabelsError> {
    let over = |m: &crate::meshlet::Meshlet| {
        m.vertex_count > limits.max_vertices || m.triangle_count > limits.max_triangles
    };
    let Some(first) = ml.meshlets().iter().position(over) else {
        return Ok((ml, 0));
    };
    if !split {
        let m = ml.meshlets()[first];
        return Err(LabelsError::OverLimits {
            id: first as u64,
            triangles: m.triangle_count as usize,
            vertices: m.vertex_count as usize,
            limits,
        });
    }
    let mut builder = MeshletBuilder::new(mesh.vertex_count(), limits);
    let mut divided = 0;
    for (i, m) in ml.meshlets().iter().enumerate() {
        if over(m) {
            divided += 1;
            split_cluster(mesh, ml.global_triangles(i), limits, &mut builder);
        } else {
            // Kept: its triangles in their order (vertices renumbered in first-use order).
            for t in ml.global_triangles(i) {
                builder.push(t);
            }
            builder.flush();
        }
    }
    Ok((builder.finish(), divided))
}

/// meshoptimizer's meshlets of one cluster, over a copy of just its vertices (its per-vertex
/// scratch is then the cluster's size, not the mesh's), pushed back with global vertex ids.
fn split_cluster(
    mesh: &Mesh,
    tris: impl Iterator<Item = [u32; 3]>,
    limits: Limits,
    builder: &mut MeshletBuilder,
) {
    let mut global: Vec<u32> = Vec::new();
    let mut local_index = std::collections::HashMap::new();
    let mut indices = Vec::new();
    for tri in tris {
        for v in tri {
            let l = *local_index.entry(v).or_insert_with(|| {
                global.push(v);
                global.len() as u32 - 1
            });
            indices.push(l);
        }
    }
    let positions: Vec<[f32; 3]> = global
        .iter()
        .map(|&v| mesh.positions()[v as usize])
        .collect();
    let adapter = VertexDataAdapter::new(bytemuck::cast_slice(&positions), 12, 0)
        .expect("stride 12 over f32x3 positions is valid");
    let out = meshopt::build_meshlets(
        &indices,
        &adapter,
        limits.max_vertices as usize,
        limits.max_triangles as usize,
        0.0,
    );
    for m in out.meshlets.iter() {
        let verts = &out.vertices[m.vertex_offset as usize..][..m.vertex_count as usize];
        let corners = &out.triangles[m.triangle_offset as usize..][..3 * m.triangle_count as usize];
        for c in corners.chunks_exact(3) {
            builder.push([0, 1, 2].map(|k| global[verts[c[k] as usize] as usize]));
        }
        builder.flush();
    }
}

/// Each mesh triangle's meshlet index: any valid meshlets (within 256/256) as the per-triangle
/// cluster ids [`from_labels`] reads. A triangle listed twice in the mesh takes the meshlets'
/// copies in order.
pub fn triangle_labels(mesh: &Mesh, ml: &Meshlets) -> Result<Vec<u32>, ValidationError> {
    validate(mesh, ml, Limits::MAX)?;
    let mut keys: Vec<([u32; 3], u32)> = (0..mesh.triangle_count())
        .map(|t| (canonical(mesh.triangle(t)), t as u32))
        .collect();
    keys.par_sort_unstable();
    // taken[i]: copies of the key starting at i already given out.
    let mut taken = vec![0u32; keys.len()];
    let mut labels = vec![0u32; mesh.triangle_count()];
    for i in 0..ml.len() {
        for tri in ml.global_triangles(i) {
            let key = canonical(tri);
            let first = keys.partition_point(|(k, _)| *k < key);
            let slot = first + taken[first] as usize;
            taken[first] += 1;
            labels[keys[slot].1 as usize] = i as u32;
        }
    }
    Ok(labels)
}
