#version 450
// grid_rank: moves each photon to its rank inside its bucket under photon_order, so the grid no
// longer depends on the order of grid_scatter's atomics: the same scene and seed give the same
// bytes. One invocation per photon scans its own bucket once (lavapipe stops an invocation after
// 65535 loop iterations, which an insertion sort of a whole bucket by one invocation can reach).
// CPU twin: src/cpu/grid_build.rs (grid_rank). Bindings: 0 grid params, 1 bucket starts,
// 2 scattered photons, 3 ranked photons.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer Grid { GridParams grid; };
layout(std430, binding = 1) readonly buffer Starts { uint starts[]; };
layout(std430, binding = 2) readonly buffer Scattered { Photon scattered[]; };
layout(std430, binding = 3) writeonly buffer Ranked { Photon ranked[]; };

#include "grid.glsl"

void main() {
    uint i = GLOBAL_INDEX;
    if (i >= grid.photon_count) return;
    Photon p = scattered[i];
    uint h = grid_hash(grid_cell(load3(p.position), grid.cell_size), grid.table_mask);
    uint begin = starts[h];
    uint end = starts[h + 1u];
    uint rank = 0u;
    for (uint j = begin; j < end; j++) {
        Photon q = scattered[j];
        // Bit-identical photons are ordered by slot: any order of them gives the same bytes.
        if (photon_less(q, p) || (j < i && !photon_less(p, q))) rank++;
    }
    STORE_PHOTON(ranked, begin + rank, p)
}
