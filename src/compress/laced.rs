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

use super::{
    anchored_box, bits_for, dequantise, quantise, read_bits, width, write_bits, DecodeError,
    Decoded, Encoded, Sizes,
};
use crate::mesh::Mesh;
use crate::meshlet::Meshlets;
use rayon::prelude::*;

/// Most vertices a meshlet may have (6-bit references).
pub const MAX_VERTICES: usize = 64;
const SECTION: usize = 24;
/// Bytes of a meshlet's culling record.
pub const CULL: usize = 8;
/// External wires of at most this many vertices are stored as corners instead: a wire's box
/// (about 9 bytes), its table entry and its padding cost more than one or two vertices at full
/// grid width on the corner wire. Measured when introduced (before long laces, culling records
/// and delta wires) at the paper's tolerance on qem 64/84 meshlets, bytes per triangle for
/// 0/1/2/3/4: bunny 4.41/4.36/4.34/4.37/4.43, igea 4.33/4.29/4.27/4.33/4.42, fandisk
/// 4.24/4.19/4.18/4.20/4.27; re-checked after long laces at 1e-4 on meshopt 64/126 meshlets for
/// 1/2/3: bunny 3.489/3.494/3.507, dragon 3.326/3.322/3.354, igea 3.238/3.242/3.265 (1 and 2 tie).
pub const SHORT_WIRE: usize = 2;
const HEAD_BITS: usize = 7 + 7 + 8 + 8 + 10;

/// Why a meshlet set cannot be encoded as laced wires.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum EncodeError {
    /// A meshlet above 64 vertices (or an empty one).
    #[error("meshlet {0}: laced wires take 1 to 64 vertices per meshlet (6-bit references)")]
    Size(usize),
    /// More strip bytes than the header's 10 bits count.
    #[error("meshlet {0}: over 1023 strip bytes (too many triangles off the wires)")]
    Strips(usize),
    /// The mesh's extent on the grid needs more than 31 bits.
    #[error("grid coordinates exceed 31 bits (tolerance too small for this mesh's extent)")]
    GridTooFine,
}

/// Owner of a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Owner {
    Unused,
    Internal(u32),
    Wire(u32),
    Corner(u32),
}

/// A boundary item of a meshlet: external wire (id, backwards) or corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Item {
    Wire(u32, bool),
    Corner(u32),
}

/// Per-meshlet topology the first pass finds: its boundary walk and internal wire.
struct Shape {
    items: Vec<Item>,
    internal: Vec<u32>,
    /// For external wires this meshlet runs (it has the smaller index): their vertices in walk order.
    runs: Vec<(u32, Vec<u32>)>,
}

/// Encodes `ml` (meshlets of `mesh`, at most 64 vertices each) at `tolerance`.
pub fn encode(mesh: &Mesh, ml: &Meshlets, tolerance: f64) -> Result<Encoded, EncodeError> {
    let m = ml.len();
    for i in 0..m {
        let n = ml.meshlet_vertices(i).len();
        if n == 0 || n > MAX_VERTICES || ml.meshlet_triangles(i).is_empty() {
            return Err(EncodeError::Size(i));
        }
    }
    let (owner, pairs, corners) = owners(mesh.vertex_count(), ml);
    let shapes: Vec<Shape> = (0..m)
        .into_par_iter()
        .map(|i| shape(ml, i, &owner, &pairs))
        .collect();
    let wires = external_wires(&owner, &pairs, &shapes);
    let e = super::grid_exponent(tolerance);
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
        return Err(EncodeError::GridTooFine);
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
    let mut data = vec![0u8; SECTION];
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
    let table_len = (wire_count * table_bits as usize).div_ceil(32) * 4;
    data.resize(table + table_len, 0);
    let mut packed = Vec::new();
    for (k, &x) in words.iter().enumerate() {
        write_bits(&mut packed, k * table_bits as usize, table_bits, x);
    }
    data[table..table + packed.len()].copy_from_slice(&packed);
    let first = data.len();
    let mut wire_head = wire_count * table_bits as usize;
    for (s, b) in &strings {
        data.extend_from_slice(s);
        for k in 0..4 {
            bits[k] += b[k];
        }
        wire_head += b[2];
    }
    let mut head = Vec::with_capacity(SECTION);
    for x in [m, wires.len(), corners.len()] {
        head.extend((x as u32).to_le_bytes());
    }
    head.extend([
        g as u8,
        table_bits as u8,
        wire_bits as u8,
        corner_bits as u8,
    ]);
    head.extend((table as u32).to_le_bytes());
    head.extend((first as u32).to_le_bytes());
    data[..SECTION].copy_from_slice(&head);

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

/// Who owns each vertex; the external wires' meshlet pairs (sorted); the corners (sorted).
fn owners(vertex_count: usize, ml: &Meshlets) -> (Vec<Owner>, Vec<(u32, u32)>, Vec<u32>) {
    // Meshlets are visited in order, so the first two users are the two smallest.
    let mut users = vec![0u8; vertex_count];
    let mut first = vec![[u32::MAX; 2]; vertex_count];
    for i in 0..ml.len() {
        for &v in ml.meshlet_vertices(i) {
            let u = &mut users[v as usize];
            if (*u as usize) < 2 {
                first[v as usize][*u as usize] = i as u32;
            }
            *u = u.saturating_add(1);
        }
    }
    let mut all: Vec<(u32, u32)> = (0..vertex_count)
        .filter(|&v| users[v] == 2)
        .map(|v| (first[v][0], first[v][1]))
        .collect();
    all.sort_unstable();
    let pairs: Vec<(u32, u32)> = all
        .chunk_by(|a, b| a == b)
        .filter(|run| run.len() > SHORT_WIRE)
        .map(|run| run[0])
        .collect();
    let mut corners = Vec::new();
    let owner = (0..vertex_count)
        .map(
            |v| match (users[v], pairs.binary_search(&(first[v][0], first[v][1]))) {
                (0, _) => Owner::Unused,
                (1, _) => Owner::Internal(first[v][0]),
                (2, Ok(j)) => Owner::Wire(j as u32),
                _ => {
                    corners.push(v as u32);
                    Owner::Corner(corners.len() as u32 - 1)
                }
            },
        )
        .collect();
    (owner, pairs, corners)
}

/// Local adjacency of meshlet `i` as bitmasks: directed edges and undirected neighbours.
fn local_edges(ml: &Meshlets, i: usize) -> (Vec<u64>, Vec<u64>) {
    let n = ml.meshlet_vertices(i).len();
    let mut dir = vec![0u64; n];
    for t in ml.meshlet_triangles(i).chunks_exact(3) {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if a != b {
                dir[a] |= 1 << b;
            }
        }
    }
    let mut adj = dir.clone();
    for (a, &d) in dir.iter().enumerate() {
        let mut d = d;
        while d != 0 {
            let b = d.trailing_zeros() as usize;
            d &= d - 1;
            adj[b] |= 1 << a;
        }
    }
    (dir, adj)
}

/// Boundary walk, items and internal wire of meshlet `i`.
fn shape(ml: &Meshlets, i: usize, owner: &[Owner], pairs: &[(u32, u32)]) -> Shape {
    let lv = ml.meshlet_vertices(i);
    let n = lv.len();
    let (dir, adj) = local_edges(ml, i);
    // Boundary edges a -> b: no b -> a in the meshlet. Follow the lowest one out of each vertex.
    let bnext: Vec<Option<usize>> = (0..n)
        .map(|a| {
            let mut d = dir[a];
            while d != 0 {
                let b = d.trailing_zeros() as usize;
                d &= d - 1;
                if dir[b] >> a & 1 == 0 {
                    return Some(b);
                }
            }
            None
        })
        .collect();
    let own = |k: usize| owner[lv[k] as usize];
    let mut walk = Vec::new();
    let mut seen = 0u64;
    for s in 0..n {
        if seen >> s & 1 == 1 || bnext[s].is_none() {
            continue;
        }
        let mut cycle = Vec::new();
        let mut a = s;
        while seen >> a & 1 == 0 {
            seen |= 1 << a;
            cycle.push(a);
            match bnext[a] {
                Some(b) => a = b,
                None => break,
            }
        }
        // Start where the owner changes, so no wire is split by the loop's seam.
        let len = cycle.len();
        let cut = (0..len)
            .find(|&k| own(cycle[k]) != own(cycle[(k + len - 1) % len]))
            .unwrap_or(0);
        cycle.rotate_left(cut);
        walk.extend(cycle);
    }
    // Items in walk order, then any the walk missed (in local order).
    let mut items = Vec::new();
    let mut runs: Vec<(u32, Vec<u32>)> = Vec::new();
    let rest: Vec<usize> = (0..n).filter(|&k| seen >> k & 1 == 0).collect();
    for &k in walk.iter().chain(&rest) {
        let item = match own(k) {
            Owner::Wire(j) => {
                let mine = pairs[j as usize].0 == i as u32;
                if mine {
                    match runs.iter_mut().find(|r| r.0 == j) {
                        Some(r) => r.1.push(lv[k]),
                        None => runs.push((j, vec![lv[k]])),
                    }
                }
                Item::Wire(j, !mine)
            }
            Owner::Corner(c) => Item::Corner(c),
            _ => continue,
        };
        // Each local vertex comes once; a wire's other vertices name the same item.
        if !items.contains(&item) {
            items.push(item);
        }
    }
    // Internal wire: levels by edge distance to the boundary.
    let inner: u64 = (0..n)
        .filter(|&k| matches!(own(k), Owner::Internal(_)))
        .fold(0, |m, k| m | 1 << k);
    let mut level = [u8::MAX; MAX_VERTICES];
    let mut frontier: u64 = (seen | !inner) & mask(n);
    let mut reached = frontier;
    let mut l = 0u8;
    while frontier != 0 {
        let mut f = frontier;
        let mut next = 0;
        while f != 0 {
            let k = f.trailing_zeros() as usize;
            f &= f - 1;
            level[k] = l;
            next |= adj[k];
        }
        frontier = next & !reached & mask(n);
        reached |= frontier;
        l = l.saturating_add(1);
    }
    let mut path = Vec::with_capacity(inner.count_ones() as usize);
    let mut path_local: Vec<usize> = Vec::with_capacity(path.capacity());
    let mut left = inner;
    let mut tip: Option<usize> = None;
    let mut prev: Option<usize> = None;
    while left != 0 {
        let mut cands = tip.map_or(0, |t| adj[t] & left);
        if cands == 0 {
            // Stuck: restart next to the most recent path vertex that has unvisited neighbours,
            // so the jump stays short and the new run laces against the old one.
            if let Some(&q) = path_local.iter().rev().find(|&&q| adj[q] & left != 0) {
                cands = adj[q] & left;
                tip = Some(q);
            }
        }
        let pool = if cands != 0 { cands } else { left };
        let mut best = usize::MAX;
        let mut key = (u8::MAX, true, usize::MAX);
        let mut p = pool;
        while p != 0 {
            let k = p.trailing_zeros() as usize;
            p &= p - 1;
            let closes = cands != 0 && prev.is_some_and(|q| adj[q] >> k & 1 == 1);
            let kk = (level[k], !closes, k);
            if kk < key {
                key = kk;
                best = k;
            }
        }
        if cands == 0 {
            prev = None;
        } else {
            prev = tip;
        }
        tip = Some(best);
        left &= !(1 << best);
        path.push(lv[best]);
        path_local.push(best);
    }
    Shape {
        items,
        internal: path,
        runs,
    }
}

fn mask(n: usize) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1 << n) - 1
    }
}

/// Each external wire's vertices: in its smaller meshlet's walk order, then any it missed.
fn external_wires(owner: &[Owner], pairs: &[(u32, u32)], shapes: &[Shape]) -> Vec<Vec<u32>> {
    let mut wires: Vec<Vec<u32>> = vec![Vec::new(); pairs.len()];
    for s in shapes {
        for (j, r) in &s.runs {
            wires[*j as usize] = r.clone();
        }
    }
    let mut missed: Vec<Vec<u32>> = vec![Vec::new(); pairs.len()];
    for (v, o) in owner.iter().enumerate() {
        if let Owner::Wire(j) = *o {
            missed[j as usize].push(v as u32);
        }
    }
    for (w, all) in wires.iter_mut().zip(missed) {
        if w.len() != all.len() {
            let mut have = w.clone();
            have.sort_unstable();
            w.extend(all.into_iter().filter(|v| have.binary_search(v).is_err()));
        }
    }
    wires
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
) -> Result<(Vec<u8>, [usize; 4]), EncodeError> {
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
    let (left, right, strips) = laces(n, s.internal.len(), &tris);
    if strips.len() > 1023 {
        return Err(EncodeError::Strips(i));
    }
    let mut out = Vec::new();
    let mut at = 0;
    let mut put = |out: &mut Vec<u8>, b: u32, v: u32| {
        write_bits(out, at, b, v);
        at += b as usize;
    };
    put(&mut out, 7, s.internal.len() as u32);
    put(&mut out, 7, s.items.len() as u32);
    put(&mut out, 8, left.len() as u32);
    put(&mut out, 8, right.len() as u32);
    put(&mut out, 10, strips.len() as u32);
    // Kind bits of every item first, then the ids: item `j` then starts at a bit offset a
    // popcount of the kind bits gives, so a shader reads every item at once.
    for it in &s.items {
        put(&mut out, 1, matches!(it, Item::Corner(_)) as u32);
    }
    for it in &s.items {
        match *it {
            Item::Wire(j, back) => {
                put(&mut out, wire_bits, j);
                put(&mut out, 1, back as u32);
            }
            Item::Corner(c) => put(&mut out, corner_bits, c),
        }
    }
    let item_bits = at - HEAD_BITS;
    let aligned = at.div_ceil(8) * 8;
    out.resize(aligned / 8, 0);
    out.extend(left.iter().chain(&right).chain(&strips));
    let symbols = 8 * (left.len() + right.len() + strips.len());
    let pad = (4 - out.len() % 4) % 4;
    out.resize(out.len() + pad, 0);
    let padding = aligned - at + 8 * pad;
    Ok((out, [item_bits + symbols, 0, HEAD_BITS, padding]))
}

/// The left, right and strip subsequences of a meshlet's triangles (in local positions).
fn laces(n: usize, ni: usize, tris: &[[u8; 3]]) -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let wrap = wraps(n, ni);
    let slots = n.saturating_sub(1) + wrap as usize;
    let mut left: Vec<Option<u8>> = vec![None; slots];
    let mut right: Vec<Option<u8>> = vec![None; slots];
    // Candidate slots of a triangle: (side, slot, third vertex).
    let cands = |t: &[u8; 3]| {
        let mut c = Vec::with_capacity(3);
        for k in 0..3 {
            let (x, y, z) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let (x_, y_) = (x as usize, y as usize);
            if y_ == x_ + 1 || wrap && x_ == n - 1 && y_ == ni {
                c.push((0, x_, z));
            } else if x_ == y_ + 1 || wrap && y_ == n - 1 && x_ == ni {
                c.push((1, y_, z));
            }
        }
        c
    };
    let mut placed = vec![false; tris.len()];
    // Triangles with one candidate first, so those with a choice do not take their slot.
    for pass in 0..2 {
        for (ti, t) in tris.iter().enumerate() {
            if placed[ti] {
                continue;
            }
            let c = cands(t);
            if pass == 0 && c.len() != 1 {
                continue;
            }
            for (side, slot, z) in c {
                let s = if side == 0 { &mut left } else { &mut right };
                if s[slot].is_none() {
                    s[slot] = Some(z);
                    placed[ti] = true;
                    break;
                }
            }
        }
    }
    // Long laces: a triangle left of k -> k + 2 (or right of it) where the wire bends round a
    // vertex, one per position and side.
    // Then k -> k + 3 (type 3), where it bends round two.
    let mut long = [0, 1].map(|_| [vec![None; slots], vec![None; slots]]);
    for (reach, l) in [2usize, 3].into_iter().zip(&mut long) {
        for (ti, t) in tris.iter().enumerate() {
            if placed[ti] {
                continue;
            }
            for k in 0..3 {
                let (x, y, z) = (t[k] as usize, t[(k + 1) % 3] as usize, t[(k + 2) % 3]);
                let (side, at) = if y == x + reach {
                    (0, x)
                } else if x == y + reach {
                    (1, y)
                } else {
                    continue;
                };
                if l[side][at].is_none() {
                    l[side][at] = Some(z);
                    placed[ti] = true;
                    break;
                }
            }
        }
    }
    let [[l2l, l2r], [l3l, l3r]] = long;
    let lace = |s: &[Option<u8>], long2: &[Option<u8>], long3: &[Option<u8>]| {
        let mut out = Vec::new();
        let mut run = 0usize;
        let flush = |out: &mut Vec<u8>, run: &mut usize| {
            while *run > 0 {
                let r = (*run).min(64);
                out.push((r - 1) as u8);
                *run -= r;
            }
        };
        for (k, x) in s.iter().enumerate() {
            for (ty, l) in [(0x80, long2), (0xC0, long3)] {
                if let Some(v) = l[k] {
                    flush(&mut out, &mut run);
                    out.push(ty | v);
                }
            }
            match x {
                None => run += 1,
                Some(v) => {
                    flush(&mut out, &mut run);
                    out.push(0x40 | v);
                }
            }
        }
        out
    };
    let rest: Vec<[u8; 3]> = tris
        .iter()
        .zip(&placed)
        .filter(|(_, &p)| !p)
        .map(|(t, _)| *t)
        .collect();
    (
        lace(&left, &l2l, &l3l),
        lace(&right, &l2r, &l3r),
        strips(&rest),
    )
}

/// Whether the boundary closes with a wire edge from its last position back to its first
/// (position `ni`, after the internal wire): it needs three boundary positions, or the closing
/// edge would be wire edge `ni` reversed.
fn wraps(n: usize, ni: usize) -> bool {
    n >= ni + 3
}

/// Strips of the triangles on no wire edge: `11 a, b, c` starts one, `tt v` continues across
/// edge `tt` of the previous triangle.
fn strips(rest: &[[u8; 3]]) -> Vec<u8> {
    let mut used = vec![false; rest.len()];
    let mut out = Vec::new();
    for s in 0..rest.len() {
        if used[s] {
            continue;
        }
        used[s] = true;
        let mut p = rest[s];
        out.extend([0xC0 | p[0], p[1], p[2]]);
        'grow: loop {
            for e in 0..3u8 {
                let (x, y) = (p[e as usize], p[(e as usize + 1) % 3]);
                // A neighbour holding y -> x, rotated to (y, x, v).
                let found = (0..rest.len()).find_map(|u| {
                    if used[u] {
                        return None;
                    }
                    let t = rest[u];
                    (0..3).find_map(|k| {
                        (t[k] == y && t[(k + 1) % 3] == x).then_some((u, t[(k + 2) % 3]))
                    })
                });
                if let Some((u, v)) = found {
                    used[u] = true;
                    out.push(e << 6 | v);
                    p = [y, x, v];
                    continue 'grow;
                }
            }
            break;
        }
    }
    out
}

/// Wire `w`'s bit string and its bits by kind.
fn wire_string(
    w: &[u32],
    grid: &(impl Fn(u32) -> [i64; 3] + Sync),
    g: u32,
    counted: bool,
) -> (Vec<u8>, [usize; 4]) {
    let q: Vec<[i64; 3]> = w.iter().map(|&v| grid(v)).collect();
    let (lo, _, b) = anchored_box(&q);
    // Delta mode: consecutive wire vertices are mostly neighbours, so their zigzag differences
    // need fewer bits than offsets across the whole box (not for the corner wire, which is read
    // at random).
    let zig = |d: i64| ((d << 1) ^ (d >> 63)) as u64;
    let db = [0, 1, 2].map(|a| {
        q.windows(2)
            .map(|p| width(zig(p[1][a] - p[0][a])))
            .max()
            .unwrap_or(0)
    });
    let sum = |x: [u32; 3]| (x[0] + x[1] + x[2]) as usize;
    let n = q.len();
    let delta = counted && n > 1 && 15 + sum(b) + (n - 1) * sum(db) < n * sum(b);
    let mut out = Vec::new();
    let mut at = 0;
    let put = |out: &mut Vec<u8>, at: &mut usize, bits: u32, v: u32| {
        write_bits(out, *at, bits, v);
        *at += bits as usize;
    };
    // The corner wire's count is in the section header; every other wire holds at most 64 and
    // says whether it is delta-coded.
    if counted {
        put(&mut out, &mut at, 7, n as u32);
        put(&mut out, &mut at, 1, delta as u32);
    }
    for x in lo {
        put(&mut out, &mut at, g, x as u32);
    }
    for x in b {
        put(&mut out, &mut at, 5, x);
    }
    if delta {
        for x in db {
            put(&mut out, &mut at, 5, x);
        }
    }
    let head = at;
    for (k, p) in q.iter().enumerate() {
        for a in 0..3 {
            if delta && k > 0 {
                put(&mut out, &mut at, db[a], zig(p[a] - q[k - 1][a]) as u32);
            } else {
                put(&mut out, &mut at, b[a], (p[a] - lo[a]) as u32);
            }
        }
    }
    out.resize(at.div_ceil(32) * 4, 0);
    let padding = out.len() * 8 - at;
    (out, [0, at - head, head, padding])
}

/// A meshlet's culling data as its 8 culling bytes decode: a bounding sphere of its decoded
/// positions and a normal cone of its decoded triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Culling {
    /// Sphere centre.
    pub center: [f32; 3],
    /// Sphere radius.
    pub radius: f32,
    /// Unit cone axis.
    pub axis: [f32; 3],
    /// Sine of the cone's half-angle; 1 = never culls.
    pub cutoff: f32,
}

impl Culling {
    /// The task shader's backface test without an apex (meshoptimizer's sphere-centre variant,
    /// as [`crate::meshlet::descriptor::QuantisedBounds::backfacing`]): cull when
    /// `dot(c - eye, axis) > cutoff |c - eye| + r`.
    pub fn backfacing(&self, camera: [f32; 3]) -> bool {
        crate::meshlet::descriptor::sphere_cone_backfacing(
            glam::Vec3::from_array(self.center),
            self.radius,
            glam::Vec3::from_array(self.axis),
            self.cutoff,
            camera,
        )
    }
}

/// Bits of the culling record's centre per axis.
const CENTER_BITS: u32 = 10;
/// Radius codes per octave (the radius is rounded up to the next of them).
const RADIUS_STEPS: f64 = 8.0;

/// Centre grid shift and the radius scale for grid width `g` at exponent `e`.
fn cull_scale(g: u32, e: i32) -> (u32, f64) {
    let shift = g.saturating_sub(CENTER_BITS);
    // The largest radius code is twice the grid's extent: no sphere of the mesh is larger.
    (shift, ((e + g as i32 + 1) as f64).exp2())
}

/// Meshlet `i`'s culling record, from the positions the decoder returns, so the bounds hold for
/// what is drawn: 10-bit centre per axis on the coarsened grid, an 8-bit radius code (eighths of
/// an octave below twice the grid extent, rounded up), the octahedral axis (2 x 8 bits) and the
/// sine of the half-angle measured around the decoded axis (8 bits, rounded up; 255 = never).
fn culling_record(
    ml: &Meshlets,
    i: usize,
    grid: &(impl Fn(u32) -> [i64; 3] + Sync),
    origin: [f32; 3],
    e: i32,
    g: u32,
) -> u64 {
    let lv = ml.meshlet_vertices(i);
    let pos = |v: u32| {
        let q = grid(v);
        glam::DVec3::from_array([0, 1, 2].map(|a| dequantise(q[a], origin[a], e) as f64))
    };
    let (shift, top) = cull_scale(g, e);
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for &v in lv {
        let q = grid(v);
        for a in 0..3 {
            lo[a] = lo[a].min(q[a]);
            hi[a] = hi[a].max(q[a]);
        }
    }
    let cc = [0, 1, 2].map(|a| {
        (((lo[a] + hi[a]) as f64 / 2.0 / (shift as f64).exp2()).round() as i64)
            .clamp(0, (1 << CENTER_BITS) - 1)
    });
    let c =
        glam::DVec3::from_array([0, 1, 2].map(|a| dequantise(cc[a] << shift, origin[a], e) as f64));
    let r = lv
        .iter()
        .map(|&v| (pos(v) - c).length())
        .fold(0.0, f64::max);
    // Round up, with room for the f32 decode of the radius.
    let k = if r > 0.0 {
        ((r * (1.0 + 1e-5) / top).log2() * RADIUS_STEPS + 255.0)
            .ceil()
            .clamp(0.0, 255.0) as u64
    } else {
        0
    };
    // Normal cone of the decoded triangles (degenerate ones face nowhere and are skipped).
    let normals: Vec<glam::DVec3> = ml
        .global_triangles(i)
        .filter_map(|t| {
            let [a, b, c] = t.map(pos);
            (b - a).cross(c - a).try_normalize()
        })
        .collect();
    // Axis: the centre of the smallest sphere around the normals' tips (as the meshlet bounds
    // do), which gives the narrowest cone; the mean normal was measured to widen it (dragon,
    // meshopt 64/126: mean cutoff 0.65 against 0.42, and 40 % fewer meshlets culled).
    let centre = crate::meshlet::bounds::min_sphere(&normals).0;
    let never = (0u64, 0u64, 255u64);
    let (ox, oy, cut) = match centre.try_normalize() {
        None => never,
        Some(axis) => {
            let (_, qx, qy) = crate::meshlet::descriptor::octahedral_code(axis);
            let decoded = crate::meshlet::descriptor::decode_octahedral(qx, qy);
            let theta = normals
                .iter()
                .map(|n| n.dot(decoded).clamp(-1.0, 1.0).acos())
                .fold(0.0, f64::max)
                + crate::meshlet::descriptor::AXIS_MARGIN;
            if theta >= std::f64::consts::FRAC_PI_2 {
                never
            } else {
                (
                    qx as u8 as u64,
                    qy as u8 as u64,
                    (theta.sin() * 255.0).ceil().min(255.0) as u64,
                )
            }
        }
    };
    cc[0] as u64
        | (cc[1] as u64) << 10
        | (cc[2] as u64) << 20
        | k << 30
        | ox << 38
        | oy << 46
        | cut << 54
}

/// Decodes meshlet `i`'s culling record (without touching its triangles or wires).
pub fn culling(enc: &Encoded, i: usize) -> Result<Culling, DecodeError> {
    if i >= enc.offsets.len() {
        return Err(DecodeError::OutOfRange(i));
    }
    let s = section(enc, i)?;
    let at = SECTION + CULL * i;
    let b = enc.data.get(at..at + CULL).ok_or(DecodeError::Truncated {
        meshlet: i,
        what: "culling record",
    })?;
    let x = u64::from_le_bytes(b.try_into().expect("8 bytes"));
    let (shift, top) = cull_scale(s.g, enc.exponent);
    let center = [0, 10, 20].map(|b| (x >> b & 1023) as i64);
    let center = [0, 1, 2].map(|a| dequantise(center[a] << shift, enc.origin[a], enc.exponent));
    let k = (x >> 30 & 255) as f64;
    let radius = if k == 0.0 {
        0.0
    } else {
        (top * ((k - 255.0) / RADIUS_STEPS).exp2()) as f32
    };
    let cut = x >> 54 & 255;
    let axis =
        crate::meshlet::descriptor::decode_octahedral((x >> 38) as u8 as i8, (x >> 46) as u8 as i8);
    Ok(Culling {
        center,
        radius,
        axis: [axis.x as f32, axis.y as f32, axis.z as f32],
        cutoff: cut as f32 / 255.0,
    })
}

/// A wire's header as the decoder reads it.
struct Wire {
    count: usize,
    lo: [u32; 3],
    bits: [u32; 3],
    start: usize,
    /// Delta-coded wires: every grid point, decoded when the wire is read.
    points: Option<Vec<[i64; 3]>>,
}

/// Reads the section header fields the decoder needs.
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

fn section(enc: &Encoded, i: usize) -> Result<Section, DecodeError> {
    let d = &enc.data;
    let h = d.get(..SECTION).ok_or(DecodeError::Truncated {
        meshlet: i,
        what: "section header",
    })?;
    let u = |k: usize| u32::from_le_bytes(h[k..k + 4].try_into().unwrap()) as usize;
    let s = Section {
        m: u(0),
        e: u(4),
        c: u(8),
        g: h[12] as u32,
        table_bits: h[13] as u32,
        wire_bits: h[14] as u32,
        corner_bits: h[15] as u32,
        table: u(16),
        first: u(20),
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

fn wire(enc: &Encoded, s: &Section, w: usize, i: usize) -> Result<Wire, DecodeError> {
    let d = &enc.data;
    let entry = read_bits(d, 8 * s.table + w * s.table_bits as usize, s.table_bits).ok_or(
        DecodeError::Truncated {
            meshlet: i,
            what: "wire table",
        },
    )? as usize;
    let start = s.first + 4 * entry;
    let mut r = super::BitReader {
        data: d,
        at: 8 * start,
        meshlet: i,
        what: "wire",
    };
    let (count, delta) = if w == s.m + s.e {
        (s.c, false)
    } else {
        (r.get(7)? as usize, r.get(1)? == 1)
    };
    let lo = [r.get(s.g)?, r.get(s.g)?, r.get(s.g)?];
    let bits = [r.get(5)?, r.get(5)?, r.get(5)?];
    let db = if delta {
        [r.get(5)?, r.get(5)?, r.get(5)?]
    } else {
        [0; 3]
    };
    if bits.iter().any(|&b| b > s.g.max(1)) || db.iter().any(|&b| b > 32) {
        return Err(DecodeError::Invalid {
            meshlet: i,
            what: format!(
                "wire {w}: bits per axis {bits:?}/{db:?} above the grid's {}",
                s.g
            ),
        });
    }
    let per = (bits[0] + bits[1] + bits[2]) as usize;
    if !delta
        && count
            .checked_mul(per)
            .is_none_or(|b| r.at + b > 8 * d.len())
    {
        return Err(DecodeError::Truncated {
            meshlet: i,
            what: "wire vertices",
        });
    }
    let start = r.at;
    let points = if delta {
        let mut pts: Vec<[i64; 3]> = Vec::with_capacity(count);
        for k in 0..count {
            let mut p = [0i64; 3];
            for a in 0..3 {
                p[a] = if k == 0 {
                    lo[a] as i64 + r.get(bits[a])? as i64
                } else {
                    let z = r.get(db[a])? as i64;
                    pts[k - 1][a] + ((z >> 1) ^ -(z & 1))
                };
            }
            pts.push(p);
        }
        Some(pts)
    } else {
        None
    };
    Ok(Wire {
        count,
        lo,
        bits,
        start,
        points,
    })
}

impl Wire {
    fn position(&self, enc: &Encoded, k: usize) -> [f32; 3] {
        if let Some(p) = &self.points {
            return [0, 1, 2].map(|a| dequantise(p[k][a], enc.origin[a], enc.exponent));
        }
        let per = (self.bits[0] + self.bits[1] + self.bits[2]) as usize;
        let mut at = self.start + k * per;
        [0, 1, 2].map(|a| {
            // In range: checked when the wire was read.
            let d = read_bits(&enc.data, at, self.bits[a]).unwrap_or(0);
            at += self.bits[a] as usize;
            dequantise(self.lo[a] as i64 + d as i64, enc.origin[a], enc.exponent)
        })
    }
}

/// Decodes meshlet `i` from the buffer alone (vertex ids through the provenance tables).
pub fn decode(enc: &Encoded, i: usize) -> Result<Decoded, DecodeError> {
    let start = *enc.offsets.get(i).ok_or(DecodeError::OutOfRange(i))? as usize;
    let s = section(enc, i)?;
    let bad = |what: String| DecodeError::Invalid { meshlet: i, what };
    let d = &enc.data;
    let mut at = 8 * start;
    let mut get = |b: u32| -> Result<u32, DecodeError> {
        let v = read_bits(d, at, b).ok_or(DecodeError::Truncated {
            meshlet: i,
            what: "record",
        })?;
        at += b as usize;
        Ok(v)
    };
    let internal = get(7)? as usize;
    let items = get(7)? as usize;
    let nl = get(8)? as usize;
    let nr = get(8)? as usize;
    let ns = get(10)? as usize;
    // Local order as (wire, index in wire).
    let mut order: Vec<(usize, usize)> = (0..internal).map(|k| (i, k)).collect();
    let mut kinds = Vec::with_capacity(items);
    for _ in 0..items {
        kinds.push(get(1)?);
    }
    for kind in kinds {
        if kind == 0 {
            let j = get(s.wire_bits)? as usize;
            let back = get(1)? == 1;
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
            let c = get(s.corner_bits)? as usize;
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
    let sym0 = at.div_ceil(8);
    let syms = d
        .get(sym0..sym0 + nl + nr + ns)
        .ok_or(DecodeError::Truncated {
            meshlet: i,
            what: "symbols",
        })?;
    let mut triangles: Vec<[u8; 3]> = Vec::new();
    let vert = |v: u8| -> Result<u8, DecodeError> {
        if (v as usize) < n {
            Ok(v)
        } else {
            Err(bad(format!("reference {v} beyond {n} vertices")))
        }
    };
    for (side, lace) in [(0, &syms[..nl]), (1, &syms[nl..nl + nr])] {
        let mut k = 0usize;
        for &b in lace {
            let v = b & 63;
            match b >> 6 {
                0 => k += v as usize + 1,
                1 => {
                    let wrap = wraps(n, internal) && k == n - 1;
                    if k + 1 >= n && !wrap {
                        return Err(bad(format!("lace at wire edge {k} of {n} vertices")));
                    }
                    let v = vert(v)?;
                    let (x, y) = if wrap {
                        (k as u8, internal as u8)
                    } else {
                        (k as u8, k as u8 + 1)
                    };
                    triangles.push(if side == 0 { [x, y, v] } else { [y, x, v] });
                    k += 1;
                }
                t => {
                    // Long laces: k -> k + 2 (type 2) or k + 3 (type 3); the cursor stays.
                    let reach = t as usize;
                    if k + reach >= n {
                        return Err(bad(format!("long lace at {k} of {n} vertices")));
                    }
                    let v = vert(v)?;
                    let (x, y) = (k as u8, (k + reach) as u8);
                    triangles.push(if side == 0 { [x, y, v] } else { [y, x, v] });
                }
            }
        }
    }
    let strip = &syms[nl + nr..];
    let mut p: Option<[u8; 3]> = None;
    let mut k = 0;
    while k < strip.len() {
        let b = strip[k];
        let t = b >> 6;
        if t == 3 {
            let rest = strip.get(k + 1..k + 3).ok_or(DecodeError::Truncated {
                meshlet: i,
                what: "strip start",
            })?;
            if rest.iter().any(|&r| r >> 6 != 0) {
                return Err(bad("strip start with high bits set".into()));
            }
            let tri = [vert(b & 63)?, vert(rest[0])?, vert(rest[1])?];
            triangles.push(tri);
            p = Some(tri);
            k += 3;
        } else {
            let q = p.ok_or_else(|| bad("strip continues before it starts".into()))?;
            let e = t as usize;
            let tri = [q[(e + 1) % 3], q[e], vert(b & 63)?];
            triangles.push(tri);
            p = Some(tri);
            k += 1;
        }
    }
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
