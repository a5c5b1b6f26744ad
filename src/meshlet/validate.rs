//! The strict validator every strategy's output goes through in tests.

use super::{Limits, Meshlets};
use crate::mesh::Mesh;
use thiserror::Error;

/// The first rule a meshlet collection breaks.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum ValidationError {
    /// A meshlet's range runs past the end of `vertices` or `triangles`.
    #[error("meshlet {meshlet}: {what} range {start}..{end} exceeds the array length {len}")]
    OffsetOutOfRange {
        /// Meshlet number.
        meshlet: usize,
        /// "vertex" or "triangle".
        what: &'static str,
        /// Range start.
        start: usize,
        /// Range end.
        end: usize,
        /// Array length.
        len: usize,
    },
    /// A meshlet has no triangles.
    #[error("meshlet {0} is empty")]
    Empty(usize),
    /// A meshlet exceeds the vertex or triangle limit.
    #[error("meshlet {meshlet} has {vertices} vertices / {triangles} triangles, limits {limits}")]
    OverLimit {
        /// Meshlet number.
        meshlet: usize,
        /// Its vertex count.
        vertices: u32,
        /// Its triangle count.
        triangles: u32,
        /// The limits.
        limits: Limits,
    },
    /// A local corner index is not below the meshlet's vertex count.
    #[error("meshlet {meshlet} triangle {triangle}: local index {index} >= vertex count {count}")]
    LocalIndexOutOfRange {
        /// Meshlet number.
        meshlet: usize,
        /// Triangle within the meshlet.
        triangle: usize,
        /// The local index.
        index: u8,
        /// The meshlet's vertex count.
        count: u32,
    },
    /// A global vertex index does not exist in the mesh.
    #[error("meshlet {meshlet}: global vertex {vertex} out of range")]
    GlobalIndexOutOfRange {
        /// Meshlet number.
        meshlet: usize,
        /// The bad index.
        vertex: u32,
    },
    /// The same global vertex appears twice in one meshlet.
    #[error("meshlet {meshlet}: global vertex {vertex} listed twice")]
    DuplicateVertex {
        /// Meshlet number.
        meshlet: usize,
        /// The repeated vertex.
        vertex: u32,
    },
    /// A meshlet vertex no triangle of that meshlet uses.
    #[error("meshlet {meshlet}: local vertex {local} is unused")]
    UnusedVertex {
        /// Meshlet number.
        meshlet: usize,
        /// The unused local index.
        local: usize,
    },
    /// The meshlets' triangles are not the input's triangles exactly once each.
    #[error("triangle multiset differs from the mesh: {0}")]
    TrianglesDiffer(String),
}

/// Rotates a triangle so its smallest index comes first, keeping the winding (a triangle up to
/// rotation, as the validator and the codecs' round trips compare them).
#[inline]
pub fn canonical(t: [u32; 3]) -> [u32; 3] {
    let [a, b, c] = t;
    if a <= b && a <= c {
        [a, b, c]
    } else if b <= a && b <= c {
        [b, c, a]
    } else {
        [c, a, b]
    }
}

/// Checks every rule: ranges in bounds, limits, local indices below the vertex count, global indices
/// in range and unique per meshlet, no unused meshlet vertex, and every input triangle present
/// exactly once (as a multiset, winding kept up to rotation).
pub fn validate(mesh: &Mesh, ml: &Meshlets, limits: Limits) -> Result<(), ValidationError> {
    let mut seen = vec![usize::MAX; mesh.vertex_count()];
    let mut out_tris: Vec<[u32; 3]> = Vec::with_capacity(mesh.triangle_count());
    for (i, m) in ml.meshlets.iter().enumerate() {
        let (vs, ve) = (
            m.vertex_offset as usize,
            m.vertex_offset as usize + m.vertex_count as usize,
        );
        let (ts, te) = (
            m.triangle_offset as usize,
            m.triangle_offset as usize + 3 * m.triangle_count as usize,
        );
        if ve > ml.vertices.len() {
            return Err(ValidationError::OffsetOutOfRange {
                meshlet: i,
                what: "vertex",
                start: vs,
                end: ve,
                len: ml.vertices.len(),
            });
        }
        if te > ml.triangles.len() {
            return Err(ValidationError::OffsetOutOfRange {
                meshlet: i,
                what: "triangle",
                start: ts,
                end: te,
                len: ml.triangles.len(),
            });
        }
        if m.triangle_count == 0 {
            return Err(ValidationError::Empty(i));
        }
        if m.vertex_count > limits.max_vertices || m.triangle_count > limits.max_triangles {
            return Err(ValidationError::OverLimit {
                meshlet: i,
                vertices: m.vertex_count,
                triangles: m.triangle_count,
                limits,
            });
        }
        let verts = &ml.vertices[vs..ve];
        for &v in verts {
            if v as usize >= mesh.vertex_count() {
                return Err(ValidationError::GlobalIndexOutOfRange {
                    meshlet: i,
                    vertex: v,
                });
            }
            if seen[v as usize] == i {
                return Err(ValidationError::DuplicateVertex {
                    meshlet: i,
                    vertex: v,
                });
            }
            seen[v as usize] = i;
        }
        let mut used = [false; 256];
        for (k, t) in ml.triangles[ts..te].chunks_exact(3).enumerate() {
            for &c in t {
                if c as u32 >= m.vertex_count {
                    return Err(ValidationError::LocalIndexOutOfRange {
                        meshlet: i,
                        triangle: k,
                        index: c,
                        count: m.vertex_count,
                    });
                }
                used[c as usize] = true;
            }
            out_tris.push(canonical([
                verts[t[0] as usize],
                verts[t[1] as usize],
                verts[t[2] as usize],
            ]));
        }
        if let Some(local) = used[..m.vertex_count as usize].iter().position(|&u| !u) {
            return Err(ValidationError::UnusedVertex { meshlet: i, local });
        }
    }
    let mut in_tris: Vec<[u32; 3]> = (0..mesh.triangle_count())
        .map(|t| canonical(mesh.triangle(t)))
        .collect();
    if in_tris.len() != out_tris.len() {
        return Err(ValidationError::TrianglesDiffer(format!(
            "mesh has {} triangles, meshlets have {}",
            in_tris.len(),
            out_tris.len()
        )));
    }
    in_tris.sort_unstable();
    out_tris.sort_unstable();
    if let Some(k) = (0..in_tris.len()).find(|&k| in_tris[k] != out_tris[k]) {
        return Err(ValidationError::TrianglesDiffer(format!(
            "first difference in sorted order: mesh has {:?}, meshlets have {:?}",
            in_tris[k], out_tris[k]
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::meshlet::MeshletBuilder;

    fn fixture() -> (Mesh, Meshlets) {
        let mesh = crate::mesh::generate::terrain(6, 1);
        let mut b = MeshletBuilder::new(mesh.vertex_count(), Limits::new(8, 6).unwrap());
        for t in 0..mesh.triangle_count() {
            b.push(mesh.triangle(t));
        }
        (mesh, b.finish())
    }

    const L: Limits = Limits {
        max_vertices: 8,
        max_triangles: 6,
    };

    #[test]
    fn builder_output_is_valid() {
        let (mesh, ml) = fixture();
        assert_eq!(validate(&mesh, &ml, L), Ok(()));
        assert!(ml.len() > 1);
    }

    #[test]
    fn every_rule_is_enforced() {
        let (mesh, ml) = fixture();
        let check = |f: &dyn Fn(&mut Meshlets), want: &dyn Fn(&ValidationError) -> bool| {
            let mut bad = ml.clone();
            f(&mut bad);
            let e = validate(&mesh, &bad, L).unwrap_err();
            assert!(want(&e), "unexpected error {e}");
        };
        check(&|m| m.meshlets[0].vertex_offset = 10_000, &|e| {
            matches!(e, ValidationError::OffsetOutOfRange { what: "vertex", .. })
        });
        check(&|m| m.meshlets[0].triangle_offset = 10_000, &|e| {
            matches!(
                e,
                ValidationError::OffsetOutOfRange {
                    what: "triangle",
                    ..
                }
            )
        });
        check(&|m| m.meshlets[0].triangle_count = 0, &|e| {
            matches!(e, ValidationError::Empty(0))
        });
        check(&|m| m.meshlets[0].triangle_count = 7, &|e| {
            matches!(e, ValidationError::OverLimit { .. })
        });
        check(&|m| m.triangles[1] = 200, &|e| {
            matches!(e, ValidationError::LocalIndexOutOfRange { .. })
        });
        check(&|m| m.vertices[0] = 1_000_000, &|e| {
            matches!(e, ValidationError::GlobalIndexOutOfRange { .. })
        });
        check(&|m| m.vertices[1] = m.vertices[0], &|e| {
            matches!(e, ValidationError::DuplicateVertex { .. })
        });
        // Flip one triangle's winding: same vertex set, different orientation.
        check(&|m| m.triangles.swap(0, 1), &|e| {
            matches!(e, ValidationError::TrianglesDiffer(_))
        });
        // Drop the last meshlet: triangles missing.
        check(
            &|m| {
                m.meshlets.pop();
            },
            &|e| matches!(e, ValidationError::TrianglesDiffer(_)),
        );
        // Duplicate a meshlet: triangles twice.
        check(
            &|m| {
                let x = m.meshlets[0];
                m.meshlets.push(x);
            },
            &|e| matches!(e, ValidationError::TrianglesDiffer(_)),
        );
        // An extra vertex that no triangle uses, under limits with room for it: only the
        // unused-vertex rule can fire.
        let mut bad = ml.clone();
        let last = *bad.meshlets.last().unwrap();
        let spare = (0..mesh.vertex_count() as u32)
            .find(|v| !bad.meshlet_vertices(bad.len() - 1).contains(v))
            .unwrap();
        bad.vertices
            .truncate((last.vertex_offset + last.vertex_count) as usize);
        bad.vertices.push(spare);
        bad.meshlets.last_mut().unwrap().vertex_count += 1;
        let roomy = Limits::new(L.max_vertices + 1, L.max_triangles).unwrap();
        assert_eq!(
            validate(&mesh, &bad, roomy),
            Err(ValidationError::UnusedVertex {
                meshlet: bad.len() - 1,
                local: last.vertex_count as usize
            })
        );
    }

    #[test]
    fn rotation_of_a_triangle_is_accepted() {
        let (mesh, mut ml) = fixture();
        let t = &mut ml.triangles[0..3];
        t.rotate_left(1);
        assert_eq!(validate(&mesh, &ml, L), Ok(()));
    }
}
