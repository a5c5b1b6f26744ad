//! Laces (Mlakar et al. 2024, §3.3): a meshlet's triangles as one-byte symbols along the wire
//! edges of its local order (left and right laces: skips, one-reference triangles and our long
//! laces) plus strips for the triangles on no free wire edge; the symbol encoding is in the
//! module doc of [`super`]. Encoding here ([`laces`]) and decoding ([`triangles`]) side by side.

use crate::compress::DecodeError;

/// The left, right and strip subsequences of a meshlet's triangles (in local positions).
pub(super) fn laces(n: usize, ni: usize, tris: &[[u8; 3]]) -> (Vec<u8>, Vec<u8>, Vec<u8>) {
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

/// Meshlet `i`'s triangles from its symbols (`nl` left, `nr` right, then strip bytes) over `n`
/// local positions, `internal` of them on the internal wire.
pub(super) fn triangles(
    syms: &[u8],
    nl: usize,
    nr: usize,
    n: usize,
    internal: usize,
    i: usize,
) -> Result<Vec<[u8; 3]>, DecodeError> {
    let bad = |what: String| DecodeError::Invalid { meshlet: i, what };
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
    Ok(triangles)
}

/// Whether the boundary closes with a wire edge from its last position back to its first
/// (position `ni`, after the internal wire): it needs three boundary positions, or the closing
/// edge would be wire edge `ni` reversed.
pub(super) fn wraps(n: usize, ni: usize) -> bool {
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
