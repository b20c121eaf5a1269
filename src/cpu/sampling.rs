//! Warps of uniform numbers to directions; twin of `shaders/sampling.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

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

/// GLSL's `reflect`: `d` mirrored about the plane of unit normal `n`.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * n.dot(d) * n
}

/// Uniform direction in the cone of unit `axis` and half-angle acos(`cos_max`): pdf
/// 1 / (2 pi (1 - cos_max)). `cos_max` = -1 gives the whole sphere, 1 the axis itself.
pub fn cone_direction(axis: Vec3, cos_max: f32, u: [f32; 2]) -> Vec3 {
    let z = 1.0 - u[0] * (1.0 - cos_max);
    let rho = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let (t, b) = onb(axis);
    rho * phi.cos() * t + rho * phi.sin() * b + z * axis
}

/// Uniform point on the unit disc (polar mapping).
pub fn disc_point(u: [f32; 2]) -> [f32; 2] {
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    [r * phi.cos(), r * phi.sin()]
}

/// Uniform point in the regular polygon of `corners` corners on the unit circle, the first at
/// angle `rotation` from +y toward +x; fewer than 3 corners mean the unit disc. u.x picks one
/// of the triangles (centre, corner k, corner k + 1) and, rescaled, the distance from the centre.
pub fn polygon_point(u: [f32; 2], corners: u32, rotation: f32) -> [f32; 2] {
    if corners < 3 {
        return disc_point(u);
    }
    let n = corners as f32;
    let k = (u[0] * n).floor().min(n - 1.0);
    let s = (u[0] * n - k).sqrt();
    let a0 = rotation + 2.0 * PI * k / n;
    let a1 = a0 + 2.0 * PI / n;
    [s * ((1.0 - u[1]) * a0.sin() + u[1] * a1.sin()), s * ((1.0 - u[1]) * a0.cos() + u[1] * a1.cos())]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean of `f` over a stratified grid of `n` x `n` points of the unit square.
    fn grid_mean(n: u32, mut f: impl FnMut([f32; 2]) -> f64) -> f64 {
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                sum += f([(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32]);
            }
        }
        sum / (n * n) as f64
    }

    #[test]
    fn cone_directions_stay_in_the_cone_with_uniform_cosine() {
        let axis = Vec3::new(0.3, -0.8, 0.52).normalize();
        let cos_max = 0.8f32;
        // Uniform in solid angle: cos is uniform on [cos_max, 1], mean (1 + cos_max) / 2.
        let mean = grid_mean(64, |u| {
            let d = cone_direction(axis, cos_max, u);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let c = d.dot(axis);
            assert!(c >= cos_max - 1e-6, "{c}");
            c as f64
        });
        assert!((mean - 0.9).abs() < 1e-4, "mean cos {mean}");
    }

    #[test]
    fn polygon_points_have_the_polygon_second_moment() {
        // A regular n-gon of circumradius 1 has E[r^2] = (1 + 2 cos^2(pi/n)) / 6; the disc 1/2.
        for (corners, expected) in [(0u32, 0.5), (4, 1.0 / 3.0), (6, (1.0 + 2.0 * 0.75) / 6.0)] {
            let mean = grid_mean(128, |u| {
                let p = polygon_point(u, corners, 0.3);
                let r2 = (p[0] * p[0] + p[1] * p[1]) as f64;
                assert!(r2 <= 1.0 + 1e-5);
                r2
            });
            println!("{corners} corners: E[r^2] {mean:.5}, expected {expected:.5}");
            assert!((mean - expected).abs() < 2e-3, "{corners} corners: E[r^2] {mean}, expected {expected}");
        }
    }
}
