//! Wavefront OBJ through `tobj`.
//!
//! tobj gets only what this reader uses: `vt` and `vn` lines are blanked and face corners cut to
//! their position index before parsing. Besides skipping work, that keeps malformed texture and
//! normal indices away from tobj, which multiplies them without overflow checks (a panic in debug
//! builds, a wrapped index in release; found by the fuzzer). Line numbers are preserved.
//!
//! Vertex-count semantics: tobj re-indexes every object/group to the vertices its faces reference,
//! numbered in order of first use. So the loaded mesh holds, object after object, only referenced
//! vertices; unreferenced `v` lines are dropped, and a vertex shared by two objects appears once per
//! object (bit-identical positions). Triangles keep their file order and winding. Polygons are fan-triangulated; points and lines are ignored.

use super::error::{parse_err, MeshErrorKind};

/// Parses OBJ text into positions and triangle indices.
pub fn parse(data: &[u8]) -> Result<(Vec<[f32; 3]>, Vec<u32>), MeshErrorKind> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let cleaned = positions_and_faces(data);
    let mut reader = std::io::BufReader::new(&cleaned[..]);
    // Materials are irrelevant here; never touch the file system for .mtl files.
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| parse_err("OBJ", e.to_string()))?;
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    for m in &models {
        let base = positions.len() as u64;
        if m.mesh.positions.len() % 3 != 0 {
            return Err(parse_err(
                format!("object '{}'", m.name),
                "position count is not a multiple of 3",
            ));
        }
        positions.extend(m.mesh.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        if positions.len() as u64 > u32::MAX as u64 {
            return Err(MeshErrorKind::TooLarge("more than 2^32 vertices".into()));
        }
        indices.extend(m.mesh.indices.iter().map(|&i| (base + i as u64) as u32));
    }
    Ok((positions, indices))
}

/// `data` with `vt`/`vn` lines blanked and every face corner `v/vt/vn` cut to `v`, line by line as
/// tobj reads it (its first token split by Unicode whitespace, like tobj's `split_whitespace`; no
/// line continuation). A line that is not UTF-8 passes unchanged: tobj rejects it.
fn positions_and_faces(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len());
    for line in data.split_inclusive(|&c| c == b'\n') {
        let Ok(text) = std::str::from_utf8(line) else {
            out.extend_from_slice(line);
            continue;
        };
        let mut words = text.split_whitespace();
        match words.next() {
            Some("vt") | Some("vn") => {}
            Some("f") => {
                out.push(b'f');
                for w in words {
                    out.push(b' ');
                    out.extend_from_slice(w.split('/').next().unwrap_or(w).as_bytes());
                }
            }
            _ => {
                out.extend_from_slice(line.strip_suffix(b"\n").unwrap_or(line));
            }
        }
        // Keep line numbers.
        if line.ends_with(b"\n") {
            out.push(b'\n');
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quads_and_objects() {
        let src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\no a\nf 1 2 3 4\no b\nf -4 -3 -2\n";
        let (p, i) = parse(src.as_bytes()).unwrap();
        // Object a: 4 vertices, 2 triangles; object b references 3 vertices again; v 9 9 9 is dropped.
        assert_eq!(p.len(), 7);
        assert_eq!(i.len(), 9);
        assert!(!p.contains(&[9.0, 9.0, 9.0]));
    }

    #[test]
    fn texture_and_normal_indices_are_ignored_even_when_absurd() {
        // Vertical tab and no-break space separate tokens for tobj too.
        let src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvn\u{b}0 0 1\n\
                   f\u{a0}1/1/1 2/9223372036854775807/1 3//-9223372036854775808\r\n";
        let (p, i) = parse(src.as_bytes()).unwrap();
        assert_eq!((p.len(), i), (3, vec![0, 1, 2]));
    }
}
