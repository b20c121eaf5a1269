//! CSG objects: the walk of a ray through the leaves of one CSG primitive; twin of
//! `shaders/csg.glsl`.
//!
//! A CSG object is one primitive of the BVH whose shape-data block lists its leaf primitives
//! (stored after the scene's own, where only this walk meets them) and a postfix program of its
//! boolean tree. The walk starts at t = -infinity, outside every leaf, and repeatedly takes the
//! next crossing after t over all leaf primitives (every kind of leaf answers "the nearest
//! crossing after t_min" exactly, from the same ray, so no crossing is found twice), toggling the
//! inside bit of each leaf crossed there. A leaf crossed by two of its primitives at the same
//! distance (a ray through a mesh edge) toggles once. No point-in-solid test is needed, and the
//! crossings behind the ray's origin set the state the visible ones are judged in.
//!
//! Which crossings show follows POV-Ray: a lone crossing of leaf L shows when every node above L
//! lets it through given its siblings' inside values: a union always (inner surfaces stay), a
//! merge when no sibling contains the point, an intersection when every sibling does, a
//! difference when the point is outside the subtracted children (for its first child) or inside
//! the first one and outside the other subtracted ones (for a subtracted child). Evaluating the
//! program on (inside value, sensitive to L) pairs gives this in one pass. Several leaves crossed
//! at one distance (coincident faces) show when the object's inside value changes there, with
//! the normal of the first of them whose lone crossing would have changed it (a ball used both
//! whole and subtracted crosses as two leaves at once, and only the subtracted one faces out).
//!
//! Bounded work: at most `CSG_MAX_STEPS` crossings, each testing `CSG_MAX_PRIMITIVES` leaf
//! primitives and running a program of at most 2 `CSG_MAX_LEAVES` - 1 words; a ray that needs
//! more crossings than that passes the rest of the object (a miss). Coincident surfaces cost,
//! once per ray (at the crossing it reports), one program run per leaf crossed there and one
//! more pass over the leaf primitives.

use glam::Vec3;

use super::shape::{analytic_intersect, ray_sphere, ray_triangle};
use super::SceneView;
use crate::layout::constants::*;

fn csg_word(s: &SceneView, a: u32) -> u32 {
    s.shape_data[a as usize].to_bits()
}

/// Next crossing in (t_min, t_max) of leaf primitive `i`: a sphere, a triangle, or an analytic
/// shape (a disc, a cone side, a torus, a superellipsoid), each of whose tests returns the
/// nearest root after any t_min exactly (the torus and the superellipsoid find their roots
/// independently of t_min for this, see `cpu/shape.rs`).
pub fn csg_leaf_intersect(s: &SceneView, i: u32, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> f32 {
    let p = &s.primitives[i as usize];
    let kind = p.kind & PRIMITIVE_KIND_MASK;
    if kind == PRIMITIVE_SPHERE {
        return ray_sphere(o, d, Vec3::from(p.p0), p.p1[0], t_min, t_max);
    }
    if kind == PRIMITIVE_TRIANGLE {
        return ray_triangle(o, d, Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2), t_min, t_max);
    }
    analytic_intersect(s, p, o, d, t_min, t_max)
}

/// The object's inside value and whether a lone crossing of `leaf` shows, for the leaves' inside
/// bits `inside`, by the postfix program of `program_length` words at `a`.
pub fn csg_evaluate(s: &SceneView, a: u32, program_length: u32, inside: u32, leaf: u32) -> (bool, bool) {
    let (mut v, mut sens) = (0u32, 0u32);
    for k in 0..program_length {
        let w = csg_word(s, a + k);
        let op = w >> CSG_OP_SHIFT;
        if op == CSG_OP_LEAF {
            let l = w & ((1 << CSG_OP_SHIFT) - 1);
            v = (v << 1) | ((inside >> l) & 1);
            sens = (sens << 1) | u32::from(l == leaf);
        } else {
            let (vb, va) = (v & 1, (v >> 1) & 1);
            let (sb, sa) = (sens & 1, (sens >> 1) & 1);
            let (mut rv, mut rs) = (va | vb, sa | sb);
            if op == CSG_OP_MERGE {
                rs = (sa & (vb ^ 1)) | (sb & (va ^ 1));
            }
            if op == CSG_OP_INTERSECTION {
                rv = va & vb;
                rs = (sa & vb) | (sb & va);
            }
            if op == CSG_OP_DIFFERENCE {
                rv = va & (vb ^ 1);
                rs = (sa & (vb ^ 1)) | (sb & va);
            }
            v = ((v >> 2) << 1) | rv;
            sens = ((sens >> 2) << 1) | rs;
        }
    }
    (v & 1 != 0, sens & 1 != 0)
}

/// First visible surface of CSG primitive `i` in (0, t_max): its distance (infinity: none) and
/// the leaf primitive crossed there (`NO_LIGHT`: none).
pub fn csg_intersect(s: &SceneView, i: u32, o: Vec3, d: Vec3, t_max: f32) -> (f32, u32) {
    let a = s.primitives[i as usize].data;
    let count = csg_word(s, a + CSG_DATA_PRIMITIVES);
    let program_length = csg_word(s, a + CSG_DATA_PROGRAM_LENGTH);
    let first = s.frame.csg_first + csg_word(s, a + CSG_DATA_FIRST);
    let leaves = a + CSG_DATA_LEAVES;
    let program = leaves + count;
    let mut inside = 0u32;
    let mut value = false;
    let mut t = f32::NEG_INFINITY;
    for _ in 0..CSG_MAX_STEPS {
        let mut t_next = f32::INFINITY;
        let mut crossed = 0u32;
        let mut first_prim = NO_LIGHT;
        let mut first_leaf = 0u32;
        for k in 0..count {
            let tk = csg_leaf_intersect(s, first + k, o, d, t, t_max);
            let leaf = csg_word(s, leaves + k);
            if tk < t_next {
                t_next = tk;
                crossed = 1 << leaf;
                first_prim = first + k;
                first_leaf = leaf;
            } else if tk == t_next && tk < f32::INFINITY {
                crossed |= 1 << leaf;
            }
        }
        if t_next == f32::INFINITY {
            break;
        }
        let before = inside;
        inside ^= crossed;
        let lone = crossed == 1 << first_leaf;
        let (after, sensitive) =
            csg_evaluate(s, program, program_length, inside, if lone { first_leaf } else { CSG_MAX_LEAVES });
        let visible = if lone { sensitive } else { after != value };
        value = after;
        if visible && t_next > 0.0 {
            if !lone {
                // Coincident surfaces (a ball used twice in one tree): the leaf whose lone
                // crossing would have made the change has the solid's normal there.
                let mut shown = first_leaf;
                let mut m = crossed;
                while m != 0 {
                    let l = m.trailing_zeros();
                    if csg_evaluate(s, program, program_length, before, l).1 {
                        shown = l;
                        break;
                    }
                    m &= m - 1;
                }
                for k in 0..count {
                    if shown == first_leaf {
                        break;
                    }
                    if csg_word(s, leaves + k) == shown && csg_leaf_intersect(s, first + k, o, d, t, t_max) == t_next {
                        first_prim = first + k;
                        break;
                    }
                }
            }
            return (t_next, first_prim);
        }
        t = t_next;
    }
    (f32::INFINITY, NO_LIGHT)
}
