//! Building the hashed grid by counting sort; twins of the kernels `grid_count`, `grid_scan`,
//! `grid_scatter` and `grid_rank` (shaders/grid_*.comp). The result is the same integers on
//! both sides: bucket starts, and photons sorted by bucket and then by `photon_order`.

use glam::Vec3;

use super::grid::{grid_cell, grid_hash, photon_order};
use crate::layout::{GridParams, Photon};

/// Buckets for `photon_count` photons: a power of two at least twice the count (load factor
/// at most 1/2 keeps collisions rare), at least 1024, and at most 2^24 so that the bucket starts
/// (4 bytes each) fit one 128 MiB storage binding; past 8 M photons the load factor grows.
pub fn table_size_for(photon_count: u32) -> u32 {
    (photon_count.max(512) as u64 * 2).next_power_of_two().min(1 << 24) as u32
}

pub fn grid_params(radius: f32, photon_count: u32, flux_scale: f32) -> GridParams {
    GridParams {
        cell_size: radius,
        radius,
        table_mask: table_size_for(photon_count) - 1,
        photon_count,
        flux_scale,
        _pad: [0; 3],
    }
}

pub fn photon_bucket(p: &Photon, g: &GridParams) -> u32 {
    grid_hash(grid_cell(Vec3::from(p.position), g.cell_size), g.table_mask)
}

/// Photons per bucket.
pub fn grid_count(photons: &[Photon], g: &GridParams, counts: &mut [u32]) {
    for p in photons {
        counts[photon_bucket(p, g) as usize] += 1;
    }
}

/// Exclusive prefix sum of `counts`, with the total appended: the start of every bucket.
pub fn grid_scan(counts: &[u32]) -> Vec<u32> {
    let mut starts = Vec::with_capacity(counts.len() + 1);
    let mut sum = 0u32;
    for &c in counts {
        starts.push(sum);
        sum += c;
    }
    starts.push(sum);
    starts
}

/// Places every photon in its bucket's range (in input order here; in any order on the GPU).
pub fn grid_scatter(photons: &[Photon], g: &GridParams, starts: &[u32], sorted: &mut [Photon]) {
    let mut cursor = starts[..starts.len() - 1].to_vec();
    for p in photons {
        let h = photon_bucket(p, g) as usize;
        sorted[cursor[h] as usize] = *p;
        cursor[h] += 1;
    }
}

/// Orders each bucket by `photon_order`, which makes the layout independent of scatter order
/// (the kernel places each photon at its rank; sorting gives the same bytes).
pub fn grid_rank(starts: &[u32], sorted: &mut [Photon]) {
    for w in starts.windows(2) {
        sorted[w[0] as usize..w[1] as usize].sort_unstable_by(photon_order);
    }
}

/// The whole build: (photons sorted by bucket, bucket starts with the total appended).
pub fn build_grid(photons: &[Photon], g: &GridParams) -> (Vec<Photon>, Vec<u32>) {
    let mut counts = vec![0u32; g.table_mask as usize + 1];
    grid_count(photons, g, &mut counts);
    let starts = grid_scan(&counts);
    let mut sorted = vec![Photon::default(); photons.len()];
    grid_scatter(photons, g, &starts, &mut sorted);
    grid_rank(&starts, &mut sorted);
    (sorted, starts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::grid::for_each_photon_near;
    use crate::cpu::rng::rand1;

    fn random_photons(n: u32, seed: u32) -> Vec<Photon> {
        (0..n)
            .map(|i| Photon {
                position: [0, 1, 2].map(|d| rand1(i, 0, seed, d) * 10.0 - 5.0),
                flux_rg: i,
                flux_b_dir: 0,
            })
            .collect()
    }

    #[test]
    fn grid_query_matches_brute_force() {
        // Radii from tiny (most cells empty) to large, and tables from 1 bucket (every cell
        // collides) to roomy: the query must find exactly the photons brute force finds.
        let photons = random_photons(5000, 1);
        for (case, (radius, table_mask)) in
            [(0.05, 16383u32), (0.3, 16383), (1.0, 1023), (0.5, 0), (0.2, 7), (2.5, 65535)].into_iter().enumerate()
        {
            let g = GridParams { cell_size: radius, radius, table_mask, photon_count: 5000, ..Default::default() };
            let (sorted, starts) = build_grid(&photons, &g);
            assert_eq!(*starts.last().unwrap(), 5000);
            for q in 0..300u32 {
                let x = Vec3::new(rand1(q, 1, 9, 0), rand1(q, 1, 9, 1), rand1(q, 1, 9, 2)) * 12.0 - 6.0;
                let mut found: Vec<u32> = Vec::new();
                for_each_photon_near(x, &g, &sorted, &starts, |p, _| found.push(p.flux_rg));
                let mut expected: Vec<u32> = photons
                    .iter()
                    .filter(|p| (Vec3::from(p.position) - x).length_squared() <= radius * radius)
                    .map(|p| p.flux_rg)
                    .collect();
                found.sort_unstable();
                expected.sort_unstable();
                assert_eq!(found, expected, "case {case}, query {q}");
            }
        }
    }

    #[test]
    fn grid_layout_does_not_depend_on_input_order() {
        let photons = random_photons(3000, 2);
        let mut reversed = photons.clone();
        reversed.reverse();
        let g = grid_params(0.4, 3000, 1.0);
        assert_eq!(build_grid(&photons, &g), build_grid(&reversed, &g));
    }
}
