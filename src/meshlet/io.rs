//! The meshlet file format written by `meshletlab build` and read by `meshletlab check`.
//!
//! All integers little-endian:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `MLTLAB01` |
//! | 4 + 4 | limits: max vertices, max triangles |
//! | 4 + 4 | source mesh vertex count, triangle count |
//! | 8 | source mesh fingerprint (FNV-1a of positions and indices, see `Mesh::fingerprint`) |
//! | 4 | strategy name length L, then L bytes of UTF-8 |
//! | 4 + 4 + 4 | meshlet count M, vertex index count V, triangle byte count B |
//! | 16 M | meshlets: vertex_offset, triangle_offset, vertex_count, triangle_count (u32 each) |
//! | 4 V | global vertex indices (u32) |
//! | B | local triangle corners (u8, three per triangle) |
//!
//! Readers check every count against the bytes present before allocating, and reject trailing bytes.

use super::{Limits, Meshlet, Meshlets};
use std::path::Path;
use thiserror::Error;

const MAGIC: &[u8; 8] = b"MLTLAB01";

/// A meshlet file's contents.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshletFile {
    /// Limits the meshlets were built for.
    pub limits: Limits,
    /// Vertex count of the source mesh.
    pub source_vertices: u32,
    /// Triangle count of the source mesh.
    pub source_triangles: u32,
    /// Fingerprint of the source mesh.
    pub fingerprint: u64,
    /// Strategy name.
    pub strategy: String,
    /// The meshlets.
    pub meshlets: Meshlets,
}

/// An error reading, writing or checking one of the project's files (meshlet, LOD, compressed);
/// the message names the file.
#[derive(Debug, Error)]
#[error("{}: {message}", path.display())]
pub struct FileError {
    /// The file.
    pub path: std::path::PathBuf,
    /// What is wrong.
    pub message: String,
}

/// Errors reading a meshlet file.
pub type MeshletFileError = FileError;

/// Writes `bytes` to `path` (atomically: an interrupted write leaves the previous file).
pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    crate::atomic::write(path, bytes).map_err(|e| FileError {
        path: path.to_path_buf(),
        message: format!("cannot write: {e}"),
    })
}

/// Reads `path`.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, FileError> {
    std::fs::read(path).map_err(|e| FileError {
        path: path.to_path_buf(),
        message: format!("cannot read: {e}"),
    })
}

impl MeshletFile {
    /// Serialises to bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let ml = &self.meshlets;
        let mut b = Vec::with_capacity(
            64 + ml.meshlets.len() * 16 + ml.vertices.len() * 4 + ml.triangles.len(),
        );
        b.extend_from_slice(MAGIC);
        for v in [
            self.limits.max_vertices,
            self.limits.max_triangles,
            self.source_vertices,
            self.source_triangles,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&self.fingerprint.to_le_bytes());
        b.extend_from_slice(&(self.strategy.len() as u32).to_le_bytes());
        b.extend_from_slice(self.strategy.as_bytes());
        for v in [ml.meshlets.len(), ml.vertices.len(), ml.triangles.len()] {
            b.extend_from_slice(&(v as u32).to_le_bytes());
        }
        for m in &ml.meshlets {
            for v in [
                m.vertex_offset,
                m.triangle_offset,
                m.vertex_count,
                m.triangle_count,
            ] {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        for v in &ml.vertices {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&ml.triangles);
        b
    }

    /// Parses bytes; `path` labels errors.
    pub fn from_bytes(data: &[u8], path: &Path) -> Result<Self, MeshletFileError> {
        let err = |m: String| MeshletFileError {
            path: path.to_path_buf(),
            message: m,
        };
        let mut r = Reader { data, pos: 0 };
        if r.bytes(8)
            .ok_or_else(|| err("file is too short to be a meshlet file".into()))?
            != MAGIC
        {
            return Err(err("not a meshletlab meshlet file (bad magic)".into()));
        }
        let trunc = || err("file is truncated".into());
        let (mv, mt) = (r.u32().ok_or_else(trunc)?, r.u32().ok_or_else(trunc)?);
        let limits = Limits::new(mv, mt).map_err(|e| err(format!("bad limits in header: {e}")))?;
        let source_vertices = r.u32().ok_or_else(trunc)?;
        let source_triangles = r.u32().ok_or_else(trunc)?;
        let fingerprint = r.u64().ok_or_else(trunc)?;
        let name_len = r.u32().ok_or_else(trunc)? as usize;
        let name = r.bytes(name_len).ok_or_else(|| {
            err(format!(
                "strategy name of {name_len} bytes runs past the end"
            ))
        })?;
        let strategy = String::from_utf8(name.to_vec())
            .map_err(|_| err("strategy name is not UTF-8".into()))?;
        let m = r.u32().ok_or_else(trunc)? as usize;
        let v = r.u32().ok_or_else(trunc)? as usize;
        let t = r.u32().ok_or_else(trunc)? as usize;
        let need = m as u64 * 16 + v as u64 * 4 + t as u64;
        let have = (data.len() - r.pos) as u64;
        if need != have {
            return Err(err(format!(
                "header announces {m} meshlets, {v} vertex indices and {t} triangle bytes ({need} bytes), but {have} bytes follow"
            )));
        }
        let meshlets = (0..m)
            .map(|_| {
                let f = [r.u32(), r.u32(), r.u32(), r.u32()].map(|x| x.expect("length checked"));
                Meshlet {
                    vertex_offset: f[0],
                    triangle_offset: f[1],
                    vertex_count: f[2],
                    triangle_count: f[3],
                }
            })
            .collect();
        let vertices = (0..v).map(|_| r.u32().expect("length checked")).collect();
        let triangles = r.bytes(t).expect("length checked").to_vec();
        Ok(Self {
            limits,
            source_vertices,
            source_triangles,
            fingerprint,
            strategy,
            meshlets: Meshlets {
                meshlets,
                vertices,
                triangles,
            },
        })
    }

    /// `meshletlab check`: the file was built from `mesh` (counts and fingerprint agree) and its
    /// meshlets pass the validator under the file's limits. `path` labels errors.
    pub fn check(&self, mesh: &crate::mesh::Mesh, path: &Path) -> Result<(), MeshletFileError> {
        let err = |m: String| MeshletFileError {
            path: path.to_path_buf(),
            message: m,
        };
        same_source(
            mesh,
            self.source_vertices,
            self.source_triangles,
            self.fingerprint,
        )
        .map_err(err)?;
        super::validate(mesh, &self.meshlets, self.limits).map_err(|e| err(format!("invalid: {e}")))
    }

    /// Writes to a file.
    pub fn save(&self, path: &Path) -> Result<(), MeshletFileError> {
        write_file(path, &self.to_bytes())
    }

    /// Reads from a file.
    pub fn load(path: &Path) -> Result<Self, MeshletFileError> {
        Self::from_bytes(&read_file(path)?, path)
    }
}

/// Whether a file's recorded source (vertex and triangle counts, fingerprint) is `mesh`; the
/// message says what differs. Shared by the meshlet and LOD files.
pub(crate) fn same_source(
    mesh: &crate::mesh::Mesh,
    vertices: u32,
    triangles: u32,
    fingerprint: u64,
) -> Result<(), String> {
    if vertices as usize != mesh.vertex_count() || triangles as usize != mesh.triangle_count() {
        return Err(format!(
            "built from a mesh with {vertices} vertices / {triangles} triangles, but this mesh has {} / {}",
            mesh.vertex_count(),
            mesh.triangle_count()
        ));
    }
    if fingerprint != mesh.fingerprint() {
        return Err("built from a different mesh (fingerprint differs)".into());
    }
    Ok(())
}

/// A bounds-checked little-endian reader over a byte slice (shared by the file formats).
pub(crate) struct Reader<'a> {
    pub(crate) data: &'a [u8],
    pub(crate) pos: usize,
}

impl<'a> Reader<'a> {
    /// Bytes left.
    pub(crate) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
    pub(crate) fn bytes(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.data.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }
    pub(crate) fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.bytes(4)?.try_into().ok()?))
    }
    pub(crate) fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.bytes(8)?.try_into().ok()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> MeshletFile {
        MeshletFile {
            limits: Limits::DEFAULT,
            source_vertices: 4,
            source_triangles: 2,
            fingerprint: 0xdead_beef,
            strategy: "nvidia".into(),
            meshlets: Meshlets {
                meshlets: vec![Meshlet {
                    vertex_offset: 0,
                    triangle_offset: 0,
                    vertex_count: 4,
                    triangle_count: 2,
                }],
                vertices: vec![0, 1, 2, 3],
                triangles: vec![0, 1, 2, 0, 2, 3],
            },
        }
    }

    #[test]
    fn round_trip_and_corruption() {
        let f = sample();
        let b = f.to_bytes();
        let p = Path::new("x.mlt");
        assert_eq!(MeshletFile::from_bytes(&b, p).unwrap(), f);
        for cut in [0, 7, 20, b.len() - 1] {
            assert!(
                MeshletFile::from_bytes(&b[..cut], p).is_err(),
                "cut at {cut}"
            );
        }
        let mut long = b.clone();
        long.push(0);
        assert!(MeshletFile::from_bytes(&long, p).is_err());
        let mut bad = b.clone();
        bad[0] = b'X';
        assert!(MeshletFile::from_bytes(&bad, p)
            .unwrap_err()
            .to_string()
            .starts_with("x.mlt: "));
        // An absurd meshlet count must not allocate: it fails the length check.
        let mut huge = b.clone();
        let at = 8 + 16 + 8 + 4 + 6;
        huge[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(MeshletFile::from_bytes(&huge, p).is_err());
    }
}
