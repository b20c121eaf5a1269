#version 450
// grid_count: photons per bucket. CPU twin: src/cpu/grid_build.rs (grid_count).
// Bindings: 0 grid params, 1 photons, 2 counts (one per bucket, plus a final 0 that the scan
// turns into the total).
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer Grid { GridParams grid; };
layout(std430, binding = 1) readonly buffer Photons { Photon photons[]; };
layout(std430, binding = 2) buffer Counts { uint counts[]; };

#include "grid.glsl"

void main() {
    uint i = GLOBAL_INDEX;
    if (i >= grid.photon_count) return;
    Photon p = photons[i];
    atomicAdd(counts[grid_hash(grid_cell(load3(p.position), grid.cell_size), grid.table_mask)], 1u);
}
