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
// The starts (R32UI) and the scattered photons (RGBA32UI, see fetch_photon) as texel buffers:
// every invocation reads its whole bucket, and texel fetches are the cheap reads on lavapipe
// (scene_bindings.glsl).
layout(binding = 1) uniform usamplerBuffer starts;
layout(binding = 2) uniform usamplerBuffer scattered;
layout(std430, binding = 3) writeonly buffer Ranked { Photon ranked[]; };

#include "grid.glsl"

void main() {
    uint i = GLOBAL_INDEX;
    if (i >= grid.photon_count) return;
    Photon p = fetch_photon(scattered, i);
    uint h = grid_hash(grid_cell(load3(p.position), grid.cell_size), grid.table_mask);
    uint begin = texelFetch(starts, int(h)).x;
    uint end = texelFetch(starts, int(h + 1u)).x;
    uint rank = 0u;
    for (uint j = begin; j < end; j++) {
        Photon q = fetch_photon(scattered, j);
        // Bit-identical photons are ordered by slot: any order of them gives the same bytes.
        if (photon_less(q, p) || (j < i && !photon_less(p, q))) rank++;
    }
    STORE_PHOTON(ranked, begin + rank, p)
}
