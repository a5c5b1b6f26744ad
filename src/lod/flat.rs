//! The DAG as the GPU sees it: every level's meshlets in one array, **coarsest level first** (as in
//! the LOD file), each with one [`Record`] of LOD and culling data. Coarsest first makes every
//! streaming state a prefix: with levels `finest..` loaded, the loaded meshlets are
//! `0..Flat::loaded(finest)`.
//!
//! [`select_meshlets`] is the CPU reference of the selection kernel (`wgsl/select.wgsl`) and of the LOD
//! task shader (`glsl/meshlet_lod.task`): the streamed LOD rule of [`super::select`], then optional
//! frustum and normal-cone culling, all in the exact arithmetic that module describes.

use super::select::{backfacing, outside_frustum, should_render_streamed, View};
use super::{Level, Lod, LodInfo};
use crate::mesh::Mesh;
use crate::meshlet::bounds::{compute_bounds, Sphere};
use crate::meshlet::{Meshlet, Meshlets};

/// One meshlet's LOD and culling data, as the kernels read it (std430, 96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Record {
    /// LOD bounds: centre, radius.
    pub bounds: [f32; 4],
    /// Parent (group) bounds: centre, radius.
    pub parent: [f32; 4],
    /// The sphere of its own triangles, for frustum culling.
    pub sphere: [f32; 4],
    /// Normal cone: apex, cutoff (1 = never culls).
    pub apex_cutoff: [f32; 4],
    /// Normal cone axis, and the LOD error.
    pub axis_error: [f32; 4],
    /// Parent error (infinite for a root).
    pub parent_error: f32,
    /// Level (0 = the source's meshlets).
    pub level: u32,
    /// Triangles in the meshlet.
    pub triangles: u32,
    /// Zero.
    pub pad: u32,
}

impl Record {
    fn info(&self) -> LodInfo {
        let sphere = |v: [f32; 4]| Sphere {
            center: [v[0], v[1], v[2]],
            radius: v[3],
        };
        LodInfo {
            bounds: sphere(self.bounds),
            error: self.axis_error[3],
            parent_bounds: sphere(self.parent),
            parent_error: self.parent_error,
            group: 0,
        }
    }
}

/// All levels in one meshlet array with their records.
#[derive(Clone, Debug)]
pub struct Flat {
    /// Every level's meshlets, coarsest level first (global vertex indices into the source).
    pub meshlets: Meshlets,
    /// One record per meshlet.
    pub records: Vec<Record>,
    /// `starts[l]`: index of the first meshlet of level `l` (levels numbered from the source).
    pub starts: Vec<u32>,
}

impl Flat {
    /// Flattens `lod` over `mesh` (its source), computing each meshlet's culling bounds.
    pub fn new(mesh: &Mesh, lod: &Lod) -> Self {
        Self::from_levels(mesh, &lod.levels)
    }

    /// Flattens levels (level 0 first) of any DAG with the CMO's per-meshlet data, such as one
    /// converted from meshoptimizer's clusterlod for a side-by-side comparison.
    pub fn from_levels(mesh: &Mesh, levels: &[Level]) -> Self {
        let mut meshlets = Meshlets::default();
        let mut records = Vec::with_capacity(levels.iter().map(|l| l.meshlets.len()).sum());
        let mut starts = vec![0u32; levels.len()];
        for (l, level) in levels.iter().enumerate().rev() {
            starts[l] = meshlets.len() as u32;
            let ml = &level.meshlets;
            for (i, b) in compute_bounds(mesh, ml).into_iter().enumerate() {
                let m = ml.meshlets[i];
                meshlets.meshlets.push(Meshlet {
                    vertex_offset: meshlets.vertices.len() as u32,
                    triangle_offset: meshlets.triangles.len() as u32,
                    ..m
                });
                meshlets.vertices.extend_from_slice(ml.meshlet_vertices(i));
                meshlets
                    .triangles
                    .extend_from_slice(ml.meshlet_triangles(i));
                let info = &level.info[i];
                let s4 = |s: &Sphere| [s.center[0], s.center[1], s.center[2], s.radius];
                records.push(Record {
                    bounds: s4(&info.bounds),
                    parent: s4(&info.parent_bounds),
                    sphere: s4(&b.sphere),
                    apex_cutoff: [
                        b.cone.apex[0],
                        b.cone.apex[1],
                        b.cone.apex[2],
                        b.cone.cutoff,
                    ],
                    axis_error: [b.cone.axis[0], b.cone.axis[1], b.cone.axis[2], info.error],
                    parent_error: info.parent_error,
                    level: l as u32,
                    triangles: m.triangle_count,
                    pad: 0,
                });
            }
        }
        Self {
            meshlets,
            records,
            starts,
        }
    }

    /// Meshlets loaded when levels `finest..` are: a prefix of the array.
    pub fn loaded(&self, finest: usize) -> usize {
        loaded(&self.starts, self.records.len(), finest)
    }

    /// Meshlets of level `l`.
    pub fn level_len(&self, l: usize) -> usize {
        let end = if l == 0 {
            self.records.len()
        } else {
            self.starts[l - 1] as usize
        };
        end - self.starts[l] as usize
    }

    /// Levels in the DAG.
    pub fn levels(&self) -> usize {
        self.starts.len()
    }
}

/// Meshlets loaded when levels `finest..` are, given the level starts and the meshlet count: all
/// of them for level 0, else everything before level `finest - 1`.
pub fn loaded(starts: &[u32], total: usize, finest: usize) -> usize {
    if finest == 0 {
        total
    } else {
        starts[finest - 1] as usize
    }
}

/// One view as the selection kernel and the LOD task shader read it (std430, 128 bytes; `View` in
/// wgsl/select.wgsl, `LodView` in glsl/lod.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewData {
    /// Camera position and `k`.
    pub eye_k: [f32; 4],
    /// Frustum planes (ignored unless flag bit 0).
    pub planes: [[f32; 4]; 6],
    /// Finest loaded level.
    pub finest: u32,
    /// Meshlets loaded (a prefix of the flat array).
    pub loaded: u32,
    /// Bit 0: frustum culling; bit 1: normal-cone culling.
    pub flags: u32,
    /// Zero.
    pub pad: u32,
}

impl ViewData {
    /// The kernels' view of `q` with `loaded` meshlets loaded ([`Flat::loaded`]).
    pub fn new(q: &Query, loaded: usize) -> Self {
        let e = q.view.eye;
        Self {
            eye_k: [e[0], e[1], e[2], q.view.k],
            planes: q.frustum.unwrap_or([[0.0; 4]; 6]),
            finest: q.finest as u32,
            loaded: loaded as u32,
            flags: q.frustum.is_some() as u32 | (q.cone as u32) << 1,
            pad: 0,
        }
    }
}

/// What one selection sees: the camera, the loaded levels and the culling it applies.
#[derive(Clone, Copy, Debug)]
pub struct Query {
    /// Camera position and error scale.
    pub view: View,
    /// Finest loaded level (0 = everything loaded).
    pub finest: usize,
    /// Frustum planes (unit normals, inside where `n . x + w >= 0`), when frustum culling.
    pub frustum: Option<[[f32; 4]; 6]>,
    /// Normal-cone culling.
    pub cone: bool,
}

/// Why a loaded meshlet is not drawn, or that it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    /// Not on the cut for this view.
    NotSelected,
    /// On the cut, but outside the frustum.
    Frustum,
    /// On the cut, but facing away.
    Cone,
    /// Drawn.
    Drawn,
}

/// The decision for record `r` (the kernel's and the task shader's per-meshlet logic).
pub fn decide(r: &Record, q: &Query) -> Decision {
    let at_finest = r.level as usize == q.finest;
    if (r.level as usize) < q.finest || !should_render_streamed(&r.info(), at_finest, &q.view) {
        return Decision::NotSelected;
    }
    let sphere = Sphere {
        center: [r.sphere[0], r.sphere[1], r.sphere[2]],
        radius: r.sphere[3],
    };
    if q.frustum.is_some_and(|p| outside_frustum(&sphere, &p)) {
        return Decision::Frustum;
    }
    let apex = [r.apex_cutoff[0], r.apex_cutoff[1], r.apex_cutoff[2]];
    let axis = [r.axis_error[0], r.axis_error[1], r.axis_error[2]];
    if q.cone && backfacing(apex, axis, r.apex_cutoff[3], q.view.eye) {
        return Decision::Cone;
    }
    Decision::Drawn
}

/// The drawn meshlets (indices into the flat array, ascending) for `q`.
pub fn select_meshlets(flat: &Flat, q: &Query) -> Vec<u32> {
    flat.records[..flat.loaded(q.finest)]
        .iter()
        .enumerate()
        .filter(|(_, r)| decide(r, q) == Decision::Drawn)
        .map(|(i, _)| i as u32)
        .collect()
}

/// Unit frustum planes (Gribb-Hartmann, Vulkan depth 0..1) of a column-major view-projection
/// matrix, normalised on the CPU so the selection kernels read them as data.
pub fn frustum_planes(view_proj: &glam::Mat4) -> [[f32; 4]; 6] {
    let m = view_proj.transpose();
    let rows = [m.x_axis, m.y_axis, m.z_axis, m.w_axis];
    let raw = [
        rows[3] + rows[0],
        rows[3] - rows[0],
        rows[3] + rows[1],
        rows[3] - rows[1],
        rows[2],
        rows[3] - rows[2],
    ];
    raw.map(|p| {
        let len = p.truncate().length();
        let p = if len > 0.0 { p / len } else { p };
        p.to_array()
    })
}
