//! The scene as the page sees it: one JSON object with every entry of the file (its fields as
//! written, for the properties panel) and its geometry as world-space triangles (for the solid
//! viewport and for picking). Format (documented in docs/editor.md):
//!
//! ```text
//! { "revision", "file", "dirty", "notice", "can_undo", "can_redo", "undo_author", "redo_author", "warnings": [..],
//!   "bounds": { "min": [x,y,z], "max": [x,y,z] },
//!   "camera": { "fields": {..}, "position", "look_at", "up", "fov", "width", "height", "projection", "view_height" },
//!   "render": {..}, "photons": {..} | null, "environment": {..} | null,
//!   "materials": [ { "name", "fields": {..}, "color": [r,g,b], "emission": [r,g,b] } ],
//!   "shapes": [ { "id", "fields": {..}, "color", "emissive", "positions": [x,y,z, ...], "groups"? } ],
//!   "lights": [ { "id", "fields": {..}, "kind", "positions": [..], "position": [..]?, "direction": [..]? } ],
//!   "instances": [ { "id", "fields": {..}, "object", "copies", "drawn", "color", "emissive",
//!                    "positions": [..], "groups": [..] } ] }
//! ```
//! `notice` (or null) says what was opened in place of the file named and why (a `.toml` saved
//! beside a `.pov` and newer than it; `SceneDocument::load`).
//! `undo_author` and `redo_author` name the page session that made the step Undo or Redo would
//! take (0: an API call; null: no step), so a page can say whether it is its own.
//! `id` is the entry's stable id (`SceneDocument::ids`): the page selects and edits by it.
//! `geometry` is a key of the entry's triangles (a hash of `positions`): the scene messages
//! broadcast after an edit (`delta_message`, `"delta": true`) leave out the `positions` of
//! entries whose key the scene before had, and the page keeps those it has.
//! `positions` lists three vertices per triangle; analytic shapes (spheres, discs, cones, tori,
//! superellipsoids) come tessellated, an infinite plane as a square as large as the scene.
//! `groups` (`{ "start", "count", "color" }`, in triangles) colours the runs of an entry made
//! of several materials: a CSG object's leaves, an instanced object's shapes.
//!
//! A CSG object is drawn as its solid's surface: each leaf's tessellated triangles where the
//! operation shows them (judged at the triangle's centre, so a cut edge is as jagged as the
//! tessellation). An `[[instances]]` entry is every copy it places (a grid's and the nested
//! placements' included) in world space, `drawn = "triangles"`; past `MAX_INSTANCE_TRIANGLES`
//! each copy is its object's bounding box instead (`"boxes"`), and past that again one box
//! around all the copies (`"bounds"`), so a million trees do not make a gigabyte of JSON.

use std::collections::BTreeMap;

use glam::{Affine3A, Mat3, Vec3};
use serde_json::{json, Value as Json};
use toml_edit::{DocumentMut, Item};

use super::document::{toml_to_json, SceneDocument};
use crate::scene::analytic::transformed_box;
use crate::scene::csg::{Csg, CsgNode, CsgOp};
use crate::scene::{AnalyticKind, Geometry, LightKind, MaterialKind, ObjectDesc, Projection, Scene};

/// Segments around a tessellated analytic shape in the solid view.
const SEGMENTS: usize = 32;
/// Most triangles the solid view gets for one `[[instances]]` entry before it draws boxes.
pub const MAX_INSTANCE_TRIANGLES: usize = 200_000;

/// Triangles (9 numbers each) by material id.
pub(super) type Parts = BTreeMap<u32, Vec<f32>>;

/// The page's view of `doc`.
pub fn scene_json(doc: &SceneDocument) -> Json {
    scene_json_known(doc, &std::collections::HashSet::new())
}

/// `scene_json` with no `positions` for the shapes whose geometry key `known` holds (the pages
/// have them): a 100k-triangle mesh is not turned into a million JSON numbers at every edit.
pub fn scene_json_known(doc: &SceneDocument, known: &std::collections::HashSet<String>) -> Json {
    let scene = doc.scene();
    let origins = doc.origins();
    let parsed: DocumentMut = doc.text().parse().unwrap_or_default();
    let (lo, hi) = finite_bounds(scene);
    let extent = (hi - lo).length().max(1e-3);

    let entries = |key: &str| -> Vec<Json> {
        match parsed.get(key).and_then(Item::as_array_of_tables) {
            Some(a) => a.iter().map(|t| toml_to_json(&Item::Table(t.clone()))).collect(),
            None => Vec::new(),
        }
    };
    let shape_fields = entries("shapes");
    let light_fields = entries("lights");
    let positions = |range: &std::ops::Range<usize>| -> Vec<f32> {
        let mut out = Vec::new();
        for shape in scene.shapes.get(range.clone()).unwrap_or(&[]) {
            triangles(&shape.geometry, lo, hi, extent, &mut out);
        }
        out
    };

    let shapes: Vec<Json> = origins
        .shapes
        .iter()
        .zip(shape_fields)
        .map(|(range, fields)| {
            let material = scene.shapes.get(range.start).map(|s| s.material as usize);
            let (color, emissive) = material.map_or(([0.8; 3], false), |m| material_color(scene, m));
            let mut entry = json!({ "fields": fields, "color": color, "emissive": emissive });
            let csg =
                scene.shapes.get(range.clone()).unwrap_or(&[]).iter().any(|s| matches!(s.geometry, Geometry::Csg(_)));
            if csg {
                // A CSG object's leaves keep their own materials: one group per material.
                let mut parts = Parts::new();
                for shape in scene.shapes.get(range.clone()).unwrap_or(&[]) {
                    shape_parts(shape, lo, hi, extent, &mut parts);
                }
                let (positions, groups) = grouped(scene, parts);
                entry["positions"] = json!(positions);
                entry["groups"] = json!(groups);
            } else {
                let positions = positions(range);
                let key = key_of(&positions);
                if !known.contains(&key) {
                    entry["positions"] = json!(positions);
                }
                entry["geometry"] = json!(key);
            }
            entry
        })
        .collect();
    let instances: Vec<Json> = origins
        .instances
        .iter()
        .zip(entries("instances"))
        .map(|(range, fields)| instance_json(scene, range.clone(), fields))
        .collect();
    let lights: Vec<Json> = origins
        .lights
        .iter()
        .zip(light_fields)
        .enumerate()
        .map(|(i, (range, fields))| {
            let mut light = json!({ "fields": fields, "positions": positions(range) });
            let kind = scene.lights.get(i).map(|l| &l.kind);
            let (name, position, direction) = match kind {
                Some(LightKind::Point { position, .. }) => ("point", Some(*position), None),
                Some(LightKind::Spot { position, direction, .. }) => ("spot", Some(*position), Some(*direction)),
                Some(LightKind::Distant { direction, .. }) => ("distant", None, Some(*direction)),
                _ => ("area", None, None),
            };
            light["kind"] = json!(name);
            if let Some(p) = position {
                light["position"] = json!(p.to_array());
            }
            if let Some(d) = direction {
                light["direction"] = json!(d.to_array());
            }
            light
        })
        .collect();

    let mut materials = Vec::new();
    if let Some(table) = parsed.get("materials").and_then(Item::as_table_like) {
        for (name, item) in table.iter() {
            let (color, _) = scene
                .material_names
                .iter()
                .position(|n| n == name)
                .map_or(([0.8; 3], false), |m| material_color(scene, m));
            let emission = scene
                .material_names
                .iter()
                .position(|n| n == name)
                .map_or([0.0; 3], |m| scene.materials[m].emission.value.to_array());
            materials.push(json!({ "name": name, "fields": toml_to_json(item), "color": color, "emission": emission }));
        }
    }

    // Each entry's stable id (`Target::ShapeId` and its kin), which the page selects by.
    let with_ids = |mut entries: Vec<Json>, ids: &[u64]| -> Vec<Json> {
        for (entry, id) in entries.iter_mut().zip(ids) {
            entry["id"] = json!(id);
            if entry.get("geometry").is_none() {
                entry["geometry"] = json!(geometry_key(&entry["positions"]));
            }
        }
        entries
    };
    let ids = doc.ids();
    let (shapes, lights, instances) =
        (with_ids(shapes, &ids.shapes), with_ids(lights, &ids.lights), with_ids(instances, &ids.instances));

    let camera = &scene.camera;
    let (projection, view_height) = match camera.projection {
        Projection::Perspective => ("perspective", None),
        Projection::Orthographic { view_height } => ("orthographic", Some(view_height)),
        Projection::LatLong => ("latlong", None),
    };
    let table = |key: &str| parsed.get(key).map_or(Json::Null, toml_to_json);
    // A translated glTF scene's [camera] is the file's own camera: the importer's note that the
    // model's cameras go unused would mislead.
    let from_gltf = doc.text().starts_with(crate::scene::gltf_scene::HEADER);
    let warnings: Vec<&String> =
        scene.warnings.iter().filter(|w| !(from_gltf && crate::scene::gltf_scene::is_camera_note(w))).collect();
    json!({
        "revision": doc.revision(),
        "file": doc.path().file_name().map(|n| n.to_string_lossy().into_owned()),
        "dirty": doc.dirty(),
        "notice": doc.notice(),
        "can_undo": doc.can_undo(),
        "can_redo": doc.can_redo(),
        "undo_author": doc.undo_author(),
        "redo_author": doc.redo_author(),
        "warnings": warnings,
        "bounds": { "min": lo.to_array(), "max": hi.to_array() },
        "camera": {
            "fields": table("camera"),
            "position": camera.position.to_array(),
            "look_at": camera.look_at.to_array(),
            "up": camera.up.to_array(),
            "fov": camera.fov_deg,
            "width": camera.width,
            "height": camera.height,
            "projection": projection,
            "view_height": view_height,
            "aperture_radius": camera.lens.map(|l| l.radius),
            "focal_distance": camera.lens.map(|l| l.focal_distance),
        },
        "render": table("render"),
        "photons": table("photons"),
        "environment": table("environment"),
        "materials": materials,
        "shapes": shapes,
        "lights": lights,
        "instances": instances,
    })
}

/// An entry's geometry key: a hash of its `positions` (FNV-1a over the numbers' bits), the same
/// for the same triangles, so a page that has them need not get them again.
fn geometry_key(positions: &Json) -> String {
    let numbers = positions.as_array().map_or(&[][..], |a| a.as_slice());
    let floats: Vec<f32> = numbers.iter().map(|v| v.as_f64().unwrap_or(f64::NAN) as f32).collect();
    key_of(&floats)
}

/// `geometry_key` of the numbers before they are JSON (the same key: JSON holds an f32 exactly).
fn key_of(numbers: &[f32]) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for v in numbers {
        for byte in v.to_bits().to_le_bytes() {
            hash = (hash ^ byte as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    format!("{hash:016x}-{}", numbers.len())
}

const LISTS: [&str; 3] = ["shapes", "lights", "instances"];

/// The scene message `scene` (from `scene_json`) as sent to pages that have the scene before
/// it: with `"delta": true` and without the `positions` of the entries whose geometry key
/// `known` holds (the page takes them from the entry of that key it has). An edit beside a
/// 100k-triangle mesh then sends kilobytes, not the mesh again. Returns the text and the keys
/// of this scene (the next message's `known`); `scene` is left as it was.
pub fn delta_message(
    scene: &mut Json,
    known: &std::collections::HashSet<String>,
) -> (String, std::collections::HashSet<String>) {
    let mut keys = std::collections::HashSet::new();
    let mut taken = Vec::new();
    for list in LISTS {
        let Some(entries) = scene.get_mut(list).and_then(Json::as_array_mut) else { continue };
        for (i, entry) in entries.iter_mut().enumerate() {
            let Some(key) = entry["geometry"].as_str().map(str::to_string) else { continue };
            if known.contains(&key) {
                if let Some(positions) = entry.as_object_mut().and_then(|o| o.remove("positions")) {
                    taken.push((list, i, positions));
                }
            }
            keys.insert(key);
        }
    }
    scene["delta"] = json!(true);
    let text = scene.to_string();
    if let Some(o) = scene.as_object_mut() {
        o.remove("delta");
    }
    for (list, i, positions) in taken {
        scene[list][i]["positions"] = positions;
    }
    (text, keys)
}

/// The bounds of every shape but the infinite planes, instanced copies included; a unit box
/// when there are none.
pub fn finite_bounds(scene: &Scene) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for shape in scene.shapes.iter().filter(|s| !s.geometry.is_unbounded()) {
        let (a, b) = shape.geometry.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let boxes: Vec<(Vec3, Vec3)> = scene.objects.iter().map(object_bounds).collect();
    for instance in &scene.instances {
        let (a, b) = {
            let (lo, hi) = boxes[instance.object as usize];
            transformed_box(&instance.world_from_object, lo, hi)
        };
        lo = lo.min(a);
        hi = hi.max(b);
    }
    for light in &scene.lights {
        if let LightKind::Point { position, .. } | LightKind::Spot { position, .. } = light.kind {
            lo = lo.min(position);
            hi = hi.max(position);
        }
    }
    if lo.cmple(hi).all() {
        (lo, hi)
    } else {
        (Vec3::splat(-1.0), Vec3::splat(1.0))
    }
}

/// A colour for the solid view: the constant part of the material's main colour, or its
/// emission for a light.
fn material_color(scene: &Scene, id: usize) -> ([f32; 3], bool) {
    let Some(m) = scene.materials.get(id) else { return ([0.8; 3], false) };
    if m.emits() {
        let e = m.emission.value;
        return ((e / e.max_element()).to_array(), true);
    }
    let color = match &m.kind {
        MaterialKind::Diffuse { reflectance } | MaterialKind::Plastic { reflectance, .. } => reflectance.value,
        MaterialKind::Mirror { tint } => tint.value,
        MaterialKind::Dielectric { .. } | MaterialKind::ThinDielectric { .. } => Vec3::new(0.75, 0.85, 0.95),
        MaterialKind::Conductor { .. } => Vec3::splat(0.75),
        MaterialKind::Mix { a, .. } => return material_color(scene, *a as usize),
        // An invisible medium boundary: drawn pale so it can still be picked in the solid view.
        MaterialKind::Null => Vec3::new(0.85, 0.9, 1.0),
    };
    (color.to_array(), false)
}

/// Appends the world-space triangles of `geometry` to `out`.
pub(super) fn triangles(geometry: &Geometry, lo: Vec3, hi: Vec3, extent: f32, out: &mut Vec<f32>) {
    let mut push = |t: [Vec3; 3]| {
        for v in t {
            out.extend_from_slice(&v.to_array());
        }
    };
    match geometry {
        Geometry::Triangle(t) => push(t.vertices),
        Geometry::Sphere(s) => {
            let rotation = s.object_from_world.map_or(Mat3::IDENTITY, |m| m.transpose());
            let (nu, nv) = (SEGMENTS, SEGMENTS / 2);
            let point = |i: usize, j: usize| {
                let phi = 2.0 * std::f32::consts::PI * i as f32 / nu as f32;
                let theta = std::f32::consts::PI * j as f32 / nv as f32;
                let local = Vec3::new(theta.sin() * phi.sin(), theta.cos(), theta.sin() * phi.cos());
                s.center + rotation * local * s.radius
            };
            for i in 0..nu {
                for j in 0..nv {
                    let (a, b, c, d) = (point(i, j), point(i, j + 1), point(i + 1, j + 1), point(i + 1, j));
                    if j > 0 {
                        push([a, b, d]);
                    }
                    if j + 1 < nv {
                        push([b, c, d]);
                    }
                }
            }
        }
        Geometry::Analytic(a) if matches!(a.kind, AnalyticKind::Plane) => {
            // A square as large as the scene, centred under the scene's middle.
            let to_world = a.world_from_object;
            let to_object = to_world.inverse();
            let centre = to_object.transform_point3((lo + hi) * 0.5);
            let scale = to_object.transform_vector3(Vec3::new(extent, 0.0, 0.0)).length().max(extent * 1e-3);
            let size = scale * 1.5;
            let corner =
                |x: f32, z: f32| to_world.transform_point3(Vec3::new(centre.x + x * size, 0.0, centre.z + z * size));
            let (p, q, r, s) = (corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0));
            push([p, r, q]);
            push([p, s, r]);
        }
        Geometry::Analytic(a) => a.tessellate(SEGMENTS).into_iter().for_each(push),
        Geometry::Csg(c) => {
            for (_, positions) in csg_surface(c, lo, hi, extent) {
                out.extend(positions);
            }
        }
    }
}

/// Appends the triangles of `shape` to `parts` under its material (a CSG object's under each
/// leaf's own).
pub(super) fn shape_parts(shape: &crate::scene::Shape, lo: Vec3, hi: Vec3, extent: f32, parts: &mut Parts) {
    match &shape.geometry {
        Geometry::Csg(c) => {
            for (material, positions) in csg_surface(c, lo, hi, extent) {
                parts.entry(material).or_default().extend(positions);
            }
        }
        geometry => triangles(geometry, lo, hi, extent, parts.entry(shape.material).or_default()),
    }
}

/// The triangles, grouped by material, of the parts of `parts` in one array, and the groups
/// (`start` and `count` in triangles, `color`) that colour them.
fn grouped(scene: &Scene, parts: Parts) -> (Vec<f32>, Vec<Json>) {
    let mut positions = Vec::new();
    let mut groups = Vec::new();
    for (material, p) in parts.into_iter().filter(|(_, p)| !p.is_empty()) {
        let (color, emissive) = material_color(scene, material as usize);
        groups
            .push(json!({ "start": positions.len() / 9, "count": p.len() / 9, "color": color, "emissive": emissive }));
        positions.extend(p);
    }
    (positions, groups)
}

// ---------------------------------------------------------------------------------------------
// Instances

/// An object's shapes as triangles in object space, by material (objects hold no infinite
/// plane, so the scene's bounds do not enter).
pub(super) fn object_parts(object: &ObjectDesc) -> Parts {
    let mut parts = Parts::new();
    for shape in &object.shapes {
        shape_parts(shape, Vec3::ZERO, Vec3::ZERO, 1.0, &mut parts);
    }
    parts
}

/// The bounds of an object's shapes, in object space.
fn object_bounds(object: &ObjectDesc) -> (Vec3, Vec3) {
    object.shapes.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), s| {
        let (a, b) = s.geometry.bounds();
        (lo.min(a), hi.max(b))
    })
}

/// The 12 triangles of box (lo, hi) moved by `m`, appended to `out`.
fn box_triangles((lo, hi): (Vec3, Vec3), m: &Affine3A, out: &mut Vec<f32>) {
    let c = |i: usize| {
        m.transform_point3(Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        ))
    };
    const FACES: [[usize; 4]; 6] = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    for [a, b, d, e] in FACES {
        for t in [[a, b, d], [a, d, e]] {
            for i in t {
                out.extend_from_slice(&c(i).to_array());
            }
        }
    }
}

/// Appends `positions` (object space) moved by `m` to `out`.
fn transformed(positions: &[f32], m: &Affine3A, out: &mut Vec<f32>) {
    for v in positions.chunks_exact(3) {
        out.extend_from_slice(&m.transform_point3(Vec3::from_slice(v)).to_array());
    }
}

/// The page's view of one `[[instances]]` entry: the copies `range` of `Scene::instances`.
fn instance_json(scene: &Scene, range: std::ops::Range<usize>, fields: Json) -> Json {
    let copies = scene.instances.get(range).unwrap_or(&[]);
    let object_name = fields.get("object").cloned().unwrap_or(Json::Null);
    let mut cache: BTreeMap<u32, Parts> = BTreeMap::new();
    for c in copies {
        cache.entry(c.object).or_insert_with(|| object_parts(&scene.objects[c.object as usize]));
    }
    let count = |parts: &Parts| parts.values().map(|p| p.len() / 9).sum::<usize>();
    let total: usize = copies.iter().map(|c| count(&cache[&c.object])).sum();
    let first_material = copies.first().and_then(|c| c.material.or_else(|| cache[&c.object].keys().next().copied()));
    let (color, _) = first_material.map_or(([0.8; 3], false), |m| material_color(scene, m as usize));
    let mut parts = Parts::new();
    let drawn = if total <= MAX_INSTANCE_TRIANGLES {
        for c in copies {
            for (material, p) in &cache[&c.object] {
                transformed(p, &c.world_from_object, parts.entry(c.material.unwrap_or(*material)).or_default());
            }
        }
        "triangles"
    } else if copies.len() * 12 <= MAX_INSTANCE_TRIANGLES {
        for c in copies {
            let bounds = object_bounds(&scene.objects[c.object as usize]);
            box_triangles(bounds, &c.world_from_object, parts.entry(first_material.unwrap_or(0)).or_default());
        }
        "boxes"
    } else {
        let (lo, hi) = copies.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| {
            let (a, b) = {
                let (lo, hi) = object_bounds(&scene.objects[c.object as usize]);
                transformed_box(&c.world_from_object, lo, hi)
            };
            (lo.min(a), hi.max(b))
        });
        box_triangles((lo, hi), &Affine3A::IDENTITY, parts.entry(first_material.unwrap_or(0)).or_default());
        "bounds"
    };
    let (positions, groups) = grouped(scene, parts);
    json!({
        "fields": fields, "object": object_name, "copies": copies.len(), "drawn": drawn,
        "color": color, "emissive": false, "positions": positions, "groups": groups,
    })
}

// ---------------------------------------------------------------------------------------------
// CSG

/// The surface of a CSG object as the solid view draws it, by material: each leaf tessellated,
/// each triangle kept when the point at its centre is on the solid's surface (`shown`), tested
/// against the other leaves' tessellations (closed, so a ray's crossings tell inside from out).
fn csg_surface(c: &Csg, lo: Vec3, hi: Vec3, extent: f32) -> Parts {
    let leaves: Vec<Vec<(u32, Vec<f32>)>> = c
        .leaves
        .iter()
        .map(|shapes| {
            shapes
                .iter()
                .map(|s| {
                    let mut out = Vec::new();
                    triangles(&s.geometry, lo, hi, extent, &mut out);
                    (s.material, out)
                })
                .collect()
        })
        .collect();
    let solids: Vec<Solid> = leaves.iter().map(|parts| Solid::new(parts.iter().map(|(_, p)| p.as_slice()))).collect();
    // A box's face is two triangles: split large ones so that a cut shows at about a twelfth of
    // the object's size.
    let (a, b) = solids.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), s| (lo.min(s.lo), hi.max(s.hi)));
    let max_edge = (b - a).length().max(1e-6) / 12.0;
    let mut out = Parts::new();
    let mut pieces = Vec::new();
    for (leaf, parts) in leaves.iter().enumerate() {
        for (material, positions) in parts {
            for t in positions.chunks_exact(9) {
                pieces.clear();
                let t = [Vec3::from_slice(&t[0..3]), Vec3::from_slice(&t[3..6]), Vec3::from_slice(&t[6..9])];
                split(t, max_edge, 5, &mut pieces);
                for piece in &pieces {
                    let centre = (piece[0] + piece[1] + piece[2]) / 3.0;
                    if shown(&c.root, leaf as u32, centre, &solids) == Some(true) {
                        let part = out.entry(*material).or_default();
                        piece.iter().for_each(|v| part.extend_from_slice(&v.to_array()));
                    }
                }
            }
        }
    }
    out
}

/// Splits `t` into four at its edges' midpoints, `depth` times at most, until no edge is
/// longer than `max_edge`; appends the pieces to `out`.
fn split(t: [Vec3; 3], max_edge: f32, depth: u32, out: &mut Vec<[Vec3; 3]>) {
    let longest = (t[1] - t[0]).length().max((t[2] - t[1]).length()).max((t[0] - t[2]).length());
    if depth == 0 || longest <= max_edge {
        out.push(t);
        return;
    }
    let [a, b, c] = t;
    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
    for piece in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
        split(piece, max_edge, depth - 1, out);
    }
}

/// Whether a point `p` on leaf `leaf`'s surface is on the surface of `node`'s solid; `None`
/// when the leaf is not under `node`. Union shows every child's surface (POV-Ray's, inner ones
/// included); merge those outside the other children; intersection those inside all of them;
/// difference the first child's outside the others, and the others' inside the first.
fn shown(node: &CsgNode, leaf: u32, p: Vec3, solids: &[Solid]) -> Option<bool> {
    let CsgNode::Op(op, children) = node else {
        return (*node == CsgNode::Leaf(leaf)).then_some(true);
    };
    let (k, on) = children.iter().enumerate().find_map(|(k, child)| shown(child, leaf, p, solids).map(|on| (k, on)))?;
    if !on {
        return Some(false);
    }
    let mut others = children.iter().enumerate().filter(|(j, _)| *j != k).map(|(_, c)| c);
    Some(match op {
        CsgOp::Union => true,
        CsgOp::Merge => !others.any(|c| inside(c, p, solids)),
        CsgOp::Intersection => others.all(|c| inside(c, p, solids)),
        CsgOp::Difference if k == 0 => !others.any(|c| inside(c, p, solids)),
        CsgOp::Difference => {
            inside(&children[0], p, solids)
                && !children.iter().enumerate().skip(1).any(|(j, c)| j != k && inside(c, p, solids))
        }
    })
}

/// Whether `p` is inside `node`'s solid.
fn inside(node: &CsgNode, p: Vec3, solids: &[Solid]) -> bool {
    match node {
        CsgNode::Leaf(l) => solids[*l as usize].contains(p),
        CsgNode::Op(op, children) => {
            let mut each = children.iter().map(|c| inside(c, p, solids));
            match op {
                CsgOp::Union | CsgOp::Merge => each.any(|x| x),
                CsgOp::Intersection => each.all(|x| x),
                CsgOp::Difference => {
                    let mut rest = children.iter().skip(1);
                    inside(&children[0], p, solids) && !rest.any(|c| inside(c, p, solids))
                }
            }
        }
    }
}

/// A closed leaf as triangles and their bounds: a point is inside when a ray from it crosses
/// the triangles an odd number of times.
struct Solid {
    triangles: Vec<[Vec3; 3]>,
    lo: Vec3,
    hi: Vec3,
}

impl Solid {
    fn new<'a>(parts: impl Iterator<Item = &'a [f32]>) -> Solid {
        let mut triangles = Vec::new();
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for positions in parts {
            for t in positions.chunks_exact(9) {
                let v = [Vec3::from_slice(&t[0..3]), Vec3::from_slice(&t[3..6]), Vec3::from_slice(&t[6..9])];
                for p in v {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                triangles.push(v);
            }
        }
        Solid { triangles, lo, hi }
    }

    fn contains(&self, p: Vec3) -> bool {
        if p.cmplt(self.lo).any() || p.cmpgt(self.hi).any() {
            return false;
        }
        // A direction along no axis or diagonal, so the ray rarely grazes a tessellation's edge.
        let d = Vec3::new(0.5381, 0.6197, 0.5713).normalize();
        let mut crossings = 0;
        for [a, b, c] in &self.triangles {
            let (e1, e2) = (*b - *a, *c - *a);
            let q = d.cross(e2);
            let det = e1.dot(q);
            if det.abs() < 1e-12 {
                continue;
            }
            let s = p - *a;
            let u = s.dot(q) / det;
            let r = s.cross(e1);
            let v = d.dot(r) / det;
            if u < 0.0 || v < 0.0 || u + v > 1.0 {
                continue;
            }
            if e2.dot(r) / det > 0.0 {
                crossings += 1;
            }
        }
        crossings % 2 == 1
    }
}
