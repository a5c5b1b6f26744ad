// k-medoids on the triangle dual graph, mirroring src/strategy/kmedoids.rs step by step:
//   clear, seed, bfs_round x levels          assign (multi-source BFS, lowest cluster wins ties)
//   mem_clear, mem_count, scan, mem_scatter  members of each cluster (CSR)
//   update                                   new medoid per cluster + shift, convergence counters
//   mark_clear, mark, scan, place            new medoids in ascending order (cluster ids)
//   stats                                    distinct vertices and farthest member per cluster
//   dist_partial                             the objective (sum of hop distances), per workgroup
//
// bfs_round is a pull relaxation: in round d an unreached triangle takes the smallest label among
// its neighbours at distance d. Every competitor is at the same distance, so the min over labels is
// the CPU's fetch_min on (distance << 32 | cluster); no 64-bit atomics needed, and the result does
// not depend on thread order.

struct Params { t: u32, k: u32, d: u32, slot: u32, max_v: u32, max_t: u32, w6: u32, w7: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read_write> dual_off: array<u32>;
@group(0) @binding(2) var<storage, read_write> dual_a: array<u32>;
@group(0) @binding(3) var<storage, read_write> dual_b: array<u32>;
@group(0) @binding(4) var<storage, read_write> labels: array<u32>;
@group(0) @binding(5) var<storage, read_write> dist: array<u32>;
@group(0) @binding(6) var<storage, read_write> medoids: array<u32>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> mem_off: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> mem_items: array<u32>;
@group(0) @binding(10) var<storage, read_write> cursor: array<atomic<u32>>;
// [0, k) new medoid, [k, 2k) shift, [2k, 3k) distinct vertices, [3k, 4k) farthest member.
@group(0) @binding(11) var<storage, read_write> result: array<u32>;
@group(0) @binding(12) var<storage, read_write> flags: array<u32>;
// Two words per triangle: the large-cluster fallback's BFS distance and queue, per cluster at
// 2 * (its member offset).
@group(0) @binding(13) var<storage, read_write> scratch: array<u32>;
@group(0) @binding(14) var<storage, read_write> idx_a: array<u32>;
@group(0) @binding(15) var<storage, read_write> idx_b: array<u32>;

const PART: u32 = 33554432u;
const NONE: u32 = 0xffffffffu;
// counters: 0 shift sum, 1 medoids changed, 2 large clusters, 8.. per-round BFS updates.
const SHIFT: u32 = 0u;
const CHANGED: u32 = 1u;
const LARGE: u32 = 2u;

fn nb(i: u32) -> u32 { if (i < PART) { return dual_a[i]; } return dual_b[i - PART]; }
fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }
fn flat(gid: vec3<u32>) -> u32 { return gid.x + gid.y * 65535u * 64u; }
fn group(wid: vec3<u32>) -> u32 { return wid.x + wid.y * 65535u; }

@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    labels[t] = NONE;
    dist[t] = NONE;
}

@compute @workgroup_size(64)
fn clear_counters(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i < arrayLength(&counters)) { atomicStore(&counters[i], 0u); }
}

@compute @workgroup_size(64)
fn seed(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k) { return; }
    labels[medoids[c]] = c;
    dist[medoids[c]] = 0u;
}

@compute @workgroup_size(64)
fn bfs_round(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t || dist[t] != NONE) { return; }
    var best = NONE;
    for (var i = dual_off[t]; i < dual_off[t + 1u]; i++) {
        let n = nb(i);
        if (dist[n] == p.d) { best = min(best, labels[n]); }
    }
    if (best != NONE) {
        labels[t] = best;
        dist[t] = p.d + 1u;
        atomicAdd(&counters[p.slot], 1u);
    }
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

// Any order within a cluster: update sorts its members, stats does not need an order.
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
const MAXADJ: u32 = 1024u;

var<workgroup> wm: array<u32, 256>;
var<workgroup> wtmp: array<u32, 256>;
var<workgroup> loff: array<u32, 257>;
var<workgroup> ladj: array<u32, 1024>;
var<workgroup> reach: array<u32, 4096>;
var<workgroup> lvl_old: array<u32, 256>;
var<workgroup> sums: array<u32, 256>;
var<workgroup> w_m: u32;
var<workgroup> w_go: u32;
var<workgroup> w_changed: atomic<u32>;
var<workgroup> w_best: atomic<u32>;
var<workgroup> w_part: array<u32, 64>;

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

fn finish(c: u32, new_medoid: u32, shift: u32) {
    result[c] = new_medoid;
    result[p.k + c] = shift;
    atomicAdd(&counters[SHIFT], shift);
    if (new_medoid != medoids[c]) { atomicAdd(&counters[CHANGED], 1u); }
}

@compute @workgroup_size(64)
fn update(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let c = group(wid);
    if (c >= p.k) { return; }
    if (lid == 0u) {
        w_m = atomicLoad(&mem_off[c + 1u]) - atomicLoad(&mem_off[c]);
        atomicStore(&w_best, NONE);
        atomicStore(&w_changed, 0u);
    }
    let m = workgroupUniformLoad(&w_m);
    let off = atomicLoad(&mem_off[c]);
    if (m > MAXM) {
        if (lid == 0u) { large_update(c, off, m); }
        return;
    }
    // Members, sorted by rank (they are distinct): local index = position in ascending order, so
    // ties on the sum go to the lowest triangle id as on the CPU.
    for (var i = lid; i < m; i += 64u) { wtmp[i] = mem_items[off + i]; }
    workgroupBarrier();
    for (var i = lid; i < m; i += 64u) {
        let x = wtmp[i];
        var r = 0u;
        for (var j = 0u; j < m; j++) { r += u32(wtmp[j] < x); }
        wm[r] = x;
    }
    workgroupBarrier();
    // Local adjacency: neighbours with the same label.
    for (var i = lid; i < m; i += 64u) {
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
    for (var i = lid; i < m; i += 64u) {
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
    for (var v = lid; v < m; v += 64u) {
        for (var w = 0u; w < words; w++) { reach[v * words + w] = 0u; }
        reach[v * words + v / 32u] = 1u << (v % 32u);
        sums[v] = 0u;
        lvl_old[v] = NONE;
    }
    workgroupBarrier();
    if (lid == 0u) { lvl_old[old] = 0u; }
    var cur = 0u;
    var d = 0u;
    loop {
        let nxt = stride - cur;
        for (var v = lid; v < m; v += 64u) {
            var grew = 0u;
            for (var w = 0u; w < words; w++) {
                let own = reach[cur + v * words + w];
                var x = own;
                for (var e = loff[v]; e < loff[v + 1u]; e++) { x |= reach[cur + ladj[e] * words + w]; }
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
                atomicStore(&w_changed, 1u);
            }
        }
        workgroupBarrier();
        if (lid == 0u) {
            w_go = atomicLoad(&w_changed);
            atomicStore(&w_changed, 0u);
        }
        cur = nxt;
        d++;
        if (workgroupUniformLoad(&w_go) == 0u) { break; }
    }
    for (var v = lid; v < m; v += 64u) {
        var reached = 0u;
        for (var w = 0u; w < words; w++) { reached += countOneBits(reach[cur + v * words + w]); }
        // Unreachable members cost the member count each, as on the CPU.
        let total = sums[v] + (m - reached) * m;
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

// ---- split support -----------------------------------------------------------------------------

// Distinct vertices (only for clusters within the triangle limit, as the CPU checks triangles
// first) and the farthest member (largest distance, lowest id).
@compute @workgroup_size(64)
fn stats(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let c = group(wid);
    if (c >= p.k) { return; }
    let off = atomicLoad(&mem_off[c]);
    let m = atomicLoad(&mem_off[c + 1u]) - off;
    // Farthest: a per-thread best, then thread 0 over the 64.
    var far = NONE;
    var fd = 0u;
    for (var i = lid; i < m; i += 64u) {
        let t = mem_items[off + i];
        let dt = dist[t];
        if (far == NONE || dt > fd || (dt == fd && t < far)) {
            far = t;
            fd = dt;
        }
    }
    let small = m <= p.max_t;
    if (small) {
        for (var i = lid; i < 3u * m; i += 64u) { reach[i] = idx(3u * mem_items[off + i / 3u] + i % 3u); }
    }
    workgroupBarrier();
    var distinct = 0u;
    if (small) {
        for (var i = lid; i < 3u * m; i += 64u) {
            var first = true;
            for (var j = 0u; j < i; j++) {
                if (reach[j] == reach[i]) { first = false; break; }
            }
            distinct += u32(first);
        }
    }
    w_part[lid] = distinct;
    wtmp[lid] = far;
    loff[lid] = fd;
    workgroupBarrier();
    if (lid == 0u) {
        var total = 0u;
        var bf = NONE;
        var bd = 0u;
        for (var i = 0u; i < 64u; i++) {
            total += w_part[i];
            let f = wtmp[i];
            if (f != NONE && (bf == NONE || loff[i] > bd || (loff[i] == bd && f < bf))) {
                bf = f;
                bd = loff[i];
            }
        }
        result[2u * p.k + c] = total;
        result[3u * p.k + c] = bf;
    }
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
