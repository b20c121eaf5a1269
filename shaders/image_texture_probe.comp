#version 450
// image_texture_probe.comp: evaluates image_lookup and image_texel at given points, for
// tests/image_texture_gpu.rs. Test-only kernel: its CPU twin is src/cpu/image_texture.rs itself.
// Bindings: 0 texture data, 1 queries (4 words each: u bits, v bits, block offset, unused),
// 2 results (2 per query: lookup, texel). Push constants: count.
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer TextureData { uint texture_data[]; };
uint texture_word(uint i) { return texture_data[i]; }
layout(std430, binding = 1) readonly buffer Queries { uint queries[]; };
layout(std430, binding = 2) writeonly buffer Results { vec4 results[]; };

#include "image_texture.glsl"

layout(push_constant) uniform Params {
    uint count;
} params;

void main() {
    uint q = gl_GlobalInvocationID.x;
    if (q >= params.count) return;
    vec2 uv = vec2(uintBitsToFloat(queries[4u * q]), uintBitsToFloat(queries[4u * q + 1u]));
    uint at = queries[4u * q + 2u];
    results[2u * q] = image_lookup(at, uv);
    results[2u * q + 1u] = image_texel(at, uv);
}
