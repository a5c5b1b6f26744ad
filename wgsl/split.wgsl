// Split statistics for fast-mode k-medoids, mirroring src/strategy/kmedoids.rs `overflowing` and
// `farthest_members`:
//   stats   per cluster (one thread each): distinct vertices (only for clusters within the
//           triangle limit, as the CPU checks triangles first) and the farthest member (largest
//           distance, lowest id)
//
// A corner counts as a new vertex when no earlier corner of its triangle and no lower-numbered
// member triangle has the same vertex; the vertex -> triangle rows (ascending) answer the second
// test in a few reads, where comparing all 3m corners pairwise cost O(m^2) per cluster.

struct Params { t: u32, k: u32, d: u32, slot: u32, max_v: u32, max_t: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> mem_off: array<u32>;
@group(0) @binding(2) var<storage, read> mem_items: array<u32>;
@group(0) @binding(3) var<storage, read> labels: array<u32>;
@group(0) @binding(4) var<storage, read> dist: array<u32>;
// [2k, 3k) distinct vertices, [3k, 4k) farthest member (the layout of update.wgsl's result).
@group(0) @binding(5) var<storage, read_write> result: array<u32>;
@group(0) @binding(6) var<storage, read> idx_a: array<u32>;
@group(0) @binding(7) var<storage, read> idx_b: array<u32>;
@group(0) @binding(8) var<storage, read> vt_off: array<u32>;
@group(0) @binding(9) var<storage, read> vt_a: array<u32>;
@group(0) @binding(10) var<storage, read> vt_b: array<u32>;

fn idx(i: u32) -> u32 { if (i < PART) { return idx_a[i]; } return idx_b[i - PART]; }
fn vt(i: u32) -> u32 { if (i < PART) { return vt_a[i]; } return vt_b[i - PART]; }

// Whether a member of cluster c below triangle t uses vertex v.
fn seen_before(v: u32, t: u32, c: u32) -> bool {
    for (var i = vt_off[v]; i < vt_off[v + 1u]; i++) {
        let u = vt(i);
        if (u >= t) { return false; }
        if (labels[u] == c) { return true; }
    }
    return false;
}

@compute @workgroup_size(64)
fn stats(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c >= p.k) { return; }
    let off = mem_off[c];
    let m = mem_off[c + 1u] - off;
    var far = NONE;
    var fd = 0u;
    var distinct = 0u;
    for (var i = 0u; i < m; i++) {
        let t = mem_items[off + i];
        let dt = dist[t];
        if (far == NONE || dt > fd || (dt == fd && t < far)) {
            far = t;
            fd = dt;
        }
        if (m <= p.max_t) {
            let a = idx(3u * t);
            let b = idx(3u * t + 1u);
            let e = idx(3u * t + 2u);
            distinct += u32(!seen_before(a, t, c));
            distinct += u32(b != a && !seen_before(b, t, c));
            distinct += u32(e != a && e != b && !seen_before(e, t, c));
        }
    }
    result[2u * p.k + c] = distinct;
    result[3u * p.k + c] = far;
}
