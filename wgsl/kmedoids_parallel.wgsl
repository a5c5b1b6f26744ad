// kmedoids-parallel on the device, mirroring src/strategy/kmedoids/parallel/ step by step
// (driver: src/gpu/kmedoids_parallel.rs), one section per CPU file:
//   init      mod.rs canonical_corners, and region.rs State's words set to their start values
//             (per triangle)
//   grow      grow.rs grow_region, calling the sections below: pockets.rs (absorb for
//             absorb_pockets, shed_front), pack.rs (nearest_piece for Packing::nearest, then
//             pack_pieces), merge.rs (merge_neighbours) and dissolve.rs (dissolve_clusters): one
//             invocation per region (one per workgroup, or eight per workgroup in grow_rows),
//             the same sequential steps over the same integer keys (regions share no word, so
//             they run at once)
//   relabel   step 3: cluster c of region r becomes base[r] + c (per triangle)
//   medoid    medoids_and_distances: the paper's medoid of one cluster (least_sum_128's reach
//             sets, or a BFS per member for wider clusters) and its members' hop distances (one
//             invocation per cluster; the steps are in medoid.wgsl, shared with kmedoids_parallel_moves.wgsl)
// The CPU keeps a region's state in local arrays (region.rs); here the same words live in global arrays
// indexed by triangle id or canonical corner (the region's own), and its lists at its member
// offset (`RS`) in `arena`.

struct Params { t: u32, regions: u32, max_v: u32, max_t: u32, k: u32, pad: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> idx_a: array<u32>;
@group(0) @binding(2) var<storage, read> idx_b: array<u32>;
@group(0) @binding(3) var<storage, read> vt_off: array<u32>;
@group(0) @binding(4) var<storage, read> vt_a: array<u32>;
@group(0) @binding(5) var<storage, read> vt_b: array<u32>;
@group(0) @binding(6) var<storage, read> dual_off: array<u32>;
@group(0) @binding(7) var<storage, read> dual_a: array<u32>;
@group(0) @binding(8) var<storage, read> dual_b: array<u32>;
// [0, R] member offsets of the regions; [R + 1, 2R + 1) clusters per region; [2R + 1, 3R + 2)
// bases (the host writes them from the counts); [3R + 2, 3R + 2 + k) medoids.
@group(0) @binding(9) var<storage, read_write> info: array<u32>;
// Members of each region, ascending.
@group(0) @binding(10) var<storage, read> items: array<u32>;
// Per triangle, TRI_SECTIONS sections of T (parallel::layout): region, lc cluster, frontier
// cluster, hops, aux, piece, position in the seed order, free neighbours while on the frontier.
@group(0) @binding(11) var<storage, read_write> tri: array<u32>;
// [0, 3T) per corner: the canonical corner; from CANON_CELLS * T per triangle: its fine centroid
// cell, two words (x | y << 16, z), from morton.wgsl (morton::packed_centres).
@group(0) @binding(12) var<storage, read_write> canon: array<u32>;
// Per canonical corner, CORNER_SECTIONS sections of 3T: mark, first, wmark. Once `grow` is done, the
// medoid kernel's scratch (9 words per member at 9x the cluster's member offset).
@group(0) @binding(13) var<storage, read_write> cstate: array<u32>;
// Per region at its member offset, ARENA_TRIANGLE_SECTIONS sections of T: order, front, pockets'
// triangles, pockets, pieces left, members by cluster (seq), cluster starts, piece starts; then
// ARENA_ROWS rows of `max_t` words per region: grown, vertex counts, histogram.
@group(0) @binding(14) var<storage, read_write> arena: array<u32>;
@group(0) @binding(15) var<storage, read_write> labels: array<u32>;
@group(0) @binding(16) var<storage, read_write> dist: array<u32>;

fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }
fn vtn(i: u32) -> u32 { if (i < PART) { return vt_a[i]; } return vt_b[i - PART]; }
fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }

// tri sections (parallel::layout's TRI_*).
fn tw(section: u32, x: u32) -> u32 { return section * p.t + x; }
fn region(x: u32) -> u32 { return tri[tw(TRI_REGION, x)]; }
fn lab(x: u32) -> u32 { return tri[tw(TRI_LABEL, x)]; }
fn set_lab(x: u32, v: u32) { tri[tw(TRI_LABEL, x)] = v; }
fn inq(x: u32) -> u32 { return tri[tw(TRI_INQ, x)]; }
fn set_inq(x: u32, v: u32) { tri[tw(TRI_INQ, x)] = v; }
fn hop(x: u32) -> u32 { return tri[tw(TRI_HOP, x)]; }
fn aux(x: u32) -> u32 { return tri[tw(TRI_AUX, x)]; }
fn set_aux(x: u32, v: u32) { tri[tw(TRI_AUX, x)] = v; }
fn piece(x: u32) -> u32 { return tri[tw(TRI_PIECE, x)]; }
fn set_piece(x: u32, v: u32) { tri[tw(TRI_PIECE, x)] = v; }
// Position in the region's seed order.
fn opos(x: u32) -> u32 { return tri[tw(TRI_OPOS, x)]; }
fn free_of(x: u32) -> u32 { return tri[tw(TRI_FREE, x)]; }
fn set_free(x: u32, v: u32) { tri[tw(TRI_FREE, x)] = v; }

// cstate sections (CORNER_*, each 3T).
fn cw(section: u32, k: u32) -> u32 { return section * 3u * p.t + k; }
fn mark(k: u32) -> u32 { return cstate[cw(CORNER_MARK, k)]; }
fn first_pos(k: u32) -> u32 { return cstate[cw(CORNER_FIRST, k)]; }
fn wmark(k: u32) -> u32 { return cstate[cw(CORNER_WMARK, k)]; }

// arena sections (ARENA_*; per-region offsets added by the callers).
fn s_order() -> u32 { return ARENA_ORDER * p.t; }
fn s_front() -> u32 { return ARENA_FRONT * p.t; }
fn s_q() -> u32 { return ARENA_Q * p.t; }
fn s_pockets() -> u32 { return ARENA_POCKETS * p.t; }
fn s_left() -> u32 { return ARENA_LEFT * p.t; }
fn s_seq() -> u32 { return ARENA_SEQ * p.t; }
fn s_cstart() -> u32 { return ARENA_CSTART * p.t; }
fn s_pstart() -> u32 { return ARENA_PSTART * p.t; }
fn s_rows(row: u32, r: u32) -> u32 {
    return ARENA_TRIANGLE_SECTIONS * p.t + (row * p.regions + r) * p.max_t;
}
fn s_grown(r: u32) -> u32 { return s_rows(0u, r); }
fn s_vcount(r: u32) -> u32 { return s_rows(1u, r); }
fn s_hist(r: u32) -> u32 { return s_rows(2u, r); }

// ---- init ------------------------------------------------------------------------------------

@compute @workgroup_size(64)
fn init(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    let r = region(t);
    for (var j = 0u; j < 3u; j++) {
        let v = idx(3u * t + j);
        // The row ascends: its first triangle in the region is the least (t itself, at worst).
        var u = NONE;
        for (var e = vt_off[v]; e < vt_off[v + 1u]; e++) {
            let x = vtn(e);
            if (region(x) == r) { u = x; break; }
        }
        var i = 0u;
        if (idx(3u * u) != v) { i = 1u; if (idx(3u * u + 1u) != v) { i = 2u; } }
        canon[3u * t + j] = 3u * u + i;
        cstate[cw(CORNER_MARK, 3u * t + j)] = NONE;
        cstate[cw(CORNER_FIRST, 3u * t + j)] = 0u;
        cstate[cw(CORNER_WMARK, 3u * t + j)] = 0u;
    }
    set_lab(t, NONE);
    set_inq(t, NONE);
    tri[tw(TRI_HOP, t)] = 0u;
    set_aux(t, 0u);
    set_piece(t, NONE);
    set_free(t, 0u);
}

// ---- grow's state and keys (region.rs: Region, State; grow.rs: the growth key) ---------------

// The region and cluster the invocation works on, and the region's triangle count.
var<private> N: u32;
var<private> R: u32;
var<private> RS: u32;
var<private> C: u32;
// Set in a piece's free count when the piece is part of a mesh piece cut by the region's border.
const CUT: u32 = 0x80000000u;
// Pocket evaluations so far (the wmark stamp).
var<private> SERIAL: u32;

fn in_region(x: u32) -> bool { return region(x) == R; }

// Distinct corners of `x` whose vertex the current cluster does not use yet.
fn added(x: u32) -> u32 {
    let k0 = canon[3u * x];
    let k1 = canon[3u * x + 1u];
    let k2 = canon[3u * x + 2u];
    var a = 0u;
    if (mark(k0) != C) { a += 1u; }
    if (mark(k1) != C && k1 != k0) { a += 1u; }
    if (mark(k2) != C && k2 != k0 && k2 != k1) { a += 1u; }
    return a;
}

fn free_neighbours(x: u32) -> u32 {
    var f = 0u;
    for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
        let y = nb(e);
        if (in_region(y) && lab(y) == NONE) { f += 1u; }
    }
    return f;
}

fn centre(x: u32) -> vec3<u32> {
    return unpack_cell(canon[CANON_CELLS * p.t + 2u * x], canon[CANON_CELLS * p.t + 2u * x + 1u]);
}

// Strict order of the growth key (added vertices, free neighbours, squared distance to the
// centre, hops, triangle id).
fn key_less(a: vec4<u32>, ah: u32, b: vec4<u32>, bh: u32) -> bool {
    if (a.x != b.x) { return a.x < b.x; }
    if (a.y != b.y) { return a.y < b.y; }
    if (a.z != b.z) { return a.z < b.z; }
    if (ah != bh) { return ah < bh; }
    return a.w < b.w;
}

// ---- pockets (pockets.rs: absorb_pockets, shed_front) -------------------------------------

// absorb_pockets for the cluster in `grown` (length `len`), keeping the pieces' free counts;
// returns its new length and the earliest seed-order position it freed, or NONE when nothing
// changed.
fn absorb(len: u32) -> vec2<u32> {
    let cap = p.max_t / 2u;
    let stamp = C + 1u;
    let G = s_grown(R);
    let Q = s_q() + RS;
    let P = s_pockets() + RS;
    var qlen = 0u;
    var npk = 0u;
    for (var gi = 0u; gi < len; gi++) {
        let g = arena[G + gi];
        for (var e = dual_off[g]; e < dual_off[g + 1u]; e++) {
            let f = nb(e);
            if (!in_region(f) || lab(f) != NONE || aux(f) == stamp || aux(f) == (stamp | BIG)) {
                continue;
            }
            let start = qlen;
            set_aux(f, stamp);
            arena[Q + qlen] = f;
            qlen += 1u;
            var head = start;
            var big = false;
            while (head < qlen && !big) {
                let u = arena[Q + head];
                head += 1u;
                for (var e2 = dual_off[u]; e2 < dual_off[u + 1u]; e2++) {
                    let y = nb(e2);
                    if (!in_region(y) || lab(y) != NONE) { continue; }
                    if (aux(y) == (stamp | BIG)) {
                        big = true;
                    } else if (aux(y) != stamp) {
                        set_aux(y, stamp);
                        arena[Q + qlen] = y;
                        qlen += 1u;
                    }
                }
                big = big || qlen - start > cap;
            }
            if (big) {
                for (var i = start; i < qlen; i++) { set_aux(arena[Q + i], stamp | BIG); }
                qlen = start;
            } else {
                arena[P + npk] = (start << 8u) | (qlen - start);
                npk += 1u;
            }
        }
    }
    if (npk == 0u) { return vec2<u32>(NONE, NONE); }
    // The front is empty of use here: it holds the taken pockets.
    let TK = s_front() + RS;
    let VC = s_vcount(R);
    let H = s_hist(R);
    var ntaken = 0u;
    var taken_size = 0u;
    // The latest of the taken pockets' earliest touches: a prefix must reach every pocket.
    var taken_touch = 0u;
    var keep = len;
    // Largest first, ties in discovery order.
    for (var sz = cap; sz >= 1u; sz--) {
        for (var pk = 0u; pk < npk; pk++) {
            let pw = arena[P + pk];
            if ((pw & 255u) != sz) { continue; }
            let size = taken_size + sz;
            var tp = NONE;
            for (var i = pw >> 8u; i < (pw >> 8u) + sz; i++) {
                let x = arena[Q + i];
                for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
                    let j = nb(e);
                    if (in_region(j) && lab(j) == C) { tp = min(tp, aux(j)); }
                }
            }
            let touch = max(taken_touch, tp);
            SERIAL += 1u;
            for (var h = 0u; h < len; h++) { arena[H + h] = 0u; }
            var outside = 0u;
            for (var ti = 0u; ti <= ntaken; ti++) {
                var w = pw;
                if (ti < ntaken) { w = arena[P + arena[TK + ti]]; }
                for (var i = w >> 8u; i < (w >> 8u) + (w & 255u); i++) {
                    let x = arena[Q + i];
                    for (var j = 0u; j < 3u; j++) {
                        let k = canon[3u * x + j];
                        if (wmark(k) != SERIAL) {
                            cstate[cw(CORNER_WMARK, k)] = SERIAL;
                            if (mark(k) == C) {
                                arena[H + first_pos(k)] += 1u;
                            } else {
                                outside += 1u;
                            }
                        }
                    }
                }
            }
            var m = len;
            var extra = outside;
            while (2u * m >= len && m > touch) {
                let verts = arena[VC + m - 1u] + extra;
                if (m + size <= p.max_t && verts <= p.max_v) {
                    arena[TK + ntaken] = pk;
                    ntaken += 1u;
                    taken_size = size;
                    taken_touch = touch;
                    keep = m;
                    break;
                }
                m -= 1u;
                extra += arena[H + m];
            }
        }
    }
    let L = s_left() + RS;
    var earliest = NONE;
    for (var gi = keep; gi < len; gi++) {
        let x = arena[G + gi];
        set_lab(x, NONE);
        set_aux(x, 0u);
        arena[L + piece(x)] += 1u;
        earliest = min(earliest, opos(x));
    }
    var glen = keep;
    for (var ti = 0u; ti < ntaken; ti++) {
        let w = arena[P + arena[TK + ti]];
        for (var i = w >> 8u; i < (w >> 8u) + (w & 255u); i++) {
            let x = arena[Q + i];
            set_lab(x, C);
            arena[L + piece(x)] -= 1u;
            arena[G + glen] = x;
            glen += 1u;
        }
    }
    // The front rule for each pocket left, in the same order (largest first).
    var changed = ntaken > 0u;
    for (var sz = cap; sz >= 1u; sz--) {
        for (var pk = 0u; pk < npk; pk++) {
            let pw = arena[P + pk];
            if ((pw & 255u) != sz || lab(arena[Q + (pw >> 8u)]) == C) { continue; }
            let got = shed_front(glen, pw);
            if (got.x != NONE) {
                glen = got.x;
                earliest = min(earliest, got.y);
                changed = true;
            }
        }
    }
    if (!changed) { return vec2<u32>(NONE, NONE); }
    return vec2<u32>(glen, earliest);
}


fn set_hop(x: u32, v: u32) { tri[tw(TRI_HOP, x)] = v; }
fn set_first(k: u32, v: u32) { cstate[cw(CORNER_FIRST, k)] = v; }
fn set_wmark(k: u32, v: u32) { cstate[cw(CORNER_WMARK, k)] = v; }
fn in_pocket(y: u32) -> bool {
    return in_region(y) && lab(y) == NONE && aux(y) == ((C + 1u) | TRYING);
}
fn next_to_pocket(x: u32) -> bool {
    for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
        if (in_pocket(nb(e))) { return true; }
    }
    return false;
}

// shed_front for the pocket of word `pw` (start << 8 | size in the pockets' triangles) and the
// cluster in `grown` (length `len`): returns the new length and the earliest seed-order position
// given back, or NONE with nothing changed. Its queue is the histogram's slots, its flood stack
// the vertex counts' (both free once the last-grown rule is done; each holds at most max_t).
fn shed_front(len: u32, pw: u32) -> vec2<u32> {
    let stamp = C + 1u;
    let G = s_grown(R);
    let Q = s_q() + RS;
    let QU = s_hist(R);
    let ST = s_vcount(R);
    let ps = pw >> 8u;
    let psz = pw & 255u;
    for (var i = ps; i < ps + psz; i++) { set_aux(arena[Q + i], stamp | TRYING); }
    // Stamps: cluster vertex (`a`), also the pocket's (`a + 1`), the pocket's only (`a + 2`).
    let a = SERIAL + 1u;
    SERIAL += 3u;
    let seen = ATTEMPT | a;
    let gone = ATTEMPT | (a + 1u);
    let reached = ATTEMPT | (a + 2u);
    var nv = 0u;
    for (var gi = 0u; gi < len; gi++) {
        let x = arena[G + gi];
        for (var j = 0u; j < 3u; j++) {
            let k = canon[3u * x + j];
            if (wmark(k) != a) {
                set_wmark(k, a);
                set_first(k, 0u);
                nv += 1u;
            }
            set_first(k, first_pos(k) + 1u);
        }
    }
    var outside = 0u;
    for (var i = ps; i < ps + psz; i++) {
        let x = arena[Q + i];
        for (var j = 0u; j < 3u; j++) {
            let k = canon[3u * x + j];
            let w = wmark(k);
            if (w == a) {
                set_wmark(k, a + 1u);
            } else if (w != a + 1u && w != a + 2u) {
                set_wmark(k, a + 2u);
                outside += 1u;
            }
        }
    }
    // Members next to the open side (free, in no pocket of this cluster), not next to the pocket.
    var qlen = 0u;
    for (var gi = 0u; gi < len; gi++) {
        let x = arena[G + gi];
        var open = false;
        var by_pocket = false;
        for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
            let y = nb(e);
            if (!in_region(y) || lab(y) != NONE) { continue; }
            if (aux(y) == (stamp | TRYING)) {
                by_pocket = true;
            } else if (aux(y) != stamp) {
                open = true;
            }
        }
        if (open && !by_pocket) {
            set_hop(x, seen);
            arena[QU + qlen] = x;
            qlen += 1u;
        }
    }
    var removed = 0u;
    var fits = len + psz <= p.max_t && nv + outside <= p.max_v;
    while (!fits && removed < qlen && 2u * (removed + 1u) <= len) {
        let u = arena[QU + removed];
        removed += 1u;
        for (var j = 0u; j < 3u; j++) {
            let k = canon[3u * u + j];
            set_first(k, first_pos(k) - 1u);
            if (first_pos(k) == 0u) {
                nv -= 1u;
                if (wmark(k) == a + 1u) { outside += 1u; }
            }
        }
        for (var e = dual_off[u]; e < dual_off[u + 1u]; e++) {
            let y = nb(e);
            if (in_region(y) && lab(y) == C && hop(y) != seen && !next_to_pocket(y)) {
                set_hop(y, seen);
                arena[QU + qlen] = y;
                qlen += 1u;
            }
        }
        fits = len - removed + psz <= p.max_t && nv + outside <= p.max_v;
    }
    var whole = false;
    if (fits) {
        for (var qi = 0u; qi < removed; qi++) { set_hop(arena[QU + qi], gone); }
        // One piece: flood the kept members and the pocket from the pocket.
        let p0 = arena[Q + ps];
        set_hop(p0, reached);
        arena[ST] = p0;
        var sl = 1u;
        var flooded = 1u;
        while (sl > 0u) {
            sl -= 1u;
            let u = arena[ST + sl];
            for (var e = dual_off[u]; e < dual_off[u + 1u]; e++) {
                let y = nb(e);
                if (!in_region(y)) { continue; }
                let member = (lab(y) == C && hop(y) != gone) || in_pocket(y);
                if (member && hop(y) != reached) {
                    set_hop(y, reached);
                    flooded += 1u;
                    arena[ST + sl] = y;
                    sl += 1u;
                }
            }
        }
        whole = flooded == len - removed + psz;
    }
    if (!whole) {
        for (var i = ps; i < ps + psz; i++) { set_aux(arena[Q + i], stamp); }
        return vec2<u32>(NONE, NONE);
    }
    let L = s_left() + RS;
    var earliest = NONE;
    for (var qi = 0u; qi < removed; qi++) {
        let x = arena[QU + qi];
        set_lab(x, NONE);
        set_aux(x, 0u);
        arena[L + piece(x)] += 1u;
        earliest = min(earliest, opos(x));
    }
    var glen = 0u;
    for (var gi = 0u; gi < len; gi++) {
        let x = arena[G + gi];
        if (lab(x) == C) {
            arena[G + glen] = x;
            glen += 1u;
        }
    }
    for (var i = ps; i < ps + psz; i++) {
        let x = arena[Q + i];
        set_lab(x, C);
        arena[L + piece(x)] -= 1u;
        arena[G + glen] = x;
        glen += 1u;
    }
    return vec2<u32>(glen, earliest);
}

// ---- grow (grow.rs: grow_region; the entry points) -------------------------------------------

// Closes the current cluster: its members (`grown`, `len`) go to the region's seq list.
fn close(len: u32, written: u32) -> u32 {
    let G = s_grown(R);
    arena[s_cstart() + RS + C] = written;
    for (var i = 0u; i < len; i++) { arena[s_seq() + RS + written + i] = arena[G + i]; }
    C += 1u;
    return written + len;
}

@compute @workgroup_size(1)
fn grow(@builtin(workgroup_id) wid: vec3<u32>) {
    grow_one(group(wid));
}

// The same, eight regions per workgroup (the driver's choice on a CPU adapter, which runs a
// workgroup's invocations side by side in SIMD rows).
@compute @workgroup_size(8)
fn grow_rows(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    grow_one(group(wid) * 8u + lid);
}

// pack.rs, during the growth: Packing::nearest, the seed of the piece nearest the centre `cen` (ties to the earlier piece)
// among the PACK_WINDOW pieces from the cursor's, the cursor's own or an untouched one after it,
// if it is not cut by the region's border and its seed fits; NONE if no piece qualifies.
fn nearest_piece(np: u32, cursor: u32, nv: u32, cen: vec3<u32>) -> u32 {
    let O = s_order() + RS;
    let L = s_left() + RS;
    let PS = s_pstart() + RS;
    let first = piece(arena[O + cursor]);
    var best = NONE;
    var best_d = 0u;
    for (var q = first; q < min(first + PACK_WINDOW, np); q++) {
        var seed = arena[O + cursor];
        if (q != first) {
            var end = N;
            if (q + 1u < np) { end = arena[PS + q + 1u]; }
            if ((arena[L + q] & ~CUT) != end - arena[PS + q]) { continue; }
            seed = arena[O + arena[PS + q]];
        }
        if ((arena[L + q] & CUT) != 0u || nv + added(seed) > p.max_v) { continue; }
        let d = cell_distance2(centre(seed), cen);
        if (best == NONE || d < best_d) {
            best = seed;
            best_d = d;
        }
    }
    return best;
}

fn grow_one(r: u32) {
    if (r >= p.regions) { return; }
    R = r;
    RS = info[r];
    C = 0u;
    SERIAL = 0u;
    let n = info[r + 1u] - RS;
    N = n;
    let O = s_order() + RS;
    let F = s_front() + RS;
    let L = s_left() + RS;
    let PS = s_pstart() + RS;
    let G = s_grown(r);
    let VC = s_vcount(r);
    // Pieces in reversed BFS order, the seed order.
    var olen = 0u;
    var np = 0u;
    for (var i = 0u; i < n; i++) {
        let root = items[RS + i];
        if (piece(root) != NONE) { continue; }
        let start = olen;
        set_piece(root, np);
        arena[O + olen] = root;
        olen += 1u;
        var head = start;
        var cut = 0u;
        while (head < olen) {
            let u = arena[O + head];
            head += 1u;
            for (var e = dual_off[u]; e < dual_off[u + 1u]; e++) {
                let x = nb(e);
                if (!in_region(x)) { cut = CUT; }
                if (in_region(x) && piece(x) == NONE) {
                    set_piece(x, np);
                    arena[O + olen] = x;
                    olen += 1u;
                }
            }
        }
        arena[L + np] = (olen - start) | cut;
        arena[PS + np] = start;
        var a = start;
        var b = olen - 1u;
        while (a < b) {
            let s = arena[O + a];
            arena[O + a] = arena[O + b];
            arena[O + b] = s;
            a += 1u;
            b -= 1u;
        }
        np += 1u;
    }
    for (var o = 0u; o < n; o++) { tri[tw(TRI_OPOS, arena[O + o])] = o; }
    var cursor = 0u;
    var open = false;
    var nv = 0u;
    var glen = 0u;
    var written = 0u;
    // Sums of the grown triangles' quantised centroids, per axis.
    var sx = 0u;
    var sy = 0u;
    var sz = 0u;
    loop {
        while (cursor < n && lab(arena[O + cursor]) != NONE) { cursor += 1u; }
        if (cursor == n) {
            if (open) { written = close(glen, written); }
            break;
        }
        var seed = arena[O + cursor];
        if (open) {
            // A packing cluster goes on at the nearest piece that fits, or closes as it is.
            seed = nearest_piece(np, cursor, nv, vec3<u32>(sx, sy, sz) / glen);
            if (seed == NONE) {
                written = close(glen, written);
                open = false;
                continue;
            }
        } else {
            nv = 0u;
            open = true;
            glen = 0u;
            sx = 0u;
            sy = 0u;
            sz = 0u;
        }
        arena[F] = seed;
        var flen = 1u;
        set_inq(seed, C);
        set_hop(seed, 0u);
        set_free(seed, free_neighbours(seed));
        while (glen < p.max_t) {
            var cen = centre(seed);
            if (glen > 0u) { cen = vec3<u32>(sx, sy, sz) / glen; }
            var bi = NONE;
            var best = vec4<u32>(0u);
            var best_hop = 0u;
            for (var fi = 0u; fi < flen; fi++) {
                let x = arena[F + fi];
                let a = added(x);
                if (nv + a > p.max_v) { continue; }
                let key = vec4<u32>(a, free_of(x), cell_distance2(centre(x), cen), x);
                if (bi == NONE || key_less(key, hop(x), best, best_hop)) {
                    best = key;
                    best_hop = hop(x);
                    bi = fi;
                }
            }
            if (bi == NONE) { break; }
            let x = arena[F + bi];
            flen -= 1u;
            arena[F + bi] = arena[F + flen];
            set_lab(x, C);
            set_aux(x, glen);
            arena[L + piece(x)] -= 1u;
            for (var j = 0u; j < 3u; j++) {
                let k = canon[3u * x + j];
                if (mark(k) != C) {
                    cstate[cw(CORNER_MARK, k)] = C;
                    set_first(k, glen);
                    nv += 1u;
                }
            }
            arena[G + glen] = x;
            arena[VC + glen] = nv;
            glen += 1u;
            let cx = centre(x);
            sx += cx.x;
            sy += cx.y;
            sz += cx.z;
            for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
                let y = nb(e);
                if (!in_region(y) || lab(y) != NONE) { continue; }
                // On the frontier: one free neighbour fewer; else it joins, counted afresh.
                if (inq(y) == C) {
                    set_free(y, free_of(y) - 1u);
                } else {
                    set_inq(y, C);
                    set_hop(y, hop(x) + 1u);
                    set_free(y, free_neighbours(y));
                    arena[F + flen] = y;
                    flen += 1u;
                }
            }
        }
        let exhausted = flen == 0u && (arena[L + piece(seed)] & ~CUT) == 0u;
        if (exhausted && glen < p.max_t && nv < p.max_v) { continue; }
        let absorbed = absorb(glen);
        if (absorbed.x != NONE) {
            glen = absorbed.x;
            cursor = min(cursor, absorbed.y);
        }
        written = close(glen, written);
        open = false;
    }
    merge_neighbours();
    info[p.regions + 1u + r] = C;
}

// ---- merge (merge.rs: merge_neighbours, step 2b, in the same invocation) ------------------------
//
// Clusters become linked lists (`next` in the frontier-cluster section, which growth no longer
// needs); per cluster, head, tail, size and the merge order live in the sections growth used for
// the seed order, the frontier, the pockets' triangles and the pockets.

fn next_of(x: u32) -> u32 { return tri[tw(TRI_INQ, x)]; }
fn set_next(x: u32, v: u32) { tri[tw(TRI_INQ, x)] = v; }
fn head(c: u32) -> u32 { return arena[s_order() + RS + c]; }
fn tail(c: u32) -> u32 { return arena[s_front() + RS + c]; }
fn size(c: u32) -> u32 { return arena[s_q() + RS + c]; }

// Member x onto the end of cluster c's list.
fn append(c: u32, x: u32) {
    set_next(tail(c), x);
    set_next(x, NONE);
    arena[s_front() + RS + c] = x;
    arena[s_q() + RS + c] = size(c) + 1u;
}

// The corners of `x` whose vertex the current evaluation (SERIAL) has not counted yet, stamped.
fn stamp_corners(x: u32) -> u32 {
    var nv = 0u;
    for (var j = 0u; j < 3u; j++) {
        let k = canon[3u * x + j];
        if (wmark(k) != SERIAL) {
            cstate[cw(CORNER_WMARK, k)] = SERIAL;
            nv += 1u;
        }
    }
    return nv;
}

// Distinct vertices of cluster `a`, and of `a` and `b` together when `b` is not NONE.
fn cluster_verts(a: u32, b: u32) -> u32 {
    SERIAL += 1u;
    var nv = 0u;
    for (var side = 0u; side < 2u; side++) {
        var x = head(a);
        if (side == 1u) {
            if (b == NONE) { break; }
            x = head(b);
        }
        while (x != NONE) {
            nv += stamp_corners(x);
            x = next_of(x);
        }
    }
    return nv;
}

// The non-empty clusters of the first `k`, smallest first (ties to the lower id), into the merge
// order's section; returns how many.
fn order_by_size(k: u32) -> u32 {
    let OC = s_pockets() + RS;
    var o = 0u;
    for (var sz = 1u; sz <= p.max_t; sz++) {
        for (var c = 0u; c < k; c++) {
            if (size(c) == sz) {
                arena[OC + o] = c;
                o += 1u;
            }
        }
    }
    return o;
}

fn merge_neighbours() {
    let k = C;
    // Lists from the clusters' ranges in seq.
    for (var c = 0u; c < k; c++) {
        let lo_i = arena[s_cstart() + RS + c];
        var hi_i = N;
        if (c + 1u < k) { hi_i = arena[s_cstart() + RS + c + 1u]; }
        let S = s_seq() + RS;
        arena[s_order() + RS + c] = arena[S + lo_i];
        arena[s_front() + RS + c] = arena[S + hi_i - 1u];
        arena[s_q() + RS + c] = hi_i - lo_i;
        for (var i = lo_i; i < hi_i; i++) {
            var nx = NONE;
            if (i + 1u < hi_i) { nx = arena[S + i + 1u]; }
            set_next(arena[S + i], nx);
        }
    }
    let OC = s_pockets() + RS;
    let o = order_by_size(k);
    for (var oi = 0u; oi < o; oi++) {
        let a = arena[OC + oi];
        let sa = size(a);
        if (sa == 0u || sa >= p.max_t) { continue; }
        let va = cluster_verts(a, NONE);
        if (va >= p.max_v) { continue; }
        var best = NONE;
        var best_common = 0u;
        var best_union = 0u;
        var x = head(a);
        while (x != NONE) {
            for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
                let y = nb(e);
                if (!in_region(y)) { continue; }
                let b = lab(y);
                if (b == a || sa + size(b) > p.max_t) { continue; }
                let u = cluster_verts(a, b);
                if (u > p.max_v) { continue; }
                let common_v = va + cluster_verts(b, NONE) - u;
                if (best == NONE || common_v > best_common || (common_v == best_common && b < best)) {
                    best = b;
                    best_common = common_v;
                    best_union = u;
                }
            }
            x = next_of(x);
        }
        if (best == NONE) { continue; }
        let keep = min(a, best);
        let gone = max(a, best);
        var g = head(gone);
        while (g != NONE) {
            set_lab(g, keep);
            g = next_of(g);
        }
        set_next(tail(keep), head(gone));
        arena[s_front() + RS + keep] = tail(gone);
        arena[s_q() + RS + keep] = size(keep) + size(gone);
        arena[s_q() + RS + gone] = 0u;
    }
    pack_pieces();
    dissolve_clusters();
    // Survivors renumbered in order, their members back in seq.
    var written = 0u;
    var nc = 0u;
    for (var c = 0u; c < k; c++) {
        if (size(c) == 0u) { continue; }
        arena[s_cstart() + RS + nc] = written;
        var y = head(c);
        while (y != NONE) {
            set_lab(y, nc);
            arena[s_seq() + RS + written] = y;
            written += 1u;
            y = next_of(y);
        }
        nc += 1u;
    }
    C = nc;
}

// ---- piece packing (pack.rs: pack_pieces, step 2c, in the same invocation) ---------------------
//
// Per cluster c, words growth no longer needs: its centre (x | y << 16, z) and radius in the hop,
// aux and position sections and its vertex count in the free-count section, each at the region's
// c-th triangle; the plan's room in seq and the cluster starts (the renumbering after rewrites
// them). The order is the merge order's section; the plan (a's pieces ascending, their targets)
// is in the grown and vertex-count rows.

fn pk_word(section: u32, c: u32) -> u32 { return tw(section, items[RS + c]); }
fn pk_centre(c: u32) -> vec3<u32> {
    return unpack_cell(tri[pk_word(TRI_HOP, c)], tri[pk_word(TRI_AUX, c)]);
}
fn pk_radius(c: u32) -> u32 { return tri[pk_word(TRI_OPOS, c)]; }
fn pk_verts(c: u32) -> u32 { return tri[pk_word(TRI_FREE, c)]; }
fn extra_t(c: u32) -> u32 { return arena[s_seq() + RS + c]; }
fn extra_v(c: u32) -> u32 { return arena[s_cstart() + RS + c]; }

// Integer floor square root, digit by digit (u32::isqrt on the CPU).
fn isqrt(x: u32) -> u32 {
    var v = x;
    var r = 0u;
    var bit = 1u << 30u;
    while (bit > v) { bit >>= 2u; }
    while (bit != 0u) {
        if (v >= r + bit) {
            v -= r + bit;
            r = (r >> 1u) + bit;
        } else {
            r >>= 1u;
        }
        bit >>= 2u;
    }
    return r;
}

// The target planned for piece `q` of the cluster being dissolved (NONE if not in the plan).
fn planned(q: u32, np: u32) -> u32 {
    for (var i = 0u; i < np; i++) {
        if (arena[s_grown(R) + i] == q) { return arena[s_vcount(R) + i]; }
    }
    return NONE;
}

// A member's planned target while its cluster is being dissolved, in its first corner's mark
// word (growth no longer reads marks).
fn target_of(x: u32) -> u32 { return cstate[cw(CORNER_MARK, 3u * x)]; }

// After member x, the next of cluster b's members and then of a's members planned for b (a ==
// NONE: b's alone); NONE at the end.
fn next_joined(x: u32, b: u32, a: u32) -> u32 {
    var y = next_of(x);
    if (y == NONE && lab(x) == b && a != NONE) { y = head(a); }
    while (y != NONE && lab(y) != b && target_of(y) != b) { y = next_of(y); }
    return y;
}

// Centre and radius of cluster b together with the members of `a` planned for it (a == NONE:
// b alone).
fn centre_radius(b: u32, a: u32) -> vec4<u32> {
    var sum = vec3<u32>(0u);
    var n = 0u;
    for (var x = head(b); x != NONE; x = next_joined(x, b, a)) {
        sum += centre(x);
        n += 1u;
    }
    let c = sum / max(n, 1u);
    var far = 0u;
    for (var x = head(b); x != NONE; x = next_joined(x, b, a)) {
        far = max(far, cell_distance2(centre(x), c));
    }
    return vec4<u32>(c, isqrt(far));
}

fn set_centre_radius(b: u32) {
    let cr = centre_radius(b, NONE);
    tri[pk_word(TRI_HOP, b)] = cr.x | (cr.y << 16u);
    tri[pk_word(TRI_AUX, b)] = cr.z;
    tri[pk_word(TRI_OPOS, b)] = cr.w;
}

fn pack_pieces() {
    let k = C;
    let L = s_left() + RS;
    let OC = s_pockets() + RS;
    let PL = s_grown(R);
    let TG = s_vcount(R);
    for (var c = 0u; c < k; c++) {
        arena[s_seq() + RS + c] = 0u;
        arena[s_cstart() + RS + c] = 0u;
        if (size(c) == 0u) { continue; }
        set_centre_radius(c);
        tri[pk_word(TRI_FREE, c)] = cluster_verts(c, NONE);
    }
    let o = order_by_size(k);
    for (var oi = 0u; oi < o; oi++) {
        let a = arena[OC + oi];
        // Made of whole pieces, with no neighbour in another cluster.
        var closed = true;
        var x = head(a);
        while (x != NONE && closed) {
            closed = (arena[L + piece(x)] & CUT) == 0u;
            for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
                let y = nb(e);
                if (in_region(y) && lab(y) != a) { closed = false; }
            }
            x = next_of(x);
        }
        if (!closed) { continue; }
        // Its pieces ascending, each planned to the nearest cluster with room.
        var np = 0u;
        var last = NONE;
        var ok = true;
        loop {
            var q = NONE;
            x = head(a);
            while (x != NONE) {
                let px = piece(x);
                if ((last == NONE || px > last) && (q == NONE || px < q)) { q = px; }
                x = next_of(x);
            }
            if (q == NONE) { break; }
            last = q;
            SERIAL += 1u;
            var pt = 0u;
            var pv = 0u;
            var sum = vec3<u32>(0u);
            x = head(a);
            while (x != NONE) {
                if (piece(x) == q) {
                    pt += 1u;
                    sum += centre(x);
                    pv += stamp_corners(x);
                }
                x = next_of(x);
            }
            let pc = sum / pt;
            var best = NONE;
            var best_d = 0u;
            for (var b = 0u; b < k; b++) {
                if (b == a || size(b) == 0u || size(b) + extra_t(b) + pt > p.max_t
                    || pk_verts(b) + extra_v(b) + pv > p.max_v) {
                    continue;
                }
                let d = cell_distance2(pk_centre(b), pc);
                if (best == NONE || d < best_d) {
                    best = b;
                    best_d = d;
                }
            }
            if (best == NONE) {
                ok = false;
                break;
            }
            arena[s_seq() + RS + best] += pt;
            arena[s_cstart() + RS + best] += pv;
            arena[PL + np] = q;
            arena[TG + np] = best;
            np += 1u;
        }
        for (var i = 0u; i < np; i++) {
            arena[s_seq() + RS + arena[TG + i]] = 0u;
            arena[s_cstart() + RS + arena[TG + i]] = 0u;
        }
        if (!ok) { continue; }
        x = head(a);
        while (x != NONE) {
            cstate[cw(CORNER_MARK, 3u * x)] = planned(piece(x), np);
            x = next_of(x);
        }
        // The radii the targets gain, each target counted once (at its first piece).
        var gain = 0i;
        for (var i = 0u; i < np; i++) {
            let b = arena[TG + i];
            var seen = false;
            for (var j = 0u; j < i; j++) { seen = seen || arena[TG + j] == b; }
            if (seen) { continue; }
            gain += i32(centre_radius(b, a).w) - i32(pk_radius(b));
        }
        if (gain > i32(pk_radius(a))) { continue; }
        x = head(a);
        while (x != NONE) {
            let nx = next_of(x);
            let b = target_of(x);
            set_lab(x, b);
            append(b, x);
            x = nx;
        }
        arena[s_q() + RS + a] = 0u;
        for (var i = 0u; i < np; i++) {
            let b = arena[TG + i];
            set_centre_radius(b);
            tri[pk_word(TRI_FREE, b)] = cluster_verts(b, NONE);
        }
    }
}

// ---- dissolve (dissolve.rs: dissolve_clusters, step 2d, in the same invocation) ---------------
//
// Scratch: the queue (circular, `max_t` words: a member is queued at most once at a time) in the
// grown row; a member's queued flag in its first corner's mark word; the plan's added triangles
// and vertices per target in seq and the cluster starts, as in pack_pieces, which leaves them
// zero and every cluster's vertex count in `pk_verts`.

// Distinct corners of `x` whose vertex no member of cluster `b` uses (moved members included).
fn added_to(x: u32, b: u32) -> u32 {
    var n = 0u;
    for (var j = 0u; j < 3u; j++) {
        let k = canon[3u * x + j];
        if ((j > 0u && canon[3u * x] == k) || (j > 1u && canon[3u * x + 1u] == k)) { continue; }
        let v = idx(3u * x + j);
        var used = false;
        for (var e = vt_off[v]; e < vt_off[v + 1u] && !used; e++) {
            let y = vtn(e);
            used = in_region(y) && lab(y) == b;
        }
        if (!used) { n += 1u; }
    }
    return n;
}

fn dissolve_clusters() {
    let k = C;
    let OC = s_pockets() + RS;
    let Q = s_grown(R);
    let o = order_by_size(k);
    for (var oi = 0u; oi < o; oi++) {
        let a = arena[OC + oi];
        let sa = size(a);
        if (sa == 0u) { continue; }
        // The members with a neighbour in another cluster, ascending (insertion sort).
        var qn = 0u;
        var x = head(a);
        while (x != NONE) {
            cstate[cw(CORNER_MARK, 3u * x)] = 0u;
            var outside = false;
            for (var e = dual_off[x]; e < dual_off[x + 1u]; e++) {
                let y = nb(e);
                if (in_region(y) && lab(y) != a) { outside = true; }
            }
            if (outside) {
                var i = qn;
                while (i > 0u && arena[Q + i - 1u] > x) {
                    arena[Q + i] = arena[Q + i - 1u];
                    i -= 1u;
                }
                arena[Q + i] = x;
                cstate[cw(CORNER_MARK, 3u * x)] = 1u;
                qn += 1u;
            }
            x = next_of(x);
        }
        var qh = 0u;
        var moved = 0u;
        while (qn > 0u) {
            let m = arena[Q + qh];
            qh = (qh + 1u) % p.max_t;
            qn -= 1u;
            cstate[cw(CORNER_MARK, 3u * m)] = 0u;
            var best = NONE;
            var best_add = 0u;
            for (var e = dual_off[m]; e < dual_off[m + 1u]; e++) {
                let y = nb(e);
                if (!in_region(y)) { continue; }
                let b = lab(y);
                if (b == a || size(b) + extra_t(b) + 1u > p.max_t) { continue; }
                let ad = added_to(m, b);
                if (pk_verts(b) + extra_v(b) + ad > p.max_v) { continue; }
                if (best == NONE || ad < best_add || (ad == best_add && b < best)) {
                    best = b;
                    best_add = ad;
                }
            }
            if (best == NONE) { continue; }
            set_lab(m, best);
            arena[s_seq() + RS + best] += 1u;
            arena[s_cstart() + RS + best] += best_add;
            moved += 1u;
            for (var e = dual_off[m]; e < dual_off[m + 1u]; e++) {
                let y = nb(e);
                if (in_region(y) && lab(y) == a && cstate[cw(CORNER_MARK, 3u * y)] == 0u) {
                    arena[Q + (qh + qn) % p.max_t] = y;
                    cstate[cw(CORNER_MARK, 3u * y)] = 1u;
                    qn += 1u;
                }
            }
        }
        // All moved: into the targets' lists in a's list order; else every member back.
        let done = moved == sa;
        x = head(a);
        while (x != NONE) {
            let nx = next_of(x);
            let b = lab(x);
            if (b != a) {
                if (done) {
                    append(b, x);
                    // Added once: extra_v(b) is zeroed below after b's first member.
                    tri[pk_word(TRI_FREE, b)] = pk_verts(b) + extra_v(b);
                } else {
                    set_lab(x, a);
                }
                arena[s_seq() + RS + b] = 0u;
                arena[s_cstart() + RS + b] = 0u;
            }
            x = nx;
        }
        if (done) { arena[s_q() + RS + a] = 0u; }
    }
}

// ---- relabel ---------------------------------------------------------------------------------

@compute @workgroup_size(64)
fn relabel(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    labels[t] = info[2u * p.regions + 1u + region(t)] + lab(t);
}

// ---- medoid ----------------------------------------------------------------------------------

// Cluster `g`'s member range: (members at `M`, queue at `Q`, member count).
fn cluster_span(g: u32) -> vec3<u32> {
    let B = 2u * p.regions + 1u;
    // The region: the last base at or below g.
    var lo = 0u;
    var hi = p.regions;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (info[B + mid] <= g) { lo = mid; } else { hi = mid; }
    }
    let r = lo;
    let rs = info[r];
    let n = info[r + 1u] - rs;
    let lc = g - info[B + r];
    let start = arena[s_cstart() + rs + lc];
    var end = n;
    if (lc + 1u < info[p.regions + 1u + r]) { end = arena[s_cstart() + rs + lc + 1u]; }
    return vec3<u32>(s_seq() + rs + start, s_q() + rs + start, end - start);
}

// Where the shared medoid (medoid.wgsl) stores its result.
fn set_medoid(g: u32, m: u32) { info[3u * p.regions + 2u + g] = m; }

// One invocation per cluster.
@compute @workgroup_size(64)
fn medoid(@builtin(global_invocation_id) gid: vec3<u32>) {
    let g = flat(gid);
    if (g >= p.k) { return; }
    let span = cluster_span(g);
    if (!medoid_bits(g, span, span.x - s_seq())) { medoid_serial(g, span); }
}
