//! The camera protocol every view-dependent step shares: the LOD selection (its pixel threshold
//! refers to this image), the GPU selection kernel's parity views and the mesh-shader pass. Plain
//! math over a [`Mesh`], so it sits below `gpu` and `render`, which both use it.

use crate::mesh::generate::random_directions;
use crate::mesh::Mesh;
use glam::{Mat4, Vec3};

/// Image width in pixels (the paper's).
pub const WIDTH: u32 = 1280;
/// Image height in pixels: LOD thresholds are pixels of this image.
pub const HEIGHT: u32 = 720;

/// How much of the image's half-height (or half-width) a framed mesh fills ([`Camera::framed`]).
pub const FRAME_FILL: f32 = 0.92;

/// Vertical field of view of every camera, degrees.
pub const FOV_Y: f32 = 60.0;

/// A perspective camera looking at a point (60 degree vertical field of view, depth 0..1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position.
    pub eye: Vec3,
    /// The point looked at.
    pub target: Vec3,
    /// Near and far plane distances.
    pub near: f32,
    /// See `near`.
    pub far: f32,
}

impl Camera {
    /// View and projection for an image of `aspect` (width / height). The y axis is flipped for
    /// Vulkan's downward framebuffer y, so the image is upright and counter-clockwise stays front.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let up = up_for((self.target - self.eye).normalize_or(Vec3::NEG_Z));
        let view = Mat4::look_at_rh(self.eye, self.target, up);
        let proj = Mat4::perspective_rh(FOV_Y.to_radians(), aspect, self.near, self.far);
        Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)) * proj * view
    }

    /// The LOD selection query of this camera: its eye, the pass's image height and field of view,
    /// a threshold of `pixels`, levels `finest..` loaded, and its frustum and normal-cone culling
    /// when `cull`.
    pub fn lod_query(&self, pixels: f32, finest: usize, cull: bool) -> crate::lod::flat::Query {
        crate::lod::flat::Query {
            view: crate::lod::select::View::new(
                self.eye,
                HEIGHT as f32,
                FOV_Y.to_radians(),
                pixels,
            ),
            finest,
            frustum: cull.then(|| {
                crate::lod::flat::frustum_planes(&self.view_proj(WIDTH as f32 / HEIGHT as f32))
            }),
            cone: cull,
        }
    }

    /// A short camera path that closes in on this camera: `frames` cameras on the ray from the
    /// target through the eye, the first half again as far away, the last this camera, evenly
    /// spaced (the far plane moved out with the eye). What occlusion culling is measured on: each
    /// frame starts from the visibility of the one before.
    pub fn approach(&self, frames: usize) -> Vec<Self> {
        let offset = self.eye - self.target;
        (0..frames)
            .map(|f| {
                let k = if frames > 1 {
                    1.0 + 0.5 * (frames - 1 - f) as f32 / (frames - 1) as f32
                } else {
                    1.0
                };
                Self {
                    eye: self.target + offset * k,
                    far: self.far + (k - 1.0) * offset.length(),
                    ..*self
                }
            })
            .collect()
    }

    /// A camera at `eye` looking at `mesh`'s bounding-sphere centre, with planes that enclose it.
    pub fn looking_at(mesh: &Mesh, eye: Vec3) -> Self {
        let (lo, hi) = mesh.bounding_box();
        let centre = (lo + hi) * 0.5;
        let r = ((hi - lo).length() * 0.5).max(1e-6);
        let dist = (eye - centre).length();
        Self {
            eye,
            target: centre,
            near: (dist - 1.5 * r).max(r * 1e-3),
            far: dist + 1.5 * r,
        }
    }

    /// The paper's random-view protocol (§4): `n` cameras at seeded random directions around the
    /// mesh, at `distance` bounding radii from its centre, looking at it; the same sequence for
    /// every strategy.
    pub fn random_views(mesh: &Mesh, n: usize, seed: u64, distance: f32) -> Vec<Self> {
        let (lo, hi) = mesh.bounding_box();
        let centre = (lo + hi) * 0.5;
        let r = ((hi - lo).length() * 0.5).max(1e-6);
        random_directions(n, seed)
            .into_iter()
            .map(|dir| Self::looking_at(mesh, centre + dir * r * distance))
            .collect()
    }

    /// The same directions as [`Camera::random_views`], each camera as close as it can be with the
    /// whole mesh inside `fill` of the image's half-width and half-height: framed, so the mesh
    /// fills most of the picture whatever its shape.
    pub fn framed_views(mesh: &Mesh, n: usize, seed: u64, aspect: f32, fill: f32) -> Vec<Self> {
        random_directions(n, seed)
            .into_iter()
            .map(|dir| Self::framed(mesh, dir, aspect, fill))
            .collect()
    }

    /// A camera on the ray from `mesh`'s box centre along `dir`, at the least distance for which
    /// every vertex projects inside `fill` (0..1) of the image (vertical field of view 60 degrees,
    /// `aspect` = width / height). A vertex at offset (x, y, z) in the camera frame (z towards the
    /// camera) is inside when |y| <= tan(30 deg) * fill * (d - z), and likewise for x with the
    /// horizontal half-angle, so d is the largest z + |y| / (tan * fill) over the vertices.
    pub fn framed(mesh: &Mesh, dir: Vec3, aspect: f32, fill: f32) -> Self {
        let (lo, hi) = mesh.bounding_box();
        let centre = (lo + hi) * 0.5;
        let r = ((hi - lo).length() * 0.5).max(1e-6);
        let dir = dir.normalize_or(Vec3::Z);
        // The same frame view_proj builds for a camera looking along -dir.
        let up = up_for(-dir);
        let right = (-dir).cross(up).normalize();
        let cam_up = right.cross(-dir);
        let tan_v = 30f32.to_radians().tan() * fill.clamp(0.05, 1.0);
        let tan_h = tan_v * aspect;
        let mut d = f32::MIN;
        for p in &mesh.positions {
            let q = Vec3::from_array(*p) - centre;
            let z = q.dot(dir);
            d = d
                .max(z + q.dot(right).abs() / tan_h)
                .max(z + q.dot(cam_up).abs() / tan_v);
        }
        // In front of every vertex (a thin mesh seen end-on needs only d > its nearest tip).
        let z_max = mesh
            .positions
            .iter()
            .map(|p| (Vec3::from_array(*p) - centre).dot(dir))
            .fold(f32::MIN, f32::max);
        let d = d.max(z_max + r * 0.05).max(r * 1e-2);
        Self::looking_at(mesh, centre + dir * d)
    }
}

/// The up vector for a camera looking along unit `forward`: +Y, or +Z when looking (almost)
/// straight up or down.
fn up_for(forward: Vec3) -> Vec3 {
    if forward.cross(Vec3::Y).length_squared() > 1e-12 {
        Vec3::Y
    } else {
        Vec3::Z
    }
}
