//! IFS, the binary indexed face set of Brown University's 3D model repository: little-endian,
//! strings written as a u32 length (counting their closing NUL) and their bytes.
//!
//! ```text
//! "IFS"  f32 version (1.0 or 2.0)  model name
//! "VERTICES"   u32 n   n x (f32 x, f32 y, f32 z)
//! "TRIANGLES"  u32 m   m x (u32 a, u32 b, u32 c)
//! "TEXTURECOORD" u32 n  n x (f32 u, f32 v)        (version 2.0, optional)
//! ```

use std::path::Path;

use glam::{Affine3A, Vec2, Vec3};

use super::{check_number, Model, ModelError, ModelMesh};

/// A little-endian reader that reports byte offsets.
pub(crate) struct Reader<'a> {
    pub bytes: &'a [u8],
    pub at: usize,
}

impl<'a> Reader<'a> {
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], (usize, String)> {
        match self.bytes.get(self.at..self.at.saturating_add(n)) {
            Some(b) => {
                self.at += n;
                Ok(b)
            }
            None => Err((
                self.at,
                format!("the file ends at byte {} in the middle of {what} (truncated?)", self.bytes.len()),
            )),
        }
    }

    pub fn u32(&mut self, what: &str) -> Result<u32, (usize, String)> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub fn u16(&mut self, what: &str) -> Result<u16, (usize, String)> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    /// A float that must be finite and within the scene range.
    pub fn f32(&mut self, what: &str) -> Result<f32, (usize, String)> {
        let at = self.at;
        let b = self.take(4, what)?;
        let v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        check_number(v as f64, what).map_err(|m| (at, m))?;
        Ok(v)
    }

    /// A count of items of `item_bytes` each that the rest of the file can hold.
    pub fn count(&mut self, item_bytes: usize, what: &str) -> Result<usize, (usize, String)> {
        let at = self.at;
        let n = self.u32(what)? as usize;
        let left = self.bytes.len() - self.at;
        if n.saturating_mul(item_bytes) > left {
            return Err((
                at,
                format!("{what} count is {n}, but only {left} bytes follow (truncated, or a wrong count)"),
            ));
        }
        Ok(n)
    }

    /// An IFS string: u32 length including the NUL, then the bytes.
    fn string(&mut self, what: &str) -> Result<String, (usize, String)> {
        let at = self.at;
        let n = self.u32(what)? as usize;
        if n > 4096 {
            return Err((at, format!("{what} is {n} bytes long; this is not an IFS file, or it is damaged")));
        }
        let b = self.take(n, what)?;
        Ok(String::from_utf8_lossy(b).trim_end_matches('\0').to_string())
    }
}

/// The model of an IFS file's bytes; `path` names it in messages.
pub fn parse_ifs(bytes: &[u8], path: &Path) -> Result<Model, ModelError> {
    read(bytes, path).map_err(|(at, message)| ModelError::new(path, format!("byte {at}"), message))
}

fn read(bytes: &[u8], path: &Path) -> Result<Model, (usize, String)> {
    let mut r = Reader { bytes, at: 0 };
    let magic = r.string("the header")?;
    if magic != "IFS" {
        return Err((0, "the file does not start with the string \"IFS\"; it is not an IFS file".into()));
    }
    let at = r.at;
    let version = f32::from_le_bytes(r.take(4, "the version")?.try_into().expect("4 bytes"));
    if version != 1.0 && version != 2.0 {
        return Err((at, format!("IFS version {version}; only 1.0 and 2.0 are read")));
    }
    let name = r.string("the model name")?;
    let mut mesh = ModelMesh {
        name: if name.is_empty() {
            path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
        } else {
            name
        },
        model_from_mesh: Affine3A::IDENTITY,
        ..Default::default()
    };
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut uvs: Option<Vec<Vec2>> = None;
    while r.at < bytes.len() {
        let at = r.at;
        match r.string("a section name")?.as_str() {
            "VERTICES" => {
                let n = r.count(12, "the vertex")?;
                mesh.positions.reserve(n);
                for _ in 0..n {
                    mesh.positions.push(Vec3::new(r.f32("a vertex x")?, r.f32("a vertex y")?, r.f32("a vertex z")?));
                }
            }
            "TRIANGLES" => {
                let n = r.count(12, "the triangle")?;
                triangles.reserve(n);
                for _ in 0..n {
                    let at = r.at;
                    let t = [r.u32("a triangle")?, r.u32("a triangle")?, r.u32("a triangle")?];
                    if let Some(bad) = t.iter().find(|&&i| i as usize >= mesh.positions.len()) {
                        return Err((
                            at,
                            format!(
                                "a triangle refers to vertex {bad}, but {} vertices precede it (indices start at 0)",
                                mesh.positions.len()
                            ),
                        ));
                    }
                    triangles.push(t);
                }
            }
            "TEXTURECOORD" => {
                let n = r.count(8, "the texture coordinate")?;
                let mut list = Vec::with_capacity(n);
                for _ in 0..n {
                    list.push(Vec2::new(r.f32("a texture coordinate")?, r.f32("a texture coordinate")?));
                }
                uvs = Some(list);
            }
            other => {
                return Err((
                    at,
                    format!(
                        "unknown section \"{}\"; an IFS file has VERTICES, TRIANGLES and TEXTURECOORD",
                        crate::limits::printable(other)
                    ),
                ))
            }
        }
    }
    if triangles.is_empty() {
        return Err((r.at, "the file has no TRIANGLES".into()));
    }
    let uvs = uvs.filter(|u| u.len() == mesh.positions.len());
    for t in &triangles {
        mesh.push_face(t, None);
        if let Some(u) = &uvs {
            mesh.uvs.get_or_insert_with(Vec::new).extend(t.iter().map(|&i| u[i as usize]));
        }
    }
    Ok(Model { meshes: vec![mesh], ..Default::default() })
}

/// Writes an IFS 1.0 file (tests and tools).
pub fn write_ifs(name: &str, positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut out = Vec::new();
    let string = |out: &mut Vec<u8>, s: &str| {
        out.extend((s.len() as u32 + 1).to_le_bytes());
        out.extend(s.as_bytes());
        out.push(0);
    };
    string(&mut out, "IFS");
    out.extend(1.0f32.to_le_bytes());
    string(&mut out, name);
    string(&mut out, "VERTICES");
    out.extend((positions.len() as u32).to_le_bytes());
    for p in positions {
        for c in p.to_array() {
            out.extend(c.to_le_bytes());
        }
    }
    string(&mut out, "TRIANGLES");
    out.extend((triangles.len() as u32).to_le_bytes());
    for t in triangles {
        for i in t {
            out.extend(i.to_le_bytes());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> Vec<u8> {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        write_ifs("tet", &p, &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    #[test]
    fn written_file_reads_back() {
        let model = parse_ifs(&tetrahedron(), Path::new("t.ifs")).unwrap();
        assert_eq!(model.meshes[0].positions.len(), 4);
        assert_eq!(model.meshes[0].face_count(), 4);
        assert_eq!(model.meshes[0].name, "tet");
    }

    #[test]
    fn every_truncation_is_an_error_naming_a_byte() {
        let full = tetrahedron();
        for cut in 0..full.len() {
            let e = parse_ifs(&full[..cut], Path::new("t.ifs")).unwrap_err();
            assert!(e.at.starts_with("byte "), "{e}");
        }
    }

    #[test]
    fn bad_index_nan_and_huge_count_are_errors() {
        let mut bad = write_ifs("x", &[Vec3::ZERO, Vec3::X, Vec3::Y], &[[0, 1, 5]]);
        let e = parse_ifs(&bad, Path::new("t.ifs")).unwrap_err();
        assert!(e.message.contains("vertex 5"), "{e}");
        bad = write_ifs("x", &[Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y], &[[0, 1, 2]]);
        assert!(parse_ifs(&bad, Path::new("t.ifs")).unwrap_err().message.contains("not a finite number"));
        bad = write_ifs("x", &[Vec3::ZERO, Vec3::new(1e30, 0.0, 0.0), Vec3::Y], &[[0, 1, 2]]);
        assert!(parse_ifs(&bad, Path::new("t.ifs")).unwrap_err().message.contains("beyond the largest"));
        // The vertex count (after "IFS", the version, "x" and "VERTICES") claims 2^31 vertices.
        let at = 4 + 4 + 4 + 4 + 2 + 4 + 9;
        bad[at..at + 4].copy_from_slice(&0x8000_0000u32.to_le_bytes());
        let e = parse_ifs(&bad, Path::new("t.ifs")).unwrap_err();
        assert!(e.message.contains("only"), "{e}");
    }
}
