//! The documented range of every number a user gives (flags and scene fields), in one place;
//! `docs/limits.md` lists the same numbers and says why each one is there. Also the helpers that
//! keep messages readable whatever the input: numbers in a bounded number of digits, names with
//! their control characters escaped and their length cut.

use std::io::Read;
use std::path::Path;

/// Largest image side, in pixels (flags and `resolution`).
pub const MAX_IMAGE_SIDE: u32 = 65536;
/// Largest image, in pixels: 2^28 (16384 x 16384). Pixel indices times the 4 layers then fit the
/// 32-bit indices the kernels use.
pub const MAX_PIXELS: u64 = 1 << 28;
/// Largest samples per pixel of one pass. With `MAX_PASSES` the sample indices (pass * spp +
/// sample) stay below 2^32, the range of the random streams' sample key.
pub const MAX_SPP: u32 = 4096;
/// Most progressive passes, and the largest end of a `--pass-range`.
pub const MAX_PASSES: u32 = 1_000_000;
/// Most surfaces a camera or photon path visits (`max_depth`, `--photon-depth`); keeps the random
/// dimensions of a path inside their domain.
pub const MAX_DEPTH: u32 = 1024;
/// Narrowest reconstruction filter, in pixels from a pixel's centre (`filter_radius`): a
/// narrower one leaves most of each pixel unsampled.
pub const MIN_FILTER_RADIUS: f32 = 0.1;
/// Widest reconstruction filter: a light-tracing splat visits (2 x radius + 1)^2 pixels, at most
/// 169, within lavapipe's loop limit on deep light paths.
pub const MAX_FILTER_RADIUS: f32 = 6.0;
/// Most final-gather rays per camera sample.
pub const MAX_GATHER_RAYS: u32 = 1024;
/// Most photon paths per map and pass.
pub const MAX_PHOTON_PATHS: u32 = 1_000_000_000;
/// Most instances of objects in a scene, nested placements and grids counted out: each takes
/// a record of 112 bytes and a node of the top-level BVH.
pub const MAX_INSTANCES: u32 = 1 << 20;
/// Largest magnitude of a coordinate, a length or a colour in a scene, after transforms: products
/// of two (areas) and sums of many (light power) then stay finite in 32-bit floats.
pub const MAX_SCENE_VALUE: f64 = 1e9;
/// Largest absorption, scattering or extinction coefficient of a medium, per scene unit: a
/// mean free path of 1e-6 scene units, far below anything a render resolves, keeps
/// sigma_t * distance finite in 32-bit floats over the whole scene range.
pub const MAX_MEDIUM_COEFFICIENT: f32 = 1e6;
/// Smallest sphere radius, in scene units (its square stays a normal f32).
pub const MIN_SPHERE_RADIUS: f64 = 1e-9;
/// Largest index of refraction, and the smallest is its inverse.
pub const MAX_IOR: f64 = 100.0;
/// Vertical field of view in degrees: at least this much, and at most 180 minus this much.
pub const MIN_FOV_DEGREES: f64 = 0.01;
/// Most blades of a polygonal lens aperture (`aperture_blades`; 0 is round, else at least 3).
pub const MAX_APERTURE_BLADES: u32 = 64;
/// Largest spot light `tightness` (the exponent of cos): cos^1000 is 0.6 at 1 degree, a beam.
pub const MAX_SPOT_TIGHTNESS: f64 = 1000.0;
/// Cells along each side of an area light's POV-Ray grid (`samples = [n, m]`).
pub const MAX_LIGHT_GRID: u32 = 64;
/// Most texels of an environment map as the renderer uses it (2048 x 1024); a larger map is
/// halved until it fits: the map, its cdfs and the scene's other data share one storage buffer
/// (128 MiB on lavapipe).
pub const MAX_ENVIRONMENT_TEXELS: u64 = 2048 * 1024;
/// Largest `--exposure` magnitude (stops).
pub const MAX_EXPOSURE: f32 = 64.0;
/// Largest `--target-error` (relMSE).
pub const MAX_TARGET_ERROR: f64 = 1000.0;
/// Longest `--time` or `--checkpoint-every`: one year, in seconds.
pub const MAX_DURATION_SECONDS: f64 = 365.0 * 24.0 * 3600.0;
/// Shortest `--time` or `--checkpoint-every`: one millisecond.
pub const MIN_DURATION_SECONDS: f64 = 1e-3;
/// Largest scene file read.
pub const MAX_SCENE_FILE_BYTES: u64 = 64 << 20;
/// Largest OBJ file read.
pub const MAX_OBJ_FILE_BYTES: u64 = 256 << 20;
/// Largest model file (OBJ, PLY, glTF, 3DS, IFS, BPT) read, in bytes; also each MTL file and glTF buffer.
pub const MAX_MODEL_FILE_BYTES: u64 = MAX_OBJ_FILE_BYTES;
/// Smallest Bezier patch flatness tolerance, relative to the patch: finer asks for more than
/// `MAX_PATCH_STEPS` per side anyway.
pub const MIN_PATCH_FLATNESS: f64 = 1e-6;
/// Longest name (material, shape, texture, unknown field) echoed in a message, in characters.
pub const MAX_ECHOED_CHARS: usize = 64;

/// Largest image file (texture, environment map, glTF image, POV-Ray height field) read, in
/// bytes: a 16384 x 16384 RGBA EXR of half floats, uncompressed, is 2 GiB.
pub const MAX_IMAGE_FILE_BYTES: u64 = 2 << 30;
/// Largest voxel file (PXVOL1) read: its largest grid (2^24 floats) and the header, with room.
pub const MAX_VOXEL_FILE_BYTES: u64 = (64 << 20) + 4096;
/// Largest TrueType font a POV-Ray `text` object reads (the largest CJK fonts are about 30 MiB).
pub const MAX_FONT_FILE_BYTES: u64 = 64 << 20;

/// Reads at most `limit` bytes of `path`, which must be a regular file (followed through links):
/// a device (`/dev/zero`), a pipe or a folder is refused unopened, as `Err(Some(error))`, since
/// opening a pipe waits for a writer and a device may never end. A file larger than `limit` by
/// its size is `Err(None)`, unread; one that grows while it is read is cut at `limit + 1` bytes
/// and refused the same way. A failure to read is `Err(Some(error))`.
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, Option<std::io::Error>> {
    let size = regular_file_size(path).map_err(Some)?;
    if size > limit {
        return Err(None);
    }
    let file = std::fs::File::open(path).map_err(Some)?;
    let mut bytes = Vec::with_capacity(size as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(Some)?;
    if bytes.len() as u64 > limit {
        return Err(None);
    }
    Ok(bytes)
}

/// The size of `path` in bytes when it is a regular file (links followed); an error that says
/// what it is otherwise.
pub fn regular_file_size(path: &Path) -> std::io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        return Ok(meta.len());
    }
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    let what = if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a pipe (FIFO)"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else {
        "not a file"
    };
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("it is {what}, not a regular file; photonix reads only regular files"),
    ))
}

/// A number as a message shows it: plain when it reads well (`0.25`, `1500`), else in exponent
/// form (`1e300`, `2.5e-12`), never hundreds of digits.
pub fn fmt_number(v: f64) -> String {
    let plain = v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs());
    if plain {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `fmt_number` for a 32-bit float, in its own shortest digits (1e-12, not 9.99999996e-13).
pub fn fmt_f32(v: f32) -> String {
    let plain = v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs());
    if plain {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `text` with every number of more than 15 digits (as parsers quote `1e300`: a 1 and 300
/// zeros) rewritten by `fmt_number`.
pub fn shorten_numbers(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < bytes.len() {
        if !bytes[i].is_ascii_digit() {
            let next = text[i..].chars().next().map_or(1, char::len_utf8);
            out.push_str(&text[i..i + next]);
            i += next;
            continue;
        }
        let start = i;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
            i += 1;
        }
        let number = &text[start..i];
        let digits = number.bytes().filter(u8::is_ascii_digit).count();
        match number.trim_end_matches('.').parse::<f64>() {
            Ok(v) if digits > 15 => {
                out.push_str(&fmt_number(v));
                if number.ends_with('.') {
                    out.push('.');
                }
            }
            _ => out.push_str(number),
        }
    }
    out
}

/// A bytes count in a unit that reads well: `512 B`, `3.2 MiB`, `1.5 TiB`.
pub fn fmt_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["KiB", "MiB", "GiB", "TiB", "PiB"];
    if bytes < 1024 {
        return format!("{bytes} B");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    format!("{value:.1} {}", UNITS[unit])
}

/// A name from the user, safe to print: control characters escaped (`\n`, `\u{1b}`), and cut to
/// `MAX_ECHOED_CHARS` characters with the number of characters left out.
pub fn printable(name: &str) -> String {
    let mut out = String::new();
    for (count, c) in name.chars().enumerate() {
        if count == MAX_ECHOED_CHARS {
            let rest = name.chars().count() - count;
            out.push_str(&format!("... ({rest} more characters)"));
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// Escapes the control characters of a whole message, except line breaks: what `main` prints.
pub fn printable_message(message: &str) -> String {
    message
        .chars()
        .flat_map(|c| {
            let escaped: Vec<char> = if c.is_control() && c != '\n' { c.escape_default().collect() } else { vec![c] };
            escaped
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_never_print_hundreds_of_digits() {
        assert_eq!(fmt_number(0.25), "0.25");
        assert_eq!(fmt_number(1500.0), "1500");
        assert_eq!(fmt_number(-2.0), "-2");
        assert_eq!(fmt_number(0.0), "0");
        assert_eq!(fmt_number(1e300), "1e300");
        assert_eq!(fmt_number(-2.5e-12), "-2.5e-12");
        assert_eq!(fmt_number(f64::NAN), "NaN");
        assert_eq!(fmt_number(f64::MAX).len(), "1.7976931348623157e308".len());
        let quoted = format!("invalid type: floating point `-{}.0`, expected an integer", "1".repeat(300));
        let short = shorten_numbers(&quoted);
        assert!(short.contains("`-1.1111111111111112e299`"), "{short}");
        assert_eq!(shorten_numbers("line 12, 4294967296 and 3.5"), "line 12, 4294967296 and 3.5");
    }

    #[test]
    fn names_are_escaped_and_cut() {
        assert_eq!(printable("wall"), "wall");
        assert_eq!(printable("a\u{1b}[31mb\n"), "a\\u{1b}[31mb\\n");
        let long = "k".repeat(1_000_000);
        let shown = printable(&long);
        assert!(shown.len() < 120 && shown.ends_with("(999936 more characters)"), "{shown}");
        assert_eq!(printable_message("x\u{7}y\nz"), "x\\u{7}y\nz");
    }

    #[test]
    fn bytes_read_well() {
        assert_eq!(fmt_bytes(100), "100 B");
        assert_eq!(fmt_bytes(3 << 20), "3.0 MiB");
        assert_eq!(fmt_bytes(3 << 40), "3.0 TiB");
    }

    #[test]
    fn only_regular_files_of_at_most_the_limit_are_read() {
        let limit = 1 << 16;
        for device in ["/dev/zero", "/dev/null", "/tmp"] {
            let e = read_limited(Path::new(device), limit).unwrap_err().expect("refused as what it is");
            assert!(e.to_string().contains("not a regular file"), "{device}: {e}");
        }
        assert!(matches!(read_limited(Path::new("/nonexistent/x"), limit), Err(Some(_))));
        let dir = tempfile::tempdir().unwrap();
        let sparse = dir.path().join("sparse");
        std::fs::File::create(&sparse).unwrap().set_len(1 << 40).unwrap();
        assert!(matches!(read_limited(&sparse, limit), Err(None)));
        std::fs::write(&sparse, b"abc").unwrap();
        assert_eq!(read_limited(&sparse, 3).unwrap(), b"abc");
    }
}
