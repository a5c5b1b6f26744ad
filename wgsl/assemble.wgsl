// Meshlets assembled on the device from a clustering (a group per triangle and an order key),
// step for step the CPU's meshlet::assemble_groups, with identical meshlets:
//   count                      triangles per group (atomic add)
//   scan(toff)                 group -> first triangle slot (exclusive)
//   place                      triangle ids into their group's slots (any order within a group)
//   sort_count                 per group: members sorted by (key, id) (each one's rank among
//                              them, through a histogram of keys below 256), distinct vertices
//                              counted, local corners written (a vertex's local index is the
//                              number of distinct vertices before its first use)
//   scan(voff), scan(mindex)   group -> first vertex; non-empty group -> meshlet index
//   write                      per triangle slot: the vertices its local corners name, and the
//                              meshlet record at a group's first slot
//
// sort_count runs one workgroup per group (a group fits the limits, so at most 256 triangles and
// 768 corners). The ranks decide the order inside a group whatever order place left it in, and
// first use is the lowest corner holding a vertex: nothing depends on scheduling. write needs no
// first-use pass of its own: every corner of a vertex carries the same local index, so the
// corners that write one vertex slot write the same value.
// Integers only. A group over the limits is counted in counters[0] (the host refuses the result;
// the strategies that feed this never make one).

struct Params { t: u32, g: u32, max_v: u32, max_t: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> idx_a: array<u32>;
@group(0) @binding(2) var<storage, read> idx_b: array<u32>;
// Group of each triangle (< g).
@group(0) @binding(3) var<storage, read> owner: array<u32>;
// Order key of each triangle inside its group (ties to the lower triangle id).
@group(0) @binding(4) var<storage, read> key: array<u32>;
// g + 1: triangles per group, scanned into first slots.
@group(0) @binding(5) var<storage, read_write> toff: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> cursor: array<atomic<u32>>;
// Triangle ids by group; sorted within each group by sort_count.
@group(0) @binding(7) var<storage, read_write> members: array<u32>;
// g + 1: distinct vertices per group, scanned into first vertex slots.
@group(0) @binding(8) var<storage, read_write> voff: array<u32>;
// g + 1: 1 per non-empty group, scanned into meshlet indices.
@group(0) @binding(9) var<storage, read_write> mindex: array<u32>;
// Out: vertex_offset, triangle_offset (bytes), vertex_count, triangle_count per meshlet.
@group(0) @binding(10) var<storage, read_write> meshlets: array<u32>;
// Out: global vertex indices.
@group(0) @binding(11) var<storage, read_write> vertices: array<u32>;
// Out: local corners, one byte each, four to a word (little-endian), so ORed in.
@group(0) @binding(12) var<storage, read_write> triangles: array<atomic<u32>>;
// [0] groups over the limits.
@group(0) @binding(13) var<storage, read_write> counters: array<atomic<u32>>;

fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }

const SLOTS: u32 = 256u;
const CORNERS: u32 = 768u;

var<workgroup> sk: array<u32, SLOTS>;
var<workgroup> st: array<u32, SLOTS>;
// Per corner: its vertex, then the first corner with that vertex.
var<workgroup> cv: array<u32, CORNERS>;
var<workgroup> first: array<u32, CORNERS>;
// Per corner: distinct vertices among the corners before it (the local index of a first use).
var<workgroup> rank: array<u32, CORNERS>;
var<workgroup> wn: u32;
// sort_count's histogram of keys below KEYS (the strategies' keys, hop distances and growth
// orders inside a group, are below its triangle limit): per key its members,
// its first place, and the members bucketed so far; `bucket` lists slots by key.
const KEYS: u32 = 256u;
var<workgroup> kcount: array<atomic<u32>, KEYS>;
var<workgroup> kfill: array<atomic<u32>, KEYS>;
var<workgroup> kbase: array<u32, KEYS>;
var<workgroup> bucket: array<u32, SLOTS>;
var<workgroup> kmax: atomic<u32>;
var<workgroup> wk: u32;
// First-use table: 1024 slots (2^10, hence the shift in the hash) for at most 768 corners.
const TABLE: u32 = 1024u;
var<workgroup> table_vertex: array<atomic<u32>, TABLE>;
var<workgroup> table_first: array<atomic<u32>, TABLE>;

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t < p.t) { atomicAdd(&toff[owner[t]], 1u); }
}

@compute @workgroup_size(64)
fn place(@builtin(global_invocation_id) gid: vec3<u32>) {
    let t = flat(gid);
    if (t >= p.t) { return; }
    let o = owner[t];
    members[atomicLoad(&toff[o]) + atomicAdd(&cursor[o], 1u)] = t;
}

// Triangles of group g, uniform across the workgroup; 0 for an empty group, NONE over the limit.
fn group_size(g: u32, lid: u32) -> u32 {
    if (lid == 0u) {
        let n = atomicLoad(&toff[g + 1u]) - atomicLoad(&toff[g]);
        wn = select(n, NONE, n > p.max_t);
    }
    return workgroupUniformLoad(&wn);
}

// Fills cv, first and rank for the n sorted triangles from slot s; returns the distinct vertices.
// First uses through a hash table in workgroup memory: each corner inserts its vertex (linear
// probing) and lowers the slot's corner to its own, so a slot ends holding the vertex's first
// corner whatever the order of the threads (which slot a vertex lands in may vary; its first
// corner does not).
fn first_uses(s: u32, n: u32, lid: u32) -> u32 {
    for (var h = lid; h < TABLE; h += 64u) {
        atomicStore(&table_vertex[h], NONE);
        atomicStore(&table_first[h], NONE);
    }
    for (var i = lid; i < 3u * n; i += 64u) {
        cv[i] = idx(3u * members[s + i / 3u] + i % 3u);
    }
    workgroupBarrier();
    for (var i = lid; i < 3u * n; i += 64u) {
        let v = cv[i];
        var h = (v * 2654435761u) >> 22u;
        loop {
            let r = atomicCompareExchangeWeak(&table_vertex[h], NONE, v);
            if (r.exchanged || r.old_value == v) { break; }
            // A weak exchange may fail on an empty slot: try it again.
            if (r.old_value != NONE) { h = (h + 1u) % TABLE; }
        }
        atomicMin(&table_first[h], i);
        first[i] = h;
    }
    workgroupBarrier();
    for (var i = lid; i < 3u * n; i += 64u) {
        first[i] = atomicLoad(&table_first[first[i]]);
    }
    workgroupBarrier();
    if (lid == 0u) {
        var d = 0u;
        for (var i = 0u; i < 3u * n; i++) {
            rank[i] = d;
            if (first[i] == i) { d++; }
        }
        wn = d;
    }
    return workgroupUniformLoad(&wn);
}

@compute @workgroup_size(64)
fn sort_count(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let g = group(wid);
    if (g >= p.g) { return; }
    let n = group_size(g, lid);
    if (n == 0u || n == NONE) {
        if (lid == 0u) {
            voff[g] = 0u;
            mindex[g] = 0u;
            if (n == NONE) { atomicAdd(&counters[0], 1u); }
        }
        return;
    }
    let s = atomicLoad(&toff[g]);
    for (var h = lid; h < KEYS; h += 64u) {
        atomicStore(&kcount[h], 0u);
        atomicStore(&kfill[h], 0u);
    }
    if (lid == 0u) { atomicStore(&kmax, 0u); }
    for (var i = lid; i < n; i += 64u) {
        st[i] = members[s + i];
        sk[i] = key[st[i]];
    }
    workgroupBarrier();
    // Each member's place is the number of members before it in (key, id) order: the pairs are
    // distinct, so the places are too. Keys below KEYS count through a histogram: the members of
    // smaller key, then those of the same key with a lower id (a bucket, not all n members).
    for (var i = lid; i < n; i += 64u) {
        atomicMax(&kmax, sk[i]);
        atomicAdd(&kcount[min(sk[i], KEYS - 1u)], 1u);
    }
    workgroupBarrier();
    if (lid == 0u) {
        wk = atomicLoad(&kmax);
        if (wk < KEYS) {
            var acc = 0u;
            for (var h = 0u; h <= wk; h++) {
                kbase[h] = acc;
                acc += atomicLoad(&kcount[h]);
            }
        }
    }
    if (workgroupUniformLoad(&wk) < KEYS) {
        for (var i = lid; i < n; i += 64u) {
            let k = sk[i];
            bucket[kbase[k] + atomicAdd(&kfill[k], 1u)] = i;
        }
        workgroupBarrier();
        for (var i = lid; i < n; i += 64u) {
            let b = kbase[sk[i]];
            var r = b;
            for (var x = b; x < b + atomicLoad(&kcount[sk[i]]); x++) {
                r += u32(st[bucket[x]] < st[i]);
            }
            members[s + r] = st[i];
        }
    } else {
        for (var i = lid; i < n; i += 64u) {
            var r = 0u;
            for (var j = 0u; j < n; j++) {
                r += u32(sk[j] < sk[i] || (sk[j] == sk[i] && st[j] < st[i]));
            }
            members[s + r] = st[i];
        }
    }
    storageBarrier();
    workgroupBarrier();
    let d = first_uses(s, n, lid);
    if (lid == 0u) {
        voff[g] = d;
        mindex[g] = 1u;
        if (d > p.max_v) { atomicAdd(&counters[0], 1u); }
    }
    // The mask keeps a group over the limits (refused by the host) inside its own bytes.
    for (var i = lid; i < 3u * n; i += 64u) {
        let b = 3u * s + i;
        atomicOr(&triangles[b / 4u], (rank[first[i]] & 0xffu) << (8u * (b % 4u)));
    }
}

@compute @workgroup_size(64)
fn write(@builtin(global_invocation_id) gid: vec3<u32>) {
    let j = flat(gid);
    if (j >= p.t) { return; }
    let x = members[j];
    let g = owner[x];
    let s = atomicLoad(&toff[g]);
    let v0 = voff[g];
    if (j == s) {
        let m = 4u * mindex[g];
        meshlets[m] = v0;
        meshlets[m + 1u] = 3u * s;
        meshlets[m + 2u] = voff[g + 1u] - v0;
        meshlets[m + 3u] = atomicLoad(&toff[g + 1u]) - s;
    }
    for (var c = 0u; c < 3u; c++) {
        let b = 3u * j + c;
        let local = (atomicLoad(&triangles[b / 4u]) >> (8u * (b % 4u))) & 0xffu;
        vertices[v0 + local] = idx(3u * x + c);
    }
}
