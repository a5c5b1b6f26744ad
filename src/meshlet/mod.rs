//! The meshlet model, shared by every strategy, the validator, bounds, metrics, the file format and
//! (later) rendering, compression and LOD.
//!
//! The layout is meshoptimizer's: one flat array of global vertex indices and one flat array of
//! local (u8) triangle corners, with per-meshlet offsets into both. `triangle_offset` counts bytes of
//! `triangles` (three per triangle), as `meshopt_Meshlet` does, so converting to and from
//! meshoptimizer is a copy. Renderers, compressed formats and LOD levels all start from this.

pub mod bounds;
mod builder;
pub mod descriptor;
pub mod export;
pub mod io;
pub mod metrics;
pub mod order;
mod validate;

pub use bounds::{Cone, MeshletBounds, Sphere};
pub use builder::MeshletBuilder;
pub use metrics::Metrics;
pub use validate::{canonical, validate, ValidationError};

use serde::Serialize;
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

/// A collection of meshlets over one mesh.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Meshlets {
    /// The meshlets, in build order.
    pub meshlets: Vec<Meshlet>,
    /// Global vertex indices, `vertex_count` per meshlet from its `vertex_offset`.
    pub vertices: Vec<u32>,
    /// Local triangle corners (indices into the meshlet's vertex range), three per triangle.
    pub triangles: Vec<u8>,
}

impl Meshlets {
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

/// Per-meshlet size limits. Mesh-shader hardware and meshoptimizer cap both at 256 here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct Limits {
    /// Most vertices in one meshlet (3..=256).
    pub max_vertices: u32,
    /// Most triangles in one meshlet (1..=256).
    pub max_triangles: u32,
}

impl Limits {
    /// The JCGT paper's (and NVIDIA's recommended) 64 vertices / 126 triangles.
    pub const DEFAULT: Limits = Limits {
        max_vertices: 64,
        max_triangles: 126,
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

    /// Checked constructor.
    pub fn new(max_vertices: u32, max_triangles: u32) -> Result<Self, String> {
        if !(3..=256).contains(&max_vertices) {
            return Err(format!(
                "max vertices must be in 3..=256, got {max_vertices}"
            ));
        }
        if !(1..=256).contains(&max_triangles) {
            return Err(format!(
                "max triangles must be in 1..=256, got {max_triangles}"
            ));
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

impl FromStr for Limits {
    type Err = String;
    /// Parses `VERTICES/TRIANGLES`, e.g. `64/126`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (v, t) = s
            .split_once('/')
            .ok_or_else(|| format!("limits '{s}' must look like 64/126"))?;
        let v = v
            .trim()
            .parse()
            .map_err(|_| format!("'{v}' is not a vertex count"))?;
        let t = t
            .trim()
            .parse()
            .map_err(|_| format!("'{t}' is not a triangle count"))?;
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
}
