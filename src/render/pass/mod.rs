//! The render pass: 1280x720, 4x MSAA resolved to one sample, D32 depth (the paper's setup), drawn
//! either by the mesh-shader pipeline (task-shader culling, one mesh workgroup per meshlet) or by
//! the classic vertex pipeline (one indexed draw of the same mesh) as the baseline.

use super::compressed::{Decoder, Upload};
use super::context::{self as vkc, Buffer, Context, Owned};
use super::interface::{self, Compact, Layout, Shader, Size};
use super::{vk_err, Camera, RenderError, HEIGHT, WIDTH};
use crate::lod::flat::{loaded, Flat, Query, ViewData};
use crate::mesh::Mesh;
use crate::meshlet::descriptor::{self, DescriptorFormat};
use crate::meshlet::{Limits, Meshlet, Meshlets};
use ash::vk;

mod frame;
mod instances;
mod objects;
mod occlusion;
mod setup;

pub use instances::InstanceRecord;
pub use occlusion::{Checked, OcclusionFrame};

use objects::{pipeline, target};

const SAMPLES: vk::SampleCountFlags = vk::SampleCountFlags::TYPE_4;
const COLOR: vk::Format = vk::Format::R8G8B8A8_UNORM;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
use interface::{FLAG_CONE, FLAG_FRUSTUM, FLAG_INSTANCED, FLAG_RECORD_IDS, FLAG_UNLIT, TASK_GROUP};

/// Which pipeline draws, and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pipeline {
    /// Task + mesh shaders over the meshlets.
    Mesh {
        /// Task-shader frustum culling against the bounding sphere.
        frustum: bool,
        /// Task-shader backface culling against the normal cone.
        cone: bool,
        /// Colour by meshlet id instead of plain shading.
        colour_ids: bool,
    },
    /// One indexed draw through the vertex shader.
    Vertex,
}

impl Pipeline {
    /// The mesh pipeline, shaded, with frustum and cone culling when `cull`.
    pub const fn mesh(cull: bool) -> Self {
        Pipeline::Mesh {
            frustum: cull,
            cone: cull,
            colour_ids: false,
        }
    }

    /// The mesh pipeline coloured by meshlet id, with frustum and cone culling when `cull`.
    pub const fn mesh_ids(cull: bool) -> Self {
        Pipeline::Mesh {
            frustum: cull,
            cone: cull,
            colour_ids: true,
        }
    }
}

/// How fragments are coloured (the meshlet-id colouring is a [`Pipeline::Mesh`] option).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// Flat shading from screen-space derivatives.
    #[default]
    Lit,
    /// Plain white: coverage and depth only, for exact comparisons between pipelines.
    Unlit,
}

/// One rendered frame.
pub struct Frame {
    /// RGBA8 pixels, row-major, top row first.
    pub pixels: Vec<u8>,
    /// GPU time of the draw in nanoseconds (timestamps around the rendering).
    pub gpu_ns: f64,
    /// Meshlets the task shader culled by the frustum and by the normal cone, and drew.
    pub culled_frustum: u32,
    /// See `culled_frustum`.
    pub culled_cone: u32,
    /// See `culled_frustum`.
    pub drawn: u32,
    /// Triangles in the meshlets culled by the frustum and by the normal cone.
    pub culled_triangles: [u32; 2],
    /// LOD passes: loaded meshlets not on the cut for the view (0 otherwise).
    pub not_selected: u32,
    /// Instanced passes: instances whose whole mesh is outside the frustum, not drawn (their
    /// meshlets are in no other count).
    pub culled_instances: u32,
    /// Mesh-pipeline queries, when the device has `meshShaderQueries` (lavapipe does).
    pub queries: Option<MeshQueries>,
}

/// What the mesh-shader queries counted for one draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshQueries {
    /// Task-shader invocations (pipeline statistics).
    pub task_invocations: u64,
    /// Mesh-shader invocations (pipeline statistics).
    pub mesh_invocations: u64,
    /// Primitives the mesh shaders emitted (`MESH_PRIMITIVES_GENERATED_EXT`).
    pub primitives: u64,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    view_proj: [f32; 16],
    camera: [f32; 4],
    box_min: [f32; 4],
    box_step: [f32; 4],
    meshlet_count: u32,
    flags: u32,
    instance: u32,
    meshlet_first: u32,
}

/// Bytes of the task shader's counters; a LOD pass's drawn-id bitmap follows.
const COUNTER_BYTES: u64 = 4 * interface::COUNTER_WORDS as u64;

/// Where each level starts in a flattened DAG (see [`Flat`]).
struct LodLayout {
    starts: Vec<u32>,
    total: usize,
}

impl LodLayout {
    fn loaded(&self, finest: usize) -> usize {
        loaded(&self.starts, self.total, finest)
    }
}

/// The SPIR-V a pass is built from: task and mesh shaders and a vertex shader with its input,
/// each where the data can be drawn that way.
struct Modules {
    task: Option<&'static [u8]>,
    mesh: Option<&'static [u8]>,
    vertex: Option<(&'static [u8], Input)>,
    lod_task: Option<&'static [u8]>,
}

/// What a pass records about its data.
struct Fields {
    index_count: u32,
    meshlet_count: u32,
    /// Visibility words occlusion culling keeps: one per (instance, meshlet) slot.
    slots: u32,
    drawn: Drawn,
    object: descriptor::ObjectBox,
    device_bytes: usize,
}

/// A render target (fields drop in order: the view before the image before its memory).
struct Target {
    view: Owned<vk::ImageView>,
    image: Owned<vk::Image>,
    _memory: Owned<vk::DeviceMemory>,
}

/// The storage buffers of descriptor set 0, one field per binding in binding order
/// ([`interface::BINDINGS`]; a test checks [`Bindings::NAMES`] against it).
struct Bindings {
    positions: Buffer,
    descriptors: Buffer,
    data: Buffer,
    triangles: Buffer,
    task: Buffer,
    counters: Buffer,
    lod_records: Buffer,
    lod_view: Buffer,
    instances: Buffer,
    visibility: Buffer,
    pyramid: Buffer,
    ids: Buffer,
}

impl Bindings {
    /// The field names, in declaration order.
    #[cfg(test)]
    const NAMES: [&'static str; 12] = [
        "positions",
        "descriptors",
        "data",
        "triangles",
        "task",
        "counters",
        "lod_records",
        "lod_view",
        "instances",
        "visibility",
        "pyramid",
        "ids",
    ];

    /// The buffers in binding order.
    fn in_order(&self) -> [&Buffer; 12] {
        [
            &self.positions,
            &self.descriptors,
            &self.data,
            &self.triangles,
            &self.task,
            &self.counters,
            &self.lod_records,
            &self.lod_view,
            &self.instances,
            &self.visibility,
            &self.pyramid,
            &self.ids,
        ]
    }
}

/// What a pass uploads: every binding but the counters (made by `finish`), and the index buffer
/// of the vertex baseline (not a storage binding).
struct Uploads {
    positions: Buffer,
    descriptors: Buffer,
    data: Buffer,
    triangles: Buffer,
    task: Buffer,
    index: Buffer,
    lod_records: Buffer,
    lod_view: Buffer,
    instances: Buffer,
}

/// What a pass holds on the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drawn {
    /// Positions and meshlets in a descriptor layout (meshlet pipeline and vertex baseline).
    Descriptors(DescriptorFormat),
    /// A compressed encoding decoded by the shaders ([`super::compressed`]).
    Compressed(crate::compress::Codec, Decoder),
}

/// What `build` uploads from.
enum Source<'s> {
    Descriptors {
        mesh: &'s Mesh,
        ml: &'s Meshlets,
        format: DescriptorFormat,
        lod: Option<&'s Flat>,
        /// Instanced passes: one record per instance (empty otherwise).
        instances: &'s [InstanceRecord],
        /// Instanced passes: (instance, meshlet) slots over all instances (0: one per meshlet).
        slots: u32,
    },
    /// The upload, and whether laced wires' scans use subgroup operations.
    Compressed(&'s Upload, bool),
}

/// How a pipeline gets its vertices.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Input {
    /// Task and mesh shaders.
    Mesh,
    /// A vertex buffer of f32 positions.
    Buffer,
    /// Pulled by the vertex shader from storage buffers.
    Pulled,
}

/// Shaded and meshlet-id pipelines of one task shader.
type PipelinePair = (Owned<vk::Pipeline>, Owned<vk::Pipeline>);

/// A mesh and its meshlets on the device, with the pipelines and targets to draw them. Every
/// Vulkan object is owned by a field that frees it; fields drop in declaration order, after
/// `drop` has waited for the device.
pub struct Pass<'a> {
    ctx: &'a Context,
    index_count: u32,
    meshlet_count: u32,
    drawn: Drawn,
    object: descriptor::ObjectBox,
    device_bytes: usize,
    /// The largest storage buffer bound (the one `maxStorageBufferRange` limits).
    largest_binding: u64,
    queries: Owned<vk::QueryPool>,
    /// Pipeline statistics (task, mesh invocations) and mesh primitives generated.
    mesh_queries: Option<(Owned<vk::QueryPool>, Owned<vk::QueryPool>)>,
    targets: [Target; 3],
    /// Task + mesh pipelines, shaded and coloured by meshlet id (none for GI and TS compact).
    mesh_shade: Option<Owned<vk::Pipeline>>,
    mesh_ids: Option<Owned<vk::Pipeline>>,
    /// Task + mesh pipeline through the occlusion check's id shader (where the device can).
    mesh_check: Option<Owned<vk::Pipeline>>,
    /// The vertex pipeline (none for the mesh-shader-only compressed formats).
    vertex: Option<Owned<vk::Pipeline>>,
    /// For a LOD pass: the DAG's level layout and the (shaded, meshlet-id) LOD pipelines.
    lod: Option<(LodLayout, PipelinePair)>,
    layout: Owned<vk::PipelineLayout>,
    /// Freed with its pool.
    set: vk::DescriptorSet,
    _pool: Owned<vk::DescriptorPool>,
    _set_layout: Owned<vk::DescriptorSetLayout>,
    bindings: Bindings,
    index: Buffer,
    readback: Buffer,
    /// Instanced passes: one draw per instance ([`Pass::instanced`]).
    draws: Option<Vec<instances::Draw>>,
    /// Visibility words (one per (instance, meshlet) slot).
    slots: u32,
    /// LOD passes: the view-projection the pyramid was last built with.
    pyramid_view: std::cell::Cell<Option<[f32; 16]>>,
    /// The LOD task shader through the occlusion check's id shader.
    lod_check: Option<Owned<vk::Pipeline>>,
    /// Occlusion culling's compute pipeline and check buffers, made at first use.
    occlusion: std::cell::OnceCell<occlusion::Objects>,
}

/// Vulkan has no empty buffers: an unused binding gets one zero vec4.
fn nonempty(w: &[u32]) -> Vec<u32> {
    if w.is_empty() {
        vec![0; 4]
    } else {
        w.to_vec()
    }
}

fn spirv(bytes: &[u8]) -> Result<Vec<u32>, RenderError> {
    if bytes.is_empty() {
        return Err(RenderError::ShadersMissing);
    }
    ash::util::read_spv(&mut std::io::Cursor::new(bytes))
        .map_err(|e| RenderError::NoVulkan(format!("bad SPIR-V: {e}")))
}

fn shader(s: Shader) -> &'static [u8] {
    super::SHADERS[s.index()]
}

/// The shaders' name for a descriptor layout.
fn layout_of(f: DescriptorFormat) -> Layout {
    match f {
        DescriptorFormat::Split => Layout::Split,
        DescriptorFormat::NvidiaA => Layout::NvidiaA,
        DescriptorFormat::NvidiaB => Layout::NvidiaB,
        DescriptorFormat::Monolithic => Layout::Monolithic,
    }
}

impl<'a> Pass<'a> {
    /// Uploads `mesh` and `ml` in the split descriptor layout (bounds computed here) and builds the
    /// pipelines.
    pub fn new(ctx: &'a Context, mesh: &Mesh, ml: &Meshlets) -> Result<Self, RenderError> {
        Self::with_format(ctx, mesh, ml, DescriptorFormat::Split)
    }

    /// Uploads `mesh` and `ml` packed in `format` and builds the pipelines for it.
    pub fn with_format(
        ctx: &'a Context,
        mesh: &Mesh,
        ml: &Meshlets,
        format: DescriptorFormat,
    ) -> Result<Self, RenderError> {
        Self::build(
            ctx,
            Source::Descriptors {
                mesh,
                ml,
                format,
                lod: None,
                instances: &[],
                slots: 0,
            },
        )
    }

    /// Uploads a compressed encoding as it is (checked by [`super::compressed::prepare`]) and
    /// builds the pipelines that decode it: task and mesh shaders, or the vertex shader for GI and
    /// TS compact.
    pub fn compressed(ctx: &'a Context, upload: &Upload) -> Result<Self, RenderError> {
        Self::compressed_with(ctx, upload, ctx.mesh_subgroups)
    }

    /// [`Pass::compressed`] choosing the laced-wires decoder's scans: subgroup operations (where
    /// the device has them in mesh shaders) or workgroup memory only.
    pub fn compressed_with(
        ctx: &'a Context,
        upload: &Upload,
        subgroups: bool,
    ) -> Result<Self, RenderError> {
        Self::build(
            ctx,
            Source::Compressed(upload, subgroups && ctx.mesh_subgroups),
        )
    }

    /// Uploads a flattened LOD DAG over its source `mesh` (split layout) with its LOD records, for
    /// [`Pass::render_lod`]; [`Pass::render`] then draws every level at once, which is only
    /// useful for debugging.
    pub fn with_lod(ctx: &'a Context, mesh: &Mesh, flat: &Flat) -> Result<Self, RenderError> {
        Self::build(
            ctx,
            Source::Descriptors {
                mesh,
                ml: &flat.meshlets,
                format: DescriptorFormat::Split,
                lod: Some(flat),
                instances: &[],
                slots: 0,
            },
        )
    }

    fn build(ctx: &'a Context, source: Source) -> Result<Self, RenderError> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let small = |v: (usize, usize)| {
            v.0 <= Limits::DEFAULT.max_vertices as usize
                && v.1 <= Limits::DEFAULT.max_triangles as usize
        };
        let (mesh, ml, format, lod, instances, slots) = match source {
            Source::Descriptors {
                mesh,
                ml,
                format,
                lod,
                instances,
                slots,
            } => (mesh, ml, format, lod, instances, slots),
            Source::Compressed(up, subgroups) => {
                return Self::build_compressed(ctx, up, small(up.max_counts), subgroups)
            }
        };
        let limits = ml.meshlets.iter().fold((0, 0), |(v, t), m| {
            (
                v.max(m.vertex_count as usize),
                t.max(m.triangle_count as usize),
            )
        });
        let size = if small(limits) {
            Size::Small
        } else {
            Size::Large
        };
        let task_spv = shader(Shader::MeshletTask(layout_of(format)));
        let mesh_spv = shader(Shader::MeshletMesh(layout_of(format), size));
        let packed = descriptor::pack(mesh, ml, format)?;
        let task: Vec<[f32; 4]> = if packed.task.is_empty() {
            vec![[0.0; 4]]
        } else {
            packed.task.clone()
        };
        let uploads = Uploads {
            positions: ctx.upload(
                &mesh.positions,
                storage | vk::BufferUsageFlags::VERTEX_BUFFER,
            )?,
            descriptors: ctx.upload(&nonempty(&packed.descriptors), storage)?,
            data: ctx.upload(&nonempty(&packed.data), storage)?,
            triangles: ctx.upload(&nonempty(&packed.triangles), storage)?,
            task: ctx.upload(&task, storage)?,
            index: ctx.upload(&mesh.indices, vk::BufferUsageFlags::INDEX_BUFFER)?,
            lod_records: match lod {
                Some(f) if !f.records.is_empty() => ctx.upload(&f.records, storage)?,
                _ => ctx.upload(&[0u32; 4], storage)?,
            },
            lod_view: ctx.buffer(std::mem::size_of::<ViewData>() as u64, storage)?,
            instances: match instances {
                [] => ctx.upload(&[0u32; 4], storage)?,
                r => ctx.upload(r, storage)?,
            },
        };
        let lod_task = lod.map(|_| shader(Shader::LodTask));
        let modules = Modules {
            task: Some(task_spv),
            mesh: Some(mesh_spv),
            vertex: Some((shader(Shader::BaselineVert), Input::Buffer)),
            lod_task,
        };
        let lod_layout = lod.map(|f| LodLayout {
            starts: f.starts.clone(),
            total: f.records.len(),
        });
        Self::finish(
            ctx,
            uploads,
            modules,
            Fields {
                index_count: mesh.indices.len() as u32,
                meshlet_count: ml.len() as u32,
                slots: if slots > 0 { slots } else { ml.len() as u32 },
                drawn: Drawn::Descriptors(format),
                object: packed.object,
                device_bytes: packed.device_bytes(mesh.positions.len()),
            },
            lod_layout,
        )
    }

    fn build_compressed(
        ctx: &'a Context,
        up: &Upload,
        small: bool,
        subgroups: bool,
    ) -> Result<Self, RenderError> {
        use crate::compress::Codec as C;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let how = super::compressed::decoder(up.format)?;
        let size = if small { Size::Small } else { Size::Large };
        let compact = match up.format {
            C::TsCompact => Some(Compact::Ts),
            C::IxCompact => Some(Compact::Ix),
            C::ScCompact => Some(Compact::Sc),
            C::GiCompact => Some(Compact::Gi),
            _ => None,
        };
        let (task, mesh, vertex) = match (up.format, how, compact) {
            (C::LacedWires, _, _) => (
                Some(shader(Shader::CompressedTask { laced: true })),
                Some(shader(Shader::LacedMesh { small, subgroups })),
                None,
            ),
            (_, Decoder::Mesh, Some(c)) => (
                Some(shader(Shader::CompressedTask { laced: false })),
                Some(shader(Shader::CompactMesh(c, size))),
                None,
            ),
            (_, Decoder::Vertex, Some(c)) => (None, None, Some(shader(Shader::CompactVert(c)))),
            // `decoder` refuses every other format.
            _ => return Err(RenderError::NoShaderDecoder(up.format.name())),
        };
        let dummy = [0u32; 4];
        let uploads = Uploads {
            positions: ctx.upload(&dummy, storage)?,
            descriptors: ctx.upload(&up.offsets, storage)?,
            data: ctx.upload(&up.words, storage)?,
            triangles: ctx.upload(&nonempty(&up.first_triangle), storage)?,
            task: ctx.upload(&dummy, storage)?,
            index: ctx.upload(&dummy, vk::BufferUsageFlags::INDEX_BUFFER)?,
            lod_records: ctx.upload(&dummy, storage)?,
            lod_view: ctx.upload(&dummy, storage)?,
            instances: ctx.upload(&dummy, storage)?,
        };
        let modules = Modules {
            task,
            mesh,
            vertex: vertex.map(|v| (v, Input::Pulled)),
            lod_task: None,
        };
        Self::finish(
            ctx,
            uploads,
            modules,
            Fields {
                index_count: 3 * up.triangles as u32,
                meshlet_count: up.meshlets() as u32,
                slots: up.meshlets() as u32,
                drawn: Drawn::Compressed(up.format, how),
                object: descriptor::ObjectBox {
                    min: up.origin,
                    step: [up.step; 3],
                },
                device_bytes: up.device_bytes(),
            },
            None,
        )
    }

    /// The descriptor layout the meshlets were uploaded in (split for a compressed pass, whose
    /// layout is [`Pass::drawn`]).
    pub fn format(&self) -> DescriptorFormat {
        match self.drawn {
            Drawn::Descriptors(f) => f,
            Drawn::Compressed(..) => DescriptorFormat::Split,
        }
    }

    /// What the pass holds: a descriptor layout or a compressed format.
    pub fn drawn(&self) -> Drawn {
        self.drawn
    }

    /// The pipeline that draws this pass's data: the mesh pipeline (with `cull`ing where the data
    /// has bounds), or the vertex pipeline for GI and TS compact.
    pub fn native(&self, cull: bool) -> Pipeline {
        match self.drawn {
            Drawn::Compressed(_, Decoder::Vertex) => Pipeline::Vertex,
            _ => Pipeline::mesh(cull),
        }
    }

    /// Bytes of the largest storage buffer the pass binds (at most the device's
    /// `maxStorageBufferRange`; the vertex and index buffers are not storage bindings).
    pub fn largest_storage_binding(&self) -> u64 {
        self.largest_binding
    }

    /// Device bytes the scene holds: positions, meshlet descriptors and data, culling data,
    /// index buffer, instance records and visibility words (not the render targets, the pyramid
    /// or the check's buffers, which depend on the image alone).
    pub fn scene_bytes(&self) -> u64 {
        let b = &self.bindings;
        [
            &b.positions,
            &b.descriptors,
            &b.data,
            &b.triangles,
            &b.task,
            &self.index,
            &b.instances,
            &b.visibility,
        ]
        .iter()
        .map(|x| x.size)
        .sum()
    }

    /// The part of [`Pass::scene_bytes`] that grows with the instances: their records and one
    /// visibility word per (instance, meshlet).
    pub fn per_instance_bytes(&self) -> u64 {
        self.bindings.instances.size + self.bindings.visibility.size
    }

    /// Device bytes of the meshlet data in this layout (see `Packed::device_bytes`).
    pub fn device_bytes(&self) -> usize {
        self.device_bytes
    }

    /// Draws one frame from `camera` with `how`.
    pub fn render(
        &self,
        camera: &Camera,
        how: Pipeline,
        shading: Shading,
    ) -> Result<Frame, RenderError> {
        let flag = |on: bool, f: u32| if on { f } else { 0 };
        let (pipeline, flags) = match how {
            Pipeline::Mesh {
                frustum,
                cone,
                colour_ids,
            } => (
                if colour_ids {
                    &self.mesh_ids
                } else {
                    &self.mesh_shade
                },
                flag(frustum, FLAG_FRUSTUM) | flag(cone, FLAG_CONE),
            ),
            Pipeline::Vertex => (&self.vertex, 0),
        };
        let mesh = matches!(how, Pipeline::Mesh { .. });
        let Some(pipeline) = pipeline else {
            // Only compressed passes lack a pipeline: each format has one decoder.
            let what = match self.drawn {
                Drawn::Compressed(f, _) => f.name(),
                Drawn::Descriptors(f) => f.to_string(),
            };
            return Err(RenderError::NoShaderDecoder(format!(
                "{what} through the {} pipeline",
                if mesh { "mesh" } else { "vertex" }
            )));
        };
        self.frame(
            camera,
            pipeline.get(),
            flags,
            shading,
            self.meshlet_count,
            mesh,
        )
    }

    /// Draws one frame of a LOD pass ([`Pass::with_lod`]) from `camera`: the task shader selects
    /// the cut for `q` (its view, threshold, loaded levels and culling; `q.view.eye` should be the
    /// camera's eye) and draws it, coloured by meshlet id when `colour_ids`.
    pub fn render_lod(
        &self,
        camera: &Camera,
        q: &Query,
        colour_ids: bool,
        shading: Shading,
    ) -> Result<Frame, RenderError> {
        self.lod_frame(camera, q, colour_ids, shading, 0)
    }

    /// [`Pass::render_lod`], with the task shader also recording which meshlets it launched: the
    /// frame and the drawn meshlets' flat indices, ascending (for comparing the GPU's cut with
    /// [`crate::lod::flat::select_meshlets`] meshlet by meshlet; the benchmarks draw without it).
    pub fn render_lod_ids(
        &self,
        camera: &Camera,
        q: &Query,
        shading: Shading,
    ) -> Result<(Frame, Vec<u32>), RenderError> {
        let frame = self.lod_frame(camera, q, false, shading, FLAG_RECORD_IDS)?;
        let counters = &self.bindings.counters;
        let bits = counters.read(counters.size as usize);
        let words: &[u32] = bytemuck::cast_slice(&bits[COUNTER_BYTES as usize..]);
        let ids = words
            .iter()
            .enumerate()
            .flat_map(|(w, &b)| {
                (0..32)
                    .filter(move |k| b >> k & 1 == 1)
                    .map(move |k| 32 * w as u32 + k)
            })
            .collect();
        Ok((frame, ids))
    }

    fn lod_frame(
        &self,
        camera: &Camera,
        q: &Query,
        colour_ids: bool,
        shading: Shading,
        flags: u32,
    ) -> Result<Frame, RenderError> {
        let (layout, (shade, ids)) = self.lod.as_ref().ok_or(RenderError::NotLod)?;
        let view = ViewData::new(q, layout.loaded(q.finest));
        self.bindings.lod_view.write(bytemuck::bytes_of(&view));
        let pipeline = if colour_ids { ids.get() } else { shade.get() };
        self.frame(camera, pipeline, flags, shading, view.loaded, true)
    }
}

impl Drop for Pass<'_> {
    fn drop(&mut self) {
        // SAFETY: waiting is always allowed; afterwards no submitted work uses the pass's objects,
        // which its fields then free in declaration order.
        let _ = unsafe { self.ctx.device.device_wait_idle() };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_are_declared_in_binding_order() {
        assert_eq!(Bindings::NAMES, interface::BINDINGS);
        for (i, name) in interface::BINDINGS.iter().enumerate() {
            assert_eq!(interface::binding(name), i as u32);
        }
    }

    #[test]
    fn every_descriptor_layout_has_its_shaders() {
        for f in [
            DescriptorFormat::Split,
            DescriptorFormat::NvidiaA,
            DescriptorFormat::NvidiaB,
            DescriptorFormat::Monolithic,
        ] {
            assert_eq!(layout_of(f).name(), f.to_string());
        }
        let all = Shader::all();
        assert_eq!(all.len(), super::super::SHADERS.len());
        for (i, s) in all.iter().enumerate() {
            assert_eq!(s.index(), i, "{} listed twice", s.label());
        }
    }

    #[test]
    fn the_glsl_header_defines_every_constant() {
        let h = interface::glsl_header();
        for name in interface::BINDINGS {
            assert!(h.contains(&format!("#define BINDING_{} ", name.to_uppercase())));
        }
        assert!(h.contains(&format!("const uint FLAG_RECORD_IDS = {FLAG_RECORD_IDS}u;")));
        assert!(h.contains(&format!("#define TASK_GROUP {TASK_GROUP}\n")));
        assert_eq!(COUNTER_BYTES, 64);
        assert_eq!(
            (interface::IMAGE_WIDTH, interface::IMAGE_HEIGHT),
            (WIDTH, HEIGHT)
        );
        assert_eq!(interface::IMAGE_SAMPLES, SAMPLES.as_raw());
    }
}
