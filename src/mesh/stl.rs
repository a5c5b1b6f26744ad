//! STL reader (ASCII and binary) and a binary writer.
//!
//! Hand-written over the byte slice rather than taken from a crate: the format is small, and this
//! way a binary facet count is checked against the file size before anything is allocated and
//! every error is a typed [`MeshErrorKind`] naming its facet or line.
//!
//! **ASCII or binary.** A file is binary when it holds the 84-byte prefix (80-byte header, u32
//! little-endian facet count) and its size is exactly `84 + 50 × count`, even when its header
//! begins with `solid`, as many exporters write it. Otherwise a file that begins with `solid` (any
//! case, after optional whitespace) and has no NUL byte in its first 84 bytes is read as ASCII:
//! `solid NAME`, then per facet `facet normal nx ny nz`, `outer loop`, three `vertex x y z`,
//! `endloop`, `endfacet`, and `endsolid NAME` (keywords in any case; several solids in a row are
//! read one after the other). Anything else is a binary file whose size disagrees with its count:
//! [`MeshErrorKind::Truncated`] when it is shorter, [`MeshErrorKind::CountMismatch`] when longer.
//!
//! **Geometry.** Facet normals and the binary attribute word are ignored (ASCII normals must still
//! be numbers, NaN allowed); triangles keep the file's winding, counter-clockwise front faces.
//! Corners are welded by exact position: bitwise-equal f32 triples, with -0.0 read as 0.0 so that
//! the two weld (the vertex holds 0.0). Vertices are numbered in order of first appearance, so the
//! mesh is a pure function of the file. NaN or infinite corner coordinates are
//! [`MeshErrorKind::NonFinite`], numbered `3 × facet + corner` in file order; a file without
//! facets is [`MeshErrorKind::Empty`].
//!
//! **Allocation** is bounded by the file: a binary count is checked against the size first, and
//! ASCII output grows only with the facets actually read (each at least 80 bytes of text).

use super::error::{parse_err, MeshErrorKind};
use super::tokens::Tokens;
use std::collections::HashMap;
use std::io::Write;

/// Bytes before the first binary facet: the 80-byte header and the u32 facet count.
const PREFIX: usize = 84;
/// Bytes per binary facet: normal, three corners (12 f32s) and a u16 attribute word.
const FACET: usize = 50;

/// Parses a whole STL file (ASCII or binary, told apart by size; see the module docs) into welded
/// positions and a triangle index buffer (not yet validated as a mesh).
pub fn parse(data: &[u8]) -> Result<(Vec<[f32; 3]>, Vec<u32>), MeshErrorKind> {
    let count = data
        .get(80..PREFIX)
        .map(|b| u32::from_le_bytes(b.try_into().expect("four bytes")));
    let want = count.map(|n| PREFIX as u64 + FACET as u64 * n as u64);
    if let (Some(n), Some(want)) = (count, want) {
        if want == data.len() as u64 {
            return read_binary(data, n as usize);
        }
    }
    if looks_ascii(data) {
        return read_ascii(data);
    }
    let len = data.len();
    Err(match (count, want) {
        (Some(n), Some(want)) if want > len as u64 => MeshErrorKind::Truncated(format!(
            "binary STL header announces {n} facets ({want} bytes), but the file has {len} bytes"
        )),
        (Some(n), Some(want)) => MeshErrorKind::CountMismatch(format!(
            "binary STL header announces {n} facets ({want} bytes), but the file has {len} bytes \
             ({} more)",
            len as u64 - want
        )),
        _ => MeshErrorKind::Truncated(format!(
            "{len} bytes, fewer than a binary STL's 84-byte header (and not an ASCII STL, which \
             starts with 'solid')"
        )),
    })
}

/// Whether a file whose size does not fit the binary layout is ASCII: it begins with `solid` and
/// its first 84 bytes hold no NUL (a binary count below 2^24 has one at byte 83).
fn looks_ascii(data: &[u8]) -> bool {
    let start = data
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(data.len());
    data[start..]
        .get(..5)
        .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"))
        && !data[..data.len().min(PREFIX)].contains(&0)
}

/// Welds corners by exact position, numbering vertices in order of first appearance.
#[derive(Default)]
struct Welder {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    ids: HashMap<[u32; 3], u32>,
}

impl Welder {
    /// Adds one (finite) corner.
    fn corner(&mut self, p: [f32; 3]) -> Result<(), MeshErrorKind> {
        // -0.0 == 0.0, so both key (and store) as 0.0's bits.
        let key = p.map(|c| if c == 0.0 { 0 } else { c.to_bits() });
        let next = self.positions.len();
        let id = match self.ids.get(&key) {
            Some(&id) => id,
            None => {
                let id = u32::try_from(next).map_err(|_| {
                    MeshErrorKind::TooLarge("more than 2^32 distinct vertices".into())
                })?;
                self.ids.insert(key, id);
                self.positions.push(key.map(f32::from_bits));
                id
            }
        };
        self.indices.push(id);
        Ok(())
    }

    fn finish(self) -> (Vec<[f32; 3]>, Vec<u32>) {
        (self.positions, self.indices)
    }
}

/// Reads `count` facets after the prefix; the caller has checked that the size is exactly
/// `84 + 50 × count`, so the reservation is bounded by the file.
fn read_binary(data: &[u8], count: usize) -> Result<(Vec<[f32; 3]>, Vec<u32>), MeshErrorKind> {
    if count == 0 {
        return Err(MeshErrorKind::Empty(
            "binary STL header announces 0 facets".into(),
        ));
    }
    let mut w = Welder::default();
    w.indices.reserve_exact(3 * count);
    for (f, rec) in data[PREFIX..].chunks_exact(FACET).enumerate() {
        for k in 0..3 {
            let at = 12 + 12 * k;
            let p: [f32; 3] = std::array::from_fn(|c| {
                let b = &rec[at + 4 * c..at + 4 * c + 4];
                f32::from_le_bytes(b.try_into().expect("four bytes"))
            });
            if let Some(c) = p.iter().find(|c| !c.is_finite()) {
                return Err(MeshErrorKind::NonFinite {
                    vertex: 3 * f + k,
                    value: c.to_string(),
                });
            }
            w.corner(p)?;
        }
    }
    Ok(w.finish())
}

/// A token as it may appear in a one-line message: escaped, at most 32 bytes.
fn show(tok: &[u8]) -> String {
    let cut = &tok[..tok.len().min(32)];
    let more = if tok.len() > 32 { "..." } else { "" };
    format!("'{}{more}'", cut.escape_ascii())
}

fn keyword(tok: &[u8], word: &str) -> bool {
    tok.eq_ignore_ascii_case(word.as_bytes())
}

/// Reads an ASCII file (see the module docs for the grammar).
fn read_ascii(data: &[u8]) -> Result<(Vec<[f32; 3]>, Vec<u32>), MeshErrorKind> {
    let mut t = Tokens::new(data, 1);
    let mut w = Welder::default();
    let mut facet = 0usize;
    while let Some((tok, line)) = t.next() {
        let solid = tok.len() >= 5 && tok[..5].eq_ignore_ascii_case(b"solid");
        if !solid {
            return Err(parse_err(
                format!("line {line}"),
                format!(
                    "expected 'solid' or the end of the file, found {}",
                    show(tok)
                ),
            ));
        }
        t.skip_line();
        loop {
            let Some((tok, line)) = t.next() else {
                return Err(MeshErrorKind::Truncated(format!(
                    "file ends before 'endsolid' (after {facet} facets)"
                )));
            };
            if tok.len() >= 8 && tok[..8].eq_ignore_ascii_case(b"endsolid") {
                t.skip_line();
                break;
            }
            if !keyword(tok, "facet") {
                return Err(parse_err(
                    format!("line {line}"),
                    format!("expected 'facet' or 'endsolid', found {}", show(tok)),
                ));
            }
            read_facet(&mut t, &mut w, facet)?;
            facet += 1;
        }
    }
    if facet == 0 {
        return Err(MeshErrorKind::Empty("ASCII STL has no facets".into()));
    }
    Ok(w.finish())
}

/// Reads one facet after its `facet` keyword.
fn read_facet(t: &mut Tokens, w: &mut Welder, facet: usize) -> Result<(), MeshErrorKind> {
    const THREE: &str = " (a facet has three vertices)";
    expect(t, facet, "normal", "")?;
    for _ in 0..3 {
        number(t, facet)?;
    }
    expect(t, facet, "outer", "")?;
    expect(t, facet, "loop", "")?;
    for k in 0..3 {
        expect(t, facet, "vertex", THREE)?;
        let mut p = [0f32; 3];
        for c in &mut p {
            let (v, tok) = number(t, facet)?;
            if !v.is_finite() {
                return Err(MeshErrorKind::NonFinite {
                    vertex: 3 * facet + k,
                    value: String::from_utf8_lossy(tok).into_owned(),
                });
            }
            *c = v;
        }
        w.corner(p)?;
    }
    expect(t, facet, "endloop", THREE)?;
    expect(t, facet, "endfacet", "")
}

/// The next token of facet `facet`; the end of the file there is truncation.
fn token<'a>(t: &mut Tokens<'a>, facet: usize) -> Result<(&'a [u8], usize), MeshErrorKind> {
    t.next().ok_or_else(|| {
        MeshErrorKind::Truncated(format!("file ends inside facet {facet} (line {})", t.line))
    })
}

/// The keyword `word` (any case), or a parse error ending in `hint`.
fn expect(t: &mut Tokens, facet: usize, word: &str, hint: &str) -> Result<(), MeshErrorKind> {
    let (tok, line) = token(t, facet)?;
    if keyword(tok, word) {
        return Ok(());
    }
    Err(parse_err(
        format!("line {line} (facet {facet})"),
        format!("expected '{word}', found {}{hint}", show(tok)),
    ))
}

/// A number (NaN and infinities included) and its text.
fn number<'a>(t: &mut Tokens<'a>, facet: usize) -> Result<(f32, &'a [u8]), MeshErrorKind> {
    let (tok, line) = token(t, facet)?;
    std::str::from_utf8(tok)
        .ok()
        .and_then(|s| s.parse::<f32>().ok())
        .map(|v| (v, tok))
        .ok_or_else(|| {
            parse_err(
                format!("line {line} (facet {facet})"),
                format!("{} is not a number", show(tok)),
            )
        })
}

/// Writes a binary STL: a header naming meshletlab (not starting with `solid`), then per triangle
/// its unit normal (zero for a degenerate one), corners and a zero attribute word. Vertex sharing
/// is lost, as in every STL; [`parse`] welds it back (exactly equal positions only).
pub fn write_binary(positions: &[[f32; 3]], indices: &[u32], w: impl Write) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::with_capacity(1 << 16, w);
    let count = u32::try_from(indices.len() / 3).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "more than 2^32 triangles do not fit a binary STL",
        )
    })?;
    let mut header = [0u8; 80];
    let text = b"binary STL written by meshletlab";
    header[..text.len()].copy_from_slice(text);
    w.write_all(&header)?;
    w.write_all(&count.to_le_bytes())?;
    for t in indices.chunks_exact(3) {
        let p: [glam::Vec3; 3] =
            std::array::from_fn(|k| glam::Vec3::from_array(positions[t[k] as usize]));
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        for v in std::iter::once(n).chain(p) {
            for c in v.to_array() {
                w.write_all(&c.to_le_bytes())?;
            }
        }
        w.write_all(&[0, 0])?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fmt::Write as _;

    /// A unit square as two triangles (four welded vertices), one corner at -0.0 in the second.
    const SQUARE: [[[f32; 3]; 3]; 2] = [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
        [[-0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, -0.0]],
    ];

    fn ascii(facets: &[[[f32; 3]; 3]]) -> String {
        let mut s = String::from("solid square  with a name\n");
        for f in facets {
            s += "  facet normal 0 0 1\n    outer loop\n";
            for p in f {
                writeln!(s, "      vertex {:e} {:e} {:e}", p[0], p[1], p[2]).unwrap();
            }
            s += "    endloop\n  endfacet\n";
        }
        s + "endsolid square\n"
    }

    fn binary(header: &[u8], facets: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut b = vec![0u8; 80];
        b[..header.len()].copy_from_slice(header);
        b.extend_from_slice(&(facets.len() as u32).to_le_bytes());
        for f in facets {
            b.extend_from_slice(&[0u8; 12]);
            for c in f.iter().flatten() {
                b.extend_from_slice(&c.to_le_bytes());
            }
            b.extend_from_slice(&[0xab, 0xcd]);
        }
        b
    }

    #[test]
    fn ascii_and_binary_give_the_same_welded_mesh() {
        let want = (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![0, 1, 2, 0, 2, 3],
        );
        let a = parse(ascii(&SQUARE).as_bytes()).unwrap();
        let b = parse(&binary(b"", &SQUARE)).unwrap();
        assert_eq!(a, want);
        assert_eq!(b, want);
        // -0.0 welded with 0.0, and stored as 0.0.
        assert!(a
            .0
            .iter()
            .flatten()
            .all(|c| c.to_bits() != (-0.0f32).to_bits()));
    }

    #[test]
    fn binary_whose_header_begins_with_solid() {
        let b = binary(b"solid exported by a CAD tool", &SQUARE);
        assert_eq!(parse(&b).unwrap().1, vec![0, 1, 2, 0, 2, 3]);
        // Cut short or lengthened, it is a binary file with a wrong size, not an ASCII one.
        let e = parse(&b[..b.len() - 1]).unwrap_err();
        assert!(matches!(e, MeshErrorKind::Truncated(_)), "{e}");
        let mut long = b.clone();
        long.push(0);
        let e = parse(&long).unwrap_err();
        assert!(matches!(e, MeshErrorKind::CountMismatch(_)), "{e}");
    }

    #[test]
    fn welding_is_exact_and_in_order_of_first_appearance() {
        let nudged = f32::from_bits(1.0f32.to_bits() + 1);
        let facets = [
            [[5.0, 5.0, 5.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[1.0, 0.0, 0.0], [nudged, 0.0, 0.0], [5.0, 5.0, 5.0]],
        ];
        let (p, i) = parse(&binary(b"", &facets)).unwrap();
        assert_eq!(p.len(), 4, "one ulp apart is another vertex");
        assert_eq!(p[0], [5.0, 5.0, 5.0]);
        assert_eq!(i, vec![0, 1, 2, 1, 3, 0]);
    }

    #[test]
    fn ascii_variants() {
        // Upper case, CRLF, tabs, two solids, a NaN normal, a name glued to 'solid'.
        let s =
            "SOLID\r\nFACET NORMAL nan 0 0\r\n\tOUTER LOOP\r\n\tVERTEX 0 0 0\r\n\tVERTEX 1 0 0\r\n\
                 \tVERTEX 1 1 0\r\n\tENDLOOP\r\nENDFACET\r\nENDSOLID\r\n\
                 solidtwo\nfacet normal 0 0 1 outer loop vertex 1 1 0 vertex 0 1 0 vertex 0 0 0 \
                 endloop endfacet\nendsolidtwo";
        let (p, i) = parse(s.as_bytes()).unwrap();
        assert_eq!(p.len(), 4);
        assert_eq!(i, vec![0, 1, 2, 2, 3, 0]);
    }

    #[test]
    fn bad_input_gets_typed_errors() {
        let good = ascii(&SQUARE);
        let kind = |s: &str| parse(s.as_bytes()).unwrap_err();
        let e = kind(&good.replacen("vertex 1e0 0e0 0e0", "vertex 1e0 nan 0e0", 1));
        assert!(
            matches!(e, MeshErrorKind::NonFinite { vertex: 1, .. }),
            "{e}"
        );
        let e = kind(&good.replacen("1e0 1e0 0e0", "1e0 1e39 0e0", 2));
        assert!(
            matches!(e, MeshErrorKind::NonFinite { vertex: 2, .. }),
            "{e}"
        );
        let e = kind(&good.replacen("vertex 1e0 0e0", "vertex 1e0 zero", 1));
        assert!(e.to_string().contains("line 5 (facet 0)"), "{e}");
        let e = kind(&good.replacen("outer loop", "outer", 1));
        assert!(matches!(e, MeshErrorKind::Parse { .. }), "{e}");
        let e = kind(&good.replacen("endloop", "vertex 0 0 0\nendloop", 1));
        assert!(e.to_string().contains("three vertices"), "{e}");
        let e = kind(&good[..good.len() - 45]);
        assert!(matches!(e, MeshErrorKind::Truncated(_)), "{e}");
        let e = kind(&good.replace("endsolid square\n", ""));
        assert!(matches!(e, MeshErrorKind::Truncated(_)), "{e}");
        let e = kind(&format!("{good}garbage"));
        assert!(matches!(e, MeshErrorKind::Parse { .. }), "{e}");
        let e = kind("solid nothing\nendsolid nothing\n");
        assert!(matches!(e, MeshErrorKind::Empty(_)), "{e}");
        let e = parse(&binary(b"", &[])).unwrap_err();
        assert!(matches!(e, MeshErrorKind::Empty(_)), "{e}");
        let mut b = binary(b"", &SQUARE);
        b[12 + 84 + 50..16 + 84 + 50].copy_from_slice(&f32::INFINITY.to_le_bytes());
        let e = parse(&b).unwrap_err();
        assert!(
            matches!(e, MeshErrorKind::NonFinite { vertex: 3, .. }),
            "{e}"
        );
        let e = parse(b"").unwrap_err();
        assert!(matches!(e, MeshErrorKind::Truncated(_)), "{e}");
        // A long binary token in a message is escaped and cut.
        let e = kind(&format!(
            "solid x\nfacet normal 0 0 \u{1}{}\n",
            "9".repeat(100)
        ));
        let msg = e.to_string();
        assert!(msg.contains("\\x01") && msg.len() < 120, "{msg}");
    }

    #[test]
    fn a_huge_count_is_refused_before_allocating() {
        let mut b = binary(b"", &SQUARE);
        b[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = parse(&b).unwrap_err();
        assert!(matches!(e, MeshErrorKind::Truncated(_)), "{e}");
        assert!(e.to_string().contains("4294967295 facets"), "{e}");
    }

    #[test]
    fn write_then_read_round_trips() {
        let pos = vec![
            [0.5, -1.0, 2.0],
            [1.0, 2.0, 3.0],
            [-4.0, 5.0, 6.25],
            [0.0, 0.0, 9.0],
        ];
        let idx = vec![0, 1, 2, 2, 1, 3, 0, 0, 0];
        let mut buf = Vec::new();
        write_binary(&pos, &idx, &mut buf).unwrap();
        assert_eq!(buf.len(), 84 + 3 * 50);
        assert_eq!(parse(&buf).unwrap(), (pos, idx));
    }
}
