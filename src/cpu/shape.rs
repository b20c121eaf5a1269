//! Shapes: one match per operation (intersect, hit record, sample); twin of `shaders/shape.glsl`.

use std::f32::consts::PI;

use glam::{Mat3, Vec2, Vec3};

use super::sampling::{onb, sphere_direction};
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Primitive;

/// Everything the shading of a surface point needs, built in one place (`shape_hit`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hit {
    pub p: Vec3,
    /// Unit geometric normal: a triangle's winding normal, a sphere's outward normal.
    pub ng: Vec3,
    /// Unit shading normal, on the side of `ng`.
    pub ns: Vec3,
    pub uv: Vec2,
    /// Surface derivatives along u and v (never zero: a frame from `ng` when uv is degenerate;
    /// uv, dpdu and dpdv are zero unless the primitive has `PRIMITIVE_FLAG_UV`).
    pub dpdu: Vec3,
    pub dpdv: Vec3,
    pub prim: u32,
    pub material: u32,
}

/// Möller and Trumbore 1997, two-sided. Returns the hit distance in (t_min, t_max), or infinity.
#[allow(clippy::too_many_arguments)] // the kernel's signature, kept identical
pub fn ray_triangle(o: Vec3, d: Vec3, p0: Vec3, p1: Vec3, p2: Vec3, t_min: f32, t_max: f32) -> f32 {
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
    if t > t_min && t < t_max {
        t
    } else {
        f32::INFINITY
    }
}

/// Nearest root in (t_min, t_max), in the form of Haines et al., Ray Tracing Gems ch. 7.
pub fn ray_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32, t_min: f32, t_max: f32) -> f32 {
    let f = o - c;
    let b = f.dot(d);
    let l = f - b * d;
    let disc = r * r - l.dot(l);
    if disc < 0.0 {
        return f32::INFINITY;
    }
    let s = disc.sqrt();
    let (t0, t1) = (-b - s, -b + s);
    let t = if t0 > t_min { t0 } else { t1 };
    if t > t_min && t < t_max {
        t
    } else {
        f32::INFINITY
    }
}

/// Distance to the first surface of `p` along o + t d with t in (t_min, t_max), or infinity.
pub fn shape_intersect(p: &Primitive, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> f32 {
    match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_SPHERE => ray_sphere(o, d, Vec3::from(p.p0), p.p1[0], t_min, t_max),
        _ => ray_triangle(o, d, Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2), t_min, t_max),
    }
}

/// dpdu and dpdv of a flat triangle with vertex uvs (pbrt-v4's
/// `Triangle::InteractionFromIntersection`); a frame around `ng` when the uvs are degenerate.
pub fn triangle_derivatives(p: [Vec3; 3], uv: [Vec2; 3], ng: Vec3) -> (Vec3, Vec3) {
    let duv02 = uv[0] - uv[2];
    let duv12 = uv[1] - uv[2];
    let dp02 = p[0] - p[2];
    let dp12 = p[1] - p[2];
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    if det.abs() > 1e-12 {
        let inv = 1.0 / det;
        let dpdu = (duv12.y * dp02 - duv02.y * dp12) * inv;
        let dpdv = (duv02.x * dp12 - duv12.x * dp02) * inv;
        if dpdu.cross(dpdv).length() > 0.0 {
            return (dpdu, dpdv);
        }
    }
    onb(ng)
}

/// The three vertex uvs of triangle `p`: from the shape data, else the barycentric default
/// (0, 0), (1, 0), (0, 1).
pub fn triangle_uvs(s: &SceneView, p: &Primitive) -> [Vec2; 3] {
    if p.data == NO_DATA {
        return [Vec2::ZERO, Vec2::X, Vec2::Y];
    }
    let a = &s.shape_data[p.data as usize..p.data as usize + 6];
    [Vec2::new(a[0], a[1]), Vec2::new(a[2], a[3]), Vec2::new(a[4], a[5])]
}

/// Longitude/latitude uv of unit vector `w` (object space, +y the pole): u grows with the angle
/// atan2(x, z) from 0 at -z, v from 0 at the south pole to 1 at the north pole. Also returns the
/// derivatives of the unit direction along u and v.
pub fn sphere_uv(w: Vec3) -> (Vec2, Vec3, Vec3) {
    let rho = (w.x * w.x + w.z * w.z).sqrt();
    let u = 0.5 + w.x.atan2(w.z) * (0.5 / PI);
    let v = 0.5 + w.y.clamp(-1.0, 1.0).asin() / PI;
    let dwdu = 2.0 * PI * Vec3::new(w.z, 0.0, -w.x);
    let dwdv = if rho > 0.0 { PI * Vec3::new(-w.y * w.x / rho, rho, -w.y * w.z / rho) } else { Vec3::ZERO };
    (Vec2::new(u, v), dwdu, dwdv)
}

/// A sphere's `object_from_world` rotation (rows in the shape data), identity without data.
pub fn sphere_rotation(s: &SceneView, p: &Primitive) -> Mat3 {
    if p.data == NO_DATA {
        return Mat3::IDENTITY;
    }
    let a = &s.shape_data[p.data as usize..p.data as usize + 9];
    Mat3::from_cols_slice(a).transpose()
}

/// The hit record of point `x` (on the surface) of primitive `i`.
pub fn shape_surface(s: &SceneView, i: u32, x: Vec3) -> Hit {
    let p = &s.primitives[i as usize];
    let mut h = Hit { p: x, prim: i, material: p.material, ..Default::default() };
    let wants_uv = p.kind & PRIMITIVE_FLAG_UV != 0;
    match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_SPHERE => {
            let (c, r) = (Vec3::from(p.p0), p.p1[0]);
            h.ng = (x - c).normalize();
            if wants_uv {
                let object_from_world = sphere_rotation(s, p);
                let (uv, dwdu, dwdv) = sphere_uv(object_from_world * h.ng);
                h.uv = uv;
                h.dpdu = r * (object_from_world.transpose() * dwdu);
                h.dpdv = r * (object_from_world.transpose() * dwdv);
                if h.dpdu.cross(h.dpdv).length() == 0.0 {
                    (h.dpdu, h.dpdv) = onb(h.ng);
                }
            }
        }
        _ => {
            let (p0, p1, p2) = (Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2));
            let (e1, e2) = (p1 - p0, p2 - p0);
            h.ng = e1.cross(e2).normalize();
            if wants_uv {
                // Barycentrics of x from the normal equations of x - p0 = b1 e1 + b2 e2.
                let v = x - p0;
                let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
                let (d20, d21) = (v.dot(e1), v.dot(e2));
                let inv = 1.0 / (d00 * d11 - d01 * d01);
                let b1 = (d11 * d20 - d01 * d21) * inv;
                let b2 = (d00 * d21 - d01 * d20) * inv;
                let uv = triangle_uvs(s, p);
                h.uv = (1.0 - b1 - b2) * uv[0] + b1 * uv[1] + b2 * uv[2];
                (h.dpdu, h.dpdv) = triangle_derivatives([p0, p1, p2], uv, h.ng);
            }
        }
    }
    h.ns = h.ng;
    h
}

/// The hit record of the ray o + t d on primitive `i`.
pub fn shape_hit(s: &SceneView, i: u32, o: Vec3, d: Vec3, t: f32) -> Hit {
    shape_surface(s, i, o + t * d)
}

/// A point on primitive `i`, uniform by area (Turk 1990 for triangles), as a hit record.
pub fn shape_sample(s: &SceneView, i: u32, u: [f32; 2]) -> Hit {
    let p = &s.primitives[i as usize];
    let x = match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_SPHERE => Vec3::from(p.p0) + p.p1[0] * sphere_direction(u),
        _ => {
            let su = u[0].sqrt();
            let b0 = 1.0 - su;
            let b1 = u[1] * su;
            b0 * Vec3::from(p.p0) + b1 * Vec3::from(p.p1) + (1.0 - b0 - b1) * Vec3::from(p.p2)
        }
    };
    shape_surface(s, i, x)
}
