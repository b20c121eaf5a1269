//! Hashed spatial grid over photons: cells, hashing, the deterministic order inside a bucket and
//! the range query; twin of `shaders/grid.glsl`. The build kernels are in `grid_build.rs`.

use std::cmp::Ordering;

use glam::{IVec3, Vec3};

use crate::layout::constants::GRID_REACH_TOLERANCE;
use crate::layout::{GridParams, Photon};

pub fn grid_cell(p: Vec3, cell_size: f32) -> IVec3 {
    let q = p / cell_size;
    IVec3::new(floor_i32(q.x), floor_i32(q.y), floor_i32(q.z))
}

/// `x.floor() as i32` (saturating; NaN gives 0) without the libm call that `floor` is on x86-64
/// without SSE 4.1: the lookup computed it for every photon it read (8% of a render's time).
fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    if (t as f32) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Distances from `x` to the lower and upper faces of its cell along each axis, each shortened
/// by a few ulps of `x` and `cell_size` (the faces lie where `grid_cell`'s rounded division puts
/// them, not exactly at multiples of the cell size): what `grid_neighbour_in_reach` compares.
pub fn grid_face_gaps(x: Vec3, cell_size: f32) -> [Vec3; 2] {
    let q = x / cell_size;
    let f = q - Vec3::new(floor_i32(q.x) as f32, floor_i32(q.y) as f32, floor_i32(q.z) as f32);
    let tolerance = (x.abs().max_element() + cell_size) * GRID_REACH_TOLERANCE;
    let lower = (f * cell_size - tolerance).max(Vec3::ZERO);
    let upper = ((1.0 - f) * cell_size - tolerance).max(Vec3::ZERO);
    [lower, upper]
}

/// Whether neighbour `k` (see `grid_neighbour`) of the cell holding the point whose face gaps are
/// `gaps` has any point within `radius` of it. For a typical point about a quarter of the 27
/// (edge and corner cells) lie out of reach, and the lookup skips their buckets. The gaps err
/// short, so a skipped cell never holds a photon the distance test would take: results are
/// those of visiting all 27.
pub fn grid_neighbour_in_reach(gaps: &[Vec3; 2], radius: f32, k: u32) -> bool {
    let gap = |o: u32, axis: usize| match o {
        0 => gaps[0][axis],
        2 => gaps[1][axis],
        _ => 0.0,
    };
    let (gx, gy, gz) = (gap(k % 3, 0), gap((k / 3) % 3, 1), gap(k / 9, 2));
    gx * gx + gy * gy + gz * gz <= radius * radius
}

/// Spatial hash of Teschner et al. 2003; the three primes are theirs.
pub fn grid_hash(c: IVec3, table_mask: u32) -> u32 {
    ((c.x as u32).wrapping_mul(73_856_093)
        ^ (c.y as u32).wrapping_mul(19_349_663)
        ^ (c.z as u32).wrapping_mul(83_492_791))
        & table_mask
}

/// A total order on photons by their bits, so that a sorted bucket no longer depends on the
/// order in which atomics placed its photons.
pub fn photon_order(a: &Photon, b: &Photon) -> Ordering {
    let key = |p: &Photon| (p.position.map(f32::to_bits), p.flux_rg, p.flux_b_dir);
    key(a).cmp(&key(b))
}

/// Cells are as large as the lookup radius, so a lookup around a point visits the 3x3x3 cells
/// around its cell; this is cell `k` (0..26) of them.
pub fn grid_neighbour(c: IVec3, k: u32) -> IVec3 {
    c + IVec3::new((k % 3) as i32, ((k / 3) % 3) as i32, (k / 9) as i32) - IVec3::ONE
}

/// Calls `visit(photon, squared distance)` for every photon within `g.radius` of `x`.
/// `cell_start` has one entry per bucket plus one (the end of the last bucket). Each of the 27
/// cells is read through its bucket, skipping photons of other cells that share the bucket, so
/// every photon is visited once.
pub fn for_each_photon_near(
    x: Vec3,
    g: &GridParams,
    photons: &[Photon],
    cell_start: &[u32],
    mut visit: impl FnMut(&Photon, f32),
) {
    let r2 = g.radius * g.radius;
    let c = grid_cell(x, g.cell_size);
    let gaps = grid_face_gaps(x, g.cell_size);
    for k in 0..27 {
        if !grid_neighbour_in_reach(&gaps, g.radius, k) {
            continue;
        }
        let cell = grid_neighbour(c, k);
        let h = grid_hash(cell, g.table_mask) as usize;
        for p in &photons[cell_start[h] as usize..cell_start[h + 1] as usize] {
            let pos = Vec3::from(p.position);
            let d = pos - x;
            let d2 = d.dot(d);
            // The distance first: it rejects most photons, and is cheaper than the cell.
            if d2 <= r2 && grid_cell(pos, g.cell_size) == cell {
                visit(p, d2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::rng::rand1;

    fn point(q: u32, stream: u32) -> Vec3 {
        Vec3::new(rand1(q, stream, 5, 0), rand1(q, stream, 5, 1), rand1(q, stream, 5, 2))
    }

    #[test]
    fn floor_matches_the_library_floor() {
        let values = [0.0, -0.0, 0.5, -0.5, -1.0, 1.0, -1.5, 2.999_999_8, -2.999_999_8, 1.0e9, -1.0e9, 3.0e9, -3.0e9];
        for x in values.into_iter().chain([f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MIN_POSITIVE]) {
            assert_eq!(floor_i32(x), x.floor() as i32, "{x}");
        }
        for q in 0..10_000 {
            let x = (rand1(q, 0, 1, 0) - 0.5) * 2.0f32.powi((q % 40) as i32 - 10);
            assert_eq!(floor_i32(x), x.floor() as i32, "{x}");
        }
    }

    #[test]
    fn cells_out_of_reach_hold_no_point_within_the_radius() {
        // Points near the cells' faces and corners, far from the origin (where the division
        // rounds most) and near it: every point within the radius of x lies in a neighbour the
        // test keeps. Near the origin about a quarter of the 27 are skipped on average (far from
        // it, with cells of a few ulps' size, the slack keeps more).
        let mut kept = 0u32;
        let mut queries = 0u32;
        for (offset, cell) in [(0.0, 0.1), (1.0e4, 0.01), (-3.0e3, 0.37), (5.0e5, 1.0)] {
            for q in 0..2000u32 {
                let x = Vec3::splat(offset) + point(q, 1) * cell * 3.0;
                let c = grid_cell(x, cell);
                let gaps = grid_face_gaps(x, cell);
                let reach: Vec<bool> = (0..27).map(|k| grid_neighbour_in_reach(&gaps, cell, k)).collect();
                if offset == 0.0 {
                    kept += reach.iter().filter(|&&r| r).count() as u32;
                    queries += 1;
                }
                // Points on the sphere of radius `cell` around x (the farthest a lookup takes).
                for j in 0..64u32 {
                    let dir = (point(q * 64 + j, 2) * 2.0 - 1.0).normalize_or(Vec3::X);
                    let y = x + dir * cell * 0.999_999;
                    if (y - x).length_squared() > cell * cell {
                        continue;
                    }
                    let k = (0..27).find(|&k| grid_neighbour(c, k) == grid_cell(y, cell));
                    let k = k.expect("a point within one cell size lies in a neighbour");
                    assert!(reach[k as usize], "offset {offset}, query {q}: neighbour {k} skipped but holds {y}");
                }
            }
        }
        let mean = kept as f64 / queries as f64;
        assert!((19.0..23.0).contains(&mean), "{mean} neighbours kept on average (expected about 20.6)");
    }
}
