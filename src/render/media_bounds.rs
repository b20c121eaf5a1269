//! The boxes heterogeneous media track in. Delta and ratio tracking take a step per tentative
//! collision, so a walk needs a bounded segment: each heterogeneous medium is tracked inside the
//! box of the shapes it fills (and, as the atmosphere, of the scene around the camera), cut to
//! its density's own support (a voxel grid's box). Outside the box its density is 0.

use glam::Vec3;

use super::pack::texture_support;
use crate::layout::BvhNode;
use crate::scene::Scene;

/// One box per medium of `scene` (homogeneous ones get an empty box they never read).
/// `shape_bounds` are the shapes' boxes in scene order, `root` the BVH's root (the finite
/// shapes). The atmosphere's box holds the finite shapes and the camera, grown by half its
/// diagonal on every side, so that haze reaches past the last object toward the horizon.
pub fn tracking_boxes(scene: &Scene, shape_bounds: &[(Vec3, Vec3)], root: &BvhNode, camera: Vec3) -> Vec<(Vec3, Vec3)> {
    let empty = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let union = |a: (Vec3, Vec3), b: (Vec3, Vec3)| (a.0.min(b.0), a.1.max(b.1));
    (0..scene.media.len() as u32)
        .map(|id| {
            let Some(density) = scene.media[id as usize].density else { return empty };
            let mut b = empty;
            for (shape, bounds) in scene.shapes.iter().zip(shape_bounds) {
                if shape.media.is_some_and(|m| m.interior == Some(id)) {
                    b = union(b, *bounds);
                }
            }
            if scene.atmosphere == Some(id) {
                let mut around = (camera, camera);
                if root.aabb_min[0] <= root.aabb_max[0] {
                    around = union(around, (Vec3::from(root.aabb_min), Vec3::from(root.aabb_max)));
                }
                let grow = Vec3::splat(0.5 * (around.1 - around.0).length());
                b = union(b, (around.0 - grow, around.1 + grow));
            }
            if let Some(support) = texture_support(&scene.textures[density.texture as usize]) {
                b = (b.0.max(support.0), b.1.min(support.1));
            }
            b
        })
        .collect()
}
