//! Hashed spatial grid over photons: cells, hashing, the deterministic order inside a bucket and
//! the range query; twin of `shaders/grid.glsl`. The build kernels are in `grid_build.rs`.

use std::cmp::Ordering;

use glam::{IVec3, Vec3};

use crate::layout::{GridParams, Photon};

pub fn grid_cell(p: Vec3, cell_size: f32) -> IVec3 {
    (p / cell_size).floor().as_ivec3()
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
    for k in 0..27 {
        let cell = grid_neighbour(c, k);
        let h = grid_hash(cell, g.table_mask) as usize;
        for p in &photons[cell_start[h] as usize..cell_start[h + 1] as usize] {
            let pos = Vec3::from(p.position);
            if grid_cell(pos, g.cell_size) != cell {
                continue;
            }
            let d = pos - x;
            let d2 = d.dot(d);
            if d2 <= r2 {
                visit(p, d2);
            }
        }
    }
}
