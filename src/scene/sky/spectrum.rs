//! Spectra to linear sRGB: the CIE 1931 2-degree colour-matching functions as the multi-lobe
//! Gaussian fit of Wyman, Sloan and Shirley ("Simple Analytic Approximations to the CIE XYZ Color
//! Matching Functions", JCGT 2013), then XYZ to linear sRGB (D65). XYZ is normalised by the
//! integral of y-bar (Mitsuba's convention), so a flat spectrum of 1 per nanometre has Y = 1:
//! RGB radiance is then a mean spectral radiance over the visible range, and 683 x 106.857 x Y
//! is the luminance in cd/m^2 for spectra in W / (m^2 sr nm).

use glam::DVec3;

/// The fitted colour-matching functions at `lambda` nanometres: (x-bar, y-bar, z-bar).
pub fn cie_xyz(lambda: f64) -> DVec3 {
    // A Gaussian with one width left of its peak and another right of it.
    let g = |mu: f64, left: f64, right: f64| {
        let s = if lambda < mu { left } else { right };
        let t = (lambda - mu) / s;
        (-0.5 * t * t).exp()
    };
    DVec3::new(
        1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2),
        0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1),
        1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8),
    )
}

/// Linear sRGB (D65 white) of CIE XYZ.
pub fn xyz_to_rgb(xyz: DVec3) -> DVec3 {
    DVec3::new(
        3.2404542 * xyz.x - 1.5371385 * xyz.y - 0.4985314 * xyz.z,
        -0.9692660 * xyz.x + 1.8760108 * xyz.y + 0.0415560 * xyz.z,
        0.0556434 * xyz.x - 0.2040259 * xyz.y + 1.0572252 * xyz.z,
    )
}

/// The integral of the CIE 1931 y-bar over 360 to 830 nm (Mitsuba's `CIE_Y_integral`).
pub const CIE_Y_INTEGRAL: f64 = 106.856895;

/// The visible range integrated over, nanometres, and its step.
pub const LAMBDA_MIN: f64 = 380.0;
pub const LAMBDA_MAX: f64 = 720.0;
pub const LAMBDA_STEP: f64 = 5.0;

/// The wavelengths of the integration grid, `LAMBDA_MIN..=LAMBDA_MAX` by `LAMBDA_STEP`.
pub fn wavelengths() -> impl Iterator<Item = f64> {
    let n = ((LAMBDA_MAX - LAMBDA_MIN) / LAMBDA_STEP).round() as usize;
    (0..=n).map(|k| LAMBDA_MIN + k as f64 * LAMBDA_STEP)
}

/// The weight of `lambda` in the trapezoidal rule on `wavelengths()`, with the normalisation.
pub fn weight(lambda: f64) -> f64 {
    let end = lambda == LAMBDA_MIN || lambda == LAMBDA_MAX;
    LAMBDA_STEP * if end { 0.5 } else { 1.0 } / CIE_Y_INTEGRAL
}

/// Normalised CIE XYZ of the spectrum `f` (per nanometre): the trapezoidal rule on
/// `wavelengths()`, divided by `CIE_Y_INTEGRAL`.
pub fn spectrum_to_xyz(mut f: impl FnMut(f64) -> f64) -> DVec3 {
    wavelengths().map(|lambda| weight(lambda) * f(lambda) * cie_xyz(lambda)).sum()
}

/// Linear sRGB of the spectrum `f`.
pub fn spectrum_to_rgb(f: impl FnMut(f64) -> f64) -> DVec3 {
    xyz_to_rgb(spectrum_to_xyz(f))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_peaks_where_the_cie_tables_do() {
        // y-bar peaks at 555 nm with value 1.0 in the CIE tables; the fit is within a few percent.
        let y = |l: f64| cie_xyz(l).y;
        let peak = (500..=600).map(|l| l as f64).max_by(|a, b| y(*a).total_cmp(&y(*b))).unwrap();
        assert!((peak - 556.0).abs() <= 4.0, "y-bar peaks at {peak} nm");
        assert!((y(555.0) - 1.0).abs() < 0.03, "y-bar(555) = {}", y(555.0));
    }

    #[test]
    fn an_equal_energy_spectrum_is_nearly_white_with_y_one() {
        // Illuminant E has x = y = 1/3; through the fit and a truncated range it stays close.
        let xyz = spectrum_to_xyz(|_| 1.0);
        assert!((xyz.y - 1.0).abs() < 0.002, "Y = {}", xyz.y);
        let (x, y) = (xyz.x / xyz.element_sum(), xyz.y / xyz.element_sum());
        assert!((x - 1.0 / 3.0).abs() < 0.01 && (y - 1.0 / 3.0).abs() < 0.01, "x {x}, y {y}");
    }
}
