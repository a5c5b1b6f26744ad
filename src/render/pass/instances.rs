//! Instanced passes: a scene's meshes and their meshlets uploaded once, drawn once per instance.
//!
//! The meshes are concatenated (positions in object space, meshlets with their vertex and triangle
//! ranges moved on), so one descriptor set serves every mesh; each instance is one draw whose push
//! constants name the instance and its mesh's meshlet range. The task shader tests a meshlet's
//! sphere in world space (radius scaled by the instance's largest stretch) and its cone in the
//! instance's object space (`glsl/culling.glsl`). Before any draw, the host drops instances whose
//! whole mesh sphere is outside the frustum, with the shader's rounding slack.

use super::*;
use crate::mesh::{Instance, Scene};
use glam::{DMat4, DVec3, DVec4};

/// One instance as the shaders read it (`Instance` in glsl/common.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct InstanceRecord {
    /// Object-to-world rows (x, y, z).
    pub to_world: [[f32; 4]; 3],
    /// World-to-object rows (the inverse, computed in f64).
    pub to_object: [[f32; 4]; 3],
    /// The factor a bounding radius grows by (the largest stretch).
    pub scale: f32,
    /// The instance's first (instance, meshlet) slot: its meshlets' visibility words and ids.
    pub slot_base: u32,
    /// Padding to 16 bytes.
    pub pad: [u32; 2],
    /// The whole mesh's bounding sphere in object space (centre, radius): the late phase's
    /// instance-level occlusion test.
    pub sphere: [f32; 4],
}

impl InstanceRecord {
    /// The record of `inst`, whose meshlets' slots start at `slot_base` and whose mesh lies in
    /// `sphere` (object space).
    pub fn new(inst: &Instance, slot_base: u32, sphere: [f32; 4]) -> Self {
        let m = inst.transform.as_dmat4();
        let inv = m.inverse();
        let rows = |m: DMat4| {
            let t = m.transpose();
            [0, 1, 2].map(|r| t.col(r).as_vec4().to_array())
        };
        Self {
            to_world: rows(m),
            to_object: rows(inv),
            scale: inst.max_scale(),
            slot_base,
            pad: [0; 2],
            sphere,
        }
    }
}

/// One draw of an instanced pass.
#[derive(Clone, Copy, Debug)]
pub(super) struct Draw {
    pub instance: u32,
    pub meshlet_first: u32,
    pub meshlet_count: u32,
    pub index_first: u32,
    pub index_count: u32,
    /// Mirrored: the front face is clockwise.
    pub mirrored: bool,
    /// The instance's whole mesh as a world sphere (centre, radius), for the host's test.
    pub sphere: DVec4,
}

/// A scene's meshes as one mesh, their meshlets as one set, and one draw per instance.
pub(super) fn concatenate(scene: &Scene, meshlets: &[Meshlets]) -> (Mesh, Meshlets, Vec<Draw>) {
    let mut mesh = Mesh::empty();
    let mut ml = Meshlets::default();
    // Per mesh: (first meshlet, meshlets, first index, indices, object sphere).
    let mut ranges = Vec::with_capacity(scene.meshes.len());
    for (m, set) in scene.meshes.iter().zip(meshlets) {
        let vbase = mesh.positions.len() as u32;
        let first = (ml.len() as u32, set.len() as u32);
        let index_first = mesh.indices.len() as u32;
        mesh.positions.extend_from_slice(&m.positions);
        mesh.indices.extend(m.indices.iter().map(|&i| i + vbase));
        let (voff, toff) = (ml.vertices.len() as u32, ml.triangles.len() as u32);
        ml.meshlets.extend(set.meshlets.iter().map(|x| Meshlet {
            vertex_offset: x.vertex_offset + voff,
            triangle_offset: x.triangle_offset + toff,
            ..*x
        }));
        ml.vertices.extend(set.vertices.iter().map(|&v| v + vbase));
        ml.triangles.extend_from_slice(&set.triangles);
        let (lo, hi) = m.bounding_box();
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        ranges.push((
            first,
            index_first,
            m.indices.len() as u32,
            (lo + hi) / 2.0,
            (hi - lo).length() / 2.0,
        ));
    }
    let draws = scene
        .instances
        .iter()
        .enumerate()
        .map(|(i, inst)| {
            let ((meshlet_first, meshlet_count), index_first, index_count, c, r) =
                ranges[inst.mesh as usize];
            let centre = inst.transform.as_dmat4().transform_point3(c);
            Draw {
                instance: i as u32,
                meshlet_first,
                meshlet_count,
                index_first,
                index_count,
                mirrored: inst.mirrored(),
                sphere: centre.extend(r * inst.max_scale() as f64),
            }
        })
        .collect();
    (mesh, ml, draws)
}

/// Whether a world sphere lies wholly outside one of the frustum planes of `view_proj`, with the
/// task shader's slack (so the host never drops an instance the shader would draw from).
pub(super) fn outside_frustum(view_proj: glam::Mat4, sphere: DVec4) -> bool {
    let m = view_proj.as_dmat4().transpose();
    let rows = [m.x_axis, m.y_axis, m.z_axis, m.w_axis];
    let planes = [
        rows[3] + rows[0],
        rows[3] - rows[0],
        rows[3] + rows[1],
        rows[3] - rows[1],
        rows[2],
        rows[3] - rows[2],
    ];
    let c: DVec3 = sphere.truncate();
    planes.iter().any(|p| {
        let n = p.truncate();
        let slack = 1e-5 * (n.abs().dot(c.abs()) + p.w.abs());
        n.dot(c) + p.w < -sphere.w * n.length() * 1.0001 - slack
    })
}

impl<'a> Pass<'a> {
    /// Uploads `scene`'s meshes and their meshlets (`meshlets[i]` of `scene.meshes[i]`) once, in
    /// the split layout, with one record per instance; every frame draws each instance whose mesh
    /// sphere meets the frustum.
    pub fn instanced(
        ctx: &'a Context,
        scene: &Scene,
        meshlets: &[Meshlets],
    ) -> Result<Self, RenderError> {
        assert_eq!(
            scene.meshes.len(),
            meshlets.len(),
            "one meshlet set per mesh"
        );
        let (mesh, ml, draws) = concatenate(scene, meshlets);
        let mut slots = 0u32;
        let records: Vec<InstanceRecord> = scene
            .instances
            .iter()
            .zip(&draws)
            .map(|(inst, d)| {
                let (lo, hi) = scene.meshes[inst.mesh as usize].bounding_box();
                let centre = (lo + hi) * 0.5;
                // Rounded up: the sphere holds every vertex despite f32 rounding.
                let radius = (((hi - lo).length() * 0.5) * (1.0 + 1e-6)).next_up();
                let r = InstanceRecord::new(inst, slots, centre.extend(radius).to_array());
                slots += d.meshlet_count;
                r
            })
            .collect();
        let mut pass = Self::build(
            ctx,
            Source::Descriptors {
                mesh: &mesh,
                ml: &ml,
                format: DescriptorFormat::Split,
                lod: None,
                instances: &records,
                slots,
            },
        )?;
        pass.draws = Some(draws);
        Ok(pass)
    }

    /// Instances of an instanced pass (1 for any other).
    pub fn instance_count(&self) -> usize {
        self.draws.as_ref().map_or(1, Vec::len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Vec3};

    #[test]
    fn records_invert_and_bound_their_transforms() {
        let inst = Instance {
            mesh: 0,
            transform: Mat4::from_scale_rotation_translation(
                Vec3::new(-2.0, 0.5, 1.0),
                glam::Quat::from_rotation_y(0.7),
                Vec3::new(3.0, 1.0, -2.0),
            ),
        };
        let r = InstanceRecord::new(&inst, 0, [0.0; 4]);
        let p = glam::Vec4::new(0.3, -1.2, 2.0, 1.0);
        let row = |m: &[[f32; 4]; 3], q: glam::Vec4| {
            Vec3::new(
                glam::Vec4::from(m[0]).dot(q),
                glam::Vec4::from(m[1]).dot(q),
                glam::Vec4::from(m[2]).dot(q),
            )
        };
        let w = row(&r.to_world, p);
        assert!((w - inst.transform.transform_point3(p.truncate())).length() < 1e-5);
        let back = row(&r.to_object, w.extend(1.0));
        assert!((back - p.truncate()).length() < 1e-5);
        assert!(r.scale >= 2.0 && r.scale < 2.001);
    }

    #[test]
    fn the_host_keeps_every_instance_the_frustum_meets() {
        let cam = Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            near: 0.1,
            far: 100.0,
        };
        let vp = cam.view_proj(16.0 / 9.0);
        assert!(!outside_frustum(vp, DVec4::new(0.0, 0.0, 0.0, 1.0)));
        assert!(outside_frustum(vp, DVec4::new(0.0, 0.0, 10.0, 1.0)));
        assert!(outside_frustum(vp, DVec4::new(100.0, 0.0, 0.0, 1.0)));
        // Touching the plane from outside is kept.
        assert!(!outside_frustum(
            vp,
            DVec4::new(0.0, 0.0, 5.0 - 0.1 + 0.5, 0.5)
        ));
    }
}
