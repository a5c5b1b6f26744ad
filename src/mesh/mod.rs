//! Triangle meshes: the input of every strategy.
//!
//! A [`Mesh`] is a flat vertex array (f32 x 3) and a flat u32 index buffer, three indices per triangle,
//! counter-clockwise front faces. Loaders in this module produce only validated meshes: finite
//! positions, indices in range, at least one triangle. Degenerate and duplicated triangles and
//! non-manifold edges are legal; [`MeshStats`] counts them.

pub mod edges;
mod error;
pub mod generate;
#[cfg(feature = "io")]
pub mod gltf_io;
#[cfg(feature = "io")]
mod gltf_meshopt;
#[cfg(feature = "io")]
mod load;
#[cfg(feature = "io")]
mod obj;
#[cfg(feature = "io")]
pub mod ply;
pub mod scene;
mod stats;
#[cfg(feature = "io")]
pub mod stl;
pub mod subdivide;
pub mod tipsify;
#[cfg(feature = "io")]
mod tokens;

pub use error::{MeshError, MeshErrorKind};
#[cfg(feature = "io")]
pub use load::{
    decompress, load, load_bytes, load_scene, save_ply, scene_from_bytes, MeshFormat,
    GENERATED_PREFIX, MAX_ZSTD_RATIO, ZSTD_SLACK,
};
pub use scene::{Instance, Scene};
pub use stats::MeshStats;

use glam::Vec3;
use std::path::Path;

/// An indexed triangle mesh, valid by construction: every way to make one outside this crate
/// ([`Mesh::new`], [`Mesh::from_slices`], [`Mesh::from_strided`], the loaders, the generators)
/// checks the invariants [`Mesh::validate`] lists, so a strategy, the bounds, the LOD build and the
/// codecs (some of which hand the arrays to meshoptimizer's C code) never see an index out of
/// range or a non-finite position. Read the arrays with [`Mesh::positions`] and [`Mesh::indices`];
/// take them back with [`Mesh::into_parts`].
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub(crate) positions: Vec<[f32; 3]>,
    /// Triangle list: three vertex indices per triangle, counter-clockwise.
    pub(crate) indices: Vec<u32>,
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

    /// Builds a mesh from arrays an engine already holds and validates it; `label` names the mesh
    /// in errors (a path or any name). The arrays are copied once, 12 bytes per vertex and per
    /// triangle: every strategy then reads one flat layout, and the copy costs far less than any
    /// of them (a few ms per million triangles).
    pub fn from_slices(
        positions: &[[f32; 3]],
        indices: &[u32],
        label: impl AsRef<Path>,
    ) -> Result<Self, MeshError> {
        Self::new(positions.to_vec(), indices.to_vec(), label.as_ref())
    }

    /// Like [`Mesh::from_slices`] for interleaved vertex data: the position of vertex `i` is three
    /// f32s at byte `offset + i * stride` of `vertices` (the layout of a typical vertex buffer).
    pub fn from_strided(
        vertices: &[u8],
        stride: usize,
        offset: usize,
        indices: &[u32],
        label: impl AsRef<Path>,
    ) -> Result<Self, MeshError> {
        let path = label.as_ref();
        if stride < 12 || offset > stride - 12 {
            return Err(MeshError::new(
                path,
                MeshErrorKind::Unsupported(format!(
                    "vertex stride {stride} with position offset {offset} does not hold three f32s"
                )),
            ));
        }
        // Vertex i fits when offset + i * stride + 12 <= len; the last one needs no full stride.
        let count = match vertices.len().checked_sub(offset + 12) {
            Some(rest) => rest / stride + 1,
            None => 0,
        };
        let positions = (0..count)
            .map(|i| {
                let at = &vertices[offset + i * stride..][..12];
                std::array::from_fn(|k| {
                    f32::from_le_bytes(at[4 * k..4 * k + 4].try_into().unwrap())
                })
            })
            .collect();
        Self::new(positions, indices.to_vec(), path)
    }

    /// An empty mesh, invalid as input: scratch that crate code fills (a scene's baked copy, a
    /// renderer's joined buffers) before anything reads it.
    pub(crate) fn empty() -> Self {
        Self {
            positions: Vec::new(),
            indices: Vec::new(),
        }
    }

    /// Vertex positions (f32 x 3).
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// The triangle list: three vertex indices per triangle, counter-clockwise.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// The positions and the triangle list, moved out.
    pub fn into_parts(self) -> (Vec<[f32; 3]>, Vec<u32>) {
        (self.positions, self.indices)
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

#[cfg(test)]
mod slice_tests {
    use super::*;

    #[test]
    fn borrowed_and_strided_arrays_make_the_same_mesh() {
        let m = generate::terrain(6, 1);
        let from = Mesh::from_slices(&m.positions, &m.indices, "engine").unwrap();
        assert_eq!(from, m);
        // Interleaved: a 4-byte tag, the position, a 12-byte normal; 28-byte stride.
        let mut bytes = Vec::new();
        for p in &m.positions {
            bytes.extend_from_slice(&7u32.to_le_bytes());
            bytes.extend(p.iter().flat_map(|c| c.to_le_bytes()));
            bytes.extend_from_slice(&[0u8; 12]);
        }
        let strided = Mesh::from_strided(&bytes, 28, 4, &m.indices, "engine").unwrap();
        assert_eq!(strided, m);
        // The last vertex needs no padding after its position.
        bytes.truncate(bytes.len() - 12);
        assert_eq!(
            Mesh::from_strided(&bytes, 28, 4, &m.indices, "engine").unwrap(),
            m
        );
        // One byte short of the last position: one vertex fewer, so an index is out of range.
        bytes.pop();
        let e = Mesh::from_strided(&bytes, 28, 4, &m.indices, "engine").unwrap_err();
        assert!(e.to_string().starts_with("engine: "), "{e}");
        let e = Mesh::from_strided(&bytes, 12, 4, &m.indices, "engine").unwrap_err();
        assert!(e.to_string().contains("stride 12"), "{e}");
        let e = Mesh::from_slices(&m.positions, &[0, 1], "engine").unwrap_err();
        assert!(e.to_string().starts_with("engine: "), "{e}");
    }
}
