//! Error metrics between a test image and a reference.

use super::image::Image;

/// relMSE as the shared references define it: the mean over pixels and channels of
/// (t - r)^2 / (r^2 + 0.01).
pub fn rel_mse(test: &Image, reference: &Image) -> f64 {
    assert_eq!((test.width, test.height), (reference.width, reference.height), "images of one size");
    let mut sum = 0.0f64;
    for (t, r) in test.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (t, r) = (t[c] as f64, r[c] as f64);
            sum += (t - r).powi(2) / (r * r + 0.01);
        }
    }
    sum / (3 * test.pixels.len()).max(1) as f64
}

/// Root of the mean squared difference over pixels and channels.
pub fn rmse(test: &Image, reference: &Image) -> f64 {
    let mut sum = 0.0f64;
    for (t, r) in test.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            sum += (t[c] as f64 - r[c] as f64).powi(2);
        }
    }
    (sum / (3 * test.pixels.len()).max(1) as f64).sqrt()
}

/// Per-channel ratio of mean radiance, test over reference.
pub fn mean_ratio(test: &Image, reference: &Image) -> [f64; 3] {
    let (t, r) = (test.channel_means(), reference.channel_means());
    [t[0] / r[0], t[1] / r[1], t[2] / r[2]]
}

/// A box-filtered copy at 1/`factor` of the size: compares a small render with a large reference.
pub fn downsample(image: &Image, factor: u32) -> Image {
    let (w, h) = (image.width / factor, image.height / factor);
    let mut out = Image::new(w, h);
    let inv = 1.0 / (factor * factor) as f32;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0.0f32; 3];
            for dy in 0..factor {
                for dx in 0..factor {
                    let p = image.pixel(x * factor + dx, y * factor + dy);
                    for c in 0..3 {
                        acc[c] += p[c];
                    }
                }
            }
            out.pixels[(y * w + x) as usize] = acc.map(|a| a * inv);
        }
    }
    out
}

/// Per-pixel relMSE (mean over channels), for error images.
pub fn rel_mse_per_pixel(test: &Image, reference: &Image) -> Vec<f64> {
    test.pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(t, r)| {
            (0..3).map(|c| (t[c] as f64 - r[c] as f64).powi(2) / ((r[c] as f64).powi(2) + 0.01)).sum::<f64>() / 3.0
        })
        .collect()
}

/// A false-colour image of per-pixel relMSE on a log scale: black below 1e-4, then blue, green,
/// yellow, red and white at 1 and above. Linear values, so it survives PNG's sRGB encoding.
pub fn error_heatmap(test: &Image, reference: &Image) -> Image {
    const STOPS: [[f32; 3]; 6] =
        [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 1.0]];
    let mut out = Image::new(test.width, test.height);
    for (o, e) in out.pixels.iter_mut().zip(rel_mse_per_pixel(test, reference)) {
        // log10 from -4 to 0 onto the stops.
        let x = ((e.max(1e-12).log10() + 4.0) / 4.0).clamp(0.0, 1.0) as f32 * (STOPS.len() - 1) as f32;
        let i = (x.floor() as usize).min(STOPS.len() - 2);
        let f = x - i as f32;
        *o = [0, 1, 2].map(|c| STOPS[i][c] * (1.0 - f) + STOPS[i + 1][c] * f);
    }
    out
}
