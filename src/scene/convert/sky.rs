//! `[environment] type = "sky"` and `[rainbow]`: the physical sky and sun (scene::sky) and the
//! rainbows drawn into the environment image.

use std::ops::Range;

use glam::{DVec3, Vec3};
use toml::Spanned;

use super::values::vec3_text;
use super::{span_of, Builder, Present, Result};
use crate::limits::{fmt_f32, MAX_SCENE_VALUE};
use crate::scene::format::{EnvironmentDef, RainbowDef, Vec3Def};
use crate::scene::image_texture::ImageTexture;
use crate::scene::sky::rainbow::RainbowTable;
use crate::scene::sky::solar::{parse_date, parse_time, sun_position, DateTime};
use crate::scene::sky::{
    direction_from_angles, latlong_direction, Sky, SkyParams, SUN_ANGULAR_RADIUS, TURBIDITY_RANGE,
};
use crate::scene::{LightDesc, LightKind};

/// The sky's image: 0.35 degrees a texel, fine enough for a rainbow's colours.
pub(super) const SKY_WIDTH: u32 = 1024;
pub(super) const SKY_HEIGHT: u32 = 512;

/// The fields only a sky takes.
pub(super) const SKY_FIELDS: &[&str] = &[
    "turbidity",
    "ground_albedo",
    "sun",
    "sun_direction",
    "sun_elevation",
    "sun_azimuth",
    "latitude",
    "longitude",
    "date",
    "time",
    "utc_offset",
    "north",
];

const RAINBOW_TYPES: &[&str] = &["physical", "pov"];

/// What the environment's radiance gains from a rainbow, per direction.
pub(super) type Addition = Box<dyn Fn(DVec3) -> DVec3 + Sync>;

impl Builder<'_> {
    /// The physical sky's image (scaled later with the rest by `strength`); pushes the sun as a
    /// distant light (irradiance times `strength`) unless `sun = false` or it is below the horizon.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn sky(
        &mut self,
        e: &EnvironmentDef,
        table: &Range<usize>,
        object: &str,
        strength: f32,
        direct: bool,
        photons: bool,
        rainbow: Option<&Spanned<RainbowDef>>,
    ) -> Result<ImageTexture> {
        if let Some(r) = &e.rotation {
            return Err(self.invalid(
                &r.span(),
                object,
                "`rotation` does not apply to a sky: the sun's place sets it; turn the compass with \
                 `north = [x, 0, z]` instead"
                    .to_string(),
            ));
        }
        let turbidity = match &e.turbidity {
            Some(t) => {
                let v = self.number(t, object, "turbidity")? as f64;
                if !(TURBIDITY_RANGE.0..=TURBIDITY_RANGE.1).contains(&v) {
                    return Err(self.invalid(
                        &t.span(),
                        object,
                        format!(
                            "`turbidity` is {}; the sky model covers 1 (pure air) to 10 (haze); a clear day is 2 to 3",
                            fmt_f32(v as f32)
                        ),
                    ));
                }
                v
            }
            None => 3.0,
        };
        let ground_albedo = match &e.ground_albedo {
            Some(a) => Vec3::from(self.color(a, object, "ground_albedo", true)?).as_dvec3(),
            None => DVec3::splat(0.3),
        };
        let sun = self.sun_direction(e, table, object)?;
        let params = SkyParams { turbidity, ground_albedo, sun };
        let sky = Sky::new(params);
        let elevation = params.elevation().to_degrees();
        let at = self.src.at(table);
        if elevation < 0.0 {
            self.warnings.push(format!(
                "{at}: {object}: the sun is {:.1} degrees below the horizon; the sky is drawn as at sunset and there is no sunlight",
                -elevation
            ));
        }
        let add_sun = e.sun.as_ref().is_none_or(|s| *s.get_ref()) && elevation >= 0.0;
        if add_sun {
            let irradiance = (sky.sun_irradiance() * strength as f64).as_vec3();
            if irradiance.max_element() as f64 > MAX_SCENE_VALUE {
                return Err(self.invalid(
                    table,
                    object,
                    format!("the sun's irradiance times `strength` is {}; lower `strength`", vec3_text(irradiance)),
                ));
            }
            let kind = LightKind::Distant {
                direction: (-sun).as_vec3(),
                irradiance,
                half_angle_deg: SUN_ANGULAR_RADIUS.to_degrees() as f32,
                visible: true,
            };
            self.lights.push(LightDesc { kind, direct, photons });
        }
        let addition = match rainbow {
            Some(r) => self.rainbow(r, Some(&sky))?,
            None => None,
        };
        let texels = sky.image(SKY_WIDTH, SKY_HEIGHT, |d| addition.as_ref().map_or(DVec3::ZERO, |f| f(d)));
        Ok(ImageTexture { width: SKY_WIDTH, height: SKY_HEIGHT, texels })
    }

    /// The unit direction toward the sun: `sun_direction`, or `sun_elevation` and `sun_azimuth`,
    /// or a place and a time.
    fn sun_direction(&mut self, e: &EnvironmentDef, table: &Range<usize>, object: &str) -> Result<DVec3> {
        let north = match &e.north {
            Some(n) => {
                let v = self.direction(n, object, "north")?;
                if v.x.abs().max(v.z.abs()) < 1e-3 {
                    return Err(self.invalid(
                        &n.span(),
                        object,
                        format!(
                            "`north` is {}, straight up or down; give a horizontal direction such as [0, 0, -1]",
                            vec3_text(v)
                        ),
                    ));
                }
                v
            }
            None => Vec3::NEG_Z,
        };
        let by_angles = e.sun_elevation.is_some() || e.sun_azimuth.is_some();
        let by_place = e.latitude.is_some() || e.longitude.is_some() || e.date.is_some() || e.time.is_some();
        let given = [e.sun_direction.is_some(), by_angles, by_place].iter().filter(|&&b| b).count();
        if given != 1 {
            let span = span_of(&e.sun_direction).or(span_of(&e.sun_elevation)).or(span_of(&e.latitude));
            let message = if given == 0 {
                "a sky needs the sun's place: `sun_direction = [x, y, z]`, or `sun_elevation` and \
                 `sun_azimuth` (degrees), or `latitude`, `longitude`, `date` and `time`"
            } else {
                "give the sun's place one way only: `sun_direction`, or `sun_elevation` and \
                 `sun_azimuth`, or `latitude`, `longitude`, `date` and `time`"
            };
            return Err(self.invalid(&span.unwrap_or(table.clone()), object, message.to_string()));
        }
        if let Some(d) = &e.sun_direction {
            return Ok(self.direction(d, object, "sun_direction")?.as_dvec3().normalize());
        }
        if by_angles {
            let elevation = self.require(&e.sun_elevation, table, object, "sun_elevation", "sun_elevation = 35")?;
            let azimuth = self.require(&e.sun_azimuth, table, object, "sun_azimuth", "sun_azimuth = 200")?;
            let el = self.within(elevation, object, "sun_elevation", (-90.0, 90.0), "degrees above the horizon")?;
            let az = self.number(azimuth, object, "sun_azimuth")? as f64;
            return Ok(direction_from_angles(el, az, north));
        }
        let latitude = self.require(&e.latitude, table, object, "latitude", "latitude = 48.85")?;
        let longitude = self.require(&e.longitude, table, object, "longitude", "longitude = 2.35")?;
        let date = self.require(&e.date, table, object, "date", "date = \"2026-06-21\"")?;
        let time = self.require(&e.time, table, object, "time", "time = \"14:30\"")?;
        let lat = self.within(latitude, object, "latitude", (-90.0, 90.0), "degrees north (south negative)")?;
        let lon = self.within(longitude, object, "longitude", (-180.0, 180.0), "degrees east (west negative)")?;
        let (year, month, day) =
            parse_date(date.get_ref()).map_err(|m| self.invalid(&date.span(), object, format!("`date`: {m}")))?;
        let (hour, minute, second) =
            parse_time(time.get_ref()).map_err(|m| self.invalid(&time.span(), object, format!("`time`: {m}")))?;
        let utc_offset_hours = match &e.utc_offset {
            Some(o) => self.within(o, object, "utc_offset", (-14.0, 14.0), "hours east of UTC")?,
            None => 0.0,
        };
        let t = DateTime { year, month, day, hour, minute, second, utc_offset_hours };
        let p = sun_position(&t, lat, lon);
        Ok(direction_from_angles(p.elevation, p.azimuth, north))
    }

    /// A number of `field` in `range`, else an error saying what it measures.
    fn within(&self, v: &Spanned<f64>, object: &str, field: &str, range: (f64, f64), what: &str) -> Result<f64> {
        let x = self.number(v, object, field)? as f64;
        if !(range.0..=range.1).contains(&x) {
            return Err(self.invalid(
                &v.span(),
                object,
                format!("`{field}` is {}; give {what}, {} to {}", fmt_f32(x as f32), range.0, range.1),
            ));
        }
        Ok(x)
    }

    /// `[rainbow]` as radiance added per direction. A physical bow needs `sky` (its sun).
    pub(super) fn rainbow(&mut self, def: &Spanned<RainbowDef>, sky: Option<&Sky>) -> Result<Option<Addition>> {
        let object = "[rainbow]";
        let table = def.span();
        let r = def.get_ref();
        let kind = match &r.r#type {
            Some(t) => self.one_of(t, object, "type", RAINBOW_TYPES)?,
            None => "physical",
        };
        let present: [Present<'_>; 9] = [
            ("type", span_of(&r.r#type)),
            ("strength", span_of(&r.strength)),
            ("direction", span_of(&r.direction)),
            ("angle", span_of(&r.angle)),
            ("width", span_of(&r.width)),
            ("colors", span_of(&r.colors)),
            ("up", span_of(&r.up)),
            ("arc_angle", span_of(&r.arc_angle)),
            ("falloff_angle", span_of(&r.falloff_angle)),
        ];
        let strength = match &r.strength {
            Some(s) => {
                let v = self.number(s, object, "strength")?;
                if !(0.0..=1.0).contains(&v) {
                    return Err(self.invalid(
                        &s.span(),
                        object,
                        format!(
                            "`strength` is {}; for a physical bow it is the rain's optical depth along the view, \
                             for a POV-Ray bow a scale on its colours: 0 to 1",
                            fmt_f32(v)
                        ),
                    ));
                }
                v as f64
            }
            None => 0.1,
        };
        if kind == "physical" {
            self.only_fields(object, "a physical rainbow", &present, &["type", "strength"])?;
            let Some(sky) = sky else {
                return Err(self.invalid(
                    &table,
                    object,
                    "a physical rainbow is sunlight in rain and needs a sun: use `[environment] type = \"sky\"`, \
                     or `type = \"pov\"` for POV-Ray's drawn bow"
                        .to_string(),
                ));
            };
            let sun = sky.params().sun;
            if sun.y < 0.0 {
                return Ok(None);
            }
            let table = {
                // The sky's own sun spectrum, so the bow has the sun's colour at that elevation.
                let spectrum = |l: f64| sky.sun_spectral_irradiance(l);
                RainbowTable::new(spectrum, SUN_ANGULAR_RADIUS)
            };
            return Ok(Some(Box::new(
                move |d: DVec3| {
                    if d.y <= 0.0 {
                        DVec3::ZERO
                    } else {
                        strength * table.radiance(d, sun)
                    }
                },
            )));
        }
        self.only_fields(
            object,
            "a POV-Ray rainbow",
            &present,
            &["type", "strength", "direction", "angle", "width", "colors", "up", "arc_angle", "falloff_angle"],
        )?;
        let direction = self.require(&r.direction, &table, object, "direction", "direction = [0, -0.3, 1]")?;
        let direction = self.direction(direction, object, "direction")?.as_dvec3();
        let degrees =
            |this: &Self, v: &Option<Spanned<f64>>, name: &str, default: f64, range: (f64, f64)| -> Result<f64> {
                let Some(v) = v else { return Ok(default) };
                let x = this.number(v, object, name)? as f64;
                if !(range.0..=range.1).contains(&x) {
                    return Err(this.invalid(
                        &v.span(),
                        object,
                        format!("`{name}` is {}; give degrees in [{}, {}]", fmt_f32(x as f32), range.0, range.1),
                    ));
                }
                Ok(x)
            };
        let angle = degrees(self, &r.angle, "angle", 42.5, (0.0, 180.0))?;
        let width = degrees(self, &r.width, "width", 5.0, (0.001, 180.0))?;
        let arc = degrees(self, &r.arc_angle, "arc_angle", 360.0, (0.0, 360.0))?;
        let falloff = degrees(self, &r.falloff_angle, "falloff_angle", arc, (0.0, 360.0))?;
        if falloff > arc {
            return Err(self.invalid(
                &r.falloff_angle.as_ref().map_or(table.clone(), |f| f.span()),
                object,
                format!(
                    "`falloff_angle` ({}) is wider than `arc_angle` ({}); the bow fades out between the two, so falloff <= arc",
                    fmt_f32(falloff as f32),
                    fmt_f32(arc as f32)
                ),
            ));
        }
        let up = match &r.up {
            Some(u) => self.direction(u, object, "up")?.as_dvec3(),
            None => DVec3::Y,
        };
        let side = direction.cross(up);
        if side.length() < 1e-6 {
            return Err(self.invalid(
                &r.up.as_ref().map_or(table.clone(), |u| u.span()),
                object,
                "`up` is parallel to `direction`; the arc is measured around `direction` from `up`".to_string(),
            ));
        }
        let side = side.normalize();
        let up = side.cross(direction).normalize();
        let colors = self.rainbow_colors(r.colors.as_ref(), object)?;
        Ok(Some(Box::new(move |d: DVec3| {
            let from_centre = d.dot(direction).clamp(-1.0, 1.0).acos().to_degrees();
            let x = (from_centre - (angle - 0.5 * width)) / width;
            if !(0.0..=1.0).contains(&x) {
                return DVec3::ZERO;
            }
            // Around the axis, from `up`: full inside falloff/2, fading to nothing at arc/2.
            let around = d.dot(side).atan2(d.dot(up)).to_degrees().abs();
            let fade = if around <= 0.5 * falloff {
                1.0
            } else if around >= 0.5 * arc {
                0.0
            } else {
                (0.5 * arc - around) / (0.5 * (arc - falloff))
            };
            let t = x * (colors.len() - 1) as f64;
            let k = (t.floor() as usize).min(colors.len() - 2);
            strength * fade * colors[k].lerp(colors[k + 1], t - k as f64)
        })))
    }

    /// POV-Ray's colour map across the bow, inside edge first; the default runs violet to red.
    fn rainbow_colors(&self, colors: Option<&Spanned<Vec<Vec3Def>>>, object: &str) -> Result<Vec<DVec3>> {
        let Some(colors) = colors else {
            return Ok([
                [0.5, 0.0, 1.0],
                [0.0, 0.0, 1.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
                [1.0, 0.5, 0.0],
                [1.0, 0.0, 0.0],
            ]
            .into_iter()
            .map(DVec3::from_array)
            .collect());
        };
        let mut out = Vec::new();
        for c in colors.get_ref() {
            let v = DVec3::from_array(c.value);
            if !v.is_finite() || v.min_element() < 0.0 || v.max_element() > MAX_SCENE_VALUE {
                return Err(self.invalid(
                    &colors.span(),
                    object,
                    format!("`colors` holds {}; give finite radiances >= 0", vec3_text(v.as_vec3())),
                ));
            }
            out.push(v);
        }
        if out.len() < 2 {
            return Err(self.invalid(
                &colors.span(),
                object,
                "`colors` needs at least 2 colours (inside edge to outside)".to_string(),
            ));
        }
        Ok(out)
    }
}

/// Adds `addition` to the latitude-longitude `image` (drawn without rotation), texel by texel at
/// 2x2 directions, for a rainbow over an environment that is not a sky.
pub(super) fn add_to_image(image: &mut ImageTexture, rotation_deg: f32, addition: &Addition) {
    let (w, h) = (image.width, image.height);
    let (s, c) = (rotation_deg as f64).to_radians().sin_cos();
    for j in 0..h {
        for i in 0..w {
            let mut sum = DVec3::ZERO;
            for (di, dj) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
                let l = latlong_direction((i as f64 + di) / w as f64, (j as f64 + dj) / h as f64);
                // The image turns about +y by the rotation; the bow stays put in the world.
                let d = DVec3::new(c * l.x + s * l.z, l.y, c * l.z - s * l.x);
                sum += addition(d);
            }
            let t = &mut image.texels[(j * w + i) as usize];
            let add = 0.25 * sum;
            t[0] += add.x as f32;
            t[1] += add.y as f32;
            t[2] += add.z as f32;
        }
    }
}
