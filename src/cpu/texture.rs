//! Textures behind one evaluate function, and material parameters that may be textured; twin of
//! `shaders/texture.glsl`.

use glam::{Vec3, Vec4};

use super::image_texture::{image_lookup, image_projection};
use super::pattern::{color_map_eval, pattern_value};
use super::shape::Hit;
use super::voxel::{ground_fog_density, voxel_lookup};
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Texture;

pub fn texture_lookup_point(t: &Texture, h: &Hit) -> Vec3 {
    let p = if t.space & 0xff == TEXTURE_SPACE_UV { h.uv.extend(0.0) } else { h.p };
    let p = p.extend(1.0);
    let row = |r: usize| Vec4::from_slice(&t.transform[4 * r..4 * r + 4]);
    Vec3::new(p.dot(row(0)), p.dot(row(1)), p.dot(row(2)))
}

/// The colour of texture `index` at hit `h` (scalar textures are grey).
pub fn texture_eval(s: &SceneView, index: u32, h: &Hit) -> Vec3 {
    let t = &s.textures[index as usize];
    let p = texture_lookup_point(t, h);
    match t.kind {
        TEXTURE_CONSTANT => Vec3::from(t.value),
        TEXTURE_IMAGE => {
            let uv = image_projection(p, t.space >> TEXTURE_PROJECTION_SHIFT);
            let c = image_lookup(s.texture_data, t.data, uv);
            if t.channel == TEXTURE_CHANNEL_RGB {
                c.truncate()
            } else {
                Vec3::splat(c[t.channel as usize - 1])
            }
        }
        TEXTURE_PATTERN => color_map_eval(s.texture_data, t.color_map, pattern_value(s.texture_data, t.data, p)),
        TEXTURE_VOXELS => Vec3::splat(voxel_lookup(s.texture_data, t.data, p)),
        TEXTURE_GROUND_FOG => Vec3::splat(ground_fog_density(s.texture_data, p, t.value[0], t.value[1], t.data)),
        _ => Vec3::ZERO, // unreachable: the host packs only known kinds
    }
}

/// A colour parameter: the constant, times the texture when it has one.
pub fn param_color(s: &SceneView, value: [f32; 3], tex: u32, h: &Hit) -> Vec3 {
    let v = Vec3::from(value);
    if tex == NO_TEXTURE {
        v
    } else {
        v * texture_eval(s, tex, h)
    }
}

/// A scalar parameter: the constant, times the texture's first channel when it has one.
pub fn param_scalar(s: &SceneView, value: f32, tex: u32, h: &Hit) -> f32 {
    if tex == NO_TEXTURE {
        value
    } else {
        value * texture_eval(s, tex, h).x
    }
}

/// Hit `h` moved by (du, dv) in uv along the surface's tangent plane.
pub fn hit_moved(h: &Hit, du: f32, dv: f32) -> Hit {
    let mut m = *h;
    m.uv += glam::Vec2::new(du, dv);
    m.p += du * h.dpdu + dv * h.dpdv;
    m
}

/// The shading normal of a bump map at `h`: its four heights looked up, then
/// `bump_normal_from_heights`. (The kernel makes the same lookups in `material_bsdf`'s one loop.)
pub fn bump_normal(s: &SceneView, tex: u32, strength: f32, h: &Hit) -> Vec3 {
    let d = BUMP_DELTA;
    let height = |du: f32, dv: f32| texture_eval(s, tex, &hit_moved(h, du, dv)).x;
    bump_normal_from_heights(height(d, 0.0), height(-d, 0.0), height(0.0, d), height(0.0, -d), strength, h)
}

/// The shading normal of a bump map: the surface displaced along `ns` (`ng`, or a smooth
/// triangle's interpolated normal, around which its dpdu and dpdv already lie) by `strength` times a
/// height (scene units), its slopes from central differences along u and v (pbrt-v4's `BumpMap`)
/// of the heights at u +- `BUMP_DELTA` and v +- `BUMP_DELTA`. Works alike for uv-space images and
/// 3D patterns, since moving in uv moves the point along dpdu and dpdv.
pub fn bump_normal_from_heights(u_plus: f32, u_minus: f32, v_plus: f32, v_minus: f32, strength: f32, h: &Hit) -> Vec3 {
    let d = BUMP_DELTA;
    let dhdu = strength * (u_plus - u_minus) / (2.0 * d);
    let dhdv = strength * (v_plus - v_minus) / (2.0 * d);
    let n = (h.dpdu + dhdu * h.ns).cross(h.dpdv + dhdv * h.ns);
    let len = n.length();
    if len.is_nan() || len <= 0.0 {
        return h.ns;
    }
    let n = n / len;
    if n.dot(h.ns) < 0.0 {
        -n
    } else {
        n
    }
}

/// The shading normal of a tangent-space normal map at `h`.
pub fn normal_map_normal(s: &SceneView, tex: u32, h: &Hit) -> Vec3 {
    normal_map_normal_from_texel(texture_eval(s, tex, h), h)
}

/// The shading normal of a tangent-space normal map from its texel (OpenGL convention: red along
/// +u, green along +v, blue along the normal; texels in [0, 1] map to [-1, 1]).
pub fn normal_map_normal_from_texel(texel: Vec3, h: &Hit) -> Vec3 {
    let c = 2.0 * texel - 1.0;
    let t = h.dpdu - h.ns * h.ns.dot(h.dpdu);
    if t.length().is_nan() || t.length() <= 0.0 {
        return h.ns;
    }
    let t = t.normalize();
    let mut b = h.ns.cross(t);
    if b.dot(h.dpdv) < 0.0 {
        b = -b;
    }
    let n = t * c.x + b * c.y + h.ns * c.z;
    let len = n.length();
    if len.is_nan() || len <= 0.0 {
        return h.ns;
    }
    let n = n / len;
    // A normal map never turns the shading normal below the surface.
    if n.dot(h.ng) <= 0.0 {
        h.ns
    } else {
        n
    }
}
