//! `<shape>`: `obj`, `ply`, `serialized`, `rectangle`, `disk`, `cube`, `sphere`, `cylinder`, each a
//! `[[shapes]]` entry with its `to_world` as a `transform.matrix`, its BSDF as a material, an area
//! emitter as that material's emission, and media as `interior`/`exterior`.

use glam::{DMat3, DMat4, DVec3};

use super::out::{list, num, string, vec3, Fields};
use super::props::Plugin;
use super::xml::Element;
use super::{transform, Result, Translator, Uv};

impl<'a> Translator<'a> {
    pub(crate) fn shape(&mut self, el: &'a Element) -> Result<()> {
        let p = Plugin::new(el);
        let world_from_object = match p.prop("to_world") {
            Some(t) => transform::parse(t)?,
            None => DMat4::IDENTITY,
        };
        let mut fields = Fields::new();
        if let Some(id) = p.id() {
            fields.push(("name".into(), string(id)));
        }
        let mut uv = Uv::AsIs;
        let mut matrix = true;
        match p.kind.as_str() {
            "obj" | "ply" | "serialized" => {
                let Some((file, at)) = p.string("filename")? else {
                    return Err(p.error(el.pos, "needs a `filename`".into()));
                };
                fields.push(("type".into(), string("mesh")));
                fields.push(("file".into(), string(&self.file_name(file, at))));
                if p.kind == "obj" && p.boolean("flip_tex_coords")?.unwrap_or(true) {
                    uv = Uv::Flipped;
                }
                if p.boolean("face_normals")?.unwrap_or(false) {
                    fields.push(("smooth_angle".into(), num(0.0)));
                }
                if p.boolean("flip_normals")?.unwrap_or(false) {
                    self.warn(el.pos, "`flip_normals` is not supported; the faces keep their winding".into());
                }
                if p.kind == "serialized" {
                    let index = p.integer("shape_index")?.unwrap_or(0);
                    fields.push(("shape_index".into(), index.to_string()));
                }
                let _ = p.boolean("collapse")?;
            }
            "rectangle" => {
                fields.push(("type".into(), string("quad")));
                fields.push(("vertices".into(), "[[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]".into()));
            }
            "disk" => {
                fields.push(("type".into(), string("disc")));
                fields.push(("center".into(), vec3([0.0; 3])));
                fields.push(("normal".into(), vec3([0.0, 0.0, 1.0])));
                fields.push(("radius".into(), num(1.0)));
            }
            "cube" => {
                fields.push(("type".into(), string("box")));
                fields.push(("min".into(), vec3([-1.0; 3])));
                fields.push(("max".into(), vec3([1.0; 3])));
            }
            "cylinder" => {
                let p0 = p.vector("p0")?.unwrap_or([0.0; 3]);
                let p1 = p.vector("p1")?.unwrap_or([0.0, 0.0, 1.0]);
                let r = p.float_or("radius", 1.0)?;
                fields.push(("type".into(), string("cylinder")));
                fields.push(("base".into(), vec3(p0)));
                fields.push(("cap".into(), vec3(p1)));
                fields.push(("radius".into(), num(r)));
                // Mitsuba's cylinder has no caps.
                fields.push(("open".into(), "true".into()));
            }
            "sphere" => {
                let c = DVec3::from(p.vector("center")?.unwrap_or([0.0; 3]));
                let r = p.float_or("radius", 1.0)?;
                let Some(s) = uniform_scale(&world_from_object) else {
                    return Err(p.error(el.pos, "`to_world` scales the sphere unevenly; Photonix's spheres take a uniform scale".into()));
                };
                fields.push(("type".into(), string("sphere")));
                fields.push(("center".into(), vec3(world_from_object.transform_point3(c).to_array())));
                fields.push(("radius".into(), num(r * s)));
                matrix = false;
            }
            other => {
                return Err(p.error(
                    el.pos,
                    format!(
                        "the `{}` shape is not supported; Photonix reads obj, ply, serialized, rectangle, disk, cube, sphere and cylinder",
                        crate::limits::printable(other)
                    ),
                ))
            }
        }

        // The BSDF, an area emitter, media.
        let mut bsdf = None;
        let mut emission = None;
        for (i, c) in el.children.iter().enumerate() {
            if !super::props::PLUGIN_TAGS.contains(&c.tag.as_str()) {
                continue;
            }
            let target = if c.tag == "ref" { self.ids_target(c)? } else { c };
            p.mark(i);
            match target.tag.as_str() {
                "bsdf" => bsdf = Some(target),
                "emitter" => emission = Some(self.area_emitter(target)?),
                "medium" => {
                    let side = c.attr("name").map(super::props::snake_case).unwrap_or_default();
                    let name = self.medium(target)?;
                    match side.as_str() {
                        "interior" | "exterior" => fields.push((side, string(&name))),
                        _ => self.warn(
                            c.pos,
                            "a medium on a shape needs name=\"interior\" or \"exterior\"; it is ignored".into(),
                        ),
                    }
                }
                other => self.warn(c.pos, format!("<{other}> inside a shape is not read by Photonix and is ignored")),
            }
        }
        let material = self.material_name(bsdf, uv, emission.as_deref(), el.pos)?;
        fields.push(("material".into(), string(&material)));
        if matrix && !world_from_object.abs_diff_eq(DMat4::IDENTITY, 0.0) {
            fields.push((
                "transform".into(),
                format!("{{ matrix = {} }}", list(&transform::row_major(&world_from_object))),
            ));
        }
        self.finish(&p);
        self.out.entry("[[shapes]]", &fields, el.pos);
        Ok(())
    }

    fn ids_target(&self, r: &'a Element) -> Result<&'a Element> {
        let tag = r.attr("id").and_then(|id| self.ids.get(id)).map(|t| t.tag.clone()).unwrap_or_else(|| "bsdf".into());
        self.resolve(r, &tag)
    }
}

/// The scale of a similarity transform (rotation times a uniform scale), or `None`.
fn uniform_scale(m: &DMat4) -> Option<f64> {
    let l = DMat3::from_mat4(*m);
    let g = l.transpose() * l;
    let s2 = g.x_axis.x;
    let tolerance = 1e-6 * s2;
    let ok = (g - DMat3::from_diagonal(DVec3::splat(s2))).to_cols_array().iter().all(|v| v.abs() <= tolerance);
    (ok && s2 > 0.0).then(|| s2.sqrt())
}
