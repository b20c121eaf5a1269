#version 450
// render: the four terms of each pixel, accumulated over a band of rows, one sample and one part
// of it (see DispatchRange). A camera
// path follows path lobes (mirrors, glass) to the first estimate lobe; there the direct light comes from
// light sampling, the caustics from the caustic map, the indirect light from a final gather on
// the global map. Terms reached through a mirror or glass are the specular term.
// CPU twin: src/cpu/render.rs. Bindings: the scene (scene_bindings.glsl), then the
// accumulation (LAYER_COUNT vec4 per pixel of the band; rgb = sum of samples; w of the direct
// layer = rays cast), grids, global photons, global starts, caustic photons, caustic starts.
// variant: textured
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

#include "scene_bindings.glsl"
layout(std430, binding = SCENE_BINDINGS + 0) buffer Accumulation { vec4 accumulation[]; };
layout(std430, binding = SCENE_BINDINGS + 1) readonly buffer Grids { GridParams grids[2]; };
layout(std430, binding = SCENE_BINDINGS + 2) readonly buffer GlobalPhotons { Photon global_photons[]; };
layout(std430, binding = SCENE_BINDINGS + 3) readonly buffer GlobalStarts { uint global_starts[]; };
layout(std430, binding = SCENE_BINDINGS + 4) readonly buffer CausticPhotons { Photon caustic_photons[]; };
layout(std430, binding = SCENE_BINDINGS + 5) readonly buffer CausticStarts { uint caustic_starts[]; };
layout(push_constant) uniform Push { DispatchRange range; };

#include "scene.glsl"
#include "photon.glsl"
#include "grid.glsl"
#include "gather.glsl"

// Adds part `part` of the sample's terms to `terms` and the rays it casts to `rays` (see
// DispatchRange: part 0 is everything but the final gather, part k >= 1 is gather ray k - 1).
void radiance(uint px, uint py, uint sample_index, uint part, inout vec3 terms[4], inout uint rays) {
    uint stream = py * frame.width + px;
    // xy jitter the film position, zw sample the lens.
    vec4 film = rand4(stream, sample_index, frame.seed, RNG_PIXEL_X);
    float sx = 2.0 * (float(px) + film.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + film.y) / float(frame.height);
    vec3 o, d;
    camera_ray(sx, sy, film.zw, o, d);
    vec3 throughput = vec3(1.0);
    for (uint depth = 0u; depth < frame.max_depth; depth++) {
        float t;
        rays++;
        uint prim = trace_ray(o, d, INF, false, t);
        // Everything a mirror or glass shows is the specular term.
        bool via_specular = depth > 0u;
        if (prim == NO_LIGHT) {
            // A ray that leaves the scene sees the environment (a path lobe's view of a light).
            WHEN(frame.environment != NO_LIGHT && part == 0u) {
                terms[via_specular ? LAYER_SPECULAR : LAYER_DIRECT] += throughput * environment_radiance(lights[frame.environment], d);
            }
            break;
        }
        Hit h = shape_hit(prim, o, d, t);
        Material m = materials[h.material];
        vec3 wo = -d;
        // Emission leaves the front face only; it counts wherever a camera path meets it, since
        // estimate lobes end the path and light sampling covers them.
        if (dot(wo, h.ng) > 0.0 && part == 0u) terms[via_specular ? LAYER_SPECULAR : LAYER_DIRECT] += throughput * material_emission(m, h);
        Bsdf b = material_bsdf(m, h);
        uint dim = depth * RNG_DIMS_PER_BOUNCE;
        vec4 u = rand4(stream, sample_index, frame.seed, dim + RNG_FRESNEL);
        // Follow the path lobes (mirrors, glass) with their probability; else end here.
        float q = bsdf_path_probability(b, wo);
        if (u.w < q) {
            BsdfSample s = bsdf_sample(b, wo, u.xyz, LOBES_PATH);
            if (s.flags == 0u) break;
            throughput *= s.weight / q;
            o = offset_origin(h, wo, s.flags);
            d = s.wi;
            continue;
        }
        if ((bsdf_flags(b) & BSDF_ESTIMATE) == 0u) break;
        vec3 weight = throughput / (1.0 - q);
        if (part == 0u) {
            terms[via_specular ? LAYER_SPECULAR : LAYER_DIRECT] += weight * direct_light(h, b, wo, stream, sample_index, dim, rays);
        }
        if (frame.photon_mapping == 0u) break;
        if (part == 0u) {
            terms[via_specular ? LAYER_SPECULAR : LAYER_CAUSTICS] += weight * caustic_light(h, b, wo);
            if (frame.gather_rays == 0u) {
                terms[via_specular ? LAYER_SPECULAR : LAYER_INDIRECT] += weight * indirect_preview(h, b, wo);
            }
        } else {
            terms[via_specular ? LAYER_SPECULAR : LAYER_INDIRECT] += weight * gather_ray(h, b, wo, stream, sample_index, part - 1u, rays);
        }
        break;
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
