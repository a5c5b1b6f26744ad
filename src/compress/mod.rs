//! Compressed meshlets (Mlakar, Steinberger, Schmalstieg, "End-to-End Compressed Meshlet
//! Rendering", CGF 43(1), 2024), one file per format family: the shared position
//! grid, the size accounting every format reports, the strongest public peer, meshoptimizer's
//! meshlet codec with anchored positions ([`meshopt_codec`]), laced wires ([`laced`]) and the
//! paper's TS/IX/SC/GI comparison formats ([`baseline`]).
//!
//! **Positions.** Every format quantises on one global power-of-two grid anchored at the mesh's
//! bounding-box minimum `o`: step `2^e`, the largest with `step / 2 <= tolerance`, so every decoded
//! position lies within the tolerance of the original, and a vertex shared by several meshlets
//! decodes to the same bits from each (crack-free by construction). A grid coordinate `q` decodes
//! as `o + q * 2^e` with one rounding to f32 (`q * 2^e` is exact). Anchoring at `o` keeps `q`
//! small for a mesh far from the origin (1e6 away, a 14-bit grid still needs 15 bits, not 35), and
//! where the grid is finer than f32's spacing at that distance the rounding lands back on the
//! original value exactly, so f32 never adds error beyond the tolerance.
//!
//! **Bits.** Every codec packs its fields through one bit writer and reader (`bits.rs`), least
//! significant bit first: the order the shaders (glsl/compressed.glsl `bits_at`) read the same
//! bytes in.

pub mod baseline;
mod bits;
mod codec;
#[cfg(feature = "io")]
pub mod file;
pub mod laced;
pub mod meshopt_codec;

use crate::mesh::Mesh;
use bits::width;
pub use codec::Codec;
use thiserror::Error;

/// Why a meshlet set cannot be encoded, by format.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum EncodeError {
    /// meshoptimizer's codec.
    #[error(transparent)]
    Meshopt(#[from] meshopt_codec::MeshoptEncodeError),
    /// Laced wires.
    #[error(transparent)]
    Laced(#[from] laced::LacedEncodeError),
    /// The paper's comparison formats.
    #[error(transparent)]
    Baseline(#[from] baseline::BaselineEncodeError),
}

/// A corrupt or truncated encoded buffer.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
pub enum DecodeError {
    /// The buffer ends before the data it announces.
    #[error("encoded meshlet {meshlet}: truncated ({what})")]
    Truncated {
        /// Meshlet index.
        meshlet: usize,
        /// Which part.
        what: &'static str,
    },
    /// A field holds an impossible value.
    #[error("encoded meshlet {meshlet}: {what}")]
    Invalid {
        /// Meshlet index.
        meshlet: usize,
        /// What is wrong.
        what: String,
    },
    /// No such meshlet.
    #[error("meshlet {0} out of range")]
    OutOfRange(usize),
}

/// An encoded meshlet set.
#[derive(Clone, Debug, PartialEq)]
pub struct Encoded {
    /// Grid step exponent.
    pub exponent: i32,
    /// Grid origin (the mesh's bounding-box minimum).
    pub origin: [f32; 3],
    /// Vertices of the source mesh (references must stay below).
    pub source_vertices: u32,
    /// Byte offset of each meshlet's record.
    pub offsets: Vec<u32>,
    /// The records.
    pub data: Vec<u8>,
    /// What the bytes hold.
    pub sizes: Sizes,
    /// Laced wires: the first stored-vertex id of each wire (provenance: maps decoded vertices
    /// to the source mesh's; not part of the format). Empty for the other formats.
    pub wire_base: Vec<u32>,
    /// Laced wires: the source vertex of each stored vertex (provenance, as above).
    pub stored_to_source: Vec<u32>,
}

/// One decoded meshlet.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// Source vertex indices.
    pub vertices: Vec<u32>,
    /// Triangles over `vertices`.
    pub triangles: Vec<[u8; 3]>,
    /// Decoded position of each vertex.
    pub positions: Vec<[f32; 3]>,
}

/// The paper's default tolerance: the error of 14-bit quantisation of the mesh's bounding box
/// (half a step of 2^14 steps over its largest extent).
pub fn paper_tolerance(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.bounding_box();
    let extent = (hi - lo).max_element() as f64;
    (extent / 16384.0 / 2.0).max(f64::MIN_POSITIVE)
}

/// The global grid for a tolerance: exponent `e` of the step `2^e`, the largest step whose
/// half is within `tolerance`.
pub fn grid_exponent(tolerance: f64) -> i32 {
    (2.0 * tolerance).log2().floor() as i32
}

/// The grid exponent for `tolerance` over `mesh` (origin its box's low corner, as every codec
/// places it), or `None` when the tolerance is not positive and finite or the grid rounds the
/// box's high corner past the f32 range (a position near f32::MAX and a coarse step), which
/// would decode to an infinity.
pub(crate) fn checked_grid(mesh: &Mesh, tolerance: f64) -> Option<i32> {
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return None;
    }
    let e = grid_exponent(tolerance);
    let (lo, hi) = mesh.bounding_box();
    let fits = (0..3).all(|a| dequantise(quantise(hi[a], lo[a], e), lo[a], e).is_finite());
    fits.then_some(e)
}

/// Grid coordinate of a position component relative to the grid origin `o`.
pub fn quantise(x: f32, o: f32, e: i32) -> i64 {
    ((x as f64 - o as f64) * (-e as f64).exp2()).round() as i64
}

/// Position component of a grid coordinate (one rounding to f32).
pub fn dequantise(q: i64, o: f32, e: i32) -> f32 {
    (o as f64 + q as f64 * (e as f64).exp2()) as f32
}

/// Bytes of an encoding, by what they hold (the paper reports these separately).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Sizes {
    /// Triangle connectivity and vertex references.
    pub connectivity: usize,
    /// Vertex positions.
    pub positions: usize,
    /// Per-meshlet headers and the random-access offset table.
    pub headers: usize,
    /// Of `headers`: the bytes that place positions (per-wire or per-meshlet boxes: anchors, bit
    /// widths, laced wires' wire table); the paper counts them as geometry. Not added again in
    /// [`Sizes::total`].
    pub geometry_headers: usize,
    /// Per-meshlet culling records (laced wires).
    pub culling: usize,
    /// Alignment padding.
    pub padding: usize,
}

impl Sizes {
    /// All bytes.
    pub fn total(&self) -> usize {
        self.connectivity + self.positions + self.headers + self.culling + self.padding
    }
}

/// The box of grid points, (lowest, highest) per axis, and its bits per axis; zeros when empty.
/// Every format that anchors positions (per wire, per meshlet) stores `lo` and offsets in `bits`.
pub(crate) fn anchored_box(q: &[[i64; 3]]) -> ([i64; 3], [i64; 3], [u32; 3]) {
    let Some(&first) = q.first() else {
        return ([0; 3], [0; 3], [0; 3]);
    };
    let (mut lo, mut hi) = (first, first);
    for p in q {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi, [0, 1, 2].map(|a| width((hi[a] - lo[a]) as u64)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_meets_the_tolerance() {
        for t in [1e-6, 3e-4, 0.5, 7.0] {
            let e = grid_exponent(t);
            assert!((e as f64).exp2() / 2.0 <= t && ((e + 1) as f64).exp2() / 2.0 > t);
            for x in [0.1f32, -3.7, 123.456, 1e3] {
                let err = (dequantise(quantise(x, -5.0, e), -5.0, e) as f64 - x as f64).abs();
                assert!(err <= t + (x.abs() as f64) * 1e-7, "{x} at {t}: {err}");
            }
        }
    }
}
