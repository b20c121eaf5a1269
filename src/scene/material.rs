//! Materials and textures as the scene describes them, independent of any renderer: each kind is
//! a variant with its parameters. `render::pack` turns them into the GPU's structs.

use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::image_texture::{ImageTexture, Wrap};
use super::pattern::{ColorMap, PatternDesc};
use super::voxel::VoxelGrid;

/// A colour parameter: a constant, optionally times a texture (index into `Scene::textures`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorParam {
    pub value: Vec3,
    pub texture: Option<u32>,
}

impl ColorParam {
    pub fn constant(value: Vec3) -> ColorParam {
        ColorParam { value, texture: None }
    }
}

/// A scalar parameter: a constant, optionally times a texture's first channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScalarParam {
    pub value: f32,
    pub texture: Option<u32>,
}

impl ScalarParam {
    pub fn constant(value: f32) -> ScalarParam {
        ScalarParam { value, texture: None }
    }
}

/// Microfacet widths along dpdu and dpdv (alpha itself, not a perceptual roughness to square),
/// each optionally times a texture's first channel, and the distribution of the microfacet
/// normals; (0, 0) is smooth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roughness {
    pub alpha: [f32; 2],
    pub texture: Option<u32>,
    pub distribution: Distribution,
}

impl Roughness {
    pub const SMOOTH: Roughness = Roughness { alpha: [0.0; 2], texture: None, distribution: Distribution::Ggx };

    /// Isotropic GGX of width `alpha`.
    pub fn ggx(alpha: f32) -> Roughness {
        Roughness { alpha: [alpha; 2], ..Roughness::SMOOTH }
    }
}

/// How a rough surface's microfacet normals are distributed (scene `distribution`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Distribution {
    /// GGX (Trowbridge-Reitz): long tails; alpha is its width.
    #[default]
    Ggx,
    /// Beckmann (Gaussian slopes; alpha is their RMS): Mitsuba's default for its rough plugins.
    Beckmann,
}

/// What a material does with light, by kind.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// Lambertian reflection of albedo `reflectance`, on both sides.
    Diffuse { reflectance: ColorParam },
    /// Perfect mirror tinted by `tint`, on both sides.
    Mirror { tint: ColorParam },
    /// Dielectric interface, index `ior` inside (the side opposite the front face), smooth or GGX.
    Dielectric { ior: f32, roughness: Roughness },
    /// Metal of complex index of refraction `eta` + i `k` per channel, smooth or GGX, both sides;
    /// its Fresnel reflectance times `tint` (Mitsuba's `specular_reflectance`).
    Conductor { eta: ColorParam, k: ColorParam, roughness: Roughness, tint: ColorParam },
    /// A diffuse base of albedo `reflectance` under a dielectric coat of index `ior`; with
    /// `nonlinear`, light bouncing under the coat is tinted by the base at every bounce
    /// (Mitsuba's `nonlinear`).
    Plastic { reflectance: ColorParam, ior: f32, roughness: Roughness, nonlinear: bool },
    /// A thin pane of index `ior`: Fresnel reflection summed over its inner bounces, the rest
    /// passing straight through (Mitsuba's `thindielectric`).
    ThinDielectric { ior: f32 },
    /// Material `b` where a hash of the point falls below `weight`, else `a` (material ids).
    Mix { a: u32, b: u32, weight: ScalarParam },
    /// An invisible interface: rays pass straight through; it only bounds a medium.
    Null,
}

/// A material: its kind, the radiance it emits from its front side, its opacity and what bends
/// its shading normal.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    pub kind: MaterialKind,
    pub emission: ColorParam,
    /// The emission leaves both faces (scene `two_sided`), not the front alone.
    pub two_sided: bool,
    /// In [0, 1]; below 1 the surface lets that fraction of rays through (stochastic alpha).
    pub opacity: ScalarParam,
    pub normal: NormalMod,
}

/// How a material bends its shading normal (never its geometric normal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalMod {
    None,
    /// The surface displaced along its normal by `strength` (scene units) times the texture's
    /// first channel.
    Bump {
        texture: u32,
        strength: f32,
    },
    /// A tangent-space normal map (OpenGL convention).
    NormalMap {
        texture: u32,
    },
}

impl MaterialDesc {
    /// A material of `kind` that emits nothing and is opaque.
    pub fn new(kind: MaterialKind) -> MaterialDesc {
        MaterialDesc {
            kind,
            emission: ColorParam::constant(Vec3::ZERO),
            two_sided: false,
            opacity: ScalarParam::constant(1.0),
            normal: NormalMod::None,
        }
    }

    /// True when some point of the material emits.
    pub fn emits(&self) -> bool {
        self.emission.value.max_element() > 0.0
    }

    /// True when the material reads the surface's uv or derivatives: a texture anywhere, or a
    /// bump or normal map (3D patterns move the lookup point along the derivatives for bumps).
    pub fn uses_uv(&self) -> bool {
        let textured = |p: &ColorParam| p.texture.is_some();
        let rough = |r: &Roughness| r.texture.is_some() || r.alpha[0] != r.alpha[1];
        let kind_textured = match &self.kind {
            MaterialKind::Diffuse { reflectance } => textured(reflectance),
            MaterialKind::Mirror { tint } => textured(tint),
            MaterialKind::Dielectric { roughness, .. } => rough(roughness),
            MaterialKind::Conductor { eta, k, roughness, tint } => {
                textured(eta) || textured(k) || textured(tint) || rough(roughness)
            }
            MaterialKind::Plastic { reflectance, roughness, .. } => textured(reflectance) || rough(roughness),
            // A mix hashes the point; what its materials read is decided by theirs (see `pack`).
            MaterialKind::Mix { weight, .. } => weight.texture.is_some(),
            MaterialKind::ThinDielectric { .. } | MaterialKind::Null => false,
        };
        kind_textured || textured(&self.emission) || self.opacity.texture.is_some() || self.normal != NormalMod::None
    }

    /// True when some point of the material may let rays through.
    pub fn has_alpha(&self) -> bool {
        self.opacity.value < 1.0 || self.opacity.texture.is_some()
    }
}

/// Where a texture looks itself up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSpace {
    /// At (u, v, 0) of the surface.
    Uv,
    /// At the hit point in world space.
    World,
}

/// How an image texture turns its texture-space point into uv (POV-Ray's `map_type` 0, 1, 2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ImageProjection {
    /// uv = (x, y): the image covers the unit square, row 0 at y = 1.
    #[default]
    Planar,
    /// u = longitude around +y (0 on +x, a quarter turn on +z), v = 1/2 + latitude / pi.
    Spherical,
    /// u = longitude around +y as for `Spherical`, v = y.
    Cylindrical,
}

/// Which channel of an image a texture gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Rgb,
    R,
    G,
    B,
    Alpha,
}

/// What a texture computes at its lookup point, by kind.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureKind {
    Constant(Vec3),
    /// An image looked up, bilinear, at the uv that `projection` makes of the texture-space point
    /// ((x, y) for a planar one).
    Image {
        image: Arc<ImageTexture>,
        wrap: Wrap,
        channel: Channel,
        projection: ImageProjection,
    },
    /// A POV-Ray pattern and the map from its value to a colour.
    Pattern {
        pattern: PatternDesc,
        color_map: ColorMap,
    },
    /// A voxel grid (grey), trilinear, 0 outside its box; for media densities.
    Voxels(Arc<VoxelGrid>),
    /// POV-Ray's ground fog density (grey): 1 up to height `offset`, 1 / (1 + (y - offset) /
    /// `alt`)^2 above, the point first moved by the turbulence of `turbulence` if any.
    GroundFog {
        offset: f32,
        alt: f32,
        turbulence: Option<PatternDesc>,
    },
}

impl TextureKind {
    /// The largest first channel the texture takes anywhere (a medium density's majorant).
    pub fn max_value(&self) -> f32 {
        match self {
            TextureKind::Constant(c) => c.x,
            // An image is looked up in uv space, which a medium does not have.
            TextureKind::Image { .. } => 1.0,
            TextureKind::Pattern { color_map, .. } => color_map.max_first_channel(),
            TextureKind::Voxels(grid) => grid.max,
            TextureKind::GroundFog { .. } => 1.0,
        }
    }
}

/// A texture: its kind, where it is looked up, and where it is placed there (`lookup_from_texture`:
/// a scale of 0.5 makes its features half as large).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureDesc {
    pub kind: TextureKind,
    pub space: TextureSpace,
    pub lookup_from_texture: Affine3A,
}
