//! `<transform>`: `matrix`, `lookat`, `translate`, `rotate` and `scale`, each applied after the
//! ones before it (Mitsuba's order: the last element is the outermost).

use glam::{DMat4, DVec3};

use super::props::{numbers, parse_number, xyz};
use super::xml::Element;
use super::MitsubaError;

type Result<T> = std::result::Result<T, MitsubaError>;

/// The `world_from_object` matrix of a `<transform>` element.
pub fn parse(t: &Element) -> Result<DMat4> {
    let mut m = DMat4::IDENTITY;
    for op in &t.children {
        let step = match op.tag.as_str() {
            "matrix" => matrix(op)?,
            "translate" => DMat4::from_translation(DVec3::from(xyz(op, 0.0)?)),
            "scale" => scale(op)?,
            "rotate" => rotate(op)?,
            "lookat" => lookat(op)?,
            other => {
                return Err(MitsubaError::at(
                    op.pos,
                    format!(
                        "<{}> is not a transform; a <transform> holds <matrix>, <lookat>, <translate>, <rotate> and <scale>",
                        crate::limits::printable(other)
                    ),
                ))
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(MitsubaError::at(t.pos, "the transform is not finite".into()));
    }
    Ok(m)
}

fn matrix(op: &Element) -> Result<DMat4> {
    let v = super::props::value(op)?;
    let n = numbers(v).unwrap_or_default();
    let rows: [[f64; 4]; 4] = match n.len() {
        16 => std::array::from_fn(|r| std::array::from_fn(|c| n[4 * r + c])),
        9 => std::array::from_fn(|r| {
            std::array::from_fn(|c| {
                if r < 3 && c < 3 {
                    n[3 * r + c]
                } else if r == c {
                    1.0
                } else {
                    0.0
                }
            })
        }),
        _ => {
            return Err(MitsubaError::at(
                op.pos,
                format!("<matrix>: `value` holds {} numbers; give 16 (row by row) or 9", n.len()),
            ))
        }
    };
    let m = DMat4::from_cols_array_2d(&rows).transpose();
    if m.row(3) != glam::DVec4::new(0.0, 0.0, 0.0, 1.0) {
        return Err(MitsubaError::at(
            op.pos,
            "<matrix>: the last row must be 0 0 0 1 (projective matrices are not supported)".into(),
        ));
    }
    Ok(m)
}

fn scale(op: &Element) -> Result<DMat4> {
    let s = xyz(op, 1.0)?;
    if s.contains(&0.0) {
        return Err(MitsubaError::at(op.pos, "<scale> by 0 flattens the object; give non-zero factors".into()));
    }
    Ok(DMat4::from_scale(DVec3::from(s)))
}

fn rotate(op: &Element) -> Result<DMat4> {
    let axis = DVec3::from(xyz(op, 0.0)?);
    let angle = op.attr("angle").and_then(parse_number).ok_or_else(|| {
        MitsubaError::at(op.pos, "<rotate> needs an `angle` in degrees (and the axis as x, y, z)".into())
    })?;
    if axis.length_squared() == 0.0 {
        return Err(MitsubaError::at(op.pos, "<rotate> has no axis; give x, y and z (e.g. y=\"1\")".into()));
    }
    Ok(DMat4::from_axis_angle(axis.normalize(), angle.to_radians()))
}

/// Mitsuba's `lookat`: object +z toward the target, +y toward `up`, +x = up x dir (the image's
/// left for a sensor).
fn lookat(op: &Element) -> Result<DMat4> {
    let point = |name: &str, required: bool| -> Result<Option<DVec3>> {
        match op.attr(name) {
            Some(s) => match numbers(s).as_deref() {
                Some([x, y, z]) => Ok(Some(DVec3::new(*x, *y, *z))),
                _ => Err(MitsubaError::at(
                    op.pos,
                    format!("<lookat>: `{name}` = \"{}\": give 3 numbers", crate::limits::printable(s)),
                )),
            },
            None if required => Err(MitsubaError::at(op.pos, format!("<lookat> needs `{name}`"))),
            None => Ok(None),
        }
    };
    let origin = point("origin", true)?.unwrap_or_default();
    let target = point("target", true)?.unwrap_or_default();
    let up = point("up", false)?.unwrap_or(DVec3::Y);
    let dir = (target - origin).normalize_or_zero();
    let left = up.cross(dir).normalize_or_zero();
    if dir == DVec3::ZERO || left == DVec3::ZERO {
        return Err(MitsubaError::at(
            op.pos,
            "<lookat>: `target` equals `origin`, or `up` is parallel to the view direction".into(),
        ));
    }
    let new_up = dir.cross(left);
    Ok(DMat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0)))
}

/// The 16 numbers of `m`, row by row (the TOML `transform.matrix`).
pub fn row_major(m: &DMat4) -> [f64; 16] {
    let t = m.transpose().to_cols_array();
    t.map(|v| if v == 0.0 { 0.0 } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn el(tag: &str, attrs: &[(&str, &str)]) -> Element {
        Element {
            tag: tag.into(),
            attrs: attrs.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
            children: vec![],
            pos: Default::default(),
        }
    }

    #[test]
    fn operations_compose_in_file_order() {
        let mut t = el("transform", &[]);
        t.children.push(el("scale", &[("x", "2")]));
        t.children.push(el("rotate", &[("z", "1"), ("angle", "90")]));
        t.children.push(el("translate", &[("x", "1"), ("y", "2"), ("z", "3")]));
        let m = parse(&t).unwrap();
        // (1, 0, 0) -> scaled (2, 0, 0) -> rotated (0, 2, 0) -> moved (1, 4, 3).
        let p = m.transform_point3(DVec3::X);
        assert!((p - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-12, "{p}");
    }

    #[test]
    fn matrix_values_are_row_major() {
        let t = Element {
            children: vec![el("matrix", &[("value", "1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1")])],
            ..el("transform", &[])
        };
        let m = parse(&t).unwrap();
        assert_eq!(m.transform_point3(DVec3::ZERO), DVec3::new(5.0, 6.0, 7.0));
        assert_eq!(row_major(&m)[3], 5.0);
    }

    #[test]
    fn lookat_points_z_at_the_target_and_x_to_the_left() {
        let t = Element {
            children: vec![el("lookat", &[("origin", "0, 0, 5"), ("target", "0 0 0"), ("up", "0 1 0")])],
            ..el("transform", &[])
        };
        let m = parse(&t).unwrap();
        assert!((m.transform_vector3(DVec3::Z) - DVec3::NEG_Z).length() < 1e-12);
        // Looking down -z with +y up, the viewer's left is world -x.
        assert!((m.transform_vector3(DVec3::X) - DVec3::NEG_X).length() < 1e-12);
    }
}
