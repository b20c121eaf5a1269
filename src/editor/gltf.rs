//! The scene's geometry as glTF 2.0 binary (`.glb`): what `photonix export` writes and the
//! editor's *Download glTF* serves, from one writer.
//!
//! One node per `[[shapes]]` entry and per area light of the file, named as the entry is, with
//! the same world-space triangles the editor's solid view draws (`geometry::triangles`: analytic
//! shapes tessellated, an infinite plane as a square as large as the scene, a CSG object's
//! surface); one primitive per material an entry uses. Vertices are in world space (these
//! nodes carry no transform) and come without normals, so viewers shade the facets flat, as
//! glTF specifies. Instancing stays instancing: each `[objects.NAME]` becomes one mesh in object
//! space (one per replacing `material` its instances give), each `[[instances]]` entry a node
//! named as the entry with one child node per copy it places (grid cells and nested placements
//! resolved), whose `matrix` is the copy's `world_from_object`. Materials keep the
//! constant part of their colour (textures are not exported), a metal's or mirror's reflectance
//! at normal incidence, roughness (the square root of the GGX width), emission (with
//! `KHR_materials_emissive_strength` above 1), and for glass `KHR_materials_transmission` and
//! `KHR_materials_ior`. The scene's camera becomes a perspective camera node. Point, spot and
//! distant lights, media and the environment are not geometry and are left out.

use std::collections::BTreeMap;

use glam::{Mat3, Quat, Vec3};
use serde_json::{json, Value as Json};
use toml_edit::{DocumentMut, Item};

use super::document::SceneDocument;
use super::geometry::{finite_bounds, object_parts, shape_parts, Parts};
use crate::scene::{MaterialDesc, MaterialKind, Projection, Scene};

const GLB_MAGIC: u32 = 0x4654_6c67; // "glTF"
const CHUNK_JSON: u32 = 0x4e4f_534a; // "JSON"
const CHUNK_BIN: u32 = 0x004e_4942; // "BIN\0"
const FLOAT: u32 = 5126;
const ARRAY_BUFFER: u32 = 34962;

/// The `.glb` bytes of `doc`'s scene; an error when they would pass the format's 4 GiB.
pub fn scene_glb(doc: &SceneDocument) -> Result<Vec<u8>, String> {
    let scene = doc.scene();
    let origins = doc.origins();
    let parsed: DocumentMut = doc.text().parse().unwrap_or_default();
    let names = |key: &str, what: &str| -> Vec<String> {
        let tables = parsed.get(key).and_then(Item::as_array_of_tables);
        let count = tables.map_or(0, |t| t.len());
        (0..count)
            .map(|i| {
                tables
                    .and_then(|t| t.get(i))
                    .and_then(|t| t.get("name"))
                    .and_then(Item::as_str)
                    .map_or_else(|| format!("{what} {}", i + 1), str::to_string)
            })
            .collect()
    };
    let mut entries: Vec<(String, std::ops::Range<usize>)> =
        names("shapes", "shape").into_iter().zip(origins.shapes.iter().cloned()).collect();
    entries.extend(
        names("lights", "light").into_iter().zip(origins.lights.iter().cloned()).filter(|(_, r)| !r.is_empty()),
    );
    let instances: Vec<(String, std::ops::Range<usize>)> =
        names("instances", "instance").into_iter().zip(origins.instances.iter().cloned()).collect();
    write_glb(scene, &entries, &instances)
}

/// The binary buffer with its views, accessors and meshes, and the materials in order of first use.
#[derive(Default)]
struct Writer {
    bin: Vec<u8>,
    views: Vec<Json>,
    accessors: Vec<Json>,
    meshes: Vec<Json>,
    /// Scene material id -> glTF material index.
    used: BTreeMap<u32, usize>,
    order: Vec<u32>,
}

impl Writer {
    /// Adds a mesh named `name` with one primitive per material of `parts`; its index, or
    /// `None` when it has no triangles.
    fn mesh(&mut self, name: &str, parts: Parts) -> Option<usize> {
        let mut primitives = Vec::new();
        for (material, positions) in parts.into_iter().filter(|(_, p)| !p.is_empty()) {
            let next = self.order.len();
            let index = *self.used.entry(material).or_insert(next);
            if index == next {
                self.order.push(material);
            }
            let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for v in positions.chunks_exact(3) {
                min = min.min(Vec3::from_slice(v));
                max = max.max(Vec3::from_slice(v));
            }
            let offset = self.bin.len();
            self.bin.extend(positions.iter().flat_map(|x| x.to_le_bytes()));
            self.views.push(
                json!({ "buffer": 0, "byteOffset": offset, "byteLength": positions.len() * 4, "target": ARRAY_BUFFER }),
            );
            self.accessors.push(json!({
                "bufferView": self.views.len() - 1, "componentType": FLOAT, "type": "VEC3",
                "count": positions.len() / 3, "min": min.to_array(), "max": max.to_array(),
            }));
            primitives.push(json!({ "attributes": { "POSITION": self.accessors.len() - 1 }, "material": index }));
        }
        if primitives.is_empty() {
            return None;
        }
        self.meshes.push(json!({ "name": name, "primitives": primitives }));
        Some(self.meshes.len() - 1)
    }
}

/// Builds the glTF document and its binary buffer for the shapes of `entries` (a name and the
/// range of `scene.shapes` it became) and the placements of `instances` (a name and the range
/// of `scene.instances`).
fn write_glb(
    scene: &Scene,
    entries: &[(String, std::ops::Range<usize>)],
    instances: &[(String, std::ops::Range<usize>)],
) -> Result<Vec<u8>, String> {
    let (lo, hi) = finite_bounds(scene);
    let extent = (hi - lo).length().max(1e-3);
    let mut w = Writer::default();
    let mut nodes = Vec::new();
    for (name, range) in entries {
        let mut parts = Parts::new();
        for shape in scene.shapes.get(range.clone()).unwrap_or(&[]) {
            shape_parts(shape, lo, hi, extent, &mut parts);
        }
        if let Some(mesh) = w.mesh(name, parts) {
            nodes.push(json!({ "name": name, "mesh": mesh }));
        }
    }
    // One mesh per object and replacing material, made when a copy first needs it.
    let mut object_meshes: BTreeMap<(u32, Option<u32>), Option<usize>> = BTreeMap::new();
    let mut children_nodes = Vec::new();
    let mut roots: Vec<usize> = (0..nodes.len()).collect();
    for (name, range) in instances {
        let mut children = Vec::new();
        for (k, copy) in scene.instances.get(range.clone()).unwrap_or(&[]).iter().enumerate() {
            let mesh = *object_meshes.entry((copy.object, copy.material)).or_insert_with(|| {
                let object = &scene.objects[copy.object as usize];
                let mut parts = object_parts(object);
                if let Some(m) = copy.material {
                    let all: Vec<f32> = std::mem::take(&mut parts).into_values().flatten().collect();
                    parts.insert(m, all);
                }
                let mesh_name = match copy.material {
                    Some(m) => format!("{} ({})", object.name, scene.material_names[m as usize]),
                    None => object.name.clone(),
                };
                w.mesh(&mesh_name, parts)
            });
            let Some(mesh) = mesh else { continue };
            let matrix = glam::Mat4::from(copy.world_from_object).to_cols_array();
            children.push(children_nodes.len());
            children_nodes.push(json!({ "name": format!("{name} {k}"), "mesh": mesh, "matrix": matrix }));
        }
        if !children.is_empty() {
            roots.push(nodes.len());
            nodes.push(json!({ "name": name, "children": children }));
        }
    }
    // The copies' nodes follow the entries' and the instances' own.
    let first_child = nodes.len();
    for node in nodes.iter_mut() {
        if let Some(children) = node.get_mut("children").and_then(Json::as_array_mut) {
            for c in children.iter_mut() {
                *c = json!(first_child + c.as_u64().expect("child indices are numbers") as usize);
            }
        }
    }
    nodes.extend(children_nodes);
    let Writer { bin, views, accessors, meshes, order, .. } = w;
    let materials: Vec<Json> = order.iter().map(|&m| material_json(scene, m as usize)).collect();
    let mut cameras = Vec::new();
    if let Some((camera, node)) = camera_json(scene) {
        cameras.push(camera);
        roots.push(nodes.len());
        nodes.push(node);
    }
    let mut root = json!({
        "asset": { "version": "2.0", "generator": concat!("Photonix ", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [{ "name": scene.name, "nodes": roots }],
        "nodes": nodes,
    });
    let extensions: Vec<&str> = ["KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior"]
        .into_iter()
        .filter(|e| materials.iter().any(|m| m["extensions"].get(*e).is_some()))
        .collect();
    for (key, value) in [
        ("meshes", json!(meshes)),
        ("materials", json!(materials)),
        ("accessors", json!(accessors)),
        ("bufferViews", json!(views)),
        ("cameras", json!(cameras)),
        ("extensionsUsed", json!(extensions)),
    ] {
        if value.as_array().is_some_and(|a| !a.is_empty()) {
            root[key] = value;
        }
    }
    if !bin.is_empty() {
        root["buffers"] = json!([{ "byteLength": bin.len() }]);
    }
    glb(&root, bin)
}

/// A glTF material for scene material `id`.
fn material_json(scene: &Scene, id: usize) -> Json {
    let name = scene.material_names.get(id).cloned().unwrap_or_else(|| format!("material {id}"));
    let Some(m) = scene.materials.get(id) else { return json!({ "name": name }) };
    let (color, metallic, roughness) = surface(scene, m, 0);
    let opacity = m.opacity.value.clamp(0.0, 1.0);
    let mut out = json!({
        "name": name,
        "doubleSided": true,
        "pbrMetallicRoughness": {
            "baseColorFactor": [color.x, color.y, color.z, opacity],
            "metallicFactor": metallic,
            "roughnessFactor": roughness,
        },
    });
    if opacity < 1.0 {
        out["alphaMode"] = json!("BLEND");
    }
    let mut extensions = serde_json::Map::new();
    let emission = m.emission.value;
    let peak = emission.max_element();
    if peak > 0.0 {
        // glTF's emissive factor is at most 1; a stronger emitter keeps its radiance in the
        // strength extension.
        out["emissiveFactor"] = json!((emission / peak.max(1.0)).to_array());
        if peak > 1.0 {
            extensions.insert("KHR_materials_emissive_strength".into(), json!({ "emissiveStrength": peak }));
        }
    }
    if let MaterialKind::Dielectric { ior, .. } | MaterialKind::ThinDielectric { ior } = m.kind {
        extensions.insert("KHR_materials_transmission".into(), json!({ "transmissionFactor": 1.0 }));
        extensions.insert("KHR_materials_ior".into(), json!({ "ior": ior }));
    }
    if !extensions.is_empty() {
        out["extensions"] = Json::Object(extensions);
    }
    out
}

/// Base colour, metallic and roughness factors of `m` (a mix: its first material).
fn surface(scene: &Scene, m: &MaterialDesc, depth: u32) -> (Vec3, f32, f32) {
    let perceptual = |alpha: [f32; 2]| ((alpha[0] + alpha[1]) * 0.5).max(0.0).sqrt().min(1.0);
    match &m.kind {
        MaterialKind::Diffuse { reflectance } => (reflectance.value, 0.0, 1.0),
        MaterialKind::Plastic { reflectance, roughness, .. } => (reflectance.value, 0.0, perceptual(roughness.alpha)),
        MaterialKind::Mirror { tint } => (tint.value, 1.0, 0.0),
        MaterialKind::Dielectric { roughness, .. } => (Vec3::ONE, 0.0, perceptual(roughness.alpha)),
        MaterialKind::ThinDielectric { .. } => (Vec3::ONE, 0.0, 0.0),
        MaterialKind::Conductor { eta, k, roughness, .. } => {
            // Reflectance at normal incidence of the complex index eta + i k, per channel.
            let (n, k) = (eta.value, k.value);
            let f0 = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
            (f0.clamp(Vec3::ZERO, Vec3::ONE), 1.0, perceptual(roughness.alpha))
        }
        MaterialKind::Mix { a, .. } => match scene.materials.get(*a as usize) {
            Some(first) if depth < 8 => surface(scene, first, depth + 1),
            _ => (Vec3::splat(0.8), 0.0, 1.0),
        },
        MaterialKind::Null => (Vec3::ONE, 0.0, 1.0),
    }
}

/// The scene's camera as a glTF perspective camera and its node (other projections have no
/// glTF counterpart).
fn camera_json(scene: &Scene) -> Option<(Json, Json)> {
    let c = &scene.camera;
    if !matches!(c.projection, Projection::Perspective) {
        return None;
    }
    let forward = (c.look_at - c.position).try_normalize()?;
    let right = forward.cross(c.up).try_normalize()?;
    let up = right.cross(forward);
    // A glTF camera looks down its -z with +y up.
    let rotation = Quat::from_mat3(&Mat3::from_cols(right, up, -forward)).normalize();
    let camera = json!({
        "name": "camera",
        "type": "perspective",
        "perspective": {
            "yfov": c.fov_deg.to_radians(),
            "aspectRatio": c.width as f32 / c.height.max(1) as f32,
            "znear": 1e-3,
        },
    });
    let node =
        json!({ "name": "camera", "camera": 0, "translation": c.position.to_array(), "rotation": rotation.to_array() });
    Some((camera, node))
}

/// The GLB container: a 12-byte header, the JSON chunk (padded with spaces) and the binary
/// chunk (padded with zeros), each 4-byte aligned.
fn glb(root: &Json, mut bin: Vec<u8>) -> Result<Vec<u8>, String> {
    let mut text = serde_json::to_vec(root).expect("JSON values always serialize");
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + text.len() + bin_chunk;
    if total > u32::MAX as usize {
        return Err(format!(
            "the scene's triangles make a {} MiB glTF binary, more than the format's 4 GiB",
            total >> 20
        ));
    }
    let mut out = Vec::with_capacity(total);
    for word in [GLB_MAGIC, 2, total as u32, text.len() as u32, CHUNK_JSON] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&text);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(&bin);
    }
    Ok(out)
}
