//! The 20-byte stored photon: packing and unpacking; twin of `shaders/photon.glsl`, bit for bit.
//! `flux_rg`: half-float R (low 16 bits) and G (high 16); `flux_b_dir`: half-float B (bits 0-15),
//! octahedral direction toward the light (u bits 16-22, v bits 23-29), `PHOTON_FLAG_*` (bits
//! 30-31). Flux is stored divided by the map's flux scale so that the halves stay near 1, where
//! their 11-bit mantissa rounds by at most 0.05%. Flux is never negative, so the halves' three
//! sign bits carry the signs of the facing normal where the photon landed (x, y, z): a lookup
//! on the other side of a thin surface tells its photons apart (`photon_on_side`).

use glam::{Vec2, Vec3};

use crate::layout::Photon;

/// f32 to f16 bits, round to nearest even; below the smallest normal half flushes to zero, above
/// the largest finite half clamps to it. Integer-only so that both sides agree exactly.
pub fn f32_to_f16(v: f32) -> u32 {
    let b = v.to_bits();
    let sign = (b >> 16) & 0x8000;
    let e = ((b >> 23) & 0xff) as i32 - 112; // rebias 127 -> 15
    let m = b & 0x7f_ffff;
    if e <= 0 {
        return sign;
    }
    if e >= 31 {
        return sign | 0x7bff;
    }
    let mut h = sign | ((e as u32) << 10) | (m >> 13);
    let rest = m & 0x1fff;
    if rest > 0x1000 || (rest == 0x1000 && (h & 1) == 1) {
        h += 1;
    }
    (h & 0x7fff).min(0x7bff) | sign
}

pub fn f16_to_f32(h: u32) -> f32 {
    let e = (h >> 10) & 0x1f;
    if e == 0 {
        return 0.0;
    }
    f32::from_bits(((h & 0x8000) << 16) | ((e + 112) << 23) | ((h & 0x3ff) << 13))
}

fn sign_not_zero(v: Vec2) -> Vec2 {
    Vec2::new(if v.x >= 0.0 { 1.0 } else { -1.0 }, if v.y >= 0.0 { 1.0 } else { -1.0 })
}

/// Octahedral map of a unit vector to [0, 127]^2 (Meyer et al. 2010).
pub fn oct_encode(d: Vec3) -> u32 {
    let p = d / (d.x.abs() + d.y.abs() + d.z.abs());
    let mut q = Vec2::new(p.x, p.y);
    if p.z < 0.0 {
        q = (Vec2::ONE - Vec2::new(p.y, p.x).abs()) * sign_not_zero(q);
    }
    let u = ((q * 0.5 + 0.5) * 127.0 + 0.5).floor().clamp(Vec2::ZERO, Vec2::splat(127.0));
    u.x as u32 | ((u.y as u32) << 7)
}

pub fn oct_decode(bits: u32) -> Vec3 {
    let q = Vec2::new((bits & 127) as f32, ((bits >> 7) & 127) as f32) * (2.0 / 127.0) - 1.0;
    let mut v = Vec3::new(q.x, q.y, 1.0 - q.x.abs() - q.y.abs());
    if v.z < 0.0 {
        let xy = (Vec2::ONE - Vec2::new(v.y, v.x).abs()) * sign_not_zero(Vec2::new(v.x, v.y));
        v.x = xy.x;
        v.y = xy.y;
    }
    v.normalize()
}

/// Packs a photon that arrived along `wi` at `position`, where the surface's normal facing it
/// is `side` (zero in a medium).
pub fn pack_photon(position: Vec3, flux: Vec3, inv_flux_scale: f32, wi: Vec3, side: Vec3, flags: u32) -> Photon {
    let f = flux * inv_flux_scale;
    let half = |v: f32, negative: bool| (f32_to_f16(v) & 0x7fff) | if negative { 0x8000 } else { 0 };
    Photon {
        position: position.into(),
        flux_rg: half(f.x, side.x < 0.0) | (half(f.y, side.y < 0.0) << 16),
        flux_b_dir: half(f.z, side.z < 0.0) | (oct_encode(wi) << 16) | (flags << 30),
    }
}

pub fn photon_flux(p: &Photon, flux_scale: f32) -> Vec3 {
    Vec3::new(f16_to_f32(p.flux_rg & 0x7fff), f16_to_f32((p.flux_rg >> 16) & 0x7fff), f16_to_f32(p.flux_b_dir & 0x7fff))
        * flux_scale
}

/// The signs of the facing normal where the photon landed: bit k set where component k is
/// negative.
pub fn photon_side(p: &Photon) -> u32 {
    ((p.flux_rg >> 15) & 1) | ((p.flux_rg >> 30) & 2) | ((p.flux_b_dir >> 13) & 4)
}

/// Whether a photon of normal signs `side` landed on the side of its surface that a lookup of
/// facing normal `n` sees: the sign of the photon's normal along `n`'s largest component
/// agrees with `n`'s. Within a disc (curvature radius at least twice the lookup radius, or the
/// photon lies off the disc) a photon of the same side has its normal within 30 degrees of `n`,
/// and that component (at least 1/sqrt 3 of `n`) keeps its sign; one of the far side of a
/// zero-thickness surface (a closed sphere seen from inside) has it reversed. Without this a
/// photon that grazed the outside counts inside, where `wi` alone cannot tell.
pub fn photon_on_side(side: u32, n: Vec3) -> bool {
    let a = n.abs();
    let (k, nk) = if a.x >= a.y && a.x >= a.z {
        (0, n.x)
    } else if a.y >= a.z {
        (1, n.y)
    } else {
        (2, n.z)
    };
    ((side >> k) & 1) == u32::from(nk < 0.0)
}

pub fn photon_wi(p: &Photon) -> Vec3 {
    oct_decode((p.flux_b_dir >> 16) & 0x3fff)
}

pub fn photon_flags(p: &Photon) -> u32 {
    p.flux_b_dir >> 30
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_round_trip_is_within_half_an_ulp() {
        // Over the range photon fluxes take (scaled to about 1), the relative rounding error of an
        // 11-bit mantissa is at most 2^-11 = 0.049%.
        for i in 0..100_000 {
            let v = 1e-3 * (1.0 + i as f32 * 0.137);
            let back = f16_to_f32(f32_to_f16(v));
            assert!(((back - v) / v).abs() <= 1.0 / 2048.0, "{v} -> {back}");
        }
        assert_eq!(f16_to_f32(f32_to_f16(1.0)), 1.0);
        assert_eq!(f16_to_f32(f32_to_f16(65504.0)), 65504.0);
        assert_eq!(f16_to_f32(f32_to_f16(1e9)), 65504.0);
        assert_eq!(f16_to_f32(f32_to_f16(1e-9)), 0.0);
    }

    #[test]
    fn octahedral_directions_round_trip_within_two_degrees() {
        let mut worst = 1.0f32;
        for i in 0..20_000u32 {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 20_000.0;
            let phi = i as f32 * 2.399_963; // golden-angle spiral over the sphere
            let r = (1.0 - z * z).sqrt();
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            worst = worst.min(oct_decode(oct_encode(d)).dot(d));
        }
        let degrees = worst.acos().to_degrees();
        println!("worst octahedral error {degrees:.2} degrees");
        assert!(degrees < 2.0, "{degrees}");
    }

    #[test]
    fn the_landing_side_rides_in_the_flux_sign_bits() {
        let n = Vec3::new(0.3, -0.9, 0.3).normalize();
        let p = pack_photon(Vec3::ONE, Vec3::new(1.0, 0.5, 0.25), 1.0, Vec3::Z, n, 2);
        assert_eq!(photon_flux(&p, 1.0), Vec3::new(1.0, 0.5, 0.25));
        assert_eq!(photon_side(&p), 2);
        assert_eq!(photon_flags(&p), 2);
        assert!(photon_on_side(photon_side(&p), n));
        assert!(!photon_on_side(photon_side(&p), -n));
        // Normals up to 30 degrees apart agree, whatever the axis.
        for i in 0..2000u32 {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 2000.0;
            let phi = i as f32 * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            let q = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let tilt = q.any_orthonormal_vector() * 30f32.to_radians().tan();
            let m = (q + tilt).normalize();
            let side = photon_side(&pack_photon(Vec3::ZERO, Vec3::ONE, 1.0, Vec3::Z, m, 0));
            assert!(photon_on_side(side, q), "{q} {m}");
            assert!(!photon_on_side(side, -q), "{q} {m}");
        }
        // A photon in a medium has no side (volume lookups do not ask).
        assert_eq!(photon_side(&pack_photon(Vec3::ZERO, Vec3::ONE, 1.0, Vec3::Z, Vec3::ZERO, 0)), 0);
    }
}
