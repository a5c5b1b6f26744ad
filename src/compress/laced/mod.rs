//! Laced wires (Mlakar, Steinberger, Schmalstieg, CGF 43(1), 2024, §3.2-3.4): every vertex is
//! stored once, on the *wire* that owns it, and each meshlet's triangles are *laces* between
//! positions of the wires it touches.
//!
//! **Wires.** A vertex used by one meshlet belongs to that meshlet's *internal wire*; a vertex
//! used by exactly two meshlets to their *external wire*; a vertex used by three or more is a
//! *corner*, stored in the mesh frame on one corner pseudo-wire. An external wire runs
//! counter-clockwise along the boundary of its smaller-index meshlet (the larger one reads it
//! backwards). The internal wire is the paper's greedy spiral: vertices levelled by their edge
//! distance to the meshlet boundary, the path always steps to the unvisited neighbour of lowest
//! level (ties: the one that closes a triangle with the last wire edge, then the lower index)
//! and, when the tip is stuck, restarts beside the most recent path vertex that still has an
//! unvisited neighbour (the lowest unvisited level if none has).
//!
//! **Laces.** A meshlet's *local order* is its internal wire followed by its *boundary items*
//! (external wires, in their direction, and corners) in the order a counter-clockwise walk of
//! its boundary meets them: the paper's references into external wires through the meshlet's
//! boundary ordering. Local positions `k, k + 1` form a *wire edge*, and so does the boundary's
//! closing pair (last position, first boundary position) when the boundary has three or more
//! positions (wire edge `n - 1`). A triangle holding wire edge
//! `k -> k + 1` lies left of it, one holding `k + 1 -> k` right of it: either is a one-reference
//! triangle (1RT) naming only its third vertex. Left and right laces are separate subsequences of
//! one-byte symbols (2-bit type, 6-bit value) walking the wire edges: `00 n` skips `n + 1` wire
//! edges, `01 v` is a 1RT with third vertex `v`, and `10 v` and `11 v` (ours, *long laces*) are
//! the triangles `k, k + 2, v` and `k, k + 3, v` where the wire bends, without moving on. Triangles on no free wire edge (a second
//! triangle on a non-manifold edge, degenerate and isolated triangles, fans between wires) go to
//! a third subsequence of strips: `11 a`, `b`, `c` (3RT, three bytes) starts a strip, `tt v` with
//! `tt` in 0..3 adds the neighbour across edge `tt` of the previous triangle with new vertex `v`
//! (2RT: the pair shares two references). Every input triangle comes back out.
//!
//! **Geometry.** Each wire is a self-contained bit string, padded to 32-bit words: its vertex
//! count, an anchor on the global grid ([`super::grid_exponent`]) and per-axis bit widths (the
//! box, 3 G + 15 + count bits, about 9 bytes at the paper's tolerance), then each vertex's offset
//! from the anchor. Ours: where it is smaller, a wire is *delta-coded* instead (a mode bit and
//! three more widths): the first vertex as an offset, every next one as the zigzag difference to
//! the one before (wire neighbours are mostly mesh neighbours, so differences are short). Every vertex is stored once, so it decodes to the same bits in every meshlet:
//! crack-free by construction.
//!
//! **Where we differ.** The per-wire box is axis-aligned on the one global grid rather than
//! oriented to the wire's dominant plane: it keeps every coordinate an integer of one grid, so the
//! tolerance holds by construction and no rotation is rounded in f32. Corners are the vertices of
//! three or more meshlets only; the ends of an open boundary run stay on their wire (the run's
//! owner pair is known, so no corner is needed to delimit it). The restart of the internal wire
//! is implicit: a jump is a wire edge without triangles, skipped like any other. The culling
//! record (8 bytes per meshlet, [`Culling`]) stores an explicit coarse centre and octahedral axis
//! where the paper derives them from its oriented boxes and stores only radius scale, cone angle
//! and apex offset; without an apex the task shader uses the sphere-centre cone test. Both are
//! computed from the decoded positions, so they are conservative for what is drawn. Short external wires (at most [`SHORT_WIRE`] vertices)
//! are stored as corners.
//!
//! **Layout** (`data`; all offsets in bytes from its start, integers little-endian):
//!
//! | bytes | field |
//! |---|---|
//! | 4, 4, 4 | meshlets M, external wires E, corners C |
//! | 1, 1, 1, 1 | G (bits of a global grid coordinate), count bits, external-wire id bits, corner id bits |
//! | 4, 4 | wire table offset, first wire offset |
//! | 8 M | culling records, one u64 per meshlet (see [`Culling`]): centre 3 x 10 bits, radius code 8, axis 2 x 8, cutoff 8 |
//! | .. | meshlet records, each padded to 4 bytes (offsets in the file's table) |
//! | 4 (M + E + 1) | wire table: byte offset of wire `w` (internal wire of meshlet `i` is `w = i`, external wire `j` is `M + j`, the corner wire `M + E`) |
//! | .. | wires, each padded to 4 bytes |
//!
//! A meshlet record, bit-packed LSB first: internal count (7), item count (7), left symbols (8),
//! right symbols (8), strip bytes (10), then one kind bit per item (0 = external wire, 1 = corner),
//! then per item the wire id plus a direction bit (1 = backwards), or the corner id (kinds first,
//! so item `j`'s offset is a popcount of the kind bits before it: the mesh shader reads every
//! item in parallel); then, byte-aligned, the
//! left, right and strip symbols. A wire: count (7) and delta mode (1) except on the
//! corner wire, anchor (3 x G), bits per axis (3 x 5), in delta mode difference bits per axis
//! (3 x 5), then per vertex x, y, z.
//!
//! The decoder's vertex ids come from [`Encoded::wire_base`] and [`Encoded::stored_to_source`]:
//! provenance for checking against the source mesh, not part of the format's size.
//!
//! **Files.** The widths and offsets above are one table, `layout.rs`: the encoder writes it, the
//! decoders read it, and build.rs writes it as GLSL constants (`laced_layout.glsl`) for the task
//! and mesh shaders that decode the same bytes (glsl/compressed.task, glsl/laced.mesh).
//! `wires.rs` holds the topology and the wires, `laces.rs` the laces and strips, `culling.rs`
//! the culling record; this file the entry points, the section header and the meshlet record.

mod culling;
mod laces;
mod layout;
mod wires;

pub use culling::{culling, Culling};
pub use layout::CULL;

use super::bits::{bits_for, width, BitReader, BitWriter};
use super::{quantise, DecodeError, Decoded, Encoded, Sizes};
use crate::mesh::Mesh;
use crate::meshlet::Meshlets;
use culling::culling_record;
use layout::{
    CULLING_AT, DIRECTION_BITS, KIND_BITS, RECORD, RECORD_BITS, SECTION, SECTION_HEADER, STRIPS,
};
use rayon::prelude::*;
use wires::{external_wires, owners, shape, wire, wire_string, Item, Owner, Shape, Wire};

/// Most vertices a meshlet may have (6-bit references).
pub const MAX_VERTICES: usize = 64;
/// External wires of at most this many vertices are stored as corners instead: a wire's box
/// (about 9 bytes), its table entry and its padding cost more than one or two vertices at full
/// grid width on the corner wire. Measured when introduced (before long laces, culling records
/// and delta wires) at the paper's tolerance on qem 64/84 meshlets, bytes per triangle for
/// 0/1/2/3/4: bunny 4.41/4.36/4.34/4.37/4.43, igea 4.33/4.29/4.27/4.33/4.42, fandisk
/// 4.24/4.19/4.18/4.20/4.27; re-checked after long laces at 1e-4 on meshopt 64/126 meshlets for
/// 1/2/3: bunny 3.489/3.494/3.507, dragon 3.326/3.322/3.354, igea 3.238/3.242/3.265 (1 and 2 tie).
pub const SHORT_WIRE: usize = 2;

/// Why a meshlet set cannot be encoded as laced wires.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum LacedEncodeError {
    /// A meshlet above 64 vertices (or an empty one).
    #[error("meshlet {0}: laced wires take 1 to 64 vertices per meshlet (6-bit references)")]
    Size(usize),
    /// More strip bytes than the header's 10 bits count.
    #[error("meshlet {0}: over 1023 strip bytes (too many triangles off the wires)")]
    Strips(usize),
    /// The mesh's extent on the grid needs more than 31 bits.
    #[error("grid coordinates exceed 31 bits (tolerance too small for this mesh's extent)")]
    GridTooFine,
    /// A tolerance that is not positive and finite, or whose grid rounds a position past the
    /// f32 range.
    #[error("the tolerance is not positive and finite, or its grid rounds a position past f32")]
    Tolerance,
}

/// Encodes `ml` (meshlets of `mesh`, at most 64 vertices each) at `tolerance`.
pub fn encode(mesh: &Mesh, ml: &Meshlets, tolerance: f64) -> Result<Encoded, LacedEncodeError> {
    let m = ml.len();
    for i in 0..m {
        let n = ml.meshlet_vertices(i).len();
        if n == 0 || n > MAX_VERTICES || ml.meshlet_triangles(i).is_empty() {
            return Err(LacedEncodeError::Size(i));
        }
    }
    let (owner, pairs, corners) = owners(mesh.vertex_count(), ml);
    let shapes: Vec<Shape> = (0..m)
        .into_par_iter()
        .map(|i| shape(ml, i, &owner, &pairs))
        .collect();
    let wires = external_wires(&owner, &pairs, &shapes);
    let e = super::checked_grid(mesh, tolerance).ok_or(LacedEncodeError::Tolerance)?;
    let origin = mesh.bounding_box().0.to_array();
    let grid = |v: u32| {
        let p = mesh.positions[v as usize];
        [0, 1, 2].map(|a| quantise(p[a], origin[a], e).max(0))
    };
    let top = (0..mesh.vertex_count() as u32)
        .filter(|&v| owner[v as usize] != Owner::Unused)
        .flat_map(&grid)
        .max()
        .unwrap_or(0);
    let g = width(top as u64);
    if g > 31 {
        return Err(LacedEncodeError::GridTooFine);
    }
    let wire_count = m + wires.len() + 1;
    let all_wires: Vec<&[u32]> = shapes
        .iter()
        .map(|s| s.internal.as_slice())
        .chain(wires.iter().map(|w| w.as_slice()))
        .chain(std::iter::once(corners.as_slice()))
        .collect();
    let wire_bits = bits_for(wires.len());
    let corner_bits = bits_for(corners.len());

    // Meshlet records.
    let records: Vec<(Vec<u8>, [usize; 4])> = (0..m)
        .into_par_iter()
        .map(|i| record(ml, i, &shapes[i], &wires, &corners, wire_bits, corner_bits))
        .collect::<Result<_, _>>()?;
    // Wires.
    let strings: Vec<(Vec<u8>, [usize; 4])> = all_wires
        .par_iter()
        .enumerate()
        .map(|(k, w)| wire_string(w, &grid, g, k + 1 < wire_count))
        .collect();

    let culling: Vec<u64> = (0..m)
        .into_par_iter()
        .map(|i| culling_record(ml, i, &grid, origin, e, g))
        .collect();
    let mut data = vec![0u8; CULLING_AT];
    for c in &culling {
        data.extend(c.to_le_bytes());
    }
    let mut bits = [0usize; 4]; // connectivity, positions, headers, padding (in bits)
    let mut offsets = Vec::with_capacity(m);
    for (r, b) in &records {
        offsets.push(data.len() as u32);
        data.extend_from_slice(r);
        for k in 0..4 {
            bits[k] += b[k];
        }
    }
    // The wire table: each wire's start in 32-bit words after the first, in just enough bits.
    let mut words = Vec::with_capacity(wire_count);
    let mut w = 0usize;
    for (s, _) in &strings {
        words.push(w as u32);
        w += s.len() / 4;
    }
    let table_bits = width(words.last().copied().unwrap_or(0) as u64).max(1);
    let table = data.len();
    let mut packed = BitWriter::new();
    for &x in &words {
        packed.put(table_bits, x);
    }
    packed.pad(32);
    data.extend_from_slice(packed.bytes());
    let first = data.len();
    let mut wire_head = wire_count * table_bits as usize;
    for (s, b) in &strings {
        data.extend_from_slice(s);
        for k in 0..4 {
            bits[k] += b[k];
        }
        wire_head += b[2];
    }
    let mut head = BitWriter::new();
    let fields = [
        m as u32,
        wires.len() as u32,
        corners.len() as u32,
        g,
        table_bits,
        wire_bits,
        corner_bits,
        table as u32,
        first as u32,
    ];
    for (f, v) in SECTION_HEADER.iter().zip(fields) {
        head.put(f.bits, v);
    }
    data[..SECTION].copy_from_slice(head.bytes());

    let connectivity = bits[0] / 8;
    let positions = bits[1] / 8;
    let headers = (bits[2] + wire_count * table_bits as usize) / 8 + SECTION + 4 * m;
    let sizes = Sizes {
        connectivity,
        positions,
        headers,
        geometry_headers: wire_head / 8,
        culling: CULL * m,
        padding: data.len() + 4 * m - connectivity - positions - headers - CULL * m,
    };
    let mut wire_base = Vec::with_capacity(wire_count);
    let mut stored_to_source = Vec::new();
    for w in &all_wires {
        wire_base.push(stored_to_source.len() as u32);
        stored_to_source.extend_from_slice(w);
    }
    Ok(Encoded {
        exponent: e,
        origin,
        source_vertices: mesh.vertex_count() as u32,
        offsets,
        data,
        sizes,
        wire_base,
        stored_to_source,
    })
}

/// Decodes meshlet `i` from the buffer alone (vertex ids through the provenance tables).
pub fn decode(enc: &Encoded, i: usize) -> Result<Decoded, DecodeError> {
    let start = *enc.offsets.get(i).ok_or(DecodeError::OutOfRange(i))? as usize;
    let s = section(enc, i)?;
    let bad = |what: String| DecodeError::Invalid { meshlet: i, what };
    let d = &enc.data;
    let mut r = BitReader::new(d, 8 * start, i, "record");
    let mut head = [0usize; RECORD.len()];
    for (h, f) in head.iter_mut().zip(&RECORD) {
        *h = r.get(f.bits)? as usize;
    }
    let [internal, items, nl, nr, ns] = head;
    // Local order as (wire, index in wire).
    let mut order: Vec<(usize, usize)> = (0..internal).map(|k| (i, k)).collect();
    let mut kinds = Vec::with_capacity(items);
    for _ in 0..items {
        kinds.push(r.get(KIND_BITS)?);
    }
    for kind in kinds {
        if kind == 0 {
            let j = r.get(s.wire_bits)? as usize;
            let back = r.get(DIRECTION_BITS)? == 1;
            if j >= s.e {
                return Err(bad(format!("external wire {j} of {}", s.e)));
            }
            let w = wire(enc, &s, s.m + j, i)?;
            if order.len() + w.count > MAX_VERTICES {
                return Err(bad("more than 64 vertices".into()));
            }
            for k in 0..w.count {
                order.push((s.m + j, if back { w.count - 1 - k } else { k }));
            }
        } else {
            let c = r.get(s.corner_bits)? as usize;
            if c >= s.c {
                return Err(bad(format!("corner {c} of {}", s.c)));
            }
            order.push((s.m + s.e, c));
        }
        if order.len() > MAX_VERTICES {
            return Err(bad("more than 64 vertices".into()));
        }
    }
    let n = order.len();
    let sym0 = r.at().div_ceil(8);
    let syms = d
        .get(sym0..sym0 + nl + nr + ns)
        .ok_or(DecodeError::Truncated {
            meshlet: i,
            what: "symbols",
        })?;
    let triangles = laces::triangles(syms, nl, nr, n, internal, i)?;
    // Positions and ids.
    let mut cache: Vec<(usize, Wire)> = Vec::new();
    let mut positions = Vec::with_capacity(n);
    let mut vertices = Vec::with_capacity(n);
    for &(w, k) in &order {
        if !cache.iter().any(|c| c.0 == w) {
            cache.push((w, wire(enc, &s, w, i)?));
        }
        let wr = &cache.iter().find(|c| c.0 == w).expect("cached").1;
        if k >= wr.count {
            return Err(bad(format!("vertex {k} of wire {w} with {}", wr.count)));
        }
        positions.push(wr.position(enc, k));
        let id = enc
            .wire_base
            .get(w)
            .and_then(|&b| enc.stored_to_source.get(b as usize + k))
            .copied()
            .ok_or_else(|| bad(format!("wire {w} vertex {k} has no provenance")))?;
        if id >= enc.source_vertices {
            return Err(bad(format!("vertex id {id} beyond the mesh")));
        }
        vertices.push(id);
    }
    Ok(Decoded {
        vertices,
        triangles,
        positions,
    })
}

/// Meshlet `i`'s record and its bits by kind (connectivity, positions, headers, padding).
#[allow(clippy::too_many_arguments)]
fn record(
    ml: &Meshlets,
    i: usize,
    s: &Shape,
    wires: &[Vec<u32>],
    corners: &[u32],
    wire_bits: u32,
    corner_bits: u32,
) -> Result<(Vec<u8>, [usize; 4]), LacedEncodeError> {
    let lv = ml.meshlet_vertices(i);
    let n = lv.len();
    // The local order: internal wire, then the items expanded.
    let mut order: Vec<u32> = s.internal.clone();
    for it in &s.items {
        match *it {
            Item::Wire(j, back) => {
                let w = &wires[j as usize];
                if back {
                    order.extend(w.iter().rev());
                } else {
                    order.extend(w);
                }
            }
            Item::Corner(c) => order.push(corners[c as usize]),
        }
    }
    debug_assert_eq!(
        order.len(),
        n,
        "meshlet {i}: local order covers its vertices"
    );
    let mut sorted: Vec<(u32, usize)> = order.iter().enumerate().map(|(k, &v)| (v, k)).collect();
    sorted.sort_unstable();
    let pos = |v: u32| sorted[sorted.binary_search_by_key(&v, |x| x.0).expect("in order")].1 as u8;
    let tris: Vec<[u8; 3]> = ml
        .meshlet_triangles(i)
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| pos(lv[t[k] as usize])))
        .collect();
    let (left, right, strips) = laces::laces(n, s.internal.len(), &tris);
    if strips.len() as u64 > STRIPS.max() {
        return Err(LacedEncodeError::Strips(i));
    }
    let mut w = BitWriter::new();
    let head = [
        s.internal.len(),
        s.items.len(),
        left.len(),
        right.len(),
        strips.len(),
    ];
    for (f, v) in RECORD.iter().zip(head) {
        w.put(f.bits, v as u32);
    }
    // Kind bits of every item first, then the ids: item `j` then starts at a bit offset a
    // popcount of the kind bits gives, so a shader reads every item at once.
    for it in &s.items {
        w.put(KIND_BITS, matches!(it, Item::Corner(_)) as u32);
    }
    for it in &s.items {
        match *it {
            Item::Wire(j, back) => {
                w.put(wire_bits, j);
                w.put(DIRECTION_BITS, back as u32);
            }
            Item::Corner(c) => w.put(corner_bits, c),
        }
    }
    let head_bits = RECORD_BITS as usize;
    let item_bits = w.at() - head_bits;
    let byte_pad = w.pad(8);
    let mut out = w.into_bytes();
    out.extend(left.iter().chain(&right).chain(&strips));
    let symbols = 8 * (left.len() + right.len() + strips.len());
    let pad = (4 - out.len() % 4) % 4;
    out.resize(out.len() + pad, 0);
    let padding = byte_pad + 8 * pad;
    Ok((out, [item_bits + symbols, 0, head_bits, padding]))
}

/// The section header's fields as the decoder reads them.
struct Section {
    m: usize,
    e: usize,
    c: usize,
    g: u32,
    table_bits: u32,
    wire_bits: u32,
    corner_bits: u32,
    table: usize,
    first: usize,
}

/// Meshlet `i`'s view of the section header, checked against the buffer.
fn section(enc: &Encoded, i: usize) -> Result<Section, DecodeError> {
    let d = &enc.data;
    let h = d.get(..SECTION).ok_or(DecodeError::Truncated {
        meshlet: i,
        what: "section header",
    })?;
    let mut r = BitReader::new(h, 0, i, "section header");
    let mut fields = [0u32; SECTION_HEADER.len()];
    for (x, f) in fields.iter_mut().zip(&SECTION_HEADER) {
        *x = r.get(f.bits)?;
    }
    let [m, e, c, g, table_bits, wire_bits, corner_bits, table, first] = fields;
    let s = Section {
        m: m as usize,
        e: e as usize,
        c: c as usize,
        g,
        table_bits,
        wire_bits,
        corner_bits,
        table: table as usize,
        first: first as usize,
    };
    let bad = |what: String| DecodeError::Invalid { meshlet: i, what };
    if s.g > 31 || s.table_bits > 32 || s.wire_bits > 32 || s.corner_bits > 32 {
        return Err(bad(format!(
            "section header widths {}/{}/{}/{} out of range",
            s.g, s.table_bits, s.wire_bits, s.corner_bits
        )));
    }
    if s.m != enc.offsets.len() {
        return Err(bad(format!(
            "{} meshlets in the section, {} offsets",
            s.m,
            enc.offsets.len()
        )));
    }
    let wires = s.m.checked_add(s.e).and_then(|x| x.checked_add(1));
    let end = wires
        .and_then(|w| w.checked_mul(s.table_bits as usize))
        .and_then(|b| b.checked_add(8 * s.table));
    if end.is_none_or(|end| end > 8 * d.len()) || s.first > d.len() {
        return Err(DecodeError::Truncated {
            meshlet: i,
            what: "wire table",
        });
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::meshlet::canonical;
    use crate::strategy::{by_name, Options};

    #[test]
    fn every_triangle_comes_back() {
        let mesh = generate::noisy_sphere(3, 0.2, 3);
        let ml = by_name("qem", &Options::default())
            .unwrap()
            .build(&mesh, crate::meshlet::Limits::new(64, 84).unwrap());
        let enc = encode(&mesh, &ml, super::super::paper_tolerance(&mesh)).unwrap();
        for i in 0..ml.len() {
            let d = decode(&enc, i).unwrap();
            let mut want: Vec<_> = ml.global_triangles(i).map(canonical).collect();
            let mut got: Vec<_> = d
                .triangles
                .iter()
                .map(|t| canonical(t.map(|c| d.vertices[c as usize])))
                .collect();
            want.sort_unstable();
            got.sort_unstable();
            assert_eq!(got, want, "meshlet {i}");
        }
        assert_eq!(enc.sizes.total(), enc.data.len() + 4 * ml.len());
    }
}
