//! Making a pass's device objects once its data is uploaded: the counters and bindings, the
//! descriptor set, the pipeline layout, the shader modules (dropped once the pipelines exist),
//! the pipelines, targets and query pools. Everything is owned as soon as it exists, so an error
//! anywhere frees what was already made.

use super::*;

/// The pipelines of a pass, each where its shaders can draw the data.
#[derive(Default)]
struct Pipelines {
    vertex: Option<Owned<vk::Pipeline>>,
    mesh_shade: Option<Owned<vk::Pipeline>>,
    mesh_ids: Option<Owned<vk::Pipeline>>,
    mesh_check: Option<Owned<vk::Pipeline>>,
    lod: Option<PipelinePair>,
    lod_check: Option<Owned<vk::Pipeline>>,
}

/// What every task + mesh pipeline of a pass shares: the layout, the mesh shader and the
/// fragment shaders.
struct MeshStages<'d> {
    d: &'d ash::Device,
    layout: vk::PipelineLayout,
    mesh: vk::ShaderModule,
    shade: vk::ShaderModule,
    ids: vk::ShaderModule,
}

/// Timestamps (2) of a frame, and the mesh-shader queries where the device has them.
type Queries = (
    Owned<vk::QueryPool>,
    Option<(Owned<vk::QueryPool>, Owned<vk::QueryPool>)>,
);

impl<'a> Pass<'a> {
    /// The pass over uploaded data `up`: its bindings, descriptor set, pipelines, targets and
    /// queries.
    pub(super) fn finish(
        ctx: &'a Context,
        up: Uploads,
        modules: Modules,
        fields: Fields,
        lod_layout: Option<LodLayout>,
    ) -> Result<Self, RenderError> {
        let largest_binding = check_binding_limits(ctx, &up)?;
        // The counters; a LOD pass adds one bit per meshlet for the drawn-id record
        // (`render_lod_ids`).
        let id_words = lod_layout.as_ref().map_or(0, |l| l.total.div_ceil(32));
        let (bindings, index) = make_bindings(ctx, up, id_words, fields.slots)?;
        let readback = ctx.buffer(
            WIDTH as u64 * HEIGHT as u64 * 4,
            vk::BufferUsageFlags::TRANSFER_DST,
        )?;
        let d = &ctx.device;
        let (set_layout, pool, set) = make_descriptor_set(d, &bindings)?;
        let layout = objects::pipeline_layout(
            d,
            set_layout.get(),
            std::mem::size_of::<Push>() as u32,
            graphics_stages(),
        )?;
        let pipelines = make_pipelines(ctx, layout.get(), modules, fields.drawn)?;
        let targets = make_targets(ctx)?;
        let (queries, mesh_queries) = make_queries(ctx)?;
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
            mesh_shade: pipelines.mesh_shade,
            mesh_ids: pipelines.mesh_ids,
            mesh_check: pipelines.mesh_check,
            vertex: pipelines.vertex,
            lod: lod_layout.zip(pipelines.lod),
            layout,
            set,
            _pool: pool,
            _set_layout: set_layout,
            bindings,
            index,
            readback,
            draws: None,
            slots: fields.slots,
            pyramid_view: Default::default(),
            lod_check: pipelines.lod_check,
            occlusion: Default::default(),
        })
    }
}

/// The stages that read descriptor set 0 and the push constants.
fn graphics_stages() -> vk::ShaderStageFlags {
    vk::ShaderStageFlags::TASK_EXT
        | vk::ShaderStageFlags::MESH_EXT
        | vk::ShaderStageFlags::VERTEX
        | vk::ShaderStageFlags::FRAGMENT
}

/// Refuses a data binding over the device's storage-buffer range; the largest one's bytes.
fn check_binding_limits(ctx: &Context, up: &Uploads) -> Result<u64, RenderError> {
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
    Ok(largest_binding)
}

/// Makes the buffers the pass itself fills (counters with `id_words` more words, visibility,
/// pyramid, ids) and puts them with the uploads in binding order; the index buffer apart.
fn make_bindings(
    ctx: &Context,
    up: Uploads,
    id_words: usize,
    slots: u32,
) -> Result<(Bindings, Buffer), RenderError> {
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
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
        instances,
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
        instances,
        visibility: ctx.buffer(4 * slots as u64, storage)?,
        // The levels, then the view-projection they were built with (16 floats).
        pyramid: ctx.buffer(4 * (occlusion::pyramid_texels() as u64 + 16), storage)?,
        ids: ctx.buffer(
            8 * SAMPLES.as_raw() as u64 * WIDTH as u64 * HEIGHT as u64,
            storage | vk::BufferUsageFlags::TRANSFER_DST,
        )?,
    };
    Ok((bindings, index))
}

/// Makes descriptor set 0 (one storage buffer per binding) and points it at `bindings`.
fn make_descriptor_set(
    d: &ash::Device,
    bindings: &Bindings,
) -> Result<
    (
        Owned<vk::DescriptorSetLayout>,
        Owned<vk::DescriptorPool>,
        vk::DescriptorSet,
    ),
    RenderError,
> {
    let layout_bindings: Vec<_> = (0..interface::BINDINGS.len() as u32)
        .map(|b| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(b)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(graphics_stages())
        })
        .collect();
    let (set_layout, pool, set) = objects::descriptor_set(d, &layout_bindings)?;
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
    Ok((set_layout, pool, set))
}

/// A shader module of SPIR-V `bytes`, owned.
fn shader_module(d: &ash::Device, bytes: &[u8]) -> Result<Owned<vk::ShaderModule>, RenderError> {
    let code = spirv(bytes)?;
    // SAFETY: `code` is SPIR-V words read by ash; owned right away.
    let m =
        unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None) }
            .map_err(vk_err("shader module"))?;
    Ok(Owned::new(d, m, vkc::destroy_shader_module))
}

/// Makes every pipeline `modules` has shaders for: the vertex pipeline, the task + mesh
/// pipelines (shaded, coloured by meshlet id, the occlusion check's) and the LOD ones.
fn make_pipelines(
    ctx: &Context,
    layout: vk::PipelineLayout,
    modules: Modules,
    drawn: Drawn,
) -> Result<Pipelines, RenderError> {
    let d = &ctx.device;
    // Shader modules live until the pipelines are made: dropped at the end of this function.
    let shade = shader_module(d, shader(Shader::ShadeFrag))?;
    let ids = shader_module(d, shader(Shader::MeshletIdFrag))?;
    let mut p = Pipelines::default();
    if let Some((code, input)) = modules.vertex {
        let vert = shader_module(d, code)?;
        p.vertex = Some(pipeline(
            d,
            layout,
            &[
                (vk::ShaderStageFlags::VERTEX, vert.get()),
                (vk::ShaderStageFlags::FRAGMENT, shade.get()),
            ],
            input,
        )?);
    }
    if let (Some(task), Some(mesh)) = (modules.task, modules.mesh) {
        let meshm = shader_module(d, mesh)?;
        let stages = MeshStages {
            d,
            layout,
            mesh: meshm.get(),
            shade: shade.get(),
            ids: ids.get(),
        };
        let (s, i) = stages.pair(task)?;
        (p.mesh_shade, p.mesh_ids) = (Some(s), Some(i));
        if ctx.id_check && matches!(drawn, Drawn::Descriptors(_)) {
            p.mesh_check = Some(stages.check(task)?);
        }
        if let Some(lod_task) = modules.lod_task {
            p.lod = Some(stages.pair(lod_task)?);
            if ctx.id_check {
                p.lod_check = Some(stages.check(lod_task)?);
            }
        }
    }
    Ok(p)
}

impl MeshStages<'_> {
    /// The task shader `task`'s pipelines, shaded and coloured by meshlet id.
    fn pair(&self, task: &[u8]) -> Result<PipelinePair, RenderError> {
        let t = shader_module(self.d, task)?;
        let with = |frag: vk::ShaderModule| self.pipeline(t.get(), frag);
        Ok((with(self.shade)?, with(self.ids)?))
    }

    /// The task shader `task`'s pipeline through the occlusion check's id shader (64-bit
    /// atomics), for the meshlet layouts.
    fn check(&self, task: &[u8]) -> Result<Owned<vk::Pipeline>, RenderError> {
        let t = shader_module(self.d, task)?;
        let f = shader_module(self.d, shader(Shader::DepthIdFrag))?;
        self.pipeline(t.get(), f.get())
    }

    /// The pipeline of task shader `task`, the mesh shader and fragment shader `frag`.
    fn pipeline(
        &self,
        task: vk::ShaderModule,
        frag: vk::ShaderModule,
    ) -> Result<Owned<vk::Pipeline>, RenderError> {
        pipeline(
            self.d,
            self.layout,
            &[
                (vk::ShaderStageFlags::TASK_EXT, task),
                (vk::ShaderStageFlags::MESH_EXT, self.mesh),
                (vk::ShaderStageFlags::FRAGMENT, frag),
            ],
            Input::Mesh,
        )
    }
}

/// The render targets: 4x MSAA colour, its one-sample resolve, and the 4x MSAA depth.
fn make_targets(ctx: &Context) -> Result<[Target; 3], RenderError> {
    Ok([
        target(ctx, COLOR, SAMPLES, vk::ImageUsageFlags::COLOR_ATTACHMENT)?,
        target(
            ctx,
            COLOR,
            vk::SampleCountFlags::TYPE_1,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
        )?,
        // Sampled: the occlusion pyramid and the exactness check read it in a compute shader.
        target(
            ctx,
            DEPTH,
            SAMPLES,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        )?,
    ])
}

/// Makes the timestamp pool and, where the device has `meshShaderQueries`, the pipeline
/// statistics and mesh-primitives pools.
fn make_queries(ctx: &Context) -> Result<Queries, RenderError> {
    let d = &ctx.device;
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
    Ok((queries, mesh_queries))
}
