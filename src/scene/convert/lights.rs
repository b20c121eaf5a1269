//! `[[lights]]`: point, spot and distant lights, and area lights made of emissive shapes.

use std::ops::Range;

use glam::Vec3;
use toml::Spanned;

use super::{span_of, Builder, Present, Result};
use crate::layout::constants::ADAPTIVE_MAX_RAYS;
use crate::limits::{fmt_f32, MAX_LIGHT_GRID, MAX_SPOT_TIGHTNESS};
use crate::scene::error::object_name;
use crate::scene::format::{LightDef, Vec3Def};
use crate::scene::kinds::{self, AREA_LIGHT_SHAPES, LIGHTS};
use crate::scene::material::{ColorParam, MaterialDesc, MaterialKind};
use crate::scene::{LightDesc, LightKind};

impl Builder<'_> {
    pub(super) fn light(&mut self, index: usize, def: &Spanned<LightDef>) -> Result<()> {
        let l = def.get_ref();
        let object = object_name("light", index, l.name.as_ref().map(|n| n.get_ref().as_str()));
        let table = def.span();
        let kind_def = self.require(&l.r#type, &table, &object, "type", "type = \"area\"")?;
        let kind = self.one_of(kind_def, &object, "type", &LIGHTS.names())?;
        self.group(&l.group, &object, true)?;
        let present = [
            ("name", span_of(&l.name)),
            ("type", span_of(&l.r#type)),
            ("shape", span_of(&l.shape)),
            ("vertices", span_of(&l.vertices)),
            ("center", span_of(&l.center)),
            ("radius", span_of(&l.radius)),
            ("normal", span_of(&l.normal)),
            ("samples", span_of(&l.samples)),
            ("jitter", span_of(&l.jitter)),
            ("adaptive", span_of(&l.adaptive)),
            ("radiance", span_of(&l.radiance)),
            ("position", span_of(&l.position)),
            ("intensity", span_of(&l.intensity)),
            ("transform", span_of(&l.transform)),
            ("direction", span_of(&l.direction)),
            ("point_at", span_of(&l.point_at)),
            ("inner_angle", span_of(&l.inner_angle)),
            ("outer_angle", span_of(&l.outer_angle)),
            ("falloff", span_of(&l.falloff)),
            ("tightness", span_of(&l.tightness)),
            ("irradiance", span_of(&l.irradiance)),
            ("angular_diameter", span_of(&l.angular_diameter)),
            ("visible", span_of(&l.visible)),
            ("photons", span_of(&l.photons)),
            ("direct", span_of(&l.direct)),
        ];
        let direct = l.direct.as_ref().map_or(kinds::DIRECT.flag(), |d| *d.get_ref());
        let photons = l.photons.as_ref().map_or(kinds::PHOTONS.flag(), |p| *p.get_ref());
        if !direct && !photons {
            let span = span_of(&l.direct).unwrap_or(table.clone());
            return Err(self.invalid(
                &span,
                &object,
                "`direct = false` and `photons = false` leave the light nothing to do; keep one of them true or remove the light"
                    .to_string(),
            ));
        }
        let kind = match kind {
            "point" => {
                self.only_kind_fields(&object, LIGHTS.kind("point"), &present)?;
                let position = self.require(&l.position, &table, &object, "position", "position = [0, 5, 0]")?;
                let position = self.point(position, &object, "position")?;
                let intensity =
                    self.light_color(&l.intensity, &table, &object, "intensity", "intensity = [10, 10, 10]")?;
                LightKind::Point { position, intensity }
            }
            "spot" => self.spot_light(l, &table, &object, &present)?,
            "distant" => {
                self.only_kind_fields(&object, LIGHTS.kind("distant"), &present)?;
                let direction = self.light_direction(&l.direction, &table, &object, "direction = [0, -1, 0]")?;
                let irradiance = self.light_color(&l.irradiance, &table, &object, "irradiance", "irradiance = 3")?;
                let half_angle_deg = match &l.angular_diameter {
                    Some(a) => {
                        let deg = self.number(a, &object, "angular_diameter")?;
                        if !(0.0..=90.0).contains(&deg) {
                            return Err(self.invalid(
                                &a.span(),
                                &object,
                                format!(
                                    "`angular_diameter` is {}; it is the apparent size of the light in degrees, \
                                     in [0, 90] (the sun is about 0.53)",
                                    fmt_f32(deg)
                                ),
                            ));
                        }
                        0.5 * deg
                    }
                    None => 0.5 * kinds::ANGULAR_DIAMETER.number() as f32,
                };
                let visible = l.visible.as_ref().map_or(kinds::VISIBLE.flag(), |v| *v.get_ref());
                LightKind::Distant { direction, irradiance, half_angle_deg, visible }
            }
            _ => return self.area_light(index, l, &table, &object, &present, direct, photons),
        };
        self.lights.push(LightDesc { kind, direct, photons });
        Ok(())
    }

    /// A light's colour field (intensity, irradiance): required, >= 0, with a warning when 0.
    pub(super) fn light_color(
        &mut self,
        field: &Option<Spanned<Vec3Def>>,
        table: &Range<usize>,
        object: &str,
        name: &str,
        example: &str,
    ) -> Result<Vec3> {
        let def = self.require(field, table, object, name, example)?;
        let value = Vec3::from(self.color(def, object, name, false)?);
        if value.max_element() == 0.0 {
            let at = self.src.at(&def.span());
            self.warnings.push(format!("{at}: {object}: `{name}` is 0, so this light emits nothing"));
        }
        Ok(value)
    }

    /// A light's required `direction`: three numbers, not all zero; returned normalised.
    pub(super) fn light_direction(
        &self,
        field: &Option<Spanned<Vec3Def>>,
        table: &Range<usize>,
        object: &str,
        example: &str,
    ) -> Result<Vec3> {
        let def = self.require(field, table, object, "direction", example)?;
        let d = self.point(def, object, "direction")?;
        if d.length() == 0.0 {
            return Err(self.invalid(
                &def.span(),
                object,
                "`direction` is zero; give the direction the light shines in".to_string(),
            ));
        }
        Ok(d.normalize())
    }

    /// A spot light: `position`, `direction` or `point_at`, `intensity`, and either
    /// `outer_angle` (with `inner_angle`) or POV-Ray's `radius` and `falloff`; `tightness` with either.
    pub(super) fn spot_light(
        &mut self,
        l: &LightDef,
        table: &Range<usize>,
        object: &str,
        present: &[Present<'_>],
    ) -> Result<LightKind> {
        self.only_kind_fields(object, LIGHTS.kind("spot"), present)?;
        let position = self.require(&l.position, table, object, "position", "position = [0, 5, 0]")?;
        let position = self.point(position, object, "position")?;
        let direction = match (&l.direction, &l.point_at) {
            (Some(_), Some(p)) => {
                return Err(self.invalid(&p.span(), object, "give `direction` or `point_at`, not both".to_string()));
            }
            (None, Some(p)) => {
                let target = self.point(p, object, "point_at")?;
                if target == position {
                    return Err(self.invalid(
                        &p.span(),
                        object,
                        "`point_at` equals `position`; give the point the spot light aims at".to_string(),
                    ));
                }
                (target - position).normalize()
            }
            _ => {
                self.light_direction(&l.direction, table, object, "direction = [0, -1, 0]` or `point_at = [0, 0, 0]")?
            }
        };
        let intensity = self.light_color(&l.intensity, table, object, "intensity", "intensity = [50, 50, 50]")?;
        // Half-angles in degrees, at most 90; an outer angle must also be above 0.
        let angle = |value: &Spanned<f64>, field: &str, outer: bool, what: &str| -> Result<f32> {
            let deg = self.number(value, object, field)?;
            if !(0.0..=90.0).contains(&deg) || (outer && deg == 0.0) {
                return Err(self.invalid(&value.span(), object, format!("`{field}` is {}; {what}", fmt_f32(deg))));
            }
            Ok(deg)
        };
        let pov = l.radius.is_some() || l.falloff.is_some();
        let (inner, outer, inner_name, outer_name, outer_span) = if pov {
            if let Some(span) = span_of(&l.outer_angle).or(span_of(&l.inner_angle)) {
                return Err(self.invalid(
                    &span,
                    object,
                    "give `inner_angle`/`outer_angle` or POV-Ray's `radius`/`falloff`, not both".to_string(),
                ));
            }
            let inner = match &l.radius {
                Some(r) => angle(r, "radius", false, "POV-Ray's hotspot half-angle in degrees, in [0, 90]")?,
                None => kinds::SPOT_RADIUS.number() as f32,
            };
            let outer = match &l.falloff {
                Some(f) => angle(f, "falloff", true, "POV-Ray's falloff half-angle in degrees, in (0, 90]")?,
                None => kinds::SPOT_FALLOFF.number() as f32,
            };
            (inner, outer, "radius", "falloff", span_of(&l.falloff).or(span_of(&l.radius)))
        } else {
            let outer_def = self.require(
                &l.outer_angle,
                table,
                object,
                "outer_angle",
                "outer_angle = 30  # degrees from the axis",
            )?;
            let outer = angle(outer_def, "outer_angle", true, "the cone's half-angle in degrees, in (0, 90]")?;
            let inner = match &l.inner_angle {
                Some(i) => angle(i, "inner_angle", false, "the half-angle of full intensity in degrees, in [0, 90]")?,
                None => kinds::INNER_FRACTION * outer,
            };
            (inner, outer, "inner_angle", "outer_angle", Some(outer_def.span()))
        };
        if outer < inner {
            return Err(self.invalid(
                &outer_span.unwrap_or(table.clone()),
                object,
                format!(
                    "`{outer_name}` ({}) is below `{inner_name}` ({}); the light falls off from \
                     `{inner_name}` out to `{outer_name}`, so raise `{outer_name}` to at least {} or lower `{inner_name}`",
                    fmt_f32(outer),
                    fmt_f32(inner),
                    fmt_f32(inner)
                ),
            ));
        }
        let exponent = match &l.tightness {
            Some(t) => {
                let e = self.number(t, object, "tightness")?;
                if !(0.0..=MAX_SPOT_TIGHTNESS as f32).contains(&e) {
                    return Err(self.invalid(
                        &t.span(),
                        object,
                        format!(
                            "`tightness` is {}; it is the exponent of cos in [0, {MAX_SPOT_TIGHTNESS}] (0 for none)",
                            fmt_f32(e)
                        ),
                    ));
                }
                e
            }
            None => kinds::TIGHTNESS.number() as f32,
        };
        Ok(LightKind::Spot {
            position,
            direction,
            intensity,
            cos_inner: inner.to_radians().cos(),
            cos_outer: outer.to_radians().cos(),
            exponent,
        })
    }

    #[allow(clippy::too_many_arguments)] // the light's fields and options, already read
    pub(super) fn area_light(
        &mut self,
        index: usize,
        l: &LightDef,
        table: &Range<usize>,
        object: &str,
        present: &[Present<'_>],
        direct: bool,
        photons: bool,
    ) -> Result<()> {
        let shape_def = self.require(&l.shape, table, object, "shape", "shape = \"quad\"")?;
        let shape = self.one_of(shape_def, object, "shape", &AREA_LIGHT_SHAPES.names())?;
        self.only_kind_fields(object, AREA_LIGHT_SHAPES.kind(shape), present)?;
        let radiance_def = self.require(&l.radiance, table, object, "radiance", "radiance = [10, 10, 10]")?;
        let radiance = self.color(radiance_def, object, "radiance", false)?;
        if radiance.iter().all(|&c| c == 0.0) {
            let at = self.src.at(&radiance_def.span());
            self.warnings.push(format!("{at}: {object}: `radiance` is 0, so this light emits nothing"));
        }

        // Each area light gets its own black, emitting material named after the light's index.
        let material_name = format!("light {index}");
        if self.material_names.contains(&material_name) {
            return Err(self.invalid(
                table,
                object,
                format!("the material name \"{material_name}\" is reserved for this area light; rename that material"),
            ));
        }
        let mut light_material =
            MaterialDesc::new(MaterialKind::Diffuse { reflectance: ColorParam::constant(Vec3::ZERO) });
        light_material.emission = ColorParam::constant(Vec3::from(radiance));
        let material = self.add_material(material_name, light_material);
        self.material_used[material as usize] = true;
        let grid = match &l.samples {
            Some(s) => {
                let v = s.get_ref();
                if v.len() != 2 || v.iter().any(|&k| !(1..=MAX_LIGHT_GRID as i64).contains(&k)) {
                    return Err(self.invalid(
                        &s.span(),
                        object,
                        format!(
                            "`samples` is {v:?}; give POV-Ray's grid as [n, m], each 1 to {MAX_LIGHT_GRID} (e.g. `samples = [4, 4]`)"
                        ),
                    ));
                }
                [v[0] as u32, v[1] as u32]
            }
            None => [1, 1],
        };
        let jitter = l.jitter.as_ref().map_or(kinds::JITTER.flag(), |j| *j.get_ref());
        let adaptive = match &l.adaptive {
            Some(a) => {
                let level = *a.get_ref();
                let cells = grid[0] * grid[1];
                if level < 0 {
                    return Err(self.invalid(
                        &a.span(),
                        object,
                        format!("`adaptive` is {level}; it is POV-Ray's level, 0 (off) or more (on)"),
                    ));
                }
                if level > 0 && !(2..=ADAPTIVE_MAX_RAYS).contains(&cells) {
                    return Err(self.invalid(
                        &a.span(),
                        object,
                        format!(
                            "`adaptive` needs a grid of 2 to {ADAPTIVE_MAX_RAYS} cells, the shadow rays of a sample in \
                             a penumbra, and `samples` gives {cells}; e.g. `samples = [4, 4]`"
                        ),
                    ));
                }
                level > 0
            }
            None => false,
        };
        self.lights.push(LightDesc { kind: LightKind::Area { material, grid, jitter, adaptive }, direct, photons });
        let transform = self.transform(l.transform.as_ref(), object)?;
        match shape {
            "quad" => {
                let vertices = self.vertices(&l.vertices, table, object, 4)?;
                self.polygon(&vertices, span_of(&l.vertices).unwrap_or(table.clone()), object, material, transform)
            }
            "disc" => {
                // The seed's circular light: a one-sided disc facing `normal` (an ellipse under a
                // non-uniform `transform` scale), sampled over its area like a disc shape.
                let piece = self.disc(&l.center, &l.normal, &l.radius, &None, table, object)?;
                let span = l.transform.as_ref().map_or(table.clone(), |t| t.span());
                self.push_analytic(vec![piece], transform, &span, object, material)
            }
            _ => {
                let center = self.require(&l.center, table, object, "center", "center = [0, 5, 0]")?;
                let radius = self.require(&l.radius, table, object, "radius", "radius = 0.5")?;
                self.sphere(center, radius, object, material, transform)
            }
        }
    }
}
