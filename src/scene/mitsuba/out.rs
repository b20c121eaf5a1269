//! The TOML text being written: entries with the Mitsuba position each came from, unique names,
//! and values written as TOML.

use std::collections::HashSet;
use std::fmt::Write;

use super::Pos;

#[derive(Default)]
pub struct Out {
    pub text: String,
    /// (first TOML line of an entry, 1-based; the XML position it came from), in line order.
    pub origins: Vec<(usize, Pos)>,
    names: HashSet<(String, String)>,
}

/// Fields of one entry, each a key and its value as TOML text.
pub type Fields = Vec<(String, String)>;

impl Out {
    /// Writes `[header]` (or `[[header]]`) and its fields, remembering where it came from.
    pub fn entry(&mut self, header: &str, fields: &Fields, pos: Pos) {
        let line = self.text.matches('\n').count() + 1;
        self.origins.push((line, pos));
        let _ = writeln!(self.text, "{header}");
        for (k, v) in fields {
            let _ = writeln!(self.text, "{k} = {v}");
        }
        self.text.push('\n');
    }

    /// `base`, or `base 2`, `base 3`, ... : a name not yet taken in `namespace`.
    pub fn unique(&mut self, namespace: &str, base: &str) -> String {
        let base = if base.is_empty() { "unnamed" } else { base };
        let mut name = base.to_string();
        let mut n = 2;
        while self.names.contains(&(namespace.to_string(), name.clone())) {
            name = format!("{base} {n}");
            n += 1;
        }
        self.names.insert((namespace.to_string(), name.clone()));
        name
    }
}

/// A number as TOML (always with a point or exponent, never NaN: callers pass finite values).
pub fn num(v: f64) -> String {
    let v = if v == 0.0 { 0.0 } else { v };
    format!("{v:?}")
}

pub fn vec3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

pub fn list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| num(*x)).collect();
    format!("[{}]", items.join(", "))
}

pub fn string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// `materials."name"`-style key part: bare when it can be.
pub fn key(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
        s.to_string()
    } else {
        string(s)
    }
}

pub fn field(fields: &mut Fields, k: &str, v: String) {
    fields.retain(|(key, _)| key != k);
    fields.push((k.to_string(), v));
}
