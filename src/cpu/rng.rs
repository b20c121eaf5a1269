//! Counter-based random numbers; twin of `shaders/rng.glsl`, bit for bit.

/// PCG4D hash of Jarzynski and Olano, "Hash Functions for GPU Rendering" (JCGT 2020).
pub fn pcg4d(v: [u32; 4]) -> [u32; 4] {
    let mut v = v.map(|x| x.wrapping_mul(1664525).wrapping_add(1013904223));
    mix(&mut v);
    for x in &mut v {
        *x ^= *x >> 16;
    }
    mix(&mut v);
    v
}

fn mix(v: &mut [u32; 4]) {
    v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
    v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
    v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
    v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
}

/// 24 random bits scaled into [0, 1): exact in f32, so GPU and CPU agree.
pub fn rand_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Four uniform numbers in [0, 1) from one hash of `dim`; `rand2` and `rand1` are its first ones.
pub fn rand4(stream: u32, sample_index: u32, seed: u32, dim: u32) -> [f32; 4] {
    pcg4d([stream, sample_index, seed, dim]).map(rand_unit)
}

/// Two uniform numbers in [0, 1) for dimension `dim` of (`stream`, `sample_index`, `seed`).
pub fn rand2(stream: u32, sample_index: u32, seed: u32, dim: u32) -> [f32; 2] {
    let h = pcg4d([stream, sample_index, seed, dim]);
    [rand_unit(h[0]), rand_unit(h[1])]
}

pub fn rand1(stream: u32, sample_index: u32, seed: u32, dim: u32) -> f32 {
    rand_unit(pcg4d([stream, sample_index, seed, dim])[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rand_is_uniform_in_unit_interval() {
        // Mean of U[0,1) is 1/2 and variance 1/12; with 1e5 draws the mean's standard error is 9e-4.
        let n = 100_000u32;
        let values: Vec<f32> = (0..n).map(|i| rand1(i, 3, 7, 11)).collect();
        assert!(values.iter().all(|&v| (0.0..1.0).contains(&v)));
        let mean = values.iter().map(|&v| v as f64).sum::<f64>() / n as f64;
        let var = values.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.002, "variance {var}");
    }

    #[test]
    fn neighbouring_keys_are_uncorrelated() {
        // Correlation between streams i and i+1 at the same dimension must vanish (|r| < 4 sigma).
        let n = 50_000u32;
        let a: Vec<f64> = (0..n).map(|i| rand1(2 * i, 0, 0, 0) as f64 - 0.5).collect();
        let b: Vec<f64> = (0..n).map(|i| rand1(2 * i + 1, 0, 0, 0) as f64 - 0.5).collect();
        let r = a.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>() / n as f64 * 12.0;
        assert!(r.abs() < 4.0 / (n as f64).sqrt(), "correlation {r}");
    }
}
