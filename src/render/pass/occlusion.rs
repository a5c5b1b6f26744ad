//! Two-phase occlusion culling (as in Nanite and niagara) and the check that it hides nothing.
//!
//! A frame with occlusion culling, in one submission:
//! 1. **early phase**: the task shader draws the meshlets that were visible in the previous frame
//!    (one visibility word per (instance, meshlet) slot), after the frustum and cone tests;
//! 2. **pyramid** (`glsl/pyramid.comp`): the early depth, each pixel's largest depth over its
//!    samples, then level by level the largest of 2 x 2 texels (odd edges covered), down to 1 x 1;
//! 3. **late phase**: every meshlet is tested (frustum, cone, then its bounding sphere's screen
//!    rectangle and nearest depth against the pyramid texels covering the rectangle, at the finest
//!    level where it is at most 8 texels across, `glsl/occlusion.glsl`); what passes and was
//!    not drawn early is drawn now, and every slot's visibility is kept for the next frame.
//!
//! The early depth is never nearer than the final one (it has fewer occluders), so a meshlet
//! behind the pyramid is behind the final image too. The check ([`Checked`]) renders with a
//! fragment shader that keeps, per sample, the least (depth, slot) of every fragment drawn; run
//! with and without occlusion culling, the two id images and every depth sample must be equal.
//! Both are per sample (4x MSAA).

use super::*;
use interface::{
    COUNTER_CULLED_CONE, COUNTER_CULLED_FRUSTUM, COUNTER_DRAWN, COUNTER_DRAWN_LATE,
    COUNTER_INSTANCES_OCCLUDED, COUNTER_OCCLUDED, COUNTER_TRIANGLES_CONE, COUNTER_TRIANGLES_DRAWN,
    COUNTER_TRIANGLES_DRAWN_LATE, COUNTER_TRIANGLES_FRUSTUM, COUNTER_TRIANGLES_OCCLUDED,
    FLAG_EARLY, FLAG_KEEP_VISIBILITY, FLAG_LATE, FLAG_PYRAMID_ONE_TEXEL, PYRAMID_LEVELS,
};

/// Texels of every pyramid level together.
pub(super) fn pyramid_texels() -> u32 {
    let (mut w, mut h, mut total) = (WIDTH, HEIGHT, 0);
    for _ in 0..PYRAMID_LEVELS {
        total += w * h;
        (w, h) = (w.div_ceil(2), h.div_ceil(2));
    }
    total
}

/// The compute side of occlusion culling, made at the first occlusion frame.
pub(super) struct Objects {
    pipeline: Owned<vk::Pipeline>,
    layout: Owned<vk::PipelineLayout>,
    set: vk::DescriptorSet,
    _pool: Owned<vk::DescriptorPool>,
    _set_layout: Owned<vk::DescriptorSetLayout>,
    _sampler: Owned<vk::Sampler>,
    /// Every depth sample of the last checked frame.
    samples: Buffer,
    /// Timestamps: start, after the early phase, after the pyramid, after the late phase.
    queries: Owned<vk::QueryPool>,
}

/// The pyramid shader's push constants.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ComputePush {
    mode: u32,
    level: u32,
    sample_count: u32,
}

/// The exactness check's images of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Checked {
    /// Every depth sample (4 per pixel, row-major).
    pub depth: Vec<f32>,
    /// Per sample (4 per pixel, row-major), the least (depth bits << 32 | slot) drawn there
    /// (`u64::MAX`: nothing).
    pub ids: Vec<u64>,
}

impl Checked {
    /// The (instance, meshlet) slots that own at least one sample, ascending: the oracle's set.
    pub fn owners(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self
            .ids
            .iter()
            .filter(|&&x| x != u64::MAX)
            .map(|&x| x as u32)
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// (depth samples, id samples) that differ from `other`, bit for bit.
    pub fn differences(&self, other: &Checked) -> (usize, usize) {
        let depth = self
            .depth
            .iter()
            .zip(&other.depth)
            .filter(|(a, b)| a.to_bits() != b.to_bits())
            .count();
        let ids = self
            .ids
            .iter()
            .zip(&other.ids)
            .filter(|(a, b)| a != b)
            .count();
        (depth, ids)
    }
}

/// How an occlusion-culled frame went (or a reference frame: frustum and cone only, one phase,
/// everything counted as drawn early).
#[derive(Clone, Debug)]
pub struct OcclusionFrame {
    /// RGBA8 pixels.
    pub pixels: Vec<u8>,
    /// GPU time of the early phase, the pyramid and the late phase, nanoseconds.
    pub early_ns: f64,
    /// See `early_ns`.
    pub pyramid_ns: f64,
    /// See `early_ns`.
    pub late_ns: f64,
    /// Meshlets and triangles drawn by the early phase.
    pub drawn_early: u32,
    /// See `drawn_early`.
    pub triangles_early: u32,
    /// Meshlets and triangles drawn by the late phase.
    pub drawn_late: u32,
    /// See `drawn_late`.
    pub triangles_late: u32,
    /// Meshlets culled by the frustum, the cone and the pyramid (the late phase's classification).
    pub culled_frustum: u32,
    /// See `culled_frustum`.
    pub culled_cone: u32,
    /// See `culled_frustum`.
    pub occluded: u32,
    /// Triangles in the meshlets culled by the frustum, the cone and the pyramid.
    pub culled_triangles: [u32; 3],
    /// Instances wholly outside the frustum (not drawn; their meshlets are in no other count).
    pub culled_instances: u32,
    /// Instances the late phase found wholly behind the pyramid (their meshlets count as
    /// occluded).
    pub occluded_instances: u32,
    /// The check's images, when asked for.
    pub checked: Option<Checked>,
}

impl OcclusionFrame {
    /// GPU time of the whole frame, nanoseconds.
    pub fn gpu_ns(&self) -> f64 {
        self.early_ns + self.pyramid_ns + self.late_ns
    }

    /// Triangles drawn by both phases.
    pub fn triangles(&self) -> u32 {
        self.triangles_early + self.triangles_late
    }

    /// Meshlets drawn by both phases.
    pub fn drawn(&self) -> u32 {
        self.drawn_early + self.drawn_late
    }
}

/// What a frame draws.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phases {
    /// Frustum and cone culling, one phase (what occlusion culling is checked against); with
    /// `keep`, every slot's visibility recorded for the next occlusion frame.
    Reference { keep: bool },
    /// Early phase, pyramid, late phase; `one_texel` breaks the pyramid test on purpose.
    Occlusion { one_texel: bool },
}

impl Pass<'_> {
    /// Forgets what was visible: the next occlusion frame's early phase draws nothing and its
    /// late phase draws everything the frustum, cone and (empty) pyramid let through.
    pub fn reset_visibility(&self) {
        self.bindings
            .visibility
            .write(&vec![0u8; 4 * self.slots as usize]);
        // LOD passes start from no pyramid instead.
        self.bindings
            .pyramid
            .write(&vec![0u8; self.bindings.pyramid.size as usize]);
        self.pyramid_view.set(None);
    }

    /// One frame from `camera` with two-phase occlusion culling on top of frustum and cone
    /// culling, using and updating the visibility of the previous frame; with `check`, drawn
    /// through the id shader and returned with its [`Checked`] images (for exactness, not speed).
    pub fn render_occlusion(
        &self,
        camera: &Camera,
        shading: Shading,
        check: bool,
    ) -> Result<OcclusionFrame, RenderError> {
        self.occlusion_frame(
            camera,
            shading,
            check,
            Phases::Occlusion { one_texel: false },
        )
    }

    /// [`Pass::render_occlusion`] with a pyramid test made non-conservative on purpose (one level
    /// finer than a footprint needs): for showing that the check catches a wrong pyramid.
    pub fn render_occlusion_one_texel(
        &self,
        camera: &Camera,
        check: bool,
    ) -> Result<OcclusionFrame, RenderError> {
        self.occlusion_frame(
            camera,
            Shading::Unlit,
            check,
            Phases::Occlusion { one_texel: true },
        )
    }

    /// The frame occlusion culling is compared with: frustum and cone culling alone, in one
    /// phase, through the same recording (with `check`, the id shader and the [`Checked`] images).
    pub fn render_reference(
        &self,
        camera: &Camera,
        shading: Shading,
        check: bool,
    ) -> Result<OcclusionFrame, RenderError> {
        self.occlusion_frame(camera, shading, check, Phases::Reference { keep: false })
    }

    /// A frame that skips occlusion culling (frustum and cone only, one phase, no pyramid) but
    /// records what it drew as visible, so a later [`Pass::render_occlusion`] starts from it:
    /// for frames where the pyramid did not pay.
    pub fn render_without_pyramid(
        &self,
        camera: &Camera,
        shading: Shading,
        check: bool,
    ) -> Result<OcclusionFrame, RenderError> {
        self.occlusion_frame(camera, shading, check, Phases::Reference { keep: true })
    }

    fn objects(&self) -> Result<&Objects, RenderError> {
        if let Some(o) = self.occlusion.get() {
            return Ok(o);
        }
        let o = self.make_objects()?;
        Ok(self.occlusion.get_or_init(|| o))
    }

    fn make_objects(&self) -> Result<Objects, RenderError> {
        let ctx = self.ctx;
        let d = &ctx.device;
        let code = spirv(shader(Shader::PyramidComp))?;
        // SAFETY (this function's calls): valid create infos on the context's live device; every
        // handle is owned by an `Owned` right away, so an error frees what was made.
        let module = Owned::new(
            d,
            unsafe {
                d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
            }
            .map_err(vk_err("shader module"))?,
            vkc::destroy_shader_module,
        );
        let sampler = Owned::new(
            d,
            unsafe { d.create_sampler(&vk::SamplerCreateInfo::default(), None) }
                .map_err(vk_err("sampler"))?,
            vkc::destroy_sampler,
        );
        let bindings = [
            vk::DescriptorSetLayoutBinding::default()
                .binding(0)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::COMPUTE),
            vk::DescriptorSetLayoutBinding::default()
                .binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::COMPUTE),
            vk::DescriptorSetLayoutBinding::default()
                .binding(2)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::COMPUTE),
        ];
        let (set_layout, pool, set) = super::objects::descriptor_set(d, &bindings)?;
        let samples = ctx.buffer(
            4 * SAMPLES.as_raw() as u64 * WIDTH as u64 * HEIGHT as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let image = [vk::DescriptorImageInfo::default()
            .sampler(sampler.get())
            .image_view(self.targets[2].view.get())
            .image_layout(vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL)];
        let pyramid = [vk::DescriptorBufferInfo::default()
            .buffer(self.bindings.pyramid.buf)
            .range(vk::WHOLE_SIZE)];
        let sample_info = [vk::DescriptorBufferInfo::default()
            .buffer(samples.buf)
            .range(vk::WHOLE_SIZE)];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(&image),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&pyramid),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(2)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&sample_info),
        ];
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        let layout = super::objects::pipeline_layout(
            d,
            set_layout.get(),
            std::mem::size_of::<ComputePush>() as u32,
            vk::ShaderStageFlags::COMPUTE,
        )?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.get())
            .name(c"main");
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout.get());
        let pipeline = Owned::new(
            d,
            unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) }
                .map_err(|(_, e)| RenderError::Vulkan("create compute pipeline", e))?[0],
            vkc::destroy_pipeline,
        );
        let queries = Owned::new(
            d,
            unsafe {
                d.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(4),
                    None,
                )
            }
            .map_err(vk_err("query pool"))?,
            vkc::destroy_query_pool,
        );
        Ok(Objects {
            pipeline,
            layout,
            set,
            _pool: pool,
            _set_layout: set_layout,
            _sampler: sampler,
            samples,
            queries,
        })
    }

    /// [`Pass::render_occlusion`] of a LOD pass ([`Pass::with_lod`]): the cut for `q` (its
    /// view should be the camera's), with the early phase tested against the previous frame's
    /// pyramid as the previous camera saw it (visibility words do not survive a change of cut).
    pub fn render_lod_occlusion(
        &self,
        camera: &Camera,
        q: &Query,
        shading: Shading,
        check: bool,
    ) -> Result<OcclusionFrame, RenderError> {
        self.occlusion_frame_of(
            camera,
            shading,
            check,
            Phases::Occlusion { one_texel: false },
            Some(q),
        )
    }

    /// [`Pass::render_reference`] of a LOD pass: the cut for `q` with frustum and cone culling
    /// alone.
    pub fn render_lod_reference(
        &self,
        camera: &Camera,
        q: &Query,
        shading: Shading,
        check: bool,
    ) -> Result<OcclusionFrame, RenderError> {
        self.occlusion_frame_of(
            camera,
            shading,
            check,
            Phases::Reference { keep: false },
            Some(q),
        )
    }

    fn occlusion_frame(
        &self,
        camera: &Camera,
        shading: Shading,
        check: bool,
        phases: Phases,
    ) -> Result<OcclusionFrame, RenderError> {
        self.occlusion_frame_of(camera, shading, check, phases, None)
    }

    fn occlusion_frame_of(
        &self,
        camera: &Camera,
        shading: Shading,
        check: bool,
        phases: Phases,
        lod: Option<&Query>,
    ) -> Result<OcclusionFrame, RenderError> {
        let (pipeline, meshlet_count) = self.occlusion_pipeline(check, lod)?;
        let view_proj = camera
            .view_proj(WIDTH as f32 / HEIGHT as f32)
            .to_cols_array();
        if lod.is_some() && matches!(phases, Phases::Occlusion { .. }) {
            self.place_pyramid_view(view_proj);
        }
        let objects = self.objects()?;
        self.bindings.counters.write(&[0u8; COUNTER_BYTES as usize]);
        if check {
            self.bindings
                .ids
                .write(&vec![0xffu8; self.bindings.ids.size as usize]);
        }
        let (first, second, culled_instances) =
            self.phase_draws(camera, shading, meshlet_count, phases);
        let two = matches!(phases, Phases::Occlusion { .. });
        let [msaa, resolve, depth] = &self.targets;
        // SAFETY: `submit` hands a recording command buffer and waits for it; every handle
        // recorded is owned by this pass and lives past the wait.
        self.ctx.submit(|cmd| unsafe {
            Recording {
                pass: self,
                d: &self.ctx.device,
                cmd,
                objects,
                pipeline,
                msaa: (msaa.image.get(), msaa.view.get()),
                resolve: (resolve.image.get(), resolve.view.get()),
                depth: (depth.image.get(), depth.view.get()),
            }
            .record_frame(&first, two.then_some(&second[..]), check)
        })?;
        self.read_occlusion_frame(objects, check, culled_instances)
    }

    /// The graphics pipeline an occlusion frame draws with and its meshlet count (a LOD pass:
    /// the loaded levels' count, with the cut's view written for the task shader).
    fn occlusion_pipeline(
        &self,
        check: bool,
        lod: Option<&Query>,
    ) -> Result<(vk::Pipeline, u32), RenderError> {
        if !matches!(self.drawn, Drawn::Descriptors(_)) {
            return Err(RenderError::NoShaderDecoder(
                "occlusion culling of a compressed pass".into(),
            ));
        }
        let (lod_pipelines, meshlet_count) = match (lod, &self.lod) {
            (Some(q), Some((layout, pair))) => {
                let view = ViewData::new(q, layout.loaded(q.finest));
                self.bindings.lod_view.write(bytemuck::bytes_of(&view));
                (Some(pair), view.loaded)
            }
            (None, None) => (None, self.meshlet_count),
            (Some(_), None) => return Err(RenderError::NotLod),
            (None, Some(_)) => {
                return Err(RenderError::NoShaderDecoder(
                    "occlusion culling of a LOD pass without its cut (render_lod_occlusion)".into(),
                ))
            }
        };
        let pipeline = match (check, lod_pipelines) {
            (true, None) => self
                .mesh_check
                .as_ref()
                .ok_or(RenderError::NoIdCheck)?
                .get(),
            (true, Some(_)) => self.lod_check.as_ref().ok_or(RenderError::NoIdCheck)?.get(),
            (false, None) => self
                .mesh_shade
                .as_ref()
                .expect("a descriptor pass has one")
                .get(),
            (false, Some((shade, _))) => shade.get(),
        };
        Ok((pipeline, meshlet_count))
    }

    /// Writes, after the pyramid's levels, the camera the pyramid was built from, and keeps
    /// `view_proj` as the next frame's (a LOD pass's early phase tests against the previous
    /// frame's pyramid as the previous camera saw it).
    fn place_pyramid_view(&self, view_proj: [f32; 16]) {
        // The first frame after a reset: this one, over a pyramid of zeros that hides everything
        // it can test.
        let previous = self.pyramid_view.get().unwrap_or(view_proj);
        let at = 4 * pyramid_texels() as usize;
        self.bindings
            .pyramid
            .write_at(at, bytemuck::cast_slice(&previous));
        self.pyramid_view.set(Some(view_proj));
    }

    /// The draws of the first and the second phase (none for a reference frame), flagged for
    /// their phase, and the instances the frustum culled whole.
    fn phase_draws(
        &self,
        camera: &Camera,
        shading: Shading,
        meshlet_count: u32,
        phases: Phases,
    ) -> (Vec<frame::DrawCmd>, Vec<frame::DrawCmd>, u32) {
        let base = FLAG_FRUSTUM | FLAG_CONE;
        let push = self.push(camera, base, shading, meshlet_count);
        let (draws, culled_instances) = self.draw_list(camera, push);
        let with = |flags: u32| -> Vec<frame::DrawCmd> {
            draws
                .iter()
                .map(|&(p, a, b, m)| {
                    (
                        Push {
                            flags: p.flags | flags,
                            ..p
                        },
                        a,
                        b,
                        m,
                    )
                })
                .collect()
        };
        let (first, second) = match phases {
            Phases::Reference { keep } => (
                with(if keep { FLAG_KEEP_VISIBILITY } else { 0 }),
                Vec::new(),
            ),
            Phases::Occlusion { one_texel } => (
                with(FLAG_EARLY),
                with(FLAG_LATE | if one_texel { FLAG_PYRAMID_ONE_TEXEL } else { 0 }),
            ),
        };
        (first, second, culled_instances)
    }

    /// Reads a submitted occlusion frame back: timestamps, counters, pixels and, with `check`,
    /// the check's images.
    fn read_occlusion_frame(
        &self,
        objects: &Objects,
        check: bool,
        culled_instances: u32,
    ) -> Result<OcclusionFrame, RenderError> {
        let d = &self.ctx.device;
        let mut t = [0u64; 4];
        // SAFETY: the submission that wrote the timestamps has completed (`submit` waits).
        unsafe {
            d.get_query_pool_results(
                objects.queries.get(),
                0,
                &mut t,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(vk_err("timestamps"))?;
        let ns = |a: usize, b: usize| {
            t[b].saturating_sub(t[a]) as f64 * self.ctx.timestamp_period as f64
        };
        let c: Vec<u32> =
            bytemuck::cast_slice(&self.bindings.counters.read(COUNTER_BYTES as usize)).to_vec();
        let checked = check.then(|| Checked {
            depth: bytemuck::cast_slice(&objects.samples.read(objects.samples.size as usize))
                .to_vec(),
            ids: bytemuck::cast_slice(&self.bindings.ids.read(self.bindings.ids.size as usize))
                .to_vec(),
        });
        let (drawn, triangles) = (c[COUNTER_DRAWN], c[COUNTER_TRIANGLES_DRAWN]);
        let (drawn_late, triangles_late) = (c[COUNTER_DRAWN_LATE], c[COUNTER_TRIANGLES_DRAWN_LATE]);
        Ok(OcclusionFrame {
            pixels: self.readback.read((WIDTH * HEIGHT * 4) as usize),
            early_ns: ns(0, 1),
            pyramid_ns: ns(1, 2),
            late_ns: ns(2, 3),
            drawn_early: drawn - drawn_late,
            triangles_early: triangles - triangles_late,
            drawn_late,
            triangles_late,
            culled_frustum: c[COUNTER_CULLED_FRUSTUM],
            culled_cone: c[COUNTER_CULLED_CONE],
            occluded: c[COUNTER_OCCLUDED],
            culled_triangles: [
                c[COUNTER_TRIANGLES_FRUSTUM],
                c[COUNTER_TRIANGLES_CONE],
                c[COUNTER_TRIANGLES_OCCLUDED],
            ],
            culled_instances,
            occluded_instances: c[COUNTER_INSTANCES_OCCLUDED],
            checked,
        })
    }
}

/// A barrier moving `image` from layout `old` to `new` after every earlier command's writes.
fn image_barrier(
    image: vk::Image,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
    aspect: vk::ImageAspectFlags,
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .image(image)
        .old_layout(old)
        .new_layout(new)
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(aspect)
                .level_count(1)
                .layer_count(1),
        )
}

/// What recording one occlusion frame reads: the pass, the command buffer, the compute objects,
/// the graphics pipeline and the targets as (image, view).
struct Recording<'r, 'a> {
    pass: &'r Pass<'a>,
    d: &'r ash::Device,
    cmd: vk::CommandBuffer,
    objects: &'r Objects,
    pipeline: vk::Pipeline,
    msaa: (vk::Image, vk::ImageView),
    resolve: (vk::Image, vk::ImageView),
    depth: (vk::Image, vk::ImageView),
}

const DEPTH_ATTACHMENT: vk::ImageLayout = vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL;
const DEPTH_READ_ONLY: vk::ImageLayout = vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL;

impl Recording<'_, '_> {
    /// Records the whole frame: `first` (cleared), then with `second` the pyramid and `second`,
    /// with `check` the check's depth copy, then the readback; timestamps between the steps.
    ///
    /// # Safety
    /// `cmd` is recording outside a rendering; every handle is the pass's.
    unsafe fn record_frame(
        &self,
        first: &[frame::DrawCmd],
        second: Option<&[frame::DrawCmd]>,
        check: bool,
    ) {
        let (d, cmd) = (self.d, self.cmd);
        let ts = self.objects.queries.get();
        let (cw, ch) = (WIDTH.div_ceil(16), HEIGHT.div_ceil(16));
        // SAFETY: the caller's contract.
        unsafe {
            d.cmd_reset_query_pool(cmd, ts, 0, 4);
            self.start_targets();
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, ts, 0);
            self.draw_phase(true, second.is_none(), first);
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, ts, 1);
            if second.is_some() {
                self.move_depth(DEPTH_ATTACHMENT, DEPTH_READ_ONLY);
                self.bind_pyramid_shader();
                // Levels 0-3 per 8 x 8 block (16 x 16 blocks a workgroup), then the rest in one
                // workgroup.
                self.dispatch(0, 0, (WIDTH.div_ceil(128), HEIGHT.div_ceil(128)));
                self.barrier_all();
                self.dispatch(1, 0, (1, 1));
                self.barrier_all();
                self.move_depth(DEPTH_READ_ONLY, DEPTH_ATTACHMENT);
            }
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, ts, 2);
            if let Some(second) = second {
                self.draw_phase(false, true, second);
            }
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, ts, 3);
            if check {
                self.move_depth(DEPTH_ATTACHMENT, DEPTH_READ_ONLY);
                self.bind_pyramid_shader();
                self.dispatch(2, 0, (cw, ch));
            }
            self.pass.record_readback(cmd, self.resolve.0);
        }
    }

    /// Moves the targets from undefined contents into their attachment layouts.
    ///
    /// # Safety
    /// As [`Recording::record_frame`].
    unsafe fn start_targets(&self) {
        let start = [
            image_barrier(
                self.msaa.0,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::ImageAspectFlags::COLOR,
            ),
            image_barrier(
                self.resolve.0,
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::ImageAspectFlags::COLOR,
            ),
            image_barrier(
                self.depth.0,
                vk::ImageLayout::UNDEFINED,
                DEPTH_ATTACHMENT,
                vk::ImageAspectFlags::DEPTH,
            ),
        ];
        // SAFETY: the caller's contract.
        unsafe {
            self.d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&start),
            );
        }
    }

    /// Records one phase's rendering of `draws`: clearing the targets or loading them, and on
    /// the `last` phase resolving the colour.
    ///
    /// # Safety
    /// As [`Recording::record_frame`].
    unsafe fn draw_phase(&self, clear: bool, last: bool, draws: &[frame::DrawCmd]) {
        let load = if clear {
            vk::AttachmentLoadOp::CLEAR
        } else {
            vk::AttachmentLoadOp::LOAD
        };
        let mut colour = vk::RenderingAttachmentInfo::default()
            .image_view(self.msaa.1)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [0.08, 0.09, 0.12, 1.0],
                },
            });
        if last {
            colour = colour
                .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                .resolve_image_view(self.resolve.1)
                .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        }
        let colour = [colour];
        let depth_att = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.1)
            .image_layout(DEPTH_ATTACHMENT)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            });
        // SAFETY: the caller's contract; the attachments are the pass's targets in the layouts
        // they name.
        unsafe {
            self.pass
                .begin_drawing(self.cmd, &colour, &depth_att, self.pipeline);
            self.pass.record_draws(self.cmd, draws, true);
            self.d.cmd_end_rendering(self.cmd);
        }
    }

    /// Makes every buffer write before visible to every read and write after.
    ///
    /// # Safety
    /// As [`Recording::record_frame`].
    unsafe fn barrier_all(&self) {
        let m = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)];
        // SAFETY: the caller's contract.
        unsafe {
            self.d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().memory_barriers(&m),
            );
        }
    }

    /// Binds the pyramid shader and its descriptor set.
    ///
    /// # Safety
    /// As [`Recording::record_frame`].
    unsafe fn bind_pyramid_shader(&self) {
        let o = self.objects;
        // SAFETY: the caller's contract.
        unsafe {
            self.d
                .cmd_bind_pipeline(self.cmd, vk::PipelineBindPoint::COMPUTE, o.pipeline.get());
            self.d.cmd_bind_descriptor_sets(
                self.cmd,
                vk::PipelineBindPoint::COMPUTE,
                o.layout.get(),
                0,
                &[o.set],
                &[],
            );
        }
    }

    /// Dispatches the bound pyramid shader in `mode` at `level` over `groups` workgroups.
    ///
    /// # Safety
    /// As [`Recording::record_frame`], with the pyramid shader bound.
    unsafe fn dispatch(&self, mode: u32, level: u32, groups: (u32, u32)) {
        let p = ComputePush {
            mode,
            level,
            sample_count: SAMPLES.as_raw(),
        };
        // SAFETY: the caller's contract.
        unsafe {
            self.d.cmd_push_constants(
                self.cmd,
                self.objects.layout.get(),
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::bytes_of(&p),
            );
            self.d.cmd_dispatch(self.cmd, groups.0, groups.1, 1);
        }
    }

    /// Moves the depth target from layout `old` to `new`.
    ///
    /// # Safety
    /// As [`Recording::record_frame`], with the depth target in `old`.
    unsafe fn move_depth(&self, old: vk::ImageLayout, new: vk::ImageLayout) {
        let b = [image_barrier(
            self.depth.0,
            old,
            new,
            vk::ImageAspectFlags::DEPTH,
        )];
        // SAFETY: the caller's contract.
        unsafe {
            self.d.cmd_pipeline_barrier2(
                self.cmd,
                &vk::DependencyInfo::default().image_memory_barriers(&b),
            );
        }
    }
}
