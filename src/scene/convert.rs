//! From the file as written (`format`) to the `Scene` the renderer uses: checks every value,
//! applies defaults, turns quads, boxes, meshes and area lights into triangles and materials.
//! This file only orders the work; each section of the format has its module: `camera` and
//! `settings` (`[render]`, `[photons]`), `textures`, `materials` and `params` (a value or a
//! texture), `media` (and fog), `shapes` with `analytic`, `meshes`, `csg` and `objects`,
//! `lights`, `environment` with `sky`; `values` checks the numbers, points and colours they share.

mod analytic;
mod camera;
mod csg;
mod environment;
mod lights;
mod materials;
mod media;
mod meshes;
mod objects;
mod params;
mod settings;
mod shapes;
mod sky;
mod textures;
mod values;

use std::ops::Range;

use toml::Spanned;

use super::error::{SceneError, Source};
use super::format::SceneFile;
use super::material::{MaterialDesc, TextureDesc};
use super::{LightDesc, LightKind, MediumDesc, Scene, SceneOrigins, Shape};

type Result<T> = std::result::Result<T, SceneError>;

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
    let (mut render, auto_integrator) = builder.render(file.render.as_ref())?;
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
    // A mix after the materials it names, wherever the file has it (the editor's switch of a
    // material to a mix of one added after it); otherwise in file order.
    let mut ordered = Vec::with_capacity(materials.len());
    while !materials.is_empty() {
        let ready = |def: &Spanned<crate::scene::format::MaterialDef>| {
            def.get_ref()
                .materials
                .as_ref()
                .is_none_or(|list| list.get_ref().iter().all(|n| !materials.iter().any(|(k, _)| k.get_ref() == n)))
        };
        // The first one ready, or the first one (a cycle or an unknown name: its error then).
        let next = materials.iter().position(|(_, def)| ready(def)).unwrap_or(0);
        ordered.push(materials.remove(next));
    }
    for (key, def) in ordered {
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
    let mut scene = Scene {
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
    if auto_integrator {
        scene.set_integrator(None);
    }
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
