//! Lights behind one interface: pick by power, a light sample toward a point, a photon leaving a
//! light; twin of `shaders/light.glsl`.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::{material_emission, Bsdf};
use super::sampling::{cone_direction, cosine_direction, disc_point, onb};
use super::shape::{shape_sample, shape_sample_from, SampleDensity};
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::Light;

/// Index of the light whose cdf interval holds `u`: lights are picked in proportion to power,
/// among those that cast direct light (`photons` false: `cdf`) or emit photons (`photons` true:
/// `photon_cdf`). A light left out of a distribution has an empty interval and is never picked.
pub fn pick_light(s: &SceneView, u: f32, photons: bool) -> u32 {
    let (mut lo, mut hi) = (0u32, s.frame.light_count - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        let l = &s.lights[mid as usize];
        if u < (if photons { l.photon_cdf } else { l.cdf }) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

fn tree_word(s: &SceneView, w: u32) -> f32 {
    f32::from_bits(s.texture_data[w as usize])
}

fn tree_vec(s: &SceneView, w: u32) -> Vec3 {
    Vec3::new(tree_word(s, w), tree_word(s, w + 1), tree_word(s, w + 2))
}

/// A bound on the light that the lights under light-tree node `node` send to a point `x` of
/// normal `n` (zero in a medium): their power over the squared distance to their box, times the
/// cosine of the smallest angle between their emission cone and `x` as seen from anywhere in the
/// box, times the cosine of the smallest angle at `x` to the box (Conty and Kulla 2018, as
/// pbrt-v4's `LightBounds::Importance`; the squared distance is at least the box's half-diagonal
/// squared). Twin of `light_node_importance` in shaders/light.glsl.
pub fn light_node_importance(s: &SceneView, node: u32, x: Vec3, n: Vec3) -> f32 {
    let lo = tree_vec(s, node + LIGHT_NODE_MIN);
    let hi = tree_vec(s, node + LIGHT_NODE_MAX);
    let axis = tree_vec(s, node + LIGHT_NODE_AXIS);
    let power = tree_word(s, node + LIGHT_NODE_POWER);
    let cos_o = tree_word(s, node + LIGHT_NODE_COS_SPREAD);
    let to_x = x - 0.5 * (lo + hi);
    let d2 = to_x.dot(to_x);
    let half_diagonal = 0.5 * (hi - lo);
    let r2 = half_diagonal.dot(half_diagonal);
    // The box as seen from x: a cone of cos_b around the direction to its centre (the whole
    // sphere from inside its bounding sphere).
    let cos_b = if d2 <= r2 { -1.0 } else { (1.0 - r2 / d2).max(0.0).sqrt() };
    let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
    let w = if d2 > 0.0 { to_x / d2.sqrt() } else { Vec3::Z };
    let cos_w = axis.dot(w);
    let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
    let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
    // theta_x = max(0, theta_w - theta_o), then theta' = max(0, theta_x - theta_b).
    let (cos_x, sin_x) =
        if cos_w > cos_o { (1.0, 0.0) } else { (cos_w * cos_o + sin_w * sin_o, sin_w * cos_o - cos_w * sin_o) };
    let cos_p = if cos_x > cos_b { 1.0 } else { cos_x * cos_b + sin_x * sin_b };
    // Past the cone by the falloff, pi/2 (cos 0), nothing leaves.
    if cos_p <= 0.0 {
        return 0.0;
    }
    let mut importance = power * cos_p / d2.max(r2).max(1e-20);
    if n != Vec3::ZERO {
        let cos_i = w.dot(n).abs();
        let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        importance *= if cos_i > cos_b { 1.0 } else { cos_i * cos_b + sin_i * sin_b };
    }
    importance.max(0.0)
}

/// The light tree's share of direct-light selection; the infinite lights have the rest.
fn tree_share(s: &SceneView) -> f32 {
    tree_word(s, s.frame.light_tree + LIGHT_TREE_SHARE)
}

/// The light that casts direct light on point `x` of normal `n` (zero in a medium), and the
/// probability of that choice: (`NO_LIGHT`, 0) when none can. An infinite light is drawn by
/// power outside the tree's share; else a walk down the light tree, each step in proportion to
/// the children's importance (see `render::light_tree`).
pub fn pick_direct_light(s: &SceneView, u: f32, x: Vec3, n: Vec3) -> (u32, f32) {
    let base = s.frame.light_tree;
    if base == NO_LIGHT {
        return (NO_LIGHT, 0.0);
    }
    let share = tree_share(s);
    if u >= share {
        // The lights beside the tree (the infinite ones; every light under `light_sampler =
        // "power"`): their running probabilities cover the rest, [share, 1), searched for the
        // first that passes v.
        let v = (u - share) / (1.0 - share);
        let count = s.texture_data[(base + LIGHT_TREE_INFINITE_COUNT) as usize];
        if count == 0 {
            return (NO_LIGHT, 0.0);
        }
        let (mut lo, mut hi) = (0u32, count - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if v < tree_word(s, base + LIGHT_TREE_INFINITE + 2 * mid + 1) {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        let light = s.texture_data[(base + LIGHT_TREE_INFINITE + 2 * lo) as usize];
        return (light, (1.0 - share) * s.lights[light as usize].tree_probability);
    }
    let mut u = u / share;
    let mut pmf = share;
    let mut node = s.texture_data[(base + LIGHT_TREE_ROOT) as usize];
    for _ in 0..LIGHT_TREE_MAX_DEPTH {
        let child = s.texture_data[(node + LIGHT_NODE_CHILD) as usize];
        if child & LIGHT_NODE_LEAF != 0 {
            return (child & !LIGHT_NODE_LEAF, pmf);
        }
        let first = node + LIGHT_NODE_WORDS;
        let a = light_node_importance(s, first, x, n);
        let b = light_node_importance(s, child, x, n);
        if (a + b).is_nan() || a + b <= 0.0 {
            break;
        }
        let p = a / (a + b);
        if u < p {
            u = (u / p).min(ONE_MINUS_EPSILON);
            pmf *= p;
            node = first;
        } else {
            u = ((u - p) / (1.0 - p)).min(ONE_MINUS_EPSILON);
            pmf *= b / (a + b);
            node = child;
        }
    }
    (NO_LIGHT, 0.0)
}

/// The normal that light selection weighs a vertex's view of the lights with: the shading
/// normal, or zero at a medium's scattering point (light arrives from every side).
pub fn receiver_normal(b: &Bsdf) -> Vec3 {
    if b.kind == MATERIAL_PHASE {
        Vec3::ZERO
    } else {
        b.ns
    }
}

/// The largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 0.999_999_94;

/// The probability that `pick_direct_light` at `x` of normal `n` chooses light `i`: its trail
/// through the tree, step by step.
pub fn direct_light_pmf(s: &SceneView, i: u32, x: Vec3, n: Vec3) -> f32 {
    let l = &s.lights[i as usize];
    if l.tree_probability <= 0.0 {
        return 0.0;
    }
    let share = tree_share(s);
    if l.tree_trail == NO_LIGHT {
        return (1.0 - share) * l.tree_probability;
    }
    let mut pmf = share;
    let mut node = s.texture_data[(s.frame.light_tree + LIGHT_TREE_ROOT) as usize];
    for depth in 0..LIGHT_TREE_MAX_DEPTH {
        let child = s.texture_data[(node + LIGHT_NODE_CHILD) as usize];
        if child & LIGHT_NODE_LEAF != 0 {
            return pmf;
        }
        let first = node + LIGHT_NODE_WORDS;
        let a = light_node_importance(s, first, x, n);
        let b = light_node_importance(s, child, x, n);
        if (a + b).is_nan() || a + b <= 0.0 {
            return 0.0;
        }
        if (l.tree_trail >> depth) & 1 == 0 {
            pmf *= a / (a + b);
            node = first;
        } else {
            pmf *= b / (a + b);
            node = child;
        }
    }
    0.0
}

/// The cosine between a surface's geometric normal and `w` that its emission sees: emission
/// leaves where it is > 0, the front face of a one-sided emitter, either face of a two-sided one.
pub fn emitter_cosine(flags: u32, ng: Vec3, w: Vec3) -> f32 {
    let c = ng.dot(w);
    if flags & MATERIAL_FLAG_TWO_SIDED != 0 {
        c.abs()
    } else {
        c
    }
}

/// Intensity profile of point and spot lights along unit direction `w` (away from the light):
/// a smooth step (3t^2 - 2t^3, as pbrt-v4 and POV-Ray's `cubic_spline`) in cos from the outer
/// cone to the inner one, times cos^exponent (POV-Ray's tightness). A point light's cone is the
/// whole sphere, so its profile is 1.
pub fn spot_falloff(l: &Light, w: Vec3) -> f32 {
    let c = w.dot(Vec3::from(l.direction));
    let t = ((c - l.cos_outer) * l.falloff_scale).clamp(0.0, 1.0);
    let tight = if l.exponent > 0.0 { c.max(0.0).powf(l.exponent) } else { 1.0 };
    t * t * (3.0 - 2.0 * t) * tight
}

// The environment (`LIGHT_ENVIRONMENT`): a latitude-longitude image of radiance, its block at
// word `base` of the texture data (layout at `ENV_TEXELS`). Texel (i, j) covers the directions
// of polar angle theta in pi [j, j + 1] / H from +y and longitude phi in pi (2 [i, i + 1] / W - 1)
// around +y, phi = 0 toward -z, pi/2 toward +x, before the rotation about +y.

fn env_float(s: &SceneView, word: u32) -> f32 {
    f32::from_bits(s.texture_data[word as usize])
}

/// The direction of image position `uv` in [0, 1]^2, in world space.
pub fn env_direction(s: &SceneView, base: u32, uv: [f32; 2]) -> Vec3 {
    let theta = PI * uv[1];
    let phi = PI * (2.0 * uv[0] - 1.0);
    let local = Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos());
    let c = env_float(s, base + ENV_COS_ROTATION);
    let sn = env_float(s, base + ENV_SIN_ROTATION);
    Vec3::new(c * local.x + sn * local.z, local.y, c * local.z - sn * local.x)
}

/// The texel (column, row) that world direction `d` falls in.
pub fn env_texel(s: &SceneView, base: u32, d: Vec3) -> (u32, u32) {
    let w = s.texture_data[(base + ENV_WIDTH) as usize];
    let h = s.texture_data[(base + ENV_HEIGHT) as usize];
    let c = env_float(s, base + ENV_COS_ROTATION);
    let sn = env_float(s, base + ENV_SIN_ROTATION);
    let local = Vec3::new(c * d.x - sn * d.z, d.y, c * d.z + sn * d.x);
    let u = 0.5 * (local.x.atan2(-local.z) / PI + 1.0);
    let v = local.y.clamp(-1.0, 1.0).acos() / PI;
    (((u * w as f32) as u32).min(w - 1), ((v * h as f32) as u32).min(h - 1))
}

fn env_radiance_at(s: &SceneView, base: u32, (i, j): (u32, u32)) -> Vec3 {
    let k = base + ENV_TEXELS + 3 * (j * s.texture_data[(base + ENV_WIDTH) as usize] + i);
    Vec3::new(env_float(s, k), env_float(s, k + 1), env_float(s, k + 2))
}

/// Radiance of the environment of light `l` arriving along -`d` (`d` points away from the scene).
pub fn environment_radiance(s: &SceneView, l: &Light, d: Vec3) -> Vec3 {
    env_radiance_at(s, l.primitive, env_texel(s, l.primitive, d))
}

/// Radiance of the discs of distant lights that a ray leaving the scene along `d` meets. The
/// host puts the lights with a visible disc at the front of the list (see `render::prepare`),
/// each with its cone's solid angle in `area`, so the search stops at the first light without one.
pub fn distant_discs_radiance(s: &SceneView, d: Vec3) -> Vec3 {
    s.lights
        .iter()
        .take_while(|l| l.kind == LIGHT_DISTANT && l.area > 0.0)
        .filter(|l| d.dot(Vec3::from(l.direction)) <= -l.cos_outer)
        .map(|l| Vec3::from(l.intensity) / l.area)
        .sum()
}

/// Index of the interval [cdf[k], cdf[k + 1]) of the n + 1 values from `first` that holds `u`.
fn env_search(s: &SceneView, first: u32, n: u32, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, n - 1);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if env_float(s, first + mid) <= u {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    lo
}

/// A direction toward the environment of light `l`, drawn in proportion to luminance times
/// sin(theta) per texel (a piecewise-constant 2D distribution, pbrt's `Distribution2D`), and
/// the radiance from it divided by its solid-angle pdf: (direction, weight).
pub fn environment_sample(s: &SceneView, l: &Light, u: [f32; 2]) -> (Vec3, Vec3) {
    let base = l.primitive;
    let w = s.texture_data[(base + ENV_WIDTH) as usize];
    let h = s.texture_data[(base + ENV_HEIGHT) as usize];
    let marginal = base + ENV_TEXELS + 3 * w * h;
    let j = env_search(s, marginal, h, u[1]);
    let (m0, m1) = (env_float(s, marginal + j), env_float(s, marginal + j + 1));
    let row = marginal + h + 1 + j * (w + 1);
    let i = env_search(s, row, w, u[0]);
    let (c0, c1) = (env_float(s, row + i), env_float(s, row + i + 1));
    let uv = [
        (i as f32 + ((u[0] - c0) / (c1 - c0)).clamp(0.0, 1.0)) / w as f32,
        (j as f32 + ((u[1] - m0) / (m1 - m0)).clamp(0.0, 1.0)) / h as f32,
    ];
    let d = env_direction(s, base, uv);
    // pdf in (u, v) is W H (m1 - m0)(c1 - c0); the map to directions has Jacobian 2 pi^2 sin(theta).
    let sin_theta = (PI * uv[1]).sin();
    let pdf = (w * h) as f32 * (m1 - m0) * (c1 - c0) / (2.0 * PI * PI * sin_theta);
    let weight = if sin_theta > 0.0 && pdf > 0.0 { env_radiance_at(s, base, (i, j)) / pdf } else { Vec3::ZERO };
    (d, weight)
}

/// Light `l` as seen from `x`: the direction `wi` toward it, a point `p` to aim the shadow ray
/// at (beyond the scene for a distant light) and `weight`, the radiance arriving along -wi
/// divided by the solid-angle pdf of the sample (so the direct light is f |cos| weight / pick
/// probability).
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub p: Vec3,
    pub wi: Vec3,
    pub weight: Vec3,
    /// How far short of `p` a shadow ray stops: an area light's point's own offset (`Hit::eps`)
    /// over the cosine there, else the frame's `ray_epsilon`.
    pub eps: f32,
    /// Solid-angle density that multiple importance sampling weighs this sample with (before the
    /// pick probability; `light_pdf` gives the same number for a ray that meets the light):
    /// 0 for a light no ray can meet (point, spot, a distant light without a visible disc).
    pub pdf: f32,
    /// Cosine at the light between its normal and -wi (area lights; 1 for the others): what
    /// vertex connection and merging turns densities by area into densities by solid angle with.
    pub cos_l: f32,
}

/// The solid-angle density `light_sample` would have drawn direction `wi` with from a point
/// `dist` away, toward light `l` met by a ray (area lights: at a point of cosine `cos_l`
/// toward it). Area lights use their uniform density by area, 1 / `area`, whatever their shape's
/// sampler does: multiple importance sampling needs only that both strategies weigh a path by
/// the same function (the sample's value keeps the sampler's own pdf), and for triangles and
/// spheres it is exact.
pub fn light_pdf(s: &SceneView, l: &Light, wi: Vec3, dist: f32, cos_l: f32) -> f32 {
    match l.kind {
        LIGHT_AREA if cos_l > 0.0 && l.area > 0.0 => dist * dist / (cos_l * l.area),
        LIGHT_ENVIRONMENT => environment_pdf(s, l, wi),
        LIGHT_DISTANT if l.area > 0.0 => 1.0 / l.area,
        _ => 0.0,
    }
}

/// Solid-angle pdf of `environment_sample` drawing direction `d` (toward the environment).
pub fn environment_pdf(s: &SceneView, l: &Light, d: Vec3) -> f32 {
    let base = l.primitive;
    let w = s.texture_data[(base + ENV_WIDTH) as usize];
    let h = s.texture_data[(base + ENV_HEIGHT) as usize];
    let (i, j) = env_texel(s, base, d);
    let marginal = base + ENV_TEXELS + 3 * w * h;
    let row = marginal + h + 1 + j * (w + 1);
    let pm = env_float(s, marginal + j + 1) - env_float(s, marginal + j);
    let pc = env_float(s, row + i + 1) - env_float(s, row + i);
    let sin_theta = (1.0 - d.y * d.y).max(0.0).sqrt();
    if sin_theta <= 0.0 {
        return 0.0;
    }
    (w * h) as f32 * pm * pc / (2.0 * PI * PI * sin_theta)
}

pub fn light_sample(s: &SceneView, l: &Light, x: Vec3, u: [f32; 2]) -> LightSample {
    match l.kind {
        LIGHT_ENVIRONMENT => {
            let (wi, weight) = environment_sample(s, l, u);
            let beyond = (x - Vec3::from(l.position)).length() + 2.0 * l.radius;
            let pdf = environment_pdf(s, l, wi);
            LightSample { p: x + wi * beyond, wi, weight, eps: s.frame.ray_epsilon, pdf, cos_l: 1.0 }
        }
        LIGHT_AREA => {
            // `shape_sample_from`: a sphere seen from outside by its cap's solid angle, L over
            // the pdf by solid angle. Else by area (see `shape_sample` for the density): L cos' / d^2 over the
            // pdf by area. The MIS density stays `light_pdf`'s by area either way: the two
            // strategies weigh a path by the same function, and both reach exactly the faces x
            // sees.
            let (h, density) = shape_sample_from(s, l.primitive, x, u);
            let to_light = h.p - x;
            let dist2 = to_light.dot(to_light);
            let wi = to_light / dist2.sqrt();
            let m = &s.materials[h.material as usize];
            let cos_l = emitter_cosine(m.flags, h.ng, -wi);
            let jacobian = match density {
                SampleDensity::SolidAngle(solid_angle) => solid_angle,
                SampleDensity::Area(inv_pdf) => cos_l * inv_pdf / dist2,
            };
            let weight = if cos_l > 0.0 { material_emission(s, m, &h) * jacobian } else { Vec3::ZERO };
            // The shadow ray stops short of the point by its offset over the cosine there: a hit on
            // the light's own surface moves along a grazing ray by its error over that cosine.
            let pdf = light_pdf(s, l, wi, dist2.sqrt(), cos_l);
            LightSample { p: h.p, wi, weight, eps: h.eps / cos_l.max(1e-2), pdf, cos_l }
        }
        LIGHT_DISTANT => {
            // Uniform in the cone of directions; intensity holds radiance times the cone's solid angle.
            let wi = -cone_direction(Vec3::from(l.direction), l.cos_outer, u);
            let beyond = (x - Vec3::from(l.position)).length() + 2.0 * l.radius;
            let pdf = light_pdf(s, l, wi, 0.0, 0.0);
            LightSample {
                p: x + wi * beyond,
                wi,
                weight: Vec3::from(l.intensity),
                eps: s.frame.ray_epsilon,
                pdf,
                cos_l: 1.0,
            }
        }
        _ => {
            // Point and spot lights: I(w) / d^2.
            let p = Vec3::from(l.position);
            let to_light = p - x;
            let dist2 = to_light.dot(to_light);
            let wi = to_light / dist2.sqrt();
            let weight = Vec3::from(l.intensity) * (spot_falloff(l, -wi) / dist2);
            LightSample { p, wi, weight, eps: s.frame.ray_epsilon, pdf: 0.0, cos_l: 1.0 }
        }
    }
}

/// A photon leaving light `l`: (origin, direction, power before the division by the pick
/// probability and the path count). Area lights emit from a point drawn by `shape_sample` (their
/// power over that point's pdf by area) in a cosine-distributed direction (Lambertian); point and
/// spot lights uniformly in their cone, weighted by the spot's profile; distant lights from a
/// uniform point of the disc of the scene's bounding sphere that faces them, uniformly in their
/// cone of directions.
pub fn light_emit(s: &SceneView, l: &Light, u_pos: [f32; 2], u_dir: [f32; 2]) -> (Vec3, Vec3, Vec3) {
    let e = light_emission(s, l, u_pos, u_dir);
    (e.origin, e.direction, e.power)
}

/// A ray leaving a light (see `light_emit`) with the cosine at its origin between the light's
/// normal and the direction (area lights; 1 for the others).
pub struct Emission {
    pub origin: Vec3,
    pub direction: Vec3,
    pub power: Vec3,
    pub cos_l: f32,
}

pub fn light_emission(s: &SceneView, l: &Light, u_pos: [f32; 2], u_dir: [f32; 2]) -> Emission {
    let axis = Vec3::from(l.direction);
    match l.kind {
        LIGHT_AREA => {
            let (h, inv_pdf) = shape_sample(s, l.primitive, u_pos);
            let emitted = material_emission(s, &s.materials[h.material as usize], &h);
            // A two-sided emitter (cos_outer -1, see `light_record`) leaves by either face, each
            // half the time by the first number, the number stretched back over [0, 1).
            let (n, ud) = match (l.cos_outer < 0.0, u_dir[0] < 0.5) {
                (false, _) => (h.ng, u_dir),
                (true, true) => (h.ng, [2.0 * u_dir[0], u_dir[1]]),
                (true, false) => (-h.ng, [2.0 * u_dir[0] - 1.0, u_dir[1]]),
            };
            let direction = cosine_direction(n, ud);
            Emission {
                origin: h.p + n * h.eps,
                direction,
                power: (1.0 - l.cos_outer) * PI * inv_pdf * emitted,
                cos_l: direction.dot(n),
            }
        }
        LIGHT_DISTANT | LIGHT_ENVIRONMENT => {
            // The environment: a direction toward it, then a disc facing it, as for a distant light.
            let (axis, env_weight) = if l.kind == LIGHT_ENVIRONMENT {
                let (w, weight) = environment_sample(s, l, u_dir);
                (-w, weight)
            } else {
                (axis, Vec3::ZERO)
            };
            let (t, b) = onb(axis);
            let q = disc_point(u_pos);
            let (qx, qy) = (q[0] * l.radius, q[1] * l.radius);
            let origin = Vec3::from(l.position) - axis * l.radius + qx * t + qy * b;
            if l.kind == LIGHT_ENVIRONMENT {
                // Radiance over the direction's pdf, through the whole disc.
                let power = env_weight * (PI * l.radius * l.radius);
                return Emission { origin, direction: axis, power, cos_l: 1.0 };
            }
            let d = cone_direction(axis, l.cos_outer, u_dir);
            // Flux through the disc: radiance times solid angle times the projected disc area.
            let power = Vec3::from(l.intensity) * (PI * l.radius * l.radius * d.dot(axis));
            Emission { origin, direction: d, power, cos_l: 1.0 }
        }
        _ => {
            let d = cone_direction(axis, l.cos_outer, u_dir);
            let power = Vec3::from(l.intensity) * (2.0 * PI * (1.0 - l.cos_outer) * spot_falloff(l, d));
            Emission { origin: Vec3::from(l.position), direction: d, power, cos_l: 1.0 }
        }
    }
}
