//! The Khronos validation layer and a `VK_EXT_debug_utils` messenger that records every warning
//! and error, so that the next GPU call can return them as [`GpuError::Validation`].

use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

use ash::vk;

use super::error::GpuError;

/// The layer's name, as the loader knows it.
pub(crate) const LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Messages recorded by the callback since the last [`MessageLog::take`].
#[derive(Default)]
pub(crate) struct MessageLog {
    messages: Mutex<Vec<String>>,
}

impl MessageLog {
    fn push(&self, message: String) {
        // A poisoned lock still holds a valid Vec; the callback must never panic.
        let mut messages = self.messages.lock().unwrap_or_else(|e| e.into_inner());
        messages.push(message);
    }

    /// Removes and returns every recorded message.
    pub(crate) fn take(&self) -> Vec<String> {
        std::mem::take(&mut *self.messages.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// `Err(GpuError::Validation)` when anything was recorded since the last check.
    pub(crate) fn check(&self) -> Result<(), GpuError> {
        let messages = self.take();
        if messages.is_empty() {
            Ok(())
        } else {
            Err(GpuError::Validation(messages))
        }
    }
}

/// Whether the loader can find the validation layer.
pub(crate) fn layer_available(entry: &ash::Entry) -> bool {
    // SAFETY: the entry holds a loaded Vulkan loader; the call has no other preconditions.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
    layers.iter().any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == LAYER))
}

/// The messenger description: warnings and errors of every type go to [`callback`], which
/// appends them to `log`. `log` must outlive every messenger created from this description.
pub(crate) fn messenger_info(log: &Arc<MessageLog>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(callback))
        .user_data(Arc::as_ptr(log) as *mut c_void)
}

/// Records one message as "severity: text (object names)". Never panics and never unwinds.
// SAFETY: only the loader calls this, with the pointers described in the Vulkan spec for
// PFN_vkDebugUtilsMessengerCallbackEXT and the user data set in `messenger_info`.
unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if data.is_null() || user_data.is_null() {
            return;
        }
        // SAFETY: the loader passes a valid callback-data struct for the duration of the call, and
        // `user_data` is the `Arc<MessageLog>` pointer from `messenger_info`, kept alive by the
        // context until after the messenger is destroyed.
        let (data, log) = unsafe { (&*data, &*(user_data as *const MessageLog)) };
        let level = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) { "error" } else { "warning" };
        // SAFETY: the pointers inside `data` are valid C strings or null for the call's duration.
        let text = unsafe { data.message_as_c_str() }.map(|m| m.to_string_lossy().into_owned()).unwrap_or_default();
        let mut names = Vec::new();
        if !data.p_objects.is_null() {
            // SAFETY: `p_objects` points to `object_count` valid object-name infos.
            let objects = unsafe { std::slice::from_raw_parts(data.p_objects, data.object_count as usize) };
            for object in objects {
                // SAFETY: as above, each name is a valid C string or null.
                if let Some(name) = unsafe { object.object_name_as_c_str() } {
                    let name = name.to_string_lossy().into_owned();
                    // The layer usually names objects in the text already.
                    if !text.contains(&name) && !names.contains(&name) {
                        names.push(name);
                    }
                }
            }
        }
        let message = if names.is_empty() {
            format!("{level}: {text}")
        } else {
            format!("{level}: {text} (objects: `{}`)", names.join("`, `"))
        };
        log.push(message);
    }));
    // A panic cannot cross the FFI boundary; dropping its payload is all we can do here.
    drop(result);
    vk::FALSE
}
