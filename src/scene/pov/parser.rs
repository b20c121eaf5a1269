//! The evaluator of POV-Ray's language: a token stream that runs directives as it goes
//! (`#declare`, `#if`, `#while`, `#macro`, `#include`, ...), as POV-Ray's own parser does, and
//! the expressions (floats, vectors, colours, strings, arrays, the built-in functions).
//! The scene's statements are read in `objects.rs`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{DMat3, DVec3};

use super::ast::{Camera, Colour, Finish, Interior, Obj, Pigment, PovScene, Tex};
use super::lexer::{lex, Tok, Token};
use super::{Pos, PovError, PovOptions};

/// Most nested frames (include files and macro calls): deeper is runaway recursion. An include
/// or call made as a file's or macro's last statement counts one deeper than the frame it was
/// made in, although that frame has ended by then (a file that includes itself last).
pub const MAX_DEPTH: usize = 128;
/// Most tokens one scene may deliver, loops and macros counted out (runaway loops stop here).
pub const MAX_TOKENS: u64 = 50_000_000;
/// Most elements of one array.
pub const MAX_ARRAY: usize = 1 << 22;
/// Most `{` and `(` open at once. The evaluator recurses a few times per level, about 8 KiB of
/// stack per level in a release build; the front-end runs on a thread of its own with 64 MiB of
/// stack (`pov::translate_file`), so 256 levels of braces with 256 of expressions inside fit
/// whatever thread asked for the translation (tests/hardening4.rs asks from a 1 MiB thread).
pub const MAX_NESTING: i64 = 256;
/// Most nested sub-expressions without a bracket (`- - - 1`, `<<1, 2>.x, 3>`, `a ? b : c ? ...`).
pub const MAX_EXPRESSION_DEPTH: usize = 256;
/// Longest string value, in bytes (`concat` of a string with itself doubles it).
pub const MAX_STRING_BYTES: usize = 1 << 20;
/// Most nodes (objects, textures, pigments, array elements) one value may hold as the
/// translation expands it: an object declared from itself (`#declare U = union { object { U }
/// object { U } }` in a loop) doubles (`measure`).
pub const MAX_VALUE_NODES: usize = 1 << 20;
/// Deepest value: objects in objects, textures in texture maps, arrays in arrays (`measure`).
pub const MAX_VALUE_DEPTH: usize = 256;
/// The language's memory as a whole: an estimate of every declared value (strings, arrays,
/// objects) and of the scene's objects, in bytes.
pub const MAX_LANGUAGE_BYTES: usize = 1 << 30;
/// Most include files read (a file included again is read once; its tokens are kept).
pub const MAX_INCLUDE_FILES: usize = 4096;

pub type Result<T> = std::result::Result<T, PovError>;

#[derive(Clone, Debug)]
pub struct MacroDef {
    pub tokens: Rc<Vec<Token>>,
    pub body: usize,
    pub params: Vec<String>,
}

#[derive(Clone, Debug)]
pub struct PovArray {
    pub dims: Vec<usize>,
    pub items: Vec<Option<Value>>,
}

/// A value of the language.
#[derive(Clone, Debug)]
pub enum Value {
    Float(f64),
    /// 2 to 5 components (a colour is 5: red, green, blue, filter, transmit).
    Vector(Vec<f64>),
    Str(String),
    Array(Box<PovArray>),
    Object(Box<Obj>),
    Texture(Vec<Tex>),
    Pigment(Pigment),
    Finish(Finish),
    Interior(Interior),
    Normal(Box<super::ast::Normal>),
    Media(Box<super::ast::Media>),
    Sky(Box<super::ast::SkySphere>),
    /// A `material`: texture layers and an interior.
    Material(Vec<Tex>, Option<Interior>),
    Camera(Box<Camera>),
    ColorMap(Vec<(f64, Colour)>),
    Transform(glam::DMat4),
    Macro(Rc<MacroDef>),
    /// Something read but not used by the translation (a normal, a media, a density): its kind.
    Other(&'static str),
}

impl Value {
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Float(_) => "a float",
            Value::Vector(_) => "a vector",
            Value::Str(_) => "a string",
            Value::Array(_) => "an array",
            Value::Object(_) => "an object",
            Value::Texture(_) => "a texture",
            Value::Pigment(_) => "a pigment",
            Value::Finish(_) => "a finish",
            Value::Interior(_) => "an interior",
            Value::Normal(_) => "a normal",
            Value::Media(_) => "a media",
            Value::Sky(_) => "a sky_sphere",
            Value::Material(..) => "a material",
            Value::Camera(_) => "a camera",
            Value::ColorMap(_) => "a color_map",
            Value::Transform(_) => "a transform",
            Value::Macro(_) => "a macro",
            Value::Other(k) => k,
        }
    }
}

#[derive(Clone, Debug)]
enum Ctrl {
    If,
    While { cond: usize },
    For { var: String, end: f64, step: f64, body: usize },
    Switch { delivered: u64 },
}

#[derive(Clone, Debug)]
struct Frame {
    tokens: Rc<Vec<Token>>,
    pos: usize,
    /// A macro call returns at its `#end`; a file ends with its tokens.
    is_macro: bool,
    control: Vec<(Ctrl, Pos)>,
    /// Where the file or the macro call started, for "never closed" messages.
    start: Pos,
    /// Includes and macro calls this frame is nested in (the scene file is 0), counted from the
    /// frame the include or call was made in even when that frame ended first.
    depth: usize,
}

pub struct Parser {
    pub files: Vec<PathBuf>,
    frames: Vec<Frame>,
    scopes: Vec<HashMap<String, Value>>,
    rand: Vec<u32>,
    pub options: PovOptions,
    pub scene: PovScene,
    pub warnings: Vec<String>,
    delivered: u64,
    /// Whether `>` closes a vector rather than compares: one entry per open `<` or `(`.
    angle: Vec<bool>,
    /// A `<` ends the expression (a float followed by a vector, as in bicubic_patch's
    /// `v_steps 5 <1, 0, 0>`).
    pub stop_at_less: bool,
    pub default_finish: Finish,
    pub default_pigment: Option<Pigment>,
    last_pos: Pos,
    scene_dir: PathBuf,
    /// Open `{` and `(` delivered so far.
    nesting: i64,
    /// While a `#declare` reads its value: (frame count, nesting) where it started. At that
    /// level, peeking stops at a directive instead of running it, so that looking for an
    /// optional `,` or `filter` after the value cannot run the next `#declare` first.
    barriers: Vec<(usize, i64)>,
    /// `MAX_TOKENS`, lowered by tests.
    pub max_tokens: u64,
    /// Sub-expressions open now (`MAX_EXPRESSION_DEPTH`).
    expression_depth: usize,
    /// Every file read, by its path: its number in `files` and its tokens (an include read again
    /// in a loop is not read, nor held, twice).
    read: HashMap<PathBuf, (u32, Rc<Vec<Token>>)>,
    /// The estimated bytes of every declared value by name and scope (`MAX_LANGUAGE_BYTES`).
    declared_bytes: usize,
    /// The estimated bytes of the scene's objects so far.
    scene_bytes: usize,
    /// `MAX_LANGUAGE_BYTES`, or half the memory available when that is less (the memory budget,
    /// docs/limits.md): the translation and the scene it loads need the rest.
    memory_budget: usize,
    /// The language version `#version` set last (None before any): `version` reads it, and a
    /// scene that ends below 3.7 without `assumed_gamma` has POV-Ray's legacy gamma.
    version: Option<f64>,
}

/// The gamma of a legacy scene's colours (`Parser::legacy_gamma`): POV-Ray's default display gamma.
pub const LEGACY_DISPLAY_GAMMA: f64 = 2.2;

/// Directives that may open a declared value (`#declare X = #if (c) A #else B #end`).
const VALUE_CONDITIONALS: [&str; 4] = ["if", "ifdef", "ifndef", "switch"];

/// Directives that open a block closed by `#end`.
const OPENERS: [&str; 7] = ["if", "ifdef", "ifndef", "while", "for", "switch", "macro"];

impl Parser {
    pub fn new(path: &Path, options: PovOptions) -> Parser {
        let scene_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Parser {
            files: Vec::new(),
            frames: Vec::new(),
            scopes: vec![HashMap::new()],
            rand: Vec::new(),
            options,
            scene: PovScene::default(),
            warnings: Vec::new(),
            delivered: 0,
            angle: Vec::new(),
            stop_at_less: false,
            default_finish: Finish::default(),
            default_pigment: None,
            last_pos: Pos::default(),
            scene_dir,
            nesting: 0,
            barriers: Vec::new(),
            max_tokens: MAX_TOKENS,
            version: None,
            expression_depth: 0,
            read: HashMap::new(),
            declared_bytes: 0,
            scene_bytes: 0,
            memory_budget: crate::render::memory::available_host_memory()
                .map_or(MAX_LANGUAGE_BYTES, |a| MAX_LANGUAGE_BYTES.min((a / 2) as usize)),
        }
    }

    /// Evaluates the scene file: every statement, include and macro.
    pub fn run_file(&mut self, path: &Path) -> Result<PovScene> {
        let tokens = self.read_file(path, None)?;
        let start = Pos { file: (self.files.len() - 1) as u32, line: 1, col: 1 };
        self.frames.push(Frame { tokens, pos: 0, is_macro: false, control: Vec::new(), start, depth: 0 });
        while self.peek()?.is_some() {
            self.statement()?;
        }
        self.scene.default_tex = Some(self.default_tex(start));
        self.legacy_gamma();
        Ok(std::mem::take(&mut self.scene))
    }

    /// POV-Ray 3.7 reads a scene whose language version ends below 3.7 (`#version 3.6`)
    /// without `assumed_gamma` in its legacy mode: the colours go to the display as written, so
    /// they are display-encoded (gamma 2.2, POV-Ray's default `Display_Gamma`), as
    /// `assumed_gamma 2.2` says. Checked with POV-Ray 3.7.0: such a scene writes 0.706 for a
    /// white face at 45 degrees, a `#version 3.7` one 0.859 (0.706 encoded). A file with no
    /// `#version` at all is read as 3.7 here (POV-Ray warns and takes it as legacy): every
    /// example scene names its version, and short hand-written scenes mean linear colours.
    fn legacy_gamma(&mut self) {
        if self.scene.assumed_gamma.is_none() && self.version.is_some_and(|v| v < 3.7 - 1e-9) {
            self.scene.assumed_gamma = Some(LEGACY_DISPLAY_GAMMA);
        }
    }

    /// Evaluates scene text as if it were the file `path` (the unit tests).
    #[cfg(test)]
    pub fn run_text(&mut self, text: &str, path: &Path) -> Result<PovScene> {
        self.files.push(path.to_path_buf());
        let tokens = lex(text, 0)?;
        let start = Pos { file: 0, line: 1, col: 1 };
        self.frames.push(Frame {
            tokens: Rc::new(tokens),
            pos: 0,
            is_macro: false,
            control: Vec::new(),
            start,
            depth: 0,
        });
        while self.peek()?.is_some() {
            self.statement()?;
        }
        self.scene.default_tex = Some(self.default_tex(start));
        self.legacy_gamma();
        Ok(std::mem::take(&mut self.scene))
    }

    fn read_file(&mut self, path: &Path, at: Option<Pos>) -> Result<Rc<Vec<Token>>> {
        if let Some((_, tokens)) = self.read.get(path) {
            return Ok(tokens.clone());
        }
        let fail = |message: String| match at {
            Some(pos) => PovError::at(pos, message),
            None => PovError { pos: None, message },
        };
        if self.files.len() > MAX_INCLUDE_FILES {
            return Err(fail(format!("the scene includes more than {MAX_INCLUDE_FILES} files; see docs/limits.md")));
        }
        // Through the scene's file gate: a regular file of at most the limit, recorded as an
        // input (no command writes over it), confined to the scene's folder in the editor.
        let what = if at.is_some() { "the included file" } else { "the scene file" };
        let bytes = read_gated(path, crate::limits::MAX_SCENE_FILE_BYTES, what).map_err(fail)?;
        // POV-Ray files are often Latin-1: read bytes above 127 as such rather than refusing them.
        let text: String = match String::from_utf8(bytes) {
            Ok(s) => s,
            Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
        };
        self.files.push(path.to_path_buf());
        let file = (self.files.len() - 1) as u32;
        let tokens = Rc::new(lex(&text, file)?);
        self.read.insert(path.to_path_buf(), (file, tokens.clone()));
        Ok(tokens)
    }

    // ---------------------------------------------------------------------------------------
    // The token stream

    pub fn err<T>(&self, pos: Pos, message: String) -> Result<T> {
        Err(PovError::at(pos, message))
    }

    /// The position of the last token delivered (for messages about what ended too soon).
    pub fn here(&self) -> Pos {
        self.last_pos
    }

    /// The next token without running directives, after returning from macros at their `#end`
    /// and leaving finished include files. `None` at the end of the scene.
    pub fn peek_raw(&mut self) -> Result<Option<Token>> {
        loop {
            let Some(frame) = self.frames.last() else { return Ok(None) };
            match frame.tokens.get(frame.pos) {
                None => {
                    if let Some((_, pos)) = frame.control.last() {
                        return self.err(*pos, "this directive has no #end; add one".into());
                    }
                    if frame.is_macro {
                        return self.err(frame.start, "this macro's body has no #end".into());
                    }
                    if self.frames.len() == 1 {
                        return Ok(None);
                    }
                    self.frames.pop();
                    self.pop_scope();
                }
                Some(t) if frame.is_macro && frame.control.is_empty() && t.tok == Tok::Directive("end".into()) => {
                    self.frames.pop();
                    self.pop_scope();
                }
                Some(t) => return Ok(Some(t.clone())),
            }
        }
    }

    fn advance(&mut self) {
        if let Some(f) = self.frames.last_mut() {
            f.pos += 1;
        }
    }

    /// The next token after running directives and expanding macros, not consumed.
    pub fn peek(&mut self) -> Result<Option<Token>> {
        loop {
            let Some(t) = self.peek_raw()? else { return Ok(None) };
            match &t.tok {
                Tok::Directive(_) if self.barriers.last() == Some(&(self.frames.len(), self.nesting)) => {
                    return Ok(Some(t));
                }
                Tok::Directive(d) => {
                    self.advance();
                    self.directive(d, t.pos)?;
                }
                Tok::Word(w) if matches!(self.lookup(w), Some(Value::Macro(_))) => {
                    self.advance();
                    self.call_macro(w, t.pos)?;
                }
                _ => return Ok(Some(t)),
            }
        }
    }

    /// The next token, consumed.
    pub fn next(&mut self) -> Result<Option<Token>> {
        let t = self.peek()?;
        if let Some(t) = &t {
            self.advance();
            self.last_pos = t.pos;
            self.delivered += 1;
            match t.tok {
                Tok::Sym("{") | Tok::Sym("(") => {
                    self.nesting += 1;
                    if self.nesting > MAX_NESTING {
                        return self.err(
                            t.pos,
                            format!("braces and parentheses nest deeper than {MAX_NESTING} here; see docs/limits.md"),
                        );
                    }
                }
                Tok::Sym("}") | Tok::Sym(")") => self.nesting -= 1,
                _ => {}
            }
            if self.delivered > self.max_tokens {
                return self.err(
                    t.pos,
                    format!(
                        "the scene ran past {} tokens (a runaway #while or macro?); see docs/pov-ray.md",
                        self.max_tokens
                    ),
                );
            }
        }
        Ok(t)
    }

    /// The next token, which must exist.
    pub fn expect_any(&mut self, what: &str) -> Result<Token> {
        match self.next()? {
            Some(t) => Ok(t),
            None => self.err(self.here(), format!("the file ends where {what} was expected")),
        }
    }

    pub fn expect_sym(&mut self, sym: &str) -> Result<Pos> {
        let t = self.expect_any(&format!("`{sym}`"))?;
        if t.tok == Tok::Sym(leak(sym)) {
            Ok(t.pos)
        } else {
            self.err(t.pos, format!("expected `{sym}` here, found {}", describe(&t.tok)))
        }
    }

    /// Consumes `sym` when it comes next (after directives).
    pub fn accept_sym(&mut self, sym: &str) -> Result<bool> {
        match self.peek()? {
            Some(t) if matches!(&t.tok, Tok::Sym(s) if *s == sym) => {
                self.next()?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// Consumes `sym` when it comes next in the raw stream (no directive is run to see it).
    pub fn accept_sym_raw(&mut self, sym: &str) -> Result<bool> {
        match self.peek_raw()? {
            Some(t) if matches!(&t.tok, Tok::Sym(s) if *s == sym) => {
                self.next()?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// The next word, if the next token is one (after directives), not consumed.
    pub fn peek_word(&mut self) -> Result<Option<String>> {
        Ok(match self.peek()? {
            Some(Token { tok: Tok::Word(w), .. }) => Some(w),
            _ => None,
        })
    }

    pub fn accept_word(&mut self, word: &str) -> Result<bool> {
        if self.peek_word()?.as_deref() == Some(word) {
            self.next()?;
            return Ok(true);
        }
        Ok(false)
    }

    // ---------------------------------------------------------------------------------------
    // Identifiers

    pub fn lookup(&self, name: &str) -> Option<&Value> {
        self.scopes.iter().rev().find_map(|s| s.get(name))
    }

    fn declare(&mut self, name: &str, value: Value, local: bool) -> Result<()> {
        let size = self.measure_value(&value, 0, name)?;
        let depth = if local {
            self.scopes.len() - 1
        } else {
            // #declare changes a local of that name where one is in scope, else the global.
            self.scopes.iter().rposition(|s| s.contains_key(name)).unwrap_or(0)
        };
        let old = self.scopes[depth].insert(name.to_string(), value);
        self.forget(old.as_ref());
        self.declared_bytes += size.bytes;
        self.check_memory()
    }

    /// Measures a value about to be stored as `name` (`measure`), refusing it past the limits,
    /// and charges its work to the token budget: a loop that stores a copy of a large array
    /// each turn delivers few tokens but copies, measures and drops millions of slots.
    fn measure_value(&mut self, value: &Value, depth: usize, name: &str) -> Result<super::measure::Size> {
        let size = super::measure::value_at(value, depth).map_err(|e| {
            PovError::at(
                self.here(),
                format!("`{}` {}; see docs/limits.md", crate::limits::printable(name), e.reason()),
            )
        })?;
        self.charge(size.work, self.here())?;
        Ok(size)
    }

    /// Counts `work` (array slots made, copied or measured) as tokens delivered, refusing the
    /// scene past `max_tokens` like a runaway loop.
    pub fn charge(&mut self, work: usize, pos: Pos) -> Result<()> {
        self.delivered = self.delivered.saturating_add(work as u64);
        if self.delivered > self.max_tokens {
            return self.err(
                pos,
                format!(
                    "the scene ran past {} tokens, an array's slots counting one each when it is made or stored (a runaway #while or macro, or large arrays made over and over?); see docs/limits.md",
                    self.max_tokens
                ),
            );
        }
        Ok(())
    }

    /// Takes a value no longer stored off the language's memory.
    fn forget(&mut self, old: Option<&Value>) {
        if let Some(v) = old {
            let bytes = super::measure::value(v).map_or(0, |s| s.bytes);
            self.declared_bytes = self.declared_bytes.saturating_sub(bytes);
        }
    }

    fn pop_scope(&mut self) {
        if let Some(scope) = self.scopes.pop() {
            scope.values().for_each(|v| self.forget(Some(v)));
        }
    }

    /// Refuses a scene whose values and objects together pass `MAX_LANGUAGE_BYTES`.
    fn check_memory(&self) -> Result<()> {
        let total = self.declared_bytes.saturating_add(self.scene_bytes);
        if total > self.memory_budget {
            return self.err(
                self.here(),
                format!(
                    "the scene's declared values and objects take more than {} of memory; see docs/limits.md",
                    crate::limits::fmt_bytes(self.memory_budget as u64)
                ),
            );
        }
        Ok(())
    }

    /// Refuses to allocate `bytes` more where the language's memory (`check_memory`) would not
    /// hold them beside what is stored.
    pub fn check_allocation(&self, bytes: usize, pos: Pos) -> Result<()> {
        let total = self.declared_bytes.saturating_add(self.scene_bytes).saturating_add(bytes);
        if total > self.memory_budget {
            return self.err(
                pos,
                format!(
                    "this would take {} more, past the {} the scene's declared values and objects may take; see docs/limits.md",
                    crate::limits::fmt_bytes(bytes as u64),
                    crate::limits::fmt_bytes(self.memory_budget as u64)
                ),
            );
        }
        Ok(())
    }

    /// Adds an object placed in the scene to the language's memory.
    pub fn count_scene_object(&mut self, o: &super::ast::Obj) -> Result<()> {
        let bytes = super::measure::object(o).map_or(MAX_LANGUAGE_BYTES, |s| s.bytes);
        self.scene_bytes = self.scene_bytes.saturating_add(bytes);
        self.check_memory()
    }

    /// Refuses an object past the limits of `measure` as soon as it is read.
    pub fn check_object(&self, o: &super::ast::Obj) -> Result<()> {
        super::measure::object(o)
            .map(|_| ())
            .map_err(|e| PovError::at(o.pos, format!("this object {}; see docs/limits.md", e.reason())))
    }

    // ---------------------------------------------------------------------------------------
    // Directives

    fn raw_word(&mut self, what: &str) -> Result<(String, Pos)> {
        let t = self.peek_raw()?;
        match t {
            Some(Token { tok: Tok::Word(w), pos }) => {
                self.advance();
                Ok((w, pos))
            }
            Some(t) => self.err(t.pos, format!("expected {what} here, found {}", describe(&t.tok))),
            None => self.err(self.here(), format!("the file ends where {what} was expected")),
        }
    }

    /// Skips raw tokens of the current frame up to the directive in `stops` at this nesting level,
    /// which is consumed and returned.
    fn skip_to(&mut self, stops: &[&str], from: Pos) -> Result<String> {
        let mut depth = 0usize;
        loop {
            let frame = self.frames.last_mut().expect("a directive runs inside a frame");
            let Some(t) = frame.tokens.get(frame.pos).cloned() else {
                return self.err(from, "this directive has no #end; add one".into());
            };
            frame.pos += 1;
            if let Tok::Directive(d) = &t.tok {
                let d = d.as_str();
                if depth == 0 && stops.contains(&d) {
                    self.last_pos = t.pos;
                    return Ok(d.to_string());
                }
                if OPENERS.contains(&d) {
                    depth += 1;
                } else if d == "end" {
                    if depth == 0 {
                        return self.err(t.pos, "unexpected #end".into());
                    }
                    depth -= 1;
                }
            }
        }
    }

    fn push_ctrl(&mut self, c: Ctrl, pos: Pos) {
        self.frames.last_mut().expect("inside a frame").control.push((c, pos));
    }

    fn pop_ctrl(&mut self) -> Option<(Ctrl, Pos)> {
        self.frames.last_mut().and_then(|f| f.control.pop())
    }

    fn cond(&mut self) -> Result<bool> {
        Ok(self.float()? != 0.0)
    }

    fn directive(&mut self, d: &str, pos: Pos) -> Result<()> {
        match d {
            "declare" | "local" => {
                let (mut name, mut npos) = self.raw_word("an identifier")?;
                if name == "deprecated" {
                    // `#declare deprecated [once] "message" Name = ...` (3.7's include files).
                    if matches!(self.peek_raw()?, Some(t) if t.tok == Tok::Word("once".into())) {
                        self.advance();
                    }
                    if let Some(Token { tok: Tok::Str(_), .. }) = self.peek_raw()? {
                        self.advance();
                    }
                    (name, npos) = self.raw_word("an identifier")?;
                }
                if is_reserved(&name) {
                    return self.err(npos, format!("`{name}` is a POV-Ray keyword and cannot be declared"));
                }
                let mut index = Vec::new();
                while self.accept_sym_raw("[")? {
                    index.push(self.float()?);
                    self.expect_sym("]")?;
                }
                self.expect_sym("=")?;
                // `#declare X = #ifdef (A) value #else value #end`: the conditionals that open
                // (or, in a skipped branch's place, continue) the value run before it is read;
                // the `#else` or `#end` after the value then ends it as any directive does and
                // runs next.
                while let Some(Token { tok: Tok::Directive(d), pos: dpos }) = self.peek_raw()? {
                    if !VALUE_CONDITIONALS.contains(&d.as_str()) {
                        break;
                    }
                    self.advance();
                    self.directive(&d, dpos)?;
                }
                self.barriers.push((self.frames.len(), self.nesting));
                let value = self.rvalue();
                self.barriers.pop();
                let value = value?;
                self.accept_sym_raw(";")?;
                if index.is_empty() {
                    self.declare(&name, value, d == "local")?;
                } else {
                    self.assign_element(&name, &index, value, npos)?;
                }
            }
            "undef" => {
                let (name, _) = self.raw_word("an identifier")?;
                if let Some(s) = self.scopes.iter_mut().rev().find(|s| s.contains_key(&name)) {
                    let old = s.remove(&name);
                    self.forget(old.as_ref());
                }
            }
            "if" => {
                let c = self.cond()?;
                self.branch(c, pos)?;
            }
            "ifdef" | "ifndef" => {
                self.expect_sym("(")?;
                let (name, _) = self.raw_word("an identifier")?;
                let mut defined = self.lookup(&name).is_some();
                // `#ifdef (A[i])`: the element must be set.
                let mut index = Vec::new();
                while self.accept_sym_raw("[")? {
                    index.push(self.float()?);
                    self.expect_sym("]")?;
                }
                if defined && !index.is_empty() {
                    defined = matches!(self.lookup(&name), Some(Value::Array(a)) if element_index(a, &index).is_some_and(|i| a.items[i].is_some()));
                }
                self.expect_sym(")")?;
                self.branch(defined == (d == "ifdef"), pos)?;
            }
            "else" | "elseif" => match self.pop_ctrl() {
                Some((Ctrl::If, _)) | Some((Ctrl::Switch { .. }, _)) => {
                    self.skip_to(&["end"], pos)?;
                }
                _ => return self.err(pos, format!("#{d} without a matching #if")),
            },
            "while" => {
                let cond = self.frames.last().expect("inside a frame").pos;
                if self.cond()? {
                    self.push_ctrl(Ctrl::While { cond }, pos);
                } else {
                    self.skip_to(&["end"], pos)?;
                }
            }
            "for" => {
                self.expect_sym("(")?;
                let (var, _) = self.raw_word("the loop's identifier")?;
                self.expect_sym(",")?;
                let start = self.float()?;
                self.expect_sym(",")?;
                let end = self.float()?;
                let step = if self.accept_sym(",")? { self.float()? } else { 1.0 };
                self.expect_sym(")")?;
                if step == 0.0 {
                    return self.err(pos, "#for with a step of 0 never ends; give a step other than 0".into());
                }
                self.declare(&var, Value::Float(start), false)?;
                if (step > 0.0 && start <= end) || (step < 0.0 && start >= end) {
                    let body = self.frames.last().expect("inside a frame").pos;
                    self.push_ctrl(Ctrl::For { var, end, step, body }, pos);
                } else {
                    self.skip_to(&["end"], pos)?;
                }
            }
            "switch" => {
                let v = self.float()?;
                loop {
                    match self.skip_to(&["case", "range", "else", "end"], pos)?.as_str() {
                        "case" => {
                            self.expect_sym("(")?;
                            let c = self.float()?;
                            self.expect_sym(")")?;
                            if (c - v).abs() < 1e-10 {
                                break;
                            }
                        }
                        "range" => {
                            self.expect_sym("(")?;
                            let a = self.float()?;
                            self.expect_sym(",")?;
                            let b = self.float()?;
                            self.expect_sym(")")?;
                            if a <= v && v <= b {
                                break;
                            }
                        }
                        "else" => break,
                        _ => return Ok(()),
                    }
                }
                self.push_ctrl(Ctrl::Switch { delivered: self.delivered }, pos);
            }
            "case" | "range" => match self.frames.last().and_then(|f| f.control.last()).cloned() {
                // Consecutive labels share the statements that follow them.
                Some((Ctrl::Switch { delivered }, _)) if delivered == self.delivered => {
                    self.expect_sym("(")?;
                    self.float()?;
                    if d == "range" {
                        self.expect_sym(",")?;
                        self.float()?;
                    }
                    self.expect_sym(")")?;
                }
                Some((Ctrl::Switch { .. }, _)) => {
                    self.pop_ctrl();
                    self.skip_to(&["end"], pos)?;
                }
                _ => return self.err(pos, format!("#{d} outside a #switch")),
            },
            "break" => loop {
                match self.pop_ctrl() {
                    Some((Ctrl::If, _)) => {
                        self.skip_to(&["end"], pos)?;
                    }
                    Some(_) => {
                        self.skip_to(&["end"], pos)?;
                        break;
                    }
                    None => return self.err(pos, "#break outside a #switch or a loop".into()),
                }
            },
            "end" => match self.pop_ctrl() {
                Some((Ctrl::If, _)) | Some((Ctrl::Switch { .. }, _)) => {}
                Some((Ctrl::While { cond }, at)) => {
                    self.frames.last_mut().expect("inside a frame").pos = cond;
                    if self.cond()? {
                        self.push_ctrl(Ctrl::While { cond }, at);
                    } else {
                        self.skip_to(&["end"], at)?;
                    }
                }
                Some((Ctrl::For { var, end, step, body }, at)) => {
                    let v = match self.lookup(&var) {
                        Some(Value::Float(v)) => *v + step,
                        _ => return self.err(at, format!("the #for variable `{var}` is no longer a float")),
                    };
                    self.declare(&var, Value::Float(v), false)?;
                    if (step > 0.0 && v <= end) || (step < 0.0 && v >= end) {
                        self.frames.last_mut().expect("inside a frame").pos = body;
                        self.push_ctrl(Ctrl::For { var, end, step, body }, at);
                    }
                }
                None => return self.err(pos, "#end without a matching #if, #while, #for, #switch or #macro".into()),
            },
            "macro" => {
                let (name, _) = self.raw_word("the macro's name")?;
                self.expect_sym("(")?;
                let mut params = Vec::new();
                if !self.accept_sym_raw(")")? {
                    loop {
                        let (mut p, _) = self.raw_word("a parameter name")?;
                        if p == "optional" {
                            p = self.raw_word("a parameter name")?.0;
                        }
                        params.push(p);
                        if self.accept_sym_raw(")")? {
                            break;
                        }
                        self.expect_sym(",")?;
                    }
                }
                let frame = self.frames.last().expect("inside a frame");
                let def = MacroDef { tokens: frame.tokens.clone(), body: frame.pos, params };
                self.skip_to(&["end"], pos)?;
                self.declare(&name, Value::Macro(Rc::new(def)), false)?;
            }
            "include" => {
                // The including frame, before reading the name: past a file's last statement
                // reading it ends that frame, and the depth must still grow.
                let depth = self.frames.last().map_or(0, |f| f.depth) + 1;
                let name = self.string()?;
                let path = self.find_include(&name, pos)?;
                if depth >= MAX_DEPTH {
                    return self.err(
                        pos,
                        format!(
                            "includes nest deeper than {MAX_DEPTH}; does a file include itself? see docs/limits.md"
                        ),
                    );
                }
                let tokens = self.read_file(&path, Some(pos))?;
                let file = self.read.get(&path).map_or(0, |(f, _)| *f);
                let start = Pos { file, line: 1, col: 1 };
                self.frames.push(Frame { tokens, pos: 0, is_macro: false, control: Vec::new(), start, depth });
                self.scopes.push(HashMap::new());
            }
            "version" => {
                let v = self.float()?;
                self.accept_sym_raw(";")?;
                self.version = Some(v);
            }
            "debug" | "warning" | "render" | "statistics" => {
                let text = self.string()?;
                if d == "warning" {
                    self.warnings.push(format!("#warning: {}", text.trim()));
                }
            }
            "error" => {
                let text = self.string()?;
                return self.err(pos, format!("#error in the scene: {}", text.trim()));
            }
            "default" => self.default_block()?,
            "fopen" => {
                // Writing is read and ignored (the portfolio scenes write HTML pages beside their
                // images; a render has no business writing files); reading is refused.
                let (name, _) = self.raw_word("a file identifier")?;
                self.string()?;
                let mode = self.raw_word("read, write or append")?;
                match mode.0.as_str() {
                    "write" | "append" => {
                        self.warnings.push(format!(
                            "{}: #fopen {name} ... {}: file output is not written (the scene's writes are ignored)",
                            self.loc(pos),
                            mode.0
                        ));
                        self.declare(&name, Value::Other("an output file"), false)?;
                    }
                    "read" => return self.err(pos, "reading files (#fopen ... read) is not supported yet".into()),
                    other => {
                        return self.err(mode.1, format!("#fopen takes read, write or append, not `{other}`"));
                    }
                }
            }
            "fclose" => {
                let (name, npos) = self.raw_word("a file identifier")?;
                if !matches!(self.lookup(&name), Some(Value::Other("an output file"))) {
                    return self.err(npos, format!("`{name}` is not an open file"));
                }
            }
            "write" => {
                // #write (File, item, item ...): the items are evaluated (their errors still
                // count) and dropped.
                self.expect_sym("(")?;
                let (name, npos) = self.raw_word("a file identifier")?;
                if !matches!(self.lookup(&name), Some(Value::Other("an output file"))) {
                    return self.err(npos, format!("`{name}` is not a file opened for writing"));
                }
                loop {
                    if self.accept_sym(")")? {
                        break;
                    }
                    self.accept_sym(",")?;
                    if self.accept_sym(")")? {
                        break;
                    }
                    if self.accept_word("uint8")? || self.accept_word("sint8")? {
                        // binary formats: the value follows
                    }
                    self.expr()?;
                }
            }
            "read" => return self.err(pos, "reading files (#read) is not supported yet".into()),
            other => return self.err(pos, format!("unknown directive #{other}")),
        }
        Ok(())
    }

    fn branch(&mut self, taken: bool, pos: Pos) -> Result<()> {
        if taken {
            self.push_ctrl(Ctrl::If, pos);
            return Ok(());
        }
        loop {
            match self.skip_to(&["else", "elseif", "end"], pos)?.as_str() {
                "else" => {
                    self.push_ctrl(Ctrl::If, pos);
                    return Ok(());
                }
                "elseif" => {
                    if self.cond()? {
                        self.push_ctrl(Ctrl::If, pos);
                        return Ok(());
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    pub fn find_include(&self, name: &str, pos: Pos) -> Result<PathBuf> {
        let here = self.files.get(pos.file as usize).and_then(|p| p.parent()).map(Path::to_path_buf);
        let mut dirs: Vec<PathBuf> = here.into_iter().collect();
        dirs.push(self.scene_dir.clone());
        dirs.extend(self.options.include_dirs.iter().cloned());
        // Each candidate passes the scene's file gate: in the editor a name that leads out of
        // the scene's folder (and the standard include folder) is refused whether or not a file
        // is there, and the message names neither the file nor the folders searched.
        let (mut outside, mut not_regular) = (None, None);
        for dir in &dirs {
            let p = dir.join(name);
            match crate::scene::files::probe(&p) {
                Ok(_) if p.is_file() => return Ok(p),
                // There, but a device, a pipe or a folder: say what it is, not "no such file".
                Ok(r) => {
                    if let Err(e) = crate::limits::regular_file_size(&r) {
                        not_regular = not_regular.or(Some(e));
                    }
                }
                Err(e @ crate::scene::files::FileError::Outside { .. }) => outside = outside.or(Some(e)),
                _ => {}
            }
        }
        if let Some(e) = outside {
            return self.err(pos, format!("#include: {e}"));
        }
        if let Some(e) = not_regular {
            return self.err(pos, format!("#include \"{}\": {e}", crate::limits::printable(name)));
        }
        let hint = if Path::new(super::STANDARD_INCLUDE_DIR).is_dir() {
            String::new()
        } else {
            " (POV-Ray's standard includes are not installed: `apt-get install povray-includes`)".into()
        };
        self.err(
            pos,
            format!(
                "#include \"{name}\": no such file in {}{hint}",
                dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ")
            ),
        )
    }

    fn call_macro(&mut self, name: &str, pos: Pos) -> Result<()> {
        let Some(Value::Macro(def)) = self.lookup(name).cloned() else { unreachable!("checked by peek") };
        let depth = self.frames.last().map_or(0, |f| f.depth) + 1;
        self.expect_sym("(")?;
        let mut args = Vec::new();
        if !self.accept_sym(")")? {
            loop {
                args.push(self.rvalue()?);
                if self.accept_sym(")")? {
                    break;
                }
                self.expect_sym(",")?;
            }
        }
        if args.len() != def.params.len() {
            return self.err(pos, format!("macro `{name}` takes {} arguments, not {}", def.params.len(), args.len()));
        }
        if depth >= MAX_DEPTH || self.frames.len() >= MAX_DEPTH {
            return self.err(
                pos,
                format!(
                    "macro calls nest deeper than {MAX_DEPTH} (runaway recursion in `{name}`?); see docs/pov-ray.md"
                ),
            );
        }
        for (param, arg) in def.params.iter().zip(&args) {
            self.declared_bytes += self.measure_value(arg, 0, param)?.bytes;
        }
        self.check_memory()?;
        let scope: HashMap<String, Value> = def.params.iter().cloned().zip(args).collect();
        self.scopes.push(scope);
        self.frames.push(Frame {
            tokens: def.tokens.clone(),
            pos: def.body,
            is_macro: true,
            control: Vec::new(),
            start: pos,
            depth,
        });
        Ok(())
    }

    fn assign_element(&mut self, name: &str, index: &[f64], value: Value, pos: Pos) -> Result<()> {
        let depth = self.scopes.iter().rposition(|s| s.contains_key(name));
        let Some(depth) = depth else { return self.err(pos, format!("`{name}` is not a declared array")) };
        let size = self.measure_value(&value, 1, name)?;
        let Some(Value::Array(a)) = self.scopes[depth].get_mut(name) else {
            return self.err(pos, format!("`{name}` is not an array"));
        };
        let Some(i) = element_index(a, index) else {
            let dims = a.dims.clone();
            return self.err(pos, format!("index {index:?} is outside the array `{name}` of size {dims:?}"));
        };
        let old = a.items[i].replace(value);
        self.forget(old.as_ref());
        self.declared_bytes += size.bytes;
        self.check_memory()
    }

    // ---------------------------------------------------------------------------------------
    // Values

    /// The right-hand side of `#declare`, or a macro argument: an object, a texture, ... or an
    /// expression.
    pub fn rvalue(&mut self) -> Result<Value> {
        if let Some(w) = self.peek_word()? {
            if let Some(v) = self.block_value(&w)? {
                return Ok(v);
            }
        }
        self.expr()
    }

    pub fn float(&mut self) -> Result<f64> {
        let pos = self.peek()?.map(|t| t.pos).unwrap_or(self.here());
        match self.expr()? {
            Value::Float(f) => Ok(f),
            Value::Vector(v) => Ok(v[0]),
            other => self.err(pos, format!("expected a float here, found {}", other.kind())),
        }
    }

    /// A vector of `n` components (a float is promoted to all of them).
    pub fn vector(&mut self, n: usize) -> Result<Vec<f64>> {
        let pos = self.peek()?.map(|t| t.pos).unwrap_or(self.here());
        match self.expr()? {
            Value::Float(f) => Ok(vec![f; n]),
            Value::Vector(mut v) => {
                v.resize(n, 0.0);
                Ok(v)
            }
            other => self.err(pos, format!("expected a vector here, found {}", other.kind())),
        }
    }

    pub fn vec3(&mut self) -> Result<DVec3> {
        let v = self.vector(3)?;
        Ok(DVec3::new(v[0], v[1], v[2]))
    }

    pub fn string(&mut self) -> Result<String> {
        let pos = self.peek()?.map(|t| t.pos).unwrap_or(self.here());
        match self.expr()? {
            Value::Str(s) => Ok(s),
            other => self.err(pos, format!("expected a string here, found {}", other.kind())),
        }
    }

    /// A colour: `rgb <..>`, `color Red filter 0.5`, `White * 0.8`, ...
    pub fn colour(&mut self) -> Result<Colour> {
        let mut c = [0.0; 5];
        let mut first = true;
        loop {
            let Some(w) = self.peek_word()? else {
                if first {
                    c = to_colour(self.expr()?, self.here(), self)?;
                }
                return Ok(c);
            };
            match w.as_str() {
                "color" | "colour" if first => {
                    self.next()?;
                    continue;
                }
                "rgb" | "rgbf" | "rgbt" | "rgbft" | "srgb" | "srgbf" | "srgbt" | "srgbft" => {
                    // A second colour vector starts the next colour, as POV-Ray reads
                    // `checker rgb 0.8 rgb 0.6`; only the component keywords amend this one.
                    if !first {
                        return Ok(c);
                    }
                    c = to_colour(self.expr()?, self.here(), self)?;
                }
                "red" | "green" | "blue" | "filter" | "transmit" => {
                    self.next()?;
                    let i = ["red", "green", "blue", "filter", "transmit"].iter().position(|k| *k == w).unwrap_or(0);
                    c[i] = self.float()?;
                }
                _ if first => c = to_colour(self.expr()?, self.here(), self)?,
                _ => return Ok(c),
            }
            first = false;
        }
    }

    // Expressions, lowest precedence first: ?:, |, &, comparisons, + -, * /, unary, postfix.

    pub fn expr(&mut self) -> Result<Value> {
        self.deeper()?;
        let v = self.expr_inner();
        self.expression_depth -= 1;
        v
    }

    /// One sub-expression deeper, refused past `MAX_EXPRESSION_DEPTH` (the evaluator recurses).
    fn deeper(&mut self) -> Result<()> {
        if self.expression_depth >= MAX_EXPRESSION_DEPTH {
            let pos = self.peek_raw()?.map_or(self.here(), |t| t.pos);
            return self.err(
                pos,
                format!("the expression nests deeper than {MAX_EXPRESSION_DEPTH} levels; see docs/limits.md"),
            );
        }
        self.expression_depth += 1;
        Ok(())
    }

    fn expr_inner(&mut self) -> Result<Value> {
        let c = self.or()?;
        if self.accept_sym_raw("?")? {
            let pos = self.here();
            let a = self.expr()?;
            self.expect_sym(":")?;
            let b = self.expr()?;
            return Ok(if truth(&c, pos, self)? { a } else { b });
        }
        Ok(c)
    }

    fn or(&mut self) -> Result<Value> {
        let mut a = self.and()?;
        while self.accept_sym_raw("|")? {
            let pos = self.here();
            let b = self.and()?;
            a = Value::Float((truth(&a, pos, self)? || truth(&b, pos, self)?) as u8 as f64);
        }
        Ok(a)
    }

    fn and(&mut self) -> Result<Value> {
        let mut a = self.compare()?;
        while self.accept_sym_raw("&")? {
            let pos = self.here();
            let b = self.compare()?;
            a = Value::Float((truth(&a, pos, self)? && truth(&b, pos, self)?) as u8 as f64);
        }
        Ok(a)
    }

    fn compare(&mut self) -> Result<Value> {
        let mut a = self.sum()?;
        loop {
            let op = match self.peek_raw()? {
                Some(Token { tok: Tok::Sym(s), .. }) if ["<", "<=", "=", "!=", ">=", ">"].contains(&s) => s,
                _ => return Ok(a),
            };
            // Inside `< ... >` a `>` closes the vector (POV-Ray asks for parentheses there).
            if (op == ">" || op == ">=") && self.angle.last() == Some(&true) {
                return Ok(a);
            }
            // `<a, b> <c, d>`: a vector followed by another (a list without commas), not a comparison.
            if op == "<" && (matches!(a, Value::Vector(_)) || self.stop_at_less) {
                return Ok(a);
            }
            self.next()?;
            let pos = self.here();
            let b = self.sum()?;
            // Strings compare by their text, as POV-Ray 3.7 compares them (`#if (c_file != "")`
            // in the mesh camera's macros).
            if let (Value::Str(x), Value::Str(y)) = (&a, &b) {
                let r = match op {
                    "=" => x == y,
                    "!=" => x != y,
                    "<" => x < y,
                    "<=" => x <= y,
                    ">=" => x >= y,
                    _ => x > y,
                };
                a = Value::Float(r as u8 as f64);
                continue;
            }
            let (x, y) = (scalar(&a, pos, self)?, scalar(&b, pos, self)?);
            let r = match op {
                "<" => x < y,
                "<=" => x <= y,
                "=" => (x - y).abs() < 1e-10,
                "!=" => (x - y).abs() >= 1e-10,
                ">=" => x >= y,
                _ => x > y,
            };
            a = Value::Float(r as u8 as f64);
        }
    }

    fn sum(&mut self) -> Result<Value> {
        let mut a = self.product()?;
        loop {
            let op = match self.peek_raw()? {
                Some(Token { tok: Tok::Sym(s @ ("+" | "-")), .. }) => s,
                _ => return Ok(a),
            };
            self.next()?;
            let pos = self.here();
            let b = self.product()?;
            a = arith(a, b, op, pos, self)?;
        }
    }

    fn product(&mut self) -> Result<Value> {
        let mut a = self.unary()?;
        loop {
            let op = match self.peek_raw()? {
                Some(Token { tok: Tok::Sym(s @ ("*" | "/")), .. }) => s,
                _ => return Ok(a),
            };
            self.next()?;
            let pos = self.here();
            let b = self.unary()?;
            a = arith(a, b, op, pos, self)?;
        }
    }

    fn unary(&mut self) -> Result<Value> {
        // A unary operator recurses without a bracket: counted like a sub-expression.
        let nested = |p: &mut Parser| -> Result<Value> {
            p.deeper()?;
            let v = p.unary();
            p.expression_depth -= 1;
            v
        };
        if self.accept_sym("-")? {
            let pos = self.here();
            let v = nested(self)?;
            return arith(Value::Float(0.0), v, "-", pos, self);
        }
        if self.accept_sym("+")? {
            return nested(self);
        }
        if self.accept_sym("!")? {
            let pos = self.here();
            let v = nested(self)?;
            return Ok(Value::Float((!truth(&v, pos, self)?) as u8 as f64));
        }
        let v = self.factor()?;
        self.postfix(v)
    }

    pub fn postfix(&mut self, mut v: Value) -> Result<Value> {
        loop {
            if let Some(Token { tok: Tok::Sym("["), .. }) = self.peek_raw()? {
                if let Value::Array(_) = v {
                    self.next()?;
                    let pos = self.here();
                    let i = self.float()?;
                    self.expect_sym("]")?;
                    v = index_array(v, i, pos, self)?;
                    continue;
                }
            }
            if let Some(Token { tok: Tok::Sym("."), .. }) = self.peek_raw()? {
                self.next()?;
                let (m, pos) = self.raw_word("a component such as .x or .red")?;
                let i = match m.as_str() {
                    "x" | "u" | "red" => 0,
                    "y" | "v" | "green" => 1,
                    "z" | "blue" => 2,
                    "t" | "filter" => 3,
                    "transmit" => 4,
                    "gray" | "grey" => {
                        let c = vec_of(&v, 3, pos, self)?;
                        v = Value::Float(0.297 * c[0] + 0.589 * c[1] + 0.114 * c[2]);
                        continue;
                    }
                    other => {
                        return self.err(
                            pos,
                            format!(
                                "unknown component `.{other}`; use .x .y .z .t or .red .green .blue .filter .transmit"
                            ),
                        )
                    }
                };
                let c = vec_of(&v, 5, pos, self)?;
                v = Value::Float(c[i]);
                continue;
            }
            return Ok(v);
        }
    }

    fn args(&mut self) -> Result<Vec<Value>> {
        self.expect_sym("(")?;
        self.angle.push(false);
        let mut out = Vec::new();
        if !self.accept_sym(")")? {
            loop {
                out.push(self.expr()?);
                if self.accept_sym(")")? {
                    break;
                }
                self.expect_sym(",")?;
            }
        }
        self.angle.pop();
        Ok(out)
    }

    fn factor(&mut self) -> Result<Value> {
        let t = self.expect_any("a value")?;
        let pos = t.pos;
        match t.tok {
            Tok::Num(n) => Ok(Value::Float(n)),
            Tok::Str(s) => Ok(Value::Str(s)),
            Tok::Sym("(") => {
                self.angle.push(false);
                let v = self.expr();
                self.angle.pop();
                let v = v?;
                self.expect_sym(")")?;
                Ok(v)
            }
            Tok::Sym("<") => {
                let comps = self.angle_list()?;
                if comps.len() < 2 || comps.len() > 5 {
                    return self.err(pos, format!("a vector has 2 to 5 components, not {}", comps.len()));
                }
                Ok(Value::Vector(comps))
            }
            Tok::Word(w) => self.word_value(&w, pos),
            other => self.err(pos, format!("expected a value here, found {}", describe(&other))),
        }
    }

    /// The numbers of `< a, b, ... >` after the `<`, up to and including the `>`. Commas are
    /// optional, as in POV-Ray (`< -1 0 0 >`).
    pub fn angle_list(&mut self) -> Result<Vec<f64>> {
        self.angle_list_max(16)
    }

    /// `angle_list` for lists of up to `max` numbers (a polynomial's coefficients).
    pub fn angle_list_max(&mut self, max: usize) -> Result<Vec<f64>> {
        self.angle.push(true);
        let mut comps = Vec::new();
        let result = (|| -> Result<()> {
            loop {
                comps.push(self.float()?);
                if self.accept_sym(">")? {
                    return Ok(());
                }
                self.accept_sym(",")?;
                if comps.len() > max {
                    return self.err(self.here(), "a vector this long never closes; add `>`".into());
                }
            }
        })();
        self.angle.pop();
        result.map(|()| comps)
    }

    fn word_value(&mut self, w: &str, pos: Pos) -> Result<Value> {
        if let Some(Value::Other("a function")) = self.lookup(w) {
            return self.err(pos, format!("`{w}` is a user-defined function, and functions are not supported yet"));
        }
        if let Some(v) = self.lookup(w) {
            return Ok(v.clone());
        }
        let f = |x: f64| Ok(Value::Float(x));
        let vec3 = |x: f64, y: f64, z: f64| Ok(Value::Vector(vec![x, y, z]));
        match w {
            "pi" => f(std::f64::consts::PI),
            "tau" => f(std::f64::consts::TAU),
            "true" | "yes" | "on" => f(1.0),
            "false" | "no" | "off" => f(0.0),
            "x" => vec3(1.0, 0.0, 0.0),
            "y" => vec3(0.0, 1.0, 0.0),
            "z" => vec3(0.0, 0.0, 1.0),
            "t" => Ok(Value::Vector(vec![0.0, 0.0, 0.0, 1.0])),
            "u" => Ok(Value::Vector(vec![1.0, 0.0])),
            "v" => Ok(Value::Vector(vec![0.0, 1.0])),
            "clock" | "initial_clock" => f(self.options.clock),
            "final_clock" => f(1.0),
            "clock_delta" => f(0.0),
            "clock_on" => f((self.options.final_frame > self.options.initial_frame) as u8 as f64),
            "frame_number" => f(self.options.frame as f64),
            "initial_frame" => f(self.options.initial_frame as f64),
            "final_frame" => f(self.options.final_frame as f64),
            "image_width" => f(self.options.width as f64),
            "image_height" => f(self.options.height as f64),
            // POV-Ray's own version until a `#version` sets the language's (the standard
            // includes save it, set 3.5 and restore it).
            "version" => f(self.version.unwrap_or(3.7)),
            "color" | "colour" | "rgb" | "rgbf" | "rgbt" | "rgbft" | "srgb" | "srgbf" | "srgbt" | "srgbft" => {
                self.colour_word(w, pos)
            }
            "function" => self.err(pos, "user-defined functions (`function`) are not supported yet".into()),
            "trace" | "inside" | "eval_pigment" | "vturbulence" | "now" => {
                self.err(pos, format!("`{w}` is not supported yet"))
            }
            _ => self.builtin(w, pos),
        }
    }

    fn colour_word(&mut self, w: &str, pos: Pos) -> Result<Value> {
        if w == "color" || w == "colour" {
            return Ok(Value::Vector(self.colour()?.to_vec()));
        }
        let n = match w.trim_start_matches('s') {
            "rgb" => 3,
            "rgbf" | "rgbt" => 4,
            _ => 5,
        };
        let v = self.unary()?;
        let c = vec_of(&v, n, pos, self)?;
        let mut out = [0.0; 5];
        out[..3].copy_from_slice(&c[..3]);
        match w.trim_start_matches('s') {
            "rgbf" => out[3] = c[3],
            "rgbt" => out[4] = c[3],
            "rgbft" => {
                out[3] = c[3];
                out[4] = c[4];
            }
            _ => {}
        }
        if w.starts_with('s') {
            // sRGB-encoded colour (3.7.1): decode with the exact curve.
            for c in &mut out[..3] {
                *c = if *c <= 0.04045 { *c / 12.92 } else { ((*c + 0.055) / 1.055).powf(2.4) };
            }
        }
        Ok(Value::Vector(out.to_vec()))
    }

    fn builtin(&mut self, w: &str, pos: Pos) -> Result<Value> {
        let one = |p: &mut Parser| -> Result<f64> {
            let a = p.args()?;
            if a.len() != 1 {
                return p.err(pos, format!("{w}() takes 1 argument, not {}", a.len()));
            }
            scalar(&a[0], pos, p)
        };
        let two = |p: &mut Parser| -> Result<(f64, f64)> {
            let a = p.args()?;
            if a.len() != 2 {
                return p.err(pos, format!("{w}() takes 2 arguments, not {}", a.len()));
            }
            Ok((scalar(&a[0], pos, p)?, scalar(&a[1], pos, p)?))
        };
        let f1: Option<fn(f64) -> f64> = match w {
            "abs" => Some(f64::abs),
            "acos" => Some(f64::acos),
            "acosh" => Some(f64::acosh),
            "asin" => Some(f64::asin),
            "asinh" => Some(asinh),
            "atan" => Some(f64::atan),
            "atanh" => Some(f64::atanh),
            "ceil" => Some(f64::ceil),
            "cos" => Some(f64::cos),
            "cosh" => Some(f64::cosh),
            "degrees" => Some(f64::to_degrees),
            "radians" => Some(f64::to_radians),
            "exp" => Some(f64::exp),
            "floor" => Some(f64::floor),
            "int" => Some(f64::trunc),
            "ln" => Some(f64::ln),
            "log" => Some(f64::log10),
            "sin" => Some(f64::sin),
            "sinh" => Some(f64::sinh),
            "sqrt" => Some(f64::sqrt),
            "tan" => Some(f64::tan),
            "tanh" => Some(f64::tanh),
            _ => None,
        };
        if let Some(f) = f1 {
            return Ok(Value::Float(f(one(self)?)));
        }
        let v = match w {
            "atan2" => {
                let (a, b) = two(self)?;
                Value::Float(a.atan2(b))
            }
            "pow" => {
                let (a, b) = two(self)?;
                Value::Float(a.powf(b))
            }
            // C's fmod and truncating division, as POV-Ray computes them.
            "mod" => {
                let (a, b) = two(self)?;
                Value::Float(a % b)
            }
            "div" => {
                let (a, b) = two(self)?;
                Value::Float((a / b).trunc())
            }
            "bitwise_and" | "bitwise_or" | "bitwise_xor" => {
                let a = self.args()?;
                let mut r: Option<i64> = None;
                for x in &a {
                    let x = scalar(x, pos, self)? as i64;
                    r = Some(match (r, w) {
                        (None, _) => x,
                        (Some(r), "bitwise_and") => r & x,
                        (Some(r), "bitwise_or") => r | x,
                        (Some(r), _) => r ^ x,
                    });
                }
                Value::Float(r.unwrap_or(0) as f64)
            }
            "min" | "max" => {
                let a = self.args()?;
                if a.is_empty() {
                    return self.err(pos, format!("{w}() needs at least 1 argument"));
                }
                let mut r = scalar(&a[0], pos, self)?;
                for x in &a[1..] {
                    let x = scalar(x, pos, self)?;
                    r = if w == "min" { r.min(x) } else { r.max(x) };
                }
                Value::Float(r)
            }
            "select" => {
                let a = self.args()?;
                if a.len() != 3 && a.len() != 4 {
                    return self.err(pos, "select() takes 3 or 4 arguments".into());
                }
                let c = scalar(&a[0], pos, self)?;
                if a.len() == 3 {
                    if c < 0.0 {
                        a[1].clone()
                    } else {
                        a[2].clone()
                    }
                } else if c < 0.0 {
                    a[1].clone()
                } else if c == 0.0 {
                    a[2].clone()
                } else {
                    a[3].clone()
                }
            }
            "seed" => {
                // POV-Ray's stream_seed: a new stream starting at the integer seed.
                let s = one(self)?;
                self.rand.push((s as i64) as i32 as u32);
                Value::Float((self.rand.len() - 1) as f64)
            }
            "rand" => {
                let s = one(self)?;
                let i = s as i64;
                if i < 0 || i as usize >= self.rand.len() {
                    return self.err(pos, format!("rand({s}): no such random stream; create one with seed()"));
                }
                Value::Float(pov_rand(&mut self.rand[i as usize]))
            }
            "min_extent" | "max_extent" => {
                // The object's bounding box (POV-Ray's is its own bounding box; here each part's
                // box through its transform, so the same for boxes and close for the rest).
                let a = self.args()?;
                let Some(Value::Object(o)) = a.first() else {
                    return self.err(pos, format!("{w}() takes an object"));
                };
                let (lo, hi) = super::emit::bounds_of(o);
                // POV-Ray's answer for an unbounded object: its huge bound.
                let (lo, hi) = if lo.x <= hi.x { (lo, hi) } else { (DVec3::splat(-2e10), DVec3::splat(2e10)) };
                vec_value(if w == "min_extent" { lo } else { hi })
            }
            "vlength" => {
                let a = self.args()?;
                Value::Float(vec3_of(a.first(), pos, self)?.length())
            }
            "vnormalize" => {
                let a = self.args()?;
                let v = vec3_of(a.first(), pos, self)?;
                let n = if v.length() > 0.0 { v / v.length() } else { v };
                vec_value(n)
            }
            "vaxis_rotate" => {
                let a = self.args()?;
                if a.len() != 3 {
                    return self.err(pos, "vaxis_rotate() takes 3 arguments: the point, the axis and degrees".into());
                }
                let (p, axis) = (vec3_of(a.first(), pos, self)?, vec3_of(a.get(1), pos, self)?);
                let angle = scalar(&a[2], pos, self)?;
                vec_value(axis_angle(axis, angle) * p)
            }
            "vdot" | "vcross" | "vrotate" => {
                let a = self.args()?;
                if a.len() != 2 {
                    return self.err(pos, format!("{w}() takes 2 arguments"));
                }
                let (p, q) = (vec3_of(a.first(), pos, self)?, vec3_of(a.get(1), pos, self)?);
                match w {
                    "vdot" => Value::Float(p.dot(q)),
                    "vcross" => vec_value(p.cross(q)),
                    _ => vec_value(rotation(q).transform_vector3(p)),
                }
            }
            "strlen" => {
                let a = self.args()?;
                Value::Float(str_of(a.first(), pos, self)?.chars().count() as f64)
            }
            "val" => {
                let a = self.args()?;
                let s = str_of(a.first(), pos, self)?;
                Value::Float(s.trim().parse().unwrap_or(0.0))
            }
            "asc" => {
                let a = self.args()?;
                Value::Float(str_of(a.first(), pos, self)?.chars().next().map_or(0.0, |c| c as u32 as f64))
            }
            "strcmp" => {
                let a = self.args()?;
                let (x, y) = (str_of(a.first(), pos, self)?, str_of(a.get(1), pos, self)?);
                Value::Float(x.cmp(&y) as i8 as f64)
            }
            "chr" => {
                let c = one(self)?;
                Value::Str(char::from_u32(c as u32).unwrap_or(' ').to_string())
            }
            "concat" => {
                let a = self.args()?;
                let mut s = String::new();
                for x in &a {
                    let part = str_of(Some(x), pos, self)?;
                    check_string_length(s.len() + part.len(), pos)?;
                    s += &part;
                }
                Value::Str(s)
            }
            "strupr" | "strlwr" => {
                let a = self.args()?;
                let s = str_of(a.first(), pos, self)?;
                Value::Str(if w == "strupr" { s.to_uppercase() } else { s.to_lowercase() })
            }
            "substr" => {
                let a = self.args()?;
                let s = str_of(a.first(), pos, self)?;
                let start = scalar(a.get(1).unwrap_or(&Value::Float(1.0)), pos, self)? as usize;
                let len = scalar(a.get(2).unwrap_or(&Value::Float(0.0)), pos, self)? as usize;
                Value::Str(s.chars().skip(start.saturating_sub(1)).take(len).collect())
            }
            "str" => {
                let a = self.args()?;
                let x = scalar(a.first().unwrap_or(&Value::Float(0.0)), pos, self)?;
                let width = scalar(a.get(1).unwrap_or(&Value::Float(0.0)), pos, self)?;
                let prec = scalar(a.get(2).unwrap_or(&Value::Float(6.0)), pos, self)?;
                Value::Str(pov_str(x, width, prec))
            }
            "vstr" => {
                let a = self.args()?;
                let n = scalar(a.first().unwrap_or(&Value::Float(3.0)), pos, self)? as usize;
                let v = vec_of(a.get(1).unwrap_or(&Value::Float(0.0)), n.clamp(2, 5), pos, self)?;
                let sep = str_of(a.get(2), pos, self)?;
                let width = scalar(a.get(3).unwrap_or(&Value::Float(0.0)), pos, self)?;
                let prec = scalar(a.get(4).unwrap_or(&Value::Float(6.0)), pos, self)?;
                check_string_length(sep.len().saturating_mul(4), pos)?;
                Value::Str(v.iter().map(|x| pov_str(*x, width, prec)).collect::<Vec<_>>().join(&sep))
            }
            "file_exists" => {
                let a = self.args()?;
                let name = str_of(a.first(), pos, self)?;
                Value::Float(self.find_include(&name, pos).is_ok() as u8 as f64)
            }
            "defined" => {
                self.expect_sym("(")?;
                let (name, _) = self.raw_word("an identifier")?;
                self.expect_sym(")")?;
                Value::Float(self.lookup(&name).is_some() as u8 as f64)
            }
            "dimensions" | "dimension_size" => {
                let a = self.args()?;
                let Some(Value::Array(arr)) = a.first() else {
                    return self.err(pos, format!("{w}() takes an array"));
                };
                if w == "dimensions" {
                    Value::Float(arr.dims.len() as f64)
                } else {
                    let d = scalar(a.get(1).unwrap_or(&Value::Float(1.0)), pos, self)? as usize;
                    Value::Float(arr.dims.get(d.wrapping_sub(1)).copied().unwrap_or(0) as f64)
                }
            }
            _ => {
                return self.err(
                    pos,
                    format!(
                        "unknown identifier `{w}` (not declared; check its spelling, or the #include that declares it)"
                    ),
                )
            }
        };
        Ok(v)
    }
}

/// POV-Ray's `rand`: the linear congruential generator of its `POV_rand`
/// (source/core/math/randomsequences.cpp): next = next * 1812433253 + 12345 in 32 bits, divided
/// by 2^32 - 1.
pub fn pov_rand(state: &mut u32) -> f64 {
    *state = state.wrapping_mul(1_812_433_253).wrapping_add(12_345);
    *state as f64 / 4_294_967_295.0
}

/// `str(x, width, precision)`: printf's `%*.*f` (a negative width pads with zeros).
fn pov_str(x: f64, width: f64, prec: f64) -> String {
    let prec = if prec < 0.0 { 6 } else { prec.min(20.0) as usize };
    let w = width.abs().min(64.0) as usize;
    if width < 0.0 {
        format!("{x:0w$.prec$}")
    } else {
        format!("{x:w$.prec$}")
    }
}

/// POV-Ray's rotate <a, b, c>: about x, then y, then z, degrees.
pub fn rotation(angles: DVec3) -> glam::DMat4 {
    let r = angles * std::f64::consts::PI / 180.0;
    glam::DMat4::from_rotation_z(r.z) * glam::DMat4::from_rotation_y(r.y) * glam::DMat4::from_rotation_x(r.x)
}

fn vec_value(v: DVec3) -> Value {
    Value::Vector(vec![v.x, v.y, v.z])
}

fn truth(v: &Value, pos: Pos, p: &Parser) -> Result<bool> {
    Ok(scalar(v, pos, p)? != 0.0)
}

fn scalar(v: &Value, pos: Pos, p: &Parser) -> Result<f64> {
    match v {
        Value::Float(f) => Ok(*f),
        other => p.err(pos, format!("expected a float here, found {}", other.kind())),
    }
}

fn vec_of(v: &Value, n: usize, pos: Pos, p: &Parser) -> Result<Vec<f64>> {
    match v {
        Value::Float(f) => Ok(vec![*f; n]),
        Value::Vector(c) => {
            let mut c = c.clone();
            c.resize(n.max(c.len()), 0.0);
            Ok(c)
        }
        other => p.err(pos, format!("expected a vector here, found {}", other.kind())),
    }
}

fn vec3_of(v: Option<&Value>, pos: Pos, p: &Parser) -> Result<DVec3> {
    let Some(v) = v else { return p.err(pos, "a vector argument is missing".into()) };
    let c = vec_of(v, 3, pos, p)?;
    Ok(DVec3::new(c[0], c[1], c[2]))
}

/// Refuses a string of more than `MAX_STRING_BYTES` before it is made.
fn check_string_length(bytes: usize, pos: Pos) -> Result<()> {
    if bytes > MAX_STRING_BYTES {
        return Err(PovError::at(
            pos,
            format!(
                "this string would be longer than {} (the longest the language holds); see docs/limits.md",
                crate::limits::fmt_bytes(MAX_STRING_BYTES as u64)
            ),
        ));
    }
    Ok(())
}

/// Reads a file the scene names (`what`: "the included file", "the image", "the font") through
/// the scene's file gate (`scene::files`): a regular file of at most `limit` bytes, recorded as
/// an input, confined to the scene's folder in the editor. A refusal for confinement names
/// neither the file nor what it holds.
pub fn read_gated(path: &Path, limit: u64, what: &str) -> std::result::Result<Vec<u8>, String> {
    use crate::scene::files::FileError;
    crate::scene::files::read(path, limit).map_err(|e| {
        let shown = crate::limits::printable_message(&path.display().to_string());
        match e {
            FileError::Outside { .. } => format!("{what}: {e}"),
            FileError::TooLarge { .. } | FileError::NoMemory { .. } => format!("{what} {shown}: {e}"),
            FileError::Io(e) => format!("cannot read {what} {shown}: {e}"),
        }
    })
}

fn str_of(v: Option<&Value>, pos: Pos, p: &Parser) -> Result<String> {
    match v {
        Some(Value::Str(s)) => Ok(s.clone()),
        Some(other) => p.err(pos, format!("expected a string here, found {}", other.kind())),
        None => p.err(pos, "a string argument is missing".into()),
    }
}

pub fn to_colour(v: Value, pos: Pos, p: &Parser) -> Result<Colour> {
    let c = vec_of(&v, 5, pos, p)?;
    Ok([c[0], c[1], c[2], c[3], c[4]])
}

fn arith(a: Value, b: Value, op: &str, pos: Pos, p: &Parser) -> Result<Value> {
    let f = |x: f64, y: f64| match op {
        "+" => x + y,
        "-" => x - y,
        "*" => x * y,
        _ => x / y,
    };
    match (&a, &b) {
        (Value::Float(x), Value::Float(y)) => Ok(Value::Float(f(*x, *y))),
        (Value::Str(x), Value::Str(y)) if op == "+" => {
            check_string_length(x.len() + y.len(), pos)?;
            Ok(Value::Str(format!("{x}{y}")))
        }
        (Value::Float(_) | Value::Vector(_), Value::Float(_) | Value::Vector(_)) => {
            let n = match (&a, &b) {
                (Value::Vector(x), Value::Vector(y)) => x.len().max(y.len()),
                (Value::Vector(x), _) | (_, Value::Vector(x)) => x.len(),
                _ => 3,
            };
            let (x, y) = (vec_of(&a, n, pos, p)?, vec_of(&b, n, pos, p)?);
            Ok(Value::Vector(x.iter().zip(&y).map(|(x, y)| f(*x, *y)).collect()))
        }
        _ => p.err(pos, format!("cannot apply `{op}` to {} and {}", a.kind(), b.kind())),
    }
}

fn element_index(a: &PovArray, index: &[f64]) -> Option<usize> {
    if index.len() != a.dims.len() {
        return None;
    }
    let mut i = 0usize;
    for (x, d) in index.iter().zip(&a.dims) {
        if *x < 0.0 || *x as usize >= *d {
            return None;
        }
        i = i * d + *x as usize;
    }
    Some(i)
}

fn index_array(v: Value, i: f64, pos: Pos, p: &Parser) -> Result<Value> {
    let Value::Array(a) = v else { unreachable!("checked by the caller") };
    let d = a.dims[0];
    if i < 0.0 || i as usize >= d {
        return p.err(pos, format!("index {i} is outside the array (size {d})"));
    }
    let i = i as usize;
    if a.dims.len() == 1 {
        return match &a.items[i] {
            Some(v) => Ok(v.clone()),
            None => p.err(pos, format!("element {i} of the array was never set")),
        };
    }
    let stride: usize = a.dims[1..].iter().product();
    Ok(Value::Array(Box::new(PovArray {
        dims: a.dims[1..].to_vec(),
        items: a.items[i * stride..(i + 1) * stride].to_vec(),
    })))
}

pub fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(n) => format!("the number {}", crate::limits::fmt_number(*n)),
        Tok::Str(s) => format!("the string \"{s}\""),
        Tok::Word(w) => format!("`{w}`"),
        Tok::Directive(d) => format!("#{d}"),
        Tok::Sym(s) => format!("`{s}`"),
    }
}

/// Interns a symbol for comparison with `Tok::Sym` (symbols are the lexer's static strings).
fn leak(sym: &str) -> &'static str {
    [
        "<=", ">=", "!=", "{", "}", "(", ")", "[", "]", "<", ">", "=", "+", "-", "*", "/", ",", ";", ".", "?", ":",
        "!", "&", "|",
    ]
    .into_iter()
    .find(|s| *s == sym)
    .unwrap_or("")
}

fn is_reserved(w: &str) -> bool {
    matches!(
        w,
        "sphere"
            | "box"
            | "cylinder"
            | "cone"
            | "plane"
            | "torus"
            | "union"
            | "difference"
            | "intersection"
            | "merge"
            | "object"
            | "texture"
            | "pigment"
            | "finish"
            | "camera"
            | "light_source"
            | "rgb"
            | "color"
            | "colour"
            | "x"
            | "y"
            | "z"
            | "pi"
            | "clock"
            | "declare"
            | "local"
    )
}

/// Rotation matrix about the unit axis by degrees (POV-Ray's vaxis_rotate and `axis_rotate`).
pub fn axis_angle(axis: DVec3, degrees: f64) -> DMat3 {
    let a = if axis.length() > 0.0 { axis / axis.length() } else { DVec3::Y };
    DMat3::from_axis_angle(a, degrees.to_radians())
}

/// POV-Ray's `asinh`. Not `f64::asinh`: Rust's std computes it with libm's `hypot`, which
/// glibc 2.35 gave a new symbol version, so calling it made the Python wheel need glibc 2.35
/// (`hypot@GLIBC_2.35`, the only symbol past 2.34). The same formula as std's, with the
/// square root written out: asinh x = ln(1 + |x| + x^2 / (1 + sqrt(1 + x^2))), signed as x;
/// ln 2|x| where x^2 would overflow.
fn asinh(x: f64) -> f64 {
    let a = x.abs();
    let r =
        if a > 1e150 { a.ln() + std::f64::consts::LN_2 } else { (a + a * a / (1.0 + (1.0 + a * a).sqrt())).ln_1p() };
    r.copysign(x)
}

#[cfg(test)]
mod tests {
    #[test]
    fn asinh_matches_std_without_hypot() {
        for x in [0.0, 1e-300, 1e-8, 0.3, 1.0, 2.5, 1e3, 1e10, 1e149, 1e151, 1e300, f64::INFINITY] {
            for x in [x, -x] {
                let (ours, std) = (super::asinh(x), x.asinh());
                // A couple of ulps: the same formula, the square root in place of hypot.
                let close = ours == std || (ours - std).abs() <= 4.0 * f64::EPSILON * std.abs();
                assert!(close, "asinh({x}) = {ours}, std {std}");
            }
        }
        assert!(super::asinh(f64::NAN).is_nan());
    }

    use super::*;

    /// Runs `text` and returns the value declared as `R`.
    fn eval(text: &str) -> Value {
        let mut p = Parser::new(Path::new("test.pov"), PovOptions::default());
        if let Err(e) = p.run_text(text, Path::new("test.pov")) {
            panic!("{text}: {} at {:?}", e.message, e.pos);
        }
        p.lookup("R").cloned().expect("the text declares R")
    }

    fn float(text: &str) -> f64 {
        match eval(text) {
            Value::Float(f) => f,
            other => panic!("{text}: {other:?}"),
        }
    }

    fn vector(text: &str) -> Vec<f64> {
        match eval(text) {
            Value::Vector(v) => v,
            other => panic!("{text}: {other:?}"),
        }
    }

    fn error(text: &str) -> PovError {
        let mut p = Parser::new(Path::new("test.pov"), PovOptions::default());
        p.max_tokens = 100_000;
        match p.run_text(text, Path::new("test.pov")) {
            Ok(_) => panic!("{text}: no error"),
            Err(e) => e,
        }
    }

    #[test]
    fn arithmetic_follows_povray_precedence() {
        assert_eq!(float("#declare R = 1 + 2 * 3 - 4 / 2;"), 5.0);
        assert_eq!(float("#declare R = -2 * -3;"), 6.0);
        assert_eq!(float("#declare R = (1 < 2) & (3 >= 3) | 0;"), 1.0);
        assert_eq!(float("#declare R = 1 = 2 ? 10 : 20;"), 20.0);
        assert_eq!(float("#declare R = !0 + (2 != 2);"), 1.0);
        // Values POV-Ray 3.7 printed for the same expressions (#debug str(...)).
        assert_eq!(float("#declare R = mod(-7, 3);"), -1.0);
        assert_eq!(float("#declare R = int(-2.5);"), -2.0);
        assert_eq!(float("#declare R = div(-7, 2);"), -3.0);
        assert!((float("#declare R = vlength(vrotate(<1,0,0>, <0,90,0>));") - 1.0).abs() < 1e-12);
        assert_eq!(float("#declare R = max(1, 5, 3) + min(4, 2) + abs(-1) + pow(2, 3) + sqrt(16);"), 20.0);
        assert!((float("#declare R = degrees(atan2(1, 1)) + radians(180) - pi;") - 45.0).abs() < 1e-12);
        assert_eq!(float("#declare R = select(-1, 10, 20) + select(0, 1, 2, 3);"), 12.0);
    }

    #[test]
    fn vrotate_matches_povray() {
        // POV-Ray 3.7: vstr(3, vrotate(<1,2,3>, <30,40,50>), ",", 0, 9) = 1.801281062,2.507690147,2.113498678
        let v = vector("#declare R = vrotate(<1,2,3>, <30,40,50>);");
        let want = [1.801281062, 2.507690147, 2.113498678];
        for i in 0..3 {
            assert!((v[i] - want[i]).abs() < 1e-9, "{v:?}");
        }
    }

    #[test]
    fn vectors_colours_and_components() {
        assert_eq!(vector("#declare R = <1, 2, 3> * 2 + x;"), vec![3.0, 4.0, 6.0]);
        assert_eq!(vector("#declare R = vcross(x, y);"), vec![0.0, 0.0, 1.0]);
        assert_eq!(float("#declare V = <1, 2, 3>; #declare R = V.y + V.z;"), 5.0);
        assert_eq!(vector("#declare R = rgb <1, 0.5, 0>;"), vec![1.0, 0.5, 0.0, 0.0, 0.0]);
        assert_eq!(vector("#declare R = color rgb 1 filter 0.5;"), vec![1.0, 1.0, 1.0, 0.5, 0.0]);
        assert_eq!(vector("#declare R = rgbt <0.2, 0.3, 0.4, 0.9>;"), vec![0.2, 0.3, 0.4, 0.0, 0.9]);
        assert_eq!(
            vector("#declare C = rgb <1, 0, 0>; #declare R = color C * 0.5 green 1;"),
            vec![0.5, 1.0, 0.0, 0.0, 0.0]
        );
        // A vector list without commas is two vectors, not a comparison.
        assert_eq!(vector("#declare A = array[2] { <1, 2> <3, 4> } #declare R = A[1];"), vec![3.0, 4.0]);
    }

    #[test]
    fn strings_and_their_functions() {
        let s = |t: &str| match eval(t) {
            Value::Str(s) => s,
            other => panic!("{other:?}"),
        };
        assert_eq!(s("#declare R = concat(\"a\", str(1.5, 0, 2), chr(66));"), "a1.50B");
        assert_eq!(s("#declare R = substr(\"photonix\", 2, 4);"), "hoto");
        assert_eq!(float("#declare R = strlen(\"abc\") + val(\"2.5\");"), 5.5);
    }

    #[test]
    fn rand_gives_povray_numbers() {
        // Printed by POV-Ray 3.7.0 (Debian's povray): seed(42) then three rand(), seed(-7) then one.
        let v = vector("#declare S = seed(42); #declare R = <rand(S), rand(S), rand(S)>;");
        let want = [0.723582911241, 0.329979259598, 0.755761670357];
        for i in 0..3 {
            assert!((v[i] - want[i]).abs() < 1e-12, "{v:?}");
        }
        let f = float("#declare S = seed(1); #declare T = seed(-7); #declare R = rand(T);");
        assert!((f - 0.046072868175).abs() < 1e-12, "{f}");
        assert!((float("#declare S = seed(0); #declare R = rand(S);") - 0.000002874294).abs() < 1e-12);
    }

    #[test]
    fn loops_conditionals_and_switch() {
        assert_eq!(
            float("#declare R = 0; #declare I = 0; #while (I < 10) #declare R = R + I; #declare I = I + 1; #end"),
            45.0
        );
        assert_eq!(float("#declare R = 0; #for (I, 1, 9, 2) #declare R = R + I; #end"), 25.0);
        assert_eq!(float("#declare R = 0; #for (I, 3, 1, -1) #declare R = R * 10 + I; #end"), 321.0);
        assert_eq!(float("#declare R = 0; #for (I, 5, 1) #declare R = 1; #end"), 0.0);
        let sw = |v: f64| {
            float(&format!(
                "#declare R = 0; #switch ({v}) #case (1) #declare R = 10; #break #case (2) #case (3) #declare R = 23; #break \
                 #range (4, 6) #declare R = 46; #else #declare R = -1; #end"
            ))
        };
        assert_eq!((sw(1.0), sw(2.0), sw(3.0), sw(5.0), sw(9.0)), (10.0, 23.0, 23.0, 46.0, -1.0));
        assert_eq!(float("#declare A = 1; #if (A > 2) #declare R = 1; #elseif (A = 1) #declare R = 2; #else #declare R = 3; #end"), 2.0);
        assert_eq!(float("#ifdef (Nope) #declare R = 1; #else #declare R = 2; #end"), 2.0);
        assert_eq!(
            float(
                "#declare X = 1; #ifndef (X) #declare R = 1; #else #if (0) #declare R = 5; #end #declare R = 3; #end"
            ),
            3.0
        );
    }

    #[test]
    fn macros_take_parameters_and_recurse_to_a_limit() {
        assert_eq!(float("#macro Fact(N) #if (N <= 1) 1 #else N * Fact(N - 1) #end #end #declare R = Fact(5);"), 120.0);
        assert_eq!(float("#macro Add(A, B) (A + B) #end #declare R = Add(2, 3) * 2;"), 10.0);
        assert_eq!(float("#macro Set(V) #local T = V * 2; #declare R = T; #end Set(4)"), 8.0);
        // #local in a macro does not leak; #declare of a global inside does.
        let e = error("#macro F() #local Q = 1; #end F() #declare R = Q;");
        assert!(e.message.contains("unknown identifier `Q`"), "{}", e.message);
        let e = error("#macro Loop(N) Loop(N + 1) #end #declare R = Loop(1);");
        assert!(e.message.contains("deeper than"), "{}", e.message);
        assert_eq!(e.pos.map(|p| p.line), Some(1));
        let e = error("#macro Two(A, B) A #end #declare R = Two(1);");
        assert!(e.message.contains("takes 2 arguments"), "{}", e.message);
    }

    #[test]
    fn arrays_hold_values_and_check_their_bounds() {
        assert_eq!(
            float(
                "#declare A = array[3] {1, 2, 3} #declare A[1] = 5; #declare R = A[0] + A[1] + dimension_size(A, 1);"
            ),
            9.0
        );
        assert_eq!(float("#declare A = array[2][2] {{1, 2}, {3, 4}} #declare R = A[1][0];"), 3.0);
        let e = error("#declare A = array[2]; #declare R = A[2];");
        assert!(e.message.contains("outside the array"), "{}", e.message);
        let e = error("#declare A = array[2]; #declare R = A[1];");
        assert!(e.message.contains("never set"), "{}", e.message);
    }

    #[test]
    fn errors_name_line_and_column_and_refuse_what_is_missing() {
        let e = error("#declare A = 1;\n#declare R = A + Bogus;");
        assert_eq!(e.pos.map(|p| (p.line, p.col)), Some((2, 18)));
        assert!(e.message.contains("unknown identifier `Bogus`"));
        let e = error("#declare F = function { x * 2 }\n#declare R = F(1);");
        assert!(e.message.contains("functions are not supported yet"), "{}", e.message);
        assert_eq!(e.pos.map(|p| p.line), Some(2));
        let e = error("#declare R = trace(A, <0,0,0>, y);");
        assert!(e.message.contains("`trace` is not supported yet"), "{}", e.message);
        let e = error("#fopen F \"in.txt\" read");
        assert!(e.message.contains("reading files"), "{}", e.message);
        let e = error("#write (G, \"x\")");
        assert!(e.message.contains("not a file opened for writing"), "{}", e.message);
        let e = error("#if (1) #declare R = 1;");
        assert!(e.message.contains("no #end"), "{}", e.message);
        let e = error("#declare R = 0; #while (1) #declare R = R + 1; #end");
        assert!(e.message.contains("runaway"), "{}", e.message);
    }

    #[test]
    fn file_output_is_evaluated_and_not_written() {
        let mut p = Parser::new(Path::new("t.pov"), PovOptions::default());
        p.run_text(
            "#fopen F \"out.html\" write\n#write (F, \"<p>\", 1 + 2, \"\\n\")\n#write(F concat(\"a\", \"b\"))\n#fclose F\n#declare R = 1;",
            Path::new("t.pov"),
        )
        .unwrap();
        assert!(matches!(p.lookup("R"), Some(Value::Float(_))));
        assert!(p.warnings.iter().any(|w| w.contains("file output is not written")), "{:?}", p.warnings);
    }

    #[test]
    fn image_size_and_clock_come_from_the_options() {
        let mut p = Parser::new(
            Path::new("t.pov"),
            PovOptions { width: 640, height: 480, clock: 0.25, ..PovOptions::default() },
        );
        p.run_text("#declare R = image_width / image_height + clock;", Path::new("t.pov")).unwrap();
        let Some(Value::Float(r)) = p.lookup("R") else { panic!() };
        assert!((r - (640.0 / 480.0 + 0.25)).abs() < 1e-12);
    }

    #[test]
    fn array_slots_count_against_the_token_budget() {
        // (The budget here is 100 000.) A 60 000-slot array made once fits; made twice, or
        // copied once, it does not, whatever few tokens ask for it.
        float("#declare A = array[60000]; #declare R = 1;");
        let e = error("#declare A = array[60000]; #declare B = array[60000];");
        assert!(e.message.contains("array's slots"), "{}", e.message);
        let e = error("#declare A = array[40000]; #declare B = A;");
        assert!(e.message.contains("array's slots"), "{}", e.message);
        let e = error("#declare A = array[1000]; #for (I, 1, 1000) #declare B = A; #end");
        assert!(e.message.contains("array's slots") && e.pos.map(|p| p.line) == Some(1), "{}", e.message);
    }
}
