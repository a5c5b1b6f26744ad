//! Scenes: meshes placed by instances, as a glTF scene's nodes (and `EXT_mesh_gpu_instancing`)
//! place them. Meshlets are built once per mesh and drawn once per instance; [`Scene::flatten`]
//! bakes every instance into one mesh, which is what `mesh::load` returns;
//! `mesh::load_scene` keeps them apart.
//!
//! An instance is an affine transform. Mirrored ones (negative determinant) reverse the winding
//! of what they draw: [`Scene::flatten`] swaps two corners of each of their triangles, and a
//! renderer flips its front face for them. Bounds move conservatively: a sphere's radius is scaled
//! by [`Instance::max_scale`] (the transform's largest stretch, rounded up), and a normal cone is
//! tested in the instance's own space, with the camera moved there (exact for any invertible
//! affine transform, non-uniform scales included: the sign of a triangle's facing survives it).

use super::{Mesh, MeshError, MeshErrorKind};
use glam::{DMat3, Mat4, Vec3};
use std::path::Path;

/// One placement of a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`Scene::meshes`].
    pub mesh: u32,
    /// Object to world (affine: the last row is 0, 0, 0, 1).
    pub transform: Mat4,
}

impl Instance {
    /// Whether the transform mirrors (reverses the winding of) what it places.
    pub fn mirrored(&self) -> bool {
        self.transform.determinant() < 0.0
    }

    /// An upper bound of the factor by which the transform stretches any length: the spectral
    /// norm of its linear part, from the largest eigenvalue of MᵀM in closed form (f64), rounded
    /// up by a relative 1e-6 so a sphere scaled by it always contains the transformed one.
    pub fn max_scale(&self) -> f32 {
        let m = DMat3::from_mat4(self.transform.as_dmat4());
        let a = m.transpose() * m;
        let largest = largest_eigenvalue(a).max(0.0).sqrt();
        ((largest * (1.0 + 1e-6)) as f32).next_up()
    }
}

/// Largest eigenvalue of a symmetric 3x3 matrix (the trigonometric closed form).
fn largest_eigenvalue(a: DMat3) -> f64 {
    let (a00, a11, a22) = (a.x_axis.x, a.y_axis.y, a.z_axis.z);
    let (a01, a02, a12) = (a.y_axis.x, a.z_axis.x, a.z_axis.y);
    let off = a01 * a01 + a02 * a02 + a12 * a12;
    if off == 0.0 {
        return a00.max(a11).max(a22);
    }
    let q = (a00 + a11 + a22) / 3.0;
    let p = (((a00 - q).powi(2) + (a11 - q).powi(2) + (a22 - q).powi(2) + 2.0 * off) / 6.0).sqrt();
    let b = (a - DMat3::from_diagonal(glam::DVec3::splat(q))) * (1.0 / p);
    let phi = (b.determinant() / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    q + 2.0 * p * phi.cos()
}

/// Meshes and the instances that place them; valid by construction (at least one instance, each
/// naming a mesh, and a baked copy with finite positions that fits 32-bit indices), so
/// [`Scene::flatten`] always yields a valid [`Mesh`].
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Each mesh once, in the order instances first name them.
    pub(crate) meshes: Vec<Mesh>,
    /// Every placement, in the file's node order.
    pub(crate) instances: Vec<Instance>,
}

impl Scene {
    /// Checks `meshes` and `instances` (see the type's invariants) and takes them; `label` names
    /// the scene in errors.
    pub fn new(
        meshes: Vec<Mesh>,
        instances: Vec<Instance>,
        label: impl AsRef<Path>,
    ) -> Result<Self, MeshError> {
        let err = |k| MeshError::new(label.as_ref(), k);
        if instances.is_empty() {
            return Err(err(MeshErrorKind::Empty(
                "a scene without instances".into(),
            )));
        }
        let mut total = 0usize;
        for (k, inst) in instances.iter().enumerate() {
            let Some(m) = meshes.get(inst.mesh as usize) else {
                return Err(err(MeshErrorKind::Unsupported(format!(
                    "instance {k} places mesh {} of {}",
                    inst.mesh,
                    meshes.len()
                ))));
            };
            total += m.vertex_count();
            // The very arithmetic flatten does: a finite transform can still overflow a point.
            let placed = m
                .positions
                .iter()
                .map(|&p| inst.transform.transform_point3(Vec3::from_array(p)));
            if let Some(v) = placed.clone().position(|p| !p.is_finite()) {
                return Err(err(MeshErrorKind::NonFinite {
                    vertex: total - m.vertex_count() + v,
                    value: format!(
                        "instance {k} places a vertex at {}",
                        placed.clone().nth(v).unwrap()
                    ),
                }));
            }
        }
        if total > u32::MAX as usize {
            return Err(err(MeshErrorKind::TooLarge(format!(
                "{total} baked vertices do not fit 32-bit indices"
            ))));
        }
        Ok(Self { meshes, instances })
    }

    /// Each mesh once, in the order instances first name them.
    pub fn meshes(&self) -> &[Mesh] {
        &self.meshes
    }

    /// Every placement, in the file's node order.
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// One mesh placed once, untransformed.
    pub fn single(mesh: Mesh) -> Self {
        Self {
            meshes: vec![mesh],
            instances: vec![Instance {
                mesh: 0,
                transform: Mat4::IDENTITY,
            }],
        }
    }

    /// `n` x `n` x `n` copies of `mesh` on a grid whose spacing is `spacing` times the mesh's
    /// largest extent (below 1 the copies interpenetrate, so most of them hide the others); an
    /// error when `n` is 0 or the copies leave the f32 range.
    pub fn grid(mesh: Mesh, n: usize, spacing: f32) -> Result<Self, MeshError> {
        let (lo, hi) = mesh.bounding_box();
        let step = (hi - lo).max_element() * spacing;
        let mut instances = Vec::with_capacity(n * n * n);
        for k in 0..n * n * n {
            let (x, y, z) = (k % n, (k / n) % n, k / (n * n));
            let offset = (Vec3::new(x as f32, y as f32, z as f32) - (n as f32 - 1.0) / 2.0) * step;
            instances.push(Instance {
                mesh: 0,
                transform: Mat4::from_translation(offset),
            });
        }
        Self::new(vec![mesh], instances, "grid")
    }

    /// Whether instancing saves anything: some mesh is placed more than once. A scene that places
    /// each mesh once is as well baked ([`Scene::baked`]), which keeps the geometry strategies see
    /// in world space (a glTF node's transform may scale unevenly, as gltfpack's dequantisation
    /// does).
    pub fn is_instanced(&self) -> bool {
        self.instances.len() > self.meshes.len()
    }

    /// The scene as one mesh placed once: itself when it is that already, else
    /// [`Scene::flatten`]'s mesh.
    pub fn baked(self) -> Self {
        let single = self.meshes.len() == 1
            && self.instances.len() == 1
            && self.instances[0].transform == Mat4::IDENTITY;
        if single {
            self
        } else {
            Self::single(self.flatten())
        }
    }

    /// Triangles built (each mesh once).
    pub fn triangles_built(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// Triangles drawn when nothing is culled (each instance's mesh).
    pub fn triangles_drawn(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh as usize].triangle_count())
            .sum()
    }

    /// Every instance baked into one mesh (world positions; mirrored instances get two corners
    /// of each triangle swapped so front faces stay front faces).
    pub fn flatten(&self) -> Mesh {
        let mut out = Mesh::empty();
        for inst in &self.instances {
            let m = &self.meshes[inst.mesh as usize];
            let base = out.positions.len() as u32;
            out.positions.extend(m.positions.iter().map(|&p| {
                inst.transform
                    .transform_point3(Vec3::from_array(p))
                    .to_array()
            }));
            let flip = inst.mirrored();
            for t in m.indices.chunks_exact(3) {
                let [a, b, c] = [t[0] + base, t[1] + base, t[2] + base];
                out.indices
                    .extend_from_slice(&if flip { [a, c, b] } else { [a, b, c] });
            }
        }
        out
    }

    /// The corners of every instance's (transformed) mesh box, as a mesh of one triangle: what
    /// cameras are framed on, without baking the scene.
    pub fn box_corners(&self) -> Mesh {
        let boxes: Vec<(Vec3, Vec3)> = self.meshes.iter().map(Mesh::bounding_box).collect();
        let mut positions = Vec::with_capacity(8 * self.instances.len());
        for inst in &self.instances {
            let (a, b) = boxes[inst.mesh as usize];
            for k in 0..8 {
                let corner = Vec3::new(
                    if k & 1 == 0 { a.x } else { b.x },
                    if k & 2 == 0 { a.y } else { b.y },
                    if k & 4 == 0 { a.z } else { b.z },
                );
                positions.push(inst.transform.transform_point3(corner).to_array());
            }
        }
        Mesh {
            positions,
            indices: vec![0, 1, 2],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    #[test]
    fn max_scale_bounds_every_stretch_tightly() {
        let cases = [
            Mat4::IDENTITY,
            Mat4::from_scale(Vec3::new(2.0, 0.5, 1.0)),
            Mat4::from_scale_rotation_translation(
                Vec3::new(-1.0, 3.0, 0.25),
                Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.7),
                Vec3::new(5.0, -2.0, 1.0),
            ),
            Mat4::from_cols_array(&[
                1.0, 0.0, 0.0, 0.0, 0.8, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ]),
        ];
        for m in cases {
            let s = Instance {
                mesh: 0,
                transform: m,
            }
            .max_scale();
            let mut seen = 0.0f32;
            for d in crate::mesh::generate::random_directions(2000, 7) {
                let len = m.transform_vector3(d).length();
                assert!(len <= s, "{m:?} stretches {d:?} to {len} > {s}");
                seen = seen.max(len);
            }
            assert!(s <= seen * 1.01, "{m:?}: bound {s} far above {seen}");
        }
    }

    #[test]
    fn flatten_keeps_mirrored_instances_front_facing() {
        let tri = Mesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            indices: vec![0, 1, 2],
        };
        let scene = Scene {
            meshes: vec![tri],
            instances: vec![
                Instance {
                    mesh: 0,
                    transform: Mat4::IDENTITY,
                },
                Instance {
                    mesh: 0,
                    transform: Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
                },
            ],
        };
        let flat = scene.flatten();
        let normal = |t: usize| {
            let [a, b, c] = flat.triangle(t).map(|v| flat.position(v));
            (b - a).cross(c - a)
        };
        // Mirroring in x keeps a triangle in the z = 0 plane facing +z.
        assert!(normal(0).z > 0.0 && normal(1).z > 0.0);
        assert_eq!(scene.triangles_built(), 1);
        assert_eq!(scene.triangles_drawn(), 2);
        assert!(scene.instances[1].mirrored() && !scene.instances[0].mirrored());
    }

    #[test]
    fn new_refuses_what_would_bake_to_an_invalid_mesh() {
        let tri = Mesh::from_slices(
            &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[0, 1, 2],
            "t",
        )
        .unwrap();
        let place = |mesh, transform| Instance { mesh, transform };
        let ok = Scene::new(vec![tri.clone()], vec![place(0, Mat4::IDENTITY)], "s").unwrap();
        assert_eq!(ok.flatten(), tri);
        let e = Scene::new(vec![tri.clone()], vec![], "s").unwrap_err();
        assert!(matches!(e.kind, MeshErrorKind::Empty(_)), "{e}");
        let e = Scene::new(vec![tri.clone()], vec![place(1, Mat4::IDENTITY)], "s").unwrap_err();
        assert!(e.to_string().contains("places mesh 1 of 1"), "{e}");
        // Finite, but it sends a vertex past f32::MAX.
        let huge = Mat4::from_scale_rotation_translation(
            Vec3::splat(f32::MAX),
            glam::Quat::IDENTITY,
            Vec3::splat(f32::MAX),
        );
        let e = Scene::new(vec![tri.clone()], vec![place(0, huge)], "s").unwrap_err();
        assert!(
            matches!(e.kind, MeshErrorKind::NonFinite { vertex: 1, .. }),
            "{e}"
        );
        assert!(Scene::grid(tri.clone(), 0, 1.0).is_err());
        assert!(Scene::grid(tri, 2, f32::NAN).is_err());
    }
}
