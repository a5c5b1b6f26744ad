//! Recording and reading back one frame: the barriers, the dynamic-rendering pass with its
//! timestamps and mesh-pipeline queries, the draw, the copy of the resolved image, and the
//! counters the task shader wrote.

use super::*;

/// One draw: its push constants, index range (vertex pipeline) and whether it is mirrored.
pub(super) type DrawCmd = (Push, u32, u32, bool);

impl Pass<'_> {
    /// The push constants of a frame from `camera` (for one draw of everything).
    pub(super) fn push(
        &self,
        camera: &Camera,
        flags: u32,
        shading: Shading,
        meshlet_count: u32,
    ) -> Push {
        Push {
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
            instance: 0,
            meshlet_first: 0,
        }
    }

    /// The draws of a frame: one per instance the frustum meets (instanced passes, with the
    /// instances dropped), else `push` alone.
    pub(super) fn draw_list(&self, camera: &Camera, push: Push) -> (Vec<DrawCmd>, u32) {
        let view_proj = camera.view_proj(WIDTH as f32 / HEIGHT as f32);
        let mut culled_instances = 0;
        let draws = match &self.draws {
            None => vec![(push, 0, self.index_count, false)],
            Some(draws) => draws
                .iter()
                .filter(|d| {
                    let out = push.flags & FLAG_FRUSTUM != 0
                        && instances::outside_frustum(view_proj, d.sphere);
                    culled_instances += u32::from(out);
                    !out
                })
                .map(|d| {
                    let p = Push {
                        meshlet_count: d.meshlet_count,
                        flags: push.flags | FLAG_INSTANCED,
                        instance: d.instance,
                        meshlet_first: d.meshlet_first,
                        ..push
                    };
                    (p, d.index_first, d.index_count, d.mirrored)
                })
                .collect(),
        };
        (draws, culled_instances)
    }

    /// Records `draws` inside a rendering, pipeline and descriptor set bound (`mesh`: through the
    /// task and mesh shaders).
    ///
    /// # Safety
    /// `cmd` is recording inside a rendering of this pass with its pipeline layout bound.
    pub(super) unsafe fn record_draws(
        &self,
        cmd: vk::CommandBuffer,
        draws: &[DrawCmd],
        mesh: bool,
    ) {
        let d = &self.ctx.device;
        // SAFETY: the caller's contract; every handle is this pass's.
        unsafe {
            if !mesh && !matches!(self.drawn, Drawn::Compressed(..)) {
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.bindings.positions.buf], &[0]);
                d.cmd_bind_index_buffer(cmd, self.index.buf, 0, vk::IndexType::UINT32);
            }
            for &(push, index_first, index_count, mirrored) in draws {
                d.cmd_set_front_face(
                    cmd,
                    if mirrored {
                        vk::FrontFace::CLOCKWISE
                    } else {
                        vk::FrontFace::COUNTER_CLOCKWISE
                    },
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
                    if push.meshlet_count > 0 {
                        self.ctx.mesh.cmd_draw_mesh_tasks(
                            cmd,
                            push.meshlet_count.div_ceil(TASK_GROUP),
                            1,
                            1,
                        );
                    }
                } else if matches!(self.drawn, Drawn::Compressed(..)) {
                    d.cmd_draw(cmd, self.index_count, 1, 0, 0);
                } else {
                    d.cmd_draw_indexed(cmd, index_count, 1, index_first, 0, 0);
                }
            }
        }
    }

    /// Begins a rendering of the whole image into `colour` and `depth`, with the viewport,
    /// scissor, `pipeline` and this pass's descriptor set bound.
    ///
    /// # Safety
    /// `cmd` is recording outside a rendering; the attachments are this pass's targets in the
    /// layouts they name.
    pub(super) unsafe fn begin_drawing(
        &self,
        cmd: vk::CommandBuffer,
        colour: &[vk::RenderingAttachmentInfo],
        depth: &vk::RenderingAttachmentInfo,
        pipeline: vk::Pipeline,
    ) {
        let d = &self.ctx.device;
        let area = vk::Rect2D::default().extent(vk::Extent2D {
            width: WIDTH,
            height: HEIGHT,
        });
        // SAFETY: the caller's contract; every handle is this pass's.
        unsafe {
            d.cmd_begin_rendering(
                cmd,
                &vk::RenderingInfo::default()
                    .render_area(area)
                    .layer_count(1)
                    .color_attachments(colour)
                    .depth_attachment(depth),
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
        }
    }

    /// Records the copy of the resolved colour image (in `COLOR_ATTACHMENT_OPTIMAL`, written by
    /// a rendering) to the readback buffer, and makes every write visible to the host.
    ///
    /// # Safety
    /// `cmd` is recording outside a rendering; `resolve` is this pass's resolve image.
    pub(super) unsafe fn record_readback(&self, cmd: vk::CommandBuffer, resolve: vk::Image) {
        let d = &self.ctx.device;
        let to_copy = [vk::ImageMemoryBarrier2::default()
            .image(resolve)
            .old_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .new_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
            .src_stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)
            .src_access_mask(vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::TRANSFER)
            .dst_access_mask(vk::AccessFlags2::TRANSFER_READ)
            .subresource_range(
                vk::ImageSubresourceRange::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .level_count(1)
                    .layer_count(1),
            )];
        let host = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        // SAFETY: the caller's contract; the readback buffer holds a whole RGBA8 image.
        unsafe {
            d.cmd_pipeline_barrier2(
                cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&to_copy),
            );
            d.cmd_copy_image_to_buffer(
                cmd,
                resolve,
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
            d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&host));
        }
    }

    pub(super) fn frame(
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
        let push = self.push(camera, flags, shading, meshlet_count);
        let (draws, culled_instances) = self.draw_list(camera, push);
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
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, timestamps, 0);
            // Queries span the whole rendering (lavapipe left them unavailable when begun inside).
            let mesh_queries = if mesh { mesh_pools } else { None };
            if let Some((stats, prims)) = mesh_queries {
                d.cmd_begin_query(cmd, stats, 0, vk::QueryControlFlags::empty());
                d.cmd_begin_query(cmd, prims, 0, vk::QueryControlFlags::empty());
            }
            self.begin_drawing(cmd, &colour, &depth_att, pipeline);
            self.record_draws(cmd, &draws, mesh);
            d.cmd_end_rendering(cmd);
            if let Some((stats, prims)) = mesh_queries {
                d.cmd_end_query(cmd, prims, 0);
                d.cmd_end_query(cmd, stats, 0);
            }
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, timestamps, 1);
            self.record_readback(cmd, resolve.0);
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
            culled_instances,
            queries,
        })
    }
}
