//! Model files: what every importer (OBJ with MTL, PLY, glTF 2.0, 3DS, IFS, Bezier patches)
//! turns its file into, and the host-side geometry shared by all of them: triangulation, smooth
//! vertex normals with an angle threshold, subdivision surfaces. The scene converter
//! (`convert.rs`) maps a `Model` onto the scene's triangles, materials, textures and lights.
//!
//! Every importer reads the whole file first (at most `limits::MAX_MODEL_FILE_BYTES`), checks
//! every count, index and number against what the file holds, and returns a `ModelError` naming
//! the file, where in it (line or byte offset) and what is wrong; nothing is kept from a file
//! that fails.

pub mod gltf;
pub mod ifs;
pub mod normals;
pub mod obj;
pub mod patch;
pub mod ply;
pub mod serialized;
pub mod subdivide;
pub mod tds;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};

use super::image_texture::{ImageTexture, Wrap};
use crate::limits::{fmt_number, MAX_SCENE_VALUE};

/// A polygon mesh in model space: positions shared by index, and per-corner (face-varying)
/// normals and uvs, as OBJ writes them; formats with per-vertex attributes spread them to the
/// corners. Faces are polygons of 3 or more corners (`face_offsets` delimit them in
/// `corners`), kept as polygons for subdivision and fanned into triangles afterwards.
#[derive(Clone, Debug, Default)]
pub struct ModelMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Index into `positions` of every corner of every face.
    pub corners: Vec<u32>,
    /// Face f has corners `face_offsets[f] .. face_offsets[f + 1]`; starts with 0.
    pub face_offsets: Vec<u32>,
    /// One per corner, when the file has normals (not necessarily unit length).
    pub normals: Option<Vec<Vec3>>,
    /// One per corner, when the file has texture coordinates.
    pub uvs: Option<Vec<Vec2>>,
    /// Material of each face: an index into `Model::materials`, or `None` (the scene's default).
    pub face_materials: Vec<Option<u32>>,
    /// 3DS smoothing groups, one bit mask per face: faces share normals at a vertex only when
    /// their masks share a bit (0: flat). `None`: the angle threshold decides.
    pub smoothing_groups: Option<Vec<u32>>,
    /// Where the mesh sits in the model (glTF node transforms); the identity elsewhere.
    pub model_from_mesh: Affine3A,
}

impl ModelMesh {
    pub fn face_count(&self) -> usize {
        self.face_offsets.len().saturating_sub(1)
    }

    /// Corner indices (into `corners`) of face `f`.
    pub fn face(&self, f: usize) -> std::ops::Range<usize> {
        self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize
    }

    /// Appends a face of corners `positions` (indices into `positions`), with its material.
    pub fn push_face(&mut self, positions: &[u32], material: Option<u32>) {
        if self.face_offsets.is_empty() {
            self.face_offsets.push(0);
        }
        self.corners.extend_from_slice(positions);
        self.face_offsets.push(self.corners.len() as u32);
        self.face_materials.push(material);
    }
}

/// An image a model's material refers to, decoded (colours from sRGB, data linear).
#[derive(Clone, Debug)]
pub struct ModelImage {
    pub image: Arc<ImageTexture>,
    pub wrap: Wrap,
}

/// A model's material in the terms the formats share; `convert.rs` maps it onto the scene's
/// material kinds (see docs/scene-format.md, "Materials of imported models").
#[derive(Clone, Debug)]
pub struct ModelMaterial {
    pub name: String,
    /// Diffuse colour (OBJ `Kd`, 3DS diffuse) or glTF base colour, linear.
    pub base_color: Vec3,
    pub base_color_texture: Option<ModelImage>,
    /// glTF `metallicFactor`; OBJ and 3DS: 0.
    pub metallic: f32,
    /// GGX alpha of the specular lobe (glTF roughness squared; OBJ `Ns` through Walter et al.'s
    /// Phong-to-Beckmann width); `None`: no specular lobe (a diffuse material).
    pub roughness: Option<f32>,
    /// glTF metallic-roughness texture: metallic in blue, roughness in green (linear).
    pub metallic_roughness_texture: Option<ModelImage>,
    /// Opacity in [0, 1] (OBJ `d`, 3DS 1 - transparency, glTF base colour alpha when blended).
    pub opacity: f32,
    /// Opacity from the alpha channel of the base colour texture (glTF `BLEND`/`MASK`).
    pub opacity_from_texture_alpha: bool,
    /// Emitted radiance, linear (OBJ `Ke`, glTF `emissiveFactor`).
    pub emission: Vec3,
    pub emission_texture: Option<ModelImage>,
    /// Tangent-space normal map (glTF), linear.
    pub normal_texture: Option<ModelImage>,
    /// Bump map (OBJ `bump`/`map_bump`) and its height scale in model units (`-bm`).
    pub bump_texture: Option<(ModelImage, f32)>,
    /// Index of refraction of the specular coat (OBJ `Ni`, glTF KHR_materials_ior), default 1.5.
    pub ior: f32,
    /// glTF KHR_materials_transmission's factor in [0, 1]: the share of light that passes through
    /// the surface (a dielectric's refraction); 0 elsewhere.
    pub transmission: f32,
    /// glTF KHR_materials_volume's attenuation: the colour light keeps after travelling the
    /// distance (model units) inside; `None`: clear.
    pub attenuation: Option<(Vec3, f32)>,
}

impl ModelMaterial {
    pub fn new(name: &str) -> ModelMaterial {
        ModelMaterial {
            name: name.to_string(),
            base_color: Vec3::splat(0.8),
            base_color_texture: None,
            metallic: 0.0,
            roughness: None,
            metallic_roughness_texture: None,
            opacity: 1.0,
            opacity_from_texture_alpha: false,
            emission: Vec3::ZERO,
            emission_texture: None,
            normal_texture: None,
            bump_texture: None,
            ior: 1.5,
            transmission: 0.0,
            attenuation: None,
        }
    }
}

/// A camera of the model (glTF), in model space.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelCamera {
    pub name: String,
    pub position: Vec3,
    /// Unit view direction and up vector.
    pub forward: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees (perspective), or the view height (orthographic).
    pub projection: ModelProjection,
    /// Width over height, when the file gives it.
    pub aspect: Option<f32>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModelProjection {
    Perspective { yfov_deg: f32 },
    Orthographic { view_height: f32 },
}

/// A light of the model (glTF KHR_lights_punctual), in model space. Intensities are the file's
/// (candela for point and spot lights, lux for directional ones), read as W/sr and W/m^2.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelLight {
    Point { position: Vec3, intensity: Vec3 },
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, inner_deg: f32, outer_deg: f32 },
    Directional { direction: Vec3, irradiance: Vec3 },
}

/// Everything a model file holds that the scene can use.
#[derive(Clone, Debug, Default)]
pub struct Model {
    pub meshes: Vec<ModelMesh>,
    pub materials: Vec<ModelMaterial>,
    pub cameras: Vec<ModelCamera>,
    pub lights: Vec<ModelLight>,
    /// The name of each light's node (glTF), same index as `lights`; empty when it has none.
    pub light_names: Vec<String>,
    /// Problems that do not stop the import (e.g. a missing MTL file), for `Scene::warnings`.
    pub warnings: Vec<String>,
}

/// Why a model file could not be used. `Display` names the file, where in it and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelError {
    pub path: PathBuf,
    /// "line 12", "byte 4096", "mesh 2 (\"wheel\")", or empty when the whole file is concerned.
    pub at: String,
    pub message: String,
    /// True when the file itself does not exist.
    pub not_found: bool,
}

impl ModelError {
    /// The message as users read it, whatever bytes the file held: control characters escaped
    /// and numbers of more than 15 digits (a garbage float or count) in short form.
    pub fn new(path: &Path, at: impl Into<String>, message: impl Into<String>) -> ModelError {
        let message = crate::limits::printable_message(&crate::limits::shorten_numbers(&message.into()));
        let at = crate::limits::printable_message(&at.into());
        ModelError { path: path.to_path_buf(), at, message, not_found: false }
    }

    /// `path:at` as messages show it (`at` left out when empty).
    pub fn location(&self) -> String {
        let path = crate::limits::printable_message(&self.path.display().to_string());
        match self.at.strip_prefix("line ") {
            _ if self.at.is_empty() => path,
            // `file:line`, as compilers and editors read it.
            Some(line) => format!("{path}:{line}"),
            None => format!("{path}: {}", self.at),
        }
    }
}

impl std::fmt::Display for ModelError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.location(), self.message)
    }
}

impl std::error::Error for ModelError {}

/// The model formats, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Obj,
    Ply,
    Gltf,
    Tds,
    Ifs,
    /// Bicubic Bezier patches in the `.bpt` text format (the Utah teapot's).
    Patches,
    /// Mitsuba's `.serialized` meshes.
    Serialized,
}

impl Format {
    pub const EXTENSIONS: &'static str = ".obj, .ply, .gltf, .glb, .3ds, .ifs, .bpt or .serialized";

    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "obj" => Format::Obj,
            "ply" => Format::Ply,
            "gltf" | "glb" => Format::Gltf,
            "3ds" => Format::Tds,
            "ifs" => Format::Ifs,
            "bpt" => Format::Patches,
            "serialized" => Format::Serialized,
            _ => return None,
        })
    }
}

/// How a model's patches are tessellated (only `.bpt` files have patches).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    /// Largest distance, in model units, between a Bezier patch and its triangles.
    pub flatness: f32,
}

impl Default for LoadOptions {
    fn default() -> LoadOptions {
        LoadOptions { flatness: 0.01 }
    }
}

/// Reads a model file of any supported format (by its extension).
pub fn load_model(path: &Path, options: &LoadOptions) -> Result<Model, ModelError> {
    let Some(format) = Format::from_path(path) else {
        return Err(ModelError::new(
            path,
            "",
            format!("unknown model format; the file name must end in {}", Format::EXTENSIONS),
        ));
    };
    let bytes = read_model_file(path)?;
    let model = match format {
        Format::Obj => obj::parse_obj(&bytes, path)?,
        Format::Ply => ply::parse_ply(&bytes, path)?,
        Format::Gltf => gltf::parse_gltf(&bytes, path)?,
        Format::Tds => tds::parse_3ds(&bytes, path)?,
        Format::Ifs => ifs::parse_ifs(&bytes, path)?,
        Format::Patches => patch::parse_bpt(&bytes, path, options.flatness)?,
        Format::Serialized => serialized::parse_serialized(&bytes, path)?,
    };
    check_model(&model, path)?;
    Ok(model)
}

/// The bytes of a model file, at most `MAX_MODEL_FILE_BYTES`.
pub fn read_model_file(path: &Path) -> Result<Vec<u8>, ModelError> {
    let limit = crate::limits::MAX_MODEL_FILE_BYTES;
    crate::scene::files::read(path, limit).map_err(|e| match e {
        e if e.not_found() => ModelError { not_found: true, ..ModelError::new(path, "", "file not found") },
        crate::scene::files::FileError::Io(e) => ModelError::new(path, "", format!("cannot read the file: {e}")),
        e => ModelError::new(path, "", e.to_string()),
    })
}

/// A finite number within the scene range, or a message saying what `what` holds instead.
pub fn check_number(v: f64, what: &str) -> Result<(), String> {
    if !v.is_finite() {
        return Err(format!("{what} is {v}, not a finite number"));
    }
    if v.abs() > MAX_SCENE_VALUE {
        return Err(format!(
            "{what} is {}, beyond the largest scene coordinate, +-{MAX_SCENE_VALUE:e} (see docs/limits.md)",
            fmt_number(v)
        ));
    }
    Ok(())
}

/// Checks what every importer must guarantee: indices in range, finite numbers within the scene
/// range, at least one face. Importers check as they read; this catches what slips past.
fn check_model(model: &Model, path: &Path) -> Result<(), ModelError> {
    let mut faces = 0;
    for (m, mesh) in model.meshes.iter().enumerate() {
        let at = || format!("mesh {m} (\"{}\")", crate::limits::printable(&mesh.name));
        for p in &mesh.positions {
            for c in p.to_array() {
                check_number(c as f64, "a vertex coordinate").map_err(|e| ModelError::new(path, at(), e))?;
            }
        }
        if let Some(&bad) = mesh.corners.iter().find(|&&i| i as usize >= mesh.positions.len()) {
            return Err(ModelError::new(
                path,
                at(),
                format!("a face refers to vertex {bad}, but the mesh has {} vertices", mesh.positions.len()),
            ));
        }
        let corners = mesh.corners.len();
        if mesh.normals.as_ref().is_some_and(|n| n.len() != corners)
            || mesh.uvs.as_ref().is_some_and(|u| u.len() != corners)
            || mesh.face_materials.len() != mesh.face_count()
        {
            return Err(ModelError::new(path, at(), "per-corner data does not match the faces"));
        }
        if let Some(n) = &mesh.normals {
            if n.iter().any(|n| !n.is_finite()) {
                return Err(ModelError::new(path, at(), "a normal is not finite"));
            }
        }
        if let Some(uv) = &mesh.uvs {
            if uv.iter().any(|u| !u.is_finite()) {
                return Err(ModelError::new(path, at(), "a texture coordinate is not finite"));
            }
        }
        faces += mesh.face_count();
    }
    if faces == 0 {
        return Err(ModelError::new(path, "", "the file has no faces (polygons of 3 or more vertices)"));
    }
    Ok(())
}

/// A triangle of a model, in model space, ready for the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelTriangle {
    pub vertices: [Vec3; 3],
    pub uv: Option<[Vec2; 3]>,
    /// Unit vertex normals for smooth shading; `None` for a flat triangle.
    pub normals: Option<[Vec3; 3]>,
    pub material: Option<u32>,
}

/// How a mesh's triangles get their shading normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Use the file's normals where it has them.
    pub file_normals: bool,
    /// Where normals are computed: faces whose normals differ by at most this (degrees) share
    /// a vertex normal; 0 keeps every face flat.
    pub smooth_angle_deg: f32,
}

/// The mesh's faces cut into triangles (`triangulate_polygon`, keeping their winding) in model space, with smooth
/// normals per `shading` (file normals, else computed, see `normals.rs`). A triangle whose
/// three normals equal its face normal is flat (`normals: None`): it costs the kernels nothing.
pub fn mesh_triangles(mesh: &ModelMesh, shading: Shading) -> Vec<ModelTriangle> {
    let corner_normals = match (&mesh.normals, shading.file_normals) {
        (Some(n), true) => Some(n.iter().map(|n| n.normalize_or_zero()).collect::<Vec<_>>()),
        _ if shading.smooth_angle_deg > 0.0 => Some(normals::corner_normals(mesh, shading.smooth_angle_deg)),
        _ => None,
    };
    let transform = mesh.model_from_mesh;
    let normal_matrix = transform.matrix3.inverse().transpose();
    let mirrored = transform.matrix3.determinant() < 0.0;
    let mut out = Vec::with_capacity(mesh.corners.len());
    let mut polygon = Vec::new();
    let mut triangles = Vec::new();
    for f in 0..mesh.face_count() {
        let range = mesh.face(f);
        polygon.clear();
        polygon.extend(range.clone().map(|c| mesh.positions[mesh.corners[c] as usize]));
        triangulate_polygon(&polygon, &mut triangles);
        for &[a, b, c] in &triangles {
            let mut c = [range.start + a, range.start + b, range.start + c];
            if mirrored {
                c.swap(1, 2);
            }
            let vertices = c.map(|c| transform.transform_point3(mesh.positions[mesh.corners[c] as usize]));
            let uv = mesh.uvs.as_ref().map(|uv| c.map(|c| uv[c]));
            let face_normal = (vertices[1] - vertices[0]).cross(vertices[2] - vertices[0]).normalize_or_zero();
            let normals = corner_normals.as_ref().and_then(|n| {
                let mut ns = c.map(|c| (normal_matrix * Vec3A::from(n[c])).normalize_or_zero().into());
                smooth_normals(&mut ns, face_normal).then_some(ns)
            });
            out.push(ModelTriangle { vertices, uv, normals, material: mesh.face_materials[f] });
        }
    }
    out
}

use glam::Vec3A;

/// Most corners of a polygon that is ear-clipped; a larger concave one is fanned (clipping
/// costs O(n^2) per polygon, and such faces come from damaged files, not modellers).
const MAX_EAR_CLIPPED_CORNERS: usize = 4096;

/// Triangles (corner indices into `polygon`, in its winding) covering the planar polygon
/// `polygon`: a fan from corner 0 when it is convex (as before, so convex faces triangulate as
/// they always did), else ear clipping (Eberly, "Triangulation by Ear Clipping", 2002) in the
/// plane of its Newell normal. A ring drawn as one face (outer loop, a bridge edge, inner loop
/// backwards) is clipped around its hole: a corner sitting on an ear's own corners (the two ends
/// of the bridge) does not block it.
pub fn triangulate_polygon(polygon: &[Vec3], out: &mut Vec<[usize; 3]>) {
    out.clear();
    let n = polygon.len();
    let fan = |out: &mut Vec<[usize; 3]>| out.extend((1..n.saturating_sub(1)).map(|k| [0, k, k + 1]));
    if n <= 3 {
        fan(out);
        return;
    }
    // Newell's normal: robust for non-planar and concave polygons.
    let mut normal = Vec3::ZERO;
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        normal += Vec3::new((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    }
    let Some(normal) = normal.try_normalize() else {
        fan(out);
        return;
    };
    // A right-handed frame (u, v, normal): the polygon winds counter-clockwise in (u, v).
    let u = normal.any_orthonormal_vector();
    let v = normal.cross(u);
    let p: Vec<Vec2> = polygon.iter().map(|q| Vec2::new(q.dot(u), q.dot(v))).collect();
    let cross = |a: Vec2, b: Vec2, c: Vec2| (b - a).perp_dot(c - a);
    let convex = (0..n).all(|i| cross(p[(i + n - 1) % n], p[i], p[(i + 1) % n]) >= 0.0);
    if convex || n > MAX_EAR_CLIPPED_CORNERS {
        fan(out);
        return;
    }
    let mut ring: Vec<usize> = (0..n).collect();
    while ring.len() > 3 {
        let m = ring.len();
        let ear = (0..m).find(|&i| {
            let (a, b, c) = (ring[(i + m - 1) % m], ring[i], ring[(i + 1) % m]);
            if cross(p[a], p[b], p[c]) <= 0.0 {
                return false; // reflex or flat: not an ear
            }
            // No other corner inside or on the triangle, except copies of its own corners.
            ring.iter().all(|&k| {
                let q = p[k];
                if k == a || k == b || k == c || q == p[a] || q == p[b] || q == p[c] {
                    return true;
                }
                !(cross(p[a], p[b], q) >= 0.0 && cross(p[b], p[c], q) >= 0.0 && cross(p[c], p[a], q) >= 0.0)
            })
        });
        if let Some(i) = ear {
            out.push([ring[(i + m - 1) % m], ring[i], ring[(i + 1) % m]]);
            ring.remove(i);
            continue;
        }
        // No ear: a corner on the line of its neighbours (the bridge of a ring, once its sides
        // are clipped) bounds no area; drop it without a zero-area triangle.
        let flat = (0..m).find(|&i| cross(p[ring[(i + m - 1) % m]], p[ring[i]], p[ring[(i + 1) % m]]) == 0.0);
        // Else a self-intersecting remainder: cut the first corner off as a fan would.
        let i = flat.unwrap_or(0);
        if flat.is_none() {
            out.push([ring[(i + m - 1) % m], ring[i], ring[(i + 1) % m]]);
        }
        ring.remove(i);
    }
    if cross(p[ring[0]], p[ring[1]], p[ring[2]]) != 0.0 {
        out.push([ring[0], ring[1], ring[2]]);
    }
}

/// Orients vertex normals `ns` to the side of the winding normal and says whether they make
/// the triangle smooth: false when they are missing (zero), or all equal the face normal (a flat
/// triangle draws the same without the cost).
pub fn smooth_normals(ns: &mut [Vec3; 3], face_normal: Vec3) -> bool {
    if face_normal == Vec3::ZERO || ns.iter().any(|n| *n == Vec3::ZERO || !n.is_finite()) {
        return false;
    }
    // Files whose normals point against their winding (mirrored exports) keep their shading:
    // the normals are turned to the winding side, where the kernels expect them.
    if (ns[0] + ns[1] + ns[2]).dot(face_normal) < 0.0 {
        for n in ns.iter_mut() {
            *n = -*n;
        }
    }
    ns.iter().any(|n| n.dot(face_normal) < 1.0 - 1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> ModelMesh {
        let mut mesh = ModelMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            model_from_mesh: Affine3A::IDENTITY,
            ..Default::default()
        };
        mesh.push_face(&[0, 1, 2, 3], None);
        mesh
    }

    #[test]
    fn polygon_fans_keep_winding_and_flat_faces_stay_flat() {
        let tris = mesh_triangles(&square(), Shading { file_normals: true, smooth_angle_deg: 30.0 });
        assert_eq!(tris.len(), 2);
        for t in &tris {
            let n = (t.vertices[1] - t.vertices[0]).cross(t.vertices[2] - t.vertices[0]);
            assert!(n.z > 0.0);
            assert_eq!(t.normals, None, "a planar face needs no smooth normals");
        }
    }

    /// Area of the triangles of `polygon`, each signed by its winding against +z.
    fn covered_area(polygon: &[Vec3]) -> f32 {
        let mut tris = Vec::new();
        triangulate_polygon(polygon, &mut tris);
        tris.iter().map(|&[a, b, c]| 0.5 * (polygon[b] - polygon[a]).cross(polygon[c] - polygon[a]).z).sum()
    }

    #[test]
    fn concave_faces_and_rings_are_clipped_not_fanned() {
        // An L of area 3: a fan from corner 0 would cover the notch and overlap itself.
        let l = [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)];
        let l: Vec<Vec3> = l.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect();
        // Start the fan at the reflex corner's neighbour to make fanning wrong.
        let rotated: Vec<Vec3> = l.iter().cycle().skip(4).take(6).copied().collect();
        assert!((covered_area(&rotated) - 3.0).abs() < 1e-5, "{}", covered_area(&rotated));
        // A square ring 4x4 with a 2x2 hole, as one face: outer loop counter-clockwise, a bridge to
        // the hole, the hole clockwise, and back along the bridge. Area 16 - 4 = 12.
        let ring = [(0., 0.), (4., 0.), (4., 4.), (0., 4.), (0., 0.), (1., 1.), (1., 3.), (3., 3.), (3., 1.), (1., 1.)];
        let ring: Vec<Vec3> = ring.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect();
        let mut tris = Vec::new();
        triangulate_polygon(&ring, &mut tris);
        let area = covered_area(&ring);
        assert!((area - 12.0).abs() < 1e-4, "ring covers {area}, not 12 (a fan fills the hole)");
        // No triangle covers the hole's centre.
        let centre = Vec3::new(2.0, 2.0, 0.0);
        for &[a, b, c] in &tris {
            let (a, b, c) = (ring[a], ring[b], ring[c]);
            let side = |p: Vec3, q: Vec3| (q - p).cross(centre - p).z;
            let inside = side(a, b) > 0.0 && side(b, c) > 0.0 && side(c, a) > 0.0;
            assert!(!inside, "triangle {a} {b} {c} covers the hole");
        }
        // Every triangle keeps the face's winding (front side +z).
        assert!(tris.iter().all(|&[a, b, c]| (ring[b] - ring[a]).cross(ring[c] - ring[a]).z >= 0.0));
        // A convex face is fanned from corner 0 exactly as before.
        let mut tris = Vec::new();
        triangulate_polygon(&square().positions, &mut tris);
        assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn normals_against_the_winding_are_turned_to_it() {
        let mut ns = [Vec3::new(0.1, 0.0, -1.0).normalize(), -Vec3::Z, -Vec3::Z];
        assert!(smooth_normals(&mut ns, Vec3::Z));
        assert!(ns.iter().all(|n| n.z > 0.0));
    }

    #[test]
    fn mirroring_transform_swaps_corners() {
        let mut mesh = square();
        mesh.model_from_mesh = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let tris = mesh_triangles(&mesh, Shading { file_normals: true, smooth_angle_deg: 0.0 });
        for t in &tris {
            let n = (t.vertices[1] - t.vertices[0]).cross(t.vertices[2] - t.vertices[0]);
            assert!(n.z > 0.0, "front face kept on the same side: {n}");
        }
    }
}
