//! Images in and out: linear float EXR, sRGB PNG, atomic writes, error metrics.

pub mod image;
pub mod metrics;

pub use self::image::{check_output_path, read_exr, write_image, Image, ImageError};
