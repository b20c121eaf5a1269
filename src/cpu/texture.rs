//! Textures behind one evaluate function, and material parameters that may be textured; twin of
//! `shaders/texture.glsl`.

use glam::{Vec3, Vec4};

use super::shape::Hit;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Texture;

pub fn texture_lookup_point(t: &Texture, h: &Hit) -> Vec3 {
    let p = if t.space == TEXTURE_SPACE_UV { h.uv.extend(0.0) } else { h.p };
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
        TEXTURE_CHECKER => {
            let c = p.floor().as_ivec3();
            if (c.x.wrapping_add(c.y).wrapping_add(c.z) & 1) == 0 {
                Vec3::from(t.value)
            } else {
                Vec3::from(t.value2)
            }
        }
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
