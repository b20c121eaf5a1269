#version 450
// grid_scan_add: adds each block's scanned offset to its values, finishing a multi-block scan.
// CPU twin: src/cpu/grid_build.rs (grid_scan). Bindings: 0 values, 1 scanned block sums.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) buffer Values { uint values[]; };
layout(std430, binding = 1) readonly buffer Sums { uint sums[]; };
layout(push_constant) uniform Push { uint count; };

void main() {
    uint i = GLOBAL_INDEX;
    if (i >= count) return;
    values[i] += sums[i / SCAN_BLOCK];
}
