#version 450
// rng_probe.comp: the quasi-random numbers of rng.glsl on one input record per invocation, so that
// tests/rng_gpu.rs can compare them with the Rust twin (src/cpu/rng.rs) bit for bit. Test-only
// kernel. Bindings: 0 inputs, 1 outputs. Push constants: count.
//
// Input record, 4 words: stream, sample_index, seed, dim. Output record, 8 words: qmc2's two
// numbers as float bits, then sequence_point(stream & 1, sample_index, seed, dim), the last three
// inputs read as batch, size and item; then qmc2_choice's three numbers as float bits and 0.
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"
#include "rng.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer Inputs { uvec4 inputs[]; };
layout(std430, binding = 1) writeonly buffer Outputs { uvec4 outputs[]; };

layout(push_constant) uniform Params {
    uint count;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) return;
    uvec4 r = inputs[i];
    vec2 q = qmc2(r.x, r.y, r.z, r.w);
    uvec2 s = sequence_point(r.x & 1u, r.y, r.z, r.w);
    vec3 c = qmc2_choice(r.x, r.y, r.z, r.w);
    outputs[2u * i] = uvec4(floatBitsToUint(q.x), floatBitsToUint(q.y), s.x, s.y);
    outputs[2u * i + 1u] = uvec4(floatBitsToUint(c.x), floatBitsToUint(c.y), floatBitsToUint(c.z), 0u);
}
