//! `photonix devices`: the Vulkan devices and the limits that matter to Photonix.

use anyhow::Result;

use photonix::gpu::list_devices;

pub fn run() -> Result<()> {
    for device in list_devices()? {
        out!("{}", device.describe());
    }
    Ok(())
}
