//! The one place where the scene's description becomes the structs the kernels read: primitives
//! and their shape data, materials, textures and their data. A new kind of shape, material or
//! texture adds one arm to the matching function here.

use std::collections::HashMap;

use glam::{Affine3A, Mat3, Vec2, Vec3};

use super::plastic_coat::plastic_coat_table;
use crate::layout::constants::*;
use crate::layout::{Material, Medium, Primitive, Texture, TriangleShading};
use crate::scene::image_texture::ImageTexture;
use crate::scene::{
    AnalyticKind, Channel, ColorParam, Distribution, Geometry, ImageProjection, MaterialDesc, MaterialKind, MediumDesc,
    NormalMod, Phase, Roughness, ScalarParam, Scene, Shape, TextureDesc, TextureKind, TextureSpace,
};

/// The scene's arrays as the kernels read them (primitives not yet in BVH order).
#[derive(Clone, Debug, Default)]
pub struct PackedScene {
    pub primitives: Vec<Primitive>,
    /// Axis-aligned bounds of each primitive, same index.
    pub bounds: Vec<(Vec3, Vec3)>,
    /// Surface area of each primitive, same index.
    pub areas: Vec<f32>,
    /// Total area that holds photons: each shape's area times its constant opacity.
    pub photon_area: f32,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub texture_data: Vec<u32>,
    pub shape_data: Vec<f32>,
    /// True when some texture is an image or a pattern, or some material has alpha: the kernels
    /// then need their `textured` variant.
    pub textured: bool,
    /// True when some shape has an opacity below 1: the kernels then need the alpha test, in
    /// their `textured_alpha` variant.
    pub alpha: bool,
    /// True when some shape is a plane, disc, cone, torus or superellipsoid: the kernels then
    /// need their `analytic` variant.
    pub analytic: bool,
    /// True when some shape is a torus or a superellipsoid: the kernels then need their
    /// `analytic_implicit` variant.
    pub implicit: bool,
    /// True when a CSG object has a torus or a superellipsoid among its leaves: the kernels then
    /// need their `analytic_implicit_csg` variant.
    pub implicit_csg: bool,
    /// The leaf primitives of the CSG objects, which follow all others in the primitive array
    /// (their CSG blocks count them from `FrameParams::csg_first`).
    pub csg_primitives: Vec<Primitive>,
}

pub fn pack_scene(scene: &Scene) -> PackedScene {
    let mut packed = PackedScene::default();
    for texture in &scene.textures {
        let t = pack_texture(texture, &mut packed.texture_data);
        packed.textures.push(t);
    }
    // Plastics that share a coat share its table.
    let mut coat_tables = HashMap::new();
    for m in &scene.materials {
        let mut out = pack_material(m);
        if let MaterialKind::Plastic { ior, roughness, nonlinear: true, .. } = &m.kind {
            // A textured roughness scales the widths per point; the table is the constant's.
            let alpha = 0.5 * (roughness.alpha[0] + roughness.alpha[1]);
            let dist = microfacet_distribution(roughness);
            let data = &mut packed.texture_data;
            out.data = *coat_tables.entry((alpha.to_bits(), dist, ior.to_bits())).or_insert_with(|| {
                plastic_coat_table(alpha, dist, *ior).map_or(NO_DATA, |table| {
                    data.extend(table);
                    (data.len() as u32) - PLASTIC_COAT_WORDS
                })
            });
        }
        packed.materials.push(out);
    }
    for shape in &scene.shapes {
        let (alpha, uses_uv) = material_needs(scene, shape.material, 0);
        let p = match &shape.geometry {
            Geometry::Csg(csg) => super::pack_csg::pack_csg(
                csg,
                |m| material_needs(scene, m, 0).1,
                &mut packed.shape_data,
                &mut packed.csg_primitives,
            ),
            _ => pack_shape(shape, alpha, uses_uv, &mut packed.shape_data),
        };
        packed.primitives.push(p);
        packed.bounds.push(shape.geometry.bounds());
        // The area that holds photons: a constant opacity scales it (a fully transparent shape
        // holds none, so adding one leaves the automatic photon radius alone).
        let opacity = scene.materials[shape.material as usize].opacity;
        let visible = if opacity.texture.is_some() { 1.0 } else { opacity.value };
        let area = shape.geometry.area();
        packed.areas.push(area);
        // An infinite plane's share is added by `prepare`, which knows the scene's extent.
        if area.is_finite() {
            packed.photon_area += area * visible;
        }
    }
    packed.analytic = scene.shapes.iter().any(|s| s.geometry.is_analytic());
    super::open_edges::mark_open_edges(&mut packed.primitives);
    packed.implicit = scene.shapes.iter().any(|s| s.geometry.is_implicit());
    packed.implicit_csg = scene.shapes.iter().any(|s| s.geometry.is_implicit_csg());
    packed.alpha = packed.primitives.iter().any(|p| p.kind & PRIMITIVE_FLAG_ALPHA != 0);
    packed.textured = packed.alpha || packed.textures.iter().any(|t| t.kind != TEXTURE_CONSTANT);
    // Vulkan has no empty buffers: every array gets at least one (unused) element.
    if packed.textures.is_empty() {
        packed.textures.push(Texture::default());
    }
    if packed.texture_data.is_empty() {
        packed.texture_data.push(0);
    }
    if packed.shape_data.is_empty() {
        packed.shape_data.push(0.0);
    }
    packed
}

/// Whether evaluating texture `t` may call Perlin noise (shaders/pattern.glsl, noise_signed):
/// a pattern of a noise kind, any turbulence, or ground fog with turbulence. Read from the
/// packed words, as the kernels read them; the kernels compile noise out of scenes where no
/// texture needs it (`KernelVariant::noise`).
pub fn texture_uses_noise(t: &Texture, data: &[u32]) -> bool {
    let word = |i: u32| data.get(i as usize).copied().unwrap_or(0);
    match t.kind {
        TEXTURE_PATTERN => {
            let kind = word(t.data + PATTERN_KIND);
            let turbulence = (0..3).any(|i| f32::from_bits(word(t.data + PATTERN_TURBULENCE + i)) != 0.0);
            let noise_free = matches!(
                kind,
                PATTERN_BRICK
                    | PATTERN_CHECKER
                    | PATTERN_GRADIENT
                    | PATTERN_HEXAGON
                    | PATTERN_LEOPARD
                    | PATTERN_ONION
                    | PATTERN_RADIAL
                    | PATTERN_RIPPLES
                    | PATTERN_WAVES
            );
            turbulence || !noise_free
        }
        TEXTURE_GROUND_FOG => t.data != NO_DATA,
        _ => false,
    }
}

/// Whether material `id` (or any material a mix of it may pick) has alpha, and whether it reads
/// uv or the surface derivatives.
pub(super) fn material_needs(scene: &Scene, id: u32, depth: u32) -> (bool, bool) {
    let m = &scene.materials[id as usize];
    let own = (m.has_alpha(), m.uses_uv());
    match m.kind {
        MaterialKind::Mix { a, b, .. } if depth < MIX_MAX_DEPTH => {
            let (na, nb) = (material_needs(scene, a, depth + 1), material_needs(scene, b, depth + 1));
            (own.0 || na.0 || nb.0, own.1 || na.1 || nb.1)
        }
        _ => own,
    }
}

fn texture_index(texture: Option<u32>) -> u32 {
    texture.unwrap_or(NO_TEXTURE)
}

fn color(param: &ColorParam) -> ([f32; 3], u32) {
    (param.value.into(), texture_index(param.texture))
}

fn scalar(param: &ScalarParam) -> (f32, u32) {
    (param.value, texture_index(param.texture))
}

/// The only place that turns a medium into the GPU's `Medium`. `bounds` is the box a
/// heterogeneous medium tracks in (the density is 0 outside it; `prepare` finds it).
pub fn pack_medium(m: &MediumDesc, bounds: (Vec3, Vec3)) -> Medium {
    let (density, majorant) = match m.density {
        Some(d) => (d.texture, m.sigma_t().max_element() * d.max),
        None => (NO_TEXTURE, 0.0),
    };
    Medium {
        sigma_a: m.sigma_a.into(),
        phase: match m.phase {
            Phase::Isotropic => PHASE_ISOTROPIC,
            Phase::HenyeyGreenstein { .. } => PHASE_HENYEY_GREENSTEIN,
        },
        sigma_s: m.sigma_s.into(),
        g: m.phase.g(),
        emission: m.emission.into(),
        density,
        bounds_min: bounds.0.into(),
        majorant,
        bounds_max: bounds.1.into(),
        _pad: 0,
    }
}

/// The only place that turns a material into the GPU's `Material`: which slot holds what, per kind.
pub fn pack_material(m: &MaterialDesc) -> Material {
    let (emission, emission_tex) = color(&m.emission);
    let (alpha, alpha_tex) = scalar(&m.opacity);
    let mut out = Material {
        emission,
        emission_tex,
        alpha,
        alpha_tex,
        color0_tex: NO_TEXTURE,
        color1_tex: NO_TEXTURE,
        color2: [1.0; 3],
        color2_tex: NO_TEXTURE,
        roughness_tex: NO_TEXTURE,
        bump_tex: NO_TEXTURE,
        normal_tex: NO_TEXTURE,
        weight_tex: NO_TEXTURE,
        data: NO_DATA,
        ior: 1.0,
        ..Default::default()
    };
    match m.normal {
        NormalMod::None => {}
        NormalMod::Bump { texture, strength } => (out.bump_tex, out.bump_strength) = (texture, strength),
        NormalMod::NormalMap { texture } => out.normal_tex = texture,
    }
    match &m.kind {
        MaterialKind::Diffuse { reflectance } => {
            out.kind = MATERIAL_DIFFUSE;
            (out.color0, out.color0_tex) = color(reflectance);
        }
        MaterialKind::Mirror { tint } => {
            out.kind = MATERIAL_MIRROR;
            (out.color0, out.color0_tex) = color(tint);
        }
        MaterialKind::Dielectric { ior, roughness } => {
            out.kind = MATERIAL_DIELECTRIC;
            out.color0 = [1.0; 3];
            out.ior = *ior;
            (out.roughness, out.roughness_tex) = (roughness.alpha, texture_index(roughness.texture));
            out.flags = distribution_flag(roughness);
        }
        MaterialKind::Conductor { eta, k, roughness, tint } => {
            out.kind = MATERIAL_CONDUCTOR;
            (out.color0, out.color0_tex) = color(eta);
            (out.color1, out.color1_tex) = color(k);
            (out.color2, out.color2_tex) = color(tint);
            (out.roughness, out.roughness_tex) = (roughness.alpha, texture_index(roughness.texture));
            out.flags = distribution_flag(roughness);
        }
        MaterialKind::Plastic { reflectance, ior, roughness, nonlinear } => {
            out.kind = MATERIAL_PLASTIC;
            // `data`, a rough nonlinear coat's table, is added by `pack_scene`.
            out.flags = if *nonlinear { MATERIAL_FLAG_NONLINEAR } else { 0 } | distribution_flag(roughness);
            (out.color0, out.color0_tex) = color(reflectance);
            out.ior = *ior;
            (out.roughness, out.roughness_tex) = (roughness.alpha, texture_index(roughness.texture));
        }
        MaterialKind::ThinDielectric { ior } => {
            out.kind = MATERIAL_THIN_DIELECTRIC;
            out.ior = *ior;
        }
        MaterialKind::Mix { a, b, weight } => {
            out.kind = MATERIAL_MIX;
            (out.mix_a, out.mix_b) = (*a, *b);
            (out.weight, out.weight_tex) = scalar(weight);
        }
        MaterialKind::Null => out.kind = MATERIAL_NULL,
    }
    if m.two_sided {
        out.flags |= MATERIAL_FLAG_TWO_SIDED;
    }
    out
}

/// `MATERIAL_FLAG_BECKMANN` for Beckmann microfacets, else 0 (GGX).
fn distribution_flag(r: &Roughness) -> u32 {
    match r.distribution {
        Distribution::Ggx => 0,
        Distribution::Beckmann => MATERIAL_FLAG_BECKMANN,
    }
}

/// The `MICROFACET_*` argument of the microfacet functions for `r`.
fn microfacet_distribution(r: &Roughness) -> u32 {
    match r.distribution {
        Distribution::Ggx => MICROFACET_GGX,
        Distribution::Beckmann => MICROFACET_BECKMANN,
    }
}

/// The rows of the 3x4 affine map `a`.
pub(super) fn affine_rows(a: &Affine3A) -> [f32; 12] {
    let m = Mat3::from(a.matrix3);
    let t = Vec3::from(a.translation);
    let mut rows = [0.0; 12];
    for r in 0..3 {
        let row = m.row(r);
        rows[4 * r..4 * r + 4].copy_from_slice(&[row.x, row.y, row.z, t[r]]);
    }
    rows
}

/// The only place that turns a texture into the GPU's `Texture` (and its data block, if any).
pub fn pack_texture(t: &TextureDesc, data: &mut Vec<u32>) -> Texture {
    let mut out = Texture {
        space: match t.space {
            TextureSpace::Uv => TEXTURE_SPACE_UV,
            TextureSpace::World => TEXTURE_SPACE_WORLD,
        },
        data: NO_DATA,
        color_map: NO_DATA,
        // The kernels move the lookup point into texture space.
        transform: affine_rows(&t.lookup_from_texture.inverse()),
        ..Default::default()
    };
    match &t.kind {
        TextureKind::Constant(c) => {
            out.kind = TEXTURE_CONSTANT;
            out.value = (*c).into();
        }
        TextureKind::Image { image, wrap, channel, projection } => {
            out.kind = TEXTURE_IMAGE;
            let projection = match projection {
                ImageProjection::Planar => TEXTURE_PROJECTION_PLANAR,
                ImageProjection::Spherical => TEXTURE_PROJECTION_SPHERICAL,
                ImageProjection::Cylindrical => TEXTURE_PROJECTION_CYLINDRICAL,
            };
            out.space |= projection << TEXTURE_PROJECTION_SHIFT;
            out.data = image.pack(*wrap, data);
            out.channel = match channel {
                Channel::Rgb => TEXTURE_CHANNEL_RGB,
                Channel::R => TEXTURE_CHANNEL_R,
                Channel::G => TEXTURE_CHANNEL_G,
                Channel::B => TEXTURE_CHANNEL_B,
                Channel::Alpha => TEXTURE_CHANNEL_A,
            };
        }
        TextureKind::Pattern { pattern, color_map } => {
            out.kind = TEXTURE_PATTERN;
            out.data = pattern.pack(data);
            out.color_map = color_map.pack(data);
        }
        TextureKind::Voxels(grid) => {
            out.kind = TEXTURE_VOXELS;
            out.data = data.len() as u32;
            data.extend(grid.dims);
            data.extend(grid.values.iter().map(|v| v.to_bits()));
            // The kernels look the grid up in its unit cube: the box the file gives, in
            // texture space, maps onto it.
            let unit_from_texture = Affine3A::from_scale(1.0 / (grid.bounds_max - grid.bounds_min))
                * Affine3A::from_translation(-grid.bounds_min);
            out.transform = affine_rows(&(unit_from_texture * t.lookup_from_texture.inverse()));
        }
        TextureKind::GroundFog { offset, alt, turbulence } => {
            out.kind = TEXTURE_GROUND_FOG;
            out.value = [*offset, *alt, 0.0];
            if let Some(pattern) = turbulence {
                out.data = pattern.pack(data);
            }
        }
    }
    out
}

/// The box a texture is non-zero in, in lookup space, when it has one (a voxel grid's, moved
/// by its placement); a medium tracks only there.
pub fn texture_support(t: &TextureDesc) -> Option<(Vec3, Vec3)> {
    let TextureKind::Voxels(grid) = &t.kind else { return None };
    let (lo, hi) = (grid.bounds_min, grid.bounds_max);
    let mut out = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for i in 0..8 {
        let corner = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let p = t.lookup_from_texture.transform_point3(corner);
        out = (out.0.min(p), out.1.max(p));
    }
    Some(out)
}

/// The only place that turns a shape into the GPU's `Primitive` (and its shape data, if any);
/// `pack_scene` packs CSG objects with `pack_csg`, which calls this for each leaf shape.
pub fn pack_shape(shape: &Shape, alpha: bool, uses_uv: bool, shape_data: &mut Vec<f32>) -> Primitive {
    let flags = if alpha { PRIMITIVE_FLAG_ALPHA } else { 0 } | if uses_uv { PRIMITIVE_FLAG_UV } else { 0 };
    let mut p = Primitive { material: shape.material, light: NO_LIGHT, data: NO_DATA, ..Default::default() };
    let medium_flag = if let Some(m) = shape.media {
        (p.interior, p.exterior) = (m.interior.unwrap_or(NO_MEDIUM), m.exterior.unwrap_or(NO_MEDIUM));
        PRIMITIVE_FLAG_MEDIUM
    } else {
        0
    };
    let flags = flags | medium_flag;
    match &shape.geometry {
        Geometry::Triangle(t) => {
            p.kind = PRIMITIVE_TRIANGLE | flags;
            (p.p0, p.p1, p.p2) = (t.vertices[0].into(), t.vertices[1].into(), t.vertices[2].into());
            if let Some(normals) = t.normals {
                // A smooth triangle's block is a `TriangleShading`: uvs (the default ones when the
                // triangle has none), then the vertex normals.
                p.kind |= PRIMITIVE_FLAG_SMOOTH;
                p.data = shape_data.len() as u32;
                let uv = t.uv.unwrap_or([Vec2::ZERO, Vec2::X, Vec2::Y]);
                let block = TriangleShading {
                    uv: [uv[0].x, uv[0].y, uv[1].x, uv[1].y, uv[2].x, uv[2].y],
                    normals: [normals[0], normals[1], normals[2]]
                        .map(|n| n.to_array())
                        .concat()
                        .try_into()
                        .expect("9 floats"),
                };
                shape_data.extend(bytemuck::cast_slice::<TriangleShading, f32>(&[block]));
                debug_assert_eq!(shape_data.len() as u32 - p.data, TRIANGLE_DATA_FLOATS);
            } else if let Some(uv) = t.uv {
                p.data = shape_data.len() as u32;
                shape_data.extend(uv.iter().flat_map(|v| [v.x, v.y]));
            }
        }
        Geometry::Analytic(a) => {
            let (kind, p0, p1) = match a.kind {
                AnalyticKind::Plane => (PRIMITIVE_PLANE, [0.0; 3], [0.0; 3]),
                AnalyticKind::Disc { radius, inner_radius } => (PRIMITIVE_DISC, [radius, inner_radius, 0.0], [0.0; 3]),
                AnalyticKind::Cone { r0, r1, height } => (PRIMITIVE_CONE, [r0, r1, height], [0.0; 3]),
                AnalyticKind::Torus { major, minor } => (PRIMITIVE_TORUS, [major, minor, 0.0], [0.0; 3]),
                AnalyticKind::Superellipsoid { e, n } => {
                    (PRIMITIVE_SUPERELLIPSOID, [2.0 / e, e / 2.0, 2.0 / n], [n / 2.0, 0.0, 0.0])
                }
            };
            p.kind = kind | flags;
            (p.p0, p.p1) = (p0, p1);
            p.data = shape_data.len() as u32;
            let world_from_object = a.world_from_object;
            shape_data.extend(affine_rows(&world_from_object.inverse()));
            shape_data.extend(affine_rows(&world_from_object));
            shape_data.push(world_from_object.matrix3.determinant().abs());
            shape_data.push(a.size());
            debug_assert_eq!(shape_data.len() as u32 - p.data, SHAPE_DATA_FLOATS);
        }
        // Packed by `pack_csg` (it needs the leaves' own array); here a triangle no ray meets.
        Geometry::Csg(_) => {}
        Geometry::Sphere(s) => {
            p.kind = PRIMITIVE_SPHERE | flags;
            p.p0 = s.center.into();
            p.p1 = [s.radius, 0.0, 0.0];
            if let Some(r) = s.object_from_world {
                p.data = shape_data.len() as u32;
                for row in 0..3 {
                    shape_data.extend(r.row(row).to_array());
                }
            }
        }
    }
    p
}

/// Appends the block of an environment (layout at `ENV_TEXELS`) to the texture data and returns
/// its word offset and the integral of its luminance (mean of the channels) over the sphere of
/// directions, W/(m^2 sr) times sr: the irradiance it would give a disc from every side.
pub fn pack_environment(image: &ImageTexture, rotation_deg: f32, data: &mut Vec<u32>) -> (u32, f64) {
    let (w, h) = (image.width, image.height);
    let base = data.len() as u32;
    let rotation = rotation_deg.to_radians();
    data.extend([w, h, rotation.cos().to_bits(), rotation.sin().to_bits()]);
    for t in &image.texels {
        data.extend([t[0].to_bits(), t[1].to_bits(), t[2].to_bits()]);
    }
    // Luminance times sin(theta) at each row's centre: the distribution directions are drawn
    // from; texel (i, j) covers solid angle (2 pi / W)(pi / H) sin(theta_j) to first order.
    let mut rows = Vec::with_capacity(h as usize);
    let mut integral = 0.0f64;
    for j in 0..h {
        let sin_theta = (std::f64::consts::PI * (j as f64 + 0.5) / h as f64).sin();
        let row: Vec<f64> = (0..w)
            .map(|i| {
                let t = image.texels[(j * w + i) as usize];
                (t[0] as f64 + t[1] as f64 + t[2] as f64) / 3.0 * sin_theta
            })
            .collect();
        integral += row.iter().sum::<f64>();
        rows.push(row);
    }
    integral *= 2.0 * std::f64::consts::PI * std::f64::consts::PI / (w as f64 * h as f64);
    let cdf = |values: &[f64]| -> Vec<u32> {
        let total: f64 = values.iter().sum();
        let mut running = 0.0;
        let mut out = vec![0.0f32.to_bits()];
        for (k, v) in values.iter().enumerate() {
            running += v;
            // A row (or a whole map) without light is drawn uniformly, never picked by the
            // marginal; the last value is exactly 1 so no u in [0, 1) falls past it.
            let c = if total > 0.0 { running / total } else { (k + 1) as f64 / values.len() as f64 };
            out.push(if k + 1 == values.len() { 1.0f32.to_bits() } else { (c as f32).to_bits() });
        }
        out
    };
    let row_sums: Vec<f64> = rows.iter().map(|r| r.iter().sum()).collect();
    data.extend(cdf(&row_sums));
    for row in &rows {
        data.extend(cdf(row));
    }
    (base, integral)
}
