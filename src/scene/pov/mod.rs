//! A front-end for POV-Ray's scene description language (3.7): `photonix render scene.pov`.
//!
//! The language is evaluated here (`lexer`, `parser`: directives, expressions, macros, loops,
//! includes) into POV-Ray's objects (`ast`), which `emit` writes as a scene in Photonix's own TOML
//! format (docs/scene-format.md). The TOML is then loaded by the same code as any `.toml` file,
//! so every check, default and the renderer are shared; each TOML entry remembers the `.pov`
//! position it came from, and errors found in the TOML are reported there. docs/pov-ray.md
//! describes what is read and how POV-Ray's shading maps onto physics.

mod ast;
mod emit;
mod image;
mod implicit;
mod ini;
mod lexer;
mod measure;
mod objects;
mod parser;
mod tessellate;
mod ttf;

use std::path::{Path, PathBuf};

use super::SceneError;

pub use ini::{ini_path, options_for, Given};

/// POV-Ray's standard include folder as Debian's `povray-includes` installs it.
pub const STANDARD_INCLUDE_DIR: &str = "/usr/share/povray-3.7/include";

pub use super::front_end::Pos;

/// An error of the front-end (the one type both translating front-ends use).
pub type PovError = super::front_end::FrontEndError;

/// What POV-Ray takes from its command line: the image size (`image_width`, `image_height`)
/// and the animation clock.
#[derive(Clone, Debug)]
pub struct PovOptions {
    pub width: u32,
    pub height: u32,
    pub clock: f64,
    /// `frame_number`, and the animation's `initial_frame` and `final_frame` (0, 0, 0 for a
    /// still; `--frame` and the scene's `.ini`, `ini::options_for`).
    pub frame: i64,
    pub initial_frame: i64,
    pub final_frame: i64,
    /// Folders searched for `#include` after the scene's own folder.
    pub include_dirs: Vec<PathBuf>,
}

impl Default for PovOptions {
    fn default() -> PovOptions {
        // 320x240 is the size of POV-Ray's own quick renders; `--resolution` overrides it.
        PovOptions {
            width: 320,
            height: 240,
            clock: 0.0,
            frame: 0,
            initial_frame: 0,
            final_frame: 0,
            include_dirs: vec![PathBuf::from(STANDARD_INCLUDE_DIR)],
        }
    }
}

/// A `.pov` scene as TOML text, with where each TOML entry came from.
#[derive(Clone, Debug)]
pub struct Translation {
    pub toml: String,
    /// (first TOML line of an entry, 1-based; the `.pov` position it came from), in line order.
    pub origins: Vec<(usize, Pos)>,
    /// Every file read: the scene, then its includes in the order they were first read.
    pub files: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

impl Translation {
    /// `file:line:column` of a position.
    pub fn location(&self, pos: Pos) -> String {
        let path = self.files.get(pos.file as usize).map(|p| p.display().to_string()).unwrap_or_default();
        format!("{}:{}:{}", crate::limits::printable_message(&path), pos.line, pos.col)
    }

    /// The `.pov` position of the entry that holds TOML line `line`.
    pub fn origin_of_line(&self, line: usize) -> Option<Pos> {
        self.origins.iter().take_while(|(l, _)| *l <= line).last().map(|(_, p)| *p)
    }
}

/// Stack of the thread the front-end runs on: the evaluator recurses per nesting level (about
/// 8 KiB per level of brackets in a release build), and its limits (`parser::MAX_NESTING`,
/// `MAX_EXPRESSION_DEPTH`, `MAX_VALUE_DEPTH`, 256 each) need a few MiB at most. Run on its own
/// thread, a scene gets that whatever thread asked (tokio's 2 MiB threads in `serve`); the
/// stack is reserved, and only what is used is ever touched.
const PARSER_STACK_BYTES: usize = 64 << 20;

/// Reads, evaluates and translates a `.pov` file, on a thread of its own with a known stack
/// (`PARSER_STACK_BYTES`); the files it reads pass the caller's file gate and are recorded there.
pub fn translate_file(path: &Path, options: &PovOptions) -> Result<Translation, SceneError> {
    let (confine, also) = super::files::current_rules();
    let (result, read) = std::thread::scope(|s| {
        let run = || {
            let also: Vec<&Path> = also.iter().map(PathBuf::as_path).collect();
            super::files::collect_allowing(confine.as_deref(), &also, || translate_here(path, options))
        };
        let thread = std::thread::Builder::new()
            .name("pov-front-end".into())
            .stack_size(PARSER_STACK_BYTES)
            .spawn_scoped(s, run);
        let thread = match thread {
            Ok(t) => t,
            Err(cause) => return (Err(SceneError::Read { path: path.to_path_buf(), cause }), Vec::new()),
        };
        match thread.join() {
            Ok(done) => done,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    });
    super::files::record(&read);
    result
}

fn translate_here(path: &Path, options: &PovOptions) -> Result<Translation, SceneError> {
    let mut p = parser::Parser::new(path, options.clone());
    let result = p.run_file(path).and_then(|scene| emit::emit(&scene, options, &p.files));
    match result {
        Ok((toml, origins, mut emitted)) => {
            let mut warnings = p.scene.warnings.clone();
            warnings.append(&mut p.warnings);
            warnings.append(&mut emitted);
            Ok(Translation { toml, origins, files: p.files.clone(), warnings })
        }
        Err(e) => Err(to_scene_error(&e, &p.files, path)),
    }
}

fn to_scene_error(e: &PovError, files: &[PathBuf], main: &Path) -> SceneError {
    let location = match e.pos {
        Some(pos) => {
            let path = files.get(pos.file as usize).map(PathBuf::as_path).unwrap_or(main);
            format!("{}:{}:{}", crate::limits::printable_message(&path.display().to_string()), pos.line, pos.col)
        }
        None => crate::limits::printable_message(&main.display().to_string()),
    };
    SceneError::Syntax { location, message: crate::limits::printable_message(&e.message) }
}

/// Loads a `.pov` scene: translates it and loads the TOML as `load_scene` loads a file. An error
/// the TOML checks find is reported at the `.pov` position its entry came from.
/// Every file the translation read (includes, height fields, fonts) is one of the scene's
/// inputs, which no command may write over, as are the files the TOML names.
pub fn load_pov(path: &Path, options: &PovOptions) -> Result<super::Scene, SceneError> {
    let (t, read) = super::files::collect(None, || translate_file(path, options));
    let t = t?;
    let mut scene = super::parse_scene(&t.toml, path).map_err(|e| relocate(e, &t, path))?;
    for file in read {
        if !scene.inputs.contains(&file) {
            scene.inputs.push(file);
        }
    }
    scene.warnings.extend(t.warnings);
    Ok(scene)
}

/// Replaces the `path:line` (or `path:line:column`) of a TOML error with the `.pov` position of
/// the entry at that line, and says that the field names are those of the translated scene.
fn relocate(e: SceneError, t: &Translation, path: &Path) -> SceneError {
    let prefix = format!("{}:", crate::limits::printable_message(&path.display().to_string()));
    let message = e.to_string();
    let Some(rest) = message.strip_prefix(&prefix) else { return e };
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    let Ok(line) = digits.parse::<usize>() else { return e };
    let mut tail = &rest[digits.len()..];
    // Drop a column: it counts in the TOML text, not in the .pov file.
    if let Some(after) = tail.strip_prefix(':') {
        let col: String = after.chars().take_while(char::is_ascii_digit).collect();
        if !col.is_empty() {
            tail = &after[col.len()..];
        }
    }
    let location = match t.origin_of_line(line) {
        Some(pos) => t.location(pos),
        None => format!("{}", path.display()),
    };
    let tail = tail.trim_start_matches(':').trim_start();
    SceneError::Syntax {
        location,
        message: format!("{tail} (in the scene as translated; `photonix convert` shows it)"),
    }
}

/// True when `path` names a POV-Ray scene (extension `.pov`, any case).
pub fn is_pov_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("pov"))
}
