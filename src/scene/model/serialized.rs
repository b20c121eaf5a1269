//! Mitsuba's `.serialized` meshes (its `SerializedMesh` format, versions 3 and 4): shapes one
//! after another, each a little-endian header and a zlib stream, and at the end of the file a
//! table of where each shape starts.
//!
//! ```text
//! u16 0x041C  u16 version          then, zlib-compressed:
//!   u32 flags  (v4: name, NUL-terminated)  u64 vertices  u64 triangles
//!   positions (3 floats each), normals (flag 0x0001), uvs (0x0002, 2 floats), colours (0x0008)
//!   triangles (3 x u32, or u64 above 2^32 vertices)
//! ...  table: v4 u64 / v3 u32 offset of each shape, then u32 shape count
//! ```
//! Floats are f32 with flag 0x1000 and f64 with 0x2000. Every shape becomes one mesh of the
//! model, in file order (Mitsuba's `shape_index`).

use std::io::Read;
use std::path::Path;

use glam::{Vec2, Vec3};

use super::{check_number, Model, ModelError, ModelMesh};

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_UVS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const SINGLE: u32 = 0x1000;
const DOUBLE: u32 = 0x2000;

pub fn parse_serialized(bytes: &[u8], path: &Path) -> Result<Model, ModelError> {
    let err = |at: usize, m: String| ModelError::new(path, format!("byte {at}"), m);
    if bytes.len() < 8 {
        return Err(err(0, "the file is too short for a Mitsuba serialized mesh".into()));
    }
    let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]);
    if u16_at(0) != MAGIC {
        return Err(err(0, "not a Mitsuba serialized mesh (its first bytes are not 1C 04)".into()));
    }
    let version = u16_at(2);
    if !(3..=4).contains(&version) {
        return Err(err(2, format!("serialized-mesh version {version}; Photonix reads versions 3 and 4")));
    }
    // The table of shapes at the end of the file.
    let n = bytes.len();
    let count = u32::from_le_bytes(bytes[n - 4..].try_into().expect("4 bytes")) as usize;
    let entry = if version == 4 { 8 } else { 4 };
    let table = count
        .checked_mul(entry)
        .and_then(|t| t.checked_add(4))
        .filter(|t| *t <= n - 4 && count >= 1)
        .ok_or_else(|| err(n - 4, format!("the shape table's count ({count}) does not fit the file")))?;
    let mut offsets = Vec::with_capacity(count);
    for i in 0..count {
        let at = n - table + i * entry;
        let o = if version == 4 {
            u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes")) as usize
        } else {
            u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize
        };
        if o + 4 > n - table {
            return Err(err(at, format!("shape {i} starts at byte {o}, beyond the shapes")));
        }
        offsets.push(o);
    }
    let mut model = Model::default();
    for (i, &start) in offsets.iter().enumerate() {
        let end = offsets.get(i + 1).copied().unwrap_or(n - table);
        if end < start + 4 {
            return Err(err(start, format!("shape {i} overlaps the next")));
        }
        if u16::from_le_bytes([bytes[start], bytes[start + 1]]) != MAGIC {
            return Err(err(start, format!("shape {i} does not start with the serialized-mesh header")));
        }
        let mut data = Vec::new();
        let limit = crate::limits::MAX_MODEL_FILE_BYTES;
        flate2::read::ZlibDecoder::new(&bytes[start + 4..end])
            .take(limit)
            .read_to_end(&mut data)
            .map_err(|e| err(start + 4, format!("shape {i}: its zlib stream cannot be read: {e}")))?;
        let mesh = shape(&data, version).map_err(|(at, m)| {
            ModelError::new(path, format!("shape {i}"), format!("{m} (byte {at} of its uncompressed data)"))
        })?;
        model.meshes.push(mesh);
    }
    Ok(model)
}

/// One shape's uncompressed data.
fn shape(d: &[u8], version: u16) -> Result<ModelMesh, (usize, String)> {
    let mut at = 0usize;
    let mut take = |len: usize, what: &str| -> Result<&[u8], (usize, String)> {
        let s = d.get(at..at.saturating_add(len)).ok_or((at, format!("the data ends in the middle of {what}")))?;
        at += len;
        Ok(s)
    };
    let flags = u32::from_le_bytes(take(4, "the flags")?.try_into().expect("4 bytes"));
    let mut mesh = ModelMesh::default();
    if version == 4 {
        let rest = d.get(4..).unwrap_or_default();
        let nul = rest.iter().position(|&b| b == 0).ok_or((4, "the shape's name has no end".to_string()))?;
        mesh.name = String::from_utf8_lossy(&rest[..nul]).into_owned();
        take(nul + 1, "the name")?;
    }
    let vertices = u64::from_le_bytes(take(8, "the vertex count")?.try_into().expect("8 bytes"));
    let triangles = u64::from_le_bytes(take(8, "the triangle count")?.try_into().expect("8 bytes"));
    let float = match (flags & SINGLE != 0, flags & DOUBLE != 0) {
        (true, false) => 4,
        (false, true) => 8,
        _ => return Err((0, format!("flags {flags:#x} name neither single nor double precision"))),
    };
    // Counts must fit what is left: a shape of 4 billion vertices in a small file is damage.
    let left = d.len() as u64;
    if vertices.saturating_mul(3 * float as u64) > left || triangles.saturating_mul(12) > left {
        return Err((4, format!("{vertices} vertices and {triangles} triangles do not fit the shape's data")));
    }
    let (nv, nt) = (vertices as usize, triangles as usize);
    let mut read_floats = |k: usize, what: &str| -> Result<Vec<f32>, (usize, String)> {
        let bytes = take(nv * k * float, what)?;
        bytes
            .chunks_exact(float)
            .map(|c| {
                let v = if float == 4 {
                    f32::from_le_bytes(c.try_into().expect("4 bytes")) as f64
                } else {
                    f64::from_le_bytes(c.try_into().expect("8 bytes"))
                };
                check_number(v, what).map(|_| v as f32).map_err(|m| (0, m))
            })
            .collect()
    };
    let p = read_floats(3, "a position")?;
    let positions: Vec<Vec3> = p.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    let normals = if flags & HAS_NORMALS != 0 {
        let n = read_floats(3, "a normal")?;
        Some(n.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>())
    } else {
        None
    };
    let uvs = if flags & HAS_UVS != 0 {
        let t = read_floats(2, "a texture coordinate")?;
        Some(t.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect::<Vec<_>>())
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        read_floats(3, "a vertex colour")?;
    }
    let wide = vertices > u32::MAX as u64;
    let index_bytes = if wide { 8 } else { 4 };
    let raw = take(nt * 3 * index_bytes, "the triangles")?;
    let index_at = |i: usize| -> u64 {
        let c = &raw[i * index_bytes..(i + 1) * index_bytes];
        if wide {
            u64::from_le_bytes(c.try_into().expect("8 bytes"))
        } else {
            u32::from_le_bytes(c.try_into().expect("4 bytes")) as u64
        }
    };
    let mut corner_normals = normals.as_ref().map(|_| Vec::with_capacity(nt * 3));
    let mut corner_uvs = uvs.as_ref().map(|_| Vec::with_capacity(nt * 3));
    for t in 0..nt {
        let idx = [index_at(3 * t), index_at(3 * t + 1), index_at(3 * t + 2)];
        if let Some(&bad) = idx.iter().find(|&&i| i >= vertices) {
            return Err((0, format!("triangle {t} names vertex {bad}; the shape has {vertices}")));
        }
        let idx = idx.map(|i| i as u32);
        mesh.push_face(&idx, None);
        if let (Some(out), Some(n)) = (corner_normals.as_mut(), normals.as_ref()) {
            out.extend(idx.iter().map(|&i| n[i as usize]));
        }
        if let (Some(out), Some(uv)) = (corner_uvs.as_mut(), uvs.as_ref()) {
            out.extend(idx.iter().map(|&i| uv[i as usize]));
        }
    }
    mesh.positions = positions;
    mesh.normals = corner_normals;
    mesh.uvs = corner_uvs;
    mesh.model_from_mesh = glam::Affine3A::IDENTITY;
    Ok(mesh)
}

/// A serialized file of `shapes` (positions, triangles), version 4, single precision: for tests.
pub fn write_serialized(shapes: &[(&[Vec3], &[[u32; 3]])]) -> Vec<u8> {
    use std::io::Write;
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for (positions, triangles) in shapes {
        offsets.push(out.len() as u64);
        out.extend_from_slice(&MAGIC.to_le_bytes());
        out.extend_from_slice(&4u16.to_le_bytes());
        let mut d = Vec::new();
        d.extend_from_slice(&SINGLE.to_le_bytes());
        d.extend_from_slice(b"shape\0");
        d.extend_from_slice(&(positions.len() as u64).to_le_bytes());
        d.extend_from_slice(&(triangles.len() as u64).to_le_bytes());
        for p in positions.iter() {
            for c in p.to_array() {
                d.extend_from_slice(&c.to_le_bytes());
            }
        }
        for t in triangles.iter() {
            for i in t {
                d.extend_from_slice(&i.to_le_bytes());
            }
        }
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&d).expect("writing to memory");
        out.extend(z.finish().expect("writing to memory"));
    }
    for o in &offsets {
        out.extend_from_slice(&o.to_le_bytes());
    }
    out.extend_from_slice(&(shapes.len() as u32).to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_read_back_in_order() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let quad = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let bytes = write_serialized(&[(&tri, &[[0, 1, 2]]), (&quad, &[[0, 1, 2], [0, 2, 3]])]);
        let model = parse_serialized(&bytes, Path::new("m.serialized")).unwrap();
        assert_eq!(model.meshes.len(), 2);
        assert_eq!(model.meshes[1].face_count(), 2);
        assert_eq!(model.meshes[1].positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(model.meshes[0].name, "shape");
    }

    #[test]
    fn damaged_files_are_errors() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let bytes = write_serialized(&[(&tri, &[[0, 1, 5]])]);
        let e = parse_serialized(&bytes, Path::new("m.serialized")).unwrap_err();
        assert!(e.to_string().contains("names vertex 5"), "{e}");
        let e = parse_serialized(&bytes[..bytes.len() - 3], Path::new("m.serialized")).unwrap_err();
        assert!(e.to_string().contains("m.serialized"), "{e}");
    }
}
