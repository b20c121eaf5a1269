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
