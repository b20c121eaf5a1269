//! `<emitter>`: `area` (on a shape: its material's emission), `point`, `spot`, `directional`
//! (`[[lights]]`), `envmap`, `constant` and `sunsky` (`[environment]`).

use glam::{DMat4, DVec3};

use super::out::{num, string, vec3, Fields};
use super::props::Plugin;
use super::textures::Param;
use super::xml::Element;
use super::{transform, Result, Translator, Uv};

impl<'a> Translator<'a> {
    /// The emission (TOML value) of an area emitter on a shape.
    pub(crate) fn area_emitter(&mut self, el: &'a Element) -> Result<String> {
        let p = Plugin::new(el);
        if p.kind != "area" {
            return Err(p.error(el.pos, "a shape carries an `area` emitter; other emitters stand on their own".into()));
        }
        let radiance = self.color(&p, "radiance", Uv::AsIs)?.unwrap_or(Param::Constant([1.0; 3]));
        let scale = p.float_or("scale", 1.0)?;
        let _ = p.float("sampling_weight")?;
        self.finish(&p);
        Ok(match radiance {
            Param::Constant(c) => Param::Constant(c.map(|x| x * scale)).toml(),
            Param::Texture(t) if scale == 1.0 => t,
            Param::Texture(t) => t.replacen('}', &format!(", scale = {} }}", num(scale)), 1),
        })
    }

    pub(crate) fn emitter(&mut self, el: &'a Element) -> Result<()> {
        let p = Plugin::new(el);
        let world_from_light = match p.prop("to_world") {
            Some(t) => transform::parse(t)?,
            None => DMat4::IDENTITY,
        };
        let scale = p.float_or("scale", 1.0)?;
        let _ = p.float("sampling_weight")?;
        let mut fields = Fields::new();
        let constant = |this: &mut Self, name: &str, default: [f64; 3]| -> Result<[f64; 3]> {
            match this.color(&p, name, Uv::AsIs)? {
                None => Ok(default),
                Some(Param::Constant(c)) => Ok(c.map(|x| x * scale)),
                Some(Param::Texture(_)) => Err(p.error(el.pos, format!("`{name}` must be a constant colour here"))),
            }
        };
        match p.kind.as_str() {
            "area" => return Err(p.error(el.pos, "an `area` emitter belongs inside a <shape>".into())),
            "point" => {
                let position = match p.vector("position")? {
                    Some(v) => DVec3::from(v),
                    None => world_from_light.transform_point3(DVec3::ZERO),
                };
                fields.push(("type".into(), string("point")));
                fields.push(("position".into(), vec3(position.to_array())));
                fields.push(("intensity".into(), vec3(constant(self, "intensity", [1.0; 3])?)));
                self.finish(&p);
                self.out.entry("[[lights]]", &fields, el.pos);
            }
            "spot" => {
                let outer = p.float_or("cutoff_angle", 20.0)?;
                let inner = p.float_or("beam_width", outer * 0.75)?;
                fields.push(("type".into(), string("spot")));
                fields.push(("position".into(), vec3(world_from_light.transform_point3(DVec3::ZERO).to_array())));
                fields.push(("direction".into(), vec3(world_from_light.transform_vector3(DVec3::Z).to_array())));
                fields.push(("intensity".into(), vec3(constant(self, "intensity", [1.0; 3])?)));
                fields.push(("inner_angle".into(), num(inner.min(outer))));
                fields.push(("outer_angle".into(), num(outer)));
                self.warn(el.pos, "`spot`: Mitsuba's falloff is linear in angle, Photonix's a smooth step between the same angles".into());
                self.finish(&p);
                self.out.entry("[[lights]]", &fields, el.pos);
            }
            "directional" => {
                let direction = match p.vector("direction")? {
                    Some(v) => DVec3::from(v),
                    None => world_from_light.transform_vector3(DVec3::Z),
                };
                fields.push(("type".into(), string("distant")));
                fields.push(("direction".into(), vec3(direction.to_array())));
                fields.push(("irradiance".into(), vec3(constant(self, "irradiance", [1.0; 3])?)));
                self.finish(&p);
                self.out.entry("[[lights]]", &fields, el.pos);
            }
            "constant" => {
                fields.push(("type".into(), string("uniform")));
                fields.push(("radiance".into(), vec3(constant(self, "radiance", [1.0; 3])?)));
                self.finish(&p);
                self.environment(&fields, el);
            }
            "envmap" => {
                let Some((file, at)) = p.string("filename")? else {
                    return Err(p.error(el.pos, "needs a `filename`".into()));
                };
                fields.push(("type".into(), string("map")));
                fields.push(("file".into(), string(&self.file_name(file, at))));
                if scale != 1.0 {
                    fields.push(("strength".into(), num(scale)));
                }
                // Mitsuba's map has its left edge toward -z and its middle toward +z (u =
                // atan2(x, -z) / 2 pi); Photonix's middle looks toward -z: half a turn apart.
                let z = world_from_light.transform_vector3(DVec3::Z);
                let y = world_from_light.transform_vector3(DVec3::Y).normalize_or_zero();
                if (y - DVec3::Y).length() > 1e-4 {
                    self.warn(el.pos, "the environment map's `to_world` tilts it; only its turn about +y is kept".into());
                }
                let turn = z.x.atan2(z.z).to_degrees() + 180.0;
                let turn = if turn > 180.0 { turn - 360.0 } else { turn };
                if turn.abs() > 1e-9 {
                    fields.push(("rotation".into(), num(turn)));
                }
                let _ = p.string("filter_type")?;
                self.finish(&p);
                self.environment(&fields, el);
            }
            "sunsky" | "sky" | "sun" => self.sunsky(&p, &world_from_light, scale)?,
            other => {
                return Err(p.error(
                    el.pos,
                    format!(
                        "the `{}` emitter is not supported; Photonix reads area, point, spot, directional, envmap, constant and sunsky",
                        crate::limits::printable(other)
                    ),
                ))
            }
        }
        Ok(())
    }

    fn environment(&mut self, fields: &Fields, el: &Element) {
        if self.out.text.lines().any(|l| l == "[environment]") {
            self.warn(el.pos, "the scene has more than one environment emitter; the first is used".into());
            return;
        }
        self.out.entry("[environment]", fields, el.pos);
    }

    /// Mitsuba 3's `sunsky` (Hosek-Wilkie, as Photonix's sky): the sun by `sun_direction` or
    /// by place and time.
    fn sunsky(&mut self, p: &Plugin<'a>, world_from_light: &DMat4, scale: f64) -> Result<()> {
        let mut fields: Fields = vec![("type".into(), string("sky"))];
        if let Some(t) = p.float("turbidity")? {
            fields.push(("turbidity".into(), num(t)));
        }
        if let Some(a) = self.color(p, "albedo", Uv::AsIs)? {
            match a {
                Param::Constant(c) => fields.push(("ground_albedo".into(), vec3(c))),
                Param::Texture(_) => return Err(p.error(p.pos(), "`albedo` must be a constant".into())),
            }
        }
        let sky_scale = p.float_or("sky_scale", 1.0)? * scale;
        let sun_scale = p.float_or("sun_scale", 1.0)? * scale;
        if (sky_scale - sun_scale).abs() > 1e-9 * sky_scale.abs().max(1.0) {
            self.warn(
                p.pos(),
                format!("`sun_scale` ({sun_scale}) differs from `sky_scale` ({sky_scale}); both use `sky_scale`"),
            );
        }
        if sky_scale != 1.0 {
            fields.push(("strength".into(), num(sky_scale)));
        }
        if p.kind == "sky" {
            fields.push(("sun".into(), "false".into()));
        }
        if let Some(d) = p.vector("sun_direction")? {
            let d = world_from_light.transform_vector3(DVec3::from(d));
            fields.push(("sun_direction".into(), vec3(d.to_array())));
        } else {
            let lat = p.float_or("latitude", 35.6894)?;
            let lon = p.float_or("longitude", 139.6917)?;
            let tz = p.float_or("timezone", 9.0)?;
            let year = p.integer("year")?.unwrap_or(2010);
            let month = p.integer("month")?.unwrap_or(7);
            let day = p.integer("day")?.unwrap_or(10);
            let hour = p.float_or("hour", 15.0)?;
            let minute = p.float_or("minute", 0.0)?;
            let second = p.float_or("second", 0.0)?;
            let seconds = ((hour * 3600.0 + minute * 60.0 + second).round() as i64).clamp(0, 86399);
            fields.push(("latitude".into(), num(lat)));
            fields.push(("longitude".into(), num(lon)));
            fields.push(("date".into(), string(&format!("{year:04}-{month:02}-{day:02}"))));
            fields.push((
                "time".into(),
                string(&format!("{:02}:{:02}:{:02}", seconds / 3600, seconds / 60 % 60, seconds % 60)),
            ));
            fields.push(("utc_offset".into(), num(tz)));
        }
        self.finish(p);
        self.environment(&fields, p.el);
        Ok(())
    }
}
