// The medoid update of k-medoids on the triangle dual graph, mirroring src/strategy/kmedoids/update.rs
// step by step (the assignment, a multi-source BFS, is wgsl/assign.wgsl):
//   dirty_clear, medoid_index, dirty_mark    clusters whose members changed since the last update
//                                            (the CPU's UpdateCache: the others keep their medoid)
//   mem_clear, mem_count, scan, mem_scatter  members of each cluster (CSR)
//   update                                   new medoid per changed cluster + shift, counters
//   mark_clear, mark, scan, place            new medoids in ascending order (cluster ids)
//   remember                                 each triangle's new medoid, for the next dirty_mark
//   (split statistics: wgsl/split.wgsl)
//   dist_partial                             the objective (sum of hop distances), per workgroup

struct Params { t: u32, k: u32, d: u32, slot: u32, max_v: u32, max_t: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> dual_off: array<u32>;
@group(0) @binding(2) var<storage, read> dual_a: array<u32>;
@group(0) @binding(3) var<storage, read> dual_b: array<u32>;
@group(0) @binding(4) var<storage, read> labels: array<u32>;
@group(0) @binding(5) var<storage, read> dist: array<u32>;
@group(0) @binding(6) var<storage, read_write> medoids: array<u32>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> mem_off: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> mem_items: array<u32>;
@group(0) @binding(10) var<storage, read_write> cursor: array<atomic<u32>>;
// [0, k) new medoid, [k, 2k) shift; [2k, 4k) split.wgsl's statistics.
@group(0) @binding(11) var<storage, read_write> result: array<u32>;
@group(0) @binding(12) var<storage, read_write> flags: array<u32>;
// Two words per triangle: the large-cluster fallback's BFS distance and queue, per cluster at
// 2 * (its member offset).
@group(0) @binding(13) var<storage, read_write> scratch: array<u32>;
// [0, T): the medoid each triangle's cluster moved to at the last update (NONE before the first);
// [T, T + k): 1 where the cluster's members changed since then.
@group(0) @binding(14) var<storage, read_write> prev: array<u32>;

// counters: 0 shift sum, 1 medoids changed, 2 large clusters, 3 updates skipped as unchanged;
// 8.. assign.wgsl's frontier sizes.
const SHIFT: u32 = 0u;
const CHANGED: u32 = 1u;
const LARGE: u32 = 2u;
const SKIPPED: u32 = 3u;

fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }

@compute @workgroup_size(64)
fn clear_counters(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i < arrayLength(&counters)) { atomicStore(&counters[i], 0u); }
}

// ---- which clusters changed ------------------------------------------------------------------
//
// The CPU caches each cluster's update by its member list: a cluster whose members are exactly
// those that moved to its medoid at the last update gets that medoid again, with shift 0. Here a
// triangle whose current medoid differs from the one it remembered marks both clusters changed;
// every other cluster is unchanged (same test, per triangle).

@compute @workgroup_size(64)
fn dirty_clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c < p.k) { prev[p.t + c] = 0u; }
}

// flags[medoid] = its cluster (flags is free until mark_clear).
@compute @workgroup_size(64)
fn medoid_index(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c < p.k) { flags[medoids[c]] = c; }
}

@compute @workgroup_size(64)
fn dirty_mark(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || labels[t] == NONE) { return; }
    let l = labels[t];
    let before = prev[t];
    if (medoids[l] == before) { return; }
    prev[p.t + l] = 1u;
    if (before == NONE) { return; }
    // The cluster that triangle left, if its medoid is still one (it always is: splits only add).
    let c = flags[before];
    if (c < p.k && medoids[c] == before) { prev[p.t + c] = 1u; }
}

@compute @workgroup_size(64)
fn remember(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t < p.t && labels[t] != NONE) { prev[t] = result[labels[t]]; }
}

@compute @workgroup_size(64)
fn mem_clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c > p.k) { return; }
    atomicStore(&mem_off[c], 0u);
    if (c < p.k) { atomicStore(&cursor[c], 0u); }
}

@compute @workgroup_size(64)
fn mem_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || labels[t] == NONE) { return; }
    atomicAdd(&mem_off[labels[t]], 1u);
}

// Any order within a cluster: update sorts its members, split.wgsl does not need an order.
@compute @workgroup_size(64)
fn mem_scatter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || labels[t] == NONE) { return; }
    let l = labels[t];
    mem_items[atomicLoad(&mem_off[l]) + atomicAdd(&cursor[l], 1u)] = t;
}

// ---- medoid update: one workgroup per cluster --------------------------------------------------
//
// Clusters of up to MAXM members run an all-sources BFS at once in workgroup memory: reach[v] is
// the bitset of sources that reached local node v; per level v ORs its neighbours' sets, and the
// newly arrived sources are at distance d + 1. By symmetry the sum over sources of dist(s, v) is
// v's own sum of distances, so each node accumulates its sum without per-source queues. Larger
// clusters (rare) fall back to one thread running a BFS per source in global scratch.

const MAXM: u32 = 256u;
// Threads per update workgroup: 64 on a GPU; the host sets 8 (one SIMD row) on lavapipe, where
// every barrier switches between the rows of a workgroup and the BFS levels are barrier-bound.
override UW: u32 = 64u;
const MAXADJ: u32 = 1024u;

var<workgroup> wm: array<u32, 256>;
var<workgroup> wtmp: array<u32, 256>;
var<workgroup> loff: array<u32, 257>;
var<workgroup> ladj: array<u32, 1024>;
var<workgroup> reach: array<u32, 4096>;
var<workgroup> lvl_old: array<u32, 256>;
var<workgroup> sums: array<u32, 256>;
var<workgroup> cnt: array<u32, 256>;
// Packed (sum << 8 | local index) keys: the best member whose sum is final, and the smallest lower
// bound of the others.
var<workgroup> w_full: atomic<u32>;
var<workgroup> w_lb: atomic<u32>;
var<workgroup> w_m: u32;
var<workgroup> w_go: u32;
var<workgroup> w_changed: atomic<u32>;
var<workgroup> w_best: atomic<u32>;

// Local index of triangle x in the sorted member list wm[0..m).
fn local_index(x: u32, m: u32) -> u32 {
    var lo = 0u;
    var hi = m;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (wm[mid] < x) { lo = mid + 1u; } else { hi = mid; }
    }
    return lo;
}

// Word w of a reach set with every source of an m-member cluster present.
fn full_word(w: u32, words: u32, m: u32) -> u32 {
    if (w + 1u == words && m % 32u != 0u) { return (1u << (m % 32u)) - 1u; }
    return NONE;
}

fn finish(c: u32, new_medoid: u32, shift: u32) {
    result[c] = new_medoid;
    result[p.k + c] = shift;
    atomicAdd(&counters[SHIFT], shift);
    if (new_medoid != medoids[c]) { atomicAdd(&counters[CHANGED], 1u); }
}

@compute @workgroup_size(UW)
fn update(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let c = group(wid);
    if (c >= p.k) { return; }
    if (lid == 0u) {
        w_m = atomicLoad(&mem_off[c + 1u]) - atomicLoad(&mem_off[c]);
        // Unchanged members: the same medoid, no shift (as the CPU's cache hit).
        if (prev[p.t + c] == 0u) { w_m = NONE; }
        atomicStore(&w_best, NONE);
        atomicStore(&w_changed, 0u);
    }
    let m = workgroupUniformLoad(&w_m);
    if (m == NONE) {
        if (lid == 0u) {
            result[c] = medoids[c];
            result[p.k + c] = 0u;
            atomicAdd(&counters[SKIPPED], 1u);
        }
        return;
    }
    let off = atomicLoad(&mem_off[c]);
    if (m > MAXM) {
        if (lid == 0u) { large_update(c, off, m); }
        return;
    }
    // Members, sorted by rank (they are distinct): local index = position in ascending order, so
    // ties on the sum go to the lowest triangle id as on the CPU.
    for (var i = lid; i < m; i += UW) { wtmp[i] = mem_items[off + i]; }
    workgroupBarrier();
    for (var i = lid; i < m; i += UW) {
        let x = wtmp[i];
        var r = 0u;
        for (var j = 0u; j < m; j++) { r += u32(wtmp[j] < x); }
        wm[r] = x;
    }
    workgroupBarrier();
    // Local adjacency: neighbours with the same label.
    for (var i = lid; i < m; i += UW) {
        let t = wm[i];
        var n = 0u;
        for (var e = dual_off[t]; e < dual_off[t + 1u]; e++) { n += u32(labels[nb(e)] == c); }
        loff[i + 1u] = n;
    }
    workgroupBarrier();
    if (lid == 0u) {
        loff[0] = 0u;
        for (var i = 0u; i < m; i++) { loff[i + 1u] += loff[i]; }
        w_go = u32(loff[m] <= MAXADJ);
    }
    if (workgroupUniformLoad(&w_go) == 0u) {
        if (lid == 0u) { large_update(c, off, m); }
        return;
    }
    for (var i = lid; i < m; i += UW) {
        let t = wm[i];
        var at = loff[i];
        for (var e = dual_off[t]; e < dual_off[t + 1u]; e++) {
            let x = nb(e);
            if (labels[x] == c) {
                ladj[at] = local_index(x, m);
                at++;
            }
        }
    }
    let words = (m + 31u) / 32u;
    let stride = m * words; // second reach buffer
    let old = local_index(medoids[c], m);
    for (var v = lid; v < m; v += UW) {
        for (var w = 0u; w < words; w++) { reach[v * words + w] = 0u; }
        reach[v * words + v / 32u] = 1u << (v % 32u);
        sums[v] = 0u;
        cnt[v] = 1u;
        lvl_old[v] = NONE;
    }
    if (lid == 0u) {
        atomicStore(&w_full, NONE);
        atomicStore(&w_lb, NONE);
    }
    workgroupBarrier();
    if (lid == 0u) { lvl_old[old] = 0u; }
    var cur = 0u;
    var d = 0u;
    loop {
        let nxt = stride - cur;
        for (var v = lid; v < m; v += UW) {
            var grew = 0u;
            let first = loff[v];
            let end = loff[v + 1u];
            for (var w = 0u; w < words; w++) {
                let own = reach[cur + v * words + w];
                var x = own;
                // A word whose sources have all arrived cannot grow: skip its neighbours (most
                // words fill well before the last level).
                if (own != full_word(w, words, m)) {
                    for (var e = first; e < end; e++) { x |= reach[cur + ladj[e] * words + w]; }
                }
                var fresh = x & ~own;
                reach[nxt + v * words + w] = x;
                if (fresh != 0u) {
                    grew += countOneBits(fresh);
                    if (v == old) {
                        while (fresh != 0u) {
                            let b = firstTrailingBit(fresh);
                            lvl_old[w * 32u + b] = d + 1u;
                            fresh &= fresh - 1u;
                        }
                    }
                }
            }
            if (grew != 0u) {
                sums[v] += (d + 1u) * grew;
                cnt[v] += grew;
                atomicStore(&w_changed, 1u);
            }
            // Early stop: a member reached by every source has its final sum; any other has at
            // least its sum so far plus d + 2 hops per missing source. Once no such bound can beat
            // (or tie below) the best final sum, the remaining levels would only finish the sums
            // of members that cannot win: central members fill at about the cluster's radius,
            // the BFS would otherwise run to its diameter.
            if (cnt[v] == m) {
                atomicMin(&w_full, (sums[v] << 8u) | v);
            } else {
                atomicMin(&w_lb, ((sums[v] + (d + 2u) * (m - cnt[v])) << 8u) | v);
            }
        }
        workgroupBarrier();
        if (lid == 0u) {
            w_go = atomicLoad(&w_changed) * u32(atomicLoad(&w_lb) < atomicLoad(&w_full));
            atomicStore(&w_changed, 0u);
            atomicStore(&w_lb, NONE);
        }
        cur = nxt;
        d++;
        if (workgroupUniformLoad(&w_go) == 0u) { break; }
    }
    for (var v = lid; v < m; v += UW) {
        // Unreachable members cost the member count each, as on the CPU. After an early stop a
        // member not yet reached by every source gets a total above its bound, so it loses.
        let total = sums[v] + (m - cnt[v]) * m;
        atomicMin(&w_best, (total << 8u) | v);
    }
    workgroupBarrier();
    if (lid == 0u) {
        let s = atomicLoad(&w_best) & 255u;
        finish(c, wm[s], lvl_old[s]);
    }
}

// One thread: members sorted in place, then a queue BFS per source over global memory.
fn large_update(c: u32, off: u32, m: u32) {
    atomicAdd(&counters[LARGE], 1u);
    for (var i = off + 1u; i < off + m; i++) {
        let x = mem_items[i];
        var j = i;
        while (j > off && mem_items[j - 1u] > x) {
            mem_items[j] = mem_items[j - 1u];
            j--;
        }
        mem_items[j] = x;
    }
    var best_sum = NONE;
    var best = 0u;
    for (var s = 0u; s < m; s++) {
        let sum = large_bfs(c, off, m, s);
        if (sum < best_sum) {
            best_sum = sum;
            best = s;
        }
    }
    large_bfs(c, off, m, best);
    let old = large_index(medoids[c], off, m);
    finish(c, mem_items[off + best], scratch[2u * off + old]);
}

fn large_index(x: u32, off: u32, m: u32) -> u32 {
    var lo = 0u;
    var hi = m;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (mem_items[off + mid] < x) { lo = mid + 1u; } else { hi = mid; }
    }
    return lo;
}

// BFS from local node s; distances at scratch[2 off ..], queue at scratch[2 off + m ..]. Returns
// the sum of distances with the CPU's penalty for unreachable members.
fn large_bfs(c: u32, off: u32, m: u32, s: u32) -> u32 {
    let db = 2u * off;
    let qb = 2u * off + m;
    for (var i = 0u; i < m; i++) { scratch[db + i] = NONE; }
    scratch[db + s] = 0u;
    scratch[qb] = s;
    var head = 0u;
    var tail = 1u;
    var sum = 0u;
    while (head < tail) {
        let u = scratch[qb + head];
        head++;
        let du = scratch[db + u];
        sum += du;
        let t = mem_items[off + u];
        for (var e = dual_off[t]; e < dual_off[t + 1u]; e++) {
            let x = nb(e);
            if (labels[x] != c) { continue; }
            let l = large_index(x, off, m);
            if (scratch[db + l] == NONE) {
                scratch[db + l] = du + 1u;
                scratch[qb + tail] = l;
                tail++;
            }
        }
    }
    return sum + (m - tail) * m;
}

// ---- new medoids in ascending order ------------------------------------------------------------

@compute @workgroup_size(64)
fn mark_clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t <= p.t) { flags[t] = 0u; }
}

@compute @workgroup_size(64)
fn mark(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c < p.k) { flags[result[c]] = 1u; }
}

// After the scan flags[t] is the rank of medoid t among the new medoids (they are distinct).
@compute @workgroup_size(64)
fn place(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c < p.k) { medoids[flags[result[c]]] = result[c]; }
}

var<workgroup> w_sum: atomic<u32>;

@compute @workgroup_size(64)
fn dist_partial(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let t = flat(gid);
    if (lid == 0u) { atomicStore(&w_sum, 0u); }
    workgroupBarrier();
    if (t < p.t && dist[t] != NONE) { atomicAdd(&w_sum, dist[t]); }
    workgroupBarrier();
    if (lid == 0u) { scratch[group(wid)] = atomicLoad(&w_sum); }
}
