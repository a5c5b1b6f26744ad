//! Making a pass's device objects once its data is uploaded: the counters and bindings, the
//! descriptor set, the pipeline layout, the shader modules (dropped once the pipelines exist),
//! the pipelines, targets and query pools. Everything is owned as soon as it exists, so an error
//! anywhere frees what was already made.

use super::*;

impl<'a> Pass<'a> {
    pub(super) fn finish(
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
            visibility: ctx.buffer(4 * fields.slots as u64, storage)?,
            // The levels, then the view-projection they were built with (16 floats).
            pyramid: ctx.buffer(4 * (occlusion::pyramid_texels() as u64 + 16), storage)?,
            ids: ctx.buffer(
                8 * SAMPLES.as_raw() as u64 * WIDTH as u64 * HEIGHT as u64,
                storage | vk::BufferUsageFlags::TRANSFER_DST,
            )?,
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
        let layout = objects::pipeline_layout(
            d,
            set_layout.get(),
            std::mem::size_of::<Push>() as u32,
            stages,
        )?;
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
        let (mut mesh_check, mut lod_check) = (None, None);
        if let (Some(task), Some(mesh)) = (modules.task, modules.mesh) {
            let meshm = module(mesh)?;
            let (s, i) = mesh_pair(task, meshm.get())?;
            (mesh_shade, mesh_ids) = (Some(s), Some(i));
            // The occlusion check's id shader (64-bit atomics), for the meshlet layouts.
            let check_pipeline = |task: &[u8]| {
                let (t, f) = (module(task)?, module(shader(Shader::DepthIdFrag))?);
                pipeline(
                    d,
                    layout.get(),
                    &[
                        (vk::ShaderStageFlags::TASK_EXT, t.get()),
                        (vk::ShaderStageFlags::MESH_EXT, meshm.get()),
                        (vk::ShaderStageFlags::FRAGMENT, f.get()),
                    ],
                    Input::Mesh,
                )
            };
            if ctx.id_check && matches!(fields.drawn, Drawn::Descriptors(_)) {
                mesh_check = Some(check_pipeline(task)?);
            }
            if let Some(lod_task) = modules.lod_task {
                lod_pipelines = Some(mesh_pair(lod_task, meshm.get())?);
                if ctx.id_check {
                    lod_check = Some(check_pipeline(lod_task)?);
                }
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
            // Sampled: the occlusion pyramid and the exactness check read it in a compute shader.
            target(
                ctx,
                DEPTH,
                SAMPLES,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
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
            mesh_check,
            vertex,
            lod: lod_layout.zip(lod_pipelines),
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
            lod_check,
            occlusion: Default::default(),
        })
    }
}
