//! Camera rays, light sampling and specular scattering; twin of `shaders/shading.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

use super::rng::{rand1, rand2};
use super::trace::trace_ray;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Light;

/// Primary ray direction through film position (sx, sy) in [-1, 1]^2, sy = +1 at the top row.
pub fn camera_direction(s: &SceneView, sx: f32, sy: f32) -> Vec3 {
    let f = s.frame;
    (Vec3::from(f.camera_forward) + sx * Vec3::from(f.camera_right) + sy * Vec3::from(f.camera_up)).normalize()
}

/// Geometric normal at `x` of primitive `i`: triangle winding normal, sphere outward normal.
pub fn primitive_normal(s: &SceneView, i: u32, x: Vec3) -> Vec3 {
    let p = &s.primitives[i as usize];
    if p.kind == PRIMITIVE_SPHERE {
        return (x - Vec3::from(p.p0)).normalize();
    }
    (Vec3::from(p.p1) - Vec3::from(p.p0)).cross(Vec3::from(p.p2) - Vec3::from(p.p0)).normalize()
}

/// Orthonormal basis around unit `n` (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
pub fn onb(n: Vec3) -> (Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let c = n.x * n.y * a;
    (Vec3::new(1.0 + s * n.x * n.x * a, s * c, -s * n.x), Vec3::new(c, s + n.y * n.y * a, -n.y))
}

/// Cosine-distributed direction around unit `n` (Malley's method): pdf cos(theta) / pi.
pub fn cosine_direction(n: Vec3, u: [f32; 2]) -> Vec3 {
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let (t, b) = onb(n);
    (r * phi.cos() * t + r * phi.sin() * b + (1.0 - u[0]).max(0.0).sqrt() * n).normalize()
}

/// Uniform direction on the unit sphere.
pub fn sphere_direction(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let rho = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3::new(rho * phi.cos(), rho * phi.sin(), z)
}

/// A point on light `l`, uniform by area (Turk 1990 for triangles), and the light's normal
/// there; a point light gives its position and a zero normal.
pub fn sample_light_point(l: &Light, u: [f32; 2]) -> (Vec3, Vec3) {
    match l.kind {
        LIGHT_TRIANGLE => {
            let su = u[0].sqrt();
            let b0 = 1.0 - su;
            let b1 = u[1] * su;
            let (p0, p1, p2) = (Vec3::from(l.p0), Vec3::from(l.p1), Vec3::from(l.p2));
            (b0 * p0 + b1 * p1 + (1.0 - b0 - b1) * p2, (p1 - p0).cross(p2 - p0).normalize())
        }
        LIGHT_SPHERE => {
            let n = sphere_direction(u);
            (Vec3::from(l.p0) + l.p1[0] * n, n)
        }
        _ => (Vec3::from(l.p0), Vec3::ZERO),
    }
}

/// Index of the light whose cdf interval holds `u`: lights are picked in proportion to power.
pub fn pick_light(s: &SceneView, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, s.frame.light_count - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if u < s.lights[mid as usize].cdf {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// GLSL's `reflect`: `d` mirrored about the plane of unit normal `n`.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * n.dot(d) * n
}

/// Radiance reflected at `x` toward the viewer from one sampled light: a one-sample estimate of
/// direct light for a Lambertian surface of albedo `albedo`; `n` faces the viewer. Counts the
/// shadow ray it casts in `rays`.
#[allow(clippy::too_many_arguments)] // the kernel's signature, kept identical
pub fn direct_light(
    s: &SceneView,
    x: Vec3,
    n: Vec3,
    albedo: Vec3,
    stream: u32,
    sample: u32,
    dim: u32,
    rays: &mut u32,
) -> Vec3 {
    let f = s.frame;
    if f.light_count == 0 {
        return Vec3::ZERO;
    }
    let li = pick_light(s, rand1(stream, sample, f.seed, dim + RNG_LIGHT_PICK));
    let l = &s.lights[li as usize];
    let u = rand2(stream, sample, f.seed, dim + RNG_LIGHT_U);
    let (target, ln) = sample_light_point(l, u);
    let to_light = target - x;
    let dist2 = to_light.dot(to_light);
    let dist = dist2.sqrt();
    let wi = to_light / dist;
    let cos_x = n.dot(wi);
    if cos_x <= 0.0 {
        return Vec3::ZERO;
    }
    // Point light: E = I cos / d^2. Area light: L cos cos' / d^2 times area (uniform-area pdf).
    let mut geometry = cos_x / dist2;
    if l.kind != LIGHT_POINT {
        let cos_l = -ln.dot(wi);
        if cos_l <= 0.0 {
            return Vec3::ZERO;
        }
        geometry *= cos_l * l.area;
    }
    // The shadow ray runs from the offset origin to the sampled point itself: aiming along wi from
    // the offset origin would meet the light's plane early at grazing angles.
    let origin = x + n * f.ray_epsilon;
    let to_target = target - origin;
    let shadow_length = to_target.length();
    *rays += 1;
    let (blocker, _) =
        trace_ray(s.nodes, s.primitives, origin, to_target / shadow_length, shadow_length - f.ray_epsilon, true);
    if blocker != NO_LIGHT {
        return Vec3::ZERO;
    }
    albedo * (1.0 / PI) * Vec3::from(l.radiance) * (geometry / l.pick_probability)
}

/// Unpolarised Fresnel reflectance for a ray meeting the interface with `cos_i > 0`, going from
/// index `eta_i` into `eta_t`; returns (reflectance, cos_t), reflectance 1 under total internal
/// reflection.
pub fn fresnel_dielectric(cos_i: f32, eta_i: f32, eta_t: f32) -> (f32, f32) {
    let eta = eta_i / eta_t;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// Scatters direction `d` at a smooth dielectric of index `ior` hit at `x` (`nf` faces the
/// incoming ray; `front`: the ray arrives from outside): reflection or refraction, chosen with
/// the Fresnel probability against `u` (weight 1). Returns the new origin (offset to the new
/// direction's side) and direction.
pub fn dielectric_scatter(s: &SceneView, x: Vec3, nf: Vec3, front: bool, ior: f32, u: f32, d: Vec3) -> (Vec3, Vec3) {
    let (eta_i, eta_t) = if front { (1.0, ior) } else { (ior, 1.0) };
    let cos_i = -d.dot(nf);
    let (fr, cos_t) = fresnel_dielectric(cos_i, eta_i, eta_t);
    if u < fr {
        (x + nf * s.frame.ray_epsilon, reflect(d, nf))
    } else {
        let eta = eta_i / eta_t;
        (x - nf * s.frame.ray_epsilon, (eta * d + (eta * cos_i - cos_t) * nf).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_matches_known_values() {
        // Normal incidence on glass: ((1.5 - 1) / (1.5 + 1))^2 = 0.04.
        let (f, cos_t) = fresnel_dielectric(1.0, 1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-6 && (cos_t - 1.0).abs() < 1e-6);
        // Brewster's angle, atan(1.5): p-polarised reflectance vanishes, so F = rs^2 / 2.
        let theta = 1.5f32.atan();
        let (f, _) = fresnel_dielectric(theta.cos(), 1.0, 1.5);
        assert!((f - 0.0739).abs() < 1e-3, "{f}");
        // Total internal reflection beyond the critical angle asin(1/1.5) = 41.8 degrees.
        assert_eq!(fresnel_dielectric(45f32.to_radians().cos(), 1.5, 1.0).0, 1.0);
    }
}
