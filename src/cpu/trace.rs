//! Ray casting against the flattened BVH; twin of `shaders/trace.glsl`.

use glam::Vec3;

use super::bsdf::hash_point;
use super::bsdf::material_opacity;
use super::csg::csg_intersect;
use super::shape::{shape_hit, shape_intersect};
use super::SceneView;
use crate::layout::constants::{NO_LIGHT, PRIMITIVE_CSG, PRIMITIVE_FLAG_ALPHA, PRIMITIVE_KIND_MASK};

/// Distance at which the ray enters the box, or infinity when it misses it within [0, t_max).
pub fn ray_box(o: Vec3, inv_d: Vec3, lo: Vec3, hi: Vec3, t_max: f32) -> f32 {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let tn = t0.min(t1);
    let tf = t0.max(t1);
    let enter = tn.x.max(tn.y).max(tn.z.max(0.0));
    let leave = tf.x.min(tf.y).min(tf.z.min(t_max));
    if enter <= leave {
        enter
    } else {
        f32::INFINITY
    }
}

/// Stochastic transparency: the ray passes through primitive `i` at distance `t` with
/// probability 1 - opacity. Camera rays, shadow rays and photons all decide here.
pub fn passes_through(s: &SceneView, i: u32, o: Vec3, d: Vec3, t: f32) -> bool {
    if s.primitives[i as usize].kind & PRIMITIVE_FLAG_ALPHA == 0 {
        return false;
    }
    let h = shape_hit(s, i, o, d, t);
    hash_point(s, h.p, i) >= material_opacity(s, &s.materials[h.material as usize], &h)
}

/// Tests primitive `i` against the ray and keeps it in (`hit`, `t_hit`) when it is closer; the
/// primitive `ignore` is not tested (see `trace_ray`).
fn visit(s: &SceneView, i: u32, o: Vec3, d: Vec3, ignore: u32, hit: &mut u32, t_hit: &mut f32) {
    let mut t = if i == ignore { f32::INFINITY } else { shape_intersect(s, i, o, d, 0.0, *t_hit) };
    // A ray that passes a transparent point may meet the shape again behind it (a
    // sphere's far side); a shape has at most two surfaces along a ray.
    let mut k = 0;
    while k < 2 && t < *t_hit && passes_through(s, i, o, d, t) {
        t = shape_intersect(s, i, o, d, t, *t_hit);
        k += 1;
    }
    if t < *t_hit {
        *t_hit = t;
        *hit = i;
    }
}

/// Closest hit in [0, t_max) as (primitive index, distance), or `NO_LIGHT` and t_max on a miss.
/// With `any_hit` the first hit found is returned (shadow rays). The unbounded primitives
/// (infinite planes, after the BVH's) come first, then the BVH, stackless: a missed box, or a
/// finished leaf, continues at the node's miss link.
///
/// Primitive `ignore` (`NO_LIGHT`: none) is ignored: the smooth triangle the ray leaves. A ray
/// leaving a smooth triangle may head below the triangle's plane (its shading normal allows
/// directions the flat facet faces away from), and would then meet its own facet at once; Hanika's
/// shifted origin (`Hit::shift`) keeps it off the neighbouring facets. A flat triangle's rays never
/// cross its plane, so flat scenes skip nothing.
pub fn trace_ray(s: &SceneView, o: Vec3, d: Vec3, t_max: f32, any_hit: bool, ignore: u32) -> (u32, f32) {
    let nodes = s.nodes;
    let inv_d = d.recip();
    let mut t_hit = t_max;
    let mut hit = NO_LIGHT;
    for i in s.frame.unbounded_first..s.frame.primitive_count {
        visit(s, i, o, d, ignore, &mut hit, &mut t_hit);
        if any_hit && hit != NO_LIGHT {
            return (hit, t_hit);
        }
    }
    let mut node = 0usize;
    while node < nodes.len() {
        let n = &nodes[node];
        let (count, skip) = (n.count(), n.skip() as usize);
        if ray_box(o, inv_d, Vec3::from(n.aabb_min), Vec3::from(n.aabb_max), t_hit) == f32::INFINITY {
            node = skip;
            continue;
        }
        if count == 0 {
            node += 1;
            continue;
        }
        for i in n.first..n.first + count {
            let before = hit;
            // A CSG object (always in the BVH) reports the leaf primitive it shows
            // (`cpu/csg.rs`), so callers see an ordinary primitive.
            if s.primitives[i as usize].kind & PRIMITIVE_KIND_MASK == PRIMITIVE_CSG {
                let (t, leaf) = csg_intersect(s, i, o, d, t_hit);
                if t < t_hit {
                    t_hit = t;
                    hit = leaf;
                }
            } else {
                visit(s, i, o, d, ignore, &mut hit, &mut t_hit);
            }
            if any_hit && hit != before {
                return (hit, t_hit);
            }
        }
        node = skip;
    }
    (hit, t_hit)
}
