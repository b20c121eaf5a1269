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

/// The buckets a lookup of `radius` (= cell_size / 2) around `x` must read, duplicates dropped.
pub fn grid_lookup_buckets(x: Vec3, g: &GridParams) -> ([u32; 8], usize) {
    let q = x / g.cell_size;
    let c = q.floor().as_ivec3();
    let f = q - c.as_vec3();
    let step =
        IVec3::new(if f.x >= 0.5 { 1 } else { -1 }, if f.y >= 0.5 { 1 } else { -1 }, if f.z >= 0.5 { 1 } else { -1 });
    let mut buckets = [0u32; 8];
    let mut n = 0;
    for k in 0..8u32 {
        let offset = IVec3::new((k & 1) as i32, ((k >> 1) & 1) as i32, ((k >> 2) & 1) as i32);
        let h = grid_hash(c + offset * step, g.table_mask);
        if !buckets[..n].contains(&h) {
            buckets[n] = h;
            n += 1;
        }
    }
    (buckets, n)
}

/// Calls `visit(photon, squared distance)` for every photon within `g.radius` of `x`.
/// `cell_start` has one entry per bucket plus one (the end of the last bucket).
pub fn for_each_photon_near(
    x: Vec3,
    g: &GridParams,
    photons: &[Photon],
    cell_start: &[u32],
    mut visit: impl FnMut(&Photon, f32),
) {
    let r2 = g.radius * g.radius;
    let (buckets, n) = grid_lookup_buckets(x, g);
    for &h in &buckets[..n] {
        for p in &photons[cell_start[h as usize] as usize..cell_start[h as usize + 1] as usize] {
            let d = Vec3::from(p.position) - x;
            let d2 = d.dot(d);
            if d2 <= r2 {
                visit(p, d2);
            }
        }
    }
}
