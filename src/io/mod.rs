//! Images in and out: linear float EXR, sRGB PNG, atomic writes, error metrics.

pub mod image;
pub mod layers;
pub mod metrics;

pub use self::image::{
    check_exr_input, check_not_input, check_not_overwriting, check_output_path, read_exr, same_file, write_image,
    Image, ImageError,
};
pub use self::layers::{contact_sheet, write_layers_exr};
