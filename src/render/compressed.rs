//! Compressed meshlets drawn from their encoded bytes (Mlakar et al. 2024, §4): what goes to the
//! GPU and the CPU check that guards it.
//!
//! The device holds exactly the encoding (`Encoded::data`, padded to 32-bit words), its per-meshlet
//! offset table and, for the two formats drawn through the vertex pipeline, a first-triangle table;
//! no decoded copy. Which shaders decode which format:
//!
//! | format | task shader | decoder |
//! |---|---|---|
//! | laced wires | `compressed.task` with its culling records | `laced.mesh` (parallel, see its header) |
//! | SC, IX compact | `compressed.task`, no culling data | `compact.mesh` |
//! | GI, TS compact | none | `compact.vert`, one vertex per triangle corner |
//!
//! meshoptimizer's codec and the basic (f32) formats have no shader here: the codec is a byte
//! stream meant for CPU decoding, and the basic formats are the uncompressed layouts' peers that
//! the descriptor pass already draws.
//!
//! **Before upload** every meshlet is decoded on the CPU ([`prepare`]): a corrupted buffer is
//! rejected with a typed error naming the meshlet and never reaches the GPU. The shaders read the
//! fields the CPU decoder read, so a buffer that decodes is a buffer the shaders read in range.
//! Positions must also lie within 2^24 grid steps of the origin (the shaders dequantise in f32,
//! exactly there) and the counts within the shader variant's outputs.

use super::RenderError;
use crate::compress::Codec;
use crate::compress::{DecodeError, Encoded};
use crate::mesh::Mesh;
use crate::meshlet::{Meshlet, Meshlets};

/// How a compressed format is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decoder {
    /// Task and mesh shaders (laced wires, SC and IX compact).
    Mesh,
    /// One non-indexed draw through the vertex shader (GI and TS compact).
    Vertex,
}

/// An encoding checked and laid out for the GPU.
#[derive(Clone, Debug)]
pub struct Upload {
    /// The format.
    pub format: Codec,
    /// The encoded bytes as little-endian words (zero-padded to a word).
    pub words: Vec<u32>,
    /// Byte offset of each meshlet's record.
    pub offsets: Vec<u32>,
    /// First triangle of each meshlet and the total (vertex-pipeline formats; empty otherwise).
    pub first_triangle: Vec<u32>,
    /// Grid origin.
    pub origin: [f32; 3],
    /// Grid step `2^e`.
    pub step: f32,
    /// Triangles over all meshlets.
    pub triangles: usize,
    /// Largest vertex and triangle count of a meshlet (picks the shader variant).
    pub max_counts: (usize, usize),
}

impl Upload {
    /// Bytes resident on the device: the encoding, its offset table and the first-triangle table.
    pub fn device_bytes(&self) -> usize {
        4 * (self.words.len() + self.offsets.len() + self.first_triangle.len())
    }

    /// Meshlets.
    pub fn meshlets(&self) -> usize {
        self.offsets.len()
    }
}

/// How `format` is decoded on the GPU, or why it is not.
pub fn decoder(format: Codec) -> Result<Decoder, RenderError> {
    match format {
        Codec::LacedWires | Codec::ScCompact | Codec::IxCompact => Ok(Decoder::Mesh),
        Codec::GiCompact | Codec::TsCompact => Ok(Decoder::Vertex),
        f => Err(RenderError::NoShaderDecoder(f.name())),
    }
}

/// The formats the GPU decodes, in the order the bench reports them.
pub const FORMATS: [Codec; 5] = [
    Codec::LacedWires,
    Codec::ScCompact,
    Codec::IxCompact,
    Codec::GiCompact,
    Codec::TsCompact,
];

/// Checks `enc` (in `format`) by decoding every meshlet on the CPU and lays it out for upload.
pub fn prepare(enc: &Encoded, format: Codec) -> Result<Upload, RenderError> {
    let how = decoder(format)?;
    let bad =
        |meshlet: usize, what: String| RenderError::Corrupt(DecodeError::Invalid { meshlet, what });
    if enc.offsets.is_empty() {
        return Err(bad(0, "no meshlets".into()));
    }
    let step = (enc.exponent as f64).exp2();
    // The shaders dequantise in f32: exact (the CPU's bits) for grid points below 2^24, a grid
    // finer than f32 can place anyway. Positions beyond that extent are refused.
    let hi: [f64; 3] = enc.origin.map(|o| o as f64 + step * (1u64 << 24) as f64);
    let mut first_triangle = Vec::with_capacity(enc.offsets.len() + 1);
    let mut triangles = 0usize;
    let mut max_counts = (0, 0);
    for i in 0..enc.offsets.len() {
        let d = format.decode(enc, i)?;
        if format == Codec::LacedWires {
            // The task shader reads the culling record.
            crate::compress::laced::culling(enc, i)?;
        }
        let (v, t) = (d.positions.len(), d.triangles.len());
        if t == 0 {
            return Err(bad(i, "no triangles".into()));
        }
        for p in &d.positions {
            for a in 0..3 {
                let x = p[a] as f64;
                if !(x >= enc.origin[a] as f64 && x <= hi[a]) {
                    return Err(bad(
                        i,
                        format!(
                            "position {p:?} off the grid's first 2^24 steps (f32 in the shaders)"
                        ),
                    ));
                }
            }
        }
        max_counts = (max_counts.0.max(v), max_counts.1.max(t));
        first_triangle.push(triangles as u32);
        triangles += t;
    }
    if triangles >= 1 << 30 {
        return Err(bad(0, format!("{triangles} triangles in one draw")));
    }
    first_triangle.push(triangles as u32);
    if how == Decoder::Mesh && (max_counts.0 > 256 || max_counts.1 > 256) {
        return Err(bad(
            0,
            format!(
                "a meshlet of {} vertices / {} triangles: the mesh shaders take 256/256",
                max_counts.0, max_counts.1
            ),
        ));
    }
    let mut words: Vec<u32> = enc
        .data
        .chunks(4)
        .map(|c| {
            let mut b = [0u8; 4];
            b[..c.len()].copy_from_slice(c);
            u32::from_le_bytes(b)
        })
        .collect();
    // One spare word: a read of a field that ends on the last word may touch the next.
    words.push(0);
    Ok(Upload {
        format,
        words,
        offsets: enc.offsets.clone(),
        first_triangle: if how == Decoder::Vertex {
            first_triangle
        } else {
            Vec::new()
        },
        origin: enc.origin,
        step: step as f32,
        triangles,
        max_counts,
    })
}

/// The uncompressed reference for an image test: one vertex per decoded meshlet vertex, at the
/// position the CPU decoder gives it, and the meshlets exactly as decoded (same local vertex
/// order, triangles, corner rotation and meshlet order as the shaders emit; the index buffer in
/// that order too). Drawn by the uncompressed pass it must give the compressed pass's image. Each
/// meshlet owns its vertices, so the reference holds even for a buffer whose copies of one source
/// vertex disagree (a damaged but decodable SC record).
pub fn decoded_reference(enc: &Encoded, format: Codec) -> Result<(Mesh, Meshlets), DecodeError> {
    let mut mesh = Mesh::empty();
    let mut ml = Meshlets::default();
    for i in 0..enc.offsets.len() {
        let d = format.decode(enc, i)?;
        let first = mesh.positions.len() as u32;
        ml.meshlets.push(Meshlet {
            vertex_offset: first,
            triangle_offset: ml.triangles.len() as u32,
            vertex_count: d.positions.len() as u32,
            triangle_count: d.triangles.len() as u32,
        });
        ml.vertices.extend(first..first + d.positions.len() as u32);
        mesh.positions.extend(&d.positions);
        for t in &d.triangles {
            ml.triangles.extend(t);
            mesh.indices.extend(t.map(|c| first + c as u32));
        }
    }
    Ok((mesh, ml))
}
