//! The mesh-shader render benchmark (ash + VK_EXT_mesh_shader, shaders in glsl/): a headless
//! [`Context`], the [`Pass`] that draws meshlets through task and mesh shaders or the whole mesh
//! through the vertex pipeline, compressed meshlets decoded by the shaders from their encoded
//! bytes ([`compressed`]), and the camera protocol. Instanced scenes ([`Pass::instanced`]: meshlets
//! uploaded once per mesh, one draw per instance) and two-phase occlusion culling with its
//! sample-exact check ([`Pass::render_occlusion`], measured along camera paths by [`occlusion`]).

pub mod compressed;
pub mod context;
pub mod interface;
pub mod occlusion;
pub mod pass;
pub mod validation;

pub use crate::lod::camera::{Camera, FOV_Y, FRAME_FILL, HEIGHT, WIDTH};
pub use crate::mesh::generate::random_directions;
pub use context::Context;
pub use pass::{Checked, Drawn, Frame, MeshQueries, OcclusionFrame, Pass, Pipeline, Shading};

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
    /// The occlusion check needs 64-bit buffer atomics in fragment shaders.
    #[error("this device has no 64-bit buffer atomics in fragment shaders (shaderBufferInt64Atomics, fragmentStoresAndAtomics): the occlusion exactness check cannot run on it")]
    NoIdCheck,
    /// A Vulkan call failed.
    #[error("Vulkan call failed: {0}: {1}")]
    Vulkan(&'static str, ash::vk::Result),
}

/// Maps a failed Vulkan call to [`RenderError::Vulkan`] naming the call.
pub(crate) fn vk_err(what: &'static str) -> impl Fn(ash::vk::Result) -> RenderError {
    move |e| RenderError::Vulkan(what, e)
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
        .with_context(|| format!("{}: cannot write", path.display()))
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
