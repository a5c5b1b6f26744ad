//! Quality metrics of a meshlet collection: what the tables in results/ and `meshletlab stats` show.

use super::{bounds::MeshletBounds, Limits, Meshlets};
use crate::mesh::Mesh;
use std::time::Duration;

/// Metrics of one meshlet collection.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Metrics {
    /// Number of meshlets.
    pub meshlets: usize,
    /// Mean vertices per meshlet.
    pub mean_vertices: f64,
    /// Mean triangles per meshlet.
    pub mean_triangles: f64,
    /// Mean vertices / max vertices.
    pub vertex_fill: f64,
    /// Mean triangles / max triangles (the paper's "primitive fill", Table 8).
    pub primitive_fill: f64,
    /// `vertex_histogram[k]` = meshlets with k vertices (k = 0..=max vertices; paper Figure 9).
    pub vertex_histogram: Vec<u32>,
    /// `triangle_histogram[k]` = meshlets with k triangles (k = 0..=max triangles).
    pub triangle_histogram: Vec<u32>,
    /// Mean bounding-sphere radius divided by the mesh bounding-box diagonal.
    pub mean_radius_rel: f64,
    /// Flatness: mean over meshlets of the RMS distance of its vertices to their least-squares
    /// plane, over the mesh bounding-box diagonal (0 = every meshlet planar; what compressed
    /// formats with plane-aligned boxes profit from).
    pub flatness_rel: f64,
    /// Fraction of meshlets whose normal cone can cull from some viewpoint.
    pub cone_cullable: f64,
    /// Sum of meshlet vertex counts / vertices referenced by the mesh (1 = no vertex shared).
    pub duplication: f64,
    /// Fraction of meshlets whose triangles form one edge-connected piece.
    pub connected: f64,
    /// Wall time of the build in milliseconds (None when not measured).
    pub build_ms: Option<f64>,
}

impl Metrics {
    /// Computes the metrics; `bounds` must come from [`super::bounds::compute_bounds`] on the same meshlets.
    pub fn compute(
        mesh: &Mesh,
        ml: &Meshlets,
        limits: Limits,
        bounds: &[MeshletBounds],
        build_time: Option<Duration>,
    ) -> Self {
        let n = ml.len().max(1) as f64;
        let mut vh = vec![0u32; limits.max_vertices as usize + 1];
        let mut th = vec![0u32; limits.max_triangles as usize + 1];
        let (mut sv, mut st) = (0usize, 0usize);
        for m in &ml.meshlets {
            sv += m.vertex_count as usize;
            st += m.triangle_count as usize;
            // Clamp: metrics of invalid collections still compute (the validator reports those).
            let (vmax, tmax) = (vh.len() - 1, th.len() - 1);
            vh[(m.vertex_count as usize).min(vmax)] += 1;
            th[(m.triangle_count as usize).min(tmax)] += 1;
        }
        let mut referenced = vec![false; mesh.vertex_count()];
        for &i in &mesh.indices {
            referenced[i as usize] = true;
        }
        let referenced = referenced.iter().filter(|&&r| r).count().max(1);
        let diag = mesh.bounding_box_diagonal().max(f32::MIN_POSITIVE) as f64;
        let connected = (0..ml.len())
            .filter(|&i| is_edge_connected(ml.meshlet_triangles(i)))
            .count();
        Self {
            meshlets: ml.len(),
            mean_vertices: sv as f64 / n,
            mean_triangles: st as f64 / n,
            vertex_fill: sv as f64 / n / limits.max_vertices as f64,
            primitive_fill: st as f64 / n / limits.max_triangles as f64,
            vertex_histogram: vh,
            triangle_histogram: th,
            mean_radius_rel: bounds.iter().map(|b| b.sphere.radius as f64).sum::<f64>() / n / diag,
            flatness_rel: (0..ml.len())
                .map(|i| plane_fit_rms(mesh, ml, i))
                .sum::<f64>()
                / n
                / diag,
            cone_cullable: bounds.iter().filter(|b| b.cone.can_cull()).count() as f64 / n,
            duplication: sv as f64 / referenced as f64,
            connected: connected as f64 / n,
            build_ms: build_time.map(|d| d.as_secs_f64() * 1e3),
        }
    }
}

/// Whether a meshlet's triangles (local corners) form one piece through shared edges.
pub fn is_edge_connected(tris: &[u8]) -> bool {
    let t = tris.len() / 3;
    if t <= 1 {
        return true;
    }
    let mut parent: Vec<u16> = (0..t as u16).collect();
    fn find(p: &mut [u16], mut x: u16) -> u16 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    // (edge key, triangle) pairs sorted: runs of equal keys are triangles sharing an edge.
    let mut keys: Vec<(u16, u16)> = Vec::with_capacity(3 * t);
    for (k, c) in tris.chunks_exact(3).enumerate() {
        for i in 0..3 {
            let (a, b) = (c[i], c[(i + 1) % 3]);
            if a != b {
                keys.push(((a.min(b) as u16) << 8 | a.max(b) as u16, k as u16));
            }
        }
    }
    keys.sort_unstable();
    let mut pieces = t;
    for w in keys.windows(2) {
        if w[0].0 == w[1].0 {
            let (ra, rb) = (find(&mut parent, w[0].1), find(&mut parent, w[1].1));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
                pieces -= 1;
            }
        }
    }
    pieces == 1
}

/// RMS distance of meshlet `i`'s vertices to their least-squares plane (the square root of the
/// smallest eigenvalue of their covariance).
fn plane_fit_rms(mesh: &Mesh, ml: &Meshlets, i: usize) -> f64 {
    let pts: Vec<glam::DVec3> = ml
        .meshlet_vertices(i)
        .iter()
        .map(|&v| glam::DVec3::from_array(mesh.positions[v as usize].map(f64::from)))
        .collect();
    let n = pts.len().max(1) as f64;
    let mean = pts.iter().sum::<glam::DVec3>() / n;
    let mut z = [0.0f64; 6];
    for p in &pts {
        let d = *p - mean;
        z[0] += d.x * d.x;
        z[1] += d.y * d.y;
        z[2] += d.z * d.z;
        z[3] += d.x * d.y;
        z[4] += d.x * d.z;
        z[5] += d.y * d.z;
    }
    smallest_eigenvalue(z.map(|x| x / n)).max(0.0).sqrt()
}

/// Smallest eigenvalue of the symmetric matrix (xx, yy, zz, xy, xz, yz) (the trigonometric closed
/// form). Shared with the `qem` strategy, which scores its merges by it.
pub(crate) fn smallest_eigenvalue(z: [f64; 6]) -> f64 {
    let [a, b, c, d, e, f] = z;
    let p1 = d * d + e * e + f * f;
    if p1 <= 1e-300 {
        return a.min(b).min(c);
    }
    let q = (a + b + c) / 3.0;
    let p2 = (a - q).powi(2) + (b - q).powi(2) + (c - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let (ba, bb, bc, bd, be, bf) = ((a - q) / p, (b - q) / p, (c - q) / p, d / p, e / p, f / p);
    let det = ba * (bb * bc - bf * bf) - bd * (bd * bc - bf * be) + be * (bd * bf - bb * be);
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvalue_of_a_flat_and_a_round_covariance() {
        // Points spread in x and y only: the smallest eigenvalue is 0 (a plane fits exactly).
        assert!(smallest_eigenvalue([2.0, 1.0, 0.0, 0.5, 0.0, 0.0]).abs() < 1e-12);
        // Diagonal: the smallest diagonal entry.
        assert!((smallest_eigenvalue([3.0, 2.0, 5.0, 0.0, 0.0, 0.0]) - 2.0).abs() < 1e-12);
        // A rotated diag(1, 2, 3): eigenvalue 1.
        let z = [1.5, 1.5, 3.0, 0.5, 0.0, 0.0];
        assert!((smallest_eigenvalue(z) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn connectivity() {
        assert!(is_edge_connected(&[0, 1, 2, 2, 1, 3]));
        // Sharing only a vertex is not edge-connected.
        assert!(!is_edge_connected(&[0, 1, 2, 2, 3, 4]));
        assert!(is_edge_connected(&[0, 1, 2]));
    }

    #[test]
    fn a_planar_meshlet_is_flat_and_a_bent_one_is_not() {
        let mesh = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
                [1.0, 1.0, 1.0],
            ],
            indices: vec![0, 1, 2, 2, 1, 3, 2, 3, 4],
        };
        let ml = |tris: Vec<u8>, verts: Vec<u32>| Meshlets {
            meshlets: vec![super::super::Meshlet {
                vertex_offset: 0,
                triangle_offset: 0,
                vertex_count: verts.len() as u32,
                triangle_count: tris.len() as u32 / 3,
            }],
            vertices: verts,
            triangles: tris,
        };
        let flat = ml(vec![0, 1, 2, 2, 1, 3], vec![0, 1, 2, 3]);
        assert!(plane_fit_rms(&mesh, &flat, 0) < 1e-12);
        let bent = ml(vec![0, 1, 2, 2, 1, 3, 2, 3, 4], vec![0, 1, 2, 3, 4]);
        assert!(plane_fit_rms(&mesh, &bent, 0) > 0.1);
    }
}
