//! Images a POV-Ray scene names: height fields' heights and image maps' mean colours.
//!
//! PNG and GIF are read with the `png` and `gif` crates directly, so a palette image gives its
//! indices (POV-Ray's height field takes the palette index as the height, not the colour); JPEG
//! and TGA through `image`; PGM and PPM (binary and plain) here. TIFF, IFF, POT, SYS, EXR and
//! HDR are refused with the format named.

use std::path::Path;

/// The image type keywords POV-Ray accepts before a file name.
pub const FORMATS: &[&str] = &["png", "jpeg", "pgm", "ppm", "tga", "gif", "tiff", "iff", "pot", "sys", "exr", "hdr"];

/// Grey values (or palette indices) scaled to [0, 1], row 0 the image's top.
pub struct Heights {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f64>,
}

/// An image's colours as stored (sRGB-encoded by convention, as POV-Ray reads PNG, JPEG and
/// PNM without a gamma chunk) and its heights.
struct Decoded {
    width: usize,
    height: usize,
    /// Per pixel: red, green, blue in [0, 1] as stored (not decoded), and the height.
    rgb: Vec<[f64; 3]>,
    heights: Vec<f64>,
}

/// Images larger than this (pixels) are refused: a height field of 2^24 samples is already
/// far beyond the triangles the front end writes.
const MAX_PIXELS: usize = 1 << 24;

fn kind_of(path: &Path, kind: &str) -> String {
    if !kind.is_empty() {
        return kind.to_string();
    }
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("jpg") | Some("jpeg") => "jpeg".into(),
        Some(e) => e.to_string(),
        None => "png".into(),
    }
}

fn decode(path: &Path, kind: &str) -> Result<Decoded, String> {
    let kind = kind_of(path, kind);
    let shown = crate::limits::printable_message(&path.display().to_string());
    let bytes = super::parser::read_gated(path, crate::limits::MAX_IMAGE_FILE_BYTES, "the image")?;
    let d = match kind.as_str() {
        "png" => decode_png(&bytes),
        "jpeg" => decode_jpeg(&bytes),
        "pgm" | "ppm" => decode_pnm(&bytes),
        "gif" => decode_gif(&bytes),
        "tga" => decode_tga(&bytes),
        other => {
            return Err(format!(
                "{other} images are not supported yet ({shown}); convert it to PNG (PNG, JPEG, GIF, TGA, PGM and PPM are read)"
            ))
        }
    };
    let d = d.map_err(|e| format!("{shown} is not a {kind} image this front-end reads: {e}"))?;
    if d.width == 0 || d.height == 0 {
        return Err(format!("the image {shown} is empty"));
    }
    Ok(d)
}

fn decode_png(bytes: &[u8]) -> Result<Decoded, String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    if w.saturating_mul(h) > MAX_PIXELS {
        return Err(format!("{w} x {h} pixels is more than {MAX_PIXELS}"));
    }
    let palette: Option<Vec<u8>> = reader.info().palette.as_ref().map(|p| p.to_vec());
    let size = reader.output_buffer_size().ok_or("the image is too large")?;
    let mut buf = vec![0u8; size];
    let frame = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let (ct, depth) = (frame.color_type, frame.bit_depth as usize);
    let line = frame.line_size;
    let channels = match ct {
        png::ColorType::Grayscale | png::ColorType::Indexed => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
    };
    let max = ((1u32 << depth) - 1) as f64;
    // Sample s of row y (packed below 8 bits, big-endian at 16).
    let sample = |y: usize, s: usize| -> u32 {
        let row = &buf[y * line..(y + 1) * line];
        match depth {
            16 => u16::from_be_bytes([row[2 * s], row[2 * s + 1]]) as u32,
            8 => row[s] as u32,
            d => {
                let per = 8 / d;
                let byte = row[s / per];
                let shift = 8 - d * (s % per + 1);
                ((byte >> shift) as u32) & ((1 << d) - 1)
            }
        }
    };
    let mut d = Decoded { width: w, height: h, rgb: Vec::with_capacity(w * h), heights: Vec::with_capacity(w * h) };
    for y in 0..h {
        for x in 0..w {
            let s = x * channels;
            match ct {
                png::ColorType::Indexed => {
                    let i = sample(y, s) as usize;
                    let p = palette.as_deref().unwrap_or(&[]);
                    let c = if 3 * i + 2 < p.len() { [p[3 * i], p[3 * i + 1], p[3 * i + 2]] } else { [0, 0, 0] };
                    d.rgb.push(c.map(|v| v as f64 / 255.0));
                    // POV-Ray: a palette image's height is its index (reference manual, "Height Field").
                    d.heights.push(i as f64 / 255.0);
                }
                png::ColorType::Grayscale | png::ColorType::GrayscaleAlpha => {
                    let v = sample(y, s) as f64 / max;
                    d.rgb.push([v; 3]);
                    d.heights.push(v);
                }
                _ => {
                    let c = [sample(y, s), sample(y, s + 1), sample(y, s + 2)].map(|v| v as f64 / max);
                    d.heights.push(colour_height(c, depth));
                    d.rgb.push(c);
                }
            }
        }
    }
    Ok(d)
}

/// Rec. 601 luma, POV-Ray's grey for a colour image's height.
fn grey(c: [f64; 3]) -> f64 {
    0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]
}

/// A colour pixel's height as POV-Ray 3.7 takes it (`image_height_at`, source/core/material/
/// imageutil.cpp): up to 8 bits a channel, red is the high byte and green the low byte of a
/// 16-bit height (the convention of POV-Ray's TGA height fields: (255 r + g) / 65535 with r, g
/// the 8-bit values); deeper channels give their grey.
fn colour_height(c: [f64; 3], bits: usize) -> f64 {
    if bits > 8 {
        grey(c)
    } else {
        (c[0] * 255.0 + c[1]) * 255.0 / 65535.0
    }
}

/// The first frame of a GIF on its logical screen (the background index around a smaller
/// frame): heights are palette indices / 255, as for a palette PNG.
fn decode_gif(bytes: &[u8]) -> Result<Decoded, String> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::Indexed);
    let mut decoder = options.read_info(std::io::Cursor::new(bytes)).map_err(|e| e.to_string())?;
    let (w, h) = (decoder.width() as usize, decoder.height() as usize);
    if w.saturating_mul(h) > MAX_PIXELS {
        return Err(format!("{w} x {h} pixels is more than {MAX_PIXELS}"));
    }
    let global: Vec<u8> = decoder.global_palette().map(|p| p.to_vec()).unwrap_or_default();
    let background = decoder.bg_color().unwrap_or(0);
    let frame = decoder.read_next_frame().map_err(|e| e.to_string())?.ok_or("the file holds no image")?;
    let palette = frame.palette.clone().unwrap_or(global);
    let mut indices = vec![background as u8; w * h];
    let (fx, fy, fw) = (frame.left as usize, frame.top as usize, frame.width as usize);
    for (k, i) in frame.buffer.iter().enumerate() {
        let (x, y) = (fx + k % fw.max(1), fy + k / fw.max(1));
        if x < w && y < h {
            indices[y * w + x] = *i;
        }
    }
    let mut d = Decoded { width: w, height: h, rgb: Vec::with_capacity(w * h), heights: Vec::with_capacity(w * h) };
    for i in indices {
        let i = i as usize;
        let c = palette.get(3 * i..3 * i + 3).map_or([0.0; 3], |p| [p[0], p[1], p[2]].map(|v| v as f64 / 255.0));
        d.rgb.push(c);
        d.heights.push(i as f64 / 255.0);
    }
    Ok(d)
}

/// A TGA through `image` (grey, colour and colour-mapped, run-length or not; a colour-mapped
/// one expanded to its colours): grey images give their grey, colour ones red and green as
/// POV-Ray composes them (`colour_height`).
fn decode_tga(bytes: &[u8]) -> Result<Decoded, String> {
    let img = image::load_from_memory_with_format(bytes, image::ImageFormat::Tga).map_err(|e| e.to_string())?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w.saturating_mul(h) > MAX_PIXELS {
        return Err(format!("{w} x {h} pixels is more than {MAX_PIXELS}"));
    }
    let is_grey = matches!(img.color(), image::ColorType::L8 | image::ColorType::La8 | image::ColorType::L16);
    let rgb = img.to_rgb8();
    let mut d = Decoded { width: w, height: h, rgb: Vec::with_capacity(w * h), heights: Vec::with_capacity(w * h) };
    for p in rgb.pixels() {
        let c = p.0.map(|v| v as f64 / 255.0);
        d.heights.push(if is_grey { c[0] } else { colour_height(c, 8) });
        d.rgb.push(c);
    }
    Ok(d)
}

fn decode_jpeg(bytes: &[u8]) -> Result<Decoded, String> {
    let img = image::load_from_memory_with_format(bytes, image::ImageFormat::Jpeg).map_err(|e| e.to_string())?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w.saturating_mul(h) > MAX_PIXELS {
        return Err(format!("{w} x {h} pixels is more than {MAX_PIXELS}"));
    }
    let rgb = img.to_rgb8();
    let mut d = Decoded { width: w, height: h, rgb: Vec::with_capacity(w * h), heights: Vec::with_capacity(w * h) };
    let is_grey = matches!(img.color(), image::ColorType::L8 | image::ColorType::L16);
    for p in rgb.pixels() {
        let c = p.0.map(|v| v as f64 / 255.0);
        d.heights.push(if is_grey { c[0] } else { colour_height(c, 8) });
        d.rgb.push(c);
    }
    Ok(d)
}

/// PGM (P2, P5) and PPM (P3, P6), maxval up to 65535.
fn decode_pnm(bytes: &[u8]) -> Result<Decoded, String> {
    let mut at = 0;
    // The header's tokens, skipping whitespace and # comments.
    let token = |at: &mut usize| -> Option<String> {
        loop {
            while *at < bytes.len() && bytes[*at].is_ascii_whitespace() {
                *at += 1;
            }
            if *at < bytes.len() && bytes[*at] == b'#' {
                while *at < bytes.len() && bytes[*at] != b'\n' {
                    *at += 1;
                }
                continue;
            }
            break;
        }
        let start = *at;
        while *at < bytes.len() && !bytes[*at].is_ascii_whitespace() {
            *at += 1;
        }
        (start < *at).then(|| String::from_utf8_lossy(&bytes[start..*at]).into_owned())
    };
    let magic = token(&mut at).ok_or("no header")?;
    let (channels, binary) = match magic.as_str() {
        "P2" => (1, false),
        "P5" => (1, true),
        "P3" => (3, false),
        "P6" => (3, true),
        m => return Err(format!("`{m}` is not a PGM or PPM header (P2, P3, P5, P6)")),
    };
    let number = |at: &mut usize, what: &str| -> Result<usize, String> {
        token(at).and_then(|t| t.parse::<usize>().ok()).ok_or(format!("the header's {what} is not a number"))
    };
    let w = number(&mut at, "width")?;
    let h = number(&mut at, "height")?;
    let maxval = number(&mut at, "maxval")?;
    if !(1..=65535).contains(&maxval) {
        return Err(format!("maxval {maxval} is not 1 to 65535"));
    }
    if w.saturating_mul(h) > MAX_PIXELS {
        return Err(format!("{w} x {h} pixels is more than {MAX_PIXELS}"));
    }
    let n = w * h * channels;
    let mut samples = Vec::with_capacity(n);
    if binary {
        at += 1; // the one whitespace byte after maxval
        let size = if maxval > 255 { 2 } else { 1 };
        let data = bytes.get(at..at + n * size).ok_or("the file is shorter than its header says")?;
        for i in 0..n {
            samples.push(if size == 2 {
                u16::from_be_bytes([data[2 * i], data[2 * i + 1]]) as usize
            } else {
                data[i] as usize
            });
        }
    } else {
        for _ in 0..n {
            samples.push(number(&mut at, "sample").map_err(|_| "the file is shorter than its header says")?);
        }
    }
    let max = maxval as f64;
    let mut d = Decoded { width: w, height: h, rgb: Vec::with_capacity(w * h), heights: Vec::with_capacity(w * h) };
    for px in samples.chunks(channels) {
        let c = if channels == 1 { [px[0] as f64 / max; 3] } else { [px[0], px[1], px[2]].map(|v| v as f64 / max) };
        let bits = if maxval > 255 { 16 } else { 8 };
        d.heights.push(if channels == 1 { c[0] } else { colour_height(c, bits) });
        d.rgb.push(c);
    }
    Ok(d)
}

/// Heights for a height field, row 0 the image's top, in [0, 1].
pub fn heights(path: &Path, kind: &str) -> Result<Heights, String> {
    let d = decode(path, kind)?;
    Ok(Heights { width: d.width, height: d.height, values: d.heights })
}

/// The image's mean colour in linear RGB (colours decoded from sRGB with the exact curve).
pub fn mean_colour(path: &Path, kind: &str) -> Result<[f64; 3], String> {
    let d = decode(path, kind)?;
    let decode = |v: f64| {
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let mut sum = [0.0; 3];
    for c in &d.rgb {
        for i in 0..3 {
            sum[i] += decode(c[i]);
        }
    }
    let n = d.rgb.len().max(1) as f64;
    Ok(sum.map(|s| s / n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pgm_and_ppm_read_plain_and_binary() {
        let plain = decode_pnm(b"P2\n# a comment\n2 1\n10\n0 10\n").unwrap();
        assert_eq!((plain.width, plain.height), (2, 1));
        assert_eq!(plain.heights, vec![0.0, 1.0]);
        let mut binary = b"P6 1 1 255\n".to_vec();
        binary.extend([255, 0, 0]);
        let d = decode_pnm(&binary).unwrap();
        // Red is the high byte of the height: (255 x 255 + 0) / 65535.
        assert!((d.heights[0] - 255.0 * 255.0 / 65535.0).abs() < 1e-12, "{}", d.heights[0]);
        assert!(decode_pnm(b"P5 2 2 255\n\x00").is_err(), "a short file is an error");
        assert!(decode_pnm(b"P7 1 1 255\n").is_err());
    }
}
