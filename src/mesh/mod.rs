//! Triangle meshes: the input of every strategy.
//!
//! A [`Mesh`] is a flat vertex array (f32 x 3) and a flat u32 index buffer, three indices per triangle,
//! counter-clockwise front faces. Loaders in this module produce only validated meshes: finite
//! positions, indices in range, at least one triangle. Degenerate and duplicated triangles and
//! non-manifold edges are legal; [`MeshStats`] counts them.

mod error;
pub mod generate;
pub mod gltf_io;
mod gltf_meshopt;
mod load;
mod obj;
pub mod ply;
mod stats;
pub mod subdivide;

pub use error::{MeshError, MeshErrorKind};
pub use load::{decompress, load, load_bytes, save_ply, Format, MAX_ZSTD_RATIO, ZSTD_SLACK};
pub use stats::MeshStats;

use glam::Vec3;
use std::path::Path;

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangle list: three vertex indices per triangle, counter-clockwise.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Builds a mesh and validates it; `path` only labels errors.
    pub fn new(
        positions: Vec<[f32; 3]>,
        indices: Vec<u32>,
        path: &Path,
    ) -> Result<Self, MeshError> {
        let mesh = Self { positions, indices };
        mesh.validate().map_err(|k| MeshError::new(path, k))?;
        Ok(mesh)
    }

    /// Number of vertices (referenced or not).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The three vertex indices of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [u32; 3] {
        [
            self.indices[3 * t],
            self.indices[3 * t + 1],
            self.indices[3 * t + 2],
        ]
    }

    /// Position of vertex `v` as a vector.
    #[inline]
    pub fn position(&self, v: u32) -> Vec3 {
        Vec3::from_array(self.positions[v as usize])
    }

    /// Axis-aligned bounding box (min, max) over all vertices.
    pub fn bounding_box(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &self.positions {
            let p = Vec3::from_array(*p);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }

    /// Length of the bounding-box diagonal (the scale that relative metrics divide by).
    pub fn bounding_box_diagonal(&self) -> f32 {
        let (lo, hi) = self.bounding_box();
        (hi - lo).length()
    }

    /// Checks the invariants every loader guarantees: at least one triangle, a whole number of
    /// triangles, finite positions, indices in range, and a vertex count that fits u32.
    pub fn validate(&self) -> Result<(), MeshErrorKind> {
        if self.positions.len() > u32::MAX as usize {
            return Err(MeshErrorKind::TooLarge(format!(
                "{} vertices do not fit 32-bit indices",
                self.positions.len()
            )));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(MeshErrorKind::CountMismatch(format!(
                "index count {} is not a multiple of 3",
                self.indices.len()
            )));
        }
        if self.indices.is_empty() {
            return Err(MeshErrorKind::Empty(format!(
                "{} vertices but no triangles",
                self.positions.len()
            )));
        }
        for (v, p) in self.positions.iter().enumerate() {
            if let Some(c) = p.iter().find(|c| !c.is_finite()) {
                return Err(MeshErrorKind::NonFinite {
                    vertex: v,
                    value: c.to_string(),
                });
            }
        }
        let n = self.positions.len();
        if let Some(i) = self.indices.iter().position(|&i| i as usize >= n) {
            return Err(MeshErrorKind::IndexOutOfRange {
                triangle: i / 3,
                index: self.indices[i] as i64,
                vertex_count: n,
            });
        }
        Ok(())
    }

    /// Positions as a flat byte slice (stride 12), as meshoptimizer's vertex adapters want.
    pub fn position_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.positions)
    }

    /// A 64-bit FNV-1a fingerprint of positions and indices, stored in meshlet files so that
    /// `check` notices when a file is validated against a different mesh.
    pub fn fingerprint(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for &b in bytes {
                h ^= b as u64;
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        };
        eat(&(self.positions.len() as u64).to_le_bytes());
        eat(bytemuck::cast_slice(&self.positions));
        eat(&(self.indices.len() as u64).to_le_bytes());
        eat(bytemuck::cast_slice(&self.indices));
        h
    }
}
