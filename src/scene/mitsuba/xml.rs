//! Mitsuba's XML as a plain element tree with positions: `include` spliced in, `default`
//! parameters collected and every `$name` in an attribute replaced, so the translator never
//! sees either.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::{MitsubaError, Pos};

/// Includes nest at most this deep (a file that includes itself is caught sooner).
const MAX_INCLUDE_DEPTH: usize = 16;

/// One XML element after includes and substitution.
#[derive(Clone, Debug)]
pub struct Element {
    pub tag: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Element>,
    pub pos: Pos,
}

impl Element {
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }
}

/// The scene element of `path` and every file read (the scene first, then its includes).
pub fn read_scene(path: &Path) -> Result<(Element, Vec<PathBuf>), MitsubaError> {
    let mut reader = Reader { files: Vec::new(), stack: Vec::new() };
    let mut root = reader.read_file(path, None)?;
    // Defaults apply to the whole file, wherever they stand (Mitsuba reads them first too).
    let mut params = HashMap::new();
    collect_defaults(&root, &mut params)?;
    substitute(&mut root, &params)?;
    Ok((root, reader.files))
}

struct Reader {
    files: Vec<PathBuf>,
    /// The files being read, outermost first: an include of one of them is a cycle.
    stack: Vec<PathBuf>,
}

impl Reader {
    fn read_file(&mut self, path: &Path, from: Option<Pos>) -> Result<Element, MitsubaError> {
        let err = |message: String| MitsubaError { pos: from, message };
        let shown = crate::limits::printable_message(&path.display().to_string());
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if self.stack.contains(&canonical) {
            return Err(err(format!("{shown} includes itself (through the files it includes)")));
        }
        if self.stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(err(format!("includes nest more than {MAX_INCLUDE_DEPTH} deep at {shown}")));
        }
        // Through the scene's file gate: recorded as an input (no output may replace it) and,
        // under the editor, confined to the scene's folder, where a refusal names no file.
        let bytes = crate::scene::files::read(path, crate::limits::MAX_SCENE_FILE_BYTES).map_err(|e| match e {
            crate::scene::files::FileError::Outside { .. } => err(format!("cannot read an included file: {e}")),
            e => err(format!("cannot read {shown}: {e}")),
        })?;
        let file = self.files.len() as u32;
        self.files.push(path.to_path_buf());
        let text = String::from_utf8(bytes).map_err(|e| MitsubaError {
            pos: Some(Pos { file, line: 1, col: 1 }),
            message: format!("the file is not UTF-8 text (bad byte at offset {})", e.utf8_error().valid_up_to()),
        })?;
        let options = roxmltree::ParsingOptions { allow_dtd: false, nodes_limit: 4_000_000, ..Default::default() };
        let doc = roxmltree::Document::parse_with_options(&text, options).map_err(|e| {
            let p = e.pos();
            MitsubaError { pos: Some(Pos { file, line: p.row, col: p.col }), message: format!("not valid XML: {e}") }
        })?;
        let lines = LineIndex::new(&text);
        let root = doc.root_element();
        let root_pos = lines.pos(file, root.range().start);
        if root.tag_name().name() != "scene" {
            return Err(MitsubaError {
                pos: Some(root_pos),
                message: format!(
                    "the root element is <{}>; a Mitsuba scene file starts with <scene>",
                    root.tag_name().name()
                ),
            });
        }
        self.stack.push(canonical);
        let result = self.element(root, file, &lines, path);
        self.stack.pop();
        result
    }

    fn element(
        &mut self,
        node: roxmltree::Node,
        file: u32,
        lines: &LineIndex,
        path: &Path,
    ) -> Result<Element, MitsubaError> {
        let pos = lines.pos(file, node.range().start);
        let attrs = node.attributes().map(|a| (a.name().to_string(), a.value().to_string())).collect();
        let mut children = Vec::new();
        for child in node.children().filter(|c| c.is_element()) {
            if child.tag_name().name() == "include" {
                let at = lines.pos(file, child.range().start);
                let Some(name) = child.attribute("filename") else {
                    return Err(MitsubaError::at(at, "<include> needs a `filename` attribute".into()));
                };
                if name.contains('$') {
                    return Err(MitsubaError::at(at, "an <include> filename cannot use $parameters".into()));
                }
                let folder = path.parent().unwrap_or(Path::new(""));
                let included = self.read_file(&folder.join(name), Some(at))?;
                children.extend(included.children);
            } else {
                children.push(self.element(child, file, lines, path)?);
            }
        }
        Ok(Element { tag: node.tag_name().name().to_string(), attrs, children, pos })
    }
}

fn collect_defaults(e: &Element, params: &mut HashMap<String, String>) -> Result<(), MitsubaError> {
    for child in &e.children {
        if child.tag == "default" {
            let (Some(name), Some(value)) = (child.attr("name"), child.attr("value")) else {
                return Err(MitsubaError::at(child.pos, "<default> needs `name` and `value` attributes".into()));
            };
            params.entry(name.to_string()).or_insert_with(|| value.to_string());
        }
        collect_defaults(child, params)?;
    }
    Ok(())
}

/// Replaces `$name` (a parameter's name: letters, digits, `_`) in every attribute.
fn substitute(e: &mut Element, params: &HashMap<String, String>) -> Result<(), MitsubaError> {
    for (_, value) in &mut e.attrs {
        if !value.contains('$') {
            continue;
        }
        let mut out = String::new();
        let mut rest = value.as_str();
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let name = &after[..len];
            let Some(v) = params.get(name) else {
                return Err(MitsubaError::at(
                    e.pos,
                    format!(
                        "parameter `${}` has no value; add <default name=\"{}\" value=\"...\"/> to the scene",
                        crate::limits::printable(name),
                        crate::limits::printable(name)
                    ),
                ));
            };
            out.push_str(v);
            rest = &after[len..];
        }
        out.push_str(rest);
        *value = out;
    }
    for child in &mut e.children {
        substitute(child, params)?;
    }
    Ok(())
}

/// Byte offset to line and column (from 1, columns in characters).
struct LineIndex<'a> {
    text: &'a str,
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    fn new(text: &'a str) -> LineIndex<'a> {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { text, starts }
    }

    fn pos(&self, file: u32, offset: usize) -> Pos {
        let line = self.starts.partition_point(|&s| s <= offset).max(1);
        let start = self.starts[line - 1];
        let col = self.text.get(start..offset).map_or(1, |s| s.chars().count() + 1);
        Pos { file, line: line as u32, col: col as u32 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Element, MitsubaError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.xml");
        std::fs::write(&path, text).unwrap();
        read_scene(&path).map(|(e, _)| e)
    }

    #[test]
    fn defaults_substitute_anywhere_in_an_attribute() {
        let e = read("<scene version=\"3.0.0\">\n<default name=\"res\" value=\"64\"/>\n<film type=\"hdrfilm\"><integer name=\"width\" value=\"$res\"/><string name=\"f\" value=\"a$res.b\"/></film></scene>").unwrap();
        let film = &e.children[1];
        assert_eq!(film.pos.line, 3);
        assert_eq!(film.children[0].attr("value"), Some("64"));
        assert_eq!(film.children[1].attr("value"), Some("a64.b"));
    }

    #[test]
    fn an_unknown_parameter_is_an_error_at_its_element() {
        let e = read("<scene>\n  <float name=\"x\" value=\"$nope\"/></scene>").unwrap_err();
        assert_eq!((e.pos.unwrap().line, e.pos.unwrap().col), (2, 3));
        assert!(e.message.contains("$nope"), "{}", e.message);
    }

    #[test]
    fn a_file_that_includes_itself_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.xml");
        std::fs::write(&path, "<scene><include filename=\"a.xml\"/></scene>").unwrap();
        let e = read_scene(&path).unwrap_err();
        assert!(e.message.contains("includes itself"), "{}", e.message);
    }
}
