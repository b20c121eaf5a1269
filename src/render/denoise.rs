//! Denoising a render's mean image with Open Image Denoise (src/gpu/oidn.rs), guided by its
//! feature layers (albedo and normal). The denoiser sees the mean over all passes, never a
//! part: `merge --denoise` denoises the merged sum.

use super::Features;
use crate::gpu::oidn::{DenoiseError, Denoiser};
use crate::io::Image;

/// Whether the denoiser should run on OIDN's CUDA device: the renderer runs on an NVIDIA GPU
/// (its Vulkan device's name says so). Everywhere else, and where CUDA fails to open, the CPU.
pub fn prefers_cuda(device_name: &str) -> bool {
    device_name.to_ascii_lowercase().contains("nvidia")
}

/// `image` denoised, guided by `features` where given (HDR, guides prefiltered).
pub fn denoise_image(
    denoiser: &mut Denoiser,
    image: &Image,
    features: Option<&Features>,
) -> Result<Image, DenoiseError> {
    let guides = features.map(|f| (f.albedo.pixels.as_slice(), f.normal.pixels.as_slice()));
    let pixels = denoiser.denoise(image.width, image.height, &image.pixels, guides)?;
    Ok(Image { pixels, ..image.clone() })
}
