//! Wavefront OBJ meshes, read with `tobj`: positions, faces and texture coordinates (`vt`);
//! materials and normals are ignored (the scene file assigns the material).

use std::io::BufReader;
use std::path::Path;

use glam::{Vec2, Vec3};

/// Why an OBJ file could not be used.
#[derive(Debug)]
pub(crate) enum ObjError {
    NotFound,
    /// `line` is 1-based, when known.
    Malformed {
        line: Option<usize>,
        message: String,
    },
}

#[derive(Debug)]
/// A triangle of an OBJ file, with its vertices' `vt` texture coordinates when the face has them.
pub(crate) struct MeshTriangle {
    pub vertices: [Vec3; 3],
    pub uv: Option<[Vec2; 3]>,
}

/// Every triangle of every object in the OBJ file, in object space, in file order. Polygons are
/// fanned into triangles by `tobj`, keeping their winding.
pub(crate) fn load_obj_triangles(path: &Path) -> Result<Vec<MeshTriangle>, ObjError> {
    let limit = crate::limits::MAX_OBJ_FILE_BYTES;
    let bytes = match crate::limits::read_limited(path, limit) {
        Ok(bytes) => bytes,
        Err(Some(e)) if e.kind() == std::io::ErrorKind::NotFound => return Err(ObjError::NotFound),
        Err(Some(e)) => {
            return Err(ObjError::Malformed { line: None, message: format!("cannot read the OBJ file: {e}") })
        }
        Err(None) => {
            let message = format!(
                "the OBJ file is larger than {} (the most photonix reads; see docs/limits.md)",
                crate::limits::fmt_bytes(limit)
            );
            return Err(ObjError::Malformed { line: None, message });
        }
    };
    let models = parse(&bytes)
        .map_err(|error| ObjError::Malformed { line: find_error_line(&bytes, &error), message: describe(&error) })?;
    // tobj reads `nan`, `inf` and 1e39 (which overflows) as floats; refuse them here, on their
    // line, rather than as the "zero-area triangles" they would turn into.
    if let Some((line, message)) = bad_number_line(&bytes) {
        return Err(ObjError::Malformed { line: Some(line), message });
    }

    let mut triangles = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let position = |i: u32| {
            let i = i as usize * 3;
            Vec3::new(mesh.positions[i], mesh.positions[i + 1], mesh.positions[i + 2])
        };
        let texcoord = |i: u32| {
            let i = i as usize * 2;
            Vec2::new(mesh.texcoords[i], mesh.texcoords[i + 1])
        };
        // tobj keeps a separate index list for `vt`, parallel to the positions' when every face
        // has texture coordinates.
        let has_uv = mesh.texcoord_indices.len() == mesh.indices.len()
            && mesh.texcoord_indices.iter().all(|&i| (i as usize) * 2 + 1 < mesh.texcoords.len());
        for (k, face) in mesh.indices.chunks_exact(3).enumerate() {
            let uv = has_uv.then(|| {
                let t = &mesh.texcoord_indices[3 * k..3 * k + 3];
                [texcoord(t[0]), texcoord(t[1]), texcoord(t[2])]
            });
            triangles.push(MeshTriangle { vertices: [position(face[0]), position(face[1]), position(face[2])], uv });
        }
    }
    if triangles.is_empty() {
        return Err(ObjError::Malformed {
            line: None,
            message: "the OBJ file has no triangles (it needs `v` lines and `f` lines with 3 or more vertices)"
                .to_string(),
        });
    }
    Ok(triangles)
}

/// The first `v` or `vt` line holding a number that is not finite in 32-bit floats or lies beyond
/// the scene range, with what is wrong.
fn bad_number_line(bytes: &[u8]) -> Option<(usize, String)> {
    use crate::limits::{fmt_number, printable, MAX_SCENE_VALUE};
    let text = String::from_utf8_lossy(bytes);
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let what = match words.next() {
            Some("v") => "vertex position",
            Some("vt") => "texture coordinate",
            _ => continue,
        };
        for word in words {
            let Ok(v) = word.parse::<f64>() else { continue };
            if !v.is_finite() {
                // `nan` and `inf` as written; digits that overflow even 64-bit floats are not
                // echoed (they can run to any length).
                let message = if word.contains(|c: char| c.is_ascii_digit()) {
                    format!("a {what} overflows 64-bit floats; the largest scene coordinate is +-{MAX_SCENE_VALUE:e}")
                } else {
                    format!("a {what} is `{}`, not a finite number", printable(word))
                };
                return Some((i + 1, message));
            }
            if v.abs() > MAX_SCENE_VALUE {
                let message = format!(
                    "a {what} is {}, beyond the largest scene coordinate, +-{MAX_SCENE_VALUE:e} (see docs/limits.md)",
                    fmt_number(v)
                );
                return Some((i + 1, message));
            }
        }
    }
    None
}

fn parse(bytes: &[u8]) -> Result<Vec<tobj::Model>, tobj::LoadError> {
    // `..Default::default()` covers fields that only exist with tobj's optional features.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Materials are not used, so `mtllib` lines load nothing (and a missing .mtl is no error).
    let (models, _materials) =
        tobj::load_obj_buf(&mut BufReader::new(bytes), &options, |_| Err(tobj::LoadError::OpenFileFailed))?;
    Ok(models)
}

/// `tobj` does not report lines. Parse ever longer prefixes (binary search) to find the first
/// line whose prefix fails with the same error: a bad line makes every longer prefix fail too.
fn find_error_line(bytes: &[u8], error: &tobj::LoadError) -> Option<usize> {
    let line_ends: Vec<usize> = bytes
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == b'\n')
        .map(|(i, _)| i + 1)
        .chain(std::iter::once(bytes.len()))
        .collect();
    let fails = |lines: usize| parse(&bytes[..line_ends[lines - 1]]).err();
    let (mut good, mut bad) = (0, line_ends.len());
    if fails(bad).as_ref() != Some(error) {
        return None;
    }
    while bad - good > 1 {
        let mid = (good + bad) / 2;
        if fails(mid).as_ref() == Some(error) {
            bad = mid;
        } else {
            good = mid;
        }
    }
    Some(bad)
}

fn describe(error: &tobj::LoadError) -> String {
    use tobj::LoadError as E;
    match error {
        E::PositionParseError => "cannot parse a vertex position; `v` needs 3 numbers".to_string(),
        E::NormalParseError => "cannot parse a normal; `vn` needs 3 numbers".to_string(),
        E::TexcoordParseError => "cannot parse a texture coordinate (`vt`)".to_string(),
        E::FaceParseError => "cannot parse a face; `f` needs 3 or more vertex indices".to_string(),
        E::FaceVertexOutOfBounds => "a face refers to a vertex that does not exist (indices start at 1)".to_string(),
        E::ReadError => "cannot read the OBJ file (is it UTF-8 text?)".to_string(),
        other => format!("malformed OBJ file: {other}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn obj_file(text: &str) -> tempfile::NamedTempFile {
        let mut file = tempfile::Builder::new().suffix(".obj").tempfile().unwrap();
        file.write_all(text.as_bytes()).unwrap();
        file
    }

    #[test]
    fn quad_face_fans_into_two_triangles_keeping_winding() {
        let file = obj_file("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
        let triangles = load_obj_triangles(file.path()).unwrap();
        assert_eq!(triangles.len(), 2);
        for t in &triangles {
            let t = &t.vertices;
            let normal = (t[1] - t[0]).cross(t[2] - t[0]);
            assert!(normal.z > 0.0, "winding kept: {normal}");
        }
    }

    #[test]
    fn nan_infinite_and_huge_numbers_report_their_line() {
        for (text, line, piece) in [
            ("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", 2, "`nan`, not a finite number"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n", 3, "`-inf`, not a finite number"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 1e39\nf 1 2 3\n", 3, "1e39, beyond the largest scene coordinate"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 1.79769342949672961348623157e308\nf 1 2 3\n", 3, "overflows 64-bit floats"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 NaN\nf 1/1 2/1 3/1\n", 4, "texture coordinate is `NaN`"),
        ] {
            let file = obj_file(text);
            match load_obj_triangles(file.path()) {
                Err(ObjError::Malformed { line: Some(l), message }) => {
                    assert_eq!(l, line, "{text}");
                    assert!(message.contains(piece), "{message}");
                }
                other => panic!("expected a malformed OBJ at line {line}, got {other:?}"),
            }
        }
    }

    #[test]
    fn bad_position_reports_its_line() {
        let file = obj_file("v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n");
        match load_obj_triangles(file.path()) {
            Err(ObjError::Malformed { line, .. }) => assert_eq!(line, Some(3)),
            other => panic!("expected a malformed OBJ, got {other:?}"),
        }
    }
}
