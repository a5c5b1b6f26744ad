//! Cluster LOD: the Clustered Meshlet Optimizer's meshlet DAG: the build, the CMO data, the CPU
//! selection rules and the checks here; the same selection runs in a wgpu kernel
//! (`gpu::select`) and in the task shader (`render`, `glsl/lod.glsl`), and `bench lod` compares
//! the DAG with meshoptimizer's clusterlod.
//!
//! Level 0 is the meshlets of any strategy. Each further level partitions the current meshlets into
//! groups of about [`Config::group_size`] edge-adjacent meshlets (meshoptimizer's
//! `partition_clusters`, fed each meshlet's welded vertices), merges each group, simplifies it to
//! half its triangles with the vertices it shares with other groups locked (meshoptimizer's
//! simplifier is the reducer), and splits the result into new meshlets with the same strategy.
//! Every meshlet carries its own bounds and error and its group's ("parent") bounds and error:
//!
//! * a group's error is the largest of its children's errors and the simplifier's (absolute) error,
//!   so errors never decrease upward;
//! * a group's sphere encloses every child's sphere (radius >= child radius + centre distance,
//!   rounded up), so the projected error test is monotonic along every DAG path.
//!
//! With those two rules the per-meshlet test "my own error is invisible and my parent's is visible"
//! ([`select`]) selects exactly one meshlet on every path from a level-0 meshlet to a root: a
//! crack-free cut, decided independently per meshlet.
//!
//! **Welding.** Simplification and locking work on welded vertices (positions that coincide are one
//! vertex, meshoptimizer's `generate_position_remap`), so an unwelded or faceted input still
//! reduces. Level 0 keeps the source's own indices (the validator checks it against the source);
//! levels above use the welded (lowest) index of each position.
//!
//! **Stuck groups.** A group whose simplification keeps more than [`Config::stuck_ratio`] of its
//! triangles is stuck: its meshlets are carried to the next level unchanged (a pass-through group
//! with their error and bounds), so every level covers the whole surface and streaming stays
//! crack-free. A level where no group reduces ends the build; its meshlets are the roots. A single
//! root meshlet is halved again while it has more than [`Config::min_root_triangles`] triangles.
//!
//! **Determinism.** Groups are built in parallel with rayon and collected in group order; the
//! partitioner, simplifier and strategies are deterministic, so the output is identical for any
//! thread count.

pub mod camera;
pub mod flat;
pub mod group;
#[cfg(feature = "io")]
pub mod io;
pub mod select;

use crate::mesh::Mesh;
use crate::meshlet::bounds::Sphere;
use crate::meshlet::{Limits, Meshlet, Meshlets};
use crate::strategy::Strategy;
use glam::DVec3;
use rayon::prelude::*;

/// How the meshlets of a level are grouped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Grouping {
    /// meshoptimizer's `partition_clusters` over welded vertices and positions.
    #[default]
    Meshopt,
    /// Our k-medoids on the meshlet graph (`group::kmedoids`).
    KMedoids,
}

/// Build settings.
#[derive(Clone, Copy, Debug)]
pub struct Config {
    /// How meshlets are grouped.
    pub grouping: Grouping,
    /// Target meshlets per group, at least 1 (meshoptimizer's clusterlod uses 16 at 128
    /// triangles; 8 keeps groups near 500 triangles at 64/126, which simplify well and keep locked
    /// borders short).
    pub group_size: usize,
    /// A group keeping more than this share of its triangles is stuck.
    pub stuck_ratio: f64,
    /// Most levels (a safety net; the build stops long before on real meshes).
    pub max_levels: usize,
    /// Level 0 is built in chunks of this many triangles (consecutive in Morton order of their
    /// centroids), in parallel; 0 builds it in one call. Chunks depend only on the mesh, so the
    /// output is the same for any thread count.
    pub level0_chunk: usize,
    /// A single root meshlet with more triangles than this is simplified further.
    pub min_root_triangles: usize,
    /// Simplify in meshoptimizer's permissive mode (collapses across attribute seams allowed; what
    /// clod uses by default).
    pub permissive: bool,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            group_size: 8,
            stuck_ratio: 0.85,
            grouping: Grouping::Meshopt,
            max_levels: 32,
            min_root_triangles: 8,
            level0_chunk: 1 << 17,
            permissive: false,
        }
    }
}

/// LOD data of one meshlet (the CMO's per-meshlet record).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct LodInfo {
    /// Bounds of the geometry this meshlet simplifies (its own sphere at level 0, else the sphere of
    /// the group that produced it).
    pub bounds: Sphere,
    /// Its error (0 at level 0, else the producing group's error).
    pub error: f32,
    /// Bounds of the group it is simplified in (the same as `bounds` for a root).
    pub parent_bounds: Sphere,
    /// That group's error; infinite for a root.
    pub parent_error: f32,
    /// The group it belongs to as a child ([`NO_GROUP`] for a root).
    pub group: u32,
}

/// `LodInfo::group` of a root.
pub const NO_GROUP: u32 = crate::common::NONE;

/// One level: its meshlets (the existing model, global vertex indices) and their LOD data.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// The meshlets.
    pub meshlets: Meshlets,
    /// LOD data, one per meshlet.
    pub info: Vec<LodInfo>,
}

/// One group: a set of meshlets of one level simplified together.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Group {
    /// Level of its children.
    pub level: u32,
    /// Its outputs: meshlets `first..first + count` of level `level + 1`.
    pub first: u32,
    /// See `first`.
    pub count: u32,
    /// Triangles before and after simplification.
    pub triangles_in: u32,
    /// See `triangles_in`.
    pub triangles_out: u32,
    /// Kept more than the stuck ratio (its outputs are its children, carried over).
    pub stuck: bool,
}

/// A meshlet DAG. Levels are numbered from the source (0) up; the file stores them coarsest first.
#[derive(Clone, Debug, PartialEq)]
pub struct Lod {
    /// Limits every meshlet respects.
    pub limits: Limits,
    /// Strategy of every level's split.
    pub strategy: String,
    /// Level 0 (the source's meshlets) first.
    pub levels: Vec<Level>,
    /// Every group, level by level.
    pub groups: Vec<Group>,
}

impl Lod {
    /// Meshlets over all levels.
    pub fn meshlet_count(&self) -> usize {
        self.levels.iter().map(|l| l.meshlets.len()).sum()
    }
    /// Triangles over all levels.
    pub fn triangle_count(&self) -> usize {
        self.levels.iter().map(level_triangles).sum()
    }
    /// Groups that were stuck.
    pub fn stuck_groups(&self) -> usize {
        self.groups.iter().filter(|g| g.stuck).count()
    }
    /// Meshlets with no parent.
    pub fn roots(&self) -> usize {
        self.levels
            .iter()
            .flat_map(|l| &l.info)
            .filter(|i| i.group == NO_GROUP)
            .count()
    }
}

/// Triangles of one level.
pub fn level_triangles(l: &Level) -> usize {
    l.meshlets
        .meshlets
        .iter()
        .map(|m| m.triangle_count as usize)
        .sum()
}

/// The welded index of every vertex: the lowest index with the same position.
pub fn weld(mesh: &Mesh) -> Vec<u32> {
    let adapter = meshopt::VertexDataAdapter::new(mesh.position_bytes(), 12, 0)
        .expect("stride 12 over f32x3 positions is valid");
    meshopt::generate_position_remap(&adapter)
}

/// A meshlet under construction: welded triangles and LOD data.
pub(crate) struct Cluster {
    pub(crate) tris: Vec<[u32; 3]>,
    pub(crate) bounds: Sphere,
    pub(crate) error: f32,
}

/// Builds the DAG over `mesh` with `strategy` at `limits`.
pub fn build(mesh: &Mesh, strategy: &dyn Strategy, limits: Limits, cfg: &Config) -> Lod {
    let level0 = level_zero(mesh, strategy, limits, cfg.level0_chunk);
    build_from(mesh, level0, strategy, limits, cfg)
}

/// [`build`] over a level 0 made elsewhere (a clustering brought in from another tool): the
/// levels above are `strategy`'s splits. `level0` must be `mesh`'s meshlets within `limits`
/// (see [`crate::meshlet::validate`]).
pub fn build_from(
    mesh: &Mesh,
    level0: Meshlets,
    strategy: &dyn Strategy,
    limits: Limits,
    cfg: &Config,
) -> Lod {
    let remap = weld(mesh);
    let mut levels = vec![Level {
        info: (0..level0.len())
            .into_par_iter()
            .map(|i| {
                let b = sphere_of(mesh, level0.global_triangles(i).flatten());
                LodInfo {
                    bounds: b,
                    error: 0.0,
                    parent_bounds: b,
                    parent_error: f32::INFINITY,
                    group: NO_GROUP,
                }
            })
            .collect(),
        meshlets: level0,
    }];
    let mut groups: Vec<Group> = Vec::new();
    while levels.len() < cfg.max_levels {
        let cur = levels.last().expect("level 0 exists");
        // A lone root keeps being halved down to `min_root_triangles`: the farthest views draw
        // the root, so its size is what they cost (clod stops at one cluster; measured on the
        // neurons, ours then drew 2.2x clod's triangles from 6 to 48 radii).
        if cur.meshlets.len() <= 1 && level_triangles(cur) <= cfg.min_root_triangles {
            break;
        }
        let clusters: Vec<Cluster> = (0..cur.meshlets.len())
            .into_par_iter()
            .map(|i| Cluster {
                tris: cur
                    .meshlets
                    .global_triangles(i)
                    .map(|t| t.map(|v| remap[v as usize]))
                    .collect(),
                bounds: cur.info[i].bounds,
                error: cur.info[i].error,
            })
            .collect();
        let parts = match cfg.grouping {
            // A group size of 0 would reach meshoptimizer's partitioner, which asserts it is not.
            Grouping::Meshopt => group_with_meshopt(mesh, &clusters, cfg.group_size.max(1)),
            Grouping::KMedoids => {
                group::kmedoids(mesh.vertex_count(), &clusters, cfg.group_size.max(1))
            }
        };
        let locked = shared_vertices(mesh.vertex_count(), &clusters, &parts);
        let level = (levels.len() - 1) as u32;
        let built: Vec<Reduced> = parts
            .par_iter()
            .map(|members| reduce(mesh, strategy, limits, cfg, &clusters, members, &locked))
            .collect();
        if built.iter().all(|b| b.stuck) {
            break;
        }
        // Record the groups, the children's parent data and the next level.
        let mut next = Level {
            meshlets: Meshlets::default(),
            info: Vec::new(),
        };
        let local: Vec<Vec<(Vec<u32>, Vec<u8>)>> = built
            .par_iter()
            .map(|r| r.out.iter().map(|c| local_meshlet(&c.tris)).collect())
            .collect();
        let cur = levels.last_mut().expect("level exists");
        for ((members, r), local) in parts.iter().zip(built).zip(&local) {
            let g = groups.len() as u32;
            for &c in members {
                cur.info[c].parent_bounds = r.bounds;
                cur.info[c].parent_error = r.error;
                cur.info[c].group = g;
            }
            let first = next.meshlets.len() as u32;
            let tin: usize = members.iter().map(|&c| clusters[c].tris.len()).sum();
            let tout: usize = r.out.iter().map(|c| c.tris.len()).sum();
            for (c, m) in r.out.iter().zip(local) {
                push_meshlet(&mut next.meshlets, m);
                next.info.push(LodInfo {
                    bounds: c.bounds,
                    error: c.error,
                    parent_bounds: c.bounds,
                    parent_error: f32::INFINITY,
                    group: NO_GROUP,
                });
            }
            groups.push(Group {
                level,
                first,
                count: r.out.len() as u32,
                triangles_in: tin as u32,
                triangles_out: tout as u32,
                stuck: r.stuck,
            });
        }
        levels.push(next);
    }
    Lod {
        limits,
        strategy: strategy.name().to_string(),
        levels,
        groups,
    }
}

/// Partitions clusters into groups of about `size` (meshoptimizer's partitioner over welded
/// vertices and positions); groups listed in order of their first cluster.
fn group_with_meshopt(mesh: &Mesh, clusters: &[Cluster], size: usize) -> Vec<Vec<usize>> {
    let mut indices = Vec::new();
    let mut counts = Vec::with_capacity(clusters.len());
    for c in clusters {
        let mut vs: Vec<u32> = c.tris.iter().flatten().copied().collect();
        vs.sort_unstable();
        vs.dedup();
        counts.push(vs.len() as u32);
        indices.extend(vs);
    }
    let adapter = meshopt::VertexDataAdapter::new(mesh.position_bytes(), 12, 0)
        .expect("stride 12 over f32x3 positions is valid");
    let mut part = vec![0u32; clusters.len()];
    let n =
        meshopt::partition_clusters_with_positions(&mut part, &indices, &counts, &adapter, size);
    let mut groups = vec![Vec::new(); n];
    for (c, &p) in part.iter().enumerate() {
        groups[p as usize].push(c);
    }
    groups.retain(|g| !g.is_empty());
    groups.sort_by_key(|g| g[0]);
    groups
}

/// Welded vertices used by clusters of two or more groups: they stay where they are, so
/// neighbouring groups keep meeting along the same edges whatever each simplifies to.
fn shared_vertices(n: usize, clusters: &[Cluster], parts: &[Vec<usize>]) -> Vec<bool> {
    let mut owner = vec![u32::MAX; n];
    let mut shared = vec![false; n];
    for (g, members) in parts.iter().enumerate() {
        for &c in members {
            for &v in clusters[c].tris.iter().flatten() {
                let o = &mut owner[v as usize];
                if *o == u32::MAX {
                    *o = g as u32;
                } else if *o != g as u32 {
                    shared[v as usize] = true;
                }
            }
        }
    }
    shared
}

/// One group's result.
struct Reduced {
    /// The new meshlets (the children themselves when stuck).
    out: Vec<Cluster>,
    /// The group's bounds and error.
    bounds: Sphere,
    error: f32,
    stuck: bool,
}

/// Merges, simplifies and splits one group.
fn reduce(
    mesh: &Mesh,
    strategy: &dyn Strategy,
    limits: Limits,
    cfg: &Config,
    clusters: &[Cluster],
    members: &[usize],
    locked: &[bool],
) -> Reduced {
    let merged: Vec<u32> = members
        .iter()
        .flat_map(|&c| clusters[c].tris.iter().flatten().copied())
        .collect();
    // Padded so the cut-bit selection test stays monotonic (select::PAD).
    let children_error = pad(members
        .iter()
        .map(|&c| clusters[c].error)
        .fold(0.0f32, f32::max));
    let adapter = meshopt::VertexDataAdapter::new(mesh.position_bytes(), 12, 0)
        .expect("stride 12 over f32x3 positions is valid");
    let target = (merged.len() / 3 / 2) * 3;
    let opts = meshopt::SimplifyOptions::Sparse | meshopt::SimplifyOptions::ErrorAbsolute;
    let mut err = 0.0f32;
    let mut simplified = meshopt::simplify_with_locks(
        &merged,
        &adapter,
        locked,
        target,
        f32::MAX,
        if cfg.permissive {
            opts | meshopt::SimplifyOptions::Permissive
        } else {
            opts
        },
        Some(&mut err),
    );
    cancel_fins(&mut simplified, &merged);
    let child_bounds: Vec<Sphere> = members.iter().map(|&c| clusters[c].bounds).collect();
    let bounds = enclosing(&child_bounds);
    // An empty result (an open sheet simplified away) would leave no meshlet: stuck too.
    let stuck =
        simplified.is_empty() || simplified.len() as f64 > cfg.stuck_ratio * merged.len() as f64;
    if stuck {
        // Carried over unchanged: same triangles, same error.
        let out = members
            .iter()
            .map(|&c| Cluster {
                tris: clusters[c].tris.clone(),
                bounds,
                error: children_error,
            })
            .collect();
        return Reduced {
            out,
            bounds,
            error: children_error,
            stuck: true,
        };
    }
    let error = children_error.max(err);
    let out = split(mesh, strategy, limits, &simplified)
        .into_iter()
        .map(|tris| Cluster {
            tris,
            bounds,
            error,
        })
        .collect();
    Reduced {
        out,
        bounds,
        error,
        stuck: false,
    }
}

/// Sorted corners and winding parity (true: an even rotation of the sorted order).
fn key(c: &[u32]) -> ([u32; 3], bool) {
    let mut k = [c[0], c[1], c[2]];
    k.sort_unstable();
    // The rotation starting at the smallest corner tells the winding.
    let even = match c.iter().position(|&v| v == k[0]) {
        Some(0) => c[1] == k[1],
        Some(1) => c[2] == k[1],
        _ => c[0] == k[1],
    };
    (k, even)
}

/// Removes pairs of triangles over the same three vertices in opposite windings that the
/// simplifier created (pairs already in `input`, a two-sided sheet of the source, stay). The
/// simplifier occasionally folds a thin pocket into such a two-sided fin (measured: about one per
/// level on the noisy sphere); it covers no area, but its edges would be used four times and make
/// a closed cut non-manifold. Returns the number of triangles removed.
fn cancel_fins(idx: &mut Vec<u32>, input: &[u32]) -> usize {
    use std::collections::{HashMap, HashSet};
    let mut sides: HashMap<[u32; 3], (bool, bool)> = HashMap::new();
    for c in input.chunks_exact(3) {
        let (k, even) = key(c);
        let e = sides.entry(k).or_default();
        if even {
            e.0 = true
        } else {
            e.1 = true
        }
    }
    let two_sided: HashSet<[u32; 3]> = sides
        .into_iter()
        .filter(|(_, (a, b))| *a && *b)
        .map(|(k, _)| k)
        .collect();
    // Per key: indices of triangles per winding (even, odd).
    let mut seen: HashMap<[u32; 3], (Vec<usize>, Vec<usize>)> = HashMap::new();
    for (t, c) in idx.chunks_exact(3).enumerate() {
        let (k, even) = key(c);
        if two_sided.contains(&k) {
            continue;
        }
        let e = seen.entry(k).or_default();
        if even {
            e.0.push(t)
        } else {
            e.1.push(t)
        }
    }
    let mut drop = vec![false; idx.len() / 3];
    for (a, b) in seen.values() {
        for (&x, &y) in a.iter().zip(b) {
            drop[x] = true;
            drop[y] = true;
        }
    }
    let removed = drop.iter().filter(|&&d| d).count();
    if removed > 0 {
        let kept: Vec<u32> = idx
            .chunks_exact(3)
            .zip(&drop)
            .filter(|(_, &d)| !d)
            .flat_map(|(c, _)| c.iter().copied())
            .collect();
        *idx = kept;
    }
    removed
}

/// Splits welded triangles into meshlets with `strategy` (on a compacted sub-mesh).
fn split(mesh: &Mesh, strategy: &dyn Strategy, limits: Limits, idx: &[u32]) -> Vec<Vec<[u32; 3]>> {
    let mut local = std::collections::HashMap::new();
    let mut back = Vec::new();
    let indices: Vec<u32> = idx
        .iter()
        .map(|&v| {
            *local.entry(v).or_insert_with(|| {
                back.push(v);
                (back.len() - 1) as u32
            })
        })
        .collect();
    let sub = Mesh {
        positions: back.iter().map(|&v| mesh.positions[v as usize]).collect(),
        indices,
    };
    let ml = strategy.build(&sub, limits);
    (0..ml.len())
        .map(|i| {
            ml.global_triangles(i)
                .map(|t| t.map(|v| back[v as usize]))
                .collect()
        })
        .collect()
}

/// Level 0: the strategy's meshlets of the source, with the source's own vertex indices. Above
/// `chunk` triangles the mesh is cut into chunks of `chunk` triangles consecutive in Morton order
/// (a space-filling curve, so each chunk is compact), built in parallel and concatenated in chunk
/// order: meshlets cannot cross a chunk border, which costs a few meshlets per chunk (measured on
/// the dragon: see `bench lod`) and turns the largest serial step into a parallel one.
fn level_zero(mesh: &Mesh, strategy: &dyn Strategy, limits: Limits, chunk: usize) -> Meshlets {
    let n = mesh.triangle_count();
    if chunk == 0 || n <= chunk {
        return strategy.build(mesh, limits);
    }
    let (lo, hi) = mesh.bounding_box();
    let scale = (hi - lo).max_element().max(f32::MIN_POSITIVE);
    let mut order: Vec<(u64, u32)> = (0..n as u32)
        .into_par_iter()
        .map(|t| {
            let [a, b, c] = mesh.triangle(t as usize);
            let p = |v: u32| glam::Vec3::from_array(mesh.positions[v as usize]);
            let q = ((p(a) + p(b) + p(c)) / 3.0 - lo) / scale * 2_097_151.0;
            (
                crate::common::morton3(q.x as u32, q.y as u32, q.z as u32),
                t,
            )
        })
        .collect();
    order.par_sort_unstable();
    let parts: Vec<Vec<(Vec<u32>, Vec<u8>)>> = order
        .par_chunks(chunk)
        .map(|c| {
            let idx: Vec<u32> = c
                .iter()
                .flat_map(|&(_, t)| mesh.triangle(t as usize))
                .collect();
            split(mesh, strategy, limits, &idx)
                .iter()
                .map(|tris| local_meshlet(tris))
                .collect()
        })
        .collect();
    let mut ml = Meshlets::default();
    for m in parts.iter().flatten() {
        push_meshlet(&mut ml, m);
    }
    ml
}

/// Appends one meshlet made by [`local_meshlet`].
fn push_meshlet(ml: &mut Meshlets, (vertices, corners): &(Vec<u32>, Vec<u8>)) {
    ml.meshlets.push(Meshlet {
        vertex_offset: ml.vertices.len() as u32,
        triangle_offset: ml.triangles.len() as u32,
        vertex_count: vertices.len() as u32,
        triangle_count: (corners.len() / 3) as u32,
    });
    ml.vertices.extend_from_slice(vertices);
    ml.triangles.extend_from_slice(corners);
}

/// A meshlet's vertex list (first-use order) and local corners, from global triangles; the
/// per-meshlet work of [`push_meshlet`], done in parallel.
fn local_meshlet(tris: &[[u32; 3]]) -> (Vec<u32>, Vec<u8>) {
    let mut local: Vec<u32> = Vec::new();
    let mut corners = Vec::with_capacity(3 * tris.len());
    for t in tris {
        for &v in t {
            let l = match local.iter().position(|&x| x == v) {
                Some(l) => l,
                None => {
                    local.push(v);
                    local.len() - 1
                }
            };
            corners.push(l as u8);
        }
    }
    (local, corners)
}

/// The minimal sphere of the given vertices (f32, conservative).
fn sphere_of(mesh: &Mesh, vs: impl Iterator<Item = u32>) -> Sphere {
    let pts: Vec<DVec3> = vs
        .map(|v| DVec3::from_array(mesh.positions[v as usize].map(f64::from)))
        .collect();
    crate::meshlet::bounds::bounding_sphere(&pts)
}

/// The group's sphere: one that encloses every child sphere (so it encloses the group's geometry
/// too). Its centre is meshoptimizer's sphere-of-spheres bound (as clod's `boundsMerge`); the
/// radius is re-measured as the largest `|centre - c_i| + r_i` in f64 and rounded up with the
/// relative margin [`select::PAD`] so the cut-bit selection test stays monotonic.
///
/// Measured: centring on the merged vertices' minimal sphere instead (our first version) let
/// radii compound level over level to 2.5x the whole mesh's radius at the top of the bunny's DAG,
/// which makes coarse errors visible from twice as far and drew up to 2x clod's triangles.
fn enclosing(children: &[Sphere]) -> Sphere {
    let centres: Vec<[f32; 3]> = children.iter().map(|s| s.center).collect();
    let radii: Vec<f32> = children.iter().map(|s| s.radius).collect();
    let merged = meshopt::compute_sphere_bounds(
        meshopt::PositionDataAdapter {
            data: bytemuck::cast_slice(&centres),
            position_count: centres.len(),
            position_stride: 12,
            position_offset: 0,
        },
        Some(meshopt::RadiusDataAdapter {
            data: bytemuck::cast_slice(&radii),
            radius_count: radii.len(),
            radius_stride: 4,
            radius_offset: 0,
        }),
    );
    let c = DVec3::from_array(merged.center.map(f64::from));
    let r = children
        .iter()
        .map(|ch| (DVec3::from_array(ch.center.map(f64::from)) - c).length() + ch.radius as f64)
        .fold(0.0, f64::max);
    Sphere {
        center: merged.center,
        radius: pad(r as f32).max(((r * (1.0 + select::PAD)) as f32).next_up()),
    }
}

/// `x * (1 + select::PAD)`, rounded up (0 stays 0).
fn pad(x: f32) -> f32 {
    if x > 0.0 {
        ((x as f64 * (1.0 + select::PAD)) as f32).next_up()
    } else {
        x
    }
}
