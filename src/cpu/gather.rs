//! Radiance estimates from the photon maps; twin of `shaders/gather.glsl`. The camera path reads
//! them at its end (`render::radiance`): caustics, the indirect preview, and the global map where a
//! final-gather path ends.

use std::f32::consts::PI;

use glam::Vec3;

use super::bsdf::{bsdf_estimate_is_constant, bsdf_eval, bsdf_flags, facing, Bsdf};
use super::photon::photon_on_side;
use super::photon_index::PhotonIndex;
use super::sampling::onb;
use super::shape::Hit;
use super::SceneView;
use crate::layout::constants::*;
use crate::layout::{GridParams, Primitive};

pub const MAP_GLOBAL: usize = crate::layout::constants::MAP_GLOBAL as usize;
pub const MAP_CAUSTIC: usize = crate::layout::constants::MAP_CAUSTIC as usize;
pub const MAP_VOLUME: usize = crate::layout::constants::MAP_VOLUME as usize;

/// The lookup layout of `map`, which must have left out only photons that `exclude` skips
/// (see `render::excluded_by_every_lookup`).
fn map_index<'a>(s: &SceneView<'a>, map: usize, exclude: u32) -> (&'a PhotonIndex, &'a GridParams) {
    let index = &s.maps.indices[map];
    assert_eq!(index.dropped & !exclude, 0, "map {map} left out photons of flags a lookup keeps");
    (index, &s.maps.grids[map])
}

/// Irradiance at `x` (normal `n`, facing the side photons must arrive from) from the photons of
/// `map` within the map's radius, with the 2D Epanechnikov kernel K = 2/(pi r^2) (1 - d^2/r^2),
/// whose integral over the disc is 1. Photons whose flags intersect `exclude` are skipped, as are
/// photons that arrived from behind the surface, landed on its other side or lie off its tangent
/// plane.
pub fn photon_irradiance(s: &SceneView, map: usize, x: Vec3, n: Vec3, exclude: u32) -> Gathered {
    let (index, g) = map_index(s, map, exclude);
    let mut found = Gathered::default();
    if g.photon_count == 0 {
        return found;
    }
    let r2 = g.radius * g.radius;
    let thickness = PHOTON_DISC_THICKNESS * g.radius;
    let thin = PHOTON_EDGE_THICKNESS * g.radius;
    index.for_each_near(x, g, |pos, flags, p, d2| {
        let off = (pos - x).dot(n).abs();
        if (flags & exclude) != 0 {
            return;
        }
        if off > thickness {
            found.off_disc = true;
            return;
        }
        if p.wi.dot(n) <= 0.0 || !photon_on_side(p.side, n) {
            return;
        }
        let c = p.flux * (1.0 - d2 / r2);
        found.disc += c;
        if off <= thin {
            found.thin += c;
        }
    });
    found.scale(Vec3::splat(2.0 / (PI * r2)))
}

/// Probe ray `k` (`0..2 * EDGE_PROBES`) of a lookup at `x` (facing normal `n`) whose largest
/// radius is `reach`, the directions turned by `turn` (a number in [0, 1)): even probes leave a
/// point just above the surface along direction k / 2 and meet a wall that rises from it (a
/// concave edge); odd probes run back toward `x` just below the surface from `reach` away and
/// meet the side of a solid whose face ends (a convex edge). Returns the origin and direction.
pub fn edge_probe_ray(x: Vec3, n: Vec3, reach: f32, turn: f32, k: u32) -> (Vec3, Vec3) {
    let dir = probe_direction(n, turn, k / 2);
    let lift = n * (PHOTON_DISC_THICKNESS * reach);
    if k.is_multiple_of(2) {
        (x + lift, dir)
    } else {
        (x + dir * reach - lift, -dir)
    }
}

/// Direction i of the probes around `n`, turned by `turn` (a quarter of a turn at most).
pub fn probe_direction(n: Vec3, turn: f32, i: u32) -> Vec3 {
    let (t1, t2) = onb(n);
    let phi = 2.0 * PI * (i as f32 + turn) / EDGE_PROBES as f32;
    t1 * phi.cos() + t2 * phi.sin()
}

/// How far the surface of triangle `p` reaches from `x` in each probe direction before one of its
/// open edges (`PRIMITIVE_FLAG_OPEN_EDGE`), at most `reach`: the distance along the direction to
/// the edge's line, in the plane of the facing normal `n`.
pub fn open_edge_reach(p: &Primitive, x: Vec3, n: Vec3, reach: f32, turn: f32) -> [f32; EDGE_PROBES as usize] {
    let mut out = [reach; EDGE_PROBES as usize];
    if p.kind & PRIMITIVE_KIND_MASK != PRIMITIVE_TRIANGLE {
        return out;
    }
    let v = [Vec3::from(p.p0), Vec3::from(p.p1), Vec3::from(p.p2)];
    let dirs: [Vec3; EDGE_PROBES as usize] = std::array::from_fn(|i| probe_direction(n, turn, i as u32));
    for e in 0..3 {
        if p.kind & (PRIMITIVE_FLAG_OPEN_EDGE << e) == 0 {
            continue;
        }
        let (a, b, c) = (v[e], v[(e + 1) % 3], v[(e + 2) % 3]);
        // The edge's normal in the plane, toward the triangle's inside.
        let m = n.cross(b - a).normalize_or_zero();
        let m = if m.dot(c - a) < 0.0 { -m } else { m };
        let inside = (x - a).dot(m).max(0.0);
        for (r, dir) in out.iter_mut().zip(dirs) {
            let toward = -dir.dot(m);
            if toward > 0.0 {
                *r = r.min(inside / toward);
            }
        }
    }
    out
}

/// The share of a disc of radius `r` that the surface covers, as the probes found it: in each
/// direction the surface reaches `reach[i]` (the Epanechnikov kernel's mass within s r of the
/// centre along a ray is 2 s^2 - s^4 of the ray's share).
pub fn edge_mass(reach: &[f32; EDGE_PROBES as usize], r: f32) -> f32 {
    let mut mass = 0.0;
    for &rho in reach {
        let s2 = (rho.min(r) / r) * (rho.min(r) / r);
        mass += 2.0 * s2 - s2 * s2;
    }
    mass / EDGE_PROBES as f32
}

/// A surface lookup's sums: over the disc (the estimate), over its thin core (what the estimate
/// becomes where probes found an edge: photons of a surface across the edge lie in the disc but
/// not in the core), and whether photons lay in reach off the disc (another surface nearby).
#[derive(Clone, Copy, Debug, Default)]
pub struct Gathered {
    pub disc: Vec3,
    pub thin: Vec3,
    pub off_disc: bool,
}

impl Gathered {
    fn scale(self, k: Vec3) -> Gathered {
        Gathered { disc: self.disc * k, thin: self.thin * k, off_disc: self.off_disc }
    }
}

/// Radiance toward `wo` at `h` through the estimate lobes of `b`, from the photons of `map`
/// (those with flags in `exclude` skipped): each photon weighted by the BSDF's value for its
/// direction. The volume map (`b` a medium's phase function) is read over the ball of radius r
/// with the 3D Epanechnikov kernel 15/(8 pi r^3) (1 - d^2/r^2): the sum of flux times phase
/// over the collisions near the point, which estimates sigma_t times the in-scattered radiance
/// (Jensen and Christensen 1998); the caller divides by sigma_t.
pub fn photon_radiance(s: &SceneView, map: usize, h: &Hit, b: &Bsdf, wo: Vec3, exclude: u32) -> Gathered {
    let volume = map == MAP_VOLUME;
    let nf = facing(b, wo);
    // A Lambertian BSDF has one value for every photon: sum the irradiance, apply it once.
    if !volume && bsdf_estimate_is_constant(b) {
        return photon_irradiance(s, map, h.p, nf, exclude).scale(bsdf_eval(b, wo, nf));
    }
    let (index, g) = map_index(s, map, exclude);
    let mut found = Gathered::default();
    if g.photon_count == 0 {
        return found;
    }
    let r2 = g.radius * g.radius;
    let thickness = if volume { f32::INFINITY } else { PHOTON_DISC_THICKNESS * g.radius };
    // Photons arriving from behind count only where the BSDF transmits.
    let thin = if volume { f32::INFINITY } else { PHOTON_EDGE_THICKNESS * g.radius };
    let both_sides = volume || bsdf_flags(b) & BSDF_TRANSMISSION != 0;
    index.for_each_near(h.p, g, |pos, flags, p, d2| {
        let off = (pos - h.p).dot(nf).abs();
        if (flags & exclude) != 0 {
            return;
        }
        if off > thickness {
            found.off_disc = true;
            return;
        }
        if !both_sides && (p.wi.dot(nf) <= 0.0 || !photon_on_side(p.side, nf)) {
            return;
        }
        let c = bsdf_eval(b, wo, p.wi) * p.flux * (1.0 - d2 / r2);
        found.disc += c;
        if off <= thin {
            found.thin += c;
        }
    });
    found.scale(Vec3::splat(if volume { 15.0 / (8.0 * PI * r2 * g.radius) } else { 2.0 / (PI * r2) }))
}
