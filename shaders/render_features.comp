#version 450
// render_features: the feature layers a denoiser is guided by: albedo and shading normal of the
// first vertex that is not a delta lobe (through mirrors and glass), position and depth of the
// first surface seen, summed over the samples. Contract and conventions: src/cpu/render_features.rs
// (CPU twin). Bindings: the scene, then the feature sums (FEATURE_COUNT vec4 per pixel of the band).
// variant: textured
// variant: textured alpha
// variant: analytic
// variant: textured analytic
// variant: textured alpha analytic
// variant: analytic implicit
// variant: textured analytic implicit
// variant: textured alpha analytic implicit
// variant: analytic implicit csg
// variant: textured analytic implicit csg
// variant: textured alpha analytic implicit csg
// variant: media
// variant: textured media
// variant: textured alpha media
// variant: analytic media
// variant: textured analytic media
// variant: textured alpha analytic media
// variant: analytic implicit media
// variant: textured analytic implicit media
// variant: textured alpha analytic implicit media
// variant: analytic implicit csg media
// variant: textured analytic implicit csg media
// variant: textured alpha analytic implicit csg media
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

#include "scene_bindings.glsl"
layout(std430, binding = SCENE_BINDINGS + 0) buffer Features { vec4 features[]; };
layout(push_constant) uniform Push { DispatchRange range; };

#include "scene.glsl"

void sample_features(uint px, uint py, uint sample_index, out vec3 albedo, out vec3 normal, out vec3 position, out float depth) {
    uint stream = py * frame.width + px;
    vec2 film = film_offset(qmc2(stream, sample_index, frame.seed, RNG_PIXEL_X));
    float sx = 2.0 * (float(px) + film.x) / float(frame.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(py) + film.y) / float(frame.height);
    vec3 o, d;
    camera_ray(sx, sy, lens_sample(stream, sample_index), o, d);
    vec3 eye = o;
    vec3 tint = vec3(1.0);
    uint skip = NO_LIGHT;
    uint vertex = 0u;
    albedo = vec3(0.0);
    normal = vec3(0.0);
    position = vec3(0.0);
    depth = 0.0;
    bool seen = false;
    for (uint step = 0u; step < frame.max_depth + MEDIUM_CROSSINGS; step++) {
        float t;
        uint prim = trace_ray(o, d, INF, false, skip, t);
        if (prim == NO_LIGHT) {
            WHEN(frame.environment != NO_LIGHT) {
                Light l = light_at(frame.environment);
                albedo = tint * min(environment_radiance(l, d), vec3(1.0));
            }
            break;
        }
        Hit h = shape_hit(prim, o, d, t);
        Material m = material_at(h.material);
        if (m.kind == MATERIAL_NULL) {
            // An invisible boundary of a medium: straight through.
            skip = ray_skip(prim);
            o = offset_origin(h, -d, BSDF_TRANSMISSION);
            continue;
        }
        if (!seen) {
            position = h.p;
            depth = length(h.p - eye);
            seen = true;
        }
        vec3 wo = -d;
        Bsdf b = material_bsdf(m, h);
        normal = facing(b, wo);
        uint flags = bsdf_flags(b);
        if (flags == 0u) {
            albedo = tint * min(material_emission(m, h), vec3(1.0));
            break;
        }
        vec4 u = bsdf_numbers(stream, sample_index, uvec2(stream, sample_index), frame.seed, vertex * RNG_DIMS_PER_BOUNCE + RNG_FRESNEL);
        bool last = vertex + 1u >= frame.max_depth;
        if ((flags & BSDF_ESTIMATE) != 0u || last) {
            // The first non-specular vertex (or the last the integrators reach).
            BsdfSample smp = bsdf_sample(b, wo, u.xyz, LOBES_ALL);
            albedo = tint * clamp(smp.weight, vec3(0.0), vec3(1.0));
            break;
        }
        BsdfSample smp = bsdf_sample(b, wo, u.xyz, LOBES_PATH);
        if (smp.flags == 0u) break;
        tint *= clamp(smp.weight, vec3(0.0), vec3(1.0));
        skip = ray_skip(prim);
        o = offset_origin(h, wo, smp.flags);
        d = smp.wi;
        vertex++;
    }
}

void main() {
    uint band_pixels = range.row_count * frame.width;
    uint i = GLOBAL_INDEX;
    if (i >= band_pixels) return;
    uint px = i % frame.width;
    uint py = range.row_begin + i / frame.width;
    vec3 albedo, normal, position;
    float depth;
    sample_features(px, py, range.sample_index, albedo, normal, position, depth);
    // Each pixel belongs to one invocation, so plain read-modify-write is race-free.
    uint base = i * FEATURE_COUNT;
    features[base + FEATURE_ALBEDO] += vec4(albedo, 0.0);
    features[base + FEATURE_NORMAL] += vec4(normal, 0.0);
    features[base + FEATURE_POSITION] += vec4(position, depth);
}
