//! `SceneError`, and the helpers that turn byte offsets into `path:line` and name the object and
//! field an offset belongs to.

use std::ops::Range;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::limits::{printable, printable_message, shorten_numbers};

/// Why a scene could not be loaded. `Display` is the whole user-facing message: it starts with
/// `path:line` (or `path:line:column` for TOML errors), names the object and field, and says what
/// to do.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read. (`cause`, not `source`: the message already holds its
    /// text, and an error chain printed by `main` would repeat it.)
    #[error("{}: cannot read the scene file: {cause}", path.display())]
    Read { path: PathBuf, cause: std::io::Error },
    /// The scene file is larger than `limit` bytes, or endless (a device file).
    #[error(
        "{}: the scene file is larger than {} (the most photonix reads; see docs/limits.md); \
         is it the right file?",
        path.display(),
        crate::limits::fmt_bytes(*limit)
    )]
    TooLarge { path: PathBuf, limit: u64 },
    /// TOML syntax error, or a value of the wrong type (`radius = "big"`).
    #[error("{location}: {message}")]
    Syntax { location: String, message: String },
    /// A field that no table of this kind has.
    #[error("{location}: unknown field `{field}` in {object} ({hint})")]
    UnknownField {
        location: String,
        field: String,
        object: String,
        /// `did you mean `x`?` or the list of valid fields.
        hint: String,
    },
    /// A value that parses but makes no sense: NaN, a negative radius, an unknown material...
    #[error("{location}: {object}: {message}")]
    Invalid { location: String, object: String, message: String },
    /// The scene has no `[camera]` table.
    #[error("{location}: the scene has no [camera]; add a [camera] table with `position`, `look_at` and `fov`")]
    MissingCamera { location: String },
    /// A mesh's OBJ file does not exist.
    #[error(
        "{location}: {object}: mesh file not found: {} (paths are relative to the scene file)",
        printable_message(&looked_for.display().to_string())
    )]
    MeshNotFound { location: String, object: String, looked_for: PathBuf },
    /// A mesh's OBJ file exists but cannot be used. `obj_location` is `file.obj:line` when the
    /// line is known, else the OBJ path.
    #[error("{obj_location}: {message} (mesh of {object} at {location})")]
    Obj { obj_location: String, message: String, object: String, location: String },
}

/// The scene source and its path, for turning byte offsets into `path:line`.
pub(crate) struct Source<'a> {
    pub text: &'a str,
    pub path: &'a Path,
}

impl Source<'_> {
    /// 1-based line and column of a byte offset.
    pub fn line_column(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        (line, column)
    }

    /// `path:line`.
    pub fn at(&self, span: &Range<usize>) -> String {
        format!("{}:{}", self.path_text(), self.line_column(span.start).0)
    }

    /// `path:line:column`.
    pub fn at_column(&self, span: &Range<usize>) -> String {
        let (line, column) = self.line_column(span.start);
        format!("{}:{line}:{column}", self.path_text())
    }

    fn path_text(&self) -> String {
        printable_message(&self.path.display().to_string())
    }

    /// An `Invalid` error at `span`. Control characters that reach the object or the message
    /// (from names in the file) are escaped here, whatever the caller did.
    pub fn invalid(&self, span: &Range<usize>, object: &str, message: String) -> SceneError {
        SceneError::Invalid {
            location: self.at(span),
            object: printable_message(object),
            message: printable_message(&message),
        }
    }

    /// Turns an error of `toml::from_str` into a `SceneError` that names the object and field.
    pub fn toml_error(&self, error: &toml::de::Error) -> SceneError {
        let mut span = error.span().unwrap_or(0..0);
        // The parser's nesting limit on dotted keys comes without a place (it says 1:1): point at
        // the deepest nesting, where the limit was crossed.
        if span == (0..0) && error.message().contains("recursion") {
            let at = deepest_nesting(self.text);
            span = at..at;
        }
        let location = self.at_column(&span);
        // The parser quotes values as written: escape what a terminal would act on, and write
        // long numbers (`1e300` arrives as 1 followed by 300 zeros) in exponent form.
        let message = shorten_numbers(&printable_message(error.message().trim()));
        // The syntax is valid whenever serde, not the parser, complains, so this parse succeeds
        // and tells us which table the offset is in.
        let key_path = DeTable::parse(self.text)
            .ok()
            .and_then(|root| find_key_path(root.get_ref(), span.start))
            .unwrap_or_default();

        if let Some(rest) = message.strip_prefix("unknown field `") {
            let field = printable(rest.split('`').next().unwrap_or_default());
            let table = &key_path[..key_path.len().saturating_sub(1)];
            // The entry's own kind knows better than the format which fields are meant.
            let valid = kind_fields(self.text, table).unwrap_or_else(|| expected_names(rest));
            let object = describe_table(self.text, table);
            let unknown = rest.split('`').next().unwrap_or_default();
            let hint = match suggest(unknown, &valid) {
                Some(best) => format!("did you mean `{best}`?"),
                None if valid.is_empty() => "this table takes no fields".to_string(),
                None => format!("valid fields: {}", backticked(&valid)),
            };
            return SceneError::UnknownField { location, field, object, hint };
        }

        if key_path.is_empty() || message == "duplicate key" || error.span().is_none() {
            let message = if message == "duplicate key" {
                "duplicate key; each field may appear once per table".to_string()
            } else if message.contains("recursion") {
                "nested too deeply (dotted keys, arrays or inline tables many levels down); a scene needs a few levels"
                    .to_string()
            } else {
                message
            };
            return SceneError::Syntax { location, message };
        }

        // A type error: name the object and the field.
        let field = key_path
            .iter()
            .rev()
            .find_map(|k| match k {
                KeyPart::Key(name) => Some(name.clone()),
                KeyPart::Index(_) => None,
            })
            .unwrap_or_default();
        let owner_len = key_path.iter().rposition(|k| matches!(k, KeyPart::Key(name) if *name == field)).unwrap_or(0);
        let object = describe_table(self.text, &key_path[..owner_len]);
        SceneError::Syntax { location, message: format!("{object}: `{field}`: {}", friendly_types(&message)) }
    }
}

/// The byte offset where `text` nests deepest: arrays and inline tables (`[`, `{` outside
/// strings and comments) plus the dots of the key being written.
fn deepest_nesting(text: &str) -> usize {
    let (mut depth, mut dots, mut best, mut best_at) = (0usize, 0usize, 0usize, 0usize);
    let mut in_string: Option<char> = None;
    let mut comment = false;
    let mut in_key = true;
    for (i, c) in text.char_indices() {
        if comment {
            comment = c != '\n';
            if !comment {
                (dots, in_key) = (0, depth == 0);
            }
            continue;
        }
        if let Some(quote) = in_string {
            if c == quote {
                in_string = None;
            }
            continue;
        }
        match c {
            '"' | '\'' => in_string = Some(c),
            '#' => comment = true,
            '[' | '{' => depth += 1,
            ']' | '}' => depth = depth.saturating_sub(1),
            '.' if in_key => dots += 1,
            '=' => in_key = false,
            ',' if depth > 0 => in_key = true,
            '\n' => (dots, in_key) = (0, depth == 0 || in_key),
            _ => {}
        }
        if depth + dots > best {
            (best, best_at) = (depth + dots, i);
        }
    }
    best_at
}

/// One step of the path from the document root to a value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum KeyPart {
    Key(String),
    Index(usize),
}

/// The path of keys to the innermost key or value whose span contains `offset`.
fn find_key_path(table: &DeTable<'_>, offset: usize) -> Option<Vec<KeyPart>> {
    for (key, value) in table.iter() {
        let mut path = vec![KeyPart::Key(key.get_ref().to_string())];
        if let Some(inner) = find_in_value(value, offset) {
            path.extend(inner);
            return Some(path);
        }
        if key.span().contains(&offset) || value.span().contains(&offset) {
            return Some(path);
        }
    }
    None
}

fn find_in_value(value: &Spanned<DeValue<'_>>, offset: usize) -> Option<Vec<KeyPart>> {
    match value.get_ref() {
        DeValue::Table(table) => find_key_path(table, offset),
        DeValue::Array(array) => array.iter().enumerate().find_map(|(i, element)| {
            let mut path = vec![KeyPart::Index(i)];
            if let Some(inner) = find_in_value(element, offset) {
                path.extend(inner);
                Some(path)
            } else if element.span().contains(&offset) && element.get_ref().is_table() {
                Some(path)
            } else {
                None
            }
        }),
        _ => None,
    }
}

/// Names the table at `path` the way the messages do: `material "wall"`, `shape 3 ("ball")`.
fn describe_table(text: &str, path: &[KeyPart]) -> String {
    let key = |i: usize| match path.get(i) {
        Some(KeyPart::Key(k)) => Some(k.as_str()),
        _ => None,
    };
    let index = |i: usize| match path.get(i) {
        Some(KeyPart::Index(n)) => Some(*n),
        _ => None,
    };
    let base = match (key(0), path.len()) {
        (None, _) => "the top level of the scene".to_string(),
        (Some("camera"), 1) => "[camera]".to_string(),
        (Some("render"), 1) => "[render]".to_string(),
        (Some("materials"), 1) => "[materials]".to_string(),
        (Some("materials"), _) => format!("material \"{}\"", printable(key(1).unwrap_or_default())),
        (Some(list @ ("shapes" | "lights")), _) => match index(1) {
            Some(n) => {
                object_name(if list == "shapes" { "shape" } else { "light" }, n, element_name(text, list, n).as_deref())
            }
            None => format!("`{list}`"),
        },
        (Some(other), _) => format!("`{}`", printable(other)),
    };
    // A nested table such as `transform`.
    let nested: Vec<&str> = path
        .iter()
        .skip(2)
        .filter_map(|k| match k {
            KeyPart::Key(k) => Some(k.as_str()),
            KeyPart::Index(_) => None,
        })
        .collect();
    if nested.is_empty() {
        base
    } else {
        format!("`{}` of {base}", printable(&nested.join(".")))
    }
}

/// The `name` of `[[shapes]]` or `[[lights]]` element `index`, if it has one.
fn element_name(text: &str, list: &str, index: usize) -> Option<String> {
    let root = DeTable::parse(text).ok()?;
    let element = root.get_ref().get(list)?.get_ref().as_array()?.get(index)?;
    let name = element.get_ref().as_table()?.get("name")?;
    name.get_ref().as_str().map(str::to_string)
}

/// `shape 3 ("ball")` or `shape 3`.
pub(crate) fn object_name(kind: &str, index: usize, name: Option<&str>) -> String {
    match name {
        Some(name) => format!("{kind} {index} (\"{}\")", printable(name)),
        None => format!("{kind} {index}"),
    }
}

/// The names serde lists after "expected" in an unknown-field message.
fn expected_names(message_tail: &str) -> Vec<String> {
    let Some((_, expected)) = message_tail.split_once("expected") else {
        return Vec::new();
    };
    expected.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

/// The fields that the kind of the entry at `path` takes (`scene::kinds`): a material, a shape, a
/// light or a medium whose `type` (and an area light's `shape`) names a kind; `None` for any
/// other table, or a kind the file does not name.
fn kind_fields(text: &str, path: &[KeyPart]) -> Option<Vec<String>> {
    use super::kinds::{AREA_LIGHT_SHAPES, LIGHTS, MATERIALS, MEDIA, SHAPES};
    let root = DeTable::parse(text).ok()?;
    fn find<'a>(table: &DeTable<'a>, name: &str) -> Option<DeValue<'a>> {
        table.iter().find(|(k, _)| k.get_ref().as_ref() == name).map(|(_, v)| v.get_ref().clone())
    }
    let (family, entry) = match path {
        [KeyPart::Key(f), KeyPart::Key(name)] if f == "materials" || f == "media" => {
            let DeValue::Table(list) = find(root.get_ref(), f)? else { return None };
            (f.as_str(), find(&list, name)?)
        }
        [KeyPart::Key(f), KeyPart::Index(i)] if f == "shapes" || f == "lights" => {
            let DeValue::Array(list) = find(root.get_ref(), f)? else { return None };
            (f.as_str(), list.get(*i)?.get_ref().clone())
        }
        _ => return None,
    };
    let DeValue::Table(entry) = entry else { return None };
    let text_of = |name: &str| match find(&entry, name) {
        Some(DeValue::String(s)) => Some(s.to_string()),
        _ => None,
    };
    let (family, kind) = match family {
        "materials" => (MATERIALS, text_of("type")?),
        "shapes" => (SHAPES, text_of("type")?),
        "lights" if text_of("type")? == "area" => (AREA_LIGHT_SHAPES, text_of("shape")?),
        "lights" => (LIGHTS, text_of("type")?),
        _ => {
            let heterogeneous = find(&entry, "density").is_some();
            (MEDIA, text_of("type").unwrap_or(if heterogeneous { "heterogeneous" } else { "homogeneous" }.to_string()))
        }
    };
    let kind = family.kinds.iter().find(|k| k.name == kind)?;
    Some(kind.all_fields().map(|f| f.name.to_string()).collect())
}

/// serde names Rust types; users know numbers and integers.
fn friendly_types(message: &str) -> String {
    message
        .replace("expected f64", "expected a number")
        .replace("expected f32", "expected a number")
        .replace("expected i64", "expected an integer")
        .replace("expected u32", "expected a non-negative integer")
        .replace("expected a string", "expected a quoted string")
}

/// `a`, `b`, `c`
pub(crate) fn backticked(names: &[impl AsRef<str>]) -> String {
    names.iter().map(|n| format!("`{}`", n.as_ref())).collect::<Vec<_>>().join(", ")
}

/// Words people write for our fields, tried before spelling similarity: `colour` is not spelled
/// like `reflectance`, but that is what it means.
const SYNONYMS: &[(&str, &[&str])] = &[
    ("color", &["reflectance", "tint", "radiance", "intensity"]),
    ("colour", &["reflectance", "tint", "radiance", "intensity"]),
    ("albedo", &["reflectance", "tint"]),
    ("kd", &["reflectance"]),
    ("diffuse", &["reflectance"]),
    ("rgb", &["reflectance", "tint", "radiance", "intensity"]),
    ("emit", &["emission", "radiance"]),
    ("emissive", &["emission", "radiance"]),
    ("emittance", &["emission", "radiance"]),
    ("le", &["emission", "radiance"]),
    ("eta", &["ior"]),
    ("index", &["ior"]),
    ("fovy", &["fov"]),
    ("fov_deg", &["fov"]),
    ("target", &["look_at", "point_at"]),
    ("location", &["position"]),
    ("cone_angle", &["outer_angle"]),
    ("cutoff_angle", &["outer_angle"]),
    ("angle", &["outer_angle", "angular_diameter"]),
    ("beam_width", &["inner_angle"]),
    ("hotspot", &["inner_angle"]),
    ("focus_distance", &["focal_distance"]),
    ("fstop", &["f_number"]),
    ("f_stop", &["f_number"]),
    ("lens_radius", &["aperture_radius"]),
    ("blades", &["aperture_blades"]),
    ("spotlight", &["spot"]),
    ("directional", &["distant"]),
    ("parallel", &["distant"]),
    ("sun", &["distant"]),
    ("ortho", &["orthographic"]),
    ("equirectangular", &["latlong"]),
    ("spherical", &["latlong"]),
    ("pinhole", &["perspective"]),
    ("lookat", &["look_at"]),
    ("centre", &["center"]),
    ("origin", &["position", "center"]),
    ("pos", &["position", "center"]),
    ("size", &["resolution", "radius"]),
    ("samples", &["spp"]),
    ("depth", &["max_depth"]),
    ("bounces", &["max_depth"]),
    ("power", &["intensity", "radiance"]),
    ("rotation", &["rotate"]),
    ("translation", &["translate"]),
    ("scaling", &["scale"]),
    ("path", &["file"]),
    ("filename", &["file"]),
    ("mat", &["material"]),
    ("kind", &["type"]),
    ("points", &["vertices"]),
    ("positions", &["vertices"]),
];

/// The valid name closest to `unknown`, or `None` when nothing is close enough to be a typo.
pub(crate) fn suggest(unknown: &str, valid: &[impl AsRef<str>]) -> Option<String> {
    // Nothing that long is a typo of a field name (and the edit distance would cost its length
    // times theirs).
    if unknown.len() > 4 * crate::limits::MAX_ECHOED_CHARS {
        return None;
    }
    let lower = unknown.to_lowercase();
    if let Some((_, targets)) = SYNONYMS.iter().find(|(word, _)| *word == lower) {
        if let Some(hit) = targets.iter().find(|t| valid.iter().any(|v| v.as_ref() == **t)) {
            return Some(hit.to_string());
        }
    }
    valid
        .iter()
        .map(|v| {
            let v = v.as_ref();
            (strsim::normalized_damerau_levenshtein(&lower, &v.to_lowercase()), v)
        })
        .filter(|(score, _)| *score >= 0.5)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, v)| v.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggest_finds_typos_and_synonyms_but_not_noise() {
        let material = ["type", "reflectance", "tint", "ior", "emission"];
        assert_eq!(suggest("colour", &material).as_deref(), Some("reflectance"));
        assert_eq!(suggest("reflectence", &material).as_deref(), Some("reflectance"));
        assert_eq!(suggest("emision", &material).as_deref(), Some("emission"));
        assert_eq!(suggest("zzzzzzzz", &material), None);
        let shape = ["name", "type", "material", "center", "radius"];
        assert_eq!(suggest("radious", &shape).as_deref(), Some("radius"));
        assert_eq!(suggest("centre", &shape).as_deref(), Some("center"));
    }

    #[test]
    fn line_column_counts_from_one() {
        let source = Source { text: "a = 1\nbb = 2\n", path: Path::new("x.toml") };
        assert_eq!(source.line_column(0), (1, 1));
        assert_eq!(source.line_column(6), (2, 1));
        assert_eq!(source.line_column(9), (2, 4));
        assert_eq!(source.at(&(7..8)), "x.toml:2");
    }

    #[test]
    fn expected_names_reads_serde_lists() {
        assert_eq!(expected_names("x`, expected `a` or `b`"), ["a", "b"]);
        assert_eq!(expected_names("x`, expected one of `a`, `b`, `c`"), ["a", "b", "c"]);
        assert!(expected_names("x`, there are no fields").is_empty());
    }
}
