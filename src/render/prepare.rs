//! Turns a parsed scene into the flat arrays the kernels and their CPU twins read.

use glam::Vec3;

use super::pack::{pack_scene, KernelVariant};
use crate::accel::{build_bvh, BvhError};
use crate::cpu::SceneView;
use crate::layout::constants::*;
use crate::layout::{BvhNode, FrameParams, Light, Material, Primitive, Texture};
use crate::scene::Scene;

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
    /// Which build of the scene kernels the scene needs.
    pub variant: KernelVariant,
    /// Radius of a sphere around the whole scene (scene units).
    pub bounding_radius: f32,
    /// Total area of all surfaces (scene units squared), for the automatic photon radius.
    pub surface_area: f32,
}

impl SceneBuffers {
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
    // Primitives in BVH order, each emitter tagged with its light index
    let packed = pack_scene(scene);
    let surface_area = packed.photon_area;
    let bvh = build_bvh(&packed.primitives, &packed.bounds)?;
    let mut primitives = bvh.primitives;
    // Areas follow the primitives into BVH order (their bounds and areas are keyed by the
    // original index, which the reorder keeps in `order`).
    let areas: Vec<f32> = bvh.order.iter().map(|&i| packed.areas.get(i as usize).copied().unwrap_or(0.0)).collect();

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
    for (what, value) in [("total light power", total_power), ("total surface area", surface_area as f64)] {
        if !(value as f32).is_finite() {
            let value = crate::limits::fmt_number(value);
            return Err(PrepareError::Overflow { path: path(), what, value });
        }
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
        variant: packed.variant,
        bounding_radius,
        surface_area,
    })
}
