//! The scene as the page sees it: one JSON object with every entry of the file (its fields as
//! written, for the properties panel) and its geometry as world-space triangles (for the solid
//! viewport and for picking). Format (documented in docs/editor.md):
//!
//! ```text
//! { "revision", "file", "dirty", "can_undo", "can_redo", "warnings": [..],
//!   "bounds": { "min": [x,y,z], "max": [x,y,z] },
//!   "camera": { "fields": {..}, "position", "look_at", "up", "fov", "width", "height", "projection", "view_height" },
//!   "render": {..}, "photons": {..} | null, "environment": {..} | null,
//!   "materials": [ { "name", "fields": {..}, "color": [r,g,b], "emission": [r,g,b] } ],
//!   "shapes": [ { "fields": {..}, "color", "emissive", "positions": [x,y,z, ...] } ],
//!   "lights": [ { "fields": {..}, "kind", "positions": [..], "position": [..]?, "direction": [..]? } ] }
//! ```
//! `positions` lists three vertices per triangle; analytic shapes (spheres, discs, cones, tori,
//! superellipsoids) come tessellated, an infinite plane as a square as large as the scene.

use glam::{Mat3, Vec3};
use serde_json::{json, Value as Json};
use toml_edit::{DocumentMut, Item};

use super::document::{toml_to_json, SceneDocument};
use crate::scene::{AnalyticKind, Geometry, LightKind, MaterialKind, Projection, Scene};

/// Segments around a tessellated analytic shape in the solid view.
const SEGMENTS: usize = 32;

/// The page's view of `doc`.
pub fn scene_json(doc: &SceneDocument) -> Json {
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
            json!({ "fields": fields, "color": color, "emissive": emissive, "positions": positions(range) })
        })
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

    let camera = &scene.camera;
    let (projection, view_height) = match camera.projection {
        Projection::Perspective => ("perspective", None),
        Projection::Orthographic { view_height } => ("orthographic", Some(view_height)),
        Projection::LatLong => ("latlong", None),
    };
    let table = |key: &str| parsed.get(key).map_or(Json::Null, toml_to_json);
    json!({
        "revision": doc.revision(),
        "file": doc.path().file_name().map(|n| n.to_string_lossy().into_owned()),
        "dirty": doc.dirty(),
        "can_undo": doc.can_undo(),
        "can_redo": doc.can_redo(),
        "warnings": scene.warnings,
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
    })
}

/// The bounds of every shape but the infinite planes; a unit box when there are none.
pub fn finite_bounds(scene: &Scene) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for shape in scene.shapes.iter().filter(|s| !s.geometry.is_unbounded()) {
        let (a, b) = shape.geometry.bounds();
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
        MaterialKind::Dielectric { .. } => Vec3::new(0.75, 0.85, 0.95),
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
        // Every leaf whole: the preview shows the parts a CSG object is made of.
        Geometry::Csg(c) => {
            for shape in c.leaves.iter().flatten() {
                triangles(&shape.geometry, lo, hi, extent, out);
            }
        }
    }
}
