//! NVIDIA's index-buffer scan (Kubisch, "Introduction to Turing Mesh Shaders", 2018), as the JCGT
//! paper describes it: walk the triangles in index-buffer order and append each to the current
//! meshlet; when it would exceed the vertex or triangle limit, close the meshlet and start a new one.
//! Its quality depends entirely on the input order, hence the optional tipsify reordering first.

use super::Strategy;
use crate::mesh::tipsify;
use crate::mesh::Mesh;
use crate::meshlet::{Limits, MeshletBuilder, Meshlets};

/// The scan, optionally over a tipsify-reordered index buffer.
pub struct Nvidia {
    /// Run tipsify with this cache size first (`nvidia+tipsify`).
    pub tipsify_cache: Option<u32>,
}

impl Strategy for Nvidia {
    fn name(&self) -> &'static str {
        if self.tipsify_cache.is_some() {
            "nvidia+tipsify"
        } else {
            "nvidia"
        }
    }

    fn build(&self, mesh: &Mesh, limits: Limits) -> Meshlets {
        let mut b = MeshletBuilder::new(mesh.vertex_count(), limits);
        match self.tipsify_cache {
            Some(k) => {
                for t in tipsify::order(mesh, k) {
                    b.push(mesh.triangle(t as usize));
                }
            }
            None => {
                for t in 0..mesh.triangle_count() {
                    b.push(mesh.triangle(t));
                }
            }
        }
        b.finish()
    }
}
