//! The Vulkan objects a pass is drawn with: render targets and graphics pipelines, each owned
//! (`Owned`) from the moment it exists.

use super::*;

pub(super) fn target(
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

pub(super) fn pipeline(
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
    // The front face is set per draw: a mirrored instance's is clockwise (core in Vulkan 1.3).
    let dynamic = [
        vk::DynamicState::VIEWPORT,
        vk::DynamicState::SCISSOR,
        vk::DynamicState::FRONT_FACE,
    ];
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

/// A descriptor set layout of `bindings`, a pool for one set of it and that set (freed with the
/// pool), each owned as soon as it exists.
pub(super) fn descriptor_set(
    d: &ash::Device,
    bindings: &[vk::DescriptorSetLayoutBinding],
) -> Result<
    (
        Owned<vk::DescriptorSetLayout>,
        Owned<vk::DescriptorPool>,
        vk::DescriptorSet,
    ),
    RenderError,
> {
    // SAFETY (this function's calls): valid create infos on a live device; every handle goes
    // straight into an `Owned`, which destroys it on every path out of here.
    let set_layout = Owned::new(
        d,
        unsafe {
            d.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(bindings),
                None,
            )
        }
        .map_err(vk_err("descriptor set layout"))?,
        vkc::destroy_descriptor_set_layout,
    );
    let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
    for b in bindings {
        match sizes.iter_mut().find(|s| s.ty == b.descriptor_type) {
            Some(s) => s.descriptor_count += b.descriptor_count,
            None => sizes.push(
                vk::DescriptorPoolSize::default()
                    .ty(b.descriptor_type)
                    .descriptor_count(b.descriptor_count),
            ),
        }
    }
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
    // One set from a pool sized for it; freed with the pool.
    let set = unsafe {
        d.allocate_descriptor_sets(
            &vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(pool.get())
                .set_layouts(&layouts),
        )
    }
    .map_err(vk_err("descriptor set"))?[0];
    Ok((set_layout, pool, set))
}

/// A pipeline layout of one descriptor set and `push` bytes of push constants for `stages`.
pub(super) fn pipeline_layout(
    d: &ash::Device,
    set_layout: vk::DescriptorSetLayout,
    push: u32,
    stages: vk::ShaderStageFlags,
) -> Result<Owned<vk::PipelineLayout>, RenderError> {
    let layouts = [set_layout];
    let ranges = [vk::PushConstantRange::default()
        .stage_flags(stages)
        .size(push)];
    // SAFETY: a valid create info on a live device; owned right away.
    let layout = unsafe {
        d.create_pipeline_layout(
            &vk::PipelineLayoutCreateInfo::default()
                .set_layouts(&layouts)
                .push_constant_ranges(&ranges),
            None,
        )
    }
    .map_err(vk_err("pipeline layout"))?;
    Ok(Owned::new(d, layout, vkc::destroy_pipeline_layout))
}
