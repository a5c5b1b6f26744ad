//! What `kmedoids-parallel`'s CPU reference, its GPU driver (`gpu::kmedoids_parallel`) and
//! `wgsl/kmedoids_parallel.wgsl` must agree on, defined once: the markers and bounds of the
//! growth, and the sections of the kernel's storage buffers. `build.rs` includes this file and
//! writes [`wgsl`]'s constants in front of the kernel, so a value changed here changes all three.
//!
//! A buffer of sections holds, for section `s` of length `len`, the words `s * len..(s + 1) *
//! len`; `t` is the mesh's triangle count.

/// How many pieces, in seed order from the first free one, a packing cluster weighs for its next
/// piece: pieces come in runs along the mesh (the order a generator or a scanner wrote them), so
/// the nearest is usually a few ahead, and the bound keeps a region of many pieces linear.
pub const PACK_WINDOW: u32 = 32;

/// Marks a pocket stamp whose free component is too large to absorb.
pub const BIG: u32 = 1 << 31;
/// Marks the pocket being tried by the front rule in `aux`, beside its stamp `c + 1`.
pub const TRYING: u32 = 1 << 30;
/// Marks the front rule's per-attempt stamps in `hop`, apart from hop counts.
pub const ATTEMPT: u32 = 1 << 31;

/// `tri`, per triangle, sections of `t`: the region, then the words of the CPU's `State` (the
/// label, the cluster that put it on its frontier, hops, aux, piece, seed-order position, free
/// neighbours while on the frontier). Once the growth is done, the merges and the piece packing
/// reuse the frontier-cluster, hop, aux, position and free-count sections for their lists.
pub const TRI_REGION: u32 = 0;
/// See [`TRI_REGION`].
pub const TRI_LABEL: u32 = 1;
/// See [`TRI_REGION`].
pub const TRI_INQ: u32 = 2;
/// See [`TRI_REGION`].
pub const TRI_HOP: u32 = 3;
/// See [`TRI_REGION`].
pub const TRI_AUX: u32 = 4;
/// See [`TRI_REGION`].
pub const TRI_PIECE: u32 = 5;
/// See [`TRI_REGION`].
pub const TRI_OPOS: u32 = 6;
/// See [`TRI_REGION`].
pub const TRI_FREE: u32 = 7;
/// Sections of `tri`.
pub const TRI_SECTIONS: u32 = 8;

/// `cstate`, per canonical corner, sections of `3t`: mark, first, wmark (the CPU's per-corner
/// `State` words). Once the growth is done, the medoid kernel's scratch.
pub const CORNER_MARK: u32 = 0;
/// See [`CORNER_MARK`].
pub const CORNER_FIRST: u32 = 1;
/// See [`CORNER_MARK`].
pub const CORNER_WMARK: u32 = 2;
/// Sections of `cstate`, each `3t` words.
pub const CORNER_SECTIONS: u32 = 3;

/// `canon`: the canonical corner of each of the `3t` corners, then from `CANON_CELLS * t` each
/// triangle's fine centroid cell in two words (`x | y << 16`, `z`).
pub const CANON_CELLS: u32 = 3;
/// Words of `canon` per triangle.
pub const CANON_WORDS: u32 = CANON_CELLS + 2;

/// `arena`, per region at its member offset, sections of `t`: seed order, frontier, pockets'
/// triangles, pockets, free triangles per piece, members by cluster, cluster starts, piece starts.
pub const ARENA_ORDER: u32 = 0;
/// See [`ARENA_ORDER`].
pub const ARENA_FRONT: u32 = 1;
/// See [`ARENA_ORDER`].
pub const ARENA_Q: u32 = 2;
/// See [`ARENA_ORDER`].
pub const ARENA_POCKETS: u32 = 3;
/// See [`ARENA_ORDER`].
pub const ARENA_LEFT: u32 = 4;
/// See [`ARENA_ORDER`].
pub const ARENA_SEQ: u32 = 5;
/// See [`ARENA_ORDER`].
pub const ARENA_CSTART: u32 = 6;
/// See [`ARENA_ORDER`].
pub const ARENA_PSTART: u32 = 7;
/// Sections of `t` words at the start of `arena`.
pub const ARENA_TRIANGLE_SECTIONS: u32 = 8;
/// After them, rows of `max_t` words, one per region in each of these sections: the growing
/// cluster's triangles, its vertex count after each, the pocket rule's histogram.
pub const ARENA_ROWS: u32 = 3;

/// Words of `arena` for `t` triangles in `regions` regions at `max_t` triangles per meshlet.
pub fn arena_words(t: usize, regions: usize, max_t: usize) -> usize {
    ARENA_TRIANGLE_SECTIONS as usize * t + ARENA_ROWS as usize * regions * max_t
}

/// Every constant above by name, in order: what [`wgsl`] writes.
pub const CONSTANTS: &[(&str, u32)] = &[
    ("PACK_WINDOW", PACK_WINDOW),
    ("BIG", BIG),
    ("TRYING", TRYING),
    ("ATTEMPT", ATTEMPT),
    ("TRI_REGION", TRI_REGION),
    ("TRI_LABEL", TRI_LABEL),
    ("TRI_INQ", TRI_INQ),
    ("TRI_HOP", TRI_HOP),
    ("TRI_AUX", TRI_AUX),
    ("TRI_PIECE", TRI_PIECE),
    ("TRI_OPOS", TRI_OPOS),
    ("TRI_FREE", TRI_FREE),
    ("TRI_SECTIONS", TRI_SECTIONS),
    ("CORNER_MARK", CORNER_MARK),
    ("CORNER_FIRST", CORNER_FIRST),
    ("CORNER_WMARK", CORNER_WMARK),
    ("CORNER_SECTIONS", CORNER_SECTIONS),
    ("CANON_CELLS", CANON_CELLS),
    ("CANON_WORDS", CANON_WORDS),
    ("ARENA_ORDER", ARENA_ORDER),
    ("ARENA_FRONT", ARENA_FRONT),
    ("ARENA_Q", ARENA_Q),
    ("ARENA_POCKETS", ARENA_POCKETS),
    ("ARENA_LEFT", ARENA_LEFT),
    ("ARENA_SEQ", ARENA_SEQ),
    ("ARENA_CSTART", ARENA_CSTART),
    ("ARENA_PSTART", ARENA_PSTART),
    ("ARENA_TRIANGLE_SECTIONS", ARENA_TRIANGLE_SECTIONS),
    ("ARENA_ROWS", ARENA_ROWS),
];

/// [`CONSTANTS`] as WGSL declarations, one per line (what `build.rs` writes in front of
/// `wgsl/kmedoids_parallel.wgsl`).
pub fn wgsl() -> String {
    let mut s =
        String::from("// Generated by build.rs from src/strategy/kmedoids/parallel/layout.rs.\n");
    for (name, value) in CONSTANTS {
        s.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    s
}
