//! Open edges: the sides of triangles that no other triangle of the scene shares, where a
//! surface ends (the open front of a box, a quad's rim). ppm's lookups near them count the
//! kernel's share on the surface (docs/integrators.md, "`ppm` at edges").

use std::collections::HashMap;

use glam::Vec3;

use crate::layout::constants::{PRIMITIVE_FLAG_OPEN_EDGE, PRIMITIVE_KIND_MASK, PRIMITIVE_TRIANGLE};
use crate::layout::Primitive;

/// Sets `PRIMITIVE_FLAG_OPEN_EDGE << e` on each triangle whose side e (from vertex e to the
/// next) no other triangle of `primitives` has. Sides match by their vertices rounded to a
/// millionth of the triangles' extent: a quad's two triangles and an indexed mesh's neighbours
/// share them exactly, and tessellated patches (the teapot's) evaluate a shared boundary to within
/// rounding. A side that another surface meets at an angle (a wall's top under the ceiling) is
/// shared, and the lookups' probes find such edges instead.
pub fn mark_open_edges(primitives: &mut [Primitive]) {
    let is_triangle = |p: &Primitive| p.kind & PRIMITIVE_KIND_MASK == PRIMITIVE_TRIANGLE;
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in primitives.iter().filter(|p| is_triangle(p)) {
        for v in [p.p0, p.p1, p.p2] {
            (lo, hi) = (lo.min(Vec3::from(v)), hi.max(Vec3::from(v)));
        }
    }
    let cell = ((hi - lo).max_element() as f64 * 1e-6).max(f64::MIN_POSITIVE);
    let snap = |v: [f32; 3]| v.map(|c| (c as f64 / cell).round() as i64);
    let key = |a: [f32; 3], b: [f32; 3]| {
        let (a, b) = (snap(a), snap(b));
        if a <= b {
            (a, b)
        } else {
            (b, a)
        }
    };
    let sides = |p: &Primitive| [(p.p0, p.p1), (p.p1, p.p2), (p.p2, p.p0)];
    let mut count: HashMap<_, u32> = HashMap::new();
    for p in primitives.iter().filter(|p| is_triangle(p)) {
        for (a, b) in sides(p) {
            *count.entry(key(a, b)).or_default() += 1;
        }
    }
    for p in primitives.iter_mut().filter(|p| is_triangle(p)) {
        for (e, (a, b)) in sides(p).into_iter().enumerate() {
            if count[&key(a, b)] == 1 {
                p.kind |= PRIMITIVE_FLAG_OPEN_EDGE << e;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(p0: [f32; 3], p1: [f32; 3], p2: [f32; 3]) -> Primitive {
        Primitive { p0, p1, p2, kind: PRIMITIVE_TRIANGLE, ..Default::default() }
    }

    #[test]
    fn a_quads_diagonal_is_shared_and_its_rim_is_open() {
        let (a, b, c, d) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]);
        let mut quad = [triangle(a, b, c), triangle(a, c, d)];
        mark_open_edges(&mut quad);
        let open = |p: &Primitive| (p.kind >> PRIMITIVE_FLAG_OPEN_EDGE.trailing_zeros()) & 7;
        // First: a-b and b-c open, c-a shared; second: a-c shared, c-d and d-a open.
        assert_eq!(open(&quad[0]), 0b011);
        assert_eq!(open(&quad[1]), 0b110);
        // A neighbour whose shared vertices differ in their last bits still closes the side.
        let nudged = [1.0 + f32::EPSILON, 1.0, 0.0];
        let mut pair = [triangle(a, b, c), triangle(b, [2.0, 0.5, 0.0], nudged)];
        mark_open_edges(&mut pair);
        assert_eq!(open(&pair[0]) & 0b010, 0, "the side b-c is shared");
    }
}
