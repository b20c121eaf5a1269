//! Wavefront OBJ meshes with their MTL materials, read with `tobj`: positions, polygons (kept
//! as polygons for subdivision), texture coordinates, normals, and per `usemtl` the material:
//! `Kd`/`map_Kd` (diffuse colour), `Ks` and `Ns` (a specular coat), `d` (opacity), `Ni` (its
//! index), `Ke` (emission), `bump`/`map_bump` with `-bm` (a bump map).

use std::io::BufReader;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};

use super::{Model, ModelError, ModelImage, ModelMaterial, ModelMesh};
use crate::scene::image_texture::{load_image_texture, ColorSpace, Wrap};

/// The model of an OBJ file's bytes; `path` names it in messages and locates its MTL files and
/// their images.
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<Model, ModelError> {
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let (models, materials) = parse(bytes, &base).map_err(|error| {
        let at = find_error_line(bytes, &base, &error).map(|l| format!("line {l}")).unwrap_or_default();
        ModelError::new(path, at, describe(&error))
    })?;
    // tobj reads `nan`, `inf` and 1e39 (which overflows) as floats; refuse them here, on their
    // line, rather than as the "zero-area triangles" they would turn into.
    if let Some((line, message)) = bad_number_line(bytes) {
        return Err(ModelError::new(path, format!("line {line}"), message));
    }
    let mut model = Model::default();
    match materials {
        Ok(materials) => {
            for m in &materials {
                model.materials.push(mtl_material(m, &base, path)?);
            }
        }
        Err(_) => model.warnings.push(format!(
            "{}: its MTL file (`mtllib`) cannot be read; its faces get the scene's material",
            crate::limits::printable_message(&path.display().to_string())
        )),
    }
    // `v x y z r g b` (an extension of MeshLab and ZBrush exports): the renderer has no
    // per-vertex colour, so say the colours are dropped rather than drop them silently.
    let coloured: Vec<&str> =
        models.iter().filter(|m| !m.mesh.vertex_color.is_empty()).map(|m| m.name.as_str()).collect();
    if !coloured.is_empty() {
        model.warnings.push(format!(
            "{}: its vertices carry colours (`v x y z r g b`, in {}), which photonix does not use; the faces get \
             their material's colour (bake the colours into a texture to keep them)",
            crate::limits::printable_message(&path.display().to_string()),
            match coloured.len() {
                1 => format!("mesh \"{}\"", crate::limits::printable(coloured[0])),
                n => format!("{n} meshes"),
            }
        ));
    }
    for m in &models {
        let mesh = &m.mesh;
        let mut out = ModelMesh { name: m.name.clone(), model_from_mesh: Affine3A::IDENTITY, ..Default::default() };
        out.positions = mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let material = mesh.material_id.filter(|&id| id < model.materials.len()).map(|id| id as u32);
        // tobj keeps separate index lists for `vt` and `vn`, parallel to the positions' when every
        // face has them.
        let corners = mesh.indices.len();
        let has_uv = mesh.texcoord_indices.len() == corners
            && mesh.texcoord_indices.iter().all(|&i| (i as usize) * 2 + 1 < mesh.texcoords.len());
        let has_normals = mesh.normal_indices.len() == corners
            && mesh.normal_indices.iter().all(|&i| (i as usize) * 3 + 2 < mesh.normals.len());
        if has_uv {
            out.uvs = Some(
                mesh.texcoord_indices
                    .iter()
                    .map(|&i| Vec2::new(mesh.texcoords[2 * i as usize], mesh.texcoords[2 * i as usize + 1]))
                    .collect(),
            );
        }
        if has_normals {
            out.normals = Some(
                mesh.normal_indices
                    .iter()
                    .map(|&i| {
                        let i = 3 * i as usize;
                        Vec3::new(mesh.normals[i], mesh.normals[i + 1], mesh.normals[i + 2])
                    })
                    .collect(),
            );
        }
        // Without `face_arities` every face is a triangle.
        let mut at = 0usize;
        let arities: Vec<u32> =
            if mesh.face_arities.is_empty() { vec![3; corners / 3] } else { mesh.face_arities.clone() };
        out.face_offsets.push(0);
        for arity in arities {
            at += arity as usize;
            if at > corners {
                return Err(ModelError::new(path, "", "a face has more corners than the file lists"));
            }
            out.face_offsets.push(at as u32);
            out.face_materials.push(material);
        }
        out.corners = mesh.indices.clone();
        // Faces of fewer than 3 corners (points, lines) carry no surface.
        drop_small_faces(&mut out);
        if out.face_count() > 0 {
            model.meshes.push(out);
        }
    }
    if model.meshes.is_empty() {
        return Err(ModelError::new(
            path,
            "",
            "the OBJ file has no triangles (it needs `v` lines and `f` lines with 3 or more vertices)",
        ));
    }
    Ok(model)
}

/// Removes faces of fewer than 3 corners with their per-corner data.
fn drop_small_faces(mesh: &mut ModelMesh) {
    if (0..mesh.face_count()).all(|f| mesh.face(f).len() >= 3) {
        return;
    }
    let old = std::mem::take(mesh);
    let mut out = ModelMesh {
        name: old.name.clone(),
        positions: old.positions.clone(),
        model_from_mesh: old.model_from_mesh,
        normals: old.normals.as_ref().map(|_| Vec::new()),
        uvs: old.uvs.as_ref().map(|_| Vec::new()),
        face_offsets: vec![0],
        ..Default::default()
    };
    for f in 0..old.face_count() {
        let r = old.face(f);
        if r.len() < 3 {
            continue;
        }
        out.corners.extend_from_slice(&old.corners[r.clone()]);
        if let (Some(o), Some(n)) = (&mut out.normals, &old.normals) {
            o.extend_from_slice(&n[r.clone()]);
        }
        if let (Some(o), Some(u)) = (&mut out.uvs, &old.uvs) {
            o.extend_from_slice(&u[r.clone()]);
        }
        out.face_offsets.push(out.corners.len() as u32);
        out.face_materials.push(old.face_materials[f]);
    }
    *mesh = out;
}

/// An MTL material in the model's terms.
fn mtl_material(m: &tobj::Material, base: &Path, path: &Path) -> Result<ModelMaterial, ModelError> {
    let mut out = ModelMaterial::new(&m.name);
    let at = || format!("material \"{}\"", crate::limits::printable(&m.name));
    let color = |c: Option<[f32; 3]>, what: &str| -> Result<Option<Vec3>, ModelError> {
        match c {
            Some(c) if c.iter().all(|v| v.is_finite() && *v >= 0.0 && *v <= 1e6) => Ok(Some(Vec3::from(c))),
            Some(c) => Err(ModelError::new(
                path,
                at(),
                format!("`{what}` is [{}, {}, {}]; it must hold numbers >= 0", c[0], c[1], c[2]),
            )),
            None => Ok(None),
        }
    };
    if let Some(kd) = color(m.diffuse, "Kd")? {
        out.base_color = kd.min(Vec3::ONE);
    }
    let ks = color(m.specular, "Ks")?.unwrap_or(Vec3::ZERO);
    if ks.max_element() > 0.0 {
        let ns = m.shininess.unwrap_or(0.0);
        if !(ns.is_finite() && ns >= 0.0) {
            return Err(ModelError::new(path, at(), format!("`Ns` is {ns}; it must be a number >= 0")));
        }
        // Phong exponent to a microfacet width: alpha = sqrt(2 / (Ns + 2)) (Walter et al. 2007,
        // eq. 25, for Beckmann, which GGX follows closely at these widths).
        out.roughness = Some((2.0 / (ns + 2.0)).sqrt().clamp(0.0, 1.0));
    }
    if let Some(d) = m.dissolve {
        if !(0.0..=1.0).contains(&d) {
            return Err(ModelError::new(path, at(), format!("`d` (dissolve) is {d}; it must be in [0, 1]")));
        }
        out.opacity = d;
    }
    if let Some(ni) = m.optical_density {
        if ni.is_finite() && (1.0..=crate::limits::MAX_IOR as f32).contains(&ni) {
            out.ior = ni;
        }
    }
    if let Some(ke) = color(m.emissive, "Ke")? {
        out.emission = ke;
    }
    let image = |spec: &str, what: &str, space: ColorSpace| -> Result<(ModelImage, f32), ModelError> {
        let (file, scale) = texture_options(spec);
        let file_path = base.join(file.replace('\\', "/"));
        let image =
            load_image_texture(&file_path, space).map_err(|e| ModelError::new(path, at(), format!("`{what}`: {e}")))?;
        Ok((ModelImage { image: Arc::new(image), wrap: Wrap::Repeat }, scale))
    };
    if let Some(spec) = &m.diffuse_texture {
        out.base_color_texture = Some(image(spec, "map_Kd", ColorSpace::Srgb)?.0);
        // The texture gives the colour; Kd scales it, as most renderers read MTL.
    }
    if let Some(spec) = &m.normal_texture {
        let (img, scale) = image(spec, "bump", ColorSpace::Linear)?;
        out.bump_texture = Some((img, scale));
    }
    Ok(out)
}

/// The file name and the `-bm` multiplier (default 1) of an MTL texture statement's arguments.
fn texture_options(spec: &str) -> (String, f32) {
    // Options and how many arguments each takes (the MTL specification).
    const OPTIONS: &[(&str, usize)] = &[
        ("-blendu", 1),
        ("-blendv", 1),
        ("-bm", 1),
        ("-boost", 1),
        ("-cc", 1),
        ("-clamp", 1),
        ("-imfchan", 1),
        ("-mm", 2),
        ("-o", 3),
        ("-s", 3),
        ("-t", 3),
        ("-texres", 1),
        ("-type", 1),
    ];
    let words: Vec<&str> = spec.split_whitespace().collect();
    let mut scale = 1.0;
    let mut i = 0;
    while i < words.len() {
        match OPTIONS.iter().find(|(o, _)| *o == words[i]) {
            Some((option, count)) => {
                if *option == "-bm" {
                    scale =
                        words.get(i + 1).and_then(|w| w.parse::<f32>().ok()).filter(|v| v.is_finite()).unwrap_or(1.0);
                }
                // `-o`, `-s` and `-t` take 1 to 3 numbers.
                let mut taken = 0;
                while taken < *count && words.get(i + 1).is_some_and(|w| w.parse::<f32>().is_ok() || *count == 1) {
                    i += 1;
                    taken += 1;
                }
                i += 1;
            }
            None => break,
        }
    }
    (words[i.min(words.len())..].join(" "), scale)
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
            Some("vn") => "normal",
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

type MaterialsResult = Result<Vec<tobj::Material>, tobj::LoadError>;

fn parse(bytes: &[u8], base: &Path) -> Result<(Vec<tobj::Model>, MaterialsResult), tobj::LoadError> {
    // `..Default::default()` covers fields that only exist with tobj's optional features.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // An MTL file beyond the size limit, or missing, loads no materials (a warning).
    tobj::load_obj_buf(&mut BufReader::new(bytes), &options, |p| {
        let file = base.join(p);
        // Through the scene's file gate, like the OBJ itself: confined in the editor.
        match crate::scene::files::read(&file, crate::limits::MAX_MODEL_FILE_BYTES) {
            Ok(text) => tobj::load_mtl_buf(&mut BufReader::new(&text[..])),
            Err(_) => Err(tobj::LoadError::OpenFileFailed),
        }
    })
}

/// `tobj` does not report lines. Parse ever longer prefixes (binary search) to find the first
/// line whose prefix fails with the same error: a bad line makes every longer prefix fail too.
fn find_error_line(bytes: &[u8], base: &Path, error: &tobj::LoadError) -> Option<usize> {
    let line_ends: Vec<usize> = bytes
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == b'\n')
        .map(|(i, _)| i + 1)
        .chain(std::iter::once(bytes.len()))
        .collect();
    let fails = |lines: usize| parse(&bytes[..line_ends[lines - 1]], base).err();
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
    use crate::scene::model::{mesh_triangles, Shading};

    fn obj(text: &str) -> Result<Model, ModelError> {
        parse_obj(text.as_bytes(), Path::new("test.obj"))
    }

    #[test]
    fn quad_face_stays_a_polygon_and_fans_keeping_winding() {
        let model = obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        assert_eq!(model.meshes[0].face_count(), 1);
        let triangles = mesh_triangles(&model.meshes[0], Shading { file_normals: true, smooth_angle_deg: 0.0 });
        assert_eq!(triangles.len(), 2);
        for t in &triangles {
            let t = &t.vertices;
            let normal = (t[1] - t[0]).cross(t[2] - t[0]);
            assert!(normal.z > 0.0, "winding kept: {normal}");
        }
    }

    #[test]
    fn file_normals_make_smooth_triangles() {
        let model = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn -0.3 0 1\nvn 0.3 0 1\nvn 0 0.3 1\nf 1//1 2//2 3//3\n").unwrap();
        let t = mesh_triangles(&model.meshes[0], Shading { file_normals: true, smooth_angle_deg: 0.0 });
        let n = t[0].normals.expect("file normals that differ from the face normal are smooth");
        assert!((n[0] - Vec3::new(-0.3, 0.0, 1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn nan_infinite_and_huge_numbers_report_their_line() {
        for (text, line, piece) in [
            ("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", 2, "`nan`, not a finite number"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n", 3, "`-inf`, not a finite number"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 1e39\nf 1 2 3\n", 3, "1e39, beyond the largest scene coordinate"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 1.79769342949672961348623157e308\nf 1 2 3\n", 3, "overflows 64-bit floats"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 NaN\nf 1/1 2/1 3/1\n", 4, "texture coordinate is `NaN`"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 inf 1\nf 1//1 2//1 3//1\n", 4, "normal is `inf`"),
        ] {
            let error = obj(text).unwrap_err();
            assert_eq!(error.at, format!("line {line}"), "{text}");
            assert!(error.message.contains(piece), "{}", error.message);
        }
    }

    #[test]
    fn bad_position_and_index_report_their_line() {
        assert_eq!(obj("v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n").unwrap_err().at, "line 3");
        let error = obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 1 2 9\n").unwrap_err();
        assert_eq!(error.at, "line 5");
        assert!(error.message.contains("does not exist"), "{error}");
    }

    #[test]
    fn mtl_options_give_file_and_bump_multiplier() {
        assert_eq!(texture_options("-bm 0.25 bump.png"), ("bump.png".to_string(), 0.25));
        assert_eq!(texture_options("-o 0.5 0.5 -clamp on wood.jpg"), ("wood.jpg".to_string(), 1.0));
        assert_eq!(texture_options("plain.png"), ("plain.png".to_string(), 1.0));
    }
}
