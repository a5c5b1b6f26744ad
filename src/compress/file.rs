//! The compressed-meshlet file written by `meshletlab compress` and read by `meshletlab check`.
//!
//! All integers little-endian:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `MLTCMP01` |
//! | 4 | format: 1 = meshoptimizer's codec with anchored positions ([`super::meshopt_codec`]), 2 = laced wires ([`super::laced`]), 3-10 = TS, TS compact, IX, IX compact, SC, SC compact, GI, GI compact ([`super::baseline`]) |
//! | 4, 4, 8 | source mesh vertex count, triangle count, fingerprint |
//! | 8 | tolerance (f64): every decoded position is within it of the source's |
//! | 4 | grid exponent (i32) |
//! | 12 | grid origin (3 x f32) |
//! | 4 | meshlet count M |
//! | 4 M | byte offset of each meshlet's record in the data |
//! | 4 | data length D |
//! | D | the encoding (layout: [`super::meshopt_codec`], [`super::laced`]) |
//! | 4, 4 W | wire count W (0 but for laced wires), first stored-vertex id of each wire |
//! | 4, 4 S | stored-vertex count S, source vertex of each |
//!
//! The last two tables are provenance: they let `check` compare decoded vertices with the source
//! mesh's and are not counted in the format's size.
//!
//! Readers check every count against the bytes present before allocating, reject NaN and
//! non-positive tolerances and trailing bytes; `check` decodes every meshlet at random access and
//! compares it with the mesh.

use super::{Codec, Encoded};
use crate::mesh::Mesh;
use crate::meshlet::io::Reader;
use std::path::Path;

const MAGIC: &[u8; 8] = b"MLTCMP01";

/// A compressed-meshlet file.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressedFile {
    /// Vertex count of the source mesh.
    pub source_vertices: u32,
    /// Triangle count of the source mesh.
    pub source_triangles: u32,
    /// Fingerprint of the source mesh.
    pub fingerprint: u64,
    /// The format.
    pub format: Codec,
    /// Position tolerance the encoding guarantees.
    pub tolerance: f64,
    /// The encoded meshlets.
    pub encoded: Encoded,
}

/// Errors reading or checking a compressed file; the message names the file.
pub type CompressedFileError = crate::meshlet::io::FileError;

impl CompressedFile {
    /// Whether `data` starts like a compressed-meshlet file.
    pub fn sniff(data: &[u8]) -> bool {
        data.starts_with(MAGIC)
    }

    /// The file of `encoded`, an encoding of meshlets of `mesh` in `format` within `tolerance`.
    pub fn new(mesh: &Mesh, format: Codec, tolerance: f64, encoded: Encoded) -> Self {
        Self {
            source_vertices: mesh.vertex_count() as u32,
            source_triangles: mesh.triangle_count() as u32,
            fingerprint: mesh.fingerprint(),
            format,
            tolerance,
            encoded,
        }
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let e = &self.encoded;
        let mut b = Vec::with_capacity(64 + 4 * e.offsets.len() + e.data.len());
        b.extend_from_slice(MAGIC);
        b.extend(self.format.id().to_le_bytes());
        b.extend(self.source_vertices.to_le_bytes());
        b.extend(self.source_triangles.to_le_bytes());
        b.extend(self.fingerprint.to_le_bytes());
        b.extend(self.tolerance.to_le_bytes());
        b.extend(e.exponent.to_le_bytes());
        for o in e.origin {
            b.extend(o.to_le_bytes());
        }
        b.extend((e.offsets.len() as u32).to_le_bytes());
        for o in &e.offsets {
            b.extend(o.to_le_bytes());
        }
        b.extend((e.data.len() as u32).to_le_bytes());
        b.extend_from_slice(&e.data);
        for table in [&e.wire_base, &e.stored_to_source] {
            b.extend((table.len() as u32).to_le_bytes());
            for x in table {
                b.extend(x.to_le_bytes());
            }
        }
        b
    }

    /// Parses a file (structure only; [`CompressedFile::check`] decodes).
    pub fn from_bytes(data: &[u8], path: &Path) -> Result<Self, CompressedFileError> {
        let err = |m: String| CompressedFileError {
            path: path.to_path_buf(),
            message: m,
        };
        let short = || err("truncated compressed-meshlet file".into());
        let mut r = Reader { data, pos: 0 };
        if r.bytes(8).ok_or_else(short)? != MAGIC {
            return Err(err(
                "not a meshletlab compressed-meshlet file (bad magic)".into()
            ));
        }
        let id = r.u32().ok_or_else(short)?;
        let format = Codec::from_id(id).ok_or_else(|| err(format!("unknown format {id}")))?;
        let source_vertices = r.u32().ok_or_else(short)?;
        let source_triangles = r.u32().ok_or_else(short)?;
        let fingerprint = r.u64().ok_or_else(short)?;
        let tolerance = f64::from_bits(r.u64().ok_or_else(short)?);
        if !(tolerance > 0.0 && tolerance.is_finite()) {
            return Err(err(format!(
                "tolerance {tolerance} is not a positive number"
            )));
        }
        let exponent = r.u32().ok_or_else(short)? as i32;
        if !(-149..=127).contains(&exponent) {
            return Err(err(format!("grid exponent {exponent} outside f32's range")));
        }
        let mut origin = [0f32; 3];
        for o in &mut origin {
            *o = f32::from_bits(r.u32().ok_or_else(short)?);
            if !o.is_finite() {
                return Err(err("grid origin is not finite".into()));
            }
        }
        let count = r.u32().ok_or_else(short)? as usize;
        if count > r.remaining() / 4 {
            return Err(short());
        }
        let offsets: Vec<u32> = (0..count)
            .map(|_| r.u32().ok_or_else(short))
            .collect::<Result<_, _>>()?;
        let len = r.u32().ok_or_else(short)? as usize;
        let bytes = r.bytes(len).ok_or_else(short)?.to_vec();
        let mut tables = [Vec::new(), Vec::new()];
        for t in &mut tables {
            let n = r.u32().ok_or_else(short)? as usize;
            if n > r.remaining() / 4 {
                return Err(short());
            }
            *t = (0..n)
                .map(|_| r.u32().ok_or_else(short))
                .collect::<Result<_, _>>()?;
        }
        let [wire_base, stored_to_source] = tables;
        if r.remaining() > 0 {
            return Err(err(format!("{} trailing bytes", r.remaining())));
        }
        if let Some((i, o)) = offsets.iter().enumerate().find(|(_, &o)| o as usize >= len) {
            return Err(err(format!(
                "meshlet {i}: record offset {o} beyond {len} data bytes"
            )));
        }
        Ok(Self {
            source_vertices,
            source_triangles,
            fingerprint,
            format,
            tolerance,
            encoded: Encoded {
                exponent,
                origin,
                source_vertices,
                offsets,
                data: bytes,
                sizes: Default::default(),
                wire_base,
                stored_to_source,
            },
        })
    }

    /// Decodes every meshlet at random access and checks it against `mesh`: the source's
    /// triangles, each exactly once over all meshlets (winding kept up to rotation), and every
    /// position within the tolerance. Returns the largest position error.
    pub fn check(&self, mesh: &Mesh, path: &Path) -> Result<f64, CompressedFileError> {
        let err = |m: String| CompressedFileError {
            path: path.to_path_buf(),
            message: m,
        };
        crate::meshlet::io::same_source(
            mesh,
            self.source_vertices,
            self.source_triangles,
            self.fingerprint,
        )
        .map_err(err)?;
        use crate::meshlet::canonical;
        let mut want: Vec<[u32; 3]> = (0..mesh.triangle_count())
            .map(|t| canonical(mesh.triangle(t)))
            .collect();
        let mut got = Vec::with_capacity(want.len());
        let mut worst = 0.0f64;
        for i in 0..self.encoded.offsets.len() {
            let d = self
                .format
                .decode(&self.encoded, i)
                .map_err(|e| err(e.to_string()))?;
            for (k, &v) in d.vertices.iter().enumerate() {
                let o = mesh.positions[v as usize];
                let e = (0..3)
                    .map(|a| (d.positions[k][a] as f64 - o[a] as f64).abs())
                    .fold(0.0, f64::max);
                if e.is_nan() || e > self.tolerance {
                    return Err(err(format!(
                        "meshlet {i}: vertex {v} decodes {e} away, above the tolerance {}",
                        self.tolerance
                    )));
                }
                worst = worst.max(e);
            }
            got.extend(
                d.triangles
                    .iter()
                    .map(|t| canonical(t.map(|c| d.vertices[c as usize]))),
            );
        }
        want.sort_unstable();
        got.sort_unstable();
        if got != want {
            let missing = want.iter().find(|t| got.binary_search(t).is_err());
            return Err(err(format!(
                "the decoded triangles are not the mesh's ({} decoded, {} in the mesh; first missing: {missing:?})",
                got.len(),
                want.len()
            )));
        }
        Ok(worst)
    }

    /// Writes the file.
    pub fn save(&self, path: &Path) -> Result<(), CompressedFileError> {
        crate::meshlet::io::write_file(path, &self.to_bytes())
    }
}

/// Only with the tool: the names are checked against clap's.
#[cfg(all(test, feature = "tool"))]
mod tests {
    use super::*;

    /// `name()` is written out so the core needs no clap; it must stay clap's kebab-case.
    #[test]
    fn names_are_the_command_lines() {
        use clap::ValueEnum;
        for f in Codec::ALL {
            assert_eq!(f.name(), f.to_possible_value().unwrap().get_name());
        }
    }
}
