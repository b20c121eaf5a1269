//! Scene format v1: TOML scene files (documented in `docs/scene-format.md`), checked and turned
//! into a renderer-agnostic description: shapes (triangles, analytic spheres and the analytic
//! shapes of `analytic.rs`: planes, discs, cones and cylinders, tori, superellipsoids), materials,
//! textures, lights (point, spot, distant, and the options of area lights), the environment and
//! the photon settings. Nothing here knows the GPU's structs; the
//! renderer packs this description for its kernels in one place (`render::pack`).
//!
//! Light sources are every shape whose material has `emission` > 0, plus the point, spot and
//! distant lights and the environment; the renderer builds its light list from those. An area
//! light of the file becomes ordinary shapes with its own material, named `light <index>`
//! (diffuse, reflectance 0, emission = its radiance).

pub mod analytic;
mod auto_integrator;
mod convert;
pub mod csg;
mod error;
pub mod files;
mod format;
pub mod front_end;
pub mod gltf_scene;
mod material;
pub use auto_integrator::auto_integrator;
mod medium;
pub mod mitsuba;
pub mod model;
pub mod pattern;
mod photons;
pub mod pov;
pub mod sky;
pub mod voxel;

pub mod image_texture;
pub mod kinds;

use std::path::{Path, PathBuf};

use glam::{Mat3, Vec2, Vec3};

pub use analytic::{Analytic, AnalyticKind};
pub use csg::{Csg, CsgNode, CsgOp};
pub use error::SceneError;
pub use material::{
    Channel, ColorParam, Distribution, ImageProjection, MaterialDesc, MaterialKind, NormalMod, Roughness, ScalarParam,
    TextureDesc, TextureKind, TextureSpace,
};
pub use medium::{Density, MediumDesc, MediumInterface, Phase};
pub use photons::PhotonSettings;

/// A loaded, validated scene. Right-handed, y up, lengths in scene units.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The file stem, e.g. "cornell-box".
    pub name: String,
    /// The file it came from.
    pub path: PathBuf,
    pub camera: Camera,
    pub render: RenderSettings,
    /// Photon mapping settings; `None` renders direct light and specular paths only.
    pub photons: Option<PhotonSettings>,
    /// Index = material id. Materials of the file in file order, then one per area light.
    pub materials: Vec<MaterialDesc>,
    /// Name of each material, same index as `materials`.
    pub material_names: Vec<String>,
    /// Index = texture id, in file order.
    pub textures: Vec<TextureDesc>,
    pub shapes: Vec<Shape>,
    /// The lights of `[[lights]]` in file order: point, spot and distant lights, and for each
    /// area light the options of the shapes that carry its material.
    pub lights: Vec<LightDesc>,
    /// What rays that leave the scene see, and a light of its own; `None` is black.
    pub environment: Option<Environment>,
    /// Index = medium id, in file order (`[media.NAME]`).
    pub media: Vec<MediumDesc>,
    pub medium_names: Vec<String>,
    /// The medium that fills space outside every closed medium shape (`[atmosphere]`).
    pub atmosphere: Option<u32>,
    /// Problems that do not stop rendering, e.g. "scene has no lights; the image will be black".
    pub warnings: Vec<String>,
    /// The objects of `[objects.NAME]` that some instance places, in file order; their shapes
    /// are in object space and appear in `shapes` only through `instances`.
    pub objects: Vec<ObjectDesc>,
    /// Every placement of an object, nested placements resolved (their transforms composed).
    pub instances: Vec<InstanceDesc>,
    /// Every file the scene read, resolved through links: the scene file (when it exists), then
    /// textures, environment maps, models with their MTL files, buffers and images, voxel grids.
    /// No command may write over one of them (`io::image::check_not_input`).
    pub inputs: Vec<PathBuf>,
}

impl Scene {
    /// Names the integrator (`Some`), or lets `auto_integrator` choose (`None`), as it does for a
    /// scene that names none.
    pub fn set_integrator(&mut self, named: Option<Integrator>) {
        (self.render.integrator, self.render.integrator_auto) = match named {
            Some(integrator) => (integrator, None),
            None => {
                let threshold = self.photons.as_ref().map(|p| p.glossy_threshold);
                let (integrator, why) = auto_integrator(&self.materials, &self.lights, self.media.len(), threshold);
                (integrator, Some(why))
            }
        };
    }

    /// The caller gave photon-map options (command-line flags, Python arguments): they ask for
    /// photon mapping, so an automatic choice yields to them; a named integrator stays.
    pub fn photon_options_given(&mut self) {
        if self.render.integrator_auto.is_some() {
            (self.render.integrator, self.render.integrator_auto) =
                (Integrator::Ppm, Some("photon-map options were given"));
        }
    }
}

/// A named object: shapes defined once (object space) and placed by instances. No shape of an
/// object is unbounded (an infinite plane) or emits light (instanced emitters are not sampled).
#[derive(Clone, Debug)]
pub struct ObjectDesc {
    pub name: String,
    pub shapes: Vec<Shape>,
}

/// One placement of object `object` (index in `Scene::objects`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceDesc {
    pub object: u32,
    /// Invertible.
    pub world_from_object: glam::Affine3A,
    /// A material that replaces every material of the object; `None` keeps them.
    pub material: Option<u32>,
}

impl Scene {
    /// The triangles of the scene with their materials.
    pub fn triangles(&self) -> impl Iterator<Item = (&Triangle, u32)> {
        self.shapes.iter().filter_map(|s| match &s.geometry {
            Geometry::Triangle(t) => Some((t, s.material)),
            _ => None,
        })
    }

    /// The spheres of the scene with their materials.
    pub fn spheres(&self) -> impl Iterator<Item = (&Sphere, u32)> {
        self.shapes.iter().filter_map(|s| match &s.geometry {
            Geometry::Sphere(sphere) => Some((sphere, s.material)),
            _ => None,
        })
    }
}

/// The camera: where it is, how film positions become rays, and the image size.
#[derive(Clone, Debug)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    /// Not necessarily perpendicular to the view direction, nor normalised; never parallel to it.
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180); used by the perspective projection.
    pub fov_deg: f32,
    pub projection: Projection,
    /// A thin lens (depth of field); `None` is a pinhole.
    pub lens: Option<ThinLens>,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// The camera's frame, (forward, right, up), unit length and orthogonal; right-handed:
    /// right = forward x up, so with forward +z and up +y it is -x. `None` when 32-bit floats
    /// cannot make one: `look_at` (nearly) equals `position`, or `up` is (nearly) zero or parallel
    /// to the view direction. Loading refuses such a camera; the renderer reads this same frame.
    pub fn basis(&self) -> Option<(Vec3, Vec3, Vec3)> {
        let forward = (self.look_at - self.position).try_normalize()?;
        // Parallel to within 1e-6 radians: the right vector would be mostly rounding noise.
        let sine = forward.cross(self.up.try_normalize()?).length();
        if sine.is_nan() || sine <= 1e-6 {
            return None;
        }
        let right = forward.cross(self.up).try_normalize()?;
        Some((forward, right, right.cross(forward)))
    }
}

/// How film positions map to rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole or thin lens with the vertical field of view `Camera::fov_deg`.
    Perspective,
    /// Parallel rays; `view_height` is the height of the view in scene units (its width follows
    /// the image's aspect ratio).
    Orthographic { view_height: f32 },
    /// Every direction: longitude across the image (-180..180 degrees, 0 straight ahead),
    /// latitude up it (-90..90).
    LatLong,
}

/// A thin lens: rays leave a point of the aperture and meet where the pinhole ray meets the
/// plane in focus.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLens {
    /// Aperture radius, scene units, > 0.
    pub radius: f32,
    /// Distance of the plane in focus along the view direction, scene units, > 0.
    pub focal_distance: f32,
    /// Blades of a polygonal aperture (3 or more); 0 for a round one.
    pub blades: u32,
    /// Angle of the first corner from the image's up toward its right, degrees.
    pub rotation_deg: f32,
}

#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Samples per pixel in each progressive pass, >= 1.
    pub spp: u32,
    /// Progressive passes, >= 1; the image is their mean.
    pub passes: u32,
    /// Most specular bounces of a path, >= 1.
    pub max_depth: u32,
    pub seed: u32,
    /// The estimator (`[render] integrator`, `--integrator`).
    pub integrator: Integrator,
    /// Why `integrator` was chosen for the scene when it names none (`auto_integrator`); `None`
    /// when the scene or the caller named it.
    pub integrator_auto: Option<&'static str>,
    /// The reconstruction filter (`[render] filter`).
    pub filter: Filter,
    /// How far the filter reaches from a pixel's centre, in pixels (`[render] filter_radius`);
    /// `None`: the filter's own, `Filter::default_radius`.
    pub filter_radius: Option<f32>,
    /// Denoise the image with Open Image Denoise (`[render] denoise`, `--denoise`).
    pub denoise: bool,
    /// How light sampling at a shading point picks its light (`[render] light_sampler`).
    pub light_sampler: LightSampler,
    /// Adaptive sampling in progressive renders (`[render] adaptive`, `--adaptive`).
    pub adaptive: bool,
}

/// How light sampling at a shading point picks the light (`[render] light_sampler`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSampler {
    /// The light tree: by each light's importance for the point (the default).
    #[default]
    Tree,
    /// In proportion to power, wherever the point is: the baseline the tree is measured against.
    Power,
}

impl LightSampler {
    pub const NAMES: [(&'static str, LightSampler); 2] = [("tree", LightSampler::Tree), ("power", LightSampler::Power)];
}

impl RenderSettings {
    /// `FrameParams::filter_scale`: the filter's radius over its default.
    pub fn filter_scale(&self) -> f32 {
        self.filter_radius.map_or(1.0, |r| r / self.filter.default_radius())
    }
}

/// The pixel reconstruction filter, with Mitsuba 3's radii: how much a film point counts toward
/// each pixel near it (see `FILTER_*`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Each pixel the mean of its own square (the default, Photonix's before filters).
    #[default]
    Box,
    /// 1 - |x| per axis over a radius of 1 pixel.
    Tent,
    /// Standard deviation 0.5 pixel, truncated at 2 pixels.
    Gaussian,
}

impl Filter {
    pub const NAMES: [(&'static str, Filter); 3] =
        [("box", Filter::Box), ("tent", Filter::Tent), ("gaussian", Filter::Gaussian)];

    /// How far the filter reaches from a pixel's centre at its default size, in pixels (a
    /// Gaussian's: four standard deviations, as in Mitsuba).
    pub fn default_radius(self) -> f32 {
        match self {
            Filter::Box => 0.5,
            Filter::Tent => 1.0,
            Filter::Gaussian => crate::layout::constants::FILTER_GAUSSIAN_RADIUS,
        }
    }

    /// `FrameParams::filter`.
    pub fn code(self) -> u32 {
        match self {
            Filter::Box => crate::layout::constants::FILTER_BOX,
            Filter::Tent => crate::layout::constants::FILTER_TENT,
            Filter::Gaussian => crate::layout::constants::FILTER_GAUSSIAN,
        }
    }
}

/// How a render estimates light transport: one place that chooses (`render::render_cpu`,
/// `render::gpu`), like Mitsuba's integrators.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    /// Progressive photon mapping: light sampling, a caustic map and a final gather on a global
    /// map, a shrinking radius per pass.
    #[default]
    Ppm,
    /// Path tracing with light sampling, weighed by multiple importance sampling; no photons.
    Pt,
    /// Bidirectional path tracing: light sub-paths connected to camera sub-paths (`cpu::vcm`).
    Bpt,
    /// Vertex connection and merging: bidirectional path tracing plus merging with light
    /// vertices nearby, all weighed by multiple importance sampling (`cpu::vcm`).
    Vcm,
}

impl Integrator {
    /// Every integrator by its name in scene files and on the command line.
    pub const NAMES: &'static [(&'static str, Integrator)] =
        &[("ppm", Integrator::Ppm), ("pt", Integrator::Pt), ("bpt", Integrator::Bpt), ("vcm", Integrator::Vcm)];

    /// The name (`[render] integrator`, `--integrator`, Python's `integrator=`) that lets
    /// `auto_integrator` choose.
    pub const AUTO: &'static str = "auto";

    pub fn from_name(name: &str) -> Option<Integrator> {
        Self::NAMES.iter().find(|(n, _)| *n == name).map(|&(_, i)| i)
    }

    pub fn name(self) -> &'static str {
        Self::NAMES.iter().find(|(_, i)| *i == self).map_or("ppm", |(n, _)| n)
    }

    /// `FrameParams::integrator`.
    pub fn code(self) -> u32 {
        match self {
            Integrator::Ppm => crate::layout::constants::INTEGRATOR_PPM,
            Integrator::Pt => crate::layout::constants::INTEGRATOR_PT,
            Integrator::Bpt => crate::layout::constants::INTEGRATOR_BPT,
            Integrator::Vcm => crate::layout::constants::INTEGRATOR_VCM,
        }
    }

    /// Whether the integrator traces light sub-paths each sample (`cpu::vcm`).
    pub fn is_bidirectional(self) -> bool {
        matches!(self, Integrator::Bpt | Integrator::Vcm)
    }

    /// Whether the integrator reads photon maps (and so traces photons each pass).
    pub fn uses_photons(self) -> bool {
        self == Integrator::Ppm
    }
}

/// One shape of the scene: its geometry, its material id, and the media it bounds.
#[derive(Clone, Debug)]
pub struct Shape {
    pub geometry: Geometry,
    pub material: u32,
    /// The media inside and outside the closed shape this is (part of); `None` for a surface
    /// that leaves a ray's medium as it is.
    pub media: Option<MediumInterface>,
}

/// Every kind of geometry, behind one match per host-side operation (bounds, area).
#[derive(Clone, Debug)]
pub enum Geometry {
    Triangle(Triangle),
    Sphere(Sphere),
    /// Plane, disc, cone or cylinder side, torus, superellipsoid (`analytic.rs`).
    Analytic(Analytic),
    /// A CSG object of closed shapes (`csg.rs`).
    Csg(Box<Csg>),
}

impl Geometry {
    /// Axis-aligned bounds (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Geometry::Triangle(t) => {
                let [a, b, c] = t.vertices;
                (a.min(b).min(c), a.max(b).max(c))
            }
            Geometry::Sphere(s) => (s.center - Vec3::splat(s.radius), s.center + Vec3::splat(s.radius)),
            Geometry::Analytic(a) => a.bounds(),
            Geometry::Csg(c) => c.bounds(),
        }
    }

    /// True for shapes no box bounds (the infinite plane): they stay out of the BVH.
    pub fn is_unbounded(&self) -> bool {
        matches!(self, Geometry::Analytic(a) if a.is_unbounded())
    }

    /// True for the shapes that need the kernels' `analytic` variant: the analytic ones (planes,
    /// discs, cones, tori, superellipsoids) and CSG objects (their leaves may be any of them).
    pub fn is_analytic(&self) -> bool {
        matches!(self, Geometry::Analytic(_) | Geometry::Csg(_))
    }

    /// True for the shapes that need the `analytic_implicit` variant: tori, superellipsoids and
    /// CSG objects with one among their leaves.
    pub fn is_implicit(&self) -> bool {
        match self {
            Geometry::Analytic(a) => matches!(a.kind, AnalyticKind::Torus { .. } | AnalyticKind::Superellipsoid { .. }),
            Geometry::Csg(c) => c.leaves.iter().flatten().any(|s| s.geometry.is_implicit()),
            _ => false,
        }
    }

    /// True for CSG objects with a torus or a superellipsoid among their leaves: they need the
    /// `analytic_implicit_csg` variant.
    pub fn is_implicit_csg(&self) -> bool {
        matches!(self, Geometry::Csg(_)) && self.is_implicit()
    }

    /// Surface area in scene units squared (infinite for the plane).
    pub fn area(&self) -> f32 {
        match self {
            Geometry::Triangle(t) => {
                let [a, b, c] = t.vertices;
                0.5 * (b - a).cross(c - a).length()
            }
            Geometry::Sphere(s) => 4.0 * std::f32::consts::PI * s.radius * s.radius,
            Geometry::Analytic(a) => a.area(),
            Geometry::Csg(c) => c.area(),
        }
    }
}

/// A triangle with non-zero area. Its front face is the side (v1-v0)x(v2-v0) points to.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    pub vertices: [Vec3; 3],
    /// Texture coordinates of the vertices; `None` means (0, 0), (1, 0), (0, 1).
    pub uv: Option<[Vec2; 3]>,
    /// Unit vertex normals on the side of the winding normal, for smooth shading; `None` is flat.
    pub normals: Option<[Vec3; 3]>,
}

/// An analytic sphere; its front face is outward. Its uv is longitude/latitude about its own
/// +y axis, turned by `object_from_world`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    /// Scene units, > 0.
    pub radius: f32,
    /// Rotation into the sphere's own frame; `None` is the identity.
    pub object_from_world: Option<Mat3>,
}

/// The environment: radiance from every direction, as a latitude-longitude image (an HDR map,
/// or a gradient or uniform sky drawn into one). Row 0 is the zenith (+y), the middle column
/// looks toward -z and the column at three quarters toward +x, before `rotation_deg`.
#[derive(Clone, Debug)]
pub struct Environment {
    /// Linear RGB radiance, already scaled by the file's `strength`.
    pub image: std::sync::Arc<image_texture::ImageTexture>,
    /// Rotation about +y, degrees, right-handed: 90 turns the image's middle from -z to -x.
    pub rotation_deg: f32,
    /// As `LightDesc::direct` and `LightDesc::photons`.
    pub direct: bool,
    pub photons: bool,
}

/// A light of `[[lights]]`, with the options every kind takes.
#[derive(Clone, Debug)]
pub struct LightDesc {
    pub kind: LightKind,
    /// Whether the light casts direct light (shadow rays); false: it lights the scene through
    /// its photons only (indirect light and caustics).
    pub direct: bool,
    /// Whether the light emits photons; false: direct light only.
    pub photons: bool,
}

impl LightDesc {
    /// A light with both direct light and photons.
    pub fn new(kind: LightKind) -> LightDesc {
        LightDesc { kind, direct: true, photons: true }
    }
}

/// Every kind of light, behind one match per host-side operation (the light records of
/// `render::prepare`).
#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    /// An isotropic point light; `intensity` in W/sr per channel, >= 0.
    Point { position: Vec3, intensity: Vec3 },
    /// A spot light: `intensity` (W/sr) along unit `direction`, falling off smoothly from the
    /// inner cone to the outer one (half-angles; cosines stored, `cos_inner` >= `cos_outer` > 0)
    /// and scaled by cos^`exponent` (POV-Ray's `tightness`, >= 0).
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, cos_inner: f32, cos_outer: f32, exponent: f32 },
    /// A distant light: light travels along unit `direction` with `irradiance` (W/m^2) on a
    /// surface facing it, from a cone of directions of half-angle `half_angle_deg` (0: sharp).
    /// Camera paths that leave the scene (directly or through mirrors and glass) see its disc
    /// when it has one and `visible` is true.
    Distant { direction: Vec3, irradiance: Vec3, half_angle_deg: f32, visible: bool },
    /// The options of an area light: they apply to the shapes of material `material`. `grid` is
    /// POV-Ray's `area_light` grid, [n, m] cells of stratified shadow samples over each of its
    /// shapes ([1, 1]: plain sampling), jittered in their cells or at the centres.
    /// `adaptive` (POV-Ray's): pixels whose shadow rays toward it disagree cast one ray per
    /// cell at each sample (see `LIGHT_GRID_ADAPTIVE`).
    Area { material: u32, grid: [u32; 2], jitter: bool, adaptive: bool },
}

/// Where the shapes of a `Scene` came from in its file: for each `[[shapes]]` entry and each
/// `[[lights]]` entry, in file order, the range of `Scene::shapes` it became (a quad is two
/// triangles, a closed cylinder three shapes, a mesh many; a point, spot or distant light none),
/// and for each `[[instances]]` entry the range of `Scene::instances` it became (a grid's copies
/// and the placements nested in its object). The editor uses it to map a click on a triangle
/// back to the entry to edit.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneOrigins {
    pub shapes: Vec<std::ops::Range<usize>>,
    pub lights: Vec<std::ops::Range<usize>>,
    pub instances: Vec<std::ops::Range<usize>>,
}

/// Reads and parses a scene file; mesh paths in it are relative to the file's folder. Files above
/// `limits::MAX_SCENE_FILE_BYTES` (and endless ones such as /dev/zero) are refused unread.
/// A `.pov` file is read by the POV-Ray front-end (`pov`), with its default options, and a
/// `.gltf` or `.glb` file as a whole glTF scene (`gltf_scene`), a `.xml` file as a Mitsuba scene
/// (`mitsuba`).
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    if pov::is_pov_path(path) {
        // The `.ini` beside the scene gives its size and frame, as POV-Ray reads it.
        return pov::load_pov(path, &pov::options_for(path, pov::Given::default())?);
    }
    if gltf_scene::is_gltf_path(path) {
        return gltf_scene::load_gltf(path);
    }
    if mitsuba::is_mitsuba_path(path) {
        return mitsuba::load_mitsuba(path);
    }
    let bytes = crate::limits::read_limited(path, crate::limits::MAX_SCENE_FILE_BYTES).map_err(|e| match e {
        Some(cause) => SceneError::Read { path: path.to_path_buf(), cause },
        None => SceneError::TooLarge { path: path.to_path_buf(), limit: crate::limits::MAX_SCENE_FILE_BYTES },
    })?;
    let source = String::from_utf8(bytes).map_err(|e| SceneError::Read {
        path: path.to_path_buf(),
        cause: std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("it is not UTF-8 text (bad byte at offset {})", e.utf8_error().valid_up_to()),
        ),
    })?;
    parse_scene(&source, path)
}

/// Parses scene text. `path` names the file in messages, gives the scene its name, and is the
/// base for relative mesh paths.
pub fn parse_scene(source: &str, path: &Path) -> Result<Scene, SceneError> {
    parse_scene_with_origins(source, path).map(|(scene, _)| scene)
}

/// `parse_scene`, also returning which shapes each entry of the file became.
pub fn parse_scene_with_origins(source: &str, path: &Path) -> Result<(Scene, SceneOrigins), SceneError> {
    parse_scene_in(source, path, None)
}

/// `parse_scene_with_origins` that reads no file outside `folder` (canonical), whatever the
/// scene or a model names: the editor's server. A file outside is an error that does not name
/// it (`files::FileError::Outside`).
pub fn parse_scene_in(source: &str, path: &Path, folder: Option<&Path>) -> Result<(Scene, SceneOrigins), SceneError> {
    let src = error::Source { text: source, path };
    let (result, mut inputs) = files::collect(folder, || -> Result<_, SceneError> {
        let file: format::SceneFile = toml::from_str(source).map_err(|e| src.toml_error(&e))?;
        convert::convert_with_origins(file, &src)
    });
    let (mut scene, origins) = result?;
    if let Ok(own) = std::fs::canonicalize(path) {
        inputs.retain(|p| *p != own);
        inputs.insert(0, own);
    }
    scene.inputs = inputs;
    Ok((scene, origins))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_light_and_transform_table_parse_as_documented() {
        let text = r#"
[camera]
position = [0, 1, 5]
look_at = [0, 1, 0]
fov = 40

[materials.white]
type = "diffuse"

[[shapes]]
type = "sphere"
material = "white"
center = [1, 0, 0]
radius = 1
[shapes.transform]
scale = 2
rotate = [0, 0, 90]
translate = [0, 1, 0]

[[lights]]
type = "area"
shape = "sphere"
center = [0, 3, 0]
radius = 0.25
radiance = 20
"#;
        let scene = parse_scene(text, Path::new("doc.toml")).unwrap();
        let spheres: Vec<_> = scene.spheres().collect();
        assert_eq!(spheres.len(), 2);
        // Scale 2 then rotate 90 degrees about z: (1,0,0) -> (2,0,0) -> (0,2,0), then +y.
        let s = spheres[0].0;
        assert!(s.center.abs_diff_eq(Vec3::new(0.0, 3.0, 0.0), 1e-5), "{}", s.center);
        assert_eq!(s.radius, 2.0);
        let light = &scene.materials[spheres[1].1 as usize];
        assert_eq!(light.emission.value, Vec3::splat(20.0));
        assert_eq!(scene.material_names[1], "light 0");
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }
}
