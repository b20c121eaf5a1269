//! `type = "csg"`: a boolean tree over closed shapes (scene::csg). Each child is a closed shape
//! table of its own (or another csg node), parsed as a `[[shapes]]` entry would be and then taken
//! out of the scene's shape list into the tree's leaves.

use toml::Spanned;

use super::{Builder, Result};
use crate::layout::constants::{CSG_MAX_DEPTH, CSG_MAX_IMPLICIT, CSG_MAX_LEAVES, CSG_MAX_PRIMITIVES};
use crate::limits::printable;
use crate::scene::format::ShapeDef;
use crate::scene::kinds::SHAPES;
use crate::scene::{Csg, CsgNode, CsgOp, Geometry, Shape};

const CSG_OPERATIONS: &[&str] = &["union", "intersection", "difference", "merge"];

impl Builder<'_> {
    /// Adds the CSG object of `def` as one shape.
    pub(super) fn csg(&mut self, def: &Spanned<ShapeDef>, object: &str) -> Result<()> {
        let mut leaves = Vec::new();
        let root = self.csg_node(def, object, 1, None, &mut leaves)?;
        let span = def.get_ref().children.as_ref().map_or(def.span(), |c| c.span());
        if leaves.len() > CSG_MAX_LEAVES as usize {
            return Err(self.invalid(
                &span,
                object,
                format!(
                    "this csg has {} leaf shapes, and one CSG object takes at most {CSG_MAX_LEAVES}; split it into several csg objects side by side",
                    leaves.len()
                ),
            ));
        }
        let primitives: usize = leaves.iter().map(Vec::len).sum();
        if primitives > CSG_MAX_PRIMITIVES as usize {
            return Err(self.invalid(
                &span,
                object,
                format!(
                    "the leaves of this csg make {primitives} primitives (a sphere is 1, a capped cylinder 3, a box 12, a mesh one per triangle), and one CSG object takes at most {CSG_MAX_PRIMITIVES}; use fewer or simpler children, or split it into several csg objects"
                ),
            ));
        }
        let implicit = leaves.iter().flatten().filter(|s| s.geometry.is_implicit()).count();
        if implicit > CSG_MAX_IMPLICIT as usize {
            return Err(self.invalid(
                &span,
                object,
                format!(
                    "this csg has {implicit} tori and superellipsoids among its leaves, and one CSG object takes at most {CSG_MAX_IMPLICIT} (each costs a root search at every crossing of every ray, see docs/limits.md); split it into several csg objects"
                ),
            ));
        }
        let material = leaves[0][0].material;
        self.shapes.push(Shape { geometry: Geometry::Csg(Box::new(Csg { root, leaves })), material, media: None });
        Ok(())
    }

    /// The node of `def` (nested `depth` deep), its leaves appended to `leaves`; `inherited` is the
    /// material of the nearest csg node above that names one.
    fn csg_node(
        &mut self,
        def: &Spanned<ShapeDef>,
        object: &str,
        depth: u32,
        inherited: Option<&Spanned<String>>,
        leaves: &mut Vec<Vec<Shape>>,
    ) -> Result<CsgNode> {
        let s = def.get_ref();
        let table = def.span();
        if depth > CSG_MAX_DEPTH {
            return Err(self.invalid(
                &table,
                object,
                format!(
                    "csg nodes are nested {depth} deep here, and a CSG object takes at most {CSG_MAX_DEPTH}; flatten the tree (a union, merge or intersection takes any number of children, and so does a difference: the first minus all the others)"
                ),
            ));
        }
        let op_def = self.require(&s.operation, &table, object, "operation", "operation = \"difference\"")?;
        let op = match self.one_of(op_def, object, "operation", CSG_OPERATIONS)? {
            "union" => CsgOp::Union,
            "intersection" => CsgOp::Intersection,
            "difference" => CsgOp::Difference,
            _ => CsgOp::Merge,
        };
        let children = self.require(
            &s.children,
            &table,
            object,
            "children",
            "children = [{ type = \"box\", min = [0, 0, 0], max = [1, 1, 1] }, { type = \"sphere\", center = [1, 1, 1], radius = 0.5 }]",
        )?;
        if children.get_ref().len() < 2 {
            return Err(self.invalid(
                &children.span(),
                object,
                format!("a csg needs at least two children, and this one has {}", children.get_ref().len()),
            ));
        }
        if let Some(m) = &s.material {
            self.material_id(m, object)?;
        }
        let default = s.material.as_ref().or(inherited);
        let mut nodes = Vec::new();
        for (k, child) in children.get_ref().iter().enumerate() {
            let c = child.get_ref();
            let child_object = match &c.name {
                Some(n) => format!("{object}, child {k} (\"{}\")", printable(n.get_ref())),
                None => format!("{object}, child {k}"),
            };
            let kind_def = self.require(&c.r#type, &child.span(), &child_object, "type", "type = \"sphere\"")?;
            let kind = self.one_of(kind_def, &child_object, "type", &SHAPES.names())?;
            self.shape_fields(kind, c, &child_object)?;
            self.group(&c.group, &child_object, false)?;
            if kind == "csg" {
                nodes.push(self.csg_node(child, &child_object, depth + 1, default, leaves)?);
                continue;
            }
            let open = c.open.as_ref().filter(|o| *o.get_ref());
            let refusal = match kind {
                "quad" | "triangle" | "disc" | "plane" | "bicubic_patch" => {
                    Some(format!("a {kind} encloses no volume, and a csg child must be a closed shape; use a box, a sphere, a capped cylinder or cone, a closed mesh or another csg"))
                }
                "cylinder" | "cone" if open.is_some() => Some(format!(
                    "an open {kind} encloses no volume, and a csg child must be a closed shape; drop `open` to cap it"
                )),
                _ => None,
            };
            if let Some(message) = refusal {
                let span = open.map_or(kind_def.span(), |o| o.span());
                return Err(self.invalid(&span, &child_object, message));
            }
            if let Some(m) = c.interior.as_ref().or(c.exterior.as_ref()) {
                return Err(self.invalid(
                    &m.span(),
                    &child_object,
                    "a csg child cannot bound a medium (media inside CSG objects are not supported, see docs/limits.md); drop `interior` and `exterior`".to_string(),
                ));
            }
            let first = self.shapes.len();
            self.shape_kind(kind, c, &child.span(), &child_object, default)?;
            if kind == "mesh" {
                let file = c.file.as_ref().expect("shape_kind required the file");
                self.close_mesh(first, file, &child_object, "a csg child", "")?;
            }
            let mut shapes: Vec<Shape> = self.shapes.drain(first..).collect();
            let material_span = c.material.as_ref().or(default).map_or(child.span(), |m| m.span());
            for shape in &mut shapes {
                // Rays leaving a smooth triangle skip it (`trace_ray`'s `ignore`), which the
                // walk's inside bits cannot: CSG meshes are shaded flat.
                if let Geometry::Triangle(t) = &mut shape.geometry {
                    t.normals = None;
                }
                let m = &self.materials[shape.material as usize];
                let name = printable(&self.material_names[shape.material as usize]);
                if m.emits() {
                    return Err(self.invalid(
                        &material_span,
                        &child_object,
                        format!("material \"{name}\" emits light, but a csg child cannot be a light (its sampled surface would include the parts the CSG hides); use a material without `emission`"),
                    ));
                }
                if m.has_alpha() {
                    return Err(self.invalid(
                        &material_span,
                        &child_object,
                        format!("material \"{name}\" has an opacity below 1, which a csg child does not support (see docs/limits.md); use an opaque material"),
                    ));
                }
            }
            leaves.push(shapes);
            nodes.push(CsgNode::Leaf(leaves.len() as u32 - 1));
        }
        Ok(CsgNode::Op(op, nodes))
    }
}
