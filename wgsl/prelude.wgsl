// The prelude of every kernel module: src/gpu/mod.rs (`wgsl!`) puts it in front of each file here.
// One definition of what the modules share; gpu::shaders_test checks PART against the Rust side.

// Elements per part of a split array (gpu::PART, 2^25 u32 = 128 MiB: lavapipe's binding limit).
const PART: u32 = 33554432u;
// Largest coordinate of a fine centroid cell, 15 bits per axis (kmedoids::morton::FINE_MAX): the
// cells kmedoids-parallel's growth key measures distances in (morton.wgsl writes, kmedoids_parallel.wgsl reads).
const FINE_MAX: u32 = 32767u;
// "No index": an unassigned label, an unreached distance, a padded neighbour slot.
const NONE: u32 = 0xffffffffu;

// Flat thread id of a @workgroup_size(64) dispatch (Batch splits more than 65535 groups over y).
fn flat(gid: vec3<u32>) -> u32 { return gid.x + gid.y * 65535u * 64u; }
// Flat workgroup id of the same split.
fn group(wid: vec3<u32>) -> u32 { return wid.x + wid.y * 65535u; }
// Step of a grid-stride loop over a @workgroup_size(64) dispatch (few workgroups on a CPU adapter).
fn stride(nwg: vec3<u32>) -> u32 { return nwg.x * nwg.y * 64u; }

// A packed centroid cell (x | y << 16, z): its coordinates, and the squared distance between two
// (kmedoids::morton::{unpack, distance2}; kmedoids_parallel.wgsl's growth key, kmedoids_parallel_moves.wgsl's distance rule).
fn unpack_cell(xy: u32, z: u32) -> vec3<u32> { return vec3<u32>(xy & 0xffffu, xy >> 16u, z); }
fn cell_distance2(a: vec3<u32>, b: vec3<u32>) -> u32 {
    let e = max(a, b) - min(a, b);
    return e.x * e.x + e.y * e.y + e.z * e.z;
}
