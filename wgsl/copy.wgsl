// The memory-bandwidth probe behind `bench gpu`'s physical limits. No CPU step mirrors it:
//   copy   dst[i] = src[i]: every word read once and written once, the least traffic any kernel
//          that touches an array can have; bytes moved over its time is the device's bandwidth.
// vec4 elements: the widest plain load and store WGSL has (16 bytes a lane). A grid-stride loop
// (Gpu::stride_groups): on lavapipe each workgroup costs a coroutine start, which a probe of
// memory speed must not measure.

struct Params { n: u32 }

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> src: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> dst: array<vec4<u32>>;

@compute @workgroup_size(64)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    for (var i = flat(gid); i < p.n; i += stride(nwg)) {
        dst[i] = src[i];
    }
}
