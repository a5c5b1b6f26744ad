//! Headless Vulkan through ash: an instance without surfaces, a device with VK_EXT_mesh_shader
//! (task + mesh), Vulkan 1.3 dynamic rendering and `maintenance4`, host-visible buffers and a
//! one-shot command helper.

use super::{vk_err, RenderError};
use ash::vk;
use std::ffi::CStr;

/// The Vulkan objects every pass needs.
pub struct Context {
    _entry: ash::Entry,
    /// The instance.
    pub instance: ash::Instance,
    /// The chosen physical device.
    pub physical: vk::PhysicalDevice,
    /// The logical device.
    pub device: ash::Device,
    /// VK_EXT_mesh_shader entry points.
    pub mesh: ash::ext::mesh_shader::Device,
    /// A graphics queue.
    pub queue: vk::Queue,
    /// Its family.
    pub family: u32,
    /// Command pool on that family.
    pub pool: vk::CommandPool,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Whether the device has `meshShaderQueries` (mesh primitives generated, task/mesh invocations).
    pub mesh_queries: bool,
    /// Largest storage-buffer binding in bytes (lavapipe: 128 MiB).
    pub max_storage_range: u64,
    /// Subgroup width.
    pub subgroup_size: u32,
    /// Whether mesh shaders have subgroup arithmetic and ballot.
    pub mesh_subgroups: bool,
    /// Device name and driver.
    pub name: String,
    /// Whether fragment shaders have 64-bit buffer atomics and per-sample shading: what the
    /// occlusion exactness check's id image needs (lavapipe has both).
    pub id_check: bool,
    /// Errors reported by the validation layer (when enabled).
    pub validation: Option<super::validation::Messenger>,
    memory: vk::PhysicalDeviceMemoryProperties,
}

const MESH_EXT: &CStr = ash::ext::mesh_shader::NAME;

impl Context {
    /// Opens the first device with task and mesh shaders. With `validate`, the Khronos validation
    /// layer is enabled (when installed) and its errors are counted.
    pub fn new(validate: bool) -> Result<Self, RenderError> {
        // SAFETY: loading the system Vulkan loader; every handle below is destroyed in Drop.
        let entry =
            unsafe { ash::Entry::load() }.map_err(|e| RenderError::NoVulkan(e.to_string()))?;
        let app = vk::ApplicationInfo::default()
            .application_name(c"meshletlab")
            .api_version(vk::API_VERSION_1_3);
        let layer = c"VK_LAYER_KHRONOS_validation";
        // SAFETY: a query on the loaded entry, no handles involved.
        let have_layer = unsafe { entry.enumerate_instance_layer_properties() }
            .unwrap_or_default()
            .iter()
            .any(|l| l.layer_name_as_c_str() == Ok(layer));
        if validate && !have_layer {
            return Err(RenderError::NoValidationLayer);
        }
        let layers = if validate {
            vec![layer.as_ptr()]
        } else {
            vec![]
        };
        let exts = if validate {
            vec![ash::ext::debug_utils::NAME.as_ptr()]
        } else {
            vec![]
        };
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&exts);
        // SAFETY: a valid create info whose strings and layers outlive the call; destroyed in Drop
        // (or below when no device qualifies).
        let instance = unsafe { entry.create_instance(&info, None) }
            .map_err(|e| RenderError::NoVulkan(format!("vkCreateInstance: {e}")))?;
        let validation = if validate {
            Some(super::validation::Messenger::new(&entry, &instance)?)
        } else {
            None
        };
        // SAFETY: `instance` is live.
        let devices = unsafe { instance.enumerate_physical_devices() }
            .map_err(vk_err("enumerate physical devices"))?;
        let mut seen = Vec::new();
        let mut chosen = None;
        for &pd in &devices {
            // SAFETY: `pd` comes from this instance (so do the next three queries).
            let props = unsafe { instance.get_physical_device_properties(pd) };
            let name = props
                .device_name_as_c_str()
                .map(|c| c.to_string_lossy().into_owned())
                .unwrap_or_default();
            // SAFETY: as above.
            let has_ext = unsafe { instance.enumerate_device_extension_properties(pd) }
                .unwrap_or_default()
                .iter()
                .any(|e| e.extension_name_as_c_str() == Ok(MESH_EXT));
            let mut ms = vk::PhysicalDeviceMeshShaderFeaturesEXT::default();
            let mut v13 = vk::PhysicalDeviceVulkan13Features::default();
            let mut f2 = vk::PhysicalDeviceFeatures2::default()
                .push_next(&mut ms)
                .push_next(&mut v13);
            if has_ext {
                // SAFETY: as above; `f2` chains only structs that outlive the call.
                unsafe { instance.get_physical_device_features2(pd, &mut f2) };
            }
            let ok = has_ext
                && ms.task_shader == vk::TRUE
                && ms.mesh_shader == vk::TRUE
                && v13.dynamic_rendering == vk::TRUE
                && v13.maintenance4 == vk::TRUE
                && props.api_version >= vk::API_VERSION_1_3;
            // SAFETY: as above.
            let family = unsafe { instance.get_physical_device_queue_family_properties(pd) }
                .iter()
                .position(|q| q.queue_flags.contains(vk::QueueFlags::GRAPHICS));
            seen.push(format!(
                "{name} ({})",
                if ok {
                    "mesh shaders"
                } else {
                    "no mesh shaders"
                }
            ));
            if let (true, Some(f), None) = (ok, family, &chosen) {
                chosen = Some((
                    pd,
                    f as u32,
                    name,
                    ms.mesh_shader_queries == vk::TRUE,
                    props,
                ));
            }
        }
        let Some((physical, family, name, mesh_queries, props)) = chosen else {
            // SAFETY: nothing was made from the instance yet.
            unsafe { instance.destroy_instance(None) };
            return Err(RenderError::NoMeshShader(seen.join(", ")));
        };
        // Subgroups: whether mesh shaders may use subgroup arithmetic (the laced-wires decoder's
        // scans pick a variant by this; lavapipe's subgroups are 8 wide).
        let mut sub = vk::PhysicalDeviceSubgroupProperties::default();
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut sub);
        // SAFETY: `physical` comes from this instance; `p2` chains structs that outlive the call.
        unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
        let subgroup_size = sub.subgroup_size;
        let mesh_subgroups = sub
            .supported_stages
            .contains(vk::ShaderStageFlags::MESH_EXT)
            && sub
                .supported_operations
                .contains(vk::SubgroupFeatureFlags::ARITHMETIC | vk::SubgroupFeatureFlags::BALLOT);
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let mut ms = vk::PhysicalDeviceMeshShaderFeaturesEXT::default()
            .task_shader(true)
            .mesh_shader(true)
            .mesh_shader_queries(mesh_queries);
        // glslangValidator's vulkan1.3 target emits LocalSizeId, which needs maintenance4.
        let mut v13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .maintenance4(true)
            .synchronization2(true);
        // The occlusion exactness check's id image: 64-bit atomics from fragment shaders.
        let mut have12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut have12);
        // SAFETY: `physical` comes from this instance; `f2` chains only live structs.
        unsafe { instance.get_physical_device_features2(physical, &mut f2) };
        let id_check = f2.features.fragment_stores_and_atomics == vk::TRUE
            && f2.features.sample_rate_shading == vk::TRUE
            && f2.features.shader_int64 == vk::TRUE
            && have12.shader_buffer_int64_atomics == vk::TRUE;
        let mut v12 =
            vk::PhysicalDeviceVulkan12Features::default().shader_buffer_int64_atomics(id_check);
        let core = vk::PhysicalDeviceFeatures::default()
            .pipeline_statistics_query(true)
            .fragment_stores_and_atomics(id_check)
            .sample_rate_shading(id_check)
            .shader_int64(id_check);
        let dev_exts = [MESH_EXT.as_ptr()];
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&dev_exts)
            .enabled_features(&core)
            .push_next(&mut ms)
            .push_next(&mut v12)
            .push_next(&mut v13);
        // SAFETY: a valid create info for a device of this instance; destroyed in Drop.
        let device = unsafe { instance.create_device(physical, &info, None) }
            .map_err(vk_err("create device"))?;
        // SAFETY: the family and queue index were requested in the create info.
        let queue = unsafe { device.get_device_queue(family, 0) };
        // SAFETY: a pool for that family on the live device; destroyed in Drop.
        let pool = unsafe {
            device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }
        .map_err(vk_err("create command pool"))?;
        // SAFETY: `physical` comes from this instance.
        let memory = unsafe { instance.get_physical_device_memory_properties(physical) };
        let mesh = ash::ext::mesh_shader::Device::new(&instance, &device);
        Ok(Self {
            _entry: entry,
            instance,
            physical,
            device,
            mesh,
            queue,
            family,
            pool,
            timestamp_period: props.limits.timestamp_period,
            mesh_queries,
            max_storage_range: props.limits.max_storage_buffer_range as u64,
            subgroup_size,
            mesh_subgroups,
            name,
            id_check,
            validation,
            memory,
        })
    }

    /// A buffer in host-visible, coherent memory (lavapipe has nothing else; on a discrete GPU a
    /// device-local copy would be faster, which the render timings do not include anyway). Freed
    /// when dropped, also when a later step here fails.
    pub fn buffer(&self, size: u64, usage: vk::BufferUsageFlags) -> Result<Buffer, RenderError> {
        let size = size.max(16);
        let d = &self.device;
        // SAFETY: a valid create info on a live device; the handle is owned by `b` below.
        let buf = unsafe {
            d.create_buffer(
                &vk::BufferCreateInfo::default().size(size).usage(usage),
                None,
            )
        }
        .map_err(vk_err("create buffer"))?;
        let mut b = Buffer {
            device: d.clone(),
            buf,
            mem: vk::DeviceMemory::null(),
            ptr: std::ptr::null_mut(),
            size,
        };
        // SAFETY: `buf` was created on this device above.
        let req = unsafe { d.get_buffer_memory_requirements(buf) };
        b.mem = self.allocate(
            req,
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
        )?;
        // SAFETY: fresh memory of a type the requirements allow, bound once at offset 0.
        unsafe { d.bind_buffer_memory(buf, b.mem, 0) }.map_err(vk_err("bind buffer"))?;
        // SAFETY: host-visible memory, mapped once for the buffer's life (freeing unmaps it).
        b.ptr = unsafe { d.map_memory(b.mem, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty()) }
            .map_err(vk_err("map memory"))? as *mut u8;
        Ok(b)
    }

    /// A buffer holding `data`.
    pub fn upload<T: bytemuck::Pod>(
        &self,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> Result<Buffer, RenderError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let b = self.buffer(bytes.len() as u64, usage)?;
        // SAFETY: the mapping is at least `bytes.len()` long and not aliased.
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), b.ptr, bytes.len()) };
        Ok(b)
    }

    /// Device memory of a type with `flags` fitting `req`.
    pub fn allocate(
        &self,
        req: vk::MemoryRequirements,
        flags: vk::MemoryPropertyFlags,
    ) -> Result<vk::DeviceMemory, RenderError> {
        let index = (0..self.memory.memory_type_count)
            .find(|&i| {
                req.memory_type_bits & (1 << i) != 0
                    && self.memory.memory_types[i as usize]
                        .property_flags
                        .contains(flags)
            })
            .ok_or(RenderError::Vulkan(
                "no suitable memory type",
                vk::Result::ERROR_OUT_OF_DEVICE_MEMORY,
            ))?;
        // SAFETY: a valid allocate info with a memory type index of this device.
        unsafe {
            self.device.allocate_memory(
                &vk::MemoryAllocateInfo::default()
                    .allocation_size(req.size)
                    .memory_type_index(index),
                None,
            )
        }
        .map_err(vk_err("allocate memory"))
    }

    /// Records `f` into a fresh command buffer, submits it and waits.
    pub fn submit(&self, f: impl FnOnce(vk::CommandBuffer)) -> Result<(), RenderError> {
        let d = &self.device;
        // SAFETY: the pool belongs to this device and is used from this thread only (`&self`
        // methods of one context are not called concurrently: Context is not Sync).
        let cmd = unsafe {
            d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(self.pool)
                    .command_buffer_count(1),
            )
        }
        .map_err(vk_err("allocate command buffer"))?[0];
        // SAFETY: a freshly allocated primary command buffer in the initial state.
        unsafe {
            d.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
        }
        .map_err(vk_err("begin command buffer"))?;
        f(cmd);
        // SAFETY (the three calls): `cmd` is recording; it is submitted once to this device's
        // queue, and the wait makes it idle before it is freed below.
        let result = (|| {
            unsafe { d.end_command_buffer(cmd) }.map_err(vk_err("end command buffer"))?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            unsafe { d.queue_submit(self.queue, &submit, vk::Fence::null()) }
                .map_err(vk_err("queue submit"))?;
            unsafe { d.queue_wait_idle(self.queue) }.map_err(vk_err("queue wait idle"))
        })();
        // SAFETY: the queue is idle (or the submission failed), so `cmd` is not pending.
        unsafe { d.free_command_buffers(self.pool, &[cmd]) };
        result
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: every object made from the device is gone (passes and buffers borrow or clone
        // it and are dropped first: `Pass<'a>` borrows the context); wait idle, then destroy in
        // reverse creation order.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_command_pool(self.pool, None);
            self.device.destroy_device(None);
            if let Some(v) = self.validation.take() {
                v.destroy();
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// A host-visible buffer, persistently mapped; destroyed with its memory when dropped (after the
/// device is idle: its owner waits, as `Pass` does).
pub struct Buffer {
    device: ash::Device,
    /// The buffer.
    pub buf: vk::Buffer,
    mem: vk::DeviceMemory,
    ptr: *mut u8,
    /// Size in bytes.
    pub size: u64,
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: the buffer and memory were made on `device` and are not in use (owners wait
        // for the device first); null handles (a failed `Context::buffer`) are ignored by Vulkan.
        unsafe {
            self.device.destroy_buffer(self.buf, None);
            self.device.free_memory(self.mem, None);
        }
    }
}

/// A Vulkan handle destroyed by `destroy` when dropped, so every path out of a function that
/// made it, error paths included, frees it.
pub struct Owned<T: Copy> {
    device: ash::Device,
    handle: T,
    destroy: fn(&ash::Device, T),
}

impl<T: Copy> Owned<T> {
    /// Takes ownership of `handle`, made on `device`.
    pub fn new(device: &ash::Device, handle: T, destroy: fn(&ash::Device, T)) -> Self {
        Self {
            device: device.clone(),
            handle,
            destroy,
        }
    }

    /// The raw handle (valid while `self` lives).
    pub fn get(&self) -> T {
        self.handle
    }
}

impl<T: Copy> Drop for Owned<T> {
    fn drop(&mut self) {
        (self.destroy)(&self.device, self.handle)
    }
}

// The destroyers `Owned` calls. SAFETY (all of them): the handle was made on `d` and is owned
// by exactly one `Owned`, whose owner waits for the device to be idle before dropping it (or
// drops it before ever submitting work that uses it).

/// Destroys a pipeline.
pub fn destroy_pipeline(d: &ash::Device, h: vk::Pipeline) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_pipeline(h, None) }
}
/// Destroys a pipeline layout.
pub fn destroy_pipeline_layout(d: &ash::Device, h: vk::PipelineLayout) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_pipeline_layout(h, None) }
}
/// Destroys a descriptor pool (and frees its sets).
pub fn destroy_descriptor_pool(d: &ash::Device, h: vk::DescriptorPool) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_descriptor_pool(h, None) }
}
/// Destroys a descriptor-set layout.
pub fn destroy_descriptor_set_layout(d: &ash::Device, h: vk::DescriptorSetLayout) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_descriptor_set_layout(h, None) }
}
/// Destroys a shader module.
pub fn destroy_shader_module(d: &ash::Device, h: vk::ShaderModule) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_shader_module(h, None) }
}
/// Destroys a sampler.
pub fn destroy_sampler(d: &ash::Device, h: vk::Sampler) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_sampler(h, None) }
}
/// Destroys a query pool.
pub fn destroy_query_pool(d: &ash::Device, h: vk::QueryPool) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_query_pool(h, None) }
}
/// Destroys an image.
pub fn destroy_image(d: &ash::Device, h: vk::Image) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_image(h, None) }
}
/// Destroys an image view.
pub fn destroy_image_view(d: &ash::Device, h: vk::ImageView) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.destroy_image_view(h, None) }
}
/// Frees device memory.
pub fn free_memory(d: &ash::Device, h: vk::DeviceMemory) {
    // SAFETY: see the note above the destroyers.
    unsafe { d.free_memory(h, None) }
}

impl Buffer {
    /// Copies the buffer's first `len` bytes out.
    pub fn read(&self, len: usize) -> Vec<u8> {
        let len = len.min(self.size as usize);
        // SAFETY: mapped, coherent, at least `len` bytes, and the GPU is idle after `submit`.
        unsafe { std::slice::from_raw_parts(self.ptr, len) }.to_vec()
    }

    /// Overwrites the start of the buffer with `data`.
    pub fn write(&self, data: &[u8]) {
        self.write_at(0, data);
    }

    /// Overwrites the buffer from byte `at` with `data`.
    pub fn write_at(&self, at: usize, data: &[u8]) {
        assert!((at + data.len()) as u64 <= self.size);
        // SAFETY: as in `read`; the range lies inside the mapping (checked above).
        unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), self.ptr.add(at), data.len()) };
    }
}
