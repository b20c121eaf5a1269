#version 450
// grid_scan: exclusive prefix sum of each block of SCAN_BLOCK values, in place, and each block's
// total into `sums`; scanning the sums and adding them back (grid_scan_add) completes a scan of
// any length. CPU twin: src/cpu/grid_build.rs (grid_scan). Bindings: 0 values, 1 block sums.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = SCAN_THREADS) in;

layout(std430, binding = 0) buffer Values { uint values[]; };
layout(std430, binding = 1) buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint count; };

shared uint partial[SCAN_THREADS];

void main() {
    uint per_thread = SCAN_BLOCK / SCAN_THREADS;
    uint base = gl_WorkGroupID.x * SCAN_BLOCK + gl_LocalInvocationID.x * per_thread;
    // Each thread scans its own run serially...
    uint local_sum = 0u;
    for (uint k = 0u; k < per_thread; k++) {
        uint i = base + k;
        if (i < count) local_sum += values[i];
    }
    partial[gl_LocalInvocationID.x] = local_sum;
    barrier();
    // ...then the run totals are scanned across the workgroup (Hillis and Steele 1986).
    for (uint offset = 1u; offset < SCAN_THREADS; offset *= 2u) {
        uint add = gl_LocalInvocationID.x >= offset ? partial[gl_LocalInvocationID.x - offset] : 0u;
        barrier();
        partial[gl_LocalInvocationID.x] += add;
        barrier();
    }
    uint running = partial[gl_LocalInvocationID.x] - local_sum;
    for (uint k = 0u; k < per_thread; k++) {
        uint i = base + k;
        if (i < count) {
            uint v = values[i];
            values[i] = running;
            running += v;
        }
    }
    if (gl_LocalInvocationID.x == SCAN_THREADS - 1u) sums[gl_WorkGroupID.x] = partial[SCAN_THREADS - 1u];
}
