//! Wavefront OBJ through `tobj`.
//!
//! tobj gets only what this reader uses: `vt` and `vn` lines are blanked and face corners cut to
//! their position index before parsing. Besides skipping work, that keeps malformed texture and
//! normal indices away from tobj, which multiplies them without overflow checks (a panic in debug
//! builds, a wrapped index in release; found by the fuzzer). Line numbers are preserved.
//!
//! tobj's errors name no line, so when it fails (or lets a NaN vertex through) a walk over the same
//! text that follows tobj's rules finds the line; every error is `line N: ...`.
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
    // Materials are irrelevant here; never touch the file system for .mtl files. Only a failure
    // pays for the walk that finds its line; "OBJ" is left for a disagreement the tests rule out.
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| located(&cleaned).unwrap_or_else(|| parse_err("OBJ", e.to_string())))?;
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
    // A NaN vertex is named by its line too (else `Mesh::validate` names tobj's renumbered vertex).
    if positions.iter().flatten().any(|c| !c.is_finite()) {
        if let Some(e) = located(&cleaned) {
            return Err(e);
        }
    }
    Ok((positions, indices))
}

/// The first error in OBJ text as tobj reads it, with its line: tobj's rejections, and a
/// non-finite coordinate on a vertex a triangle uses. `None` for text tobj reads into a finite mesh.
fn located(data: &[u8]) -> Option<MeshErrorKind> {
    locate(data).map(|(line, message)| parse_err(format!("line {line}"), message))
}

/// Lines numbered from 1, split as `BufRead::lines` splits them.
fn lines(data: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    data.split(|&c| c == b'\n').zip(1..).map(|(l, n)| (n, l))
}

/// [`located`] as (line, message), in two passes that follow tobj's rules (tobj 4.0, with the
/// options [`parse`] sets). Pass 1 finds the first error tobj raises while reading a line, and the
/// vertex and colour counts at each object's end: tobj checks an object's face indices only then,
/// against every vertex read so far. Pass 2 checks the faces of the objects ended before that line.
fn locate(data: &[u8]) -> Option<(usize, String)> {
    let mut ends: Vec<(usize, usize)> = Vec::new();
    let mut non_finite = std::collections::HashMap::new();
    let (mut vertices, mut colours, mut faces) = (0, 0, false);
    let mut stop = None;
    for (n, line) in lines(data) {
        let Ok(text) = std::str::from_utf8(line) else {
            stop = Some((n, "not UTF-8 text".to_string()));
            break;
        };
        let mut words = text.split_whitespace();
        let err = match words.next() {
            Some("v") => vertex(words).map(|(p, c)| {
                if let Some(x) = p.iter().find(|x| !x.is_finite()) {
                    non_finite.insert(vertices, (n, *x));
                }
                vertices += 1;
                colours += c;
            }),
            Some("f" | "l") => {
                faces = true;
                words.try_for_each(|w| corner(w, vertices).map(drop))
            }
            Some("o" | "g") if faces => {
                ends.push((vertices, colours));
                faces = false;
                Ok(())
            }
            Some("usemtl")
                if text
                    .split_once(' ')
                    .is_none_or(|(_, m)| m.trim().is_empty()) =>
            {
                Err("usemtl without a material name".to_string())
            }
            _ => Ok(()),
        };
        if let Err(m) = err {
            stop = Some((n, m));
            break;
        }
    }
    if stop.is_none() {
        ends.push((vertices, colours));
    }
    let (mut object, mut vertices, mut faces) = (0, 0, false);
    for (n, line) in lines(data) {
        // Lines past the last ended object are never checked by tobj (and may not be text).
        let Some(&(known, coloured)) = ends.get(object) else {
            break;
        };
        let mut words = std::str::from_utf8(line).ok()?.split_whitespace();
        match words.next() {
            Some("v") => vertices += 1,
            Some("o" | "g") if faces => {
                object += 1;
                faces = false;
            }
            Some("f" | "l") => {
                faces = true;
                let corners: Vec<(&str, usize)> = words
                    .map(|w| corner(w, vertices).map(|v| (w, v)))
                    .collect::<Result<_, _>>()
                    .ok()?;
                // One or two corners are a point or a line, which tobj skips; none is an error.
                if corners.is_empty() {
                    return Some((n, "face without vertices".into()));
                }
                if corners.len() < 3 {
                    continue;
                }
                for (w, v) in corners {
                    if w.starts_with('/') {
                        return Some((n, "face corner without a vertex index".into()));
                    }
                    if v >= known {
                        return Some((
                            n,
                            format!("face vertex {w} is out of range: there are {known} vertices"),
                        ));
                    }
                    if coloured > 0 && v * 3 + 2 >= coloured {
                        return Some((
                            n,
                            format!(
                                "face vertex {w} has no colour while other vertices have one \
                                 (give all vertices a colour or none)"
                            ),
                        ));
                    }
                    if let Some(&(at, x)) = non_finite.get(&v) {
                        return Some((
                            at,
                            format!("vertex {} has a non-finite coordinate ({x})", v + 1),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    stop
}

/// A `v` statement's position (divided by its weight, if any) and how many colour values tobj
/// keeps from it (it stops at the first that is not a number).
fn vertex(mut words: std::str::SplitWhitespace) -> Result<([f32; 3], usize), String> {
    let mut p = [0f32; 3];
    for c in &mut p {
        let w = words.next().ok_or("vertex with fewer than 3 coordinates")?;
        *c = w
            .parse()
            .map_err(|_| format!("vertex coordinate '{w}' is not a number"))?;
    }
    let rest: Vec<&str> = words.take(4).collect();
    match rest[..] {
        [] => Ok((p, 0)),
        [w] => match w.parse::<f32>() {
            Err(_) => Err(format!("vertex weight '{w}' is not a number")),
            Ok(0.0) => Err("vertex weight is 0".into()),
            Ok(w) => Ok((p.map(|c| c / w), 0)),
        },
        [_, _, _] => Ok((
            p,
            rest.iter().take_while(|c| c.parse::<f32>().is_ok()).count(),
        )),
        _ => Err(format!(
            "vertex with {} values: expected 3 coordinates, then a weight or 3 colour values",
            if rest.len() == 2 { "5" } else { "more than 6" }
        )),
    }
}

/// The 0-based vertex a face corner `v`, `v/vt`, `v/vt/vn` or `-k` names when `vertices` have
/// been read (`usize::MAX` without a vertex number; tobj's range check refuses it).
fn corner(word: &str, vertices: usize) -> Result<usize, String> {
    let mut v = usize::MAX;
    for (i, part) in word.split('/').enumerate().filter(|(_, p)| !p.is_empty()) {
        let x: isize = part
            .parse()
            .ok()
            .filter(|_| i < 3)
            .ok_or_else(|| format!("face corner '{word}' is not an index"))?;
        if i == 0 {
            v = if x < 0 {
                (vertices as isize + x) as usize
            } else {
                (x - 1) as usize
            };
        }
    }
    Ok(v)
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
                    // A corner without a vertex index stays one ("/"), which tobj refuses.
                    let v = w.split('/').next().unwrap_or(w);
                    out.extend_from_slice(if v.is_empty() { b"/" } else { v.as_bytes() });
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

    /// The error's location and message.
    fn error_at(src: &str) -> (String, String) {
        match parse(src.as_bytes()) {
            Err(MeshErrorKind::Parse { location, message }) => (location, message),
            other => panic!("{src:?}: {other:?}"),
        }
    }

    #[test]
    fn every_error_names_its_line() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let cases = [
            (format!("{tri}f 1 2 9\n"), "line 4", "out of range"),
            (format!("{tri}f 1 2 0\n"), "line 4", "out of range"),
            (format!("{tri}f -1 -2 -4\n"), "line 4", "out of range"),
            (
                format!("{tri}f 1 2 3\nf 1 /2 3\n"),
                "line 5",
                "without a vertex index",
            ),
            (format!("{tri}f 1 2 x\n"), "line 4", "'x' is not an index"),
            (
                "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n".to_string(),
                "line 2",
                "'zero'",
            ),
            ("# c\nv 0 0\n".to_string(), "line 2", "fewer than 3"),
            ("v 0 0 0 0\n".to_string(), "line 1", "weight is 0"),
            ("v 0 0 0 1 1\n".to_string(), "line 1", "5 values"),
            (format!("{tri}usemtl\nf 1 2 3\n"), "line 4", "material name"),
            (format!("{tri}f\n"), "line 4", "without vertices"),
            // Checked when the object ends: the face before, the vertex after, in one object.
            (
                "v 0 0 0\nv 1 0 0\no a\nf 1 2 3\no b\nv 0 1 0\n".to_string(),
                "line 4",
                "there are 2",
            ),
            (
                "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_string(),
                "line 4",
                "no colour",
            ),
            (
                "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_string(),
                "line 2",
                "vertex 2 has a non-finite coordinate (NaN)",
            ),
            (
                "v 0 0 0\nv 1 0 0 1e-39\nv 0 1 0\nf 1 2 3\n".to_string(),
                "line 2",
                "(inf)",
            ),
        ];
        for (src, line, msg) in cases {
            let (at, m) = error_at(&src);
            assert_eq!(at, line, "{src:?}: {m}");
            assert!(m.contains(msg), "{src:?}: {m}");
        }
        let (at, _) = parse(b"v 0 0 0\n\xff\xfe\nf 1 1 1\n")
            .map(drop)
            .map_err(|e| match e {
                MeshErrorKind::Parse { location, .. } => (location, ()),
                e => panic!("{e:?}"),
            })
            .unwrap_err();
        assert_eq!(at, "line 2");
        // Legal: a NaN vertex no face uses, a forward reference within the object, points and lines.
        parse(b"v nan 0 0\nv 0 0 0\nv 1 0 0\nf 2 3 4\nv 0 1 0\nf 2 99\nl 7\n").unwrap();
    }

    /// tobj fails (or gives a non-finite vertex) exactly where [`locate`] finds an error, over
    /// random texts of the statements tobj treats specially.
    #[test]
    fn the_walk_agrees_with_tobj() {
        use rand_core::{Rng, SeedableRng};
        let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(7);
        let num = ["0", "1", "-2.5", "1e-39", "nan", "inf", "x", "0.5"];
        let idx = [
            "1", "2", "3", "4", "9", "0", "-1", "-3", "-7", "/2", "1/2/3", "2//1", "1/x", "q",
            "1/2/3/4",
        ];
        let (mut mismatches, mut bad) = (Vec::new(), 0);
        for case in 0..20000 {
            let mut pick = |n: usize| (rng.next_u64() % n as u64) as usize;
            // Four sound vertices first, so that faces of 1..4 are often in range.
            let mut text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n".to_vec();
            for _ in 0..pick(6) + 1 {
                let kind = pick(10);
                let words = match kind {
                    0..=3 => {
                        let k = [3, 3, 3, 3, 3, 3, 4, 5, 6, 7, 2][pick(11)];
                        let good = pick(8) > 0;
                        let vals: Vec<&str> = (0..k)
                            .map(|_| {
                                if good {
                                    ["0", "1", "0.5"][pick(3)]
                                } else {
                                    num[pick(num.len())]
                                }
                            })
                            .collect();
                        format!("v {}", vals.join(" "))
                    }
                    4..=6 => {
                        let k = [3, 3, 4, 5, 0, 1, 2][pick(7)];
                        let c: Vec<&str> = (0..k)
                            .map(|_| {
                                let pool = if pick(3) > 0 { 4 } else { idx.len() };
                                idx[pick(pool)]
                            })
                            .collect();
                        format!("{} {}", ["f", "f", "l"][pick(3)], c.join(" "))
                    }
                    7 => ["o a", "g", "o"][pick(3)].to_string(),
                    8 => ["usemtl m", "usemtl", "usemtl  ", "# f 1 2 9", ""][pick(5)].to_string(),
                    _ => ["vt 0 0", "vn 0 0 1", "mtllib x.mtl", "\u{ff}"][pick(4)].to_string(),
                };
                text.extend_from_slice(words.as_bytes());
                if kind == 9 && pick(8) == 0 {
                    text.push(0xff);
                }
                text.push(b'\n');
            }
            let cleaned = positions_and_faces(&text);
            let opts = tobj::LoadOptions {
                triangulate: true,
                single_index: false,
                ignore_points: true,
                ignore_lines: true,
            };
            let tobj_bad = match tobj::load_obj_buf(&mut &cleaned[..], &opts, |_| {
                Err(tobj::LoadError::OpenFileFailed)
            }) {
                Err(_) => true,
                Ok((models, _)) => models
                    .iter()
                    .any(|m| m.mesh.positions.iter().any(|c| !c.is_finite())),
            };
            bad += tobj_bad as usize;
            if tobj_bad != locate(&cleaned).is_some() {
                mismatches.push((
                    case,
                    String::from_utf8_lossy(&text).into_owned(),
                    locate(&cleaned),
                ));
            }
        }
        assert!(
            mismatches.is_empty(),
            "{} mismatches, first: {:?}",
            mismatches.len(),
            mismatches[0]
        );
        // Both outcomes are common, so the agreement means something.
        assert!((5000..15000).contains(&bad), "{bad} of 20000 texts are bad");
    }
}
