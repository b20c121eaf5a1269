//! A rough nonlinear plastic's coat table (host only, read by `cpu::microfacet::plastic_eval`
//! and its GLSL twin): its internal diffuse reflectance, then the transmittance of its rough
//! interface from outside at the cosines i / (`PLASTIC_COAT_TABLE` - 1). These are the integrals
//! Mitsuba 3's `roughplastic` precomputes (microfacet.h's `eval_transmittance` and
//! `eval_reflectance`, the same Gauss-Legendre orders), over the coat distribution's visible normals: a sample of
//! the interface's reflection or refraction weighted by its Fresnel term and the masking of the
//! direction it leaves along, so light that the interface's microfacets shadow is lost, as there.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::cpu::microfacet::{mf_fresnel_dielectric, mf_g1, mf_is_smooth, mf_sample_visible};
use crate::layout::constants::PLASTIC_COAT_TABLE;

/// The table of a coat of width `alpha` (isotropic; the host passes the mean of an anisotropic
/// pair) of distribution `dist` (`MICROFACET_*`) and index `ior`, as `PLASTIC_COAT_WORDS` f32
/// bit patterns; `None` for a smooth coat, whose terms have closed forms.
pub fn plastic_coat_table(alpha: f32, dist: u32, ior: f32) -> Option<Vec<u32>> {
    if mf_is_smooth(Vec2::splat(alpha)) {
        return None;
    }
    let alpha = Vec2::splat(alpha.max(1e-4));
    let n = PLASTIC_COAT_TABLE as usize;
    // Mitsuba's grid: the cosine 0 moved to 1e-6, so the direction stays above the surface.
    let mu = |i: usize| (i as f32 / (n - 1) as f32).max(1e-6);
    let (outside, inside) = (gauss_legendre(32), gauss_legendre(128));
    let transmittance: Vec<f32> =
        (0..n).into_par_iter().map(|i| coat_integral(mu(i), alpha, dist, ior, &outside, true)).collect();
    // 2 mean(R(mu) mu) over the same grid: Mitsuba's mean, not a quadrature rule in mu.
    let internal: f32 = (0..n)
        .into_par_iter()
        .map(|i| coat_integral(mu(i), alpha, dist, 1.0 / ior, &inside, false) * mu(i))
        .sum::<f32>()
        * 2.0
        / n as f32;
    Some(std::iter::once(internal).chain(transmittance).map(f32::to_bits).collect())
}

/// The interface's albedo for light arriving at cosine `mu` from the side where the relative
/// index is `eta` (eta_t / eta_i): its refraction's when `transmit`, else its reflection's.
fn coat_integral(mu: f32, alpha: Vec2, dist: u32, eta: f32, rule: &[(f64, f64)], transmit: bool) -> f32 {
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let mut sum = 0.0f64;
    for &(x, wx) in rule {
        for &(y, wy) in rule {
            let m = mf_sample_visible(wi, alpha, dist, Vec2::new(0.5 * x as f32 + 0.5, 0.5 * y as f32 + 0.5));
            let cos_i = wi.dot(m);
            if cos_i <= 0.0 {
                continue;
            }
            let (f, cos_t) = mf_fresnel_dielectric(cos_i, 1.0, eta);
            let value = if transmit {
                let wt = -wi / eta + (cos_i / eta - cos_t) * m;
                if f >= 1.0 || wt.z >= 0.0 {
                    0.0
                } else {
                    (1.0 - f) * mf_g1(wt, m, alpha, dist)
                }
            } else {
                let wr = 2.0 * cos_i * m - wi;
                if wr.z <= 0.0 {
                    0.0
                } else {
                    f * mf_g1(wr, m, alpha, dist)
                }
            };
            sum += value as f64 * wx * wy;
        }
    }
    (sum * 0.25) as f32
}

/// Nodes and weights of the `n`-point Gauss-Legendre rule on [-1, 1] (Newton's iteration on
/// P_n from Chebyshev's guesses).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    (p0, p1) = (p1, p2);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::constants::{MICROFACET_GGX, PLASTIC_COAT_WORDS};

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in [32, 128] {
            let rule = gauss_legendre(n);
            let weights: f64 = rule.iter().map(|&(_, w)| w).sum();
            let x4: f64 = rule.iter().map(|&(x, w)| w * x.powi(4)).sum();
            assert!((weights - 2.0).abs() < 1e-12 && (x4 - 0.4).abs() < 1e-12, "{n}: {weights} {x4}");
        }
    }

    #[test]
    fn coat_table_matches_mitsuba() {
        // Mitsuba 3.9.1's roughplastic at ior 1.5 (eval of a base of 0.7 through
        // tests/references/make_mitsuba_references.py's set-up, and its numbers printed by a
        // numpy copy of its integrals): internal reflectance 0.576 (alpha 0.05), 0.486 (0.2),
        // 0.348 (0.4); transmittance at cosine 1 about 0.960, 0.957, 0.947.
        for (alpha, r_int, t1) in [(0.05, 0.5762, 0.9598), (0.2, 0.4863, 0.9568), (0.4, 0.3482, 0.9472)] {
            let t = plastic_coat_table(alpha, MICROFACET_GGX, 1.5).expect("a rough coat");
            assert_eq!(t.len() as u32, PLASTIC_COAT_WORDS);
            let (r, top) = (f32::from_bits(t[0]), f32::from_bits(t[PLASTIC_COAT_WORDS as usize - 1]));
            println!("alpha {alpha}: internal reflectance {r:.4} (Mitsuba {r_int}), T(1) {top:.4} (Mitsuba {t1})");
            assert!((r - r_int).abs() < 2e-3 && (top - t1).abs() < 2e-3, "alpha {alpha}: {r} {top}");
        }
        assert!(plastic_coat_table(0.0, MICROFACET_GGX, 1.5).is_none());
    }
}
