//! The Khronos validation layer's messages, counted (errors) and kept (first few) so a test can
//! assert that a whole run produced none.

use super::RenderError;
use ash::vk;
use std::sync::Mutex;

/// What the layer reported.
#[derive(Default)]
struct Log {
    errors: u32,
    first: Vec<String>,
}

/// A debug-utils messenger and its log.
pub struct Messenger {
    loader: ash::ext::debug_utils::Instance,
    handle: vk::DebugUtilsMessengerEXT,
    log: Box<Mutex<Log>>,
}

// SAFETY: Vulkan calls it with valid (possibly null) pointers during the messenger's life;
// `user` is the Log registered with it.
unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut std::ffi::c_void,
) -> vk::Bool32 {
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) && !user.is_null() {
        // SAFETY: `user` is the boxed Mutex<Log> owned by the Messenger, alive until destroy().
        let log = unsafe { &*(user as *const Mutex<Log>) };
        // SAFETY: `data` is null or points to the callback data for this call.
        let msg = unsafe { data.as_ref() }
            .and_then(|d| unsafe { d.message_as_c_str() })
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_default();
        if let Ok(mut l) = log.lock() {
            l.errors += 1;
            if l.first.len() < 5 {
                l.first.push(msg);
            }
        }
    }
    vk::FALSE
}

impl Messenger {
    /// Registers the callback on `instance`.
    pub fn new(entry: &ash::Entry, instance: &ash::Instance) -> Result<Self, RenderError> {
        let loader = ash::ext::debug_utils::Instance::new(entry, instance);
        let log = Box::new(Mutex::new(Log::default()));
        let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
            .message_severity(
                vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                    | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
            )
            .message_type(
                vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                    | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                    | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
            )
            .pfn_user_callback(Some(callback))
            .user_data(&*log as *const Mutex<Log> as *mut std::ffi::c_void);
        // SAFETY: a valid create info whose user pointer (the boxed Log) outlives the messenger.
        let handle = unsafe { loader.create_debug_utils_messenger(&info, None) }
            .map_err(|e| RenderError::Vulkan("create debug messenger", e))?;
        Ok(Self {
            loader,
            handle,
            log,
        })
    }

    /// Errors so far and the first few messages.
    pub fn errors(&self) -> (u32, Vec<String>) {
        let l = self.log.lock().expect("validation log");
        (l.errors, l.first.clone())
    }

    /// Unregisters the callback (before the instance goes).
    pub fn destroy(self) {
        // SAFETY: the messenger was made by this loader and is destroyed once, before the instance.
        unsafe { self.loader.destroy_debug_utils_messenger(self.handle, None) };
    }
}
