//! meshoptimizer 1.3 (through crate `meshopt` 0.7): the peer every strategy of ours is measured
//! against. The wrapper runs `meshopt_optimizeMeshlet` on each meshlet, as meshoptimizer users do,
//! and that time is included. meshoptimizer aligns each meshlet's triangle bytes to 4, so its
//! `triangles` array has padding between meshlets; the model allows that.

use super::Strategy;
use crate::mesh::Mesh;
use crate::meshlet::{Limits, Meshlet, Meshlets};
use meshopt::VertexDataAdapter;

fn adapter(mesh: &Mesh) -> VertexDataAdapter<'_> {
    VertexDataAdapter::new(mesh.position_bytes(), 12, 0)
        .expect("stride 12 over f32x3 positions is valid")
}

fn convert(m: meshopt::Meshlets) -> Meshlets {
    Meshlets {
        meshlets: m
            .meshlets
            .iter()
            .map(|x| Meshlet {
                vertex_offset: x.vertex_offset,
                triangle_offset: x.triangle_offset,
                vertex_count: x.vertex_count,
                triangle_count: x.triangle_count,
            })
            .collect(),
        vertices: m.vertices,
        triangles: m.triangles,
    }
}

/// `meshopt_buildMeshlets`: greedy growth by topology and position, optional cone weight.
pub struct Meshopt {
    /// 0 = pure size/locality; towards 1 = tighter normal cones at the cost of more meshlets.
    pub cone_weight: f32,
}

impl Strategy for Meshopt {
    fn name(&self) -> &'static str {
        "meshopt"
    }
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        // The C++ asserts 0..=1 (and a NaN passes a clamp): out-of-range weights are clamped, NaN
        // is the default 0.
        let cw = match self.cone_weight {
            w if w.is_nan() => 0.0,
            w => w.clamp(0.0, 1.0),
        };
        convert(meshopt::build_meshlets(
            &mesh.indices,
            &adapter(mesh),
            limits.max_vertices as usize,
            limits.max_triangles as usize,
            cw,
        ))
    }
}

/// `meshopt_optimizeVertexCache` + `meshopt_buildMeshletsScan`: meshoptimizer's take on the scan.
pub struct MeshoptScan;

impl Strategy for MeshoptScan {
    fn name(&self) -> &'static str {
        "meshopt-scan"
    }
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let ordered = meshopt::optimize_vertex_cache(&mesh.indices, mesh.vertex_count());
        convert(meshopt::build_meshlets_scan(
            &ordered,
            mesh.vertex_count(),
            limits.max_vertices as usize,
            limits.max_triangles as usize,
        ))
    }
}

/// `meshopt_buildMeshletsSpatial`: SAH-driven spatial splits (built for ray tracing clusters).
///
/// Its BVH makes a leaf only when a node fits both limits, otherwise it splits. At 64/126 almost no
/// 126-triangle patch fits in 64 vertices (a 64-vertex patch holds about 100), so nearly every node is
/// split in two and clusters hold about 63 triangles; at 64/84 it fills its meshlets. The minimum
/// triangle count (set equal to the maximum here) does not change that.
pub struct MeshoptSpatial {
    /// Preference for full clusters over SAH quality (meshoptimizer suggests 0.5).
    pub fill_weight: f32,
}

impl Strategy for MeshoptSpatial {
    fn name(&self) -> &'static str {
        "meshopt-spatial"
    }
    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let t = limits.max_triangles as usize;
        convert(meshopt::build_meshlets_spatial(
            &mesh.indices,
            &adapter(mesh),
            limits.max_vertices as usize,
            t,
            t,
            self.fill_weight.max(0.0),
        ))
    }
}
