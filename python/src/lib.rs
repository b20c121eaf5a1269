//! `photonix._photonix`: the compiled half of the `photonix` Python package. A thin layer over
//! the library's public API (scene parsing, `prepare`, the GPU renderer or the CPU reference,
//! `render_progressive`, the accumulation files), doing what `photonix render` does with its
//! flags; `photonix/__init__.py` re-exports it and converts Python-side conveniences.
//!
//! Threads: a render runs on a worker thread while the calling thread, without the GIL, waits
//! for its progress reports. Every 50 ms the calling thread takes the GIL to run Python's signal
//! handlers (so Ctrl-C raises KeyboardInterrupt there) and the progress callback; an interrupt
//! sets the worker's stop flag, which the renderer reads between its submissions.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use toml_edit::{DocumentMut, Item, Value};

use photonix::gpu::{list_devices, GpuContext, GpuOptions};
use photonix::io::Image;
use photonix::limits::{MAX_DEPTH, MAX_GATHER_RAYS, MAX_IMAGE_SIDE, MAX_PASSES, MAX_PHOTON_PATHS, MAX_PIXELS, MAX_SPP};
use photonix::render::accumulation::{merge as merge_parts, write_accumulation, Provenance};
use photonix::render::memory::{self, available_host_memory, check_fits};
use photonix::render::photons::check_radii;
use photonix::render::progressive::{render_progressive, Accumulator, Budget, StopReason};
use photonix::render::{auto_backend, prepare, Backend, FrameSettings, Layers, PhotonSettings, Renderer};
use photonix::scene::Integrator;

create_exception!(_photonix, PhotonixError, PyException, "Base class of the errors Photonix raises.");
create_exception!(
    _photonix,
    SceneError,
    PhotonixError,
    "A scene that does not parse or an edit it refuses; the message has file:line:column."
);
create_exception!(
    _photonix,
    RenderError,
    PhotonixError,
    "A render refused before it starts (memory, radii, device) or failed on the device."
);
create_exception!(
    _photonix,
    Cancelled,
    PhotonixError,
    "A render cancelled (Renderer.cancel) before its first pass finished."
);
create_exception!(
    _photonix,
    ImageError,
    PhotonixError,
    "An image or accumulation file that cannot be read or written."
);

/// How often the waiting thread looks at Python's signals and reports progress.
const POLL: Duration = Duration::from_millis(50);
/// Paths between two looks at the stop flag: small enough that Ctrl-C stops a pass within a
/// fraction of a second even on lavapipe; the image does not depend on it.
const STOP_CHECK_PATHS: u64 = 1 << 16;

// ---------------------------------------------------------------------------------------------
// Scenes

/// A scene: its TOML text, the file it came from (for messages and relative mesh and texture
/// paths), and the parsed scene. Edits go through the text, so what renders is always what
/// `toml` says, and an edit the parser refuses changes nothing.
#[pyclass(module = "photonix")]
#[derive(Clone)]
pub struct Scene {
    path: PathBuf,
    /// The file read: the TOML itself, or the POV-Ray, glTF or Mitsuba file translated to it.
    source: PathBuf,
    text: String,
    scene: photonix::scene::Scene,
}

fn scene_error(e: impl std::fmt::Display) -> PyErr {
    SceneError::new_err(e.to_string())
}

impl Scene {
    fn parse(text: String, path: PathBuf) -> PyResult<Scene> {
        let scene = photonix::scene::parse_scene(&text, &path).map_err(scene_error)?;
        Ok(Scene { source: path.clone(), path, text, scene })
    }

    /// Parses `doc` as this scene's new text: on a SceneError the scene is unchanged.
    fn reparse(&mut self, doc: &DocumentMut) -> PyResult<()> {
        let source = self.source.clone();
        *self = Scene::parse(doc.to_string(), self.path.clone())?;
        self.source = source;
        Ok(())
    }
}

#[pymethods]
impl Scene {
    /// The scene's TOML text, with every edit made so far.
    #[getter]
    fn toml(&self) -> String {
        self.text.clone()
    }

    /// The file the scene was read from (or named after, for `loads`).
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// The scene's name: its file name without the extension.
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The camera's image size as (width, height).
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        (self.scene.camera.width, self.scene.camera.height)
    }

    /// Warnings the parser gave (settings that have no effect, and the like).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.scene.warnings.clone()
    }

    /// The value at a scene path, e.g. `materials.red.reflectance`, `camera.position`,
    /// `lights[0].radiance` or `shapes[floor].material` (brackets pick an entry of an array of
    /// tables by position or by its `name`). Raises KeyError when nothing is there.
    fn get(&self, py: Python<'_>, path: &str) -> PyResult<Py<PyAny>> {
        let doc = self.document()?;
        let steps = parse_scene_path(path)?;
        let node = lookup(doc.as_item(), &steps, path)?;
        node_to_py(py, &node)
    }

    /// Sets the value at a scene path (see `get`): a number, a bool, a string, or a list of
    /// them (e.g. a colour `[0.8, 0.1, 0.1]`); `None` removes the key. The new text is parsed
    /// like any scene file; on a SceneError the scene is unchanged. The last step may name a
    /// key that is not there yet (it is added).
    fn set(&mut self, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut doc = self.document()?;
        set_in(&mut doc, path, value)?;
        self.reparse(&doc)
    }

    /// Sets several scene paths at once (a list of (path, value), as `set`), parsing once: all
    /// of them change, or on an error none. What `traverse(...).update()` calls.
    fn set_many(&mut self, edits: Vec<(String, Bound<'_, PyAny>)>) -> PyResult<()> {
        let mut doc = self.document()?;
        for (path, value) in &edits {
            set_in(&mut doc, path, value)?;
        }
        self.reparse(&doc)
    }

    /// Adds an entry: to an array of tables (`add("shapes", {...})`, `add("lights", {...})`,
    /// appended as a table), or a new key of a table (`add("materials.blue", {...})`; refused
    /// when it is there already: use `set` to replace it). Parsed like any edit: a SceneError
    /// leaves the scene unchanged.
    fn add(&mut self, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let mut doc = self.document()?;
        let steps = parse_scene_path(path)?;
        let (last, parents) = steps.split_last().expect("parse_scene_path returns at least one step");
        let Step::Key(key) = last else {
            return Err(PyValueError::new_err(format!(
                "scene path `{path}` ends in an array entry; name the array to add to (e.g. `shapes`)"
            )));
        };
        let table = lookup_table_mut(doc.as_item_mut(), parents, path)?;
        match table.get_mut(key) {
            Some(item) if item.is_array_of_tables() => {
                let entry = py_to_table(value, path)?;
                item.as_array_of_tables_mut().expect("checked to be an array of tables").push(entry);
            }
            Some(_) => {
                return Err(PyValueError::new_err(format!(
                    "scene path `{path}` is there already; `set` replaces it, `remove` removes it"
                )))
            }
            None if value.cast::<PyDict>().is_ok() && parents.is_empty() && ARRAYS.contains(&key.as_str()) => {
                let mut array = toml_edit::ArrayOfTables::new();
                array.push(py_to_table(value, path)?);
                table.insert(key, Item::ArrayOfTables(array));
            }
            None => {
                let item = match value.cast::<PyDict>() {
                    Ok(_) => Item::Table(py_to_table(value, path)?),
                    Err(_) => Item::Value(py_to_value(value, path, 0)?),
                };
                table.insert(key, item);
            }
        }
        self.reparse(&doc)
    }

    /// Removes what a scene path names: a key (`materials.blue`, `camera.fov`) or an entry of
    /// an array of tables (`shapes[floor]`, `lights[0]`). A removal the parser refuses (a
    /// material a shape still uses) raises SceneError and changes nothing.
    fn remove(&mut self, path: &str) -> PyResult<()> {
        let mut doc = self.document()?;
        let steps = parse_scene_path(path)?;
        match steps.as_slice() {
            [parents @ .., Step::Key(key), entry @ (Step::Index(_) | Step::Name(_))] => {
                let table = lookup_table_mut(doc.as_item_mut(), parents, path)?;
                let array = table.get_mut(key).and_then(Item::as_array_of_tables_mut).ok_or_else(|| {
                    pyo3::exceptions::PyKeyError::new_err(format!(
                        "scene path `{path}`: `{key}` is not an array of tables"
                    ))
                })?;
                let index = match entry {
                    Step::Index(i) => (*i < array.len()).then_some(*i),
                    Step::Name(name) => array.iter().position(|t| has_name(t, name)),
                    Step::Key(_) => unreachable!("matched as an entry"),
                };
                let names: Vec<String> = array
                    .iter()
                    .enumerate()
                    .map(|(i, t)| t.get("name").and_then(|n| n.as_str()).map_or(format!("[{i}]"), |n| format!("[{n}]")))
                    .collect();
                let index = index.ok_or_else(|| {
                    pyo3::exceptions::PyKeyError::new_err(format!(
                        "scene path `{path}`: no such entry (there is {})",
                        names.join(", ")
                    ))
                })?;
                array.remove(index);
                if array.is_empty() {
                    table.remove(key);
                }
            }
            [parents @ .., Step::Key(key)] => {
                let table = lookup_table_mut(doc.as_item_mut(), parents, path)?;
                if table.remove(key).is_none() {
                    return Err(pyo3::exceptions::PyKeyError::new_err(format!(
                        "scene path `{path}`: there is no `{key}` to remove"
                    )));
                }
            }
            _ => {
                return Err(PyValueError::new_err(format!(
                    "scene path `{path}`: name a key or an array entry to remove"
                )))
            }
        }
        self.reparse(&doc)
    }

    /// The whole scene as nested dicts and lists (tables, arrays of tables, values), as `get`
    /// gives each part: what `traverse` walks, and what `load_dict` takes back.
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let doc = self.document()?;
        node_to_py(py, &Node::Item(doc.as_item()))
    }

    /// The file that was read: the TOML itself, or the POV-Ray, glTF or Mitsuba scene that
    /// `load` translated (then `path` is the TOML's name beside it, where `save` would put it).
    #[getter]
    fn source(&self) -> PathBuf {
        self.source.clone()
    }

    fn __getitem__(&self, py: Python<'_>, path: &str) -> PyResult<Py<PyAny>> {
        self.get(py, path)
    }

    fn __setitem__(&mut self, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set(path, value)
    }

    /// A copy that can be edited without changing this one.
    fn copy(&self) -> Scene {
        self.clone()
    }

    /// Writes the TOML text to `path` (mesh and texture paths stay relative to the scene's
    /// folder, so save next to the original to keep them valid).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        std::fs::write(&path, &self.text)
            .map_err(|e| PhotonixError::new_err(format!("cannot write {}: {e}", path.display())))
    }

    fn __repr__(&self) -> String {
        format!(
            "<photonix.Scene {:?} from {} ({}x{})>",
            self.scene.name,
            self.path.display(),
            self.scene.camera.width,
            self.scene.camera.height
        )
    }
}

/// The top-level arrays of tables of the scene format (docs/scene-format.md).
const ARRAYS: [&str; 3] = ["shapes", "lights", "instances"];

/// `Scene.set` on a document: sets (or with None removes) the value at `path`.
fn set_in(doc: &mut DocumentMut, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
    {
        let steps = parse_scene_path(path)?;
        let (last, parents) = steps.split_last().expect("parse_scene_path returns at least one step");
        let Step::Key(key) = last else {
            return Err(PyValueError::new_err(format!(
                "scene path `{path}` ends in an array entry; name the field to set (e.g. `{path}.radiance`)"
            )));
        };
        let table = lookup_table_mut(doc.as_item_mut(), parents, path)?;
        if value.is_none() {
            if table.remove(key).is_none() {
                return Err(pyo3::exceptions::PyKeyError::new_err(format!(
                    "scene path `{path}`: there is no `{key}` to remove"
                )));
            }
        } else {
            let new = py_to_value(value, path, 0)?;
            // Keep the old value's comment and spacing where there was one.
            match table.get_mut(key) {
                Some(Item::Value(old)) => {
                    let decor = old.decor().clone();
                    *old = new;
                    *old.decor_mut() = decor;
                }
                _ => {
                    table.insert(key, Item::Value(new));
                }
            }
        }
    }
    Ok(())
}

/// A dict as a table: a list of dicts in it becomes an array of tables (`[[shapes.children]]`),
/// a dict an inline table, anything else a value (`py_to_value`).
fn py_to_table(value: &Bound<'_, PyAny>, path: &str) -> PyResult<toml_edit::Table> {
    let dict = value.cast::<PyDict>().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "scene path `{path}`: an entry is a dict of its fields, not a {}",
            value.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        ))
    })?;
    let mut table = toml_edit::Table::new();
    for (k, v) in dict.iter() {
        let key: String = k
            .extract()
            .map_err(|_| PyValueError::new_err(format!("scene path `{path}`: a table's keys must be strings")))?;
        let inner = format!("{path}.{key}");
        table.insert(&key, py_to_item(&v, &inner, 2)?);
    }
    Ok(table)
}

/// A Python value as a TOML item for `load_dict`: the top-level dicts and the dicts in them
/// (`camera`, `materials`, `materials.red`) as tables, lists of dicts as arrays of tables
/// (`shapes`, `lights`), deeper dicts as inline tables, the rest as values.
fn py_to_item(value: &Bound<'_, PyAny>, path: &str, depth: usize) -> PyResult<Item> {
    if let Ok(dict) = value.cast::<PyDict>() {
        if depth >= 2 {
            return Ok(Item::Value(py_to_value(value, path, 0)?));
        }
        let mut table = toml_edit::Table::new();
        let mut only_tables = !dict.is_empty();
        for (k, v) in dict.iter() {
            let key: String = k
                .extract()
                .map_err(|_| PyValueError::new_err(format!("scene path `{path}`: a table's keys must be strings")))?;
            let item = py_to_item(&v, &format!("{path}.{key}"), depth + 1)?;
            only_tables &= item.is_table();
            table.insert(&key, item);
        }
        // `[materials]` with nothing but `[materials.red]`, ... under it needs no header.
        table.set_implicit(only_tables);
        return Ok(Item::Table(table));
    }
    if let Ok(list) = value.cast::<PyList>() {
        if !list.is_empty() && list.iter().all(|v| v.cast::<PyDict>().is_ok()) {
            let mut array = toml_edit::ArrayOfTables::new();
            for (i, v) in list.iter().enumerate() {
                array.push(py_to_table(&v, &format!("{path}[{i}]"))?);
            }
            return Ok(Item::ArrayOfTables(array));
        }
    }
    Ok(Item::Value(py_to_value(value, path, 0)?))
}

impl Scene {
    fn document(&self) -> PyResult<DocumentMut> {
        self.text.parse().map_err(|e| scene_error(format!("{}: {e}", self.path.display())))
    }
}

/// One step of a scene path: a key of a table, or an entry of an array of tables by position
/// or by `name`.
#[derive(Debug)]
enum Step {
    Key(String),
    Index(usize),
    Name(String),
}

/// Splits `materials.red.reflectance` or `lights[0].radiance` or `shapes[tall block].material`
/// into steps. Keys are split at dots; brackets hold a position or a `name`.
fn parse_scene_path(path: &str) -> PyResult<Vec<Step>> {
    let bad = |why: &str| {
        PyValueError::new_err(format!(
            "scene path `{path}` {why}; write it as table keys joined by dots, with [N] or [name] for an entry of \
             an array (e.g. `materials.red.reflectance`, `lights[0].radiance`)"
        ))
    };
    let mut steps = Vec::new();
    for part in path.split('.') {
        let (key, mut rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if key.is_empty() && (steps.is_empty() || rest.is_empty()) {
            return Err(bad("has an empty key"));
        }
        if !key.is_empty() {
            steps.push(Step::Key(key.to_string()));
        }
        while !rest.is_empty() {
            let close = rest.find(']').ok_or_else(|| bad("has a `[` without its `]`"))?;
            let inside = rest[1..close].trim();
            if inside.is_empty() {
                return Err(bad("has empty brackets"));
            }
            let inside = inside.trim_matches('"');
            steps.push(match inside.parse::<usize>() {
                Ok(i) => Step::Index(i),
                Err(_) => Step::Name(inside.to_string()),
            });
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return Err(bad("has text after a `]` that is not a `.`"));
            }
        }
    }
    if steps.is_empty() {
        return Err(bad("is empty"));
    }
    Ok(steps)
}

fn describe(steps: &[Step]) -> String {
    let mut s = String::new();
    for step in steps {
        match step {
            Step::Key(k) if s.is_empty() => s.push_str(k),
            Step::Key(k) => {
                s.push('.');
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
            Step::Name(n) => s.push_str(&format!("[{n}]")),
        }
    }
    s
}

fn missing(path: &str, steps: &[Step], i: usize, keys: Vec<String>) -> PyErr {
    let what = describe(&steps[..=i]);
    let hint = if keys.is_empty() { String::new() } else { format!(" (there is {})", keys.join(", ")) };
    pyo3::exceptions::PyKeyError::new_err(format!("scene path `{path}`: no `{what}` in the scene{hint}"))
}

/// Where a walk along a scene path stands: an item of a table, or an entry of an array of
/// tables (a `Table`, which toml_edit does not hold as an `Item`).
enum Node<'a> {
    Item(&'a Item),
    Table(&'a toml_edit::Table),
}

enum NodeMut<'a> {
    Item(&'a mut Item),
    Table(&'a mut toml_edit::Table),
}

impl<'a> Node<'a> {
    fn table_like(&self) -> Option<&'a dyn toml_edit::TableLike> {
        match *self {
            Node::Item(item) => item.as_table_like(),
            Node::Table(table) => Some(table),
        }
    }
    fn array(&self) -> Option<&'a toml_edit::ArrayOfTables> {
        match *self {
            Node::Item(item) => item.as_array_of_tables(),
            Node::Table(_) => None,
        }
    }
}

/// The names of the entries of an array of tables, or the keys of a table, for a message.
fn choices(node: &Node<'_>) -> Vec<String> {
    if let Some(array) = node.array() {
        return array
            .iter()
            .enumerate()
            .map(|(i, t)| match t.get("name").and_then(|n| n.as_str()) {
                Some(name) => format!("[{i}] or [{name}]"),
                None => format!("[{i}]"),
            })
            .collect();
    }
    if let Some(table) = node.table_like() {
        return table.iter().map(|(k, _)| format!("`{k}`")).collect();
    }
    Vec::new()
}

fn has_name(table: &toml_edit::Table, name: &str) -> bool {
    table.get("name").and_then(|v| v.as_str()) == Some(name)
}

fn lookup<'a>(root: &'a Item, steps: &[Step], path: &str) -> PyResult<Node<'a>> {
    let mut node = Node::Item(root);
    for (i, step) in steps.iter().enumerate() {
        let next = match step {
            Step::Key(k) => node.table_like().and_then(|t| t.get(k)).map(Node::Item),
            Step::Index(n) => node.array().and_then(|a| a.get(*n)).map(Node::Table),
            Step::Name(name) => node.array().and_then(|a| a.iter().find(|t| has_name(t, name))).map(Node::Table),
        };
        node = next.ok_or_else(|| missing(path, steps, i, choices(&node)))?;
    }
    Ok(node)
}

/// `lookup` for writing: the table named by `steps`.
fn lookup_table_mut<'a>(root: &'a mut Item, steps: &[Step], path: &str) -> PyResult<&'a mut dyn toml_edit::TableLike> {
    let mut node = NodeMut::Item(root);
    for (i, step) in steps.iter().enumerate() {
        let keys = choices(&match &node {
            NodeMut::Item(item) => Node::Item(item),
            NodeMut::Table(table) => Node::Table(table),
        });
        let next = match (node, step) {
            (NodeMut::Item(item), Step::Key(k)) => {
                item.as_table_like_mut().and_then(|t| t.get_mut(k)).map(NodeMut::Item)
            }
            (NodeMut::Table(table), Step::Key(k)) => table.get_mut(k).map(NodeMut::Item),
            (NodeMut::Item(item), Step::Index(n)) => {
                item.as_array_of_tables_mut().and_then(|a| a.get_mut(*n)).map(NodeMut::Table)
            }
            (NodeMut::Item(item), Step::Name(name)) => {
                item.as_array_of_tables_mut().and_then(|a| a.iter_mut().find(|t| has_name(t, name))).map(NodeMut::Table)
            }
            (NodeMut::Table(_), _) => None,
        };
        node = next.ok_or_else(|| missing(path, steps, i, keys))?;
    }
    let what = describe(steps);
    match node {
        NodeMut::Item(item) => item
            .as_table_like_mut()
            .ok_or_else(|| PyValueError::new_err(format!("scene path `{path}`: `{what}` is not a table"))),
        NodeMut::Table(table) => Ok(table),
    }
}

// ---------------------------------------------------------------------------------------------
// TOML values <-> Python

fn node_to_py(py: Python<'_>, node: &Node<'_>) -> PyResult<Py<PyAny>> {
    match *node {
        Node::Item(Item::Value(v)) => value_to_py(py, v),
        Node::Item(Item::ArrayOfTables(a)) => {
            let list = PyList::empty(py);
            for table in a.iter() {
                list.append(node_to_py(py, &Node::Table(table))?)?;
            }
            Ok(list.into_any().unbind())
        }
        Node::Item(Item::None) => Ok(py.None()),
        _ => {
            let dict = PyDict::new(py);
            for (k, v) in node.table_like().expect("a table or an inline table").iter() {
                dict.set_item(k, node_to_py(py, &Node::Item(v))?)?;
            }
            Ok(dict.into_any().unbind())
        }
    }
}

fn value_to_py(py: Python<'_>, value: &Value) -> PyResult<Py<PyAny>> {
    Ok(match value {
        Value::String(s) => s.value().into_pyobject(py)?.into_any().unbind(),
        Value::Integer(i) => i.value().into_pyobject(py)?.into_any().unbind(),
        Value::Float(f) => f.value().into_pyobject(py)?.into_any().unbind(),
        Value::Boolean(b) => PyBool::new(py, *b.value()).to_owned().into_any().unbind(),
        Value::Datetime(d) => d.value().to_string().into_pyobject(py)?.into_any().unbind(),
        Value::Array(a) => {
            let list = PyList::empty(py);
            for v in a.iter() {
                list.append(value_to_py(py, v)?)?;
            }
            list.into_any().unbind()
        }
        Value::InlineTable(t) => {
            let dict = PyDict::new(py);
            for (k, v) in t.iter() {
                dict.set_item(k, value_to_py(py, v)?)?;
            }
            dict.into_any().unbind()
        }
    })
}

/// A Python value as a TOML value: bool, int, float, str, a sequence of them (lists, tuples,
/// numpy arrays), or a dict (an inline table).
fn py_to_value(value: &Bound<'_, PyAny>, path: &str, depth: usize) -> PyResult<Value> {
    if depth > 8 {
        return Err(PyValueError::new_err(format!("scene path `{path}`: the value is nested more than 8 deep")));
    }
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(Value::from(b.is_true()));
    }
    if value.is_instance_of::<PyInt>() {
        let i: i64 = value.extract()?;
        return Ok(Value::from(i));
    }
    if value.is_instance_of::<PyFloat>() {
        let f: f64 = value.extract()?;
        if !f.is_finite() {
            return Err(PyValueError::new_err(format!("scene path `{path}`: {f} is not a finite number")));
        }
        return Ok(Value::from(f));
    }
    if value.is_instance_of::<PyString>() {
        let s: String = value.extract()?;
        return Ok(Value::from(s));
    }
    if let Ok(d) = value.cast::<PyDict>() {
        let mut table = toml_edit::InlineTable::new();
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| PyValueError::new_err(format!("scene path `{path}`: a table's keys must be strings")))?;
            table.insert(&key, py_to_value(&v, path, depth + 1)?);
        }
        return Ok(Value::InlineTable(table));
    }
    // numpy scalars (np.float32(0.5)) and anything else with __float__ or __index__.
    if value.hasattr("dtype")? && value.getattr("ndim")?.extract::<usize>()? == 0 {
        return py_to_value(&value.call_method0("item")?, path, depth);
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() || value.hasattr("tolist")? {
        let list = if value.hasattr("tolist")? { value.call_method0("tolist")? } else { value.clone() };
        let mut array = toml_edit::Array::new();
        for v in list.try_iter()? {
            array.push(py_to_value(&v?, path, depth + 1)?);
        }
        return Ok(Value::Array(array));
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "scene path `{path}`: cannot put a {} in a scene; give a number, bool, string, list or dict",
        value.get_type().name()?
    )))
}

// ---------------------------------------------------------------------------------------------
// Rendering

/// A render's settings, checked; what `photonix render`'s flags carry.
#[derive(Clone)]
struct Job {
    scene: photonix::scene::Scene,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    max_depth: u32,
    photons: Option<PhotonSettings>,
    budget: Budget,
    backend: BackendChoice,
    device: Option<String>,
    /// Render the feature layers too (`denoise=True`, `aovs=True`).
    features: bool,
}

#[derive(Clone, Copy, PartialEq)]
enum BackendChoice {
    Auto,
    Gpu,
    Cpu,
}

/// What the worker reports to the waiting thread.
enum Event {
    /// (pass, passes finished, paths done in this pass, paths in this pass)
    Progress(u32, u32, u64, u64),
}

/// A finished render.
struct Outcome {
    acc: Accumulator,
    reason: StopReason,
    provenance: Provenance,
    backend: Backend,
    why: String,
    device: String,
    seconds: f64,
    /// Seconds spent opening the device and making (or updating) the renderer.
    setup_seconds: f64,
    /// Whether a kept renderer was given the scene (no new kernels, no new device).
    reused: bool,
}

enum Failure {
    Render(String),
    Scene(String),
}

impl From<Failure> for PyErr {
    fn from(f: Failure) -> PyErr {
        match f {
            Failure::Render(m) => RenderError::new_err(m),
            Failure::Scene(m) => SceneError::new_err(m),
        }
    }
}

fn render_failure(e: impl std::fmt::Display) -> Failure {
    Failure::Render(e.to_string())
}

/// The backend a render (or a kept `Renderer`) runs on, chosen and opened once: the device
/// context when it is a GPU, with the seconds opening it took.
struct Opened {
    ctx: Option<GpuContext>,
    backend: Backend,
    why: String,
    open_seconds: f64,
}

/// Chooses the backend as `photonix render` does and opens the device; auto falls back to the
/// CPU backend when the GPU will not open.
fn open_backend(choice: BackendChoice, device: Option<String>) -> Result<Opened, Failure> {
    let t = Instant::now();
    let options = GpuOptions::from_env(device.clone()).map_err(render_failure)?;
    let (backend, why) = match choice {
        BackendChoice::Gpu => (Backend::Gpu, "backend=\"gpu\"".to_string()),
        BackendChoice::Cpu => (Backend::Cpu, "backend=\"cpu\"".to_string()),
        BackendChoice::Auto => {
            let (backend, why) = auto_backend(&list_devices(), device.is_some());
            (backend, format!("auto: {why}"))
        }
    };
    let opened = |ctx, backend, why| Opened { ctx, backend, why, open_seconds: t.elapsed().as_secs_f64() };
    match backend {
        Backend::Cpu => Ok(opened(None, backend, why)),
        Backend::Gpu => match GpuContext::new(&options) {
            Ok(ctx) => Ok(opened(Some(ctx), backend, why)),
            Err(_) if choice == BackendChoice::Auto && device.is_none() => {
                Ok(opened(None, Backend::Cpu, "auto: the GPU failed to open".to_string()))
            }
            Err(e) => Err(render_failure(e)),
        },
    }
}

/// A renderer kept from one render to the next on the same backend, with the image size it was
/// made for (a new size makes a new one; the device and its context stay).
type Kept<'a> = Option<(Renderer<'a>, (u32, u32))>;

/// Runs `job` on the calling thread (the worker), as `photonix render` does: memory checks,
/// prepare, then the progressive passes, on `opened`'s backend. With a renderer in `kept` it is
/// given the new scene (`update_scene`: the kernels stay, only the arrays that changed are
/// written) instead of being made anew; `setup_seconds` in the outcome is what that took.
fn run_on<'a>(
    job: &Job,
    opened: &'a Opened,
    kept: &mut Kept<'a>,
    stop: Arc<AtomicBool>,
    events: mpsc::Sender<Event>,
) -> Result<Outcome, Failure> {
    photonix::render::set_thread_stop_flag(Some(stop));
    photonix::render::set_thread_stop_paths(Some(STOP_CHECK_PATHS));
    let start = Instant::now();
    let settings = FrameSettings { width: job.width, height: job.height, max_depth: job.max_depth, seed: job.seed };
    let photons = job.photons.as_ref();
    let estimate = |limit| memory::estimate(job.width, job.height, photons, limit);
    let host = estimate((opened.backend == Backend::Gpu).then_some(u64::MAX));
    check_fits(&host, job.width, job.height, photons, available_host_memory(), None).map_err(render_failure)?;

    let buffers = prepare(&job.scene, &settings).map_err(|e| Failure::Scene(e.to_string()))?;
    if let Some(p) = photons {
        check_radii(&buffers, p).map_err(render_failure)?;
    }
    if let Some(ctx) = &opened.ctx {
        let info = ctx.info();
        let limit = info.max_storage_buffer_range.min(info.max_memory_allocation_size);
        if let Some(p) = photons {
            memory::check_photon_buffer(p, limit).map_err(render_failure)?;
        }
        let device = estimate(Some(limit));
        check_fits(&device, job.width, job.height, photons, None, Some(info.device_local_heap_bytes))
            .map_err(render_failure)?;
    }
    let provenance = Provenance::new(&buffers, job.spp, photons);
    let setup = Instant::now();
    let size = (job.width, job.height);
    let reused = match kept.as_mut() {
        Some((renderer, kept_size)) if *kept_size == size => {
            // A failed update leaves a renderer that must not be used again.
            if let Err(e) = renderer.update_scene(&buffers, photons) {
                *kept = None;
                return Err(render_failure(e));
            }
            true
        }
        _ => false,
    };
    if !reused {
        *kept = None;
        *kept = Some((Renderer::new(opened.ctx.as_ref(), &buffers, photons).map_err(render_failure)?, size));
    }
    let setup_seconds = setup.elapsed().as_secs_f64();
    let renderer = &mut kept.as_mut().expect("made above").0;
    renderer.set_features(job.features);
    let mut device = String::new();
    let passes_done = std::cell::Cell::new(0u32);
    let max_group = renderer.max_pass_group(job.spp);
    let result = render_progressive(
        job.width,
        job.height,
        &job.budget,
        max_group,
        |pass, most, pixels| {
            let mut progress = |done: u64, total: u64| {
                // The waiting thread may be gone (an exception there); the render then stops
                // by its flag.
                let _ = events.send(Event::Progress(pass, passes_done.get(), done, total));
            };
            renderer.set_pixels(pixels.cloned());
            let out = renderer.render_passes(job.spp, pass, most, &mut progress).map_err(render_failure)?;
            device.clone_from(&out.stats.device);
            Ok(out)
        },
        |acc, _| {
            passes_done.set(acc.passes);
            let last = acc.ranges.last().map_or(0, |r| r.1.saturating_sub(1));
            let _ = events.send(Event::Progress(last, acc.passes, 1, 1));
            Ok::<(), Failure>(())
        },
    );
    // A device error mid-render may leave the kept renderer unusable: make a new one next time.
    let (acc, reason) = result.inspect_err(|_| *kept = None)?;
    Ok(Outcome {
        acc,
        reason,
        provenance,
        backend: opened.backend,
        why: opened.why.clone(),
        device,
        seconds: start.elapsed().as_secs_f64(),
        setup_seconds,
        reused,
    })
}

/// A render with nothing kept: opens the backend, renders, and lets everything go.
fn run_job(job: &Job, stop: Arc<AtomicBool>, events: mpsc::Sender<Event>) -> Result<Outcome, Failure> {
    let opened = open_backend(job.backend, job.device.clone())?;
    let mut kept = None;
    let mut outcome = run_on(job, &opened, &mut kept, stop, events)?;
    outcome.setup_seconds += opened.open_seconds;
    Ok(outcome)
}

// ---------------------------------------------------------------------------------------------
// A kept renderer

/// One render for a `RendererCore`'s thread.
struct Request {
    job: Job,
    stop: Arc<AtomicBool>,
    events: mpsc::Sender<Event>,
    reply: mpsc::Sender<Result<Outcome, Failure>>,
}

/// The thread that owns a kept renderer: it opens the backend once, then renders each request
/// with the renderer of the one before (the device context and the kernels stay). The thread
/// owns them because the renderer borrows the context; it ends, freeing them, when the
/// `RendererCore` is dropped (its request channel closes).
fn renderer_thread(choice: BackendChoice, device: Option<String>, requests: mpsc::Receiver<Request>) {
    let opened = open_backend(choice, device);
    let mut first = true;
    let opened = match &opened {
        Ok(o) => Ok(o),
        Err(Failure::Render(m)) => Err(m.clone()),
        Err(Failure::Scene(m)) => Err(m.clone()),
    };
    let mut kept: Kept<'_> = None;
    for request in requests {
        let outcome = match opened {
            Err(ref message) => Err(Failure::Render(message.clone())),
            Ok(opened) => run_on(&request.job, opened, &mut kept, request.stop, request.events).map(|mut o| {
                if std::mem::take(&mut first) {
                    o.setup_seconds += opened.open_seconds;
                }
                o
            }),
        };
        let _ = request.reply.send(outcome);
    }
}

/// The compiled half of `photonix.Renderer`: a render thread keeping the backend, the device and
/// the kernels from one render to the next, and the stop flag of the render under way, which
/// `cancel` sets from any thread. Frozen (no `&mut self`): `render` on one thread and `cancel`
/// on another never meet a borrow error.
#[pyclass(module = "photonix", frozen)]
pub struct RendererCore {
    requests: std::sync::Mutex<Option<mpsc::Sender<Request>>>,
    worker: std::sync::Mutex<Option<std::thread::JoinHandle<()>>>,
    /// The stop flag of the render under way, if any.
    current: std::sync::Mutex<Option<Arc<AtomicBool>>>,
    /// Renders waiting for the thread or under way: one at a time runs, the others queue.
    busy: std::sync::Mutex<()>,
    backend: BackendChoice,
    device: Option<String>,
}

#[pymethods]
impl RendererCore {
    #[new]
    #[pyo3(signature = (backend="auto", device=None))]
    fn new(backend: &str, device: Option<String>) -> PyResult<RendererCore> {
        let choice = parse_backend(backend)?;
        if device.is_some() && choice == BackendChoice::Cpu {
            return Err(PyValueError::new_err(
                "device picks a Vulkan device, but backend=\"cpu\" uses none; leave one of them out",
            ));
        }
        let (sender, receiver) = mpsc::channel();
        let thread_device = device.clone();
        let worker = std::thread::Builder::new()
            .name("photonix-renderer".into())
            .spawn(move || renderer_thread(choice, thread_device, receiver))
            .map_err(|e| RenderError::new_err(format!("cannot start the render thread: {e}")))?;
        Ok(RendererCore {
            requests: std::sync::Mutex::new(Some(sender)),
            worker: std::sync::Mutex::new(Some(worker)),
            current: std::sync::Mutex::new(None),
            busy: std::sync::Mutex::new(()),
            backend: choice,
            device,
        })
    }

    /// Stops the render under way after the submission in progress (it returns the passes
    /// finished, see `photonix.Renderer.cancel`); does nothing when none is. Any thread may call it.
    fn cancel(&self) {
        if let Some(stop) = self.current.lock().expect("the stop flag's lock is not poisoned").as_ref() {
            stop.store(true, Ordering::Relaxed);
        }
    }

    /// Ends the render thread, freeing the device (also done when the renderer is dropped).
    fn close(&self, py: Python<'_>) {
        self.requests.lock().expect("the request lock is not poisoned").take();
        let worker = self.worker.lock().expect("the worker lock is not poisoned").take();
        if let Some(worker) = worker {
            py.detach(|| {
                let _ = worker.join();
            });
        }
    }
}

impl RendererCore {
    /// Sends `job` to the render thread and returns the channel its outcome comes back on, with
    /// the guard that keeps other renders waiting meanwhile.
    fn submit(
        &self,
        job: Job,
        stop: Arc<AtomicBool>,
        events: mpsc::Sender<Event>,
    ) -> Result<mpsc::Receiver<Result<Outcome, Failure>>, Failure> {
        let (reply, outcome) = mpsc::channel();
        let requests = self.requests.lock().expect("the request lock is not poisoned");
        let sender =
            requests.as_ref().ok_or_else(|| Failure::Render("this Renderer was closed; make a new one".into()))?;
        *self.current.lock().expect("the stop flag's lock is not poisoned") = Some(stop.clone());
        sender
            .send(Request { job, stop, events, reply })
            .map_err(|_| Failure::Render("the render thread has ended; make a new Renderer".into()))?;
        Ok(outcome)
    }
}

fn parse_backend(backend: &str) -> PyResult<BackendChoice> {
    match backend {
        "auto" => Ok(BackendChoice::Auto),
        "gpu" => Ok(BackendChoice::Gpu),
        "cpu" => Ok(BackendChoice::Cpu),
        other => Err(PyValueError::new_err(format!("backend={other:?} is not one of \"auto\", \"gpu\", \"cpu\""))),
    }
}

/// Progress of a render, as the callback receives it.
#[pyclass(module = "photonix", get_all, frozen)]
pub struct Progress {
    /// Passes finished so far.
    passes_done: u32,
    /// Passes the budget allows at most (the time or error budget may stop sooner).
    passes_total: u32,
    /// The pass under way (its index, from 0 or the start of the pass range); on a GPU, the first
    /// of the group of consecutive passes under way (passes there come in groups read back once).
    current_pass: u32,
    /// How much of the pass (or group of passes) under way is done, 0 to 1.
    pass_fraction: f64,
    /// Seconds since the render started.
    elapsed: f64,
}

#[pymethods]
impl Progress {
    fn __repr__(&self) -> String {
        format!(
            "Progress(passes_done={}, passes_total={}, current_pass={}, pass_fraction={:.3}, elapsed={:.2})",
            self.passes_done, self.passes_total, self.current_pass, self.pass_fraction, self.elapsed
        )
    }
}

fn check_range(name: &str, value: Option<u32>, min: u32, max: u32) -> PyResult<Option<u32>> {
    match value {
        Some(v) if !(min..=max).contains(&v) => {
            Err(PyValueError::new_err(format!("{name}={v} is out of range; give {name} from {min} to {max}")))
        }
        v => Ok(v),
    }
}

fn image_to_numpy<'py>(py: Python<'py>, image: &Image) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f32> = image.pixels.iter().flatten().copied().collect();
    let array = PyArray1::from_vec(py, flat);
    Ok(array.reshape([image.height as usize, image.width as usize, 3])?.into_any())
}

fn layers_to_dict<'py>(py: Python<'py>, layers: &Layers) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("combined", image_to_numpy(py, &layers.combined())?)?;
    for (name, image) in layers.named() {
        dict.set_item(name, image_to_numpy(py, image)?)?;
    }
    Ok(dict)
}

/// Renders `scene` and returns the mean of the passes as a float32 array of shape
/// (height, width, 3) (linear radiance), or with `layers=True` a dict of such arrays
/// (`combined`, `direct`, `specular`, `indirect`, `caustics`). See `photonix.render`.
#[pyfunction]
#[pyo3(signature = (scene, *, passes=None, time=None, target_error=None, seed=None, backend="auto",
    resolution=None, pass_range=None, layers=false, spp=None, max_depth=None, photons=None,
    caustic_photons=None, radius=None, caustic_radius=None, gather_rays=None, photon_depth=None,
    no_photons=false, device=None, accumulation=None, progress=None, info=None, integrator=None,
    renderer=None, denoise=None, aovs=false, adaptive=None))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, Scene>,
    passes: Option<u32>,
    time: Option<f64>,
    target_error: Option<f64>,
    seed: Option<u32>,
    backend: &str,
    resolution: Option<(u32, u32)>,
    pass_range: Option<(u32, u32)>,
    layers: bool,
    spp: Option<u32>,
    max_depth: Option<u32>,
    photons: Option<u32>,
    caustic_photons: Option<u32>,
    radius: Option<f32>,
    caustic_radius: Option<f32>,
    gather_rays: Option<u32>,
    photon_depth: Option<u32>,
    no_photons: bool,
    device: Option<String>,
    accumulation: Option<PathBuf>,
    progress: Option<Bound<'py, PyAny>>,
    info: Option<Bound<'py, PyDict>>,
    integrator: Option<&str>,
    renderer: Option<Py<RendererCore>>,
    denoise: Option<bool>,
    aovs: bool,
    adaptive: Option<bool>,
) -> PyResult<Bound<'py, PyAny>> {
    // Check every argument before any work, with the command line's ranges.
    let backend = parse_backend(backend)?;
    if let Some(core) = &renderer {
        let core = core.get();
        if core.backend != backend || core.device != device {
            return Err(PyValueError::new_err(
                "a kept renderer renders on the backend and device it was made with; leave backend and device out",
            ));
        }
    }
    if device.is_some() && backend == BackendChoice::Cpu {
        return Err(PyValueError::new_err(
            "device picks a Vulkan device, but backend=\"cpu\" uses none; leave one of them out",
        ));
    }
    check_range("passes", passes, 1, MAX_PASSES)?;
    check_range("spp", spp, 1, MAX_SPP)?;
    check_range("max_depth", max_depth, 1, MAX_DEPTH)?;
    check_range("photon_depth", photon_depth, 1, MAX_DEPTH)?;
    check_range("photons", photons, 1, MAX_PHOTON_PATHS)?;
    check_range("caustic_photons", caustic_photons, 1, MAX_PHOTON_PATHS)?;
    check_range("gather_rays", gather_rays, 0, MAX_GATHER_RAYS)?;
    let time = match time {
        Some(t) if !(t.is_finite() && (1e-3..=photonix::limits::MAX_DURATION_SECONDS).contains(&t)) => {
            return Err(PyValueError::new_err(format!("time={t} is out of range; give seconds from 0.001 to 31536000")))
        }
        t => t.map(Duration::from_secs_f64),
    };
    if let Some(e) = target_error.filter(|e| !(e.is_finite() && *e > 0.0 && *e <= photonix::limits::MAX_TARGET_ERROR)) {
        return Err(PyValueError::new_err(format!(
            "target_error={e} is out of range; give a relMSE above 0, at most 1000"
        )));
    }
    for (name, r) in [("radius", radius), ("caustic_radius", caustic_radius)] {
        if let Some(r) = r.filter(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(PyValueError::new_err(format!("{name}={r} is not a positive number of scene units")));
        }
    }
    if let Some((w, h)) = resolution {
        let side = 1..=MAX_IMAGE_SIDE;
        if !side.contains(&w) || !side.contains(&h) || w as u64 * h as u64 > MAX_PIXELS {
            return Err(PyValueError::new_err(format!(
                "resolution=({w}, {h}) is out of range; give sizes from 1 to {MAX_IMAGE_SIDE}, at most {MAX_PIXELS} pixels"
            )));
        }
    }
    if let Some((a, b)) = pass_range {
        if a >= b || b > MAX_PASSES {
            return Err(PyValueError::new_err(format!(
                "pass_range=({a}, {b}) is not a range A..B with A < B <= {MAX_PASSES}"
            )));
        }
        if passes.is_some() {
            return Err(PyValueError::new_err("passes and pass_range both choose passes; give one of them"));
        }
    }
    if let Some(path) = &accumulation {
        if !path.to_string_lossy().to_ascii_lowercase().ends_with(".exr") {
            return Err(PyValueError::new_err(format!(
                "accumulation={:?}: an accumulation file is an EXR; give a name ending in .exr",
                path.display().to_string()
            )));
        }
        photonix::io::check_output_path(path).map_err(|e| ImageError::new_err(e.to_string()))?;
    }
    let photon_flags = [
        ("photons", photons.is_some()),
        ("caustic_photons", caustic_photons.is_some()),
        ("radius", radius.is_some()),
        ("caustic_radius", caustic_radius.is_some()),
        ("gather_rays", gather_rays.is_some()),
        ("photon_depth", photon_depth.is_some()),
    ];
    let given: Vec<&str> = photon_flags.iter().filter_map(|(n, on)| on.then_some(*n)).collect();
    // The scene as it is now, borrowed only for this copy: another thread may edit it while
    // this one renders (the render is of the scene as it was when it started).
    let mut s = scene
        .try_borrow()
        .map_err(|_| SceneError::new_err("the scene is being edited; render it after the edit"))?
        .scene
        .clone();
    if let Some(name) = integrator {
        let named = match name {
            Integrator::AUTO => None,
            _ => Some(Integrator::from_name(name).ok_or_else(|| {
                let names: Vec<&str> = Integrator::NAMES.iter().map(|(n, _)| *n).collect();
                PyValueError::new_err(format!("integrator={name:?} is not one of {}, auto", names.join(", ")))
            })?),
        };
        s.set_integrator(named);
    }
    if !given.is_empty() || no_photons {
        s.photon_options_given();
    }
    let s = &s;
    let photon_settings = if !s.render.integrator.uses_photons() {
        if let Some(flag) = given.first().copied().or(no_photons.then_some("no_photons")) {
            return Err(PyValueError::new_err(format!(
                "the {} integrator uses no photon maps, so {flag} would be ignored; leave it out, or use integrator=\"ppm\"",
                s.render.integrator.name()
            )));
        }
        None
    } else if no_photons {
        if !given.is_empty() {
            return Err(PyValueError::new_err(format!(
                "no_photons renders without photon maps, so {} would be ignored; give one or the other",
                given.join(", ")
            )));
        }
        None
    } else if s.photons.is_none() && given.is_empty() {
        None
    } else {
        let mut p = s.photons.unwrap_or_default();
        p.photons = photons.unwrap_or(p.photons);
        p.caustic_photons = caustic_photons.unwrap_or(p.caustic_photons);
        p.radius = radius.or(p.radius);
        p.caustic_radius = caustic_radius.or(p.caustic_radius);
        p.gather_rays = gather_rays.unwrap_or(p.gather_rays);
        p.max_depth = photon_depth.unwrap_or(p.max_depth);
        Some(p)
    };
    let (first, end) = match (pass_range, passes) {
        (Some((a, b)), _) => (a, b),
        (None, Some(n)) => (0, n),
        (None, None) if time.is_some() || target_error.is_some() => (0, MAX_PASSES),
        (None, None) => (0, s.render.passes),
    };
    let (width, height) = resolution.unwrap_or((s.camera.width, s.camera.height));
    let denoise = denoise.unwrap_or(s.render.denoise);
    // Load the library before the render, so that a missing one fails now, not after it.
    if denoise {
        photonix::gpu::oidn::available().map_err(|e| RenderError::new_err(e.to_string()))?;
    }
    let job = Job {
        scene: s.clone(),
        width,
        height,
        spp: spp.unwrap_or(s.render.spp),
        seed: seed.unwrap_or(s.render.seed),
        max_depth: max_depth.unwrap_or(s.render.max_depth),
        photons: photon_settings,
        budget: Budget { first, end, time, target_error, adaptive: adaptive.unwrap_or(s.render.adaptive) },
        backend,
        device,
        features: denoise || aovs,
    };

    // Render on a worker; this thread waits without the GIL, taking it back every POLL for
    // the signal handlers and the progress callback.
    let stop = Arc::new(AtomicBool::new(false));
    let progress = progress.map(Bound::unbind);
    let started = Instant::now();
    let (result, raised) = py.detach(|| {
        std::thread::scope(|threads| {
            let (sender, receiver) = mpsc::channel();
            let worker_stop = stop.clone();
            // A kept renderer's thread renders one request at a time; `busy` keeps the stop
            // flag that `cancel` sets that of the render under way.
            let core = renderer.as_ref().map(|r| r.get());
            let _busy = core.map(|c| c.busy.lock().unwrap_or_else(|e| e.into_inner()));
            enum Running<'s> {
                Here(std::thread::ScopedJoinHandle<'s, Result<Outcome, Failure>>),
                Kept(Result<mpsc::Receiver<Result<Outcome, Failure>>, Failure>),
            }
            let running = match core {
                Some(core) => Running::Kept(core.submit(job.clone(), worker_stop, sender)),
                None => {
                    let job = &job;
                    Running::Here(threads.spawn(move || run_job(job, worker_stop, sender)))
                }
            };
            let mut raised: Option<PyErr> = None;
            let mut latest: Option<Event> = None;
            loop {
                let finished = match receiver.recv_timeout(POLL) {
                    Ok(event) => {
                        latest = Some(event);
                        // Report only the newest of a burst.
                        while let Ok(event) = receiver.try_recv() {
                            latest = Some(event);
                        }
                        false
                    }
                    Err(mpsc::RecvTimeoutError::Timeout) => false,
                    Err(mpsc::RecvTimeoutError::Disconnected) => true,
                };
                if raised.is_none() {
                    let report = latest.take();
                    let outcome = Python::attach(|py| -> PyResult<()> {
                        py.check_signals()?;
                        if let (Some(callback), Some(Event::Progress(pass, done, part, total))) = (&progress, report) {
                            let report = Progress {
                                passes_done: done,
                                passes_total: end - first,
                                current_pass: pass,
                                pass_fraction: if total == 0 { 0.0 } else { part as f64 / total as f64 },
                                elapsed: started.elapsed().as_secs_f64(),
                            };
                            callback.call1(py, (report,))?;
                        }
                        Ok(())
                    });
                    if let Err(e) = outcome {
                        // Ctrl-C or an exception in the callback: stop the worker after the
                        // submission under way, and keep the passes it finished.
                        stop.store(true, Ordering::Relaxed);
                        raised = Some(e);
                    }
                }
                if finished {
                    break;
                }
            }
            let result = match running {
                Running::Here(worker) => worker.join().expect("the render worker does not panic"),
                Running::Kept(submitted) => submitted.and_then(|outcome| {
                    outcome.recv().unwrap_or_else(|_| {
                        Err(Failure::Render("the render thread has ended; make a new Renderer".into()))
                    })
                }),
            };
            if let Some(core) = core {
                *core.current.lock().unwrap_or_else(|e| e.into_inner()) = None;
            }
            (result, raised)
        })
    });

    let interrupted = raised.as_ref().is_some_and(|e| e.is_instance_of::<PyKeyboardInterrupt>(py));
    if let Some(e) = raised {
        if !interrupted {
            return Err(e);
        }
    }
    let outcome = result?;
    // Stopped with nothing raised here: `Renderer.cancel` from another thread.
    let cancelled = !interrupted && outcome.reason == StopReason::Interrupted;
    if outcome.acc.passes == 0 {
        if interrupted {
            return Err(PyKeyboardInterrupt::new_err("interrupted before the first pass finished; no image"));
        }
        if cancelled {
            return Err(Cancelled::new_err("cancelled before the first pass finished; no image"));
        }
        return Err(RenderError::new_err("no pass finished; no image"));
    }
    if interrupted {
        let warnings = py.import("warnings")?;
        let message = format!(
            "render interrupted: returning the mean of the {} passes finished ({})",
            outcome.acc.passes,
            photonix::render::accumulation::format_ranges(&outcome.acc.ranges)
        );
        warnings.call_method1("warn", (message, py.get_type::<pyo3::exceptions::PyRuntimeWarning>(), 2))?;
    }
    if let Some(path) = &accumulation {
        write_accumulation(path, &outcome.acc, &outcome.provenance).map_err(|e| ImageError::new_err(e.to_string()))?;
    }
    if let Some(info) = &info {
        let reason = match (interrupted, outcome.reason) {
            (true, _) => "interrupted",
            (_, StopReason::Interrupted) => "cancelled",
            (_, StopReason::Passes) => "passes",
            (_, StopReason::Time) => "time",
            (_, StopReason::TargetError) => "target_error",
        };
        info.set_item("passes", outcome.acc.passes)?;
        info.set_item("pass_ranges", outcome.acc.ranges.clone())?;
        info.set_item("stop_reason", reason)?;
        info.set_item("error_estimate", outcome.acc.error_estimate())?;
        info.set_item("backend", outcome.backend.name())?;
        info.set_item("backend_reason", &outcome.why)?;
        info.set_item("device", &outcome.device)?;
        info.set_item("seconds", outcome.seconds)?;
        info.set_item("resolution", (width, height))?;
        info.set_item("spp", job.spp)?;
        info.set_item("integrator", job.scene.render.integrator.name())?;
        info.set_item("integrator_reason", job.scene.render.integrator_auto.map(|why| format!("auto: {why}")))?;
        info.set_item("setup_seconds", outcome.setup_seconds)?;
        info.set_item("renderer_kept", outcome.reused)?;
    }
    let mean = outcome.acc.mean();
    let features = outcome.acc.mean_features();
    let noisy = mean.combined();
    let denoised = if denoise {
        let cuda = photonix::render::denoise::prefers_cuda(&outcome.device);
        let t = Instant::now();
        let image = py
            .detach(|| {
                let mut denoiser = photonix::gpu::oidn::Denoiser::open(cuda)?;
                photonix::render::denoise::denoise_image(&mut denoiser, &noisy, features.as_ref())
            })
            .map_err(|e| RenderError::new_err(e.to_string()))?;
        if let Some(info) = &info {
            info.set_item("denoise_seconds", t.elapsed().as_secs_f64())?;
        }
        Some(image)
    } else {
        None
    };
    if layers || aovs {
        let dict = layers_to_dict(py, &mean)?;
        if let Some(image) = &denoised {
            dict.set_item("combined", image_to_numpy(py, image)?)?;
            dict.set_item("noisy", image_to_numpy(py, &noisy)?)?;
        }
        if let Some(features) = features.as_ref().filter(|_| aovs) {
            for (name, image) in features.named() {
                dict.set_item(name, image_to_numpy(py, image)?)?;
            }
        }
        Ok(dict.into_any())
    } else {
        image_to_numpy(py, denoised.as_ref().unwrap_or(&noisy))
    }
}

// ---------------------------------------------------------------------------------------------
// Files

fn image_error(e: impl std::fmt::Display) -> PyErr {
    ImageError::new_err(e.to_string())
}

fn numpy_to_image(array: &PyReadonlyArray3<'_, f32>, what: &str) -> PyResult<Image> {
    let shape = array.shape();
    if shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
        return Err(PyValueError::new_err(format!(
            "{what} has shape {shape:?}; give an array of shape (height, width, 3)"
        )));
    }
    let (h, w) = (shape[0] as u32, shape[1] as u32);
    let values = array.as_array();
    let mut image = Image::new(w, h);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let (y, x) = (i / w as usize, i % w as usize);
        *p = [values[[y, x, 0]], values[[y, x, 1]], values[[y, x, 2]]];
    }
    Ok(image)
}

/// Writes a float32 (height, width, 3) array of linear radiance to `path`: OpenEXR for `.exr`,
/// 8-bit sRGB for `.png` (scaled by 2^exposure first), atomically.
#[pyfunction]
#[pyo3(signature = (path, image, exposure=0.0))]
fn write_image(path: PathBuf, image: PyReadonlyArray3<'_, f32>, exposure: f32) -> PyResult<()> {
    let image = numpy_to_image(&image, "the image")?;
    photonix::io::check_output_path(&path).map_err(image_error)?;
    photonix::io::write_image(&path, &image, exposure).map_err(image_error)
}

/// Writes named float32 (height, width, 3) arrays as the layers of one OpenEXR file.
#[pyfunction]
fn write_layers(path: PathBuf, layers: Vec<(String, PyReadonlyArray3<'_, f32>)>) -> PyResult<()> {
    let images: Vec<(String, Image)> = layers
        .iter()
        .map(|(name, array)| Ok((name.clone(), numpy_to_image(array, &format!("layer {name:?}"))?)))
        .collect::<PyResult<_>>()?;
    if images.windows(2).any(|w| (w[0].1.width, w[0].1.height) != (w[1].1.width, w[1].1.height)) {
        return Err(PyValueError::new_err("the layers have different sizes; an EXR's layers share one size"));
    }
    let named: Vec<(&str, &Image)> = images.iter().map(|(n, i)| (n.as_str(), i)).collect();
    photonix::io::check_output_path(&path).map_err(image_error)?;
    photonix::io::write_layers_exr(&path, &named).map_err(image_error)
}

/// Reads an OpenEXR image (its RGB or first layer; an accumulation file as its mean image) as
/// a float32 (height, width, 3) array.
#[pyfunction]
fn read_image(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let image = photonix::io::read_exr(&path).map_err(image_error)?;
    image_to_numpy(py, &image)
}

/// Sums accumulation files of disjoint pass ranges (written by `render(..., accumulation=...)`
/// or `photonix render --pass-range`) and returns the mean image, as `photonix merge` does;
/// writes it to `output` when given (or, with `accumulation=True`, the merged accumulation file).
#[pyfunction]
#[pyo3(signature = (parts, output=None, *, accumulation=false, layers=false, exposure=0.0))]
fn merge<'py>(
    py: Python<'py>,
    parts: Vec<PathBuf>,
    output: Option<PathBuf>,
    accumulation: bool,
    layers: bool,
    exposure: f32,
) -> PyResult<Bound<'py, PyAny>> {
    if accumulation && output.is_none() {
        return Err(PyValueError::new_err("accumulation=True writes the merged accumulation file; give output"));
    }
    if let Some(out) = &output {
        photonix::io::check_output_path(out).map_err(image_error)?;
        for (i, part) in parts.iter().enumerate() {
            photonix::io::check_not_overwriting(out, part, &format!("part {} of the merge", i + 1))
                .map_err(image_error)?;
        }
    }
    let (acc, provenance) = py.detach(|| merge_parts(&parts)).map_err(image_error)?;
    let mean = acc.mean();
    if let Some(out) = &output {
        if accumulation {
            write_accumulation(out, &acc, &provenance).map_err(image_error)?;
        } else {
            photonix::io::write_image(out, &mean.combined(), exposure).map_err(image_error)?;
        }
    }
    if layers {
        Ok(layers_to_dict(py, &mean)?.into_any())
    } else {
        image_to_numpy(py, &mean.combined())
    }
}

/// The Vulkan devices the loader lists, as dicts (index, name, type, driver, api_version);
/// an empty list when there is no Vulkan driver.
#[pyfunction]
fn devices(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for d in py.detach(list_devices).unwrap_or_default() {
        let dict = PyDict::new(py);
        dict.set_item("index", d.index)?;
        dict.set_item("name", d.name)?;
        dict.set_item("type", d.device_type)?;
        dict.set_item("driver", d.driver)?;
        dict.set_item("api_version", d.api_version)?;
        list.append(dict)?;
    }
    Ok(list)
}

/// Reads a scene file through the front-end its extension names, as `photonix render` does:
/// TOML, POV-Ray (`.pov`, at `resolution`, default 320x240 as POV-Ray's +W +H), glTF (`.gltf`,
/// `.glb`; `resolution` in place of the camera's) or Mitsuba (`.xml`). A POV-Ray, glTF or
/// Mitsuba scene is translated to TOML as `photonix convert` does, so it edits like any other;
/// its `path` is the TOML's name beside the file (nothing is written there).
#[pyfunction]
#[pyo3(signature = (path, resolution=None))]
fn load(path: PathBuf, resolution: Option<(u32, u32)>) -> PyResult<Scene> {
    use photonix::scene::{gltf_scene, mitsuba, pov};
    if let Some((w, h)) = resolution {
        let side = 1..=MAX_IMAGE_SIDE;
        if !side.contains(&w) || !side.contains(&h) || w as u64 * h as u64 > MAX_PIXELS {
            return Err(PyValueError::new_err(format!(
                "resolution=({w}, {h}) is out of range; give sizes from 1 to {MAX_IMAGE_SIDE}, at most {MAX_PIXELS} pixels"
            )));
        }
    }
    let translated = if pov::is_pov_path(&path) {
        let mut options = pov::PovOptions::default();
        if let Some((w, h)) = resolution {
            (options.width, options.height) = (w, h);
        }
        Some(pov::translate_file(&path, &options).map(|t| t.toml))
    } else if gltf_scene::is_gltf_path(&path) {
        Some(gltf_scene::translate_file_at(&path, None, resolution).map(|t| t.toml))
    } else if mitsuba::is_mitsuba_path(&path) {
        if resolution.is_some() {
            return Err(PyValueError::new_err(
                "resolution= sizes a POV-Ray or glTF scene; a Mitsuba scene has its film's: set `camera.resolution` after loading, or pass resolution to render",
            ));
        }
        Some(mitsuba::translate_file(&path).map(|t| t.toml))
    } else {
        None
    };
    if let Some(toml) = translated {
        let toml = toml.map_err(scene_error)?;
        let mut scene = Scene::parse(toml, path.with_extension("toml"))?;
        scene.source = path;
        return Ok(scene);
    }
    if resolution.is_some() {
        return Err(PyValueError::new_err(
            "resolution= sizes a POV-Ray or glTF scene; a TOML scene has its camera's: pass resolution to render",
        ));
    }
    // Read once, under the library's size limit (the text is kept for edits); when that fails,
    // `load_scene` says why in the command line's words.
    let limit = photonix::limits::MAX_SCENE_FILE_BYTES;
    match photonix::limits::read_limited(&path, limit).ok().and_then(|bytes| String::from_utf8(bytes).ok()) {
        Some(text) if text.len() as u64 <= limit => Scene::parse(text, path),
        _ => Err(scene_error(match photonix::scene::load_scene(&path) {
            Err(e) => e.to_string(),
            Ok(_) => format!("cannot read {}", path.display()),
        })),
    }
}

/// A scene from a dict in the TOML schema (docs/scene-format.md), as Mitsuba's `load_dict`:
/// top-level dicts are tables (`camera`, `render`, `materials` with one dict per material),
/// lists of dicts arrays of tables (`shapes`, `lights`). `path` names it and is where relative
/// mesh and texture paths are read from.
#[pyfunction]
#[pyo3(signature = (scene, path="scene.toml"))]
fn load_dict(scene: &Bound<'_, PyDict>, path: &str) -> PyResult<Scene> {
    let mut doc = DocumentMut::new();
    for (k, v) in scene.iter() {
        let key: String = k.extract().map_err(|_| PyValueError::new_err("the scene dict's keys must be strings"))?;
        let item = py_to_item(&v, &key, 0)?;
        doc.insert(&key, item);
    }
    Scene::parse(doc.to_string(), PathBuf::from(path))
}

/// Parses scene text. `path` names it in messages, gives the scene its name, and is where
/// relative mesh and texture paths are read from (its folder).
#[pyfunction]
#[pyo3(signature = (text, path="scene.toml"))]
fn loads(text: String, path: &str) -> PyResult<Scene> {
    Scene::parse(text, PathBuf::from(path))
}

#[pymodule]
fn _photonix(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<Scene>()?;
    m.add_class::<Progress>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(loads, m)?)?;
    m.add_function(wrap_pyfunction!(load_dict, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(write_image, m)?)?;
    m.add_function(wrap_pyfunction!(write_layers, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(devices, m)?)?;
    m.add("PhotonixError", py.get_type::<PhotonixError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("RenderError", py.get_type::<RenderError>())?;
    m.add("ImageError", py.get_type::<ImageError>())?;
    m.add("Cancelled", py.get_type::<Cancelled>())?;
    m.add_class::<RendererCore>()?;
    m.add("MAX_PASSES", MAX_PASSES)?;
    Ok(())
}
