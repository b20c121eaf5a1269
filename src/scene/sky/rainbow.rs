//! The rainbow: sunlight scattered by spherical water drops, by geometric optics. A ray entering
//! a drop at incidence i refracts to r (sin i = n sin r), reflects k times inside and leaves
//! deviated by D = 2(i - r) + k (pi - 2r); k = 1 gives the primary bow (minimum deviation near
//! 138 degrees, so 42 degrees from the antisolar point), k = 2 the secondary (near 51 degrees,
//! colours reversed), and between them Alexander's dark band, where only the drop surface's
//! reflection sends light. Water's dispersion moves each bow with wavelength; the spectra are
//! turned into RGB through the CIE observer.

use super::spectrum::{cie_xyz, wavelengths, weight, xyz_to_rgb};
use glam::DVec3;
use std::f64::consts::PI;

/// Bins of the scattering angle, 0 to 180 degrees.
const BINS: usize = 1800;
const BIN: f64 = PI / BINS as f64;
/// Impact parameters traced per wavelength.
const RAYS: usize = 20000;
/// Internal reflections followed: 0 (straight through), 1 (primary), 2 (secondary).
const MAX_INTERNAL: u32 = 2;

/// Refractive index of fresh water at 20 C for `lambda` nanometres (Quan and Fry 1995, salinity 0).
pub fn water_ior(lambda: f64) -> f64 {
    1.313242 + 15.7834 / lambda - 4382.0 / (lambda * lambda) + 1.1455e6 / (lambda * lambda * lambda)
}

/// Fresnel reflectances (s, p) of a water surface hit at incidence `i` (its refraction angle r).
fn fresnel(i: f64, r: f64, n: f64) -> (f64, f64) {
    let (ci, cr) = (i.cos(), r.cos());
    let rs = (ci - n * cr) / (ci + n * cr);
    let rp = (n * ci - cr) / (n * ci + cr);
    (rs * rs, rp * rp)
}

/// A deviation folded to a scattering angle in [0, pi].
fn scattering_angle(deviation: f64) -> f64 {
    let d = deviation.rem_euclid(2.0 * PI);
    if d > PI {
        2.0 * PI - d
    } else {
        d
    }
}

/// The phase function of one drop at one wavelength: per bin of scattering angle, the fraction
/// of the light intercepted by the drop that leaves into each steradian there.
pub fn drop_phase(n: f64) -> Vec<f64> {
    let mut flux = vec![0.0; BINS];
    for k in 0..RAYS {
        // Uniform in the drop's cross-section: b^2 uniform; weight 1 / RAYS each.
        let b = ((k as f64 + 0.5) / RAYS as f64).sqrt();
        let i = b.asin();
        let r = (b / n).asin();
        let (rs, rp) = fresnel(i, r, n);
        let mut add = |deviation: f64, weight: f64| {
            let bin = ((scattering_angle(deviation) / BIN) as usize).min(BINS - 1);
            flux[bin] += weight / RAYS as f64;
        };
        add(PI - 2.0 * i, 0.5 * (rs + rp));
        for internal in 0..=MAX_INTERNAL {
            let p = internal as i32;
            let weight = 0.5 * ((1.0 - rs).powi(2) * rs.powi(p) + (1.0 - rp).powi(2) * rp.powi(p));
            add(2.0 * (i - r) + internal as f64 * (PI - 2.0 * r), weight);
        }
    }
    // Per steradian: a bin is a ring of solid angle 2 pi sin(theta) dtheta.
    (0..BINS)
        .map(|j| {
            let (a, b) = (j as f64 * BIN, (j + 1) as f64 * BIN);
            flux[j] / (2.0 * PI * (a.cos() - b.cos()))
        })
        .collect()
}

/// The rainbow's radiance per unit of optical depth of rain, as linear RGB per bin of scattering
/// angle, for the sun's spectral irradiance `sun(lambda)`; smoothed over the sun's disc.
pub struct RainbowTable {
    rgb: Vec<DVec3>,
}

impl RainbowTable {
    pub fn new(mut sun: impl FnMut(f64) -> f64, sun_radius: f64) -> RainbowTable {
        use rayon::prelude::*;
        let grid: Vec<f64> = wavelengths().collect();
        // The sun's spectrum first (it may not be Sync), then the drops per wavelength in parallel.
        let weights: Vec<f64> = grid.iter().map(|&lambda| sun(lambda) * weight(lambda)).collect();
        let xyz = grid
            .par_iter()
            .zip(weights.par_iter())
            .filter(|(_, &e)| e != 0.0)
            .map(|(&lambda, &e)| {
                let cmf = cie_xyz(lambda);
                drop_phase(water_ior(lambda)).into_iter().map(|p| e * p * cmf).collect::<Vec<DVec3>>()
            })
            .reduce(
                || vec![DVec3::ZERO; BINS],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        // The sun's disc (and the drops' spread of sizes) blur the caustic: a triangle as wide as
        // the disc, which also tames the bins on the 1 / sqrt singularity of minimum deviation.
        let half = ((sun_radius / BIN).round() as i64).max(1);
        let smoothed = (0..BINS as i64)
            .map(|j| {
                let mut sum = DVec3::ZERO;
                let mut weights = 0.0;
                for o in -half..=half {
                    let w = (half + 1 - o.abs()) as f64;
                    let k = (j + o).clamp(0, BINS as i64 - 1) as usize;
                    sum += w * xyz[k];
                    weights += w;
                }
                xyz_to_rgb(sum / weights).max(DVec3::ZERO)
            })
            .collect();
        RainbowTable { rgb: smoothed }
    }

    /// Radiance seen along unit `d` per unit optical depth, the sun toward unit `sun`.
    pub fn radiance(&self, d: DVec3, sun: DVec3) -> DVec3 {
        let theta = d.dot(sun).clamp(-1.0, 1.0).acos();
        self.rgb[((theta / BIN) as usize).min(BINS - 1)]
    }

    /// The value at scattering angle `theta` (radians).
    pub fn at(&self, theta: f64) -> DVec3 {
        self.rgb[((theta / BIN) as usize).min(BINS - 1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Degrees from the antisolar point of the brightest bin within `range` degrees of it.
    fn brightest(phase: &[f64], range: (f64, f64)) -> f64 {
        let bins = (0..BINS).filter(|&j| {
            let from_antisolar = 180.0 - (j as f64 + 0.5) * 0.1;
            from_antisolar >= range.0 && from_antisolar <= range.1
        });
        let j = bins.max_by(|&a, &b| phase[a].total_cmp(&phase[b])).unwrap();
        180.0 - (j as f64 + 0.5) * 0.1
    }

    #[test]
    fn bows_sit_where_descartes_put_them() {
        // Minimum deviation for n = 1.3317 (red, 656 nm) and 1.3435 (violet, 405 nm): primary
        // at 42.3 and 40.6 degrees from the antisolar point, secondary at 50.4 and 53.4.
        for (lambda, primary, secondary) in [(656.0, 42.3, 50.4), (405.0, 40.6, 53.4)] {
            let phase = drop_phase(water_ior(lambda));
            let p = brightest(&phase, (35.0, 46.0));
            let s = brightest(&phase, (48.0, 60.0));
            assert!((p - primary).abs() < 0.3, "{lambda} nm: primary at {p}");
            assert!((s - secondary).abs() < 0.4, "{lambda} nm: secondary at {s}");
        }
    }

    #[test]
    fn a_drop_scatters_what_it_intercepts() {
        // Every ray leaves once per order followed; the orders kept carry all but a few percent.
        let phase = drop_phase(1.333);
        let total: f64 =
            (0..BINS).map(|j| phase[j] * 2.0 * PI * ((j as f64 * BIN).cos() - ((j + 1) as f64 * BIN).cos())).sum();
        assert!((0.95..=1.0).contains(&total), "scattered fraction {total}");
    }

    #[test]
    fn red_outside_the_primary_inside_the_secondary_and_a_dark_band_between() {
        let table = RainbowTable::new(|_| 1.0, 0.26f64.to_radians());
        let at = |deg_from_antisolar: f64| table.at((180.0 - deg_from_antisolar).to_radians());
        let band = at(46.0);
        let inside = at(38.0);
        let primary: DVec3 = (400..430).map(|k| at(k as f64 / 10.0)).sum::<DVec3>() / 30.0;
        let y = |c: DVec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        assert!(y(band) < 0.5 * y(inside), "dark band {band}, inside the bow {inside}");
        assert!(y(primary) > 1.4 * y(inside), "bow {primary}, inside {inside}");
        // Where red peaks and where blue peaks, for each bow.
        let peak = |c: usize, lo: f64, hi: f64| {
            let mut best = (lo, 0.0);
            let mut a = lo;
            while a <= hi {
                if at(a)[c] > best.1 {
                    best = (a, at(a)[c]);
                }
                a += 0.05;
            }
            best.0
        };
        assert!(peak(0, 39.0, 44.0) > peak(2, 39.0, 44.0) + 0.8, "primary: red outside blue");
        assert!(peak(0, 49.0, 55.0) + 1.5 < peak(2, 49.0, 55.0), "secondary: red inside blue");
    }
}
