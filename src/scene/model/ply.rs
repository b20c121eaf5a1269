//! Stanford PLY meshes, ASCII and binary (both byte orders), read by a small parser of our own:
//! the `vertex` element's `x y z`, normals `nx ny nz`, texture coordinates (`u v`, `s t` or
//! `texture_u texture_v`) and colours (`red green blue`), and the `face` element's
//! `vertex_indices` (or `vertex_index`) list. Other elements and properties are read past.
//!
//! Vertex colours have no place in the material system (a material's colour is a constant or
//! an image): each face takes the mean colour of its vertices, rounded to 1/32 steps of the sRGB
//! value, and the faces of each distinct colour share one diffuse material.

use std::collections::HashMap;
use std::path::Path;

use glam::{Affine3A, Vec2, Vec3};

use super::{check_number, Model, ModelError, ModelMaterial, ModelMesh};
use crate::scene::image_texture::srgb_to_linear;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list property.
    list: Option<Scalar>,
    ty: Scalar,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// Reads values one at a time from the body, ASCII or binary.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
    /// 1-based line of an ASCII body's current position.
    line: usize,
}

impl Body<'_> {
    /// Where the reader is, for messages: a line in ASCII, a byte offset in binary.
    fn position(&mut self) -> String {
        if self.encoding == Encoding::Ascii {
            self.skip_space();
        }
        match self.encoding {
            Encoding::Ascii => format!("line {}", self.line),
            _ => format!("byte {}", self.at),
        }
    }

    fn skip_space(&mut self) {
        while self.at < self.bytes.len() && self.bytes[self.at].is_ascii_whitespace() {
            if self.bytes[self.at] == b'\n' {
                self.line += 1;
            }
            self.at += 1;
        }
    }

    fn value(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.encoding == Encoding::Ascii {
            self.skip_space();
            let start = self.at;
            while self.at < self.bytes.len() && !self.bytes[self.at].is_ascii_whitespace() {
                self.at += 1;
            }
            if start == self.at {
                return Err("the file ends before the last element (fewer values than the header's counts)".into());
            }
            let word = std::str::from_utf8(&self.bytes[start..self.at]).unwrap_or("?");
            let v: f64 = word.parse().map_err(|_| format!("`{}` is not a number", crate::limits::printable(word)))?;
            if matches!(ty, Scalar::F32 | Scalar::F64) {
                Ok(v)
            } else if v.fract() != 0.0 {
                Err(format!("`{}` is not a whole number, as the header's type says", crate::limits::printable(word)))
            } else {
                Ok(v)
            }
        } else {
            let n = ty.size();
            let Some(raw) = self.bytes.get(self.at..self.at + n) else {
                return Err(format!(
                    "the file ends at byte {} before the last element (truncated, or the header's counts are wrong)",
                    self.bytes.len()
                ));
            };
            self.at += n;
            let mut b = [0u8; 8];
            b[..n].copy_from_slice(raw);
            if self.encoding == Encoding::Big {
                b[..n].reverse();
            }
            Ok(match ty {
                Scalar::I8 => b[0] as i8 as f64,
                Scalar::U8 => b[0] as f64,
                Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                Scalar::F64 => f64::from_le_bytes(b),
            })
        }
    }
}

/// Most vertices in a face: a bigger list is a damaged count, not a polygon.
const MAX_FACE_CORNERS: usize = 1024;

/// The model of a PLY file's bytes; `path` names it in messages.
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<Model, ModelError> {
    let err = |at: String, message: String| ModelError::new(path, at, message);
    // Header
    let Some(end) = find(bytes, b"end_header") else {
        return Err(err(
            String::new(),
            "no `end_header` line; this is not a PLY file, or its header is cut short".into(),
        ));
    };
    let header =
        std::str::from_utf8(&bytes[..end]).map_err(|_| err("header".into(), "the header is not ASCII text".into()))?;
    let mut body_start = end + "end_header".len();
    // The header ends with its line: "\n", or "\r\n" from some writers.
    if bytes.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if bytes.get(body_start) == Some(&b'\n') {
        body_start += 1;
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in header.lines().enumerate() {
        let at = format!("line {}", i + 1);
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first().copied() {
            Some("ply") if i == 0 => {}
            _ if i == 0 => return Err(err(at, "the file does not start with `ply`; it is not a PLY file".into())),
            Some("format") => {
                encoding = Some(match words.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::Little,
                    Some("binary_big_endian") => Encoding::Big,
                    _ => {
                        return Err(err(
                            at,
                            "unknown `format`; use ascii, binary_little_endian or binary_big_endian".into(),
                        ))
                    }
                })
            }
            Some("element") => {
                let (Some(name), Some(count)) = (words.get(1), words.get(2)) else {
                    return Err(err(at, "`element` needs a name and a count".into()));
                };
                let count: usize = count.parse().map_err(|_| {
                    err(
                        at.clone(),
                        format!("element count `{}` is not a whole number", crate::limits::printable(count)),
                    )
                })?;
                elements.push(Element { name: name.to_string(), count, properties: Vec::new() });
            }
            Some("property") => {
                let Some(element) = elements.last_mut() else {
                    return Err(err(at, "`property` before any `element`".into()));
                };
                let bad_type =
                    |t: &str| err(at.clone(), format!("unknown property type `{}`", crate::limits::printable(t)));
                let property = if words.get(1) == Some(&"list") {
                    let (Some(c), Some(t), Some(name)) = (words.get(2), words.get(3), words.get(4)) else {
                        return Err(err(at, "`property list` needs a count type, a value type and a name".into()));
                    };
                    let count_type = Scalar::parse(c).ok_or_else(|| bad_type(c))?;
                    if matches!(count_type, Scalar::F32 | Scalar::F64) {
                        return Err(err(at, "a list's count type must be an integer type".into()));
                    }
                    Property {
                        name: name.to_string(),
                        list: Some(count_type),
                        ty: Scalar::parse(t).ok_or_else(|| bad_type(t))?,
                    }
                } else {
                    let (Some(t), Some(name)) = (words.get(1), words.get(2)) else {
                        return Err(err(at, "`property` needs a type and a name".into()));
                    };
                    Property { name: name.to_string(), list: None, ty: Scalar::parse(t).ok_or_else(|| bad_type(t))? }
                };
                element.properties.push(property);
            }
            // Comments, and lines some writers put in the header without `comment` (Blender 2.47
            // wrote "Created by Blender3D ...").
            _ => {}
        }
    }
    let Some(encoding) = encoding else {
        return Err(err("header".into(), "no `format` line".into()));
    };
    let Some(vertex_index) = elements.iter().position(|e| e.name == "vertex") else {
        return Err(err("header".into(), "no `element vertex`".into()));
    };
    // Counts no file of this size could hold are refused before anything is allocated.
    let body_len = bytes.len() - body_start;
    for e in &elements {
        let least = e
            .properties
            .iter()
            .map(|p| if encoding == Encoding::Ascii { 2 } else { p.list.unwrap_or(p.ty).size() })
            .sum::<usize>();
        if e.count.saturating_mul(least.max(1)) > body_len.saturating_add(1) && least > 0 {
            return Err(err(
                "header".into(),
                format!(
                    "`element {} {}` cannot fit in the {} bytes after the header (truncated file, or a wrong count)",
                    crate::limits::printable(&e.name),
                    e.count,
                    body_len
                ),
            ));
        }
    }

    // Body
    let header_lines = header.lines().count() + 1;
    let mut body = Body { bytes, at: body_start, encoding, line: header_lines + 1 };
    let mut mesh = ModelMesh {
        name: path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        model_from_mesh: Affine3A::IDENTITY,
        ..Default::default()
    };
    let vertex = &elements[vertex_index];
    let find_prop =
        |names: &[&str]| vertex.properties.iter().position(|p| names.contains(&p.name.as_str()) && p.list.is_none());
    let (Some(px), Some(py), Some(pz)) = (find_prop(&["x"]), find_prop(&["y"]), find_prop(&["z"])) else {
        return Err(err("header".into(), "the vertex element needs properties x, y and z".into()));
    };
    let normal_props = (find_prop(&["nx"]), find_prop(&["ny"]), find_prop(&["nz"]));
    let uv_props = (find_prop(&["u", "s", "texture_u"]), find_prop(&["v", "t", "texture_v"]));
    let color_props = (
        find_prop(&["red", "r", "diffuse_red"]),
        find_prop(&["green", "g", "diffuse_green"]),
        find_prop(&["blue", "b", "diffuse_blue"]),
    );
    let mut vertex_normals = Vec::new();
    let mut vertex_uvs = Vec::new();
    let mut vertex_colors = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for (e_index, e) in elements.iter().enumerate() {
        for item in 0..e.count {
            let mut values: Vec<f64> = Vec::with_capacity(e.properties.len());
            let mut list: Option<Vec<u32>> = None;
            for p in &e.properties {
                let at = body.position();
                let fail = |m: String| err(at.clone(), format!("{} {item}, `{}`: {m}", e.name, p.name));
                match p.list {
                    None => values.push(body.value(p.ty).map_err(fail)?),
                    Some(count_type) => {
                        let n = body.value(count_type).map_err(&fail)?;
                        if !(0.0..=MAX_FACE_CORNERS as f64).contains(&n) {
                            return Err(fail(format!("a list of {n} values; at most {MAX_FACE_CORNERS} are read")));
                        }
                        let mut items = Vec::with_capacity(n as usize);
                        for _ in 0..n as usize {
                            items.push(body.value(p.ty).map_err(&fail)?);
                        }
                        values.push(f64::NAN);
                        if e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index") {
                            let mut face = Vec::with_capacity(items.len());
                            for v in items {
                                if !(v >= 0.0 && v < vertex.count as f64) {
                                    return Err(fail(format!(
                                        "vertex index {v} is out of range; the file has {} vertices (indices start at 0)",
                                        vertex.count
                                    )));
                                }
                                face.push(v as u32);
                            }
                            list = Some(face);
                        }
                    }
                }
            }
            if e_index == vertex_index {
                let at = body.position();
                let v = |k: usize, what: &str| -> Result<f32, ModelError> {
                    check_number(values[k], what).map_err(|m| err(at.clone(), format!("vertex {item}: {m}")))?;
                    Ok(values[k] as f32)
                };
                mesh.positions.push(Vec3::new(v(px, "x")?, v(py, "y")?, v(pz, "z")?));
                if let (Some(a), Some(b), Some(c)) = normal_props {
                    vertex_normals.push(Vec3::new(v(a, "nx")?, v(b, "ny")?, v(c, "nz")?));
                }
                if let (Some(a), Some(b)) = uv_props {
                    vertex_uvs.push(Vec2::new(v(a, "u")?, v(b, "v")?));
                }
                if let (Some(r), Some(g), Some(b)) = color_props {
                    // Integer colours count to their type's maximum (255 for uchar), floats to 1.
                    let scale = |k: usize| match vertex.properties[k].ty {
                        Scalar::U8 | Scalar::I8 => 255.0,
                        Scalar::U16 | Scalar::I16 => 65535.0,
                        Scalar::U32 | Scalar::I32 => 4294967295.0,
                        _ => 1.0,
                    };
                    let c = |k: usize| (values[k] / scale(k)).clamp(0.0, 1.0);
                    vertex_colors.push([c(r), c(g), c(b)]);
                }
            } else if let Some(face) = list {
                if face.len() >= 3 {
                    faces.push(face);
                }
            }
        }
    }
    // Colours to materials
    let mut model = Model::default();
    let mut color_material: HashMap<[u8; 3], u32> = HashMap::new();
    for face in &faces {
        let material = if vertex_colors.is_empty() {
            None
        } else {
            let mut mean = [0.0f64; 3];
            for &v in face {
                for k in 0..3 {
                    mean[k] += vertex_colors[v as usize][k] / face.len() as f64;
                }
            }
            let key = mean.map(|c| (c * 31.0).round() as u8);
            let id = *color_material.entry(key).or_insert_with(|| {
                let mut m = ModelMaterial::new(&format!("colour {} {} {}", key[0], key[1], key[2]));
                m.base_color = Vec3::from(key.map(|k| srgb_to_linear(k as f64 / 31.0) as f32));
                model.materials.push(m);
                (model.materials.len() - 1) as u32
            });
            Some(id)
        };
        mesh.push_face(face, material);
        if !vertex_normals.is_empty() {
            mesh.normals.get_or_insert_with(Vec::new).extend(face.iter().map(|&v| vertex_normals[v as usize]));
        }
        if !vertex_uvs.is_empty() {
            mesh.uvs.get_or_insert_with(Vec::new).extend(face.iter().map(|&v| vertex_uvs[v as usize]));
        }
    }
    if faces.is_empty() {
        return Err(err(
            String::new(),
            "the PLY file has no faces (an `element face` with `vertex_indices` lists of 3 or more)".into(),
        ));
    }
    model.meshes.push(mesh);
    Ok(model)
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "ply\nformat FORMAT 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

    fn binary(big: bool) -> Vec<u8> {
        let mut out =
            HEADER.replace("FORMAT", if big { "binary_big_endian" } else { "binary_little_endian" }).into_bytes();
        for (p, c) in
            [([0.0f32, 0.0, 0.0], [255u8, 0, 0]), ([1.0, 0.0, 0.0], [255, 0, 0]), ([0.0, 1.0, 0.0], [255, 0, 0])]
        {
            for v in p {
                out.extend(if big { v.to_be_bytes() } else { v.to_le_bytes() });
            }
            out.extend(c);
        }
        out.push(3);
        for i in [0i32, 1, 2] {
            out.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        out
    }

    #[test]
    fn ascii_and_both_binary_orders_read_the_same_triangle() {
        let ascii = HEADER.replace("FORMAT", "ascii") + "0 0 0 255 0 0\n1 0 0 255 0 0\n0 1 0 255 0 0\n3 0 1 2\n";
        for bytes in [ascii.into_bytes(), binary(false), binary(true)] {
            let model = parse_ply(&bytes, Path::new("t.ply")).unwrap();
            let mesh = &model.meshes[0];
            assert_eq!(mesh.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
            assert_eq!(mesh.corners, vec![0, 1, 2]);
            assert_eq!(model.materials.len(), 1);
            assert_eq!(model.materials[0].base_color, Vec3::new(1.0, 0.0, 0.0));
        }
    }

    #[test]
    fn truncated_files_wrong_counts_and_bad_indices_are_errors() {
        let full = binary(false);
        let header = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        for cut in [full.len() - 1, full.len() - 13, header + 5] {
            let e = parse_ply(&full[..cut], Path::new("t.ply")).unwrap_err();
            assert!(e.message.contains("ends") || e.message.contains("cannot fit"), "{e}");
        }
        let ascii = HEADER.replace("FORMAT", "ascii") + "0 0 0 255 0 0\n1 0 0 255 0 0\n0 1 0 255 0 0\n3 0 1 7\n";
        let e = parse_ply(ascii.as_bytes(), Path::new("t.ply")).unwrap_err();
        assert!(e.message.contains("vertex index 7 is out of range"), "{e}");
        assert_eq!(e.at, "line 16");
        let nan = HEADER.replace("FORMAT", "ascii") + "0 0 0 255 0 0\nnan 0 0 255 0 0\n0 1 0 255 0 0\n3 0 1 2\n";
        let e = parse_ply(nan.as_bytes(), Path::new("t.ply")).unwrap_err();
        assert!(e.message.contains("not a finite number"), "{e}");
        let huge = HEADER.replace("FORMAT", "ascii").replace("vertex 3", "vertex 4000000000");
        let e = parse_ply(huge.as_bytes(), Path::new("t.ply")).unwrap_err();
        assert!(e.message.contains("cannot fit"), "{e}");
    }
}
