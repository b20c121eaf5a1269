//! Surfaces POV-Ray defines by an equation (quadric, cubic, quartic, poly) or a field (blob),
//! and the CSG objects that hold them, as triangles: marching tetrahedra over a grid on the
//! object's bounds, each crossing point found by bisection on the solid's inside test.
//!
//! Tolerance (docs/pov-ray.md): the grid has `GRID` cells along the bounds' longest side; a
//! vertex lies within 1/2^`BISECTIONS` of a cell edge from the true surface; detail smaller than
//! a cell can be lost and sharp CSG edges are bevelled by up to a cell.

use glam::{DMat4, DVec3};

use super::ast::{CsgOp, Obj, ObjKind};
use super::tessellate::Tri;

/// Grid cells along the longest side of the bounds.
pub const GRID: usize = 40;
/// Bisection steps that place a vertex on a crossing edge.
pub const BISECTIONS: usize = 10;

#[derive(Clone, Debug)]
pub enum Implicit {
    /// sum of c x^i y^j z^k; inside where negative (POV-Ray's poly, quadric, cubic, quartic).
    Poly { terms: Vec<(f64, [i32; 3])> },
    /// POV-Ray's blob: inside where the summed field exceeds the threshold; each component's
    /// field is s (1 - d^2 / r^2)^2 within r of its centre (or axis, for a cylinder).
    Blob { threshold: f64, comps: Vec<BlobComp> },
}

#[derive(Clone, Debug)]
pub struct BlobComp {
    pub strength: f64,
    pub radius: f64,
    pub a: DVec3,
    /// The other end of a cylinder component.
    pub b: Option<DVec3>,
    /// component_from_blob: the component's own transforms, inverted.
    pub inv: DMat4,
}

impl Implicit {
    /// POV-Ray's coefficient order for a polynomial of order n: x powers from n down, then y,
    /// then z, every term of total degree at most n (reference manual, "Poly").
    pub fn poly(order: i32, coeffs: &[f64]) -> Option<Implicit> {
        let mut terms = Vec::new();
        let mut it = coeffs.iter();
        for i in (0..=order).rev() {
            for j in (0..=order - i).rev() {
                for k in (0..=order - i - j).rev() {
                    let c = *it.next()?;
                    if c != 0.0 {
                        terms.push((c, [i, j, k]));
                    }
                }
            }
        }
        it.next().is_none().then_some(Implicit::Poly { terms })
    }

    /// The number of coefficients of a polynomial of order n: (n + 1)(n + 2)(n + 3) / 6.
    pub fn coefficients(order: i32) -> usize {
        let n = order as usize;
        (n + 1) * (n + 2) * (n + 3) / 6
    }

    pub fn value(&self, p: DVec3) -> f64 {
        match self {
            Implicit::Poly { terms } => {
                terms.iter().map(|(c, [i, j, k])| c * p.x.powi(*i) * p.y.powi(*j) * p.z.powi(*k)).sum()
            }
            Implicit::Blob { threshold, comps } => {
                let mut field = 0.0;
                for c in comps {
                    let q = c.inv.transform_point3(p);
                    let d2 = match c.b {
                        None => (q - c.a).length_squared(),
                        Some(b) => {
                            let ab = b - c.a;
                            let t = ((q - c.a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
                            (q - (c.a + t * ab)).length_squared()
                        }
                    };
                    let r2 = c.radius * c.radius;
                    if d2 < r2 {
                        let f = 1.0 - d2 / r2;
                        field += c.strength * f * f;
                    }
                }
                threshold - field
            }
        }
    }

    /// A blob's own bounds (object space): its components with positive strength.
    pub fn blob_bounds(&self) -> Option<(DVec3, DVec3)> {
        let Implicit::Blob { comps, .. } = self else { return None };
        let mut lo = DVec3::splat(f64::MAX);
        let mut hi = DVec3::splat(f64::MIN);
        for c in comps.iter().filter(|c| c.strength > 0.0) {
            let fwd = c.inv.inverse();
            let (a, b) = (c.a.min(c.b.unwrap_or(c.a)), c.a.max(c.b.unwrap_or(c.a)));
            let (a, b) = (a - c.radius, b + c.radius);
            for q in corners(a, b) {
                let w = fwd.transform_point3(q);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
        (lo.x <= hi.x).then_some((lo, hi))
    }
}

pub fn corners(a: DVec3, b: DVec3) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { a.x } else { b.x },
            if i & 2 == 0 { a.y } else { b.y },
            if i & 4 == 0 { a.z } else { b.z },
        )
    })
}

/// The box that holds box (a, b) moved by m.
pub fn moved_box(a: DVec3, b: DVec3, m: &DMat4) -> (DVec3, DVec3) {
    corners(a, b).iter().fold((DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)), |(lo, hi), q| {
        let w = m.transform_point3(*q);
        (lo.min(w), hi.max(w))
    })
}

/// Whether an object needs this module: an implicit surface, or a CSG (not a union, whose
/// parts are written one by one) holding one.
pub fn needs_mesher(o: &Obj) -> bool {
    fn holds(o: &Obj) -> bool {
        match &o.kind {
            ObjKind::Implicit { .. } => true,
            ObjKind::Csg { children, .. } => children.iter().any(holds),
            _ => false,
        }
    }
    match &o.kind {
        ObjKind::Implicit { .. } => true,
        ObjKind::Csg { op, children } if *op != CsgOp::Union => {
            children.iter().any(holds) || {
                // Beyond what Photonix's own CSG takes (docs/scene-format.md: 32 leaves, 64
                // primitives, 4 tori and superellipsoids; no triangles): meshed here too.
                let (mut leaves, mut prims, mut implicit, mut open) = (0usize, 0usize, 0usize, false);
                count(o, &mut leaves, &mut prims, &mut implicit, &mut open);
                leaves > 32 || prims > 64 || implicit > 4 || open
            }
        }
        _ => false,
    }
}

/// Leaves, primitives, tori and superellipsoids of a CSG as the TOML loader counts them, and
/// whether a part has no inside there (triangles, patches).
fn count(o: &Obj, leaves: &mut usize, prims: &mut usize, implicit: &mut usize, open: &mut bool) {
    match &o.kind {
        ObjKind::Csg { children, .. } => {
            children.iter().for_each(|c| count(c, leaves, prims, implicit, open));
            return;
        }
        ObjKind::Light(_) => return,
        ObjKind::Sphere { .. } => {
            // A sphere under a non-uniform scale is written as a superellipsoid.
            let m = glam::DMat3::from_mat4(o.xform);
            let (a, b, c) = (m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
            *prims += 1;
            if (a - b).abs() > 1e-9 * a || (a - c).abs() > 1e-9 * a {
                *implicit += 1;
            }
        }
        ObjKind::Torus { .. } | ObjKind::Superellipsoid { .. } => {
            *prims += 1;
            *implicit += 1;
        }
        ObjKind::Cylinder { .. } | ObjKind::Cone { .. } => *prims += 3,
        ObjKind::Box { .. } | ObjKind::Plane { .. } => *prims += 12,
        ObjKind::Triangles { tris, .. } => {
            *prims += tris.len();
            *open = true;
        }
        ObjKind::Patch { .. } | ObjKind::Disc { .. } => *open = true,
        _ => {}
    }
    *leaves += 1;
}

/// The bounds of the solid (POV-Ray coordinates), or `None` when it is unbounded.
pub fn finite_bounds(o: &Obj) -> Option<(DVec3, DVec3)> {
    if o.inverse {
        return None;
    }
    match &o.kind {
        ObjKind::Implicit { bound, .. } => bound.map(|(a, b)| moved_box(a, b, &o.xform)),
        ObjKind::Plane { .. } | ObjKind::Light(_) | ObjKind::Unsupported(_) => None,
        ObjKind::Csg { op: CsgOp::Intersection, children } => {
            children.iter().filter_map(finite_bounds).reduce(|(a, b), (c, d)| (a.max(c), b.min(d)))
        }
        ObjKind::Csg { op: CsgOp::Difference, children } => children.first().and_then(finite_bounds),
        ObjKind::Csg { children, .. } => {
            let all: Option<Vec<_>> = children.iter().map(finite_bounds).collect();
            all?.into_iter().reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
        }
        _ => {
            let (lo, hi) = super::emit::bounds_of(o);
            (lo.x <= hi.x).then_some((lo, hi))
        }
    }
}

/// The solid as an inside test, object transforms inverted once.
enum Solid {
    Leaf {
        inv: DMat4,
        kind: ObjKind,
        inverse: bool,
    },
    Node {
        op: CsgOp,
        kids: Vec<Solid>,
        inverse: bool,
    },
    /// Triangles (a mesh, lathe, prism, text): inside where a ray along +x crosses them an
    /// odd number of times (exact for closed meshes).
    Mesh {
        inv: DMat4,
        tris: std::rc::Rc<Vec<Tri>>,
        lo: DVec3,
        hi: DVec3,
        inverse: bool,
    },
}

fn solid(o: &Obj) -> Result<Solid, (super::Pos, String)> {
    Ok(match &o.kind {
        ObjKind::Csg { op, children } => {
            let kids = children
                .iter()
                .filter(|c| !matches!(c.kind, ObjKind::Light(_)))
                .map(solid)
                .collect::<Result<Vec<_>, _>>()?;
            Solid::Node { op: *op, kids, inverse: o.inverse }
        }
        ObjKind::Patch { .. } | ObjKind::Disc { .. } | ObjKind::Unsupported(_) => {
            return Err((
                o.pos,
                "this part has no inside (a disc or a bicubic_patch) and cannot be part of intersection, difference or merge yet".into(),
            ))
        }
        ObjKind::Triangles { tris, .. } => {
            let (lo, hi) = tris.iter().flatten().fold((DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)), |(l, h), p| {
                (l.min(*p), h.max(*p))
            });
            Solid::Mesh { inv: o.xform.inverse(), tris: tris.clone(), lo, hi, inverse: o.inverse }
        }
        kind => Solid::Leaf { inv: o.xform.inverse(), kind: kind.clone(), inverse: o.inverse },
    })
}

fn inside(s: &Solid, p: DVec3) -> bool {
    match s {
        Solid::Node { op, kids, inverse } => {
            let r = match op {
                CsgOp::Union | CsgOp::Merge => kids.iter().any(|k| inside(k, p)),
                CsgOp::Intersection => kids.iter().all(|k| inside(k, p)),
                CsgOp::Difference => {
                    kids.first().is_some_and(|k| inside(k, p)) && !kids.iter().skip(1).any(|k| inside(k, p))
                }
            };
            r != *inverse
        }
        Solid::Mesh { inv, tris, lo, hi, inverse } => {
            // Nudged off the grid's planes by odd fractions of the mesh's size: a lathe has
            // vertices at z = 0 and rings at heights the grid also holds, and a ray through an
            // edge would count it twice.
            let q = inv.transform_point3(p) + DVec3::new(0.0, 1.234_567e-7, 7.654_321e-8) * (*hi - *lo).length();
            let r = q.cmpge(*lo).all() && q.cmple(*hi).all() && {
                // Crossings of the ray q + t x (t > 0) with each triangle, in the (y, z) plane.
                let mut n = 0;
                for t in tris.iter() {
                    let (a, b, c) = (t[0], t[1], t[2]);
                    if (a.y > q.y) == (b.y > q.y) && (b.y > q.y) == (c.y > q.y) {
                        continue;
                    }
                    let d = (b.y - a.y) * (c.z - a.z) - (b.z - a.z) * (c.y - a.y);
                    if d == 0.0 {
                        continue;
                    }
                    let u = ((q.y - a.y) * (c.z - a.z) - (q.z - a.z) * (c.y - a.y)) / d;
                    let v = ((b.y - a.y) * (q.z - a.z) - (b.z - a.z) * (q.y - a.y)) / d;
                    if u >= 0.0 && v >= 0.0 && u + v < 1.0 {
                        let x = a.x + u * (b.x - a.x) + v * (c.x - a.x);
                        if x > q.x {
                            n += 1;
                        }
                    }
                }
                n % 2 == 1
            };
            r != *inverse
        }
        Solid::Leaf { inv, kind, inverse } => {
            let q = inv.transform_point3(p);
            let r = match kind {
                ObjKind::Sphere { center, radius } => (q - *center).length_squared() < radius * radius,
                ObjKind::Box { a, b } => q.cmpgt(*a).all() && q.cmplt(*b).all(),
                ObjKind::Cylinder { a, b, radius, .. } => {
                    let d = *b - *a;
                    let t = (q - *a).dot(d) / d.length_squared().max(1e-300);
                    t > 0.0 && t < 1.0 && (q - (*a + t * d)).length_squared() < radius * radius
                }
                ObjKind::Cone { a, ra, b, rb, .. } => {
                    let d = *b - *a;
                    let t = (q - *a).dot(d) / d.length_squared().max(1e-300);
                    let r = ra + t * (rb - ra);
                    t > 0.0 && t < 1.0 && (q - (*a + t * d)).length_squared() < r * r
                }
                ObjKind::Plane { normal, offset } => q.dot(normal.normalize_or_zero()) < *offset,
                ObjKind::Torus { major, minor } => {
                    let r = (q.x * q.x + q.z * q.z).sqrt() - major;
                    r * r + q.y * q.y < minor * minor
                }
                ObjKind::Superellipsoid { e, n } => {
                    let (e, n) = (e.max(1e-3), n.max(1e-3));
                    let xy = q.x.abs().powf(2.0 / e) + q.y.abs().powf(2.0 / e);
                    xy.powf(e / n) + q.z.abs().powf(2.0 / n) < 1.0
                }
                ObjKind::Implicit { shape, .. } => shape.value(q) < 0.0,
                _ => false,
            };
            r != *inverse
        }
    }
}

/// Bounds for a solid given none (POV-Ray solves such equations everywhere): the smallest cube
/// about the origin, of half-side 2^k up to 2^12, whose faces hold no point of the solid
/// (sampled 24 x 24 a face), shrunk to the points of the solid a 32^3 sampling inside finds,
/// plus one sampling step.
fn search_bounds(s: &Solid) -> Option<(DVec3, DVec3)> {
    const FACE: usize = 24;
    const INNER: usize = 32;
    for k in 0..=12 {
        let r = (1u32 << k) as f64;
        let mut touches = false;
        'faces: for axis in 0..3 {
            for side in [-r, r] {
                for i in 0..=FACE {
                    for j in 0..=FACE {
                        let (a, b) = (-r + 2.0 * r * i as f64 / FACE as f64, -r + 2.0 * r * j as f64 / FACE as f64);
                        let p = match axis {
                            0 => DVec3::new(side, a, b),
                            1 => DVec3::new(a, side, b),
                            _ => DVec3::new(a, b, side),
                        };
                        if inside(s, p) {
                            touches = true;
                            break 'faces;
                        }
                    }
                }
            }
        }
        if touches {
            continue;
        }
        let step = 2.0 * r / INNER as f64;
        let mut lo = DVec3::splat(f64::MAX);
        let mut hi = DVec3::splat(f64::MIN);
        for i in 0..=INNER {
            for j in 0..=INNER {
                for l in 0..=INNER {
                    let p = DVec3::splat(-r) + DVec3::new(i as f64, j as f64, l as f64) * step;
                    if inside(s, p) {
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
            }
        }
        if lo.x <= hi.x {
            return Some(((lo - step).max(DVec3::splat(-r)), (hi + step).min(DVec3::splat(r))));
        }
    }
    None
}

/// The six tetrahedra of a cube around its diagonal from corner 0 to corner 7 (corner bits:
/// x 1, y 2, z 4); they share faces, so the surface is closed where the solid is.
const TETS: [[usize; 4]; 6] = [[0, 1, 3, 7], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7], [0, 4, 5, 7], [0, 5, 1, 7]];

/// The triangles of an object's surface (POV-Ray coordinates, the object's transforms applied).
pub fn mesh(o: &Obj) -> Result<Vec<Tri>, (super::Pos, String)> {
    let s = solid(o)?;
    let Some((lo, hi)) = finite_bounds(o).or_else(|| search_bounds(&s)) else {
        return Err((
            o.pos,
            "this surface is unbounded: give it bounded_by or clipped_by, or intersect it with a finite shape".into(),
        ));
    };
    if !(lo.cmplt(hi).all() && lo.is_finite() && hi.is_finite()) {
        return Err((o.pos, "this surface's bounds are empty".into()));
    }
    let size = hi - lo;
    let cell = size.max_element() / GRID as f64;
    let n = (size / cell).ceil().as_uvec3().max(glam::UVec3::ONE);
    let (nx, ny, nz) = (n.x as usize + 1, n.y as usize + 1, n.z as usize + 1);
    let step = size / n.as_dvec3();
    let at = |i: usize, j: usize, k: usize| lo + DVec3::new(i as f64, j as f64, k as f64) * step;
    let mut grid = vec![false; nx * ny * nz];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                grid[(k * ny + j) * nx + i] = inside(&s, at(i, j, k));
            }
        }
    }
    let cross = |a: DVec3, b: DVec3, a_in: bool| {
        // Bisection between a point inside and one outside.
        let (mut p_in, mut p_out) = if a_in { (a, b) } else { (b, a) };
        for _ in 0..BISECTIONS {
            let m = 0.5 * (p_in + p_out);
            if inside(&s, m) {
                p_in = m;
            } else {
                p_out = m;
            }
        }
        0.5 * (p_in + p_out)
    };
    let mut tris = Vec::new();
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let c: [(DVec3, bool); 8] = std::array::from_fn(|b| {
                    let (ii, jj, kk) = (i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
                    (at(ii, jj, kk), grid[(kk * ny + jj) * nx + ii])
                });
                if c.iter().all(|x| x.1) || c.iter().all(|x| !x.1) {
                    continue;
                }
                for t in TETS {
                    let v = t.map(|b| c[b]);
                    let ins: Vec<usize> = (0..4).filter(|&q| v[q].1).collect();
                    let outs: Vec<usize> = (0..4).filter(|&q| !v[q].1).collect();
                    match ins.len() {
                        1 | 3 => {
                            let (lone, others) = if ins.len() == 1 { (ins[0], &outs) } else { (outs[0], &ins) };
                            let p = others.iter().map(|&q| cross(v[lone].0, v[q].0, v[lone].1)).collect::<Vec<_>>();
                            tris.push([p[0], p[1], p[2]]);
                        }
                        2 => {
                            let (a0, a1, b0, b1) = (ins[0], ins[1], outs[0], outs[1]);
                            let e = |a: usize, b: usize| cross(v[a].0, v[b].0, true);
                            let (p, q, r, u) = (e(a0, b0), e(a0, b1), e(a1, b1), e(a1, b0));
                            tris.push([p, q, r]);
                            tris.push([p, r, u]);
                        }
                        _ => {}
                    }
                }
            }
        }
    }
    Ok(tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::pov::Pos;

    fn obj(kind: ObjKind) -> Obj {
        Obj { kind, xform: DMat4::IDENTITY, tex: None, interior: None, inverse: false, pos: Pos::default() }
    }

    #[test]
    fn quadric_sphere_is_meshed_on_its_surface() {
        // x^2 + y^2 + z^2 - 1 as a quadric (order 2: 10 coefficients), bounded by a box.
        let mut c = vec![0.0; 10];
        c[0] = 1.0; // x^2
        c[4] = 1.0; // y^2
        c[7] = 1.0; // z^2
        c[9] = -1.0; // constant
        let shape = Implicit::poly(2, &c).unwrap();
        let o = obj(ObjKind::Implicit {
            shape: std::rc::Rc::new(shape),
            bound: Some((DVec3::splat(-1.5), DVec3::splat(1.5))),
        });
        let tris = mesh(&o).unwrap();
        let worst = tris.iter().flatten().map(|v| (v.length() - 1.0).abs()).fold(0.0, f64::max);
        println!("{} triangles, vertices off the unit sphere by at most {worst:.2e}", tris.len());
        // Bisection to 1/2^10 of a cell edge of 3/40.
        assert!(worst < 3.0 / 40.0 / 1024.0 * 2.0, "worst {worst}");
        assert!(!tris.is_empty());
    }

    #[test]
    fn coefficient_counts_follow_povray() {
        assert_eq!(Implicit::coefficients(2), 10);
        assert_eq!(Implicit::coefficients(3), 20);
        assert_eq!(Implicit::coefficients(4), 35);
        assert!(Implicit::poly(4, &[0.0; 34]).is_none());
    }
}
