//! A physical sky and sun: the Hosek-Wilkie sky dome (RGB version) drawn into a
//! latitude-longitude environment image, and the sun as a distant light whose irradiance is the
//! Hosek-Wilkie solar radiance (with its limb darkening) integrated over the solar disc. Both are
//! in one set of units (Mitsuba 3's for its `sunsky`: spectra through the CIE observer, divided
//! by the integral of y-bar), so a sunlit and a sky-lit scene compare. The sun's direction
//! is given, or comes from a place and a time (`solar`). `rainbow` adds the bows of sunlight in
//! rain drops.

mod hosek_data;
pub mod rainbow;
pub mod solar;
pub mod spectrum;

use glam::{DVec3, Vec3};
use hosek_data::{LIMB_DARKENING, SKY_RGB, SKY_RGB_RADIANCE, SOLAR};
use spectrum::CIE_Y_INTEGRAL;
use std::f64::consts::{FRAC_PI_2, PI};

/// The sun's angular radius, radians: 0.5358 degrees across, as Mitsuba 3's `sunsky` (the
/// Hosek-Wilkie sample code draws 0.51; the real sun is 0.524 to 0.542). The model's radiance
/// and limb darkening are spread over this disc.
pub const SUN_ANGULAR_RADIUS: f64 = 0.5358 * PI / 180.0 / 2.0;
/// The turbidities the model was fitted for.
pub const TURBIDITY_RANGE: (f64, f64) = (1.0, 10.0);

/// What the sky is made of.
#[derive(Clone, Copy, Debug)]
pub struct SkyParams {
    /// Atmospheric turbidity, in `TURBIDITY_RANGE` (2 to 3 is a clear day, 10 haze).
    pub turbidity: f64,
    /// Albedo of the ground under the atmosphere, per channel, in [0, 1].
    pub ground_albedo: DVec3,
    /// Unit vector toward the sun's centre (world space, +y up).
    pub sun: DVec3,
}

impl SkyParams {
    /// The sun's elevation above the horizon, radians (negative below it).
    pub fn elevation(&self) -> f64 {
        self.sun.y.clamp(-1.0, 1.0).asin()
    }
}

/// The nine parameters of one channel's radiance distribution and its scale, for one sun.
struct Channel {
    config: [f64; 9],
    radiance: f64,
}

/// A quintic Bezier in `t` over six control points taken every `stride` values from `at`.
fn bezier5(data: &[f64], at: usize, stride: usize, t: f64) -> f64 {
    const BINOMIAL: [f64; 6] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    (0..6).map(|k| BINOMIAL[k] * (1.0 - t).powi(5 - k as i32) * t.powi(k as i32) * data[at + k * stride]).sum()
}

/// The model's coefficients blended over albedo and turbidity, for solar elevation `elevation`
/// (radians, clamped to [0, pi/2]). `block` values per (albedo, turbidity) set, each made of six
/// control points of `block / 6` values.
fn cook(data: &[f64], block: usize, value: usize, turbidity: f64, albedo: f64, elevation: f64) -> f64 {
    let t = (elevation.clamp(0.0, FRAC_PI_2) / FRAC_PI_2).cbrt();
    let low = (turbidity.floor() as usize).clamp(1, 10);
    let frac = turbidity - low as f64;
    let stride = block / 6;
    let at =
        |albedo_set: usize, turb: usize| bezier5(data, albedo_set * 10 * block + (turb - 1) * block + value, stride, t);
    let mut v = (1.0 - albedo) * (1.0 - frac) * at(0, low) + albedo * (1.0 - frac) * at(1, low);
    if low < 10 {
        v += (1.0 - albedo) * frac * at(0, low + 1) + albedo * frac * at(1, low + 1);
    }
    v
}

/// The sky of `params`, ready to evaluate.
pub struct Sky {
    params: SkyParams,
    channels: [Channel; 3],
}

impl Sky {
    pub fn new(params: SkyParams) -> Sky {
        let elevation = params.elevation();
        let channel = |c: usize| {
            let albedo = params.ground_albedo[c];
            let mut config = [0.0; 9];
            for (i, v) in config.iter_mut().enumerate() {
                *v = cook(&SKY_RGB[c], 54, i, params.turbidity, albedo, elevation);
            }
            // The RGB data are spectra through the observer, not yet normalised.
            let radiance = cook(&SKY_RGB_RADIANCE[c], 6, 0, params.turbidity, albedo, elevation) / CIE_Y_INTEGRAL;
            Channel { config, radiance }
        };
        Sky { params, channels: [channel(0), channel(1), channel(2)] }
    }

    pub fn params(&self) -> &SkyParams {
        &self.params
    }

    /// Linear RGB radiance of the sky dome seen along unit `d` (without the sun's disc); zero
    /// below the horizon, where the model has no data (the scene's ground stands there).
    pub fn radiance(&self, d: DVec3) -> DVec3 {
        if d.y <= 0.0 {
            return DVec3::ZERO;
        }
        let cos_theta = d.y.min(1.0);
        let cos_gamma = d.dot(self.params.sun).clamp(-1.0, 1.0);
        let gamma = cos_gamma.acos();
        let f = |ch: &Channel| {
            let c = &ch.config;
            let exp_m = (c[4] * gamma).exp();
            let ray_m = cos_gamma * cos_gamma;
            let mie_m = (1.0 + cos_gamma * cos_gamma) / (1.0 + c[8] * c[8] - 2.0 * c[8] * cos_gamma).powf(1.5);
            let zenith = cos_theta.sqrt();
            let v = (1.0 + c[0] * (c[1] / (cos_theta + 0.01)).exp())
                * (c[2] + c[3] * exp_m + c[5] * ray_m + c[6] * mie_m + c[7] * zenith);
            (v * ch.radiance).max(0.0)
        };
        DVec3::new(f(&self.channels[0]), f(&self.channels[1]), f(&self.channels[2]))
    }

    /// Spectral radiance of the sun's centre through the atmosphere at wavelength index `wl`
    /// (320 + 40 wl nm), W / (m^2 sr nm), before limb darkening.
    fn sun_centre(&self, wl: usize, elevation: f64) -> f64 {
        const PIECES: usize = 45;
        const ORDER: usize = 4;
        let elevation = elevation.clamp(0.0, FRAC_PI_2);
        let pos = (((2.0 * elevation / PI).cbrt() * PIECES as f64) as usize).min(PIECES - 1);
        let break_x = (pos as f64 / PIECES as f64).powi(3) * FRAC_PI_2;
        let x = elevation - break_x;
        let at_turbidity = |t: usize| {
            // Coefficients of the piece, highest power first.
            let last = ORDER * PIECES * t + ORDER * (pos + 1) - 1;
            (0..ORDER).fold((0.0, 1.0), |(sum, xe), i| (sum + xe * SOLAR[wl][last - i], xe * x)).0
        };
        let low = (self.params.turbidity.floor() as usize).clamp(1, 10) - 1;
        let (low, frac) = if low == 9 { (8, 1.0) } else { (low, self.params.turbidity - (low + 1) as f64) };
        (1.0 - frac) * at_turbidity(low) + frac * at_turbidity(low + 1)
    }

    /// The sun's spectral irradiance at wavelength `lambda` (nm) on a plane facing it: its
    /// limb-darkened radiance integrated over the disc. Zero when the sun is below the horizon.
    pub fn sun_spectral_irradiance(&self, lambda: f64) -> f64 {
        let elevation = self.params.elevation();
        if elevation < 0.0 {
            return 0.0;
        }
        let x = ((lambda - 320.0) / 40.0).clamp(0.0, 10.0);
        let wl = (x.floor() as usize).min(9);
        let frac = x - wl as f64;
        let centre = (1.0 - frac) * self.sun_centre(wl, elevation) + frac * self.sun_centre(wl + 1, elevation);
        let ld: Vec<f64> =
            (0..6).map(|i| (1.0 - frac) * LIMB_DARKENING[wl][i] + frac * LIMB_DARKENING[wl + 1][i]).collect();
        // Over the disc: gamma from the centre to the rim, mu the cosine on the sun's surface.
        const STEPS: usize = 256;
        let sin_r = SUN_ANGULAR_RADIUS.sin();
        let mut sum = 0.0;
        for k in 0..STEPS {
            let gamma = (k as f64 + 0.5) / STEPS as f64 * SUN_ANGULAR_RADIUS;
            let s = gamma.sin() / sin_r;
            let mu = (1.0 - s * s).max(0.0).sqrt();
            let darkening = (0..6).fold((0.0, 1.0), |(acc, m), i| (acc + ld[i] * m, m * mu)).0;
            sum += darkening * 2.0 * PI * gamma.sin() * gamma.cos() * (SUN_ANGULAR_RADIUS / STEPS as f64);
        }
        centre * sum
    }

    /// The sun's irradiance on a plane facing it, linear RGB, in the sky's units.
    pub fn sun_irradiance(&self) -> DVec3 {
        spectrum::spectrum_to_rgb(|l| self.sun_spectral_irradiance(l)).max(DVec3::ZERO)
    }

    /// The sky dome drawn into a `width` x `height` latitude-longitude image in the
    /// environment's layout (row 0 the zenith, column `width / 2` toward -z, `3 width / 4`
    /// toward +x), each texel the mean of 2x2 directions inside it.
    pub fn image(&self, width: u32, height: u32, extra: impl Fn(DVec3) -> DVec3 + Sync) -> Vec<[f32; 4]> {
        use rayon::prelude::*;
        (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % width, k / width);
                let mut sum = DVec3::ZERO;
                for (di, dj) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
                    let d = latlong_direction((i as f64 + di) / width as f64, (j as f64 + dj) / height as f64);
                    sum += self.radiance(d) + extra(d);
                }
                let c = (0.25 * sum).as_vec3();
                [c.x, c.y, c.z, 1.0]
            })
            .collect()
    }
}

/// The direction of image position (u, v) in [0, 1]^2 of the environment's latitude-longitude
/// layout (before its rotation): v = 0 is +y, u = 1/2 looks toward -z, u = 3/4 toward +x.
pub fn latlong_direction(u: f64, v: f64) -> DVec3 {
    let theta = PI * v;
    let phi = PI * (2.0 * u - 1.0);
    DVec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// The world direction toward the sun at `elevation` and `azimuth` (degrees, clockwise from
/// north seen from above), with north along `north` (horizontal) and +y up.
pub fn direction_from_angles(elevation_deg: f64, azimuth_deg: f64, north: Vec3) -> DVec3 {
    let north = DVec3::new(north.x as f64, 0.0, north.z as f64).normalize();
    // East is north turned a quarter clockwise seen from above (+y): north x up.
    let east = north.cross(DVec3::Y);
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    (e.cos() * (a.cos() * north + a.sin() * east) + e.sin() * DVec3::Y).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sky(turbidity: f64, elevation_deg: f64) -> Sky {
        let sun = direction_from_angles(elevation_deg, 180.0, Vec3::NEG_Z);
        Sky::new(SkyParams { turbidity, ground_albedo: DVec3::splat(0.3), sun })
    }

    /// Luminance-weighted Y of linear sRGB.
    fn luminance(c: DVec3) -> f64 {
        0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
    }

    /// The horizontal irradiance of the sky dome (Y), by a midpoint rule in (cos theta, phi).
    fn sky_horizontal_y(s: &Sky) -> f64 {
        let (n, m) = (200, 400);
        let mut sum = 0.0;
        for a in 0..n {
            let mu = (a as f64 + 0.5) / n as f64;
            for b in 0..m {
                let phi = 2.0 * PI * (b as f64 + 0.5) / m as f64;
                let st = (1.0 - mu * mu).sqrt();
                let d = DVec3::new(st * phi.cos(), mu, st * phi.sin());
                sum += luminance(s.radiance(d)) * mu;
            }
        }
        sum * (1.0 / n as f64) * (2.0 * PI / m as f64)
    }

    #[test]
    fn clear_sky_is_blue_overhead_and_brightest_near_the_sun() {
        let s = sky(2.5, 40.0);
        let zenith = s.radiance(DVec3::Y);
        assert!(zenith.z > zenith.x, "zenith {zenith}");
        let near_sun = s.radiance(direction_from_angles(42.0, 180.0, Vec3::NEG_Z));
        let away = s.radiance(direction_from_angles(42.0, 0.0, Vec3::NEG_Z));
        assert!(luminance(near_sun) > 3.0 * luminance(away), "near {near_sun}, away {away}");
        assert_eq!(s.radiance(DVec3::new(0.0, -0.5, 0.8).normalize()), DVec3::ZERO);
    }

    #[test]
    fn sun_and_sky_light_the_ground_in_daylight_proportions() {
        // Measured clear-sky daylight: at 40-60 degrees of elevation the sun gives 75 to 90
        // percent of the horizontal illuminance (sky 10 to 25 percent); and about 100 klx in
        // total at 60 degrees. Both need the sky and sun in the same units.
        for (elevation, turbidity) in [(40.0, 2.5), (60.0, 3.0)] {
            let s = sky(turbidity, elevation);
            let sun = luminance(s.sun_irradiance()) * elevation.to_radians().sin();
            let sky = sky_horizontal_y(&s);
            let share = sun / (sun + sky);
            assert!((0.7..0.92).contains(&share), "elevation {elevation}: sun share {share} (sun {sun}, sky {sky})");
            let lux = 683.0 * CIE_Y_INTEGRAL * (sun + sky);
            println!("elevation {elevation}, turbidity {turbidity}: sun share {share:.3}, {lux:.0} lx");
            if elevation == 60.0 {
                assert!((70e3..130e3).contains(&lux), "total {lux} lx");
            }
        }
    }

    #[test]
    fn the_sun_reddens_toward_the_horizon_and_haze_dims_it() {
        let high = sky(3.0, 60.0).sun_irradiance();
        let low = sky(3.0, 5.0).sun_irradiance();
        assert!(low.x / low.z > 1.5 * high.x / high.z, "high {high}, low {low}");
        let hazy = sky(9.0, 60.0).sun_irradiance();
        assert!(luminance(hazy) < 0.8 * luminance(high), "hazy {hazy}, clear {high}");
        assert_eq!(sky(3.0, -2.0).sun_irradiance(), DVec3::ZERO);
    }

    #[test]
    fn the_image_follows_the_environment_layout() {
        // The brightest texel of a low sun toward +x (azimuth 90 with north -z) is in the column
        // at three quarters of the width.
        let sun = direction_from_angles(10.0, 90.0, Vec3::NEG_Z);
        assert!((sun - DVec3::new(10f64.to_radians().cos(), 10f64.to_radians().sin(), 0.0)).length() < 1e-12);
        let s = Sky::new(SkyParams { turbidity: 3.0, ground_albedo: DVec3::splat(0.3), sun });
        let (w, h) = (64, 32);
        let texels = s.image(w, h, |_| DVec3::ZERO);
        let best = (0..texels.len()).max_by(|&a, &b| texels[a][1].total_cmp(&texels[b][1])).unwrap();
        let (i, j) = (best as u32 % w, best as u32 / w);
        assert!((i as i32 - 48).abs() <= 1 && (j as i32 - 14).abs() <= 1, "brightest texel ({i}, {j})");
    }
}
