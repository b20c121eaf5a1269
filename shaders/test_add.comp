#version 450
// test_add.comp: adds a push-constant value to every element; tests batching and barriers.
// Test-only kernel (tests/gpu_context.rs), so no CPU twin. Bindings: 0 values.
// Push constants: count, add.
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) buffer Values { uint values[]; };

layout(push_constant) uniform Params {
    uint count;
    uint add;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) return;
    values[i] += params.add;
}
