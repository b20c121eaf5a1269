//! Ray casting against the flattened BVH; twin of `shaders/trace.glsl`.

use glam::Vec3;

use crate::layout::constants::{NO_LIGHT, PRIMITIVE_SPHERE};
use crate::layout::{BvhNode, Primitive};

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

/// Möller and Trumbore 1997, two-sided. Returns the hit distance, or infinity.
pub fn ray_triangle(o: Vec3, d: Vec3, p0: Vec3, p1: Vec3, p2: Vec3, t_max: f32) -> f32 {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return f32::INFINITY;
    }
    let inv_det = 1.0 / det;
    let tv = o - p0;
    let u = tv.dot(pv) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return f32::INFINITY;
    }
    let qv = tv.cross(e1);
    let v = d.dot(qv) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return f32::INFINITY;
    }
    let t = e2.dot(qv) * inv_det;
    if t > 0.0 && t < t_max {
        t
    } else {
        f32::INFINITY
    }
}

/// Nearest positive root, in the form of Haines et al., Ray Tracing Gems ch. 7.
pub fn ray_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32, t_max: f32) -> f32 {
    let f = o - c;
    let b = f.dot(d);
    let l = f - b * d;
    let disc = r * r - l.dot(l);
    if disc < 0.0 {
        return f32::INFINITY;
    }
    let s = disc.sqrt();
    let (t0, t1) = (-b - s, -b + s);
    let t = if t0 > 0.0 { t0 } else { t1 };
    if t > 0.0 && t < t_max {
        t
    } else {
        f32::INFINITY
    }
}

pub fn ray_primitive(p: &Primitive, o: Vec3, d: Vec3, t_max: f32) -> f32 {
    if p.kind == PRIMITIVE_SPHERE {
        return ray_sphere(o, d, Vec3::from(p.p0), p.p1[0], t_max);
    }
    ray_triangle(o, d, Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2), t_max)
}

/// Closest hit in [0, t_max) as (primitive index, distance), or `NO_LIGHT` and t_max on a miss.
/// With `any_hit` the first hit found is returned (shadow rays). Stackless: a missed box, or a
/// finished leaf, continues at the node's miss link.
pub fn trace_ray(nodes: &[BvhNode], prims: &[Primitive], o: Vec3, d: Vec3, t_max: f32, any_hit: bool) -> (u32, f32) {
    let inv_d = d.recip();
    let mut t_hit = t_max;
    let mut hit = NO_LIGHT;
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
            let t = ray_primitive(&prims[i as usize], o, d, t_hit);
            if t < t_hit {
                t_hit = t;
                hit = i;
                if any_hit {
                    return (hit, t_hit);
                }
            }
        }
        node = skip;
    }
    (hit, t_hit)
}
