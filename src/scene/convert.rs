//! From the file as written (`format`) to the `Scene` the renderer uses: checks every value,
//! applies defaults, turns quads, boxes, meshes and area lights into triangles and materials.

mod csg;
mod objects;
mod sky;

use std::ops::Range;
use std::path::Path;

use glam::{Affine3A, Mat3, Vec2, Vec3};
use toml::Spanned;

use super::error::{backticked, object_name, suggest, SceneError, Source};
use super::format::{
    AtmosphereDef, EnvironmentDef, FogDef, LightDef, MaterialDef, MediumDef, ParamDef, RainbowDef, SceneFile, ShapeDef,
    TextureDef, TransformDef, Vec3Def,
};
use super::image_texture::{load_image_texture, ColorSpace, ImageTexture, Wrap};
use super::material::{
    Channel, ColorParam, MaterialDesc, MaterialKind, NormalMod, Roughness, ScalarParam, TextureDesc, TextureKind,
    TextureSpace,
};
use super::model::patch;
use super::model::subdivide::{subdivide, Scheme, MAX_LEVELS};
use super::model::{
    load_model, mesh_triangles, Format, LoadOptions, ModelError, ModelImage, ModelLight, ModelMaterial, Shading,
};
use super::pattern::{parse_pattern, ColorMap, PatternDesc, PatternKind, PATTERN_FIELDS};
use super::voxel::load_voxel_grid;
use super::{
    Analytic, AnalyticKind, Camera, Density, Environment, Geometry, Integrator, LightDesc, LightKind, MediumDesc,
    MediumInterface, Phase, PhotonSettings, Projection, RenderSettings, Scene, SceneOrigins, Shape, Sphere, ThinLens,
    Triangle,
};
use crate::layout::constants::{ADAPTIVE_MAX_RAYS, MIX_MAX_DEPTH};
use crate::limits::{
    fmt_f32, fmt_number, printable, printable_message, MAX_APERTURE_BLADES, MAX_DEPTH, MAX_ENVIRONMENT_TEXELS,
    MAX_GATHER_RAYS, MAX_IMAGE_SIDE, MAX_IOR, MAX_LIGHT_GRID, MAX_MEDIUM_COEFFICIENT, MAX_PASSES, MAX_PHOTON_PATHS,
    MAX_PIXELS, MAX_SCENE_VALUE, MAX_SPOT_TIGHTNESS, MAX_SPP, MIN_FOV_DEGREES, MIN_PATCH_FLATNESS, MIN_SPHERE_RADIUS,
};

type Result<T> = std::result::Result<T, SceneError>;

/// Defaults of the format; `docs/scene-format.md` lists the same numbers.
const DEFAULT_UP: Vec3 = Vec3::Y;
const DEFAULT_RESOLUTION: [u32; 2] = [512, 512];
const DEFAULT_SPP: u32 = 4;
const DEFAULT_PASSES: u32 = 4;
const DEFAULT_MAX_DEPTH: u32 = 16;
const DEFAULT_REFLECTANCE: f32 = 0.8;
const DEFAULT_IOR: f32 = 1.5;
/// Unused by orthographic and latlong cameras; kept so `Camera::fov_deg` is always valid.
const DEFAULT_FOV: f32 = 40.0;
/// Spot lights: the inner angle is this fraction of the outer one unless given (Mitsuba 3's
/// default beam width); POV-Ray's defaults for `radius`, `falloff` and `tightness`.
const DEFAULT_INNER_FRACTION: f32 = 0.75;
const POV_SPOT_RADIUS: f32 = 30.0;
const POV_SPOT_FALLOFF: f32 = 45.0;

const MATERIAL_TYPES: &[&str] = &["diffuse", "mirror", "dielectric", "conductor", "plastic", "mix", "null"];

/// Complex indices of refraction (eta, k) of common metals at the wavelengths of the R, G and B
/// primaries (about 650, 550 and 450 nm), from published optical constants: gold, silver and
/// copper after Johnson and Christy (1972), aluminium after Rakic (1995), the others from
/// refractiveindex.info's tables of Palik's data (rounded; RGB rendering has no spectrum).
const METAL_PRESETS: &[(&str, [f32; 3], [f32; 3])] = &[
    ("gold", [0.143, 0.374, 1.442], [3.983, 2.385, 1.603]),
    ("silver", [0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
    ("copper", [0.200, 0.924, 1.102], [3.912, 2.452, 2.142]),
    ("aluminium", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    ("aluminum", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
    ("chrome", [3.18, 3.18, 2.22], [3.30, 3.33, 3.05]),
    ("iron", [2.91, 2.95, 2.59], [3.08, 2.93, 2.77]),
    ("platinum", [2.38, 2.08, 1.85], [4.26, 3.72, 3.15]),
    ("titanium", [2.74, 2.54, 2.16], [3.82, 3.43, 2.98]),
];
const TEXTURE_TYPES: &[&str] = &["constant", "image", "pattern", "voxels"];
const TEXTURE_SPACES: &[&str] = &["uv", "world"];
const SHAPE_TYPES: &[&str] = &[
    "quad",
    "triangle",
    "sphere",
    "box",
    "mesh",
    "bicubic_patch",
    "plane",
    "disc",
    "cylinder",
    "cone",
    "torus",
    "superellipsoid",
    "csg",
];
/// Mesh defaults (docs/scene-format.md): faces whose normals differ by up to this share vertex
/// normals where the file has none (Blender's auto-smooth default); subdivision levels; the
/// flatness of Bezier patches in model units.
const DEFAULT_SMOOTH_ANGLE: f32 = 30.0;
const DEFAULT_LEVELS: i64 = 2;
const DEFAULT_FLATNESS: f64 = 0.01;
const SUBDIVISION_SCHEMES: &[&str] = &["catmull-clark", "loop"];
/// Smallest superellipsoid exponent: below it the shape is a box to float precision and its
/// gauge's powers (2/e) pass 200.
const SUPERELLIPSOID_MIN_EXPONENT: f64 = 0.01;
const LIGHT_TYPES: &[&str] = &["area", "point", "spot", "distant"];
const CAMERA_TYPES: &[&str] = &["perspective", "orthographic", "latlong"];
const ENVIRONMENT_TYPES: &[&str] = &["map", "gradient", "uniform", "sky"];
/// Rows of the image a gradient sky is drawn into (its colours vary with elevation only).
const GRADIENT_ROWS: u32 = 512;
const AREA_LIGHT_SHAPES: &[&str] = &["quad", "sphere", "disc"];

/// What a texture parameter's values must be, as the same parameter typed in the scene.
#[derive(Clone, Copy)]
enum TexelRole<'w> {
    /// A fraction of light per channel, [0, 1] (reflectance, transmittance).
    Fraction,
    /// Finite and >= 0 (emission, conductor eta and k).
    NonNegative,
    /// A number in [min, max]; `what` says the range as the scene's message does.
    Scalar { min: f32, max: f32, what: &'w str },
}

/// The scene of a parsed file, and which shapes each `[[shapes]]` and `[[lights]]` entry became.
pub(crate) fn convert_with_origins(file: SceneFile, src: &Source<'_>) -> Result<(Scene, SceneOrigins)> {
    let mut origins = SceneOrigins::default();
    let mut builder = Builder {
        src,
        materials: Vec::new(),
        material_names: Vec::new(),
        material_used: Vec::new(),
        textures: Vec::new(),
        texture_names: Vec::new(),
        texture_used: Vec::new(),
        shapes: Vec::new(),
        lights: Vec::new(),
        warnings: Vec::new(),
        media: Vec::new(),
        medium_names: Vec::new(),
        atmosphere: None,
        context: String::new(),
    };

    let Some(camera) = &file.camera else {
        return Err(SceneError::MissingCamera { location: src.path.display().to_string() });
    };
    let (camera, blur_samples) = builder.camera(camera)?;
    let mut render = builder.render(file.render.as_ref())?;
    // POV-Ray's blur_samples: lens samples per pixel, here over all passes.
    if let Some(samples) = blur_samples {
        render.spp = render.spp.max(samples.div_ceil(render.passes));
    }
    let photons = builder.photons(file.photons.as_ref())?;

    // Textures, then materials, in file order, so ids follow the file.
    let mut textures: Vec<_> = file.textures.iter().collect();
    textures.sort_by_key(|(key, _)| key.span().start);
    for (key, def) in textures {
        builder.texture(key, def)?;
    }
    let mut materials: Vec<_> = file.materials.iter().collect();
    materials.sort_by_key(|(key, _)| key.span().start);
    for (key, def) in materials {
        builder.material(key, def)?;
    }

    // Media, then the atmosphere, before the shapes that name them.
    let mut media: Vec<_> = file.media.iter().collect();
    media.sort_by_key(|(key, _)| key.span().start);
    for (key, def) in media {
        builder.medium(key, def)?;
    }
    if let Some(def) = &file.atmosphere {
        builder.atmosphere(def)?;
    }
    if let Some(def) = &file.fog {
        builder.fog(def, file.atmosphere.is_some())?;
    }

    for (index, shape) in file.shapes.iter().enumerate() {
        let first = builder.shapes.len();
        builder.shape(index, shape)?;
        origins.shapes.push(first..builder.shapes.len());
    }
    for (index, light) in file.lights.iter().enumerate() {
        let first = builder.shapes.len();
        builder.light(index, light)?;
        origins.lights.push(first..builder.shapes.len());
    }
    let (objects, instances) = builder.objects(&file.objects, &file.instances, &mut origins.instances)?;
    let environment = match (&file.environment, &file.rainbow) {
        (Some(def), rainbow) => Some(builder.environment(def, rainbow.as_ref())?),
        (None, Some(rainbow)) => {
            return Err(src.invalid(
                &rainbow.span(),
                "[rainbow]",
                "a rainbow is drawn into the environment; add an `[environment]` (e.g. `type = \"sky\"`)".to_string(),
            ))
        }
        (None, None) => None,
    };

    // Warnings
    for (name, used) in builder.material_names.iter().zip(&builder.material_used) {
        if !used {
            builder.warnings.push(format!("material \"{name}\" is defined but no shape uses it"));
        }
    }
    for (name, used) in builder.texture_names.iter().zip(&builder.texture_used) {
        if !used {
            builder.warnings.push(format!("texture \"{name}\" is defined but no material uses it"));
        }
    }
    let has_light = builder.shapes.iter().any(|s| builder.materials[s.material as usize].emits())
        || builder.lights.iter().any(|l| match l.kind {
            LightKind::Point { intensity, .. } | LightKind::Spot { intensity, .. } => intensity.max_element() > 0.0,
            LightKind::Distant { irradiance, .. } => irradiance.max_element() > 0.0,
            LightKind::Area { .. } => false,
        })
        || environment.as_ref().is_some_and(|e| e.image.texels.iter().any(|t| t[..3].iter().any(|&c| c > 0.0)));
    if !has_light {
        builder.warnings.push("scene has no lights; the image will be black".to_string());
    }

    let name = src.path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let scene = Scene {
        name,
        path: src.path.to_path_buf(),
        camera,
        render,
        photons,
        materials: builder.materials,
        material_names: builder.material_names,
        textures: builder.textures,
        shapes: builder.shapes,
        lights: builder.lights,
        environment,
        warnings: builder.warnings,
        media: builder.media,
        medium_names: builder.medium_names,
        atmosphere: builder.atmosphere,
        objects,
        instances,
        // Filled in by `parse_scene_in`, which saw every file read.
        inputs: Vec::new(),
    };
    Ok((scene, origins))
}

struct Builder<'a> {
    src: &'a Source<'a>,
    materials: Vec<MaterialDesc>,
    material_names: Vec<String>,
    material_used: Vec<bool>,
    textures: Vec<TextureDesc>,
    texture_names: Vec<String>,
    texture_used: Vec<bool>,
    shapes: Vec<Shape>,
    lights: Vec<LightDesc>,
    warnings: Vec<String>,
    media: Vec<MediumDesc>,
    medium_names: Vec<String>,
    atmosphere: Option<u32>,
    /// Put before the names of shapes in messages: `objects.NAME ` inside an object, else empty.
    context: String,
}

/// A field as written: its name, and its span when present.
type Present<'f> = (&'static str, Option<Range<usize>>);

fn span_of<T>(field: &Option<Spanned<T>>) -> Option<Range<usize>> {
    field.as_ref().map(|f| f.span())
}

impl Builder<'_> {
    fn invalid(&self, span: &Range<usize>, object: &str, message: String) -> SceneError {
        self.src.invalid(span, object, message)
    }

    /// The field, or an error at the table's line saying what to add.
    fn require<'f, T>(
        &self,
        field: &'f Option<Spanned<T>>,
        table: &Range<usize>,
        object: &str,
        name: &str,
        example: &str,
    ) -> Result<&'f Spanned<T>> {
        field
            .as_ref()
            .ok_or_else(|| self.invalid(table, object, format!("missing field `{name}`; add it, e.g. `{example}`")))
    }

    /// Rejects fields that exist in the format but not for this `type`.
    fn only_fields(&self, object: &str, what: &str, present: &[Present<'_>], allowed: &[&str]) -> Result<()> {
        for (name, span) in present {
            if let Some(span) = span {
                if !allowed.contains(name) {
                    return Err(self.invalid(
                        span,
                        object,
                        format!("`{name}` does not apply to {what} (it takes {})", backticked(allowed)),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks an entry's `group` (docs/scene-format.md, "Groups"): a name of 1 to 64 characters
    /// with no control characters, on a top-level `[[shapes]]`, `[[lights]]` or `[[instances]]`
    /// entry only. Groups are the editor's folders: the scene is already flat, so the renderer
    /// reads nothing more from them.
    fn group(&self, group: &Option<Spanned<String>>, object: &str, top_level: bool) -> Result<()> {
        let Some(group) = group else { return Ok(()) };
        if !top_level {
            return Err(self.invalid(
                &group.span(),
                object,
                "`group` applies only to top-level [[shapes]], [[lights]] and [[instances]] entries, not to an \
                 object's shapes or a csg's children; remove it"
                    .to_string(),
            ));
        }
        let name = group.get_ref();
        if name.is_empty() || name.chars().count() > 64 || name.chars().any(char::is_control) {
            return Err(self.invalid(
                &group.span(),
                object,
                "a `group` is a name of 1 to 64 characters with no control characters".to_string(),
            ));
        }
        Ok(())
    }

    /// A `type` (or `shape`) value that must be one of `valid`.
    fn one_of<'v>(&self, value: &Spanned<String>, object: &str, field: &str, valid: &[&'v str]) -> Result<&'v str> {
        let given = value.get_ref().as_str();
        if let Some(hit) = valid.iter().find(|v| **v == given) {
            return Ok(hit);
        }
        let given = printable(given);
        let hint = match suggest(&given, valid) {
            Some(best) => format!("did you mean \"{best}\"?"),
            None => format!("use one of {}", valid.iter().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", ")),
        };
        Err(self.invalid(&value.span(), object, format!("unknown {field} \"{given}\" ({hint})")))
    }

    /// A finite number within the scene range, +-`MAX_SCENE_VALUE`.
    fn number(&self, value: &Spanned<f64>, object: &str, field: &str) -> Result<f32> {
        let v = *value.get_ref();
        if !v.is_finite() {
            return Err(self.invalid(&value.span(), object, format!("`{field}` is {v}; give a finite number")));
        }
        if v.abs() > MAX_SCENE_VALUE {
            return Err(self.invalid(&value.span(), object, out_of_scene_range(field, v)));
        }
        Ok(v as f32)
    }

    /// A point or direction: three finite numbers, never a single number.
    fn point(&self, value: &Spanned<Vec3Def>, object: &str, field: &str) -> Result<Vec3> {
        if value.get_ref().scalar {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` must be an array of 3 numbers [x, y, z]"),
            ));
        }
        self.vector(value, object, field)
    }

    /// Three finite numbers; a single number `v` means `[v, v, v]`.
    fn vector(&self, value: &Spanned<Vec3Def>, object: &str, field: &str) -> Result<Vec3> {
        let v = value.get_ref().value;
        if let Some(bad) = v.iter().find(|c| !c.is_finite()) {
            return Err(self.invalid(&value.span(), object, format!("`{field}` contains {bad}; give finite numbers")));
        }
        if let Some(big) = v.iter().find(|c| c.abs() > MAX_SCENE_VALUE) {
            return Err(self.invalid(&value.span(), object, out_of_scene_range(field, *big)));
        }
        Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
    }

    /// An RGB triple that must be >= 0, and <= 1 when `at_most_one` (albedos and tints).
    fn color(&self, value: &Spanned<Vec3Def>, object: &str, field: &str, at_most_one: bool) -> Result<[f32; 3]> {
        let c = self.vector(value, object, field)?;
        if c.min_element() < 0.0 {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is negative ({}); it must be >= 0 in every channel", vec3_text(c)),
            ));
        }
        if at_most_one && c.max_element() > 1.0 {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is above 1 ({}); it is a fraction of light, in [0, 1] per channel", vec3_text(c)),
            ));
        }
        Ok(c.to_array())
    }

    /// A whole number in `min..=max`; `unit` follows the numbers in the message (" photon
    /// paths"), `hint` follows a number below the minimum.
    #[allow(clippy::too_many_arguments)]
    fn integer(
        &self,
        value: &Spanned<i64>,
        object: &str,
        field: &str,
        min: u32,
        max: u32,
        unit: &str,
        hint: &str,
    ) -> Result<u32> {
        let v = *value.get_ref();
        if v < min as i64 {
            let message = format!("`{field}` is {v}; it must be at least {min}{unit} (and at most {max}){hint}");
            return Err(self.invalid(&value.span(), object, message));
        }
        if v > max as i64 {
            let message = format!("`{field}` is {v}; it must be at most {max}{unit} (see docs/limits.md)");
            return Err(self.invalid(&value.span(), object, message));
        }
        Ok(v as u32)
    }

    // Camera and render settings

    /// The camera, and POV-Ray's `blur_samples` when given (it raises the samples per pixel).
    fn camera(&mut self, def: &Spanned<super::format::CameraDef>) -> Result<(Camera, Option<u32>)> {
        let object = "[camera]";
        let table = def.span();
        let c = def.get_ref();
        let kind = match &c.r#type {
            Some(t) => self.one_of(t, object, "type", CAMERA_TYPES)?,
            None => "perspective",
        };
        let present = [
            ("type", span_of(&c.r#type)),
            ("position", span_of(&c.position)),
            ("look_at", span_of(&c.look_at)),
            ("up", span_of(&c.up)),
            ("fov", span_of(&c.fov)),
            ("resolution", span_of(&c.resolution)),
            ("view_height", span_of(&c.view_height)),
            ("aperture_radius", span_of(&c.aperture_radius)),
            ("f_number", span_of(&c.f_number)),
            ("focal_length", span_of(&c.focal_length)),
            ("focal_distance", span_of(&c.focal_distance)),
            ("focal_point", span_of(&c.focal_point)),
            ("aperture_blades", span_of(&c.aperture_blades)),
            ("aperture_rotation", span_of(&c.aperture_rotation)),
            ("aperture", span_of(&c.aperture)),
            ("blur_samples", span_of(&c.blur_samples)),
        ];
        let common = ["type", "position", "look_at", "up", "resolution"];
        let lens_fields = [
            "aperture_radius",
            "f_number",
            "focal_length",
            "focal_distance",
            "focal_point",
            "aperture_blades",
            "aperture_rotation",
            "aperture",
            "blur_samples",
        ];
        match kind {
            "perspective" => self.only_fields(
                object,
                "a perspective camera",
                &present,
                &[&common[..], &["fov"], &lens_fields[..]].concat(),
            )?,
            "orthographic" => self.only_fields(
                object,
                "an orthographic camera",
                &present,
                &[&common[..], &["view_height"], &lens_fields[..]].concat(),
            )?,
            _ => self.only_fields(object, "a latlong camera (it has no lens)", &present, &common)?,
        }
        let position = self.require(&c.position, &table, object, "position", "position = [0, 1, 5]")?;
        let position = self.point(position, object, "position")?;
        let look_at_def = self.require(&c.look_at, &table, object, "look_at", "look_at = [0, 1, 0]")?;
        let look_at = self.point(look_at_def, object, "look_at")?;
        // The same test as `Camera::basis`, which the renderer uses: nearly equal points (closer
        // than 32-bit floats can tell apart) are as bad as equal ones.
        if (look_at - position).try_normalize().is_none() {
            return Err(self.invalid(
                &look_at_def.span(),
                object,
                "`look_at` equals `position` (or is too close to it to give a direction); the camera needs a \
                 direction to look in"
                    .to_string(),
            ));
        }
        let forward = (look_at - position).normalize();
        let up = match &c.up {
            Some(up_def) => self.point(up_def, object, "up")?,
            None => DEFAULT_UP,
        };
        let probe = Camera {
            position,
            look_at,
            up,
            fov_deg: 45.0,
            projection: Projection::Perspective,
            lens: None,
            width: 1,
            height: 1,
        };
        if probe.basis().is_none() {
            let (span, message) = match &c.up {
                Some(up_def) => (
                    up_def.span(),
                    "`up` is zero or parallel to the view direction; give a direction roughly perpendicular to it",
                ),
                // Looking straight up or down with no `up` given.
                None => (
                    look_at_def.span(),
                    "the view direction is vertical, parallel to the default `up` = [0, 1, 0]; add an `up` roughly \
                     perpendicular to it, e.g. `up = [0, 0, -1]`",
                ),
            };
            return Err(self.invalid(&span, object, message.to_string()));
        }
        let mut fov_deg = DEFAULT_FOV;
        let projection = match kind {
            "perspective" => {
                let fov_def = self.require(&c.fov, &table, object, "fov", "fov = 40")?;
                fov_deg = self.number(fov_def, object, "fov")?;
                let fov_range = MIN_FOV_DEGREES as f32..=(180.0 - MIN_FOV_DEGREES) as f32;
                if !fov_range.contains(&fov_deg) {
                    return Err(self.invalid(
                        &fov_def.span(),
                        object,
                        format!(
                            "`fov` is {}; the vertical field of view must be between 0 and 180 degrees (from {} to {})",
                            fmt_f32(fov_deg),
                            fov_range.start(),
                            fov_range.end()
                        ),
                    ));
                }
                Projection::Perspective
            }
            "orthographic" => {
                let h = self.require(&c.view_height, &table, object, "view_height", "view_height = 4")?;
                let view_height =
                    self.positive_measure(h, object, "view_height", "the height of the view in scene units")?;
                Projection::Orthographic { view_height }
            }
            _ => Projection::LatLong,
        };
        let lens = self.lens(c, forward, position, object)?;
        let blur_samples = match &c.blur_samples {
            Some(b) => Some(self.integer(b, object, "blur_samples", 1, MAX_SPP, " lens samples per pixel", "")?),
            None => None,
        };
        let [width, height] = match &c.resolution {
            Some(res) => {
                let values = res.get_ref();
                if values.len() != 2 {
                    return Err(self.invalid(
                        &res.span(),
                        object,
                        format!("`resolution` has {} numbers; give [width, height]", values.len()),
                    ));
                }
                let mut wh = [0; 2];
                for (out, &v) in wh.iter_mut().zip(values) {
                    if v < 1 || v > MAX_IMAGE_SIDE as i64 {
                        return Err(self.invalid(
                            &res.span(),
                            object,
                            format!(
                                "`resolution` is {values:?}; width and height must be at least 1 and at most \
                                 {MAX_IMAGE_SIDE}"
                            ),
                        ));
                    }
                    *out = v as u32;
                }
                if wh[0] as u64 * wh[1] as u64 > MAX_PIXELS {
                    return Err(self.invalid(
                        &res.span(),
                        object,
                        format!("`resolution` is {values:?}; an image has at most {MAX_PIXELS} pixels (16384x16384)"),
                    ));
                }
                wh
            }
            None => DEFAULT_RESOLUTION,
        };
        Ok((Camera { position, look_at, up, fov_deg, projection, lens, width, height }, blur_samples))
    }

    /// A number > 0; `what` says what it measures.
    fn positive_measure(&self, value: &Spanned<f64>, object: &str, field: &str, what: &str) -> Result<f32> {
        let v = self.number(value, object, field)?;
        if v <= 0.0 {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is {}; it must be > 0 ({what})", fmt_f32(v)),
            ));
        }
        Ok(v)
    }

    /// The thin lens of a camera, or `None` for a pinhole: an aperture (`aperture_radius`,
    /// `f_number` with `focal_length`, or POV-Ray's `aperture`) and a plane in focus
    /// (`focal_distance` or `focal_point`).
    fn lens(
        &mut self,
        c: &super::format::CameraDef,
        forward: Vec3,
        position: Vec3,
        object: &str,
    ) -> Result<Option<ThinLens>> {
        let apertures = [("aperture_radius", &c.aperture_radius), ("f_number", &c.f_number), ("aperture", &c.aperture)];
        let given: Vec<_> = apertures.iter().filter_map(|(n, f)| f.as_ref().map(|v| (*n, v))).collect();
        if given.len() > 1 {
            return Err(self.invalid(
                &given[1].1.span(),
                object,
                format!(
                    "give one of `aperture_radius`, `f_number` and `aperture`, not both `{}` and `{}`",
                    given[0].0, given[1].0
                ),
            ));
        }
        let Some(&(name, value)) = given.first() else {
            if let Some(span) = span_of(&c.focal_length) {
                return Err(self.invalid(
                    &span,
                    object,
                    "`focal_length` only sets the aperture with `f_number`; add `f_number = 2.8` or remove it"
                        .to_string(),
                ));
            }
            for (field, span) in [
                ("focal_distance", span_of(&c.focal_distance)),
                ("focal_point", span_of(&c.focal_point)),
                ("aperture_blades", span_of(&c.aperture_blades)),
                ("aperture_rotation", span_of(&c.aperture_rotation)),
                ("blur_samples", span_of(&c.blur_samples)),
            ] {
                if let Some(span) = span {
                    let at = self.src.at(&span);
                    self.warnings.push(format!(
                        "{at}: {object}: `{field}` has no effect without an aperture (add `aperture_radius`)"
                    ));
                }
            }
            return Ok(None);
        };
        let radius = match name {
            "aperture_radius" => self.positive_measure(value, object, name, "the radius of the lens in scene units")?,
            "f_number" => {
                let n = self.positive_measure(value, object, name, "the focal length over the aperture's diameter")?;
                let Some(fl) = &c.focal_length else {
                    return Err(self.invalid(
                        &value.span(),
                        object,
                        "`f_number` needs the lens's `focal_length` in scene units to size the aperture, e.g. \
                         `focal_length = 0.05` (a 50 mm lens in a scene in metres), or give `aperture_radius`"
                            .to_string(),
                    ));
                };
                let focal_length = self.positive_measure(fl, object, "focal_length", "scene units")?;
                let radius = focal_length as f64 / (2.0 * n as f64);
                if radius > MAX_SCENE_VALUE {
                    return Err(self.invalid(
                        &value.span(),
                        object,
                        format!(
                            "`f_number` {} with `focal_length` {} gives an aperture of radius {}, beyond the scene \
                             range, +-{MAX_SCENE_VALUE:e} (see docs/limits.md)",
                            fmt_f32(n),
                            fmt_f32(focal_length),
                            fmt_number(radius)
                        ),
                    ));
                }
                radius as f32
            }
            // POV-Ray offsets the eye by aperture/2 times lens samples within +-0.5
            // (tracepixel.cpp, JitterCameraRay): a disc of radius aperture/4.
            _ => 0.25 * self.positive_measure(value, object, name, "POV-Ray's aperture, four times the lens radius")?,
        };
        if name != "f_number" {
            if let Some(span) = span_of(&c.focal_length) {
                return Err(self.invalid(
                    &span,
                    object,
                    format!(
                        "`focal_length` only sets the aperture with `f_number`; remove it (the aperture is `{name}`)"
                    ),
                ));
            }
        }
        let focal_distance = match (&c.focal_distance, &c.focal_point) {
            (Some(_), Some(p)) => {
                return Err(self.invalid(
                    &p.span(),
                    object,
                    "give `focal_distance` or `focal_point`, not both".to_string(),
                ));
            }
            (Some(d), None) => {
                self.positive_measure(d, object, "focal_distance", "scene units along the view direction")?
            }
            (None, Some(p)) => {
                let point = self.point(p, object, "focal_point")?;
                let depth = (point - position).dot(forward);
                if depth <= 0.0 {
                    return Err(self.invalid(
                        &p.span(),
                        object,
                        format!(
                            "`focal_point` {} is not in front of the camera; give a point it looks at",
                            vec3_text(point)
                        ),
                    ));
                }
                depth
            }
            (None, None) => {
                return Err(self.invalid(
                    &value.span(),
                    object,
                    format!(
                        "`{name}` needs a plane in focus; add `focal_distance = 5` (scene units along the view) \
                         or `focal_point = [x, y, z]`"
                    ),
                ));
            }
        };
        let blades = match &c.aperture_blades {
            Some(b) => {
                let n =
                    self.integer(b, object, "aperture_blades", 0, MAX_APERTURE_BLADES, "", "; 0 is a round aperture")?;
                if n != 0 && !(3..=MAX_APERTURE_BLADES).contains(&n) {
                    return Err(self.invalid(
                        &b.span(),
                        object,
                        format!(
                            "`aperture_blades` is {n}; it must be 0 (a round aperture) or 3 to {MAX_APERTURE_BLADES}"
                        ),
                    ));
                }
                n
            }
            None => 0,
        };
        let rotation_deg = match &c.aperture_rotation {
            Some(r) => self.number(r, object, "aperture_rotation")?,
            None => 0.0,
        };
        Ok(Some(ThinLens { radius, focal_distance, blades, rotation_deg }))
    }

    fn render(&self, def: Option<&Spanned<super::format::RenderDef>>) -> Result<RenderSettings> {
        let object = "[render]";
        let mut settings = RenderSettings {
            spp: DEFAULT_SPP,
            passes: DEFAULT_PASSES,
            max_depth: DEFAULT_MAX_DEPTH,
            seed: 0,
            integrator: Integrator::default(),
        };
        let Some(def) = def else {
            return Ok(settings);
        };
        let r = def.get_ref();
        if let Some(spp) = &r.spp {
            settings.spp = self.integer(spp, object, "spp", 1, MAX_SPP, " samples per pixel", "")?;
        }
        if let Some(depth) = &r.max_depth {
            settings.max_depth = self.integer(depth, object, "max_depth", 1, MAX_DEPTH, "", "")?;
        }
        if let Some(passes) = &r.passes {
            settings.passes = self.integer(passes, object, "passes", 1, MAX_PASSES, "", "")?;
        }
        if let Some(seed) = &r.seed {
            settings.seed = self.integer(seed, object, "seed", 0, u32::MAX, "", "")?;
        }
        if let Some(name) = &r.integrator {
            let names: Vec<&str> = Integrator::NAMES.iter().map(|(n, _)| *n).collect();
            let name = self.one_of(name, object, "integrator", &names)?;
            settings.integrator = Integrator::from_name(name).expect("one_of returns one of the names");
        }
        Ok(settings)
    }

    fn photons(&self, def: Option<&Spanned<super::format::PhotonsDef>>) -> Result<Option<PhotonSettings>> {
        let object = "[photons]";
        let mut settings = PhotonSettings::default();
        let Some(def) = def else {
            return Ok(Some(settings));
        };
        let p = def.get_ref();
        if let Some(count) = &p.count {
            settings.photons = self.integer(
                count,
                object,
                "count",
                1,
                MAX_PHOTON_PATHS,
                " photon paths",
                "; set `enabled = false` to turn photon mapping off",
            )?;
        }
        if let Some(count) = &p.caustic_count {
            settings.caustic_photons =
                self.integer(count, object, "caustic_count", 1, MAX_PHOTON_PATHS, " photon paths", "")?;
        }
        let radius = |value: &Spanned<f64>, field: &str| -> Result<f32> {
            let r = self.number(value, object, field)?;
            if r <= 0.0 {
                return Err(self.invalid(
                    &value.span(),
                    object,
                    format!(
                        "`{field}` is {}; give a positive radius in scene units, or leave it out to derive one",
                        fmt_f32(r)
                    ),
                ));
            }
            Ok(r)
        };
        if let Some(r) = &p.radius {
            settings.radius = Some(radius(r, "radius")?);
        }
        if let Some(r) = &p.caustic_radius {
            settings.caustic_radius = Some(radius(r, "caustic_radius")?);
        }
        if let Some(r) = &p.volume_radius {
            settings.volume_radius = Some(radius(r, "volume_radius")?);
        }
        if let Some(rays) = &p.gather_rays {
            settings.gather_rays =
                self.integer(rays, object, "gather_rays", 0, MAX_GATHER_RAYS, "", "; 0 reads the global map directly")?;
        }
        if let Some(depth) = &p.max_depth {
            settings.max_depth = self.integer(depth, object, "max_depth", 1, MAX_DEPTH, "", "")?;
        }
        if let Some(a) = &p.alpha {
            let alpha = self.number(a, object, "alpha")?;
            if !(alpha > 0.0 && alpha < 1.0) {
                return Err(self.invalid(
                    &a.span(),
                    object,
                    format!("`alpha` is {}; it must be in (0, 1), e.g. 0.667", fmt_f32(alpha)),
                ));
            }
            settings.alpha = alpha;
        }
        if let Some(g) = &p.glossy_threshold {
            let threshold = self.number(g, object, "glossy_threshold")?;
            if !(0.0..=1.0).contains(&threshold) {
                return Err(self.invalid(
                    &g.span(),
                    object,
                    format!("`glossy_threshold` is {threshold}; it is a GGX width in [0, 1], e.g. 0.25"),
                ));
            }
            settings.glossy_threshold = threshold;
        }
        if p.enabled.as_ref().is_some_and(|e| !*e.get_ref()) {
            return Ok(None);
        }
        Ok(Some(settings))
    }

    // Materials

    fn material(&mut self, key: &Spanned<String>, def: &Spanned<MaterialDef>) -> Result<()> {
        let name = key.get_ref().clone();
        let object = format!("material \"{}\"", printable(&name));
        let m = def.get_ref();
        let kind_def = self.require(&m.r#type, &def.span(), &object, "type", "type = \"diffuse\"")?;
        let kind = self.one_of(kind_def, &object, "type", MATERIAL_TYPES)?;
        let present = [
            ("type", span_of(&m.r#type)),
            ("reflectance", span_of(&m.reflectance)),
            ("tint", span_of(&m.tint)),
            ("ior", span_of(&m.ior)),
            ("emission", span_of(&m.emission)),
            ("opacity", span_of(&m.opacity)),
            ("bump", span_of(&m.bump)),
            ("normal_map", span_of(&m.normal_map)),
            ("roughness", span_of(&m.roughness)),
            ("eta", span_of(&m.eta)),
            ("k", span_of(&m.k)),
            ("preset", span_of(&m.preset)),
            ("materials", span_of(&m.materials)),
            ("weight", span_of(&m.weight)),
        ];
        let emission = match &m.emission {
            Some(e) => self.color_param(e, &object, "emission", false)?,
            None => ColorParam::constant(Vec3::ZERO),
        };
        let opacity = match &m.opacity {
            Some(o) => self.scalar_param(o, &object, "opacity", 0.0, 1.0, "a fraction in [0, 1] (1 is opaque)")?,
            None => ScalarParam::constant(1.0),
        };
        let normal = match (&m.bump, &m.normal_map) {
            (Some(_), Some(n)) => {
                return Err(self.invalid(
                    &n.span(),
                    &object,
                    "a material takes `bump` or `normal_map`, not both".to_string(),
                ));
            }
            (Some(b), None) => {
                let what = "a texture, e.g. `bump = { texture = \"dents\", scale = 0.02 }` (scale in scene units)";
                let ParamDef::Texture { .. } = b.get_ref() else {
                    return Err(self.invalid(&b.span(), &object, format!("`bump` must be {what}")));
                };
                let p = self.scalar_param(b, &object, "bump", -f32::MAX, f32::MAX, "a finite number")?;
                NormalMod::Bump { texture: p.texture.expect("a texture parameter"), strength: p.value }
            }
            (None, Some(n)) => match n.get_ref() {
                ParamDef::Texture { name, scale: None } => {
                    let texture = self.texture_id(name, &n.span(), &object)?;
                    let role = TexelRole::Scalar { min: -f32::MAX, max: f32::MAX, what: "a finite number" };
                    self.check_texels(texture, Vec3::ONE, role, &n.span(), &object, "normal_map")?;
                    NormalMod::NormalMap { texture }
                }
                _ => {
                    return Err(self.invalid(
                        &n.span(),
                        &object,
                        "`normal_map` must be a texture, e.g. `normal_map = { texture = \"tiles_normal\" }`"
                            .to_string(),
                    ));
                }
            },
            (None, None) => NormalMod::None,
        };
        let common = ["type", "emission", "opacity", "bump", "normal_map"];
        let kind = match kind {
            "diffuse" => {
                self.only_fields(&object, "a diffuse material", &present, &[&common[..], &["reflectance"]].concat())?;
                let reflectance = match &m.reflectance {
                    Some(r) => self.color_param(r, &object, "reflectance", true)?,
                    None => ColorParam::constant(Vec3::splat(DEFAULT_REFLECTANCE)),
                };
                MaterialKind::Diffuse { reflectance }
            }
            "mirror" => {
                self.only_fields(&object, "a mirror material", &present, &[&common[..], &["tint"]].concat())?;
                let tint = match &m.tint {
                    Some(t) => self.color_param(t, &object, "tint", true)?,
                    None => ColorParam::constant(Vec3::ONE),
                };
                MaterialKind::Mirror { tint }
            }
            "dielectric" => {
                self.only_fields(
                    &object,
                    "a dielectric material",
                    &present,
                    &[&common[..], &["ior", "roughness"]].concat(),
                )?;
                let ior = self.ior(m, &object)?;
                let roughness = self.roughness(m, &object)?;
                MaterialKind::Dielectric { ior, roughness }
            }
            "conductor" => {
                let fields = [&common[..], &["eta", "k", "preset", "roughness"]].concat();
                self.only_fields(&object, "a conductor material", &present, &fields)?;
                let (eta, k) = match (&m.preset, &m.eta, &m.k) {
                    (Some(preset), None, None) => {
                        let names: Vec<&str> = METAL_PRESETS.iter().map(|(n, _, _)| *n).collect();
                        let name = self.one_of(preset, &object, "preset", &names)?;
                        let (_, eta, k) = METAL_PRESETS.iter().find(|(n, _, _)| *n == name).expect("one_of found it");
                        (ColorParam::constant(Vec3::from(*eta)), ColorParam::constant(Vec3::from(*k)))
                    }
                    (None, Some(eta), Some(k)) => {
                        (self.color_param(eta, &object, "eta", false)?, self.color_param(k, &object, "k", false)?)
                    }
                    (Some(p), _, _) => {
                        return Err(self.invalid(
                            &p.span(),
                            &object,
                            "give either `preset` or `eta` and `k`, not both".to_string(),
                        ));
                    }
                    _ => {
                        return Err(self.invalid(
                            &def.span(),
                            &object,
                            format!(
                                "a conductor needs `preset` (one of {}) or both `eta` and `k`",
                                METAL_PRESETS.iter().map(|(n, _, _)| format!("\"{n}\"")).collect::<Vec<_>>().join(", ")
                            ),
                        ));
                    }
                };
                if let ColorParam { value, texture: None } = eta {
                    if value.min_element() <= 0.0 {
                        let span = span_of(&m.eta).unwrap_or(def.span());
                        return Err(self.invalid(
                            &span,
                            &object,
                            format!("`eta` is {value}; it must be > 0 per channel"),
                        ));
                    }
                }
                let roughness = self.roughness(m, &object)?;
                MaterialKind::Conductor { eta, k, roughness }
            }
            "plastic" => {
                let fields = [&common[..], &["reflectance", "ior", "roughness"]].concat();
                self.only_fields(&object, "a plastic material", &present, &fields)?;
                let reflectance = match &m.reflectance {
                    Some(r) => self.color_param(r, &object, "reflectance", true)?,
                    None => ColorParam::constant(Vec3::splat(DEFAULT_REFLECTANCE)),
                };
                let ior = self.ior(m, &object)?;
                let roughness = self.roughness(m, &object)?;
                MaterialKind::Plastic { reflectance, ior, roughness }
            }
            "null" => {
                self.only_fields(&object, "a null material (an invisible medium boundary)", &present, &["type"])?;
                MaterialKind::Null
            }
            _ => {
                self.only_fields(&object, "a mix material", &present, &["type", "materials", "weight"])?;
                let example = "materials = [\"rust\", \"paint\"]";
                let list = self.require(&m.materials, &def.span(), &object, "materials", example)?;
                if list.get_ref().len() != 2 {
                    return Err(self.invalid(
                        &list.span(),
                        &object,
                        format!(
                            "`materials` names {} materials; a mix takes 2, e.g. `{example}`",
                            list.get_ref().len()
                        ),
                    ));
                }
                let mut ids = [0u32; 2];
                for (id, mixed) in ids.iter_mut().zip(list.get_ref()) {
                    *id = self.material_id(&Spanned::new(list.span(), mixed.clone()), &object)?;
                    if self.materials[*id as usize].kind == MaterialKind::Null {
                        return Err(self.invalid(
                            &list.span(),
                            &object,
                            format!("\"{}\" is a null material, which a mix cannot hold", printable(mixed)),
                        ));
                    }
                    if self.mix_depth(*id) + 1 > MIX_MAX_DEPTH {
                        return Err(self.invalid(
                            &list.span(),
                            &object,
                            format!("mixes nest at most {MIX_MAX_DEPTH} deep; \"{mixed}\" is already a deep mix"),
                        ));
                    }
                }
                let weight = match &m.weight {
                    Some(w) => self.scalar_param(
                        w,
                        &object,
                        "weight",
                        0.0,
                        1.0,
                        "a fraction in [0, 1] (of the second material)",
                    )?,
                    None => ScalarParam::constant(0.5),
                };
                MaterialKind::Mix { a: ids[0], b: ids[1], weight }
            }
        };
        self.add_material(name, MaterialDesc { kind, emission, opacity, normal });
        Ok(())
    }

    fn ior(&self, m: &MaterialDef, object: &str) -> Result<f32> {
        let Some(ior_def) = &m.ior else {
            return Ok(DEFAULT_IOR);
        };
        let ior = self.number(ior_def, object, "ior")?;
        if !(ior as f64 >= 1.0 / MAX_IOR && ior as f64 <= MAX_IOR) {
            return Err(self.invalid(
                &ior_def.span(),
                object,
                format!(
                    "`ior` is {}; the index of refraction must be > 0, from {} to {MAX_IOR} (glass is about 1.5)",
                    fmt_f32(ior),
                    1.0 / MAX_IOR
                ),
            ));
        }
        Ok(ior)
    }

    /// `roughness`: the GGX width alpha, one number, [along u, along v], or a texture.
    fn roughness(&mut self, m: &MaterialDef, object: &str) -> Result<Roughness> {
        let Some(def) = &m.roughness else {
            return Ok(Roughness::SMOOTH);
        };
        let span = def.span();
        let what = "`roughness` is the GGX width alpha in [0, 1]: one number, [along u, along v], or \
                    { texture = \"name\", scale = 0.3 }";
        let number = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        let (alpha, texture) = match def.get_ref() {
            toml::Value::Array(list) if list.len() == 2 => match (number(&list[0]), number(&list[1])) {
                (Some(u), Some(v)) => ([u, v], None),
                _ => return Err(self.invalid(&span, object, what.to_string())),
            },
            toml::Value::Table(t) => {
                let Some(toml::Value::String(name)) = t.get("texture") else {
                    return Err(self.invalid(&span, object, what.to_string()));
                };
                if let Some(bad) = t.keys().find(|k| *k != "texture" && *k != "scale") {
                    return Err(self.invalid(&span, object, format!("unknown field `{bad}` in `roughness`; {what}")));
                }
                let scale = match t.get("scale") {
                    Some(v) => number(v).ok_or_else(|| self.invalid(&span, object, what.to_string()))?,
                    None => 1.0,
                };
                let id = self.texture_id(name, &span, object)?;
                let role = TexelRole::Scalar { min: 0.0, max: 1.0, what: "a GGX alpha in [0, 1]" };
                self.check_texels(id, Vec3::splat(scale as f32), role, &span, object, "roughness")?;
                ([scale, scale], Some(id))
            }
            v => match number(v) {
                Some(a) => ([a, a], None),
                None => return Err(self.invalid(&span, object, what.to_string())),
            },
        };
        if let Some(bad) = alpha.iter().find(|a| !(**a >= 0.0 && **a <= 1.0)) {
            return Err(self.invalid(&span, object, format!("`roughness` is {bad}; {what}")));
        }
        Ok(Roughness { alpha: alpha.map(|a| a as f32), texture })
    }

    /// How deep the mixes under material `id` nest (0 for a material that is no mix).
    fn mix_depth(&self, id: u32) -> u32 {
        match self.materials[id as usize].kind {
            MaterialKind::Mix { a, b, .. } => 1 + self.mix_depth(a).max(self.mix_depth(b)),
            _ => 0,
        }
    }

    /// A colour parameter: a colour (checked like `color`), or `{ texture = "name" }`.
    fn color_param(
        &mut self,
        value: &Spanned<ParamDef>,
        object: &str,
        field: &str,
        at_most_one: bool,
    ) -> Result<ColorParam> {
        match value.get_ref() {
            ParamDef::Value(v) => {
                let c = self.color(&Spanned::new(value.span(), *v), object, field, at_most_one)?;
                Ok(ColorParam::constant(Vec3::from(c)))
            }
            ParamDef::Texture { name, scale } => {
                let id = self.texture_id(name, &value.span(), object)?;
                let scale = match scale {
                    Some(s) => Vec3::from(self.color(&Spanned::new(value.span(), *s), object, field, at_most_one)?),
                    None => Vec3::ONE,
                };
                let role = if at_most_one { TexelRole::Fraction } else { TexelRole::NonNegative };
                self.check_texels(id, scale, role, &value.span(), object, field)?;
                Ok(ColorParam { value: scale, texture: Some(id) })
            }
        }
    }

    /// A scalar parameter in [min, max]: a number, or `{ texture = "name" }`.
    fn scalar_param(
        &mut self,
        value: &Spanned<ParamDef>,
        object: &str,
        field: &str,
        min: f32,
        max: f32,
        what: &str,
    ) -> Result<ScalarParam> {
        let (number, texture) = match value.get_ref() {
            ParamDef::Value(v) if v.scalar => (v.value[0], None),
            ParamDef::Value(_) => {
                return Err(self.invalid(&value.span(), object, format!("`{field}` is one number, not a colour")));
            }
            ParamDef::Texture { name, scale } => {
                let texture = Some(self.texture_id(name, &value.span(), object)?);
                match scale {
                    Some(s) if s.scalar => (s.value[0], texture),
                    Some(_) => {
                        return Err(self.invalid(&value.span(), object, format!("`{field}`'s scale is one number")));
                    }
                    None => (1.0, texture),
                }
            }
        };
        let v = number as f32;
        if !(v >= min && v <= max) {
            let shown = fmt_number(number);
            return Err(self.invalid(&value.span(), object, format!("`{field}` is {shown}; it must be {what}")));
        }
        if let Some(id) = texture {
            self.check_texels(id, Vec3::splat(v), TexelRole::Scalar { min, max, what }, &value.span(), object, field)?;
        }
        Ok(ScalarParam { value: v, texture })
    }

    /// Checks the values an image texture gives parameter `field` (its texels, times `scale`,
    /// per channel) against the range the same parameter typed in the scene must have, with the
    /// same words: an EXR or HDR texel of 3 is a reflectance of 3, which `reflectance = 3` is
    /// refused as. (8- and 16-bit files hold [0, 1] already; NaN texels were made 0 at load.)
    fn check_texels(
        &self,
        id: u32,
        scale: Vec3,
        role: TexelRole<'_>,
        span: &Range<usize>,
        object: &str,
        field: &str,
    ) -> Result<()> {
        let TextureKind::Image { image, channel, .. } = &self.textures[id as usize].kind else {
            return Ok(());
        };
        let channels: &[usize] = match channel {
            Channel::Rgb => &[0, 1, 2],
            Channel::R => &[0],
            Channel::G => &[1],
            Channel::B => &[2],
            Channel::Alpha => &[3],
        };
        let name = printable(&self.texture_names[id as usize]);
        for (k, t) in image.texels.iter().enumerate() {
            for &c in channels {
                let v = t[c] * if c < 3 { scale[c] } else { scale.x };
                let problem = match role {
                    _ if v.is_infinite() => Some("give finite numbers".to_string()),
                    TexelRole::Fraction | TexelRole::NonNegative if v < 0.0 => {
                        Some("it must be >= 0 in every channel".to_string())
                    }
                    TexelRole::Fraction if v > 1.0 => {
                        Some("it is a fraction of light, in [0, 1] per channel".to_string())
                    }
                    TexelRole::NonNegative if v as f64 > MAX_SCENE_VALUE => {
                        Some(format!("give values up to the largest scene value, {MAX_SCENE_VALUE:e}"))
                    }
                    TexelRole::Scalar { min, max, what } if !(v >= min && v <= max) => {
                        Some(format!("it must be {what}"))
                    }
                    _ => None,
                };
                if let Some(problem) = problem {
                    let (x, y) = (k % image.width as usize, k / image.width as usize);
                    let shown = if v.is_infinite() { format!("{v}") } else { fmt_f32(v) };
                    let scaled = if scale == Vec3::ONE { "" } else { " (times its `scale`)" };
                    return Err(self.invalid(
                        span,
                        object,
                        format!(
                            "`{field}` is {shown} at texel ({x}, {y}) of texture \"{name}\"{scaled}; {problem} \
                             (clamp the image, or lower `scale`)"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn texture_id(&mut self, name: &str, span: &Range<usize>, object: &str) -> Result<u32> {
        if let Some(id) = self.texture_names.iter().position(|n| n == name) {
            self.texture_used[id] = true;
            return Ok(id as u32);
        }
        let hint = match suggest(name, &self.texture_names) {
            Some(best) => format!("did you mean \"{}\"?", printable(&best)),
            None => format!("define it with a [textures.{}] table", printable(name)),
        };
        Err(self.invalid(span, object, format!("unknown texture \"{}\" ({hint})", printable(name))))
    }

    // Textures

    fn texture(&mut self, key: &Spanned<String>, def: &Spanned<TextureDef>) -> Result<()> {
        let name = key.get_ref().clone();
        let object = format!("texture \"{}\"", printable(&name));
        let t = def.get_ref();
        let table = def.span();
        let kind_def = self.require(&t.r#type, &table, &object, "type", "type = \"pattern\"")?;
        let kind = self.one_of(kind_def, &object, "type", TEXTURE_TYPES)?;
        let mut present = vec![
            ("type", span_of(&t.r#type)),
            ("space", span_of(&t.space)),
            ("transform", span_of(&t.transform)),
            ("color", span_of(&t.color)),
            ("file", span_of(&t.file)),
            ("color_space", span_of(&t.color_space)),
            ("wrap", span_of(&t.wrap)),
            ("channel", span_of(&t.channel)),
            ("colors", span_of(&t.colors)),
        ];
        let pattern_fields = t.pattern_fields();
        present.extend(pattern_fields.iter().map(|(name, value)| (*name, Some(value.span()))));
        let (kind, default_space) = match kind {
            "constant" => {
                self.only_fields(&object, "a constant texture", &present, &["type", "color"])?;
                let color = self.require(&t.color, &table, &object, "color", "color = [0.8, 0.2, 0.2]")?;
                (TextureKind::Constant(Vec3::from(self.color(color, &object, "color", false)?)), TextureSpace::Uv)
            }
            "voxels" => {
                self.only_fields(&object, "a voxels texture", &present, &["type", "transform", "file"])?;
                let file = self.require(&t.file, &table, &object, "file", "file = \"volumes/smoke.pxvol\"")?;
                let base = self.src.path.parent().unwrap_or(Path::new(""));
                let path = base.join(file.get_ref());
                let grid = load_voxel_grid(&path)
                    .map_err(|e| self.invalid(&file.span(), &object, format!("{}: {e}", path.display())))?;
                (TextureKind::Voxels(std::sync::Arc::new(grid)), TextureSpace::World)
            }
            "image" => {
                let fields = ["type", "space", "transform", "file", "color_space", "wrap", "channel"];
                self.only_fields(&object, "an image texture", &present, &fields)?;
                (self.image_texture(t, &table, &object)?, TextureSpace::Uv)
            }
            _ => {
                let mut fields = vec!["type", "space", "transform", "colors"];
                fields.extend_from_slice(PATTERN_FIELDS);
                self.only_fields(&object, "a pattern texture", &present, &fields)?;
                (self.pattern_texture(t, &table, &object)?, TextureSpace::World)
            }
        };
        let space = match &t.space {
            Some(space) => match self.one_of(space, &object, "space", TEXTURE_SPACES)? {
                "uv" => TextureSpace::Uv,
                _ => TextureSpace::World,
            },
            None => default_space,
        };
        if matches!(kind, TextureKind::Image { .. }) && space != TextureSpace::Uv {
            let span = span_of(&t.space).unwrap_or(table.clone());
            return Err(self.invalid(&span, &object, "an image is looked up in `space = \"uv\"`".to_string()));
        }
        let lookup_from_texture = self.transform(t.transform.as_ref(), &object)?.unwrap_or(Affine3A::IDENTITY);
        self.textures.push(TextureDesc { kind, space, lookup_from_texture });
        self.texture_names.push(name);
        self.texture_used.push(false);
        Ok(())
    }

    fn image_texture(&mut self, t: &TextureDef, table: &Range<usize>, object: &str) -> Result<TextureKind> {
        let file = self.require(&t.file, table, object, "file", "file = \"textures/wood.png\"")?;
        let color_space = match &t.color_space {
            Some(cs) => match self.one_of(cs, object, "color_space", &["srgb", "linear"])? {
                "srgb" => ColorSpace::Srgb,
                _ => ColorSpace::Linear,
            },
            None => ColorSpace::Srgb,
        };
        let wrap = match &t.wrap {
            Some(w) => match self.one_of(w, object, "wrap", &["repeat", "clamp", "mirror"])? {
                "repeat" => Wrap::Repeat,
                "clamp" => Wrap::Clamp,
                _ => Wrap::Mirror,
            },
            None => Wrap::Repeat,
        };
        let channel = match &t.channel {
            Some(c) => match self.one_of(c, object, "channel", &["rgb", "r", "g", "b", "alpha"])? {
                "rgb" => Channel::Rgb,
                "r" => Channel::R,
                "g" => Channel::G,
                "b" => Channel::B,
                _ => Channel::Alpha,
            },
            None => Channel::Rgb,
        };
        let base = self.src.path.parent().unwrap_or(Path::new(""));
        let mut image = load_image_texture(&base.join(file.get_ref()), color_space)
            .map_err(|e| self.invalid(&file.span(), object, e.to_string()))?;
        // As the environment map does: NaN (EXR and HDR hold them) means nothing, so 0, said once.
        let mut cleared = 0usize;
        for c in image.texels.iter_mut().flatten().filter(|c| c.is_nan()) {
            *c = 0.0;
            cleared += 1;
        }
        if cleared > 0 {
            let at = self.src.at(&file.span());
            self.warnings
                .push(format!("{at}: {object}: {cleared} texel channels of the image are NaN; they are taken as 0"));
        }
        Ok(TextureKind::Image { image: std::sync::Arc::new(image), wrap, channel })
    }

    fn pattern_texture(&self, t: &TextureDef, table: &Range<usize>, object: &str) -> Result<TextureKind> {
        let fields = t.pattern_fields();
        let mut pattern_table = toml::Table::new();
        for (name, value) in &fields {
            pattern_table.insert(name.to_string(), value.get_ref().clone());
        }
        // The message names the field; point at it when it is one of the table's, else at the table.
        let at = |message: &str| -> Range<usize> {
            fields
                .iter()
                .find(|(name, _)| message.contains(&format!("`{name}`")) || message.contains(&format!("{name} \"")))
                .map(|(_, v)| v.span())
                .unwrap_or(table.clone())
        };
        let (pattern, color_map) = parse_pattern(&toml::Value::Table(pattern_table))
            .map_err(|message| self.invalid(&at(&message), object, message))?;
        let color_map = match (&t.colors, color_map) {
            (Some(colors), None) => {
                let list = colors.get_ref();
                let mut entries = Vec::new();
                for (i, c) in list.iter().enumerate() {
                    let c = self.color(&Spanned::new(colors.span(), *c), object, "colors", false)?;
                    let position = if list.len() > 1 { i as f32 / (list.len() - 1) as f32 } else { 0.0 };
                    entries.push((position, c));
                }
                ColorMap::new(entries).map_err(|message| self.invalid(&colors.span(), object, message))?
            }
            (Some(colors), Some(_)) => {
                return Err(self.invalid(
                    &colors.span(),
                    object,
                    "give either `colors` (evenly spaced) or `color_map`, not both".to_string(),
                ));
            }
            (None, Some(map)) => map,
            (None, None) => pattern.kind.default_color_map(),
        };
        Ok(TextureKind::Pattern { pattern, color_map })
    }

    fn add_material(&mut self, name: String, material: MaterialDesc) -> u32 {
        self.materials.push(material);
        self.material_names.push(name);
        self.material_used.push(false);
        (self.materials.len() - 1) as u32
    }

    fn material_id(&mut self, value: &Spanned<String>, object: &str) -> Result<u32> {
        let name = value.get_ref();
        if let Some(id) = self.material_names.iter().position(|n| n == name) {
            self.material_used[id] = true;
            return Ok(id as u32);
        }
        let shown = printable(name);
        let hint = match suggest(name, &self.material_names) {
            Some(best) => format!("did you mean \"{}\"?", printable(&best)),
            None if self.material_names.is_empty() => {
                format!("define it with a [materials.{shown}] table")
            }
            None => format!(
                "defined materials: {}; or add a [materials.{shown}] table",
                self.material_names
                    .iter()
                    .take(20)
                    .map(|n| format!("\"{}\"", printable(n)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        Err(self.invalid(&value.span(), object, format!("unknown material \"{shown}\" ({hint})")))
    }

    // Media

    fn medium(&mut self, key: &Spanned<String>, def: &Spanned<MediumDef>) -> Result<()> {
        let name = key.get_ref().clone();
        let object = format!("medium \"{}\"", printable(&name));
        let m = def.get_ref();
        if let Some(kind) = &m.r#type {
            let kind = self.one_of(kind, &object, "type", &["homogeneous", "heterogeneous"])?;
            match (kind, &m.density) {
                ("homogeneous", Some(d)) => {
                    return Err(self.invalid(
                        &d.span(),
                        &object,
                        "a `density` makes the medium heterogeneous; drop it, or say `type = \"heterogeneous\"`"
                            .to_string(),
                    ))
                }
                ("heterogeneous", None) => return Err(self.invalid(
                    &def.span(),
                    &object,
                    "a heterogeneous medium needs `density = \"name\"`, a [textures.name] pattern or voxels texture"
                        .to_string(),
                )),
                _ => {}
            }
        }
        let density = match &m.density {
            Some(name) => Some(self.density(name, &object)?),
            None => None,
        };
        let coefficient = |builder: &Self, value: &Spanned<Vec3Def>, field: &str| -> Result<Vec3> {
            let c = builder.vector(value, &object, field)?;
            if c.min_element() < 0.0 {
                return Err(builder.invalid(
                    &value.span(),
                    &object,
                    format!(
                        "`{field}` is negative ({}); a coefficient is >= 0 per channel (1 / scene unit)",
                        vec3_text(c)
                    ),
                ));
            }
            if c.max_element() > MAX_MEDIUM_COEFFICIENT {
                return Err(builder.invalid(
                    &value.span(),
                    &object,
                    format!(
                        "`{field}` is {}; coefficients are at most {} per scene unit (see docs/limits.md)",
                        vec3_text(c),
                        fmt_number(MAX_MEDIUM_COEFFICIENT as f64)
                    ),
                ));
            }
            Ok(c)
        };
        let (sigma_a, sigma_s) = match (&m.sigma_a, &m.sigma_s, &m.sigma_t, &m.albedo) {
            (None, None, Some(t), albedo) => {
                let sigma_t = coefficient(self, t, "sigma_t")?;
                let albedo = match albedo {
                    Some(a) => Vec3::from(self.color(a, &object, "albedo", true)?),
                    None => Vec3::ONE,
                };
                (sigma_t * (Vec3::ONE - albedo), sigma_t * albedo)
            }
            (a, s, None, None) if a.is_some() || s.is_some() => (
                a.as_ref().map_or(Ok(Vec3::ZERO), |a| coefficient(self, a, "sigma_a"))?,
                s.as_ref().map_or(Ok(Vec3::ZERO), |s| coefficient(self, s, "sigma_s"))?,
            ),
            (_, _, None, Some(albedo)) => {
                return Err(self.invalid(
                    &albedo.span(),
                    &object,
                    "`albedo` goes with `sigma_t`; give `sigma_t` and `albedo`, or `sigma_a` and `sigma_s`".to_string(),
                ))
            }
            (None, None, None, None) => {
                return Err(self.invalid(
                    &def.span(),
                    &object,
                    "a medium needs `sigma_t` (and `albedo`) or `sigma_a` and `sigma_s`, e.g. `sigma_t = 0.1`"
                        .to_string(),
                ))
            }
            _ => {
                let span = span_of(&m.sigma_t).unwrap_or(def.span());
                return Err(self.invalid(
                    &span,
                    &object,
                    "give either `sigma_t` (with `albedo`) or `sigma_a` and `sigma_s`, not both".to_string(),
                ));
            }
        };
        let emission = match &m.emission {
            Some(e) => {
                let c = Vec3::from(self.color(e, &object, "emission", false)?);
                // Emission is estimated at collisions, so a channel without extinction has none.
                let st = sigma_a + sigma_s;
                if (0..3).any(|i| c[i] > 0.0 && st[i] <= 0.0) {
                    return Err(self.invalid(
                        &e.span(),
                        &object,
                        format!(
                            "`emission` ({}) is positive in a channel where the medium has no extinction ({}); give that channel some `sigma_a`",
                            vec3_text(c),
                            vec3_text(st)
                        ),
                    ));
                }
                c
            }
            None => Vec3::ZERO,
        };
        let phase_name = match &m.phase {
            Some(p) => self.one_of(p, &object, "phase", &["isotropic", "henyey-greenstein"])?,
            None if m.g.is_some() => "henyey-greenstein",
            None => "isotropic",
        };
        let phase = match (phase_name, &m.g) {
            ("isotropic", Some(g)) => {
                return Err(self.invalid(
                    &g.span(),
                    &object,
                    "`g` needs `phase = \"henyey-greenstein\"` (the isotropic phase has none)".to_string(),
                ))
            }
            ("isotropic", None) => Phase::Isotropic,
            (_, g) => {
                let g = match g {
                    Some(g) => {
                        let v = *g.get_ref();
                        if !(v.is_finite() && v > -1.0 && v < 1.0) {
                            return Err(self.invalid(
                                &g.span(),
                                &object,
                                format!("`g` is {}; the asymmetry lies strictly between -1 and 1 (0 is isotropic, > 0 scatters forward)", fmt_number(v)),
                            ));
                        }
                        v as f32
                    }
                    None => 0.0,
                };
                Phase::HenyeyGreenstein { g }
            }
        };
        self.media.push(MediumDesc { sigma_a, sigma_s, emission, phase, density });
        self.medium_names.push(name);
        Ok(())
    }

    /// A medium's `density`: a texture that has a value at every point of space.
    fn density(&mut self, name: &Spanned<String>, object: &str) -> Result<Density> {
        let texture = self.texture_id(name.get_ref(), &name.span(), object)?;
        let t = &self.textures[texture as usize];
        let refuse = |why: &str| {
            Err(self.invalid(
                &name.span(),
                object,
                format!("`density` texture \"{}\" {why}; use a pattern or a voxels texture", printable(name.get_ref())),
            ))
        };
        if matches!(t.kind, TextureKind::Image { .. })
            || t.space == TextureSpace::Uv && !matches!(t.kind, TextureKind::Constant(_))
        {
            return refuse("is looked up in uv space, which a medium does not have");
        }
        let max = t.kind.max_value();
        if !(max.is_finite() && max > 0.0) {
            return refuse("is 0 everywhere (the medium would be vacuum)");
        }
        Ok(Density { texture, max })
    }

    fn medium_id(&self, value: &Spanned<String>, object: &str, field: &str) -> Result<Option<u32>> {
        let name = value.get_ref();
        if name == "vacuum" {
            return Ok(None);
        }
        if let Some(id) = self.medium_names.iter().position(|n| n == name) {
            return Ok(Some(id as u32));
        }
        let shown = printable(name);
        let hint = match suggest(name, &self.medium_names) {
            Some(best) => format!("did you mean \"{}\"?", printable(&best)),
            None => format!("define it with a [media.{shown}] table, or use \"vacuum\""),
        };
        Err(self.invalid(&value.span(), object, format!("unknown medium \"{shown}\" in `{field}` ({hint})")))
    }

    fn atmosphere(&mut self, def: &Spanned<AtmosphereDef>) -> Result<()> {
        let object = "[atmosphere]";
        let medium = self.require(&def.get_ref().medium, &def.span(), object, "medium", "medium = \"fog\"")?;
        self.atmosphere = self.medium_id(medium, object, "medium")?;
        Ok(())
    }

    /// POV-Ray's `fog` as the atmosphere: a medium that absorbs with sigma_a = 1 / `distance` and
    /// glows with `color` / `distance`, so that a camera ray of length d returns exp(-d / D) of
    /// what it meets plus (1 - exp(-d / D)) of the colour, POV-Ray's blend. Ground fog scales
    /// both by POV-Ray's density (1 below `fog_offset`, 1 / (1 + (y - offset) / alt)^2 above).
    fn fog(&mut self, def: &Spanned<FogDef>, has_atmosphere: bool) -> Result<()> {
        let object = "[fog]";
        let f = def.get_ref();
        let table = def.span();
        if has_atmosphere {
            return Err(self.invalid(
                &table,
                object,
                "[fog] fills all space, as [atmosphere] does; keep one of them".to_string(),
            ));
        }
        let kind = match &f.r#type {
            Some(t) => self.one_of(t, object, "type", &["constant", "ground"])?,
            None => "constant",
        };
        let distance = self.require(&f.distance, &table, object, "distance", "distance = 20")?;
        let distance = self.positive(distance, object, "distance")?;
        let color = match &f.color {
            Some(c) => Vec3::from(self.color(c, object, "color", false)?),
            None => Vec3::ZERO,
        };
        let present = [
            ("fog_offset", span_of(&f.fog_offset)),
            ("fog_alt", span_of(&f.fog_alt)),
            ("turbulence", span_of(&f.turbulence)),
            ("octaves", span_of(&f.octaves)),
            ("omega", span_of(&f.omega)),
            ("lambda", span_of(&f.lambda)),
        ];
        let sigma_a = Vec3::splat(1.0 / distance);
        if sigma_a.x > MAX_MEDIUM_COEFFICIENT {
            return Err(self.invalid(
                &span_of(&f.distance).unwrap_or(table.clone()),
                object,
                format!(
                    "`distance` is {distance}; it must be at least 1 / {MAX_MEDIUM_COEFFICIENT} (see docs/limits.md)"
                ),
            ));
        }
        let density = if kind == "ground" {
            let offset = match &f.fog_offset {
                Some(v) => self.number(v, object, "fog_offset")?,
                None => 0.0,
            };
            let alt = self.require(&f.fog_alt, &table, object, "fog_alt", "fog_alt = 1.5")?;
            let alt = self.positive(alt, object, "fog_alt")?;
            let turbulence = match &f.turbulence {
                Some(t) => {
                    let mut p = PatternDesc::new(PatternKind::Bozo);
                    p.turbulence = self.vector(t, object, "turbulence")?;
                    if let Some(o) = &f.octaves {
                        p.octaves = self.integer(o, object, "octaves", 1, 10, "", "")?;
                    }
                    if let Some(o) = &f.omega {
                        p.omega = self.number(o, object, "omega")?;
                    }
                    if let Some(l) = &f.lambda {
                        p.lambda = self.number(l, object, "lambda")?;
                    }
                    p.validate().map_err(|message| self.invalid(&t.span(), object, message))?;
                    Some(p)
                }
                None => {
                    self.fog_fields_unused(&present[3..], "ground fog without `turbulence`", "add `turbulence`")?;
                    None
                }
            };
            self.textures.push(TextureDesc {
                kind: TextureKind::GroundFog { offset, alt, turbulence },
                space: TextureSpace::World,
                lookup_from_texture: Affine3A::IDENTITY,
            });
            self.texture_names.push("[fog] ground fog".to_string());
            self.texture_used.push(true);
            Some(Density { texture: (self.textures.len() - 1) as u32, max: 1.0 })
        } else {
            self.fog_fields_unused(&present, "constant fog", "say `type = \"ground\"` for ground fog")?;
            None
        };
        self.media.push(MediumDesc {
            sigma_a,
            sigma_s: Vec3::ZERO,
            emission: color * sigma_a,
            phase: Phase::Isotropic,
            density,
        });
        self.medium_names.push("[fog]".to_string());
        self.atmosphere = Some((self.media.len() - 1) as u32);
        Ok(())
    }

    fn fog_fields_unused(&self, present: &[Present<'_>], what: &str, fix: &str) -> Result<()> {
        for (name, span) in present {
            if let Some(span) = span {
                return Err(self.invalid(
                    span,
                    "[fog]",
                    format!("`{name}` does not apply to {what}; {fix}, or remove it"),
                ));
            }
        }
        Ok(())
    }

    /// The media a shape bounds (`interior`, `exterior`), refused on shapes that enclose nothing.
    fn medium_interface(&self, kind: &str, s: &ShapeDef, object: &str) -> Result<Option<MediumInterface>> {
        let (interior, exterior) = match (&s.interior, &s.exterior) {
            (None, None) => return Ok(None),
            (None, Some(e)) => {
                return Err(self.invalid(
                    &e.span(),
                    object,
                    "`exterior` needs `interior`: name the medium inside the shape too (or \"vacuum\")".to_string(),
                ))
            }
            (Some(i), e) => (i, e),
        };
        let open = match kind {
            "quad" | "triangle" | "disc" | "bicubic_patch" => true,
            "cylinder" | "cone" => s.open.as_ref().is_some_and(|o| *o.get_ref()),
            _ => false,
        };
        if open {
            return Err(self.invalid(
                &interior.span(),
                object,
                format!(
                    "a medium needs a closed shape, and {} encloses no volume; use a box, a sphere, a closed mesh or another solid",
                    if kind == "cylinder" || kind == "cone" { format!("an open {kind}") } else { format!("a {kind}") }
                ),
            ));
        }
        let interior = self.medium_id(interior, object, "interior")?;
        let exterior = match exterior {
            Some(e) => self.medium_id(e, object, "exterior")?,
            None => self.atmosphere,
        };
        Ok(Some(MediumInterface { interior, exterior }))
    }

    /// Checks that the triangles from `first` on (one mesh) close up, every edge shared by two
    /// triangles that run it in opposite directions, and turns them around when they face
    /// inward (negative volume), so that the winding normal points out of the medium.
    fn close_mesh(
        &mut self,
        first: usize,
        file: &Spanned<String>,
        object: &str,
        needs: &str,
        or_else: &str,
    ) -> Result<()> {
        use std::collections::HashMap;
        let key = |v: Vec3| v.to_array().map(f32::to_bits);
        let mut edges: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
        let mut volume = 0.0f64;
        for shape in &self.shapes[first..] {
            let Geometry::Triangle(t) = &shape.geometry else { continue };
            let [a, b, c] = t.vertices;
            volume += a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())) / 6.0;
            for (p, q) in [(a, b), (b, c), (c, a)] {
                // +1 for p -> q, -1 for q -> p, under one key: a closed, consistently wound mesh
                // sums every edge to 0.
                let (k, sign) = if key(p) < key(q) { ((key(p), key(q)), 1) } else { ((key(q), key(p)), -1) };
                *edges.entry(k).or_insert(0) += sign;
            }
        }
        let open = edges.values().filter(|&&n| n != 0).count();
        if open > 0 {
            return Err(self.invalid(
                &file.span(),
                object,
                format!(
                    "mesh {}: {needs} needs a closed mesh, but {open} edges border a single triangle or triangles wound against their neighbours; close the mesh{or_else}",
                    printable(file.get_ref())
                ),
            ));
        }
        if volume < 0.0 {
            for shape in &mut self.shapes[first..] {
                if let Geometry::Triangle(t) = &mut shape.geometry {
                    t.vertices.swap(1, 2);
                    if let Some(uv) = &mut t.uv {
                        uv.swap(1, 2);
                    }
                    if let Some(normals) = &mut t.normals {
                        normals.swap(1, 2);
                    }
                }
            }
        }
        Ok(())
    }

    // Shapes

    fn shape(&mut self, index: usize, def: &Spanned<ShapeDef>) -> Result<()> {
        let s = def.get_ref();
        let object =
            format!("{}{}", self.context, object_name("shape", index, s.name.as_ref().map(|n| n.get_ref().as_str())));
        let table = def.span();
        let kind_def = self.require(&s.r#type, &table, &object, "type", "type = \"quad\"")?;
        let kind = self.one_of(kind_def, &object, "type", SHAPE_TYPES)?;
        self.shape_fields(kind, s, &object)?;
        self.group(&s.group, &object, self.context.is_empty())?;
        if kind == "csg" {
            return self.csg(def, &object);
        }
        let first_shape = self.shapes.len();
        let media = self.medium_interface(kind, s, &object)?;
        self.shape_kind(kind, s, &table, &object, None)?;
        if let Some(media) = media {
            if kind == "mesh" {
                let file = s.file.as_ref().expect("shape_kind required the file");
                self.close_mesh(first_shape, file, &object, "a medium", " or drop `interior`")?;
            }
            for shape in &mut self.shapes[first_shape..] {
                shape.media = Some(media);
            }
        }
        Ok(())
    }

    /// Refuses the fields a shape of type `kind` does not take.
    fn shape_fields(&self, kind: &str, s: &ShapeDef, object: &str) -> Result<()> {
        let present = [
            ("name", span_of(&s.name)),
            ("type", span_of(&s.r#type)),
            ("material", span_of(&s.material)),
            ("vertices", span_of(&s.vertices)),
            ("center", span_of(&s.center)),
            ("radius", span_of(&s.radius)),
            ("min", span_of(&s.min)),
            ("max", span_of(&s.max)),
            ("file", span_of(&s.file)),
            ("transform", span_of(&s.transform)),
            ("normal", span_of(&s.normal)),
            ("offset", span_of(&s.offset)),
            ("inner_radius", span_of(&s.inner_radius)),
            ("base", span_of(&s.base)),
            ("cap", span_of(&s.cap)),
            ("base_radius", span_of(&s.base_radius)),
            ("cap_radius", span_of(&s.cap_radius)),
            ("open", span_of(&s.open)),
            ("axis", span_of(&s.axis)),
            ("major_radius", span_of(&s.major_radius)),
            ("minor_radius", span_of(&s.minor_radius)),
            ("exponents", span_of(&s.exponents)),
            ("smooth_angle", span_of(&s.smooth_angle)),
            ("file_normals", span_of(&s.file_normals)),
            ("subdivision", span_of(&s.subdivision)),
            ("levels", span_of(&s.levels)),
            ("crease_angle", span_of(&s.crease_angle)),
            ("flatness", span_of(&s.flatness)),
            ("lights", span_of(&s.lights)),
            ("points", span_of(&s.points)),
            ("interior", span_of(&s.interior)),
            ("exterior", span_of(&s.exterior)),
            ("operation", span_of(&s.operation)),
            ("children", span_of(&s.children)),
        ];
        let (what, fields): (&str, &[&str]) = match kind {
            "quad" | "triangle" => (if kind == "quad" { "a quad" } else { "a triangle" }, &["vertices"]),
            "sphere" => ("a sphere", &["center", "radius"]),
            "box" => ("a box", &["min", "max"]),
            "plane" => ("a plane", &["normal", "offset"]),
            "disc" => ("a disc", &["center", "normal", "radius", "inner_radius"]),
            "cylinder" => ("a cylinder", &["base", "cap", "radius", "open"]),
            "cone" => ("a cone", &["base", "cap", "base_radius", "cap_radius", "open"]),
            "torus" => ("a torus", &["center", "axis", "major_radius", "minor_radius"]),
            "superellipsoid" => ("a superellipsoid", &["center", "exponents"]),
            "bicubic_patch" => ("a bicubic patch", &["points", "flatness", "smooth_angle"]),
            "csg" => ("a csg", &["operation", "children"]),
            _ => (
                "a mesh",
                &[
                    "file",
                    "smooth_angle",
                    "file_normals",
                    "subdivision",
                    "levels",
                    "crease_angle",
                    "flatness",
                    "lights",
                ],
            ),
        };
        let mut allowed = vec!["name", "type", "material", "transform", "interior", "exterior"];
        if kind == "csg" {
            allowed = vec!["name", "type", "material"];
        }
        allowed.extend_from_slice(fields);
        self.only_fields(object, what, &present, &allowed)
    }

    /// Adds the shapes of one `[[shapes]]` table of type `kind`.
    /// `default_material` stands in for a missing `material` (a CSG node's, for its children).
    fn shape_kind(
        &mut self,
        kind: &str,
        s: &ShapeDef,
        table: &Range<usize>,
        object: &str,
        default_material: Option<&Spanned<String>>,
    ) -> Result<()> {
        let (table, object) = (table.clone(), object.to_string());
        let material_field = s.material.as_ref().or(default_material);

        // A mesh may leave out `material`: its file's materials apply.
        if kind == "mesh" {
            let material = match material_field {
                Some(m) => Some(self.material_id(m, &object)?),
                None => None,
            };
            let transform = self.transform(s.transform.as_ref(), &object)?;
            let file = self.require(&s.file, &table, &object, "file", "file = \"meshes/bunny.obj\"")?;
            return self.mesh(file, s, &object, material, transform);
        }
        let material_def = match material_field {
            Some(m) => m,
            None => self.require(&s.material, &table, &object, "material", "material = \"white\"")?,
        };
        let material = self.material_id(material_def, &object)?;
        let transform = self.transform(s.transform.as_ref(), &object)?;

        match kind {
            "quad" | "triangle" => {
                let count = if kind == "quad" { 4 } else { 3 };
                let vertices = self.vertices(&s.vertices, &table, &object, count)?;
                self.polygon(
                    &vertices,
                    s.vertices.as_ref().map(|v| v.span()).unwrap_or(table),
                    &object,
                    material,
                    transform,
                )
            }
            "sphere" => {
                let center = self.require(&s.center, &table, &object, "center", "center = [0, 1, 0]")?;
                let radius = self.require(&s.radius, &table, &object, "radius", "radius = 1.0")?;
                self.sphere(center, radius, &object, material, transform)
            }
            "box" => {
                let min_def = self.require(&s.min, &table, &object, "min", "min = [0, 0, 0]")?;
                let max_def = self.require(&s.max, &table, &object, "max", "max = [1, 1, 1]")?;
                let min = self.point(min_def, &object, "min")?;
                let max = self.point(max_def, &object, "max")?;
                if !min.cmplt(max).all() {
                    return Err(self.invalid(
                        &max_def.span(),
                        &object,
                        format!(
                            "`max` ({}) must be greater than `min` ({}) in x, y and z",
                            vec3_text(max),
                            vec3_text(min)
                        ),
                    ));
                }
                for corners in box_faces(min, max) {
                    self.quad_triangles(&corners, &max_def.span(), &object, material, transform)?;
                }
                Ok(())
            }
            "bicubic_patch" => self.bicubic_patch(s, &table, &object, material, transform),
            _ => {
                if kind == "plane" && self.materials[material as usize].emits() {
                    return Err(self.invalid(
                        &material_def.span(),
                        &object,
                        format!(
                            "material \"{}\" emits light, but an infinite plane cannot be a light (its power would be infinite); use a quad or a disc, or a material without `emission`",
                            material_def.get_ref()
                        ),
                    ));
                }
                let pieces = self.analytic(kind, s, &table, &object)?;
                let span = s.transform.as_ref().map_or(table.clone(), |t| t.span());
                self.push_analytic(pieces, transform, &span, &object, material)
            }
        }
    }

    /// Places the object-space analytic `pieces` under `transform` as shapes of `material`, each
    /// checked against the scene range (an error at `span`).
    fn push_analytic(
        &mut self,
        pieces: Vec<(AnalyticKind, Affine3A)>,
        transform: Option<Affine3A>,
        span: &Range<usize>,
        object: &str,
        material: u32,
    ) -> Result<()> {
        for (kind, placement) in pieces {
            let shape = Analytic { kind, world_from_object: transform.unwrap_or(Affine3A::IDENTITY) * placement };
            self.check_placement(&shape, span, object)?;
            self.shapes.push(Shape { geometry: Geometry::Analytic(shape), material, media: None });
        }
        Ok(())
    }

    /// A disc (a disc shape, or a disc area light without `inner_radius`) and its placement.
    fn disc(
        &self,
        center: &Option<Spanned<Vec3Def>>,
        normal: &Option<Spanned<Vec3Def>>,
        radius: &Option<Spanned<f64>>,
        inner_radius: &Option<Spanned<f64>>,
        table: &Range<usize>,
        object: &str,
    ) -> Result<(AnalyticKind, Affine3A)> {
        let center = self.require(center, table, object, "center", "center = [0, 0, 0]")?;
        let center = self.point(center, object, "center")?;
        let normal = self.require(normal, table, object, "normal", "normal = [0, 1, 0]")?;
        let normal = self.direction(normal, object, "normal")?;
        let radius_def = self.require(radius, table, object, "radius", "radius = 1.0")?;
        let radius = self.positive(radius_def, object, "radius")?;
        let inner_radius = match inner_radius {
            Some(r) => {
                let v = self.number(r, object, "inner_radius")?;
                if v < 0.0 || v >= radius {
                    return Err(self.invalid(
                        &r.span(),
                        object,
                        format!("`inner_radius` is {v}; it must be in [0, radius) = [0, {radius})"),
                    ));
                }
                v
            }
            None => 0.0,
        };
        Ok((AnalyticKind::Disc { radius, inner_radius }, frame(center, normal)))
    }

    /// A number > 0 from a required field.
    fn positive(&self, value: &Spanned<f64>, object: &str, field: &str) -> Result<f32> {
        let v = self.number(value, object, field)?;
        if v <= 0.0 {
            return Err(self.invalid(&value.span(), object, format!("`{field}` is {v}; it must be > 0")));
        }
        Ok(v)
    }

    /// A direction: three finite numbers, not all zero, normalised.
    fn direction(&self, value: &Spanned<Vec3Def>, object: &str, field: &str) -> Result<Vec3> {
        let v = self.point(value, object, field)?;
        let n = v.normalize_or_zero();
        if n == Vec3::ZERO || !n.is_finite() {
            return Err(self.invalid(
                &value.span(),
                object,
                format!("`{field}` is [0, 0, 0], which has no direction; give e.g. `{field} = [0, 1, 0]`"),
            ));
        }
        Ok(n)
    }

    /// The object-space pieces of an analytic shape, each with its `world_from_object` before
    /// the shape's own `transform`: a closed cylinder or cone is its side and two discs.
    fn analytic(
        &self,
        kind: &str,
        s: &ShapeDef,
        table: &Range<usize>,
        object: &str,
    ) -> Result<Vec<(AnalyticKind, Affine3A)>> {
        let optional_point = |field: &Option<Spanned<Vec3Def>>, name: &str| -> Result<Vec3> {
            field.as_ref().map_or(Ok(Vec3::ZERO), |v| self.point(v, object, name))
        };
        match kind {
            "plane" => {
                let normal = self.require(&s.normal, table, object, "normal", "normal = [0, 1, 0]")?;
                let normal = self.direction(normal, object, "normal")?;
                let offset = s.offset.as_ref().map_or(Ok(0.0), |o| self.number(o, object, "offset"))?;
                Ok(vec![(AnalyticKind::Plane, frame(normal * offset, normal))])
            }
            "disc" => Ok(vec![self.disc(&s.center, &s.normal, &s.radius, &s.inner_radius, table, object)?]),
            "cylinder" | "cone" => {
                let base_def = self.require(&s.base, table, object, "base", "base = [0, 0, 0]")?;
                let base = self.point(base_def, object, "base")?;
                let cap_def = self.require(&s.cap, table, object, "cap", "cap = [0, 1, 0]")?;
                let cap = self.point(cap_def, object, "cap")?;
                let height = base.distance(cap);
                if height <= 0.0 || !height.is_finite() {
                    return Err(self.invalid(
                        &cap_def.span(),
                        object,
                        format!("`cap` ({cap}) is the same point as `base`; a {kind} needs a height"),
                    ));
                }
                let (r0, r1) = if kind == "cylinder" {
                    let r = self.require(&s.radius, table, object, "radius", "radius = 0.5")?;
                    let r = self.positive(r, object, "radius")?;
                    (r, r)
                } else {
                    let r0_def = self.require(&s.base_radius, table, object, "base_radius", "base_radius = 0.5")?;
                    let r1_def = self.require(&s.cap_radius, table, object, "cap_radius", "cap_radius = 0")?;
                    let r0 = self.number(r0_def, object, "base_radius")?;
                    let r1 = self.number(r1_def, object, "cap_radius")?;
                    for (r, def, name) in [(r0, r0_def, "base_radius"), (r1, r1_def, "cap_radius")] {
                        if r < 0.0 {
                            return Err(self.invalid(&def.span(), object, format!("`{name}` is {r}; it must be >= 0")));
                        }
                    }
                    if r0 == 0.0 && r1 == 0.0 {
                        return Err(self.invalid(
                            &r1_def.span(),
                            object,
                            "`base_radius` and `cap_radius` are both 0, which leaves a line; give one of them a radius"
                                .to_string(),
                        ));
                    }
                    (r0, r1)
                };
                let placement = frame(base, (cap - base) / height);
                let mut pieces = vec![(AnalyticKind::Cone { r0, r1, height }, placement)];
                if !s.open.as_ref().is_some_and(|o| *o.get_ref()) {
                    // Caps face outward: the base's disc turned upside down (a half turn about x).
                    let down = placement * Affine3A::from_rotation_x(std::f32::consts::PI);
                    let up = placement * Affine3A::from_translation(Vec3::new(0.0, height, 0.0));
                    for (radius, placement) in [(r0, down), (r1, up)] {
                        if radius > 0.0 {
                            pieces.push((AnalyticKind::Disc { radius, inner_radius: 0.0 }, placement));
                        }
                    }
                }
                Ok(pieces)
            }
            "torus" => {
                let center = optional_point(&s.center, "center")?;
                let axis = s.axis.as_ref().map_or(Ok(Vec3::Y), |a| self.direction(a, object, "axis"))?;
                let major_def = self.require(&s.major_radius, table, object, "major_radius", "major_radius = 1.0")?;
                let minor_def = self.require(&s.minor_radius, table, object, "minor_radius", "minor_radius = 0.25")?;
                let major = self.positive(major_def, object, "major_radius")?;
                let minor = self.positive(minor_def, object, "minor_radius")?;
                if minor >= major {
                    return Err(self.invalid(
                        &minor_def.span(),
                        object,
                        format!(
                            "`minor_radius` ({minor}) must be smaller than `major_radius` ({major}); a horn or spindle torus intersects itself"
                        ),
                    ));
                }
                Ok(vec![(AnalyticKind::Torus { major, minor }, frame(center, axis))])
            }
            _ => {
                let center = optional_point(&s.center, "center")?;
                let def = self.require(&s.exponents, table, object, "exponents", "exponents = [0.5, 0.5]")?;
                let values = def.get_ref();
                let in_range = |v: f64| (SUPERELLIPSOID_MIN_EXPONENT..=2.0).contains(&v);
                if values.len() != 2 || !values.iter().all(|&v| in_range(v)) {
                    return Err(self.invalid(
                        &def.span(),
                        object,
                        format!(
                            "`exponents` is {values:?}; give two numbers [e, n] (POV-Ray's east-west and north-south exponents), each in [{SUPERELLIPSOID_MIN_EXPONENT}, 2] (1 is round, small is boxy, 2 is an octahedron)"
                        ),
                    ));
                }
                let (e, n) = (values[0] as f32, values[1] as f32);
                Ok(vec![(AnalyticKind::Superellipsoid { e, n }, Affine3A::from_translation(center))])
            }
        }
    }

    /// Refuses a placed analytic shape that float arithmetic cannot handle: a transform that
    /// flattens it (no inverse) or sends its bounds to infinity.
    fn check_placement(&self, shape: &Analytic, span: &Range<usize>, object: &str) -> Result<()> {
        let det = shape.world_from_object.matrix3.determinant();
        let (lo, hi) = shape.bounds();
        let bounded = shape.is_unbounded() || (lo.is_finite() && hi.is_finite());
        let invertible = det.is_finite() && det.abs() > 1e-30 && shape.world_from_object.inverse().is_finite();
        if !bounded || !invertible {
            return Err(self.invalid(
                span,
                object,
                "`transform` scales the shape to zero or to infinity in float precision; use scale factors between about 1e-6 and 1e6"
                    .to_string(),
            ));
        }
        Ok(())
    }

    /// `count` vertices from a `vertices` field.
    fn vertices(
        &self,
        field: &Option<Spanned<Vec<Vec3Def>>>,
        table: &Range<usize>,
        object: &str,
        count: usize,
    ) -> Result<Vec<Vec3>> {
        let example = "vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]";
        let field = self.require(field, table, object, "vertices", example)?;
        let list = field.get_ref();
        if list.len() != count {
            return Err(self.invalid(
                &field.span(),
                object,
                format!("`vertices` has {} points; this shape needs {count}", list.len()),
            ));
        }
        list.iter()
            .map(|v| {
                let spanned = Spanned::new(field.span(), *v);
                self.point(&spanned, object, "vertices")
            })
            .collect()
    }

    /// A triangle (3 vertices) or a quad (4 vertices, split into (v0,v1,v2), (v0,v2,v3)).
    fn polygon(
        &mut self,
        vertices: &[Vec3],
        span: Range<usize>,
        object: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        if vertices.len() == 3 {
            let t = [vertices[0], vertices[1], vertices[2]];
            self.explicit_triangle(t, None, &span, object, "the triangle", material, transform)
        } else {
            let q = [vertices[0], vertices[1], vertices[2], vertices[3]];
            self.quad_triangles(&q, &span, object, material, transform)
        }
    }

    fn quad_triangles(
        &mut self,
        q: &[Vec3; 4],
        span: &Range<usize>,
        object: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        // The split the Cornell data prescribes; some of its walls are not planar. The quad's uv
        // runs from (0, 0) at v0 over (1, 0) at v1 to (0, 1) at v3.
        let first = [q[0], q[1], q[2]];
        let second = [q[0], q[2], q[3]];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let which = "triangle (v0, v1, v2) of the quad";
        self.explicit_triangle(first, Some([uv[0], uv[1], uv[2]]), span, object, which, material, transform)?;
        let which = "triangle (v0, v2, v3) of the quad";
        self.explicit_triangle(second, Some([uv[0], uv[2], uv[3]]), span, object, which, material, transform)
    }

    /// A triangle written in the scene file: zero area is an error.
    #[allow(clippy::too_many_arguments)]
    fn explicit_triangle(
        &mut self,
        vertices: [Vec3; 3],
        uv: Option<[Vec2; 3]>,
        span: &Range<usize>,
        object: &str,
        which: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        let (vertices, uv) = apply(transform, vertices, uv);
        if let Some(far) = beyond_scene_range(&vertices) {
            return Err(self.invalid(span, object, transformed_out_of_range(far)));
        }
        if is_degenerate(&vertices) {
            return Err(self.invalid(
                span,
                object,
                format!("`vertices`: {which} has zero area (its points are equal or on a line); fix the points"),
            ));
        }
        self.shapes.push(Shape {
            geometry: Geometry::Triangle(Triangle { vertices, uv, normals: None }),
            material,
            media: None,
        });
        Ok(())
    }

    fn sphere(
        &mut self,
        center: &Spanned<Vec3Def>,
        radius: &Spanned<f64>,
        object: &str,
        material: u32,
        transform: Option<Affine3A>,
    ) -> Result<()> {
        let mut c = self.point(center, object, "center")?;
        let mut r = self.number(radius, object, "radius")?;
        if (r as f64) < MIN_SPHERE_RADIUS {
            return Err(self.invalid(
                &radius.span(),
                object,
                format!(
                    "`radius` is {}; it must be > 0 (at least {MIN_SPHERE_RADIUS:e}, at most {MAX_SCENE_VALUE:e})",
                    fmt_f32(r)
                ),
            ));
        }
        let mut object_from_world = None;
        if let Some(t) = transform {
            // Columns of the linear part have the scale's lengths (rotation keeps lengths).
            let lengths = Vec3::new(t.matrix3.x_axis.length(), t.matrix3.y_axis.length(), t.matrix3.z_axis.length());
            if lengths.max_element() - lengths.min_element() > 1e-5 * lengths.max_element() {
                return Err(self.invalid(
                    &radius.span(),
                    object,
                    "`transform`: a sphere can only be scaled uniformly; give `scale` as one number".to_string(),
                ));
            }
            c = t.transform_point3(c);
            r *= lengths.x;
            // The rotation part orients the sphere's uv; a mirroring scale keeps its handedness
            // out of the rotation (the uv of a mirrored sphere is the unmirrored one's).
            let rotation = Mat3::from(t.matrix3) * (1.0 / lengths.x);
            let rotation = if rotation.determinant() < 0.0 { -rotation } else { rotation };
            object_from_world = Some(rotation.transpose());
        }
        if let Some(far) = beyond_scene_range(&[c - Vec3::splat(r), c + Vec3::splat(r)]) {
            let message = match transform {
                Some(_) => transformed_out_of_range(far),
                None => format!(
                    "the sphere reaches coordinate {}, beyond the largest scene coordinate, +-{MAX_SCENE_VALUE:e} (see \
                     docs/limits.md)",
                    fmt_f32(far)
                ),
            };
            return Err(self.invalid(&radius.span(), object, message));
        }
        if (r as f64) < MIN_SPHERE_RADIUS {
            let message = format!(
                "`transform` shrinks the sphere to radius {}, below the smallest, {MIN_SPHERE_RADIUS:e}",
                fmt_f32(r)
            );
            return Err(self.invalid(&radius.span(), object, message));
        }
        let sphere = Sphere { center: c, radius: r, object_from_world };
        self.shapes.push(Shape { geometry: Geometry::Sphere(sphere), material, media: None });
        Ok(())
    }

    /// A model file (any format of `model::Format`) as triangles, materials and lights.
    fn mesh(
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
            None => DEFAULT_FLATNESS as f32,
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
        let mut triangles = Vec::new();
        for (m, mesh) in model.meshes.iter().enumerate() {
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
                            reflectance: ColorParam::constant(Vec3::splat(DEFAULT_REFLECTANCE)),
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
        if skipped == total {
            return Err(SceneError::Obj {
                obj_location: printable_message(&model_path.display().to_string()),
                message: format!("all {total} triangles have zero area"),
                object: object.to_string(),
                location,
            });
        }
        if skipped > 0 {
            self.warnings.push(format!(
                "{location}: {object}: skipped {skipped} of {total} triangles of {} with zero area",
                printable_message(&model_path.display().to_string())
            ));
        }

        // Lights of the model (glTF KHR_lights_punctual), moved by the shape's transform.
        if s.lights.as_ref().is_none_or(|l| *l.get_ref()) {
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
    fn shading(&self, s: &ShapeDef, object: &str) -> Result<Shading> {
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
            None => DEFAULT_SMOOTH_ANGLE,
        };
        let file_normals = s.file_normals.as_ref().is_none_or(|f| *f.get_ref());
        // smooth_angle = 0 asks for flat faces whatever the file says.
        Ok(Shading { file_normals: file_normals && smooth_angle_deg > 0.0, smooth_angle_deg })
    }

    /// `subdivision`, `levels` and `crease_angle` of a mesh.
    fn subdivision(&self, s: &ShapeDef, object: &str) -> Result<Option<(Scheme, u32, Option<f32>)>> {
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
        let scheme = match self.one_of(scheme, object, "subdivision", SUBDIVISION_SCHEMES)? {
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
            None => DEFAULT_LEVELS as u32,
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

    fn flatness(&self, f: &Spanned<f64>, object: &str) -> Result<f32> {
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
    fn bicubic_patch(
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
            None => DEFAULT_FLATNESS as f32,
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
    fn check_model_texels(&self, id: u32, span: &Range<usize>, object: &str) -> Result<()> {
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
    fn model_material(&mut self, m: &ModelMaterial, file: &str) -> u32 {
        let name = format!("{file}: {}", m.name);
        let image = |b: &mut Self, img: &ModelImage, channel: Channel| -> u32 {
            b.textures.push(TextureDesc {
                kind: TextureKind::Image { image: img.image.clone(), wrap: img.wrap, channel },
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
        let roughness = m.roughness.map(|alpha| Roughness { alpha: [alpha; 2], texture: rough_tex });
        let base_kind = match roughness {
            None => MaterialKind::Diffuse { reflectance },
            Some(r) => MaterialKind::Plastic { reflectance, ior: m.ior, roughness: r },
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
        let finish = |kind: MaterialKind| MaterialDesc { kind, emission, opacity, normal };
        let metallic = m.metallic > 0.0 || metal_tex.is_some();
        let id = match roughness {
            Some(roughness) if metallic => {
                let (eta, k) = metal_eta_k(m.base_color);
                let conductor =
                    MaterialKind::Conductor { eta: ColorParam::constant(eta), k: ColorParam::constant(k), roughness };
                if m.metallic >= 1.0 && metal_tex.is_none() {
                    self.add_material(name, finish(conductor))
                } else {
                    let a = self.add_material(format!("{name} (dielectric part)"), finish(base_kind));
                    let b = self.add_material(format!("{name} (metal part)"), finish(conductor));
                    self.material_used[a as usize] = true;
                    self.material_used[b as usize] = true;
                    let weight = ScalarParam { value: m.metallic, texture: metal_tex };
                    self.add_material(name, finish(MaterialKind::Mix { a, b, weight }))
                }
            }
            _ => self.add_material(name, finish(base_kind)),
        };
        self.material_used[id as usize] = true;
        id
    }

    /// `world_from_object` = translate · rotate Z · rotate Y · rotate X · scale.
    fn transform(&self, def: Option<&Spanned<TransformDef>>, object: &str) -> Result<Option<Affine3A>> {
        let Some(def) = def else {
            return Ok(None);
        };
        let t = def.get_ref();
        let scale = match &t.scale {
            Some(s) => {
                let scale = self.vector(s, object, "transform.scale")?;
                if scale.abs().min_element() == 0.0 {
                    return Err(self.invalid(
                        &s.span(),
                        object,
                        "`transform.scale` is 0 along an axis, which flattens the shape; give non-zero factors"
                            .to_string(),
                    ));
                }
                scale
            }
            None => Vec3::ONE,
        };
        let rotate = match &t.rotate {
            Some(r) => self.point(r, object, "transform.rotate")?,
            None => Vec3::ZERO,
        };
        let translate = match &t.translate {
            Some(tr) => self.point(tr, object, "transform.translate")?,
            None => Vec3::ZERO,
        };
        let r = rotate * (std::f32::consts::PI / 180.0);
        let rotation = Mat3::from_rotation_z(r.z) * Mat3::from_rotation_y(r.y) * Mat3::from_rotation_x(r.x);
        Ok(Some(Affine3A::from_mat3_translation(rotation * Mat3::from_diagonal(scale), translate)))
    }

    // Lights

    fn light(&mut self, index: usize, def: &Spanned<LightDef>) -> Result<()> {
        let l = def.get_ref();
        let object = object_name("light", index, l.name.as_ref().map(|n| n.get_ref().as_str()));
        let table = def.span();
        let kind_def = self.require(&l.r#type, &table, &object, "type", "type = \"area\"")?;
        let kind = self.one_of(kind_def, &object, "type", LIGHT_TYPES)?;
        self.group(&l.group, &object, true)?;
        let present = [
            ("name", span_of(&l.name)),
            ("type", span_of(&l.r#type)),
            ("shape", span_of(&l.shape)),
            ("vertices", span_of(&l.vertices)),
            ("center", span_of(&l.center)),
            ("radius", span_of(&l.radius)),
            ("normal", span_of(&l.normal)),
            ("samples", span_of(&l.samples)),
            ("jitter", span_of(&l.jitter)),
            ("adaptive", span_of(&l.adaptive)),
            ("radiance", span_of(&l.radiance)),
            ("position", span_of(&l.position)),
            ("intensity", span_of(&l.intensity)),
            ("transform", span_of(&l.transform)),
            ("direction", span_of(&l.direction)),
            ("point_at", span_of(&l.point_at)),
            ("inner_angle", span_of(&l.inner_angle)),
            ("outer_angle", span_of(&l.outer_angle)),
            ("falloff", span_of(&l.falloff)),
            ("tightness", span_of(&l.tightness)),
            ("irradiance", span_of(&l.irradiance)),
            ("angular_diameter", span_of(&l.angular_diameter)),
            ("visible", span_of(&l.visible)),
            ("photons", span_of(&l.photons)),
            ("direct", span_of(&l.direct)),
        ];
        let common = ["name", "type", "photons", "direct"];
        let direct = l.direct.as_ref().is_none_or(|d| *d.get_ref());
        let photons = l.photons.as_ref().is_none_or(|p| *p.get_ref());
        if !direct && !photons {
            let span = span_of(&l.direct).unwrap_or(table.clone());
            return Err(self.invalid(
                &span,
                &object,
                "`direct = false` and `photons = false` leave the light nothing to do; keep one of them true or remove the light"
                    .to_string(),
            ));
        }
        let kind = match kind {
            "point" => {
                let allowed = [&common[..], &["position", "intensity"]].concat();
                self.only_fields(&object, "a point light", &present, &allowed)?;
                let position = self.require(&l.position, &table, &object, "position", "position = [0, 5, 0]")?;
                let position = self.point(position, &object, "position")?;
                let intensity =
                    self.light_color(&l.intensity, &table, &object, "intensity", "intensity = [10, 10, 10]")?;
                LightKind::Point { position, intensity }
            }
            "spot" => self.spot_light(l, &table, &object, &present, &common)?,
            "distant" => {
                let allowed = [&common[..], &["direction", "irradiance", "angular_diameter", "visible"]].concat();
                self.only_fields(&object, "a distant light", &present, &allowed)?;
                let direction = self.light_direction(&l.direction, &table, &object, "direction = [0, -1, 0]")?;
                let irradiance = self.light_color(&l.irradiance, &table, &object, "irradiance", "irradiance = 3")?;
                let half_angle_deg = match &l.angular_diameter {
                    Some(a) => {
                        let deg = self.number(a, &object, "angular_diameter")?;
                        if !(0.0..=90.0).contains(&deg) {
                            return Err(self.invalid(
                                &a.span(),
                                &object,
                                format!(
                                    "`angular_diameter` is {}; it is the apparent size of the light in degrees, \
                                     in [0, 90] (the sun is about 0.53)",
                                    fmt_f32(deg)
                                ),
                            ));
                        }
                        0.5 * deg
                    }
                    None => 0.0,
                };
                let visible = l.visible.as_ref().is_none_or(|v| *v.get_ref());
                LightKind::Distant { direction, irradiance, half_angle_deg, visible }
            }
            _ => return self.area_light(index, l, &table, &object, &present, &common, direct, photons),
        };
        self.lights.push(LightDesc { kind, direct, photons });
        Ok(())
    }

    /// A light's colour field (intensity, irradiance): required, >= 0, with a warning when 0.
    fn light_color(
        &mut self,
        field: &Option<Spanned<Vec3Def>>,
        table: &Range<usize>,
        object: &str,
        name: &str,
        example: &str,
    ) -> Result<Vec3> {
        let def = self.require(field, table, object, name, example)?;
        let value = Vec3::from(self.color(def, object, name, false)?);
        if value.max_element() == 0.0 {
            let at = self.src.at(&def.span());
            self.warnings.push(format!("{at}: {object}: `{name}` is 0, so this light emits nothing"));
        }
        Ok(value)
    }

    /// A light's required `direction`: three numbers, not all zero; returned normalised.
    fn light_direction(
        &self,
        field: &Option<Spanned<Vec3Def>>,
        table: &Range<usize>,
        object: &str,
        example: &str,
    ) -> Result<Vec3> {
        let def = self.require(field, table, object, "direction", example)?;
        let d = self.point(def, object, "direction")?;
        if d.length() == 0.0 {
            return Err(self.invalid(
                &def.span(),
                object,
                "`direction` is zero; give the direction the light shines in".to_string(),
            ));
        }
        Ok(d.normalize())
    }

    /// A spot light: `position`, `direction` or `point_at`, `intensity`, and either
    /// `outer_angle` (with `inner_angle`) or POV-Ray's `radius` and `falloff`; `tightness` with either.
    fn spot_light(
        &mut self,
        l: &LightDef,
        table: &Range<usize>,
        object: &str,
        present: &[Present<'_>],
        common: &[&str],
    ) -> Result<LightKind> {
        let allowed = [
            common,
            &[
                "position",
                "direction",
                "point_at",
                "intensity",
                "inner_angle",
                "outer_angle",
                "radius",
                "falloff",
                "tightness",
            ],
        ]
        .concat();
        self.only_fields(object, "a spot light", present, &allowed)?;
        let position = self.require(&l.position, table, object, "position", "position = [0, 5, 0]")?;
        let position = self.point(position, object, "position")?;
        let direction = match (&l.direction, &l.point_at) {
            (Some(_), Some(p)) => {
                return Err(self.invalid(&p.span(), object, "give `direction` or `point_at`, not both".to_string()));
            }
            (None, Some(p)) => {
                let target = self.point(p, object, "point_at")?;
                if target == position {
                    return Err(self.invalid(
                        &p.span(),
                        object,
                        "`point_at` equals `position`; give the point the spot light aims at".to_string(),
                    ));
                }
                (target - position).normalize()
            }
            _ => {
                self.light_direction(&l.direction, table, object, "direction = [0, -1, 0]` or `point_at = [0, 0, 0]")?
            }
        };
        let intensity = self.light_color(&l.intensity, table, object, "intensity", "intensity = [50, 50, 50]")?;
        // Half-angles in degrees, at most 90; an outer angle must also be above 0.
        let angle = |value: &Spanned<f64>, field: &str, outer: bool, what: &str| -> Result<f32> {
            let deg = self.number(value, object, field)?;
            if !(0.0..=90.0).contains(&deg) || (outer && deg == 0.0) {
                return Err(self.invalid(&value.span(), object, format!("`{field}` is {}; {what}", fmt_f32(deg))));
            }
            Ok(deg)
        };
        let pov = l.radius.is_some() || l.falloff.is_some();
        let (inner, outer, inner_name, outer_name, outer_span) = if pov {
            if let Some(span) = span_of(&l.outer_angle).or(span_of(&l.inner_angle)) {
                return Err(self.invalid(
                    &span,
                    object,
                    "give `inner_angle`/`outer_angle` or POV-Ray's `radius`/`falloff`, not both".to_string(),
                ));
            }
            let inner = match &l.radius {
                Some(r) => angle(r, "radius", false, "POV-Ray's hotspot half-angle in degrees, in [0, 90]")?,
                None => POV_SPOT_RADIUS,
            };
            let outer = match &l.falloff {
                Some(f) => angle(f, "falloff", true, "POV-Ray's falloff half-angle in degrees, in (0, 90]")?,
                None => POV_SPOT_FALLOFF,
            };
            (inner, outer, "radius", "falloff", span_of(&l.falloff).or(span_of(&l.radius)))
        } else {
            let outer_def = self.require(
                &l.outer_angle,
                table,
                object,
                "outer_angle",
                "outer_angle = 30  # degrees from the axis",
            )?;
            let outer = angle(outer_def, "outer_angle", true, "the cone's half-angle in degrees, in (0, 90]")?;
            let inner = match &l.inner_angle {
                Some(i) => angle(i, "inner_angle", false, "the half-angle of full intensity in degrees, in [0, 90]")?,
                None => DEFAULT_INNER_FRACTION * outer,
            };
            (inner, outer, "inner_angle", "outer_angle", Some(outer_def.span()))
        };
        if outer < inner {
            return Err(self.invalid(
                &outer_span.unwrap_or(table.clone()),
                object,
                format!(
                    "`{outer_name}` ({}) is below `{inner_name}` ({}); the light falls off from \
                     `{inner_name}` out to `{outer_name}`, so raise `{outer_name}` to at least {} or lower `{inner_name}`",
                    fmt_f32(outer),
                    fmt_f32(inner),
                    fmt_f32(inner)
                ),
            ));
        }
        let exponent = match &l.tightness {
            Some(t) => {
                let e = self.number(t, object, "tightness")?;
                if !(0.0..=MAX_SPOT_TIGHTNESS as f32).contains(&e) {
                    return Err(self.invalid(
                        &t.span(),
                        object,
                        format!(
                            "`tightness` is {}; it is the exponent of cos in [0, {MAX_SPOT_TIGHTNESS}] (0 for none)",
                            fmt_f32(e)
                        ),
                    ));
                }
                e
            }
            None => 0.0,
        };
        Ok(LightKind::Spot {
            position,
            direction,
            intensity,
            cos_inner: inner.to_radians().cos(),
            cos_outer: outer.to_radians().cos(),
            exponent,
        })
    }

    #[allow(clippy::too_many_arguments)] // the light's fields and options, already read
    fn area_light(
        &mut self,
        index: usize,
        l: &LightDef,
        table: &Range<usize>,
        object: &str,
        present: &[Present<'_>],
        common: &[&str],
        direct: bool,
        photons: bool,
    ) -> Result<()> {
        let shape_def = self.require(&l.shape, table, object, "shape", "shape = \"quad\"")?;
        let shape = self.one_of(shape_def, object, "shape", AREA_LIGHT_SHAPES)?;
        let mut allowed = [common, &["shape", "radiance", "transform", "samples", "jitter", "adaptive"]].concat();
        let what = match shape {
            "quad" => {
                allowed.push("vertices");
                "a quad area light"
            }
            "disc" => {
                allowed.extend_from_slice(&["center", "radius", "normal"]);
                "a disc area light"
            }
            _ => {
                allowed.extend_from_slice(&["center", "radius"]);
                "a sphere area light"
            }
        };
        self.only_fields(object, what, present, &allowed)?;
        let radiance_def = self.require(&l.radiance, table, object, "radiance", "radiance = [10, 10, 10]")?;
        let radiance = self.color(radiance_def, object, "radiance", false)?;
        if radiance.iter().all(|&c| c == 0.0) {
            let at = self.src.at(&radiance_def.span());
            self.warnings.push(format!("{at}: {object}: `radiance` is 0, so this light emits nothing"));
        }

        // Each area light gets its own black, emitting material named after the light's index.
        let material_name = format!("light {index}");
        if self.material_names.contains(&material_name) {
            return Err(self.invalid(
                table,
                object,
                format!("the material name \"{material_name}\" is reserved for this area light; rename that material"),
            ));
        }
        let mut light_material =
            MaterialDesc::new(MaterialKind::Diffuse { reflectance: ColorParam::constant(Vec3::ZERO) });
        light_material.emission = ColorParam::constant(Vec3::from(radiance));
        let material = self.add_material(material_name, light_material);
        self.material_used[material as usize] = true;
        let grid = match &l.samples {
            Some(s) => {
                let v = s.get_ref();
                if v.len() != 2 || v.iter().any(|&k| !(1..=MAX_LIGHT_GRID as i64).contains(&k)) {
                    return Err(self.invalid(
                        &s.span(),
                        object,
                        format!(
                            "`samples` is {v:?}; give POV-Ray's grid as [n, m], each 1 to {MAX_LIGHT_GRID} (e.g. `samples = [4, 4]`)"
                        ),
                    ));
                }
                [v[0] as u32, v[1] as u32]
            }
            None => [1, 1],
        };
        let jitter = l.jitter.as_ref().is_none_or(|j| *j.get_ref());
        let adaptive = match &l.adaptive {
            Some(a) => {
                let level = *a.get_ref();
                let cells = grid[0] * grid[1];
                if level < 0 {
                    return Err(self.invalid(
                        &a.span(),
                        object,
                        format!("`adaptive` is {level}; it is POV-Ray's level, 0 (off) or more (on)"),
                    ));
                }
                if level > 0 && !(2..=ADAPTIVE_MAX_RAYS).contains(&cells) {
                    return Err(self.invalid(
                        &a.span(),
                        object,
                        format!(
                            "`adaptive` needs a grid of 2 to {ADAPTIVE_MAX_RAYS} cells, the shadow rays of a sample in \
                             a penumbra, and `samples` gives {cells}; e.g. `samples = [4, 4]`"
                        ),
                    ));
                }
                level > 0
            }
            None => false,
        };
        self.lights.push(LightDesc { kind: LightKind::Area { material, grid, jitter, adaptive }, direct, photons });
        let transform = self.transform(l.transform.as_ref(), object)?;
        match shape {
            "quad" => {
                let vertices = self.vertices(&l.vertices, table, object, 4)?;
                self.polygon(&vertices, span_of(&l.vertices).unwrap_or(table.clone()), object, material, transform)
            }
            "disc" => {
                // The seed's circular light: a one-sided disc facing `normal` (an ellipse under a
                // non-uniform `transform` scale), sampled over its area like a disc shape.
                let piece = self.disc(&l.center, &l.normal, &l.radius, &None, table, object)?;
                let span = l.transform.as_ref().map_or(table.clone(), |t| t.span());
                self.push_analytic(vec![piece], transform, &span, object, material)
            }
            _ => {
                let center = self.require(&l.center, table, object, "center", "center = [0, 5, 0]")?;
                let radius = self.require(&l.radius, table, object, "radius", "radius = 0.5")?;
                self.sphere(center, radius, object, material, transform)
            }
        }
    }
}

impl Builder<'_> {
    // Environment

    fn environment(
        &mut self,
        def: &Spanned<EnvironmentDef>,
        rainbow: Option<&Spanned<RainbowDef>>,
    ) -> Result<Environment> {
        let object = "[environment]";
        let table = def.span();
        let e = def.get_ref();
        let kind_def = self.require(&e.r#type, &table, object, "type", "type = \"map\"")?;
        let kind = self.one_of(kind_def, object, "type", ENVIRONMENT_TYPES)?;
        let present = [
            ("type", span_of(&e.r#type)),
            ("file", span_of(&e.file)),
            ("radiance", span_of(&e.radiance)),
            ("colors", span_of(&e.colors)),
            ("elevations", span_of(&e.elevations)),
            ("strength", span_of(&e.strength)),
            ("rotation", span_of(&e.rotation)),
            ("photons", span_of(&e.photons)),
            ("direct", span_of(&e.direct)),
            ("turbidity", span_of(&e.turbidity)),
            ("ground_albedo", span_of(&e.ground_albedo)),
            ("sun", span_of(&e.sun)),
            ("sun_direction", span_of(&e.sun_direction)),
            ("sun_elevation", span_of(&e.sun_elevation)),
            ("sun_azimuth", span_of(&e.sun_azimuth)),
            ("latitude", span_of(&e.latitude)),
            ("longitude", span_of(&e.longitude)),
            ("date", span_of(&e.date)),
            ("time", span_of(&e.time)),
            ("utc_offset", span_of(&e.utc_offset)),
            ("north", span_of(&e.north)),
        ];
        let common = ["type", "strength", "rotation", "photons", "direct"];
        let strength = match &e.strength {
            Some(v) => {
                let k = self.number(v, object, "strength")?;
                if k < 0.0 {
                    return Err(self.invalid(
                        &v.span(),
                        object,
                        format!("`strength` is {}; it scales the radiance and must be >= 0", fmt_f32(k)),
                    ));
                }
                k
            }
            None => 1.0,
        };
        let rotation_deg = match &e.rotation {
            Some(r) => self.number(r, object, "rotation")?,
            None => 0.0,
        };
        let direct = e.direct.as_ref().is_none_or(|d| *d.get_ref());
        let photons = e.photons.as_ref().is_none_or(|p| *p.get_ref());
        if !direct && !photons {
            return Err(self.invalid(
                &span_of(&e.direct).unwrap_or(table.clone()),
                object,
                "`direct = false` and `photons = false` leave the environment only visible to camera rays; keep one true".to_string(),
            ));
        }
        let mut image = match kind {
            "map" => {
                self.only_fields(object, "an environment map", &present, &[&common[..], &["file"]].concat())?;
                let file = self.require(&e.file, &table, object, "file", "file = \"textures/sky.hdr\"")?;
                let base = self.src.path.parent().unwrap_or(Path::new(""));
                let image = load_image_texture(&base.join(file.get_ref()), ColorSpace::Srgb).map_err(|err| {
                    self.invalid(
                        &file.span(),
                        object,
                        format!("`file`: {err}; give a latitude-longitude EXR or Radiance HDR image, its path relative to the scene file"),
                    )
                })?;
                let mut image = image;
                let (w0, h0) = (image.width, image.height);
                while image.width as u64 * image.height as u64 > MAX_ENVIRONMENT_TEXELS
                    && image.width > 1
                    && image.height > 1
                {
                    image = halve(&image);
                }
                if image.width != w0 {
                    let at = self.src.at(&file.span());
                    self.warnings.push(format!(
                        "{at}: {object}: the map is {w0}x{h0}; it is used at {}x{} to fit one storage buffer",
                        image.width, image.height
                    ));
                }
                image
            }
            "gradient" => {
                self.only_fields(
                    object,
                    "a gradient sky",
                    &present,
                    &[&common[..], &["colors", "elevations"]].concat(),
                )?;
                let colors_def =
                    self.require(&e.colors, &table, object, "colors", "colors = [[0.9, 0.9, 1.0], [0.3, 0.5, 1.0]]")?;
                let mut colors = Vec::new();
                for c in colors_def.get_ref() {
                    let v = Vec3::new(c.value[0] as f32, c.value[1] as f32, c.value[2] as f32);
                    if !v.is_finite() || v.min_element() < 0.0 || v.max_element() as f64 > MAX_SCENE_VALUE {
                        return Err(self.invalid(
                            &colors_def.span(),
                            object,
                            format!(
                                "`colors` holds {}; give finite radiances >= 0 (at most {MAX_SCENE_VALUE:e})",
                                vec3_text(v)
                            ),
                        ));
                    }
                    colors.push(v);
                }
                if colors.len() < 2 {
                    return Err(self.invalid(
                        &colors_def.span(),
                        object,
                        "`colors` needs at least 2 colours (horizon to zenith)".to_string(),
                    ));
                }
                let elevations: Vec<f32> = match &e.elevations {
                    Some(el) => {
                        let values: Vec<f32> = el.get_ref().iter().map(|&v| v as f32).collect();
                        let increasing = values.windows(2).all(|w| w[0] < w[1]);
                        if values.len() != colors.len()
                            || !increasing
                            || values.iter().any(|v| !(-90.0..=90.0).contains(v))
                        {
                            return Err(self.invalid(
                                &el.span(),
                                object,
                                format!(
                                    "`elevations` is [{}]; give one elevation per colour ({}), increasing, in [-90, 90] degrees",
                                    values.iter().map(|&v| fmt_f32(v)).collect::<Vec<_>>().join(", "),
                                    colors.len()
                                ),
                            ));
                        }
                        values
                    }
                    None => (0..colors.len()).map(|k| 90.0 * k as f32 / (colors.len() - 1) as f32).collect(),
                };
                gradient_image(&colors, &elevations)
            }
            "sky" => {
                self.only_fields(object, "a sky", &present, &[&common[..], sky::SKY_FIELDS].concat())?;
                self.sky(e, &table, object, strength, direct, photons, rainbow)?
            }
            _ => {
                self.only_fields(object, "a uniform environment", &present, &[&common[..], &["radiance"]].concat())?;
                let r = self.require(&e.radiance, &table, object, "radiance", "radiance = 1")?;
                let c = self.color(r, object, "radiance", false)?;
                // Rows, so that directions are drawn in proportion to sin(theta): uniformly.
                ImageTexture {
                    width: 1,
                    height: GRADIENT_ROWS,
                    texels: vec![[c[0], c[1], c[2], 1.0]; GRADIENT_ROWS as usize],
                }
            }
        };
        if kind != "sky" {
            if let Some(r) = rainbow {
                if let Some(addition) = self.rainbow(r, None)? {
                    if (image.width as u64) * (image.height as u64) < (sky::SKY_WIDTH * sky::SKY_HEIGHT) as u64 {
                        image = resample(&image, sky::SKY_WIDTH, sky::SKY_HEIGHT);
                    }
                    sky::add_to_image(&mut image, rotation_deg, &addition);
                }
            }
        }
        // Radiance is in [0, MAX_SCENE_VALUE] like every colour of a scene: a map's NaN and
        // negative texels (EXR allows them) become 0, and a texel too bright is refused.
        let mut cleared = 0usize;
        let mut brightest = 0.0f32;
        for t in &mut image.texels {
            for c in &mut t[..3] {
                if c.is_nan() || *c < 0.0 {
                    cleared += 1;
                    *c = 0.0;
                }
                // (An infinite texel at strength 0 is black, not NaN.)
                *c = if strength == 0.0 { 0.0 } else { *c * strength };
                brightest = brightest.max(*c);
            }
        }
        let at_field = span_of(&e.file).or(span_of(&e.strength)).unwrap_or(table.clone());
        if cleared > 0 {
            let at = self.src.at(&at_field);
            self.warnings.push(format!(
                "{at}: {object}: {cleared} texel channels of the map are negative or NaN; they are taken as 0"
            ));
        }
        if brightest as f64 > MAX_SCENE_VALUE {
            return Err(self.invalid(
                &at_field,
                object,
                format!(
                    "the environment's radiance reaches {} (times `strength`), beyond the largest scene value, \
                     {MAX_SCENE_VALUE:e} (see docs/limits.md); lower `strength`",
                    fmt_f32(brightest)
                ),
            ));
        }
        Ok(Environment { image: std::sync::Arc::new(image), rotation_deg, direct, photons })
    }
}

/// The image at `width` x `height`, each texel the source texel its centre falls in (for a
/// gradient or uniform sky that a rainbow is drawn over).
fn resample(image: &ImageTexture, width: u32, height: u32) -> ImageTexture {
    let mut texels = Vec::with_capacity((width * height) as usize);
    for j in 0..height {
        let sj = (((j as f64 + 0.5) / height as f64 * image.height as f64) as u32).min(image.height - 1);
        for i in 0..width {
            let si = (((i as f64 + 0.5) / width as f64 * image.width as f64) as u32).min(image.width - 1);
            texels.push(image.texels[(sj * image.width + si) as usize]);
        }
    }
    ImageTexture { width, height, texels }
}

/// The image halved in both directions (odd last rows and columns dropped), each texel the mean
/// of the 2x2 it replaces.
fn halve(image: &ImageTexture) -> ImageTexture {
    let (w, h) = (image.width / 2, image.height / 2);
    let mut texels = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let mut sum = [0.0f32; 4];
            for (di, dj) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let t = image.texels[((2 * j + dj) * image.width + 2 * i + di) as usize];
                (0..4).for_each(|c| sum[c] += 0.25 * t[c]);
            }
            texels.push(sum);
        }
    }
    ImageTexture { width: w, height: h, texels }
}

/// A one-column latitude-longitude image of `colors` at `elevations` (degrees), linear in
/// elevation between them and constant beyond the first and the last.
fn gradient_image(colors: &[Vec3], elevations: &[f32]) -> ImageTexture {
    let texels = (0..GRADIENT_ROWS)
        .map(|j| {
            let elevation = 90.0 - 180.0 * (j as f32 + 0.5) / GRADIENT_ROWS as f32;
            let k = elevations.iter().rposition(|&e| e <= elevation).unwrap_or(0);
            let c = if elevation <= elevations[0] {
                colors[0]
            } else if k + 1 >= colors.len() {
                colors[colors.len() - 1]
            } else {
                let t = (elevation - elevations[k]) / (elevations[k + 1] - elevations[k]);
                colors[k].lerp(colors[k + 1], t)
            };
            [c.x, c.y, c.z, 1.0]
        })
        .collect();
    ImageTexture { width: 1, height: GRADIENT_ROWS, texels }
}

/// The placement of an object space whose origin goes to `origin` and whose +y axis goes to the
/// unit vector `axis` (the shortest rotation: none for +y, a half turn about x for -y).
fn frame(origin: Vec3, axis: Vec3) -> Affine3A {
    let rotation = if axis.dot(Vec3::Y) < -0.999_999 {
        glam::Quat::from_rotation_x(std::f32::consts::PI)
    } else {
        glam::Quat::from_rotation_arc(Vec3::Y, axis)
    };
    Affine3A::from_rotation_translation(rotation, origin)
}

/// The triangle moved by `transform`, with its vertex uvs kept in step with its vertices.
fn apply(transform: Option<Affine3A>, vertices: [Vec3; 3], uv: Option<[Vec2; 3]>) -> ([Vec3; 3], Option<[Vec2; 3]>) {
    let Some(t) = transform else {
        return (vertices, uv);
    };
    let [a, b, c] = vertices.map(|v| t.transform_point3(v));
    // A mirroring transform flips the winding normal; swap two vertices so the front face stays
    // on the same side of the surface (outward stays outward). The default uv goes with them.
    if t.matrix3.determinant() < 0.0 {
        let [u0, u1, u2] = uv.unwrap_or([Vec2::ZERO, Vec2::X, Vec2::Y]);
        ([a, c, b], Some([u0, u2, u1]))
    } else {
        ([a, b, c], uv)
    }
}

/// `apply` for a triangle with vertex normals: normals move by the inverse transpose and follow
/// their vertices when a mirroring transform swaps two of them.
fn apply_with_normals(
    transform: Option<Affine3A>,
    vertices: [Vec3; 3],
    uv: Option<[Vec2; 3]>,
    normals: Option<[Vec3; 3]>,
) -> ([Vec3; 3], Option<[Vec2; 3]>, Option<[Vec3; 3]>) {
    let (v, uv_out) = apply(transform, vertices, uv);
    let Some(n) = normals else {
        return (v, uv_out, None);
    };
    let Some(t) = transform else {
        return (v, uv_out, Some(n));
    };
    let normal_matrix = Mat3::from(t.matrix3).inverse().transpose();
    let [a, b, c] = n.map(|n| (normal_matrix * n).normalize_or_zero());
    let mut moved = if t.matrix3.determinant() < 0.0 { [a, c, b] } else { [a, b, c] };
    let face = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
    let smooth = super::model::smooth_normals(&mut moved, face);
    (v, uv_out, smooth.then_some(moved))
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

/// Zero area, to f32 precision: |cross| is tiny next to the longest edge squared. Also catches
/// non-finite vertices (a huge scale).
fn is_degenerate(v: &[Vec3; 3]) -> bool {
    let e0 = v[1] - v[0];
    let e1 = v[2] - v[0];
    let e2 = v[2] - v[1];
    let longest = e0.length_squared().max(e1.length_squared()).max(e2.length_squared());
    let twice_area = e0.cross(e1).length();
    let has_area = twice_area.is_finite() && twice_area > 1e-7 * longest;
    !has_area
}

/// A number outside +-`MAX_SCENE_VALUE`, as a message.
fn out_of_scene_range(field: &str, v: f64) -> String {
    format!(
        "`{field}` holds {}; every number in a scene (coordinates, lengths, colours, angles) must be within \
         +-{MAX_SCENE_VALUE:e} (see docs/limits.md)",
        fmt_number(v)
    )
}

/// The first coordinate of `points` beyond +-`MAX_SCENE_VALUE` (or not finite), if any.
fn beyond_scene_range(points: &[Vec3]) -> Option<f32> {
    points.iter().flat_map(|p| p.to_array()).find(|c| !c.is_finite() || c.abs() as f64 > MAX_SCENE_VALUE)
}

fn transformed_out_of_range(coordinate: f32) -> String {
    format!(
        "`transform` moves the shape to coordinate {}, beyond the largest scene coordinate, +-{MAX_SCENE_VALUE:e} \
         (see docs/limits.md); use a smaller `scale` or `translate`",
        fmt_f32(coordinate)
    )
}

fn vec3_text(c: Vec3) -> String {
    format!("[{}, {}, {}]", fmt_f32(c.x), fmt_f32(c.y), fmt_f32(c.z))
}

/// The six faces of an axis-aligned box as quads whose winding normal points outward.
fn box_faces(min: Vec3, max: Vec3) -> [[Vec3; 4]; 6] {
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(if x { max.x } else { min.x }, if y { max.y } else { min.y }, if z { max.z } else { min.z })
    };
    // Each face listed counter-clockwise seen from outside, so (v1-v0)x(v2-v0) points out.
    [
        [p(false, false, false), p(false, false, true), p(false, true, true), p(false, true, false)], // -x
        [p(true, false, false), p(true, true, false), p(true, true, true), p(true, false, true)],     // +x
        [p(false, false, false), p(true, false, false), p(true, false, true), p(false, false, true)], // -y
        [p(false, true, false), p(false, true, true), p(true, true, true), p(true, true, false)],     // +y
        [p(false, false, false), p(false, true, false), p(true, true, false), p(true, false, false)], // -z
        [p(false, false, true), p(true, false, true), p(true, true, true), p(false, true, true)],     // +z
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_face_normals_point_outward() {
        let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 5.0));
        let center = (min + max) / 2.0;
        for face in box_faces(min, max) {
            let n = (face[1] - face[0]).cross(face[2] - face[0]);
            let face_center = (face[0] + face[1] + face[2] + face[3]) / 4.0;
            assert!(n.dot(face_center - center) > 0.0, "face {face:?} normal {n}");
        }
    }

    #[test]
    fn mirroring_transform_keeps_the_front_face_outward() {
        let t = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let triangle = [Vec3::ZERO, Vec3::X, Vec3::Y]; // normal +z
        let (out, _) = apply(Some(t), triangle, None);
        let n = (out[1] - out[0]).cross(out[2] - out[0]);
        assert!(n.z > 0.0, "mirror in x keeps a +z normal: {n}");
    }

    #[test]
    fn degenerate_catches_collinear_and_equal_points() {
        assert!(is_degenerate(&[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]));
        assert!(is_degenerate(&[Vec3::ONE, Vec3::ONE, Vec3::ONE]));
        assert!(!is_degenerate(&[Vec3::ZERO, Vec3::X, Vec3::Y]));
    }
}
