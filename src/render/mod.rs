//! The mesh-shader render benchmark (ash + VK_EXT_mesh_shader, shaders in glsl/): a headless
//! [`Context`], the [`Pass`] that draws meshlets through task and mesh shaders or the whole mesh
//! through the vertex pipeline, compressed meshlets decoded by the shaders from their encoded
//! bytes ([`compressed`]), and the camera protocol.

pub mod compressed;
pub mod context;
pub mod pass;
pub mod validation;

pub use context::Context;
pub use pass::{Drawn, Frame, MeshQueries, Pass, Pipeline, Shading, HEIGHT, WIDTH};

use crate::mesh::Mesh;
use glam::{Mat4, Vec3};
use thiserror::Error;

/// Why rendering is not possible or failed.
#[derive(Debug, Error)]
pub enum RenderError {
    /// No Vulkan loader or instance.
    #[error("no Vulkan: {0}. Install a Vulkan driver; on Debian 12 `make setup` installs Mesa's lavapipe from bookworm-backports")]
    NoVulkan(String),
    /// No device with task and mesh shaders.
    #[error("no Vulkan device with VK_EXT_mesh_shader (task + mesh), Vulkan 1.3 dynamic rendering and maintenance4; found: {0}. Mesa >= 24 lavapipe has it: `make setup` installs it on Debian 12")]
    NoMeshShader(String),
    /// The build found no glslangValidator.
    #[error("the shaders were not compiled (glslangValidator was missing at build time): run `make setup`, then rebuild")]
    ShadersMissing,
    /// Validation requested but the layer is not installed.
    #[error("the Khronos validation layer is not installed (`make setup` installs vulkan-validationlayers)")]
    NoValidationLayer,
    /// The meshlets do not fit the chosen descriptor layout.
    #[error(transparent)]
    Descriptor(#[from] crate::meshlet::descriptor::DescriptorError),
    /// `render_lod` on a pass built without a LOD DAG.
    #[error("this render pass holds no LOD DAG (build it with Pass::with_lod)")]
    NotLod,
    /// A compressed buffer that does not decode on the CPU: never uploaded.
    #[error("compressed meshlets rejected before upload: {0}")]
    Corrupt(#[from] crate::compress::DecodeError),
    /// A compressed format (or format and pipeline) without a shader decoder.
    #[error("no shader decoder for {0}: the GPU decodes laced-wires, sc-compact and ix-compact in mesh shaders, gi-compact and ts-compact in the vertex shader")]
    NoShaderDecoder(String),
    /// A storage buffer beyond the device's binding limit (the pass does not chunk).
    #[error("{what}: {bytes} bytes in one storage binding, above the device's {limit}; draw a smaller mesh or scene")]
    TooLarge {
        /// Which buffer.
        what: &'static str,
        /// Its size.
        bytes: u64,
        /// The device's `maxStorageBufferRange`.
        limit: u64,
    },
    /// A Vulkan call failed.
    #[error("Vulkan call failed: {0}: {1}")]
    Vulkan(&'static str, ash::vk::Result),
}

/// Maps a failed Vulkan call to [`RenderError::Vulkan`] naming the call.
pub(crate) fn vk_err(what: &'static str) -> impl Fn(ash::vk::Result) -> RenderError {
    move |e| RenderError::Vulkan(what, e)
}

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

/// `n` seeded directions, uniform on the unit sphere (z uniform in [-1, 1], angle uniform).
pub fn random_directions(n: usize, seed: u64) -> Vec<Vec3> {
    let mut state = seed;
    let mut unit = || {
        state = crate::mesh::generate::splitmix64(state);
        (state >> 11) as f32 / (1u64 << 53) as f32
    };
    (0..n)
        .map(|_| {
            let z = 2.0 * unit() - 1.0;
            let a = std::f32::consts::TAU * unit();
            let s = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(s * a.cos(), z, s * a.sin())
        })
        .collect()
}

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Pixels that differ between two RGBA8 images (any channel).
pub fn differing_pixels(a: &[u8], b: &[u8]) -> usize {
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(x, y)| x != y)
        .count()
}

/// Largest difference of any channel between two RGBA8 images.
pub fn max_channel_difference(a: &[u8], b: &[u8]) -> u8 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

/// Renders `cam`'s view through the mesh shaders coloured by meshlet (the paper's Figure 1; with
/// task-shader culling when `cull`, so culled meshlets are absent) and writes it as a PNG.
pub fn write_meshlet_png(
    pass: &Pass,
    cam: &Camera,
    cull: bool,
    path: &std::path::Path,
) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let how = Pipeline::Mesh {
        frustum: cull,
        cone: cull,
        colour_ids: true,
    };
    let img = pass.render(cam, how, Shading::Lit)?;
    write_png(path, WIDTH, HEIGHT, &img.pixels)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes RGBA8 `pixels` of a `width` x `height` image as a PNG.
pub fn write_png(
    path: &std::path::Path,
    width: u32,
    height: u32,
    pixels: &[u8],
) -> std::io::Result<()> {
    crate::atomic::write_with(path, |file| {
        let mut enc = png::Encoder::new(file, width, height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(std::io::Error::other)?;
        w.write_image_data(pixels).map_err(std::io::Error::other)?;
        w.finish().map_err(std::io::Error::other)
    })
}
