//! POV-Ray's `.ini` options beside a scene (`scene.ini` for `scene.pov`): the image size and the
//! animation's frames and clock, which the scene reads as `image_width`, `frame_number`,
//! `clock`, ... (POV-Ray's portfolio scenes are animations whose first frame is 1, and index
//! arrays at `frame_number - 1`). Everything else in the file (antialiasing, output) is
//! POV-Ray's rendering and is not read.

use std::path::{Path, PathBuf};

use super::PovOptions;
use crate::scene::SceneError;

/// The largest `.ini` file read: POV-Ray's are a few KiB.
const MAX_INI_BYTES: u64 = 1 << 20;

/// What the command line gives for a POV-Ray scene (`--frame`, `--clock`, `--resolution`); each
/// overrides the `.ini`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Given {
    pub frame: Option<i64>,
    pub clock: Option<f64>,
    pub resolution: Option<(u32, u32)>,
}

/// The `.ini` file that goes with a scene: the scene's name with `.ini`, when it exists.
pub fn ini_path(scene: &Path) -> Option<PathBuf> {
    let p = scene.with_extension("ini");
    p.is_file().then_some(p)
}

/// POV-Ray's options for a scene: its `.ini` (when there is one) under what the command line
/// gives. The clock of frame f of an animation runs from Initial_Clock at Initial_Frame to
/// Final_Clock at Final_Frame, as POV-Ray steps it; without frames it is `Clock` (default 0).
pub fn options_for(scene: &Path, given: Given) -> Result<PovOptions, SceneError> {
    let mut o = PovOptions::default();
    let mut ini = Ini::default();
    if let Some(path) = ini_path(scene) {
        ini = read_ini(&path)?;
    }
    if let Some(w) = ini.width {
        o.width = w;
    }
    if let Some(h) = ini.height {
        o.height = h;
    }
    if let Some((w, h)) = given.resolution {
        (o.width, o.height) = (w, h);
    }
    let first = ini.initial_frame.unwrap_or(0);
    let last = ini.final_frame.unwrap_or(first);
    o.initial_frame = first;
    o.final_frame = last.max(first);
    o.frame = given.frame.unwrap_or(first);
    let (c0, c1) = (ini.initial_clock.unwrap_or(0.0), ini.final_clock.unwrap_or(1.0));
    o.clock = match given.clock {
        Some(c) => c,
        None if o.final_frame > o.initial_frame => {
            c0 + (c1 - c0) * (o.frame - o.initial_frame) as f64 / (o.final_frame - o.initial_frame) as f64
        }
        None => ini.clock.unwrap_or(c0),
    };
    Ok(o)
}

#[derive(Default)]
struct Ini {
    width: Option<u32>,
    height: Option<u32>,
    initial_frame: Option<i64>,
    final_frame: Option<i64>,
    initial_clock: Option<f64>,
    final_clock: Option<f64>,
    clock: Option<f64>,
}

fn read_ini(path: &Path) -> Result<Ini, SceneError> {
    let read_error = |cause| SceneError::Read { path: path.to_path_buf(), cause };
    let size = std::fs::metadata(path).map_err(read_error)?.len();
    if size > MAX_INI_BYTES {
        return Err(SceneError::Syntax {
            location: path.display().to_string(),
            message: format!("this .ini file is {size} bytes; POV-Ray's options files are read up to {MAX_INI_BYTES}"),
        });
    }
    let bytes = std::fs::read(path).map_err(read_error)?;
    let text = String::from_utf8_lossy(&bytes);
    let mut ini = Ini::default();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split(';').next().unwrap_or("").trim();
        let bad = |what: &str| SceneError::Syntax {
            location: format!("{}:{}", path.display(), n + 1),
            message: format!("{what}: expected a number"),
        };
        // Switches: +W200 +H150 (and several on a line).
        if line.starts_with('+') || line.starts_with('-') {
            for word in line.split_whitespace() {
                let (key, value) = word.split_at(word.len().min(2));
                match key.to_ascii_lowercase().as_str() {
                    "+w" => ini.width = Some(value.parse().map_err(|_| bad(word))?),
                    "+h" => ini.height = Some(value.parse().map_err(|_| bad(word))?),
                    "+k" if value.starts_with(['f', 'F']) => {
                        ini.final_frame = Some(value[1..].parse().map_err(|_| bad(word))?)
                    }
                    "+k" if value.starts_with(['i', 'I']) => {
                        ini.initial_frame = Some(value[1..].parse().map_err(|_| bad(word))?)
                    }
                    "+k" => ini.clock = Some(value.parse().map_err(|_| bad(word))?),
                    _ => {}
                }
            }
            continue;
        }
        let Some((key, value)) = line.split_once('=') else { continue };
        let (key, value) = (key.trim().to_ascii_lowercase(), value.trim());
        let int = || value.parse::<i64>().map_err(|_| bad(&key));
        let float = || value.parse::<f64>().map_err(|_| bad(&key));
        match key.as_str() {
            "width" => ini.width = Some(value.parse().map_err(|_| bad(&key))?),
            "height" => ini.height = Some(value.parse().map_err(|_| bad(&key))?),
            "initial_frame" => ini.initial_frame = Some(int()?),
            "final_frame" => ini.final_frame = Some(int()?),
            "initial_clock" => ini.initial_clock = Some(float()?),
            "final_clock" => ini.final_clock = Some(float()?),
            "clock" => ini.clock = Some(float()?),
            _ => {}
        }
    }
    Ok(ini)
}
