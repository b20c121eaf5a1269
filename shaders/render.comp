#version 450
// render: radiance of camera paths (emission, direct light at the first diffuse surface, mirror and
// glass recursion), accumulated per pixel over a range of rows and samples.
// CPU twin: src/cpu/render.rs. Bindings: 0 frame, 1 nodes, 2 primitives, 3 materials, 4 lights,
// 5 accumulation (one vec4 per pixel of the band: rgb = sum of samples, w = rays cast).
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer Frame { FrameParams frame; };
layout(std430, binding = 1) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, binding = 2) readonly buffer Primitives { Primitive primitives[]; };
layout(std430, binding = 3) readonly buffer Materials { Material materials[]; };
layout(std430, binding = 4) readonly buffer Lights { Light lights[]; };
layout(std430, binding = 5) buffer Accumulation { vec4 accumulation[]; };
layout(push_constant) uniform Push { DispatchRange range; };

#include "rng.glsl"
#include "trace.glsl"
#include "shading.glsl"

// Adds the rays it casts (closest-hit and shadow) to `rays`, for the throughput summary.
vec3 radiance(uint px, uint py, uint sample_index, inout uint rays) {
    uint stream = py * frame.width + px;
    vec2 jitter = rand2(stream, sample_index, frame.seed, RNG_PIXEL_X);
    float sx = 2.0 * (float(px) + jitter.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + jitter.y) / float(frame.height);
    vec3 o = load3(frame.camera_position);
    vec3 d = camera_direction(sx, sy);
    vec3 throughput = vec3(1.0);
    vec3 result = vec3(0.0);
    for (uint depth = 0u; depth < frame.max_depth; depth++) {
        float t;
        rays++;
        uint prim = trace_ray(o, d, INF, false, t);
        if (prim == NO_LIGHT) break;
        vec3 x = o + t * d;
        vec3 n = primitive_normal(prim, x);
        Material m = materials[primitives[prim].material];
        bool front = dot(n, d) < 0.0;
        // Emission leaves the front face only; it is counted wherever a camera path meets it,
        // since diffuse vertices end the path and light sampling covers them.
        if (front) result += throughput * load3(m.emission);
        vec3 nf = front ? n : -n;
        uint dim = depth * RNG_DIMS_PER_BOUNCE;
        if (m.kind == MATERIAL_DIFFUSE) {
            vec3 albedo = load3(m.reflectance);
            if (albedo != vec3(0.0) && frame.light_count > 0u) {
                result += throughput * direct_light(x, nf, albedo, stream, sample_index, dim, rays);
            }
            break;
        }
        if (m.kind == MATERIAL_MIRROR) {
            throughput *= load3(m.reflectance);
            d = reflect(d, nf);
            o = x + nf * frame.ray_epsilon;
            continue;
        }
        // Dielectric: choose reflection or refraction with the Fresnel probability, weight 1.
        float eta_i = front ? 1.0 : m.ior;
        float eta_t = front ? m.ior : 1.0;
        float cos_i = -dot(d, nf);
        float cos_t;
        float f = fresnel_dielectric(cos_i, eta_i, eta_t, cos_t);
        if (rand1(stream, sample_index, frame.seed, dim + RNG_FRESNEL) < f) {
            d = reflect(d, nf);
            o = x + nf * frame.ray_epsilon;
        } else {
            float eta = eta_i / eta_t;
            d = normalize(eta * d + (eta * cos_i - cos_t) * nf);
            o = x - nf * frame.ray_epsilon;
        }
    }
    return result;
}

void main() {
    uint band_pixels = range.row_count * frame.width;
    uint i = gl_GlobalInvocationID.x;
    if (i >= band_pixels) return;
    uint px = i % frame.width;
    uint py = range.row_begin + i / frame.width;
    vec3 sum = vec3(0.0);
    uint rays = 0u;
    for (uint s = range.sample_begin; s < range.sample_begin + range.sample_count; s++) {
        sum += radiance(px, py, s, rays);
    }
    // w counts rays; a float holds counts exactly up to 2^24 per pixel.
    accumulation[i] += vec4(sum, float(rays));
}
