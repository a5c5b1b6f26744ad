//! PLY reader (ASCII and binary little/big endian) and a binary little-endian writer.
//!
//! Reads the `vertex` element's `x`, `y`, `z` (any numeric type), polygons from `face`
//! (`vertex_indices` or `vertex_index`, any integer list type; fan-triangulated) and triangle strips
//! from `tristrips` (unrolled with alternating winding, `-1` restarts a strip). Other elements and
//! properties are skipped. Header counts are never trusted for allocation: reservations are capped by
//! the bytes actually present, and a body shorter or longer than the header says is an error.

use super::error::{parse_err, MeshErrorKind};
use super::tokens::Tokens;
use std::io::Write;

/// Longest header we accept; a real header is a few hundred bytes, so this stops a scan of a binary blob.
const MAX_HEADER_BYTES: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Clone, Debug)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: PropKind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

/// What the reader does with one element.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Vertex { x: usize, y: usize, z: usize },
    Face { list: usize },
    Strips { list: usize },
    Skip,
}

/// Parses a whole PLY file into positions and a triangle index buffer (not yet validated as a mesh).
pub fn parse(data: &[u8]) -> Result<(Vec<[f32; 3]>, Vec<u32>), MeshErrorKind> {
    let (encoding, elements, body_start, header_lines) = parse_header(data)?;
    let vertex_count = elements
        .iter()
        .find(|e| e.name == "vertex")
        .map(|e| e.count)
        .ok_or_else(|| parse_err("header", "no 'vertex' element"))?;
    if vertex_count > u32::MAX as u64 {
        return Err(MeshErrorKind::TooLarge(format!(
            "{vertex_count} vertices do not fit 32-bit indices"
        )));
    }
    if !elements
        .iter()
        .any(|e| e.name == "face" || e.name == "tristrips")
    {
        return Err(parse_err("header", "no 'face' or 'tristrips' element"));
    }
    let roles = elements
        .iter()
        .map(role_of)
        .collect::<Result<Vec<_>, _>>()?;

    let mut out = Output {
        positions: Vec::new(),
        indices: Vec::new(),
        vertex_count,
    };
    let body = &data[body_start..];
    match encoding {
        Encoding::Ascii => read_ascii(body, header_lines, &elements, &roles, &mut out)?,
        Encoding::BinaryLe => read_binary::<false>(body, &elements, &roles, &mut out)?,
        Encoding::BinaryBe => read_binary::<true>(body, &elements, &roles, &mut out)?,
    }
    Ok((out.positions, out.indices))
}

fn parse_header(data: &[u8]) -> Result<(Encoding, Vec<Element>, usize, usize), MeshErrorKind> {
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= data.len() || pos > MAX_HEADER_BYTES {
            return Err(if pos >= data.len() {
                MeshErrorKind::Truncated("header has no 'end_header' line".into())
            } else {
                parse_err("header", "no 'end_header' in the first 1 MiB")
            });
        }
        let end = data[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map(|i| pos + i);
        let Some(end) = end else {
            return Err(MeshErrorKind::Truncated(
                "header has no 'end_header' line".into(),
            ));
        };
        let raw = &data[pos..end];
        pos = end + 1;
        line_no += 1;
        let line = std::str::from_utf8(raw)
            .map_err(|_| parse_err(format!("header line {line_no}"), "not valid text"))?
            .trim_end_matches('\r');
        let loc = || format!("header line {line_no}");
        let mut words = line.split_whitespace();
        let first = words.next().unwrap_or("");
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err(parse_err(loc(), "not a PLY file (first line is not 'ply')"));
            }
            continue;
        }
        match first {
            "" | "comment" | "obj_info" => {}
            "format" => {
                let enc = match words.next() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::BinaryLe,
                    Some("binary_big_endian") => Encoding::BinaryBe,
                    other => {
                        return Err(MeshErrorKind::Unsupported(format!(
                            "PLY format '{}' ({})",
                            other.unwrap_or(""),
                            loc()
                        )))
                    }
                };
                encoding = Some(enc);
            }
            "element" => {
                let name = words
                    .next()
                    .ok_or_else(|| parse_err(loc(), "element without a name"))?;
                let count = words
                    .next()
                    .and_then(|c| c.parse::<u64>().ok())
                    .ok_or_else(|| {
                        parse_err(loc(), "element count is not a non-negative integer")
                    })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            "property" => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| parse_err(loc(), "property before any element"))?;
                let ty = words
                    .next()
                    .ok_or_else(|| parse_err(loc(), "property without a type"))?;
                let kind = if ty == "list" {
                    let c = words.next().unwrap_or("");
                    let i = words.next().unwrap_or("");
                    let count = Scalar::parse(c).ok_or_else(|| {
                        MeshErrorKind::Unsupported(format!("list count type '{c}' ({})", loc()))
                    })?;
                    let item = Scalar::parse(i).ok_or_else(|| {
                        MeshErrorKind::Unsupported(format!("list item type '{i}' ({})", loc()))
                    })?;
                    if !count.is_integer() {
                        return Err(MeshErrorKind::Unsupported(format!(
                            "list count type '{c}' is not an integer type ({})",
                            loc()
                        )));
                    }
                    PropKind::List { count, item }
                } else {
                    PropKind::Scalar(Scalar::parse(ty).ok_or_else(|| {
                        MeshErrorKind::Unsupported(format!("property type '{ty}' ({})", loc()))
                    })?)
                };
                let name = words
                    .next()
                    .ok_or_else(|| parse_err(loc(), "property without a name"))?;
                el.props.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            "end_header" => break,
            other => {
                return Err(parse_err(
                    loc(),
                    format!("unknown header keyword '{other}'"),
                ))
            }
        }
    }
    let encoding = encoding.ok_or_else(|| parse_err("header", "no 'format' line"))?;
    Ok((encoding, elements, pos, line_no))
}

fn role_of(e: &Element) -> Result<Role, MeshErrorKind> {
    let find = |name: &str| e.props.iter().position(|p| p.name == name);
    match e.name.as_str() {
        "vertex" => {
            let get = |n: &str| {
                let i = find(n)
                    .ok_or_else(|| parse_err("header", format!("vertex has no '{n}' property")))?;
                match e.props[i].kind {
                    PropKind::Scalar(_) => Ok(i),
                    PropKind::List { .. } => Err(MeshErrorKind::Unsupported(format!(
                        "vertex '{n}' is a list"
                    ))),
                }
            };
            Ok(Role::Vertex {
                x: get("x")?,
                y: get("y")?,
                z: get("z")?,
            })
        }
        "face" | "tristrips" => {
            let list = find("vertex_indices")
                .or_else(|| find("vertex_index"))
                .ok_or_else(|| {
                    parse_err(
                        "header",
                        format!("{} has no 'vertex_indices' property", e.name),
                    )
                })?;
            match e.props[list].kind {
                PropKind::List { item, .. } if item.is_integer() => {}
                PropKind::List { item, .. } => {
                    return Err(MeshErrorKind::Unsupported(format!(
                        "{} indices of type {item:?}; integer types only",
                        e.name
                    )))
                }
                PropKind::Scalar(_) => {
                    return Err(MeshErrorKind::Unsupported(format!(
                        "{} vertex_indices is not a list",
                        e.name
                    )))
                }
            }
            Ok(if e.name == "face" {
                Role::Face { list }
            } else {
                Role::Strips { list }
            })
        }
        _ => Ok(Role::Skip),
    }
}

/// Accumulates triangles from faces and strips, checking indices against the declared vertex count.
struct Output {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    vertex_count: u64,
}

impl Output {
    fn index(&self, v: i64, what: &dyn Fn() -> String) -> Result<u32, MeshErrorKind> {
        if v < 0 || v as u64 >= self.vertex_count {
            return Err(parse_err(
                what(),
                format!(
                    "vertex index {v} out of range (the header declares {} vertices)",
                    self.vertex_count
                ),
            ));
        }
        Ok(v as u32)
    }

    /// Fan-triangulates one polygon.
    fn face(&mut self, poly: &[i64], what: &dyn Fn() -> String) -> Result<(), MeshErrorKind> {
        if poly.len() < 3 {
            return Err(parse_err(
                what(),
                format!("polygon with {} vertices (at least 3 needed)", poly.len()),
            ));
        }
        let a = self.index(poly[0], what)?;
        for w in poly[1..].windows(2) {
            let b = self.index(w[0], what)?;
            let c = self.index(w[1], what)?;
            self.indices.extend_from_slice(&[a, b, c]);
        }
        Ok(())
    }

    /// Unrolls triangle strips; -1 restarts. Odd triangles swap their first two corners to keep the winding.
    fn strips(&mut self, list: &[i64], what: &dyn Fn() -> String) -> Result<(), MeshErrorKind> {
        for strip in list.split(|&v| v == -1) {
            for i in 2..strip.len() {
                let (a, b, c) = if i % 2 == 0 {
                    (strip[i - 2], strip[i - 1], strip[i])
                } else {
                    (strip[i - 1], strip[i - 2], strip[i])
                };
                let tri = [
                    self.index(a, what)?,
                    self.index(b, what)?,
                    self.index(c, what)?,
                ];
                self.indices.extend_from_slice(&tri);
            }
        }
        Ok(())
    }
}

fn read_binary<const BE: bool>(
    body: &[u8],
    elements: &[Element],
    roles: &[Role],
    out: &mut Output,
) -> Result<(), MeshErrorKind> {
    let mut r = BinReader::<BE> { data: body, pos: 0 };
    let mut list: Vec<i64> = Vec::new();
    for (e, role) in elements.iter().zip(roles) {
        // Smallest possible record size caps the reservation: a header cannot make us allocate.
        let min_record: usize = e
            .props
            .iter()
            .map(|p| match p.kind {
                PropKind::Scalar(s) => s.size(),
                PropKind::List { count, .. } => count.size(),
            })
            .sum::<usize>()
            .max(1);
        check_count(e, role, out, r.remaining(), min_record)?;
        for rec in 0..e.count {
            let what = || format!("{} {rec}", e.name);
            match *role {
                Role::Vertex { x, y, z } => {
                    let mut xyz = [0f32; 3];
                    for (pi, p) in e.props.iter().enumerate() {
                        let PropKind::Scalar(s) = p.kind else {
                            r.skip_list(p, &what)?;
                            continue;
                        };
                        let v = r.scalar(s, &what)?;
                        if pi == x {
                            xyz[0] = v as f32;
                        } else if pi == y {
                            xyz[1] = v as f32;
                        } else if pi == z {
                            xyz[2] = v as f32;
                        }
                    }
                    out.positions.push(xyz);
                }
                Role::Face { list: li } | Role::Strips { list: li } => {
                    for (pi, p) in e.props.iter().enumerate() {
                        match p.kind {
                            PropKind::List { count, item } if pi == li => {
                                let n = r.scalar(count, &what)?;
                                let n = list_len(n, &what)?;
                                if n.saturating_mul(item.size()) > r.remaining() {
                                    return Err(MeshErrorKind::Truncated(format!(
                                        "file ends inside {} ({n} indices announced, {} bytes left)",
                                        what(),
                                        r.remaining()
                                    )));
                                }
                                list.clear();
                                for _ in 0..n {
                                    list.push(r.scalar(item, &what)? as i64);
                                }
                            }
                            PropKind::List { .. } => r.skip_list(p, &what)?,
                            PropKind::Scalar(s) => r.skip(s.size(), &what)?,
                        }
                    }
                    if matches!(role, Role::Face { .. }) {
                        out.face(&list, &what)?;
                    } else {
                        out.strips(&list, &what)?;
                    }
                }
                Role::Skip => {
                    for p in &e.props {
                        match p.kind {
                            PropKind::Scalar(s) => r.skip(s.size(), &what)?,
                            PropKind::List { .. } => r.skip_list(p, &what)?,
                        }
                    }
                }
            }
        }
    }
    if r.remaining() > 0 {
        return Err(MeshErrorKind::CountMismatch(format!(
            "{} bytes follow the last element the header declares",
            r.remaining()
        )));
    }
    Ok(())
}

/// Refuses a record count that the remaining bytes cannot hold (so a header can never make us
/// allocate), then reserves room for vertices.
fn check_count(
    e: &Element,
    role: &Role,
    out: &mut Output,
    bytes: usize,
    min_record: usize,
) -> Result<(), MeshErrorKind> {
    if e.count > (bytes / min_record) as u64 {
        return Err(MeshErrorKind::Truncated(format!(
            "header declares {} {} records, but only {bytes} bytes remain (at least {min_record} per record)",
            e.count, e.name
        )));
    }
    if let Role::Vertex { .. } = role {
        out.positions.reserve(e.count as usize);
    }
    Ok(())
}

fn list_len(n: f64, what: &dyn Fn() -> String) -> Result<usize, MeshErrorKind> {
    if n < 0.0 {
        return Err(parse_err(what(), format!("negative list length {n}")));
    }
    Ok(n as usize)
}

struct BinReader<'a, const BE: bool> {
    data: &'a [u8],
    pos: usize,
}

impl<const BE: bool> BinReader<'_, BE> {
    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
    fn take<const N: usize>(
        &mut self,
        what: &dyn Fn() -> String,
    ) -> Result<[u8; N], MeshErrorKind> {
        let Some(bytes) = self.data.get(self.pos..self.pos + N) else {
            return Err(MeshErrorKind::Truncated(format!(
                "file ends inside {}",
                what()
            )));
        };
        self.pos += N;
        let mut a: [u8; N] = bytes.try_into().expect("slice has length N");
        if BE {
            a.reverse();
        }
        Ok(a)
    }
    fn skip(&mut self, n: usize, what: &dyn Fn() -> String) -> Result<(), MeshErrorKind> {
        if n > self.remaining() {
            return Err(MeshErrorKind::Truncated(format!(
                "file ends inside {}",
                what()
            )));
        }
        self.pos += n;
        Ok(())
    }
    fn skip_list(&mut self, p: &Property, what: &dyn Fn() -> String) -> Result<(), MeshErrorKind> {
        let PropKind::List { count, item } = p.kind else {
            unreachable!("skip_list on a scalar")
        };
        let n = list_len(self.scalar(count, what)?, what)?;
        self.skip(n.saturating_mul(item.size()), what)
    }
    /// Reads one value; f64 holds every supported type exactly.
    fn scalar(&mut self, s: Scalar, what: &dyn Fn() -> String) -> Result<f64, MeshErrorKind> {
        Ok(match s {
            Scalar::I8 => i8::from_le_bytes(self.take::<1>(what)?) as f64,
            Scalar::U8 => u8::from_le_bytes(self.take::<1>(what)?) as f64,
            Scalar::I16 => i16::from_le_bytes(self.take::<2>(what)?) as f64,
            Scalar::U16 => u16::from_le_bytes(self.take::<2>(what)?) as f64,
            Scalar::I32 => i32::from_le_bytes(self.take::<4>(what)?) as f64,
            Scalar::U32 => u32::from_le_bytes(self.take::<4>(what)?) as f64,
            Scalar::F32 => f32::from_le_bytes(self.take::<4>(what)?) as f64,
            Scalar::F64 => f64::from_le_bytes(self.take::<8>(what)?),
        })
    }
}

/// The next ASCII value of scalar type `s`; `what` names the record for messages.
fn value(t: &mut Tokens, s: Scalar, what: &dyn Fn() -> String) -> Result<f64, MeshErrorKind> {
    let Some((tok, line)) = t.next() else {
        return Err(MeshErrorKind::Truncated(format!(
            "file ends inside {}",
            what()
        )));
    };
    let bad = || {
        parse_err(
            format!("line {line} ({})", what()),
            format!(
                "'{}' is not a valid {s:?} value",
                String::from_utf8_lossy(tok)
            ),
        )
    };
    // The body was checked to be UTF-8 and tokens end at ASCII whitespace, so this never fails;
    // if it did, the token is no number either.
    let tok = std::str::from_utf8(tok).map_err(|_| bad())?;
    if s.is_integer() {
        tok.parse::<i64>().map(|v| v as f64).map_err(|_| bad())
    } else {
        tok.parse::<f64>().map_err(|_| bad())
    }
}

fn read_ascii(
    body: &[u8],
    header_lines: usize,
    elements: &[Element],
    roles: &[Role],
    out: &mut Output,
) -> Result<(), MeshErrorKind> {
    let text = std::str::from_utf8(body).map_err(|e| {
        parse_err(
            format!("byte {} of the body", e.valid_up_to()),
            "ASCII PLY body is not valid text",
        )
    })?;
    let mut t = Tokens::new(text.as_bytes(), header_lines + 1);
    let mut list: Vec<i64> = Vec::new();
    for (e, role) in elements.iter().zip(roles) {
        // Every ASCII value takes at least two bytes (digit and separator).
        check_count(e, role, out, body.len() - t.pos, 2 * e.props.len().max(1))?;
        for rec in 0..e.count {
            let what = || format!("{} {rec}", e.name);
            let mut xyz = [0f32; 3];
            list.clear();
            for (pi, p) in e.props.iter().enumerate() {
                match p.kind {
                    PropKind::Scalar(s) => {
                        let v = value(&mut t, s, &what)?;
                        if let Role::Vertex { x, y, z } = *role {
                            if pi == x {
                                xyz[0] = v as f32;
                            } else if pi == y {
                                xyz[1] = v as f32;
                            } else if pi == z {
                                xyz[2] = v as f32;
                            }
                        }
                    }
                    PropKind::List { count, item } => {
                        let n = list_len(value(&mut t, count, &what)?, &what)?;
                        let keep = matches!(*role, Role::Face { list: li } | Role::Strips { list: li } if li == pi);
                        for _ in 0..n {
                            let v = value(&mut t, item, &what)?;
                            if keep {
                                list.push(v as i64);
                            }
                        }
                    }
                }
            }
            match role {
                Role::Vertex { .. } => out.positions.push(xyz),
                Role::Face { .. } => out.face(&list, &what)?,
                Role::Strips { .. } => out.strips(&list, &what)?,
                Role::Skip => {}
            }
        }
    }
    if let Some((tok, line)) = t.next() {
        return Err(MeshErrorKind::CountMismatch(format!(
            "line {line}: '{}' follows the last element the header declares",
            String::from_utf8_lossy(tok)
        )));
    }
    Ok(())
}

/// Writes a binary little-endian PLY (float x/y/z; `list uchar uint vertex_indices`), the format of
/// the shared test meshes.
pub fn write_binary(positions: &[[f32; 3]], indices: &[u32], w: impl Write) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::with_capacity(1 << 16, w);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment written by meshletlab\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        positions.len(),
        indices.len() / 3
    )?;
    for p in positions {
        for c in p {
            w.write_all(&c.to_le_bytes())?;
        }
    }
    for t in indices.chunks_exact(3) {
        w.write_all(&[3])?;
        for i in t {
            w.write_all(&i.to_le_bytes())?;
        }
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI_ASCII: &str =
        "ply\nformat ascii 1.0\ncomment x\nelement vertex 4\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_is_fan_triangulated() {
        let (p, i) = parse(TRI_ASCII.as_bytes()).unwrap();
        assert_eq!(p.len(), 4);
        assert_eq!(i, vec![0, 1, 2, 0, 2, 3]);
    }

    fn binary(be: bool, count_ty: &str, item_ty: &str, faces: &[&[i64]]) -> Vec<u8> {
        let enc = if be {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut d = format!(
            "ply\nformat {enc} 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
             property uchar red\nelement face {}\nproperty list {count_ty} {item_ty} vertex_indices\n\
             property float quality\nend_header\n",
            faces.len()
        )
        .into_bytes();
        let put = |d: &mut Vec<u8>, mut b: Vec<u8>| {
            if be {
                b.reverse();
            }
            d.extend(b);
        };
        for v in 0..4 {
            for c in 0..3 {
                put(&mut d, ((v * 3 + c) as f64).to_le_bytes().to_vec());
            }
            d.push(7);
        }
        let enc_int = |ty: &str, v: i64| -> Vec<u8> {
            match ty {
                "uchar" => (v as u8).to_le_bytes().to_vec(),
                "char" => (v as i8).to_le_bytes().to_vec(),
                "ushort" => (v as u16).to_le_bytes().to_vec(),
                "short" => (v as i16).to_le_bytes().to_vec(),
                "uint" => (v as u32).to_le_bytes().to_vec(),
                "int" => (v as i32).to_le_bytes().to_vec(),
                _ => unreachable!(),
            }
        };
        for f in faces {
            put(&mut d, enc_int(count_ty, f.len() as i64));
            for &i in f.iter() {
                put(&mut d, enc_int(item_ty, i));
            }
            put(&mut d, 0.5f32.to_le_bytes().to_vec());
        }
        d
    }

    #[test]
    fn binary_all_list_types_both_endians() {
        for be in [false, true] {
            for ct in ["uchar", "char", "ushort", "short", "uint", "int"] {
                for it in ["uchar", "char", "ushort", "short", "uint", "int"] {
                    let d = binary(be, ct, it, &[&[0, 1, 2], &[0, 2, 3, 1]]);
                    let (p, i) = parse(&d).unwrap_or_else(|e| panic!("{be} {ct} {it}: {e}"));
                    assert_eq!(p[1], [3.0, 4.0, 5.0]);
                    assert_eq!(i, vec![0, 1, 2, 0, 2, 3, 0, 3, 1]);
                }
            }
        }
    }

    #[test]
    fn tristrips_unroll_with_alternating_winding() {
        let d = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
                 element tristrips 1\nproperty list int int vertex_indices\nend_header\n\
                 0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 2 0\n8 0 1 2 3 -1 2 3 4\n";
        let (_, i) = parse(d.as_bytes()).unwrap();
        // Strip 0 1 2 3 -> (0,1,2), (2,1,3); after the restart, strip 2 3 4 -> (2,3,4).
        assert_eq!(i, vec![0, 1, 2, 2, 1, 3, 2, 3, 4]);
    }

    #[test]
    fn write_then_read_round_trips() {
        let pos = vec![[0.5, -1.0, 2.0], [1.0, 2.0, 3.0], [-4.0, 5.0, 6.25]];
        let idx = vec![0, 1, 2, 2, 1, 0];
        let mut buf = Vec::new();
        write_binary(&pos, &idx, &mut buf).unwrap();
        assert_eq!(parse(&buf).unwrap(), (pos, idx));
    }

    #[test]
    fn trailing_bytes_and_short_bodies_are_errors() {
        let d = binary(false, "uchar", "int", &[&[0, 1, 2]]);
        let mut long = d.clone();
        long.push(0);
        assert!(matches!(parse(&long), Err(MeshErrorKind::CountMismatch(_))));
        assert!(matches!(
            parse(&d[..d.len() - 1]),
            Err(MeshErrorKind::Truncated(_))
        ));
        let extra = format!("{TRI_ASCII}1 2 3\n");
        assert!(matches!(
            parse(extra.as_bytes()),
            Err(MeshErrorKind::CountMismatch(_))
        ));
    }

    #[test]
    fn absurd_counts_do_not_allocate() {
        let d = TRI_ASCII.replace("element vertex 4", "element vertex 999999999999");
        assert!(matches!(
            parse(d.as_bytes()),
            Err(MeshErrorKind::TooLarge(_))
        ));
        let d = TRI_ASCII.replace("element face 1", "element face 4000000000");
        assert!(matches!(
            parse(d.as_bytes()),
            Err(MeshErrorKind::Truncated(_))
        ));
        let mut b = binary(false, "uint", "int", &[&[0, 1, 2]]);
        // Claim a 4-billion-entry polygon.
        let at = b.len() - 4 - 12 - 4;
        b[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(parse(&b), Err(MeshErrorKind::Truncated(_))));
    }

    #[test]
    fn unsupported_types_and_bad_indices() {
        let d = TRI_ASCII.replace("property float z", "property float128 z");
        assert!(matches!(
            parse(d.as_bytes()),
            Err(MeshErrorKind::Unsupported(_))
        ));
        let d = TRI_ASCII.replace("uchar int vertex_indices", "uchar float vertex_indices");
        assert!(matches!(
            parse(d.as_bytes()),
            Err(MeshErrorKind::Unsupported(_))
        ));
        let d = TRI_ASCII.replace("4 0 1 2 3", "4 0 1 2 9");
        let e = parse(d.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("face 0") && e.contains("9"), "{e}");
        let d = TRI_ASCII.replace("4 0 1 2 3", "3 0 1 -2");
        assert!(parse(d.as_bytes()).is_err());
        let d = TRI_ASCII.replace("1 1 0\n", "1 x 0\n");
        let e = parse(d.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("line 13"), "{e}");
    }
}
