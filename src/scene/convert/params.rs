//! Material parameters that are a value or a texture, checked against the same range either way.

use std::ops::Range;

use glam::Vec3;
use toml::Spanned;

use super::{Builder, Result};
use crate::limits::{fmt_f32, fmt_number, printable, MAX_SCENE_VALUE};
use crate::scene::format::ParamDef;
use crate::scene::material::{Channel, ColorParam, ScalarParam, TextureKind};

/// What a texture parameter's values must be, as the same parameter typed in the scene.
#[derive(Clone, Copy)]
pub(super) enum TexelRole<'w> {
    /// A fraction of light per channel, [0, 1] (reflectance, transmittance).
    Fraction,
    /// Finite and >= 0 (emission, conductor eta and k).
    NonNegative,
    /// A number in [min, max]; `what` says the range as the scene's message does.
    Scalar { min: f32, max: f32, what: &'w str },
}

impl Builder<'_> {
    /// A colour parameter: a colour (checked like `color`), or `{ texture = "name" }`.
    pub(super) fn color_param(
        &mut self,
        value: &Spanned<ParamDef>,
        object: &str,
        field: &str,
        at_most_one: bool,
    ) -> Result<ColorParam> {
        match value.get_ref() {
            ParamDef::Value(v) => {
                let c = self.color(&Spanned::new(value.span(), *v), object, field, at_most_one)?;
                Ok(ColorParam::constant(Vec3::from(c)))
            }
            ParamDef::Texture { name, scale } => {
                let id = self.texture_id(name, &value.span(), object)?;
                let scale = match scale {
                    Some(s) => Vec3::from(self.color(&Spanned::new(value.span(), *s), object, field, at_most_one)?),
                    None => Vec3::ONE,
                };
                let role = if at_most_one { TexelRole::Fraction } else { TexelRole::NonNegative };
                self.check_texels(id, scale, role, &value.span(), object, field)?;
                Ok(ColorParam { value: scale, texture: Some(id) })
            }
        }
    }

    /// A scalar parameter in [min, max]: a number, or `{ texture = "name" }`.
    pub(super) fn scalar_param(
        &mut self,
        value: &Spanned<ParamDef>,
        object: &str,
        field: &str,
        min: f32,
        max: f32,
        what: &str,
    ) -> Result<ScalarParam> {
        let (number, texture) = match value.get_ref() {
            ParamDef::Value(v) if v.scalar => (v.value[0], None),
            ParamDef::Value(_) => {
                return Err(self.invalid(&value.span(), object, format!("`{field}` is one number, not a colour")));
            }
            ParamDef::Texture { name, scale } => {
                let texture = Some(self.texture_id(name, &value.span(), object)?);
                match scale {
                    Some(s) if s.scalar => (s.value[0], texture),
                    Some(_) => {
                        return Err(self.invalid(&value.span(), object, format!("`{field}`'s scale is one number")));
                    }
                    None => (1.0, texture),
                }
            }
        };
        let v = number as f32;
        if !(v >= min && v <= max) {
            let shown = fmt_number(number);
            return Err(self.invalid(&value.span(), object, format!("`{field}` is {shown}; it must be {what}")));
        }
        if let Some(id) = texture {
            self.check_texels(id, Vec3::splat(v), TexelRole::Scalar { min, max, what }, &value.span(), object, field)?;
        }
        Ok(ScalarParam { value: v, texture })
    }

    /// Checks the values an image texture gives parameter `field` (its texels, times `scale`,
    /// per channel) against the range the same parameter typed in the scene must have, with the
    /// same words: an EXR or HDR texel of 3 is a reflectance of 3, which `reflectance = 3` is
    /// refused as. (8- and 16-bit files hold [0, 1] already; NaN texels were made 0 at load.)
    pub(super) fn check_texels(
        &self,
        id: u32,
        scale: Vec3,
        role: TexelRole<'_>,
        span: &Range<usize>,
        object: &str,
        field: &str,
    ) -> Result<()> {
        let TextureKind::Image { image, channel, .. } = &self.textures[id as usize].kind else {
            return Ok(());
        };
        let channels: &[usize] = match channel {
            Channel::Rgb => &[0, 1, 2],
            Channel::R => &[0],
            Channel::G => &[1],
            Channel::B => &[2],
            Channel::Alpha => &[3],
        };
        let name = printable(&self.texture_names[id as usize]);
        for (k, t) in image.texels.iter().enumerate() {
            for &c in channels {
                let v = t[c] * if c < 3 { scale[c] } else { scale.x };
                let problem = match role {
                    _ if v.is_infinite() => Some("give finite numbers".to_string()),
                    TexelRole::Fraction | TexelRole::NonNegative if v < 0.0 => {
                        Some("it must be >= 0 in every channel".to_string())
                    }
                    TexelRole::Fraction if v > 1.0 => {
                        Some("it is a fraction of light, in [0, 1] per channel".to_string())
                    }
                    TexelRole::NonNegative if v as f64 > MAX_SCENE_VALUE => {
                        Some(format!("give values up to the largest scene value, {MAX_SCENE_VALUE:e}"))
                    }
                    TexelRole::Scalar { min, max, what } if !(v >= min && v <= max) => {
                        Some(format!("it must be {what}"))
                    }
                    _ => None,
                };
                if let Some(problem) = problem {
                    let (x, y) = (k % image.width as usize, k / image.width as usize);
                    let shown = if v.is_infinite() { format!("{v}") } else { fmt_f32(v) };
                    let scaled = if scale == Vec3::ONE { "" } else { " (times its `scale`)" };
                    return Err(self.invalid(
                        span,
                        object,
                        format!(
                            "`{field}` is {shown} at texel ({x}, {y}) of texture \"{name}\"{scaled}; {problem} \
                             (clamp the image, or lower `scale`)"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}
