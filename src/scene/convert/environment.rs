//! `[environment]`: an image map, a gradient, a uniform colour or (in `sky`) the physical sky, as
//! the latitude-longitude image the renderer samples.

use std::path::Path;

use glam::Vec3;
use toml::Spanned;

use super::values::vec3_text;
use super::{span_of, Builder, Result};
use crate::limits::{fmt_f32, MAX_ENVIRONMENT_TEXELS, MAX_SCENE_VALUE};
use crate::scene::format::{EnvironmentDef, RainbowDef};
use crate::scene::image_texture::{load_image_texture, ColorSpace, ImageTexture};
use crate::scene::Environment;

const ENVIRONMENT_TYPES: &[&str] = &["map", "gradient", "uniform", "sky"];

/// Rows of the image a gradient sky is drawn into (its colours vary with elevation only).
const GRADIENT_ROWS: u32 = 512;

impl Builder<'_> {
    pub(super) fn environment(
        &mut self,
        def: &Spanned<EnvironmentDef>,
        rainbow: Option<&Spanned<RainbowDef>>,
    ) -> Result<Environment> {
        let object = "[environment]";
        let table = def.span();
        let e = def.get_ref();
        let kind_def = self.require(&e.r#type, &table, object, "type", "type = \"map\"")?;
        let kind = self.one_of(kind_def, object, "type", ENVIRONMENT_TYPES)?;
        let present = [
            ("type", span_of(&e.r#type)),
            ("file", span_of(&e.file)),
            ("radiance", span_of(&e.radiance)),
            ("colors", span_of(&e.colors)),
            ("elevations", span_of(&e.elevations)),
            ("strength", span_of(&e.strength)),
            ("rotation", span_of(&e.rotation)),
            ("photons", span_of(&e.photons)),
            ("direct", span_of(&e.direct)),
            ("turbidity", span_of(&e.turbidity)),
            ("ground_albedo", span_of(&e.ground_albedo)),
            ("sun", span_of(&e.sun)),
            ("sun_direction", span_of(&e.sun_direction)),
            ("sun_elevation", span_of(&e.sun_elevation)),
            ("sun_azimuth", span_of(&e.sun_azimuth)),
            ("latitude", span_of(&e.latitude)),
            ("longitude", span_of(&e.longitude)),
            ("date", span_of(&e.date)),
            ("time", span_of(&e.time)),
            ("utc_offset", span_of(&e.utc_offset)),
            ("north", span_of(&e.north)),
        ];
        let common = ["type", "strength", "rotation", "photons", "direct"];
        let strength = match &e.strength {
            Some(v) => {
                let k = self.number(v, object, "strength")?;
                if k < 0.0 {
                    return Err(self.invalid(
                        &v.span(),
                        object,
                        format!("`strength` is {}; it scales the radiance and must be >= 0", fmt_f32(k)),
                    ));
                }
                k
            }
            None => 1.0,
        };
        let rotation_deg = match &e.rotation {
            Some(r) => self.number(r, object, "rotation")?,
            None => 0.0,
        };
        let direct = e.direct.as_ref().is_none_or(|d| *d.get_ref());
        let photons = e.photons.as_ref().is_none_or(|p| *p.get_ref());
        if !direct && !photons {
            return Err(self.invalid(
                &span_of(&e.direct).unwrap_or(table.clone()),
                object,
                "`direct = false` and `photons = false` leave the environment only visible to camera rays; keep one true".to_string(),
            ));
        }
        let mut image = match kind {
            "map" => {
                self.only_fields(object, "an environment map", &present, &[&common[..], &["file"]].concat())?;
                let file = self.require(&e.file, &table, object, "file", "file = \"textures/sky.hdr\"")?;
                let base = self.src.path.parent().unwrap_or(Path::new(""));
                let image = load_image_texture(&base.join(file.get_ref()), ColorSpace::Srgb).map_err(|err| {
                    self.invalid(
                        &file.span(),
                        object,
                        format!("`file`: {err}; give a latitude-longitude EXR or Radiance HDR image, its path relative to the scene file"),
                    )
                })?;
                let mut image = image;
                let (w0, h0) = (image.width, image.height);
                while image.width as u64 * image.height as u64 > MAX_ENVIRONMENT_TEXELS
                    && image.width > 1
                    && image.height > 1
                {
                    image = halve(&image);
                }
                if image.width != w0 {
                    let at = self.src.at(&file.span());
                    self.warnings.push(format!(
                        "{at}: {object}: the map is {w0}x{h0}; it is used at {}x{} to fit one storage buffer",
                        image.width, image.height
                    ));
                }
                image
            }
            "gradient" => {
                self.only_fields(
                    object,
                    "a gradient sky",
                    &present,
                    &[&common[..], &["colors", "elevations"]].concat(),
                )?;
                let colors_def =
                    self.require(&e.colors, &table, object, "colors", "colors = [[0.9, 0.9, 1.0], [0.3, 0.5, 1.0]]")?;
                let mut colors = Vec::new();
                for c in colors_def.get_ref() {
                    let v = Vec3::new(c.value[0] as f32, c.value[1] as f32, c.value[2] as f32);
                    if !v.is_finite() || v.min_element() < 0.0 || v.max_element() as f64 > MAX_SCENE_VALUE {
                        return Err(self.invalid(
                            &colors_def.span(),
                            object,
                            format!(
                                "`colors` holds {}; give finite radiances >= 0 (at most {MAX_SCENE_VALUE:e})",
                                vec3_text(v)
                            ),
                        ));
                    }
                    colors.push(v);
                }
                if colors.len() < 2 {
                    return Err(self.invalid(
                        &colors_def.span(),
                        object,
                        "`colors` needs at least 2 colours (horizon to zenith)".to_string(),
                    ));
                }
                let elevations: Vec<f32> = match &e.elevations {
                    Some(el) => {
                        let values: Vec<f32> = el.get_ref().iter().map(|&v| v as f32).collect();
                        let increasing = values.windows(2).all(|w| w[0] < w[1]);
                        if values.len() != colors.len()
                            || !increasing
                            || values.iter().any(|v| !(-90.0..=90.0).contains(v))
                        {
                            return Err(self.invalid(
                                &el.span(),
                                object,
                                format!(
                                    "`elevations` is [{}]; give one elevation per colour ({}), increasing, in [-90, 90] degrees",
                                    values.iter().map(|&v| fmt_f32(v)).collect::<Vec<_>>().join(", "),
                                    colors.len()
                                ),
                            ));
                        }
                        values
                    }
                    None => (0..colors.len()).map(|k| 90.0 * k as f32 / (colors.len() - 1) as f32).collect(),
                };
                gradient_image(&colors, &elevations)
            }
            "sky" => {
                self.only_fields(object, "a sky", &present, &[&common[..], super::sky::SKY_FIELDS].concat())?;
                self.sky(e, &table, object, strength, direct, photons, rainbow)?
            }
            _ => {
                self.only_fields(object, "a uniform environment", &present, &[&common[..], &["radiance"]].concat())?;
                let r = self.require(&e.radiance, &table, object, "radiance", "radiance = 1")?;
                let c = self.color(r, object, "radiance", false)?;
                // Rows, so that directions are drawn in proportion to sin(theta): uniformly.
                ImageTexture {
                    width: 1,
                    height: GRADIENT_ROWS,
                    texels: vec![[c[0], c[1], c[2], 1.0]; GRADIENT_ROWS as usize],
                }
            }
        };
        if kind != "sky" {
            if let Some(r) = rainbow {
                if let Some(addition) = self.rainbow(r, None)? {
                    if (image.width as u64) * (image.height as u64)
                        < (super::sky::SKY_WIDTH * super::sky::SKY_HEIGHT) as u64
                    {
                        image = resample(&image, super::sky::SKY_WIDTH, super::sky::SKY_HEIGHT);
                    }
                    super::sky::add_to_image(&mut image, rotation_deg, &addition);
                }
            }
        }
        // Radiance is in [0, MAX_SCENE_VALUE] like every colour of a scene: a map's NaN and
        // negative texels (EXR allows them) become 0, and a texel too bright is refused.
        let mut cleared = 0usize;
        let mut brightest = 0.0f32;
        for t in &mut image.texels {
            for c in &mut t[..3] {
                if c.is_nan() || *c < 0.0 {
                    cleared += 1;
                    *c = 0.0;
                }
                // (An infinite texel at strength 0 is black, not NaN.)
                *c = if strength == 0.0 { 0.0 } else { *c * strength };
                brightest = brightest.max(*c);
            }
        }
        let at_field = span_of(&e.file).or(span_of(&e.strength)).unwrap_or(table.clone());
        if cleared > 0 {
            let at = self.src.at(&at_field);
            self.warnings.push(format!(
                "{at}: {object}: {cleared} texel channels of the map are negative or NaN; they are taken as 0"
            ));
        }
        if brightest as f64 > MAX_SCENE_VALUE {
            return Err(self.invalid(
                &at_field,
                object,
                format!(
                    "the environment's radiance reaches {} (times `strength`), beyond the largest scene value, \
                     {MAX_SCENE_VALUE:e} (see docs/limits.md); lower `strength`",
                    fmt_f32(brightest)
                ),
            ));
        }
        Ok(Environment { image: std::sync::Arc::new(image), rotation_deg, direct, photons })
    }
}

/// The image at `width` x `height`, each texel the source texel its centre falls in (for a
/// gradient or uniform sky that a rainbow is drawn over).
fn resample(image: &ImageTexture, width: u32, height: u32) -> ImageTexture {
    let mut texels = Vec::with_capacity((width * height) as usize);
    for j in 0..height {
        let sj = (((j as f64 + 0.5) / height as f64 * image.height as f64) as u32).min(image.height - 1);
        for i in 0..width {
            let si = (((i as f64 + 0.5) / width as f64 * image.width as f64) as u32).min(image.width - 1);
            texels.push(image.texels[(sj * image.width + si) as usize]);
        }
    }
    ImageTexture { width, height, texels }
}

/// The image halved in both directions (odd last rows and columns dropped), each texel the mean
/// of the 2x2 it replaces.
fn halve(image: &ImageTexture) -> ImageTexture {
    let (w, h) = (image.width / 2, image.height / 2);
    let mut texels = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let mut sum = [0.0f32; 4];
            for (di, dj) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let t = image.texels[((2 * j + dj) * image.width + 2 * i + di) as usize];
                (0..4).for_each(|c| sum[c] += 0.25 * t[c]);
            }
            texels.push(sum);
        }
    }
    ImageTexture { width: w, height: h, texels }
}

/// A one-column latitude-longitude image of `colors` at `elevations` (degrees), linear in
/// elevation between them and constant beyond the first and the last.
fn gradient_image(colors: &[Vec3], elevations: &[f32]) -> ImageTexture {
    let texels = (0..GRADIENT_ROWS)
        .map(|j| {
            let elevation = 90.0 - 180.0 * (j as f32 + 0.5) / GRADIENT_ROWS as f32;
            let k = elevations.iter().rposition(|&e| e <= elevation).unwrap_or(0);
            let c = if elevation <= elevations[0] {
                colors[0]
            } else if k + 1 >= colors.len() {
                colors[colors.len() - 1]
            } else {
                let t = (elevation - elevations[k]) / (elevations[k + 1] - elevations[k]);
                colors[k].lerp(colors[k + 1], t)
            };
            [c.x, c.y, c.z, 1.0]
        })
        .collect();
    ImageTexture { width: 1, height: GRADIENT_ROWS, texels }
}
