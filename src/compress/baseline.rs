//! The paper's comparison formats (Mlakar et al. 2024, §5.1), basic and compact, with real
//! encodings and decoders so their sizes are measured, not estimated:
//!
//! * **TS**, triangle soup: each meshlet holds its triangles' corner positions, no indices.
//! * **IX**, indexed meshlets: each meshlet holds references into one global vertex buffer and
//!   local triangle indices.
//! * **SC**, self-contained meshlets: each meshlet holds copies of its vertices (boundary vertices
//!   duplicated) and local triangle indices.
//! * **GI**, global index buffer: each meshlet is a range of one index buffer of global indices
//!   into one vertex buffer.
//!
//! *Basic* stores f32 positions (exact), 32-bit references and 8-bit local indices. *Compact*
//! quantises on the shared grid ([`super::grid_exponent`]): per-meshlet anchored boxes where the
//! positions live in the meshlet (TS, SC), G bits per axis in the global buffer (IX, GI); and
//! packs references in `ceil(log2 V)` bits and local indices in `ceil(log2 vertices)` bits.
//! Records are padded to 32-bit words, like laced wires.
//!
//! **Layout** (`data`): a 16-byte section header (kind, compact, G, reference bits as bytes;
//! global buffer offset, global vertex count, 4 reserved bytes), the meshlet records, then the
//! global vertex buffer (IX, GI). Record fields, in order, bit-packed LSB first in compact form:
//!
//! | format | record |
//! |---|---|
//! | TS | triangles - 1 (8); [compact: anchor 3 x G, bits per axis 3 x 5]; 3 positions per triangle |
//! | IX | vertices - 1 (8), triangles - 1 (8); [basic: 2 pad bytes]; references; 3 local indices per triangle |
//! | SC | vertices - 1 (8), triangles - 1 (8); [compact: anchor, bits per axis; basic: 2 pad bytes]; positions; local indices |
//! | GI | triangles - 1 (8); [basic: 3 pad bytes]; 3 global indices per triangle |
//!
//! TS and SC carry no vertex ids; like laced wires, provenance tables (not counted) map their
//! stored vertices to the source mesh for checking.

use super::bits::{bits_for, width, BitReader, BitWriter};
use super::{anchored_box, dequantise, quantise, DecodeError, Decoded, Encoded, Sizes};
use crate::mesh::Mesh;
use crate::meshlet::Meshlets;

const SECTION: usize = 16;

/// The four formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Triangle soup.
    Ts,
    /// Indexed meshlets.
    Ix,
    /// Self-contained meshlets.
    Sc,
    /// Global index buffer.
    Gi,
}

impl Kind {
    fn id(self) -> u8 {
        self as u8
    }
    fn of(id: u8) -> Option<Self> {
        [Kind::Ts, Kind::Ix, Kind::Sc, Kind::Gi]
            .into_iter()
            .find(|k| k.id() == id)
    }
}

/// Why a meshlet set cannot be encoded.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum BaselineEncodeError {
    /// A meshlet beyond 256 vertices or triangles, or an empty one.
    #[error("meshlet {0}: the formats take 1 to 256 vertices and triangles per meshlet")]
    Size(usize),
    /// Grid coordinates beyond 31 bits.
    #[error("grid coordinates exceed 31 bits (tolerance too small for this mesh's extent)")]
    GridTooFine,
    /// A tolerance that is not positive and finite, or whose grid rounds a position past the
    /// f32 range.
    #[error("the tolerance is not positive and finite, or its grid rounds a position past f32")]
    Tolerance,
}

/// A record's bit stream with its bits tallied by kind (connectivity, positions, headers).
struct Tallied {
    w: BitWriter,
    kind: [usize; 3],
}

impl Tallied {
    fn new() -> Self {
        Self {
            w: BitWriter::new(),
            kind: [0; 3],
        }
    }
    fn put(&mut self, k: usize, bits: u32, v: u32) {
        self.w.put(bits, v);
        self.kind[k] += bits as usize;
    }
    fn f32(&mut self, v: f32) {
        self.put(1, 32, v.to_bits());
    }
    /// Pads to a 32-bit word; returns the padding bits.
    fn pad(&mut self) -> usize {
        self.w.pad(32)
    }
}

const CONN: usize = 0;
const POS: usize = 1;
const HEAD: usize = 2;

/// Encodes `ml` in `kind` (compact or basic) at `tolerance` (compact only; basic is exact).
pub fn encode(
    mesh: &Mesh,
    ml: &Meshlets,
    tolerance: f64,
    kind: Kind,
    compact: bool,
) -> Result<Encoded, BaselineEncodeError> {
    // The basic formats store f32s exactly: any tolerance will do, clamped so that no exponent
    // arithmetic overflows (0 and NaN give i32's extremes).
    let e = match compact {
        true => super::checked_grid(mesh, tolerance).ok_or(BaselineEncodeError::Tolerance)?,
        false => super::grid_exponent(tolerance).clamp(-1100, 1100),
    };
    let origin = mesh.bounding_box().0.to_array();
    let nv = mesh.vertex_count();
    let grid = |v: u32| {
        let p = mesh.positions[v as usize];
        [0, 1, 2].map(|a| quantise(p[a], origin[a], e).max(0))
    };
    let g = if compact {
        let top = mesh.positions.iter().enumerate().fold(0i64, |m, (v, _)| {
            grid(v as u32).into_iter().fold(m, i64::max)
        });
        width(top as u64)
    } else {
        0
    };
    if g > 31 {
        return Err(BaselineEncodeError::GridTooFine);
    }
    let vbits = if compact { bits_for(nv) } else { 32 };
    let mut data = vec![0u8; SECTION];
    let mut offsets = Vec::with_capacity(ml.len());
    let mut tally = [0usize; 4];
    let mut boxes = 0usize;
    let mut wire_base = Vec::new();
    let mut stored_to_source = Vec::new();
    for i in 0..ml.len() {
        let lv = ml.meshlet_vertices(i);
        let lt = ml.meshlet_triangles(i);
        let (vc, tc) = (lv.len(), lt.len() / 3);
        if vc == 0 || tc == 0 || vc > 256 || tc > 256 {
            return Err(BaselineEncodeError::Size(i));
        }
        let mut b = Tallied::new();
        // Positions held by the meshlet (TS: every corner; SC: every vertex).
        let held: Vec<u32> = match kind {
            Kind::Ts => lt.iter().map(|&c| lv[c as usize]).collect(),
            Kind::Sc => lv.to_vec(),
            _ => Vec::new(),
        };
        if matches!(kind, Kind::Ts | Kind::Sc) {
            wire_base.push(stored_to_source.len() as u32);
            stored_to_source.extend_from_slice(&held);
        }
        if kind != Kind::Ts && kind != Kind::Gi {
            b.put(HEAD, 8, (vc - 1) as u32);
        }
        b.put(HEAD, 8, (tc - 1) as u32);
        let ibits = if compact { bits_for(vc) } else { 8 };
        match (kind, compact) {
            (Kind::Ts | Kind::Sc, true) => {
                let q: Vec<[i64; 3]> = held.iter().map(|&v| grid(v)).collect();
                let (lo, _, bits) = anchored_box(&q);
                for a in lo {
                    b.put(HEAD, g, a as u32);
                }
                for x in bits {
                    b.put(HEAD, 5, x);
                }
                boxes += 3 * (g + 5) as usize;
                for p in &q {
                    for a in 0..3 {
                        b.put(POS, bits[a], (p[a] - lo[a]) as u32);
                    }
                }
            }
            (Kind::Ts | Kind::Sc, false) => {
                tally[3] += b.pad();
                for &v in &held {
                    for x in mesh.positions[v as usize] {
                        b.f32(x);
                    }
                }
            }
            (Kind::Ix, _) => {
                if !compact {
                    tally[3] += b.pad();
                }
                for &v in lv {
                    b.put(CONN, vbits, v);
                }
            }
            (Kind::Gi, _) => {
                if !compact {
                    tally[3] += b.pad();
                }
                for &c in lt {
                    b.put(CONN, vbits, lv[c as usize]);
                }
            }
        }
        if matches!(kind, Kind::Ix | Kind::Sc) {
            for &c in lt {
                b.put(CONN, ibits, c as u32);
            }
        }
        tally[3] += b.pad();
        for (t, k) in tally.iter_mut().zip(b.kind) {
            *t += k;
        }
        offsets.push(data.len() as u32);
        data.extend_from_slice(b.w.bytes());
    }
    let global = data.len();
    if matches!(kind, Kind::Ix | Kind::Gi) {
        let mut b = Tallied::new();
        for v in 0..nv as u32 {
            if compact {
                for x in grid(v) {
                    b.put(POS, g, x as u32);
                }
            } else {
                for x in mesh.positions[v as usize] {
                    b.f32(x);
                }
            }
        }
        tally[3] += b.pad();
        tally[POS] += b.kind[POS];
        data.extend_from_slice(b.w.bytes());
    }
    data[0] = kind.id();
    data[1] = compact as u8;
    data[2] = g as u8;
    data[3] = vbits as u8;
    data[4..8].copy_from_slice(&(global as u32).to_le_bytes());
    data[8..12].copy_from_slice(&(nv as u32).to_le_bytes());
    let sizes = Sizes {
        connectivity: tally[CONN] / 8,
        positions: tally[POS] / 8,
        headers: tally[HEAD] / 8 + SECTION + 4 * ml.len(),
        geometry_headers: boxes / 8,
        culling: 0,
        padding: 0,
    };
    let sizes = Sizes {
        padding: data.len() + 4 * ml.len() - sizes.connectivity - sizes.positions - sizes.headers,
        ..sizes
    };
    Ok(Encoded {
        exponent: e,
        origin,
        source_vertices: nv as u32,
        offsets,
        data,
        sizes,
        wire_base,
        stored_to_source,
    })
}

/// Decodes meshlet `i`.
pub fn decode(enc: &Encoded, i: usize) -> Result<Decoded, DecodeError> {
    let start = *enc.offsets.get(i).ok_or(DecodeError::OutOfRange(i))? as usize;
    let d = &enc.data;
    let bad = |what: String| DecodeError::Invalid { meshlet: i, what };
    let h = d.get(..SECTION).ok_or(DecodeError::Truncated {
        meshlet: i,
        what: "section header",
    })?;
    let kind = Kind::of(h[0]).ok_or_else(|| bad(format!("unknown kind {}", h[0])))?;
    let compact = h[1] == 1;
    let (g, vbits) = (h[2] as u32, h[3] as u32);
    let global = u32::from_le_bytes(h[4..8].try_into().unwrap()) as usize;
    let nv = u32::from_le_bytes(h[8..12].try_into().unwrap()) as usize;
    if g > 31 || vbits > 32 || h[1] > 1 {
        return Err(bad("section header out of range".into()));
    }
    let mut r = BitReader::new(d, 8 * start, i, "record");
    let vc = if kind != Kind::Ts && kind != Kind::Gi {
        r.get(8)? as usize + 1
    } else {
        0
    };
    let tc = r.get(8)? as usize + 1;
    let ibits = if compact { bits_for(vc) } else { 8 };
    let mut vertices: Vec<u32> = Vec::new();
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut triangles: Vec<[u8; 3]> = Vec::new();
    let provenance = |k: usize| -> Result<u32, DecodeError> {
        enc.wire_base
            .get(i)
            .and_then(|&b| enc.stored_to_source.get(b as usize + k))
            .copied()
            .filter(|&v| v < enc.source_vertices)
            .ok_or_else(|| bad(format!("stored vertex {k} has no provenance")))
    };
    let held = match kind {
        Kind::Ts => 3 * tc,
        Kind::Sc => vc,
        _ => 0,
    };
    if held > 0 {
        if compact {
            let lo = [r.get(g)?, r.get(g)?, r.get(g)?];
            let bits = [r.get(5)?, r.get(5)?, r.get(5)?];
            if bits.iter().any(|&b| b > g.max(1)) {
                return Err(bad(format!("bits per axis {bits:?} above the grid's {g}")));
            }
            for _ in 0..held {
                let mut p = [0f32; 3];
                for a in 0..3 {
                    let x = lo[a] as i64 + r.get(bits[a])? as i64;
                    p[a] = dequantise(x, enc.origin[a], enc.exponent);
                }
                positions.push(p);
            }
        } else {
            r.align(32);
            for _ in 0..held {
                let mut p = [0f32; 3];
                for x in &mut p {
                    *x = f32::from_bits(r.get(32)?);
                }
                positions.push(p);
            }
        }
        for k in 0..held {
            vertices.push(provenance(k)?);
        }
    }
    let read_ref = |r: &mut BitReader| {
        let v = r.get(vbits)? as usize;
        if v >= nv || v >= enc.source_vertices as usize {
            return Err(bad(format!("reference {v} beyond {nv} vertices")));
        }
        Ok(v as u32)
    };
    match kind {
        Kind::Gi => {
            if !compact {
                r.align(32);
            }
            // Global indices, one per corner (merged into local vertices below).
            for _ in 0..3 * tc {
                vertices.push(read_ref(&mut r)?);
            }
        }
        Kind::Ts => {}
        Kind::Ix => {
            if !compact {
                r.align(32);
            }
            for _ in 0..vc {
                vertices.push(read_ref(&mut r)?);
            }
        }
        Kind::Sc => {}
    }
    if matches!(kind, Kind::Ix | Kind::Sc) {
        for _ in 0..tc {
            let mut t = [0u8; 3];
            for c in &mut t {
                let x = r.get(ibits)? as usize;
                if x >= vc {
                    return Err(bad(format!("local index {x} beyond {vc} vertices")));
                }
                *c = x as u8;
            }
            triangles.push(t);
        }
    }
    if matches!(kind, Kind::Ix | Kind::Gi) {
        // Positions from the global buffer.
        let per = if compact { 3 * g as usize } else { 96 };
        for &v in &vertices {
            let mut p = [0f32; 3];
            let base = 8 * global + v as usize * per;
            for (a, x) in p.iter_mut().enumerate() {
                let b = if compact { g } else { 32 };
                let raw = BitReader::new(d, base + a * b as usize, i, "vertex buffer").get(b)?;
                *x = if compact {
                    dequantise(raw as i64, enc.origin[a], enc.exponent)
                } else {
                    f32::from_bits(raw)
                };
            }
            positions.push(p);
        }
    }
    if matches!(kind, Kind::Ts | Kind::Gi) {
        // Corners to local vertices: one per distinct source vertex.
        let mut ids = vertices.clone();
        ids.sort_unstable();
        ids.dedup();
        if ids.len() > 256 {
            return Err(bad(format!(
                "{} distinct vertices in one meshlet",
                ids.len()
            )));
        }
        let mut local: Vec<Option<[f32; 3]>> = vec![None; ids.len()];
        for t in 0..tc {
            let mut tri = [0u8; 3];
            for (k, c) in tri.iter_mut().enumerate() {
                let j = ids.binary_search(&vertices[3 * t + k]).unwrap_or(0);
                let p = positions[3 * t + k];
                // TS stores a vertex once per corner: copies that disagree are damage (one
                // decoded position per vertex could not say what a renderer draws).
                if local[j].is_some_and(|q| q.map(f32::to_bits) != p.map(f32::to_bits)) {
                    return Err(bad(format!("copies of vertex {} disagree", ids[j])));
                }
                local[j] = Some(p);
                *c = j as u8;
            }
            triangles.push(tri);
        }
        return Ok(Decoded {
            vertices: ids,
            triangles,
            positions: local.into_iter().map(|p| p.unwrap_or_default()).collect(),
        });
    }
    Ok(Decoded {
        vertices,
        triangles,
        positions,
    })
}
