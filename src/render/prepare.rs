//! Turns a parsed scene into the flat arrays the kernels and their CPU twins read.

use glam::{Mat3, Vec3};

use super::pack::pack_scene;
use crate::accel::{build_bvh, BvhError};
use crate::cpu::SceneView;
use crate::layout::constants::*;
use crate::layout::{BvhNode, FrameParams, Light, Material, Primitive, Texture};
use crate::scene::{Geometry, Scene};

/// Everything a render dispatch binds, owned.
#[derive(Clone, Debug)]
pub struct SceneBuffers {
    pub frame: FrameParams,
    pub nodes: Vec<BvhNode>,
    pub primitives: Vec<Primitive>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub textures: Vec<Texture>,
    pub texture_data: Vec<u32>,
    pub shape_data: Vec<f32>,
    /// True when the scene has image or pattern textures (see `PackedScene::textured`).
    pub textured: bool,
    /// True when the scene has analytic shapes other than spheres (see `PackedScene::analytic`).
    pub analytic: bool,
    /// True when the scene has tori or superellipsoids (see `PackedScene::implicit`).
    pub implicit: bool,
    /// True when some shape has an opacity below 1 (see `PackedScene::alpha`).
    pub alpha: bool,
    /// Radius of a sphere around the whole scene (scene units).
    pub bounding_radius: f32,
    /// Total area of all surfaces (scene units squared), for the automatic photon radius.
    pub surface_area: f32,
}

/// Which variant of the scene kernels a scene needs: lavapipe runs every branch of a shader
/// under masks, so each kind of costly code lives only in the kernels of the scenes that use it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KernelVariant {
    /// Image and pattern textures, alpha.
    pub textured: bool,
    /// The alpha test inside BVH traversal (with the textures): it slowed textured scenes'
    /// photon tracing 3x on lavapipe, so only scenes with a shape of opacity below 1 pay for it.
    pub alpha: bool,
    /// Planes, discs and cones.
    pub analytic: bool,
    /// Tori and superellipsoids (with the analytic shapes).
    pub implicit: bool,
}

impl KernelVariant {
    /// The kernel `name` in this variant's build: `name[_textured[_alpha]][_analytic[_implicit]]`
    /// (the `// variant:` lines of the kernels, see build.rs).
    pub fn kernel_name(self, name: &str) -> String {
        let mut out = name.to_string();
        if self.textured || self.alpha {
            out.push_str("_textured");
        }
        if self.alpha {
            out.push_str("_alpha");
        }
        if self.analytic || self.implicit {
            out.push_str("_analytic");
        }
        if self.implicit {
            out.push_str("_implicit");
        }
        out
    }
}

impl SceneBuffers {
    /// The variant of the scene kernels this scene needs.
    pub fn variant(&self) -> KernelVariant {
        KernelVariant { textured: self.textured, alpha: self.alpha, analytic: self.analytic, implicit: self.implicit }
    }

    pub fn view(&self) -> SceneView<'_> {
        SceneView {
            frame: &self.frame,
            nodes: &self.nodes,
            primitives: &self.primitives,
            materials: &self.materials,
            lights: &self.lights,
            textures: &self.textures,
            texture_data: &self.texture_data,
            shape_data: &self.shape_data,
            maps: crate::cpu::NO_MAPS,
        }
    }
}

/// Render settings that the command line may override.
#[derive(Clone, Copy, Debug)]
pub struct FrameSettings {
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub seed: u32,
}

/// Power used to pick lights: luminous-agnostic mean of the three channels.
fn channel_mean(v: [f32; 3]) -> f32 {
    (v[0] + v[1] + v[2]) / 3.0
}

/// Why a scene cannot be prepared. Loading checks scene files so that only hand-built scenes
/// meet the last two.
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error(
        "{path}: [camera]: no camera frame: `look_at` equals `position`, or `up` is zero or parallel to the view \
         direction"
    )]
    Camera { path: String },
    #[error(
        "{path}: the scene's {what} is {value}, beyond what 32-bit floats hold; scale the scene or its lights down \
         (see docs/limits.md)"
    )]
    Overflow { path: String, what: &'static str, value: String },
}

pub fn prepare(scene: &Scene, settings: &FrameSettings) -> Result<SceneBuffers, PrepareError> {
    let path = || crate::limits::printable_message(&scene.path.display().to_string());
    // Primitives in BVH order, then the unbounded ones (infinite planes) that every ray tests
    let packed = pack_scene(scene);
    let is_unbounded: Vec<bool> = scene.shapes.iter().map(|s| s.geometry.is_unbounded()).collect();
    let bounded: Vec<usize> = (0..packed.primitives.len()).filter(|&i| !is_unbounded[i]).collect();
    let unbounded: Vec<usize> = (0..packed.primitives.len()).filter(|&i| is_unbounded[i]).collect();
    let bvh = build_bvh(
        &bounded.iter().map(|&i| packed.primitives[i]).collect::<Vec<_>>(),
        &bounded.iter().map(|&i| packed.bounds[i]).collect::<Vec<_>>(),
    )?;
    let mut primitives = bvh.primitives;
    let unbounded_first = primitives.len() as u32;
    primitives.extend(unbounded.iter().map(|&i| packed.primitives[i]));
    // Areas follow the primitives into BVH order (their bounds and areas are keyed by the
    // original index, which the reorder keeps in `order`).
    let areas: Vec<f32> = bvh
        .order
        .iter()
        .map(|&i| bounded.get(i as usize).map_or(0.0, |&j| packed.areas[j]))
        .chain(unbounded.iter().map(|_| 0.0))
        .collect();

    // Lights: emissive primitives (in BVH order) and point lights, with power-proportional picking
    let mut lights = Vec::new();
    let mut powers = Vec::new();
    for (i, (p, &area)) in primitives.iter_mut().zip(&areas).enumerate() {
        let Some(material) = scene.materials.get(p.material as usize) else { continue };
        // A textured emission's power is estimated from its constant (the texture scales it
        // by at most its values; the pick probability only steers sampling, it keeps no bias).
        let emission = material.emission.value;
        // A Lambertian emitter of radiance L and area A emits power pi * A * L. A light of no
        // power (or one so faint its power rounds to 0) is left out: were every light such, the
        // pick probabilities would be 0 / 0.
        let power = std::f32::consts::PI * area * channel_mean(emission.into());
        if power.is_nan() || power <= 0.0 {
            continue;
        }
        p.light = lights.len() as u32;
        powers.push(power);
        lights.push(Light { kind: LIGHT_AREA, primitive: i as u32, area, ..Default::default() });
    }
    for pl in &scene.point_lights {
        // An isotropic point light of intensity I emits power 4 pi I.
        let power = 4.0 * std::f32::consts::PI * channel_mean(pl.intensity.into());
        if power.is_nan() || power <= 0.0 {
            continue;
        }
        powers.push(power);
        lights.push(Light {
            position: pl.position.into(),
            kind: LIGHT_POINT,
            intensity: pl.intensity.into(),
            ..Default::default()
        });
    }
    let total_power: f64 = powers.iter().map(|&p| p as f64).sum();
    let overflow = |what: &'static str, value: f64| {
        (!(value as f32).is_finite()).then(|| PrepareError::Overflow {
            path: path(),
            what,
            value: crate::limits::fmt_number(value),
        })
    };
    if let Some(e) = overflow("total light power", total_power) {
        return Err(e);
    }
    let mut running = 0.0f64;
    for (light, &power) in lights.iter_mut().zip(&powers) {
        running += power as f64;
        light.pick_probability = (power as f64 / total_power) as f32;
        light.cdf = (running / total_power) as f32;
    }
    if let Some(last) = lights.last_mut() {
        last.cdf = 1.0; // so a pick of u close to 1 never falls past the end
    }

    // Bounds and camera
    let root = &bvh.nodes[0];
    let (lo, hi) = (Vec3::from(root.aabb_min), Vec3::from(root.aabb_max));
    let (bounding_center, bounding_radius) =
        if lo.cmple(hi).all() { ((lo + hi) * 0.5, (hi - lo).length() * 0.5) } else { (Vec3::ZERO, 1.0) };
    // An infinite plane holds photons over the part of it near the rest of the scene: its disc
    // inside the sphere around the bounded shapes, the point lights and the camera.
    let mut surface_area = packed.photon_area;
    if !unbounded.is_empty() {
        let mut extent = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        if lo.cmple(hi).all() {
            extent = (lo, hi);
        }
        for p in scene.point_lights.iter().map(|l| l.position).chain([scene.camera.position]) {
            extent = (extent.0.min(p), extent.1.max(p));
        }
        let (center, radius) = ((extent.0 + extent.1) * 0.5, (extent.1 - extent.0).length() * 0.5);
        for &i in &unbounded {
            if let Geometry::Analytic(a) = &scene.shapes[i].geometry {
                let m = a.world_from_object;
                let normal = (Mat3::from(m.matrix3).inverse().transpose() * Vec3::Y).normalize();
                let distance = (center - Vec3::from(m.translation)).dot(normal).abs();
                let opacity = scene.materials[scene.shapes[i].material as usize].opacity;
                let visible = if opacity.texture.is_some() { 1.0 } else { opacity.value };
                surface_area += std::f32::consts::PI * (radius * radius - distance * distance).max(0.0) * visible;
            }
        }
    }
    if let Some(e) = overflow("total surface area", surface_area as f64) {
        return Err(e);
    }
    let cam = &scene.camera;
    let (forward, right, up) = cam.basis().ok_or_else(|| PrepareError::Camera { path: path() })?;
    let tan_half = (cam.fov_deg.to_radians() * 0.5).tan();
    let aspect = settings.width as f32 / settings.height as f32;
    let scale = bounding_radius.max(cam.position.distance(bounding_center));
    let frame = FrameParams {
        camera_position: cam.position.into(),
        width: settings.width,
        camera_forward: forward.into(),
        height: settings.height,
        camera_right: (right * tan_half * aspect).into(),
        max_depth: settings.max_depth,
        camera_up: (up * tan_half).into(),
        seed: settings.seed,
        light_count: lights.len() as u32,
        ray_epsilon: scale * RAY_EPSILON_SCALE,
        primitive_count: primitives.len() as u32,
        node_count: bvh.nodes.len() as u32,
        total_light_power: total_power as f32,
        photon_mapping: 0,
        gather_rays: 0,
        glossy_threshold: scene.photons.map_or(GLOSSY_THRESHOLD, |p| p.glossy_threshold),
        unbounded_first,
        _pad: [0; 3],
    };
    Ok(SceneBuffers {
        frame,
        nodes: bvh.nodes,
        primitives,
        materials: packed.materials,
        lights,
        textures: packed.textures,
        texture_data: packed.texture_data,
        shape_data: packed.shape_data,
        textured: packed.textured,
        analytic: packed.analytic,
        implicit: packed.implicit,
        alpha: packed.alpha,
        bounding_radius,
        surface_area,
    })
}
