//! How much a value of the language holds: its nodes (objects, textures, pigments, array
//! elements) and an estimate of its bytes, as the translation would expand it, and how deep it
//! nests. Values built from declared values (`#declare U = union { object { U } object { U } }`
//! in a loop, a texture map of a declared texture, an array holding the array before it) can
//! double or deepen with every statement; the evaluator measures each value it stores and
//! refuses one past the limits (`parser::MAX_VALUE_NODES`, `MAX_VALUE_DEPTH`,
//! `MAX_LANGUAGE_BYTES`), so that nothing later (the translation, dropping the value) recurses
//! deeper or works longer than those limits allow.
//!
//! The walk stops at the first node past a limit: its time and its recursion are bounded by the
//! limits whatever the value, since every stored value was measured when it was stored.

use std::mem::size_of;

use super::ast::{Interior, Media, Obj, ObjKind, Pigment, PigmentKind, Tex};
use super::parser::{Value, MAX_LANGUAGE_BYTES, MAX_VALUE_DEPTH, MAX_VALUE_NODES};

/// What a value holds, within the limits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Size {
    pub nodes: usize,
    pub bytes: usize,
    /// The nodes and array slots (empty ones too) the walk visited: what storing, copying or
    /// dropping the value costs, charged to the scene's token budget.
    pub work: usize,
}

/// Which limit a value passed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TooBig {
    /// It nests deeper than `MAX_VALUE_DEPTH`.
    Deep,
    /// It holds more than `MAX_VALUE_NODES` nodes or `MAX_LANGUAGE_BYTES` bytes.
    Large,
}

impl TooBig {
    /// The reason, for a message that names the value.
    pub fn reason(self) -> String {
        match self {
            TooBig::Deep => format!(
                "nests deeper than {MAX_VALUE_DEPTH} levels (objects in objects, textures in texture maps, arrays in arrays)"
            ),
            TooBig::Large => format!(
                "holds more than {MAX_VALUE_NODES} objects, textures or elements, or more than {} (a value declared from itself in a loop doubles)",
                crate::limits::fmt_bytes(MAX_LANGUAGE_BYTES as u64)
            ),
        }
    }
}

/// Measures `v`.
pub fn value(v: &Value) -> Result<Size, TooBig> {
    value_at(v, 0)
}

/// Measures `v` as it stands `depth` levels down in another value (an array's element).
pub fn value_at(v: &Value, depth: usize) -> Result<Size, TooBig> {
    let mut w = Walk::default();
    w.value(v, depth)?;
    Ok(w.size)
}

/// Measures an object.
pub fn object(o: &Obj) -> Result<Size, TooBig> {
    let mut w = Walk::default();
    w.obj(o, 0)?;
    Ok(w.size)
}

#[derive(Default)]
struct Walk {
    size: Size,
}

impl Walk {
    fn node(&mut self, depth: usize, bytes: usize) -> Result<(), TooBig> {
        if depth > MAX_VALUE_DEPTH {
            return Err(TooBig::Deep);
        }
        self.size.nodes += 1;
        self.size.work += 1;
        self.size.bytes = self.size.bytes.saturating_add(bytes);
        if self.size.nodes > MAX_VALUE_NODES || self.size.bytes > MAX_LANGUAGE_BYTES {
            return Err(TooBig::Large);
        }
        Ok(())
    }

    fn value(&mut self, v: &Value, d: usize) -> Result<(), TooBig> {
        match v {
            Value::Str(s) => self.node(d, size_of::<Value>() + s.len()),
            Value::Vector(c) => self.node(d, size_of::<Value>() + 8 * c.len()),
            Value::Array(a) => {
                self.node(d, size_of::<Value>() + a.items.len() * size_of::<Option<Value>>())?;
                self.size.work += a.items.len();
                a.items.iter().flatten().try_for_each(|x| self.value(x, d + 1))
            }
            Value::Object(o) => self.obj(o, d),
            Value::Texture(layers) | Value::Material(layers, None) => {
                self.node(d, size_of::<Value>())?;
                layers.iter().try_for_each(|t| self.tex(t, d + 1))
            }
            Value::Material(layers, Some(i)) => {
                self.node(d, size_of::<Value>())?;
                layers.iter().try_for_each(|t| self.tex(t, d + 1))?;
                self.interior(i, d + 1)
            }
            Value::Pigment(p) => self.pigment(p, d),
            Value::Interior(i) => self.interior(i, d),
            Value::Media(m) => self.media(m, d),
            Value::Sky(s) => {
                self.node(d, size_of::<Value>())?;
                s.pigments.iter().try_for_each(|p| self.pigment(p, d + 1))
            }
            Value::ColorMap(m) => self.node(d, size_of::<Value>() + m.len() * 48),
            _ => self.node(d, size_of::<Value>()),
        }
    }

    fn obj(&mut self, o: &Obj, d: usize) -> Result<(), TooBig> {
        // Shared triangles count once per reference: the translation writes each reference's.
        let triangles = match &o.kind {
            ObjKind::Triangles { tris, normals } => tris.len() * 72 + normals.as_ref().map_or(0, |n| n.len() * 72),
            _ => 0,
        };
        self.node(d, size_of::<Obj>() + triangles)?;
        if let Some(layers) = &o.tex {
            layers.iter().try_for_each(|t| self.tex(t, d + 1))?;
        }
        if let Some(i) = &o.interior {
            self.interior(i, d + 1)?;
        }
        match &o.kind {
            ObjKind::Csg { children, .. } => children.iter().try_for_each(|c| self.obj(c, d + 1)),
            ObjKind::Light(l) => l.looks_like.as_ref().map_or(Ok(()), |o| self.obj(o, d + 1)),
            _ => Ok(()),
        }
    }

    fn tex(&mut self, t: &Tex, d: usize) -> Result<(), TooBig> {
        self.node(d, size_of::<Tex>())?;
        self.pigment(&t.pigment, d + 1)?;
        if let Some(map) = &t.map {
            for (_, layers) in &map.entries {
                layers.iter().try_for_each(|t| self.tex(t, d + 1))?;
            }
        }
        Ok(())
    }

    fn pigment(&mut self, p: &Pigment, d: usize) -> Result<(), TooBig> {
        let extra = match &p.kind {
            PigmentKind::Pattern { map, fields, .. } => map.len() * 48 + fields.len() * 64,
            PigmentKind::Image { file, .. } => file.len(),
            PigmentKind::Solid(_) => 0,
        };
        self.node(d, size_of::<Pigment>() + extra)?;
        if let Some(entries) = &p.entries {
            entries.iter().try_for_each(|(_, p)| self.pigment(p, d + 1))?;
        }
        Ok(())
    }

    fn interior(&mut self, i: &Interior, d: usize) -> Result<(), TooBig> {
        self.node(d, size_of::<Interior>())?;
        i.media.iter().try_for_each(|m| self.media(m, d + 1))
    }

    fn media(&mut self, m: &Media, d: usize) -> Result<(), TooBig> {
        self.node(d, size_of::<Media>())?;
        m.density.as_ref().map_or(Ok(()), |p| self.pigment(p, d + 1))
    }
}
