//! Meshes from files (OBJ, PLY, glTF, ...), their subdivision and materials, and bicubic patches.

use std::ops::Range;
use std::path::Path;

use glam::{Affine3A, Vec3};
use toml::Spanned;

use super::params::TexelRole;
use super::shapes::apply_with_normals;
use super::shapes::is_degenerate;
use super::values::beyond_scene_range;
use super::values::transformed_out_of_range;
use super::{span_of, Builder, Result};
use crate::limits::{fmt_f32, printable_message, MIN_PATCH_FLATNESS};
use crate::scene::error::SceneError;
use crate::scene::format::ShapeDef;
use crate::scene::image_texture::ImageTexture;
use crate::scene::kinds;
use crate::scene::material::{
    Channel, ColorParam, ImageProjection, MaterialDesc, MaterialKind, NormalMod, Roughness, ScalarParam, TextureDesc,
    TextureKind, TextureSpace,
};
use crate::scene::model::patch;
use crate::scene::model::subdivide::{subdivide, Scheme, MAX_LEVELS};
use crate::scene::model::{
    load_model, mesh_triangles, Format, LoadOptions, ModelError, ModelImage, ModelLight, ModelMaterial, Shading,
};
use crate::scene::{Geometry, LightDesc, LightKind, Shape, Triangle};

impl Builder<'_> {
    /// A model file (any format of `model::Format`) as triangles, materials and lights.
    pub(super) fn mesh(
        &mut self,
        file: &Spanned<String>,
        s: &ShapeDef,
        object: &str,
        material: Option<u32>,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        let base = self.src.path.parent().unwrap_or(Path::new(""));
        let model_path = base.join(file.get_ref());
        let location = self.src.at(&file.span());
        let model_error = |e: ModelError| {
            if e.not_found {
                SceneError::MeshNotFound {
                    location: location.clone(),
                    object: object.to_string(),
                    looked_for: model_path.clone(),
                }
            } else {
                SceneError::Obj {
                    obj_location: e.location(),
                    message: e.message,
                    object: object.to_string(),
                    location: location.clone(),
                }
            }
        };
        let is_patches = Format::from_path(&model_path) == Some(Format::Patches);
        let flatness = match &s.flatness {
            Some(f) if !is_patches => {
                return Err(self.invalid(
                    &f.span(),
                    object,
                    "`flatness` applies to Bezier patch files (.bpt) only".into(),
                ))
            }
            Some(f) => self.flatness(f, object)?,
            None => kinds::FLATNESS.number() as f32,
        };
        let model = load_model(&model_path, &LoadOptions { flatness }).map_err(model_error)?;
        let shading = self.shading(s, object)?;
        let subdivision = self.subdivision(s, object)?;
        for w in &model.warnings {
            self.warnings.push(format!("{location}: {object}: {w}"));
        }

        // Materials: the shape's own for every face, else the file's (created as used), else a
        // default diffuse one.
        let mut scene_material: Vec<Option<u32>> = vec![None; model.materials.len()];
        let mut default_material = None;
        let stem = model_path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
        let only = match &s.shape_index {
            Some(i) => {
                let n = model.meshes.len();
                let index = *i.get_ref();
                if index < 0 || index as usize >= n {
                    let message = format!("`shape_index` is {index}; the file holds {n} mesh(es), numbered from 0");
                    return Err(self.invalid(&i.span(), object, message));
                }
                Some(index as usize)
            }
            None => None,
        };
        let mut triangles = Vec::new();
        for (m, mesh) in model.meshes.iter().enumerate() {
            if only.is_some_and(|k| k != m) {
                continue;
            }
            let subdivided;
            let mesh = match subdivision {
                Some((scheme, levels, crease)) => {
                    subdivided = subdivide(mesh, scheme, levels, crease).map_err(|e| {
                        self.invalid(
                            &s.subdivision.as_ref().map_or(file.span(), |x| x.span()),
                            object,
                            format!("mesh {m} of {}: {e}", printable_message(&model_path.display().to_string())),
                        )
                    })?;
                    &subdivided
                }
                None => mesh,
            };
            triangles.extend(mesh_triangles(mesh, shading));
        }
        let total = triangles.len();
        let mut skipped = 0;
        for t in triangles {
            let id = match (material, t.material) {
                (Some(id), _) => id,
                (None, Some(k)) => match scene_material[k as usize] {
                    Some(id) => id,
                    None => {
                        let id = self.model_material(&model.materials[k as usize], &stem);
                        self.check_model_texels(id, &file.span(), object)?;
                        scene_material[k as usize] = Some(id);
                        id
                    }
                },
                (None, None) => *default_material.get_or_insert_with(|| {
                    let id = self.add_material(
                        format!("{stem}: default"),
                        MaterialDesc::new(MaterialKind::Diffuse {
                            reflectance: ColorParam::constant(Vec3::from(kinds::REFLECTANCE.triple())),
                        }),
                    );
                    self.material_used[id as usize] = true;
                    id
                }),
            };
            let (vertices, uv, normals) = apply_with_normals(transform, t.vertices, t.uv, t.normals);
            if let Some(far) = beyond_scene_range(&vertices) {
                return Err(SceneError::Invalid {
                    location,
                    object: object.to_string(),
                    message: format!(
                        "mesh {}: {}",
                        printable_message(&model_path.display().to_string()),
                        transformed_out_of_range(far)
                    ),
                });
            }
            // Zero-area triangles are common in exported meshes and harmless to skip.
            if is_degenerate(&vertices) {
                skipped += 1;
                continue;
            }
            self.shapes.push(Shape {
                geometry: Geometry::Triangle(Triangle { vertices, uv, normals }),
                material: id,
                media: None,
            });
        }
        // Exported scenes hold meshes that are all slivers (Mitsuba loads them, as no surface):
        // such a file adds nothing, with a warning.
        if skipped == total {
            self.warnings.push(format!(
                "{location}: {object}: all {total} triangles of {} have zero area; the mesh is left out",
                printable_message(&model_path.display().to_string())
            ));
        } else if skipped > 0 {
            self.warnings.push(format!(
                "{location}: {object}: skipped {skipped} of {total} triangles of {} with zero area",
                printable_message(&model_path.display().to_string())
            ));
        }

        // Lights of the model (glTF KHR_lights_punctual), moved by the shape's transform.
        if s.lights.as_ref().map_or(kinds::MODEL_LIGHTS.flag(), |l| *l.get_ref()) {
            let t = transform.unwrap_or(Affine3A::IDENTITY);
            for light in &model.lights {
                let kind = match *light {
                    ModelLight::Point { position, intensity } => {
                        LightKind::Point { position: t.transform_point3(position), intensity }
                    }
                    ModelLight::Spot { position, direction, intensity, inner_deg, outer_deg } => {
                        let outer = outer_deg.clamp(0.01, 90.0);
                        let inner = inner_deg.clamp(0.0, outer);
                        LightKind::Spot {
                            position: t.transform_point3(position),
                            direction: t.transform_vector3(direction).normalize_or(Vec3::NEG_Y),
                            intensity,
                            cos_inner: inner.to_radians().cos(),
                            cos_outer: outer.to_radians().cos(),
                            exponent: 0.0,
                        }
                    }
                    ModelLight::Directional { direction, irradiance } => LightKind::Distant {
                        direction: t.transform_vector3(direction).normalize_or(Vec3::NEG_Y),
                        irradiance,
                        half_angle_deg: 0.0,
                        visible: true,
                    },
                };
                let finite = match &kind {
                    LightKind::Point { position, intensity } => position.is_finite() && intensity.is_finite(),
                    LightKind::Spot { position, intensity, .. } => position.is_finite() && intensity.is_finite(),
                    LightKind::Distant { irradiance, .. } => irradiance.is_finite(),
                    LightKind::Area { .. } => true,
                };
                if !finite || kind_power_negative(&kind) {
                    return Err(SceneError::Obj {
                        obj_location: printable_message(&model_path.display().to_string()),
                        message: "a light has a position or intensity that is not finite, or is negative".to_string(),
                        object: object.to_string(),
                        location,
                    });
                }
                self.lights.push(LightDesc::new(kind));
            }
        }
        if !model.cameras.is_empty() {
            self.warnings.push(format!(
                "{location}: {object}: the model's {} camera(s) are not used; the scene's [camera] applies",
                model.cameras.len()
            ));
        }
        Ok(())
    }

    /// `smooth_angle` and `file_normals` of a mesh or patch.
    pub(super) fn shading(&self, s: &ShapeDef, object: &str) -> Result<Shading> {
        let smooth_angle_deg = match &s.smooth_angle {
            Some(a) => {
                let v = self.number(a, object, "smooth_angle")?;
                if !(0.0..=180.0).contains(&v) {
                    return Err(self.invalid(
                        &a.span(),
                        object,
                        format!(
                            "`smooth_angle` is {}; it must be in [0, 180] degrees (0 keeps every face flat)",
                            fmt_f32(v)
                        ),
                    ));
                }
                v
            }
            None => kinds::SMOOTH_ANGLE.number() as f32,
        };
        let file_normals = s.file_normals.as_ref().map_or(kinds::FILE_NORMALS.flag(), |f| *f.get_ref());
        // smooth_angle = 0 asks for flat faces whatever the file says.
        Ok(Shading { file_normals: file_normals && smooth_angle_deg > 0.0, smooth_angle_deg })
    }

    /// `subdivision`, `levels` and `crease_angle` of a mesh.
    pub(super) fn subdivision(&self, s: &ShapeDef, object: &str) -> Result<Option<(Scheme, u32, Option<f32>)>> {
        let Some(scheme) = &s.subdivision else {
            for (field, span) in [("levels", span_of(&s.levels)), ("crease_angle", span_of(&s.crease_angle))] {
                if let Some(span) = span {
                    return Err(self.invalid(
                        &span,
                        object,
                        format!("`{field}` needs `subdivision = \"catmull-clark\"` or `\"loop\"`"),
                    ));
                }
            }
            return Ok(None);
        };
        let scheme = match self.one_of(scheme, object, "subdivision", kinds::SUBDIVISION.choices())? {
            "catmull-clark" => Scheme::CatmullClark,
            _ => Scheme::Loop,
        };
        let levels = match &s.levels {
            Some(l) => {
                let v = *l.get_ref();
                if !(0..=MAX_LEVELS as i64).contains(&v) {
                    return Err(self.invalid(
                        &l.span(),
                        object,
                        format!("`levels` is {v}; it must be a whole number from 0 to {MAX_LEVELS} (each level makes 4 times the faces)"),
                    ));
                }
                v as u32
            }
            None => kinds::LEVELS.number() as u32,
        };
        let crease = match &s.crease_angle {
            Some(a) => {
                let v = self.number(a, object, "crease_angle")?;
                if !(0.0..=180.0).contains(&v) {
                    return Err(self.invalid(
                        &a.span(),
                        object,
                        format!("`crease_angle` is {}; it must be in [0, 180] degrees", fmt_f32(v)),
                    ));
                }
                Some(v)
            }
            None => None,
        };
        Ok(Some((scheme, levels, crease)))
    }

    pub(super) fn flatness(&self, f: &Spanned<f64>, object: &str) -> Result<f32> {
        let v = self.number(f, object, "flatness")?;
        if v.is_nan() || (v as f64) < MIN_PATCH_FLATNESS {
            return Err(self.invalid(
                &f.span(),
                object,
                format!("`flatness` is {}; it must be at least {MIN_PATCH_FLATNESS:e} (model units between the patch and its triangles)", fmt_f32(v)),
            ));
        }
        Ok(v)
    }

    /// POV-Ray's `bicubic_patch`: 16 control points, rows of constant v, tessellated to `flatness`.
    pub(super) fn bicubic_patch(
        &mut self,
        s: &ShapeDef,
        table: &Range<usize>,
        object: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        let points = self.vertices(&s.points, table, object, 16)?;
        let points: [Vec3; 16] =
            points.try_into().map_err(|_| self.invalid(table, object, "`points` needs 16 points".into()))?;
        let flatness = match &s.flatness {
            Some(f) => self.flatness(f, object)?,
            None => kinds::FLATNESS.number() as f32,
        };
        let shading = self.shading(s, object)?;
        let span = s.points.as_ref().map_or(table.clone(), |p| p.span());
        let mesh = patch::tessellate(&[points], flatness).map_err(|m| self.invalid(&span, object, m))?;
        let mut added = 0;
        for t in mesh_triangles(&mesh, shading) {
            let (vertices, uv, normals) = apply_with_normals(transform, t.vertices, t.uv, t.normals);
            if let Some(far) = beyond_scene_range(&vertices) {
                return Err(self.invalid(&span, object, transformed_out_of_range(far)));
            }
            if is_degenerate(&vertices) {
                continue;
            }
            self.shapes.push(Shape {
                geometry: Geometry::Triangle(Triangle { vertices, uv, normals }),
                material,
                media: None,
            });
            added += 1;
        }
        if added == 0 {
            return Err(self.invalid(
                &span,
                object,
                "the patch has no area (its points are equal or on a line)".into(),
            ));
        }
        Ok(())
    }

    /// `check_texels` for the images a model's material `id` (and a mix's parts) got: its
    /// colour is a reflectance, its emission an emission, as in the scene.
    pub(super) fn check_model_texels(&self, id: u32, span: &Range<usize>, object: &str) -> Result<()> {
        let m = &self.materials[id as usize];
        if let Some(t) = m.emission.texture {
            self.check_texels(t, m.emission.value, TexelRole::NonNegative, span, object, "emission")?;
        }
        match &m.kind {
            MaterialKind::Diffuse { reflectance } | MaterialKind::Plastic { reflectance, .. } => {
                if let Some(t) = reflectance.texture {
                    self.check_texels(t, reflectance.value, TexelRole::Fraction, span, object, "reflectance")?;
                }
            }
            MaterialKind::Mix { a, b, .. } => {
                self.check_model_texels(*a, span, object)?;
                self.check_model_texels(*b, span, object)?;
            }
            _ => {}
        }
        Ok(())
    }

    /// A material of an imported model as a scene material (docs/scene-format.md, "Materials of
    /// imported models"), named `<file>: <name>`; its images become textures.
    pub(super) fn model_material(&mut self, m: &ModelMaterial, file: &str) -> u32 {
        let name = format!("{file}: {}", m.name);
        let image = |b: &mut Self, img: &ModelImage, channel: Channel| -> u32 {
            b.textures.push(TextureDesc {
                kind: TextureKind::Image {
                    image: img.image.clone(),
                    wrap: img.wrap,
                    channel,
                    projection: ImageProjection::Planar,
                },
                space: TextureSpace::Uv,
                lookup_from_texture: Affine3A::IDENTITY,
            });
            b.texture_names.push(format!("{name} texture {}", b.textures.len()));
            b.texture_used.push(true);
            (b.textures.len() - 1) as u32
        };
        let reflectance = ColorParam {
            value: m.base_color,
            texture: m.base_color_texture.as_ref().map(|t| image(self, t, Channel::Rgb)),
        };
        // glTF keeps metallic in blue and roughness in green; the GGX alpha is roughness
        // squared, so the texture of alpha holds green squared (and the factor is squared).
        let (metal_tex, rough_tex) = match &m.metallic_roughness_texture {
            Some(t) => {
                let squared = ImageTexture {
                    width: t.image.width,
                    height: t.image.height,
                    texels: t.image.texels.iter().map(|c| [c[1] * c[1]; 4]).collect(),
                };
                let rough = ModelImage { image: std::sync::Arc::new(squared), wrap: t.wrap };
                (Some(image(self, t, Channel::B)), Some(image(self, &rough, Channel::R)))
            }
            None => (None, None),
        };
        let roughness =
            m.roughness.map(|alpha| Roughness { alpha: [alpha; 2], texture: rough_tex, ..Roughness::SMOOTH });
        let base_kind = match roughness {
            None => MaterialKind::Diffuse { reflectance },
            Some(r) => MaterialKind::Plastic { reflectance, ior: m.ior, roughness: r, nonlinear: false },
        };
        let emission = ColorParam {
            value: m.emission,
            texture: m.emission_texture.as_ref().map(|t| image(self, t, Channel::Rgb)),
        };
        let opacity = ScalarParam {
            value: m.opacity,
            texture: if m.opacity_from_texture_alpha {
                m.base_color_texture.as_ref().map(|t| image(self, t, Channel::Alpha))
            } else {
                None
            },
        };
        let normal = match (&m.normal_texture, &m.bump_texture) {
            (Some(t), _) => NormalMod::NormalMap { texture: image(self, t, Channel::Rgb) },
            // MTL's `-bm` scales heights in [0, 1]; one unit of height is 1/100 of a model unit.
            (None, Some((t, scale))) => NormalMod::Bump { texture: image(self, t, Channel::R), strength: 0.01 * scale },
            (None, None) => NormalMod::None,
        };
        let finish = |kind: MaterialKind| MaterialDesc { kind, emission, two_sided: false, opacity, normal };
        let metallic = m.metallic > 0.0 || metal_tex.is_some();
        // glTF's transmission passes light through the dielectric part (not the metal): a mix of
        // the opaque material and smooth or rough glass of the material's index, by the factor.
        let transmission = m.transmission * (1.0 - m.metallic.clamp(0.0, 1.0));
        let name_opaque = if transmission > 0.0 { format!("{name} (opaque part)") } else { name.clone() };
        let id = match roughness {
            Some(roughness) if metallic => {
                let (eta, k) = metal_eta_k(m.base_color);
                let conductor = MaterialKind::Conductor {
                    eta: ColorParam::constant(eta),
                    k: ColorParam::constant(k),
                    roughness,
                    tint: ColorParam::constant(Vec3::ONE),
                };
                if m.metallic >= 1.0 && metal_tex.is_none() {
                    self.add_material(name_opaque, finish(conductor))
                } else {
                    let a = self.add_material(format!("{name} (dielectric part)"), finish(base_kind));
                    let b = self.add_material(format!("{name} (metal part)"), finish(conductor));
                    self.material_used[a as usize] = true;
                    self.material_used[b as usize] = true;
                    let weight = ScalarParam { value: m.metallic, texture: metal_tex };
                    self.add_material(name_opaque, finish(MaterialKind::Mix { a, b, weight }))
                }
            }
            _ => self.add_material(name_opaque, finish(base_kind)),
        };
        self.material_used[id as usize] = true;
        if transmission <= 0.0 {
            return id;
        }
        let glass = MaterialKind::Dielectric { ior: m.ior, roughness: roughness.unwrap_or(Roughness::SMOOTH) };
        let glass = self.add_material(format!("{name} (transmission)"), finish(glass));
        self.material_used[glass as usize] = true;
        let weight = ScalarParam { value: transmission.min(1.0), texture: None };
        let mixed = self.add_material(name, finish(MaterialKind::Mix { a: id, b: glass, weight }));
        self.material_used[mixed as usize] = true;
        mixed
    }
}

/// Complex index of refraction of a metal whose normal-incidence reflectance is `r` per channel,
/// with an edge tint equal to it (Gulbrandsen 2014, "Artist friendly metallic Fresnel").
fn metal_eta_k(r: Vec3) -> (Vec3, Vec3) {
    let f = |r: f32, g: f32| {
        let r = r.clamp(0.0, 0.99);
        let sr = r.sqrt();
        let n = g * (1.0 - r) / (1.0 + r) + (1.0 - g) * (1.0 + sr) / (1.0 - sr);
        let k2 = ((n + 1.0) * (n + 1.0) * r - (n - 1.0) * (n - 1.0)) / (1.0 - r);
        (n, k2.max(0.0).sqrt())
    };
    let (x, y, z) = (f(r.x, r.x), f(r.y, r.y), f(r.z, r.z));
    (Vec3::new(x.0, y.0, z.0), Vec3::new(x.1, y.1, z.1))
}

/// True when a light's intensity or irradiance has a negative channel.
fn kind_power_negative(kind: &LightKind) -> bool {
    match kind {
        LightKind::Point { intensity, .. } | LightKind::Spot { intensity, .. } => intensity.min_element() < 0.0,
        LightKind::Distant { irradiance, .. } => irradiance.min_element() < 0.0,
        LightKind::Area { .. } => false,
    }
}
