//! The peer: meshoptimizer's meshlet codec (`meshopt_encodeMeshlet` after
//! `meshopt_optimizeMeshletLevel(3)`) for triangles and vertex references, with positions stored
//! per meshlet on the shared power-of-two grid ([`super::grid_exponent`]) as a per-meshlet anchor
//! and per-axis bit widths: the layout meshoptimizer's documentation recommends for meshlet
//! positions. Every vertex a meshlet uses is stored in that meshlet (1.3-1.8x duplication: the
//! lever laced wires pull).
//!
//! **Layout**, per meshlet, byte-aligned, each record padded to 4 bytes:
//!
//! | bytes | field |
//! |---|---|
//! | 1 | vertex count - 1 |
//! | 1 | triangle count - 1 |
//! | 3 | bits per axis (x, y, z), each <= 31 |
//! | 12 | anchor: the meshlet's smallest grid coordinate per axis (from the grid origin), i32 little-endian |
//! | 2 | connectivity length C, u16 little-endian |
//! | C | meshoptimizer's encoded meshlet (triangles and vertex references) |
//! | ceil(V (bx + by + bz) / 8) | positions: per vertex x, y, z minus the anchor, packed LSB first |
//!
//! plus a u32 offset per meshlet for random access. Position k belongs to the k-th decoded
//! vertex reference.

use super::bits::{BitReader, BitWriter};
use super::{anchored_box, dequantise, quantise, DecodeError, Sizes};
pub use super::{Decoded, Encoded};
use crate::mesh::Mesh;
use crate::meshlet::Meshlets;

const HEADER: usize = 19;

/// Why a meshlet set cannot be encoded.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum MeshoptEncodeError {
    /// Grid coordinates beyond i32 (a tolerance far below the coordinates' magnitude).
    #[error(
        "meshlet {0}: grid coordinates exceed 32 bits (tolerance too small for these coordinates)"
    )]
    GridTooFine(usize),
    /// A meshlet beyond 256 vertices or triangles, or an empty one.
    #[error("meshlet {0}: the codec takes 1 to 256 vertices and triangles")]
    Size(usize),
    /// A tolerance that is not positive and finite, or whose grid rounds a position past the
    /// f32 range.
    #[error("the tolerance is not positive and finite, or its grid rounds a position past f32")]
    Tolerance,
}

/// Encodes `ml` (meshlets of `mesh`) at `tolerance`.
pub fn encode(mesh: &Mesh, ml: &Meshlets, tolerance: f64) -> Result<Encoded, MeshoptEncodeError> {
    let e = super::checked_grid(mesh, tolerance).ok_or(MeshoptEncodeError::Tolerance)?;
    let origin = mesh.bounding_box().0.to_array();
    let mut data = Vec::new();
    let mut offsets = Vec::with_capacity(ml.len());
    let mut sizes = Sizes {
        headers: 4 * ml.len(),
        ..Default::default()
    };
    // Stored vertex ids in order of first use: the codec codes each reference against the one
    // before, so ids that rise meshlet by meshlet cost a few bits instead of a full index.
    let mut remap = vec![u32::MAX; mesh.vertex_count()];
    let mut stored_to_source: Vec<u32> = Vec::new();
    for i in 0..ml.len() {
        let mut vertices = ml.meshlet_vertices(i).to_vec();
        let mut triangles = ml.meshlet_triangles(i).to_vec();
        let (vc, tc) = (vertices.len(), triangles.len() / 3);
        if vc == 0 || tc == 0 || vc > 256 || tc > 256 {
            return Err(MeshoptEncodeError::Size(i));
        }
        meshopt::optimize_meshlet_level(&mut vertices, &mut triangles, 3);
        for v in &mut vertices {
            let r = &mut remap[*v as usize];
            if *r == u32::MAX {
                *r = stored_to_source.len() as u32;
                stored_to_source.push(*v);
            }
            *v = *r;
        }
        let conn = meshopt::encode_meshlet(meshopt::Meshlet {
            vertices: &vertices,
            triangles: &triangles,
        })
        .map_err(|_| MeshoptEncodeError::Size(i))?;
        // The decoder returns references in the order the encoder stored them: decode once to
        // learn that order, so positions follow it.
        let (order, _) =
            meshopt::decode_meshlet(&conn, vc, tc).map_err(|_| MeshoptEncodeError::Size(i))?;
        let q: Vec<[i64; 3]> = order
            .iter()
            .map(|&v| {
                let p = mesh.positions[stored_to_source[v as usize] as usize];
                [0, 1, 2].map(|a| quantise(p[a], origin[a], e))
            })
            .collect();
        let (anchor, top, bits) = anchored_box(&q);
        if anchor
            .iter()
            .chain(&top)
            .any(|&x| x < i32::MIN as i64 || x > i32::MAX as i64)
        {
            return Err(MeshoptEncodeError::GridTooFine(i));
        }
        if bits.iter().any(|&b| b > 31) {
            return Err(MeshoptEncodeError::GridTooFine(i));
        }
        let start = data.len();
        offsets.push(start as u32);
        data.push((vc - 1) as u8);
        data.push((tc - 1) as u8);
        data.extend(bits.map(|b| b as u8));
        for a in anchor {
            data.extend((a as i32).to_le_bytes());
        }
        data.extend((conn.len() as u16).to_le_bytes());
        data.extend_from_slice(&conn);
        let mut w = BitWriter::new();
        for p in &q {
            for a in 0..3 {
                w.put(bits[a], (p[a] - anchor[a]) as u32);
            }
        }
        let packed = w.into_bytes();
        data.extend_from_slice(&packed);
        let pad = (4 - data.len() % 4) % 4;
        data.resize(data.len() + pad, 0);
        sizes.headers += HEADER;
        // The anchor and the bits per axis place the positions.
        sizes.geometry_headers += 15;
        sizes.connectivity += conn.len();
        sizes.positions += packed.len();
        sizes.padding += pad;
        debug_assert_eq!(data.len() - start, HEADER + conn.len() + packed.len() + pad);
    }
    Ok(Encoded {
        exponent: e,
        origin,
        source_vertices: mesh.vertex_count() as u32,
        offsets,
        data,
        sizes,
        wire_base: Vec::new(),
        stored_to_source,
    })
}

/// Decodes meshlet `i` from the buffer alone.
pub fn decode(enc: &Encoded, i: usize) -> Result<Decoded, DecodeError> {
    let trunc = |what| DecodeError::Truncated { meshlet: i, what };
    let start = *enc.offsets.get(i).ok_or(DecodeError::OutOfRange(i))? as usize;
    let rec = enc.data.get(start..).ok_or(trunc("offset"))?;
    let head = rec.get(..HEADER).ok_or(trunc("header"))?;
    let (vc, tc) = (head[0] as usize + 1, head[1] as usize + 1);
    let bits = [head[2] as u32, head[3] as u32, head[4] as u32];
    if bits.iter().any(|&b| b > 31) {
        return Err(DecodeError::Invalid {
            meshlet: i,
            what: format!("bits per axis {bits:?} above 31"),
        });
    }
    let anchor: [i64; 3] = [0, 1, 2]
        .map(|a| i32::from_le_bytes(head[5 + 4 * a..9 + 4 * a].try_into().unwrap()) as i64);
    let clen = u16::from_le_bytes([head[17], head[18]]) as usize;
    let conn = rec
        .get(HEADER..HEADER + clen)
        .ok_or(trunc("connectivity"))?;
    let (vertices, tris) =
        meshopt::decode_meshlet(conn, vc, tc).map_err(|e| DecodeError::Invalid {
            meshlet: i,
            what: format!("connectivity: {e:?}"),
        })?;
    let vertices: Vec<u32> = vertices
        .iter()
        .map(|&v| {
            enc.stored_to_source
                .get(v as usize)
                .copied()
                .filter(|&s| s < enc.source_vertices)
                .ok_or_else(|| DecodeError::Invalid {
                    meshlet: i,
                    what: format!("vertex reference {v} beyond the stored vertices"),
                })
        })
        .collect::<Result<_, _>>()?;
    let triangles: Vec<[u8; 3]> = tris[..3 * tc]
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    if let Some(t) = triangles
        .iter()
        .find(|t| t.iter().any(|&c| c as usize >= vc))
    {
        return Err(DecodeError::Invalid {
            meshlet: i,
            what: format!("triangle {t:?} beyond {vc} vertices"),
        });
    }
    let mut r = BitReader::new(&rec[HEADER + clen..], 0, i, "positions");
    let mut positions = Vec::with_capacity(vc);
    for _ in 0..vc {
        let mut p = [0f32; 3];
        for a in 0..3 {
            let d = r.get(bits[a])?;
            p[a] = dequantise(anchor[a] + d as i64, enc.origin[a], enc.exponent);
        }
        positions.push(p);
    }
    Ok(Decoded {
        vertices,
        triangles,
        positions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::strategy::{by_name, Options};

    #[test]
    fn a_truncated_or_corrupt_record_is_an_error_not_a_panic() {
        let mesh = generate::noisy_sphere(2, 0.2, 3);
        let ml = by_name("meshopt", &Options::default())
            .unwrap()
            .build(&mesh, crate::meshlet::Limits::DEFAULT);
        let enc = encode(&mesh, &ml, super::super::paper_tolerance(&mesh)).unwrap();
        assert!(decode(&enc, 0).is_ok());
        assert_eq!(
            decode(&enc, ml.len()),
            Err(DecodeError::OutOfRange(ml.len()))
        );
        let mut cut = enc.clone();
        cut.data.truncate(enc.offsets[0] as usize + 10);
        assert!(matches!(
            decode(&cut, 0),
            Err(DecodeError::Truncated { .. })
        ));
        let mut bad = enc.clone();
        bad.data[enc.offsets[0] as usize + 2] = 40;
        assert!(matches!(decode(&bad, 0), Err(DecodeError::Invalid { .. })));
        // Every single-byte corruption of the first record decodes or errs, never panics.
        for k in 0..enc.offsets.get(1).copied().unwrap_or(64) as usize {
            for x in [0u8, 0xff, 0x55] {
                let mut c = enc.clone();
                c.data[k] = x;
                let _ = decode(&c, 0);
            }
        }
    }
}
