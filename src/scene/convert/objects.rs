//! `[objects.NAME]` and `[[instances]]`: shapes defined once, in object space, and placed many
//! times. An object may place other objects (its own `instances`); those placements are resolved
//! here, their transforms composed, so the renderer sees one flat list of instances of objects
//! that hold shapes.

use std::collections::BTreeMap;
use std::ops::Range;

use glam::{Affine3A, Vec3};
use toml::Spanned;

use super::{span_of, Builder, Result};
use crate::limits::{printable, MAX_INSTANCES};
use crate::scene::error::{object_name, suggest};
use crate::scene::format::{InstanceDef, ObjectDef, ShapeDef};
use crate::scene::{Geometry, InstanceDesc, ObjectDesc};

/// The objects of the file in file order: (name, definition).
type Entries<'f> = [(&'f Spanned<String>, &'f Spanned<ObjectDef>)];

impl Builder<'_> {
    /// Builds every object's shapes once, then resolves the placements of `[[instances]]`;
    /// `origins` gets, per placement, the range of instances it became.
    pub(super) fn objects(
        &mut self,
        defs: &BTreeMap<Spanned<String>, Spanned<ObjectDef>>,
        placements: &[Spanned<InstanceDef>],
        origins: &mut Vec<Range<usize>>,
    ) -> Result<(Vec<ObjectDesc>, Vec<InstanceDesc>)> {
        let mut entries: Vec<_> = defs.iter().collect();
        entries.sort_by_key(|(key, _)| key.span().start);
        let mut objects = Vec::with_capacity(entries.len());
        for (key, def) in &entries {
            objects.push(self.object(key, def)?);
        }
        let mut instances = Vec::new();
        let mut placed = vec![false; objects.len()];
        for (index, def) in placements.iter().enumerate() {
            let what = object_name("instance", index, def.get_ref().name.as_ref().map(|n| n.get_ref().as_str()));
            self.group(&def.get_ref().group, &what, true)?;
            let first = instances.len();
            let mut place = Placement {
                entries: &entries,
                objects: &objects,
                out: &mut instances,
                stack: Vec::new(),
                placed: &mut placed,
            };
            self.place(def, &what, Affine3A::IDENTITY, None, &mut place)?;
            origins.push(first..instances.len());
        }
        for (object, placed) in objects.iter().zip(&placed) {
            if !placed {
                self.warnings
                    .push(format!("object \"{}\" is defined but no instance places it", printable(&object.name)));
            }
        }
        Ok((objects, instances))
    }

    /// The shapes of one object, in object space.
    fn object(&mut self, key: &Spanned<String>, def: &Spanned<ObjectDef>) -> Result<ObjectDesc> {
        let name = key.get_ref();
        let object = format!("[objects.{}]", printable(name));
        let o = def.get_ref();
        if o.shapes.is_empty() && o.instances.is_empty() {
            return Err(self.invalid(
                &key.span(),
                &object,
                "the object is empty; give it shapes (`[[objects.NAME.shapes]]`, as `[[shapes]]`) or instances of \
                 other objects"
                    .to_string(),
            ));
        }
        for (index, placement) in o.instances.iter().enumerate() {
            self.group(&placement.get_ref().group, &format!("{object} instance {index}"), false)?;
        }
        let outer = std::mem::take(&mut self.shapes);
        let context = std::mem::replace(&mut self.context, format!("{object} "));
        let result = self.object_shapes(&o.shapes, &object);
        self.context = context;
        let shapes = std::mem::replace(&mut self.shapes, outer);
        result?;
        Ok(ObjectDesc { name: name.clone(), shapes })
    }

    fn object_shapes(&mut self, defs: &[Spanned<ShapeDef>], object: &str) -> Result<()> {
        for (index, def) in defs.iter().enumerate() {
            let first = self.shapes.len();
            self.shape(index, def)?;
            let table = def.span();
            if self.shapes[first..].iter().any(|s| s.geometry.is_unbounded()) {
                return Err(self.invalid(
                    &table,
                    object,
                    format!(
                        "shape {index} is an infinite plane, which no box bounds, so it cannot be part of an \
                         object; place it with [[shapes]]"
                    ),
                ));
            }
            if let Some(s) = self.shapes[first..].iter().find(|s| self.materials[s.material as usize].emits()) {
                let material = printable(&self.material_names[s.material as usize]);
                return Err(self.invalid(
                    &table,
                    object,
                    format!(
                        "shape {index} has material \"{material}\", which emits light; instanced shapes cannot be \
                         lights (their emission would not be sampled); place emitters with [[shapes]] or [[lights]]"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Places the object `def` names under `parent` (and, for a grid, at each of its places),
    /// then the objects that object places in turn.
    fn place(
        &mut self,
        def: &Spanned<InstanceDef>,
        what: &str,
        parent: Affine3A,
        material: Option<u32>,
        place: &mut Placement<'_, '_>,
    ) -> Result<()> {
        let p = def.get_ref();
        let table = def.span();
        let object_def = self.require(&p.object, &table, what, "object", "object = \"tree\"")?;
        let id = self.object_id(object_def, what, place.entries)?;
        if let Some(start) = place.stack.iter().position(|&o| o == id) {
            let chain: Vec<String> = place.stack[start..]
                .iter()
                .chain([&id])
                .map(|&o| format!("\"{}\"", printable(place.entries[o].0.get_ref())))
                .collect();
            return Err(self.invalid(
                &object_def.span(),
                what,
                format!(
                    "objects place each other in a circle ({}): an object cannot contain itself; remove one of \
                     these placements",
                    chain.join(" places ")
                ),
            ));
        }
        let transform = self.transform(p.transform.as_ref(), what)?.unwrap_or(Affine3A::IDENTITY);
        let own = match &p.material {
            Some(m) => {
                let id = self.material_id(m, what)?;
                if self.materials[id as usize].emits() {
                    return Err(self.invalid(
                        &m.span(),
                        what,
                        format!(
                            "material \"{}\" emits light; instanced shapes cannot be lights (their emission would \
                             not be sampled); give the instance a material without emission",
                            printable(m.get_ref())
                        ),
                    ));
                }
                Some(id)
            }
            None => None,
        };
        // The outermost placement's material wins: it replaces every material inside.
        let material = material.or(own);
        let offsets = self.grid(p, &table, what)?;
        place.placed[id] = true;
        place.stack.push(id);
        for offset in offsets {
            let world_from_object = parent * Affine3A::from_translation(offset) * transform;
            let det = world_from_object.matrix3.determinant();
            if !det.is_normal() || !world_from_object.is_finite() {
                let span = p.transform.as_ref().map_or(table.clone(), |t| t.span());
                return Err(self.invalid(
                    &span,
                    what,
                    format!(
                        "the placement's transform (with those of the objects around it) is not invertible in \
                         32-bit floats (determinant {det}); use scales between 1e-6 and 1e6"
                    ),
                ));
            }
            if !place.objects[id].shapes.is_empty() {
                if let Some(m) = material.filter(|&m| self.materials[m as usize].has_alpha()) {
                    if place.objects[id].shapes.iter().any(|s| matches!(s.geometry, Geometry::Csg(_))) {
                        let span = p.material.as_ref().map_or(table.clone(), |m| m.span());
                        return Err(self.invalid(
                            &span,
                            what,
                            format!(
                                "material \"{}\" has an opacity below 1, and object \"{}\" holds a CSG object, \
                                 whose leaves must be opaque (see docs/limits.md); give the instance an opaque \
                                 material",
                                printable(&self.material_names[m as usize]),
                                printable(place.entries[id].0.get_ref())
                            ),
                        ));
                    }
                }
                if place.out.len() >= MAX_INSTANCES as usize {
                    return Err(self.invalid(
                        &table,
                        what,
                        format!(
                            "the scene places more than {MAX_INSTANCES} instances (grids and nested objects counted \
                             out; see docs/limits.md); use fewer or smaller grids"
                        ),
                    ));
                }
                place.out.push(InstanceDesc { object: id as u32, world_from_object, material });
            }
            let (key, object_def) = place.entries[id];
            for (index, nested) in object_def.get_ref().instances.iter().enumerate() {
                let name = nested.get_ref().name.as_ref().map(|n| n.get_ref().as_str());
                let nested_what =
                    format!("[objects.{}] {}", printable(key.get_ref()), object_name("instance", index, name));
                self.place(nested, &nested_what, world_from_object, material, place)?;
            }
        }
        place.stack.pop();
        Ok(())
    }

    fn object_id(&self, value: &Spanned<String>, what: &str, entries: &Entries<'_>) -> Result<usize> {
        let name = value.get_ref();
        if let Some(id) = entries.iter().position(|(key, _)| key.get_ref() == name) {
            return Ok(id);
        }
        let names: Vec<String> = entries.iter().map(|(key, _)| key.get_ref().clone()).collect();
        let shown = printable(name);
        let hint = match suggest(name, &names) {
            Some(best) => format!("did you mean \"{}\"?", printable(&best)),
            None if names.is_empty() => format!("define it with an [objects.{shown}] table"),
            None => format!(
                "defined objects: {}; or add an [objects.{shown}] table",
                names.iter().take(20).map(|n| format!("\"{}\"", printable(n))).collect::<Vec<_>>().join(", ")
            ),
        };
        Err(self.invalid(&value.span(), what, format!("unknown object \"{shown}\" ({hint})")))
    }

    /// The offsets of a grid placement (`count` places along x, y, z, `spacing` apart), or the
    /// one offset 0 of a single placement.
    fn grid(&self, p: &InstanceDef, table: &Range<usize>, what: &str) -> Result<Vec<Vec3>> {
        let (count, spacing) = match (&p.count, &p.spacing) {
            (None, None) => return Ok(vec![Vec3::ZERO]),
            (Some(count), Some(spacing)) => (count, spacing),
            (Some(_), None) => {
                return Err(self.invalid(
                    table,
                    what,
                    "a grid of instances needs `spacing` (e.g. `spacing = [2, 0, 2]`) beside `count`".to_string(),
                ))
            }
            (None, Some(_)) => {
                return Err(self.invalid(
                    &span_of(&p.spacing).unwrap_or(table.clone()),
                    what,
                    "`spacing` places a grid of instances: give `count` too, e.g. `count = [10, 1, 10]`".to_string(),
                ))
            }
        };
        if count.get_ref().len() != 3 {
            return Err(self.invalid(
                &count.span(),
                what,
                format!("`count` has {} numbers; give 3, e.g. `count = [10, 1, 10]`", count.get_ref().len()),
            ));
        }
        let mut n = [0u32; 3];
        for (axis, c) in count.get_ref().iter().enumerate() {
            n[axis] = self.integer(c, what, "count", 1, MAX_INSTANCES, "", "")?;
        }
        let total = n.iter().map(|&c| c as u64).product::<u64>();
        if total > MAX_INSTANCES as u64 {
            return Err(self.invalid(
                &count.span(),
                what,
                format!("`count` places {total} instances; at most {MAX_INSTANCES} (see docs/limits.md)"),
            ));
        }
        let spacing = self.vector(spacing, what, "spacing")?;
        let mut offsets = Vec::with_capacity(total as usize);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    offsets.push(Vec3::new(i as f32, j as f32, k as f32) * spacing);
                }
            }
        }
        Ok(offsets)
    }
}

/// The state of resolving placements: the objects, the instances so far, the objects being
/// placed (outermost first, to catch an object that contains itself) and which were placed.
struct Placement<'e, 'f> {
    entries: &'e Entries<'f>,
    objects: &'e [ObjectDesc],
    out: &'e mut Vec<InstanceDesc>,
    stack: Vec<usize>,
    placed: &'e mut [bool],
}
