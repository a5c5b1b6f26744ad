//! The meshlet model, shared by every strategy, the validator, bounds, metrics, the file format,
//! rendering, compression and LOD.
//!
//! The layout is meshoptimizer's: one flat array of global vertex indices and one flat array of
//! local (u8) triangle corners, with per-meshlet offsets into both. `triangle_offset` counts bytes of
//! `triangles` (three per triangle), as `meshopt_Meshlet` does, so converting to and from
//! meshoptimizer is a copy. Renderers, compressed formats and LOD levels all start from this.

pub mod assemble;
pub mod bounds;
mod builder;
pub mod descriptor;
#[cfg(feature = "io")]
pub mod export;
#[cfg(feature = "io")]
pub mod io;
pub mod metrics;
#[cfg(feature = "io")]
pub(crate) mod npy;
#[cfg(feature = "io")]
pub mod npz;
pub mod order;
mod validate;

pub use bounds::{Cone, MeshletBounds, Sphere};
pub use builder::MeshletBuilder;
pub use metrics::Metrics;
pub use validate::{canonical, validate, ValidationError};

use std::fmt;
use std::str::FromStr;

/// One meshlet: a range of [`Meshlets::vertices`] and a range of [`Meshlets::triangles`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Meshlet {
    /// First entry in `vertices`.
    pub vertex_offset: u32,
    /// First byte in `triangles` (three bytes per triangle).
    pub triangle_offset: u32,
    /// Number of vertices.
    pub vertex_count: u32,
    /// Number of triangles.
    pub triangle_count: u32,
}

impl Meshlet {
    /// Records from meshoptimizer's rows of four u32s (vertex offset, triangle offset, vertex
    /// count, triangle count), as a `.npz` or a numpy array holds them; a partial last row is
    /// dropped.
    pub fn from_rows(rows: &[u32]) -> Vec<Meshlet> {
        rows.chunks_exact(4)
            .map(|r| Meshlet {
                vertex_offset: r[0],
                triangle_offset: r[1],
                vertex_count: r[2],
                triangle_count: r[3],
            })
            .collect()
    }
}

/// A collection of meshlets over one mesh, consistent by construction: every meshlet's ranges lie
/// inside the two arrays, it has at most 256 vertices and 256 triangles, and every corner names
/// one of its vertices. The strategies build it; [`Meshlets::new`] checks arrays made elsewhere.
/// Whether it covers a mesh's triangles, and within which limits, is [`validate`]'s question.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Meshlets {
    /// The meshlets, in build order.
    pub(crate) meshlets: Vec<Meshlet>,
    /// Global vertex indices, `vertex_count` per meshlet from its `vertex_offset`.
    pub(crate) vertices: Vec<u32>,
    /// Local triangle corners (indices into the meshlet's vertex range), three per triangle.
    pub(crate) triangles: Vec<u8>,
}

/// Why arrays do not make a [`Meshlets`] of a mesh.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum MeshletsError {
    /// A meshlet's vertex or triangle range runs past its array.
    #[error("meshlet {0}: its vertex or triangle range runs past the array")]
    Range(usize),
    /// A meshlet with more than 256 vertices or triangles (corners are u8).
    #[error("meshlet {0}: more than 256 vertices or triangles")]
    Size(usize),
    /// A corner that names no vertex of its meshlet.
    #[error("meshlet {meshlet}: corner {corner} is not below its vertex count {vertex_count}")]
    Corner {
        /// The meshlet.
        meshlet: usize,
        /// The corner's value.
        corner: u8,
        /// The meshlet's vertex count.
        vertex_count: u32,
    },
    /// A global vertex index the mesh does not have.
    #[error("meshlet {meshlet}: vertex {vertex} is not below the mesh's {vertex_count} vertices")]
    Vertex {
        /// The meshlet.
        meshlet: usize,
        /// The vertex index.
        vertex: u32,
        /// The mesh's vertex count.
        vertex_count: usize,
    },
}

impl Meshlets {
    /// Checks arrays made elsewhere (another tool's clusters, a cache) against the invariants
    /// above and against `mesh`'s vertex count, and takes them.
    pub fn new(
        mesh: &crate::mesh::Mesh,
        meshlets: Vec<Meshlet>,
        vertices: Vec<u32>,
        triangles: Vec<u8>,
    ) -> Result<Self, MeshletsError> {
        for (i, m) in meshlets.iter().enumerate() {
            if m.vertex_count > 256 || m.triangle_count > 256 {
                return Err(MeshletsError::Size(i));
            }
            // u64: offsets near u32::MAX must not wrap into range.
            let v_end = m.vertex_offset as u64 + m.vertex_count as u64;
            let t_end = m.triangle_offset as u64 + 3 * m.triangle_count as u64;
            if v_end > vertices.len() as u64 || t_end > triangles.len() as u64 {
                return Err(MeshletsError::Range(i));
            }
            let corners = &triangles[m.triangle_offset as usize..t_end as usize];
            if let Some(&corner) = corners.iter().find(|&&c| c as u32 >= m.vertex_count) {
                return Err(MeshletsError::Corner {
                    meshlet: i,
                    corner,
                    vertex_count: m.vertex_count,
                });
            }
            let used = &vertices[m.vertex_offset as usize..v_end as usize];
            if let Some(&vertex) = used.iter().find(|&&v| v as usize >= mesh.vertex_count()) {
                return Err(MeshletsError::Vertex {
                    meshlet: i,
                    vertex,
                    vertex_count: mesh.vertex_count(),
                });
            }
        }
        Ok(Self {
            meshlets,
            vertices,
            triangles,
        })
    }

    /// The meshlets, in build order.
    pub fn meshlets(&self) -> &[Meshlet] {
        &self.meshlets
    }

    /// Global vertex indices, `vertex_count` per meshlet from its `vertex_offset`.
    pub fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    /// Local triangle corners (indices into the meshlet's vertex range), three per triangle.
    pub fn triangles(&self) -> &[u8] {
        &self.triangles
    }

    /// The meshlet records as meshoptimizer's rows of four u32s (the inverse of
    /// [`Meshlet::from_rows`]), without a copy: a record is four u32s, `repr(C)`.
    pub fn meshlet_rows(&self) -> &[u32] {
        bytemuck::cast_slice(&self.meshlets)
    }

    /// The three arrays, moved out.
    pub fn into_parts(self) -> (Vec<Meshlet>, Vec<u32>, Vec<u8>) {
        (self.meshlets, self.vertices, self.triangles)
    }

    /// The meshlets of `parts` one after another (offsets moved to the joined arrays).
    pub fn concat(parts: Vec<Meshlets>) -> Meshlets {
        let mut out = Meshlets {
            meshlets: Vec::with_capacity(parts.iter().map(Meshlets::len).sum()),
            vertices: Vec::with_capacity(parts.iter().map(|p| p.vertices.len()).sum()),
            triangles: Vec::with_capacity(parts.iter().map(|p| p.triangles.len()).sum()),
        };
        for p in parts {
            let (v, t) = (out.vertices.len() as u32, out.triangles.len() as u32);
            out.meshlets.extend(p.meshlets.iter().map(|m| Meshlet {
                vertex_offset: m.vertex_offset + v,
                triangle_offset: m.triangle_offset + t,
                ..*m
            }));
            out.vertices.extend_from_slice(&p.vertices);
            out.triangles.extend_from_slice(&p.triangles);
        }
        out
    }

    /// Number of meshlets.
    pub fn len(&self) -> usize {
        self.meshlets.len()
    }

    /// True when there are no meshlets.
    pub fn is_empty(&self) -> bool {
        self.meshlets.is_empty()
    }

    /// Global vertex indices of meshlet `i`.
    pub fn meshlet_vertices(&self, i: usize) -> &[u32] {
        let m = &self.meshlets[i];
        &self.vertices[m.vertex_offset as usize..(m.vertex_offset + m.vertex_count) as usize]
    }

    /// Local triangle corners of meshlet `i` (3 per triangle).
    pub fn meshlet_triangles(&self, i: usize) -> &[u8] {
        let m = &self.meshlets[i];
        &self.triangles
            [m.triangle_offset as usize..(m.triangle_offset + 3 * m.triangle_count) as usize]
    }

    /// Global vertex indices of every triangle of meshlet `i`.
    pub fn global_triangles(&self, i: usize) -> impl Iterator<Item = [u32; 3]> + '_ {
        let v = self.meshlet_vertices(i);
        self.meshlet_triangles(i)
            .chunks_exact(3)
            .map(move |t| [v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]])
    }

    /// Total triangles over all meshlets.
    pub fn triangle_count(&self) -> usize {
        self.meshlets
            .iter()
            .map(|m| m.triangle_count as usize)
            .sum()
    }
}

/// Per-meshlet size limits. Mesh-shader hardware and meshoptimizer cap both at 256 here; made
/// only by [`Limits::new`] (or taken from the constants), so no strategy sees a limit it cannot
/// meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Limits {
    /// Most vertices in one meshlet (3..=256).
    pub(crate) max_vertices: u32,
    /// Most triangles in one meshlet (1..=256).
    pub(crate) max_triangles: u32,
}

impl Limits {
    /// The JCGT paper's (and NVIDIA's recommended) 64 vertices / 126 triangles.
    pub const DEFAULT: Limits = Limits {
        max_vertices: 64,
        max_triangles: 126,
    };
    /// The largest limits the model allows: 256 vertices / 256 triangles (corners are u8).
    pub const MAX: Limits = Limits {
        max_vertices: 256,
        max_triangles: 256,
    };
    /// The three presets the tests and benches cover: 64/126, 64/124 and 64/84.
    pub const PRESETS: [Limits; 3] = [
        Limits::DEFAULT,
        Limits {
            max_vertices: 64,
            max_triangles: 124,
        },
        Limits {
            max_vertices: 64,
            max_triangles: 84,
        },
    ];

    /// The presets of the meshlet-count comparison: 64/126 (vertex-bound: a 64-vertex patch holds
    /// about 100 triangles), 64/84 (nearly triangle-bound) and 128/128 (triangle-bound).
    pub const COUNT_PRESETS: [Limits; 3] = [
        Limits::DEFAULT,
        Limits {
            max_vertices: 64,
            max_triangles: 84,
        },
        Limits {
            max_vertices: 128,
            max_triangles: 128,
        },
    ];

    /// Most vertices in one meshlet (3..=256).
    pub fn max_vertices(&self) -> u32 {
        self.max_vertices
    }

    /// Most triangles in one meshlet (1..=256).
    pub fn max_triangles(&self) -> u32 {
        self.max_triangles
    }

    /// No partition of `triangles` triangles has fewer meshlets than this (a hard bound).
    pub fn min_meshlets(&self, triangles: usize) -> usize {
        triangles.div_ceil(self.max_triangles as usize)
    }

    /// Triangles in the roundest `max_vertices`-vertex patch of a regular triangulation: a
    /// hexagon of side k has V = 3k² + 3k + 1 vertices, B = 6k = sqrt(12V - 3) - 3 of them on its
    /// boundary, and by Euler's formula T = 2V - B - 2 triangles (about 101.3 at 64 vertices).
    pub fn disc_triangles(&self) -> f64 {
        let v = self.max_vertices as f64;
        2.0 * v - ((12.0 * v - 3.0).sqrt() - 3.0) - 2.0
    }

    /// The meshlet count if every meshlet were as full as the limits and [`Self::disc_triangles`]
    /// allow. Not a hard bound: irregular or open meshes can pack more triangles per vertex; it
    /// says how far a count is from the best that regular, closed meshes permit.
    pub fn disc_meshlets(&self, triangles: usize) -> usize {
        let per = self.disc_triangles().min(self.max_triangles as f64);
        (triangles as f64 / per).ceil() as usize
    }

    /// Checked constructor: at least 3 vertices and 1 triangle, at most 256 of each (a meshlet's
    /// corners are u8).
    pub fn new(max_vertices: u32, max_triangles: u32) -> Result<Self, LimitsError> {
        if !(3..=256).contains(&max_vertices) {
            return Err(LimitsError::Vertices(max_vertices));
        }
        if !(1..=256).contains(&max_triangles) {
            return Err(LimitsError::Triangles(max_triangles));
        }
        Ok(Self {
            max_vertices,
            max_triangles,
        })
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl fmt::Display for Limits {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.max_vertices, self.max_triangles)
    }
}

/// Why [`Limits::new`] or parsing `VERTICES/TRIANGLES` refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LimitsError {
    /// The vertex limit is outside 3..=256.
    #[error("max vertices must be in 3..=256, got {0}")]
    Vertices(u32),
    /// The triangle limit is outside 1..=256.
    #[error("max triangles must be in 1..=256, got {0}")]
    Triangles(u32),
    /// The text has no `/` between the two counts.
    #[error("limits '{0}' must look like 64/126")]
    Syntax(String),
    /// The part before the `/` is not a number.
    #[error("'{0}' is not a vertex count")]
    VertexCount(String),
    /// The part after the `/` is not a number.
    #[error("'{0}' is not a triangle count")]
    TriangleCount(String),
}

impl FromStr for Limits {
    type Err = LimitsError;
    /// Parses `VERTICES/TRIANGLES`, e.g. `64/126`.
    fn from_str(s: &str) -> Result<Self, LimitsError> {
        let (v, t) = s
            .split_once('/')
            .ok_or_else(|| LimitsError::Syntax(s.to_string()))?;
        let v = v
            .trim()
            .parse()
            .map_err(|_| LimitsError::VertexCount(v.to_string()))?;
        let t = t
            .trim()
            .parse()
            .map_err(|_| LimitsError::TriangleCount(t.to_string()))?;
        Self::new(v, t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_parse_and_check() {
        assert_eq!("64/126".parse::<Limits>().unwrap(), Limits::DEFAULT);
        assert!("64".parse::<Limits>().is_err());
        assert!("2/10".parse::<Limits>().is_err());
        assert!("64/257".parse::<Limits>().is_err());
        assert!("257/10".parse::<Limits>().is_err());
        assert_eq!(Limits::PRESETS[2].to_string(), "64/84");
    }

    #[test]
    fn count_bounds() {
        // Hexagons of side 1, 2, 3 on the triangular lattice: 6k² triangles on 3k² + 3k + 1 vertices.
        for k in 1..=3u32 {
            let l = Limits::new(3 * k * k + 3 * k + 1, 256).unwrap();
            assert!((l.disc_triangles() - (6 * k * k) as f64).abs() < 1e-9);
        }
        let l = Limits::DEFAULT;
        assert_eq!(l.min_meshlets(126), 1);
        assert_eq!(l.min_meshlets(127), 2);
        // Vertex-bound at 64/126: about 101 triangles per meshlet, not 126.
        assert_eq!(l.disc_meshlets(1013), 10);
        assert_eq!(l.disc_meshlets(1014), 11);
        // Triangle-bound at 128/128: the disc holds more than 128.
        let l = Limits::COUNT_PRESETS[2];
        assert_eq!(l.disc_meshlets(1280), l.min_meshlets(1280));
    }
}
