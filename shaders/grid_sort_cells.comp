#version 450
// grid_sort_cells: sorts every bucket by photon_order, so the grid no longer depends on the
// order of grid_scatter's atomics: the same scene and seed give the same bytes.
// CPU twin: src/cpu/grid_build.rs. Bindings: 0 grid params, 1 bucket starts, 2 sorted photons.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer Grid { GridParams grid; };
layout(std430, binding = 1) readonly buffer Starts { uint starts[]; };
layout(std430, binding = 2) buffer Sorted { Photon sorted_photons[]; };

#include "grid.glsl"

void main() {
    uint h = gl_GlobalInvocationID.x;
    if (h > grid.table_mask) return;
    uint begin = starts[h];
    uint end = starts[h + 1u];
    // Insertion sort: buckets hold tens of photons at the default radius.
    for (uint i = begin + 1u; i < end; i++) {
        Photon p = sorted_photons[i];
        uint j = i;
        while (j > begin && photon_less(p, sorted_photons[j - 1u])) {
            STORE_PHOTON(sorted_photons, j, sorted_photons[j - 1u])
            j--;
        }
        STORE_PHOTON(sorted_photons, j, p)
    }
}
