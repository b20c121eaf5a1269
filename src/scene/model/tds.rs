//! Autodesk 3DS files, read by a small chunk parser of our own (no maintained crate reads them).
//! A chunk is a u16 id and a u32 length (its 6-byte header included), little-endian; the parser
//! descends into the chunks it knows and skips the others by their length:
//!
//! ```text
//! 4D4D main / 3D3D editor
//!   4000 object: name, then 4100 triangle mesh:
//!     4110 vertices (u16 n, n x 3 f32)   4140 uvs (u16 n, n x 2 f32)
//!     4160 local frame (4 x 3 f32)       4120 faces (u16 n, n x (3 u16 + u16 flags)), with
//!       4130 material of faces (name, u16 n, n x u16)   4150 smoothing groups (n x u32)
//!   AFFF material: A000 name, A020 diffuse, A030 specular colour, A040 shininess,
//!     A050 transparency (colour chunks 0010 f32 x 3 / 0011 u8 x 3, percentages 0030 u16 / 0031 f32),
//!     A200 texture map with A300 its file name
//! ```
//!
//! 3DS stores vertices already in world space (the 4160 frame only says where the object's own
//! axes were), so no transform is applied. 3DS is z-up; its coordinates (x, y, z) become
//! (x, z, -y) so the model stands upright in Photonix's y-up world. Smoothing groups decide the
//! vertex normals (faces share a normal where their groups share a bit).

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};

use super::ifs::Reader;
use super::{Model, ModelError, ModelImage, ModelMaterial, ModelMesh};
use crate::scene::image_texture::{load_image_texture, ColorSpace, Wrap};

/// Deepest chunk nesting read; real files nest about 5 deep.
const MAX_DEPTH: u32 = 16;

struct Parser<'a> {
    bytes: &'a [u8],
    path: &'a Path,
    model: Model,
    /// Per mesh: its material names per face, resolved once all materials are known.
    face_material_names: Vec<Vec<Option<String>>>,
}

type Fail = (usize, String);

/// The model of a 3DS file's bytes; `path` names it in messages and locates its textures.
pub fn parse_3ds(bytes: &[u8], path: &Path) -> Result<Model, ModelError> {
    let mut p = Parser { bytes, path, model: Model::default(), face_material_names: Vec::new() };
    let fail = |(at, message): Fail| ModelError::new(path, format!("byte {at}"), message);
    let mut r = Reader { bytes, at: 0 };
    let id = r.u16("the first chunk").map_err(fail)?;
    if id != 0x4D4D {
        return Err(ModelError::new(
            path,
            "byte 0",
            format!("the first chunk is {id:04X}, not 4D4D; this is not a 3DS file"),
        ));
    }
    let (start, end) = p.chunk_bounds(0, bytes.len()).map_err(fail)?;
    p.children(start, end, 0).map_err(fail)?;
    // Face materials by name
    let mut model = p.model;
    for (mesh, names) in model.meshes.iter_mut().zip(&p.face_material_names) {
        for (f, name) in names.iter().enumerate() {
            mesh.face_materials[f] =
                name.as_ref().and_then(|n| model.materials.iter().position(|m| &m.name == n)).map(|i| i as u32);
        }
    }
    model.meshes.retain(|m| m.face_count() > 0);
    Ok(model)
}

impl Parser<'_> {
    /// The body of the chunk at `at` (after its header), checked to lie inside `parent_end`.
    fn chunk_bounds(&self, at: usize, parent_end: usize) -> Result<(usize, usize), Fail> {
        let mut r = Reader { bytes: &self.bytes[..parent_end], at };
        let id = r.u16("a chunk header")?;
        let length = r.u32("a chunk header")? as usize;
        if length < 6 || at.saturating_add(length) > parent_end {
            return Err((
                at,
                format!(
                    "chunk {id:04X} claims {length} bytes, but its parent ends {} bytes later (truncated or damaged file)",
                    parent_end - at
                ),
            ));
        }
        Ok((at + 6, at + length))
    }

    /// Reads the chunks from `start` to `end`, descending into those that hold others.
    fn children(&mut self, mut at: usize, end: usize, depth: u32) -> Result<(), Fail> {
        if depth > MAX_DEPTH {
            return Err((at, format!("chunks nest more than {MAX_DEPTH} deep; the file is damaged")));
        }
        while at + 6 <= end {
            let id = u16::from_le_bytes([self.bytes[at], self.bytes[at + 1]]);
            let (body, next) = self.chunk_bounds(at, end)?;
            match id {
                0x3D3D => self.children(body, next, depth + 1)?,
                0x4000 => {
                    let mut r = Reader { bytes: &self.bytes[..next], at: body };
                    let name = cstring(&mut r)?;
                    self.model.meshes.push(ModelMesh {
                        name,
                        model_from_mesh: Affine3A::IDENTITY,
                        ..Default::default()
                    });
                    self.face_material_names.push(Vec::new());
                    self.children(r.at, next, depth + 1)?;
                }
                0x4100 => self.children(body, next, depth + 1)?,
                0x4110 => {
                    let mesh = self.mesh(at)?;
                    let mut r = Reader { bytes: &self.bytes[..next], at: body };
                    let n = r.u16("the vertex count")? as usize;
                    if n * 12 > next - r.at {
                        return Err((body, format!("{n} vertices do not fit in their chunk of {} bytes", next - body)));
                    }
                    let mesh = &mut self.model.meshes[mesh];
                    for _ in 0..n {
                        let (x, y, z) = (r.f32("a vertex")?, r.f32("a vertex")?, r.f32("a vertex")?);
                        mesh.positions.push(Vec3::new(x, z, -y));
                    }
                }
                0x4140 => {
                    let mesh = self.mesh(at)?;
                    let mut r = Reader { bytes: &self.bytes[..next], at: body };
                    let n = r.u16("the uv count")? as usize;
                    let mut uv = Vec::with_capacity(n);
                    for _ in 0..n {
                        uv.push(Vec2::new(r.f32("a texture coordinate")?, r.f32("a texture coordinate")?));
                    }
                    // Kept per vertex until the faces spread them to corners (`finish_uvs`).
                    self.model.meshes[mesh].uvs = Some(uv);
                }
                0x4120 => {
                    let m = self.mesh(at)?;
                    let mut r = Reader { bytes: &self.bytes[..next], at: body };
                    let n = r.u16("the face count")? as usize;
                    if n * 8 > next - r.at {
                        return Err((body, format!("{n} faces do not fit in their chunk of {} bytes", next - body)));
                    }
                    let vertex_uvs = self.model.meshes[m].uvs.take();
                    let mesh = &mut self.model.meshes[m];
                    let count = mesh.positions.len();
                    for _ in 0..n {
                        let at = r.at;
                        let face = [r.u16("a face")? as u32, r.u16("a face")? as u32, r.u16("a face")? as u32];
                        r.u16("a face's flags")?;
                        if let Some(bad) = face.iter().find(|&&i| i as usize >= count) {
                            return Err((
                                at,
                                format!("a face refers to vertex {bad}, but the object has {count} vertices"),
                            ));
                        }
                        mesh.push_face(&face, None);
                        if let Some(uv) = &vertex_uvs {
                            if uv.len() == count {
                                mesh.uvs.get_or_insert_with(Vec::new).extend(face.iter().map(|&i| uv[i as usize]));
                            }
                        }
                    }
                    self.face_material_names[m] = vec![None; n];
                    self.face_chunks(r.at, next, m, n)?;
                }
                0xAFFF => {
                    self.model.materials.push(ModelMaterial::new(""));
                    self.material(body, next, depth + 1)?;
                }
                _ => {}
            }
            at = next;
        }
        Ok(())
    }

    fn mesh(&self, at: usize) -> Result<usize, Fail> {
        self.model.meshes.len().checked_sub(1).ok_or((at, "mesh data outside an object chunk (4000)".to_string()))
    }

    /// The sub-chunks of a face list: materials of faces and smoothing groups.
    fn face_chunks(&mut self, mut at: usize, end: usize, m: usize, faces: usize) -> Result<(), Fail> {
        while at + 6 <= end {
            let id = u16::from_le_bytes([self.bytes[at], self.bytes[at + 1]]);
            let (body, next) = self.chunk_bounds(at, end)?;
            let mut r = Reader { bytes: &self.bytes[..next], at: body };
            match id {
                0x4130 => {
                    let name = cstring(&mut r)?;
                    let n = r.u16("a material's face count")?;
                    for _ in 0..n {
                        let at = r.at;
                        let f = r.u16("a material's face")? as usize;
                        if f >= faces {
                            return Err((
                                at,
                                format!("material \"{name}\" lists face {f}, but the object has {faces}"),
                            ));
                        }
                        self.face_material_names[m][f] = Some(name.clone());
                    }
                }
                0x4150 => {
                    let mut groups = Vec::with_capacity(faces);
                    for _ in 0..faces {
                        groups.push(r.u32("the smoothing groups")?);
                    }
                    self.model.meshes[m].smoothing_groups = Some(groups);
                }
                _ => {}
            }
            at = next;
        }
        Ok(())
    }

    fn material(&mut self, mut at: usize, end: usize, depth: u32) -> Result<(), Fail> {
        let base = self.path.parent().unwrap_or(Path::new("")).to_path_buf();
        while at + 6 <= end {
            let id = u16::from_le_bytes([self.bytes[at], self.bytes[at + 1]]);
            let (body, next) = self.chunk_bounds(at, end)?;
            let mut r = Reader { bytes: &self.bytes[..next], at: body };
            let m = self.model.materials.last_mut().expect("a material chunk pushed its material");
            match id {
                0xA000 => m.name = cstring(&mut r)?,
                0xA020 => {
                    if let Some(c) = color(self.bytes, body, next)? {
                        m.base_color = c;
                    }
                }
                0xA030 => {
                    if let Some(c) = color(self.bytes, body, next)? {
                        if c.max_element() > 0.0 && m.roughness.is_none() {
                            m.roughness = Some(0.3);
                        }
                    }
                }
                0xA040 => {
                    // Shininess in percent: 100 % is a sharp highlight (alpha 0.05), 0 % rough.
                    if let Some(s) = percent(self.bytes, body, next)? {
                        if m.roughness.is_some() || s > 0.0 {
                            m.roughness = Some((1.0 - s).clamp(0.05, 1.0));
                        }
                    }
                }
                0xA050 => {
                    if let Some(t) = percent(self.bytes, body, next)? {
                        m.opacity = (1.0 - t).clamp(0.0, 1.0);
                    }
                }
                0xA200 => {
                    let mut k = body;
                    while k + 6 <= next {
                        let (b, n) = self.chunk_bounds(k, next)?;
                        if u16::from_le_bytes([self.bytes[k], self.bytes[k + 1]]) == 0xA300 {
                            let mut r = Reader { bytes: &self.bytes[..n], at: b };
                            let file = cstring(&mut r)?;
                            match find_file(&base, &file) {
                                Some(p) => match load_image_texture(&p, ColorSpace::Srgb) {
                                    Ok(image) => {
                                        let m = self.model.materials.last_mut().expect("pushed");
                                        m.base_color_texture =
                                            Some(ModelImage { image: Arc::new(image), wrap: Wrap::Repeat });
                                    }
                                    Err(e) => self.model.warnings.push(format!("{e}; the material keeps its colour")),
                                },
                                None => self.model.warnings.push(format!(
                                    "{}: texture \"{}\" not found next to the file; the material keeps its colour",
                                    crate::limits::printable_message(&self.path.display().to_string()),
                                    crate::limits::printable(&file)
                                )),
                            }
                        }
                        k = n;
                    }
                }
                _ => {
                    let _ = depth;
                }
            }
            at = next;
        }
        Ok(())
    }
}

/// A NUL-terminated string of at most 256 bytes.
fn cstring(r: &mut Reader<'_>) -> Result<String, Fail> {
    let start = r.at;
    let rest = &r.bytes[start..];
    let Some(len) = rest.iter().take(256).position(|&b| b == 0) else {
        return Err((start, "a name is not closed by a NUL byte within 256 bytes".to_string()));
    };
    r.at += len + 1;
    Ok(String::from_utf8_lossy(&rest[..len]).into_owned())
}

/// The first colour sub-chunk (float or 24-bit) of a colour chunk's body, linear.
fn color(bytes: &[u8], mut at: usize, end: usize) -> Result<Option<Vec3>, Fail> {
    while at + 6 <= end {
        let id = u16::from_le_bytes([bytes[at], bytes[at + 1]]);
        let length = u32::from_le_bytes([bytes[at + 2], bytes[at + 3], bytes[at + 4], bytes[at + 5]]) as usize;
        if length < 6 || at + length > end {
            return Err((at, format!("colour chunk {id:04X} runs past its parent")));
        }
        let mut r = Reader { bytes: &bytes[..at + length], at: at + 6 };
        match id {
            0x0010 | 0x0013 => {
                let c = Vec3::new(r.f32("a colour")?, r.f32("a colour")?, r.f32("a colour")?);
                return Ok(Some(c.clamp(Vec3::ZERO, Vec3::ONE)));
            }
            0x0011 | 0x0012 => {
                let b = r.take(3, "a colour")?;
                let c = |v: u8| crate::scene::image_texture::srgb_to_linear(v as f64 / 255.0) as f32;
                return Ok(Some(Vec3::new(c(b[0]), c(b[1]), c(b[2]))));
            }
            _ => {}
        }
        at += length;
    }
    Ok(None)
}

/// A percentage sub-chunk as a fraction.
fn percent(bytes: &[u8], mut at: usize, end: usize) -> Result<Option<f32>, Fail> {
    while at + 6 <= end {
        let id = u16::from_le_bytes([bytes[at], bytes[at + 1]]);
        let length = u32::from_le_bytes([bytes[at + 2], bytes[at + 3], bytes[at + 4], bytes[at + 5]]) as usize;
        if length < 6 || at + length > end {
            return Err((at, format!("percentage chunk {id:04X} runs past its parent")));
        }
        let mut r = Reader { bytes: &bytes[..at + length], at: at + 6 };
        match id {
            0x0030 => return Ok(Some(r.u16("a percentage")? as f32 / 100.0)),
            0x0031 => return Ok(Some(r.f32("a percentage")? / 100.0)),
            _ => {}
        }
        at += length;
    }
    Ok(None)
}

/// `name` in `dir`, matched without regard to case (3DS files name textures in 8.3 upper case).
/// Both lookups pass the scene's file gate: in the editor a name leading out of the scene's
/// folder is "not found", whether or not something is there.
fn find_file(dir: &Path, name: &str) -> Option<std::path::PathBuf> {
    let name = name.replace('\\', "/");
    let direct = dir.join(&name);
    if direct.is_file() && crate::scene::files::check(&direct).is_ok() {
        return Some(direct);
    }
    let file = Path::new(&name).file_name()?.to_str()?.to_ascii_lowercase();
    crate::scene::files::read_dir(dir)?
        .flatten()
        .map(|e| e.path())
        .find(|p| p.file_name().and_then(|f| f.to_str()).is_some_and(|f| f.to_ascii_lowercase() == file))
}

/// Writes a 3DS file of one object with one material (tests).
pub fn write_3ds(positions: &[Vec3], faces: &[[u16; 3]], diffuse: [u8; 3]) -> Vec<u8> {
    fn chunk(id: u16, body: &[u8]) -> Vec<u8> {
        let mut out = id.to_le_bytes().to_vec();
        out.extend((body.len() as u32 + 6).to_le_bytes());
        out.extend(body);
        out
    }
    let mut vertices = (positions.len() as u16).to_le_bytes().to_vec();
    for p in positions {
        // Photonix (x, y, z) is 3DS (x, -z, y).
        for c in [p.x, -p.z, p.y] {
            vertices.extend(c.to_le_bytes());
        }
    }
    let mut face_body = (faces.len() as u16).to_le_bytes().to_vec();
    for f in faces {
        for i in f {
            face_body.extend(i.to_le_bytes());
        }
        face_body.extend(0u16.to_le_bytes());
    }
    let mut material_faces = b"red\0".to_vec();
    material_faces.extend((faces.len() as u16).to_le_bytes());
    for i in 0..faces.len() as u16 {
        material_faces.extend(i.to_le_bytes());
    }
    face_body.extend(chunk(0x4130, &material_faces));
    let mut mesh = chunk(0x4110, &vertices);
    mesh.extend(chunk(0x4120, &face_body));
    let mut object = b"thing\0".to_vec();
    object.extend(chunk(0x4100, &mesh));
    let mut material = chunk(0xA000, b"red\0");
    material.extend(chunk(0xA020, &chunk(0x0011, &diffuse)));
    let mut editor = chunk(0xAFFF, &material);
    editor.extend(chunk(0x4000, &object));
    chunk(0x4D4D, &chunk(0x3D3D, &editor))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file() -> Vec<u8> {
        write_3ds(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], &[[0, 1, 2], [0, 1, 3]], [255, 0, 0])
    }

    #[test]
    fn written_file_reads_back_upright_with_its_material() {
        let model = parse_3ds(&file(), Path::new("t.3ds")).unwrap();
        let mesh = &model.meshes[0];
        assert_eq!(mesh.name, "thing");
        assert!(mesh.positions[2].abs_diff_eq(Vec3::Y, 1e-6), "{:?}", mesh.positions);
        assert_eq!(mesh.face_materials, vec![Some(0), Some(0)]);
        assert_eq!(model.materials[0].name, "red");
        assert_eq!(model.materials[0].base_color, Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn every_truncation_is_an_error_or_fewer_faces() {
        let full = file();
        for cut in 0..full.len() {
            if let Ok(model) = parse_3ds(&full[..cut], Path::new("t.3ds")) {
                panic!("cut at {cut} of {} read as {} meshes", full.len(), model.meshes.len());
            }
        }
    }

    #[test]
    fn out_of_range_face_is_an_error() {
        let bad = write_3ds(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[[0, 1, 9]], [1, 2, 3]);
        let e = parse_3ds(&bad, Path::new("t.3ds")).unwrap_err();
        assert!(e.message.contains("vertex 9"), "{e}");
        assert!(e.at.starts_with("byte "));
    }
}
