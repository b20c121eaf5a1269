//! The light tree: a binary tree over the lights that cast direct light, so that a shading point
//! picks a light in proportion to a bound on what it can receive from each part of the scene
//! (Conty and Kulla 2018; pbrt-v4's `BVHLightSampler`), not in proportion to power alone. A
//! sun and a lamp, a sky dome and a bulb, or hundreds of small lamps each get their share where
//! they matter. Built here, flattened into the texture data (`LIGHT_TREE_*`, `LIGHT_NODE_*`),
//! walked by `pick_direct_light` and `direct_light_pmf` on both twins (shaders/light.glsl,
//! src/cpu/light.rs).
//!
//! Infinite lights (distant lights, the environment) have no position: they are chosen beside
//! the tree, among themselves by power, the tree taking the share one more infinite light would
//! (pbrt-v4's choice). A share from the root's importance against the infinite lights' power
//! was tried and lost: the root's bound over a street of lamps is loose, and the sky starved
//! (relMSE 2.2x on scenes/many-lights.toml at equal time). Photons and light paths, which
//! start with no shading point, keep the choice by power (`Light::cdf`, `photon_cdf`).

use std::f32::consts::PI;

use glam::Vec3;

use crate::layout::constants::*;
use crate::layout::Light;

/// What the tree knows of one light (or of a node's lights together): where it is, its power
/// and the cone its light leaves in.
#[derive(Clone, Copy, Debug)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    pub power: f32,
    pub cone: Cone,
}

/// The directions light leaves in: those within `spread` (radians) of `axis`, then a falloff of
/// up to pi/2 past them (Conty and Kulla's theta_e: a Lambertian surface's light leaves all of
/// its hemisphere; a spot is given as much, conservatively). A `spread` of pi is every direction.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    pub axis: Vec3,
    pub spread: f32,
}

impl Cone {
    pub const SPHERE: Cone = Cone { axis: Vec3::Y, spread: PI };

    /// The smallest cone holding both (pbrt-v4's `DirectionCone::Union`).
    fn union(a: Cone, b: Cone) -> Cone {
        let between = a.axis.dot(b.axis).clamp(-1.0, 1.0).acos();
        if (between + b.spread).min(PI) <= a.spread {
            return a;
        }
        if (between + a.spread).min(PI) <= b.spread {
            return b;
        }
        let spread = 0.5 * (a.spread + between + b.spread);
        let turn_axis = a.axis.cross(b.axis);
        if spread >= PI || turn_axis.length_squared() < 1e-12 {
            return Cone::SPHERE;
        }
        let turn = spread - a.spread;
        let axis = glam::Quat::from_axis_angle(turn_axis.normalize(), turn) * a.axis;
        Cone { axis: axis.normalize(), spread }
    }
}

impl LightBounds {
    fn union(a: &LightBounds, b: &LightBounds) -> LightBounds {
        // A light of no power adds nothing to the cone (it is never reached through it).
        let cone = match (a.power > 0.0, b.power > 0.0) {
            (true, false) => a.cone,
            (false, true) => b.cone,
            _ => Cone::union(a.cone, b.cone),
        };
        LightBounds { lo: a.lo.min(b.lo), hi: a.hi.max(b.hi), power: a.power + b.power, cone }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }
}

/// The bounds of a finite light: a point light's cone is the sphere, a spot's is its outer
/// cone; an area light's are its primitive's box, with `normal` (a flat one-sided emitter's
/// front) or every direction.
pub fn point_bounds(l: &Light, power: f32) -> LightBounds {
    let p = Vec3::from(l.position);
    let cone = if l.kind == LIGHT_SPOT {
        Cone { axis: Vec3::from(l.direction), spread: l.cos_outer.clamp(-1.0, 1.0).acos() }
    } else {
        Cone::SPHERE
    };
    LightBounds { lo: p, hi: p, power, cone }
}

pub fn area_bounds(lo: Vec3, hi: Vec3, normal: Option<Vec3>, power: f32) -> LightBounds {
    let cone = match normal {
        Some(n) if n.length_squared() > 0.0 => Cone { axis: n.normalize(), spread: 0.0 },
        _ => Cone::SPHERE,
    };
    LightBounds { lo, hi, power, cone }
}

/// Writes the tree over `finite` (light index, bounds) and the choice among `infinite` (light
/// index, power) at the end of `words`, sets each light's `tree_trail` and `tree_probability`,
/// and returns the block's word offset, or `NO_LIGHT` when no light casts direct light.
pub fn build(
    lights: &mut [Light],
    finite: &[(u32, LightBounds)],
    infinite: &[(u32, f32)],
    words: &mut Vec<u32>,
) -> u32 {
    for l in lights.iter_mut() {
        l.tree_trail = NO_LIGHT;
        l.tree_probability = 0.0;
    }
    let finite: Vec<(u32, LightBounds)> = finite.iter().copied().filter(|(_, b)| b.power > 0.0).collect();
    let infinite: Vec<(u32, f32)> = infinite.iter().copied().filter(|&(_, p)| p > 0.0).collect();
    if finite.is_empty() && infinite.is_empty() {
        return NO_LIGHT;
    }
    // The tree takes the share of one more infinite light; the infinite lights split the rest
    // by power.
    let share = if finite.is_empty() { 0.0 } else { 1.0 / (infinite.len() as f32 + 1.0) };
    let base = words.len() as u32;
    let nodes_at = base + LIGHT_TREE_INFINITE + 2 * infinite.len() as u32;
    words.extend([if finite.is_empty() { NO_LIGHT } else { nodes_at }, share.to_bits(), infinite.len() as u32]);
    let total: f64 = infinite.iter().map(|&(_, p)| p as f64).sum();
    let mut running = 0.0f64;
    for (k, &(light, power)) in infinite.iter().enumerate() {
        running += power as f64;
        let cdf = if k + 1 == infinite.len() { 1.0 } else { (running / total) as f32 };
        words.extend([light, cdf.to_bits()]);
        lights[light as usize].tree_probability = (power as f64 / total) as f32;
    }
    if !finite.is_empty() {
        let mut items = finite;
        emit(&mut items, words, lights, 0, 0);
        for &(light, _) in &items {
            lights[light as usize].tree_probability = 1.0;
        }
    }
    base
}

/// Writes the node over `items` (depth-first: a node, its first subtree, its second) and
/// returns its bounds. A leaf holds one light; an inner node splits its lights at the median
/// of their centres along the widest axis, so the tree is balanced (depth ceil(log2 n)).
fn emit(
    items: &mut [(u32, LightBounds)],
    words: &mut Vec<u32>,
    lights: &mut [Light],
    trail: u32,
    depth: u32,
) -> LightBounds {
    let at = words.len();
    words.resize(at + LIGHT_NODE_WORDS as usize, 0);
    let bounds = if let [(light, b)] = items {
        lights[*light as usize].tree_trail = trail;
        words[at + LIGHT_NODE_CHILD as usize] = *light | LIGHT_NODE_LEAF;
        *b
    } else {
        let (lo, hi) = items.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (_, b)| {
            (lo.min(b.centroid()), hi.max(b.centroid()))
        });
        let axis = (hi - lo).max_position();
        // Ties broken by light index, so the tree does not depend on the sort's stability.
        items.sort_by(|a, b| a.1.centroid()[axis].total_cmp(&b.1.centroid()[axis]).then(a.0.cmp(&b.0)));
        let (first, second) = items.split_at_mut(items.len() / 2);
        let a = emit(first, words, lights, trail, depth + 1);
        words[at + LIGHT_NODE_CHILD as usize] = words.len() as u32;
        let b = emit(second, words, lights, trail | 1 << depth, depth + 1);
        LightBounds::union(&a, &b)
    };
    let node = &mut words[at..at + LIGHT_NODE_WORDS as usize];
    let floats = [
        bounds.lo.x,
        bounds.lo.y,
        bounds.lo.z,
        bounds.hi.x,
        bounds.hi.y,
        bounds.hi.z,
        bounds.power,
        bounds.cone.axis.x,
        bounds.cone.axis.y,
        bounds.cone.axis.z,
        bounds.cone.spread.cos(),
    ];
    for (w, f) in node.iter_mut().zip(floats) {
        *w = f.to_bits();
    }
    bounds
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cone_union_holds_both_cones() {
        let a = Cone { axis: Vec3::Y, spread: 0.0 };
        let b = Cone { axis: Vec3::X, spread: 0.0 };
        let u = Cone::union(a, b);
        assert!((u.spread - PI / 4.0).abs() < 1e-5, "{u:?}");
        assert!(u.axis.dot(Vec3::Y).acos() <= u.spread + 1e-5 && u.axis.dot(Vec3::X).acos() <= u.spread + 1e-5);
        let opposite = Cone::union(a, Cone { axis: -Vec3::Y, ..a });
        assert_eq!(opposite.spread, PI);
    }

    #[test]
    fn every_light_gets_a_trail_and_the_infinite_ones_their_share() {
        let mut lights = vec![Light::default(); 5];
        let finite: Vec<(u32, LightBounds)> = (0..4)
            .map(|i| {
                (i, area_bounds(Vec3::splat(i as f32), Vec3::splat(i as f32 + 0.5), Some(Vec3::Y), 1.0 + i as f32))
            })
            .collect();
        let mut words = vec![7];
        let base = build(&mut lights, &finite, &[(4, 3.0)], &mut words);
        assert_eq!(base, 1);
        assert_eq!(f32::from_bits(words[(base + LIGHT_TREE_SHARE) as usize]), 0.5);
        assert_eq!(lights[4].tree_probability, 1.0);
        assert_eq!(lights[4].tree_trail, NO_LIGHT);
        let trails: Vec<u32> = lights[..4].iter().map(|l| l.tree_trail).collect();
        assert_eq!(trails, [0, 2, 1, 3]);
        let root = words[(base + LIGHT_TREE_ROOT) as usize] as usize;
        assert_eq!(f32::from_bits(words[root + LIGHT_NODE_POWER as usize]), 10.0);
    }
}
