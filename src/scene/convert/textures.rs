//! `[textures.NAME]`: constant, image, pattern and voxel textures.

use std::ops::Range;
use std::path::Path;

use glam::{Affine3A, Vec3};
use toml::Spanned;

use super::{span_of, Builder, Result};
use crate::limits::printable;
use crate::scene::error::suggest;
use crate::scene::format::TextureDef;
use crate::scene::image_texture::{load_image_texture, ColorSpace, Wrap};
use crate::scene::material::{Channel, ImageProjection, TextureDesc, TextureKind, TextureSpace};
use crate::scene::pattern::{parse_pattern, ColorMap, PATTERN_FIELDS};
use crate::scene::voxel::load_voxel_grid;

const TEXTURE_TYPES: &[&str] = &["constant", "image", "pattern", "voxels"];
const TEXTURE_SPACES: &[&str] = &["uv", "world"];

impl Builder<'_> {
    pub(super) fn texture_id(&mut self, name: &str, span: &Range<usize>, object: &str) -> Result<u32> {
        if let Some(id) = self.texture_names.iter().position(|n| n == name) {
            self.texture_used[id] = true;
            return Ok(id as u32);
        }
        let hint = match suggest(name, &self.texture_names) {
            Some(best) => format!("did you mean \"{}\"?", printable(&best)),
            None => format!("define it with a [textures.{}] table", printable(name)),
        };
        Err(self.invalid(span, object, format!("unknown texture \"{}\" ({hint})", printable(name))))
    }

    pub(super) fn texture(&mut self, key: &Spanned<String>, def: &Spanned<TextureDef>) -> Result<()> {
        let name = key.get_ref().clone();
        let object = format!("texture \"{}\"", printable(&name));
        let t = def.get_ref();
        let table = def.span();
        let kind_def = self.require(&t.r#type, &table, &object, "type", "type = \"pattern\"")?;
        let kind = self.one_of(kind_def, &object, "type", TEXTURE_TYPES)?;
        let mut present = vec![
            ("type", span_of(&t.r#type)),
            ("space", span_of(&t.space)),
            ("transform", span_of(&t.transform)),
            ("color", span_of(&t.color)),
            ("file", span_of(&t.file)),
            ("color_space", span_of(&t.color_space)),
            ("wrap", span_of(&t.wrap)),
            ("channel", span_of(&t.channel)),
            ("projection", span_of(&t.projection)),
            ("colors", span_of(&t.colors)),
        ];
        let pattern_fields = t.pattern_fields();
        present.extend(pattern_fields.iter().map(|(name, value)| (*name, Some(value.span()))));
        let (kind, default_space) = match kind {
            "constant" => {
                self.only_fields(&object, "a constant texture", &present, &["type", "color"])?;
                let color = self.require(&t.color, &table, &object, "color", "color = [0.8, 0.2, 0.2]")?;
                (TextureKind::Constant(Vec3::from(self.color(color, &object, "color", false)?)), TextureSpace::Uv)
            }
            "voxels" => {
                self.only_fields(&object, "a voxels texture", &present, &["type", "transform", "file"])?;
                let file = self.require(&t.file, &table, &object, "file", "file = \"volumes/smoke.pxvol\"")?;
                let base = self.src.path.parent().unwrap_or(Path::new(""));
                let path = base.join(file.get_ref());
                let grid = load_voxel_grid(&path)
                    .map_err(|e| self.invalid(&file.span(), &object, format!("{}: {e}", path.display())))?;
                (TextureKind::Voxels(std::sync::Arc::new(grid)), TextureSpace::World)
            }
            "image" => {
                let fields = ["type", "space", "transform", "file", "color_space", "wrap", "channel", "projection"];
                self.only_fields(&object, "an image texture", &present, &fields)?;
                (self.image_texture(t, &table, &object)?, TextureSpace::Uv)
            }
            _ => {
                let mut fields = vec!["type", "space", "transform", "colors"];
                fields.extend_from_slice(PATTERN_FIELDS);
                self.only_fields(&object, "a pattern texture", &present, &fields)?;
                (self.pattern_texture(t, &table, &object)?, TextureSpace::World)
            }
        };
        let space = match &t.space {
            Some(space) => match self.one_of(space, &object, "space", TEXTURE_SPACES)? {
                "uv" => TextureSpace::Uv,
                _ => TextureSpace::World,
            },
            None => default_space,
        };
        if let (Some(projection), TextureSpace::Uv) = (&t.projection, space) {
            let message =
                "`projection` places an image in `space = \"world\"`; add that, or drop `projection` to look \
                           the image up at the surface's uv";
            return Err(self.invalid(&projection.span(), &object, message.to_string()));
        }
        let lookup_from_texture = self.transform(t.transform.as_ref(), &object)?.unwrap_or(Affine3A::IDENTITY);
        self.textures.push(TextureDesc { kind, space, lookup_from_texture });
        self.texture_names.push(name);
        self.texture_used.push(false);
        Ok(())
    }

    pub(super) fn image_texture(&mut self, t: &TextureDef, table: &Range<usize>, object: &str) -> Result<TextureKind> {
        let file = self.require(&t.file, table, object, "file", "file = \"textures/wood.png\"")?;
        let color_space = match &t.color_space {
            Some(cs) => match self.one_of(cs, object, "color_space", &["srgb", "linear"])? {
                "srgb" => ColorSpace::Srgb,
                _ => ColorSpace::Linear,
            },
            None => ColorSpace::Srgb,
        };
        let wrap = match &t.wrap {
            Some(w) => match self.one_of(w, object, "wrap", &["repeat", "clamp", "mirror"])? {
                "repeat" => Wrap::Repeat,
                "clamp" => Wrap::Clamp,
                _ => Wrap::Mirror,
            },
            None => Wrap::Repeat,
        };
        let channel = match &t.channel {
            Some(c) => match self.one_of(c, object, "channel", &["rgb", "r", "g", "b", "alpha"])? {
                "rgb" => Channel::Rgb,
                "r" => Channel::R,
                "g" => Channel::G,
                "b" => Channel::B,
                _ => Channel::Alpha,
            },
            None => Channel::Rgb,
        };
        let base = self.src.path.parent().unwrap_or(Path::new(""));
        let mut image = load_image_texture(&base.join(file.get_ref()), color_space)
            .map_err(|e| self.invalid(&file.span(), object, e.to_string()))?;
        // As the environment map does: NaN (EXR and HDR hold them) means nothing, so 0, said once.
        let mut cleared = 0usize;
        for c in image.texels.iter_mut().flatten().filter(|c| c.is_nan()) {
            *c = 0.0;
            cleared += 1;
        }
        if cleared > 0 {
            let at = self.src.at(&file.span());
            self.warnings
                .push(format!("{at}: {object}: {cleared} texel channels of the image are NaN; they are taken as 0"));
        }
        let projection = match &t.projection {
            Some(p) => match self.one_of(p, object, "projection", &["planar", "spherical", "cylindrical"])? {
                "planar" => ImageProjection::Planar,
                "spherical" => ImageProjection::Spherical,
                _ => ImageProjection::Cylindrical,
            },
            None => ImageProjection::Planar,
        };
        Ok(TextureKind::Image { image: std::sync::Arc::new(image), wrap, channel, projection })
    }

    pub(super) fn pattern_texture(&self, t: &TextureDef, table: &Range<usize>, object: &str) -> Result<TextureKind> {
        let fields = t.pattern_fields();
        let mut pattern_table = toml::Table::new();
        for (name, value) in &fields {
            pattern_table.insert(name.to_string(), value.get_ref().clone());
        }
        // The message names the field; point at it when it is one of the table's, else at the table.
        let at = |message: &str| -> Range<usize> {
            fields
                .iter()
                .find(|(name, _)| message.contains(&format!("`{name}`")) || message.contains(&format!("{name} \"")))
                .map(|(_, v)| v.span())
                .unwrap_or(table.clone())
        };
        let (pattern, color_map) = parse_pattern(&toml::Value::Table(pattern_table))
            .map_err(|message| self.invalid(&at(&message), object, message))?;
        let color_map = match (&t.colors, color_map) {
            (Some(colors), None) => {
                let list = colors.get_ref();
                let mut entries = Vec::new();
                for (i, c) in list.iter().enumerate() {
                    let c = self.color(&Spanned::new(colors.span(), *c), object, "colors", false)?;
                    let position = if list.len() > 1 { i as f32 / (list.len() - 1) as f32 } else { 0.0 };
                    entries.push((position, c));
                }
                ColorMap::new(entries).map_err(|message| self.invalid(&colors.span(), object, message))?
            }
            (Some(colors), Some(_)) => {
                return Err(self.invalid(
                    &colors.span(),
                    object,
                    "give either `colors` (evenly spaced) or `color_map`, not both".to_string(),
                ));
            }
            (None, Some(map)) => map,
            (None, None) => pattern.kind.default_color_map(),
        };
        Ok(TextureKind::Pattern { pattern, color_map })
    }
}
