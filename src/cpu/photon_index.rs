//! The CPU backend's own layout of a photon map for lookups; no shader twin. The kernels read
//! the hashed grid of `grid.rs` (photons sorted by bucket, 20 bytes each, decoded per visit).
//! On the CPU a pass's lookups read each photon about twenty times, so this layout pays for
//! itself within the pass: photons sorted by cell (a cell is one contiguous range, found in a
//! table keyed by the exact cell, so no photon of a colliding cell is read), their positions
//! and flags in 16-byte records (what the distance test reads for every candidate), their flux
//! and direction decoded once into a second array read only for photons within the radius.
//! Photons that every lookup of the render excludes are left out. Within a cell the photons
//! keep `photon_order`, which is their order in the grid's bucket, and cells are visited in the
//! grid's neighbour order: a lookup visits the same photons in the same order as
//! `for_each_photon_near`, so the sums, and the images, are the same bits.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::grid::{grid_cell, grid_face_gaps, grid_hash, grid_neighbour, grid_neighbour_in_reach, photon_order};
use super::photon::{photon_flags, photon_flux, photon_side, photon_wi};
use crate::layout::{GridParams, Photon};

static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// A thread's last lookup cell and its neighbours' photon ranges: the pixels of a row, which a
/// thread renders one after the other, mostly look up points a few millimetres apart, in one
/// cell, and then skip the 27 table probes (about a third of a lookup's time).
struct LastCell {
    id: u64,
    cell: IVec3,
    ranges: [(u32, u32); 27],
}

thread_local! {
    static NEIGHBOURS: std::cell::RefCell<LastCell> =
        const { std::cell::RefCell::new(LastCell { id: 0, cell: IVec3::ZERO, ranges: [(0, 0); 27] }) };
}

/// A photon's flux (times the map's flux scale), unit direction toward the light and the signs
/// of the normal it landed on (`photon::photon_side`), decoded.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhotonData {
    pub flux: Vec3,
    pub wi: Vec3,
    pub side: u32,
}

impl PhotonData {
    pub fn of(p: &Photon, flux_scale: f32) -> PhotonData {
        PhotonData { flux: photon_flux(p, flux_scale), wi: photon_wi(p), side: photon_side(p) }
    }
}

/// One slot of the cell table: an occupied cell and its range of photons (`end` = 0: empty).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct CellSlot {
    cell: IVec3,
    start: u32,
    end: u32,
}

/// The cell table while photons are counted: a slot's `start` is its cell's ordinal (order of
/// first appearance), `end` is 1 (occupied), and `counts` is indexed by ordinal. It doubles
/// whenever it would be more than half full, which keeps probe runs short (most lookups of
/// empty cells end at the first slot).
struct CellTable {
    slots: Vec<CellSlot>,
    mask: u32,
    counts: Vec<u32>,
}

impl CellTable {
    fn with_capacity(cells: usize) -> CellTable {
        let size = (cells.max(8) * 2).next_power_of_two();
        CellTable { slots: vec![CellSlot::default(); size], mask: size as u32 - 1, counts: Vec::new() }
    }

    fn slot(slots: &[CellSlot], mask: u32, cell: IVec3) -> usize {
        let mut h = grid_hash(cell, mask);
        while slots[h as usize].end != 0 && slots[h as usize].cell != cell {
            h = (h + 1) & mask;
        }
        h as usize
    }

    /// Counts a photon of `cell`; returns the cell's ordinal.
    fn count(&mut self, cell: IVec3) -> u32 {
        let h = Self::slot(&self.slots, self.mask, cell);
        if self.slots[h].end != 0 {
            let o = self.slots[h].start;
            self.counts[o as usize] += 1;
            return o;
        }
        let o = self.counts.len() as u32;
        self.counts.push(1);
        self.slots[h] = CellSlot { cell, start: o, end: 1 };
        if self.counts.len() * 2 > self.slots.len() {
            let size = self.slots.len() * 2;
            let mask = size as u32 - 1;
            let mut slots = vec![CellSlot::default(); size];
            for s in self.slots.iter().filter(|s| s.end != 0) {
                let h = Self::slot(&slots, mask, s.cell);
                slots[h] = *s;
            }
            (self.slots, self.mask) = (slots, mask);
        }
        o
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonIndex {
    /// Which index this is, for `NEIGHBOURS` (0: the empty one); unique per build.
    id: u64,
    /// Flags of the photons left out.
    pub dropped: u32,
    table: Vec<CellSlot>,
    table_mask: u32,
    /// Position and flags (as bits) of each photon, in cell order.
    records: Vec<[f32; 4]>,
    data: Vec<PhotonData>,
}

impl PhotonIndex {
    /// No photons: every lookup finds none.
    pub const EMPTY: PhotonIndex =
        PhotonIndex { id: 0, dropped: 0, table: Vec::new(), table_mask: 0, records: Vec::new(), data: Vec::new() };

    /// Indexes `photons` (in any order) with the cells and flux scale of `g`, leaving out those
    /// whose flags intersect `drop`.
    pub fn build(photons: &[Photon], g: &GridParams, drop: u32) -> PhotonIndex {
        // A counting sort by cell (cells numbered as they first appear), then `photon_order`
        // within each cell: a comparison sort of all photons took 4 times as long.
        let mut table = CellTable::with_capacity(photons.len() / 16);
        let ordinals: Vec<u32> = photons
            .iter()
            .map(|p| {
                if photon_flags(p) & drop != 0 {
                    return u32::MAX;
                }
                table.count(grid_cell(Vec3::from(p.position), g.cell_size))
            })
            .collect();
        let mut starts = Vec::with_capacity(table.counts.len() + 1);
        let mut sum = 0;
        for &c in &table.counts {
            starts.push(sum);
            sum += c;
        }
        starts.push(sum);
        let mut cursor = starts.clone();
        let mut sorted = vec![Photon::default(); sum as usize];
        for (p, &o) in photons.iter().zip(&ordinals).filter(|(_, &o)| o != u32::MAX) {
            sorted[cursor[o as usize] as usize] = *p;
            cursor[o as usize] += 1;
        }
        for w in starts.windows(2) {
            sorted[w[0] as usize..w[1] as usize].sort_unstable_by(photon_order);
        }
        let CellTable { mut slots, mask, .. } = table;
        for slot in slots.iter_mut().filter(|s| s.end != 0) {
            let o = slot.start as usize;
            (slot.start, slot.end) = (starts[o], starts[o + 1]);
        }
        let records = sorted
            .par_iter()
            .map(|p| [p.position[0], p.position[1], p.position[2], f32::from_bits(photon_flags(p))])
            .collect();
        let data = sorted.par_iter().map(|p| PhotonData::of(p, g.flux_scale)).collect();
        let id = NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        PhotonIndex { id, dropped: drop, table: slots, table_mask: mask, records, data }
    }

    /// Photons indexed.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The range of photons of `cell` (empty when it holds none).
    fn cell_range(&self, cell: IVec3) -> (u32, u32) {
        let mut h = grid_hash(cell, self.table_mask);
        loop {
            let slot = &self.table[h as usize];
            if slot.end == 0 {
                return (0, 0);
            }
            if slot.cell == cell {
                return (slot.start, slot.end);
            }
            h = (h + 1) & self.table_mask;
        }
    }

    /// The photon ranges of the 27 neighbours of `c`, from this thread's last lookup when it
    /// was in the same cell of the same index.
    fn neighbour_ranges(&self, c: IVec3) -> [(u32, u32); 27] {
        NEIGHBOURS.with(|last| {
            let mut last = last.borrow_mut();
            if last.id != self.id || last.cell != c {
                last.id = self.id;
                last.cell = c;
                for k in 0..27 {
                    last.ranges[k] = self.cell_range(grid_neighbour(c, k as u32));
                }
            }
            last.ranges
        })
    }

    /// Calls `visit(position, flags, data, squared distance)` for every photon within
    /// `g.radius` of `x`, in `for_each_photon_near`'s order; `g` is the grid the index was
    /// built with.
    pub fn for_each_near(&self, x: Vec3, g: &GridParams, mut visit: impl FnMut(Vec3, u32, &PhotonData, f32)) {
        if self.records.is_empty() {
            return;
        }
        let r2 = g.radius * g.radius;
        let c = grid_cell(x, g.cell_size);
        let gaps = grid_face_gaps(x, g.cell_size);
        let ranges = self.neighbour_ranges(c);
        for (k, &(start, end)) in ranges.iter().enumerate() {
            if start == end || !grid_neighbour_in_reach(&gaps, g.radius, k as u32) {
                continue;
            }
            let range = start as usize..end as usize;
            for (r, data) in self.records[range.clone()].iter().zip(&self.data[range]) {
                let pos = Vec3::new(r[0], r[1], r[2]);
                let d = pos - x;
                let d2 = d.dot(d);
                if d2 <= r2 {
                    visit(pos, r[3].to_bits(), data, d2);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::grid::for_each_photon_near;
    use crate::cpu::grid_build::build_grid;
    use crate::cpu::photon::pack_photon;
    use crate::cpu::rng::rand1;

    #[test]
    fn lookups_visit_the_grids_photons_in_the_grids_order() {
        // Photons crowded on a few planes (many per cell, as on a scene's walls) and scattered
        // ones, with every flag combination; tables from one bucket (all cells collide) to roomy.
        let photons: Vec<Photon> = (0..6000u32)
            .map(|i| {
                let u = |d| rand1(i, 3, 7, d);
                let mut p = Vec3::new(u(0), u(1), u(2)) * 4.0 - 2.0;
                if i % 3 != 0 {
                    p.y = (i % 4) as f32 * 0.5 - 1.0;
                }
                let wi = (Vec3::new(u(3), u(4), u(5)) * 2.0 - 1.0).normalize_or(Vec3::Y);
                pack_photon(p, Vec3::new(u(6), u(7), u(8)), 1.0, wi, wi, i % 4)
            })
            .collect();
        for (radius, table_mask) in [(0.1, 16383u32), (0.3, 0), (0.3, 1023), (0.7, 7)] {
            let g =
                GridParams { cell_size: radius, radius, table_mask, photon_count: 6000, flux_scale: 3.0, _pad: [0; 3] };
            let (sorted, starts) = build_grid(&photons, &g);
            // Queries alternate between indices of the same photons, at the same points: each
            // must see its own photons (a thread's last cell is kept per index). Points come in
            // pairs, mostly in one cell, as neighbouring pixels' do.
            let indices = [0, 1, 3].map(|drop| (drop, PhotonIndex::build(&photons, &g, drop)));
            for q in 0..800u32 {
                let x = Vec3::new(rand1(q / 2, 4, 7, 0), rand1(q / 2, 4, 7, 1), rand1(q / 2, 4, 7, 2)) * 5.0 - 2.5
                    + Vec3::new(0.03, 0.02, 0.0) * radius * (q % 2) as f32;
                for (drop, index) in indices.iter().chain(&indices) {
                    let mut expected = Vec::new();
                    for_each_photon_near(x, &g, &sorted, &starts, |p, d2| {
                        if photon_flags(p) & drop == 0 {
                            let data = PhotonData::of(p, g.flux_scale);
                            expected.push((Vec3::from(p.position), photon_flags(p), data, d2));
                        }
                    });
                    let mut found = Vec::new();
                    index.for_each_near(x, &g, |pos, flags, data, d2| found.push((pos, flags, *data, d2)));
                    assert_eq!(found, expected, "radius {radius}, table mask {table_mask}, drop {drop}, query {q}");
                }
            }
        }
    }
}
