#version 450
// render: the four terms of each pixel, accumulated over a band of rows, one sample and one part
// of it (see DispatchRange). A camera
// path follows mirrors and glass to the first diffuse surface; there the direct light comes from
// light sampling, the caustics from the caustic map, the indirect light from a final gather on
// the global map. Terms reached through a mirror or glass are the specular term.
// CPU twin: src/cpu/render.rs. Bindings: 0 frame, 1 nodes, 2 primitives, 3 materials, 4 lights,
// 5 accumulation (LAYER_COUNT vec4 per pixel of the band; rgb = sum of samples; w of the direct
// layer = rays cast), 6 grids, 7 global photons, 8 global starts, 9 caustic photons,
// 10 caustic starts.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430, binding = 0) readonly buffer Frame { FrameParams frame; };
layout(std430, binding = 1) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, binding = 2) readonly buffer Primitives { Primitive primitives[]; };
layout(std430, binding = 3) readonly buffer Materials { Material materials[]; };
layout(std430, binding = 4) readonly buffer Lights { Light lights[]; };
layout(std430, binding = 5) buffer Accumulation { vec4 accumulation[]; };
layout(std430, binding = 6) readonly buffer Grids { GridParams grids[2]; };
layout(std430, binding = 7) readonly buffer GlobalPhotons { Photon global_photons[]; };
layout(std430, binding = 8) readonly buffer GlobalStarts { uint global_starts[]; };
layout(std430, binding = 9) readonly buffer CausticPhotons { Photon caustic_photons[]; };
layout(std430, binding = 10) readonly buffer CausticStarts { uint caustic_starts[]; };
layout(push_constant) uniform Push { DispatchRange range; };

#include "rng.glsl"
#include "trace.glsl"
#include "shading.glsl"
#include "photon.glsl"
#include "grid.glsl"
#include "gather.glsl"

// Adds part `part` of the sample's terms to `terms` and the rays it casts to `rays` (see
// DispatchRange: part 0 is everything but the final gather, part k >= 1 is gather ray k - 1).
void radiance(uint px, uint py, uint sample_index, uint part, inout vec3 terms[4], inout uint rays) {
    uint stream = py * frame.width + px;
    vec2 jitter = rand2(stream, sample_index, frame.seed, RNG_PIXEL_X);
    float sx = 2.0 * (float(px) + jitter.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + jitter.y) / float(frame.height);
    vec3 o = load3(frame.camera_position);
    vec3 d = camera_direction(sx, sy);
    vec3 throughput = vec3(1.0);
    for (uint depth = 0u; depth < frame.max_depth; depth++) {
        float t;
        rays++;
        uint prim = trace_ray(o, d, INF, false, t);
        if (prim == NO_LIGHT) break;
        vec3 x = o + t * d;
        vec3 n = primitive_normal(prim, x);
        Material m = materials[primitives[prim].material];
        bool front = dot(n, d) < 0.0;
        // Everything a mirror or glass shows is the specular term.
        bool via_specular = depth > 0u;
        // Emission leaves the front face only; it counts wherever a camera path meets it, since
        // diffuse vertices end the path and light sampling covers them.
        if (front && part == 0u) terms[via_specular ? LAYER_SPECULAR : LAYER_DIRECT] += throughput * load3(m.emission);
        vec3 nf = front ? n : -n;
        uint dim = depth * RNG_DIMS_PER_BOUNCE;
        if (m.kind == MATERIAL_DIFFUSE) {
            vec3 albedo = load3(m.reflectance);
            if (albedo == vec3(0.0)) break;
            if (part == 0u) {
                vec3 direct = direct_light(x, nf, albedo, stream, sample_index, dim, rays);
                terms[via_specular ? LAYER_SPECULAR : LAYER_DIRECT] += throughput * direct;
            }
            if (frame.photon_mapping == 0u) break;
            if (part == 0u) {
                terms[via_specular ? LAYER_SPECULAR : LAYER_CAUSTICS] += throughput * caustic_light(x, nf, albedo);
                if (frame.gather_rays == 0u) {
                    terms[via_specular ? LAYER_SPECULAR : LAYER_INDIRECT] += throughput * indirect_preview(x, nf, albedo);
                }
            } else {
                vec3 indirect = gather_ray(x, nf, albedo, stream, sample_index, part - 1u, rays);
                terms[via_specular ? LAYER_SPECULAR : LAYER_INDIRECT] += throughput * indirect;
            }
            break;
        }
        if (m.kind == MATERIAL_MIRROR) {
            throughput *= load3(m.reflectance);
            d = reflect(d, nf);
            o = x + nf * frame.ray_epsilon;
            continue;
        }
        // Dielectric: reflection or refraction with the Fresnel probability, weight 1.
        dielectric_scatter(x, nf, front, m.ior, rand1(stream, sample_index, frame.seed, dim + RNG_FRESNEL), o, d);
    }
}

void main() {
    uint band_pixels = range.row_count * frame.width;
    uint i = GLOBAL_INDEX;
    if (i >= band_pixels) return;
    uint px = i % frame.width;
    uint py = range.row_begin + i / frame.width;
    vec3 terms[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    uint rays = 0u;
    radiance(px, py, range.sample_index, range.part, terms, rays);
    uint base = i * LAYER_COUNT;
    // w of the direct layer counts rays; a float holds counts exactly up to 2^24 per pixel.
    // Each pixel belongs to one invocation, so plain read-modify-write is race-free.
    accumulation[base + LAYER_DIRECT] += vec4(terms[LAYER_DIRECT], float(rays));
    accumulation[base + LAYER_SPECULAR] += vec4(terms[LAYER_SPECULAR], 0.0);
    accumulation[base + LAYER_INDIRECT] += vec4(terms[LAYER_INDIRECT], 0.0);
    accumulation[base + LAYER_CAUSTICS] += vec4(terms[LAYER_CAUSTICS], 0.0);
}
