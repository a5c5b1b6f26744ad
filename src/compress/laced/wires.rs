//! Topology and wires (Mlakar et al. 2024, §3.2): who owns each vertex (one meshlet's internal
//! wire, two meshlets' external wire, or the corner wire), each meshlet's boundary walk and
//! greedy-spiral internal wire, and each wire's self-contained bit string (anchored box, offsets
//! or zigzag differences), written and read through the wire header of [`super::layout`].

use super::layout::{AXIS_WIDTH_BITS, WIRE_COUNT, WIRE_DELTA};
use super::{Section, MAX_VERTICES, SHORT_WIRE};
use crate::compress::bits::{width, BitReader, BitWriter};
use crate::compress::{anchored_box, dequantise, DecodeError, Encoded};
use crate::meshlet::Meshlets;

/// Owner of a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Owner {
    Unused,
    Internal(u32),
    Wire(u32),
    Corner(u32),
}

/// A boundary item of a meshlet: external wire (id, backwards) or corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Item {
    Wire(u32, bool),
    Corner(u32),
}

/// Per-meshlet topology the first pass finds: its boundary walk and internal wire.
pub(super) struct Shape {
    pub(super) items: Vec<Item>,
    pub(super) internal: Vec<u32>,
    /// For external wires this meshlet runs (it has the smaller index): their vertices in walk order.
    runs: Vec<(u32, Vec<u32>)>,
}

/// Who owns each vertex; the external wires' meshlet pairs (sorted); the corners (sorted).
pub(super) fn owners(
    vertex_count: usize,
    ml: &Meshlets,
) -> (Vec<Owner>, Vec<(u32, u32)>, Vec<u32>) {
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
pub(super) fn shape(ml: &Meshlets, i: usize, owner: &[Owner], pairs: &[(u32, u32)]) -> Shape {
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
pub(super) fn external_wires(
    owner: &[Owner],
    pairs: &[(u32, u32)],
    shapes: &[Shape],
) -> Vec<Vec<u32>> {
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

/// Wire `w`'s bit string and its bits by kind.
pub(super) fn wire_string(
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
    let delta_head = 3 * AXIS_WIDTH_BITS as usize;
    let delta = counted && n > 1 && delta_head + sum(b) + (n - 1) * sum(db) < n * sum(b);
    let mut out = BitWriter::new();
    // The corner wire's count is in the section header; every other wire holds at most 64 and
    // says whether it is delta-coded.
    if counted {
        out.put(WIRE_COUNT.bits, n as u32);
        out.put(WIRE_DELTA.bits, delta as u32);
    }
    for x in lo {
        out.put(g, x as u32);
    }
    for x in b {
        out.put(AXIS_WIDTH_BITS, x);
    }
    if delta {
        for x in db {
            out.put(AXIS_WIDTH_BITS, x);
        }
    }
    let head = out.at();
    for (k, p) in q.iter().enumerate() {
        for a in 0..3 {
            if delta && k > 0 {
                out.put(db[a], zig(p[a] - q[k - 1][a]) as u32);
            } else {
                out.put(b[a], (p[a] - lo[a]) as u32);
            }
        }
    }
    let at = out.at();
    let padding = out.pad(32);
    (out.into_bytes(), [0, at - head, head, padding])
}

/// A wire's header as the decoder reads it.
pub(super) struct Wire {
    pub(super) count: usize,
    lo: [u32; 3],
    bits: [u32; 3],
    start: usize,
    /// Delta-coded wires: every grid point, decoded when the wire is read.
    points: Option<Vec<[i64; 3]>>,
}

/// Reads wire `w`'s header (and a delta-coded wire's points) for meshlet `i`.
pub(super) fn wire(enc: &Encoded, s: &Section, w: usize, i: usize) -> Result<Wire, DecodeError> {
    let d = &enc.data;
    let entry = BitReader::new(d, 8 * s.table + w * s.table_bits as usize, i, "wire table")
        .get(s.table_bits)? as usize;
    let start = s.first + 4 * entry;
    let mut r = BitReader::new(d, 8 * start, i, "wire");
    let (count, delta) = if w == s.m + s.e {
        (s.c, false)
    } else {
        (
            r.get(WIRE_COUNT.bits)? as usize,
            r.get(WIRE_DELTA.bits)? == 1,
        )
    };
    let lo = [r.get(s.g)?, r.get(s.g)?, r.get(s.g)?];
    let ab = AXIS_WIDTH_BITS;
    let bits = [r.get(ab)?, r.get(ab)?, r.get(ab)?];
    let db = if delta {
        [r.get(ab)?, r.get(ab)?, r.get(ab)?]
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
            .is_none_or(|b| r.at() + b > 8 * d.len())
    {
        return Err(DecodeError::Truncated {
            meshlet: i,
            what: "wire vertices",
        });
    }
    let start = r.at();
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
    /// Decoded position of the wire's vertex `k`.
    pub(super) fn position(&self, enc: &Encoded, k: usize) -> [f32; 3] {
        if let Some(p) = &self.points {
            return [0, 1, 2].map(|a| dequantise(p[k][a], enc.origin[a], enc.exponent));
        }
        let per = (self.bits[0] + self.bits[1] + self.bits[2]) as usize;
        let mut r = BitReader::new(&enc.data, self.start + k * per, 0, "wire");
        [0, 1, 2].map(|a| {
            // In range: checked when the wire was read.
            let d = r.get(self.bits[a]).unwrap_or(0);
            dequantise(self.lo[a] as i64 + d as i64, enc.origin[a], enc.exponent)
        })
    }
}
