//! `[[shapes]]`: the dispatch by `type`, the fields each type takes, transforms, and the
//! triangle shapes (quad, triangle, box) and spheres.

use std::ops::Range;

use glam::{Affine3A, Mat3, Vec2, Vec3};
use toml::Spanned;

use super::values::beyond_scene_range;
use super::values::transformed_out_of_range;
use super::values::vec3_text;
use super::{span_of, Builder, Result};
use crate::limits::{fmt_f32, MAX_SCENE_VALUE, MIN_SPHERE_RADIUS};
use crate::scene::error::object_name;
use crate::scene::format::{ShapeDef, TransformDef, Vec3Def};
use crate::scene::kinds::SHAPES;
use crate::scene::{Analytic, AnalyticKind, Geometry, Shape, Sphere, Triangle};

impl Builder<'_> {
    pub(super) fn shape(&mut self, index: usize, def: &Spanned<ShapeDef>) -> Result<()> {
        let s = def.get_ref();
        let object =
            format!("{}{}", self.context, object_name("shape", index, s.name.as_ref().map(|n| n.get_ref().as_str())));
        let table = def.span();
        let kind_def = self.require(&s.r#type, &table, &object, "type", "type = \"quad\"")?;
        let kind = self.one_of(kind_def, &object, "type", &SHAPES.names())?;
        self.shape_fields(kind, s, &object)?;
        self.group(&s.group, &object, self.context.is_empty())?;
        if kind == "csg" {
            return self.csg(def, &object);
        }
        let first_shape = self.shapes.len();
        let media = self.medium_interface(kind, s, &object)?;
        self.shape_kind(kind, s, &table, &object, None)?;
        if let Some(media) = media {
            if kind == "mesh" {
                let file = s.file.as_ref().expect("shape_kind required the file");
                self.close_mesh(first_shape, file, &object, "a medium", " or drop `interior`")?;
            }
            for shape in &mut self.shapes[first_shape..] {
                shape.media = Some(media);
            }
        }
        Ok(())
    }

    /// Refuses the fields a shape of type `kind` does not take.
    pub(super) fn shape_fields(&self, kind: &str, s: &ShapeDef, object: &str) -> Result<()> {
        let present = [
            ("name", span_of(&s.name)),
            ("type", span_of(&s.r#type)),
            ("material", span_of(&s.material)),
            ("vertices", span_of(&s.vertices)),
            ("normals", span_of(&s.normals)),
            ("center", span_of(&s.center)),
            ("radius", span_of(&s.radius)),
            ("min", span_of(&s.min)),
            ("max", span_of(&s.max)),
            ("file", span_of(&s.file)),
            ("transform", span_of(&s.transform)),
            ("normal", span_of(&s.normal)),
            ("offset", span_of(&s.offset)),
            ("inner_radius", span_of(&s.inner_radius)),
            ("base", span_of(&s.base)),
            ("cap", span_of(&s.cap)),
            ("base_radius", span_of(&s.base_radius)),
            ("cap_radius", span_of(&s.cap_radius)),
            ("open", span_of(&s.open)),
            ("axis", span_of(&s.axis)),
            ("major_radius", span_of(&s.major_radius)),
            ("minor_radius", span_of(&s.minor_radius)),
            ("exponents", span_of(&s.exponents)),
            ("smooth_angle", span_of(&s.smooth_angle)),
            ("file_normals", span_of(&s.file_normals)),
            ("subdivision", span_of(&s.subdivision)),
            ("levels", span_of(&s.levels)),
            ("crease_angle", span_of(&s.crease_angle)),
            ("flatness", span_of(&s.flatness)),
            ("lights", span_of(&s.lights)),
            ("shape_index", span_of(&s.shape_index)),
            ("points", span_of(&s.points)),
            ("interior", span_of(&s.interior)),
            ("exterior", span_of(&s.exterior)),
            ("operation", span_of(&s.operation)),
            ("children", span_of(&s.children)),
        ];
        self.only_kind_fields(object, SHAPES.kind(kind), &present)
    }

    /// Adds the shapes of one `[[shapes]]` table of type `kind`.
    /// `default_material` stands in for a missing `material` (a CSG node's, for its children).
    pub(super) fn shape_kind(
        &mut self,
        kind: &str,
        s: &ShapeDef,
        table: &Range<usize>,
        object: &str,
        default_material: Option<&Spanned<String>>,
    ) -> Result<()> {
        let (table, object) = (table.clone(), object.to_string());
        let material_field = s.material.as_ref().or(default_material);

        // A mesh may leave out `material`: its file's materials apply.
        if kind == "mesh" {
            let material = match material_field {
                Some(m) => Some(self.material_id(m, &object)?),
                None => None,
            };
            let transform = self.transform(s.transform.as_ref(), &object)?;
            let file = self.require(&s.file, &table, &object, "file", "file = \"meshes/bunny.obj\"")?;
            return self.mesh(file, s, &object, material, transform);
        }
        let material_def = match material_field {
            Some(m) => m,
            None => self.require(&s.material, &table, &object, "material", "material = \"white\"")?,
        };
        let material = self.material_id(material_def, &object)?;
        let transform = self.transform(s.transform.as_ref(), &object)?;

        match kind {
            "quad" | "triangle" => {
                let count = if kind == "quad" { 4 } else { 3 };
                let vertices = self.vertices(&s.vertices, &table, &object, count)?;
                self.polygon(
                    &vertices,
                    s.vertices.as_ref().map(|v| v.span()).unwrap_or(table),
                    &object,
                    material,
                    transform,
                )?;
                if let Some(normals) = &s.normals {
                    // Moved as the vertices were (a mirroring transform swaps two), turned to the
                    // winding side; `None` when they all equal the face's normal.
                    let normals = self.vertex_normals(normals, &object)?;
                    let raw = [vertices[0], vertices[1], vertices[2]];
                    let (_, _, moved) = apply_with_normals(transform, raw, None, Some(normals));
                    if let Some(Geometry::Triangle(t)) = self.shapes.last_mut().map(|s| &mut s.geometry) {
                        t.normals = moved;
                    }
                }
                Ok(())
            }
            "sphere" => {
                let center = self.require(&s.center, &table, &object, "center", "center = [0, 1, 0]")?;
                let radius = self.require(&s.radius, &table, &object, "radius", "radius = 1.0")?;
                self.sphere(center, radius, &object, material, transform)
            }
            "box" => {
                let min_def = self.require(&s.min, &table, &object, "min", "min = [0, 0, 0]")?;
                let max_def = self.require(&s.max, &table, &object, "max", "max = [1, 1, 1]")?;
                let min = self.point(min_def, &object, "min")?;
                let max = self.point(max_def, &object, "max")?;
                if !min.cmplt(max).all() {
                    return Err(self.invalid(
                        &max_def.span(),
                        &object,
                        format!(
                            "`max` ({}) must be greater than `min` ({}) in x, y and z",
                            vec3_text(max),
                            vec3_text(min)
                        ),
                    ));
                }
                for corners in box_faces(min, max) {
                    self.quad_triangles(&corners, &max_def.span(), &object, material, transform)?;
                }
                Ok(())
            }
            "bicubic_patch" => self.bicubic_patch(s, &table, &object, material, transform),
            _ => {
                if kind == "plane" && self.materials[material as usize].emits() {
                    return Err(self.invalid(
                        &material_def.span(),
                        &object,
                        format!(
                            "material \"{}\" emits light, but an infinite plane cannot be a light (its power would be infinite); use a quad or a disc, or a material without `emission`",
                            material_def.get_ref()
                        ),
                    ));
                }
                let pieces = self.analytic(kind, s, &table, &object)?;
                let span = s.transform.as_ref().map_or(table.clone(), |t| t.span());
                self.push_analytic(pieces, transform, &span, &object, material)
            }
        }
    }

    /// Places the object-space analytic `pieces` under `transform` as shapes of `material`, each
    /// checked against the scene range (an error at `span`).
    pub(super) fn push_analytic(
        &mut self,
        pieces: Vec<(AnalyticKind, Affine3A)>,
        transform: Option<Affine3A>,
        span: &Range<usize>,
        object: &str,
        material: u32,
    ) -> Result<()> {
        for (kind, placement) in pieces {
            let shape = Analytic { kind, world_from_object: transform.unwrap_or(Affine3A::IDENTITY) * placement };
            self.check_placement(&shape, span, object)?;
            self.shapes.push(Shape { geometry: Geometry::Analytic(shape), material, media: None });
        }
        Ok(())
    }

    /// `count` vertices from a `vertices` field.
    pub(super) fn vertices(
        &self,
        field: &Option<Spanned<Vec<Vec3Def>>>,
        table: &Range<usize>,
        object: &str,
        count: usize,
    ) -> Result<Vec<Vec3>> {
        let example = "vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]";
        let field = self.require(field, table, object, "vertices", example)?;
        let list = field.get_ref();
        if list.len() != count {
            return Err(self.invalid(
                &field.span(),
                object,
                format!("`vertices` has {} points; this shape needs {count}", list.len()),
            ));
        }
        list.iter()
            .map(|v| {
                let spanned = Spanned::new(field.span(), *v);
                self.point(&spanned, object, "vertices")
            })
            .collect()
    }

    /// A triangle's `normals`: three directions (any length but 0), made unit.
    fn vertex_normals(&self, field: &Spanned<Vec<Vec3Def>>, object: &str) -> Result<[Vec3; 3]> {
        let list = field.get_ref();
        if list.len() != 3 {
            return Err(self.invalid(
                &field.span(),
                object,
                format!(
                    "`normals` has {} directions; a triangle takes one per vertex, e.g. `normals = [[0, 0, 1], [0, 0.1, 1], [0.1, 0, 1]]`",
                    list.len()
                ),
            ));
        }
        let mut out = [Vec3::ZERO; 3];
        for (k, v) in list.iter().enumerate() {
            let n = self.point(&Spanned::new(field.span(), *v), object, "normals")?;
            let n = n.normalize_or_zero();
            if n == Vec3::ZERO || !n.is_finite() {
                return Err(self.invalid(
                    &field.span(),
                    object,
                    format!("`normals`: direction {k} has no length; give each vertex a direction such as [0, 0, 1]"),
                ));
            }
            out[k] = n;
        }
        Ok(out)
    }

    /// A triangle (3 vertices) or a quad (4 vertices, split into (v0,v1,v2), (v0,v2,v3)).
    pub(super) fn polygon(
        &mut self,
        vertices: &[Vec3],
        span: Range<usize>,
        object: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        if vertices.len() == 3 {
            let t = [vertices[0], vertices[1], vertices[2]];
            self.explicit_triangle(t, None, &span, object, "the triangle", material, transform)
        } else {
            let q = [vertices[0], vertices[1], vertices[2], vertices[3]];
            self.quad_triangles(&q, &span, object, material, transform)
        }
    }

    pub(super) fn quad_triangles(
        &mut self,
        q: &[Vec3; 4],
        span: &Range<usize>,
        object: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        // The split the Cornell data prescribes; some of its walls are not planar. The quad's uv
        // runs from (0, 0) at v0 over (1, 0) at v1 to (0, 1) at v3.
        let first = [q[0], q[1], q[2]];
        let second = [q[0], q[2], q[3]];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let which = "triangle (v0, v1, v2) of the quad";
        self.explicit_triangle(first, Some([uv[0], uv[1], uv[2]]), span, object, which, material, transform)?;
        let which = "triangle (v0, v2, v3) of the quad";
        self.explicit_triangle(second, Some([uv[0], uv[2], uv[3]]), span, object, which, material, transform)
    }

    /// A triangle written in the scene file: zero area is an error.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn explicit_triangle(
        &mut self,
        vertices: [Vec3; 3],
        uv: Option<[Vec2; 3]>,
        span: &Range<usize>,
        object: &str,
        which: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        let (vertices, uv) = apply(transform, vertices, uv);
        if let Some(far) = beyond_scene_range(&vertices) {
            return Err(self.invalid(span, object, transformed_out_of_range(far)));
        }
        if is_degenerate(&vertices) {
            return Err(self.invalid(
                span,
                object,
                format!("`vertices`: {which} has zero area (its points are equal or on a line); fix the points"),
            ));
        }
        self.shapes.push(Shape {
            geometry: Geometry::Triangle(Triangle { vertices, uv, normals: None }),
            material,
            media: None,
        });
        Ok(())
    }

    pub(super) fn sphere(
        &mut self,
        center: &Spanned<Vec3Def>,
        radius: &Spanned<f64>,
        object: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        let mut c = self.point(center, object, "center")?;
        let mut r = self.number(radius, object, "radius")?;
        if (r as f64) < MIN_SPHERE_RADIUS {
            return Err(self.invalid(
                &radius.span(),
                object,
                format!(
                    "`radius` is {}; it must be > 0 (at least {MIN_SPHERE_RADIUS:e}, at most {MAX_SCENE_VALUE:e})",
                    fmt_f32(r)
                ),
            ));
        }
        let mut object_from_world = None;
        if let Some(t) = transform {
            // Columns of the linear part have the scale's lengths (rotation keeps lengths).
            let lengths = Vec3::new(t.matrix3.x_axis.length(), t.matrix3.y_axis.length(), t.matrix3.z_axis.length());
            if lengths.max_element() - lengths.min_element() > 1e-5 * lengths.max_element() {
                return Err(self.invalid(
                    &radius.span(),
                    object,
                    "`transform`: a sphere can only be scaled uniformly; give `scale` as one number".to_string(),
                ));
            }
            c = t.transform_point3(c);
            r *= lengths.x;
            // The rotation part orients the sphere's uv; a mirroring scale keeps its handedness
            // out of the rotation (the uv of a mirrored sphere is the unmirrored one's).
            let rotation = Mat3::from(t.matrix3) * (1.0 / lengths.x);
            let rotation = if rotation.determinant() < 0.0 { -rotation } else { rotation };
            object_from_world = Some(rotation.transpose());
        }
        if let Some(far) = beyond_scene_range(&[c - Vec3::splat(r), c + Vec3::splat(r)]) {
            let message = match transform {
                Some(_) => transformed_out_of_range(far),
                None => format!(
                    "the sphere reaches coordinate {}, beyond the largest scene coordinate, +-{MAX_SCENE_VALUE:e} (see \
                     docs/limits.md)",
                    fmt_f32(far)
                ),
            };
            return Err(self.invalid(&radius.span(), object, message));
        }
        if (r as f64) < MIN_SPHERE_RADIUS {
            let message = format!(
                "`transform` shrinks the sphere to radius {}, below the smallest, {MIN_SPHERE_RADIUS:e}",
                fmt_f32(r)
            );
            return Err(self.invalid(&radius.span(), object, message));
        }
        let sphere = Sphere { center: c, radius: r, object_from_world };
        self.shapes.push(Shape { geometry: Geometry::Sphere(sphere), material, media: None });
        Ok(())
    }

    /// `world_from_object` = translate · rotate Z · rotate Y · rotate X · scale.
    pub(super) fn transform(&self, def: Option<&Spanned<TransformDef>>, object: &str) -> Result<Option<Affine3A>> {
        let Some(def) = def else {
            return Ok(None);
        };
        let t = def.get_ref();
        if let Some(m) = &t.matrix {
            return self.matrix_transform(m, t, object).map(Some);
        }
        let scale = match &t.scale {
            Some(s) => {
                let scale = self.vector(s, object, "transform.scale")?;
                if scale.abs().min_element() == 0.0 {
                    return Err(self.invalid(
                        &s.span(),
                        object,
                        "`transform.scale` is 0 along an axis, which flattens the shape; give non-zero factors"
                            .to_string(),
                    ));
                }
                scale
            }
            None => Vec3::ONE,
        };
        let rotate = match &t.rotate {
            Some(r) => self.point(r, object, "transform.rotate")?,
            None => Vec3::ZERO,
        };
        let translate = match &t.translate {
            Some(tr) => self.point(tr, object, "transform.translate")?,
            None => Vec3::ZERO,
        };
        let r = rotate * (std::f32::consts::PI / 180.0);
        let rotation = Mat3::from_rotation_z(r.z) * Mat3::from_rotation_y(r.y) * Mat3::from_rotation_x(r.x);
        Ok(Some(Affine3A::from_mat3_translation(rotation * Mat3::from_diagonal(scale), translate)))
    }
}

impl Builder<'_> {
    /// `transform.matrix`: 16 numbers, row by row, an affine map whose last row is 0 0 0 1.
    fn matrix_transform(&self, m: &Spanned<Vec<f64>>, t: &TransformDef, object: &str) -> Result<Affine3A> {
        let others =
            [("scale", t.scale.is_some()), ("rotate", t.rotate.is_some()), ("translate", t.translate.is_some())];
        if let Some((name, _)) = others.iter().find(|(_, given)| *given) {
            let message =
                format!("`transform.matrix` is the whole transform; drop `{name}` or fold it into the matrix");
            return Err(self.invalid(&m.span(), object, message));
        }
        let v = m.get_ref();
        if v.len() != 16 {
            let message = format!("`transform.matrix` has {} numbers; give 16, row by row", v.len());
            return Err(self.invalid(&m.span(), object, message));
        }
        if v.iter().any(|x| !x.is_finite() || x.abs() > 1e30) {
            return Err(self.invalid(&m.span(), object, "`transform.matrix` holds a number that is not finite".into()));
        }
        if v[12..] != [0.0, 0.0, 0.0, 1.0] {
            let message = "`transform.matrix`: the last row must be [0, 0, 0, 1] (an affine transform)".to_string();
            return Err(self.invalid(&m.span(), object, message));
        }
        let f = |r: usize, c: usize| v[4 * r + c] as f32;
        let linear = Mat3::from_cols(
            Vec3::new(f(0, 0), f(1, 0), f(2, 0)),
            Vec3::new(f(0, 1), f(1, 1), f(2, 1)),
            Vec3::new(f(0, 2), f(1, 2), f(2, 2)),
        );
        let det = linear.determinant();
        let size = linear.to_cols_array().iter().fold(0f32, |a, x| a.max(x.abs()));
        if !det.is_finite() || det.abs() <= 1e-12 * size * size * size || size == 0.0 {
            let message = "`transform.matrix` flattens the shape (its 3x3 part is not invertible)".to_string();
            return Err(self.invalid(&m.span(), object, message));
        }
        Ok(Affine3A::from_mat3_translation(linear, Vec3::new(f(0, 3), f(1, 3), f(2, 3))))
    }
}

/// The triangle moved by `transform`, with its vertex uvs kept in step with its vertices.
fn apply(transform: Option<Affine3A>, vertices: [Vec3; 3], uv: Option<[Vec2; 3]>) -> ([Vec3; 3], Option<[Vec2; 3]>) {
    let Some(t) = transform else {
        return (vertices, uv);
    };
    let [a, b, c] = vertices.map(|v| t.transform_point3(v));
    // A mirroring transform flips the winding normal; swap two vertices so the front face stays
    // on the same side of the surface (outward stays outward). The default uv goes with them.
    if t.matrix3.determinant() < 0.0 {
        let [u0, u1, u2] = uv.unwrap_or([Vec2::ZERO, Vec2::X, Vec2::Y]);
        ([a, c, b], Some([u0, u2, u1]))
    } else {
        ([a, b, c], uv)
    }
}

/// `apply` for a triangle with vertex normals: normals move by the inverse transpose and follow
/// their vertices when a mirroring transform swaps two of them.
pub(super) fn apply_with_normals(
    transform: Option<Affine3A>,
    vertices: [Vec3; 3],
    uv: Option<[Vec2; 3]>,
    normals: Option<[Vec3; 3]>,
) -> ([Vec3; 3], Option<[Vec2; 3]>, Option<[Vec3; 3]>) {
    let (v, uv_out) = apply(transform, vertices, uv);
    let Some(n) = normals else {
        return (v, uv_out, None);
    };
    let Some(t) = transform else {
        return (v, uv_out, Some(n));
    };
    let normal_matrix = Mat3::from(t.matrix3).inverse().transpose();
    let [a, b, c] = n.map(|n| (normal_matrix * n).normalize_or_zero());
    let mut moved = if t.matrix3.determinant() < 0.0 { [a, c, b] } else { [a, b, c] };
    let face = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
    let smooth = crate::scene::model::smooth_normals(&mut moved, face);
    (v, uv_out, smooth.then_some(moved))
}

/// Zero area, to f32 precision: |cross| is tiny next to the longest edge squared. Also catches
/// non-finite vertices (a huge scale).
pub(super) fn is_degenerate(v: &[Vec3; 3]) -> bool {
    let e0 = v[1] - v[0];
    let e1 = v[2] - v[0];
    let e2 = v[2] - v[1];
    let longest = e0.length_squared().max(e1.length_squared()).max(e2.length_squared());
    let twice_area = e0.cross(e1).length();
    let has_area = twice_area.is_finite() && twice_area > 1e-7 * longest;
    !has_area
}

/// The six faces of an axis-aligned box as quads whose winding normal points outward.
fn box_faces(min: Vec3, max: Vec3) -> [[Vec3; 4]; 6] {
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(if x { max.x } else { min.x }, if y { max.y } else { min.y }, if z { max.z } else { min.z })
    };
    // Each face listed counter-clockwise seen from outside, so (v1-v0)x(v2-v0) points out.
    [
        [p(false, false, false), p(false, false, true), p(false, true, true), p(false, true, false)], // -x
        [p(true, false, false), p(true, true, false), p(true, true, true), p(true, false, true)],     // +x
        [p(false, false, false), p(true, false, false), p(true, false, true), p(false, false, true)], // -y
        [p(false, true, false), p(false, true, true), p(true, true, true), p(true, true, false)],     // +y
        [p(false, false, false), p(false, true, false), p(true, true, false), p(true, false, false)], // -z
        [p(false, false, true), p(true, false, true), p(true, true, true), p(false, true, true)],     // +z
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_face_normals_point_outward() {
        let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 5.0));
        let center = (min + max) / 2.0;
        for face in box_faces(min, max) {
            let n = (face[1] - face[0]).cross(face[2] - face[0]);
            let face_center = (face[0] + face[1] + face[2] + face[3]) / 4.0;
            assert!(n.dot(face_center - center) > 0.0, "face {face:?} normal {n}");
        }
    }

    #[test]
    fn mirroring_transform_keeps_the_front_face_outward() {
        let t = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let triangle = [Vec3::ZERO, Vec3::X, Vec3::Y]; // normal +z
        let (out, _) = apply(Some(t), triangle, None);
        let n = (out[1] - out[0]).cross(out[2] - out[0]);
        assert!(n.z > 0.0, "mirror in x keeps a +z normal: {n}");
    }

    #[test]
    fn degenerate_catches_collinear_and_equal_points() {
        assert!(is_degenerate(&[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]));
        assert!(is_degenerate(&[Vec3::ONE, Vec3::ONE, Vec3::ONE]));
        assert!(!is_degenerate(&[Vec3::ZERO, Vec3::X, Vec3::Y]));
    }
}
