//! The LOD file written by `meshletlab lod` and read by `meshletlab lod-check`.
//!
//! All integers little-endian, floats IEEE-754 binary32:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `MLTLOD01` |
//! | 4 + 4 | limits: max vertices, max triangles |
//! | 4 + 4 | source mesh vertex count, triangle count |
//! | 8 | source mesh fingerprint (as in meshlet files) |
//! | 4 + S | strategy name length S, then S bytes of UTF-8 |
//! | 4 + 4 | level count L, group count G |
//! | 24 G | groups: children's level, first output meshlet, output count, triangles in, triangles out, stuck (u32 each) |
//! | ... | L levels, **coarsest first** (level L-1 down to 0), each: |
//! | 4 × 5 | level number, first meshlet (over all levels in file order), meshlet count M, new vertices (not used by a coarser level), vertex index count V, |
//! | 4 | triangle byte count B |
//! | 16 M | meshlets: vertex offset, triangle offset, vertex count, triangle count |
//! | 44 M | LOD data: centre xyz, radius, error, parent centre xyz, parent radius, parent error (f32), group (u32; 2^32-1 for a root) |
//! | 4 V + B | global vertex indices (u32), local triangle corners (u8) |
//!
//! Readers check every count against the bytes present before allocating, every float for NaN,
//! every group reference, and reject trailing bytes.

use super::{Group, Level, Lod, LodInfo, NO_GROUP};
use crate::meshlet::bounds::Sphere;
use crate::meshlet::io::Reader;
use crate::meshlet::{Limits, Meshlet, Meshlets};
use std::path::Path;

const MAGIC: &[u8; 8] = b"MLTLOD01";

/// A LOD file: the DAG and the source mesh it was built from.
#[derive(Clone, Debug, PartialEq)]
pub struct LodFile {
    /// Vertex count of the source mesh.
    pub source_vertices: u32,
    /// Triangle count of the source mesh.
    pub source_triangles: u32,
    /// Fingerprint of the source mesh.
    pub fingerprint: u64,
    /// The DAG.
    pub lod: Lod,
}

/// Errors reading or checking a LOD file; the message names the file.
pub type LodFileError = crate::meshlet::io::FileError;

fn sphere_bytes(b: &mut Vec<u8>, s: &Sphere) {
    for v in s.center.iter().chain([&s.radius]) {
        b.extend_from_slice(&v.to_le_bytes());
    }
}

impl LodFile {
    /// Serialises to bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let l = &self.lod;
        let mut b = Vec::new();
        b.extend_from_slice(MAGIC);
        for v in [
            l.limits.max_vertices,
            l.limits.max_triangles,
            self.source_vertices,
            self.source_triangles,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&self.fingerprint.to_le_bytes());
        b.extend_from_slice(&(l.strategy.len() as u32).to_le_bytes());
        b.extend_from_slice(l.strategy.as_bytes());
        b.extend_from_slice(&(l.levels.len() as u32).to_le_bytes());
        b.extend_from_slice(&(l.groups.len() as u32).to_le_bytes());
        for g in &l.groups {
            for v in [
                g.level,
                g.first,
                g.count,
                g.triangles_in,
                g.triangles_out,
                g.stuck as u32,
            ] {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        let new = new_vertices(l);
        let mut first = 0u32;
        for (n, level) in l.levels.iter().enumerate().rev() {
            let ml = &level.meshlets;
            for v in [
                n as u32,
                first,
                ml.len() as u32,
                new[n],
                ml.vertices.len() as u32,
                ml.triangles.len() as u32,
            ] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            first += ml.len() as u32;
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
            for i in &level.info {
                sphere_bytes(&mut b, &i.bounds);
                b.extend_from_slice(&i.error.to_le_bytes());
                sphere_bytes(&mut b, &i.parent_bounds);
                b.extend_from_slice(&i.parent_error.to_le_bytes());
                b.extend_from_slice(&i.group.to_le_bytes());
            }
            for v in &ml.vertices {
                b.extend_from_slice(&v.to_le_bytes());
            }
            b.extend_from_slice(&ml.triangles);
        }
        b
    }

    /// Parses bytes; `path` labels errors.
    pub fn from_bytes(data: &[u8], path: &Path) -> Result<Self, LodFileError> {
        let err = |m: String| LodFileError {
            path: path.to_path_buf(),
            message: m,
        };
        let trunc = || err("file is truncated".into());
        let mut r = Reader { data, pos: 0 };
        if r.bytes(8)
            .ok_or_else(|| err("too short to be a LOD file".into()))?
            != MAGIC
        {
            return Err(err("not a meshletlab LOD file (bad magic)".into()));
        }
        let (mv, mt) = (r.u32().ok_or_else(trunc)?, r.u32().ok_or_else(trunc)?);
        let limits = Limits::new(mv, mt).map_err(|e| err(format!("bad limits: {e}")))?;
        let source_vertices = r.u32().ok_or_else(trunc)?;
        let source_triangles = r.u32().ok_or_else(trunc)?;
        let fingerprint = r.u64().ok_or_else(trunc)?;
        let s = r.u32().ok_or_else(trunc)? as usize;
        let name = r.bytes(s).ok_or_else(trunc)?;
        let strategy = String::from_utf8(name.to_vec())
            .map_err(|_| err("strategy name is not UTF-8".into()))?;
        let nl = r.u32().ok_or_else(trunc)? as usize;
        let ng = r.u32().ok_or_else(trunc)? as usize;
        // Each level needs at least its 24-byte header, each group 24 bytes.
        if (nl as u64 * 24 + ng as u64 * 24) > r.remaining() as u64 {
            return Err(err(format!(
                "header announces {nl} levels and {ng} groups, more than the file holds"
            )));
        }
        let mut groups = Vec::with_capacity(ng);
        for _ in 0..ng {
            let f: Vec<u32> = (0..6).map(|_| r.u32().expect("length checked")).collect();
            groups.push(Group {
                level: f[0],
                first: f[1],
                count: f[2],
                triangles_in: f[3],
                triangles_out: f[4],
                stuck: f[5] != 0,
            });
        }
        let mut levels: Vec<Option<Level>> = vec![None; nl];
        let mut first = 0u64;
        for k in 0..nl {
            let h: Vec<u32> = (0..6)
                .map(|_| r.u32().ok_or_else(trunc))
                .collect::<Result<_, _>>()?;
            let (n, f, m, v, t) = (h[0] as usize, h[1], h[2] as u64, h[4] as u64, h[5] as u64);
            if n != nl - 1 - k || levels[n].is_some() {
                return Err(err(format!(
                    "level {n} out of order (expected {})",
                    nl - 1 - k
                )));
            }
            if f as u64 != first {
                return Err(err(format!(
                    "level {n}: first meshlet {f}, expected {first}"
                )));
            }
            first += m;
            if m * 60 + v * 4 + t > r.remaining() as u64 {
                return Err(err(format!(
                    "level {n} announces {m} meshlets, {v} indices and {t} triangle bytes, more than the file holds"
                )));
            }
            let meshlets: Vec<Meshlet> = (0..m)
                .map(|_| {
                    let f: Vec<u32> = (0..4).map(|_| r.u32().expect("length checked")).collect();
                    Meshlet {
                        vertex_offset: f[0],
                        triangle_offset: f[1],
                        vertex_count: f[2],
                        triangle_count: f[3],
                    }
                })
                .collect();
            let mut info = Vec::with_capacity(m as usize);
            for j in 0..m {
                let mut fl = [0f32; 10];
                for x in fl.iter_mut() {
                    *x = f32::from_le_bytes(r.u32().expect("length checked").to_le_bytes());
                }
                let group = r.u32().expect("length checked");
                if fl[..9].iter().any(|x| !x.is_finite()) || fl[9].is_nan() {
                    return Err(err(format!(
                        "level {n} meshlet {j}: a non-finite bound or error"
                    )));
                }
                if group != NO_GROUP && group as usize >= ng {
                    return Err(err(format!(
                        "level {n} meshlet {j}: group {group} does not exist ({ng} groups)"
                    )));
                }
                info.push(LodInfo {
                    bounds: Sphere {
                        center: [fl[0], fl[1], fl[2]],
                        radius: fl[3],
                    },
                    error: fl[4],
                    parent_bounds: Sphere {
                        center: [fl[5], fl[6], fl[7]],
                        radius: fl[8],
                    },
                    parent_error: fl[9],
                    group,
                });
            }
            let vertices = (0..v).map(|_| r.u32().expect("length checked")).collect();
            let triangles = r.bytes(t as usize).expect("length checked").to_vec();
            levels[n] = Some(Level {
                meshlets: Meshlets {
                    meshlets,
                    vertices,
                    triangles,
                },
                info,
            });
        }
        if r.remaining() != 0 {
            return Err(err(format!("{} trailing bytes", r.remaining())));
        }
        let levels: Vec<Level> = levels
            .into_iter()
            .map(|l| l.expect("every level read"))
            .collect();
        for (gi, g) in groups.iter().enumerate() {
            let next = levels
                .get(g.level as usize + 1)
                .map_or(0, |l| l.meshlets.len());
            if g.first as u64 + g.count as u64 > next as u64 {
                return Err(err(format!(
                    "group {gi}: outputs {}..{} of level {} do not exist",
                    g.first,
                    g.first as u64 + g.count as u64,
                    g.level as u64 + 1
                )));
            }
        }
        for (n, l) in levels.iter().enumerate() {
            for (j, i) in l.info.iter().enumerate() {
                if i.group != NO_GROUP && groups[i.group as usize].level as usize != n {
                    return Err(err(format!(
                        "level {n} meshlet {j}: its group {} belongs to level {}",
                        i.group, groups[i.group as usize].level
                    )));
                }
            }
        }
        Ok(Self {
            source_vertices,
            source_triangles,
            fingerprint,
            lod: Lod {
                limits,
                strategy,
                levels,
                groups,
            },
        })
    }

    /// The checks of `meshletlab lod-check` that need no view: the file was built from `mesh`;
    /// level 0 passes the validator against it; every level's meshlets respect the limits; errors
    /// and bounds are monotonic. (`lod-check` then tests cuts over random views.)
    pub fn check(&self, mesh: &crate::mesh::Mesh, path: &Path) -> Result<(), LodFileError> {
        let err = |m: String| LodFileError {
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
        let lod = &self.lod;
        if lod.levels.is_empty() {
            return Err(err("no levels".into()));
        }
        crate::meshlet::validate(mesh, &lod.levels[0].meshlets, lod.limits)
            .map_err(|e| err(format!("level 0: {e}")))?;
        for (n, l) in lod.levels.iter().enumerate().skip(1) {
            let level_mesh = crate::mesh::Mesh {
                positions: mesh.positions.clone(),
                indices: checked_triangles(&l.meshlets, mesh.vertex_count())
                    .map_err(|e| err(format!("level {n}: {e}")))?,
            };
            crate::meshlet::validate(&level_mesh, &l.meshlets, lod.limits)
                .map_err(|e| err(format!("level {n}: {e}")))?;
        }
        super::select::check_monotonic(lod).map_err(err)?;
        Ok(())
    }

    /// Writes to a file.
    pub fn save(&self, path: &Path) -> Result<(), LodFileError> {
        crate::meshlet::io::write_file(path, &self.to_bytes())
    }

    /// Reads from a file.
    pub fn load(path: &Path) -> Result<Self, LodFileError> {
        Self::from_bytes(&crate::meshlet::io::read_file(path)?, path)
    }
}

/// Every meshlet's triangles as global indices, with every range and index checked first (a
/// corrupt file must give an error here, not a panic).
fn checked_triangles(ml: &Meshlets, vertex_count: usize) -> Result<Vec<u32>, String> {
    let mut out = Vec::new();
    for (i, m) in ml.meshlets.iter().enumerate() {
        let vs = m.vertex_offset as usize..m.vertex_offset as usize + m.vertex_count as usize;
        let ts =
            m.triangle_offset as usize..m.triangle_offset as usize + 3 * m.triangle_count as usize;
        let (Some(verts), Some(tris)) = (ml.vertices.get(vs), ml.triangles.get(ts)) else {
            return Err(format!("meshlet {i}: ranges past the end of its arrays"));
        };
        for &c in tris {
            let v = *verts
                .get(c as usize)
                .ok_or_else(|| format!("meshlet {i}: local index {c} >= {}", verts.len()))?;
            if v as usize >= vertex_count {
                return Err(format!("meshlet {i}: vertex {v} does not exist"));
            }
            out.push(v);
        }
    }
    Ok(out)
}

/// Per level, the vertices it uses that no coarser level uses (what streaming it in adds).
pub fn new_vertices(lod: &Lod) -> Vec<u32> {
    let mut seen = std::collections::HashSet::new();
    let mut out = vec![0; lod.levels.len()];
    for (n, l) in lod.levels.iter().enumerate().rev() {
        out[n] = l
            .meshlets
            .vertices
            .iter()
            .filter(|&&v| seen.insert(v))
            .count() as u32;
    }
    out
}
