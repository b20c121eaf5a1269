//! The 20-byte stored photon: packing and unpacking; twin of `shaders/photon.glsl`, bit for bit.
//! `flux_rg`: half-float R (low 16 bits) and G (high 16); `flux_b_dir`: half-float B (bits 0-15),
//! octahedral direction toward the light (u bits 16-22, v bits 23-29), `PHOTON_FLAG_*` (bits
//! 30-31). Flux is stored divided by the map's flux scale so that the halves stay near 1, where
//! their 11-bit mantissa rounds by at most 0.05%.

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

pub fn pack_photon(position: Vec3, flux: Vec3, inv_flux_scale: f32, wi: Vec3, flags: u32) -> Photon {
    let f = flux * inv_flux_scale;
    Photon {
        position: position.into(),
        flux_rg: f32_to_f16(f.x) | (f32_to_f16(f.y) << 16),
        flux_b_dir: f32_to_f16(f.z) | (oct_encode(wi) << 16) | (flags << 30),
    }
}

pub fn photon_flux(p: &Photon, flux_scale: f32) -> Vec3 {
    Vec3::new(f16_to_f32(p.flux_rg & 0xffff), f16_to_f32(p.flux_rg >> 16), f16_to_f32(p.flux_b_dir & 0xffff))
        * flux_scale
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
}
