//! The checks every section shares: required fields, fields a kind does not take, names from a
//! list, and finite numbers, points, directions and colours within the scene's range.

use std::ops::Range;

use glam::Vec3;
use toml::Spanned;

use super::{Builder, Present, Result};
use crate::limits::{fmt_f32, fmt_number, printable, MAX_SCENE_VALUE};
use crate::scene::error::{backticked, suggest, SceneError};
use crate::scene::format::Vec3Def;
use crate::scene::kinds::Kind;

impl Builder<'_> {
    pub(super) fn invalid(&self, span: &Range<usize>, object: &str, message: String) -> SceneError {
        self.src.invalid(span, object, message)
    }

    /// The field, or an error at the table's line saying what to add.
    pub(super) fn require<'f, T>(
        &self,
        field: &'f Option<Spanned<T>>,
        table: &Range<usize>,
        object: &str,
        name: &str,
        example: &str,
    ) -> Result<&'f Spanned<T>> {
        field
            .as_ref()
            .ok_or_else(|| self.invalid(table, object, format!("missing field `{name}`; add it, e.g. `{example}`")))
    }

    /// Rejects the fields of the format that `kind` does not take (`scene::kinds` declares those
    /// it takes).
    pub(super) fn only_kind_fields(&self, object: &str, kind: &Kind, present: &[Present<'_>]) -> Result<()> {
        self.only_fields(object, kind.what, present, &kind.field_names())
    }

    /// Rejects fields that exist in the format but not for this `type`, suggesting the one it
    /// takes that is spelled most like it.
    pub(super) fn only_fields(
        &self,
        object: &str,
        what: &str,
        present: &[Present<'_>],
        allowed: &[&str],
    ) -> Result<()> {
        for (name, span) in present {
            if let Some(span) = span {
                if !allowed.contains(name) {
                    let hint = match suggest(name, allowed) {
                        Some(best) => format!("did you mean `{best}`? "),
                        None => String::new(),
                    };
                    return Err(self.invalid(
                        span,
                        object,
                        format!("`{name}` does not apply to {what} ({hint}it takes {})", backticked(allowed)),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks an entry's `group` (docs/scene-format.md, "Groups"): a name of 1 to 64 characters
    /// with no control characters, on a top-level `[[shapes]]`, `[[lights]]` or `[[instances]]`
    /// entry only. Groups are the editor's folders: the scene is already flat, so the renderer
    /// reads nothing more from them.
    pub(super) fn group(&self, group: &Option<Spanned<String>>, object: &str, top_level: bool) -> Result<()> {
        let Some(group) = group else { return Ok(()) };
        if !top_level {
            return Err(self.invalid(
                &group.span(),
                object,
                "`group` applies only to top-level [[shapes]], [[lights]] and [[instances]] entries, not to an \
                 object's shapes or a csg's children; remove it"
                    .to_string(),
            ));
        }
        let name = group.get_ref();
        if name.is_empty() || name.chars().count() > 64 || name.chars().any(char::is_control) {
            return Err(self.invalid(
                &group.span(),
                object,
                "a `group` is a name of 1 to 64 characters with no control characters".to_string(),
            ));
        }
        Ok(())
    }

    /// A `type` (or `shape`) value that must be one of `valid`.
    pub(super) fn one_of<'v>(
        &self,
        value: &Spanned<String>,
        object: &str,
        field: &str,
        valid: &[&'v str],
    ) -> Result<&'v str> {
        let given = value.get_ref().as_str();
        if let Some(hit) = valid.iter().find(|v| **v == given) {
            return Ok(hit);
        }
        let given = printable(given);
        let hint = match suggest(&given, valid) {
            Some(best) => format!("did you mean \"{best}\"?"),
            None => format!("use one of {}", valid.iter().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", ")),
        };
        Err(self.invalid(&value.span(), object, format!("unknown {field} \"{given}\" ({hint})")))
    }

    /// A finite number within the scene range, +-`MAX_SCENE_VALUE`.
    pub(super) fn number(&self, value: &Spanned<f64>, object: &str, field: &str) -> Result<f32> {
        let v = *value.get_ref();
        if !v.is_finite() {
            return Err(self.invalid(&value.span(), object, format!("`{field}` is {v}; give a finite number")));
        }
        if v.abs() > MAX_SCENE_VALUE {
            return Err(self.invalid(&value.span(), object, out_of_scene_range(field, v)));
        }
        Ok(v as f32)
    }

    /// A point or direction: three finite numbers, never a single number.
    pub(super) fn point(&self, value: &Spanned<Vec3Def>, object: &str, field: &str) -> Result<Vec3> {
        if value.get_ref().scalar {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` must be an array of 3 numbers [x, y, z]"),
            ));
        }
        self.vector(value, object, field)
    }

    /// Three finite numbers; a single number `v` means `[v, v, v]`.
    pub(super) fn vector(&self, value: &Spanned<Vec3Def>, object: &str, field: &str) -> Result<Vec3> {
        let v = value.get_ref().value;
        if let Some(bad) = v.iter().find(|c| !c.is_finite()) {
            return Err(self.invalid(&value.span(), object, format!("`{field}` contains {bad}; give finite numbers")));
        }
        if let Some(big) = v.iter().find(|c| c.abs() > MAX_SCENE_VALUE) {
            return Err(self.invalid(&value.span(), object, out_of_scene_range(field, *big)));
        }
        Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
    }

    /// An RGB triple that must be >= 0, and <= 1 when `at_most_one` (albedos and tints).
    pub(super) fn color(
        &self,
        value: &Spanned<Vec3Def>,
        object: &str,
        field: &str,
        at_most_one: bool,
    ) -> Result<[f32; 3]> {
        let c = self.vector(value, object, field)?;
        if c.min_element() < 0.0 {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is negative ({}); it must be >= 0 in every channel", vec3_text(c)),
            ));
        }
        if at_most_one && c.max_element() > 1.0 {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is above 1 ({}); it is a fraction of light, in [0, 1] per channel", vec3_text(c)),
            ));
        }
        Ok(c.to_array())
    }

    /// A whole number in `min..=max`; `unit` follows the numbers in the message (" photon
    /// paths"), `hint` follows a number below the minimum.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn integer(
        &self,
        value: &Spanned<i64>,
        object: &str,
        field: &str,
        min: u32,
        max: u32,
        unit: &str,
        hint: &str,
    ) -> Result<u32> {
        let v = *value.get_ref();
        if v < min as i64 {
            let message = format!("`{field}` is {v}; it must be at least {min}{unit} (and at most {max}){hint}");
            return Err(self.invalid(&value.span(), object, message));
        }
        if v > max as i64 {
            let message = format!("`{field}` is {v}; it must be at most {max}{unit} (see docs/limits.md)");
            return Err(self.invalid(&value.span(), object, message));
        }
        Ok(v as u32)
    }

    /// A number > 0; `what` says what it measures.
    pub(super) fn positive_measure(&self, value: &Spanned<f64>, object: &str, field: &str, what: &str) -> Result<f32> {
        let v = self.number(value, object, field)?;
        if v <= 0.0 {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is {}; it must be > 0 ({what})", fmt_f32(v)),
            ));
        }
        Ok(v)
    }

    /// A number > 0 from a required field.
    pub(super) fn positive(&self, value: &Spanned<f64>, object: &str, field: &str) -> Result<f32> {
        let v = self.number(value, object, field)?;
        if v <= 0.0 {
            return Err(self.invalid(&value.span(), object, format!("`{field}` is {v}; it must be > 0")));
        }
        Ok(v)
    }

    /// A direction: three finite numbers, not all zero, normalised.
    pub(super) fn direction(&self, value: &Spanned<Vec3Def>, object: &str, field: &str) -> Result<Vec3> {
        let v = self.point(value, object, field)?;
        let n = v.normalize_or_zero();
        if n == Vec3::ZERO || !n.is_finite() {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is [0, 0, 0], which has no direction; give e.g. `{field} = [0, 1, 0]`"),
            ));
        }
        Ok(n)
    }
}

/// A number outside +-`MAX_SCENE_VALUE`, as a message.
fn out_of_scene_range(field: &str, v: f64) -> String {
    format!(
        "`{field}` holds {}; every number in a scene (coordinates, lengths, colours, angles) must be within \
         +-{MAX_SCENE_VALUE:e} (see docs/limits.md)",
        fmt_number(v)
    )
}

/// The first coordinate of `points` beyond +-`MAX_SCENE_VALUE` (or not finite), if any.
pub(super) fn beyond_scene_range(points: &[Vec3]) -> Option<f32> {
    points.iter().flat_map(|p| p.to_array()).find(|c| !c.is_finite() || c.abs() as f64 > MAX_SCENE_VALUE)
}

pub(super) fn transformed_out_of_range(coordinate: f32) -> String {
    format!(
        "`transform` moves the shape to coordinate {}, beyond the largest scene coordinate, +-{MAX_SCENE_VALUE:e} \
         (see docs/limits.md); use a smaller `scale` or `translate`",
        fmt_f32(coordinate)
    )
}

pub(super) fn vec3_text(c: Vec3) -> String {
    format!("[{}, {}, {}]", fmt_f32(c.x), fmt_f32(c.y), fmt_f32(c.z))
}
