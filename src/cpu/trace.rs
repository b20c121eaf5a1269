//! Ray casting against the flattened BVH; twin of `shaders/trace.glsl`.

use glam::{Vec3, Vec3A};

use super::bsdf::hash_point;
use super::bsdf::material_opacity;
use super::csg::csg_intersect;
use super::instance::{hit_primitive, object_nodes, object_ray, record};
use super::shape::{shape_hit, shape_intersect};
use super::SceneView;
use crate::layout::constants::{NO_LIGHT, PRIMITIVE_CSG, PRIMITIVE_FLAG_ALPHA, PRIMITIVE_KIND_MASK, TRACE_STEPS};

/// Distance at which the ray enters the box, or infinity when it misses it within [0, t_max).
///
/// In SIMD lanes (`Vec3A`: SSE `minps`/`maxps`), as lavapipe runs the kernel's: for finite
/// values every min and max is exact, so the result is the scalar form's bit for bit. They differ
/// only where a slab's distance is NaN (a ray parallel to a box face and lying in its plane, 0 x
/// inf), where GLSL leaves min and max undefined too; such a ray meets that face's triangles
/// edge-on, which `ray_triangle` misses either way.
#[inline]
pub fn ray_box(o: Vec3A, inv_d: Vec3A, lo: Vec3A, hi: Vec3A, t_max: f32) -> f32 {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let enter = t0.min(t1).max_element();
    let leave = t0.max(t1).min_element();
    // Scalar selects rather than f32::max/min, which add NaN fix-ups to every box test.
    let enter = if enter > 0.0 { enter } else { 0.0 };
    let leave = if leave < t_max { leave } else { t_max };
    if enter <= leave {
        enter
    } else {
        f32::INFINITY
    }
}

/// Stochastic transparency: the ray passes through the primitive of hit name `id` at distance
/// `t` with probability 1 - opacity. Camera rays, shadow rays and photons all decide here.
pub fn passes_through(s: &SceneView, id: u32, o: Vec3, d: Vec3, t: f32) -> bool {
    if s.primitives[hit_primitive(s, id) as usize].kind & PRIMITIVE_FLAG_ALPHA == 0 {
        return false;
    }
    let h = shape_hit(s, id, o, d, t);
    hash_point(s, h.p, id) >= material_opacity(s, &s.materials[h.material as usize], &h)
}

/// The ray a BVH walk tests its boxes and primitives with: the world's, or an instance's
/// object-space form with a unit direction whose distances are `len` times the world's.
struct WalkRay {
    o: Vec3,
    d: Vec3,
    /// `o` and 1 / `d` in SIMD lanes, for `ray_box`.
    o_a: Vec3A,
    inv_d: Vec3A,
    len: f32,
}

impl WalkRay {
    fn new(o: Vec3, d: Vec3, len: f32) -> WalkRay {
        WalkRay { o, d, o_a: o.into(), inv_d: Vec3A::from(d).recip(), len }
    }
}

/// Tests primitive `i` (hit name `id`) against the ray and keeps it in (`hit`, `t_hit`, world
/// distances) when it is closer; the hit name `ignore` is not tested (see `trace_ray`). (`o`,
/// `d`) is the world ray.
#[allow(clippy::too_many_arguments)]
fn visit(s: &SceneView, i: u32, id: u32, r: &WalkRay, o: Vec3, d: Vec3, ignore: u32, hit: &mut u32, t_hit: &mut f32) {
    let t_max = *t_hit * r.len;
    let mut t = if id == ignore { f32::INFINITY } else { shape_intersect(s, i, r.o, r.d, 0.0, t_max) };
    // A ray that passes a transparent point may meet the shape again behind it (a
    // sphere's far side); a shape has at most two surfaces along a ray.
    let mut k = 0;
    while k < 2 && t < t_max && passes_through(s, id, o, d, t / r.len) {
        t = shape_intersect(s, i, r.o, r.d, t, t_max);
        k += 1;
    }
    let t = t / r.len;
    if t < *t_hit {
        *t_hit = t;
        *hit = id;
    }
}

/// Closest hit in [0, t_max) as (hit name, distance), or `NO_LIGHT` and t_max on a miss. With
/// `any_hit` the first hit found is returned (shadow rays). The unbounded primitives (infinite
/// planes, after the BVH's) come first, then the BVH, stackless: a missed box, or a finished
/// leaf, continues at the node's miss link.
///
/// With instances the walk has two levels in one loop: after the world's BVH (which ends at
/// node 0's miss link) comes the top level over the instances' bounds, one instance per leaf;
/// a leaf's instance moves the ray into its object's space and walks the object's BVH, whose
/// end returns to the top level at the leaf's miss link. Both levels share one bound of
/// `TRACE_STEPS` loop turns (lavapipe's loop limit).
///
/// Hit name `ignore` (`NO_LIGHT`: none) is ignored: the smooth triangle the ray leaves. A ray
/// leaving a smooth triangle may head below the triangle's plane (its shading normal allows
/// directions the flat facet faces away from), and would then meet its own facet at once; Hanika's
/// shifted origin (`Hit::shift`) keeps it off the neighbouring facets. A flat triangle's rays never
/// cross its plane, so flat scenes skip nothing.
pub fn trace_ray(s: &SceneView, o: Vec3, d: Vec3, t_max: f32, any_hit: bool, ignore: u32) -> (u32, f32) {
    let nodes = s.nodes;
    let world = WalkRay::new(o, d, 1.0);
    let mut t_hit = t_max;
    let mut hit = NO_LIGHT;
    for i in s.frame.unbounded_first..s.frame.csg_first {
        visit(s, i, i, &world, o, d, ignore, &mut hit, &mut t_hit);
        if any_hit && hit != NO_LIGHT {
            return (hit, t_hit);
        }
    }
    let flat_end = nodes.first().map_or(0, |n| n.skip() as usize);
    let world_end = if s.frame.instance_count > 0 { nodes[flat_end].skip() as usize } else { flat_end };
    let mut r = WalkRay::new(o, d, 1.0);
    let (mut node, mut end, mut base) = (0usize, world_end, 0u32);
    let mut resume: Option<usize> = None;
    for _ in 0..TRACE_STEPS {
        if node >= end {
            let Some(next) = resume.take() else { break };
            (node, end, base) = (next, world_end, 0);
            r = WalkRay::new(o, d, 1.0);
            continue;
        }
        let n = &nodes[node];
        let (count, skip) = (n.count(), n.skip() as usize);
        if ray_box(r.o_a, r.inv_d, Vec3A::from(n.aabb_min), Vec3A::from(n.aabb_max), t_hit * r.len) == f32::INFINITY {
            node = skip;
            continue;
        }
        if count == 0 {
            node += 1;
            continue;
        }
        if node >= flat_end && resume.is_none() {
            // A leaf of the top level: walk its instance's object.
            let rec = record(s, n.first);
            let (oo, od, len) = object_ray(rec, o, d);
            r = WalkRay::new(oo, od, len);
            base = (n.first + 1) * s.frame.primitive_count;
            resume = Some(skip);
            let (root, object_end) = object_nodes(rec);
            (node, end) = (root as usize, object_end as usize);
            continue;
        }
        for i in n.first..n.first + count {
            let before = hit;
            // A CSG object reports the leaf primitive it shows (`cpu/csg.rs`), so callers see an
            // ordinary primitive (an instance's: base + leaf). The walk runs on the walk's ray,
            // the world's or an instance's object-space one, like any primitive's test.
            if s.primitives[i as usize].kind & PRIMITIVE_KIND_MASK == PRIMITIVE_CSG {
                let (t, leaf) = csg_intersect(s, i, r.o, r.d, t_hit * r.len);
                let t = t / r.len;
                if t < t_hit {
                    t_hit = t;
                    hit = base + leaf;
                }
            } else {
                visit(s, i, base + i, &r, o, d, ignore, &mut hit, &mut t_hit);
            }
            if any_hit && hit != before {
                return (hit, t_hit);
            }
        }
        node = skip;
    }
    (hit, t_hit)
}
