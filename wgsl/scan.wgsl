// Exclusive prefix sum of u32 in place, in three passes: block sums, a scan of the block sums in
// one workgroup, then each block scanned with its offset. A block is 64 threads x 16 items; the
// one-workgroup middle pass handles any number of blocks (serial chunks per thread).

struct Params { n: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

const ITEMS: u32 = 16u;
const BLOCK: u32 = 1024u; // 64 * ITEMS

var<workgroup> part: array<u32, 64>;

// Exclusive scan of part[] by thread 0 (64 values: cheaper than a tree with barriers on lavapipe).
fn scan_part(lid: u32) -> u32 {
    workgroupBarrier();
    if (lid == 0u) {
        var acc = 0u;
        for (var i = 0u; i < 64u; i++) {
            let v = part[i];
            part[i] = acc;
            acc += v;
        }
    }
    workgroupBarrier();
    return part[lid];
}

// Sum of the thread's ITEMS elements from base (those below n).
fn thread_sum(base: u32) -> u32 {
    var s = 0u;
    for (var i = 0u; i < ITEMS; i++) {
        if (base + i < p.n) { s += data[base + i]; }
    }
    return s;
}

@compute @workgroup_size(64)
fn block_sums(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let g = group(wid);
    part[lid] = thread_sum(g * BLOCK + lid * ITEMS);
    workgroupBarrier();
    if (lid == 0u) {
        var t = 0u;
        for (var i = 0u; i < 64u; i++) { t += part[i]; }
        sums[g] = t;
    }
}

@compute @workgroup_size(64)
fn scan_sums(@builtin(local_invocation_index) lid: u32) {
    let blocks = (p.n + BLOCK - 1u) / BLOCK;
    let chunk = (blocks + 63u) / 64u;
    let lo = min(lid * chunk, blocks);
    let hi = min(lo + chunk, blocks);
    var s = 0u;
    for (var i = lo; i < hi; i++) { s += sums[i]; }
    part[lid] = s;
    var acc = scan_part(lid);
    for (var i = lo; i < hi; i++) {
        let v = sums[i];
        sums[i] = acc;
        acc += v;
    }
}

@compute @workgroup_size(64)
fn scan_blocks(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let g = group(wid);
    let base = g * BLOCK + lid * ITEMS;
    part[lid] = thread_sum(base);
    var acc = scan_part(lid) + sums[g];
    for (var i = 0u; i < ITEMS; i++) {
        if (base + i < p.n) {
            let v = data[base + i];
            data[base + i] = acc;
            acc += v;
        }
    }
}
