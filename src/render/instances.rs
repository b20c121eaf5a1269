//! Objects and their instances as the kernels read them: each placed object's primitives once,
//! with a BVH of their own (object space), each instance a record in the shape data (its
//! transform both ways and its object's BVH), and a top level over the instances' world bounds,
//! one instance per leaf. Memory grows with the unique geometry and by a record and about two
//! nodes per instance. The traversal is `cpu::trace::trace_ray` and its GLSL twin.

use glam::{Affine3A, Vec3};

use super::pack::{affine_rows, material_needs, pack_shape};
use super::pack_csg::pack_csg;
use crate::accel::{build_bvh, build_bvh_with_leaves, BvhError};
use crate::layout::constants::*;
use crate::layout::{BvhNode, Primitive};
use crate::scene::analytic::transformed_box;
use crate::scene::{Geometry, Scene};

/// The instanced part of the scene, to append after the world's BVH and primitives.
#[derive(Clone, Debug, Default)]
pub struct PackedInstances {
    /// The top level (its root first), then each placed object's BVH; node indices already
    /// count from the world's node count, leaves of objects index `primitives` from the world's
    /// primitive count.
    pub nodes: Vec<BvhNode>,
    /// The placed objects' primitives, each object's contiguous and in its BVH's order.
    pub primitives: Vec<Primitive>,
    /// How many instances there are (0: no nodes, no primitives, no records).
    pub instance_count: u32,
    /// Offset of the first instance's record in the shape data.
    pub instance_data: u32,
    /// World bounds (min, max) of all instances; empty (min > max) without instances.
    pub bounds: (Vec3, Vec3),
    /// Area that holds photons, summed over the instances (see `pack_instances`).
    pub photon_area: f32,
    /// As `PackedScene`'s flags, for the objects' shapes.
    pub analytic: bool,
    pub implicit: bool,
    pub implicit_csg: bool,
    pub alpha: bool,
}

/// Packs the objects that instances place (their shape data and records go to `shape_data`, the
/// leaf primitives of their CSG objects to `csg_primitives`, after the world's). `node_base` and
/// `primitive_base` are the world BVH's node and primitive counts: these nodes and primitives
/// follow them.
pub fn pack_instances(
    scene: &Scene,
    shape_data: &mut Vec<f32>,
    csg_primitives: &mut Vec<Primitive>,
    node_base: u32,
    primitive_base: u32,
) -> Result<PackedInstances, BvhError> {
    let empty = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let mut out = PackedInstances { bounds: empty, ..Default::default() };
    if scene.instances.is_empty() {
        return Ok(out);
    }
    // The materials each object is shown with: a shape that some instance overrides needs
    // whatever the override needs (alpha, uv) as well as its own material's needs.
    let mut overrides: Vec<Vec<u32>> = vec![Vec::new(); scene.objects.len()];
    for inst in &scene.instances {
        if let Some(m) = inst.material {
            let list = &mut overrides[inst.object as usize];
            if !list.contains(&m) {
                list.push(m);
            }
        }
    }
    let placed: Vec<bool> =
        (0..scene.objects.len()).map(|o| scene.instances.iter().any(|i| i.object as usize == o)).collect();

    // Each placed object's BVH, nodes numbered from 0 for now.
    let mut object_nodes: Vec<BvhNode> = Vec::new();
    let mut objects: Vec<Option<PlacedObject>> = vec![None; scene.objects.len()];
    for (o, object) in scene.objects.iter().enumerate() {
        if !placed[o] || object.shapes.is_empty() {
            continue;
        }
        let mut primitives = Vec::with_capacity(object.shapes.len());
        let mut bounds = Vec::with_capacity(object.shapes.len());
        let mut area = 0.0f32;
        for shape in &object.shapes {
            let (mut alpha, mut uses_uv) = material_needs(scene, shape.material, 0);
            for &m in &overrides[o] {
                let (a, u) = material_needs(scene, m, 0);
                (alpha, uses_uv) = (alpha || a, uses_uv || u);
            }
            let p = match &shape.geometry {
                // Scene loading refuses instance materials with alpha over objects holding CSG.
                Geometry::Csg(csg) => pack_csg(
                    csg,
                    |m| material_needs(scene, m, 0).1 || overrides[o].iter().any(|&v| material_needs(scene, v, 0).1),
                    shape_data,
                    csg_primitives,
                ),
                _ => pack_shape(shape, alpha, uses_uv, shape_data),
            };
            primitives.push(p);
            bounds.push(shape.geometry.bounds());
            let opacity = scene.materials[shape.material as usize].opacity;
            let visible = if opacity.texture.is_some() { 1.0 } else { opacity.value };
            area += shape.geometry.area() * visible;
            out.analytic |= shape.geometry.is_analytic();
            out.implicit |= shape.geometry.is_implicit();
            out.implicit_csg |= shape.geometry.is_implicit_csg();
        }
        let bvh = build_bvh(&primitives, &bounds)?;
        let first_node = object_nodes.len() as u32;
        let first_primitive = primitive_base + out.primitives.len() as u32;
        let root = &bvh.nodes[0];
        let object_bounds = (Vec3::from(root.aabb_min), Vec3::from(root.aabb_max));
        for n in &bvh.nodes {
            object_nodes.push(BvhNode {
                first: n.first + first_primitive,
                skip_count: ((n.skip() + first_node) << BVH_COUNT_BITS) | n.count(),
                ..*n
            });
        }
        out.primitives.extend(bvh.primitives);
        objects[o] = Some((first_node, first_node + bvh.nodes.len() as u32, object_bounds, area));
    }
    out.alpha = out.primitives.iter().any(|p| p.kind & PRIMITIVE_FLAG_ALPHA != 0);

    // The top level: one leaf per instance, over its object's box moved to the world.
    let instances: Vec<_> = scene.instances.iter().filter(|i| objects[i.object as usize].is_some()).collect();
    let world_bounds: Vec<(Vec3, Vec3)> = instances
        .iter()
        .map(|i| {
            let (_, _, (lo, hi), _) = objects[i.object as usize].expect("placed");
            transformed_box(&i.world_from_object, lo, hi)
        })
        .collect();
    let top = build_bvh_with_leaves(&vec![Primitive::default(); instances.len()], &world_bounds, 1)?;
    let objects_base = node_base + top.nodes.len() as u32;
    // The top level's leaves name instances by their place in `top.order`, as the records follow.
    out.nodes = top
        .nodes
        .iter()
        .map(|n| BvhNode { skip_count: ((n.skip() + node_base) << BVH_COUNT_BITS) | n.count(), ..*n })
        .collect();
    out.nodes.extend(
        object_nodes
            .iter()
            .map(|n| BvhNode { skip_count: ((n.skip() + objects_base) << BVH_COUNT_BITS) | n.count(), ..*n }),
    );
    out.instance_count = instances.len() as u32;
    out.instance_data = shape_data.len() as u32;
    for &k in &top.order {
        let inst = instances[k as usize];
        let (root, end, _, area) = objects[inst.object as usize].expect("placed");
        let m = inst.world_from_object;
        shape_data.extend(affine_rows(&m.inverse()));
        shape_data.extend(affine_rows(&m));
        shape_data.push(f32::from_bits(root + objects_base));
        shape_data.push(f32::from_bits(end + objects_base));
        shape_data.push(f32::from_bits(inst.material.unwrap_or(NO_DATA)));
        shape_data.push(largest_stretch(&m));
        // An affine map scales areas by |det|^(2/3) on average over orientations: close enough
        // for the automatic photon radius this feeds.
        out.photon_area += area * m.matrix3.determinant().abs().powf(2.0 / 3.0);
        let (lo, hi) = world_bounds[k as usize];
        out.bounds = (out.bounds.0.min(lo), out.bounds.1.max(hi));
    }
    debug_assert_eq!(shape_data.len() as u32 - out.instance_data, out.instance_count * INSTANCE_DATA_FLOATS);
    Ok(out)
}

/// A packed object: (root node, end node, object-space bounds, area that holds photons).
type PlacedObject = (u32, u32, (Vec3, Vec3), f32);

/// The factor `m`'s linear part stretches a length by: its largest column norm, exact for
/// rotations and axis scales (the usual placements), an estimate for shears.
fn largest_stretch(m: &Affine3A) -> f32 {
    let l = m.matrix3;
    l.x_axis.length().max(l.y_axis.length()).max(l.z_axis.length())
}
