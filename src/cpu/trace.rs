//! Ray casting against the flattened BVH; twin of `shaders/trace.glsl`.

use arrayvec::ArrayVec;
use glam::{Vec3, Vec3A, Vec4};

use super::bsdf::hash_point;
use super::bsdf::material_opacity;
use super::csg::csg_intersect;
use super::instance::{hit_primitive, object_nodes, object_ray, record};
use super::shape::{shape_hit, shape_intersect};
use super::SceneView;
use crate::accel::wide::{TriangleBlock, WideBvh, WideNode, NO_BLOCK};
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

/// `visit` for a BVH leaf's primitive `i` of the instance whose hit names start at `base` (the
/// world's: 0). A CSG object reports the leaf primitive it shows (`cpu/csg.rs`), so callers see an
/// ordinary primitive (an instance's: base + leaf). Either runs on the walk's ray, the world's or
/// an instance's object-space one.
#[allow(clippy::too_many_arguments)]
fn visit_leaf_primitive(
    s: &SceneView,
    i: u32,
    base: u32,
    r: &WalkRay,
    o: Vec3,
    d: Vec3,
    ignore: u32,
    hit: &mut u32,
    t_hit: &mut f32,
) {
    if s.primitives[i as usize].kind & PRIMITIVE_KIND_MASK == PRIMITIVE_CSG {
        let (t, leaf) = csg_intersect(s, i, r.o, r.d, *t_hit * r.len);
        let t = t / r.len;
        if t < *t_hit {
            *t_hit = t;
            *hit = base + leaf;
        }
    } else {
        visit(s, i, base + i, r, o, d, ignore, hit, t_hit);
    }
}

/// The unbounded primitives (infinite planes), which both walks test before the BVH's: the
/// closest hit among them as (hit name, distance), or the first with `any_hit`.
fn visit_unbounded(s: &SceneView, world: &WalkRay, t_max: f32, any_hit: bool, ignore: u32) -> (u32, f32) {
    let (mut hit, mut t_hit) = (NO_LIGHT, t_max);
    for i in s.frame.unbounded_first..s.frame.csg_first {
        visit(s, i, i, world, world.o, world.d, ignore, &mut hit, &mut t_hit);
        if any_hit && hit != NO_LIGHT {
            break;
        }
    }
    (hit, t_hit)
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
    if let Some(found) = s.wide.and_then(|w| trace_wide(s, w, o, d, t_max, any_hit, ignore)) {
        return found;
    }
    trace_threaded(s, o, d, t_max, any_hit, ignore)
}

/// The kernels' walk (`shaders/trace.glsl`) over the binary BVH: every box in the fixed depth
/// first order, each missed one skipped by its miss link. The CPU backend takes it for views
/// without the wide BVH (`SceneView::geometry`) and where `trace_wide`'s stack overflows.
fn trace_threaded(s: &SceneView, o: Vec3, d: Vec3, t_max: f32, any_hit: bool, ignore: u32) -> (u32, f32) {
    let nodes = s.nodes;
    let world = WalkRay::new(o, d, 1.0);
    let (mut hit, mut t_hit) = visit_unbounded(s, &world, t_max, any_hit, ignore);
    if any_hit && hit != NO_LIGHT {
        return (hit, t_hit);
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
            visit_leaf_primitive(s, i, base, &r, o, d, ignore, &mut hit, &mut t_hit);
            if any_hit && hit != before {
                return (hit, t_hit);
            }
        }
        node = skip;
    }
    (hit, t_hit)
}

/// Most nodes and leaves one `trace_wide` takes over both levels; a ray that needs more is
/// traced again by the kernels' walk under the kernels' bound (`TRACE_STEPS` binary nodes, where
/// lavapipe's loop limit would otherwise stop them): in scenes that deep (hundreds of
/// overlapping instances) the backends then find the same hits, or miss the same ones. A wide
/// turn stands for two to four binary ones, so ordinary rays (tens of turns) never come close.
const WIDE_TURNS: u32 = TRACE_STEPS / 8;

/// Deferred children of `walk_wide`: three per level of a tree far deeper than any SAH build's.
const WIDE_STACK: usize = 192;

/// A `WalkRay` in SIMD lanes: each coordinate of the origin and of 1 / direction in all four.
struct WideRay {
    o: [Vec4; 3],
    d: [Vec4; 3],
    inv_d: [Vec4; 3],
}

impl WideRay {
    fn new(r: &WalkRay) -> WideRay {
        WideRay {
            o: [0, 1, 2].map(|a| Vec4::splat(r.o_a[a])),
            d: [0, 1, 2].map(|a| Vec4::splat(r.d[a])),
            inv_d: [0, 1, 2].map(|a| Vec4::splat(r.inv_d[a])),
        }
    }
}

/// `ray_box` for a wide node's four boxes at once: their entry distances, and the lanes whose
/// box the ray enters within [0, t_max). Each `min` and `max` takes the running bound as its
/// second operand, which SSE returns where a slab distance is NaN, so a NaN slab (a ray in a
/// box face's plane) is ignored rather than deciding the lane.
#[inline]
fn enter_wide(n: &WideNode, r: &WideRay, t_max: f32) -> (Vec4, u32) {
    let mut enter = Vec4::ZERO;
    let mut leave = Vec4::splat(t_max);
    for axis in 0..3 {
        let t0 = (n.lo[axis] - r.o[axis]) * r.inv_d[axis];
        let t1 = (n.hi[axis] - r.o[axis]) * r.inv_d[axis];
        enter = t0.min(t1).max(enter);
        leave = t0.max(t1).min(leave);
    }
    (enter, enter.cmple(leave).bitmask() & n.lanes)
}

/// Cross and dot products of vectors in lanes, in the operations and order of glam's `Vec3`, so
/// that each lane rounds as `ray_triangle`'s scalar form does.
fn cross4(a: &[Vec4; 3], b: &[Vec4; 3]) -> [Vec4; 3] {
    [a[1] * b[2] - b[1] * a[2], a[2] * b[0] - b[2] * a[0], a[0] * b[1] - b[0] * a[1]]
}

fn dot4(a: &[Vec4; 3], b: &[Vec4; 3]) -> Vec4 {
    (a[0] * b[0]) + (a[1] * b[1]) + (a[2] * b[2])
}

/// `ray_triangle` (t_min 0) in four lanes: each lane's distance, and the lanes whose triangle
/// the ray meets in (0, t_max). Every lane computes `ray_triangle`'s very floats; its early
/// outs become the mask (a NaN fails every comparison, as there).
#[inline]
fn ray_triangles(b: &TriangleBlock, r: &WideRay, t_max: f32) -> (Vec4, u32) {
    let pv = cross4(&r.d, &b.e2);
    let det = dot4(&b.e1, &pv);
    let inv_det = Vec4::ONE / det;
    let tv = [r.o[0] - b.p0[0], r.o[1] - b.p0[1], r.o[2] - b.p0[2]];
    let u = dot4(&tv, &pv) * inv_det;
    let qv = cross4(&tv, &b.e1);
    let v = dot4(&r.d, &qv) * inv_det;
    let t = dot4(&b.e2, &qv) * inv_det;
    let inside = det.cmpne(Vec4::ZERO)
        & u.cmpge(Vec4::ZERO)
        & u.cmple(Vec4::ONE)
        & v.cmpge(Vec4::ZERO)
        & (u + v).cmple(Vec4::ONE)
        & t.cmpgt(Vec4::ZERO)
        & t.cmplt(Vec4::splat(t_max));
    (t, inside.bitmask())
}

/// `trace_threaded` over the wide BVH (`accel::wide`): four boxes a node, four opaque
/// triangles a leaf, and a deferred child dropped unseen once the closest hit lies before its
/// box. It takes the leaves in the kernels' order, the binary tree's depth first, not front to
/// back: where two surfaces lie within a rounding of each other (coplanar faces: a floor and
/// the bottom of a fog box on it) the first one found keeps the hit and a box entered a rounding
/// later is dropped, so only the kernels' order finds the kernels' hit, and which surface a
/// ray meets there decides which medium it enters. Front to back gained nothing measurable on
/// the shipped scenes. `None` when the stack overflows or the walk takes more than
/// `WIDE_TURNS`.
fn trace_wide(
    s: &SceneView,
    w: &WideBvh,
    o: Vec3,
    d: Vec3,
    t_max: f32,
    any_hit: bool,
    ignore: u32,
) -> Option<(u32, f32)> {
    let world = WalkRay::new(o, d, 1.0);
    let (mut hit, mut t_hit) = visit_unbounded(s, &world, t_max, any_hit, ignore);
    if any_hit && hit != NO_LIGHT {
        return Some((hit, t_hit));
    }
    // A leaf's primitives (`base`: the hit names' offset of an instance's), true to stop.
    let primitives = |r: &WalkRay, wr: &WideRay, base: u32, leaf: Leaf, t_hit: &mut f32, hit: &mut u32| {
        let Leaf { first, count, block } = leaf;
        if block != NO_BLOCK {
            // Opaque triangles: tested at once, then taken in leaf order as `visit` would.
            let (t, lanes) = ray_triangles(&w.blocks[block as usize], wr, *t_hit * r.len);
            for k in 0..count {
                let id = base + first + k;
                let t = t[k as usize];
                if lanes & (1 << k) != 0 && id != ignore && t < *t_hit * r.len && t / r.len < *t_hit {
                    *t_hit = t / r.len;
                    *hit = id;
                    if any_hit {
                        return true;
                    }
                }
            }
            return false;
        }
        for i in first..first + count {
            let before = *hit;
            visit_leaf_primitive(s, i, base, r, o, d, ignore, hit, t_hit);
            if any_hit && *hit != before {
                return true;
            }
        }
        false
    };
    let wide_world = WideRay::new(&world);
    let leaves =
        &mut |leaf, t_hit: &mut f32, hit: &mut u32, _: &mut u32| primitives(&world, &wide_world, 0, leaf, t_hit, hit);
    let mut turns = 0;
    if walk_wide(w, w.world, &world, &wide_world, &mut t_hit, &mut hit, &mut turns, leaves)? {
        return Some((hit, t_hit));
    }
    if s.frame.instance_count > 0 {
        // The top level, one instance per leaf, each walked in its object's space.
        let mut overflow = false;
        let instances = &mut |leaf: Leaf, t_hit: &mut f32, hit: &mut u32, turns: &mut u32| {
            let k = leaf.first;
            let rec = record(s, k);
            let (oo, od, len) = object_ray(rec, o, d);
            let r = WalkRay::new(oo, od, len);
            let base = (k + 1) * s.frame.primitive_count;
            let root = w.instance_roots[k as usize];
            let wr = WideRay::new(&r);
            let leaves =
                &mut |leaf, t_hit: &mut f32, hit: &mut u32, _: &mut u32| primitives(&r, &wr, base, leaf, t_hit, hit);
            let stop = walk_wide(w, root, &r, &wr, t_hit, hit, turns, leaves);
            overflow |= stop.is_none();
            stop.unwrap_or(true)
        };
        let stopped = walk_wide(w, w.top, &world, &wide_world, &mut t_hit, &mut hit, &mut turns, instances);
        if overflow {
            return None;
        }
        stopped?;
    }
    Some((hit, t_hit))
}

/// A leaf of the wide BVH: its primitives (a top-level leaf's: its instance record) and their
/// `TriangleBlock`, if they have one.
#[derive(Clone, Copy)]
struct Leaf {
    first: u32,
    count: u32,
    block: u32,
}

/// Walks the wide tree at `root` along `r` (`wr` its lanes), calling `leaf` with each leaf
/// whose box the ray enters before the closest hit so far (`t_hit`, world
/// distance). Some(true) when `leaf` asked to stop, None when the stack overflowed.
#[allow(clippy::too_many_arguments)]
fn walk_wide(
    w: &WideBvh,
    root: u32,
    r: &WalkRay,
    wr: &WideRay,
    t_hit: &mut f32,
    hit: &mut u32,
    turns: &mut u32,
    leaf: &mut impl FnMut(Leaf, &mut f32, &mut u32, &mut u32) -> bool,
) -> Option<bool> {
    // (child, leaf count or 0 for a node, leaf block, entry distance on the walk's ray)
    let mut stack: ArrayVec<(u32, u32, u32, f32), WIDE_STACK> = ArrayVec::new();
    stack.push((root, 0, NO_BLOCK, 0.0));
    while let Some((child, count, block, t_enter)) = stack.pop() {
        if t_enter >= *t_hit * r.len {
            continue;
        }
        *turns += 1;
        if *turns > WIDE_TURNS {
            return None;
        }
        if count > 0 {
            if leaf(Leaf { first: child, count, block }, t_hit, hit, turns) {
                return Some(true);
            }
            continue;
        }
        let n = &w.nodes[child as usize];
        let (enter, lanes) = enter_wide(n, wr, *t_hit * r.len);
        if stack.remaining_capacity() < 4 {
            return None;
        }
        // Last lane first, so that the walk takes the leaves in the kernels' order (below).
        for lane in (0..4).rev() {
            if lanes & (1 << lane) != 0 {
                stack.push((n.child[lane], n.count[lane], n.block[lane], enter[lane]));
            }
        }
    }
    Some(false)
}
