//! Laced wires' bit layout in one place (Mlakar et al. 2024, §3.4 and §4.1 for the record and the
//! culling data; our fields as the module doc of [`super`] describes them): the section header,
//! the per-meshlet record header, the wire header and the culling record, each a table of fields
//! in stream order. The encoder writes these tables, the CPU decoder reads them, and build.rs
//! includes this file (`#[path]`) to write the same numbers as GLSL constants
//! (`laced_layout.glsl`, see [`glsl`]) for the task and mesh shaders, so the three cannot drift.
//!
//! Self-contained on purpose (plain consts and `std` only, no `crate::` paths): build.rs compiles
//! it on its own.

use std::fmt::Write as _;

/// A bit field of a record: `bits` bits at bit offset `at` from the record's first bit (bit
/// order as `compress::bits`: least significant first).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// Name of the GLSL constants (`LACED_<name>_AT`, `LACED_<name>_BITS`).
    #[allow(dead_code)] // Read by `glsl`, which only build.rs and the tests call.
    pub name: &'static str,
    /// Bit offset from the record's start.
    pub at: u32,
    /// Width in bits.
    pub bits: u32,
}

impl Field {
    /// The first field of a record.
    const fn first(name: &'static str, bits: u32) -> Self {
        Field { name, at: 0, bits }
    }

    /// The field right after this one.
    const fn then(self, name: &'static str, bits: u32) -> Self {
        Field {
            name,
            at: self.end(),
            bits,
        }
    }

    /// The bit after the field.
    pub const fn end(self) -> u32 {
        self.at + self.bits
    }

    /// The largest value the field holds.
    pub const fn max(self) -> u64 {
        (1u64 << self.bits) - 1
    }

    /// `v` (which fits) moved to the field's place in a 64-bit record.
    pub const fn place(self, v: u64) -> u64 {
        v << self.at
    }

    /// The field's value in a 64-bit record.
    pub const fn get(self, record: u64) -> u64 {
        record >> self.at & self.max()
    }
}

/// Whether `fields` follow one another without gaps, from bit 0.
const fn contiguous(fields: &[Field]) -> bool {
    let mut at = 0;
    let mut k = 0;
    while k < fields.len() {
        if fields[k].at != at {
            return false;
        }
        at = fields[k].end();
        k += 1;
    }
    true
}

// Section header: the start of `data`, integers little-endian (so LSB-first bit fields).

/// Meshlets M.
pub const MESHLETS: Field = Field::first("MESHLETS", 32);
/// External wires E.
pub const WIRES: Field = MESHLETS.then("WIRES", 32);
/// Corners C.
pub const CORNERS: Field = WIRES.then("CORNERS", 32);
/// G: bits of a global grid coordinate.
pub const GRID: Field = CORNERS.then("GRID", 8);
/// Bits of a wire table entry.
pub const TABLE_WIDTH: Field = GRID.then("TABLE_WIDTH", 8);
/// Bits of an external-wire id in a record.
pub const WIRE_ID_WIDTH: Field = TABLE_WIDTH.then("WIRE_ID_WIDTH", 8);
/// Bits of a corner id in a record.
pub const CORNER_ID_WIDTH: Field = WIRE_ID_WIDTH.then("CORNER_ID_WIDTH", 8);
/// Byte offset of the wire table.
pub const TABLE: Field = CORNER_ID_WIDTH.then("TABLE", 32);
/// Byte offset of the first wire.
pub const FIRST_WIRE: Field = TABLE.then("FIRST_WIRE", 32);
/// The section header in order.
pub const SECTION_HEADER: [Field; 9] = [
    MESHLETS,
    WIRES,
    CORNERS,
    GRID,
    TABLE_WIDTH,
    WIRE_ID_WIDTH,
    CORNER_ID_WIDTH,
    TABLE,
    FIRST_WIRE,
];
/// Bytes of the section header.
pub const SECTION: usize = FIRST_WIRE.end() as usize / 8;

/// Byte offset of the culling records (one per meshlet, right after the section header); the
/// meshlet records, the wire table and the wires follow them.
pub const CULLING_AT: usize = SECTION;

// Meshlet record header, then one kind bit per item, then per item the wire id and a direction
// bit or the corner id, then (byte-aligned) the left, right and strip symbols.

/// Vertices on the meshlet's internal wire.
pub const INTERNAL: Field = Field::first("INTERNAL", 7);
/// Boundary items (external wires and corners).
pub const ITEMS: Field = INTERNAL.then("ITEMS", 7);
/// Left lace symbols.
pub const LEFT: Field = ITEMS.then("LEFT", 8);
/// Right lace symbols.
pub const RIGHT: Field = LEFT.then("RIGHT", 8);
/// Strip bytes.
pub const STRIPS: Field = RIGHT.then("STRIPS", 10);
/// The record header in order.
pub const RECORD: [Field; 5] = [INTERNAL, ITEMS, LEFT, RIGHT, STRIPS];
/// Bits of the record header: the items' kind bits start here.
pub const RECORD_BITS: u32 = STRIPS.end();
/// Bits of an item's kind (0 = external wire, 1 = corner).
pub const KIND_BITS: u32 = 1;
/// Bits of an external wire's direction after its id (1 = backwards).
pub const DIRECTION_BITS: u32 = 1;

// Wire header: count and delta mode (except on the corner wire), the anchor (3 x G bits), bits
// per axis, in delta mode difference bits per axis, then the vertices.

/// Vertices on the wire.
pub const WIRE_COUNT: Field = Field::first("WIRE_COUNT", 7);
/// Delta mode.
pub const WIRE_DELTA: Field = WIRE_COUNT.then("WIRE_DELTA", 1);
/// The wire header before the anchor.
pub const WIRE: [Field; 2] = [WIRE_COUNT, WIRE_DELTA];
/// Bits of the wire header before the anchor (none on the corner wire).
pub const WIRE_BITS: u32 = WIRE_DELTA.end();
/// Bits of one axis's offset or difference width.
pub const AXIS_WIDTH_BITS: u32 = 5;

// Culling record: one little-endian u64 per meshlet.

/// Centre on the coarsened grid, x.
pub const CENTRE_X: Field = Field::first("CENTRE_X", 10);
/// Centre, y.
pub const CENTRE_Y: Field = CENTRE_X.then("CENTRE_Y", 10);
/// Centre, z.
pub const CENTRE_Z: Field = CENTRE_Y.then("CENTRE_Z", 10);
/// Radius code (`RADIUS_STEPS` per octave below twice the grid's extent; 0 = a point).
pub const RADIUS: Field = CENTRE_Z.then("RADIUS", 8);
/// Octahedral axis, x (i8).
pub const AXIS_X: Field = RADIUS.then("AXIS_X", 8);
/// Octahedral axis, y (i8).
pub const AXIS_Y: Field = AXIS_X.then("AXIS_Y", 8);
/// Sine of the cone's half-angle in 255ths (255 = never culls).
pub const CUTOFF: Field = AXIS_Y.then("CUTOFF", 8);
/// The culling record in order.
pub const CULLING: [Field; 7] = [CENTRE_X, CENTRE_Y, CENTRE_Z, RADIUS, AXIS_X, AXIS_Y, CUTOFF];
/// Bits of the culling record's centre per axis.
pub const CENTER_BITS: u32 = CENTRE_X.bits;
/// Radius codes per octave (the radius is rounded up to the next of them).
pub const RADIUS_STEPS: f64 = 8.0;
/// Bytes of a meshlet's culling record.
pub const CULL: usize = 8;

const _: () = {
    assert!(contiguous(&SECTION_HEADER) && FIRST_WIRE.end().is_multiple_of(32));
    assert!(contiguous(&RECORD) && contiguous(&WIRE) && contiguous(&CULLING));
    assert!(CUTOFF.end() as usize <= 8 * CULL && CENTRE_Y.bits == CENTER_BITS);
    assert!(CENTRE_Z.bits == CENTER_BITS && CULLING_AT.is_multiple_of(4));
};

/// The layout as GLSL constants (`laced_layout.glsl`, written by build.rs): `LACED_<field>_AT`
/// and `LACED_<field>_BITS` for every field, and the derived sizes.
#[allow(dead_code)] // Called by build.rs and the tests only.
pub fn glsl() -> String {
    let mut s = String::from(
        "// Generated by build.rs from src/compress/laced/layout.rs: laced wires' bit layout.\n\
         // Do not edit; change layout.rs (the encoder and the CPU decoder read the same table).\n",
    );
    for (what, fields) in [
        (
            "Section header (bit offsets from data's start)",
            &SECTION_HEADER[..],
        ),
        (
            "Meshlet record header (bit offsets from the record)",
            &RECORD[..],
        ),
        ("Wire header (bit offsets from the wire)", &WIRE[..]),
        ("Culling record (bit offsets in its 64 bits)", &CULLING[..]),
    ] {
        writeln!(s, "// {what}.").unwrap();
        for f in fields {
            writeln!(s, "const uint LACED_{}_AT = {}u;", f.name, f.at).unwrap();
            writeln!(s, "const uint LACED_{}_BITS = {}u;", f.name, f.bits).unwrap();
        }
    }
    s.push_str("// Sizes.\n");
    for (name, v) in [
        ("SECTION_BYTES", SECTION),
        ("CULLING_AT", CULLING_AT),
        ("CULL_BYTES", CULL),
        ("RECORD_BITS", RECORD_BITS as usize),
        ("KIND_BITS", KIND_BITS as usize),
        ("DIRECTION_BITS", DIRECTION_BITS as usize),
        ("WIRE_BITS", WIRE_BITS as usize),
        ("AXIS_WIDTH_BITS", AXIS_WIDTH_BITS as usize),
        ("CENTER_BITS", CENTER_BITS as usize),
    ] {
        writeln!(s, "const uint LACED_{name} = {v}u;").unwrap();
    }
    writeln!(s, "const float LACED_RADIUS_STEPS = {RADIUS_STEPS:?};").unwrap();
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_is_the_documented_one() {
        assert_eq!(SECTION, 24);
        assert_eq!(
            RECORD.map(|f| (f.at, f.bits)),
            [(0, 7), (7, 7), (14, 8), (22, 8), (30, 10)]
        );
        assert_eq!(RECORD_BITS, 40);
        assert_eq!(WIRE_BITS, 8);
        assert_eq!(
            CULLING.map(|f| f.at),
            [0, 10, 20, 30, 38, 46, 54],
            "culling record offsets"
        );
        assert_eq!(GRID.at / 8, 12);
        assert_eq!(TABLE.at / 8, 16);
    }

    #[test]
    fn the_glsl_header_names_every_field() {
        let s = glsl();
        assert!(s.contains("const uint LACED_STRIPS_AT = 30u;\n"));
        assert!(s.contains("const uint LACED_RADIUS_BITS = 8u;\n"));
        assert!(s.contains("const uint LACED_GRID_AT = 96u;\n"));
        assert!(s.contains("const float LACED_RADIUS_STEPS = 8.0;\n"));
        let n = SECTION_HEADER.len() + RECORD.len() + WIRE.len() + CULLING.len();
        assert_eq!(s.matches("_AT = ").count(), n + 1);
    }
}
