//! A plugin's properties (`<float name=..>`, `<rgb ..>`, nested plugins), read by their Mitsuba 3
//! names: the 0.5/0.6 camelCase names (`toWorld`, `intIOR`, `specularReflectance`) are the same
//! names in snake_case. Every property read is marked, so the ones Photonix ignores can be named.

use std::cell::RefCell;

use super::xml::Element;
use super::{MitsubaError, Pos};

type Result<T> = std::result::Result<T, MitsubaError>;

/// Tags of nested plugins (the rest of a plugin's children are properties).
pub const PLUGIN_TAGS: &[&str] = &[
    "bsdf",
    "texture",
    "emitter",
    "medium",
    "phase",
    "rfilter",
    "film",
    "sampler",
    "shape",
    "sensor",
    "integrator",
    "ref",
    "volume",
];

/// Properties Mitsuba 0.5 files carry that change nothing Photonix renders (film and output
/// settings, quality knobs of Mitsuba's own), read quietly.
const QUIET: &[&str] = &[
    "high_quality_edges",
    "file_format",
    "pixel_format",
    "component_format",
    "banner",
    "attach_log",
    "rr_depth",
    "strict_normals",
    "hide_emitters",
    "near_clip",
    "far_clip",
    "max_anisotropy",
    "sample_visible",
    "cache",
];

/// `toWorld` -> `to_world`, `intIOR` -> `int_ior`, `sigmaA` -> `sigma_a`; snake_case stays.
pub fn snake_case(name: &str) -> String {
    let mut out = String::new();
    let mut prev: Option<char> = None;
    for c in name.chars() {
        if c.is_ascii_uppercase() {
            if prev.is_some_and(|p| p.is_ascii_lowercase() || p.is_ascii_digit()) {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
        prev = Some(c);
    }
    out
}

/// A plugin element (`<bsdf type="diffuse">`) and which of its children were read.
pub struct Plugin<'a> {
    pub el: &'a Element,
    pub kind: String,
    used: RefCell<Vec<bool>>,
}

impl<'a> Plugin<'a> {
    pub fn new(el: &'a Element) -> Plugin<'a> {
        Plugin {
            el,
            kind: el.attr("type").unwrap_or("").to_string(),
            used: RefCell::new(vec![false; el.children.len()]),
        }
    }

    pub fn pos(&self) -> Pos {
        self.el.pos
    }

    pub fn id(&self) -> Option<&'a str> {
        self.el.attr("id")
    }

    /// "`diffuse` (<bsdf>)" for messages.
    pub fn what(&self) -> String {
        format!("<{} type=\"{}\">", self.el.tag, crate::limits::printable(&self.kind))
    }

    pub fn error(&self, pos: Pos, message: String) -> MitsubaError {
        MitsubaError::at(pos, format!("{}: {message}", self.what()))
    }

    /// The child property of this (normalised) name, marked as read.
    pub fn prop(&self, name: &str) -> Option<&'a Element> {
        let i = self.el.children.iter().position(|c| {
            !PLUGIN_TAGS.contains(&c.tag.as_str()) && c.attr("name").is_some_and(|n| snake_case(n) == name)
        })?;
        self.used.borrow_mut()[i] = true;
        Some(&self.el.children[i])
    }

    /// A nested plugin or `<ref>` of this `name` attribute (or, with `None`, every nested plugin
    /// of this tag without a name), marked as read.
    pub fn plugins(&self, tag: &str, name: Option<&str>) -> Vec<&'a Element> {
        let mut out = Vec::new();
        for (i, c) in self.el.children.iter().enumerate() {
            let tag_ok = c.tag == tag || c.tag == "ref";
            let name_ok = match name {
                Some(n) => c.attr("name").is_some_and(|m| snake_case(m) == n),
                None => c.tag == tag,
            };
            if tag_ok && name_ok {
                self.used.borrow_mut()[i] = true;
                out.push(c);
            }
        }
        out
    }

    /// Marks child `i` as read.
    pub fn mark(&self, i: usize) {
        self.used.borrow_mut()[i] = true;
    }

    pub fn float(&self, name: &str) -> Result<Option<f64>> {
        let Some(p) = self.prop(name) else { return Ok(None) };
        if !matches!(p.tag.as_str(), "float" | "integer") {
            return Err(self.error(p.pos, format!("`{name}` is a <{}>; give a <float>", p.tag)));
        }
        let v = value(p)?;
        parse_number(v).map(Some).ok_or_else(|| {
            self.error(p.pos, format!("`{name}` = \"{}\" is not a finite number", crate::limits::printable(v)))
        })
    }

    pub fn float_or(&self, name: &str, default: f64) -> Result<f64> {
        Ok(self.float(name)?.unwrap_or(default))
    }

    pub fn integer(&self, name: &str) -> Result<Option<i64>> {
        let Some(p) = self.prop(name) else { return Ok(None) };
        let v = value(p)?;
        v.trim()
            .parse::<i64>()
            .map(Some)
            .map_err(|_| self.error(p.pos, format!("`{name}` = \"{}\" is not an integer", crate::limits::printable(v))))
    }

    pub fn boolean(&self, name: &str) -> Result<Option<bool>> {
        let Some(p) = self.prop(name) else { return Ok(None) };
        match value(p)?.trim() {
            "true" | "1" => Ok(Some(true)),
            "false" | "0" => Ok(Some(false)),
            v => Err(self.error(p.pos, format!("`{name}` = \"{}\": give true or false", crate::limits::printable(v)))),
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<(&'a str, Pos)>> {
        let Some(p) = self.prop(name) else { return Ok(None) };
        Ok(Some((value(p)?, p.pos)))
    }

    /// A point or vector property: `<point name=".." x=".." y=".." z=".."/>` or `value="x, y, z"`.
    pub fn vector(&self, name: &str) -> Result<Option<[f64; 3]>> {
        let Some(p) = self.prop(name) else { return Ok(None) };
        xyz(p, 0.0).map(Some)
    }

    /// Warnings for the properties nobody read, with their positions.
    pub fn unread(&self, location: &dyn Fn(Pos) -> String, warnings: &mut Vec<String>) {
        for (i, c) in self.el.children.iter().enumerate() {
            if self.used.borrow()[i] {
                continue;
            }
            let name = c.attr("name").map(snake_case).unwrap_or_default();
            if QUIET.contains(&name.as_str()) {
                continue;
            }
            let what =
                if name.is_empty() { format!("<{}>", c.tag) } else { format!("`{}`", crate::limits::printable(&name)) };
            warnings.push(format!(
                "{}: {}: {what} is not read by Photonix and is ignored",
                location(c.pos),
                self.what()
            ));
        }
    }
}

/// The `value` attribute of a property element.
pub fn value(p: &Element) -> Result<&str> {
    p.attr("value").ok_or_else(|| MitsubaError::at(p.pos, format!("<{}> needs a `value` attribute", p.tag)))
}

pub fn parse_number(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok().filter(|v| v.is_finite() && v.abs() < 1e30)
}

/// Numbers separated by commas and/or spaces.
pub fn numbers(s: &str) -> Option<Vec<f64>> {
    s.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty()).map(parse_number).collect()
}

/// `x`, `y`, `z` attributes (each defaulting to `default`), or `value="x, y, z"` (one number: all three).
pub fn xyz(p: &Element, default: f64) -> Result<[f64; 3]> {
    if let Some(v) = p.attr("value") {
        return match numbers(v).as_deref() {
            Some([a]) => Ok([*a; 3]),
            Some([a, b, c]) => Ok([*a, *b, *c]),
            _ => Err(MitsubaError::at(
                p.pos,
                format!("<{}>: `value` = \"{}\": give 3 numbers", p.tag, crate::limits::printable(v)),
            )),
        };
    }
    let mut out = [default; 3];
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        if let Some(s) = p.attr(axis) {
            out[k] = parse_number(s).ok_or_else(|| {
                MitsubaError::at(
                    p.pos,
                    format!("<{}>: `{axis}` = \"{}\" is not a finite number", p.tag, crate::limits::printable(s)),
                )
            })?;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mitsuba_05_names_become_mitsuba_3_names() {
        for (old, new) in [
            ("toWorld", "to_world"),
            ("intIOR", "int_ior"),
            ("specularReflectance", "specular_reflectance"),
            ("sigmaA", "sigma_a"),
            ("fovAxis", "fov_axis"),
            ("to_world", "to_world"),
            ("alpha", "alpha"),
        ] {
            assert_eq!(snake_case(old), new);
        }
    }
}
