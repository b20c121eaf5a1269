#version 450
// grid_scatter: places each photon in its bucket's range. The slot inside the range depends on
// the order of the atomics; grid_rank removes that. CPU twin: src/cpu/grid_build.rs.
// Bindings: 0 grid params, 1 photons, 2 bucket starts, 3 fill counters (zeroed), 4 sorted photons.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer Grid { GridParams grid; };
layout(std430, binding = 1) readonly buffer Photons { Photon photons[]; };
layout(std430, binding = 2) readonly buffer Starts { uint starts[]; };
layout(std430, binding = 3) buffer Fill { uint fill[]; };
layout(std430, binding = 4) writeonly buffer Sorted { Photon sorted_photons[]; };

#include "grid.glsl"

void main() {
    uint i = GLOBAL_INDEX;
    if (i >= grid.photon_count) return;
    Photon p = photons[i];
    uint h = grid_hash(grid_cell(load3(p.position), grid.cell_size), grid.table_mask);
    STORE_PHOTON(sorted_photons, starts[h] + atomicAdd(fill[h], 1u), p)
}
