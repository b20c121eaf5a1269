//! Analytic shapes on the host: their object-space definitions (the same as `shaders/shape.glsl`
//! and `cpu::shape`), world bounds and areas, and two things the tests compare the kernels with: a
//! double-precision ray intersection that shares no code with the kernels, and a fine
//! tessellation.
//!
//! Every shape lives in its own object space (y is its axis) and reaches the world through an
//! affine `world_from_object` (any rotation, scale, mirror and translation):
//! - plane: y = 0, normal +y, unbounded;
//! - disc: y = 0, |(x, z)| in [inner_radius, radius], normal +y;
//! - cone: the side of a truncated cone from radius `r0` at y = 0 to `r1` at y = h (a cylinder
//!   when they are equal), normal outward; its caps are discs of their own;
//! - torus: (|p|^2 + R^2 - r^2)^2 = 4 R^2 (x^2 + z^2), around the y axis;
//! - superellipsoid: POV-Ray's, (|x|^(2/e) + |y|^(2/e))^(e/n) + |z|^(2/n) = 1 inside [-1, 1]^3.

use std::f64::consts::PI;

use glam::{Affine3A, DAffine3, DMat3, DVec3, Vec3};

/// The shape in its object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnalyticKind {
    Plane,
    Disc {
        radius: f32,
        inner_radius: f32,
    },
    /// Radius `r0` at y = 0 and `r1` at y = `height`.
    Cone {
        r0: f32,
        r1: f32,
        height: f32,
    },
    Torus {
        major: f32,
        minor: f32,
    },
    /// POV-Ray's exponents: `e` (east-west, in x and y) and `n` (north-south, along z), in (0, 2].
    Superellipsoid {
        e: f32,
        n: f32,
    },
}

/// An analytic shape placed in the world. Its front face is outward (a plane's and a disc's is
/// their +y side in object space).
#[derive(Clone, Debug, PartialEq)]
pub struct Analytic {
    pub kind: AnalyticKind,
    pub world_from_object: Affine3A,
}

/// Side of the grid of (u, v) samples that estimates a world area by quadrature.
const AREA_GRID: usize = 64;

impl Analytic {
    /// True for the infinite plane, which no box bounds.
    pub fn is_unbounded(&self) -> bool {
        matches!(self.kind, AnalyticKind::Plane)
    }

    /// Axis-aligned bounds in object space; `None` for the plane.
    pub fn object_bounds(&self) -> Option<(Vec3, Vec3)> {
        Some(match self.kind {
            AnalyticKind::Plane => return None,
            AnalyticKind::Disc { radius, .. } => (Vec3::new(-radius, 0.0, -radius), Vec3::new(radius, 0.0, radius)),
            AnalyticKind::Cone { r0, r1, height } => {
                let r = r0.max(r1);
                (Vec3::new(-r, 0.0, -r), Vec3::new(r, height, r))
            }
            AnalyticKind::Torus { major, minor } => {
                let r = major + minor;
                (Vec3::new(-r, -minor, -r), Vec3::new(r, minor, r))
            }
            AnalyticKind::Superellipsoid { .. } => (Vec3::splat(-1.0), Vec3::ONE),
        })
    }

    /// World bounds (min, max): the object box's eight corners moved; infinite for the plane.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let Some((lo, hi)) = self.object_bounds() else {
            return (Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY));
        };
        transformed_box(&self.world_from_object, lo, hi)
    }

    /// The largest coordinate of the world bounds (0 for the plane): the scale of the shape's
    /// float error, which its ray offsets follow (`SHAPE_DATA_SIZE`).
    pub fn size(&self) -> f32 {
        if self.is_unbounded() {
            return 0.0;
        }
        let (lo, hi) = self.bounds();
        lo.abs().max(hi.abs()).max_element()
    }

    /// World surface area; infinite for the plane. Exact for discs and cones under similarity
    /// transforms; otherwise the mean of the emitter sampling's 1/pdf over a midpoint grid of
    /// (u, v), which converges fast for smooth, periodic integrands (within 1e-6 of the closed
    /// forms for discs, cones, tori and round superellipsoids; 0.6% for the octahedron, e = n = 2,
    /// whose edges are kinks). Lights are picked by power from this area, and the automatic
    /// photon radius follows it; neither needs more.
    pub fn area(&self) -> f32 {
        if self.is_unbounded() {
            return f32::INFINITY;
        }
        let n = AREA_GRID;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                sum += self.sample(u).2;
            }
        }
        (sum / (n * n) as f64) as f32
    }

    fn world_from_object_f64(&self) -> DAffine3 {
        let m = &self.world_from_object;
        DAffine3::from_mat3_translation(
            DMat3::from_cols(m.matrix3.x_axis.as_dvec3(), m.matrix3.y_axis.as_dvec3(), m.matrix3.z_axis.as_dvec3()),
            m.translation.as_dvec3(),
        )
    }

    /// A point of the surface for (u, v) in [0, 1)^2, with the world point, its unit world normal
    /// and the inverse of the density of such points by world area (the same warps as the
    /// kernels' `shape_sample`, in double precision).
    pub fn sample(&self, u: [f64; 2]) -> (DVec3, DVec3, f64) {
        let (q, n, inv_pdf) = object_sample(self.kind, u);
        let m = self.world_from_object_f64();
        let normal_from_object = m.matrix3.inverse().transpose();
        let nw = normal_from_object * n;
        // Nanson's formula: a patch of object area dA covers |det M| |M^-T n| dA in the world.
        let scale = m.matrix3.determinant().abs() * nw.length();
        (m.transform_point3(q), nw.normalize(), inv_pdf * scale)
    }

    /// The first hit of the world ray o + t d with t > 0, as (t, unit outward normal), computed
    /// in double precision by methods independent of the kernels' (closed forms for the plane,
    /// disc and cone; conservative marching on a distance bound, then bisection, for the torus
    /// and the superellipsoid). `Err(margin)` means a miss, with the smallest distance bound
    /// seen along the ray (so a test can skip rays that pass within rounding of the surface).
    pub fn intersect_reference(&self, o: DVec3, d: DVec3) -> Result<(f64, DVec3), f64> {
        let m = self.world_from_object_f64();
        let inv = m.inverse();
        let (oo, od) = (inv.transform_point3(o), inv.transform_vector3(d));
        let (t, n) = object_intersect_reference(self.kind, oo, od)?;
        Ok((t, (m.matrix3.inverse().transpose() * n).normalize()))
    }

    /// A smallest distance bound of a world point to the surface, in object units (0 on it).
    pub fn object_distance_bound(&self, p: DVec3) -> f64 {
        let q = self.world_from_object_f64().inverse().transform_point3(p);
        distance_bound(self.kind, q).abs()
    }

    /// The unit outward world normal at the object point of world point p (which should lie on
    /// the surface), in double precision.
    pub fn normal_at(&self, p: DVec3) -> DVec3 {
        let m = self.world_from_object_f64();
        let q = m.inverse().transform_point3(p);
        let n = match self.kind {
            AnalyticKind::Cone { r0, r1, height } => {
                let phi = q.x.atan2(q.z);
                DVec3::new(height as f64 * phi.sin(), -(r1 - r0) as f64, height as f64 * phi.cos())
            }
            kind => object_normal_f64(kind, q),
        };
        (m.matrix3.inverse().transpose() * n).normalize()
    }

    /// Largest angle (radians) by which the normal turns when p moves by 1e-5 object units along
    /// an axis: large near a superellipsoid's edges or a cone's apex, where a normal computed
    /// from a point rounded to float precision may point anywhere nearby.
    pub fn normal_sensitivity(&self, p: DVec3) -> f64 {
        let m = self.world_from_object_f64();
        let n = self.normal_at(p);
        [DVec3::X, DVec3::Y, DVec3::Z]
            .iter()
            .map(|&axis| self.normal_at(p + m.matrix3 * (axis * 1e-5)).dot(n).clamp(-1.0, 1.0).acos())
            .fold(0.0, f64::max)
    }

    /// Object-space distance of a world point from the shape's rim (a disc's circles, a cone's
    /// end circles), infinite for shapes without one: rays this close to a rim may hit or miss
    /// by rounding.
    pub fn rim_distance(&self, p: DVec3) -> f64 {
        let q = self.world_from_object_f64().inverse().transform_point3(p);
        let rho = (q.x * q.x + q.z * q.z).sqrt();
        match self.kind {
            AnalyticKind::Disc { radius, inner_radius } => {
                let edge = (rho - radius as f64).abs();
                if inner_radius > 0.0 {
                    edge.min((rho - inner_radius as f64).abs())
                } else {
                    edge
                }
            }
            AnalyticKind::Cone { height, .. } => q.y.abs().min((q.y - height as f64).abs()),
            _ => f64::INFINITY,
        }
    }

    /// How deep (object units, by the distance bound) the world ray o + t d goes into the shape
    /// for t within `window` of `t`: about 0 or less for a ray that only touches the surface
    /// there, which rounding may count as a hit or a miss. Infinite for planes and discs.
    pub fn local_depth(&self, o: DVec3, d: DVec3, t: f64, window: f64) -> f64 {
        if matches!(self.kind, AnalyticKind::Plane | AnalyticKind::Disc { .. }) {
            return f64::INFINITY;
        }
        let inv = self.world_from_object_f64().inverse();
        let steps = 4000;
        (0..=steps)
            .map(|i| {
                let s = (t - window + 2.0 * window * i as f64 / steps as f64).max(0.0);
                -distance_bound(self.kind, inv.transform_point3(o + s * d))
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// How deep the world ray o + t d (t > 0) goes into a torus or superellipsoid, by its
    /// distance bound sampled finely along the chord of the bounding sphere (object units; <= 0
    /// for a miss). A ray that goes in by less than rounding may hit or miss.
    pub fn penetration(&self, o: DVec3, d: DVec3) -> f64 {
        let inv = self.world_from_object_f64().inverse();
        let (o, d) = (inv.transform_point3(o), inv.transform_vector3(d).normalize());
        let radius = match self.kind {
            AnalyticKind::Torus { major, minor } => (major + minor) as f64,
            AnalyticKind::Superellipsoid { .. } => 3f64.sqrt(),
            _ => return f64::INFINITY,
        };
        let tc = -o.dot(d);
        let m2 = (o + tc * d).length_squared();
        if m2 >= radius * radius {
            return 0.0;
        }
        let half = (radius * radius - m2).sqrt();
        let (start, end) = ((tc - half).max(0.0), tc + half);
        let steps = 20_000;
        (0..=steps)
            .map(|i| -distance_bound(self.kind, o + (start + (end - start) * i as f64 / steps as f64) * d))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Triangles approximating the surface, `segments` around and proportionally across, with
    /// the outward winding; none for the plane.
    pub fn tessellate(&self, segments: usize) -> Vec<[Vec3; 3]> {
        let (nu, nv) = match self.kind {
            AnalyticKind::Plane => return Vec::new(),
            AnalyticKind::Disc { .. } | AnalyticKind::Cone { .. } => (segments, segments / 4),
            AnalyticKind::Torus { .. } => (segments, segments / 2),
            AnalyticKind::Superellipsoid { .. } => (segments, segments / 2),
        };
        let nv = nv.max(1);
        let point = |i: usize, j: usize| -> Vec3 {
            let (u, v) = (i as f64 / nu as f64, j as f64 / nv as f64);
            let q = object_grid_point(self.kind, u, v);
            self.world_from_object.transform_point3(q.as_vec3())
        };
        let mirrored = self.world_from_object.matrix3.determinant() < 0.0;
        let mut out = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let (a, b, c, d) = (point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
                for t in [[a, b, c], [a, c, d]] {
                    let t = if mirrored { [t[0], t[2], t[1]] } else { t };
                    let area = (t[1] - t[0]).cross(t[2] - t[0]).length();
                    if area > 1e-12 {
                        out.push(t);
                    }
                }
            }
        }
        out
    }
}

/// A point of the grid (u, v) in [0, 1]^2 over the object surface whose cells, with corners
/// in the order (i, j), (i+1, j), (i+1, j+1), (i, j+1), wind outward. The superellipsoid uses
/// its own parametric form (POV-Ray's), not the kernels' radial map, so a tessellation test
/// compares two different descriptions of the same surface.
fn object_grid_point(kind: AnalyticKind, u: f64, v: f64) -> DVec3 {
    let phi = 2.0 * PI * (u - 0.5);
    match kind {
        AnalyticKind::Plane => DVec3::ZERO,
        AnalyticKind::Disc { radius, inner_radius } => {
            let rho = radius as f64 - v * (radius - inner_radius) as f64;
            DVec3::new(rho * phi.sin(), 0.0, rho * phi.cos())
        }
        AnalyticKind::Cone { r0, r1, height } => {
            let rho = r0 as f64 + (r1 - r0) as f64 * v;
            DVec3::new(rho * phi.sin(), v * height as f64, rho * phi.cos())
        }
        AnalyticKind::Torus { major, minor } => {
            let psi = 2.0 * PI * (v - 0.5);
            let rho = major as f64 + minor as f64 * psi.cos();
            DVec3::new(rho * phi.sin(), minor as f64 * psi.sin(), rho * phi.cos())
        }
        AnalyticKind::Superellipsoid { e, n } => {
            // x = c(eta)^n c(omega)^e, y = c(eta)^n s(omega)^e, z = s(eta)^n, eta from the south
            // pole (v = 0) to the north pole, omega around z.
            let signed_pow = |x: f64, p: f64| x.signum() * x.abs().powf(p);
            let eta = PI * (v - 0.5);
            let omega = 2.0 * PI * u;
            let (ce, se) = (signed_pow(eta.cos(), n as f64), signed_pow(eta.sin(), n as f64));
            DVec3::new(ce * signed_pow(omega.cos(), e as f64), ce * signed_pow(omega.sin(), e as f64), se)
        }
    }
}

/// The superellipsoid's gauge h (homogeneous of degree 1, h = 1 on the surface) and its
/// gradient, in double precision.
fn gauge(e: f64, n: f64, p: DVec3) -> (f64, DVec3) {
    let (a, b) = (2.0 / e, 2.0 / n);
    let rho = (p.x.abs().powf(a) + p.y.abs().powf(a)).powf(1.0 / a);
    let h = (rho.powf(b) + p.z.abs().powf(b)).powf(1.0 / b);
    if h == 0.0 {
        return (0.0, DVec3::Z);
    }
    let hr = (rho / h).powf(b - 1.0);
    let ratio = |x: f64| if rho > 0.0 { (x.abs() / rho).powf(a - 1.0) * x.signum() } else { 0.0 };
    let grad = DVec3::new(hr * ratio(p.x), hr * ratio(p.y), (p.z.abs() / h).powf(b - 1.0) * p.z.signum());
    (h, grad)
}

/// Object point, unit object normal and 1/pdf by object area of the sample (u, v).
fn object_sample(kind: AnalyticKind, u: [f64; 2]) -> (DVec3, DVec3, f64) {
    let phi = 2.0 * PI * u[1];
    match kind {
        AnalyticKind::Plane => (DVec3::ZERO, DVec3::Y, f64::INFINITY),
        AnalyticKind::Disc { radius, inner_radius } => {
            let (r, ri) = (radius as f64, inner_radius as f64);
            let rho = (ri * ri + u[0] * (r * r - ri * ri)).sqrt();
            (DVec3::new(rho * phi.sin(), 0.0, rho * phi.cos()), DVec3::Y, PI * (r * r - ri * ri))
        }
        AnalyticKind::Cone { r0, r1, height } => {
            let (r0, r1, h) = (r0 as f64, r1 as f64, height as f64);
            let v = u[0] * (r0 + r1) / (r0 + (r0 * r0 + u[0] * (r1 * r1 - r0 * r0)).sqrt());
            let rho = r0 + (r1 - r0) * v;
            let slant = (h * h + (r1 - r0) * (r1 - r0)).sqrt();
            let n = DVec3::new(h * phi.sin(), -(r1 - r0), h * phi.cos()) / slant;
            (DVec3::new(rho * phi.sin(), v * h, rho * phi.cos()), n, PI * (r0 + r1) * slant)
        }
        AnalyticKind::Torus { major, minor } => {
            let (big, small) = (major as f64, minor as f64);
            let theta = 2.0 * PI * u[0];
            let n = DVec3::new(phi.cos() * theta.sin(), phi.sin(), phi.cos() * theta.cos());
            let q = DVec3::new(big * theta.sin(), 0.0, big * theta.cos()) + small * n;
            (q, n, 4.0 * PI * PI * small * (big + small * phi.cos()))
        }
        AnalyticKind::Superellipsoid { e, n } => {
            let z = 1.0 - 2.0 * u[0];
            let s = (1.0 - z * z).max(0.0).sqrt();
            let w = DVec3::new(s * phi.cos(), s * phi.sin(), z);
            let (h, grad) = gauge(e as f64, n as f64, w);
            let r = 1.0 / h;
            (w * r, grad.normalize(), 4.0 * PI * grad.length() * r * r * r)
        }
    }
}

/// A signed lower bound on the distance of object point p to the surface (or, for the plane,
/// disc and cone, their exact signed distance to the infinite surface they lie in): negative
/// inside closed shapes.
fn distance_bound(kind: AnalyticKind, p: DVec3) -> f64 {
    match kind {
        AnalyticKind::Plane | AnalyticKind::Disc { .. } => p.y,
        AnalyticKind::Cone { r0, r1, height } => {
            let (r0, r1, h) = (r0 as f64, r1 as f64, height as f64);
            let slant = (h * h + (r1 - r0) * (r1 - r0)).sqrt();
            let rho = (p.x * p.x + p.z * p.z).sqrt();
            (h * (rho - r0) - (r1 - r0) * p.y) / slant
        }
        AnalyticKind::Torus { major, minor } => {
            let rho = (p.x * p.x + p.z * p.z).sqrt();
            ((rho - major as f64).powi(2) + p.y * p.y).sqrt() - minor as f64
        }
        AnalyticKind::Superellipsoid { e, n } => {
            // The shape holds the octahedron |x| + |y| + |z| <= 1 when e, n <= 2, so its support
            // planes are at least 1/sqrt(3) from the centre and |grad h| <= sqrt(3): the gauge
            // changes by at most sqrt(3) per unit of length.
            let (h, _) = gauge(e as f64, n as f64, p);
            (h - 1.0) / 3f64.sqrt()
        }
    }
}

/// Double-precision intersection in object space (see `Analytic::intersect_reference`).
fn object_intersect_reference(kind: AnalyticKind, o: DVec3, d: DVec3) -> Result<(f64, DVec3), f64> {
    match kind {
        AnalyticKind::Plane | AnalyticKind::Disc { .. } => {
            let t = -o.y / d.y;
            let p = o + t * d;
            let inside = match kind {
                AnalyticKind::Disc { radius, inner_radius } => {
                    let rho = (p.x * p.x + p.z * p.z).sqrt();
                    rho >= inner_radius as f64 && rho <= radius as f64
                }
                _ => true,
            };
            if t > 0.0 && t.is_finite() && inside {
                Ok((t, DVec3::Y))
            } else {
                Err(f64::INFINITY)
            }
        }
        AnalyticKind::Cone { r0, r1, height } => {
            let (r0, r1, h) = (r0 as f64, r1 as f64, height as f64);
            let k = (r1 - r0) / h;
            let a = d.x * d.x + d.z * d.z - k * k * d.y * d.y;
            let rho0 = r0 + k * o.y;
            let b = 2.0 * (o.x * d.x + o.z * d.z - k * rho0 * d.y);
            let c = o.x * o.x + o.z * o.z - rho0 * rho0;
            let disc = b * b - 4.0 * a * c;
            if disc < 0.0 {
                return Err(f64::INFINITY);
            }
            let mut roots = if a.abs() < 1e-300 {
                vec![-c / b]
            } else {
                vec![(-b - disc.sqrt()) / (2.0 * a), (-b + disc.sqrt()) / (2.0 * a)]
            };
            roots.sort_by(f64::total_cmp);
            for t in roots {
                let p = o + t * d;
                if t > 0.0 && p.y >= 0.0 && p.y <= h {
                    let phi = p.x.atan2(p.z);
                    let n = DVec3::new(h * phi.sin(), -(r1 - r0), h * phi.cos()).normalize();
                    return Ok((t, n));
                }
            }
            Err(f64::INFINITY)
        }
        AnalyticKind::Torus { .. } | AnalyticKind::Superellipsoid { .. } => march(kind, o, d),
    }
}

/// The first root of the distance bound along the ray inside the shape's bounding sphere, by
/// steps no longer than the bound (which cannot step over the surface), then bisection.
fn march(kind: AnalyticKind, o: DVec3, d: DVec3) -> Result<(f64, DVec3), f64> {
    let len = d.length();
    let dn = d / len;
    let radius = match kind {
        AnalyticKind::Torus { major, minor } => (major + minor) as f64,
        _ => 3f64.sqrt(),
    };
    let tc = -o.dot(dn);
    let m2 = (o + tc * dn).length_squared();
    if m2 >= radius * radius {
        return Err(m2.sqrt() - radius);
    }
    let half = (radius * radius - m2).sqrt();
    let (mut s, end) = ((tc - half).max(0.0), tc + half);
    let f = |s: f64| distance_bound(kind, o + s * dn);
    let start_sign = f(s).signum();
    let mut margin = f64::INFINITY;
    // Steps of at least 1e-9 of the radius: a ray that stays closer to the surface than that
    // for its whole length is reported as a miss with a tiny margin (the test skips those).
    let min_step = 1e-9 * radius;
    let (mut steps, mut prev) = (0, s);
    while s < end + min_step && steps < 2_000_000 {
        let v = f(s);
        margin = margin.min(v.abs());
        if v.signum() != start_sign || v == 0.0 {
            // Bisect the last step down to double precision.
            let (mut lo, mut hi) = (prev, s);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                let fm = f(mid);
                if fm.signum() == start_sign && fm != 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Ok((hi / len, object_normal_f64(kind, o + hi * dn)));
        }
        prev = s;
        s += v.abs().max(min_step);
        steps += 1;
    }
    Err(margin)
}

/// Unit outward normal of the torus or superellipsoid at object point p, in double precision.
fn object_normal_f64(kind: AnalyticKind, p: DVec3) -> DVec3 {
    match kind {
        AnalyticKind::Torus { major, .. } => {
            let rho = (p.x * p.x + p.z * p.z).sqrt();
            let ring = DVec3::new(p.x, 0.0, p.z) * (major as f64 / rho);
            (p - ring).normalize()
        }
        AnalyticKind::Superellipsoid { e, n } => gauge(e as f64, n as f64, p).1.normalize(),
        _ => DVec3::Y,
    }
}

/// The axis-aligned box around the box (lo, hi) moved by `m`: its eight corners moved. Shapes,
/// instances and the editor's solid view all bound their transformed boxes with it.
pub fn transformed_box(m: &Affine3A, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let mut out = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for corner in 0..8 {
        let c = Vec3::new(
            if corner & 1 == 0 { lo.x } else { hi.x },
            if corner & 2 == 0 { lo.y } else { hi.y },
            if corner & 4 == 0 { lo.z } else { hi.z },
        );
        let p = m.transform_point3(c);
        out = (out.0.min(p), out.1.max(p));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(kind: AnalyticKind) -> Analytic {
        Analytic { kind, world_from_object: Affine3A::IDENTITY }
    }

    #[test]
    fn areas_match_closed_forms() {
        let pi = std::f32::consts::PI;
        let cases = [
            (AnalyticKind::Disc { radius: 2.0, inner_radius: 1.0 }, pi * 3.0, 1e-6),
            (AnalyticKind::Cone { r0: 1.0, r1: 1.0, height: 2.0 }, 2.0 * pi * 2.0, 1e-6),
            (AnalyticKind::Cone { r0: 1.0, r1: 0.0, height: 1.0 }, pi * 2f32.sqrt(), 1e-6),
            (AnalyticKind::Torus { major: 2.0, minor: 0.5 }, 4.0 * pi * pi * 2.0 * 0.5, 1e-6),
            // e = n = 1 is the unit sphere.
            (AnalyticKind::Superellipsoid { e: 1.0, n: 1.0 }, 4.0 * pi, 1e-6),
            // e = n = 2 is the octahedron |x| + |y| + |z| = 1: 8 equilateral faces of side sqrt 2;
            // its edges are kinks, which the midpoint rule resolves to 0.6%.
            (AnalyticKind::Superellipsoid { e: 2.0, n: 2.0 }, 8.0 * 3f32.sqrt() / 4.0 * 2.0, 1e-2),
        ];
        for (kind, expected, tolerance) in cases {
            let a = shape(kind).area();
            println!("{kind:?}: area {a} (closed form {expected})");
            assert!((a - expected).abs() <= tolerance * expected, "{kind:?}: {a} vs {expected}");
        }
        // A scale of 2 along x doubles a disc's area (it becomes an ellipse).
        let stretched = Analytic {
            kind: AnalyticKind::Disc { radius: 1.0, inner_radius: 0.0 },
            world_from_object: Affine3A::from_scale(Vec3::new(2.0, 1.0, 1.0)),
        };
        assert!((stretched.area() - 2.0 * pi).abs() < 1e-4);
    }

    #[test]
    fn reference_hits_a_torus_where_the_closed_form_says() {
        // Along the x axis from far away: the outer equator at x = R + r.
        let t = shape(AnalyticKind::Torus { major: 2.0, minor: 0.5 });
        let (hit, n) = t.intersect_reference(DVec3::new(10.0, 0.0, 0.0), DVec3::new(-1.0, 0.0, 0.0)).unwrap();
        assert!((hit - 7.5).abs() < 1e-9 && (n - DVec3::X).length() < 1e-9, "{hit} {n}");
        // Down the axis: through the hole.
        assert!(t.intersect_reference(DVec3::new(0.0, 5.0, 0.0), DVec3::new(0.0, -1.0, 0.0)).is_err());
    }
}
