//! Turns a parsed scene into the flat arrays the kernels and their CPU twins read.

use std::f32::consts::PI;
use std::sync::OnceLock;

use glam::{Mat3, Vec3};

use super::instances::pack_instances;
use super::light_tree;
use super::pack::{pack_environment, pack_scene};
use crate::accel::wide::WideBvh;
use crate::accel::{build_bvh, BvhError};
use crate::cpu::SceneView;
use crate::layout::constants::*;
use crate::layout::{BvhNode, FrameParams, Light, Material, Medium, Primitive, Texture};
use crate::scene::{Geometry, LightKind, LightSampler, Projection, Scene, ThinLens};

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
    /// The participating media; empty when the scene has none (and no null surface).
    pub media: Vec<Medium>,
    /// True when the scene has image or pattern textures (see `PackedScene::textured`).
    pub textured: bool,
    /// True when the scene has analytic shapes other than spheres (see `PackedScene::analytic`).
    pub analytic: bool,
    /// True when the scene has tori or superellipsoids (see `PackedScene::implicit`).
    pub implicit: bool,
    /// True when a CSG object has a torus or a superellipsoid among its leaves (see
    /// `PackedScene::implicit_csg`).
    pub implicit_csg: bool,
    /// True when some shape has an opacity below 1 (see `PackedScene::alpha`).
    pub alpha: bool,
    /// Radius of a sphere around the whole scene (scene units).
    pub bounding_radius: f32,
    /// Total area of all surfaces (scene units squared), for the automatic photon radius.
    pub surface_area: f32,
    /// Volume the media fill (scene units cubed; bounding boxes), for the automatic volume radius.
    pub media_volume: f32,
    /// The CPU backend's wide BVH over `nodes`, built at the first `view` (the GPU backend
    /// needs none).
    pub wide: OnceLock<WideBvh>,
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
    /// Tori and superellipsoids as CSG leaves (with the implicit shapes): the CSG walk's copy of
    /// their root searches, which lavapipe would otherwise compile into, and pay for in, every
    /// kernel of the implicit variant.
    pub implicit_csg: bool,
    /// Participating media and null surfaces.
    pub media: bool,
    /// Instances (the two-level walk). A specialization constant, not a build of its own.
    pub instances: bool,
    /// CSG objects (their walk, in the analytic builds). A specialization constant.
    pub csg: bool,
    /// Textures that read Perlin noise (`pack::texture_uses_noise`). A specialization constant:
    /// without it the textured kernels lose most of their code.
    pub noise: bool,
    /// Materials whose emission is textured. A specialization constant: without it every call
    /// of `material_emission` is a colour read rather than a texture lookup's code.
    pub emission_textures: bool,
    /// The material kinds the kernels' BSDFs can meet, bit `MATERIAL_*` (`MATERIAL_PHASE` with
    /// media), and bit `SCENE_KIND_BECKMANN` where a material has Beckmann microfacets. A
    /// specialization constant: each kind's code is inlined at every BSDF call.
    pub material_kinds: u32,
    /// The path tracer's camera kernel (render_pt) in place of photon mapping's (render).
    pub path_traced: bool,
    /// The bidirectional integrators' kernels (vcm_light, render_vcm) and no others.
    pub bidirectional: bool,
    /// The most pages a scene array takes on the device (1 unless one exceeds a page), and the
    /// words in a page, log2 (`DeviceScene::page`). With one page the kernels are the builds
    /// whose fetches are single texel fetches; with more, the `paged` builds, whose page
    /// selection takes both as specialization constants. A constant alone left the selection
    /// in the SPIR-V, and lavapipe inlines it at every fetch before folding it away: twice the
    /// code to create, for every scene.
    pub pages: u32,
    pub page_words_log2: u32,
}

/// `SCENE_PAGE_WORDS_LOG2`'s default in shaders/scene_bindings.glsl (128 MiB pages).
const DEFAULT_PAGE_WORDS_LOG2: u32 = 25;

impl KernelVariant {
    /// The kernel `name` in this variant's build:
    /// `name[_textured[_alpha]][_analytic[_implicit[_csg]]][_media][_paged]`
    /// (the `// variant:` and `// every build also:` lines of the kernels, see build.rs).
    pub fn kernel_name(self, name: &str) -> String {
        let mut out = name.to_string();
        if self.textured || self.alpha {
            out.push_str("_textured");
        }
        if self.alpha {
            out.push_str("_alpha");
        }
        if self.analytic || self.implicit || self.implicit_csg {
            out.push_str("_analytic");
        }
        if self.implicit || self.implicit_csg {
            out.push_str("_implicit");
        }
        if self.implicit_csg {
            out.push_str("_csg");
        }
        if self.media {
            out.push_str("_media");
        }
        // The page selection, only where an array spans pages (shaders/scene_fetch.glsl).
        if self.pages > 1 {
            out.push_str("_paged");
        }
        out
    }

    /// The values of the scene kernels' specialization constants (`constant_id` 0, 1, ...: see
    /// shaders/scene_bindings.glsl).
    pub fn specialization(self) -> [u32; 7] {
        [
            self.instances as u32,
            self.csg as u32,
            self.noise as u32,
            self.emission_textures as u32,
            self.material_kinds,
            // A default variant (no scene yet) reads one page, as every kernel made without
            // constants does.
            self.pages.max(1),
            self.page_words_log2,
        ]
    }

    /// This variant for arrays of up to `pages` pages of 2^`page_words_log2` words. With one
    /// page the size is irrelevant and left at its default, so the variant equals that of any
    /// device.
    pub fn with_pages(self, pages: u32, page_words_log2: u32) -> KernelVariant {
        let page_words_log2 = if pages > 1 { page_words_log2 } else { DEFAULT_PAGE_WORDS_LOG2 };
        KernelVariant { pages: pages.max(1), page_words_log2, ..self }
    }
}

impl SceneBuffers {
    /// The variant of the scene kernels this scene needs.
    pub fn variant(&self) -> KernelVariant {
        KernelVariant {
            textured: self.textured,
            alpha: self.alpha,
            analytic: self.analytic,
            implicit: self.implicit,
            implicit_csg: self.implicit_csg,
            media: !self.media.is_empty(),
            instances: self.frame.instance_count > 0,
            csg: self.frame.csg_first < self.frame.primitive_count,
            noise: self.textures.iter().any(|t| super::pack::texture_uses_noise(t, &self.texture_data)),
            emission_textures: self.materials.iter().any(|m| m.emission_tex != NO_TEXTURE),
            material_kinds: self.materials.iter().fold(
                if self.media.is_empty() { 0 } else { 1 << MATERIAL_PHASE },
                |kinds, m| {
                    let beckmann = if m.flags & MATERIAL_FLAG_BECKMANN != 0 { 1 << SCENE_KIND_BECKMANN } else { 0 };
                    kinds | 1 << m.kind | beckmann
                },
            ),
            path_traced: self.frame.integrator == INTEGRATOR_PT,
            bidirectional: self.frame.integrator == INTEGRATOR_BPT || self.frame.integrator == INTEGRATOR_VCM,
            pages: 1,
            page_words_log2: DEFAULT_PAGE_WORDS_LOG2,
        }
    }

    /// Whether a caustic photon pass can store anything: caustic paths end at the first surface
    /// with an estimate lobe, so only scenes with a material that can lack one (mirror, glass,
    /// metal, plastic with a black or textured base, mixes of these) get caustic photons. Scenes
    /// of diffuse surfaces skip the caustic pass (its paths would each cost a ray and store
    /// nothing); their images are unchanged.
    pub fn can_store_caustics(&self) -> bool {
        self.materials.iter().any(|m| {
            matches!(
                m.kind,
                MATERIAL_MIRROR
                    | MATERIAL_DIELECTRIC
                    | MATERIAL_THIN_DIELECTRIC
                    | MATERIAL_CONDUCTOR
                    | MATERIAL_PLASTIC
                    | MATERIAL_MIX
            )
        })
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
            media: &self.media,
            maps: crate::cpu::NO_MAPS,
            wide: Some(
                self.wide.get_or_init(|| WideBvh::build(&self.frame, &self.nodes, &self.primitives, &self.shape_data)),
            ),
            pixel_list: &[],
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

/// A light's power in the two distributions (direct light, photons): 0 where it takes no part.
fn light_powers(power: f32, direct: bool, photons: bool) -> (f32, f32) {
    (if direct { power } else { 0.0 }, if photons { power } else { 0.0 })
}

/// The light record of a point, spot or distant light and its power (W, mean of the channels),
/// or `None` for the options of an area light (its primitives are its records).
pub fn light_record(kind: &LightKind, bounding_center: Vec3, bounding_radius: f32) -> Option<(Light, f32)> {
    let (light, power) = match *kind {
        LightKind::Point { position, intensity } => {
            // An isotropic point light of intensity I emits power 4 pi I. Its cone is the sphere.
            let light = Light {
                position: position.into(),
                kind: LIGHT_POINT,
                intensity: intensity.into(),
                direction: [0.0, 1.0, 0.0],
                cos_outer: -1.0,
                falloff_scale: HARD_EDGE,
                ..Default::default()
            };
            (light, 4.0 * PI * channel_mean(intensity.into()))
        }
        LightKind::Spot { position, direction, intensity, cos_inner, cos_outer, exponent } => {
            let falloff_scale = if cos_inner > cos_outer { 1.0 / (cos_inner - cos_outer) } else { HARD_EDGE };
            let light = Light {
                position: position.into(),
                kind: LIGHT_SPOT,
                intensity: intensity.into(),
                direction: direction.into(),
                cos_outer,
                falloff_scale,
                exponent,
                ..Default::default()
            };
            (light, channel_mean(intensity.into()) * spot_solid_angle(&light))
        }
        LightKind::Distant { direction, irradiance, half_angle_deg, visible } => {
            // A cone of half-angle a and radiance L gives E = L pi sin^2 a on a surface facing it
            // and has solid angle 2 pi (1 - cos a): radiance times solid angle is
            // E 2 (1 - cos a) / sin^2 a, which tends to E as a -> 0.
            let a = (half_angle_deg as f64).to_radians();
            let ratio = if a > 0.0 { 2.0 * (1.0 - a.cos()) / (a.sin() * a.sin()) } else { 1.0 };
            // `area` holds the cone's solid angle (in f64: 1 - cos a of the sun's half-angle is
            // 1e-5, where f32's cos_outer keeps only two digits of it), so that the disc a
            // camera path sees has radiance intensity / area; 0 for a light with no disc.
            let light = Light {
                position: bounding_center.into(),
                kind: LIGHT_DISTANT,
                intensity: (irradiance * ratio as f32).into(),
                direction: direction.into(),
                cos_outer: a.cos() as f32,
                radius: bounding_radius,
                area: if visible && a > 0.0 { (2.0 * std::f64::consts::PI * (1.0 - a.cos())) as f32 } else { 0.0 },
                ..Default::default()
            };
            // The power that crosses the disc of the bounding sphere.
            (light, channel_mean(irradiance.into()) * PI * bounding_radius * bounding_radius)
        }
        LightKind::Area { .. } => return None,
    };
    Some((light, power))
}

/// True for a distant light whose disc camera paths see (see `light_record`).
fn has_visible_disc(l: &Light) -> bool {
    l.kind == LIGHT_DISTANT && l.area > 0.0
}

/// `falloff_scale` of a cone with no smooth part: any cos inside the cone gives t >= 1.
const HARD_EDGE: f32 = 1.0e30;

/// The integral of a spot light's profile over the sphere (steradians): power = I times this.
/// 2 pi times the integral over cos in [cos_outer, 1], by the midpoint rule in f64 (the profile
/// is smooth; 4096 steps leave an error far below the f32 of the result).
fn spot_solid_angle(l: &Light) -> f32 {
    const STEPS: u32 = 4096;
    let (lo, scale, exponent) = (l.cos_outer as f64, l.falloff_scale as f64, l.exponent as f64);
    let h = (1.0 - lo) / STEPS as f64;
    let sum: f64 = (0..STEPS)
        .map(|i| {
            let c = lo + (i as f64 + 0.5) * h;
            let t = ((c - lo) * scale).clamp(0.0, 1.0);
            t * t * (3.0 - 2.0 * t) * if exponent > 0.0 { c.max(0.0).powf(exponent) } else { 1.0 }
        })
        .sum();
    (2.0 * std::f64::consts::PI * sum * h) as f32
}

/// Builds the light tree over the lights that cast direct light (see `render::light_tree`) at
/// the end of the texture data; returns its word offset, or `NO_LIGHT`. Under `light_sampler =
/// "power"` the tree is empty and every light is picked beside it by power.
fn tree_lights(
    sampler: LightSampler,
    lights: &mut [Light],
    powers: &[(f32, f32)],
    (primitives, primitive_bounds): (&[Primitive], &[(Vec3, Vec3)]),
    materials: &[Material],
    texture_data: &mut Vec<u32>,
) -> u32 {
    let mut finite = Vec::new();
    let mut infinite = Vec::new();
    for (i, (l, &(direct, _))) in lights.iter().zip(powers).enumerate() {
        let i = i as u32;
        match l.kind {
            // Picked by power beside the tree: the infinite lights, and every light when asked.
            _ if sampler == LightSampler::Power => infinite.push((i, direct)),
            LIGHT_DISTANT | LIGHT_ENVIRONMENT => infinite.push((i, direct)),
            LIGHT_AREA => {
                let p = &primitives[l.primitive as usize];
                let (lo, hi) = primitive_bounds[l.primitive as usize];
                let one_sided = materials[p.material as usize].flags & MATERIAL_FLAG_TWO_SIDED == 0;
                let normal = (p.kind & PRIMITIVE_KIND_MASK == PRIMITIVE_TRIANGLE && one_sided)
                    .then(|| (Vec3::from(p.p1) - Vec3::from(p.p0)).cross(Vec3::from(p.p2) - Vec3::from(p.p0)));
                finite.push((i, light_tree::area_bounds(lo, hi, normal, direct)));
            }
            _ => finite.push((i, light_tree::point_bounds(l, direct))),
        }
    }
    light_tree::build(lights, &finite, &infinite, texture_data)
}

/// Fills one pick distribution (probability and running cdf) from `power(powers[i])`; returns
/// the total. A light of power 0 gets an empty interval; the last light with power gets cdf 1
/// (and every light after it), so a pick of u close to 1 never falls past it.
fn fill_cdf(
    lights: &mut [Light],
    powers: &[(f32, f32)],
    power: impl Fn(&(f32, f32)) -> f32,
    mut set: impl FnMut(&mut Light, f32, f32),
) -> f64 {
    let total: f64 = powers.iter().map(|p| power(p) as f64).sum();
    let last = powers.iter().rposition(|p| power(p) > 0.0);
    let mut running = 0.0f64;
    for (i, (light, p)) in lights.iter_mut().zip(powers).enumerate() {
        running += power(p) as f64;
        let (probability, cdf) = if total > 0.0 { (power(p) as f64 / total, running / total) } else { (0.0, 0.0) };
        let cdf = if last.is_some_and(|last| i >= last) { 1.0 } else { cdf as f32 };
        set(light, probability as f32, cdf);
    }
    total
}

/// Why a scene cannot be prepared. Loading checks scene files so that only hand-built scenes
/// meet the last two.
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error(
        "{path}: {instances} instances of a scene of {primitives} primitives are too many to name every hit in 32 \
         bits ((instances + 1) x primitives must stay below 2^32); use fewer instances or smaller objects (see \
         docs/limits.md)"
    )]
    TooManyInstances { path: String, instances: u32, primitives: usize },
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
    let mut packed = packed;
    // The objects that instances place: their primitives after the world BVH's, their nodes
    // (the top level, then each object's BVH) after its nodes.
    let instanced = pack_instances(
        scene,
        &mut packed.shape_data,
        &mut packed.csg_primitives,
        bvh.nodes.len() as u32,
        bvh.primitives.len() as u32,
    )?;
    let mut primitives = bvh.primitives;
    primitives.extend(&instanced.primitives);
    let unbounded_first = primitives.len() as u32;
    primitives.extend(unbounded.iter().map(|&i| packed.primitives[i]));
    // The CSG objects' leaves come last: no ray meets them but through their object's walk.
    // `primitive_count` counts them too: it is the stride of instances' hit names, which must
    // stay above every world primitive's index, the CSG leaves' included.
    let csg_first = primitives.len() as u32;
    primitives.extend_from_slice(&packed.csg_primitives);
    let primitive_count = primitives.len() as u32;
    // Areas follow the primitives into BVH order (their bounds and areas are keyed by the
    // original index, which the reorder keeps in `order`). The objects' primitives have none
    // here: they are never lights.
    let areas: Vec<f32> = bvh
        .order
        .iter()
        .map(|&i| bounded.get(i as usize).map_or(0.0, |&j| packed.areas[j]))
        .chain(instanced.primitives.iter().map(|_| 0.0))
        .chain(unbounded.iter().map(|_| 0.0))
        .collect();
    let primitive_bounds: Vec<(Vec3, Vec3)> = bvh
        .order
        .iter()
        .map(|&i| bounded.get(i as usize).map_or((Vec3::ZERO, Vec3::ZERO), |&j| packed.bounds[j]))
        .collect();
    // A hit on an instance is named (instance + 1) x primitive count + primitive, in one u32.
    let names = (instanced.instance_count as u64 + 1) * primitives.len() as u64;
    if names >= NO_LIGHT as u64 {
        return Err(PrepareError::TooManyInstances {
            path: path(),
            instances: instanced.instance_count,
            primitives: primitives.len(),
        });
    }

    // Bounds of the shapes in the BVH and of the instances (not the infinite planes)
    let flat_root = &bvh.nodes[0];
    let (lo, hi) = (
        Vec3::from(flat_root.aabb_min).min(instanced.bounds.0),
        Vec3::from(flat_root.aabb_max).max(instanced.bounds.1),
    );
    let root = &BvhNode { aabb_min: lo.into(), aabb_max: hi.into(), ..*flat_root };
    let (bounding_center, bounding_radius) =
        if lo.cmple(hi).all() { ((lo + hi) * 0.5, (hi - lo).length() * 0.5) } else { (Vec3::ZERO, 1.0) };
    // Distant lights and the environment send their photons through the disc of that bounding
    // sphere. A scene of infinite planes alone has none (its BVH is one empty leaf, radius 0): a
    // unit sphere at the origin stands in, so that those lights keep a power and stay lights.
    let (light_center, light_radius) = if bounded.is_empty() && instanced.instance_count == 0 {
        (Vec3::ZERO, 1.0)
    } else {
        (bounding_center, bounding_radius)
    };

    // Lights: distant lights with a disc (camera paths that leave the scene look for them at
    // the front of the list, see `distant_discs_radiance`), emissive primitives (in BVH order),
    // then the other lights of the file.
    let mut lights = Vec::new();
    let mut powers = Vec::new();
    let file_lights: Vec<_> = scene
        .lights
        .iter()
        .filter_map(|desc| {
            let (light, power) = light_record(&desc.kind, light_center, light_radius)?;
            (!power.is_nan() && power > 0.0).then_some((light, light_powers(power, desc.direct, desc.photons)))
        })
        .collect();
    let (discs, others): (Vec<_>, Vec<_>) = file_lights.into_iter().partition(|(l, _)| has_visible_disc(l));
    for (light, power) in discs {
        lights.push(light);
        powers.push(power);
    }
    for (i, (p, &area)) in primitives.iter_mut().zip(&areas).enumerate() {
        let Some(material) = scene.materials.get(p.material as usize) else { continue };
        // A textured emission's power is estimated from its constant (the texture scales it
        // by at most its values; the pick probability only steers sampling, it keeps no bias).
        let emission = material.emission.value;
        // A Lambertian emitter of radiance L and area A emits power pi * A * L. A light of no
        // power (or one so faint its power rounds to 0) is left out: were every light such, the
        // pick probabilities would be 0 / 0.
        // A two-sided one, twice that.
        let sides = if material.two_sided { 2.0 } else { 1.0 };
        let power = sides * PI * area * channel_mean(emission.into());
        if power.is_nan() || power <= 0.0 {
            continue;
        }
        p.light = lights.len() as u32;
        let options =
            scene.lights.iter().find(|l| matches!(l.kind, LightKind::Area { material, .. } if material == p.material));
        powers.push(light_powers(power, options.is_none_or(|o| o.direct), options.is_none_or(|o| o.photons)));
        let grid = match options.map(|o| &o.kind) {
            Some(&LightKind::Area { grid: [n, m], jitter, adaptive, .. }) if n * m > 1 => {
                n | m << 8 | if jitter { LIGHT_GRID_JITTER } else { 0 } | if adaptive { LIGHT_GRID_ADAPTIVE } else { 0 }
            }
            _ => 0,
        };
        // `cos_outer`: the emitter's cone about its normal, the hemisphere or (two-sided) the sphere.
        let cos_outer = if material.two_sided { -1.0 } else { 0.0 };
        lights.push(Light { kind: LIGHT_AREA, primitive: i as u32, area, grid, cos_outer, ..Default::default() });
    }
    for (light, power) in others {
        lights.push(light);
        powers.push(power);
    }
    let mut texture_data = packed.texture_data;
    let mut environment = NO_LIGHT;
    if let Some(env) = &scene.environment {
        let (offset, integral) = pack_environment(&env.image, env.rotation_deg, &mut texture_data);
        // The power that enters the bounding sphere's disc from every direction. A black
        // environment is left out like any light of no power (rays that leave see black anyway).
        let power = integral as f32 * PI * light_radius * light_radius;
        if !power.is_nan() && power > 0.0 {
            environment = lights.len() as u32;
            lights.push(Light {
                position: light_center.into(),
                kind: LIGHT_ENVIRONMENT,
                primitive: offset,
                radius: light_radius,
                ..Default::default()
            });
            powers.push(light_powers(power, env.direct, env.photons));
        }
    }
    let total_power: f64 = powers.iter().map(|&(direct, photons)| direct.max(photons) as f64).sum();
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
    fill_cdf(
        &mut lights,
        &powers,
        |p| p.0,
        |l, probability, cdf| {
            l.pick_probability = probability;
            l.cdf = cdf;
        },
    );
    let total_photon = fill_cdf(
        &mut lights,
        &powers,
        |p| p.1,
        |l, probability, cdf| {
            l.photon_probability = probability;
            l.photon_cdf = cdf;
        },
    );
    let light_tree = tree_lights(
        scene.render.light_sampler,
        &mut lights,
        &powers,
        (&primitives, &primitive_bounds),
        &packed.materials,
        &mut texture_data,
    );

    // An infinite plane holds photons over the part of it near the rest of the scene: its disc
    // inside the sphere around the bounded shapes, the point and spot lights and the camera.
    // (Distant lights and the environment send theirs through the bounding sphere's disc only.)
    let mut surface_area = packed.photon_area + instanced.photon_area;
    if !unbounded.is_empty() {
        let mut extent = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        if lo.cmple(hi).all() {
            extent = (lo, hi);
        }
        let positions = scene.lights.iter().filter_map(|l| match l.kind {
            LightKind::Point { position, .. } | LightKind::Spot { position, .. } => Some(position),
            LightKind::Distant { .. } | LightKind::Area { .. } => None,
        });
        for p in positions.chain([scene.camera.position]) {
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
                surface_area += PI * (radius * radius - distance * distance).max(0.0) * visible;
            }
        }
    }
    if let Some(e) = overflow("total surface area", surface_area as f64) {
        return Err(e);
    }

    // Camera
    let cam = &scene.camera;
    let (forward, right, up) = cam.basis().ok_or_else(|| PrepareError::Camera { path: path() })?;
    let aspect = settings.width as f32 / settings.height as f32;
    // `right` and `up` carry the film's half-extent: tangents of the half field of view, half
    // the view's size in scene units, or nothing (latlong).
    let (camera_kind, half_height) = match cam.projection {
        Projection::Perspective => (CAMERA_PERSPECTIVE, (cam.fov_deg.to_radians() * 0.5).tan()),
        Projection::Orthographic { view_height } => (CAMERA_ORTHOGRAPHIC, 0.5 * view_height),
        Projection::LatLong => (CAMERA_LATLONG, 1.0),
    };
    let half_width = if camera_kind == CAMERA_LATLONG { 1.0 } else { half_height * aspect };
    let lens = cam.lens.unwrap_or(ThinLens { radius: 0.0, focal_distance: 1.0, blades: 0, rotation_deg: 0.0 });
    let scale = bounding_radius.max(cam.position.distance(bounding_center));
    let frame = FrameParams {
        camera_position: cam.position.into(),
        width: settings.width,
        camera_forward: forward.into(),
        height: settings.height,
        camera_right: (right * half_width).into(),
        max_depth: settings.max_depth,
        camera_up: (up * half_height).into(),
        seed: settings.seed,
        light_count: lights.len() as u32,
        ray_epsilon: scale * RAY_EPSILON_SCALE,
        primitive_count,
        csg_first,
        node_count: (bvh.nodes.len() + instanced.nodes.len()) as u32,
        total_light_power: total_photon as f32,
        photon_mapping: 0,
        gather_rays: 0,
        glossy_threshold: scene.photons.map_or(GLOSSY_THRESHOLD, |p| p.glossy_threshold),
        camera_kind,
        lens_radius: lens.radius,
        focal_distance: lens.focal_distance,
        aperture_blades: lens.blades,
        aperture_rotation: lens.rotation_deg.to_radians(),
        environment,
        unbounded_first,
        camera_medium: NO_MEDIUM,
        instance_count: instanced.instance_count,
        instance_data: instanced.instance_data,
        integrator: scene.render.integrator.code(),
        techniques: TECHNIQUES_ALL,
        pixel_filter: scene.render.filter.code(),
        filter_scale: scene.render.filter_scale(),
        light_tree,
    };
    // Media: the null material needs the media variant's kernels even without a medium.
    let tracking_boxes = super::media_bounds::tracking_boxes(scene, &packed.bounds, root, cam.position);
    let mut media: Vec<Medium> =
        scene.media.iter().zip(tracking_boxes).map(|(m, b)| super::pack::pack_medium(m, b)).collect();
    let has_null = scene.materials.iter().any(|m| m.kind == crate::scene::MaterialKind::Null);
    if media.is_empty() && has_null {
        media.push(Medium { density: NO_TEXTURE, ..Medium::default() });
    }
    let mut media_volume = 0.0f32;
    if !scene.media.is_empty() {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for (shape, (blo, bhi)) in scene.shapes.iter().zip(&packed.bounds) {
            if shape.media.is_some_and(|m| m.interior.is_some()) {
                (lo, hi) = (lo.min(*blo), hi.max(*bhi));
            }
        }
        if scene.atmosphere.is_some() && root.aabb_min[0] <= root.aabb_max[0] {
            (lo, hi) = (lo.min(Vec3::from(root.aabb_min)), hi.max(Vec3::from(root.aabb_max)));
        }
        if lo.cmple(hi).all() {
            let size = (hi - lo).max(Vec3::splat(bounding_radius * 1e-3));
            media_volume = size.x * size.y * size.z;
        }
    }
    let mut nodes = bvh.nodes;
    nodes.extend(instanced.nodes);
    let mut buffers = SceneBuffers {
        frame,
        nodes,
        primitives,
        materials: packed.materials,
        lights,
        textures: packed.textures,
        texture_data,
        shape_data: packed.shape_data,
        textured: packed.textured || instanced.alpha,
        analytic: packed.analytic || instanced.analytic,
        implicit: packed.implicit || instanced.implicit,
        implicit_csg: packed.implicit_csg || instanced.implicit_csg,
        alpha: packed.alpha || instanced.alpha,
        bounding_radius,
        surface_area,
        media,
        media_volume,
        wide: OnceLock::new(),
    };
    // Lights start in vacuum unless a medium is found around them.
    for l in &mut buffers.lights {
        l.medium = NO_MEDIUM;
    }
    locate_media(&mut buffers, scene.atmosphere.unwrap_or(NO_MEDIUM));
    Ok(buffers)
}

/// Finds the medium around the camera and around each light (where its photons start): a ray
/// from the point goes out until it meets a medium boundary; crossing it outward means the
/// point was inside (its interior), inward that it was outside (its exterior). A point that
/// meets no boundary is in the atmosphere. Distant lights and the environment start theirs
/// outside everything, in the atmosphere.
fn locate_media(buffers: &mut SceneBuffers, atmosphere: u32) {
    if buffers.media.is_empty() {
        return;
    }
    let camera = Vec3::from(buffers.frame.camera_position);
    let view = buffers.view();
    let at = |p: Vec3| medium_at(&view, p, atmosphere);
    let camera_medium = at(camera);
    let light_media: Vec<u32> = buffers
        .lights
        .iter()
        .map(|l| match l.kind {
            LIGHT_POINT | LIGHT_SPOT => at(Vec3::from(l.position)),
            LIGHT_AREA => {
                // A point just off the emitter's front face, at its centre.
                let p = &view.primitives[l.primitive as usize];
                let centre = if p.kind & PRIMITIVE_KIND_MASK == PRIMITIVE_TRIANGLE {
                    let (a, b, c) = (Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2));
                    (a + b + c) / 3.0 + (b - a).cross(c - a).normalize_or_zero() * (4.0 * view.frame.ray_epsilon)
                } else {
                    Vec3::from(p.p0)
                };
                at(centre)
            }
            _ => atmosphere,
        })
        .collect();
    buffers.frame.camera_medium = camera_medium;
    for (l, m) in buffers.lights.iter_mut().zip(light_media) {
        l.medium = m;
    }
}

/// The medium at `p` (see `locate_media`): the ray runs along a fixed direction of no symmetry,
/// so it does not graze the edges of axis-aligned boxes.
pub fn medium_at(view: &crate::cpu::SceneView, p: Vec3, atmosphere: u32) -> u32 {
    use crate::cpu::shading::offset_origin;
    let d = Vec3::new(0.5773, 0.6157, 0.5362).normalize();
    let mut o = p;
    let mut skip = NO_LIGHT;
    for _ in 0..100_000 {
        let (prim, t) = crate::cpu::trace::trace_ray(view, o, d, f32::INFINITY, false, skip);
        if prim == NO_LIGHT {
            return atmosphere;
        }
        let h = crate::cpu::shape::shape_hit(view, prim, o, d, t);
        let q = &view.primitives[crate::cpu::instance::hit_primitive(view, prim) as usize];
        if q.kind & PRIMITIVE_FLAG_MEDIUM != 0 {
            return if d.dot(h.ng) > 0.0 { q.interior } else { q.exterior };
        }
        o = offset_origin(&h, -d, BSDF_TRANSMISSION);
        skip = crate::cpu::shading::ray_skip(view, prim);
    }
    atmosphere
}
