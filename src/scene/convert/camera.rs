//! `[camera]`: the projection, its resolution and field of view, and the thin lens (including
//! POV-Ray's focal blur).

use glam::Vec3;
use toml::Spanned;

use super::values::vec3_text;
use super::{span_of, Builder, Result};
use crate::limits::{
    fmt_f32, fmt_number, MAX_APERTURE_BLADES, MAX_IMAGE_SIDE, MAX_PIXELS, MAX_SCENE_VALUE, MAX_SPP, MIN_FOV_DEGREES,
};
use crate::scene::{Camera, Projection, ThinLens};

/// Defaults of the format; `docs/scene-format.md` lists the same numbers.
const DEFAULT_UP: Vec3 = Vec3::Y;
const DEFAULT_RESOLUTION: [u32; 2] = [512, 512];

/// Unused by orthographic and latlong cameras; kept so `Camera::fov_deg` is always valid.
const DEFAULT_FOV: f32 = 40.0;
const CAMERA_TYPES: &[&str] = &["perspective", "orthographic", "latlong"];

impl Builder<'_> {
    /// The camera, and POV-Ray's `blur_samples` when given (it raises the samples per pixel).
    pub(super) fn camera(&mut self, def: &Spanned<crate::scene::format::CameraDef>) -> Result<(Camera, Option<u32>)> {
        let object = "[camera]";
        let table = def.span();
        let c = def.get_ref();
        let kind = match &c.r#type {
            Some(t) => self.one_of(t, object, "type", CAMERA_TYPES)?,
            None => "perspective",
        };
        let present = [
            ("type", span_of(&c.r#type)),
            ("position", span_of(&c.position)),
            ("look_at", span_of(&c.look_at)),
            ("up", span_of(&c.up)),
            ("fov", span_of(&c.fov)),
            ("resolution", span_of(&c.resolution)),
            ("view_height", span_of(&c.view_height)),
            ("aperture_radius", span_of(&c.aperture_radius)),
            ("f_number", span_of(&c.f_number)),
            ("focal_length", span_of(&c.focal_length)),
            ("focal_distance", span_of(&c.focal_distance)),
            ("focal_point", span_of(&c.focal_point)),
            ("aperture_blades", span_of(&c.aperture_blades)),
            ("aperture_rotation", span_of(&c.aperture_rotation)),
            ("aperture", span_of(&c.aperture)),
            ("blur_samples", span_of(&c.blur_samples)),
        ];
        let common = ["type", "position", "look_at", "up", "resolution"];
        let lens_fields = [
            "aperture_radius",
            "f_number",
            "focal_length",
            "focal_distance",
            "focal_point",
            "aperture_blades",
            "aperture_rotation",
            "aperture",
            "blur_samples",
        ];
        match kind {
            "perspective" => self.only_fields(
                object,
                "a perspective camera",
                &present,
                &[&common[..], &["fov"], &lens_fields[..]].concat(),
            )?,
            "orthographic" => self.only_fields(
                object,
                "an orthographic camera",
                &present,
                &[&common[..], &["view_height"], &lens_fields[..]].concat(),
            )?,
            _ => self.only_fields(object, "a latlong camera (it has no lens)", &present, &common)?,
        }
        let position_def = self.require(&c.position, &table, object, "position", "position = [0, 1, 5]")?;
        let position = self.point(position_def, object, "position")?;
        let look_at_def = self.require(&c.look_at, &table, object, "look_at", "look_at = [0, 1, 0]")?;
        let look_at = self.point(look_at_def, object, "look_at")?;
        // The same test as `Camera::basis`, which the renderer uses: nearly equal points (closer
        // than 32-bit floats can tell apart) are as bad as equal ones.
        if (look_at - position).try_normalize().is_none() {
            // Apart but too close for their distance from the origin: say that, not "equal".
            let message = if look_at_def.get_ref().value == position_def.get_ref().value {
                "`look_at` equals `position`; the camera needs a direction to look in".to_string()
            } else {
                format!(
                    "`look_at` is too close to `position` for 32-bit floats to give a direction (the camera is {} \
                     units from the origin): move `look_at` farther away along the view",
                    crate::limits::fmt_f32(position.abs().max_element())
                )
            };
            return Err(self.invalid(&look_at_def.span(), object, message));
        }
        let forward = (look_at - position).normalize();
        let up = match &c.up {
            Some(up_def) => self.point(up_def, object, "up")?,
            None => DEFAULT_UP,
        };
        let probe = Camera {
            position,
            look_at,
            up,
            fov_deg: 45.0,
            projection: Projection::Perspective,
            lens: None,
            width: 1,
            height: 1,
        };
        if probe.basis().is_none() {
            let (span, message) = match &c.up {
                Some(up_def) => (
                    up_def.span(),
                    "`up` is zero or parallel to the view direction; give a direction roughly perpendicular to it",
                ),
                // Looking straight up or down with no `up` given.
                None => (
                    look_at_def.span(),
                    "the view direction is vertical, parallel to the default `up` = [0, 1, 0]; add an `up` roughly \
                     perpendicular to it, e.g. `up = [0, 0, -1]`",
                ),
            };
            return Err(self.invalid(&span, object, message.to_string()));
        }
        let mut fov_deg = DEFAULT_FOV;
        let projection = match kind {
            "perspective" => {
                let fov_def = self.require(&c.fov, &table, object, "fov", "fov = 40")?;
                fov_deg = self.number(fov_def, object, "fov")?;
                let fov_range = MIN_FOV_DEGREES as f32..=(180.0 - MIN_FOV_DEGREES) as f32;
                if !fov_range.contains(&fov_deg) {
                    return Err(self.invalid(
                        &fov_def.span(),
                        object,
                        format!(
                            "`fov` is {}; the vertical field of view must be between 0 and 180 degrees (from {} to {})",
                            fmt_f32(fov_deg),
                            fov_range.start(),
                            fov_range.end()
                        ),
                    ));
                }
                Projection::Perspective
            }
            "orthographic" => {
                let h = self.require(&c.view_height, &table, object, "view_height", "view_height = 4")?;
                let view_height =
                    self.positive_measure(h, object, "view_height", "the height of the view in scene units")?;
                Projection::Orthographic { view_height }
            }
            _ => Projection::LatLong,
        };
        let lens = self.lens(c, forward, position, object)?;
        let blur_samples = match &c.blur_samples {
            Some(b) => Some(self.integer(b, object, "blur_samples", 1, MAX_SPP, " lens samples per pixel", "")?),
            None => None,
        };
        let [width, height] = match &c.resolution {
            Some(res) => {
                let values = res.get_ref();
                if values.len() != 2 {
                    return Err(self.invalid(
                        &res.span(),
                        object,
                        format!("`resolution` has {} numbers; give [width, height]", values.len()),
                    ));
                }
                let mut wh = [0; 2];
                for (out, &v) in wh.iter_mut().zip(values) {
                    if v < 1 || v > MAX_IMAGE_SIDE as i64 {
                        return Err(self.invalid(
                            &res.span(),
                            object,
                            format!(
                                "`resolution` is {values:?}; width and height must be at least 1 and at most \
                                 {MAX_IMAGE_SIDE}"
                            ),
                        ));
                    }
                    *out = v as u32;
                }
                if wh[0] as u64 * wh[1] as u64 > MAX_PIXELS {
                    return Err(self.invalid(
                        &res.span(),
                        object,
                        format!("`resolution` is {values:?}; an image has at most {MAX_PIXELS} pixels (16384x16384)"),
                    ));
                }
                wh
            }
            None => DEFAULT_RESOLUTION,
        };
        Ok((Camera { position, look_at, up, fov_deg, projection, lens, width, height }, blur_samples))
    }

    /// The thin lens of a camera, or `None` for a pinhole: an aperture (`aperture_radius`,
    /// `f_number` with `focal_length`, or POV-Ray's `aperture`) and a plane in focus
    /// (`focal_distance` or `focal_point`).
    pub(super) fn lens(
        &mut self,
        c: &crate::scene::format::CameraDef,
        forward: Vec3,
        position: Vec3,
        object: &str,
    ) -> Result<Option<ThinLens>> {
        let apertures = [("aperture_radius", &c.aperture_radius), ("f_number", &c.f_number), ("aperture", &c.aperture)];
        let given: Vec<_> = apertures.iter().filter_map(|(n, f)| f.as_ref().map(|v| (*n, v))).collect();
        if given.len() > 1 {
            return Err(self.invalid(
                &given[1].1.span(),
                object,
                format!(
                    "give one of `aperture_radius`, `f_number` and `aperture`, not both `{}` and `{}`",
                    given[0].0, given[1].0
                ),
            ));
        }
        let Some(&(name, value)) = given.first() else {
            if let Some(span) = span_of(&c.focal_length) {
                return Err(self.invalid(
                    &span,
                    object,
                    "`focal_length` only sets the aperture with `f_number`; add `f_number = 2.8` or remove it"
                        .to_string(),
                ));
            }
            for (field, span) in [
                ("focal_distance", span_of(&c.focal_distance)),
                ("focal_point", span_of(&c.focal_point)),
                ("aperture_blades", span_of(&c.aperture_blades)),
                ("aperture_rotation", span_of(&c.aperture_rotation)),
                ("blur_samples", span_of(&c.blur_samples)),
            ] {
                if let Some(span) = span {
                    let at = self.src.at(&span);
                    self.warnings.push(format!(
                        "{at}: {object}: `{field}` has no effect without an aperture (add `aperture_radius`)"
                    ));
                }
            }
            return Ok(None);
        };
        let radius = match name {
            "aperture_radius" => self.positive_measure(value, object, name, "the radius of the lens in scene units")?,
            "f_number" => {
                let n = self.positive_measure(value, object, name, "the focal length over the aperture's diameter")?;
                let Some(fl) = &c.focal_length else {
                    return Err(self.invalid(
                        &value.span(),
                        object,
                        "`f_number` needs the lens's `focal_length` in scene units to size the aperture, e.g. \
                         `focal_length = 0.05` (a 50 mm lens in a scene in metres), or give `aperture_radius`"
                            .to_string(),
                    ));
                };
                let focal_length = self.positive_measure(fl, object, "focal_length", "scene units")?;
                let radius = focal_length as f64 / (2.0 * n as f64);
                if radius > MAX_SCENE_VALUE {
                    return Err(self.invalid(
                        &value.span(),
                        object,
                        format!(
                            "`f_number` {} with `focal_length` {} gives an aperture of radius {}, beyond the scene \
                             range, +-{MAX_SCENE_VALUE:e} (see docs/limits.md)",
                            fmt_f32(n),
                            fmt_f32(focal_length),
                            fmt_number(radius)
                        ),
                    ));
                }
                radius as f32
            }
            // POV-Ray offsets the eye by aperture/2 times lens samples within +-0.5
            // (tracepixel.cpp, JitterCameraRay): a disc of radius aperture/4.
            _ => 0.25 * self.positive_measure(value, object, name, "POV-Ray's aperture, four times the lens radius")?,
        };
        if name != "f_number" {
            if let Some(span) = span_of(&c.focal_length) {
                return Err(self.invalid(
                    &span,
                    object,
                    format!(
                        "`focal_length` only sets the aperture with `f_number`; remove it (the aperture is `{name}`)"
                    ),
                ));
            }
        }
        let focal_distance = match (&c.focal_distance, &c.focal_point) {
            (Some(_), Some(p)) => {
                return Err(self.invalid(
                    &p.span(),
                    object,
                    "give `focal_distance` or `focal_point`, not both".to_string(),
                ));
            }
            (Some(d), None) => {
                self.positive_measure(d, object, "focal_distance", "scene units along the view direction")?
            }
            (None, Some(p)) => {
                let point = self.point(p, object, "focal_point")?;
                let depth = (point - position).dot(forward);
                if depth <= 0.0 {
                    return Err(self.invalid(
                        &p.span(),
                        object,
                        format!(
                            "`focal_point` {} is not in front of the camera; give a point it looks at",
                            vec3_text(point)
                        ),
                    ));
                }
                depth
            }
            (None, None) => {
                return Err(self.invalid(
                    &value.span(),
                    object,
                    format!(
                        "`{name}` needs a plane in focus; add `focal_distance = 5` (scene units along the view) \
                         or `focal_point = [x, y, z]`"
                    ),
                ));
            }
        };
        let blades = match &c.aperture_blades {
            Some(b) => {
                let n =
                    self.integer(b, object, "aperture_blades", 0, MAX_APERTURE_BLADES, "", "; 0 is a round aperture")?;
                if n != 0 && !(3..=MAX_APERTURE_BLADES).contains(&n) {
                    return Err(self.invalid(
                        &b.span(),
                        object,
                        format!(
                            "`aperture_blades` is {n}; it must be 0 (a round aperture) or 3 to {MAX_APERTURE_BLADES}"
                        ),
                    ));
                }
                n
            }
            None => 0,
        };
        let rotation_deg = match &c.aperture_rotation {
            Some(r) => self.number(r, object, "aperture_rotation")?,
            None => 0.0,
        };
        Ok(Some(ThinLens { radius, focal_distance, blades, rotation_deg }))
    }
}
