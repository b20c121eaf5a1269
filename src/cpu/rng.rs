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

/// Key that sets the scrambles of `qmc2` apart from `rand4`'s hashes of the same dimension.
const QMC_KEY: u32 = 0x51ed_270b;

/// Laine and Karras's hash as Burley improved it ("Practical Hash-based Owen Scrambling", JCGT
/// 2020): each bit is flipped by a function of the bits below it, so on reversed bits it is an
/// Owen scramble.
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// The second dimension of the Sobol sequence, bits reversed (the first is the index itself):
/// its generator matrix is Pascal's triangle mod 2, whose blocks [[P, 0], [P, P]] make the
/// product five shift-and-xor steps instead of a loop over the index's 32 bits.
fn sobol_y_reversed(mut index: u32) -> u32 {
    for (shift, low) in [(1, 0x5555_5555u32), (2, 0x3333_3333), (4, 0x0f0f_0f0f), (8, 0x00ff_00ff), (16, 0x0000_ffff)] {
        index ^= (index & !low) >> shift;
    }
    index
}

/// The `qmc2` stream and index of item `item` of batch `batch`, every batch `size` items long:
/// point batch x size + item of the sequence of `stream`. The index has 32 bits, so every 2^32
/// points the stream moves on by 2 (`stream` is 0 or 1 where this is used) and the points are
/// scrambled anew: a render long enough to wrap never draws the same points twice.
pub fn sequence_point(stream: u32, batch: u32, size: u32, item: u32) -> (u32, u32) {
    let i = batch as u64 * size as u64 + item as u64;
    (stream.wrapping_add(((i >> 32) as u32).wrapping_mul(2)), i as u32)
}

/// Two numbers in [0, 1) for dimension `dim`: point `sample_index` of a two-dimensional Sobol
/// sequence, Owen-scrambled, its points shuffled, both by hashes of (`stream`, `seed`, `dim`),
/// after Burley 2020. A pixel's first 2^k samples of one `dim` are a (0, k, 2)-net (one point in
/// every elementary interval), so what varies smoothly over those two numbers (the film, a light
/// or BSDF sample) loses its error faster than independent numbers would lose it; other
/// dimensions and other pixels see unrelated shuffles and scrambles, as independent numbers would.
pub fn qmc2(stream: u32, sample_index: u32, seed: u32, dim: u32) -> [f32; 2] {
    sobol_pair(&pcg4d([stream, seed, dim, QMC_KEY]), sample_index)
}

fn sobol_pair(h: &[u32; 4], sample_index: u32) -> [f32; 2] {
    // Owen scrambling acts on a fraction's bits most significant first: on reversed bits, the
    // Laine-Karras hash. The index is shuffled the same way (on its own bits reversed).
    let index = laine_karras(sample_index.reverse_bits(), h[0]).reverse_bits();
    let x = laine_karras(index, h[1]).reverse_bits();
    let y = laine_karras(sobol_y_reversed(index), h[2]).reverse_bits();
    [rand_unit(x), rand_unit(y)]
}

/// Scrambles the choice's own copy of the sequence apart from the pair's shuffle.
const CHOICE_KEY: u32 = 0x9e37_79b9;

/// `qmc2`'s pair, and a number for a choice among lobes: the first Sobol dimension again, its
/// points shuffled and scrambled by the same hash's fourth word. Shuffled apart from the pair, it
/// pairs with neither of its numbers (pbrt's padded one-dimensional samples), yet over a pixel's
/// samples it is stratified: the share of samples that take a lobe (glass's reflection, a coat)
/// is its probability to within one sample, where independent choices add their own noise.
pub fn qmc2_choice(stream: u32, sample_index: u32, seed: u32, dim: u32) -> ([f32; 2], f32) {
    let h = pcg4d([stream, seed, dim, QMC_KEY]);
    let index = laine_karras(sample_index.reverse_bits(), h[3]).reverse_bits();
    let choice = laine_karras(index, h[3] ^ CHOICE_KEY).reverse_bits();
    (sobol_pair(&h, sample_index), rand_unit(choice))
}

/// The four numbers of a BSDF sample at dimension `dim`: the choice among lobes (0) stratified
/// along `seq` (`qmc2_choice`), the choice between delta and other lobes (3) hashed from
/// (`stream`, `sample`), the direction (1 and 2) point `seq.1` of `qmc2`'s sequence `seq.0`. Camera paths pass their own stream and sample as `seq`, photon and light paths their
/// `sequence_point`.
pub fn bsdf_numbers(stream: u32, sample: u32, seq: (u32, u32), seed: u32, dim: u32) -> [f32; 4] {
    let mut u = rand4(stream, sample, seed, dim);
    ([u[1], u[2]], u[0]) = qmc2_choice(seq.0, seq.1, seed, dim);
    u
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
    fn sobol_y_matches_its_direction_numbers() {
        // The textbook form: v_0 = 2^31, v_(j+1) = v_j ^ (v_j >> 1), xor of v_j over set bits j.
        let sobol_y = |mut i: u32| {
            let (mut v, mut r) = (1u32 << 31, 0u32);
            while i != 0 {
                if i & 1 != 0 {
                    r ^= v;
                }
                i >>= 1;
                v ^= v >> 1;
            }
            r
        };
        for i in (0..5000u32).chain((0..5000).map(|k| pcg4d([k, 1, 2, 3])[0])) {
            assert_eq!(sobol_y_reversed(i).reverse_bits(), sobol_y(i), "index {i}");
        }
    }

    #[test]
    fn sequence_points_wrap_into_a_new_scramble() {
        assert_eq!(sequence_point(1, 3, 10, 4), (1, 34));
        // 2^32 - 1 is the last point of the first run; the next one starts stream 1 + 2.
        assert_eq!(sequence_point(1, 65_535, 65_537, 0), (1, u32::MAX));
        assert_eq!(sequence_point(1, 65_535, 65_537, 1), (3, 0));
        // The largest index, (2^32 - 1) 2^32: 2^32 - 1 wraps, stream 2 (2^32 - 1) mod 2^32.
        assert_eq!(sequence_point(0, u32::MAX, u32::MAX, u32::MAX), (u32::MAX - 1, 0));
    }

    #[test]
    fn qmc2_is_a_net_at_powers_of_two() {
        // Every 2^k points of one pixel and dimension hold one point in each of the 2^k
        // elementary intervals of every shape (2^a x 2^(k-a)).
        let k = 8u32;
        for (stream, dim) in [(0u32, 0u32), (12345, 3), (7, 99)] {
            let points: Vec<[f32; 2]> = (0..1u32 << k).map(|i| qmc2(stream, i, 42, dim)).collect();
            for a in 0..=k {
                let mut seen = vec![false; 1 << k];
                for p in &points {
                    let cx = (p[0] * (1u32 << a) as f32) as usize;
                    let cy = (p[1] * (1u32 << (k - a)) as f32) as usize;
                    let cell = cx * (1 << (k - a)) + cy;
                    assert!(!seen[cell], "two points in one interval 2^{a} x 2^{}", k - a);
                    seen[cell] = true;
                }
            }
        }
    }

    #[test]
    fn qmc2_integrates_better_than_independent_numbers() {
        // A smooth integrand over 64 points in 2000 pixels: the scrambled net's squared error is
        // far below independent numbers' (Owen scrambling: O(n^-3) against n^-1 for smooth ones).
        let f = |p: [f32; 2]| (p[0] as f64 * 3.0).sin() * (p[1] as f64 + 0.5).powi(2);
        let exact = (1.0 - 3f64.cos()) / 3.0 * ((1.5f64.powi(3) - 0.125) / 3.0);
        let n = 64u32;
        let (mut e_qmc, mut e_rand, mut bias) = (0.0, 0.0, 0.0);
        for stream in 0..2000u32 {
            let q = (0..n).map(|i| f(qmc2(stream, i, 1, 5))).sum::<f64>() / n as f64;
            let r = (0..n).map(|i| f(rand2(stream, i, 1, 5))).sum::<f64>() / n as f64;
            e_qmc += (q - exact).powi(2);
            bias += q - exact;
            e_rand += (r - exact).powi(2);
        }
        assert!(e_qmc * 100.0 < e_rand, "squared error {e_qmc} against independent {e_rand}");
        // Unbiased: over the pixels the estimates average to the integral (within 4 sigma).
        let pixels = 2000.0;
        assert!((bias / pixels).abs() < 4.0 * (e_qmc / pixels).sqrt() / pixels.sqrt(), "bias {}", bias / pixels);
    }

    #[test]
    fn a_choice_is_stratified_over_a_pixels_samples_and_apart_from_the_pair() {
        // Glass's reflection at probability 0.07 over 64 samples: taken 4.48 times, so 4 or 5
        // times in every pixel (independent choices: anywhere from 0 to about 11).
        for stream in 0..500u32 {
            let taken = (0..64u32).filter(|&i| qmc2_choice(stream, i, 9, 3).1 < 0.07).count();
            assert!((4..=5).contains(&taken), "stream {stream}: {taken} of 64");
            assert_eq!(qmc2_choice(stream, 17, 9, 3).0, qmc2(stream, 17, 9, 3));
        }
        // The choice pairs with neither number of the pair: no correlation over many pixels.
        let n = 40_000u32;
        for k in 0..2 {
            let r = (0..n)
                .map(|i| {
                    let (pair, choice) = qmc2_choice(i / 16, i % 16, 5, 8);
                    (pair[k] as f64 - 0.5) * (choice as f64 - 0.5)
                })
                .sum::<f64>()
                / n as f64
                * 12.0;
            assert!(r.abs() < 4.0 / (n as f64).sqrt(), "correlation with the pair's number {k}: {r}");
        }
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
