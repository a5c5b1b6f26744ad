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

/// `data` with `vt`/`vn` lines blanked and every face corner `v/vt/vn` cut to `v` (logical lines:
/// a trailing backslash continues a line, as tobj reads it).
fn positions_and_faces(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len());
    let mut logical: Vec<u8> = Vec::new();
    let mut newlines = 0;
    let flush = |logical: &mut Vec<u8>, newlines: &mut usize, out: &mut Vec<u8>| {
        let mut words = logical
            .split(|c| c.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"vt") | Some(b"vn") => {}
            Some(b"f") => {
                out.push(b'f');
                for w in words {
                    out.push(b' ');
                    out.extend_from_slice(w.split(|&c| c == b'/').next().unwrap_or(w));
                }
            }
            _ => out.extend_from_slice(logical),
        }
        // Keep line numbers: one newline per physical line consumed.
        out.extend(std::iter::repeat_n(b'\n', *newlines));
        logical.clear();
        *newlines = 0;
    };
    for line in data.split_inclusive(|&c| c == b'\n') {
        let body = line.strip_suffix(b"\n").unwrap_or(line);
        let body = body.strip_suffix(b"\r").unwrap_or(body);
        newlines += line.ends_with(b"\n") as usize;
        match body.strip_suffix(b"\\") {
            Some(cont) => {
                logical.extend_from_slice(cont);
                logical.push(b' ');
            }
            None => {
                logical.extend_from_slice(body);
                flush(&mut logical, &mut newlines, &mut out);
            }
        }
    }
    if !logical.is_empty() || newlines > 0 {
        flush(&mut logical, &mut newlines, &mut out);
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
        let src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvn 0 0 1\n\
                   f 1/1/1 2/9223372036854775807/1 \\\n 3//-9223372036854775808\n";
        let (p, i) = parse(src.as_bytes()).unwrap();
        assert_eq!((p.len(), i), (3, vec![0, 1, 2]));
    }
}
