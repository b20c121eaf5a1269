#version 450
// pattern_probe.comp: evaluates pattern.glsl at given points so tests/pattern_gpu.rs can compare
// with the CPU twin. Test-only kernel; its twin is src/cpu/pattern.rs itself.
// Bindings: 0 texture data, 1 inputs (4 floats per point), 2 outputs (4 floats per point).
// Push constants: count; mode: 0 pattern_value, 1 pattern_gradient, 2 color_map_eval of the input's
// x, 3 noise_signed, noise_unit, turbulence and pattern_sin_turns of x, 4 the colour of the pattern
// through its map; at (pattern or map block); map_at (map block of mode 4); h (gradient step).
#extension GL_GOOGLE_include_directive : require
#include "constants.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer TextureData { uint texture_data[]; };
uint texture_word(uint i) { return texture_data[i]; }
layout(std430, binding = 1) readonly buffer Inputs { vec4 inputs[]; };
layout(std430, binding = 2) writeonly buffer Outputs { vec4 outputs[]; };

// The scene kernels' specialization constant (scene_bindings.glsl), so that the tests can check
// which patterns may lose their noise.
layout(constant_id = 2) const bool SCENE_HAS_NOISE = true;
#include "pattern.glsl"

layout(push_constant) uniform Params {
    uint count;
    uint mode;
    uint at;
    uint map_at;
    float h;
} params;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= params.count) return;
    vec3 p = inputs[i].xyz;
    vec4 result = vec4(0.0);
    switch (params.mode) {
    case 0u:
        result.x = pattern_value(params.at, p);
        break;
    case 1u:
        result.xyz = pattern_gradient(params.at, p, params.h);
        break;
    case 2u:
        result.xyz = color_map_eval(params.at, p.x);
        break;
    case 3u:
        result = vec4(noise_signed(p, 0u), noise_unit(p), turbulence(p, 6u, 0.5, 2.0), pattern_sin_turns(p.x));
        break;
    case 4u:
        result.xyz = color_map_eval(params.map_at, pattern_value(params.at, p));
        break;
    }
    outputs[i] = result;
}
