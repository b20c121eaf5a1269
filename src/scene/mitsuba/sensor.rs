//! `<sensor>` (`perspective`, `thinlens`) with its `<film>`, `<rfilter>` and `<sampler>`, and
//! `<integrator>`: the `[camera]` and `[render]` tables.

use glam::{DMat4, DVec3};

use super::out::{num, string, vec3, Fields};
use super::props::Plugin;
use super::xml::Element;
use super::{transform, MitsubaError, Pos, Result, Translator};

/// Mitsuba's film size when the file gives none.
const DEFAULT_SIZE: (i64, i64) = (768, 576);
/// The diagonal of 35 mm film (36 x 24 mm), for `focal_length`.
const FILM_DIAGONAL_MM: f64 = 43.266_615_305_567_87;

impl<'a> Translator<'a> {
    pub(crate) fn sensor(
        &mut self,
        sensor: Option<&'a Element>,
        integrator: Option<&'a Element>,
        scene_pos: Pos,
    ) -> Result<()> {
        let mut camera = Fields::new();
        let mut render = Fields::new();
        let pos = sensor.map_or(scene_pos, |s| s.pos);
        let (mut width, mut height) = DEFAULT_SIZE;
        let mut world_from_camera = DMat4::IDENTITY;
        let mut fov_x = 2.0 * (FILM_DIAGONAL_MM / 100.0).atan().to_degrees();
        let mut fov_axis = "diagonal".to_string();
        let mut lens: Option<(f64, f64)> = None;
        match sensor {
            None => self.warn(scene_pos, "the scene has no <sensor>; Mitsuba's default camera is used (at the origin, looking down +z, a 50 mm lens)".into()),
            Some(s) => {
                let p = Plugin::new(s);
                if !matches!(p.kind.as_str(), "perspective" | "thinlens") {
                    return Err(p.error(s.pos, "Photonix reads the `perspective` and `thinlens` sensors".into()));
                }
                if let Some(t) = p.prop("to_world") {
                    world_from_camera = transform::parse(t)?;
                }
                // Film and sampler
                for f in p.plugins("film", None) {
                    let film = Plugin::new(self.resolve(f, "film")?);
                    width = film.integer("width")?.unwrap_or(DEFAULT_SIZE.0);
                    height = film.integer("height")?.unwrap_or(DEFAULT_SIZE.1);
                    if !(1..=65536).contains(&width) || !(1..=65536).contains(&height) {
                        return Err(film.error(film.pos(), format!("the film is {width}x{height}; give sizes of 1 to 65536")));
                    }
                    for c in ["crop_offset_x", "crop_offset_y", "crop_width", "crop_height"] {
                        if film.prop(c).is_some() {
                            self.warn(film.pos(), format!("`{c}`: Photonix renders the whole film"));
                        }
                    }
                    let filters = film.plugins("rfilter", None);
                    self.filter(filters.first().copied(), &film, &mut render)?;
                    self.finish(&film);
                }
                if p.plugins("film", None).is_empty() {
                    self.filter(None, &p, &mut render)?;
                }
                for s in p.plugins("sampler", None) {
                    let sampler = Plugin::new(self.resolve(s, "sampler")?);
                    if let Some(n) = sampler.integer("sample_count")? {
                        let (spp, passes) = split_samples(n.clamp(1, crate::limits::MAX_SPP as i64));
                        render.push(("spp".into(), spp.to_string()));
                        render.push(("passes".into(), passes.to_string()));
                    }
                    let _ = sampler.integer("seed")?.map(|s| render.push(("seed".into(), (s.rem_euclid(1 << 32)).to_string())));
                    self.finish(&sampler);
                }
                fov_axis = p.string("fov_axis")?.map_or("x".to_string(), |(s, _)| s.to_string());
                let focal = p.string("focal_length")?;
                fov_x = match (p.float("fov")?, focal) {
                    (Some(f), _) => f,
                    (None, Some((mm, at))) => {
                        let f = super::props::parse_number(mm.trim_end_matches("mm"))
                            .filter(|f| *f > 0.0)
                            .ok_or_else(|| p.error(at, format!("`focal_length` = \"{}\": give millimetres, e.g. \"50mm\"", crate::limits::printable(mm))))?;
                        fov_axis = "diagonal".into();
                        2.0 * (FILM_DIAGONAL_MM / (2.0 * f)).atan().to_degrees()
                    }
                    // Mitsuba's default lens: 50 mm on 35 mm film, along the diagonal.
                    (None, None) => {
                        fov_axis = "diagonal".into();
                        2.0 * (FILM_DIAGONAL_MM / 100.0).atan().to_degrees()
                    }
                };
                if !(fov_x > 0.0 && fov_x < 180.0) {
                    return Err(p.error(s.pos, format!("`fov` is {fov_x}; it must be in (0, 180) degrees")));
                }
                if p.kind == "thinlens" {
                    let radius = p.float_or("aperture_radius", 1.0)?;
                    let focus = p.float_or("focus_distance", 0.0)?;
                    lens = Some((radius, focus));
                }
                for m in p.plugins("medium", None) {
                    self.warn(m.pos, "a medium around the sensor is not translated; the camera sits in vacuum".into());
                }
                self.finish(&p);
            }
        }

        // Camera: Mitsuba's looks down its +z with +y up and +x to the image's left, as ours
        // does, so its frame gives position, look_at and up directly.
        let origin = world_from_camera.transform_point3(DVec3::ZERO);
        let dir = world_from_camera.transform_vector3(DVec3::Z).normalize_or_zero();
        let up = world_from_camera.transform_vector3(DVec3::Y).normalize_or_zero();
        if dir == DVec3::ZERO || up == DVec3::ZERO || dir.cross(up).length() < 1e-6 {
            return Err(MitsubaError::at(
                pos,
                "the sensor's `to_world` is degenerate (no view direction or up)".into(),
            ));
        }
        if glam::DMat3::from_mat4(world_from_camera).determinant() < 0.0 {
            self.warn(pos, "the sensor's `to_world` mirrors the image; Photonix renders it unmirrored".into());
        }
        let aspect = width as f64 / height as f64;
        let half = (fov_x.to_radians() / 2.0).tan();
        let tan_y = match fov_axis.as_str() {
            "x" => half / aspect,
            "y" => half,
            "diagonal" => half / (1.0 + aspect * aspect).sqrt(),
            "smaller" if aspect > 1.0 => half,
            "smaller" => half / aspect,
            "larger" if aspect > 1.0 => half / aspect,
            "larger" => half,
            other => {
                return Err(MitsubaError::at(
                    pos,
                    format!(
                        "`fov_axis` = \"{}\": give x, y, diagonal, smaller or larger",
                        crate::limits::printable(other)
                    ),
                ))
            }
        };
        camera.push(("position".into(), vec3(origin.to_array())));
        camera.push(("look_at".into(), vec3((origin + dir).to_array())));
        camera.push(("up".into(), vec3(up.to_array())));
        camera.push(("fov".into(), num(2.0 * tan_y.atan().to_degrees())));
        camera.push(("resolution".into(), format!("[{width}, {height}]")));
        if let Some((radius, focus)) = lens {
            camera.push(("aperture_radius".into(), num(radius)));
            camera.push(("focal_distance".into(), num(focus)));
        }
        self.out.entry("[camera]", &camera, pos);

        // Integrator: its depth; the choice of estimator stays Photonix's (`auto`).
        if let Some(i) = integrator {
            let p = Plugin::new(i);
            if let Some(depth) = p.integer("max_depth")? {
                // Mitsuba counts path segments (1: emitters seen directly); Photonix counts the
                // surfaces a path visits. -1 is unlimited: Photonix's largest.
                let ours = if depth < 0 { crate::limits::MAX_DEPTH as i64 } else { (depth - 1).max(1) };
                render.push(("max_depth".into(), ours.min(crate::limits::MAX_DEPTH as i64).to_string()));
            }
            let _ = p.integer("rr_depth")?;
            render.push(("# Mitsuba's integrator".into(), string(&p.kind)));
            self.finish(&p);
        }
        let mut fields: Fields = Vec::new();
        let mut comment = None;
        for (k, v) in render {
            if k.starts_with('#') {
                comment = Some(v);
            } else {
                fields.push((k, v));
            }
        }
        if !fields.is_empty() || comment.is_some() {
            let header = match comment {
                Some(c) => format!("[render]   # Mitsuba's integrator was {c}; Photonix picks its own (`integrator`)"),
                None => "[render]".into(),
            };
            self.out.entry(&header, &fields, pos);
        }
        Ok(())
    }

    /// The film's reconstruction filter (Mitsuba 3's default: a Gaussian) and its size: a box's
    /// or a tent's `radius`, a Gaussian's `stddev` (its radius is four of them, in Mitsuba as
    /// here).
    fn filter(&mut self, rfilter: Option<&'a Element>, film: &Plugin, render: &mut Fields) -> Result<()> {
        let (kind, pos, radius) = match rfilter {
            Some(f) => {
                let f = self.resolve(f, "rfilter")?;
                let p = Plugin::new(f);
                let kind = p.kind.clone();
                let radius = match kind.as_str() {
                    "box" | "tent" => p.float("radius")?,
                    "gaussian" => p.float("stddev")?.map(|s| 4.0 * s),
                    _ => None,
                };
                self.finish(&p);
                (kind, f.pos, radius)
            }
            None => ("gaussian".to_string(), film.pos(), None),
        };
        let ours = match kind.as_str() {
            "box" | "tent" | "gaussian" => kind.clone(),
            other => {
                self.warn(
                    pos,
                    format!(
                        "the `{}` reconstruction filter is rendered as a Gaussian",
                        crate::limits::printable(other)
                    ),
                );
                "gaussian".into()
            }
        };
        render.push(("filter".into(), string(&ours)));
        if let Some(r) = radius {
            let (lo, hi) = (f64::from(crate::limits::MIN_FILTER_RADIUS), f64::from(crate::limits::MAX_FILTER_RADIUS));
            // Finite: props::parse_number admits no NaN or infinity.
            let kept = r.clamp(lo, hi);
            if kept != r {
                self.warn(
                    pos,
                    format!(
                        "the filter reaches {} pixels; Photonix's reach {lo} to {hi}, so it uses {}",
                        num(r),
                        num(kept)
                    ),
                );
            }
            render.push(("filter_radius".into(), num(kept)));
        }
        Ok(())
    }
}

/// Mitsuba's `sample_count` as progressive passes of a few samples each, the same samples in all:
/// a `--time` budget or a preview then stops after a few samples rather than after the whole
/// count (one pass of 256 samples of a room runs a minute at 160 x 90).
pub(super) fn split_samples(n: i64) -> (i64, i64) {
    let spp = [4, 3, 2].into_iter().find(|d| n % d == 0).unwrap_or(1);
    (spp, n / spp)
}
