//! Camera rays, path vertices and direct light; twin of `shaders/shading.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::{bsdf_eval, Bsdf};
use super::light::{light_sample, pick_direct_light, receiver_normal};
use super::microfacet::mf_erfinv;
use super::rng::{qmc2, rand1};
use super::sampling::polygon_point;
use super::shape::Hit;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::FrameParams;

/// Where uniform `u` puts a camera sample along one axis of its pixel (0 to 1 is the pixel),
/// drawn from the reconstruction filter around the pixel's centre by inverting its cdf: filter
/// importance sampling, so every sample weighs 1 and the accumulation is a plain mean. The box
/// at its own size returns `u` itself.
pub fn filter_sample(f: &FrameParams, u: f32) -> f32 {
    let s = f.filter_scale;
    match f.pixel_filter {
        FILTER_TENT => 0.5 + s * if u < 0.5 { (2.0 * u).sqrt() - 1.0 } else { 1.0 - (2.0 - 2.0 * u).sqrt() },
        // The Gaussian's cdf inverted between its two truncation points.
        FILTER_GAUSSIAN => {
            0.5 + s
                * FILTER_GAUSSIAN_STDDEV
                * std::f32::consts::SQRT_2
                * mf_erfinv((2.0 * u - 1.0) * FILTER_GAUSSIAN_MASS)
        }
        _ if s == 1.0 => u,
        _ => 0.5 + s * (u - 0.5),
    }
}

/// The film point of a camera sample in its pixel, from the sample's uniform pair `u`.
pub fn film_offset(f: &FrameParams, u: [f32; 2]) -> [f32; 2] {
    [filter_sample(f, u[0]), filter_sample(f, u[1])]
}

/// The filter's value (normalised: it integrates to 1 along its axis) at `d` pixels from a
/// pixel's centre; [`filter_sample`] draws from it. Mitsuba's Gaussian also subtracts its value
/// at the radius (3.4e-4 of its peak), which this one leaves out.
pub fn filter_weight(f: &FrameParams, d: f32) -> f32 {
    let s = f.filter_scale;
    let x = d / s;
    let w = match f.pixel_filter {
        FILTER_TENT => (1.0 - x.abs()).max(0.0),
        FILTER_GAUSSIAN if x.abs() <= FILTER_GAUSSIAN_RADIUS => {
            FILTER_GAUSSIAN_NORM * (-x * x / (2.0 * FILTER_GAUSSIAN_STDDEV * FILTER_GAUSSIAN_STDDEV)).exp()
        }
        FILTER_GAUSSIAN => 0.0,
        _ => f32::from(u8::from(x.abs() < 0.5)),
    };
    w / s
}

/// How far from a pixel's centre the filter reaches, in pixels.
pub fn filter_radius(f: &FrameParams) -> f32 {
    f.filter_scale
        * match f.pixel_filter {
            FILTER_TENT => 1.0,
            FILTER_GAUSSIAN => FILTER_GAUSSIAN_RADIUS,
            _ => 0.5,
        }
}

/// Whether the filter is each pixel's own square: a film point then counts toward the one pixel
/// it lies in, whole.
pub fn filter_is_pixel(f: &FrameParams) -> bool {
    f.pixel_filter == FILTER_BOX && f.filter_scale == 1.0
}

/// The lens sample of a camera path: a pinhole draws none.
pub fn lens_sample(s: &SceneView, stream: u32, sample: u32) -> [f32; 2] {
    let f = s.frame;
    if f.lens_radius > 0.0 {
        qmc2(stream, sample, f.seed, RNG_PIXEL_Y)
    } else {
        [0.0; 2]
    }
}

/// Where lens sample `u` puts a ray's origin on the aperture, from its centre (`camera_ray`'s
/// thin lens, and light tracing's eye).
pub fn lens_offset(f: &FrameParams, u: [f32; 2]) -> Vec3 {
    let a = polygon_point(u, f.aperture_blades, f.aperture_rotation);
    let (right, up) = (Vec3::from(f.camera_right), Vec3::from(f.camera_up));
    a[0] * f.lens_radius * right.normalize() + a[1] * f.lens_radius * up.normalize()
}

/// Primary ray (origin, direction) through film position (sx, sy) in [-1, 1]^2, sy = +1 at the
/// top row, with lens sample `u` (see `FrameParams` and the `CAMERA_*` kinds).
pub fn camera_ray(s: &SceneView, sx: f32, sy: f32, u: [f32; 2]) -> (Vec3, Vec3) {
    let f = s.frame;
    let forward = Vec3::from(f.camera_forward);
    let right = Vec3::from(f.camera_right);
    let up = Vec3::from(f.camera_up);
    let mut o = Vec3::from(f.camera_position);
    if f.camera_kind == CAMERA_LATLONG {
        let phi = PI * sx;
        let theta = 0.5 * PI * sy;
        return (o, theta.cos() * (phi.sin() * right + phi.cos() * forward) + theta.sin() * up);
    }
    let mut d = if f.camera_kind == CAMERA_ORTHOGRAPHIC {
        o += sx * right + sy * up;
        forward
    } else {
        (forward + sx * right + sy * up).normalize()
    };
    // Thin lens: the ray from a point of the aperture aims where the pinhole ray meets the plane
    // in focus.
    if f.lens_radius > 0.0 {
        let focus = o + d * (f.focal_distance / d.dot(forward));
        o += lens_offset(f, u);
        d = (focus - o).normalize();
    }
    (o, d)
}

/// Origin of the ray that leaves `h` in a direction sampled from a lobe with `lobe_flags`:
/// offset off the surface to the side the ray goes (`wo`'s side for reflection, the other for
/// transmission) by the hit's own offset (`Hit::eps`), plus a smooth triangle's `Hit::shift`
/// when the ray leaves to the side the shift points to (the outside of the curved surface its
/// normals describe; toward the inside it would start the ray beyond the triangle).
///
/// The side is `wo`'s side of the shading normal `h.ns` (the geometric one but on smooth
/// triangles). A ray toward a light just above a smooth triangle's shading horizon may head below
/// its flat facet: judged by the facet, it would start under the mesh's skin without the shift
/// and be shadowed by the mesh itself, the dark terminator facets that the shift is there to
/// remove. From the shifted point on the curved surface it crosses only its own facet's plane,
/// which `trace_ray` skips.
pub fn offset_origin(h: &Hit, wo: Vec3, lobe_flags: u32) -> Vec3 {
    let nf = if wo.dot(h.ns) > 0.0 { h.ng } else { -h.ng };
    let side = if lobe_flags & BSDF_TRANSMISSION != 0 { -nf } else { nf };
    h.p + side * h.eps + if h.shift.dot(side) > 0.0 { h.shift } else { Vec3::ZERO }
}

/// The primitive that rays leaving a hit on primitive `i` skip: `i` itself when it is a smooth
/// triangle, else none (`NO_LIGHT`); see `trace_ray`.
pub fn ray_skip(s: &SceneView, i: u32) -> u32 {
    if s.primitives[super::instance::hit_primitive(s, i) as usize].kind & PRIMITIVE_FLAG_SMOOTH != 0 {
        i
    } else {
        NO_LIGHT
    }
}

/// The length of a shadow ray that is not cast: `trace_ray` meets nothing before it.
pub const NO_RAY: f32 = -1.0;

/// A shadow ray toward a point sampled on a light, and the radiance the light reflects at the
/// shading point toward `wo` through the estimate lobes of its BSDF if nothing blocks the ray: a
/// one-sample estimate of the direct light. `t_max` is `NO_RAY` when no ray is needed (no light,
/// a light picked with probability 0, or nothing to reflect).
pub struct ShadowRay {
    pub origin: Vec3,
    pub direction: Vec3,
    pub t_max: f32,
    pub unoccluded: Vec3,
    /// The vertex's shadow rays (see `LIGHT_GRID_ADAPTIVE`), and whether the picked light is
    /// adaptive (its rays' visibility is the pixel's history).
    pub rays: u32,
    pub adaptive: bool,
}

/// A light's sample numbers `u` moved into one cell of its POV-Ray grid (`Light::grid`; 0: `u`
/// as it is): cell (sample + a hash of the pixel) mod (n m), so each pixel's consecutive n m
/// samples visit every cell once, at a jittered point in it or at its centre.
pub fn grid_sample(grid: u32, u: [f32; 2], stream: u32, sample: u32) -> [f32; 2] {
    if grid == 0 {
        return u;
    }
    let (n, m) = (grid & 0xff, (grid >> 8) & 0xff);
    let k = sample.wrapping_add(stream.wrapping_mul(0x9E37_79B1)) % (n * m);
    let j = if grid & LIGHT_GRID_JITTER != 0 { u } else { [0.5, 0.5] };
    [((k % n) as f32 + j[0]) / n as f32, ((k / n) as f32 + j[1]) / m as f32]
}

/// Shadow ray `ray` of the vertex: every ray picks the same light. Toward an adaptive light, a
/// pixel found in a penumbra at sample `penumbra_since` casts one ray per cell from the first
/// sample of the light's next cycle of n m samples on (ray j of sample s takes the sequence's
/// entry s rays + j, so the rays visit every cell once); before that, one ray in the sample's
/// cell. The switch falls on a cycle's first sample and depends on earlier samples alone, so
/// every cycle of single rays visits each cell once and every sample of many rays is unbiased
/// by itself: the mean stays unbiased.
#[allow(clippy::too_many_arguments)]
pub fn direct_light_sample(
    s: &SceneView,
    h: &Hit,
    b: &Bsdf,
    wo: Vec3,
    stream: u32,
    sample: u32,
    dim: u32,
    penumbra_since: u32,
    ray: u32,
) -> ShadowRay {
    let f = s.frame;
    let mut none =
        ShadowRay { origin: h.p, direction: Vec3::Y, t_max: NO_RAY, unoccluded: Vec3::ZERO, rays: 1, adaptive: false };
    if f.light_count == 0 {
        return none;
    }
    let receiver = receiver_normal(b);
    let (light, pmf) = pick_direct_light(s, rand1(stream, sample, f.seed, dim + RNG_LIGHT_PICK), h.p, receiver);
    // A scene whose lights all give photons only picks none.
    if pmf <= 0.0 {
        return none;
    }
    let l = &s.lights[light as usize];
    // A scattering point in a homogeneous medium leaves point and spot lights to the camera
    // segment's equiangular sample (`render::radiance`).
    if b.kind == MATERIAL_PHASE && b.color1.y == 0.0 && (l.kind == LIGHT_POINT || l.kind == LIGHT_SPOT) {
        return none;
    }
    none.adaptive = l.grid & LIGHT_GRID_ADAPTIVE != 0;
    if none.adaptive {
        // An adaptive light has a grid of at least 2 cells (scene loading checks it).
        let cells = (l.grid & 0xff) * ((l.grid >> 8) & 0xff);
        if penumbra_since <= sample - sample % cells {
            none.rays = cells;
        }
    }
    let u = qmc2(stream, sample, f.seed, if ray == 0 { dim + RNG_LIGHT_U } else { RNG_ADAPTIVE_DOMAIN + ray });
    let ls = light_sample(s, l, h.p, grid_sample(l.grid, u, stream, sample.wrapping_mul(none.rays).wrapping_add(ray)));
    let fr = bsdf_eval(b, wo, ls.wi) * ls.weight;
    if fr == Vec3::ZERO {
        return none;
    }
    // The shadow ray runs from the offset origin to the sampled point itself: aiming along wi from
    // the offset origin would meet the light's plane early at grazing angles.
    let origin = offset_origin(h, ls.wi, BSDF_REFLECTION);
    let to_target = ls.p - origin;
    let shadow_length = to_target.length();
    ShadowRay {
        origin,
        direction: to_target / shadow_length,
        t_max: (shadow_length - ls.eps).max(0.0),
        // A medium's phase function has no cosine: it is per solid angle already.
        unoccluded: fr
            * (if b.kind == MATERIAL_PHASE { 1.0 } else { b.ns.dot(ls.wi).abs() } / (pmf * none.rays as f32)),
        rays: none.rays,
        adaptive: none.adaptive,
    }
}
