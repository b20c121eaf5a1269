//! Materials and textures as the scene describes them, independent of any renderer: each kind is
//! a variant with its parameters. `render::pack` turns them into the GPU's structs.

use glam::{Affine3A, Vec3};

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

/// What a material does with light, by kind.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// Lambertian reflection of albedo `reflectance`, on both sides.
    Diffuse { reflectance: ColorParam },
    /// Perfect mirror tinted by `tint`, on both sides.
    Mirror { tint: ColorParam },
    /// Smooth dielectric interface, index `ior` inside (the side opposite the front face).
    Dielectric { ior: f32 },
}

/// A material: its kind, the radiance it emits from its front side and its opacity.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    pub kind: MaterialKind,
    pub emission: ColorParam,
    /// In [0, 1]; below 1 the surface lets that fraction of rays through (stochastic alpha).
    pub opacity: ScalarParam,
}

impl MaterialDesc {
    /// A material of `kind` that emits nothing and is opaque.
    pub fn new(kind: MaterialKind) -> MaterialDesc {
        MaterialDesc { kind, emission: ColorParam::constant(Vec3::ZERO), opacity: ScalarParam::constant(1.0) }
    }

    /// True when some point of the material emits.
    pub fn emits(&self) -> bool {
        self.emission.value.max_element() > 0.0
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

/// What a texture computes at its lookup point, by kind.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureKind {
    Constant(Vec3),
    /// POV-Ray's `checker`: the first colour where floor(x) + floor(y) + floor(z) is even.
    Checker([Vec3; 2]),
}

/// A texture: its kind, where it is looked up, and where it is placed there (`lookup_from_texture`:
/// a scale of 0.5 makes its features half as large).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureDesc {
    pub kind: TextureKind,
    pub space: TextureSpace,
    pub lookup_from_texture: Affine3A,
}
