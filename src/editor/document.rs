//! The scene the editor holds: the file's text as a `toml_edit` document (so comments and
//! formatting survive every edit and the save), the `Scene` parsed from it, and the undo and
//! redo stacks. An edit is a small command applied to the document; the result is parsed by
//! the same code as any scene file (`scene::parse_scene_with_origins`), and an edit the parser
//! refuses changes nothing.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use serde_json::Value as Json;
use toml_edit::{DocumentMut, Item, Table, TableLike, Value};

use crate::scene::{parse_scene_in, Scene, SceneOrigins};

/// Undo steps kept; older ones are dropped.
const MAX_UNDO: usize = 200;
/// Array nesting accepted in an edit's value (a colour map is two deep).
const MAX_VALUE_DEPTH: usize = 4;
/// Longest string an edit may carry.
const MAX_STRING_BYTES: usize = 4096;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum EditError {
    /// The edited text is not a valid scene; the message is the parser's, file:line and all.
    #[error("{0}")]
    Invalid(String),
    /// The command itself is malformed: bad target, field or value.
    #[error("{0}")]
    Command(String),
    #[error("nothing to undo")]
    NothingToUndo,
    #[error("nothing to redo")]
    NothingToRedo,
}

fn bad(message: impl Into<String>) -> EditError {
    EditError::Command(message.into())
}

/// What an edit applies to.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Target {
    /// Entry of `[[shapes]]`, from 0 in file order.
    Shape(usize),
    /// Entry of `[[lights]]`, from 0 in file order.
    Light(usize),
    /// Entry of `[[instances]]`, from 0 in file order.
    Instance(usize),
    /// The `[[shapes]]` entry of this stable id (`id` in the page's scene): it names the same
    /// entry whatever is added or deleted before it, so one tab's delete never moves another
    /// tab's edit onto the next entry.
    ShapeId(u64),
    LightId(u64),
    InstanceId(u64),
    /// `[materials.<name>]`.
    Material(String),
    Camera,
    Render,
    Photons,
    Environment,
}

impl Target {
    fn describe(&self) -> String {
        match self {
            Target::Shape(i) => format!("shape {i}"),
            Target::Light(i) => format!("light {i}"),
            Target::Instance(i) => format!("instance {i}"),
            Target::ShapeId(id) => format!("shape of id {id}"),
            Target::LightId(id) => format!("light of id {id}"),
            Target::InstanceId(id) => format!("instance of id {id}"),
            Target::Material(name) => format!("material \"{}\"", crate::limits::printable(name)),
            Target::Camera => "[camera]".into(),
            Target::Render => "[render]".into(),
            Target::Photons => "[photons]".into(),
            Target::Environment => "[environment]".into(),
        }
    }
}

/// A scale: one number (uniform) or one per axis.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f64),
    Axes([f64; 3]),
}

/// What `add` adds.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    Shape,
    Light,
    Material,
}

/// One edit, as the page sends it (JSON, `op` names the command).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum Command {
    /// Sets the `transform` of a shape, an area light or an instance; parts left out keep
    /// their value.
    SetTransform {
        target: Target,
        translate: Option<[f64; 3]>,
        rotate: Option<[f64; 3]>,
        scale: Option<Scale>,
    },
    /// Sets one field of a table (`null` removes it), e.g. a material's `reflectance`.
    Set {
        target: Target,
        field: String,
        value: Json,
    },
    /// Sets several fields of one table in one step (one undo), e.g. "camera to view".
    SetFields {
        target: Target,
        fields: serde_json::Map<String, Json>,
    },
    Delete {
        target: Target,
    },
    /// Appends a copy of a shape, light or instance (named "<name> copy"), or of a material
    /// (as "<name>_copy"), to the file. `offset` moves the copy (its `transform`'s translate,
    /// or a point or spot light's `position` and `point_at`), so it does not hide the original.
    Duplicate {
        target: Target,
        #[serde(default)]
        offset: Option<[f64; 3]>,
    },
    /// Several commands as one step (one undo): moving a multi-selection or a group.
    Batch {
        commands: Vec<Command>,
    },
    /// Points a material's colour or scalar `field` (`reflectance`, `roughness`, ...) at an
    /// image in the scene's folder: adds `[textures.<file's stem>]` of `type = "image"` (or
    /// reuses the texture that already reads `file`) and sets `field = { texture = "..." }`,
    /// in one step (one undo). `linear` reads the image as data rather than sRGB colour.
    SetTexture {
        material: String,
        field: String,
        file: String,
        #[serde(default)]
        linear: bool,
    },
    /// Appends a new shape, light or material (`name` is the material's) made of `table`.
    Add {
        kind: Kind,
        table: serde_json::Map<String, Json>,
        name: Option<String>,
    },
}

/// The scene under edit.
pub struct SceneDocument {
    path: PathBuf,
    /// The folder files may be read from and written to (canonical).
    folder: PathBuf,
    /// Whether every parse reads files inside `folder` only (the editor's server), or wherever
    /// the scene names them (`photonix export`, run by the user on their own scene).
    confined: bool,
    text: String,
    scene: Scene,
    origins: SceneOrigins,
    /// Each step: the text before it, its entries' ids, and who made it (`apply_by`).
    undo: Vec<(String, Ids, u64)>,
    redo: Vec<(String, Ids, u64)>,
    /// Who makes the change under way (`apply_by`); 0 for anyone.
    author: u64,
    /// The stable id of each `[[shapes]]`, `[[lights]]` and `[[instances]]` entry.
    ids: Ids,
    /// The next id to give.
    next_id: u64,
    /// The text last loaded or saved.
    saved: String,
    /// The POV-Ray or glTF scene this document translates, until its first save: that save
    /// must not replace a `.toml` of the same name already beside it.
    translated_from: Option<PathBuf>,
    /// Counts every change of the text (edits, undo, redo).
    revision: u64,
    /// What the editor opened when it is not simply the file it was given (the `.toml` saved
    /// beside a `.pov` in place of its translation, or the other way round): the page says it.
    notice: Option<String>,
}

/// Why a save wrote nothing.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SaveError {
    /// The save would replace a file that is not the one the editor opened or last saved (a
    /// `.toml` beside the translated `.pov`, or a scene file changed on disk since): the page
    /// asks, and saves again with `replace` only when told to.
    #[error("{0}")]
    WouldReplace(String),
    #[error("{0}")]
    Failed(String),
}

/// The result of parsing a candidate text.
type Parsed = (Scene, SceneOrigins);

/// Most commands in one `batch`.
const MAX_BATCH: usize = 10_000;

/// Stable ids of the entries of the three arrays of tables, in file order: an entry keeps its id
/// through every edit (and undo and redo) until it is deleted; a new entry gets a new one.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ids {
    pub shapes: Vec<u64>,
    pub lights: Vec<u64>,
    pub instances: Vec<u64>,
}

/// The first entry id of a document: the time it was opened in milliseconds, times 1000, so the
/// ids of a restarted server are not those of the one before (a page left open, reconnecting,
/// then drops a selection whose entry it cannot know rather than moving it onto another);
/// below 2^53, so JSON carries them exactly.
fn first_id() -> u64 {
    let ms = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64);
    (ms % (1 << 42)) * 1000 + 1
}

/// The number of entries of each array of tables in `text`: shapes, lights, instances.
fn entry_counts(text: &str) -> [usize; 3] {
    let doc: DocumentMut = text.parse().unwrap_or_default();
    ["shapes", "lights", "instances"].map(|k| doc.get(k).and_then(Item::as_array_of_tables).map_or(0, |a| a.len()))
}

impl SceneDocument {
    /// Loads `path`, which must parse as a scene reading no file outside its folder (the
    /// editor's server: no model, texture or file a model names is read outside it).
    ///
    /// A translated scene (`.pov`, `.glb`/`.gltf`, Mitsuba `.xml`) with a `.toml` of its name beside
    /// it that is newer opens that `.toml`: the editor saved it there, and opening the
    /// translation again would show none of those edits (and a Save would lose them). `notice`
    /// says which file was opened and why.
    pub fn load(path: &Path) -> Result<SceneDocument, EditError> {
        if let Some(doc) = SceneDocument::open_saved_beside(path)? {
            return Ok(doc);
        }
        let mut doc = SceneDocument::open(path, true)?;
        if doc.translated_from.is_some() && std::fs::symlink_metadata(&doc.path).is_ok() {
            doc.notice = Some(format!(
                "opened the translation of {source}: {toml} beside it is older than {source}, so it was not opened; Save asks before replacing it",
                source = file_name(path),
                toml = file_name(&doc.path),
            ));
        }
        Ok(doc)
    }

    /// The `.toml` beside the translated scene `path` when it is newer than `path` (or as new).
    fn open_saved_beside(path: &Path) -> Result<Option<SceneDocument>, EditError> {
        let translated = crate::scene::pov::is_pov_path(path)
            || crate::scene::gltf_scene::is_gltf_path(path)
            || crate::scene::mitsuba::is_mitsuba_path(path);
        let beside = path.with_extension("toml");
        if !translated || beside == path {
            return Ok(None);
        }
        let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
        let (Some(source_time), Some(toml_time)) = (modified(path), modified(&beside)) else {
            return Ok(None);
        };
        if toml_time < source_time {
            return Ok(None);
        }
        let (source, toml) = (file_name(path), file_name(&beside));
        let mut doc = SceneDocument::open(&beside, true).map_err(|e| {
            EditError::Invalid(format!(
                "{toml} beside {source} is newer than it (the editor's last save) and was opened in its place, but it does not load: {e}; fix it, or move it away to open {source} again"
            ))
        })?;
        doc.notice = Some(format!(
            "opened {toml}, saved beside {source} and newer than it, so the edits saved there are kept; to start again from {source}, move {toml} away"
        ));
        Ok(Some(doc))
    }

    /// What the editor opened in place of the file it was given, and why (see `load`).
    pub fn notice(&self) -> Option<&str> {
        self.notice.as_deref()
    }

    /// `load`, reading the files the scene names wherever they are (`photonix export`).
    pub fn load_unconfined(path: &Path) -> Result<SceneDocument, EditError> {
        SceneDocument::open(path, false)
    }

    fn open(path: &Path, confined: bool) -> Result<SceneDocument, EditError> {
        // A POV-Ray scene is translated (scene::pov); the editor edits the translation and saves
        // it as the .toml beside the .pov file, never the .pov file itself. Until then it is unsaved.
        // Both translations read through the scene's file gate, confined like the TOML: includes,
        // height fields, fonts and glTF buffers inside the scene's folder (POV-Ray's standard
        // include folder aside).
        let pov = crate::scene::pov::is_pov_path(path);
        if pov || crate::scene::gltf_scene::is_gltf_path(path) {
            let folder = folder_of(path)?;
            let confine = confined.then_some(folder.as_path());
            let standard = Path::new(crate::scene::pov::STANDARD_INCLUDE_DIR);
            let (toml, _) = crate::scene::files::collect_allowing(confine, &[standard], || {
                if pov {
                    crate::scene::pov::translate_file(path, &crate::scene::pov::PovOptions::default()).map(|t| t.toml)
                } else {
                    crate::scene::gltf_scene::translate_file(path, None).map(|t| t.toml)
                }
            });
            let mut toml = toml.map_err(|e| EditError::Invalid(e.to_string()))?;
            if pov {
                // One POV-Ray object, one entry (a blob is not 10 000 triangles in the tree).
                let source = std::fs::read_to_string(path).ok();
                toml = super::pov_objects::regroup(&toml, source.as_deref());
            }
            let mut doc = Self::from_text(&path.with_extension("toml"), toml, confined)?;
            doc.saved = String::new();
            doc.translated_from = Some(path.to_path_buf());
            return Ok(doc);
        }
        // A Mitsuba scene likewise (scene::mitsuba): its includes read through the same gate,
        // confined alike; its TOML names the files beside it, which the TOML's load confines.
        if crate::scene::mitsuba::is_mitsuba_path(path) {
            let folder = folder_of(path)?;
            let (t, _) = crate::scene::files::collect(confined.then_some(folder.as_path()), || {
                crate::scene::mitsuba::translate_file(path)
            });
            let t = t.map_err(|e| EditError::Invalid(e.to_string()))?;
            let mut doc = Self::from_text(&path.with_extension("toml"), t.toml, confined)?;
            doc.saved = String::new();
            doc.translated_from = Some(path.to_path_buf());
            return Ok(doc);
        }
        let bytes = crate::limits::read_limited(path, crate::limits::MAX_SCENE_FILE_BYTES).map_err(|e| {
            EditError::Invalid(match e {
                Some(cause) => format!("cannot read {}: {cause}", path.display()),
                None => format!("{} is larger than {} bytes", path.display(), crate::limits::MAX_SCENE_FILE_BYTES),
            })
        })?;
        let text = String::from_utf8(bytes)
            .map_err(|_| EditError::Invalid(format!("{} is not UTF-8 text", path.display())))?;
        Self::from_text(path, text, confined)
    }

    /// A document of `text`, to be saved at `path`; with `confined`, reading no file outside
    /// the folder of `path`.
    fn from_text(path: &Path, text: String, confined: bool) -> Result<SceneDocument, EditError> {
        let folder = folder_of(path)?;
        let (scene, origins) = parse(&text, path, confined.then_some(folder.as_path()))?;
        let mut doc = SceneDocument {
            path: path.to_path_buf(),
            folder,
            confined,
            saved: text.clone(),
            translated_from: None,
            notice: None,
            text,
            scene,
            origins,
            undo: Vec::new(),
            redo: Vec::new(),
            author: 0,
            ids: Ids::default(),
            next_id: first_id(),
            revision: 0,
        };
        doc.ids = doc.fresh_ids();
        Ok(doc)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
    /// The scene's folder, canonical: the only folder the editor reads or writes.
    pub fn folder(&self) -> &Path {
        &self.folder
    }
    fn confinement(&self) -> Option<&Path> {
        self.confined.then_some(self.folder.as_path())
    }
    pub fn text(&self) -> &str {
        &self.text
    }
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    pub fn origins(&self) -> &SceneOrigins {
        &self.origins
    }
    pub fn revision(&self) -> u64 {
        self.revision
    }
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
    /// Who made the step that undo would undo (the editor's page session; 0: anyone, the API).
    pub fn undo_author(&self) -> Option<u64> {
        self.undo.last().map(|step| step.2)
    }
    /// Who made the step that redo would redo.
    pub fn redo_author(&self) -> Option<u64> {
        self.redo.last().map(|step| step.2)
    }

    /// `apply`, the step recorded as made by `author` (a page session), so that each page can
    /// say whose edit Undo would undo: the undo stack is the scene's, shared by every page.
    pub fn apply_by(&mut self, command: &Command, author: u64) -> Result<(), EditError> {
        self.author = author;
        let result = self.apply(command);
        self.author = 0;
        result
    }
    /// The stable ids of the entries (`Target::ShapeId` and its kin).
    pub fn ids(&self) -> &Ids {
        &self.ids
    }

    /// New ids for every entry of the current text.
    fn fresh_ids(&mut self) -> Ids {
        let [shapes, lights, instances] = entry_counts(&self.text);
        let mut take = |n: usize| -> Vec<u64> {
            let ids = (self.next_id..self.next_id + n as u64).collect();
            self.next_id += n as u64;
            ids
        };
        Ids { shapes: take(shapes), lights: take(lights), instances: take(instances) }
    }

    /// `target` with a stable id replaced by the entry's index now.
    pub fn resolve(&self, target: &Target) -> Result<Target, EditError> {
        let find = |ids: &[u64], id: &u64, what: &str| {
            ids.iter().position(|x| x == id).ok_or_else(|| {
                bad(format!("there is no {what} of id {id} any more (another page may have deleted it)"))
            })
        };
        Ok(match target {
            Target::ShapeId(id) => Target::Shape(find(&self.ids.shapes, id, "shape")?),
            Target::LightId(id) => Target::Light(find(&self.ids.lights, id, "light")?),
            Target::InstanceId(id) => Target::Instance(find(&self.ids.instances, id, "instance")?),
            other => other.clone(),
        })
    }

    /// `command` with its targets resolved (`resolve`).
    fn resolve_command(&self, command: &Command) -> Result<Command, EditError> {
        let mut command = command.clone();
        match &mut command {
            Command::SetTransform { target, .. }
            | Command::Set { target, .. }
            | Command::SetFields { target, .. }
            | Command::Delete { target }
            | Command::Duplicate { target, .. } => *target = self.resolve(target)?,
            Command::Batch { commands } => {
                if commands.len() > MAX_BATCH {
                    return Err(bad(format!("a batch takes at most {MAX_BATCH} commands")));
                }
                for c in commands.iter_mut() {
                    if matches!(c, Command::Batch { .. }) {
                        return Err(bad("a batch cannot hold another batch"));
                    }
                    *c = self.resolve_command(c)?;
                }
            }
            Command::SetTexture { .. } | Command::Add { .. } => {}
        }
        Ok(command)
    }

    /// The ids after `command` (resolved) is applied to entries with `ids`.
    fn ids_after(&mut self, ids: &mut Ids, command: &Command) {
        fn pick(ids: &mut Ids, which: usize) -> &mut Vec<u64> {
            match which {
                0 => &mut ids.shapes,
                1 => &mut ids.lights,
                _ => &mut ids.instances,
            }
        }
        let which = |target: &Target| match target {
            Target::Shape(i) => Some((0, *i)),
            Target::Light(i) => Some((1, *i)),
            Target::Instance(i) => Some((2, *i)),
            _ => None,
        };
        match command {
            Command::Delete { target } => {
                if let Some((w, i)) = which(target) {
                    let v = pick(ids, w);
                    if i < v.len() {
                        v.remove(i);
                    }
                }
            }
            Command::Duplicate { target, .. } => {
                if let Some((w, _)) = which(target) {
                    pick(ids, w).push(self.next_id);
                    self.next_id += 1;
                }
            }
            Command::Add { kind, .. } => {
                let w = match kind {
                    Kind::Shape => 0,
                    Kind::Light => 1,
                    Kind::Material => return,
                };
                pick(ids, w).push(self.next_id);
                self.next_id += 1;
            }
            Command::Batch { commands } => {
                for c in commands {
                    self.ids_after(ids, c);
                }
            }
            _ => {}
        }
    }

    /// Makes the last change and the one before it one step: undo goes back past both
    /// (an import and the move that placed it).
    pub fn merge_last_step(&mut self) {
        if self.undo.len() >= 2 {
            self.undo.pop();
        }
    }

    /// True when the text differs from the file as last loaded or saved.
    pub fn dirty(&self) -> bool {
        self.text != self.saved
    }

    /// Applies `command`; on any error the document is unchanged.
    pub fn apply(&mut self, command: &Command) -> Result<(), EditError> {
        let command = self.resolve_command(command)?;
        let mut doc: DocumentMut =
            self.text.parse().map_err(|e| EditError::Invalid(format!("the scene text no longer parses: {e}")))?;
        edit(&mut doc, &command)?;
        let text = doc.to_string();
        let next_id = self.next_id;
        let mut ids = self.ids.clone();
        self.ids_after(&mut ids, &command);
        self.change_text(text, Some(ids)).inspect_err(|_| self.next_id = next_id)
    }

    /// Replaces the text with `text` after parsing it as a scene and checking the files it
    /// names; pushes the old text on the undo stack. Entries keep their ids where the text has
    /// as many of them as before; otherwise every entry gets a new id.
    pub fn replace(&mut self, text: String) -> Result<(), EditError> {
        self.change_text(text, None)
    }

    fn change_text(&mut self, text: String, ids: Option<Ids>) -> Result<(), EditError> {
        if text == self.text {
            return Ok(());
        }
        let parsed = self.check(&text)?;
        let old = std::mem::replace(&mut self.text, text);
        let ids = match ids {
            Some(ids) => ids,
            None if entry_counts(&old) == entry_counts(&self.text) => self.ids.clone(),
            None => self.fresh_ids(),
        };
        let old_ids = std::mem::replace(&mut self.ids, ids);
        self.undo.push((old, old_ids, self.author));
        if self.undo.len() > MAX_UNDO {
            self.undo.remove(0);
        }
        self.redo.clear();
        self.install(parsed);
        Ok(())
    }

    pub fn undo(&mut self) -> Result<(), EditError> {
        let (text, ids, author) = self.undo.last().ok_or(EditError::NothingToUndo)?.clone();
        // The text was valid when it was current; files it names may have gone since.
        let parsed = parse(&text, &self.path, self.confinement())?;
        self.undo.pop();
        let old_ids = std::mem::replace(&mut self.ids, ids);
        self.redo.push((std::mem::replace(&mut self.text, text), old_ids, author));
        self.install(parsed);
        Ok(())
    }

    pub fn redo(&mut self) -> Result<(), EditError> {
        let (text, ids, author) = self.redo.last().ok_or(EditError::NothingToRedo)?.clone();
        let parsed = parse(&text, &self.path, self.confinement())?;
        self.redo.pop();
        let old_ids = std::mem::replace(&mut self.ids, ids);
        self.undo.push((std::mem::replace(&mut self.text, text), old_ids, author));
        self.install(parsed);
        Ok(())
    }

    /// Writes the text to the scene file atomically (a temporary file in the same folder, then
    /// a rename): the file is either the old one or the new one, never a mix. Replaces nothing
    /// the editor did not open or last write (`save_replacing` does, once the user said so).
    pub fn save(&mut self) -> Result<(), String> {
        self.save_replacing(false).map_err(|e| e.to_string())
    }

    /// `save`; with `replace`, also over a file that `save` would not replace: a `.toml`
    /// beside the translated scene, or a scene file changed on disk since it was opened or saved.
    pub fn save_replacing(&mut self, replace: bool) -> Result<(), SaveError> {
        if !replace {
            self.check_replace()?;
        }
        let text = self.text.clone();
        crate::io::image::write_atomically(&self.path, |tmp| {
            std::fs::write(tmp, text.as_bytes()).map_err(|e| e.to_string())
        })
        .map_err(|e| SaveError::Failed(e.to_string()))?;
        self.saved = self.text.clone();
        self.translated_from = None;
        self.notice = None;
        Ok(())
    }

    /// Refuses a save that would replace a file other than the one this document was read from
    /// or last wrote.
    fn check_replace(&self) -> Result<(), SaveError> {
        let name = file_name(&self.path);
        if std::fs::symlink_metadata(&self.path).is_err() {
            return Ok(());
        }
        // The first save of a translation writes `<name>.toml` beside the .pov or .glb: a file of
        // that name already there is not this document.
        if let Some(source) = &self.translated_from {
            return Err(SaveError::WouldReplace(format!(
                "not saved: {name} already exists beside {}, and saving the translation would replace it; replace it, or move it away (or edit it with `photonix serve {name}`)",
                file_name(source),
            )));
        }
        // Something else wrote the file since the editor read or saved it.
        let on_disk = crate::limits::read_limited(&self.path, crate::limits::MAX_SCENE_FILE_BYTES).ok();
        if on_disk.as_deref() != Some(self.saved.as_bytes()) {
            return Err(SaveError::WouldReplace(format!(
                "not saved: {name} changed on disk since the editor opened or last saved it (another program or editor wrote it); replace it with the editor's scene, or save nothing and keep it"
            )));
        }
        Ok(())
    }

    fn install(&mut self, (scene, origins): Parsed) {
        self.scene = scene;
        self.origins = origins;
        self.revision += 1;
    }

    /// Parses `text` and checks that every file it names that the current text does not name
    /// lies inside the scene's folder (no `..` out of it, no absolute path elsewhere, no
    /// symbolic link leading out).
    fn check(&self, text: &str) -> Result<Parsed, EditError> {
        if text.len() as u64 > crate::limits::MAX_SCENE_FILE_BYTES {
            return Err(bad(format!(
                "the edited scene would be larger than {} bytes",
                crate::limits::MAX_SCENE_FILE_BYTES
            )));
        }
        let before = file_fields(&self.text);
        for file in file_fields(text).difference(&before) {
            self.check_inside(file)?;
        }
        parse(text, &self.path, self.confinement())
    }

    /// Resolves `file` (relative to the scene's folder) and refuses it unless it exists inside
    /// the folder once every symbolic link is followed.
    /// The same gate as every loader's (`scene::files`): a path out of the folder is refused
    /// alike whether or not something is there, so the page cannot probe for files outside.
    pub fn check_inside(&self, file: &str) -> Result<PathBuf, EditError> {
        let path = self.folder.join(file);
        let (checked, _) = crate::scene::files::collect(Some(&self.folder), || crate::scene::files::check(&path));
        checked.map_err(|e| match e {
            crate::scene::files::FileError::Outside { .. } => bad(format!(
                "file \"{}\" is outside the scene's folder; the editor reads only files inside {}",
                crate::limits::printable(file),
                self.folder.display()
            )),
            e => bad(format!(
                "file \"{}\": {e} (paths are relative to the scene's folder)",
                crate::limits::printable(file)
            )),
        })
    }
}

/// The folder of `path`, canonical.
/// The file's name, printable, for messages.
fn file_name(path: &Path) -> String {
    crate::limits::printable(&path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default())
}

fn folder_of(path: &Path) -> Result<PathBuf, EditError> {
    path.parent()
        .map(|p| if p.as_os_str().is_empty() { Path::new(".") } else { p })
        .unwrap_or(Path::new("."))
        .canonicalize()
        .map_err(|e| EditError::Invalid(format!("cannot open the folder of {}: {e}", path.display())))
}

/// Parses `text`; with `folder`, every file the scene or its models name must be inside it.
fn parse(text: &str, path: &Path, folder: Option<&Path>) -> Result<Parsed, EditError> {
    parse_scene_in(text, path, folder).map_err(|e| EditError::Invalid(e.to_string()))
}

/// Every `file = "..."` value of the text (meshes, textures, the environment map).
fn file_fields(text: &str) -> BTreeSet<String> {
    fn walk(item: &Item, out: &mut BTreeSet<String>) {
        match item {
            Item::Table(t) => t.iter().for_each(|(k, v)| visit(k, v, out)),
            Item::ArrayOfTables(a) => a.iter().for_each(|t| t.iter().for_each(|(k, v)| visit(k, v, out))),
            Item::Value(Value::InlineTable(t)) => {
                t.iter().for_each(|(k, v)| visit(k, &Item::Value(v.clone()), out));
            }
            _ => {}
        }
    }
    fn visit(key: &str, item: &Item, out: &mut BTreeSet<String>) {
        if key == "file" {
            if let Some(s) = item.as_str() {
                out.insert(s.to_string());
            }
        }
        walk(item, out);
    }
    let mut out = BTreeSet::new();
    if let Ok(doc) = text.parse::<DocumentMut>() {
        doc.iter().for_each(|(k, v)| visit(k, v, &mut out));
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Edits on the document

fn edit(doc: &mut DocumentMut, command: &Command) -> Result<(), EditError> {
    match command {
        Command::SetTransform { target, translate, rotate, scale } => {
            if !matches!(target, Target::Shape(_) | Target::Light(_) | Target::Instance(_)) {
                return Err(bad(format!(
                    "{} has no transform; only shapes, area lights and instances do",
                    target.describe()
                )));
            }
            let table = target_table(doc, target)?;
            if matches!(target, Target::Light(_)) && table.get("type").and_then(|t| t.as_str()) != Some("area") {
                return Err(bad(format!(
                    "{} is not an area light, so it has no transform; set its `position` or `direction` instead",
                    target.describe()
                )));
            }
            if table.get("transform").is_none() {
                table.insert("transform", Item::Value(Value::InlineTable(Default::default())));
            }
            let transform = table
                .get_mut("transform")
                .and_then(|t| t.as_table_like_mut())
                .ok_or_else(|| bad(format!("the `transform` of {} is not a table", target.describe())))?;
            if transform.contains_key("matrix") {
                return Err(bad(format!(
                    "{} is placed by a `transform.matrix` (a Mitsuba import); the editor moves things by scale, \
                     rotate and translate: edit the matrix in the file, or replace it by those three",
                    target.describe()
                )));
            }
            if let Some(t) = translate {
                set_key(transform, "translate", vector(t)?, [0.0; 3] == *t);
            }
            if let Some(r) = rotate {
                set_key(transform, "rotate", vector(r)?, [0.0; 3] == *r);
            }
            if let Some(s) = scale {
                let (value, identity) = match s {
                    Scale::Uniform(v) => (number(*v)?, *v == 1.0),
                    Scale::Axes(a) if a[0] == a[1] && a[1] == a[2] => (number(a[0])?, a[0] == 1.0),
                    Scale::Axes(a) => (vector(a)?, false),
                };
                set_key(transform, "scale", value, identity);
            }
            if transform.is_empty() {
                table.remove("transform");
            }
            Ok(())
        }
        Command::SetFields { target, fields } => {
            if fields.is_empty() {
                return Err(bad("`fields` is empty"));
            }
            for (field, value) in fields {
                edit(doc, &Command::Set { target: target.clone(), field: field.clone(), value: value.clone() })?;
            }
            Ok(())
        }
        Command::Set { target, field, value } => {
            check_key(field)?;
            if let Target::Material(_) = target {
                if field == "name" {
                    return Err(bad("a material's name is its table's name; duplicate it and delete the old one"));
                }
            }
            if field == "file" {
                if let Json::String(_) = value {
                } else if !value.is_null() {
                    return Err(bad("`file` takes a path relative to the scene's folder"));
                }
            }
            let table = target_table(doc, target)?;
            if value.is_null() {
                if field == "type" {
                    return Err(bad("`type` cannot be removed"));
                }
                table.remove(field);
            } else {
                let keep_absent = false;
                set_key(table, field, json_to_toml(value, 0)?, keep_absent);
            }
            Ok(())
        }
        Command::Delete { target } => match target {
            Target::Shape(i) | Target::Light(i) | Target::Instance(i) => {
                let (key, count) = array_of(doc, target)?;
                if *i >= count {
                    return Err(bad(format!("there is no {} (the file has {count})", target.describe())));
                }
                let array = doc[key].as_array_of_tables_mut().expect("checked by array_of");
                array.remove(*i);
                if array.is_empty() {
                    doc.remove(key);
                }
                Ok(())
            }
            Target::Material(name) => {
                let materials = doc
                    .get_mut("materials")
                    .and_then(|m| m.as_table_like_mut())
                    .ok_or_else(|| bad("the scene has no materials"))?;
                materials.remove(name).ok_or_else(|| bad(format!("there is no {}", target.describe())))?;
                Ok(())
            }
            Target::Environment | Target::Photons | Target::Render => {
                let key = match target {
                    Target::Environment => "environment",
                    Target::Photons => "photons",
                    _ => "render",
                };
                doc.remove(key).ok_or_else(|| bad(format!("the scene has no {}", target.describe())))?;
                Ok(())
            }
            Target::Camera => Err(bad("a scene needs its [camera]; it cannot be deleted")),
            Target::ShapeId(_) | Target::LightId(_) | Target::InstanceId(_) => Err(unresolved()),
        },
        Command::Batch { commands } => {
            for c in commands {
                edit(doc, c)?;
            }
            Ok(())
        }
        Command::Duplicate { target, offset } => match target {
            Target::Shape(_) | Target::Light(_) | Target::Instance(_) => {
                let mut copy = fresh_copy(target_table(doc, target)?);
                if let Some(name) = copy.get("name").and_then(|n| n.as_str()).map(str::to_string) {
                    set_key(&mut copy, "name", Value::from(format!("{name} copy")), false);
                }
                if let Some(offset) = offset {
                    offset_copy(&mut copy, offset, target)?;
                }
                let (key, _) = array_of(doc, target)?;
                doc[key].as_array_of_tables_mut().expect("checked by array_of").push(copy);
                Ok(())
            }
            Target::Material(name) => {
                let copy = fresh_copy(target_table(doc, target)?);
                let materials = doc["materials"].as_table_like_mut().expect("target_table found it");
                let mut new_name = format!("{name}_copy");
                let mut n = 2;
                while materials.contains_key(&new_name) {
                    new_name = format!("{name}_copy{n}");
                    n += 1;
                }
                materials.insert(&new_name, Item::Table(copy));
                Ok(())
            }
            _ => Err(bad(format!("{} cannot be duplicated", target.describe()))),
        },
        Command::SetTexture { material, field, file, linear } => {
            check_key(field)?;
            if matches!(field.as_str(), "type" | "name" | "materials") {
                return Err(bad(format!("`{field}` cannot take a texture")));
            }
            if file.is_empty() || file.len() > MAX_STRING_BYTES {
                return Err(bad("`file` takes a path relative to the scene's folder"));
            }
            let target = Target::Material(material.clone());
            target_table(doc, &target)?;
            let name = texture_for(doc, file, *linear)?;
            let mut reference = toml_edit::InlineTable::new();
            reference.insert("texture", Value::from(name));
            let table = target_table(doc, &target)?;
            set_key(table, field, Value::InlineTable(reference), false);
            Ok(())
        }
        Command::Add { kind, table, name } => {
            let mut new = Table::new();
            for (key, value) in table {
                check_key(key)?;
                new.insert(key, Item::Value(json_to_toml(value, 0)?));
            }
            match kind {
                Kind::Shape | Kind::Light => {
                    if name.is_some() {
                        return Err(bad("`name` goes in the table of a shape or light"));
                    }
                    let key = if *kind == Kind::Shape { "shapes" } else { "lights" };
                    if doc.get(key).is_none() {
                        doc.insert(key, Item::ArrayOfTables(Default::default()));
                    }
                    let array = doc[key]
                        .as_array_of_tables_mut()
                        .ok_or_else(|| bad(format!("`{key}` is not an array of tables")))?;
                    array.push(new);
                }
                Kind::Material => {
                    let name = name.as_deref().ok_or_else(|| bad("a new material needs a `name`"))?;
                    check_name(name)?;
                    if doc.get("materials").is_none() {
                        let mut materials = Table::new();
                        materials.set_implicit(true);
                        doc.insert("materials", Item::Table(materials));
                    }
                    let materials =
                        doc["materials"].as_table_like_mut().ok_or_else(|| bad("`materials` is not a table"))?;
                    if materials.contains_key(name) {
                        return Err(bad(format!(
                            "a material named \"{}\" exists already",
                            crate::limits::printable(name)
                        )));
                    }
                    materials.insert(name, Item::Table(new));
                }
            }
            Ok(())
        }
    }
}

/// The name of an image texture reading `file` (with the colour space `linear` asks for): the
/// one the scene has, else a new `[textures.<stem>]` (`<stem>_2`, ... when the name is taken).
fn texture_for(doc: &mut DocumentMut, file: &str, linear: bool) -> Result<String, EditError> {
    let space = if linear { "linear" } else { "srgb" };
    if doc.get("textures").is_none() {
        let mut textures = Table::new();
        textures.set_implicit(true);
        doc.insert("textures", Item::Table(textures));
    }
    let textures = doc["textures"].as_table_like_mut().ok_or_else(|| bad("`textures` is not a table"))?;
    for (name, item) in textures.iter() {
        let Some(t) = item.as_table_like() else { continue };
        let same_file = t.get("file").and_then(|f| f.as_str()) == Some(file);
        let same_space = t.get("color_space").and_then(|c| c.as_str()).unwrap_or("srgb") == space;
        let plain = t.get("transform").is_none() && t.get("channel").is_none();
        if t.get("type").and_then(|t| t.as_str()) == Some("image") && same_file && same_space && plain {
            return Ok(name.to_string());
        }
    }
    let stem = Path::new(file).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut base: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if !base.starts_with(|c: char| c.is_ascii_alphabetic()) {
        base = format!("image_{base}");
    }
    let mut name = base.clone();
    let mut n = 2;
    while textures.contains_key(&name) {
        name = format!("{base}_{n}");
        n += 1;
    }
    let mut table = Table::new();
    table.insert("type", toml_edit::value("image"));
    table.insert("file", toml_edit::value(file));
    if linear {
        table.insert("color_space", toml_edit::value("linear"));
    }
    textures.insert(&name, Item::Table(table));
    Ok(name)
}

/// Image files (what `[textures.*]` reads: PNG, JPEG, OpenEXR, Radiance HDR, TGA, GIF) in `folder` and
/// its subfolders, as paths relative to it with `/`, sorted; hidden entries skipped, symbolic
/// links followed only while they stay inside the folder, at most `limit` files.
pub fn image_files(folder: &Path, limit: usize) -> Vec<String> {
    const EXTENSIONS: [&str; 7] = ["png", "jpg", "jpeg", "exr", "hdr", "tga", "gif"];
    const MAX_DEPTH: usize = 4;
    let mut out = Vec::new();
    let mut stack = vec![(folder.to_path_buf(), 0usize)];
    while let Some((dir, depth)) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            let path = entry.path();
            let Ok(resolved) = path.canonicalize() else { continue };
            if !resolved.starts_with(folder) {
                continue;
            }
            if resolved.is_dir() {
                if depth < MAX_DEPTH {
                    stack.push((path, depth + 1));
                }
            } else if Path::new(&name).extension().is_some_and(|e| EXTENSIONS.iter().any(|x| e.eq_ignore_ascii_case(x)))
            {
                if let Ok(relative) = path.strip_prefix(folder) {
                    let parts: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
                    out.push(parts.join("/"));
                }
            }
        }
    }
    out.sort();
    out.truncate(limit);
    out
}

/// A copy of `table`'s fields as a new table (no comments, no place in the file yet, so it
/// goes at the end), its sub-tables (`[shapes.transform]`) made inline.
fn fresh_copy(table: &dyn TableLike) -> Table {
    let mut copy = Table::new();
    for (key, item) in table.iter() {
        let item = match item {
            Item::Table(t) => Item::Value(Value::InlineTable(t.clone().into_inline_table())),
            other => other.clone(),
        };
        copy.insert(key, item);
    }
    copy
}

fn unresolved() -> EditError {
    bad("internal: an entry id reached the edit unresolved")
}

/// Moves a duplicate by `offset`: a point or spot light's `position` (and `point_at`), anything
/// else's `transform.translate` (a distant light stays where it is: it has no place).
fn offset_copy(copy: &mut Table, offset: &[f64; 3], target: &Target) -> Result<(), EditError> {
    let kind = copy.get("type").and_then(|t| t.as_str()).unwrap_or("").to_string();
    let moved = |value: Option<&Item>| -> Option<[f64; 3]> {
        let array = value?.as_array()?;
        let n = |i: usize| array.get(i).and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)));
        Some([n(0)? + offset[0], n(1)? + offset[1], n(2)? + offset[2]])
    };
    if matches!(target, Target::Light(_)) && kind != "area" {
        for field in ["position", "point_at"] {
            if let Some(p) = moved(copy.get(field)) {
                copy.insert(field, Item::Value(vector(&p)?));
            }
        }
        return Ok(());
    }
    let mut transform = match copy.remove("transform") {
        Some(Item::Value(Value::InlineTable(t))) => t,
        Some(Item::Table(t)) => t.into_inline_table(),
        Some(_) => return Err(bad(format!("the `transform` of {} is not a table", target.describe()))),
        None => toml_edit::InlineTable::new(),
    };
    // A matrix carries its translation in its last column.
    if let Some(m) = transform.get_mut("matrix").and_then(|m| m.as_array_mut()) {
        for (row, d) in offset.iter().enumerate() {
            let at = 4 * row + 3;
            let old = m.get(at).and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)));
            let Some(old) = old else {
                return Err(bad(format!("the `transform.matrix` of {} is not 16 numbers", target.describe())));
            };
            m.replace(at, old + d);
        }
        copy.insert("transform", Item::Value(Value::InlineTable(transform)));
        return Ok(());
    }
    let translate = match transform.get("translate") {
        Some(v) => moved(Some(&Item::Value(v.clone())))
            .ok_or_else(|| bad(format!("the `transform.translate` of {} is not three numbers", target.describe())))?,
        None => *offset,
    };
    transform.insert("translate", vector(&translate)?);
    copy.insert("transform", Item::Value(Value::InlineTable(transform)));
    Ok(())
}

/// The array of tables a shape, light or instance target lives in, and its length.
fn array_of(doc: &DocumentMut, target: &Target) -> Result<(&'static str, usize), EditError> {
    let key = match target {
        Target::Shape(_) => "shapes",
        Target::Light(_) => "lights",
        Target::Instance(_) => "instances",
        _ => unreachable!("array_of is only called for shapes, lights and instances"),
    };
    match doc.get(key) {
        None => Ok((key, 0)),
        Some(item) => match item.as_array_of_tables() {
            Some(a) => Ok((key, a.len())),
            None => Err(bad(format!("`{key}` is not an array of tables ([[{key}]])"))),
        },
    }
}

/// The table a target names, created for `[render]`, `[photons]` and `[environment]`.
fn target_table<'d>(doc: &'d mut DocumentMut, target: &Target) -> Result<&'d mut dyn TableLike, EditError> {
    match target {
        Target::Shape(i) | Target::Light(i) | Target::Instance(i) => {
            let (key, count) = array_of(doc, target)?;
            if *i >= count {
                return Err(bad(format!("there is no {} (the file has {count})", target.describe())));
            }
            let table = doc[key].as_array_of_tables_mut().expect("checked by array_of").get_mut(*i).expect("in range");
            Ok(table as &mut dyn TableLike)
        }
        Target::Material(name) => doc
            .get_mut("materials")
            .and_then(|m| m.as_table_like_mut())
            .and_then(|m| m.get_mut(name))
            .and_then(|t| t.as_table_like_mut())
            .ok_or_else(|| bad(format!("there is no {}", target.describe()))),
        Target::Camera | Target::Render | Target::Photons | Target::Environment => {
            let key = match target {
                Target::Camera => "camera",
                Target::Render => "render",
                Target::Photons => "photons",
                _ => "environment",
            };
            if doc.get(key).is_none() {
                doc.insert(key, Item::Table(Table::new()));
            }
            doc[key].as_table_like_mut().ok_or_else(|| bad(format!("`{key}` is not a table")))
        }
        Target::ShapeId(_) | Target::LightId(_) | Target::InstanceId(_) => Err(unresolved()),
    }
}

/// Sets `key` to `value`, keeping the comments around the old value; with `remove_if_absent`,
/// a key that is absent stays absent (an identity transform part is not written out).
fn set_key(table: &mut dyn TableLike, key: &str, mut value: Value, remove_if_absent: bool) {
    match table.get_mut(key) {
        Some(Item::Value(old)) => {
            let decor = old.decor().clone();
            *value.decor_mut() = decor;
            *old = value;
        }
        Some(item) => *item = Item::Value(value),
        None if remove_if_absent => {}
        None => {
            table.insert(key, Item::Value(value));
        }
    }
}

fn check_key(key: &str) -> Result<(), EditError> {
    let ok = !key.is_empty()
        && key.len() <= 64
        && key.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_');
    if ok {
        Ok(())
    } else {
        Err(bad(format!("\"{}\" is not a field name (lowercase letters, digits and _)", crate::limits::printable(key))))
    }
}

fn check_name(name: &str) -> Result<(), EditError> {
    if name.is_empty() || name.len() > 64 || name.chars().any(|c| c.is_control()) {
        return Err(bad("a name must be 1 to 64 characters with no control characters"));
    }
    Ok(())
}

/// Rounds to 7 significant digits, so a value dragged in the page (0.30000000000000004) is
/// written as a person would type it (0.3); f32, which the renderer reads, keeps about 7.
fn round_number(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    format!("{v:.6e}").parse().unwrap_or(v)
}

fn number(v: f64) -> Result<Value, EditError> {
    if !v.is_finite() {
        return Err(bad("numbers must be finite"));
    }
    let v = round_number(v);
    if v.fract() == 0.0 && v.abs() < 1e15 {
        Ok(Value::from(v as i64))
    } else {
        Ok(Value::from(v))
    }
}

fn vector(v: &[f64; 3]) -> Result<Value, EditError> {
    let mut array = toml_edit::Array::new();
    for &c in v {
        array.push(number(c)?);
    }
    Ok(Value::Array(array))
}

/// A JSON value of an edit as a TOML value: numbers, strings, booleans, arrays and tables.
fn json_to_toml(value: &Json, depth: usize) -> Result<Value, EditError> {
    if depth > MAX_VALUE_DEPTH {
        return Err(bad("the value is nested too deeply"));
    }
    Ok(match value {
        Json::Null => return Err(bad("`null` is only allowed as a whole value (it removes the field)")),
        Json::Bool(b) => Value::from(*b),
        Json::Number(n) => match n.as_i64() {
            Some(i) => Value::from(i),
            None => number(n.as_f64().ok_or_else(|| bad("the number is out of range"))?)?,
        },
        Json::String(s) => {
            if s.len() > MAX_STRING_BYTES {
                return Err(bad("strings are limited to 4096 bytes"));
            }
            Value::from(s.as_str())
        }
        Json::Array(items) => {
            let mut array = toml_edit::Array::new();
            for item in items {
                array.push(json_to_toml(item, depth + 1)?);
            }
            Value::Array(array)
        }
        Json::Object(map) => {
            let mut table = toml_edit::InlineTable::new();
            for (k, v) in map {
                check_key(k)?;
                table.insert(k, json_to_toml(v, depth + 1)?);
            }
            Value::InlineTable(table)
        }
    })
}

/// A TOML item as JSON, for the page: numbers, strings, booleans, arrays and tables.
pub fn toml_to_json(item: &Item) -> Json {
    match item {
        Item::None => Json::Null,
        Item::Value(v) => value_to_json(v),
        Item::Table(t) => Json::Object(t.iter().map(|(k, v)| (k.to_string(), toml_to_json(v))).collect()),
        Item::ArrayOfTables(a) => Json::Array(
            a.iter().map(|t| Json::Object(t.iter().map(|(k, v)| (k.to_string(), toml_to_json(v))).collect())).collect(),
        ),
    }
}

fn value_to_json(v: &Value) -> Json {
    match v {
        Value::String(s) => Json::String(s.value().clone()),
        Value::Integer(i) => Json::from(*i.value()),
        Value::Float(f) => serde_json::Number::from_f64(*f.value()).map_or(Json::Null, Json::Number),
        Value::Boolean(b) => Json::Bool(*b.value()),
        Value::Datetime(d) => Json::String(d.value().to_string()),
        Value::Array(a) => Json::Array(a.iter().map(value_to_json).collect()),
        Value::InlineTable(t) => Json::Object(t.iter().map(|(k, v)| (k.to_string(), value_to_json(v))).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_rounded_to_seven_digits() {
        assert_eq!(round_number(0.1 + 0.2), 0.3);
        assert_eq!(round_number(552.8000000001), 552.8);
        assert_eq!(number(2.0).unwrap().to_string().trim(), "2");
        assert!(number(f64::NAN).is_err());
    }

    #[test]
    fn commands_parse_from_the_json_the_page_sends() {
        let c: Command =
            serde_json::from_str(r#"{"op":"set_transform","target":{"shape":3},"translate":[1,2,3]}"#).unwrap();
        assert_eq!(
            c,
            Command::SetTransform {
                target: Target::Shape(3),
                translate: Some([1.0, 2.0, 3.0]),
                rotate: None,
                scale: None
            }
        );
        let c: Command = serde_json::from_str(r#"{"op":"delete","target":"camera"}"#).unwrap();
        assert_eq!(c, Command::Delete { target: Target::Camera });
        assert!(serde_json::from_str::<Command>(r#"{"op":"delete","target":"camera","extra":1}"#).is_err());
        assert!(serde_json::from_str::<Command>(r#"{"op":"explode"}"#).is_err());
    }
}
