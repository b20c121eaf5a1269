//! Linear RGB images and their files. The output's extension picks the format: `.exr` is linear
//! float radiance, `.png` is sRGB-encoded 8-bit. Every file is written to a temporary name in the
//! same folder and renamed into place, so a failure never leaves a partial image.

use std::path::{Path, PathBuf};

/// A linear-radiance RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Image {
        Image { width, height, pixels: vec![[0.0; 3]; width as usize * height as usize] }
    }

    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Mean of each channel over all pixels.
    pub fn channel_means(&self) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                sum[c] += p[c] as f64;
            }
        }
        sum.map(|s| s / self.pixels.len().max(1) as f64)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: unsupported output format; use a .exr (linear radiance) or .png (sRGB) file name")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: cannot write output ({reason}); check that the folder exists and is writable")]
    NotWritable { path: PathBuf, reason: String },
    #[error("{path}: cannot write image: {reason}")]
    Write { path: PathBuf, reason: String },
    #[error("{path}: cannot read image: {reason}")]
    Read { path: PathBuf, reason: String },
}

/// Output file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Exr,
    Png,
}

pub fn format_of(path: &Path) -> Result<Format, ImageError> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("exr") => Ok(Format::Exr),
        Some("png") => Ok(Format::Png),
        _ => Err(ImageError::UnknownFormat { path: path.to_owned() }),
    }
}

fn temp_path_for(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    let ext = path.extension().map(|e| e.to_string_lossy().to_string()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp.{ext}", std::process::id()))
}

/// Fails early, before any rendering, when `path` has an unknown extension or cannot be written:
/// it creates and removes a temporary file next to it.
pub fn check_output_path(path: &Path) -> Result<(), ImageError> {
    format_of(path)?;
    if path.is_dir() {
        return Err(ImageError::NotWritable { path: path.to_owned(), reason: "it is a folder".into() });
    }
    let probe = temp_path_for(path);
    std::fs::write(&probe, b"")
        .map_err(|e| ImageError::NotWritable { path: path.to_owned(), reason: e.to_string() })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// sRGB transfer function (IEC 61966-2-1) of a linear value clamped to [0, 1].
pub fn srgb_encode(linear: f32) -> u8 {
    let v = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// 8-bit sRGB bytes of `image` after scaling by 2^`exposure`.
pub fn to_srgb8(image: &Image, exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    image.pixels.iter().flat_map(|p| p.map(|c| srgb_encode(c * scale))).collect()
}

/// Writes `image` atomically; `.png` gets exposure 2^`exposure` and sRGB encoding, `.exr` is
/// written as linear radiance, untouched.
pub fn write_image(path: &Path, image: &Image, exposure: f32) -> Result<(), ImageError> {
    match format_of(path)? {
        Format::Exr => write_atomically(path, |tmp| write_exr(tmp, image)),
        Format::Png => write_atomically(path, |tmp| write_png(tmp, image, exposure)),
    }
}

/// Runs `write` on a temporary file next to `path`, then renames it into place; on failure the
/// temporary file is removed and `path` is untouched.
pub fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), ImageError> {
    let tmp = temp_path_for(path);
    let finished = write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    finished.map_err(|reason| {
        let _ = std::fs::remove_file(&tmp);
        ImageError::Write { path: path.to_owned(), reason }
    })
}

fn write_png(tmp: &Path, image: &Image, exposure: f32) -> Result<(), String> {
    let buffer = ::image::RgbImage::from_raw(image.width, image.height, to_srgb8(image, exposure))
        .ok_or("pixel count does not match the size")?;
    buffer.save_with_format(tmp, ::image::ImageFormat::Png).map_err(|e| e.to_string())
}

fn write_exr(tmp: &Path, image: &Image) -> Result<(), String> {
    use exr::prelude::*;
    let w = image.width as usize;
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = image.pixels[pos.y() * w + pos.x()];
        (p[0], p[1], p[2])
    });
    // Increasing line order: the parallel compressor writes blocks in a fixed order, so the same
    // image always gives the same bytes.
    let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
    exr::image::Image::from_encoded_channels((w, image.height as usize), encoding, channels)
        .write()
        .to_file(tmp)
        .map_err(|e| e.to_string())
}

/// Reads the first RGB(A) layer of an EXR file as linear radiance.
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let read = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| Image::new(resolution.width() as u32, resolution.height() as u32),
        |image: &mut Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = image.width as usize;
            image.pixels[pos.y() * w + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| ImageError::Read { path: path.to_owned(), reason: e.to_string() })?;
    Ok(read.layer_data.channel_data.pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let mut image = Image::new(3, 2);
        for (i, p) in image.pixels.iter_mut().enumerate() {
            *p = [i as f32 * 0.5, 17.0, 1e-3 * i as f32];
        }
        write_image(&path, &image, 0.0).unwrap();
        assert_eq!(read_exr(&path).unwrap(), image);
        // Nothing but the image is left in the folder.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn srgb_encoding_hits_known_points() {
        assert_eq!(srgb_encode(0.0), 0);
        assert_eq!(srgb_encode(1.0), 255);
        assert_eq!(srgb_encode(0.2), 124); // 1.055 * 0.2^(1/2.4) - 0.055 = 0.4845
        assert_eq!(srgb_encode(f32::NAN), 0);
    }

    #[test]
    fn bad_output_paths_are_refused_before_rendering() {
        let dir = tempfile::tempdir().unwrap();
        let err = check_output_path(&dir.path().join("x.jpg")).unwrap_err().to_string();
        assert!(err.contains("unsupported output format"), "{err}");
        let err = check_output_path(&dir.path().join("missing/x.png")).unwrap_err().to_string();
        assert!(err.contains("cannot write output"), "{err}");
    }
}
