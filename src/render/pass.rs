//! The render pass: 1280x720, 4x MSAA resolved to one sample, D32 depth (the paper's setup), drawn
//! either by the mesh-shader pipeline (task-shader culling, one mesh workgroup per meshlet) or by
//! the classic vertex pipeline (one indexed draw of the same mesh) as the baseline.

use super::compressed::{Decoder, Upload};
use super::context::{self as vkc, Buffer, Context, Owned};
use super::interface::{self, Compact, Layout, Shader, Size};
use super::{vk_err, Camera, RenderError, HEIGHT, WIDTH};
use crate::lod::flat::{loaded, Flat, Query, ViewData};
use crate::mesh::Mesh;
use crate::meshlet::descriptor::{self, Format};
use crate::meshlet::{Limits, Meshlets};
use ash::vk;

const SAMPLES: vk::SampleCountFlags = vk::SampleCountFlags::TYPE_4;
const COLOR: vk::Format = vk::Format::R8G8B8A8_UNORM;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;
use interface::{FLAG_CONE, FLAG_FRUSTUM, FLAG_RECORD_IDS, FLAG_UNLIT, TASK_GROUP};

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
}

impl Bindings {
    /// The field names, in declaration order.
    #[cfg(test)]
    const NAMES: [&'static str; 8] = [
        "positions",
        "descriptors",
        "data",
        "triangles",
        "task",
        "counters",
        "lod_records",
        "lod_view",
    ];

    /// The buffers in binding order.
    fn in_order(&self) -> [&Buffer; 8] {
        [
            &self.positions,
            &self.descriptors,
            &self.data,
            &self.triangles,
            &self.task,
            &self.counters,
            &self.lod_records,
            &self.lod_view,
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
fn layout_of(f: Format) -> Layout {
    match f {
        Format::Split => Layout::Split,
        Format::NvidiaA => Layout::NvidiaA,
        Format::NvidiaB => Layout::NvidiaB,
        Format::Monolithic => Layout::Monolithic,
    }
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
        up: Uploads,
        modules: Modules,
        fields: Fields,
        lod_layout: Option<LodLayout>,
    ) -> Result<Self, RenderError> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        // What the limit check names (the first five bindings hold the data).
        let checked = [
            (&up.positions, "positions"),
            (&up.descriptors, "descriptors / offsets"),
            (&up.data, "meshlet data"),
            (&up.triangles, "triangles / first triangles"),
            (&up.task, "task data"),
        ];
        let largest_binding = checked.iter().map(|(b, _)| b.size).max().unwrap_or(0);
        for (b, what) in checked {
            if b.size > ctx.max_storage_range {
                let (bytes, limit) = (b.size, ctx.max_storage_range);
                return Err(RenderError::TooLarge { what, bytes, limit });
            }
        }
        // The counters; a LOD pass adds one bit per meshlet for the drawn-id record
        // (`render_lod_ids`).
        let id_words = lod_layout.as_ref().map_or(0, |l| l.total.div_ceil(32));
        let counters = ctx.buffer(COUNTER_BYTES + 4 * id_words as u64, storage)?;
        let Uploads {
            positions,
            descriptors,
            data,
            triangles,
            task,
            index,
            lod_records,
            lod_view,
        } = up;
        let bindings = Bindings {
            positions,
            descriptors,
            data,
            triangles,
            task,
            counters,
            lod_records,
            lod_view,
        };
        let readback = ctx.buffer(
            WIDTH as u64 * HEIGHT as u64 * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        let d = &ctx.device;
        let stages = vk::ShaderStageFlags::TASK_EXT
            | vk::ShaderStageFlags::MESH_EXT
            | vk::ShaderStageFlags::VERTEX
            | vk::ShaderStageFlags::FRAGMENT;
        let layout_bindings: Vec<_> = (0..interface::BINDINGS.len() as u32)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        // SAFETY: valid create infos on the context's live device; each handle goes straight
        // into an `Owned`, which destroys it on every path out of here.
        let set_layout = Owned::new(
            d,
            unsafe {
                d.create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                    None,
                )
            }
            .map_err(vk_err("descriptor set layout"))?,
            vkc::destroy_descriptor_set_layout,
        );
        let sizes = [vk::DescriptorPoolSize::default()
            .ty(vk::DescriptorType::STORAGE_BUFFER)
            .descriptor_count(interface::BINDINGS.len() as u32)];
        // SAFETY: as above.
        let pool = Owned::new(
            d,
            unsafe {
                d.create_descriptor_pool(
                    &vk::DescriptorPoolCreateInfo::default()
                        .max_sets(1)
                        .pool_sizes(&sizes),
                    None,
                )
            }
            .map_err(vk_err("descriptor pool"))?,
            vkc::destroy_descriptor_pool,
        );
        let layouts = [set_layout.get()];
        // SAFETY: one set from a pool sized for it; freed with the pool.
        let set = unsafe {
            d.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(pool.get())
                    .set_layouts(&layouts),
            )
        }
        .map_err(vk_err("descriptor set"))?[0];
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
            .in_order()
            .iter()
            .map(|b| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(b.buf)
                    .range(vk::WHOLE_SIZE)]
            })
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .zip(0..)
            .map(|(info, binding)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(binding)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .buffer_info(info)
            })
            .collect();
        // SAFETY: the set is not in use yet; every write names a live buffer of this device.
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(stages)
            .size(std::mem::size_of::<Push>() as u32)];
        // SAFETY: as for the set layout.
        let layout = Owned::new(
            d,
            unsafe {
                d.create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default()
                        .set_layouts(&layouts)
                        .push_constant_ranges(&ranges),
                    None,
                )
            }
            .map_err(vk_err("pipeline layout"))?,
            vkc::destroy_pipeline_layout,
        );
        // Shader modules live until the pipelines are made: dropped at the end of this function.
        let module = |bytes: &[u8]| -> Result<Owned<vk::ShaderModule>, RenderError> {
            let code = spirv(bytes)?;
            // SAFETY: `code` is SPIR-V words read by ash; owned right away.
            let m = unsafe {
                d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
            }
            .map_err(vk_err("shader module"))?;
            Ok(Owned::new(d, m, vkc::destroy_shader_module))
        };
        let shade = module(shader(Shader::ShadeFrag))?;
        let ids = module(shader(Shader::MeshletIdFrag))?;
        let mut vertex = None;
        if let Some((code, input)) = modules.vertex {
            let vert = module(code)?;
            vertex = Some(pipeline(
                d,
                layout.get(),
                &[
                    (vk::ShaderStageFlags::VERTEX, vert.get()),
                    (vk::ShaderStageFlags::FRAGMENT, shade.get()),
                ],
                input,
            )?);
        }
        // Task + mesh pipelines, shaded and coloured by meshlet id.
        let mesh_pair = |task: &[u8], mesh: vk::ShaderModule| {
            let t = module(task)?;
            let pair = |frag: &Owned<vk::ShaderModule>| {
                pipeline(
                    d,
                    layout.get(),
                    &[
                        (vk::ShaderStageFlags::TASK_EXT, t.get()),
                        (vk::ShaderStageFlags::MESH_EXT, mesh),
                        (vk::ShaderStageFlags::FRAGMENT, frag.get()),
                    ],
                    Input::Mesh,
                )
            };
            Ok::<_, RenderError>((pair(&shade)?, pair(&ids)?))
        };
        let (mut mesh_shade, mut mesh_ids, mut lod_pipelines) = (None, None, None);
        if let (Some(task), Some(mesh)) = (modules.task, modules.mesh) {
            let meshm = module(mesh)?;
            let (s, i) = mesh_pair(task, meshm.get())?;
            (mesh_shade, mesh_ids) = (Some(s), Some(i));
            if let Some(lod_task) = modules.lod_task {
                lod_pipelines = Some(mesh_pair(lod_task, meshm.get())?);
            }
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
        let query_pool = |info: &vk::QueryPoolCreateInfo, what| {
            // SAFETY: a valid create info; owned right away.
            unsafe { d.create_query_pool(info, None) }
                .map(|q| Owned::new(d, q, vkc::destroy_query_pool))
                .map_err(vk_err(what))
        };
        let queries = query_pool(
            &vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::TIMESTAMP)
                .query_count(2),
            "query pool",
        )?;
        let mesh_queries = if ctx.mesh_queries {
            let stats = query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::PIPELINE_STATISTICS)
                    .pipeline_statistics(
                        vk::QueryPipelineStatisticFlags::TASK_SHADER_INVOCATIONS_EXT
                            | vk::QueryPipelineStatisticFlags::MESH_SHADER_INVOCATIONS_EXT,
                    )
                    .query_count(1),
                "statistics query pool",
            )?;
            let prims = query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::MESH_PRIMITIVES_GENERATED_EXT)
                    .query_count(1),
                "primitives query pool",
            )?;
            Some((stats, prims))
        } else {
            None
        };
        Ok(Self {
            ctx,
            index_count: fields.index_count,
            meshlet_count: fields.meshlet_count,
            drawn: fields.drawn,
            object: fields.object,
            device_bytes: fields.device_bytes,
            largest_binding,
            queries,
            mesh_queries,
            targets,
            mesh_shade,
            mesh_ids,
            vertex,
            lod: lod_layout.zip(lod_pipelines),
            layout,
            set,
            _pool: pool,
            _set_layout: set_layout,
            bindings,
            index,
            readback,
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
    /// [`crate::lod::flat::select`] meshlet by meshlet; the benchmarks draw without it).
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
            _ => self.bindings.counters.size,
        };
        self.bindings.counters.write(&vec![0u8; clear as usize]);
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
            flags: flags
                | if shading == Shading::Unlit {
                    FLAG_UNLIT
                } else {
                    0
                },
        };
        let [msaa, resolve, depth] = &self.targets;
        let (msaa, resolve, depth) = (
            (msaa.image.get(), msaa.view.get()),
            (resolve.image.get(), resolve.view.get()),
            (depth.image.get(), depth.view.get()),
        );
        let timestamps = self.queries.get();
        let mesh_pools = self.mesh_queries.as_ref().map(|(s, p)| (s.get(), p.get()));
        // SAFETY: `submit` hands a command buffer in the recording state and waits for it; every
        // handle recorded is owned by this pass and lives past the wait.
        ctx.submit(|cmd| unsafe {
            d.cmd_reset_query_pool(cmd, timestamps, 0, 2);
            if let Some((stats, prims)) = mesh_pools {
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
                    msaa.0,
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    vk::ImageAspectFlags::COLOR,
                    colour_out,
                    vk::AccessFlags2::NONE,
                    colour_out,
                    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                ),
                barrier(
                    resolve.0,
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                    vk::ImageAspectFlags::COLOR,
                    vk::PipelineStageFlags2::TRANSFER | colour_out,
                    vk::AccessFlags2::NONE,
                    colour_out,
                    vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
                ),
                barrier(
                    depth.0,
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
                .image_view(msaa.1)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                .resolve_image_view(resolve.1)
                .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .clear_value(vk::ClearValue {
                    color: vk::ClearColorValue {
                        float32: [0.08, 0.09, 0.12, 1.0],
                    },
                })];
            let depth_att = vk::RenderingAttachmentInfo::default()
                .image_view(depth.1)
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
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, timestamps, 0);
            // Queries span the whole rendering (lavapipe left them unavailable when begun inside).
            let mesh_queries = if mesh { mesh_pools } else { None };
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
                self.layout.get(),
                0,
                &[self.set],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                self.layout.get(),
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
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.bindings.positions.buf], &[0]);
                d.cmd_bind_index_buffer(cmd, self.index.buf, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cmd, self.index_count, 1, 0, 0, 0);
            }
            d.cmd_end_rendering(cmd);
            if let Some((stats, prims)) = mesh_queries {
                d.cmd_end_query(cmd, prims, 0);
                d.cmd_end_query(cmd, stats, 0);
            }
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, timestamps, 1);
            let to_copy = [barrier(
                resolve.0,
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
                resolve.0,
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
        // SAFETY: the submission that wrote both timestamps has completed (`submit` waits).
        unsafe {
            d.get_query_pool_results(
                timestamps,
                0,
                &mut ts,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(vk_err("timestamps"))?;
        let c: Vec<u32> =
            bytemuck::cast_slice(&self.bindings.counters.read(COUNTER_BYTES as usize)).to_vec();
        let queries = match (mesh, mesh_pools) {
            (true, Some((stats, prims))) => {
                // In ash the slice length is the number of queries: one query, two statistics.
                let mut s = [[0u64; 2]];
                let mut p = [0u64];
                let flags = vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT;
                // SAFETY: both queries ended in the completed submission.
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
            culled_frustum: c[interface::COUNTER_CULLED_FRUSTUM],
            culled_cone: c[interface::COUNTER_CULLED_CONE],
            drawn: c[interface::COUNTER_DRAWN],
            culled_triangles: [
                c[interface::COUNTER_TRIANGLES_FRUSTUM],
                c[interface::COUNTER_TRIANGLES_CONE],
            ],
            not_selected: c[interface::COUNTER_NOT_SELECTED],
            queries,
        })
    }
}

impl Drop for Pass<'_> {
    fn drop(&mut self) {
        // SAFETY: waiting is always allowed; afterwards no submitted work uses the pass's objects,
        // which its fields then free in declaration order.
        let _ = unsafe { self.ctx.device.device_wait_idle() };
    }
}

fn target(
    ctx: &Context,
    format: vk::Format,
    samples: vk::SampleCountFlags,
    usage: vk::ImageUsageFlags,
) -> Result<Target, RenderError> {
    let d = &ctx.device;
    // SAFETY (this function's calls): valid create infos on a live device; every handle is owned
    // by an `Owned` as soon as it exists, so a later failure frees the earlier ones.
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
    let image = Owned::new(d, image, vkc::destroy_image);
    // SAFETY: `image` is a live image of this device.
    let req = unsafe { d.get_image_memory_requirements(image.get()) };
    let memory = Owned::new(
        d,
        ctx.allocate(req, vk::MemoryPropertyFlags::empty())?,
        vkc::free_memory,
    );
    // SAFETY: fresh memory of a type the requirements allow, bound once at offset 0.
    unsafe { d.bind_image_memory(image.get(), memory.get(), 0) }.map_err(vk_err("bind image"))?;
    let aspect = if format == DEPTH {
        vk::ImageAspectFlags::DEPTH
    } else {
        vk::ImageAspectFlags::COLOR
    };
    // SAFETY: a view of the bound image with a matching format and aspect; owned below.
    let view = unsafe {
        d.create_image_view(
            &vk::ImageViewCreateInfo::default()
                .image(image.get())
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
        view: Owned::new(d, view, vkc::destroy_image_view),
        image,
        _memory: memory,
    })
}

fn pipeline(
    d: &ash::Device,
    layout: vk::PipelineLayout,
    mods: &[(vk::ShaderStageFlags, vk::ShaderModule)],
    input: Input,
) -> Result<Owned<vk::Pipeline>, RenderError> {
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
    // SAFETY: every state the info points to lives until the call returns; owned right away.
    unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
        .map(|p| Owned::new(d, p[0], vkc::destroy_pipeline))
        .map_err(|(_, e)| RenderError::Vulkan("create graphics pipeline", e))
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
            Format::Split,
            Format::NvidiaA,
            Format::NvidiaB,
            Format::Monolithic,
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
        assert_eq!(COUNTER_BYTES, 32);
    }
}
