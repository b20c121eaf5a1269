//! Instances of objects as the kernels see them: hit names, instance records and the move of a
//! hit record from object space to the world. The GLSL twin is the `Instances` part of
//! `shaders/shape.glsl`; the two-level walk itself is in `trace`.
//!
//! A hit on primitive p of instance k is named (k + 1) x `primitive_count` + p, so one u32
//! still names every hit (the host refuses scenes where that would overflow), and names below
//! `primitive_count` are the world's own primitives, as before instancing.

use glam::Vec3;

use super::shape::{affine_point, affine_transpose_vector, affine_vector, Hit};
use super::SceneView;
use crate::layout::constants::*;

/// (instance, primitive) of hit name `id`, or `None` for a primitive of the world.
pub fn split_hit(s: &SceneView, id: u32) -> Option<(u32, u32)> {
    let n = s.frame.primitive_count;
    if s.frame.instance_count == 0 || id < n {
        return None;
    }
    let k = id / n;
    Some((k - 1, id - k * n))
}

/// The primitive a hit name refers to (the object's primitive for an instance's hit).
pub fn hit_primitive(s: &SceneView, id: u32) -> u32 {
    split_hit(s, id).map_or(id, |(_, p)| p)
}

/// The record of instance `k` (`INSTANCE_DATA_*`).
pub fn record<'a>(s: &SceneView<'a>, k: u32) -> &'a [f32] {
    let a = (s.frame.instance_data + k * INSTANCE_DATA_FLOATS) as usize;
    &s.shape_data[a..a + INSTANCE_DATA_FLOATS as usize]
}

pub fn object_from_world(rec: &[f32]) -> &[f32] {
    &rec[INSTANCE_DATA_OBJECT_FROM_WORLD as usize..]
}

/// The object's BVH: its root node and the node where its nodes end.
pub fn object_nodes(rec: &[f32]) -> (u32, u32) {
    (rec[INSTANCE_DATA_ROOT as usize].to_bits(), rec[INSTANCE_DATA_END as usize].to_bits())
}

/// The ray o + t d in instance `rec`'s object space as (origin, unit direction, object length
/// per world length): distances along it are `len` times the world's.
pub fn object_ray(rec: &[f32], o: Vec3, d: Vec3) -> (Vec3, Vec3, f32) {
    let od = affine_vector(object_from_world(rec), d);
    let len = od.length();
    (affine_point(object_from_world(rec), o), od / len, len)
}

/// `h`, filled in object space at the object point of world point `x`, moved to the world:
/// the point (x, or an analytic shape's projected point moved back), normals by the inverse
/// transpose, derivatives and the smooth triangles' shift by the linear part, the analytic
/// shapes' offsets by its largest stretch; the instance's material replaces the object's when it
/// has one.
pub fn to_world(rec: &[f32], x: Vec3, kind: u32, h: &mut Hit) {
    let ofw = object_from_world(rec);
    let wfo = &rec[INSTANCE_DATA_WORLD_FROM_OBJECT as usize..];
    // The analytic shapes' point projected onto the surface (`analytic_surface`), moved back:
    // x carries the ray's rounding, which grows with its length (on a torus, less exact than
    // the offset allows for, that was shadow acne).
    h.p = if kind > PRIMITIVE_SPHERE { affine_point(wfo, h.p) } else { x };
    h.ng = affine_transpose_vector(ofw, h.ng).normalize();
    h.ns = affine_transpose_vector(ofw, h.ns).normalize();
    h.dpdu = affine_vector(wfo, h.dpdu);
    h.dpdv = affine_vector(wfo, h.dpdv);
    h.shift = affine_vector(wfo, h.shift);
    if kind > PRIMITIVE_SPHERE {
        // The offset scales with the point's coordinates and the shape's size (SHAPE_EPSILON_SCALE).
        h.eps = (h.eps * rec[INSTANCE_DATA_SCALE as usize]).max(SHAPE_EPSILON_SCALE * x.abs().max_element());
    }
    let material = rec[INSTANCE_DATA_MATERIAL as usize].to_bits();
    if material != NO_DATA {
        h.material = material;
    }
}
