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
    #[error(
        "{path} is {what}, not an EXR; diff and merge read the EXR files (linear radiance) that `photonix render -o \
         NAME.exr` writes"
    )]
    NotExr { path: PathBuf, what: &'static str },
    #[error(
        "{path} is {width}x{height}, more than the {} pixels photonix reads (see docs/limits.md)",
        crate::limits::MAX_PIXELS
    )]
    TooLarge { path: PathBuf, width: usize, height: usize },
    #[error("exposure {exposure} is not a finite number of stops; the image would be black or white")]
    BadExposure { exposure: f32 },
    #[error("{path} is {what} too; writing it would overwrite that file, so give another name")]
    Overwrites { path: PathBuf, what: String },
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
    check_not_read_only(path)?;
    let probe = temp_path_for(path);
    std::fs::write(&probe, b"")
        .map_err(|e| ImageError::NotWritable { path: path.to_owned(), reason: e.to_string() })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Whether `a` and `b` name the same file: the same inode when both exist (hard links too), else
/// the same resolved path. A path that does not exist yet resolves through its parent folder, so
/// `out.png` and `./dir/../out.png` compare equal before either is written.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    match (resolve(a), resolve(b)) {
        (Some(a), Some(b)) => a == b,
        _ => false,
    }
}

/// `path` made absolute with symbolic links resolved, through its parent when it does not exist.
fn resolve(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = std::fs::canonicalize(path) {
        return Some(p);
    }
    let name = path.file_name()?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    Some(std::fs::canonicalize(parent).ok()?.join(name))
}

/// Refuses to write `output` when it is the same file as `input` (`what` names the input in the
/// message: "the scene file", "input 2 of the merge").
pub fn check_not_overwriting(output: &Path, input: &Path, what: &str) -> Result<(), ImageError> {
    if same_file(output, input) {
        return Err(ImageError::Overwrites { path: output.to_owned(), what: what.to_string() });
    }
    Ok(())
}

/// Refuses to write `output` when it is one of `inputs`, the files a scene read
/// (`Scene::inputs`: textures, environment maps, models and what they name, voxel grids).
pub fn check_not_input(output: &Path, inputs: &[PathBuf]) -> Result<(), ImageError> {
    for input in inputs {
        if same_file(output, input) {
            return Err(ImageError::Overwrites {
                path: output.to_owned(),
                what: format!("{}, a file the scene reads,", input.display()),
            });
        }
    }
    Ok(())
}

/// Refuses to replace a file the user made read-only: renaming over it would succeed (only the
/// folder's permissions matter) where the shell's `>` would fail.
fn check_not_read_only(path: &Path) -> Result<(), ImageError> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() && meta.permissions().readonly() => Err(ImageError::NotWritable {
            path: path.to_owned(),
            reason: "the file is read-only; make it writable (chmod u+w) or give another name".into(),
        }),
        _ => Ok(()),
    }
}

/// Refuses what is not an EXR before the EXR reader sees it (it would say "file identifier
/// missing" about a PNG), and EXR files larger than `limits::MAX_PIXELS`, before allocating them.
pub fn check_exr_input(path: &Path) -> Result<(), ImageError> {
    use std::io::Read;
    let read_error = |e: std::io::Error| ImageError::Read { path: path.to_owned(), reason: e.to_string() };
    let mut magic = [0u8; 4];
    let mut file = std::fs::File::open(path).map_err(read_error)?;
    let n = file.read(&mut magic).map_err(read_error)?;
    let what = match &magic[..n] {
        [0x76, 0x2f, 0x31, 0x01] => None,
        [0x89, b'P', b'N', b'G'] => Some("a PNG image"),
        [0xff, 0xd8, ..] => Some("a JPEG image"),
        [] => Some("empty"),
        _ => Some("not an image photonix knows"),
    };
    if let Some(what) = what {
        return Err(ImageError::NotExr { path: path.to_owned(), what });
    }
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| ImageError::Read { path: path.to_owned(), reason: e.to_string() })?;
    let mut bytes = 0u64;
    for header in meta.headers.iter() {
        let sizes = [header.layer_size, header.shared_attributes.display_window.size];
        for size in sizes {
            if (size.width() as u64).saturating_mul(size.height() as u64) > crate::limits::MAX_PIXELS {
                return Err(ImageError::TooLarge { path: path.to_owned(), width: size.width(), height: size.height() });
            }
        }
        // Decoded samples (4 bytes each, whatever the file's type) and our copy of them.
        let pixels = header.layer_size.width() as u64 * header.layer_size.height() as u64;
        bytes += 2 * 4 * pixels * header.channels.list.len() as u64;
    }
    if let Some(available) = crate::render::memory::available_host_memory().filter(|&a| bytes > a) {
        return Err(ImageError::Read {
            path: path.to_owned(),
            reason: format!(
                "reading it needs about {} of memory but {} is available",
                crate::limits::fmt_bytes(bytes),
                crate::limits::fmt_bytes(available)
            ),
        });
    }
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
    if !exposure.is_finite() {
        return Err(ImageError::BadExposure { exposure });
    }
    match format_of(path)? {
        Format::Exr => write_atomically(path, |tmp| write_exr(tmp, image)),
        Format::Png => write_atomically(path, |tmp| write_png(tmp, image, exposure)),
    }
}

/// Runs `write` on a temporary file next to `path`, then renames it into place; on failure the
/// temporary file is removed and `path` is untouched. A read-only `path` is refused; a file it
/// replaces keeps its permissions.
pub fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), ImageError> {
    check_not_read_only(path)?;
    let old_permissions = std::fs::metadata(path).ok().filter(|m| m.is_file()).map(|m| m.permissions());
    let tmp = temp_path_for(path);
    let finished = write(&tmp)
        .and_then(|()| match old_permissions {
            Some(p) => std::fs::set_permissions(&tmp, p).map_err(|e| e.to_string()),
            None => Ok(()),
        })
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
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
    check_exr_input(path)?;
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
    fn same_file_sees_through_names_links_and_missing_files() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.png");
        std::fs::write(&a, b"x").unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        assert!(same_file(&a, &dir.path().join("sub/../a.png")));
        std::fs::hard_link(&a, dir.path().join("hard.png")).unwrap();
        assert!(same_file(&a, &dir.path().join("hard.png")));
        std::os::unix::fs::symlink(&a, dir.path().join("soft.png")).unwrap();
        assert!(same_file(&dir.path().join("soft.png"), &a));
        // Neither exists yet: compared through their folders.
        let (x, y) = (dir.path().join("new.png"), dir.path().join("sub/../new.png"));
        assert!(same_file(&x, &y));
        assert!(!same_file(&x, &a));
        assert!(!same_file(&dir.path().join("missing/new.png"), &x));
    }

    #[test]
    fn non_exr_inputs_are_named_for_what_they_are() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("a.png");
        write_image(&png, &Image::new(2, 2), 0.0).unwrap();
        let e = read_exr(&png).unwrap_err().to_string();
        assert!(e.contains("is a PNG image, not an EXR"), "{e}");
        let empty = dir.path().join("e.exr");
        std::fs::write(&empty, b"").unwrap();
        assert!(read_exr(&empty).unwrap_err().to_string().contains("is empty, not an EXR"));
        assert!(write_image(&png, &Image::new(2, 2), f32::NAN).is_err());
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
