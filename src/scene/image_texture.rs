//! Image textures on the host: PNG, JPEG, OpenEXR and Radiance HDR files loaded as linear RGBA,
//! and packed into the shared texture buffer. The block layout and the lookups (bilinear, wrap
//! modes, orientation) are in `crate::cpu::image_texture` and its twin
//! `shaders/image_texture.glsl`.
//!
//! Colour: 8- and 16-bit colour channels are decoded with the exact sRGB curve for
//! `ColorSpace::Srgb` (colour textures), or divided by 255 / 65535 for `ColorSpace::Linear` (data
//! textures: roughness, bump, normal, alpha). Embedded gamma or ICC data are ignored. OpenEXR and
//! Radiance HDR hold linear floats and are taken as they are. Alpha is always linear, and 1 when
//! the file has none; grey images become R = G = B.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use crate::cpu::image_texture::{
    IMAGE_FLAG_ALPHA, IMAGE_HEADER_WORDS, IMAGE_WRAP_CLAMP, IMAGE_WRAP_MIRROR, IMAGE_WRAP_REPEAT,
};

/// Most texels per side: keeps every index of a block in `u32` and a block below 2^31 words.
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// The formats a texture file may have, for messages.
const SUPPORTED: &str = "use PNG, JPEG, OpenEXR, Radiance HDR, TGA or GIF (.png, .jpg, .jpeg, .exr, .hdr, .tga, .gif)";

/// How the 8- and 16-bit colour channels of a file are decoded. Float files are always linear.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorSpace {
    /// The exact sRGB curve (IEC 61966-2-1), for colours: reflectance, emission.
    Srgb,
    /// Value / maximum, for data: roughness, bump, normal maps, alpha.
    Linear,
}

/// What a lookup does outside [0, 1]: `Repeat` tiles, `Clamp` extends the edge texels, `Mirror`
/// reflects (..., 1, 0, 0, 1, ..., W-1, W-1, W-2, ...).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat,
    Clamp,
    Mirror,
}

impl Wrap {
    /// The `IMAGE_WRAP_*` code stored in a block's header.
    pub fn code(self) -> u32 {
        match self {
            Wrap::Repeat => IMAGE_WRAP_REPEAT,
            Wrap::Clamp => IMAGE_WRAP_CLAMP,
            Wrap::Mirror => IMAGE_WRAP_MIRROR,
        }
    }
}

/// A decoded image: linear RGBA, row 0 = the file's top row (v = 1 in texture coordinates).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    /// 1 ..= `MAX_IMAGE_SIDE`.
    pub width: u32,
    /// 1 ..= `MAX_IMAGE_SIDE`.
    pub height: u32,
    /// `width * height` texels, row by row; texel (i, j) is `texels[j * width + i]`.
    pub texels: Vec<[f32; 4]>,
}

/// Why an image texture could not be loaded. `Display` is the whole message and names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageTextureError {
    /// The file does not exist or cannot be read. `error` is not a `source`, so a report that
    /// prints the chain does not repeat the OS reason.
    #[error("{}: cannot read the image texture: {error}", path.display())]
    Read { path: PathBuf, error: crate::scene::files::FileError },
    /// Neither the content nor the extension is a supported format. `found` says what it is:
    /// "a `.txt` file", "a GIF image named `.png`".
    #[error("{}: unsupported image format ({found}); {SUPPORTED}", path.display())]
    Unsupported { path: PathBuf, found: String },
    /// The file claims a supported format but does not decode: truncated, damaged, or another
    /// kind of file with that extension.
    #[error("{}: cannot decode the {format} image: {reason}", path.display())]
    Decode { path: PathBuf, format: &'static str, reason: String },
    /// More than `MAX_IMAGE_SIDE` texels on a side.
    #[error("{}: the image is {width}x{height} texels, too large for a texture; scale it down to at most {max} texels per side", path.display())]
    TooLarge { path: PathBuf, width: u64, height: u64, max: u32 },
}

/// The exact sRGB decoding curve: c <= 0.04045 ? c/12.92 : ((c + 0.055)/1.055)^2.4, c in [0, 1].
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads an image texture. The content decides the format (PNG, JPEG, OpenEXR, Radiance HDR,
/// GIF), whatever the extension; TGA, which has no signature, by the extension `.tga`.
/// `color_space` applies to 8- and 16-bit colour channels only.
pub fn load_image_texture(path: &Path, color_space: ColorSpace) -> Result<ImageTexture, ImageTextureError> {
    // Through the scene's file gate: recorded as an input, confined in the editor, a regular
    // file of at most `MAX_IMAGE_FILE_BYTES`; the decoded image is checked too (`MAX_IMAGE_SIDE`).
    let bytes = crate::scene::files::read(path, crate::limits::MAX_IMAGE_FILE_BYTES)
        .map_err(|error| ImageTextureError::Read { path: path.to_owned(), error })?;
    decode_image_texture(&bytes, path, color_space)
}

/// `load_image_texture` on bytes already read; `path` names the file in messages.
pub fn decode_image_texture(
    bytes: &[u8],
    path: &Path,
    color_space: ColorSpace,
) -> Result<ImageTexture, ImageTextureError> {
    let tga = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("tga"));
    let Some(kind) = sniff(bytes).or(tga.then_some(FileKind::Tga)) else {
        return Err(unrecognised(bytes, path));
    };
    let decode_error = |reason: String| ImageTextureError::Decode {
        path: path.to_owned(),
        format: kind.name(),
        reason: reason.trim_end_matches('.').to_string(),
    };
    let texture = match kind {
        FileKind::Exr => {
            let (width, height) = exr_size(bytes).map_err(decode_error)?;
            check_size(path, width, height)?;
            decode_exr(bytes).map_err(decode_error)?
        }
        FileKind::Png | FileKind::Jpeg | FileKind::Hdr | FileKind::Gif | FileKind::Tga => {
            let format = match kind {
                FileKind::Png => image::ImageFormat::Png,
                FileKind::Jpeg => image::ImageFormat::Jpeg,
                FileKind::Gif => image::ImageFormat::Gif,
                FileKind::Tga => image::ImageFormat::Tga,
                _ => image::ImageFormat::Hdr,
            };
            let reader = || image::ImageReader::with_format(Cursor::new(bytes), format);
            let (width, height) = reader().into_dimensions().map_err(|e| decode_error(e.to_string()))?;
            check_size(path, width.into(), height.into())?;
            let mut reader = reader();
            // The size is checked above; the crate's default 512 MiB limit would refuse big
            // 16-bit images that fit.
            reader.no_limits();
            let image = reader.decode().map_err(|e| decode_error(e.to_string()))?;
            from_dynamic_image(&image, color_space)
        }
    };
    if texture.width == 0 || texture.height == 0 {
        return Err(decode_error("the image has no texels".to_string()));
    }
    Ok(texture)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FileKind {
    Png,
    Jpeg,
    Exr,
    Hdr,
    /// The first frame of a GIF.
    Gif,
    Tga,
}

/// The supported format of `bytes` by its signature, if any.
fn sniff(bytes: &[u8]) -> Option<FileKind> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some(FileKind::Png)
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some(FileKind::Jpeg)
    } else if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        Some(FileKind::Exr)
    } else if bytes.starts_with(b"#?") {
        // "#?RADIANCE" or "#?RGBE"
        Some(FileKind::Hdr)
    } else if bytes.starts_with(b"GIF87a") || bytes.starts_with(b"GIF89a") {
        Some(FileKind::Gif)
    } else {
        None
    }
}

impl FileKind {
    fn name(self) -> &'static str {
        match self {
            FileKind::Png => "PNG",
            FileKind::Jpeg => "JPEG",
            FileKind::Exr => "OpenEXR",
            FileKind::Hdr => "Radiance HDR",
            FileKind::Gif => "GIF",
            FileKind::Tga => "TGA",
        }
    }
}

/// The error for content without a supported signature: a supported extension makes it a damaged
/// file of that format, anything else an unsupported format.
fn unrecognised(bytes: &[u8], path: &Path) -> ImageTextureError {
    let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    let claimed = match extension.as_deref() {
        Some("png") => Some("PNG"),
        Some("jpg" | "jpeg") => Some("JPEG"),
        Some("exr") => Some("OpenEXR"),
        Some("hdr") => Some("Radiance HDR"),
        Some("gif") => Some("GIF"),
        _ => None,
    };
    let named = match &extension {
        Some(e) => format!("`.{e}`"),
        None => "no extension".to_string(),
    };
    // The image crate knows the signatures of formats we do not decode (BMP, TIFF, WebP...).
    if let Ok(other) = image::guess_format(bytes) {
        let found = format!("a {} image named {named}", format!("{other:?}").to_uppercase());
        return ImageTextureError::Unsupported { path: path.to_owned(), found };
    }
    match claimed {
        Some(format) => ImageTextureError::Decode {
            path: path.to_owned(),
            format,
            reason: format!("the file does not start with the {format} signature"),
        },
        None => {
            let found = match &extension {
                Some(e) => format!("a `.{e}` file"),
                None => "a file with no extension".to_string(),
            };
            ImageTextureError::Unsupported { path: path.to_owned(), found }
        }
    }
}

fn check_size(path: &Path, width: u64, height: u64) -> Result<(), ImageTextureError> {
    let max = u64::from(MAX_IMAGE_SIDE);
    if width > max || height > max {
        return Err(ImageTextureError::TooLarge { path: path.to_owned(), width, height, max: MAX_IMAGE_SIDE });
    }
    Ok(())
}

/// Texels of interleaved samples with 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA) channels.
fn texels_from_samples<T: Copy>(
    samples: &[T],
    channels: usize,
    color: impl Fn(T) -> f32,
    alpha: impl Fn(T) -> f32,
) -> Vec<[f32; 4]> {
    samples
        .chunks_exact(channels)
        .map(|p| match channels {
            1 => {
                let g = color(p[0]);
                [g, g, g, 1.0]
            }
            2 => {
                let g = color(p[0]);
                [g, g, g, alpha(p[1])]
            }
            3 => [color(p[0]), color(p[1]), color(p[2]), 1.0],
            _ => [color(p[0]), color(p[1]), color(p[2]), alpha(p[3])],
        })
        .collect()
}

fn from_dynamic_image(image: &image::DynamicImage, color_space: ColorSpace) -> ImageTexture {
    let (width, height) = (image.width(), image.height());
    let channels = usize::from(image.color().channel_count());
    let texels = if let Some(rgb) = image.as_rgb32f() {
        texels_from_samples(rgb.as_raw(), 3, |c| c, |a| a)
    } else if let Some(rgba) = image.as_rgba32f() {
        texels_from_samples(rgba.as_raw(), 4, |c| c, |a| a)
    } else if image.color().bytes_per_pixel() as usize == channels {
        // 8 bits per channel: a table of the 256 decoded values.
        let table: Vec<f32> = (0..=255u8).map(|b| decode_channel(f64::from(b) / 255.0, color_space)).collect();
        texels_from_samples(image.as_bytes(), channels, |b| table[usize::from(b)], |b| (f64::from(b) / 255.0) as f32)
    } else {
        // 16 bits per channel (or a future layout, converted to it).
        let converted;
        let (samples, channels) = match image.as_flat_samples_u16() {
            Some(flat) => (flat.samples, channels),
            None => {
                converted = image.to_rgba16();
                (converted.as_raw().as_slice(), 4)
            }
        };
        let table: Vec<f32> = (0..=u16::MAX).map(|v| decode_channel(f64::from(v) / 65535.0, color_space)).collect();
        texels_from_samples(samples, channels, |v| table[usize::from(v)], |v| (f64::from(v) / 65535.0) as f32)
    };
    ImageTexture { width, height, texels }
}

fn decode_channel(c: f64, color_space: ColorSpace) -> f32 {
    match color_space {
        ColorSpace::Srgb => srgb_to_linear(c) as f32,
        ColorSpace::Linear => c as f32,
    }
}

/// The largest width and height of the layers of an OpenEXR file, from its headers.
fn exr_size(bytes: &[u8]) -> Result<(u64, u64), String> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(|e| e.to_string())?;
    let sizes = meta.headers.iter().map(|h| (h.layer_size.x() as u64, h.layer_size.y() as u64));
    Ok(sizes.fold((0, 0), |(w, h), (x, y)| (w.max(x), h.max(y))))
}

/// The first layer of an OpenEXR file: channels R, G, B (A optional), or Y (A optional) for a
/// grey image; a layer prefix ("diffuse.R") is ignored. The error is the reason only.
fn decode_exr(bytes: &[u8]) -> Result<ImageTexture, String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let layer = image.layer_data;
    let (width, height) = (layer.size.x(), layer.size.y());
    let count = width * height;
    let channel = |name: &str| -> std::result::Result<Option<Vec<f32>>, String> {
        let Some(found) = layer.channel_data.list.iter().find(|c| {
            let full = c.name.to_string();
            full.rsplit('.').next().is_some_and(|base| base.eq_ignore_ascii_case(name))
        }) else {
            return Ok(None);
        };
        let values: Vec<f32> = found.sample_data.values_as_f32().collect();
        if values.len() != count {
            return Err(format!("channel {} is subsampled, which textures do not support", found.name));
        }
        Ok(Some(values))
    };
    let alpha = channel("A")?;
    let alpha_at = |k: usize| alpha.as_ref().map_or(1.0, |a| a[k]);
    let texels = match (channel("R")?, channel("G")?, channel("B")?, channel("Y")?) {
        (Some(r), Some(g), Some(b), _) => (0..count).map(|k| [r[k], g[k], b[k], alpha_at(k)]).collect(),
        (_, _, _, Some(y)) => (0..count).map(|k| [y[k], y[k], y[k], alpha_at(k)]).collect(),
        _ => {
            let names: Vec<String> = layer.channel_data.list.iter().map(|c| c.name.to_string()).collect();
            return Err(format!("no R, G, B or Y channels (it has {})", names.join(", ")));
        }
    };
    let too_big = |_| "the image is too large".to_string();
    Ok(ImageTexture {
        width: u32::try_from(width).map_err(too_big)?,
        height: u32::try_from(height).map_err(too_big)?,
        texels,
    })
}

/// f32 to IEEE half bits, rounded to nearest even, subnormal halves included. Values beyond the
/// largest finite half (65504) and infinities clamp to it; NaN becomes 0. Integer-only, so the
/// result does not depend on the machine (the idea of `crate::cpu::photon::f32_to_f16`, which
/// flushes subnormals instead).
pub fn f32_to_half(v: f32) -> u32 {
    let b = if v.is_nan() { 0 } else { v.to_bits() };
    let sign = (b >> 16) & 0x8000;
    let e = ((b >> 23) & 0xff) as i32 - 112; // rebias 127 -> 15
    let m = b & 0x7f_ffff;
    if e >= 31 {
        return sign | 0x7bff;
    }
    if e <= 0 {
        // Subnormal half: the value is q * 2^-24 with q = (1.m) * 2^(e - 14 + 23).
        if e < -10 {
            return sign; // below a quarter of the smallest subnormal: rounds to zero
        }
        let full = m | 0x80_0000;
        let shift = (14 - e) as u32;
        let mut q = full >> shift;
        let rest = full & ((1 << shift) - 1);
        let half_way = 1 << (shift - 1);
        if rest > half_way || (rest == half_way && (q & 1) == 1) {
            q += 1; // may reach 0x400, the smallest normal half: still the right bits
        }
        return sign | q;
    }
    let mut h = ((e as u32) << 10) | (m >> 13);
    let rest = m & 0x1fff;
    if rest > 0x1000 || (rest == 0x1000 && (h & 1) == 1) {
        h += 1;
    }
    h.min(0x7bff) | sign
}

impl ImageTexture {
    /// Words `pack` appends: `IMAGE_HEADER_WORDS + 2 * width * height`. Compare 4 times the
    /// total with the device's `maxStorageBufferRange` before packing.
    pub fn packed_words(&self) -> u64 {
        u64::from(IMAGE_HEADER_WORDS) + 2 * u64::from(self.width) * u64::from(self.height)
    }

    /// Appends this image's block (layout in `crate::cpu::image_texture`) to `data` and returns
    /// its word offset `at`, the argument of `image_lookup`.
    pub fn pack(&self, wrap: Wrap, data: &mut Vec<u32>) -> u32 {
        assert!(
            (1..=MAX_IMAGE_SIDE).contains(&self.width)
                && (1..=MAX_IMAGE_SIDE).contains(&self.height)
                && self.texels.len() == self.width as usize * self.height as usize,
            "an ImageTexture has 1..={MAX_IMAGE_SIDE} texels per side and width x height texels"
        );
        let at = u32::try_from(data.len())
            .ok()
            .filter(|&at| u64::from(at) + self.packed_words() <= u64::from(u32::MAX))
            .expect("texture data stays below 2^32 words (the caller checks packed_words against the device)");
        data.reserve(self.packed_words() as usize);
        data.extend([self.width, self.height, wrap.code(), 0]);
        let mut flags = 0;
        for t in &self.texels {
            let [r, g, b, a] = t.map(f32_to_half);
            if a != 0x3c00 {
                flags |= IMAGE_FLAG_ALPHA;
            }
            data.push(r | (g << 16));
            data.push(b | (a << 16));
        }
        data[at as usize + 3] = flags;
        at
    }

    /// Texel (column i, row j), row 0 = the file's top row.
    pub fn texel(&self, i: u32, j: u32) -> [f32; 4] {
        self.texels[(j * self.width + i) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shared ground-truth folder lies next to the repository.
    const BACK_WALL: &str =
        concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/reference/cornell-glossy/textures/back_wall.png");

    /// sRGB bytes decoded with the exact curve, in f64 (python3, float64).
    const SRGB_BYTES: [(u8, f64); 4] =
        [(0, 0.0), (10, 0.003_035_269_835_488_375), (128, 0.215_860_500_113_899_26), (255, 1.0)];

    fn close(a: [f32; 4], b: [f64; 4], tolerance: f64) -> bool {
        a.iter().zip(b).all(|(&x, y)| (f64::from(x) - y).abs() <= tolerance)
    }

    #[test]
    fn srgb_bytes_decode_to_hand_computed_values() {
        // 10/255 = 0.0392 is on the linear segment (/12.92), 128/255 on the power segment.
        for (byte, expected) in SRGB_BYTES {
            let got = srgb_to_linear(f64::from(byte) / 255.0);
            assert!((got - expected).abs() < 1e-12, "{byte}: {got} vs {expected}");
        }
        // The same through a file, 8- and 16-bit, both colour spaces; alpha is always linear.
        let dir = tempfile::tempdir().unwrap();
        let bytes: Vec<u8> = SRGB_BYTES.iter().flat_map(|&(b, _)| [b, b, b, b]).collect();
        let path8 = dir.path().join("bytes.png");
        image::RgbaImage::from_raw(4, 1, bytes.clone()).unwrap().save(&path8).unwrap();
        let path16 = dir.path().join("words.png");
        let words: Vec<u16> = bytes.iter().map(|&b| u16::from(b) * 257).collect();
        image::ImageBuffer::<image::Rgba<u16>, _>::from_raw(4, 1, words).unwrap().save(&path16).unwrap();
        for path in [&path8, &path16] {
            let srgb = load_image_texture(path, ColorSpace::Srgb).unwrap();
            let linear = load_image_texture(path, ColorSpace::Linear).unwrap();
            for (i, &(byte, expected)) in SRGB_BYTES.iter().enumerate() {
                let c = f64::from(byte) / 255.0;
                let t = srgb.texel(i as u32, 0);
                assert!(close(t, [expected, expected, expected, c], 1e-6), "{}: {byte}: {t:?}", path.display());
                let t = linear.texel(i as u32, 0);
                assert!(close(t, [c, c, c, c], 1e-6), "{}: {byte}: {t:?}", path.display());
            }
        }
    }

    #[test]
    fn half_packing_round_trips_within_half_an_ulp() {
        // Normal halves: 11 significant bits, so the relative rounding error is at most 2^-11.
        let mut worst = 0.0f64;
        for k in 0..200_000 {
            let v = 6.2e-5 * 1.000_05f32.powi(k); // 6.2e-5 (smallest normal 6.1e-5) .. 1.4e0 ..
            let v = if v > 65_000.0 { break } else { v };
            for s in [v, -v] {
                let back = crate::cpu::image_texture::image_half_to_f32(f32_to_half(s));
                let error = ((f64::from(back) - f64::from(s)) / f64::from(s)).abs();
                worst = worst.max(error);
                assert!(error <= 1.0 / 2048.0, "{s} -> {back}");
            }
        }
        println!("worst relative error of normal halves {worst:.3e} (bound 2^-11 = 4.88e-4)");
        // Subnormal halves: steps of 2^-24, so the absolute error is at most 2^-25.
        for k in 0..10_000 {
            let v = k as f32 * 6.1e-9;
            let back = crate::cpu::image_texture::image_half_to_f32(f32_to_half(v));
            assert!((back - v).abs() <= 2f32.powi(-25), "{v} -> {back}");
        }
        // Edge cases: exact values, ties to even, clamping, NaN.
        let cases = [
            (1.0, 0x3c00),
            (-2.0, 0xc000),
            (65504.0, 0x7bff),
            (1e9, 0x7bff),
            (f32::INFINITY, 0x7bff),
            (f32::NEG_INFINITY, 0xfbff),
            (f32::NAN, 0),
            (2f32.powi(-24), 0x0001),
            (2f32.powi(-25), 0),            // tie between 0 and the smallest subnormal: to even
            (3.0 * 2f32.powi(-25), 0x0002), // tie between 1 and 2: to even
            (2f32.powi(-14), 0x0400),
            (2f32.powi(-14) - 2f32.powi(-26), 0x0400), // rounds up into the smallest normal
            (1.0 + 2f32.powi(-11), 0x3c00),            // tie: to even
            (1.0 + 3.0 * 2f32.powi(-11), 0x3c02),      // tie: to even
            (1e-30, 0),
        ];
        for (v, bits) in cases {
            assert_eq!(f32_to_half(v), bits, "{v:e}");
        }
    }

    #[test]
    fn pack_writes_the_documented_block() {
        let image = ImageTexture { width: 2, height: 1, texels: vec![[1.0, 0.5, 0.25, 1.0], [0.0, -2.0, 2.0, 0.5]] };
        assert_eq!(image.packed_words(), 8);
        let mut data = vec![7, 7, 7];
        let at = image.pack(Wrap::Mirror, &mut data);
        assert_eq!(at, 3);
        assert_eq!(
            data,
            [7, 7, 7, 2, 1, IMAGE_WRAP_MIRROR, IMAGE_FLAG_ALPHA, 0x3800_3c00, 0x3c00_3400, 0xc000_0000, 0x3800_4000]
        );
        let opaque = ImageTexture { width: 1, height: 1, texels: vec![[0.0, 0.0, 0.0, 1.0]] };
        let at = opaque.pack(Wrap::Repeat, &mut data);
        assert_eq!(&data[at as usize..], [1, 1, IMAGE_WRAP_REPEAT, 0, 0, 0x3c00_0000]);
    }

    #[test]
    fn back_wall_texels_are_as_documented() {
        let t = load_image_texture(Path::new(BACK_WALL), ColorSpace::Srgb).unwrap();
        assert_eq!((t.width, t.height), (64, 64));
        let s = |b: u8| srgb_to_linear(f64::from(b) / 255.0);
        let rgb = |r, g, b| [s(r), s(g), s(b), 1.0];
        let (red, yellow, green, blue) = (rgb(200, 50, 50), rgb(235, 190, 40), rgb(60, 150, 70), rgb(50, 80, 190));
        let (dark, white) = (rgb(20, 20, 40), rgb(245, 245, 245));
        // (column, row, colour): stripes below the F, the white square, the F's stem and arms.
        let expected = [
            (2, 60, red),
            (15, 40, red),
            (16, 60, yellow),
            (28, 60, yellow),
            (40, 50, green),
            (47, 5, green),
            (48, 5, blue),
            (63, 63, blue),
            (0, 0, white),
            (7, 7, white),
            (8, 7, red),
            (7, 8, red),
            (18, 53, dark),
            (25, 40, dark),
            (26, 40, yellow),
            (45, 10, dark),
            (46, 12, green),
            (39, 34, dark),
            (40, 34, green),
            (30, 20, yellow),
        ];
        for (i, j, colour) in expected {
            assert!(close(t.texel(i, j), colour, 1e-6), "texel ({i}, {j}) = {:?}, expected {colour:?}", t.texel(i, j));
        }
        // Through the lookup: uv (0.05, 0.95) is texel coordinate (2.7, 2.7), inside the white
        // square (the top-left corner: v = 1 is the top row), and a texel centre of the F's stem.
        let mut data = Vec::new();
        let at = t.pack(Wrap::Repeat, &mut data);
        let lookup = |u: f32, v: f32| crate::cpu::image_texture::image_lookup(&data, at, glam::Vec2::new(u, v));
        let near = |got: glam::Vec4, want: [f64; 4]| {
            // Halves round by at most 2^-11 relative.
            got.to_array().iter().zip(want).all(|(&g, w)| (f64::from(g) - w).abs() <= w.abs() / 2048.0 + 1e-7)
        };
        let mut worst = 0.0f64;
        for j in 0..64 {
            for i in 0..64 {
                let stored = crate::cpu::image_texture::image_fetch(&data, at, 64, i, j).to_array();
                for (s, e) in stored.iter().zip(t.texel(i, j)) {
                    worst = worst.max(f64::from((s - e).abs() / e.max(1e-30)));
                }
            }
        }
        println!("back wall: worst relative change by half-float storage {worst:.2e}");
        assert!(worst <= 1.0 / 2048.0);
        assert!(near(lookup(0.05, 0.95), white), "{}", lookup(0.05, 0.95));
        assert!(near(lookup(20.5 / 64.0, 1.0 - 30.5 / 64.0), dark));
        assert!(near(lookup(2.5 / 64.0, 1.0 - 60.5 / 64.0), red));
        assert!(near(lookup(60.5 / 64.0, 1.0 - 60.5 / 64.0), blue));
    }

    #[test]
    fn every_format_loads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = |name: &str| dir.path().join(name);
        let linear = |p: &Path| load_image_texture(p, ColorSpace::Linear).unwrap();

        // PNG: grey and grey + alpha expand to RGB(A); 2x2, rows top to bottom.
        image::GrayImage::from_raw(2, 2, vec![0, 51, 102, 255]).unwrap().save(path("grey.png")).unwrap();
        let t = linear(&path("grey.png"));
        assert_eq!((t.width, t.height), (2, 2));
        assert_eq!(t.texels, [[0.0, 0.0, 0.0, 1.0], [0.2, 0.2, 0.2, 1.0], [0.4, 0.4, 0.4, 1.0], [1.0, 1.0, 1.0, 1.0]]);
        image::GrayAlphaImage::from_raw(1, 1, vec![255, 51]).unwrap().save(path("grey_alpha.png")).unwrap();
        assert_eq!(linear(&path("grey_alpha.png")).texels, [[1.0, 1.0, 1.0, 0.2]]);
        image::RgbImage::from_raw(1, 2, vec![255, 0, 51, 0, 255, 0]).unwrap().save(path("rgb.png")).unwrap();
        assert_eq!(linear(&path("rgb.png")).texels, [[1.0, 0.0, 0.2, 1.0], [0.0, 1.0, 0.0, 1.0]]);
        let t = load_image_texture(&path("rgb.png"), ColorSpace::Srgb).unwrap();
        assert!(close(t.texel(0, 0), [1.0, 0.0, 0.033_104_766_570_885_055, 1.0], 1e-6), "{:?}", t.texels);

        // JPEG is lossy: a flat 16x16 image decodes within a few steps of its bytes.
        let flat = [200u8, 100, 50];
        image::RgbImage::from_fn(16, 16, |_, _| image::Rgb(flat)).save(path("flat.jpg")).unwrap();
        let t = linear(&path("flat.jpg"));
        assert_eq!((t.width, t.height), (16, 16));
        let want = flat.map(|b| f64::from(b) / 255.0);
        assert!(t.texels.iter().all(|&p| close(p, [want[0], want[1], want[2], 1.0], 3.0 / 255.0)), "{:?}", t.texels[0]);
        image::GrayImage::from_fn(8, 8, |_, _| image::Luma([128])).save(path("grey.jpeg")).unwrap();
        let t = load_image_texture(&path("grey.jpeg"), ColorSpace::Srgb).unwrap();
        assert!(close(t.texel(3, 3), [0.2159, 0.2159, 0.2159, 1.0], 0.01), "{:?}", t.texel(3, 3));

        // OpenEXR: linear floats kept as they are (also under ColorSpace::Srgb), alpha kept or 1.
        let value = |x: usize, y: usize| (x as f32 * 0.5, y as f32 * 2.0, 100.0, 0.25);
        exr::prelude::write_rgba_file(path("rgba.exr"), 3, 2, value).unwrap();
        let t = load_image_texture(&path("rgba.exr"), ColorSpace::Srgb).unwrap();
        assert_eq!((t.width, t.height), (3, 2));
        assert_eq!(t.texel(2, 1), [1.0, 2.0, 100.0, 0.25]);
        exr::prelude::write_rgb_file(path("rgb.exr"), 2, 1, |x, _| (x as f32, 3.5f32, 1e-3f32)).unwrap();
        assert_eq!(linear(&path("rgb.exr")).texels, [[0.0, 3.5, 1e-3, 1.0], [1.0, 3.5, 1e-3, 1.0]]);
        {
            use exr::prelude::*;
            let y = AnyChannel::new("Y", FlatSamples::F32(vec![0.5, 4.0]));
            let channels = AnyChannels::sort(SmallVec::from_vec(vec![y]));
            Image::from_channels((1, 2), channels).write().to_file(path("luma.exr")).unwrap();
        }
        assert_eq!(linear(&path("luma.exr")).texels, [[0.5, 0.5, 0.5, 1.0], [4.0, 4.0, 4.0, 1.0]]);

        // Radiance HDR: RGBE keeps 8 bits of mantissa, and these values are exact in it.
        let pixels = [image::Rgb([0.5f32, 0.25, 2.0]), image::Rgb([1.0, 1.0, 1.0])];
        let file = std::fs::File::create(path("sky.hdr")).unwrap();
        image::codecs::hdr::HdrEncoder::new(file).encode(&pixels, 1, 2).unwrap();
        let t = load_image_texture(&path("sky.hdr"), ColorSpace::Srgb).unwrap();
        assert_eq!(t.texels, [[0.5, 0.25, 2.0, 1.0], [1.0, 1.0, 1.0, 1.0]]);
        // The content decides, not the extension.
        std::fs::copy(path("sky.hdr"), path("sky.png")).unwrap();
        assert_eq!(linear(&path("sky.png")), t);
    }

    #[test]
    fn bad_files_give_clear_errors() {
        let dir = tempfile::tempdir().unwrap();
        let path = |name: &str| dir.path().join(name);
        let load = |p: &Path| load_image_texture(p, ColorSpace::Srgb).unwrap_err();

        let err = load(&path("missing.png"));
        let message = format!("{:#}", anyhow::Error::new(err));
        println!("{message}");
        // The OS reason once, even when a report prints the error's whole chain.
        assert!(message.contains("missing.png: cannot read the image texture: "), "{message}");
        assert_eq!(message.matches("No such file or directory").count(), 1, "{message}");

        std::fs::write(path("notes.txt"), "not an image").unwrap();
        let err = load(&path("notes.txt"));
        println!("{err}");
        assert!(matches!(err, ImageTextureError::Unsupported { .. }), "{err}");
        assert!(err.to_string().contains("notes.txt: unsupported image format (a `.txt` file); use PNG"), "{err}");

        let bmp = b"BM\x3a\x00\x00\x00\x00\x00\x00\x00\x36\x00\x00\x00";
        std::fs::write(path("paint.bmp"), bmp).unwrap();
        let err = load(&path("paint.bmp"));
        assert!(err.to_string().contains("(a BMP image named `.bmp`)"), "{err}");
        std::fs::write(path("renamed.png"), bmp).unwrap();
        let err = load(&path("renamed.png"));
        println!("{err}");
        assert!(err.to_string().contains("renamed.png: unsupported image format (a BMP image named `.png`)"), "{err}");

        std::fs::write(path("text.png"), "not an image").unwrap();
        let err = load(&path("text.png"));
        println!("{err}");
        assert!(matches!(err, ImageTextureError::Decode { format: "PNG", .. }), "{err}");

        image::RgbImage::from_fn(32, 32, |x, y| image::Rgb([x as u8 * 8, y as u8 * 8, 7]))
            .save(path("full.png"))
            .unwrap();
        let bytes = std::fs::read(path("full.png")).unwrap();
        std::fs::write(path("truncated.png"), &bytes[..bytes.len() / 2]).unwrap();
        let err = load(&path("truncated.png"));
        println!("{err}");
        assert!(matches!(err, ImageTextureError::Decode { format: "PNG", .. }), "{err}");
        assert!(err
            .to_string()
            .starts_with(&format!("{}: cannot decode the PNG image: ", path("truncated.png").display())));

        image::GrayImage::new(MAX_IMAGE_SIDE + 1, 1).save(path("wide.png")).unwrap();
        let err = load(&path("wide.png"));
        println!("{err}");
        assert!(matches!(err, ImageTextureError::TooLarge { width: 16385, height: 1, .. }), "{err}");

        for err in [load(&path("missing.png")), load(&path("notes.txt")), load(&path("truncated.png"))] {
            let message = err.to_string();
            assert!(!message.ends_with('.') && message.contains(&*dir.path().to_string_lossy()), "{message}");
        }
    }
}
