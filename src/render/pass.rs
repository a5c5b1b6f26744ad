//! The render pass: 1280x720, 4x MSAA resolved to one sample, D32 depth (the paper's setup), drawn
//! either by the mesh-shader pipeline (task-shader culling, one mesh workgroup per meshlet) or by
//! the classic vertex pipeline (one indexed draw of the same mesh) as the baseline.

use super::compressed::{Decoder, Upload};
use super::context::{Buffer, Context};
use super::{vk_err, Camera, RenderError, HEIGHT, WIDTH};
use crate::lod::flat::{loaded, Flat, Query, ViewData};
use crate::mesh::Mesh;
use crate::meshlet::descriptor::{self, Format};
use crate::meshlet::{Limits, Meshlets};
use ash::vk;

const SAMPLES: vk::SampleCountFlags = vk::SampleCountFlags::TYPE_4;
const COLOR: vk::Format = vk::Format::R8G8B8A8_UNORM;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
/// Meshlets per task workgroup (`TASK_GROUP` in glsl/common.glsl).
const TASK_GROUP: u32 = 32;

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
}

/// Bytes of the task shader's counters (`glsl/common.glsl`); a LOD pass's drawn-id bitmap follows.
const COUNTER_BYTES: u64 = 32;
/// Push-constant flag: the LOD task shader records each drawn meshlet's bit after the counters.
const FLAG_RECORD_IDS: u32 = 1 << 3;

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
    drawn: Drawn,
    object: descriptor::ObjectBox,
    device_bytes: usize,
}

struct Target {
    image: vk::Image,
    memory: vk::DeviceMemory,
    view: vk::ImageView,
}

/// What a pass holds on the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drawn {
    /// Positions and meshlets in a descriptor layout (meshlet pipeline and vertex baseline).
    Descriptors(Format),
    /// A compressed encoding decoded by the shaders ([`super::compressed`]).
    Compressed(crate::compress::file::Format, Decoder),
}

/// What `build` uploads from.
enum Source<'s> {
    Descriptors {
        mesh: &'s Mesh,
        ml: &'s Meshlets,
        format: Format,
        lod: Option<&'s Flat>,
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

/// A mesh and its meshlets on the device, with the pipelines and targets to draw them.
pub struct Pass<'a> {
    ctx: &'a Context,
    buffers: Vec<Buffer>,
    counters: Buffer,
    readback: Buffer,
    index_count: u32,
    meshlet_count: u32,
    drawn: Drawn,
    object: descriptor::ObjectBox,
    device_bytes: usize,
    /// The largest storage buffer bound (the one `maxStorageBufferRange` limits).
    largest_binding: u64,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    layout: vk::PipelineLayout,
    mesh_shade: vk::Pipeline,
    mesh_ids: vk::Pipeline,
    vertex: vk::Pipeline,
    /// For a LOD pass: the DAG's level layout and the (shaded, meshlet-id) LOD pipelines.
    lod: Option<(LodLayout, (vk::Pipeline, vk::Pipeline))>,
    targets: [Target; 3],
    queries: vk::QueryPool,
    /// Pipeline statistics (task, mesh invocations) and mesh primitives generated.
    mesh_queries: Option<(vk::QueryPool, vk::QueryPool)>,
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

fn shader(name: &str) -> &'static [u8] {
    super::SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, b)| *b)
        .unwrap_or_else(|| panic!("shader {name} not in SHADERS"))
}

impl<'a> Pass<'a> {
    /// Uploads `mesh` and `ml` in the split descriptor layout (bounds computed here) and builds the
    /// pipelines.
    pub fn new(ctx: &'a Context, mesh: &Mesh, ml: &Meshlets) -> Result<Self, RenderError> {
        Self::with_format(ctx, mesh, ml, Format::Split)
    }

    /// Uploads `mesh` and `ml` packed in `format` and builds the pipelines for it.
    pub fn with_format(
        ctx: &'a Context,
        mesh: &Mesh,
        ml: &Meshlets,
        format: Format,
    ) -> Result<Self, RenderError> {
        Self::build(
            ctx,
            Source::Descriptors {
                mesh,
                ml,
                format,
                lod: None,
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
                format: Format::Split,
                lod: Some(flat),
            },
        )
    }

    fn build(ctx: &'a Context, source: Source) -> Result<Self, RenderError> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let small = |v: (usize, usize)| {
            v.0 <= Limits::DEFAULT.max_vertices as usize
                && v.1 <= Limits::DEFAULT.max_triangles as usize
        };
        let (mesh, ml, format, lod) = match source {
            Source::Descriptors {
                mesh,
                ml,
                format,
                lod,
            } => (mesh, ml, format, lod),
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
        let size = if small(limits) { "64/126" } else { "256/256" };
        let task_spv = shader(&format!("meshlet.task ({format})"));
        let mesh_spv = shader(&format!("meshlet.mesh ({format}, {size})"));
        let packed = descriptor::pack(mesh, ml, format)?;
        let task: Vec<[f32; 4]> = if packed.task.is_empty() {
            vec![[0.0; 4]]
        } else {
            packed.task.clone()
        };
        let buffers = vec![
            ctx.upload(
                &mesh.positions,
                storage | vk::BufferUsageFlags::VERTEX_BUFFER,
            )?,
            ctx.upload(&nonempty(&packed.descriptors), storage)?,
            ctx.upload(&nonempty(&packed.data), storage)?,
            ctx.upload(&nonempty(&packed.triangles), storage)?,
            ctx.upload(&task, storage)?,
            ctx.upload(&mesh.indices, vk::BufferUsageFlags::INDEX_BUFFER)?,
            match lod {
                Some(f) if !f.records.is_empty() => ctx.upload(&f.records, storage)?,
                _ => ctx.upload(&[0u32; 4], storage)?,
            },
            ctx.buffer(std::mem::size_of::<ViewData>() as u64, storage)?,
        ];
        let lod_task = lod.map(|_| shader("meshlet.task (split, lod)"));
        let modules = Modules {
            task: Some(task_spv),
            mesh: Some(mesh_spv),
            vertex: Some((shader("baseline.vert"), Input::Buffer)),
            lod_task,
        };
        let lod_layout = lod.map(|f| LodLayout {
            starts: f.starts.clone(),
            total: f.records.len(),
        });
        Self::finish(
            ctx,
            buffers,
            modules,
            Fields {
                index_count: mesh.indices.len() as u32,
                meshlet_count: ml.len() as u32,
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
        use crate::compress::file::Format as C;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let how = super::compressed::decoder(up.format)?;
        let name = up.format.name();
        let size = if small { "64/126" } else { "256/256" };
        let (task, mesh, vertex) = match (up.format, how) {
            (C::LacedWires, _) => (
                Some(shader("compressed.task (laced-wires)")),
                Some(shader(&format!(
                    "laced.mesh (64/{}{})",
                    if small { 126 } else { 256 },
                    if subgroups { ", subgroups" } else { "" }
                ))),
                None,
            ),
            (_, Decoder::Mesh) => (
                Some(shader("compressed.task")),
                Some(shader(&format!("compact.mesh ({name}, {size})"))),
                None,
            ),
            (_, Decoder::Vertex) => (None, None, Some(shader(&format!("compact.vert ({name})")))),
        };
        let dummy = [0u32; 4];
        let buffers = vec![
            ctx.upload(&dummy, storage)?,
            ctx.upload(&up.offsets, storage)?,
            ctx.upload(&up.words, storage)?,
            ctx.upload(&nonempty(&up.first_triangle), storage)?,
            ctx.upload(&dummy, storage)?,
            ctx.upload(&dummy, vk::BufferUsageFlags::INDEX_BUFFER)?,
            ctx.upload(&dummy, storage)?,
            ctx.upload(&dummy, storage)?,
        ];
        let modules = Modules {
            task,
            mesh,
            vertex: vertex.map(|v| (v, Input::Pulled)),
            lod_task: None,
        };
        Self::finish(
            ctx,
            buffers,
            modules,
            Fields {
                index_count: 3 * up.triangles as u32,
                meshlet_count: up.meshlets() as u32,
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

    fn finish(
        ctx: &'a Context,
        buffers: Vec<Buffer>,
        modules: Modules,
        fields: Fields,
        lod_layout: Option<LodLayout>,
    ) -> Result<Self, RenderError> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        const NAMES: [&str; 5] = [
            "positions",
            "descriptors / offsets",
            "meshlet data",
            "triangles / first triangles",
            "task data",
        ];
        let largest_binding = buffers.iter().take(NAMES.len()).map(|b| b.size).max();
        for (b, what) in buffers.iter().zip(NAMES) {
            if b.size > ctx.max_storage_range {
                let (bytes, limit) = (b.size, ctx.max_storage_range);
                for b in &buffers {
                    ctx.destroy_buffer(b);
                }
                return Err(RenderError::TooLarge { what, bytes, limit });
            }
        }
        // Eight counters; a LOD pass adds one bit per meshlet for the drawn-id record
        // (`render_lod_ids`).
        let id_words = lod_layout.as_ref().map_or(0, |l| l.total.div_ceil(32));
        let counters = ctx.buffer(COUNTER_BYTES + 4 * id_words as u64, storage)?;
        let readback = ctx.buffer(
            WIDTH as u64 * HEIGHT as u64 * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        let d = &ctx.device;
        let stages = vk::ShaderStageFlags::TASK_EXT
            | vk::ShaderStageFlags::MESH_EXT
            | vk::ShaderStageFlags::VERTEX
            | vk::ShaderStageFlags::FRAGMENT;
        let bindings: Vec<_> = (0..8)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let set_layout = unsafe {
            d.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                None,
            )
        }
        .map_err(vk_err("descriptor set layout"))?;
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(8)];
        let pool = unsafe {
            d.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(1)
                    .pool_sizes(&sizes),
                None,
            )
        }
        .map_err(vk_err("descriptor pool"))?;
        let layouts = [set_layout];
        let set = unsafe {
            d.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(pool)
                    .set_layouts(&layouts),
            )
        }
        .map_err(vk_err("descriptor set"))?[0];
        // Bindings 0-4: positions and the packed meshlets; 5: counters; 6, 7: LOD records, view.
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers[..5]
            .iter()
            .chain([&counters, &buffers[6], &buffers[7]])
            .map(|b| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(b.buf)
                    .range(vk::WHOLE_SIZE)]
            })
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(i as u32)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(stages)
            .size(std::mem::size_of::<Push>() as u32)];
        let layout = unsafe {
            d.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default()
                    .set_layouts(&layouts)
                    .push_constant_ranges(&ranges),
                None,
            )
        }
        .map_err(vk_err("pipeline layout"))?;
        let module = |bytes: &[u8]| -> Result<vk::ShaderModule, RenderError> {
            let code = spirv(bytes)?;
            unsafe {
                d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
            }
            .map_err(vk_err("shader module"))
        };
        let shade = module(shader("shade.frag"))?;
        let ids = module(shader("meshlet_id.frag"))?;
        let mut made = vec![shade, ids];
        let null = vk::Pipeline::null();
        let mut vertex = null;
        if let Some((code, input)) = modules.vertex {
            let vert = module(code)?;
            made.push(vert);
            vertex = pipeline(
                d,
                layout,
                &[
                    (vk::ShaderStageFlags::VERTEX, vert),
                    (vk::ShaderStageFlags::FRAGMENT, shade),
                ],
                input,
            )?;
        }
        // Task + mesh pipelines, shaded and coloured by meshlet id.
        let mut mesh_pair = |task: &[u8], mesh: vk::ShaderModule| {
            let t = module(task)?;
            made.push(t);
            let mut pair = [null; 2];
            for (p, frag) in pair.iter_mut().zip([shade, ids]) {
                *p = pipeline(
                    d,
                    layout,
                    &[
                        (vk::ShaderStageFlags::TASK_EXT, t),
                        (vk::ShaderStageFlags::MESH_EXT, mesh),
                        (vk::ShaderStageFlags::FRAGMENT, frag),
                    ],
                    Input::Mesh,
                )?;
            }
            Ok::<_, RenderError>((pair[0], pair[1]))
        };
        let (mut mesh_shade, mut mesh_ids, mut lod_pipelines) = (null, null, None);
        if let (Some(task), Some(mesh)) = (modules.task, modules.mesh) {
            let meshm = module(mesh)?;
            (mesh_shade, mesh_ids) = mesh_pair(task, meshm)?;
            if let Some(lod_task) = modules.lod_task {
                lod_pipelines = Some(mesh_pair(lod_task, meshm)?);
            }
            made.push(meshm);
        }
        for m in made {
            unsafe { d.destroy_shader_module(m, None) };
        }
        let targets = [
            target(ctx, COLOR, SAMPLES, vk::ImageUsageFlags::COLOR_ATTACHMENT)?,
            target(
                ctx,
                COLOR,
                vk::SampleCountFlags::TYPE_1,
                vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            )?,
            target(
                ctx,
                DEPTH,
                SAMPLES,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            )?,
        ];
        let queries = unsafe {
            d.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::TIMESTAMP)
                    .query_count(2),
                None,
            )
        }
        .map_err(vk_err("query pool"))?;
        let mesh_queries = if ctx.mesh_queries {
            let stats = unsafe {
                d.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::PIPELINE_STATISTICS)
                        .pipeline_statistics(
                            vk::QueryPipelineStatisticFlags::TASK_SHADER_INVOCATIONS_EXT
                                | vk::QueryPipelineStatisticFlags::MESH_SHADER_INVOCATIONS_EXT,
                        )
                        .query_count(1),
                    None,
                )
            }
            .map_err(vk_err("statistics query pool"))?;
            let prims = unsafe {
                d.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::MESH_PRIMITIVES_GENERATED_EXT)
                        .query_count(1),
                    None,
                )
            }
            .map_err(vk_err("primitives query pool"))?;
            Some((stats, prims))
        } else {
            None
        };
        Ok(Self {
            ctx,
            buffers,
            counters,
            readback,
            index_count: fields.index_count,
            meshlet_count: fields.meshlet_count,
            drawn: fields.drawn,
            object: fields.object,
            device_bytes: fields.device_bytes,
            largest_binding: largest_binding.unwrap_or(0),
            set_layout,
            pool,
            set,
            layout,
            mesh_shade,
            mesh_ids,
            vertex,
            lod: lod_layout.zip(lod_pipelines),
            targets,
            queries,
            mesh_queries,
        })
    }

    /// The descriptor layout the meshlets were uploaded in (split for a compressed pass, whose
    /// layout is [`Pass::drawn`]).
    pub fn format(&self) -> Format {
        match self.drawn {
            Drawn::Descriptors(f) => f,
            Drawn::Compressed(..) => Format::Split,
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
        let (pipeline, flags) = match how {
            Pipeline::Mesh {
                frustum,
                cone,
                colour_ids,
            } => (
                if colour_ids {
                    self.mesh_ids
                } else {
                    self.mesh_shade
                },
                frustum as u32 | (cone as u32) << 1,
            ),
            Pipeline::Vertex => (self.vertex, 0),
        };
        let mesh = matches!(how, Pipeline::Mesh { .. });
        if pipeline == vk::Pipeline::null() {
            // Only compressed passes lack a pipeline: each format has one decoder.
            let what = match self.drawn {
                Drawn::Compressed(f, _) => f.name(),
                Drawn::Descriptors(f) => f.to_string(),
            };
            return Err(RenderError::NoShaderDecoder(format!(
                "{what} through the {} pipeline",
                if mesh { "mesh" } else { "vertex" }
            )));
        }
        self.frame(camera, pipeline, flags, shading, self.meshlet_count, mesh)
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
    /// [`crate::lod::flat::select`] meshlet by meshlet; the benchmarks draw without it).
    pub fn render_lod_ids(
        &self,
        camera: &Camera,
        q: &Query,
        shading: Shading,
    ) -> Result<(Frame, Vec<u32>), RenderError> {
        let frame = self.lod_frame(camera, q, false, shading, FLAG_RECORD_IDS)?;
        let bits = self.counters.read(self.counters.size as usize);
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
        self.buffers[7].write(bytemuck::bytes_of(&view));
        let pipeline = if colour_ids { *ids } else { *shade };
        self.frame(camera, pipeline, flags, shading, view.loaded, true)
    }

    fn frame(
        &self,
        camera: &Camera,
        pipeline: vk::Pipeline,
        flags: u32,
        shading: Shading,
        meshlet_count: u32,
        mesh: bool,
    ) -> Result<Frame, RenderError> {
        let ctx = self.ctx;
        let d = &ctx.device;
        // The drawn-id bitmap only when this frame records it (render_lod_ids reads it back).
        let clear = match flags & FLAG_RECORD_IDS {
            0 => COUNTER_BYTES,
            _ => self.counters.size,
        };
        self.counters.write(&vec![0u8; clear as usize]);
        let push = Push {
            view_proj: camera
                .view_proj(WIDTH as f32 / HEIGHT as f32)
                .to_cols_array(),
            camera: camera.eye.extend(1.0).to_array(),
            box_min: [
                self.object.min[0],
                self.object.min[1],
                self.object.min[2],
                0.0,
            ],
            box_step: [
                self.object.step[0],
                self.object.step[1],
                self.object.step[2],
                0.0,
            ],
            meshlet_count,
            flags: flags | u32::from(shading == Shading::Unlit) << 2,
        };
        let [msaa, resolve, depth] = &self.targets;
        ctx.submit(|cmd| unsafe {
            d.cmd_reset_query_pool(cmd, self.queries, 0, 2);
            if let Some((stats, prims)) = self.mesh_queries {
                d.cmd_reset_query_pool(cmd, stats, 0, 1);
                d.cmd_reset_query_pool(cmd, prims, 0, 1);
            }
            let barrier =
                |image, old, new, aspect, src_stage, src_access, dst_stage, dst_access| {
                    vk::ImageMemoryBarrier2::default()
                        .image(image)
                        .old_layout(old)
                        .new_layout(new)
                        .src_stage_mask(src_stage)
                        .src_access_mask(src_access)
                        .dst_stage_mask(dst_stage)
                        .dst_access_mask(dst_access)
                        .subresource_range(
                            vk::ImageSubresourceRange::default()
                                .aspect_mask(aspect)
                                .level_count(1)
                                .layer_count(1),
                        )
                };
            let colour_out = vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT;
            let depth_stages = vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
                | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS;
            let start = [
                barrier(
                    msaa.image,
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    vk::ImageAspectFlags::COLOR,
                    colour_out,
                    vk::AccessFlags2::NONE,
                    colour_out,
                    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                ),
                barrier(
                    resolve.image,
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    vk::ImageAspectFlags::COLOR,
                    vk::PipelineStageFlags2::TRANSFER | colour_out,
                    vk::AccessFlags2::NONE,
                    colour_out,
                    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                ),
                barrier(
                    depth.image,
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
                    vk::ImageAspectFlags::DEPTH,
                    depth_stages,
                    vk::AccessFlags2::NONE,
                    depth_stages,
                    vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE
                        | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
                ),
            ];
            d.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&start),
            );
            let colour = [vk::RenderingAttachmentInfo::default()
                .image_view(msaa.view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                .resolve_image_view(resolve.view)
                .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .clear_value(vk::ClearValue {
                    color: vk::ClearColorValue {
                        float32: [0.08, 0.09, 0.12, 1.0],
                    },
                })];
            let depth_att = vk::RenderingAttachmentInfo::default()
                .image_view(depth.view)
                .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .clear_value(vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue {
                        depth: 1.0,
                        stencil: 0,
                    },
                });
            let area = vk::Rect2D::default().extent(vk::Extent2D {
                width: WIDTH,
                height: HEIGHT,
            });
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, self.queries, 0);
            // Queries span the whole rendering (lavapipe left them unavailable when begun inside).
            let mesh_queries = if mesh { self.mesh_queries } else { None };
            if let Some((stats, prims)) = mesh_queries {
                d.cmd_begin_query(cmd, stats, 0, vk::QueryControlFlags::empty());
                d.cmd_begin_query(cmd, prims, 0, vk::QueryControlFlags::empty());
            }
            d.cmd_begin_rendering(
                cmd,
                &vk::RenderingInfo::default()
                    .render_area(area)
                    .layer_count(1)
                    .color_attachments(&colour)
                    .depth_attachment(&depth_att),
            );
            d.cmd_set_viewport(
                cmd,
                0,
                &[vk::Viewport::default()
                    .width(WIDTH as f32)
                    .height(HEIGHT as f32)
                    .max_depth(1.0)],
            );
            d.cmd_set_scissor(cmd, 0, &[area]);
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout,
                0,
                &[self.set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                self.layout,
                vk::ShaderStageFlags::TASK_EXT
                    | vk::ShaderStageFlags::MESH_EXT
                    | vk::ShaderStageFlags::VERTEX
                    | vk::ShaderStageFlags::FRAGMENT,
                0,
                bytemuck::bytes_of(&push),
            );
            if mesh {
                ctx.mesh
                    .cmd_draw_mesh_tasks(cmd, meshlet_count.div_ceil(TASK_GROUP), 1, 1);
            } else if matches!(self.drawn, Drawn::Compressed(..)) {
                d.cmd_draw(cmd, self.index_count, 1, 0, 0);
            } else {
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.buffers[0].buf], &[0]);
                d.cmd_bind_index_buffer(cmd, self.buffers[5].buf, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cmd, self.index_count, 1, 0, 0, 0);
            }
            d.cmd_end_rendering(cmd);
            if let Some((stats, prims)) = mesh_queries {
                d.cmd_end_query(cmd, prims, 0);
                d.cmd_end_query(cmd, stats, 0);
            }
            d.cmd_write_timestamp2(
                cmd,
                vk::PipelineStageFlags2::BOTTOM_OF_PIPE,
                self.queries,
                1,
            );
            let to_copy = [barrier(
                resolve.image,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::ImageAspectFlags::COLOR,
                colour_out,
                vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                vk::PipelineStageFlags2::TRANSFER,
                vk::AccessFlags2::TRANSFER_READ,
            )];
            d.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&to_copy),
            );
            d.cmd_copy_image_to_buffer(
                cmd,
                resolve.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.readback.buf,
                &[vk::BufferImageCopy::default()
                    .image_subresource(
                        vk::ImageSubresourceLayers::default()
                            .aspect_mask(vk::ImageAspectFlags::COLOR)
                            .layer_count(1),
                    )
                    .image_extent(vk::Extent3D {
                        width: WIDTH,
                        height: HEIGHT,
                        depth: 1,
                    })],
            );
            let host = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ)];
            d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&host));
        })?;
        let mut ts = [0u64; 2];
        unsafe {
            d.get_query_pool_results(
                self.queries,
                0,
                &mut ts,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(vk_err("timestamps"))?;
        let c: Vec<u32> = bytemuck::cast_slice(&self.counters.read(24)).to_vec();
        let queries = match (mesh, self.mesh_queries) {
            (true, Some((stats, prims))) => {
                // In ash the slice length is the number of queries: one query, two statistics.
                let mut s = [[0u64; 2]];
                let mut p = [0u64];
                let flags = vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT;
                unsafe {
                    d.get_query_pool_results(stats, 0, &mut s, flags)
                        .map_err(vk_err("pipeline statistics"))?;
                    d.get_query_pool_results(prims, 0, &mut p, flags)
                        .map_err(vk_err("mesh primitives generated"))?;
                }
                Some(MeshQueries {
                    task_invocations: s[0][0],
                    mesh_invocations: s[0][1],
                    primitives: p[0],
                })
            }
            _ => None,
        };
        Ok(Frame {
            pixels: self.readback.read((WIDTH * HEIGHT * 4) as usize),
            gpu_ns: ts[1].saturating_sub(ts[0]) as f64 * ctx.timestamp_period as f64,
            culled_frustum: c[0],
            culled_cone: c[1],
            drawn: c[2],
            culled_triangles: [c[3], c[4]],
            not_selected: c[5],
            queries,
        })
    }
}

impl Drop for Pass<'_> {
    fn drop(&mut self) {
        let ctx = self.ctx;
        let d = &ctx.device;
        unsafe {
            let _ = d.device_wait_idle();
            d.destroy_query_pool(self.queries, None);
            if let Some((stats, prims)) = self.mesh_queries {
                d.destroy_query_pool(stats, None);
                d.destroy_query_pool(prims, None);
            }
            for t in &self.targets {
                d.destroy_image_view(t.view, None);
                d.destroy_image(t.image, None);
                d.free_memory(t.memory, None);
            }
            for p in [self.mesh_shade, self.mesh_ids, self.vertex] {
                d.destroy_pipeline(p, None);
            }
            if let Some((_, (a, b))) = &self.lod {
                d.destroy_pipeline(*a, None);
                d.destroy_pipeline(*b, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
        for b in self.buffers.iter().chain([&self.counters, &self.readback]) {
            ctx.destroy_buffer(b);
        }
    }
}

fn target(
    ctx: &Context,
    format: vk::Format,
    samples: vk::SampleCountFlags,
    usage: vk::ImageUsageFlags,
) -> Result<Target, RenderError> {
    let d = &ctx.device;
    let image = unsafe {
        d.create_image(
            &vk::ImageCreateInfo::default()
                .image_type(vk::ImageType::TYPE_2D)
                .format(format)
                .extent(vk::Extent3D {
                    width: WIDTH,
                    height: HEIGHT,
                    depth: 1,
                })
                .mip_levels(1)
                .array_layers(1)
                .samples(samples)
                .tiling(vk::ImageTiling::OPTIMAL)
                .usage(usage),
            None,
        )
    }
    .map_err(vk_err("create image"))?;
    let req = unsafe { d.get_image_memory_requirements(image) };
    let memory = ctx.allocate(req, vk::MemoryPropertyFlags::empty())?;
    unsafe { d.bind_image_memory(image, memory, 0) }.map_err(vk_err("bind image"))?;
    let aspect = if format == DEPTH {
        vk::ImageAspectFlags::DEPTH
    } else {
        vk::ImageAspectFlags::COLOR
    };
    let view = unsafe {
        d.create_image_view(
            &vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(
                    vk::ImageSubresourceRange::default()
                        .aspect_mask(aspect)
                        .level_count(1)
                        .layer_count(1),
                ),
            None,
        )
    }
    .map_err(vk_err("create image view"))?;
    Ok(Target {
        image,
        memory,
        view,
    })
}

fn pipeline(
    d: &ash::Device,
    layout: vk::PipelineLayout,
    mods: &[(vk::ShaderStageFlags, vk::ShaderModule)],
    input: Input,
) -> Result<vk::Pipeline, RenderError> {
    let stages: Vec<_> = mods
        .iter()
        .map(|&(s, m)| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(s)
                .module(m)
                .name(c"main")
        })
        .collect();
    let attributes = [vk::VertexInputAttributeDescription::default()
        .location(0)
        .format(vk::Format::R32G32B32_SFLOAT)];
    let vbind = [vk::VertexInputBindingDescription::default()
        .stride(12)
        .input_rate(vk::VertexInputRate::VERTEX)];
    let vi = if input == Input::Buffer {
        vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_attribute_descriptions(&attributes)
            .vertex_binding_descriptions(&vbind)
    } else {
        vk::PipelineVertexInputStateCreateInfo::default()
    };
    let ia = vk::PipelineInputAssemblyStateCreateInfo::default()
        .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let vp = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    // Back faces are culled by the rasteriser in both pipelines (counter-clockwise = front, as in
    // meshoptimizer and the meshlet cones), so task-shader cone culling removes nothing visible.
    let rs = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::BACK)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let ms = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(SAMPLES);
    let ds = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(true)
        .depth_write_enable(true)
        .depth_compare_op(vk::CompareOp::LESS);
    let blend = [vk::PipelineColorBlendAttachmentState::default()
        .color_write_mask(vk::ColorComponentFlags::RGBA)];
    let cb = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
    let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dy = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
    let formats = [COLOR];
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(&formats)
        .depth_attachment_format(DEPTH);
    let mut info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .viewport_state(&vp)
        .rasterization_state(&rs)
        .multisample_state(&ms)
        .depth_stencil_state(&ds)
        .color_blend_state(&cb)
        .dynamic_state(&dy)
        .layout(layout)
        .push_next(&mut rendering);
    if input != Input::Mesh {
        info = info.vertex_input_state(&vi).input_assembly_state(&ia);
    }
    unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
        .map(|p| p[0])
        .map_err(|(_, e)| RenderError::Vulkan("create graphics pipeline", e))
}
