//! Mitsuba scenes (`.xml`, Mitsuba 3 and the 0.5/0.6 dialect): `photonix render scene.xml`,
//! `photonix convert`, `photonix serve`. Like the POV-Ray and glTF front-ends, the file becomes a
//! scene in Photonix's own TOML, which the TOML loader then reads, so every check and default is
//! shared; each TOML entry remembers the XML position it came from, and errors the TOML checks
//! find are reported there.
//!
//! `xml` reads the file (includes, `default` parameters, `$name`), `props` a plugin's properties
//! under their Mitsuba 3 names, `transform` the transforms; `sensor`, `shapes`, `bsdfs`,
//! `textures`, `emitters` and `media` translate one kind of plugin each. docs/mitsuba.md gives
//! the mapping plugin by plugin.

mod bsdfs;
mod emitters;
mod media;
mod out;
mod props;
mod sensor;
mod shapes;
mod textures;
mod transform;
mod xml;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::SceneError;
use out::Out;
use xml::Element;

/// The first words of every translation.
pub const HEADER: &str = "# Translated from the Mitsuba scene";

pub use super::front_end::Pos;

/// An error of the front-end (the one type both translating front-ends use).
pub type MitsubaError = super::front_end::FrontEndError;

/// A Mitsuba scene as TOML text, with where each TOML entry came from.
#[derive(Clone, Debug)]
pub struct Translation {
    pub toml: String,
    /// (first TOML line of an entry, 1-based; the XML position it came from), in line order.
    pub origins: Vec<(usize, Pos)>,
    /// Every file read: the scene, then its includes.
    pub files: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

/// True when `path` names a Mitsuba scene (extension `.xml`, any case).
pub fn is_mitsuba_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// Reads and translates a Mitsuba XML scene.
pub fn translate_file(path: &Path) -> std::result::Result<Translation, SceneError> {
    let mut files = vec![path.to_path_buf()];
    let result = xml::read_scene(path).and_then(|(root, read)| {
        files = read;
        let mut t = Translator::new(&root, &files);
        t.scene(&root)?;
        Ok((t.out, t.warnings))
    });
    match result {
        Ok((out, warnings)) => Ok(Translation { toml: out.text, origins: out.origins, files, warnings }),
        Err(e) => Err(SceneError::Syntax {
            location: location_of(e.pos, &files, path),
            message: crate::limits::printable_message(&e.message),
        }),
    }
}

/// Loads a Mitsuba scene: translates it and loads the TOML as `load_scene` loads a file. An error
/// the TOML checks find is reported at the XML position its entry came from.
pub fn load_mitsuba(path: &Path) -> std::result::Result<super::Scene, SceneError> {
    let t = translate_file(path)?;
    let mut scene = super::parse_scene(&t.toml, path).map_err(|e| relocate(e, &t, path))?;
    let mut warnings = t.warnings.clone();
    warnings.extend(scene.warnings.drain(..).map(|w| relocate_warning(w, &t, path)));
    scene.warnings = warnings;
    Ok(scene)
}

fn location_of(pos: Option<Pos>, files: &[PathBuf], main: &Path) -> String {
    match pos {
        Some(p) => {
            let path = files.get(p.file as usize).map(PathBuf::as_path).unwrap_or(main);
            format!("{}:{}:{}", crate::limits::printable_message(&path.display().to_string()), p.line, p.col)
        }
        None => crate::limits::printable_message(&main.display().to_string()),
    }
}

/// Replaces the `path:line` of a TOML error with the XML position of the entry at that line.
fn relocate(e: SceneError, t: &Translation, path: &Path) -> SceneError {
    match relocate_message(&e.to_string(), t, path) {
        Some((location, tail)) => SceneError::Syntax {
            location,
            message: format!("{tail} (in the scene as translated; `photonix convert` shows it)"),
        },
        None => e,
    }
}

/// A TOML loader's warning, placed at the XML position of its entry.
fn relocate_warning(w: String, t: &Translation, path: &Path) -> String {
    match relocate_message(&w, t, path) {
        Some((location, tail)) => format!("{location}: {tail}"),
        None => w,
    }
}

/// (`file:line:column` of the XML entry, the rest) of a message that starts `path:line[:col]:`.
fn relocate_message(message: &str, t: &Translation, path: &Path) -> Option<(String, String)> {
    let prefix = format!("{}:", crate::limits::printable_message(&path.display().to_string()));
    let rest = message.strip_prefix(&prefix)?;
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    let line = digits.parse::<usize>().ok()?;
    let mut tail = &rest[digits.len()..];
    // A column counts in the TOML text, not in the XML.
    if let Some(after) = tail.strip_prefix(':') {
        let col: String = after.chars().take_while(char::is_ascii_digit).collect();
        if !col.is_empty() {
            tail = &after[col.len()..];
        }
    }
    let origin = t.origins.iter().take_while(|(l, _)| *l <= line).last().map(|(_, p)| *p);
    Some((location_of(origin, &t.files, path), tail.trim_start_matches(':').trim_start().to_string()))
}

/// How a shape's uv relates to Mitsuba's: OBJ files have their v flipped by Mitsuba
/// (`flip_tex_coords`, on by default), other shapes keep it. Textures are written once per kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Uv {
    Flipped,
    AsIs,
}

pub(crate) type Result<T> = std::result::Result<T, MitsubaError>;

/// The translation in progress.
pub(crate) struct Translator<'a> {
    files: &'a [PathBuf],
    ids: HashMap<&'a str, &'a Element>,
    out: Out,
    warnings: Vec<String>,
    /// Materials written, by (element, uv kind, emission).
    materials: HashMap<(usize, Uv, String), String>,
    /// Textures written, by (element, uv kind, use as a scalar).
    textures: HashMap<(usize, Uv, bool), String>,
    media: HashMap<usize, String>,
    /// Mitsuba 0.5/0.6 (`version` below 3): some defaults differ.
    legacy: bool,
    default_material: Option<String>,
    /// Reflective materials Mitsuba shades on their front only (no `twosided`).
    one_sided: Vec<String>,
}

impl<'a> Translator<'a> {
    fn new(root: &'a Element, files: &'a [PathBuf]) -> Translator<'a> {
        let mut ids = HashMap::new();
        collect_ids(root, &mut ids);
        let legacy =
            root.attr("version").and_then(|v| v.split('.').next()?.trim().parse::<u32>().ok()).is_some_and(|m| m < 3);
        Translator {
            files,
            ids,
            out: Out::default(),
            warnings: Vec::new(),
            materials: HashMap::new(),
            textures: HashMap::new(),
            media: HashMap::new(),
            legacy,
            default_material: None,
            one_sided: Vec::new(),
        }
    }

    /// `file:line:column` of a position.
    pub(crate) fn location(&self, pos: Pos) -> String {
        location_of(Some(pos), self.files, self.files.first().map(PathBuf::as_path).unwrap_or(Path::new("")))
    }

    pub(crate) fn warn(&mut self, pos: Pos, message: String) {
        let w = format!("{}: {}", self.location(pos), crate::limits::printable_message(&message));
        self.warnings.push(w);
    }

    /// Warnings for the properties of `p` that nothing read.
    pub(crate) fn finish(&mut self, p: &props::Plugin) {
        let mut w = Vec::new();
        p.unread(&|pos| self.location(pos), &mut w);
        self.warnings.extend(w);
    }

    /// The element a `<ref id="..">` names (or `e` itself), with the tag it must have.
    pub(crate) fn resolve(&self, e: &'a Element, tag: &str) -> Result<&'a Element> {
        if e.tag != "ref" {
            return Ok(e);
        }
        let Some(id) = e.attr("id") else {
            return Err(MitsubaError::at(e.pos, "<ref> needs an `id`".into()));
        };
        let Some(target) = self.ids.get(id) else {
            let mut known: Vec<&str> = self.ids.keys().copied().collect();
            known.sort_unstable();
            let hint = known
                .iter()
                .map(|k| (strsim::levenshtein(k, id), *k))
                .min()
                .filter(|(d, _)| *d <= 3)
                .map(|(_, k)| format!(" (did you mean \"{}\"?)", crate::limits::printable(k)))
                .unwrap_or_default();
            return Err(MitsubaError::at(
                e.pos,
                format!("<ref id=\"{}\">: no element has this id{hint}", crate::limits::printable(id)),
            ));
        };
        if target.tag != tag {
            return Err(MitsubaError::at(
                e.pos,
                format!(
                    "<ref id=\"{}\"> names a <{}>; a <{tag}> is needed here",
                    crate::limits::printable(id),
                    target.tag
                ),
            ));
        }
        Ok(target)
    }

    /// The nested plugins of `p` with this tag, `<ref>`s to such plugins resolved, marked as read.
    pub(crate) fn nested_plugins(&self, p: &props::Plugin<'a>, tag: &str) -> Result<Vec<&'a Element>> {
        let mut out = Vec::new();
        for (i, c) in p.el.children.iter().enumerate() {
            let target = if c.tag == "ref" { self.resolve_any(c)? } else { c };
            if target.tag == tag {
                p.mark(i);
                out.push(target);
            }
        }
        Ok(out)
    }

    /// The element a `<ref>` names, whatever its tag.
    fn resolve_any(&self, e: &'a Element) -> Result<&'a Element> {
        match e.attr("id").and_then(|id| self.ids.get(id)) {
            Some(t) => self.resolve(e, &t.tag),
            None => self.resolve(e, "ref"),
        }
    }

    /// A file name as the TOML gives it: relative to the scene's folder when written in the
    /// scene file itself, else absolute (an include elsewhere). Backslashes of Windows exports
    /// become slashes.
    pub(crate) fn file_name(&self, name: &str, pos: Pos) -> String {
        let name = name.replace('\\', "/");
        if pos.file == 0 || Path::new(&name).is_absolute() {
            return name;
        }
        let folder = self.files.get(pos.file as usize).and_then(|f| f.parent()).unwrap_or(Path::new(""));
        let joined = folder.join(&name);
        std::path::absolute(&joined).unwrap_or(joined).display().to_string()
    }

    fn scene(&mut self, root: &'a Element) -> Result<()> {
        let _ = std::fmt::Write::write_fmt(
            &mut self.out.text,
            format_args!(
                "{HEADER} {} by Photonix (docs/mitsuba.md).\n\n",
                crate::limits::printable(
                    &self.files[0].file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default()
                )
            ),
        );
        // The sensor first: [camera] and [render] lead the file.
        let sensors: Vec<&Element> = root.children.iter().filter(|c| c.tag == "sensor").collect();
        if sensors.len() > 1 {
            self.warn(sensors[1].pos, format!("the scene has {} sensors; the first is used", sensors.len()));
        }
        let integrator = root.children.iter().find(|c| c.tag == "integrator");
        self.sensor(sensors.first().copied(), integrator, root.pos)?;
        for child in &root.children {
            match child.tag.as_str() {
                "shape" => self.shape(child)?,
                "emitter" => self.emitter(child)?,
                "sensor" | "integrator" | "default" => {}
                // Declared for `ref`s; translated where they are used.
                "bsdf" | "texture" | "medium" | "phase" | "rfilter" | "sampler" | "film" => {
                    if child.attr("id").is_none() {
                        self.warn(child.pos, format!("<{}> without an `id` is never used; it is ignored", child.tag));
                    }
                }
                other => self.warn(
                    child.pos,
                    format!("<{}> is not read by Photonix and is ignored", crate::limits::printable(other)),
                ),
            }
        }
        if !self.one_sided.is_empty() {
            let n = self.one_sided.len();
            let names = self.one_sided.iter().take(3).map(|s| format!("\"{s}\"")).collect::<Vec<_>>().join(", ");
            self.warn(
                root.pos,
                format!(
                    "{n} material(s) ({names}{}) have no <bsdf type=\"twosided\">: Mitsuba shades their back faces black, \
                     Photonix shades both sides alike",
                    if n > 3 { ", ..." } else { "" }
                ),
            );
        }
        Ok(())
    }
}

fn collect_ids<'a>(e: &'a Element, ids: &mut HashMap<&'a str, &'a Element>) {
    for c in &e.children {
        if let (Some(id), false) = (c.attr("id"), c.tag == "ref") {
            ids.entry(id).or_insert(c);
        }
        collect_ids(c, ids);
    }
}
