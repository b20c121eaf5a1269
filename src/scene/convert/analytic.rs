//! The analytic shapes (plane, disc, cylinder, cone, torus, superellipsoid): their fields, and
//! the placement that takes each from its object space into the scene.

use std::ops::Range;

use glam::{Affine3A, Vec3};
use toml::Spanned;

use super::{Builder, Result};
use crate::scene::format::{ShapeDef, Vec3Def};
use crate::scene::kinds;
use crate::scene::{Analytic, AnalyticKind};

/// Smallest superellipsoid exponent: below it the shape is a box to float precision and its
/// gauge's powers (2/e) pass 200.
const SUPERELLIPSOID_MIN_EXPONENT: f64 = 0.01;

impl Builder<'_> {
    /// A disc (a disc shape, or a disc area light without `inner_radius`) and its placement.
    pub(super) fn disc(
        &self,
        center: &Option<Spanned<Vec3Def>>,
        normal: &Option<Spanned<Vec3Def>>,
        radius: &Option<Spanned<f64>>,
        inner_radius: &Option<Spanned<f64>>,
        table: &Range<usize>,
        object: &str,
    ) -> Result<(AnalyticKind, Affine3A)> {
        let center = self.require(center, table, object, "center", "center = [0, 0, 0]")?;
        let center = self.point(center, object, "center")?;
        let normal = self.require(normal, table, object, "normal", "normal = [0, 1, 0]")?;
        let normal = self.direction(normal, object, "normal")?;
        let radius_def = self.require(radius, table, object, "radius", "radius = 1.0")?;
        let radius = self.positive(radius_def, object, "radius")?;
        let inner_radius = match inner_radius {
            Some(r) => {
                let v = self.number(r, object, "inner_radius")?;
                if v < 0.0 || v >= radius {
                    return Err(self.invalid(
                        &r.span(),
                        object,
                        format!("`inner_radius` is {v}; it must be in [0, radius) = [0, {radius})"),
                    ));
                }
                v
            }
            None => kinds::INNER_RADIUS.number() as f32,
        };
        Ok((AnalyticKind::Disc { radius, inner_radius }, frame(center, normal)))
    }

    /// The object-space pieces of an analytic shape, each with its `world_from_object` before
    /// the shape's own `transform`: a closed cylinder or cone is its side and two discs.
    pub(super) fn analytic(
        &self,
        kind: &str,
        s: &ShapeDef,
        table: &Range<usize>,
        object: &str,
    ) -> Result<Vec<(AnalyticKind, Affine3A)>> {
        let optional_point = |field: &Option<Spanned<Vec3Def>>, name: &str| -> Result<Vec3> {
            field.as_ref().map_or(Ok(Vec3::ZERO), |v| self.point(v, object, name))
        };
        match kind {
            "plane" => {
                let normal = self.require(&s.normal, table, object, "normal", "normal = [0, 1, 0]")?;
                let normal = self.direction(normal, object, "normal")?;
                let offset = s
                    .offset
                    .as_ref()
                    .map_or(Ok(kinds::PLANE_OFFSET.number() as f32), |o| self.number(o, object, "offset"))?;
                Ok(vec![(AnalyticKind::Plane, frame(normal * offset, normal))])
            }
            "disc" => Ok(vec![self.disc(&s.center, &s.normal, &s.radius, &s.inner_radius, table, object)?]),
            "cylinder" | "cone" => {
                let base_def = self.require(&s.base, table, object, "base", "base = [0, 0, 0]")?;
                let base = self.point(base_def, object, "base")?;
                let cap_def = self.require(&s.cap, table, object, "cap", "cap = [0, 1, 0]")?;
                let cap = self.point(cap_def, object, "cap")?;
                let height = base.distance(cap);
                if height <= 0.0 || !height.is_finite() {
                    return Err(self.invalid(
                        &cap_def.span(),
                        object,
                        format!("`cap` ({cap}) is the same point as `base`; a {kind} needs a height"),
                    ));
                }
                let (r0, r1) = if kind == "cylinder" {
                    let r = self.require(&s.radius, table, object, "radius", "radius = 0.5")?;
                    let r = self.positive(r, object, "radius")?;
                    (r, r)
                } else {
                    let r0_def = self.require(&s.base_radius, table, object, "base_radius", "base_radius = 0.5")?;
                    let r1_def = self.require(&s.cap_radius, table, object, "cap_radius", "cap_radius = 0")?;
                    let r0 = self.number(r0_def, object, "base_radius")?;
                    let r1 = self.number(r1_def, object, "cap_radius")?;
                    for (r, def, name) in [(r0, r0_def, "base_radius"), (r1, r1_def, "cap_radius")] {
                        if r < 0.0 {
                            return Err(self.invalid(&def.span(), object, format!("`{name}` is {r}; it must be >= 0")));
                        }
                    }
                    if r0 == 0.0 && r1 == 0.0 {
                        return Err(self.invalid(
                            &r1_def.span(),
                            object,
                            "`base_radius` and `cap_radius` are both 0, which leaves a line; give one of them a radius"
                                .to_string(),
                        ));
                    }
                    (r0, r1)
                };
                let placement = frame(base, (cap - base) / height);
                let mut pieces = vec![(AnalyticKind::Cone { r0, r1, height }, placement)];
                if !s.open.as_ref().map_or(kinds::OPEN.flag(), |o| *o.get_ref()) {
                    // Caps face outward: the base's disc turned upside down (a half turn about x).
                    let down = placement * Affine3A::from_rotation_x(std::f32::consts::PI);
                    let up = placement * Affine3A::from_translation(Vec3::new(0.0, height, 0.0));
                    for (radius, placement) in [(r0, down), (r1, up)] {
                        if radius > 0.0 {
                            pieces.push((AnalyticKind::Disc { radius, inner_radius: 0.0 }, placement));
                        }
                    }
                }
                Ok(pieces)
            }
            "torus" => {
                let center = optional_point(&s.center, "center")?;
                let axis = s
                    .axis
                    .as_ref()
                    .map_or(Ok(Vec3::from(kinds::AXIS.triple())), |a| self.direction(a, object, "axis"))?;
                let major_def = self.require(&s.major_radius, table, object, "major_radius", "major_radius = 1.0")?;
                let minor_def = self.require(&s.minor_radius, table, object, "minor_radius", "minor_radius = 0.25")?;
                let major = self.positive(major_def, object, "major_radius")?;
                let minor = self.positive(minor_def, object, "minor_radius")?;
                if minor >= major {
                    return Err(self.invalid(
                        &minor_def.span(),
                        object,
                        format!(
                            "`minor_radius` ({minor}) must be smaller than `major_radius` ({major}); a horn or spindle torus intersects itself"
                        ),
                    ));
                }
                Ok(vec![(AnalyticKind::Torus { major, minor }, frame(center, axis))])
            }
            _ => {
                let center = optional_point(&s.center, "center")?;
                let def = self.require(&s.exponents, table, object, "exponents", "exponents = [0.5, 0.5]")?;
                let values = def.get_ref();
                let in_range = |v: f64| (SUPERELLIPSOID_MIN_EXPONENT..=2.0).contains(&v);
                if values.len() != 2 || !values.iter().all(|&v| in_range(v)) {
                    return Err(self.invalid(
                        &def.span(),
                        object,
                        format!(
                            "`exponents` is {values:?}; give two numbers [e, n] (POV-Ray's east-west and north-south exponents), each in [{SUPERELLIPSOID_MIN_EXPONENT}, 2] (1 is round, small is boxy, 2 is an octahedron)"
                        ),
                    ));
                }
                let (e, n) = (values[0] as f32, values[1] as f32);
                Ok(vec![(AnalyticKind::Superellipsoid { e, n }, Affine3A::from_translation(center))])
            }
        }
    }

    /// Refuses a placed analytic shape that float arithmetic cannot handle: a transform that
    /// flattens it (no inverse) or sends its bounds to infinity.
    pub(super) fn check_placement(&self, shape: &Analytic, span: &Range<usize>, object: &str) -> Result<()> {
        let det = shape.world_from_object.matrix3.determinant();
        let (lo, hi) = shape.bounds();
        let bounded = shape.is_unbounded() || (lo.is_finite() && hi.is_finite());
        let invertible = det.is_finite() && det.abs() > 1e-30 && shape.world_from_object.inverse().is_finite();
        if !bounded || !invertible {
            return Err(self.invalid(
                span,
                object,
                "`transform` scales the shape to zero or to infinity in float precision; use scale factors between about 1e-6 and 1e6"
                    .to_string(),
            ));
        }
        Ok(())
    }
}

/// The placement of an object space whose origin goes to `origin` and whose +y axis goes to the
/// unit vector `axis` (the shortest rotation: none for +y, a half turn about x for -y).
fn frame(origin: Vec3, axis: Vec3) -> Affine3A {
    let rotation = if axis.dot(Vec3::Y) < -0.999_999 {
        glam::Quat::from_rotation_x(std::f32::consts::PI)
    } else {
        glam::Quat::from_rotation_arc(Vec3::Y, axis)
    };
    Affine3A::from_rotation_translation(rotation, origin)
}
