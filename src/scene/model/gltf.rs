//! glTF 2.0 models, `.gltf` (JSON with external or embedded buffers) and `.glb` (binary), read
//! with the `gltf` crate: the node hierarchy of the default scene with each node's transform,
//! triangle meshes (positions, normals, the first texture coordinates, indices), materials
//! (metallic-roughness with base-colour, metallic-roughness, normal and emissive textures,
//! alpha modes), cameras and KHR_lights_punctual lights.
//!
//! glTF texture coordinates have v down (the image's top row at v = 0); Photonix's have v up, so
//! v becomes 1 - v. Every accessor is checked against its buffer before it is read, and every
//! index against the vertex count.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Mat3, Mat4, Vec2, Vec3};

use super::{Model, ModelCamera, ModelError, ModelImage, ModelLight, ModelMaterial, ModelMesh, ModelProjection};
use crate::scene::image_texture::{srgb_to_linear, ColorSpace, ImageTexture, Wrap};

/// Deepest node nesting followed (a cycle in a damaged file would otherwise never end).
const MAX_NODE_DEPTH: usize = 64;

/// The model of a glTF or GLB file's bytes; `path` names it in messages and locates external
/// buffers and images.
pub fn parse_gltf(bytes: &[u8], path: &Path) -> Result<Model, ModelError> {
    // The gltf crate asserts a few invariants with panics after its validation; a damaged file
    // that trips one becomes an error here rather than a crash.
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| read(bytes, path))) {
        Ok(result) => result,
        Err(_) => Err(ModelError::new(path, "", "the glTF file is malformed (its reader gave up)")),
    }
}

/// The `asset.version` a `.gltf` file's JSON declares, or "1" for a version-1 binary container.
fn declared_version(bytes: &[u8]) -> Option<String> {
    if bytes.starts_with(b"glTF") {
        let version = u32::from_le_bytes(bytes.get(4..8)?.try_into().ok()?);
        return Some(version.to_string());
    }
    let json: serde_json::Value = serde_json::from_slice(bytes).ok()?;
    json.get("asset")?.get("version")?.as_str().map(str::to_string)
}

/// Checks a `.glb` container (a 12-byte header, then chunks of a length, a type and the data;
/// glTF 2.0 spec, section 4.4) against the file's size, so a truncated file is reported at the
/// byte where it ends rather than as the reader's bare "unexpected end". `None`: not a binary
/// container, or a sound one.
fn check_binary_container(bytes: &[u8]) -> Option<(String, String)> {
    if !bytes.starts_with(b"glTF") {
        return None;
    }
    let size = bytes.len();
    let word = |at: usize| bytes.get(at..at + 4).map(|w| u32::from_le_bytes(w.try_into().expect("4 bytes")) as usize);
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Some((
            format!("byte {size}"),
            format!("the file ends at byte {size}, inside its 12-byte header (truncated file?)"),
        ));
    };
    if version != 2 {
        let hint = if version == 1 { "; convert glTF 1.0 files to 2.0 first, e.g. with Blender" } else { "" };
        return Some(("byte 4".into(), format!("the binary container is version {version}, not 2{hint}")));
    }
    if length > size {
        return Some((
            format!("byte {size}"),
            format!("the file ends at byte {size}, but its header declares {length} bytes (truncated file?)"),
        ));
    }
    let mut at = 12;
    while at < length {
        let Some(chunk) = word(at) else {
            return Some((format!("byte {at}"), format!("a chunk header at byte {at} runs past the end of the file")));
        };
        let end = at.saturating_add(8).saturating_add(chunk);
        if end > length {
            return Some((
                format!("byte {at}"),
                format!("the chunk at byte {at} declares {chunk} bytes, past the file's end at byte {length} (truncated file?)"),
            ));
        }
        at = end;
    }
    None
}

/// The file a glTF URI names, as the `gltf` crate resolves it (its `Scheme`): `file:` paths as
/// they are, relative references percent-decoded under `base`; `None` for embedded `data:` and
/// schemes the crate refuses itself.
fn uri_file(base: &Path, uri: &str) -> Option<std::path::PathBuf> {
    if uri.contains(':') {
        let rest = uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:"))?;
        return Some(std::path::PathBuf::from(rest));
    }
    // The crate unwraps this decoding: a URI it cannot decode panics there (caught by
    // `parse_gltf`) before anything is opened.
    let decoded = urlencoding::decode(uri).unwrap_or(std::borrow::Cow::Borrowed(uri));
    Some(base.join(&*decoded))
}

fn read(bytes: &[u8], path: &Path) -> Result<Model, ModelError> {
    let err = |at: String, message: String| ModelError::new(path, at, message);
    if let Some((at, message)) = check_binary_container(bytes) {
        return Err(err(at, message));
    }
    let gltf = ::gltf::Gltf::from_slice(bytes).map_err(|e| {
        // The hint about glTF 1.0 only where the file says it is 1.0: every 2.0 error carried it.
        let hint = if declared_version(bytes).is_some_and(|v| v.starts_with('1')) {
            " (this is a glTF 1.0 file; convert it to 2.0 first, e.g. with Blender)"
        } else {
            ""
        };
        err(String::new(), format!("not a valid glTF 2.0 file: {e}{hint}"))
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    let document = gltf.document;
    // Every file a buffer or an image names passes the scene's file gate before the crate opens
    // it (recorded as an input; confined to the scene's folder in the editor). The crate's own
    // message for a missing file does not say which file it looked for.
    let uris = document
        .buffers()
        .filter_map(|b| match b.source() {
            ::gltf::buffer::Source::Uri(uri) => {
                Some((format!("buffer {}", b.index()), "data file", uri, crate::limits::MAX_MODEL_FILE_BYTES))
            }
            ::gltf::buffer::Source::Bin => None,
        })
        .chain(document.images().filter_map(|i| match i.source() {
            ::gltf::image::Source::Uri { uri, .. } => {
                Some((format!("image {}", i.index()), "image file", uri, crate::limits::MAX_IMAGE_FILE_BYTES))
            }
            ::gltf::image::Source::View { .. } => None,
        }));
    // The crate reads each file to its end: only a regular file of at most the limit may reach it
    // (a URI naming /dev/zero, a FIFO or a huge sparse file would take all memory or wait forever).
    for (at, what, uri, limit) in uris {
        let Some(file) = uri_file(base, uri) else { continue };
        match crate::scene::files::check_file(&file, limit) {
            Ok(_) => {}
            Err(e) if e.not_found() => {
                return Err(err(
                    at,
                    format!(
                        "its {what} `{}` is missing; put it next to the glTF file, or export a .glb",
                        crate::limits::printable_message(uri)
                    ),
                ))
            }
            // Outside the editor's folder: the message names no file (the page must learn nothing).
            Err(e @ crate::scene::files::FileError::Outside { .. }) => return Err(err(at, format!("its {what}: {e}"))),
            Err(e) => return Err(err(at, format!("its {what} `{}`: {e}", crate::limits::printable(uri)))),
        }
    }
    let buffers = ::gltf::import_buffers(&document, Some(base), gltf.blob)
        .map_err(|e| err(String::new(), format!("cannot load its buffers: {e}")))?;
    for (b, buffer) in document.buffers().enumerate() {
        if buffers[b].len() < buffer.length() {
            return Err(err(
                format!("buffer {b}"),
                format!(
                    "holds {} bytes, fewer than the {} it declares (truncated file?)",
                    buffers[b].len(),
                    buffer.length()
                ),
            ));
        }
    }
    let mut model = Model::default();

    // Materials
    check_image_sizes(&document, base, &buffers, &err)?;
    let images = ::gltf::import_images(&document, Some(base), &buffers)
        .map_err(|e| err(String::new(), format!("cannot load its images: {e}")))?;
    let mut cache: HashMap<(usize, bool), Arc<ImageTexture>> = HashMap::new();
    let mut texture = |info: ::gltf::texture::Texture<'_>, space: ColorSpace| -> Result<ModelImage, ModelError> {
        let index = info.source().index();
        let srgb = space == ColorSpace::Srgb;
        let image = match cache.get(&(index, srgb)) {
            Some(i) => i.clone(),
            None => {
                let i = Arc::new(convert_image(&images[index], srgb).map_err(|m| err(format!("image {index}"), m))?);
                cache.insert((index, srgb), i.clone());
                i
            }
        };
        let wrap = match info.sampler().wrap_s() {
            ::gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
            ::gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
            ::gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        };
        Ok(ModelImage { image, wrap })
    };
    // One uv transform per material (KHR_texture_transform), applied to the uvs of its primitives.
    let mut uv_transforms: Vec<Option<Mat3>> = Vec::new();
    for (i, m) in document.materials().enumerate() {
        let name = m.name().map(str::to_string).unwrap_or_else(|| format!("material {i}"));
        let mut out = ModelMaterial::new(&name);
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        // Factors the spec keeps in 0..1: one outside is clamped, and said so.
        let mut unit = |field: &str, values: &[f32]| {
            if values.iter().any(|v| !(0.0..=1.0).contains(v)) {
                let shown: Vec<String> = values.iter().map(|v| crate::limits::fmt_f32(*v)).collect();
                model.warnings.push(format!(
                    "material \"{}\": {field} [{}] is outside 0 to 1 (glTF's range); it is clamped to it",
                    crate::limits::printable(&name),
                    shown.join(", ")
                ));
            }
        };
        unit("baseColorFactor", &[r, g, b, a]);
        unit("metallicFactor", &[pbr.metallic_factor()]);
        unit("roughnessFactor", &[pbr.roughness_factor()]);
        unit("emissiveFactor", &m.emissive_factor());
        out.base_color = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
        out.metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        // glTF's roughness is perceptual: the GGX alpha is its square.
        out.roughness = Some(pbr.roughness_factor().clamp(0.0, 1.0).powi(2));
        if let Some(t) = pbr.base_color_texture() {
            out.base_color_texture = Some(texture(t.texture(), ColorSpace::Srgb)?);
        }
        if let Some(t) = pbr.metallic_roughness_texture() {
            out.metallic_roughness_texture = Some(texture(t.texture(), ColorSpace::Linear)?);
        }
        if let Some(t) = m.normal_texture() {
            out.normal_texture = Some(texture(t.texture(), ColorSpace::Linear)?);
        }
        // KHR_materials_emissive_strength scales the factor past 1 (Blender writes its emission
        // strength there).
        let strength = m.emissive_strength().unwrap_or(1.0);
        out.emission = Vec3::from(m.emissive_factor()).clamp(Vec3::ZERO, Vec3::ONE) * strength;
        // An emission past the scene range (docs/limits.md) would be refused typed in a scene;
        // so it is here, naming the material (not clamped: the picture would be wrong).
        if !(strength.is_finite() && strength >= 0.0)
            || out.emission.max_element() as f64 > crate::limits::MAX_SCENE_VALUE
        {
            return Err(err(
                format!("material {i}"),
                format!(
                    "\"{}\": its emission (emissiveFactor x emissiveStrength {}) is outside 0 to 1e9 per channel; see docs/limits.md",
                    crate::limits::printable(&name),
                    crate::limits::fmt_f32(strength)
                ),
            ));
        }
        if let Some(ior) = m.ior().filter(|i| i.is_finite() && *i >= 1.0) {
            out.ior = ior.min(4.0);
        }
        if let Some(t) = m.transmission() {
            out.transmission = t.transmission_factor().clamp(0.0, 1.0);
            if t.transmission_texture().is_some() {
                model.warnings.push(format!(
                    "material \"{}\": KHR_materials_transmission's transmissionTexture is not supported; its factor applies",
                    crate::limits::printable(&name)
                ));
            }
        }
        if let Some(v) = m.volume() {
            let distance = v.attenuation_distance();
            if distance.is_finite() && distance > 0.0 {
                out.attenuation = Some((Vec3::from(v.attenuation_color()).clamp(Vec3::ZERO, Vec3::ONE), distance));
            }
        }
        uv_transforms.push(uv_transform(&m, &name, &mut model.warnings));
        if let Some(t) = m.emissive_texture() {
            out.emission_texture = Some(texture(t.texture(), ColorSpace::Srgb)?);
        }
        match m.alpha_mode() {
            ::gltf::material::AlphaMode::Opaque => {}
            ::gltf::material::AlphaMode::Mask | ::gltf::material::AlphaMode::Blend => {
                out.opacity = a.clamp(0.0, 1.0);
                out.opacity_from_texture_alpha = out.base_color_texture.is_some();
            }
        }
        model.materials.push(out);
    }

    // Nodes
    let roots: Vec<::gltf::Node<'_>> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            // No scene: every node that no other node names as a child is a root.
            let children: std::collections::HashSet<usize> =
                document.nodes().flat_map(|n| n.children().map(|c| c.index())).collect();
            document.nodes().filter(|n| !children.contains(&n.index())).collect()
        }
    };
    let mut stack: Vec<(::gltf::Node<'_>, Mat4, usize)> = roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > MAX_NODE_DEPTH {
            return Err(err(
                format!("node {}", node.index()),
                format!("nodes nest more than {MAX_NODE_DEPTH} deep (a cycle in the hierarchy?)"),
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() || world.to_cols_array().iter().any(|v| v.abs() > 1e9) {
            return Err(err(
                format!("node {}", node.index()),
                "its transform holds numbers that are not finite or too large".into(),
            ));
        }
        let affine = Affine3A::from_mat4(world);
        if let Some(mesh) = node.mesh() {
            read_mesh(&mesh, affine, &buffers, &uv_transforms, &mut model, path)?;
        }
        if let Some(camera) = node.camera() {
            let forward = affine.transform_vector3(-Vec3::Z).normalize_or_zero();
            let up = affine.transform_vector3(Vec3::Y).normalize_or_zero();
            let (projection, aspect) = match camera.projection() {
                ::gltf::camera::Projection::Perspective(p) => {
                    (ModelProjection::Perspective { yfov_deg: p.yfov().to_degrees() }, p.aspect_ratio())
                }
                ::gltf::camera::Projection::Orthographic(o) => {
                    (ModelProjection::Orthographic { view_height: 2.0 * o.ymag() }, Some(o.xmag() / o.ymag()))
                }
            };
            model.cameras.push(ModelCamera {
                name: camera.name().unwrap_or("").to_string(),
                position: affine.translation.into(),
                forward,
                up,
                projection,
                aspect,
            });
        }
        if let Some(light) = node.light() {
            model.light_names.push(node.name().or(light.name()).unwrap_or("").to_string());
            let color = Vec3::from(light.color()) * light.intensity();
            let position: Vec3 = affine.translation.into();
            let direction = affine.transform_vector3(-Vec3::Z).normalize_or_zero();
            model.lights.push(match light.kind() {
                ::gltf::khr_lights_punctual::Kind::Point => ModelLight::Point { position, intensity: color },
                ::gltf::khr_lights_punctual::Kind::Directional => {
                    ModelLight::Directional { direction, irradiance: color }
                }
                ::gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => ModelLight::Spot {
                    position,
                    direction,
                    intensity: color,
                    inner_deg: inner_cone_angle.to_degrees(),
                    outer_deg: outer_cone_angle.to_degrees(),
                },
            });
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    if model.meshes.is_empty() {
        return Err(err(String::new(), "the glTF scene has no triangle meshes".into()));
    }
    Ok(model)
}

/// A texture slot's texture coordinates and transform.
type Slot<'a> = (u32, Option<::gltf::texture::TextureTransform<'a>>);

/// The uv transform of a material's textures (KHR_texture_transform: translation · rotation ·
/// scale, on the file's uvs), taken from the first textured slot (base colour, then
/// metallic-roughness, emissive; the reader does not expose a normal texture's transform, so
/// the normal map follows the others); `None` when it has none. Slots with another transform,
/// or reading other texture coordinates than the first, get a warning: one set of uvs serves them all.
fn uv_transform(m: &::gltf::Material<'_>, name: &str, warnings: &mut Vec<String>) -> Option<Mat3> {
    let pbr = m.pbr_metallic_roughness();
    let slots: [(&str, Option<Slot<'_>>); 3] = [
        ("baseColorTexture", pbr.base_color_texture().map(|t| (t.tex_coord(), t.texture_transform()))),
        ("metallicRoughnessTexture", pbr.metallic_roughness_texture().map(|t| (t.tex_coord(), t.texture_transform()))),
        ("emissiveTexture", m.emissive_texture().map(|t| (t.tex_coord(), t.texture_transform()))),
    ];
    let matrix = |t: &::gltf::texture::TextureTransform<'_>| {
        let [ox, oy] = t.offset();
        let [sx, sy] = t.scale();
        let (sin, cos) = t.rotation().sin_cos();
        // The extension's matrices, column-major: T * R * S with R = [[cos, sin], [-sin, cos]].
        let m = Mat3::from_translation(Vec2::new(ox, oy))
            * Mat3::from_cols(glam::Vec3::new(cos, -sin, 0.0), glam::Vec3::new(sin, cos, 0.0), glam::Vec3::Z)
            * Mat3::from_scale(Vec2::new(sx, sy));
        m.is_finite().then_some(m)
    };
    let printable = crate::limits::printable(name);
    if let Some(coord) = m.normal_texture().map(|t| t.tex_coord()).filter(|c| *c != 0) {
        warnings.push(format!(
            "material \"{printable}\": its normalTexture reads TEXCOORD_{coord}; only TEXCOORD_0 is read, so it uses those"
        ));
    }
    let mut chosen: Option<Option<Mat3>> = None;
    for (slot, info) in slots {
        let Some((tex_coord, transform)) = info else { continue };
        let coord = transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(tex_coord);
        if coord != 0 {
            warnings.push(format!(
                "material \"{printable}\": its {slot} reads TEXCOORD_{coord}; only TEXCOORD_0 is read, so it uses those"
            ));
        }
        let this = transform.as_ref().and_then(matrix);
        match chosen {
            None => chosen = Some(this),
            Some(first) if first != this => warnings.push(format!(
                "material \"{printable}\": its {slot} has another KHR_texture_transform than its first texture; \
                 the first one's applies to all"
            )),
            Some(_) => {}
        }
    }
    chosen.flatten()
}

/// Checks that accessor `a` lies inside its buffer, so reading it cannot go out of bounds.
fn check_accessor(a: &::gltf::Accessor<'_>, buffers: &[::gltf::buffer::Data], what: &str) -> Result<(), String> {
    if a.sparse().is_some() {
        return Err(format!("{what}: sparse accessors are not supported"));
    }
    let Some(view) = a.view() else {
        return Err(format!("{what}: the accessor has no buffer view"));
    };
    let data = &buffers[view.buffer().index()];
    let element = a.size();
    let stride = view.stride().unwrap_or(element);
    let start = view.offset() + a.offset();
    let end = if a.count() == 0 { start } else { start + stride * (a.count() - 1) + element };
    if view.offset() + view.length() > data.len() || end > view.offset() + view.length() {
        return Err(format!(
            "{what}: accessor {} reads bytes {start}..{end}, beyond its buffer view or buffer ({} bytes)",
            a.index(),
            data.len()
        ));
    }
    Ok(())
}

fn read_mesh(
    mesh: &::gltf::Mesh<'_>,
    model_from_mesh: Affine3A,
    buffers: &[::gltf::buffer::Data],
    uv_transforms: &[Option<Mat3>],
    model: &mut Model,
    path: &Path,
) -> Result<(), ModelError> {
    let mesh_name = mesh.name().map(str::to_string).unwrap_or_else(|| format!("mesh {}", mesh.index()));
    for (p, primitive) in mesh.primitives().enumerate() {
        let at = format!("mesh {} (\"{}\") primitive {p}", mesh.index(), crate::limits::printable(&mesh_name));
        let err = |m: String| ModelError::new(path, at.clone(), m);
        // Points and lines carry no surface.
        let mode = primitive.mode();
        if !matches!(
            mode,
            ::gltf::mesh::Mode::Triangles | ::gltf::mesh::Mode::TriangleStrip | ::gltf::mesh::Mode::TriangleFan
        ) {
            continue;
        }
        for (_, accessor) in primitive.attributes() {
            check_accessor(&accessor, buffers, "an attribute").map_err(err)?;
        }
        if let Some(indices) = primitive.indices() {
            check_accessor(&indices, buffers, "the indices").map_err(err)?;
        }
        let reader = primitive.reader(|b| Some(&buffers[b.index()]));
        let Some(positions) = reader.read_positions() else {
            return Err(err("the primitive has no POSITION attribute".into()));
        };
        let positions: Vec<Vec3> = positions.map(Vec3::from).collect();
        let normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
        // The material's texture transform acts on the file's uvs (v down), before the flip.
        let uv_transform = primitive.material().index().and_then(|i| uv_transforms.get(i).copied().flatten());
        let uvs: Option<Vec<Vec2>> = reader.read_tex_coords(0).map(|t| {
            t.into_f32()
                .map(|[u, v]| {
                    let [u, v] = match uv_transform {
                        Some(m) => m.transform_point2(Vec2::new(u, v)).to_array(),
                        None => [u, v],
                    };
                    Vec2::new(u, 1.0 - v)
                })
                .collect()
        });
        let n = positions.len();
        if normals.as_ref().is_some_and(|x| x.len() != n) || uvs.as_ref().is_some_and(|x| x.len() != n) {
            return Err(err("its attributes have different counts".into()));
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(err(format!("index {bad} is out of range; the primitive has {n} vertices")));
        }
        let triangles: Vec<[u32; 3]> = match mode {
            ::gltf::mesh::Mode::Triangles => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            ::gltf::mesh::Mode::TriangleStrip => (2..indices.len())
                .map(|k| {
                    if k % 2 == 0 {
                        [indices[k - 2], indices[k - 1], indices[k]]
                    } else {
                        [indices[k - 1], indices[k - 2], indices[k]]
                    }
                })
                .collect(),
            _ => (2..indices.len()).map(|k| [indices[0], indices[k - 1], indices[k]]).collect(),
        };
        let material = primitive.material().index().map(|i| i as u32);
        let mut out = ModelMesh { name: mesh_name.clone(), positions, model_from_mesh, ..Default::default() };
        for t in &triangles {
            out.push_face(t, material);
            if let Some(nv) = &normals {
                out.normals.get_or_insert_with(Vec::new).extend(t.iter().map(|&i| nv[i as usize]));
            }
            if let Some(uv) = &uvs {
                out.uvs.get_or_insert_with(Vec::new).extend(t.iter().map(|&i| uv[i as usize]));
            }
        }
        if out.face_count() > 0 {
            model.meshes.push(out);
        }
    }
    Ok(())
}

/// A decoded glTF image as a texture: 8 and 16-bit channels from sRGB (colours) or linear
/// (data), floats as they are.
/// The most bytes the `image` crate allocates to decode one image (its default `Limits`), which
/// the glTF crate decodes with.
const MAX_DECODED_IMAGE_BYTES: u64 = 512 << 20;

/// Reads each image's header (a file through the gate, or a buffer view) and refuses one larger
/// than a texture may be, naming the image, its size and the limit, before anything is decoded
/// (the decoder's own refusal said only "Memory limit exceeded").
fn check_image_sizes(
    document: &::gltf::Document,
    base: &Path,
    buffers: &[::gltf::buffer::Data],
    err: &dyn Fn(String, String) -> ModelError,
) -> Result<(), ModelError> {
    use image::ImageDecoder;
    for image in document.images() {
        let (name, bytes): (String, std::borrow::Cow<[u8]>) = match image.source() {
            ::gltf::image::Source::Uri { uri, .. } => {
                let Some(file) = uri_file(base, uri) else { continue };
                let Ok(bytes) = crate::scene::files::read(&file, crate::limits::MAX_IMAGE_FILE_BYTES) else { continue };
                (format!("`{}`", crate::limits::printable(uri)), bytes.into())
            }
            ::gltf::image::Source::View { view, .. } => {
                let Some(buffer) = buffers.get(view.buffer().index()) else { continue };
                let Some(bytes) =
                    view.offset().checked_add(view.length()).and_then(|end| buffer.get(view.offset()..end))
                else {
                    continue;
                };
                (format!("in buffer view {}", view.index()), bytes.into())
            }
        };
        let reader = image::ImageReader::new(std::io::Cursor::new(&bytes[..])).with_guessed_format();
        let Some(decoder) = reader.ok().and_then(|r| r.into_decoder().ok()) else { continue };
        let (w, h) = decoder.dimensions();
        let max = crate::limits::MAX_IMAGE_SIDE;
        let at = format!("image {}", image.index());
        if w > max || h > max {
            return Err(err(
                at,
                format!("{name} is {w} x {h} texels; an image texture has at most {max} per side (docs/limits.md)"),
            ));
        }
        let decoded = decoder.total_bytes();
        if decoded > MAX_DECODED_IMAGE_BYTES {
            return Err(err(
                at,
                format!(
                    "{name} is {w} x {h} texels, {} decoded, more than the {} the glTF reader decodes per image; make it smaller",
                    crate::limits::fmt_bytes(decoded),
                    crate::limits::fmt_bytes(MAX_DECODED_IMAGE_BYTES)
                ),
            ));
        }
    }
    Ok(())
}

fn convert_image(data: &::gltf::image::Data, srgb: bool) -> Result<ImageTexture, String> {
    use ::gltf::image::Format as F;
    let (channels, bytes_per) = match data.format {
        F::R8 => (1, 1),
        F::R8G8 => (2, 1),
        F::R8G8B8 => (3, 1),
        F::R8G8B8A8 => (4, 1),
        F::R16 => (1, 2),
        F::R16G16 => (2, 2),
        F::R16G16B16 => (3, 2),
        F::R16G16B16A16 => (4, 2),
        F::R32G32B32FLOAT => (3, 4),
        F::R32G32B32A32FLOAT => (4, 4),
    };
    let (w, h) = (data.width, data.height);
    let max = crate::limits::MAX_IMAGE_SIDE;
    if w == 0 || h == 0 || w > max || h > max {
        return Err(format!("the image is {w}x{h} texels; a texture needs 1 to {max} per side"));
    }
    let texel_bytes = channels * bytes_per;
    if data.pixels.len() < w as usize * h as usize * texel_bytes {
        return Err("the decoded image holds fewer pixels than its size".into());
    }
    let value = |t: &[u8], c: usize| -> f32 {
        let b = &t[c * bytes_per..(c + 1) * bytes_per];
        match bytes_per {
            1 => b[0] as f32 / 255.0,
            2 => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
            _ => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    };
    let decode = |v: f32| if srgb && bytes_per < 4 { srgb_to_linear(v as f64) as f32 } else { v };
    let texels = data
        .pixels
        .chunks_exact(texel_bytes)
        .take(w as usize * h as usize)
        .map(|t| {
            let c = |k: usize| if k < channels { value(t, k) } else { value(t, channels.min(3) - 1) };
            let (r, g, b) = if channels <= 2 { (c(0), c(0), c(0)) } else { (c(0), c(1), c(2)) };
            let a = if channels == 4 || channels == 2 { value(t, channels - 1) } else { 1.0 };
            [decode(r), decode(g), decode(b), a]
        })
        .collect();
    Ok(ImageTexture { width: w, height: h, texels })
}
