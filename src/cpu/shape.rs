//! Shapes: one match per operation (intersect, hit record, sample); twin of `shaders/shape.glsl`.

use std::f32::consts::PI;

use glam::{Mat3, Vec2, Vec3, Vec4};

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
    /// How far rays leaving this point start off the surface (scene units): the scene's
    /// `ray_epsilon` for triangles and spheres, a multiple of the point's own size for the
    /// analytic shapes (`SHAPE_EPSILON_SCALE`).
    pub eps: f32,
    /// Smooth triangles: Hanika's shift of the origin of rays that leave to its side
    /// (`triangle_smooth`); zero for every other shape.
    pub shift: Vec3,
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

/// Distance to the first surface of primitive `i` along o + t d with t in (t_min, t_max), or
/// infinity.
pub fn shape_intersect(s: &SceneView, i: u32, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> f32 {
    let p = &s.primitives[i as usize];
    match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_SPHERE => ray_sphere(o, d, Vec3::from(p.p0), p.p1[0], t_min, t_max),
        PRIMITIVE_TRIANGLE => ray_triangle(o, d, Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2), t_min, t_max),
        _ => analytic_intersect(s, p, o, d, t_min, t_max),
    }
}

// Analytic shapes (plane, disc, cone, torus, superellipsoid): intersected in their object space.

/// An affine map stored as the rows of a 3x4 matrix, applied to a point.
pub fn affine_point(m: &[f32], x: Vec3) -> Vec3 {
    Vec3::new(
        m[0] * x.x + m[1] * x.y + m[2] * x.z + m[3],
        m[4] * x.x + m[5] * x.y + m[6] * x.z + m[7],
        m[8] * x.x + m[9] * x.y + m[10] * x.z + m[11],
    )
}

/// The linear part of an affine map stored as rows, applied to a vector.
pub fn affine_vector(m: &[f32], v: Vec3) -> Vec3 {
    Vec3::new(
        m[0] * v.x + m[1] * v.y + m[2] * v.z,
        m[4] * v.x + m[5] * v.y + m[6] * v.z,
        m[8] * v.x + m[9] * v.y + m[10] * v.z,
    )
}

/// The transposed linear part applied to v: with `object_from_world` this takes an object
/// normal to the world (normals transform by the inverse transpose).
pub fn affine_transpose_vector(m: &[f32], v: Vec3) -> Vec3 {
    Vec3::new(m[0], m[1], m[2]) * v.x + Vec3::new(m[4], m[5], m[6]) * v.y + Vec3::new(m[8], m[9], m[10]) * v.z
}

/// The infinite plane y = 0.
pub fn ray_plane(o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> f32 {
    let t = -o.y / d.y;
    if t > t_min && t < t_max {
        t
    } else {
        f32::INFINITY
    }
}

/// The disc (annulus) of y = 0 with |(x, z)| in [inner, radius].
pub fn ray_disc(o: Vec3, d: Vec3, radius: f32, inner: f32, t_min: f32, t_max: f32) -> f32 {
    let t = ray_plane(o, d, t_min, t_max);
    let (x, z) = (o.x + t * d.x, o.z + t * d.z);
    let r2 = x * x + z * z;
    if r2 <= radius * radius && r2 >= inner * inner {
        t
    } else {
        f32::INFINITY
    }
}

/// The side of the truncated cone of radius r0 at y = 0 and r1 at y = h (a cylinder when they
/// are equal). The quadratic is set up at the point of the ray closest to the cone's centre (as
/// Haines et al. do for spheres), so its coefficients stay small however far the origin is, and
/// solved in the form that never subtracts nearly equal numbers (Press et al., Numerical
/// Recipes 5.6).
#[allow(clippy::too_many_arguments)] // the kernel's signature, kept identical
pub fn ray_cone(o: Vec3, d: Vec3, r0: f32, r1: f32, h: f32, t_min: f32, t_max: f32) -> f32 {
    let c = Vec3::new(0.0, 0.5 * h, 0.0);
    let ts = (c - o).dot(d) / d.dot(d);
    let p = o + ts * d;
    let rb = r0.max(r1);
    if (p - c).length_squared() > rb * rb + 0.25 * h * h {
        return f32::INFINITY;
    }
    let k = (r1 - r0) / h;
    let rho = r0 + k * p.y;
    let a = d.x * d.x + d.z * d.z - k * k * d.y * d.y;
    let b = 2.0 * (p.x * d.x + p.z * d.z - k * rho * d.y);
    let cc = p.x * p.x + p.z * p.z - rho * rho;
    let disc = b * b - 4.0 * a * cc;
    if disc < 0.0 {
        return f32::INFINITY;
    }
    let sq = disc.sqrt();
    let q = -0.5 * (b + if b >= 0.0 { sq } else { -sq });
    let (mut s0, mut s1) = (q / a, cc / q);
    if s0 > s1 {
        (s0, s1) = (s1, s0);
    }
    let (t0, y0) = (ts + s0, p.y + s0 * d.y);
    if t0 > t_min && t0 < t_max && y0 >= 0.0 && y0 <= h {
        return t0;
    }
    let (t1, y1) = (ts + s1, p.y + s1 * d.y);
    if t1 > t_min && t1 < t_max && y1 >= 0.0 && y1 <= h {
        return t1;
    }
    f32::INFINITY
}

/// (value, derivative) at x of lead x^4 + c.w x^3 + c.z x^2 + c.y x + c.x (Horner).
pub fn poly4(lead: f32, c: Vec4, x: f32) -> (f32, f32) {
    let f = (((lead * x + c.w) * x + c.z) * x + c.y) * x + c.x;
    let df = ((4.0 * lead * x + 3.0 * c.w) * x + 2.0 * c.z) * x + c.y;
    (f, df)
}

/// The root of the polynomial in [a, b] when its values at a and b differ in sign, else
/// `none`: Newton steps that fall back to bisection whenever they leave the bracket, which
/// shrinks every step (at most `TORUS_ROOT_STEPS`).
pub fn poly_root_in(lead: f32, c: Vec4, a: f32, b: f32, none: f32) -> f32 {
    let fa = poly4(lead, c, a).0;
    let fb = poly4(lead, c, b).0;
    if (fa < 0.0) == (fb < 0.0) {
        return none;
    }
    let (mut lo, mut hi) = (a, b);
    let mut x = 0.5 * (a + b);
    for _ in 0..TORUS_ROOT_STEPS {
        let (f, df) = poly4(lead, c, x);
        if (f < 0.0) == (fa < 0.0) {
            lo = x;
        } else {
            hi = x;
        }
        let mut next = x - f / df;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let done = (next - x).abs() <= 1e-7;
        x = next;
        if done {
            break;
        }
    }
    x
}

/// The torus (|p|^2 + R^2 - r^2)^2 = 4 R^2 (x^2 + z^2). The quartic is set up in units of the
/// bounding sphere's radius R + r from the ray's point closest to the centre, so its variable
/// runs over the chord [-1, 1] and its coefficients stay near 1 (Haines et al.'s trick, which
/// keeps the far-away rays of a camera as accurate as near ones). Its real roots are isolated
/// by those of its derivatives (Yuksel 2022, "High-Performance Polynomial Root Finding for
/// Graphics"): the roots of the quadratic f'' split the chord into pieces where f' is monotone,
/// the roots of f' found there split it into pieces where f is monotone, and each piece holds
/// at most one root of f, found by safeguarded Newton. No root is lost to a bad starting point,
/// and a grazing ray's pair of nearby roots is either found or truly absent to float precision.
///
/// The pieces and their roots come from the whole chord, whatever t_min and t_max (which only
/// skip pieces): a search restarted at one root finds the next one exactly, never the same one
/// again, which the CSG walk (`cpu/csg.rs`) relies on.
#[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must read as a miss, as in the kernel
pub fn ray_torus(o: Vec3, d: Vec3, big_r: f32, small_r: f32, t_min: f32, t_max: f32) -> f32 {
    let scale = big_r + small_r;
    let len = d.length();
    let dn = d / len;
    let tc = -o.dot(dn);
    let p = (o + tc * dn) / scale;
    let m2 = p.dot(p);
    // The chord runs to a sphere 0.1% larger than the bounding one: the outer equator touches
    // the bounding sphere, and a ray leaving there would end its chord on a root, whose sign
    // rounding may hide.
    let reach = TORUS_CHORD * TORUS_CHORD;
    if m2 >= reach {
        return f32::INFINITY;
    }
    let hi = (reach - m2).sqrt();
    let lo = -hi;
    if !((tc + scale * hi) / len > t_min && (tc + scale * lo) / len < t_max) {
        return f32::INFINITY;
    }
    let (br, sr) = (big_r / scale, small_r / scale);
    let g = m2 + br * br - sr * sr;
    let k = p.dot(dn);
    let four_r2 = 4.0 * br * br;
    let c = Vec4::new(
        g * g - four_r2 * (p.x * p.x + p.z * p.z),
        4.0 * k * g - 2.0 * four_r2 * (p.x * dn.x + p.z * dn.z),
        4.0 * k * k + 2.0 * g - four_r2 * (dn.x * dn.x + dn.z * dn.z),
        4.0 * k,
    );
    // Roots of f'' = 12 x^2 + 6 c.w x + 2 c.z, clamped into the chord.
    let (qa, qb, qc) = (12.0, 6.0 * c.w, 2.0 * c.z);
    let disc = qb * qb - 4.0 * qa * qc;
    let (mut x1, mut x2) = (lo, lo);
    if disc > 0.0 {
        let sq = disc.sqrt();
        let q = -0.5 * (qb + if qb >= 0.0 { sq } else { -sq });
        let (ra, rb) = (q / qa, qc / q);
        x1 = ra.min(rb).clamp(lo, hi);
        x2 = ra.max(rb).clamp(lo, hi);
    }
    // Seven searches in one loop (one copy of `poly_root_in` in the kernel): the roots of
    // f' = 4 x^3 + 3 c.w x^2 + 2 c.z x + c.y between those of f'' (or a piece's start), then
    // the first root of f after t_min, piece by piece between them. Pieces wholly before t_min
    // or after t_max are not searched.
    let dc = Vec4::new(c.y, 2.0 * c.z, 3.0 * c.w, 4.0);
    let mut e = [lo, x1, x2];
    let mut t = f32::INFINITY;
    for k in 0..7 {
        let derivative = k < 3;
        let (a, b) = if derivative {
            ([lo, x1, x2][k], [x1, x2, hi][k])
        } else {
            ([lo, e[0], e[1], e[2]][k - 3], [e[0], e[1], e[2], hi][k - 3])
        };
        let none = if derivative { a } else { f32::INFINITY };
        let search = derivative || ((tc + scale * b) / len > t_min && (tc + scale * a) / len < t_max);
        let r = if search {
            poly_root_in(if derivative { 0.0 } else { 1.0 }, if derivative { dc } else { c }, a, b, none)
        } else {
            none
        };
        if derivative {
            e[k] = r;
        }
        let tk = (tc + scale * r) / len;
        if !derivative && r != f32::INFINITY && tk > t_min {
            t = tk;
            break;
        }
    }
    if t < t_max {
        t
    } else {
        f32::INFINITY
    }
}

/// x^y for x >= 0 as GLSL computes it, with 0^y = 0 for y > 0 and 0^0 = 1 (x is clamped to a
/// tiny positive number so that the log is finite).
pub fn safe_pow(x: f32, y: f32) -> f32 {
    (y * x.max(1e-30).log2()).exp2()
}

/// The superellipsoid's gauge h(p) (homogeneous of degree 1, 1 on the surface, convex when both
/// exponents are at most 2) and its gradient. `ex` = (2/e, e/2, 2/n, n/2). Written with ratios
/// of at most 1 raised to the powers, so that no power overflows or loses everything to
/// underflow: rho = max(|x|,|y|) (1 + (min/max)^(2/e))^(e/2), and likewise h from rho and |z|.
pub fn superellipsoid_gauge(p: Vec3, ex: Vec4) -> (f32, Vec3) {
    let a = p.abs();
    let m = a.x.max(a.y);
    let rho = m * safe_pow(1.0 + safe_pow(a.x.min(a.y) / m.max(1e-30), ex.x), ex.y);
    let big = rho.max(a.z);
    let h = big * safe_pow(1.0 + safe_pow(rho.min(a.z) / big.max(1e-30), ex.z), ex.w);
    let (hs, rs) = (h.max(1e-30), rho.max(1e-30));
    let hr = safe_pow(rho / hs, ex.z - 1.0);
    let sign = |v: f32| {
        if v > 0.0 {
            1.0
        } else if v < 0.0 {
            -1.0
        } else {
            0.0
        }
    };
    let grad = Vec3::new(
        hr * safe_pow(a.x / rs, ex.x - 1.0) * sign(p.x),
        hr * safe_pow(a.y / rs, ex.x - 1.0) * sign(p.y),
        safe_pow(a.z / hs, ex.z - 1.0) * sign(p.z),
    );
    (h, grad)
}

/// POV-Ray's superellipsoid inside [-1, 1]^3. Along a ray, h - 1 is a convex function (both
/// exponents at most 2), so the ray crosses the surface at most twice, and Newton's method
/// started outside the surface climbs monotonically to the nearest root and never steps over
/// it; a step that leaves the box (or a slope that turns upward) proves there is no root: no
/// holes at silhouettes and no missed thin parts, in at most 2 `SUPERELLIPSOID_STEPS` steps. The
/// gauge grows linearly (not as |x|^(2/e)), so even boxy shapes converge in a few steps.
///
/// The entry is sought from the box's near side, the exit from its far side, whatever t_min
/// and t_max: the two roots do not depend on them, so a search restarted at the entry finds the
/// exit exactly (the CSG walk, `cpu/csg.rs`, relies on it). A ray that starts outside the
/// surface heading away from it (a shadow ray leaving it) is told apart by one evaluation.
#[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN must read as a miss, as in the kernel
pub fn ray_superellipsoid(o: Vec3, d: Vec3, ex: Vec4, t_min: f32, t_max: f32) -> f32 {
    // The box is grown by 1e-3 so that its entry point lies clearly outside even a boxy shape,
    // whose faces fill the unit box's faces to float precision.
    let inv = d.recip();
    let ta = (Vec3::splat(-SUPERELLIPSOID_BOX) - o) * inv;
    let tb = (Vec3::splat(SUPERELLIPSOID_BOX) - o) * inv;
    let t_in = ta.min(tb).max_element();
    let t_out = ta.max(tb).min_element();
    if !(t_in < t_out && t_out > t_min && t_in < t_max) {
        return f32::INFINITY;
    }
    if t_min > t_in {
        // Past both roots (convexity): the searches below stop within the tolerance of the
        // surface, so a margin of twice it keeps this shortcut from hiding a root they find.
        let (h, g) = superellipsoid_gauge(o + t_min * d, ex);
        if h - 1.0 > 2.0 * SUPERELLIPSOID_TOLERANCE && g.dot(d) >= 0.0 {
            return f32::INFINITY;
        }
    }
    // One loop for both searches (one copy of the gauge's code in the kernel): the entry, and
    // when it lies before t_min the exit. The entry search always starts the loop, so it gets
    // the same turns (and the same root) every time; the exit gets what it leaves.
    let p = o + t_in * d;
    let span = t_out - t_in;
    let (mut s, mut forward, mut t) = (0.0f32, true, f32::INFINITY);
    for _ in 0..2 * SUPERELLIPSOID_STEPS {
        let (h, g) = superellipsoid_gauge(p + s * d, ex);
        let (phi, slope) = (h - 1.0, g.dot(d));
        if phi <= SUPERELLIPSOID_TOLERANCE {
            t = t_in + s;
            if !forward || t > t_min {
                break;
            }
            (forward, s) = (false, span);
            continue;
        }
        if if forward { slope >= 0.0 } else { slope <= 0.0 } {
            break;
        }
        s -= phi / slope;
        if !(s >= 0.0 && s <= span) {
            break;
        }
    }
    if t > t_min && t < t_max {
        t
    } else {
        f32::INFINITY
    }
}

/// Distance along o + t d to analytic primitive `p`, intersected in its object space (the ray
/// moved by `object_from_world`; t is unchanged since d is not renormalised).
pub fn analytic_intersect(s: &SceneView, p: &Primitive, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> f32 {
    let a = p.data as usize;
    let ow = &s.shape_data[a + SHAPE_DATA_OBJECT_FROM_WORLD as usize..];
    let (oo, od) = (affine_point(ow, o), affine_vector(ow, d));
    match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_PLANE => ray_plane(oo, od, t_min, t_max),
        PRIMITIVE_DISC => ray_disc(oo, od, p.p0[0], p.p0[1], t_min, t_max),
        PRIMITIVE_CONE => ray_cone(oo, od, p.p0[0], p.p0[1], p.p0[2], t_min, t_max),
        PRIMITIVE_TORUS => ray_torus(oo, od, p.p0[0], p.p0[1], t_min, t_max),
        PRIMITIVE_SUPERELLIPSOID => {
            ray_superellipsoid(oo, od, Vec4::new(p.p0[0], p.p0[1], p.p0[2], p.p1[0]), t_min, t_max)
        }
        _ => f32::INFINITY,
    }
}

/// The surface fields of `h` at world point `x` of analytic primitive `p`: x is moved into
/// object space and projected onto the surface there (exactly for planes, discs and tori,
/// radially for cones and superellipsoids), so the hit point's error no longer grows with the
/// ray's length, and the offset of rays leaving it scales with the shape (`Hit::eps`).
pub fn analytic_surface(s: &SceneView, p: &Primitive, x: Vec3, wants_uv: bool, h: &mut Hit) {
    let a = p.data as usize;
    let ow = &s.shape_data[a + SHAPE_DATA_OBJECT_FROM_WORLD as usize..];
    let wo = &s.shape_data[a + SHAPE_DATA_WORLD_FROM_OBJECT as usize..];
    let size = s.shape_data[a + SHAPE_DATA_SIZE as usize];
    let mut q = affine_point(ow, x);
    let mut n = Vec3::Y;
    let (uv, dqdu, dqdv): (Vec2, Vec3, Vec3);
    // Longitude about +y, as for spheres: u = 0.5 toward +z, growing toward +x.
    let rho = (q.x * q.x + q.z * q.z).sqrt();
    let (sin_phi, cos_phi) = if rho > 0.0 { (q.x / rho, q.z / rho) } else { (0.0, 1.0) };
    let u_around = 0.5 + q.x.atan2(q.z) * (0.5 / PI);
    match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_PLANE => {
            q.y = 0.0;
            (uv, dqdu, dqdv) = (Vec2::new(q.x, -q.z), Vec3::X, Vec3::NEG_Z);
        }
        PRIMITIVE_DISC => {
            q.y = 0.0;
            let (r, ri) = (p.p0[0], p.p0[1]);
            uv = Vec2::new(u_around, (r - rho) / (r - ri));
            dqdu = 2.0 * PI * Vec3::new(q.z, 0.0, -q.x);
            dqdv = -(r - ri) * Vec3::new(sin_phi, 0.0, cos_phi);
        }
        PRIMITIVE_CONE => {
            let (r0, r1, height) = (p.p0[0], p.p0[1], p.p0[2]);
            let y = q.y.clamp(0.0, height);
            let radius = r0 + (r1 - r0) * (y / height);
            q = Vec3::new(radius * sin_phi, y, radius * cos_phi);
            n = Vec3::new(height * sin_phi, -(r1 - r0), height * cos_phi);
            uv = Vec2::new(u_around, y / height);
            dqdu = 2.0 * PI * Vec3::new(q.z, 0.0, -q.x);
            dqdv = Vec3::new((r1 - r0) * sin_phi, height, (r1 - r0) * cos_phi);
        }
        PRIMITIVE_TORUS => {
            let (big_r, small_r) = (p.p0[0], p.p0[1]);
            let out = Vec3::new(sin_phi, 0.0, cos_phi);
            let ring = big_r * out;
            let w = (q - ring).normalize_or(out);
            q = ring + small_r * w;
            n = w;
            let cos_psi = w.dot(out);
            uv = Vec2::new(u_around, 0.5 + w.y.atan2(cos_psi) * (0.5 / PI));
            dqdu = 2.0 * PI * Vec3::new(q.z, 0.0, -q.x);
            dqdv = 2.0 * PI * small_r * Vec3::new(-w.y * sin_phi, cos_psi, -w.y * cos_phi);
        }
        _ => {
            let ex = Vec4::new(p.p0[0], p.p0[1], p.p0[2], p.p1[0]);
            let (hq, _) = superellipsoid_gauge(q, ex);
            q /= hq.max(1e-30);
            let (_, g) = superellipsoid_gauge(q, ex);
            n = g;
            // Longitude and latitude of the direction from the centre, z the pole (POV-Ray's
            // axis of the n exponent): sphere_uv's +y pole gets z through the cyclic swap
            // (x, y, z) -> (y, z, x), which keeps the frame right-handed.
            let r = q.length();
            let w = q / r;
            let (suv, dwdu, dwdv) = sphere_uv(Vec3::new(w.y, w.z, w.x));
            let (dwdu, dwdv) = (Vec3::new(dwdu.z, dwdu.x, dwdu.y), Vec3::new(dwdv.z, dwdv.x, dwdv.y));
            uv = suv;
            // The surface point along direction w is w / h(w): its derivative is r (dw - q (grad h . dw)).
            dqdu = r * (dwdu - q * g.dot(dwdu));
            dqdv = r * (dwdv - q * g.dot(dwdv));
        }
    }
    h.p = affine_point(wo, q);
    h.ng = affine_transpose_vector(ow, n).normalize();
    if wants_uv {
        h.uv = uv;
        h.dpdu = affine_vector(wo, dqdu);
        h.dpdv = affine_vector(wo, dqdv);
        if h.dpdu.cross(h.dpdv).length() == 0.0 {
            (h.dpdu, h.dpdv) = onb(h.ng);
        }
    }
    h.eps = SHAPE_EPSILON_SCALE * (h.p.abs().max_element() + size);
}

/// A point of analytic primitive `p` for the uniform numbers `u`, in the world, with 1/pdf by
/// world area: discs and cones uniformly by area, tori uniformly in their two angles, and
/// superellipsoids along a uniform direction from the centre (pdf cos / (4 pi r^2) by area);
/// the transform's stretch of the area at the point (Nanson's formula) divides the density.
pub fn analytic_sample(s: &SceneView, p: &Primitive, u: [f32; 2]) -> (Vec3, f32) {
    let a = p.data as usize;
    let ow = &s.shape_data[a + SHAPE_DATA_OBJECT_FROM_WORLD as usize..];
    let wo = &s.shape_data[a + SHAPE_DATA_WORLD_FROM_OBJECT as usize..];
    let det = s.shape_data[a + SHAPE_DATA_DET as usize];
    let phi = 2.0 * PI * u[1];
    let (sin_phi, cos_phi) = phi.sin_cos();
    let (q, n, inv_pdf) = match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_DISC => {
            let (r, ri) = (p.p0[0], p.p0[1]);
            let rho = (ri * ri + u[0] * (r * r - ri * ri)).sqrt();
            (Vec3::new(rho * sin_phi, 0.0, rho * cos_phi), Vec3::Y, PI * (r * r - ri * ri))
        }
        PRIMITIVE_CONE => {
            let (r0, r1, height) = (p.p0[0], p.p0[1], p.p0[2]);
            // The inverse of the cdf (r0 v + (r1 - r0) v^2 / 2) / ((r0 + r1) / 2), rationalised
            // so that equal radii (a cylinder) and r0 = 0 need no special case.
            let den = r0 + (r0 * r0 + u[0] * (r1 * r1 - r0 * r0)).sqrt();
            let v = if den > 0.0 { u[0] * (r0 + r1) / den } else { 0.0 };
            let rho = r0 + (r1 - r0) * v;
            let slant = (height * height + (r1 - r0) * (r1 - r0)).sqrt();
            let n = Vec3::new(height * sin_phi, -(r1 - r0), height * cos_phi) / slant;
            (Vec3::new(rho * sin_phi, v * height, rho * cos_phi), n, PI * (r0 + r1) * slant)
        }
        PRIMITIVE_TORUS => {
            let (big_r, small_r) = (p.p0[0], p.p0[1]);
            let (sin_theta, cos_theta) = (2.0 * PI * u[0]).sin_cos();
            let n = Vec3::new(cos_phi * sin_theta, sin_phi, cos_phi * cos_theta);
            let q = big_r * Vec3::new(sin_theta, 0.0, cos_theta) + small_r * n;
            (q, n, 4.0 * PI * PI * small_r * (big_r + small_r * cos_phi))
        }
        _ => {
            let ex = Vec4::new(p.p0[0], p.p0[1], p.p0[2], p.p1[0]);
            let w = sphere_direction(u);
            let (hw, g) = superellipsoid_gauge(w, ex);
            let r = 1.0 / hw;
            (w * r, g, 4.0 * PI * g.length() * r * r * r)
        }
    };
    let nw = affine_transpose_vector(ow, n);
    (affine_point(wo, q), inv_pdf * det * nw.length() / n.length())
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

/// The shading normal of smooth triangle `p` at `x` (barycentrics `b` of vertices `v`): its unit
/// vertex normals (`TriangleShading`) interpolated (Phong shading), or `ng` where they cancel or
/// would turn below the triangle. Sets `h.shift`, the shadow-terminator fix of Hanika (2021,
/// "Hacking the shadow terminator", Ray Tracing Gems II ch. 4): x projected onto the tangent
/// plane of each vertex (only where that moves it outward, so concave parts stay put), those
/// three points mixed by the barycentrics. Rays leaving from x + shift start on the curved surface
/// the normals describe, so the neighbouring flat facets of a low-poly mesh no longer shadow
/// points whose shading normal faces the light. dpdu and dpdv are projected onto the shading
/// normal's tangent plane (as pbrt-v4 does for its shading frame), so bump and normal maps and
/// anisotropic roughness bend around the smooth normal.
pub fn triangle_smooth(s: &SceneView, p: &Primitive, x: Vec3, b: Vec3, v: [Vec3; 3], h: &mut Hit) -> Vec3 {
    let a = (p.data + TRIANGLE_DATA_NORMALS) as usize;
    let d = &s.shape_data[a..a + 9];
    let (n0, n1, n2) = (Vec3::new(d[0], d[1], d[2]), Vec3::new(d[3], d[4], d[5]), Vec3::new(d[6], d[7], d[8]));
    let n = b.x * n0 + b.y * n1 + b.z * n2;
    let len = n.length();
    let mut n = if len > 0.0 { n / len } else { h.ng };
    // NaN-safe: a normal below the triangle, or none at all, falls back to the flat one.
    if n.dot(h.ng).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        n = h.ng;
    }
    h.shift = -(b.x * (x - v[0]).dot(n0).min(0.0) * n0
        + b.y * (x - v[1]).dot(n1).min(0.0) * n1
        + b.z * (x - v[2]).dot(n2).min(0.0) * n2);
    h.dpdu -= n * n.dot(h.dpdu);
    h.dpdv -= n * n.dot(h.dpdv);
    n
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
    let smooth = p.kind & PRIMITIVE_FLAG_SMOOTH != 0;
    let mut ns = Vec3::ZERO;
    h.eps = s.frame.ray_epsilon;
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
        PRIMITIVE_TRIANGLE => {
            let (p0, p1, p2) = (Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2));
            let (e1, e2) = (p1 - p0, p2 - p0);
            h.ng = e1.cross(e2).normalize();
            if wants_uv || smooth {
                // Barycentrics of x from the normal equations of x - p0 = b1 e1 + b2 e2.
                let v = x - p0;
                let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
                let (d20, d21) = (v.dot(e1), v.dot(e2));
                let inv = 1.0 / (d00 * d11 - d01 * d01);
                let b1 = (d11 * d20 - d01 * d21) * inv;
                let b2 = (d00 * d21 - d01 * d20) * inv;
                if wants_uv {
                    let uv = triangle_uvs(s, p);
                    h.uv = (1.0 - b1 - b2) * uv[0] + b1 * uv[1] + b2 * uv[2];
                    (h.dpdu, h.dpdv) = triangle_derivatives([p0, p1, p2], uv, h.ng);
                }
                if smooth {
                    ns = triangle_smooth(s, p, x, Vec3::new(1.0 - b1 - b2, b1, b2), [p0, p1, p2], &mut h);
                }
            }
        }
        _ => analytic_surface(s, p, x, wants_uv, &mut h),
    }
    h.ns = if smooth { ns } else { h.ng };
    // A leaf on the subtracted side of a CSG difference: the solid lies on its other side.
    if p.kind & PRIMITIVE_FLAG_CSG_FLIP != 0 {
        h.ng = -h.ng;
        h.ns = -h.ns;
        h.dpdv = -h.dpdv;
    }
    h
}

/// The hit record of the ray o + t d on primitive `i`, or on an instance's primitive (`i` a
/// hit name, see `cpu::instance`): filled at the object point, then moved to the world.
pub fn shape_hit(s: &SceneView, i: u32, o: Vec3, d: Vec3, t: f32) -> Hit {
    let x = o + t * d;
    let Some((k, prim)) = super::instance::split_hit(s, i) else {
        return shape_surface(s, i, x);
    };
    let rec = super::instance::record(s, k);
    let mut h = shape_surface(s, prim, affine_point(super::instance::object_from_world(rec), x));
    super::instance::to_world(rec, x, s.primitives[prim as usize].kind & PRIMITIVE_KIND_MASK, &mut h);
    h.prim = i;
    h
}

/// A point on primitive `i` for the uniform numbers `u`, as a hit record, and 1/pdf of such
/// points by area: triangles (Turk 1990) and spheres uniformly, so 1/pdf is their area; the
/// analytic shapes as `analytic_sample` says.
pub fn shape_sample(s: &SceneView, i: u32, u: [f32; 2]) -> (Hit, f32) {
    let p = &s.primitives[i as usize];
    let (x, inv_pdf) = match p.kind & PRIMITIVE_KIND_MASK {
        PRIMITIVE_SPHERE => {
            let r = p.p1[0];
            (Vec3::from(p.p0) + r * sphere_direction(u), 4.0 * PI * r * r)
        }
        PRIMITIVE_TRIANGLE => {
            let su = u[0].sqrt();
            let b0 = 1.0 - su;
            let b1 = u[1] * su;
            let (p0, p1, p2) = (Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2));
            (b0 * p0 + b1 * p1 + (1.0 - b0 - b1) * p2, 0.5 * (p1 - p0).cross(p2 - p0).length())
        }
        _ => analytic_sample(s, p, u),
    };
    (shape_surface(s, i, x), inv_pdf)
}

/// What 1/pdf a point of `shape_sample_from` carries.
#[derive(Clone, Copy, Debug)]
pub enum SampleDensity {
    /// 1/pdf by area (`shape_sample`).
    Area(f32),
    /// 1/pdf by solid angle seen from the point asked for: the solid angle sampled.
    SolidAngle(f32),
}

/// `shape_sample` as seen from `x`: a sphere seen from outside by the solid angle of the cap `x`
/// sees, any other shape, or a sphere from inside, by `shape_sample`.
pub fn shape_sample_from(s: &SceneView, i: u32, x: Vec3, u: [f32; 2]) -> (Hit, SampleDensity) {
    let p = &s.primitives[i as usize];
    if p.kind & PRIMITIVE_KIND_MASK == PRIMITIVE_SPHERE {
        if let Some((point, solid_angle)) = sphere_cap_point(Vec3::from(p.p0), p.p1[0], x, u) {
            return (shape_surface(s, i, point), SampleDensity::SolidAngle(solid_angle));
        }
    }
    let (h, inv_pdf) = shape_sample(s, i, u);
    (h, SampleDensity::Area(inv_pdf))
}

/// A point of the cap of the sphere (centre `c`, radius `r`) that `x` sees, drawn uniformly in
/// the cap's solid angle (pbrt-v4's `Sphere::Sample`, after Shirley's cone sampling), and the
/// cap's solid angle, 1/pdf; `None` where `x` is inside the sphere (the caller then samples by
/// area). Every sample from outside lands on a face `x` sees, where by area half of them fall
/// behind.
pub fn sphere_cap_point(c: Vec3, r: f32, x: Vec3, u: [f32; 2]) -> Option<(Vec3, f32)> {
    let to_c = c - x;
    let d2 = to_c.dot(to_c);
    if d2 <= 1.0001 * r * r {
        return None;
    }
    let sin2_max = r * r / d2;
    let sin_max = sin2_max.sqrt();
    let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
    let mut one_minus_cos_max = 1.0 - cos_max;
    let mut cos_t = (cos_max - 1.0) * u[0] + 1.0;
    let mut sin2_t = 1.0 - cos_t * cos_t;
    // A far, small sphere: 1 - cos_max cancels in single precision; its series instead.
    if sin2_max < 0.00068523 {
        sin2_t = sin2_max * u[0];
        cos_t = (1.0 - sin2_t).sqrt();
        one_minus_cos_max = 0.5 * sin2_max;
    }
    // The angle at the centre between x and the point whose direction from x makes angle t.
    let cos_a = sin2_t / sin_max + cos_t * (1.0 - sin2_t / sin2_max).max(0.0).sqrt();
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let z = to_c / d2.sqrt();
    let (t, b) = onb(z);
    let p = c - r * (sin_a * phi.cos() * t + sin_a * phi.sin() * b + cos_a * z);
    Some((p, 2.0 * PI * one_minus_cos_max))
}
